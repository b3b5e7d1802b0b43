//! Mesh import: OBJ and glTF fixtures under `tests/data`, and every error case.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use shadowmap_eval::EvalError;
use shadowmap_eval::import::{load_gltf, load_mesh, load_obj};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

#[test]
fn obj_cube_merges_models_and_triangulates_quads() {
    let mesh = load_obj(data("cube.obj")).unwrap();
    assert_eq!(mesh.triangle_count(), 12);
    let b = mesh.bounds().unwrap();
    assert_eq!((b.min, b.max), (Vec3::ZERO, Vec3::ONE));
    // Closed cube: total area 6.
    let area: f64 = mesh
        .triangles()
        .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length())
        .sum();
    assert!((area - 6.0).abs() < 1e-12, "area {area}");
    // Same through the extension dispatch.
    assert_eq!(load_mesh(data("cube.obj")).unwrap(), mesh);
}

#[test]
fn gltf_applies_node_transforms_down_the_hierarchy() {
    let mesh = load_gltf(data("quad.gltf")).unwrap();
    // The quad twice: translated by 10 in x, and its child scaled by 2 under that.
    assert_eq!(mesh.triangle_count(), 4);
    let b = mesh.bounds().unwrap();
    assert_eq!(
        (b.min, b.max),
        (Vec3::new(10.0, 0.0, 0.0), Vec3::new(12.0, 0.0, 2.0))
    );
    let area: f64 = mesh
        .triangles()
        .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length())
        .sum();
    assert!((area - 5.0).abs() < 1e-12, "area {area}");
    assert!(mesh.positions.contains(&DVec3::new(12.0, 0.0, 2.0)));
    assert_eq!(load_mesh(data("quad.gltf")).unwrap(), mesh);
}

fn error_path(e: &EvalError) -> Option<&Path> {
    match e {
        EvalError::Io { path, .. }
        | EvalError::Malformed { path, .. }
        | EvalError::UnsupportedFormat { path }
        | EvalError::NoTriangles { path } => Some(path),
        _ => None,
    }
}

#[test]
fn missing_files_are_io_errors_naming_the_path() {
    for name in ["nope.obj", "nope.gltf", "nope.glb"] {
        let e = load_mesh(data(name)).unwrap_err();
        assert!(matches!(e, EvalError::Io { .. }), "{name}: {e:?}");
        assert_eq!(error_path(&e), Some(data(name).as_path()));
        assert!(e.to_string().contains(name), "{e}");
    }
}

#[test]
fn unsupported_extension_is_refused_before_reading() {
    for name in ["mesh.stl", "mesh", "cube.OBJX"] {
        let e = load_mesh(data(name)).unwrap_err();
        assert!(
            matches!(e, EvalError::UnsupportedFormat { .. }),
            "{name}: {e:?}"
        );
        assert!(e.to_string().contains(name));
    }
}

#[test]
fn malformed_files_are_typed_errors() {
    for name in [
        "malformed.obj",
        "bad_index.obj",
        "truncated.gltf",
        "short_buffer.gltf",
    ] {
        let e = load_mesh(data(name)).unwrap_err();
        assert!(matches!(e, EvalError::Malformed { .. }), "{name}: {e:?}");
        assert_eq!(error_path(&e), Some(data(name).as_path()));
    }
}

#[test]
fn files_without_triangles_are_refused() {
    for name in ["points_only.obj", "lines.gltf"] {
        let e = load_mesh(data(name)).unwrap_err();
        assert!(matches!(e, EvalError::NoTriangles { .. }), "{name}: {e:?}");
        assert!(e.to_string().contains(name));
    }
}

/// A fresh directory for files a test writes.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowmap-import-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// One triangle in an external buffer `uri` (36 bytes of positions); the POSITION
/// attribute names accessor `position`, which holds `count` vertices.
fn triangle_gltf(uri: &str, position: usize, count: usize) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":{position}}}}}]}}],
        "buffers":[{{"uri":"{uri}","byteLength":36}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3",
        "min":[0,0,0],"max":[1,0,1]}}]}}"#
    )
}

fn triangle_bin() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

fn gltf_error(tag: &str, json: &str, with_bin: bool) -> String {
    let dir = scratch(tag);
    if with_bin {
        std::fs::write(dir.join("tri.bin"), triangle_bin()).unwrap();
    }
    let path = dir.join("mesh.gltf");
    std::fs::write(&path, json).unwrap();
    let e = load_mesh(&path).unwrap_err();
    assert!(matches!(e, EvalError::Malformed { .. }), "{e:?}");
    assert_eq!(error_path(&e), Some(path.as_path()));
    let _ = std::fs::remove_dir_all(&dir);
    e.to_string()
}

#[test]
fn gltf_written_by_the_test_loads() {
    let dir = scratch("good");
    std::fs::write(dir.join("tri.bin"), triangle_bin()).unwrap();
    std::fs::write(dir.join("mesh.gltf"), triangle_gltf("tri.bin", 0, 3)).unwrap();
    let mesh = load_mesh(dir.join("mesh.gltf")).unwrap();
    assert_eq!(mesh.triangle_count(), 1);
    assert!(mesh.positions.contains(&DVec3::new(1.0, 0.0, 0.0)));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_position_naming_a_missing_accessor_is_named() {
    let e = gltf_error("missing-accessor", &triangle_gltf("tri.bin", 4, 3), true);
    assert!(e.contains("POSITION") && e.contains("accessor 4"), "{e}");
}

#[test]
fn gltf_accessor_overrunning_its_view_is_named() {
    let e = gltf_error("overrun", &triangle_gltf("tri.bin", 0, 10), true);
    assert!(e.contains("accessor 0") && e.contains("overruns"), "{e}");
    assert!(!e.contains("without POSITION"), "{e}");
}

#[test]
fn gltf_missing_external_buffer_is_named() {
    let e = gltf_error("no-buffer", &triangle_gltf("gone.bin", 0, 3), false);
    assert!(e.contains("buffer 0") && e.contains("gone.bin"), "{e}");
}

#[test]
fn bytes_that_are_not_glb_say_so() {
    use shadowmap_eval::import::gltf_from_bytes;
    let e = gltf_from_bytes(b"{\"not\": \"binary\"}", Path::new("x.glb"), None).unwrap_err();
    assert!(e.to_string().contains("magic"), "{e}");
    // A GLB header with a truncated body is a container error, not a panic.
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&1000u32.to_le_bytes());
    let e = gltf_from_bytes(&glb, Path::new("x.glb"), None).unwrap_err();
    assert!(matches!(e, EvalError::Malformed { .. }), "{e:?}");
}

#[test]
fn in_memory_gltf_with_an_external_buffer_needs_a_directory() {
    use shadowmap_eval::import::gltf_from_bytes;
    let json = triangle_gltf("tri.bin", 0, 3);
    let e = gltf_from_bytes(json.as_bytes(), Path::new("m.gltf"), None).unwrap_err();
    assert!(e.to_string().contains("tri.bin"), "{e}");
}

#[test]
fn obj_with_a_huge_texture_coordinate_index_is_read_without_panicking() {
    // Found by the `import_obj` fuzz target: a line element whose texture-coordinate
    // index overflows inside the OBJ parser. Only positions and faces reach it now.
    let result = load_obj(data("huge_texcoord_index.obj"));
    assert!(
        matches!(
            result,
            Err(EvalError::Malformed { .. } | EvalError::NoTriangles { .. })
        ),
        "{result:?}"
    );
}

#[test]
fn obj_texture_coordinates_and_normals_do_not_change_the_mesh() {
    let plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\n";
    let full = "vt 0 0\nvn 0 0 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                f 1/1/1 2/1/1 3//1 4/1\nl 1/99999999999999999999 2\n";
    let a = shadowmap_eval::import::obj_from_bytes(plain.as_bytes(), Path::new("a.obj")).unwrap();
    let b = shadowmap_eval::import::obj_from_bytes(full.as_bytes(), Path::new("b.obj")).unwrap();
    assert_eq!(a.triangle_count(), 2);
    assert_eq!(
        (a.positions.clone(), a.indices.clone()),
        (b.positions.clone(), b.indices.clone())
    );
}
