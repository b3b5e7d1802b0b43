//! Per-frame cost of the umbrella's stateful fits of a directional light
//! (`shadowmap::fit_with_state`): LiSPSM with and without the eye samples (which it
//! measures its strength on), the stable, tight and warped cascades with their
//! count chosen from the predicted error (also given the eye samples of a 160 x 90
//! G-buffer, which they measure each count on, the warped ones at the strength
//! each count measures finest at), and
//! `auto`, which fits all seven candidates and predicts their error (or, given the
//! samples, measures it on them), and the stable cascades from a fresh state (every
//! map sized, its orientation ranked on the samples where given); each beside the
//! uniform fit timed in the same run. Besides
//! criterion's figures it prints each fit's time per call (the fastest of many short
//! batches, see `support/timing.rs`) and its ratio to the uniform fit. `FIT_STATE_ONLY`
//! runs one fit for instruction counting (see `only`).

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, DepthBounds, Light, Projection, SceneBounds};
use shadowmap::rtw::EyeSample;
use shadowmap::{CascadePlan, FitInput, FitState, Technique, fit_with_state};
use std::hint::black_box;

#[path = "support/timing.rs"]
mod timing;

/// A street view: a camera 2 m over a 400 m ground with 40 m of casters, the sun
/// from the side and above, the depth bounds of what it sees.
fn frame() -> (Camera, Light, SceneBounds, DepthBounds) {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.1, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
    )
    .unwrap();
    let ground = Aabb::new(Vec3::new(-200.0, -1.0, -300.0), Vec3::new(200.0, 0.0, 10.0));
    let casters = ground.union(&Aabb::new(
        Vec3::new(-200.0, 0.0, -300.0),
        Vec3::new(200.0, 40.0, 10.0),
    ));
    let light = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let bounds = DepthBounds {
        min: 2.0,
        max: 280.0,
    };
    (camera, light, SceneBounds::new(ground, casters), bounds)
}

/// With `FIT_STATE_ONLY=<name>` (and `FIT_STATE_CALLS=<n>`, default 1), fits that
/// technique `n` times and times nothing, for instruction counts
/// (`timing::only_request`).
fn only(techniques: &[(&str, Technique, &FitInput<'_>)]) -> bool {
    let Some((name, calls)) = timing::only_request("FIT_STATE_ONLY", "FIT_STATE_CALLS") else {
        return false;
    };
    let (_, technique, input) = techniques
        .iter()
        .find(|(n, _, _)| *n == name)
        .unwrap_or_else(|| panic!("FIT_STATE_ONLY: no fit {name}"));
    let mut state = FitState::default();
    for _ in 0..calls {
        black_box(fit_with_state(technique, input, &mut state).is_ok());
    }
    true
}

/// What a 160 x 90 G-buffer of the street view holds: where the camera's pixel
/// rays meet the ground (`y = 0`).
fn ground_samples(camera: &Camera) -> Vec<EyeSample> {
    let c = camera.frustum().unwrap().corners;
    let eye = camera.eye();
    let (columns, rows) = (160, 90);
    let mut out = Vec::new();
    for row in 0..rows {
        for column in 0..columns {
            let x = (column as f32 + 0.5) / columns as f32;
            let y = (row as f32 + 0.5) / rows as f32;
            let d = (c[0].lerp(c[1], x).lerp(c[3].lerp(c[2], x), y) - eye).normalize();
            if d.y < -1e-3 {
                let t = -eye.y / d.y;
                out.push(EyeSample {
                    position: eye + d * t,
                    normal: Vec3::Y,
                    eye_distance: t,
                });
            }
        }
    }
    out
}

#[allow(clippy::print_stdout)] // The table is this bench's output.
fn fits(c: &mut Criterion) {
    let (camera, light, scene, bounds) = frame();
    let input = FitInput::new(&camera, &light, scene, 2048 * 2048).with_depth_bounds(Some(bounds));
    let samples = ground_samples(&camera);
    // 90 pixel rows over the vertical field of view of 1 rad.
    let sampled = input
        .with_eye_samples(&samples)
        .with_pixels_per_radian(90.0 / 1.0);
    let plan = CascadePlan::default();
    let warped = Technique::WarpedCascades {
        plan,
        lispsm: Default::default(),
    };
    let techniques = [
        (
            "uniform",
            Technique::UniformFocused(Default::default()),
            &input,
        ),
        ("tight_cascades", Technique::TightCascades(plan), &input),
        ("stable_cascades", Technique::StableCascades(plan), &input),
        ("warped_cascades", warped, &input),
        ("auto", Technique::Auto(plan), &input),
        ("lispsm", Technique::Lispsm(Default::default()), &input),
        (
            "lispsm_on_samples",
            Technique::Lispsm(Default::default()),
            &sampled,
        ),
        ("tight_on_samples", Technique::TightCascades(plan), &sampled),
        (
            "stable_on_samples",
            Technique::StableCascades(plan),
            &sampled,
        ),
        ("warped_on_samples", warped, &sampled),
        ("auto_on_samples", Technique::Auto(plan), &sampled),
    ];
    if only(&techniques) {
        return;
    }
    let mut group = c.benchmark_group("fit_with_state");
    for (name, technique, input) in &techniques {
        let mut state = FitState::default();
        group.bench_function(*name, |b| {
            b.iter(|| fit_with_state(black_box(technique), black_box(input), &mut state));
        });
    }
    // A fresh state each call: what a frame that (re)sizes every stable map costs,
    // its new orientations ranked on the samples where it has them.
    let stable = Technique::StableCascades(plan);
    let fresh = [
        ("stable_fresh", &input),
        ("stable_on_samples_fresh", &sampled),
    ];
    for (name, input) in fresh {
        group.bench_function(name, |b| {
            b.iter(|| fit_with_state(&stable, black_box(input), &mut FitState::default()));
        });
    }
    group.finish();
    let time = |technique: &Technique, input: &FitInput<'_>| {
        let mut state = FitState::default();
        timing::min_ns(|| fit_with_state(technique, input, &mut state))
    };
    let uniform = time(&techniques[0].1, &input);
    println!("\nper-frame fit_with_state, fastest batch (same run):");
    for (name, technique, input) in &techniques {
        let ns = time(technique, input);
        println!(
            "  {name:<16} {:>9.1} us  {:>6.1}x uniform",
            ns / 1e3,
            ns / uniform
        );
    }
    for (name, input) in fresh {
        let ns = timing::min_ns(|| fit_with_state(&stable, input, &mut FitState::default()));
        println!(
            "  {name:<16} {:>9.1} us  {:>6.1}x uniform",
            ns / 1e3,
            ns / uniform
        );
    }
}

criterion_group!(benches, fits);
criterion_main!(benches);
