#![no_main]
//! The RTW warp builder on any importance map and options: typed errors or finite,
//! monotone warps mapping [0, 1] onto [0, 1] (`shadowmap_testgen::rtw::check_warp`).

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::arbitrary::Unstructured;
use shadowmap_testgen::rtw::{check_warp, warp_case_raw};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = warp_case_raw(&mut Unstructured::new(data)) {
        check_warp(&case);
    }
});
