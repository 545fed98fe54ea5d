//! A four-wide BVH and its traversal: the ray caster of the visibility pass and of the ground
//! truth.
//!
//! **Build.** `obvhs` builds a binary BVH (PLOC, then reinsertion: its `fast_build` preset)
//! over the binary32 triangles; it is collapsed into nodes of up to four children by opening,
//! while a node has fewer than four, the child of largest surface area. Each node stores its
//! children's boxes as six lanes of four binary32 values (min and max per axis), so one ray
//! tests all four boxes with the same four-wide operations. Triangles are stored in the order
//! of the leaves.
//!
//! **Conservative boxes.** Each stored box is the exact binary32 box of its triangles widened on
//! every side by `2^-16` of its largest absolute coordinate (and at least `1e-20`), well above
//! the rounding of the slab test and of the triangle test's hit distance, so a box test never
//! drops a triangle that the triangle test would hit. The slab test uses `1 / d` per axis,
//! replaced by `±1e30` where `|d| <= 1e-30` (a zero component: the slab then spans every
//! distance from inside it, none from outside, since a widened box is never thinner than
//! `2e-20`).
//!
//! **The same hits.** A leaf runs `obvhs`'s own triangle test (Möller–Trumbore in binary32).
//! The answer is the triangle of least hit distance `t` with `tmin <= t < tmax`; among
//! triangles at exactly that distance (a ray through a shared edge), the one of least index.
//! That rule does not depend on the tree or on the order of traversal: it is what testing
//! every triangle gives (`nearest_brute_force`, which the tests compare against).

use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::PlocBuilder;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// No triangle.
const NONE: u32 = u32::MAX;

/// A node: the boxes of up to four children, lane `i` for child `i`.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Node4 {
    /// `[min x, max x, min y, max y, min z, max z]`, each over the four children. An empty
    /// lane has min `+inf` and max `-inf` (no ray meets it).
    b: [[f32; 4]; 6],
    /// Inner child: its node index; leaf child: its leaf's index.
    child: [u32; 4],
    /// 0 for an inner child, else the leaf's number of triangles.
    count: [u32; 4],
}

impl Node4 {
    const EMPTY: Node4 = Node4 {
        b: [
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
        ],
        child: [NONE; 4],
        count: [0; 4],
    };
}

/// Most triangles in a leaf: a binary subtree of at most this many becomes one leaf.
const LEAF: u32 = 4;

/// Four triangles side by side (lane `i` for triangle `i`), with what `obvhs`'s triangle test
/// computes from the vertices alone: `v0`, `e1 = v0 - v1`, `e2 = v2 - v0` and `n = e1 x e2`
/// (x, y, z rows). The test below is that test's operations in the same order, four lanes at
/// once, so each lane's distance is the same to the bit.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Tri4 {
    v0: [[f32; 4]; 3],
    e1: [[f32; 4]; 3],
    e2: [[f32; 4]; 3],
    n: [[f32; 4]; 3],
}

impl Tri4 {
    fn new(tris: &[Triangle]) -> Tri4 {
        let mut q = Tri4 {
            v0: [[0.0; 4]; 3],
            e1: [[0.0; 4]; 3],
            e2: [[0.0; 4]; 3],
            n: [[0.0; 4]; 3],
        };
        for (i, t) in tris.iter().enumerate() {
            let e1 = t.v0 - t.v1;
            let e2 = t.v2 - t.v0;
            let n = e1.cross(e2);
            for a in 0..3 {
                q.v0[a][i] = t.v0[a];
                q.e1[a][i] = e1[a];
                q.e2[a][i] = e2[a];
                q.n[a][i] = n[a];
            }
        }
        q
    }

    /// `Triangle::intersect` of each lane: the distance `t` in `[tmin, tmax]`, else infinity.
    /// Branch-free over the four lanes (so that the compiler makes it four-wide).
    #[inline(always)]
    fn intersect(&self, o: [f32; 3], d: [f32; 3], tmin: f32, tmax: f32) -> [f32; 4] {
        // The origin's terms, then the per-ray rest: one copy of the test for single rays and
        // packets (the same operations in the same order either way).
        self.intersect_seen(&self.seen_from(o), d, tmin, tmax)
    }
}

/// [`Tri4::intersect`] of rays from one origin (a packet's), with each term of the test that
/// depends on the origin and the triangle alone worked out once: `c = v0 - o` and the
/// distance's numerator `n . c`. The remaining per-ray operations are the plain test's, on the
/// same operands in the same order, so each lane's distance is the same to the bit.
struct SeenFrom {
    /// Per lane: `c` (x, y, z rows) and `n . c`.
    c: [[f32; 4]; 3],
    nc: [f32; 4],
}

impl Tri4 {
    /// The origin's terms of each lane ([`SeenFrom`]).
    #[inline(always)]
    fn seen_from(&self, o: [f32; 3]) -> SeenFrom {
        let (v0, n) = (&self.v0, &self.n);
        let mut c = [[0.0f32; 4]; 3];
        let mut nc = [0.0f32; 4];
        for i in 0..4 {
            c[0][i] = v0[0][i] - o[0];
            c[1][i] = v0[1][i] - o[1];
            c[2][i] = v0[2][i] - o[2];
            nc[i] = n[0][i] * c[0][i] + n[1][i] * c[1][i] + n[2][i] * c[2][i];
        }
        SeenFrom { c, nc }
    }

    /// [`Tri4::intersect`] of the ray from the origin of `at` ([`Tri4::seen_from`]) along `d`.
    #[inline(always)]
    fn intersect_seen(&self, at: &SeenFrom, d: [f32; 3], tmin: f32, tmax: f32) -> [f32; 4] {
        let (n, e1, e2, c) = (&self.n, &self.e1, &self.e2, &at.c);
        let mut out = [0.0f32; 4];
        for i in 0..4 {
            let (c0, c1, c2) = (c[0][i], c[1][i], c[2][i]);
            let r0 = d[1] * c2 - d[2] * c1;
            let r1 = d[2] * c0 - d[0] * c2;
            let r2 = d[0] * c1 - d[1] * c0;
            let inv_det = 1.0 / (n[0][i] * d[0] + n[1][i] * d[1] + n[2][i] * d[2]);
            let u = (r0 * e2[0][i] + r1 * e2[1][i] + r2 * e2[2][i]) * inv_det;
            let v = (r0 * e1[0][i] + r1 * e1[1][i] + r2 * e1[2][i]) * inv_det;
            let w = 1.0 - u - v;
            let inside = (u.to_bits() | v.to_bits() | w.to_bits()) & 0x8000_0000 == 0;
            let t = at.nc[i] * inv_det;
            let ok = inv_det != 0.0 && inside && t >= tmin && t <= tmax;
            out[i] = if ok { t } else { f32::INFINITY };
        }
        out
    }
}

/// [`Tri4::intersect`] of rays straight down (`d`: zero x and z) from a grid of origins at one
/// height, with each term of the test that depends on the origin's x alone worked out once per
/// column and each that depends on its z alone once per row: the same operations on the same
/// operands, so the same bits. With `d = (0, dy, 0)` the test's cross products are
/// `r0 = dy c2 - 0 c1`, `r1 = 0 c0 - 0 c2` (a signed zero, from the signs of `c0` and `c2`) and
/// `r2 = 0 c1 - dy c0`, where `c0` depends on x, `c2` on z and `c1` on neither.
struct Down4 {
    tri: Tri4,
    d: [f32; 3],
    /// Per lane: `c1`, `n1 c1` and the inverse determinant (the same for every origin).
    c1: [f32; 4],
    n1c1: [f32; 4],
    inv_det: [f32; 4],
    /// Per column and lane: `d2 c0`, `r2 e2z`, `r2 e1z`, `n0 c0`.
    cols: Vec<[[f32; 4]; 4]>,
}

/// The terms of one row of origins (one z), per lane: `d0 c2`, `r0 e2x`, `r0 e1x`, `n2 c2`.
struct DownRow([[f32; 4]; 4]);

impl Tri4 {
    /// The column terms of rays straight down (`d`) from `(x, y, ·)` for each x of `xs`.
    fn down(&self, xs: &[f32], y: f32, d: [f32; 3]) -> Down4 {
        let (v0, n, e1, e2) = (&self.v0, &self.n, &self.e1, &self.e2);
        let mut c1 = [0.0f32; 4];
        let mut n1c1 = [0.0f32; 4];
        let mut inv_det = [0.0f32; 4];
        for i in 0..4 {
            c1[i] = v0[1][i] - y;
            n1c1[i] = n[1][i] * c1[i];
            inv_det[i] = 1.0 / (n[0][i] * d[0] + n[1][i] * d[1] + n[2][i] * d[2]);
        }
        let cols = xs
            .iter()
            .map(|&x| {
                let mut t = [[0.0f32; 4]; 4];
                for i in 0..4 {
                    let c0 = v0[0][i] - x;
                    let r2 = d[0] * c1[i] - d[1] * c0;
                    t[0][i] = d[2] * c0;
                    t[1][i] = r2 * e2[2][i];
                    t[2][i] = r2 * e1[2][i];
                    t[3][i] = n[0][i] * c0;
                }
                t
            })
            .collect();
        Down4 {
            tri: *self,
            d,
            c1,
            n1c1,
            inv_det,
            cols,
        }
    }
}

impl Down4 {
    /// The row terms of the origins at `z`.
    fn row(&self, z: f32) -> DownRow {
        let (v0, n, e1, e2, d) = (&self.tri.v0, &self.tri.n, &self.tri.e1, &self.tri.e2, &self.d);
        let mut t = [[0.0f32; 4]; 4];
        for i in 0..4 {
            let c2 = v0[2][i] - z;
            let r0 = d[1] * c2 - d[2] * self.c1[i];
            t[0][i] = d[0] * c2;
            t[1][i] = r0 * e2[0][i];
            t[2][i] = r0 * e1[0][i];
            t[3][i] = n[2][i] * c2;
        }
        DownRow(t)
    }

    /// [`Tri4::intersect`] of the ray from column `c` of `row`.
    #[inline(always)]
    fn intersect(&self, row: &DownRow, c: usize, tmin: f32, tmax: f32) -> [f32; 4] {
        let (e1, e2) = (&self.tri.e1, &self.tri.e2);
        let (col, row) = (&self.cols[c], &row.0);
        let mut out = [0.0f32; 4];
        for i in 0..4 {
            let r1 = col[0][i] - row[0][i];
            let u = (row[1][i] + r1 * e2[1][i] + col[1][i]) * self.inv_det[i];
            let v = (row[2][i] + r1 * e1[1][i] + col[2][i]) * self.inv_det[i];
            let w = 1.0 - u - v;
            let inside = (u.to_bits() | v.to_bits() | w.to_bits()) & 0x8000_0000 == 0;
            let t = (col[3][i] + self.n1c1[i] + row[3][i]) * self.inv_det[i];
            let ok = self.inv_det[i] != 0.0 && inside && t >= tmin && t <= tmax;
            out[i] = if ok { t } else { f32::INFINITY };
        }
        out
    }
}

/// One entry of the traversal stack: a child, and the distance at which the ray enters its box.
#[derive(Clone, Copy)]
pub(crate) struct Entry {
    child: u32,
    count: u32,
    near: f32,
}

/// The four-wide BVH over a list of triangles (see the module documentation).
pub(crate) struct Bvh4 {
    nodes: Vec<Node4>,
    /// The root: a node, or a leaf when the tree is one leaf.
    root: Entry,
    /// The leaves: up to [`LEAF`] triangles each, in four lanes.
    leaves: Vec<Tri4>,
    /// The index (in the list given to [`Bvh4::new`]) of each leaf's triangles.
    ids: Vec<[u32; 4]>,
    /// Each leaf's widened box, `[min x, max x, min y, max y, min z, max z]` (what its parent
    /// holds): a packet's rays test it one by one before the triangles.
    leaf_box: Vec<[f32; 6]>,
    /// The longest the traversal stack gets: three per level, plus one.
    stack_len: usize,
}

/// `v` widened outward (see the module documentation).
fn widened(min: [f32; 3], max: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let big = (0..3).fold(0.0f32, |m, i| m.max(min[i].abs()).max(max[i].abs()));
    let pad = (big * (1.0 / 65536.0)).max(1e-20);
    (
        [min[0] - pad, min[1] - pad, min[2] - pad],
        [max[0] + pad, max[1] + pad, max[2] + pad],
    )
}

impl Bvh4 {
    /// The BVH of `tris` (at least one triangle).
    pub(crate) fn new(tris: &[Triangle]) -> Bvh4 {
        assert!(!tris.is_empty(), "a BVH needs a triangle");
        let p = BvhBuildParams::fast_build();
        let mut bvh2 = PlocBuilder::with_capacity(tris.len()).build(
            p.ploc_search_distance,
            tris,
            (0..tris.len() as u32).collect(),
            p.sort_precision,
            p.search_depth_threshold,
        );
        ReinsertionOptimizer::default().run(&mut bvh2, p.reinsertion_batch_ratio, None);
        let b2 = &bvh2.nodes;
        // The number of triangles under each binary node (children come after their parent
        // in PLOC's output only sometimes: a post-order walk).
        let mut under = vec![0u32; b2.len()];
        let mut order = vec![(0usize, false)];
        while let Some((id, done)) = order.pop() {
            let n = &b2[id];
            if n.is_leaf() {
                // PLOC's leaves hold one triangle each: any leaf is small.
                assert!(n.prim_count <= LEAF, "a binary leaf of {} triangles", n.prim_count);
                under[id] = n.prim_count;
            } else if done {
                let f = n.first_index as usize;
                under[id] = under[f] + under[f + 1];
            } else {
                let f = n.first_index as usize;
                order.extend([(id, true), (f, false), (f + 1, false)]);
            }
        }
        let small = |id: usize| under[id] <= LEAF;
        let mut out = Bvh4 {
            nodes: Vec::with_capacity(b2.len() / 4 + 1),
            root: Entry {
                child: 0,
                count: 0,
                near: 0.0,
            },
            leaves: Vec::with_capacity(b2.len() / 4 + 1),
            ids: Vec::with_capacity(b2.len() / 4 + 1),
            leaf_box: Vec::with_capacity(b2.len() / 4 + 1),
            stack_len: 1,
        };
        // A small subtree's triangles as one leaf: (leaf index, triangle count).
        let emit = |out: &mut Bvh4, id: usize| -> (u32, u32) {
            let mut ks = Vec::with_capacity(LEAF as usize);
            let mut walk = vec![id];
            while let Some(i) = walk.pop() {
                let n = &b2[i];
                if n.is_leaf() {
                    let f = n.first_index as usize;
                    ks.extend_from_slice(&bvh2.primitive_indices[f..f + n.prim_count as usize]);
                } else {
                    walk.extend([n.first_index as usize + 1, n.first_index as usize]);
                }
            }
            let lane: Vec<Triangle> = ks.iter().map(|&k| tris[k as usize]).collect();
            let mut ids = [NONE; 4];
            ids[..ks.len()].copy_from_slice(&ks);
            out.leaves.push(Tri4::new(&lane));
            out.ids.push(ids);
            let a = b2[id].aabb();
            let (lo, hi) = widened(a.min.into(), a.max.into());
            out.leaf_box.push([lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]]);
            ((out.leaves.len() - 1) as u32, ks.len() as u32)
        };
        if small(0) {
            let (first, count) = emit(&mut out, 0);
            out.root = Entry {
                child: first,
                count,
                near: 0.0,
            };
            return out;
        }
        out.nodes.push(Node4::EMPTY);
        // (node index, binary node, depth in the four-wide tree)
        let mut work = vec![(0usize, 0usize, 1usize)];
        let mut depth = 1;
        while let Some((at, id, level)) = work.pop() {
            depth = depth.max(level);
            let first = b2[id].first_index as usize;
            let mut kids = vec![first, first + 1];
            while kids.len() < 4 {
                let open = kids
                    .iter()
                    .enumerate()
                    .filter(|(_, &k)| !small(k))
                    .max_by(|a, b| b2[*a.1].aabb().half_area().total_cmp(&b2[*b.1].aabb().half_area()))
                    .map(|(i, _)| i);
                let Some(i) = open else { break };
                let k = kids.remove(i);
                let f = b2[k].first_index as usize;
                kids.extend([f, f + 1]);
            }
            let mut node = Node4::EMPTY;
            for (lane, &k) in kids.iter().enumerate() {
                let a = b2[k].aabb();
                let (lo, hi) = widened(a.min.into(), a.max.into());
                for axis in 0..3 {
                    node.b[2 * axis][lane] = lo[axis];
                    node.b[2 * axis + 1][lane] = hi[axis];
                }
                if small(k) {
                    let (first, count) = emit(&mut out, k);
                    node.child[lane] = first;
                    node.count[lane] = count;
                } else {
                    let index = out.nodes.len();
                    out.nodes.push(Node4::EMPTY);
                    node.child[lane] = index as u32;
                    work.push((index, k, level + 1));
                }
            }
            out.nodes[at] = node;
        }
        out.stack_len = 3 * depth + 1;
        out
    }

    /// A stack long enough for any traversal of this tree.
    pub(crate) fn stack(&self) -> Vec<Entry> {
        Vec::with_capacity(self.stack_len)
    }

    /// The index (in the list given to [`Bvh4::new`]) of the triangle the ray meets first:
    /// least `t` with `tmin <= t < tmax`, ties to the least index. `stack` is scratch space
    /// ([`Bvh4::stack`]).
    #[inline]
    pub(crate) fn nearest(&self, ray: &Ray, stack: &mut Vec<Entry>) -> Option<u32> {
        let o = [ray.origin.x, ray.origin.y, ray.origin.z];
        let d = [ray.direction.x, ray.direction.y, ray.direction.z];
        let id = [inverse(d[0]), inverse(d[1]), inverse(d[2])];
        // Per axis, whether the ray enters a box through its max plane.
        let neg = [id[0] < 0.0, id[1] < 0.0, id[2] < 0.0];
        let mut best_t = ray.tmax;
        let mut best = NONE;
        stack.clear();
        let mut cur = Entry {
            near: ray.tmin,
            ..self.root
        };
        loop {
            if cur.count > 0 {
                let ts = self.leaves[cur.child as usize].intersect(o, d, ray.tmin, ray.tmax);
                let ids = &self.ids[cur.child as usize];
                for (i, &t) in ts.iter().enumerate().take(cur.count as usize) {
                    if t < best_t || (t == best_t && best != NONE && ids[i] < best) {
                        best_t = t;
                        best = ids[i];
                    }
                }
            } else {
                let n = &self.nodes[cur.child as usize];
                let (x0, x1) = if neg[0] { (&n.b[1], &n.b[0]) } else { (&n.b[0], &n.b[1]) };
                let (y0, y1) = if neg[1] { (&n.b[3], &n.b[2]) } else { (&n.b[2], &n.b[3]) };
                let (z0, z1) = if neg[2] { (&n.b[5], &n.b[4]) } else { (&n.b[4], &n.b[5]) };
                let mut t0 = [0f32; 4];
                let mut t1 = [0f32; 4];
                for i in 0..4 {
                    let a = max((x0[i] - o[0]) * id[0], (y0[i] - o[1]) * id[1]);
                    t0[i] = max(a, max((z0[i] - o[2]) * id[2], ray.tmin));
                    let b = min((x1[i] - o[0]) * id[0], (y1[i] - o[1]) * id[1]);
                    t1[i] = min(b, min((z1[i] - o[2]) * id[2], best_t));
                }
                if let Some(next) = descend(n, &t0, &t1, stack) {
                    cur = next;
                    continue;
                }
            }
            // The nearest entry left that the ray enters before its nearest hit so far.
            loop {
                match stack.pop() {
                    None => return (best != NONE).then_some(best),
                    Some(e) if e.near > best_t => {}
                    Some(e) => {
                        cur = e;
                        break;
                    }
                }
            }
        }
    }
}

impl Bvh4 {
    /// [`Bvh4::nearest`] of every ray straight down (direction (0, −1, 0), `tmin..tmax`) from
    /// the points `(xs[i], y, zs[j])`, row-major (row `j` holds `xs.len()` answers): the same
    /// answers, without a traversal per ray. `xs` and `zs` must be in increasing order.
    ///
    /// Each leaf's triangles are tested (by the same four-lane test) only by the rays whose
    /// origin passes the leaf box's x and z slab tests as a traversal computes them (necessary
    /// for the traversal to reach the leaf, so a superset of the rays it lets in), and each
    /// ray keeps the least distance, ties to the least index, as testing every triangle does.
    /// The traversal's answer is that brute force's (the module's tests), and its triangle lies
    /// in a leaf the ray reaches, so it is among those tested: the answers are equal.
    pub(crate) fn nearest_down(&self, xs: &[f32], zs: &[f32], y: f32, tmin: f32, tmax: f32) -> Vec<u32> {
        let d = [0.0f32, -1.0, 0.0];
        // The traversal's inverse of a zero direction component.
        let inv = inverse(0.0);
        let cols = xs.len();
        let mut best_t = vec![tmax; cols * zs.len()];
        let mut best = vec![NONE; cols * zs.len()];
        // The range of origins whose slab on one axis can admit the ray: the entry distance
        // `(lo - o) inv` at most `tmax` and the exit distance `(hi - o) inv` at least `tmin`
        // (both decrease as `o` grows, so the range is contiguous).
        let range = |v: &[f32], lo: f32, hi: f32| {
            let first = v.partition_point(|&o| (lo - o) * inv > tmax);
            let end = v.partition_point(|&o| (hi - o) * inv >= tmin);
            first..end.max(first)
        };
        for ((tri, ids), b) in self.leaves.iter().zip(&self.ids).zip(&self.leaf_box) {
            let (ri, rj) = (range(xs, b[0], b[1]), range(zs, b[4], b[5]));
            if ri.is_empty() || rj.is_empty() {
                continue;
            }
            let down = tri.down(&xs[ri.clone()], y, d);
            for j in rj {
                let row = down.row(zs[j]);
                for (c, i) in ri.clone().enumerate() {
                    let k = j * cols + i;
                    let ts = down.intersect(&row, c, tmin, tmax);
                    for (&t, &id) in ts.iter().zip(ids) {
                        if id != NONE && (t < best_t[k] || (t == best_t[k] && best[k] != NONE && id < best[k])) {
                            best_t[k] = t;
                            best[k] = id;
                        }
                    }
                }
            }
        }
        best
    }
}

/// Most rays traced as one packet.
pub(crate) const PACKET: usize = 64;

/// The children of `node` whose box the ray (or packet) enters, `t0[i] <= t1[i]`: the nearest is
/// returned to visit next and the others are pushed farthest first; None when it enters none.
#[inline]
fn descend(node: &Node4, t0: &[f32; 4], t1: &[f32; 4], stack: &mut Vec<Entry>) -> Option<Entry> {
    let mut mask = 0u32;
    for i in 0..4 {
        mask |= u32::from(t0[i] <= t1[i]) << i;
    }
    if mask == 0 {
        return None;
    }
    let entry = |i: usize| Entry {
        child: node.child[i],
        count: node.count[i],
        near: t0[i],
    };
    let first = mask.trailing_zeros() as usize;
    mask &= mask - 1;
    if mask == 0 {
        return Some(entry(first));
    }
    // Several: sorted by entry distance, the nearest last.
    let mut met = [entry(first); 4];
    let mut m = 1;
    while mask != 0 {
        let e = entry(mask.trailing_zeros() as usize);
        mask &= mask - 1;
        let mut k = m;
        while k > 0 && met[k - 1].near < e.near {
            met[k] = met[k - 1];
            k -= 1;
        }
        met[k] = e;
        m += 1;
    }
    stack.extend_from_slice(&met[..m - 1]);
    Some(met[m - 1])
}

/// `1 / d`, or `±1e30` (the sign of `d`) where `|d| <= 1e-30` (see the module documentation).
/// Written as a select (no branch), so that a packet's inverses are worked out four at a time.
#[inline(always)]
fn inverse(d: f32) -> f32 {
    let big = f32::from_bits(1e30f32.to_bits() | (d.to_bits() & 0x8000_0000));
    if d.abs() > 1e-30 {
        1.0 / d
    } else {
        big
    }
}

impl Bvh4 {
    /// [`Bvh4::nearest`] of each of up to [`PACKET`] rays (`u32::MAX` for none), traced
    /// together when they share their origin and, per axis, the sign of their direction (a
    /// tile of primary rays): a node is visited once for the packet, when the interval of its
    /// rays' slab distances (the least entry and the greatest exit over the packet) says that
    /// one of them may meet it; a leaf's box is then tested by each ray, and its triangles by
    /// those that meet it. Every test is conservative for each ray's own box test, so each
    /// ray's answer is the one it gets alone. Other rays are traced one by one.
    pub(crate) fn nearest_packet(&self, rays: &[Ray], out: &mut [u32], stack: &mut Vec<Entry>) {
        let n = rays.len();
        assert!(n <= PACKET && out.len() == n);
        if n == 0 {
            return;
        }
        let origin = rays[0].origin;
        let o = [origin.x, origin.y, origin.z];
        let mut d = [[0f32; PACKET]; 3];
        let mut id = [[0f32; PACKET]; 3];
        let mut tmin = [0f32; PACKET];
        let mut tmax = [0f32; PACKET];
        let mut shared = true;
        for (r, ray) in rays.iter().enumerate() {
            shared &= ray.origin.x.to_bits() == origin.x.to_bits()
                && ray.origin.y.to_bits() == origin.y.to_bits()
                && ray.origin.z.to_bits() == origin.z.to_bits();
            d[0][r] = ray.direction.x;
            d[1][r] = ray.direction.y;
            d[2][r] = ray.direction.z;
            tmin[r] = ray.tmin;
            tmax[r] = ray.tmax;
        }
        // Axis by axis over the packet (four rays at a time).
        for a in 0..3 {
            for (i, &x) in id[a][..n].iter_mut().zip(&d[a][..n]) {
                *i = inverse(x);
            }
        }
        let neg = [id[0][0] < 0.0, id[1][0] < 0.0, id[2][0] < 0.0];
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for a in 0..3 {
            // Every ray's sign is the first's: all negative or none.
            let negative = id[a][..n].iter().filter(|&&x| x < 0.0).count();
            shared &= negative == if neg[a] { n } else { 0 };
            for &x in &id[a][..n] {
                lo[a] = min(lo[a], x);
                hi[a] = max(hi[a], x);
            }
        }
        if !shared {
            for (ray, out) in rays.iter().zip(out.iter_mut()) {
                *out = self.nearest(ray, stack).unwrap_or(NONE);
            }
            return;
        }
        let tmin_lo = tmin[..n].iter().fold(f32::INFINITY, |m, &t| min(m, t));
        let mut best_t = tmax;
        let mut best = [NONE; PACKET];
        // The greatest distance at which a ray of the packet may still find a nearer hit.
        let mut reach = tmax[..n].iter().fold(f32::NEG_INFINITY, |m, &t| max(m, t));
        // Per axis, the lanes of the planes through which the rays enter and leave a box.
        let (ax, ay, az) = (usize::from(neg[0]), 2 + usize::from(neg[1]), 4 + usize::from(neg[2]));
        stack.clear();
        let mut cur = Entry {
            near: tmin_lo,
            ..self.root
        };
        loop {
            if cur.count > 0 {
                let b = &self.leaf_box[cur.child as usize];
                let (nx, ny, nz) = (b[ax] - o[0], b[ay] - o[1], b[az] - o[2]);
                let (fx, fy, fz) = (b[ax ^ 1] - o[0], b[ay ^ 1] - o[1], b[az ^ 1] - o[2]);
                let mut meets = [false; PACKET];
                for r in 0..n {
                    let t0 = max(max(nx * id[0][r], ny * id[1][r]), max(nz * id[2][r], tmin[r]));
                    let t1 = min(min(fx * id[0][r], fy * id[1][r]), min(fz * id[2][r], best_t[r]));
                    meets[r] = t0 <= t1;
                }
                let leaf = &self.leaves[cur.child as usize];
                let ids = &self.ids[cur.child as usize];
                let at = leaf.seen_from(o);
                for r in 0..n {
                    if !meets[r] {
                        continue;
                    }
                    let ts = leaf.intersect_seen(&at, [d[0][r], d[1][r], d[2][r]], tmin[r], tmax[r]);
                    for (i, &t) in ts.iter().enumerate().take(cur.count as usize) {
                        if t < best_t[r] || (t == best_t[r] && best[r] != NONE && ids[i] < best[r]) {
                            best_t[r] = t;
                            best[r] = ids[i];
                        }
                    }
                }
                reach = best_t[..n].iter().fold(f32::NEG_INFINITY, |m, &t| max(m, t));
            } else {
                let nd = &self.nodes[cur.child as usize];
                let mut t0 = [0f32; 4];
                let mut t1 = [0f32; 4];
                for i in 0..4 {
                    let (nx, ny, nz) = (nd.b[ax][i] - o[0], nd.b[ay][i] - o[1], nd.b[az][i] - o[2]);
                    let (fx, fy, fz) = (nd.b[ax ^ 1][i] - o[0], nd.b[ay ^ 1][i] - o[1], nd.b[az ^ 1][i] - o[2]);
                    // Rounded products are monotonic in each factor: the least entry and the
                    // greatest exit over the packet are at the ends of its inverse directions.
                    let ex = min(nx * lo[0], nx * hi[0]);
                    let ey = min(ny * lo[1], ny * hi[1]);
                    let ez = min(nz * lo[2], nz * hi[2]);
                    let lx = max(fx * lo[0], fx * hi[0]);
                    let ly = max(fy * lo[1], fy * hi[1]);
                    let lz = max(fz * lo[2], fz * hi[2]);
                    t0[i] = max(max(ex, ey), max(ez, tmin_lo));
                    t1[i] = min(min(lx, ly), min(lz, reach));
                }
                if let Some(next) = descend(nd, &t0, &t1, stack) {
                    cur = next;
                    continue;
                }
            }
            loop {
                match stack.pop() {
                    None => {
                        out.copy_from_slice(&best[..n]);
                        return;
                    }
                    Some(e) if e.near > reach => {}
                    Some(e) => {
                        cur = e;
                        break;
                    }
                }
            }
        }
    }
}

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// What [`Bvh4::nearest`] answers, by testing every triangle: least `t` with
/// `tmin <= t < tmax`, ties to the least index.
#[cfg(test)]
pub(crate) fn nearest_brute_force(tris: &[Triangle], ray: &Ray) -> Option<u32> {
    let mut best = (ray.tmax, NONE);
    for (k, tri) in tris.iter().enumerate() {
        let t = tri.intersect(ray);
        if t < best.0 {
            best = (t, k as u32);
        }
    }
    (best.1 != NONE).then_some(best.1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam_bvh::Vec3A;
    use proptest::prelude::*;

    /// Möller–Trumbore in binary32 for each lane of `tri`, every term from the ray's origin:
    /// the reference the shared-origin test ([`Tri4::seen_from`], [`Tri4::intersect_seen`])
    /// must equal to the bit.
    fn plain_lane_test(tri: &Tri4, o: [f32; 3], d: [f32; 3], tmin: f32, tmax: f32) -> [f32; 4] {
        let (v0, n, e1, e2) = (&tri.v0, &tri.n, &tri.e1, &tri.e2);
        let mut out = [0.0f32; 4];
        for i in 0..4 {
            let c0 = v0[0][i] - o[0];
            let c1 = v0[1][i] - o[1];
            let c2 = v0[2][i] - o[2];
            let r0 = d[1] * c2 - d[2] * c1;
            let r1 = d[2] * c0 - d[0] * c2;
            let r2 = d[0] * c1 - d[1] * c0;
            let inv_det = 1.0 / (n[0][i] * d[0] + n[1][i] * d[1] + n[2][i] * d[2]);
            let u = (r0 * e2[0][i] + r1 * e2[1][i] + r2 * e2[2][i]) * inv_det;
            let v = (r0 * e1[0][i] + r1 * e1[1][i] + r2 * e1[2][i]) * inv_det;
            let w = 1.0 - u - v;
            let inside = (u.to_bits() | v.to_bits() | w.to_bits()) & 0x8000_0000 == 0;
            let t = (n[0][i] * c0 + n[1][i] * c1 + n[2][i] * c2) * inv_det;
            let ok = inv_det != 0.0 && inside && t >= tmin && t <= tmax;
            out[i] = if ok { t } else { f32::INFINITY };
        }
        out
    }

    fn v(p: [f32; 3]) -> Vec3A {
        Vec3A::new(p[0], p[1], p[2])
    }

    /// A heightfield of `n x n` cells (two triangles each, sharing edges) with random heights,
    /// plus loose random triangles: many shared edges and grazing rays.
    fn scene(n: usize, heights: &[f32], loose: &[[f32; 9]]) -> Vec<Triangle> {
        let h = |i: usize, j: usize| heights[(i * 31 + j * 17) % heights.len()];
        let p = |i: usize, j: usize| v([i as f32 * 2.0 - n as f32, h(i, j), j as f32 * 2.0 - n as f32]);
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..n {
                tris.push(Triangle {
                    v0: p(i, j),
                    v1: p(i + 1, j),
                    v2: p(i + 1, j + 1),
                });
                tris.push(Triangle {
                    v0: p(i, j),
                    v1: p(i + 1, j + 1),
                    v2: p(i, j + 1),
                });
            }
        }
        for l in loose {
            tris.push(Triangle {
                v0: v([l[0], l[1], l[2]]),
                v1: v([l[3], l[4], l[5]]),
                v2: v([l[6], l[7], l[8]]),
            });
        }
        tris
    }

    /// A coordinate drawn from small integers, halves, signed zeros and arbitrary values: the
    /// cases where a lane's barycentric sign or distance sits on a zero.
    fn coordinate() -> impl Strategy<Value = f32> {
        prop_oneof![
            (-6i32..6).prop_map(|k| k as f32),
            (-12i32..12).prop_map(|k| k as f32 * 0.5),
            Just(0.0f32),
            Just(-0.0f32),
            -20.0f32..20.0,
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// The grid form of the four-lane test gives each straight-down ray the bits of the
        /// plain test ([`Tri4::intersect`]), whatever the triangles (flat, vertical, degenerate,
        /// on signed zeros) and origins.
        #[test]
        fn the_straight_down_grid_test_is_the_lane_test_to_the_bit(
            verts in prop::collection::vec(prop::array::uniform9(coordinate()), 1..=4),
            xs in prop::collection::vec(coordinate(), 1..6),
            zs in prop::collection::vec(coordinate(), 1..6),
            y in coordinate(),
            (tmin, tmax) in prop::sample::select(vec![(0.0f32, 100.0f32), (0.5, 3.0), (-5.0, 5.0)]),
        ) {
            let tris: Vec<Triangle> = verts
                .iter()
                .map(|l| Triangle { v0: v([l[0], l[1], l[2]]), v1: v([l[3], l[4], l[5]]), v2: v([l[6], l[7], l[8]]) })
                .collect();
            let tri = Tri4::new(&tris);
            let d = [0.0f32, -1.0, 0.0];
            let down = tri.down(&xs, y, d);
            for &z in &zs {
                let row = down.row(z);
                for (c, &x) in xs.iter().enumerate() {
                    let ours = down.intersect(&row, c, tmin, tmax).map(f32::to_bits);
                    let theirs = tri.intersect([x, y, z], d, tmin, tmax).map(f32::to_bits);
                    prop_assert_eq!(ours, theirs, "origin ({}, {}, {})", x, y, z);
                }
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// The packet's leaf test, with the origin's terms worked out once per leaf, gives each
        /// ray of a shared origin the bits of the plain lane test written out in full
        /// ([`plain_lane_test`]; [`Tri4::intersect`] is the packet's test too), whatever the
        /// triangles (flat, vertical, degenerate, on signed zeros), origin and directions.
        #[test]
        fn the_shared_origin_test_is_the_lane_test_to_the_bit(
            verts in prop::collection::vec(prop::array::uniform9(coordinate()), 1..=4),
            o in prop::array::uniform3(coordinate()),
            dirs in prop::collection::vec(prop::array::uniform3(coordinate()), 1..8),
            (tmin, tmax) in prop::sample::select(vec![(0.0f32, 100.0f32), (0.5, 3.0), (-5.0, 5.0)]),
        ) {
            let tris: Vec<Triangle> = verts
                .iter()
                .map(|l| Triangle { v0: v([l[0], l[1], l[2]]), v1: v([l[3], l[4], l[5]]), v2: v([l[6], l[7], l[8]]) })
                .collect();
            let tri = Tri4::new(&tris);
            let at = tri.seen_from(o);
            for d in dirs {
                let ours = tri.intersect_seen(&at, d, tmin, tmax).map(f32::to_bits);
                let theirs = plain_lane_test(&tri, o, d, tmin, tmax).map(f32::to_bits);
                prop_assert_eq!(ours, theirs, "direction {:?}", d);
                prop_assert_eq!(tri.intersect(o, d, tmin, tmax).map(f32::to_bits), theirs);
            }
        }

        /// The branch-free inverse is the plain definition's, bit for bit: `1 / d`, else
        /// `-1e30` for a negative sign bit and `1e30` otherwise (zeros, tiny values, NaN).
        #[test]
        fn the_inverse_is_its_definition(bits in any::<u32>(), tiny in -1e-29f32..1e-29) {
            let plain = |d: f32| if d.abs() > 1e-30 { 1.0 / d } else if d.is_sign_negative() { -1e30 } else { 1e30 };
            for d in [f32::from_bits(bits), tiny, 1e-30, -1e-30, 0.0, -0.0, f32::NAN, -f32::NAN] {
                prop_assert_eq!(inverse(d).to_bits(), plain(d).to_bits(), "{}", d);
            }
        }
    }

    fn ray(o: [f32; 3], d: [f32; 3], tmin: f32, tmax: f32) -> Ray {
        let d = v(d);
        let d = if d.length() > 1e-6 { d.normalize() } else { Vec3A::Y };
        Ray::new(v(o), d, tmin, tmax)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Hit for hit, the same triangle as testing every triangle (ties included), on random
        /// scenes and rays: from above, grazing, axis-aligned (zero direction components).
        #[test]
        fn nearest_equals_brute_force(
            n in 1usize..12,
            heights in prop::collection::vec(-2.0f32..2.0, 1..40),
            loose in prop::collection::vec(prop::array::uniform9(-15.0f32..15.0), 0..30),
            rays in prop::collection::vec(
                (prop::array::uniform3(-20.0f32..20.0), prop::array::uniform3(-1.0f32..1.0), 0u8..4, 0.0f32..2.0),
                1..200,
            ),
        ) {
            let tris = scene(n, &heights, &loose);
            let bvh = Bvh4::new(&tris);
            let mut stack = bvh.stack();
            for (o, d, kind, tmin) in rays {
                // Half of the rays with a zero, or a negative zero, direction component.
                let mut d = d;
                match kind {
                    1 => d[0] = 0.0,
                    2 => { d[2] = -0.0; d[0] = 0.0 }
                    3 => d[1] *= 1e-3,
                    _ => {}
                }
                let r = ray(o, d, tmin, 60.0);
                prop_assert_eq!(bvh.nearest(&r, &mut stack), nearest_brute_force(&tris, &r), "{:?}", r);
            }
        }
    }

    /// Against the traversal it replaced (`obvhs`'s eight-wide compressed BVH, its nearest hit
    /// kept by the first triangle found at the least distance): on a terrain seen by a fan of
    /// grazing rays, every ray hits or misses alike at the same binary32 distance, and the
    /// triangle is the same wherever the distance is not a tie.
    #[test]
    fn the_same_hits_as_the_compressed_wide_bvh() {
        use obvhs::cwbvh::builder::build_cwbvh_from_tris;
        use obvhs::ray::RayHit;
        let heights: Vec<f32> = (0..97).map(|k| ((k * 37 % 101) as f32 / 101.0 - 0.5) * 0.8).collect();
        let tris = scene(60, &heights, &[]);
        let old = build_cwbvh_from_tris(&tris, BvhBuildParams::fast_build(), &mut Default::default());
        let bvh = Bvh4::new(&tris);
        let mut stack = bvh.stack();
        let (mut hits, mut ties) = (0, 0);
        for i in 0..200 {
            for j in 0..120 {
                let d = [(i as f32 - 100.0) / 100.0, -0.02 - j as f32 * 0.004, -1.0];
                let r = ray([0.3, 2.5, 55.0], d, 0.1, 500.0);
                let mut h = RayHit::none();
                let found = old
                    .ray_traverse(r, &mut h, |r, k| tris[old.primitive_indices[k] as usize].intersect(r))
                    .then(|| old.primitive_indices[h.primitive_id as usize]);
                let new = bvh.nearest(&r, &mut stack);
                assert_eq!(found.is_some(), new.is_some(), "{r:?}");
                if let (Some(a), Some(b)) = (found, new) {
                    hits += 1;
                    let t = tris[a as usize].intersect(&r);
                    assert_eq!(t, tris[b as usize].intersect(&r), "{r:?}");
                    let tied = tris.iter().filter(|x| x.intersect(&r) == t).count() > 1;
                    ties += usize::from(tied);
                    assert!(tied || a == b, "{r:?}");
                }
            }
        }
        assert!(hits > 12_000, "{hits} hits, {ties} ties");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// A packet's answers are each ray's own: rays from one origin in a narrow cone (one
        /// packet), in a wide one (mixed signs: one by one), and from two origins.
        #[test]
        fn packets_equal_brute_force(
            n in 1usize..10,
            heights in prop::collection::vec(-2.0f32..2.0, 1..40),
            loose in prop::collection::vec(prop::array::uniform9(-15.0f32..15.0), 0..20),
            o in prop::array::uniform3(-12.0f32..12.0),
            axis in prop::array::uniform3(-1.0f32..1.0),
            spread in prop::sample::select(vec![1e-4f32, 1e-2, 0.2, 2.0]),
            jitter in prop::collection::vec(prop::array::uniform3(-1.0f32..1.0), 1..=PACKET),
            moved in any::<bool>(),
        ) {
            let tris = scene(n, &heights, &loose);
            let bvh = Bvh4::new(&tris);
            let mut stack = bvh.stack();
            let rays: Vec<Ray> = jitter
                .iter()
                .enumerate()
                .map(|(k, j)| {
                    let d = [axis[0] + spread * j[0], axis[1] + spread * j[1], axis[2] + spread * j[2]];
                    let o = if moved && k % 2 == 1 { [o[0] + 0.5, o[1], o[2]] } else { o };
                    ray(o, d, 0.05 * (k % 3) as f32, 40.0 + k as f32)
                })
                .collect();
            let mut out = vec![0u32; rays.len()];
            bvh.nearest_packet(&rays, &mut out, &mut stack);
            for (r, &got) in rays.iter().zip(&out) {
                prop_assert_eq!(got, nearest_brute_force(&tris, r).unwrap_or(NONE), "{:?}", r);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// A grid of rays straight down answered leaf by leaf: each answer is the ray's own
        /// traversal's and the brute force's, on random terrains with loose triangles, grids
        /// on the terrain's shared edges and vertices (ties) or off them, with origins inside
        /// and outside the scene, above it and within it (hits behind the origin miss).
        #[test]
        fn straight_down_grids_equal_each_rays_own_traversal(
            n in 1usize..10,
            heights in prop::collection::vec(-2.0f32..2.0, 1..40),
            loose in prop::collection::vec(prop::array::uniform9(-15.0f32..15.0), 0..20),
            x0 in -14.0f32..4.0,
            z0 in -14.0f32..4.0,
            step in prop::sample::select(vec![0.5f32, 1.0, 0.37, 0.113]),
            (cols, rows) in (1usize..40, 1usize..40),
            y in prop::sample::select(vec![20.0f32, 1.0, -0.5]),
            tmin in prop::sample::select(vec![0.0f32, 0.5]),
            tmax in prop::sample::select(vec![100.0f32, 3.0]),
        ) {
            let tris = scene(n, &heights, &loose);
            let bvh = Bvh4::new(&tris);
            let mut stack = bvh.stack();
            // On the half-unit lattice when `step` is a multiple of it: the terrain's edges.
            let (x0, z0) = if step == 0.5 || step == 1.0 { (x0.round(), z0.round()) } else { (x0, z0) };
            let xs: Vec<f32> = (0..cols).map(|i| x0 + i as f32 * step).collect();
            let zs: Vec<f32> = (0..rows).map(|j| z0 + j as f32 * step).collect();
            let got = bvh.nearest_down(&xs, &zs, y, tmin, tmax);
            for (k, &g) in got.iter().enumerate() {
                let r = Ray::new(v([xs[k % cols], y, zs[k / cols]]), Vec3A::NEG_Y, tmin, tmax);
                let want = bvh.nearest(&r, &mut stack);
                prop_assert_eq!(want, nearest_brute_force(&tris, &r));
                prop_assert_eq!(g, want.unwrap_or(NONE), "{:?}", r);
            }
        }
    }

    /// Rays straight down onto the shared vertices and edges of a flat grid, and along it: every
    /// one is a tie between several triangles, settled as the brute force settles it.
    #[test]
    fn ties_on_shared_edges_go_to_the_least_index() {
        let tris = scene(8, &[0.0], &[]);
        let bvh = Bvh4::new(&tris);
        let mut stack = bvh.stack();
        let mut ties = 0;
        for i in 0..=32 {
            for j in 0..=32 {
                let (x, z) = (i as f32 * 0.5 - 8.0, j as f32 * 0.5 - 8.0);
                let r = ray([x, 5.0, z], [0.0, -1.0, 0.0], 0.0, 100.0);
                let want = nearest_brute_force(&tris, &r);
                let hits = tris.iter().filter(|t| t.intersect(&r) == 5.0).count();
                ties += usize::from(hits > 1);
                assert_eq!(bvh.nearest(&r, &mut stack), want, "{x} {z}");
            }
        }
        assert!(ties > 100, "{ties}");
    }
}
