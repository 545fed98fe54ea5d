//! Every figure `sweep`, `analyze`, `compare` and `bench` write on every bundled config, and
//! `sweep --preset P` for every engine, is checked on its SVG: it draws data marks, and no
//! legend box covers one. The SVG is read with a small XML parser; plotters' output is flat
//! (rect, circle, line, polyline, polygon, path, text), in drawing order.

use std::path::{Path, PathBuf};
use std::process::Command;

const CONFIGS: [&str; 5] = ["default", "indoor", "open_world", "top_down", "village"];

const PRESETS: [&str; 11] = [
    "dart",
    "threejs",
    "unity-sample",
    "eevee",
    "learnopengl",
    "bevy",
    "godot",
    "unreal",
    "unity",
    "unity-urp",
    "filament",
];

/// A shape's geometry in SVG pixels.
#[derive(Debug, Clone, PartialEq)]
enum Shape {
    /// x0, y0, x1, y1.
    Box(f64, f64, f64, f64),
    /// Connected points.
    Path(Vec<(f64, f64)>),
}

/// What a figure's SVG holds: its data marks and its legend boxes.
#[derive(Debug, Default)]
struct Marks {
    data: Vec<(String, Shape)>,
    legends: Vec<(f64, f64, f64, f64)>,
}

fn num(n: &roxmltree::Node, a: &str) -> f64 {
    n.attribute(a).and_then(|v| v.parse().ok()).unwrap_or(0.0)
}

fn points(text: &str) -> Vec<(f64, f64)> {
    let nums: Vec<f64> = text
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .filter_map(|t| t.parse().ok())
        .collect();
    nums.chunks_exact(2).map(|p| (p[0], p[1])).collect()
}

/// Splits a figure's shapes into data marks and legend boxes. A legend box is the house legend
/// background (white, opacity 0.85); the marks drawn after it are its swatches. Axes, ticks
/// and mesh lines (black strokes without fill) and white shapes (background, budget line,
/// halo of a marker) are not data.
fn marks(svg: &str) -> Marks {
    let doc = roxmltree::Document::parse(svg).expect("the SVG parses");
    let mut m = Marks::default();
    for n in doc.descendants().filter(|n| n.is_element()) {
        let tag = n.tag_name().name();
        let fill = n.attribute("fill").unwrap_or("none").to_ascii_uppercase();
        let stroke = n.attribute("stroke").unwrap_or("none").to_ascii_uppercase();
        if tag == "rect" && fill == "#FFFFFF" && n.attribute("opacity") == Some("0.85") {
            let (x, y) = (num(&n, "x"), num(&n, "y"));
            m.legends.push((x, y, x + num(&n, "width"), y + num(&n, "height")));
            continue;
        }
        if !m.legends.is_empty() {
            continue; // swatches and labels of the legend
        }
        let white = |c: &str| c == "#FFFFFF" || c == "NONE";
        if white(&fill) && white(&stroke) {
            continue;
        }
        if fill == "NONE" && stroke == "#000000" {
            continue;
        }
        let shape = match tag {
            "rect" => {
                let (x, y) = (num(&n, "x"), num(&n, "y"));
                Shape::Box(x, y, x + num(&n, "width"), y + num(&n, "height"))
            }
            "circle" => {
                let (x, y, r) = (num(&n, "cx"), num(&n, "cy"), num(&n, "r"));
                Shape::Box(x - r, y - r, x + r, y + r)
            }
            "line" => Shape::Path(vec![(num(&n, "x1"), num(&n, "y1")), (num(&n, "x2"), num(&n, "y2"))]),
            "polyline" | "polygon" => Shape::Path(points(n.attribute("points").unwrap_or(""))),
            "path" => Shape::Path(points(n.attribute("d").unwrap_or(""))),
            _ => continue,
        };
        m.data.push((tag.to_string(), shape));
    }
    m
}

/// True when the segment a-b passes through the open rectangle (Liang-Barsky clipping).
fn segment_hits(a: (f64, f64), b: (f64, f64), r: (f64, f64, f64, f64)) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [(-dx, a.0 - r.0), (dx, r.2 - a.0), (-dy, a.1 - r.1), (dy, r.3 - a.1)] {
        if p == 0.0 {
            if q <= 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 < t1
}

/// The data marks a legend box covers (the box shrunk by a pixel, so touching is not covering).
fn covered(m: &Marks) -> Vec<(String, Shape)> {
    let mut out = Vec::new();
    for &(x0, y0, x1, y1) in &m.legends {
        let r = (x0 + 1.0, y0 + 1.0, x1 - 1.0, y1 - 1.0);
        for (tag, s) in &m.data {
            let hit = match s {
                Shape::Box(a, b, c, d) => *a < r.2 && *c > r.0 && *b < r.3 && *d > r.1,
                Shape::Path(p) if p.len() == 1 => segment_hits(p[0], p[0], r),
                Shape::Path(p) => p.windows(2).any(|w| segment_hits(w[0], w[1], r)),
            };
            if hit {
                out.push((tag.clone(), s.clone()));
            }
        }
    }
    out
}

/// Checks one figure; returns what is wrong with it.
pub(crate) fn problems(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let m = marks(&svg);
    let mut out = Vec::new();
    if m.data.is_empty() {
        out.push(format!("{}: no data marks", path.display()));
    }
    for (tag, s) in covered(&m).into_iter().take(3) {
        out.push(format!("{}: the legend covers a {tag} at {s:?}", path.display()));
    }
    out
}

fn run(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_csm-lab")).args(args).output().unwrap();
    assert!(
        o.status.success(),
        "csm-lab {args:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn config(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(format!("{name}.toml"))
        .to_string_lossy()
        .into_owned()
}

/// Runs `args` with `--out` into a fresh directory under `dir` and returns its SVG files.
fn svgs_of(dir: &Path, name: &str, args: &[&str]) -> Vec<PathBuf> {
    let out = dir.join(name);
    let mut full: Vec<&str> = args.to_vec();
    let out_s = out.to_string_lossy().into_owned();
    full.extend(["--out", &out_s]);
    run(&full);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_figure_of_every_command_draws_data_and_keeps_its_legend_off_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut checked = Vec::new();
    for c in CONFIGS {
        let cfg = config(c);
        let sweep = svgs_of(dir.path(), &format!("sweep-{c}"), &["sweep", &cfg, "--quiet"]);
        // With scene geometry a sweep also draws the render cost (cost_pareto).
        let geometry = csm_lab::Config::load(std::path::Path::new(&cfg))
            .unwrap()
            .geometry
            .is_some();
        assert_eq!(sweep.len(), 4 + usize::from(geometry), "{c}: {sweep:?}");
        checked.extend(sweep);
        let analyze = svgs_of(dir.path(), &format!("analyze-{c}"), &["analyze", &cfg]);
        assert_eq!(analyze.len(), 3, "{c}: {analyze:?}");
        checked.extend(analyze);
        let compare = svgs_of(dir.path(), &format!("compare-{c}"), &["compare", &cfg]);
        assert_eq!(compare.len(), 2, "{c}: {compare:?}");
        checked.extend(compare);
        let bench = svgs_of(
            dir.path(),
            &format!("bench-{c}"),
            &["bench", "--repeats", "1", "--config", &cfg],
        );
        assert_eq!(bench.len(), 1, "{c}: {bench:?}");
        checked.extend(bench);
    }
    let cfg = config("default");
    for p in PRESETS {
        let sweep = svgs_of(
            dir.path(),
            &format!("preset-{p}"),
            &["sweep", &cfg, "--preset", p, "--quiet"],
        );
        // The default scene has geometry: cost_pareto beside the four.
        assert_eq!(sweep.len(), 5, "{p}: {sweep:?}");
        checked.extend(sweep);
    }
    // Every bundled config and the default scene of the presets have geometry: each sweep
    // draws cost_pareto beside its four figures.
    assert_eq!(checked.len(), 5 * 11 + 11 * 5);
    let wrong: Vec<String> = checked.iter().flat_map(|p| problems(p)).collect();
    assert!(wrong.is_empty(), "{} problems:\n{}", wrong.len(), wrong.join("\n"));
}

/// A minimal plotters-style SVG: background, an axis, a data line, then a legend box with a
/// swatch, at the given legend position.
fn synthetic(legend_y: u32) -> String {
    format!(
        r##"<svg width="400" height="300" viewBox="0 0 400 300" xmlns="http://www.w3.org/2000/svg">
<rect x="0" y="0" width="400" height="300" opacity="1" fill="#FFFFFF" stroke="none"/>
<polyline fill="none" opacity="1" stroke="#000000" stroke-width="1" points="40,20 40,200 "/>
<line opacity="0.2" stroke="#000000" stroke-width="1" x1="40" y1="100" x2="380" y2="100"/>
<polyline fill="none" opacity="1" stroke="#0072B2" stroke-width="3" points="40,190 200,120 380,30 "/>
<rect x="250" y="{legend_y}" width="120" height="40" opacity="0.85" fill="#FFFFFF" stroke="none"/>
<rect x="250" y="{legend_y}" width="120" height="40" opacity="1" fill="none" stroke="#000000"/>
<polyline fill="none" opacity="1" stroke="#0072B2" stroke-width="3" points="255,{sy} 273,{sy} "/>
</svg>"##,
        sy = legend_y + 20
    )
}

#[test]
fn the_checker_finds_a_legend_over_data_and_passes_one_beside_it() {
    // The data line passes y = 30..75 at x = 250..370: a legend at y = 20 covers it.
    let over = marks(&synthetic(20));
    assert_eq!(over.legends, vec![(250.0, 20.0, 370.0, 60.0)]);
    // The background, the axis and the mesh line are not data; the swatch comes after the box.
    assert_eq!(over.data.len(), 1);
    assert_eq!(covered(&over).len(), 1);
    // Below the plot (y = 240..280) it covers nothing.
    let below = marks(&synthetic(240));
    assert_eq!(below.data.len(), 1);
    assert!(covered(&below).is_empty());
    // A segment that crosses the box without a vertex inside it still counts.
    assert!(segment_hits((200.0, 40.0), (400.0, 40.0), (250.0, 20.0, 370.0, 60.0)));
    assert!(!segment_hits((200.0, 10.0), (400.0, 10.0), (250.0, 20.0, 370.0, 60.0)));
    // A figure with no data marks is reported.
    let empty = r##"<svg width="10" height="10" xmlns="http://www.w3.org/2000/svg">
<rect x="0" y="0" width="10" height="10" opacity="1" fill="#FFFFFF" stroke="none"/></svg>"##;
    assert!(marks(empty).data.is_empty());
}
