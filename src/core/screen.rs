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

use crate::metrics::cascade_at;
use crate::visibility::Visibility;

/// The screen metrics of one configuration. Fractions are of sampled pixels (receivers,
/// self-shadowed) or of served receiver pixels (undersampled). Every value is finite; all
/// statistics of `m` are 0 when no receiver pixel is served.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
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

/// Nearest-rank percentiles at increasing `ps` of non-negative finite values given as their
/// bit patterns (which order like the values), reordering them. Each selection works only on
/// the part at and above the previous one.
fn percentiles_of_bits(bits: &mut [u64], ps: &[f64]) -> Vec<f64> {
    let n = bits.len();
    if n == 0 {
        return vec![0.0; ps.len()];
    }
    let mut start = 0;
    ps.iter()
        .map(|&p| {
            let r = rank_index(p, n).max(start);
            let x = *bits[start..].select_nth_unstable(r - start).1;
            start = r;
            f64::from_bits(x)
        })
        .collect()
}

/// The visible depth range clipped to `[lo, hi]`, or None when nothing visible lies in it.
pub fn visible_range(vis: &Visibility, lo: f64, hi: f64) -> Option<(f64, f64)> {
    let (a, b) = vis.depth_range?;
    let (a, b) = (a.max(lo), b.min(hi));
    (a <= b).then_some((a, b))
}

/// The per-pixel aliasing of every served receiver pixel, cascade by cascade (in depth order).
pub fn served_aliasing(vis: &Visibility, splits: &[f64], texel: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let r = &vis.receivers;
    let m = texel.len();
    let mut out = Vec::with_capacity(r.len());
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
        let t = texel[i];
        out.extend(r[k..run_end].iter().map(|&(_, g)| t * g));
        counts[i] += run_end - k;
        k = run_end.max(k + 1);
    }
    (out, counts)
}

/// The screen metrics of a configuration with selection `splits` and texel sizes `texel`;
/// `visible` is the visible depth range already clipped (see [`visible_range`]).
pub fn stats(vis: &Visibility, splits: &[f64], texel: &[f64], visible: Option<(f64, f64)>) -> ScreenStats {
    let total = vis.sample_count().max(1) as f64;
    let receivers = vis.receivers.len();
    let (values, counts) = served_aliasing(vis, splits, texel);
    let n = values.len();
    let (mut sum, mut max, mut under) = (0.0, 0.0f64, 0usize);
    // m is finite and positive, so its bit pattern orders like its value (a faster selection).
    let mut bits: Vec<u64> = values
        .iter()
        .map(|&m| {
            sum += m;
            max = max.max(m);
            under += usize::from(m > 1.0);
            m.to_bits()
        })
        .collect();
    let (mean, under) = if n == 0 {
        (0.0, 0.0)
    } else {
        (sum / n as f64, under as f64 / n as f64)
    };
    let p = percentiles_of_bits(&mut bits, &[50.0, 95.0, 99.0]);
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
        let mut bits: Vec<u64> = (1..=20).rev().map(|x| f64::from(x).to_bits()).collect();
        assert_eq!(
            percentiles_of_bits(&mut bits, &[50.0, 95.0, 99.0]),
            vec![10.0, 19.0, 20.0]
        );
        assert_eq!(percentiles_of_bits(&mut [], &[50.0]), vec![0.0]);
    }
}
