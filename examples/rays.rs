//! The visibility pass's rays, measured and dumped for a peer (Embree, `benches/peers/embree_rays.py`).
//!
//! ```text
//! cargo run --release --example rays -- SCENE [--dump DIR] [--threads N] [--repeat N]
//! ```
//!
//! SCENE is `default` (the geometry of `configs/default.toml`), `terrain-100k` or `terrain-1m`
//! (a heightfield of 100,352 or 1,002,528 triangles over the default scene's 400 m square, the
//! one `benches/kernels.rs` times), or the path of a config with geometry. The camera, screen
//! and light are always those of `configs/default.toml` (or of the config given), with every
//! pixel sampled (`screen_scale = 1`): 1920 × 1080 primary rays.
//!
//! It prints, on one thread unless `--threads` says otherwise, the CPU time (user + sys of the
//! process) of the BVH build, of the traversal alone (which triangle each ray hits, nothing
//! else), and of the whole pass (traversal, the f64 hits, the depth order and one light's
//! shading), with rays per CPU-second and the number of rays that hit. `--repeat N` runs the
//! traversal and the pass N times on the one BVH and keeps the least CPU of each.
//!
//! `--dump DIR` writes what a peer needs to trace the very same rays: `tris.f32` (the BVH's
//! triangles, 9 little-endian binary32 each: v0, v1, v2), `rays.f32` (8 each: origin,
//! unit direction, tmin, tmax) and `hits.u32` (csm-lab's answer per ray: the triangle's index in
//! `tris.f32`, or 2^32 − 1 for a miss).

use std::io::Write;
use std::path::{Path, PathBuf};

use csm_core::visibility::{primary_rays, SceneGeometry};
use csm_lab::config::Config;

#[path = "../benches/common/terrain.rs"]
mod terrain;
use terrain::terrain;

/// CPU time (user + sys) of the whole process so far, in seconds.
fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes one timespec through a valid pointer.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_PROCESS_CPUTIME_ID)");
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn cpu<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t0 = cpu_seconds();
    let r = f();
    (r, cpu_seconds() - t0)
}

fn write_le(path: &Path, words: impl Iterator<Item = [u8; 4]>) {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).expect("create dump file"));
    for w in words {
        out.write_all(&w).expect("write dump file");
    }
    out.flush().expect("write dump file");
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: rays SCENE [--dump DIR] [--threads N] [--repeat N]   (SCENE: default, terrain-100k, terrain-1m or a config path)";
    let mut scene = None;
    let mut dump: Option<PathBuf> = None;
    let mut threads = 1usize;
    let mut repeat = 1usize;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--dump" => dump = Some(PathBuf::from(it.next().expect(usage))),
            "--threads" => threads = it.next().and_then(|s| s.parse().ok()).expect(usage),
            "--repeat" => repeat = it.next().and_then(|s| s.parse().ok()).expect(usage),
            s if scene.is_none() => scene = Some(s.to_string()),
            _ => panic!("{usage}"),
        }
    }
    let scene = scene.expect(usage);
    let default_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
    let config_path = match scene.as_str() {
        "default" | "terrain-100k" | "terrain-1m" => default_path,
        p => PathBuf::from(p),
    };
    let mut config = Config::load(&config_path).unwrap_or_else(|e| panic!("{}: {e}", config_path.display()));
    let mut setup = config.setup();
    setup.geometry.as_mut().expect("the scene has geometry").screen_scale = 1.0;
    let view = setup.view().expect("a view");
    let mesh = match scene.as_str() {
        "terrain-100k" => terrain(224),
        "terrain-1m" => terrain(708),
        _ => setup.geometry.as_ref().unwrap().scene.mesh.clone(),
    };
    config.geometry = None;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| {
        let rays = primary_rays(&view);
        let geometry = SceneGeometry::new(mesh);
        let (_, build) = cpu(|| geometry.bvh_dropped());
        let mut trace = f64::INFINITY;
        let mut pass = f64::INFINITY;
        let mut ids = Vec::new();
        let mut receivers = 0;
        for _ in 0..repeat {
            let (r, t) = cpu(|| geometry.trace(&view));
            ids = r;
            trace = trace.min(t);
            // A fresh cache each time: the pass casts again.
            let fresh = SceneGeometry::new(geometry.mesh.clone());
            let _ = fresh.bvh_dropped();
            let (v, t) = cpu(|| fresh.cast(&view));
            receivers = v.receivers.len();
            pass = pass.min(t);
        }
        let hits = ids.iter().filter(|&&i| i != u32::MAX).count();
        let n = rays.len();
        println!(
            "scene {scene}: {} triangles in the BVH, {n} rays, {threads} thread(s)",
            geometry.bvh_triangles().len()
        );
        println!("build CPU s {build:.4}");
        println!(
            "trace CPU s {trace:.4} ({:.2} M rays per CPU-second)",
            n as f64 / trace / 1e6
        );
        println!(
            "pass CPU s {pass:.4} ({:.2} M rays per CPU-second; traversal {:.0} % of it)",
            n as f64 / pass / 1e6,
            100.0 * trace / pass
        );
        println!("build+trace CPU s {:.4}", build + trace);
        println!("hits {hits}");
        println!("receivers {receivers}");
        if let Some(dir) = dump {
            std::fs::create_dir_all(&dir).expect("create dump directory");
            let tris = geometry.bvh_triangles();
            write_le(
                &dir.join("tris.f32"),
                tris.iter()
                    .flat_map(|t| [t.v0, t.v1, t.v2])
                    .flat_map(|v| [v.x, v.y, v.z])
                    .map(f32::to_le_bytes),
            );
            write_le(
                &dir.join("rays.f32"),
                rays.iter()
                    .flat_map(|r| {
                        [
                            r.origin.x,
                            r.origin.y,
                            r.origin.z,
                            r.direction.x,
                            r.direction.y,
                            r.direction.z,
                            r.tmin,
                            r.tmax,
                        ]
                    })
                    .map(f32::to_le_bytes),
            );
            write_le(&dir.join("hits.u32"), ids.iter().map(|i| i.to_le_bytes()));
            println!("dumped to {}", dir.display());
        }
    });
}
