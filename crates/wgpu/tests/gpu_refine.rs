//! Caster refinement on the GPU (`GpuRefine` + `ShadowDepthPass::encode_refined`)
//! against the CPU reference subdivisions (+ `encode`), rendered by the same depth
//! pass: RTW's (`subdivide_for_rtw`: the same triangles), the paraboloid grid of
//! `subdivide_triangles` (DPSM, IPSM) and RTW over paraboloid sides
//! (`subdivide_for_rtw_clipped` at the side's plane, `point_rtw`): piece counts
//! within 0.5% (an edge whose error is within `f32` rounding of its bound may split
//! differently) and the same
//! depth map within the tolerance of the other depth tests (at most 0.1% of texels
//! differ by more than 1e-4); no cracks on a closed mesh; a coarser mesh, never a
//! truncated one, when the capacity is short; casters behind a perspective light
//! dropped both ways.

use std::collections::HashSet;

use glam::{Mat4, Vec2, Vec3};
use shadowmap::paraboloid::{
    IpsmOptions, IpsmPlan, MapOptions, ParaboloidMap, Side, SubdivisionOptions, subdivide_triangles,
};
use shadowmap::{FitInput, Technique, fit};
use shadowmap_eval::scene::Scene;
use shadowmap_frustum::{Camera, DepthBounds, Light, LightDirection, Projection, ShadowTransform};
use shadowmap_rtw::{
    ImportanceMap, RtwShadow, WarpMaps, WarpOptions, forward_warp, subdivide_for_rtw_clipped,
};
use shadowmap_warp::SceneBounds;
use shadowmap_wgpu::depth::{
    DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, RtwSubdivision, ShadowDepthPass,
    subdivide_for_rtw,
};
use shadowmap_wgpu::refine::{GpuRefine, RefineOptions, RefineStats};
use shadowmap_wgpu::uniforms::{RtwShadowRaw, ToRaw, paraboloid_layers, warped_paraboloid};
use shadowmap_wgpu::{BackendError, GpuContext};
use wgpu::util::DeviceExt;

const RES: u32 = 256;

fn city() -> Vec<[Vec3; 3]> {
    Scene::city_block(1).mesh.triangles_f32()
}

/// The uniform fit of the depth tests (`gpu_depth.rs`) over the city block.
fn city_base() -> ShadowTransform {
    let camera = Camera::look_at(
        Vec3::new(0.0, 40.0, 90.0),
        Vec3::new(0.0, 0.0, -20.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 4.0 / 3.0, 1.0, 300.0),
    )
    .unwrap();
    let light = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let focus = SceneBounds::whole(Scene::city_block(1).bounds().unwrap());
    let input = FitInput::new(&camera, &light, focus, u64::from(RES * RES));
    *fit(&Technique::UniformFocused(Default::default()), &input)
        .unwrap()
        .transform()
        .unwrap()
}

/// Tables with a strong warp: three importance peaks over `64 x 48` cells.
fn warps() -> WarpMaps {
    let mut importance = ImportanceMap::new(64, 48).unwrap();
    importance.splat(Vec2::new(0.5, 0.6), 10.0).unwrap();
    importance.splat(Vec2::new(0.3, 0.2), 3.0).unwrap();
    importance.splat(Vec2::new(0.8, 0.9), 1.0).unwrap();
    let mut warps = WarpMaps::new(64, 48).unwrap();
    warps
        .build(&importance, &WarpOptions::default().with_blur_radius(4))
        .unwrap();
    assert!(
        warps.x_table().iter().any(|t| t.abs() > 1e-2),
        "a real warp"
    );
    warps
}

/// What one frame drew both ways.
struct Frame {
    /// The pass fed the CPU-subdivided mesh.
    cpu_depth: Vec<f32>,
    /// The pass fed the GPU-refined casters.
    gpu_depth: Vec<f32>,
    stats: RefineStats,
    refined: Vec<[Vec3; 3]>,
}

/// Renders `cpu_meshes` (one per layer) with `encode` and `casters` refined on the
/// GPU with `encode_refined`, in one submission, from the same uniforms.
fn render_both(
    ctx: &GpuContext,
    uniforms: &DepthUniforms<'_>,
    cpu_meshes: &[&[[Vec3; 3]]],
    casters: &[[Vec3; 3]],
    options: &RefineOptions,
) -> Frame {
    let technique = match uniforms {
        DepthUniforms::Rtw { .. } | DepthUniforms::RtwGpuTables { .. } => DepthTechnique::Rtw,
        _ => DepthTechnique::Paraboloid,
    };
    ctx.scoped(|ctx| {
        let meshes = cpu_meshes
            .iter()
            .map(|m| MeshBuffers::from_triangles(ctx, m))
            .collect::<Result<Vec<_>, _>>()?;
        let refs: Vec<&MeshBuffers> = meshes.iter().collect();
        let mut refine = GpuRefine::new(ctx, casters, options)?;
        let layers = u32::try_from(refs.len()).unwrap();
        let desc = DepthPassDesc::new(technique, RES).with_layers(layers);
        let mut cpu_pass = ShadowDepthPass::new(ctx, &desc)?;
        let mut gpu_pass = ShadowDepthPass::new(ctx, &desc)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        cpu_pass.encode(ctx, &mut encoder, &refs, uniforms)?;
        refine.encode(ctx, &mut encoder, uniforms)?;
        gpu_pass.encode_refined(ctx, &mut encoder, &refine, uniforms)?;
        ctx.queue.submit([encoder.finish()]);
        Ok(Frame {
            cpu_depth: cpu_pass.readback_depth(ctx)?,
            gpu_depth: gpu_pass.readback_depth(ctx)?,
            stats: refine.read_stats(ctx)?,
            refined: refine.read_triangles(ctx)?,
        })
    })
    .expect("GPU refinement and depth passes")
}

/// The bits of a triangle, for exact set comparison.
fn key(t: &[Vec3; 3]) -> [u32; 9] {
    let f = [
        t[0].x, t[0].y, t[0].z, t[1].x, t[1].y, t[1].z, t[2].x, t[2].y, t[2].z,
    ];
    f.map(f32::to_bits)
}

/// Asserts the GPU pieces are the CPU's (up to `f32` decisions within an ulp of the
/// bound: at most 0.5% of them differ) and the two maps agree.
fn assert_same(name: &str, frame: &Frame, cpu_mesh: &[[Vec3; 3]]) {
    let cpu: HashSet<[u32; 9]> = cpu_mesh.iter().map(key).collect();
    let shared = frame
        .refined
        .iter()
        .filter(|t| cpu.contains(&key(t)))
        .count();
    let (gpu_n, cpu_n) = (frame.refined.len(), cpu_mesh.len());
    eprintln!("{name}: GPU {gpu_n} pieces, CPU {cpu_n}, {shared} identical");
    assert_eq!(gpu_n, frame.stats.triangles as usize);
    assert!(
        shared as f64 >= 0.995 * cpu_n.max(gpu_n) as f64,
        "{name}: meshes differ"
    );
    assert_maps_agree(name, frame);
}

/// Asserts each layer's piece count is the CPU's within 0.5% (the paraboloid grid's
/// vertices are computed in `f32` on the GPU, in `f64` on the CPU, so pieces are
/// compared by count) and the two maps agree.
fn assert_counts(name: &str, frame: &Frame, cpu_meshes: &[&[[Vec3; 3]]]) {
    for (layer, mesh) in cpu_meshes.iter().enumerate() {
        let (gpu, cpu) = (frame.stats.layer_triangles[layer] as usize, mesh.len());
        eprintln!("{name} layer {layer}: GPU {gpu} pieces, CPU {cpu}");
        assert!(
            gpu.abs_diff(cpu) as f64 <= 5e-3 * cpu as f64,
            "{name} layer {layer}: GPU {gpu}, CPU {cpu} pieces"
        );
    }
    assert_maps_agree(name, frame);
}

/// Asserts the two maps agree on all but 0.1% of texels (1e-4 in depth), with
/// something drawn.
fn assert_maps_agree(name: &str, frame: &Frame) {
    let drawn = frame.gpu_depth.iter().filter(|d| **d < 1.0).count();
    assert!(
        drawn > frame.gpu_depth.len() / 20,
        "{name}: only {drawn} texels drawn"
    );
    let differing = frame
        .gpu_depth
        .iter()
        .zip(&frame.cpu_depth)
        .filter(|(g, c)| (**g - **c).abs() > 1e-4)
        .count();
    eprintln!(
        "{name}: {differing} of {} texels differ by more than 1e-4",
        drawn
    );
    assert!(differing as f64 <= 1e-3 * frame.gpu_depth.len() as f64);
}

#[test]
fn gpu_refinement_draws_the_cpu_subdivision() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("gpu_refinement_draws_the_cpu_subdivision")
    else {
        return;
    };
    let warps = warps();
    let shadow = RtwShadow {
        base: city_base(),
        warps: &warps,
    };
    let casters = city();
    let subdivision = RtwSubdivision::default().with_resolution(RES);
    let mut cpu_mesh = Vec::new();
    subdivide_for_rtw(&shadow, &casters, &subdivision, &mut cpu_mesh);
    assert!(
        cpu_mesh.len() > 3 * casters.len(),
        "the warp splits casters"
    );
    let options = RefineOptions::default().with_subdivision(subdivision);
    let tables = RtwShadowRaw::tables(&shadow);
    let from_slice = DepthUniforms::Rtw {
        raw: shadow.to_raw(),
        tables: &tables,
    };
    let frame = render_both(&ctx, &from_slice, &[&cpu_mesh], &casters, &options);
    assert!(!frame.stats.overflowed);
    assert_eq!(frame.stats.levels, frame.stats.requested_levels);
    assert_same("tables from a slice", &frame, &cpu_mesh);

    // The same tables in a GPU buffer (as `GpuRtw::depth_uniforms` hands them over).
    let buffer = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("tables"),
            contents: bytemuck::cast_slice(&tables),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
    let from_buffer = DepthUniforms::RtwGpuTables {
        raw: shadow.to_raw(),
        tables: &buffer,
    };
    let frame = render_both(&ctx, &from_buffer, &[&cpu_mesh], &casters, &options);
    assert_same("tables in a GPU buffer", &frame, &cpu_mesh);
}

#[test]
fn a_short_capacity_refines_coarser_and_drops_nothing() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("a_short_capacity_refines_coarser_and_drops_nothing")
    else {
        return;
    };
    let warps = warps();
    let shadow = RtwShadow {
        base: city_base(),
        warps: &warps,
    };
    let casters = city();
    let subdivision = RtwSubdivision::default().with_resolution(RES);
    let capacity = 3 * casters.len() as u32;
    let options = RefineOptions::default()
        .with_subdivision(subdivision)
        .with_capacity(capacity);
    let tables = RtwShadowRaw::tables(&shadow);
    let uniforms = DepthUniforms::Rtw {
        raw: shadow.to_raw(),
        tables: &tables,
    };
    // Learn the level that fits, then compare with the CPU capped at that level.
    let probe = render_both(&ctx, &uniforms, &[&casters], &casters, &options);
    let stats = probe.stats;
    eprintln!("{stats:?}");
    assert!(stats.overflowed, "{} triangles fit", capacity);
    assert!(stats.levels < stats.requested_levels);
    assert!(stats.triangles <= capacity && stats.triangles >= casters.len() as u32);
    let mut cpu_mesh = Vec::new();
    let capped = subdivision.with_max_segments(1 << stats.levels);
    subdivide_for_rtw(&shadow, &casters, &capped, &mut cpu_mesh);
    let frame = render_both(&ctx, &uniforms, &[&cpu_mesh], &casters, &options);
    assert_eq!(frame.stats, stats);
    assert_same("capped", &frame, &cpu_mesh);
}

/// An orthographic base with `uv = (x, y)` and depth `z`, light along `-z`.
fn identity_base() -> ShadowTransform {
    let clip_from_world = Mat4::from_cols_array(&[
        2.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0,
    ]);
    ShadowTransform::new(
        Mat4::IDENTITY,
        clip_from_world,
        false,
        LightDirection::Directional(Vec3::NEG_Z),
    )
}

/// A closed box `[0.2, 0.7] x [0.3, 0.8] x [0.3, 0.6]` whose face toward the light
/// (`z = 0.3`) is cut into irregular triangles through two inner points.
fn closed_box() -> Vec<[Vec3; 3]> {
    let (x0, x1, y0, y1, near, far) = (0.2, 0.7, 0.3, 0.8, 0.3, 0.6);
    let corner = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let [a, b, c, d] = [
        corner(x0, y0, near),
        corner(x1, y0, near),
        corner(x1, y1, near),
        corner(x0, y1, near),
    ];
    let [e, f, g, h] = [
        corner(x0, y0, far),
        corner(x1, y0, far),
        corner(x1, y1, far),
        corner(x0, y1, far),
    ];
    let p = corner(0.31, 0.42, near);
    let q = corner(0.63, 0.71, near);
    vec![
        // The near face: a fan around p and q (all edges shared).
        [a, b, p],
        [b, q, p],
        [b, c, q],
        [c, d, q],
        [d, p, q],
        [d, a, p],
        // The far face and the four sides.
        [e, g, f],
        [e, h, g],
        [a, e, f],
        [a, f, b],
        [b, f, g],
        [b, g, c],
        [c, g, h],
        [c, h, d],
        [d, h, e],
        [d, e, a],
    ]
}

/// The warp is separable, so the near face's image is exactly the rectangle of its
/// warped corners: every texel whose centre lies a texel inside holds the near depth
/// (a crack would show the far face or the clear value), and every texel a texel
/// outside is clear.
#[test]
fn a_closed_box_covers_its_silhouette_without_cracks() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("a_closed_box_covers_its_silhouette_without_cracks")
    else {
        return;
    };
    let mut importance = ImportanceMap::new(16, 8).unwrap();
    importance.splat(Vec2::new(0.4, 0.5), 1.0).unwrap();
    let mut warps = WarpMaps::new(16, 8).unwrap();
    warps.build(&importance, &WarpOptions::default()).unwrap();
    let shadow = RtwShadow {
        base: identity_base(),
        warps: &warps,
    };
    let casters = closed_box();
    let tables = RtwShadowRaw::tables(&shadow);
    let uniforms = DepthUniforms::Rtw {
        raw: shadow.to_raw(),
        tables: &tables,
    };
    let subdivision = RtwSubdivision::default().with_resolution(RES);
    let options = RefineOptions::default().with_subdivision(subdivision);
    let frame = render_both(&ctx, &uniforms, &[&casters], &casters, &options);
    assert!(
        frame.stats.triangles > 4 * casters.len() as u32,
        "{:?}",
        frame.stats
    );
    let (u0, u1) = (
        forward_warp(warps.x_table(), 0.2),
        forward_warp(warps.x_table(), 0.7),
    );
    let (v0, v1) = (
        forward_warp(warps.y_table(), 0.3),
        forward_warp(warps.y_table(), 0.8),
    );
    let texel = 1.0 / RES as f32;
    let (mut inside, mut outside) = (0, 0);
    for (i, depth) in frame.gpu_depth.iter().enumerate() {
        let u = ((i as u32 % RES) as f32 + 0.5) * texel;
        let v = ((i as u32 / RES) as f32 + 0.5) * texel;
        let within = |lo: f32, hi: f32, x: f32, margin: f32| lo + margin < x && x < hi - margin;
        if within(u0, u1, u, texel) && within(v0, v1, v, texel) {
            inside += 1;
            assert!(
                (depth - 0.3).abs() < 1e-6,
                "crack at ({u}, {v}): depth {depth}"
            );
        } else if !(within(u0, u1, u, -texel) && within(v0, v1, v, -texel)) {
            outside += 1;
            assert_eq!(*depth, 1.0, "texel ({u}, {v}) outside the silhouette drawn");
        }
    }
    assert!(
        inside > 1000 && outside > 1000,
        "{inside} inside, {outside} outside"
    );
}

#[test]
fn bad_input_is_a_typed_error() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("bad_input_is_a_typed_error") else {
        return;
    };
    let options = RefineOptions::default();
    let one = [[Vec3::ZERO, Vec3::X, Vec3::Y]];
    let invalid =
        |r: Result<GpuRefine, BackendError>| matches!(r, Err(BackendError::InvalidInput(_)));
    assert!(invalid(GpuRefine::new(&ctx, &[], &options)));
    assert!(invalid(GpuRefine::new(
        &ctx,
        &one,
        &options.with_capacity(0)
    )));
    assert!(invalid(GpuRefine::new(
        &ctx,
        &one,
        &options.with_capacity(u32::MAX)
    )));
    let mut refine = GpuRefine::new(&ctx, &one, &options).unwrap();
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let base = identity_base();
    let matrix = DepthUniforms::Matrix(&[base.to_raw()]);
    assert!(refine.encode(&ctx, &mut encoder, &matrix).is_err());
    let short = DepthUniforms::Rtw {
        raw: RtwShadowRaw::from_base(&base, 16, 8),
        tables: &[0.0; 4],
    };
    assert!(refine.encode(&ctx, &mut encoder, &short).is_err());
    let mut matrix_pass =
        ShadowDepthPass::new(&ctx, &DepthPassDesc::new(DepthTechnique::Matrix, 64)).unwrap();
    assert!(
        matrix_pass
            .encode_refined(&ctx, &mut encoder, &refine, &matrix)
            .is_err()
    );
}

/// A DPSM over the city block, the front side facing down.
fn dpsm() -> ParaboloidMap {
    ParaboloidMap::dual(
        Vec3::new(5.0, 45.0, 10.0),
        Vec3::new(0.1, -1.0, 0.05),
        0.5,
        600.0,
        &MapOptions::default(),
    )
    .unwrap()
}

/// IPSM's map for a view of the block with the lamp behind and above the camera,
/// outside the truncated frustum: one cut paraboloid.
fn ipsm() -> ParaboloidMap {
    let camera = Camera::look_at(
        Vec3::new(10.0, 18.0, 120.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 1.0, 500.0),
    )
    .unwrap();
    let lamp = Light::Point {
        position: Vec3::new(-30.0, 80.0, 220.0),
        range: 600.0,
    };
    let bounds = DepthBounds {
        min: 5.0,
        max: 250.0,
    };
    let map = IpsmPlan::new(&lamp, &camera, Some(bounds), &IpsmOptions::default())
        .unwrap()
        .map;
    assert_eq!(map.layers(), 1, "a single cut paraboloid");
    map
}

/// Each side's CPU grid subdivision of the city block.
fn cpu_grid(map: &ParaboloidMap, options: &SubdivisionOptions) -> Vec<Vec<[Vec3; 3]>> {
    let casters = city();
    [Side::Front, Side::Back]
        .into_iter()
        .take(map.layers() as usize)
        .map(|side| {
            let mut out = Vec::new();
            subdivide_triangles(map, side, &casters, options, &mut out).unwrap();
            out
        })
        .collect()
}

fn slices(meshes: &[Vec<[Vec3; 3]>]) -> Vec<&[[Vec3; 3]]> {
    meshes.iter().map(Vec::as_slice).collect()
}

#[test]
fn gpu_grid_refinement_draws_the_cpu_subdivision() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("gpu_grid_refinement_draws_the_cpu_subdivision")
    else {
        return;
    };
    let sub = SubdivisionOptions::default().with_resolution(RES);
    let options = RefineOptions::default().with_paraboloid(sub);
    let casters = city();
    for (name, map) in [("dpsm", dpsm()), ("ipsm", ipsm())] {
        let cpu = cpu_grid(&map, &sub);
        let pieces: usize = cpu.iter().map(Vec::len).sum();
        assert!(
            pieces > 2 * casters.len() * cpu.len(),
            "{name}: the paraboloid splits casters ({pieces} pieces)"
        );
        let layers = paraboloid_layers(&map);
        let uniforms = DepthUniforms::Paraboloid(&layers);
        let frame = render_both(&ctx, &uniforms, &slices(&cpu), &casters, &options);
        assert!(!frame.stats.overflowed, "{name}: {:?}", frame.stats);
        assert_eq!(frame.stats.levels, 4, "{name}: 16 segments, 2^4");
        assert_counts(name, &frame, &slices(&cpu));
    }
}

#[test]
fn a_short_capacity_caps_the_grid_and_drops_nothing() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("a_short_capacity_caps_the_grid_and_drops_nothing")
    else {
        return;
    };
    let map = dpsm();
    let casters = city();
    let sub = SubdivisionOptions::default().with_resolution(RES);
    let capacity = 4 * casters.len() as u32;
    let options = RefineOptions::default()
        .with_paraboloid(sub)
        .with_capacity(capacity);
    let layers = paraboloid_layers(&map);
    let uniforms = DepthUniforms::Paraboloid(&layers);
    // Learn the cap that fits, then compare with the CPU capped there.
    let full = cpu_grid(&map, &sub);
    let probe = render_both(&ctx, &uniforms, &slices(&full), &casters, &options);
    let stats = probe.stats;
    eprintln!("{stats:?}");
    assert!(stats.overflowed && stats.levels < stats.requested_levels);
    assert!(stats.triangles <= capacity);
    assert!(
        stats
            .layer_triangles
            .iter()
            .take(layers.len())
            .all(|&n| n >= casters.len() as u32)
    );
    let capped = cpu_grid(&map, &sub.with_max_segments(1 << stats.levels));
    let frame = render_both(&ctx, &uniforms, &slices(&capped), &casters, &options);
    assert_eq!(frame.stats, stats);
    assert_counts("capped grid", &frame, &slices(&capped));
}

/// Tables with a strong warp over `64 x 64` cells, the peaks moved by `shift`.
fn square_warps(shift: f32) -> WarpMaps {
    let mut importance = ImportanceMap::new(64, 64).unwrap();
    importance.splat(Vec2::new(0.5, 0.6 - shift), 10.0).unwrap();
    importance.splat(Vec2::new(0.3 + shift, 0.2), 3.0).unwrap();
    importance.splat(Vec2::new(0.8, 0.9), 1.0).unwrap();
    let mut warps = WarpMaps::new(64, 64).unwrap();
    warps
        .build(&importance, &WarpOptions::default().with_blur_radius(3))
        .unwrap();
    warps
}

#[test]
fn gpu_rtw_over_paraboloid_sides_draws_the_cpu_subdivision() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "gpu_rtw_over_paraboloid_sides_draws_the_cpu_subdivision",
    ) else {
        return;
    };
    // Both sides of a DPSM, and IPSM's single cut paraboloid (zoomed: its disc
    // spans more than the map, so edges need more pieces to cross it).
    for (name, map) in [("dpsm", dpsm()), ("ipsm", ipsm())] {
        rtw_over_paraboloid(&ctx, name, &map);
    }
}

fn rtw_over_paraboloid(ctx: &shadowmap_wgpu::GpuContext, name: &str, map: &ParaboloidMap) {
    let (front, back) = (square_warps(0.0), square_warps(0.1));
    let sides = [(Side::Front, &front), (Side::Back, &back)];
    let sides = &sides[..map.layers() as usize];
    let sub = RtwSubdivision::default().with_resolution(RES);
    let casters = city();
    let cpu: Vec<Vec<[Vec3; 3]>> = sides
        .iter()
        .map(|(side, warps)| {
            // As eval's reference: cut at the side's plane, with enough pieces an
            // edge to cross the side's disc.
            let uv = |p: Vec3| map.project(p, *side).map(|s| s.uv);
            let plane = |p: Vec3| map.plane_distance(p, *side);
            let cells = warps.x_table().len().max(warps.y_table().len());
            let rule = sub.with_segments_for_extent(1.0 / f64::from(map.zoom), cells);
            let mut out = Vec::new();
            subdivide_for_rtw_clipped(uv, &[&plane], warps, &casters, &rule, &mut out);
            out
        })
        .collect();
    assert!(cpu[0].len() > 2 * casters.len(), "the warp splits casters");
    let warped = warped_paraboloid(map, Some(&front), (map.layers() > 1).then_some(&back));
    let uniforms = DepthUniforms::WarpedParaboloid {
        layers: &warped.layers,
        tables: &warped.tables,
    };
    let options = RefineOptions::default().with_subdivision(sub);
    let frame = render_both(ctx, &uniforms, &slices(&cpu), &casters, &options);
    assert!(!frame.stats.overflowed, "{:?}", frame.stats);
    assert_counts(name, &frame, &slices(&cpu));
}

/// RTW over a spot light's perspective fit with the light among the buildings:
/// casters with a vertex behind the light's plane are dropped by the CPU subdivision
/// and by the GPU refinement alike, and the maps agree.
#[test]
fn a_perspective_base_drops_casters_behind_the_light_both_ways() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "a_perspective_base_drops_casters_behind_the_light_both_ways",
    ) else {
        return;
    };
    let camera = Camera::look_at(
        Vec3::new(0.0, 30.0, 80.0),
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::Y,
        Projection::perspective(1.0, 4.0 / 3.0, 1.0, 300.0),
    )
    .unwrap();
    let spot = Light::Spot {
        position: Vec3::new(0.0, 12.0, 10.0),
        direction: Vec3::new(0.2, -0.6, -1.0),
        half_angle: 0.8,
        range: 300.0,
    };
    let focus = SceneBounds::whole(Scene::city_block(1).bounds().unwrap());
    let input = FitInput::new(&camera, &spot, focus, u64::from(RES * RES));
    let base = *fit(&Technique::SpotFit { reversed_z: false }, &input)
        .unwrap()
        .transform()
        .unwrap();
    let warps = warps();
    let shadow = RtwShadow {
        base,
        warps: &warps,
    };
    let casters = city();
    let behind = casters
        .iter()
        .filter(|t| {
            t.iter()
                .any(|p| (base.uv_from_world * p.extend(1.0)).w <= 0.0)
        })
        .count();
    assert!(
        behind > 100,
        "only {behind} casters cross the light's plane"
    );
    let subdivision = RtwSubdivision::default().with_resolution(RES);
    let mut cpu_mesh = Vec::new();
    subdivide_for_rtw(&shadow, &casters, &subdivision, &mut cpu_mesh);
    let options = RefineOptions::default().with_subdivision(subdivision);
    let tables = RtwShadowRaw::tables(&shadow);
    let uniforms = DepthUniforms::Rtw {
        raw: shadow.to_raw(),
        tables: &tables,
    };
    let frame = render_both(&ctx, &uniforms, &[&cpu_mesh], &casters, &options);
    assert_same("spot base", &frame, &cpu_mesh);
}
