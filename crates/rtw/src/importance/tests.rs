use super::*;
use glam::Mat4;

fn identity_base() -> ShadowTransform {
    // uv = (x, y) directly: clip x = 2u - 1, clip y = 1 - 2v.
    let clip = Mat4::from_cols_array(&[
        2.0, 0.0, 0.0, 0.0, //
        0.0, -2.0, 0.0, 0.0, //
        0.0, 0.0, 1.0, 0.0, //
        -1.0, 1.0, 0.0, 1.0,
    ]);
    ShadowTransform::new(
        Mat4::IDENTITY,
        clip,
        false,
        LightDirection::Directional(Vec3::NEG_Z),
    )
}

#[test]
fn sizes_and_values_are_checked() {
    assert_eq!(ImportanceMap::new(0, 4), Err(RtwError::EmptyMap));
    assert_eq!(
        ImportanceMap::new(MAX_MAP_SIDE + 1, 1),
        Err(RtwError::MapTooLarge)
    );
    let mut m = ImportanceMap::new(4, 2).unwrap();
    assert_eq!(m.set(4, 0, 1.0), Err(RtwError::OutOfBounds));
    assert_eq!(m.set(0, 0, f32::NAN), Err(RtwError::NonFinite));
    assert_eq!(m.set(0, 0, -1.0), Err(RtwError::NegativeImportance));
    assert_eq!(
        m.copy_from_slice(&[1.0; 3]),
        Err(RtwError::SizeMismatch {
            expected: 8,
            got: 3
        })
    );
    m.set(3, 1, 2.0).unwrap();
    assert_eq!(m.get(3, 1), Some(2.0));
    assert_eq!(m.as_slice()[7], 2.0);
}

#[test]
fn backward_analysis_prefers_near_samples_and_edges() {
    let mut m = ImportanceMap::new(4, 4).unwrap();
    let base = identity_base();
    let near = EyeSample {
        position: Vec3::new(0.1, 0.1, 0.0),
        normal: Vec3::Z,
        eye_distance: 1.0,
    };
    let far = EyeSample {
        position: Vec3::new(0.9, 0.9, 0.0),
        eye_distance: 10.0,
        ..near
    };
    let outside = EyeSample {
        position: Vec3::new(2.0, 0.5, 0.0),
        ..near
    };
    let opts = ImportanceOptions::default();
    let st = m
        .accumulate_backward(&base, &[near, far, outside], None, &opts)
        .unwrap();
    assert_eq!(
        st,
        AccumulateStats {
            accepted: 2,
            skipped: 1
        }
    );
    assert!((m.get(0, 0).unwrap() - 1.0).abs() < 1e-6);
    assert!((m.get(3, 3).unwrap() - 0.1).abs() < 1e-6);
    // Edge factor.
    m.accumulate_backward(&base, &[far], Some(&[true]), &opts)
        .unwrap();
    assert!((m.get(3, 3).unwrap() - 0.4).abs() < 1e-6);
    // Grazing light raises importance.
    let graze = EyeSample {
        normal: Vec3::X,
        ..far
    };
    m.clear();
    m.accumulate_backward(&base, &[graze], None, &opts).unwrap();
    assert!((m.get(3, 3).unwrap() - 0.2).abs() < 1e-6);
    // Errors leave the map unchanged.
    let bad = EyeSample {
        eye_distance: f32::NAN,
        ..near
    };
    assert_eq!(
        m.accumulate_backward(&base, &[near, bad], None, &opts),
        Err(RtwError::NonFinite)
    );
    assert_eq!(m.get(0, 0), Some(0.0));
    assert!(matches!(
        m.accumulate_backward(&base, &[near], Some(&[]), &opts),
        Err(RtwError::SizeMismatch { .. })
    ));
}

#[test]
fn forward_analysis_lifts_texels_the_eye_sees() {
    use shadowmap_frustum::{CascadeFit, CascadeOptions, Projection, fit_cascade};
    let camera = Camera::look_to(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(1.0, 1.0, 0.1, 50.0),
    )
    .unwrap();
    let opts = CascadeOptions::default().with_fit(CascadeFit::Tight);
    let base = fit_cascade(&camera, Vec3::NEG_Y, 0.1, 50.0, &opts)
        .unwrap()
        .transform;
    // A previous map of the ground plane y = 0 where the eye sees it; empty elsewhere.
    let (dw, dh) = (32u32, 32u32);
    let mut depths = vec![1.0f32; (dw * dh) as usize];
    let seen = [Vec3::new(0.0, 0.0, -3.0), Vec3::new(0.5, 0.0, -30.0)];
    let mut texels = Vec::new();
    for p in seen {
        let s = base.project(p).unwrap();
        let (i, j) = (
            (s.uv.x * f64::from(dw)) as usize,
            (s.uv.y * f64::from(dh)) as usize,
        );
        depths[j * dw as usize + i] = s.depth as f32;
        texels.push((i, j));
    }
    // A texel inside the base map that the eye does not see.
    let hidden = Vec3::new(-20.0, 0.0, -5.0);
    let behind = base.project(hidden).unwrap();
    assert!(behind.uv.cmpge(glam::DVec2::ZERO).all() && behind.uv.cmplt(glam::DVec2::ONE).all());
    let (bi, bj) = ((behind.uv.x * 32.0) as usize, (behind.uv.y * 32.0) as usize);
    depths[bj * 32 + bi] = behind.depth as f32;

    let mut m = ImportanceMap::new(16, 16).unwrap();
    let options = ImportanceOptions::default();
    let st = m
        .accumulate_forward(&base, &base, None, &depths, dw, dh, &camera, &options)
        .unwrap();
    assert_eq!(st.accepted, 2, "{st:?}");
    assert_eq!(st.skipped, depths.len() - 2);
    let cell = |p: Vec3| {
        let s = base.project(p).unwrap();
        m.get((s.uv.x * 16.0) as u32, (s.uv.y * 16.0) as u32)
            .unwrap()
    };
    // Importance = 1 / view depth, up to the texel's extent.
    assert!((cell(seen[0]) - 1.0 / 3.0).abs() < 0.1, "{}", cell(seen[0]));
    assert!(
        (cell(seen[1]) - 1.0 / 30.0).abs() < 0.01,
        "{}",
        cell(seen[1])
    );
    assert_eq!(cell(hidden), 0.0);
    assert!(matches!(
        m.accumulate_forward(&base, &base, None, &depths[1..], dw, dh, &camera, &options),
        Err(RtwError::SizeMismatch { .. })
    ));
}

/// A plane 10 units from the camera, 100 pixels per radian, lit along its normal: a
/// pixel spans 0.1 units of the identity base, so each axis needs 10 pixels per unit;
/// seen 30 degrees off the normal (turned about `v`), a pixel spans `0.1 / cos 30°`
/// along `u`, which needs `10 cos 30°`; a surface the light grazes is measured on
/// the bisector of the eye and light directions (here the facing plane's).
#[test]
fn oracle_needs_are_the_inverse_jacobian() {
    let base = identity_base();
    let centre = Vec3::new(0.5, 0.5, 0.0);
    let needs_from = |direction: Vec3, normal: Vec3| {
        let camera = shadowmap_frustum::Camera::look_to(
            centre - direction * 10.0,
            direction,
            Vec3::Y,
            shadowmap_frustum::Projection::perspective(1.0, 1.0, 0.1, 100.0),
        )
        .unwrap();
        let sample = EyeSample {
            position: centre,
            normal,
            eye_distance: 10.0,
        };
        let mut needs = Vec::new();
        let skipped = oracle_needs(&base, &camera, 100.0, &[sample], |_, n| needs.push(n)).unwrap();
        (skipped, needs.first().copied())
    };
    let (_, facing) = needs_from(Vec3::NEG_Z, Vec3::Z);
    let facing = facing.unwrap();
    assert!((facing.uv - DVec2::splat(0.5)).length() < 1e-9);
    for q in [facing.u, facing.v, facing.isotropic] {
        assert!((q - 10.0).abs() < 1e-6, "{facing:?}");
    }
    let a = 30f32.to_radians();
    let (_, slanted) = needs_from(Vec3::new(-a.sin(), 0.0, -a.cos()), Vec3::Z);
    let slanted = slanted.unwrap();
    let expected_u = 10.0 * f64::from(a.cos());
    assert!((slanted.u - expected_u).abs() < 1e-4, "{slanted:?}");
    assert!((slanted.v - 10.0).abs() < 1e-4 && (slanted.isotropic - 10.0).abs() < 1e-4);
    let (skipped, grazed) = needs_from(Vec3::NEG_Z, Vec3::X);
    assert_eq!((skipped, grazed), (0, Some(facing)));
    let camera = facing_the_base();
    assert!(matches!(
        oracle_needs(&base, &camera, 0.0, &[], |_, _| {}),
        Err(RtwError::InvalidOption)
    ));
}

/// A camera 10 units in front of the identity base's unit square, looking at it.
fn facing_the_base() -> shadowmap_frustum::Camera {
    shadowmap_frustum::Camera::look_to(
        Vec3::new(0.5, 0.5, 10.0),
        Vec3::NEG_Z,
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.0, 0.1, 100.0),
    )
    .unwrap()
}

/// The kept samples' needs are `oracle_needs`' for them, at their own indices, kept
/// by a predicate or picked by the caller; a sample not kept is not measured, not
/// counted and not checked.
#[test]
fn oracle_needs_where_measures_only_the_kept_samples() {
    let base = identity_base();
    let camera = facing_the_base();
    let sample = |x: f32| EyeSample {
        position: Vec3::new(x, 0.5, 0.0),
        normal: Vec3::Z,
        eye_distance: 10.0,
    };
    let mut samples: Vec<EyeSample> = (0..8).map(|i| sample(0.3 + 0.05 * i as f32)).collect();
    let mut all = Vec::new();
    oracle_needs(&base, &camera, 100.0, &samples, |i, n| all.push((i, n))).unwrap();
    assert_eq!(all.len(), 8);
    samples[3].position.x = f32::NAN;
    let mut even = Vec::new();
    let skipped = oracle_needs_where(
        &base,
        &camera,
        100.0,
        &samples,
        |i, _| i % 2 == 0,
        |i, n| even.push((i, n)),
    )
    .unwrap();
    assert_eq!(skipped, 0);
    let expected: Vec<_> = all.iter().copied().filter(|(i, _)| i % 2 == 0).collect();
    assert_eq!(even, expected);
    // The same subset picked by the caller: the same needs at the given indices.
    let mut picked = Vec::new();
    let evens = samples.iter().enumerate().step_by(2);
    oracle_needs_of(&base, &camera, 100.0, evens, |i, n| picked.push((i, n))).unwrap();
    assert_eq!(picked, expected);
    // Kept, the non-finite sample is an error; unchecked by `oracle_needs` it is too.
    let keep_all = oracle_needs_where(&base, &camera, 100.0, &samples, |_, _| true, |_, _| {});
    assert!(matches!(keep_all, Err(RtwError::NonFinite)));
    assert!(matches!(
        oracle_needs(&base, &camera, 100.0, &samples, |_, _| {}),
        Err(RtwError::NonFinite)
    ));
}

#[test]
fn backward_importance_over_a_perspective_base_grows_with_the_light_depth() {
    // A spot at the origin looking down -Z, 90 degrees wide: the base texel at light
    // depth z spans z times the world extent it spans at depth 1, so a sample there
    // needs z times the texels per unit of base uv.
    let light = Mat4::IDENTITY;
    let clip = shadowmap_frustum::projection::perspective(
        core::f64::consts::FRAC_PI_2,
        1.0,
        0.5,
        100.0,
        false,
    )
    .as_mat4();
    let base = ShadowTransform::new(light, clip, false, LightDirection::Position(Vec3::ZERO));
    let mut m = ImportanceMap::new(8, 8).unwrap();
    let sample = |position: Vec3| EyeSample {
        position,
        normal: Vec3::ZERO,
        eye_distance: 5.0,
    };
    // Same eye distance, light depths 2 and 20, in different cells.
    let samples = [
        sample(Vec3::new(-1.5, 0.0, -2.0)),
        sample(Vec3::new(15.0, 0.0, -20.0)),
    ];
    let stats = m
        .accumulate_backward(&base, &samples, None, &ImportanceOptions::default())
        .unwrap();
    assert_eq!(stats.accepted, 2);
    let mut cells: Vec<f32> = m.as_slice().iter().copied().filter(|c| *c > 0.0).collect();
    cells.sort_by(f32::total_cmp);
    assert_eq!(cells.len(), 2);
    assert!((cells[0] - 2.0 / 5.0).abs() < 1e-5, "{cells:?}");
    assert!((cells[1] - 20.0 / 5.0).abs() < 1e-4, "{cells:?}");
    // An orthographic base (w = 1) keeps the plain distance term.
    let mut flat = ImportanceMap::new(4, 4).unwrap();
    flat.accumulate_backward(
        &identity_base(),
        &[sample(Vec3::new(0.5, 0.5, 0.0))],
        None,
        &ImportanceOptions::default(),
    )
    .unwrap();
    assert_eq!(flat.get(2, 2), Some(1.0 / 5.0));
}

#[test]
fn pixel_steps_span_depth_over_focal_length_and_follow_the_surface() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.0, 0.1, 100.0),
    )
    .unwrap();
    let steps = PixelSteps::new(&camera);
    // A wall facing the eye 10 m away: one pixel at 500 px/rad is 2 cm either way.
    let p = DVec3::new(0.0, 0.0, -10.0);
    let (dx, dy) = steps.at(p, DVec3::Z, 500.0).unwrap();
    assert!((dx - DVec3::new(0.02, 0.0, 0.0)).length() < 1e-12, "{dx}");
    assert!((dy - DVec3::new(0.0, 0.02, 0.0)).length() < 1e-12, "{dy}");
    // The floor seen at a slant: the vertical step stretches along the ray.
    let q = DVec3::new(0.0, -1.0, -10.0);
    let (_, dy) = steps.at(q, DVec3::Y, 500.0).unwrap();
    assert!(dy.y.abs() < 1e-12 && dy.length() > 0.1, "{dy}");
    // Behind the eye, at it, or edge-on: none.
    assert_eq!(steps.at(DVec3::new(0.0, 0.0, 5.0), DVec3::Z, 500.0), None);
    assert_eq!(steps.at(DVec3::ZERO, DVec3::Z, 500.0), None);
    assert_eq!(steps.at(p, DVec3::X, 500.0), None);
}
