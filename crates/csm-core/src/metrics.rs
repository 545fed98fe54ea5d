//! Texel density and perspective aliasing against view depth.
//!
//! With interval selection (cascade i serves `C_{i-1} <= d < C_i`) and a constant texel size
//! `T_i` per cascade, the aliasing ratio is `a(d) = T_i / P(d) = K T_i / d` with
//! `K = H / (2 tanV)`: a sawtooth that falls as 1/d inside each cascade and jumps at each
//! split. `a > 1` means one shadow texel covers more than one screen pixel (blocky);
//! texels per pixel is `1/a`. The aggregates below integrate that sawtooth exactly, in O(M).

use crate::geometry::Lens;

/// Closed-form aggregates over the split range `[C_0, C_M]`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Aggregates {
    /// Worst aliasing anywhere: max over cascades of `K T_i / C_{i-1}` (each near edge).
    pub max_aliasing: f64,
    /// Mean of a(d) over depth (weight dd).
    pub mean_aliasing: f64,
    /// Mean of a(d) over log depth (weight dd/d): every octave of depth counts the same.
    pub mean_log_aliasing: f64,
    /// Share of the depth range where a(d) > 1 (under-sampled).
    pub undersampled_fraction: f64,
    /// Per cascade: aliasing at its near edge (max) and far edge (min).
    pub cascade_max_aliasing: Vec<f64>,
    pub cascade_min_aliasing: Vec<f64>,
    /// Per interior split i (between cascades i and i+1): T_{i+1}/T_i, the factor by which
    /// the texel size jumps as depth crosses the split.
    pub split_jumps: Vec<f64>,
}

/// Computes the aggregates from the split depths, each cascade's texel size and `K`.
pub fn aggregates(splits: &[f64], texel: &[f64], k: f64) -> Aggregates {
    let m = texel.len();
    assert_eq!(splits.len(), m + 1, "one texel size per cascade");
    let (z_lo, z_hi) = (splits[0], splits[m]);
    let mut max_aliasing: f64 = 0.0;
    let mut sum_z = 0.0;
    let mut sum_log = 0.0;
    let mut under = 0.0;
    let mut cmax = Vec::with_capacity(m);
    let mut cmin = Vec::with_capacity(m);
    for i in 0..m {
        let (a, b) = (splits[i], splits[i + 1]);
        let kt = k * texel[i];
        cmax.push(kt / a);
        cmin.push(kt / b);
        // An empty selection interval (an engine cascade no visible depth reads) has no worst point.
        if b > a {
            max_aliasing = max_aliasing.max(kt / a);
        }
        sum_z += kt * (b / a).ln();
        sum_log += kt * (1.0 / a - 1.0 / b);
        // a(d) > 1 exactly for d < K T_i.
        under += kt.clamp(a, b) - a;
    }
    Aggregates {
        max_aliasing,
        mean_aliasing: sum_z / (z_hi - z_lo),
        mean_log_aliasing: sum_log / (z_hi / z_lo).ln(),
        // The per-cascade lengths add up to the range only up to rounding: a share cannot
        // exceed 1, so a sum one ulp over the range is reported as exactly 1.
        undersampled_fraction: (under / (z_hi - z_lo)).min(1.0),
        cascade_max_aliasing: cmax,
        cascade_min_aliasing: cmin,
        split_jumps: texel.windows(2).map(|w| w[1] / w[0]).collect(),
    }
}

/// One row of the density profile.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DensitySample {
    pub depth: f64,
    pub cascade: usize,
    pub texel_size: f64,
    pub pixel_size: f64,
    pub texels_per_pixel: f64,
    pub aliasing: f64,
}

/// Cascade serving view depth `d` under interval selection (the last one includes `C_M`).
pub fn cascade_at(splits: &[f64], d: f64) -> usize {
    let m = splits.len() - 1;
    // First split strictly greater than d, minus one.
    let i = splits[1..m].partition_point(|&c| c <= d);
    i.min(m - 1)
}

/// `count` log-spaced depths over the split range, plus both sides of every interior split.
pub fn density_profile(
    splits: &[f64],
    texel: &[f64],
    lens: &Lens,
    screen_height: u32,
    count: usize,
) -> Vec<DensitySample> {
    let m = texel.len();
    let (z_lo, z_hi) = (splits[0], splits[m]);
    let sample = |depth: f64, cascade: usize| {
        let pixel = lens.pixel_size(depth, screen_height);
        let t = texel[cascade];
        DensitySample {
            depth,
            cascade,
            texel_size: t,
            pixel_size: pixel,
            texels_per_pixel: pixel / t,
            aliasing: t / pixel,
        }
    };
    let mut out: Vec<DensitySample> = (0..count)
        .map(|j| {
            let d = if j + 1 == count {
                z_hi
            } else {
                z_lo * (z_hi / z_lo).powf(j as f64 / (count - 1) as f64)
            };
            sample(d, cascade_at(splits, d))
        })
        .collect();
    for (i, &c) in splits.iter().enumerate().take(m).skip(1) {
        // Both sides of each split, skipping cascades whose interval is empty.
        if splits[i - 1] < c {
            out.push(sample(c, i - 1));
        }
        if c < splits[i + 1] {
            out.push(sample(c, i));
        }
    }
    out.sort_by(|a, b| a.depth.total_cmp(&b.depth).then(a.cascade.cmp(&b.cascade)));
    out.dedup_by(|a, b| a.depth == b.depth && a.cascade == b.cascade);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fitting::minimal_sphere;
    use crate::splits::practical;
    use approx::assert_relative_eq;

    fn reference_setup(n: f64, f: f64, lambda: f64, fov: f64, aspect: f64) -> (Vec<f64>, Vec<f64>, f64) {
        let lens = Lens::new(fov.to_radians(), aspect);
        let s = practical(n, f, 4, lambda);
        let t: Vec<f64> = s
            .windows(2)
            .map(|w| 2.0 * minimal_sphere(w[0], w[1], lens.k2()).radius / 2048.0)
            .collect();
        (s, t, lens.pixels_per_unit_slope(1080))
    }

    /// Hand-computed aggregates (W_i = 2 R_i, N = 2048, H = 1080).
    #[test]
    fn aggregates_match_the_reference_table() {
        let rows: [(f64, f64, f64, f64, f64, f64); 10] = [
            (0.1, 200.0, 0.0, 538.626, 2.684, 70.981),
            (0.1, 200.0, 0.5, 272.910, 2.082, 36.189),
            (0.1, 200.0, 0.75, 140.051, 1.998, 18.939),
            (0.1, 200.0, 0.9, 60.336, 2.119, 8.824),
            (0.1, 200.0, 1.0, 7.193, 2.403, 3.219),
            (2.0, 150.0, 0.0, 20.975, 1.845, 5.048),
            (2.0, 150.0, 0.5, 12.070, 1.637, 3.211),
            (2.0, 150.0, 0.75, 7.618, 1.631, 2.410),
            (2.0, 150.0, 0.9, 4.946, 1.684, 2.045),
            (2.0, 150.0, 1.0, 3.165, 1.759, 1.936),
        ];
        for (n, f, lambda, linf, mean_z, mean_ln) in rows {
            let (s, t, k) = reference_setup(n, f, lambda, 60.0, 16.0 / 9.0);
            let a = aggregates(&s, &t, k);
            assert_relative_eq!(a.max_aliasing, linf, max_relative = 2e-4);
            assert_relative_eq!(a.mean_aliasing, mean_z, max_relative = 5e-4);
            assert_relative_eq!(a.mean_log_aliasing, mean_ln, max_relative = 5e-4);
        }
        let (s, t, k) = reference_setup(0.1, 200.0, 0.5, 30.0, 1.0);
        let a = aggregates(&s, &t, k);
        assert_relative_eq!(a.max_aliasing, 284.678, max_relative = 1e-5);
        assert_relative_eq!(a.mean_aliasing, 1.782, max_relative = 5e-4);
        assert_relative_eq!(a.mean_log_aliasing, 37.622, max_relative = 5e-5);
        let (s, t, k) = reference_setup(0.1, 200.0, 1.0, 30.0, 1.0);
        let a = aggregates(&s, &t, k);
        for m in &a.cascade_max_aliasing {
            assert_relative_eq!(*m, 6.724, max_relative = 1e-4);
        }
    }

    /// The closed forms against dense numerical integration of the sawtooth.
    #[test]
    fn aggregates_agree_with_dense_sampling() {
        let mut rng = crate::rng::SplitMix64::new(3);
        for _ in 0..40 {
            let n = 10f64.powf(rng.range(-2.0, 1.0));
            let f = n * 10f64.powf(rng.range(0.5, 3.5));
            let m = 1 + (rng.unit() * 8.0) as usize;
            let s = practical(n, f, m, rng.unit());
            let t: Vec<f64> = (0..m).map(|_| rng.range(0.001, 0.5)).collect();
            let k = rng.range(300.0, 2000.0);
            let a = aggregates(&s, &t, k);
            // Midpoint rule in d and in ln d, 400k cells each.
            let cells = 400_000;
            let (mut sum_z, mut sum_ln, mut under, mut worst) = (0.0, 0.0, 0.0, 0.0f64);
            for j in 0..cells {
                let d = n + (f - n) * (j as f64 + 0.5) / cells as f64;
                let al = k * t[cascade_at(&s, d)] / d;
                sum_z += al;
                if al > 1.0 {
                    under += 1.0;
                }
                let u = (j as f64 + 0.5) / cells as f64;
                let dl = n * (f / n).powf(u);
                sum_ln += k * t[cascade_at(&s, dl)] / dl;
                let de = n * (f / n).powf(j as f64 / cells as f64);
                worst = worst.max(k * t[cascade_at(&s, de)] / de);
            }
            assert_relative_eq!(a.mean_aliasing, sum_z / cells as f64, max_relative = 2e-3);
            assert_relative_eq!(a.mean_log_aliasing, sum_ln / cells as f64, max_relative = 2e-3);
            assert!((a.undersampled_fraction - under / cells as f64).abs() < 1e-4);
            assert!((0.0..=1.0).contains(&a.undersampled_fraction));
            assert!(a.max_aliasing >= worst && a.max_aliasing <= worst * 1.001);
        }
    }

    /// A cascade no depth reads (an engine preset clipped by the camera's planes) changes
    /// nothing: not the worst case, not the means, not the profile.
    #[test]
    fn empty_selection_intervals_contribute_nothing() {
        let lens = Lens::new(1.0, 1.6);
        let a = aggregates(&[1.0, 10.0, 100.0], &[0.01, 0.1], 500.0);
        let b = aggregates(&[1.0, 10.0, 10.0, 100.0], &[0.01, 50.0, 0.1], 500.0);
        assert_eq!(a.max_aliasing, b.max_aliasing);
        assert_eq!(a.mean_aliasing, b.mean_aliasing);
        assert_eq!(a.mean_log_aliasing, b.mean_log_aliasing);
        assert_eq!(a.undersampled_fraction, b.undersampled_fraction);
        let p = density_profile(&[1.0, 10.0, 10.0, 100.0], &[0.01, 50.0, 0.1], &lens, 1080, 64);
        assert!(p.iter().all(|x| x.cascade != 1));
        assert_eq!(p.iter().filter(|x| x.depth == 10.0).count(), 2);
    }

    #[test]
    fn profile_has_both_sides_of_each_split() {
        let lens = Lens::new(1.0, 1.6);
        let s = practical(1.0, 100.0, 3, 0.5);
        let t = [0.01, 0.05, 0.2];
        let p = density_profile(&s, &t, &lens, 1080, 64);
        for &c in &s[1..3] {
            let at: Vec<_> = p.iter().filter(|x| x.depth == c).map(|x| x.cascade).collect();
            assert_eq!(at.len(), 2, "split {c}");
        }
        assert!(p.windows(2).all(|w| w[0].depth <= w[1].depth));
        assert_eq!(p.first().unwrap().depth, 1.0);
        assert_eq!(p.last().unwrap().depth, 100.0);
        for x in &p {
            assert_relative_eq!(x.aliasing * x.texels_per_pixel, 1.0, epsilon = 1e-12);
        }
    }
}
