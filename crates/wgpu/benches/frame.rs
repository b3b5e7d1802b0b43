//! Per-frame CPU work of the backend: packing the uniform blocks with `to_raw` for
//! each technique, subdividing the casters of the city block for RTW, and recording
//! depth passes (needs an adapter; skipped without one).

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use shadowmap::{DpsmOptions, FitInput, Fitted, Shadow, Technique, fit};
use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds};
use shadowmap_rtw::{ImportanceMap, RtwShadow, WarpMaps, WarpOptions};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::depth::{
    DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, RtwSubdivision, ShadowDepthPass,
    subdivide_for_rtw,
};
use shadowmap_wgpu::uniforms::{RtwShadowRaw, ToRaw, cascade_layers, paraboloid_layers};

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 20.0, 40.0),
        Vec3::ZERO,
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.5, 500.0),
    )
    .expect("camera")
}

/// Fits a technique for the bench camera over a 400 m block, `1024²` per layer.
fn fit_bench(technique: &Technique, light: &Light, layers: u64) -> Shadow {
    let cam = camera();
    let scene = SceneBounds::whole(Aabb::new(
        Vec3::new(-200.0, 0.0, -200.0),
        Vec3::new(200.0, 60.0, 200.0),
    ));
    fit(
        technique,
        &FitInput::new(&cam, light, scene, layers * 1024 * 1024),
    )
    .unwrap_or_else(|e| panic!("{}: {e}", technique.name()))
}

fn packing(c: &mut Criterion) {
    let sun = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let uniform = fit_bench(&Technique::UniformFocused(Default::default()), &sun, 1);
    let uniform = *uniform.transform().expect("uniform");
    let xpsm = fit_bench(&Technique::Xpsm(Default::default()), &sun, 1);
    let Fitted::Xpsm(x) = xpsm.fitted() else {
        panic!("xpsm");
    };
    let cascades = fit_bench(&Technique::StableCascades(Default::default()), &sun, 4);
    let Fitted::Cascades(set) = cascades.fitted() else {
        panic!("cascades");
    };
    assert_eq!(set.cascades.len(), 4);
    let lamp = Light::Point {
        position: Vec3::new(0.0, 10.0, 0.0),
        range: 300.0,
    };
    let dpsm = fit_bench(
        &Technique::Dpsm(DpsmOptions::default().with_near(0.1)),
        &lamp,
        2,
    );
    let map = dpsm.paraboloid().expect("paraboloid");
    let mut importance = ImportanceMap::new(256, 256).expect("map");
    let _ = importance.splat(Vec2::new(0.5, 0.5), 1.0);
    let mut warps = WarpMaps::new(256, 256).expect("warps");
    warps
        .build(&importance, &WarpOptions::default())
        .expect("build");
    let rtw = RtwShadow {
        base: uniform,
        warps: &warps,
    };

    let mut g = c.benchmark_group("pack");
    g.bench_function("uniform", |b| {
        b.iter(|| black_box(black_box(&uniform).to_raw()));
    });
    g.bench_function("xpsm", |b| b.iter(|| black_box(black_box(x).to_raw())));
    g.bench_function("cascades_lookup_4", |b| {
        b.iter(|| black_box(black_box(set).to_raw()));
    });
    g.bench_function("cascades_layers_4", |b| {
        b.iter(|| black_box(cascade_layers(black_box(set))));
    });
    g.bench_function("paraboloid_layers", |b| {
        b.iter(|| black_box(paraboloid_layers(black_box(map))));
    });
    g.bench_function("rtw_256", |b| {
        b.iter(|| {
            let r = black_box(&rtw);
            black_box((r.to_raw(), RtwShadowRaw::tables(r)))
        });
    });
    g.finish();

    // RTW casters: the city block (5264 triangles) into a 2048² map over 256-cell
    // tables, redone whenever the tables change (every frame).
    let city: Vec<[Vec3; 3]> = shadowmap_eval::scene::Scene::city_block(1)
        .mesh
        .triangles()
        .map(|t| t.map(glam::DVec3::as_vec3))
        .collect();
    let subdivision = RtwSubdivision::default().with_resolution(2048);
    let mut casters = Vec::new();
    let pieces = subdivide_for_rtw(&rtw, &city, &subdivision, &mut casters);
    eprintln!("subdivide_rtw: {} -> {pieces} triangles", city.len());
    c.bench_function("subdivide_rtw/city_block_256_cells_2048", |b| {
        b.iter(|| {
            black_box(subdivide_for_rtw(
                black_box(&rtw),
                black_box(&city),
                &subdivision,
                &mut casters,
            ))
        });
    });

    // Command encoding needs a device; without an adapter only packing is measured.
    let Ok(ctx) = GpuContext::new_headless() else {
        eprintln!("frame bench: no adapter, encoding not measured");
        return;
    };
    let ground = [
        [
            Vec3::new(-100.0, 0.0, -100.0),
            Vec3::new(100.0, 0.0, -100.0),
            Vec3::new(100.0, 0.0, 100.0),
        ],
        [
            Vec3::new(-100.0, 0.0, -100.0),
            Vec3::new(100.0, 0.0, 100.0),
            Vec3::new(-100.0, 0.0, 100.0),
        ],
    ];
    let Ok(mesh) = MeshBuffers::from_triangles(&ctx, &ground) else {
        return;
    };
    let layers = cascade_layers(set);
    let desc = DepthPassDesc::new(DepthTechnique::Matrix, 1024).with_layers(layers.len() as u32);
    let Ok(mut pass) = ShadowDepthPass::new(&ctx, &desc) else {
        return;
    };
    c.bench_function("encode/cascades_4_depth_passes", |b| {
        b.iter(|| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let r = pass.encode(
                &ctx,
                &mut encoder,
                &[&mesh],
                &DepthUniforms::Matrix(&layers),
            );
            black_box((r.is_ok(), encoder.finish()))
        });
    });
    let tables = RtwShadowRaw::tables(&rtw);
    let rtw_desc = DepthPassDesc::new(DepthTechnique::Rtw, 2048);
    let Ok(mut rtw_pass) = ShadowDepthPass::new(&ctx, &rtw_desc) else {
        return;
    };
    let rtw_uniforms = DepthUniforms::Rtw {
        raw: rtw.to_raw(),
        tables: &tables,
    };
    c.bench_function("encode/rtw_depth_pass_256_cell_tables", |b| {
        b.iter(|| {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let r = rtw_pass.encode(&ctx, &mut encoder, &[&mesh], &rtw_uniforms);
            black_box((r.is_ok(), encoder.finish()))
        });
    });
}

criterion_group!(benches, packing);
criterion_main!(benches);
