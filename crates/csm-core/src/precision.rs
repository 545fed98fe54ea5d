//! Emulating an engine's binary32 cascade pipeline, operation by operation.
//!
//! The f64 pipeline of [`crate::cascades`] keeps window origins in *texel units*, so a snapped
//! window sits on an exact integer and its shimmer is exactly zero at any distance from the
//! world origin. Engines do not: they build the light matrix, the sphere centre, the snapped
//! window and the shader lookup in binary32 (`f32`) at absolute world coordinates. This module
//! redoes those steps the way an engine writes them, each `+ - * /` rounded to f32, for the
//! rig's own [`crate::cascades::Scheme`] (csm-lab's fits and every engine preset alike):
//!
//! 1. `light_from_world` rows (the light x/y axes) stored in f32: the rig's fixed basis, or
//!    the basis the scheme derives from the camera that frame (computed in f64, then stored);
//! 2. the camera position and unit axes stored in f32; an axis-centred window (any sphere
//!    fit): the centre `C = P + forward * c` in f32; a box-shaped window (tight box, padded
//!    box, box-centred square, box at the world origin): the 8 slice corners
//!    `P + forward*z + right*(sx*z) + up*(sy*z)` in f32, transformed and bounded in f32, the
//!    size from the bounds (plus padding and snapping border) or the scheme's constant side;
//! 3. the light-space centre `c = light_from_world * C` (dot products, left to right);
//! 4. the texel size `T = W / N` in f32;
//! 5. snapping in world units: `round(c / (T*step)) * (T*step)` with the rig's
//!    [`crate::snapping::SnapRule`] (round, floor or trunc), on a grid through the world origin
//!    or through the scheme's snap anchor (EEVEE's lamp), and only if the scheme snaps at all.
//!    `k*T` is rarely representable in
//!    f32, so the snapped centre is off the grid by up to half an ulp of `c`, differently every
//!    frame: this is the engine bug the emulation reproduces;
//! 6. the window origin `o = snapped - W/2` in f32;
//! 7. the probe lookup `s = (light_from_world * X - o) / T` in f32, with the probe X stored in f32.
//!
//! No fused multiply-add: every operation rounds, as on a CPU without FMA contraction. (GPUs
//! that fuse a multiply-add round once instead of twice; individual values change, the ulp32
//! scale of the errors does not.)
//!
//! **Snap space.** With [`SnapSpace::World`] every position enters at its absolute world
//! coordinates. With [`SnapSpace::CameraRelative`] positions are first taken relative to an
//! anchor in f64 and only then rounded to f32, as an engine that keeps the camera in double
//! precision and re-bases its render origin on the camera every frame does. The anchor of
//! cascade i in frame t is that frame's camera position moved (by less than one snap step,
//! along the light's x and y) onto the cascade's snap grid, in f64: its light-space x/y are
//! whole multiples of `T*step`. Relative snapping with `round` and `floor` therefore picks the
//! same world-anchored grid line as world snapping would, and every number the f32 pipeline
//! sees is small. (`trunc` truncates toward the anchor rather than toward the world origin, as
//! an engine applying `fmod` to camera-relative coordinates does.)
//!
//! **Metrics.** Along the path the emulated pipeline is measured with the shimmer metrics of
//! [`crate::shimmer`] (S1 size change, S3 sub-texel drift of the f32 lookups of static probes,
//! S4 cell flips, coverage of the exact slice corners by the f32 window) plus S7 below. S3, S4
//! and S7 count the probes the cascade serves: those inside the window the engine means to
//! build (the exact f64 window of that frame; in both frames, for S3 and S4), wherever the f32
//! window and lookup put them. Probes are fixed in frame 0's slices; once the camera has left
//! them behind an engine looks them up in another cascade, and their f32 error would only
//! measure how far the camera travelled. Frame pairs with no such probe are skipped. (An f32
//! window misplaced by more than its border shows as coverage violations.)
//!
//! * **S7, static lookup error**: for probe X, cascade i, frame t,
//!   `e = max over axes |s_f32(X) - s_ref(X)|` in texels. `s_f32` is the shader's binary32
//!   lookup of X stored in f32. `s_ref = (M*X - o)/T` is where X really falls in the window the
//!   f32 pipeline built, evaluated exactly: the same f32 matrix rows `M`, origin `o` and texel
//!   size `T` (taken exactly as f64), but X exact and no rounding. The shadow map is rasterised
//!   through the same `M`, `o` and `T`, so S7 is the error of the lookup itself: the rounding
//!   of the stored probe, of its transform and of `(u - o)/T`. It is about `ulp32(|u|)/T` with
//!   `u` the light-space coordinate, and it sets the minimum depth bias. S7 is reported as the
//!   max and the RMS over every frame of the path, every cascade and every probe, for the
//!   configured snap setting. (Where the window itself lands, `k*T` rounding included, is the
//!   temporal part: S3.)
//!
//! The [`Real`] trait also instantiates the pipeline in f64, an independent implementation of
//! the rig's windows (world units instead of texel units) that the tests compare against.
//! Only light-space x/y are emulated: the depth (z) lookup is not part of S3/S7.

use std::ops::{Add, Div, Mul, Sub};

use glam::{DVec2, DVec3};

use crate::cascades::{LightPose, Rig, WindowRule};
use crate::fitting::Window;
use crate::geometry::{Aabb, CameraPose, Corner, LightBasis};
use crate::scene::SnapSpace;
use crate::shimmer::{PathResult, ShimmerOptions};
use crate::snapping::SnapMode;
use crate::walk::{walk, Landing, PathModel, PathTotals};

/// Spacing of binary32 numbers at `|x|`: the distance from `|x|` (rounded to f32) to the next
/// larger f32. `ulp32(1e5) = 2^-7`.
pub fn ulp32(x: f64) -> f64 {
    let v = (x as f32).abs();
    (f32::from_bits(v.to_bits() + 1) as f64) - v as f64
}

/// The arithmetic the emulated pipeline runs in: `f32` (the engine) or `f64` (the reference).
/// Every operation rounds to the type; conversions from f64 round to nearest.
pub trait Real:
    Copy + PartialOrd + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    fn of(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn round_half_away(self) -> Self;
    fn floor_(self) -> Self;
    fn trunc_(self) -> Self;
}

// The two arithmetics differ only in their type: each operation is the type's own (rounding
// to that type), so one body serves both.
macro_rules! impl_real {
    ($t:ty) => {
        impl Real for $t {
            fn of(x: f64) -> Self {
                x as $t
            }
            fn to_f64(self) -> f64 {
                self as f64
            }
            fn round_half_away(self) -> Self {
                self.round()
            }
            fn floor_(self) -> Self {
                self.floor()
            }
            fn trunc_(self) -> Self {
                self.trunc()
            }
        }
    };
}
impl_real!(f32);
impl_real!(f64);

fn v3<R: Real>(p: DVec3) -> [R; 3] {
    [R::of(p.x), R::of(p.y), R::of(p.z)]
}

/// `a.x*b.x + a.y*b.y + a.z*b.z`, left to right, every operation rounded.
fn dot3<R: Real>(a: &[R; 3], b: &[R; 3]) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A cascade's window as the engine holds it: origin (minimum corner) and texel size in
/// light-space units, relative to the cascade's anchor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineWindow<R> {
    pub origin: [R; 2],
    pub texel: [R; 2],
}

impl<R: Real> EngineWindow<R> {
    /// The shader's texel coordinate `(u - o) / T` of light-space `u` (relative to the anchor).
    pub fn lookup(&self, u: [R; 2]) -> [R; 2] {
        [
            (u[0] - self.origin[0]) / self.texel[0],
            (u[1] - self.origin[1]) / self.texel[1],
        ]
    }

    pub fn origin_f64(&self) -> DVec2 {
        DVec2::new(self.origin[0].to_f64(), self.origin[1].to_f64())
    }

    pub fn texel_f64(&self) -> DVec2 {
        DVec2::new(self.texel[0].to_f64(), self.texel[1].to_f64())
    }
}

/// Per-cascade constants, converted once (they are bit-identical every frame in an engine).
#[derive(Debug, Clone)]
struct CascadeConsts<R> {
    /// Constant-size windows: side (border included).
    side: R,
    /// Axis-centred windows: view depth of the window centre.
    centre_depth: R,
    /// Box-shaped windows: the fitted slice's depths.
    near: R,
    far: R,
}

/// The cascade pipeline of a [`Rig`] under its [`crate::cascades::Scheme`], written as an
/// engine writes it, in arithmetic `R`: the scheme's light basis, window centre and size
/// (axis-centred, box-centred, tight box with its padding and border, tight box at the world
/// origin), its snap rule (round, floor or trunc, grid step) on its snap anchor, and the lookup.
/// A light basis that follows the camera is derived in f64 each frame and stored in `R`, as an
/// engine stores the matrix it computed.
#[derive(Debug, Clone)]
pub struct EnginePipeline<R> {
    rig: Rig,
    /// Rows of `light_from_world` for light x and y of the rig's fixed basis.
    rows: [[R; 3]; 2],
    resolution: R,
    /// `N - 2*shift`: a bordered box's side is `extent * N / (N - 2 shift)` (snapping border).
    border_denominator: R,
    step_texels: R,
    mode: SnapMode,
    tan_h: R,
    tan_v: R,
    half: R,
    /// Twice a tight box's padding per side (world units).
    pad2: R,
    consts: Vec<CascadeConsts<R>>,
}

/// Per-cascade anchors of one frame: the world origin, or (camera-relative) the frame's camera
/// position moved along the cascade's light x/y onto its snap grid of that frame, in f64.
pub fn frame_anchors(rig: &Rig, pose: &CameraPose, space: SnapSpace) -> Vec<DVec3> {
    match space {
        SnapSpace::World => vec![DVec3::ZERO; rig.cascade_count()],
        SnapSpace::CameraRelative => {
            let lp = LightPose::new(&rig.light, pose);
            let a = pose.position;
            let step = rig.snap_rule.step_texels as f64;
            let g = rig.scheme.snap_anchor;
            (0..rig.cascade_count())
                .map(|i| {
                    let b = rig.basis(i, &lp);
                    let axy = b.to_light_xy(a);
                    let t = rig.window(i, &lp, true).texel * step;
                    let d = if g == DVec2::ZERO {
                        (axy / t).round() * t - axy
                    } else {
                        ((axy - g) / t).round() * t + g - axy
                    };
                    a + b.x * d.x + b.y * d.y
                })
                .collect()
        }
    }
}

impl<R: Real> EnginePipeline<R> {
    pub fn new(rig: &Rig) -> Self {
        let n = rig.resolution as f64;
        let centre_depth = |i: usize| match &rig.scheme.window {
            WindowRule::AxisCentred { centre_depth } => centre_depth[i],
            _ => rig.slices[i].sphere.centre_depth,
        };
        let consts = rig
            .slices
            .iter()
            .zip(&rig.sphere_side)
            .enumerate()
            .map(|(i, (s, &side))| CascadeConsts {
                side: R::of(side),
                centre_depth: R::of(centre_depth(i)),
                near: R::of(s.near),
                far: R::of(s.far),
            })
            .collect();
        let pad = match rig.scheme.window {
            WindowRule::Tight { pad, .. } => pad,
            _ => 0.0,
        };
        EnginePipeline {
            rig: rig.clone(),
            rows: [v3(rig.light.x), v3(rig.light.y)],
            resolution: R::of(n),
            border_denominator: R::of(n - 2.0 * rig.snap_rule.max_shift_texels()),
            step_texels: R::of(rig.snap_rule.step_texels as f64),
            mode: rig.snap_rule.mode,
            tan_h: R::of(rig.lens.tan_h),
            tan_v: R::of(rig.lens.tan_v),
            half: R::of(0.5),
            pad2: R::of(2.0 * pad),
            consts,
        }
    }

    /// The light x/y rows of the fixed basis as stored, exactly as f64 (for exact evaluations
    /// of the same map).
    pub fn rows_f64(&self) -> [DVec3; 2] {
        rows_as_f64(&self.rows)
    }

    /// Cascade `i`'s `light_from_world` x/y rows in the frame of `pose`, as stored.
    pub fn rows_of(&self, i: usize, pose: &CameraPose) -> [[R; 3]; 2] {
        if self.rig.fixed_basis() {
            self.rows
        } else {
            let b = self.rig.basis(i, &LightPose::new(&self.rig.light, pose));
            [v3(b.x), v3(b.y)]
        }
    }

    /// A world point as the engine stores it: relative to `anchor` (subtracted in f64), then
    /// rounded to `R`; returns its light-space x/y in the fixed basis, computed in `R`.
    pub fn probe(&self, anchor: DVec3, x: DVec3) -> [R; 2] {
        light_xy(&self.rows, &v3(x - anchor))
    }

    fn snap(&self, q: R) -> R {
        match self.mode {
            SnapMode::Round => q.round_half_away(),
            SnapMode::Floor => q.floor_(),
            SnapMode::Trunc => q.trunc_(),
        }
    }

    /// Cascade `i`'s window for a camera pose, in coordinates relative to `anchor`.
    pub fn window(&self, i: usize, pose: &CameraPose, anchor: DVec3, snapped: bool) -> EngineWindow<R> {
        self.window_with(i, &self.rows_of(i, pose), pose, anchor, snapped)
    }

    /// The light-space bounds of cascade `i`'s 8 slice corners, each corner built and
    /// transformed in `R`.
    fn corner_bounds(
        &self,
        i: usize,
        rows: &[[R; 3]; 2],
        p: &[R; 3],
        f: &[R; 3],
        pose: &CameraPose,
    ) -> ([R; 2], [R; 2]) {
        let c = &self.consts[i];
        let r: [R; 3] = v3(pose.right);
        let u: [R; 3] = v3(pose.up);
        let mut lo = [R::of(f64::INFINITY); 2];
        let mut hi = [R::of(f64::NEG_INFINITY); 2];
        for corner in Corner::ALL {
            let sx = corner.x(R::of(0.0) - self.tan_h, self.tan_h);
            let sy = corner.y(R::of(0.0) - self.tan_v, self.tan_v);
            let z = corner.z(c.near, c.far);
            let (sxz, syz) = (sx * z, sy * z);
            let world: [R; 3] = std::array::from_fn(|k| p[k] + f[k] * z + r[k] * sxz + u[k] * syz);
            let xy = light_xy(rows, &world);
            for a in 0..2 {
                if xy[a] < lo[a] {
                    lo[a] = xy[a];
                }
                if xy[a] > hi[a] {
                    hi[a] = xy[a];
                }
            }
        }
        (lo, hi)
    }

    /// [`EnginePipeline::window`] with the cascade's rows given.
    pub(crate) fn window_with(
        &self,
        i: usize,
        rows: &[[R; 3]; 2],
        pose: &CameraPose,
        anchor: DVec3,
        snapped: bool,
    ) -> EngineWindow<R> {
        let c = &self.consts[i];
        let p: [R; 3] = v3(pose.position - anchor);
        let f: [R; 3] = v3(pose.forward);
        let mid = |lo: [R; 2], hi: [R; 2]| [(lo[0] + hi[0]) * self.half, (lo[1] + hi[1]) * self.half];
        let (centre, size) = match &self.rig.scheme.window {
            WindowRule::AxisCentred { .. } => {
                let world = [
                    p[0] + f[0] * c.centre_depth,
                    p[1] + f[1] * c.centre_depth,
                    p[2] + f[2] * c.centre_depth,
                ];
                (light_xy(rows, &world), [c.side, c.side])
            }
            WindowRule::BoxCentred => {
                let (lo, hi) = self.corner_bounds(i, rows, &p, &f, pose);
                (mid(lo, hi), [c.side, c.side])
            }
            WindowRule::Tight { pad, border } => {
                let (lo, hi) = self.corner_bounds(i, rows, &p, &f, pose);
                let extent = |a: usize| {
                    if *pad == 0.0 {
                        hi[a] - lo[a]
                    } else {
                        hi[a] - lo[a] + self.pad2
                    }
                };
                let side = |a: usize| {
                    if *border {
                        extent(a) * self.resolution / self.border_denominator
                    } else {
                        extent(a)
                    }
                };
                (mid(lo, hi), [side(0), side(1)])
            }
            WindowRule::TightAtOrigin => {
                let (lo, hi) = self.corner_bounds(i, rows, &p, &f, pose);
                // The light-space axis through the world origin, relative to the anchor.
                (light_xy(rows, &v3(-anchor)), [hi[0] - lo[0], hi[1] - lo[1]])
            }
        };
        let texel = [size[0] / self.resolution, size[1] / self.resolution];
        // The grid's own anchor (EEVEE's lamp) relative to the pipeline's anchor, or None for
        // a grid through the world origin.
        let g = self.rig.scheme.snap_anchor;
        let grid = (g != DVec2::ZERO).then(|| {
            let rel = g - self.rig.light.to_light_xy(anchor);
            [R::of(rel.x), R::of(rel.y)]
        });
        let snaps = snapped && self.rig.scheme.snaps;
        let origin: [R; 2] = std::array::from_fn(|a| {
            let centre = if snaps {
                // World-unit snapping: k*step is generally not representable in f32.
                let step = texel[a] * self.step_texels;
                match grid {
                    None => self.snap(centre[a] / step) * step,
                    Some(g) => self.snap((centre[a] - g[a]) / step) * step + g[a],
                }
            } else {
                centre[a]
            };
            centre - size[a] * self.half
        });
        EngineWindow { origin, texel }
    }
}

fn rows_as_f64<R: Real>(rows: &[[R; 3]; 2]) -> [DVec3; 2] {
    rows.map(|r| DVec3::new(r[0].to_f64(), r[1].to_f64(), r[2].to_f64()))
}

/// `light_from_world * p`, x and y.
fn light_xy<R: Real>(rows: &[[R; 3]; 2], p: &[R; 3]) -> [R; 2] {
    [dot3(&rows[0], p), dot3(&rows[1], p)]
}

/// S7 over a path: the largest and the RMS static lookup error, in texels.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct LookupError {
    pub max: f64,
    pub rms: f64,
    pub cascade_max: Vec<f64>,
    pub cascade_rms: Vec<f64>,
}

impl LookupError {
    fn of(totals: &PathTotals) -> Self {
        let total: usize = totals.lookup_count.iter().sum();
        LookupError {
            max: totals.lookup_max.iter().cloned().fold(0.0, f64::max),
            rms: if total > 0 {
                (totals.lookup_sq.iter().sum::<f64>() / total as f64).sqrt()
            } else {
                0.0
            },
            cascade_rms: totals
                .lookup_sq
                .iter()
                .zip(&totals.lookup_count)
                .map(|(s, &c)| if c > 0 { (s / c as f64).sqrt() } else { 0.0 })
                .collect(),
            cascade_max: totals.lookup_max.clone(),
        }
    }
}

/// One pass of the emulated f32 pipeline along a path, for one snap setting.
#[derive(Debug, Clone, PartialEq)]
pub struct EmulatedPath {
    /// S1, S3, S4 and coverage of the f32 pipeline, in the same form as the f64 path.
    pub path: PathResult,
    /// S7 (see the module documentation).
    pub lookup: LookupError,
}

/// The binary32 pipeline as a [`PathModel`]. Always per probe: in f32 the drift differs from
/// probe to probe, so there is no closed form.
pub struct EnginePath<'a> {
    rig: &'a Rig,
    engine: EnginePipeline<f32>,
    probes: &'a [Vec<DVec3>],
    /// Fixed basis: each probe's exact light-space x/y, computed once.
    probe_xy: Vec<Vec<DVec2>>,
    space: SnapSpace,
    pose: Option<CameraPose>,
    lp: Option<LightPose>,
    anchors: Vec<DVec3>,
}

/// Per frame and cascade: the anchor, the cascade's basis (exact and as stored in f32) and
/// the camera frame in that basis.
pub struct EngineShared {
    anchor: DVec3,
    anchor_xy: DVec2,
    basis: LightBasis,
    rows: [[f32; 3]; 2],
    rows_f64: [DVec3; 2],
    lp: LightPose,
}

/// A window of the binary32 pipeline: as the engine holds it, its origin and texel size
/// exactly as f64, the origin in world-anchored light space, and the exact window the engine
/// means to build (which decides the probes it serves).
#[derive(Debug, Clone, Copy)]
pub struct EngineWin {
    engine: EngineWindow<f32>,
    origin: DVec2,
    texel: DVec2,
    origin_world: DVec2,
    intended: Window,
}

impl<'a> EnginePath<'a> {
    pub fn new(rig: &'a Rig, probes: &'a [Vec<DVec3>], space: SnapSpace) -> Self {
        EnginePath {
            rig,
            engine: EnginePipeline::new(rig),
            probes,
            probe_xy: rig.fixed_probe_xy(probes),
            space,
            pose: None,
            lp: None,
            anchors: Vec::new(),
        }
    }
}

impl PathModel for EnginePath<'_> {
    type Shared = EngineShared;
    type Win = EngineWin;
    const SKIP_UNSERVED: bool = true;

    fn cascade_count(&self) -> usize {
        self.rig.cascade_count()
    }

    fn probes_needed(&self, _opts: ShimmerOptions) -> bool {
        true
    }

    fn begin_frame(&mut self, _t: usize, pose: &CameraPose) {
        self.pose = Some(*pose);
        self.lp = Some(LightPose::new(&self.rig.light, pose));
        self.anchors = frame_anchors(self.rig, pose, self.space);
    }

    fn shared(&self, i: usize) -> EngineShared {
        let lp = self.lp.expect("begin_frame first");
        let anchor = self.anchors[i];
        let (basis, lp) = self.rig.cascade_pose(i, &lp);
        let rows = self.engine.rows_of(i, &lp.pose);
        EngineShared {
            anchor,
            anchor_xy: basis.to_light_xy(anchor),
            basis,
            rows,
            rows_f64: rows_as_f64(&rows),
            lp,
        }
    }

    fn window(&self, i: usize, sh: &mut EngineShared, snapped: bool) -> EngineWin {
        let pose = &sh.lp.pose;
        let w = self.engine.window_with(i, &sh.rows, pose, sh.anchor, snapped);
        let (origin, texel) = (w.origin_f64(), w.texel_f64());
        EngineWin {
            engine: w,
            origin,
            texel,
            // The origin in world-anchored light space, so frames with different anchors
            // compare (f64; the anchor is on the grid, so this only adds a whole number of
            // steps).
            origin_world: origin + sh.anchor_xy,
            intended: self.rig.window_in(i, &sh.lp, snapped),
        }
    }

    fn texel(w: &EngineWin) -> DVec2 {
        w.texel
    }

    fn cover(&self, i: usize, sh: &mut EngineShared, w: &EngineWin, totals: &mut PathTotals) {
        // Coverage of the exact slice by the f32 window, evaluated exactly (f64) from the
        // window's f32 origin and texel size.
        let n = self.rig.resolution as f64;
        for (near, far) in self.rig.covered_intervals(i) {
            for c in sh.lp.corners(&self.rig.lens, near, far) {
                totals.corner(
                    i,
                    (c - sh.anchor_xy - w.origin) / w.texel,
                    n,
                    (c / w.texel).abs().max_element(),
                );
            }
        }
    }

    fn closed_form(&self, _p: &EngineWin, _w: &EngineWin) -> Option<f64> {
        None
    }

    fn land(
        &self,
        i: usize,
        sh: &EngineShared,
        w: &EngineWin,
        out: &mut Vec<Option<Landing>>,
        totals: &mut PathTotals,
    ) {
        let n = self.rig.resolution as f64;
        let [row_x, row_y] = sh.rows_f64;
        let probes = self.probes.get(i).map_or(&[][..], |v| &v[..]);
        for (j, x) in probes.iter().enumerate() {
            let xy = match self.probe_xy.get(i) {
                Some(v) => v[j],
                None => sh.basis.to_light_xy(*x),
            };
            // Served: the probe lies in the window the engine means to build (the exact one),
            // whatever the f32 window and lookup did with it. Probes the camera has left
            // behind are looked up in another cascade by an engine.
            let se = w.intended.texel_coords(xy);
            if !(se.cmpge(DVec2::ZERO).all() && se.cmple(DVec2::splat(n)).all()) {
                out.push(None);
                continue;
            }
            // S7: the shader's lookup against the exact lookup in the same window.
            let rel = *x - sh.anchor;
            let exact = (DVec2::new(row_x.dot(rel), row_y.dot(rel)) - w.origin) / w.texel;
            let s = w.engine.lookup(light_xy(&sh.rows, &v3(rel)));
            let s = DVec2::new(s[0] as f64, s[1] as f64);
            totals.lookup_error(i, (s - exact).abs().max_element());
            out.push(Some(Landing {
                s,
                centre: w.origin_world + (s.floor() + 0.5) * w.texel,
                world: DVec3::ZERO,
            }));
        }
    }

    fn centre_in(&self, _w: &EngineWin, earlier: &Landing) -> DVec2 {
        earlier.centre
    }
}

/// Walks the path with the binary32 pipeline for one snap setting.
pub fn along_path<P: std::borrow::Borrow<CameraPose>, I>(
    rig: &Rig,
    poses: I,
    probes: &[Vec<DVec3>],
    space: SnapSpace,
    snapped: bool,
    opts: ShimmerOptions,
) -> EmulatedPath
where
    I: IntoIterator<Item = P>,
    I::IntoIter: ExactSizeIterator,
{
    let [t] = walk(&mut EnginePath::new(rig, probes, space), poses, [snapped], opts);
    emulated(t, opts)
}

/// Both snap settings in one walk, `(snapped, unsnapped)`: the same results as two calls of
/// [`along_path`].
pub fn along_path_both<P: std::borrow::Borrow<CameraPose>, I>(
    rig: &Rig,
    poses: I,
    probes: &[Vec<DVec3>],
    space: SnapSpace,
    opts: ShimmerOptions,
) -> (EmulatedPath, EmulatedPath)
where
    I: IntoIterator<Item = P>,
    I::IntoIter: ExactSizeIterator,
{
    let [s, u] = walk(&mut EnginePath::new(rig, probes, space), poses, [true, false], opts);
    (emulated(s, opts), emulated(u, opts))
}

fn emulated(t: PathTotals, opts: ShimmerOptions) -> EmulatedPath {
    let lookup = LookupError::of(&t);
    EmulatedPath {
        path: t.finish(opts),
        lookup,
    }
}

/// Largest ratio of a coordinate to a texel size (and largest coordinate, smallest texel) the
/// binary32 pipeline accepts: 2^100 keeps every product and quotient far from f32's 2^128
/// overflow and 2^-126 underflow.
pub const F32_LIMIT: f64 = 1.2676506002282294e30; // 2^100

/// Why a rig cannot run in binary32 along `poses`, or None. Checks the texel sizes of frame 0
/// and the largest world coordinate the pipeline handles (camera positions along the path plus
/// the farthest slice point, and the scene bounds `bounds`) against [`F32_LIMIT`], on absolute
/// coordinates (conservative for `camera_relative`); then builds every frame's f32 windows in
/// snap space `space` and refuses one that collapses or is not finite. The message completes
/// "use precision = ...".
pub fn f32_range_problem<P: std::borrow::Borrow<CameraPose>>(
    rig: &Rig,
    poses: impl IntoIterator<Item = P> + Clone,
    bounds: &Aabb,
    space: SnapSpace,
) -> Option<String> {
    let reach = rig
        .slices
        .iter()
        .map(|s| s.sphere.centre_depth + s.sphere.radius)
        .fold(0.0, f64::max);
    // Two passes over the poses (a generator is cloned, not collected).
    let camera = poses
        .clone()
        .into_iter()
        .map(|p| p.borrow().position.abs().max_element())
        .fold(0.0, f64::max);
    let scene = bounds.min.abs().max(bounds.max.abs()).max_element();
    let coord = (camera + reach).max(scene);
    let lp0 = LightPose::new(&rig.light, poses.clone().into_iter().next()?.borrow());
    let texel = (0..rig.cascade_count())
        .map(|i| rig.window(i, &lp0, true).texel.min_element())
        .fold(f64::INFINITY, f64::min);
    let size = (0..rig.cascade_count())
        .map(|i| rig.window(i, &lp0, true).texel.max_element())
        .fold(0.0, f64::max);
    let texel_ok = texel.is_finite() && texel >= 1.0 / F32_LIMIT;
    if !texel_ok || size > F32_LIMIT || coord > F32_LIMIT {
        return Some(format!(
            "\"f64\" for this scene: binary32 cannot hold it (texel sizes {texel:e} .. {size:e}, coordinates up to \
             {coord:e}; the f32 pipeline needs them within 2^-100 .. 2^100)"
        ));
    }
    if coord / texel > F32_LIMIT {
        return Some(format!(
            "\"f64\" for this scene: binary32 cannot hold its texel coordinates (|coordinate| / texel = {:e} \
             exceeds 2^100); move the scene toward the origin or use precision = \"f64\"",
            coord / texel
        ));
    }
    // The windows themselves, built in binary32 as the analysis will build them: a slice
    // thinner than one f32 step at its coordinates collapses an AABB window to zero size (an
    // engine would divide by zero), which no metric can describe.
    let engine: EnginePipeline<f32> = EnginePipeline::new(rig);
    let smallest = (1.0 / F32_LIMIT) as f32;
    for (t, pose) in poses.into_iter().enumerate() {
        let pose = pose.borrow();
        let anchors = frame_anchors(rig, pose, space);
        for (i, anchor) in anchors.iter().enumerate() {
            for snapped in [true, false] {
                let w = engine.window(i, pose, *anchor, snapped);
                let ok =
                    w.texel.iter().all(|t| t.is_finite() && *t >= smallest) && w.origin.iter().all(|o| o.is_finite());
                if !ok {
                    let lp = LightPose::new(&rig.light, pose);
                    let exact = rig.window(i, &lp, snapped);
                    let at = (exact.centre() - rig.light.to_light_xy(*anchor)).abs().max_element();
                    return Some(format!(
                        "\"f64\"{} for this scene: in binary32 cascade {i}'s window collapses in frame {t} (its \
                         slice is {:e} units across, one binary32 step at its coordinates is {:e})",
                        if space == SnapSpace::World {
                            ", or snap_space = \"camera_relative\","
                        } else {
                            ""
                        },
                        exact.width().min(exact.height()),
                        ulp32(at),
                    ));
                }
            }
        }
    }
    None
}
