//! The GPU depth passes match the CPU reference rasterizer of `shadowmap-eval` for
//! every technique: at most 0.1% of texels differ by more than 1e-4 in depth.

use glam::{DVec3, Vec2, Vec3};
use shadowmap::paraboloid::{Side, SubdivisionOptions, subdivide_triangles};
use shadowmap::{CascadePlan, DpsmOptions, FitInput, Fitted, Shadow, Technique, fit};
use shadowmap_eval::raster::{
    DepthMap, DepthProjector, MatrixProjector, ParaboloidProjector, RasterOptions, RtwProjector,
    rasterize_depth,
};
use shadowmap_eval::scene::{Mesh, Scene};
use shadowmap_frustum::{Camera, Light, Projection, ShadowTransform};
use shadowmap_rtw::{ImportanceMap, RtwShadow, WarpMaps, WarpOptions};
use shadowmap_warp::{SceneBounds, UniformOptions};
use shadowmap_wgpu::GpuContext;
use shadowmap_wgpu::depth::{
    DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, RtwSubdivision, ShadowDepthPass,
    subdivide_for_rtw,
};
use shadowmap_wgpu::uniforms::{RtwShadowRaw, ToRaw, cascade_layers, paraboloid_layers};

const RES: u32 = 256;

fn scene() -> Scene {
    Scene::city_block(1)
}

fn camera() -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 40.0, 90.0),
        Vec3::new(0.0, 0.0, -20.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 4.0 / 3.0, 1.0, 300.0),
    )
    .unwrap()
}

const LIGHT: Vec3 = Vec3::new(0.4, -1.0, 0.3);

fn mesh_of(tris: &[[Vec3; 3]]) -> Mesh {
    let mut m = Mesh::new();
    for t in tris {
        m.push_triangle(t.map(Vec3::as_dvec3));
    }
    m
}

fn focus() -> SceneBounds {
    SceneBounds::whole(scene().bounds().unwrap())
}

/// Fits a technique for the test camera over the city block, `RES²` texels per layer
/// (`layers` of them).
fn fit_test(technique: &Technique, light: &Light, layers: u64) -> Shadow {
    let camera = camera();
    let budget = layers * u64::from(RES) * u64::from(RES);
    let shadow = fit(technique, &FitInput::new(&camera, light, focus(), budget)).unwrap();
    assert_eq!(shadow.layer_side(), RES);
    shadow
}

fn sun() -> Light {
    Light::Directional { direction: LIGHT }
}

/// The base fit of the RTW tests.
fn uniform() -> ShadowTransform {
    *fit_test(&Technique::UniformFocused(Default::default()), &sun(), 1)
        .transform()
        .unwrap()
}

/// Renders `tris` on the GPU and the CPU and returns (differing texels, total).
fn compare(
    ctx: &GpuContext,
    desc: DepthPassDesc,
    layer_tris: &[Vec<[Vec3; 3]>],
    uniforms: &DepthUniforms<'_>,
    projector: &dyn DepthProjector,
) -> (usize, usize, DepthMap) {
    let gpu = ctx
        .scoped(|ctx| {
            let meshes: Vec<MeshBuffers> = layer_tris
                .iter()
                .map(|t| MeshBuffers::from_triangles(ctx, t))
                .collect::<Result<_, _>>()?;
            let refs: Vec<&MeshBuffers> = meshes.iter().collect();
            let mut pass = ShadowDepthPass::new(ctx, &desc)?;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            pass.encode(ctx, &mut encoder, &refs, uniforms)?;
            ctx.queue.submit([encoder.finish()]);
            pass.readback_depth(ctx)
        })
        .expect("GPU depth pass");
    let options = RasterOptions::default().with_size(RES, RES);
    let mut cpu = DepthMap::cleared(RES, RES, desc.layers, desc.reversed_z).unwrap();
    for layer in 0..desc.layers {
        // Each layer may have its own (subdivided) mesh: rasterize it alone.
        let tris = &layer_tris[(layer as usize).min(layer_tris.len() - 1)];
        let one = OneLayer {
            inner: projector,
            layer,
        };
        let map = rasterize_depth(&mesh_of(tris), &one, &options).unwrap();
        let n = (RES * RES) as usize;
        cpu.depth[layer as usize * n..(layer as usize + 1) * n].copy_from_slice(&map.depth);
    }
    assert_eq!(gpu.len(), cpu.depth.len());
    // DEBUG_DIFF=1 lists the differing texels.
    if std::env::var("DEBUG_DIFF").is_ok() {
        for (i, (g, c)) in gpu.iter().zip(&cpu.depth).enumerate() {
            if (g - c).abs() > 1e-4 {
                let t = i % (RES * RES) as usize;
                eprintln!(
                    "texel {} {}: gpu {g} cpu {c}",
                    t % RES as usize,
                    t / RES as usize
                );
            }
        }
    }
    let differing = gpu
        .iter()
        .zip(&cpu.depth)
        .filter(|(g, c)| (**g - **c).abs() > 1e-4)
        .count();
    // The map must not be empty: something was drawn in every layer.
    let clear = cpu.clear_value();
    let n = (RES * RES) as usize;
    for layer in 0..desc.layers as usize {
        let drawn = cpu.depth[layer * n..(layer + 1) * n]
            .iter()
            .filter(|d| **d != clear)
            .count();
        assert!(drawn > n / 20, "layer {layer}: only {drawn} texels drawn");
    }
    (differing, gpu.len(), cpu)
}

/// One layer of a projector, as a single-layer projector.
struct OneLayer<'a> {
    inner: &'a dyn DepthProjector,
    layer: u32,
}

impl DepthProjector for OneLayer<'_> {
    fn layers(&self) -> u32 {
        1
    }
    fn reversed_z(&self) -> bool {
        self.inner.reversed_z()
    }
    fn project_vertex(
        &self,
        _layer: u32,
        world: DVec3,
    ) -> Option<shadowmap_eval::raster::ClipVertex> {
        self.inner.project_vertex(self.layer, world)
    }
}

fn assert_close(name: &str, differing: usize, total: usize) {
    let fraction = differing as f64 / total as f64;
    eprintln!("{name}: {differing} of {total} texels differ by more than 1e-4 ({fraction:.5})");
    assert!(
        fraction <= 1e-3,
        "{name}: {differing} of {total} texels differ"
    );
}

fn matrix_case(
    ctx: &GpuContext,
    name: &str,
    t: &ShadowTransform,
    raw: shadowmap_wgpu::uniforms::MatrixShadowRaw,
) {
    let tris = scene().mesh.triangles_f32();
    let desc = DepthPassDesc::new(DepthTechnique::Matrix, RES).with_reversed_z(t.reversed_z);
    let result = compare(
        ctx,
        desc,
        &[tris],
        &DepthUniforms::Matrix(&[raw]),
        &MatrixProjector::from(t),
    );
    assert_close(name, result.0, result.1);
}

#[test]
fn matrix_techniques_match_the_cpu_rasterizer() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("matrix_techniques_match_the_cpu_rasterizer")
    else {
        return;
    };
    let reversed = UniformOptions::default().with_reversed_z(true);
    for (name, technique) in [
        ("uniform", Technique::UniformFocused(Default::default())),
        ("uniform reversed-Z", Technique::UniformFocused(reversed)),
        ("lispsm", Technique::Lispsm(Default::default())),
        ("xpsm", Technique::Xpsm(Default::default())),
        ("tsm", Technique::Tsm(Default::default())),
    ] {
        let shadow = fit_test(&technique, &sun(), 1);
        let t = shadow.transform().unwrap();
        // XPSM's block carries its Z bias scale.
        let raw = match shadow.fitted() {
            Fitted::Xpsm(x) => x.to_raw(),
            _ => t.to_raw(),
        };
        matrix_case(&ctx, name, t, raw);
    }
}

#[test]
fn cascades_render_one_layer_each_and_match() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("cascades_render_one_layer_each_and_match")
    else {
        return;
    };
    let plan = CascadePlan::default()
        .with_max_cascades(3)
        .with_split_lambda(0.7);
    let shadow = fit_test(&Technique::TightCascades(plan), &sun(), 3);
    let Fitted::Cascades(set) = shadow.fitted() else {
        panic!("cascades expected");
    };
    let layers = cascade_layers(set);
    assert_eq!(layers.len(), 3);
    let desc = DepthPassDesc::new(DepthTechnique::Matrix, RES).with_layers(3);
    let result = compare(
        &ctx,
        desc,
        &[scene().mesh.triangles_f32()],
        &DepthUniforms::Matrix(&layers),
        &MatrixProjector::from(set),
    );
    assert_close("cascades", result.0, result.1);
}

#[test]
fn paraboloid_front_and_back_match() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("paraboloid_front_and_back_match") else {
        return;
    };
    // A point light among the buildings, front paraboloid facing down: the back side
    // sees the tall buildings' upper floors.
    let lamp = Light::Point {
        position: Vec3::new(3.0, 30.0, -2.0),
        range: 400.0,
    };
    let dpsm = DpsmOptions::default()
        .with_axis(Vec3::new(0.2, -1.0, 0.1))
        .with_near(0.5);
    let shadow = fit_test(&Technique::Dpsm(dpsm), &lamp, 2);
    let map = shadow.paraboloid().unwrap();
    let tris = scene().mesh.triangles_f32();
    let options = SubdivisionOptions::default().with_resolution(RES);
    let mut front = Vec::new();
    let mut back = Vec::new();
    subdivide_triangles(map, Side::Front, &tris, &options, &mut front).unwrap();
    subdivide_triangles(map, Side::Back, &tris, &options, &mut back).unwrap();
    assert!(front.len() > tris.len(), "subdivision split something");
    let layers = paraboloid_layers(map);
    let desc = DepthPassDesc::new(DepthTechnique::Paraboloid, RES).with_layers(2);
    let (differing, total, cpu) = compare(
        &ctx,
        desc,
        &[front, back],
        &DepthUniforms::Paraboloid(&layers),
        &ParaboloidProjector::from(map),
    );
    // The hemisphere clip left the outside of the unit disc empty in both layers.
    let corner = cpu.get(0, 2, 2);
    assert_eq!(corner, cpu.clear_value());
    assert_close("paraboloid", differing, total);
}

/// A strongly non-identity warp (floor 1e-3: up to 1000x compression) over the city
/// block. Where it compresses, whole walls become one-texel slivers with depth slopes
/// of 0.1-1 per texel; llvmpipe derives the depth plane from the unsnapped vertex
/// positions and the reference from the snapped ones, which differed by up to
/// slope/512 (0.2-0.5% of texels off by > 1e-4) until the vertex shader snapped to
/// the 1/256-pixel grid itself (`shaders/depth_rtw.wgsl`). Not the cause: `f32` vs
/// `f64` warping (a CPU projector mirroring the shader's `f32` arithmetic gave the
/// same 356 differing texels), the meshes (both sides rasterize the same
/// triangles), or the table upload.
#[test]
fn rtw_matches_with_warped_vertices() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("rtw_matches_with_warped_vertices")
    else {
        return;
    };
    let base = uniform();
    let mut importance = ImportanceMap::new(64, 48).unwrap();
    importance.splat(Vec2::new(0.5, 0.6), 10.0).unwrap();
    importance.splat(Vec2::new(0.3, 0.2), 3.0).unwrap();
    importance.splat(Vec2::new(0.8, 0.9), 1.0).unwrap();
    let mut warps = WarpMaps::new(64, 48).unwrap();
    warps
        .build(&importance, &WarpOptions::default().with_blur_radius(4))
        .unwrap();
    let shadow = RtwShadow {
        base,
        warps: &warps,
    };
    assert!(
        warps.x_table().iter().any(|t| t.abs() > 1e-3),
        "a real warp"
    );
    let tables = RtwShadowRaw::tables(&shadow);
    let uniforms = DepthUniforms::Rtw {
        raw: shadow.to_raw(),
        tables: &tables,
    };
    let desc = DepthPassDesc::new(DepthTechnique::Rtw, RES);
    // Unsplit casters, and the default subdivision.
    for (name, subdivision) in [
        ("unsplit", RtwSubdivision::default().with_max_segments(1)),
        ("split", RtwSubdivision::default().with_resolution(RES)),
    ] {
        let mut tris = Vec::new();
        subdivide_for_rtw(
            &shadow,
            &scene().mesh.triangles_f32(),
            &subdivision,
            &mut tris,
        );
        let result = compare(&ctx, desc, &[tris], &uniforms, &RtwProjector::from(shadow));
        assert_close(&format!("rtw, {name}"), result.0, result.1);
    }
}

#[test]
fn bad_inputs_are_typed_errors() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("bad_inputs_are_typed_errors") else {
        return;
    };
    assert!(ShadowDepthPass::new(&ctx, &DepthPassDesc::new(DepthTechnique::Matrix, 0)).is_err());
    assert!(
        ShadowDepthPass::new(
            &ctx,
            &DepthPassDesc::new(DepthTechnique::Rtw, 64)
                .with_layers(shadowmap_wgpu::refine::MAX_LAYERS + 1)
        )
        .is_err()
    );
    assert!(MeshBuffers::new(&ctx, &[Vec3::ZERO], &[[0, 0, 1]]).is_err());
    assert!(MeshBuffers::new(&ctx, &[Vec3::NAN; 3], &[[0, 1, 2]]).is_err());
    let mesh = MeshBuffers::from_triangles(&ctx, &[[Vec3::ZERO, Vec3::X, Vec3::Y]]).unwrap();
    let mut pass = ShadowDepthPass::new(
        &ctx,
        &DepthPassDesc::new(DepthTechnique::Matrix, 64).with_layers(2),
    )
    .unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    // One block for a two-layer pass.
    let t = uniform();
    assert!(
        pass.encode(
            &ctx,
            &mut encoder,
            &[&mesh],
            &DepthUniforms::Matrix(&[t.to_raw()])
        )
        .is_err()
    );
}

/// Eye samples of the scene for the RTW importance: points on every triangle the
/// camera sees (in its clip volume; occlusion does not matter here), with the
/// triangle's normal and the eye distance. Samples within 1e-3 of a cell border of
/// the `width x height` importance map are left out: there the GPU (`f32`) and the
/// CPU (`f64`) may rightly pick neighbouring cells.
fn eye_samples(base: &ShadowTransform, width: u32, height: u32) -> Vec<shadowmap_rtw::EyeSample> {
    let cam = camera();
    let clip_from_world = cam.clip_from_world().unwrap().as_dmat4();
    let eye = cam.eye().as_dvec3();
    let uv_from_world = base.uv_from_world.as_dmat4();
    let off_border = |t: f64, n: u32| {
        let x = t * f64::from(n);
        (1e-3..=1.0 - 1e-3).contains(&(x - x.floor()))
    };
    let mut samples = Vec::new();
    for [a, b, c] in scene().mesh.triangles() {
        let normal = (b - a).cross(c - a).normalize_or_zero();
        const STEPS: u32 = 6;
        for i in 0..=STEPS {
            for j in 0..=STEPS - i {
                let (s, t) = (f64::from(i) / 6.0, f64::from(j) / 6.0);
                let p = a + (b - a) * s + (c - a) * t;
                let h = clip_from_world * p.extend(1.0);
                let inside =
                    h.w > 0.0 && h.x.abs() <= h.w && h.y.abs() <= h.w && (0.0..=h.w).contains(&h.z);
                let uv = uv_from_world * p.extend(1.0);
                if inside && off_border(uv.x / uv.w, width) && off_border(uv.y / uv.w, height) {
                    samples.push(shadowmap_rtw::EyeSample {
                        position: p.as_vec3(),
                        normal: normal.as_vec3(),
                        eye_distance: p.distance(eye) as f32,
                    });
                }
            }
        }
    }
    samples
}

/// The RTW depth pass fed the tables that `GpuRtw` builds on the GPU from a G-buffer
/// (`GpuRtw::depth_uniforms`, recorded in the same encoder as the build) renders the
/// same map as the pass fed the CPU tables (`accumulate_backward` + `WarpMaps::build`
/// on the same samples): at most 0.1% of texels differ by more than 1e-4.
#[test]
fn rtw_depth_pass_with_gpu_built_tables_matches_cpu_tables() {
    use shadowmap_rtw::ImportanceOptions;
    use shadowmap_wgpu::rtw::{GpuRtw, RtwGBufferTextures};
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "rtw_depth_pass_with_gpu_built_tables_matches_cpu_tables",
    ) else {
        return;
    };
    let (width, height) = (64u32, 48u32);
    let base = uniform();
    let warp_options = WarpOptions::default().with_blur_radius(2);
    let importance_options = ImportanceOptions::default();
    let samples = eye_samples(&base, width, height);
    // The G-buffer: one sample per texel, as many texels as samples (rows of 64).
    let gb_width = 64u32;
    let gb_height = (samples.len() as u32).div_ceil(gb_width);
    assert!(samples.len() > 500, "{} samples", samples.len());
    let mut texels: Vec<Option<shadowmap_rtw::EyeSample>> =
        samples.iter().copied().map(Some).collect();
    texels.resize((gb_width * gb_height) as usize, None);

    let mut importance = ImportanceMap::new(width, height).unwrap();
    importance
        .accumulate_backward(&base, &samples, None, &importance_options)
        .unwrap();
    let mut warps = WarpMaps::new(width, height).unwrap();
    warps.build(&importance, &warp_options).unwrap();
    let shadow = RtwShadow {
        base,
        warps: &warps,
    };
    assert!(
        warps
            .x_table()
            .iter()
            .chain(warps.y_table())
            .any(|t| t.abs() > 1e-2),
        "a real warp"
    );
    let mut casters = Vec::new();
    subdivide_for_rtw(
        &shadow,
        &scene().mesh.triangles_f32(),
        &RtwSubdivision::default().with_resolution(RES),
        &mut casters,
    );
    let cpu_tables = RtwShadowRaw::tables(&shadow);

    let (gpu_tables, from_cpu, from_gpu) = ctx
        .scoped(|ctx| {
            let mesh = MeshBuffers::from_triangles(ctx, &casters)?;
            let gbuffer =
                RtwGBufferTextures::from_samples(ctx, gb_width, gb_height, &texels, None)?;
            let rtw = GpuRtw::new(ctx, width, height, &warp_options, &importance_options)?;
            let desc = DepthPassDesc::new(DepthTechnique::Rtw, RES);
            let mut cpu_pass = ShadowDepthPass::new(ctx, &desc)?;
            let mut gpu_pass = ShadowDepthPass::new(ctx, &desc)?;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            cpu_pass.encode(
                ctx,
                &mut encoder,
                &[&mesh],
                &DepthUniforms::Rtw {
                    raw: shadow.to_raw(),
                    tables: &cpu_tables,
                },
            )?;
            rtw.encode(ctx, &mut encoder, &gbuffer.as_gbuffer(), &base)?;
            gpu_pass.encode(ctx, &mut encoder, &[&mesh], &rtw.depth_uniforms(&base))?;
            ctx.queue.submit([encoder.finish()]);
            let tables = rtw.read_tables(ctx)?;
            Ok((
                tables,
                cpu_pass.readback_depth(ctx)?,
                gpu_pass.readback_depth(ctx)?,
            ))
        })
        .expect("GPU RTW build and depth passes");

    // The tables agree (gpu_rtw.rs tests this in depth); the maps are then compared.
    let table_error = gpu_tables
        .0
        .iter()
        .chain(&gpu_tables.1)
        .zip(&cpu_tables)
        .map(|(g, c)| (g - c).abs())
        .fold(0.0f32, f32::max);
    assert!(table_error < 1e-4, "tables differ by {table_error}");
    let drawn = from_gpu.iter().filter(|d| **d < 1.0).count();
    assert!(drawn > from_gpu.len() / 20, "only {drawn} texels drawn");
    let differing = from_gpu
        .iter()
        .zip(&from_cpu)
        .filter(|(g, c)| (**g - **c).abs() > 1e-4)
        .count();
    eprintln!("tables differ by at most {table_error:e}");
    assert_close("rtw, GPU-built vs CPU tables", differing, from_gpu.len());
}
