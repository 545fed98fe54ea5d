//! `analyze` with the binary32 emulation and world offsets, as a user runs it.

use crate::common;

use std::path::Path;
use std::process::{Command, Output};

use common::with;

fn analyze(text: &str, dir: &Path, extra: &[&str]) -> Output {
    let cfg = dir.join("scene.toml");
    std::fs::write(&cfg, text).unwrap();
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .arg("analyze")
        .arg(&cfg)
        .arg("--out")
        .arg(dir.join("out"))
        .args(extra)
        .output()
        .unwrap()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("out/summary.json")).unwrap()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const AT_1E5: (&str, &str) = ("scene.world_offset", "world_offset = [100000.0, 0.0, 0.0]");

#[test]
fn analyze_with_precision_f32_measures_the_emulated_pipeline_and_reports_s7() {
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(&with(&[AT_1E5]), dir.path(), &["--precision", "f32"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(
        table.contains("precision f32, snap_space world") && table.contains("lookup_error_max"),
        "{table}"
    );
    let s = summary(dir.path());
    assert_eq!(s["inputs"]["shadow"]["precision"], "f32");
    assert_eq!(s["inputs"]["scene"]["world_offset"][0].as_f64(), Some(1e5));
    assert!(
        s["shimmer_snapped"].as_f64().unwrap() > 1e-2,
        "world-anchored f32 at 1e5 drifts"
    );
    assert!(s["lookup_error_max"].as_f64().unwrap() > 0.1);
    assert!(s["lookup_error_rms"].as_f64().unwrap() > 0.0);
    let csv = std::fs::read_to_string(dir.path().join("out/cascades.csv")).unwrap();
    assert!(csv
        .lines()
        .next()
        .unwrap()
        .contains(",lookup_error_max,lookup_error_rms,"));
    let shimmer = std::fs::read_to_string(dir.path().join("out/shimmer.csv")).unwrap();
    assert!(!shimmer.contains("NaN") && shimmer.lines().count() > 1);
}

#[test]
fn the_precision_flag_overrides_the_config_file() {
    let text = with(&[
        AT_1E5,
        ("shadow.precision", "precision = \"f32\""),
        ("shadow.snap_space", "snap_space = \"camera_relative\""),
    ]);
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(&text, dir.path(), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let s = summary(dir.path());
    let relative = s["shimmer_snapped"].as_f64().unwrap();
    assert!(relative > 0.0 && relative < 1e-3, "camera-relative f32: {relative}");
    let out = analyze(&text, dir.path(), &["--precision", "f64"]);
    assert_eq!(out.status.code(), Some(0));
    let s = summary(dir.path());
    assert_eq!(s["inputs"]["shadow"]["precision"], "f64");
    assert_eq!(s["shimmer_snapped"].as_f64(), Some(0.0));
    assert_eq!(s["lookup_error_max"].as_f64(), Some(0.0));
    assert!(!String::from_utf8_lossy(&out.stdout).contains("precision f32"));
}

#[test]
fn precision_f32_on_a_scene_binary32_cannot_hold_is_an_error_naming_the_flag_or_key() {
    // Millimetre-thin slices (near 1e-3, pure log splits, 16 cascades, tight AABB fit) 200 km
    // from the origin: one binary32 step there is 1.6 cm, so the f32 window collapses.
    let tiny = [
        ("camera.near", "near = 0.001"),
        ("shadow.lambda", "lambda = 1.0"),
        ("shadow.cascades", "cascades = 16"),
        ("shadow.fit", "fit = \"aabb\""),
        ("scene.world_offset", "world_offset = [200000.0, 0.0, 200000.0]"),
    ];
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(&with(&tiny), dir.path(), &[]);
    assert_eq!(out.status.code(), Some(0), "fine in f64: {}", stderr(&out));
    let dir = tempfile::tempdir().unwrap();
    let out = analyze(&with(&tiny), dir.path(), &["--precision", "f32"]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("--precision \"f32\"") && err.contains("binary32") && !err.contains("panicked"),
        "{err}"
    );
    assert!(!dir.path().join("out").exists(), "no output on error");
    let mut in_file = tiny.to_vec();
    in_file.push(("shadow.precision", "precision = \"f32\""));
    let out = analyze(&with(&in_file), dir.path(), &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("`shadow.precision` = \"f32\""),
        "{}",
        stderr(&out)
    );
    // An unknown precision on the command line is a usage error.
    let out = analyze(&with(&[]), dir.path(), &["--precision", "f16"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("f16"));
}

/// Regression (found by `csm-lab stress`): a shadow distance below the near plane with
/// `fit_depth_to_scene = false` panicked; it needs no cascades, as with scene clipping.
#[test]
fn a_shadow_distance_below_the_near_plane_needs_no_cascades_instead_of_panicking() {
    for clip in ["true", "false"] {
        let dir = tempfile::tempdir().unwrap();
        let text = with(&[
            ("shadow.max_distance", "max_distance = 0.05"),
            ("shadow.fit_depth_to_scene", &format!("fit_depth_to_scene = {clip}")),
        ]);
        let out = analyze(&text, dir.path(), &[]);
        assert_eq!(out.status.code(), Some(0), "{clip}: {}", stderr(&out));
        assert!(String::from_utf8_lossy(&out.stdout).contains("no cascades needed"));
        assert_eq!(summary(dir.path())["cascades_needed"], false);
    }
}
