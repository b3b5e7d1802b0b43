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
