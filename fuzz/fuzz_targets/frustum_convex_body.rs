#![no_main]
//! Fuzzes `shadowmap-frustum`: convex body. Generator and check live in
//! `shadowmap_testgen::frustum`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, frustum};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = frustum::body_case_raw(&mut Unstructured::new(data)) {
        frustum::check_convex_body(&case);
    }
});
