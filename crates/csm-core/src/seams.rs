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
/// Also covers the rounding of a difference of computed vectors relative to their lengths.
const KAPPA: f64 = 1e-14;

/// Inflation of each bound and deflation of each gap, covering the rounding of the few
/// operations that compute them (each a few units in the 16th digit).
const ROUNDING: f64 = 1e-12;

/// Slots of the calendar of due frames (a power of two).
const SLOTS: usize = 1024;

/// Frames a point is set aside at most (its due frame stays far below 2^63).
const MAX_AHEAD: f64 = (1u64 << 40) as f64;

/// Counts the frames in which each of a set of world-fixed points changes cascade, frame by
/// frame as the camera moves, without computing every point's depth in every frame.
///
/// A point's view depth is `D_t = (p − c_t)·f_t`. With `g_t = f_{t+1} − f_t` and
/// `h_t = c_{t+1} − c_t`, its change per frame is `e_t = (p − c_t)·g_t − h_t·f_{t+1}`, and
/// that change's own change is
/// `e_t − e_{t−1} = (p − c_t)·(g_t − g_{t−1}) − h_{t−1}·(g_{t−1} + g_t) − (h_t − h_{t−1})·f_{t+1}`,
/// so at most `w_t(r) = (r + |o − c_t|)·|Δg_t| + |h_{t−1}|·|g_{t−1} + g_t| + |Δh_t|·|f_{t+1}|`
/// for a point at distance `r` from a fixed point `o` (frame 0's camera position): the path's
/// curvature, not its speed (a steady turn or a steady move has a small one). When a point is
/// computed in frame `u` (its depth there and in frame `u − 1`, so its last change `v`), its
/// depth `n` frames later is within `n·v ± (n·η + w·n(n+1)/2 + 2ε)` of `D_u` while every
/// frame's `w_t(r)` stays below `w` (`η` and `ε` the rounding of the computed depths, at most
/// `KAPPA·(|p| + |c|)·|f|` each). Its cascade can change only when its depth reaches a split
/// value, so the point is set aside until the first `n` at which that interval could reach the
/// split value below or above its depth: a quadratic's root, checked by evaluating it. The
/// bounds assumed (`w` per unit distance and absolute, the largest `|c|` and `|f|`) are the
/// counter's: checked every frame against the path's, lowered when the path's fall well below
/// them, and when the path exceeds one every point is computed again (a jump, a new turn) and
/// the bounds raised. A point set aside kept its cascade in every frame in between, so each
/// change is counted in the frame it happens: the counts equal a computation of every point in
/// every frame, exactly. A point whose depth is not finite or on a split value is computed in
/// the next frame.
pub struct SeamCounter<'a> {
    splits: &'a [f64],
    points: &'a [DVec3],
    /// Frame 0's camera position: distances are measured from it.
    origin: DVec3,
    /// Each point's cascade as last computed (unchanged since), its distance `|p − o|` and
    /// magnitude `|p|`, and the frame it must be computed again.
    cascade: Vec<usize>,
    dist: Vec<f64>,
    size: Vec<f64>,
    due: Vec<u64>,
    /// Points by due frame modulo SLOTS (each point once, in the slot of its due frame).
    calendar: Vec<Vec<u32>>,
    /// The bounds assumed since the last time every point was computed: `w = r·curve + bend`,
    /// `|c| ≤ reach`, `|f| ≤ length`. None before the third frame.
    assumed: Option<Assumed>,
    frame: u64,
    poses: [Option<CameraPose>; 2],
    changed: u64,
    steps: u64,
    evaluated: u64,
}

#[derive(Debug, Clone, Copy)]
struct Assumed {
    curve: f64,
    bend: f64,
    reach: f64,
    length: f64,
}

impl<'a> SeamCounter<'a> {
    /// A counter of `points` under the selection `splits` (sorted), before any frame.
    pub fn new(splits: &'a [f64], points: &'a [DVec3]) -> Self {
        SeamCounter {
            splits,
            points,
            origin: DVec3::ZERO,
            cascade: Vec::new(),
            dist: Vec::new(),
            size: Vec::new(),
            due: Vec::new(),
            calendar: Vec::new(),
            assumed: None,
            frame: 0,
            poses: [None, None],
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
        match self.poses {
            [None, _] => self.first(pose),
            [Some(prev), before] => self.next(&prev, before.as_ref(), pose),
        }
        self.poses = [Some(*pose), self.poses[0]];
        self.frame += 1;
    }

    /// Changes counted so far (a point changing cascade between two consecutive frames).
    pub fn changes(&self) -> u64 {
        self.changed
    }

    /// Frame-to-frame steps so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Depths computed so far (points × frames for the brute-force count; a point computed
    /// in a frame counts once though its depth in the frame before is computed too).
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

    /// Frame 0: every point's cascade; every point is due in frame 1.
    fn first(&mut self, pose: &CameraPose) {
        let o = pose.position;
        self.origin = o;
        self.dist = self.points.iter().map(|p| (*p - o).length()).collect();
        self.size = self.points.iter().map(|p| p.length()).collect();
        self.cascade = self
            .points
            .iter()
            .map(|p| index(self.splits, (*p - pose.position).dot(pose.forward)))
            .collect();
        self.evaluated += self.points.len() as u64;
        self.due = vec![1; self.points.len()];
        self.calendar = vec![Vec::new(); SLOTS];
        self.calendar[1] = (0..self.points.len() as u32).collect();
    }

    /// A frame after the first: check the assumed bounds against the path's, then compute
    /// the points that are due (every point when a bound was exceeded).
    fn next(&mut self, prev: &CameraPose, before: Option<&CameraPose>, pose: &CameraPose) {
        self.steps += 1;
        let t = self.frame;
        let mut all = false;
        if let Some(b) = before {
            // The curvature of frame t − 1 (poses t − 2, t − 1, t): `w_{t−1}(r) = r·curve + bend`.
            let o = self.origin;
            let (g0, g1) = (prev.forward - b.forward, pose.forward - prev.forward);
            let (h0, h1) = (prev.position - b.position, pose.position - prev.position);
            let dg = (g1 - g0).length() + KAPPA * (g0.length() + g1.length());
            let dh = (h1 - h0).length() + KAPPA * (h0.length() + h1.length());
            let up = 1.0 + ROUNDING;
            let curve = dg * up;
            let bend = ((o - prev.position).length() * dg
                + h0.length() * ((g0 + g1).length() + KAPPA * (g0.length() + g1.length()))
                + dh * pose.forward.length())
                * up;
            let reach = pose.position.length().max(prev.position.length());
            let length = pose.forward.length().max(prev.forward.length());
            let fits = |a: &Assumed| curve <= a.curve && bend <= a.bend && reach <= a.reach && length <= a.length;
            match &mut self.assumed {
                Some(a) if fits(a) => {
                    // Lowering a bound keeps every prediction made under the higher one.
                    if 4.0 * curve < a.curve {
                        a.curve = 2.0 * curve;
                    }
                    if 4.0 * bend < a.bend {
                        a.bend = 2.0 * bend;
                    }
                }
                _ => {
                    all = true;
                    // Room for the path to vary before every point is computed again.
                    self.assumed = Some(Assumed {
                        curve: 2.0 * curve,
                        bend: 2.0 * bend,
                        reach: 2.0 * reach + o.length(),
                        length: 2.0 * length,
                    });
                }
            }
        }
        if all {
            for slot in &mut self.calendar {
                slot.clear();
            }
            for k in 0..self.points.len() {
                self.compute(k, t, prev, pose);
            }
            return;
        }
        let slot = t as usize % SLOTS;
        let entries = std::mem::take(&mut self.calendar[slot]);
        let mut kept = Vec::new();
        for &k in &entries {
            if self.due[k as usize] <= t {
                self.compute(k as usize, t, prev, pose);
            } else {
                kept.push(k);
            }
        }
        // Entries due in a later turn of the calendar stay; computed points were pushed to
        // the slots of their new due frames (this slot's included).
        let mut entries = entries;
        entries.clear();
        entries.extend(kept);
        entries.append(&mut self.calendar[slot]);
        self.calendar[slot] = entries;
    }

    /// Point `k`'s cascade in frame `t` (pose `pose`, after `prev`): counts a change, and sets
    /// the frame it must be computed again.
    fn compute(&mut self, k: usize, t: u64, prev: &CameraPose, pose: &CameraPose) {
        self.evaluated += 1;
        let p = self.points[k];
        let d = (p - pose.position).dot(pose.forward);
        let cascade = index(self.splits, d);
        self.changed += u64::from(cascade != self.cascade[k]);
        self.cascade[k] = cascade;
        let ahead = match &self.assumed {
            Some(a) => self.frames_ahead(k, d, (p - prev.position).dot(prev.forward), a),
            None => 0,
        };
        let due = t + 1 + ahead;
        self.due[k] = due;
        self.calendar[due as usize % SLOTS].push(k as u32);
    }

    /// How many frames after this one point `k` keeps its cascade for sure: its depth `d` here
    /// and `d0` one frame before, under the bounds `a`.
    fn frames_ahead(&self, k: usize, d: f64, d0: f64, a: &Assumed) -> u64 {
        if !(d.is_finite() && d0.is_finite()) {
            return 0;
        }
        // The nearest split values below and above `d` (the cascade is constant between them).
        let mut below = f64::NEG_INFINITY;
        let mut above = f64::INFINITY;
        for &s in self.splits {
            if s < d {
                below = below.max(s);
            } else if s > d {
                above = above.min(s);
            } else {
                return 0;
            }
        }
        let up = 1.0 + ROUNDING;
        // The rounding of one computed depth in any frame of the assumed bounds.
        let eps = KAPPA * (self.size[k] + a.reach) * a.length * up;
        let v = d - d0;
        // The computed change `v` against the true one: two depths' rounding and its own.
        let eta = (2.0 * eps + v.abs() * 2.5e-16) * up;
        let w = (self.dist[k] * up * a.curve + a.bend) * up;
        let half = 0.5 * w;
        // Side above: half·n² + (v + eta + half)·n < gap − 2·eps; below: with −v.
        let side = |slope: f64, gap: f64| -> f64 {
            if gap == f64::INFINITY {
                // No split value on this side.
                return MAX_AHEAD;
            }
            let c = gap * (1.0 - ROUNDING) - 2.0 * eps * up;
            if c.is_nan() || c <= 0.0 {
                return 0.0;
            }
            let b = slope + eta + half;
            let root = if b >= 0.0 {
                2.0 * c / (b + (b * b + 4.0 * half * c).sqrt())
            } else {
                (-b + (b * b + 4.0 * half * c).sqrt()) / (2.0 * half)
            };
            // NaN (0/0) gives 0; infinity the cap.
            let n = (root * (1.0 - 1e-9)).floor().clamp(0.0, MAX_AHEAD);
            let n = if n.is_nan() { 0.0 } else { n };
            // Checked: the quadratic below zero at n (so on 0..=n, being convex and below zero
            // at 0), with room for the rounding of this check.
            let lhs = (half * n + b) * n;
            let room = 1e-12 * ((half * n + slope.abs() + eta + half) * n);
            if lhs + room < c * (1.0 - ROUNDING) {
                n
            } else {
                0.0
            }
        };
        let n = side(v, above - d).min(side(-v, d - below));
        n as u64
    }
}
