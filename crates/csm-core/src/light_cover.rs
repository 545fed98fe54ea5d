//! Which triangle a ray along the light meets first, decided per cell of a light-space grid
//! where that is certain: the fast path of the ground truth's texel rays
//! (docs/ground-truth.md, "The map").
//!
//! A texel's ray starts before every triangle and runs along the light, so the triangle it
//! meets first depends only on where it crosses light-space x/y. A [`LightCover`] splits the
//! scene's light-space footprint into cells and classifies each one, on first use:
//!
//! - **empty** when no triangle's projection comes within the margin `δ` of the cell: every
//!   ray through it misses;
//! - **owned** by triangle `T` when the cell grown by `δ` lies inside `T`'s projection and
//!   every other triangle's part over that grown cell lies at least `δ` deeper along the light
//!   than `T`'s plane: every ray through the cell meets `T` first;
//! - **unknown** otherwise (an edge, a silhouette or a tie runs through it): the BVH answers.
//!
//! `δ` is [`MARGIN_REL`] times the scene's coordinate scale, orders of magnitude above the
//! error of the BVH's binary32 ray and triangle tests, so the BVH's own answer for a ray
//! through an owned cell is that triangle (its mesh index as the BVH reports it: the first of
//! identical binary32 triangles; zero-area ones are never owners or obstacles, since the BVH
//! leaves them out). A coarse cell that is unknown is split into [`FINE`]² fine cells,
//! classified the same way. The hit distance is then computed from the triangle exactly as
//! [`SceneGeometry::first_hit`] computes it, so a texel's stored depth is the same to the bit.
//!
//! A ray through a cell still unknown after the refinements is answered by
//! [`LightCover::nearest`]: the BVH's own binary32 triangle test on each of the coarse cell's
//! candidates (the triangles whose bounding box, grown by `2δ`, meets the cell), with the BVH's
//! rule (least hit distance, ties to the least index). That rule is what the BVH answers
//! whatever its tree (its boxes are conservative, [`crate::bvh4`]), and the candidates hold
//! every triangle the ray can meet, so the answer is the BVH's without traversing it.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::OnceLock;

use glam::{DVec2, DVec3};

use crate::geometry::LightBasis;
use crate::mesh::Mesh;

/// The margin `δ` (light-space x/y and depth) is this fraction of `1 +` the scene's largest
/// absolute coordinate: about 1,700 binary32 unit roundoffs of it, where the BVH's
/// ray and triangle tests err by a few tens.
pub const MARGIN_REL: f64 = 1e-4;

/// Cells per side of a refined cell.
pub const FINE: usize = 16;

/// How many times a cell is refined at most.
pub const LEVELS: usize = 2;

const UNKNOWN: u32 = u32::MAX;
const EMPTY: u32 = u32::MAX - 1;
const AMBIGUOUS: u32 = u32::MAX - 2;
const REFINED: u32 = u32::MAX - 3;

/// What a cell says about the rays through it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cell {
    /// No triangle: the ray misses.
    Miss,
    /// This triangle (mesh index) is met first.
    Owner(usize),
    /// Not certain: cast the ray.
    Unknown,
}

/// Most candidates [`LightCover::nearest`] tests; a coarse cell with more is left to the BVH.
pub const TESTED_MAX: usize = 64;

/// Most cells [`LightCover::region_owner`] visits before it gives up.
pub const REGION_CELLS: usize = 64;

/// A triangle's plane along the light ([`LightCover::plane`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightPlane {
    pub k: f64,
    pub gx: f64,
    pub gy: f64,
    /// `|n| / |n . z|` (`n` the triangle's edge cross product, `z` the light): the factor by
    /// which the hit distance's rounding grows over its inputs' (1 facing the light).
    pub cond: f64,
    /// The largest absolute coordinate of the vertex the hit distance starts from.
    pub reach: f64,
}

/// A triangle as the BVH's leaf test holds it (`crate::bvh4`'s `Tri4`, one lane): its binary32
/// vertex `v0`, `e1 = v0 - v1`, `e2 = v2 - v0` and `n = e1 x e2`, computed by the same
/// operations from the same binary32 triangle ([`crate::visibility::bvh_input`]'s); and its
/// light-space x/y box grown by `2δ` (`lo`, `hi`), outside which no ray along the light meets it.
#[derive(Debug, Clone, Copy)]
struct Tri32 {
    lo: DVec2,
    hi: DVec2,
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
    n: [f32; 3],
}

impl Tri32 {
    fn new(t: &[DVec3; 3], light: &LightTri, margin: f64) -> Self {
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for p in light.p {
            lo = lo.min(p.truncate());
            hi = hi.max(p.truncate());
        }
        let v = |p: DVec3| glam_bvh::Vec3A::new(p.x as f32, p.y as f32, p.z as f32);
        let (v0, v1, v2) = (v(t[0]), v(t[1]), v(t[2]));
        let e1 = v0 - v1;
        let e2 = v2 - v0;
        let n = e1.cross(e2);
        let a = |x: glam_bvh::Vec3A| [x.x, x.y, x.z];
        Tri32 {
            lo: lo - DVec2::splat(2.0 * margin),
            hi: hi + DVec2::splat(2.0 * margin),
            v0: a(v0),
            e1: a(e1),
            e2: a(e2),
            n: a(n),
        }
    }

    /// The BVH leaf test's distance for the binary32 ray `o + t d` (its lane's operations in
    /// the same order, hence the same value to the bit): `t` in `[tmin, tmax]`, else infinity.
    #[inline]
    fn hit(&self, o: [f32; 3], d: [f32; 3], tmin: f32, tmax: f32) -> f32 {
        let (v0, n, e1, e2) = (&self.v0, &self.n, &self.e1, &self.e2);
        let c0 = v0[0] - o[0];
        let c1 = v0[1] - o[1];
        let c2 = v0[2] - o[2];
        let r0 = d[1] * c2 - d[2] * c1;
        let r1 = d[2] * c0 - d[0] * c2;
        let r2 = d[0] * c1 - d[1] * c0;
        let inv_det = 1.0 / (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]);
        let u = (r0 * e2[0] + r1 * e2[1] + r2 * e2[2]) * inv_det;
        let v = (r0 * e1[0] + r1 * e1[1] + r2 * e1[2]) * inv_det;
        let w = 1.0 - u - v;
        let inside = (u.to_bits() | v.to_bits() | w.to_bits()) & 0x8000_0000 == 0;
        let t = (n[0] * c0 + n[1] * c1 + n[2] * c2) * inv_det;
        let ok = inv_det != 0.0 && inside && t >= tmin && t <= tmax;
        if ok {
            t
        } else {
            f32::INFINITY
        }
    }
}

/// A triangle in light coordinates (x, y across the light, z its depth along it).
#[derive(Debug, Clone, Copy)]
struct LightTri {
    p: [DVec3; 3],
    /// Its mesh index (the one the BVH reports).
    mesh: u32,
}

/// The scene's triangles over a light-space grid, classified lazily (see the module docs).
pub struct LightCover {
    pub basis: LightBasis,
    tris: Vec<LightTri>,
    lo: DVec2,
    cell: DVec2,
    inv: DVec2,
    cols: usize,
    rows: usize,
    /// The coarse cells.
    coarse: Node,
    /// Candidates per coarse cell (CSR): triangles whose grown bounding box meets the grown cell.
    start: Vec<u32>,
    cand: Vec<u32>,
    margin: f64,
    /// The triangles' edge vectors' cross products, as `first_hit` computes them.
    normals: Vec<DVec3>,
    /// Per triangle of `tris`, what the BVH's leaf test holds ([`LightCover::nearest`]).
    tris32: Vec<Tri32>,
}

/// A block of cells: per cell its class (`UNKNOWN` until classified, `EMPTY`, `AMBIGUOUS`,
/// `REFINED` or the owner's mesh index) and, once refined, its [`FINE`]² sub-cells.
struct Node {
    class: Box<[AtomicU32]>,
    sub: Box<[OnceLock<Box<Node>>]>,
}

impl Node {
    fn new(cells: usize) -> Self {
        Self {
            class: (0..cells).map(|_| AtomicU32::new(UNKNOWN)).collect(),
            sub: (0..cells).map(|_| OnceLock::new()).collect(),
        }
    }
}

impl std::fmt::Debug for LightCover {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LightCover")
            .field("triangles", &self.tris.len())
            .field("cols", &self.cols)
            .field("rows", &self.rows)
            .finish()
    }
}

impl LightCover {
    /// The cover of `mesh` in `basis` (no cell classified yet), over its triangles `index`
    /// (the distinct ones the BVH holds).
    pub fn new(mesh: &Mesh, index: &[u32], basis: &LightBasis) -> Self {
        let scale = mesh
            .bounds()
            .map_or(1.0, |b| b.min.abs().max(b.max.abs()).max_element())
            + 1.0;
        let margin = MARGIN_REL * scale;
        let light = |v: DVec3| DVec3::new(basis.x.dot(v), basis.y.dot(v), basis.z.dot(v));
        let tris: Vec<LightTri> = index
            .iter()
            .map(|&k| LightTri {
                p: mesh.triangles[k as usize].map(light),
                mesh: k,
            })
            .collect();
        let normals = mesh
            .triangles
            .iter()
            .map(|[a, b, c]| (*b - *a).cross(*c - *a))
            .collect();
        let tris32 = tris
            .iter()
            .map(|t| Tri32::new(&mesh.triangles[t.mesh as usize], t, margin))
            .collect();
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for t in &tris {
            for p in t.p {
                lo = lo.min(p.truncate());
                hi = hi.max(p.truncate());
            }
        }
        if tris.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            lo = DVec2::ZERO;
            hi = DVec2::ONE;
        }
        let lo = lo - DVec2::splat(2.0 * margin);
        let hi = hi + DVec2::splat(2.0 * margin);
        // About 16 coarse cells per triangle, between 16 and 512 per side.
        let side = ((tris.len() as f64).sqrt() * 4.0).ceil().clamp(16.0, 512.0) as usize;
        let (cols, rows) = (side, side);
        let cell = (hi - lo) / DVec2::new(cols as f64, rows as f64);
        let inv = DVec2::ONE / cell;
        // Bin each triangle's grown bounding box into the coarse cells it meets.
        let range = |t: &LightTri| {
            let (mut a, mut b) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
            for p in t.p {
                a = a.min(p.truncate());
                b = b.max(p.truncate());
            }
            let a = ((a - DVec2::splat(2.0 * margin) - lo) * inv).floor().max(DVec2::ZERO);
            let b = ((b + DVec2::splat(2.0 * margin) - lo) * inv).floor();
            let b = b.min(DVec2::new(cols as f64 - 1.0, rows as f64 - 1.0));
            (a.x as usize, a.y as usize, b.x as usize, b.y as usize)
        };
        let mut count = vec![0u32; cols * rows + 1];
        for t in &tris {
            let (x0, y0, x1, y1) = range(t);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    count[y * cols + x + 1] += 1;
                }
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let start = count.clone();
        let mut cand = vec![0u32; *count.last().unwrap_or(&0) as usize];
        for (k, t) in tris.iter().enumerate() {
            let (x0, y0, x1, y1) = range(t);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * cols + x;
                    cand[count[c] as usize] = k as u32;
                    count[c] += 1;
                }
            }
        }
        Self {
            basis: *basis,
            tris,
            lo,
            cell,
            inv,
            cols,
            rows,
            coarse: Node::new(cols * rows),
            start,
            cand,
            margin,
            normals,
            tris32,
        }
    }

    /// What the cell under light-space x/y `q` says (classifying it on first use, and refining
    /// an uncertain cell into [`FINE`]² cells up to [`LEVELS`] times).
    #[inline]
    pub fn at(&self, q: DVec2) -> Cell {
        let u = (q - self.lo) * self.inv;
        if !(u.x >= 0.0 && u.y >= 0.0 && u.x < self.cols as f64 && u.y < self.rows as f64) {
            // Outside the grid: at least 2δ from every triangle's projection (or not a number).
            return if u.is_finite() { Cell::Miss } else { Cell::Unknown };
        }
        let (i, j) = (u.x as usize, u.y as usize);
        let cands = self.candidates(i, j);
        let mut node = &self.coarse;
        let mut k = j * self.cols + i;
        // The cell's minimum corner and size, and `u` within it (0 to 1 per axis).
        let mut a = self.lo + self.cell * DVec2::new(i as f64, j as f64);
        let mut size = self.cell;
        let mut u = u - DVec2::new(i as f64, j as f64);
        let mut level = 0;
        loop {
            match self.class(node, k, cands, a, size, level) {
                EMPTY => return Cell::Miss,
                AMBIGUOUS => return Cell::Unknown,
                REFINED => {
                    node = node.sub[k].get_or_init(|| Box::new(Node::new(FINE * FINE)));
                    // `u` is at least 0: truncation is its floor.
                    let v = u * FINE as f64;
                    let (x, y) = ((v.x as usize).min(FINE - 1), (v.y as usize).min(FINE - 1));
                    let f = DVec2::new(x as f64, y as f64);
                    k = y * FINE + x;
                    size /= FINE as f64;
                    a += size * f;
                    u = v - f;
                    level += 1;
                }
                t => return Cell::Owner(t as usize),
            }
        }
    }

    /// Cell `k` of `node` (minimum corner `a`, size `size`, at refinement `level`, among the
    /// coarse cell's candidates `cands`): its class, classified on first use.
    #[inline]
    fn class(&self, node: &Node, k: usize, cands: &[u32], a: DVec2, size: DVec2, level: usize) -> u32 {
        let mut class = node.class[k].load(Ordering::Relaxed);
        if class == UNKNOWN {
            class = match classify(&self.tris, cands, a, a + size, self.margin) {
                AMBIGUOUS if level < LEVELS => REFINED,
                c => c,
            };
            node.class[k].store(class, Ordering::Relaxed);
        }
        class
    }

    /// The triangle every ray along the light through the rectangle `[lo, hi]` (light-space
    /// x/y) meets first, when every cell the rectangle meets (at the depth [`LightCover::at`]
    /// reaches) is owned by that one triangle: then [`LightCover::at`] names it at every point
    /// of the rectangle, and so does the BVH (the owner test's margin). None when the
    /// rectangle meets an empty, uncertain or differently owned cell, leaves the grid, or
    /// meets more than [`REGION_CELLS`] cells (classifying the cells it visits on first use).
    pub fn region_owner(&self, lo: DVec2, hi: DVec2) -> Option<usize> {
        let u0 = (lo - self.lo) * self.inv;
        let u1 = (hi - self.lo) * self.inv;
        if !(u0.x >= 0.0 && u0.y >= 0.0 && u1.x < self.cols as f64 && u1.y < self.rows as f64) {
            return None;
        }
        let (i0, j0, i1, j1) = (u0.x as usize, u0.y as usize, u1.x as usize, u1.y as usize);
        let mut owner = None;
        let mut budget = REGION_CELLS;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let a = self.lo + self.cell * DVec2::new(i as f64, j as f64);
                let cell = (&self.coarse, j * self.cols + i, a, self.cell, 0);
                if !self.owns(cell, self.candidates(i, j), (lo, hi), &mut owner, &mut budget) {
                    return None;
                }
            }
        }
        owner.map(|t| t as usize)
    }

    /// Whether every cell of `(node, k, corner, size, level)` that meets `rect` is owned by
    /// `owner` (set by the first owner met); [`LightCover::region_owner`]'s walk.
    fn owns(
        &self,
        (node, k, a, size, level): (&Node, usize, DVec2, DVec2, usize),
        cands: &[u32],
        rect: (DVec2, DVec2),
        owner: &mut Option<u32>,
        budget: &mut usize,
    ) -> bool {
        if *budget == 0 {
            return false;
        }
        *budget -= 1;
        match self.class(node, k, cands, a, size, level) {
            EMPTY | AMBIGUOUS => false,
            REFINED => {
                let sub: &Node = node.sub[k].get_or_init(|| Box::new(Node::new(FINE * FINE)));
                let fine = size / FINE as f64;
                // The sub-cells the rectangle meets, one more either side of the rounding.
                let last = (FINE - 1) as f64;
                let v0 = ((rect.0 - a) / fine).floor().clamp(DVec2::ZERO, DVec2::splat(last));
                let v1 = ((rect.1 - a) / fine).floor().clamp(DVec2::ZERO, DVec2::splat(last));
                for y in v0.y as usize..=v1.y as usize {
                    for x in v0.x as usize..=v1.x as usize {
                        let corner = a + fine * DVec2::new(x as f64, y as f64);
                        let cell = (sub, y * FINE + x, corner, fine, level + 1);
                        if !self.owns(cell, cands, rect, owner, budget) {
                            return false;
                        }
                    }
                }
                true
            }
            t => *owner.get_or_insert(t) == t,
        }
    }

    /// The plane of mesh triangle `id` as a texel's ray along the light sees it: the depth
    /// [`LightCover::hit_distance`] gives (plus the ray's start depth) for the ray through
    /// light-space x/y `c` is, in exact arithmetic, `k - gx c.x - gy c.y` whatever the
    /// start. None for a triangle edge-on to the light.
    pub fn plane(&self, mesh: &Mesh, id: usize) -> Option<LightPlane> {
        let n = self.normals[id];
        let dir = self.basis.z + DVec3::ZERO;
        let nd = n.dot(dir);
        if nd == 0.0 || !nd.is_finite() {
            return None;
        }
        let a = mesh.triangles[id][0];
        Some(LightPlane {
            k: n.dot(a) / nd,
            gx: n.dot(self.basis.x) / nd,
            gy: n.dot(self.basis.y) / nd,
            cond: n.length() / nd.abs(),
            reach: a.abs().max_element(),
        })
    }

    /// The hit of the ray from `origin` along `dir` on mesh triangle `id`, as
    /// [`SceneGeometry::first_hit`] computes it once the BVH has named the triangle.
    #[inline]
    pub fn hit_distance(&self, mesh: &Mesh, id: usize, origin: DVec3, dir: DVec3, tmin: f64) -> f64 {
        let dir = dir + DVec3::ZERO;
        let a = mesh.triangles[id][0];
        let n = self.normals[id];
        let nd = n.dot(dir);
        if nd != 0.0 {
            n.dot(a - origin) / nd
        } else {
            tmin
        }
    }

    /// The mesh index of the triangle [`SceneGeometry::first_hit`]'s BVH names for the ray
    /// from `origin` along `dir` over `[tmin, tmax]`, which runs along the light through
    /// light-space x/y `q` (None: it misses): each candidate of `q`'s coarse cell whose box
    /// grown by `2δ` holds `q` tested as the BVH's leaves test it, with its rule (least binary32 distance, ties to the least index;
    /// the candidates are in index order). None when `q` is off the grid (or not a number) or
    /// its coarse cell has more than [`TESTED_MAX`] candidates: ask the BVH.
    ///
    /// Any triangle the binary32 ray meets lies within the rounding of the ray's origin and
    /// direction (and of the test) of `q` in light space, orders of magnitude inside the `2δ`
    /// by which a candidate's box is grown: the candidates whose grown box holds `q` hold it.
    #[inline]
    pub fn nearest(&self, q: DVec2, origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> Option<Option<usize>> {
        let u = (q - self.lo) * self.inv;
        if !(u.x >= 0.0 && u.y >= 0.0 && u.x < self.cols as f64 && u.y < self.rows as f64) {
            return None;
        }
        let cands = self.candidates(u.x as usize, u.y as usize);
        if cands.len() > TESTED_MAX {
            return None;
        }
        // The binary32 ray as `first_hit` builds it (a -0 component of the direction made +0).
        let dir = dir + DVec3::ZERO;
        let o = [origin.x as f32, origin.y as f32, origin.z as f32];
        let d = [dir.x as f32, dir.y as f32, dir.z as f32];
        let (tmin, tmax) = (tmin as f32, tmax as f32);
        let mut best = (tmax, None);
        for &k in cands {
            let tri = &self.tris32[k as usize];
            // Off its grown box the ray cannot meet it (the candidates' own rule, per ray).
            if !(q.x >= tri.lo.x && q.x <= tri.hi.x && q.y >= tri.lo.y && q.y <= tri.hi.y) {
                continue;
            }
            let t = tri.hit(o, d, tmin, tmax);
            if t < best.0 {
                best = (t, Some(k));
            }
        }
        Some(best.1.map(|k| self.tris[k as usize].mesh as usize))
    }

    fn candidates(&self, i: usize, j: usize) -> &[u32] {
        let c = j * self.cols + i;
        &self.cand[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

/// A convex polygon in light coordinates (at most 7 vertices: a triangle clipped by 4 lines).
struct Poly {
    v: [DVec3; 8],
    n: usize,
}

impl Poly {
    /// Keeps the part where `side(p) >= 0` (`side` linear in x/y), interpolating depth.
    fn clip(&self, side: impl Fn(DVec3) -> f64) -> Self {
        let mut out = Self {
            v: [DVec3::ZERO; 8],
            n: 0,
        };
        for k in 0..self.n {
            let (p, q) = (self.v[k], self.v[(k + 1) % self.n]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push(p + (q - p) * t);
            }
        }
        out
    }

    fn push(&mut self, p: DVec3) {
        if self.n < self.v.len() {
            self.v[self.n] = p;
            self.n += 1;
        }
    }
}

/// Twice the signed area of 2D triangle (a, b, c).
fn cross2(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// The class of the rectangle `[a, b]` (light-space x/y) among `cands`: `EMPTY`, an owner's
/// mesh index, or `AMBIGUOUS` (see the module docs).
fn classify(tris: &[LightTri], cands: &[u32], a: DVec2, b: DVec2, margin: f64) -> u32 {
    let (a, b) = (a - DVec2::splat(margin), b + DVec2::splat(margin));
    let corners = [a, DVec2::new(b.x, a.y), b, DVec2::new(a.x, b.y)];
    // The candidates' parts over the grown cell.
    let mut parts: Vec<(usize, Poly)> = Vec::with_capacity(cands.len());
    for &k in cands {
        let t = &tris[k as usize];
        let mut p = Poly {
            v: [DVec3::ZERO; 8],
            n: 3,
        };
        p.v[..3].copy_from_slice(&t.p);
        let p = p
            .clip(|v| v.x - a.x)
            .clip(|v| b.x - v.x)
            .clip(|v| v.y - a.y)
            .clip(|v| b.y - v.y);
        if p.n >= 3 {
            parts.push((k as usize, p));
        }
    }
    if parts.is_empty() {
        return EMPTY;
    }
    // The owner must contain the grown cell; of several, the nearest at its centre.
    let centre = (a + b) * 0.5;
    let mut owner: Option<(usize, f64)> = None;
    for (k, _) in &parts {
        let t = &tris[*k];
        let [p, q, r] = t.p.map(|v| v.truncate());
        let area = cross2(p, q, r);
        if area == 0.0 {
            continue;
        }
        let inside = corners.iter().all(|&c| {
            [cross2(p, q, c), cross2(q, r, c), cross2(r, p, c)]
                .iter()
                .all(|e| e * area > 0.0)
        });
        if inside {
            let z = plane_depth(t, centre);
            if owner.is_none_or(|(_, best)| z < best) {
                owner = Some((*k, z));
            }
        }
    }
    let Some((o, _)) = owner else {
        return AMBIGUOUS;
    };
    let t = &tris[o];
    for (k, part) in &parts {
        if *k == o {
            continue;
        }
        if part.v[..part.n]
            .iter()
            .any(|v| v.z.is_nan() || v.z < plane_depth(t, v.truncate()) + margin)
        {
            return AMBIGUOUS;
        }
    }
    t.mesh
}

/// The depth of triangle `t`'s plane over light-space x/y `q` (barycentric interpolation).
fn plane_depth(t: &LightTri, q: DVec2) -> f64 {
    let [p, r, s] = t.p;
    let (p2, r2, s2) = (p.truncate(), r.truncate(), s.truncate());
    let area = cross2(p2, r2, s2);
    let (wp, wr, ws) = (
        cross2(r2, s2, q) / area,
        cross2(s2, p2, q) / area,
        cross2(p2, r2, q) / area,
    );
    wp * p.z + wr * r.z + ws * s.z
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::mesh::Mesh;
    use crate::rng::SplitMix64;
    use crate::visibility::SceneGeometry;

    /// Four lights: the default one, a low one from the side, straight down and grazing; the
    /// ground-truth tests use them too.
    pub(crate) const LIGHTS: [DVec3; 4] = [
        DVec3::new(-0.4, -1.0, -0.3),
        DVec3::new(0.3, -0.2, 0.9),
        DVec3::new(0.0, -1.0, 0.0),
        DVec3::new(1.0, -1e-3, 0.0),
    ];

    /// The default scene's ground and boxes (a tree canopy above its trunk, a low wall); the
    /// ground-truth tests use it too.
    pub(crate) fn scene() -> SceneGeometry {
        let mut mesh = Mesh::default();
        mesh.add_ground(0.0, -200.0, 200.0, -200.0, 200.0);
        for (min, max) in [
            ([-40.0, 0.0, -90.0], [-20.0, 40.0, -60.0]),
            ([15.0, 0.0, -70.0], [35.0, 25.0, -45.0]),
            ([-12.0, 0.0, -160.0], [12.0, 30.0, -130.0]),
            ([-7.2, 0.0, -24.2], [-6.8, 3.0, -23.8]),
            ([-9.0, 3.0, -26.0], [-5.0, 7.0, -22.0]),
            ([5.0, 0.0, -20.0], [25.0, 1.5, -19.5]),
        ] {
            mesh.add_box(&Aabb::new(DVec3::from(min), DVec3::from(max)));
        }
        SceneGeometry::new(mesh)
    }

    /// Rays along the light from before every triangle, through points spread over the scene's
    /// footprint and clustered at its edges: wherever the cover names a triangle (or a miss),
    /// the BVH names the same one and the hit distance is the same to the bit. The cover must
    /// decide most rays, or it is no fast path.
    #[test]
    fn the_cover_agrees_with_the_bvh_wherever_it_decides() {
        let scene = scene();
        let b = scene.mesh.bounds().unwrap();
        for light in LIGHTS {
            let basis = LightBasis::new(light);
            let cover = LightCover::new(&scene.mesh, &crate::visibility::bvh_input(&scene.mesh).1, &basis);
            let (lo, hi) = crate::cost::light_depth_extent(&basis, &b);
            let start = lo - 1.0;
            let mut rng = SplitMix64::new(7);
            let mut decided = 0;
            let n = 40_000;
            for k in 0..n {
                // Half uniform over the footprint, half within a unit of a box corner.
                let q = if k % 2 == 0 {
                    let p = DVec3::new(rng.range(-230.0, 230.0), rng.range(0.0, 40.0), rng.range(-230.0, 230.0));
                    basis.to_light_xy(p)
                } else {
                    let c = scene.mesh.triangles[(rng.next_u64() % scene.mesh.triangles.len() as u64) as usize][0];
                    basis.to_light_xy(c) + DVec2::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))
                };
                let origin = basis.x * q.x + basis.y * q.y + basis.z * start;
                let bvh = scene.first_hit(origin, basis.z, 0.0, hi - lo + 2.0);
                match cover.at(q) {
                    Cell::Unknown => continue,
                    Cell::Miss => assert_eq!(bvh, None, "{light} at {q}"),
                    Cell::Owner(t) => {
                        let h = bvh.unwrap_or_else(|| panic!("{light} at {q}: the BVH misses {t}"));
                        assert_eq!(h.triangle, t, "{light} at {q}");
                        assert_eq!(
                            cover.hit_distance(&scene.mesh, t, origin, basis.z, 0.0).to_bits(),
                            h.t.to_bits()
                        );
                    }
                }
                decided += 1;
            }
            assert!(decided > n * 7 / 10, "{light}: the cover decided {decided} of {n} rays");
        }
    }

    /// [`LightCover::nearest`] names the BVH's triangle for every ray it answers, ties on
    /// shared edges included, and the hit distance from it is the BVH's to the bit: rays along
    /// the light through the triangles' projected vertices and through points of their edges
    /// moved across by 0 to 1 % of a unit (most of them inside the band `δ` where the cover
    /// leaves cells unknown), under the four lights, on the default scene and on a mesh of
    /// fans (shared edges), a copy and overlapping coplanar triangles (equal distances).
    #[test]
    fn nearest_is_the_bvh_s_answer_on_edges_and_ties() {
        let mut ties = Mesh::default();
        ties.add_ground(0.0, -20.0, 20.0, -20.0, 20.0);
        let c = DVec3::new(1.0, 2.0, -3.0);
        for k in 0..7 {
            let a = |k: i32| {
                let f = f64::from(k) * std::f64::consts::TAU / 7.0;
                c + DVec3::new(5.0 * f.cos(), 0.5 * f.sin(), 5.0 * f.sin())
            };
            ties.push([c, a(k), a(k + 1)]);
        }
        let [p, q, r] = [
            DVec3::new(-8.0, 1.0, 8.0),
            DVec3::new(-2.0, 1.0, 8.0),
            DVec3::new(-5.0, 1.0, 2.0),
        ];
        ties.push([p, q, r]);
        ties.push([q, r, p]);
        ties.push([p, (p + q) * 0.5, r]);
        ties.push([
            DVec3::new(-9.0, 1.0, 9.0),
            DVec3::new(-1.0, 1.0, 9.0),
            DVec3::new(-5.0, 1.0, 4.0),
        ]);
        for (n, scene) in [scene(), SceneGeometry::new(ties)].into_iter().enumerate() {
            let b = scene.mesh.bounds().unwrap();
            let (mut asked, mut unknown, mut tied) = (0, 0, 0);
            for light in LIGHTS {
                let basis = LightBasis::new(light);
                let cover = LightCover::new(&scene.mesh, &crate::visibility::bvh_input(&scene.mesh).1, &basis);
                let (lo, hi) = crate::cost::light_depth_extent(&basis, &b);
                let (start, length) = (lo - 1.0, hi - lo + 2.0);
                let mut rng = SplitMix64::new(11);
                for t in &scene.mesh.triangles {
                    let p = t.map(|v| basis.to_light_xy(v));
                    for e in 0..3 {
                        let (a, z) = (p[e], p[(e + 1) % 3]);
                        let across = (z - a).perp().normalize_or_zero();
                        for k in 0..24 {
                            let along = if k == 0 { 0.0 } else { rng.range(0.0, 1.0) };
                            let by = [0.0, 1e-7, 1e-5, 1e-3, 1e-2][k % 5] * rng.range(-1.0, 1.0);
                            let q = a + (z - a) * along + across * by;
                            let origin = basis.x * q.x + basis.y * q.y + basis.z * start;
                            let Some(got) = cover.nearest(q, origin, basis.z, 0.0, length) else {
                                continue;
                            };
                            let bvh = scene.first_hit(origin, basis.z, 0.0, length);
                            assert_eq!(got, bvh.map(|h| h.triangle), "{light} at {q}");
                            if let (Some(t), Some(h)) = (got, bvh) {
                                let d = cover.hit_distance(&scene.mesh, t, origin, basis.z, 0.0);
                                assert_eq!(d.to_bits(), h.t.to_bits(), "{light} at {q}");
                            }
                            asked += 1;
                            unknown += usize::from(cover.at(q) == Cell::Unknown);
                            // Rays that two triangles meet at the same binary32 distance.
                            let (o, d) = (origin.as_vec3().to_array(), basis.z.as_vec3().to_array());
                            let mut ts: Vec<f32> =
                                cover.tris32.iter().map(|t| t.hit(o, d, 0.0, length as f32)).collect();
                            ts.sort_by(f32::total_cmp);
                            tied += usize::from(ts[0].is_finite() && ts[0] == ts[1]);
                        }
                    }
                }
            }
            assert!(unknown > asked / 4, "{unknown} of {asked} rays in unknown cells");
            assert!(n == 0 || tied > 100, "{tied} of {asked} rays tied");
        }
    }
}
