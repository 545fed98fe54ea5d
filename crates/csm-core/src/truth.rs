//! Ground truth: the shadow maps sampled the way a GPU samples them, against the exact answer.
//!
//! **The map.** A cascade's depth map holds, at each texel centre, the light depth of the first
//! surface a ray along the light meets there (the point-sampling rasterisation rule; both faces
//! of every triangle cast, no culling). Maps are never rasterised whole: [`ShadowMaps`] casts the
//! ray of a texel the first time a receiver reads it and keeps the depth, keyed by the texel's
//! grid (cascade, light basis, texel size and the window origin's fraction of a texel) and its
//! whole-texel index on that grid. A snapped window moves by whole texels, so its grid stays the
//! same and every frame reuses the texels read before; an unsnapped window's fraction changes
//! each frame, so its grid is new each frame and only texels shared within the frame are reused
//! (a grid not read in a frame is dropped). The fraction is rounded to `2^-20` texel for the key
//! and for the texel centres (a shift below a millionth of a texel).
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

use crate::cascades::{LightPose, Rig};
use crate::fitting::Window;
use crate::geometry::{CameraPose, LightBasis};
use crate::metrics::cascade_at;
use crate::shade::{FlipImage, Shade, ShadeImage};
use crate::visibility::{SceneGeometry, Visibility};

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

/// How the maps are sampled: per-cascade bias, depth format, PCF width (1, 3 or 5) and the
/// filter of each tap.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampling {
    pub bias: Vec<Bias>,
    /// None: exact f64 depths (no quantisation).
    pub format: Option<DepthFormat>,
    /// Light depth range of each cascade over which depths are quantised (frame 0's).
    pub ranges: Vec<(f64, f64)>,
    pub pcf: u32,
    pub filter: PcfFilter,
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
            let s = (*s).filter(|s| s.lit)?;
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

/// The exact answer at `r`: None when the ray toward the light is free (truly lit), else the
/// distance along the light to the surface that blocks it. `light` is the unit direction light
/// travels; `eps` from [`epsilon`].
pub fn occluder(scene: &SceneGeometry, light: DVec3, r: &Receiver, eps: f64) -> Option<f64> {
    let origin = r.p + r.n * eps;
    // Every triangle is within the bounds' diagonal of any point inside them.
    let reach = scene.mesh.bounds().map_or(0.0, |b| {
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

struct Grid {
    basis: LightBasis,
    texel: DVec2,
    /// The window origin's fraction of a texel (rounded, see the module docs).
    fraction: DVec2,
    /// Light depth where texel rays start, and how far they go.
    start: f64,
    length: f64,
    texels: Fast<(i64, i64), Stored>,
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
    /// Rays cast for texels not yet held.
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

/// The cascades' depth maps, sampled on demand.
pub struct ShadowMaps<'a> {
    scene: &'a SceneGeometry,
    grids: Vec<Option<Grid>>,
    index: Fast<GridKey, usize>,
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
}

impl<'a> ShadowMaps<'a> {
    pub fn new(scene: &'a SceneGeometry) -> Self {
        ShadowMaps {
            scene,
            grids: Vec::new(),
            index: Fast::default(),
            stats: CacheStats::default(),
        }
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
        let id = match self.index.get(&key) {
            Some(&id) => id,
            None => {
                let (start, length) = self.ray_span(basis);
                self.grids.push(Some(Grid {
                    basis: *basis,
                    texel: w.texel,
                    fraction: fraction / FRACTION_STEPS,
                    start,
                    length,
                    texels: Fast::default(),
                    used: false,
                }));
                let id = self.grids.len() - 1;
                self.index.insert(key, id);
                id
            }
        };
        if let Some(g) = self.grids[id].as_mut() {
            g.used = true;
        }
        FrameGrid {
            id,
            first: (whole.x as i64, whole.y as i64),
            resolution: w.resolution,
        }
    }

    /// Light depth where texel rays start (before every triangle) and their length.
    fn ray_span(&self, basis: &LightBasis) -> (f64, f64) {
        let Some(b) = self.scene.mesh.bounds() else {
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
                    *slot = None;
                } else {
                    g.used = false;
                }
            }
        }
        let grids = &self.grids;
        self.index.retain(|_, id| grids[*id].is_some());
    }

    /// Casts the rays of the texels in `wanted` that are not held yet (in parallel; the
    /// result does not depend on the order).
    pub fn fetch(&mut self, mut wanted: Vec<(usize, (i64, i64))>) {
        wanted.sort_unstable();
        wanted.dedup();
        wanted.retain(|(id, g)| {
            self.grids[*id]
                .as_ref()
                .is_some_and(|grid| !grid.texels.contains_key(g))
        });
        self.stats.rays += wanted.len() as u64;
        let scene = self.scene;
        let grids = &self.grids;
        let found: Vec<Stored> = wanted
            .par_iter()
            .map(|(id, g)| {
                let grid = grids[*id].as_ref().expect("retained above");
                trace_texel(scene, grid, *g)
            })
            .collect();
        for ((id, g), s) in wanted.into_iter().zip(found) {
            if let Some(grid) = self.grids[id].as_mut() {
                grid.texels.insert(g, s);
            }
        }
    }

    /// A held texel (call [`ShadowMaps::fetch`] first); None if it was never fetched.
    pub fn stored(&self, id: usize, g: (i64, i64)) -> Option<Stored> {
        self.grids[id].as_ref()?.texels.get(&g).copied()
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
}

/// The ray of texel `g`: from its centre, before every triangle, along the light.
fn trace_texel(scene: &SceneGeometry, grid: &Grid, g: (i64, i64)) -> Stored {
    let c = grid.centre(g);
    let b = &grid.basis;
    let origin = b.x * c.x + b.y * c.y + b.z * grid.start;
    match scene.first_hit(origin, b.z, 0.0, grid.length) {
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

/// Largest depth slope per texel kept (a surface edge-on to the light).
const MAX_SLOPE_TEXELS: f64 = 1e6;

fn place(basis: LightBasis, texel: DVec2, fraction: DVec2, r: &Receiver, bias: &Bias) -> Placement {
    let t = texel.x.max(texel.y);
    let mut v = r.n * (bias.normal * t);
    if bias.offset == NormalOffset::Lateral {
        v *= 1.0 - r.n.dot(-basis.z).max(0.0);
        v -= basis.z * v.dot(basis.z);
    }
    let p = r.p + v;
    let q = DVec2::new(basis.x.dot(p), basis.y.dot(p));
    let s = q / texel - fraction;
    let nz = r.n.dot(basis.z);
    let slope = if nz.abs() > 0.0 {
        ((r.n.dot(basis.x) / nz).abs() * texel.x)
            .max((r.n.dot(basis.y) / nz).abs() * texel.y)
            .min(MAX_SLOPE_TEXELS * t)
    } else {
        MAX_SLOPE_TEXELS * t
    };
    Placement {
        at: s,
        texel: (s.x.floor() as i64, s.y.floor() as i64),
        depth: basis.z.dot(p),
        slope,
        bias: bias.facing.apply(bias.depth + bias.slope * slope, r.n.dot(-basis.z)),
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
                PcfFilter::Nearest => out[0] = ((t.x.floor() as i64, t.y.floor() as i64), tap),
                PcfFilter::Bilinear => {
                    let b = t - DVec2::splat(0.5);
                    let i0 = b.floor();
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

/// Every cascade's grid in a frame (`light` is the frame's light: the rig's, until lights move).
pub fn frame_grids(
    maps: &mut ShadowMaps,
    rig: &Rig,
    light: &LightBasis,
    pose: &CameraPose,
    snapped: bool,
) -> Vec<FrameGrid> {
    let lp = LightPose::new(light, pose);
    (0..rig.cascade_count())
        .map(|i| {
            let w = rig.window(i, &lp, snapped);
            let basis = rig.basis(i, &lp);
            maps.grid(i, &basis, &w)
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
    answer_with(maps, fg, r, s, cascade, &s.bias[cascade])
}

fn answer_with(
    maps: &ShadowMaps,
    fg: &FrameGrid,
    r: &Receiver,
    s: &Sampling,
    cascade: usize,
    bias: &Bias,
) -> Option<Answer> {
    let pl = maps.place(fg.id, r, bias);
    if !inside(fg, pl.texel) {
        return None;
    }
    let (near, far) = s.ranges[cascade];
    let own_depth = maps.basis(fg.id).z.dot(r.p);
    let (mut lit_w, mut lit_n, mut unb_w, mut unb_n) = (0.0, 0u32, 0.0, 0u32);
    let mut own_only = true;
    for (g, w) in footprint(pl.at, s.pcf, s.filter) {
        let held = maps.stored(fg.id, g);
        let stored = held.map_or(f64::INFINITY, |x| x.depth);
        let stored = s.format.map_or(stored, |f| f.quantise(stored, near, far));
        if pl.depth <= stored + pl.bias {
            lit_w += w;
            lit_n += 1;
        }
        if own_depth <= stored {
            unb_w += w;
            unb_n += 1;
        }
        own_only &= held
            .and_then(|x| x.triangle)
            .is_some_and(|t| same_plane(maps.scene, t, r));
    }
    let pass = |w: f64, n: u32| match s.filter {
        // Whole counts for the vote: no rounding of 1/k² sums.
        PcfFilter::Nearest => 2 * n >= s.pcf * s.pcf,
        PcfFilter::Bilinear => w >= 0.5,
    };
    Some(Answer {
        lit: pass(lit_w, lit_n),
        own_only,
        lit_unbiased: pass(unb_w, unb_n),
    })
}

/// One receiver's key in a frame: its cascade, grid and texel (its state is a function of it).
type Key = Option<(usize, usize, (i64, i64))>;

fn key_of(maps: &ShadowMaps, grids: &[FrameGrid], rig: &Rig, pose: &CameraPose, r: &Receiver, s: &Sampling) -> Key {
    let i = reading_cascade(rig, pose, r.p)?;
    let fg = &grids[i];
    let pl = maps.place(fg.id, r, &s.bias[i]);
    inside(fg, pl.texel).then_some((i, fg.id, pl.texel))
}

/// The texels receiver `r` reads in grid `fg` of cascade `i` under the sampling's bias.
fn texels_read(maps: &ShadowMaps, fg: &FrameGrid, r: &Receiver, s: &Sampling, i: usize) -> Vec<(usize, (i64, i64))> {
    let pl = maps.place(fg.id, r, &s.bias[i]);
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
    let grids = frame_grids(maps, rig, light, pose, snapped);
    let keys: Vec<Key> = points
        .par_iter()
        .map(|r| key_of(maps, &grids, rig, pose, r, s))
        .collect();
    let wanted: Vec<(usize, (i64, i64))> = points
        .iter()
        .zip(&keys)
        .filter_map(|(r, k)| k.map(|(i, _, _)| texels_read(maps, &grids[i], r, s, i)))
        .flatten()
        .collect();
    maps.stats.reads += wanted.len() as u64;
    maps.fetch(wanted);
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
#[allow(clippy::too_many_arguments)]
pub fn flicker(
    scene: &SceneGeometry,
    rig: &Rig,
    light: &LightBasis,
    poses: impl Iterator<Item = CameraPose>,
    snapped: bool,
    points: &[Receiver],
    s: &Sampling,
    on_frame: &mut dyn FnMut(usize, &[Option<Answer>]),
) -> Flicker {
    flicker_cached(
        scene,
        rig,
        light,
        poses,
        snapped,
        points,
        s,
        crate::walk::Cadence::EVERY_FRAME,
        on_frame,
    )
}

/// [`flicker`] with cached cascades: a cascade not rendered again in a frame (see
/// [`crate::walk::Cadence`]) keeps the window, and so the map, of its last update; a receiver
/// it serves then keeps its texel and its state, and one that the held window no longer holds
/// has no answer (its step is not counted). With [`crate::walk::Cadence::EVERY_FRAME`] this is
/// [`flicker`].
#[allow(clippy::too_many_arguments)]
pub fn flicker_cached(
    scene: &SceneGeometry,
    rig: &Rig,
    light: &LightBasis,
    poses: impl Iterator<Item = CameraPose>,
    snapped: bool,
    points: &[Receiver],
    s: &Sampling,
    cadence: crate::walk::Cadence<'_>,
    on_frame: &mut dyn FnMut(usize, &[Option<Answer>]),
) -> Flicker {
    let m = rig.cascade_count();
    let mut held: Vec<Option<(LightBasis, Window)>> = vec![None; m];
    let mut update_flips = vec![0u64; m];
    let mut update_steps = vec![0u64; m];
    let mut maps = ShadowMaps::new(scene);
    let n = points.len();
    let mut keys: Vec<Key> = vec![None; n];
    let mut states: Vec<Option<Answer>> = vec![None; n];
    let mut flips = vec![0u32; n];
    let mut steps = vec![0u32; n];
    let (mut total_flips, mut edge_flips, mut total_steps) = (0u64, 0u64, 0u64);
    // A bilinear tap reads 2x2 texels.
    let per_tap = if s.filter == PcfFilter::Bilinear { 4 } else { 1 };
    let mut frames = 0;
    for (t, pose) in poses.enumerate() {
        frames += 1;
        let grids = if cadence.caches() {
            let lp = LightPose::new(light, &pose);
            (0..m)
                .map(|i| {
                    let (basis, w) = match held[i] {
                        Some(h) if !cadence.updates(i, t) => h,
                        _ => (rig.basis(i, &lp), rig.window(i, &lp, snapped)),
                    };
                    held[i] = Some((basis, w));
                    maps.grid(i, &basis, &w)
                })
                .collect()
        } else {
            frame_grids(&mut maps, rig, light, &pose, snapped)
        };
        let new_keys: Vec<Key> = points
            .par_iter()
            .map(|r| key_of(&maps, &grids, rig, &pose, r, s))
            .collect();
        let k2 = (s.pcf * s.pcf * per_tap) as u64;
        maps.stats.reads += new_keys.iter().flatten().count() as u64 * k2;
        // Texels to fetch: those of receivers whose key changed.
        let changed: Vec<usize> = (0..n)
            .filter(|&j| new_keys[j].is_some() && new_keys[j] != keys[j])
            .collect();
        let wanted: Vec<(usize, (i64, i64))> = changed
            .iter()
            .flat_map(|&j| {
                let (i, _, _) = new_keys[j].expect("changed keys are Some");
                texels_read(&maps, &grids[i], &points[j], s, i)
            })
            .collect();
        maps.fetch(wanted);
        let answers: Vec<Option<Answer>> = changed
            .par_iter()
            .map(|&j| {
                let (i, _, _) = new_keys[j].expect("changed keys are Some");
                answer(&maps, &grids[i], &points[j], s, i)
            })
            .collect();
        let mut next = states.clone();
        for j in 0..n {
            if new_keys[j].is_none() {
                next[j] = None;
            }
        }
        for (&j, a) in changed.iter().zip(answers) {
            next[j] = a;
        }
        if t > 0 {
            for j in 0..n {
                let same_cascade = matches!((keys[j], new_keys[j]), (Some(a), Some(b)) if a.0 == b.0);
                if let (true, Some(a), Some(b)) = (same_cascade, states[j], next[j]) {
                    steps[j] += 1;
                    total_steps += 1;
                    let i = new_keys[j].map_or(0, |k| k.0);
                    let update = cadence.updates(i, t);
                    update_steps[i] += u64::from(update);
                    if a.lit != b.lit {
                        update_flips[i] += u64::from(update);
                        flips[j] += 1;
                        total_flips += 1;
                        if !(a.own_only && b.own_only) {
                            edge_flips += 1;
                        }
                    }
                }
            }
        }
        on_frame(t, &next);
        states = next;
        keys = new_keys;
        maps.end_frame();
    }
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
        flips,
        steps,
        frames,
        stats: maps.stats,
        update_flips,
        update_steps,
    }
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
pub fn frame_zero(
    scene: &SceneGeometry,
    rig: &Rig,
    light: &LightBasis,
    pose: &CameraPose,
    snapped: bool,
    points: &[Receiver],
    s: &Sampling,
) -> (Vec<PointZero>, CacheStats) {
    let lp = LightPose::new(light, pose);
    let windows: Vec<(LightBasis, Window)> = (0..rig.cascade_count())
        .map(|i| (rig.basis(i, &lp), rig.window(i, &lp, snapped)))
        .collect();
    let cascades: Vec<Option<usize>> = points.par_iter().map(|r| reading_cascade(rig, pose, r.p)).collect();
    frame_zero_in(scene, light, &windows, &cascades, points, s)
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
    let eps = epsilon(scene);
    let zero: Vec<Option<Placement>> = points
        .par_iter()
        .zip(cascades)
        .map(|(r, c)| c.map(|i| maps.place(grids[i].id, r, &Bias::ZERO)))
        .collect();
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
    let out = points
        .par_iter()
        .enumerate()
        .map(|(j, r)| {
            let occ = occluder(scene, light.z, r, eps);
            let truly_lit = occ.is_none();
            let (cascade, answer, excess, own, slope, needed) = match (cascades[j], zero[j]) {
                (Some(i), Some(z)) if inside(&grids[i], z.texel) => {
                    let fg = &grids[i];
                    let stored = maps.stored(fg.id, z.texel).expect("fetched");
                    let own = stored.triangle.is_some_and(|t| same_plane(scene, t, r));
                    let reads: Vec<(f64, f64, bool)> = footprint(z.at, s.pcf, s.filter)
                        .map(|(g, w)| {
                            let st = maps.stored(fg.id, g).expect("fetched");
                            let own = st.triangle.is_some_and(|t| same_plane(scene, t, r));
                            (z.depth - st.depth, w, own)
                        })
                        .collect();
                    let can_be_acne = truly_lit && reads.iter().all(|x| x.2);
                    let needed = can_be_acne.then(|| needed_bias(reads.iter().map(|x| (x.0, x.1)).collect(), s));
                    (
                        Some(i),
                        answer(&maps, fg, r, s, i),
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

/// The picture of one frame's answers over the visibility grid.
pub fn shade_image(
    cols: u32,
    rows: u32,
    points: &[Receiver],
    truly_lit: &[bool],
    states: &[Option<Answer>],
) -> ShadeImage {
    let mut image = ShadeImage::empty(cols, rows);
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
