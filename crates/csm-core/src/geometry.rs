//! Conventions, stated once for the whole crate.
//!
//! * World space is right-handed with +Y up. All lengths are world units, all angles radians.
//! * The camera looks along `forward = normalise(target - position)`; `right = forward x up`,
//!   `up' = right x forward`. **View depth** `d` of a point `p` is `forward . (p - position)`:
//!   distance along the view axis, not Euclidean distance. (Engines that look down -z in view
//!   space flip the sign on input; nothing here depends on that.)
//! * Slice corners of the view frustum between depths `n` and `f` are
//!   `position + forward*z + right*(+-tanH*z) + up'*(+-tanV*z)` for `z in {n, f}`.
//!   Corner `i` uses bit 0 for the sign along right, bit 1 along up, bit 2 for near (0) / far (1).
//! * `L` is the unit direction in which light **travels** (from the sun toward the ground).
//! * Light space (`light_from_world`, a pure rotation): `z = L`, `x = normalise(world_up x z)`
//!   with world_up = +Y, falling back to +Z when `L` is within 1e-6 of vertical, `y = z x x`.
//!   There is no translation, so a texel grid in light space is anchored to the world origin and
//!   a static point keeps its light-space coordinates in every frame.

use glam::{DMat3, DVec2, DVec3};
use std::cell::Cell;

/// One of the 8 corners of a box or a frustum slice, and the single place that decodes its
/// index: bit 0 picks the low (0) or high (1) side of the first axis (light or world x, or
/// the image slope along the camera's right), bit 1 of the second axis (y, or the slope along
/// up), bit 2 of the third (z, or the slice's near (0) or far (1) depth).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Corner(pub usize);

impl Corner {
    /// `f` of every corner, in index order. (`std::array::from_fn` rather than `ALL.map`:
    /// the latter is not inlined in the per-frame loops and cost a few percent of a walk.)
    #[inline]
    pub fn each<T>(f: impl FnMut(Corner) -> T) -> [T; 8] {
        let mut f = f;
        std::array::from_fn(|i| f(Corner(i)))
    }

    /// Every corner, in index order.
    pub const ALL: [Corner; 8] = [
        Corner(0),
        Corner(1),
        Corner(2),
        Corner(3),
        Corner(4),
        Corner(5),
        Corner(6),
        Corner(7),
    ];

    /// `lo` or `hi` along the first axis.
    #[inline]
    pub fn x<T>(self, lo: T, hi: T) -> T {
        if self.0 & 1 == 0 {
            lo
        } else {
            hi
        }
    }

    /// `lo` or `hi` along the second axis.
    #[inline]
    pub fn y<T>(self, lo: T, hi: T) -> T {
        if self.0 & 2 == 0 {
            lo
        } else {
            hi
        }
    }

    /// `near` or `far` along the third axis.
    #[inline]
    pub fn z<T>(self, near: T, far: T) -> T {
        if self.0 & 4 == 0 {
            near
        } else {
            far
        }
    }

    /// The corner's image slopes `(sx, sy)` and depth of the slice `[near, far]` seen through
    /// `lens`: `(+-tanH, +-tanV, near or far)`.
    #[inline]
    pub fn of_slice(self, lens: &Lens, near: f64, far: f64) -> (f64, f64, f64) {
        (
            self.x(-lens.tan_h, lens.tan_h),
            self.y(-lens.tan_v, lens.tan_v),
            self.z(near, far),
        )
    }
}

/// Axis-aligned box in world space.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub fn new(min: DVec3, max: DVec3) -> Self {
        Aabb { min, max }
    }

    pub fn corner(&self, i: usize) -> DVec3 {
        let c = Corner(i);
        DVec3::new(
            c.x(self.min.x, self.max.x),
            c.y(self.min.y, self.max.y),
            c.z(self.min.z, self.max.z),
        )
    }

    pub fn contains(&self, p: DVec3, eps: f64) -> bool {
        p.cmpge(self.min - DVec3::splat(eps)).all() && p.cmple(self.max + DVec3::splat(eps)).all()
    }

    pub fn translated(&self, offset: DVec3) -> Self {
        Aabb::new(self.min + offset, self.max + offset)
    }

    pub fn hexahedron(&self) -> Hexahedron {
        let planes = [
            Plane::new(-DVec3::X, -self.min.x),
            Plane::new(DVec3::X, self.max.x),
            Plane::new(-DVec3::Y, -self.min.y),
            Plane::new(DVec3::Y, self.max.y),
            Plane::new(-DVec3::Z, -self.min.z),
            Plane::new(DVec3::Z, self.max.z),
        ];
        Hexahedron {
            vertices: std::array::from_fn(|i| self.corner(i)),
            planes,
        }
    }
}

/// Half-angle tangents of a symmetric perspective frustum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    /// tan(fov_y / 2)
    pub tan_v: f64,
    /// aspect * tan(fov_y / 2)
    pub tan_h: f64,
}

impl Lens {
    /// `fov_y` in radians, `aspect` = width / height.
    pub fn new(fov_y: f64, aspect: f64) -> Self {
        let tan_v = (0.5 * fov_y).tan();
        Lens {
            tan_v,
            tan_h: aspect * tan_v,
        }
    }

    /// Squared tangent of the half-diagonal field of view, `k^2 = tanH^2 + tanV^2`.
    pub fn k2(&self) -> f64 {
        self.tan_h * self.tan_h + self.tan_v * self.tan_v
    }

    /// World size of one screen pixel at view depth `d` on a surface facing the camera:
    /// `P(d) = 2 d tanV / H`. The same for every pixel (the plane z = d maps linearly).
    pub fn pixel_size(&self, depth: f64, screen_height: u32) -> f64 {
        2.0 * depth * self.tan_v / screen_height as f64
    }

    /// Pixels per unit of x/z on the image: `K = H / (2 tanV)`, so aliasing is `K*T/d`.
    pub fn pixels_per_unit_slope(&self, screen_height: u32) -> f64 {
        screen_height as f64 / (2.0 * self.tan_v)
    }
}

/// An orthonormal camera frame at a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    pub position: DVec3,
    pub forward: DVec3,
    pub right: DVec3,
    pub up: DVec3,
}

impl CameraPose {
    /// None when `target == position` or `up` is parallel to the view direction.
    pub fn look_at(position: DVec3, target: DVec3, up: DVec3) -> Option<Self> {
        Self::look_to(position, target - position, up)
    }

    /// This pose's axes at another `position`: `look_to(position, d, up)` for the `d` and `up`
    /// this pose was made from, which give the same axes (None for a non-finite position, as
    /// there).
    pub fn moved_to(&self, position: DVec3) -> Option<Self> {
        position.is_finite().then_some(CameraPose { position, ..*self })
    }

    pub fn look_to(position: DVec3, direction: DVec3, up: DVec3) -> Option<Self> {
        let forward = direction.try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        if forward.cross(up.normalize()).length() < 1e-9 {
            return None;
        }
        let up = right.cross(forward);
        if !(position.is_finite() && forward.is_finite() && right.is_finite()) {
            return None;
        }
        Some(CameraPose {
            position,
            forward,
            right,
            up,
        })
    }

    /// View depth of a world point.
    pub fn depth(&self, p: DVec3) -> f64 {
        self.forward.dot(p - self.position)
    }

    /// The world point at view depth `z` whose image-plane slopes are (sx, sy) = (x/z, y/z).
    pub fn point(&self, sx: f64, sy: f64, z: f64) -> DVec3 {
        self.position + self.forward * z + self.right * (sx * z) + self.up * (sy * z)
    }

    /// The 8 corners of the frustum slice between depths `near` and `far`.
    pub fn slice_corners(&self, lens: &Lens, near: f64, far: f64) -> [DVec3; 8] {
        Corner::each(|c| {
            let (sx, sy, z) = c.of_slice(lens, near, far);
            self.point(sx, sy, z)
        })
    }

    /// The slice as a convex hexahedron with exact (analytic) bounding planes.
    pub fn slice_hexahedron(&self, lens: &Lens, near: f64, far: f64) -> Hexahedron {
        let p = self.position;
        let side = |n: DVec3| Plane::new(n, n.dot(p));
        let planes = [
            side(-self.right - self.forward * lens.tan_h),
            side(self.right - self.forward * lens.tan_h),
            side(-self.up - self.forward * lens.tan_v),
            side(self.up - self.forward * lens.tan_v),
            Plane::new(-self.forward, -(near + self.forward.dot(p))),
            Plane::new(self.forward, far + self.forward.dot(p)),
        ];
        Hexahedron {
            vertices: self.slice_corners(lens, near, far),
            planes,
        }
    }
}

/// The light's orthonormal basis. `light_from_world` is a pure rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBasis {
    pub x: DVec3,
    pub y: DVec3,
    /// The direction light travels.
    pub z: DVec3,
    /// True when the +Z fallback reference was used (light within 1e-6 of vertical).
    pub vertical_fallback: bool,
}

impl LightBasis {
    /// `direction` need not be normalised but must be non-zero and finite.
    pub fn new(direction: DVec3) -> Self {
        let z = direction.normalize();
        // A light straight down (or up) makes world_up x z vanish; a fixed fallback reference
        // keeps the basis deterministic, so the grid does not spin from frame to frame.
        let (reference, vertical_fallback) = if DVec3::Y.cross(z).length() < 1e-6 {
            (DVec3::Z, true)
        } else {
            (DVec3::Y, false)
        };
        let x = reference.cross(z).normalize();
        let y = z.cross(x);
        LightBasis {
            x,
            y,
            z,
            vertical_fallback,
        }
    }

    /// Rows are the light axes, so `light_from_world * p` gives light-space coordinates.
    pub fn light_from_world(&self) -> DMat3 {
        DMat3::from_cols(self.x, self.y, self.z).transpose()
    }

    pub fn world_from_light(&self) -> DMat3 {
        DMat3::from_cols(self.x, self.y, self.z)
    }

    pub fn to_light(&self, p: DVec3) -> DVec3 {
        DVec3::new(self.x.dot(p), self.y.dot(p), self.z.dot(p))
    }

    pub fn to_light_xy(&self, p: DVec3) -> DVec2 {
        DVec2::new(self.x.dot(p), self.y.dot(p))
    }
}

/// Half-space `normal . p <= offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    pub normal: DVec3,
    pub offset: f64,
}

impl Plane {
    pub fn new(normal: DVec3, offset: f64) -> Self {
        Plane { normal, offset }
    }

    pub fn signed_distance(&self, p: DVec3) -> f64 {
        (self.normal.dot(p) - self.offset) / self.normal.length()
    }
}

/// A convex hexahedron (box, frustum slice, light-space window prism): 8 corners indexed by
/// bits as in [`CameraPose::slice_corners`], and its 6 bounding half-spaces given exactly,
/// so degenerate (zero-thickness) boxes keep well-defined planes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hexahedron {
    pub vertices: [DVec3; 8],
    pub planes: [Plane; 6],
}

/// The 12 edges: corner pairs that differ in exactly one index bit.
pub const HEX_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

impl Hexahedron {
    fn scale(&self) -> f64 {
        self.vertices.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max)
    }

    fn extent(&self) -> f64 {
        let mut lo = self.vertices[0];
        let mut hi = self.vertices[0];
        for v in &self.vertices {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        (hi - lo).max_element()
    }

    pub fn contains(&self, p: DVec3, eps: f64) -> bool {
        self.planes.iter().all(|pl| pl.signed_distance(p) <= eps)
    }
}

/// Range of `dir . p` over the intersection of two convex hexahedra, or None when they do not
/// meet. Exact up to rounding: a linear function attains its extremes at vertices of the
/// intersection, and each such vertex is a vertex of one solid inside the other, or where an
/// edge of one solid crosses a face plane of the other.
pub fn intersection_range(a: &Hexahedron, b: &Hexahedron, dir: DVec3) -> Option<(f64, f64)> {
    let (lo, hi) = (Cell::new(f64::INFINITY), Cell::new(f64::NEG_INFINITY));
    // A candidate whose value already lies in [lo, hi] (or is NaN, which min/max ignore) cannot
    // change the range: its inside tests, most of the work, are skipped. The same result.
    each_inside_candidate(
        a,
        b,
        dir,
        |v| v < lo.get() || v > hi.get(),
        |v| {
            lo.set(lo.get().min(v));
            hi.set(hi.get().max(v));
        },
    );
    let (lo, hi) = (lo.get(), hi.get());
    if lo <= hi {
        Some((lo, hi))
    } else {
        None
    }
}

/// The largest value of `dir . p` over the intersection of two convex hexahedra:
/// `intersection_range(a, b, dir).map(|(_, hi)| hi)`, bit for bit, with fewer inside tests.
/// [`intersection_range`]'s upper end is the largest value among its candidates (vertices of
/// one solid inside the other, edge-plane crossings inside both) that pass their inside tests,
/// whatever the order they are met in: a passing candidate above the running maximum always
/// widens it, and one at or below it never raises it. The same candidates with the same
/// operations (so the same values), but only one above the running maximum is tested, every
/// vertex first, and an edge whose two ends lie below the running maximum by more than
/// rounding is skipped (its crossings lie below it too).
pub fn intersection_max(a: &Hexahedron, b: &Hexahedron, dir: DVec3) -> Option<f64> {
    intersection_max_from(a, b, dir, &mut None)
}

/// One candidate of [`intersection_max`]: a vertex of one solid (`side` 0: of `a`, 1: of `b`),
/// or the crossing of one of its edges ([`HEX_EDGES`]) with a face plane of the other.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaxCandidate {
    Vertex { side: u8, vertex: u8 },
    Crossing { side: u8, edge: u8, plane: u8 },
}

/// [`intersection_max`], bit for bit, starting from the candidate `hint` (the one that gave
/// the maximum of a nearby pair of solids: the previous frame's), which is left holding the
/// candidate that gives this maximum. A hint that still passes its inside tests sets the
/// running maximum before the rest are met, so that nearly no other candidate is tested; the
/// maximum is that of every candidate whatever the hint.
pub fn intersection_max_from(
    a: &Hexahedron,
    b: &Hexahedron,
    dir: DVec3,
    hint: &mut Option<MaxCandidate>,
) -> Option<f64> {
    let scale = a.scale().max(b.scale());
    let size = a.extent().max(b.extent()).max(1e-300);
    let eps = 1e-9 * size + 4.0 * f64::EPSILON * scale;
    let solids = [(a, b), (b, a)];
    let values = solids.map(|(s, _)| s.vertices.map(|v| dir.dot(v)));
    // A candidate's value when it passes its inside tests (the same operations wherever it is
    // met); `wanted` is asked before the inside tests, the most of the work.
    let vertex = |side: usize, k: usize, wanted: &dyn Fn(f64) -> bool| {
        let (s, o) = solids[side];
        let value = values[side][k];
        (wanted(value) && o.contains(s.vertices[k], eps)).then_some(value)
    };
    let crossing = |side: usize, e: usize, plane: usize, wanted: &dyn Fn(f64) -> bool| {
        let (s, o) = solids[side];
        let (i, j) = HEX_EDGES[e];
        let (p, q) = (s.vertices[i], s.vertices[j]);
        let pl = &o.planes[plane];
        let denom = pl.normal.dot(q - p);
        if denom.abs() <= 1e-300 {
            return None;
        }
        let t = (pl.offset - pl.normal.dot(p)) / denom;
        if !(0.0..=1.0).contains(&t) {
            return None;
        }
        let x = p + (q - p) * t;
        let value = dir.dot(x);
        (wanted(value) && o.contains(x, eps) && s.contains(x, eps)).then_some(value)
    };
    let (mut hi, mut found, mut best) = (f64::NEG_INFINITY, false, None);
    if let Some(h) = *hint {
        let any = |v: f64| !v.is_nan();
        let value = match h {
            MaxCandidate::Vertex { side, vertex: k } => vertex(side as usize, k as usize, &any),
            MaxCandidate::Crossing { side, edge, plane } => {
                crossing(side as usize, edge as usize, plane as usize, &any)
            }
        };
        if let Some(v) = value {
            (hi, found, best) = (v, true, Some(h));
        }
    }
    // Every vertex, then every edge-plane crossing (the order does not change the maximum).
    for side in 0..2 {
        for k in 0..8 {
            let wanted = |v: f64| v > hi || !found && v == hi;
            if let Some(v) = vertex(side, k, &wanted) {
                (hi, found) = (hi.max(v), true);
                best = Some(MaxCandidate::Vertex {
                    side: side as u8,
                    vertex: k as u8,
                });
            }
        }
    }
    // A crossing lies on its edge, so its value is at most the larger of the ends' values plus
    // rounding: a few ulps of |dir|_1 x scale, far below `slack`. An edge whose ends lie below
    // the running maximum by more than `slack` has no crossing worth computing.
    let slack = 1e-12 * (1.0 + (dir.x.abs() + dir.y.abs() + dir.z.abs()) * scale);
    for side in 0..2 {
        for (e, &(i, j)) in HEX_EDGES.iter().enumerate() {
            if found && values[side][i].max(values[side][j]) + slack < hi {
                continue;
            }
            for plane in 0..solids[side].1.planes.len() {
                let wanted = |v: f64| v > hi || !found && v == hi;
                if let Some(v) = crossing(side, e, plane, &wanted) {
                    (hi, found) = (hi.max(v), true);
                    best = Some(MaxCandidate::Crossing {
                        side: side as u8,
                        edge: e as u8,
                        plane: plane as u8,
                    });
                }
            }
        }
    }
    *hint = best;
    found.then_some(hi)
}

/// The candidates for the extremes of `dir . p` over the intersection of two convex
/// hexahedra, in a fixed order: each vertex of one solid, then each crossing of its edges with
/// the other's face planes, for (a, b) and then (b, a). A candidate whose value `wanted`
/// accepts is tested for being inside (the vertex inside the other solid, the crossing inside
/// both), and `take` gets the value of one that is. `wanted` is asked first because the inside
/// tests are most of the work.
fn each_inside_candidate(a: &Hexahedron, b: &Hexahedron, dir: DVec3, wanted: impl Fn(f64) -> bool, take: impl Fn(f64)) {
    // Tolerance for "inside": relative to the coordinates involved, so a touching contact
    // still counts and rounding at 1e6 units does not reject real vertices.
    let scale = a.scale().max(b.scale());
    let size = a.extent().max(b.extent()).max(1e-300);
    let eps = 1e-9 * size + 4.0 * f64::EPSILON * scale;
    for (s, o) in [(a, b), (b, a)] {
        for v in &s.vertices {
            let value = dir.dot(*v);
            if wanted(value) && o.contains(*v, eps) {
                take(value);
            }
        }
        for &(i, j) in &HEX_EDGES {
            let p = s.vertices[i];
            let q = s.vertices[j];
            for pl in &o.planes {
                let denom = pl.normal.dot(q - p);
                if denom.abs() <= 1e-300 {
                    continue;
                }
                let t = (pl.offset - pl.normal.dot(p)) / denom;
                if !(0.0..=1.0).contains(&t) {
                    continue;
                }
                let x = p + (q - p) * t;
                let value = dir.dot(x);
                if wanted(value) && o.contains(x, eps) && s.contains(x, eps) {
                    take(value);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn light_basis_is_orthonormal_and_right_handed() {
        for d in [
            DVec3::new(-0.4, -1.0, -0.3),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1e-9, -1.0, 0.0),
        ] {
            let b = LightBasis::new(d);
            assert_relative_eq!(b.x.length(), 1.0, epsilon = 1e-12);
            assert_relative_eq!(b.y.length(), 1.0, epsilon = 1e-12);
            assert!(b.x.dot(b.y).abs() < 1e-12 && b.x.dot(b.z).abs() < 1e-12);
            assert_relative_eq!(b.x.cross(b.y).dot(b.z), 1.0, epsilon = 1e-12);
            assert_relative_eq!(b.z.dot(d.normalize()), 1.0, epsilon = 1e-12);
        }
        assert!(LightBasis::new(DVec3::NEG_Y).vertical_fallback);
        // world_up x z for a horizontal light along +X is -Z.
        let b = LightBasis::new(DVec3::X);
        assert_relative_eq!(b.x.dot(DVec3::NEG_Z), 1.0, epsilon = 1e-12);
    }

    #[test]
    fn view_depth_is_along_the_axis_not_euclidean() {
        let pose = CameraPose::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -10.0), DVec3::Y).unwrap();
        let p = pose.point(0.5, 0.25, 4.0);
        assert_relative_eq!(pose.depth(p), 4.0, epsilon = 1e-12);
        assert!(p.length() > 4.0);
    }

    #[test]
    fn box_inside_frustum_range_is_its_depth_span() {
        let pose = CameraPose::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::Y).unwrap();
        let lens = Lens::new(60f64.to_radians(), 1.0);
        let frustum = pose.slice_hexahedron(&lens, 0.1, 100.0);
        let small = Aabb::new(DVec3::new(-1.0, -1.0, -20.0), DVec3::new(1.0, 1.0, -10.0));
        let (lo, hi) = intersection_range(&frustum, &small.hexahedron(), pose.forward).unwrap();
        assert_relative_eq!(lo, 10.0, epsilon = 1e-9);
        assert_relative_eq!(hi, 20.0, epsilon = 1e-9);
        // A huge box around the camera: the frustum itself bounds the range.
        let huge = Aabb::new(DVec3::splat(-1e4), DVec3::splat(1e4));
        let (lo, hi) = intersection_range(&frustum, &huge.hexahedron(), pose.forward).unwrap();
        assert_relative_eq!(lo, 0.1, epsilon = 1e-9);
        assert_relative_eq!(hi, 100.0, epsilon = 1e-9);
        // Behind the camera: nothing.
        let behind = Aabb::new(DVec3::new(-1.0, -1.0, 5.0), DVec3::new(1.0, 1.0, 6.0));
        assert!(intersection_range(&frustum, &behind.hexahedron(), pose.forward).is_none());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig { cases: 256, ..Default::default() })]

        /// The upper end alone equals `intersection_range`'s, bit for bit (and both miss
        /// together), from no hint and from every candidate as the hint: camera slices against boxes, in both orders, along random directions,
        /// with coordinates on a coarse grid in half the cases (features touching: ties).
        #[test]
        fn intersection_max_is_the_upper_end_of_intersection_range(
            eye in proptest::array::uniform3(-20.0..20.0f64),
            look in proptest::array::uniform3(-1.0..1.0f64),
            fov in 10.0..120.0f64,
            aspect in 0.5..2.5f64,
            (near, far) in (0.05..30.0f64, 1.0..200.0f64),
            corner in proptest::array::uniform3(-60.0..60.0f64),
            size in proptest::array::uniform3(0.0..80.0f64),
            dir in proptest::array::uniform3(-1.0..1.0f64),
            grid in proptest::bool::ANY,
        ) {
            let snap = |x: f64| if grid { (x / 4.0).round() * 4.0 } else { x };
            let v = |a: [f64; 3]| DVec3::new(snap(a[0]), snap(a[1]), snap(a[2]));
            let Some(pose) = CameraPose::look_to(v(eye), DVec3::from_array(look), DVec3::Y) else {
                return Ok(());
            };
            let lens = Lens::new(fov.to_radians(), aspect);
            let slice = pose.slice_hexahedron(&lens, near, near + far);
            let lo = v(corner);
            let boxed = Aabb::new(lo, lo + v(size)).hexahedron();
            let dir = DVec3::from_array(dir);
            // Every candidate as a hint (the one a nearby frame might leave), and no hint.
            let hints = (0..2u8)
                .flat_map(|side| (0..8u8).map(move |vertex| MaxCandidate::Vertex { side, vertex }))
                .chain((0..2u8).flat_map(|side| {
                    (0..12u8).flat_map(move |edge| (0..6u8).map(move |plane| MaxCandidate::Crossing { side, edge, plane }))
                }));
            for (a, b) in [(&slice, &boxed), (&boxed, &slice)] {
                let max = intersection_max(a, b, dir).map(f64::to_bits);
                let range = intersection_range(a, b, dir).map(|(_, hi)| hi.to_bits());
                proptest::prop_assert_eq!(max, range);
                // The candidate it leaves gives the maximum again from itself.
                let mut left = None;
                intersection_max_from(a, b, dir, &mut left);
                let mut again = left;
                proptest::prop_assert_eq!(intersection_max_from(a, b, dir, &mut again).map(f64::to_bits), range);
                proptest::prop_assert_eq!(again, left);
                for h in hints.clone() {
                    let mut hint = Some(h);
                    proptest::prop_assert_eq!(intersection_max_from(a, b, dir, &mut hint).map(f64::to_bits), range);
                }
            }
        }
    }
}
