//! Per-frame CPU work of the backend: packing the uniform blocks with `to_raw` for
//! each technique, subdividing the casters of the city block for RTW, and recording
//! depth passes (needs an adapter; skipped without one). `rtw_frame_cpu`: the CPU
//! cost of a whole RTW frame with the tables built and the casters refined on the
//! GPU; `ipsm_frame_cpu`: the same for IPSM (and DPSM beside it), the casters refined
//! against the paraboloid on the GPU; `cube_rtw_frame_cpu`: the same for RTW over
//! the cube faces of a lamp, and its fit.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use shadowmap::paraboloid::{
    CubeOptions, CubeOrientation, FaceSizes, IpsmOptions, IpsmPlan, ParaboloidMap, Side,
    SubdivisionOptions, subdivide_triangles,
};
use shadowmap::{DpsmOptions, FitInput, Fitted, Shadow, Technique, fit};
use shadowmap_frustum::{
    Aabb, Camera, DepthBounds, Light, Projection, SceneBounds, ShadowTransform,
};
use shadowmap_rtw::{
    EyeSample, ImportanceMap, ImportanceOptions, RtwShadow, WarpMaps, WarpOptions,
};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::depth::{
    DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, RtwSubdivision, ShadowDepthPass,
    subdivide_for_rtw,
};
use shadowmap_wgpu::refine::{GpuRefine, RefineOptions};
use shadowmap_wgpu::rtw::{GpuRtw, RtwGBufferTextures};
use shadowmap_wgpu::uniforms::{
    ParaboloidLayerRaw, RtwShadowRaw, ToRaw, cascade_layers, paraboloid_layers, warped_cube,
};

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
        .triangles_f32();
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

/// The city block's casters as a triangle soup.
fn city_casters() -> Vec<[Vec3; 3]> {
    shadowmap_eval::scene::Scene::city_block(1)
        .mesh
        .triangles_f32()
}

/// A `width x height` G-buffer of the bench camera looking at the ground plane of
/// the block (`y = 0`, `|x|, |z| <= 200`): one eye sample per pixel that hits it.
fn ground_gbuffer(width: u32, height: u32) -> Vec<Option<EyeSample>> {
    let cam = camera();
    let world_from_clip = cam.clip_from_world().expect("camera").inverse();
    let eye = cam.eye();
    let pixel = |x: u32, y: u32| {
        let ndc_x = 2.0 * (x as f32 + 0.5) / width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * (y as f32 + 0.5) / height as f32;
        let through = world_from_clip.project_point3(Vec3::new(ndc_x, ndc_y, 0.5));
        let direction = through - eye;
        let t = -eye.y / direction.y;
        let hit = eye + direction * t;
        (direction.y < 0.0 && hit.x.abs() <= 200.0 && hit.z.abs() <= 200.0).then(|| EyeSample {
            position: hit,
            normal: Vec3::Y,
            eye_distance: hit.distance(eye),
        })
    };
    (0..height)
        .flat_map(|y| (0..width).map(move |x| pixel(x, y)))
        .collect()
}

/// One RTW frame's GPU objects: the G-buffer, the table build, the refinement and
/// the depth pass.
struct RtwFrame {
    gbuffer: RtwGBufferTextures,
    rtw: GpuRtw,
    refine: GpuRefine,
    pass: ShadowDepthPass,
    base: ShadowTransform,
}

impl RtwFrame {
    /// Records the frame: tables, refinement, indirect depth pass.
    fn record(&mut self, ctx: &GpuContext) -> (bool, wgpu::CommandBuffer) {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let recorded = self
            .rtw
            .encode(ctx, &mut encoder, &self.gbuffer.as_gbuffer(), &self.base)
            .and_then(|()| {
                let uniforms = self.rtw.depth_uniforms(&self.base);
                self.refine.encode(ctx, &mut encoder, &uniforms)?;
                self.pass
                    .encode_refined(ctx, &mut encoder, &self.refine, &uniforms)
            });
        (recorded.is_ok(), encoder.finish())
    }
}

/// CPU time to prepare and record one RTW frame of the city block into a 2048² map:
/// importance, blur and 256-cell tables on the GPU ([`GpuRtw::encode`]), the casters
/// refined on the GPU ([`GpuRefine::encode`]), the depth pass drawn indirectly
/// ([`ShadowDepthPass::encode_refined`]), the command buffer finished and the frame's
/// uploads flushed (`submit([])`). The frame's command buffer itself is not submitted:
/// on a software adapter its execution is CPU rasterization, not CPU cost of the
/// frame. No read-back. The G-buffer's size only changes a dispatch count.
fn rtw_frame_cpu(c: &mut Criterion) {
    let Ok(ctx) = GpuContext::new_headless() else {
        eprintln!("rtw_frame_cpu: no adapter, not measured");
        return;
    };
    let sun = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let base = *fit_bench(&Technique::UniformFocused(Default::default()), &sun, 4)
        .transform()
        .expect("uniform");
    let (width, height) = (480, 270);
    let casters = city_casters();
    let options =
        RefineOptions::default().with_subdivision(RtwSubdivision::default().with_resolution(2048));
    let setup = ctx.scoped(|ctx| {
        let samples = ground_gbuffer(width, height);
        Ok(RtwFrame {
            gbuffer: RtwGBufferTextures::from_samples(ctx, width, height, &samples, None)?,
            rtw: GpuRtw::new(
                ctx,
                256,
                256,
                &WarpOptions::default(),
                &ImportanceOptions::default(),
            )?,
            refine: GpuRefine::new(ctx, &casters, &options)?,
            pass: ShadowDepthPass::new(ctx, &DepthPassDesc::new(DepthTechnique::Rtw, 2048))?,
            base,
        })
    });
    let mut frame = match setup {
        Ok(frame) => frame,
        Err(e) => {
            eprintln!("rtw_frame_cpu: setup failed: {e}");
            return;
        }
    };
    // One frame run for real, to report what it draws.
    let (ok, commands) = frame.record(&ctx);
    ctx.queue.submit([commands]);
    match frame.refine.read_stats(&ctx) {
        Ok(stats) if ok => eprintln!("rtw_frame_cpu: {} casters -> {stats:?}", casters.len()),
        other => eprintln!("rtw_frame_cpu: frame failed: {other:?}"),
    }
    let mut g = c.benchmark_group("rtw_frame_cpu");
    g.bench_function("city_block_2048_tables_256_gpu_refine", |b| {
        b.iter(|| {
            let recorded = black_box(frame.record(&ctx));
            ctx.queue.submit([]);
            recorded.0
        });
    });
    g.finish();
}

/// One paraboloid frame's GPU objects: the refinement and the depth pass.
struct ParaboloidFrame {
    refine: GpuRefine,
    pass: ShadowDepthPass,
}

impl ParaboloidFrame {
    fn new(ctx: &GpuContext, casters: &[[Vec3; 3]], layers: u32) -> Result<Self, String> {
        let options = RefineOptions::default().with_resolution(2048);
        let desc = DepthPassDesc::new(DepthTechnique::Paraboloid, 2048).with_layers(layers);
        ctx.scoped(|ctx| {
            Ok(Self {
                refine: GpuRefine::new(ctx, casters, &options)?,
                pass: ShadowDepthPass::new(ctx, &desc)?,
            })
        })
        .map_err(|e| e.to_string())
    }

    /// The frame's objects, with one frame run for real to report what it draws.
    fn run_once(
        ctx: &GpuContext,
        casters: &[[Vec3; 3]],
        name: &str,
        map: &ParaboloidMap,
    ) -> Result<Self, String> {
        let mut frame = Self::new(ctx, casters, map.layers())?;
        let (ok, commands) = frame.record(ctx, map);
        ctx.queue.submit([commands]);
        match frame.refine.read_stats(ctx) {
            Ok(stats) if ok => eprintln!(
                "ipsm_frame_cpu: {name}, {} side(s): {} casters -> {stats:?}",
                map.layers(),
                casters.len()
            ),
            other => eprintln!("ipsm_frame_cpu: {name} frame failed: {other:?}"),
        }
        Ok(frame)
    }

    /// Records the frame: the blocks packed, the casters refined, the indirect depth
    /// pass (one layer per side).
    fn record(&mut self, ctx: &GpuContext, map: &ParaboloidMap) -> (bool, wgpu::CommandBuffer) {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let layers: Vec<ParaboloidLayerRaw> = paraboloid_layers(map);
        let uniforms = DepthUniforms::Paraboloid(&layers);
        let recorded = self
            .refine
            .encode(ctx, &mut encoder, &uniforms)
            .and_then(|()| {
                self.pass
                    .encode_refined(ctx, &mut encoder, &self.refine, &uniforms)
            });
        (recorded.is_ok(), encoder.finish())
    }
}

/// CPU time to prepare and record one IPSM frame of the city block into a 2048² map:
/// the plan fitted (`IpsmPlan::new`: truncated frustum, exact cone, cut), its blocks
/// packed, the casters refined against the paraboloid on the GPU
/// ([`GpuRefine::encode`]) and the depth pass drawn indirectly
/// ([`ShadowDepthPass::encode_refined`]), the command buffer finished and the
/// frame's uploads flushed (`submit([])`); the frame itself is not submitted (on a
/// software adapter its execution is CPU rasterization). DPSM beside it: the same
/// frame with two sides and a fixed map (no fit). The baseline, measured in the same
/// run: the CPU subdivision of the casters for the IPSM side
/// (`subdivide_paraboloid`), which the renderer did every frame before.
fn ipsm_frame_cpu(c: &mut Criterion) {
    let cam = camera();
    // Behind and above the camera, outside the truncated frustum: one cut paraboloid.
    let lamp = Light::Point {
        position: Vec3::new(-30.0, 80.0, 120.0),
        range: 600.0,
    };
    let bounds = DepthBounds {
        min: 5.0,
        max: 250.0,
    };
    let options = IpsmOptions::default();
    let casters = city_casters();
    let ipsm = IpsmPlan::new(&lamp, &cam, Some(bounds), &options).expect("ipsm");
    let dpsm = ParaboloidMap::dual(
        Vec3::new(-30.0, 80.0, 120.0),
        Vec3::NEG_Y,
        0.5,
        600.0,
        &Default::default(),
    )
    .expect("dpsm");
    // The baseline in the same run: the CPU subdivision the GPU refinement replaces
    // (what the renderer uploaded every frame before).
    let sub = SubdivisionOptions::default().with_resolution(2048);
    let mut pieces = Vec::new();
    let n = subdivide_triangles(&ipsm.map, Side::Front, &casters, &sub, &mut pieces);
    eprintln!("subdivide_paraboloid: {} -> {n:?} triangles", casters.len());
    c.bench_function("subdivide_paraboloid/city_block_ipsm_2048", |b| {
        b.iter(|| {
            black_box(subdivide_triangles(
                black_box(&ipsm.map),
                Side::Front,
                black_box(&casters),
                &sub,
                &mut pieces,
            ))
        });
    });
    let Ok(ctx) = GpuContext::new_headless() else {
        eprintln!("ipsm_frame_cpu: no adapter, not measured");
        return;
    };
    let frames = [("ipsm", ipsm.map), ("dpsm", dpsm)]
        .into_iter()
        .map(|(name, map)| ParaboloidFrame::run_once(&ctx, &casters, name, &map))
        .collect::<Result<Vec<_>, _>>();
    let mut frames = match frames {
        Ok(frames) => frames,
        Err(e) => {
            eprintln!("ipsm_frame_cpu: setup failed: {e}");
            return;
        }
    };
    let [ipsm_frame, dpsm_frame] = &mut frames[..] else {
        return;
    };
    let mut g = c.benchmark_group("ipsm_frame_cpu");
    g.bench_function("city_block_2048_fit_and_gpu_refine", |b| {
        b.iter(|| {
            let plan = IpsmPlan::new(&lamp, &cam, Some(bounds), &options);
            let recorded = match &plan {
                Ok(plan) => black_box(ipsm_frame.record(&ctx, &plan.map)).0,
                Err(_) => false,
            };
            ctx.queue.submit([]);
            recorded
        });
    });
    g.bench_function("dpsm_city_block_2048_gpu_refine", |b| {
        b.iter(|| {
            let recorded = black_box(dpsm_frame.record(&ctx, &dpsm));
            ctx.queue.submit([]);
            recorded.0
        });
    });
    g.finish();
}

/// CPU time to prepare and record one frame of RTW over the cube faces of a lamp
/// among the city block's buildings (`cube_rtw`, 2048² of texels in all): the
/// blocks and the tables of every kept face packed ([`warped_cube`]), the casters
/// clipped to each face's window and refined on the GPU, the depth pass drawn
/// indirectly, uploads flushed; and the fit before it (`cube_rtw_fit`: the oracle's
/// needs of a 480x270 ground G-buffer, one pair of 256-cell tables per face), with
/// the cube maps sized by the same samples' needs beside it (`cube_fit_by_need`;
/// `cube_fit_by_need_oriented` with the orientation chosen on them),
/// and tiled cube maps' fit, depth-pass blocks and caster bins (`cube_tiled_fit`,
/// `cube_tiled_uniforms`, `cube_tiled_bins`).
fn cube_rtw_frame_cpu(c: &mut Criterion) {
    let cam = camera();
    let lamp = Light::Point {
        position: Vec3::new(3.0, 30.0, -2.0),
        range: 400.0,
    };
    let samples: Vec<EyeSample> = ground_gbuffer(480, 270).into_iter().flatten().collect();
    let scene = SceneBounds::whole(Aabb::new(
        Vec3::new(-200.0, 0.0, -200.0),
        Vec3::new(200.0, 60.0, 200.0),
    ));
    let pixels_per_radian = 270.0 / 2.0 / 0.5f32.tan();
    let input = FitInput::new(&cam, &lamp, scene, 2048 * 2048)
        .with_eye_samples(&samples)
        .with_pixels_per_radian(pixels_per_radian);
    let technique = Technique::CubeRtw {
        cube: Default::default(),
        rtw: Default::default(),
    };
    // The fit first, before any GPU work is queued (a software adapter's threads
    // would share the CPU with it).
    c.bench_function("cube_rtw_fit/city_block_lamp_2048", |b| {
        b.iter(|| black_box(fit(black_box(&technique), &input).is_ok()));
    });
    // The cube maps sized by the samples' needs, on the same input.
    let by_need = Technique::CubeMaps(CubeOptions::default().with_sizes(FaceSizes::ByNeed));
    c.bench_function("cube_fit_by_need/city_block_lamp_2048", |b| {
        b.iter(|| black_box(fit(black_box(&by_need), &input).is_ok()));
    });
    // The same with the orientation chosen on the samples: the world-axis, the
    // turned and the corner-up cube each sized by them, the least error kept.
    let oriented = Technique::CubeMaps(
        CubeOptions::default()
            .with_sizes(FaceSizes::ByNeed)
            .with_orientation(CubeOrientation::Predicted),
    );
    c.bench_function("cube_fit_by_need_oriented/city_block_lamp_2048", |b| {
        b.iter(|| black_box(fit(black_box(&oriented), &input).is_ok()));
    });
    // Tiled cube maps on the same input: the fit (the samples' isotropic needs per
    // cell, the quadtree, the packing) and the blocks of its depth pass and lookup.
    let tiled = Technique::TiledCube {
        cube: Default::default(),
        tiles: Default::default(),
    };
    c.bench_function("cube_tiled_fit/city_block_lamp_2048", |b| {
        b.iter(|| black_box(fit(black_box(&tiled), &input).is_ok()));
    });
    if let Some(t) = fit(&tiled, &input)
        .ok()
        .as_ref()
        .and_then(Shadow::tiled_cube)
    {
        c.bench_function("cube_tiled_uniforms/city_block_lamp_2048", |b| {
            b.iter(|| black_box(shadowmap_wgpu::tiles::tiled_uniforms(black_box(t), 2048)));
        });
        let casters = city_casters();
        c.bench_function("cube_tiled_bins/city_block_lamp_2048", |b| {
            b.iter(|| black_box(shadowmap_wgpu::tiles::tile_bins(black_box(t), &casters)));
        });
    }
    let shadow = fit(&technique, &input).expect("cube_rtw");
    let Fitted::CubeRtw { cube, warps } = shadow.fitted() else {
        return;
    };
    let Ok(ctx) = GpuContext::new_headless() else {
        eprintln!("cube_rtw_frame_cpu: no adapter, not measured");
        return;
    };
    let side = cube.largest_side();
    let casters = city_casters();
    let setup = ctx.scoped(|ctx| {
        let refine = GpuRefine::new(
            ctx,
            &casters,
            &RefineOptions::default().with_resolution(side),
        )?;
        let desc = DepthPassDesc::new(DepthTechnique::Rtw, side).with_layers(cube.layers());
        Ok((refine, ShadowDepthPass::new(ctx, &desc)?))
    });
    let Ok((mut refine, mut pass)) = setup else {
        eprintln!("cube_rtw_frame_cpu: setup failed");
        return;
    };
    let mut record = || {
        let warped = warped_cube(cube, warps);
        let uniforms = DepthUniforms::WarpedCube {
            layers: &warped.layers,
            tables: &warped.tables,
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let ok = refine
            .encode(&ctx, &mut encoder, &uniforms)
            .and_then(|()| pass.encode_refined(&ctx, &mut encoder, &refine, &uniforms))
            .is_ok();
        (ok, encoder.finish())
    };
    let (ok, commands) = record();
    ctx.queue.submit([commands]);
    eprintln!(
        "cube_rtw_frame_cpu: {} faces, side {side}, {} casters, recorded {ok}",
        cube.layers(),
        casters.len()
    );
    let mut g = c.benchmark_group("cube_rtw_frame_cpu");
    g.bench_function("city_block_lamp_2048_gpu_refine", |b| {
        b.iter(|| {
            let recorded = black_box(record());
            ctx.queue.submit([]);
            recorded.0
        });
    });
    g.finish();
}

criterion_group!(benches, packing);
// `cube_rtw_frame_cpu` first: its fit is timed before any GPU work is queued.
criterion_group!(frame_cpu, cube_rtw_frame_cpu, rtw_frame_cpu, ipsm_frame_cpu);
criterion_main!(frame_cpu, benches);
