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
    let terms = vis.view.ray_terms();
    vis.samples
        .iter()
        .enumerate()
        .filter_map(|(k, s)| {
            let s = s?;
            (s.lit && s.depth >= lo && s.depth <= hi).then(|| terms.point(k, s.depth))
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
/// frames or no point. [`SeamCounter`] fed every pose: memory is a few words per point,
/// whatever the path's length.
pub fn seam_crossings(splits: &[f64], points: &[DVec3], poses: impl IntoIterator<Item = CameraPose>) -> f64 {
    let mut counter = SeamCounter::new(splits, points);
    for pose in poses {
        counter.frame(&pose);
    }
    counter.rate()
}

/// Relative bound on the rounding of a computed view depth `(p − c)·f`: at most
/// `KAPPA · (|p| + |c|) · |f|` (the true bound is about 4 units in the last place, 9e-16).
const KAPPA: f64 = 1e-14;

/// Inflation of each frame's depth bound and deflation of each slack, covering the rounding of
/// the few operations that compute them (each a few units in the 16th digit).
const ROUNDING: f64 = 1e-12;

/// Distance levels per octave: a group's points are within a factor `2^(1/LEVELS_PER_OCTAVE)`
/// of each other's distance from the origin (or closer than 2^-20 of the largest distance).
const LEVELS_PER_OCTAVE: f64 = 4.0;

/// Distance levels in all (20 octaves).
const LEVELS: f64 = 80.0;

/// Direction cells per side of each of the 6 faces of a cube around the origin: a group's
/// points also share the cell of their direction from the origin.
const FACE_CELLS: f64 = 8.0;

/// Counts the frames in which each of a set of world-fixed points changes cascade, frame by
/// frame as the camera moves, without computing every point's depth in every frame.
///
/// Between frames `u` and `u + 1` a point `p`'s view depth `(p − c)·f` changes by
/// `(p − c_u)·(f_{u+1} − f_u) − (c_{u+1} − c_u)·f_{u+1}`, so by at most
/// `|(p − o)·Δf| + |o − c_u|·|Δf| + |Δc|·|f_{u+1}|` for any fixed point `o` (frame 0's camera
/// position), plus the rounding of the two computed depths. The points are grouped by their
/// distance and direction from `o` (a small cell of space around `q`, the mean of its points,
/// and `ρ`, their largest distance from it): for every point of a group
/// `|(p − o)·Δf| ≤ min(R·|Δf|, |(q − o)·Δf| + ρ·|Δf|)`, `R` the group's largest distance from
/// `o`. The second form is what makes the bound tight: while the camera turns, a group's
/// depths change at about the rate of its centre's, not of its distance. A point's cascade can
/// change only when its depth reaches a split value, so after computing a point's depth and
/// cascade the counter sets it aside until the sum of its group's bounds since then could
/// reach its distance to the nearest split value (its slack). The sums run as integer
/// odometers (bounds rounded up, slacks rounded down, in units of a power of two), one per
/// group, with each point's due reading and each group's smallest. A point set aside kept its
/// cascade in every frame in between, so each change is counted in the frame it happens: the
/// counts equal a computation of every point in every frame, exactly. A point whose slack is
/// not finite or below the bound of one frame is computed every frame.
pub struct SeamCounter<'a> {
    splits: &'a [f64],
    points: &'a [DVec3],
    /// Frame 0's camera position: distances and directions are measured from it.
    origin: DVec3,
    /// The points, group by group (`starts[g]..starts[g + 1]`).
    order: Vec<DVec3>,
    starts: Vec<usize>,
    /// Each point (in `order`) as last computed: its cascade, and the reading of its group's
    /// odometer at which it must be computed again.
    cascade: Vec<usize>,
    reading: Vec<u64>,
    /// Per group: `q − o`, `R`, `ρ + KAPPA·|q − o|`, the odometer and its smallest due reading.
    centre: Vec<DVec3>,
    radius: Vec<f64>,
    spread: Vec<f64>,
    odometer: Vec<u64>,
    next_due: Vec<u64>,
    /// Odometer units per world unit (a power of two).
    scale: f64,
    prev: Option<CameraPose>,
    changed: u64,
    steps: u64,
    evaluated: u64,
}

impl<'a> SeamCounter<'a> {
    /// A counter of `points` under the selection `splits` (sorted), before any frame.
    pub fn new(splits: &'a [f64], points: &'a [DVec3]) -> Self {
        SeamCounter {
            splits,
            points,
            origin: DVec3::ZERO,
            order: Vec::new(),
            starts: Vec::new(),
            cascade: Vec::new(),
            reading: Vec::new(),
            centre: Vec::new(),
            radius: Vec::new(),
            spread: Vec::new(),
            odometer: Vec::new(),
            next_due: Vec::new(),
            scale: 1.0,
            prev: None,
            changed: 0,
            steps: 0,
            evaluated: 0,
        }
    }

    /// The next frame's camera pose.
    pub fn frame(&mut self, pose: &CameraPose) {
        if self.points.is_empty() {
            return;
        }
        match self.prev {
            None => self.first(pose),
            Some(prev) => self.next(&prev, pose),
        }
        self.prev = Some(*pose);
    }

    /// Changes counted so far (a point changing cascade between two consecutive frames).
    pub fn changes(&self) -> u64 {
        self.changed
    }

    /// Frame-to-frame steps so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Depths computed so far (points × frames for the brute-force count).
    pub fn evaluations(&self) -> u64 {
        self.evaluated
    }

    /// Groups of points the counter keeps an odometer for (0 before the first frame).
    pub fn groups(&self) -> usize {
        self.odometer.len()
    }

    /// Changes per point and step: [`seam_crossings`]. 0 with no step or no point.
    pub fn rate(&self) -> f64 {
        if self.steps == 0 || self.points.is_empty() {
            0.0
        } else {
            self.changed as f64 / (self.steps as f64 * self.points.len() as f64)
        }
    }

    /// Frame 0: the groups, every point's cascade and its first due reading.
    fn first(&mut self, pose: &CameraPose) {
        let o = pose.position;
        self.origin = o;
        let rel: Vec<DVec3> = self.points.iter().map(|p| *p - o).collect();
        let dist: Vec<f64> = rel.iter().map(|v| v.length()).collect();
        let far = dist.iter().copied().fold(0.0, f64::max);
        // A group is a distance level and a direction cell (a cell of a cube's face); a
        // misplaced point (NaN, or at the origin) only costs time: the bounds hold for any
        // grouping.
        let key = |v: DVec3, r: f64| -> u64 {
            let level = (LEVELS_PER_OCTAVE * (r / far).log2()).floor();
            let level = if level.is_nan() {
                0.0
            } else {
                level.clamp(-(LEVELS - 1.0), 0.0)
            };
            let a = v.abs();
            let (face, s, t) = if a.x >= a.y && a.x >= a.z {
                (u64::from(v.x < 0.0), v.y / a.x, v.z / a.x)
            } else if a.y >= a.z {
                (2 + u64::from(v.y < 0.0), v.x / a.y, v.z / a.y)
            } else {
                (4 + u64::from(v.z < 0.0), v.x / a.z, v.y / a.z)
            };
            // `as` saturates (NaN to 0).
            let cell = |c: f64| (((c + 1.0) * 0.5 * FACE_CELLS) as u64).min(FACE_CELLS as u64 - 1);
            ((((level + LEVELS) as u64) * 6 + face) * 64 + cell(s)) * 64 + cell(t)
        };
        let keys: Vec<u64> = rel.iter().zip(&dist).map(|(v, &r)| key(*v, r)).collect();
        let mut idx: Vec<u32> = (0..self.points.len() as u32).collect();
        idx.sort_by_key(|&k| (keys[k as usize], k));
        self.order = idx.iter().map(|&k| self.points[k as usize]).collect();
        self.starts.clear();
        for (n, &k) in idx.iter().enumerate() {
            if n == 0 || keys[k as usize] != keys[idx[n - 1] as usize] {
                self.starts.push(n);
            }
        }
        self.starts.push(idx.len());
        let groups = self.starts.len() - 1;
        self.centre = Vec::with_capacity(groups);
        self.radius = Vec::with_capacity(groups);
        self.spread = Vec::with_capacity(groups);
        for g in 0..groups {
            let members = &idx[self.starts[g]..self.starts[g + 1]];
            let sum = members.iter().fold(DVec3::ZERO, |s, &k| s + rel[k as usize]);
            let q = sum / members.len() as f64;
            let radius = members.iter().fold(0.0f64, |m, &k| m.max(dist[k as usize]));
            // |p − q| for the real values, within the rounding of `p − o` (relative to
            // |p − o|), of the subtraction of `q` and of the length: covered by KAPPA.
            let rho = members.iter().fold(0.0f64, |m, &k| {
                let v = rel[k as usize];
                m.max((v - q).length() + KAPPA * (v.length() + q.length()))
            });
            self.centre.push(q);
            self.radius.push(radius);
            self.spread.push(rho + KAPPA * q.length());
        }
        // Units: 2^-32 of the extent of the points and the origin (a power of two, so the
        // conversions to units are exact); 10^6 frames of the largest turns stay below 2^53.
        let extent = far.max(o.length()).max(f64::MIN_POSITIVE);
        let k = (extent.log2().ceil() as i32).clamp(-960, 960);
        self.scale = 2f64.powi(32 - k);
        self.odometer = vec![0; groups];
        self.next_due = vec![u64::MAX; groups];
        self.cascade = vec![0; self.points.len()];
        self.reading = vec![0; self.points.len()];
        for g in 0..groups {
            for k in self.starts[g]..self.starts[g + 1] {
                let (cascade, reading) = self.compute(k, g, pose);
                self.cascade[k] = cascade;
                self.reading[k] = reading;
                self.next_due[g] = self.next_due[g].min(reading);
            }
        }
    }

    /// A frame after the first: advance the odometers, compute the points that are due.
    fn next(&mut self, prev: &CameraPose, pose: &CameraPose) {
        self.steps += 1;
        let (fq, ft) = (prev.forward.length(), pose.forward.length());
        let df = pose.forward - prev.forward;
        let turn = df.length();
        let o = self.origin;
        // The bound of a point of group g: min(R·turn, |(q − o)·Δf| + spread·turn) + R·kappa
        // + base (the rounding of `Δf`, of its length and of the dot product: relative,
        // covered by ROUNDING; the dot product's cancellation: KAPPA·|q − o| in the spread).
        let kappa = KAPPA * (fq + ft);
        let base = (o - prev.position).length() * turn
            + (pose.position - prev.position).length() * ft
            + KAPPA * ((o.length() + prev.position.length()) * fq + (o.length() + pose.position.length()) * ft);
        let groups = self.odometer.len();
        for g in 0..groups {
            let r = self.radius[g];
            let lateral = self.centre[g].dot(df).abs() + self.spread[g] * turn;
            let bound = ((r * turn).min(lateral) + r * kappa + base) * (1.0 + ROUNDING) * self.scale;
            // Truncated plus one: at least the bound (a saturated odometer computes every
            // point every frame).
            let step = if bound < 1e18 { bound as u64 + 1 } else { u64::MAX };
            let odometer = self.odometer[g].saturating_add(step);
            self.odometer[g] = odometer;
            if odometer < self.next_due[g] {
                continue;
            }
            let mut due = u64::MAX;
            for k in self.starts[g]..self.starts[g + 1] {
                if self.reading[k] <= odometer {
                    let (cascade, reading) = self.compute(k, g, pose);
                    self.changed += u64::from(cascade != self.cascade[k]);
                    self.cascade[k] = cascade;
                    self.reading[k] = reading;
                }
                due = due.min(self.reading[k]);
            }
            self.next_due[g] = due;
        }
    }

    /// Point `k`'s (in group order) cascade in the frame of `pose`, and the reading of its
    /// group `g`'s odometer (as it stands) at which it must be computed again.
    #[inline]
    fn compute(&mut self, k: usize, g: usize, pose: &CameraPose) -> (usize, u64) {
        self.evaluated += 1;
        let d = (self.order[k] - pose.position).dot(pose.forward);
        let slack = self.splits.iter().map(|&s| (d - s).abs()).fold(f64::INFINITY, f64::min);
        let units = slack * (1.0 - ROUNDING) * self.scale;
        // Truncated (the floor of a non-negative number); not finite (or NaN): computed
        // again next frame.
        let units = if units.is_finite() { units as u64 } else { 0 };
        (index(self.splits, d), self.odometer[g].saturating_add(units))
    }
}
