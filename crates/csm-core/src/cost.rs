//! What a cascade costs to render: the draw calls, triangles and fragments of its casters.
//!
//! **The caster volume** of a cascade is a box in its light space: the window's rectangle in
//! light x/y, and light depths from the scene's light-near plane (the smallest light depth of
//! the scene bounds) to the cascade's light far. An engine draws every object whose bounds
//! meet that box.
//!
//! **Counts** (one cascade, one frame), over the objects of [`Mesh::objects`] (one draw call
//! each):
//! - `caster_objects`: the objects whose world bounds (an axis-aligned box) intersect the
//!   caster volume (an oriented box in world space), decided exactly by the separating-axis
//!   test of two boxes (15 axes: the 3 + 3 face normals and the 9 edge cross products);
//! - `caster_triangles`: the triangles of those objects;
//! - `caster_triangles_inside`: those of their triangles that intersect the volume (what a
//!   per-triangle culler keeps), decided by clipping the triangle against the box's six planes
//!   (non-empty result: it intersects);
//! - `raster_fragments`: the area of the caster objects' triangles (both faces, no culling)
//!   projected along the light and clipped to the window's rectangle only (not to light
//!   near/far), divided by a texel's area: the fragments rasterised, overdraw included.
//!   The clipping is exact (Sutherland-Hodgman against the rectangle's four edges).
//!
//! **Speed.** [`LightScene`] holds the scene in one light basis: every triangle in light
//! coordinates, each object's tight light-space bounds and its whole projected area. For a
//! volume, an object outside the rectangle costs nothing more, one inside it adds its
//! precomputed area and triangle count, and only objects crossing an edge are clipped triangle
//! by triangle. [`LightScene::counts`] therefore costs O(objects) plus the triangles of the
//! objects on the window's edges.
//!
//! **Receiver-aware culling** ([`ReceiverBox`]): an object is kept for a cascade only when its
//! bounds, extruded along the light to the scene's far side, meet the light-space box of that
//! cascade's visible receivers padded by the bias and the filter radius. The rule is stated in
//! `docs/cost.md`.

use glam::{DVec2, DVec3};

use crate::geometry::{Aabb, LightBasis};
use crate::mesh::Mesh;

/// One cascade's caster volume: a box in the light space of `basis` (light x, y, z).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CasterVolume {
    pub basis: LightBasis,
    /// Light-space minimum corner: the window's minimum x/y and the scene's light near.
    pub lo: DVec3,
    /// Light-space maximum corner: the window's maximum x/y and the cascade's light far.
    pub hi: DVec3,
    /// World size of one texel along light x and y (the fragment unit).
    pub texel: DVec2,
}

impl CasterVolume {
    /// False when the depth range is empty (light far before the scene's light near).
    pub fn is_empty(&self) -> bool {
        self.lo.cmpgt(self.hi).any()
    }
}

/// The smallest and largest light depth of `bounds`' corners in `basis`.
pub fn light_depth_extent(basis: &LightBasis, bounds: &Aabb) -> (f64, f64) {
    (0..8).fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), c| {
        let z = basis.z.dot(bounds.corner(c));
        (a.min(z), b.max(z))
    })
}

/// The light-space bounding box of a world box (its 8 corners in light coordinates).
pub fn light_bounds_of(basis: &LightBasis, b: &Aabb) -> (DVec3, DVec3) {
    (0..8).fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), c| {
        let p = basis.to_light(b.corner(c));
        (lo.min(p), hi.max(p))
    })
}

/// Whether the world box `b` intersects the volume: the exact separating-axis test of an
/// axis-aligned box against an oriented box (closed boxes: touching counts).
pub fn aabb_meets_volume(b: &Aabb, v: &CasterVolume) -> bool {
    SeparatingAxes::new(&v.basis).meets(b, v)
}

/// One candidate separating axis of a world box against a light-space box, with what depends
/// only on the light basis.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    axis: DVec3,
    /// `|axis|` per world component (the world box's radius along the axis).
    abs: DVec3,
    /// `|axis · b_k|` for the light axes `b_k` (the light box's radius along the axis).
    light: [f64; 3],
    len: f64,
}

/// The 15 separating axes of [`aabb_meets_volume`] in one light basis (the three world axes,
/// the three light axes, their nine cross products), made once per basis: a path or sweep
/// tests many boxes against many volumes of the same basis. The same operations in the same
/// order as a test that derives each axis on the spot, so the same answers bit for bit.
#[derive(Debug, Clone, PartialEq)]
pub struct SeparatingAxes {
    axes: Vec<Axis>,
}

impl SeparatingAxes {
    pub fn new(basis: &LightBasis) -> Self {
        let light = [basis.x, basis.y, basis.z];
        let world = [DVec3::X, DVec3::Y, DVec3::Z];
        let cross = world.iter().flat_map(|a| light.iter().map(move |b| a.cross(*b)));
        let axes = (world.into_iter().chain(light).chain(cross))
            .map(|axis| Axis {
                axis,
                abs: axis.abs(),
                light: light.map(|b| axis.dot(b).abs()),
                len: axis.length(),
            })
            // A near-zero cross product (parallel edges) is not a separating direction of its
            // own: the face axes cover that case.
            .filter(|a| a.len >= 1e-12)
            .collect();
        SeparatingAxes { axes }
    }

    /// [`aabb_meets_volume`] for a volume in this basis.
    pub fn meets(&self, b: &Aabb, v: &CasterVolume) -> bool {
        if v.is_empty() {
            return false;
        }
        let ca = 0.5 * (b.min + b.max);
        let ea = 0.5 * (b.max - b.min);
        let cl = 0.5 * (v.lo + v.hi);
        let eb = 0.5 * (v.hi - v.lo);
        let cb = v.basis.world_from_light() * cl;
        let d = cb - ca;
        let eb_arr = [eb.x, eb.y, eb.z];
        // The tolerance's scale, the same for every axis.
        let tol = 1e-12 * (1.0 + d.length() + ea.length() + eb.length());
        !self.axes.iter().any(|a| {
            let ra = ea.x * a.abs.x + ea.y * a.abs.y + ea.z * a.abs.z;
            let rb = (0..3).map(|k| eb_arr[k] * a.light[k]).sum::<f64>();
            d.dot(a.axis).abs() > ra + rb + tol * a.len
        })
    }
}

/// Most vertices a clipped triangle has: 3, plus one per clipping plane.
const MAX_VERTICES: usize = 9;

/// A convex polygon on the stack (no allocation per clip).
#[derive(Clone, Copy)]
struct Poly<const N: usize> {
    v: [[f64; N]; MAX_VERTICES],
    n: usize,
}

impl<const N: usize> Poly<N> {
    fn of(points: [[f64; N]; 3]) -> Self {
        let mut v = [[0.0; N]; MAX_VERTICES];
        v[..3].copy_from_slice(&points);
        Poly { v, n: 3 }
    }

    /// Clipped to the half-space `p[axis] <= bound` (`keep_below`) or `p[axis] >= bound`
    /// (Sutherland-Hodgman, one plane).
    fn clip(&self, axis: usize, bound: f64, keep_below: bool) -> Self {
        let mut out = Poly {
            v: [[0.0; N]; MAX_VERTICES],
            n: 0,
        };
        let inside = |p: &[f64; N]| if keep_below { p[axis] <= bound } else { p[axis] >= bound };
        for i in 0..self.n {
            let a = &self.v[i];
            let b = &self.v[(i + 1) % self.n];
            let (ia, ib) = (inside(a), inside(b));
            if ia && out.n < MAX_VERTICES {
                out.v[out.n] = *a;
                out.n += 1;
            }
            if ia != ib && out.n < MAX_VERTICES {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                let mut p: [f64; N] = std::array::from_fn(|k| a[k] + t * (b[k] - a[k]));
                p[axis] = bound;
                out.v[out.n] = p;
                out.n += 1;
            }
        }
        out
    }
}

/// Whether a triangle (light coordinates) intersects the closed box `[lo, hi]`: a vertex
/// inside decides yes, bounds apart decide no, and otherwise its clip by the box's six planes
/// is not empty.
pub fn triangle_meets_box(t: &[DVec3; 3], lo: DVec3, hi: DVec3) -> bool {
    if t.iter().any(|p| p.cmpge(lo).all() && p.cmple(hi).all()) {
        return true;
    }
    let (tlo, thi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    if tlo.cmpgt(hi).any() || thi.cmplt(lo).any() {
        return false;
    }
    let mut poly = Poly::of(t.map(|p| p.to_array()));
    for axis in 0..3 {
        for (bound, below) in [(lo[axis], false), (hi[axis], true)] {
            poly = poly.clip(axis, bound, below);
            if poly.n == 0 {
                return false;
            }
        }
    }
    true
}

/// The area of a triangle's projection on the light plane (light x/y) clipped to the
/// rectangle `[lo, hi]`, exactly (Sutherland-Hodgman, then the shoelace formula; a triangle
/// inside the rectangle keeps its area, one apart from it has none).
pub fn clipped_area(t: &[DVec3; 3], lo: DVec2, hi: DVec2) -> f64 {
    let (tlo, thi) = (t[0].min(t[1]).min(t[2]).truncate(), t[0].max(t[1]).max(t[2]).truncate());
    if tlo.cmpge(lo).all() && thi.cmple(hi).all() {
        return projected_area(t);
    }
    if tlo.cmpgt(hi).any() || thi.cmplt(lo).any() {
        return 0.0;
    }
    let mut poly = Poly::of(t.map(|p| [p.x, p.y]));
    for axis in 0..2 {
        for (bound, below) in [(lo[axis], false), (hi[axis], true)] {
            poly = poly.clip(axis, bound, below);
            if poly.n < 3 {
                return 0.0;
            }
        }
    }
    polygon_area(&poly.v[..poly.n])
}

/// The (unsigned) area of a simple polygon.
fn polygon_area(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    0.5 * twice.abs()
}

/// The projected area of a triangle on the light plane (light x/y), unclipped.
pub fn projected_area(t: &[DVec3; 3]) -> f64 {
    let (a, b, c) = (t[0], t[1], t[2]);
    0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y)).abs()
}

/// One cascade's cost counts in one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CostCounts {
    pub caster_objects: u64,
    pub caster_triangles: u64,
    pub caster_triangles_inside: u64,
    /// Texels (fractional: an exact area over a texel's area).
    pub raster_fragments: f64,
}

impl CostCounts {
    pub fn add(&mut self, o: &CostCounts) {
        self.caster_objects += o.caster_objects;
        self.caster_triangles += o.caster_triangles;
        self.caster_triangles_inside += o.caster_triangles_inside;
        self.raster_fragments += o.raster_fragments;
    }
}

/// Triangles per leaf of an object's tree.
const LEAF: usize = 8;

/// A node of an object's tree: a run of its triangles (spatially close: the object's
/// triangles are in a Morton order of their world centroids) with its light-space bounds and
/// projected area; an inner node has two children halving the run.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Chunk {
    /// Tight light-space bounds of its vertices.
    lo: DVec3,
    hi: DVec3,
    /// Sum of its triangles' projected areas (world units²).
    area: f64,
    /// Its triangles: `order[start..end]`.
    start: usize,
    end: usize,
    /// Its children in [`LightScene::chunks`]; None for a leaf.
    children: Option<(usize, usize)>,
}

/// One object in a light basis.
#[derive(Debug, Clone, PartialEq)]
struct LightObject {
    /// Tight light-space bounds of its vertices.
    lo: DVec3,
    hi: DVec3,
    /// Light-space bounds of its world bounding box (for culling by bounds).
    box_lo: DVec3,
    box_hi: DVec3,
    /// Sum of its triangles' projected areas (world units²).
    area: f64,
    /// The root of its tree in [`LightScene::chunks`].
    root: usize,
}

/// The scene in one light basis, made once per basis and shared by every window in it.
#[derive(Debug)]
pub struct LightScene {
    pub basis: LightBasis,
    /// Every triangle in light coordinates, in the mesh's order.
    triangles: Vec<[DVec3; 3]>,
    /// Triangle indices, each object's in a Morton order of their world centroids (so that a
    /// chunk of consecutive ones is compact).
    order: Vec<usize>,
    chunks: Vec<Chunk>,
    objects: Vec<LightObject>,
    /// The separating axes of this basis, for the objects' boxes against a volume.
    axes: SeparatingAxes,
    /// The counts of volumes already counted without culling, by the exact bits of the volume
    /// (a window a sweep meets again, e.g. a single cascade at every λ, is counted once).
    seen: std::sync::Mutex<std::collections::HashMap<[u64; 8], CostCounts>>,
}

/// Volumes a [`LightScene`] remembers the counts of, at most.
const REMEMBERED: usize = 1 << 14;

/// Bounds of a set of light-space triangles.
fn bounds_of<'a>(tris: impl Iterator<Item = &'a [DVec3; 3]>) -> (DVec3, DVec3) {
    tris.flatten()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

/// Builds the tree over `order[start..end]` (light-space `triangles`) into `nodes`; returns
/// its root.
fn build_tree(triangles: &[[DVec3; 3]], order: &[usize], start: usize, end: usize, nodes: &mut Vec<Chunk>) -> usize {
    if end - start <= LEAF {
        let tris = order[start..end].iter().map(|&k| &triangles[k]);
        let (lo, hi) = bounds_of(tris.clone());
        nodes.push(Chunk {
            lo,
            hi,
            area: tris.map(projected_area).sum(),
            start,
            end,
            children: None,
        });
        return nodes.len() - 1;
    }
    // Split on a leaf boundary, so every leaf but the last is full.
    let half = (end - start).div_ceil(2).div_ceil(LEAF) * LEAF;
    let a = build_tree(triangles, order, start, start + half, nodes);
    let b = build_tree(triangles, order, start + half, end, nodes);
    let (x, y) = (nodes[a], nodes[b]);
    nodes.push(Chunk {
        lo: x.lo.min(y.lo),
        hi: x.hi.max(y.hi),
        area: x.area + y.area,
        start,
        end,
        children: Some((a, b)),
    });
    nodes.len() - 1
}

/// The 30-bit Morton code of a point's place in a box (10 bits per axis).
fn morton(p: DVec3, lo: DVec3, hi: DVec3) -> u32 {
    let spread = |x: f64| {
        let mut v = (x.clamp(0.0, 1.0) * 1023.0) as u32;
        v = (v | (v << 16)) & 0x030000FF;
        v = (v | (v << 8)) & 0x0300F00F;
        v = (v | (v << 4)) & 0x030C30C3;
        (v | (v << 2)) & 0x09249249
    };
    let t = (p - lo) / (hi - lo).max(DVec3::splat(1e-300));
    spread(t.x) | (spread(t.y) << 1) | (spread(t.z) << 2)
}

impl LightScene {
    pub fn new(mesh: &Mesh, basis: &LightBasis) -> Self {
        let triangles: Vec<[DVec3; 3]> = mesh.triangles.iter().map(|t| t.map(|p| basis.to_light(p))).collect();
        let mut order: Vec<usize> = Vec::with_capacity(mesh.triangles.len());
        let mut chunks = Vec::new();
        let objects = mesh
            .objects
            .iter()
            .map(|o| {
                let start = order.len();
                let mut ids: Vec<(u32, usize)> = o
                    .triangles
                    .clone()
                    .map(|k| {
                        let t = &mesh.triangles[k];
                        (morton((t[0] + t[1] + t[2]) / 3.0, o.bounds.min, o.bounds.max), k)
                    })
                    .collect();
                ids.sort_unstable();
                order.extend(ids.into_iter().map(|(_, k)| k));
                let root = build_tree(&triangles, &order, start, order.len(), &mut chunks);
                let area = chunks[root].area;
                let (lo, hi) = bounds_of(triangles[o.triangles.clone()].iter());
                let (box_lo, box_hi) = light_bounds_of(basis, &o.bounds);
                LightObject {
                    lo,
                    hi,
                    box_lo,
                    box_hi,
                    area,
                    root,
                }
            })
            .collect();
        LightScene {
            basis: *basis,
            triangles,
            order,
            chunks,
            objects,
            axes: SeparatingAxes::new(basis),
            seen: Default::default(),
        }
    }

    /// [`LightScene::counts`] without culling, remembered per volume: a volume counted before
    /// (bit for bit the same window, depth range and texel) is not counted again.
    pub fn counts_all(&self, mesh: &Mesh, v: &CasterVolume) -> CostCounts {
        let key = [
            v.lo.x.to_bits(),
            v.lo.y.to_bits(),
            v.lo.z.to_bits(),
            v.hi.x.to_bits(),
            v.hi.y.to_bits(),
            v.hi.z.to_bits(),
            v.texel.x.to_bits(),
            v.texel.y.to_bits(),
        ];
        if let Some(c) = self.seen.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return *c;
        }
        let c = self.counts(mesh, v, |_| true);
        let mut seen = self.seen.lock().unwrap_or_else(|e| e.into_inner());
        if seen.len() < REMEMBERED {
            seen.insert(key, c);
        }
        c
    }

    /// The triangles of a chunk.
    fn tris<'a>(&'a self, c: &Chunk) -> impl Iterator<Item = &'a [DVec3; 3]> + 'a {
        self.order[c.start..c.end].iter().map(|&k| &self.triangles[k])
    }

    /// Under node `n`: how many triangles intersect the volume `v` (when `count`) and their
    /// projected area inside its rectangle (when `area`), in one walk of the tree: a node
    /// inside (apart) settles a part for its whole subtree, a leaf crossing an edge is settled
    /// triangle by triangle.
    fn walk(&self, n: usize, v: &CasterVolume, mut count: bool, mut area: bool) -> (u64, f64) {
        let c = &self.chunks[n];
        let (mut k, mut a) = (0, 0.0);
        if count {
            if c.lo.cmpge(v.lo).all() && c.hi.cmple(v.hi).all() {
                k = (c.end - c.start) as u64;
                count = false;
            } else if c.lo.cmpgt(v.hi).any() || c.hi.cmplt(v.lo).any() {
                count = false;
            }
        }
        if area {
            let (lo, hi, rlo, rhi) = (c.lo.truncate(), c.hi.truncate(), v.lo.truncate(), v.hi.truncate());
            if lo.cmpge(rlo).all() && hi.cmple(rhi).all() {
                a = c.area;
                area = false;
            } else if lo.cmpgt(rhi).any() || hi.cmplt(rlo).any() {
                area = false;
            }
        }
        if !count && !area {
            return (k, a);
        }
        match c.children {
            Some((x, y)) => {
                let (k1, a1) = self.walk(x, v, count, area);
                let (k2, a2) = self.walk(y, v, count, area);
                (k + k1 + k2, a + a1 + a2)
            }
            None => {
                let (rlo, rhi) = (v.lo.truncate(), v.hi.truncate());
                for t in self.tris(c) {
                    if count && triangle_meets_box(t, v.lo, v.hi) {
                        k += 1;
                    }
                    if area {
                        a += clipped_area(t, rlo, rhi);
                    }
                }
                (k, a)
            }
        }
    }

    /// The counts of a volume in this basis, over the objects `keep` accepts (by index into
    /// [`Mesh::objects`]; `|_| true` without culling).
    pub fn counts(&self, mesh: &Mesh, v: &CasterVolume, keep: impl Fn(usize) -> bool) -> CostCounts {
        debug_assert_eq!(v.basis, self.basis, "a volume of another basis");
        let mut out = CostCounts::default();
        if v.is_empty() {
            return out;
        }
        let texel_area = v.texel.x * v.texel.y;
        let apart3 = |lo: DVec3, hi: DVec3| lo.cmpgt(v.hi).any() || hi.cmplt(v.lo).any();
        let mut area = 0.0;
        for (k, (o, lo)) in mesh.objects.iter().zip(&self.objects).enumerate() {
            // The light-space bounds of the world box hold the box: apart from the volume on a
            // light axis, the two are apart (three of the separating axes, checked first).
            if apart3(lo.box_lo, lo.box_hi) {
                continue;
            }
            if !keep(k) || !self.axes.meets(&o.bounds, v) {
                continue;
            }
            let n = o.triangles.len() as u64;
            out.caster_objects += 1;
            out.caster_triangles += n;
            let (inside, a) = self.walk(lo.root, v, true, true);
            out.caster_triangles_inside += inside;
            area += a;
        }
        out.raster_fragments = area / texel_area;
        out
    }

    /// The light-space bounds of object `k`'s world bounding box.
    pub fn object_box(&self, k: usize) -> (DVec3, DVec3) {
        (self.objects[k].box_lo, self.objects[k].box_hi)
    }
}

/// The light-space box of one cascade's visible receivers, padded: the receiver-aware culling
/// rule's target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceiverBox {
    pub lo: DVec3,
    pub hi: DVec3,
}

impl ReceiverBox {
    /// The box of `points` (world) in `basis`, grown by `pad_xy` across the light and `pad_z`
    /// along it; None without points.
    pub fn of(basis: &LightBasis, points: impl IntoIterator<Item = DVec3>, pad_xy: f64, pad_z: f64) -> Option<Self> {
        let (lo, hi) = points
            .into_iter()
            .map(|p| basis.to_light(p))
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            });
        if lo.x > hi.x {
            return None;
        }
        let pad = DVec3::new(pad_xy, pad_xy, pad_z);
        Some(ReceiverBox {
            lo: lo - pad,
            hi: hi + pad,
        })
    }

    /// Whether an object whose light-space bounds are `[lo, hi]`, extruded along the light to
    /// `scene_far` (the scene's largest light depth), meets this box: their x and y ranges
    /// overlap and the object starts no deeper than the box ends.
    pub fn shadowed_by(&self, lo: DVec3, hi: DVec3, scene_far: f64) -> bool {
        lo.x <= self.hi.x
            && hi.x >= self.lo.x
            && lo.y <= self.hi.y
            && hi.y >= self.lo.y
            && lo.z <= self.hi.z
            && scene_far.max(hi.z) >= self.lo.z
    }
}

/// The linear cost model: weights per draw, triangle, fragment and cleared texel.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CostModel {
    pub per_draw: f64,
    pub per_triangle: f64,
    pub per_fragment: f64,
    pub per_texel_cleared: f64,
}

impl CostModel {
    /// The model's value of a set of counts (in the weights' unit).
    pub fn of(&self, draws: f64, triangles: f64, fragments: f64, texels_cleared: f64) -> f64 {
        self.per_draw * draws
            + self.per_triangle * triangles
            + self.per_fragment * fragments
            + self.per_texel_cleared * texels_cleared
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_inside_the_rectangle_keeps_its_area_and_one_across_an_edge_loses_the_part_outside() {
        let t = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 5.0),
            DVec3::new(0.0, 2.0, -1.0),
        ];
        assert!((projected_area(&t) - 2.0).abs() < 1e-12);
        assert!((clipped_area(&t, DVec2::splat(-1.0), DVec2::splat(3.0)) - 2.0).abs() < 1e-12);
        // Cut at x = 1: the part with x <= 1 is the triangle minus the corner triangle of area 0.5.
        assert!((clipped_area(&t, DVec2::splat(-1.0), DVec2::new(1.0, 3.0)) - 1.5).abs() < 1e-12);
        assert_eq!(clipped_area(&t, DVec2::splat(5.0), DVec2::splat(6.0)), 0.0);
    }
}
