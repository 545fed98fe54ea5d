//! Shimmer under camera motion: how the texel grid slides over world-fixed points.
//!
//! For cascade i and frame pair (t-1, t), with texel coordinates `s_t(X)` of a static point X:
//!
//! * **S1 size change** `|T_t / T_{t-1} - 1|` (the larger of the two axes). Zero when the
//!   window size is fixed (sphere fit); a tight AABB changes size whenever the camera turns.
//! * **S3 sub-texel phase drift** `d = w(s_t(X) - s_{t-1}(X))` per axis, `w(x) = x - round(x)`,
//!   reported as the 2-D magnitude in texels. A whole-texel move is invisible; a fractional one
//!   is shimmer.
//! * **S4 cell flips**: the fraction of probes whose sampled texel (centre
//!   `o_t + (floor(s_t) + 1/2) T_t`) moves by half a texel or more in world space along either
//!   light axis, i.e. the probe now reads a different texel. Under a uniform sub-texel shift
//!   `(dx, dy)` this is about `|dx| + |dy| - |dx||dy|`.
//!
//! **Closed form.** When the light basis is fixed (csm-lab's fits, most presets) and
//! `T_t == T_{t-1}`, the grid only translates: every point drifts by the same
//! `d = w(o_{t-1} - o_t)` (window origins in texels), whatever the camera did. S3 is then computed from the two window origins alone, without probes; only
//! a size change needs the per-probe evaluation. Windows keep their origin in texel units, so
//! snapped origins are exact integers and the snapped drift is exactly zero, even far from the
//! world origin.
//!
//! **Moving bases.** A few engine presets derive the light basis from the camera (Filament's
//! look-to with the camera's right axis, seed 004's look-at from a light position). Then the
//! grid rotates between frames and every probe is read through each frame's own basis.

use glam::{DVec2, DVec3};

use crate::cascades::{LightPose, Rig};
use crate::fitting::Window;
use crate::geometry::{Aabb, CameraPose, LightBasis};
use crate::rng::halton;

/// `x - round(x)`, in [-0.5, 0.5].
pub fn wrap(x: f64) -> f64 {
    x - x.round()
}

/// Shimmer of one cascade between frames `frame - 1` and `frame`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FrameShimmer {
    pub frame: usize,
    pub cascade: usize,
    pub snapped: bool,
    /// S1.
    pub size_change: f64,
    /// S3 RMS and max over probes (equal under a uniform shift).
    pub phase_drift_rms: f64,
    pub phase_drift_max: f64,
    /// S4, when probes were evaluated.
    pub cell_flips: Option<f64>,
}

/// Shimmer over the whole path for one snap mode.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct ShimmerStats {
    /// RMS of S3 over all frame pairs, cascades and probes (texels).
    pub rms: f64,
    /// Largest S3 seen (texels).
    pub max: f64,
    /// Largest S1 seen.
    pub size_jitter: f64,
    /// Mean S4 over frame pairs and cascades, when computed.
    pub cell_flip_rate: Option<f64>,
}

/// Coverage of the slices by their windows over the path, for one snap mode.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct Coverage {
    /// Per cascade: number of (frame, slice corner) pairs outside the window.
    pub violations: Vec<u64>,
    /// Per cascade: how far outside the worst point was, in texels (0 when covered).
    pub worst_texels: Vec<f64>,
    /// Per cascade: the smallest margin between a slice corner and the window edge, in texels.
    pub min_slack_texels: Vec<f64>,
}

impl Coverage {
    pub fn total(&self) -> u64 {
        self.violations.iter().sum()
    }
}

/// What to compute along the path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShimmerOptions {
    /// Evaluate S4 (cell flips) per probe.
    pub cell_flips: bool,
    /// Evaluate S3 per probe even where the closed form applies (an independent check).
    pub probe_drift: bool,
    /// Keep the per-frame rows.
    pub frame_rows: bool,
}

/// World-fixed probe points for each cascade, placed in the configured camera's slice and,
/// where possible, inside the scene bounds: receivers that exist. Deterministic (Halton).
pub fn probes(rig: &Rig, pose0: &CameraPose, scene: &Aabb, per_cascade: usize) -> Vec<Vec<DVec3>> {
    let lens = &rig.lens;
    rig.slices
        .iter()
        .enumerate()
        .map(|(i, s)| {
            // Probes go where the cascade is read: its selection interval (the fitted slice
            // when the selection is empty; the two are equal in csm-lab's own pipeline).
            let (near, far) = match rig.selection(i) {
                (a, b) if b > a => (a, b),
                _ => (s.near, s.far),
            };
            let point = |j: u64| {
                let z = near + (far - near) * halton(j, 2);
                let sx = (2.0 * halton(j, 3) - 1.0) * lens.tan_h;
                let sy = (2.0 * halton(j, 5) - 1.0) * lens.tan_v;
                pose0.point(sx, sy, z)
            };
            let eps = 1e-9 * (scene.max - scene.min).max_element().max(1.0);
            let offset = 1 + 7919 * i as u64;
            let mut out: Vec<DVec3> = (0..16 * per_cascade as u64)
                .map(|j| point(offset + j))
                .filter(|p| scene.contains(*p, eps))
                .take(per_cascade)
                .collect();
            let mut j = 0;
            while out.len() < per_cascade {
                out.push(point(offset + j));
                j += 1;
            }
            out
        })
        .collect()
}

/// Result of one pass along the path for one snap mode.
#[derive(Debug, Clone, PartialEq)]
pub struct PathResult {
    pub stats: ShimmerStats,
    pub coverage: Coverage,
    pub frames: Vec<FrameShimmer>,
}

/// Walk the path once for one snap mode: shimmer and coverage together, so each window is
/// computed once per frame.
pub fn along_path(
    rig: &Rig,
    poses: &[CameraPose],
    probes: &[Vec<DVec3>],
    snapped: bool,
    opts: ShimmerOptions,
) -> PathResult {
    let m = rig.cascade_count();
    // With a fixed basis a static probe has the same light-space x/y in every frame.
    let fixed = rig.fixed_basis();
    let probe_xy: Vec<Vec<DVec2>> = if fixed {
        probes
            .iter()
            .map(|ps| ps.iter().map(|p| rig.light.to_light_xy(*p)).collect())
            .collect()
    } else {
        Vec::new()
    };
    let mut prev: Vec<Option<Window>> = vec![None; m];
    // Each cascade's basis in the previous frame (only tracked when it can change).
    let mut prev_basis: Vec<LightBasis> = vec![rig.light; m];
    let mut coverage = Coverage {
        violations: vec![0; m],
        worst_texels: vec![0.0; m],
        min_slack_texels: vec![f64::INFINITY; m],
    };
    let mut sum_ms = 0.0;
    let mut pairs = 0usize;
    let mut max_drift: f64 = 0.0;
    let mut jitter: f64 = 0.0;
    let mut flip_sum = 0.0;
    let mut frames = Vec::new();
    for (t, pose) in poses.iter().enumerate() {
        let lp = LightPose::new(&rig.light, pose);
        for i in 0..m {
            let w = rig.window(i, &lp, snapped);
            let cov = rig.coverage(i, &lp, &w);
            coverage.violations[i] += cov.violations;
            coverage.worst_texels[i] = coverage.worst_texels[i].max(cov.worst_texels);
            coverage.min_slack_texels[i] = coverage.min_slack_texels[i].min(cov.min_slack_texels);
            if let Some(p) = prev[i] {
                let size_change = ((w.texel.x / p.texel.x - 1.0).abs()).max((w.texel.y / p.texel.y - 1.0).abs());
                jitter = jitter.max(size_change);
                let same_size = w.texel == p.texel;
                let basis = if fixed { rig.light } else { rig.basis(i, &lp) };
                let pb = prev_basis[i];
                let closed_form = same_size && (fixed || pb == basis) && !opts.probe_drift;
                let mut flips = None;
                let (mut ms, mut mx) = (0.0, 0.0f64);
                if closed_form {
                    let d = DVec2::new(
                        wrap(p.origin_texels.x - w.origin_texels.x),
                        wrap(p.origin_texels.y - w.origin_texels.y),
                    );
                    ms = d.length_squared();
                    mx = d.length();
                }
                if !closed_form || opts.cell_flips {
                    let (mut ss, mut pmx, mut flipped) = (0.0, 0.0f64, 0usize);
                    let mut probe = |s0: DVec2, s1: DVec2, moved: DVec2| {
                        let d = DVec2::new(wrap(s1.x - s0.x), wrap(s1.y - s0.y));
                        ss += d.length_squared();
                        pmx = pmx.max(d.length());
                        if moved.x >= 0.5 || moved.y >= 0.5 {
                            flipped += 1;
                        }
                    };
                    let count = if fixed {
                        for q in &probe_xy[i] {
                            let s0 = p.texel_coords(*q);
                            let s1 = w.texel_coords(*q);
                            // Sampled texel centres in light space, and how far they moved in
                            // texels of the current window.
                            let c0 = (p.origin_texels + s0.floor() + 0.5) * p.texel;
                            let c1 = (w.origin_texels + s1.floor() + 0.5) * w.texel;
                            probe(s0, s1, ((c1 - c0) / w.texel).abs());
                        }
                        probe_xy[i].len()
                    } else {
                        // The basis changed: each frame reads a probe through its own basis.
                        // The previous texel centre is a line along the previous light
                        // direction; take its point at the probe's depth and measure how far
                        // it lies from the current texel centre in the current basis.
                        for q in &probes[i] {
                            let s0 = p.texel_coords(pb.to_light_xy(*q));
                            let s1 = w.texel_coords(basis.to_light_xy(*q));
                            let c0 = (p.origin_texels + s0.floor() + 0.5) * p.texel;
                            let c1 = (w.origin_texels + s1.floor() + 0.5) * w.texel;
                            let c0_world = pb.x * c0.x + pb.y * c0.y + pb.z * pb.z.dot(*q);
                            let c0_now = basis.to_light_xy(c0_world);
                            probe(s0, s1, ((c1 - c0_now) / w.texel).abs());
                        }
                        probes[i].len()
                    };
                    let count = count.max(1) as f64;
                    if !closed_form {
                        ms = ss / count;
                        mx = pmx;
                    }
                    if opts.cell_flips {
                        flips = Some(flipped as f64 / count);
                        flip_sum += flipped as f64 / count;
                    }
                }
                sum_ms += ms;
                pairs += 1;
                max_drift = max_drift.max(mx);
                if opts.frame_rows {
                    frames.push(FrameShimmer {
                        frame: t,
                        cascade: i,
                        snapped,
                        size_change,
                        phase_drift_rms: ms.sqrt(),
                        phase_drift_max: mx,
                        cell_flips: flips,
                    });
                }
            }
            prev[i] = Some(w);
            if !fixed {
                prev_basis[i] = rig.basis(i, &lp);
            }
        }
    }
    for s in &mut coverage.min_slack_texels {
        if !s.is_finite() {
            *s = 0.0;
        }
    }
    let stats = ShimmerStats {
        rms: if pairs > 0 { (sum_ms / pairs as f64).sqrt() } else { 0.0 },
        max: max_drift,
        size_jitter: jitter,
        cell_flip_rate: opts
            .cell_flips
            .then(|| if pairs > 0 { flip_sum / pairs as f64 } else { 0.0 }),
    };
    PathResult {
        stats,
        coverage,
        frames,
    }
}
