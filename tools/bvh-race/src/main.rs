//! The race that chose the BVH crate: obvhs (CWBVH) against bvh 0.11 on a 100,352-triangle
//! terrain, one full-HD frame of primary rays from the default camera, one thread.
//! A standalone crate (its own workspace): `cd tools/bvh-race && cargo run --release`.

use std::time::Instant;
use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use bvh::ray::Ray as BRay;
use nalgebra::{Point3, Vector3};
use obvhs::{cwbvh::builder::build_cwbvh_from_tris, ray::{Ray, RayHit}, triangle::Triangle, BvhBuildParams};

#[derive(Clone)]
struct Tri { v: [Point3<f32>; 3], node: usize }
impl Bounded<f32, 3> for Tri {
    fn aabb(&self) -> Aabb<f32, 3> { Aabb::empty().grow(&self.v[0]).grow(&self.v[1]).grow(&self.v[2]) }
}
impl BHShape<f32, 3> for Tri {
    fn set_bh_node_index(&mut self, i: usize) { self.node = i; }
    fn bh_node_index(&self) -> usize { self.node }
}

fn main() {
    let n = 224;
    let p = |i: usize, j: usize| {
        let (x, z) = (-200.0 + 400.0 * i as f32 / n as f32, -200.0 + 400.0 * j as f32 / n as f32);
        [x, 0.6 * (x * 0.05).sin() * (z * 0.07).cos() + 0.3 * (x * 0.13 + z * 0.11).sin(), z]
    };
    let mut tris = Vec::new();
    for j in 0..n { for i in 0..n {
        tris.push([p(i, j), p(i, j + 1), p(i + 1, j + 1)]);
        tris.push([p(i, j), p(i + 1, j + 1), p(i + 1, j)]);
    }}
    let (w, h) = (1920usize, 1080usize);
    let tv = (30f32).to_radians().tan(); let th = tv * w as f32 / h as f32;
    let c = glam::Vec3A::new(0.0, 10.0, 0.0);
    let f = (glam::Vec3A::new(0.0, 0.0, -50.0) - c).normalize();
    let r = f.cross(glam::Vec3A::Y).normalize(); let u = r.cross(f);
    let dirs: Vec<glam::Vec3A> = (0..w * h).map(|k| {
        let (x, y) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
        (f + r * ((2.0 * x / w as f32 - 1.0) * th) + u * ((1.0 - 2.0 * y / h as f32) * tv)).normalize()
    }).collect();
    // obvhs
    let t0 = Instant::now();
    let ot: Vec<Triangle> = tris.iter().map(|t| Triangle { v0: t[0].into(), v1: t[1].into(), v2: t[2].into() }).collect();
    let bvh = build_cwbvh_from_tris(&ot, BvhBuildParams::fast_build(), &mut Default::default());
    let tb = t0.elapsed();
    let t1 = Instant::now();
    let mut hits = 0;
    for d in &dirs {
        let mut hit = RayHit::none();
        if bvh.ray_traverse(Ray::new(c, *d, 0.0, 1e9), &mut hit, |ray, id| ot[bvh.primitive_indices[id] as usize].intersect(ray)) { hits += 1; }
    }
    println!("obvhs cwbvh: build {:?}, {} rays {:?} (one thread), hits {}", tb, dirs.len(), t1.elapsed(), hits);
    // bvh crate
    let t0 = Instant::now();
    let mut shapes: Vec<Tri> = tris.iter().map(|t| Tri { v: [Point3::from(t[0]), Point3::from(t[1]), Point3::from(t[2])], node: 0 }).collect();
    let b = bvh::bvh::Bvh::build(&mut shapes);
    let tb = t0.elapsed();
    let t1 = Instant::now();
    let mut hits2 = 0;
    for d in &dirs {
        let ray = BRay::new(Point3::new(c.x, c.y, c.z), Vector3::new(d.x, d.y, d.z));
        let mut best = f32::INFINITY;
        for s in b.traverse_iterator(&ray, &shapes) {
            let hit = ray.intersects_triangle(&s.v[0], &s.v[1], &s.v[2]);
            if hit.distance < best { best = hit.distance; }
        }
        if best.is_finite() { hits2 += 1; }
    }
    println!("bvh 0.11:    build {:?}, {} rays {:?} (one thread), hits {}", tb, dirs.len(), t1.elapsed(), hits2);
}
