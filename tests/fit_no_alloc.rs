//! `fit` allocates nothing per frame for every technique but RTW (its importance map
//! and tables), `auto` included, and IPSM, cube maps, warps, cascades and `auto`
//! measured on eye samples,
//! under a counting global allocator.
//!
//! The test runs alone on the main thread, without libtest's harness
//! (`harness = false` in Cargo.toml; see `shadowmap_testgen::run_alone`), since the
//! counting allocator counts every thread.

use std::alloc::System;

use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, Light, Projection, SceneBounds, TechniqueSelector};
use shadowmap::paraboloid::{CubeOptions, FaceSizes, IpsmOptions};
use shadowmap::rtw::EyeSample;
use shadowmap::{CascadePlan, FitInput, Technique, fit_with_selector};
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    shadowmap_testgen::run_alone("fit_does_not_allocate", fit_does_not_allocate);
}

fn fit_does_not_allocate() {
    let camera = Camera::look_to(
        Vec3::new(3.0, 2.0, 1.0),
        Vec3::new(0.2, -0.1, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 1.6, 0.1, 300.0),
    )
    .unwrap();
    let ground = Aabb::new(Vec3::new(-200.0, -1.0, -300.0), Vec3::new(200.0, 0.0, 10.0));
    let scene = SceneBounds::new(
        ground,
        ground.union(&Aabb::new(Vec3::ZERO, Vec3::splat(40.0))),
    );
    let sun = Light::Directional {
        direction: Vec3::new(-0.3, -1.0, -0.4),
    };
    let lamp = Light::Point {
        position: Vec3::new(2.0, 3.0, -8.0),
        range: 60.0,
    };
    let spot = Light::Spot {
        position: Vec3::new(0.0, 30.0, -20.0),
        direction: Vec3::NEG_Y,
        half_angle: 1.0,
        range: 100.0,
    };
    let techniques: Vec<Technique> = Technique::all_default()
        .into_iter()
        .filter(|t| !matches!(t, Technique::Rtw(_) | Technique::RtwOracle(_)))
        .collect();
    // Every technique but the two RTW ones.
    assert_eq!(techniques.len(), Technique::all_default().len() - 2);
    let mut selector = TechniqueSelector::new();
    // With the eye's samples, IPSM, cube maps sized by need, the warps' strength, the
    // cascades' count and `auto` measure on them.
    let samples: Vec<EyeSample> = (0..2000)
        .map(|k| {
            let p = Vec3::new(
                -40.0 + (k % 50) as f32 * 1.6,
                0.0,
                -2.0 - (k / 50) as f32 * 3.0,
            );
            EyeSample {
                position: p,
                normal: Vec3::Y,
                eye_distance: p.distance(camera.eye()),
            }
        })
        .collect();
    let plan = CascadePlan::default();
    let measured = [
        (Technique::Ipsm(IpsmOptions::default()), &lamp),
        (
            Technique::CubeMaps(CubeOptions::default().with_sizes(FaceSizes::ByNeed)),
            &lamp,
        ),
        (Technique::Lispsm(Default::default()), &sun),
        (Technique::Xpsm(Default::default()), &sun),
        (Technique::Tsm(Default::default()), &sun),
        (Technique::TightCascades(plan), &sun),
        (Technique::StableCascades(plan), &sun),
        (Technique::Auto(plan), &sun),
    ];

    // Counted around each call only: the test harness's own threads may allocate
    // between calls.
    let mut allocations = (0, 0);
    let mut fitted = 0;
    let mut counted = |technique: &Technique, input: &FitInput<'_>| {
        let region = Region::new(GLOBAL);
        let layers = fit_with_selector(technique, input, &mut selector)
            .unwrap()
            .layers();
        let stats = region.change();
        allocations.0 += stats.allocations;
        allocations.1 += stats.reallocations;
        if stats.allocations + stats.reallocations > 0 {
            eprintln!("{}: {stats:?}", technique.name());
        }
        layers
    };
    for frame in 0..5 {
        let camera = Camera {
            world_from_view: glam::Mat4::from_translation(Vec3::new(frame as f32 * 0.37, 0.0, 0.0))
                * camera.world_from_view,
            ..camera
        };
        for technique in &techniques {
            let light = [&sun, &lamp, &spot]
                .into_iter()
                .find(|l| technique.applies_to(l))
                .unwrap();
            let input = FitInput::new(&camera, light, scene, 2048 * 2048);
            fitted += counted(technique, &input);
        }
    }
    for (technique, light) in &measured {
        let input = FitInput::new(&camera, light, scene, 2048 * 2048)
            .with_eye_samples(&samples)
            .with_pixels_per_radian(500.0);
        fitted += counted(technique, &input);
    }
    assert!(fitted as usize >= 5 * techniques.len());
    assert_eq!(allocations, (0, 0), "allocations, reallocations");
}
