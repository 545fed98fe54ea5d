//! three.js CSM with `fade = true`: the grown window sides, the blend bands the shader reads
//! and what they cost, each checked against a computation of its own; fade off changes nothing.

use csm_lab::analysis::{analyze, rig, AnalysisOptions};
use csm_lab::commands::terms::EngineSetting;
use csm_lab::presets::{apply_terms, Knobs};
use csm_lab::Config;

use crate::common::{config, with};

/// The default camera over a ground plane on a small screen, three.js preset, 4 cascades,
/// camera far 1000 and maxFar (shadow distance) 150; `table` is the `[threejs]` table's body.
fn ground(table: &str) -> String {
    with(&[
        ("screen.width", "width = 160"),
        ("screen.height", "height = 90"),
        ("light.direction", "direction = [-0.4, -1.0, -0.3]"),
        ("analysis.screen_scale", "screen_scale = 1.0"),
    ])
    .replace("max_distance = 150.0", "max_distance = 150.0\npreset = \"threejs\"")
        + "\n[[scene.box]]\nmin = [-400.0, -1.0, -400.0]\nmax = [400.0, 0.0, 400.0]\n"
        + "\n[threejs]\n"
        + table
        + "\n"
}

const NEAR: f64 = 0.1;
const CAMERA_FAR: f64 = 1000.0;
const MAX_FAR: f64 = 150.0;

/// three.js's practical breaks (fractions of F = min(far, maxFar)), written out here.
fn breaks(m: usize) -> Vec<f64> {
    let f = CAMERA_FAR.min(MAX_FAR);
    let mut b: Vec<f64> = (1..m)
        .map(|i| {
            let t = i as f64 / m as f64;
            let uniform = (NEAR + (f - NEAR) * t) / f;
            let log = NEAR * (f / NEAR).powf(t) / f;
            0.5 * (uniform + log)
        })
        .collect();
    b.push(1.0);
    b
}

/// The cascades the WebGL shader reads at linear depth `ld` with fade on, and their blend
/// ratios: its per-cascade loop, rule for rule.
fn shader_reads(b: &[f64], ld: f64) -> Vec<(usize, f64)> {
    let m = b.len();
    let mut out = Vec::new();
    for i in 0..m {
        let (x, y) = (if i == 0 { 0.0 } else { b[i - 1] }, b[i]);
        let centre = 0.5 * (x + y);
        let edge = if ld < centre { x } else { y };
        let margin = 0.25 * edge * edge;
        let (lo, hi) = (x - 0.5 * margin, y + 0.5 * margin);
        if ld >= lo && (ld < hi || i == m - 1) {
            let ratio = ((ld - lo).min(hi - ld) / margin).clamp(0.0, 1.0);
            out.push((i, ratio));
        }
    }
    out
}

#[test]
fn fade_grows_each_window_by_the_margin_of_its_far_end() {
    let off = config(&ground(""));
    let on = config(&ground("fade = true"));
    let (r0, r1) = (rig(&off).unwrap(), rig(&on).unwrap());
    let b = breaks(4);
    let f = CAMERA_FAR.min(MAX_FAR);
    let k = r1.lens.tan_h.hypot(r1.lens.tan_v);
    // Fmax takes the larger of camera far and maxFar (1000 here, not 150).
    let span = CAMERA_FAR.max(MAX_FAR) - NEAR;
    for i in 0..4 {
        let (d0, d1) = (if i == 0 { NEAR } else { b[i - 1] * f }, b[i] * f);
        let diameter = (2.0 * d1 * k).max(((d1 + d0).powi(2) * k * k + (d1 - d0).powi(2)).sqrt());
        let growth = 0.25 * (d1 / span).powi(2) * span;
        assert!(
            (r0.sphere_side[i] - diameter).abs() < 1e-9 * diameter,
            "off, cascade {i}"
        );
        let want = diameter + growth;
        assert!(
            (r1.sphere_side[i] - want).abs() < 1e-9 * want,
            "cascade {i}: {} vs {want}",
            r1.sphere_side[i]
        );
        assert!(growth > 1e-3, "the growth is visible: {growth}");
    }
    // Fade off is three.js's default: the same rig as no [threejs] fade key at all.
    let plain = config(&ground("fade = false"));
    let rp = rig(&plain).unwrap();
    assert_eq!(rp.sphere_side, r0.sphere_side);
    assert_eq!(rp.splits, r0.splits);
    assert_eq!(off.shadow.preset, plain.shadow.preset);
}

#[test]
fn fade_band_pixel_shares_equal_a_per_pixel_count_with_the_shader_rule() {
    let c = config(&ground("fade = true"));
    let a = analyze(&c, &AnalysisOptions::full());
    let vis = c.setup().visibility().unwrap();
    let lit: Vec<f64> = vis
        .samples
        .iter()
        .flatten()
        .filter(|s| s.lit)
        .map(|s| s.depth)
        .collect();
    assert!(lit.len() > 1000, "{}", lit.len());
    let b = breaks(4);
    let u = CAMERA_FAR.min(MAX_FAR) - NEAR;
    // A pixel is in the band of split j when the shader reads cascades j and j + 1 both, each
    // with a ratio below 1 (their ratios then add up to 1).
    let mut counts = [0usize; 3];
    for &d in &lit {
        let reads = shader_reads(&b, d / u);
        if reads.len() == 2 {
            let (j, r) = (reads[0].0, reads[0].1 + reads[1].1);
            assert_eq!(reads[1].0, j + 1);
            assert!((r - 1.0).abs() < 1e-9, "depth {d}: ratios {reads:?}");
            counts[j] += 1;
        } else {
            assert!(reads.len() <= 1, "depth {d}: {reads:?}");
        }
    }
    let mut total = 0.0;
    for (j, n) in counts.iter().enumerate() {
        let expected = *n as f64 / lit.len() as f64;
        let k = &a.cascades[j];
        assert_eq!(k.screen.unwrap().band_pixels, expected, "band {j}");
        // The band in view depth: b ± b²/8 of linear depth.
        let (lo, hi) = ((b[j] - b[j] * b[j] / 8.0) * u, (b[j] + b[j] * b[j] / 8.0) * u);
        assert!(
            (k.band_near - lo).abs() < 1e-9 && (k.band_far - hi).abs() < 1e-9,
            "{k:?}"
        );
        total += expected;
    }
    assert!(total > 0.02, "the bands hold pixels: {total}");
    assert!((a.summary.band_pixel_share - total).abs() < 1e-12);
    // Without fade, three.js has no band, no share and no doubled area.
    let off = analyze(&config(&ground("")), &AnalysisOptions::full());
    assert_eq!(off.summary.band_pixel_share, 0.0);
    assert_eq!(off.summary.overlap_area_fraction, 0.0);
    assert!(a.summary.overlap_area_fraction > 0.0);
}

#[test]
fn fade_overlap_area_equals_a_count_of_texels_that_see_the_band() {
    let c = config(&ground("fade = true").replace("resolution = 2048", "resolution = 512"));
    let a = analyze(&c, &AnalysisOptions::full());
    let rig = a.rig().unwrap();
    let pose = c.camera.pose();
    let (tan_h, tan_v) = (rig.lens.tan_h, rig.lens.tan_v);
    let m = a.cascades.len();
    let n = 512usize;
    let b = breaks(m);
    let u = CAMERA_FAR.min(MAX_FAR) - NEAR;
    let mut sum = 0.0;
    for (j, &bj) in b.iter().enumerate().take(m - 1) {
        let (lo, hi) = ((bj - bj * bj / 8.0) * u, (bj + bj * bj / 8.0) * u);
        let k = &a.cascades[j];
        let l = rig.light; // three.js's basis is fixed
        let texel = k.width / n as f64;
        let (x0, y0) = (k.centre_x - 0.5 * k.width, k.centre_y - 0.5 * k.height);
        let mut inside = 0usize;
        for p in 0..n {
            for q in 0..n {
                let (qx, qy) = (
                    x0 + (p as f64 + 0.5) * texel,
                    y0 + (q as f64 + 0.5) * k.height / n as f64,
                );
                // The light ray through the texel centre, e + t·w, against the band's slab
                // of the view frustum (six half-spaces a + c·t >= 0).
                let e0 = l.x * qx + l.y * qy - pose.position;
                let w = l.z;
                let (ez, wz) = (e0.dot(pose.forward), w.dot(pose.forward));
                let (ex, wx) = (e0.dot(pose.right), w.dot(pose.right));
                let (ey, wy) = (e0.dot(pose.up), w.dot(pose.up));
                let halves = [
                    (ez - lo, wz),
                    (hi - ez, -wz),
                    (tan_h * ez - ex, tan_h * wz - wx),
                    (tan_h * ez + ex, tan_h * wz + wx),
                    (tan_v * ez - ey, tan_v * wz - wy),
                    (tan_v * ez + ey, tan_v * wz + wy),
                ];
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                for (a0, c0) in halves {
                    if c0.abs() < 1e-15 {
                        if a0 < 0.0 {
                            t0 = f64::INFINITY;
                        }
                    } else if c0 > 0.0 {
                        t0 = t0.max(-a0 / c0);
                    } else {
                        t1 = t1.min(-a0 / c0);
                    }
                }
                inside += usize::from(t0 <= t1);
            }
        }
        let expected = inside as f64 / (m * n * n) as f64;
        let got = k.overlap_area_fraction;
        assert!(expected > 0.0);
        assert!(
            (got - expected).abs() <= 0.02 * expected,
            "split {j}: {got} vs {expected}"
        );
        sum += got;
    }
    assert!((a.summary.overlap_area_fraction - sum).abs() < 1e-12);
}

/// The three.js knobs of a config.
fn knobs(c: &Config) -> Knobs {
    c.shadow.preset.as_ref().unwrap().knobs.clone()
}

#[test]
fn the_settings_file_sets_fade_after_construction_and_reads_back() {
    for fade in [true, false] {
        let c = config(&ground(&format!("fade = {fade}")));
        let s = EngineSetting::of(&c, vec!["a test".to_string()]).unwrap();
        let text = csm_lab::report::terms::text(&s);
        assert!(
            text.contains(&format!("\ncsm.fade = {fade};\ncsm.updateFrustums();\n")),
            "{text}"
        );
        // Read back onto the opposite setting: the file decides.
        let mut back = config(&ground(&format!("fade = {}", !fade)));
        apply_terms(&mut back, &text, "recommendation.threejs.txt").unwrap();
        assert_eq!(knobs(&back), knobs(&c));
        let (r0, r1) = (rig(&c).unwrap(), rig(&back).unwrap());
        assert_eq!(r0.sphere_side, r1.sphere_side);
        assert_eq!(r0.splits, r1.splits);
        let ends = |r: &csm_core::cascades::Rig| r.slices.iter().map(|s| (s.near, s.far)).collect::<Vec<_>>();
        assert_eq!(ends(&r0), ends(&r1));
    }
    // A bad value names the field and the key.
    let c = config(&ground("fade = true"));
    let s = EngineSetting::of(&c, vec![]).unwrap();
    let text = csm_lab::report::terms::text(&s).replace("csm.fade = true;", "csm.fade = maybe;");
    let mut back = config(&ground(""));
    let e = apply_terms(&mut back, &text, "rec.txt").unwrap_err().to_string();
    assert!(e.contains("fade") && e.contains("maybe"), "{e}");
}

#[test]
fn split_rule_says_whether_fade_is_on() {
    use csm_lab::presets::PresetName;
    let rule = |t: &str| PresetName::Threejs.engine().split_rule(&knobs(&config(&ground(t))));
    assert!(!rule("").contains("fade"));
    assert!(rule("fade = true").contains("fade on"));
}
