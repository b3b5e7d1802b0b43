//! The GPU depth pass of cube shadow maps (the matrix pass, one layer per kept face,
//! faces sized by need in their layers' corners) matches the CPU reference
//! rasterizer of `shadowmap-eval`, with the tolerance of the
//! other depth tests: at most 0.1% of texels differ by more than 1e-4 in depth; and
//! a frame rendered through `render_shadow` (depth pass and face lookup) shadows what
//! a DPSM of the same light shadows. Tiled cube maps: every tile's square of the
//! GPU atlas matches the CPU rasterizer's map of the tile.

use glam::Vec3;
use shadowmap::Fitted;
use shadowmap::paraboloid::{CubeMap, CubeOptions, CubeOrientation, FaceSizes};
use shadowmap::{FitInput, Technique, fit};
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::GBuffer;
use shadowmap_eval::metrics::ScreenGeometry;
use shadowmap_eval::raster::{DepthMap, MatrixProjector, RasterOptions, rasterize_depth};
use shadowmap_eval::scene::Scene;
use shadowmap_eval::technique::{
    FrameContext, Technique as EvalTechnique, TechniqueKind, TechniqueOptions, eye_samples,
};
use shadowmap_frustum::{Camera, Light, Projection, SceneBounds};
use shadowmap_wgpu::depth::DepthBias;
use shadowmap_wgpu::depth::{
    DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, ShadowDepthPass,
};
use shadowmap_wgpu::refine::{GpuRefine, RefineOptions};
use shadowmap_wgpu::render::{
    HeadlessRenderer, MaskValue, RenderOptions, ShadowBias, ShadowFilter,
};
use shadowmap_wgpu::uniforms::{ToRaw, warped_cube};

const RES: u32 = 256;

/// The face matrices as the matrix pass's blocks.
fn blocks(cube: &CubeMap) -> Vec<shadowmap_wgpu::uniforms::MatrixShadowRaw> {
    (0..cube.layers())
        .filter_map(|layer| cube.transform(layer))
        .map(|t| t.to_raw())
        .collect()
}

/// The city block, its triangles, a camera over it and a lamp among its buildings,
/// inside the view (several faces kept).
fn lamp_among_buildings() -> (Scene, Vec<[Vec3; 3]>, Camera, Light) {
    let scene = Scene::city_block(1);
    let tris = scene.mesh.triangles_f32();
    let camera = Camera::look_at(
        Vec3::new(0.0, 40.0, 90.0),
        Vec3::new(0.0, 0.0, -20.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 4.0 / 3.0, 1.0, 300.0),
    )
    .unwrap();
    let lamp = Light::Point {
        position: Vec3::new(3.0, 30.0, -2.0),
        range: 400.0,
    };
    (scene, tris, camera, lamp)
}

/// `kind` fitted with 384² texels to the lamp among the buildings, on the eye
/// samples of a 320x240 G-buffer traced on the CPU; with the scene and its triangles.
fn fitted_among_buildings(kind: TechniqueKind) -> (Scene, Vec<[Vec3; 3]>, EvalTechnique) {
    let (scene, tris, camera, lamp) = lamp_among_buildings();
    let (width, height) = (320, 240);
    let bvh = Bvh::build(&scene.mesh).unwrap();
    let gbuffer = GBuffer::trace(&bvh, &camera, width, height).unwrap();
    let samples = eye_samples(&gbuffer, &camera);
    let screen = ScreenGeometry::new(&camera, width, height).unwrap();
    let frame = FrameContext {
        camera: &camera,
        light: &lamp,
        scene: scene.scene_bounds().unwrap(),
        eye_samples: &samples,
        pixels_per_radian: screen.pixels_per_radian().unwrap() as f32,
    };
    let options = TechniqueOptions::default().with_texel_budget(384 * 384);
    let technique = EvalTechnique::build(kind, &frame, &options).unwrap();
    (scene, tris, technique)
}

/// The matrix depth pass of `raws` over `tris`, read back.
fn gpu_depth(
    ctx: &shadowmap_wgpu::GpuContext,
    tris: &[[Vec3; 3]],
    desc: &DepthPassDesc,
    raws: &[shadowmap_wgpu::uniforms::MatrixShadowRaw],
) -> Vec<f32> {
    ctx.scoped(|ctx| {
        let mesh = MeshBuffers::from_triangles(ctx, tris)?;
        let mut pass = ShadowDepthPass::new(ctx, desc)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        pass.encode(ctx, &mut encoder, &[&mesh], &DepthUniforms::Matrix(raws))?;
        ctx.queue.submit([encoder.finish()]);
        pass.readback_depth(ctx)
    })
    .expect("GPU depth pass")
}

#[test]
fn cube_faces_match_the_cpu_rasterizer() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("cube_faces_match_the_cpu_rasterizer")
    else {
        return;
    };
    let (scene, tris, camera, lamp) = lamp_among_buildings();
    let bounds = SceneBounds::whole(scene.bounds().unwrap());
    // One layer per face: faces of one side.
    let equal = CubeOptions::default().with_sizes(FaceSizes::Equal);
    for options in [
        equal,
        equal.with_reversed_z(true),
        equal.with_focused(false),
    ] {
        let cube = CubeMap::fit(&lamp, &camera, None, &bounds, &options).unwrap();
        let layers = cube.layers();
        assert!(layers >= 3, "{layers} faces");
        let raws = blocks(&cube);
        let desc = DepthPassDesc::new(DepthTechnique::Matrix, RES)
            .with_layers(layers)
            .with_reversed_z(cube.reversed_z);
        let gpu = gpu_depth(&ctx, &tris, &desc, &raws);
        let matrices = cube
            .faces
            .iter()
            .map(|f| f.clip_from_world.as_dmat4())
            .collect();
        let projector = MatrixProjector::new(matrices, cube.reversed_z);
        let raster = RasterOptions::default().with_size(RES, RES);
        let cpu: DepthMap = rasterize_depth(&scene.mesh, &projector, &raster).unwrap();
        assert_eq!(gpu.len(), cpu.depth.len());
        let differing = gpu
            .iter()
            .zip(&cpu.depth)
            .filter(|(g, c)| (**g - **c).abs() > 1e-4)
            .count();
        let fraction = differing as f64 / gpu.len() as f64;
        eprintln!(
            "cube {options:?}: {differing} of {} texels differ ({fraction:.5})",
            gpu.len()
        );
        assert!(
            fraction <= 1e-3,
            "{differing} of {} texels differ",
            gpu.len()
        );
        // Every kept face has something drawn in it.
        let n = (RES * RES) as usize;
        let clear = cpu.clear_value();
        for layer in 0..layers as usize {
            let drawn = cpu.depth[layer * n..(layer + 1) * n]
                .iter()
                .filter(|d| **d != clear)
                .count();
            assert!(drawn > n / 20, "layer {layer}: only {drawn} texels drawn");
        }
    }
}

/// A frame through `render_shadow` (the face lookup by projection): its shadow mask
/// is not trivial and agrees with a DPSM's of the same light on nearly every pixel
/// both cover (the two differ only along shadow edges, at their own resolutions),
/// the cube along the world axes, turned toward the receivers or stood on a corner.
#[test]
fn cube_frames_shadow_what_a_dpsm_shadows() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("cube_frames_shadow_what_a_dpsm_shadows")
    else {
        return;
    };
    let scene = Scene::city_block(1);
    let tris: Vec<[Vec3; 3]> = scene.mesh.triangles_f32();
    let camera = Camera::look_at(
        Vec3::new(0.0, 40.0, 90.0),
        Vec3::new(0.0, 0.0, -20.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 4.0 / 3.0, 1.0, 300.0),
    )
    .unwrap();
    let lamp = Light::Point {
        position: Vec3::new(10.0, 45.0, -30.0),
        range: 400.0,
    };
    let input = FitInput::new(
        &camera,
        &lamp,
        SceneBounds::whole(scene.bounds().unwrap()),
        1 << 20,
    );
    // Perspective depth with the light among the buildings (near plane 0.05 m,
    // receivers 45 to 240 m away) changes by about `near / d²` per metre: a small
    // lookup and rasterizer bias, or the default's 1e-4 leaks light metres deep.
    let raster = DepthBias {
        constant: 2,
        slope_scale: 1.5,
        clamp: 0.0,
    };
    let options = RenderOptions::default()
        .with_size(200, 150)
        .with_filter(ShadowFilter::Hard)
        .with_bias(ShadowBias::new(raster, 2e-7, 0.0));
    let mut renderer = HeadlessRenderer::new();
    let mut mask = |technique: &Technique| {
        let shadow = fit(technique, &input).unwrap();
        if let Technique::CubeMaps(o) = technique {
            let turned = shadow.cube().unwrap().orientation() != glam::Quat::IDENTITY;
            assert_eq!(turned, o.orientation != CubeOrientation::WorldAxes);
        }

        renderer
            .render_shadow(&ctx, &tris, &camera, &shadow, &options)
            .unwrap()
            .mask
            .values
    };
    let dpsm = mask(&Technique::Dpsm(Default::default()));
    let equal = CubeOptions::default().with_sizes(FaceSizes::Equal);
    for cube in [
        Technique::CubeMaps(equal),
        Technique::CubeMaps(equal.with_reversed_z(true)),
        Technique::CubeMaps(equal.with_focused(false)),
        Technique::CubeMaps(equal.with_orientation(CubeOrientation::TowardReceivers)),
        Technique::CubeMaps(equal.with_orientation(CubeOrientation::CornerUp)),
    ] {
        let values = mask(&cube);
        let count = |v: MaskValue| values.iter().filter(|g| **g == v).count();
        let (lit, shadowed) = (count(MaskValue::Lit), count(MaskValue::Shadowed));
        let both: Vec<(bool, bool)> = values
            .iter()
            .zip(&dpsm)
            .filter_map(|(c, d)| Some((c.lit()?, d.lit()?)))
            .collect();
        let differing = both.iter().filter(|(c, d)| c != d).count();
        let leaks = both.iter().filter(|(c, d)| *c && !*d).count();
        eprintln!("lit where DPSM shadowed: {leaks}");
        eprintln!(
            "{cube:?}: lit {lit}, shadowed {shadowed}; {differing} of {} differ from DPSM",
            both.len()
        );
        assert!(
            lit > values.len() / 10 && shadowed > values.len() / 100,
            "a trivial mask"
        );
        assert!(both.len() > values.len() / 2);
        assert!(
            differing as f64 <= 0.03 * both.len() as f64,
            "{differing} of {} differ",
            both.len()
        );
    }
}

/// Faces sized by need (different sides): each drawn into the top-left corner of a
/// layer of the largest face's side, its corner matches the CPU rasterizer's map of
/// the face at its own size (the fit's texel density), within the tolerance of the
/// other depth tests. (Whole frames of them, lookup included, are compared with the
/// CPU reference in `gpu_volume`, as the report's `cube`.)
#[test]
fn cube_faces_of_different_sides_match_the_cpu_rasterizer() {
    let Some(ctx) = shadowmap_wgpu::context::test_context(
        "cube_faces_of_different_sides_match_the_cpu_rasterizer",
    ) else {
        return;
    };
    let (scene, tris, camera, lamp) = lamp_among_buildings();
    let bounds = SceneBounds::whole(scene.bounds().unwrap());
    let options = CubeOptions::default()
        .with_sizes(FaceSizes::ByNeed)
        .with_texel_budget(384 * 384);
    let cube = CubeMap::fit(&lamp, &camera, None, &bounds, &options).unwrap();
    assert!(!cube.has_equal_faces());
    let side = cube.largest_side();
    let layers = cube.layers();
    let raws = shadowmap_wgpu::uniforms::cube_layers(&cube);
    let desc = DepthPassDesc::new(DepthTechnique::Matrix, side).with_layers(layers);
    let gpu = gpu_depth(&ctx, &tris, &desc, &raws);
    let n = (side * side) as usize;
    let (mut differing, mut compared) = (0, 0);
    for (layer, face) in cube.faces.iter().enumerate() {
        let [w, h] = face.size;
        let projector = MatrixProjector::new(vec![face.clip_from_world.as_dmat4()], false);
        let raster = RasterOptions::default().with_size(w, h);
        let cpu: DepthMap = rasterize_depth(&scene.mesh, &projector, &raster).unwrap();
        let corner = &gpu[layer * n..(layer + 1) * n];
        for row in 0..h as usize {
            for col in 0..w as usize {
                let g = corner[row * side as usize + col];
                let c = cpu.depth[row * w as usize + col];
                differing += usize::from((g - c).abs() > 1e-4);
                compared += 1;
            }
        }
    }
    let fraction = differing as f64 / compared as f64;
    eprintln!(
        "cube by need (side {side}): {differing} of {compared} texels differ ({fraction:.5})"
    );
    assert!(fraction <= 1e-3, "{differing} of {compared} texels differ");
}

/// RTW over the kept faces of a cube map (`cube_rtw`, faces sized by need, each with
/// its own warp tables): the casters cut to each face's window frustum and refined
/// on the GPU, drawn through the face's base and tables into its layer's corner,
/// match eval's reference (the CPU clip and subdivision, then its rasterizer) at the
/// face's own size, within the tolerance of the other depth tests.
#[test]
fn warped_cube_faces_match_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("warped_cube_faces_match_the_cpu_reference")
    else {
        return;
    };
    let (scene, tris, technique) = fitted_among_buildings(TechniqueKind::CubeRtw);
    let Fitted::CubeRtw { cube, warps } = technique.shadow().fitted() else {
        panic!("cube_rtw fits a cube map with tables");
    };
    assert!(cube.layers() >= 3, "{} faces", cube.layers());
    let cpu = technique
        .rasterize(&scene.mesh, &RasterOptions::default())
        .unwrap();
    let side = cube.largest_side();
    let warped = warped_cube(cube, warps);
    let uniforms = DepthUniforms::WarpedCube {
        layers: &warped.layers,
        tables: &warped.tables,
    };
    let gpu = ctx
        .scoped(|ctx| {
            let refine_options = RefineOptions::default()
                .with_resolution(side)
                .with_capacity(3 << 20);
            let mut refine = GpuRefine::new(ctx, &tris, &refine_options)?;
            let desc = DepthPassDesc::new(DepthTechnique::Rtw, side).with_layers(cube.layers());
            let mut pass = ShadowDepthPass::new(ctx, &desc)?;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            refine.encode(ctx, &mut encoder, &uniforms)?;
            pass.encode_refined(ctx, &mut encoder, &refine, &uniforms)?;
            ctx.queue.submit([encoder.finish()]);
            let stats = refine.read_stats(ctx)?;
            eprintln!("{stats:?}");
            assert!(!stats.overflowed, "refined at the CPU's depth");
            assert!(
                stats.layer_triangles[..cube.faces.len()]
                    .iter()
                    .all(|&n| n > 0)
            );
            pass.readback_depth(ctx)
        })
        .expect("GPU depth pass");
    let n = (side * side) as usize;
    let (mut differing, mut compared, mut offset) = (0, 0, 0);
    for (layer, face) in cube.faces.iter().enumerate() {
        let [w, h] = face.size;
        assert_eq!(cpu.layer_size(layer as u32), (w, h));
        let corner = &gpu[layer * n..(layer + 1) * n];
        let mut face_differing = 0;
        for row in 0..h as usize {
            for col in 0..w as usize {
                let g = corner[row * side as usize + col];
                let c = cpu.depth[offset + row * w as usize + col];
                face_differing += usize::from((g - c).abs() > 1e-4);
            }
        }
        eprintln!("face {layer} ({w}x{h}): {face_differing} texels differ");
        differing += face_differing;
        compared += (w * h) as usize;
        offset += (w * h) as usize;
    }
    let fraction = differing as f64 / compared as f64;
    eprintln!("cube_rtw (side {side}): {differing} of {compared} texels differ ({fraction:.5})");
    assert!(fraction <= 1e-3, "{differing} of {compared} texels differ");
}

/// Tiled cube maps (`cube_tiled`): every tile drawn through its cropped face
/// projection into its square of the atlas (one matrix pass, a viewport per tile),
/// with the whole mesh and with only the casters binned to the tile, matches eval's
/// reference, which rasterizes each tile on its own at its stored side, within the
/// tolerance of the other depth tests; texels between the tiles stay clear; the bins
/// draw under a quarter of the triangles the unbinned pass draws (on this city
/// block, 5.5 times fewer: the ground's and the walls' large triangles reach many
/// tiles).
#[test]
fn tiled_cube_atlas_matches_the_cpu_reference() {
    let Some(ctx) =
        shadowmap_wgpu::context::test_context("tiled_cube_atlas_matches_the_cpu_reference")
    else {
        return;
    };
    let (scene, tris, technique) = fitted_among_buildings(TechniqueKind::CubeTiled);
    let tiled = technique.shadow().tiled_cube().expect("a tiled cube map");
    assert!(tiled.tiles.len() > 20, "{} tiles", tiled.tiles.len());
    let cpu = technique
        .rasterize(&scene.mesh, &RasterOptions::default())
        .unwrap();
    let side = technique.shadow().layer_side();
    let uniforms = shadowmap_wgpu::tiles::tiled_uniforms(tiled, side);
    let bins = shadowmap_wgpu::tiles::tile_bins(tiled, &tris);
    let drawn = bins.indices.len() / 3;
    eprintln!(
        "{drawn} triangles drawn over {} tiles ({} per tile of {})",
        tiled.tiles.len(),
        drawn / tiled.tiles.len(),
        tris.len()
    );
    assert!(drawn < tris.len() * tiled.tiles.len() / 4, "{drawn}");
    for bins in [None, Some(&bins)] {
        let gpu = ctx
            .scoped(|ctx| {
                let mesh = MeshBuffers::from_triangles(ctx, &tris)?;
                let desc = DepthPassDesc::new(DepthTechnique::Matrix, side);
                let mut pass = ShadowDepthPass::new(ctx, &desc)?;
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                pass.encode_tiles(ctx, &mut encoder, &mesh, &uniforms.draws, bins)?;
                ctx.queue.submit([encoder.finish()]);
                pass.readback_depth(ctx)
            })
            .expect("GPU depth pass");
        compare_atlas(&gpu, &cpu, &uniforms.draws, side);
    }
}

/// Every tile's square of the GPU atlas (`side` texels a row) against the CPU
/// reference's layer of the tile: at most 0.1% of texels more than 1e-4 apart, and
/// nothing drawn outside the tiles.
fn compare_atlas(
    gpu: &[f32],
    cpu: &DepthMap,
    draws: &[shadowmap_wgpu::tiles::TileDraw],
    side: u32,
) {
    let (mut differing, mut compared, mut offset) = (0, 0, 0);
    let mut covered = vec![false; gpu.len()];
    for (layer, draw) in draws.iter().enumerate() {
        let s = draw.side as usize;
        assert_eq!(cpu.layer_size(layer as u32), (draw.side, draw.side));
        for row in 0..s {
            for col in 0..s {
                let at =
                    (draw.offset[1] as usize + row) * side as usize + draw.offset[0] as usize + col;
                covered[at] = true;
                let c = cpu.depth[offset + row * s + col];
                differing += usize::from((gpu[at] - c).abs() > 1e-4);
            }
        }
        compared += s * s;
        offset += s * s;
    }
    let fraction = differing as f64 / compared as f64;
    eprintln!(
        "cube_tiled ({} tiles in {side}): {differing} of {compared} texels differ ({fraction:.5})",
        draws.len()
    );
    assert!(fraction <= 1e-3, "{differing} of {compared} texels differ");
    let stray = gpu
        .iter()
        .zip(&covered)
        .filter(|(d, c)| !**c && **d != 1.0)
        .count();
    assert_eq!(stray, 0, "texels drawn outside every tile");
}
