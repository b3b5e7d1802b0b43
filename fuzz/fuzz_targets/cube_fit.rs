#![no_main]
//! Fuzzes `shadowmap-paraboloid`: `CubeMap::fit`. Generator and check live in
//! `shadowmap_testgen::cube`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, cube};

fuzz_target!(|data: &[u8]| {
    if let Ok(input) = cube::cube_input_raw(&mut Unstructured::new(data)) {
        if let Err(e) = cube::check_cube(&input, false) {
            panic!("{e}: {input:?}");
        }
    }
});
