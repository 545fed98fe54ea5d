//! Ground truth (issue 11): the sampled shadow maps checked against closed forms and an
//! independent brute-force rasterisation written here.

use csm_core::cascades::LightPose;
use csm_core::fitting::Window;
use csm_core::geometry::{Aabb, LightBasis};
use csm_core::mesh::Mesh;
use csm_core::truth::{self, Bias, BiasRule, DepthFormat, NormalOffset, PcfFilter, Receiver, Sampling};
use csm_core::visibility::SceneGeometry;
use csm_lab::analysis::ground_truth::GroundTruth;
use csm_lab::{analyze, AnalysisOptions, Config};
use glam::{DVec2, DVec3};
use proptest::prelude::*;

fn load(text: &str) -> Config {
    Config::from_toml_str(text, "test.toml", None).unwrap()
}

fn err(text: &str) -> String {
    Config::from_toml_str(text, "test.toml", None).unwrap_err().to_string()
}

/// A small scene: ground, one box, a camera looking at the box's shadow.
fn scene_text(path: &str, snap: bool, extra: &str) -> String {
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
max_distance = 60.0
cascades = 2
lambda = 0.75
resolution = 256
fit = "sphere"
snap = {snap}
{extra}

[motion]
path = "{path}"
frames = 24
step = 0.05

[analysis]
screen_scale = 0.25
ground_truth = true
"#
    )
}

fn ground_truth(text: &str) -> (Config, csm_lab::Analysis) {
    let c = load(text);
    let a = analyze(&c, &AnalysisOptions::full());
    (c, a)
}

fn truth_of(a: &csm_lab::Analysis) -> &GroundTruth {
    a.ground_truth.as_ref().expect("ground truth ran")
}

/// What the pass `g` of config `c` sampled with, at PCF width `pcf` (binary64 maps).
fn pass_sampling(c: &Config, g: &GroundTruth, pcf: u32) -> Sampling {
    Sampling {
        bias: g.bias.clone(),
        format: Some(c.truth.depth_format),
        ranges: g.ranges.clone(),
        pcf,
        filter: g.filter,
        binary32: None,
    }
}

/// The ground plane y = 0 as a mesh.
fn ground(half: f64) -> SceneGeometry {
    let mut m = Mesh::default();
    m.add_ground(0.0, -half, half, -half, half);
    SceneGeometry::new(m)
}

/// The light basis turned by `beta` about the light direction.
fn turned(light: DVec3, beta: f64) -> LightBasis {
    let b = LightBasis::new(light);
    let (s, c) = beta.sin_cos();
    LightBasis {
        x: b.x * c + b.y * s,
        y: -b.x * s + b.y * c,
        z: b.z,
        vertical_fallback: false,
    }
}

/// The point of the plane y = 0 with light-space x/y `q` in basis `b`.
fn on_ground(b: &LightBasis, q: DVec2) -> DVec3 {
    let d = -(b.x.y * q.x + b.y.y * q.y) / b.z.y;
    b.x * q.x + b.y * q.y + b.z * d
}

fn sampling(bias: Bias) -> Sampling {
    Sampling {
        bias: vec![bias],
        format: Some(DepthFormat::D32F),
        ranges: vec![(-200.0, 200.0)],
        pcf: 1,
        filter: PcfFilter::Nearest,
        binary32: None,
    }
}

#[test]
fn ground_plane_depth_bias_for_zero_acne_is_the_closed_form() {
    let scene = ground(50.0);
    let t = 0.05;
    let w = Window {
        texel: DVec2::splat(t),
        origin_texels: DVec2::splat(-32.0),
        resolution: 64,
    };
    let mut checked = 0;
    for theta in [0.1f64, 0.5, 0.9, 1.2] {
        for phi in [0.3f64, 2.0] {
            let light = DVec3::new(theta.sin() * phi.cos(), -theta.cos(), theta.sin() * phi.sin());
            for beta in [0.0f64, 0.4, 1.1, 2.5, -0.7] {
                let b = turned(light, beta);
                // The four corners of three texels (the far corners just inside).
                let inside = 1.0 - 1e-12;
                let mut points = Vec::new();
                for g in [(0.0, 0.0), (3.0, -5.0), (-10.0, 7.0)] {
                    for (u, v) in [(0.0, 0.0), (inside, 0.0), (0.0, inside), (inside, inside)] {
                        let q = DVec2::new(g.0 + u, g.1 + v) * t;
                        points.push(Receiver {
                            pixel: 0,
                            p: on_ground(&b, q),
                            n: DVec3::Y,
                            triangle: 0,
                        });
                    }
                }
                let cascades = vec![Some(0); points.len()];
                let (zero, _) = truth::frame_zero_in(&scene, &b, &[(b, w)], &cascades, &points, &sampling(Bias::ZERO));
                let mut excess: Vec<f64> = zero.iter().map(|p| p.excess).collect();
                let needed = truth::smallest_bias(&mut excess, 0);
                let expected = theta.tan() * t / 2.0 * (beta.cos().abs() + beta.sin().abs());
                assert!(
                    (needed - expected).abs() <= 1e-9 * expected,
                    "theta {theta} phi {phi} beta {beta}: {needed} vs {expected}"
                );
                // With that bias, no acne; slightly less, some.
                let run = |bias: f64| {
                    let (z, _) = truth::frame_zero_in(
                        &scene,
                        &b,
                        &[(b, w)],
                        &cascades,
                        &points,
                        &Sampling {
                            format: None,
                            ..sampling(Bias::depth(bias))
                        },
                    );
                    truth::fractions(&z).0
                };
                assert_eq!(run(expected * 1.001), 0.0);
                assert!(run(expected * 0.99) > 0.0);
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 40);
}

/// The first surface along `origin + s dir` (s >= 0) among the ground (y = 0, |x|, |z| <= 60)
/// and an AABB, by slabs: the parameter s, or infinity.
fn first_surface(origin: DVec3, dir: DVec3, b: &Aabb) -> f64 {
    let mut best = f64::INFINITY;
    if dir.y != 0.0 {
        let s = -origin.y / dir.y;
        let hit = origin + dir * s;
        if s >= 0.0 && hit.x.abs() <= 60.0 && hit.z.abs() <= 60.0 {
            best = s;
        }
    }
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        let (o, d, a, c) = (origin[k], dir[k], b.min[k], b.max[k]);
        if d == 0.0 {
            if o < a || o > c {
                return best;
            }
            continue;
        }
        let (t0, t1) = ((a - o) / d, (c - o) / d);
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    if lo <= hi {
        best = best.min(lo);
    }
    best
}

/// The texel map of the ground and the box seen along the light, by brute force: texel
/// `(i, j)`'s centre's first surface (texel indices relative to the window's first texel; any
/// index, inside the window or not).
struct BruteMap {
    b: LightBasis,
    w: Window,
    bx: Aabb,
}

impl BruteMap {
    const START: f64 = -500.0;

    fn depth(&self, i: i64, j: i64) -> f64 {
        let c = (self.w.origin_texels + DVec2::new(i as f64 + 0.5, j as f64 + 0.5)) * self.w.texel;
        let origin = self.b.x * c.x + self.b.y * c.y + self.b.z * Self::START;
        Self::START + first_surface(origin, self.b.z, &self.bx)
    }

    /// A comparison sampler's answer at `p` with depth bias `bias`: `k x k` taps one texel apart
    /// around `p`, each the 2x2 bilinear weights of its compare results (bilinear) or its own
    /// texel's result (nearest), lit when the weighted share is at least 1/2.
    fn lit(&self, p: DVec3, bias: f64, k: i64, bilinear: bool) -> bool {
        let s = DVec2::new(self.b.x.dot(p), self.b.y.dot(p)) / self.w.texel - self.w.origin_texels;
        let z = self.b.z.dot(p);
        let pass = |i: i64, j: i64| if z <= self.depth(i, j) + bias { 1.0 } else { 0.0 };
        let h = k / 2;
        let mut sum = 0.0;
        for dy in -h..=h {
            for dx in -h..=h {
                let t = s + DVec2::new(dx as f64, dy as f64);
                sum += if bilinear {
                    let (fx, fy) = ((t.x - 0.5).fract_gl(), (t.y - 0.5).fract_gl());
                    let (i, j) = ((t.x - 0.5).floor() as i64, (t.y - 0.5).floor() as i64);
                    (1.0 - fx) * (1.0 - fy) * pass(i, j)
                        + fx * (1.0 - fy) * pass(i + 1, j)
                        + (1.0 - fx) * fy * pass(i, j + 1)
                        + fx * fy * pass(i + 1, j + 1)
                } else {
                    pass(t.x.floor() as i64, t.y.floor() as i64)
                };
            }
        }
        sum / (k * k) as f64 >= 0.5
    }
}

trait FractGl {
    fn fract_gl(self) -> f64;
}

impl FractGl for f64 {
    /// `x - floor(x)` (GLSL's fract; Rust's `fract` keeps the sign).
    fn fract_gl(self) -> f64 {
        self - self.floor()
    }
}

/// csm-lab's lookups equal a brute-force comparison sampler over a brute-force rasterisation of
/// the whole map (the ground and the box, every texel's first surface by slabs), for nearest and
/// bilinear filtering at PCF 1 and 3.
#[test]
fn a_box_on_the_ground_equals_a_brute_force_rasterisation_of_the_whole_map() {
    for (filter, pcf) in [("nearest", 1), ("bilinear", 1), ("nearest", 3), ("bilinear", 3)] {
        let text = scene_text(
            "strafe",
            true,
            &format!("depth_bias = 0.01\npcf_filter = \"{filter}\"\npcf = {pcf}\ndepth_format = \"d32f\""),
        )
        .replace("cascades = 2", "cascades = 1")
        .replace("resolution = 256", "resolution = 64");
        let (c, a) = ground_truth(&text);
        let g = truth_of(&a);
        assert_eq!(g.filter.name(), filter);
        let rig = a.rig().unwrap();
        let pose = c.camera.pose();
        let lp = LightPose::new(&rig.light, &pose);
        let brute = BruteMap {
            b: rig.light,
            w: rig.window(0, &lp, true),
            bx: Aabb::new(DVec3::new(-2.3, 0.0, -8.7), DVec3::new(1.9, 3.1, -4.4)),
        };
        let (near, far) = g.ranges[0];
        let mut compared = 0;
        let (mut lit, mut shadowed) = (0, 0);
        for (r, z) in g.points.iter().zip(&g.zero) {
            let Some(map_lit) = z.map_lit else { continue };
            // d32f stores each depth rounded to binary32 over the light depth range: the same
            // rounding applied to the brute-force depths would move a comparison by at most
            // 2^-24 of the range; skip the receivers that close to a decision.
            let expected = brute.lit(r.p, 0.01, pcf, filter == "bilinear");
            let margin = 4.0 * (far - near) * (2.0f64).powi(-24);
            if brute.lit(r.p, 0.01 + margin, pcf, filter == "bilinear")
                != brute.lit(r.p, 0.01 - margin, pcf, filter == "bilinear")
            {
                continue;
            }
            assert_eq!(map_lit, expected, "{filter} pcf {pcf}: receiver at {:?}", r.p);
            compared += 1;
            if expected {
                lit += 1;
            } else {
                shadowed += 1;
            }
        }
        assert!(
            compared > 1000 && lit > 100 && shadowed > 100,
            "{filter} pcf {pcf}: {compared} {lit} {shadowed}"
        );
    }
}

#[test]
fn snapped_sphere_fits_never_flicker_and_unsnapped_ones_do_with_a_shadow_edge_in_view() {
    for path in ["strafe", "dolly", "yaw", "pitch", "orbit"] {
        let (_, a) = ground_truth(&scene_text(path, true, "depth_bias = 0.05"));
        let g = truth_of(&a);
        assert_eq!(g.summary.flicker_snapped, 0.0, "{path}");
        assert!(g.snapped.steps.iter().sum::<u32>() > 1000, "{path}: steps counted");
        assert!(
            g.summary.flicker_unsnapped > 0.0,
            "{path}: unsnapped S5 {}",
            g.summary.flicker_unsnapped
        );
        // Flip images agree with the flip counts.
        let flipped = g
            .pictures_unsnapped
            .flips
            .flips
            .iter()
            .flatten()
            .filter(|&&x| x > 0.0)
            .count();
        assert!(flipped > 0, "{path}");
    }
}

#[test]
fn the_exact_answer_leaves_the_surface_by_epsilon_and_sees_the_box() {
    let mut m = Mesh::default();
    m.add_ground(0.0, -50.0, 50.0, -50.0, 50.0);
    let bx = Aabb::new(DVec3::new(-1.0, 0.0, -1.0), DVec3::new(1.0, 2.0, 1.0));
    m.add_box(&bx);
    let scene = SceneGeometry::new(m);
    let eps = truth::epsilon(&scene);
    assert_eq!(eps, truth::EPSILON_REL * 50.0);
    let light = DVec3::new(0.0, -1.0, -1.0).normalize();
    let at = |p: DVec3, n: DVec3| Receiver {
        pixel: 0,
        p,
        n,
        triangle: 0,
    };
    // Open ground, the box's top and its lit side: no self-hit.
    assert_eq!(
        truth::occluder(&scene, light, &at(DVec3::new(10.0, 0.0, 10.0), DVec3::Y), eps),
        None
    );
    assert_eq!(
        truth::occluder(&scene, light, &at(DVec3::new(0.3, 2.0, 0.2), DVec3::Y), eps),
        None
    );
    assert_eq!(
        truth::occluder(&scene, light, &at(DVec3::new(0.3, 1.0, 1.0), DVec3::Z), eps),
        None
    );
    // Behind the box (light travels toward -z): the ray back toward +z meets the box's face
    // z = -1 after (|z| - 1) * sqrt 2, from 0.5 above the ground.
    let d = truth::occluder(&scene, light, &at(DVec3::new(0.0, 0.0, -1.5), DVec3::Y), eps).unwrap();
    assert!((d - 0.5 * 2f64.sqrt()).abs() < 1e-3, "{d}");
    // Just beyond the shadow's far end (2 units past the face): lit.
    assert_eq!(
        truth::occluder(&scene, light, &at(DVec3::new(0.0, 0.0, -3.01), DVec3::Y), eps),
        None
    );
}

/// A plane through the origin with unit normal `n` (turned toward the light), as a big quad.
fn tilted_plane(n: DVec3) -> SceneGeometry {
    let u = n.cross(DVec3::X).normalize();
    let v = n.cross(u);
    let c = |a: f64, b: f64| u * a + v * b;
    let mut m = Mesh::default();
    m.push([c(-40.0, -40.0), c(40.0, -40.0), c(40.0, 40.0)]);
    m.push([c(-40.0, -40.0), c(40.0, 40.0), c(-40.0, 40.0)]);
    SceneGeometry::new(m)
}

fn plane_points(n: DVec3, count: usize) -> Vec<Receiver> {
    let u = n.cross(DVec3::X).normalize();
    let v = n.cross(u);
    // A low-discrepancy set over 10 x 10 units of the plane.
    (0..count)
        .map(|k| {
            let a = (k as f64 * 0.618_033_988_749_894_9).fract() * 10.0 - 5.0;
            let b = (k as f64 * 0.754_877_666_246_692_7).fract() * 10.0 - 5.0;
            Receiver {
                pixel: k,
                p: u * a + v * b,
                n,
                triangle: 0,
            }
        })
        .collect()
}

#[test]
fn zero_bias_on_a_lit_tilted_plane_gives_acne_on_about_half_of_its_points() {
    let light = DVec3::new(-0.4, -1.0, -0.3).normalize();
    for n in [
        DVec3::new(0.3, 1.0, 0.2),
        DVec3::new(-0.5, 0.8, 0.4),
        DVec3::new(0.0, 0.2, 1.0),
    ] {
        let n = n.normalize();
        assert!(n.dot(-light) > 0.0);
        let scene = tilted_plane(n);
        let b = LightBasis::new(light);
        let w = Window::centred(DVec2::ZERO, DVec2::splat(30.0), 512, None);
        let points = plane_points(n, 4000);
        let (zero, _) = truth::frame_zero_in(
            &scene,
            &b,
            &[(b, w)],
            &vec![Some(0); points.len()],
            &points,
            &sampling(Bias::ZERO),
        );
        let (acne, leak) = truth::fractions(&zero);
        assert!((acne - 0.5).abs() < 0.05, "normal {n}: acne {acne}");
        assert_eq!(leak, 0.0);
        // PCF 3 and 5 on the same plane vote the same way about half the time too; a bias of
        // the closed form's worst case (slope bias 1) removes all of it.
        let no_acne = Sampling {
            bias: vec![Bias {
                slope: 1.0,
                ..Bias::ZERO
            }],
            format: None,
            ..sampling(Bias::ZERO)
        };
        let (z, _) = truth::frame_zero_in(&scene, &b, &[(b, w)], &vec![Some(0); points.len()], &points, &no_acne);
        assert_eq!(truth::fractions(&z).0, 0.0, "normal {n}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

    #[test]
    fn more_bias_never_increases_acne(
        b1 in 0.0f64..0.2, db in 0.0f64..0.2, s1 in 0.0f64..1.5, ds in 0.0f64..1.5,
        normal in 0.0f64..2.0, pcf in prop::sample::select(vec![1u32, 3, 5]),
        fmt in prop::sample::select(DepthFormat::ALL.to_vec()),
        filter in prop::sample::select(PcfFilter::ALL.to_vec()),
    ) {
        let light = DVec3::new(-0.4, -1.0, -0.3).normalize();
        let n = DVec3::new(0.3, 1.0, 0.2).normalize();
        let scene = tilted_plane(n);
        let b = LightBasis::new(light);
        let w = Window::centred(DVec2::ZERO, DVec2::splat(30.0), 256, None);
        let points = plane_points(n, 600);
        let cascades = vec![Some(0); points.len()];
        let acne = |depth: f64, slope: f64| {
            let s = Sampling {
                bias: vec![Bias { depth, slope, normal, ..Bias::ZERO }],
                format: Some(fmt),
                ranges: vec![(-30.0, 30.0)],
                pcf,
                filter,
                binary32: None,
            };
            truth::fractions(&truth::frame_zero_in(&scene, &b, &[(b, w)], &cascades, &points, &s).0).0
        };
        let (lo, hi) = (acne(b1, s1), acne(b1 + db, s1 + ds));
        prop_assert!(hi <= lo, "acne {lo} at ({b1}, {s1}), {hi} at ({}, {})", b1 + db, s1 + ds);
    }
}

#[test]
fn bad_bias_keys_name_the_key_and_what_is_allowed() {
    let base = scene_text("strafe", true, "");
    for (line, key, allowed) in [
        ("depth_bias = -0.1", "shadow.depth_bias", ">= 0"),
        ("slope_bias = -1.0", "shadow.slope_bias", ">= 0"),
        ("normal_bias = -2.0", "shadow.normal_bias", ">= 0"),
        (
            "depth_format = \"d15\"",
            "shadow.depth_format",
            "\"d16\", \"d24\", \"d32f\"",
        ),
        ("pcf = 2", "shadow.pcf", "1, 3 or 5"),
    ] {
        let text = base.replace("snap = true", &format!("snap = true\n{line}"));
        let e = err(&text);
        assert!(e.contains(key) && e.contains(allowed), "{line}: {e}");
    }
    // Ground truth needs geometry.
    let text = base
        .replace("ground = 0.0\n", "")
        .replace("[[scene.box]]\nmin = [-2.3, 0.0, -8.7]\nmax = [1.9, 3.1, -4.4]\n", "");
    let e = err(&text);
    assert!(e.contains("analysis.ground_truth"), "{e}");
}

#[test]
fn depth_formats_quantise_to_their_step() {
    let (near, far) = (10.0, 110.0);
    for f in DepthFormat::ALL {
        let step = f.step(far - near);
        for k in 0..200 {
            let d = near + (k as f64 * 0.379_1).fract() * (far - near);
            let q = f.quantise(d, near, far);
            assert!((q - d).abs() <= 0.5 * step * (1.0 + 1e-9), "{f:?} {d} -> {q}");
        }
        assert_eq!(f.quantise(f64::INFINITY, near, far), f64::INFINITY);
        assert_eq!(DepthFormat::from_name(f.name()), Some(f));
    }
    assert_eq!(DepthFormat::D16.step(65_535.0), 1.0);
}

#[test]
fn engine_bias_rules_convert_per_cascade_and_back() {
    // Godot: bias / 100 x the depth range.
    let godot = BiasRule::RangeFraction {
        fraction: 0.1 / 100.0,
        normal_texels: 2.0,
        offset: NormalOffset::Lateral,
    };
    let b = godot.for_cascade(0.05, 250.0);
    assert!((b.depth - 0.25).abs() < 1e-15);
    assert!((godot.depth_in_own_units(0.25, 0.05, 250.0) - 0.001).abs() < 1e-15);
    // Unity: texels.
    let unity = BiasRule::Texels {
        depth_texels: 1.0,
        normal_texels: 1.0,
    };
    assert_eq!(unity.for_cascade(0.04, 10.0).depth, 0.04);
    assert_eq!(unity.depth_in_own_units(0.1, 0.04, 10.0), 2.5);
    // The preset's default reaches the analysis: Godot's bias is 0.1 % of each cascade's range.
    let text = scene_text("strafe", true, "").replace("[shadow]", "[shadow]\npreset = \"godot\"");
    let (_, a) = ground_truth(&text);
    let g = truth_of(&a);
    for (i, b) in g.bias.iter().enumerate() {
        let range = g.ranges[i].1 - g.ranges[i].0;
        assert!((b.depth - 0.001 * range).abs() <= 1e-12 * range, "cascade {i}");
        assert_eq!(b.normal, 2.0);
        assert_eq!(b.offset, NormalOffset::Lateral);
    }
    assert!(g.engine.is_some());
}

#[test]
fn sweeps_leave_the_pass_out_and_analyze_without_it_writes_what_it_did() {
    let (c, a) = ground_truth(&scene_text("strafe", true, ""));
    let quick = analyze(&c, &AnalysisOptions::summary_only());
    assert!(quick.ground_truth.is_none() && quick.summary.truth.is_none());
    assert!(a.summary.truth.is_some());
    // The summary without the pass equals the one with it, but for the truth metrics.
    let mut s = a.summary.clone();
    s.truth = None;
    let mut off = c.clone();
    off.truth.enabled = false;
    assert_eq!(analyze(&off, &AnalysisOptions::full()).summary, s);
}

#[test]
fn analyze_ground_truth_writes_bias_csv_and_the_recommendation() {
    use std::process::Command;
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("scene.toml");
    let text = scene_text("strafe", true, "").replace("ground_truth = true\n", "");
    std::fs::write(&cfg, &text).unwrap();
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_csm-lab"))
            .args([
                "analyze",
                cfg.to_str().unwrap(),
                "--quiet",
                "--out",
                out.to_str().unwrap(),
            ])
            .args(extra)
            .output()
            .unwrap()
    };
    // Without the flag: no bias.csv, no pictures, no truth column.
    let plain = run(&[]);
    assert!(plain.status.success());
    assert!(!out.join("bias.csv").exists());
    assert!(!out.join("shadow.png").exists() && !out.join("shadow.apng").exists());
    let cascades = std::fs::read_to_string(out.join("cascades.csv")).unwrap();
    assert!(!cascades.contains("acne_fraction"));
    let summary_of =
        || -> serde_json::Value { serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap() };
    // --raw-bias: today's zero-bias run, acne on about half of the lit surfaces.
    let raw = run(&["--ground-truth", "--raw-bias"]);
    assert!(raw.status.success(), "{}", String::from_utf8_lossy(&raw.stderr));
    assert!(String::from_utf8_lossy(&raw.stdout).contains("bias_source = none"));
    let s = summary_of();
    assert_eq!(s["bias_source"], "none");
    assert!(
        s["acne_fraction"].as_f64().unwrap() > 0.3,
        "zero bias: acne on lit surfaces {s}"
    );
    let o = run(&["--ground-truth"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("recommended depth bias (D32F"), "{stdout}");
    assert!(stdout.contains("bias_source = recommended"), "{stdout}");
    let bias = std::fs::read_to_string(out.join("bias.csv")).unwrap();
    assert!(bias.starts_with("cascade,points,texel_size,"), "{bias}");
    assert_eq!(bias.lines().count(), 3, "header and two cascades");
    let s = summary_of();
    // No bias set: the pass samples with csm-lab's recommended bias and says so.
    assert_eq!(s["bias_source"], "recommended");
    assert_eq!(s["pcf_filter"], "bilinear");
    assert!(s["acne_fraction"].as_f64().unwrap() <= 0.001, "{s}");
    assert!(s["edge_error_fraction"].as_f64().unwrap() > 0.0, "{s}");
    assert_eq!(s["flicker_snapped"].as_f64(), Some(0.0));
    let split = s["flicker_edge_unsnapped"].as_f64().unwrap() + s["flicker_acne_unsnapped"].as_f64().unwrap();
    assert!((split - s["flicker_unsnapped"].as_f64().unwrap()).abs() < 1e-12, "{s}");
    // --raw-bias with a bias key is refused, naming the flag (exit 2).
    std::fs::write(
        &cfg,
        text.replace("fit = \"sphere\"", "fit = \"sphere\"\ndepth_bias = 0.1"),
    )
    .unwrap();
    let both = run(&["--ground-truth", "--raw-bias"]);
    assert_eq!(both.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&both.stderr).contains("--raw-bias"));
    std::fs::write(&cfg, &text).unwrap();
    run(&["--ground-truth"]);
    let cascades = std::fs::read_to_string(out.join("cascades.csv")).unwrap();
    assert!(cascades
        .lines()
        .next()
        .unwrap()
        .contains("bias_needed,slope_bias_needed,peter_pan"));
    // The pictures of the pass: two panels each, decoded; the animation has the kept frames.
    for name in ["shadow.png", "flicker.png", "shadow.apng"] {
        let bytes = std::fs::read(out.join(name)).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = decoder.read_info().unwrap();
        let info = reader.info();
        assert!(info.width >= 960, "{name}: two panels side by side ({} px)", info.width);
        if name == "shadow.apng" {
            let frames = info.animation_control().expect("an animated PNG").num_frames;
            assert!((2..=48).contains(&frames), "{name}: {frames} frames");
        } else {
            assert!(info.animation_control().is_none(), "{name} is a still");
        }
    }

    // Without geometry the flag is refused, naming it (exit 2).
    let bare = text
        .replace("ground = 0.0\n", "")
        .replace("[[scene.box]]\nmin = [-2.3, 0.0, -8.7]\nmax = [1.9, 3.1, -4.4]\n", "");
    std::fs::write(&cfg, bare).unwrap();
    let e = run(&["--ground-truth"]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("--ground-truth"));
}

#[test]
fn flicker_points_pair_the_proxies_with_s5_per_snap_mode() {
    let c = load(&scene_text("yaw", true, "depth_bias = 0.05"));
    let pts = csm_lab::analysis::ground_truth::flicker_points(&[c.clone(), c.with_resolution(512).unwrap()]);
    assert_eq!(pts.len(), 4);
    for p in &pts {
        assert!(p.s4.is_some());
        if p.snapped {
            assert_eq!(p.s5, 0.0);
        } else {
            assert!(p.s3 > 0.0 && p.s5 > 0.0, "{p:?}");
        }
    }
}

/// Each receiver's `needed` bias is where its lookup turns lit: re-running the lookups with a
/// depth bias `b` (exact depths) lights exactly the receivers whose `needed` is at most `b`,
/// for both filters and PCF 1, 3 and 5.
#[test]
fn a_receivers_needed_bias_is_where_its_lookup_turns_lit() {
    let light = DVec3::new(-0.4, -1.0, -0.3).normalize();
    let n = DVec3::new(0.3, 1.0, 0.2).normalize();
    let scene = tilted_plane(n);
    let b = LightBasis::new(light);
    let w = Window::centred(DVec2::ZERO, DVec2::splat(30.0), 256, None);
    let points = plane_points(n, 1500);
    let cascades = vec![Some(0); points.len()];
    for filter in PcfFilter::ALL {
        for pcf in [1u32, 3, 5] {
            let s = |depth: f64| Sampling {
                bias: vec![Bias::depth(depth)],
                format: None,
                ranges: vec![(-30.0, 30.0)],
                pcf,
                filter,
                binary32: None,
            };
            let (zero, _) = truth::frame_zero_in(&scene, &b, &[(b, w)], &cascades, &points, &s(0.0));
            let needed: Vec<f64> = zero
                .iter()
                .map(|p| p.needed.expect("a lit plane can only be acne"))
                .collect();
            let mut sorted = needed.clone();
            sorted.sort_by(f64::total_cmp);
            let (mut lit_checked, mut dark_checked) = (0, 0);
            for q in [0.1, 0.3, 0.5, 0.7, 0.9, 0.99] {
                let bias = sorted[(q * sorted.len() as f64) as usize];
                let (z, _) = truth::frame_zero_in(&scene, &b, &[(b, w)], &cascades, &points, &s(bias));
                for (p, need) in z.iter().zip(&needed) {
                    if (need - bias).abs() <= 1e-9 * bias.max(1e-6) {
                        continue;
                    }
                    assert_eq!(
                        p.map_lit,
                        Some(*need <= bias),
                        "{filter:?} pcf {pcf}: needed {need}, bias {bias}"
                    );
                    if *need <= bias {
                        lit_checked += 1;
                    } else {
                        dark_checked += 1;
                    }
                    // A lit plane: a wrong answer is acne, never an edge or a leak.
                    assert_ne!(p.error(), Some(truth::ErrorKind::Edge));
                }
            }
            assert!(
                lit_checked > 1000 && dark_checked > 1000,
                "{lit_checked} {dark_checked}"
            );
        }
    }
}

/// A cascade with fewer than MIN_POINTS receivers has no fractions and no bias needed (n/a),
/// one with MIN_POINTS has them.
#[test]
fn too_few_receivers_give_n_a_instead_of_a_number() {
    let light = DVec3::new(-0.4, -1.0, -0.3).normalize();
    let n = DVec3::new(0.3, 1.0, 0.2).normalize();
    let scene = tilted_plane(n);
    let b = LightBasis::new(light);
    let w = Window::centred(DVec2::ZERO, DVec2::splat(30.0), 256, None);
    let s = Sampling {
        ranges: vec![(-30.0, 30.0)],
        ..sampling(Bias::ZERO)
    };
    for (count, known) in [(truth::MIN_POINTS - 1, false), (truth::MIN_POINTS, true)] {
        let points = plane_points(n, count);
        let (zero, _) = truth::frame_zero_in(&scene, &b, &[(b, w)], &vec![Some(0); count], &points, &s);
        let c = &truth::cascade_truth(&zero, 1, &s)[0];
        assert_eq!(c.points, count);
        for x in [
            c.acne_fraction,
            c.edge_error_fraction,
            c.leak_fraction,
            c.chosen_bias,
            c.slope_bias,
        ] {
            assert_eq!(x.is_some(), known, "{count} points: {c:?}");
        }
    }
}

/// The default scene with no bias set: the pass samples with csm-lab's recommended bias per
/// cascade and says so; acne stays within 0.1 % in every cascade (also in D16, whose step the
/// margin must cover, and with one configured bias equal to the largest cascade's), the edge
/// error is reported apart, S5 splits into its edge and acne parts, and a cascade without
/// enough receivers is n/a in cascades.csv.
#[test]
fn the_recommended_bias_keeps_its_promise_on_the_default_scene() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/configs/default.toml")).unwrap();
    let mut c = Config::from_toml_str(&text, "default.toml", None).unwrap();
    c.truth.enabled = true;
    let a = analyze(&c, &AnalysisOptions::full());
    let g = truth_of(&a);
    assert_eq!(g.bias_source.name(), "recommended");
    assert_eq!(g.filter, PcfFilter::Bilinear);
    let s = g.summary;
    assert!(s.acne_fraction <= 0.001, "{s:?}");
    assert!(s.edge_error_fraction > 0.0, "{s:?}");
    assert!((s.flicker_edge_unsnapped + s.flicker_acne_unsnapped - s.flicker_unsnapped).abs() < 1e-12);
    assert_eq!(s.flicker_snapped, 0.0);
    let mut largest: f64 = 0.0;
    let mut with_bias = 0;
    for (i, ct) in g.cascades.iter().enumerate() {
        // The pass sampled each cascade with its own bias_needed.
        if let Some(b) = ct.chosen_bias {
            assert_eq!(g.bias[i].depth, b);
            largest = largest.max(b);
            with_bias += 1;
            // Counted again from the receivers' answers.
            let mine: Vec<_> = g
                .zero
                .iter()
                .filter(|p| p.cascade == Some(i) && p.map_lit.is_some())
                .collect();
            let acne = mine
                .iter()
                .filter(|p| p.error() == Some(truth::ErrorKind::Acne))
                .count();
            assert!(
                acne as f64 <= 0.001 * mine.len() as f64,
                "cascade {i}: {acne} of {}",
                mine.len()
            );
            assert_eq!(ct.acne_fraction, Some(acne as f64 / mine.len() as f64));
        } else {
            assert!(ct.points < truth::MIN_POINTS);
            let fields = csm_lab::metric::cascade_fields(&a.cascades[i]).unwrap();
            let cols = csm_lab::metric::cascade_columns(true, false, true, false, false, false);
            let at = |name: &str| fields[cols.iter().position(|c| *c == name).unwrap()].clone();
            assert_eq!(at("acne_fraction"), "n/a");
            assert_eq!(at("bias_needed"), "n/a");
        }
    }
    assert!(with_bias >= 3, "{with_bias} cascades with enough receivers");
    let per_cascade_acne = |c: &Config| -> Vec<Option<f64>> {
        // Acne is a frame-0 count: two frames of the path suffice.
        let mut c = c.clone();
        c.motion.frames = 2;
        let a = analyze(&c, &AnalysisOptions::full());
        truth_of(&a).cascades.iter().map(|x| x.acne_fraction).collect()
    };
    // One configured depth bias, the largest cascade's: no cascade above 0.1 %.
    let mut one = c.clone();
    one.truth.depth_bias = Some(largest);
    for (i, x) in per_cascade_acne(&one).into_iter().enumerate() {
        assert!(x.is_none_or(|x| x <= 0.001), "cascade {i}: {x:?}");
    }
    // D16: the margin's format step covers the coarse depths.
    let mut d16 = c.clone();
    d16.truth.depth_format = DepthFormat::D16;
    for (i, x) in per_cascade_acne(&d16).into_iter().enumerate() {
        assert!(x.is_none_or(|x| x <= 0.001), "d16 cascade {i}: {x:?}");
    }
}

/// The walk's S5 split equals a brute force that answers every frame from scratch (a new map
/// cache per frame, no reuse of unchanged keys) and classifies each change itself.
#[test]
fn the_s5_split_equals_answering_every_frame_from_scratch() {
    let (c, a) = ground_truth(&scene_text("yaw", false, "pcf = 3"));
    let g = truth_of(&a);
    let rig = a.rig().unwrap();
    let setup = c.setup();
    let scene = &setup.geometry.as_ref().unwrap().scene;
    let s = pass_sampling(&c, g, 3);
    let poses: Vec<_> = c.camera_path().unwrap();
    let (mut steps, mut edge, mut acne) = (0u64, 0u64, 0u64);
    type Frame = (Vec<Option<usize>>, Vec<Option<truth::Answer>>);
    let mut prev: Option<Frame> = None;
    for pose in &poses {
        let mut maps = truth::ShadowMaps::new(scene);
        let now = truth::frame_states(&mut maps, rig, &rig.light, pose, false, &g.points, &s);
        if let Some((pc, pa)) = &prev {
            for j in 0..g.points.len() {
                if let (Some(ci), Some(cj), Some(x), Some(y)) = (pc[j], now.0[j], pa[j], now.1[j]) {
                    if ci != cj {
                        continue;
                    }
                    steps += 1;
                    if x.lit != y.lit {
                        if x.own_only && y.own_only {
                            acne += 1;
                        } else {
                            edge += 1;
                        }
                    }
                }
            }
        }
        prev = Some(now);
    }
    assert!(steps > 1000 && edge > 0, "{steps} {edge} {acne}");
    assert_eq!(g.unsnapped.steps.iter().map(|&x| x as u64).sum::<u64>(), steps);
    assert_eq!(g.summary.flicker_edge_unsnapped, edge as f64 / steps as f64);
    assert_eq!(g.summary.flicker_acne_unsnapped, acne as f64 / steps as f64);
    assert_eq!(g.summary.flicker_unsnapped, (edge + acne) as f64 / steps as f64);
}

/// The walk answers a receiver from its triangle's plane wherever the light-space cover owns
/// every texel it can read (`truth::PlaneLookup`), and keeps the answer of a receiver whose
/// key did not change: every frame's answers equal answering that frame from scratch with
/// every texel traced (fresh maps per frame), in both snap modes, on paths that strafe and
/// turn, with the recommended, configured, engine (Godot's lateral normal offset) and no bias,
/// PCF 1, 3 and 5, both filters and every depth format.
#[test]
fn every_frame_of_the_walk_equals_tracing_it_from_scratch() {
    let cases = [
        ("yaw", true, ""),
        (
            "strafe",
            false,
            "pcf = 3\npcf_filter = \"nearest\"\ndepth_format = \"d16\"\ndepth_bias = 0.02\nslope_bias = 1.0\nnormal_bias = 0.5",
        ),
        ("yaw", false, "pcf = 5\ndepth_format = \"d24\"\nbias = \"none\""),
        ("strafe", true, "preset = \"godot\""),
        ("dolly", false, "depth_bias = 0.004\npcf_filter = \"bilinear\""),
    ];
    for (path, snap, extra) in cases {
        let text = scene_text(path, snap, "").replace("[shadow]", &format!("[shadow]\n{extra}"));
        let (c, a) = ground_truth(&text);
        let g = truth_of(&a);
        let rig = a.rig().unwrap();
        let setup = c.setup();
        let scene = &setup.geometry.as_ref().unwrap().scene;
        let s = pass_sampling(&c, g, c.truth.pcf);
        let poses: Vec<_> = c.camera_path().unwrap();
        // Both snap modes walked in one pass (as the pass walks them), each frame of each
        // compared with tracing it from scratch.
        // Both modes' walks, counting texel reads or not.
        let walks = |counting: bool, on: &mut truth::OnWalkFrame<'_>| {
            truth::flicker_walks(
                vec![
                    (truth::ShadowMaps::new(scene).counting(counting), true),
                    (truth::ShadowMaps::new(scene).counting(counting), false),
                ],
                rig,
                &rig.light,
                poses.iter().copied(),
                &g.points,
                &s,
                csm_core::walk::Cadence::EVERY_FRAME,
                on,
            )
        };
        let mut walked: [Vec<Vec<Option<truth::Answer>>>; 2] = [Vec::new(), Vec::new()];
        let flicker = walks(true, &mut |w, _, states| walked[w].push(states.to_vec()));
        // Without texel counts (a sweep's rows) the walk steps the receivers through blocks
        // of frames: every frame's states and every count are the frame-by-frame walk's.
        let mut blocks: [Vec<Vec<Option<truth::Answer>>>; 2] = [Vec::new(), Vec::new()];
        let in_blocks = walks(false, &mut |w, t, states| {
            assert_eq!(t, blocks[w].len(), "frames in order");
            blocks[w].push(states.to_vec())
        });
        assert!(poses.len() > 17, "{} frames: more than one block", poses.len());
        for w in 0..2 {
            assert!(
                blocks[w] == walked[w],
                "{path} {extra:?} walk {w}: a frame's states differ in blocks"
            );
            let (a, b) = (&in_blocks[w], &flicker[w]);
            assert_eq!(
                (a.s5, a.s5_edge, a.s5_acne, &a.flips, &a.steps, a.frames),
                (b.s5, b.s5_edge, b.s5_acne, &b.flips, &b.steps, b.frames),
                "{path} {extra:?} walk {w}"
            );
            assert_eq!((&a.update_flips, &a.update_steps), (&b.update_flips, &b.update_steps));
            assert_eq!(a.stats, truth::CacheStats::default(), "no counts without counting");
        }
        for (w, snapped) in [true, false].into_iter().enumerate() {
            assert_eq!(walked[w].len(), poses.len());
            let mut answered = 0;
            let mut prev: Option<Vec<Option<usize>>> = None;
            let mut steps = 0u64;
            for (t, pose) in poses.iter().enumerate() {
                let mut maps = truth::ShadowMaps::new(scene).counting(false);
                let (cascades, fresh) = truth::frame_states(&mut maps, rig, &rig.light, pose, snapped, &g.points, &s);
                answered += fresh.iter().flatten().count();
                assert!(
                    walked[w][t] == fresh,
                    "{path} {extra:?} snapped {snapped}: frame {t} differs"
                );
                if let Some(pc) = &prev {
                    let pa = &walked[w][t - 1];
                    steps += (0..g.points.len())
                        .filter(|&j| pc[j].is_some() && pc[j] == cascades[j] && pa[j].is_some() && fresh[j].is_some())
                        .count() as u64;
                }
                prev = Some(cascades);
            }
            assert!(answered > 1000 * poses.len(), "{path} {extra:?}: {answered} answers");
            assert_eq!(
                flicker[w].steps.iter().map(|&x| x as u64).sum::<u64>(),
                steps,
                "{path} {extra:?}"
            );
            // One walk alone gives the same.
            let alone = truth::flicker_cached(
                truth::ShadowMaps::new(scene),
                rig,
                &rig.light,
                poses.iter().copied(),
                snapped,
                &g.points,
                &s,
                csm_core::walk::Cadence::EVERY_FRAME,
                &mut |_, _| {},
            );
            assert_eq!(alone, flicker[w], "{path} {extra:?} snapped {snapped}");
        }
    }
}

/// The receivers and exact answers a pass reads are cast once per view and light and shared
/// by every setting that has them (a sweep's rows): the cached copy equals casting them again,
/// a second setting gets the same copy, and frame 0 read from it equals frame 0 casting its
/// own exact answers.
#[test]
fn cached_receivers_and_exact_answers_equal_casting_them_again() {
    let (c, a) = ground_truth(&scene_text("strafe", false, ""));
    let g = truth_of(&a);
    let rig = a.rig().unwrap();
    let setup = c.setup();
    let scene = &setup.geometry.as_ref().unwrap().scene;
    let vis = setup.visibility().unwrap();
    let cached = truth::exact_of(scene, &vis, rig.light.z);
    let points = truth::receivers(scene, &vis);
    assert!(points.len() > 1000, "{} receivers", points.len());
    assert_eq!(cached.points, points);
    assert_eq!(g.points, points);
    let eps = truth::epsilon(scene);
    let occluders: Vec<Option<f64>> = points
        .iter()
        .map(|r| truth::occluder(scene, rig.light.z, r, eps))
        .collect();
    assert!(occluders.iter().any(|o| o.is_some()) && occluders.iter().any(|o| o.is_none()));
    assert_eq!(cached.occluders, occluders);
    assert!(std::sync::Arc::ptr_eq(
        &cached,
        &truth::exact_of(scene, &vis, rig.light.z)
    ));
    let s = pass_sampling(&c, g, c.truth.pcf);
    let pose0 = c.camera_path().unwrap()[0];
    let maps = truth::ShadowMaps::new(scene);
    let (zero, _) = truth::frame_zero(maps, rig, &rig.light, &pose0, false, &points, &s);
    assert_eq!(zero, g.zero);
    assert!(zero.iter().filter(|z| z.answer.is_some()).count() > 1000);
}
