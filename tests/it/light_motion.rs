//! A moving light (`motion.light_path`, `shadow.light_update`): crawl and jumps against
//! independent computations, periodicity of a full turn, and the bad inputs of its keys.

use crate::common;

use common::{config, with};
use csm_core::cascades::LightPose;
use csm_core::geometry::LightBasis;
use csm_core::rig_path::{along_path_lit, probes};
use csm_core::shimmer::{PathResult, ShimmerOptions};
use csm_lab::analysis::{analyze, light_track, AnalysisOptions};
use csm_lab::Config;
use glam::{DQuat, DVec2, DVec3};

const ROWS_AND_FLIPS: ShimmerOptions = ShimmerOptions {
    cell_flips: true,
    probe_drift: false,
    frame_rows: true,
};

/// The walk of a config with 120 probes per cascade, one snap mode.
fn walked(c: &Config, snapped: bool) -> PathResult {
    let rig = csm_lab::analysis::rig(c).unwrap();
    let poses = c.camera_path().unwrap();
    let pr = probes(&rig, &c.camera.pose(), &c.scene, 120);
    along_path_lit(&rig, &poses, &pr, light_track(c, 0), snapped, ROWS_AND_FLIPS)
}

fn sun_text(path: &str, az: f64, el: f64, frames: usize, update: &str) -> String {
    with(&[
        ("motion.path", &format!("path = \"{path}\"")),
        ("motion.frames", &format!("frames = {frames}")),
        ("motion.light_path", "light_path = \"sun\""),
        ("motion.sun_azimuth_step_deg", &format!("sun_azimuth_step_deg = {az}")),
        (
            "motion.sun_elevation_step_deg",
            &format!("sun_elevation_step_deg = {el}"),
        ),
        ("shadow.light_update", &format!("light_update = {update}")),
    ])
}

#[test]
fn between_updates_a_snapped_sphere_fit_does_not_crawl() {
    for path in ["still", "strafe"] {
        for k in [2usize, 4, 7] {
            let c = config(&sun_text(path, 0.3, -0.1, 43, &format!("{{ every_frames = {k} }}")));
            let s = walked(&c, true);
            let l = s.light.expect("a moving light reports crawl and jumps");
            assert_eq!(l.crawl_rms, 0.0, "{path} K={k}");
            assert_eq!(l.crawl_max, 0.0, "{path} K={k}");
            // Updates at frames K, 2K, ... (the pair ending there), once per cascade.
            assert_eq!(l.update_pairs, (42 / k) * 4, "{path} K={k}");
            assert!(
                l.jump_max > 0.1,
                "{path} K={k}: the sun turned, probes moved ({})",
                l.jump_max
            );
            // Every frame pair that is not an update has zero drift, frame by frame.
            for row in &s.frames {
                if row.frame % k != 0 {
                    assert_eq!(row.phase_drift_max, 0.0, "{path} K={k} {row:?}");
                    assert_eq!(row.cell_flips, Some(0.0), "{path} K={k} {row:?}");
                }
            }
            // The analysis says the same.
            let a = analyze(&c, &AnalysisOptions::summary_only());
            let ls = a.summary.light.unwrap();
            assert_eq!(ls.crawl_snapped, 0.0);
            assert_eq!(ls.crawl, 0.0);
            // Per cascade (cascades.csv): no crawl, and the largest jump is the summary's.
            let per: Vec<_> = a.cascades.iter().map(|x| x.light.unwrap()).collect();
            assert!(per.iter().all(|x| x.crawl == 0.0));
            assert_eq!(per.iter().map(|x| x.jump).fold(0.0, f64::max), ls.jump);
            if path == "strafe" {
                // Without snapping the strafing camera drifts between updates too.
                assert!(ls.crawl_unsnapped > 1e-3, "{path} K={k}: {}", ls.crawl_unsnapped);
            }
        }
    }
}

#[test]
fn a_quantized_sun_crawls_no_more_than_a_still_one_when_snapped() {
    // 0.05° per frame over 40 frames on a 0.5° grid: a few updates, crawl 0 between them.
    let c = config(&sun_text("strafe", 0.05, 0.0, 41, "{ quantize_deg = 0.5 }"));
    let l = walked(&c, true).light.unwrap();
    assert_eq!(l.crawl_rms, 0.0);
    assert!(l.update_pairs > 0 && l.update_pairs < 40 * 4, "{}", l.update_pairs);
    // A grid coarser than the whole turn (2°): no update at all, hence no jump.
    let c = config(&sun_text("strafe", 0.05, 0.0, 21, "{ quantize_deg = 45 }"));
    let l = walked(&c, true).light.unwrap();
    assert_eq!((l.update_pairs, l.jump_max), (0, 0.0));
}

/// The largest probe move at the one update of a two-frame path, computed directly: the sun
/// of frame 1 is frame 0's turned about the vertical (independently of the compass
/// conversion), each frame's window is built in its own basis, and each probe's texel
/// coordinates are its light-space x/y minus the window's corner, over the texel size.
#[test]
fn a_jump_is_the_probe_move_between_the_two_light_bases() {
    for path in ["still", "strafe"] {
        for turn_deg in [0.1, 1.0, 7.5] {
            let c = config(&sun_text(path, turn_deg, 0.0, 2, "{ every_frames = 1 }"));
            let rig = csm_lab::analysis::rig(&c).unwrap();
            let poses = c.camera_path().unwrap();
            let pr = probes(&rig, &poses[0], &c.scene, 120);
            let d0 = c.light_direction;
            // A compass azimuth grows from north toward east: a turn by −angle about +Y.
            let d1 = DQuat::from_rotation_y(-turn_deg.to_radians()) * d0;
            let bases = [LightBasis::new(d0), LightBasis::new(d1)];
            for snapped in [true, false] {
                let mut expected = 0.0f64;
                for (i, cascade) in pr.iter().enumerate() {
                    let s = |k: usize, x: DVec3| -> DVec2 {
                        let b = &bases[k];
                        let w = rig.window_in(i, &LightPose::new(b, &poses[k]), snapped);
                        let q = DVec2::new(b.x.dot(x), b.y.dot(x));
                        (q - w.min()) / w.texel
                    };
                    for x in cascade {
                        expected = expected.max((s(1, *x) - s(0, *x)).length());
                    }
                }
                let got = along_path_lit(&rig, &poses, &pr, light_track(&c, 0), snapped, ROWS_AND_FLIPS)
                    .light
                    .unwrap();
                assert_eq!(got.update_pairs, 4);
                assert!(
                    (got.jump_max - expected).abs() <= 1e-9 * expected.max(1.0),
                    "{path} {turn_deg}° snapped={snapped}: {} vs {expected}",
                    got.jump_max
                );
                // Larger turns, larger jumps: a 1° turn moves probes by more than a texel.
                if turn_deg >= 1.0 {
                    assert!(expected > 1.0, "{expected}");
                }
            }
        }
    }
}

#[test]
fn a_sun_turning_once_around_gives_periodic_frame_statistics() {
    let n = 24usize;
    for update in ["{ every_frames = 1 }", "{ every_frames = 3 }"] {
        let c = config(&sun_text("still", 360.0 / n as f64, 0.0, 2 * n + 1, update));
        for snapped in [true, false] {
            let rows = walked(&c, snapped).frames;
            let at = |t: usize, i: usize| rows.iter().find(|r| r.frame == t && r.cascade == i).copied();
            for t in 1..=n {
                for i in 0..4 {
                    let (a, b) = (at(t, i).unwrap(), at(t + n, i).unwrap());
                    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9;
                    assert!(
                        close(a.size_change, b.size_change)
                            && close(a.phase_drift_rms, b.phase_drift_rms)
                            && close(a.phase_drift_max, b.phase_drift_max)
                            && close(a.cell_flips.unwrap(), b.cell_flips.unwrap()),
                        "{update} snapped={snapped} frame {t} cascade {i}: {a:?} vs {b:?}"
                    );
                }
            }
            // And the sun does change something over the turn.
            assert!(rows.iter().any(|r| r.phase_drift_max > 1e-3));
        }
    }
}

#[test]
fn a_still_light_is_the_walk_without_light_motion() {
    // light_path = "still" with an update rule, and no light keys at all: the same walk.
    let plain = config(&with(&[]));
    let still = config(&with(&[
        ("motion.light_path", "light_path = \"still\""),
        ("shadow.light_update", "light_update = { quantize_deg = 5 }"),
    ]));
    assert!(light_track(&still, 0).is_none());
    let (a, b) = (
        analyze(&plain, &AnalysisOptions::full()),
        analyze(&still, &AnalysisOptions::full()),
    );
    assert_eq!(a.summary, b.summary);
    assert!(a.summary.light.is_none());
    assert_eq!(a.snapped(), b.snapped());
}

#[test]
fn a_camera_that_does_not_move_neither_shimmers_nor_crosses_seams() {
    let c = config(&with(&[("motion.path", "path = \"still\"")]));
    let a = analyze(&c, &AnalysisOptions::full());
    assert_eq!(a.summary.shimmer_snapped, 0.0);
    assert_eq!(a.summary.shimmer_unsnapped, 0.0);
    assert_eq!(a.summary.seam_crossings, Some(0.0));
    let poses = c.camera_path().unwrap();
    assert_eq!(poses.len(), 60);
    assert!(poses.iter().all(|p| *p == poses[0]));
}

#[test]
fn a_light_file_gives_one_direction_per_frame() {
    let dir = tempfile::tempdir().unwrap();
    let rows: Vec<String> = (0..5)
        .map(|t| format!("{}, -1, -0.3", -0.4 + 0.01 * t as f64))
        .collect();
    std::fs::write(dir.path().join("sun.csv"), format!("x,y,z\n{}\n", rows.join("\n"))).unwrap();
    let text = with(&[
        ("motion.frames", "frames = 5"),
        ("motion.light_path", "light_path = \"file\""),
        ("motion.light_file", "light_file = \"sun.csv\""),
    ]);
    let c = Config::from_toml_str(&text, "t.toml", Some(dir.path())).unwrap();
    for t in 0..5 {
        let d = DVec3::new(-0.4 + 0.01 * t as f64, -1.0, -0.3).normalize();
        assert!((c.motion.light.direction(c.light_direction, t) - d).length() < 1e-15);
    }
    let a = analyze(&c, &AnalysisOptions::summary_only());
    let l = a.summary.light.unwrap();
    assert!(l.jump > 0.0 && l.crawl == 0.0, "{l:?}");
}

fn rejected(text: &str) -> String {
    match Config::from_toml_str(text, "t.toml", None) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_light_motion_names_the_key_the_value_and_what_is_allowed() {
    let cases: Vec<(String, &[&str])> = vec![
        // A sun that does not move.
        (
            sun_text("still", 0.0, 0.0, 10, "{ every_frames = 1 }"),
            &["motion.sun_azimuth_step_deg", "non-zero", "\"still\""],
        ),
        // Sinking below the horizon on frame 7 (start elevation ≈ 63.4°, 10° per frame).
        (
            sun_text("still", 0.0, -10.0, 10, "{ every_frames = 1 }"),
            &["motion.sun_elevation_step_deg", "frame 7", "(0, 90]"],
        ),
        // Rising past the zenith.
        (
            sun_text("still", 0.0, 10.0, 10, "{ every_frames = 1 }"),
            &["motion.sun_elevation_step_deg", "frame 3", "(0, 90]"],
        ),
        (
            sun_text("still", 0.5, 0.0, 10, "{ every_frames = 0 }"),
            &["shadow.light_update.every_frames", "0", "1..="],
        ),
        (
            sun_text("still", 0.5, 0.0, 10, "{ quantize_deg = 0 }"),
            &["shadow.light_update.quantize_deg", "(0, 90]"],
        ),
        (
            sun_text("still", 0.5, 0.0, 10, "{ }"),
            &["shadow.light_update", "exactly one of"],
        ),
        (
            sun_text("still", 0.5, 0.0, 10, "{ every_frames = 2, quantize_deg = 1 }"),
            &["shadow.light_update", "exactly one of"],
        ),
        (
            with(&[("motion.light_path", "light_path = \"moon\"")]),
            &["motion.light_path", "\"moon\"", "\"sun\""],
        ),
        (
            with(&[("motion.sun_azimuth_step_deg", "sun_azimuth_step_deg = 1")]),
            &["motion.sun_azimuth_step_deg", "light_path = \"sun\""],
        ),
        (
            with(&[("motion.light_path", "light_path = \"file\"")]),
            &["motion.light_file", "(missing)", "x,y,z"],
        ),
        // A sun below the horizon from the start.
        (
            sun_text("still", 0.5, 0.0, 10, "{ every_frames = 1 }").replace("[-0.4, -1.0, -0.3]", "[-0.4, 0.2, -0.3]"),
            &["light.direction", "above the horizon"],
        ),
        (
            sun_text("still", 0.5, 0.0, 10, "{ every_frames = 1 }")
                .replace("[shadow]", "[shadow]\nprecision = \"f32\""),
            &["shadow.precision", "\"f64\" when the light moves"],
        ),
    ];
    for (text, needles) in cases {
        let e = rejected(&text);
        for n in needles {
            assert!(e.contains(n), "{n:?} not in: {e}");
        }
    }
    // A light file that points up, or has the wrong row count, names the file and the line.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("up.csv"), "x,y,z\n0,-1,0\n0.1,0.5,0\n").unwrap();
    let text = with(&[
        ("motion.frames", "frames = 2"),
        ("motion.light_path", "light_path = \"file\""),
        ("motion.light_file", "light_file = \"up.csv\""),
    ]);
    let e = Config::from_toml_str(&text, "t.toml", Some(dir.path()))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("up.csv") && e.contains('3') && e.contains("above the horizon"),
        "{e}"
    );
    let text = text.replace("frames = 2", "frames = 3").replace("up.csv", "two.csv");
    std::fs::write(dir.path().join("two.csv"), "x,y,z\n0,-1,0\n0.1,-1,0\n").unwrap();
    let e = Config::from_toml_str(&text, "t.toml", Some(dir.path()))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("motion.light_file") && e.contains("2 rows") && e.contains("(3 rows)"),
        "{e}"
    );
}

/// The sunset config's sweep table with the light update axis, as a small grid.
fn sunset() -> Config {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/sunset.toml")).unwrap();
    Config::from_toml_str(&text, "sunset.toml", None).unwrap()
}

#[test]
fn each_light_update_row_is_the_analysis_of_a_file_with_that_rule() {
    use csm_lab::commands::sweep::grid::Grid;
    use csm_lab::commands::sweep::run::run;
    use csm_lab::commands::sweep::SweepResult;
    use csm_lab::config::sweep_spec::SweepAxes;
    let c = sunset();
    let grid = Grid::resolve(&c, &SweepAxes::default()).unwrap();
    assert_eq!(grid.len(), 2 * 2 * 2 * 6);
    let rows = run(&c, &grid, Some(2), &|| {}).unwrap();
    let base = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/sunset.toml")).unwrap();
    for row in rows.iter().step_by(5) {
        let st = row.setting;
        let rule = match st.light_update.unwrap() {
            csm_core::light_motion::LightUpdate::EveryFrames(k) => format!("{{ every_frames = {k} }}"),
            csm_core::light_motion::LightUpdate::Quantize(q) => format!("{{ quantize_deg = {} }}", q.to_degrees()),
            other => panic!("{other:?}"),
        };
        let text = base
            .replace("light_update = { every_frames = 4 }", &format!("light_update = {rule}"))
            .replace("lambda = 0.75\n", &format!("lambda = {}\n", st.lambda))
            .replace("cascades = 4\n", &format!("cascades = {}\n", st.cascades))
            .replace("resolution = 2048\n", &format!("resolution = {}\n", st.resolution));
        let a = analyze(&config(&text), &AnalysisOptions::summary_only());
        let (l, r) = (a.summary.light.unwrap(), row.summary.light.unwrap());
        assert!(
            (l.jump - r.jump).abs() <= 1e-9 * l.jump.max(1.0),
            "{st:?}: {l:?} vs {r:?}"
        );
        assert_eq!(l.crawl, r.crawl, "{st:?}");
    }
    // Under a moving light the stability gate reads the snapped crawl between updates, not the
    // snapped shimmer, which counts every update's (deliberate) move: the snapped sphere fits
    // do not crawl, so they qualify although their shimmer_snapped is far above the gate.
    let result = SweepResult::new(c.clone(), grid, rows, String::new()).unwrap();
    let rec = result.recommended().expect("the snapped sphere fits qualify");
    let light = rec.summary.light.unwrap();
    assert_eq!(rec.summary.snapped_drift(), light.crawl_snapped);
    assert!(light.crawl_snapped <= csm_lab::commands::sweep::rank::STABLE_SHIMMER);
    assert!(
        rec.summary.shimmer_snapped > 10.0 * csm_lab::commands::sweep::rank::STABLE_SHIMMER,
        "{:?}",
        rec.summary
    );
    // The named step is the largest of its kind whose jump is under one texel, at the
    // recommended setting.
    let choice = result.light_update.clone().unwrap();
    let at = result.rows[choice.at].setting;
    assert_eq!((at.lambda, at.cascades, at.resolution), (0.75, 4, 2048));
    assert_eq!(choice.rows.len(), 6);
    let calm_every: Vec<_> = choice
        .rows
        .iter()
        .filter(|x| matches!(x.update, csm_core::light_motion::LightUpdate::EveryFrames(_)) && x.jump < 1.0)
        .collect();
    assert_eq!(choice.every.unwrap().update, calm_every.last().unwrap().update);
    assert!(
        choice.rows.iter().any(|x| x.jump >= 1.0),
        "the grid reaches a visible jump"
    );
    // Jumps grow with the update step: every K frames turns the sun K times as far.
    let jumps: Vec<f64> = choice.rows[..4].iter().map(|x| x.jump).collect();
    assert!(jumps.windows(2).all(|w| w[1] > 1.8 * w[0]), "{jumps:?}");
}

#[test]
fn a_light_update_axis_needs_a_moving_light_and_valid_rules() {
    use csm_lab::commands::sweep::grid::{parse_light_update_spec, Grid};
    use csm_lab::config::sweep_spec::SweepAxes;
    let still = config(&with(&[]));
    let o = SweepAxes {
        light_update: Some(parse_light_update_spec("every:1,2").unwrap()),
        ..Default::default()
    };
    let e = Grid::resolve(&still, &o).unwrap_err().to_string();
    assert!(e.contains("--light-update") && e.contains("moving light"), "{e}");
    for (spec, needle) in [
        ("every:0", "1..=1000000"),
        ("4", "has no rule"),
        ("quantize:0", "(0, 90]"),
        ("hourly:2", "not an update rule"),
        ("every:2,2", "twice"),
    ] {
        let e = parse_light_update_spec(spec).unwrap_err().to_string();
        assert!(e.contains("--light-update") && e.contains(needle), "{spec}: {e}");
    }
    let text = sunset_text().replace("\"every:8\"", "\"every:-1\"");
    let e = rejected(&text);
    assert!(e.contains("sweep.light_update") && e.contains("every:-1"), "{e}");
}

fn sunset_text() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/sunset.toml")).unwrap()
}

#[test]
fn ground_truth_refuses_a_moving_light_naming_the_flag_or_key() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let moving = base.replace(
        "[motion]\n",
        "[motion]\nlight_path = \"sun\"\nsun_azimuth_step_deg = 0.05\n",
    );
    assert_ne!(moving, base, "the default config has a [motion] table");
    let cfg = dir.path().join("moving.toml");
    std::fs::write(&cfg, &moving).unwrap();
    let keyed = dir.path().join("keyed.toml");
    std::fs::write(&keyed, format!("{moving}\n[analysis]\nground_truth = true\n")).unwrap();
    let out = dir.path().join("out");
    let run = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_csm-lab"))
            .args(args)
            .args(["--quiet", "--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let c = cfg.to_str().unwrap();
    for (args, named) in [
        (vec!["analyze", c, "--ground-truth"], "--ground-truth"),
        (vec!["sweep", c, "--ground-truth", "--no-plots"], "--ground-truth"),
        (vec!["analyze", keyed.to_str().unwrap()], "analysis.ground_truth"),
    ] {
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains(named) && err.contains("motion.light_path"),
            "{args:?}: {err}"
        );
    }
    assert!(!out.exists(), "nothing is written");
}
