//! Screen-weighted statistics of per-pixel aliasing for one configuration, from a
//! [`Visibility`] pass made once per camera pose.
//!
//! A lit-facing receiver pixel at view depth `d` is served by the cascade the selection rule
//! gives `d` (interval selection over the rig's selection splits, see
//! [`crate::metrics::cascade_at`]); pixels outside the split range `[C_0, C_M]` have no
//! shadow map and are not *served*. The aliasing of a served pixel is `m = T_i g` (texel size
//! of its cascade times the pixel's geometric factor, see [`crate::visibility`]).
//!
//! Because the receivers are sorted by depth once, each cascade serves a contiguous run of
//! them: a configuration costs one multiplication per pixel plus three selections
//! (`select_nth_unstable`) for the percentiles, with no geometry.
//!
//! **Percentiles** are nearest-rank: with the `n` served values sorted ascending, the
//! `p`-th percentile is the value of rank `max(1, ceil(p n / 100))`.
//!
//! **Visible aliasing** weighs each served pixel by its direct-light contrast `w = N · L`
//! (0 when the surface faces away from the light, 1 when it faces the light; stored as whole
//! multiples of `2^-24`, [`crate::visibility::contrast_weight`]), so a surface barely lit counts
//! barely and the statistics change continuously with the light direction. The weighted mean
//! is `Σ w m / Σ w`; the weighted nearest-rank `p`-th percentile is, with the values sorted
//! ascending, the first value at which the running sum of weights reaches
//! `max(1, ceil(p W / 100))` (`W = Σ w`, in whole steps: exact); the maximum is over pixels of
//! weight above 0.

use crate::metrics::cascade_at;
use crate::visibility::Visibility;

/// The screen metrics of one configuration. Fractions are of sampled pixels (receivers,
/// self-shadowed) or of served receiver pixels (undersampled). Every value is finite; all
/// statistics of `m` are 0 when no receiver pixel is served.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScreenStats {
    /// Share of sampled pixels whose nearest hit is a lit-facing receiver.
    pub receiver_fraction: f64,
    /// Share of sampled pixels whose nearest hit faces away from the light.
    pub self_shadowed_fraction: f64,
    pub aliasing_mean: f64,
    pub aliasing_p50: f64,
    pub aliasing_p95: f64,
    pub aliasing_p99: f64,
    pub aliasing_max: f64,
    /// Share of served receiver pixels with `m > 1`.
    pub undersampled_fraction: f64,
    /// The same statistics weighted by each pixel's direct-light contrast `N · L` (see the
    /// module docs); 0 when no served pixel has weight.
    pub visible_mean: f64,
    pub visible_p50: f64,
    pub visible_p95: f64,
    pub visible_p99: f64,
    pub visible_max: f64,
    /// View-depth range of the visible geometry, clipped to the bounds' split range.
    pub visible_z_lo: f64,
    pub visible_z_hi: f64,
    /// Per cascade: share of the receiver pixels it serves.
    pub cascade_pixels: Vec<f64>,
}

/// The 0-based index of the nearest-rank percentile `p` (0..=100) among `n` sorted values.
pub fn rank_index(p: f64, n: usize) -> usize {
    ((p / 100.0 * n as f64).ceil() as usize).clamp(1, n) - 1
}

/// Nearest-rank percentile `p` (0..=100) of values, reordering them; 0 for no values.
pub fn percentile(values: &mut [f64], p: f64) -> f64 {
    let n = values.len();
    if n == 0 {
        return 0.0;
    }
    *values.select_nth_unstable_by(rank_index(p, n), f64::total_cmp).1
}

/// A monotone bucket key for positive finite values in `[lo, hi]`: a positive finite f64
/// orders like its bit pattern, so `(bits - bits(lo)) >> shift` never decreases with the
/// value, and `shift` is chosen so that every key is below [`Buckets::COUNT`].
#[derive(Clone, Copy)]
struct Buckets {
    base: u64,
    shift: u32,
}

impl Buckets {
    const COUNT: usize = 4096;

    fn new(lo: f64, hi: f64) -> Self {
        let base = lo.to_bits();
        let span = hi.to_bits() - base;
        let shift = (u64::BITS - span.leading_zeros()).saturating_sub(Self::COUNT.trailing_zeros());
        Buckets { base, shift }
    }

    #[inline]
    fn key(self, m: f64) -> usize {
        ((m.to_bits() - self.base) >> self.shift) as usize
    }
}

/// For each wanted 0-based rank (increasing): its bucket and its rank inside that bucket.
fn locate(hist: &[u32], ranks: &[usize]) -> Vec<(usize, usize)> {
    let (mut bucket, mut below) = (0, 0);
    ranks
        .iter()
        .map(|&r| {
            while below + hist[bucket] as usize <= r {
                below += hist[bucket] as usize;
                bucket += 1;
            }
            (bucket, r - below)
        })
        .collect()
}

/// Exact nearest-rank values at the 0-based `ranks` (increasing) of the served values `t g`,
/// without storing or sorting them: `runs` are `(start, end, t)` ranges of receivers, `hist`
/// the counts of every value's bucket. One pass gathers the values of the wanted buckets only
/// and a selection inside each gives the exact value.
fn values_at_ranks(
    g: &[(f64, f64)],
    runs: &[(usize, usize, f64)],
    buckets: Buckets,
    hist: &[u32],
    ranks: &[usize],
) -> Vec<f64> {
    let wanted = locate(hist, ranks);
    // Bucket -> which gathered list it feeds (u8::MAX: none); the wanted buckets are few.
    let mut slot = vec![u8::MAX; Buckets::COUNT];
    let mut lists: Vec<Vec<u64>> = Vec::new();
    for &(b, _) in &wanted {
        if slot[b] == u8::MAX {
            slot[b] = lists.len() as u8;
            lists.push(Vec::with_capacity(hist[b] as usize));
        }
    }
    for &(a, b, t) in runs {
        for &(_, gk) in &g[a..b] {
            let m = t * gk;
            let s = slot[buckets.key(m)];
            if s != u8::MAX {
                lists[s as usize].push(m.to_bits());
            }
        }
    }
    wanted
        .iter()
        .map(|&(b, r)| f64::from_bits(*lists[slot[b] as usize].select_nth_unstable(r).1))
        .collect()
}

/// The whole-step weight each weighted nearest-rank percentile `p` (integer percent) must
/// reach among values of total weight `total`: `max(1, ceil(p total / 100))`.
pub fn weight_target(p: u64, total: u64) -> u64 {
    ((p as u128 * total as u128).div_ceil(100) as u64).max(1)
}

/// For each wanted weight target (increasing): its bucket and the weight below that bucket.
fn locate_weight(hist: &[u64], targets: &[u64]) -> Vec<(usize, u64)> {
    let (mut bucket, mut below) = (0, 0u64);
    targets
        .iter()
        .map(|&t| {
            while below + hist[bucket] < t {
                below += hist[bucket];
                bucket += 1;
            }
            (bucket, below)
        })
        .collect()
}

/// Exact weighted nearest-rank values for the weight `targets` (increasing) of the served
/// values `t g` with weights `w`: as [`values_at_ranks`], one pass gathers the values of the
/// wanted buckets, and a sort inside each finds the value where the running weight reaches
/// the target.
fn weighted_values_at(
    g: &[(f64, f64)],
    w: &[u32],
    runs: &[(usize, usize, f64)],
    buckets: Buckets,
    hist: &[u64],
    targets: &[u64],
) -> Vec<f64> {
    let wanted = locate_weight(hist, targets);
    let mut slot = vec![u8::MAX; Buckets::COUNT];
    let mut lists: Vec<Vec<(f64, u32)>> = Vec::new();
    for &(b, _) in &wanted {
        if slot[b] == u8::MAX {
            slot[b] = lists.len() as u8;
            lists.push(Vec::new());
        }
    }
    for &(a, b, t) in runs {
        for (&(_, gk), &wk) in g[a..b].iter().zip(&w[a..b]) {
            let m = t * gk;
            let s = slot[buckets.key(m)];
            if s != u8::MAX && wk > 0 {
                lists[s as usize].push((m, wk));
            }
        }
    }
    for l in &mut lists {
        l.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    }
    wanted
        .iter()
        .zip(targets)
        .map(|(&(b, below), &target)| {
            let mut run = below;
            let list = &lists[slot[b] as usize];
            for &(m, wk) in list {
                run += wk as u64;
                if run >= target {
                    return m;
                }
            }
            list.last().map_or(0.0, |x| x.0)
        })
        .collect()
}

/// The visible depth range clipped to `[lo, hi]`, or None when nothing visible lies in it.
pub fn visible_range(vis: &Visibility, lo: f64, hi: f64) -> Option<(f64, f64)> {
    let (a, b) = vis.depth_range?;
    let (a, b) = (a.max(lo), b.min(hi));
    (a <= b).then_some((a, b))
}

/// The runs of depth-sorted receivers each cascade serves: `(start, end, texel size)`, in
/// depth order, and the number of pixels each cascade serves.
fn served_runs(vis: &Visibility, splits: &[f64], texel: &[f64]) -> (Vec<(usize, usize, f64)>, Vec<usize>) {
    let r = &vis.receivers;
    let m = texel.len();
    let mut runs = Vec::with_capacity(m);
    let mut counts = vec![0; m];
    let start = r.partition_point(|&(d, _)| d < splits[0]);
    let end = r.partition_point(|&(d, _)| d <= splits[m]);
    let mut k = start;
    while k < end {
        let i = cascade_at(splits, r[k].0);
        // The run of pixels the same cascade serves ends at the next split (the last cascade
        // keeps its far split).
        let run_end = if i + 1 == m {
            end
        } else {
            k + r[k..end].partition_point(|&(d, _)| d < splits[i + 1])
        };
        runs.push((k, run_end, texel[i]));
        counts[i] += run_end - k;
        k = run_end.max(k + 1);
    }
    (runs, counts)
}

/// The screen metrics of a configuration with selection `splits` and texel sizes `texel`;
/// `visible` is the visible depth range already clipped (see [`visible_range`]).
pub fn stats(vis: &Visibility, splits: &[f64], texel: &[f64], visible: Option<(f64, f64)>) -> ScreenStats {
    let (runs, counts) = served_runs(vis, splits, texel);
    let g = &vis.receivers;
    let n: usize = counts.iter().sum();
    let weights = &vis.weights;
    let (t, p, wp) = if n == 0 {
        (Tally::empty(), vec![0.0; 3], vec![0.0; 3])
    } else {
        // Every served value lies in [min t * min g, max t * max g]; rounding is monotone, so
        // the bounds hold for the rounded products too, and the keys need no first pass.
        let (g_lo, g_hi) = vis.factor_range.unwrap_or((0.0, 0.0));
        let (t_lo, t_hi) = runs
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), r| (l.min(r.2), h.max(r.2)));
        let buckets = Buckets::new(t_lo * g_lo, t_hi * g_hi);
        let t = tally(vis, &runs, buckets, n);
        let wp = if t.wtotal > 0 {
            let targets = [50, 95, 99].map(|p| weight_target(p, t.wtotal));
            weighted_values_at(g, weights, &runs, buckets, &t.whist, &targets)
        } else {
            vec![0.0; 3]
        };
        let ranks = [50.0, 95.0, 99.0].map(|p| rank_index(p, n));
        let p = values_at_ranks(g, &runs, buckets, &t.hist, &ranks);
        (t, p, wp)
    };
    from_tally(vis, &counts, n, &t, [p[0], p[1], p[2]], [wp[0], wp[1], wp[2]], visible)
}

/// [`stats`] with only the per-cascade pixel shares (`cascade_pixels`) and the receiver and
/// self-shadowed fractions measured, every statistic of `m` 0: for a camera whose screen
/// statistics a level of views replaces, whose cascades still report their shares.
pub fn cascade_shares_only(vis: &Visibility, splits: &[f64], texel: &[f64]) -> ScreenStats {
    let (_, counts) = served_runs(vis, splits, texel);
    from_tally(vis, &counts, 0, &Tally::empty(), [0.0; 3], [0.0; 3], None)
}

/// A pass's statistics from its tally: `n` served pixels, `counts` per cascade, the plain and
/// weighted percentiles (p50, p95, p99) already selected.
fn from_tally(
    vis: &Visibility,
    counts: &[usize],
    n: usize,
    t: &Tally,
    plain: [f64; 3],
    weighted: [f64; 3],
    visible: Option<(f64, f64)>,
) -> ScreenStats {
    let total = vis.sample_count().max(1) as f64;
    let receivers = vis.receivers.len();
    let (mean, under) = if n == 0 {
        (0.0, 0.0)
    } else {
        (t.sum / n as f64, t.under as f64 / n as f64)
    };
    let (visible_z_lo, visible_z_hi) = visible.unwrap_or((0.0, 0.0));
    ScreenStats {
        receiver_fraction: receivers as f64 / total,
        self_shadowed_fraction: vis.self_shadowed as f64 / total,
        aliasing_mean: mean,
        aliasing_p50: plain[0],
        aliasing_p95: plain[1],
        aliasing_p99: plain[2],
        aliasing_max: t.max,
        undersampled_fraction: under,
        visible_mean: if t.wtotal > 0 { t.wsum / t.wtotal as f64 } else { 0.0 },
        visible_p50: weighted[0],
        visible_p95: weighted[1],
        visible_p99: weighted[2],
        visible_max: t.wmax,
        visible_z_lo,
        visible_z_hi,
        cascade_pixels: counts
            .iter()
            .map(|&c| {
                if receivers == 0 {
                    0.0
                } else {
                    c as f64 / receivers as f64
                }
            })
            .collect(),
    }
}

/// The whole steps of one unit of view weight: a view's weight `w` counts as
/// `round(w · VIEW_WEIGHT_STEPS)` steps, so the pooled statistics sum whole numbers exactly (in
/// any order) and a weight of 1 (a power of two) changes no rounding.
pub const VIEW_WEIGHT_STEPS: f64 = (1u64 << 20) as f64;

/// A view weight in whole steps of [`VIEW_WEIGHT_STEPS`] (at least one step).
pub fn view_weight_steps(weight: f64) -> u64 {
    ((weight * VIEW_WEIGHT_STEPS).round() as u64).max(1)
}

/// One view's part of a level's pooled screen statistics: its pass, the selection splits and
/// texel sizes of the cascades built for its pose, its visible depth range (as for [`stats`])
/// and its weight in whole steps ([`view_weight_steps`]).
#[derive(Clone, Copy)]
pub struct PoolPart<'a> {
    pub vis: &'a Visibility,
    pub splits: &'a [f64],
    pub texel: &'a [f64],
    pub visible: Option<(f64, f64)>,
    pub steps: u64,
}

/// The level's screen statistics over every view's pixels together, and each view's own.
#[derive(Debug, Clone, PartialEq)]
pub struct Pooled {
    pub level: ScreenStats,
    /// Per part, in order: exactly what [`stats`] gives for that part alone.
    pub views: Vec<ScreenStats>,
}

/// What one pass over served pixels accumulates: the histograms of the values and of the
/// contrast weights, and the sums, maxima and undersampled count.
struct Tally {
    hist: Vec<u32>,
    whist: Vec<u64>,
    sum: f64,
    max: f64,
    under: usize,
    wsum: f64,
    wtotal: u64,
    wmax: f64,
    /// Served values per [`octave`] (only when asked for; empty otherwise).
    octaves: Vec<u32>,
}

impl Tally {
    /// Nothing counted (no histogram bins).
    fn empty() -> Tally {
        Tally {
            hist: Vec::new(),
            whist: Vec::new(),
            sum: 0.0,
            max: 0.0,
            under: 0,
            wsum: 0.0,
            wtotal: 0,
            wmax: 0.0,
            octaves: Vec::new(),
        }
    }
}

/// The tally of the served `runs` of `vis` (histograms of `Buckets::COUNT` bins, or none when
/// no pixel is served). [`stats`] and the pooled statistics both count through here, so their
/// sums are equal bit for bit (the same operations in the same order).
fn tally(vis: &Visibility, runs: &[(usize, usize, f64)], buckets: Buckets, served: usize) -> Tally {
    tally_counting::<false>(vis, runs, buckets, served)
}

/// [`tally`], and with `OCTAVES` also each value's [`octave`] counted (`Tally::octaves`).
fn tally_counting<const OCTAVES: bool>(
    vis: &Visibility,
    runs: &[(usize, usize, f64)],
    buckets: Buckets,
    served: usize,
) -> Tally {
    let mut t = Tally::empty();
    if served > 0 {
        t.hist = vec![0u32; Buckets::COUNT];
        t.whist = vec![0u64; Buckets::COUNT];
        if OCTAVES {
            t.octaves = vec![0u32; OCTAVES_COUNT];
        }
    }
    let g = &vis.receivers;
    let weights = &vis.weights;
    for &(a, b, tx) in runs {
        for (&(_, gk), &wk) in g[a..b].iter().zip(&weights[a..b]) {
            let m = tx * gk;
            if OCTAVES {
                t.octaves[octave(m)] += 1;
            }
            t.sum += m;
            // A plain comparison (not f64::max, which also handles NaN): m is finite.
            t.max = if m > t.max { m } else { t.max };
            t.under += usize::from(m > 1.0);
            let key = buckets.key(m);
            t.hist[key] += 1;
            t.whist[key] += wk as u64;
            t.wtotal += wk as u64;
            t.wsum += wk as f64 * m;
            if wk > 0 && m > t.wmax {
                t.wmax = m;
            }
        }
    }
    t
}

/// One part's first pass: its served runs and their tally.
struct PartPass {
    runs: Vec<(usize, usize, f64)>,
    counts: Vec<usize>,
    n: usize,
    t: Tally,
}

fn first_pass<const OCTAVES: bool>(
    part: &PoolPart<'_>,
    runs: Vec<(usize, usize, f64)>,
    counts: Vec<usize>,
    buckets: Buckets,
) -> PartPass {
    let n = counts.iter().sum();
    let t = tally_counting::<OCTAVES>(part.vis, &runs, buckets, n);
    PartPass { runs, counts, n, t }
}

/// The weighted nearest-rank targets of one pool (the level, or one view alone): the pool's
/// bucket histograms of plain weight (every served pixel carries its view's steps) and of
/// contrast weight (`N · L` steps times the view's steps), and the six targets (p50, p95, p99
/// of each) located in them.
struct Targets {
    /// (bucket, weight below the bucket, target weight): three plain, three contrast-weighted.
    at: Vec<(usize, u128, u128)>,
    plain_total: u128,
    contrast_total: u128,
}

impl Targets {
    /// The targets of histograms `hist` (plain weight) and `whist` (contrast weight), each
    /// bucket's weight read through `as128` (the level's are 128-bit; a view's own are its
    /// counts).
    fn new<A: Copy, B: Copy>(hist: &[A], whist: &[B], a: impl Fn(A) -> u128, b: impl Fn(B) -> u128) -> Targets {
        let plain_total: u128 = hist.iter().map(|&x| a(x)).sum();
        let contrast_total: u128 = whist.iter().map(|&x| b(x)).sum();
        let mut at = Vec::with_capacity(6);
        for (k, total) in [plain_total, contrast_total].into_iter().enumerate() {
            let weight = |bucket: usize| if k == 0 { a(hist[bucket]) } else { b(whist[bucket]) };
            // The targets increase: each search goes on from where the previous one stopped.
            let (mut bucket, mut below) = (0, 0u128);
            for p in [50u128, 95, 99] {
                if total == 0 {
                    continue;
                }
                let target = (p * total).div_ceil(100).max(1);
                while below + weight(bucket) < target {
                    below += weight(bucket);
                    bucket += 1;
                }
                at.push((bucket, below, target));
            }
        }
        Targets {
            at,
            plain_total,
            contrast_total,
        }
    }

    /// Marks the wanted buckets in `slot` (their list index) and returns the number of lists.
    fn mark(&self, slot: &mut [u8]) -> usize {
        let mut lists = 0;
        for &(b, _, _) in &self.at {
            if slot[b] == u8::MAX {
                slot[b] = lists as u8;
                lists += 1;
            }
        }
        lists
    }

    /// The values at the targets from the gathered lists: `(m, contrast weight, view steps)`
    /// of every served value in the wanted buckets, sorted by value. Plain percentiles first.
    fn resolve(&self, slot: &[u8], lists: &[Vec<(f64, u32, u64)>]) -> ([f64; 3], [f64; 3]) {
        let mut out = [[0.0; 3]; 2];
        let plain = usize::from(self.plain_total > 0) * 3;
        for (k, &(b, below, target)) in self.at.iter().enumerate() {
            let weighted = k >= plain;
            let list = &lists[slot[b] as usize];
            let mut run = below;
            let mut value = 0.0;
            for &(m, wk, s) in list {
                let w = if weighted { wk as u128 * s as u128 } else { s as u128 };
                if w == 0 {
                    continue;
                }
                run += w;
                value = m;
                if run >= target {
                    break;
                }
            }
            out[usize::from(weighted)][k % 3] = value;
        }
        (out[0], out[1])
    }
}

/// The screen statistics of a level of views: every served receiver pixel of every view,
/// carrying its view's weight ([`PoolPart::steps`]), pooled into one set of statistics, and
/// each view's own statistics beside them. With equal weights the level's percentiles are the
/// nearest-rank percentiles of all views' values together, and its visible percentiles weigh
/// each pixel by its `N · L` alone; in general a pixel counts its view's steps (times its
/// contrast steps for the visible statistics), and the weighted nearest-rank percentile is the
/// first value at which the running weight reaches `max(1, ceil(p W / 100))`. Means are
/// weighted the same way; fractions are of the views' sampled (or receiver, or served) pixels,
/// each counted with its view's weight; the maxima are over every served pixel (of contrast
/// above 0 for `visible_max`); the visible depth range is the union of the views'.
///
/// Two passes over each view's receivers, whatever the number of views: one builds every
/// view's histograms on a bucket key common to all views, the second gathers the values of the
/// buckets that hold a wanted rank, of the level or of the view itself.
pub fn pool(parts: &[PoolPart<'_>]) -> Pooled {
    pool_passes::<false>(parts).0
}

/// [`pool`], with each part's first pass (its served count and, with `OCTAVES`, its values per
/// [`octave`]).
fn pool_passes<const OCTAVES: bool>(parts: &[PoolPart<'_>]) -> (Pooled, Vec<PartPass>) {
    // The bounds of every served value of every part, as in `stats`, for one common key.
    let mut lo = f64::INFINITY;
    let mut hi = 0.0f64;
    let served: Vec<_> = parts.iter().map(|p| served_runs(p.vis, p.splits, p.texel)).collect();
    for (p, (runs, _)) in parts.iter().zip(&served) {
        if let (Some((g_lo, g_hi)), false) = (p.vis.factor_range, runs.is_empty()) {
            let (t_lo, t_hi) = runs
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(l, h), r| (l.min(r.2), h.max(r.2)));
            lo = lo.min(t_lo * g_lo);
            hi = hi.max(t_hi * g_hi);
        }
    }
    let buckets = if lo <= hi {
        Buckets::new(lo, hi)
    } else {
        Buckets::new(1.0, 1.0)
    };
    let passes: Vec<PartPass> = parts
        .iter()
        .zip(served)
        .map(|(p, (runs, counts))| first_pass::<OCTAVES>(p, runs, counts, buckets))
        .collect();

    // The level's histograms and targets, and each part's own.
    let mut hist = vec![0u128; Buckets::COUNT];
    let mut whist = vec![0u128; Buckets::COUNT];
    for (p, pass) in parts.iter().zip(&passes) {
        for (k, (&h, &w)) in pass.t.hist.iter().zip(&pass.t.whist).enumerate() {
            hist[k] += h as u128 * p.steps as u128;
            whist[k] += w as u128 * p.steps as u128;
        }
    }
    let level = Targets::new(&hist, &whist, |x| x, |x| x);
    let own: Vec<Targets> = passes
        .iter()
        .map(|pass| Targets::new(&pass.t.hist, &pass.t.whist, |x| x as u128, |x| x as u128))
        .collect();

    // The second pass: every part's values in the level's wanted buckets or its own.
    let mut level_slot = vec![u8::MAX; Buckets::COUNT];
    let level_lists = level.mark(&mut level_slot);
    let mut level_values: Vec<Vec<(f64, u32, u64)>> = vec![Vec::new(); level_lists];
    let mut own_values: Vec<([f64; 3], [f64; 3])> = Vec::with_capacity(parts.len());
    for ((p, pass), targets) in parts.iter().zip(&passes).zip(&own) {
        let mut slot = vec![u8::MAX; Buckets::COUNT];
        let mut lists: Vec<Vec<(f64, u32, u64)>> = vec![Vec::new(); targets.mark(&mut slot)];
        let g = &p.vis.receivers;
        let weights = &p.vis.weights;
        for &(a, b, t) in &pass.runs {
            for (&(_, gk), &wk) in g[a..b].iter().zip(&weights[a..b]) {
                let m = t * gk;
                let key = buckets.key(m);
                let (s, l) = (slot[key], level_slot[key]);
                if s != u8::MAX {
                    lists[s as usize].push((m, wk, 1));
                }
                if l != u8::MAX {
                    level_values[l as usize].push((m, wk, p.steps));
                }
            }
        }
        for l in &mut lists {
            l.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        }
        own_values.push(targets.resolve(&slot, &lists));
    }
    for l in &mut level_values {
        l.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    }
    let level_p = level.resolve(&level_slot, &level_values);

    let views: Vec<ScreenStats> = parts
        .iter()
        .zip(&passes)
        .zip(&own_values)
        .map(|((p, pass), &(plain, weighted))| {
            from_tally(p.vis, &pass.counts, pass.n, &pass.t, plain, weighted, p.visible)
        })
        .collect();

    // The level: every count and sum weighted by its view's steps (whole numbers; the sums of
    // values are each view's own sum times its steps).
    let weighted_ratio = |num: &dyn Fn(usize) -> u128, den: &dyn Fn(usize) -> u128| {
        let (mut a, mut b) = (0u128, 0u128);
        for (k, p) in parts.iter().enumerate() {
            a += num(k) * p.steps as u128;
            b += den(k) * p.steps as u128;
        }
        (a as f64, b as f64)
    };
    let (recv, samples) = weighted_ratio(&|k| parts[k].vis.receivers.len() as u128, &|k| {
        parts[k].vis.sample_count().max(1) as u128
    });
    let (shadowed, _) = weighted_ratio(&|k| parts[k].vis.self_shadowed as u128, &|_| 0);
    let (under, served) = weighted_ratio(&|k| passes[k].t.under as u128, &|k| passes[k].n as u128);
    let sum: f64 = parts.iter().zip(&passes).map(|(p, x)| p.steps as f64 * x.t.sum).sum();
    let wsum: f64 = parts.iter().zip(&passes).map(|(p, x)| p.steps as f64 * x.t.wsum).sum();
    let cascades = passes.iter().map(|x| x.counts.len()).max().unwrap_or(0);
    let cascade_pixels = (0..cascades)
        .map(|i| {
            let (c, _) = weighted_ratio(&|k| passes[k].counts.get(i).copied().unwrap_or(0) as u128, &|_| 0);
            if recv > 0.0 {
                c / recv
            } else {
                0.0
            }
        })
        .collect();
    let visible = parts
        .iter()
        .filter_map(|p| p.visible)
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
    let (visible_z_lo, visible_z_hi) = visible.unwrap_or((0.0, 0.0));
    let level = ScreenStats {
        receiver_fraction: recv / samples,
        self_shadowed_fraction: shadowed / samples,
        aliasing_mean: if served > 0.0 { sum / served } else { 0.0 },
        aliasing_p50: level_p.0[0],
        aliasing_p95: level_p.0[1],
        aliasing_p99: level_p.0[2],
        aliasing_max: passes.iter().fold(0.0, |a, x| if x.t.max > a { x.t.max } else { a }),
        undersampled_fraction: if served > 0.0 { under / served } else { 0.0 },
        visible_mean: if level.contrast_total > 0 {
            wsum / level.contrast_total as f64
        } else {
            0.0
        },
        visible_p50: level_p.1[0],
        visible_p95: level_p.1[1],
        visible_p99: level_p.1[2],
        visible_max: passes.iter().fold(0.0, |a, x| if x.t.wmax > a { x.t.wmax } else { a }),
        visible_z_lo,
        visible_z_hi,
        cascade_pixels,
    };
    (Pooled { level, views }, passes)
}

/// Number of [`octave`]s: every finite `m >= 0` has one below it.
const OCTAVES_COUNT: usize = 2048;

/// A value's octave: `(bits(m) - 1) >> 52`, so that a normal `m` with octave `b` lies in
/// `(2^(b - 1023), 2^(b - 1022)]` and `m > 2^j` exactly when `b >= j + 1023` (0 counts in octave 0).
#[inline]
fn octave(m: f64) -> usize {
    (m.to_bits().saturating_sub(1) >> 52) as usize
}

/// `2^e` as an f64 (`e` in the normal range).
fn pow2(e: i32) -> f64 {
    f64::from_bits(((1023 + e) as u64) << 52)
}

/// Pooled statistics already computed, by their inputs up to one power-of-two factor of every
/// texel size (see [`pool_memo`]). A cache: two memos always compare equal.
#[derive(Default)]
pub struct PoolMemo {
    entries: std::sync::Mutex<std::collections::HashMap<Vec<u64>, std::sync::Arc<MemoEntry>>>,
}

impl std::fmt::Debug for PoolMemo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let n = self.entries.lock().map_or(0, |e| e.len());
        f.debug_struct("PoolMemo").field("entries", &n).finish()
    }
}

impl PartialEq for PoolMemo {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// View statistics the memo keeps at most (entries times views): about 50 MB.
const MEMO_VIEW_STATS: usize = 200_000;

/// One memo entry: the pooled statistics at the normalised texel sizes, and per part its
/// served count and, for the undersampled counts at any scale, the number of its values at or
/// above each octave (ascending octaves, those that hold values only).
struct MemoEntry {
    pooled: Pooled,
    served: Vec<u64>,
    above: Vec<Vec<(u16, u64)>>,
}

impl MemoEntry {
    /// Part `k`'s values above `2^j` (at the normalised scale).
    fn count_above(&self, k: usize, j: i32) -> u64 {
        let b = j + 1023;
        let list = &self.above[k];
        let at = list.partition_point(|&(o, _)| (o as i32) < b);
        list.get(at).map_or(0, |x| x.1)
    }
}

/// The normalising exponent of a level's texel sizes: that of the first positive texel size,
/// when every served value, at either scale, keeps far from the ends of the f64 range (so that
/// scaling by `2^e` is exact through every product, sum and quotient of [`pool`]); else None.
fn normaliser(parts: &[PoolPart<'_>]) -> Option<i32> {
    let first = parts
        .iter()
        .flat_map(|p| p.texel.iter())
        .find(|&&t| t > 0.0 && t.is_normal())?;
    let e = ((first.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    let (lo_ok, hi_ok) = (pow2(-1000), pow2(800));
    let f = pow2(-e);
    for p in parts {
        let Some((g_lo, g_hi)) = p.vis.factor_range else {
            continue;
        };
        for &t in p.texel {
            if t == 0.0 {
                continue;
            }
            for scaled in [t, t * f] {
                let (lo, hi) = (scaled * g_lo, scaled * g_hi);
                if !(lo >= lo_ok && hi <= hi_ok && scaled.is_normal()) {
                    return None;
                }
            }
        }
    }
    Some(e)
}

/// [`pool`], remembered in `memo`. Every statistic of [`pool`] but the undersampled fractions
/// scales exactly with the texel sizes when they all change by one power-of-two factor `2^e`
/// (a product `t g` of a normal result, its sums, means, maxima and percentiles are all scaled
/// by `2^e` without rounding), and the undersampled count `m > 1` is the count of normalised
/// values above `2^-e`, read from the values' octaves. So the statistics of texel sizes
/// `t · 2^e` are computed once, at `t`, for every `e`: a sweep's resolutions (powers of two)
/// share one computation, and so do settings that build the same cascades (a single
/// cascade at every λ). The result equals [`pool`]'s bit for bit; when a value could leave the
/// normal range at either scale, [`pool`] runs as is.
pub fn pool_memo(parts: &[PoolPart<'_>], memo: &PoolMemo) -> Pooled {
    let Some(e) = normaliser(parts) else {
        return pool(parts);
    };
    let f = pow2(-e);
    let texels: Vec<Vec<f64>> = parts.iter().map(|p| p.texel.iter().map(|&t| t * f).collect()).collect();
    let norm: Vec<PoolPart<'_>> = parts
        .iter()
        .zip(&texels)
        .map(|(p, t)| PoolPart { texel: t, ..*p })
        .collect();
    let key: Vec<u64> = norm
        .iter()
        .flat_map(|p| {
            let v = &p.vis.view;
            let head = [
                p.vis.receivers.as_ptr() as usize as u64,
                p.vis.receivers.len() as u64,
                p.steps,
                v.pose.position.x.to_bits(),
                v.pose.position.y.to_bits(),
                v.pose.position.z.to_bits(),
                v.light.x.to_bits(),
                v.light.y.to_bits(),
                v.light.z.to_bits(),
                p.visible.map_or(u64::MAX, |x| x.0.to_bits()),
                p.visible.map_or(u64::MAX, |x| x.1.to_bits()),
                p.splits.len() as u64,
            ];
            head.into_iter()
                .chain(p.splits.iter().map(|x| x.to_bits()))
                .chain(p.texel.iter().map(|x| x.to_bits()))
        })
        .collect();
    let found = memo.entries.lock().ok().and_then(|m| m.get(&key).cloned());
    let entry = found.unwrap_or_else(|| {
        let (pooled, passes) = pool_passes::<true>(&norm);
        let above = passes
            .iter()
            .map(|pass| {
                let mut list = Vec::new();
                let mut acc = 0u64;
                for (b, &c) in pass.t.octaves.iter().enumerate().rev() {
                    if c > 0 {
                        acc += c as u64;
                        list.push((b as u16, acc));
                    }
                }
                list.reverse();
                list
            })
            .collect();
        let entry = std::sync::Arc::new(MemoEntry {
            pooled,
            served: passes.iter().map(|p| p.n as u64).collect(),
            above,
        });
        if let Ok(mut m) = memo.entries.lock() {
            if (m.len() + 1) * parts.len().max(1) > MEMO_VIEW_STATS {
                m.clear();
            }
            m.insert(key, entry.clone());
        }
        entry
    });
    // Back to the true scale: the values times 2^e, the undersampled counts above 2^-e.
    let s = pow2(e);
    let under: Vec<u64> = (0..parts.len()).map(|k| entry.count_above(k, -e)).collect();
    let scale = |st: &ScreenStats, under: Option<f64>| ScreenStats {
        aliasing_mean: st.aliasing_mean * s,
        aliasing_p50: st.aliasing_p50 * s,
        aliasing_p95: st.aliasing_p95 * s,
        aliasing_p99: st.aliasing_p99 * s,
        aliasing_max: st.aliasing_max * s,
        undersampled_fraction: under.unwrap_or(st.undersampled_fraction),
        visible_mean: st.visible_mean * s,
        visible_p50: st.visible_p50 * s,
        visible_p95: st.visible_p95 * s,
        visible_p99: st.visible_p99 * s,
        visible_max: st.visible_max * s,
        ..st.clone()
    };
    let views = entry
        .pooled
        .views
        .iter()
        .enumerate()
        .map(|(k, st)| {
            let n = entry.served[k];
            scale(st, Some(if n == 0 { 0.0 } else { under[k] as f64 / n as f64 }))
        })
        .collect();
    let (mut u, mut n) = (0u128, 0u128);
    for (k, p) in parts.iter().enumerate() {
        u += under[k] as u128 * p.steps as u128;
        n += entry.served[k] as u128 * p.steps as u128;
    }
    let level_under = if n > 0 { u as f64 / n as f64 } else { 0.0 };
    Pooled {
        level: scale(&entry.pooled.level, Some(level_under)),
        views,
    }
}

/// A share pooled over views: `Σ s_k a_k / Σ s_k b_k` for each view's count `a_k` out of
/// `b_k` and its weight steps `s_k`; 0 when the weighted denominator is 0.
pub fn pooled_share(parts: &[(u64, u64, u64)]) -> f64 {
    let (mut a, mut b) = (0u128, 0u128);
    for &(num, den, steps) in parts {
        a += num as u128 * steps as u128;
        b += den as u128 * steps as u128;
    }
    if b == 0 {
        0.0
    } else {
        a as f64 / b as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank_percentiles() {
        let mut v: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(percentile(&mut v, 50.0), 10.0);
        assert_eq!(percentile(&mut v, 95.0), 19.0);
        assert_eq!(percentile(&mut v, 99.0), 20.0);
        assert_eq!(percentile(&mut v, 0.0), 1.0);
        assert_eq!(percentile(&mut [], 50.0), 0.0);
    }

    /// The bucketed selection equals sorting every value, on spreads from one repeated value
    /// to many octaves, with several runs of different texel sizes.
    #[test]
    fn bucketed_percentiles_equal_a_full_sort() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for (n, spread) in [(1, 1.0), (7, 0.0), (20, 1.0), (1000, 0.0), (5000, 3.0), (30000, 40.0)] {
            let g: Vec<(f64, f64)> = (0..n).map(|k| (k as f64, 0.1 * (spread * next()).exp2())).collect();
            let cut = n / 3;
            let runs = vec![(0, cut, 0.7), (cut, n, 1.9)];
            let mut all: Vec<f64> = runs
                .iter()
                .flat_map(|&(a, b, t)| g[a..b].iter().map(move |&(_, x)| t * x))
                .collect();
            let (lo, hi) = all
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(l, h), &m| (l.min(m), h.max(m)));
            let buckets = Buckets::new(lo, hi);
            let mut hist = vec![0u32; Buckets::COUNT];
            all.iter().for_each(|&m| hist[buckets.key(m)] += 1);
            let ps = [50.0, 95.0, 99.0];
            let got = values_at_ranks(&g, &runs, buckets, &hist, &ps.map(|p| rank_index(p, n)));
            all.sort_by(f64::total_cmp);
            let want: Vec<f64> = ps.iter().map(|&p| all[rank_index(p, n)]).collect();
            assert_eq!(got, want, "n = {n}, spread = {spread}");
        }
    }

    /// The bucketed weighted percentiles equal a brute force: every (value, weight) pair sorted
    /// by value, the running weight compared with ceil(p W / 100) in whole steps; zero weights
    /// (surfaces edge-on to the light) and one heavy pixel included.
    #[test]
    fn weighted_percentiles_equal_a_sorted_brute_force() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for (n, spread) in [(1, 1.0), (9, 0.0), (50, 1.0), (2000, 2.0), (30000, 30.0)] {
            let g: Vec<(f64, f64)> = (0..n).map(|k| (k as f64, 0.1 * (spread * next()).exp2())).collect();
            let w: Vec<u32> = (0..n)
                .map(|k| match k % 11 {
                    0 => 0,
                    5 => crate::visibility::contrast_weight(1.0),
                    _ => crate::visibility::contrast_weight(next()),
                })
                .collect();
            let cut = n / 2;
            let runs = vec![(0, cut, 1.3), (cut, n, 0.4)];
            let mut all: Vec<(f64, u32)> = runs
                .iter()
                .flat_map(|&(a, b, t)| (a..b).map(move |k| (t, k)))
                .map(|(t, k)| (t * g[k].1, w[k]))
                .collect();
            let (lo, hi) = all
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(l, h), &(m, _)| (l.min(m), h.max(m)));
            let buckets = Buckets::new(lo, hi);
            let mut whist = vec![0u64; Buckets::COUNT];
            all.iter().for_each(|&(m, x)| whist[buckets.key(m)] += x as u64);
            let total: u64 = all.iter().map(|x| x.1 as u64).sum();
            if total == 0 {
                continue;
            }
            let targets = [50, 95, 99].map(|p| weight_target(p, total));
            let got = weighted_values_at(&g, &w, &runs, buckets, &whist, &targets);
            all.sort_by(|a, b| a.0.total_cmp(&b.0));
            let want: Vec<f64> = [50u64, 95, 99]
                .iter()
                .map(|&p| {
                    // Brute force in 128-bit arithmetic: the first value whose running weight
                    // times 100 reaches p times the total.
                    let mut run = 0u128;
                    for &(m, x) in &all {
                        run += x as u128;
                        if x > 0 && run * 100 >= p as u128 * total as u128 {
                            return m;
                        }
                    }
                    unreachable!()
                })
                .collect();
            assert_eq!(got, want, "n = {n}, spread = {spread}");
        }
    }

    /// A synthetic pass: `n` receivers at increasing depths in [1, 200) with factors spread
    /// over `spread` octaves and contrast weights (some 0), among `n + extra` samples.
    fn synthetic(seed: u64, n: usize, spread: f64, extra: usize) -> Visibility {
        use crate::geometry::{CameraPose, Lens};
        let mut rng = crate::rng::SplitMix64::new(seed);
        let mut depths: Vec<f64> = (0..n).map(|_| 1.0 + 199.0 * rng.unit()).collect();
        depths.sort_by(f64::total_cmp);
        let receivers: Vec<(f64, f64)> = depths
            .iter()
            .map(|&d| (d, 0.05 * (spread * rng.unit()).exp2()))
            .collect();
        let weights: Vec<u32> = (0..n)
            .map(|k| {
                if k % 7 == 0 {
                    0
                } else {
                    crate::visibility::contrast_weight(rng.unit())
                }
            })
            .collect();
        let factor_range = receivers.iter().fold(None, |r: Option<(f64, f64)>, &(_, g)| {
            Some(r.map_or((g, g), |(lo, hi)| (lo.min(g), hi.max(g))))
        });
        let view = crate::visibility::View {
            pose: CameraPose::look_at(glam::DVec3::ZERO, glam::DVec3::NEG_Z, glam::DVec3::Y).unwrap(),
            lens: Lens::new(1.0, 1.5),
            near: 0.1,
            far: 500.0,
            width: 64,
            height: 48,
            scale: 1.0,
            light: glam::DVec3::NEG_Y,
        };
        Visibility {
            view,
            cols: 1,
            rows: (n + extra) as u32,
            samples: vec![None; n + extra],
            receivers,
            weights,
            self_shadowed: extra / 2,
            depth_range: Some((1.0, 200.0)),
            factor_range,
        }
    }

    /// Brute force over the pooled pixels: every served `(m, N·L steps, view steps)` listed,
    /// sorted by value, and the weighted nearest-rank values found by a running sum in 128-bit
    /// whole numbers (plain: each pixel counts its view's steps; visible: contrast × steps).
    fn brute_percentiles(parts: &[PoolPart<'_>]) -> ([f64; 3], [f64; 3], f64, f64, usize) {
        let mut all: Vec<(f64, u128, u128)> = Vec::new();
        for p in parts {
            for (k, &(d, g)) in p.vis.receivers.iter().enumerate() {
                let m = p.splits.len() - 1;
                if d < p.splits[0] || d > p.splits[m] {
                    continue;
                }
                // The cascade by a linear search (independent of `cascade_at`'s).
                let mut i = 0;
                while i + 1 < m && d >= p.splits[i + 1] {
                    i += 1;
                }
                let s = p.steps as u128;
                all.push((p.texel[i] * g, s, p.vis.weights[k] as u128 * s));
            }
        }
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let pick = |which: usize| -> [f64; 3] {
            let w = |x: &(f64, u128, u128)| if which == 0 { x.1 } else { x.2 };
            let total: u128 = all.iter().map(w).sum();
            [50u128, 95, 99].map(|p| {
                if total == 0 {
                    return 0.0;
                }
                let mut run = 0u128;
                for x in &all {
                    run += w(x);
                    if w(x) > 0 && run * 100 >= p * total {
                        return x.0;
                    }
                }
                unreachable!()
            })
        };
        let max = all.iter().map(|x| x.0).fold(0.0, f64::max);
        let vmax = all.iter().filter(|x| x.2 > 0).map(|x| x.0).fold(0.0, f64::max);
        (pick(0), pick(1), max, vmax, all.len())
    }

    /// The level's percentiles are those of a brute-force pool of every view's served pixels,
    /// each view's own statistics are `stats` of that view alone, and the pooled fractions are
    /// the step-weighted counts; over views of different sizes, spreads, cascade counts and
    /// weights (1, 2.5, 0.25 and an unserved view).
    #[test]
    fn pooled_percentiles_equal_a_brute_force_pool() {
        let vis: Vec<Visibility> = [
            (1, 3000, 4.0, 500),
            (2, 800, 10.0, 0),
            (3, 1, 1.0, 9),
            (4, 12000, 2.0, 100),
        ]
        .iter()
        .map(|&(seed, n, spread, extra)| synthetic(seed, n, spread, extra))
        .collect();
        let splits: [Vec<f64>; 4] = [
            vec![0.5, 10.0, 40.0, 150.0],
            vec![2.0, 30.0, 60.0, 90.0, 120.0, 210.0],
            vec![0.5, 300.0],
            vec![5.0, 12.0, 100.0],
        ];
        let texels: [Vec<f64>; 4] = [
            vec![0.05, 0.2, 0.8],
            vec![0.1, 0.3, 0.4, 0.9, 1.7],
            vec![2.0],
            vec![0.07, 0.5],
        ];
        for weights in [[1.0, 1.0, 1.0, 1.0], [2.5, 1.0, 0.25, 3.0], [1.0, 0.001, 7.0, 1.0]] {
            let parts: Vec<PoolPart<'_>> = (0..4)
                .map(|k| PoolPart {
                    vis: &vis[k],
                    splits: &splits[k],
                    texel: &texels[k],
                    visible: Some((1.0 + k as f64, 100.0 + k as f64)),
                    steps: view_weight_steps(weights[k]),
                })
                .collect();
            let pooled = pool(&parts);
            for (k, p) in parts.iter().enumerate() {
                assert_eq!(pooled.views[k], stats(p.vis, p.splits, p.texel, p.visible), "view {k}");
            }
            let (plain, visible, max, vmax, served) = brute_percentiles(&parts);
            let l = &pooled.level;
            assert_eq!([l.aliasing_p50, l.aliasing_p95, l.aliasing_p99], plain, "{weights:?}");
            assert_eq!([l.visible_p50, l.visible_p95, l.visible_p99], visible, "{weights:?}");
            assert_eq!((l.aliasing_max, l.visible_max), (max, vmax));
            assert!(served > 0);
            // Fractions: step-weighted counts.
            let steps: Vec<f64> = parts.iter().map(|p| p.steps as f64).collect();
            let recv: f64 = (0..4).map(|k| steps[k] * vis[k].receivers.len() as f64).sum();
            let samples: f64 = (0..4).map(|k| steps[k] * vis[k].samples.len() as f64).sum();
            assert!((l.receiver_fraction - recv / samples).abs() < 1e-15);
            let w_mean: f64 = (0..4)
                .map(|k| steps[k] * pooled.views[k].aliasing_mean * served_of(&parts[k]) as f64)
                .sum::<f64>()
                / (0..4).map(|k| steps[k] * served_of(&parts[k]) as f64).sum::<f64>();
            assert!(
                (l.aliasing_mean - w_mean).abs() <= 1e-12 * w_mean,
                "{} vs {w_mean}",
                l.aliasing_mean
            );
            assert_eq!((l.visible_z_lo, l.visible_z_hi), (1.0, 103.0));
            assert_eq!(l.cascade_pixels.len(), 5);
        }
    }

    /// The remembered pool equals `pool` bit for bit: texel sizes scaled by powers of two
    /// (entries shared, the undersampled counts read from the octaves) and by other factors
    /// (new entries), with weights; a repeat is a hit, not a new entry.
    #[test]
    fn the_remembered_pool_equals_the_pool_at_every_scale() {
        let vis: Vec<Visibility> = [(11, 4000, 5.0, 100), (12, 2500, 9.0, 0), (13, 7000, 3.0, 50)]
            .iter()
            .map(|&(seed, n, spread, extra)| synthetic(seed, n, spread, extra))
            .collect();
        let splits: [Vec<f64>; 3] = [
            vec![0.5, 10.0, 40.0, 150.0],
            vec![2.0, 30.0, 90.0, 210.0],
            vec![1.0, 200.0],
        ];
        let base: [Vec<f64>; 3] = [vec![0.5, 2.0, 7.0], vec![1.1, 3.3, 9.0], vec![4.0]];
        let memo = PoolMemo::default();
        let entries = |m: &PoolMemo| m.entries.lock().unwrap().len();
        // 2^k scales share one entry; 0.7 and 3 are new ones. The values straddle m = 1 at
        // most scales, so the undersampled counts change with the scale.
        let scales = [1.0, 0.5, 0.25, 2.0, 1.0 / 64.0, 0.7, 3.0, 0.5];
        let mut unders = Vec::new();
        for (i, &scale) in scales.iter().enumerate() {
            let texels: Vec<Vec<f64>> = base.iter().map(|t| t.iter().map(|&x| x * scale).collect()).collect();
            let parts: Vec<PoolPart<'_>> = (0..3)
                .map(|k| PoolPart {
                    vis: &vis[k],
                    splits: &splits[k],
                    texel: &texels[k],
                    visible: Some((1.0, 150.0 + k as f64)),
                    steps: view_weight_steps([1.0, 2.5, 0.5][k]),
                })
                .collect();
            let direct = pool(&parts);
            assert_eq!(pool_memo(&parts, &memo), direct, "scale {scale}");
            unders.push(direct.level.undersampled_fraction);
            let want = match i {
                0..=4 => 1,
                5 => 2,
                _ => 3,
            };
            assert_eq!(entries(&memo), want, "after scale {scale}");
        }
        // The shared entries answered different undersampled fractions.
        unders.sort_by(f64::total_cmp);
        unders.dedup();
        assert!(unders.len() >= 5, "{unders:?}");
    }

    fn served_of(p: &PoolPart<'_>) -> usize {
        let m = p.splits.len() - 1;
        p.vis
            .receivers
            .iter()
            .filter(|&&(d, _)| d >= p.splits[0] && d <= p.splits[m])
            .count()
    }

    /// A level of one view is that view, and two identical views (any equal weights) are one.
    #[test]
    fn one_view_and_two_identical_views_equal_the_single_view_statistics() {
        let vis = synthetic(9, 5000, 6.0, 300);
        let (splits, texel) = (vec![1.0, 8.0, 30.0, 90.0, 180.0], vec![0.02, 0.1, 0.4, 1.1]);
        let alone = stats(&vis, &splits, &texel, Some((1.0, 180.0)));
        let part = |w: f64| PoolPart {
            vis: &vis,
            splits: &splits,
            texel: &texel,
            visible: Some((1.0, 180.0)),
            steps: view_weight_steps(w),
        };
        assert_eq!(pool(&[part(1.0)]).level, alone);
        assert_eq!(pool(&[part(1.0), part(1.0)]).level, alone);
        assert_eq!(pool(&[part(4.0), part(4.0), part(4.0)]).level, alone);
        // Weights only matter relative to each other: one view of weight 3 is still itself.
        assert_eq!(pool(&[part(3.0)]).level.aliasing_p95, alone.aliasing_p95);
    }
}
