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
    if v.is_empty() {
        return false;
    }
    let ca = 0.5 * (b.min + b.max);
    let ea = 0.5 * (b.max - b.min);
    let axes_b = [v.basis.x, v.basis.y, v.basis.z];
    let cl = 0.5 * (v.lo + v.hi);
    let eb = 0.5 * (v.hi - v.lo);
    let cb = v.basis.world_from_light() * cl;
    let d = cb - ca;
    let eb_arr = [eb.x, eb.y, eb.z];
    // Radius of box A (world axes) and box B (light axes) along `axis`.
    let ra = |axis: DVec3| ea.x * axis.x.abs() + ea.y * axis.y.abs() + ea.z * axis.z.abs();
    let rb = |axis: DVec3| (0..3).map(|k| eb_arr[k] * axis.dot(axes_b[k]).abs()).sum::<f64>();
    let separated = |axis: DVec3| {
        let len = axis.length();
        // A near-zero cross product (parallel edges) is not a separating direction of its own:
        // the face axes cover that case.
        if len < 1e-12 {
            return false;
        }
        d.dot(axis).abs() > ra(axis) + rb(axis) + 1e-12 * (1.0 + d.length() + ea.length() + eb.length()) * len
    };
    let world = [DVec3::X, DVec3::Y, DVec3::Z];
    for a in world {
        if separated(a) {
            return false;
        }
    }
    for a in axes_b {
        if separated(a) {
            return false;
        }
    }
    for a in world {
        for b in axes_b {
            if separated(a.cross(b)) {
                return false;
            }
        }
    }
    true
}

/// Clips a convex polygon (light coordinates) to the half-space `sign * p[axis] <= sign * bound`
/// (Sutherland-Hodgman, one plane).
fn clip_plane<const N: usize>(poly: &[[f64; N]], axis: usize, bound: f64, keep_below: bool, out: &mut Vec<[f64; N]>) {
    out.clear();
    let inside = |p: &[f64; N]| if keep_below { p[axis] <= bound } else { p[axis] >= bound };
    let n = poly.len();
    for i in 0..n {
        let a = &poly[i];
        let b = &poly[(i + 1) % n];
        let (ia, ib) = (inside(a), inside(b));
        if ia {
            out.push(*a);
        }
        if ia != ib {
            let t = (bound - a[axis]) / (b[axis] - a[axis]);
            let mut p = [0.0; N];
            for k in 0..N {
                p[k] = a[k] + t * (b[k] - a[k]);
            }
            p[axis] = bound;
            out.push(p);
        }
    }
}

/// Whether a triangle (light coordinates) intersects the closed box `[lo, hi]`: its clip by
/// the box's six planes is not empty.
pub fn triangle_meets_box(t: &[DVec3; 3], lo: DVec3, hi: DVec3) -> bool {
    let mut poly: Vec<[f64; 3]> = t.iter().map(|p| p.to_array()).collect();
    let mut next = Vec::with_capacity(9);
    for axis in 0..3 {
        for (bound, below) in [(lo[axis], false), (hi[axis], true)] {
            clip_plane(&poly, axis, bound, below, &mut next);
            std::mem::swap(&mut poly, &mut next);
            if poly.is_empty() {
                return false;
            }
        }
    }
    true
}

/// The area of a triangle's projection on the light plane (light x/y) clipped to the
/// rectangle `[lo, hi]`, exactly (Sutherland-Hodgman, then the shoelace formula).
pub fn clipped_area(t: &[DVec3; 3], lo: DVec2, hi: DVec2) -> f64 {
    let mut poly: Vec<[f64; 2]> = t.iter().map(|p| [p.x, p.y]).collect();
    let mut next = Vec::with_capacity(7);
    for axis in 0..2 {
        for (bound, below) in [(lo[axis], false), (hi[axis], true)] {
            clip_plane(&poly, axis, bound, below, &mut next);
            std::mem::swap(&mut poly, &mut next);
            if poly.len() < 3 {
                return 0.0;
            }
        }
    }
    polygon_area(&poly)
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

/// One object in a light basis.
#[derive(Debug, Clone, Copy, PartialEq)]
struct LightObject {
    /// Tight light-space bounds of its vertices.
    lo: DVec3,
    hi: DVec3,
    /// Light-space bounds of its world bounding box (for culling by bounds).
    box_lo: DVec3,
    box_hi: DVec3,
    /// Sum of its triangles' projected areas (world units²).
    area: f64,
}

/// The scene in one light basis, made once per basis and shared by every window in it.
#[derive(Debug, Clone, PartialEq)]
pub struct LightScene {
    pub basis: LightBasis,
    triangles: Vec<[DVec3; 3]>,
    objects: Vec<LightObject>,
}

impl LightScene {
    pub fn new(mesh: &Mesh, basis: &LightBasis) -> Self {
        let triangles: Vec<[DVec3; 3]> = mesh.triangles.iter().map(|t| t.map(|p| basis.to_light(p))).collect();
        let objects = mesh
            .objects
            .iter()
            .map(|o| {
                let tris = &triangles[o.triangles.clone()];
                let (lo, hi) = tris
                    .iter()
                    .flatten()
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(*p), hi.max(*p))
                    });
                let (box_lo, box_hi) = light_bounds_of(basis, &o.bounds);
                LightObject {
                    lo,
                    hi,
                    box_lo,
                    box_hi,
                    area: tris.iter().map(projected_area).sum(),
                }
            })
            .collect();
        LightScene {
            basis: *basis,
            triangles,
            objects,
        }
    }

    /// The counts of a volume in this basis, over the objects `keep` accepts (by index into
    /// [`Mesh::objects`]; `|_| true` without culling).
    pub fn counts(&self, mesh: &Mesh, v: &CasterVolume, keep: impl Fn(usize) -> bool) -> CostCounts {
        let mut out = CostCounts::default();
        if v.is_empty() {
            return out;
        }
        let (rlo, rhi) = (v.lo.truncate(), v.hi.truncate());
        let texel_area = v.texel.x * v.texel.y;
        let mut area = 0.0;
        for (k, (o, lo)) in mesh.objects.iter().zip(&self.objects).enumerate() {
            // The light-space bounds of the world box hold the box: apart from the volume on a
            // light axis, the two are apart (three of the separating axes, checked first).
            if lo.box_lo.cmpgt(v.hi).any() || lo.box_hi.cmplt(v.lo).any() {
                continue;
            }
            if !keep(k) || !aabb_meets_volume(&o.bounds, v) {
                continue;
            }
            let tris = &self.triangles[o.triangles.clone()];
            out.caster_objects += 1;
            out.caster_triangles += tris.len() as u64;
            out.caster_triangles_inside += if lo.lo.cmpge(v.lo).all() && lo.hi.cmple(v.hi).all() {
                tris.len() as u64
            } else if lo.lo.cmpgt(v.hi).any() || lo.hi.cmplt(v.lo).any() {
                0
            } else {
                tris.iter().filter(|t| triangle_meets_box(t, v.lo, v.hi)).count() as u64
            };
            let (olo, ohi) = (lo.lo.truncate(), lo.hi.truncate());
            area += if olo.cmpge(rlo).all() && ohi.cmple(rhi).all() {
                lo.area
            } else if olo.cmpgt(rhi).any() || ohi.cmplt(rlo).any() {
                0.0
            } else {
                tris.iter().map(|t| clipped_area(t, rlo, rhi)).sum()
            };
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
        if !(lo.x <= hi.x) {
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
