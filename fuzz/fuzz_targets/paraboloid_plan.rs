#![no_main]
//! Fuzzes `shadowmap-paraboloid`: `IpsmPlan::new`. Generator and check live in
//! `shadowmap_testgen::paraboloid`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, paraboloid};

fuzz_target!(|data: &[u8]| {
    if let Ok(input) = paraboloid::plan_input_raw(&mut Unstructured::new(data)) {
        if let Err(e) = paraboloid::check_plan(&input) {
            panic!("{e}: {input:?}");
        }
    }
});
