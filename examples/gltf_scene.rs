//! Writes a small self-contained glTF 2.0 scene (one `.gltf` file, its buffer embedded as a
//! base64 data URI) for csm-lab's `scene.gltf` key: a gently rolling terrain grid with a few
//! houses, each a node with its own translation, so node transforms are exercised.
//!
//! ```sh
//! cargo run --release --example gltf_scene -- configs/village.gltf        # 30 x 30 terrain
//! cargo run --release --example gltf_scene -- /tmp/big.gltf 220          # ~100k triangles
//! cargo run --release --example gltf_scene -- --town configs/town.glb     # a town, ~103k triangles
//! ```
//!
//! `--town` writes a town for a level of views (`configs/level.toml`): a 216 x 216 terrain
//! grid over 400 m and 676 houses of three sizes on a street grid of 32 x 32 plots (every
//! fifth row and column left open as a square), each a node with its own translation and a
//! rotation about +Y in quarter turns; a name ending in `.glb` writes the binary container.
//!
//! Units are metres (world units), +Y up, like csm-lab.

use std::fmt::Write as _;

/// A mesh as flat f32 positions and u32 indices.
#[derive(Default)]
struct Mesh {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

impl Mesh {
    fn quad(&mut self, a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]) {
        let i = self.positions.len() as u32;
        self.positions.extend([a, b, c, d]);
        self.indices.extend([i, i + 1, i + 2, i, i + 2, i + 3]);
    }

    fn tri(&mut self, a: [f32; 3], b: [f32; 3], c: [f32; 3]) {
        let i = self.positions.len() as u32;
        self.positions.extend([a, b, c]);
        self.indices.extend([i, i + 1, i + 2]);
    }
}

/// Terrain over [-size, size]^2 with `n` x `n` cells, height a few gentle waves (metres).
fn terrain(n: u32, size: f32) -> Mesh {
    let mut m = Mesh::default();
    let h = |x: f32, z: f32| 0.6 * (x * 0.05).sin() * (z * 0.07).cos() + 0.3 * (x * 0.13 + z * 0.11).sin();
    for j in 0..=n {
        for i in 0..=n {
            let x = -size + 2.0 * size * i as f32 / n as f32;
            let z = -size + 2.0 * size * j as f32 / n as f32;
            m.positions.push([x, h(x, z), z]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 2, a + n + 1);
            m.indices.extend([a, d, c, a, c, b]);
        }
    }
    m
}

/// A house at the origin: walls `w` x `d` x `h` with a gable roof along x.
fn house(w: f32, d: f32, h: f32, roof: f32) -> Mesh {
    let mut m = Mesh::default();
    let (x0, x1, z0, z1) = (-w / 2.0, w / 2.0, -d / 2.0, d / 2.0);
    m.quad([x0, 0.0, z0], [x1, 0.0, z0], [x1, h, z0], [x0, h, z0]);
    m.quad([x0, 0.0, z1], [x1, 0.0, z1], [x1, h, z1], [x0, h, z1]);
    m.quad([x0, 0.0, z0], [x0, 0.0, z1], [x0, h, z1], [x0, h, z0]);
    m.quad([x1, 0.0, z0], [x1, 0.0, z1], [x1, h, z1], [x1, h, z0]);
    let top = h + roof;
    m.quad([x0, h, z0], [x1, h, z0], [x1, top, 0.0], [x0, top, 0.0]);
    m.quad([x0, h, z1], [x1, h, z1], [x1, top, 0.0], [x0, top, 0.0]);
    m.tri([x0, h, z0], [x0, h, z1], [x0, top, 0.0]);
    m.tri([x1, h, z0], [x1, h, z1], [x1, top, 0.0]);
    m
}

/// The town's houses: (mesh, translation, quarter turns about +Y) on a 32 x 32 grid of 12 m
/// plots, streets between them, every fifth row and column an open square; sizes and turns
/// from a fixed hash of the plot, so the file is the same on every run.
fn town_houses() -> Vec<(usize, [f32; 3], u32)> {
    let mut out = Vec::new();
    for j in 0..32u32 {
        for i in 0..32u32 {
            if i % 5 == 2 || j % 5 == 2 {
                continue;
            }
            let hash = (i.wrapping_mul(73_856_093) ^ j.wrapping_mul(19_349_663)).wrapping_mul(2_654_435_761);
            let (x, z) = (-186.0 + 12.0 * i as f32, -186.0 + 12.0 * j as f32);
            out.push((1 + (hash >> 7) as usize % 3, [x, 0.0, z], (hash >> 13) % 4));
        }
    }
    out
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let town = args.first().is_some_and(|a| a == "--town");
    if town {
        args.remove(0);
    }
    let mut args = args.into_iter();
    let out = args.next().unwrap_or_else(|| "village.gltf".to_string());
    let n: u32 = args.next().map_or(if town { 216 } else { 30 }, |s| {
        s.parse().expect("terrain cells per side")
    });
    let mut meshes = vec![terrain(n, 200.0), house(10.0, 8.0, 6.0, 3.0), house(6.0, 6.0, 4.0, 2.5)];
    if town {
        meshes.push(house(8.0, 8.0, 12.0, 2.0));
    }
    // Houses (mesh 1 or 2) placed along the road ahead of the default camera.
    let village: [(usize, [f32; 3]); 8] = [
        (1, [-14.0, 0.0, -30.0]),
        (2, [12.0, 0.0, -24.0]),
        (1, [-16.0, 0.0, -55.0]),
        (2, [15.0, 0.0, -48.0]),
        (1, [-18.0, 0.0, -85.0]),
        (1, [16.0, 0.0, -80.0]),
        (2, [-10.0, 0.0, -120.0]),
        (1, [20.0, 0.0, -130.0]),
    ];
    let houses: Vec<(usize, [f32; 3], u32)> = if town {
        town_houses()
    } else {
        village.iter().map(|&(m, t)| (m, t, 0)).collect()
    };
    let mut buffer: Vec<u8> = Vec::new();
    let mut views = String::new();
    let mut accessors = String::new();
    let mut gltf_meshes = String::new();
    for (k, m) in meshes.iter().enumerate() {
        let (lo, hi) = m.positions.iter().fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1]), lo[2].min(p[2])],
                [hi[0].max(p[0]), hi[1].max(p[1]), hi[2].max(p[2])],
            )
        });
        let pos_offset = buffer.len();
        buffer.extend(m.positions.iter().flatten().flat_map(|x| x.to_le_bytes()));
        let idx_offset = buffer.len();
        buffer.extend(m.indices.iter().flat_map(|x| x.to_le_bytes()));
        let sep = if k == 0 { "" } else { "," };
        let _ = write!(
            views,
            "{sep}{{\"buffer\":0,\"byteOffset\":{pos_offset},\"byteLength\":{}}},{{\"buffer\":0,\"byteOffset\":{idx_offset},\"byteLength\":{}}}",
            idx_offset - pos_offset,
            m.indices.len() * 4
        );
        let _ = write!(
            accessors,
            "{sep}{{\"bufferView\":{},\"componentType\":5126,\"count\":{},\"type\":\"VEC3\",\"min\":{lo:?},\"max\":{hi:?}}},\
             {{\"bufferView\":{},\"componentType\":5125,\"count\":{},\"type\":\"SCALAR\"}}",
            2 * k,
            m.positions.len(),
            2 * k + 1,
            m.indices.len()
        );
        let _ = write!(
            gltf_meshes,
            "{sep}{{\"primitives\":[{{\"attributes\":{{\"POSITION\":{}}},\"indices\":{}}}]}}",
            2 * k,
            2 * k + 1
        );
    }
    let mut nodes = String::from("{\"mesh\":0}");
    for &(mesh, t, turns) in &houses {
        if turns == 0 {
            let _ = write!(nodes, ",{{\"mesh\":{mesh},\"translation\":{t:?}}}");
        } else {
            // A rotation about +Y by `turns` quarter turns, as a unit quaternion (x, y, z, w).
            let half = turns as f32 * std::f32::consts::FRAC_PI_4;
            let r = [0.0, half.sin(), 0.0, half.cos()];
            let _ = write!(nodes, ",{{\"mesh\":{mesh},\"translation\":{t:?},\"rotation\":{r:?}}}");
        }
    }
    let node_list: Vec<String> = (0..=houses.len()).map(|i| i.to_string()).collect();
    let glb = out.ends_with(".glb");
    let uri = if glb {
        String::new()
    } else {
        format!(
            ",\"uri\":\"data:application/octet-stream;base64,{}\"",
            csm_lab::report::html::base64(&buffer)
        )
    };
    let json = format!(
        "{{\"asset\":{{\"version\":\"2.0\",\"generator\":\"csm-lab examples/gltf_scene.rs\"}},\"scene\":0,\
         \"scenes\":[{{\"nodes\":[{}]}}],\"nodes\":[{nodes}],\"meshes\":[{gltf_meshes}],\"accessors\":[{accessors}],\
         \"bufferViews\":[{views}],\"buffers\":[{{\"byteLength\":{}{uri}}}]}}\n",
        node_list.join(","),
        buffer.len(),
    );
    if glb {
        // The binary container: a 12-byte header, the JSON chunk padded with spaces and the
        // buffer chunk padded with zeros, each to a multiple of 4 bytes.
        let mut j = json.into_bytes();
        while j.len() % 4 != 0 {
            j.push(b' ');
        }
        while buffer.len() % 4 != 0 {
            buffer.push(0);
        }
        let total = 12 + 8 + j.len() + 8 + buffer.len();
        let mut bytes = Vec::with_capacity(total);
        bytes.extend(b"glTF");
        bytes.extend(2u32.to_le_bytes());
        bytes.extend((total as u32).to_le_bytes());
        bytes.extend((j.len() as u32).to_le_bytes());
        bytes.extend(b"JSON");
        bytes.extend(&j);
        bytes.extend((buffer.len() as u32).to_le_bytes());
        bytes.extend(b"BIN\0");
        bytes.extend(&buffer);
        std::fs::write(&out, bytes).expect("write the scene");
    } else {
        std::fs::write(&out, json).expect("write the scene");
    }
    let triangles: usize = meshes[0].indices.len() / 3
        + houses
            .iter()
            .map(|(m, _, _)| meshes[*m].indices.len() / 3)
            .sum::<usize>();
    eprintln!("wrote {out}: {triangles} triangles");
}
