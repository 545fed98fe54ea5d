//! Shimmer and coverage against independent computations.

use crate::common;

use common::{config, with};
use csm_core::cascades::LightPose;
use csm_core::rig_path::{along_path, probes};
use csm_core::shimmer::{wrap, ShimmerOptions};
use csm_lab::analysis::{analyze, AnalysisOptions};
use proptest::prelude::*;

const PROBE_EVERYTHING: ShimmerOptions = ShimmerOptions {
    cell_flips: true,
    probe_drift: true,
    frame_rows: true,
};

fn path_result(text: &str, snapped: bool) -> csm_core::shimmer::PathResult {
    let c = config(text);
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let poses = c.camera_path().unwrap();
    let pr = probes(&rig, &c.camera.pose(), &c.scene, 200);
    along_path(&rig, &poses, &pr, snapped, PROBE_EVERYTHING)
}

#[test]
fn sphere_fit_with_snapping_has_zero_shimmer_under_every_motion() {
    for (path, step) in [
        ("strafe", "0.037"),
        ("dolly", "0.21"),
        ("yaw", "0.05"),
        ("pitch", "0.05"),
        ("orbit", "0.1"),
    ] {
        let text = with(&[
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", &format!("step = {step}")),
        ]);
        let r = path_result(&text, true);
        assert!(r.stats.size_jitter < 1e-9, "{path}: S1 {}", r.stats.size_jitter);
        assert!(r.stats.max < 1e-9, "{path}: S3 {}", r.stats.max);
        assert_eq!(r.stats.cell_flip_rate, Some(0.0), "{path}: S4");
        // The analysis (closed form) agrees.
        let a = analyze(&config(&text), &AnalysisOptions::full());
        assert!(
            a.summary.shimmer_snapped < 1e-9 && a.summary.size_jitter < 1e-9,
            "{path}"
        );
        assert!(a.summary.shimmer_unsnapped > 1e-3, "{path}: unsnapped should drift");
    }
}

#[test]
fn unsnapped_strafe_drift_equals_the_closed_form_per_axis() {
    let step = 0.0137;
    let text = with(&[("motion.step", &format!("step = {step}"))]);
    let c = config(&text);
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let pose = c.camera.pose();
    let delta = pose.right * step;
    let r = path_result(&text, false);
    let lp = LightPose::new(&rig.light, &pose);
    for row in &r.frames {
        let w = rig.window(row.cascade, &lp, false);
        let dx = wrap(rig.light.x.dot(delta) / w.texel.x);
        let dy = wrap(rig.light.y.dot(delta) / w.texel.y);
        let expected = (dx * dx + dy * dy).sqrt();
        assert!((row.phase_drift_rms - expected).abs() < 1e-9, "{row:?} vs {expected}");
        assert!((row.phase_drift_max - expected).abs() < 1e-9);
        // Cell flips: about |dx| + |dy| - |dx||dy| of the probes (Monte Carlo, 200 probes).
        let p = dx.abs() + dy.abs() - dx.abs() * dy.abs();
        let sigma = (p * (1.0 - p) / 200.0).sqrt().max(0.01);
        assert!((row.cell_flips.unwrap() - p).abs() < 5.0 * sigma, "{row:?} vs {p}");
    }
    // The per-probe path and the analysis' closed form give the same summary.
    let a = analyze(&c, &AnalysisOptions::full());
    assert!((a.summary.shimmer_unsnapped - r.stats.rms).abs() < 1e-9);
}

#[test]
fn tight_aabb_changes_texel_size_when_the_camera_turns() {
    let text = with(&[
        ("shadow.fit", "fit = \"aabb\""),
        ("motion.path", "path = \"yaw\""),
        ("motion.step", "step = 0.05"),
        ("analysis.probes", "probes = 200"),
    ]);
    let r = path_result(&text, true);
    assert!(r.stats.size_jitter > 1e-5, "S1 {}", r.stats.size_jitter);
    assert!(r.stats.size_jitter < 1e-2, "S1 {}", r.stats.size_jitter);
    // Snapping cannot fix a size change: probes still drift.
    assert!(r.stats.rms > 1e-3);
    assert_eq!(r.coverage.total(), 0);
    let a = analyze(&config(&text), &AnalysisOptions::full());
    assert!(a.summary.size_jitter > 1e-5);
    assert!(
        (a.summary.shimmer_snapped - r.stats.rms).abs() < 1e-12,
        "per-probe when sizes change"
    );
    // Under pure translation the AABB keeps its size (it translates rigidly).
    let strafe = with(&[("shadow.fit", "fit = \"aabb\"")]);
    let t = path_result(&strafe, true);
    assert!(t.stats.size_jitter < 1e-9 && t.stats.max < 1e-6, "{:?}", t.stats);
}

#[test]
fn snapped_drift_stays_below_1e_9_a_million_units_from_the_origin() {
    let text = r#"
[camera]
position = [1000000.0, 10.0, 1000000.0]
target = [1000000.0, 0.0, 999950.0]
fov_y_deg = 60.0
near = 0.1
far = 1000.0
[screen]
width = 1920
height = 1080
[light]
direction = [-0.4, -1.0, -0.3]
[scene]
min = [999800.0, 0.0, 999800.0]
max = [1000200.0, 40.0, 1000200.0]
[motion]
path = "orbit"
frames = 50
step = 0.3
"#;
    let r = path_result(text, true);
    assert!(r.stats.max < 1e-9, "{:?}", r.stats);
    assert_eq!(r.coverage.total(), 0);
}

/// Dense samples on every face of every slice stay inside the windows: the corner-only
/// coverage check is exact because slices and windows are convex.
#[test]
fn dense_face_samples_never_find_a_miss_the_corner_check_missed() {
    for fit in ["sphere", "aabb"] {
        let text = with(&[
            ("shadow.fit", &format!("fit = \"{fit}\"")),
            ("motion.path", "path = \"yaw\""),
        ]);
        let c = config(&text);
        let rig = csm_lab::analysis::rig(&c).unwrap();
        for pose in c.camera_path().unwrap().iter().step_by(7) {
            let lp = LightPose::new(&rig.light, pose);
            for (i, s) in rig.slices.iter().enumerate() {
                let w = rig.window(i, &lp, true);
                let mut worst: f64 = 0.0;
                for a in 0..=8 {
                    for b in 0..=8 {
                        let u = a as f64 / 8.0 * 2.0 - 1.0;
                        let v = b as f64 / 8.0 * 2.0 - 1.0;
                        let t = a as f64 / 8.0;
                        let z = s.near + (s.far - s.near) * t;
                        let (th, tv) = (rig.lens.tan_h, rig.lens.tan_v);
                        for p in [
                            lp.point(u * th, v * tv, s.near),
                            lp.point(u * th, v * tv, s.far),
                            lp.point(th, v * tv, z),
                            lp.point(-th, v * tv, z),
                            lp.point(u * th, tv, z),
                            lp.point(u * th, -tv, z),
                        ] {
                            worst = worst.max(w.outside_by_texels(p));
                        }
                    }
                }
                assert!(worst <= 1e-9, "{fit} cascade {i}: {worst}");
            }
        }
    }
}

fn arb_scene() -> impl Strategy<Value = String> {
    (
        (-50.0f64..50.0, 1.0f64..80.0, -50.0f64..50.0),
        (-1.0f64..1.0, -1.0f64..0.2, -1.0f64..1.0),
        (10.0f64..120.0, 0.3f64..3.0, 0.01f64..2.0),
        (-1.0f64..1.0, -1.0f64..-0.05, -1.0f64..1.0),
        (1usize..9, 0.0f64..1.0, prop_oneof![Just(64u32), Just(512), Just(2048)]),
        (prop_oneof![Just("sphere"), Just("aabb")], any::<bool>()),
        prop_oneof![Just("strafe"), Just("yaw"), Just("pitch"), Just("orbit"), Just("dolly")],
    )
        .prop_filter("view direction not vertical", |(_, d, ..)| {
            (d.0 * d.0 + d.2 * d.2) > 0.01
        })
        .prop_map(
            |(p, d, (fov, aspect, near), l, (m, lambda, res), (fit, to_scene), path)| {
                format!(
                    r#"
[camera]
position = [{}, {}, {}]
target = [{}, {}, {}]
fov_y_deg = {fov}
near = {near}
far = 400.0
[screen]
width = {}
height = 1000
[light]
direction = [{}, {}, {}]
[scene]
min = [-150.0, 0.0, -150.0]
max = [150.0, 30.0, 150.0]
[shadow]
max_distance = 200.0
cascades = {m}
lambda = {lambda}
resolution = {res}
fit = "{fit}"
fit_depth_to_scene = {to_scene}
[motion]
path = "{path}"
frames = 12
step = 0.7
"#,
                    p.0,
                    p.1,
                    p.2,
                    p.0 + d.0 * 10.0,
                    p.1 + d.1 * 10.0,
                    p.2 + d.2 * 10.0,
                    (1000.0 * aspect) as u32,
                    l.0,
                    l.1,
                    l.2
                )
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, .. ProptestConfig::default() })]

    /// Coverage is 0 for both fits and both snap modes, and the sphere fit is stable.
    #[test]
    fn windows_cover_their_slices_for_random_cameras_lights_and_fits(text in arb_scene()) {
        let c = config(&text);
        let a = analyze(&c, &AnalysisOptions::summary_only());
        if let (Some(s), Some(u)) = (a.snapped(), a.unsnapped()) {
            prop_assert_eq!(s.coverage.total(), 0);
            prop_assert_eq!(u.coverage.total(), 0);
            if c.shadow.fit == csm_lab::config::Fit::Sphere {
                prop_assert!(a.summary.shimmer_snapped < 1e-9);
                prop_assert!(a.summary.size_jitter == 0.0);
            }
            for v in [a.summary.max_aliasing, a.summary.mean_aliasing, a.summary.mean_log_aliasing, a.summary.shimmer_unsnapped] {
                prop_assert!(v.is_finite() && v > 0.0);
            }
        }
    }
}

/// `analyze --all-frames` writes every frame's rows (streamed, walked in overlapping chunks);
/// they equal, frame for frame, the rows the default output keeps of a long path, and on a
/// path of at most 1,000 frames both files are the same bytes.
#[test]
fn all_frames_writes_every_frame_and_agrees_with_the_kept_rows() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let run = |frames: usize, all: bool| {
        let cfg = dir.path().join(format!("p{frames}.toml"));
        let text = crate::common::with(&[
            ("motion.path", "path = \"yaw\""),
            ("motion.frames", &format!("frames = {frames}")),
        ]);
        std::fs::write(&cfg, text).unwrap();
        let out = dir.path().join(format!("o{frames}{all}"));
        let mut c = Command::new(env!("CARGO_BIN_EXE_csm-lab"));
        c.args(["analyze", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        if all {
            c.arg("--all-frames");
        }
        assert!(c.output().unwrap().status.success());
        let mut r = csv::Reader::from_path(out.join("shimmer.csv")).unwrap();
        r.records()
            .map(|x| x.unwrap().iter().map(String::from).collect::<Vec<_>>())
            .collect::<Vec<_>>()
    };
    assert_eq!(run(600, false), run(600, true));
    let kept = run(2_500, false);
    let all = run(2_500, true);
    let cascades = all
        .iter()
        .map(|r| r[1].clone())
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    assert_eq!(
        all.len(),
        2_499 * cascades * 2,
        "every frame pair, cascade and snap mode"
    );
    let frames: std::collections::BTreeSet<usize> = all.iter().map(|r| r[0].parse().unwrap()).collect();
    assert_eq!(frames, (1..2_500).collect());
    let by_key: std::collections::BTreeMap<_, _> = all
        .iter()
        .map(|r| ((r[0].clone(), r[1].clone(), r[2].clone()), r.clone()))
        .collect();
    assert!(kept.len() < all.len() / 2);
    for r in &kept {
        assert_eq!(&by_key[&(r[0].clone(), r[1].clone(), r[2].clone())], r);
    }
}
