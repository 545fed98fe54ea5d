//! The binary32 emulation against the reference figures of csm-math.md §10 and against the
//! exact f64 pipeline; the world offset; the precision settings.

use crate::common;

use common::{config, with};
use csm_core::cascades::{LightPose, Rig};
use csm_core::geometry::{Aabb, CameraPose, Lens, LightBasis};
use csm_core::precision::{self, along_path, ulp32, EmulatedPath, EnginePipeline};
use csm_core::rig_path::probes;
use csm_core::scene::{Precision, SnapSpace};
use csm_core::shimmer::ShimmerOptions;
use csm_core::snapping::{SnapMode, SnapRule};
use csm_lab::analysis::{analyze, AnalysisOptions};
use csm_lab::config::Fit;
use csm_lab::drift_table::drift_table;
use glam::DVec3;

const OPTS: ShimmerOptions = ShimmerOptions {
    cell_flips: true,
    probe_drift: true,
    frame_rows: false,
};

/// The set-up of csm-math.md §10.3: one cascade whose window is exactly `window` units wide
/// (no border, as in the reference), N = 2048, the camera strafing 0.0137 per frame for 30
/// frames at `offset` along +x, 800 world-fixed probes.
fn reference_run(window: f64, offset: f64, mode: SnapMode, space: SnapSpace) -> EmulatedPath {
    let lens = Lens::new(60f64.to_radians(), 16.0 / 9.0);
    // Far-cap slice with 2R = 2 k f below the window, so the window covers it.
    let far = 0.45 * window / lens.k2().sqrt();
    let mut rig = Rig::new(
        lens,
        LightBasis::new(DVec3::new(-0.4, -1.0, -0.3)),
        Fit::Sphere,
        2048,
        SnapRule { mode, step_texels: 1 },
        vec![0.1, far],
    );
    rig.sphere_side[0] = window;
    let o = DVec3::new(offset, 0.0, 0.0);
    let pose0 = CameraPose::look_at(
        o + DVec3::new(0.0, 10.0, 0.0),
        o + DVec3::new(0.0, 0.0, -50.0),
        DVec3::Y,
    )
    .unwrap();
    let poses: Vec<CameraPose> = (0..30)
        .map(|t| {
            CameraPose::look_to(
                pose0.position + pose0.right * (0.0137 * t as f64),
                pose0.forward,
                DVec3::Y,
            )
            .unwrap()
        })
        .collect();
    let scene = Aabb::new(o - DVec3::splat(500.0), o + DVec3::splat(500.0));
    let pr = probes(&rig, &pose0, &scene, 800);
    along_path(&rig, &poses, &pr, space, true, OPTS)
}

#[test]
fn ulp32_matches_the_reference_table() {
    // csm-math.md §10.1; ulp32(1e5) = 2^-7 exactly.
    assert_eq!(ulp32(1e5), 2f64.powi(-7));
    assert_eq!(ulp32(1e3), 2f64.powi(-14));
    assert_eq!(ulp32(1e4), 2f64.powi(-10));
    assert_eq!(ulp32(1e6), 2f64.powi(-4));
    assert_eq!(ulp32(-1e5), 2f64.powi(-7));
    // Independent definition: for |x| in [2^e, 2^(e+1)), ulp = 2^(e - 23).
    let mut rng = csm_core::rng::SplitMix64::new(11);
    for _ in 0..1000 {
        let x = 10f64.powf(rng.range(-3.0, 9.0));
        let e = (x as f32).log2().floor() as i32;
        assert_eq!(ulp32(x), 2f64.powi(e - 23), "{x}");
    }
    // §10.2: ulp32(1e5)/T for a 20 m and a 200 m window at 2048².
    assert!((ulp32(1e5) / (20.0 / 2048.0) - 0.80).abs() < 1e-12);
    assert!((ulp32(1e5) / (200.0 / 2048.0) - 0.080).abs() < 1e-12);
}

/// The f64 instantiation of the engine pipeline (world units, snapping `round(c/T)*T`) is an
/// independent implementation of the rig's windows (texel units): their lookups agree to
/// rounding, for both fits, every snap rule and both snap spaces, up to a 1e6 offset.
#[test]
fn the_f64_twin_of_the_engine_pipeline_reproduces_the_rig_windows() {
    for fit in ["sphere", "aabb"] {
        for (path, step) in [("strafe", "0.037"), ("yaw", "0.3"), ("orbit", "0.5")] {
            for offset in [0.0, 1e3, 1e6] {
                let c = config(&with(&[
                    ("shadow.fit", &format!("fit = \"{fit}\"")),
                    ("motion.path", &format!("path = \"{path}\"")),
                    ("motion.step", &format!("step = {step}")),
                    ("motion.frames", "frames = 12"),
                    (
                        "scene.world_offset",
                        &format!("world_offset = [{offset:?}, {:?}, 0.0]", -offset),
                    ),
                ]));
                let base = csm_lab::analysis::rig(&c).unwrap();
                let poses = c.camera_path().unwrap();
                let pr = probes(&base, &poses[0], &c.scene, 40);
                for (mode, steps) in [(SnapMode::Round, 1), (SnapMode::Floor, 2), (SnapMode::Trunc, 4)] {
                    let rig = Rig::new(
                        base.lens,
                        base.light,
                        base.fit,
                        base.resolution,
                        SnapRule {
                            mode,
                            step_texels: steps,
                        },
                        base.splits.clone(),
                    );
                    for space in [SnapSpace::World, SnapSpace::CameraRelative] {
                        // trunc is toward the anchor in camera-relative space, by design.
                        if space == SnapSpace::CameraRelative && mode == SnapMode::Trunc {
                            continue;
                        }
                        let twin: EnginePipeline<f64> = EnginePipeline::new(&rig);
                        for pose in &poses {
                            let lp = LightPose::new(&rig.light, pose);
                            let anchors = precision::frame_anchors(&rig, pose, space);
                            for i in 0..rig.cascade_count() {
                                for snapped in [false, true] {
                                    let w = rig.window(i, &lp, snapped);
                                    let e = twin.window(i, pose, anchors[i], snapped);
                                    for x in &pr[i] {
                                        let u = rig.light.to_light_xy(*x);
                                        let exact = w.texel_coords(u);
                                        let s = e.lookup(twin.probe(anchors[i], *x));
                                        // f64 rounding of coordinates up to 1.5e6 over texels
                                        // of >= 5 mm: a few 1e-16 * 3e8 texels. The AABB size
                                        // is recomputed every frame from coordinates |u|, so
                                        // its relative rounding (~eps |u| / W) is magnified
                                        // by |u| / T texels as well.
                                        let scale = u.abs().max_element() / w.texel_size();
                                        let tol = match fit {
                                            "aabb" => {
                                                1e-6 + 16.0 * f64::EPSILON * scale * scale * w.texel_size() / w.width()
                                            }
                                            _ => 1e-6,
                                        };
                                        let d = (s[0] - exact.x).abs().max((s[1] - exact.y).abs());
                                        assert!(
                                            d < tol,
                                            "{fit} {path} {offset} {mode:?} {space:?} cascade {i}: {d} > {tol}"
                                        );
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn f64_stabilised_shimmer_stays_below_1e_9_at_every_world_offset() {
    for offset in [0.0, 1e3, 1e4, 1e5, 1e6] {
        for (path, step) in [("strafe", "0.0137"), ("yaw", "0.05"), ("dolly", "0.21")] {
            let text = with(&[
                (
                    "scene.world_offset",
                    &format!("world_offset = [{offset:?}, 0.0, {offset:?}]"),
                ),
                ("motion.path", &format!("path = \"{path}\"")),
                ("motion.step", &format!("step = {step}")),
            ]);
            let a = analyze(&config(&text), &AnalysisOptions::full());
            let s = a.snapped().unwrap();
            assert!(s.stats.max < 1e-9, "{offset} {path}: {}", s.stats.max);
            assert_eq!(a.summary.coverage_violations, 0);
            assert_eq!(a.summary.lookup_error_max, 0.0, "S7 is 0 in f64");
            // The per-probe evaluation agrees with the closed form at this offset.
            let c = config(&text);
            let rig = csm_lab::analysis::rig(&c).unwrap();
            let poses = c.camera_path().unwrap();
            let pr = probes(&rig, &poses[0], &c.scene, 64);
            let r = csm_core::rig_path::along_path(&rig, &poses, &pr, true, OPTS);
            assert!(r.stats.max < 1e-9, "{offset} {path}: probes {}", r.stats.max);
        }
    }
}

/// csm-math.md §10.3, "DX floor snap, f32", with the engine's world-unit snapping. The drift is
/// the difference between two frames' roundings of the snapped origin `k*T` to f32, each at
/// most half an ulp32 of the light-space coordinate.
#[test]
fn world_anchored_f32_drift_grows_with_the_offset_as_in_the_reference() {
    // 1e4, 20 m: T = 20/2048 = 5*2^-9 has three significant bits, so k*T is exact in f32 below
    // 2^24 * 2^-9 = 32768 units; only the lookup's own rounding of s < 2048 is left (ulp32 of
    // s is at most 2^-13 = 1.2e-4, a drift of two such roundings stays below 2.5e-4). The
    // reference reports 6e-5.
    let d = reference_run(20.0, 1e4, SnapMode::Floor, SnapSpace::World)
        .path
        .stats
        .max;
    assert!(d < 2.5e-4, "1e4, 20 m: {d}");
    // 1e5, 20 m: ulp32(|u|)/T = 0.8 for light-space coordinates in [65536, 131072) (0.4 below),
    // so each axis drifts by up to 0.8 texel, wrapped into [-0.5, 0.5]; the 2-D magnitude is
    // at most 0.71. The reference measured 0.40 (per axis) over the same 30 frames; the
    // largest of 58 frame-pair drifts lies well above 0.25 unless the roundings conspire.
    let r = reference_run(20.0, 1e5, SnapMode::Floor, SnapSpace::World);
    assert!(
        (0.25..=0.71).contains(&r.path.stats.max),
        "1e5, 20 m: {}",
        r.path.stats.max
    );
    assert!(
        r.path.stats.cell_flip_rate.unwrap() > 0.05,
        "a real fraction of probes flips"
    );
    // 1e5, 200 m: ulp32/T = 0.08 per axis, so at most 0.113 in 2-D; reference 0.040.
    let d = reference_run(200.0, 1e5, SnapMode::Floor, SnapSpace::World)
        .path
        .stats
        .max;
    assert!((0.02..=0.113).contains(&d), "1e5, 200 m: {d}");
    // 1e6, 200 m: ulp32/T = 0.64, wrapped; reference 0.36.
    let d = reference_run(200.0, 1e6, SnapMode::Floor, SnapSpace::World)
        .path
        .stats
        .max;
    assert!((0.2..=0.71).contains(&d), "1e6, 200 m: {d}");
    // The round rule rounds k*T the same way: same physics.
    let d = reference_run(20.0, 1e5, SnapMode::Round, SnapSpace::World)
        .path
        .stats
        .max;
    assert!((0.25..=0.71).contains(&d), "round, 1e5, 20 m: {d}");
}

/// "DX snap with T a power of two": k*T is exact in f32 at every offset, and the lookup
/// subtraction of two nearby coordinates is exact (Sterbenz), so the drift is exactly 0.
#[test]
fn a_power_of_two_texel_size_has_no_f32_drift_away_from_the_origin() {
    for offset in [1e3, 1e4, 1e5, 1e6] {
        let d = reference_run(16.0, offset, SnapMode::Floor, SnapSpace::World)
            .path
            .stats
            .max;
        assert_eq!(d, 0.0, "{offset}");
    }
}

/// csm-math.md §10.3, "camera-relative": near zero at every offset (the reference, with a
/// fixed anchor and static relative coordinates, reports drift ≤ 2.4e-4). Here the anchor
/// follows the camera every frame, as in engines that re-base on the camera, so the stored
/// receivers are rounded afresh each frame. Every relative value is below 32 units (probes
/// within ~12 units of the camera, window origins within ~W/2 + W/2 of the anchor, scaled for
/// the 200-unit window by its 10x larger texel), where half an ulp32 is at most 2^-20 units,
/// 1e-4 of a 9.77 mm texel. A lookup chains about five such roundings (storage, products and
/// sums, subtraction) plus the division of s < 2048 (half an ulp32: 6e-5), so S7 < 1e-3, and
/// the drift, the difference of two frames' errors, stays below 1e-3 in practice (measured
/// 6.9e-4 at most); whole-texel flips never happen.
#[test]
fn camera_relative_f32_stays_near_zero_at_every_offset() {
    let mut worst: f64 = 0.0;
    for window in [20.0, 200.0] {
        for offset in [0.0, 1e3, 1e4, 1e5, 1e6] {
            let r = reference_run(window, offset, SnapMode::Floor, SnapSpace::CameraRelative);
            assert!(
                r.path.stats.max <= 1e-3,
                "{window} {offset}: drift {}",
                r.path.stats.max
            );
            assert_eq!(r.path.stats.cell_flip_rate, Some(0.0));
            assert!(r.lookup.max <= 1e-3, "{window} {offset}: S7 {}", r.lookup.max);
            worst = worst.max(r.path.stats.max);
        }
    }
    // Offset-independent: the same scene at 1e6 is as good as at the origin (within the
    // spread of rounding patterns, a factor of 2 at most).
    let at0 = reference_run(20.0, 0.0, SnapMode::Floor, SnapSpace::CameraRelative)
        .path
        .stats
        .max;
    let at6 = reference_run(20.0, 1e6, SnapMode::Floor, SnapSpace::CameraRelative)
        .path
        .stats
        .max;
    assert!(at6 <= 2.0 * at0 && at0 <= 2.0 * at6, "{at0} {at6}");
    // World-anchored f32 at 1e5 is more than 500 times worse.
    let world = reference_run(20.0, 1e5, SnapMode::Floor, SnapSpace::World)
        .path
        .stats
        .max;
    assert!(world > 500.0 * worst, "{world} vs {worst}");
}

/// S7 is about ulp32(|u|)/T: the roundings of the stored probe (three coordinates), of its
/// transform (three products, two sums) and of `u - o` are each at most half an ulp32 of a
/// value up to |X| ~ |u|; weighted by the unit matrix rows they bound S7 by about 4 ulp32/T.
/// With 800 probes over 30 frames the largest is well above half an ulp32/T.
#[test]
fn the_static_lookup_error_scales_as_ulp32_over_the_texel_size() {
    for window in [20.0, 200.0] {
        for offset in [1e4, 1e5, 1e6] {
            let r = reference_run(window, offset, SnapMode::Round, SnapSpace::World);
            let scale = ulp32(offset) / (window / 2048.0);
            let ratio = r.lookup.max / scale;
            assert!(
                (0.5..=4.0).contains(&ratio),
                "{window} {offset}: S7 {} vs {scale}",
                r.lookup.max
            );
            assert!(r.lookup.rms <= r.lookup.max && r.lookup.rms > 0.1 * scale);
        }
    }
    // The reference's "1e5, 20 m" static error is 0.98 to 1.31 texels depending on the
    // snapping; the same scale here.
    let r = reference_run(20.0, 1e5, SnapMode::Floor, SnapSpace::World);
    assert!((0.5..=3.2).contains(&r.lookup.max), "{}", r.lookup.max);
}

#[test]
fn the_aabb_fit_runs_in_f32_with_its_size_jitter_visible() {
    for space in ["world", "camera_relative"] {
        let text = with(&[
            ("shadow.fit", "fit = \"aabb\""),
            ("shadow.precision", "precision = \"f32\""),
            ("shadow.snap_space", &format!("snap_space = \"{space}\"")),
            ("scene.world_offset", "world_offset = [100000.0, 0.0, 0.0]"),
            ("motion.path", "path = \"yaw\""),
        ]);
        let a = analyze(&config(&text), &AnalysisOptions::full());
        let s = &a.summary;
        assert!(s.size_jitter > 1e-5, "{space}: an AABB window changes size under yaw");
        assert!(s.shimmer_snapped > 1e-3, "{space}: {}", s.shimmer_snapped);
        assert!(s.lookup_error_max.is_finite() && s.lookup_error_max > 0.0);
        if space == "camera_relative" {
            assert!(s.lookup_error_max < 1e-2, "{}", s.lookup_error_max);
        }
    }
}

#[test]
fn the_analysis_in_f32_reports_the_emulated_pipeline() {
    let text = with(&[
        ("shadow.precision", "precision = \"f32\""),
        ("scene.world_offset", "world_offset = [100000.0, 0.0, 0.0]"),
        ("motion.step", "step = 0.0137"),
    ]);
    let c = config(&text);
    assert_eq!(c.shadow.precision, Precision::F32);
    assert_eq!(c.shadow.snap_space, SnapSpace::World, "default snap space");
    let a = analyze(&c, &AnalysisOptions::full());
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let poses = c.camera_path().unwrap();
    let pr = probes(&rig, &poses[0], &c.scene, c.analysis.probes);
    let s = along_path(&rig, &poses, &pr, SnapSpace::World, true, OPTS);
    let u = along_path(&rig, &poses, &pr, SnapSpace::World, false, OPTS);
    assert_eq!(a.summary.shimmer_snapped, s.path.stats.rms);
    assert_eq!(a.summary.shimmer_unsnapped, u.path.stats.rms);
    assert_eq!(a.summary.lookup_error_max, s.lookup.max);
    assert_eq!(a.summary.lookup_error_rms, s.lookup.rms);
    assert_eq!(a.summary.coverage_violations, s.path.coverage.total());
    assert!(a.summary.shimmer_snapped > 1e-2, "world f32 at 1e5 shimmers");
    for (i, r) in a.cascades.iter().enumerate() {
        assert_eq!(r.lookup_error_max, s.lookup.cascade_max[i]);
    }
    // The f64 analysis of the same scene: exact.
    let mut c64 = c.clone();
    c64.shadow.precision = Precision::F64;
    let a64 = analyze(&c64, &AnalysisOptions::full());
    assert!(a64.snapped().unwrap().stats.max < 1e-9);
    assert_eq!((a64.summary.lookup_error_max, a64.summary.lookup_error_rms), (0.0, 0.0));
    // Camera-relative: near zero.
    let rel = config(&with(&[
        ("shadow.precision", "precision = \"f32\""),
        ("shadow.snap_space", "snap_space = \"camera_relative\""),
        ("scene.world_offset", "world_offset = [100000.0, 0.0, 0.0]"),
        ("motion.step", "step = 0.0137"),
    ]));
    let ar = analyze(&rel, &AnalysisOptions::full());
    assert!(ar.summary.shimmer_snapped < 1e-3, "{}", ar.summary.shimmer_snapped);
    assert!(ar.summary.lookup_error_max < 1e-3, "{}", ar.summary.lookup_error_max);
}

#[test]
fn the_world_offset_moves_camera_target_scene_and_path_file_together() {
    let offset = DVec3::new(1e5, -250.0, 3e4);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("p.csv"),
        "px,py,pz,tx,ty,tz\n0,10,0,0,0,-50\n0.5,10,0,0.5,0,-50\n1,10,0,1,0,-50\n",
    )
    .unwrap();
    let edits = [("motion.path", "path = \"file\""), ("motion.file", "file = \"p.csv\"")];
    let plain = csm_lab::Config::from_toml_str(&with(&edits), "a.toml", Some(dir.path())).unwrap();
    let line = format!("world_offset = [{:?}, {:?}, {:?}]", offset.x, offset.y, offset.z);
    let mut moved_edits = edits.to_vec();
    moved_edits.push(("scene.world_offset", &line));
    let moved = csm_lab::Config::from_toml_str(&with(&moved_edits), "b.toml", Some(dir.path())).unwrap();
    assert_eq!(moved.world_offset, offset);
    assert_eq!(moved.camera.position, plain.camera.position + offset);
    assert_eq!(moved.camera.target, plain.camera.target + offset);
    assert_eq!(moved.scene.min, plain.scene.min + offset);
    assert_eq!(moved.scene.max, plain.scene.max + offset);
    let (csm_lab::config::MotionPath::File { poses: a, .. }, csm_lab::config::MotionPath::File { poses: b, .. }) =
        (&plain.motion.path, &moved.motion.path)
    else {
        panic!("file paths");
    };
    for ((p0, t0), (p1, t1)) in a.iter().zip(b) {
        assert_eq!((*p1, *t1), (*p0 + offset, *t0 + offset));
    }
    // Downstream sees the same scene, only moved: identical splits and aliasing up to f64
    // rounding of coordinates near 1e5 (relative 1e-16 * 1e5 / 0.1 near plane ~ 1e-10).
    let a0 = analyze(&plain, &AnalysisOptions::full());
    let a1 = analyze(&moved, &AnalysisOptions::full());
    for (x, y) in a0.rig().unwrap().splits.iter().zip(&a1.rig().unwrap().splits) {
        assert!((x - y).abs() <= 1e-8 * y, "{x} {y}");
    }
    assert!((a0.summary.max_aliasing - a1.summary.max_aliasing).abs() <= 1e-8 * a0.summary.max_aliasing);
    assert_eq!(a1.summary.coverage_violations, 0);
    // The echo shows the offset and the moved camera.
    let echo = moved.echo();
    assert_eq!(echo["scene"]["world_offset"][0].as_f64(), Some(1e5));
    assert_eq!(echo["camera"]["position"][0].as_f64(), Some(1e5));
    assert_eq!(echo["shadow"]["precision"], "f64");
    assert_eq!(echo["shadow"]["snap_space"], "world");
}

#[test]
fn bad_precision_settings_name_the_key_the_value_and_what_is_allowed() {
    let err = |edits: &[(&str, &str)]| {
        csm_lab::Config::from_toml_str(&with(edits), "s.toml", None)
            .unwrap_err()
            .to_string()
    };
    let e = err(&[("shadow.precision", "precision = \"f16\"")]);
    assert!(
        e.contains("shadow.precision") && e.contains("f16") && e.contains("\"f64\", \"f32\""),
        "{e}"
    );
    assert!(e.starts_with("s.toml:"), "line and column: {e}");
    let e = err(&[("shadow.snap_space", "snap_space = \"local\"")]);
    assert!(
        e.contains("shadow.snap_space") && e.contains("local") && e.contains("camera_relative"),
        "{e}"
    );
    let e = err(&[("scene.world_offset", "world_offset = [nan, 0.0, 0.0]")]);
    assert!(e.contains("scene.world_offset") && e.contains("finite"), "{e}");
    // Each part is within the ±1e9 world bound, their sum is not.
    let e = err(&[
        ("scene.world_offset", "world_offset = [6e8, 0.0, 0.0]"),
        ("camera.position", "position = [6e8, 10.0, 0.0]"),
    ]);
    assert!(e.contains("scene.world_offset") && e.contains("camera.position"), "{e}");
    let e = err(&[("scene.world_offset", "world_offset = [1e308, 0.0, 0.0]")]);
    assert!(e.contains("scene.world_offset") && e.contains("1e9"), "{e}");
    // A wrong type is a TOML error with the line and column, as for every key.
    let text = with(&[("shadow.precision", "precision = 32")]);
    let line = text.lines().position(|l| l == "precision = 32").unwrap() + 1;
    let e = err(&[("shadow.precision", "precision = 32")]);
    assert!(e.starts_with(&format!("s.toml:{line}:")) && e.contains("string"), "{e}");
    // Texels of 1e-33 units: the loader already refuses far / near > 1e12, so such a scene
    // cannot come from a file; the binary32 range guard is checked on a hand-built config below.
    let e = err(&[("camera.near", "near = 1e-35")]);
    assert!(e.contains("camera.near") && e.contains("1e12"), "{e}");
    // An AABB slice narrower than one binary32 step at 2e5 units (ulp32 = 2^-6) collapses to
    // a zero-size window in world space (an engine divides by zero): refused, with the way
    // out; camera-relative coordinates are small, so that works.
    let collapse = [
        ("shadow.fit", "fit = \"aabb\""),
        ("shadow.cascades", "cascades = 1"),
        ("shadow.fit_depth_to_scene", "fit_depth_to_scene = false"),
        ("camera.near", "near = 0.001"),
        ("shadow.max_distance", "max_distance = 0.003"),
        ("scene.world_offset", "world_offset = [200000.0, 0.0, 0.0]"),
        ("shadow.precision", "precision = \"f32\""),
    ];
    let e = err(&collapse);
    assert!(
        e.contains("shadow.precision") && e.contains("collapses") && e.contains("camera_relative"),
        "{e}"
    );
    let mut relative = collapse.to_vec();
    relative.push(("shadow.snap_space", "snap_space = \"camera_relative\""));
    let a = analyze(&config(&with(&relative)), &AnalysisOptions::full());
    assert!(a.summary.lookup_error_max.is_finite() && a.summary.shimmer_snapped.is_finite());
    // precision::f32_range_problem explains why binary32 cannot hold texels of 1e-33 units.
    let mut c = config(&with(&[]));
    c.camera.near = 1e-35;
    c.shadow.lambda = 1.0;
    c.shadow.cascades = 16;
    let why = csm_lab::analysis::f32_range_problem(&c).unwrap();
    assert!(why.contains("binary32") && why.contains("2^-100"), "{why}");
    assert!(csm_lab::analysis::f32_range_problem(&config(&with(&[]))).is_none());
}

/// The library function behind the table in docs/accuracy.md.
#[test]
fn the_drift_table_shows_f64_exact_world_f32_growing_and_camera_relative_flat() {
    let rows = drift_table().unwrap();
    assert_eq!(rows.len(), 2 * 5 * 3);
    let get = |w: f64, o: f64, p: Precision, s: SnapSpace| {
        rows.iter()
            .find(|r| (r.window - w).abs() < 1e-9 * w && r.offset == o && r.precision == p && r.snap_space == s)
            .unwrap_or_else(|| panic!("row {w} {o} {p} {s}"))
    };
    for w in csm_lab::drift_table::DRIFT_WINDOWS {
        for o in csm_lab::drift_table::DRIFT_OFFSETS {
            let f = get(w, o, Precision::F64, SnapSpace::World);
            assert!(f.drift_max < 1e-9 && f.lookup_error_max == 0.0, "f64 {w} {o}");
            // Bounds as in camera_relative_f32_stays_near_zero_at_every_offset.
            let c = get(w, o, Precision::F32, SnapSpace::CameraRelative);
            assert!(
                c.drift_max <= 1e-3 && c.lookup_error_max <= 1e-3,
                "relative {w} {o}: {c:?}"
            );
            assert_eq!(f.coverage_violations + c.coverage_violations, 0);
            // The window really is the nominal size (texel = W / 2048).
            assert!((f.window - w).abs() < 1e-9 * w && (f.texel * 2048.0 - f.window).abs() < 1e-12 * w);
        }
        // World-anchored f32: flat while k*T is representable, then a large fraction of a
        // texel; S7 grows with the offset like ulp32/T.
        let world: Vec<_> = csm_lab::drift_table::DRIFT_OFFSETS
            .iter()
            .map(|&o| get(w, o, Precision::F32, SnapSpace::World))
            .collect();
        assert!(world[4].drift_max > 100.0 * world[1].drift_max, "{w}: {world:?}");
        for pair in world.windows(2).skip(1) {
            assert!(
                pair[1].lookup_error_max > 3.0 * pair[0].lookup_error_max,
                "{w}: {pair:?}"
            );
        }
        for r in &world[1..] {
            let ratio = r.lookup_error_max / r.ulp32_over_texel;
            assert!((0.5..=4.0).contains(&ratio), "{r:?}");
        }
    }
    let world_20_1e5 = get(20.0, 1e5, Precision::F32, SnapSpace::World);
    assert!(world_20_1e5.drift_max > 0.25, "{world_20_1e5:?}");
    // The Markdown lists one line per window and offset.
    let md = csm_lab::drift_table::drift_table_markdown(&rows);
    assert_eq!(md.lines().count(), 2 + 10);
    assert!(md.contains("| 20 (9.77 mm texels) | 1e5 |"), "{md}");
}

/// The default scene with an engine preset, in binary32 at a world offset.
fn preset_f32_text(preset: &str, offset: f64, precision: &str) -> String {
    crate::common::with(&[
        ("shadow.preset", &format!("preset = \"{preset}\"")),
        ("shadow.precision", &format!("precision = \"{precision}\"")),
        ("scene.world_offset", &format!("world_offset = [{offset:?}, 0.0, 0.0]")),
        ("motion.frames", "frames = 24"),
    ])
}

#[test]
fn every_preset_analyses_in_f32_with_finite_outputs() {
    for p in csm_lab::presets::PresetName::ALL {
        for offset in [0.0, 1e5] {
            let c = config(&preset_f32_text(p.as_str(), offset, "f32"));
            let a = csm_lab::analyze(&c, &csm_lab::AnalysisOptions::full());
            let s = &a.summary;
            assert!(s.cascades_needed, "{}", p.as_str());
            for v in [
                s.shimmer_snapped,
                s.shimmer_unsnapped,
                s.size_jitter,
                s.lookup_error_max,
                s.lookup_error_rms,
                s.max_aliasing,
            ] {
                assert!(v.is_finite(), "{} at {offset}: {s:?}", p.as_str());
            }
            // (At 1e5 a window kept at the world origin, unity-sample's defect, serves no probe.)
            if offset == 0.0 {
                assert!(
                    s.lookup_error_max > 0.0,
                    "{}: the f32 lookups were measured",
                    p.as_str()
                );
            }
        }
    }
}

#[test]
fn at_the_origin_every_presets_f32_windows_agree_with_its_f64_windows_to_a_few_ulps() {
    for p in csm_lab::presets::PresetName::ALL {
        let c = config(&preset_f32_text(p.as_str(), 0.0, "f64"));
        let rig = csm_lab::analysis::rig(&c).unwrap();
        let engine: EnginePipeline<f32> = EnginePipeline::new(&rig);
        let step = rig.snap_rule.step_texels as f64;
        for pose in c.camera_path().unwrap().iter().step_by(5) {
            let lp = LightPose::new(&rig.light, pose);
            for i in 0..rig.cascade_count() {
                for snapped in [false, true] {
                    let exact = rig.window(i, &lp, snapped);
                    let e = engine.window(i, pose, DVec3::ZERO, snapped);
                    let (o, t) = (e.origin_f64(), e.texel_f64());
                    let scale = exact.min().abs().max_element() + exact.width().max(exact.height());
                    let tol = 8.0 * ulp32(scale);
                    assert!(
                        ((t - exact.texel) * rig.resolution as f64).abs().max_element() <= tol,
                        "{} cascade {i}: texel {t} vs {}",
                        p.as_str(),
                        exact.texel
                    );
                    // A centre within an ulp of a grid line may snap to the neighbouring line.
                    let d = o - exact.min();
                    for a in 0..2 {
                        let grid = step * exact.texel[a];
                        let off = if snapped {
                            d[a] - (d[a] / grid).round() * grid
                        } else {
                            d[a]
                        };
                        assert!(
                            off.abs() <= tol,
                            "{} cascade {i} snapped {snapped}: {d} (tol {tol})",
                            p.as_str()
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn at_1e5_world_anchored_f32_shimmer_of_a_snapping_engine_is_positive_where_f64_is_zero() {
    let mut checked = Vec::new();
    for p in csm_lab::presets::PresetName::ALL {
        let exact = config(&preset_f32_text(p.as_str(), 1e5, "f64"));
        let rig = csm_lab::analysis::rig(&exact).unwrap();
        if !(rig.scheme.snaps && rig.fixed_basis()) {
            continue;
        }
        let f64_shimmer = csm_lab::analyze(&exact, &csm_lab::AnalysisOptions::summary_only())
            .summary
            .shimmer_snapped;
        if f64_shimmer != 0.0 {
            continue;
        }
        let f32_config = config(&preset_f32_text(p.as_str(), 1e5, "f32"));
        assert_eq!(f32_config.shadow.snap_space, SnapSpace::World);
        let f32_shimmer = csm_lab::analyze(&f32_config, &csm_lab::AnalysisOptions::summary_only())
            .summary
            .shimmer_snapped;
        assert!(
            f32_shimmer > 0.0,
            "{}: f32 world-anchored shimmer {f32_shimmer}",
            p.as_str()
        );
        checked.push(p.as_str());
    }
    assert!(checked.len() >= 5, "{checked:?}");
}
