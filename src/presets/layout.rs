//! Split rules: each preset's fitted slices and selection boundaries, as view depths.

use super::*;

/// Where a preset's cascades are, before the camera's planes clip the selection.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Fitted slices, near to far: what each window is built around.
    pub fitted: Vec<(f64, f64)>,
    /// Selection boundaries (one more than cascades): cascade `i` serves view depths
    /// `[selection[i], selection[i+1])`; ±infinity where the engine has no bound.
    pub selection: Vec<f64>,
}

impl Layout {
    /// Consecutive boundaries as both fitted slices and selection.
    pub fn contiguous(splits: Vec<f64>) -> Layout {
        Layout {
            fitted: splits.windows(2).map(|w| (w[0], w[1])).collect(),
            selection: splits,
        }
    }
}

/// Practical split exactly as seed 000 writes it: the last boundary also from the formula.
pub fn dart_splits(near: f64, far: f64, cascades: usize, lambda: f64) -> Vec<f64> {
    let count = cascades.clamp(1, 4);
    let mut s = vec![near];
    for i in 1..=count {
        let ratio = i as f64 / count as f64;
        let log = near * (far / near).powf(ratio);
        let uni = near + (far - near) * ratio;
        s.push(lambda * log + (1.0 - lambda) * uni);
    }
    s
}

/// three.js `breaks`: far end of each cascade as a fraction of `far`, the last one 1.
pub fn threejs_breaks(mode: ThreejsMode, cascades: usize, near: f64, far: f64) -> Vec<f64> {
    let m = cascades as f64;
    let uniform = |i: f64| (near + (far - near) * i / m) / far;
    let log = |i: f64| near * (far / near).powf(i / m) / far;
    let mut b: Vec<f64> = (1..cascades)
        .map(|i| {
            let i = i as f64;
            match mode {
                ThreejsMode::Uniform => uniform(i),
                ThreejsMode::Logarithmic => log(i),
                // lerp(uniform, log, 0.5)
                ThreejsMode::Practical => 0.5 * uniform(i) + 0.5 * log(i),
            }
        })
        .collect();
    b.push(1.0);
    b
}

/// Bevy far bounds: `first·(max/first)^(i/(N−1))`, or just `max` for one cascade.
pub fn bevy_far_bounds(cascades: usize, first: f64, max: f64) -> Vec<f64> {
    if cascades == 1 {
        return vec![max];
    }
    (0..cascades)
        .map(|i| first * (max / first).powf(i as f64 / (cascades - 1) as f64))
        .collect()
}

/// EEVEE 2017 split ends and (fade-overlapped) starts on `[start, end]`.
pub fn eevee_starts_ends(start: f64, end: f64, cascades: usize, lambda: f64, fade: f64) -> (Vec<f64>, Vec<f64>) {
    let m = cascades;
    let mut starts = vec![start; m];
    let mut ends = vec![end; m];
    let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
    for c in 1..m {
        let r = c as f64 / m as f64;
        let linear = lerp(r, start, end);
        let exp = start * (end / start).powf(r);
        ends[c - 1] = lerp(lambda, linear, exp);
        let prev = if c > 1 { ends[c - 2] } else { starts[0] };
        starts[c] = lerp(fade, ends[c - 1], prev);
    }
    (starts, ends)
}

/// Unreal split distances: `near + (Σ_{k<i} e^k / Σ_{k<N} e^k)·(distance − near)`.
pub fn unreal_splits(cascades: usize, exponent: f64, near: f64, distance: f64) -> Vec<f64> {
    let total: f64 = (0..cascades).map(|k| exponent.powi(k as i32)).sum();
    let mut acc = 0.0;
    let mut out = vec![near];
    for i in 1..cascades {
        acc += exponent.powi(i as i32 - 1);
        out.push(near + acc / total * (distance - near));
    }
    out.push(distance);
    out
}

/// Filament split positions in (0, 1) for `cascades`.
pub fn filament_positions(k: &FilamentKnobs, cascades: usize, near: f64, far: f64) -> Vec<f64> {
    let m = cascades as f64;
    (1..cascades)
        .map(|c| {
            let c = c as f64;
            let uniform = c / m;
            let log = (near * (far / near).powf(c / m) - near) / (far - near);
            match k.split_mode {
                FilamentSplit::Positions => k.split_positions[c as usize - 1],
                FilamentSplit::Uniform => uniform,
                FilamentSplit::Logarithmic => log,
                FilamentSplit::Practical => k.lambda * log + (1.0 - k.lambda) * uniform,
            }
        })
        .collect()
}

/// The fitted slices and selection boundaries of a preset. `max_distance` is the engine's
/// shadow distance (unused by presets without one); `near`/`far` are the camera planes.
pub fn layout(knobs: &Knobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
    let inf = f64::INFINITY;
    match knobs {
        Knobs::Dart(d) => Layout::contiguous(dart_splits(near, max_distance, cascades, d.lambda)),
        Knobs::Threejs(t) => {
            let f = far.min(max_distance);
            let b = threejs_breaks(t.mode, cascades, near, f);
            // r185: cascade i spans [b_{i-1} F, b_i F], the first starting at the near plane;
            // the WebGL shader selects on [b_{i-1} (F - n), b_i (F - n)).
            let fitted = (0..cascades)
                .map(|i| (if i == 0 { near } else { b[i - 1] * f }, b[i] * f))
                .collect();
            let mut selection = vec![-inf];
            selection.extend(b.iter().map(|x| x * (f - near)));
            Layout { fitted, selection }
        }
        Knobs::UnitySample(_) => {
            // Accumulated in the seed's own order (far * p + ... + near).
            let (n, f) = (near, far);
            let e = [
                f * 0.067 + n,
                f * 0.133 + f * 0.067 + n,
                f * 0.267 + f * 0.133 + f * 0.067 + n,
            ];
            Layout::contiguous(vec![n, e[0], e[1], e[2], f])
        }
        Knobs::Eevee(e) => {
            let end = near.max(far.min(max_distance));
            let (starts, ends) = eevee_starts_ends(near, end, cascades, e.cascade_exponent, e.fade);
            // In the fade band [start_c, end_{c-1}] both cascades are read: the coarser (c)
            // counts for selection.
            let mut selection = starts.clone();
            selection.push(end);
            Layout {
                fitted: starts.into_iter().zip(ends).collect(),
                selection,
            }
        }
        Knobs::LearnOpenGl(l) => {
            let p = &l.planes;
            let m = p.len() - 1;
            // index = #(planes[0..m] below the depth), clamped to m - 1: depth <= p0 reads
            // cascade 0 (slice [p0, p1]), (p0, p1] reads cascade 1, ..., beyond p_{m-2} the last.
            let mut selection = vec![-inf];
            selection.extend_from_slice(&p[..m - 1]);
            selection.push(inf);
            Layout {
                fitted: p.windows(2).map(|w| (w[0], w[1])).collect(),
                selection,
            }
        }
        Knobs::Bevy(b) => {
            let fars = bevy_far_bounds(cascades, b.first_cascade_far_bound, max_distance);
            let nears: Vec<f64> = (0..cascades)
                .map(|i| {
                    if i == 0 {
                        b.minimum_distance
                    } else {
                        (1.0 - b.overlap_proportion) * fars[i - 1]
                    }
                })
                .collect();
            // Cascade 0 serves everything nearer than its far bound; in the blend band
            // [(1 - p) far_i, far_i] the coarser cascade i + 1 counts; nothing beyond the last.
            let mut selection = vec![-inf];
            selection.extend_from_slice(&nears[1..]);
            selection.push(fars[cascades - 1]);
            Layout {
                fitted: nears.into_iter().zip(fars).collect(),
                selection,
            }
        }
        Knobs::Godot(g) => {
            let max_d = far.min(max_distance).max(near + 0.001);
            let min_d = near.min(max_d);
            let used: &[f64] = match cascades {
                1 => &[],
                2 => &g.splits[..1],
                _ => &g.splits[..],
            };
            let mut d = vec![min_d];
            d.extend(used.iter().map(|s| min_d + s * (max_d - min_d)));
            d.push(max_d);
            if g.blend_splits {
                // Each cascade after the first also covers the previous one; the last 10 % of
                // each interval blends toward the next (coarser) cascade.
                let m = d.len() - 1;
                let fitted = (0..m).map(|i| (d[i.saturating_sub(1)], d[i + 1])).collect();
                let mut selection = vec![d[0]];
                selection.extend(d[1..m].iter().map(|x| 0.9 * x));
                selection.push(d[m]);
                Layout { fitted, selection }
            } else {
                Layout::contiguous(d)
            }
        }
        Knobs::Unreal(u) => {
            let s = unreal_splits(cascades, u.cascade_distribution_exponent, near, max_distance);
            let m = cascades;
            let fitted = (0..m)
                .map(|i| {
                    let (a, b) = (s[i], s[i + 1]);
                    // Every far end but the last is extended by the transition band.
                    let ext = if i + 1 < m {
                        (b - a) * u.transition_fraction
                    } else {
                        0.0
                    };
                    (a, b + ext)
                })
                .collect();
            Layout { fitted, selection: s }
        }
        Knobs::Unity(u) => {
            let dist = far.min(max_distance);
            let fr: &[f64] = match cascades {
                1 => &[],
                2 => std::slice::from_ref(&u.cascade2_split),
                _ => &u.cascade4_split[..],
            };
            Layout::contiguous(fraction_splits(near, dist, fr))
        }
        Knobs::UnityUrp(u) => {
            let dist = far.min(max_distance);
            let fr: &[f64] = match cascades {
                1 => &[],
                2 => std::slice::from_ref(&u.cascade2_split),
                3 => &u.cascade3_split[..],
                _ => &u.cascade4_split[..],
            };
            Layout::contiguous(fraction_splits(near, dist, fr))
        }
        Knobs::Filament(k) => {
            let f = max_distance;
            let p = filament_positions(k, cascades, near, f);
            let mut s = vec![near];
            s.extend(p.iter().map(|p| near + (f - near) * p));
            s.push(f);
            Layout::contiguous(s)
        }
    }
}

/// Unity's cascade boundaries: fractions of the shadow distance measured from the eye, the
/// first cascade starting at the near plane.
fn fraction_splits(near: f64, distance: f64, fractions: &[f64]) -> Vec<f64> {
    let mut s = vec![near];
    s.extend(fractions.iter().map(|f| f * distance));
    s.push(distance);
    s
}

/// Clips selection boundaries to the visible depths `[near, far]`, keeping them
/// non-decreasing; None when no visible depth reads any cascade.
pub fn clip_selection(selection: &[f64], near: f64, far: f64) -> Option<Vec<f64>> {
    let lo = near.max(selection[0]);
    let hi = far.min(selection[selection.len() - 1]);
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mut out = Vec::with_capacity(selection.len());
    out.push(lo);
    let mut prev = lo;
    for s in &selection[1..selection.len() - 1] {
        prev = s.clamp(lo, hi).max(prev);
        out.push(prev);
    }
    out.push(hi);
    Some(out)
}
