//! Seams and transitions between cascades: the blend bands a rig's layout implies, the share
//! of receiver pixels inside them, the shadow-map area the overlap spends twice, and how often
//! world-fixed receivers change cascade while the camera moves (`seam_crossings`).
//!
//! **Band.** At the split between cascades `j − 1` and `j` (`j = 1..m−1`), the band is the
//! view-depth interval inside both fitted slices where the selection already reads the coarser
//! cascade: `[max(splits[j], slices[j].near), min(slices[j−1].far, splits[j+1])]`, empty when
//! the upper end is not above the lower one. csm-lab's own pipeline fits what it selects, so its
//! bands are empty; engines with an overlap, a transition or a fade have one per split.

use glam::{DVec2, DVec3};

use crate::cascades::{LightPose, Rig};
use crate::fitting::Window;
use crate::geometry::CameraPose;
use crate::metrics::cascade_at;
use crate::visibility::Visibility;

/// The blend band at each interior split, `(lo, hi)` with `hi ≥ lo` (equal when there is none);
/// `m − 1` entries.
pub fn bands(rig: &Rig) -> Vec<(f64, f64)> {
    let m = rig.cascade_count();
    (1..m)
        .map(|j| {
            let lo = rig.splits[j].max(rig.slices[j].near);
            let hi = rig.slices[j - 1].far.min(rig.splits[j + 1]);
            (lo, hi.max(lo))
        })
        .collect()
}

/// Per interior split: the share of the lit-facing receiver pixels whose view depth lies in the
/// band `[lo, hi)` (the same denominator as each cascade's share of receiver pixels).
pub fn band_shares(vis: &Visibility, bands: &[(f64, f64)]) -> Vec<f64> {
    let r = &vis.receivers;
    if r.is_empty() {
        return vec![0.0; bands.len()];
    }
    bands
        .iter()
        .map(|&(lo, hi)| {
            let a = r.partition_point(|&(d, _)| d < lo);
            let b = r.partition_point(|&(d, _)| d < hi);
            (b - a) as f64 / r.len() as f64
        })
        .collect()
}

/// Per interior split: the texels of the finer cascade's map (`j − 1`) that render the band's
/// slice of the view frustum — depths the coarser cascade serves and renders too — as a
/// fraction of every cascade's map together (`m · N²`). The slice's light-space footprint is the
/// convex hull of its 8 corners, clipped to the window.
pub fn overlap_area(rig: &Rig, lp: &LightPose, windows: &[Window], bands: &[(f64, f64)]) -> Vec<f64> {
    let m = rig.cascade_count();
    let total: f64 = windows.iter().map(|w| (w.resolution as f64).powi(2)).sum();
    bands
        .iter()
        .enumerate()
        .map(|(k, &(lo, hi))| {
            if hi <= lo || m < 2 {
                return 0.0;
            }
            let i = k; // the finer cascade at split k + 1
            let basis = rig.basis(i, lp);
            let corners = LightPose::new(&basis, &lp.pose).corners(&rig.lens, lo, hi);
            let w = &windows[i];
            let wmin = w.min();
            let wmax = wmin + w.texel * w.resolution as f64;
            let clipped = clip_to_rect(&convex_hull(&corners), wmin, wmax);
            let texels = polygon_area(&clipped) / (w.texel.x * w.texel.y);
            if total > 0.0 {
                texels / total
            } else {
                0.0
            }
        })
        .collect()
}

/// Convex hull, counter-clockwise (Andrew's monotone chain).
fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// Sutherland–Hodgman clipping of a convex polygon to an axis-aligned rectangle.
fn clip_to_rect(poly: &[DVec2], min: DVec2, max: DVec2) -> Vec<DVec2> {
    let mut out = poly.to_vec();
    // (axis, bound, keep the side >= bound)
    for (axis, bound, above) in [(0, min.x, true), (0, max.x, false), (1, min.y, true), (1, max.y, false)] {
        if out.is_empty() {
            break;
        }
        let inside = |p: DVec2| if above { p[axis] >= bound } else { p[axis] <= bound };
        let input = std::mem::take(&mut out);
        for k in 0..input.len() {
            let a = input[k];
            let b = input[(k + 1) % input.len()];
            let cut = |a: DVec2, b: DVec2| a + (b - a) * ((bound - a[axis]) / (b[axis] - a[axis]));
            match (inside(a), inside(b)) {
                (true, true) => out.push(b),
                (true, false) => out.push(cut(a, b)),
                (false, true) => {
                    out.push(cut(a, b));
                    out.push(b);
                }
                (false, false) => {}
            }
        }
    }
    out
}

/// Area of a simple polygon (shoelace).
fn polygon_area(poly: &[DVec2]) -> f64 {
    let n = poly.len();
    if n < 3 {
        return 0.0;
    }
    0.5 * (0..n).map(|k| poly[k].perp_dot(poly[(k + 1) % n])).sum::<f64>().abs()
}

/// The world positions of the lit-facing pixels of a visibility pass whose view depth is served
/// (within `[splits[0], splits[m]]`): the receivers [`seam_crossings`] follows.
pub fn receiver_points(vis: &Visibility, splits: &[f64]) -> Vec<DVec3> {
    let (lo, hi) = (splits[0], splits[splits.len() - 1]);
    vis.samples
        .iter()
        .enumerate()
        .filter_map(|(k, s)| {
            let s = (*s)?;
            (s.lit && s.depth >= lo && s.depth <= hi).then(|| vis.position(k, s.depth))
        })
        .collect()
}

/// The cascade a view depth reads under the selection `splits`, or `m` outside `[splits[0],
/// splits[m]]` (no cascade).
fn index(splits: &[f64], d: f64) -> usize {
    let m = splits.len() - 1;
    if d < splits[0] || d > splits[m] {
        m
    } else {
        cascade_at(splits, d)
    }
}

/// The fraction of `points` whose cascade (by their view depth in each frame and the selection
/// `splits`; leaving or entering the shadowed range counts as a change) differs from the
/// previous frame's, averaged over the frame-to-frame steps of `poses`. 0 with fewer than two
/// frames or no point. Memory: one index per point.
pub fn seam_crossings(splits: &[f64], points: &[DVec3], poses: impl IntoIterator<Item = CameraPose>) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let depth = |p: DVec3, pose: &CameraPose| (p - pose.position).dot(pose.forward);
    let mut prev: Vec<usize> = Vec::new();
    let (mut changed, mut steps) = (0u64, 0u64);
    for pose in poses {
        if prev.is_empty() {
            prev = points.iter().map(|&p| index(splits, depth(p, &pose))).collect();
            continue;
        }
        for (k, &p) in points.iter().enumerate() {
            let i = index(splits, depth(p, &pose));
            changed += u64::from(i != prev[k]);
            prev[k] = i;
        }
        steps += 1;
    }
    if steps == 0 {
        0.0
    } else {
        changed as f64 / (steps as f64 * points.len() as f64)
    }
}
