//! One "worst" (issue 21, item 2): with scene geometry every worst case the sweep and compare
//! print or rank on is the on-screen `screen_aliasing_max`, never the bounds' near-plane
//! `max_aliasing`; the depth charts shade the depths without visible geometry.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

fn run(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

fn default_scene(dir: &Path) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("configs/default.toml")).unwrap();
    // The scene with its geometry, without its [sweep] table (the grid comes from the flags).
    let text = text
        .split("[sweep]")
        .next()
        .unwrap()
        .replace("frames = 240", "frames = 30");
    std::fs::write(dir.join("scene.toml"), text).unwrap();
}

fn percent(base: f64, value: f64) -> f64 {
    100.0 * (value / base - 1.0)
}

#[test]
fn with_geometry_the_sweep_speaks_of_the_worst_case_on_screen() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    default_scene(d);
    let stdout = run(
        d,
        &[
            "sweep",
            "scene.toml",
            "--quiet",
            "--no-plots",
            "--lambda",
            "0.2,0.4,0.6",
            "--cascades",
            "2,3,4,5",
            "--resolution",
            "1024,2048",
            "--out",
            "out",
        ],
    );
    let rec: Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/recommendation.json")).unwrap()).unwrap();
    let recommended = &rec["recommended"];
    let worst = recommended["screen_aliasing_max"].as_f64().unwrap();
    let bounds = recommended["max_aliasing"].as_f64().unwrap();
    assert!(
        bounds > 2.0 * worst,
        "the scene's near plane aliases far more than any pixel: {bounds} / {worst}"
    );
    // The verdict's "worst" is the screen value, and so is the Pareto table's column.
    assert!(
        stdout.contains(&format!("worst {}", csm_lab::output::short_number(worst))),
        "{stdout}"
    );
    assert!(stdout.contains("      worst    shimmer"), "{stdout}");
    assert!(
        !stdout.contains("max aliasing"),
        "the bounds value is not printed as the worst: {stdout}"
    );
    // Alternatives: the change of the screen worst case, computed from the two rows.
    let alts = rec["alternatives"].as_array().unwrap();
    assert!(!alts.is_empty());
    for a in alts {
        assert!(a.get("max_aliasing_change_percent").is_none(), "{a}");
        let x = a["configuration"]["screen_aliasing_max"].as_f64().unwrap();
        let p = a["screen_aliasing_max_change_percent"].as_f64().unwrap();
        assert!(
            (p - percent(worst, x)).abs() < 1e-9,
            "{p} against {}",
            percent(worst, x)
        );
        let line = format!("worst on screen {}", csm_lab::output::short_number(x));
        assert!(stdout.contains(&line), "{line} not in {stdout}");
    }
    // A rival tied on the objective loses on the screen worst case, and says so by that name.
    for r in rec["rivals"].as_array().unwrap() {
        assert_ne!(r["lost_on"], "max_aliasing", "{r}");
    }
    // The rule in words names the tie-breaker it uses.
    let text = serde_json::to_string(&rec).unwrap();
    assert!(
        text.contains("the lowest screen_aliasing_max"),
        "the rule names the screen worst case"
    );
    assert!(!text.contains("the lowest max aliasing"), "{text}");
}

#[test]
fn bounds_only_keeps_max_aliasing_as_its_worst_case() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("scene.toml"), crate::common::BASE).unwrap();
    let stdout = run(
        d,
        &[
            "sweep",
            "scene.toml",
            "--quiet",
            "--no-plots",
            "--lambda",
            "0.2,0.4,0.6",
            "--cascades",
            "2,3,4",
            "--resolution",
            "1024,2048",
            "--out",
            "out",
        ],
    );
    let rec: Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("out/recommendation.json")).unwrap()).unwrap();
    assert!(rec["recommended"].get("screen_aliasing_max").is_none());
    for a in rec["alternatives"].as_array().unwrap() {
        assert!(a.get("screen_aliasing_max_change_percent").is_none(), "{a}");
        assert!(a.get("max_aliasing_change_percent").is_some(), "{a}");
    }
    assert!(stdout.contains("        max    shimmer"), "{stdout}");
}

/// The depth charts shade the depths outside the visible geometry's range, and their legend
/// names that range as `summary.json` gives it.
#[test]
fn the_density_chart_shades_the_depths_without_visible_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    default_scene(d);
    run(d, &["analyze", "scene.toml", "--quiet", "--out", "out"]);
    let summary: Value = serde_json::from_str(&std::fs::read_to_string(d.join("out/summary.json")).unwrap()).unwrap();
    let (lo, hi) = (
        summary["visible_z_lo"].as_f64().unwrap(),
        summary["visible_z_hi"].as_f64().unwrap(),
    );
    let z_lo = summary["z_lo"].as_f64().unwrap();
    assert!(
        lo > 10.0 * z_lo,
        "the visible geometry starts well beyond the near plane: {lo} against {z_lo}"
    );
    let svg = std::fs::read_to_string(d.join("out/density.svg")).unwrap();
    assert!(svg.contains("shaded: no visible geometry"), "no shading legend");
    // The shade is drawn (a translucent grey rectangle).
    assert!(svg.contains("opacity=\"0.35\" fill=\"#A0A0A0\""), "no shaded rectangle");
    // The legend's numbers are the summary's, in the figures' tick format.
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let legend = doc
        .descendants()
        .filter_map(|n| n.text())
        .map(str::trim)
        .find(|t| t.starts_with("shaded: no visible geometry"))
        .unwrap()
        .to_string();
    for v in [lo, hi] {
        let shown = csm_lab::output::short_number(v);
        assert!(legend.contains(&shown), "{legend} lacks {shown}");
    }
    // Bounds only: nothing to shade, no legend entry.
    std::fs::write(d.join("bounds.toml"), crate::common::BASE).unwrap();
    run(d, &["analyze", "bounds.toml", "--quiet", "--out", "bounds"]);
    let svg = std::fs::read_to_string(d.join("bounds/density.svg")).unwrap();
    assert!(!svg.contains("shaded: no visible geometry"));
}

/// `compare` with geometry: the near-plane value is labelled the bounds metric it is, and the
/// worst case on screen stands beside the objective the verdict ranks on.
#[test]
fn compare_names_the_bounds_max_and_shows_the_worst_on_screen() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    default_scene(d);
    let stdout = run(
        d,
        &[
            "compare",
            "scene.toml",
            "--quiet",
            "--presets",
            "bevy,unity",
            "--out",
            "out",
        ],
    );
    assert!(
        stdout.contains("bounds max") && stdout.contains("scr worst"),
        "{stdout}"
    );
    let md = std::fs::read_to_string(d.join("out/compare.md")).unwrap();
    let header = md.lines().find(|l| l.starts_with("| preset |")).unwrap();
    let cells: Vec<&str> = header.split('|').map(str::trim).collect();
    assert!(cells.contains(&"bounds max aliasing"), "{header}");
    assert!(!cells.contains(&"max aliasing"), "{header}");
    assert!(cells.contains(&"visible_aliasing_p95"), "{header}");
    let col = cells.iter().position(|c| *c == "worst on screen").expect(header);
    // Each preset's cell is its screen_aliasing_max, from its own analysis.
    for (preset, line) in ["bevy", "unity"]
        .iter()
        .map(|p| (*p, md.lines().find(|l| l.starts_with(&format!("| {p} |"))).unwrap()))
    {
        let sub = d.join(format!("a-{preset}"));
        run(
            d,
            &[
                "analyze",
                "scene.toml",
                "--quiet",
                "--preset",
                preset,
                "--out",
                sub.to_str().unwrap(),
            ],
        );
        let s: Value = serde_json::from_str(&std::fs::read_to_string(sub.join("summary.json")).unwrap()).unwrap();
        let want = csm_lab::output::short_number(s["screen_aliasing_max"].as_f64().unwrap());
        let got = line.split('|').map(str::trim).nth(col).unwrap();
        assert_eq!(got, want, "{preset}: {line}");
    }
}
