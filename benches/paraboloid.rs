//! Per-frame cost of one IPSM plan with the exact minimal cone versus the paper's
//! averaged cone (same configurations, same run, camera validation alone as the
//! floor), and of the two cone fits alone; the per-frame fit of the cube maps
//! (focused and full faces) against building a DPSM, in the same run.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, DepthBounds, Light, Projection, SceneBounds};
use shadowmap::paraboloid::{
    ConeFit, CubeMap, CubeOptions, CubeOrientation, IpsmOptions, IpsmPlan, MapOptions,
    ParaboloidMap, fit_minimal_cone, fit_paper_cone,
};
use std::hint::black_box;
use std::time::Duration;

/// 64 fixed configurations: lights around a camera, inside and outside the frustum.
fn configs() -> Vec<(Light, Camera, DepthBounds)> {
    let camera = Camera::look_to(
        Vec3::new(10.0, 1.8, 3.0),
        Vec3::new(0.3, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.1, 500.0),
    )
    .unwrap();
    (0..64)
        .map(|i| {
            let t = i as f32 * 0.7;
            let position = Vec3::new(80.0 * t.cos(), 20.0 + 5.0 * (i % 7) as f32, 80.0 * t.sin());
            let bounds = DepthBounds {
                min: 0.5 + (i % 5) as f32,
                max: 40.0 + 20.0 * (i % 9) as f32,
            };
            (
                Light::Point {
                    position,
                    range: 2000.0,
                },
                camera,
                bounds,
            )
        })
        .collect()
}

fn plan(c: &mut Criterion) {
    let cases = configs();
    // One plan per iteration, cycling through the 64 configurations: criterion's time
    // is the mean cost of one call. `Camera::validate` alone, measured in the same run,
    // is the floor every plan pays at its door.
    let mut g = c.benchmark_group("ipsm_plan");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    let mut i = 0usize;
    g.bench_function("camera_validate", |b| {
        b.iter(|| {
            i = (i + 1) % cases.len();
            black_box(cases[i].1.validate().is_ok())
        });
    });
    for (name, fit) in [("paper", ConeFit::Paper), ("exact", ConeFit::Exact)] {
        let options = IpsmOptions::default().with_fit(fit);
        g.bench_function(name, |b| {
            b.iter(|| {
                i = (i + 1) % cases.len();
                let (light, camera, bounds) = &cases[i];
                black_box(IpsmPlan::new(light, camera, Some(*bounds), &options).unwrap())
            });
        });
    }
    g.finish();

    let plan = IpsmPlan::new(
        &cases[0].0,
        &cases[0].1,
        Some(cases[0].2),
        &IpsmOptions::default(),
    )
    .unwrap();
    let dirs = plan.border_points.map(|p| p - plan.map.position);
    let mut g = c.benchmark_group("cone_fit_8");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    g.bench_function("paper", |b| b.iter(|| fit_paper_cone(black_box(&dirs))));
    g.bench_function("exact", |b| b.iter(|| fit_minimal_cone(black_box(&dirs))));
    g.finish();
}

/// One cube-map fit per iteration over the same 64 configurations, above a ground
/// slab with casters: focused (world axes, as by default; turned toward the
/// receivers; the better of the two predicted) and unfocused, and
/// `ParaboloidMap::dual` (a DPSM's whole per-frame build) in the same group as the
/// reference for the ratio.
fn cube(c: &mut Criterion) {
    let cases = configs();
    let ground = Aabb::new(
        Vec3::new(-300.0, -1.0, -300.0),
        Vec3::new(300.0, 0.0, 300.0),
    );
    let scene = SceneBounds::new(
        ground,
        ground.union(&Aabb::new(ground.min, Vec3::new(300.0, 30.0, 300.0))),
    );
    let mut g = c.benchmark_group("cube_fit");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    let mut i = 0usize;
    g.bench_function("dpsm_map", |b| {
        b.iter(|| {
            i = (i + 1) % cases.len();
            let Light::Point { position, range } = cases[i].0 else {
                unreachable!()
            };
            black_box(
                ParaboloidMap::dual(position, Vec3::NEG_Y, 0.05, range, &MapOptions::default())
                    .unwrap(),
            )
        });
    });
    let focused = CubeOptions::default();
    for (name, options) in [
        ("focused", focused),
        (
            "focused_toward_receivers",
            focused.with_orientation(CubeOrientation::TowardReceivers),
        ),
        (
            "focused_predicted",
            focused.with_orientation(CubeOrientation::Predicted),
        ),
        ("unfocused", focused.with_focused(false)),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                i = (i + 1) % cases.len();
                let (light, camera, bounds) = &cases[i];
                black_box(CubeMap::fit(light, camera, Some(*bounds), &scene, &options).unwrap())
            });
        });
    }
    g.finish();
}

criterion_group!(benches, plan, cube);
criterion_main!(benches);
