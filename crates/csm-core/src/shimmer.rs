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
//!
//! The walk along the path is [`crate::walk::walk`]; [`crate::rig_path::RigPath`] is the exact f64 rig as a
//! [`crate::walk::PathModel`], the binary32 pipeline is the other ([`crate::precision`]).

/// `x - round(x)`, in [-0.5, 0.5].
pub fn wrap(x: f64) -> f64 {
    x - round_half_away(x)
}

/// `f64::round` (ties away from zero), bit for bit, without the libm call that baseline x86-64
/// makes for it: this sits in the innermost shimmer loops (and snaps every window).
///
/// For `|x| < 2^52` it needs neither a branch nor an integer conversion: adding and subtracting
/// 2^52 rounds `|x|` to a whole number (every sum in [2^52, 2^53) is one), one less when that
/// rounded up gives `⌊|x|⌋`; `|x| − ⌊|x|⌋` is exact, and adding 1 when it is at least ½ rounds
/// half away from zero; the result carries the sign of x (round(−0.3) is −0.0).
#[inline]
pub(crate) fn round_half_away(x: f64) -> f64 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    let a = x.abs();
    // At 2^52 and beyond every double is an integer (and NaN/inf fall through too).
    if a.is_nan() || a >= TWO_52 {
        return x.round();
    }
    let r = (a + TWO_52) - TWO_52;
    let fl = if r > a { r - 1.0 } else { r };
    let up = if a - fl >= 0.5 { 1.0 } else { 0.0 };
    (fl + up).copysign(x)
}

/// `f64::floor`, bit for bit, without the libm call that baseline x86-64 makes for it: it
/// runs once per probe, axis, frame and snap mode.
#[inline]
pub(crate) fn floor_exact(x: f64) -> f64 {
    if x.is_nan() || x.abs() >= 4_503_599_627_370_496.0 {
        return x.floor();
    }
    // Truncation toward zero is exact here; one less when that rounded up (negative x).
    let t = (x as i64) as f64;
    let r = if t > x { t - 1.0 } else { t };
    // floor(-0.0) is -0.0 and floor(0.3) is +0.0: the result carries the sign of x.
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

    /// Adds another path's coverage of the same cascades: violations add up, the worst miss and
    /// the smallest slack take the extreme.
    pub fn merge(&mut self, other: &Coverage) {
        for i in 0..self.violations.len() {
            self.violations[i] += other.violations[i];
            self.worst_texels[i] = self.worst_texels[i].max(other.worst_texels[i]);
            self.min_slack_texels[i] = self.min_slack_texels[i].min(other.min_slack_texels[i]);
        }
    }
}

/// What to compute along the path.
/// Per-frame rows kept for a path of this many frames at most: a longer path keeps every
/// `frame_row_stride(frames)`-th frame, so its rows (and `shimmer.csv`, and the figure) stay
/// bounded whatever the frame count. Summaries always use every frame.
pub const MAX_FRAME_ROWS: usize = 1_000;

/// 1 up to [`MAX_FRAME_ROWS`] frames; then the smallest stride that keeps at most that many.
pub fn frame_row_stride(frames: usize) -> usize {
    frames.div_ceil(MAX_FRAME_ROWS).max(1)
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShimmerOptions {
    /// Evaluate S4 (cell flips) per probe.
    pub cell_flips: bool,
    /// Evaluate S3 per probe even where the closed form applies (an independent check).
    pub probe_drift: bool,
    /// Keep the per-frame rows.
    pub frame_rows: bool,
}

/// Result of one pass along the path for one snap mode.
#[derive(Debug, Clone, PartialEq)]
pub struct PathResult {
    pub stats: ShimmerStats,
    pub coverage: Coverage,
    pub frames: Vec<FrameShimmer>,
    /// Crawl and jumps, when the light moves (None under a still light).
    pub light: Option<LightStats>,
    /// Cached cascades, when the walk held some cascade between updates
    /// ([`crate::walk::Cadence`]); None otherwise.
    pub stale: Option<StaleStats>,
}

/// What cached cascades cost along a path, for one snap mode, per cascade. A cascade with
/// cadence `k` is rendered at every `k`-th frame and keeps its window in between; a frame in
/// which it keeps an earlier window is *stale*.
///
/// * **Stale coverage violations**: stale frames in which some corner of the current slice
///   lies outside the held window (the same corner test and tolerance as [`Coverage`]).
/// * **Stale margin**: the smallest growth of the held window, in its texels on every side,
///   that would have covered the slice in every stale frame: the largest distance a corner got
///   outside, over the violated stale frames (0 without one). `margin_world` is that growth
///   in world units (times the held window's larger texel side).
/// * **Update drift**: S3 over the frame pairs at which the cascade was rendered again (a held
///   window does not move, so the pairs between updates drift by 0): RMS and largest.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct StaleStats {
    /// The cadence of each cascade (1: every frame).
    pub every: Vec<usize>,
    /// Frames walked.
    pub frames: usize,
    pub stale_frames: Vec<u64>,
    pub violations: Vec<u64>,
    pub margin_texels: Vec<f64>,
    pub margin_world: Vec<f64>,
    pub update_drift_rms: Vec<f64>,
    pub update_drift_max: Vec<f64>,
    /// Frame pairs at an update of the cascade.
    pub update_pairs: Vec<u64>,
}

impl StaleStats {
    /// Adds another path's stale statistics of the same cascades: frames and violations add
    /// up, the margins and the update drift take the worst path's.
    pub fn merge(&mut self, other: &StaleStats) {
        self.frames += other.frames;
        for i in 0..self.violations.len() {
            self.stale_frames[i] += other.stale_frames[i];
            self.violations[i] += other.violations[i];
            self.margin_texels[i] = self.margin_texels[i].max(other.margin_texels[i]);
            self.margin_world[i] = self.margin_world[i].max(other.margin_world[i]);
            self.update_drift_rms[i] = self.update_drift_rms[i].max(other.update_drift_rms[i]);
            self.update_drift_max[i] = self.update_drift_max[i].max(other.update_drift_max[i]);
            self.update_pairs[i] += other.update_pairs[i];
        }
    }
}

/// Crawl and jumps of a moving light along the path, for one snap mode (texels; see
/// `docs/metrics.md`).
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct LightStats {
    /// RMS of S3 over the frame pairs whose used light direction did not change.
    pub crawl_rms: f64,
    /// Largest S3 over those pairs.
    pub crawl_max: f64,
    /// Largest move of a world-fixed probe's texel coordinates (not wrapped) over the pairs
    /// at an update of the used light direction.
    pub jump_max: f64,
    /// Frame pairs (times cascades) at an update.
    pub update_pairs: usize,
    /// Per cascade: crawl RMS and largest jump.
    pub cascade_crawl_rms: Vec<f64>,
    pub cascade_jump_max: Vec<f64>,
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
            assert_eq!(floor_exact(x).to_bits(), x.floor().to_bits(), "{x:e}");
            assert_eq!(round_half_away(x).to_bits(), x.round().to_bits(), "{x:e}");
            assert_eq!(wrap(x).to_bits(), (x - x.round()).to_bits(), "{x:e}");
        }
        assert!(round_half_away(f64::NAN).is_nan());
        assert!(floor_exact(f64::NAN).is_nan());
    }
}
