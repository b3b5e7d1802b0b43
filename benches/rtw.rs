//! RTW importance-to-warp for a 1024 x 1024 importance map, against the memory
//! bandwidth limit: one streaming pass that only sums the same buffer.
//!
//! Besides criterion's two timings, the bench prints their ratio measured in the same
//! run (minimum of many repetitions of each). Goal: at most 1.5x.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec2;
use shadowmap::rtw::{ImportanceMap, WarpMaps, WarpOptions};
use std::hint::black_box;
use std::time::{Duration, Instant};

const SIDE: u32 = 1024;

fn map() -> ImportanceMap {
    let mut map = ImportanceMap::new(SIDE, SIDE).unwrap();
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let values: Vec<f32> = (0..SIDE * SIDE)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32
        })
        .collect();
    map.copy_from_slice(&values).unwrap();
    map.splat(Vec2::new(0.3, 0.6), 50.0).unwrap();
    map
}

/// The bandwidth baseline: one pass summing the buffer with `LANES` independent
/// accumulators. With 8 lanes the sum is bound by the latency of the adds; with 32 it
/// runs at the speed of the loads (the stricter baseline, reported as the ratio).
fn streaming_sum<const LANES: usize>(cells: &[f32]) -> f32 {
    let mut acc = [0.0f32; LANES];
    let mut chunks = cells.chunks_exact(LANES);
    for c in &mut chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            *a += x;
        }
    }
    acc.iter().sum::<f32>() + chunks.remainder().iter().sum::<f32>()
}

fn min_time(mut f: impl FnMut(), reps: usize) -> Duration {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed()
        })
        .min()
        .unwrap_or_default()
}

fn rtw(c: &mut Criterion) {
    let map = map();
    let mut warps = WarpMaps::new(SIDE, SIDE).unwrap();
    let options = WarpOptions::default();

    let mut g = c.benchmark_group("rtw");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(2));
    g.bench_function("importance_to_warp_1024", |b| {
        b.iter(|| warps.build(black_box(&map), &options).unwrap());
    });
    g.bench_function("streaming_sum_1024", |b| {
        b.iter(|| streaming_sum::<32>(black_box(map.as_slice())));
    });
    g.bench_function("streaming_sum_1024_8_lanes", |b| {
        b.iter(|| streaming_sum::<8>(black_box(map.as_slice())));
    });
    g.finish();

    let sum = |lanes8: bool| {
        if lanes8 {
            streaming_sum::<8>(black_box(map.as_slice()))
        } else {
            streaming_sum::<32>(black_box(map.as_slice()))
        }
    };
    let build = min_time(|| warps.build(black_box(&map), &options).unwrap(), 300);
    let sum32 = min_time(
        || {
            black_box(sum(false));
        },
        300,
    );
    let sum8 = min_time(
        || {
            black_box(sum(true));
        },
        300,
    );
    let ratio = |a: Duration, b: Duration| a.as_secs_f64() / b.as_secs_f64();
    eprintln!(
        "rtw (cache-resident, min of 300): importance_to_warp_1024 {build:?}; streaming sum \
         {sum32:?} (32 lanes), {sum8:?} (8 lanes); ratio {:.2}x (32 lanes), {:.2}x (8 lanes); \
         goal <= 1.5x",
        ratio(build, sum32),
        ratio(build, sum8)
    );

    // Cold: evict the map from every cache level (the L3 of a server part is tens of
    // MiB) before each timed pass, so both run at memory bandwidth.
    let mut scrub = vec![0u8; 128 << 20];
    let mut cold = |f: &mut dyn FnMut()| {
        let mut times: Vec<Duration> = (0..25u8)
            .map(|i| {
                scrub.fill(i);
                black_box(&scrub);
                let t = Instant::now();
                f();
                t.elapsed()
            })
            .collect();
        times.sort();
        times[times.len() / 2]
    };
    let build_cold = cold(&mut || warps.build(black_box(&map), &options).unwrap());
    let sum_cold = cold(&mut || {
        black_box(sum(false));
    });
    eprintln!(
        "rtw (cold cache, median of 25): importance_to_warp_1024 {build_cold:?}; streaming sum \
         {sum_cold:?} (32 lanes); ratio {:.2}x",
        ratio(build_cold, sum_cold)
    );
}

criterion_group!(benches, rtw);
criterion_main!(benches);
