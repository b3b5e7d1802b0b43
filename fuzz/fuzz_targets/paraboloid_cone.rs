#![no_main]
//! Fuzzes `shadowmap-paraboloid`: `fit_minimal_cone` and `fit_paper_cone`. Generator
//! and check live in `shadowmap_testgen::paraboloid`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, paraboloid};

fuzz_target!(|data: &[u8]| {
    if let Ok(dirs) = paraboloid::cone_directions_raw(&mut Unstructured::new(data)) {
        if let Err(e) = paraboloid::check_cone(&dirs) {
            panic!("{e}: {dirs:?}");
        }
    }
});
