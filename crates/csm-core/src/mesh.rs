//! Scene geometry as a triangle soup: the receivers and casters the player actually sees.
//!
//! Three sources build it (any combination): a ground quad at height `Y` over the bounds' x/z
//! extent, solid boxes (twelve triangles each), and the triangles of a glTF file (loaded by the
//! config layer, node transforms applied). Coordinates are world units in the crate's frame
//! (right-handed, +Y up, see [`crate::geometry`]). Winding is irrelevant: the visibility pass
//! turns every normal toward the camera. Triangles with zero area are dropped when added:
//! they can neither receive nor cast.

use glam::DVec3;

use crate::geometry::Aabb;

/// A triangle soup, world units.
#[derive(Clone, Default, PartialEq)]
pub struct Mesh {
    pub triangles: Vec<[DVec3; 3]>,
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

    /// A horizontal quad at height `y` over `[x0, x1] x [z0, z1]` (two triangles).
    pub fn add_ground(&mut self, y: f64, x0: f64, x1: f64, z0: f64, z1: f64) {
        let a = DVec3::new(x0, y, z0);
        let b = DVec3::new(x1, y, z0);
        let c = DVec3::new(x1, y, z1);
        let d = DVec3::new(x0, y, z1);
        self.push([a, b, c]);
        self.push([a, c, d]);
    }

    /// The six faces of a box (twelve triangles; faces of a flat box with zero area are dropped).
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
        for [a, b, c, d] in faces {
            self.push([a, b, c]);
            self.push([a, c, d]);
        }
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
    }

    #[test]
    fn a_flat_box_keeps_only_faces_with_area() {
        let b = Aabb::new(DVec3::new(0.0, 1.0, 0.0), DVec3::new(2.0, 1.0, 2.0));
        let mut m = Mesh::default();
        m.add_box(&b);
        assert_eq!(m.triangles.len(), 4);
    }
}
