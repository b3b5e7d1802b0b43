//! The per-frame path allocates nothing: the IPSM plan with both cone fits (single
//! cut maps and dual fallbacks; from a camera and from a `ValidCamera`, the same
//! plan), the cone fits alone and the map's lookups, under a
//! counting global allocator.
//!
//! The test runs alone on the main thread, without libtest's harness
//! (`harness = false` in Cargo.toml; see `shadowmap_testgen::run_alone`), since the
//! counting allocator counts every thread.

use std::alloc::System;

use glam::Vec3;
use shadowmap_frustum::{Camera, DepthBounds, Light, Projection, ShadowMapping, ValidCamera};
use shadowmap_paraboloid::{ConeFit, IpsmOptions, IpsmPlan, fit_minimal_cone, fit_paper_cone};
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
    let bounds = DepthBounds {
        min: 1.0,
        max: 80.0,
    };
    let exact = IpsmOptions::default();
    let paper = IpsmOptions::default().with_fit(ConeFit::Paper);
    let valid = ValidCamera::new(&camera).unwrap();

    let region = Region::new(GLOBAL);
    let (mut singles, mut duals) = (0, 0);
    let mut checksum = 0.0f64;
    for frame in 0..16 {
        let t = frame as f32 * 0.4;
        // Outside the frustum (single) and inside it (dual fallback).
        let position = if frame % 2 == 0 {
            Vec3::new(60.0 * t.cos(), 30.0, 60.0 * t.sin())
        } else {
            Vec3::new(3.0 + 0.3 * t, 1.0, -20.0)
        };
        let light = Light::Point {
            position,
            range: 500.0,
        };
        for options in [&exact, &paper] {
            let plan = IpsmPlan::new(&light, &camera, Some(bounds), options).unwrap();
            let from_valid = IpsmPlan::new_valid(&light, &valid, Some(bounds), options);
            assert!(from_valid == Ok(plan));
            if plan.is_single() {
                singles += 1;
            } else {
                duals += 1;
            }
            let s = plan.map_point(plan.border_points[6].as_dvec3());
            checksum += s.map_or(0.0, |s| s.depth) + f64::from(plan.zoom());
            let dirs = plan.border_points.map(|p| p - position);
            checksum += f64::from(fit_paper_cone(&dirs).map_or(0.0, |c| c.half_angle));
            checksum += f64::from(fit_minimal_cone(&dirs).map_or(0.0, |c| c.half_angle));
        }
    }
    let stats = region.change();
    assert!(checksum.is_finite());
    assert!(singles > 0 && duals > 0, "{singles} single, {duals} dual");
    assert_eq!(stats.allocations, 0, "{stats:?}");
    assert_eq!(stats.reallocations, 0, "{stats:?}");
}
