//! Property tests of the spot warps (LiSPSM and TSM in the spot light's
//! post-projective space), driven by `shadowmap_testgen::spot_warp`.

use proptest::prelude::*;
use shadowmap_testgen::spot_warp::{check_spot_warp, spot_warp_case};
use shadowmap_testgen::strategy;

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// What the spot fit stores the warp stores, inside its map, each ray on one
    /// texel with depth growing away from the light; matrices finite and invertible.
    #[test]
    fn spot_warps_keep_what_the_spot_fit_stores(case in strategy(spot_warp_case)) {
        check_spot_warp(&case).map_err(TestCaseError::fail)?;
    }
}

/// The generator reaches fitted warps with points to check, warped and not.
#[test]
fn the_generator_reaches_warped_fits() {
    use shadowmap_testgen::arbitrary::Unstructured;
    use shadowmap_warp::spot_warp;
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let (mut checked, mut warped) = (0, 0);
    for _ in 0..400 {
        let bytes = shadowmap_testgen::xorshift_bytes(&mut state, 256);
        let Ok(case) = spot_warp_case(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        checked += usize::from(check_spot_warp(&case).unwrap() > 0);
        let fit = spot_warp(
            &case.light,
            &case.camera,
            case.bounds,
            &case.scene,
            &case.options,
        );
        warped += usize::from(fit.is_ok_and(|w| w.strength > 0.0));
    }
    assert!(
        checked > 50 && warped > 10,
        "{checked} checked, {warped} warped"
    );
}

/// The data feature: options and fits round-trip, a focus outside (0, 1) is refused.
#[cfg(feature = "serde")]
#[test]
fn spot_warps_round_trip() {
    use shadowmap_testgen::arbitrary::Unstructured;
    use shadowmap_testgen::serde_check::{rejects_with, round_trip};
    use shadowmap_warp::{SpotWarpKind, SpotWarpOptions, WarpError, spot_warp};
    for kind in [SpotWarpKind::Lispsm, SpotWarpKind::Tsm] {
        round_trip(&SpotWarpOptions::default().with_kind(kind).with_focus(0.3));
    }
    rejects_with::<SpotWarpOptions>(r#"{"focus": 1.0}"#, WarpError::InvalidOption);
    let mut fitted = 0;
    for seed in 0..64u8 {
        let bytes: Vec<u8> = (0..256u32)
            .map(|i| (i as u8).wrapping_mul(31) ^ seed)
            .collect();
        let Ok(case) = spot_warp_case(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        if let Ok(w) = spot_warp(
            &case.light,
            &case.camera,
            case.bounds,
            &case.scene,
            &case.options,
        ) {
            round_trip(&w);
            fitted += 1;
        }
    }
    assert!(fitted > 0);
}
