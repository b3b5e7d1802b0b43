//! The data features: every public options and result type survives a `serde_json`
//! round trip unchanged (values from the shared generators), and bad payloads give an
//! error.
#![cfg(feature = "serde")]

use proptest::prelude::*;
use shadowmap_frustum::{CascadeSplits, SplitScheme};
use shadowmap_testgen::serde_check::{rejects, rejects_with, round_trip};
use shadowmap_testgen::{strategy, warp as cases};
use shadowmap_warp::{
    LispsmOptions, ParallelFade, TsmOptions, UniformOptions, WarpError, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
};

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// Every technique's options and fit over the generators' valid scenes; the
    /// cascades come from two and three practical splits.
    #[test]
    fn fits_round_trip(case in strategy(cases::warp_case)) {
        let (camera, light, scene) = (&case.camera, case.light, &case.scene);
        let uniform = UniformOptions::default().with_reversed_z(case.reversed_z);
        round_trip(&uniform);
        if let Ok(t) = uniform_focused(camera, light, scene, &uniform) {
            round_trip(&t);
        }
        let options = LispsmOptions::default()
            .with_reversed_z(case.reversed_z)
            .with_eta(case.eta.clamp(-1.0, 1.0));
        round_trip(&options);
        round_trip(&options.with_hints(0.5, 50.0));
        if let Ok(shadow) = lispsm(camera, light, scene, &options) {
            round_trip(&shadow);
        }
        let options = TsmOptions::default().with_reversed_z(case.reversed_z);
        round_trip(&options.fade);
        round_trip(&options);
        if let Ok(shadow) = tsm(camera, light, scene, &options) {
            round_trip(&shadow);
        }
        let options = XpsmOptions::default().with_reversed_z(case.reversed_z);
        round_trip(&options);
        round_trip(&options.with_coef(0.25));
        if let Ok(shadow) = xpsm(camera, light, scene, &options) {
            round_trip(&shadow);
        }
        let Ok((near, far)) = camera.depth_range() else {
            return Ok(());
        };
        let count = if case.reversed_z { 2 } else { 3 };
        let scheme = SplitScheme::Practical { lambda: 0.7 };
        let Ok(splits) = CascadeSplits::new(&scheme, count, near, far.min(near * 1e4)) else {
            return Ok(());
        };
        let etas = [case.eta.clamp(-1.0, 1.0), 0.0, -0.5];
        let lispsm_options = LispsmOptions::default();
        if let Ok(set) = warped_cascades(camera, light, scene, &splits, &etas[..count], &lispsm_options) {
            for cascade in &set.cascades {
                round_trip(cascade);
            }
            round_trip(&set);
        }
    }
}

#[test]
fn unbounded_hints_read_back_as_infinity() {
    // The default far hint is infinite: JSON writes it as null.
    let json = serde_json::to_string(&LispsmOptions::default()).unwrap();
    assert!(json.contains(r#""far_hint":null"#), "{json}");
    let back: LispsmOptions = serde_json::from_str(&json).unwrap();
    assert_eq!(back.far_hint, f32::INFINITY);
    round_trip(&LispsmOptions::default());
}

#[test]
fn missing_option_fields_take_their_defaults() {
    let options: LispsmOptions = serde_json::from_str(r#"{"eta": 0.5}"#).unwrap();
    assert_eq!(options, LispsmOptions::default().with_eta(0.5));
    let options: TsmOptions = serde_json::from_str(r#"{"fade": {"end_deg": 5.0}}"#).unwrap();
    assert_eq!(options, TsmOptions::default().with_fade(10.0, 5.0));
    let options: XpsmOptions = serde_json::from_str("{}").unwrap();
    assert_eq!(options, XpsmOptions::default());
    let options: UniformOptions = serde_json::from_str(r#"{"reversed_z": true}"#).unwrap();
    assert_eq!(options, UniformOptions::default().with_reversed_z(true));
}

#[test]
fn bad_payloads_are_errors() {
    // Out of the documented ranges (as the builders reject them).
    rejects_with::<LispsmOptions>(r#"{"eta": 1.5}"#, WarpError::InvalidOption);
    rejects_with::<LispsmOptions>(
        r#"{"near_hint": 10.0, "far_hint": 5.0}"#,
        WarpError::InvalidOption,
    );
    rejects_with::<LispsmOptions>(
        r#"{"fade": {"start_deg": 2.0, "end_deg": 3.0}}"#,
        WarpError::InvalidOption,
    );
    rejects_with::<ParallelFade>(r#"{"start_deg": 95.0}"#, WarpError::InvalidOption);
    rejects_with::<TsmOptions>(r#"{"focus": 1.0}"#, WarpError::InvalidOption);
    rejects_with::<XpsmOptions>(r#"{"epsilon_w": 0.0}"#, WarpError::InvalidOption);
    rejects_with::<XpsmOptions>(r#"{"coef": -1.0}"#, WarpError::InvalidOption);
    rejects_with::<XpsmOptions>(r#"{"miner_lamp_threshold": 0.5}"#, WarpError::InvalidOption);
    // Wrong types.
    rejects::<LispsmOptions>(r#"{"eta": "strong"}"#);
    rejects::<UniformOptions>(r#"{"reversed_z": 1}"#);
}
