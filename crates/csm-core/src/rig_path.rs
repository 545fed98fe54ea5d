//! The exact f64 rig walked along the camera path: probe placement, the rig as a
//! [`PathModel`] ([`RigPath`]), and the walks that measure shimmer and coverage for one or both
//! snap modes. The metrics themselves (S1, S3, S4, coverage) are defined in [`crate::shimmer`];
//! the walk is [`crate::walk::walk`]; the binary32 pipeline is the other path model
//! ([`crate::precision`]).

use std::borrow::Borrow;

use glam::{DVec2, DVec3};

use crate::cascades::{bounds_2d, LightPose, Rig, WindowRule};
use crate::fitting::{Fit, Window};
use crate::geometry::{Aabb, CameraPose, LightBasis};
use crate::light_motion::LightTrack;
use crate::rng::halton;
use crate::shimmer::{floor_exact, round_half_away, PathResult, ShimmerOptions};
use crate::snapping::{SnapMode, SnapRule};
use crate::walk::{closed_form_drift, walk, walk_cached, Cadence, Landing, PathModel, PathTotals};

/// World-fixed probe points for each cascade, placed in the configured camera's slice and,
/// where possible, inside the scene bounds: receivers that exist. Deterministic (Halton).
pub fn probes(rig: &Rig, pose0: &CameraPose, scene: &Aabb, per_cascade: usize) -> Vec<Vec<DVec3>> {
    let lens = &rig.lens;
    rig.slices
        .iter()
        .enumerate()
        .map(|(i, s)| {
            // Probes go where the cascade is read: its selection interval (the fitted slice
            // when the selection is empty; the two are equal in csm-lab's own pipeline).
            let (near, far) = match rig.selection(i) {
                (a, b) if b > a => (a, b),
                _ => (s.near, s.far),
            };
            let point = |j: u64| {
                let z = near + (far - near) * halton(j, 2);
                let sx = (2.0 * halton(j, 3) - 1.0) * lens.tan_h;
                let sy = (2.0 * halton(j, 5) - 1.0) * lens.tan_v;
                pose0.point(sx, sy, z)
            };
            let eps = 1e-9 * (scene.max - scene.min).max_element().max(1.0);
            let offset = 1 + 7919 * i as u64;
            let mut out: Vec<DVec3> = (0..16 * per_cascade as u64)
                .map(|j| point(offset + j))
                .filter(|p| scene.contains(*p, eps))
                .take(per_cascade)
                .collect();
            let mut j = 0;
            while out.len() < per_cascade {
                out.push(point(offset + j));
                j += 1;
            }
            out
        })
        .collect()
}

/// True when [`along_path`] evaluates probes with these options: for S4, on request, or
/// whenever a window can change size between frames. A sphere-fit window's side is fixed per
/// cascade in the [`Rig`] (never recomputed per frame), so its S3 always has the closed form
/// and needs no probes; callers may then pass empty probe lists.
pub fn needs_probes(rig: &Rig, opts: ShimmerOptions) -> bool {
    opts.cell_flips || opts.probe_drift || rig.fit != Fit::Sphere || !fast_walk_applies(rig)
}

/// Whether the fast coverage test serves this rig: a fixed light basis, and each cascade's
/// selection interval inside its fitted slice (so the slice corners decide coverage). True for
/// csm-lab's own fits and most engine presets; the others are checked with [`Rig::coverage`].
fn fast_walk_applies(rig: &Rig) -> bool {
    rig.fixed_basis()
        && (0..rig.cascade_count()).all(|i| {
            let (a, b) = rig.selection(i);
            b <= a || (a >= rig.slices[i].near && b <= rig.slices[i].far)
        })
}

/// Walk the path once for one snap mode: shimmer and coverage together, so each window is
/// computed once per frame.
pub fn along_path<P: Borrow<CameraPose>>(
    rig: &Rig,
    poses: impl IntoIterator<Item = P, IntoIter: ExactSizeIterator>,
    probes: &[Vec<DVec3>],
    snapped: bool,
    opts: ShimmerOptions,
) -> PathResult {
    along_path_lit(rig, poses, probes, None, snapped, opts)
}

/// [`along_path`] under a moving light (`light`; None or a still light is [`along_path`]).
pub fn along_path_lit<P: Borrow<CameraPose>>(
    rig: &Rig,
    poses: impl IntoIterator<Item = P, IntoIter: ExactSizeIterator>,
    probes: &[Vec<DVec3>],
    light: Option<LightTrack<'_>>,
    snapped: bool,
    opts: ShimmerOptions,
) -> PathResult {
    let [r] = walk(&mut model(rig, probes, light), poses, [snapped], opts);
    r.finish(opts)
}

/// [`along_path`] with cached cascades (see [`Cadence`]; [`Cadence::EVERY_FRAME`] is
/// [`along_path`], bit for bit), one result per snap mode of `modes` in its order: `[snapped]`
/// for one walk, `[true, false]` for both modes in one walk (as [`along_path_both`]). The held
/// windows keep the rig's light basis, so the rig's basis must not follow the camera
/// ([`Rig::fixed_basis`]) and the light must stand still.
pub fn along_path_cached<P: Borrow<CameraPose>, const K: usize>(
    rig: &Rig,
    poses: impl IntoIterator<Item = P, IntoIter: ExactSizeIterator>,
    probes: &[Vec<DVec3>],
    cadence: Cadence<'_>,
    modes: [bool; K],
    opts: ShimmerOptions,
) -> [PathResult; K] {
    walk_cached(&mut RigPath::new(rig, probes), poses, modes, opts, cadence).map(|r| r.finish(opts))
}

fn model<'a>(rig: &'a Rig, probes: &'a [Vec<DVec3>], light: Option<LightTrack<'a>>) -> RigPath<'a> {
    let m = RigPath::new(rig, probes);
    match light {
        Some(l) => m.with_light(l),
        None => m,
    }
}

/// Both snap modes in one walk, `(snapped, unsnapped)`: the same results as two calls of
/// [`along_path`], bit for bit, with the per-frame work the modes share done once.
pub fn along_path_both<P: Borrow<CameraPose>>(
    rig: &Rig,
    poses: impl IntoIterator<Item = P, IntoIter: ExactSizeIterator>,
    probes: &[Vec<DVec3>],
    opts: ShimmerOptions,
) -> (PathResult, PathResult) {
    along_path_both_lit(rig, poses, probes, None, opts)
}

/// [`along_path_both`] under a moving light (see [`along_path_lit`]).
pub fn along_path_both_lit<P: Borrow<CameraPose>>(
    rig: &Rig,
    poses: impl IntoIterator<Item = P, IntoIter: ExactSizeIterator>,
    probes: &[Vec<DVec3>],
    light: Option<LightTrack<'_>>,
    opts: ShimmerOptions,
) -> (PathResult, PathResult) {
    let still = light.as_ref().is_none_or(|l| !l.motion.moves());
    let [s, u] = if still && without_probes(rig, opts) {
        walk_without_probes(rig, poses)
    } else {
        walk(&mut model(rig, probes, light), poses, [true, false], opts)
    };
    (s.finish(opts), u.finish(opts))
}

/// Whether [`walk_without_probes`] gives what [`walk`] gives: a fixed basis with the fast
/// coverage test, no probe needed (S3 has the closed form every frame), no per-frame rows.
fn without_probes(rig: &Rig, opts: ShimmerOptions) -> bool {
    fast_walk_applies(rig) && !needs_probes(rig, opts) && !opts.frame_rows
}

/// Both snap modes `[snapped, unsnapped]` of a still light and a fixed basis when no probe is
/// needed (see [`without_probes`]): per frame the camera frame in light space, per cascade the
/// slice corners' extremes, the two windows, their coverage margins and the closed-form drift
/// of each window against its predecessor. The same operations in the same order as
/// [`walk`] with a [`RigPath`] (so the same totals, bit for bit), without the generic walker's
/// per-mode bookkeeping for probes, held cascades and moving lights: the sweep's walk.
fn walk_without_probes<P: Borrow<CameraPose>>(rig: &Rig, poses: impl IntoIterator<Item = P>) -> [PathTotals; 2] {
    if let WindowRule::AxisCentred { centre_depth } = &rig.scheme.window {
        let n = rig.resolution as f64;
        if rig.sphere_side.iter().all(|&side| side / n > 0.0) {
            return walk_axis_centred(rig, centre_depth, poses, true);
        }
    }
    let m = rig.cascade_count();
    let n = rig.resolution as f64;
    let mut totals = [PathTotals::new(true, m), PathTotals::new(false, m)];
    let mut prev: [Vec<Option<Window>>; 2] = [vec![None; m], vec![None; m]];
    for pose in poses {
        let lp = LightPose::new(&rig.light, pose.borrow());
        for (i, s) in rig.slices.iter().enumerate() {
            let corners = lp.corners(&rig.lens, s.near, s.far);
            let bounds = bounds_2d(&corners);
            let mut texels: Option<CornerTexels> = None;
            for (k, snapped) in [true, false].into_iter().enumerate() {
                let w = rig.window_in(i, &lp, snapped);
                let tot = &mut totals[k];
                if !matches!(&texels, Some(ct) if ct.texel == w.texel) {
                    texels = Some(CornerTexels::new(&corners, bounds, w.texel));
                }
                fast_cover(tot, i, &w, texels.as_ref().expect("set above"), &corners, n);
                let before = &mut prev[k][i];
                if let Some(p) = before {
                    let (pt, wt) = (p.texel, w.texel);
                    // As in `walk`: an unchanged texel size has no size change and the closed
                    // form; a changed one (no probes to land) counts a pair of zero drift.
                    let (size_change, ms) = if wt == pt {
                        (0.0, closed_form_drift(p.origin_texels, w.origin_texels))
                    } else {
                        (((wt.x / pt.x - 1.0).abs()).max((wt.y / pt.y - 1.0).abs()), 0.0)
                    };
                    tot.closed_pair(size_change, ms);
                }
                *before = Some(w);
            }
        }
    }
    totals
}

/// Frames per pass of [`walk_axis_centred`] at most: their light-space camera frames and
/// drifts are held (a few tens of KiB), so a path of any length takes the same memory.
const AXIS_CHUNK: usize = 512;

/// [`walk_without_probes`] for windows centred on the view axis (every sphere fit): each
/// cascade's texel size is fixed, so every frame pair has the closed-form drift and no size
/// change, the two snap modes share the window centre in texels, and the slice corners'
/// extremes come from the two caps' bounds (see [`AxisWalk::frames`]): what [`Rig::window_in`],
/// [`crate::fitting::Window::centred`] and `RigPath::cover` compute, bit for bit, with
/// every per-cascade constant (texel size, the caps' image slopes times depth, the snap
/// anchor in texels) taken out of the frame loop.
///
/// The frames go in chunks (of [`AXIS_CHUNK`] at most): the light-space camera frame of each once, then
/// cascade by cascade a tight loop over the chunk's frames (its coverage margins and both
/// modes' drifts; every value by the operations of the frame-by-frame walk), then the drifts
/// added to the totals in the walk's order (frame by frame, cascade by cascade), so each sum
/// is the same sum. Minima, maxima and counts are kept per cascade in frame order, as before.
/// When a chunk's camera axes do not change (a strafe, a dolly, a still camera: every frame
/// the same bits) the axes' products with each cascade's depths and slopes are computed once
/// per chunk: the same products.
fn walk_axis_centred<P: Borrow<CameraPose>>(
    rig: &Rig,
    centre_depth: &[f64],
    poses: impl IntoIterator<Item = P>,
    arrays: bool,
) -> [PathTotals; 2] {
    let m = rig.cascade_count();
    let n = rig.resolution as f64;
    let (th, tv) = (rig.lens.tan_h, rig.lens.tan_v);
    let anchor = rig.scheme.snap_anchor;
    let walk = AxisWalk {
        rig,
        n,
        half: DVec2::splat(0.5 * n),
        anchored: anchor != DVec2::ZERO,
        anchor,
    };
    let mut cascades: Vec<AxisCascade> = (0..m)
        .map(|i| {
            let s = &rig.slices[i];
            let texel = DVec2::splat(rig.sphere_side[i]) / n;
            AxisCascade {
                i,
                texel,
                depth: centre_depth[i],
                near: s.near,
                far: s.far,
                slopes: [(th * s.near, tv * s.near), (th * s.far, tv * s.far)],
                anchor_texels: (anchor != DVec2::ZERO).then(|| anchor / texel),
                prev: None,
                prev_whole: false,
            }
        })
        .collect();
    let mut totals = [PathTotals::new(true, m), PathTotals::new(false, m)];
    let mut poses = poses.into_iter();
    // A short path takes one chunk of its own length.
    let chunk = poses.size_hint().0.clamp(16, AXIS_CHUNK);
    let mut lps: Vec<LightPose> = Vec::with_capacity(chunk);
    // Each mode's squared drifts per cascade, in frame order (none for the path's first frame).
    let mut drift: [Vec<Vec<f64>>; 2] = [0, 1].map(|_| (0..m).map(|_| Vec::with_capacity(chunk)).collect());
    let mut first = true;
    let mut scratch = Arrays::default();
    let mut chunk_poses: Vec<CameraPose> = Vec::with_capacity(chunk);
    // The array walk's snap: rounding to whole texels (`SnapRule::apply` of this rule is the
    // rounding alone: x / 1 and x · 1 are x) or none; other rules and a snap anchor walk frame
    // by frame.
    let arrays_snap = match rig.scheme.snaps.then_some(rig.snap_rule) {
        _ if !arrays || walk.anchored => None,
        Some(SnapRule {
            mode: SnapMode::Round,
            step_texels: 1,
        }) => Some(true),
        None => Some(false),
        Some(_) => None,
    };
    loop {
        chunk_poses.clear();
        chunk_poses.extend(poses.by_ref().take(chunk).map(|p| *p.borrow()));
        let f = chunk_poses.len();
        if f == 0 {
            break;
        }
        // Camera axes equal in the world, bit for bit, are equal in light space (the same
        // operations): then only the positions are read per frame (the array walk), and
        // the frame-by-frame walk's light-space frames are made only if a cascade needs them.
        let soa = arrays_snap.filter(|_| same_world_axes(&chunk_poses));
        lps.clear();
        let fixed = match soa {
            Some(_) => {
                lps.push(LightPose::new(&rig.light, &chunk_poses[0]));
                let [px, py] = &mut scratch.p;
                px.clear();
                py.clear();
                for q in &chunk_poses {
                    let p = rig.light.to_light_xy(q.position);
                    px.push(p.x);
                    py.push(p.y);
                }
                true
            }
            None => {
                lps.extend(chunk_poses.iter().map(|q| LightPose::new(&rig.light, q)));
                same_axes(&lps)
            }
        };
        let [ds, du] = &mut drift;
        for (c, (ds, du)) in cascades.iter_mut().zip(ds.iter_mut().zip(du.iter_mut())) {
            ds.clear();
            du.clear();
            let done = match soa {
                Some(true) => walk.frames_arrays(c, &lps[0], round_to_whole, &mut scratch, &mut totals, [ds, du]),
                Some(false) => walk.frames_arrays(c, &lps[0], |x| x, &mut scratch, &mut totals, [ds, du]),
                None => false,
            };
            if done {
                continue;
            }
            if lps.len() < f {
                lps.clear();
                lps.extend(chunk_poses.iter().map(|q| LightPose::new(&rig.light, q)));
            }
            let out = [ds, du];
            match rig.scheme.snaps.then_some(rig.snap_rule) {
                // `SnapRule::apply` of this rule is the rounding alone (x / 1 and x · 1 are x).
                Some(SnapRule {
                    mode: SnapMode::Round,
                    step_texels: 1,
                }) => walk.frames(c, &lps, fixed, round_half_away, &mut totals, out),
                Some(rule) => walk.frames(c, &lps, fixed, |x| rule.apply(x), &mut totals, out),
                None => walk.frames(c, &lps, fixed, |x| x, &mut totals, out),
            }
        }
        // The pairs in the frame-by-frame walk's order; the first frame of the path has none.
        for (tot, drift) in totals.iter_mut().zip(&drift) {
            tot.closed_pairs_in_order(f - usize::from(first), drift);
        }
        first = false;
    }
    totals
}

/// Whether every pose of `poses` has the first one's axes, bit for bit.
#[inline]
fn same_world_axes(poses: &[CameraPose]) -> bool {
    let bits = |p: &CameraPose| [p.forward, p.right, p.up].map(|v| v.to_array().map(f64::to_bits));
    let a = bits(&poses[0]);
    poses.iter().all(|p| bits(p) == a)
}

/// Whether every frame of `lps` has the first one's camera axes in light space, bit for bit.
fn same_axes(lps: &[LightPose]) -> bool {
    let bits = |l: &LightPose| [l.forward, l.right, l.up].map(|v| [v.x.to_bits(), v.y.to_bits()]);
    let a = bits(&lps[0]);
    lps.iter().all(|l| bits(l) == a)
}

/// What [`walk_axis_centred`]'s cascades share.
struct AxisWalk<'a> {
    rig: &'a Rig,
    n: f64,
    half: DVec2,
    anchored: bool,
    anchor: DVec2,
}

/// One cascade of [`walk_axis_centred`].
struct AxisCascade {
    i: usize,
    texel: DVec2,
    depth: f64,
    near: f64,
    far: f64,
    /// `tanH·z` and `tanV·z` at the near and the far cap.
    slopes: [(f64, f64); 2],
    /// The snap anchor in texels (added to both origins) when it is not zero.
    anchor_texels: Option<DVec2>,
    /// Each mode's window origin in the previous frame.
    prev: Option<[DVec2; 2]>,
    /// Whether the previous frame's snapped origin was a whole number below 2^51.
    prev_whole: bool,
}

/// Window centres in texels below this snap to whole numbers whose differences are exact.
const WHOLE_BELOW: f64 = (1u64 << 50) as f64;

impl AxisWalk<'_> {
    /// Cascade `c` over the frames `lps` (in order): each frame's coverage margins (and, when
    /// some corner may lie outside, the per-corner test) into `totals`, and each mode's squared
    /// drift against the frame before pushed to `drift[mode]` (none for the path's first
    /// frame). `snap` is the snap rule's `apply`; `fixed` that every frame has the first
    /// one's axes.
    #[inline(always)]
    fn frames(
        &self,
        c: &mut AxisCascade,
        lps: &[LightPose],
        fixed: bool,
        snap: impl Fn(f64) -> f64,
        totals: &mut [PathTotals; 2],
        drift: [&mut Vec<f64>; 2],
    ) {
        let (n, half, i) = (self.n, self.half, c.i);
        // The products of the axes that do not change (`fixed`): the window centre's and the
        // caps' offsets along the view axis, and the caps' half-extents.
        let hoisted = fixed.then(|| c.products(&lps[0]));
        let [ds, du] = drift;
        // Whether a snapped origin is a whole number whenever the centre in texels is below
        // `WHOLE_BELOW`: snapping gives whole multiples of the rule's step, and half an even
        // resolution is whole (a snap anchor is not).
        let whole_snaps = self.rig.scheme.snaps && self.rig.resolution % 2 == 0 && c.anchor_texels.is_none();
        for lp in lps {
            let [fc, fnear, ffar, rn, un, rf, uf] = hoisted.unwrap_or_else(|| c.products(lp));
            // The window centre in texels (`Rig::centred`, `Window::centred`), shared by the
            // modes; snapped, it is rounded on the rule's grid.
            let centre = lp.position + fc;
            let centred = if self.anchored { centre - self.anchor } else { centre };
            let ct = centred / c.texel;
            let snapped = DVec2::new(snap(ct.x), snap(ct.y));
            let mut origins = [snapped - half, ct - half];
            if let Some(a) = c.anchor_texels {
                origins = origins.map(|o| o + a);
            }
            // The slice corners' extremes, in texels: the lower and upper bounds of each cap's
            // 4 corners, bit for bit those of `LightPose::point` at `(±tanH, ±tanV, z)` (a
            // corner is `((p + F·z) + R·(sx·z)) + U·(sy·z)` per axis, `sx·z` is `±(tanH·z)`
            // exactly, and rounded addition is monotone in each operand, so the smallest corner
            // adds the two negative terms and the largest the two positive ones; `x + (−y)` is
            // `x − y` exactly), then divided as `CornerTexels::new` divides them.
            let (axis_n, axis_f) = (lp.position + fnear, lp.position + ffar);
            let (lo_n, hi_n) = (axis_n - rn - un, axis_n + rn + un);
            let (lo_f, hi_f) = (axis_f - rf - uf, axis_f + rf + uf);
            let (lo, hi) = (lo_n.min(lo_f) / c.texel, hi_n.max(hi_f) / c.texel);
            for (k, o) in origins.iter().enumerate() {
                let tot = &mut totals[k];
                let slack = (lo.x - o.x).min(n - (hi.x - o.x)).min(lo.y - o.y).min(n - (hi.y - o.y));
                tot.slack(i, slack);
                if -slack > 1e-9 {
                    let w = Window {
                        texel: c.texel,
                        origin_texels: *o,
                        resolution: self.rig.resolution,
                    };
                    for corner in lp.corners(&self.rig.lens, c.near, c.far) {
                        tot.corner(i, w.texel_coords(corner), n, (corner / c.texel).abs().max_element());
                    }
                }
            }
            // Snapped origins that are whole numbers below 2^51 (rounded centres below 2^50
            // minus an even resolution's half) differ by a whole number exactly, which wraps
            // to +0.0: `closed_form_drift` of two such origins is +0.0.
            let whole = whole_snaps && ct.x.abs() < WHOLE_BELOW && ct.y.abs() < WHOLE_BELOW;
            if let Some(p) = &c.prev {
                ds.push(if whole && c.prev_whole {
                    0.0
                } else {
                    closed_form_drift(p[0], origins[0])
                });
                du.push(closed_form_drift(p[1], origins[1]));
            }
            c.prev = Some(origins);
            c.prev_whole = whole;
        }
    }
}

/// `round_half_away` for `|x| < 2^52` (and no NaN), without its guard: the same operations,
/// so the same bits there, and a loop over frames of it vectorises. Callers check the range.
#[inline(always)]
fn round_to_whole(x: f64) -> f64 {
    const TWO_52: f64 = 4_503_599_627_370_496.0;
    let a = x.abs();
    let r = (a + TWO_52) - TWO_52;
    let fl = if r > a { r - 1.0 } else { r };
    let up = if a - fl >= 0.5 { 1.0 } else { 0.0 };
    (fl + up).copysign(x)
}

/// The scratch arrays of [`AxisWalk::frames_arrays`] (one chunk's frames, one array per axis
/// and quantity), reused across cascades and chunks.
#[derive(Default)]
struct Arrays {
    /// The chunk's light-space camera positions, x and y.
    p: [Vec<f64>; 2],
    /// Each mode's window origin (snapped, unsnapped) per axis; index 0 is the frame before
    /// the chunk's first, index `t + 1` frame `t`.
    os: [Vec<f64>; 2],
    ou: [Vec<f64>; 2],
    /// Each mode's smaller coverage margin on each axis.
    ms: [Vec<f64>; 2],
    mu: [Vec<f64>; 2],
    /// `|centre in texels|` per axis.
    act: [Vec<f64>; 2],
}

impl AxisCascade {
    /// The products of the camera axes with this cascade's depths and slopes: the window
    /// centre's and the caps' offsets along the view axis, and the caps' half-extents.
    #[inline(always)]
    fn products(&self, lp: &LightPose) -> [DVec2; 7] {
        let (sn, sf) = (self.slopes[0], self.slopes[1]);
        [
            lp.forward * self.depth,
            lp.forward * self.near,
            lp.forward * self.far,
            (lp.right * sn.0).abs(),
            (lp.up * sn.1).abs(),
            (lp.right * sf.0).abs(),
            (lp.up * sf.1).abs(),
        ]
    }
}

impl AxisWalk<'_> {
    /// [`AxisWalk::frames`] of a chunk whose frames all have the camera axes of `lp0` (a strafe,
    /// a dolly, a still camera), without a snap anchor, `snap` rounding to whole texels or
    /// nothing: the same operations on each frame's values, per axis over arrays of the
    /// chunk's frames (`arrays.p`: its positions) so the loops run several frames per
    /// instruction. Returns false, having changed nothing, when the chunk needs the
    /// frame-by-frame walk: a centre in texels of 2^50 or more (or NaN), a previous origin
    /// of 2^51 or more, a frame whose window may miss a corner (the per-corner test), or a
    /// smallest margin of zero (whose sign the order of the minima decides).
    ///
    /// Why the same bits: every per-frame value is computed by the operations of `frames` in
    /// the same order; the rounding without its guard is `round_half_away` in the range
    /// checked; the minimum over frames of a margin is the same value in any order unless it
    /// is zero (±0 differ only in sign; NaN is skipped by `f64::min` in any order); with
    /// every centre below 2^50 every snapped origin is whole, as `frames` tests per frame.
    #[inline(always)]
    fn frames_arrays(
        &self,
        c: &mut AxisCascade,
        lp0: &LightPose,
        snap: impl Fn(f64) -> f64,
        arrays: &mut Arrays,
        totals: &mut [PathTotals; 2],
        drift: [&mut Vec<f64>; 2],
    ) -> bool {
        const PREV_BELOW: f64 = (1u64 << 51) as f64;
        let f = arrays.p[0].len();
        let n = self.n;
        let [fc, fnear, ffar, rn, un, rf, uf] = c.products(lp0);
        let prev = c.prev;
        if prev.is_some_and(|p| !p.iter().all(|o| o.x.abs() < PREV_BELOW && o.y.abs() < PREV_BELOW)) {
            return false;
        }
        let mut in_range = true;
        let Arrays { p, os, ou, ms, mu, act } = arrays;
        for a in 0..2 {
            let pick = |v: DVec2| if a == 0 { v.x } else { v.y };
            let (fc, fnear, ffar) = (pick(fc), pick(fnear), pick(ffar));
            let (rn, un, rf, uf) = (pick(rn), pick(un), pick(rf), pick(uf));
            let (texel, half) = (pick(c.texel), pick(self.half));
            let (p, os, ou, ms, mu, act) = (&p[a][..f], &mut os[a], &mut ou[a], &mut ms[a], &mut mu[a], &mut act[a]);
            for v in [&mut *os, &mut *ou] {
                v.clear();
                v.resize(f + 1, 0.0);
            }
            for v in [&mut *ms, &mut *mu, &mut *act] {
                v.clear();
                v.resize(f, 0.0);
            }
            let (os1, ou1) = (&mut os[1..=f], &mut ou[1..=f]);
            let (ms, mu, act) = (&mut ms[..f], &mut mu[..f], &mut act[..f]);
            for (t, &pt) in p.iter().enumerate() {
                let ct = (pt + fc) / texel;
                let (o_s, o_u) = (snap(ct) - half, ct - half);
                let (axis_n, axis_f) = (pt + fnear, pt + ffar);
                let (lo_n, hi_n) = ((axis_n - rn) - un, (axis_n + rn) + un);
                let (lo_f, hi_f) = ((axis_f - rf) - uf, (axis_f + rf) + uf);
                // `DVec2::min` and `DVec2::max`, per axis.
                let lo = (if lo_n < lo_f { lo_n } else { lo_f }) / texel;
                let hi = (if hi_n > hi_f { hi_n } else { hi_f }) / texel;
                ms[t] = (lo - o_s).min(n - (hi - o_s));
                mu[t] = (lo - o_u).min(n - (hi - o_u));
                os1[t] = o_s;
                ou1[t] = o_u;
                act[t] = ct.abs();
            }
            in_range &= act.iter().fold(true, |ok, &x| ok & (x < WHOLE_BELOW));
            let (ps, pu) = match prev {
                Some(q) => (pick(q[0]), pick(q[1])),
                None => (os[1], ou[1]),
            };
            os[0] = ps;
            ou[0] = pu;
        }
        if !in_range {
            return false;
        }
        // The smallest margin of each mode over the chunk: per frame the smaller of the two
        // axes' (the walk's four-way minimum, up to the sign of a zero), then over frames.
        let least = |m: &[Vec<f64>; 2]| {
            let (x, y) = (&m[0][..f], &m[1][..f]);
            let mut acc = [f64::INFINITY; 4];
            let mut t = 0;
            while t + 4 <= f {
                for (l, a) in acc.iter_mut().enumerate() {
                    *a = a.min(x[t + l].min(y[t + l]));
                }
                t += 4;
            }
            while t < f {
                acc[0] = acc[0].min(x[t].min(y[t]));
                t += 1;
            }
            acc[0].min(acc[1]).min(acc[2].min(acc[3]))
        };
        let least = [least(ms), least(mu)];
        if least.iter().any(|&s| s == 0.0 || -s > 1e-9) {
            return false;
        }
        // Drifts: as `frames` computes them, `closed_form_drift(previous, this)`.
        let whole_snaps = self.rig.scheme.snaps && self.rig.resolution % 2 == 0 && c.anchor_texels.is_none();
        let start = usize::from(prev.is_none());
        let [ds, du] = drift;
        let drifts = |o: &[Vec<f64>; 2], out: &mut Vec<f64>| {
            let (x, y) = (&o[0][..=f], &o[1][..=f]);
            out.clear();
            out.resize(f - start, 0.0);
            for (k, d) in out.iter_mut().enumerate() {
                let t = k + start;
                let dx = x[t] - x[t + 1];
                let dy = y[t] - y[t + 1];
                let (wx, wy) = (dx - round_to_whole(dx), dy - round_to_whole(dy));
                *d = wx * wx + wy * wy;
            }
        };
        drifts(ou, du);
        if whole_snaps {
            // Every snapped origin of the chunk is whole (centres below 2^50): each pair's
            // drift is +0.0, and the pair into the chunk's first frame too when the
            // previous frame's origin was whole.
            ds.clear();
            ds.resize(f - start, 0.0);
            if start == 0 && !c.prev_whole {
                ds[0] = closed_form_drift(DVec2::new(os[0][0], os[1][0]), DVec2::new(os[0][1], os[1][1]));
            }
        } else {
            drifts(os, ds);
        }
        for (tot, s) in totals.iter_mut().zip(least) {
            tot.slack(c.i, s);
        }
        c.prev = Some([DVec2::new(os[0][f], os[1][f]), DVec2::new(ou[0][f], ou[1][f])]);
        c.prev_whole = whole_snaps;
        true
    }
}

/// The fast coverage test of cascade `i`'s window `w` (`n` texels a side) over its slice
/// corners (`ct`: their texel extremes). The smallest margin over the corners comes from the
/// extreme corners alone: `x - o` and `n - x` are monotone in x under round-to-nearest, so the
/// extreme of the rounded margins is the rounded margin of the extreme, bit-identical to a
/// per-corner minimum. Every corner's tolerance is at least 1e-9, so unless the worst margin
/// is below -1e-9 no corner can count as outside and the per-corner pass is skipped.
#[inline]
fn fast_cover(totals: &mut PathTotals, i: usize, w: &Window, ct: &CornerTexels, corners: &[DVec2; 8], n: f64) {
    let o = w.origin_texels;
    let slack = (ct.lo.x - o.x)
        .min(n - (ct.hi.x - o.x))
        .min(ct.lo.y - o.y)
        .min(n - (ct.hi.y - o.y));
    totals.slack(i, slack);
    if -slack > 1e-9 {
        for c in corners {
            totals.corner(i, w.texel_coords(*c), n, (*c / w.texel).abs().max_element());
        }
    }
}

/// The extremes of one cascade's slice corners in texel units (`corner / T`, before the
/// window origin is subtracted) for one frame. Both snap modes use the same window size, so
/// this is computed once for both.
struct CornerTexels {
    texel: DVec2,
    lo: DVec2,
    hi: DVec2,
}

impl CornerTexels {
    /// From the corners and their light-space bounds `(lo, hi)`.
    fn new(corners: &[DVec2; 8], bounds: (DVec2, DVec2), texel: DVec2) -> Self {
        let (lo, hi) = if texel.cmpgt(DVec2::ZERO).all() {
            // Dividing by a positive number is monotone under round-to-nearest, so the bounds
            // divided are exactly the bounds of the divided corners (the values a per-corner
            // `texel_coords` call computes), for 2 divisions instead of 8.
            (bounds.0 / texel, bounds.1 / texel)
        } else {
            bounds_2d(&corners.map(|c| c / texel))
        };
        CornerTexels { texel, lo, hi }
    }
}

/// `f64::floor`, bit for bit, for `|x| < 2^51`, without branches: adding and subtracting
/// 1.5 · 2^52 rounds `x` to a whole number (the sum's last place is 1), one less when that
/// rounded up; the result carries the sign of `x` (floor(−0.0) is −0.0).
#[inline(always)]
fn floor_small(x: f64) -> f64 {
    const C: f64 = 6_755_399_441_055_744.0;
    let r = (x + C) - C;
    let r = if r > x { r - 1.0 } else { r };
    r.copysign(x)
}

/// `f64::floor` up to the sign of a zero (`floor(−0.0)` is +0.0 here), for `|x| < 2^51`:
/// [`floor_small`] without its `copysign`, so every value compares equal (`==`) to
/// `f64::floor`'s. For a loop that only compares texels.
#[inline(always)]
fn floor_unsigned(x: f64) -> f64 {
    const C: f64 = 6_755_399_441_055_744.0;
    let r = (x + C) - C;
    r - if r > x { 1.0 } else { 0.0 }
}

/// The flip count of [`PathModel::floor_flips`] over the probes' coordinates per axis (`xs`,
/// `ys`) and the kept texels `kx`, `ky` of the previous window: a probe flips when some
/// axis' new texel `⌊x − o⌋` is not the kept one plus `stay`; the new texels replace the
/// kept ones. The same comparisons, probe for probe, as a pass over `DVec2`s; one array per
/// axis and no branch, so the loop runs two probes per SSE2 instruction.
#[inline(always)]
fn flips_soa(xs: &[f64], ys: &[f64], kx: &mut [f64], ky: &mut [f64], o: DVec2, stay: DVec2) -> usize {
    let n = xs.len().min(ys.len()).min(kx.len()).min(ky.len());
    let (xs, ys, kx, ky) = (&xs[..n], &ys[..n], &mut kx[..n], &mut ky[..n]);
    let mut flipped = 0u64;
    for j in 0..n {
        let a = floor_unsigned(xs[j] - o.x);
        let b = floor_unsigned(ys[j] - o.y);
        flipped += u64::from((a != kx[j] + stay.x) | (b != ky[j] + stay.y));
        kx[j] = a;
        ky[j] = b;
    }
    flipped as usize
}

/// Probes per cascade up to which [`FractionRanks`] is kept ((n + 1)² counts).
const RANKED_PROBES: usize = 1024;

/// Pairs of a cascade [`PathModel::floor_flips`] counts over the probes before it builds the
/// cascade's [`FractionRanks`] (`RANK_AFTER_PAIRS` passes cost about what building them does).
const RANK_AFTER_PAIRS: usize = 1000;

/// Distance (in texels, cyclic) between a probe's fractional coordinate and a window origin's
/// under which the probe's texel is computed, not counted: above it `⌊x − o⌋` computed equals
/// the exact one (`|x − o| < 2^24`, so the subtraction rounds by at most 2^-29).
const NEAR_EDGE: f64 = 1e-8;

/// The probes' fractional texel coordinates `φ = x − ⌊x⌋` per axis, sorted, and the count of
/// probes below each pair of ranks: how many probes' texels change between two windows,
/// counted from the windows' origins without a pass over the probes.
///
/// With `x = U + φ` and an origin `o = O + ψ` (whole and fractional parts, both exact), the
/// exact texel is `⌊x − o⌋ = U − O − [φ < ψ]`. So between origins `a` and `b` a probe's `Δk`
/// on an axis is `O_a − O_b + [φ < ψ_a] − [φ < ψ_b]`, and it keeps its texel (`Δk = stay`)
/// exactly when `φ` lies in a set of at most two intervals of `[0, 1)` that depends on the
/// origins only. The probes that keep their texel on both axes are counted by a rectangle
/// query on ranks (`count[a][b]`: probes whose x rank is below `a` and y rank below `b`).
/// The computed `⌊fl(x − o)⌋` equals the exact one unless `φ` is within [`NEAR_EDGE`] of `ψ`
/// (cyclically): then [`FractionRanks::flips`] gives None and the caller computes the texels.
struct FractionRanks {
    fx: Vec<f64>,
    fy: Vec<f64>,
    /// `(n + 1)²` counts, row `a` (x rank), column `b` (y rank).
    count: Vec<u16>,
}

impl FractionRanks {
    fn new(xs: &[f64], ys: &[f64]) -> Option<Self> {
        let n = xs.len();
        if n > RANKED_PROBES || ys.len() != n {
            return None;
        }
        let frac = |v: f64| v - v.floor();
        let order = |vs: &[f64]| {
            let mut idx: Vec<usize> = (0..n).collect();
            idx.sort_by(|&a, &b| frac(vs[a]).total_cmp(&frac(vs[b])));
            idx
        };
        let (ox, oy) = (order(xs), order(ys));
        let mut rank_y = vec![0usize; n];
        for (r, &j) in oy.iter().enumerate() {
            rank_y[j] = r;
        }
        let w = n + 1;
        let mut count = vec![0u16; w * w];
        for (r, &j) in ox.iter().enumerate() {
            count[(r + 1) * w + rank_y[j] + 1] = 1;
        }
        for a in 1..w {
            for b in 1..w {
                count[a * w + b] =
                    count[a * w + b] + count[(a - 1) * w + b] + count[a * w + b - 1] - count[(a - 1) * w + b - 1];
            }
        }
        let fx: Vec<f64> = ox.iter().map(|&j| frac(xs[j])).collect();
        let fy: Vec<f64> = oy.iter().map(|&j| frac(ys[j])).collect();
        if fx.iter().chain(&fy).any(|f| !(0.0..1.0).contains(f)) {
            return None;
        }
        Some(FractionRanks { fx, fy, count })
    }

    /// The probes (of `n`) whose texel changes on some axis other than by `stay` between the
    /// origins `a` and `b` (what [`flips_soa`] counts), or None when a probe lies within
    /// [`NEAR_EDGE`] of either origin's fractional part on some axis.
    fn flips(&self, a: DVec2, b: DVec2, stay: DVec2) -> Option<usize> {
        let n = self.fx.len();
        let x = Self::keep(&self.fx, a.x, b.x, stay.x)?;
        let y = Self::keep(&self.fy, a.y, b.y, stay.y)?;
        let w = n + 1;
        let below = |ra: usize, rb: usize| usize::from(self.count[ra * w + rb]);
        let mut kept = 0;
        for &(x0, x1) in x.iter().flatten() {
            for &(y0, y1) in y.iter().flatten() {
                kept += below(x1, y1) + below(x0, y0) - below(x0, y1) - below(x1, y0);
            }
        }
        Some(n - kept)
    }

    /// On one axis (`f`: the sorted fractions), the rank ranges `[r0, r1)` of the probes that
    /// keep their texel (`Δk = stay`) from origin `a` to `b`; None when a probe is near either
    /// origin's fractional part.
    fn keep(f: &[f64], a: f64, b: f64, stay: f64) -> Option<[Option<(usize, usize)>; 2]> {
        let rank = |v: f64| f.partition_point(|&p| p < v);
        let (whole_a, whole_b) = (a.floor(), b.floor());
        let (pa, pb) = (a - whole_a, b - whole_b);
        for psi in [pa, pb] {
            // Probes with φ in [ψ − NEAR_EDGE, ψ + NEAR_EDGE], cyclically.
            let (lo, hi) = (psi - NEAR_EDGE, psi + NEAR_EDGE);
            let near = f.partition_point(|&p| p <= hi) - rank(lo)
                + if lo < 0.0 { f.len() - rank(lo + 1.0) } else { 0 }
                + if hi >= 1.0 {
                    f.partition_point(|&p| p <= hi - 1.0)
                } else {
                    0
                };
            if near > 0 {
                return None;
            }
        }
        // Keeps when [φ < ψa] − [φ < ψb] = −d, d = Oa − Ob − stay.
        let d = whole_a - whole_b - stay;
        let n = f.len();
        Some(if d == 0.0 {
            // Outside [min ψ, max ψ).
            let (lo, hi) = (rank(pa.min(pb)), rank(pa.max(pb)));
            [Some((0, lo)), Some((hi, n))]
        } else if d == 1.0 && pa < pb {
            [Some((rank(pa), rank(pb))), None]
        } else if d == -1.0 && pb < pa {
            [Some((rank(pb), rank(pa))), None]
        } else {
            [None, None]
        })
    }
}

/// For probes at texel coordinates `scaled` (x/y divided by the texel size, before the window
/// origin is subtracted): `(u, limit)` with `u` the largest coordinate magnitude and `limit` a
/// power of two such that for every whole number `o` with `|o| + u < limit`, each coordinate
/// `x` lands on the texel `o + floor(x − o) = floor(x)`, so its sampled centre does not depend
/// on `o`. The subtraction `x − o` is exact but for rounding below 2^(k−53) (|x − o| < 2^k);
/// it can change the floor only by rounding up to the next whole number, which needs
/// `1 − frac(x)` within that rounding. `limit = 2^k` with `2^(k−53) ≤ min(1 − frac(x)) / 2`.
/// `(∞, 0)` (never) for coordinates that are not finite or not below 2^50.
fn exact_limit(scaled: &[DVec2]) -> (f64, f64) {
    let mut u = 0.0f64;
    let mut gap = 1.0f64;
    for c in scaled.iter().flat_map(|q| [q.x, q.y]) {
        // (NaN fails the comparison too.)
        if c.abs() >= (1u64 << 50) as f64 || c.is_nan() {
            return (f64::INFINITY, 0.0);
        }
        u = u.max(c.abs());
        let f = c - c.floor();
        if f > 0.0 {
            gap = gap.min(1.0 - f);
        }
    }
    // 2^(k−53) ≤ gap/2: k = floor(log2(gap)) + 52, at most 51 (whole numbers below 2^51).
    let k = (gap.log2().floor() + 52.0).min(51.0);
    if k.is_nan() || k <= 0.0 {
        return (u, 0.0);
    }
    (u, 2f64.powi(k as i32))
}

/// The exact f64 [`Rig`] as a [`PathModel`]. With a fixed light basis a static probe has the
/// same light-space x/y in every frame and same-size windows have the closed-form drift; with
/// a basis that follows the camera each frame reads the probes through its own basis.
pub struct RigPath<'a> {
    rig: &'a Rig,
    probes: &'a [Vec<DVec3>],
    /// Fixed basis: each probe's light-space x/y, computed once.
    probe_xy: Vec<Vec<DVec2>>,
    /// Fixed basis: per cascade, a texel size and each probe's x/y divided by it, from the
    /// first landing. A window of that texel size (a sphere fit's, every frame) lands the
    /// probes with one subtraction each, bit for bit as [`Window::texel_coords`].
    probe_texels: Vec<std::cell::OnceCell<(DVec2, Vec<DVec2>)>>,
    /// Fixed basis: per cascade, for the texel size of `probe_texels`, `(u, limit)`: the
    /// largest |probe x/y divided by it| and a power of two such that for every whole-texel
    /// origin `o` with `|o| + u < limit` a probe lands on the texel `floor(x/y / texel)`
    /// whatever `o` (0: never known).
    probe_exact: Vec<std::cell::OnceCell<(f64, f64)>>,
    /// Fixed basis: per cascade, the x and the y of `probe_texels`' coordinates, one array
    /// each (what [`PathModel::floor_flips`] reads).
    probe_axes: Vec<std::cell::OnceCell<[Vec<f64>; 2]>>,
    /// Fixed basis: per cascade, the probes' fractional texel coordinates sorted and counted
    /// (None for too many probes).
    probe_ranks: Vec<std::cell::OnceCell<Option<FractionRanks>>>,
    /// Per cascade, the pairs [`PathModel::floor_flips`] has counted so far.
    probe_pairs: Vec<std::cell::Cell<usize>>,
    fixed: bool,
    /// Fixed basis and selection inside the fitted slices: coverage from the slice corners'
    /// extremes, shared by the snap modes.
    fast: bool,
    /// The camera frame in the rig's light basis, this frame.
    lp: Option<LightPose>,
    /// A basis that follows the camera: each cascade's basis and camera frame in it, this
    /// frame, and each cascade's basis in the previous frame. Kept here rather than in every
    /// window so that the fixed-basis walk copies no basis per frame.
    frame: Vec<(LightBasis, LightPose)>,
    prev_basis: Vec<Option<LightBasis>>,
    /// A moving light: the light of each frame, this frame's light basis and whether it
    /// differs from the previous frame's (an update).
    light: Option<LightTrack<'a>>,
    frame_light: Option<LightBasis>,
    updated: bool,
}

/// One cascade's window of a [`RigPath`]: the window in its cascade's basis, which cascade it
/// belongs to, and whether that basis is the one of the previous frame.
#[derive(Debug, Clone, Copy)]
pub struct RigWindow {
    pub window: Window,
    cascade: usize,
    same_basis: bool,
}

/// Per frame and cascade (fast coverage): the slice corners in the light basis, their bounds
/// and their texel-unit extremes.
pub struct RigShared {
    corners: [DVec2; 8],
    bounds: (DVec2, DVec2),
    texels: Option<CornerTexels>,
}

impl<'a> RigPath<'a> {
    pub fn new(rig: &'a Rig, probes: &'a [Vec<DVec3>]) -> Self {
        RigPath {
            rig,
            probes,
            probe_xy: rig.fixed_probe_xy(probes),
            probe_texels: (0..rig.cascade_count()).map(|_| std::cell::OnceCell::new()).collect(),
            probe_exact: (0..rig.cascade_count()).map(|_| std::cell::OnceCell::new()).collect(),
            probe_axes: (0..rig.cascade_count()).map(|_| std::cell::OnceCell::new()).collect(),
            probe_ranks: (0..rig.cascade_count()).map(|_| std::cell::OnceCell::new()).collect(),
            probe_pairs: (0..rig.cascade_count()).map(|_| std::cell::Cell::new(0)).collect(),
            fixed: rig.fixed_basis(),
            fast: fast_walk_applies(rig),
            lp: None,
            frame: Vec::new(),
            prev_basis: vec![None; rig.cascade_count()],
            light: None,
            frame_light: None,
            updated: false,
        }
    }

    /// The model under a moving light: every frame reads the light basis of `light` (a still
    /// light changes nothing).
    pub fn with_light(mut self, light: LightTrack<'a>) -> Self {
        if light.motion.moves() {
            self.light = Some(light);
            self.fixed = false;
            self.fast = false;
            self.probe_xy = Vec::new();
        }
        self
    }

    /// Cascade `i`'s camera frame in its own basis, this frame.
    fn lp_of(&self, i: usize) -> &LightPose {
        if self.fixed {
            self.lp.as_ref().expect("begin_frame first")
        } else {
            &self.frame[i].1
        }
    }

    /// Cascade `i`'s basis this frame.
    fn basis_of(&self, i: usize) -> &LightBasis {
        if self.fixed {
            &self.rig.light
        } else {
            &self.frame[i].0
        }
    }
}

impl PathModel for RigPath<'_> {
    type Shared = RigShared;
    type Win = RigWindow;
    const SKIP_UNSERVED: bool = false;

    fn cascade_count(&self) -> usize {
        self.rig.cascade_count()
    }

    fn probes_needed(&self, opts: ShimmerOptions) -> bool {
        self.light.is_some() || needs_probes(self.rig, opts)
    }

    #[inline]
    fn begin_frame(&mut self, t: usize, pose: &CameraPose) {
        let light = match &self.light {
            None => self.rig.light,
            Some(track) => {
                let b = track.basis_at(t);
                self.updated = self.frame_light.is_some_and(|p| p != b);
                self.frame_light = Some(b);
                b
            }
        };
        let lp = LightPose::new(&light, pose);
        self.lp = Some(lp);
        if !self.fixed {
            for (prev, (b, _)) in self.prev_basis.iter_mut().zip(&self.frame) {
                *prev = Some(*b);
            }
            // Reuse the buffer: this runs every frame.
            let rig = self.rig;
            self.frame.clear();
            self.frame
                .extend((0..rig.cascade_count()).map(|i| rig.cascade_pose_with(i, &lp, &light)));
        }
    }

    fn light_moves(&self) -> bool {
        self.light.is_some()
    }

    fn light_updated(&self) -> bool {
        self.updated
    }

    #[inline]
    fn shared(&self, i: usize) -> RigShared {
        let rig = self.rig;
        let (corners, bounds) = if self.fast {
            let s = &rig.slices[i];
            let corners = self.lp_of(i).corners(&rig.lens, s.near, s.far);
            (corners, bounds_2d(&corners))
        } else {
            ([DVec2::ZERO; 8], (DVec2::ZERO, DVec2::ZERO))
        };
        RigShared {
            corners,
            bounds,
            texels: None,
        }
    }

    #[inline]
    fn window(&self, i: usize, _shared: &mut RigShared, snapped: bool) -> RigWindow {
        RigWindow {
            window: self.rig.window_in(i, self.lp_of(i), snapped),
            cascade: i,
            same_basis: self.fixed || self.prev_basis[i].as_ref() == Some(&self.frame[i].0),
        }
    }

    #[inline]
    fn texel(w: &RigWindow) -> DVec2 {
        w.window.texel
    }

    #[inline]
    fn cover(&self, i: usize, shared: &mut RigShared, w: &RigWindow, totals: &mut PathTotals) {
        let w = &w.window;
        if !self.fast {
            totals.add_coverage(i, self.rig.coverage_in(i, self.lp_of(i), w));
            return;
        }
        if matches!(&shared.texels, Some(ct) if ct.texel != w.texel) {
            shared.texels = None;
        }
        let (corners, bounds) = (&shared.corners, shared.bounds);
        let ct = shared
            .texels
            .get_or_insert_with(|| CornerTexels::new(corners, bounds, w.texel));
        fast_cover(totals, i, w, ct, &shared.corners, self.rig.resolution as f64);
    }

    #[inline]
    fn closed_form(&self, p: &RigWindow, w: &RigWindow) -> Option<f64> {
        // `p` is the same cascade's window one frame earlier (the walker's previous window).
        (w.window.texel == p.window.texel && w.same_basis)
            .then(|| closed_form_drift(p.window.origin_texels, w.window.origin_texels))
    }

    fn land(
        &self,
        i: usize,
        _shared: &RigShared,
        w: &RigWindow,
        out: &mut Vec<Option<Landing>>,
        _totals: &mut PathTotals,
    ) {
        let win = &w.window;
        let centre = |s: DVec2| (win.origin_texels + DVec2::new(floor_exact(s.x), floor_exact(s.y)) + 0.5) * win.texel;
        if self.fixed {
            // A cascade without probes measures 0 wherever probes are needed.
            let xy = self.probe_xy.get(i).map_or(&[][..], |v| &v[..]);
            let (texel, scaled) =
                self.probe_texels[i].get_or_init(|| (win.texel, xy.iter().map(|q| *q / win.texel).collect()));
            if *texel == win.texel {
                out.extend(scaled.iter().map(|u| {
                    let s = *u - win.origin_texels;
                    Some(Landing {
                        s,
                        centre: centre(s),
                        world: DVec3::ZERO,
                    })
                }));
                return;
            }
            out.extend(xy.iter().map(|q| {
                let s = win.texel_coords(*q);
                Some(Landing {
                    s,
                    centre: centre(s),
                    world: DVec3::ZERO,
                })
            }));
        } else {
            let b = self.basis_of(i);
            let ps = self.probes.get(i).map_or(&[][..], |v| &v[..]);
            out.extend(ps.iter().map(|q| {
                let s = win.texel_coords(b.to_light_xy(*q));
                let c = centre(s);
                // The sampled texel's centre line along the light, at the probe's depth.
                let world = b.x * c.x + b.y * c.y + b.z * b.z.dot(*q);
                Some(Landing { s, centre: c, world })
            }));
        }
    }

    /// A fixed basis with a still light: a landing is a function of the cascade and the
    /// window, every probe is served and a landing's centre is where it stays.
    fn lands_centres(&self) -> bool {
        self.fixed && self.light.is_none()
    }

    /// The `centre` of each landing of [`PathModel::land`], by the same operations.
    fn land_centres(&self, i: usize, w: &RigWindow, out: &mut Vec<DVec2>) {
        let win = &w.window;
        let xy = self.probe_xy.get(i).map_or(&[][..], |v| &v[..]);
        let (texel, scaled) =
            self.probe_texels[i].get_or_init(|| (win.texel, xy.iter().map(|q| *q / win.texel).collect()));
        let (o, t) = (win.origin_texels, win.texel);
        let (u_max, _) = *self.probe_exact[i].get_or_init(|| exact_limit(scaled));
        if *texel == t && u_max + o.x.abs().max(o.y.abs()) < (1u64 << 51) as f64 {
            // Every |x − o| is below 2^51: the branch-free floor applies.
            out.extend(scaled.iter().map(|u| {
                let s = *u - o;
                (o + DVec2::new(floor_small(s.x), floor_small(s.y)) + 0.5) * t
            }));
        } else if *texel == t {
            out.extend(scaled.iter().map(|u| {
                let s = *u - o;
                (o + DVec2::new(floor_exact(s.x), floor_exact(s.y)) + 0.5) * t
            }));
        } else {
            out.extend(xy.iter().map(|q| {
                let s = win.texel_coords(*q);
                (o + DVec2::new(floor_exact(s.x), floor_exact(s.y)) + 0.5) * t
            }));
        }
    }

    /// S4 from the sampled texels `k = ⌊x − o⌋` (per axis, `x` a probe's coordinate in texels,
    /// `o` the window origin) instead of their centres `(o + k + ½)·T`: a centre moves by
    /// `(Δo + Δk)·T`, so the kernel's test `|Δcentre| / T ≥ ½` is `|Δo + Δk| ≥ ½` up to the
    /// rounding of the centres, below 1e-7 texel while every `|x| + |o| < 2^24`. When `Δo` is
    /// more than 1e-6 from a half-integer on both axes, exactly one whole `Δk` per axis keeps
    /// `|Δo + Δk|` below ½ (`−round(Δo)`), every other one is more than 1e-6 above it, and the
    /// kernel decides every probe on its sure path (more than 1e-9 from ½): a probe flips
    /// exactly when some axis' `Δk` is not that one. The same `k` as `land_centres` (one
    /// subtraction and the branch-free floor), kept in place of the centres; no centre, no
    /// product. Otherwise (a texel size that is not the probes', coordinates too large, a move
    /// near half a texel) None.
    fn floor_flips(
        &self,
        i: usize,
        p: &RigWindow,
        w: &RigWindow,
        held: bool,
        floors: &mut Vec<f64>,
    ) -> Option<(usize, usize)> {
        const LIMIT: f64 = (1u64 << 24) as f64;
        const MARGIN: f64 = 1e-6;
        let (a, b) = (&p.window, &w.window);
        let (texel, scaled) = self.probe_texels.get(i)?.get()?;
        if !self.fixed || *texel != a.texel || *texel != b.texel || crate::walk::flip_divisor(b.texel).is_none() {
            return None;
        }
        let (u_max, _) = *self.probe_exact[i].get_or_init(|| exact_limit(scaled));
        let small = |o: DVec2| u_max + o.x.abs().max(o.y.abs()) < LIMIT && o.is_finite();
        let (oa, ob) = (a.origin_texels, b.origin_texels);
        if !(small(oa) && small(ob)) {
            return None;
        }
        let d = ob - oa;
        let stay = DVec2::new(-round_half_away(d.x), -round_half_away(d.y));
        let r = d + stay;
        if !(r.x.abs() < 0.5 - MARGIN && r.y.abs() < 0.5 - MARGIN) {
            return None;
        }
        // The probes' coordinates one array per axis, and the kept texels `[kx…, ky…]`: the
        // loops below run two probes per instruction.
        let [xs, ys] = self.probe_axes[i].get_or_init(|| {
            [
                scaled.iter().map(|u| u.x).collect(),
                scaled.iter().map(|u| u.y).collect(),
            ]
        });
        let n = xs.len();
        // The counts cost about (n + 1)² once: kept for a cascade that has served many pairs
        // (a long path), not for every short walk of a sweep.
        let pairs = &self.probe_pairs[i];
        pairs.set(pairs.get().saturating_add(1));
        let ranks = if pairs.get() > RANK_AFTER_PAIRS {
            self.probe_ranks[i].get_or_init(|| FractionRanks::new(xs, ys)).as_ref()
        } else {
            None
        };
        if let Some(flipped) = ranks.and_then(|r| r.flips(oa, ob, stay)) {
            // No texel kept: the next pair computes the previous window's if it needs them.
            floors.clear();
            return Some((flipped, n));
        }
        if !held || floors.len() != 2 * n {
            floors.clear();
            floors.resize(2 * n, 0.0);
            let (kx, ky) = floors.split_at_mut(n);
            for (k, &x) in kx.iter_mut().zip(xs) {
                *k = floor_unsigned(x - oa.x);
            }
            for (k, &y) in ky.iter_mut().zip(ys) {
                *k = floor_unsigned(y - oa.y);
            }
        }
        let (kx, ky) = floors.split_at_mut(n);
        let flipped = flips_soa(xs, ys, kx, ky, ob, stay);
        Some((flipped, n))
    }

    /// A snapped window that moved by whole texels: every probe stays on its texel when both
    /// origins are whole numbers of texels within the limit of [`exact_limit`].
    fn unchanged_centres(&self, i: usize, p: &RigWindow, w: &RigWindow) -> Option<usize> {
        let (a, b) = (&p.window, &w.window);
        let whole = |o: DVec2| o.x.fract() == 0.0 && o.y.fract() == 0.0;
        if !self.fixed || a.texel != b.texel || !whole(a.origin_texels) || !whole(b.origin_texels) {
            return None;
        }
        let xy = self.probe_xy.get(i).map_or(&[][..], |v| &v[..]);
        let (texel, scaled) = self.probe_texels[i].get_or_init(|| (b.texel, xy.iter().map(|q| *q / b.texel).collect()));
        if *texel != b.texel {
            return None;
        }
        let (u, limit) = *self.probe_exact[i].get_or_init(|| exact_limit(scaled));
        let inside = |o: DVec2| o.x.abs() + u < limit && o.y.abs() + u < limit;
        (inside(a.origin_texels) && inside(b.origin_texels)).then_some(scaled.len())
    }

    /// With a fixed basis a landing depends only on the window's texel size and origin.
    #[inline]
    fn same_landings(&self, p: &RigWindow, w: &RigWindow) -> bool {
        self.fixed
            && p.cascade == w.cascade
            && p.window.texel == w.window.texel
            && p.window.origin_texels == w.window.origin_texels
    }

    #[inline]
    fn centre_in(&self, w: &RigWindow, earlier: &Landing) -> DVec2 {
        if self.fixed {
            earlier.centre
        } else {
            self.basis_of(w.cascade).to_light_xy(earlier.world)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flip count from the sorted fractions equals the count over the probes' texels
    /// (`flips_soa` after the previous window's texels), whenever it gives one: random probes
    /// (whole numbers, near-whole and spread ones, magnitudes up to 10^6 texels), origins
    /// that move by whole texels, by a little, by nearly half a texel, and origins placed on
    /// a probe's fraction or next to it; it gives one for nine pairs in ten at least when the
    /// probes and origins are spread.
    #[test]
    fn the_ranked_flip_count_is_the_per_probe_count() {
        let mut rng = crate::rng::SplitMix64::new(23);
        // Pairs counted and pairs given a count, among the cases of spread probes and origins.
        let (mut given, mut pairs) = (0usize, 0usize);
        for case in 0..3000 {
            let spread = case % 3 != 0;
            let n = 1 + (rng.next_u64() % 300) as usize;
            let scale = [1.0, 50.0, 3000.0, 1e6][case % 4];
            let coord = |rng: &mut crate::rng::SplitMix64| match rng.next_u64() % if spread { 1 } else { 6 } {
                0 => rng.range(-scale, scale).round(),
                1 => rng.range(-scale, scale).round() + rng.range(-1e-9, 1e-9),
                2 => rng.range(-scale, scale).round() + 0.5,
                _ => rng.range(-scale, scale),
            };
            let xs: Vec<f64> = (0..n).map(|_| coord(&mut rng)).collect();
            let ys: Vec<f64> = (0..n).map(|_| coord(&mut rng)).collect();
            let ranks = FractionRanks::new(&xs, &ys).expect("few probes");
            let origin = |rng: &mut crate::rng::SplitMix64| {
                let v = rng.range(-2000.0, 2000.0);
                match rng.next_u64() % if spread { 1 } else { 5 } {
                    0 if spread => v,
                    0 => v.round(),
                    // On a probe's fraction, or next to it.
                    1 => v.round() + (xs[0] - xs[0].floor()),
                    2 => v.round() + (ys[0] - ys[0].floor()) + rng.range(-3e-9, 3e-9),
                    _ => v,
                }
            };
            let oa = DVec2::new(origin(&mut rng), origin(&mut rng));
            for _ in 0..8 {
                let step = |rng: &mut crate::rng::SplitMix64| match rng.next_u64() % 5 {
                    0 => (rng.next_u64() % 7) as f64 - 3.0,
                    1 => rng.range(-0.01, 0.01),
                    2 => 0.5 - rng.range(2e-6, 1e-3),
                    3 => rng.range(-3.0, 3.0),
                    _ => -(0.5 - rng.range(2e-6, 1e-3)) + (rng.next_u64() % 3) as f64,
                };
                let ob = oa + DVec2::new(step(&mut rng), step(&mut rng));
                let d = ob - oa;
                let stay = DVec2::new(-round_half_away(d.x), -round_half_away(d.y));
                let r = d + stay;
                if !(r.x.abs() < 0.5 - 1e-6 && r.y.abs() < 0.5 - 1e-6) {
                    continue;
                }
                pairs += usize::from(spread);
                let mut kx: Vec<f64> = xs.iter().map(|&x| floor_unsigned(x - oa.x)).collect();
                let mut ky: Vec<f64> = ys.iter().map(|&y| floor_unsigned(y - oa.y)).collect();
                let expected = flips_soa(&xs, &ys, &mut kx, &mut ky, ob, stay);
                if let Some(got) = ranks.flips(oa, ob, stay) {
                    given += usize::from(spread);
                    assert_eq!(got, expected, "case {case}: oa {oa:?} ob {ob:?} n {n}");
                }
            }
        }
        assert!(given * 10 > pairs * 9, "counted {given} of {pairs} pairs");
    }

    /// The branch-free floor equals `f64::floor` bit for bit below 2^51: whole numbers and
    /// their neighbours, halves (ties), signed zeros, tiny and large values.
    #[test]
    fn the_branch_free_floor_is_f64_floor() {
        let mut rng = crate::rng::SplitMix64::new(11);
        let mut cases = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            1e-300,
            -1e-300,
            0.49999999999999994,
        ];
        let top = (1u64 << 51) as f64;
        for w in [1.0, 2.0, 3.0, 1e6, 4503599627370495.0 / 2.0, top - 1.0] {
            for x in [w, -w] {
                cases.extend([
                    x,
                    f64::from_bits(x.to_bits() + 1),
                    f64::from_bits(x.to_bits() - 1),
                    x + 0.5,
                    x - 0.5,
                ]);
            }
        }
        for _ in 0..200_000 {
            let x = rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-20.0, 15.3));
            cases.push(x);
            cases.push(x.round() + rng.range(-1e-9, 1e-9));
        }
        for x in cases.into_iter().filter(|x| x.abs() < top) {
            assert_eq!(floor_small(x).to_bits(), x.floor().to_bits(), "{x:e}");
            // Equal as numbers (the sign of a zero aside), which is all the flip count reads.
            assert!(floor_unsigned(x) == x.floor(), "{x:e}");
            assert!(floor_unsigned(x) != 0.0 || x.floor() == 0.0, "{x:e}");
        }
    }
}
