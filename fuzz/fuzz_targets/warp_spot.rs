#![no_main]
//! Fuzzes `shadowmap-warp`: `spot_warp` (LiSPSM and TSM in a spot light's
//! post-projective space). Generator and check live in
//! `shadowmap_testgen::spot_warp`, shared with the property tests.

use libfuzzer_sys::fuzz_target;
use shadowmap_testgen::{arbitrary::Unstructured, spot_warp};

fuzz_target!(|data: &[u8]| {
    if let Ok(case) = spot_warp::spot_warp_case(&mut Unstructured::new(data)) {
        if let Err(e) = spot_warp::check_spot_warp(&case) {
            panic!("{e}: {case:?}");
        }
    }
});
