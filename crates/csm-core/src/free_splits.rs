//! Free split positions: explicit split fractions instead of a split rule, and the change of
//! variables `sweep --optimize-splits` searches in.
//!
//! A split *fraction* `p` in (0, 1) places a boundary in a depth range `[lo, hi]` at
//! `lo + (hi − lo) p` (the convention of every engine whose splits are free numbers; csm-lab's
//! own `shadow.splits` uses its split range `[z_lo, z_hi]`). A [`FractionSpace`] says what
//! `lo`, `hi` and the first cascade's near depth `start` are.
//!
//! The search does not move fractions directly (they must stay strictly increasing in (0, 1),
//! and the good ones span orders of magnitude near the camera). It moves `m − 1` unconstrained
//! numbers `y`: the gaps between the boundaries in *log depth* are `softmax(y, 0)`, so every `y`
//! gives strictly increasing fractions, and `y = 0` is the logarithmic split (λ = 1).

use serde::ser::SerializeSeq;

/// Up to 15 split fractions (16 cascades), strictly increasing in (0, 1). `Copy`, so the
/// shadow parameters that hold it stay plain values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplitFractions {
    len: u8,
    values: [f64; SplitFractions::MAX],
}

impl SplitFractions {
    /// The most fractions: one fewer than the most cascades.
    pub const MAX: usize = 15;

    /// The fractions, if there are at most [`Self::MAX`] of them, each finite and strictly
    /// inside (0, 1), and strictly increasing.
    pub fn new(values: &[f64]) -> Option<SplitFractions> {
        if !valid(values) || values.len() > Self::MAX {
            return None;
        }
        let mut out = [0.0; Self::MAX];
        out[..values.len()].copy_from_slice(values);
        Some(SplitFractions {
            len: values.len() as u8,
            values: out,
        })
    }

    pub fn as_slice(&self) -> &[f64] {
        &self.values[..self.len as usize]
    }

    pub fn len(&self) -> usize {
        self.len as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl serde::Serialize for SplitFractions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.len()))?;
        for v in self.as_slice() {
            seq.serialize_element(v)?;
        }
        seq.end()
    }
}

/// Whether `values` are finite, strictly inside (0, 1) and strictly increasing.
pub fn valid(values: &[f64]) -> bool {
    values.iter().all(|p| p.is_finite() && *p > 0.0 && *p < 1.0) && values.windows(2).all(|w| w[0] < w[1])
}

/// What split fractions are fractions of: boundary `p` sits at depth `lo + (hi − lo) p`, and
/// the first cascade starts at depth `start` (`lo <= start < hi`, `start > 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FractionSpace {
    pub lo: f64,
    pub hi: f64,
    pub start: f64,
}

impl FractionSpace {
    /// The fraction of a depth.
    pub fn fraction(&self, depth: f64) -> f64 {
        (depth - self.lo) / (self.hi - self.lo)
    }

    /// The depth of a fraction.
    pub fn depth(&self, fraction: f64) -> f64 {
        self.lo + (self.hi - self.lo) * fraction
    }

    /// The interior fractions of the practical split with `m` cascades and weight `lambda` on
    /// `[start, hi]` (see [`crate::splits::practical`]).
    pub fn practical(&self, m: usize, lambda: f64) -> Vec<f64> {
        let c = crate::splits::practical(self.start, self.hi, m, lambda);
        c[1..m].iter().map(|&d| self.fraction(d)).collect()
    }

    /// The search coordinates of `fractions` (inverse of [`Self::from_params`]); None when a
    /// fraction lies at or before `start` (no positive log-depth gap).
    pub fn to_params(&self, fractions: &[f64]) -> Option<Vec<f64>> {
        let total = (self.hi / self.start).ln();
        let mut u = vec![0.0];
        for &p in fractions {
            let d = self.depth(p);
            if d.is_nan() || d <= self.start {
                return None;
            }
            u.push((d / self.start).ln() / total);
        }
        u.push(1.0);
        let gaps: Vec<f64> = u.windows(2).map(|w| w[1] - w[0]).collect();
        if gaps.iter().any(|g| g.is_nan() || *g <= 0.0) {
            return None;
        }
        let last = gaps[gaps.len() - 1].ln();
        Some(gaps[..gaps.len() - 1].iter().map(|g| g.ln() - last).collect())
    }

    /// The fractions of search coordinates `y` (`y.len()` + 1 cascades): log-depth gaps
    /// `softmax(y, 0)` from `start` to `hi`. Always finite; strictly increasing unless a gap
    /// underflows (then [`valid`] says so).
    pub fn from_params(&self, y: &[f64]) -> Vec<f64> {
        let top = y.iter().copied().fold(0.0f64, f64::max);
        let w: Vec<f64> = y.iter().map(|v| (v - top).exp()).chain([(-top).exp()]).collect();
        let sum: f64 = w.iter().sum();
        let total = (self.hi / self.start).ln();
        let mut acc = 0.0;
        w[..w.len() - 1]
            .iter()
            .map(|g| {
                acc += g / sum;
                self.fraction(self.start * (acc * total).exp())
            })
            .collect()
    }
}

/// `x` rounded to `digits` significant decimal digits (as the shortest decimal that parses
/// back to it, so a printed value pastes back to the same number).
pub fn round_significant(x: f64, digits: usize) -> f64 {
    format!("{:.*e}", digits.saturating_sub(1), x).parse().unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn fractions_are_checked() {
        assert!(SplitFractions::new(&[0.1, 0.3, 0.6]).is_some());
        assert!(SplitFractions::new(&[]).is_some_and(|f| f.is_empty()));
        for bad in [
            &[0.3, 0.1][..],
            &[0.1, 0.1],
            &[0.0, 0.5],
            &[0.5, 1.0],
            &[f64::NAN],
            &[-0.1],
            &[0.05; 16],
        ] {
            assert!(SplitFractions::new(bad).is_none(), "{bad:?}");
        }
        let f = SplitFractions::new(&[0.25, 0.5]).unwrap();
        assert_eq!(f.as_slice(), &[0.25, 0.5]);
    }

    #[test]
    fn params_round_trip_and_zero_is_the_log_split() {
        let space = FractionSpace {
            lo: 0.0,
            hi: 150.0,
            start: 0.1,
        };
        // y = 0: equal log gaps, i.e. λ = 1.
        let log = space.from_params(&[0.0, 0.0, 0.0]);
        for (a, b) in log.iter().zip(space.practical(4, 1.0)) {
            assert_relative_eq!(*a, b, max_relative = 1e-12);
        }
        let mut rng = crate::rng::SplitMix64::new(7);
        for _ in 0..200 {
            let y: Vec<f64> = (0..1 + (rng.unit() * 6.0) as usize)
                .map(|_| rng.range(-3.0, 3.0))
                .collect();
            let p = space.from_params(&y);
            assert!(valid(&p), "{p:?}");
            let back = space.to_params(&p).unwrap();
            for (a, b) in y.iter().zip(&back) {
                assert!((a - b).abs() < 1e-9, "{y:?} {back:?}");
            }
        }
        // A fraction before the first cascade's start has no log coordinate.
        let g = FractionSpace {
            lo: 0.0,
            hi: 100.0,
            start: 5.0,
        };
        assert!(g.to_params(&[0.01, 0.5]).is_none());
    }

    #[test]
    fn rounding_keeps_significant_digits() {
        assert_eq!(round_significant(0.063_418_27, 4), 0.06342);
        assert_eq!(round_significant(0.000_123_456, 3), 0.000123);
        assert_eq!(round_significant(0.5, 4), 0.5);
        assert_eq!(format!("{}", round_significant(0.123_456_7, 4)), "0.1235");
    }
}
