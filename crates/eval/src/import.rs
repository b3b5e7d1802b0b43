//! Mesh import: Wavefront OBJ (via `tobj`) and glTF 2.0 (`.gltf` with external or
//! embedded base64 buffers, and binary `.glb`, via `gltf`).
//!
//! Only positions and triangles are read; materials, normals and textures are
//! ignored (images are never loaded). Every error names the file and what in it is
//! wrong. The `*_from_bytes` functions parse bytes already in memory (the loaders
//! and the fuzz targets go through them); no input, however malformed, panics.
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
/// [`EvalError::Io`] for a missing or unreadable file; otherwise as
/// [`obj_from_bytes`].
pub fn load_obj(path: impl AsRef<Path>) -> Result<Mesh, EvalError> {
    let path = path.as_ref();
    obj_from_bytes(&read(path)?, path)
}

/// Parses the bytes of an OBJ file (`path` only names it in errors); material
/// libraries are not read.
///
/// # Errors
/// [`EvalError::Malformed`] for bytes that are not UTF-8 text (with the line), that
/// `tobj` cannot parse, or with a non-finite position or out-of-range index;
/// [`EvalError::NoTriangles`] for a file without faces.
pub fn obj_from_bytes(bytes: &[u8], path: &Path) -> Result<Mesh, EvalError> {
    if let Err(e) = std::str::from_utf8(bytes) {
        let at = e.valid_up_to();
        let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
        return Err(malformed(
            path,
            format!("not an OBJ text file: line {line} (byte {at}) is not UTF-8 text"),
        ));
    }
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let statements = positions_and_faces(std::str::from_utf8(bytes).unwrap_or_default());
    let mut reader = std::io::BufReader::new(statements.as_bytes());
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| malformed(path, format!("not a valid Wavefront OBJ file: {e}")))?;
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

/// The statements of an OBJ text that a shadow caster needs: vertex positions (`v`)
/// and faces (`f`) with their position indices only; texture coordinates, normals,
/// lines, points, groups and materials are dropped. `tobj` checks position indices
/// but not texture-coordinate or normal indices (a huge one overflows inside it), so
/// it is never given any. Statements are split on whitespace as `tobj` splits them.
fn positions_and_faces(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut tokens = line.split_whitespace();
        match tokens.next() {
            Some("v") => out.push_str(line),
            Some("f") => {
                out.push('f');
                for token in tokens {
                    out.push(' ');
                    out.push_str(token.split('/').next().unwrap_or_default());
                }
            }
            _ => continue,
        }
        out.push('\n');
    }
    out
}

/// Loads all meshes of a glTF file's default scene (the first scene if none is
/// marked default, or every root node if the file has no scene), node transforms
/// applied. Primitives in `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN` mode are
/// read, non-indexed ones too; point and line primitives are skipped. External
/// buffers are read relative to the file's directory.
///
/// # Errors
/// [`EvalError::Io`] for a missing or unreadable file; otherwise as
/// [`gltf_from_bytes`].
pub fn load_gltf(path: impl AsRef<Path>) -> Result<Mesh, EvalError> {
    let path = path.as_ref();
    let base = path.parent().unwrap_or_else(|| Path::new("."));
    gltf_from_bytes(&read(path)?, path, Some(base))
}

/// Parses the bytes of a `.gltf` (JSON) or `.glb` (binary) file; `path` names it in
/// errors (and a `.glb` extension requires the binary container), external buffers
/// are read from `base` (with `None`, a file that needs one is an error).
///
/// Every index of the document and every accessor's byte range are checked before
/// any of them is followed, so no input makes the parser index out of bounds.
///
/// # Errors
/// [`EvalError::Malformed`] naming what is wrong: a `.glb` without the binary
/// header, invalid JSON, an index that names no object, a buffer that cannot be
/// read (with its index and URI) or is shorter than declared, an accessor that
/// overruns its buffer view, a view that overruns its buffer, a primitive without
/// `POSITION`, a non-finite position or out-of-range vertex index;
/// [`EvalError::NoTriangles`] for a scene without triangles.
pub fn gltf_from_bytes(bytes: &[u8], path: &Path, base: Option<&Path>) -> Result<Mesh, EvalError> {
    let (json, blob) = split_container(bytes, path)?;
    let root = gltf::json::Root::from_slice(&json)
        .map_err(|e| malformed(path, format!("invalid glTF JSON: {e}")))?;
    check_primitive_indices(&root).map_err(|m| malformed(path, m))?;
    let document = gltf::Document::from_json(root).map_err(|e| malformed(path, e.to_string()))?;
    let buffers = read_buffers(&document, base, blob).map_err(|m| malformed(path, m))?;
    check_accessors(&document).map_err(|m| malformed(path, m))?;
    let mut mesh = Mesh::new();
    // Iterative walk; the depth guard stops a cyclic (invalid) node graph.
    let mut stack: Vec<(gltf::Node<'_>, DMat4, usize)> = scene_roots(&document)
        .into_iter()
        .map(|n| (n, DMat4::IDENTITY, 0))
        .collect();
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

fn read(path: &Path) -> Result<Vec<u8>, EvalError> {
    std::fs::read(path).map_err(|source| EvalError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The JSON and the binary chunk of a `.glb`, or the JSON of a `.gltf`.
fn split_container(bytes: &[u8], path: &Path) -> Result<(Vec<u8>, Option<Vec<u8>>), EvalError> {
    let is_glb_name = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if bytes.starts_with(b"glTF") {
        let glb = gltf::binary::Glb::from_slice(bytes)
            .map_err(|e| malformed(path, format!("invalid GLB container: {e}")))?;
        Ok((
            glb.json.into_owned(),
            glb.bin.map(std::borrow::Cow::into_owned),
        ))
    } else if is_glb_name {
        Err(malformed(
            path,
            "not a binary glTF file: it does not start with the `glTF` magic bytes".into(),
        ))
    } else {
        Ok((bytes.to_vec(), None))
    }
}

/// Checks every accessor index a mesh primitive names (attributes, indices, morph
/// targets) and its material, which the `gltf` crate's validation would otherwise
/// follow unchecked.
fn check_primitive_indices(root: &gltf::json::Root) -> Result<(), String> {
    let accessors = root.accessors.len();
    let check = |mesh: usize, prim: usize, what: &str, index: usize| {
        if index < accessors {
            Ok(())
        } else {
            Err(format!(
                "mesh {mesh} primitive {prim}: {what} names accessor {index}, but the file \
                 has {accessors} accessor(s)"
            ))
        }
    };
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                let name = match semantic {
                    gltf::json::validation::Checked::Valid(s) => s.to_string(),
                    gltf::json::validation::Checked::Invalid => "an attribute".into(),
                };
                check(m, p, &name, index.value())?;
            }
            if let Some(index) = prim.indices {
                check(m, p, "indices", index.value())?;
            }
            for target in prim.targets.iter().flatten() {
                for index in [target.positions, target.normals, target.tangents]
                    .into_iter()
                    .flatten()
                {
                    check(m, p, "a morph target", index.value())?;
                }
            }
            if let Some(material) = prim.material {
                if material.value() >= root.materials.len() {
                    return Err(format!(
                        "mesh {m} primitive {p}: material {} does not exist",
                        material.value()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Reads every buffer; an error names the buffer, its URI and the file looked for.
fn read_buffers(
    document: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<gltf::buffer::Data>, String> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let source = buffer.source();
        let describe = match source {
            gltf::buffer::Source::Bin => "the GLB binary chunk".to_string(),
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                "an embedded data URI".to_string()
            }
            gltf::buffer::Source::Uri(uri) => match base {
                Some(base) => format!("external file {:?} ({})", uri, base.join(uri).display()),
                None => format!("external file {uri:?}"),
            },
        };
        if base.is_none()
            && matches!(source, gltf::buffer::Source::Uri(u) if !u.starts_with("data:"))
        {
            return Err(format!(
                "buffer {i} is {describe}, which cannot be read without a directory"
            ));
        }
        let data = gltf::buffer::Data::from_source_and_blob(source, base, &mut blob)
            .map_err(|e| format!("buffer {i} ({describe}): {e}"))?;
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} ({describe}) holds {} bytes, fewer than its declared {}",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Whether `len` bytes from `offset` lie inside `available`.
fn fits(offset: usize, len: usize, available: usize) -> bool {
    offset.checked_add(len).is_some_and(|end| end <= available)
}

/// Checks that every buffer view lies inside its buffer and every accessor's
/// elements inside its view.
fn check_accessors(document: &gltf::Document) -> Result<(), String> {
    for view in document.views() {
        let buffer = view.buffer();
        if !fits(view.offset(), view.length(), buffer.length()) {
            return Err(format!(
                "buffer view {} (bytes {}..{}) overruns buffer {} of {} bytes",
                view.index(),
                view.offset(),
                view.offset().saturating_add(view.length()),
                buffer.index(),
                buffer.length()
            ));
        }
    }
    for accessor in document.accessors() {
        let Some(view) = accessor.view() else {
            continue;
        };
        let size = accessor.size();
        let stride = view.stride().unwrap_or(size).max(size);
        let count = accessor.count();
        let span = match count {
            0 => Some(0),
            n => stride.checked_mul(n - 1).and_then(|s| s.checked_add(size)),
        };
        if !span.is_some_and(|span| fits(accessor.offset(), span, view.length())) {
            return Err(format!(
                "accessor {} ({count} elements of {size} bytes, stride {stride}, offset {}) \
                 overruns buffer view {} of {} bytes",
                accessor.index(),
                accessor.offset(),
                view.index(),
                view.length()
            ));
        }
    }
    Ok(())
}

/// The root nodes of the default scene (or the first, or every parentless node).
fn scene_roots(document: &gltf::Document) -> Vec<gltf::Node<'_>> {
    match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(scene) => scene.nodes().collect(),
        None => {
            let children: Vec<usize> = document
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                .collect();
            document
                .nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect()
        }
    }
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
