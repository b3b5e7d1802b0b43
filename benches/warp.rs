//! Per-frame cost of the `shadowmap-warp` builders (uniform focused, LiSPSM, XPSM,
//! TSM, four warped cascades, and all four single-frustum fits from one shared
//! `FocusBody`), each also reported as a ratio to the uniform-focused fit timed in the
//! same run.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use shadowmap::frustum::{Aabb, Camera, CascadeSplits, Projection, SplitScheme};
use shadowmap::warp::{
    FocusBody, LispsmOptions, SceneBounds, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
};
use std::hint::black_box;
use std::time::{Duration, Instant};

struct Setup {
    camera: Camera,
    light: Vec3,
    scene: SceneBounds,
    splits: CascadeSplits,
}

fn setup() -> Setup {
    let camera = Camera::look_to(
        Vec3::new(10.0, 1.8, 3.0),
        Vec3::new(0.3, -0.15, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.1, 500.0),
    )
    .unwrap();
    let ground = Aabb::new(
        Vec3::new(-600.0, -1.0, -600.0),
        Vec3::new(600.0, 0.0, 600.0),
    );
    let scene = SceneBounds::new(
        ground,
        ground.union(&Aabb::new(Vec3::ZERO, Vec3::splat(80.0))),
    );
    let splits =
        CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 500.0).unwrap();
    Setup {
        camera,
        light: Vec3::new(-0.4, -1.0, -0.6),
        scene,
        splits,
    }
}

fn run(s: &Setup, which: usize) {
    match which {
        0 => {
            black_box(
                uniform_focused(
                    black_box(&s.camera),
                    black_box(s.light),
                    &s.scene,
                    &UniformOptions::default(),
                )
                .unwrap(),
            );
        }
        1 => {
            black_box(
                lispsm(
                    black_box(&s.camera),
                    black_box(s.light),
                    &s.scene,
                    &LispsmOptions::default(),
                )
                .unwrap(),
            );
        }
        2 => {
            black_box(
                xpsm(
                    black_box(&s.camera),
                    black_box(s.light),
                    &s.scene,
                    &XpsmOptions::default(),
                )
                .unwrap(),
            );
        }
        3 => {
            black_box(
                tsm(
                    black_box(&s.camera),
                    black_box(s.light),
                    &s.scene,
                    &TsmOptions::default(),
                )
                .unwrap(),
            );
        }
        5 => {
            let body = FocusBody::new(black_box(&s.camera), black_box(s.light), &s.scene).unwrap();
            black_box(body.uniform(&UniformOptions::default()).unwrap());
            black_box(body.lispsm(&LispsmOptions::default()).unwrap());
            black_box(body.xpsm(&XpsmOptions::default()).unwrap());
            black_box(body.tsm(&TsmOptions::default()).unwrap());
        }
        4 => {
            black_box(
                warped_cascades(
                    black_box(&s.camera),
                    black_box(s.light),
                    &s.scene,
                    &s.splits,
                    &[0.0, 0.0, -0.5, -1.0],
                    &LispsmOptions::default(),
                )
                .unwrap(),
            );
        }
        _ => unreachable!("no bench {which}"),
    }
}

const NAMES: [&str; 6] = [
    "uniform_focused",
    "lispsm",
    "xpsm",
    "tsm",
    "warped_cascades_4",
    "focus_body_then_all_four",
];

fn warp(c: &mut Criterion) {
    let s = setup();
    let mut g = c.benchmark_group("warp");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    for (i, name) in NAMES.iter().enumerate() {
        g.bench_function(*name, |b| b.iter(|| run(&s, i)));
    }
    g.finish();

    // Ratios to the uniform fit, timed back to back in this run (median of 7 batches).
    let time = |which: usize| {
        let mut t: Vec<f64> = (0..7)
            .map(|_| {
                let start = Instant::now();
                for _ in 0..2000 {
                    run(&s, which);
                }
                start.elapsed().as_secs_f64() / 2000.0
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[3]
    };
    let base = time(0);
    for (i, name) in NAMES.iter().enumerate() {
        let t = if i == 0 { base } else { time(i) };
        eprintln!(
            "warp/{name}: {:.2} us, {:.2}x uniform_focused",
            t * 1e6,
            t / base
        );
    }
}

criterion_group!(benches, warp);
criterion_main!(benches);
