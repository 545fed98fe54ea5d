//! Exact extremes of the per-depth metrics over a range of view depths.
//!
//! Under interval selection cascade `i` serves depths `C_i <= d < C_{i+1}` (the last one also
//! `d = C_M`), and there the aliasing ratio is `a(d) = K T_i / d` (see [`csm_core::metrics`]).
//! Inside one cascade `a` is strictly decreasing in `d`, so over `[lo, hi]` its supremum and
//! infimum are at the ends of the intersection of `[lo, hi]` with each cascade's interval:
//! the largest value is `K T_i / max(lo, C_i)` for some `i`, the smallest `K T_i / min(hi,
//! C_{i+1})`. No sampling is needed; the cost is O(cascades).
//!
//! Where an intersection ends at a split `C_{i+1}` that cascade `i` does not serve, the value
//! there is the limit as depth approaches the split from the near side, as for
//! `CascadeReport::min_aliasing` and the two samples `density.csv` writes at every split.
//! `texels_per_pixel` is `1 / a(d)`, so its extremes sit at the same depths, swapped.

use super::metric::DepthMetric;
use csm_core::metrics::cascade_at;

/// One extreme: its value, where it is attained (or approached) and which cascade serves it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DepthExtreme {
    pub value: f64,
    pub depth: f64,
    pub cascade: usize,
}

/// The largest and the smallest value of a per-depth metric over a depth range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DepthExtremes {
    pub max: DepthExtreme,
    pub min: DepthExtreme,
}

/// Extremes of `metric` over view depths `[lo, hi]`, which must lie inside `[splits[0],
/// splits[M]]` with `lo <= hi`. `texel[i]` is cascade `i`'s texel size (world units) and `k`
/// is `H / (2 tanV)` (pixels per unit of image slope), so `a(d) = k texel[i] / d`.
pub(crate) fn extremes(metric: DepthMetric, splits: &[f64], texel: &[f64], k: f64, lo: f64, hi: f64) -> DepthExtremes {
    let m = texel.len();
    assert_eq!(splits.len(), m + 1, "one texel size per cascade");
    assert!(
        lo <= hi && lo >= splits[0] && hi <= splits[m],
        "range inside the splits"
    );
    let aliasing = |i: usize, d: f64| DepthExtreme {
        value: k * texel[i] / d,
        depth: d,
        cascade: i,
    };
    let (max_a, min_a) = if lo == hi {
        let e = aliasing(cascade_at(splits, lo), lo);
        (e, e)
    } else {
        let mut max_a: Option<DepthExtreme> = None;
        let mut min_a: Option<DepthExtreme> = None;
        for i in 0..m {
            let (a, b) = (lo.max(splits[i]), hi.min(splits[i + 1]));
            // Only cascades that serve a stretch of positive length: a range that merely
            // touches a split is served on that side by the neighbour.
            if a >= b {
                continue;
            }
            let near_end = aliasing(i, a);
            let far_end = aliasing(i, b);
            if max_a.is_none_or(|x| near_end.value > x.value) {
                max_a = Some(near_end);
            }
            if min_a.is_none_or(|x| far_end.value < x.value) {
                min_a = Some(far_end);
            }
        }
        (
            max_a.expect("lo < hi inside the splits overlaps a cascade"),
            min_a.expect("lo < hi inside the splits overlaps a cascade"),
        )
    };
    match metric {
        DepthMetric::Aliasing => DepthExtremes { max: max_a, min: min_a },
        DepthMetric::TexelsPerPixel => {
            let inv = |e: DepthExtreme| DepthExtreme {
                value: 1.0 / e.value,
                ..e
            };
            DepthExtremes {
                max: inv(min_a),
                min: inv(max_a),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use csm_core::splits::practical;

    fn value(metric: DepthMetric, splits: &[f64], texel: &[f64], k: f64, d: f64) -> f64 {
        let a = k * texel[cascade_at(splits, d)] / d;
        match metric {
            DepthMetric::Aliasing => a,
            DepthMetric::TexelsPerPixel => 1.0 / a,
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

        /// The exact extremes against dense sampling of the sawtooth, on random splits, texel
        /// sizes and ranges (including ranges inside one cascade and ranges over many: `whole`
        /// takes the full range).
        #[test]
        fn extremes_agree_with_dense_sampling(
            log_n in -2.0f64..1.0,
            decades in 0.5f64..3.0,
            lambda in 0.0f64..1.0,
            t in proptest::collection::vec(0.001f64..0.5, 1..=8),
            k in 300.0f64..2000.0,
            ends in (0.0f64..1.0, 0.0f64..1.0),
            whole in proptest::bool::weighted(0.2),
        ) {
            let n = 10f64.powf(log_n);
            let f = n * 10f64.powf(decades);
            let m = t.len();
            let s = practical(n, f, m, lambda);
            let at = |u: f64| n + (f - n) * u;
            let (lo, hi) = if whole { (n, f) } else { (at(ends.0.min(ends.1)), at(ends.0.max(ends.1))) };
            for metric in DepthMetric::ALL {
                let e = extremes(metric, &s, &t, k, lo, hi);
                // Samples: a dense grid plus each split approached from both sides.
                let cells = 20_000;
                let mut depths: Vec<f64> = (0..=cells).map(|j| lo + (hi - lo) * j as f64 / cells as f64).collect();
                depths.extend(s[1..m].iter().flat_map(|&c| [c * (1.0 - 1e-12), c]).filter(|d| (lo..=hi).contains(d)));
                let vals: Vec<f64> = depths.iter().map(|&d| value(metric, &s, &t, k, d)).collect();
                let smax = vals.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
                let smin = vals.iter().cloned().fold(f64::INFINITY, f64::min);
                // Sampling never beats the exact extreme, and gets within rounding of it.
                proptest::prop_assert!(smax <= e.max.value * (1.0 + 1e-9), "{smax} > {:?}", e.max);
                proptest::prop_assert!(smin >= e.min.value * (1.0 - 1e-9), "{smin} < {:?}", e.min);
                proptest::prop_assert!((smax - e.max.value).abs() <= 1e-9 * e.max.value, "max {smax} {:?}", e.max);
                proptest::prop_assert!((smin - e.min.value).abs() <= 1e-9 * e.min.value, "min {smin} {:?}", e.min);
                // The reported depth and cascade give the reported value.
                for x in [e.max, e.min] {
                    proptest::prop_assert!(x.depth >= lo && x.depth <= hi);
                    proptest::prop_assert!(x.depth >= s[x.cascade] && x.depth <= s[x.cascade + 1]);
                    let a = k * t[x.cascade] / x.depth;
                    let v = if metric == DepthMetric::Aliasing { a } else { 1.0 / a };
                    proptest::prop_assert_eq!(v, x.value);
                }
            }
        }
    }

    #[test]
    fn a_single_depth_uses_the_cascade_that_serves_it() {
        let s = [1.0, 10.0, 100.0];
        let t = [0.01, 0.2];
        let k = 1000.0;
        // Exactly on the split: cascade 1 serves it.
        let e = extremes(DepthMetric::Aliasing, &s, &t, k, 10.0, 10.0);
        assert_eq!(e.max, e.min);
        assert_eq!(e.max.cascade, 1);
        assert_eq!(e.max.value, 1000.0 * 0.2 / 10.0);
        // A range ending on the split does not include cascade 1's jump.
        let e = extremes(DepthMetric::Aliasing, &s, &t, k, 2.0, 10.0);
        assert_eq!(e.max.value, 1000.0 * 0.01 / 2.0);
        assert_eq!(e.min.value, 1000.0 * 0.01 / 10.0);
        assert_eq!((e.max.cascade, e.min.cascade), (0, 0));
        // A range starting on the split is cascade 1 only.
        let e = extremes(DepthMetric::TexelsPerPixel, &s, &t, k, 10.0, 100.0);
        assert_eq!(e.min.value, 10.0 / (1000.0 * 0.2));
        assert_eq!(e.max.value, 100.0 / (1000.0 * 0.2));
    }
}
