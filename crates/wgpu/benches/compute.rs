//! Compute passes: depth min/max reduction and the RTW pipeline.
//!
//! Always measured (no GPU needed): the CPU references (`RawDepthRange::from_depths`,
//! `ImportanceMap::accumulate_backward` + `WarpMaps::build`) on the same inputs.
//! With an adapter: the CPU cost of recording each pass (`encode` + `finish`), and the
//! GPU round trip (submit, wait, read back). Without one, those are skipped with a
//! notice.
//!
//! `cargo bench -p shadowmap-wgpu --bench compute`

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DVec3, Vec3};
use shadowmap_frustum::{LightDirection, ShadowTransform, projection};
use shadowmap_rtw::{EyeSample, ImportanceMap, ImportanceOptions, WarpMaps, WarpOptions};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::reduce::{DepthReduction, RawDepthRange};
use shadowmap_wgpu::rtw::{GpuRtw, RtwGBufferTextures};

const DEPTH_SIZE: (u32, u32) = (1280, 720);
const GBUFFER_SIZE: (u32, u32) = (640, 360);
const MAP_SIZE: (u32, u32) = (512, 512);

fn depths() -> Vec<f32> {
    let (w, h) = DEPTH_SIZE;
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if y < h / 3 {
                1.0
            } else {
                (x as f32 * 0.37 + y as f32 * 0.11).fract()
            }
        })
        .collect()
}

fn base() -> ShadowTransform {
    let dir = DVec3::new(0.3, -1.0, 0.2).normalize();
    let light_from_world = projection::look_to(-dir * 20.0, dir, DVec3::Y);
    let clip_from_light = projection::orthographic(-12.0, 12.0, -12.0, 12.0, 1.0, 40.0, false);
    ShadowTransform::new(
        light_from_world.as_mat4(),
        (clip_from_light * light_from_world).as_mat4(),
        false,
        LightDirection::Directional(dir.as_vec3()),
    )
}

fn samples() -> Vec<EyeSample> {
    let (w, h) = GBUFFER_SIZE;
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            EyeSample {
                position: Vec3::new(20.0 * x - 10.0, 0.0, -20.0 * y * y + 10.0),
                normal: Vec3::Y,
                eye_distance: 1.0 + 50.0 * y,
            }
        })
        .collect()
}

fn cpu_references(c: &mut Criterion) {
    let depths = depths();
    c.bench_function("cpu/depth_min_max_1280x720", |b| {
        b.iter(|| RawDepthRange::from_depths(black_box(&depths), false));
    });
    let samples = samples();
    let base = base();
    let mut map = ImportanceMap::new(MAP_SIZE.0, MAP_SIZE.1).expect("map");
    let mut warps = WarpMaps::new(MAP_SIZE.0, MAP_SIZE.1).expect("warps");
    let (importance, warp) = (ImportanceOptions::default(), WarpOptions::default());
    c.bench_function("cpu/rtw_640x360_samples_to_512x512_tables", |b| {
        b.iter(|| {
            map.clear();
            map.accumulate_backward(&base, black_box(&samples), None, &importance)
                .expect("accumulate");
            warps.build(&map, &warp).expect("build");
        });
    });
}

fn gpu_passes(c: &mut Criterion) {
    let ctx = match GpuContext::new_headless() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("compute bench: no GPU adapter ({e}); GPU passes not measured");
            return;
        }
    };
    eprintln!("compute bench: adapter {}", ctx.describe());
    let (w, h) = DEPTH_SIZE;
    let depth = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("bench depth"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let mut reduction = DepthReduction::new(&ctx, false);
    c.bench_function("encode/depth_reduction_1280x720", |b| {
        b.iter(|| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            reduction
                .encode(&ctx, &mut encoder, &depth)
                .expect("encode");
            black_box(encoder.finish())
        });
    });
    c.bench_function("gpu/depth_reduction_1280x720_round_trip", |b| {
        b.iter(|| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            reduction
                .encode(&ctx, &mut encoder, &depth)
                .expect("encode");
            ctx.queue.submit([encoder.finish()]);
            black_box(reduction.read(&ctx).expect("read"))
        });
    });

    let texels: Vec<Option<EyeSample>> = samples().into_iter().map(Some).collect();
    let gbuffer =
        RtwGBufferTextures::from_samples(&ctx, GBUFFER_SIZE.0, GBUFFER_SIZE.1, &texels, None)
            .expect("gbuffer");
    let rtw = GpuRtw::new(
        &ctx,
        MAP_SIZE.0,
        MAP_SIZE.1,
        &WarpOptions::default(),
        &ImportanceOptions::default(),
    )
    .expect("rtw");
    let base = base();
    c.bench_function("encode/rtw_640x360_to_512x512", |b| {
        b.iter(|| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            rtw.encode(&ctx, &mut encoder, &gbuffer.as_gbuffer(), &base)
                .expect("encode");
            black_box(encoder.finish())
        });
    });
    c.bench_function("gpu/rtw_640x360_to_512x512_round_trip", |b| {
        b.iter(|| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            rtw.encode(&ctx, &mut encoder, &gbuffer.as_gbuffer(), &base)
                .expect("encode");
            ctx.queue.submit([encoder.finish()]);
            black_box(rtw.read_tables(&ctx).expect("read"))
        });
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    targets = cpu_references, gpu_passes
}
criterion_main!(benches);
