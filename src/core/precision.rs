//! Emulating an engine's binary32 cascade pipeline, operation by operation.
//!
//! The f64 pipeline of [`crate::cascades`] keeps window origins in *texel units*, so a snapped
//! window sits on an exact integer and its shimmer is exactly zero at any distance from the
//! world origin. Engines do not: they build the light matrix, the sphere centre, the snapped
//! window and the shader lookup in binary32 (`f32`) at absolute world coordinates. This module
//! redoes those steps the way an engine writes them, each `+ - * /` rounded to f32:
//!
//! 1. `light_from_world` rows (the light x/y axes) stored in f32;
//! 2. the camera position and unit axes stored in f32; sphere fit: the centre
//!    `C = P + forward * c` in f32; AABB fit: the 8 slice corners `P + forward*z + right*(sx*z)
//!    + up*(sy*z)` in f32, transformed and bounded in f32;
//! 3. the light-space centre `c = light_from_world * C` (dot products, left to right);
//! 4. the texel size `T = W / N` in f32;
//! 5. snapping in world units: `round(c / (T*step)) * (T*step)` with the rig's
//!    [`crate::snapping::SnapRule`] (round, floor or trunc). `k*T` is rarely representable in
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

use crate::cascades::{LightPose, Rig};
use crate::fitting::Fit;
use crate::geometry::{Aabb, CameraPose};
use crate::shimmer::{wrap, PathResult, PathTotals, ShimmerOptions};
use crate::snapping::SnapMode;

/// Arithmetic of the cascade pipeline (`[shadow] precision`, `--precision`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// Exact: texel-unit windows, snapped shimmer exactly 0 at any world offset.
    #[default]
    F64,
    /// An engine's binary32 pipeline, emulated operation by operation.
    F32,
}

impl Precision {
    pub fn name(self) -> &'static str {
        match self {
            Precision::F64 => "f64",
            Precision::F32 => "f32",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "f64" => Some(Precision::F64),
            "f32" => Some(Precision::F32),
            _ => None,
        }
    }
}

impl std::str::FromStr for Precision {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Precision::from_name(s).ok_or_else(|| format!("{s:?} is not one of f64, f32"))
    }
}

impl std::fmt::Display for Precision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where the binary32 pipeline computes (`[shadow] snap_space`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SnapSpace {
    /// Absolute world coordinates rounded to f32 (what engines do by default).
    #[default]
    World,
    /// Positions relative to a camera-near, grid-aligned anchor, subtracted in f64.
    CameraRelative,
}

impl SnapSpace {
    pub fn name(self) -> &'static str {
        match self {
            SnapSpace::World => "world",
            SnapSpace::CameraRelative => "camera_relative",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "world" => Some(SnapSpace::World),
            "camera_relative" => Some(SnapSpace::CameraRelative),
            _ => None,
        }
    }
}

impl std::fmt::Display for SnapSpace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

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

impl Real for f32 {
    fn of(x: f64) -> Self {
        x as f32
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

impl Real for f64 {
    fn of(x: f64) -> Self {
        x
    }
    fn to_f64(self) -> f64 {
        self
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
    /// Sphere fit: window side (with the snapping border) and centre depth.
    side: R,
    centre_depth: R,
    /// AABB fit: slice depths.
    near: R,
    far: R,
}

/// The cascade pipeline of a [`Rig`], written as an engine writes it, in arithmetic `R`.
#[derive(Debug, Clone)]
pub struct EnginePipeline<R> {
    /// Rows of `light_from_world` for light x and y.
    rows: [[R; 3]; 2],
    resolution: R,
    /// `N - 2*shift`: the AABB side is `extent * N / (N - 2 shift)` (snapping border).
    border_denominator: R,
    step_texels: R,
    mode: SnapMode,
    fit: Fit,
    tan_h: R,
    tan_v: R,
    half: R,
    consts: Vec<CascadeConsts<R>>,
}

/// Per-cascade anchors of one frame: the world origin, or (camera-relative) the frame's camera
/// position moved along light x/y onto each cascade's snap grid of that frame, in f64.
pub fn frame_anchors(rig: &Rig, pose: &CameraPose, space: SnapSpace) -> Vec<DVec3> {
    match space {
        SnapSpace::World => vec![DVec3::ZERO; rig.cascade_count()],
        SnapSpace::CameraRelative => {
            let lp = LightPose::new(&rig.light, pose);
            let a = pose.position;
            let axy = lp.position;
            let step = rig.snap_rule.step_texels as f64;
            (0..rig.cascade_count())
                .map(|i| {
                    let t = rig.window(i, &lp, true).texel * step;
                    let d = (axy / t).round() * t - axy;
                    a + rig.light.x * d.x + rig.light.y * d.y
                })
                .collect()
        }
    }
}

impl<R: Real> EnginePipeline<R> {
    pub fn new(rig: &Rig) -> Self {
        let n = rig.resolution as f64;
        let consts = rig
            .slices
            .iter()
            .zip(&rig.sphere_side)
            .map(|(s, &side)| CascadeConsts {
                side: R::of(side),
                centre_depth: R::of(s.sphere.centre_depth),
                near: R::of(s.near),
                far: R::of(s.far),
            })
            .collect();
        EnginePipeline {
            rows: [v3(rig.light.x), v3(rig.light.y)],
            resolution: R::of(n),
            border_denominator: R::of(n - 2.0 * rig.snap_rule.max_shift_texels()),
            step_texels: R::of(rig.snap_rule.step_texels as f64),
            mode: rig.snap_rule.mode,
            fit: rig.fit,
            tan_h: R::of(rig.lens.tan_h),
            tan_v: R::of(rig.lens.tan_v),
            half: R::of(0.5),
            consts,
        }
    }

    /// The light x/y rows as stored, exactly as f64 (for exact evaluations of the same map).
    pub fn rows_f64(&self) -> [DVec3; 2] {
        self.rows
            .map(|r| DVec3::new(r[0].to_f64(), r[1].to_f64(), r[2].to_f64()))
    }

    /// `light_from_world * p`, x and y.
    fn light_xy(&self, p: &[R; 3]) -> [R; 2] {
        [dot3(&self.rows[0], p), dot3(&self.rows[1], p)]
    }

    /// A world point as the engine stores it: relative to `anchor` (subtracted in f64), then
    /// rounded to `R`; returns its light-space x/y computed in `R`.
    pub fn probe(&self, anchor: DVec3, x: DVec3) -> [R; 2] {
        self.light_xy(&v3(x - anchor))
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
        let c = &self.consts[i];
        let p: [R; 3] = v3(pose.position - anchor);
        let f: [R; 3] = v3(pose.forward);
        let (centre, size) = match self.fit {
            Fit::Sphere => {
                let world = [
                    p[0] + f[0] * c.centre_depth,
                    p[1] + f[1] * c.centre_depth,
                    p[2] + f[2] * c.centre_depth,
                ];
                (self.light_xy(&world), [c.side, c.side])
            }
            Fit::Aabb => {
                let r: [R; 3] = v3(pose.right);
                let u: [R; 3] = v3(pose.up);
                let mut lo = [R::of(f64::INFINITY); 2];
                let mut hi = [R::of(f64::NEG_INFINITY); 2];
                for corner in 0..8 {
                    let sx = if corner & 1 == 0 {
                        R::of(0.0) - self.tan_h
                    } else {
                        self.tan_h
                    };
                    let sy = if corner & 2 == 0 {
                        R::of(0.0) - self.tan_v
                    } else {
                        self.tan_v
                    };
                    let z = if corner & 4 == 0 { c.near } else { c.far };
                    let (sxz, syz) = (sx * z, sy * z);
                    let world: [R; 3] = std::array::from_fn(|k| p[k] + f[k] * z + r[k] * sxz + u[k] * syz);
                    let xy = self.light_xy(&world);
                    for a in 0..2 {
                        if xy[a] < lo[a] {
                            lo[a] = xy[a];
                        }
                        if xy[a] > hi[a] {
                            hi[a] = xy[a];
                        }
                    }
                }
                let side = |a: usize| (hi[a] - lo[a]) * self.resolution / self.border_denominator;
                (
                    [(lo[0] + hi[0]) * self.half, (lo[1] + hi[1]) * self.half],
                    [side(0), side(1)],
                )
            }
        };
        let texel = [size[0] / self.resolution, size[1] / self.resolution];
        let origin: [R; 2] = std::array::from_fn(|a| {
            let centre = if snapped {
                // World-unit snapping: k*step is generally not representable in f32.
                let step = texel[a] * self.step_texels;
                self.snap(centre[a] / step) * step
            } else {
                centre[a]
            };
            centre - size[a] * self.half
        });
        EngineWindow { origin, texel }
    }
}

/// S7 over a path: the largest and the RMS static lookup error, in texels.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct LookupError {
    pub max: f64,
    pub rms: f64,
    pub cascade_max: Vec<f64>,
    pub cascade_rms: Vec<f64>,
}

/// One pass of the emulated f32 pipeline along a path, for one snap setting.
#[derive(Debug, Clone, PartialEq)]
pub struct EmulatedPath {
    /// S1, S3, S4 and coverage of the f32 pipeline, in the same form as the f64 path.
    pub path: PathResult,
    /// S7 (see the module documentation).
    pub lookup: LookupError,
}

/// Walks the path with the binary32 pipeline. Always per probe: in f32 the drift differs from
/// probe to probe, so there is no closed form.
pub fn along_path(
    rig: &Rig,
    poses: &[CameraPose],
    probes: &[Vec<DVec3>],
    space: SnapSpace,
    snapped: bool,
    opts: ShimmerOptions,
) -> EmulatedPath {
    let m = rig.cascade_count();
    let engine: EnginePipeline<f32> = EnginePipeline::new(rig);
    let [row_x, row_y] = engine.rows_f64();
    let n = rig.resolution as f64;
    let probe_xy: Vec<Vec<DVec2>> = probes
        .iter()
        .map(|ps| ps.iter().map(|p| rig.light.to_light_xy(*p)).collect())
        .collect();

    let mut totals = PathTotals::new(snapped, m);
    // Previous frame per cascade: window origin (world-anchored light space, f64), texel size
    // and the probes' texel coordinates (None outside the window).
    type Frame = (DVec2, DVec2, Vec<Option<DVec2>>);
    let mut prev: Vec<Option<Frame>> = vec![None; m];
    let mut err_sq = vec![0.0; m];
    let mut err_max = vec![0.0f64; m];
    let mut err_count = vec![0usize; m];

    for (t, pose) in poses.iter().enumerate() {
        let lp = LightPose::new(&rig.light, pose);
        let anchors = frame_anchors(rig, pose, space);
        for i in 0..m {
            let anchor = anchors[i];
            let anchor_xy = rig.light.to_light_xy(anchor);
            let w = engine.window(i, pose, anchor, snapped);
            let (o, tx) = (w.origin_f64(), w.texel_f64());
            // Coverage of the exact slice by the f32 window, evaluated exactly (f64) from the
            // window's f32 origin and texel size.
            let slice = &rig.slices[i];
            for c in lp.corners(&rig.lens, slice.near, slice.far) {
                totals.corner(i, (c - anchor_xy - o) / tx, n, (c / tx).abs().max_element());
            }
            // The shader's lookups, and S7 against the exact lookup in the same window, for the
            // probes this window serves (None for probes the camera has left behind: an
            // engine looks them up in another cascade, and their distance would only
            // measure how far the camera went).
            let mut s32: Vec<Option<DVec2>> = Vec::with_capacity(probes[i].len());
            let intended = rig.window(i, &lp, snapped);
            for (x, xy) in probes[i].iter().zip(&probe_xy[i]) {
                // Served: the probe lies in the window the engine means to build (the exact
                // one), whatever the f32 window and lookup did with it.
                let se = intended.texel_coords(*xy);
                if !(se.cmpge(DVec2::ZERO).all() && se.cmple(DVec2::splat(n)).all()) {
                    s32.push(None);
                    continue;
                }
                let rel = *x - anchor;
                let exact = (DVec2::new(row_x.dot(rel), row_y.dot(rel)) - o) / tx;
                let s = w.lookup(engine.probe(anchor, *x));
                let s = DVec2::new(s[0] as f64, s[1] as f64);
                let e = (s - exact).abs().max_element();
                err_sq[i] += e * e;
                err_max[i] = err_max[i].max(e);
                err_count[i] += 1;
                s32.push(Some(s));
            }
            // The origin in world-anchored light space, so frames with different anchors
            // compare (f64; the anchor is on the grid, so this only adds a whole number of
            // steps).
            let o_world = o + anchor_xy;
            if let Some((po, ptx, ps)) = &prev[i] {
                let size_change = (tx.x / ptx.x - 1.0).abs().max((tx.y / ptx.y - 1.0).abs());
                totals.size_change(size_change);
                let (mut ss, mut mx_sq, mut flipped, mut served) = (0.0, 0.0f64, 0usize, 0usize);
                let both = s32.iter().zip(ps).filter_map(|(a, b)| a.zip(*b));
                for (s1, s0) in both {
                    served += 1;
                    let d = DVec2::new(wrap(s1.x - s0.x), wrap(s1.y - s0.y));
                    ss += d.length_squared();
                    mx_sq = mx_sq.max(d.length_squared());
                    if opts.cell_flips {
                        // Sampled texel centres and how far they moved, in texels of the
                        // current window.
                        let c0 = *po + (s0.floor() + 0.5) * *ptx;
                        let c1 = o_world + (s1.floor() + 0.5) * tx;
                        let moved = ((c1 - c0) / tx).abs();
                        if moved.x >= 0.5 || moved.y >= 0.5 {
                            flipped += 1;
                        }
                    }
                }
                // Frame pairs in which the cascade serves no probe say nothing about drift.
                if served > 0 {
                    let count = served as f64;
                    let flips = opts.cell_flips.then_some(flipped as f64 / count);
                    totals.drift(t, i, size_change, (ss / count, mx_sq, flips), opts);
                }
            }
            prev[i] = Some((o_world, tx, s32));
        }
    }
    let total: usize = err_count.iter().sum();
    let lookup = LookupError {
        max: err_max.iter().cloned().fold(0.0, f64::max),
        rms: if total > 0 {
            (err_sq.iter().sum::<f64>() / total as f64).sqrt()
        } else {
            0.0
        },
        cascade_rms: err_sq
            .iter()
            .zip(&err_count)
            .map(|(s, &c)| if c > 0 { (s / c as f64).sqrt() } else { 0.0 })
            .collect(),
        cascade_max: err_max,
    };
    EmulatedPath {
        path: totals.finish(opts),
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
pub fn f32_range_problem(rig: &Rig, poses: &[CameraPose], bounds: &Aabb, space: SnapSpace) -> Option<String> {
    let rig = rig.clone();
    let reach = rig
        .slices
        .iter()
        .map(|s| s.sphere.centre_depth + s.sphere.radius)
        .fold(0.0, f64::max);
    let camera = poses.iter().map(|p| p.position.abs().max_element()).fold(0.0, f64::max);
    let scene = bounds.min.abs().max(bounds.max.abs()).max_element();
    let coord = (camera + reach).max(scene);
    let lp0 = LightPose::new(&rig.light, &poses[0]);
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
    let engine: EnginePipeline<f32> = EnginePipeline::new(&rig);
    let smallest = (1.0 / F32_LIMIT) as f32;
    for (t, pose) in poses.iter().enumerate() {
        let anchors = frame_anchors(&rig, pose, space);
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
