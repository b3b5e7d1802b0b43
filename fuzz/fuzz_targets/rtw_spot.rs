#![no_main]
//! RTW over the spot fit (a perspective base) on any spot light: the accumulation
//! contract, coverage of what the spot fit maps, base depth kept, inverse and
//! monotone warp (`shadowmap_testgen::rtw::check_spot_rtw`).

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::arbitrary::Unstructured;
use shadowmap_testgen::rtw::{check_spot_rtw, spot_rtw_case_raw};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = spot_rtw_case_raw(&mut Unstructured::new(data)) {
        check_spot_rtw(&case);
    }
});
