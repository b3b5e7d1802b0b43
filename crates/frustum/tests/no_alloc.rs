//! The per-frame path allocates nothing: splits, the 4-cascade stable fit with scene
//! bounds, the convex body and its extrusion, and the spot fit, under a counting
//! global allocator.
//!
//! The test runs alone on the main thread, without libtest's harness
//! (`harness = false` in Cargo.toml; see `shadowmap_testgen::run_alone`), since the
//! counting allocator counts every thread.

use std::alloc::System;

use glam::Vec3;
use shadowmap_frustum::{
    Aabb, Camera, CascadeOptions, CascadeSet, CascadeSplits, ConvexBody, Light, Projection,
    SceneBounds, SplitScheme, ValidCamera, fit_spot,
};
use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn main() {
    shadowmap_testgen::run_alone(
        "per_frame_path_does_not_allocate",
        per_frame_path_does_not_allocate,
    );
}

fn per_frame_path_does_not_allocate() {
    let camera = Camera::look_to(
        Vec3::new(3.0, 2.0, 1.0),
        Vec3::new(0.2, -0.1, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 1.6, 0.1, 300.0),
    )
    .unwrap();
    let ground = Aabb::new(Vec3::new(-200.0, -1.0, -300.0), Vec3::new(200.0, 0.0, 10.0));
    let scene = SceneBounds {
        receivers: ground,
        casters: ground.union(&Aabb::new(Vec3::ZERO, Vec3::splat(40.0))),
    };
    let options = CascadeOptions::default().with_scene(Some(scene));
    let light = Vec3::new(-0.3, -1.0, -0.4);
    let spot = Light::Spot {
        position: Vec3::new(0.0, 20.0, -10.0),
        direction: Vec3::NEG_Y,
        half_angle: 0.8,
        range: 60.0,
    };

    // A set a renderer keeps and refits in place every frame.
    let first = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 2, 0.1, 300.0).unwrap();
    let mut refitted = CascadeSet::fit(&camera, light, &first, &options).unwrap();
    let region = Region::new(GLOBAL);
    let mut checksum = 0.0f32;
    for frame in 0..10 {
        let camera = Camera {
            world_from_view: glam::Mat4::from_translation(Vec3::new(frame as f32 * 0.37, 0.0, 0.0))
                * camera.world_from_view,
            ..camera
        };
        let splits =
            CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 300.0).unwrap();
        let set = CascadeSet::fit(&camera, light, &splits, &options).unwrap();
        let valid = ValidCamera::new(&camera).unwrap();
        refitted
            .refit_valid(&valid, light, &splits, &options)
            .unwrap();
        assert_eq!(refitted, set);
        let frustum = camera.frustum().unwrap();
        let body = ConvexBody::from_frustum_aabb(&frustum, &ground).unwrap();
        let extruded = body.extruded_toward_light(light, &scene.casters).unwrap();
        let spot = fit_spot(&spot, &frustum, Some(&scene), false).unwrap();
        checksum += set.cascades[3].texel_world_size
            + extruded.vertices().len() as f32
            + spot.light_depth.1;
    }
    let stats = region.change();
    assert!(checksum.is_finite());
    assert_eq!(stats.allocations, 0, "{stats:?}");
    assert_eq!(stats.reallocations, 0, "{stats:?}");
}
