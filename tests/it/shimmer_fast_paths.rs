//! The shared-work walk of both snap modes against the plain per-mode, per-corner definitions.

use crate::common;

use common::{config, with};
use csm_core::cascades::LightPose;
use csm_core::rig_path::{along_path, along_path_both, probes};
use csm_core::shimmer::ShimmerOptions;
use csm_core::snapping::{SnapMode, SnapRule};

fn all_options() -> [ShimmerOptions; 3] {
    let o = |cell_flips, probe_drift, frame_rows| ShimmerOptions {
        cell_flips,
        probe_drift,
        frame_rows,
    };
    [o(false, false, false), o(true, false, true), o(true, true, true)]
}

/// The proptests' random path: the default camera and a 400-unit scene moved by `offset`, the
/// light along `light`, `cascades` × `resolution` (and `lambda` when given), and the snap rule
/// (mode 0 round, 1 floor, 2 trunc; step in texels). A pitch stays within 60 degrees of its
/// start (past the vertical the path is refused) and a turn takes at most 1 degree a frame.
#[allow(clippy::too_many_arguments)]
fn random_path(
    path: &str,
    step: f64,
    frames: usize,
    lambda: Option<f64>,
    (cascades, resolution): (usize, u32),
    offset: f64,
    light: (f64, f64, f64),
    snap: (usize, u32),
) -> (csm_lab::Config, csm_core::cascades::Rig) {
    let step = match path {
        "pitch" => step.min(60.0 / frames as f64),
        "yaw" | "orbit" => step.min(1.0),
        _ => step,
    };
    let lambda = lambda.map(|l| format!("lambda = {l}"));
    let mut edits = vec![
        ("camera.position", format!("position = [{offset}, 10.0, {offset}]")),
        ("camera.target", format!("target = [{offset}, 0.0, {}]", offset - 50.0)),
        (
            "scene.min",
            format!("min = [{}, 0.0, {}]", offset - 200.0, offset - 200.0),
        ),
        (
            "scene.max",
            format!("max = [{}, 40.0, {}]", offset + 200.0, offset + 200.0),
        ),
        (
            "light.direction",
            format!("direction = [{}, {}, {}]", light.0, light.1, light.2),
        ),
        ("shadow.cascades", format!("cascades = {cascades}")),
        ("shadow.resolution", format!("resolution = {resolution}")),
        ("motion.path", format!("path = \"{path}\"")),
        ("motion.step", format!("step = {step}")),
        ("motion.frames", format!("frames = {frames}")),
    ];
    edits.extend(lambda.map(|l| ("shadow.lambda", l)));
    let edits: Vec<(&str, &str)> = edits.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let c = config(&with(&edits));
    let mut rig = csm_lab::analysis::rig(&c).unwrap();
    rig.snap_rule = SnapRule {
        mode: [SnapMode::Round, SnapMode::Floor, SnapMode::Trunc][snap.0],
        step_texels: snap.1,
    };
    (c, rig)
}

#[test]
fn both_modes_in_one_walk_equal_two_separate_walks_bit_for_bit() {
    for (fit, path, step) in [
        ("sphere", "strafe", "0.37"),
        ("sphere", "orbit", "0.4"),
        ("aabb", "yaw", "0.3"),
        ("aabb", "dolly", "0.9"),
    ] {
        let text = with(&[
            ("shadow.fit", &format!("fit = \"{fit}\"")),
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", &format!("step = {step}")),
        ]);
        let c = config(&text);
        let rig = csm_lab::analysis::rig(&c).unwrap();
        let poses = c.camera_path().unwrap();
        let pr = probes(&rig, &c.camera.pose(), &c.scene, 48);
        for opts in all_options() {
            let (s, u) = along_path_both(&rig, &poses, &pr, opts);
            assert_eq!(s, along_path(&rig, &poses, &pr, true, opts), "{fit} {path} {opts:?}");
            assert_eq!(u, along_path(&rig, &poses, &pr, false, opts), "{fit} {path} {opts:?}");
        }
    }
}

/// Windows too small for their slices: the walk's coverage (extreme corners first, the
/// per-corner pass only when something can be outside) against the per-corner definition.
#[test]
fn coverage_of_shrunken_windows_matches_a_per_corner_count() {
    for (fit, path) in [("sphere", "yaw"), ("sphere", "strafe"), ("aabb", "orbit")] {
        let text = with(&[
            ("shadow.fit", &format!("fit = \"{fit}\"")),
            ("motion.path", &format!("path = \"{path}\"")),
            ("motion.step", "step = 0.7"),
        ]);
        let c = config(&text);
        let mut rig = csm_lab::analysis::rig(&c).unwrap();
        // Shrink every sphere window by a different factor, some barely, some a lot.
        for (i, side) in rig.sphere_side.iter_mut().enumerate() {
            *side *= [0.999, 0.8, 0.99999, 0.6][i % 4];
        }
        let poses = c.camera_path().unwrap();
        for snapped in [true, false] {
            let got = along_path(&rig, &poses, &[], snapped, all_options()[0]).coverage;
            let m = rig.cascade_count();
            let (mut count, mut worst, mut slack_min) = (vec![0u64; m], vec![0.0f64; m], vec![f64::INFINITY; m]);
            // The per-corner test of `Rig::coverage`, frame by frame, against the walk's
            // extremes-first shortcut.
            for pose in &poses {
                let lp = LightPose::new(&rig.light, pose);
                for i in 0..m {
                    let w = rig.window(i, &lp, snapped);
                    let f = rig.coverage(i, &lp, &w);
                    count[i] += f.violations;
                    worst[i] = worst[i].max(f.worst_texels);
                    slack_min[i] = slack_min[i].min(f.min_slack_texels);
                }
            }
            if fit == "sphere" {
                assert!(
                    count.iter().sum::<u64>() > 0,
                    "{fit} {path}: the shrunken windows must miss corners"
                );
            }
            assert_eq!(got.violations, count, "{fit} {path} {snapped}");
            assert_eq!(got.worst_texels, worst, "{fit} {path} {snapped}");
            assert_eq!(got.min_slack_texels, slack_min, "{fit} {path} {snapped}");
        }
    }
}

/// The sweep's probe-free walk of both snap modes (a still light, a fixed basis, a sphere
/// fit, no S4 and no rows: `along_path_both` takes it; paths of one and of several of its
/// chunks of frames) against the generic walk of each mode
/// (`along_path`), bit for bit, on random scenes, paths, grids, snap rules and anchors, with
/// windows shrunk so that corners fall outside.
mod probe_free_walk {
    use super::*;
    use glam::DVec2;
    use proptest::prelude::*;

    fn bits(r: &csm_core::shimmer::PathResult) -> String {
        // Debug prints every f64 in its shortest round-trip form: equal text, equal bits
        // (signed zeros included), unlike `==`.
        format!("{r:?}")
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]
        #[test]
        fn equals_the_generic_walk_bit_for_bit(
            path in prop::sample::select(vec!["strafe", "dolly", "yaw", "pitch", "orbit", "still"]),
            step in 0.001f64..2.0,
            frames in prop_oneof![2usize..40, 500usize..1100],
            lambda in 0.0f64..=1.0,
            cascades in 1usize..=8,
            resolution in prop::sample::select(vec![256u32, 512, 1000, 2048, 4096]),
            offset in prop::sample::select(vec![0.0f64, 1234.5, 1e5]),
            light in (-1.0f64..1.0, -1.0f64..-0.05, -1.0f64..1.0),
            snap in (0usize..3, prop::sample::select(vec![1u32, 2, 4])),
            anchor in (-3.0f64..3.0, -3.0f64..3.0, any::<bool>()),
            shrink in prop::collection::vec(0.5f64..1.0, 8),
        ) {
            let (c, mut rig) = random_path(
                path,
                step,
                frames,
                Some(lambda),
                (cascades, resolution),
                offset,
                light,
                snap,
            );
            if anchor.2 {
                rig.scheme.snap_anchor = DVec2::new(anchor.0, anchor.1);
            }
            for (side, k) in rig.sphere_side.iter_mut().zip(&shrink) {
                if *k < 0.75 {
                    *side *= *k;
                }
            }
            let poses = c.camera_path().unwrap();
            let opts = all_options()[0];
            let (s, u) = along_path_both(&rig, &poses, &[], opts);
            prop_assert_eq!(bits(&s), bits(&along_path(&rig, &poses, &[], true, opts)));
            prop_assert_eq!(bits(&u), bits(&along_path(&rig, &poses, &[], false, opts)));
        }
    }
}

/// The probe-free walk over arrays of frames (`rig_path`'s array walk: camera axes that do not
/// change, rounding to whole texels or no snapping, no anchor) against the generic walk of
/// each mode, bit for bit: strafes, dollies and still cameras of one and several chunks,
/// even and odd resolutions, offsets up to the loader's limit, texels so small that the centres
/// in texels pass 2^50 (the walk then goes frame by frame), windows shrunk until corners fall
/// outside (the same).
mod array_walk {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]
        #[test]
        fn equals_the_generic_walk_bit_for_bit(
            path in prop::sample::select(vec!["strafe", "dolly", "still"]),
            step in prop_oneof![0.0001f64..0.05, 0.05f64..3.0, -3.0f64..-0.05],
            frames in prop_oneof![2usize..40, 500usize..1100],
            lambda in 0.0f64..=1.0,
            cascades in 1usize..=8,
            resolution in prop::sample::select(vec![255u32, 512, 999, 1000, 2048, 4096]),
            offset in prop::sample::select(vec![0.0f64, 1234.5, 1e5, 9.99e8]),
            light in (-1.0f64..1.0, -1.0f64..-0.05, -1.0f64..1.0),
            snaps in any::<bool>(),
            shrink in prop::collection::vec(0.5f64..1.0, 8),
            tiny in any::<bool>(),
        ) {
            let (c, mut rig) = random_path(
                path,
                step,
                frames,
                Some(lambda),
                (cascades, resolution),
                offset,
                light,
                (0, 1),
            );
            rig.scheme.snaps = snaps;
            for (side, k) in rig.sphere_side.iter_mut().zip(&shrink) {
                if *k < 0.7 {
                    *side *= *k;
                }
            }
            if tiny {
                // Texels so small that the centres in texels pass 2^50 far from the origin.
                rig.sphere_side[0] *= 1e-9;
            }
            let poses = c.camera_path().unwrap();
            let opts = all_options()[0];
            let (s, u) = along_path_both(&rig, &poses, &[], opts);
            prop_assert_eq!(format!("{s:?}"), format!("{:?}", along_path(&rig, &poses, &[], true, opts)));
            prop_assert_eq!(format!("{u:?}"), format!("{:?}", along_path(&rig, &poses, &[], false, opts)));
        }
    }
}

/// Every engine preset's rig (axis-centred, box-centred and tight windows, snap anchors,
/// selection intervals): `along_path_both` (the probe-free walk wherever it applies) against the
/// generic walk of each mode, bit for bit, on a strafe, a dolly and a yaw.
#[test]
fn every_preset_walks_both_modes_as_the_generic_walk_does_bit_for_bit() {
    for preset in csm_lab::presets::PresetName::ALL {
        for (path, step) in [("strafe", "0.37"), ("dolly", "0.9"), ("yaw", "0.3")] {
            let scene = common::BASE.split("[shadow]").next().unwrap();
            let text = format!(
                "{scene}[shadow]\npreset = \"{}\"\n\n[motion]\npath = \"{path}\"\nframes = 60\nstep = {step}\n",
                preset.as_str()
            );
            let c = config(&text);
            let rig = csm_lab::analysis::rig(&c).unwrap();
            let poses = c.camera_path().unwrap();
            let opts = all_options()[0];
            let (s, u) = along_path_both(&rig, &poses, &[], opts);
            let name = preset.as_str();
            assert_eq!(
                format!("{s:?}"),
                format!("{:?}", along_path(&rig, &poses, &[], true, opts)),
                "{name} {path}"
            );
            assert_eq!(
                format!("{u:?}"),
                format!("{:?}", along_path(&rig, &poses, &[], false, opts)),
                "{name} {path}"
            );
        }
    }
}

/// S4 when S3 has the closed form (a sphere fit: the walk counts flips from the sampled texels,
/// or from their centres when a window moves by nearly half a texel) against S4 of the full
/// per-probe kernel (`probe_drift`: every probe landed, its centre's move tested), frame by
/// frame and bit for bit, on random paths, steps, offsets, lights, grids and snap rules.
mod flips_from_texels {
    use super::*;
    use proptest::prelude::*;

    fn flips(r: &csm_core::shimmer::PathResult) -> Vec<String> {
        r.frames
            .iter()
            .map(|f| format!("{} {} {:?}", f.frame, f.cascade, f.cell_flips))
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 120, ..ProptestConfig::default() })]
        #[test]
        fn equal_the_per_probe_kernel_bit_for_bit(
            path in prop::sample::select(vec!["strafe", "dolly", "yaw", "pitch", "orbit"]),
            step in prop_oneof![0.0005f64..0.05, 0.05f64..2.0],
            frames in 2usize..80,
            cascades in 1usize..=6,
            resolution in prop::sample::select(vec![256u32, 512, 1000, 2048]),
            offset in prop::sample::select(vec![0.0f64, 1234.5, 1e5]),
            light in (-1.0f64..1.0, -1.0f64..-0.05, -1.0f64..1.0),
            snap in (0usize..3, prop::sample::select(vec![1u32, 2, 4])),
        ) {
            let (c, rig) = random_path(path, step, frames, None, (cascades, resolution), offset, light, snap);
            let poses = c.camera_path().unwrap();
            let pr = probes(&rig, &c.camera.pose(), &c.scene, 64);
            let [_, texels, per_probe] = all_options();
            for snapped in [true, false] {
                let a = along_path(&rig, &poses, &pr, snapped, texels);
                let b = along_path(&rig, &poses, &pr, snapped, per_probe);
                prop_assert_eq!(flips(&a), flips(&b), "snapped {}", snapped);
                prop_assert_eq!(format!("{:?}", a.stats.cell_flip_rate), format!("{:?}", b.stats.cell_flip_rate));
            }
        }
    }
}
