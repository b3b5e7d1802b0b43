//! The data features: every public options and result type survives a `serde_json`
//! round trip unchanged (values from the shared generators), bad payloads give an
//! error, and the `mint` and `bytemuck` conversions keep every component.
#![cfg(feature = "serde")]

use core::fmt::Debug;

use glam::{Mat4, Vec3};
use proptest::prelude::*;
use shadowmap_frustum::{
    Aabb, Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, DepthBounds, FrustumError,
    Light, PredictOptions, Projection, SceneBounds, ShadowMapping, Sphere, SplitScheme,
    TechniqueSelector, fit_spot, predict_error,
};
use shadowmap_testgen::serde_check::{rejects, rejects_with, round_trip};
use shadowmap_testgen::{
    GenResult, aabb, arbitrary::Unstructured, camera, frustum as cases, in_range, light_direction,
    strategy,
};

/// Whether every float in `value` is finite (JSON has no NaN or infinity): raw
/// generator inputs are round-tripped only then.
fn all_finite(value: &impl Debug) -> bool {
    let text = format!("{value:?}");
    !(text.contains("NaN") || text.contains("inf"))
}

#[derive(Clone, Debug)]
struct SceneCase {
    camera: Camera,
    light: Vec3,
    scene: SceneBounds,
    lambda: f32,
    count: usize,
    overlap: f32,
}

fn scene_case(u: &mut Unstructured<'_>) -> GenResult<SceneCase> {
    let camera = camera(u)?;
    let receivers = aabb(u, 1e3)?;
    Ok(SceneCase {
        light: light_direction(u, &camera)?,
        scene: SceneBounds::new(receivers, receivers.union(&aabb(u, 1e3)?)),
        camera,
        lambda: in_range(u, 0.0, 1.0)?,
        count: usize::from(u.int_in_range(1u8..=8)?),
        overlap: in_range(u, 0.0, 0.9)?,
    })
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// Inputs (camera, projection, light, boxes, frustum, planes) and the cascade
    /// results fitted from them.
    #[test]
    fn inputs_and_cascades_round_trip(case in strategy(scene_case)) {
        round_trip(&case.camera);
        round_trip(&case.camera.projection);
        round_trip(&Light::Directional { direction: case.light });
        round_trip(&case.scene);
        round_trip(&case.scene.receivers);
        let (centre, size) = (case.scene.receivers.center(), case.scene.receivers.size());
        round_trip(&Sphere::new(centre, 0.5 * size.length()));
        let lamp = Light::Point { position: centre, range: 1.0 + size.length() };
        if lamp.validate().is_ok() {
            round_trip(&lamp);
        }
        if let Ok(frustum) = case.camera.frustum() {
            round_trip(&frustum);
            for plane in frustum.planes {
                round_trip(&plane);
            }
        }
        let scheme = SplitScheme::Practical { lambda: case.lambda };
        round_trip(&scheme);
        let Ok((near, far)) = case.camera.depth_range() else {
            return Ok(());
        };
        let Ok(splits) = CascadeSplits::new(&scheme, case.count, near, far.min(near * 1e4))
            .and_then(|s| s.with_overlap(case.overlap))
        else {
            return Ok(());
        };
        round_trip(&splits);
        round_trip(&SplitScheme::Custom(splits.depths()[1..case.count].iter().copied().collect()));
        let options = CascadeOptions::default()
            .with_fit(if case.count % 2 == 0 { CascadeFit::Tight } else { CascadeFit::Stable })
            .with_scene(Some(case.scene));
        round_trip(&options);
        let Ok(set) = CascadeSet::fit(&case.camera, case.light, &splits, &options) else {
            return Ok(());
        };
        round_trip(&set);
        for cascade in &set.cascades {
            round_trip(cascade);
            round_trip(&cascade.transform);
        }
        if let Some(blend) = set.select_by_depth(centre) {
            round_trip(&blend);
            let transform = set.cascades[blend.index].transform;
            round_trip(&transform.light);
            if let Some(sample) = transform.map_point(centre.as_dvec3()) {
                round_trip(&sample);
            }
        }
    }

    /// Cascade fits over the generators' nearly valid requests, with their options.
    #[test]
    fn cascade_requests_round_trip(case in strategy(cases::cascade_case_raw)) {
        if all_finite(&case.options) {
            round_trip(&case.options);
        }
        if all_finite(&case.scheme) {
            round_trip(&case.scheme);
        }
        let Ok((near, far)) = case.camera.depth_range() else {
            return Ok(());
        };
        if let Ok(splits) = CascadeSplits::new(&case.scheme, case.count, near, far) {
            round_trip(&splits);
            if let Ok(set) = CascadeSet::fit(&case.camera, case.light, &splits, &case.options) {
                round_trip(&set);
            }
        }
    }

    /// Spot fits and the lights they come from.
    #[test]
    fn spot_fits_round_trip(case in strategy(cases::spot_case_raw)) {
        if case.light.validate().is_ok() {
            round_trip(&case.light);
        }
        let Ok(frustum) = case.camera.frustum() else {
            return Ok(());
        };
        if let Ok(spot) = fit_spot(&case.light, &frustum, case.scene.as_ref(), case.reversed_z) {
            round_trip(&spot);
        }
    }

    /// Measured depth bounds and the splits over them.
    #[test]
    fn depth_bounds_round_trip(case in strategy(cases::depth_bounds_case_raw)) {
        if all_finite(&case.bounds) {
            round_trip(&case.bounds);
        }
        let scheme = SplitScheme::Logarithmic;
        if let Ok(splits) = CascadeSplits::from_depth_bounds(&scheme, case.count, &case.camera, case.bounds) {
            round_trip(&splits);
        }
    }
}

#[test]
fn predictions_round_trip() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap();
    let receivers = Aabb::new(Vec3::new(-50.0, -1.0, -100.0), Vec3::new(50.0, 0.0, 0.0));
    let splits = CascadeSplits::new(&SplitScheme::Logarithmic, 1, 0.5, 100.0).unwrap();
    let set = CascadeSet::fit(&camera, Vec3::NEG_Y, &splits, &CascadeOptions::default()).unwrap();
    let options = PredictOptions::new().with_grid(8, 4).with_percentile(0.9);
    round_trip(&options);
    round_trip(&options.with_light_direction(Vec3::new(0.3, -1.0, 0.2)));
    round_trip(&options.with_light_position(Vec3::new(3.0, 10.0, -2.0)));
    let predicted = predict_error(
        &camera,
        &receivers,
        &set.cascades[0].transform,
        1024,
        &options,
    )
    .unwrap();
    let predicted = predicted.expect("the receivers are in view");
    round_trip(&predicted);
    let mut selector = TechniqueSelector::new().with_switch_margin(0.1);
    selector.choose(&[Some(2.0), Some(1.0)]);
    round_trip(&selector);
    round_trip(&DepthBounds { min: 1.0, max: 2.0 });
}

#[test]
fn missing_option_fields_take_their_defaults() {
    let options: PredictOptions = serde_json::from_str(r#"{"grid_rows": 3}"#).unwrap();
    assert_eq!(options, PredictOptions::new().with_grid(16, 3));
    let options: CascadeOptions = serde_json::from_str(r#"{"resolution": 512}"#).unwrap();
    assert_eq!(options, CascadeOptions::default().with_resolution(512));
}

#[test]
fn bad_payloads_are_errors() {
    let identity = serde_json::to_string(&Mat4::IDENTITY).unwrap();
    let camera = |projection: &str| {
        format!(r#"{{"world_from_view":{identity},"projection":{projection},"reversed_z":false}}"#)
    };
    // A valid camera reads; a zero field of view, near beyond far and a singular
    // pose do not.
    let good = r#"{"Perspective":{"fov_y":1.0,"aspect":1.0,"near":0.1,"far":10.0}}"#;
    serde_json::from_str::<Camera>(&camera(good)).unwrap();
    let zero_fov = r#"{"Perspective":{"fov_y":0.0,"aspect":1.0,"near":0.1,"far":10.0}}"#;
    rejects_with::<Camera>(&camera(zero_fov), FrustumError::InvalidFov);
    let inverted = r#"{"Perspective":{"fov_y":1.0,"aspect":1.0,"near":10.0,"far":0.1}}"#;
    rejects_with::<Camera>(&camera(inverted), "invalid depth range");
    let zero = serde_json::to_string(&Mat4::ZERO).unwrap();
    rejects::<Camera>(&format!(
        r#"{{"world_from_view":{zero},"projection":{good},"reversed_z":false}}"#
    ));
    // Lights: a zero direction, a spot wider than a hemisphere, a negative range.
    let sun = r#"{"Directional":{"direction":[0.0,-1.0,0.0]}}"#;
    serde_json::from_str::<Light>(sun).unwrap();
    let no_sun = r#"{"Directional":{"direction":[0.0,0.0,0.0]}}"#;
    rejects_with::<Light>(no_sun, FrustumError::ZeroDirection);
    let spot = |half_angle: f32| {
        format!(
            r#"{{"Spot":{{"position":[0,0,0],"direction":[0,-1,0],"half_angle":{half_angle},"range":10}}}}"#
        )
    };
    serde_json::from_str::<Light>(&spot(1.0)).unwrap();
    rejects_with::<Light>(&spot(2.0), FrustumError::InvalidLight);
    let point = r#"{"Point":{"position":[0,0,0],"range":-1.0}}"#;
    rejects_with::<Light>(point, FrustumError::InvalidLight);
    // Splits: decreasing or too few depths, a non-positive near, an overlap of 1,
    // more depths than cascades allowed.
    serde_json::from_str::<CascadeSplits>(r#"{"depths":[0.1,1.0,10.0],"overlap":0.2}"#).unwrap();
    let decreasing = r#"{"depths":[0.1,10.0,1.0],"overlap":0.0}"#;
    rejects_with::<CascadeSplits>(decreasing, FrustumError::InvalidCustomSplits);
    rejects_with::<CascadeSplits>(r#"{"depths":[0.1],"overlap":0.0}"#, "at least two");
    let at_zero = r#"{"depths":[0.0,1.0],"overlap":0.0}"#;
    rejects_with::<CascadeSplits>(at_zero, "invalid depth range");
    let full_band = r#"{"depths":[0.1,1.0],"overlap":1.0}"#;
    rejects_with::<CascadeSplits>(full_band, FrustumError::InvalidSplitParameter);
    rejects::<CascadeSplits>(r#"{"depths":[1,2,3,4,5,6,7,8,9,10],"overlap":0.0}"#);
    // Prediction options out of range.
    let bad_percentile = r#"{"percentile":0.0}"#;
    rejects_with::<PredictOptions>(bad_percentile, FrustumError::InvalidResolution);
    rejects_with::<PredictOptions>(r#"{"grid_columns":0}"#, FrustumError::InvalidResolution);
    // Wrong shapes.
    rejects::<Aabb>(r#"{"min":[0,0],"max":[1,1,1]}"#);
    rejects::<CascadeFit>(r#""Loose""#);
}

#[cfg(feature = "mint")]
#[test]
fn mint_conversions_keep_every_component() {
    use shadowmap_frustum::Plane;
    let aabb = Aabb::new(Vec3::new(-1.0, -2.0, -3.0), Vec3::new(4.0, 5.0, 6.0));
    let corners: [mint::Point3<f32>; 2] = aabb.into();
    assert_eq!((corners[1].x, corners[1].y, corners[1].z), (4.0, 5.0, 6.0));
    assert_eq!(Aabb::from(corners), aabb);
    let plane = Plane::new(Vec3::new(0.0, 0.6, 0.8), -2.5);
    let v: mint::Vector4<f32> = plane.into();
    assert_eq!((v.y, v.z, v.w), (0.6, 0.8, -2.5));
    assert_eq!(Plane::from(v), plane);
    let sphere = Sphere::new(Vec3::new(1.0, 2.0, 3.0), 4.0);
    let v: mint::Vector4<f32> = sphere.into();
    assert_eq!((v.x, v.w), (1.0, 4.0));
    assert_eq!(Sphere::from(v), sphere);
    // glam's own conversions reach the matrices.
    let m = Mat4::from_cols_array(&core::array::from_fn(|i| i as f32));
    let cm: mint::ColumnMatrix4<f32> = m.into();
    assert_eq!((cm.y.x, cm.w.w), (4.0, 15.0));
}

#[cfg(feature = "bytemuck")]
#[test]
fn plain_data_is_pod() {
    use shadowmap_frustum::Plane;
    let planes = [Plane::new(Vec3::X, 1.0), Plane::new(Vec3::Y, -2.0)];
    let floats: &[f32] = bytemuck::cast_slice(&planes);
    assert_eq!(floats, &[1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, -2.0]);
    let sphere = Sphere::new(Vec3::new(1.0, 2.0, 3.0), 4.0);
    assert_eq!(
        bytemuck::cast::<Sphere, [f32; 4]>(sphere),
        [1.0, 2.0, 3.0, 4.0]
    );
    let aabb = Aabb::new(Vec3::ZERO, Vec3::ONE);
    assert_eq!(bytemuck::bytes_of(&aabb).len(), 24);
    let bounds = DepthBounds { min: 1.0, max: 2.0 };
    assert_eq!(bytemuck::cast::<DepthBounds, [f32; 2]>(bounds), [1.0, 2.0]);
}
