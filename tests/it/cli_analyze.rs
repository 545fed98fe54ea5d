//! The `analyze` command as a user runs it: exit codes, files, messages.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{with, BASE};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_csm-lab"))
}

fn write_config(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn analyze(text: &str) -> (Output, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), text);
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--out"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    (out, dir)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts exit code 2, no panic, and that the message names every fragment.
fn assert_rejected(text: &str, fragments: &[&str]) {
    let (out, dir) = analyze(text);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for f in fragments {
        assert!(err.contains(f), "message {err:?} should mention {f:?}");
    }
    assert!(!dir.path().join("out").exists(), "no output on error");
}

#[test]
fn analyze_writes_every_file_and_prints_the_table() {
    let (out, dir) = analyze(BASE);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("max_aliasing") && stdout.contains("shimmer_snapped"),
        "{stdout}"
    );
    let o = dir.path().join("out");
    for f in [
        "cascades.csv",
        "density.csv",
        "shimmer.csv",
        "summary.json",
        "density.svg",
        "shimmer.svg",
        "cascades.svg",
    ] {
        let bytes = std::fs::read(o.join(f)).unwrap_or_else(|_| panic!("{f} missing"));
        assert!(!bytes.is_empty());
        let text = String::from_utf8(bytes).unwrap();
        assert!(
            !text.contains("NaN") && !text.contains("inf"),
            "{f} has a non-finite value"
        );
        if f.ends_with(".svg") {
            roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{f}: {e}"));
        }
    }
    let header = std::fs::read_to_string(o.join("cascades.csv")).unwrap();
    assert!(
        header.starts_with(
        "cascade,near,far,radius,width,height,texel_size,centre_x,centre_y,centre_x_texels,centre_y_texels,light_near,light_far,coverage_violations"
    )
    );
    let header = std::fs::read_to_string(o.join("density.csv")).unwrap();
    assert!(header.starts_with("depth,cascade,texel_size,pixel_size,texels_per_pixel,aliasing\n"));
    let header = std::fs::read_to_string(o.join("shimmer.csv")).unwrap();
    assert!(header.starts_with("frame,cascade,snap,size_change,phase_drift_rms,phase_drift_max,cell_flips,path\n"));
}

#[test]
fn summary_json_matches_the_library_analysis() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), BASE);
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--format", "json", "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let printed: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let file: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("o/summary.json")).unwrap()).unwrap();
    assert_eq!(printed, file);
    let c = csm_lab::Config::load(&cfg).unwrap();
    let a = csm_lab::analyze(&c, &csm_lab::AnalysisOptions::full());
    assert_eq!(file["max_aliasing"].as_f64().unwrap(), a.summary.max_aliasing);
    assert_eq!(file["splits"].as_array().unwrap().len(), 5);
    assert_eq!(file["splits"][0].as_f64().unwrap(), a.summary.z_lo);
    assert_eq!(file["inputs"]["camera"]["fov_y_deg"].as_f64().unwrap(), 60.0);
    assert_eq!(file["coverage_violations"].as_u64().unwrap(), 0);
}

#[test]
fn the_same_input_gives_byte_identical_files() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), BASE);
    for o in ["a", "b"] {
        let out = bin()
            .args(["analyze", cfg.to_str().unwrap(), "--out"])
            .arg(dir.path().join(o))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(0));
    }
    for f in [
        "cascades.csv",
        "density.csv",
        "shimmer.csv",
        "summary.json",
        "density.svg",
        "shimmer.svg",
        "cascades.svg",
    ] {
        let x = std::fs::read(dir.path().join("a").join(f)).unwrap();
        let y = std::fs::read(dir.path().join("b").join(f)).unwrap();
        assert!(x == y, "{f} differs between runs");
    }
}

#[test]
fn a_scene_outside_the_shadow_distance_needs_no_cascades_and_exits_0() {
    let text = with(&[
        ("scene.min", "min = [-10.0, 0.0, 500.0]"),
        ("scene.max", "max = [10.0, 5.0, 600.0]"),
    ]);
    let (out, dir) = analyze(&text);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("no cascades needed"));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/summary.json")).unwrap()).unwrap();
    assert_eq!(json["cascades_needed"], serde_json::Value::Bool(false));
    assert!(json["message"].as_str().unwrap().contains("no cascades needed"));
    let csv = std::fs::read_to_string(dir.path().join("out/cascades.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1, "header only");
    let svg = std::fs::read_to_string(dir.path().join("out/density.svg")).unwrap();
    assert!(svg.contains("No cascades needed"));
}

#[test]
fn a_light_pointing_straight_down_is_valid() {
    let (out, dir) = analyze(&with(&[("light.direction", "direction = [0.0, -1.0, 0.0]")]));
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/summary.json")).unwrap()).unwrap();
    assert_eq!(json["light_basis_vertical_fallback"], serde_json::Value::Bool(true));
    assert_eq!(json["coverage_violations"].as_u64(), Some(0));
}

#[test]
fn a_toml_syntax_error_reports_line_and_column() {
    let text = BASE.replace("near = 0.1", "near = = 0.1");
    let line = text.lines().position(|l| l.contains("near = = 0.1")).unwrap() + 1;
    assert_rejected(&text, &[&format!("scene.toml:{line}:")]);
}

#[test]
fn an_unknown_key_is_an_error_naming_it_with_its_line() {
    let text = with(&[("shadow.cascade_count", "cascade_count = 4")]);
    assert_rejected(&text, &["cascade_count", "scene.toml:"]);
}

#[test]
fn nan_and_infinite_numbers_are_rejected() {
    assert_rejected(
        &with(&[("camera.near", "near = nan")]),
        &["camera.near", "NaN", "finite"],
    );
    assert_rejected(&with(&[("camera.far", "far = inf")]), &["camera.far", "inf", "finite"]);
    assert_rejected(
        &with(&[("light.direction", "direction = [0.0, -inf, 0.0]")]),
        &["light.direction"],
    );
}

#[test]
fn degenerate_vectors_are_rejected_with_the_key() {
    assert_rejected(
        &with(&[("light.direction", "direction = [0.0, 0.0, 0.0]")]),
        &["light.direction", "non-zero"],
    );
    assert_rejected(
        &with(&[("camera.up", "up = [0.0, 0.0, 0.0]")]),
        &["camera.up", "non-zero"],
    );
    assert_rejected(
        &with(&[
            ("camera.position", "position = [0.0, 10.0, 0.0]"),
            ("camera.target", "target = [0.0, 0.0, 0.0]"),
        ]),
        &["camera.up", "parallel"],
    );
    assert_rejected(
        &with(&[("camera.target", "target = [0.0, 10.0, 0.0]")]),
        &["camera.target"],
    );
}

#[test]
fn out_of_range_values_name_the_key_the_value_and_what_is_allowed() {
    let cases: [(&str, &str, &[&str]); 12] = [
        ("camera.near", "near = 0.0", &["camera.near", "= 0", "> 0"]),
        ("camera.near", "near = -1.0", &["camera.near", "-1"]),
        (
            "camera.far",
            "far = 0.05",
            &["camera.far", "0.05", "greater than camera.near"],
        ),
        (
            "camera.fov_y_deg",
            "fov_y_deg = 0.0",
            &["camera.fov_y_deg", "between 0 and 180"],
        ),
        ("camera.fov_y_deg", "fov_y_deg = 180.0", &["camera.fov_y_deg", "180"]),
        ("shadow.cascades", "cascades = 0", &["shadow.cascades", "1..=16"]),
        ("shadow.cascades", "cascades = 17", &["shadow.cascades", "17"]),
        (
            "shadow.resolution",
            "resolution = 8",
            &["shadow.resolution", "16..=16384"],
        ),
        (
            "shadow.resolution",
            "resolution = 32768",
            &["shadow.resolution", "32768"],
        ),
        ("shadow.lambda", "lambda = 1.5", &["shadow.lambda", "[0, 1]"]),
        ("shadow.lambda", "lambda = -0.1", &["shadow.lambda", "-0.1"]),
        ("shadow.fit", "fit = \"box\"", &["box", "sphere"]),
    ];
    for (key, line, fragments) in cases {
        let text = with(&[(key, line)]);
        assert_rejected(&text, fragments);
    }
    // Validation errors point at the line of the key.
    let text = with(&[("shadow.cascades", "cascades = 99")]);
    let line = text.lines().position(|l| l.trim() == "cascades = 99").unwrap() + 1;
    assert_rejected(&text, &[&format!("scene.toml:{line}:1: `shadow.cascades` = 99")]);
}

#[test]
fn a_missing_path_file_or_a_malformed_row_is_a_clear_error() {
    let text = with(&[
        ("motion.path", "path = \"file\""),
        ("motion.file", "file = \"nope.csv\""),
    ]);
    assert_rejected(&text, &["nope.csv", "cannot read"]);

    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("p.csv"),
        "px,py,pz,tx,ty,tz\n0,10,0,0,0,-50\n0.1,10,0,0.1,oops,-50\n",
    )
    .unwrap();
    let cfg = write_config(
        dir.path(),
        &with(&[("motion.path", "path = \"file\""), ("motion.file", "file = \"p.csv\"")]),
    );
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("p.csv:3") && err.contains("ty") && err.contains("oops"),
        "{err}"
    );

    std::fs::write(
        dir.path().join("p.csv"),
        "px,py,pz,tx,ty,tz\n0,10,0,0,0,-50\n0.5,10,0,0.5,0,-50\n1,10,0,1,0,-50\n",
    )
    .unwrap();
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let shimmer = std::fs::read_to_string(dir.path().join("o/shimmer.csv")).unwrap();
    assert_eq!(
        shimmer.lines().count(),
        1 + 2 * 2 * 4,
        "2 frame pairs x 2 snap modes x 4 cascades"
    );
}

#[test]
fn pitching_through_the_up_vector_is_a_config_error_not_a_panic() {
    assert_rejected(
        &with(&[
            ("motion.path", "path = \"pitch\""),
            ("motion.step", "step = 1.0"),
            ("motion.frames", "frames = 200"),
        ]),
        &["motion.step", "parallel"],
    );
}

#[test]
fn a_missing_config_file_exits_2() {
    let out = bin().args(["analyze", "/definitely/not/here.toml"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("cannot read /definitely/not/here.toml"));
}

#[test]
fn an_unknown_flag_exits_2_and_help_exits_0() {
    let out = bin().args(["analyze", "x.toml", "--bogus"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = bin().arg("--help").output().unwrap();
    assert_eq!(out.status.code(), Some(0));
}

/// The binary32 emulation follows each preset's own scheme, so presets run in f32 whether
/// the file or the flag asks for it (they used to be refused).
#[test]
fn the_f32_emulation_runs_with_an_engine_preset_from_the_key_or_the_flag() {
    let (out, _dir) = analyze(&with(&[
        ("shadow.preset", "preset = \"bevy\""),
        ("shadow.precision", "precision = \"f32\""),
    ]));
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("precision f32"));
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), &with(&[("shadow.preset", "preset = \"godot\"")]));
    let out = bin()
        .args(["analyze", cfg.to_str().unwrap(), "--precision", "f32", "--out"])
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("precision f32"));
    assert!(dir.path().join("o").join("cascades.csv").exists());
}
