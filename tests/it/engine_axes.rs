//! Engine knob and shadow-distance sweep axes (`docs/presets.md`, "Sweep axes"): a preset's
//! sweep varies the knobs the engine really has, each row equals an analysis of a config file
//! that sets that knob in the engine's own table, and the report names the knob in the engine's
//! terms.

use crate::common::{config, with};

use std::process::Command;

use csm_lab::commands::sweep::grid::{parse_distance_spec, parse_knob_spec, Grid};
use csm_lab::commands::sweep::run::run;
use csm_lab::config::sweep_spec::SweepAxes;
use csm_lab::{analyze, AnalysisOptions};

fn preset_text(preset: &str, extra: &[(&str, &str)]) -> String {
    let mut edits = vec![("shadow.preset", format!("preset = \"{preset}\""))];
    edits.extend(extra.iter().map(|(k, l)| (*k, l.to_string())));
    let edits: Vec<(&str, &str)> = edits.iter().map(|(k, l)| (*k, l.as_str())).collect();
    with(&edits)
}

/// Every row of a knob × distance sweep equals `analyze` of the file with the knob written in
/// the engine's table, the count, map size and distance in `[shadow]` (an independent path:
/// the engine parses and validates its own table).
fn rows_equal_file_analyses(preset: &str, table: &str, knob: &str, knobs: &str, distances: &str) {
    let base = config(&preset_text(preset, &[]));
    let overrides = SweepAxes {
        cascades: Some(csm_lab::commands::sweep::grid::parse_cascades_spec("2,4").unwrap()),
        resolution: Some(csm_lab::commands::sweep::grid::parse_resolution_spec("1024").unwrap()),
        knob: Some(parse_knob_spec(knobs).unwrap()),
        distance: Some(parse_distance_spec(distances).unwrap()),
        ..Default::default()
    };
    let grid = Grid::resolve(&base, &overrides).unwrap();
    let n_knobs = knobs.split(',').count();
    let n_dist = distances.split(',').count();
    assert_eq!(grid.len(), 2 * n_knobs * n_dist);
    let rows = run(&base, &grid, Some(2), &|| {}).unwrap();
    assert_eq!(rows.len(), grid.len());
    let mut distinct = std::collections::BTreeSet::new();
    for row in &rows {
        let st = row.setting;
        let (k, d) = (st.knob.unwrap(), st.distance.unwrap());
        let text = preset_text(
            preset,
            &[
                ("shadow.cascades", &format!("cascades = {}", st.cascades)),
                ("shadow.resolution", &format!("resolution = {}", st.resolution)),
                ("shadow.max_distance", &format!("max_distance = {d}")),
                (&format!("{table}.{knob}"), &format!("{knob} = {k}")),
            ],
        );
        let a = analyze(&config(&text), &AnalysisOptions::summary_only());
        assert_eq!(a.summary, row.summary, "{preset}: {}", st.label());
        distinct.insert(row.summary.mean_aliasing.to_bits());
    }
    // The knob and the distance change the result (the axis is not ignored).
    assert!(
        distinct.len() > rows.len() / 2,
        "{preset}: {} distinct of {}",
        distinct.len(),
        rows.len()
    );
}

#[test]
fn unreal_exponent_and_distance_rows_equal_analyses_of_files_with_them_set() {
    rows_equal_file_analyses(
        "unreal",
        "unreal",
        "cascade_distribution_exponent",
        "1.5,3,4",
        "100,150",
    );
}

#[test]
fn bevy_first_far_bound_and_distance_rows_equal_analyses_of_files_with_them_set() {
    rows_equal_file_analyses("bevy", "bevy", "first_cascade_far_bound", "5,10,20", "80,150");
}

#[test]
fn default_preset_grids_sweep_the_knob_around_its_configured_value() {
    let unreal = Grid::resolve(&config(&preset_text("unreal", &[])), &SweepAxes::default()).unwrap();
    let k = unreal.knob.as_ref().unwrap();
    assert_eq!(k.values, vec![1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0]);
    // 8 counts × 4 sizes × 7 exponents: hundreds, not thousands.
    assert_eq!(unreal.len(), 8 * 4 * 7);
    assert!(unreal.distance.is_none());
    // Bevy's default far bound 10, ×¼ … ×2, all below the 150 shadow distance.
    let bevy = Grid::resolve(&config(&preset_text("bevy", &[])), &SweepAxes::default()).unwrap();
    assert_eq!(bevy.knob.unwrap().values, vec![2.5, 5.0, 7.5, 10.0, 15.0, 20.0]);
    // A short shadow distance drops the far bounds beyond it.
    let short = config(&preset_text("bevy", &[("shadow.max_distance", "max_distance = 12")]));
    let g = Grid::resolve(&short, &SweepAxes::default()).unwrap();
    assert_eq!(g.knob.unwrap().values, vec![2.5, 5.0, 7.5, 10.0]);
    // Presets without a scalar knob, and csm-lab's own pipeline, have no knob axis.
    for p in ["unity", "dart", "godot"] {
        let g = Grid::resolve(&config(&preset_text(p, &[])), &SweepAxes::default()).unwrap();
        assert!(g.knob.is_none(), "{p}");
    }
    assert!(Grid::resolve(&config(&with(&[])), &SweepAxes::default())
        .unwrap()
        .knob
        .is_none());
}

#[test]
fn the_sweep_table_takes_knob_and_distance_axes() {
    let text = preset_text(
        "unreal",
        &[
            ("sweep.knob", "knob = [2.0, 3.0]"),
            (
                "sweep.distance",
                "distance = { start = 100.0, end = 200.0, step = 50.0 }",
            ),
            ("sweep.cascades", "cascades = [3]"),
            ("sweep.resolution", "resolution = [1024]"),
        ],
    );
    let g = Grid::resolve(&config(&text), &SweepAxes::default()).unwrap();
    assert_eq!(g.knob.unwrap().values, vec![2.0, 3.0]);
    assert_eq!(g.distance.unwrap().values, vec![100.0, 150.0, 200.0]);
    // A bad distance names the key.
    let bad = preset_text("unreal", &[("sweep.distance", "distance = [0.0]")]);
    let e = csm_lab::Config::from_toml_str(&bad, "t.toml", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("sweep.distance"), "{e}");
}

fn cli(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

#[test]
fn knob_and_distance_flags_are_refused_naming_the_flag_where_the_preset_lacks_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let out = out.to_str().unwrap();
    let cases: [(&[&str], &str, &str); 5] = [
        (
            &["--preset", "unity", "--knob", "1,2"],
            "--knob",
            "the unity preset has no split knob",
        ),
        (&["--knob", "2"], "--knob", "csm-lab's own pipeline has no split knob"),
        (
            &["--preset", "learnopengl", "--distance", "50"],
            "--distance",
            "no shadow distance",
        ),
        (
            &["--preset", "unreal", "--knob", "20"],
            "--knob",
            "unreal.cascade_distribution_exponent = 20 is outside",
        ),
        (
            &["--preset", "unreal", "--distance", "0,50"],
            "--distance",
            "0 is outside",
        ),
    ];
    for (extra, flag, says) in cases {
        let mut args = vec!["sweep", "configs/default.toml", "--quiet", "--out", out];
        args.extend_from_slice(extra);
        let (code, _, err) = cli(&args);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(err.contains(flag) && err.contains(says), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // A grid too large names the knob and distance flags among the axes to narrow.
    let (code, _, err) = cli(&[
        "sweep",
        "configs/default.toml",
        "--quiet",
        "--out",
        out,
        "--preset",
        "unreal",
        "--knob",
        "0.5:10:0.001",
        "--distance",
        "1:1000:1",
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("× 9501 knob values × 1000 distances") && err.contains("--knob, --distance"),
        "{err}"
    );
    // A Bevy far bound beyond a swept distance names the point.
    let (code, _, err) = cli(&[
        "sweep",
        "configs/default.toml",
        "--quiet",
        "--out",
        out,
        "--preset",
        "bevy",
        "--knob",
        "20",
        "--distance",
        "15",
        "--cascades",
        "2",
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("bevy.first_cascade_far_bound"), "{err}");
}

#[test]
fn a_knob_sweep_reports_in_the_engines_terms_and_never_a_lambda() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("u");
    let (code, stdout, err) = cli(&[
        "sweep",
        "configs/default.toml",
        "--preset",
        "unreal",
        "--quiet",
        "--no-plots",
        "--cascades",
        "3,4",
        "--distance",
        "100,150",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(
        header.ends_with(",preset,unreal.cascade_distribution_exponent,shadow.max_distance"),
        "{header}"
    );
    // 2 distances × 4 sizes × 2 counts × 7 exponents.
    assert_eq!(csv.lines().count(), 1 + 2 * 4 * 2 * 7);
    let line = stdout.lines().find(|l| l.starts_with("recommended")).unwrap();
    assert!(line.contains("CascadeDistributionExponent"), "{line}");
    assert!(!line.contains('λ') && !line.contains("lambda"), "{line}");
    // What to change is said relative to the configured setting, in the engine's terms.
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let change = md.lines().find(|l| l.contains("change ")).unwrap();
    assert!(
        change.contains("CascadeDistributionExponent 3 → ") || change.contains("shadow distance 150 → "),
        "{change}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("recommendation.json")).unwrap()).unwrap();
    let rec = &json["recommended"];
    assert!(rec["knob"].is_number() && rec["distance"].is_number(), "{rec}");
}

#[test]
fn the_heat_map_of_a_knob_sweep_has_the_knob_on_its_x_axis() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let (code, _, err) = cli(&[
        "sweep",
        "configs/default.toml",
        "--preset",
        "bevy",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let svg = std::fs::read_to_string(out.join("heatmap.svg")).unwrap();
    assert!(svg.contains("first_cascade_far_bound"), "no knob axis label");
}
