//! The GPU min/max depth reduction equals the CPU min/max of the same depth buffer,
//! bit for bit, with and without reversed-Z, and reports an all-background buffer as
//! `None`.
//!
//! Depth textures cannot be written by `queue.write_texture`, so each test uploads its
//! depths to an `R32Float` texture, copies them into a `Depth32Float` texture with a
//! fullscreen pass writing `frag_depth`, reads the depth texture back, and compares the
//! GPU reduction with [`RawDepthRange::from_depths`] of that readback.

use shadowmap_wgpu::reduce::{DepthReduction, RawDepthRange};
use shadowmap_wgpu::{BackendError, GpuContext, context::test_context};

const COPY_DEPTH_WGSL: &str = r"
@group(0) @binding(0) var depths: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
    return vec4<f32>(xy, 0.5, 1.0);
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @builtin(frag_depth) f32 {
    return textureLoad(depths, vec2<u32>(p.xy), 0).x;
}
";

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40;
        bits as f32 / (1u64 << 24) as f32
    }
}

/// A `Depth32Float` texture holding `depths` (row-major), written by a fullscreen pass.
fn depth_texture(ctx: &GpuContext, width: u32, height: u32, depths: &[f32]) -> wgpu::Texture {
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    let source = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("depth source"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        source.as_image_copy(),
        bytemuck::cast_slice(depths),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(width * 4),
            rows_per_image: Some(height),
        },
        size,
    );
    let depth = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("depth"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("copy depth"),
            source: wgpu::ShaderSource::Wgsl(COPY_DEPTH_WGSL.into()),
        });
    let pipeline = ctx
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("copy depth"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
    let source_view = source.create_view(&Default::default());
    let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("copy depth"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(&source_view),
        }],
    });
    let depth_view = depth.create_view(&Default::default());
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("copy depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
    ctx.queue.submit([encoder.finish()]);
    depth
}

/// Reduces `depths` on the GPU; returns (GPU range, CPU range of the readback).
fn reduce(
    ctx: &GpuContext,
    reduction: &mut DepthReduction,
    width: u32,
    height: u32,
    depths: &[f32],
) -> Result<(Option<RawDepthRange>, Option<RawDepthRange>), BackendError> {
    let texture = depth_texture(ctx, width, height, depths);
    let stored = ctx.read_depth_texture(&texture)?;
    assert_eq!(stored.len(), depths.len());
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    reduction.encode(ctx, &mut encoder, &texture)?;
    ctx.queue.submit([encoder.finish()]);
    let gpu = reduction.read(ctx)?;
    let cpu = RawDepthRange::from_depths(&stored, reduction.reversed_z());
    Ok((gpu, cpu))
}

/// Random depths in `[0, 1)` with a fraction of background texels.
fn random_depths(rng: &mut Rng, len: usize, background: f32, fraction: f32) -> Vec<f32> {
    (0..len)
        .map(|_| {
            if rng.next_f32() < fraction {
                background
            } else {
                rng.next_f32()
            }
        })
        .collect()
}

#[test]
fn gpu_reduction_equals_cpu_min_max() {
    let Some(ctx) = test_context("gpu_reduction_equals_cpu_min_max") else {
        return;
    };
    ctx.scoped(|ctx| {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let mut reduction = DepthReduction::new(ctx, false);
        // 640x480 has 300 tiles, more than the final pass's 256 invocations; the odd
        // sizes leave partial tiles; the last one grows the partials buffer.
        for (width, height) in [(37, 5), (640, 480), (1, 1), (1000, 333)] {
            let len = (width * height) as usize;
            let mut depths = random_depths(&mut rng, len, 1.0, 0.3);
            // Keep the extremes away from the first texel so tiles matter.
            depths[len / 2] = 0.0;
            let (gpu, cpu) = reduce(ctx, &mut reduction, width, height, &depths)?;
            assert!(cpu.is_some());
            assert_eq!(gpu, cpu, "{width}x{height}");
            if width * height > 1 {
                assert_eq!(gpu.map(|r| r.min), Some(0.0));
            }
        }
        // The result must move with the content: a narrow band in one corner.
        let (width, height) = (200, 100);
        let mut depths = vec![1.0; (width * height) as usize];
        depths[(height as usize - 1) * width as usize + 199] = 0.625;
        depths[5 * width as usize + 150] = 0.375;
        let (gpu, cpu) = reduce(ctx, &mut reduction, width, height, &depths)?;
        assert_eq!(
            gpu,
            Some(RawDepthRange {
                min: 0.375,
                max: 0.625
            })
        );
        assert_eq!(gpu, cpu);
        Ok(())
    })
    .expect("GPU reduction");
}

#[test]
fn gpu_reduction_handles_reversed_z_and_empty_buffers() {
    let Some(ctx) = test_context("gpu_reduction_handles_reversed_z_and_empty_buffers") else {
        return;
    };
    ctx.scoped(|ctx| {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let mut reversed = DepthReduction::new(ctx, true);
        let (width, height) = (333, 97);
        let len = (width * height) as usize;
        let mut depths = random_depths(&mut rng, len, 0.0, 0.4);
        depths[len - 1] = 1.0; // the nearest possible depth with reversed-Z is visible
        let (gpu, cpu) = reduce(ctx, &mut reversed, width, height, &depths)?;
        assert_eq!(gpu, cpu);
        assert_eq!(gpu.map(|r| r.max), Some(1.0));
        assert!(gpu.is_some_and(|r| r.min > 0.0));

        // All background: nothing visible, with either convention.
        let (gpu, cpu) = reduce(ctx, &mut reversed, width, height, &vec![0.0; len])?;
        assert_eq!((gpu, cpu), (None, None));
        let mut forward = DepthReduction::new(ctx, false);
        let (gpu, cpu) = reduce(ctx, &mut forward, width, height, &vec![1.0; len])?;
        assert_eq!((gpu, cpu), (None, None));
        // The same buffer of zeros is all visible without reversed-Z.
        let (gpu, _) = reduce(ctx, &mut forward, width, height, &vec![0.0; len])?;
        assert_eq!(gpu, Some(RawDepthRange { min: 0.0, max: 0.0 }));
        Ok(())
    })
    .expect("GPU reduction");
}

#[test]
fn gpu_reduction_rejects_textures_it_cannot_read() {
    let Some(ctx) = test_context("gpu_reduction_rejects_textures_it_cannot_read") else {
        return;
    };
    let color = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("not depth"),
        size: wgpu::Extent3d {
            width: 4,
            height: 4,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let mut reduction = DepthReduction::new(&ctx, false);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    assert!(matches!(
        reduction.encode(&ctx, &mut encoder, &color),
        Err(BackendError::InvalidInput(_))
    ));
}

#[test]
fn gpu_reduction_gives_the_view_depth_bounds_of_a_camera() {
    use glam::{Vec3, Vec4};
    use shadowmap_frustum::{Camera, CascadeSplits, Projection, SplitScheme};
    let Some(ctx) = test_context("gpu_reduction_gives_the_view_depth_bounds_of_a_camera") else {
        return;
    };
    ctx.scoped(|ctx| {
        let mut rng = Rng(0x0dd5_eed5_0000_0001);
        for reversed_z in [false, true] {
            let camera = Camera::look_to(
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::new(0.2, -0.3, -1.0),
                Vec3::Y,
                Projection::perspective(1.0, 1.6, 0.5, 200.0),
            )
            .expect("camera")
            .with_reversed_z(reversed_z);
            let clip_from_view = camera.clip_from_view().expect("projection");
            let background = if reversed_z { 0.0 } else { 1.0 };
            let (width, height) = (160, 90);
            // View depths in [3, 40] (the sky elsewhere), stored as the raw depth the
            // camera's projection gives them.
            let depths: Vec<f32> = (0..width * height)
                .map(|i| {
                    if i % 7 == 0 {
                        return background;
                    }
                    let z = match i {
                        100 => 3.0,
                        5000 => 40.0,
                        _ => rng.next_f32().mul_add(37.0, 3.0).clamp(3.0, 40.0),
                    };
                    let c = clip_from_view * Vec4::new(0.0, 0.0, -z, 1.0);
                    c.z / c.w
                })
                .collect();
            let mut reduction = DepthReduction::new(ctx, reversed_z);
            let (gpu, cpu) = reduce(ctx, &mut reduction, width, height, &depths)?;
            assert_eq!(gpu, cpu);
            let bounds = gpu
                .expect("visible samples")
                .view_depth_bounds(&camera)
                .expect("bounds");
            assert!(
                (bounds.min - 3.0).abs() < 3.0 * 1e-4,
                "{reversed_z}: {bounds:?}"
            );
            assert!(
                (bounds.max - 40.0).abs() < 40.0 * 1e-3,
                "{reversed_z}: {bounds:?}"
            );
            // SDSM: cascades split the measured range, not [near, far].
            let splits =
                CascadeSplits::from_depth_bounds(&SplitScheme::Logarithmic, 4, &camera, bounds)
                    .expect("splits");
            let d = splits.depths();
            assert!((d[0] - bounds.min).abs() < 1e-4 && (d[d.len() - 1] - bounds.max).abs() < 1e-3);
        }
        Ok(())
    })
    .expect("GPU depth bounds");
}
