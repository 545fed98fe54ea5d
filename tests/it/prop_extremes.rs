//! Extreme cameras and bounds on every command's computation (issue 25): a camera up to the
//! largest accepted coordinate (±1e9) with a near plane down to 1e-12, scenes from a
//! micrometre to a kilometre around it or far away, 1 to 16 cascades of up to 16384², both
//! fits, both snap modes, both precisions. Every case is either refused by validation with a
//! message, or analysed and swept with every output rendered: never a panic, never an
//! "internal error" (a non-finite number reaching a file).

use std::panic::{catch_unwind, AssertUnwindSafe};

use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::app::sweep::{sweep_files, SweepRequest};
use csm_lab::commands::sweep::grid::GridFlags;
use csm_lab::output::Exporter;
use csm_lab::report::analyze as analyze_files;
use csm_lab::Config;
use proptest::prelude::*;

/// 10^u, u uniform in [lo, hi).
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..hi).prop_map(|u| 10f64.powf(u))
}

/// A coordinate near the largest accepted one, or anywhere up to it.
fn far_coordinate() -> impl Strategy<Value = f64> {
    (
        prop_oneof![
            Just(999_999_999.9),
            Just(1e9),
            Just(5e8),
            log_uniform(5.0, 9.0),
            Just(0.0)
        ],
        any::<bool>(),
    )
        .prop_map(|(x, neg)| if neg { -x } else { x })
}

#[derive(Debug, Clone)]
struct Case {
    camera: [f64; 3],
    view: [f64; 3],
    near: f64,
    far: f64,
    /// Scene centre relative to the camera, and half extents.
    scene_at: [f64; 3],
    half: [f64; 3],
    cascades: usize,
    resolution: u32,
    fit: &'static str,
    snap: bool,
    precision: &'static str,
    path: &'static str,
    step: f64,
    max_distance: f64,
}

fn case() -> impl Strategy<Value = Case> {
    (
        (far_coordinate(), -100.0f64..100.0, far_coordinate()),
        (-1.0f64..1.0, -1.0f64..-0.05, -1.0f64..1.0),
        prop_oneof![Just(1e-9), log_uniform(-12.0, -1.0)],
        prop_oneof![log_uniform(0.5, 12.0), Just(1e3)],
        prop_oneof![
            (-50.0f64..50.0, -50.0f64..0.0, -200.0f64..0.0),
            Just((0.0, 0.0, -50.0)),
            (-1e9f64..1e9, -10.0f64..10.0, -1e9f64..1e9)
        ],
        (log_uniform(-6.0, 3.0), log_uniform(-6.0, 3.0), log_uniform(-6.0, 3.0)),
        (
            prop_oneof![Just(1usize), Just(4), Just(16), 1usize..=16],
            prop_oneof![Just(16u32), Just(2048), Just(16384)],
            prop_oneof![Just("sphere"), Just("aabb")],
            any::<bool>(),
            prop_oneof![3 => Just("f64"), 1 => Just("f32")],
        ),
        (
            prop_oneof![Just("strafe"), Just("yaw"), Just("orbit"), Just("dolly")],
            log_uniform(-9.0, 2.0),
            log_uniform(-3.0, 4.0),
        ),
    )
        .prop_map(
            |(
                (x, y, z),
                (vx, vy, vz),
                near,
                far_ratio,
                (sx, sy, sz),
                (hx, hy, hz),
                (cascades, resolution, fit, snap, precision),
                (path, step, max_distance),
            )| Case {
                camera: [x, y, z],
                view: [vx, vy, vz],
                near,
                far: near * far_ratio,
                scene_at: [sx, sy, sz],
                half: [hx, hy, hz],
                cascades,
                resolution,
                fit,
                snap,
                precision,
                path,
                step,
                max_distance,
            },
        )
}

fn v3(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

impl Case {
    fn toml(&self) -> String {
        let c = self.camera;
        let target = [0, 1, 2].map(|i| c[i] + self.view[i] * 10.0);
        let centre = [0, 1, 2].map(|i| c[i] + self.scene_at[i]);
        let min = [0, 1, 2].map(|i| centre[i] - self.half[i]);
        let max = [0, 1, 2].map(|i| centre[i] + self.half[i]);
        format!(
            r#"
[camera]
position = {}
target = {}
up = [0.0, 1.0, 0.0]
fov_y_deg = 60.0
near = {:?}
far = {:?}

[screen]
width = 64
height = 36

[light]
direction = [-0.4, -1.0, -0.3]

[scene]
min = {}
max = {}

[shadow]
max_distance = {:?}
cascades = {}
lambda = 0.75
resolution = {}
fit = "{}"
snap = {}
precision = "{}"

[motion]
path = "{}"
frames = 4
step = {:?}
"#,
            v3(c),
            v3(target),
            self.near,
            self.far,
            v3(min),
            v3(max),
            self.max_distance,
            self.cascades,
            self.resolution,
            self.fit,
            self.snap,
            self.precision,
            self.path,
            self.step,
        )
    }
}

/// The analysis and every file `analyze` renders from it.
fn analyze_renders(c: &Config) -> Result<(), String> {
    let a = analyze(c, &AnalysisOptions::full());
    let exporters: [&dyn Exporter<_>; 4] = [
        &analyze_files::CascadesCsv,
        &analyze_files::DensityCsv,
        &analyze_files::ShimmerCsv,
        &analyze_files::SummaryJson,
    ];
    for e in exporters {
        e.render(&a)
            .map_err(|err| format!("analyze, {}: {err}", e.file_name()))?;
    }
    Ok(())
}

/// A sweep of a small grid around the case (`sweep --no-plots`), every file rendered. An
/// error is allowed (a grid point the config cannot hold is refused like the file) but not an
/// internal one.
fn sweep_renders(text: &str) -> Result<(), String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("case.toml");
    std::fs::write(&path, text).unwrap();
    let req = SweepRequest {
        config: path,
        out: Some(dir.path().join("out")),
        grid: GridFlags {
            cascades: Some("1,4".to_string()),
            resolution: Some("16,16384".to_string()),
            lambda: Some("0,1".to_string()),
            ..Default::default()
        },
        threads: Some(1),
        quiet: true,
        no_plots: true,
        format: csm_lab::app::Format::Table,
        shard: None,
        optimize_splits: false,
        ground_truth: false,
    };
    match sweep_files(&req) {
        Ok(_) => Ok(()),
        Err(e) => {
            let msg = e.to_string();
            if msg.contains("internal error") || msg.trim().is_empty() {
                Err(format!("sweep: {msg}"))
            } else {
                Ok(())
            }
        }
    }
}

fn check(text: &str) -> Result<bool, String> {
    match Config::from_toml_str(text, "case.toml", None) {
        Ok(c) => {
            analyze_renders(&c)?;
            sweep_renders(text)?;
            Ok(true)
        }
        Err(e) => {
            let msg = e.to_string();
            if msg.trim().is_empty() || msg.contains("internal error") {
                Err(format!("config: {msg:?}"))
            } else {
                Ok(false)
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, max_shrink_iters: 500, .. ProptestConfig::default() })]

    /// No panic and no internal error: a clear refusal, or an analysis and a sweep whose
    /// every file renders.
    #[test]
    fn extreme_cameras_and_bounds_are_refused_or_analysed_and_swept(case in case()) {
        let text = case.toml();
        match catch_unwind(AssertUnwindSafe(|| check(&text))) {
            Ok(Ok(_)) => {}
            Ok(Err(why)) => prop_assert!(false, "{}\n{}", why, text),
            Err(_) => prop_assert!(false, "panicked on\n{}", text),
        }
    }
}

/// The reported case: a camera at x = 999999999.9, near = 1e-9, 16 cascades of 16384², AABB
/// fit, no snapping, with a scene around the camera; and enough generated cases reach the
/// analysis (the property above is not vacuous).
#[test]
fn the_reported_extreme_camera_and_most_generated_cases_are_analysed() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let reported = Case {
        camera: [999_999_999.9, 10.0, 0.0],
        view: [0.0, -0.2, -1.0],
        near: 1e-9,
        far: 1000.0,
        // Up to x = 999999999.9: the largest coordinate accepted is 1e9.
        scene_at: [-100.0, -10.0, -50.0],
        half: [100.0, 20.0, 100.0],
        cascades: 16,
        resolution: 16384,
        fit: "aabb",
        snap: false,
        precision: "f64",
        path: "strafe",
        step: 0.05,
        max_distance: 150.0,
    };
    let text = reported.toml();
    if let Err(e) = Config::from_toml_str(&text, "case.toml", None) {
        panic!("{e}");
    }
    assert_eq!(check(&text), Ok(true));
    let mut runner = TestRunner::deterministic();
    let strategy = case();
    let mut valid = 0;
    for _ in 0..100 {
        let text = strategy.new_tree(&mut runner).unwrap().current().toml();
        if Config::from_toml_str(&text, "case.toml", None).is_ok() {
            valid += 1;
        }
    }
    assert!(valid > 30, "{valid} of 100 valid");
}

/// What the property found: a camera 5e8 from the origin with near 1e-9 and 4 logarithmic
/// cascades (λ = 1) up to 1e-6: the slices are thinner than f64 resolves at those coordinates,
/// so the AABB windows collapsed to zero size and analyze ended in "internal error: centre_x is
/// not finite (NaN)" (a sweep with that point in "pareto_front.shimmer is not finite"). Now
/// validation refuses it naming camera.near, and a sweep over it names the point.
#[test]
fn slices_thinner_than_f64_resolves_are_refused_naming_the_key() {
    let case = Case {
        camera: [5e8, 0.0, 5e8],
        view: [0.0, -0.05, 0.5721360855125875],
        near: 1e-9,
        far: 1.0000000000000002e-6,
        scene_at: [0.0, 0.0, -50.0],
        half: [1.0, 1.0, 68.8],
        cascades: 4,
        resolution: 16,
        fit: "aabb",
        snap: false,
        precision: "f64",
        path: "strafe",
        step: 1.0,
        max_distance: 1.0,
    };
    let text = case.toml().replace("lambda = 0.75", "lambda = 1.0");
    let e = Config::from_toml_str(&text, "case.toml", None).unwrap_err().to_string();
    assert!(
        e.contains("`camera.near` = 0.000000001 is not allowed")
            && e.contains("cascade 0's window collapses")
            && e.contains("raise camera.near"),
        "{e}"
    );
    // With uniform splits (λ = 0) the file loads and is analysed and swept; a sweep's λ = 1
    // point is refused by name.
    let text = case.toml().replace("lambda = 0.75", "lambda = 0.0");
    assert!(Config::from_toml_str(&text, "case.toml", None).is_ok());
    assert_eq!(check(&text), Ok(true));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("case.toml");
    std::fs::write(&path, &text).unwrap();
    let req = SweepRequest {
        config: path,
        out: None,
        grid: GridFlags {
            cascades: Some("4".to_string()),
            lambda: Some("1".to_string()),
            ..Default::default()
        },
        threads: Some(1),
        quiet: true,
        no_plots: true,
        format: csm_lab::app::Format::Table,
        shard: None,
        optimize_splits: false,
        ground_truth: false,
    };
    let e = sweep_files(&req).err().expect("refused").to_string();
    assert!(
        e.contains("sweep point") && e.contains("camera.near") && !e.contains("internal error"),
        "{e}"
    );
}
