//! An engine's split knobs matched to csm-lab's own cascades (`compare`'s engine settings
//! files): free split fractions are set exactly; a single split knob (Unreal's distribution
//! exponent, Bevy's first far bound) or λ is fitted in one dimension. The rule in words:
//! `docs/presets.md`, "Engine settings files".

use crate::config::Validator;

use super::*;

/// What an engine's split knobs are matched to: csm-lab's cascade boundaries `ends`
/// (`d_0 .. d_N`, N the engine's count), at the engine's shadow distance `distance`, with the
/// camera planes `near`/`far`.
#[derive(Debug, Clone, Copy)]
pub struct Target<'a> {
    pub ends: &'a [f64],
    pub distance: f64,
    pub near: f64,
    pub far: f64,
}

impl Target<'_> {
    pub(crate) fn cascades(&self) -> usize {
        self.ends.len() - 1
    }

    /// csm-lab's inner boundaries `d_1 .. d_{N-1}` as fractions of `[from, to]`.
    pub fn fractions(&self, from: f64, to: f64) -> Vec<f64> {
        let n = self.cascades();
        self.ends[1..n].iter().map(|d| (d - from) / (to - from)).collect()
    }
}

/// The far end of each cascade but the last for knobs `k` (the last ends at the distance).
pub(crate) fn far_ends<E: Engine + ?Sized>(k: &E::Knobs, t: &Target<'_>) -> Vec<f64> {
    let n = t.cascades();
    let lay = E::layout(k, n, t.distance, t.near, t.far);
    lay.fitted.iter().take(n.saturating_sub(1)).map(|s| s.1).collect()
}

/// Σ (ln e_i − ln d_{i+1})² over the inner far ends: how far the engine's cascades end from
/// csm-lab's, scale-free. Infinite for knobs the engine refuses at this count and distance.
pub(crate) fn log_misfit<E: Engine + ?Sized>(k: &E::Knobs, t: &Target<'_>) -> f64 {
    let v = Validator { path: "", text: "" };
    if E::check(k, t.cascades(), t.distance, &v).is_err() {
        return f64::INFINITY;
    }
    let e = far_ends::<E>(k, t);
    let mut sum = 0.0;
    for (i, x) in e.iter().enumerate() {
        let d = t.ends[i + 1];
        if !(*x > 0.0 && x.is_finite()) {
            return f64::INFINITY;
        }
        sum += (x.ln() - d.ln()).powi(2);
    }
    sum
}

/// Minimises `cost` over `(lo, hi)`: 256 points spread evenly (in `ln x` when `log`), then a
/// golden-section search between the best point's neighbours. Deterministic; ties keep the
/// smaller x.
pub(crate) fn fit_1d(lo: f64, hi: f64, log: bool, cost: impl Fn(f64) -> f64) -> f64 {
    const M: usize = 256;
    let (a, b) = if log { (lo.ln(), hi.ln()) } else { (lo, hi) };
    let x_of = |u: f64| if log { u.exp() } else { u };
    let grid: Vec<f64> = (0..M).map(|j| a + (b - a) * (j as f64 + 0.5) / M as f64).collect();
    let costs: Vec<f64> = grid.iter().map(|&u| cost(x_of(u))).collect();
    let best = (0..M)
        .min_by(|&i, &j| costs[i].total_cmp(&costs[j]).then(i.cmp(&j)))
        .expect("M > 0");
    let (mut l, mut r) = (grid[best.saturating_sub(1)], grid[(best + 1).min(M - 1)]);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = r - g * (r - l);
    let mut d = l + g * (r - l);
    let (mut fc, mut fd) = (cost(x_of(c)), cost(x_of(d)));
    for _ in 0..100 {
        if fc <= fd {
            r = d;
            d = c;
            fd = fc;
            c = r - g * (r - l);
            fc = cost(x_of(c));
        } else {
            l = c;
            c = d;
            fc = fd;
            d = l + g * (r - l);
            fd = cost(x_of(d));
        }
    }
    let (u, fu) = if fc <= fd { (c, fc) } else { (d, fd) };
    if fu <= costs[best] {
        x_of(u)
    } else {
        x_of(grid[best])
    }
}

/// The default of [`Engine::match_ends`]: the engine's split knob fitted over its range (in
/// `ln x`), else λ over [0, 1], minimising [`log_misfit`]. Nothing to fit for one cascade.
pub(crate) fn fit_split_knob<E: Engine + ?Sized>(k: &mut E::Knobs, t: &Target<'_>) {
    if t.cascades() < 2 {
        return;
    }
    if let Some(knob) = E::knob(k, t.distance) {
        // Values the engine refuses at this count and distance (Bevy's first far bound
        // beyond the distance) cost infinity, so the range is the knob's whole range.
        let hi = knob.max;
        let base = k.clone();
        let cost = |x: f64| {
            let mut c = base.clone();
            E::set_knob(&mut c, x);
            log_misfit::<E>(&c, t)
        };
        let x = fit_1d(knob.min.max(1e-9), hi, true, cost);
        E::set_knob(k, x);
    } else if E::lambda_key(k).is_some() {
        let base = k.clone();
        let cost = |x: f64| {
            let mut c = base.clone();
            E::set_lambda(&mut c, x);
            log_misfit::<E>(&c, t)
        };
        // λ in [0, 1]: the scan is over the open interval, the ends are tried as well.
        let mut best = fit_1d(0.0, 1.0, false, cost);
        for end in [0.0, 1.0] {
            if cost(end) < cost(best) {
                best = end;
            }
        }
        E::set_lambda(k, best);
    }
}

/// `used` fractions first, then `keep`'s where they still increase inside (0, 1), else the
/// midpoint between the previous one and 1: a complete, valid fraction table whose first
/// `used.len()` entries are `used` (the others are not read at this count).
pub(crate) fn complete_fractions<const N: usize>(used: &[f64], keep: [f64; N]) -> [f64; N] {
    let mut out = keep;
    for i in 0..N {
        if i < used.len() {
            out[i] = used[i];
        } else {
            let prev = if i == 0 { 0.0 } else { out[i - 1] };
            if !(keep[i] > prev && keep[i] < 1.0) {
                out[i] = 0.5 * (prev + 1.0);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_1d_fit_finds_the_minimum_of_a_smooth_cost() {
        let x = fit_1d(0.1, 10.0, true, |x: f64| (x.ln() - 2.5f64.ln()).powi(2));
        assert!((x - 2.5).abs() < 1e-9, "{x}");
        let x = fit_1d(0.0, 1.0, false, |x| (x - 0.3).powi(2));
        assert!((x - 0.3).abs() < 1e-9, "{x}");
    }

    #[test]
    fn unreal_exponent_fit_recovers_the_exponent_that_made_the_splits() {
        let k = engines::unreal::UnrealKnobs {
            cascade_distribution_exponent: 2.2,
            transition_fraction: 0.1,
        };
        let lay = <engines::unreal::Unreal as Engine>::layout(&k, 4, 150.0, 0.1, 1000.0);
        // csm-lab's ends taken as the fitted far ends of Unreal at exponent 2.2.
        let mut ends = vec![0.1];
        ends.extend(lay.fitted[..3].iter().map(|s| s.1));
        ends.push(150.0);
        let t = Target {
            ends: &ends,
            distance: 150.0,
            near: 0.1,
            far: 1000.0,
        };
        let mut fitted = engines::unreal::UnrealKnobs {
            cascade_distribution_exponent: 3.0,
            ..k
        };
        <engines::unreal::Unreal as Engine>::match_ends(&mut fitted, &t);
        assert!((fitted.cascade_distribution_exponent - 2.2).abs() < 1e-7, "{fitted:?}");
    }

    #[test]
    fn completed_fractions_keep_the_used_ones_and_stay_increasing() {
        assert_eq!(complete_fractions(&[0.3], [0.1, 0.2, 0.5]), [0.3, 0.65, 0.825]);
        assert_eq!(complete_fractions(&[0.05], [0.1, 0.2, 0.5]), [0.05, 0.2, 0.5]);
        assert_eq!(complete_fractions(&[], [0.1, 0.2, 0.5]), [0.1, 0.2, 0.5]);
    }
}
