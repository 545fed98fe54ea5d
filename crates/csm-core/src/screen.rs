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
    let total = vis.sample_count().max(1) as f64;
    let receivers = vis.receivers.len();
    let (runs, counts) = served_runs(vis, splits, texel);
    let g = &vis.receivers;
    let n: usize = counts.iter().sum();
    let (mut sum, mut max, mut under) = (0.0, 0.0f64, 0usize);
    let (mut wsum, mut wtotal, mut wmax) = (0.0, 0u64, 0.0f64);
    let weights = &vis.weights;
    let mut wp = vec![0.0; 3];
    let p = if n == 0 {
        vec![0.0; 3]
    } else {
        // Every served value lies in [min t * min g, max t * max g]; rounding is monotone, so
        // the bounds hold for the rounded products too, and the keys need no first pass.
        let (g_lo, g_hi) = vis.factor_range.unwrap_or((0.0, 0.0));
        let (t_lo, t_hi) = runs
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), r| (l.min(r.2), h.max(r.2)));
        let buckets = Buckets::new(t_lo * g_lo, t_hi * g_hi);
        let mut hist = vec![0u32; Buckets::COUNT];
        let mut whist = vec![0u64; Buckets::COUNT];
        for &(a, b, t) in &runs {
            for (&(_, gk), &wk) in g[a..b].iter().zip(&weights[a..b]) {
                let m = t * gk;
                sum += m;
                // A plain comparison (not f64::max, which also handles NaN): m is finite.
                max = if m > max { m } else { max };
                under += usize::from(m > 1.0);
                let key = buckets.key(m);
                hist[key] += 1;
                whist[key] += wk as u64;
                wtotal += wk as u64;
                wsum += wk as f64 * m;
                if wk > 0 && m > wmax {
                    wmax = m;
                }
            }
        }
        if wtotal > 0 {
            let targets = [50, 95, 99].map(|p| weight_target(p, wtotal));
            wp = weighted_values_at(g, weights, &runs, buckets, &whist, &targets);
        }
        let ranks = [50.0, 95.0, 99.0].map(|p| rank_index(p, n));
        values_at_ranks(g, &runs, buckets, &hist, &ranks)
    };
    let (mean, under) = if n == 0 {
        (0.0, 0.0)
    } else {
        (sum / n as f64, under as f64 / n as f64)
    };
    let (p50, p95, p99) = (p[0], p[1], p[2]);
    let (visible_z_lo, visible_z_hi) = visible.unwrap_or((0.0, 0.0));
    ScreenStats {
        receiver_fraction: receivers as f64 / total,
        self_shadowed_fraction: vis.self_shadowed as f64 / total,
        aliasing_mean: mean,
        aliasing_p50: p50,
        aliasing_p95: p95,
        aliasing_p99: p99,
        aliasing_max: max,
        undersampled_fraction: under,
        visible_mean: if wtotal > 0 { wsum / wtotal as f64 } else { 0.0 },
        visible_p50: wp[0],
        visible_p95: wp[1],
        visible_p99: wp[2],
        visible_max: wmax,
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
}
