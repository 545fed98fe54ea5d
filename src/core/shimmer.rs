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
    x - round_half_away(x)
}

/// `f64::round` (ties away from zero), bit for bit, without the libm call that baseline x86-64
/// makes for it: this sits in the innermost shimmer loops.
#[inline]
fn round_half_away(x: f64) -> f64 {
    // At 2^52 and beyond every double is an integer (and NaN/inf fall through too).
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        return x.round();
    }
    // The i64 conversion truncates exactly here, and `x - t` is exact (its fractional part).
    let t = (x as i64) as f64;
    let r = match x - t {
        d if d >= 0.5 => t + 1.0,
        d if d <= -0.5 => t - 1.0,
        _ => t,
    };
    // round(-0.3) is -0.0: the result always carries the sign of x.
    r.copysign(x)
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

/// True when [`along_path`] evaluates probes with these options: for S4, on request, or
/// whenever a window can change size between frames. A sphere-fit window's side is fixed per
/// cascade in the [`Rig`] (never recomputed per frame), so its S3 always has the closed form
/// and needs no probes; callers may then pass empty probe lists.
pub fn needs_probes(rig: &Rig, opts: ShimmerOptions) -> bool {
    opts.cell_flips || opts.probe_drift || rig.fit != crate::fitting::Fit::Sphere || !fast_walk_applies(rig)
}

/// Whether the shared two-mode walk serves this rig: a fixed light basis, and each cascade's
/// selection interval inside its fitted slice (so the slice corners decide coverage). True for
/// csm-lab's own fits and most engine presets; the others take [`along_path_general`].
fn fast_walk_applies(rig: &Rig) -> bool {
    rig.fixed_basis()
        && (0..rig.cascade_count()).all(|i| {
            let (a, b) = rig.selection(i);
            b <= a || (a >= rig.slices[i].near && b <= rig.slices[i].far)
        })
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
    if fast_walk_applies(rig) {
        let [r] = walk(rig, poses, probes, [snapped], opts);
        r
    } else {
        along_path_general(rig, poses, probes, snapped, opts)
    }
}

/// Both snap modes in one walk, `(snapped, unsnapped)`: the same results as two calls of
/// [`along_path`], bit for bit, with the per-frame work the modes share done once.
pub fn along_path_both(
    rig: &Rig,
    poses: &[CameraPose],
    probes: &[Vec<DVec3>],
    opts: ShimmerOptions,
) -> (PathResult, PathResult) {
    if fast_walk_applies(rig) {
        let [s, u] = walk(rig, poses, probes, [true, false], opts);
        (s, u)
    } else {
        (
            along_path_general(rig, poses, probes, true, opts),
            along_path_general(rig, poses, probes, false, opts),
        )
    }
}

/// The extremes of one cascade's slice corners in texel units (`corner / T`, before the
/// window origin is subtracted) for one frame. Both snap modes use the same window size, so
/// this is computed once for both.
struct CornerTexels {
    texel: DVec2,
    lo: DVec2,
    hi: DVec2,
}

impl CornerTexels {
    /// From the corners and their light-space bounds `(lo, hi)`.
    fn new(corners: &[DVec2; 8], bounds: (DVec2, DVec2), texel: DVec2) -> Self {
        let (lo, hi) = if texel.cmpgt(DVec2::ZERO).all() {
            // Dividing by a positive number is monotone under round-to-nearest, so the bounds
            // divided are exactly the bounds of the divided corners (the values a per-corner
            // `texel_coords` call computes), for 2 divisions instead of 8.
            (bounds.0 / texel, bounds.1 / texel)
        } else {
            crate::cascades::bounds_2d(&corners.map(|c| c / texel))
        };
        CornerTexels { texel, lo, hi }
    }
}

/// Running totals of one snap mode along a path: coverage, S1, S3, S4 and the per-frame rows.
/// Every walk (the shared two-mode walk, the general walk for engine presets, the binary32
/// emulation in [`crate::precision`]) accumulates into one of these.
pub(crate) struct PathTotals {
    snapped: bool,
    coverage: Coverage,
    sum_ms: f64,
    pairs: usize,
    /// Largest squared S3: `sqrt` is monotone, so the largest drift is its root (one
    /// square root per path instead of one per frame pair, bit-identical).
    max_drift_sq: f64,
    jitter: f64,
    flip_sum: f64,
    frames: Vec<FrameShimmer>,
}

impl PathTotals {
    pub(crate) fn new(snapped: bool, m: usize) -> Self {
        PathTotals {
            snapped,
            coverage: Coverage {
                violations: vec![0; m],
                worst_texels: vec![0.0; m],
                min_slack_texels: vec![f64::INFINITY; m],
            },
            sum_ms: 0.0,
            pairs: 0,
            max_drift_sq: 0.0,
            jitter: 0.0,
            flip_sum: 0.0,
            frames: Vec::new(),
        }
    }

    /// One slice corner of cascade `i` at texel coordinates `s` in a window of `n` texels;
    /// `magnitude` is the size of the coordinate before the origin was subtracted, which sets
    /// the rounding tolerance (a few ulps of it, at least 1e-9 texel).
    #[inline]
    pub(crate) fn corner(&mut self, i: usize, s: DVec2, n: f64, magnitude: f64) {
        let slack = s.x.min(n - s.x).min(s.y).min(n - s.y);
        let cov = &mut self.coverage;
        cov.min_slack_texels[i] = cov.min_slack_texels[i].min(slack);
        let tol = 1e-9 + 8.0 * f64::EPSILON * magnitude;
        if -slack > tol {
            cov.violations[i] += 1;
            cov.worst_texels[i] = cov.worst_texels[i].max(-slack);
        }
    }

    /// One frame's coverage of cascade `i` as [`Rig::coverage`] measured it.
    pub(crate) fn add_coverage(&mut self, i: usize, cov: crate::cascades::FrameCoverage) {
        let c = &mut self.coverage;
        c.violations[i] += cov.violations;
        c.worst_texels[i] = c.worst_texels[i].max(cov.worst_texels);
        c.min_slack_texels[i] = c.min_slack_texels[i].min(cov.min_slack_texels);
    }

    /// S1 of one frame pair.
    #[inline]
    pub(crate) fn size_change(&mut self, size_change: f64) {
        self.jitter = self.jitter.max(size_change);
    }

    /// S3 and S4 of one frame pair: (mean square drift, largest square drift, flip share).
    #[inline]
    pub(crate) fn drift(
        &mut self,
        t: usize,
        i: usize,
        size_change: f64,
        (ms, mx_sq, flips): (f64, f64, Option<f64>),
        opts: ShimmerOptions,
    ) {
        if let Some(f) = flips {
            self.flip_sum += f;
        }
        self.sum_ms += ms;
        self.pairs += 1;
        self.max_drift_sq = self.max_drift_sq.max(mx_sq);
        if opts.frame_rows {
            self.frames.push(FrameShimmer {
                frame: t,
                cascade: i,
                snapped: self.snapped,
                size_change,
                phase_drift_rms: ms.sqrt(),
                phase_drift_max: mx_sq.sqrt(),
                cell_flips: flips,
            });
        }
    }

    pub(crate) fn finish(mut self, opts: ShimmerOptions) -> PathResult {
        for s in &mut self.coverage.min_slack_texels {
            if !s.is_finite() {
                *s = 0.0;
            }
        }
        let pairs = self.pairs;
        let stats = ShimmerStats {
            rms: if pairs > 0 {
                (self.sum_ms / pairs as f64).sqrt()
            } else {
                0.0
            },
            max: self.max_drift_sq.sqrt(),
            size_jitter: self.jitter,
            cell_flip_rate: opts
                .cell_flips
                .then(|| if pairs > 0 { self.flip_sum / pairs as f64 } else { 0.0 }),
        };
        PathResult {
            stats,
            coverage: self.coverage,
            frames: self.frames,
        }
    }
}

/// One snap mode of a walk: its totals and each cascade's previous window.
struct ModeState {
    totals: PathTotals,
    prev: Vec<Option<Window>>,
}

impl ModeState {
    fn new(snapped: bool, m: usize) -> Self {
        ModeState {
            totals: PathTotals::new(snapped, m),
            prev: vec![None; m],
        }
    }

    /// Coverage: the slice and the window are convex, so the slice's light-space footprint is
    /// the hull of its corners; checking the 8 corners is exact.
    #[inline]
    fn cover(&mut self, i: usize, w: &Window, corners: &[DVec2; 8], ct: &CornerTexels, resolution: u32) {
        let n = resolution as f64;
        let o = w.origin_texels;
        // Smallest margin over the corners, from the extreme corners alone: `x - o` and
        // `n - x` are monotone in x under round-to-nearest, so the extreme of the rounded
        // margins is the rounded margin of the extreme: bit-identical to a per-corner minimum.
        let slack = (ct.lo.x - o.x)
            .min(n - (ct.hi.x - o.x))
            .min(ct.lo.y - o.y)
            .min(n - (ct.hi.y - o.y));
        let cov = &mut self.totals.coverage;
        cov.min_slack_texels[i] = cov.min_slack_texels[i].min(slack);
        // Every corner's tolerance is at least 1e-9, so unless the worst margin is below
        // -1e-9 no corner can count as outside and the per-corner pass is skipped.
        if -slack > 1e-9 {
            for c in corners {
                self.totals
                    .corner(i, w.texel_coords(*c), n, (*c / w.texel).abs().max_element());
            }
        }
    }

    /// Shimmer between this cascade's previous window and `w`.
    #[inline]
    fn shimmer(&mut self, t: usize, i: usize, w: &Window, probe_xy: &[DVec2], opts: ShimmerOptions) {
        let Some(p) = self.prev[i] else {
            return;
        };
        let same_size = w.texel == p.texel;
        // x / x is exactly 1, so an unchanged size gives exactly 0 without the divisions.
        let size_change = if same_size {
            0.0
        } else {
            ((w.texel.x / p.texel.x - 1.0).abs()).max((w.texel.y / p.texel.y - 1.0).abs())
        };
        let closed_form = same_size && !opts.probe_drift;
        let (ms, mx_sq, flips) = if closed_form && !opts.cell_flips {
            let ms = closed_form_drift(&p, w);
            (ms, ms, None)
        } else {
            per_probe(&p, w, probe_xy, closed_form, opts.cell_flips)
        };
        self.totals.size_change(size_change);
        self.totals.drift(t, i, size_change, (ms, mx_sq, flips), opts);
    }
}

/// S3 of a same-size window pair without probes: the grid translates, so every point drifts
/// by the wrapped origin difference. Returns the squared drift.
#[inline]
fn closed_form_drift(p: &Window, w: &Window) -> f64 {
    let d = DVec2::new(
        wrap(p.origin_texels.x - w.origin_texels.x),
        wrap(p.origin_texels.y - w.origin_texels.y),
    );
    d.length_squared()
}

/// S3 between windows `p` and `w` as (mean square, largest square) over the probes, or from
/// the closed form when `closed_form` says it holds; with `cell_flips`, S4 too. (Squares
/// throughout: `DVec2::length` is the root of `length_squared`, taken once at the end.)
#[inline(never)]
fn per_probe(
    p: &Window,
    w: &Window,
    probe_xy: &[DVec2],
    closed_form: bool,
    cell_flips: bool,
) -> (f64, f64, Option<f64>) {
    let (mut ss, mut pmx_sq, mut flipped) = (0.0, 0.0f64, 0usize);
    for q in probe_xy {
        let s0 = p.texel_coords(*q);
        let s1 = w.texel_coords(*q);
        let d = DVec2::new(wrap(s1.x - s0.x), wrap(s1.y - s0.y));
        let d2 = d.length_squared();
        ss += d2;
        pmx_sq = pmx_sq.max(d2);
        // Sampled texel centres in light space, and how far they moved in texels of the
        // current window.
        let c0 = (p.origin_texels + s0.floor() + 0.5) * p.texel;
        let c1 = (w.origin_texels + s1.floor() + 0.5) * w.texel;
        let moved = ((c1 - c0) / w.texel).abs();
        if moved.x >= 0.5 || moved.y >= 0.5 {
            flipped += 1;
        }
    }
    let count = probe_xy.len().max(1) as f64;
    let (ms, mx_sq) = if closed_form {
        let ms = closed_form_drift(p, w);
        (ms, ms)
    } else {
        (ss / count, pmx_sq)
    };
    (ms, mx_sq, cell_flips.then(|| flipped as f64 / count))
}

/// The walk behind [`along_path`] and [`along_path_both`]: per frame, the camera's light-space
/// frame and each slice's corners are computed once for all modes; so are the corners' texel
/// coordinates whenever the modes' windows have the same texel size (always, in the [`Rig`]).
fn walk<const K: usize>(
    rig: &Rig,
    poses: &[CameraPose],
    probes: &[Vec<DVec3>],
    modes: [bool; K],
    opts: ShimmerOptions,
) -> [PathResult; K] {
    let m = rig.cascade_count();
    let mut probe_xy: Vec<Vec<DVec2>> = if needs_probes(rig, opts) {
        probes
            .iter()
            .map(|ps| ps.iter().map(|p| rig.light.to_light_xy(*p)).collect())
            .collect()
    } else {
        Vec::new()
    };
    // A cascade without probes measures 0 wherever probes are needed.
    probe_xy.resize(m, Vec::new());
    let mut states = modes.map(|snapped| ModeState::new(snapped, m));
    for (t, pose) in poses.iter().enumerate() {
        let lp = LightPose::new(&rig.light, pose);
        for (i, (slice, probe_xy)) in rig.slices.iter().zip(&probe_xy).enumerate() {
            let corners = lp.corners(&rig.lens, slice.near, slice.far);
            let bounds = crate::cascades::bounds_2d(&corners);
            let mut shared: Option<CornerTexels> = None;
            for st in &mut states {
                let w = rig.window(i, &lp, st.totals.snapped);
                if matches!(&shared, Some(ct) if ct.texel != w.texel) {
                    shared = None;
                }
                let ct = shared.get_or_insert_with(|| CornerTexels::new(&corners, bounds, w.texel));
                st.cover(i, &w, &corners, ct, rig.resolution);
                st.shimmer(t, i, &w, probe_xy, opts);
                st.prev[i] = Some(w);
            }
        }
    }
    states.map(|st| st.totals.finish(opts))
}

/// One snap mode along the path for any rig, including engine presets whose light basis moves
/// with the camera (each probe is read through each frame's basis) or whose selection interval
/// reaches outside the fitted slice (coverage then checks both, via [`Rig::coverage`]).
fn along_path_general(
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
    let no_probes: Vec<DVec3> = Vec::new();
    // Each cascade's basis in the previous frame (only tracked when it can change).
    let mut prev_basis: Vec<LightBasis> = vec![rig.light; m];
    let mut st = ModeState::new(snapped, m);
    for (t, pose) in poses.iter().enumerate() {
        let lp = LightPose::new(&rig.light, pose);
        for (i, prev_basis) in prev_basis.iter_mut().enumerate() {
            let w = rig.window(i, &lp, snapped);
            st.totals.add_coverage(i, rig.coverage(i, &lp, &w));
            let basis = if fixed { rig.light } else { rig.basis(i, &lp) };
            if let Some(p) = st.prev[i] {
                let size_change = ((w.texel.x / p.texel.x - 1.0).abs()).max((w.texel.y / p.texel.y - 1.0).abs());
                let pb = *prev_basis;
                let closed_form = w.texel == p.texel && (fixed || pb == basis) && !opts.probe_drift;
                let drift = if closed_form && !opts.cell_flips {
                    let ms = closed_form_drift(&p, &w);
                    (ms, ms, None)
                } else if fixed {
                    per_probe(
                        &p,
                        &w,
                        probe_xy.get(i).map_or(&[][..], |v| &v[..]),
                        closed_form,
                        opts.cell_flips,
                    )
                } else {
                    let ps = probes.get(i).unwrap_or(&no_probes);
                    per_probe_moving_basis(&p, &w, ps, (&pb, &basis), closed_form, opts.cell_flips)
                };
                st.totals.size_change(size_change);
                st.totals.drift(t, i, size_change, drift, opts);
            }
            st.prev[i] = Some(w);
            *prev_basis = basis;
        }
    }
    st.totals.finish(opts)
}

/// [`per_probe`] for a basis that moved between the frames: each frame reads a probe through
/// its own basis. The previous texel centre is a line along the previous light direction; its
/// point at the probe's depth is measured against the current texel centre in the current basis.
fn per_probe_moving_basis(
    p: &Window,
    w: &Window,
    probes: &[DVec3],
    (pb, basis): (&LightBasis, &LightBasis),
    closed_form: bool,
    cell_flips: bool,
) -> (f64, f64, Option<f64>) {
    let (mut ss, mut pmx_sq, mut flipped) = (0.0, 0.0f64, 0usize);
    for q in probes {
        let s0 = p.texel_coords(pb.to_light_xy(*q));
        let s1 = w.texel_coords(basis.to_light_xy(*q));
        let d = DVec2::new(wrap(s1.x - s0.x), wrap(s1.y - s0.y));
        let d2 = d.length_squared();
        ss += d2;
        pmx_sq = pmx_sq.max(d2);
        let c0 = (p.origin_texels + s0.floor() + 0.5) * p.texel;
        let c1 = (w.origin_texels + s1.floor() + 0.5) * w.texel;
        let c0_world = pb.x * c0.x + pb.y * c0.y + pb.z * pb.z.dot(*q);
        let moved = ((c1 - basis.to_light_xy(c0_world)) / w.texel).abs();
        if moved.x >= 0.5 || moved.y >= 0.5 {
            flipped += 1;
        }
    }
    let count = probes.len().max(1) as f64;
    let (ms, mx_sq) = if closed_form {
        let ms = closed_form_drift(p, w);
        (ms, ms)
    } else {
        (ss / count, pmx_sq)
    };
    (ms, mx_sq, cell_flips.then(|| flipped as f64 / count))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inlined rounding against `f64::round`, bit for bit, on ties, signed zeros, the
    /// 2^52 boundary, huge values and random numbers of every magnitude.
    #[test]
    fn round_half_away_is_bit_identical_to_f64_round() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            4503599627370496.0,
            9007199254740993.0,
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut rng = crate::rng::SplitMix64::new(11);
        for _ in 0..200_000 {
            let x = rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-12.0, 18.0));
            xs.push(x);
            xs.push(x.trunc() + 0.5);
        }
        for x in xs {
            assert_eq!(round_half_away(x).to_bits(), x.round().to_bits(), "{x:e}");
            assert_eq!(wrap(x).to_bits(), (x - x.round()).to_bits(), "{x:e}");
        }
        assert!(round_half_away(f64::NAN).is_nan());
    }
}
