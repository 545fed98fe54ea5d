//! Scene geometry as a triangle soup: the receivers and casters the player actually sees.
//!
//! Three sources build it (any combination): a ground quad at height `Y` over the bounds' x/z
//! extent, solid boxes (twelve triangles each), and the triangles of a glTF file (loaded by the
//! config layer, node transforms applied). Coordinates are world units in the crate's frame
//! (right-handed, +Y up, see [`crate::geometry`]). Winding is irrelevant: the visibility pass
//! turns every normal toward the camera. Triangles with zero area are dropped when added:
//! they can neither receive nor cast.
//!
//! **Objects.** The triangles are also grouped into the objects an engine would draw, one draw
//! call each: the ground quad, each box, and each glTF mesh primitive under each node that
//! instances it. [`Mesh::objects`] keeps each object's triangle range and world bounds (what
//! the cost counts of [`crate::cost`] cull against). A triangle added with [`Mesh::push`] outside
//! [`Mesh::add_object`] belongs to no object and is never counted as a caster.

use std::ops::Range;

use glam::DVec3;

use crate::geometry::Aabb;

/// A triangle soup, world units, and the draw calls it is made of.
#[derive(Clone, Default, PartialEq)]
pub struct Mesh {
    pub triangles: Vec<[DVec3; 3]>,
    /// The objects (draw calls), in the order they were added; their triangle ranges are
    /// disjoint and increasing.
    pub objects: Vec<MeshObject>,
}

/// What kind of thing an object is (for tables and docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectKind {
    /// The ground quad (`scene.ground`).
    Ground,
    /// A box (`[[scene.box]]`).
    Box,
    /// One glTF mesh primitive under one node.
    Primitive,
}

/// One draw call: a contiguous range of [`Mesh::triangles`] and the world bounds of its vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshObject {
    pub kind: ObjectKind,
    pub triangles: Range<usize>,
    pub bounds: Aabb,
}

impl std::fmt::Debug for Mesh {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mesh({} triangles)", self.triangles.len())
    }
}

impl Mesh {
    /// Adds a triangle unless its area is zero (or not finite).
    pub fn push(&mut self, t: [DVec3; 3]) {
        let area2 = (t[1] - t[0]).cross(t[2] - t[0]).length();
        if area2 > 0.0 && area2.is_finite() {
            self.triangles.push(t);
        }
    }

    /// Adds the triangles of one object (one draw call; zero-area triangles dropped as by
    /// [`Mesh::push`]). An object left without triangles is not recorded.
    pub fn add_object(&mut self, kind: ObjectKind, triangles: impl IntoIterator<Item = [DVec3; 3]>) {
        let start = self.triangles.len();
        for t in triangles {
            self.push(t);
        }
        let end = self.triangles.len();
        if end == start {
            return;
        }
        let mut it = self.triangles[start..end].iter().flatten();
        let first = *it.next().expect("a non-empty range");
        let (lo, hi) = it.fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        self.objects.push(MeshObject {
            kind,
            triangles: start..end,
            bounds: Aabb::new(lo, hi),
        });
    }

    /// A horizontal quad at height `y` over `[x0, x1] x [z0, z1]` (two triangles, one object).
    pub fn add_ground(&mut self, y: f64, x0: f64, x1: f64, z0: f64, z1: f64) {
        let a = DVec3::new(x0, y, z0);
        let b = DVec3::new(x1, y, z0);
        let c = DVec3::new(x1, y, z1);
        let d = DVec3::new(x0, y, z1);
        self.add_object(ObjectKind::Ground, [[a, b, c], [a, c, d]]);
    }

    /// The six faces of a box (twelve triangles, one object; faces of a flat box with zero area
    /// are dropped).
    pub fn add_box(&mut self, b: &Aabb) {
        let p = |x: bool, y: bool, z: bool| {
            DVec3::new(
                if x { b.max.x } else { b.min.x },
                if y { b.max.y } else { b.min.y },
                if z { b.max.z } else { b.min.z },
            )
        };
        // Each face as four corners in order around it.
        let faces = [
            [
                p(false, false, false),
                p(false, true, false),
                p(false, true, true),
                p(false, false, true),
            ],
            [
                p(true, false, false),
                p(true, true, false),
                p(true, true, true),
                p(true, false, true),
            ],
            [
                p(false, false, false),
                p(true, false, false),
                p(true, false, true),
                p(false, false, true),
            ],
            [
                p(false, true, false),
                p(true, true, false),
                p(true, true, true),
                p(false, true, true),
            ],
            [
                p(false, false, false),
                p(true, false, false),
                p(true, true, false),
                p(false, true, false),
            ],
            [
                p(false, false, true),
                p(true, false, true),
                p(true, true, true),
                p(false, true, true),
            ],
        ];
        let tris = faces.into_iter().flat_map(|[a, b, c, d]| [[a, b, c], [a, c, d]]);
        self.add_object(ObjectKind::Box, tris);
    }

    /// The bounding box of every vertex, or None for an empty mesh.
    pub fn bounds(&self) -> Option<Aabb> {
        let mut it = self.triangles.iter().flatten();
        let first = *it.next()?;
        let (lo, hi) = it.fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        Some(Aabb::new(lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_has_twelve_triangles_and_its_own_bounds() {
        let b = Aabb::new(DVec3::new(-1.0, 0.0, 2.0), DVec3::new(3.0, 5.0, 4.0));
        let mut m = Mesh::default();
        m.add_box(&b);
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.bounds(), Some(b));
        assert_eq!(m.objects.len(), 1);
        assert_eq!(m.objects[0].triangles, 0..12);
        assert_eq!(m.objects[0].bounds, b);
    }

    #[test]
    fn a_flat_box_keeps_only_faces_with_area() {
        let b = Aabb::new(DVec3::new(0.0, 1.0, 0.0), DVec3::new(2.0, 1.0, 2.0));
        let mut m = Mesh::default();
        m.add_box(&b);
        assert_eq!(m.triangles.len(), 4);
        assert_eq!(m.objects[0].triangles, 0..4);
    }

    #[test]
    fn objects_keep_their_ranges_and_bounds_and_skip_empty_ones() {
        let mut m = Mesh::default();
        m.add_ground(0.0, -5.0, 5.0, -2.0, 2.0);
        let p = DVec3::new(1.0, 1.0, 1.0);
        m.add_object(ObjectKind::Primitive, [[p, p, p]]);
        let t = [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 3.0, -1.0)];
        m.add_object(ObjectKind::Primitive, [t]);
        assert_eq!(m.objects.len(), 2);
        assert_eq!(m.objects[0].triangles, 0..2);
        assert_eq!(m.objects[0].kind, ObjectKind::Ground);
        assert_eq!(m.objects[1].triangles, 2..3);
        assert_eq!(
            m.objects[1].bounds,
            Aabb::new(DVec3::new(0.0, 0.0, -1.0), DVec3::new(1.0, 3.0, 0.0))
        );
    }
}
