//! The per-frame path of every warp allocates nothing: the focus body, uniform,
//! LiSPSM, XPSM, TSM and four warped cascades, under a counting global allocator
//!.
//!
//! The test runs alone on the main thread, without libtest's harness
//! (`harness = false` in Cargo.toml; see `shadowmap_testgen::run_alone`), since the
//! counting allocator counts every thread.

use std::alloc::System;

use glam::Vec3;
use shadowmap_frustum::{Aabb, Camera, CascadeSplits, Projection, SplitScheme};
use shadowmap_warp::{
    FocusBody, LispsmOptions, SceneBounds, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
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
    let scene = SceneBounds::new(
        ground,
        ground.union(&Aabb::new(Vec3::ZERO, Vec3::splat(40.0))),
    );
    let light = Vec3::new(-0.3, -1.0, -0.4);
    let splits =
        CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 300.0).unwrap();

    let region = Region::new(GLOBAL);
    let mut checksum = 0.0f32;
    for frame in 0..10 {
        let camera = Camera {
            world_from_view: glam::Mat4::from_translation(Vec3::new(frame as f32 * 0.37, 0.0, 0.0))
                * camera.world_from_view,
            ..camera
        };
        let body = FocusBody::new(&camera, light, &scene).unwrap();
        let shared = body.lispsm(&LispsmOptions::default()).unwrap().n
            + body.xpsm(&XpsmOptions::default()).unwrap().length_p
            + body.tsm(&TsmOptions::default()).unwrap().eta
            + body
                .uniform(&UniformOptions::default())
                .unwrap()
                .clip_from_world
                .x_axis
                .x;
        let u = uniform_focused(&camera, light, &scene, &UniformOptions::default()).unwrap();
        let l = lispsm(&camera, light, &scene, &LispsmOptions::default()).unwrap();
        let x = xpsm(&camera, light, &scene, &XpsmOptions::default()).unwrap();
        let t = tsm(&camera, light, &scene, &TsmOptions::default()).unwrap();
        let c = warped_cascades(
            &camera,
            light,
            &scene,
            &splits,
            &[0.0, 0.0, -0.5, -1.0],
            &LispsmOptions::default(),
        )
        .unwrap();
        checksum += shared
            + u.clip_from_world.x_axis.x
            + l.n
            + x.length_p
            + t.eta
            + c.cascades.len() as f32;
    }
    let stats = region.change();
    assert!(checksum.is_finite());
    assert_eq!(
        (stats.allocations, stats.reallocations),
        (0, 0),
        "the per-frame warp path allocated: {stats:?}"
    );
}
