//! Example-based tests of `shadowmap-frustum`: golden values computed by hand, every
//! error path, and the behaviour of selection, blending and the spot fit.

use approx::assert_relative_eq;
use arrayvec::ArrayVec;
use glam::{Mat4, Vec3};
use shadowmap_frustum::{
    Aabb, Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, ConvexBody, DepthBounds,
    FrustumError, Light, Projection, SceneBounds, ShadowMapping, SplitScheme, fit_cascade,
    fit_spot, projection,
};

fn camera() -> Camera {
    Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 1.0, 1000.0),
    )
    .unwrap()
}

#[test]
fn practical_split_golden_values() {
    // n = 1, f = 1000, m = 4, lambda = 0.5, by hand:
    //   log:     C_i = 1000^(i/4)       = 1, 5.623413, 31.622777, 177.827941, 1000
    //   uniform: C_i = 1 + 999 * i / 4  = 1, 250.75,   500.5,     750.25,     1000
    //   mean:                             1, 128.186707, 266.061389, 464.038971, 1000
    let s = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 1.0, 1000.0).unwrap();
    let expected = [1.0, 128.186707, 266.061389, 464.038971, 1000.0];
    for (got, want) in s.depths().iter().zip(expected) {
        assert_relative_eq!(*got, want, max_relative = 1e-6);
    }
}

#[test]
fn blend_band_and_selection() {
    let s = CascadeSplits::new(&SplitScheme::Uniform, 2, 10.0, 30.0)
        .unwrap()
        .with_overlap(0.25)
        .unwrap();
    // Cascade 0 is [10, 20]; its band is the last quarter, [17.5, 20].
    assert_eq!(s.band_width(0), 2.5);
    assert_eq!(s.band_width(1), 0.0);
    assert_eq!(s.cascade_range(1), Some((17.5, 30.0)));
    let at = |d| s.select(d).unwrap();
    assert_eq!((at(12.0).index, at(12.0).next_weight), (0, 0.0));
    assert_eq!(at(18.75).index, 0);
    assert_relative_eq!(at(18.75).next_weight, 0.5);
    assert_eq!((at(25.0).index, at(25.0).next_weight), (1, 0.0));
    assert_eq!(
        at(5.0).index,
        0,
        "depths before near select the first cascade"
    );
    assert_eq!(s.select(31.0), None);
    assert_eq!(s.select(f32::NAN), None);
}

#[test]
fn split_errors() {
    let p = SplitScheme::Practical { lambda: 0.5 };
    assert_eq!(
        CascadeSplits::new(&p, 0, 1.0, 10.0),
        Err(FrustumError::InvalidCascadeCount)
    );
    assert_eq!(
        CascadeSplits::new(&p, 9, 1.0, 10.0),
        Err(FrustumError::InvalidCascadeCount)
    );
    assert_eq!(
        CascadeSplits::new(&p, 4, f32::NAN, 10.0),
        Err(FrustumError::NonFinite)
    );
    assert!(matches!(
        CascadeSplits::new(&p, 4, 0.0, 10.0),
        Err(FrustumError::InvalidDepthRange { .. })
    ));
    assert!(matches!(
        CascadeSplits::new(&p, 4, 10.0, 10.0),
        Err(FrustumError::InvalidDepthRange { .. })
    ));
    let next = f32::from_bits(10f32.to_bits() + 2);
    assert!(matches!(
        CascadeSplits::new(&p, 4, 10.0, next),
        Err(FrustumError::InvalidDepthRange { .. })
    ));
    assert_eq!(
        CascadeSplits::new(&SplitScheme::Practical { lambda: 1.5 }, 4, 1.0, 10.0),
        Err(FrustumError::InvalidSplitParameter)
    );
    let custom: ArrayVec<f32, 7> = [3.0, 2.0].into_iter().collect();
    assert_eq!(
        CascadeSplits::new(&SplitScheme::Custom(custom.clone()), 3, 1.0, 10.0),
        Err(FrustumError::InvalidCustomSplits)
    );
    assert_eq!(
        CascadeSplits::new(&SplitScheme::Custom(custom), 2, 1.0, 10.0),
        Err(FrustumError::InvalidCascadeCount)
    );
    let ok: ArrayVec<f32, 7> = [2.0, 5.0].into_iter().collect();
    assert_eq!(
        CascadeSplits::new(&SplitScheme::Custom(ok), 3, 1.0, 10.0)
            .unwrap()
            .depths(),
        &[1.0, 2.0, 5.0, 10.0]
    );
    let s = CascadeSplits::new(&p, 2, 1.0, 10.0).unwrap();
    assert_eq!(
        s.clone().with_overlap(1.0),
        Err(FrustumError::InvalidSplitParameter)
    );
    assert_eq!(
        s.with_overlap(-0.1),
        Err(FrustumError::InvalidSplitParameter)
    );
}

#[test]
fn camera_errors() {
    let p = Projection::perspective(1.0, 1.0, 0.1, 10.0);
    let look = |eye, fwd, up, proj| Camera::look_to(eye, fwd, up, proj).map(|_| ());
    assert_eq!(
        look(Vec3::NAN, Vec3::NEG_Z, Vec3::Y, p),
        Err(FrustumError::NonFinite)
    );
    assert_eq!(
        look(Vec3::ZERO, Vec3::ZERO, Vec3::Y, p),
        Err(FrustumError::ZeroDirection)
    );
    assert_eq!(
        look(Vec3::ZERO, Vec3::Y, Vec3::Y, p),
        Err(FrustumError::UpParallelToView)
    );
    for fov in [0.0, -1.0, std::f32::consts::PI, 4.0] {
        assert_eq!(
            look(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                Projection::perspective(fov, 1.0, 0.1, 10.0)
            ),
            Err(FrustumError::InvalidFov)
        );
    }
    assert_eq!(
        look(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            Projection::perspective(1.0, 0.0, 0.1, 10.0)
        ),
        Err(FrustumError::InvalidAspect)
    );
    for (n, f) in [(0.0, 10.0), (-1.0, 10.0), (10.0, 10.0), (10.0, 1.0)] {
        assert!(matches!(
            look(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                Projection::perspective(1.0, 1.0, n, f)
            ),
            Err(FrustumError::InvalidDepthRange { .. })
        ));
    }
    let singular = Projection::Custom {
        clip_from_view: Mat4::ZERO,
        shadow_distance: 10.0,
    };
    assert_eq!(
        look(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, singular),
        Err(FrustumError::InvalidProjection)
    );
    // A projection looking down +Z is refused.
    let backwards = Projection::Custom {
        clip_from_view: projection::perspective(1.0, 1.0, 0.1, 10.0, false).as_mat4()
            * Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0)),
        shadow_distance: 10.0,
    };
    // Its near plane unprojects behind the eye.
    assert!(matches!(
        look(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, backwards),
        Err(FrustumError::InvalidDepthRange { near, .. }) if near < 0.0
    ));
    // A tiny frustum far from the origin has no volume in f32.
    let tiny = Projection::perspective(1e-3, 1.0, 1e-4, 1.0001e-4);
    assert_eq!(
        look(Vec3::splat(1e6), Vec3::NEG_Z, Vec3::Y, tiny),
        Err(FrustumError::DegenerateFrustum)
    );
    // Slices outside the range.
    let cam = camera();
    assert!(matches!(
        cam.slice(0.5, 10.0),
        Err(FrustumError::InvalidDepthRange { .. })
    ));
    assert!(matches!(
        cam.slice(10.0, 5.0),
        Err(FrustumError::InvalidDepthRange { .. })
    ));
    assert!(matches!(
        cam.slice(10.0, 2000.0),
        Err(FrustumError::InvalidDepthRange { .. })
    ));
}

#[test]
fn custom_and_reversed_projections_agree_with_the_builtin_one() {
    let cam = camera();
    for reversed in [false, true] {
        let cam = cam.with_reversed_z(reversed);
        let custom = Camera {
            projection: Projection::Custom {
                clip_from_view: cam.clip_from_view().unwrap(),
                shadow_distance: 1000.0,
            },
            ..cam
        };
        let (a, b) = (cam.frustum().unwrap(), custom.frustum().unwrap());
        for (p, q) in a.corners.iter().zip(b.corners) {
            assert!((*p - q).length() < 1e-3 * p.length().max(1.0), "{p} vs {q}");
        }
        // Clip depth: 0 at near and 1 at far, or the reverse.
        let m = cam.clip_from_world().unwrap();
        let near = m.project_point3(cam.eye() + Vec3::NEG_Z * 1.0).z;
        let far = m.project_point3(cam.eye() + Vec3::NEG_Z * 1000.0).z;
        let (want_near, want_far) = if reversed { (1.0, 0.0) } else { (0.0, 1.0) };
        assert_relative_eq!(near, want_near, epsilon = 1e-5);
        assert_relative_eq!(far, want_far, epsilon = 1e-4);
    }
    // An infinite reversed projection matches the finite one up to the shadow distance.
    let inf = Camera {
        projection: Projection::InfinitePerspective {
            fov_y: 60f32.to_radians(),
            aspect: 16.0 / 9.0,
            near: 1.0,
            shadow_distance: 1000.0,
        },
        ..cam
    };
    assert_eq!(
        inf.frustum().unwrap().corners,
        cam.frustum().unwrap().corners
    );
    let m = inf.with_reversed_z(true).clip_from_world().unwrap();
    assert_relative_eq!(
        m.project_point3(cam.eye() + Vec3::NEG_Z).z,
        1.0,
        epsilon = 1e-6
    );
}

#[test]
fn frustum_corner_order_and_planes() {
    let f = camera().frustum().unwrap();
    // Near bottom-left is left of and below near top-right, and nearer than far.
    assert!(f.corners[0].x < f.corners[2].x && f.corners[0].y < f.corners[2].y);
    assert!(f.corners[4].z < f.corners[0].z);
    let inside = Vec3::new(0.0, 2.0, -100.0);
    assert!(f.planes.iter().all(|p| p.signed_distance(inside) > 0.0));
    assert!(!f.contains(Vec3::new(0.0, 2.0, 10.0), 0.0));
    assert!(!f.contains(Vec3::new(0.0, 2.0, -1001.0), 0.0));
}

#[test]
fn cascade_errors_and_fallbacks() {
    let cam = camera();
    let splits = CascadeSplits::new(&SplitScheme::Logarithmic, 4, 1.0, 1000.0).unwrap();
    let o = CascadeOptions::default();
    assert_eq!(
        CascadeSet::fit(&cam, Vec3::ZERO, &splits, &o),
        Err(FrustumError::ZeroDirection)
    );
    assert_eq!(
        CascadeSet::fit(&cam, Vec3::NAN, &splits, &o),
        Err(FrustumError::NonFinite)
    );
    assert_eq!(
        CascadeSet::fit(&cam, Vec3::NEG_Y, &splits, &o.with_resolution(0)),
        Err(FrustumError::InvalidResolution)
    );
    let inverted = SceneBounds {
        receivers: Aabb::new(Vec3::ONE, Vec3::ZERO),
        casters: Aabb::new(Vec3::ZERO, Vec3::ONE),
    };
    assert_eq!(
        CascadeSet::fit(&cam, Vec3::NEG_Y, &splits, &o.with_scene(Some(inverted))),
        Err(FrustumError::EmptyBounds)
    );
    // A light parallel to the up hint still gives a valid frame (documented fallback).
    let set = CascadeSet::fit(&cam, Vec3::NEG_Y, &splits, &o.with_up_hint(Vec3::Y)).unwrap();
    assert!(
        set.cascades
            .iter()
            .all(|c| c.transform.clip_from_world.is_finite())
    );
    // Receivers only near the camera: far slices miss them and fall back.
    let near_scene = SceneBounds {
        receivers: Aabb::new(Vec3::new(-5.0, -1.0, -20.0), Vec3::new(5.0, 0.0, -2.0)),
        casters: Aabb::new(Vec3::new(-5.0, -1.0, -20.0), Vec3::new(5.0, 10.0, -2.0)),
    };
    let set = CascadeSet::fit(
        &cam,
        Vec3::new(0.3, -1.0, 0.2),
        &splits,
        &o.with_scene(Some(near_scene)),
    )
    .unwrap();
    assert!(!set.cascades[0].receivers_missed);
    assert!(set.cascades[3].receivers_missed);
    assert_eq!(
        fit_cascade(
            &cam,
            Vec3::new(0.3, -1.0, 0.2),
            500.0,
            1000.0,
            &o.with_scene(Some(near_scene))
        ),
        Err(FrustumError::SliceOutsideScene)
    );
}

#[test]
fn scene_fit_is_tighter_and_pulls_near_back_to_casters() {
    let cam = camera();
    let light = Vec3::new(0.2, -1.0, 0.1);
    let ground = Aabb::new(Vec3::new(-50.0, -0.1, -60.0), Vec3::new(50.0, 0.0, 0.0));
    let tower = Aabb::new(Vec3::new(-2.0, 0.0, -30.0), Vec3::new(2.0, 80.0, -26.0));
    let scene = SceneBounds {
        receivers: ground,
        casters: ground.union(&tower),
    };
    let tight = CascadeOptions::default().with_fit(CascadeFit::Tight);
    let free = fit_cascade(&cam, light, 1.0, 100.0, &tight).unwrap();
    let fitted = fit_cascade(&cam, light, 1.0, 100.0, &tight.with_scene(Some(scene))).unwrap();
    assert!(
        fitted.texel_world_size < free.texel_world_size,
        "{} vs {}",
        fitted.texel_world_size,
        free.texel_world_size
    );
    // The tower top is between the light and the ground: inside the depth range.
    let top = fitted
        .transform
        .project(Vec3::new(0.0, 80.0, -28.0))
        .unwrap();
    assert!((0.0..=1.0).contains(&top.depth), "{top:?}");
    let (cn, _) = fitted.caster_depth.unwrap();
    assert!(cn <= fitted.light_depth.0 + 1e-3);
}

#[test]
fn cascade_set_maps_points_through_the_trait() {
    let cam = camera();
    let splits =
        CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 1.0, 1000.0).unwrap();
    let set = CascadeSet::fit(
        &cam,
        Vec3::new(-0.4, -1.0, -0.3),
        &splits,
        &CascadeOptions::default(),
    )
    .unwrap();
    for (depth, layer) in [(5.0, 0), (200.0, 1), (300.0, 2), (900.0, 3)] {
        let p = cam.eye() + Vec3::new(0.1 * depth, -0.05 * depth, -depth);
        let s = set.map_point(p.as_dvec3()).unwrap();
        assert_eq!(s.layer, layer, "depth {depth}");
        assert!((0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y));
        // Selection by projection never picks a coarser cascade than selection by depth.
        assert!(set.select_by_projection(p, 1.0).unwrap() <= layer as usize);
    }
    assert!(set.map_point(glam::DVec3::new(0.0, 2.0, -2000.0)).is_none());
}

#[test]
fn texel_size_and_bias_of_an_orthographic_cascade() {
    let cam = camera();
    let c = fit_cascade(
        &cam,
        Vec3::NEG_Y,
        1.0,
        50.0,
        &CascadeOptions::default().with_resolution(1024),
    )
    .unwrap();
    let p = Vec3::new(0.0, 0.0, -20.0);
    assert_relative_eq!(
        c.transform.texel_world_size(p, 1024).unwrap(),
        c.texel_world_size,
        max_relative = 1e-4
    );
    // Moving one unit toward the light lowers depth by 1 / (far - near) of light space.
    let (n, f) = c.light_depth;
    assert_relative_eq!(
        c.transform.depth_bias(p, 1.0).unwrap(),
        -1.0 / (f - n),
        max_relative = 1e-3
    );
    let rev = fit_cascade(
        &cam,
        Vec3::NEG_Y,
        1.0,
        50.0,
        &CascadeOptions::default()
            .with_resolution(1024)
            .with_reversed_z(true),
    )
    .unwrap();
    assert_relative_eq!(
        rev.transform.depth_bias(p, 1.0).unwrap(),
        1.0 / (f - n),
        max_relative = 1e-3
    );
}

#[test]
fn spot_fit_covers_the_lit_visible_region() {
    let cam = camera();
    let frustum = cam.slice(1.0, 60.0).unwrap();
    let light = Light::Spot {
        position: Vec3::new(10.0, 20.0, -20.0),
        direction: Vec3::new(-0.4, -1.0, -0.2),
        half_angle: 0.7,
        range: 100.0,
    };
    let ground = Aabb::new(Vec3::new(-40.0, -0.1, -60.0), Vec3::new(40.0, 0.0, 0.0));
    let scene = SceneBounds {
        receivers: ground,
        casters: ground,
    };
    let spot = fit_spot(&light, &frustum, Some(&scene), false).unwrap();
    let body = ConvexBody::from_frustum_aabb(&frustum, &ground).unwrap();
    let cone_cos = 0.7f32.cos();
    let dir = Vec3::new(-0.4, -1.0, -0.2).normalize();
    for v in body.vertices() {
        let to = (*v - Vec3::new(10.0, 20.0, -20.0)).normalize();
        if to.dot(dir) >= cone_cos {
            let s = spot.transform.project(*v).unwrap();
            assert!(
                (-1e-4..=1.0001).contains(&s.uv.x) && (-1e-4..=1.0001).contains(&s.uv.y),
                "{s:?}"
            );
            assert!((-1e-4..=1.0001).contains(&s.depth), "{s:?}");
        }
    }
    let point = Light::Point {
        position: Vec3::ZERO,
        range: 10.0,
    };
    assert_eq!(
        fit_spot(&point, &frustum, None, false),
        Err(FrustumError::UnsupportedLight)
    );
    let wide = Light::Spot {
        position: Vec3::ZERO,
        direction: Vec3::NEG_Z,
        half_angle: 1.6,
        range: 10.0,
    };
    assert_eq!(
        fit_spot(&wide, &frustum, None, false),
        Err(FrustumError::InvalidLight)
    );
}

#[test]
fn depth_bounds_truncate_the_splits_and_fall_back_when_empty() {
    let cam = camera();
    let measured = DepthBounds {
        min: 3.0,
        max: 120.0,
    };
    let s = CascadeSplits::from_depth_bounds(&SplitScheme::Logarithmic, 4, &cam, measured).unwrap();
    assert_eq!((s.depths()[0], s.depths()[4]), (3.0, 120.0));
    // An empty reduction (min > max) and NaN give the whole camera range.
    assert_eq!(
        DepthBounds {
            min: 500.0,
            max: 2.0
        }
        .clamped_to(&cam)
        .unwrap(),
        (1.0, 1000.0)
    );
    // A NaN bound is replaced by the camera's own.
    assert_eq!(
        DepthBounds {
            min: f32::NAN,
            max: 5.0
        }
        .clamped_to(&cam)
        .unwrap(),
        (1.0, 5.0)
    );
    assert_eq!(
        DepthBounds {
            min: f32::NAN,
            max: f32::NAN
        }
        .clamped_to(&cam)
        .unwrap(),
        (1.0, 1000.0)
    );
    // Bounds beyond the camera are clamped.
    assert_eq!(
        DepthBounds {
            min: 0.01,
            max: 1e9
        }
        .clamped_to(&cam)
        .unwrap(),
        (1.0, 1000.0)
    );
}

#[test]
fn extruded_body_reaches_the_scene_boundary_toward_the_light() {
    let frustum = camera().slice(1.0, 20.0).unwrap();
    let scene = Aabb::new(Vec3::new(-30.0, 0.0, -30.0), Vec3::new(30.0, 50.0, 5.0));
    let body = ConvexBody::from_frustum_aabb(&frustum, &scene).unwrap();
    let ext = body.extruded_toward_light(Vec3::NEG_Y, &scene).unwrap();
    // The body and everything straight above it (toward the light) is inside; a
    // scene corner no ray from the body reaches is not.
    for v in body.vertices() {
        assert!(ext.contains(*v, 1e-3));
        assert!(ext.contains(Vec3::new(v.x, 49.9, v.z), 1e-3), "{v}");
    }
    assert!(!ext.contains(Vec3::new(-30.0, 50.0, 5.0), 1e-3));
    // The top face is the silhouette seen from above: a vertex at the scene top sits
    // straight above the outermost body vertices.
    let top = ext
        .vertices()
        .iter()
        .filter(|e| (e.y - 50.0).abs() < 1e-3)
        .count();
    assert!(top >= 3, "{:?}", ext.vertices());

    // A grazing light: rays leave through the side of the scene box, and the swept
    // region reaches the box edges between the exits (a hull of the exit points
    // alone would miss them).
    let light = Vec3::new(1.0, -0.02, 0.0);
    let ext = body.extruded_toward_light(light, &scene).unwrap();
    let toward = -light.normalize();
    for v in body.vertices() {
        for t in [0.0, 5.0, 20.0, 45.0] {
            let x = *v + toward * t;
            if scene.contains(x) {
                assert!(ext.contains(x, 1e-3), "{x} (from {v}, t = {t})");
            }
        }
    }
    assert_eq!(
        body.extruded_toward_light(Vec3::ZERO, &scene),
        Err(FrustumError::ZeroDirection)
    );
    let far_away = Aabb::new(Vec3::splat(500.0), Vec3::splat(600.0));
    assert!(
        ConvexBody::from_frustum_aabb(&frustum, &far_away)
            .unwrap()
            .is_empty()
    );
}

/// A wide depth range (far / near = 1e6) has volume and resolves in `f32` with either
/// depth convention: both validate, and the matrices keep near and far apart.
#[test]
fn wide_depth_range_validates_with_both_depth_conventions() {
    let p = Projection::perspective(1.0, 16.0 / 9.0, 0.1, 1e5);
    let eye = Vec3::new(3.0, 2.0, -1.0);
    let standard = Camera::look_to(eye, Vec3::new(0.2, -0.1, -1.0), Vec3::Y, p).unwrap();
    let reversed = Camera::look_to_reversed_z(eye, Vec3::new(0.2, -0.1, -1.0), Vec3::Y, p).unwrap();
    assert!(reversed.reversed_z && !standard.reversed_z);
    assert_eq!(standard.with_reversed_z(true), reversed);
    for (camera, near_depth) in [(standard, 0.0), (reversed, 1.0)] {
        let clip = camera.clip_from_world().unwrap();
        let project = |d: f32| {
            let h = clip * (eye + camera.forward() * d).extend(1.0);
            h.z / h.w
        };
        assert!((project(0.1) - near_depth).abs() < 1e-3);
        assert!((project(1e5) - (1.0 - near_depth)).abs() < 1e-3);
        assert_ne!(project(1e3), project(1e5));
    }
    // Still refused: a frustum f32 cannot place (tiny near plane far from the origin).
    let tiny = Projection::perspective(1.0, 1.0, 1e-3, 1e5);
    assert_eq!(
        Camera::look_to(Vec3::splat(1e6), Vec3::NEG_Z, Vec3::Y, tiny).map(|_| ()),
        Err(FrustumError::DegenerateFrustum)
    );
}

/// A custom reversed-Z projection validates through `look_to_reversed_z`, which reads
/// its near plane at depth 1; `look_to` reads it as standard depth and refuses it.
#[test]
fn custom_reversed_z_matrix_validates_with_its_convention() {
    let clip_from_view = projection::perspective(1.0, 1.5, 0.5, 300.0, true).as_mat4();
    let p = Projection::Custom {
        clip_from_view,
        shadow_distance: 200.0,
    };
    let camera = Camera::look_to_reversed_z(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, p).unwrap();
    let (near, far) = camera.depth_range().unwrap();
    assert_relative_eq!(near, 0.5, max_relative = 1e-4);
    assert_relative_eq!(far, 200.0, max_relative = 1e-4);
    assert!(Camera::look_to(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, p).is_err());
}

/// A region wholly behind the spot light is outside what it can light.
#[test]
fn spot_with_region_behind_it_is_outside_the_scene() {
    let frustum = camera().frustum().unwrap();
    // The camera looks down -Z from the origin area; the spot sits far in front of
    // it and points back the other way (+Z), away from everything the camera sees.
    let light = Light::Spot {
        position: Vec3::new(0.0, 2.0, -2000.0),
        direction: Vec3::new(0.0, 0.0, -1.0),
        half_angle: 0.7,
        range: 100.0,
    };
    assert_eq!(
        fit_spot(&light, &frustum, None, false),
        Err(FrustumError::SliceOutsideScene)
    );
    let ground = Aabb::new(Vec3::new(-40.0, -0.1, -60.0), Vec3::new(40.0, 0.0, 0.0));
    let scene = SceneBounds {
        receivers: ground,
        casters: ground,
    };
    let behind = Light::Spot {
        position: Vec3::new(0.0, 5.0, -100.0),
        direction: Vec3::new(0.0, 0.0, -1.0),
        half_angle: 0.7,
        range: 100.0,
    };
    assert_eq!(
        fit_spot(&behind, &frustum, Some(&scene), false),
        Err(FrustumError::SliceOutsideScene)
    );
}

/// The stable fit on a size ladder: fitted to slice ∩ receivers, so much smaller than
/// the whole slice's sphere over a small receiver; the size stays on its rung while
/// the camera moves a little, and the map moves by whole texels.
#[test]
fn stable_size_ladder_fits_receivers_and_keeps_its_size() {
    let cam = camera();
    let splits = CascadeSplits::new(&SplitScheme::Logarithmic, 2, 1.0, 1000.0).unwrap();
    let ground = Aabb::new(Vec3::new(-5.0, -0.1, -60.0), Vec3::new(5.0, 0.0, -40.0));
    let scene = SceneBounds {
        receivers: ground,
        casters: ground,
    };
    let light = Vec3::new(-0.3, -1.0, -0.2);
    let whole = CascadeOptions::default()
        .with_resolution(1024)
        .with_scene(Some(scene));
    let ladder = whole.with_stable_size_step(Some(std::f32::consts::SQRT_2));
    let a = CascadeSet::fit(&cam, light, &splits, &whole).unwrap();
    let b = CascadeSet::fit(&cam, light, &splits, &ladder).unwrap();
    let (ta, tb) = (
        a.cascades[1].texel_world_size,
        b.cascades[1].texel_world_size,
    );
    assert!(tb < 0.2 * ta, "{tb} vs {ta}");
    // Needed side at most 60 units (the receiver's diagonal): at most sqrt 2 more.
    assert!(
        tb * 1022.0 <= 60.0 * std::f32::consts::SQRT_2 * 1.001,
        "{tb}"
    );
    let moved = Camera {
        world_from_view: Mat4::from_translation(Vec3::new(0.01, 0.0, 0.0)) * cam.world_from_view,
        ..cam
    };
    let c = CascadeSet::fit(&moved, light, &splits, &ladder).unwrap();
    assert_eq!(c.cascades[1].texel_world_size, tb);
    let p = Vec3::new(1.0, 0.0, -50.0);
    let (sb, sc) = (
        b.cascades[1].transform.project(p).unwrap(),
        c.cascades[1].transform.project(p).unwrap(),
    );
    let texels = (sc.uv - sb.uv) * 1024.0;
    assert!((texels - texels.round()).length() < 1e-3, "{texels}");
    assert_eq!(
        CascadeSet::fit(
            &cam,
            light,
            &splits,
            &whole.with_stable_size_step(Some(1.0))
        ),
        Err(FrustumError::InvalidSplitParameter)
    );
}
