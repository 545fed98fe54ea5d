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

/// Groups of points by their distance from the origin: a point's bound uses its group's
/// largest distance, at most √2 times its own (or 2^-20 of the largest distance of all).
const GROUPS: usize = 41;

/// Counts the frames in which each of a set of world-fixed points changes cascade, frame by
/// frame as the camera moves, without computing every point's depth in every frame.
///
/// Between frames `u` and `u + 1` a point `p`'s view depth `(p − c)·f` changes by
/// `(p − c_u)·(f_{u+1} − f_u) − (c_{u+1} − c_u)·f_{u+1}`, so by at most
/// `(|p − o| + |o − c_u|)·|Δf| + |Δc|·|f_{u+1}|` for any fixed point `o` (frame 0's camera
/// position), plus the rounding of the two computed depths. Its cascade can change only when
/// its depth reaches a split value, so after computing a point's depth and cascade the counter
/// sets it aside until the sum of these bounds since then could reach its distance to the
/// nearest split value (its slack). The sums run as integer odometers (bounds rounded up,
/// slacks rounded down, in units of a power of two), one per group of points of similar
/// distance from `o`, with a monotone queue (a radix heap) of the odometer readings at which each point is due. A
/// point set aside kept its cascade in every frame in between, so each change is counted in
/// the frame it happens: the counts equal a computation of every point in every frame, exactly.
/// A point whose slack is not finite or below the bound of one frame is computed every frame.
pub struct SeamCounter<'a> {
    splits: &'a [f64],
    points: &'a [DVec3],
    /// Each point's cascade as last computed (unchanged since).
    cascade: Vec<usize>,
    /// Frame 0's camera position: distances are measured from it.
    origin: DVec3,
    groups: Vec<Group>,
    /// Which group each point is in.
    group: Vec<u8>,
    /// Odometer units per world unit (a power of two).
    scale: f64,
    prev: Option<CameraPose>,
    /// Points due this frame (reused).
    due: Vec<u32>,
    changed: u64,
    steps: u64,
    evaluated: u64,
}

/// Points of similar distance from the origin, with their odometer.
struct Group {
    /// The largest distance of a point of the group from the origin.
    radius: f64,
    /// The sum, since frame 0, of the group's bound on a depth change per frame, rounded up.
    odometer: u64,
    /// `(reading, point)`: the point is computed again when the odometer reaches the reading.
    due: RadixQueue,
}

/// A monotone min-queue of `(reading, point)` (a radix heap): every reading pushed is at least
/// the last one taken out, so an entry sits in the bucket of the highest bit in which its
/// reading differs from that one, and moves only to lower buckets. Taking out every entry up to
/// a reading costs a few operations per entry, not a heap's sift through log n levels.
struct RadixQueue {
    last: u64,
    buckets: Vec<Vec<(u64, u32)>>,
    /// The smallest reading in each bucket (`u64::MAX` when empty): whether the lowest bucket
    /// holds a due entry is one comparison, not a pass over the bucket every frame.
    mins: [u64; 65],
    /// Bit b set when bucket b holds entries.
    full: u128,
}

impl RadixQueue {
    fn new() -> Self {
        RadixQueue {
            last: 0,
            buckets: vec![Vec::new(); 65],
            mins: [u64::MAX; 65],
            full: 0,
        }
    }

    fn is_empty(&self) -> bool {
        self.full == 0
    }

    #[inline]
    fn bucket(last: u64, reading: u64) -> usize {
        (u64::BITS - (reading ^ last).leading_zeros()) as usize
    }

    /// Adds an entry; `reading` is at least every reading taken out so far.
    #[inline]
    fn push(&mut self, reading: u64, point: u32) {
        debug_assert!(reading >= self.last);
        let b = Self::bucket(self.last, reading);
        self.buckets[b].push((reading, point));
        self.mins[b] = self.mins[b].min(reading);
        self.full |= 1 << b;
    }

    /// Takes out every entry whose reading is at most `limit`, into `out` (in no set order).
    fn take_upto(&mut self, limit: u64, out: &mut Vec<u32>) {
        while self.full != 0 {
            if self.full & 1 != 0 {
                // Bucket 0 holds readings equal to `last`.
                if self.last > limit {
                    return;
                }
                out.extend(self.buckets[0].drain(..).map(|(_, k)| k));
                self.full &= !1;
                self.mins[0] = u64::MAX;
                continue;
            }
            let b = self.full.trailing_zeros() as usize;
            let min = self.mins[b];
            if min > limit {
                return;
            }
            // Every entry of bucket b differs from `min` below bit b: they spread to lower buckets.
            self.last = min;
            let entries = std::mem::take(&mut self.buckets[b]);
            self.full &= !(1 << b);
            self.mins[b] = u64::MAX;
            for &(r, k) in &entries {
                let to = Self::bucket(min, r);
                self.buckets[to].push((r, k));
                self.mins[to] = self.mins[to].min(r);
                self.full |= 1 << to;
            }
            // Keep the emptied bucket's allocation.
            let mut entries = entries;
            entries.clear();
            self.buckets[b] = entries;
        }
    }
}

impl<'a> SeamCounter<'a> {
    /// A counter of `points` under the selection `splits` (sorted), before any frame.
    pub fn new(splits: &'a [f64], points: &'a [DVec3]) -> Self {
        SeamCounter {
            splits,
            points,
            cascade: Vec::new(),
            origin: DVec3::ZERO,
            groups: Vec::new(),
            group: Vec::new(),
            scale: 1.0,
            prev: None,
            due: Vec::new(),
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

    /// Changes per point and step: [`seam_crossings`]. 0 with no step or no point.
    pub fn rate(&self) -> f64 {
        if self.steps == 0 || self.points.is_empty() {
            0.0
        } else {
            self.changed as f64 / (self.steps as f64 * self.points.len() as f64)
        }
    }

    /// Frame 0: every point's cascade, its group and its first due reading.
    fn first(&mut self, pose: &CameraPose) {
        let o = pose.position;
        self.origin = o;
        let dist: Vec<f64> = self.points.iter().map(|p| (*p - o).length()).collect();
        let far = dist.iter().copied().fold(0.0, f64::max);
        // Group by the binary exponent of the distance relative to the farthest; a group's
        // radius is the largest distance actually in it, so a misplaced point costs time only.
        self.group = dist
            .iter()
            .map(|&r| {
                let level = (2.0 * (r / far).log2()).floor();
                let level = if level.is_nan() {
                    0.0
                } else {
                    level.clamp(-(GROUPS as f64 - 1.0), 0.0)
                };
                (level + (GROUPS as f64 - 1.0)) as u8
            })
            .collect();
        self.groups = (0..GROUPS)
            .map(|_| Group {
                radius: 0.0,
                odometer: 0,
                due: RadixQueue::new(),
            })
            .collect();
        for (&g, &r) in self.group.iter().zip(&dist) {
            let radius = &mut self.groups[g as usize].radius;
            *radius = radius.max(r);
        }
        // Units: 2^-32 of the extent of the points and the origin (a power of two, so the
        // conversions to units are exact); 10^6 frames of the largest turns stay below 2^53.
        let extent = far.max(o.length()).max(f64::MIN_POSITIVE);
        let k = (extent.log2().ceil() as i32).clamp(-960, 960);
        self.scale = 2f64.powi(32 - k);
        self.cascade = vec![0; self.points.len()];
        for k in 0..self.points.len() {
            let (cascade, reading) = self.compute(k, pose);
            self.cascade[k] = cascade;
            self.groups[self.group[k] as usize].due.push(reading, k as u32);
        }
    }

    /// A frame after the first: advance the odometers, compute the points that are due.
    fn next(&mut self, prev: &CameraPose, pose: &CameraPose) {
        self.steps += 1;
        let (fq, ft) = (prev.forward.length(), pose.forward.length());
        let turn = (pose.forward - prev.forward).length();
        let o = self.origin;
        // The bound of a point at distance r from the origin: r · per_unit + base.
        let per_unit = turn + KAPPA * (fq + ft);
        let base = (o - prev.position).length() * turn
            + (pose.position - prev.position).length() * ft
            + KAPPA * ((o.length() + prev.position.length()) * fq + (o.length() + pose.position.length()) * ft);
        self.due.clear();
        for g in &mut self.groups {
            if g.due.is_empty() {
                continue;
            }
            let bound = (g.radius * per_unit + base) * (1.0 + ROUNDING) * self.scale;
            // Truncated plus one: at least the bound (a saturated odometer computes every
            // point every frame).
            let step = if bound < 1e18 { bound as u64 + 1 } else { u64::MAX };
            g.odometer = g.odometer.saturating_add(step);
            g.due.take_upto(g.odometer, &mut self.due);
        }
        for n in 0..self.due.len() {
            let k = self.due[n] as usize;
            let (cascade, reading) = self.compute(k, pose);
            self.changed += u64::from(cascade != self.cascade[k]);
            self.cascade[k] = cascade;
            self.groups[self.group[k] as usize].due.push(reading, k as u32);
        }
    }

    /// Point `k`'s cascade in the frame of `pose`, and the odometer reading (of its group, as
    /// it stands) at which it must be computed again.
    fn compute(&mut self, k: usize, pose: &CameraPose) -> (usize, u64) {
        self.evaluated += 1;
        let d = (self.points[k] - pose.position).dot(pose.forward);
        let slack = self.splits.iter().map(|&s| (d - s).abs()).fold(f64::INFINITY, f64::min);
        let units = slack * (1.0 - ROUNDING) * self.scale;
        // Truncated (the floor of a non-negative number); not finite (or NaN): computed
        // again next frame.
        let units = if units.is_finite() { units as u64 } else { 0 };
        let odometer = self.groups[self.group[k] as usize].odometer;
        (index(self.splits, d), odometer.saturating_add(units))
    }
}
