//! The one walk along a camera path: every shimmer and coverage measurement goes through it.
//!
//! A pipeline (the exact f64 rig with a fixed light basis, a rig whose basis follows the
//! camera, the emulated binary32 pipeline) implements [`PathModel`]: where cascade `i`'s window
//! is in a frame, whether a slice corner lies inside it, and where a world-fixed probe lands in
//! it (its texel coordinates and the centre of the texel it samples). [`walk`] runs the model
//! over the poses for one or several snap modes at once and accumulates, per mode, one
//! [`PathTotals`]: coverage, S1 size change, S3 sub-texel drift, S4 cell flips and, for the
//! binary32 pipeline, S7 lookup error. The metric definitions are in [`crate::shimmer`] and
//! [`crate::precision`]; units are texels throughout.

use std::borrow::Borrow;

use glam::DVec2;

use crate::geometry::CameraPose;
use crate::shimmer::{wrap, Coverage, FrameShimmer, LightStats, PathResult, ShimmerOptions, ShimmerStats, StaleStats};

/// Cached cascades: how often each cascade is rendered again. Cascade `i` is updated at the
/// frames `t` of the path (counted from the path's first frame, `first_frame + t` for a walk
/// of a part of it) with `t % every[i] == 0`, and between two updates it keeps the window (and
/// the map) of its last update. A cascade without an entry, or with 1, is updated every frame;
/// an empty `every` is the uncached walk. The first frame a walk sees is always rendered.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Cadence<'a> {
    pub every: &'a [usize],
    /// The path index of the walk's first pose.
    pub first_frame: usize,
}

impl Cadence<'_> {
    /// Every cascade every frame: today's walk.
    pub const EVERY_FRAME: Cadence<'static> = Cadence {
        every: &[],
        first_frame: 0,
    };

    /// Whether cascade `i` is rendered again in frame `t` of the walk.
    #[inline]
    pub fn updates(&self, i: usize, t: usize) -> bool {
        self.every
            .get(i)
            .is_none_or(|&k| k <= 1 || (self.first_frame + t) % k == 0)
    }

    /// True when some cascade is held between frames.
    pub fn caches(&self) -> bool {
        self.every.iter().any(|&k| k > 1)
    }
}

/// Where one probe lands in one window: its texel coordinates `s` (0 at the window's minimum
/// edge, N at the maximum) and the centre of the texel it samples, in the model's light-space
/// x/y of that frame. `world` is that centre moved back to world space at the probe's light
/// depth, for models whose basis turns between frames (zero otherwise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landing {
    pub s: DVec2,
    pub centre: DVec2,
    pub world: glam::DVec3,
}

/// A cascade pipeline as the walker sees it.
pub trait PathModel {
    /// Values of one cascade in one frame that every snap mode shares (slice corners, the
    /// cascade's light basis, ...), computed once per frame and cascade.
    type Shared;
    /// One cascade's window in one frame, as the pipeline holds it.
    type Win: Clone;
    /// True when a frame pair in which no probe is served in both frames says nothing about
    /// drift (it is skipped); false when such a pair counts as zero drift.
    const SKIP_UNSERVED: bool;

    fn cascade_count(&self) -> usize;
    /// Whether [`PathModel::land`] must run with these options (S3 or S4 per probe).
    fn probes_needed(&self, opts: ShimmerOptions) -> bool;
    /// Starts frame `t` at camera pose `pose`.
    fn begin_frame(&mut self, t: usize, pose: &CameraPose);
    fn shared(&self, i: usize) -> Self::Shared;
    fn window(&self, i: usize, shared: &mut Self::Shared, snapped: bool) -> Self::Win;
    /// The window's texel size along light x and y (world units).
    fn texel(w: &Self::Win) -> DVec2;
    /// Coverage of cascade `i`'s slice corners by `w`, added to `totals`.
    fn cover(&self, i: usize, shared: &mut Self::Shared, w: &Self::Win, totals: &mut PathTotals);
    /// Squared S3 of the pair `(p, w)` without probes, when the grid only translated.
    fn closed_form(&self, p: &Self::Win, w: &Self::Win) -> Option<f64>;
    /// Where each of cascade `i`'s probes lands in `w` (None for a probe `w` does not serve),
    /// into `out`, which arrives empty. May add per-probe errors (S7) to `totals`.
    fn land(
        &self,
        i: usize,
        shared: &Self::Shared,
        w: &Self::Win,
        out: &mut Vec<Option<Landing>>,
        totals: &mut PathTotals,
    );
    /// The sampled-texel centre of a landing in an earlier window, in `w`'s light space.
    fn centre_in(&self, w: &Self::Win, earlier: &Landing) -> DVec2;
    /// True when every probe lands in `w` exactly as in `p` (the same cascade's window one
    /// frame earlier): the walk then keeps the earlier landings and counts no drift and no
    /// flip, which is what the kernels compute for equal landings. False unless known.
    fn same_landings(&self, _p: &Self::Win, _w: &Self::Win) -> bool {
        false
    }
    /// True when [`PathModel::land_centres`] serves this walk: every probe is served in every
    /// window, [`PathModel::centre_in`] of a landing is its own centre, and
    /// [`PathModel::land`] is a function of the cascade and the window alone (it reads no
    /// frame state and adds nothing to the totals), so the walk may land a window of an
    /// earlier frame later, or not at all. The walk then lands only the texel centres when a
    /// frame pair needs nothing else (S3 in closed form, S4 asked for).
    fn lands_centres(&self) -> bool {
        false
    }
    /// The centres of the sampled texels where cascade `i`'s probes land in `w`, into `out`
    /// (which arrives empty): the `centre` of each [`PathModel::land`] landing, bit for bit.
    /// Called only when [`PathModel::lands_centres`].
    fn land_centres(&self, _i: usize, _w: &Self::Win, _out: &mut Vec<DVec2>) {
        unreachable!("land_centres without lands_centres")
    }
    /// S4 of cascade `i` between `p` (the same cascade's window one frame earlier) and `w` from
    /// the texels the probes sample, for a model that [`PathModel::lands_centres`]:
    /// `Some((flipped, served))`, the counts [`centre_flip_kernel`] gives for the centres of
    /// both windows, bit for bit, with `floors` then holding `w`'s sampled texels (whatever the
    /// model keeps; `p`'s on entry when `held`). None, with `floors` untouched, when the model
    /// cannot tell this pair's flips that way (the walk then lands the centres).
    fn floor_flips(
        &self,
        _i: usize,
        _p: &Self::Win,
        _w: &Self::Win,
        _held: bool,
        _floors: &mut Vec<f64>,
    ) -> Option<(usize, usize)> {
        None
    }
    /// When every probe of cascade `i` lands in `w` on the texel centre it landed on in `p` (the
    /// same cascade's window one frame earlier, `p` and `w` different), bit for bit: the number
    /// of probes (all served). None unless known without landing them. Called only when
    /// [`PathModel::lands_centres`].
    fn unchanged_centres(&self, _i: usize, _p: &Self::Win, _w: &Self::Win) -> Option<usize> {
        None
    }
    /// True when the light used for the shadows can change along the path (a moving light):
    /// the walk then splits the frame pairs into crawl and jumps.
    fn light_moves(&self) -> bool {
        false
    }
    /// True when the light used in the current frame differs from the previous frame's (an
    /// update; see [`crate::light_motion`]).
    fn light_updated(&self) -> bool {
        false
    }
}

/// Running totals of one snap mode along a path: coverage, S1, S3, S4, S7 and the per-frame
/// rows.
#[derive(Debug, Clone)]
pub struct PathTotals {
    snapped: bool,
    coverage: Coverage,
    sum_ms: f64,
    pairs: usize,
    /// Largest squared S3: `sqrt` is monotone, so the largest drift is its root (one square
    /// root per path instead of one per frame pair, bit-identical).
    max_drift_sq: f64,
    jitter: f64,
    flip_sum: f64,
    frames: Vec<FrameShimmer>,
    /// S7 per cascade: sum of squares, largest, count.
    pub(crate) lookup_sq: Vec<f64>,
    pub(crate) lookup_max: Vec<f64>,
    pub(crate) lookup_count: Vec<usize>,
    /// A moving light: S3 over the frame pairs between updates (mean squares summed, pairs,
    /// largest square), and the largest squared probe move at an update and the update pairs.
    light: Option<LightTotals>,
    /// Cached cascades (a [`Cadence`] that holds some cascade): the stale frames' coverage and
    /// the drift at updates.
    stale: Option<StaleTotals>,
}

/// What holding cascades between updates costs, accumulated along the path per cascade (see
/// [`StaleStats`]).
#[derive(Debug, Clone, Default)]
struct StaleTotals {
    every: Vec<usize>,
    frames: usize,
    stale_frames: Vec<u64>,
    violations: Vec<u64>,
    margin_texels: Vec<f64>,
    margin_world: Vec<f64>,
    update_sum_ms: Vec<f64>,
    update_pairs: Vec<u64>,
    update_max_sq: Vec<f64>,
}

impl StaleTotals {
    fn new(every: &[usize], m: usize) -> Self {
        StaleTotals {
            every: (0..m).map(|i| every.get(i).copied().unwrap_or(1).max(1)).collect(),
            frames: 0,
            stale_frames: vec![0; m],
            violations: vec![0; m],
            margin_texels: vec![0.0; m],
            margin_world: vec![0.0; m],
            update_sum_ms: vec![0.0; m],
            update_pairs: vec![0; m],
            update_max_sq: vec![0.0; m],
        }
    }

    /// One stale frame of cascade `i`: the held window (texel size `texel`) covered the
    /// current slice as `c` says.
    fn stale_frame(&mut self, i: usize, c: &FrameCoverage, texel: DVec2) {
        self.stale_frames[i] += 1;
        if c.violations > 0 {
            self.violations[i] += 1;
            // The window grown by this many texels on every side holds every corner.
            let deficit = (-c.min_slack_texels).max(0.0);
            self.margin_texels[i] = self.margin_texels[i].max(deficit);
            self.margin_world[i] = self.margin_world[i].max(deficit * texel.max_element());
        }
    }

    fn finish(self) -> StaleStats {
        StaleStats {
            every: self.every,
            frames: self.frames,
            stale_frames: self.stale_frames,
            violations: self.violations,
            margin_texels: self.margin_texels,
            margin_world: self.margin_world,
            update_drift_rms: self
                .update_sum_ms
                .iter()
                .zip(&self.update_pairs)
                .map(|(&s, &n)| if n > 0 { (s / n as f64).sqrt() } else { 0.0 })
                .collect(),
            update_drift_max: self.update_max_sq.iter().map(|x| x.sqrt()).collect(),
            update_pairs: self.update_pairs,
        }
    }
}

/// Crawl and jumps of a moving light, accumulated along the path (see [`PathTotals`]), in
/// all and per cascade.
#[derive(Debug, Clone, Default)]
struct LightTotals {
    crawl_sum_ms: f64,
    crawl_pairs: usize,
    crawl_max_sq: f64,
    jump_max_sq: f64,
    update_pairs: usize,
    cascade_crawl_sum_ms: Vec<f64>,
    cascade_crawl_pairs: Vec<usize>,
    cascade_jump_max_sq: Vec<f64>,
}

/// Slice corners outside a window, accumulated over corners (and frames).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameCoverage {
    pub violations: u64,
    /// How far outside the worst corner lies, in texels (0 when all are inside).
    pub worst_texels: f64,
    /// The smallest margin between a corner and the window edge, in texels (negative outside).
    pub min_slack_texels: f64,
}

impl Default for FrameCoverage {
    fn default() -> Self {
        FrameCoverage {
            violations: 0,
            worst_texels: 0.0,
            min_slack_texels: f64::INFINITY,
        }
    }
}

impl FrameCoverage {
    /// The one corner test: a corner at texel coordinates `s` in a window of `n` texels.
    /// `magnitude` is the size of the coordinate before the window origin was subtracted,
    /// which sets the rounding tolerance (a few ulps of it, at least 1e-9 texel).
    #[inline]
    pub fn corner(&mut self, s: DVec2, n: f64, magnitude: f64) {
        let slack = s.x.min(n - s.x).min(s.y).min(n - s.y);
        self.min_slack_texels = self.min_slack_texels.min(slack);
        let tol = 1e-9 + 8.0 * f64::EPSILON * magnitude;
        if -slack > tol {
            self.violations += 1;
            self.worst_texels = self.worst_texels.max(-slack);
        }
    }
}

impl PathTotals {
    pub fn new(snapped: bool, m: usize) -> Self {
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
            lookup_sq: vec![0.0; m],
            lookup_max: vec![0.0; m],
            lookup_count: vec![0; m],
            light: None,
            stale: None,
        }
    }

    pub fn snapped(&self) -> bool {
        self.snapped
    }

    /// One slice corner of cascade `i` (see [`FrameCoverage::corner`]).
    #[inline]
    pub fn corner(&mut self, i: usize, s: DVec2, n: f64, magnitude: f64) {
        let mut c = self.frame_coverage(i);
        c.corner(s, n, magnitude);
        self.set_coverage(i, c);
    }

    /// Cascade `i`'s coverage so far, as one [`FrameCoverage`].
    #[inline]
    fn frame_coverage(&self, i: usize) -> FrameCoverage {
        FrameCoverage {
            violations: self.coverage.violations[i],
            worst_texels: self.coverage.worst_texels[i],
            min_slack_texels: self.coverage.min_slack_texels[i],
        }
    }

    #[inline]
    fn set_coverage(&mut self, i: usize, c: FrameCoverage) {
        self.coverage.violations[i] = c.violations;
        self.coverage.worst_texels[i] = c.worst_texels;
        self.coverage.min_slack_texels[i] = c.min_slack_texels;
    }

    /// [`PathModel::cover`] of one frame of cascade `i`, added to the totals as usual and
    /// returned on its own (the same totals, bit for bit, as the direct call).
    fn cover_frame<M: PathModel>(&mut self, model: &M, i: usize, shared: &mut M::Shared, w: &M::Win) -> FrameCoverage {
        let before = self.frame_coverage(i);
        self.set_coverage(i, FrameCoverage::default());
        model.cover(i, shared, w, self);
        let frame = self.frame_coverage(i);
        self.set_coverage(
            i,
            FrameCoverage {
                violations: before.violations + frame.violations,
                worst_texels: before.worst_texels.max(frame.worst_texels),
                min_slack_texels: before.min_slack_texels.min(frame.min_slack_texels),
            },
        );
        frame
    }

    /// A smallest margin found without the per-corner test (see the f64 fixed-basis model).
    #[inline]
    pub(crate) fn slack(&mut self, i: usize, slack: f64) {
        let m = &mut self.coverage.min_slack_texels[i];
        *m = m.min(slack);
    }

    /// One frame's coverage of cascade `i`, measured separately.
    pub fn add_coverage(&mut self, i: usize, cov: FrameCoverage) {
        let c = &mut self.coverage;
        c.violations[i] += cov.violations;
        c.worst_texels[i] = c.worst_texels[i].max(cov.worst_texels);
        c.min_slack_texels[i] = c.min_slack_texels[i].min(cov.min_slack_texels);
    }

    /// S7 of one probe of cascade `i` (texels).
    #[inline]
    pub(crate) fn lookup_error(&mut self, i: usize, e: f64) {
        self.lookup_sq[i] += e * e;
        self.lookup_max[i] = self.lookup_max[i].max(e);
        self.lookup_count[i] += 1;
    }

    /// S1, S3 and S4 of one frame pair: S3 as (mean square, largest square), S4 as a share.
    #[inline]
    fn pair(
        &mut self,
        t: usize,
        i: usize,
        size_change: f64,
        (ms, mx_sq, flips): (f64, f64, Option<f64>),
        keep_row: bool,
    ) {
        if let Some(f) = flips {
            self.flip_sum += f;
        }
        self.sum_ms += ms;
        self.pairs += 1;
        self.max_drift_sq = self.max_drift_sq.max(mx_sq);
        if keep_row {
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

    /// A frame pair whose S3 has the closed form (mean square `ms`, every probe alike) and
    /// no S4 or row is asked for: what [`walk`] adds for such a pair, bit for bit (S1 `size_change`
    /// into the jitter, `ms` as both the mean and the largest square).
    #[inline]
    pub(crate) fn closed_pair(&mut self, size_change: f64, ms: f64) {
        self.jitter = self.jitter.max(size_change);
        self.sum_ms += ms;
        self.pairs += 1;
        self.max_drift_sq = self.max_drift_sq.max(ms);
    }

    /// [`PathTotals::closed_pair`] of pairs without a size change, frame by frame (`frames`
    /// of them) and within a frame cascade by cascade: `drifts[c][t]` is cascade `c`'s squared
    /// drift at the chunk's pair `t`. The same totals, bit for bit: the jitter's `max` with 0
    /// is idempotent, the sum is added in that order, and a chunk whose drifts are all +0.0
    /// leaves a sum that is not −0.0 as it is (the largest drift is then taken in the same
    /// order as well).
    pub(crate) fn closed_pairs_in_order(&mut self, frames: usize, drifts: &[Vec<f64>]) {
        if frames == 0 || drifts.is_empty() {
            return;
        }
        self.jitter = self.jitter.max(0.0);
        self.pairs += frames * drifts.len();
        let zeros = drifts
            .iter()
            .all(|d| d[..frames].iter().fold(0u64, |a, x| a | x.to_bits()) == 0);
        if zeros && self.sum_ms.to_bits() != (-0.0f64).to_bits() {
            self.max_drift_sq = self.max_drift_sq.max(0.0);
            return;
        }
        for t in 0..frames {
            for d in drifts {
                let ms = d[t];
                self.sum_ms += ms;
                self.max_drift_sq = self.max_drift_sq.max(ms);
            }
        }
    }

    pub fn finish(mut self, opts: ShimmerOptions) -> PathResult {
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
        let light = self.light.map(|l| LightStats {
            cascade_crawl_rms: l
                .cascade_crawl_sum_ms
                .iter()
                .zip(&l.cascade_crawl_pairs)
                .map(|(&s, &n)| if n > 0 { (s / n as f64).sqrt() } else { 0.0 })
                .collect(),
            cascade_jump_max: l.cascade_jump_max_sq.iter().map(|x| x.sqrt()).collect(),
            crawl_rms: if l.crawl_pairs > 0 {
                (l.crawl_sum_ms / l.crawl_pairs as f64).sqrt()
            } else {
                0.0
            },
            crawl_max: l.crawl_max_sq.sqrt(),
            jump_max: l.jump_max_sq.sqrt(),
            update_pairs: l.update_pairs,
        });
        PathResult {
            stats,
            coverage: self.coverage,
            frames: self.frames,
            light,
            stale: self.stale.map(StaleTotals::finish),
        }
    }
}

/// Squared S3 of a same-size window pair whose grid only translated: every point drifts by
/// the wrapped difference of the window origins (texel units).
#[inline]
pub fn closed_form_drift(p_origin_texels: DVec2, w_origin_texels: DVec2) -> f64 {
    let d = DVec2::new(
        wrap(p_origin_texels.x - w_origin_texels.x),
        wrap(p_origin_texels.y - w_origin_texels.y),
    );
    d.length_squared()
}

/// Whether a sampled texel centre that moved by `d` (world units, either sign) moved by half a
/// texel or more along either axis: `|d / texel| >= 0.5`, bit for bit. `inv` is `1 / texel`
/// when [`flip_divisor`] allows the shortcut: the product `|d| * inv` is within a few units in
/// the 16th digit of the quotient, so away from 0.5 it decides alike; within 1e-9 of 0.5 (or
/// for NaN) the quotient itself decides. Two divisions per probe were most of the kernel.
#[inline]
fn moved_half_texel(d: DVec2, texel: DVec2, inv: Option<DVec2>) -> bool {
    let d = d.abs();
    if let Some(inv) = inv {
        let q = d * inv;
        if (q.x - 0.5).abs() > 1e-9 && (q.y - 0.5).abs() > 1e-9 {
            return q.x >= 0.5 || q.y >= 0.5;
        }
    }
    // |x / t| == |x| / t for t > 0 (division rounds symmetrically), and the original form
    // otherwise.
    let moved = if inv.is_some() { d / texel } else { (d / texel).abs() };
    moved.x >= 0.5 || moved.y >= 0.5
}

/// `1 / texel` when the multiplication shortcut of [`moved_half_texel`] is exact in its
/// decisions: positive texel sizes whose reciprocals are normal and far from overflow.
#[inline]
pub(crate) fn flip_divisor(texel: DVec2) -> Option<DVec2> {
    let inv = DVec2::ONE / texel;
    let ok = |t: f64, i: f64| t > 0.0 && (1e-300..1e300).contains(&i);
    (ok(texel.x, inv.x) && ok(texel.y, inv.y)).then_some(inv)
}

/// The per-probe kernel: over the probes landed in both windows, the sum and the largest of
/// the squared wrapped texel-coordinate change (S3), and how many sampled texel centres moved
/// by half a texel or more along either axis, in texels of the current window (S4).
/// Returns `(sum of squares, largest square, flipped, served)`.
#[inline(never)]
fn probe_kernel<M: PathModel>(
    model: &M,
    w: &M::Win,
    prev: &[Option<Landing>],
    cur: &[Option<Landing>],
) -> (f64, f64, usize, usize) {
    let texel = M::texel(w);
    let inv = flip_divisor(texel);
    let (mut ss, mut mx_sq, mut flipped, mut served) = (0.0, 0.0f64, 0usize, 0usize);
    for (a, b) in prev.iter().zip(cur) {
        let (Some(a), Some(b)) = (a, b) else {
            continue;
        };
        served += 1;
        let d = DVec2::new(wrap(b.s.x - a.s.x), wrap(b.s.y - a.s.y));
        let d2 = d.length_squared();
        ss += d2;
        mx_sq = mx_sq.max(d2);
        if moved_half_texel(b.centre - model.centre_in(w, a), texel, inv) {
            flipped += 1;
        }
    }
    (ss, mx_sq, flipped, served)
}

/// [`probe_kernel`]'s S4 part alone, for a pair whose S3 has the closed form:
/// `(flipped, served)`, the same counts bit for bit.
#[inline(never)]
fn flip_kernel<M: PathModel>(
    model: &M,
    w: &M::Win,
    prev: &[Option<Landing>],
    cur: &[Option<Landing>],
) -> (usize, usize) {
    let texel = M::texel(w);
    let inv = flip_divisor(texel);
    let (mut flipped, mut served) = (0usize, 0usize);
    for (a, b) in prev.iter().zip(cur) {
        let (Some(a), Some(b)) = (a, b) else {
            continue;
        };
        served += 1;
        flipped += moved_half_texel(b.centre - model.centre_in(w, a), texel, inv) as usize;
    }
    (flipped, served)
}

/// [`flip_kernel`] on the texel centres alone (a model that [`PathModel::lands_centres`]):
/// `(flipped, served)`, the same counts bit for bit.
#[inline(never)]
fn centre_flip_kernel(texel: DVec2, prev: &[DVec2], cur: &[DVec2]) -> (usize, usize) {
    let inv = flip_divisor(texel);
    let served = prev.len().min(cur.len());
    let Some(k) = inv else {
        let flipped = prev
            .iter()
            .zip(cur)
            .filter(|&(a, b)| moved_half_texel(*b - *a, texel, inv))
            .count();
        return (flipped, served);
    };
    // [`moved_half_texel`] with its shortcut spelled out, without branches: the product
    // decides unless some axis is within 1e-9 of half a texel (or NaN); then the function
    // itself decides every probe again.
    let (mut flipped, mut unsure) = (0usize, false);
    for (a, b) in prev.iter().zip(cur) {
        let (qx, qy) = ((b.x - a.x).abs() * k.x, (b.y - a.y).abs() * k.y);
        // (NaN is unsure too: it fails `> 1e-9`.)
        let sure = ((qx - 0.5).abs() > 1e-9) & ((qy - 0.5).abs() > 1e-9);
        unsure |= !sure;
        flipped += usize::from((qx >= 0.5) | (qy >= 0.5));
    }
    if unsure {
        flipped = prev
            .iter()
            .zip(cur)
            .filter(|&(a, b)| moved_half_texel(*b - *a, texel, inv))
            .count();
    }
    (flipped, served)
}

/// The largest squared move of a probe's texel coordinates, not wrapped, over the probes
/// served in both windows: how far a world-fixed point moved within the map (a jump, when the
/// light was updated between the two frames).
#[inline(never)]
fn jump_kernel(prev: &[Option<Landing>], cur: &[Option<Landing>]) -> f64 {
    prev.iter()
        .zip(cur)
        .filter_map(|(a, b)| Some((b.as_ref()?.s - a.as_ref()?.s).length_squared()))
        .fold(0.0, f64::max)
}

/// One snap mode of a walk: its totals, each cascade's previous window and landings.
struct ModeState<M: PathModel> {
    totals: PathTotals,
    /// Each cascade's window in the previous frame (None before the first frame)...
    prev: Vec<Option<M::Win>>,
    /// ... and where the probes landed in it. Swapped with `current` each frame, so the
    /// buffers are reused and nothing larger than a window moves per frame.
    prev_landings: Vec<Vec<Option<Landing>>>,
    current: Vec<Option<Landing>>,
    /// How many of `prev_landings` are served, once counted.
    prev_served: Vec<Option<usize>>,
    /// A model that lands centres: what is held for each cascade's previous window (its
    /// landings, its centres or neither), the centres, and this frame's.
    prev_held: Vec<Held>,
    prev_centres: Vec<Vec<DVec2>>,
    /// What [`PathModel::floor_flips`] keeps for each cascade's previous window.
    prev_floors: Vec<Vec<f64>>,
    current_centres: Vec<DVec2>,
}

/// What the walk holds of a previous window's probes (a model that lands centres).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Held {
    Nothing,
    Landings,
    Centres,
    /// What [`PathModel::floor_flips`] keeps (in `prev_floors`).
    Floors,
}

/// The one loop along a path: for every frame (in order) and every cascade, calls
/// `f(model, t, i, shared)` with the values of cascade `i` in frame `t` that every snap mode
/// shares.
pub fn each_cascade_frame<M: PathModel, P: Borrow<CameraPose>>(
    model: &mut M,
    poses: impl IntoIterator<Item = P>,
    mut f: impl FnMut(&M, usize, usize, &mut M::Shared),
) {
    let m = model.cascade_count();
    for (t, pose) in poses.into_iter().enumerate() {
        model.begin_frame(t, pose.borrow());
        for i in 0..m {
            let mut shared = model.shared(i);
            f(model, t, i, &mut shared);
        }
    }
}

/// Walks `poses` once with `model`, for each snap mode in `modes` (`true` = snapped), and
/// returns each mode's totals. Per frame and cascade, the values the modes share are computed
/// once; probes are landed only when the options need them. The poses are read once, in
/// order, and not kept: a path of any length walks in the memory of one frame (a slice, or
/// the generator [`crate::motion::poses`]).
pub fn walk<M: PathModel, P: Borrow<CameraPose>, I, const K: usize>(
    model: &mut M,
    poses: I,
    modes: [bool; K],
    opts: ShimmerOptions,
) -> [PathTotals; K]
where
    I: IntoIterator<Item = P>,
    I::IntoIter: ExactSizeIterator,
{
    walk_cached(model, poses, modes, opts, Cadence::EVERY_FRAME)
}

/// [`walk`] with cached cascades: a cascade not updated in a frame (see [`Cadence`]) keeps its
/// previous window, so its frame pair measures no drift, no size change and no flip, and its
/// coverage is that of the held window over the current slice. When the cadence holds some
/// cascade, each mode's totals also gather [`StaleStats`]: per cascade the stale frames whose
/// slice the held window does not cover, the growth that would cover them, and the drift
/// over the update pairs. [`Cadence::EVERY_FRAME`] is [`walk`], bit for bit.
pub fn walk_cached<M: PathModel, P: Borrow<CameraPose>, I, const K: usize>(
    model: &mut M,
    poses: I,
    modes: [bool; K],
    opts: ShimmerOptions,
    cadence: Cadence<'_>,
) -> [PathTotals; K]
where
    I: IntoIterator<Item = P>,
    I::IntoIter: ExactSizeIterator,
{
    let poses = poses.into_iter();
    let caches = cadence.caches();
    let m = model.cascade_count();
    let probes = model.probes_needed(opts);
    let stride = crate::shimmer::frame_row_stride(poses.len());
    let moving = model.light_moves();
    let mut states: [ModeState<M>; K] = modes.map(|snapped| ModeState {
        totals: PathTotals {
            light: moving.then(|| LightTotals {
                cascade_crawl_sum_ms: vec![0.0; m],
                cascade_crawl_pairs: vec![0; m],
                cascade_jump_max_sq: vec![0.0; m],
                ..LightTotals::default()
            }),
            stale: caches.then(|| StaleTotals::new(cadence.every, m)),
            ..PathTotals::new(snapped, m)
        },
        prev: (0..m).map(|_| None).collect(),
        prev_landings: vec![Vec::new(); m],
        current: Vec::new(),
        prev_served: vec![None; m],
        prev_held: vec![Held::Nothing; m],
        prev_centres: vec![Vec::new(); m],
        prev_floors: vec![Vec::new(); m],
        current_centres: Vec::new(),
    });
    // A model that lands centres lands nothing up front: each frame pair lands what it needs
    // (centres, or full landings when S3 has no closed form), the previous window's too when
    // they are not held.
    let centres = probes && !moving && !M::SKIP_UNSERVED && model.lands_centres();
    each_cascade_frame(model, poses, |model, t, i, shared| {
        for st in &mut states {
            // A cascade not updated this frame keeps the window of its last update.
            let held = match &st.prev[i] {
                Some(p) if !cadence.updates(i, t) => Some(p.clone()),
                _ => None,
            };
            let stale = held.is_some();
            let w = held.unwrap_or_else(|| model.window(i, shared, st.totals.snapped));
            if stale {
                let c = st.totals.cover_frame(model, i, shared, &w);
                if let Some(s) = st.totals.stale.as_mut() {
                    s.stale_frame(i, &c, M::texel(&w));
                }
            } else {
                model.cover(i, shared, &w, &mut st.totals);
            }
            if i == 0 {
                if let Some(s) = st.totals.stale.as_mut() {
                    s.frames += 1;
                }
            }
            let same = probes && st.prev[i].as_ref().is_some_and(|p| model.same_landings(p, &w));
            st.current.clear();
            if probes && !same && !centres {
                model.land(i, shared, &w, &mut st.current, &mut st.totals);
            }
            // With centres: what this frame landed (full landings or centres), if anything.
            let mut landed = Held::Nothing;
            // With centres: every probe's centre is unchanged (the number of probes).
            let mut unchanged = None;
            // With centres: S4 told from the sampled texels (`PathModel::floor_flips`).
            let mut floor_flipped = None;
            if let Some(p) = &st.prev[i] {
                let (pt, wt) = (M::texel(p), M::texel(&w));
                // x / x is exactly 1, so an unchanged size gives exactly 0 without the divisions.
                let size_change = if wt == pt {
                    0.0
                } else {
                    ((wt.x / pt.x - 1.0).abs()).max((wt.y / pt.y - 1.0).abs())
                };
                let closed = if opts.probe_drift {
                    None
                } else {
                    model.closed_form(p, &w)
                };
                if centres && !same {
                    if closed.is_none() {
                        if st.prev_held[i] != Held::Landings {
                            st.prev_landings[i].clear();
                            model.land(i, shared, p, &mut st.prev_landings[i], &mut st.totals);
                            st.prev_held[i] = Held::Landings;
                            st.prev_served[i] = None;
                        }
                        model.land(i, shared, &w, &mut st.current, &mut st.totals);
                        landed = Held::Landings;
                    } else if !opts.cell_flips {
                    } else if let Some(n) = model.unchanged_centres(i, p, &w) {
                        // The centres held for `p`, if any, are `w`'s too.
                        unchanged = Some(n);
                        landed = if st.prev_held[i] == Held::Centres {
                            Held::Centres
                        } else {
                            Held::Nothing
                        };
                    } else if let Some(f) =
                        model.floor_flips(i, p, &w, st.prev_held[i] == Held::Floors, &mut st.prev_floors[i])
                    {
                        // The flips from the sampled texels, `w`'s kept in place.
                        floor_flipped = Some(f);
                        landed = Held::Floors;
                    } else {
                        if st.prev_held[i] != Held::Centres {
                            st.prev_centres[i].clear();
                            model.land_centres(i, p, &mut st.prev_centres[i]);
                            st.prev_held[i] = Held::Centres;
                        }
                        st.current_centres.clear();
                        model.land_centres(i, &w, &mut st.current_centres);
                        landed = Held::Centres;
                    }
                }
                let pl = &st.prev_landings[i];
                let landings = &st.current;
                st.totals.jitter = st.totals.jitter.max(size_change);
                let drift = match closed {
                    Some(ms) if !opts.cell_flips => Some((ms, ms, None)),
                    // Every probe lands where it landed a frame ago (a snapped window that
                    // did not move): what the kernels give for equal landings, without them.
                    _ if same => {
                        // (Counted only when it matters: a model that lands centres holds no
                        // landings here, and skips no pair.)
                        if M::SKIP_UNSERVED
                            && *st.prev_served[i].get_or_insert_with(|| pl.iter().filter(|l| l.is_some()).count()) == 0
                        {
                            None
                        } else {
                            let (ms, mx_sq) = closed.map_or((0.0, 0.0), |ms| (ms, ms));
                            Some((ms, mx_sq, opts.cell_flips.then_some(0.0)))
                        }
                    }
                    // S3 has the closed form: the probes only count S4 flips.
                    Some(ms) => {
                        let (flipped, served) = if let Some(n) = unchanged {
                            (0, n)
                        } else if let Some(f) = floor_flipped {
                            f
                        } else if landed == Held::Centres {
                            centre_flip_kernel(M::texel(&w), &st.prev_centres[i], &st.current_centres)
                        } else {
                            flip_kernel(model, &w, pl, landings)
                        };
                        if M::SKIP_UNSERVED && served == 0 {
                            None
                        } else {
                            Some((ms, ms, Some(flipped as f64 / served.max(1) as f64)))
                        }
                    }
                    None => {
                        let (ss, mx_sq, flipped, served) = probe_kernel(model, &w, pl, landings);
                        if M::SKIP_UNSERVED && served == 0 {
                            None
                        } else {
                            let count = served.max(1) as f64;
                            let (ms, mx_sq) = closed.map_or((ss / count, mx_sq), |ms| (ms, ms));
                            Some((ms, mx_sq, opts.cell_flips.then(|| flipped as f64 / count)))
                        }
                    }
                };
                if moving {
                    let updated = model.light_updated();
                    let l = st.totals.light.as_mut().expect("a moving light keeps light totals");
                    if updated {
                        l.update_pairs += 1;
                        if probes && !same {
                            let j = jump_kernel(pl, landings);
                            l.jump_max_sq = l.jump_max_sq.max(j);
                            l.cascade_jump_max_sq[i] = l.cascade_jump_max_sq[i].max(j);
                        }
                    } else if let Some((ms, mx_sq, _)) = drift {
                        l.crawl_sum_ms += ms;
                        l.crawl_pairs += 1;
                        l.crawl_max_sq = l.crawl_max_sq.max(mx_sq);
                        l.cascade_crawl_sum_ms[i] += ms;
                        l.cascade_crawl_pairs[i] += 1;
                    }
                }
                if let Some(d) = drift {
                    if let (false, Some(s)) = (stale, st.totals.stale.as_mut()) {
                        s.update_sum_ms[i] += d.0;
                        s.update_pairs[i] += 1;
                        s.update_max_sq[i] = s.update_max_sq[i].max(d.1);
                    }
                    st.totals.pair(t, i, size_change, d, opts.frame_rows && t % stride == 0);
                }
            }
            st.prev[i] = Some(w);
            if !same {
                if !centres {
                    std::mem::swap(&mut st.prev_landings[i], &mut st.current);
                    st.prev_served[i] = None;
                } else {
                    // Landings equal to the previous window's stay held (`same`); else what
                    // this frame landed, if anything, is held for the next.
                    match landed {
                        Held::Landings => {
                            std::mem::swap(&mut st.prev_landings[i], &mut st.current);
                            st.prev_served[i] = None;
                        }
                        Held::Centres if unchanged.is_some() => {}
                        Held::Centres => std::mem::swap(&mut st.prev_centres[i], &mut st.current_centres),
                        Held::Floors | Held::Nothing => {}
                    }
                    st.prev_held[i] = landed;
                }
            }
        }
    });
    states.map(|st| st.totals)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shortcut decides exactly as the division, on moves near and far from half a texel,
    /// of every sign and magnitude, for texel sizes across the allowed range.
    #[test]
    fn the_flip_shortcut_decides_as_the_division_does() {
        let mut rng = crate::rng::SplitMix64::new(7);
        for _ in 0..400_000 {
            let texel = DVec2::new(10f64.powf(rng.range(-12.0, 9.0)), 10f64.powf(rng.range(-12.0, 9.0)));
            let pick = |rng: &mut crate::rng::SplitMix64, t: f64| match rng.range(0.0, 4.0) as u32 {
                // Exactly at, or one ulp around, half a texel.
                0 => {
                    let h = 0.5 * t;
                    [h, f64::from_bits(h.to_bits() + 1), f64::from_bits(h.to_bits() - 1)]
                        [rng.range(0.0, 2.999) as usize]
                }
                1 => rng.range(0.0, 2.0) * t,
                2 => (0.5 + rng.range(-1e-8, 1e-8)) * t,
                _ => rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-300.0, 300.0)),
            };
            let d = DVec2::new(pick(&mut rng, texel.x), pick(&mut rng, texel.y))
                * if rng.range(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
            let exact = {
                let m = (d / texel).abs();
                m.x >= 0.5 || m.y >= 0.5
            };
            assert_eq!(
                moved_half_texel(d, texel, flip_divisor(texel)),
                exact,
                "{d:?} {texel:?}"
            );
        }
    }
}
