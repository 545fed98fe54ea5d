//! Engine bias defaults of the ground-truth pass (issue 11, item 3) for Unreal, EEVEE and the
//! LearnOpenGL and Unity seed programs: each cascade's world bias against the engine's own rule
//! computed here from the cascade's texel size and light depth range, the angle terms applied
//! where the map is sampled, and the recommendation given back in the engine's own unit.

use csm_core::fitting::Window;
use csm_core::geometry::LightBasis;
use csm_core::mesh::Mesh;
use csm_core::truth::{self, Bias, BiasRule, Facing, NormalOffset, Receiver, Sampling};
use csm_core::visibility::SceneGeometry;
use csm_lab::analysis::ground_truth::GroundTruth;
use csm_lab::presets::bias::{engine_bias, BiasModel};
use csm_lab::presets::PresetName;
use csm_lab::{analyze, Analysis, AnalysisOptions, Config};
use glam::{DVec2, DVec3};

const RESOLUTION: f64 = 512.0;

fn text(preset: &str) -> String {
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

[[scene.box]]
min = [-2.3, 0.0, -8.7]
max = [1.9, 3.1, -4.4]

[shadow]
preset = "{preset}"
resolution = {RESOLUTION}

[motion]
path = "strafe"
frames = 8
step = 0.05

[analysis]
screen_scale = 0.25
ground_truth = true
"#
    )
}

fn run(preset: &str) -> Analysis {
    let c = Config::from_toml_str(&text(preset), "test.toml", None).unwrap();
    analyze(&c, &AnalysisOptions::full())
}

fn truth_of(a: &Analysis) -> &GroundTruth {
    a.ground_truth.as_ref().expect("ground truth ran")
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-300), "{what}: {a} vs {b}");
}

/// The recommendation for a cascade, given back in the engine's unit, is the setting that
/// produces `world` in that cascade.
fn own(preset: PresetName, g: &GroundTruth, i: usize, world: f64) -> f64 {
    let e = engine_bias(preset).expect("modelled");
    e.own_value(world, g.texel[i], g.ranges[i].1 - g.ranges[i].0)
}

#[test]
fn unreal_bias_is_csm_depth_bias_times_shadow_bias_times_radius_over_resolution() {
    let a = run("unreal");
    let g = truth_of(&a);
    assert!(g.engine.is_some() && g.bias.len() == 3);
    for (i, b) in g.bias.iter().enumerate() {
        // The window is the sphere's diameter over the resolution less a 4-texel border per side.
        let radius = a.cascades[i].radius;
        let inner = RESOLUTION - 8.0;
        close(g.texel[i], 2.0 * radius / inner, "texel");
        // UpdateShaderDepthBias: CSMDepthBias / z-range x radius / resolution x ShadowBias, in
        // normalised depth; times the z-range in world units.
        let zrange = g.ranges[i].1 - g.ranges[i].0;
        let normalised = 10.0 / zrange * (radius / inner) * 0.5;
        close(b.depth, normalised * zrange, "depth");
        assert_eq!((b.slope, b.normal), (0.0, 0.0));
        // The slope term: that bias x CSMSlopeScaleDepthBias x ShadowSlopeBias x min(tan, 1).
        for theta in [0.0f64, 0.3, 0.7, std::f64::consts::FRAC_PI_4, 1.2, 1.5] {
            let term = b.facing.apply(0.0, theta.cos());
            let expected = normalised * zrange * 3.0 * 0.5 * theta.tan().min(1.0);
            assert!(
                (term - expected).abs() <= 1e-12 * b.depth,
                "theta {theta}: {term} vs {expected}"
            );
        }
        // Round trip: the default world bias is ShadowBias 0.5; twice the world bias is 1.
        close(own(PresetName::Unreal, g, i, b.depth), 0.5, "own");
        close(own(PresetName::Unreal, g, i, 2.0 * b.depth), 1.0, "own x2");
    }
}

#[test]
fn eevee_bias_is_a_twentieth_of_the_lamp_bias_in_depth_over_the_lamp_clip_range() {
    let a = run("eevee");
    let g = truth_of(&a);
    assert_eq!(g.bias.len(), 4);
    for (i, b) in g.bias.iter().enumerate() {
        // The lamp's default clip range 0.05 to 40, the same for every cascade.
        close(g.ranges[i].1 - g.ranges[i].0, 40.0 - 0.05, "range");
        close(b.depth, 0.05 * 1.0 * (40.0 - 0.05), "depth");
        assert_eq!(b.facing, Facing::None);
        close(own(PresetName::Eevee, g, i, b.depth), 1.0, "own");
        close(own(PresetName::Eevee, g, i, 0.05 * 0.25 * 39.95), 0.25, "own 0.25");
    }
}

#[test]
fn learnopengl_bias_is_the_normalised_max_rule_over_each_padded_depth_range() {
    let a = run("learnopengl");
    let g = truth_of(&a);
    assert_eq!(g.bias.len(), 3);
    for (i, b) in g.bias.iter().enumerate() {
        // The padded range: the slice's light-space depth extent plus 10 on each side.
        let c = &a.cascades[i];
        let range = g.ranges[i].1 - g.ranges[i].0;
        close(range, c.light_far - c.light_near, "range");
        for cos in [1.0f64, 0.99, 0.9, 0.5, 0.0] {
            let expected = (0.05 * (1.0 - cos)).max(0.005) * range;
            let got = b.facing.apply(b.depth, cos);
            assert!(
                (got - expected).abs() <= 1e-12 * range,
                "cos {cos}: {got} vs {expected}"
            );
        }
        close(own(PresetName::LearnOpenGl, g, i, b.depth), 0.005, "own");
    }
}

#[test]
fn unity_sample_clip_space_bias_is_half_of_it_in_normalised_depth() {
    let a = run("unity-sample");
    let g = truth_of(&a);
    assert_eq!(g.bias.len(), 4);
    for (i, b) in g.bias.iter().enumerate() {
        let range = g.ranges[i].1 - g.ranges[i].0;
        // z_clip in [-1, 1] maps to [0, 1]: 0.005 of clip space is 0.0025 of the range.
        close(b.depth, 0.005 / 2.0 * range, "depth");
        assert_eq!((b.facing, b.normal), (Facing::None, 0.0));
        close(own(PresetName::UnitySample, g, i, b.depth), 0.005, "own");
    }
}

/// Every registered engine answers the bias question in its own file: a rule with a named
/// setting, a unit and a finite positive scale, or a stated reason for modelling none (the trait
/// has no default, so an engine file without an answer does not compile; this checks the answer
/// is a real one, for every engine of the registry).
#[test]
fn every_engine_gives_a_bias_rule_or_a_reason() {
    for p in PresetName::ALL {
        match p.engine().bias() {
            BiasModel::Rule(b) => {
                assert!(!b.setting.trim().is_empty() && !b.unit.trim().is_empty(), "{p}: {b:?}");
                assert!(b.scale.is_finite() && b.scale > 0.0, "{p}: scale {}", b.scale);
                assert_eq!(engine_bias(p), Some(b), "{p}");
            }
            BiasModel::NotModelled(why) => {
                assert!(why.split_whitespace().count() >= 6, "{p}: reason too short: {why:?}");
                assert!(
                    why.contains("[shadow]"),
                    "{p}: the reason says what applies instead: {why:?}"
                );
                assert_eq!(engine_bias(p), None, "{p}");
            }
        }
    }
}

#[test]
fn unity_builtin_and_dart_are_left_unmodelled() {
    assert!(engine_bias(PresetName::Unity).is_none());
    assert!(engine_bias(PresetName::Dart).is_none());
    let a = run("unity");
    let g = truth_of(&a);
    assert!(g.engine.is_none());
    // Without an engine rule the pass samples with csm-lab's recommended depth bias per cascade.
    assert_eq!(g.bias_source.name(), "recommended");
    for (b, c) in g.bias.iter().zip(&g.cascades) {
        assert_eq!((b.slope, b.normal), (0.0, 0.0));
        if let Some(chosen) = c.chosen_bias {
            assert_eq!(b.depth, chosen);
        }
    }
}

/// The ground plane y = 0 as a mesh.
fn ground(half: f64) -> SceneGeometry {
    let mut m = Mesh::default();
    m.add_ground(0.0, -half, half, -half, half);
    SceneGeometry::new(m)
}

/// Acne on the plane y = 0 lit at incidence `theta`, sampled at the corners of a few texels
/// (where point sampling needs the most bias) with the bias `bias`.
fn plane_acne(theta: f64, t: f64, bias: Bias) -> f64 {
    let scene = ground(50.0);
    let light = DVec3::new(theta.sin(), -theta.cos(), 0.0);
    let b = LightBasis::new(light);
    let w = Window {
        texel: DVec2::splat(t),
        origin_texels: DVec2::splat(-32.0),
        resolution: 64,
    };
    let inside = 1.0 - 1e-12;
    let mut points = Vec::new();
    for g in [(0.0, 0.0), (3.0, -5.0), (-10.0, 7.0)] {
        for (u, v) in [(0.0, 0.0), (inside, 0.0), (0.0, inside), (inside, inside)] {
            let q = DVec2::new(g.0 + u, g.1 + v) * t;
            let d = -(b.x.y * q.x + b.y.y * q.y) / b.z.y;
            points.push(Receiver {
                pixel: 0,
                p: b.x * q.x + b.y * q.y + b.z * d,
                n: DVec3::Y,
                triangle: 0,
            });
        }
    }
    let s = Sampling {
        bias: vec![bias],
        format: None,
        ranges: vec![(-200.0, 200.0)],
        pcf: 1,
        filter: truth::PcfFilter::Nearest,
        binary32: None,
    };
    let cascades = vec![Some(0); points.len()];
    truth::fractions(&truth::frame_zero_in(&scene, &b, &[(b, w)], &cascades, &points, &s).0).0
}

#[test]
fn the_angle_terms_reach_the_sampled_map() {
    // Point sampling on a plane at incidence theta needs up to tan(theta) T/2 (|cos a| + |sin a|),
    // at least tan(theta) T/2: half a texel's depth change.
    let t = 0.05;
    let theta = 0.9f64;
    let half = theta.tan() * t / 2.0;
    // LearnOpenGL's rule over a range of 4: the floor 0.02 is below half (acne), the angle term
    // 0.05 x 4 x (1 - cos theta) = 0.0757 is above the worst case sqrt 2 x half = 0.0446.
    let rule = BiasRule::RangeFacing {
        factor: 0.05,
        floor: 0.005,
    };
    let b = rule.for_cascade(t, 4.0);
    assert!(b.depth < half && 0.2 * (1.0 - theta.cos()) > std::f64::consts::SQRT_2 * half);
    assert_eq!(plane_acne(theta, t, b), 0.0);
    assert!(plane_acne(theta, t, Bias::depth(b.depth)) > 0.0);
    // Unreal's tangent term alone: 1 texel x tan is above the worst case, 0.4 texel below it.
    let tangent = |k: f64, cap: f64| {
        BiasRule::TexelsTangent {
            depth_texels: 0.0,
            tangent_texels: k,
            cap,
        }
        .for_cascade(t, 400.0)
    };
    assert_eq!(plane_acne(theta, t, tangent(1.0, 10.0)), 0.0);
    assert!(plane_acne(theta, t, tangent(0.4, 10.0)) > 0.0);
    // The cap binds at steep incidence: tan 1.2 = 2.57, capped to 1 texel, is below half.
    assert!(plane_acne(1.2, t, tangent(1.0, 1.0)) > 0.0);
    assert_eq!(plane_acne(1.2, t, tangent(1.0, 3.0)), 0.0);
    // The rules keep the normal offset at zero and along the normal.
    assert_eq!((b.normal, b.offset), (0.0, NormalOffset::Along));
}
