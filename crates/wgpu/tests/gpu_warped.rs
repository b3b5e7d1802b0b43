//! Warped cascades (parallel splits with a LiSPSM warp each) on the GPU: the headless
//! renderer's shadow mask equals the CPU reference (the reference rasterizer's depth
//! map of the same per-cascade perspective matrices, looked up by view depth at the
//! point each pixel's primary ray sees) on at least 99.9% of pixels, with standard
//! and reversed depth; a cascade set without a fitted cascade is a typed error; a
//! profiled render draws the same frame and times its passes.

use glam::{DMat4, DVec3, DVec4, Vec3};
use shadowmap::frustum::{Aabb, Camera, Light, Projection, ShadowMapping};
use shadowmap::warp::{LispsmOptions, SceneBounds, WarpedCascades};
use shadowmap::{CascadePlan, FitInput, Fitted, Technique};
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::shadow_mask;
use shadowmap_eval::raster::{DepthMap, MatrixProjector, RasterOptions, rasterize_depth};
use shadowmap_eval::scene::Mesh;
use shadowmap_wgpu::depth::DepthBias;
use shadowmap_wgpu::profile::GpuProfiler;
use shadowmap_wgpu::render::{
    HeadlessRenderer, MaskValue, RenderOptions, ShadowBias, ShadowFilter, ShadowTechnique,
};
use shadowmap_wgpu::{BackendError, GpuContext};

const W: u32 = 192;
const H: u32 = 108;
const RES: u32 = 512;
/// Lookup bias in depth units.
const BIAS: f64 = 1e-4;
/// Rasterizer bias (standard depth; negated for reversed-Z).
const RASTER_CONSTANT: i32 = 256;
const RASTER_SLOPE: f32 = 1.0;
/// Low and oblique, so LiSPSM warps (far from parallel to the view direction).
const LIGHT: Vec3 = Vec3::new(-0.8, -0.6, 0.1);

/// A long street of boxes receding from the camera, so every cascade sees casters.
fn mesh() -> Mesh {
    let mut m = Mesh::new();
    m.push_grid_quad(
        [
            DVec3::new(-40.0, 0.0, -140.0),
            DVec3::new(40.0, 0.0, -140.0),
            DVec3::new(40.0, 0.0, 10.0),
            DVec3::new(-40.0, 0.0, 10.0),
        ],
        8,
    );
    for i in 0..12 {
        let z = -6.0 - 11.0 * f64::from(i);
        let h = 2.0 + f64::from(i % 4) * 1.5;
        m.push_box(DVec3::new(-7.0, 0.0, z - 3.0), DVec3::new(-4.0, h, z));
        m.push_box(
            DVec3::new(4.0, 0.0, z - 5.0),
            DVec3::new(5.0, h + 2.0, z - 4.0),
        );
    }
    m
}

fn bounds() -> Aabb {
    Aabb::new(Vec3::new(-40.0, 0.0, -140.0), Vec3::new(40.0, 10.0, 10.0))
}

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 6.0, 8.0),
        Vec3::new(0.0, 1.0, -40.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), W as f32 / H as f32, 0.5, 150.0),
    )
    .unwrap()
}

/// Warped cascades (up to 3, split weight 0.8) fitted through the one `fit`.
fn fit(reversed_z: bool) -> WarpedCascades {
    let technique = Technique::WarpedCascades {
        plan: CascadePlan::default()
            .with_max_cascades(3)
            .with_split_lambda(0.8),
        lispsm: LispsmOptions::default().with_reversed_z(reversed_z),
    };
    let light = Light::Directional { direction: LIGHT };
    let camera = camera();
    let input = FitInput::new(
        &camera,
        &light,
        SceneBounds::whole(bounds()),
        3 * u64::from(RES * RES),
    );
    match shadowmap::fit(&technique, &input).unwrap().fitted() {
        Fitted::WarpedCascades { cascades, .. } => cascades.clone(),
        other => panic!("warped cascades expected, got {other:?}"),
    }
}

/// The reference depth map: one layer per cascade, a cascade without a fit clips
/// everything.
fn cpu_depth(set: &WarpedCascades, reversed_z: bool) -> DepthMap {
    let clip_all = DMat4::from_cols(
        DVec4::ZERO,
        DVec4::ZERO,
        DVec4::ZERO,
        DVec4::new(0.0, 0.0, -1.0, 1.0),
    );
    let matrices = set
        .cascades
        .iter()
        .map(|c| {
            c.shadow
                .map_or(clip_all, |s| s.transform.clip_from_world.as_dmat4())
        })
        .collect();
    let sign = if reversed_z { -1.0 } else { 1.0 };
    rasterize_depth(
        &mesh(),
        &MatrixProjector::new(matrices, reversed_z),
        &RasterOptions::default()
            .with_size(RES, RES)
            .with_depth_bias(
                sign * f64::from(RASTER_CONSTANT),
                sign * f64::from(RASTER_SLOPE),
            ),
    )
    .unwrap()
}

fn options() -> RenderOptions {
    let raster = DepthBias {
        constant: RASTER_CONSTANT,
        slope_scale: RASTER_SLOPE,
        clamp: 0.0,
    };
    RenderOptions::default()
        .with_size(W, H)
        .with_shadow_resolution(RES)
        .with_bias(ShadowBias::new(raster, BIAS as f32, 0.0))
        .with_filter(ShadowFilter::Hard)
}

fn triangles() -> Vec<[Vec3; 3]> {
    mesh().triangles_f32()
}

fn check_against_cpu(ctx: &GpuContext, renderer: &mut HeadlessRenderer, reversed_z: bool) {
    let set = fit(reversed_z);
    // The fit must exercise the perspective divide: some cascade's lookup matrix
    // has a non-trivial w row.
    let warped = set.cascades.iter().filter_map(|c| c.shadow).any(|s| {
        let row = s.transform.uv_from_world.row(3);
        (row - glam::Vec4::W).abs().max_element() > 1e-3
    });
    assert!(warped, "no cascade is perspective-warped");
    let gpu = renderer
        .render(
            ctx,
            &triangles(),
            &camera(),
            &ShadowTechnique::WarpedCascades(&set),
            &options(),
        )
        .expect("render")
        .mask;
    let camera = camera();
    let reference = set.view_from(&camera);
    let bvh = Bvh::build(&mesh()).unwrap();
    let depth = cpu_depth(&set, reversed_z);
    let cpu = shadow_mask(&bvh, &camera, W, H, &reference, &depth, BIAS).unwrap();
    let name = if reversed_z { "reversed-Z" } else { "standard" };
    let differing = gpu
        .values
        .iter()
        .zip(&cpu.lit)
        .filter(|(g, c)| g.lit() != **c)
        .count();
    let count = |v: MaskValue| gpu.values.iter().filter(|g| **g == v).count();
    let (lit, shadowed) = (count(MaskValue::Lit), count(MaskValue::Shadowed));
    let n = cpu.lit.len();
    eprintln!("warped cascades {name}: {differing} of {n} differ; lit {lit}, shadowed {shadowed}");
    assert!(lit > n / 10 && shadowed > n / 100, "{name}: a trivial mask");
    assert!(
        differing as f64 <= 1e-3 * n as f64,
        "{name}: {differing} pixels differ"
    );
    // Every cascade is the one selected somewhere in the image.
    let mut used = vec![0usize; set.cascades.len()];
    let gbuffer = shadowmap_eval::mask::GBuffer::trace(&bvh, &camera, W, H).unwrap();
    for y in 0..H {
        for x in 0..W {
            if let Some(s) = gbuffer
                .get(x, y)
                .and_then(|s| reference.map_point(s.position))
            {
                used[s.layer as usize] += 1;
            }
        }
    }
    assert!(
        used.iter().all(|&u| u > 50),
        "{name}: cascades used {used:?}"
    );
}

#[test]
fn warped_cascade_masks_match_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("warped_cascade_masks_match_the_cpu_reference")
    else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    check_against_cpu(&ctx, &mut renderer, false);
    check_against_cpu(&ctx, &mut renderer, true);
}

#[test]
fn cascade_sets_without_a_fitted_cascade_are_typed_errors() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "cascade_sets_without_a_fitted_cascade_are_typed_errors",
    ) else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    let render = |renderer: &mut HeadlessRenderer, t: &ShadowTechnique<'_>| {
        renderer.render(&ctx, &triangles(), &camera(), t, &options())
    };
    let mut unfitted = fit(false);
    for c in &mut unfitted.cascades {
        c.shadow = None;
    }
    let mut empty = fit(false);
    empty.cascades.clear();
    for set in [&unfitted, &empty] {
        let result = render(&mut renderer, &ShadowTechnique::WarpedCascades(set));
        assert!(
            matches!(result, Err(BackendError::InvalidInput(_))),
            "{result:?}"
        );
    }
    let light = Light::Directional { direction: LIGHT };
    let camera = camera();
    let input = FitInput::new(&camera, &light, SceneBounds::whole(bounds()), 1 << 20);
    let tight = Technique::TightCascades(CascadePlan::default());
    let Fitted::Cascades(mut cascades) = shadowmap::fit(&tight, &input).unwrap().fitted().clone()
    else {
        panic!("cascades expected");
    };
    cascades.cascades.clear();
    for t in [
        ShadowTechnique::Cascades(&cascades),
        ShadowTechnique::CascadesByProjection(&cascades, 1.0),
    ] {
        let result = render(&mut renderer, &t);
        assert!(
            matches!(result, Err(BackendError::InvalidInput(_))),
            "{result:?}"
        );
    }
    // The fitted set renders.
    let set = fit(false);
    assert!(render(&mut renderer, &ShadowTechnique::WarpedCascades(&set)).is_ok());
}

#[test]
fn a_profiled_render_times_each_pass_and_renders_the_same_frame() {
    let Some(plain_ctx) = shadowmap_wgpu::context::test_context(
        "a_profiled_render_times_each_pass_and_renders_the_same_frame",
    ) else {
        return;
    };
    drop(plain_ctx);
    let ctx = GpuContext::new_headless_with_features(GpuProfiler::FEATURES).expect("device");
    let mut profiler = GpuProfiler::new(&ctx, 4);
    let set = fit(false);
    let technique = ShadowTechnique::WarpedCascades(&set);
    let mut renderer = HeadlessRenderer::new();
    let options = options().with_filter(ShadowFilter::Vsm { blur_radius: 2 });
    let render = |renderer: &mut HeadlessRenderer, profiler: Option<&mut GpuProfiler>| {
        match profiler {
            Some(p) => {
                renderer.render_profiled(&ctx, &triangles(), &camera(), &technique, &options, p)
            }
            None => renderer.render(&ctx, &triangles(), &camera(), &technique, &options),
        }
        .expect("render")
    };
    let plain = render(&mut renderer, None);
    let profiled = render(&mut renderer, Some(&mut profiler));
    assert_eq!(plain.mask, profiled.mask, "profiling changes nothing drawn");
    let passes = profiler.read(&ctx).expect("timestamps");
    let labels: Vec<&str> = passes.iter().map(|p| p.label.as_str()).collect();
    assert_eq!(labels, ["depth", "vsm", "scene"]);
    let timed = profiler.unsupported().is_none();
    if let Some(why) = profiler.unsupported() {
        eprintln!("GPU times unavailable: {why}");
    }
    for p in &passes {
        eprintln!("{}: CPU {:.3} ms, GPU {:?} ms", p.label, p.cpu_ms, p.gpu_ms);
        assert!(p.cpu_ms.is_finite() && p.cpu_ms >= 0.0, "{p:?}");
        assert_eq!(p.gpu_ms.is_some(), timed, "{p:?}");
        assert!(
            p.gpu_ms.is_none_or(|ms| ms.is_finite() && ms >= 0.0),
            "{p:?}"
        );
    }
    // A frame read twice gives nothing the second time.
    assert!(profiler.read(&ctx).expect("timestamps").is_empty());
}
