//! The headless renderer's shadow mask equals the CPU reference mask (the CPU depth
//! map of `shadowmap_eval::raster` looked up, with the same bias, at the point a
//! primary ray through each pixel centre sees) on at least 99.9% of pixels. Both depth
//! passes use the same slope-scaled and constant rasterizer bias (no clamp: the
//! reference has none).

use glam::{DMat4, DVec3, DVec4, Vec3};
use shadowmap::paraboloid::{IpsmOptions, Side, subdivide_triangles};
use shadowmap::rtw::{EyeSample, WarpOptions};
use shadowmap::{CascadePlan, DpsmOptions, FitInput, RtwPlan, Shadow, Technique, fit};
use shadowmap_eval::raster::{
    DepthMap, DepthProjector, MatrixProjector, ParaboloidProjector, RasterOptions, RtwProjector,
    rasterize_depth,
};
use shadowmap_eval::scene::Mesh;
use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds, ShadowMapping};
use shadowmap_warp::UniformOptions;
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::depth::{DepthBias, subdivide_for_rtw};
use shadowmap_wgpu::render::{
    HeadlessRenderer, MaskValue, RenderOptions, ShadowBias, ShadowFilter, ShadowMask,
};

const W: u32 = 160;
const H: u32 = 120;
const RES: u32 = 512;
/// Lookup bias in depth units.
const BIAS: f64 = 1e-4;
/// Rasterizer bias (standard depth; negated for reversed-Z).
const RASTER_CONSTANT: i32 = 256;
const RASTER_SLOPE: f32 = 1.0;
const LIGHT: Vec3 = Vec3::new(0.5, -1.0, 0.35);

/// Ground, three boxes and a pole.
fn scene() -> Vec<[Vec3; 3]> {
    let mut m = Mesh::new();
    m.push_grid_quad(
        [
            DVec3::new(-30.0, 0.0, -30.0),
            DVec3::new(30.0, 0.0, -30.0),
            DVec3::new(30.0, 0.0, 30.0),
            DVec3::new(-30.0, 0.0, 30.0),
        ],
        4,
    );
    m.push_box(DVec3::new(-6.0, 0.0, -4.0), DVec3::new(-2.0, 5.0, 0.0));
    m.push_box(DVec3::new(2.0, 0.0, -8.0), DVec3::new(5.0, 3.0, -5.0));
    m.push_box(DVec3::new(0.0, 2.0, 2.0), DVec3::new(2.0, 2.5, 4.0));
    m.push_box(DVec3::new(6.0, 0.0, 3.0), DVec3::new(6.3, 7.0, 3.3));
    m.triangles_f32()
}

fn bounds() -> Aabb {
    Aabb::new(Vec3::new(-30.0, 0.0, -30.0), Vec3::new(30.0, 7.0, 30.0))
}

fn sun() -> Light {
    Light::Directional { direction: LIGHT }
}

/// Fits a technique for the test camera over the test scene's bounds, `RES²` texels
/// per layer (`layers` of them).
fn fit_test(technique: &Technique, light: &Light, layers: u64, samples: &[EyeSample]) -> Shadow {
    let camera = camera();
    let budget = layers * u64::from(RES) * u64::from(RES);
    let input = FitInput::new(&camera, light, SceneBounds::whole(bounds()), budget)
        .with_eye_samples(samples);
    let shadow = fit(technique, &input).unwrap();
    assert_eq!(shadow.layer_side(), RES);
    shadow
}

/// The surfaces a 40 x 30 grid of primary rays sees (RTW's eye samples).
fn eye_samples(tris: &[[Vec3; 3]]) -> Vec<EyeSample> {
    let world_from_clip: DMat4 = camera().clip_from_world().unwrap().as_dmat4().inverse();
    let eye = camera().eye().as_dvec3();
    let mut out = Vec::new();
    for y in 0..30 {
        for x in 0..40 {
            let ndc = DVec4::new(
                (f64::from(x) + 0.5) / 20.0 - 1.0,
                1.0 - (f64::from(y) + 0.5) / 15.0,
                1.0,
                1.0,
            );
            let far = world_from_clip * ndc;
            let dir = (far.truncate() / far.w - eye).normalize();
            if let Some(p) = cast(tris, eye, dir) {
                out.push(EyeSample {
                    position: p.as_vec3(),
                    normal: Vec3::ZERO,
                    eye_distance: p.distance(eye) as f32,
                });
            }
        }
    }
    out
}

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(2.0, 12.0, 22.0),
        Vec3::new(0.0, 0.0, -2.0),
        Vec3::Y,
        Projection::perspective(55f32.to_radians(), W as f32 / H as f32, 0.5, 120.0),
    )
    .unwrap()
}

fn mesh_of(tris: &[[Vec3; 3]]) -> Mesh {
    let mut m = Mesh::new();
    for t in tris {
        m.push_triangle(t.map(Vec3::as_dvec3));
    }
    m
}

/// Nearest hit of a ray with a triangle soup (Möller–Trumbore, f64).
fn cast(tris: &[[Vec3; 3]], origin: DVec3, dir: DVec3) -> Option<DVec3> {
    let mut best = f64::INFINITY;
    for t in tris {
        let [a, b, c] = t.map(Vec3::as_dvec3);
        let (e1, e2) = (b - a, c - a);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let inv = 1.0 / det;
        let s = origin - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let q = s.cross(e1);
        let v = dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        let d = e2.dot(q) * inv;
        if d > 1e-9 && d < best {
            best = d;
        }
    }
    best.is_finite().then(|| origin + dir * best)
}

/// The CPU reference mask: `Some(lit)` per pixel, `None` for background or not
/// covered.
fn cpu_mask(tris: &[[Vec3; 3]], mapping: &dyn ShadowMapping, map: &DepthMap) -> Vec<Option<bool>> {
    let world_from_clip: DMat4 = camera().clip_from_world().unwrap().as_dmat4().inverse();
    let eye = camera().eye().as_dvec3();
    let mut out = Vec::with_capacity((W * H) as usize);
    for y in 0..H {
        for x in 0..W {
            let ndc_x = 2.0 * (f64::from(x) + 0.5) / f64::from(W) - 1.0;
            let ndc_y = 1.0 - 2.0 * (f64::from(y) + 0.5) / f64::from(H);
            let far = world_from_clip * DVec4::new(ndc_x, ndc_y, 1.0, 1.0);
            let dir = (far.truncate() / far.w - eye).normalize();
            let lit = cast(tris, eye, dir)
                .and_then(|p| mapping.map_point(p))
                .and_then(|s| map.is_lit(&s, BIAS));
            out.push(lit);
        }
    }
    out
}

fn cpu_depth(tris: &[[Vec3; 3]], projector: &dyn DepthProjector) -> DepthMap {
    let sign = if projector.reversed_z() { -1.0 } else { 1.0 };
    rasterize_depth(
        &mesh_of(tris),
        projector,
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

/// Asserts agreement on at least 99.9% of pixels and that the mask is not trivial.
fn assert_masks_agree(name: &str, gpu: &ShadowMask, cpu: &[Option<bool>]) {
    assert_eq!(gpu.values.len(), cpu.len());
    let differing = gpu
        .values
        .iter()
        .zip(cpu)
        .filter(|(g, c)| g.lit() != **c)
        .count();
    let count = |v: MaskValue| gpu.values.iter().filter(|g| **g == v).count();
    let (lit, shadowed) = (count(MaskValue::Lit), count(MaskValue::Shadowed));
    eprintln!(
        "{name}: {differing} of {} pixels differ; lit {lit}, shadowed {shadowed}",
        cpu.len()
    );
    assert!(
        lit > cpu.len() / 10 && shadowed > cpu.len() / 100,
        "{name}: a trivial mask"
    );
    assert!(
        differing as f64 <= 1e-3 * cpu.len() as f64,
        "{name}: {differing} pixels differ"
    );
}

fn render(
    ctx: &GpuContext,
    renderer: &mut HeadlessRenderer,
    shadow: &Shadow,
    options: &RenderOptions,
) -> ShadowMask {
    renderer
        .render_shadow(ctx, &scene(), &camera(), shadow, options)
        .expect("render")
        .mask
}

#[test]
fn matrix_and_cascade_masks_match_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("matrix_and_cascade_masks_match_the_cpu_reference")
    else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    let tris = scene();
    let reversed = UniformOptions::default().with_reversed_z(true);
    for (name, technique) in [
        ("uniform", Technique::UniformFocused(Default::default())),
        ("uniform reversed-Z", Technique::UniformFocused(reversed)),
        ("xpsm", Technique::Xpsm(Default::default())),
    ] {
        let shadow = fit_test(&technique, &sun(), 1, &[]);
        let gpu = render(&ctx, &mut renderer, &shadow, &options());
        let projector = MatrixProjector::from(shadow.transform().unwrap());
        let cpu = cpu_mask(&tris, &shadow, &cpu_depth(&tris, &projector));
        assert_masks_agree(name, &gpu, &cpu);
    }

    let plan = CascadePlan::default().with_max_cascades(3);
    let shadow = fit_test(&Technique::StableCascades(plan), &sun(), 3, &[]);
    let shadowmap::Fitted::Cascades(set) = shadow.fitted() else {
        panic!("cascades expected");
    };
    assert!(shadow.layers() > 1);
    let gpu = render(&ctx, &mut renderer, &shadow, &options());
    let cpu = cpu_mask(
        &tris,
        &shadow,
        &cpu_depth(&tris, &MatrixProjector::from(set)),
    );
    assert_masks_agree("cascades", &gpu, &cpu);
}

#[test]
fn paraboloid_and_rtw_masks_match_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("paraboloid_and_rtw_masks_match_the_cpu_reference")
    else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    let tris = scene();

    let lamp = Light::Point {
        position: Vec3::new(1.0, 9.0, 1.0),
        range: 80.0,
    };
    let dpsm = DpsmOptions::default()
        .with_axis(Vec3::new(0.1, -1.0, 0.0))
        .with_near(0.2);
    let shadow = fit_test(&Technique::Dpsm(dpsm), &lamp, 2, &[]);
    let map = shadow.paraboloid().unwrap();
    let gpu = render(&ctx, &mut renderer, &shadow, &options());
    // The CPU map from the same subdivided casters, side by side.
    let sub = options().subdivision.with_resolution(RES);
    let mut depth = DepthMap::cleared(RES, RES, 2, false).unwrap();
    let n = (RES * RES) as usize;
    for (layer, side) in [Side::Front, Side::Back].into_iter().enumerate() {
        let mut out = Vec::new();
        subdivide_triangles(map, side, &tris, &sub, &mut out).unwrap();
        let full = cpu_depth(&out, &ParaboloidProjector::from(map));
        depth.depth[layer * n..(layer + 1) * n]
            .copy_from_slice(&full.depth[layer * n..(layer + 1) * n]);
    }
    let cpu = cpu_mask(&tris, &shadow, &depth);
    assert_masks_agree("paraboloid", &gpu, &cpu);
    // IPSM goes through the same match (a single or dual map).
    let ipsm = fit(
        &Technique::Ipsm(IpsmOptions::default()),
        &FitInput::new(
            &camera(),
            &lamp,
            SceneBounds::whole(bounds()),
            u64::from(RES * RES),
        ),
    )
    .unwrap();
    let frame = renderer
        .render_shadow(&ctx, &tris, &camera(), &ipsm, &options())
        .unwrap();
    assert_eq!(frame.mask.values.len(), (W * H) as usize);

    let plan = RtwPlan::default()
        .with_importance_side(32)
        .with_warp(WarpOptions::default().with_blur_radius(3));
    let samples = eye_samples(&tris);
    let shadow = fit_test(&Technique::Rtw(plan), &sun(), 1, &samples);
    let rtw = shadow.rtw().unwrap();
    let gpu = render(&ctx, &mut renderer, &shadow, &options());
    let mut casters = Vec::new();
    let sub = options().rtw_subdivision.with_resolution(RES);
    subdivide_for_rtw(&rtw, &tris, &sub, &mut casters);
    let cpu = cpu_mask(
        &tris,
        &shadow,
        &cpu_depth(&casters, &RtwProjector::from(rtw)),
    );
    assert_masks_agree("rtw", &gpu, &cpu);
}

#[test]
fn every_filter_renders_and_png_round_trips() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("every_filter_renders_and_png_round_trips")
    else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    let uniform = fit_test(
        &Technique::UniformFocused(Default::default()),
        &sun(),
        1,
        &[],
    );
    let mut brightness = Vec::new();
    for filter in [
        ShadowFilter::Hard,
        ShadowFilter::Hardware2x2,
        ShadowFilter::Pcf {
            taps: 3,
            radius: 1.5,
        },
        ShadowFilter::Poisson { radius: 2.0 },
        ShadowFilter::Vsm { blur_radius: 2 },
    ] {
        let frame = renderer
            .render_shadow(
                &ctx,
                &scene(),
                &camera(),
                &uniform,
                &options().with_filter(filter),
            )
            .unwrap_or_else(|e| panic!("{filter:?}: {e}"));
        // Shadowed pixels are darker than lit ones on the ground, whatever the filter.
        let luma = |i: usize| u32::from(frame.image.rgba[4 * i + 1]);
        let mean = |v: MaskValue| {
            let idx: Vec<usize> = (0..frame.mask.values.len())
                .filter(|&i| frame.mask.values[i] == v)
                .collect();
            idx.iter().map(|&i| luma(i)).sum::<u32>() as f64 / idx.len().max(1) as f64
        };
        let (lit, shadowed) = (mean(MaskValue::Lit), mean(MaskValue::Shadowed));
        eprintln!("{filter:?}: mean green lit {lit:.1}, shadowed {shadowed:.1}");
        assert!(lit > shadowed + 20.0, "{filter:?}: shadows not darker");
        brightness.push(lit);
        if filter == ShadowFilter::Hard {
            let path =
                std::env::temp_dir().join(format!("shadowmap-wgpu-{}.png", std::process::id()));
            frame.image.save_png(&path).unwrap();
            let decoder =
                png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
            let reader = decoder.read_info().unwrap();
            assert_eq!((reader.info().width, reader.info().height), (W, H));
            let _ = std::fs::remove_file(&path);
        }
    }
    assert_eq!(brightness.len(), 5);
}

#[test]
fn bad_render_input_is_a_typed_error() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("bad_render_input_is_a_typed_error")
    else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    let t = fit_test(
        &Technique::UniformFocused(Default::default()),
        &sun(),
        1,
        &[],
    );
    assert!(
        renderer
            .render_shadow(&ctx, &[], &camera(), &t, &options())
            .is_err()
    );
    assert!(
        renderer
            .render_shadow(&ctx, &scene(), &camera(), &t, &options().with_size(0, 10))
            .is_err()
    );
    let zero = options().with_shadow_resolution(0);
    let direct = shadowmap_wgpu::shadow::with_technique(&t, |technique| {
        renderer.render(&ctx, &scene(), &camera(), technique, &zero)
    })
    .unwrap();
    assert!(direct.is_err());
}

#[test]
fn warped_cascade_mask_through_fit_matches_the_cpu_reference() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "warped_cascade_mask_through_fit_matches_the_cpu_reference",
    ) else {
        return;
    };
    let mut renderer = HeadlessRenderer::new();
    let tris = scene();
    let shadow = fit_test(
        &Technique::WarpedCascades {
            plan: CascadePlan::default().with_max_cascades(2),
            lispsm: Default::default(),
        },
        &sun(),
        2,
        &[],
    );
    let shadowmap::Fitted::WarpedCascades { cascades, .. } = shadow.fitted() else {
        panic!("warped cascades expected");
    };
    let matrices = cascades
        .cascades
        .iter()
        .map(|c| c.shadow.unwrap().transform.clip_from_world.as_dmat4())
        .collect();
    let gpu = render(&ctx, &mut renderer, &shadow, &options());
    let cpu = cpu_mask(
        &tris,
        &shadow,
        &cpu_depth(&tris, &MatrixProjector::new(matrices, false)),
    );
    assert_masks_agree("warped cascades", &gpu, &cpu);
}
