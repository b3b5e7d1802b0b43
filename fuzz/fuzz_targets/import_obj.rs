#![no_main]
//! Fuzzes the OBJ importer of `shadowmap-eval` (the function `compare --mesh` uses)
//! on arbitrary bytes: it returns a mesh or a typed error, never panics, and a mesh
//! it returns is valid and has triangles.

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use shadowmap_eval::import::obj_from_bytes;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = obj_from_bytes(data, Path::new("fuzz.obj")) {
        assert!(mesh.validate().is_ok());
        assert!(!mesh.indices.is_empty());
    }
});
