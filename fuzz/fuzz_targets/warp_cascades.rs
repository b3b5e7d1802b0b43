#![no_main]
//! Fuzzes `shadowmap-warp`: the cascades builder. Generator and check live in
//! `shadowmap_testgen::warp`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, warp};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = warp::warp_case_raw(&mut Unstructured::new(data)) {
        let _ = warp::check_cascades(&case);
    }
});
