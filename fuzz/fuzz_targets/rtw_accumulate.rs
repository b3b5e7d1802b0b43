#![no_main]
//! RTW backward, oracle and forward sample accumulation on any input: typed errors or
//! finite, non-negative importance (`shadowmap_testgen::rtw::check_accumulate`).

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::arbitrary::Unstructured;
use shadowmap_testgen::rtw::{accumulate_case_raw, check_accumulate};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = accumulate_case_raw(&mut Unstructured::new(data)) {
        check_accumulate(&case);
    }
});
