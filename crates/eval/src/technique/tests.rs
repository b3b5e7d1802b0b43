//! Unit tests of the technique list, the budget and `auto`.
use shadowmap_frustum::{PredictOptions, predict_errors};

use super::*;

#[test]
fn budget_is_shared_evenly() {
    let o = TechniqueOptions::default();
    assert_eq!(o.layer_side(1), 1024);
    assert_eq!(o.layer_side(4), 512);
    assert_eq!(o.layer_side(2), 724);
}

#[test]
fn auto_candidates_are_the_umbrellas() {
    let plan = CascadePlan::default();
    let kinds: Vec<Option<TechniqueKind>> = shadowmap::auto_candidates(&plan)
        .iter()
        .map(TechniqueKind::of)
        .collect();
    let expected: Vec<Option<TechniqueKind>> = AUTO_CANDIDATES.iter().copied().map(Some).collect();
    assert_eq!(kinds, expected);
    // Every kind round-trips through the umbrella's value.
    let o = TechniqueOptions::default();
    for kind in TechniqueKind::ALL {
        assert_eq!(TechniqueKind::of(&kind.technique(&o)), Some(kind));
    }
}

#[test]
fn every_light_has_techniques() {
    let d = Light::Directional {
        direction: Vec3::NEG_Y,
    };
    let p = Light::Point {
        position: Vec3::Y,
        range: 10.0,
    };
    assert_eq!(TechniqueKind::for_light(&d).len(), 10);
    assert_eq!(TechniqueKind::for_light(&p).len(), 8);
    assert!(!TechniqueKind::SpotFit.applies_to(&d));
}

/// A frame over one box that both casts and receives, without eye samples.
fn frame_over<'a>(
    camera: &'a Camera,
    light: &'a Light,
    b: shadowmap_frustum::Aabb,
) -> FrameContext<'a> {
    FrameContext {
        camera,
        light,
        scene: SceneBounds {
            receivers: b,
            casters: b,
        },
        eye_samples: &[],
        pixels_per_radian: 100.0,
    }
}

#[test]
fn auto_is_the_candidate_with_the_lowest_prediction() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 10.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.5, 1.0, 300.0),
    )
    .unwrap();
    let light = Light::Directional {
        direction: Vec3::new(0.3, -1.0, 0.1),
    };
    let b =
        shadowmap_frustum::Aabb::new(Vec3::new(-300.0, 0.0, -320.0), Vec3::new(300.0, 30.0, 20.0));
    let frame = frame_over(&camera, &light, b);
    let o = TechniqueOptions::default().with_texel_budget(256 * 256);
    let auto = Technique::build(TechniqueKind::Auto, &frame, &o).unwrap();
    assert_eq!(auto.kind(), TechniqueKind::Auto);
    assert!(AUTO_CANDIDATES.contains(&auto.chosen()));
    // The candidates predicted on the rays all of them cover, as `auto` does.
    let fitted: Vec<Technique> = AUTO_CANDIDATES
        .iter()
        .filter_map(|k| Technique::build(*k, &frame, &o).ok())
        .collect();
    let candidates: Vec<(&dyn ShadowMapping, u32)> = fitted
        .iter()
        .map(|t| (t as &dyn ShadowMapping, t.shadow().layer_side()))
        .collect();
    let mut predicted = vec![None; candidates.len()];
    predict_errors(
        &camera,
        &b,
        &candidates,
        &PredictOptions::default(),
        &mut predicted,
    )
    .unwrap();
    let best = predicted
        .iter()
        .map(|p| p.unwrap().percentile)
        .fold(f64::INFINITY, f64::min);
    let chosen = fitted
        .iter()
        .position(|t| t.kind() == auto.chosen())
        .unwrap();
    assert_eq!(predicted[chosen].unwrap().percentile, best);
    let chosen = &fitted[chosen];
    // A perspective view over open ground: a warp beats the uniform fit.
    assert_ne!(auto.chosen(), TechniqueKind::UniformFocused);
    let p = DVec3::new(1.0, 0.0, -20.0);
    assert_eq!(auto.map_point(p), chosen.map_point(p));
}

#[test]
fn wrong_light_or_bad_frame_is_a_typed_error() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap();
    let light = Light::Directional {
        direction: Vec3::NEG_Y,
    };
    let b = shadowmap_frustum::Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0));
    let frame = frame_over(&camera, &light, b);
    let o = TechniqueOptions::default().with_texel_budget(64 * 64);
    let err = Technique::build(TechniqueKind::IpsmExact, &frame, &o).unwrap_err();
    assert!(matches!(
        err,
        EvalError::Technique {
            technique: "ipsm_exact",
            ..
        }
    ));
    // Receivers behind the camera: the warp crate's error, not a panic.
    let behind =
        shadowmap_frustum::Aabb::new(Vec3::new(-5.0, -5.0, 10.0), Vec3::new(5.0, 5.0, 20.0));
    let frame = frame_over(&camera, &light, behind);
    // (Stable cascades have a documented fallback instead: the whole slice.)
    for kind in TechniqueKind::for_light(&light) {
        if matches!(
            kind,
            TechniqueKind::StableCascades | TechniqueKind::TightCascades
        ) {
            assert!(Technique::build(kind, &frame, &o).is_ok());
            continue;
        }
        match Technique::build(kind, &frame, &o) {
            Err(EvalError::Technique { reason, .. }) => assert!(!reason.is_empty()),
            other => panic!("{}: {other:?}", kind.name()),
        }
    }
    // A valid frame builds every directional technique within the budget.
    let t = Technique::build(
        TechniqueKind::StableCascades,
        &frame_over(&camera, &light, b),
        &o,
    )
    .unwrap();
    // The count is the one of least predicted error among those whose maps have a
    // power-of-two side (one of 64² or four of 32²): the whole budget either way.
    assert!(matches!(t.layers(), 1 | 4), "{}", t.layers());
    assert_eq!(t.texels(), 64 * 64);
}

/// Cube maps (by need, equal full faces, and RTW over the faces) render one layer
/// per kept face (tiled: per tile) at its own side within the budget, and a box over the ground
/// shadows the ground point below it (on its own layer) but not a lit one.
#[test]
fn cube_maps_render_their_kept_faces() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 3.0, 0.0),
        Vec3::new(0.0, -0.3, -1.0),
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap();
    let light = Light::Point {
        position: Vec3::new(0.0, 10.0, -20.0),
        range: 80.0,
    };
    let mut mesh = crate::scene::Mesh::new();
    let (g0, g1) = (DVec3::new(-60.0, 0.0, -90.0), DVec3::new(60.0, 0.0, 10.0));
    mesh.push_quad([
        g0,
        DVec3::new(g1.x, 0.0, g0.z),
        g1,
        DVec3::new(g0.x, 0.0, g1.z),
    ]);
    mesh.push_box(DVec3::new(-2.0, 4.0, -26.0), DVec3::new(2.0, 5.0, -22.0));
    let b = mesh.bounds().unwrap();
    // The eye's samples: a grid on the ground ahead.
    let samples: Vec<EyeSample> = (0..40 * 30)
        .map(|k| {
            let p = Vec3::new(
                -40.0 + 2.0 * (k % 40) as f32,
                0.0,
                -5.0 - 2.0 * (k / 40) as f32,
            );
            EyeSample {
                position: p,
                normal: Vec3::Y,
                eye_distance: p.distance(camera.eye()),
            }
        })
        .collect();
    let frame = FrameContext {
        eye_samples: &samples,
        ..frame_over(&camera, &light, b)
    };
    let budget = 256 * 256;
    let o = TechniqueOptions::default().with_texel_budget(budget);
    for kind in [
        TechniqueKind::Cube,
        TechniqueKind::CubeUnfocused,
        TechniqueKind::CubeRtw,
        TechniqueKind::CubeTiled,
    ] {
        let t = Technique::build(kind, &frame, &o).unwrap();
        assert!(
            t.texels() <= budget && t.texels() >= budget * 3 / 4,
            "{}",
            t.texels()
        );
        let sides: Vec<(u32, u32)> = if let Some(tiled) = t.shadow().tiled_cube() {
            let stored = |side: u32| side + 2 * tiled.border;
            tiled
                .tiles
                .iter()
                .map(|x| (stored(x.side), stored(x.side)))
                .collect()
        } else {
            let cube = t.shadow().cube().unwrap();
            assert!((1..6).contains(&t.layers()), "{}", t.layers());
            assert_eq!(t.layers(), cube.layers());
            cube.faces.iter().map(|f| (f.size[0], f.size[1])).collect()
        };
        assert_eq!(t.layer_sizes(), sides);
        let map = t.rasterize(&mesh, &RasterOptions::default()).unwrap();
        assert_eq!(map.layers, t.layers());
        for (layer, size) in sides.iter().enumerate() {
            assert_eq!(map.layer_size(layer as u32), *size);
        }
        let stored = |p: DVec3| {
            let s = t.map_point(p).unwrap();
            (f64::from(map.lookup(&s).unwrap()), s.depth)
        };
        // Below the box (shadowed): something nearer is stored. (Both points are
        // samples: RTW's faces are narrowed to them.)
        let (occluder, ground) = stored(DVec3::new(0.0, 0.0, -29.0));
        assert!(
            occluder < ground - 1e-4,
            "{}: {occluder} {ground}",
            kind.name()
        );
        // Lit ground: the stored depth is the ground's own.
        let (stored_lit, lit) = stored(DVec3::new(16.0, 0.0, -39.0));
        assert!(
            (stored_lit - lit).abs() < 2e-3,
            "{}: {stored_lit} {lit}",
            kind.name()
        );
    }
}

/// RTW over the paraboloid renders a ground of large tiles under a point light
/// without the ground shadowing itself: the depth pass cuts edges finely enough to
/// cross the side's whole disc in pieces of the span bound, and leaves out pieces
/// behind the side (with the default cap of 32 pieces an edge, a 125 m tile under a
/// light 30 m up stayed in pieces many table cells long, and a band of the ground
/// read as shadowed).
#[test]
fn point_rtw_ground_does_not_shadow_itself() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 1.7, 118.0),
        Vec3::new(0.0, -0.05, -1.0),
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 16.0 / 9.0, 0.5, 400.0),
    )
    .unwrap();
    let light = Light::Point {
        position: Vec3::new(0.5, 30.0, 78.0),
        range: 400.0,
    };
    let mut mesh = crate::scene::Mesh::new();
    let tile = 125.0;
    for i in -8..8 {
        for j in -8..8 {
            let (x0, z0) = (f64::from(i) * tile, f64::from(j) * tile);
            let (x1, z1) = (x0 + tile, z0 + tile);
            mesh.push_quad([
                DVec3::new(x0, 0.0, z0),
                DVec3::new(x0, 0.0, z1),
                DVec3::new(x1, 0.0, z1),
                DVec3::new(x1, 0.0, z0),
            ]);
        }
    }
    // The eye's samples: where the rays of a 160 x 90 image meet the ground.
    let eye = camera.eye().as_dvec3();
    let (w, h) = (160, 90);
    let samples: Vec<EyeSample> = (0..w * h)
        .filter_map(|k| {
            let ndc = DVec3::new(
                (f64::from(k % w) + 0.5) / f64::from(w) * 2.0 - 1.0,
                1.0 - (f64::from(k / w) + 0.5) / f64::from(h) * 2.0,
                0.5,
            );
            let p = camera
                .clip_from_world()
                .unwrap()
                .as_dmat4()
                .inverse()
                .project_point3(ndc);
            let dir = (p - eye).normalize();
            let t = -eye.y / dir.y;
            (t > 0.0 && t < 400.0).then(|| {
                let p = eye + dir * t;
                EyeSample {
                    position: p.as_vec3(),
                    normal: Vec3::Y,
                    eye_distance: t as f32,
                }
            })
        })
        .collect();
    let b = mesh.bounds().unwrap();
    let frame = FrameContext {
        eye_samples: &samples,
        pixels_per_radian: h as f32 / 1.0,
        ..frame_over(&camera, &light, b)
    };
    let t = Technique::build(
        TechniqueKind::PointRtw,
        &frame,
        &TechniqueOptions::default(),
    )
    .unwrap();
    let raster = RasterOptions::default().with_depth_bias(16.0, 1.5);
    let map = t.rasterize(&mesh, &raster).unwrap();
    let (mut lit, mut looked) = (0, 0);
    for s in &samples {
        let Some(sample) = t.map_point(s.position.as_dvec3()) else {
            continue;
        };
        looked += 1;
        lit += usize::from(map.is_lit(&sample, 1e-5) == Some(true));
    }
    assert!(looked > samples.len() / 2, "{looked} of {}", samples.len());
    assert_eq!(
        lit,
        looked,
        "{} of {looked} ground points self-shadowed",
        looked - lit
    );
}
