//! `serde` round-trips of the umbrella's options and results: every [`Technique`]
//! with its options, and the [`Shadow`] of every technique fitted to a street view
//! (directional), a spot light and a point light. A payload whose layer count, layer
//! side or technique does not fit its result is refused.

use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, Light, Projection, SceneBounds, ShadowMapping};
use shadowmap::rtw::EyeSample;
use shadowmap::{FitInput, LightKind, Shadow, Technique, fit};

const BUDGET: u64 = 256 * 256;

fn street() -> (Camera, SceneBounds) {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
    )
    .unwrap();
    let ground = Aabb::new(Vec3::new(-150.0, 0.0, -320.0), Vec3::new(150.0, 1.0, 20.0));
    let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 30.0 * Vec3::Y));
    (camera, scene)
}

fn light_of(kind: LightKind) -> Light {
    match kind {
        LightKind::Directional => Light::Directional {
            direction: Vec3::new(0.4, -1.0, 0.3),
        },
        LightKind::Spot => Light::Spot {
            position: Vec3::new(0.0, 40.0, -30.0),
            direction: Vec3::NEG_Y,
            half_angle: 1.2,
            range: 200.0,
        },
        LightKind::Point => Light::Point {
            position: Vec3::new(5.0, 10.0, -40.0),
            range: 400.0,
        },
    }
}

/// Eye samples on the visible ground, for RTW.
fn samples(camera: &Camera) -> Vec<EyeSample> {
    (0..64)
        .map(|i| {
            let p = Vec3::new(
                (i % 8) as f32 * 10.0 - 35.0,
                0.5,
                -10.0 - (i / 8) as f32 * 25.0,
            );
            EyeSample {
                position: p,
                normal: Vec3::Y,
                eye_distance: p.distance(camera.eye()),
            }
        })
        .collect()
}

fn fitted(technique: &Technique) -> Shadow {
    let (camera, scene) = street();
    let light = light_of(technique.light_kind());
    let eye = samples(&camera);
    let input = FitInput::new(&camera, &light, scene, BUDGET)
        .with_eye_samples(&eye)
        .with_pixels_per_radian(800.0);
    fit(technique, &input).unwrap_or_else(|e| panic!("{}: {e}", technique.name()))
}

#[test]
fn every_technique_round_trips() {
    for technique in Technique::all_default() {
        let json = serde_json::to_string(&technique).unwrap();
        let back: Technique = serde_json::from_str(&json).unwrap();
        assert_eq!(back, technique, "{json}");
    }
}

#[test]
fn every_fitted_shadow_round_trips_and_maps_the_same() {
    let probe = [
        Vec3::new(0.0, 0.5, -20.0),
        Vec3::new(-30.0, 0.5, -120.0),
        Vec3::new(40.0, 0.5, -250.0),
    ];
    for technique in Technique::all_default() {
        let shadow = fitted(&technique);
        let json = serde_json::to_string(&shadow).unwrap();
        let back: Shadow = serde_json::from_str(&json).unwrap();
        // Written again, the same text (RTW's work buffer is not part of the value).
        assert_eq!(
            serde_json::to_string(&back).unwrap(),
            json,
            "{}",
            technique.name()
        );
        assert_eq!(back.technique(), shadow.technique());
        assert_eq!(back.layers(), shadow.layers());
        assert_eq!(back.layer_side(), shadow.layer_side());
        for p in probe {
            assert_eq!(
                back.map_point(p.as_dvec3()),
                shadow.map_point(p.as_dvec3()),
                "{} at {p}",
                technique.name()
            );
        }
    }
}

/// Tiled cube maps (tiles, cell table and atlas) round-trip and map every probe the
/// same.
#[test]
fn tiled_cube_maps_round_trip() {
    let technique = Technique::TiledCube {
        cube: Default::default(),
        tiles: Default::default(),
    };
    let shadow = fitted(&technique);
    assert!(shadow.tiled_cube().is_some_and(|t| t.tiles.len() > 1));
    let json = serde_json::to_string(&shadow).unwrap();
    let back: Shadow = serde_json::from_str(&json).unwrap();
    assert_eq!(serde_json::to_string(&back).unwrap(), json);
    assert_eq!(back.layers(), shadow.layers());
    for p in [
        Vec3::new(0.0, 0.5, -20.0),
        Vec3::new(-3.0, 0.5, -12.0),
        Vec3::new(4.0, 0.5, -25.0),
    ] {
        assert_eq!(back.map_point(p.as_dvec3()), shadow.map_point(p.as_dvec3()));
    }
}

#[test]
fn inconsistent_shadows_are_refused() {
    let shadow = fitted(&Technique::all_default()[0]);
    let value = serde_json::to_value(&shadow).unwrap();
    let edits: [(&str, serde_json::Value); 3] = [
        ("layers", serde_json::json!(3)),
        ("layer_side", serde_json::json!(2)),
        (
            "technique",
            serde_json::to_value(Technique::all_default()[3]).unwrap(),
        ),
    ];
    for (field, bad) in edits {
        let mut payload = value.clone();
        payload[field] = bad;
        let err = serde_json::from_value::<Shadow>(payload).unwrap_err();
        assert!(!err.to_string().is_empty(), "{field}");
    }
    // The unedited payload is accepted.
    assert_eq!(serde_json::from_value::<Shadow>(value).unwrap(), shadow);
}

#[test]
fn layer_counts_are_the_results() {
    for technique in Technique::all_default() {
        let shadow = fitted(&technique);
        assert_eq!(
            shadow.fitted().layer_count(),
            shadow.layers(),
            "{}",
            technique.name()
        );
    }
}
