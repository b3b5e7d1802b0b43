//! The data features: every public options and result type survives a `serde_json`
//! round trip unchanged (values from the shared generators), and bad payloads (wrong
//! sizes, negative importance, tables that do not match their densities) give an
//! error.
#![cfg(feature = "serde")]

use glam::Vec2;
use proptest::prelude::*;
use shadowmap_rtw::{
    ImportanceMap, ImportanceOptions, OracleAxis, RtwError, RtwSubdivision, WarpMaps, WarpOptions,
};
use shadowmap_testgen::serde_check::{rejects_with, round_trip};
use shadowmap_testgen::{rtw as cases, strategy};

/// `warps` through JSON: every table, density and maximum reads back bit for bit,
/// and the next build (temporal smoothing reads the previous densities and whether
/// there was a previous frame) gives the same tables from both.
fn warps_round_trip(warps: &WarpMaps, next: &ImportanceMap, options: &WarpOptions) {
    let json = serde_json::to_string(warps).expect("serializes");
    let mut back: WarpMaps = serde_json::from_str(&json)
        .unwrap_or_else(|e| panic!("{warps:?} -> {json} does not read back: {e}"));
    let bits = |s: &[f32]| s.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(back.x_table()), bits(warps.x_table()));
    assert_eq!(bits(back.y_table()), bits(warps.y_table()));
    assert_eq!(bits(back.density_x()), bits(warps.density_x()));
    assert_eq!(bits(back.density_y()), bits(warps.density_y()));
    assert_eq!(back.column_max(), warps.column_max());
    assert_eq!(back.row_max(), warps.row_max());
    assert_eq!(back.identity_fallback(), warps.identity_fallback());
    let mut original = warps.clone();
    original.build(next, options).unwrap();
    back.build(next, options).unwrap();
    assert_eq!(bits(back.x_table()), bits(original.x_table()));
    assert_eq!(bits(back.y_table()), bits(original.y_table()));
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// Importance maps, warp options and the warp maps built from them (one or two
    /// frames).
    #[test]
    fn maps_round_trip(case in strategy(cases::warp_case)) {
        round_trip(&case.options);
        let mut map = ImportanceMap::new(case.width, case.height).unwrap();
        map.copy_from_slice(&case.values).unwrap();
        round_trip(&map);
        let mut warps = WarpMaps::new(case.width, case.height).unwrap();
        warps_round_trip(&warps, &map, &case.options);
        warps.build(&map, &case.options).unwrap();
        let next = match &case.second {
            Some(values) => {
                let mut next = map.clone();
                next.copy_from_slice(values).unwrap();
                next
            }
            None => map.clone(),
        };
        warps_round_trip(&warps, &next, &case.options);
    }

    /// Eye samples, importance options and the statistics of an accumulation.
    #[test]
    fn accumulation_round_trips(case in strategy(cases::accumulate_case)) {
        round_trip(&case.options);
        round_trip(&case.base);
        for sample in &case.samples {
            round_trip(sample);
        }
        let mut map = ImportanceMap::new(case.size.0, case.size.1).unwrap();
        let mask = case.edge_mask.as_deref();
        if let Ok(stats) = map.accumulate_backward(&case.base, &case.samples, mask, &case.options) {
            round_trip(&stats);
            round_trip(&map);
        }
    }
}

#[test]
fn plain_options_round_trip() {
    round_trip(&RtwSubdivision::default());
    for axis in [OracleAxis::Isotropic, OracleAxis::U, OracleAxis::V] {
        round_trip(&axis);
    }
    let options: WarpOptions = serde_json::from_str(r#"{"blur_radius": 5}"#).unwrap();
    assert_eq!(options, WarpOptions::default().with_blur_radius(5));
    let options: ImportanceOptions = serde_json::from_str("{}").unwrap();
    assert_eq!(options, ImportanceOptions::default());
}

#[test]
fn bad_payloads_are_errors() {
    // Options out of range.
    rejects_with::<WarpOptions>(r#"{"floor": 0.0}"#, RtwError::InvalidOption);
    rejects_with::<WarpOptions>(r#"{"temporal": 1.0}"#, RtwError::InvalidOption);
    rejects_with::<WarpOptions>(r#"{"blur_radius": 65}"#, RtwError::InvalidOption);
    rejects_with::<ImportanceOptions>(r#"{"edge_weight": 0.5}"#, RtwError::InvalidOption);
    // Importance maps: the size must be valid and match the cells, which must be
    // non-negative.
    serde_json::from_str::<ImportanceMap>(r#"{"width":2,"height":1,"cells":[0.0,3.0]}"#).unwrap();
    let short = RtwError::SizeMismatch {
        expected: 2,
        got: 1,
    };
    rejects_with::<ImportanceMap>(r#"{"width":2,"height":1,"cells":[0.0]}"#, short);
    let negative = r#"{"width":2,"height":1,"cells":[0.0,-1.0]}"#;
    rejects_with::<ImportanceMap>(negative, RtwError::NegativeImportance);
    rejects_with::<ImportanceMap>(r#"{"width":0,"height":0,"cells":[]}"#, RtwError::EmptyMap);
    let huge = r#"{"width":100000,"height":1,"cells":[]}"#;
    rejects_with::<ImportanceMap>(huge, RtwError::MapTooLarge);

    // Warp maps: a built value reads back; tampering with a table, a density or a
    // length does not.
    let mut map = ImportanceMap::new(8, 4).unwrap();
    map.splat(Vec2::new(0.3, 0.6), 5.0).unwrap();
    map.splat(Vec2::new(0.9, 0.1), 1.0).unwrap();
    let mut warps = WarpMaps::new(8, 4).unwrap();
    warps.build(&map, &WarpOptions::default()).unwrap();
    let good: serde_json::Value = serde_json::to_value(&warps).unwrap();
    serde_json::from_value::<WarpMaps>(good.clone()).unwrap();
    let tampered = |field: &str, index: usize, value: f64| {
        let mut v = good.clone();
        v[field][index] = serde_json::json!(value);
        v
    };
    let mismatch = "warp tables do not match";
    let x1 = good["x"][1].as_f64().unwrap();
    let d2 = good["density_x"][2].as_f64().unwrap();
    let mut short = good.clone();
    short["row_max"].as_array_mut().unwrap().pop();
    let mut empty = good.clone();
    for field in ["x", "col_max", "density_x"] {
        empty[field] = serde_json::json!([]);
    }
    let out_of_range = RtwError::InvalidOption.to_string();
    for (bad, expected) in [
        (tampered("x", 1, x1 + 0.01), mismatch.to_string()),
        (tampered("density_x", 2, 0.5 * d2), mismatch.to_string()),
        (tampered("density_y", 0, 0.0), out_of_range.clone()),
        (tampered("density_y", 0, 1.5), out_of_range),
        (
            tampered("col_max", 0, -1.0),
            RtwError::NegativeImportance.to_string(),
        ),
        (
            short,
            RtwError::SizeMismatch {
                expected: 4,
                got: 3,
            }
            .to_string(),
        ),
        (empty, RtwError::EmptyMap.to_string()),
    ] {
        let e = serde_json::from_value::<WarpMaps>(bad.clone()).expect_err("tampered");
        assert!(
            e.to_string().contains(&expected),
            "{bad}: {e}, expected {expected}"
        );
    }
}

#[cfg(feature = "bytemuck")]
#[test]
fn eye_samples_are_pod() {
    use glam::Vec3;
    use shadowmap_rtw::EyeSample;
    let samples = [EyeSample {
        position: Vec3::new(1.0, 2.0, 3.0),
        normal: Vec3::Y,
        eye_distance: 7.0,
    }];
    let floats: &[f32] = bytemuck::cast_slice(&samples);
    assert_eq!(floats, &[1.0, 2.0, 3.0, 0.0, 1.0, 0.0, 7.0]);
}
