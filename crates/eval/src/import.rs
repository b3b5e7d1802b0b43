//! Mesh import: Wavefront OBJ (via `tobj`) and glTF 2.0 (`.gltf` with external or
//! embedded base64 buffers, and binary `.glb`, via `gltf`).
//!
//! Only positions and triangles are read; materials, normals and textures are
//! ignored (images are never loaded). Every error names the file.
//!
//! # Example
//!
//! ```no_run
//! use shadowmap_eval::import::load_mesh;
//! use shadowmap_eval::scene::Scene;
//!
//! let mesh = load_mesh("assets/sponza.glb")?;
//! let scene = Scene::new("sponza", mesh);
//! # Ok::<(), shadowmap_eval::EvalError>(())
//! ```

use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3, Mat4};

use crate::EvalError;
use crate::scene::Mesh;

/// Loads a mesh, choosing the format by extension (case-insensitive): `.obj`,
/// `.gltf`, `.glb`.
///
/// # Errors
/// [`EvalError::UnsupportedFormat`] for another extension; otherwise as
/// [`load_obj`] and [`load_gltf`].
pub fn load_mesh(path: impl AsRef<Path>) -> Result<Mesh, EvalError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("obj") => load_obj(path),
        Some("gltf" | "glb") => load_gltf(path),
        _ => Err(EvalError::UnsupportedFormat {
            path: path.to_path_buf(),
        }),
    }
}

/// Loads every model of an OBJ file into one mesh, polygons triangulated (fan).
///
/// # Errors
/// [`EvalError::Io`] for a missing or unreadable file, [`EvalError::Malformed`] for
/// one `tobj` cannot parse or with a non-finite position or out-of-range index,
/// [`EvalError::NoTriangles`] for a file without faces.
pub fn load_obj(path: impl AsRef<Path>) -> Result<Mesh, EvalError> {
    let path = path.as_ref();
    // tobj reports a missing file without the OS error: open it first to keep it.
    std::fs::File::open(path).map_err(|source| EvalError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) =
        tobj::load_obj(path, &options).map_err(|e| malformed(path, e.to_string()))?;
    let mut mesh = Mesh::new();
    for model in &models {
        let m = &model.mesh;
        let positions: Vec<DVec3> = m
            .positions
            .chunks_exact(3)
            .map(|p| DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])))
            .collect();
        let indices = m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        mesh.append(&Mesh { positions, indices });
    }
    finish(path, mesh)
}

/// Loads all meshes of a glTF file's default scene (the first scene if none is
/// marked default, or every root node if the file has no scene), node transforms
/// applied. Primitives in `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` mode are
/// read, non-indexed ones too; point and line primitives are skipped.
///
/// # Errors
/// [`EvalError::Io`] for a missing or unreadable file, [`EvalError::Malformed`] for
/// invalid JSON/GLB, a missing or short buffer, a non-finite position or an
/// out-of-range index, [`EvalError::NoTriangles`] for a scene without triangles.
pub fn load_gltf(path: impl AsRef<Path>) -> Result<Mesh, EvalError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| EvalError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let gltf = gltf::Gltf::from_slice(&bytes).map_err(|e| malformed(path, e.to_string()))?;
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let buffers = gltf::import_buffers(&gltf.document, Some(base), gltf.blob.clone())
        .map_err(|e| malformed(path, e.to_string()))?;
    let document = &gltf.document;
    let roots: Vec<gltf::Node<'_>> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child.
            let children: Vec<usize> = document
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                .collect();
            document
                .nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect()
        }
    };
    let mut mesh = Mesh::new();
    // Iterative walk; the depth guard stops a cyclic (invalid) node graph.
    let mut stack: Vec<(gltf::Node<'_>, DMat4, usize)> =
        roots.into_iter().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 256 {
            return Err(malformed(
                path,
                "node hierarchy deeper than 256 (cycle?)".into(),
            ));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world_from_node = parent * local;
        if let Some(m) = node.mesh() {
            for primitive in m.primitives() {
                read_primitive(path, &primitive, &buffers, &world_from_node, &mut mesh)?;
            }
        }
        stack.extend(node.children().map(|c| (c, world_from_node, depth + 1)));
    }
    finish(path, mesh)
}

fn read_primitive(
    path: &Path,
    primitive: &gltf::Primitive<'_>,
    buffers: &[gltf::buffer::Data],
    world_from_node: &DMat4,
    mesh: &mut Mesh,
) -> Result<(), EvalError> {
    use gltf::mesh::Mode;
    let mode = primitive.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(());
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let Some(positions) = reader.read_positions() else {
        return Err(malformed(path, "primitive without POSITION".into()));
    };
    let positions: Vec<DVec3> = positions
        .map(|p| world_from_node.transform_point3(DVec3::from(p.map(f64::from))))
        .collect();
    let list: Vec<u32> = match reader.read_indices() {
        Some(indices) => indices.into_u32().collect(),
        None => (0..u32::try_from(positions.len()).unwrap_or(u32::MAX)).collect(),
    };
    let indices: Vec<[u32; 3]> = match mode {
        Mode::Triangles => list.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        Mode::TriangleStrip => list
            .windows(3)
            .enumerate()
            .map(|(i, t)| {
                if i % 2 == 0 {
                    [t[0], t[1], t[2]]
                } else {
                    [t[1], t[0], t[2]]
                }
            })
            .collect(),
        _ => (1..list.len().saturating_sub(1))
            .map(|i| [list[0], list[i], list[i + 1]])
            .collect(),
    };
    mesh.append(&Mesh { positions, indices });
    Ok(())
}

fn malformed(path: &Path, message: String) -> EvalError {
    EvalError::Malformed {
        path: path.to_path_buf(),
        message,
    }
}

fn finish(path: &Path, mesh: Mesh) -> Result<Mesh, EvalError> {
    mesh.validate()
        .map_err(|e| malformed(path, e.to_string()))?;
    if mesh.indices.is_empty() {
        return Err(EvalError::NoTriangles {
            path: PathBuf::from(path),
        });
    }
    Ok(mesh)
}
