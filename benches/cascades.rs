//! Per-frame cost of the cascade builders: the 4-cascade stable fit (with and
//! without scene bounds), the tight fit, and the convex-body clip.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use shadowmap::frustum::{
    Aabb, Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, ConvexBody, Projection,
    SceneBounds, SplitScheme,
};
use std::hint::black_box;
use std::time::Duration;

fn cascades(c: &mut Criterion) {
    let camera = Camera::look_to(
        Vec3::new(10.0, 1.8, 3.0),
        Vec3::new(0.3, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.1, 500.0),
    )
    .unwrap();
    let light = Vec3::new(-0.4, -1.0, -0.6);
    let splits =
        CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 500.0).unwrap();
    let ground = Aabb::new(
        Vec3::new(-600.0, -1.0, -600.0),
        Vec3::new(600.0, 0.0, 600.0),
    );
    let scene = SceneBounds {
        receivers: ground,
        casters: ground.union(&Aabb::new(Vec3::ZERO, Vec3::splat(80.0))),
    };
    let stable = CascadeOptions::default();

    let mut g = c.benchmark_group("cascades");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    g.bench_function("stable_fit_4", |b| {
        b.iter(|| CascadeSet::fit(black_box(&camera), black_box(light), &splits, &stable).unwrap());
    });
    g.bench_function("stable_fit_4_scene", |b| {
        let o = stable.with_scene(Some(scene));
        b.iter(|| CascadeSet::fit(black_box(&camera), black_box(light), &splits, &o).unwrap());
    });
    g.bench_function("tight_fit_4", |b| {
        let o = stable.with_fit(CascadeFit::Tight);
        b.iter(|| CascadeSet::fit(black_box(&camera), black_box(light), &splits, &o).unwrap());
    });
    let frustum = camera.frustum().unwrap();
    g.bench_function("convex_body_clip", |b| {
        b.iter(|| ConvexBody::from_frustum_aabb(black_box(&frustum), black_box(&ground)).unwrap());
    });
    g.bench_function("convex_body_clip_extrude", |b| {
        b.iter(|| {
            ConvexBody::from_frustum_aabb(black_box(&frustum), black_box(&ground))
                .unwrap()
                .extruded_toward_light(light, &scene.casters)
                .unwrap()
        });
    });
    g.finish();
}

criterion_group!(benches, cascades);
criterion_main!(benches);
