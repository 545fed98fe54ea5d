//! Split schemes: where each cascade starts and ends, as view depths.
//!
//! The practical scheme (GPU Gems 3 ch. 10) blends the logarithmic and uniform splits of a
//! range `[n, f]` into `M` cascades:
//!
//! ```text
//! C_i = lambda * n * (f/n)^(i/M) + (1 - lambda) * (n + (f - n) * i/M),   i = 0..=M
//! ```
//!
//! `lambda` weights the logarithmic term (1 = pure log, 0 = uniform). The end points are set
//! to `n` and `f` exactly rather than trusting the formula to reproduce them in floating point.

/// Uniform split position `i` of `m`.
pub fn uniform(n: f64, f: f64, i: usize, m: usize) -> f64 {
    n + (f - n) * (i as f64 / m as f64)
}

/// Logarithmic split position `i` of `m`. Needs `n > 0`.
pub fn logarithmic(n: f64, f: f64, i: usize, m: usize) -> f64 {
    n * (f / n).powf(i as f64 / m as f64)
}

/// The `m + 1` boundaries of the practical split scheme on `[n, f]`, near to far.
/// Requires `0 < n < f`, `m >= 1`, `0 <= lambda <= 1`; the result is strictly increasing.
pub fn practical(n: f64, f: f64, m: usize, lambda: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(m + 1);
    out.push(n);
    for i in 1..m {
        out.push(lambda * logarithmic(n, f, i, m) + (1.0 - lambda) * uniform(n, f, i, m));
    }
    out.push(f);
    out
}

/// Boundaries from normalised positions `p_i` in (0, 1) (Filament, Godot, Unity style):
/// `C = n + (f - n) p`, with `n` and `f` appended at the ends.
pub fn from_positions(n: f64, f: f64, positions: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(positions.len() + 2);
    out.push(n);
    out.extend(positions.iter().map(|p| n + (f - n) * p));
    out.push(f);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// Known split depths of the practical scheme (near 0.1, far 1000), to the printed precision.
    #[test]
    fn practical_splits_match_the_reference_table() {
        let cases: [(f64, f64, f64, [f64; 5], f64); 7] = [
            (0.1, 200.0, 0.0, [0.1, 50.075, 100.05, 150.025, 200.0], 1e-9),
            (0.1, 200.0, 0.5, [0.1, 25.372, 52.261, 89.966, 200.0], 5e-4),
            (0.1, 200.0, 0.75, [0.1, 13.0, 28.4, 59.9, 200.0], 0.05),
            (0.1, 200.0, 0.9, [0.1, 5.61, 14.0, 41.9, 200.0], 0.05),
            (0.1, 200.0, 1.0, [0.1, 0.669, 4.47, 29.9, 200.0], 0.05),
            (2.0, 150.0, 1.0, [2.0, 5.89, 17.3, 51.0, 150.0], 0.05),
            (2.0, 150.0, 0.5, [2.0, 22.4, 46.7, 82.0, 150.0], 0.05),
        ];
        for (n, f, lambda, expected, tol) in cases {
            let got = practical(n, f, 4, lambda);
            for (g, e) in got.iter().zip(expected) {
                assert!((g - e).abs() <= tol, "lambda {lambda}: {got:?} vs {expected:?}");
            }
        }
    }

    #[test]
    fn end_points_are_exact_and_splits_increase() {
        for m in 1..=16 {
            for lambda in [0.0, 0.3, 1.0] {
                let s = practical(1e-4, 1e6, m, lambda);
                assert_eq!(s.len(), m + 1);
                assert_eq!(s[0], 1e-4);
                assert_eq!(s[m], 1e6);
                assert!(s.windows(2).all(|w| w[0] < w[1]), "{s:?}");
            }
        }
        assert_relative_eq!(practical(1.0, 100.0, 2, 1.0)[1], 10.0, epsilon = 1e-12);
    }
}
