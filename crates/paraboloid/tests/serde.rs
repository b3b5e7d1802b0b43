//! The data features: every public options and result type survives a `serde_json`
//! round trip unchanged (values from the shared generators), and bad payloads give an
//! error.
#![cfg(feature = "serde")]

use proptest::prelude::*;
use shadowmap_paraboloid::{
    ConeFit, DualReason, FaceSizes, IpsmOptions, IpsmPlan, MapOptions, ParaboloidError,
    ParaboloidMode, Side, SubdivisionOptions, fit_minimal_cone, fit_paper_cone,
};
use shadowmap_testgen::serde_check::{rejects, rejects_with, round_trip};
use shadowmap_testgen::{paraboloid as cases, strategy};

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// IPSM options and plans (their map, cone, dual reason and border points).
    #[test]
    fn plans_round_trip(input in strategy(cases::plan_input)) {
        round_trip(&input.options);
        round_trip(&input.light);
        if let Some(bounds) = input.bounds {
            round_trip(&bounds);
        }
        if let Ok(plan) = IpsmPlan::new(&input.light, &input.camera, input.bounds, &input.options) {
            round_trip(&plan);
            round_trip(&plan.map);
            round_trip(&plan.map.usable_disc());
            if let Some(cone) = plan.cone {
                round_trip(&cone);
            }
        }
    }

    /// Maps built directly, the sides of their probe points, and both cone fits of
    /// the directions to those points.
    #[test]
    fn maps_and_cones_round_trip(input in strategy(cases::map_input)) {
        round_trip(&input.options);
        if let Ok(map) = cases::build_map(&input) {
            round_trip(&map);
            round_trip(&map.usable_disc());
            for p in &input.points {
                round_trip(&map.side_of(*p));
            }
        }
        let directions: Vec<_> = input.points.iter().map(|p| *p - input.position).collect();
        for cone in [fit_minimal_cone(&directions), fit_paper_cone(&directions)].into_iter().flatten() {
            round_trip(&cone);
        }
    }

    /// Subdivision options.
    #[test]
    fn subdivision_options_round_trip(input in strategy(cases::subdivide_input)) {
        round_trip(&input.options);
        round_trip(&input.side);
    }
}

#[test]
fn enums_round_trip() {
    for fit in [ConeFit::Paper, ConeFit::Exact] {
        round_trip(&fit);
    }
    for mode in [ParaboloidMode::Single, ParaboloidMode::Dual] {
        round_trip(&mode);
    }
    for side in [Side::Front, Side::Back] {
        round_trip(&side);
    }
    for reason in [
        DualReason::LightInsideFrustum,
        DualReason::LightOnFrustumPoint,
        DualReason::DirectionsCancel,
        DualReason::ConeTooWide,
        DualReason::DualFiner,
    ] {
        round_trip(&reason);
    }
    for sizes in [FaceSizes::Equal, FaceSizes::ByNeed] {
        round_trip(&sizes);
    }
}

#[test]
fn missing_option_fields_take_their_defaults() {
    let options: IpsmOptions = serde_json::from_str(r#"{"fit": "Paper"}"#).unwrap();
    assert_eq!(options, IpsmOptions::default().with_fit(ConeFit::Paper));
    let options: SubdivisionOptions = serde_json::from_str(r#"{"max_segments": 4}"#).unwrap();
    assert_eq!(options, SubdivisionOptions::default().with_max_segments(4));
    let options: MapOptions = serde_json::from_str(r#"{"reversed_z": true}"#).unwrap();
    assert_eq!(options, MapOptions::default().with_reversed_z(true));
}

#[test]
fn bad_payloads_are_errors() {
    // Out of the documented ranges (as the builders reject them).
    rejects_with::<IpsmOptions>(r#"{"near": 0.0}"#, ParaboloidError::InvalidOptions);
    rejects_with::<IpsmOptions>(r#"{"margin": -0.1}"#, ParaboloidError::InvalidOptions);
    rejects_with::<IpsmOptions>(
        r#"{"max_single_half_angle": 2.0}"#,
        ParaboloidError::InvalidOptions,
    );
    rejects_with::<SubdivisionOptions>(r#"{"resolution": 0}"#, ParaboloidError::InvalidSubdivision);
    rejects_with::<SubdivisionOptions>(
        r#"{"tolerance_texels": 0.0}"#,
        ParaboloidError::InvalidSubdivision,
    );
    rejects_with::<SubdivisionOptions>(
        r#"{"max_segments": 257}"#,
        ParaboloidError::InvalidSubdivision,
    );
    // Wrong shapes and names.
    rejects::<IpsmOptions>(r#"{"fit": "Approximate"}"#);
    rejects::<MapOptions>(r#"{"up_hint": [0.0, 1.0]}"#);
}
