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
//! coordinates, and per object its light-space bounds, its whole projected area and a tree
//! over its triangles (nodes with their bounds, area and triangle count, stored depth first,
//! the triangles in the leaves' order). For a volume, an object outside it costs a comparison,
//! a node inside the rectangle (the volume) adds its stored area (triangle count), a node
//! apart adds nothing, and only leaves crossing a plane are settled triangle by triangle:
//! with one plane crossed, by comparing the triangles' vertices with that plane; otherwise by
//! clipping, against only the planes the polygon crosses. [`LightScene::counts`] therefore
//! costs O(objects) plus the leaves on the window's edges and the volume's far plane. The
//! area is the same sum whatever is settled where: a node's area is its children's sum and a
//! leaf's the sum of its triangles' in order, so every shortcut gives the same bits.
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

    /// Whether every vertex lies in the half-space of [`Poly::clip`]: the clip would then give
    /// back the polygon unchanged (the same vertices in the same order), so it can be skipped.
    fn within(&self, axis: usize, bound: f64, keep_below: bool) -> bool {
        let v = &self.v[..self.n];
        if keep_below {
            v.iter().all(|p| p[axis] <= bound)
        } else {
            v.iter().all(|p| p[axis] >= bound)
        }
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
            // The next vertex, the first after the last (no integer division per vertex).
            let b = &self.v[if i + 1 == self.n { 0 } else { i + 1 }];
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
    meets_box(t, lo, hi, true)
}

/// [`triangle_meets_box`]; with `skip_within`, a plane the polygon already lies within is not
/// clipped (the clip would return the same vertices in the same order: the same answer).
fn meets_box(t: &[DVec3; 3], lo: DVec3, hi: DVec3, skip_within: bool) -> bool {
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
            if skip_within && poly.within(axis, bound, below) {
                continue;
            }
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
    area_in(t, lo, hi, true)
}

/// [`clipped_area`]; with `skip_within`, an edge the polygon already lies within is not
/// clipped (the clip would return the same vertices in the same order: the same area).
fn area_in(t: &[DVec3; 3], lo: DVec2, hi: DVec2, skip_within: bool) -> f64 {
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
            if skip_within && poly.within(axis, bound, below) {
                continue;
            }
            poly = poly.clip(axis, bound, below);
            if poly.n < 3 {
                return 0.0;
            }
        }
    }
    polygon_area(&poly.v[..poly.n])
}

/// [`clipped_area`] of a triangle that lies within every edge of the rectangle but one, the
/// edge `(axis, bound, below)`, and has one or two vertices on that edge's inner side (as
/// [`on_side`] decides): the same value bit for bit, without the general clip. The general
/// path skips the other three edges (the triangle lies within them) and clips by this one:
/// Sutherland-Hodgman keeps each inner vertex and adds the edge's crossing after it, in
/// vertex order, with the same arithmetic as [`Poly::clip`]; the three or four vertices it
/// gives are summed by the shoelace formula in the same order as [`polygon_area`].
fn one_edge_area(t: &[DVec3; 3], axis: usize, bound: f64, below: bool) -> f64 {
    match (axis, below) {
        (0, false) => one_edge_area_at::<0, false>(t, bound),
        (0, true) => one_edge_area_at::<0, true>(t, bound),
        (_, false) => one_edge_area_at::<1, false>(t, bound),
        (_, true) => one_edge_area_at::<1, true>(t, bound),
    }
}

/// [`one_edge_area`] with the edge's axis and side fixed (no branch on them per vertex): the
/// same vertices in the same order, and the shoelace terms of [`polygon_area`] added in its
/// order from -0 (the start of a float `sum`; a sum of 0 either way loses its sign to `abs`).
fn one_edge_area_at<const AXIS: usize, const BELOW: bool>(t: &[DVec3; 3], bound: f64) -> f64 {
    let v = t.map(|p| [p.x, p.y]);
    let side = |x: f64| if BELOW { x <= bound } else { x >= bound };
    let inner = [side(v[0][AXIS]), side(v[1][AXIS]), side(v[2][AXIS])];
    let mut out = [[0.0; 2]; 4];
    let mut n = 0;
    for i in 0..3 {
        let j = if i == 2 { 0 } else { i + 1 };
        let (a, b) = (v[i], v[j]);
        if inner[i] {
            out[n] = a;
            n += 1;
        }
        if inner[i] != inner[j] {
            let s = (bound - a[AXIS]) / (b[AXIS] - a[AXIS]);
            let mut p = [0.0; 2];
            p[1 - AXIS] = a[1 - AXIS] + s * (b[1 - AXIS] - a[1 - AXIS]);
            p[AXIS] = bound;
            out[n] = p;
            n += 1;
        }
    }
    let term = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - b[0] * a[1];
    let twice = if n == 3 {
        -0.0 + term(out[0], out[1]) + term(out[1], out[2]) + term(out[2], out[0])
    } else {
        -0.0 + term(out[0], out[1]) + term(out[1], out[2]) + term(out[2], out[3]) + term(out[3], out[0])
    };
    0.5 * twice.abs()
}

/// The (unsigned) area of a simple polygon.
fn polygon_area(poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[if i + 1 == n { 0 } else { i + 1 }]);
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

/// Whether `x` lies on the inner side of a box plane: `x <= bound` (`below`) or `x >= bound`.
fn on_side(x: f64, bound: f64, below: bool) -> bool {
    if below {
        x <= bound
    } else {
        x >= bound
    }
}

/// The one plane of the box `[lo, hi]` (its first `axes` axes) that the bounds `[blo, bhi]`
/// cross, as `(axis, bound, below)` with the inner side `x <= bound` (`below`) or `x >= bound`;
/// None when they lie beyond none or more than one of those planes.
fn single_crossing(blo: DVec3, bhi: DVec3, lo: DVec3, hi: DVec3, axes: usize) -> Option<(usize, f64, bool)> {
    let mut found = None;
    for axis in 0..axes {
        for (crosses, bound, below) in [
            (blo[axis] < lo[axis], lo[axis], false),
            (bhi[axis] > hi[axis], hi[axis], true),
        ] {
            if crosses {
                if found.is_some() {
                    return None;
                }
                found = Some((axis, bound, below));
            }
        }
    }
    found
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

/// Volumes a joint walk ([`LightScene::walk_lanes`]) follows at most.
const LANES: usize = 4;

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
    /// Its triangles: [`LightScene::triangles`]`[start..end]`.
    start: u32,
    end: u32,
    /// Its second child in [`LightScene::chunks`], 0 for a leaf. The nodes are stored in
    /// depth-first order, so an inner node's first child is the next node and a walk down
    /// the tree reads memory mostly forward (the walk is bound by fetching nodes).
    right: u32,
}

impl Chunk {
    /// Its triangles' range in [`LightScene::triangles`].
    fn tris(&self) -> std::ops::Range<usize> {
        self.start as usize..self.end as usize
    }

    /// Its two children (it is node `me`); None for a leaf.
    fn children(&self, me: usize) -> Option<(usize, usize)> {
        (self.right != 0).then(|| (me + 1, self.right as usize))
    }
}

/// How a node's bounds lie against every lane of a [`Lanes`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum Class {
    /// Inside every lane's box.
    Inside,
    /// Apart from every lane's box.
    Apart,
    /// Crossing every lane's box (neither inside nor apart from any).
    Crossing,
    /// Not decided by the common box and the hull: each lane is tested.
    Mixed,
}

/// Up to [`LANES`] volumes walked together ([`LightScene::walk_lanes`]), with their common
/// box (`ilo..ihi`: inside it, inside each) and their hull (`ulo..uhi`: apart from it, apart
/// from each).
struct Lanes<'a> {
    v: &'a [CasterVolume],
    ilo: DVec3,
    ihi: DVec3,
    ulo: DVec3,
    uhi: DVec3,
    /// Every lane has the same depth range.
    same_z: bool,
}

impl<'a> Lanes<'a> {
    fn new(v: &'a [CasterVolume]) -> Self {
        assert!(!v.is_empty() && v.len() <= LANES, "1 to {LANES} lanes");
        let (mut ilo, mut ihi, mut ulo, mut uhi) = (v[0].lo, v[0].hi, v[0].lo, v[0].hi);
        for x in &v[1..] {
            (ilo, ihi) = (ilo.max(x.lo), ihi.min(x.hi));
            (ulo, uhi) = (ulo.min(x.lo), uhi.max(x.hi));
        }
        let same_z = v.iter().all(|x| x.lo.z == v[0].lo.z && x.hi.z == v[0].hi.z);
        Lanes {
            v,
            ilo,
            ihi,
            ulo,
            uhi,
            same_z,
        }
    }

    /// The bounds `[lo, hi]` against every lane's box.
    fn class3(&self, lo: DVec3, hi: DVec3) -> Class {
        if lo.cmpge(self.ilo).all() && hi.cmple(self.ihi).all() {
            Class::Inside
        } else if lo.cmpgt(self.uhi).any() || hi.cmplt(self.ulo).any() {
            Class::Apart
        } else if !(lo.cmpgt(self.ihi).any() || hi.cmplt(self.ilo).any())
            && (lo.cmplt(self.ulo).any() || hi.cmpgt(self.uhi).any())
        {
            // Meeting the common box (so each lane's) and reaching beyond the hull (so beyond
            // each lane's box).
            Class::Crossing
        } else {
            Class::Mixed
        }
    }

    /// [`Lanes::class3`] of the rectangles (light x and y).
    fn class2(&self, lo: DVec2, hi: DVec2) -> Class {
        let (ilo, ihi, ulo, uhi) = (
            self.ilo.truncate(),
            self.ihi.truncate(),
            self.ulo.truncate(),
            self.uhi.truncate(),
        );
        if lo.cmpge(ilo).all() && hi.cmple(ihi).all() {
            Class::Inside
        } else if lo.cmpgt(uhi).any() || hi.cmplt(ulo).any() {
            Class::Apart
        } else if !(lo.cmpgt(ihi).any() || hi.cmplt(ilo).any()) && (lo.cmplt(ulo).any() || hi.cmpgt(uhi).any()) {
            Class::Crossing
        } else {
            Class::Mixed
        }
    }

    /// The one window edge `(axis, below)` that bounds `[lo, hi]` cross for every lane while
    /// lying within every lane's three other edges (beyond the hull on that side, within the
    /// common box on the others): [`single_crossing`] of each lane's rectangle is then that
    /// edge at the lane's bound. None otherwise.
    fn one_edge(&self, lo: DVec3, hi: DVec3) -> Option<(usize, bool)> {
        let mut found = None;
        for axis in 0..2 {
            for (beyond, within, below) in [
                (lo[axis] < self.ulo[axis], lo[axis] >= self.ilo[axis], false),
                (hi[axis] > self.uhi[axis], hi[axis] <= self.ihi[axis], true),
            ] {
                if beyond {
                    if found.is_some() {
                        return None;
                    }
                    found = Some((axis, below));
                } else if !within {
                    return None;
                }
            }
        }
        found
    }
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
    /// Every triangle in light coordinates, each object's in a Morton order of their world
    /// centroids (so that a chunk of consecutive ones is compact), in the order of its tree's
    /// leaves: a chunk's triangles are `triangles[start..end]`, read in sequence.
    triangles: Vec<[DVec3; 3]>,
    chunks: Vec<Chunk>,
    objects: Vec<LightObject>,
    /// The separating axes of this basis, for the objects' boxes against a volume.
    axes: SeparatingAxes,
    /// The counts of volumes already counted without culling, by the exact bits of the volume
    /// (a window a sweep meets again, e.g. a single cascade at every λ, is counted once).
    seen: std::sync::Mutex<std::collections::HashMap<[u64; 8], CostCounts>>,
    /// The receiver indices of visibility passes in this basis, by the key of their pass
    /// ([`LightScene::receiver_index`]); the latest [`KEPT_INDICES`].
    receivers: std::sync::Mutex<Vec<ReceiverEntry>>,
}

/// A cached [`ReceiverIndex`] and the key of its pass.
type ReceiverEntry = (Box<dyn std::any::Any + Send + Sync>, std::sync::Arc<ReceiverIndex>);

/// Receiver indices a [`LightScene`] keeps (one per visibility pass in its basis).
const KEPT_INDICES: usize = 8;

/// Volumes a [`LightScene`] remembers the counts of, at most.
const REMEMBERED: usize = 1 << 14;

/// The key of a volume in [`LightScene`]'s memory of counts: its exact bits.
fn volume_key(v: &CasterVolume) -> [u64; 8] {
    [v.lo.x, v.lo.y, v.lo.z, v.hi.x, v.hi.y, v.hi.z, v.texel.x, v.texel.y].map(f64::to_bits)
}

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
    let me = nodes.len();
    let index = |k: usize| u32::try_from(k).expect("fewer than 2^32 triangles and nodes");
    if end - start <= LEAF {
        let tris = order[start..end].iter().map(|&k| &triangles[k]);
        let (lo, hi) = bounds_of(tris.clone());
        nodes.push(Chunk {
            lo,
            hi,
            area: tris.map(projected_area).sum(),
            start: index(start),
            end: index(end),
            right: 0,
        });
        return me;
    }
    // The node first (depth-first order), filled in once its children are built.
    nodes.push(Chunk {
        lo: DVec3::ZERO,
        hi: DVec3::ZERO,
        area: 0.0,
        start: index(start),
        end: index(end),
        right: 0,
    });
    // Split on a leaf boundary, so every leaf but the last is full.
    let half = (end - start).div_ceil(2).div_ceil(LEAF) * LEAF;
    let a = build_tree(triangles, order, start, start + half, nodes);
    let b = build_tree(triangles, order, start + half, end, nodes);
    let (x, y) = (nodes[a], nodes[b]);
    nodes[me].lo = x.lo.min(y.lo);
    nodes[me].hi = x.hi.max(y.hi);
    nodes[me].area = x.area + y.area;
    nodes[me].right = index(b);
    me
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
        // Each object's triangles in a Morton order of their world centroids, then every
        // triangle in light coordinates once, already in that order (one copy of the scene's
        // light-space triangles at a time: the peak memory of a large scene).
        let mut order: Vec<usize> = Vec::with_capacity(mesh.triangles.len());
        let mut spans = Vec::with_capacity(mesh.objects.len());
        for o in &mesh.objects {
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
            spans.push((start, order.len()));
        }
        let triangles: Vec<[DVec3; 3]> = order
            .iter()
            .map(|&k| mesh.triangles[k].map(|p| basis.to_light(p)))
            .collect();
        drop(order);
        let identity: Vec<usize> = (0..triangles.len()).collect();
        let mut chunks = Vec::new();
        let objects = mesh
            .objects
            .iter()
            .zip(spans)
            .map(|(o, (start, end))| {
                let root = build_tree(&triangles, &identity, start, end, &mut chunks);
                let area = chunks[root].area;
                // The same vertices as the object's own triangles (reordered): the same bounds.
                let (lo, hi) = bounds_of(triangles[start..end].iter());
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
            chunks,
            objects,
            axes: SeparatingAxes::new(basis),
            seen: Default::default(),
            receivers: Default::default(),
        }
    }

    /// The receiver index of a visibility pass in this basis, made by `make` once per `key`
    /// (whatever identifies the pass: the caller's view) and shared by every cascade and sweep
    /// row that culls by that pass's receivers.
    pub fn receiver_index<K: Clone + PartialEq + Send + Sync + 'static>(
        &self,
        key: &K,
        make: impl FnOnce() -> ReceiverIndex,
    ) -> std::sync::Arc<ReceiverIndex> {
        let find = |cache: &[ReceiverEntry]| {
            cache
                .iter()
                .find(|(k, _)| k.downcast_ref::<K>() == Some(key))
                .map(|(_, r)| r.clone())
        };
        if let Some(r) = find(&self.receivers.lock().unwrap_or_else(|e| e.into_inner())) {
            return r;
        }
        let made = std::sync::Arc::new(make());
        let mut cache = self.receivers.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(r) = find(&cache) {
            return r;
        }
        if cache.len() >= KEPT_INDICES {
            cache.remove(0);
        }
        cache.push((Box::new(key.clone()), made.clone()));
        made
    }

    /// [`LightScene::counts`] without culling, remembered per volume: a volume counted before
    /// (bit for bit the same window, depth range and texel) is not counted again.
    pub fn counts_all(&self, mesh: &Mesh, v: &CasterVolume) -> CostCounts {
        let key = volume_key(v);
        if let Some(c) = self.seen.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return *c;
        }
        let c = self.counts(mesh, v, |_| true);
        self.remember(key, c);
        c
    }

    fn remember(&self, key: [u64; 8], c: CostCounts) {
        let mut seen = self.seen.lock().unwrap_or_else(|e| e.into_inner());
        if seen.len() < REMEMBERED {
            seen.insert(key, c);
        }
    }

    /// [`LightScene::counts_all`] of each volume of `vs`, bit for bit, with the tree walked
    /// once for up to [`LANES`] volumes at a time ([`LightScene::walk_lanes`]): consecutive
    /// volumes with the same depth range (one cascade of settings that differ in resolution
    /// alone: their windows differ by a sub-texel shift) share the nodes and triangles they
    /// read.
    pub fn counts_all_many(&self, mesh: &Mesh, vs: &[CasterVolume]) -> Vec<CostCounts> {
        let mut out: Vec<Option<CostCounts>> = {
            let seen = self.seen.lock().unwrap_or_else(|e| e.into_inner());
            vs.iter()
                .map(|v| {
                    debug_assert_eq!(v.basis, self.basis, "a volume of another basis");
                    if v.is_empty() {
                        Some(CostCounts::default())
                    } else {
                        seen.get(&volume_key(v)).copied()
                    }
                })
                .collect()
        };
        // The volumes to count, in runs of at most LANES with one depth range.
        let todo: Vec<usize> = (0..vs.len()).filter(|&i| out[i].is_none()).collect();
        let mut runs: Vec<Vec<usize>> = Vec::new();
        for i in todo {
            let joins = runs.last().is_some_and(|r: &Vec<usize>| {
                let f = &vs[r[0]];
                r.len() < LANES && f.lo.z == vs[i].lo.z && f.hi.z == vs[i].hi.z
            });
            if joins {
                runs.last_mut().expect("a run").push(i);
            } else {
                runs.push(vec![i]);
            }
        }
        for run in runs {
            let lane_vs: Vec<CasterVolume> = run.iter().map(|&i| vs[i]).collect();
            let lanes = Lanes::new(&lane_vs);
            let mut counts = vec![CostCounts::default(); run.len()];
            let mut area = vec![0.0f64; run.len()];
            for (o, lo) in mesh.objects.iter().zip(&self.objects) {
                // `counts`' tests, per lane.
                let mut meet = 0u8;
                for (l, v) in lane_vs.iter().enumerate() {
                    if !(lo.box_lo.cmpgt(v.hi).any() || lo.box_hi.cmplt(v.lo).any()) && self.axes.meets(&o.bounds, v) {
                        meet |= 1 << l;
                    }
                }
                if meet == 0 {
                    continue;
                }
                let (k, a) = self.walk_lanes(lo.root, &lanes, meet, meet);
                for l in 0..run.len() {
                    if meet & (1 << l) != 0 {
                        counts[l].caster_objects += 1;
                        counts[l].caster_triangles += o.triangles.len() as u64;
                        counts[l].caster_triangles_inside += k[l];
                        area[l] += a[l];
                    }
                }
            }
            for (l, &i) in run.iter().enumerate() {
                let v = &vs[i];
                counts[l].raster_fragments = area[l] / (v.texel.x * v.texel.y);
                self.remember(volume_key(v), counts[l]);
                out[i] = Some(counts[l]);
            }
        }
        out.into_iter().map(|c| c.expect("every volume counted")).collect()
    }

    /// The triangles of a chunk.
    #[cfg(test)]
    fn tris<'a>(&'a self, c: &Chunk) -> impl Iterator<Item = &'a [DVec3; 3]> + 'a {
        self.triangles[c.tris()].iter()
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
        match c.children(n) {
            Some((x, y)) => {
                let (k1, a1) = self.walk(x, v, count, area);
                let (k2, a2) = self.walk(y, v, count, area);
                (k + k1 + k2, a + a1 + a2)
            }
            None => {
                if count && area {
                    if let Some(plane) = single_crossing(c.lo, c.hi, v.lo, v.hi, 3).filter(|p| p.0 < 2) {
                        let (k1, a1) = self.leaf_both(c, plane);
                        return (k + k1, a + a1);
                    }
                }
                if count {
                    k += self.leaf_meeting(c, v);
                }
                if area {
                    a += self.leaf_area(c, v);
                }
                (k, a)
            }
        }
    }

    /// [`LightScene::walk`] for up to [`LANES`] volumes at once, lane `l` counting
    /// `lanes.v[l]` where the bits `l` of `count` and `area` ask: each lane's result is the one
    /// `walk` gives for its volume, bit for bit (both are the tree's plain sums, whatever is
    /// settled where). A node is classified once against the lanes' common box and their hull
    /// when that decides every lane, and per lane otherwise.
    fn walk_lanes(&self, n: usize, lanes: &Lanes, mut count: u8, mut area: u8) -> ([u64; LANES], [f64; LANES]) {
        let c = &self.chunks[n];
        let mut k = [0u64; LANES];
        let mut a = [0.0f64; LANES];
        if count != 0 {
            match lanes.class3(c.lo, c.hi) {
                Class::Inside => {
                    for (l, k) in k.iter_mut().enumerate() {
                        if count & (1 << l) != 0 {
                            *k = (c.end - c.start) as u64;
                        }
                    }
                    count = 0;
                }
                Class::Apart => count = 0,
                Class::Crossing => {}
                Class::Mixed => {
                    for (l, v) in lanes.v.iter().enumerate() {
                        let bit = 1u8 << l;
                        if count & bit != 0 {
                            if c.lo.cmpge(v.lo).all() && c.hi.cmple(v.hi).all() {
                                k[l] = (c.end - c.start) as u64;
                                count &= !bit;
                            } else if c.lo.cmpgt(v.hi).any() || c.hi.cmplt(v.lo).any() {
                                count &= !bit;
                            }
                        }
                    }
                }
            }
        }
        if area != 0 {
            let (lo, hi) = (c.lo.truncate(), c.hi.truncate());
            match lanes.class2(lo, hi) {
                Class::Inside => {
                    for (l, a) in a.iter_mut().enumerate() {
                        if area & (1 << l) != 0 {
                            *a = c.area;
                        }
                    }
                    area = 0;
                }
                Class::Apart => area = 0,
                Class::Crossing => {}
                Class::Mixed => {
                    for (l, v) in lanes.v.iter().enumerate() {
                        let bit = 1u8 << l;
                        if area & bit != 0 {
                            let (rlo, rhi) = (v.lo.truncate(), v.hi.truncate());
                            if lo.cmpge(rlo).all() && hi.cmple(rhi).all() {
                                a[l] = c.area;
                                area &= !bit;
                            } else if lo.cmpgt(rhi).any() || hi.cmplt(rlo).any() {
                                area &= !bit;
                            }
                        }
                    }
                }
            }
        }
        if count | area == 0 {
            return (k, a);
        }
        match c.children(n) {
            Some((x, y)) => {
                let (k1, a1) = self.walk_lanes(x, lanes, count, area);
                let (k2, a2) = self.walk_lanes(y, lanes, count, area);
                for l in 0..LANES {
                    k[l] += k1[l] + k2[l];
                    a[l] = a[l] + a1[l] + a2[l];
                }
                (k, a)
            }
            None => {
                let (k1, a1) = self.leaf_lanes(c, lanes, count, area);
                for l in 0..LANES {
                    k[l] += k1[l];
                    a[l] += a1[l];
                }
                (k, a)
            }
        }
    }

    /// The leaf `c`'s part of [`LightScene::walk_lanes`]: per lane asked, the number of its
    /// triangles meeting the lane's volume (`count`) and the sum of their [`clipped_area`]s in
    /// order from 0 (`area`), as [`LightScene::leaf_meeting`] and [`LightScene::leaf_area`]
    /// give them. When the leaf crosses one window edge of every lane and lies within the
    /// lanes' other edges, each triangle's extent along that edge's axis is found once and
    /// compared with each lane's edge (all of it on the inner side: its whole area, read once;
    /// none: nothing; else clipped by that edge, [`one_edge_area`]); when it lies within every
    /// lane's rectangle and the lanes share their depth range, one count serves them all.
    fn leaf_lanes(&self, c: &Chunk, lanes: &Lanes, count: u8, area: u8) -> ([u64; LANES], [f64; LANES]) {
        let mut k = [0u64; LANES];
        let mut a = [0.0f64; LANES];
        let tris = &self.triangles[c.tris()];
        let edge = lanes.one_edge(c.lo, c.hi);
        let z_within = c.lo.z >= lanes.ilo.z && c.hi.z <= lanes.ihi.z;
        let joint_area = if edge.is_some() { area } else { 0 };
        let joint_count = if edge.is_some() && z_within { count } else { 0 };
        if let Some((axis, below)) = edge.filter(|_| joint_area | joint_count != 0) {
            let joint = joint_area | joint_count;
            let bound: [f64; LANES] = std::array::from_fn(|l| {
                let v = &lanes.v[l.min(lanes.v.len() - 1)];
                if below {
                    v.hi[axis]
                } else {
                    v.lo[axis]
                }
            });
            // The band of the lanes' edges: a triangle on the inner side of all of them has
            // its whole area in every lane, one beyond all of them none.
            let (mut bmin, mut bmax) = (f64::INFINITY, f64::NEG_INFINITY);
            for (l, b) in bound.iter().enumerate() {
                if joint & (1 << l) != 0 {
                    (bmin, bmax) = (bmin.min(*b), bmax.max(*b));
                }
            }
            let kj: [u64; LANES] = std::array::from_fn(|l| u64::from(joint_count & (1 << l) != 0));
            let aj: [bool; LANES] = std::array::from_fn(|l| joint_area & (1 << l) != 0);
            for t in tris {
                let (x0, x1, x2) = (t[0][axis], t[1][axis], t[2][axis]);
                let (tmin, tmax) = (x0.min(x1).min(x2), x0.max(x1).max(x2));
                let (all_in, all_out) = if below {
                    (tmax <= bmin, tmin > bmax)
                } else {
                    (tmin >= bmax, tmax < bmin)
                };
                if all_out {
                    continue;
                }
                if all_in {
                    // Adding 0 to a lane that does not take the area changes nothing: every
                    // lane's sum is a sum of areas, never -0.
                    let w = projected_area(t);
                    for l in 0..LANES {
                        k[l] += kj[l];
                        a[l] += if aj[l] { w } else { 0.0 };
                    }
                    continue;
                }
                let mut whole = None;
                for l in 0..lanes.v.len() {
                    if joint & (1 << l) == 0 {
                        continue;
                    }
                    let b = bound[l];
                    let (all, none) = if below {
                        (tmax <= b, tmin > b)
                    } else {
                        (tmin >= b, tmax < b)
                    };
                    if none {
                        continue;
                    }
                    k[l] += kj[l];
                    if aj[l] {
                        a[l] += if all {
                            *whole.get_or_insert_with(|| projected_area(t))
                        } else {
                            one_edge_area(t, axis, b, below)
                        };
                    }
                }
            }
        }
        let (count, area) = (count & !joint_count, area & !joint_area);
        // One count for every lane when the leaf lies within each lane's rectangle and the
        // lanes' depth ranges are the same: the triangles meeting each volume are then the same.
        let shared = count != 0 && lanes.same_z && {
            let (lo, hi) = (c.lo.truncate(), c.hi.truncate());
            lo.cmpge(lanes.ilo.truncate()).all() && hi.cmple(lanes.ihi.truncate()).all()
        };
        let mut once = None;
        for (l, v) in lanes.v.iter().enumerate() {
            let bit = 1u8 << l;
            if count & bit != 0 {
                k[l] += if shared {
                    *once.get_or_insert_with(|| self.leaf_meeting(c, v))
                } else {
                    self.leaf_meeting(c, v)
                };
            }
            if area & bit != 0 {
                a[l] += self.leaf_area(c, v);
            }
        }
        (k, a)
    }

    /// [`LightScene::leaf_meeting`] and [`LightScene::leaf_area`] in one pass over the
    /// triangles, for a leaf whose bounds cross one plane of the volume only, a window edge:
    /// that edge is then also the one edge of the rectangle the leaf crosses, and a triangle
    /// with a vertex on its inner side both meets the volume and has its area (whole, or
    /// clipped by that edge alone, [`one_edge_area`], when a vertex lies beyond), in the same
    /// order as `leaf_area` adds them.
    fn leaf_both(&self, c: &Chunk, (axis, bound, below): (usize, f64, bool)) -> (u64, f64) {
        let (mut k, mut a) = (0, 0.0);
        for t in &self.triangles[c.tris()] {
            match t.iter().filter(|p| on_side(p[axis], bound, below)).count() {
                0 => {}
                3 => {
                    k += 1;
                    a += projected_area(t);
                }
                _ => {
                    k += 1;
                    a += one_edge_area(t, axis, bound, below);
                }
            }
        }
        (k, a)
    }

    /// How many triangles of leaf `c` meet the volume: [`triangle_meets_box`] of each. When
    /// the leaf's bounds cross one plane of the box only, a triangle meets it exactly when a
    /// vertex lies on the inner side of that plane (that vertex is then inside the box, the
    /// leaf lying within every other plane; with none, the triangle's bounds are apart), so no
    /// triangle is clipped.
    fn leaf_meeting(&self, c: &Chunk, v: &CasterVolume) -> u64 {
        let tris = &self.triangles[c.tris()];
        match single_crossing(c.lo, c.hi, v.lo, v.hi, 3) {
            Some((axis, bound, below)) => tris
                .iter()
                .filter(|t| t.iter().any(|p| on_side(p[axis], bound, below)))
                .count() as u64,
            None => tris.iter().filter(|t| triangle_meets_box(t, v.lo, v.hi)).count() as u64,
        }
    }

    /// The sum of leaf `c`'s triangles' [`clipped_area`]s, in order from 0. When the leaf's
    /// bounds cross one edge of the rectangle only, a triangle with every vertex on the inner
    /// side of that edge is inside the rectangle (its projected area, as `clipped_area` gives
    /// it), one with every vertex beyond it is apart (0, nothing added), and only the others
    /// are clipped, by that edge alone ([`one_edge_area`]).
    fn leaf_area(&self, c: &Chunk, v: &CasterVolume) -> f64 {
        let (rlo, rhi) = (v.lo.truncate(), v.hi.truncate());
        let tris = &self.triangles[c.tris()];
        let mut a = 0.0;
        match single_crossing(c.lo, c.hi, v.lo, v.hi, 2) {
            Some((axis, bound, below)) => {
                for t in tris {
                    let inner = t.iter().filter(|p| on_side(p[axis], bound, below)).count();
                    if inner == 3 {
                        a += projected_area(t);
                    } else if inner > 0 {
                        a += one_edge_area(t, axis, bound, below);
                    }
                }
            }
            None => {
                for t in tris {
                    a += clipped_area(t, rlo, rhi);
                }
            }
        }
        a
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

    /// What the counts of volumes with `v`'s rectangle and light near need that does not
    /// depend on the light far: per object, whether its box misses them at any far, its
    /// clipped area, and for a small object the far beyond which each of its triangles meets
    /// the volume ([`meet_threshold`]), sorted. Volumes sharing a rectangle then cost
    /// [`LightScene::counts_in`]: the box tests and a binary search per object.
    pub fn rect_part(&self, v: &CasterVolume) -> RectPart {
        let mut thresholds = Vec::new();
        let objects = self
            .objects
            .iter()
            .map(|o| {
                // `counts`' first test but for `box_lo.z > far`, the one part that needs the far.
                let (lo, hi) = (v.lo, v.hi);
                if o.box_lo.x > hi.x || o.box_lo.y > hi.y || o.box_hi.cmplt(lo).any() {
                    return RectObject::Apart;
                }
                let root = &self.chunks[o.root];
                if root.end - root.start > SMALL_OBJECT {
                    return RectObject::Large;
                }
                let start = thresholds.len();
                thresholds.extend(
                    self.triangles[root.tris()]
                        .iter()
                        .map(|t| meet_threshold(t, lo, hi.truncate()))
                        .filter(|z| *z < f64::INFINITY),
                );
                thresholds[start..].sort_unstable_by(f64::total_cmp);
                RectObject::Small {
                    area: self.walk(o.root, v, false, true).1,
                    start: start as u32,
                    end: thresholds.len() as u32,
                }
            })
            .collect();
        RectPart { objects, thresholds }
    }

    /// [`LightScene::counts`] without culling, for a volume with the rectangle and light near
    /// of the one `part` was made for ([`LightScene::rect_part`]): the same counts, bit for bit.
    /// The area of an object is a function of the rectangle alone (the walk's area, whatever
    /// it settles where), and a triangle meets the volume exactly when the far is at least its
    /// threshold.
    pub fn counts_in(&self, mesh: &Mesh, v: &CasterVolume, part: &RectPart) -> CostCounts {
        debug_assert_eq!(v.basis, self.basis, "a volume of another basis");
        let mut out = CostCounts::default();
        if v.is_empty() {
            return out;
        }
        let texel_area = v.texel.x * v.texel.y;
        let mut area = 0.0;
        for ((o, lo), p) in mesh.objects.iter().zip(&self.objects).zip(&part.objects) {
            if matches!(p, RectObject::Apart) || lo.box_lo.z > v.hi.z || !self.axes.meets(&o.bounds, v) {
                continue;
            }
            out.caster_objects += 1;
            out.caster_triangles += o.triangles.len() as u64;
            let (inside, a) = match *p {
                RectObject::Small { area, start, end } => {
                    let t = &part.thresholds[start as usize..end as usize];
                    (t.partition_point(|&z| z <= v.hi.z) as u64, area)
                }
                _ => self.walk(lo.root, v, true, true),
            };
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

/// Triangles an object may have for [`LightScene::rect_part`] to keep its thresholds; a
/// larger one is walked per volume (its tree settles whole nodes).
const SMALL_OBJECT: u32 = 256;

/// One object's part of a [`RectPart`].
#[derive(Debug, Clone, Copy, PartialEq)]
enum RectObject {
    /// Its box misses every volume of the rectangle and light near.
    Apart,
    /// Its clipped area and its triangles' thresholds, `thresholds[start..end]` (sorted).
    Small { area: f64, start: u32, end: u32 },
    /// Walked per volume.
    Large,
}

/// What the counts of one rectangle (and light near) need whatever the light far:
/// [`LightScene::rect_part`].
#[derive(Debug, Clone, PartialEq)]
pub struct RectPart {
    objects: Vec<RectObject>,
    thresholds: Vec<f64>,
}

impl RectPart {
    /// Bytes it holds (for a caller bounding a cache of them).
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.objects.len() * std::mem::size_of::<RectObject>() + self.thresholds.len() * 8
    }
}

/// The smallest light far at which the triangle `t` meets the box `[lo, (hi, far)]`
/// ([`triangle_meets_box`]) and every larger one: `+inf` when none. Follows that test's steps
/// with the far left open: a vertex inside the box (its other five planes, and `z <= far`);
/// the bounds not apart (the far-free tests, and the lowest vertex `<= far`); the clip by the
/// five far-free planes not empty, and a vertex of it `<= far` (the last plane's clip is empty
/// exactly when no vertex lies on its inner side). Each is "far at least some value", so the
/// test is `far >= min(z_vertex, max(z_bounds, z_clip))`, with no rounding of its own.
fn meet_threshold(t: &[DVec3; 3], lo: DVec3, hi: DVec2) -> f64 {
    let inside = |p: &DVec3| p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y;
    let (tlo, thi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    if t.iter().all(inside) {
        // Every vertex inside the five planes: the lowest decides (the rest is no lower).
        return tlo.z;
    }
    let z_vertex = t.iter().filter(|p| inside(p)).fold(f64::INFINITY, |z, p| z.min(p.z));
    if tlo.x > hi.x || tlo.y > hi.y || thi.cmplt(lo).any() {
        return z_vertex;
    }
    let mut poly = Poly::of(t.map(|p| p.to_array()));
    for (axis, bound, below) in [
        (0, lo.x, false),
        (0, hi.x, true),
        (1, lo.y, false),
        (1, hi.y, true),
        (2, lo.z, false),
    ] {
        if poly.within(axis, bound, below) {
            continue;
        }
        poly = poly.clip(axis, bound, below);
        if poly.n == 0 {
            return z_vertex;
        }
    }
    let z_clip = poly.v[..poly.n].iter().fold(f64::INFINITY, |z, p| z.min(p[2]));
    z_vertex.min(tlo.z.max(z_clip))
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
        Self::padded(lo, hi, pad_xy, pad_z)
    }

    /// The light-space bounds `[lo, hi]` of the receivers grown by `pad_xy` across the light and
    /// `pad_z` along it; None when the bounds are empty (`lo.x > hi.x`: no receiver).
    pub fn padded(lo: DVec3, hi: DVec3, pad_xy: f64, pad_z: f64) -> Option<Self> {
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

/// Receivers per block of a [`ReceiverIndex`] (the leaves of its tree).
const BLOCK: usize = 32;

/// Light-space bounds: `(lo, hi)`, empty as `(+inf, -inf)`.
type Bounds3 = (DVec3, DVec3);

const NO_BOUNDS: Bounds3 = (DVec3::INFINITY, DVec3::NEG_INFINITY);

fn merge(a: Bounds3, b: Bounds3) -> Bounds3 {
    (a.0.min(b.0), a.1.max(b.1))
}

fn bounds_of_points(points: &[DVec3]) -> Bounds3 {
    points.iter().fold(NO_BOUNDS, |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// The visible receivers of one visibility pass in one light basis, for receiver-aware
/// culling: each receiver's view depth and light-space point, sorted by view depth once, and
/// a segment tree of the light-space bounds of blocks of [`BLOCK`] consecutive receivers. The
/// bounds of the receivers whose view depth lies in an interval (one cascade's) are then two
/// binary searches, the two partial blocks at the ends and O(log n) nodes, instead of a scan
/// of every sample per cascade. The bounds are a minimum and a maximum per axis, which no
/// order changes: they equal a scan's (the two can differ only in the sign of a zero, which
/// [`ReceiverBox::padded`]'s non-zero padding removes).
#[derive(Debug, Clone, PartialEq)]
pub struct ReceiverIndex {
    /// View depths, ascending.
    depths: Vec<f64>,
    /// Light-space points, in the order of `depths`.
    points: Vec<DVec3>,
    /// The tree over the blocks: node 1 the root, node `k`'s children `2k` and `2k + 1`, block
    /// `b` at `leaves + b`.
    tree: Vec<Bounds3>,
    leaves: usize,
}

impl ReceiverIndex {
    /// The index of `receivers`: `(view depth, light-space point)`, in any order.
    pub fn new(receivers: impl IntoIterator<Item = (f64, DVec3)>) -> Self {
        let mut r: Vec<(f64, DVec3)> = receivers.into_iter().collect();
        r.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (depths, points): (Vec<f64>, Vec<DVec3>) = r.into_iter().unzip();
        let leaves = points.len().div_ceil(BLOCK).next_power_of_two();
        let mut tree = vec![NO_BOUNDS; 2 * leaves];
        for (b, block) in points.chunks(BLOCK).enumerate() {
            tree[leaves + b] = bounds_of_points(block);
        }
        for k in (1..leaves).rev() {
            tree[k] = merge(tree[2 * k], tree[2 * k + 1]);
        }
        ReceiverIndex {
            depths,
            points,
            tree,
            leaves,
        }
    }

    /// How many receivers it holds.
    pub fn len(&self) -> usize {
        self.depths.len()
    }

    pub fn is_empty(&self) -> bool {
        self.depths.is_empty()
    }

    /// The light-space bounds of the receivers whose view depth lies in one of the closed
    /// `intervals` (`a <= depth <= b`); `(+inf, -inf)` when there is none.
    pub fn bounds(&self, intervals: &[(f64, f64)]) -> (DVec3, DVec3) {
        let mut acc = NO_BOUNDS;
        for &(a, b) in intervals {
            // An empty or reversed interval (or a NaN end) holds no receiver.
            if a.partial_cmp(&b).is_none_or(|o| o.is_gt()) {
                continue;
            }
            let i0 = self.depths.partition_point(|&d| d < a);
            let i1 = self.depths.partition_point(|&d| d <= b).max(i0);
            acc = merge(acc, self.range(i0, i1));
        }
        acc
    }

    /// The bounds of the points `i0..i1` (sorted order).
    fn range(&self, i0: usize, i1: usize) -> Bounds3 {
        // The whole blocks inside `i0..i1`: `b0..b1`.
        let (b0, b1) = (i0.div_ceil(BLOCK), i1 / BLOCK);
        if b0 >= b1 {
            return bounds_of_points(&self.points[i0..i1]);
        }
        let mut acc = merge(
            bounds_of_points(&self.points[i0..b0 * BLOCK]),
            bounds_of_points(&self.points[b1 * BLOCK..i1]),
        );
        let (mut l, mut r) = (b0 + self.leaves, b1 + self.leaves);
        while l < r {
            if l & 1 == 1 {
                acc = merge(acc, self.tree[l]);
                l += 1;
            }
            if r & 1 == 1 {
                r -= 1;
                acc = merge(acc, self.tree[r]);
            }
            l >>= 1;
            r >>= 1;
        }
        acc
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

    // -----------------------------------------------------------------------------------------
    // The fast paths against their plain definitions, bit for bit
    // -----------------------------------------------------------------------------------------

    use crate::mesh::ObjectKind;
    use proptest::prelude::*;

    /// A triangle's clip by the box's six planes, every plane clipped (no plane skipped).
    fn meets_plain(t: &[DVec3; 3], lo: DVec3, hi: DVec3) -> bool {
        meets_box(t, lo, hi, false)
    }

    /// A triangle's projected area clipped to the rectangle, every edge clipped.
    fn area_plain(t: &[DVec3; 3], lo: DVec2, hi: DVec2) -> f64 {
        area_in(t, lo, hi, false)
    }

    /// The definition the walk evaluates: under node `n`, the triangles meeting the volume and
    /// the tree's sum of every triangle's clipped area (a leaf adds its triangles in order from
    /// 0, an inner node its two children), with no node settled by its bounds.
    fn tree_plain(light: &LightScene, n: usize, v: &CasterVolume) -> (u64, f64) {
        let c = &light.chunks[n];
        match c.children(n) {
            Some((x, y)) => {
                let (k1, a1) = tree_plain(light, x, v);
                let (k2, a2) = tree_plain(light, y, v);
                (k1 + k2, a1 + a2)
            }
            None => {
                let (mut k, mut a) = (0, 0.0);
                for t in light.tris(c) {
                    k += u64::from(meets_plain(t, v.lo, v.hi));
                    a += area_plain(t, v.lo.truncate(), v.hi.truncate());
                }
                (k, a)
            }
        }
    }

    /// [`LightScene::counts`] by [`tree_plain`] for every object that meets the volume.
    fn counts_plain(light: &LightScene, mesh: &Mesh, v: &CasterVolume, keep: impl Fn(usize) -> bool) -> CostCounts {
        let mut out = CostCounts::default();
        if v.is_empty() {
            return out;
        }
        let mut area = 0.0;
        for (k, (o, lo)) in mesh.objects.iter().zip(&light.objects).enumerate() {
            if lo.box_lo.cmpgt(v.hi).any()
                || lo.box_hi.cmplt(v.lo).any()
                || !keep(k)
                || !aabb_meets_volume(&o.bounds, v)
            {
                continue;
            }
            out.caster_objects += 1;
            out.caster_triangles += o.triangles.len() as u64;
            let (inside, a) = tree_plain(light, lo.root, v);
            out.caster_triangles_inside += inside;
            area += a;
        }
        out.raster_fragments = area / (v.texel.x * v.texel.y);
        out
    }

    /// A rolling terrain of `n` x `n` cells over `[-s, s]²` (two triangles a cell), with
    /// heights from `seed`: one object of many triangles, so that its tree is deep.
    fn terrain(mesh: &mut Mesh, n: usize, s: f64, seed: f64) {
        let h = |i: usize, j: usize| (seed * (i as f64 + 1.3) * 0.71).sin() * (seed * (j as f64 + 0.7) * 0.37).cos();
        let p = |i: usize, j: usize| {
            DVec3::new(
                -s + 2.0 * s * i as f64 / n as f64,
                h(i, j),
                -s + 2.0 * s * j as f64 / n as f64,
            )
        };
        let tris = (0..n).flat_map(|j| {
            (0..n).flat_map(move |i| {
                [
                    [p(i, j), p(i, j + 1), p(i + 1, j + 1)],
                    [p(i, j), p(i + 1, j + 1), p(i + 1, j)],
                ]
            })
        });
        mesh.add_object(ObjectKind::Primitive, tris.collect::<Vec<_>>());
    }

    /// The next float above (`up`) or below a finite `z`.
    fn ulp(z: f64, up: bool) -> f64 {
        if z == 0.0 {
            return if up { f64::from_bits(1) } else { -f64::from_bits(1) };
        }
        let bits = z.to_bits();
        f64::from_bits(if (z > 0.0) == up { bits + 1 } else { bits - 1 })
    }

    fn scene() -> impl Strategy<Value = Mesh> {
        (
            prop::collection::vec((2usize..40, 5.0..40.0f64, 0.1..3.0f64), 1..3),
            prop::collection::vec((-30.0..30.0f64, -3.0..3.0f64, -30.0..30.0f64, 0.2..6.0f64), 0..5),
        )
            .prop_map(|(grounds, boxes)| {
                let mut m = Mesh::default();
                for (n, s, seed) in grounds {
                    terrain(&mut m, n, s, seed);
                }
                for (x, y, z, e) in boxes {
                    let c = DVec3::new(x, y, z);
                    m.add_box(&Aabb::new(c - DVec3::splat(e), c + DVec3::splat(e)));
                }
                m
            })
    }

    /// A light and a volume in its space; with `snap` its x and y bounds are moved onto light
    /// coordinates of scene vertices (edges through vertices: the ties of the clipping).
    fn volume(mesh: &Mesh, d: DVec3, r: [f64; 6], snap: Option<[usize; 4]>) -> CasterVolume {
        let basis = LightBasis::new(d);
        let mut lo = DVec3::new(-40.0 + 60.0 * r[0], -40.0 + 60.0 * r[1], -60.0 + 40.0 * r[2]);
        let mut hi = lo + DVec3::new(1.0 + 50.0 * r[3], 1.0 + 50.0 * r[4], 1.0 + 80.0 * r[5]);
        if let Some(k) = snap {
            let vertex = |i: usize| basis.to_light(mesh.triangles[i / 3 % mesh.triangles.len()][i % 3]);
            let (a, b) = (vertex(k[0]), vertex(k[1]));
            let (c, e) = (vertex(k[2]), vertex(k[3]));
            (lo.x, hi.x) = (a.x.min(b.x), a.x.max(b.x));
            (lo.y, hi.y) = (c.y.min(e.y), c.y.max(e.y));
            lo.z = lo.z.min(a.z);
            hi.z = c.z;
        }
        CasterVolume {
            basis,
            lo,
            hi,
            texel: DVec2::new(0.25, 0.5),
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// The walk (nodes settled by their bounds, planes a polygon lies within skipped, the
        /// triangles of a node read in tree order) gives the plain definition's counts, and
        /// the same bits of `raster_fragments`.
        #[test]
        fn the_walk_equals_the_plain_tree_sum_bit_for_bit(
            m in scene(),
            d in (-1.0..1.0f64, -1.0..-0.2f64, -1.0..1.0f64),
            r in prop::array::uniform6(0.0..1.0f64),
            snap in prop::option::of(prop::array::uniform4(0usize..100_000)),
            mask in prop::collection::vec(any::<bool>(), 1..8),
        ) {
            let v = volume(&m, DVec3::new(d.0, d.1, d.2), r, snap);
            let light = LightScene::new(&m, &v.basis);
            let keep = |k: usize| mask[k % mask.len()];
            for c in [(light.counts(&m, &v, |_| true), counts_plain(&light, &m, &v, |_| true)),
                      (light.counts(&m, &v, keep), counts_plain(&light, &m, &v, keep))] {
                prop_assert_eq!(c.0.caster_objects, c.1.caster_objects);
                prop_assert_eq!(c.0.caster_triangles, c.1.caster_triangles);
                prop_assert_eq!(c.0.caster_triangles_inside, c.1.caster_triangles_inside);
                prop_assert_eq!(c.0.raster_fragments.to_bits(), c.1.raster_fragments.to_bits());
            }
            prop_assert_eq!(light.counts_all(&m, &v), counts_plain(&light, &m, &v, |_| true));
        }

        /// The counts of a rectangle's part ([`LightScene::rect_part`]) at any light far equal
        /// the direct counts bit for bit: fars at random, at the scene's vertices' light depths,
        /// at every threshold and one ulp either side of it (where a triangle starts meeting
        /// the volume), below the light near (empty), on terrains and boxes (small objects)
        /// and on a terrain of more than `SMALL_OBJECT` triangles (walked).
        #[test]
        fn a_rectangles_part_counts_as_the_direct_count_at_every_far(
            m in scene(),
            d in (-1.0..1.0f64, -1.0..-0.2f64, -1.0..1.0f64),
            r in prop::array::uniform6(0.0..1.0f64),
            snap in prop::option::of(prop::array::uniform4(0usize..100_000)),
            fars in prop::collection::vec(0.0..1.0f64, 4),
            picks in prop::collection::vec(0usize..100_000, 8),
        ) {
            let v = volume(&m, DVec3::new(d.0, d.1, d.2), r, snap);
            let light = LightScene::new(&m, &v.basis);
            let part = light.rect_part(&v);
            let (zlo, zhi) = light.objects.iter().fold((v.lo.z, v.hi.z), |(a, b), o| (a.min(o.lo.z), b.max(o.hi.z)));
            let mut all: Vec<f64> = fars.iter().map(|f| zlo - 1.0 + f * (zhi - zlo + 2.0)).collect();
            all.extend(picks.iter().map(|&k| v.basis.to_light(m.triangles[k / 3 % m.triangles.len()][k % 3]).z));
            for &z in part.thresholds.iter().step_by(1 + part.thresholds.len() / 16) {
                all.extend([z, ulp(z, false), ulp(z, true)]);
            }
            all.push(ulp(v.lo.z, false));
            for far in all {
                let w = CasterVolume { hi: DVec3::new(v.hi.x, v.hi.y, far), ..v };
                let (fast, direct) = (light.counts_in(&m, &w, &part), light.counts(&m, &w, |_| true));
                prop_assert_eq!(fast.caster_objects, direct.caster_objects);
                prop_assert_eq!(fast.caster_triangles, direct.caster_triangles);
                prop_assert_eq!(fast.caster_triangles_inside, direct.caster_triangles_inside);
                prop_assert_eq!(fast.raster_fragments.to_bits(), direct.raster_fragments.to_bits());
            }
        }

        /// A window over a whole terrain with its far plane through it (nodes inside the
        /// rectangle crossing only the far plane, settled by comparing vertices with it) counts
        /// what the plain definition counts, which is the triangles with a vertex up to the
        /// far plane (a brute-force count); the area is the plain one, bit for bit.
        #[test]
        fn a_far_plane_through_a_terrain_counts_as_the_plain_definition(
            n in 8usize..40,
            s in 5.0..40.0f64,
            seed in 0.1..3.0f64,
            d in (-1.0..1.0f64, -1.0..-0.2f64, -1.0..1.0f64),
            f in 0.0..1.0f64,
        ) {
            let mut m = Mesh::default();
            terrain(&mut m, n, s, seed);
            let basis = LightBasis::new(DVec3::new(d.0, d.1, d.2));
            let light = LightScene::new(&m, &basis);
            let o = &light.objects[0];
            let far = o.lo.z + f * (o.hi.z - o.lo.z);
            let v = CasterVolume {
                basis,
                lo: o.lo - DVec3::ONE,
                hi: DVec3::new(o.hi.x + 1.0, o.hi.y + 1.0, far),
                texel: DVec2::new(0.25, 0.5),
            };
            let (c, p) = (light.counts(&m, &v, |_| true), counts_plain(&light, &m, &v, |_| true));
            let brute = m.triangles.iter().filter(|t| t.iter().any(|q| basis.to_light(*q).z <= far)).count() as u64;
            prop_assert!(brute > 0);
            prop_assert_eq!(p.caster_triangles_inside, brute);
            prop_assert_eq!(c.caster_triangles_inside, brute);
            prop_assert_eq!(c.raster_fragments.to_bits(), p.raster_fragments.to_bits());
        }

        /// Skipping the planes a polygon lies within changes no answer and no bit of an area,
        /// also for triangles with vertices on the box's planes.
        #[test]
        fn skipping_planes_changes_no_clip(
            t in prop::array::uniform3((0i32..9, 0i32..9, 0i32..9)),
            jitter in prop::array::uniform3(-0.5..0.5f64),
            b in (0i32..5, 0i32..5, 0i32..5, 1i32..6, 1i32..6, 1i32..6),
        ) {
            // Vertices on a half-unit grid (many on the box's planes), some moved off it.
            let t: [DVec3; 3] = std::array::from_fn(|k| {
                let (x, y, z) = t[k];
                DVec3::new(x as f64 * 0.5, y as f64 * 0.5 + jitter[k] * f64::from(k == 1), z as f64 * 0.5)
            });
            let lo = DVec3::new(b.0 as f64, b.1 as f64, b.2 as f64) * 0.5;
            let hi = lo + DVec3::new(b.3 as f64, b.4 as f64, b.5 as f64) * 0.5;
            prop_assert_eq!(triangle_meets_box(&t, lo, hi), meets_plain(&t, lo, hi));
            prop_assert_eq!(
                clipped_area(&t, lo.truncate(), hi.truncate()).to_bits(),
                area_plain(&t, lo.truncate(), hi.truncate()).to_bits()
            );
        }

        /// A triangle within three edges of a rectangle and crossing the fourth: its area
        /// clipped by that edge alone ([`one_edge_area`]) equals [`clipped_area`] (and the
        /// plain clip by all four edges) bit for bit, on random triangles and rectangles, with
        /// the edge through a vertex (ties) or strictly between them.
        #[test]
        fn one_edge_area_equals_the_clipped_area_bit_for_bit(
            t in prop::array::uniform3((-10.0..10.0f64, -10.0..10.0f64, -1.0..1.0f64)),
            margins in prop::array::uniform4(0.0..3.0f64),
            edge in 0usize..4,
            cut in 0.0..1.0f64,
            on_vertex in prop::option::of(0usize..3),
        ) {
            let t: [DVec3; 3] = t.map(|(x, y, z)| DVec3::new(x, y, z));
            let (tlo, thi) = (t[0].min(t[1]).min(t[2]).truncate(), t[0].max(t[1]).max(t[2]).truncate());
            // The triangle's bounds padded (every vertex within every edge), then one edge
            // moved into the triangle's extent on its axis.
            let mut lo = tlo - DVec2::new(margins[0], margins[1]);
            let mut hi = thi + DVec2::new(margins[2], margins[3]);
            let (axis, below) = (edge % 2, edge >= 2);
            let bound = match on_vertex {
                Some(k) => t[k][axis],
                None => tlo[axis] + cut * (thi[axis] - tlo[axis]),
            };
            if below { hi[axis] = bound } else { lo[axis] = bound }
            let inner = t.iter().filter(|p| on_side(p[axis], bound, below)).count();
            prop_assume!(inner == 1 || inner == 2);
            let fast = one_edge_area(&t, axis, bound, below);
            prop_assert_eq!(fast.to_bits(), clipped_area(&t, lo, hi).to_bits());
            prop_assert_eq!(fast.to_bits(), area_plain(&t, lo, hi).to_bits());
            // Independently: the parts on either side of the edge make up the whole triangle
            // (its closed-form area), within rounding.
            let (mut olo, mut ohi) = (tlo - DVec2::ONE, thi + DVec2::ONE);
            if below { olo[axis] = bound } else { ohi[axis] = bound }
            let (whole, beyond) = (projected_area(&t), clipped_area(&t, olo, ohi));
            prop_assert!((fast + beyond - whole).abs() <= 1e-9 * (1.0 + whole), "{} + {} != {}", fast, beyond, whole);
        }

        /// Volumes counted together ([`LightScene::counts_all_many`]: lanes of one depth range
        /// walked at once, nodes and leaves classified against the lanes' common box and hull)
        /// give each volume's direct count ([`LightScene::counts`]) bit for bit: runs of a
        /// volume shifted by sub-texel amounts (one cascade at several resolutions), with edges
        /// through scene vertices and lanes' edges equal, mixed with volumes of other depth
        /// ranges and empty ones, asked twice (the second time from memory).
        #[test]
        fn volumes_counted_together_equal_the_direct_counts_bit_for_bit(
            m in scene(),
            d in (-1.0..1.0f64, -1.0..-0.2f64, -1.0..1.0f64),
            r in prop::array::uniform6(0.0..1.0f64),
            snap in prop::option::of(prop::array::uniform4(0usize..10_000)),
            shifts in prop::collection::vec((prop::array::uniform4(-1.0..1.0f64), 0u8..4), 1..7),
            scale in prop::sample::select(vec![0.0, 1e-9, 0.01, 0.3, 3.0]),
            other in prop::collection::vec(prop::array::uniform6(0.0..1.0f64), 0..3),
        ) {
            let base = volume(&m, DVec3::new(d.0, d.1, d.2), r, snap);
            let light = LightScene::new(&m, &base.basis);
            let mut vs = Vec::new();
            for (k, (s, kind)) in shifts.iter().enumerate() {
                let mut v = base;
                match kind {
                    // The same volume again.
                    0 => {}
                    // One edge moved (the others shared with the base).
                    1 => v.lo.x += scale * s[0],
                    // Every edge moved: a sub-texel shift and a slightly other size.
                    2 => {
                        v.lo += DVec3::new(scale * s[0], scale * s[1], 0.0);
                        v.hi += DVec3::new(scale * s[2], scale * s[3], 0.0);
                    }
                    // An edge through a scene vertex.
                    _ => {
                        let p = light.basis.to_light(m.triangles[k * 7919 % m.triangles.len()][k % 3]);
                        if s[0] < 0.0 { v.hi.y = p.y } else { v.lo.x = p.x }
                    }
                }
                v.texel = DVec2::new(0.25, 0.5) * (1.0 + k as f64);
                vs.push(v);
            }
            // Volumes of other depth ranges (and maybe empty) between the runs.
            for (k, o) in other.iter().enumerate() {
                let v = volume(&m, DVec3::new(d.0, d.1, d.2), *o, None);
                vs.insert((k * 3) % (vs.len() + 1), v);
            }
            let direct: Vec<CostCounts> = vs.iter().map(|v| light.counts(&m, v, |_| true)).collect();
            for _ in 0..2 {
                let together = light.counts_all_many(&m, &vs);
                prop_assert_eq!(together.len(), vs.len());
                for (t, c) in together.iter().zip(&direct) {
                    prop_assert_eq!(t.caster_objects, c.caster_objects);
                    prop_assert_eq!(t.caster_triangles, c.caster_triangles);
                    prop_assert_eq!(t.caster_triangles_inside, c.caster_triangles_inside);
                    prop_assert_eq!(t.raster_fragments.to_bits(), c.raster_fragments.to_bits());
                }
            }
            // And each against the plain definition (no node settled, every plane clipped).
            for (v, c) in vs.iter().zip(&direct) {
                let plain = counts_plain(&light, &m, v, |_| true);
                prop_assert_eq!(plain.caster_triangles_inside, c.caster_triangles_inside);
                prop_assert_eq!(plain.raster_fragments.to_bits(), c.raster_fragments.to_bits());
            }
        }

        /// The bounds of the receivers in view-depth intervals equal a scan of every receiver
        /// (the same minima and maxima), with ties in depth, intervals ending on a receiver's
        /// depth, empty and reversed intervals, and any number of receivers around a block's
        /// size.
        #[test]
        fn the_receiver_index_equals_a_scan(
            pts in prop::collection::vec((0u8..40, point()), 0..300),
            intervals in prop::collection::vec((0u8..42, 0u8..42), 0..3),
        ) {
            let pts: Vec<(f64, DVec3)> = pts.into_iter().map(|(d, p)| (d as f64 * 0.5, p)).collect();
            let intervals: Vec<(f64, f64)> = intervals.into_iter().map(|(a, b)| (a as f64 * 0.5, b as f64 * 0.5)).collect();
            let index = ReceiverIndex::new(pts.iter().copied());
            prop_assert_eq!(index.len(), pts.len());
            let scan = pts
                .iter()
                .filter(|(d, _)| intervals.iter().any(|&(a, b)| *d >= a && *d <= b))
                .fold(NO_BOUNDS, |(lo, hi), (_, p)| (lo.min(*p), hi.max(*p)));
            prop_assert_eq!(index.bounds(&intervals), scan);
        }
    }

    fn point() -> impl Strategy<Value = DVec3> {
        (-50.0..50.0f64, -50.0..50.0f64, -50.0..50.0f64).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    /// A LightScene keeps one receiver index per key, made once.
    #[test]
    fn a_receiver_index_is_made_once_per_key() {
        let mut m = Mesh::default();
        m.add_ground(0.0, -1.0, 1.0, -1.0, 1.0);
        let light = LightScene::new(&m, &LightBasis::new(DVec3::new(0.1, -1.0, 0.2)));
        let made = std::cell::Cell::new(0);
        let make = |d: f64| {
            made.set(made.get() + 1);
            ReceiverIndex::new([(d, DVec3::splat(d))])
        };
        let a = light.receiver_index(&1u32, || make(1.0));
        let b = light.receiver_index(&1u32, || make(2.0));
        let c = light.receiver_index(&2u32, || make(3.0));
        assert!(std::sync::Arc::ptr_eq(&a, &b));
        assert_eq!(made.get(), 2);
        assert_eq!(c.bounds(&[(0.0, 5.0)]), (DVec3::splat(3.0), DVec3::splat(3.0)));
        assert_eq!(a.bounds(&[(0.0, 5.0)]), (DVec3::splat(1.0), DVec3::splat(1.0)));
    }
}
