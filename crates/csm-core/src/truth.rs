//! Ground truth: the shadow maps sampled the way a GPU samples them, against the exact answer.
//!
//! **The map.** A cascade's depth map holds, at each texel centre, the light depth of the first
//! surface a ray along the light meets there (the point-sampling rasterisation rule; both faces
//! of every triangle cast, no culling). Maps are never rasterised whole: [`ShadowMaps`] traces
//! a texel's ray when a receiver reads it, through the scene's [`LightCover`] in the grid's
//! basis where a cell names the first triangle for certain and through the BVH elsewhere. A
//! texel lies on a grid (cascade, light basis, texel size and the window origin's fraction of a
//! texel) at a whole-texel index. A snapped window moves by whole texels, so its grid stays the
//! same from frame to frame; an unsnapped window's fraction changes each frame, so its grid is
//! new each frame (a grid not read in a frame is dropped). The fraction is rounded to `2^-20`
//! texel for the key and for the texel centres (a shift below a millionth of a texel).
//!
//! **A receiver** `p` (a world-fixed point with unit normal `n` turned toward the light) read
//! by cascade `i`: the normal offset moves it to `p' = p + v`; its texel is the floor of its
//! texel coordinates; it is lit when its light depth `z.p'` is at most the stored depth plus the
//! depth bias and the slope bias times its depth slope. With PCF of width `k` the `k x k`
//! texels around it vote and the map's answer is "lit" when at least half of them pass.
//!
//! **The exact answer** is a ray from `p` toward the light: blocked or not. Its origin is moved
//! off the surface along `n` by [`epsilon`] (a small multiple of the scene's coordinate scale,
//! far above the binary32 BVH's error) so the surface does not hit itself.
//!
//! The formulas (bias model, depth formats, metrics) are stated in `docs/ground-truth.md`.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use std::sync::Arc;

use crate::cascades::{LightPose, Rig};
use crate::fitting::Window;
use crate::geometry::{Aabb, CameraPose, LightBasis};
use crate::light_cover::{Cell, LightCover};
use crate::metrics::cascade_at;
use crate::precision::{frame_anchors, EnginePipeline};
use crate::scene::SnapSpace;
use crate::shade::{FlipImage, Shade, ShadeImage};
use crate::visibility::{SceneGeometry, View, Visibility};

/// The truth ray's origin leaves the surface by this fraction of the scene's coordinate scale.
pub const EPSILON_REL: f64 = 1e-5;

/// The acne a recommended bias leaves: at most this fraction of a cascade's points.
pub const ACNE_ALLOWED: f64 = 0.001;

/// Window-origin fractions are rounded to this many parts of a texel.
const FRACTION_STEPS: f64 = (1u64 << 20) as f64;

/// How far the truth ray's origin leaves the surface: [`EPSILON_REL`] times the largest
/// absolute coordinate of the scene's geometry (at least 1 world unit).
pub fn epsilon(scene: &SceneGeometry) -> f64 {
    let scale = scene
        .mesh
        .bounds()
        .map_or(1.0, |b| b.min.abs().max(b.max.abs()).max_element().max(1.0));
    EPSILON_REL * scale
}

// ---------------------------------------------------------------------------------------------
// Bias model and depth formats
// ---------------------------------------------------------------------------------------------

/// The depth buffer's format: how finely it stores the normalised depth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum DepthFormat {
    D16,
    D24,
    D32F,
}

impl DepthFormat {
    pub const ALL: [DepthFormat; 3] = [DepthFormat::D16, DepthFormat::D24, DepthFormat::D32F];

    pub fn name(self) -> &'static str {
        match self {
            DepthFormat::D16 => "d16",
            DepthFormat::D24 => "d24",
            DepthFormat::D32F => "d32f",
        }
    }

    pub fn from_name(s: &str) -> Option<DepthFormat> {
        Self::ALL.into_iter().find(|f| f.name() == s)
    }

    /// The format's quantisation step over a light depth range of `range` world units:
    /// `range / (2^b - 1)` for the b-bit unorm formats, `range * 2^-24` for binary32 (the
    /// spacing of its values in [0.5, 1), the coarsest in the normalised range).
    pub fn step(self, range: f64) -> f64 {
        match self {
            DepthFormat::D16 => range / 65_535.0,
            DepthFormat::D24 => range / 16_777_215.0,
            DepthFormat::D32F => range * (2.0f64).powi(-24),
        }
    }

    /// `depth` as stored: normalised over `[near, far]` (clamped), rounded to the nearest value
    /// the format holds, and mapped back. A depth with no caster (infinite) stays infinite.
    pub fn quantise(self, depth: f64, near: f64, far: f64) -> f64 {
        let range = far - near;
        if !depth.is_finite() || range <= 0.0 {
            return depth;
        }
        let x = ((depth - near) / range).clamp(0.0, 1.0);
        let q = match self {
            DepthFormat::D16 => (x * 65_535.0).round() / 65_535.0,
            DepthFormat::D24 => (x * 16_777_215.0).round() / 16_777_215.0,
            DepthFormat::D32F => x as f32 as f64,
        };
        near + q * range
    }
}

/// Which way the normal offset moves a receiver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum NormalOffset {
    /// Along the normal, by the full amount.
    Along,
    /// Along the normal scaled by `1 - max(0, n.l)` (`l` toward the light), with the part
    /// along the light removed (Godot's rule).
    Lateral,
}

/// A depth-bias term that depends on the angle `θ` between the receiver's normal and the
/// direction toward the light (`cos θ = n.l`), in world units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Facing {
    /// No such term.
    None,
    /// Adds `k * min(tan θ, cap)`, with `tan θ = sqrt(1 - c²) / c` and `c = |n.l|` (`cap`
    /// when `c` is 0): Unreal's slope term, computed from the normal.
    Tangent { k: f64, cap: f64 },
    /// The depth term becomes `max(depth, k * (1 - n.l))`: the LearnOpenGL-style bias.
    OneMinusCos { k: f64 },
}

impl Facing {
    /// The depth bias of a receiver with `cos θ = c` whose other terms add up to `depth`.
    pub fn apply(self, depth: f64, c: f64) -> f64 {
        match self {
            Facing::None => depth,
            Facing::Tangent { k, cap } => {
                let a = c.abs().min(1.0);
                let tan = if a > 0.0 { (1.0 - a * a).sqrt() / a } else { cap };
                depth + k * tan.clamp(0.0, cap)
            }
            Facing::OneMinusCos { k } => depth.max(k * (1.0 - c)),
        }
    }
}

/// One cascade's bias in world units (the normal offset in texels of that cascade).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Bias {
    /// Added to the stored depth (world units along the light).
    pub depth: f64,
    /// Times the receiver's depth slope per texel (world units), added likewise.
    pub slope: f64,
    /// The receiver moves along its normal by this many texels before the lookup.
    pub normal: f64,
    pub offset: NormalOffset,
    /// A term of the receiver's angle to the light (engine rules only).
    pub facing: Facing,
}

impl Bias {
    pub const ZERO: Bias = Bias {
        depth: 0.0,
        slope: 0.0,
        normal: 0.0,
        offset: NormalOffset::Along,
        facing: Facing::None,
    };

    /// Only a depth bias.
    pub fn depth(b: f64) -> Bias {
        Bias { depth: b, ..Bias::ZERO }
    }
}

/// How an engine states its bias, converted per cascade to world units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum BiasRule {
    /// A depth bias in world units (and a slope factor), the normal offset in texels.
    World {
        depth: f64,
        slope: f64,
        normal_texels: f64,
        offset: NormalOffset,
    },
    /// A depth bias as a fraction of the cascade's light depth range.
    RangeFraction {
        fraction: f64,
        normal_texels: f64,
        offset: NormalOffset,
    },
    /// A depth bias in texels of the cascade (world size = value x texel size).
    Texels { depth_texels: f64, normal_texels: f64 },
    /// A depth bias in texels of the cascade plus `tangent_texels` texels times the tangent of
    /// the receiver's angle to the light, the tangent capped at `cap` (Unreal's rule).
    TexelsTangent {
        depth_texels: f64,
        tangent_texels: f64,
        cap: f64,
    },
    /// `max(factor * (1 - n.l), floor)` in fractions of the cascade's light depth range (the
    /// LearnOpenGL-style bias in normalised depth).
    RangeFacing { factor: f64, floor: f64 },
}

impl BiasRule {
    /// The bias of a cascade with texel size `texel` and light depth range `range`.
    pub fn for_cascade(&self, texel: f64, range: f64) -> Bias {
        match *self {
            BiasRule::World {
                depth,
                slope,
                normal_texels,
                offset,
            } => Bias {
                depth,
                slope,
                normal: normal_texels,
                offset,
                facing: Facing::None,
            },
            BiasRule::RangeFraction {
                fraction,
                normal_texels,
                offset,
            } => Bias {
                depth: fraction * range,
                slope: 0.0,
                normal: normal_texels,
                offset,
                facing: Facing::None,
            },
            BiasRule::Texels {
                depth_texels,
                normal_texels,
            } => Bias {
                depth: depth_texels * texel,
                slope: 0.0,
                normal: normal_texels,
                offset: NormalOffset::Along,
                facing: Facing::None,
            },
            BiasRule::TexelsTangent {
                depth_texels,
                tangent_texels,
                cap,
            } => Bias {
                depth: depth_texels * texel,
                facing: Facing::Tangent {
                    k: tangent_texels * texel,
                    cap,
                },
                ..Bias::ZERO
            },
            BiasRule::RangeFacing { factor, floor } => Bias {
                depth: floor * range,
                facing: Facing::OneMinusCos { k: factor * range },
                ..Bias::ZERO
            },
        }
    }

    /// A world-unit depth bias expressed the way this rule states it (the inverse of
    /// [`BiasRule::for_cascade`]'s depth term).
    pub fn depth_in_own_units(&self, world: f64, texel: f64, range: f64) -> f64 {
        match self {
            BiasRule::World { .. } => world,
            BiasRule::RangeFraction { .. } | BiasRule::RangeFacing { .. } => {
                if range > 0.0 {
                    world / range
                } else {
                    0.0
                }
            }
            BiasRule::Texels { .. } | BiasRule::TexelsTangent { .. } => {
                if texel > 0.0 {
                    world / texel
                } else {
                    0.0
                }
            }
        }
    }
}

/// How one PCF tap filters the depth comparisons.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum PcfFilter {
    /// The texel under the tap (a comparison sampler with nearest filtering).
    Nearest,
    /// The 2x2 texels around the tap, their compare results weighted bilinearly (a comparison
    /// sampler with linear filtering: `GL_LINEAR` on a depth texture with compare mode,
    /// `SampleCmp` with a linear comparison filter).
    Bilinear,
}

impl PcfFilter {
    pub const ALL: [PcfFilter; 2] = [PcfFilter::Nearest, PcfFilter::Bilinear];

    pub fn name(self) -> &'static str {
        match self {
            PcfFilter::Nearest => "nearest",
            PcfFilter::Bilinear => "bilinear",
        }
    }

    pub fn from_name(s: &str) -> Option<PcfFilter> {
        Self::ALL.into_iter().find(|f| f.name() == s)
    }
}

/// How the maps are sampled: per-cascade bias, depth format, PCF width (1, 3 or 5), the
/// filter of each tap, and the arithmetic of the light matrix and the depths.
#[derive(Debug, Clone)]
pub struct Sampling {
    pub bias: Vec<Bias>,
    /// None: exact f64 depths (no quantisation).
    pub format: Option<DepthFormat>,
    /// Light depth range of each cascade over which depths are quantised (frame 0's; the
    /// binary32 pipeline uses each frame's own range instead).
    pub ranges: Vec<(f64, f64)>,
    pub pcf: u32,
    pub filter: PcfFilter,
    /// None: the light matrix, lookups and depths in f64, windows exact (csm-lab's
    /// reference). Some: an engine's binary32 pipeline, rebuilt every frame (see
    /// [`Binary32`]).
    pub binary32: Option<Binary32>,
}

/// The binary32 (`f32`) pipeline of an engine, for the ground truth: every frame, each
/// cascade's light matrix and window are rebuilt in f32 the way [`EnginePipeline`] builds
/// them (rows stored in f32, window centre, snapping and origin in f32, in the rig's snap
/// space), the depth row and offset normalise light depth over that frame's light depth
/// range (fitted to `bounds` by the rig's rule) and are stored in f32, and every texel's
/// stored depth and every receiver's lookup and depth are computed in f32 through that
/// matrix. A snapped window then lands a fraction of an ulp off its grid, differently every
/// frame, and stored depths move by a few ulps: what a GPU's snapped map does.
#[derive(Debug, Clone)]
pub struct Binary32 {
    engine: Arc<EnginePipeline<f32>>,
    space: SnapSpace,
    bounds: Aabb,
}

impl Binary32 {
    /// The pipeline of `rig` in snap space `space`; `bounds` are the scene bounds the light
    /// depth range is fitted to (as in the f64 pass's ranges).
    pub fn new(rig: &Rig, space: SnapSpace, bounds: Aabb) -> Self {
        Binary32 {
            engine: Arc::new(EnginePipeline::new(rig)),
            space,
            bounds,
        }
    }
}

/// One cascade's light matrix in one frame of the binary32 pipeline, as the engine stores it
/// (every entry an f32), relative to the frame's anchor (the world origin, or the camera
/// moved onto the snap grid with `snap_space = "camera_relative"`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameMatrix {
    anchor: DVec3,
    /// Light x and y rows.
    rows: [[f32; 3]; 2],
    /// The window's minimum corner (light-space x/y relative to the anchor) and texel size.
    origin: [f32; 2],
    texel: [f32; 2],
    /// Normalised depth `x = depth_row . X + depth_offset` (light z over the range).
    depth_row: [f32; 3],
    depth_offset: f32,
    /// `1 / (far - near)`, for the bias in normalised units.
    inv_range: f32,
}

impl FrameMatrix {
    fn point(&self, x: DVec3) -> [f32; 3] {
        let r = x - self.anchor;
        [r.x as f32, r.y as f32, r.z as f32]
    }

    /// The normalised depth of a world point, in f32 (the point stored in f32 first).
    fn depth(&self, x: DVec3) -> f32 {
        let p = self.point(x);
        let d = &self.depth_row;
        d[0] * p[0] + d[1] * p[1] + d[2] * p[2] + self.depth_offset
    }

    /// The shader's texel coordinates `(M x - o) / T` of a world point, in f32.
    fn lookup(&self, x: DVec3) -> [f32; 2] {
        let p = self.point(x);
        std::array::from_fn(|a| {
            let r = &self.rows[a];
            (r[0] * p[0] + r[1] * p[1] + r[2] * p[2] - self.origin[a]) / self.texel[a]
        })
    }
}

/// A normalised depth stored in `format` (None: as computed), in f32: clamped to [0, 1], then
/// rounded to the unorm formats' steps. No caster stays infinite.
fn store32(x: f32, format: Option<DepthFormat>) -> f32 {
    if !x.is_finite() {
        return x;
    }
    let x = x.clamp(0.0, 1.0);
    match format {
        None | Some(DepthFormat::D32F) => x,
        Some(DepthFormat::D16) => ((x as f64 * 65_535.0).round() / 65_535.0) as f32,
        Some(DepthFormat::D24) => ((x as f64 * 16_777_215.0).round() / 16_777_215.0) as f32,
    }
}

// ---------------------------------------------------------------------------------------------
// Receivers and the exact answer
// ---------------------------------------------------------------------------------------------

/// A world-fixed receiver point: a lit-facing pixel of frame 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Receiver {
    /// Row-major index of its pixel in the visibility pass's grid.
    pub pixel: usize,
    pub p: DVec3,
    /// Unit normal, turned toward the light.
    pub n: DVec3,
    pub triangle: usize,
}

/// The receivers of a visibility pass: every lit-facing sample, with its surface's normal.
pub fn receivers(scene: &SceneGeometry, vis: &Visibility) -> Vec<Receiver> {
    let view = &vis.view;
    let light = view.light.normalize();
    vis.samples
        .par_iter()
        .enumerate()
        .filter_map(|(k, s)| {
            let s = s.filter(|s| s.lit)?;
            let cols = vis.cols as usize;
            let (u, v) = view.pixel_centre((k % cols) as u32, (k / cols) as u32);
            let d = view.ray(u, v);
            let len = d.length();
            let hit = scene.first_hit(
                view.pose.position,
                d / len,
                view.near * len * 0.999,
                view.far * len * 1.001,
            )?;
            let mut n = scene.triangle_normal(hit.triangle);
            if n.dot(-light) < 0.0 {
                n = -n;
            }
            Some(Receiver {
                pixel: k,
                p: vis.position(k, s.depth),
                n,
                triangle: hit.triangle,
            })
        })
        .collect()
}

/// What the ground truth reads of a view pass besides the maps, the same for every setting
/// that shares the pass and the light: the receivers ([`receivers`]) and each one's exact
/// answer ([`occluder`]). A sweep's rows share it ([`exact_of`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Exact {
    pub view: View,
    /// The unit direction light travels.
    pub light: DVec3,
    pub points: Vec<Receiver>,
    pub occluders: Vec<Option<f64>>,
}

/// [`Exact`] of pass `vis` under unit light direction `light`: made on first use and kept by
/// the scene (the latest few views and lights), so every setting of a sweep reads the same
/// receivers and exact answers without casting them again.
pub fn exact_of(scene: &SceneGeometry, vis: &Visibility, light: DVec3) -> Arc<Exact> {
    let bits = |v: DVec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let same = |e: &Exact| e.view == vis.view && bits(e.light) == bits(light);
    scene.derived(same, || {
        let points = receivers(scene, vis);
        let occluders = occluders(scene, light, &points);
        Exact {
            view: vis.view,
            light,
            points,
            occluders,
        }
    })
}

/// Every receiver's [`occluder`] along unit light direction `light`.
pub fn occluders(scene: &SceneGeometry, light: DVec3, points: &[Receiver]) -> Vec<Option<f64>> {
    let eps = epsilon(scene);
    let bounds = scene.mesh.bounds();
    points
        .par_iter()
        .map(|r| occluder_in(scene, bounds, light, r, eps))
        .collect()
}

/// The exact answer at `r`: None when the ray toward the light is free (truly lit), else the
/// distance along the light to the surface that blocks it. `light` is the unit direction light
/// travels; `eps` from [`epsilon`].
pub fn occluder(scene: &SceneGeometry, light: DVec3, r: &Receiver, eps: f64) -> Option<f64> {
    occluder_in(scene, scene.mesh.bounds(), light, r, eps)
}

/// [`occluder`] with the scene's bounds computed once by the caller.
fn occluder_in(scene: &SceneGeometry, bounds: Option<Aabb>, light: DVec3, r: &Receiver, eps: f64) -> Option<f64> {
    let origin = r.p + r.n * eps;
    // Every triangle is within the bounds' diagonal of any point inside them.
    let reach = bounds.map_or(0.0, |b| {
        (b.max - b.min).length() + (origin - b.min).length() + (origin - b.max).length()
    });
    scene.first_hit(origin, -light, 0.0, reach).map(|h| h.t)
}

// ---------------------------------------------------------------------------------------------
// The lazily sampled maps
// ---------------------------------------------------------------------------------------------

/// A multiplicative hasher for the integer keys of the texel cache (std's SipHash costs more
/// than the lookups it guards).
#[derive(Default)]
struct MulHasher(u64);

impl Hasher for MulHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(*b as u64);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
    fn write_u32(&mut self, x: u32) {
        self.write_u64(x as u64);
    }
    fn write_usize(&mut self, x: usize) {
        self.write_u64(x as u64);
    }
}

type Fast<K, V> = HashMap<K, V, BuildHasherDefault<MulHasher>>;

/// What a texel holds: the light depth of its first caster (infinite when none) and which
/// triangle that is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stored {
    pub depth: f64,
    pub triangle: Option<usize>,
}

/// A grid of texels: everything but the whole-texel index that fixes where a texel is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct GridKey {
    cascade: u32,
    basis: [u64; 6],
    texel: [u64; 2],
    fraction: [i64; 2],
}

/// A family of grids: one cascade's grids in one basis with one texel size (they differ only
/// by the window origin's fraction). A receiver's placement before the fraction is the same
/// on each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct FamilyKey {
    cascade: u32,
    basis: [u64; 6],
    texel: [u64; 2],
}

struct Grid {
    basis: LightBasis,
    texel: DVec2,
    /// The window origin's fraction of a texel (rounded, see the module docs).
    fraction: DVec2,
    /// Light depth where texel rays start, and how far they go.
    start: f64,
    length: f64,
    /// The scene's light-space cover in this basis, when one is made (see [`ShadowMaps`]).
    cover: Option<Arc<LightCover>>,
    family: u32,
    /// The texels read so far (for the counts; a cache would hold their rays).
    seen: Fast<(i64, i64), ()>,
    used: bool,
}

impl Grid {
    /// Light-space x/y of texel `g`'s centre.
    fn centre(&self, g: (i64, i64)) -> DVec2 {
        (DVec2::new(g.0 as f64, g.1 as f64) + self.fraction + DVec2::splat(0.5)) * self.texel
    }
}

/// Counts of the texel cache.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct CacheStats {
    /// Texel reads by receivers (a receiver whose texel did not change reads it again).
    pub reads: u64,
    /// Texels read for the first time on their grid: the rays a cache that keeps every texel
    /// of a live grid casts (most are answered by the light-space cover without a ray).
    pub rays: u64,
}

impl CacheStats {
    /// Share of texel reads served without a ray.
    pub fn hit_rate(&self) -> f64 {
        if self.reads == 0 {
            0.0
        } else {
            1.0 - self.rays as f64 / self.reads as f64
        }
    }

    pub fn add(&mut self, o: CacheStats) {
        self.reads += o.reads;
        self.rays += o.rays;
    }
}

/// The cascades' depth maps, sampled on demand: a texel's content is the first hit of its ray,
/// found through the scene's [`LightCover`] in the grid's basis where that cell is certain and
/// by the BVH elsewhere. A basis gets a cover when it is met in a second frame (or already has
/// one): a basis that turns every frame keeps to the BVH.
pub struct ShadowMaps<'a> {
    scene: &'a SceneGeometry,
    grids: Vec<Option<Grid>>,
    index: Fast<GridKey, usize>,
    families: Fast<FamilyKey, u32>,
    /// Per family, the texels its last dropped grid had read (the next one's set is made that
    /// large up front).
    family_reads: Vec<usize>,
    /// Bases met in earlier frames, and in this one.
    bases: Vec<LightBasis>,
    frame_bases: Vec<LightBasis>,
    count: bool,
    /// The scene's bounds (texel rays start before them).
    bounds: Option<Aabb>,
    pub stats: CacheStats,
}

/// Cascade `i`'s grid in one frame: its id in [`ShadowMaps`] and the window's whole-texel
/// origin on that grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameGrid {
    pub id: usize,
    /// The window's first texel (whole-texel index of its minimum corner).
    pub first: (i64, i64),
    pub resolution: u32,
    /// The frame's binary32 light matrix (None: the f64 pipeline).
    pub matrix: Option<FrameMatrix>,
}

impl<'a> ShadowMaps<'a> {
    /// Maps that count their reads and rays ([`ShadowMaps::stats`]).
    pub fn new(scene: &'a SceneGeometry) -> Self {
        ShadowMaps {
            scene,
            grids: Vec::new(),
            index: Fast::default(),
            families: Fast::default(),
            family_reads: Vec::new(),
            bases: Vec::new(),
            frame_bases: Vec::new(),
            count: true,
            bounds: scene.mesh.bounds(),
            stats: CacheStats::default(),
        }
    }

    /// The same, counting reads and rays only when `count` is set (counting the rays keeps a
    /// set of the texels read per grid).
    pub fn counting(mut self, count: bool) -> Self {
        self.count = count;
        self
    }

    /// The grid of cascade `cascade`'s window `w` in basis `basis` (made on first use).
    pub fn grid(&mut self, cascade: usize, basis: &LightBasis, w: &Window) -> FrameGrid {
        let origin = w.origin_texels;
        let whole = origin.floor();
        let fraction = ((origin - whole) * FRACTION_STEPS).round();
        // A fraction that rounds up to a whole texel belongs to the next whole index.
        let carry = fraction.cmpge(DVec2::splat(FRACTION_STEPS));
        let fraction = DVec2::select(carry, fraction - FRACTION_STEPS, fraction);
        let whole = DVec2::select(carry, whole + 1.0, whole);
        let bits = |v: DVec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        let (bx, by) = (bits(basis.x), bits(basis.y));
        let key = GridKey {
            cascade: cascade as u32,
            basis: [bx[0], bx[1], bx[2], by[0], by[1], by[2]],
            texel: [w.texel.x.to_bits(), w.texel.y.to_bits()],
            fraction: [fraction.x as i64, fraction.y as i64],
        };
        if !self.frame_bases.contains(basis) {
            self.frame_bases.push(*basis);
        }
        let id = match self.index.get(&key) {
            Some(&id) => id,
            None => {
                let (start, length) = self.ray_span(basis);
                let cover = self.scene.light_cover(basis, self.bases.contains(basis));
                let next = self.families.len() as u32;
                let family = *self
                    .families
                    .entry(FamilyKey {
                        cascade: key.cascade,
                        basis: key.basis,
                        texel: key.texel,
                    })
                    .or_insert(next);
                if family as usize == self.family_reads.len() {
                    self.family_reads.push(0);
                }
                let reads = if self.count {
                    self.family_reads[family as usize]
                } else {
                    0
                };
                self.grids.push(Some(Grid {
                    basis: *basis,
                    texel: w.texel,
                    fraction: fraction / FRACTION_STEPS,
                    start,
                    length,
                    cover,
                    family,
                    seen: Fast::with_capacity_and_hasher(reads, Default::default()),
                    used: false,
                }));
                let id = self.grids.len() - 1;
                self.index.insert(key, id);
                id
            }
        };
        let eligible = self.bases.contains(basis);
        if let Some(g) = self.grids[id].as_mut() {
            g.used = true;
            if g.cover.is_none() && eligible {
                g.cover = self.scene.light_cover(basis, true);
            }
        }
        FrameGrid {
            id,
            first: (whole.x as i64, whole.y as i64),
            resolution: w.resolution,
            matrix: None,
        }
    }

    /// Light depth where texel rays start (before every triangle) and their length.
    fn ray_span(&self, basis: &LightBasis) -> (f64, f64) {
        let Some(b) = self.bounds else {
            return (0.0, 0.0);
        };
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for c in 0..8 {
            let z = basis.z.dot(b.corner(c));
            lo = lo.min(z);
            hi = hi.max(z);
        }
        let margin = 0.01 * (hi - lo) + 1.0;
        (lo - margin, hi - lo + 2.0 * margin)
    }

    /// Drops the grids no frame read since the last call (an unsnapped window's grid of the
    /// previous frame) and starts a new frame.
    pub fn end_frame(&mut self) {
        for slot in self.grids.iter_mut() {
            if let Some(g) = slot {
                if !g.used {
                    self.family_reads[g.family as usize] = g.seen.len();
                    *slot = None;
                } else {
                    g.used = false;
                }
            }
        }
        let grids = &self.grids;
        self.index.retain(|_, id| grids[*id].is_some());
        self.next_frame();
    }

    /// Starts a new frame without dropping any grid: the light bases met in this frame become
    /// those met in an earlier one (a basis met in a second frame gets a cover). The walk
    /// takes a block of frames' grids this way, then [`ShadowMaps::end_frame`] drops the grids
    /// no frame of the block read.
    fn next_frame(&mut self) {
        for b in self.frame_bases.drain(..) {
            if !self.bases.contains(&b) {
                self.bases.push(b);
            }
        }
    }

    /// Counts the texels in `wanted` that no receiver read before on their grid as rays (what
    /// a cache that casts each texel once would cast). Texels themselves are traced when read.
    pub fn fetch(&mut self, wanted: Vec<(usize, (i64, i64))>) {
        if !self.count {
            return;
        }
        for (id, g) in wanted {
            if let Some(grid) = self.grids[id].as_mut() {
                if grid.seen.insert(g, ()).is_none() {
                    self.stats.rays += 1;
                }
            }
        }
    }

    /// What texel `g` of grid `id` holds (its ray traced now); None for a grid dropped.
    pub fn stored(&self, id: usize, g: (i64, i64)) -> Option<Stored> {
        Some(trace_texel(self.scene, self.grids[id].as_ref()?, g))
    }

    pub fn basis(&self, id: usize) -> LightBasis {
        self.grids[id]
            .as_ref()
            .map_or(LightBasis::new(DVec3::NEG_Y), |g| g.basis)
    }

    pub fn texel(&self, id: usize) -> DVec2 {
        self.grids[id].as_ref().map_or(DVec2::ONE, |g| g.texel)
    }

    /// Where receiver `r` reads grid `id` under `bias`: its texel (of the offset point), its
    /// light depth and the depth bias it gets (depth plus slope term).
    pub fn place(&self, id: usize, r: &Receiver, bias: &Bias) -> Placement {
        let grid = self.grids[id].as_ref().expect("a grid of this frame");
        place(grid.basis, grid.texel, grid.fraction, r, bias)
    }

    /// Where receiver `r` reads a frame's grid: [`ShadowMaps::place`] in f64, or with the
    /// frame's binary32 matrix the shader's f32 lookup and depth (see [`place32`]).
    pub fn place_in(&self, fg: &FrameGrid, r: &Receiver, bias: &Bias) -> Placement {
        match &fg.matrix {
            None => self.place(fg.id, r, bias),
            Some(m) => {
                let grid = self.grids[fg.id].as_ref().expect("a grid of this frame");
                place32(grid.basis, grid.texel, m, fg.first, r, bias)
            }
        }
    }

    /// [`ShadowMaps::place_in`] reusing `memo`, the receiver's placement before the fraction
    /// on the last f64 grid family it was placed on (filled or replaced here), with the plane
    /// every texel its lookup can read on that family holds, when the grid's cover names one
    /// ([`PlaneLookup`]; looked for once per family, from the first grid with a cover).
    #[inline(always)]
    fn place_memo<'s, 'm>(
        &'s self,
        fg: &FrameGrid,
        r: &Receiver,
        s: &Sampling,
        cascade: usize,
        memo: &'m mut Option<Memo>,
    ) -> (Placement, Option<&'m PlaneLookup>, &'s Grid) {
        let grid = self.grids[fg.id].as_ref().expect("a grid of this frame");
        let bias = &s.bias[cascade];
        if fg.matrix.is_some() {
            return (self.place_in(fg, r, bias), None, grid);
        }
        if memo.as_ref().is_some_and(|m| m.family != grid.family) {
            *memo = None;
        }
        let m = memo.get_or_insert_with(|| Memo {
            family: grid.family,
            u: unplaced(grid.basis, grid.texel, r, bias),
            plane: Lookup::Untried,
        });
        if let (Lookup::Untried, Some(cover)) = (m.plane, &grid.cover) {
            m.plane =
                PlaneLookup::of(self.scene, cover, grid, r, &m.u, s, cascade).map_or(Lookup::Traced, Lookup::Plane);
        }
        let placement = m.u.on(grid.fraction);
        let plane = match &m.plane {
            Lookup::Plane(p) => Some(p),
            _ => None,
        };
        (placement, plane, grid)
    }

    /// The world point a held texel's depth stands for: the hit of its ray.
    fn hit_point(&self, id: usize, g: (i64, i64), depth: f64) -> DVec3 {
        let grid = self.grids[id].as_ref().expect("a grid of this frame");
        let c = grid.centre(g);
        grid.basis.x * c.x + grid.basis.y * c.y + grid.basis.z * depth
    }
}

/// The ray of texel `g`: from its centre, before every triangle, along the light. Its first
/// hit is the triangle the cover names for the cell, or where the cover is not certain the
/// one the BVH names (found by testing the cell's candidates as the BVH does,
/// [`LightCover::nearest`], or by the BVH itself); the distance is computed as the BVH's hit
/// computes it.
fn trace_texel(scene: &SceneGeometry, grid: &Grid, g: (i64, i64)) -> Stored {
    let c = grid.centre(g);
    let b = &grid.basis;
    let origin = b.x * c.x + b.y * c.y + b.z * grid.start;
    let on = |cover: &LightCover, t: usize| crate::visibility::TriangleHit {
        t: cover.hit_distance(&scene.mesh, t, origin, b.z, 0.0),
        triangle: t,
    };
    let hit = match grid.cover.as_deref().map(|cover| (cover, cover.at(c))) {
        Some((_, Cell::Miss)) => None,
        Some((cover, Cell::Owner(t))) => Some(on(cover, t)),
        Some((cover, Cell::Unknown)) => match cover.nearest(c, origin, b.z, 0.0, grid.length) {
            Some(t) => t.map(|t| on(cover, t)),
            None => scene.first_hit(origin, b.z, 0.0, grid.length),
        },
        None => scene.first_hit(origin, b.z, 0.0, grid.length),
    };
    match hit {
        Some(h) => Stored {
            depth: grid.start + h.t,
            triangle: Some(h.triangle),
        },
        None => Stored {
            depth: f64::INFINITY,
            triangle: None,
        },
    }
}

/// Where a receiver reads a grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// The (offset) receiver in texel units of the grid: texel `(i, j)` covers
    /// `[i, i + 1) x [j, j + 1)`, its centre at `(i + 0.5, j + 0.5)`.
    pub at: DVec2,
    pub texel: (i64, i64),
    /// Light depth of the (offset) receiver.
    pub depth: f64,
    /// Its depth slope per texel: `max(|dz/dx| Tx, |dz/dy| Ty)` (world units).
    pub slope: f64,
    /// Depth bias plus slope bias times the slope.
    pub bias: f64,
}

/// `x.floor()`, to the bit, without a call into the maths library (the baseline x86-64 target
/// has no rounding instruction): below 2^52 in magnitude through an integer, above it `x` is
/// whole already; zero, infinities and NaN come back as they are.
#[inline]
fn floor(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 && x != 0.0 {
        let t = x as i64 as f64;
        if t > x {
            t - 1.0
        } else {
            t
        }
    } else {
        x
    }
}

/// `floor(x) as i64`, to the bit, with one conversion to an integer instead of two.
#[inline]
fn floor_i64(x: f64) -> i64 {
    if x.abs() < 4_503_599_627_370_496.0 && x != 0.0 {
        let t = x as i64;
        if t as f64 > x {
            t - 1
        } else {
            t
        }
    } else {
        x as i64
    }
}

/// Largest depth slope per texel kept (a surface edge-on to the light).
const MAX_SLOPE_TEXELS: f64 = 1e6;

/// The receiver moved by its normal offset.
fn offset_point(basis: LightBasis, texel: DVec2, r: &Receiver, bias: &Bias) -> DVec3 {
    let t = texel.x.max(texel.y);
    let mut v = r.n * (bias.normal * t);
    if bias.offset == NormalOffset::Lateral {
        v *= 1.0 - r.n.dot(-basis.z).max(0.0);
        v -= basis.z * v.dot(basis.z);
    }
    r.p + v
}

/// The receiver's depth slope per texel (world units), see [`Placement::slope`].
fn depth_slope(basis: LightBasis, texel: DVec2, r: &Receiver) -> f64 {
    let t = texel.x.max(texel.y);
    let nz = r.n.dot(basis.z);
    if nz.abs() > 0.0 {
        ((r.n.dot(basis.x) / nz).abs() * texel.x)
            .max((r.n.dot(basis.y) / nz).abs() * texel.y)
            .min(MAX_SLOPE_TEXELS * t)
    } else {
        MAX_SLOPE_TEXELS * t
    }
}

fn place(basis: LightBasis, texel: DVec2, fraction: DVec2, r: &Receiver, bias: &Bias) -> Placement {
    unplaced(basis, texel, r, bias).on(fraction)
}

/// A receiver's placement on a grid family before the window origin's fraction: its (offset)
/// light x/y in texels, light depth, depth slope and bias.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Unplaced {
    q: DVec2,
    depth: f64,
    slope: f64,
    bias: f64,
}

fn unplaced(basis: LightBasis, texel: DVec2, r: &Receiver, bias: &Bias) -> Unplaced {
    let p = offset_point(basis, texel, r, bias);
    let q = DVec2::new(basis.x.dot(p), basis.y.dot(p));
    let slope = depth_slope(basis, texel, r);
    Unplaced {
        q: q / texel,
        depth: basis.z.dot(p),
        slope,
        bias: bias.facing.apply(bias.depth + bias.slope * slope, r.n.dot(-basis.z)),
    }
}

impl Unplaced {
    /// The placement on the grid whose window origin has this fraction of a texel.
    #[inline]
    fn on(self, fraction: DVec2) -> Placement {
        let s = self.q - fraction;
        Placement {
            at: s,
            texel: (floor_i64(s.x), floor_i64(s.y)),
            depth: self.depth,
            slope: self.slope,
            bias: self.bias,
        }
    }
}

/// A receiver's work kept from frame to frame on one grid family (the walk's memo).
#[derive(Debug, Clone, Copy)]
struct Memo {
    family: u32,
    u: Unplaced,
    plane: Lookup,
}

/// Whether a receiver's lookups on a grid family read one plane.
#[derive(Debug, Clone, Copy)]
enum Lookup {
    /// Not looked for yet (no grid of the family had a cover).
    Untried,
    /// No single plane: its texels are traced.
    Traced,
    Plane(PlaneLookup),
}

/// The rounding margin of the plane's depths, relative to the magnitudes they come from
/// (`2^-36`; the rounding of the hit distance and of the plane's depth is below `2^-45` of
/// them, see [`PlaneLookup`]).
const PLANE_TOL_REL: f64 = 1.0 / (1u64 << 36) as f64;

/// A receiver on a grid family whose lookup can only read texels holding one triangle's plane:
/// the cover owns every cell within `k / 2 + 1` texels of its (offset) light-space x/y with
/// that triangle (`k` the PCF width; a tap's 2x2 texel centres lie within one texel of it, the
/// taps within `k / 2` of the lookup), so every texel ray it reads, on any grid of the family,
/// meets that triangle first, and its depth is the plane's depth at the texel centre
/// ([`crate::light_cover::LightPlane`]) up to rounding. Both compares (biased and unbiased) read
/// the depth as the format stores it, so each is decided from the plane's depth when it clears
/// its threshold by more than that rounding (`tol`) plus the format's step (`tol_lit`,
/// `tol_unbiased`); else the texels are traced ([`answer_at`]). Either way the answer is
/// [`answer_at`]'s to the bit.
///
/// The rounding: the texel's stored depth `start + n.(a - o) / n.z` (`o` the ray's origin
/// `x c.x + y c.y + z start`) and the plane's `k - gx c.x - gy c.y` are both within
/// `2^-45 (1 + cond) (|a| + 2 |c| + |start| + length)` of the exact value (a handful of
/// roundings of those magnitudes, grown by `cond = |n| / |n.z|` in the division);
/// `tol` is `2^-36` times that sum.
#[derive(Debug, Clone, Copy)]
struct PlaneLookup {
    k: f64,
    gx: f64,
    gy: f64,
    /// The receiver's own light depth (the unbiased compare's).
    own_depth: f64,
    own_only: bool,
    tol: f64,
    tol_lit: f64,
    tol_unbiased: f64,
    /// Whether the biased compare passes (Some(true)) or fails (Some(false)) at every texel any
    /// lookup of the family reads, clearing its margin, with the depth inside the format's
    /// range ([`PlaneLookup::fixed_answer`]): [`PlaneLookup::answer`] then computes only the
    /// unbiased compares.
    lit_fixed: Option<bool>,
    /// The answer on every grid of the family, when the unbiased compare is fixed too: the
    /// walk then reads no texel.
    fixed: Option<Answer>,
}

impl PlaneLookup {
    /// The plane receiver `r` (placed before the fraction at `u`) reads on `grid`'s family, if
    /// the cover names one for its whole reach.
    fn of(
        scene: &SceneGeometry,
        cover: &LightCover,
        grid: &Grid,
        r: &Receiver,
        u: &Unplaced,
        s: &Sampling,
        cascade: usize,
    ) -> Option<PlaneLookup> {
        let reach = f64::from(s.pcf / 2 + 1);
        let centre = u.q * grid.texel;
        let half = grid.texel * reach;
        let c = centre.abs().max_element() + half.max_element();
        // Grown a little past the rounding of the texel centres and of the cover's cell index.
        let grow = DVec2::splat(PLANE_TOL_REL * (1.0 + c)) + half * 1e-9;
        let t = cover.region_owner(centre - half - grow, centre + half + grow)?;
        let p = cover.plane(&scene.mesh, t)?;
        let mag = p.reach + 2.0 * c + grid.start.abs() + grid.length;
        let tol = PLANE_TOL_REL * (1.0 + p.cond) * mag;
        let quantised = s.format.map_or(0.0, |f| {
            let (near, far) = s.ranges[cascade];
            f.step(far - near) + PLANE_TOL_REL * (near.abs() + far.abs())
        });
        let tol_lit = tol + quantised + PLANE_TOL_REL * (u.depth.abs() + u.bias.abs() + mag);
        let own_depth = grid.basis.z.dot(r.p);
        let tol_unbiased = tol + quantised + PLANE_TOL_REL * (own_depth.abs() + mag);
        let all = [p.k, p.gx, p.gy, tol, tol_lit, tol_unbiased];
        if !all.iter().all(|x| x.is_finite()) {
            return None;
        }
        let mut out = PlaneLookup {
            k: p.k,
            gx: p.gx,
            gy: p.gy,
            own_depth,
            own_only: same_plane(scene, t, r),
            tol,
            tol_lit,
            tol_unbiased,
            lit_fixed: None,
            fixed: None,
        };
        (out.lit_fixed, out.fixed) = out.fixed_answer(centre, half + grow, u, s.format.map(|_| s.ranges[cascade]));
        Some(out)
    }

    /// [`PlaneLookup::answer`]'s answer at every placement of the family, when it is the same
    /// at all of them: the texel centres any lookup of the family reads lie in the rectangle
    /// `centre ± half` ([`PlaneLookup::of`]'s, grown past the rounding of the centres), over
    /// which the plane's depth `k − g_x c_x − g_y c_y` lies in `[d₀ − e, d₀ + e]`
    /// (`d₀` at the centre, `e = |g_x| half_x + |g_y| half_y`). When the biased compare
    /// (`depth − (d + bias)`) and the unbiased one (`own_depth − d`) clear their margins
    /// (`tol_lit`, `tol_unbiased`) with one sign over that whole interval, and the depth stays
    /// `tol` inside the format's range, every compare of every lookup of the family is decided
    /// from the plane with that sign: all texels pass (a weighted share of about 1, at least
    /// ½) or none does (0). `slack` (`2⁻⁴⁰` times the magnitudes involved) covers the
    /// rounding of the interval's ends and of each per-texel compare (a few ulps, below
    /// `2⁻⁵⁰` of them). Returns the biased compare's fixed result (None: it depends on the
    /// placement) and, when the unbiased one is fixed too, the answer.
    fn fixed_answer(
        &self,
        centre: DVec2,
        half: DVec2,
        u: &Unplaced,
        range: Option<(f64, f64)>,
    ) -> (Option<bool>, Option<Answer>) {
        let d0 = self.k - self.gx * centre.x - self.gy * centre.y;
        let spread = self.gx.abs() * half.x + self.gy.abs() * half.y;
        let (lo, hi) = (d0 - spread, d0 + spread);
        let c = centre.abs().max_element() + half.max_element();
        let mut mag =
            self.k.abs() + (self.gx.abs() + self.gy.abs()) * c + u.depth.abs() + u.bias.abs() + self.own_depth.abs();
        if let Some((near, far)) = range {
            mag += near.abs() + far.abs();
        }
        let slack = mag / (1u64 << 40) as f64;
        if !([lo, hi, slack].iter().all(|x| x.is_finite())) {
            return (None, None);
        }
        if let Some((near, far)) = range {
            if !(lo - slack >= near + self.tol + slack && hi + slack <= far - self.tol - slack) {
                return (None, None);
            }
        }
        // Biased: the largest and least of depth − (d + bias) over the interval.
        let (b_hi, b_lo) = (u.depth - (lo + u.bias), u.depth - (hi + u.bias));
        let lit = if b_hi < -(self.tol_lit + slack) {
            true
        } else if b_lo > self.tol_lit + slack {
            false
        } else {
            return (None, None);
        };
        let (n_hi, n_lo) = (self.own_depth - lo, self.own_depth - hi);
        let lit_unbiased = if n_hi < -(self.tol_unbiased + slack) {
            true
        } else if n_lo > self.tol_unbiased + slack {
            false
        } else {
            return (Some(lit), None);
        };
        let answer = Answer {
            lit,
            own_only: self.own_only,
            lit_unbiased,
        };
        (Some(lit), Some(answer))
    }

    /// [`answer_at`] from the plane, when every compare clears its margin (None: trace).
    #[inline]
    fn answer(&self, grid: &Grid, s: &Sampling, cascade: usize, pl: &Placement) -> Option<Answer> {
        if s.pcf == 1 && s.filter == PcfFilter::Bilinear {
            return self.answer_bilinear(grid, s, cascade, pl);
        }
        self.answer_any(grid, s, cascade, pl)
    }

    /// [`PlaneLookup::answer`] for any PCF width and filter: the footprint's texels one by one.
    #[inline]
    fn answer_any(&self, grid: &Grid, s: &Sampling, cascade: usize, pl: &Placement) -> Option<Answer> {
        let (mut lit_w, mut lit_n, mut unb_w, mut unb_n) = (0.0, 0u32, 0.0, 0u32);
        let clear = each_footprint(pl.at, s.pcf, s.filter, |g, w| {
            let c = grid.centre(g);
            self.texel_compare(s, cascade, pl, c, w, (&mut lit_w, &mut lit_n), (&mut unb_w, &mut unb_n))
        });
        clear.then(|| vote(s, self.own_only, (lit_w, lit_n), (unb_w, unb_n)))
    }

    /// [`PlaneLookup::answer_any`] for one bilinear tap (PCF 1, the default): the same texels,
    /// weights, compares and sums in the same order ([`bilinear_tap`]), written out for the
    /// 2x2 texels.
    #[inline]
    fn answer_bilinear(&self, grid: &Grid, s: &Sampling, cascade: usize, pl: &Placement) -> Option<Answer> {
        let (mut lit_w, mut lit_n, mut unb_w, mut unb_n) = (0.0, 0u32, 0.0, 0u32);
        for (c, w) in bilinear_tap(grid, pl.at) {
            if w > 0.0 && !self.texel_compare(s, cascade, pl, c, w, (&mut lit_w, &mut lit_n), (&mut unb_w, &mut unb_n))
            {
                return None;
            }
        }
        Some(vote(s, self.own_only, (lit_w, lit_n), (unb_w, unb_n)))
    }

    /// One texel's compares from the plane (its centre `c`, weight `w`), added to the passing
    /// weights and counts; false when a compare lies within its margin (then trace).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn texel_compare(
        &self,
        s: &Sampling,
        cascade: usize,
        pl: &Placement,
        c: DVec2,
        w: f64,
        (lit_w, lit_n): (&mut f64, &mut u32),
        (unb_w, unb_n): (&mut f64, &mut u32),
    ) -> bool {
        let (near, far) = s.ranges[cascade];
        {
            let d = self.k - self.gx * c.x - self.gy * c.y;
            let unbiased = self.own_depth - d;
            let lit = match self.lit_fixed {
                // The format's range and the biased compare are decided over the whole reach
                // (with this sign at every texel): only the unbiased compare is made.
                // False for NaN too: then the lookup is traced.
                Some(lit) => {
                    let clear = unbiased.abs() > self.tol_unbiased;
                    if !clear {
                        return false;
                    }
                    lit
                }
                None => {
                    // The format's range clamps nothing here.
                    if s.format.is_some() && !(d >= near + self.tol && d <= far - self.tol) {
                        return false;
                    }
                    let biased = pl.depth - (d + pl.bias);
                    if !(biased.abs() > self.tol_lit && unbiased.abs() > self.tol_unbiased) {
                        return false;
                    }
                    biased < 0.0
                }
            };
            if lit {
                *lit_w += w;
                *lit_n += 1;
            }
            if unbiased < 0.0 {
                *unb_w += w;
                *unb_n += 1;
            }
            true
        }
    }
}

/// The texel centres ([`Grid::centre`]) and weights of one bilinear tap at `at` on `grid`:
/// [`each_footprint`]'s four texels with `k = 1` (weights of 0 included), in its order and by
/// the same operations, with the texel indices' conversions to f64 made once per axis.
#[inline(always)]
fn bilinear_tap(grid: &Grid, at: DVec2) -> [(DVec2, f64); 4] {
    // `each_footprint` with k = 1: one tap at `at + 0`, weight 1/k² = 1.
    let tap = 1.0;
    let b = (at + DVec2::ZERO) - DVec2::splat(0.5);
    let i0 = DVec2::new(floor(b.x), floor(b.y));
    let fr = b - i0;
    let (i, j) = (i0.x as i64, i0.y as i64);
    // `Grid::centre` of each texel: ((index + fraction) + 0.5) * texel.
    let (f, t) = (grid.fraction, grid.texel);
    let cx = [((i as f64 + f.x) + 0.5) * t.x, (((i + 1) as f64 + f.x) + 0.5) * t.x];
    let cy = [((j as f64 + f.y) + 0.5) * t.y, (((j + 1) as f64 + f.y) + 0.5) * t.y];
    [
        (DVec2::new(cx[0], cy[0]), (1.0 - fr.x) * (1.0 - fr.y) * tap),
        (DVec2::new(cx[1], cy[0]), fr.x * (1.0 - fr.y) * tap),
        (DVec2::new(cx[0], cy[1]), (1.0 - fr.x) * fr.y * tap),
        (DVec2::new(cx[1], cy[1]), fr.x * fr.y * tap),
    ]
}

/// [`place`] through a frame's binary32 matrix: the offset point (f64) is stored in f32
/// relative to the anchor, its texel coordinates `(M p - o) / T` and its normalised depth are
/// computed in f32, and the bias (world units, as in f64) is converted to normalised depth in
/// f32. `at` is `first + s` (exact), so its floor is the texel the shader reads. `depth` and
/// `bias` hold f32 values (normalised depth), exactly.
fn place32(
    basis: LightBasis,
    texel: DVec2,
    m: &FrameMatrix,
    first: (i64, i64),
    r: &Receiver,
    bias: &Bias,
) -> Placement {
    let p = offset_point(basis, texel, r, bias);
    let s = m.lookup(p);
    let slope = depth_slope(basis, texel, r);
    let world = bias.facing.apply(bias.depth + bias.slope * slope, r.n.dot(-basis.z));
    Placement {
        at: DVec2::new(first.0 as f64 + s[0] as f64, first.1 as f64 + s[1] as f64),
        texel: (first.0 + s[0].floor() as i64, first.1 + s[1].floor() as i64),
        depth: m.depth(p) as f64,
        slope,
        bias: ((world as f32) * m.inv_range) as f64,
    }
}

/// The texels a PCF kernel of width `k` reads around `g`, in a fixed order.
pub fn kernel(g: (i64, i64), k: u32) -> impl Iterator<Item = (i64, i64)> {
    let h = (k / 2) as i64;
    (-h..=h).flat_map(move |dy| (-h..=h).map(move |dx| (g.0 + dx, g.1 + dy)))
}

/// The texels a lookup at `at` (texel units, see [`Placement::at`]) reads and the weight of
/// each compare result, in a fixed order; weights sum to 1 and texels of weight 0 are left
/// out. `k x k` taps one texel apart are centred on `at`, each weighing `1 / k²`:
/// - nearest: a tap reads the texel it falls in;
/// - bilinear: a tap at `t` reads the 2x2 texels whose centres surround it, texel
///   `(i0 + a, j0 + b)` (a, b in {0, 1}) with weight `(a ? fx : 1 - fx) (b ? fy : 1 - fy)`,
///   where `i0 = floor(t.x - 0.5)` and `fx = t.x - 0.5 - i0` (likewise in y).
pub fn footprint(at: DVec2, k: u32, filter: PcfFilter) -> impl Iterator<Item = ((i64, i64), f64)> {
    let h = (k / 2) as i64;
    let tap = 1.0 / (k * k) as f64;
    (-h..=h)
        .flat_map(move |dy| (-h..=h).map(move |dx| at + DVec2::new(dx as f64, dy as f64)))
        .flat_map(move |t| {
            let mut out = [((0i64, 0i64), 0.0f64); 4];
            match filter {
                PcfFilter::Nearest => out[0] = ((floor(t.x) as i64, floor(t.y) as i64), tap),
                PcfFilter::Bilinear => {
                    let b = t - DVec2::splat(0.5);
                    let i0 = DVec2::new(floor(b.x), floor(b.y));
                    let f = b - i0;
                    let (i, j) = (i0.x as i64, i0.y as i64);
                    out = [
                        ((i, j), (1.0 - f.x) * (1.0 - f.y) * tap),
                        ((i + 1, j), f.x * (1.0 - f.y) * tap),
                        ((i, j + 1), (1.0 - f.x) * f.y * tap),
                        ((i + 1, j + 1), f.x * f.y * tap),
                    ];
                }
            }
            out.into_iter().filter(|(_, w)| *w > 0.0)
        })
}

/// [`footprint`]'s texels and weights, in its order and computed by the same operations,
/// handed to `f` one by one until it returns false (then this returns false): the walk's
/// lookups iterate in place instead of through nested iterator adapters.
#[inline(always)]
fn each_footprint(at: DVec2, k: u32, filter: PcfFilter, mut f: impl FnMut((i64, i64), f64) -> bool) -> bool {
    let h = (k / 2) as i64;
    let tap = 1.0 / (k * k) as f64;
    for dy in -h..=h {
        for dx in -h..=h {
            let t = at + DVec2::new(dx as f64, dy as f64);
            match filter {
                PcfFilter::Nearest => {
                    if tap > 0.0 && !f((floor(t.x) as i64, floor(t.y) as i64), tap) {
                        return false;
                    }
                }
                PcfFilter::Bilinear => {
                    let b = t - DVec2::splat(0.5);
                    let i0 = DVec2::new(floor(b.x), floor(b.y));
                    let fr = b - i0;
                    let (i, j) = (i0.x as i64, i0.y as i64);
                    let out = [
                        ((i, j), (1.0 - fr.x) * (1.0 - fr.y) * tap),
                        ((i + 1, j), fr.x * (1.0 - fr.y) * tap),
                        ((i, j + 1), (1.0 - fr.x) * fr.y * tap),
                        ((i + 1, j + 1), fr.x * fr.y * tap),
                    ];
                    for (g, w) in out {
                        if w > 0.0 && !f(g, w) {
                            return false;
                        }
                    }
                }
            }
        }
    }
    true
}

// ---------------------------------------------------------------------------------------------
// One frame
// ---------------------------------------------------------------------------------------------

/// Which cascade reads a world point in a camera frame: by its view depth under the selection
/// `rig.splits`; None outside the shadowed range or the camera's view.
pub fn reading_cascade(rig: &Rig, pose: &CameraPose, p: DVec3) -> Option<usize> {
    let d = p - pose.position;
    let z = d.dot(pose.forward);
    let m = rig.cascade_count();
    if !(z >= rig.splits[0] && z < rig.splits[m]) {
        return None;
    }
    let inside = d.dot(pose.right).abs() <= rig.lens.tan_h * z && d.dot(pose.up).abs() <= rig.lens.tan_v * z;
    inside.then(|| cascade_at(&rig.splits, z))
}

/// Why a receiver pixel is not served as an engine would need at frame 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServeFault {
    /// The cascade that reads it has a window that does not contain it (the area of a missed
    /// slice corner): the map answers "lit" there whatever the casters.
    Missed,
    /// The cascade that reads it renders a light depth range that does not reach it (the
    /// receiver is clipped by the map's near or far plane).
    Clipped,
}

/// For every pixel of the visibility grid (row-major), whether its receiver (a hit facing the
/// light) is read by a cascade whose frame-0 window (`snapped` or not) misses it, or whose
/// light depth range (by the rig's scheme, [`Rig::light_depth`], over `bounds`) does not
/// contain its light depth; None for a pixel without a receiver, one no cascade reads, or one
/// served well. `slack` is the distance (world units) a point may lie past a depth plane
/// before it counts as clipped (rounding).
pub fn serve_faults(rig: &Rig, vis: &Visibility, bounds: &Aabb, snapped: bool, slack: f64) -> Vec<Option<ServeFault>> {
    let pose = vis.view.pose;
    let lp = LightPose::new(&rig.light, &pose);
    let cascades: Vec<(LightBasis, Window, (f64, f64))> = (0..rig.cascade_count())
        .map(|i| {
            let w = rig.window(i, &lp, snapped);
            let d = rig.light_depth(i, &lp, &w, bounds);
            (rig.basis(i, &lp), w, (d.near, d.far))
        })
        .collect();
    let terms = vis.view.ray_terms();
    vis.samples
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(k, s)| {
            let s = s.filter(|s| s.lit)?;
            let p = terms.point(k, s.depth);
            let i = reading_cascade(rig, &pose, p)?;
            let (basis, w, (near, far)) = &cascades[i];
            if w.outside_by_texels(basis.to_light_xy(p)) > 0.0 {
                return Some(ServeFault::Missed);
            }
            let z = basis.z.dot(p);
            (z < near - slack || z > far + slack).then_some(ServeFault::Clipped)
        })
        .collect()
}

/// Every cascade's grid in a frame (`light` is the frame's light: the rig's, until lights move).
/// With the sampling's binary32 pipeline, each window and light matrix is the one the f32
/// pipeline builds in this frame.
pub fn frame_grids(
    maps: &mut ShadowMaps,
    rig: &Rig,
    light: &LightBasis,
    pose: &CameraPose,
    snapped: bool,
    s: &Sampling,
) -> Vec<FrameGrid> {
    let lp = LightPose::new(light, pose);
    let Some(b32) = &s.binary32 else {
        return (0..rig.cascade_count())
            .map(|i| {
                let w = rig.window(i, &lp, snapped);
                let basis = rig.basis(i, &lp);
                maps.grid(i, &basis, &w)
            })
            .collect();
    };
    let anchors = frame_anchors(rig, pose, b32.space);
    (0..rig.cascade_count())
        .map(|i| {
            let (basis, lpi) = rig.cascade_pose_with(i, &lp, light);
            let f32s = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
            let rows = [f32s(basis.x), f32s(basis.y)];
            let anchor = anchors[i];
            let w = b32.engine.window_with(i, &rows, &lpi.pose, anchor, snapped);
            // The frame's light depth range, fitted as the f64 pass fits it (to the window the
            // engine means to build), then stored in the f32 matrix relative to the anchor.
            let exact = rig.window(i, &lp, snapped);
            let d = rig.light_depth(i, &lp, &exact, &b32.bounds);
            let range = d.far - d.near;
            let inv = if range > 0.0 { 1.0 / range } else { 0.0 };
            let near_rel = d.near - basis.z.dot(anchor);
            let texel = DVec2::new(w.texel[0] as f64, w.texel[1] as f64);
            let origin = DVec2::new(w.origin[0] as f64, w.origin[1] as f64) + basis.to_light_xy(anchor);
            let window = Window {
                texel,
                origin_texels: origin / texel,
                resolution: exact.resolution,
            };
            let mut fg = maps.grid(i, &basis, &window);
            fg.matrix = Some(FrameMatrix {
                anchor,
                rows,
                origin: w.origin,
                texel: w.texel,
                depth_row: f32s(basis.z * inv),
                depth_offset: (-near_rel * inv) as f32,
                inv_range: inv as f32,
            });
            fg
        })
        .collect()
}

/// The map's answer for one receiver in one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Answer {
    /// Lit: the weighted share of passing compares is at least 1/2 (for the nearest filter,
    /// at least half of the `k x k` texels pass).
    pub lit: bool,
    /// Every texel read holds the receiver's own surface (its plane): a wrong answer is then
    /// self-shadowing (acne), not an edge the map's resolution misplaces.
    pub own_only: bool,
    /// The same texels compared with the receiver's own light depth, without any bias or
    /// normal offset: what the lookup says when nothing moves the receiver toward the light.
    pub lit_unbiased: bool,
}

/// The three errors of a receiver's answer (docs/ground-truth.md, "Three errors").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ErrorKind {
    /// Truly lit, shadowed, and every texel read holds its own surface: a bias fixes it.
    Acne,
    /// Wrong because the texels read hold another surface than the one the exact answer sees:
    /// truly lit but shadowed by a caster's texels, or truly shadowed but lit because the
    /// texels do not hold the caster (lit even without bias, or every texel read holds the
    /// receiver's own surface). Only resolution fixes it.
    Edge,
    /// Truly shadowed, lit only because of the bias (shadowed without it) while a texel read
    /// holds another surface (the caster is in the map): peter-panning and light leaks.
    Leak,
}

impl Answer {
    /// Which error this answer makes at a receiver that is truly lit or not; None when right.
    pub fn error(self, truly_lit: bool) -> Option<ErrorKind> {
        match (self.lit, truly_lit) {
            (false, true) if self.own_only => Some(ErrorKind::Acne),
            (true, false) if !self.lit_unbiased && !self.own_only => Some(ErrorKind::Leak),
            (false, true) | (true, false) => Some(ErrorKind::Edge),
            _ => None,
        }
    }
}

/// The map's answer for one receiver in its cascade's grid, None when its texel is outside
/// the window. Reads held texels only.
fn answer(maps: &ShadowMaps, fg: &FrameGrid, r: &Receiver, s: &Sampling, cascade: usize) -> Option<Answer> {
    answer_at(maps, fg, r, s, cascade, &maps.place_in(fg, r, &s.bias[cascade]), None)
}

/// The texels of one grid one receiver reads, each traced once ([`trace_texel`]): a PCF
/// kernel's taps share texels, and frame 0 reads its receiver's texels three times. The first
/// [`HELD_INLINE`] are held in place (a bilinear 3x3 lookup reads 16), the rest in a vector.
struct Traced<'g> {
    scene: &'g SceneGeometry,
    grid: &'g Grid,
    inline: [((i64, i64), Stored); HELD_INLINE],
    n: usize,
    more: Vec<((i64, i64), Stored)>,
}

/// Texels [`Traced`] holds without allocating.
const HELD_INLINE: usize = 16;

impl<'g> Traced<'g> {
    fn new(scene: &'g SceneGeometry, grid: &'g Grid) -> Self {
        const NONE: ((i64, i64), Stored) = (
            (0, 0),
            Stored {
                depth: 0.0,
                triangle: None,
            },
        );
        Traced {
            scene,
            grid,
            inline: [NONE; HELD_INLINE],
            n: 0,
            more: Vec::new(),
        }
    }

    /// What texel `g` holds.
    fn get(&mut self, g: (i64, i64)) -> Stored {
        let found = self.inline[..self.n].iter().chain(&self.more).find(|(h, _)| *h == g);
        if let Some((_, x)) = found {
            return *x;
        }
        let x = trace_texel(self.scene, self.grid, g);
        if self.n < HELD_INLINE {
            self.inline[self.n] = (g, x);
            self.n += 1;
        } else {
            self.more.push((g, x));
        }
        x
    }
}

/// [`answer`] at a placement of the receiver (from [`ShadowMaps::place_in`] with its cascade's
/// bias), reading the texels through `texels` (of `fg`'s grid), or tracing them for this
/// answer alone when None.
fn answer_at<'g>(
    maps: &'g ShadowMaps<'_>,
    fg: &FrameGrid,
    r: &Receiver,
    s: &Sampling,
    cascade: usize,
    pl: &Placement,
    texels: Option<&mut Traced<'g>>,
) -> Option<Answer> {
    let mut own;
    let texels = match texels {
        Some(t) => t,
        None => {
            own = Traced::new(maps.scene, maps.grids[fg.id].as_ref()?);
            &mut own
        }
    };
    if !inside(fg, pl.texel) {
        return None;
    }
    let grid = texels.grid;
    let (near, far) = s.ranges[cascade];
    let own_depth = grid.basis.z.dot(r.p);
    let (mut lit_w, mut lit_n, mut unb_w, mut unb_n) = (0.0, 0u32, 0.0, 0u32);
    let mut own_only = true;
    each_footprint(pl.at, s.pcf, s.filter, |g, w| {
        let held = texels.get(g);
        let stored = held.depth;
        let (lit, lit_unbiased) = match &fg.matrix {
            None => {
                let stored = s.format.map_or(stored, |f| f.quantise(stored, near, far));
                (pl.depth <= stored + pl.bias, own_depth <= stored)
            }
            Some(m) => {
                // Binary32: the texel's depth written through the frame's f32 matrix, the
                // receiver's f32 depth compared with it plus the f32 bias.
                let stored = if stored.is_finite() {
                    store32(m.depth(maps.hit_point(fg.id, g, stored)), s.format)
                } else {
                    f32::INFINITY
                };
                let depth = pl.depth as f32;
                (depth <= stored + pl.bias as f32, m.depth(r.p) <= stored)
            }
        };
        if lit {
            lit_w += w;
            lit_n += 1;
        }
        if lit_unbiased {
            unb_w += w;
            unb_n += 1;
        }
        // `same_plane` is a pure test: once false, the rest need not ask it.
        own_only = own_only && held.triangle.is_some_and(|t| same_plane(maps.scene, t, r));
        true
    });
    Some(vote(s, own_only, (lit_w, lit_n), (unb_w, unb_n)))
}

/// The answer from the passing weights and counts of the biased and the unbiased compares.
#[inline]
fn vote(s: &Sampling, own_only: bool, lit: (f64, u32), unbiased: (f64, u32)) -> Answer {
    let pass = |(w, n): (f64, u32)| match s.filter {
        // Whole counts for the vote: no rounding of 1/k² sums.
        PcfFilter::Nearest => 2 * n >= s.pcf * s.pcf,
        PcfFilter::Bilinear => w >= 0.5,
    };
    Answer {
        lit: pass(lit),
        own_only,
        lit_unbiased: pass(unbiased),
    }
}

/// One receiver's key in a frame: its cascade, grid and texel (its state is a function of it).
type Key = Option<(usize, usize, (i64, i64))>;

fn key_of(maps: &ShadowMaps, grids: &[FrameGrid], rig: &Rig, pose: &CameraPose, r: &Receiver, s: &Sampling) -> Key {
    let i = reading_cascade(rig, pose, r.p)?;
    let fg = &grids[i];
    let pl = maps.place_in(fg, r, &s.bias[i]);
    inside(fg, pl.texel).then_some((i, fg.id, pl.texel))
}

/// The texels receiver `r` reads in grid `fg` of cascade `i` under the sampling's bias.
fn texels_read(maps: &ShadowMaps, fg: &FrameGrid, r: &Receiver, s: &Sampling, i: usize) -> Vec<(usize, (i64, i64))> {
    let pl = maps.place_in(fg, r, &s.bias[i]);
    footprint(pl.at, s.pcf, s.filter).map(|(g, _)| (fg.id, g)).collect()
}

/// Whether texel `g` of a frame's grid is inside its window.
fn inside(fg: &FrameGrid, g: (i64, i64)) -> bool {
    let n = fg.resolution as i64;
    let j = (g.0 - fg.first.0, g.1 - fg.first.1);
    j.0 >= 0 && j.1 >= 0 && j.0 < n && j.1 < n
}

/// The map's answers for `points` in one frame, fetching the texels they need.
pub fn frame_states(
    maps: &mut ShadowMaps,
    rig: &Rig,
    light: &LightBasis,
    pose: &CameraPose,
    snapped: bool,
    points: &[Receiver],
    s: &Sampling,
) -> (Vec<Option<usize>>, Vec<Option<Answer>>) {
    let grids = frame_grids(maps, rig, light, pose, snapped, s);
    let keys: Vec<Key> = points
        .par_iter()
        .map(|r| key_of(maps, &grids, rig, pose, r, s))
        .collect();
    if maps.count {
        let wanted: Vec<(usize, (i64, i64))> = points
            .iter()
            .zip(&keys)
            .filter_map(|(r, k)| k.map(|(i, _, _)| texels_read(maps, &grids[i], r, s, i)))
            .flatten()
            .collect();
        maps.stats.reads += wanted.len() as u64;
        maps.fetch(wanted);
    }
    let states = points
        .par_iter()
        .zip(&keys)
        .map(|(r, k)| k.and_then(|(i, _, _)| answer(maps, &grids[i], r, s, i)))
        .collect();
    maps.end_frame();
    (keys.iter().map(|k| k.map(|x| x.0)).collect(), states)
}

// ---------------------------------------------------------------------------------------------
// S5: flicker along a path
// ---------------------------------------------------------------------------------------------

/// Which cascade reads a world point in one camera frame: [`reading_cascade`] with the frame's
/// terms taken once, and the cascade counted without branches when the splits ascend (the
/// count of interior splits at or below the depth is then [`cascade_at`]'s partition point).
struct Reader<'r> {
    position: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_h: f64,
    tan_v: f64,
    splits: &'r [f64],
    ascending: bool,
}

impl<'r> Reader<'r> {
    fn new(rig: &'r Rig, pose: &CameraPose) -> Self {
        Reader {
            position: pose.position,
            forward: pose.forward,
            right: pose.right,
            up: pose.up,
            tan_h: rig.lens.tan_h,
            tan_v: rig.lens.tan_v,
            splits: &rig.splits,
            ascending: rig.splits.windows(2).all(|w| w[0] <= w[1]),
        }
    }

    /// [`reading_cascade`]'s answer for `p`, computed by the same operations.
    #[inline]
    fn cascade(&self, p: DVec3) -> Option<usize> {
        let d = p - self.position;
        let z = d.dot(self.forward);
        let m = self.splits.len() - 1;
        if !(z >= self.splits[0] && z < self.splits[m]) {
            return None;
        }
        let inside = d.dot(self.right).abs() <= self.tan_h * z && d.dot(self.up).abs() <= self.tan_v * z;
        if !inside {
            return None;
        }
        Some(if self.ascending {
            let below: usize = self.splits[1..m].iter().map(|&c| usize::from(c <= z)).sum();
            below.min(m - 1)
        } else {
            cascade_at(self.splits, z)
        })
    }
}

/// The walk's step counts: state changes, those at shadow edges, steps, and per cascade the
/// changes and steps at frames that cascade was rendered again.
#[derive(Debug, Clone)]
struct StepTotals {
    flips: u64,
    edge: u64,
    total: u64,
    update_flips: Vec<u64>,
    update_steps: Vec<u64>,
}

impl StepTotals {
    fn new(m: usize) -> Self {
        StepTotals {
            flips: 0,
            edge: 0,
            total: 0,
            update_flips: vec![0; m],
            update_steps: vec![0; m],
        }
    }

    fn add(&mut self, o: &StepTotals) {
        self.flips += o.flips;
        self.edge += o.edge;
        self.total += o.total;
        for (a, b) in self.update_flips.iter_mut().zip(&o.update_flips) {
            *a += b;
        }
        for (a, b) in self.update_steps.iter_mut().zip(&o.update_steps) {
            *a += b;
        }
    }
}

/// One frame's totals over the receivers: steps, lookups (receivers with a key) and, when the
/// maps count, the texels the changed receivers read.
struct FrameTotals {
    steps: StepTotals,
    reads: u64,
    wanted: Vec<(usize, (i64, i64))>,
}

impl FrameTotals {
    fn new(m: usize) -> Self {
        FrameTotals {
            steps: StepTotals::new(m),
            reads: 0,
            wanted: Vec::new(),
        }
    }

    fn merge(mut self, mut o: FrameTotals) -> Self {
        self.steps.add(&o.steps);
        self.reads += o.reads;
        self.wanted.append(&mut o.wanted);
        self
    }
}

/// Receiver `r`'s key in a frame of `grids`, given the cascade that reads it in that frame
/// (`cascade`, [`Reader::cascade`]: the same in every snap mode) and, when the key changed
/// from `old` (or the binary32 pipeline rebuilds every map: `rebuilt`), its answer (None: keep
/// the last one).
#[allow(clippy::too_many_arguments)]
#[inline]
fn walk_step(
    maps: &ShadowMaps,
    grids: &[FrameGrid],
    cascade: Option<usize>,
    r: &Receiver,
    s: &Sampling,
    rebuilt: bool,
    old: Key,
    memo: &mut Option<Memo>,
) -> (Key, Option<Option<Answer>>) {
    let Some(i) = cascade else {
        return (None, None);
    };
    let fg = &grids[i];
    if let Some((oi, oid, og)) = old {
        if oi == i && oid == fg.id && fg.matrix.is_none() {
            return (inside(fg, og).then_some((i, fg.id, og)), None);
        }
    }
    let (pl, plane, grid) = maps.place_memo(fg, r, s, i, memo);
    let key = inside(fg, pl.texel).then_some((i, fg.id, pl.texel));
    if !(key.is_some() && (rebuilt || key != old)) {
        return (key, None);
    }
    if let Some(a) = plane.and_then(|p| p.fixed) {
        return (key, Some(Some(a)));
    }
    let answer = plane
        .and_then(|p| p.answer(grid, s, i, &pl))
        .or_else(|| answer_at(maps, fg, r, s, i, &pl, None));
    (key, Some(answer))
}

/// One receiver in one walk (snap mode): its key in the last frame, its memo, state, state
/// changes and steps counted.
#[derive(Debug, Clone, Copy, Default)]
struct Lane {
    key: Key,
    memo: Option<Memo>,
    state: Option<Answer>,
    flips: u32,
    steps: u32,
}

/// Receivers per task of the walk's parallel pass.
const WALK_CHUNK: usize = 512;

/// Frames per block of the walk: each receiver is stepped through a block's frames before the
/// next receiver (its lanes stay in cache), one parallel pass per block.
const WALK_BLOCK: usize = 16;

/// What a walk of the path measured for one snap mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Flicker {
    /// S5: state changes over the receiver steps counted (a step: one receiver read by the
    /// same cascade in two consecutive frames).
    pub s5: f64,
    /// The part of S5 at receivers whose texels held another surface than their own in
    /// either frame of the step (the shadow edge crawling), over the same steps.
    pub s5_edge: f64,
    /// The rest of S5: changes where every texel read held the receiver's own surface in both
    /// frames (acne coming and going); `s5 = s5_edge + s5_acne` up to rounding.
    pub s5_acne: f64,
    /// Per receiver: state changes and steps counted.
    pub flips: Vec<u32>,
    pub steps: Vec<u32>,
    pub frames: usize,
    pub stats: CacheStats,
    /// Per cascade, the state changes and the receiver steps counted at the frames in which
    /// that cascade was rendered again (every frame without cached cascades).
    pub update_flips: Vec<u64>,
    pub update_steps: Vec<u64>,
}

impl Flicker {
    /// Per receiver, its flip rate (None when no step of it was counted).
    pub fn rates(&self) -> Vec<Option<f64>> {
        self.flips
            .iter()
            .zip(&self.steps)
            .map(|(&f, &n)| (n > 0).then(|| f as f64 / n as f64))
            .collect()
    }
}

/// Walks the receivers through `poses` for one snap mode: per frame each receiver's cascade,
/// grid and texel; a receiver whose key did not change keeps its state (the map content under
/// it is the same), the others are answered again from the texel cache. O(points) memory
/// besides the cache. `on_frame(t, states)` sees every frame's states (for pictures).
///
/// With cached cascades (`cadence`): a cascade not rendered again in a frame (see
/// [`crate::walk::Cadence`]) keeps the window, and so the map, of its last update; a receiver
/// it serves then keeps its texel and its state, and one that the held window no longer holds
/// has no answer (its step is not counted). [`crate::walk::Cadence::EVERY_FRAME`] renders every
/// cascade every frame.
///
/// The walk reads through `maps` (fresh, [`ShadowMaps::new`]); its counts are the walk's
/// [`Flicker::stats`] (zero with [`ShadowMaps::counting`] off, which spares the walk the set
/// of texels read per grid). [`flicker_walks`] walks several snap modes in one pass.
#[allow(clippy::too_many_arguments)]
pub fn flicker_cached(
    maps: ShadowMaps,
    rig: &Rig,
    light: &LightBasis,
    poses: impl Iterator<Item = CameraPose>,
    snapped: bool,
    points: &[Receiver],
    s: &Sampling,
    cadence: crate::walk::Cadence<'_>,
    on_frame: &mut dyn FnMut(usize, &[Option<Answer>]),
) -> Flicker {
    let walks = vec![(maps, snapped)];
    let mut on = |_: usize, t: usize, states: &[Option<Answer>]| on_frame(t, states);
    let mut f = flicker_walks(walks, rig, light, poses, points, s, cadence, &mut on);
    f.pop().expect("one walk")
}

/// What [`flicker_walks`] shows each frame of each walk: `(walk, frame, states)`.
pub type OnWalkFrame<'a> = dyn FnMut(usize, usize, &[Option<Answer>]) + 'a;

/// [`flicker_cached`] for several snap modes at once (`walks`: each one's maps and snap mode),
/// in one pass over the receivers per frame: each receiver's cascade, which depends on the
/// camera alone, is found once per frame for every walk. Each walk's result is
/// [`flicker_cached`]'s for it alone; `on_frame(w, t, states)` sees walk `w`'s states of
/// frame `t` (the walks in order, frame by frame).
#[allow(clippy::too_many_arguments)]
pub fn flicker_walks(
    mut walks: Vec<(ShadowMaps, bool)>,
    rig: &Rig,
    light: &LightBasis,
    poses: impl Iterator<Item = CameraPose>,
    points: &[Receiver],
    s: &Sampling,
    cadence: crate::walk::Cadence<'_>,
    on_frame: &mut OnWalkFrame<'_>,
) -> Vec<Flicker> {
    let m = rig.cascade_count();
    let w = walks.len();
    let mut held: Vec<Vec<Option<(LightBasis, Window)>>> = vec![vec![None; m]; w];
    let n = points.len();
    // Per receiver its position, and per receiver and walk (receiver-major) its lane.
    let at: Vec<DVec3> = points.iter().map(|r| r.p).collect();
    let mut lanes: Vec<Lane> = vec![Lane::default(); n * w];
    let mut states: Vec<Option<Answer>> = vec![None; n];
    let mut totals: Vec<StepTotals> = (0..w).map(|_| StepTotals::new(m)).collect();
    // A bilinear tap reads 2x2 texels.
    let per_tap = if s.filter == PcfFilter::Bilinear { 4 } else { 1 };
    let k2 = (s.pcf * s.pcf * per_tap) as u64;
    let rebuilt = s.binary32.is_some();
    // Frames per block: one when the maps count the texels read (each frame's reads are
    // fetched while its grids live).
    let block = if walks.iter().any(|(maps, _)| maps.count) {
        1
    } else {
        WALK_BLOCK
    };
    let mut poses = poses.enumerate();
    let mut frames = 0;
    // The block's states, per chunk of receivers frame- and walk-major: receiver `j0 + jj` of
    // the chunk starting at `j0` (`cn` receivers) has its state in walk k at the block's frame
    // dt at `j0 * len * w + (dt * w + k) * cn + jj`.
    let mut block_states: Vec<Option<Answer>> = Vec::new();
    loop {
        // Frame 0 alone (a basis gets its cover when met in a second frame, so frame 0's
        // grids have none), then blocks of `block` frames. Each frame's grids are made in
        // order, as a frame-by-frame walk makes them; they live until the block is walked.
        let len = if frames == 0 { 1 } else { block };
        let mut block_grids: Vec<Vec<Vec<FrameGrid>>> = Vec::with_capacity(len);
        let mut readers: Vec<Reader> = Vec::with_capacity(len);
        for (t, pose) in poses.by_ref().take(len) {
            let grids: Vec<Vec<FrameGrid>> = walks
                .iter_mut()
                .zip(held.iter_mut())
                .map(|((maps, snapped), held)| {
                    let grids = if cadence.caches() {
                        let lp = LightPose::new(light, &pose);
                        (0..m)
                            .map(|i| {
                                let (basis, win) = match held[i] {
                                    Some(h) if !cadence.updates(i, t) => h,
                                    _ => (rig.basis(i, &lp), rig.window(i, &lp, *snapped)),
                                };
                                held[i] = Some((basis, win));
                                maps.grid(i, &basis, &win)
                            })
                            .collect()
                    } else {
                        frame_grids(maps, rig, light, &pose, *snapped, s)
                    };
                    maps.next_frame();
                    grids
                })
                .collect();
            block_grids.push(grids);
            readers.push(Reader::new(rig, &pose));
        }
        let len = readers.len();
        if len == 0 {
            break;
        }
        let t0 = frames;
        frames += len;
        block_states.clear();
        block_states.resize(n * len * w, None);
        // One parallel pass over the receivers per block, in place: per receiver, frame by
        // frame, its cascade (the same in every walk), then per walk its key, its answer when
        // the key changed (every receiver with the binary32 pipeline: its matrix, hence every
        // depth, is rebuilt each frame), and its step. On the grid of its previous key (f64)
        // a receiver keeps its texel, so only whether the window still holds it is asked.
        // A receiver's lanes stay in cache over the block's frames. The totals are integer
        // sums: the same in any order.
        let maps: Vec<&ShadowMaps> = walks.iter().map(|(maps, _)| maps).collect();
        // In chunks of receivers, each chunk's totals in a local accumulator.
        let frame = points
            .par_chunks(WALK_CHUNK)
            .zip(at.par_chunks(WALK_CHUNK))
            .zip(lanes.par_chunks_mut(WALK_CHUNK * w))
            .zip(block_states.par_chunks_mut(WALK_CHUNK * len * w))
            .map(|(((rs, ats), ls), out)| {
                let mut acc: Vec<FrameTotals> = (0..w).map(|_| FrameTotals::new(m)).collect();
                let cn = rs.len();
                for (jj, ((r, &p), ls)) in rs.iter().zip(ats).zip(ls.chunks_exact_mut(w)).enumerate() {
                    for (dt, (reader, grids)) in readers.iter().zip(&block_grids).enumerate() {
                        let t = t0 + dt;
                        let cascade = reader.cascade(p);
                        for (k, lane) in ls.iter_mut().enumerate() {
                            let (maps, grids, acc) = (maps[k], &grids[k], &mut acc[k]);
                            let old = lane.key;
                            let (key, answer) = walk_step(maps, grids, cascade, r, s, rebuilt, old, &mut lane.memo);
                            let next = match (key, answer) {
                                (None, _) => None,
                                (Some(_), Some(a)) => a,
                                (Some(_), None) => lane.state,
                            };
                            if let (Some(k), Some(_)) = (key, answer) {
                                if maps.count {
                                    let (i, _, _) = k;
                                    acc.wanted.extend(texels_read(maps, &grids[i], r, s, i));
                                }
                            }
                            acc.reads += u64::from(key.is_some());
                            if t > 0 {
                                let same_cascade = matches!((old, key), (Some(a), Some(b)) if a.0 == b.0);
                                if let (true, Some(a), Some(b)) = (same_cascade, lane.state, next) {
                                    lane.steps += 1;
                                    acc.steps.total += 1;
                                    let i = key.map_or(0, |k| k.0);
                                    let update = cadence.updates(i, t);
                                    acc.steps.update_steps[i] += u64::from(update);
                                    if a.lit != b.lit {
                                        acc.steps.update_flips[i] += u64::from(update);
                                        lane.flips += 1;
                                        acc.steps.flips += 1;
                                        if !(a.own_only && b.own_only) {
                                            acc.steps.edge += 1;
                                        }
                                    }
                                }
                            }
                            lane.state = next;
                            lane.key = key;
                            out[(dt * w + k) * cn + jj] = next;
                        }
                    }
                }
                acc
            })
            .reduce(
                || (0..w).map(|_| FrameTotals::new(m)).collect(),
                |a, b| a.into_iter().zip(b).map(|(a, b)| a.merge(b)).collect(),
            );
        for (k, (f, (maps, _))) in frame.into_iter().zip(walks.iter_mut()).enumerate() {
            totals[k].add(&f.steps);
            if maps.count {
                maps.stats.reads += f.reads * k2;
                // The texels a cache would fetch: those of receivers whose key changed.
                maps.fetch(f.wanted);
            }
        }
        for dt in 0..len {
            for k in 0..w {
                for (j0, chunk) in (0..n).step_by(WALK_CHUNK).zip(states.chunks_mut(WALK_CHUNK)) {
                    let at = j0 * len * w + (dt * w + k) * chunk.len();
                    chunk.copy_from_slice(&block_states[at..at + chunk.len()]);
                }
                on_frame(k, t0 + dt, &states);
            }
        }
        for (maps, _) in walks.iter_mut() {
            maps.end_frame();
        }
    }
    walks
        .into_iter()
        .zip(totals)
        .enumerate()
        .map(|(k, ((maps, _), totals))| {
            let StepTotals {
                flips: total_flips,
                edge: edge_flips,
                total: total_steps,
                update_flips,
                update_steps,
            } = totals;
            let rate = |f: u64| {
                if total_steps == 0 {
                    0.0
                } else {
                    f as f64 / total_steps as f64
                }
            };
            Flicker {
                s5: rate(total_flips),
                s5_edge: rate(edge_flips),
                s5_acne: rate(total_flips - edge_flips),
                flips: lanes.iter().skip(k).step_by(w).map(|l| l.flips).collect(),
                steps: lanes.iter().skip(k).step_by(w).map(|l| l.steps).collect(),
                frames,
                stats: maps.stats,
                update_flips,
                update_steps,
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Frame 0: acne, leaks, the bias needed and peter-panning
// ---------------------------------------------------------------------------------------------

/// One receiver at frame 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointZero {
    pub cascade: Option<usize>,
    /// The map's answer with the configured sampling (None outside every window).
    pub answer: Option<Answer>,
    /// The map's answer with the configured sampling (None outside every window).
    pub map_lit: Option<bool>,
    /// Truly lit (the exact answer).
    pub truly_lit: bool,
    /// Distance along the light to the blocking surface (0 when truly lit).
    pub occluder: f64,
    /// Light depth minus the stored depth of its own texel, exact (no bias, no quantisation,
    /// point sampling); `f64::MIN` when the texel holds no caster.
    pub excess: f64,
    /// Its depth slope per texel (world units).
    pub slope: f64,
    /// Its own texel holds its own surface (the same plane).
    pub own_surface: bool,
    /// The smallest depth bias (world units, exact depths) that lights it with the configured
    /// filter and no other bias term, when it can be acne: truly lit and every texel its
    /// unbiased lookup reads holds its own surface. None otherwise (a bias cannot or need not
    /// fix it). At least 0.
    pub needed: Option<f64>,
    /// `sin` of the light's incidence on its surface (peter-panning along the surface).
    pub sin_incidence: f64,
}

/// The error of a receiver's frame-0 answer, None when right or without an answer.
impl PointZero {
    pub fn error(&self) -> Option<ErrorKind> {
        self.answer.and_then(|a| a.error(self.truly_lit))
    }
}

/// Per-cascade ground truth of frame 0. Every `Option` is None (`n/a` in the outputs) when
/// the cascade has fewer than [`MIN_POINTS`] receivers.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CascadeTruth {
    pub points: usize,
    /// Truly lit receivers the map shadows while every texel read holds their own surface.
    pub acne_fraction: Option<f64>,
    /// Receivers wrong because the texels read hold another surface (both directions).
    pub edge_error_fraction: Option<f64>,
    /// Truly shadowed receivers the bias lets through.
    pub leak_fraction: Option<f64>,
    /// Smallest depth bias (world units) leaving acne on at most [`ACNE_ALLOWED`] of the
    /// cascade's points, exact depths, no margin.
    pub depth_bias_exact: Option<f64>,
    /// The same with the margin: `exact (1 + BIAS_MARGIN_REL)` plus each format's
    /// quantisation step (D16, D24, D32F).
    pub depth_bias: Option<[f64; 3]>,
    /// Each format's quantisation step over the cascade's light depth range.
    pub step: [f64; 3],
    /// The configured format's entry of `depth_bias`.
    pub chosen_bias: Option<f64>,
    /// Smallest slope bias alone (times the depth slope per texel) doing the same, exact depths,
    /// with the relative margin.
    pub slope_bias: Option<f64>,
    /// Largest distance along the receiver from a caster to where its shadow starts, at
    /// `chosen_bias`.
    pub peter_pan: Option<f64>,
}

/// Smallest `b >= 0` with at most `allowed` of `values` above it.
pub fn smallest_bias(values: &mut [f64], allowed: usize) -> f64 {
    if values.len() <= allowed {
        return 0.0;
    }
    values.sort_unstable_by(|a, b| a.total_cmp(b));
    values[values.len() - 1 - allowed].max(0.0)
}

/// The frame-0 answers of every receiver: the configured sampling and the exact excess.
///
/// The pass reads through `maps` (fresh, [`ShadowMaps::new`]); the counts returned are zero
/// with [`ShadowMaps::counting`] off.
pub fn frame_zero(
    maps: ShadowMaps,
    rig: &Rig,
    light: &LightBasis,
    pose: &CameraPose,
    snapped: bool,
    points: &[Receiver],
    s: &Sampling,
) -> (Vec<PointZero>, CacheStats) {
    let occ = occluders(maps.scene, light.z, points);
    frame_zero_exact(maps, rig, light, pose, snapped, points, &occ, s)
}

/// [`frame_zero`] with each receiver's exact answer given (`occluders[j]` is [`occluder`] of
/// `points[j]` along `light.z`, as [`occluders`] or [`exact_of`] gives them).
#[allow(clippy::too_many_arguments)]
pub fn frame_zero_exact(
    mut maps: ShadowMaps,
    rig: &Rig,
    light: &LightBasis,
    pose: &CameraPose,
    snapped: bool,
    points: &[Receiver],
    occluders: &[Option<f64>],
    s: &Sampling,
) -> (Vec<PointZero>, CacheStats) {
    let cascades: Vec<Option<usize>> = points.par_iter().map(|r| reading_cascade(rig, pose, r.p)).collect();
    let grids = frame_grids(&mut maps, rig, light, pose, snapped, s);
    frame_zero_on(maps, light, &grids, &cascades, (points, occluders), s)
}

/// The depth bias that lights a receiver whose lookup reads texels with these excesses
/// (receiver depth minus stored depth) and weights: with the excesses sorted ascending, the
/// first at which the passing weight reaches the filter's threshold (at least 0).
fn needed_bias(mut reads: Vec<(f64, f64)>, s: &Sampling) -> f64 {
    reads.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut w, mut n) = (0.0, 0u32);
    for (e, x) in &reads {
        w += x;
        n += 1;
        let pass = match s.filter {
            PcfFilter::Nearest => 2 * n >= s.pcf * s.pcf,
            PcfFilter::Bilinear => w >= 0.5,
        };
        if pass {
            return e.max(0.0);
        }
    }
    // Rounding left the weights a hair short of 1/2: every texel must pass.
    reads.last().map_or(0.0, |r| r.0.max(0.0))
}

/// [`frame_zero`] for given windows (each in its basis) and the cascade reading each receiver.
pub fn frame_zero_in(
    scene: &SceneGeometry,
    light: &LightBasis,
    windows: &[(LightBasis, Window)],
    cascades: &[Option<usize>],
    points: &[Receiver],
    s: &Sampling,
) -> (Vec<PointZero>, CacheStats) {
    let mut maps = ShadowMaps::new(scene);
    let grids: Vec<FrameGrid> = windows
        .iter()
        .enumerate()
        .map(|(i, (b, w))| maps.grid(i, b, w))
        .collect();
    let occ = occluders(scene, light.z, points);
    frame_zero_on(maps, light, &grids, cascades, (points, &occ), s)
}

/// [`frame_zero_in`] on a frame's grids. The bias search (`excess`, `needed`) reads exact
/// f64 depths in every pipeline; the answers use the grids' own arithmetic.
fn frame_zero_on(
    mut maps: ShadowMaps,
    light: &LightBasis,
    grids: &[FrameGrid],
    cascades: &[Option<usize>],
    (points, occluders): (&[Receiver], &[Option<f64>]),
    s: &Sampling,
) -> (Vec<PointZero>, CacheStats) {
    let scene = maps.scene;
    let zero: Vec<Option<Placement>> = points
        .par_iter()
        .zip(cascades)
        .map(|(r, c)| c.map(|i| maps.place(grids[i].id, r, &Bias::ZERO)))
        .collect();
    if maps.count {
        let mut wanted = Vec::new();
        for (j, c) in cascades.iter().enumerate() {
            if let (Some(i), Some(z)) = (*c, zero[j]) {
                let id = grids[i].id;
                wanted.push((id, z.texel));
                wanted.extend(footprint(z.at, s.pcf, s.filter).map(|(g, _)| (id, g)));
                wanted.extend(texels_read(&maps, &grids[i], &points[j], s, i));
            }
        }
        maps.stats.reads += wanted.len() as u64;
        maps.fetch(wanted);
    }
    let out = points
        .par_iter()
        .enumerate()
        .map(|(j, r)| {
            let occ = occluders[j];
            let truly_lit = occ.is_none();
            let (cascade, answer, excess, own, slope, needed) = match (cascades[j], zero[j]) {
                (Some(i), Some(z)) if inside(&grids[i], z.texel) => {
                    let fg = &grids[i];
                    let grid = maps.grids[fg.id].as_ref().expect("a grid of this frame");
                    let mut texels = Traced::new(scene, grid);
                    let stored = texels.get(z.texel);
                    let own = stored.triangle.is_some_and(|t| same_plane(scene, t, r));
                    let reads: Vec<(f64, f64, bool)> = footprint(z.at, s.pcf, s.filter)
                        .map(|(g, w)| {
                            let st = texels.get(g);
                            let own = st.triangle.is_some_and(|t| same_plane(scene, t, r));
                            (z.depth - st.depth, w, own)
                        })
                        .collect();
                    let can_be_acne = truly_lit && reads.iter().all(|x| x.2);
                    let needed = can_be_acne.then(|| needed_bias(reads.iter().map(|x| (x.0, x.1)).collect(), s));
                    let pl = maps.place_in(fg, r, &s.bias[i]);
                    (
                        Some(i),
                        answer_at(&maps, fg, r, s, i, &pl, Some(&mut texels)),
                        z.depth - stored.depth,
                        own,
                        z.slope,
                        needed,
                    )
                }
                _ => (None, None, 0.0, false, 0.0, None),
            };
            PointZero {
                cascade,
                answer,
                map_lit: answer.map(|a| a.lit),
                truly_lit,
                occluder: occ.unwrap_or(0.0),
                excess: if excess.is_finite() { excess } else { f64::MIN },
                slope,
                own_surface: own,
                needed,
                sin_incidence: (1.0 - r.n.dot(light.z).powi(2)).max(0.0).sqrt(),
            }
        })
        .collect();
    (out, maps.stats)
}

/// Whether triangle `t` lies in the plane of receiver `r`'s surface.
fn same_plane(scene: &SceneGeometry, t: usize, r: &Receiver) -> bool {
    if t == r.triangle {
        return true;
    }
    let n = scene.triangle_normal(t);
    let a = scene.mesh.triangles[t][0];
    let scale = 1.0 + r.p.abs().max_element();
    n.dot(r.n).abs() > 1.0 - 1e-9 && r.n.dot(a - r.p).abs() <= 1e-9 * scale
}

/// A cascade's ground truth needs at least this many receivers: below it, its fractions and
/// the bias it needs are `n/a` (the 0.1 % cut of the bias search then allows no receiver at
/// all, and a fraction's step is above 0.1 %).
pub const MIN_POINTS: usize = 1000;

/// The relative margin on top of the bias found (beside one step of the depth format).
pub const BIAS_MARGIN_REL: f64 = 1e-3;

/// The per-cascade ground truth of frame 0 (the sampling's format picks the peter-panning's
/// bias).
pub fn cascade_truth(points: &[PointZero], cascades: usize, s: &Sampling) -> Vec<CascadeTruth> {
    (0..cascades)
        .map(|i| {
            let mine: Vec<&PointZero> = points
                .iter()
                .filter(|p| p.cascade == Some(i) && p.map_lit.is_some())
                .collect();
            let n = mine.len();
            let enough = n >= MIN_POINTS;
            let frac =
                |k: ErrorKind| enough.then(|| mine.iter().filter(|p| p.error() == Some(k)).count() as f64 / n as f64);
            let allowed = (ACNE_ALLOWED * n as f64).floor() as usize;
            let mut needed: Vec<f64> = mine.iter().filter_map(|p| p.needed).collect();
            let exact = enough.then(|| smallest_bias(&mut needed, allowed));
            let mut ratio: Vec<f64> = mine
                .iter()
                .filter_map(|p| {
                    p.needed.map(|b| {
                        if b <= 0.0 {
                            0.0
                        } else if p.slope > 0.0 {
                            b / p.slope
                        } else {
                            MAX_SLOPE_TEXELS
                        }
                    })
                })
                .collect();
            let slope =
                enough.then(|| smallest_bias(&mut ratio, allowed).min(MAX_SLOPE_TEXELS) * (1.0 + BIAS_MARGIN_REL));
            let (near, far) = s.ranges.get(i).copied().unwrap_or((0.0, 0.0));
            let step = DepthFormat::ALL.map(|f| f.step(far - near));
            let with_margin = |st: f64| exact.map(|e| e * (1.0 + BIAS_MARGIN_REL) + st);
            let depth_bias = exact.map(|_| step.map(|st| with_margin(st).expect("exact is Some")));
            let chosen = with_margin(s.format.map_or(0.0, |f| f.step(far - near)));
            let peter_pan = chosen.map(|chosen| {
                mine.iter()
                    // Leaks the bias makes: the texel holds another surface in front of the
                    // point (shadowed without bias), and the bias lets the point through.
                    .filter(|p| !p.truly_lit && !p.own_surface && p.excess > 0.0 && p.excess <= chosen)
                    .map(|p| p.occluder * p.sin_incidence)
                    .fold(0.0, f64::max)
            });
            CascadeTruth {
                points: n,
                acne_fraction: frac(ErrorKind::Acne),
                edge_error_fraction: frac(ErrorKind::Edge),
                leak_fraction: frac(ErrorKind::Leak),
                depth_bias_exact: exact,
                depth_bias,
                step,
                chosen_bias: chosen,
                slope_bias: slope,
                peter_pan,
            }
        })
        .collect()
}

/// The shares of the three errors (acne, edge, leak) over every receiver a window covers at
/// frame 0; None without any.
pub fn error_fractions(points: &[PointZero]) -> Option<[f64; 3]> {
    let covered: Vec<&PointZero> = points.iter().filter(|p| p.map_lit.is_some()).collect();
    if covered.is_empty() {
        return None;
    }
    let n = covered.len() as f64;
    let share = |k: ErrorKind| covered.iter().filter(|p| p.error() == Some(k)).count() as f64 / n;
    Some([share(ErrorKind::Acne), share(ErrorKind::Edge), share(ErrorKind::Leak)])
}

/// Acne and leak fractions over every receiver a window covers at frame 0 (0 without any).
pub fn fractions(points: &[PointZero]) -> (f64, f64) {
    error_fractions(points).map_or((0.0, 0.0), |f| (f[0], f[2]))
}

/// The pixels of the visibility grid whose nearest hit faces away from the light, in
/// grid order: they are drawn as [`Shade::Away`] under every frame's answers.
pub fn away_pixels(vis: &Visibility) -> Vec<usize> {
    vis.samples
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_some_and(|s| !s.lit))
        .map(|(i, _)| i)
        .collect()
}

/// The picture of one frame's answers over the visibility grid, the pixels `away` (facing away
/// from the light, [`away_pixels`]) drawn as [`Shade::Away`].
pub fn shade_image(
    cols: u32,
    rows: u32,
    away: &[usize],
    points: &[Receiver],
    truly_lit: &[bool],
    states: &[Option<Answer>],
) -> ShadeImage {
    let mut image = ShadeImage::empty(cols, rows);
    for &i in away {
        image.pixels[i] = Shade::Away;
    }
    for ((r, &truth), s) in points.iter().zip(truly_lit).zip(states) {
        if let Some(a) = s {
            image.pixels[r.pixel] = match a.error(truth) {
                None => Shade::of(a.lit, truth),
                Some(ErrorKind::Acne) => Shade::Acne,
                Some(ErrorKind::Edge) => Shade::Edge,
                Some(ErrorKind::Leak) => Shade::Leak,
            };
        }
    }
    image
}

/// The flip rates over the visibility grid.
pub fn flip_image(cols: u32, rows: u32, points: &[Receiver], f: &Flicker) -> FlipImage {
    let mut flips = vec![None; cols as usize * rows as usize];
    for (r, rate) in points.iter().zip(f.rates()) {
        flips[r.pixel] = rate;
    }
    FlipImage { cols, rows, flips }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_cover::tests::{scene, LIGHTS};
    use crate::rng::SplitMix64;

    /// Receivers on the scene's surfaces that face the light: straight down onto the ground
    /// and the boxes' tops, and onto the boxes' sides, spread and clustered at the boxes.
    fn receivers_of(scene: &SceneGeometry, light: DVec3, rng: &mut SplitMix64, n: usize) -> Vec<Receiver> {
        let mut out = Vec::new();
        let mut attempt = 0usize;
        while out.len() < n {
            attempt += 1;
            let (origin, dir) = if attempt % 3 == 2 {
                // Sideways onto a box (the tower's and the office block's faces).
                let y = rng.range(0.5, 29.0);
                (
                    DVec3::new(rng.range(-60.0, 60.0), y, -250.0 * rng.range(0.0, 1.0)),
                    DVec3::X,
                )
            } else if out.len() % 3 == 1 {
                (
                    DVec3::new(rng.range(-45.0, 40.0), 60.0, rng.range(-170.0, -15.0)),
                    DVec3::NEG_Y,
                )
            } else {
                (
                    DVec3::new(rng.range(-190.0, 190.0), 60.0, rng.range(-190.0, 190.0)),
                    DVec3::NEG_Y,
                )
            };
            let Some(h) = scene.first_hit(origin, dir, 0.0, 500.0) else {
                continue;
            };
            let mut nrm = scene.triangle_normal(h.triangle);
            if nrm.dot(-light.normalize()) < 0.0 {
                nrm = -nrm;
            }
            if nrm.dot(-light.normalize()) <= 0.0 {
                continue;
            }
            out.push(Receiver {
                pixel: out.len(),
                p: origin + dir * h.t,
                n: nrm,
                triangle: h.triangle,
            });
        }
        out
    }

    /// The plane lookup gives [`answer_at`]'s answer (the texels traced) to the bit wherever it
    /// decides, and decides most lookups: four lights (one straight down, where the ground's
    /// unbiased compare is a tie at every texel), texel sizes from fine to coarse, PCF 1, 3 and
    /// 5 with both filters, each depth format and none, and biases from none to one that
    /// puts many compares near their threshold, with the normal offset along the normal and
    /// laterally, at random window fractions.
    #[test]
    fn the_plane_lookup_equals_tracing_the_texels() {
        let scene = scene();
        let mut rng = SplitMix64::new(11);
        let (mut decided, mut total, mut fixed, mut lit_fixed) = (0usize, 0usize, 0usize, 0usize);
        for light in [
            DVec3::new(-0.4, -1.0, -0.3),
            DVec3::new(0.3, -0.2, 0.9),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.7, -0.5, 0.1),
        ] {
            let basis = LightBasis::new(light);
            let points = receivers_of(&scene, light, &mut rng, 300);
            let cover = scene.light_cover(&basis, true).expect("a cover");
            for (k, texel) in [0.003, 0.04, 0.3, 2.5].into_iter().enumerate() {
                let (pcf, filter) = [
                    (1, PcfFilter::Bilinear),
                    (3, PcfFilter::Nearest),
                    (5, PcfFilter::Bilinear),
                    (1, PcfFilter::Nearest),
                ][k];
                let format = [
                    Some(DepthFormat::D32F),
                    Some(DepthFormat::D16),
                    None,
                    Some(DepthFormat::D24),
                ][k];
                for bias in [
                    Bias::ZERO,
                    Bias {
                        depth: 0.4 * texel,
                        slope: 1.0,
                        normal: 0.5,
                        ..Bias::ZERO
                    },
                    Bias {
                        depth: 0.1 * texel,
                        normal: 1.0,
                        offset: NormalOffset::Lateral,
                        ..Bias::ZERO
                    },
                ] {
                    let s = Sampling {
                        bias: vec![bias],
                        format,
                        ranges: vec![(-300.0, 300.0)],
                        pcf,
                        filter,
                        binary32: None,
                    };
                    let mut maps = ShadowMaps::new(&scene).counting(false);
                    for _ in 0..2 {
                        let w = Window {
                            texel: DVec2::splat(texel),
                            origin_texels: DVec2::new(rng.range(-1e4, 1e4), rng.range(-1e4, 1e4)),
                            resolution: u32::MAX,
                        };
                        let mut fg = maps.grid(0, &basis, &w);
                        // Every receiver inside the window.
                        fg.first = (-(1 << 31), -(1 << 31));
                        let grid = maps.grids[fg.id].as_ref().expect("a grid");
                        assert!(grid.cover.is_some());
                        for r in &points {
                            let u = unplaced(grid.basis, grid.texel, r, &s.bias[0]);
                            let pl = u.on(grid.fraction);
                            let traced = answer_at(&maps, &fg, r, &s, 0, &pl, None);
                            total += 1;
                            let Some(p) = PlaneLookup::of(&scene, &cover, grid, r, &u, &s, 0) else {
                                continue;
                            };
                            if let Some(a) = p.answer(grid, &s, 0, &pl) {
                                assert_eq!(Some(a), traced, "{light} {texel} {bias:?} at {}", r.p);
                                decided += 1;
                            }
                            // With the biased compare fixed, the unbiased compares alone give
                            // what every compare gives.
                            let all = PlaneLookup {
                                lit_fixed: None,
                                fixed: None,
                                ..p
                            };
                            assert_eq!(p.answer(grid, &s, 0, &pl), all.answer(grid, &s, 0, &pl));
                            lit_fixed += usize::from(p.lit_fixed.is_some());
                            // A fixed answer is the traced one here, and the plane's at
                            // every other fraction of the family (the texels traced too).
                            if let Some(a) = p.fixed {
                                fixed += 1;
                                assert_eq!(Some(a), traced, "fixed: {light} {texel} {bias:?} at {}", r.p);
                                for _ in 0..3 {
                                    let f = DVec2::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0));
                                    let f = (f * FRACTION_STEPS).floor() / FRACTION_STEPS;
                                    let other = Grid {
                                        fraction: f,
                                        seen: Fast::default(),
                                        cover: grid.cover.clone(),
                                        ..*grid
                                    };
                                    let pl = u.on(f);
                                    assert_eq!(p.answer(&other, &s, 0, &pl), Some(a), "fraction {f}");
                                    assert_eq!(all.answer(&other, &s, 0, &pl), Some(a), "fraction {f}");
                                    let mut texels = Traced::new(&scene, &other);
                                    let got = answer_at(&maps, &fg, r, &s, 0, &pl, Some(&mut texels));
                                    assert_eq!(got, Some(a), "fixed, traced at fraction {f}: {light} {texel}");
                                }
                            }
                        }
                        maps.end_frame();
                    }
                }
            }
        }
        assert!(decided * 2 > total, "the plane decided {decided} of {total} lookups");
        assert!(fixed * 25 > total, "a fixed answer for {fixed} of {total} lookups");
        assert!(
            lit_fixed * 4 > total,
            "the biased compare fixed for {lit_fixed} of {total} lookups"
        );
    }

    /// Wherever the cover names one owner for a rectangle, it names it at every point of it
    /// and the BVH's hit there is that triangle at the plane's depth within its rounding
    /// margin ([`PlaneLookup`]): rectangles of many sizes over the scene's footprint and at the
    /// boxes' edges, under four lights.
    #[test]
    fn a_region_owner_owns_every_point_of_its_rectangle() {
        let scene = scene();
        let bounds = scene.mesh.bounds().expect("bounds");
        let mut rng = SplitMix64::new(5);
        for light in LIGHTS {
            let basis = LightBasis::new(light);
            let cover = scene.light_cover(&basis, true).expect("a cover");
            let (lo, hi) = crate::cost::light_depth_extent(&basis, &bounds);
            let start = lo - 1.0;
            let (mut owned, mut n) = (0, 0);
            for k in 0..4000 {
                let centre = if k % 2 == 0 {
                    basis.to_light_xy(DVec3::new(
                        rng.range(-230.0, 230.0),
                        rng.range(0.0, 40.0),
                        rng.range(-230.0, 230.0),
                    ))
                } else {
                    let c = scene.mesh.triangles[(rng.next_u64() % scene.mesh.triangles.len() as u64) as usize][0];
                    basis.to_light_xy(c) + DVec2::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0))
                };
                let half = DVec2::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0)).powf(3.0) * 20.0;
                n += 1;
                let Some(t) = cover.region_owner(centre - half, centre + half) else {
                    continue;
                };
                owned += 1;
                let plane = cover.plane(&scene.mesh, t).expect("an owner faces the light");
                for _ in 0..20 {
                    let q = centre + half * DVec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
                    assert_eq!(cover.at(q), Cell::Owner(t), "{light} at {q}");
                    let origin = basis.x * q.x + basis.y * q.y + basis.z * start;
                    let h = scene.first_hit(origin, basis.z, 0.0, hi - lo + 2.0).expect("a hit");
                    assert_eq!(h.triangle, t, "{light} at {q}");
                    let depth = start + h.t;
                    let d = plane.k - plane.gx * q.x - plane.gy * q.y;
                    let mag = plane.reach + 2.0 * q.abs().max_element() + start.abs() + (hi - lo + 2.0);
                    let bound = (1.0 + plane.cond) * mag / (1u64 << 45) as f64;
                    assert!(
                        (depth - d).abs() <= bound,
                        "{light} at {q}: {depth} against {d}, bound {bound}"
                    );
                }
            }
            // Light grazing the ground (the last) leaves few owners; the others own most.
            assert!(
                owned * 4 > n || light.y > -0.01,
                "{light}: {owned} of {n} rectangles owned"
            );
            assert!(owned > 0, "{light}: no rectangle owned");
        }
    }

    /// The library-free floor equals `f64::floor` to the bit, at whole numbers and either side
    /// of them, at signed zeros, beyond 2^52, at the infinities and on random values.
    /// The walk's in-place footprint hands out [`footprint`]'s texels and weights, bit for bit
    /// and in order, for every PCF width and filter, at random points, on texel edges and
    /// centres, and stops where its callback says.
    #[test]
    fn each_footprint_is_the_footprint_to_the_bit() {
        let mut rng = SplitMix64::new(24);
        let mut ats: Vec<DVec2> = (0..400)
            .map(|_| DVec2::new(rng.range(-3000.0, 3000.0), rng.range(-3000.0, 3000.0)))
            .collect();
        for x in [-2.0, -1.5, -0.5, 0.0, 0.5, 1.0, 7.25] {
            ats.extend([DVec2::new(x, 3.5), DVec2::new(0.5, x), DVec2::splat(x)]);
        }
        let bits = |v: &[((i64, i64), f64)]| v.iter().map(|(g, w)| (*g, w.to_bits())).collect::<Vec<_>>();
        for at in ats {
            for k in [1, 3, 5] {
                for filter in [PcfFilter::Nearest, PcfFilter::Bilinear] {
                    let want: Vec<_> = footprint(at, k, filter).collect();
                    let mut got = Vec::new();
                    assert!(each_footprint(at, k, filter, |g, w| {
                        got.push((g, w));
                        true
                    }));
                    assert_eq!(bits(&got), bits(&want), "at {at} k {k} {filter:?}");
                    // Stopped after the second texel: two handed out, false returned.
                    let mut seen = 0;
                    let all = each_footprint(at, k, filter, |_, _| {
                        seen += 1;
                        seen < 2
                    });
                    assert_eq!((all, seen), (want.len() < 2, want.len().min(2)));
                }
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]

        /// The plane lookup written out for one bilinear tap (`answer_bilinear`, the walk's
        /// path at PCF 1) answers as the footprint loop (`answer_any`) to the bit: random
        /// planes through the receiver's depth, margins from far below to above the depth
        /// differences (some compares within them: both trace), the biased compare fixed or
        /// not, placements on and off whole and half texels, window fractions, texel sizes,
        /// with and without a depth format.
        #[test]
        fn the_bilinear_plane_lookup_is_the_footprint_loop(
            g in (-3.0f64..3.0, -3.0f64..3.0),
            at in (-3000.0f64..3000.0, -3000.0f64..3000.0),
            snap in 0u8..4,
            fraction in (0u32..1 << 20, 0u32..1 << 20),
            texel in 0.001f64..3.0,
            offsets in (-2.0f64..2.0, -2.0f64..2.0),
            bias in 0.0f64..1.0,
            tol_exp in -14i32..1,
            lit_fixed in 0u8..3,
            format in proptest::bool::ANY,
        ) {
            let at = DVec2::new(at.0, at.1);
            let at = match snap {
                0 => at,
                1 => at.round(),
                2 => (at * 2.0).round() / 2.0,
                _ => at.round() + DVec2::new(0.5, 0.0),
            };
            let fraction = DVec2::new(fraction.0 as f64, fraction.1 as f64) / FRACTION_STEPS;
            let grid = Grid {
                basis: LightBasis::new(DVec3::new(-0.4, -1.0, -0.3)),
                texel: DVec2::splat(texel),
                fraction,
                start: -100.0,
                length: 300.0,
                cover: None,
                family: 0,
                seen: Fast::default(),
                used: true,
            };
            // The plane's depth at the receiver's light-space x/y, moved by up to two texels'
            // worth of its gradient: the compares fall either side of it.
            let c = (at + fraction) * texel;
            let k = 10.0 + g.0 * c.x + g.1 * c.y;
            let slope = (g.0.abs() + g.1.abs()) * texel;
            let own_depth = 10.0 + offsets.0 * slope;
            let tol = 10f64.powi(tol_exp) * slope.max(1e-9);
            let p = PlaneLookup {
                k,
                gx: g.0,
                gy: g.1,
                own_depth,
                own_only: offsets.1 > 0.0,
                tol,
                tol_lit: tol * 1.5,
                tol_unbiased: tol * 0.7,
                lit_fixed: [None, Some(true), Some(false)][lit_fixed as usize],
                fixed: None,
            };
            let pl = Placement {
                at,
                texel: (floor(at.x) as i64, floor(at.y) as i64),
                depth: 10.0 + offsets.1 * slope,
                slope,
                bias: bias * slope,
            };
            let s = Sampling {
                bias: vec![Bias::ZERO],
                format: format.then_some(DepthFormat::D16),
                ranges: vec![(10.0 - 1.5 * slope, 10.0 + 1.5 * slope)],
                pcf: 1,
                filter: PcfFilter::Bilinear,
                binary32: None,
            };
            proptest::prop_assert_eq!(p.answer_bilinear(&grid, &s, 0, &pl), p.answer_any(&grid, &s, 0, &pl));
            proptest::prop_assert_eq!(p.answer(&grid, &s, 0, &pl), p.answer_any(&grid, &s, 0, &pl));
        }
    }

    /// [`bilinear_tap`] hands out [`each_footprint`]'s texels at PCF 1 (bilinear), their
    /// centres ([`Grid::centre`]) and weights, to the bit: placements spread over ±3,000
    /// texels and on whole, half and quarter texels and ±0, on grids of random fractions and
    /// texel sizes.
    #[test]
    fn the_bilinear_tap_is_the_footprint_to_the_bit() {
        let mut rng = SplitMix64::new(5);
        let mut ats: Vec<DVec2> = (0..2000)
            .map(|_| DVec2::new(rng.range(-3000.0, 3000.0), rng.range(-3000.0, 3000.0)))
            .collect();
        for x in [-2.0, -1.5, -0.75, -0.5, -0.0, 0.0, 0.25, 0.5, 1.0, 7.25, 1e6 + 0.5] {
            ats.extend([DVec2::new(x, 3.5), DVec2::new(0.5, x), DVec2::splat(x)]);
        }
        for (n, at) in ats.into_iter().enumerate() {
            let fraction = DVec2::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0));
            let grid = Grid {
                basis: LightBasis::new(DVec3::new(-0.4, -1.0, -0.3)),
                texel: DVec2::new(rng.range(1e-3, 3.0), rng.range(1e-3, 3.0)),
                fraction: if n % 3 == 0 {
                    DVec2::ZERO
                } else {
                    (fraction * FRACTION_STEPS).floor() / FRACTION_STEPS
                },
                start: 0.0,
                length: 1.0,
                cover: None,
                family: 0,
                seen: Fast::default(),
                used: true,
            };
            let mut want = Vec::new();
            each_footprint(at, 1, PcfFilter::Bilinear, |g, w| {
                want.push((grid.centre(g), w));
                true
            });
            let got: Vec<(DVec2, f64)> = bilinear_tap(&grid, at).into_iter().filter(|(_, w)| *w > 0.0).collect();
            let bits = |v: &[(DVec2, f64)]| {
                v.iter()
                    .map(|(c, w)| (c.x.to_bits(), c.y.to_bits(), w.to_bits()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(
                bits(&got),
                bits(&want),
                "at {at} on {:?} x {:?}",
                grid.fraction,
                grid.texel
            );
        }
    }

    #[test]
    fn floor_is_f64_floor_to_the_bit() {
        let mut xs = vec![
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
            1e300,
            -1e300,
        ];
        for k in -5i64..=5 {
            let x = k as f64;
            xs.extend([x, x.next_up(), x.next_down(), x + 0.5]);
        }
        for e in 50..=54 {
            let x = 2f64.powi(e);
            xs.extend([
                x,
                -x,
                x.next_up(),
                x.next_down(),
                -x.next_down(),
                -x.next_up(),
                x + 0.5,
                -x - 0.5,
            ]);
        }
        let mut rng = crate::rng::SplitMix64::new(3);
        xs.extend((0..10_000).map(|_| rng.range(-1e6, 1e6)));
        xs.extend([2f64.powi(63), -(2f64.powi(63)), 2f64.powi(63).next_down(), 1e19, -1e19]);
        for x in xs {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x}");
            // One conversion: the same integer as `floor` and then `as i64` (saturating).
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
        assert!(floor(f64::NAN).is_nan());
        assert_eq!(floor_i64(f64::NAN), 0);
    }
}
