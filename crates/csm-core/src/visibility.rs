//! The visibility pass: one primary ray through the centre of each sampled screen pixel, the
//! nearest hit, and the geometric factor of per-pixel aliasing at that hit.
//!
//! **Pixels.** Screen pixel coordinates `(u, v)` run over `[0, W] x [0, H]` (the `[screen]`
//! size), `v` downward. A sampling scale `s` in (0, 1] picks `round(W s) x round(H s)` pixels
//! (at least one per axis): sample column `i` is screen pixel `floor((i + 1/2) W / cols)`, and
//! its ray goes through that pixel's centre (`+ 1/2`). The pixels stay those of `[screen]`;
//! the scale only chooses which are sampled, and every sample weighs the same.
//!
//! **Rays.** With camera frame (forward `f`, right `r`, up `u`) and half-angle tangents
//! `tanH`, `tanV`, the ray through `(u, v)` is `C + t d` with
//! `d = f + r (2u/W - 1) tanH + u (1 - 2v/H) tanV`. Because `d . f = 1`, the ray parameter `t`
//! of a hit *is* its view depth. Only hits with `near <= t <= far` count.
//!
//! **Exact hits.** The BVH ([`crate::bvh4`], binary32) only finds which triangle is nearest;
//! the hit point, depth and normal are then recomputed in f64 from that triangle's plane, so
//! the analytic tests hold to f64 precision.
//!
//! **Geometric factor.** On the hit plane (unit normal `n`), the surface point as a function
//! of the pixel is `X(u, v) = C + t(u, v) d(u, v)`, `t = n.(P0 - C) / (n.d)`. Its derivatives
//! are `X_u = t (d_u - d (n.d_u)/(n.d))` (the same with `v`), where `d_u = r 2tanH/W` and
//! `d_v = -u 2tanV/H`. With the light's x and y axes as the rows of `L` (any orthonormal pair
//! across the light direction: the singular values do not depend on which), shadow-texel
//! coordinates are `L X / T` for a texel of side `T`, so their Jacobian against pixels is
//! `J = L [X_u X_v] / T`. The per-pixel aliasing `m = 1 / sigma_min(J)` (the longest extent of
//! one texel, in pixels) is therefore `T g` with the factor `g = 1 / sigma_min(L [X_u X_v])`
//! (pixels per world unit), computed once per pixel; each configuration multiplies by its
//! cascade's texel size. `sigma_min` comes from the closed form of a 2x2 matrix: with
//! `E` the sum of squared entries and `D = |det|`, `sigma_max^2 = (E + sqrt(E^2 - 4 D^2)) / 2`
//! and `sigma_min = D / sigma_max`. A light grazing the surface drives `sigma_min` to 0; it is
//! clamped at `sigma_max / MAX_ANISOTROPY`, so `m` is always finite.
//!
//! **Facing.** The normal is turned toward the camera (`n.d < 0`). A hit is a *lit-facing
//! receiver* when that normal points toward the light: `n . (-light direction) > 0`; other
//! hits are self-shadowed whatever the map holds.
//!
//! **Two parts.** The rays, the hits, their depths and normals depend only on the camera and
//! the screen ([`Hits`], the costly part: one BVH traversal per pixel); only the lit flag and
//! the geometric factor depend on the light ([`Hits::shade`]: a few dot products per pixel and
//! a sort). A sweep over sun angles casts the rays once and shades them once per angle.

use std::sync::{Arc, Mutex, OnceLock};

use glam::DVec3;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use crate::bvh4::{Bvh4, Entry, PACKET};
use crate::geometry::{CameraPose, Lens, LightBasis};
use crate::mesh::Mesh;

/// Largest ratio of a texel's longest to shortest extent on screen: keeps `m` finite when the
/// light grazes a surface.
pub const MAX_ANISOTROPY: f64 = 1e6;

/// Everything the pass depends on: the camera (frame 0), the screen and its sampling, and the
/// light. Two passes with equal views give equal results (this is the cache key).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    pub pose: CameraPose,
    pub lens: Lens,
    pub near: f64,
    pub far: f64,
    pub width: u32,
    pub height: u32,
    /// Fraction of the width and height sampled, in (0, 1].
    pub scale: f64,
    /// Unit direction in which light travels.
    pub light: DVec3,
}

impl View {
    /// Sample columns and rows: `round(W s)` and `round(H s)`, at least 1.
    pub fn grid(&self) -> (u32, u32) {
        let n = |x: u32| ((x as f64 * self.scale).round() as u32).clamp(1, x);
        (n(self.width), n(self.height))
    }

    /// Screen coordinates (pixel units) of the centre of the pixel sampled at (col, row).
    pub fn pixel_centre(&self, col: u32, row: u32) -> (f64, f64) {
        let (cols, rows) = self.grid();
        let pick = |i: u32, n: u32, size: u32| ((i as f64 + 0.5) * size as f64 / n as f64).floor() + 0.5;
        (pick(col, cols, self.width), pick(row, rows, self.height))
    }

    /// The (unnormalised) ray direction through screen point (u, v); `d . forward = 1`.
    pub fn ray(&self, u: f64, v: f64) -> DVec3 {
        let (w, h) = (self.width as f64, self.height as f64);
        self.pose.forward
            + self.pose.right * ((2.0 * u / w - 1.0) * self.lens.tan_h)
            + self.pose.up * ((1.0 - 2.0 * v / h) * self.lens.tan_v)
    }

    /// The pass's sampling grid once: for each sample column the term `r (2u/W - 1) tanH` of
    /// [`View::ray`] at its pixel centre, for each sample row the term `u (1 - 2v/H) tanV`.
    /// `forward + across[col] + down[row]` is `ray` of that sample's centre, bit for bit (the
    /// same operations in the same order), without the per-pixel grid and rounding.
    pub fn ray_terms(&self) -> RayTerms {
        let (cols, rows) = self.grid();
        let (w, h) = (self.width as f64, self.height as f64);
        let across = (0..cols)
            .map(|c| {
                let (u, _) = self.pixel_centre(c, 0);
                self.pose.right * ((2.0 * u / w - 1.0) * self.lens.tan_h)
            })
            .collect();
        let down = (0..rows)
            .map(|r| {
                let (_, v) = self.pixel_centre(0, r);
                self.pose.up * ((1.0 - 2.0 * v / h) * self.lens.tan_v)
            })
            .collect();
        RayTerms {
            origin: self.pose.position,
            forward: self.pose.forward,
            cols: cols as usize,
            across,
            down,
        }
    }

    /// `(d_u, d_v)`: the ray direction's derivatives against screen x and y.
    pub fn ray_derivatives(&self) -> (DVec3, DVec3) {
        (
            self.pose.right * (2.0 * self.lens.tan_h / self.width as f64),
            -self.pose.up * (2.0 * self.lens.tan_v / self.height as f64),
        )
    }
}

/// [`View::ray_terms`]: a view's ray directions per sample column and row.
#[derive(Debug, Clone)]
pub struct RayTerms {
    origin: DVec3,
    forward: DVec3,
    cols: usize,
    across: Vec<DVec3>,
    down: Vec<DVec3>,
}

impl RayTerms {
    /// [`View::ray`] through the centre of sample `k` (row-major).
    #[inline]
    pub fn ray(&self, k: usize) -> DVec3 {
        self.forward + self.across[k % self.cols] + self.down[k / self.cols]
    }

    /// [`Visibility::position`] of sample `k` at view depth `depth`, bit for bit, without the
    /// per-call sampling grid.
    #[inline]
    pub fn point(&self, k: usize, depth: f64) -> DVec3 {
        self.origin + self.ray(k) * depth
    }
}

/// What one sampled pixel sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// View depth of the hit (world units); the hit point is `C + t d` with `t` this depth
    /// and `d` the pixel's ray ([`Visibility::position`]).
    pub depth: f64,
    /// The hit's normal points toward the light.
    pub lit: bool,
    /// `g`: the per-pixel aliasing is `m = T g` for texel size `T` (pixels per world unit).
    pub factor: f64,
    /// The direct-light contrast `N · L` of the hit (0 when it faces away from the light).
    pub contrast: f64,
}

/// [`Hits::triangle`] of a sample whose ray meets nothing between near and far.
pub const MISS: u32 = u32::MAX;

/// The light-independent part of a pass: every sampled pixel's hit, as two arrays (12 bytes a
/// pixel; the normal is the hit triangle's, turned toward the camera when shaded).
#[derive(Debug, Clone, PartialEq)]
pub struct Hits {
    /// The view the rays were cast for; its `light` is unused (zero).
    pub view: View,
    pub cols: u32,
    pub rows: u32,
    /// Row-major, `cols x rows`: the view depth of each sample's hit (0 for a miss).
    pub depth: Vec<f64>,
    /// Row-major: the mesh index of the triangle each sample's ray meets first, or [`MISS`]
    /// where it meets nothing between near and far.
    pub triangle: Vec<u32>,
    /// The unit normal of every mesh triangle (winding order), shared with the scene.
    normals: Arc<Vec<DVec3>>,
    /// The indices of the hits in increasing depth (ties in index order): the receivers of any
    /// light come out of it sorted by depth, without a sort per light.
    pub by_depth: Vec<u32>,
}

impl Hits {
    fn new(view: View, cols: u32, rows: u32, depth: Vec<f64>, triangle: Vec<u32>, normals: Arc<Vec<DVec3>>) -> Hits {
        let by_depth = depth_order(&depth, &triangle);
        Hits {
            view,
            cols,
            rows,
            depth,
            triangle,
            normals,
            by_depth,
        }
    }

    /// Sampled pixels (hits and misses).
    pub fn len(&self) -> usize {
        self.depth.len()
    }

    /// Whether no pixel is sampled (never for a view's grid).
    pub fn is_empty(&self) -> bool {
        self.depth.is_empty()
    }

    /// The pass of `view`: each hit shaded under `view.light` (the lit flag and the
    /// geometric factor), the receivers sorted by depth. The same, bit for bit, as casting
    /// the rays again for that light.
    pub fn shade(self: &Arc<Self>, view: &View) -> Visibility {
        let light = LightBasis::new(view.light);
        let terms = view.ray_terms();
        let derivatives = view.ray_derivatives();
        let towards_light = -view.light.normalize();
        // Per pixel: g, negated where the hit faces away from the light, and the contrast.
        // Row by row, each sample's direction the row's and column's terms added
        // ([`RayTerms::ray`]'s sum, without dividing the sample index by the row length).
        let cols = self.cols as usize;
        let (mut signed_factor, mut contrast) = (vec![0.0; self.len()], vec![0.0; self.len()]);
        signed_factor
            .par_chunks_mut(cols)
            .zip(contrast.par_chunks_mut(cols))
            .zip(self.depth.par_chunks(cols).zip(self.triangle.par_chunks(cols)))
            .enumerate()
            .with_min_len(4096usize.div_ceil(cols))
            .for_each(|(row, ((sf, c), (depth, ids)))| {
                let down = terms.down[row];
                for (col, (&depth, &id)) in depth.iter().zip(ids).enumerate() {
                    if id == MISS {
                        continue;
                    }
                    let d = terms.forward + terms.across[col] + down;
                    let n = toward(self.normals[id as usize], d);
                    let g = factor_with(derivatives, &light, n, d, depth);
                    let lit = n.dot(-view.light) > 0.0;
                    sf[col] = if lit { g } else { -g };
                    c[col] = n.dot(towards_light).max(0.0);
                }
            });
        // The lit samples in depth order, straight into the receivers and their weights;
        // equal depths then by factor (then weight), so the list is the one sorting every
        // (depth, factor, weight) triple would give.
        // Each chunk of the depth order counts its receivers, then fills its own slice of
        // the two arrays (no intermediate list).
        const CHUNK: usize = 1 << 15;
        let is_lit = |k: u32| signed_factor[k as usize].is_sign_positive();
        let counts: Vec<usize> = self
            .by_depth
            .par_chunks(CHUNK)
            .map(|ks| ks.iter().filter(|&&k| is_lit(k)).count())
            .collect();
        let total = counts.iter().sum();
        let (mut receivers, mut weights) = (vec![(0.0, 0.0); total], vec![0u32; total]);
        let mut parts = Vec::with_capacity(counts.len());
        let (mut r, mut w) = (&mut receivers[..], &mut weights[..]);
        for &n in &counts {
            let (part_r, rest_r) = std::mem::take(&mut r).split_at_mut(n);
            let (part_w, rest_w) = std::mem::take(&mut w).split_at_mut(n);
            parts.push((part_r, part_w));
            (r, w) = (rest_r, rest_w);
        }
        self.by_depth.par_chunks(CHUNK).zip(parts).for_each(|(ks, (r, w))| {
            let lit = ks.iter().filter(|&&k| is_lit(k));
            for ((r, w), &k) in r.iter_mut().zip(w.iter_mut()).zip(lit) {
                let k = k as usize;
                *r = (self.depth[k], signed_factor[k]);
                *w = contrast_weight(contrast[k]);
            }
        });
        sort_equal_depths(&mut receivers, &mut weights);
        // Every hit is a receiver or self-shadowed; depths lie in [near, far] (positive), so
        // the first and last in depth order are the least and greatest.
        let self_shadowed = self.by_depth.len() - receivers.len();
        let depth_range = self
            .by_depth
            .first()
            .zip(self.by_depth.last())
            .map(|(&a, &b)| (self.depth[a as usize], self.depth[b as usize]));
        let samples = Samples {
            hits: self.clone(),
            signed_factor,
            contrast,
        };
        Visibility::of_samples(
            *view,
            self.cols,
            self.rows,
            samples,
            (receivers, weights),
            (self_shadowed, depth_range),
        )
    }
}

/// Unit normal `n` turned toward the camera along ray `d` (negated when `n · d > 0`).
#[inline]
fn toward(n: DVec3, d: DVec3) -> DVec3 {
    if n.dot(d) > 0.0 {
        -n
    } else {
        n
    }
}

/// Every sampled pixel's [`Sample`] (row-major; [`Samples::get`]), stored compactly: the cast
/// rays' depths and triangles (shared with [`Hits`]) and two numbers per pixel, the factor `g`
/// with its sign telling whether the hit faces the light (`g > 0`, so its sign bit is free)
/// and the contrast `N · L` (16 bytes a pixel, where a list of samples took 32).
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    hits: Arc<Hits>,
    /// Per pixel: `g`, negated where the hit faces away from the light (0 for a miss).
    signed_factor: Vec<f64>,
    /// Per pixel: the contrast `N · L` (0 for a miss).
    contrast: Vec<f64>,
}

impl Samples {
    /// `n` samples that meet nothing, of a view (synthetic passes in tests).
    pub fn misses(view: &View, n: usize) -> Samples {
        let hits = Hits {
            view: unlit(view),
            cols: n as u32,
            rows: 1,
            depth: vec![0.0; n],
            triangle: vec![MISS; n],
            normals: Arc::new(Vec::new()),
            by_depth: Vec::new(),
        };
        Samples {
            hits: Arc::new(hits),
            signed_factor: vec![0.0; n],
            contrast: vec![0.0; n],
        }
    }

    /// Sampled pixels.
    pub fn len(&self) -> usize {
        self.signed_factor.len()
    }

    /// Whether no pixel is sampled.
    pub fn is_empty(&self) -> bool {
        self.signed_factor.is_empty()
    }

    /// What sample `k` (row-major) sees: None where its ray meets nothing between near and far.
    #[inline]
    pub fn get(&self, k: usize) -> Option<Sample> {
        let id = self.hits.triangle[k];
        if id == MISS {
            return None;
        }
        let g = self.signed_factor[k];
        Some(Sample {
            depth: self.hits.depth[k],
            lit: g.is_sign_positive(),
            factor: g.abs(),
            contrast: self.contrast[k],
        })
    }

    /// Every sample, row-major.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = Option<Sample>> + '_ {
        (0..self.len()).map(|k| self.get(k))
    }

    /// Every sample, row-major, on every thread.
    pub fn par_iter(&self) -> impl IndexedParallelIterator<Item = Option<Sample>> + '_ {
        (0..self.len()).into_par_iter().map(|k| self.get(k))
    }
}

/// Sorts each run of receivers at one depth (a plane seen row by row gives runs of a whole
/// row) by (factor, weight), moving the weights along. A run is sorted as whole numbers:
/// (factor in `total_cmp`'s order as bits, weight), the same order as comparing the floats.
/// Equal keys are equal entries, so a stable sort gives the same list as any; the stable sort
/// merges the rising and falling stretches a row's factors come in, where a quicksort starts
/// over. The runs are sorted on every thread.
fn sort_equal_depths(receivers: &mut [(f64, f64)], weights: &mut [u32]) {
    let mut runs = Vec::new();
    let (mut r, mut w) = (receivers, weights);
    while !r.is_empty() {
        let depth = r[0].0.to_bits();
        let len = 1 + r[1..].iter().take_while(|x| x.0.to_bits() == depth).count();
        let (run_r, rest_r) = std::mem::take(&mut r).split_at_mut(len);
        let (run_w, rest_w) = std::mem::take(&mut w).split_at_mut(len);
        if len > 1 {
            runs.push((run_r, run_w));
        }
        (r, w) = (rest_r, rest_w);
    }
    runs.into_par_iter().for_each(|(r, w)| {
        let mut keys: Vec<(u64, u32)> = r.iter().zip(w.iter()).map(|(r, &w)| (total_key(r.1), w)).collect();
        if !keys.is_sorted() {
            keys.sort();
            for ((r, w), &(k, wk)) in r.iter_mut().zip(w.iter_mut()).zip(&keys) {
                r.1 = from_total_key(k);
                *w = wk;
            }
        }
    });
}

/// The indices `k` with `depth[k]` a hit (`hit[k] != MISS`) in increasing depth, ties in
/// index order: what sorting by `(depth.total_cmp, index)` gives, by the radix sort of
/// [`sort_keys`]. O(n), where the comparison sort it replaces fetched each depth through the
/// pixel's hit on every comparison.
fn depth_order(depth: &[f64], hit: &[u32]) -> Vec<u32> {
    sort_keys(
        depth
            .iter()
            .zip(hit)
            .enumerate()
            .filter(|(_, (_, &h))| h != MISS)
            .map(|(k, (&d, _))| (total_key(d), k as u32)),
        depth.len(),
        |k| total_key(depth[k as usize]),
    )
}

/// `f64::total_cmp`'s order as unsigned integers: negative numbers reversed, below positive.
#[inline]
fn total_key(d: f64) -> u64 {
    let b = d.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | (1 << 63)
    }
}

/// The inverse of [`total_key`].
#[inline]
fn from_total_key(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// The indices `0..n` ordered by `(value(index).total_cmp, index)`: what a comparison sort
/// with that order gives, by the radix sort of [`sort_keys`].
pub(crate) fn order_by_key(n: usize, value: impl Fn(usize) -> f64) -> Vec<u32> {
    sort_keys((0..n).map(|k| (total_key(value(k)), k as u32)), n, |k| {
        total_key(value(k as usize))
    })
}

/// Binary digits of an index packed beside its key in one 64-bit word ([`sort_keys`]).
const INDEX_BITS: u32 = 21;

/// The indices of `pairs` (`(key, index)` in increasing index order, every index below
/// `bound`) ordered by `(key, index)`; `key_of(index)` is the key of an index.
///
/// When every key has the same top bit (all positive or all negative numbers, the usual case)
/// and every index fits in [`INDEX_BITS`], each pair is packed into one word: the key's bits
/// 20..62 above the index. A stable least-significant-digit radix sort of those 43 bits
/// (four passes of 11 bits, a pass skipped when every word shares its digit) orders the
/// pairs by the key's top 44 bits, ties in index order, moving 8 bytes a pair instead of 16;
/// otherwise [`radix_sort_top44`] sorts the pairs themselves. Either way, runs equal in the
/// top 44 bits are then sorted by the whole key, the index breaking ties.
fn sort_keys(pairs: impl Iterator<Item = (u64, u32)>, bound: usize, key_of: impl Fn(u32) -> u64) -> Vec<u32> {
    if bound > 1 << INDEX_BITS {
        let mut a: Vec<(u64, u32)> = pairs.collect();
        radix_sort_top44(&mut a);
        return a.into_iter().map(|(_, k)| k).collect();
    }
    let (mut all, mut any) = (u64::MAX, 0u64);
    let mut a: Vec<u64> = pairs
        .map(|(key, k)| {
            all &= key;
            any |= key;
            ((key << 1) & !((1u64 << INDEX_BITS) - 1)) | k as u64
        })
        .collect();
    if (all ^ any) >> 63 == 1 {
        // Keys of both signs: the pairs themselves.
        let mut pairs: Vec<(u64, u32)> = a
            .iter()
            .map(|&p| {
                let k = (p & ((1u64 << INDEX_BITS) - 1)) as u32;
                (key_of(k), k)
            })
            .collect();
        radix_sort_top44(&mut pairs);
        return pairs.into_iter().map(|(_, k)| k).collect();
    }
    radix_passes(&mut a, |x, p| {
        ((x >> (INDEX_BITS + RADIX_BITS * p as u32)) as usize) & (RADIX_BUCKETS - 1)
    });
    // Equal top bits: in index order (the passes are stable); order them by the whole key.
    let index = |x: u64| (x & ((1u64 << INDEX_BITS) - 1)) as u32;
    let mut out: Vec<u32> = a.iter().map(|&x| index(x)).collect();
    let mut run: Vec<(u64, u32)> = Vec::new();
    let mut start = 0;
    while start < a.len() {
        let t = a[start] >> INDEX_BITS;
        let end = start + a[start..].iter().take_while(|&&x| x >> INDEX_BITS == t).count();
        if end - start > 1 {
            run.clear();
            run.extend(out[start..end].iter().map(|&k| (key_of(k), k)));
            if !run.is_sorted() {
                run.sort_unstable();
                for (o, &(_, k)) in out[start..end].iter_mut().zip(&run) {
                    *o = k;
                }
            }
        }
        start = end;
    }
    out
}

/// Digit width and count of the radix sorts' passes: four passes of 11 bits (44 key bits).
const RADIX_BITS: u32 = 11;
const RADIX_PASSES: usize = 4;
const RADIX_BUCKETS: usize = 1 << RADIX_BITS;

/// The stable least-significant-digit passes of the radix sorts: pass `p` orders `a` by
/// `digit(x, p)` (in `0..RADIX_BUCKETS`), keeping the order of equal digits. A pass whose
/// digit every element shares is skipped (it would not move anything).
fn radix_passes<T: Copy + Default>(a: &mut Vec<T>, digit: impl Fn(T, usize) -> usize) {
    let mut counts = vec![0usize; RADIX_BUCKETS * RADIX_PASSES];
    for &x in a.iter() {
        for p in 0..RADIX_PASSES {
            counts[p * RADIX_BUCKETS + digit(x, p)] += 1;
        }
    }
    let mut b: Vec<T> = vec![T::default(); a.len()];
    for p in 0..RADIX_PASSES {
        let c = &mut counts[p * RADIX_BUCKETS..(p + 1) * RADIX_BUCKETS];
        if c.contains(&a.len()) {
            continue;
        }
        // Exclusive prefix sums: each digit's first slot.
        let mut sum = 0;
        for n in c.iter_mut() {
            let here = *n;
            *n = sum;
            sum += here;
        }
        for &x in a.iter() {
            let d = digit(x, p);
            b[c[d]] = x;
            c[d] += 1;
        }
        std::mem::swap(a, &mut b);
    }
}

/// Sorts `(key, index)` pairs given in increasing index order by `(key, index)`: a stable
/// least-significant-digit radix sort of the keys' top 44 bits (four passes of 11 bits, a
/// pass skipped when every key shares its digit), then runs of keys equal in those bits
/// sorted by the whole key, the index breaking ties ([`sort_keys`] when the pairs cannot be
/// packed into one word).
fn radix_sort_top44(a: &mut Vec<(u64, u32)>) {
    const LOW: u32 = 20;
    radix_passes(a, |x: (u64, u32), p| {
        ((x.0 >> (LOW + RADIX_BITS * p as u32)) as usize) & (RADIX_BUCKETS - 1)
    });
    // Equal top bits: in index order (the passes are stable); order them by the whole key.
    let top = |k: u64| k >> LOW;
    let mut start = 0;
    while start < a.len() {
        let t = top(a[start].0);
        let end = start + a[start..].iter().take_while(|x| top(x.0) == t).count();
        if end - start > 1 && !a[start..end].is_sorted() {
            a[start..end].sort_unstable();
        }
        start = end;
    }
}

/// The steps of a unit contrast weight: `N · L` is stored as a whole number of `2^-24`, so the
/// weighted statistics sum whole numbers exactly (in any order).
pub const CONTRAST_STEPS: f64 = (1u32 << 24) as f64;

/// A receiver's contrast weight: its direct-light contrast `N · L` in [0, 1], rounded to a
/// whole number of [`CONTRAST_STEPS`].
pub fn contrast_weight(contrast: f64) -> u32 {
    // `v.round() as u32` for v in [0, 2^24] (NaN gives 0 both ways), without the libm call
    // baseline x86-64 makes: the whole part, plus one when the rest is at least 1/2 (half away
    // from zero, as `f64::round`); the rest `v - trunc(v)` is exact below 2^52.
    let v = contrast.clamp(0.0, 1.0) * CONTRAST_STEPS;
    let whole = v as u32;
    whole + u32::from(v - whole as f64 >= 0.5)
}

/// A value made from a pass on first use and kept with it (the screen statistics' index): a
/// cache, so a clone starts empty and any two compare equal.
#[derive(Default)]
pub struct PassCache(std::sync::OnceLock<Box<dyn std::any::Any + Send + Sync>>);

impl PassCache {
    /// The value, made by `make` on first use. One cache holds one type.
    pub fn get_or_init<T: std::any::Any + Send + Sync>(&self, make: impl FnOnce() -> T) -> &T {
        self.0
            .get_or_init(|| Box::new(make()))
            .downcast_ref::<T>()
            .expect("a pass cache holds one type")
    }
}

impl Clone for PassCache {
    fn clone(&self) -> Self {
        PassCache::default()
    }
}

impl PartialEq for PassCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for PassCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PassCache")
            .field("made", &self.0.get().is_some())
            .finish()
    }
}

/// The result of one pass.
#[derive(Debug, Clone, PartialEq)]
pub struct Visibility {
    pub view: View,
    pub cols: u32,
    pub rows: u32,
    /// Row-major, `cols x rows`; None where the ray meets nothing between near and far.
    pub samples: Samples,
    /// `(depth, factor)` of every lit-facing sample, sorted by depth.
    pub receivers: Vec<(f64, f64)>,
    /// The contrast weight of each receiver (same order): [`contrast_weight`] of its `N · L`.
    pub weights: Vec<u32>,
    /// Number of samples that hit a surface facing away from the light.
    pub self_shadowed: usize,
    /// View-depth extent of every hit, or None when nothing is hit.
    pub depth_range: Option<(f64, f64)>,
    /// Smallest and largest factor `g` of the receivers, or None without receivers.
    pub factor_range: Option<(f64, f64)>,
    /// What the screen statistics of every setting read (their index of this pass), made on
    /// first use.
    pub screen_index: PassCache,
}

impl Visibility {
    /// The pass from its samples, sorted receivers with their weights, the self-shadowed
    /// count and the depth range of the hits: the factor range.
    fn of_samples(
        view: View,
        cols: u32,
        rows: u32,
        samples: Samples,
        (receivers, weights): (Vec<(f64, f64)>, Vec<u32>),
        (self_shadowed, depth_range): (usize, Option<(f64, f64)>),
    ) -> Visibility {
        let factor_range = receivers.iter().fold(None, |r: Option<(f64, f64)>, &(_, g)| {
            Some(r.map_or((g, g), |(lo, hi)| (lo.min(g), hi.max(g))))
        });
        Visibility {
            view,
            cols,
            rows,
            samples,
            receivers,
            weights,
            self_shadowed,
            depth_range,
            factor_range,
            screen_index: Default::default(),
        }
    }

    pub fn sample_count(&self) -> usize {
        self.samples.len()
    }

    /// World position of the hit of sample `k` (row-major) at view depth `depth`. It computes
    /// the sampling grid on each call: over many samples, take [`View::ray_terms`] once and
    /// [`RayTerms::point`] (the same value).
    pub fn position(&self, k: usize, depth: f64) -> DVec3 {
        let cols = self.cols as usize;
        let (u, v) = self.view.pixel_centre((k % cols) as u32, (k / cols) as u32);
        self.view.pose.position + self.view.ray(u, v) * depth
    }
}

/// `g = 1 / sigma_min(L [X_u X_v])` at a hit with view depth `t`, unit normal `n`, ray `d`.
pub fn geometric_factor(view: &View, light: &LightBasis, n: DVec3, d: DVec3, t: f64) -> f64 {
    factor_with(view.ray_derivatives(), light, n, d, t)
}

/// [`geometric_factor`] with the view's ray derivatives `(d_u, d_v)` given. Always inlined:
/// its chain of divisions and square roots is latency-bound, and inlined into the shading
/// loop the next pixels' chains overlap it (a call per pixel left them serial).
#[inline(always)]
fn factor_with((du, dv): (DVec3, DVec3), light: &LightBasis, n: DVec3, d: DVec3, t: f64) -> f64 {
    let nd = n.dot(d);
    let xu = t * (du - d * (n.dot(du) / nd));
    let xv = t * (dv - d * (n.dot(dv) / nd));
    let (a, b, c, e) = (light.x.dot(xu), light.x.dot(xv), light.y.dot(xu), light.y.dot(xv));
    1.0 / sigma_min_2x2(a, b, c, e)
}

/// Smallest singular value of `[[a, b], [c, d]]`, clamped below at
/// `sigma_max / MAX_ANISOTROPY` (and at the smallest positive normal f64 for a zero matrix).
#[inline(always)]
pub fn sigma_min_2x2(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let e = a * a + b * b + c * c + d * d;
    let det = (a * d - b * c).abs();
    let disc = (e * e - 4.0 * det * det).max(0.0).sqrt();
    let smax = ((e + disc) * 0.5).sqrt();
    if smax.is_nan() || smax <= 0.0 || !smax.is_finite() {
        return f64::MIN_POSITIVE;
    }
    (det / smax).max(smax / MAX_ANISOTROPY)
}

/// The BVH over a mesh's triangles (binary32, [`crate::bvh4`]), each distinct binary32
/// triangle once.
struct Tracer {
    /// None when no triangle is left (every one degenerate in binary32).
    bvh: Option<Bvh4>,
    tris: Vec<Triangle>,
    /// The mesh index of each BVH triangle (its first occurrence).
    mesh_index: Vec<u32>,
    dropped: BvhDropped,
}

/// What [`bvh_input`] left out of a mesh's BVH.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BvhDropped {
    /// Copies of an earlier triangle (the same three binary32 vertices, in any order).
    pub duplicates: usize,
    /// Triangles whose three binary32 vertices are collinear (zero area once rounded).
    pub degenerate: usize,
}

/// The triangles the BVH is built over: the mesh's triangles in binary32, each distinct one
/// once, without those of zero area. A ray cannot tell a copy from its original, and a
/// zero-area triangle can neither receive nor cast, so hits are unchanged; but a builder
/// given many coincident primitives makes a tree as deep as their count (10^5 copies of one
/// triangle overflowed the stack, and traversal turns linear). Returns the triangles, each
/// one's mesh index, and what was dropped.
pub fn bvh_input(mesh: &Mesh) -> (Vec<Triangle>, Vec<u32>, BvhDropped) {
    let mut seen: std::collections::HashSet<[u32; 9]> = std::collections::HashSet::with_capacity(mesh.triangles.len());
    let mut dropped = BvhDropped::default();
    let mut tris = Vec::with_capacity(mesh.triangles.len());
    let mut index = Vec::with_capacity(mesh.triangles.len());
    for (k, t) in mesh.triangles.iter().enumerate() {
        let tri = Triangle {
            v0: v3(t[0]),
            v1: v3(t[1]),
            v2: v3(t[2]),
        };
        // The area of the rounded triangle, in f64 (exact enough to tell zero).
        let f = |v: glam_bvh::Vec3A| DVec3::new(v.x as f64, v.y as f64, v.z as f64);
        if (f(tri.v1) - f(tri.v0)).cross(f(tri.v2) - f(tri.v0)) == DVec3::ZERO {
            dropped.degenerate += 1;
            continue;
        }
        let bits = |v: glam_bvh::Vec3A| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
        let mut vs = [bits(tri.v0), bits(tri.v1), bits(tri.v2)];
        vs.sort_unstable();
        let key = [
            vs[0][0], vs[0][1], vs[0][2], vs[1][0], vs[1][1], vs[1][2], vs[2][0], vs[2][1], vs[2][2],
        ];
        if !seen.insert(key) {
            dropped.duplicates += 1;
            continue;
        }
        tris.push(tri);
        index.push(k as u32);
    }
    (tris, index, dropped)
}

fn v3(p: DVec3) -> glam_bvh::Vec3A {
    glam_bvh::Vec3A::new(p.x as f32, p.y as f32, p.z as f32)
}

impl Tracer {
    fn new(mesh: &Mesh) -> Tracer {
        let (tris, mesh_index, dropped) = bvh_input(mesh);
        let bvh = (!tris.is_empty()).then(|| Bvh4::new(&tris));
        Tracer {
            bvh,
            tris,
            mesh_index,
            dropped,
        }
    }

    /// Mesh index of the nearest triangle along the ray within `[tmin, tmax]` (ray units), if
    /// any.
    fn nearest(&self, origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> Option<usize> {
        let ray = Ray::new(v3(origin), v3(dir), tmin as f32, tmax as f32);
        self.nearest_bvh(&ray).map(|b| self.mesh_index[b as usize] as usize)
    }

    /// Index (into [`bvh_input`]'s triangles) of the nearest triangle along a binary32 ray:
    /// least hit distance, ties to the least index ([`crate::bvh4`]).
    fn nearest_bvh(&self, ray: &Ray) -> Option<u32> {
        let bvh = self.bvh.as_ref()?;
        STACK.with(|s| {
            let mut s = s.borrow_mut();
            if s.capacity() == 0 {
                *s = bvh.stack();
            }
            bvh.nearest(ray, &mut s)
        })
    }
}

thread_local! {
    /// Each thread's traversal stack, reused by every ray it traces.
    static STACK: std::cell::RefCell<Vec<Entry>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The binary32 ray the BVH traverses for the pixel whose (unnormalised) ray direction is `d`
/// ([`View::ray`]): from the camera along `d / |d|`, over the view depths `[near, far]`
/// widened by a relative 1e-4 (ray units are world units along the unit direction, so view
/// depth `t` is `t |d|` along the ray). The hit is then recomputed in f64.
pub fn traced_ray(view: &View, d: DVec3) -> Ray {
    let r = primary_ray(view, d);
    Ray::new(r.origin, r.direction, r.tmin, r.tmax)
}

/// [`traced_ray`] without its inverse direction (left zero): the packet traversal computes
/// its own ([`Bvh4::nearest_packet`] reads the origin, the direction and `tmin..tmax` only),
/// so each primary ray skips `obvhs`'s three divisions.
#[inline]
fn primary_ray(view: &View, d: DVec3) -> Ray {
    let len = d.length();
    let slack = 1e-4;
    Ray {
        origin: v3(view.pose.position),
        direction: v3(d / len),
        inv_direction: glam_bvh::Vec3A::ZERO,
        tmin: (view.near * len * (1.0 - slack)) as f32,
        tmax: (view.far * len * (1.0 + slack)) as f32,
    }
}

/// The binary32 rays of every sampled pixel of a view, row-major: what [`SceneGeometry`]
/// traverses, for a benchmark peer to trace the same rays.
pub fn primary_rays(view: &View) -> Vec<Ray> {
    let (cols, rows) = view.grid();
    let terms = view.ray_terms();
    (0..cols as usize * rows as usize)
        .map(|k| traced_ray(view, terms.ray(k)))
        .collect()
}

/// A scene's geometry with its BVH (built on first use) and the passes already made.
pub struct SceneGeometry {
    pub mesh: Mesh,
    tracer: OnceLock<Tracer>,
    /// The unit normal of every mesh triangle (winding order), made with the first pass.
    normals: OnceLock<Arc<Vec<DVec3>>>,
    /// Shaded passes, one per view (camera, screen and light).
    cache: Mutex<Vec<Arc<Visibility>>>,
    /// Cast rays, one per view without its light.
    hits_cache: Mutex<Vec<Arc<Hits>>>,
    /// How many passes (and cast rays) the caches keep: [`CACHED_PASSES`], or more once a
    /// level of many views asks for it ([`SceneGeometry::keep_at_least`]).
    capacity: std::sync::atomic::AtomicUsize,
    /// The scene in a light basis (cost counts), one per basis.
    light_cache: Mutex<Vec<Arc<crate::cost::LightScene>>>,
    /// The ground truth's light-space covers (texel rays), one per basis.
    cover_cache: Mutex<Vec<Arc<crate::light_cover::LightCover>>>,
    /// Values other modules derive from the scene and keep with it ([`SceneGeometry::derived`]).
    derived_cache: Mutex<Vec<Arc<dyn std::any::Any + Send + Sync>>>,
}

/// The view without its light: the key of the light-independent part.
fn unlit(view: &View) -> View {
    View {
        light: DVec3::ZERO,
        ..*view
    }
}

/// Side of the square tiles in which the rays are traced (one packet each).
const TILE: usize = 8;
const _: () = assert!(TILE * TILE <= PACKET);

/// `f(k, d, id)` of every sample `k` of a view's grid ([`View::ray_terms`]), row-major, as two
/// arrays, where `d` is the sample's ray direction ([`RayTerms::ray`], made once per sample)
/// and `id` the nearest BVH triangle along its binary32 ray ([`primary_ray`]; an index into
/// [`bvh_input`]'s triangles, or `u32::MAX`). The grid goes in bands of [`TILE`] rows (in
/// parallel) and a band in `TILE x TILE` tiles, each tile's rays traced as one packet
/// ([`Bvh4::nearest_packet`]: each ray's answer is its own). The order changes no value.
fn tiled<A: Send + Clone + Default, B: Send + Clone + Default>(
    tracer: &Tracer,
    view: &View,
    terms: &RayTerms,
    f: impl Fn(usize, DVec3, u32) -> (A, B) + Sync,
) -> (Vec<A>, Vec<B>) {
    let (cols, rows) = (terms.cols, terms.down.len());
    let mut out_a: Vec<A> = vec![A::default(); cols * rows];
    let mut out_b: Vec<B> = vec![B::default(); cols * rows];
    out_a
        .par_chunks_mut(cols * TILE)
        .zip(out_b.par_chunks_mut(cols * TILE))
        .enumerate()
        .for_each(|(band, (out_a, out_b))| {
            let band_rows = out_a.len() / cols;
            let mut stack = tracer.bvh.as_ref().map_or_else(Vec::new, Bvh4::stack);
            let mut rays = Vec::with_capacity(TILE * TILE);
            let mut at = Vec::with_capacity(TILE * TILE);
            let mut dirs = [DVec3::ZERO; TILE * TILE];
            let mut ids = [u32::MAX; TILE * TILE];
            for x0 in (0..cols).step_by(TILE) {
                rays.clear();
                at.clear();
                for y in 0..band_rows {
                    // `terms.ray(k)` of the samples of this row: the same sum in the same order.
                    let down = terms.down[band * TILE + y];
                    for x in x0..(x0 + TILE).min(cols) {
                        let d = terms.forward + terms.across[x] + down;
                        dirs[at.len()] = d;
                        at.push(y * cols + x);
                        rays.push(primary_ray(view, d));
                    }
                }
                let ids = &mut ids[..rays.len()];
                match &tracer.bvh {
                    Some(bvh) => bvh.nearest_packet(&rays, ids, &mut stack),
                    None => ids.fill(u32::MAX),
                }
                for ((&i, &id), &d) in at.iter().zip(ids.iter()).zip(&dirs) {
                    (out_a[i], out_b[i]) = f(band * TILE * cols + i, d, id);
                }
            }
        });
    (out_a, out_b)
}

/// Passes (and cast rays) a scene keeps: the latest ones.
const CACHED_PASSES: usize = 8;

impl SceneGeometry {
    pub fn new(mesh: Mesh) -> Self {
        SceneGeometry {
            mesh,
            tracer: OnceLock::new(),
            normals: OnceLock::new(),
            cache: Mutex::new(Vec::new()),
            hits_cache: Mutex::new(Vec::new()),
            capacity: std::sync::atomic::AtomicUsize::new(CACHED_PASSES),
            light_cache: Mutex::new(Vec::new()),
            cover_cache: Mutex::new(Vec::new()),
            derived_cache: Mutex::new(Vec::new()),
        }
    }

    /// The light-space cover of the scene in `basis` (the ground truth's texel rays), made
    /// once per basis when `make` is set, else only looked up (the latest [`CACHED_PASSES`]
    /// bases are kept).
    pub fn light_cover(&self, basis: &LightBasis, make: bool) -> Option<Arc<crate::light_cover::LightCover>> {
        let same = |c: &Arc<crate::light_cover::LightCover>| c.basis == *basis;
        {
            let cache = self.cover_cache.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(c) = cache.iter().find(|c| same(c)) {
                return Some(c.clone());
            }
        }
        if !make {
            return None;
        }
        let c = Arc::new(crate::light_cover::LightCover::new(
            &self.mesh,
            &bvh_input(&self.mesh).1,
            basis,
        ));
        let mut cache = self.cover_cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(found) = cache.iter().find(|c| same(c)) {
            return Some(found.clone());
        }
        if cache.len() >= CACHED_PASSES {
            cache.remove(0);
        }
        cache.push(c.clone());
        Some(c)
    }

    /// A value derived from the scene and kept with it (the ground truth's receivers and exact
    /// answers of a view and light, `crate::truth::exact_of`): the kept `T` that `same`
    /// accepts, else `make`'s, kept (the latest [`CACHED_PASSES`] values are kept). Two threads
    /// asking at once may both make it; the first kept is returned to both.
    pub fn derived<T: std::any::Any + Send + Sync>(
        &self,
        same: impl Fn(&T) -> bool,
        make: impl FnOnce() -> T,
    ) -> Arc<T> {
        type Kept = Vec<Arc<dyn std::any::Any + Send + Sync>>;
        let find = |cache: &Kept| {
            cache
                .iter()
                .find_map(|e| e.clone().downcast::<T>().ok().filter(|t| same(t)))
        };
        if let Some(t) = find(&self.derived_cache.lock().unwrap_or_else(|e| e.into_inner())) {
            return t;
        }
        let t = Arc::new(make());
        let mut cache = self.derived_cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(found) = find(&cache) {
            return found;
        }
        if cache.len() >= CACHED_PASSES {
            cache.remove(0);
        }
        cache.push(t.clone());
        t
    }

    /// The scene's triangles and objects in light basis `basis` (cost counts), made once per
    /// basis and shared by every window in it (the latest [`CACHED_PASSES`] bases are kept).
    pub fn light_scene(&self, basis: &LightBasis) -> Arc<crate::cost::LightScene> {
        {
            let cache = self.light_cache.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(l) = cache.iter().find(|l| l.basis == *basis) {
                return l.clone();
            }
        }
        let l = Arc::new(crate::cost::LightScene::new(&self.mesh, basis));
        let mut cache = self.light_cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(found) = cache.iter().find(|x| x.basis == *basis) {
            return found.clone();
        }
        if cache.len() >= CACHED_PASSES {
            cache.remove(0);
        }
        cache.push(l.clone());
        l
    }

    /// What the BVH left out of the mesh (duplicate and binary32-degenerate triangles; see
    /// [`bvh_input`]). Builds the BVH if it is not built yet.
    pub fn bvh_dropped(&self) -> BvhDropped {
        self.tracer.get_or_init(|| Tracer::new(&self.mesh)).dropped
    }

    /// Keeps at least `n` passes (and as many cast rays) from now on: a level of `n` views
    /// shares one pass per view between every setting of a sweep only if none is evicted.
    pub fn keep_at_least(&self, n: usize) {
        self.capacity.fetch_max(n, std::sync::atomic::Ordering::Relaxed);
    }

    fn capacity(&self) -> usize {
        self.capacity.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The rays of a view cast (its light ignored), computed once per camera and screen and
    /// shared by every light.
    pub fn hits(&self, view: &View) -> Arc<Hits> {
        let key = unlit(view);
        {
            let cache = self.hits_cache.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(h) = cache.iter().find(|h| h.view == key) {
                return h.clone();
            }
        }
        let h = Arc::new(self.cast_rays(&key));
        let mut cache = self.hits_cache.lock().unwrap_or_else(|e| e.into_inner());
        if cache.len() >= self.capacity() {
            cache.remove(0);
        }
        cache.push(h.clone());
        h
    }

    /// The pass for a view, computed once per view and shared (a sweep's configurations share
    /// their camera, screen and light, so they share one pass).
    pub fn visibility(&self, view: &View) -> Arc<Visibility> {
        if let Some(v) = self.cached(view) {
            return v;
        }
        let v = Arc::new(self.cast(view));
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        // A few views at most (one per camera pose and light analysed); keep the latest ones.
        if cache.len() >= self.capacity() {
            cache.remove(0);
        }
        cache.push(v.clone());
        v
    }

    fn cached(&self, view: &View) -> Option<Arc<Visibility>> {
        let cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        cache.iter().find(|v| v.view == *view).cloned()
    }

    /// The pass itself, without the pass cache (the cast rays are shared through
    /// [`Self::hits`]).
    pub fn cast(&self, view: &View) -> Visibility {
        self.hits(view).shade(view)
    }

    /// Casts the rays of a view: every sampled pixel's hit.
    fn cast_rays(&self, view: &View) -> Hits {
        let tracer = self.tracer.get_or_init(|| Tracer::new(&self.mesh));
        let normals = self.normals.get_or_init(|| {
            Arc::new(
                self.mesh
                    .triangles
                    .par_iter()
                    .with_min_len(4096)
                    .map(|&[a, b, c]| (b - a).cross(c - a).normalize())
                    .collect(),
            )
        });
        let (cols, rows) = view.grid();
        let terms = view.ray_terms();
        let (depth, triangle) = tiled(tracer, view, &terms, |_, d, id| self.hit(tracer, normals, view, d, id));
        Hits::new(*view, cols, rows, depth, triangle, normals.clone())
    }

    /// The view depth and mesh triangle of the hit of the sample whose ray direction is `d`,
    /// given the BVH triangle its binary32 ray meets first (`u32::MAX` for none); `(0, MISS)`
    /// for none.
    fn hit(&self, tracer: &Tracer, normals: &[DVec3], view: &View, d: DVec3, bvh_id: u32) -> (f64, u32) {
        const NONE: (f64, u32) = (0.0, MISS);
        let origin = view.pose.position;
        if bvh_id == u32::MAX {
            return NONE;
        }
        let id = tracer.mesh_index[bvh_id as usize];
        let a = self.mesh.triangles[id as usize][0];
        // The unit normal turned toward the camera.
        let mut n = normals[id as usize];
        let mut nd = n.dot(d);
        if nd > 0.0 {
            n = -n;
            nd = -nd;
        }
        if nd == 0.0 {
            return NONE;
        }
        let t = n.dot(a - origin) / nd;
        if !(t >= view.near && t <= view.far) {
            return NONE;
        }
        (t, id)
    }
}

/// The nearest surface along a ray: its distance along the (unit) ray and its triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleHit {
    /// Ray distance, recomputed in f64 from the triangle's plane (the BVH's binary32 answer
    /// only picks the triangle).
    pub t: f64,
    /// Index into the mesh's triangles.
    pub triangle: usize,
}

impl SceneGeometry {
    /// The nearest triangle along `origin + t dir` (unit `dir`) with `tmin <= t <= tmax`, if
    /// any, with its f64 ray distance. Shared by every ray the ground-truth pass casts.
    pub fn first_hit(&self, origin: DVec3, dir: DVec3, tmin: f64, tmax: f64) -> Option<TriangleHit> {
        let tracer = self.tracer.get_or_init(|| Tracer::new(&self.mesh));
        // A negative zero component (a negated light along an axis plane) makes the BVH's
        // traversal miss every node: adding +0 turns -0 into +0 and changes nothing else.
        let dir = dir + DVec3::ZERO;
        let id = tracer.nearest(origin, dir, tmin, tmax)?;
        Some(self.hit_on(id, origin, dir, tmin))
    }

    /// The f64 ray distance to mesh triangle `id`'s plane along `origin + t dir` (`tmin` when
    /// the ray runs along it).
    fn hit_on(&self, id: usize, origin: DVec3, dir: DVec3, tmin: f64) -> TriangleHit {
        let [a, b, c] = self.mesh.triangles[id];
        let n = (b - a).cross(c - a);
        let nd = n.dot(dir);
        let t = if nd != 0.0 { n.dot(a - origin) / nd } else { tmin };
        TriangleHit { t, triangle: id }
    }

    /// [`Self::first_hit`] of every ray straight down (`-Y`) from `(xs[i], y, zs[j])`,
    /// row-major (row `j` holds `xs.len()` hits), each the same hit to the bit: a plan's
    /// height image. Every leaf of the BVH is tested by the rays under its box instead of each
    /// ray traversing the tree ([`Bvh4::nearest_down`]). `xs` and `zs` must increase.
    pub fn first_hits_down(&self, xs: &[f64], zs: &[f64], y: f64, tmin: f64, tmax: f64) -> Vec<Option<TriangleHit>> {
        let tracer = self.tracer.get_or_init(|| Tracer::new(&self.mesh));
        let dir = DVec3::NEG_Y + DVec3::ZERO;
        let Some(bvh) = &tracer.bvh else {
            return vec![None; xs.len() * zs.len()];
        };
        // The binary32 rays [`Tracer::nearest`] makes of these.
        let f = |v: &[f64]| v.iter().map(|&v| v as f32).collect::<Vec<f32>>();
        let ids = bvh.nearest_down(&f(xs), &f(zs), y as f32, tmin as f32, tmax as f32);
        ids.iter()
            .enumerate()
            .map(|(k, &b)| {
                (b != u32::MAX).then(|| {
                    let origin = DVec3::new(xs[k % xs.len()], y, zs[k / xs.len()]);
                    self.hit_on(tracer.mesh_index[b as usize] as usize, origin, dir, tmin)
                })
            })
            .collect()
    }

    /// The triangles the BVH is built over ([`bvh_input`]), building it if needed.
    pub fn bvh_triangles(&self) -> &[Triangle] {
        &self.tracer.get_or_init(|| Tracer::new(&self.mesh)).tris
    }

    /// Traversal alone (no f64 hit, no sort), as the pass traverses: for each sample of the
    /// view (row-major; its ray is [`primary_rays`]'), the index into
    /// [`Self::bvh_triangles`] of the nearest triangle, or `u32::MAX` for a miss. Runs on the
    /// caller's rayon pool.
    pub fn trace(&self, view: &View) -> Vec<u32> {
        let tracer = self.tracer.get_or_init(|| Tracer::new(&self.mesh));
        tiled(tracer, view, &view.ray_terms(), |_, _, id| (id, ())).0
    }

    /// Unit normal of triangle `id` (winding order; not oriented).
    pub fn triangle_normal(&self, id: usize) -> DVec3 {
        let [a, b, c] = self.mesh.triangles[id];
        (b - a).cross(c - a).normalize_or_zero()
    }
}

impl std::fmt::Debug for SceneGeometry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneGeometry").field("mesh", &self.mesh).finish()
    }
}

impl PartialEq for SceneGeometry {
    fn eq(&self, other: &Self) -> bool {
        self.mesh == other.mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contrast_weight_is_the_rounded_steps_of_f64_round() {
        // The plain definition: clamp, scale, f64::round (libm), as u32.
        let plain = |c: f64| (c.clamp(0.0, 1.0) * CONTRAST_STEPS).round() as u32;
        let mut cs = vec![f64::NAN, -1.0, -0.0, 0.0, 1.0, 2.0, f64::INFINITY, f64::NEG_INFINITY];
        // Every step's half and its neighbours near both ends and in the middle.
        for k in (0..4096)
            .chain((1 << 23) - 2048..(1 << 23) + 2048)
            .chain((1 << 24) - 4096..=1 << 24)
        {
            let h = (k as f64 + 0.5) / CONTRAST_STEPS;
            cs.extend([h, h.next_up(), h.next_down(), k as f64 / CONTRAST_STEPS]);
        }
        let mut rng = crate::rng::SplitMix64::new(11);
        cs.extend((0..200_000).map(|_| rng.unit()));
        for c in cs {
            assert_eq!(contrast_weight(c), plain(c), "{c:e}");
        }
    }

    /// A ground plane y = 0 and a box on it, seen by a camera looking down the −Z axis.
    fn scene_and_view(light: DVec3) -> (Mesh, View) {
        let g = |x: f64, z: f64| DVec3::new(x, 0.0, z);
        let mut triangles = vec![
            [g(-100.0, 10.0), g(100.0, 10.0), g(100.0, -200.0)],
            [g(-100.0, 10.0), g(100.0, -200.0), g(-100.0, -200.0)],
        ];
        // A vertical wall facing +Z (toward the camera) at z = -40.
        let w = |x: f64, y: f64| DVec3::new(x, y, -40.0);
        triangles.push([w(-10.0, 0.0), w(10.0, 0.0), w(10.0, 8.0)]);
        triangles.push([w(-10.0, 0.0), w(10.0, 8.0), w(-10.0, 8.0)]);
        let pose = CameraPose::look_at(DVec3::new(0.0, 5.0, 0.0), DVec3::new(0.0, 0.0, -30.0), DVec3::Y).unwrap();
        let view = View {
            pose,
            lens: Lens::new(1.0, 16.0 / 9.0),
            near: 0.1,
            far: 500.0,
            width: 320,
            height: 180,
            scale: 0.5,
            light: light.normalize(),
        };
        (
            Mesh {
                triangles,
                ..Mesh::default()
            },
            view,
        )
    }

    #[test]
    fn shading_shared_rays_under_another_light_equals_a_fresh_pass_for_that_light() {
        let lights = [
            DVec3::new(-0.4, -1.0, -0.3),
            DVec3::new(0.0, -0.2, 1.0),
            DVec3::new(1.0, -0.05, 0.0),
        ];
        let (mesh, first) = scene_and_view(lights[0]);
        let shared = SceneGeometry::new(mesh.clone());
        let _ = shared.visibility(&first);
        for l in lights {
            let view = View {
                light: l.normalize(),
                ..first
            };
            let fresh = SceneGeometry::new(mesh.clone()).visibility(&view);
            let reused = shared.visibility(&view);
            assert_eq!(*reused, *fresh, "{l}");
            // The receivers are exactly the lit samples sorted by (depth, factor).
            let mut sorted: Vec<(f64, f64)> = reused
                .samples
                .iter()
                .flatten()
                .filter(|s| s.lit)
                .map(|s| (s.depth, s.factor))
                .collect();
            sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            assert_eq!(reused.receivers, sorted, "{l}");
            // One set of rays for every light.
            assert_eq!(shared.hits_cache.lock().unwrap().len(), 1);
            // Independently: the ground's samples are lit exactly when the light comes down,
            // the wall's (normal +Z) when it travels toward −Z; each factor is g of the hit.
            let light = LightBasis::new(view.light);
            for (k, s) in reused.samples.iter().enumerate() {
                let Some(s) = s else { continue };
                let p = reused.position(k, s.depth);
                let on_wall = (p.z + 40.0).abs() < 1e-6 && p.y > 1e-6;
                let n = if on_wall { DVec3::Z } else { DVec3::Y };
                assert_eq!(s.lit, n.dot(-view.light) > 0.0, "{l} sample {k}");
                let (u, v) = view.pixel_centre((k % reused.cols as usize) as u32, (k / reused.cols as usize) as u32);
                let g = geometric_factor(&view, &light, n, view.ray(u, v), s.depth);
                assert!((s.factor - g).abs() <= 1e-9 * g, "{l} sample {k}: {} vs {g}", s.factor);
            }
        }
    }

    /// The radix depth order against the comparison sort it replaced, on depths with many
    /// exact ties (a plane seen row by row), ties in the low bits only, near-equal values and
    /// a few misses.
    #[test]
    fn depth_order_equals_sorting_by_depth_then_index() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let (mut depths, mut hit) = (Vec::new(), Vec::new());
        for k in 0..50_000u32 {
            let r = next();
            let depth = match r % 5 {
                0 => 0.1 + (k / 97) as f64 * 0.37,                      // rows of equal depths
                1 => f64::from_bits(40.0f64.to_bits() + (r >> 40) % 8), // equal top bits
                2 => 1.0 + (r % 1000) as f64 * 1e-3,
                3 => (r >> 11) as f64 / (1u64 << 53) as f64 * 999.0 + 0.1,
                _ => -1.0,
            };
            // A miss keeps a depth that would sort first: it must be left out.
            depths.push(depth);
            hit.push(if depth > 0.0 { k % 7 } else { MISS });
        }
        let mut expected: Vec<u32> = (0..depths.len() as u32).filter(|&k| hit[k as usize] != MISS).collect();
        let depth = |k: u32| depths[k as usize];
        expected.sort_by(|&a, &b| depth(a).total_cmp(&depth(b)).then(a.cmp(&b)));
        assert_eq!(depth_order(&depths, &hit), expected);
        // Negative and signed-zero keys (keys of both signs: the pairs are not packed) order
        // as total_cmp orders them; so do all-negative keys (packed).
        let odd: [f64; 7] = [-2.0, 0.0, -0.0, 3.5, -1e-300, 1e300, -0.0];
        let negative: [f64; 7] = [-2.0, -0.0, -1e-300, -7.5, -0.0, -2.0, -1e300];
        for depths in [&odd[..], &negative[..]] {
            let hit = vec![0; depths.len()];
            let mut expected: Vec<u32> = (0..depths.len() as u32).collect();
            expected.sort_by(|&a, &b| depths[a as usize].total_cmp(&depths[b as usize]).then(a.cmp(&b)));
            assert_eq!(depth_order(depths, &hit), expected);
        }
    }

    /// The whole-number keys of the receivers' orders: integer order is `total_cmp`'s, the
    /// inverse gives the bits back, and the key order of a list equals its comparison sort.
    #[test]
    fn total_keys_order_as_total_cmp_and_invert() {
        let mut xs = vec![-2.0, 0.0, -0.0, 3.5, -1e-300, 1e300, f64::MIN_POSITIVE, 5e-324, -5e-324];
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        for _ in 0..20_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = f64::from_bits(state);
            if x.is_finite() {
                xs.push(x);
                // Many exact ties and neighbours.
                xs.push((state % 64) as f64 * 0.25);
            }
        }
        for &a in &xs {
            assert_eq!(from_total_key(total_key(a)).to_bits(), a.to_bits());
        }
        for w in xs.windows(2) {
            assert_eq!(total_key(w[0]).cmp(&total_key(w[1])), w[0].total_cmp(&w[1]));
        }
        let mut expected: Vec<u32> = (0..xs.len() as u32).collect();
        expected.sort_by(|&a, &b| xs[a as usize].total_cmp(&xs[b as usize]).then(a.cmp(&b)));
        assert_eq!(order_by_key(xs.len(), |k| xs[k]), expected);
        // Positive values alone: keys and indices packed into one word.
        let pos: Vec<f64> = xs.iter().copied().filter(|x| x.is_sign_positive()).collect();
        let mut expected: Vec<u32> = (0..pos.len() as u32).collect();
        expected.sort_by(|&a, &b| pos[a as usize].total_cmp(&pos[b as usize]).then(a.cmp(&b)));
        assert_eq!(order_by_key(pos.len(), |k| pos[k]), expected);
    }

    /// The traversal against a brute-force nearest hit over every triangle (the same binary32
    /// test), on a terrain with boxes seen through a camera's full grid of rays.
    #[test]
    fn traversal_finds_the_nearest_triangle_of_a_brute_force_search() {
        let (mut mesh, view) = scene_and_view(DVec3::new(-0.4, -1.0, -0.3));
        for i in 0..6 {
            let x = -30.0 + 11.0 * i as f64;
            mesh.add_box(&crate::geometry::Aabb {
                min: DVec3::new(x, 0.0, -60.0 - 7.0 * i as f64),
                max: DVec3::new(x + 4.0, 2.0 + i as f64, -55.0 - 7.0 * i as f64),
            });
        }
        let scene = SceneGeometry::new(mesh);
        let tris = scene.bvh_triangles().to_vec();
        let found = scene.trace(&view);
        let rays = primary_rays(&view);
        assert_eq!(found.len(), rays.len());
        let mut hits = 0;
        for (ray, &id) in rays.iter().zip(&found) {
            let mut best = (ray.tmax, u32::MAX);
            for (k, t) in tris.iter().enumerate() {
                let d = t.intersect(ray);
                if d >= ray.tmin && d < best.0 {
                    best = (d, k as u32);
                }
            }
            // The very triangle: a tie on a shared edge goes to the least index either way.
            assert_eq!(id, best.1);
            hits += usize::from(id != u32::MAX);
        }
        assert!(hits > rays.len() / 2, "{hits} of {}", rays.len());
    }

    /// The packets' rays ([`primary_ray`], no inverse direction) are [`traced_ray`]'s (made
    /// through `obvhs`'s constructor) in every field the traversal reads, to the bit, over a
    /// view's whole grid.
    #[test]
    fn primary_rays_are_the_traced_rays() {
        let (_, view) = scene_and_view(DVec3::new(-0.4, -1.0, -0.3));
        let terms = view.ray_terms();
        let (cols, rows) = view.grid();
        let bits = |r: &Ray| {
            let (o, d) = (r.origin, r.direction);
            [o.x, o.y, o.z, d.x, d.y, d.z, r.tmin, r.tmax].map(f32::to_bits)
        };
        for k in 0..(cols * rows) as usize {
            let d = terms.ray(k);
            assert_eq!(bits(&primary_ray(&view, d)), bits(&traced_ray(&view, d)), "sample {k}");
        }
    }

    #[test]
    fn sigma_min_of_a_diagonal_and_a_rotation() {
        assert!((sigma_min_2x2(3.0, 0.0, 0.0, 2.0) - 2.0).abs() < 1e-15);
        let (s, c) = 0.3f64.sin_cos();
        assert!((sigma_min_2x2(2.0 * c, -s, 2.0 * s, c) - 1.0).abs() < 1e-14);
        // Rank one: clamped, finite.
        let g = sigma_min_2x2(1.0, 1.0, 1.0, 1.0);
        assert!(g > 0.0 && g.is_finite());
        assert!(sigma_min_2x2(0.0, 0.0, 0.0, 0.0) > 0.0);
    }
}
