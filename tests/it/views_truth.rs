//! Ground truth over a level of views (issue 22, docs/ground-truth.md "Over a level of views"):
//! the judged views' passes pooled, each view's own equal to the single-camera pass from its
//! pose, the subset of a large level stated; and the level's other promises met from every
//! source of views (`[[view]]`, `from_gltf`, `sample`), with a view inside geometry named by its
//! key.

use std::path::Path;

use crate::common::{self, read_csv};
use crate::views::{level, run_cli, scene, VIEWS};
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::Config;

/// The ground-truth pass, on a coarse screen (the pass per view stays well under a second).
const TRUTH: &str = "\n[analysis]\nground_truth = true\nscreen_scale = 0.125\n";

fn with_truth(views: &[(&str, [f64; 3], [f64; 3], f64)]) -> Config {
    common::config(&(level(views) + TRUTH))
}

/// The scene with `[camera]` at a view's pose, no views, and the pass.
fn camera_with_truth(p: [f64; 3], t: [f64; 3]) -> Config {
    let text = scene()
        .replace("position = [0.0, 10.0, 0.0]", &format!("position = {p:?}"))
        .replace("target = [0.0, 0.0, -50.0]", &format!("target = {t:?}"));
    common::config(&(text + TRUTH))
}

fn truth_opts() -> AnalysisOptions {
    AnalysisOptions {
        ground_truth: true,
        ..AnalysisOptions::summary_only()
    }
}

/// Each judged view's ground truth is the single-camera pass from its pose, bit for bit, and
/// the level's is the brute-force pool of those passes: every fraction's numerator and
/// denominator (receivers covered at frame 0, receiver steps per snap mode) summed with the
/// view's weight, then divided.
#[test]
fn the_levels_ground_truth_is_the_weighted_pool_of_the_single_camera_passes() {
    let a = analyze(&with_truth(&VIEWS), &truth_opts());
    let pooled = a.summary.truth.expect("the level's ground truth");
    // [camera]'s own pass still runs (bias.csv, cascades.csv, the pictures).
    assert!(a.ground_truth.is_some());
    // (numerator, denominator) sums per metric, in the order of `metric` below.
    let mut sums = [(0.0f64, 0.0f64); 9];
    for (k, &(name, p, t, w)) in VIEWS.iter().enumerate() {
        let alone = analyze(&camera_with_truth(p, t), &truth_opts());
        let g = alone.ground_truth.as_ref().expect("a pass");
        let v = &a.summary.views[k];
        assert!(v.judged, "{name}");
        assert_eq!(v.truth, Some(g.summary), "{name}");
        let covered = g.zero.iter().filter(|z| z.map_lit.is_some()).count() as f64;
        let steps = |f: &csm_core::truth::Flicker| f.steps.iter().map(|&x| f64::from(x)).sum::<f64>();
        let (ss, su) = (steps(&g.snapped), steps(&g.unsnapped));
        assert!(covered > 500.0 && su > 1000.0, "{name}: {covered} covered, {su} steps");
        let s = &g.summary;
        let parts = [
            (s.acne_fraction, covered),
            (s.edge_error_fraction, covered),
            (s.leak_fraction, covered),
            (s.flicker_snapped, ss),
            (s.flicker_unsnapped, su),
            (s.flicker_edge_snapped, ss),
            (s.flicker_edge_unsnapped, su),
            (s.flicker_acne_snapped, ss),
            (s.flicker_acne_unsnapped, su),
        ];
        for (sum, (fraction, den)) in sums.iter_mut().zip(parts) {
            sum.0 += w * fraction * den;
            sum.1 += w * den;
        }
    }
    let got = [
        pooled.acne_fraction,
        pooled.edge_error_fraction,
        pooled.leak_fraction,
        pooled.flicker_snapped,
        pooled.flicker_unsnapped,
        pooled.flicker_edge_snapped,
        pooled.flicker_edge_unsnapped,
        pooled.flicker_acne_snapped,
        pooled.flicker_acne_unsnapped,
    ];
    for (i, ((num, den), x)) in sums.iter().zip(got).enumerate() {
        let want = if *den > 0.0 { num / den } else { 0.0 };
        assert!(
            (x - want).abs() <= 1e-12 * want.abs().max(1e-12),
            "metric {i}: {x} vs {want}"
        );
    }
    // The views differ: the pool is none of them.
    let own: Vec<f64> = a
        .summary
        .views
        .iter()
        .map(|v| v.truth.unwrap().edge_error_fraction)
        .collect();
    assert!(own.iter().all(|&x| x != pooled.edge_error_fraction), "{own:?}");
}

/// A level of one view is that view's single-camera ground truth, bit for bit, whatever its
/// weight: at `[camera]`'s pose (the camera's pass reused) and elsewhere (a pass of its own).
#[test]
fn a_level_of_one_view_equals_the_single_camera_ground_truth() {
    let plain = camera_with_truth([0.0, 10.0, 0.0], [0.0, 0.0, -50.0]);
    let a = analyze(&plain, &truth_opts());
    let one = with_truth(&[("camera", [0.0, 10.0, 0.0], [0.0, 0.0, -50.0], 1.0)]);
    let b = analyze(&one, &truth_opts());
    assert!(a.summary.views.is_empty());
    assert_eq!(b.summary.truth, a.summary.truth);
    assert_eq!(b.summary.views[0].truth, a.summary.truth);
    let (_, p, t, _) = VIEWS[1];
    let alone = analyze(&camera_with_truth(p, t), &truth_opts());
    let lvl = analyze(&with_truth(&[("roof", p, t, 2.0)]), &truth_opts());
    assert!(alone.summary.truth.is_some());
    assert_eq!(lvl.summary.truth, alone.summary.truth);
    // Two identical views are one.
    let two = analyze(&with_truth(&[("a", p, t, 3.0), ("b", p, t, 3.0)]), &truth_opts());
    assert_eq!(two.summary.truth, alone.summary.truth);
}

/// Ten views on a line, none inside a box, each looking into the scene.
fn ten_views() -> Vec<(String, [f64; 3], [f64; 3])> {
    (0..10)
        .map(|i| {
            let x = -45.0 + 10.0 * f64::from(i);
            (format!("v{i}"), [x, 1.7, 10.0], [x * 0.5, 0.0, -60.0])
        })
        .collect()
}

/// Of ten views the pass judges eight, `floor(k · 10 / 8)`: views 0, 1, 2, 3, 5, 6, 7, 8. They
/// are named in `summary.json` (`ground_truth_views`), marked in `views.csv` with their own
/// values (the others' left empty), and said on stdout; the same at one and two threads.
#[test]
fn a_large_level_judges_a_stated_evenly_spaced_subset() {
    let views = ten_views();
    let entries: Vec<(&str, [f64; 3], [f64; 3], f64)> =
        views.iter().map(|(n, p, t)| (n.as_str(), *p, *t, 1.0)).collect();
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("ten.toml");
    std::fs::write(&cfg, level(&entries) + TRUTH).unwrap();
    let outs = [dir.path().join("t1"), dir.path().join("t2")];
    let mut stdout = String::new();
    for (threads, out) in ["1", "2"].iter().zip(&outs) {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_csm-lab"))
            .args([
                "analyze",
                cfg.to_str().unwrap(),
                "--quiet",
                "--out",
                out.to_str().unwrap(),
            ])
            .env("RAYON_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    }
    assert_eq!(common::files(&outs[0]), common::files(&outs[1]));
    let want = ["v0", "v1", "v2", "v3", "v5", "v6", "v7", "v8"];
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(outs[0].join("summary.json")).unwrap()).unwrap();
    let judged = &summary["ground_truth_views"];
    assert_eq!(judged["count"], 8);
    assert_eq!(judged["of"], 10);
    let names: Vec<&str> = judged["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(names, want);
    assert!(judged["rule"].as_str().unwrap().contains("floor(k * N / 8)"));
    assert!(
        stdout.contains("pool 8 of 10 views (evenly spaced by index, at most 8: v0, v1, v2, v3, v5, v6, v7, v8)"),
        "{stdout}"
    );
    let (head, rows) = read_csv(&outs[0].join("views.csv"));
    let col = |key: &str| head.iter().position(|h| h == key).unwrap_or_else(|| panic!("{key}"));
    for r in &rows {
        let judged = want.contains(&r[0].as_str());
        assert_eq!(r[col("ground_truth_judged")], judged.to_string(), "{}", r[0]);
        assert_eq!(r[col("flicker_unsnapped")].is_empty(), !judged, "{}", r[0]);
    }
    // The level's acne is the pool of the judged views' rows (equal weights: covered counts
    // are not in the file, so only its range is checked here; the exact pool is checked above).
    let own: Vec<f64> = rows
        .iter()
        .filter(|r| want.contains(&r[0].as_str()))
        .map(|r| r[col("edge_error_fraction")].parse().unwrap())
        .collect();
    let level = summary["edge_error_fraction"].as_f64().unwrap();
    let (lo, hi) = own.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    assert!(lo <= level && level <= hi, "{level} outside {lo}..{hi}");
}

/// `sweep --ground-truth` over a level: each sampled row's S5 is the level's pooled value, the
/// one `analyze --ground-truth` gives for that row's setting, and the sentence names the views.
#[test]
fn a_ground_truth_sweep_over_a_level_pools_each_rows_s5_over_the_views() {
    let dir = tempfile::tempdir().unwrap();
    let text = level(&VIEWS[..2]) + "\n[analysis]\nscreen_scale = 0.125\n[sweep]\nlambda = [0.5, 0.75]\ncascades = [2]\nresolution = [1024]\nfit = [\"sphere\"]\n";
    let cfg = dir.path().join("lvl.toml");
    std::fs::write(&cfg, &text).unwrap();
    let out = dir.path().join("sweep");
    let o = run_cli(&[
        "sweep",
        cfg.to_str().unwrap(),
        "--ground-truth",
        "--no-plots",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("each row's S5 pools the ground truth of 2 of the level's 2 views (every view: street, roof)"),
        "{stdout}"
    );
    let (head, rows) = read_csv(&out.join("flicker.csv"));
    let col = |key: &str| head.iter().position(|h| h == key).unwrap();
    assert_eq!(rows.len(), 2);
    for (r, lambda) in rows.iter().zip(["0.5", "0.75"]) {
        let one = text.replace("lambda = 0.75", &format!("lambda = {lambda}"));
        let an = dir.path().join(format!("an{lambda}"));
        let c = dir.path().join(format!("c{lambda}.toml"));
        std::fs::write(
            &c,
            one.replace("cascades = 4", "cascades = 2")
                .replace("resolution = 2048", "resolution = 1024"),
        )
        .unwrap();
        let a = run_cli(&[
            "analyze",
            c.to_str().unwrap(),
            "--ground-truth",
            "--quiet",
            "--out",
            an.to_str().unwrap(),
        ]);
        assert_eq!(a.status.code(), Some(0), "{}", String::from_utf8_lossy(&a.stderr));
        let s: serde_json::Value = serde_json::from_slice(&std::fs::read(an.join("summary.json")).unwrap()).unwrap();
        assert_eq!(s["ground_truth_views"]["count"], 2);
        for key in ["flicker_snapped", "flicker_unsnapped"] {
            let got: f64 = r[col(key)].parse().unwrap();
            assert_eq!(got, s[key].as_f64().unwrap(), "λ {lambda} {key}");
        }
    }
}

/// A small sweep grid for the levels below.
const SMALL_GRID: &str =
    "\n[sweep]\nlambda = [0.5, 0.75]\ncascades = [2, 4]\nresolution = [1024]\nfit = [\"sphere\"]\n";

/// What a level writes, whatever made its views: `analyze` writes `views.csv` (one row per
/// view), the pooled statistics and the views in `summary.json`, and `plan.png`; `sweep`
/// writes `plan.png`, `views.csv` and a recommendation for the level with each view's own
/// choice beside it (`recommendation.json`).
fn writes_a_levels_files(dir: &Path, text: &str, views: usize) {
    let cfg = dir.join("level.toml");
    std::fs::write(&cfg, text.to_string() + SMALL_GRID).unwrap();
    let an = dir.join("an");
    let a = run_cli(&[
        "analyze",
        cfg.to_str().unwrap(),
        "--quiet",
        "--out",
        an.to_str().unwrap(),
    ]);
    assert_eq!(a.status.code(), Some(0), "{}", String::from_utf8_lossy(&a.stderr));
    let (_, rows) = read_csv(&an.join("views.csv"));
    assert_eq!(rows.len(), views);
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(an.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["views"]["count"], views);
    assert!(s["visible_aliasing_p95"].as_f64().unwrap() > 0.0);
    assert!(an.join("plan.png").exists());
    let sw = dir.join("sweep");
    let o = run_cli(&["sweep", cfg.to_str().unwrap(), "--quiet", "--out", sw.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(sw.join("plan.png").exists());
    let (head, rows) = read_csv(&sw.join("views.csv"));
    assert_eq!(rows.len(), views);
    assert!(head.contains(&"alone_setting".to_string()));
    let rec: serde_json::Value =
        serde_json::from_slice(&std::fs::read(sw.join("recommendation.json")).unwrap()).unwrap();
    assert!(rec["recommended"].is_object(), "{rec}");
    let per_view = rec["views"]["views"].as_array().unwrap();
    assert_eq!(per_view.len(), views);
    assert!(per_view.iter().any(|v| v["alone"].is_string()), "{per_view:?}");
    let md = std::fs::read_to_string(sw.join("report.md")).unwrap();
    assert!(md.contains("## Views") && md.contains("(plan.png)"), "{md}");
}

#[test]
fn a_level_of_sampled_players_writes_a_levels_files() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene() + "\n[views]\nsample = 3\nseed = 7\n";
    writes_a_levels_files(dir.path(), &text, 3);
}

#[test]
fn a_level_of_gltf_cameras_writes_a_levels_files() {
    // The bundled village with two camera nodes added: one at the street's start looking down
    // it (-Z), one turned a quarter about +Y (looking along -X).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut g: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("configs/village.gltf")).unwrap()).unwrap();
    g["cameras"] = serde_json::json!([{"type": "perspective", "perspective": {"yfov": 1.0, "aspectRatio": 1.7777778, "znear": 0.1}}]);
    let nodes = g["nodes"].as_array_mut().unwrap();
    let first = nodes.len();
    let h = std::f64::consts::FRAC_PI_4;
    nodes.push(serde_json::json!({"name": "street", "translation": [0.0, 1.8, 5.0], "camera": 0}));
    nodes.push(serde_json::json!({"name": "lane", "translation": [0.0, 1.8, -40.0], "rotation": [0.0, h.sin(), 0.0, h.cos()], "camera": 0}));
    let scene_nodes = g["scenes"][0]["nodes"].as_array_mut().unwrap();
    scene_nodes.push(first.into());
    scene_nodes.push((first + 1).into());
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("village.gltf"), serde_json::to_vec(&g).unwrap()).unwrap();
    let text = std::fs::read_to_string(root.join("configs/village.toml")).unwrap();
    let text = text.split("[sweep]").next().unwrap().to_string() + "\n[views]\nfrom_gltf = true\n";
    writes_a_levels_files(dir.path(), &text, 2);
    let (_, rows) = read_csv(&dir.path().join("an/views.csv"));
    assert_eq!(rows[0][0], "street");
    assert_eq!(rows[1][0], "lane");
}

/// A `[[view]]` entry inside a box is an error naming its own key, `view[1].position`, with
/// the file's line and column, and the view's name.
#[test]
fn a_view_entry_inside_geometry_is_named_by_its_key() {
    let inside = [VIEWS[0], ("boxed", [-30.0, 10.0, -75.0], [0.0, 0.0, 0.0], 1.0)];
    let err = match Config::from_toml_str(&level(&inside), "t.toml", None) {
        Ok(_) => panic!("a view inside a box was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("view[1].position") && err.contains("\"boxed\"") && err.contains("inside geometry"),
        "{err}"
    );
    assert!(err.contains("t.toml:"), "no line and column: {err}");
}
