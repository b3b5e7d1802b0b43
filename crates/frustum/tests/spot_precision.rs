//! The spot fit's window against `f32` rounding: a window finer than `f32` resolves
//! is widened (both ends of a light ray then land on one texel), one that `f32`
//! resolves is kept as fitted.

use glam::{DVec3, Mat4, Vec3, Vec4};
use shadowmap_frustum::{
    Aabb, Camera, ConvexBody, FrustumError, Light, Projection, SceneBounds, ShadowTransform,
    fit_spot,
};
use shadowmap_testgen::frustum::ray_gap;

/// The body's vertices and the midpoints of every pair of them.
fn region_points(body: &ConvexBody) -> Vec<DVec3> {
    let v = body.vertices();
    let mut points: Vec<DVec3> = v.iter().map(|p| p.as_dvec3()).collect();
    for (i, a) in v.iter().enumerate() {
        points.extend(v[i + 1..].iter().map(|b| ((*a + *b) * 0.5).as_dvec3()));
    }
    points
}

/// Every light ray from `light` through a point of `body` (its vertices and their
/// midpoints) has its two ends within a tenth of a `1024²` texel in `map`, and at
/// least one such ray is in the map.
fn assert_rays_on_one_texel(map: &ShadowTransform, light: Vec3, body: &ConvexBody) {
    let mut checked = 0;
    for p in region_points(body) {
        if let Some(gap) = ray_gap(map, light.as_dvec3(), p) {
            assert!(gap <= 1e-4, "{p}: the ray's ends {gap} apart");
            checked += 1;
        }
    }
    assert!(checked > 0);
}

/// A spot 0.05 from the origin lighting, from its own position along the view, a
/// receiver slab 1.7e-7 thick and 3 mm away: the receivers' window (5.7e-5 tall,
/// 1.7e-7 at them, 44 f32 steps of the coordinates) put the two ends of a ray
/// 0.37 texels of a 1024² map apart.
#[test]
fn a_window_finer_than_f32_resolves_is_widened() {
    let position = Vec3::new(-0.045266125, 0.026110286, -0.023142785);
    let light = Light::Spot {
        position,
        direction: Vec3::new(-1.1336593e-5, 6.613013e-6, 1.0),
        half_angle: 0.05,
        range: 0.01,
    };
    let camera = Camera {
        world_from_view: Mat4::from_cols(
            Vec4::new(0.0, 1.0, -6.8421896e-6, 0.0),
            Vec4::new(1.0, 8.236331e-11, 1.2037566e-5, 0.0),
            Vec4::new(1.2037566e-5, -6.8421896e-6, -1.0, 0.0),
            position.extend(1.0),
        ),
        projection: Projection::perspective(0.55297774, 0.0100592915, 0.0010011252, 0.0029421665),
        reversed_z: false,
    };
    let receivers = Aabb::new(
        Vec3::new(-0.04610102, 0.026101908, -0.022141663),
        Vec3::new(-0.044431303, 0.026102075, -0.020200608),
    );
    let frustum = camera.frustum().unwrap();
    let scene = SceneBounds::new(receivers, receivers);
    let spot = fit_spot(&light, &frustum, Some(&scene), false).unwrap();

    let body = ConvexBody::from_frustum_aabb(&frustum, &receivers).unwrap();
    // The slab's own window is 5.7e-5 tall: widened.
    let [_, _, b, t] = spot.tangents;
    assert!(t - b > 1e-3, "{b} {t}");
    assert_rays_on_one_texel(&spot.transform, position, &body);
}

/// A street-lamp spot over a ground plane: the window `f32` resolves is the
/// receivers' own, each side the smallest and largest tangent of the visible region.
#[test]
fn a_window_f32_resolves_is_kept() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.3, -0.2, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 1.6, 0.1, 200.0),
    )
    .unwrap();
    let position = Vec3::new(10.0, 17.0, -5.0);
    let light = Light::Spot {
        position,
        direction: Vec3::new(-0.4, -1.0, -0.6).normalize(),
        half_angle: 0.9,
        range: 200.0,
    };
    let ground = Aabb::new(Vec3::new(-60.0, -1.0, -80.0), Vec3::new(60.0, 0.0, 10.0));
    let frustum = camera.frustum().unwrap();
    let spot = fit_spot(
        &light,
        &frustum,
        Some(&SceneBounds::new(ground, ground)),
        false,
    )
    .unwrap();
    let body = ConvexBody::from_frustum_aabb(&frustum, &ground).unwrap();
    let light_from_world = spot.transform.light_from_world.as_dmat4();
    let cone = f64::from(0.9f32.tan());
    let mut expected = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for v in body.vertices() {
        let q = light_from_world.transform_point3(v.as_dvec3());
        let (x, y) = (q.x / -q.z, q.y / -q.z);
        expected = [
            expected[0].min(x),
            expected[1].max(x),
            expected[2].min(y),
            expected[3].max(y),
        ];
    }
    let expected = expected.map(|t| t.clamp(-cone, cone));
    for (got, want) in spot.tangents.iter().zip(expected) {
        assert!(
            (f64::from(*got) - want).abs() <= 1e-5 * want.abs().max(1.0),
            "{got} {want}"
        );
    }
    assert!(
        expected.iter().any(|t| t.abs() < cone),
        "the window is the cone's"
    );
}

/// Found by fuzzing the spot warps: a spot 140 from the origin seeing a thin
/// receiver slab 84° off its axis. The window's side `(2 x - (l + r) z) / (r - l)`
/// grows with its tangents (9.4 here) over its width, so a window 0.2 wide at the
/// nearest receiver (1/500 of the scene's reach) put a ray's ends 1.35e-4 apart.
#[test]
fn an_off_axis_window_is_widened_by_its_tangents() {
    let position = Vec3::new(-99.995674, 74.21842, -99.995674);
    let light = Light::Spot {
        position,
        direction: Vec3::new(0.105249815, 3.9262826e-8, -0.9944458),
        half_angle: 1.5,
        range: 399.91803,
    };
    let camera = Camera {
        world_from_view: Mat4::from_cols(
            Vec4::new(0.0, -1.0, 0.0, 0.0),
            Vec4::new(1.0, 0.0, 0.0, 0.0),
            Vec4::Z,
            Vec4::W,
        ),
        projection: Projection::InfinitePerspective {
            fov_y: 0.023713738,
            aspect: 0.5055542,
            near: 0.0010000006,
            shadow_distance: 99.995674,
        },
        reversed_z: false,
    };
    let receivers = Aabb::new(
        Vec3::new(-1.1856911, 0.5994311, -99.995674),
        Vec3::new(1.1856911, 0.61141974, -0.0010000006),
    );
    let frustum = camera.frustum().unwrap();
    let spot = fit_spot(
        &light,
        &frustum,
        Some(&SceneBounds::new(receivers, receivers)),
        false,
    )
    .unwrap();
    let body = ConvexBody::from_frustum_aabb(&frustum, &receivers).unwrap();
    assert_rays_on_one_texel(&spot.transform, position, &body);
}

/// A spot of half angle 0.01, 5,000 from the origin, 0.1 from its nearest visible
/// receiver: even the whole cone is 0.002 wide there, a texel of a `1024²` map a
/// tenth of an `f32` step of the scene's coordinates (a ray's ends far more than a
/// texel apart): refused. The same spot 1,000
/// from its receivers resolves them.
#[test]
fn a_cone_too_narrow_for_f32_at_its_nearest_receiver_is_refused() {
    let position = Vec3::new(5000.0, 0.0, 0.0);
    let fit_at = |distance: f32| {
        let light = Light::Spot {
            position,
            direction: Vec3::NEG_Z,
            half_angle: 0.01,
            range: 2.0 * distance + 10.0,
        };
        let camera = Camera::look_to(
            position,
            Vec3::NEG_Z,
            Vec3::Y,
            Projection::perspective(0.5, 1.0, 0.05, 2.0 * distance + 10.0),
        )
        .unwrap();
        let receivers = Aabb::new(
            position + Vec3::new(-1.0, -1.0, -2.0 * distance),
            position + Vec3::new(1.0, 1.0, -distance),
        );
        let scene = SceneBounds::new(receivers, receivers);
        fit_spot(&light, &camera.frustum().unwrap(), Some(&scene), false)
    };
    assert_eq!(fit_at(0.1), Err(FrustumError::DegenerateFrustum));
    let far = fit_at(1000.0).unwrap();
    assert!(far.receiver_depth.0 >= 999.0);
}
