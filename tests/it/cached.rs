//! Cached cascades (`[shadow] update_every`): the stale windows' coverage, margin and drift
//! against a closed form and a per-frame recomputation, the invariants of the cadence, the
//! ground-truth flicker at updates, the outputs and the errors.

use crate::common;

use common::{config, with};
use csm_core::cascades::{LightPose, Rig};
use csm_core::geometry::CameraPose;
use csm_core::rig_path::{along_path, along_path_cached, probes};
use csm_core::shimmer::{wrap, PathResult, ShimmerOptions, StaleStats};
use csm_core::walk::Cadence;
use csm_lab::analysis::{analyze, AnalysisOptions};
use glam::DVec2;
use proptest::prelude::*;

const OPTS: ShimmerOptions = ShimmerOptions {
    cell_flips: false,
    probe_drift: false,
    frame_rows: true,
};

fn rig_and_poses(text: &str) -> (Rig, Vec<CameraPose>, csm_lab::Config) {
    let c = config(text);
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let poses = c.camera_path().unwrap();
    (rig, poses, c)
}

fn cached(rig: &Rig, poses: &[CameraPose], every: &[usize], snapped: bool) -> PathResult {
    let [r] = along_path_cached(rig, poses, &[], Cadence { every, first_frame: 0 }, [snapped], OPTS);
    r
}

/// The four side margins (texels) of a window over a set of light-space corners:
/// `[x low, x high, y low, y high]`.
fn sides(w: &csm_core::fitting::Window, corners: &[DVec2; 8]) -> [f64; 4] {
    let n = w.resolution as f64;
    let mut out = [f64::INFINITY; 4];
    for c in corners {
        let s = w.texel_coords(*c);
        out[0] = out[0].min(s.x);
        out[1] = out[1].min(n - s.x);
        out[2] = out[2].min(s.y);
        out[3] = out[3].min(n - s.y);
    }
    out
}

/// A strafe at constant speed moves the slice rigidly by `d` (light space) per frame; an
/// unsnapped sphere window moves with it, so its side margins are constant. A window held for
/// `j` frames then has the margins of frame 0 shifted by `j d / T`: it is exceeded exactly when
/// the slice has moved beyond the margin on the side it moves toward. Violations and the
/// margin needed follow by hand from frame 0 and the speed, for every cadence.
#[test]
fn a_strafe_exceeds_a_held_window_exactly_when_the_slice_outruns_its_margin() {
    let text = with(&[
        ("shadow.cascades", "cascades = 2"),
        ("shadow.resolution", "resolution = 256"),
        ("shadow.snap", "snap = false"),
        ("motion.frames", "frames = 50"),
        ("motion.step", "step = 1.7"),
    ]);
    let (rig, poses, c) = rig_and_poses(&text);
    let step = 1.7;
    let lp0 = LightPose::new(&rig.light, &poses[0]);
    let right = poses[0].right * step;
    let d = DVec2::new(rig.light.x.dot(right), rig.light.y.dot(right));
    let mut seen_violation = false;
    for k in [1usize, 2, 3, 5, 8, 13, 60] {
        let every = vec![k; 2];
        let r = cached(&rig, &poses, &every, false);
        let stale = r.stale.as_ref();
        assert_eq!(stale.is_some(), k > 1, "stale statistics only when a cascade is held");
        for i in 0..2 {
            let s = &rig.slices[i];
            let w0 = rig.window(i, &lp0, false);
            let corners0 = lp0.corners(&rig.lens, s.near, s.far);
            let [xl, xh, yl, yh] = sides(&w0, &corners0);
            let (mut violations, mut margin, mut stale_frames) = (0u64, 0.0f64, 0u64);
            for t in 0..poses.len() {
                let j = (t % k) as f64;
                if t % k == 0 {
                    continue;
                }
                stale_frames += 1;
                let m = j * d / w0.texel;
                let slack = (xl + m.x).min(xh - m.x).min(yl + m.y).min(yh - m.y);
                if slack < -1e-6 {
                    violations += 1;
                    margin = margin.max(-slack);
                } else {
                    assert!(slack > 1e-6, "frame {t} sits on the boundary: pick another step");
                }
            }
            if k == 1 {
                continue;
            }
            let st = stale.unwrap();
            assert_eq!(st.every[i], k);
            assert_eq!(st.stale_frames[i], stale_frames, "k {k} cascade {i}");
            assert_eq!(st.violations[i], violations, "k {k} cascade {i}");
            assert!(
                (st.margin_texels[i] - margin).abs() < 1e-6 * margin.max(1.0),
                "k {k} cascade {i}: {} vs {margin}",
                st.margin_texels[i]
            );
            assert!((st.margin_world[i] - margin * w0.texel.max_element()).abs() < 1e-6 * margin.max(1.0));
            seen_violation |= violations > 0;
        }
    }
    assert!(
        seen_violation,
        "the step must outrun some margin ({c:?})",
        c = c.motion.step
    );
}

/// Every cascade's held window recomputed from scratch in every frame (the window of the last
/// update frame, the current slice's corners, the drift between consecutive held windows),
/// against the incremental walk: coverage per corner, stale holes, the margin and S3.
fn brute_force_matches(text: &str, every: &[usize], snapped: bool) {
    let (rig, poses, _) = rig_and_poses(text);
    let m = rig.cascade_count();
    let r = cached(&rig, &poses, every, snapped);
    let held = |i: usize, t: usize| {
        let k = every[i].max(1);
        let u = t - t % k;
        rig.window(i, &LightPose::new(&rig.light, &poses[u]), snapped)
    };
    let mut corners_out = vec![0u64; m];
    let mut holes = vec![0u64; m];
    let mut margin = vec![0.0f64; m];
    let (mut sum_sq, mut pairs) = (0.0, 0usize);
    let mut upd = vec![(0.0, 0u64); m];
    for (t, pose) in poses.iter().enumerate() {
        let lp = LightPose::new(&rig.light, pose);
        for i in 0..m {
            let w = held(i, t);
            let cov = rig.coverage_in(i, &lp, &w);
            corners_out[i] += cov.violations;
            if t % every[i].max(1) != 0 && cov.violations > 0 {
                holes[i] += 1;
                margin[i] = margin[i].max(-cov.min_slack_texels);
            }
            if t > 0 {
                let p = held(i, t - 1);
                assert_eq!(p.texel, w.texel, "a sphere fit keeps its texel size");
                let dd = DVec2::new(
                    wrap(p.origin_texels.x - w.origin_texels.x),
                    wrap(p.origin_texels.y - w.origin_texels.y),
                );
                sum_sq += dd.length_squared();
                pairs += 1;
                if t % every[i].max(1) == 0 {
                    upd[i].0 += dd.length_squared();
                    upd[i].1 += 1;
                }
            }
        }
    }
    assert_eq!(r.coverage.violations, corners_out, "corners outside, per cascade");
    let rms = (sum_sq / pairs as f64).sqrt();
    assert!(
        (r.stats.rms - rms).abs() <= 1e-12 * rms.max(1.0),
        "{} vs {rms}",
        r.stats.rms
    );
    if every.iter().any(|&k| k > 1) {
        let st: &StaleStats = r.stale.as_ref().unwrap();
        assert_eq!(st.violations, holes);
        assert_eq!(st.frames, poses.len());
        for i in 0..m {
            assert!((st.margin_texels[i] - margin[i]).abs() <= 1e-9 * margin[i].max(1.0));
            let want = if upd[i].1 > 0 {
                (upd[i].0 / upd[i].1 as f64).sqrt()
            } else {
                0.0
            };
            assert!((st.update_drift_rms[i] - want).abs() <= 1e-12 * want.max(1.0));
            assert_eq!(st.update_pairs[i], upd[i].1);
        }
    } else {
        assert!(r.stale.is_none());
    }
}

#[test]
fn the_incremental_walk_equals_a_per_frame_recomputation() {
    let moving = [
        ("strafe", "step = 0.9"),
        ("yaw", "step = 0.03"),
        ("orbit", "step = 0.02"),
        ("dolly", "step = 1.3"),
    ];
    for (path, step) in moving {
        let text = with(&[
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", step),
            ("motion.frames", "frames = 40"),
            ("shadow.resolution", "resolution = 512"),
        ]);
        for snapped in [true, false] {
            for every in [[1, 1, 1, 1], [1, 1, 2, 4], [3, 1, 7, 2], [40, 40, 40, 40]] {
                brute_force_matches(&text, &every, snapped);
            }
        }
    }
}

/// A tight box fit changes size between frames, so its windows are compared corner by corner
/// (coverage and holes); its drift needs the probes, which the walk's own tests check.
#[test]
fn a_tight_fit_holds_its_window_and_leaves_holes_a_per_frame_recomputation_finds() {
    let text = with(&[
        ("shadow.fit", "fit = \"aabb\""),
        ("motion.path", "path = \"yaw\""),
        ("motion.step", "step = 0.02"),
        ("motion.frames", "frames = 30"),
    ]);
    let (rig, poses, _) = rig_and_poses(&text);
    let every = [2usize, 3, 4, 5];
    let pr = probes(&rig, &poses[0], &config(&text).scene, 50);
    let [r] = along_path_cached(
        &rig,
        &poses,
        &pr,
        Cadence {
            every: &every,
            first_frame: 0,
        },
        [true],
        OPTS,
    );
    let st = r.stale.as_ref().unwrap();
    let mut holes = [0u64; 4];
    let mut margin = [0.0f64; 4];
    for (t, pose) in poses.iter().enumerate() {
        let lp = LightPose::new(&rig.light, pose);
        for i in 0..4 {
            if t % every[i] == 0 {
                continue;
            }
            let u = t - t % every[i];
            let w = rig.window(i, &LightPose::new(&rig.light, &poses[u]), true);
            let cov = rig.coverage_in(i, &lp, &w);
            if cov.violations > 0 {
                holes[i] += 1;
                margin[i] = margin[i].max(-cov.min_slack_texels);
            }
        }
    }
    assert_eq!(st.violations, holes.to_vec());
    for (got, want) in st.margin_texels.iter().zip(margin) {
        assert!((got - want).abs() <= 1e-9 * want.max(1.0));
    }
    assert!(
        holes.iter().sum::<u64>() > 0,
        "a tight fit under a turning camera leaves holes"
    );
    // Between updates the held window does not change: its frame rows drift by exactly 0.
    for f in &r.frames {
        if f.frame % every[f.cascade] != 0 {
            assert_eq!((f.size_change, f.phase_drift_max), (0.0, 0.0), "{f:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Cascades with cadence 1 walk exactly as without caching (their coverage and every frame
    /// row), whatever the others do; all ones is the uncached walk, bit for bit.
    #[test]
    fn cadence_one_is_the_uncached_walk(
        k in proptest::collection::vec(1usize..6, 4),
        path in prop::sample::select(vec!["strafe", "yaw", "orbit", "pitch", "dolly"]),
        step in 0.01f64..0.08,
        snapped in any::<bool>(),
    ) {
        let text = with(&[
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", &format!("step = {step}")),
            ("motion.frames", "frames = 24"),
            ("shadow.resolution", "resolution = 256"),
        ]);
        let (rig, poses, _) = rig_and_poses(&text);
        let plain = along_path(&rig, &poses, &[], snapped, OPTS);
        let ones = cached(&rig, &poses, &[1, 1, 1, 1], snapped);
        prop_assert_eq!(&ones, &plain);
        let mixed = cached(&rig, &poses, &k, snapped);
        for i in (0..4).filter(|&i| k[i] == 1) {
            prop_assert_eq!(mixed.coverage.violations[i], plain.coverage.violations[i]);
            prop_assert_eq!(mixed.coverage.min_slack_texels[i].to_bits(), plain.coverage.min_slack_texels[i].to_bits());
            let rows = |r: &PathResult| r.frames.iter().filter(|f| f.cascade == i).cloned().collect::<Vec<_>>();
            prop_assert_eq!(rows(&mixed), rows(&plain));
        }
    }

    /// On a strafe at constant speed (the slice only moves one way) a longer cadence never
    /// leaves fewer holes nor needs a smaller margin.
    #[test]
    fn violations_and_margin_grow_with_the_cadence_on_a_strafe(
        k1 in 1usize..12,
        extra in 0usize..12,
        step in 0.2f64..3.0,
        light_x in -0.8f64..0.8,
    ) {
        let text = with(&[
            ("light.direction", &format!("direction = [{light_x}, -1.0, 0.2]")),
            ("motion.step", &format!("step = {step}")),
            ("motion.frames", "frames = 40"),
            ("shadow.snap", "snap = false"),
            ("shadow.resolution", "resolution = 256"),
        ]);
        let (rig, poses, _) = rig_and_poses(&text);
        let k2 = k1 + extra;
        let a = cached(&rig, &poses, &[k1; 4], false);
        let b = cached(&rig, &poses, &[k2; 4], false);
        let none = StaleStats { violations: vec![0; 4], margin_texels: vec![0.0; 4], ..StaleStats::default() };
        let (sa, sb) = (a.stale.unwrap_or(none.clone()), b.stale.unwrap_or(none));
        for i in 0..4 {
            prop_assert!(sa.violations[i] <= sb.violations[i], "cascade {} k {} {}: {} > {}", i, k1, k2, sa.violations[i], sb.violations[i]);
            prop_assert!(sa.margin_texels[i] <= sb.margin_texels[i] + 1e-9);
        }
    }
}

/// The ground-truth flicker of cached cascades: a held map changes no receiver's state, so
/// every state change happens at an update of its cascade; all ones is the uncached pass.
#[test]
fn a_held_map_flips_no_receiver_between_its_updates() {
    let text = with(&[
        ("scene.ground", "ground = 0.0"),
        ("screen.width", "width = 320"),
        ("screen.height", "height = 180"),
        ("shadow.snap", "snap = false"),
        ("motion.frames", "frames = 12"),
        ("motion.step", "step = 0.37"),
    ]) + "\n[[scene.box]]\nmin = [-4.0, 0.0, -30.0]\nmax = [4.0, 6.0, -22.0]\n";
    let c = config(&text);
    let rig = csm_lab::analysis::rig(&c).unwrap();
    let setup = c.setup();
    let vis = setup.visibility().unwrap();
    let scene = &setup.geometry.as_ref().unwrap().scene;
    let points = csm_core::truth::receivers(scene, &vis);
    let m = rig.cascade_count();
    let sampling = csm_core::truth::Sampling {
        bias: vec![csm_core::truth::Bias::depth(0.05); m],
        format: None,
        ranges: vec![(-500.0, 500.0); m],
        pcf: 1,
        filter: csm_core::truth::PcfFilter::Nearest,
        binary32: None,
    };
    // The unsnapped walk with `counting` texel reads, at `cadence`.
    let walk = |counting: bool, cadence: Cadence<'_>| {
        csm_core::truth::flicker_cached(
            csm_core::truth::ShadowMaps::new(scene).counting(counting),
            &rig,
            &rig.light,
            c.camera_path().unwrap().into_iter(),
            false,
            &points,
            &sampling,
            cadence,
            &mut |_, _| {},
        )
    };
    let run = |every: &[usize]| walk(true, Cadence { every, first_frame: 0 });
    let plain = walk(true, Cadence::EVERY_FRAME);
    let ones = run(&[1, 1, 1, 1]);
    assert_eq!(ones, plain);
    let total = |f: &csm_core::truth::Flicker| -> (u64, u64) {
        (
            f.flips.iter().map(|&x| x as u64).sum(),
            f.steps.iter().map(|&x| x as u64).sum(),
        )
    };
    assert_eq!(plain.update_steps.iter().sum::<u64>(), total(&plain).1);
    assert!(total(&plain).0 > 0, "the unsnapped strafe flickers");
    let held = run(&[1, 2, 3, 4]);
    // Without texel counts (a sweep's rows) the walk steps the receivers through blocks of
    // frames: the same counts, held cascades included.
    let in_blocks = walk(
        false,
        Cadence {
            every: &[1, 2, 3, 4],
            first_frame: 0,
        },
    );
    assert_eq!(in_blocks.stats, csm_core::truth::CacheStats::default());
    assert_eq!(
        csm_core::truth::Flicker {
            stats: held.stats,
            ..in_blocks
        },
        held
    );
    let (flips, steps) = total(&held);
    assert_eq!(
        held.update_flips.iter().sum::<u64>(),
        flips,
        "every change at an update"
    );
    assert!(held.update_steps.iter().sum::<u64>() < steps);
    // Cascade 0 is rendered every frame in both passes: its receivers step and flip alike.
    assert_eq!(
        (held.update_steps[0], held.update_flips[0]),
        (plain.update_steps[0], plain.update_flips[0])
    );
    assert!((held.s5 - flips as f64 / steps as f64).abs() < 1e-15);
}

/// `update_every = 1` (or all ones) is today's setting: the same config, the same analysis;
/// a cached far cascade shows its figures in the summary and per cascade.
#[test]
fn all_ones_is_todays_analysis_and_a_cached_cascade_reports_its_cost() {
    let base = config(common::BASE);
    let full = AnalysisOptions::full();
    let today = analyze(&base, &full);
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, text: &str| {
        let d = dir.path().join(name);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("scene.toml"), text).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_csm-lab"))
            .args(["analyze", "--quiet", "--out", "out", "scene.toml"])
            .current_dir(&d)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        (out.stdout, common::files(&d.join("out")))
    };
    let (stdout, files) = run("today", common::BASE);
    for (k, ones) in ["update_every = 1", "update_every = [1, 1, 1, 1]"]
        .into_iter()
        .enumerate()
    {
        let text = with(&[("shadow.update_every", ones)]);
        let c = config(&text);
        assert_eq!(c.shadow, base.shadow, "{ones}");
        let a = analyze(&c, &full);
        assert_eq!((&a.summary, &a.cascades), (&today.summary, &today.cascades), "{ones}");
        let (o, f) = run(&format!("ones{k}"), &text);
        assert_eq!(String::from_utf8_lossy(&o), String::from_utf8_lossy(&stdout), "{ones}");
        assert_eq!(f.keys().collect::<Vec<_>>(), files.keys().collect::<Vec<_>>());
        for (name, bytes) in &f {
            assert!(bytes == &files[name], "{ones}: {name} differs");
        }
    }
    let text = with(&[
        ("shadow.update_every", "update_every = [1, 1, 2, 4]"),
        ("shadow.fit", "fit = \"aabb\""),
        ("motion.path", "path = \"yaw\""),
        ("motion.step", "step = 0.02"),
    ]);
    let a = analyze(&config(&text), &AnalysisOptions::summary_only());
    let s = a.summary.cache.expect("cached cascades measured");
    assert_eq!(s.renders_per_frame, 2.75);
    let per: Vec<_> = a.cascades.iter().map(|c| c.cache.unwrap()).collect();
    assert_eq!(per.iter().map(|c| c.update_every).collect::<Vec<_>>(), [1, 1, 2, 4]);
    assert_eq!(
        per[0].figures.stale_coverage_violations + per[1].figures.stale_coverage_violations,
        0
    );
    assert_eq!(
        s.figures.stale_coverage_violations,
        per.iter().map(|c| c.figures.stale_coverage_violations).sum::<u64>()
    );
    assert!(
        s.figures.stale_coverage_violations > 0,
        "a tight fit under a turn leaves holes"
    );
    assert_eq!(
        s.figures.stale_margin,
        per.iter().map(|c| c.figures.stale_margin).fold(0.0, f64::max)
    );
    let cols = csm_lab::metric::cascade_columns(false, false, false, true, false, false);
    for name in [
        "update_every",
        "stale_coverage_violations",
        "stale_margin",
        "update_drift",
    ] {
        assert!(cols.contains(&name), "{name}");
    }
    let fields = csm_lab::metric::cascade_fields(&a.cascades[3]).unwrap();
    assert_eq!(fields.len(), cols.len());
    let at = |n: &str| &fields[cols.iter().position(|c| *c == n).unwrap()];
    assert_eq!(at("update_every"), "4");
    assert_eq!(at("update_rate"), "0.25");
    assert_eq!(
        at("stale_coverage_violations"),
        &per[3].figures.stale_coverage_violations.to_string()
    );
}

#[test]
fn bad_cadences_are_errors_that_name_the_key_the_value_and_what_is_allowed() {
    let rejected = |text: &str| match csm_lab::Config::from_toml_str(text, "t.toml", None) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    };
    for (line, shown, allowed) in [
        ("update_every = 0", "0", "an integer in 1..=256"),
        ("update_every = 257", "257", "an integer in 1..=256"),
        ("update_every = \"4\"", "\"4\"", "an integer in 1..=256"),
        ("update_every = [1, 0, 2, 4]", "[1, 0, 2, 4]", "one per cascade"),
        ("update_every = [1, 1.5]", "[1, 1.5]", "one per cascade"),
        ("update_every = []", "[]", "an integer in 1..=256"),
        (
            "update_every = [1, 2, 4]",
            "[1, 2, 4]",
            "one integer per cascade (4 here)",
        ),
    ] {
        let e = rejected(&with(&[("shadow.update_every", line)]));
        assert!(e.contains("shadow.update_every"), "{line}: {e}");
        assert!(e.contains(shown), "{line}: {e}");
        assert!(e.contains(allowed), "{line}: {e}");
        assert!(e.contains("t.toml:"), "{line}: line and column: {e}");
    }
    let f32 = rejected(&with(&[
        ("shadow.update_every", "update_every = 2"),
        ("shadow.precision", "precision = \"f32\""),
    ]));
    assert!(
        f32.contains("shadow.update_every") && f32.contains("f64 pipeline only"),
        "{f32}"
    );
    let turning = rejected(&with(&[
        ("shadow.update_every", "update_every = 2"),
        ("shadow.preset", "preset = \"filament\""),
    ]));
    assert!(turning.contains("follows the camera"), "{turning}");
    let sun = rejected(&with(&[
        ("shadow.update_every", "update_every = 2"),
        ("motion.light_path", "light_path = \"sun\""),
        ("motion.sun_azimuth_step_deg", "sun_azimuth_step_deg = 0.01"),
    ]));
    assert!(sun.contains("when the light moves"), "{sun}");
}

/// `analyze --all-frames` walks a long path in overlapping chunks; with cached cascades each
/// chunk starts early enough that every cascade holds the window of its last render, so its
/// rows equal, frame for frame, those one walk of the whole path keeps, and between a
/// cascade's renders its rows drift by 0.
#[test]
fn every_frame_rows_of_a_long_path_agree_with_one_walk_of_it() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let every = [1usize, 3, 7, 250];
    let cfg = dir.path().join("long.toml");
    let text = with(&[
        ("motion.path", "path = \"yaw\""),
        ("motion.frames", "frames = 2500"),
        ("shadow.update_every", "update_every = [1, 3, 7, 250]"),
        ("shadow.fit", "fit = \"aabb\""),
    ]);
    std::fs::write(&cfg, text).unwrap();
    let run = |all: bool| {
        let out = dir.path().join(format!("o{all}"));
        let mut c = Command::new(env!("CARGO_BIN_EXE_csm-lab"));
        c.args([
            "analyze",
            "--quiet",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        if all {
            c.arg("--all-frames");
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        common::read_csv(&out.join("shimmer.csv")).1
    };
    let kept = run(false);
    let all = run(true);
    assert_eq!(all.len(), 2_499 * 4 * 2, "every frame pair, cascade and snap mode");
    let by_key: std::collections::BTreeMap<_, _> = all
        .iter()
        .map(|r| ((r[0].clone(), r[1].clone(), r[2].clone()), r.clone()))
        .collect();
    assert!(kept.len() < all.len() / 2);
    for r in &kept {
        assert_eq!(&by_key[&(r[0].clone(), r[1].clone(), r[2].clone())], r);
    }
    let mut moved = 0;
    for r in &all {
        let (t, i): (usize, usize) = (r[0].parse().unwrap(), r[1].parse().unwrap());
        let drift: f64 = r[5].parse().unwrap();
        if t % every[i] != 0 {
            assert_eq!((r[3].as_str(), drift), ("0", 0.0), "{r:?}");
        } else if drift > 0.0 {
            moved += 1;
        }
    }
    assert!(moved > 0, "the renders drift");
}

/// A sweep point with another cascade count than a per-cascade `update_every` is an error
/// naming the key, never a row silently rendered every frame; one value fits every count.
#[test]
fn a_per_cascade_cadence_refuses_a_sweep_point_of_another_count() {
    use csm_lab::config::{Fit, SplitRange};
    let c = config(&with(&[("shadow.update_every", "update_every = [1, 1, 2, 4]")]));
    let e = c
        .with_sweep_point(0.5, 3, 1024, Fit::Sphere, SplitRange::Bounds)
        .unwrap_err()
        .to_string();
    assert!(e.contains("shadow.update_every") && e.contains("(3 here)"), "{e}");
    assert!(c
        .with_sweep_point(0.5, 4, 1024, Fit::Sphere, SplitRange::Bounds)
        .is_ok());
    let one = config(&with(&[("shadow.update_every", "update_every = 3")]));
    for n in [1, 3, 8] {
        let p = one
            .with_sweep_point(0.5, n, 1024, Fit::Sphere, SplitRange::Bounds)
            .unwrap();
        let a = analyze(&p, &AnalysisOptions::summary_only());
        let r = a.summary.cache.unwrap().renders_per_frame;
        assert!((r - n as f64 / 3.0).abs() < 1e-12, "{n}: {r}");
    }
}
