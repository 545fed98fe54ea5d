//! glTF scenes: the triangles of a `.gltf` or `.glb` file's default scene, in world space, and
//! its perspective camera nodes and directional lights (`[views] from_gltf`, `[light] from_gltf`).
//!
//! Every node of the default scene (the first scene when none is marked default) is visited
//! with its transform composed down the hierarchy (glTF's column-major matrices, or
//! translation/rotation/scale); each mesh primitive in `TRIANGLES` mode contributes its
//! triangles (indexed or not). Other modes (points, lines, strips, fans) are skipped. Buffers
//! come from the GLB binary chunk, a file next to the scene, or a base64 `data:` URI. glTF is
//! right-handed with +Y up, like csm-lab, and its unit is the metre, read as world units.
//!
//! A camera node looks down its local −Z axis with +Y up; its world position is the node's
//! world transform applied to the origin, its view direction and up that transform applied to
//! −Z and +Y (normalised). A `KHR_lights_punctual` directional light shines along its node's
//! −Z in world space. Nodes are visited depth first in the scene's order, so "the first light"
//! is the first met that way.

use std::path::Path;

use glam::{DMat4, DVec3};

/// A perspective camera node of the default scene, in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfCamera {
    /// The node's name (None when it has none or an empty one).
    pub name: Option<String>,
    /// The node's index in the file.
    pub node: usize,
    pub position: DVec3,
    /// Unit view direction: the node's −Z in world space.
    pub forward: DVec3,
    /// The node's +Y in world space (unit).
    pub up: DVec3,
    /// Vertical field of view, radians, as the file gives it.
    pub yfov: f64,
    /// The camera's aspect ratio (width / height), when the file gives one.
    pub aspect: Option<f64>,
}

/// A `KHR_lights_punctual` directional light of the default scene.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfLight {
    pub name: Option<String>,
    pub node: usize,
    /// Unit direction the light travels: its node's −Z in world space.
    pub direction: DVec3,
}

/// What csm-lab reads from a glTF file: triangles, camera nodes and directional lights.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GltfScene {
    /// Triangles per draw call (mesh primitive under a node), in visiting order.
    pub primitives: Vec<Vec<[DVec3; 3]>>,
    /// Perspective camera nodes, in visiting order.
    pub cameras: Vec<GltfCamera>,
    /// Camera nodes with an orthographic projection (not read: a player camera is perspective).
    pub orthographic_cameras: usize,
    /// Directional lights, in visiting order.
    pub directional_lights: Vec<GltfLight>,
}

/// The world-space triangles of the file's default scene, or why they cannot be read (a
/// sentence for the error message; never a panic).
///
/// The file and each buffer file must be regular files of at most [`MAX_GLTF_BYTES`] (a FIFO
/// or `/dev/zero` is refused before a byte is read). A buffer URI that leaves the glTF's folder
/// (an absolute path, a `..` component, another scheme) is refused unless `outside_buffers`
/// (`scene.gltf_outside_buffers = true`).
pub fn read_gltf(path: &Path, outside_buffers: bool) -> Result<Vec<[DVec3; 3]>, String> {
    Ok(read_gltf_primitives(path, outside_buffers)?
        .into_iter()
        .flatten()
        .collect())
}

/// [`read_gltf`], grouped by draw call: one entry per mesh primitive in `TRIANGLES` mode under
/// each node that instances it, in the order of the node walk (a primitive whose triangles are
/// all non-finite is an empty entry).
pub fn read_gltf_primitives(path: &Path, outside_buffers: bool) -> Result<Vec<Vec<[DVec3; 3]>>, String> {
    read_gltf_scene(path, outside_buffers).map(|s| s.primitives)
}

/// The file's default scene: triangles grouped by draw call as [`read_gltf_primitives`], plus
/// its camera nodes and directional lights.
pub fn read_gltf_scene(path: &Path, outside_buffers: bool) -> Result<GltfScene, String> {
    let bytes = read_file(path)?;
    let gltf = gltf::Gltf::from_slice(&bytes).map_err(|e| format!("not a valid glTF file: {e}"))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut buffers = Vec::new();
    for buffer in gltf.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or("buffer refers to a GLB binary chunk the file does not have")?,
            gltf::buffer::Source::Uri(uri) => read_uri(dir, uri, outside_buffers)?,
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
    let mut out = GltfScene::default();
    let json = gltf.document.as_json();
    for node in scene.nodes() {
        visit(&node, DMat4::IDENTITY, &buffers, json, &mut out, 0)?;
    }
    Ok(out)
}

/// A node's name, None when absent or empty.
fn node_name(node: &gltf::Node<'_>) -> Option<String> {
    node.name().filter(|n| !n.trim().is_empty()).map(str::to_string)
}

/// The camera or light a node carries, read from the JSON with every index checked (the
/// crate's accessors unwrap some of them).
fn node_extras(
    node: &gltf::Node<'_>,
    world: DMat4,
    json: &gltf::json::Root,
    out: &mut GltfScene,
) -> Result<(), String> {
    use gltf::json::validation::Checked;
    let axis = |v: DVec3, what: &str| -> Result<DVec3, String> {
        world.transform_vector3(v).try_normalize().ok_or_else(|| {
            format!(
                "node {}: its world transform turns the {what} axis into a zero or non-finite vector",
                node.index()
            )
        })
    };
    if let Some(camera) = node.camera() {
        let cam = json.cameras.get(camera.index()).ok_or_else(|| {
            format!(
                "node {} names camera {}, which the file does not have",
                node.index(),
                camera.index()
            )
        })?;
        match (&cam.type_, &cam.perspective) {
            (Checked::Valid(gltf::json::camera::Type::Perspective), Some(p)) => {
                let position = world.transform_point3(DVec3::ZERO);
                if !position.is_finite() {
                    return Err(format!("node {}: camera position is not finite", node.index()));
                }
                out.cameras.push(GltfCamera {
                    name: node_name(node),
                    node: node.index(),
                    position,
                    forward: axis(DVec3::NEG_Z, "camera's view (−Z)")?,
                    up: axis(DVec3::Y, "camera's up (+Y)")?,
                    yfov: f64::from(p.yfov),
                    aspect: p.aspect_ratio.map(f64::from),
                });
            }
            (Checked::Valid(gltf::json::camera::Type::Orthographic), _) => out.orthographic_cameras += 1,
            _ => {
                return Err(format!(
                    "camera {} (node {}) is marked perspective but has no perspective projection",
                    camera.index(),
                    node.index()
                ))
            }
        }
    }
    let light = json
        .nodes
        .get(node.index())
        .and_then(|n| n.extensions.as_ref())
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map(|l| l.light.value());
    if let Some(index) = light {
        let lights = json
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map_or(&[][..], |l| &l.lights[..]);
        let l = lights.get(index).ok_or_else(|| {
            format!(
                "node {} names light {index}, which the file does not have",
                node.index()
            )
        })?;
        if matches!(
            l.type_,
            Checked::Valid(gltf::json::extensions::scene::khr_lights_punctual::Type::Directional)
        ) {
            out.directional_lights.push(GltfLight {
                name: node_name(node),
                node: node.index(),
                direction: axis(DVec3::NEG_Z, "light's (−Z)")?,
            });
        }
    }
    Ok(())
}

fn visit(
    node: &gltf::Node<'_>,
    parent: DMat4,
    buffers: &[Vec<u8>],
    json: &gltf::json::Root,
    scene: &mut GltfScene,
    level: usize,
) -> Result<(), String> {
    if level > 256 {
        return Err("the node hierarchy is deeper than 256 levels (a cycle?)".to_string());
    }
    let local = node.transform().matrix();
    let local = DMat4::from_cols_array_2d(&local.map(|c| c.map(f64::from)));
    let world = parent * local;
    node_extras(node, world, json, scene)?;
    let out = &mut scene.primitives;
    if let Some(mesh) = node.mesh() {
        for primitive in mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let at = |accessor: Option<usize>| Place {
                mesh: mesh.index(),
                primitive: primitive.index(),
                accessor,
            };
            let position = primitive
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| format!("{}: it has no POSITION attribute", at(None)))?;
            let place = at(Some(position.index()));
            let positions: Vec<DVec3> = read_accessor(&position, Semantic::Position, buffers, &place)?
                .chunks_exact(3)
                .map(|p| world.transform_point3(DVec3::new(p[0], p[1], p[2])))
                .collect();
            let indices: Vec<u32> = match primitive.indices() {
                Some(a) => {
                    let place = at(Some(a.index()));
                    read_accessor(&a, Semantic::Index, buffers, &place)?
                        .into_iter()
                        .map(|i| i as u32)
                        .collect()
                }
                None => (0..positions.len() as u32).collect(),
            };
            let mut tris = Vec::with_capacity(indices.len() / 3);
            for t in indices.chunks_exact(3) {
                let get = |i: u32| {
                    positions.get(i as usize).copied().ok_or_else(|| {
                        format!(
                            "{}: index {i} is past its {} vertices",
                            at(primitive.indices().map(|a| a.index())),
                            positions.len()
                        )
                    })
                };
                let tri = [get(t[0])?, get(t[1])?, get(t[2])?];
                if tri.iter().all(|p| p.is_finite()) {
                    tris.push(tri);
                }
            }
            out.push(tris);
        }
    }
    for child in node.children() {
        visit(&child, world, buffers, json, scene, level + 1)?;
    }
    Ok(())
}

/// Most elements of an accessor without a buffer view (all zeros but its sparse values): 16 M.
const MAX_VIEWLESS_ELEMENTS: usize = 1 << 24;

/// Where an accessor is used, for error messages: "mesh 0, primitive 1, accessor 3".
struct Place {
    mesh: usize,
    primitive: usize,
    accessor: Option<usize>,
}

impl std::fmt::Display for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "mesh {}, primitive {}", self.mesh, self.primitive)?;
        if let Some(a) = self.accessor {
            write!(f, ", accessor {a}")?;
        }
        Ok(())
    }
}

/// The two kinds of accessor csm-lab reads.
#[derive(Clone, Copy, PartialEq)]
enum Semantic {
    /// `POSITION`: VEC3 of FLOAT.
    Position,
    /// Triangle indices: SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT.
    Index,
}

/// Reads an accessor's elements as f64 components (`count` x 3 for positions, `count` for
/// indices), after checking everything the glTF 2.0 specification requires of it for this use:
/// component and element type, normalisation, `byteStride` (at least the element size and a
/// multiple of the component size), offsets and counts inside the buffer view and the buffer,
/// and the same for a sparse accessor's indices and values (indices ascending, below `count`).
/// Nothing here can panic or read out of bounds: every range is checked before it is sliced.
/// Elements are read in full only once every check has passed, so the allocation is bounded by
/// the bytes the buffers really hold.
fn read_accessor(
    a: &gltf::Accessor<'_>,
    semantic: Semantic,
    buffers: &[Vec<u8>],
    place: &Place,
) -> Result<Vec<f64>, String> {
    use gltf::accessor::{DataType, Dimensions};
    let bad = |m: String| format!("{place}: {m}");
    let (what, want_dims) = match semantic {
        Semantic::Position => ("POSITION", Dimensions::Vec3),
        Semantic::Index => ("index", Dimensions::Scalar),
    };
    let component = a.data_type();
    let type_ok = match semantic {
        Semantic::Position => component == DataType::F32,
        Semantic::Index => matches!(component, DataType::U8 | DataType::U16 | DataType::U32),
    };
    if !type_ok {
        return Err(bad(format!(
            "a {what} accessor has component type {component:?}; it must be {}",
            match semantic {
                Semantic::Position => "FLOAT (5126)",
                Semantic::Index => "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT (5121, 5123, 5125)",
            }
        )));
    }
    if a.dimensions() != want_dims {
        return Err(bad(format!(
            "a {what} accessor has type {:?}; it must be {want_dims:?}",
            a.dimensions()
        )));
    }
    if semantic == Semantic::Index && a.normalized() {
        return Err(bad("an index accessor is marked normalized; indices never are".into()));
    }
    let width = component.size();
    let n_comp = want_dims.multiplicity();
    let element = width * n_comp;
    let count = a.count();
    let read_component = |bytes: &[u8]| -> f64 {
        match component {
            DataType::U8 => f64::from(bytes[0]),
            DataType::U16 => f64::from(u16::from_le_bytes([bytes[0], bytes[1]])),
            DataType::U32 => f64::from(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
            _ => f64::from(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
        }
    };
    // The bytes of `count` elements at `offset` in `view`, with their stride, all checked.
    let span = |view: &gltf::buffer::View<'_>,
                offset: usize,
                count: usize,
                element: usize,
                width: usize,
                strided: bool,
                part: &str|
     -> Result<(&[u8], usize), String> {
        let buffer = buffers
            .get(view.buffer().index())
            .ok_or_else(|| bad(format!("{part}buffer view {} names a missing buffer", view.index())))?;
        let declared = view.buffer().length().min(buffer.len());
        let view_end = view
            .offset()
            .checked_add(view.length())
            .filter(|&e| e <= declared)
            .ok_or_else(|| {
                bad(format!(
                    "{part}buffer view {} (bytes {}..+{}) runs past its buffer {} of {declared} bytes",
                    view.index(),
                    view.offset(),
                    view.length(),
                    view.buffer().index()
                ))
            })?;
        let stride = match view.stride() {
            Some(s) if strided => {
                if s < element || s % width != 0 {
                    return Err(bad(format!(
                        "{part}buffer view {} has byteStride {s}; an element of this accessor takes {element}                          bytes, so the stride must be at least {element} and a multiple of {width}",
                        view.index()
                    )));
                }
                s
            }
            Some(s) => {
                return Err(bad(format!(
                    "{part}buffer view {} has byteStride {s}, which this kind of data may not have",
                    view.index()
                )))
            }
            None => element,
        };
        if offset % width != 0 {
            return Err(bad(format!(
                "{part}byteOffset {offset} is not a multiple of the component size {width}"
            )));
        }
        let need = match count {
            0 => Some(0),
            c => (c - 1).checked_mul(stride).and_then(|x| x.checked_add(element)),
        };
        let fits = need
            .and_then(|need| offset.checked_add(need))
            .and_then(|end| view.offset().checked_add(end).map(|abs| (abs, end)))
            .filter(|&(_, end)| end <= view.length());
        let Some(_) = fits else {
            return Err(bad(format!(
                "{part}{count} elements of {element} bytes (stride {stride}) from byteOffset {offset} run past \
                 buffer view {} of {} bytes",
                view.index(),
                view.length()
            )));
        };
        Ok((&buffer[view.offset() + offset..view_end], stride))
    };
    // The sparse part's byte ranges, checked before anything is allocated.
    let sparse = match a.sparse() {
        None => None,
        Some(sparse) => {
            let n = sparse.count();
            if n > count {
                return Err(bad(format!("sparse count {n} is above the accessor's count {count}")));
            }
            let indices = sparse.indices();
            let index_width = match indices.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let (index_bytes, _) = span(
                &indices.view(),
                indices.offset(),
                n,
                index_width,
                index_width,
                false,
                "sparse indices: ",
            )?;
            let values = sparse.values();
            let (value_bytes, _) = span(
                &values.view(),
                values.offset(),
                n,
                element,
                width,
                false,
                "sparse values: ",
            )?;
            Some((n, index_width, index_bytes, value_bytes))
        }
    };
    let mut out = match a.view() {
        Some(view) => {
            let (bytes, stride) = span(&view, a.offset(), count, element, width, true, "")?;
            let mut out = Vec::with_capacity(count * n_comp);
            for k in 0..count {
                for c in 0..n_comp {
                    let at = k * stride + c * width;
                    out.push(read_component(&bytes[at..at + width]));
                }
            }
            out
        }
        None if sparse.is_some() => {
            // Zeros, then the sparse values. The count is not backed by bytes here: bound it.
            if count > MAX_VIEWLESS_ELEMENTS {
                return Err(bad(format!(
                    "an accessor without a buffer view declares {count} elements; at most {MAX_VIEWLESS_ELEMENTS}"
                )));
            }
            vec![0.0; count * n_comp]
        }
        None => {
            return Err(bad(format!(
                "a {what} accessor has no buffer view and no sparse values"
            )));
        }
    };
    if let Some((n, index_width, index_bytes, value_bytes)) = sparse {
        let mut last: Option<usize> = None;
        for k in 0..n {
            let at = k * index_width;
            let i = match index_width {
                1 => usize::from(index_bytes[at]),
                2 => usize::from(u16::from_le_bytes([index_bytes[at], index_bytes[at + 1]])),
                _ => u32::from_le_bytes([
                    index_bytes[at],
                    index_bytes[at + 1],
                    index_bytes[at + 2],
                    index_bytes[at + 3],
                ]) as usize,
            };
            if i >= count || last.is_some_and(|l| i <= l) {
                return Err(bad(format!(
                    "sparse index {i} (entry {k}) is not below the count {count} and above the entry before it"
                )));
            }
            last = Some(i);
            for c in 0..n_comp {
                let at = k * element + c * width;
                out[i * n_comp + c] = read_component(&value_bytes[at..at + width]);
            }
        }
    }
    Ok(out)
}

/// Largest glTF file, and largest buffer file, read (1 GiB each).
pub(crate) const MAX_GLTF_BYTES: u64 = 1 << 30;

fn read_file(path: &Path) -> Result<Vec<u8>, String> {
    super::read_bytes_bounded(path, MAX_GLTF_BYTES, "a glTF file or buffer").map_err(|e| e.to_string())
}

fn read_uri(dir: &Path, uri: &str, outside_buffers: bool) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest.split_once(";base64,").ok_or("a data: URI that is not base64")?;
        return base64_decode(data).ok_or_else(|| "a data: URI with invalid base64".to_string());
    }
    let relative = Path::new(uri);
    let leaves = relative.is_absolute()
        || uri.contains(':')
        || uri.starts_with('\\')
        || relative
            .components()
            .any(|c| !matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir));
    if leaves && !outside_buffers {
        return Err(format!(
            "buffer URI {:?} points outside the glTF's folder {}; set scene.gltf_outside_buffers = true \
             to read it",
            super::clip_quote(uri),
            dir.display()
        ));
    }
    let file = dir.join(uri);
    read_file(&file).map_err(|e| format!("buffer {:?}: {e}", super::clip_quote(uri)))
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
        assert!(read_gltf(Path::new("/nonexistent/x.glb"), false)
            .unwrap_err()
            .contains("cannot read"));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.gltf");
        std::fs::write(&p, "{ not json").unwrap();
        assert!(read_gltf(&p, false).unwrap_err().contains("not a valid glTF"));
    }
}
