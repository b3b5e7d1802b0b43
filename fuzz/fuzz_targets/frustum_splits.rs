#![no_main]
//! Fuzzes `shadowmap-frustum`: splits. Generator and check live in
//! `shadowmap_testgen::frustum`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, frustum};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = frustum::split_case_raw(&mut Unstructured::new(data)) {
        frustum::check_splits(&case);
    }
});
