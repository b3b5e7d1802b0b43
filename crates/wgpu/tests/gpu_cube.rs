//! The GPU depth pass of cube shadow maps (the matrix pass, one layer per kept face)
//! matches the CPU reference rasterizer of `shadowmap-eval`, with the tolerance of the
//! other depth tests: at most 0.1% of texels differ by more than 1e-4 in depth.

use glam::Vec3;
use shadowmap::paraboloid::{CubeMap, CubeOptions};
use shadowmap_eval::raster::{DepthMap, MatrixProjector, RasterOptions, rasterize_depth};
use shadowmap_eval::scene::Scene;
use shadowmap_frustum::{Camera, Light, Projection, SceneBounds};
use shadowmap_wgpu::depth::{
    DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, ShadowDepthPass,
};
use shadowmap_wgpu::uniforms::ToRaw;

const RES: u32 = 256;

/// The face matrices as the matrix pass's blocks.
fn blocks(cube: &CubeMap) -> Vec<shadowmap_wgpu::uniforms::MatrixShadowRaw> {
    (0..cube.layers())
        .filter_map(|layer| cube.transform(layer))
        .map(|t| t.to_raw())
        .collect()
}

#[test]
fn cube_faces_match_the_cpu_rasterizer() {
    let Some(ctx) = shadowmap_wgpu::context::test_context("cube_faces_match_the_cpu_rasterizer")
    else {
        return;
    };
    let scene = Scene::city_block(1);
    let tris: Vec<[Vec3; 3]> = scene
        .mesh
        .triangles()
        .map(|t| t.map(glam::DVec3::as_vec3))
        .collect();
    let camera = Camera::look_at(
        Vec3::new(0.0, 40.0, 90.0),
        Vec3::new(0.0, 0.0, -20.0),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 4.0 / 3.0, 1.0, 300.0),
    )
    .unwrap();
    // A lamp among the buildings, inside the view: several faces kept.
    let lamp = Light::Point {
        position: Vec3::new(3.0, 30.0, -2.0),
        range: 400.0,
    };
    let bounds = SceneBounds::whole(scene.bounds().unwrap());
    for options in [
        CubeOptions::default(),
        CubeOptions::default().with_reversed_z(true),
        CubeOptions::default().with_focused(false),
    ] {
        let cube = CubeMap::fit(&lamp, &camera, None, &bounds, &options).unwrap();
        let layers = cube.layers();
        assert!(layers >= 3, "{layers} faces");
        let raws = blocks(&cube);
        let desc = DepthPassDesc::new(DepthTechnique::Matrix, RES)
            .with_layers(layers)
            .with_reversed_z(cube.reversed_z);
        let gpu = ctx
            .scoped(|ctx| {
                let mesh = MeshBuffers::from_triangles(ctx, &tris)?;
                let mut pass = ShadowDepthPass::new(ctx, &desc)?;
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                pass.encode(ctx, &mut encoder, &[&mesh], &DepthUniforms::Matrix(&raws))?;
                ctx.queue.submit([encoder.finish()]);
                pass.readback_depth(ctx)
            })
            .expect("GPU depth pass");
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
