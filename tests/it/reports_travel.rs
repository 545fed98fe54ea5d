//! Reports that travel (issue 21, items 6 and 5's pictures): `report.html` and `compare.html`
//! show every figure from the single file (no figure read from a file beside the page; every
//! data URI a PNG), figures read at a 1280-pixel page, captions name the objective the verdict
//! uses, and `compare`'s pictures of invalid presets mark the receivers they fail.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::common::unbase64;

fn run(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

/// A decoded PNG: (width, height, RGB8 pixels).
fn decode_png(bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut reader = png::Decoder::new(bytes).read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("a PNG frame");
    buf.truncate(info.buffer_size());
    let rgb = match info.color_type {
        png::ColorType::Rgb => buf,
        png::ColorType::Rgba => buf.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        other => panic!("unexpected colour type {other:?}"),
    };
    (info.width, info.height, rgb)
}

/// Every `<img>` of a page as (decoded image bytes, alt text, figure caption); panics on a
/// source that is not a PNG data URI.
fn images(page: &str) -> Vec<(Vec<u8>, String, String)> {
    let doc = roxmltree::Document::parse_with_options(
        page,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .expect("the page is well-formed XML");
    // No element at all loads a file: every src is a data URI, no object or embed.
    for n in doc.descendants() {
        assert!(!n.has_tag_name("object") && !n.has_tag_name("embed") && !n.has_tag_name("iframe"));
        if let Some(src) = n.attribute("src") {
            assert!(src.starts_with("data:"), "a figure read from a file: {src}");
        }
    }
    doc.descendants()
        .filter(|n| n.has_tag_name("img"))
        .map(|n| {
            let src = n.attribute("src").unwrap();
            let payload = src
                .strip_prefix("data:image/png;base64,")
                .or_else(|| src.strip_prefix("data:image/apng;base64,"))
                .unwrap_or_else(|| panic!("not a PNG data URI: {}", &src[..src.len().min(40)]));
            let bytes = unbase64(payload);
            assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
            let figure = n.ancestors().find(|a| a.has_tag_name("figure")).unwrap();
            let caption = figure
                .descendants()
                .find(|c| c.has_tag_name("figcaption"))
                .map(|c| c.descendants().filter_map(|t| t.text()).collect::<String>())
                .unwrap_or_default();
            (bytes, n.attribute("alt").unwrap_or_default().to_string(), caption)
        })
        .collect()
}

fn default_scene(d: &Path) {
    std::fs::create_dir_all(d.join("configs")).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(root.join("configs/default.toml"), d.join("configs/default.toml")).unwrap();
}

#[test]
fn the_sweep_report_shows_every_figure_from_the_single_file_captioned_by_the_objective() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    default_scene(d);
    // The README's first command: the heat map's SVG is over the inlining limit.
    run(d, &["sweep", "configs/default.toml", "--quiet"]);
    let out = d.join("out/default/sweep");
    assert!(std::fs::metadata(out.join("heatmap.svg")).unwrap().len() > 256 * 1024);
    let page = std::fs::read_to_string(out.join("report.html")).unwrap();
    let imgs = images(&page);
    // The plan of the view, the two camera views and the heat map (as a PNG no wider than the
    // page), each decoding.
    assert_eq!(imgs.len(), 4, "{:?}", imgs.iter().map(|i| &i.2).collect::<Vec<_>>());
    for (bytes, _, _) in &imgs {
        let (w, h, px) = decode_png(bytes);
        assert!(w > 0 && h > 0 && px.len() == (w * h * 3) as usize);
    }
    let heat = imgs
        .iter()
        .find(|i| i.2.contains("heatmap.svg"))
        .expect("the heat map inlined");
    let (w, _, _) = decode_png(&heat.0);
    assert_eq!(w, 1280);
    // One raster serves the file and the page: the inlined heat map has heatmap.png's pixels
    // (another compression), and the inlined plan is plan.png itself.
    assert_eq!(
        decode_png(&heat.0),
        decode_png(&std::fs::read(out.join("heatmap.png")).unwrap())
    );
    let plan = std::fs::read(out.join("plan.png")).unwrap();
    assert!(imgs.iter().any(|i| i.0 == plan), "plan.png inlined as it is");
    // The page can be sent alone: the report's files beside it are linked, never needed.
    let alone = tempfile::tempdir().unwrap();
    std::fs::write(alone.path().join("report.html"), &page).unwrap();
    assert_eq!(
        images(&std::fs::read_to_string(alone.path().join("report.html")).unwrap()).len(),
        4
    );

    // Captions say what the figures draw, from the objective the verdict uses.
    let rec: Value = serde_json::from_str(&std::fs::read_to_string(out.join("recommendation.json")).unwrap()).unwrap();
    let objective = rec["objective_metric"].as_str().unwrap();
    assert_eq!(objective, "visible_aliasing_p95");
    let doc = roxmltree::Document::parse_with_options(
        &page,
        roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        },
    )
    .unwrap();
    let captions: Vec<String> = doc
        .descendants()
        .filter(|n| n.has_tag_name("figcaption"))
        .map(|c| c.descendants().filter_map(|t| t.text()).collect::<String>())
        .collect();
    let pareto = captions.iter().find(|c| c.starts_with("Pareto front")).unwrap();
    assert!(
        pareto.contains(objective) && !pareto.contains("mean aliasing"),
        "{pareto}"
    );
    assert!(
        heat.2.contains(objective) && heat.2.contains("screen_aliasing_max"),
        "{}",
        heat.2
    );
    // The Pareto figure's own axis names the same metric.
    let svg = std::fs::read_to_string(out.join("pareto.svg")).unwrap();
    assert!(svg.contains(objective), "the Pareto figure draws {objective}");
}

/// Every text of every figure a page shows is at least 9.5 pixels tall when the figure is shown
/// 1280 pixels wide (or narrower at its own size): the heat map of the default sweep was 6 px.
#[test]
fn figures_are_legible_at_a_1280_pixel_page() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    default_scene(d);
    run(d, &["sweep", "configs/default.toml", "--quiet"]);
    run(d, &["compare", "configs/default.toml", "--quiet"]);
    run(d, &["analyze", "configs/default.toml", "--quiet"]);
    let mut checked = 0;
    for sub in ["sweep", "compare", "analyze"] {
        for e in std::fs::read_dir(d.join("out/default").join(sub)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "svg") {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap();
            let doc = roxmltree::Document::parse(&text).unwrap();
            let width: f64 = doc.root_element().attribute("width").unwrap().parse().unwrap();
            let shown = (1280.0 / width).min(1.0);
            for t in doc.descendants().filter(|n| n.has_tag_name("text")) {
                let content: String = t.descendants().filter_map(|x| x.text()).collect();
                if content.trim().is_empty() {
                    continue;
                }
                let size: f64 = t
                    .attribute("font-size")
                    .or_else(|| t.ancestors().find_map(|a| a.attribute("font-size")))
                    .unwrap()
                    .parse()
                    .unwrap();
                assert!(
                    size * shown >= 9.5,
                    "{}: {:?} is {:.1} px at a 1280-pixel page",
                    p.display(),
                    content.trim(),
                    size * shown
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 9, "{checked} figures");
}

/// `compare.html`: invalid presets' camera pictures mark the receivers their windows miss (red)
/// and their light depth ranges clip (magenta), with counts in the captions; a valid preset's
/// pictures have neither colour.
#[test]
fn compare_marks_the_receivers_invalid_presets_fail() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    default_scene(d);
    let stdout = run(
        d,
        &[
            "compare",
            "configs/default.toml",
            "--quiet",
            "--presets",
            "unity-sample,eevee,bevy",
        ],
    );
    assert!(stdout.contains("unity-sample: 2880 slice corners missed"), "{stdout}");
    assert!(stdout.contains("eevee: receivers clipped"), "{stdout}");
    let page = std::fs::read_to_string(d.join("out/default/compare/compare.html")).unwrap();
    let imgs = images(&page);
    const MISSED: [u8; 3] = [214, 39, 40];
    const CLIPPED: [u8; 3] = [230, 0, 230];
    let count = |bytes: &[u8], c: [u8; 3]| {
        let (_, _, px) = decode_png(bytes);
        px.chunks(3).filter(|p| *p == c).count()
    };
    let of = |preset: &str| -> Vec<&(Vec<u8>, String, String)> {
        imgs.iter().filter(|i| i.2.starts_with(&format!("{preset}:"))).collect()
    };
    let (us, ev, bevy) = (of("unity-sample"), of("eevee"), of("bevy"));
    assert_eq!((us.len(), ev.len(), bevy.len()), (2, 2, 2));
    for (bytes, _, caption) in &us {
        assert!(
            caption.contains("Red: ") && caption.contains("outside the window"),
            "{caption}"
        );
        // The caption's count is the picture's: each sampled pixel is a k × k block.
        let n: usize = caption
            .split("Red: ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let red = count(bytes, MISSED);
        let (w, _, _) = decode_png(bytes);
        let k = (w / 240) as usize;
        // Split lines drawn over a few of them in the cascade picture; the legend's swatch.
        assert!(
            n > 0 && red * 100 >= n * k * k * 95 && red <= n * k * k + 400,
            "{n} pixels, {red} red"
        );
    }
    for (bytes, _, caption) in &ev {
        assert!(caption.contains("Magenta: "), "{caption}");
        assert!(count(bytes, CLIPPED) > 0);
    }
    for (bytes, _, caption) in &bevy {
        assert!(
            !caption.contains("Red: ") && !caption.contains("Magenta: "),
            "{caption}"
        );
        assert_eq!(count(bytes, MISSED), 0);
        assert_eq!(count(bytes, CLIPPED), 0);
    }
}
