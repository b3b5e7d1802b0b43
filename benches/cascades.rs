//! Per-frame cost of the cascade builders: the 4-cascade stable fit (with and
//! without scene bounds), the tight fit, and the convex-body clip; and
//! `cascades_vs_bevy`, the stable and tight fits against a transcription of Bevy's
//! per-frame directional cascade math (`calculate_cascade` and the per-view loop of
//! `build_directional_light_cascades` in `bevy_light`) for the same camera, light and
//! splits, timed in the same run, with the ratios printed.
//!
//! Bevy's per-call code is the work per light: it takes the view's transform and
//! projection as they are, checked elsewhere once per frame. Ours splits the same
//! way: `ValidCamera::new` checks the camera once per frame (timed alone), and
//! `CascadeSet::fit_valid` is the per-light work Bevy's code does (the ratio the
//! comparison is about). A renderer that keeps each light's set (as Bevy keeps each
//! light's `Cascades`) refits it in place with `CascadeSet::refit_valid`, which
//! writes the cascades where they are kept instead of returning a new set; both
//! are timed. `CascadeSet::fit` does the check and the fit in one call (a frame
//! with one light), and is reported too.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use shadowmap::frustum::{
    Aabb, Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, ConvexBody, Projection,
    SceneBounds, SplitScheme, ValidCamera,
};
use std::hint::black_box;
use std::time::Duration;

#[path = "support/bevy_like.rs"]
mod bevy_like;
#[path = "support/timing.rs"]
mod timing;

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

#[allow(clippy::print_stdout)] // The ratios are this bench's output.
fn cascades_vs_bevy(c: &mut Criterion) {
    use bevy_like::{CASCADES, FIRST_FAR, MAP_SIZE, MAX_DISTANCE, MIN_DISTANCE, OVERLAP};
    // Bevy's default perspective camera (fov pi/4, near 0.1, far 1000) at 16:9.
    let (fov_y, aspect) = (core::f32::consts::FRAC_PI_4, 16.0 / 9.0);
    let camera = Camera::look_to(
        Vec3::new(10.0, 1.8, 3.0),
        Vec3::new(0.3, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(fov_y, aspect, 0.1, 1000.0),
    )
    .unwrap();
    let light_dir = Vec3::new(-0.4, -1.0, -0.6).normalize();
    // A light entity looking along `light_dir` (Bevy's lights shine down their -Z).
    let light_rotation = glam::Quat::from_rotation_arc(Vec3::NEG_Z, light_dir);
    let far_bounds = bevy_like::far_bounds();
    let interior = SplitScheme::Custom(far_bounds[..CASCADES - 1].iter().copied().collect());
    let splits = CascadeSplits::new(&interior, CASCADES, MIN_DISTANCE, MAX_DISTANCE)
        .unwrap()
        .with_overlap(OVERLAP)
        .unwrap();
    assert_eq!(*splits.depths().last().unwrap(), MAX_DISTANCE);
    assert!((far_bounds[0] - FIRST_FAR).abs() < 1e-6);
    let stable = CascadeOptions::default().with_resolution(MAP_SIZE as u32);
    let tight = stable.with_fit(CascadeFit::Tight);
    let world_from_view = camera.world_from_view;

    // Each output is kept where it was returned (`black_box` of a reference): no
    // side is charged for moving it out of a `Result` or a return slot.
    let bevy_cascades = || {
        bevy_like::cascades(
            black_box(light_rotation),
            black_box(world_from_view),
            fov_y,
            aspect,
            &far_bounds,
        )
    };
    let bevy = || {
        black_box(&bevy_cascades());
    };
    let ours = |o: &CascadeOptions| {
        let set = CascadeSet::fit(black_box(&camera), black_box(light_dir), &splits, o);
        black_box(set.as_ref().unwrap());
    };
    // Per frame: the camera checked once, shared by every light.
    let frame = || {
        black_box(ValidCamera::new(black_box(&camera)).as_ref().unwrap());
    };
    let valid = ValidCamera::new(&camera).unwrap();
    // Per light: the work Bevy's per-call code does.
    let per_light = |o: &CascadeOptions| {
        let set = CascadeSet::fit_valid(black_box(&valid), black_box(light_dir), &splits, o);
        black_box(set.as_ref().unwrap());
    };
    // Per light, into the set a renderer keeps for the light (as Bevy keeps its
    // `Cascades` component): refitted in place every frame.
    let mut kept_stable = CascadeSet::fit_valid(&valid, light_dir, &splits, &stable).unwrap();
    let mut kept_tight = CascadeSet::fit_valid(&valid, light_dir, &splits, &tight).unwrap();
    let refit = |set: &mut CascadeSet, o: &CascadeOptions| {
        let fitted = set.refit_valid(black_box(&valid), black_box(light_dir), &splits, o);
        fitted.unwrap();
        black_box(&*set);
    };
    // Both cover the same slices with maps of the same size.
    let (b, s) = (
        bevy_cascades(),
        CascadeSet::fit(&camera, light_dir, &splits, &stable).unwrap(),
    );
    for (bc, sc) in b.iter().zip(&s.cascades) {
        assert!(bc.texel_size > 0.0 && sc.texel_world_size > 0.0);
        assert!(bc.clip_from_world.is_finite() && bc.world_from_cascade.is_finite());
        assert!(bc.clip_from_cascade.is_finite());
    }

    let mut g = c.benchmark_group("cascades_vs_bevy");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    g.bench_function("bevy_4", |bch| bch.iter(bevy));
    g.bench_function("stable_fit_4_per_light", |bch| {
        bch.iter(|| per_light(&stable));
    });
    g.bench_function("tight_fit_4_per_light", |bch| {
        bch.iter(|| per_light(&tight));
    });
    g.bench_function("stable_refit_4_per_light", |bch| {
        bch.iter(|| refit(&mut kept_stable, &stable));
    });
    g.bench_function("tight_refit_4_per_light", |bch| {
        bch.iter(|| refit(&mut kept_tight, &tight));
    });
    g.bench_function("camera_per_frame", |bch| bch.iter(frame));
    g.bench_function("stable_fit_4", |bch| bch.iter(|| ours(&stable)));
    g.bench_function("tight_fit_4", |bch| bch.iter(|| ours(&tight)));
    g.finish();

    // One run, interleaved so that a change in the machine's load falls on all.
    let mut t = [f64::INFINITY; 8];
    for _ in 0..3 {
        let round = [
            timing::min_ns(bevy),
            timing::min_ns(|| per_light(&stable)),
            timing::min_ns(|| per_light(&tight)),
            timing::min_ns(|| refit(&mut kept_stable, &stable)),
            timing::min_ns(|| refit(&mut kept_tight, &tight)),
            timing::min_ns(frame),
            timing::min_ns(|| ours(&stable)),
            timing::min_ns(|| ours(&tight)),
        ];
        for (best, x) in t.iter_mut().zip(round) {
            *best = best.min(x);
        }
    }
    let [
        t_bevy,
        t_stable,
        t_tight,
        t_stable_refit,
        t_tight_refit,
        t_frame,
        t_stable_all,
        t_tight_all,
    ] = t;
    println!("cascades_vs_bevy (time per call, fastest of 3 x 201 batches):");
    println!("  bevy_4 (per light)          {t_bevy:>7.0} ns");
    for (name, ns) in [
        ("stable_fit_4 per light", t_stable),
        ("tight_fit_4 per light", t_tight),
        ("stable refit_4 per light", t_stable_refit),
        ("tight refit_4 per light", t_tight_refit),
        ("camera check per frame", t_frame),
        ("stable_fit_4 with check", t_stable_all),
        ("tight_fit_4 with check", t_tight_all),
    ] {
        println!("  {name:<27} {ns:>7.0} ns  {:>5.2}x bevy", ns / t_bevy);
    }
}

criterion_group!(benches, cascades, cascades_vs_bevy);
criterion_main!(benches);
