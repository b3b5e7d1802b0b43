//! Every WGSL file in `shaders/` (and every source composed at runtime) parses and
//! validates with naga, and every technique is covered by at least one file.
//!
//! Capabilities: [`naga::valid::Capabilities::default()`], the set wgpu grants a device
//! opened with no optional features (which is how [`shadowmap_wgpu::GpuContext`] opens
//! it), so a shader that needs more fails here instead of at pipeline creation.

use std::path::{Path, PathBuf};

use naga::valid::{Capabilities, ValidationFlags, Validator};

/// The techniques a `// techniques:` header may name, besides `any`.
const TECHNIQUES: [&str; 8] = [
    "uniform",
    "cascades",
    "lispsm",
    "xpsm",
    "tsm",
    "paraboloid",
    "rtw",
    "tiles",
];

fn shader_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders")
}

/// `(file name, source)` of every `.wgsl` file in `shaders/`, sorted by name.
fn shader_files() -> Vec<(String, String)> {
    let dir = shader_dir();
    let entries =
        std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()));
    let mut files: Vec<(String, String)> = entries
        .map(|entry| entry.expect("directory entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "wgsl"))
        .map(|path| {
            let name = path
                .file_name()
                .expect("file name")
                .to_string_lossy()
                .into_owned();
            let source = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
            (name, source)
        })
        .collect();
    files.sort();
    files
}

/// The techniques named by the first line, which must be `// techniques: a, b, ...`.
fn header_techniques(name: &str, source: &str) -> Vec<String> {
    let first = source.lines().next().unwrap_or_default();
    let list = first.strip_prefix("// techniques:").unwrap_or_else(|| {
        panic!("{name}: first line must be `// techniques: ...`, got {first:?}")
    });
    let names: Vec<String> = list
        .split(',')
        .map(|t| t.trim().to_owned())
        .filter(|t| !t.is_empty())
        .collect();
    assert!(!names.is_empty(), "{name}: empty techniques header");
    for t in &names {
        assert!(
            t == "any" || TECHNIQUES.contains(&t.as_str()),
            "{name}: unknown technique {t:?} in header"
        );
    }
    names
}

/// Parses and validates one source; the error carries naga's rendered diagnostic.
fn validate(name: &str, source: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: parse error\n{}", e.emit_to_string(source)))?;
    Validator::new(ValidationFlags::all(), Capabilities::default())
        .validate(&module)
        .map_err(|e| format!("{name}: validation error\n{}", e.emit_to_string(source)))?;
    Ok(())
}

/// Sources composed at runtime (WGSL has no includes): every scene shader (lookup +
/// filter) of the renderer, RTW's depth pass and caster refinement (with the shared
/// table sampler), each with its composition result.
fn composed_sources() -> Vec<(&'static str, Result<String, shadowmap_wgpu::BackendError>)> {
    shadowmap_wgpu::render::composed_shaders()
}

/// Lookups times filters the renderer composes, the RTW and paraboloid depth passes
/// and the refinement.
const COMPOSITIONS: usize = 5 * 5 + 3;

#[test]
fn every_shader_file_parses_and_validates() {
    let files = shader_files();
    assert!(
        !files.is_empty(),
        "no .wgsl files in {}",
        shader_dir().display()
    );
    let errors: Vec<String> = files
        .iter()
        .filter_map(|(name, source)| validate(name, source).err())
        .collect();
    assert!(errors.is_empty(), "{}", errors.join("\n\n"));
}

#[test]
fn every_technique_is_named_by_some_shader_header() {
    let files = shader_files();
    assert!(
        !files.is_empty(),
        "no .wgsl files in {}",
        shader_dir().display()
    );
    let named: Vec<String> = files
        .iter()
        .flat_map(|(name, source)| header_techniques(name, source))
        .collect();
    let missing: Vec<&str> = TECHNIQUES
        .iter()
        .copied()
        .filter(|t| !named.iter().any(|n| n == t))
        .collect();
    assert!(
        missing.is_empty(),
        "no shader header names {missing:?}; headers name {named:?}"
    );
}

#[test]
fn composed_sources_parse_and_validate() {
    let composed = composed_sources();
    assert_eq!(
        composed.len(),
        COMPOSITIONS,
        "every lookup with every filter, the RTW and paraboloid depth passes, the refinement"
    );
    let errors: Vec<String> = composed
        .iter()
        .filter_map(|(name, source)| match source {
            Ok(source) => validate(name, source).err(),
            Err(e) => Some(format!("{name}: composition failed: {e}")),
        })
        .collect();
    assert!(errors.is_empty(), "{}", errors.join("\n\n"));
}

#[test]
fn a_broken_shader_is_rejected() {
    // The checker itself must be able to fail: a type error and a syntax error.
    let type_error =
        "// techniques: any\n@compute @workgroup_size(1) fn main() { let x: u32 = 1.5; }";
    assert!(validate("type_error", type_error).is_err());
    assert!(validate("syntax_error", "fn main( {").is_err());
    let ok = "// techniques: any\n@compute @workgroup_size(1) fn main() {}";
    assert_eq!(validate("ok", ok), Ok(()));
}
