//! The benchmark terrain, shared by `benches/kernels.rs` and `examples/rays.rs` (each includes
//! this file with `#[path]`; `benches/common/` is not a bench target of its own).

use csm_core::mesh::Mesh;
use glam::DVec3;

/// A heightfield over [-200, 200]^2 with `n` x `n` cells (2 n^2 triangles): the terrain of the
/// kernel benchmarks, `examples/rays.rs` and `tools/bvh-race` (which builds it in its own crate).
pub fn terrain(n: usize) -> Mesh {
    let mut m = Mesh::default();
    let p = |i: usize, j: usize| {
        let (x, z) = (
            -200.0 + 400.0 * i as f64 / n as f64,
            -200.0 + 400.0 * j as f64 / n as f64,
        );
        DVec3::new(
            x,
            0.6 * (x * 0.05).sin() * (z * 0.07).cos() + 0.3 * (x * 0.13 + z * 0.11).sin(),
            z,
        )
    };
    for j in 0..n {
        for i in 0..n {
            m.push([p(i, j), p(i, j + 1), p(i + 1, j + 1)]);
            m.push([p(i, j), p(i + 1, j + 1), p(i + 1, j)]);
        }
    }
    m
}
