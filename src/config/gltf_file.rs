//! glTF scenes: the triangles of a `.gltf` or `.glb` file's default scene, in world space.
//!
//! Every node of the default scene (the first scene when none is marked default) is visited
//! with its transform composed down the hierarchy (glTF's column-major matrices, or
//! translation/rotation/scale); each mesh primitive in `TRIANGLES` mode contributes its
//! triangles (indexed or not). Other modes (points, lines, strips, fans) are skipped. Buffers
//! come from the GLB binary chunk, a file next to the scene, or a base64 `data:` URI. glTF is
//! right-handed with +Y up, like csm-lab, and its unit is the metre, read as world units.

use std::path::Path;

use glam::{DMat4, DVec3};

/// The world-space triangles of the file's default scene, or why they cannot be read (a
/// sentence for the error message; never a panic).
pub fn read_gltf(path: &Path) -> Result<Vec<[DVec3; 3]>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let gltf = gltf::Gltf::from_slice(&bytes).map_err(|e| format!("not a valid glTF file: {e}"))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut buffers = Vec::new();
    for buffer in gltf.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or("buffer refers to a GLB binary chunk the file does not have")?,
            gltf::buffer::Source::Uri(uri) => read_uri(dir, uri)?,
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {} holds {} bytes, fewer than the {} it declares",
                buffer.index(),
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    let scene = gltf
        .default_scene()
        .or_else(|| gltf.scenes().next())
        .ok_or("the file has no scene")?;
    let mut out = Vec::new();
    for node in scene.nodes() {
        visit(&node, DMat4::IDENTITY, &buffers, &mut out, 0)?;
    }
    Ok(out)
}

fn visit(
    node: &gltf::Node<'_>,
    parent: DMat4,
    buffers: &[Vec<u8>],
    out: &mut Vec<[DVec3; 3]>,
    level: usize,
) -> Result<(), String> {
    if level > 256 {
        return Err("the node hierarchy is deeper than 256 levels (a cycle?)".to_string());
    }
    let local = node.transform().matrix();
    let local = DMat4::from_cols_array_2d(&local.map(|c| c.map(f64::from)));
    let world = parent * local;
    if let Some(mesh) = node.mesh() {
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let positions: Vec<DVec3> = reader
                .read_positions()
                .ok_or_else(|| format!("mesh {} has a primitive without readable positions", mesh.index()))?
                .map(|p| world.transform_point3(DVec3::new(p[0].into(), p[1].into(), p[2].into())))
                .collect();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..positions.len() as u32).collect(),
            };
            for t in indices.chunks_exact(3) {
                let get = |i: u32| {
                    positions.get(i as usize).copied().ok_or_else(|| {
                        format!(
                            "mesh {} has an index {i} past its {} vertices",
                            mesh.index(),
                            positions.len()
                        )
                    })
                };
                let tri = [get(t[0])?, get(t[1])?, get(t[2])?];
                if tri.iter().all(|p| p.is_finite()) {
                    out.push(tri);
                }
            }
        }
    }
    for child in node.children() {
        visit(&child, world, buffers, out, level + 1)?;
    }
    Ok(())
}

fn read_uri(dir: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest.split_once(";base64,").ok_or("a data: URI that is not base64")?;
        return base64_decode(data).ok_or_else(|| "a data: URI with invalid base64".to_string());
    }
    let file = dir.join(uri);
    std::fs::read(&file).map_err(|e| format!("cannot read buffer {}: {e}", file.display()))
}

/// Standard base64 (with or without padding); None on any other character.
fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let bytes = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * i);
        }
        let n = match chunk.len() {
            4 => 3,
            3 => 2,
            2 => 1,
            _ => return None,
        };
        out.extend_from_slice(&acc.to_be_bytes()[1..1 + n]);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_values() {
        assert_eq!(base64_decode("TWFu").unwrap(), b"Man");
        assert_eq!(base64_decode("TWE=").unwrap(), b"Ma");
        assert_eq!(base64_decode("TQ==").unwrap(), b"M");
        assert!(base64_decode("T").is_none());
        assert!(base64_decode("T$==").is_none());
    }

    #[test]
    fn a_missing_or_corrupt_file_is_an_error() {
        assert!(read_gltf(Path::new("/nonexistent/x.glb"))
            .unwrap_err()
            .contains("cannot read"));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.gltf");
        std::fs::write(&p, "{ not json").unwrap();
        assert!(read_gltf(&p).unwrap_err().contains("not a valid glTF"));
    }
}
