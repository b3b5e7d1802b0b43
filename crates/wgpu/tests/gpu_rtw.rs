//! The GPU RTW pipeline reproduces the CPU one: on random (seeded) G-buffers, the warp
//! tables of [`GpuRtw`] equal those of `ImportanceMap::accumulate_backward` +
//! `WarpMaps::build` within 1e-4 (in practice ~1e-6), for several map sizes including
//! non-powers of two, orthographic and perspective base projections, several blur
//! radii and floors, temporal smoothing over two frames, and the identity fallback.
//!
//! Samples whose base `uv` lies within 1e-3 of a cell border are left out of the
//! G-buffer: there the GPU (`f32`) and the CPU (`f64`) may rightly pick neighbouring
//! cells. The G-buffer rendered on the GPU (`RtwGBufferPass`) holds the ray-traced
//! surfaces of `shadowmap_eval`'s G-buffer away from silhouettes.

use glam::{DVec3, Mat4, Vec3};
use shadowmap_eval::bvh::Bvh;
use shadowmap_eval::mask::GBuffer;
use shadowmap_eval::scene::Scene;
use shadowmap_frustum::{Camera, Projection};
use shadowmap_frustum::{LightDirection, ShadowTransform, projection};
use shadowmap_rtw::{EyeSample, ImportanceMap, ImportanceOptions, WarpMaps, WarpOptions};
use shadowmap_wgpu::depth::MeshBuffers;
use shadowmap_wgpu::gbuffer::RtwGBufferPass;
use shadowmap_wgpu::rtw::{GpuRtw, RtwGBufferTextures};
use shadowmap_wgpu::{BackendError, GpuContext, context::test_context};

const TABLE_TOLERANCE: f32 = 1e-4;

/// Width and height.
type MapSize = (u32, u32);

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40;
        bits as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
}

/// A directional light looking down at the box `[-10, 10]³` (orthographic base).
fn orthographic_base() -> ShadowTransform {
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

/// A spot light above the box (perspective base: `w` varies).
fn perspective_base() -> ShadowTransform {
    let eye = DVec3::new(2.0, 25.0, 3.0);
    let dir = (DVec3::ZERO - eye).normalize();
    let light_from_world = projection::look_to(eye, dir, DVec3::Z);
    let clip_from_light = projection::perspective(1.2, 1.0, 1.0, 60.0, false);
    ShadowTransform::new(
        light_from_world.as_mat4(),
        (clip_from_light * light_from_world).as_mat4(),
        false,
        LightDirection::Position(eye.as_vec3()),
    )
}

/// A random G-buffer: mostly samples in the box, some outside the base map, some
/// texels empty, some zero normals, some edge samples.
struct Frame {
    width: u32,
    height: u32,
    texels: Vec<Option<EyeSample>>,
    edges: Vec<bool>,
}

impl Frame {
    fn random(
        rng: &mut Rng,
        width: u32,
        height: u32,
        base: &ShadowTransform,
        map: (u32, u32),
    ) -> Self {
        let uv_from_world = base.uv_from_world.as_dmat4();
        let near_border = |p: Vec3| {
            let h = uv_from_world * p.as_dvec3().extend(1.0);
            if h.w <= 0.0 {
                return false;
            }
            let cell = |t: f64, n: u32| {
                let x = t * f64::from(n);
                let f = x - x.floor();
                !(1e-3..=1.0 - 1e-3).contains(&f)
            };
            cell(h.x / h.w, map.0) || cell(h.y / h.w, map.1)
        };
        let len = (width * height) as usize;
        let mut texels = Vec::with_capacity(len);
        let mut edges = Vec::with_capacity(len);
        // A few hot spots make the importance uneven, as real views do.
        let spots: Vec<Vec3> = (0..3)
            .map(|_| Vec3::new(rng.range(-8.0, 8.0), 0.0, rng.range(-8.0, 8.0)))
            .collect();
        for i in 0..len {
            let kind = rng.unit();
            let position = if kind < 0.1 {
                Vec3::new(
                    rng.range(-40.0, 40.0),
                    rng.range(-5.0, 5.0),
                    rng.range(-40.0, 40.0),
                )
            } else {
                let spot = spots[i % spots.len()];
                let spread = if kind < 0.5 { 1.0 } else { 10.0 };
                spot + Vec3::new(
                    rng.range(-spread, spread),
                    rng.range(-2.0, 2.0),
                    rng.range(-spread, spread),
                )
            };
            let normal = if rng.unit() < 0.2 {
                Vec3::ZERO
            } else {
                Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(0.0, 2.0),
                    rng.range(-1.0, 1.0),
                )
            };
            let sample = EyeSample {
                position,
                normal,
                eye_distance: rng.range(-0.5, 60.0),
            };
            let empty = rng.unit() < 0.15 || near_border(position);
            texels.push((!empty).then_some(sample));
            edges.push(rng.unit() < 0.1);
        }
        Self {
            width,
            height,
            texels,
            edges,
        }
    }

    /// The CPU reference: samples and edge mask of the non-empty texels.
    fn cpu_inputs(&self) -> (Vec<EyeSample>, Vec<bool>) {
        self.texels
            .iter()
            .zip(&self.edges)
            .filter_map(|(t, &e)| t.map(|s| (s, e)))
            .unzip()
    }
}

/// Asserts `|gpu - cpu| <= tolerance` elementwise; returns the largest difference.
fn assert_close(what: &str, gpu: &[f32], cpu: &[f32], tolerance: f32) -> f32 {
    assert_eq!(gpu.len(), cpu.len(), "{what}: length");
    let (worst, at) = gpu
        .iter()
        .zip(cpu)
        .enumerate()
        .map(|(i, (g, c))| ((g - c).abs(), i))
        .fold((0.0f32, 0), |a, b| if b.0 > a.0 { b } else { a });
    assert!(
        worst <= tolerance,
        "{what}: |gpu - cpu| = {worst} at {at} (gpu {}, cpu {})",
        gpu[at],
        cpu[at]
    );
    worst
}

/// Runs `frames` through both pipelines with the same options and compares every
/// frame's tables, densities, importance map and counts.
fn compare(
    ctx: &GpuContext,
    map: (u32, u32),
    base: &ShadowTransform,
    frames: &[Frame],
    warp: &WarpOptions,
    importance: &ImportanceOptions,
) -> Result<(), BackendError> {
    let label = format!("{}x{} map, {warp:?}", map.0, map.1);
    let gpu = GpuRtw::new(ctx, map.0, map.1, warp, importance)?;
    let mut cpu_map = ImportanceMap::new(map.0, map.1).expect("map");
    let mut cpu_warps = WarpMaps::new(map.0, map.1).expect("warps");
    for (f, frame) in frames.iter().enumerate() {
        let gbuffer = RtwGBufferTextures::from_samples(
            ctx,
            frame.width,
            frame.height,
            &frame.texels,
            Some(&frame.edges),
        )?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        gpu.encode(ctx, &mut encoder, &gbuffer.as_gbuffer(), base)?;
        ctx.queue.submit([encoder.finish()]);

        let (samples, edges) = frame.cpu_inputs();
        cpu_map.clear();
        let stats = cpu_map
            .accumulate_backward(base, &samples, Some(&edges), importance)
            .expect("CPU accumulate");
        cpu_warps.build(&cpu_map, warp).expect("CPU build");

        let gpu_stats = gpu.read_stats(ctx)?;
        assert_eq!(
            (gpu_stats.accepted as usize, gpu_stats.skipped as usize),
            (stats.accepted, stats.skipped),
            "{label} frame {f}: counts"
        );
        assert_eq!(
            gpu_stats.identity_fallback,
            cpu_warps.identity_fallback(),
            "{label} frame {f}"
        );
        // The importance map: same cells, values to f32 rounding of the formula.
        let cells = gpu.read_importance(ctx)?;
        let cpu_cells = cpu_map.as_slice();
        assert_eq!(cells.len(), cpu_cells.len());
        for (i, (g, c)) in cells.iter().zip(cpu_cells).enumerate() {
            assert!(
                (g - c).abs() <= 1e-5 * c.abs().max(1e-30),
                "{label} frame {f}: cell {i}: gpu {g}, cpu {c}"
            );
        }
        let (du, dv) = gpu.read_densities(ctx)?;
        assert_close(
            &format!("{label} frame {f}: density u"),
            &du,
            cpu_warps.density_x(),
            1e-5,
        );
        assert_close(
            &format!("{label} frame {f}: density v"),
            &dv,
            cpu_warps.density_y(),
            1e-5,
        );
        let (tu, tv) = gpu.read_tables(ctx)?;
        let worst = assert_close(
            &format!("{label} frame {f}: u table"),
            &tu,
            cpu_warps.x_table(),
            TABLE_TOLERANCE,
        )
        .max(assert_close(
            &format!("{label} frame {f}: v table"),
            &tv,
            cpu_warps.y_table(),
            TABLE_TOLERANCE,
        ));
        eprintln!("{label} frame {f}: largest |gpu - cpu| table difference {worst:e}");
        assert_eq!((tu[0], tu[tu.len() - 1]), (0.0, 0.0));
        assert_eq!((tv[0], tv[tv.len() - 1]), (0.0, 0.0));
    }
    Ok(())
}

#[test]
fn gpu_tables_equal_cpu_tables_on_random_gbuffers() {
    let Some(ctx) = test_context("gpu_tables_equal_cpu_tables_on_random_gbuffers") else {
        return;
    };
    ctx.scoped(|ctx| {
        let mut rng = Rng(0x5eed_0f2a_7c00_u64);
        let importance = ImportanceOptions::default();
        // (map size, G-buffer size, warp options, perspective base)
        let cases: [(MapSize, MapSize, WarpOptions, bool); 6] = [
            ((64, 64), (48, 40), WarpOptions::default(), false),
            (
                (100, 37),
                (61, 29),
                WarpOptions::default().with_blur_radius(7),
                true,
            ),
            (
                (256, 128),
                (96, 80),
                WarpOptions::default().with_blur_radius(0).with_floor(0.05),
                false,
            ),
            (
                (3, 2),
                (16, 16),
                WarpOptions::default().with_blur_radius(1),
                true,
            ),
            (
                (1000, 5),
                (64, 32),
                WarpOptions::default().with_blur_radius(3).with_floor(1e-5),
                false,
            ),
            // One lane past the build's 256-wide workgroup and the collapse's 64, a
            // G-buffer one texel past a 16x16 splat workgroup each way, with the
            // options of the NVIDIA report.
            (
                (257, 65),
                (17, 17),
                WarpOptions::default().with_blur_radius(5).with_floor(0.001),
                true,
            ),
        ];
        for (map, gbuffer, warp, perspective) in cases {
            let base = if perspective {
                perspective_base()
            } else {
                orthographic_base()
            };
            let frame = Frame::random(&mut rng, gbuffer.0, gbuffer.1, &base, map);
            compare(ctx, map, &base, &[frame], &warp, &importance)?;
        }
        // Other importance knobs: squared distance term, strong orientation weight.
        let importance = ImportanceOptions::default()
            .with_distance_exponent(2.0)
            .with_orientation_weight(5.0)
            .with_reference_distance(3.0)
            .with_min_distance(0.5)
            .with_edge_weight(10.0);
        let base = perspective_base();
        let frame = Frame::random(&mut rng, 50, 50, &base, (77, 77));
        compare(
            ctx,
            (77, 77),
            &base,
            &[frame],
            &WarpOptions::default(),
            &importance,
        )?;
        // Importance up to f32::MAX (samples nearer than ~0.5 saturate on both sides).
        let importance = ImportanceOptions::default()
            .with_distance_exponent(2.0)
            .with_reference_distance(1e19);
        let frame = Frame::random(&mut rng, 40, 40, &base, (64, 48));
        compare(
            ctx,
            (64, 48),
            &base,
            &[frame],
            &WarpOptions::default().with_blur_radius(5),
            &importance,
        )
    })
    .expect("GPU RTW");
}

#[test]
fn gpu_temporal_smoothing_and_fallback_match_cpu() {
    let Some(ctx) = test_context("gpu_temporal_smoothing_and_fallback_match_cpu") else {
        return;
    };
    ctx.scoped(|ctx| {
        let mut rng = Rng(0x7e47_0a11_u64);
        let base = orthographic_base();
        let map = (90, 70);
        let warp = WarpOptions::default()
            .with_temporal(0.6)
            .with_blur_radius(4);
        let frames: Vec<Frame> = (0..3)
            .map(|_| Frame::random(&mut rng, 40, 30, &base, map))
            .collect();
        compare(
            ctx,
            map,
            &base,
            &frames,
            &warp,
            &ImportanceOptions::default(),
        )?;

        // No sample at all: identity tables on both axes.
        let empty = Frame {
            width: 8,
            height: 8,
            texels: vec![None; 64],
            edges: vec![false; 64],
        };
        compare(
            ctx,
            (32, 16),
            &base,
            &[empty],
            &WarpOptions::default(),
            &ImportanceOptions::default(),
        )?;
        Ok(())
    })
    .expect("GPU RTW temporal");
}

#[test]
fn gpu_rtw_rejects_bad_input() {
    let Some(ctx) = test_context("gpu_rtw_rejects_bad_input") else {
        return;
    };
    let opts = (WarpOptions::default(), ImportanceOptions::default());
    let bad = |r: Result<GpuRtw, BackendError>| matches!(r, Err(BackendError::InvalidInput(_)));
    assert!(bad(GpuRtw::new(&ctx, 0, 4, &opts.0, &opts.1)));
    assert!(bad(GpuRtw::new(&ctx, 4, 20_000, &opts.0, &opts.1)));
    assert!(bad(GpuRtw::new(
        &ctx,
        4,
        4,
        &opts.0.with_floor(0.0),
        &opts.1
    )));
    assert!(bad(GpuRtw::new(
        &ctx,
        4,
        4,
        &opts.0,
        &opts.1.with_edge_weight(0.5)
    )));
    let gpu = GpuRtw::new(&ctx, 4, 4, &opts.0, &opts.1).expect("valid");
    let gbuffer = RtwGBufferTextures::from_samples(&ctx, 1, 1, &[None], None).expect("gbuffer");
    let mut base = orthographic_base();
    base.uv_from_world = Mat4::from_cols_array(&[f32::NAN; 16]);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    assert!(matches!(
        gpu.encode(&ctx, &mut encoder, &gbuffer.as_gbuffer(), &base),
        Err(BackendError::InvalidInput(_))
    ));
    assert!(matches!(
        RtwGBufferTextures::from_samples(&ctx, 2, 2, &[None], None),
        Err(BackendError::InvalidInput(_))
    ));
}

/// The G-buffer pass against the ray-traced G-buffer of the same camera: the same
/// pixels hold a sample (all but silhouette pixels), at the same position and eye
/// distance (to 1e-3 of the distance) with the same face normal up to sign.
#[test]
fn the_gpu_gbuffer_is_the_ray_traced_one() {
    let Some(ctx) = test_context("the_gpu_gbuffer_is_the_ray_traced_one") else {
        return;
    };
    let scene = Scene::city_block(1);
    let camera = Camera::look_at(
        Vec3::new(10.0, 18.0, 120.0),
        Vec3::new(0.0, 4.0, 0.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 1.0, 500.0),
    )
    .unwrap();
    let (width, height) = (160, 90);
    let triangles: Vec<[Vec3; 3]> = scene.mesh.triangles_f32();
    let (positions, normals) = ctx
        .scoped(|ctx| {
            let mesh = MeshBuffers::from_triangles(ctx, &triangles)?;
            let mut pass = RtwGBufferPass::new(ctx, width, height, camera.reversed_z)?;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            pass.encode(ctx, &mut encoder, &mesh, &camera)?;
            ctx.queue.submit([encoder.finish()]);
            pass.read(ctx)
        })
        .expect("G-buffer pass");
    let traced = GBuffer::trace(&Bvh::build(&scene.mesh).unwrap(), &camera, width, height).unwrap();
    let eye = camera.eye().as_dvec3();
    let (mut both, mut flags_differ, mut far, mut turned) = (0, 0, 0, 0);
    for ((p, n), surface) in positions.iter().zip(&normals).zip(&traced.surfaces) {
        match (n.w >= 0.5, surface) {
            (true, Some(s)) => {
                both += 1;
                let distance = s.position.distance(eye);
                let gpu = p.truncate().as_dvec3();
                if gpu.distance(s.position) > 1e-3 * distance
                    || (f64::from(p.w) - distance).abs() > 1e-3 * distance
                {
                    far += 1;
                }
                if n.truncate().as_dvec3().dot(s.normal).abs() < 0.99 {
                    turned += 1;
                }
            }
            (false, None) => {}
            _ => flags_differ += 1,
        }
    }
    let pixels = (width * height) as usize;
    eprintln!(
        "G-buffer: {both} samples both ways, {flags_differ} pixels with a sample one way only, \
         {far} positions and {turned} normals apart"
    );
    assert!(both > pixels / 2, "{both} samples");
    assert!(flags_differ as f64 <= 5e-3 * pixels as f64);
    assert!(far as f64 <= 2e-2 * both as f64);
    assert!(turned as f64 <= 2e-2 * both as f64);
}
