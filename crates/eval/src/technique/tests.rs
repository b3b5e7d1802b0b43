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
    assert_eq!(TechniqueKind::for_light(&p).len(), 6);
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
    assert_eq!((t.layers(), t.texels()), (4, 4 * 32 * 32));
}

/// Cube maps render one layer per kept face through the matrix depth pass, and a
/// box over the ground shadows the ground point below it (on its own layer) but not
/// a lit one.
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
    let frame = frame_over(&camera, &light, b);
    let o = TechniqueOptions::default().with_texel_budget(256 * 256);
    for kind in [TechniqueKind::Cube, TechniqueKind::CubeUnfocused] {
        let t = Technique::build(kind, &frame, &o).unwrap();
        let cube = t.shadow().cube().unwrap();
        assert!((1..6).contains(&t.layers()), "{}", t.layers());
        assert_eq!(t.layers(), cube.layers());
        let map = t.rasterize(&mesh, &RasterOptions::default()).unwrap();
        assert_eq!(map.layers, t.layers());
        let stored = |p: DVec3| {
            let s = t.map_point(p).unwrap();
            (f64::from(map.lookup(&s).unwrap()), s.depth)
        };
        // Below the box (shadowed): something nearer is stored.
        let (occluder, ground) = stored(DVec3::new(0.0, 0.0, -30.0));
        assert!(
            occluder < ground - 1e-4,
            "{}: {occluder} {ground}",
            kind.name()
        );
        // Lit ground: the stored depth is the ground's own.
        let (stored_lit, lit) = stored(DVec3::new(15.0, 0.0, -40.0));
        assert!(
            (stored_lit - lit).abs() < 2e-3,
            "{}: {stored_lit} {lit}",
            kind.name()
        );
    }
}
