//! Seams and transitions: blend-band pixel shares, the map area the bands cost and
//! `seam_crossings`, each checked against a computation of its own (brute-force counts).

use csm_core::geometry::CameraPose;
use csm_core::seams;
use csm_lab::analysis::{analyze, AnalysisOptions};
use glam::DVec3;
use proptest::prelude::*;

use crate::common::{config, with, BASE};

/// A ground plane under the default camera, seen on a small screen.
fn ground(extra: &str) -> String {
    with(&[
        ("screen.width", "width = 160"),
        ("screen.height", "height = 90"),
        ("light.direction", "direction = [-0.4, -1.0, -0.3]"),
        ("analysis.screen_scale", "screen_scale = 1.0"),
    ]) + extra
        + "\n[[scene.box]]\nmin = [-400.0, -1.0, -400.0]\nmax = [400.0, 0.0, 400.0]\n"
}

fn bevy(extra: &str) -> String {
    ground(extra).replace("max_distance = 150.0", "max_distance = 150.0\npreset = \"bevy\"")
}

#[test]
fn a_camera_that_stays_has_no_seam_crossings() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("still.csv");
    std::fs::write(
        &csv,
        "px,py,pz,tx,ty,tz\n0,10,0,0,0,-50\n0,10,0,0,0,-50\n0,10,0,0,0,-50\n0,10,0,0,0,-50\n",
    )
    .unwrap();
    let still = |text: String| {
        text.replace(
            "path = \"strafe\"\nframes = 60\nstep = 0.05",
            &format!("path = \"file\"\nfile = {:?}", csv.to_str().unwrap()),
        )
    };
    for text in [still(BASE.to_string()), still(ground("")), still(bevy(""))] {
        assert!(text.contains("path = \"file\""));
        let a = analyze(&config(&text), &AnalysisOptions::full());
        assert_eq!(a.summary.seam_crossings, Some(0.0), "{text}");
    }
    // A strafe keeps every view depth (no crossing); a dolly crosses seams (the test above can fail).
    let strafe = analyze(
        &config(&bevy("").replace("step = 0.05", "step = 2.0")),
        &AnalysisOptions::full(),
    );
    assert_eq!(strafe.summary.seam_crossings, Some(0.0));
    let dolly = bevy("")
        .replace("path = \"strafe\"", "path = \"dolly\"")
        .replace("step = 0.05", "step = 0.5");
    let a = analyze(&config(&dolly), &AnalysisOptions::full());
    assert!(a.summary.seam_crossings.unwrap() > 0.0);
    // A sweep row does not compute it, and no output shows a value it did not compute.
    let a = analyze(&config(BASE), &AnalysisOptions::summary_only());
    assert_eq!(a.summary.seam_crossings, None);
    assert!(csm_lab::metric::summary_json(&a.summary)
        .iter()
        .all(|(k, _)| *k != "seam_crossings"));
}

#[test]
fn seam_crossings_of_a_dolly_equal_a_direct_count() {
    // Points on the view axis at depths 0.5, 1.5, ..., 99.5; the camera dollies forward by s
    // per frame, so a point's depth falls by s each frame. Splits 1, 10, 30, 60, 80.
    let splits = [1.0, 10.0, 30.0, 60.0, 80.0];
    let points: Vec<DVec3> = (0..100).map(|k| DVec3::new(0.0, 0.0, -(k as f64 + 0.5))).collect();
    for (s, frames) in [(0.7, 40usize), (3.0, 12), (25.0, 5)] {
        let poses = (0..frames).map(|t| {
            CameraPose::look_at(
                DVec3::new(0.0, 0.0, -(t as f64) * s),
                DVec3::new(0.0, 0.0, -1e6),
                DVec3::Y,
            )
            .unwrap()
        });
        let got = csm_core::seams::seam_crossings(&splits, &points, poses);
        // Direct count: between frames t-1 and t a point changes cascade when some boundary
        // is crossed: the near end and interior splits are "at or beyond", the far end "beyond".
        let mut changed = 0usize;
        for t in 1..frames {
            for k in 0..100 {
                let d0 = k as f64 + 0.5;
                let (a, b) = (d0 - (t - 1) as f64 * s, d0 - t as f64 * s); // a > b
                let crossed = splits[..4].iter().any(|&x| b < x && x <= a) || (b <= 80.0 && 80.0 < a);
                changed += usize::from(crossed);
            }
        }
        let expected = changed as f64 / ((frames - 1) as f64 * 100.0);
        assert!((got - expected).abs() < 1e-12, "step {s}: {got} vs {expected}");
        assert!(expected > 0.0);
    }
}

/// Bevy's far bounds and blend bands, computed here from its rule.
fn bevy_bands(m: usize, first: f64, max: f64, overlap: f64) -> Vec<(f64, f64)> {
    let far: Vec<f64> = (0..m)
        .map(|i| first * (max / first).powf(i as f64 / (m - 1) as f64))
        .collect();
    (0..m - 1).map(|i| ((1.0 - overlap) * far[i], far[i])).collect()
}

#[test]
fn band_pixel_shares_equal_a_per_pixel_count() {
    let c = config(&bevy(""));
    let a = analyze(&c, &AnalysisOptions::full());
    let bands = bevy_bands(4, 10.0, 150.0, 0.2);
    let vis = c.setup().visibility().unwrap();
    let lit: Vec<f64> = vis
        .samples
        .iter()
        .flatten()
        .filter(|s| s.lit)
        .map(|s| s.depth)
        .collect();
    assert!(lit.len() > 1000, "{}", lit.len());
    let mut total = 0.0;
    for (j, &(lo, hi)) in bands.iter().enumerate() {
        let n = lit.iter().filter(|&&d| lo <= d && d < hi).count();
        let expected = n as f64 / lit.len() as f64;
        let k = &a.cascades[j];
        assert!(
            (k.band_near - lo).abs() < 1e-9 && (k.band_far - hi).abs() < 1e-9,
            "{k:?}"
        );
        assert_eq!(k.screen.unwrap().band_pixels, expected, "band {j}");
        total += expected;
    }
    assert!(total > 0.05, "the bands hold pixels: {total}");
    assert!((a.summary.band_pixel_share - total).abs() < 1e-12);
    // csm-lab's own pipeline selects what it fits: no band, no share, no doubled area.
    let own = analyze(&config(&ground("")), &AnalysisOptions::full());
    assert_eq!(own.summary.band_pixel_share, 0.0);
    assert_eq!(own.summary.overlap_area_fraction, 0.0);
    assert!(own.cascades.iter().all(|k| k.band_near == k.band_far));
}

#[test]
fn the_overlap_area_equals_a_count_of_texels_that_see_the_band() {
    let c = config(&bevy("").replace("resolution = 2048", "resolution = 512"));
    let a = analyze(&c, &AnalysisOptions::full());
    let rig = a.rig().unwrap();
    let pose = c.camera.pose();
    let (tan_h, tan_v) = (rig.lens.tan_h, rig.lens.tan_v);
    let m = a.cascades.len();
    let n = 512usize;
    let mut sum = 0.0;
    for (j, &(lo, hi)) in bevy_bands(m, 10.0, 150.0, 0.2).iter().enumerate() {
        let k = &a.cascades[j];
        let b = rig.light; // Bevy's basis is fixed per frame
        let texel = k.width / n as f64;
        let (x0, y0) = (k.centre_x - 0.5 * k.width, k.centre_y - 0.5 * k.height);
        let mut inside = 0usize;
        for u in 0..n {
            for v in 0..n {
                let (qx, qy) = (
                    x0 + (u as f64 + 0.5) * texel,
                    y0 + (v as f64 + 0.5) * k.height / n as f64,
                );
                // The light ray through the texel centre, in camera terms: e + t·w.
                let e0 = b.x * qx + b.y * qy - pose.position;
                let w = b.z;
                let (ez, wz) = (e0.dot(pose.forward), w.dot(pose.forward));
                let (ex, wx) = (e0.dot(pose.right), w.dot(pose.right));
                let (ey, wy) = (e0.dot(pose.up), w.dot(pose.up));
                // Half-spaces a + c·t >= 0.
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
    assert_eq!(a.cascades[m - 1].overlap_area_fraction, 0.0);
    assert!((a.summary.overlap_area_fraction - sum).abs() < 1e-15);
}

#[test]
fn the_split_jump_is_the_texel_ratio_of_neighbours() {
    let a = analyze(&config(BASE), &AnalysisOptions::full());
    let k = &a.cascades;
    for i in 0..k.len() - 1 {
        assert_eq!(k[i].split_jump, k[i + 1].texel_size / k[i].texel_size);
    }
    assert_eq!(k[k.len() - 1].split_jump, 0.0);
}

/// The cascade a view depth reads, from the definition (docs/metrics.md): none (`m`) before the
/// first split or beyond the last; else the number of interior splits at or before it.
fn cascade_of(splits: &[f64], d: f64) -> usize {
    let m = splits.len() - 1;
    if d < splits[0] || d > splits[m] {
        return m;
    }
    splits[1..m].iter().filter(|&&s| s <= d).count().min(m - 1)
}

/// Every point's cascade recomputed in every frame: the changes between consecutive frames.
fn brute_force_changes(splits: &[f64], points: &[DVec3], poses: &[CameraPose]) -> u64 {
    let depth = |p: DVec3, pose: &CameraPose| (p - pose.position).dot(pose.forward);
    let mut changes = 0;
    for pair in poses.windows(2) {
        for &p in points {
            changes += u64::from(cascade_of(splits, depth(p, &pair[0])) != cascade_of(splits, depth(p, &pair[1])));
        }
    }
    changes
}

/// One stretch of a random camera path: `frames` frames of a per-frame turn (radians, about
/// +Y, and a pitch), a per-frame move, or a jump to anywhere.
#[derive(Debug, Clone)]
enum Stretch {
    Turn { frames: usize, yaw: f64, pitch: f64 },
    Move { frames: usize, step: DVec3 },
    Jump { to: DVec3, yaw: f64 },
    Still { frames: usize },
}

fn stretch() -> impl Strategy<Value = Stretch> {
    let v = || -5.0f64..5.0;
    prop_oneof![
        (1usize..80, -0.05f64..0.05, -0.01f64..0.01).prop_map(|(frames, yaw, pitch)| Stretch::Turn {
            frames,
            yaw,
            pitch
        }),
        (1usize..80, v(), v(), v()).prop_map(|(frames, x, y, z)| Stretch::Move {
            frames,
            step: DVec3::new(x, y, z) * 0.2
        }),
        (-50.0f64..50.0, -5.0f64..5.0, -50.0f64..50.0, -3.2f64..3.2).prop_map(|(x, y, z, yaw)| Stretch::Jump {
            to: DVec3::new(x, y, z),
            yaw
        }),
        (1usize..10).prop_map(|frames| Stretch::Still { frames }),
    ]
}

/// The poses of a path of stretches, each stretch repeated `back` times with its direction
/// reversed every other time (the camera turns or moves back over where it was).
fn path(stretches: &[(Stretch, usize)]) -> Vec<CameraPose> {
    let (mut position, mut yaw, mut pitch) = (DVec3::new(0.0, 10.0, 0.0), 0.0f64, -0.2f64);
    let pose = |p: DVec3, yaw: f64, pitch: f64| {
        let dir = DVec3::new(-yaw.sin() * pitch.cos(), pitch.sin(), -yaw.cos() * pitch.cos());
        CameraPose::look_to(p, dir, DVec3::Y).unwrap()
    };
    let mut out = vec![pose(position, yaw, pitch)];
    for (s, back) in stretches {
        for k in 0..*back {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            match s {
                Stretch::Turn {
                    frames,
                    yaw: dy,
                    pitch: dp,
                } => {
                    for _ in 0..*frames {
                        yaw += sign * dy;
                        pitch = (pitch + sign * dp).clamp(-1.2, 1.2);
                        out.push(pose(position, yaw, pitch));
                    }
                }
                Stretch::Move { frames, step } => {
                    for _ in 0..*frames {
                        position += sign * *step;
                        out.push(pose(position, yaw, pitch));
                    }
                }
                Stretch::Jump { to, yaw: y } => {
                    position = *to;
                    yaw = *y;
                    out.push(pose(position, yaw, pitch));
                }
                Stretch::Still { frames } => {
                    for _ in 0..*frames {
                        out.push(pose(position, yaw, pitch));
                    }
                }
            }
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, .. ProptestConfig::default() })]

    /// The incremental count (`SeamCounter`, which computes a point again only when its depth
    /// could have reached a split) equals the count of every point in every frame, on random
    /// paths that turn, move, jump, stand still and go back over themselves, with points
    /// anywhere and points exactly on a split's depth in frame 0.
    #[test]
    fn the_incremental_seam_count_equals_the_per_frame_count(
        gaps in prop::collection::vec(prop_oneof![4 => 0.5f64..40.0, 1 => Just(0.0)], 2..6),
        first in 0.05f64..5.0,
        points in prop::collection::vec((-120.0f64..120.0, -10.0f64..50.0, -120.0f64..120.0), 1..40),
        on_split in prop::collection::vec((0usize..8, -30.0f64..30.0), 0..6),
        stretches in prop::collection::vec((stretch(), 1usize..4), 1..8),
    ) {
        let splits: Vec<f64> = std::iter::once(first)
            .chain(gaps.iter().scan(first, |d, g| { *d += g; Some(*d) }))
            .collect();
        let poses = path(&stretches);
        let p0 = poses[0];
        let mut pts: Vec<DVec3> = points.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
        // Exactly on a split in frame 0 (up to the rounding of the depth), off the view axis.
        pts.extend(on_split.iter().map(|&(j, side)| {
            p0.position + p0.forward * splits[j % splits.len()] + p0.right * side
        }));
        let mut counter = seams::SeamCounter::new(&splits, &pts);
        for p in &poses {
            counter.frame(p);
        }
        let expected = brute_force_changes(&splits, &pts, &poses);
        prop_assert_eq!(counter.changes(), expected);
        prop_assert_eq!(counter.steps(), poses.len() as u64 - 1);
        let rate = expected as f64 / ((poses.len() - 1) as f64 * pts.len() as f64);
        prop_assert_eq!(counter.rate().to_bits(), if poses.len() > 1 { rate.to_bits() } else { 0f64.to_bits() });
        prop_assert!(counter.evaluations() <= (poses.len() * pts.len()) as u64);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 60, .. ProptestConfig::default() })]

    /// The same on long smooth paths, where the counter sets points aside for many frames on
    /// the strength of the path's small curvature: the camera circles a centre while it turns
    /// at its own rate, pitches back and forth and drifts up, with a kink (a change of rate)
    /// part of the way, and points scattered around and on the splits' depths.
    #[test]
    fn the_incremental_seam_count_equals_the_per_frame_count_on_long_smooth_paths(
        frames in 200usize..1500,
        radius in 0.0f64..60.0,
        orbit in -0.01f64..0.01,
        turn in -0.01f64..0.01,
        nod in (0.0f64..0.3, 0.001f64..0.05),
        rise in -0.05f64..0.05,
        kink in (0.0f64..1.0, 0.2f64..3.0),
        points in prop::collection::vec((-150.0f64..150.0, -10.0f64..60.0, -150.0f64..150.0), 1..60),
        on_split in prop::collection::vec((0usize..5, -30.0f64..30.0), 0..8),
    ) {
        let splits = [0.1, 9.86, 21.67, 46.21, 150.0];
        let at = (kink.0 * frames as f64) as usize;
        let poses: Vec<CameraPose> = (0..frames)
            .map(|t| {
                // A change of every rate at frame `at`.
                let s = if t < at { t as f64 } else { at as f64 + kink.1 * (t - at) as f64 };
                let a = orbit * s;
                let position = DVec3::new(radius * a.cos(), 10.0 + rise * s, radius * a.sin());
                let yaw = turn * s;
                let pitch = -0.2 + nod.0 * (nod.1 * s).sin();
                let dir = DVec3::new(-yaw.sin() * pitch.cos(), pitch.sin(), -yaw.cos() * pitch.cos());
                CameraPose::look_to(position, dir, DVec3::Y).unwrap()
            })
            .collect();
        let p0 = poses[0];
        let mut pts: Vec<DVec3> = points.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
        pts.extend(on_split.iter().map(|&(j, side)| p0.position + p0.forward * splits[j] + p0.right * side));
        let mut counter = seams::SeamCounter::new(&splits, &pts);
        for p in &poses {
            counter.frame(p);
        }
        prop_assert_eq!(counter.changes(), brute_force_changes(&splits, &pts, &poses));
    }
}

#[test]
fn a_long_yaw_computes_few_receivers_per_frame_and_counts_as_every_frame() {
    // 4,096 points on a 400 x 400 ground, the default camera yawing 0.05 degrees a frame for
    // 20,000 frames (2.8 turns): the incremental count equals the brute-force one while it
    // computes a small share of the point-frames.
    let splits = [0.1, 9.86, 21.67, 46.21, 150.0];
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<DVec3> = (0..4096)
        .map(|_| DVec3::new(400.0 * next() - 200.0, 40.0 * next() * next(), 400.0 * next() - 200.0))
        .collect();
    let step = 0.05f64.to_radians();
    let poses: Vec<CameraPose> = (0..20_000)
        .map(|t| {
            let q = glam::DQuat::from_axis_angle(DVec3::Y, step * t as f64);
            CameraPose::look_to(DVec3::new(0.0, 10.0, 0.0), q * DVec3::new(0.0, -10.0, -50.0), DVec3::Y).unwrap()
        })
        .collect();
    let mut counter = seams::SeamCounter::new(&splits, &pts);
    for p in &poses {
        counter.frame(p);
    }
    assert_eq!(counter.changes(), brute_force_changes(&splits, &pts, &poses));
    assert!(counter.changes() > 10_000, "{}", counter.changes());
    let share = counter.evaluations() as f64 / (poses.len() * pts.len()) as f64;
    assert!(share < 0.01, "computed {share} of the point-frames");
}
