//! Malformed glTF accessors: every case is an error naming the mesh, primitive and accessor
//! (never a panic inside a reader, never a silently different triangle count), and a fuzzer
//! over the accessor, buffer view and sparse fields that finds no panic. Well-formed strided
//! and sparse accessors read back the exact values written.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use csm_lab::config::read_gltf;
use glam::DVec3;
use proptest::prelude::*;
use serde_json::{json, Value};

/// Writes a one-mesh, one-primitive glTF (buffer 0 embedded as a data URI) and returns its path.
/// Accessor 0 is the POSITION accessor, and gets the `min`/`max` glTF requires of one.
fn write_gltf(
    dir: &Path,
    primitive: Value,
    mut accessors: Value,
    views: Value,
    buffer: &[u8],
    declared: usize,
) -> PathBuf {
    let a = &mut accessors[0];
    if a.get("min").is_none() {
        let n = match a["type"].as_str() {
            Some("SCALAR") => 1,
            Some("VEC2") => 2,
            Some("VEC4") => 4,
            Some("MAT4") => 16,
            _ => 3,
        };
        a["min"] = json!(vec![-1e6; n]);
        a["max"] = json!(vec![1e6; n]);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [primitive]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": declared,
                     "uri": format!("data:application/octet-stream;base64,{}", csm_lab::report::html::base64(buffer))}],
    });
    let path = dir.join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    path
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Four vertices of a unit square and the two triangles over them (6 u16 indices).
fn square() -> (Vec<u8>, usize) {
    let mut b = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    let n = b.len();
    (b, n)
}

fn read(path: &Path) -> Result<Vec<[DVec3; 3]>, String> {
    catch_unwind(AssertUnwindSafe(|| read_gltf(path, false))).unwrap_or_else(|_| panic!("read_gltf panicked"))
}

fn error_of(primitive: Value, accessors: Value, views: Value, buffer: &[u8], declared: usize) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(dir.path(), primitive, accessors, views, buffer, declared);
    match read(&path) {
        Ok(t) => panic!("read {} triangles from a malformed file", t.len()),
        Err(e) => e,
    }
}

#[test]
fn a_well_formed_indexed_square_reads_its_two_triangles() {
    let (b, n) = square();
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(
        dir.path(),
        json!({"attributes": {"POSITION": 0}, "indices": 1}),
        json!([{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]),
        json!([{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}]),
        &b,
        n,
    );
    let t = read(&path).unwrap();
    let v = |x: f64, z: f64| DVec3::new(x, 0.0, z);
    assert_eq!(
        t,
        vec![
            [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)],
            [v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]
        ]
    );
}

#[test]
fn an_index_accessor_of_floats_is_an_error_naming_it() {
    let (b, n) = square();
    let e = error_of(
        json!({"attributes": {"POSITION": 0}, "indices": 1}),
        json!([{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 1, "componentType": 5126, "count": 3, "type": "SCALAR"}]),
        json!([{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}]),
        &b,
        n,
    );
    assert!(
        e.contains("mesh 0, primitive 0, accessor 1") && e.contains("component type F32"),
        "{e}"
    );
}

#[test]
fn a_position_stride_shorter_than_a_vec3_is_an_error_naming_it() {
    let (b, n) = square();
    for stride in [4, 8, 14] {
        let e = error_of(
            json!({"attributes": {"POSITION": 0}}),
            json!([{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}]),
            json!([{"buffer": 0, "byteLength": 48, "byteStride": stride}]),
            &b,
            n,
        );
        assert!(
            e.contains("mesh 0, primitive 0, accessor 0") && e.contains(&format!("byteStride {stride}")),
            "{e}"
        );
    }
}

#[test]
fn a_sparse_values_view_with_a_stride_is_an_error_naming_it() {
    let (mut b, _) = square();
    // Sparse: one index (u8 1) and one VEC3 value, appended.
    let at = b.len();
    b.extend_from_slice(&[1, 0, 0, 0]);
    b.extend_from_slice(&f32_bytes(&[5.0, 0.0, 0.0]));
    let n = b.len();
    let e = error_of(
        json!({"attributes": {"POSITION": 0}}),
        json!([{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5121},
                           "values": {"bufferView": 2}}}]),
        json!([{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": at, "byteLength": 4},
               {"buffer": 0, "byteOffset": at + 4, "byteLength": 12, "byteStride": 4}]),
        &b,
        n,
    );
    assert!(
        e.contains("accessor 0") && e.contains("sparse values") && e.contains("byteStride 4"),
        "{e}"
    );
}

#[test]
fn an_unreadable_index_accessor_is_an_error_not_a_non_indexed_mesh() {
    let (b, n) = square();
    // The index view runs 100 bytes past the buffer: before, the mesh was read as non-indexed.
    let e = error_of(
        json!({"attributes": {"POSITION": 0}, "indices": 1}),
        json!([{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}]),
        json!([{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 112}]),
        &b,
        n,
    );
    assert!(e.contains("accessor 1") && e.contains("runs past its buffer"), "{e}");
    // An index count past the view's end.
    let e = error_of(
        json!({"attributes": {"POSITION": 0}, "indices": 1}),
        json!([{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 1, "componentType": 5123, "count": 9, "type": "SCALAR"}]),
        json!([{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}]),
        &b,
        n,
    );
    assert!(e.contains("accessor 1") && e.contains("9 elements"), "{e}");
}

#[test]
fn interleaved_and_sparse_positions_read_back_exactly() {
    // Three vertices interleaved with a 4-byte attribute (stride 16), then a sparse override of
    // vertex 2 (u16 index).
    let mut b = Vec::new();
    let verts = [[1.5f32, 2.0, 3.0], [4.0, 5.0, 6.25], [7.0, 8.0, 9.0]];
    for v in verts {
        b.extend_from_slice(&f32_bytes(&v));
        b.extend_from_slice(&[0xAA; 4]);
    }
    let at = b.len();
    b.extend_from_slice(&2u16.to_le_bytes());
    b.extend_from_slice(&[0, 0]);
    b.extend_from_slice(&f32_bytes(&[-1.0, 0.5, 2.0]));
    let n = b.len();
    let dir = tempfile::tempdir().unwrap();
    let path = write_gltf(
        dir.path(),
        json!({"attributes": {"POSITION": 0}}),
        json!([{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                           "values": {"bufferView": 2}}}]),
        json!([{"buffer": 0, "byteLength": 48, "byteStride": 16}, {"buffer": 0, "byteOffset": at, "byteLength": 2},
               {"buffer": 0, "byteOffset": at + 4, "byteLength": 12}]),
        &b,
        n,
    );
    let t = read(&path).unwrap();
    assert_eq!(
        t,
        vec![[
            DVec3::new(1.5, 2.0, 3.0),
            DVec3::new(4.0, 5.0, 6.25),
            DVec3::new(-1.0, 0.5, 2.0)
        ]]
    );
}

#[test]
fn buffer_files_outside_the_folder_are_read_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("scene");
    std::fs::create_dir(&sub).unwrap();
    std::fs::write(
        dir.path().join("outside.bin"),
        f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
    )
    .unwrap();
    let doc = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": "../outside.bin"}],
    });
    let path = sub.join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let e = read_gltf(&path, false).unwrap_err();
    assert!(e.contains("outside") && e.contains("scene.gltf_outside_buffers"), "{e}");
    assert_eq!(read_gltf(&path, true).unwrap().len(), 1);
}

#[cfg(unix)]
#[test]
fn a_fifo_or_device_as_scene_or_buffer_is_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.gltf");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let e = read_gltf(&fifo, false).unwrap_err();
    assert!(e.contains("not a regular file"), "{e}");
    let e = read_gltf(Path::new("/dev/zero"), false).unwrap_err();
    assert!(e.contains("not a regular file"), "{e}");
    // A buffer URI naming the FIFO.
    let doc = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36, "uri": "pipe.gltf"}],
    });
    let path = dir.path().join("scene.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let e = read_gltf(&path, false).unwrap_err();
    assert!(e.contains("pipe.gltf") && e.contains("not a regular file"), "{e}");
}

/// Component types glTF defines, and a few it does not.
fn component() -> impl Strategy<Value = u32> {
    prop_oneof![
        Just(5120u32),
        Just(5121),
        Just(5122),
        Just(5123),
        Just(5125),
        Just(5126),
        Just(5124)
    ]
}

fn element_type() -> impl Strategy<Value = &'static str> {
    prop_oneof![Just("SCALAR"), Just("VEC2"), Just("VEC3"), Just("VEC4"), Just("MAT4")]
}

fn small() -> impl Strategy<Value = u64> {
    prop_oneof![0u64..80, Just(u32::MAX as u64), Just(1u64 << 40)]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    /// Any combination of accessor, view and sparse fields: read_gltf answers Ok (finite
    /// triangles) or a short error, never a panic.
    #[test]
    fn malformed_accessors_never_panic(
        pos_ct in component(), pos_ty in element_type(), pos_count in small(), pos_off in small(),
        idx in proptest::option::of((component(), element_type(), small(), small())),
        stride in proptest::option::of(0u64..40), view_off in small(), view_len in small(),
        sparse in proptest::option::of((small(), 5121u32..5126, small(), proptest::option::of(0u64..20))),
        declared in 0usize..200, bytes in proptest::collection::vec(any::<u8>(), 0..160),
    ) {
        let mut pos = json!({"bufferView": 0, "componentType": pos_ct, "count": pos_count,
                             "type": pos_ty, "byteOffset": pos_off});
        if let Some((count, ct, off, vstride)) = sparse {
            pos["sparse"] = json!({"count": count, "indices": {"bufferView": 1, "componentType": ct, "byteOffset": off},
                                   "values": {"bufferView": 2, "byteOffset": off}});
            let _ = vstride;
        }
        let mut accessors = vec![pos];
        let mut primitive = json!({"attributes": {"POSITION": 0}});
        if let Some((ct, ty, count, off)) = idx {
            accessors.push(json!({"bufferView": 1, "componentType": ct, "count": count, "type": ty, "byteOffset": off}));
            primitive["indices"] = json!(1);
        }
        let mut v0 = json!({"buffer": 0, "byteOffset": view_off, "byteLength": view_len});
        if let Some(s) = stride {
            v0["byteStride"] = json!(s);
        }
        let mut v2 = json!({"buffer": 0, "byteOffset": 4, "byteLength": 24});
        if let Some((_, _, _, Some(s))) = sparse {
            v2["byteStride"] = json!(s);
        }
        let views = json!([v0, {"buffer": 0, "byteLength": 16}, v2]);
        let dir = tempfile::tempdir().unwrap();
        let path = write_gltf(dir.path(), primitive, Value::Array(accessors), views, &bytes, declared);
        let r = catch_unwind(AssertUnwindSafe(|| read_gltf(&path, false)));
        prop_assert!(r.is_ok(), "read_gltf panicked");
        match r.unwrap() {
            Ok(tris) => {
                for t in tris {
                    prop_assert!(t.iter().all(|p| p.is_finite()));
                }
            }
            Err(e) => prop_assert!(!e.is_empty() && e.len() < 2000, "{e}"),
        }
    }
}
