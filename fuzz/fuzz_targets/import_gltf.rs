#![no_main]
//! Fuzzes the glTF / GLB importer of `shadowmap-eval` (the function `compare --mesh`
//! uses) on arbitrary bytes, as a `.gltf` and as a `.glb`: it returns a mesh or a
//! typed error, never panics, and a mesh it returns is valid and has triangles.
//! External buffers are not read (no directory is given); embedded data URIs and
//! the GLB binary chunk are.

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use shadowmap_eval::import::gltf_from_bytes;

fuzz_target!(|data: &[u8]| {
    for name in ["fuzz.gltf", "fuzz.glb"] {
        if let Ok(mesh) = gltf_from_bytes(data, Path::new(name), None) {
            assert!(mesh.validate().is_ok());
            assert!(!mesh.indices.is_empty());
        }
    }
});
