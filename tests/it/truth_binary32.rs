//! The ground truth's binary32 pipeline (issue 20 item 5): with `precision = "f32"` the pass
//! rebuilds each cascade's light matrix in f32 every frame and stores and compares depths in
//! f32. Checked against a brute force written here (the f32 re-projection of receivers, their
//! texel's ray and both depths through the frame's f32 matrix), and against the f64 pass, whose
//! snapped maps never flicker.

use csm_core::cascades::LightPose;
use csm_core::precision::EnginePipeline;
use csm_core::truth::{self, Sampling};
use csm_lab::analysis::ground_truth::GroundTruth;
use csm_lab::{analyze, AnalysisOptions, Config};
use glam::DVec3;

/// A small scene far from the world origin (so binary32 rounds coarsely), a box casting a
/// shadow into view, snapped sphere fits, no bias, one nearest tap per lookup.
fn scene(precision: &str, snap: bool) -> String {
    format!(
        r#"
[camera]
position = [0.0, 6.0, 12.0]
target = [0.0, 0.0, -6.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 60.0
near = 0.1
far = 200.0

[screen]
width = 320
height = 180

[light]
direction = [-0.4, -1.0, -0.3]

[scene]
min = [-60.0, 0.0, -60.0]
max = [60.0, 10.0, 60.0]
ground = 0.0
world_offset = [3000.0, 0.0, -2000.0]

[[scene.box]]
min = [-2.3, 0.0, -8.7]
max = [1.9, 3.1, -4.4]

[shadow]
max_distance = 60.0
cascades = 2
lambda = 0.75
resolution = 256
fit = "sphere"
snap = {snap}
precision = "{precision}"
bias = "none"
pcf_filter = "nearest"

[motion]
path = "strafe"
frames = 24
step = 0.05

[analysis]
screen_scale = 0.25
ground_truth = true
"#
    )
}

fn run(text: &str) -> (Config, csm_lab::Analysis) {
    let c = Config::from_toml_str(text, "test.toml", None).unwrap();
    let a = analyze(&c, &AnalysisOptions::full());
    (c, a)
}

fn truth_of(a: &csm_lab::Analysis) -> &GroundTruth {
    a.ground_truth.as_ref().expect("ground truth ran")
}

fn sampling(c: &Config, g: &GroundTruth, rig: &csm_core::cascades::Rig, f32s: bool) -> Sampling {
    Sampling {
        bias: g.bias.clone(),
        format: Some(c.truth.depth_format),
        ranges: g.ranges.clone(),
        pcf: 1,
        filter: g.filter,
        binary32: f32s.then(|| truth::Binary32::new(rig, c.shadow.snap_space, c.scene)),
    }
}

/// `a . b` in f32, left to right, every operation rounded.
fn dot32(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn f32s(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

#[test]
fn binary32_answers_equal_a_brute_force_f32_reprojection_in_every_frame() {
    for snapped in [true, false] {
        let (c, a) = run(&scene("f32", snapped));
        let g = truth_of(&a);
        assert_eq!(g.bias_source.name(), "none");
        let rig = a.rig().unwrap();
        let setup = c.setup();
        let scene = &setup.geometry.as_ref().unwrap().scene;
        let s = sampling(&c, g, rig, true);
        let engine: EnginePipeline<f32> = EnginePipeline::new(rig);
        let poses = c.camera_path().unwrap();
        let (mut compared, mut agree, mut lit, mut shadowed) = (0usize, 0usize, 0usize, 0usize);
        for pose in poses.iter().step_by(5) {
            let mut maps = truth::ShadowMaps::new(scene);
            let (cascades, states) = truth::frame_states(&mut maps, rig, &rig.light, pose, snapped, &g.points, &s);
            let lp = LightPose::new(&rig.light, pose);
            for (j, r) in g.points.iter().enumerate().step_by(7) {
                let Some(i) = truth::reading_cascade(rig, pose, r.p) else {
                    assert_eq!(cascades[j], None);
                    continue;
                };
                assert_eq!(cascades[j], Some(i));
                // The engine's window and matrix of this frame, in f32 (world snap space: the
                // anchor is the origin).
                let w = engine.window(i, pose, DVec3::ZERO, snapped);
                let b = rig.basis(i, &lp);
                let rows = [f32s(b.x), f32s(b.y)];
                let exact = rig.window(i, &lp, snapped);
                let d = rig.light_depth(i, &lp, &exact, &c.scene);
                let range = d.far - d.near;
                let zrow = f32s(b.z / range);
                let zoff = (-d.near / range) as f32;
                let depth32 = |x: DVec3| dot32(zrow, f32s(x)) + zoff;
                // The receiver's texel: its f32 lookup.
                let p = f32s(r.p);
                let st: [f32; 2] = std::array::from_fn(|k| (dot32(rows[k], p) - w.origin[k]) / w.texel[k]);
                let n = rig.resolution as f32;
                if !(st.iter().all(|v| *v >= 0.0 && *v < n)) {
                    assert_eq!(states[j], None, "frame receiver {j}: outside the window");
                    continue;
                }
                // The texel's ray from its centre (placed by the f32 window), before every
                // triangle, along the light; its hit's depth through the f32 matrix.
                let centre: [f64; 2] =
                    std::array::from_fn(|k| w.origin[k] as f64 + (st[k].floor() as f64 + 0.5) * w.texel[k] as f64);
                let origin = b.x * centre[0] + b.y * centre[1] - b.z * 1.0e5;
                let stored = match scene.first_hit(origin, b.z, 0.0, 2.0e5) {
                    Some(h) => depth32(origin + b.z * h.t).clamp(0.0, 1.0),
                    None => f32::INFINITY,
                };
                let want = depth32(r.p) <= stored;
                let got = states[j].expect("inside the window").lit;
                compared += 1;
                agree += (got == want) as usize;
                if want {
                    lit += 1;
                } else {
                    shadowed += 1;
                }
            }
        }
        // Both answers occur (zero bias: acne shadows about half the lit ground).
        assert!(
            compared > 1500 && lit > 200 && shadowed > 200,
            "{compared} {lit} {shadowed}"
        );
        // (The pass places texel centres to 2^-20 texel, its grid key, the brute force exactly;
        // on this scene that never changes a stored f32 depth's comparison.)
        assert_eq!(agree, compared, "snapped {snapped}");
    }
}

#[test]
fn binary32_snapped_maps_flicker_where_f64_ones_are_exactly_still() {
    let (_, f64s) = run(&scene("f64", true));
    let (c, a) = run(&scene("f32", true));
    let (g64, g32) = (truth_of(&f64s), truth_of(&a));
    assert_eq!(g64.points.len(), g32.points.len());
    // The f64 snapped map is bit-identical from frame to frame; the f32 one is rebuilt each
    // frame and some receivers change state.
    assert_eq!(g64.summary.flicker_snapped, 0.0);
    assert!(g32.summary.flicker_snapped > 0.0, "{:?}", g32.summary);
    assert!(
        g32.summary.flicker_snapped < 0.01,
        "a few ulps flip few receivers: {:?}",
        g32.summary
    );
    // The pass's S5 equals a recount from every frame's states answered from scratch.
    let rig = a.rig().unwrap();
    let setup = c.setup();
    let scene = &setup.geometry.as_ref().unwrap().scene;
    let s = sampling(&c, g32, rig, true);
    let (mut steps, mut flips) = (0u64, 0u64);
    type Frame = (Vec<Option<usize>>, Vec<Option<truth::Answer>>);
    let mut prev: Option<Frame> = None;
    for pose in &c.camera_path().unwrap() {
        let mut maps = truth::ShadowMaps::new(scene);
        let now = truth::frame_states(&mut maps, rig, &rig.light, pose, true, &g32.points, &s);
        if let Some((pc, pa)) = &prev {
            for j in 0..g32.points.len() {
                if let (Some(ci), Some(cj), Some(x), Some(y)) = (pc[j], now.0[j], pa[j], now.1[j]) {
                    if ci == cj {
                        steps += 1;
                        flips += (x.lit != y.lit) as u64;
                    }
                }
            }
        }
        prev = Some(now);
    }
    assert!(flips > 0);
    assert_eq!(g32.summary.flicker_snapped, flips as f64 / steps as f64);
}
