//! Projective shadows on the GPU (Blinn, *Me and my (fake) shadow*, 1988): the
//! occluders drawn from the light into a mask, projected onto separate receivers
//! with homogeneous texture coordinates; the matrices and the CPU reference are
//! `shadowmap_volume::ProjectiveShadow` and `shadowmap_volume::OccluderMask`.
//!
//! Limits of the algorithm: occluders and receivers are separate sets, so nothing
//! shadows itself and occluders are drawn fully lit; the mask has no depth, so a
//! receiver between the light and an occluder is darkened too; receivers behind a
//! point or spot light (`q <= 0`) stay lit.

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use shadowmap_frustum::Camera;
use shadowmap_volume::{MAX_MASK_SIDE, ProjectiveShadow};
use wgpu::util::DeviceExt;

use super::pipelines::{CLASS_FORMAT, VolumeFrameRaw};
use super::{clear, decode};
use crate::depth::{DEPTH_FORMAT, MeshBuffers};
use crate::render::ShadowMask;
use crate::{BackendError, GpuContext, shaders};

/// `Projective` of `projective_shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct ProjectiveRaw {
    clip_from_world: [[f32; 4]; 4],
    uv_from_world: [[f32; 4]; 4],
}

#[derive(Debug)]
struct Pipelines {
    uniforms: wgpu::BindGroupLayout,
    mask: wgpu::BindGroupLayout,
    occluder_mask: wgpu::RenderPipeline,
    occluders: [wgpu::RenderPipeline; 2],
    receivers: [wgpu::RenderPipeline; 2],
}

fn uniform_entry(binding: u32, size: usize) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: NonZeroU64::new(size as u64),
        },
        count: None,
    }
}

impl Pipelines {
    fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadowmap projective_shadow"),
            source: wgpu::ShaderSource::Wgsl(shaders::PROJECTIVE_SHADOW.into()),
        });
        let uniforms = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadowmap projective uniforms"),
            entries: &[
                uniform_entry(0, size_of::<VolumeFrameRaw>()),
                uniform_entry(1, size_of::<ProjectiveRaw>()),
            ],
        });
        let mask = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadowmap projective mask"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Uint,
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let light_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadowmap projective light"),
            bind_group_layouts: &[Some(&uniforms)],
            immediate_size: 0,
        });
        let camera_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadowmap projective camera"),
            bind_group_layouts: &[Some(&uniforms), Some(&mask)],
            immediate_size: 0,
        });
        let create = |layout, vertex, fragment, depth: Option<bool>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vertex),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers: &[Some(MeshBuffers::layout())],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: depth.map(|reversed| wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(if reversed {
                        wgpu::CompareFunction::Greater
                    } else {
                        wgpu::CompareFunction::Less
                    }),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState::from(CLASS_FORMAT))],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let camera = |fragment| {
            [false, true]
                .map(|reversed| create(&camera_layout, "vs_camera", fragment, Some(reversed)))
        };
        Self {
            occluder_mask: create(&light_layout, "vs_occluder_mask", "fs_occluder_mask", None),
            occluders: camera("fs_occluder"),
            receivers: camera("fs_receiver"),
            uniforms,
            mask,
        }
    }
}

/// Renders projective shadows headlessly; caches its pipelines across frames.
#[derive(Debug, Default)]
pub struct ProjectiveRenderer {
    pipelines: Option<Pipelines>,
}

fn texture(
    ctx: &GpuContext,
    (w, h): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    crate::context::texture_2d(
        &ctx.device,
        "shadowmap projective target",
        (w, h),
        format,
        usage,
    )
}

impl ProjectiveRenderer {
    /// A renderer with no pipelines yet.
    #[must_use]
    pub const fn new() -> Self {
        Self { pipelines: None }
    }

    /// Draws the `occluders` into a `mask_side²` mask from the light of `shadow`,
    /// then the camera's view at `width x height`: receivers lit or shadowed by the
    /// mask, occluders lit, background where nothing (within the camera's depth
    /// range) is seen.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a size or mask side of zero or past the
    /// device's limit or an invalid camera; [`BackendError::Wgpu`] for GPU errors.
    pub fn render_mask(
        &mut self,
        ctx: &GpuContext,
        (receivers, occluders): (&[[Vec3; 3]], &[[Vec3; 3]]),
        camera: &Camera,
        shadow: &ProjectiveShadow,
        mask_side: u32,
        (width, height): (u32, u32),
    ) -> Result<ShadowMask, BackendError> {
        let max = ctx
            .device
            .limits()
            .max_texture_dimension_2d
            .min(MAX_MASK_SIDE);
        if [width, height, mask_side]
            .iter()
            .any(|&s| s == 0 || s > max)
        {
            return Err(BackendError::InvalidInput(
                "size or mask side is zero or too large",
            ));
        }
        let invalid = |_| BackendError::InvalidInput("the camera fails validation");
        let clip_from_world = camera.clip_from_world().map_err(invalid)?;
        let (_, far) = camera.depth_range().map_err(invalid)?;
        let frame = VolumeFrameRaw {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            eye: camera.eye().extend(far).to_array(),
            forward: camera.forward().extend(0.0).to_array(),
        };
        let raw = ProjectiveRaw {
            clip_from_world: shadow.clip_from_world.to_cols_array_2d(),
            uv_from_world: shadow.uv_from_world.to_cols_array_2d(),
        };
        ctx.scoped(|ctx| {
            let pipelines = self
                .pipelines
                .get_or_insert_with(|| Pipelines::new(&ctx.device));
            let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
            let mask = texture(
                ctx,
                (mask_side, mask_side),
                CLASS_FORMAT,
                attach | wgpu::TextureUsages::TEXTURE_BINDING,
            );
            let class = texture(
                ctx,
                (width, height),
                CLASS_FORMAT,
                attach | wgpu::TextureUsages::COPY_SRC,
            );
            let depth = texture(ctx, (width, height), DEPTH_FORMAT, attach);
            let buffer = |label, contents: &[u8]| {
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents,
                        usage: wgpu::BufferUsages::UNIFORM,
                    })
            };
            let (frame_buf, raw_buf) = (
                buffer("shadowmap projective frame", bytemuck::bytes_of(&frame)),
                buffer("shadowmap projective", bytemuck::bytes_of(&raw)),
            );
            let uniforms = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadowmap projective uniforms"),
                layout: &pipelines.uniforms,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: frame_buf.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: raw_buf.as_entire_binding(),
                    },
                ],
            });
            let mask_view = mask.create_view(&Default::default());
            let mask_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadowmap projective mask"),
                layout: &pipelines.mask,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&mask_view),
                }],
            });
            let meshes = [occluders, receivers].map(|tris| {
                (!tris.is_empty())
                    .then(|| MeshBuffers::from_triangles(ctx, tris))
                    .transpose()
            });
            let [occluder_mesh, receiver_mesh] = meshes;
            let (occluder_mesh, receiver_mesh) = (occluder_mesh?, receiver_mesh?);
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            mask_pass(
                &mut encoder,
                &mask_view,
                pipelines,
                &uniforms,
                occluder_mesh.as_ref(),
            );
            let class_view = class.create_view(&Default::default());
            let depth_view = depth.create_view(&Default::default());
            let meshes = [occluder_mesh.as_ref(), receiver_mesh.as_ref()];
            camera_pass(
                &mut encoder,
                (&class_view, &depth_view, camera.reversed_z),
                pipelines,
                [&uniforms, &mask_group],
                meshes,
            );
            ctx.queue.submit([encoder.finish()]);
            let classes = ctx.read_texture(&class, wgpu::TextureAspect::All)?;
            Ok(decode(width, height, &classes))
        })
    }
}

fn draw(pass: &mut wgpu::RenderPass<'_>, mesh: &MeshBuffers) {
    pass.set_vertex_buffer(0, mesh.vertices.slice(..));
    pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
    pass.draw_indexed(0..mesh.index_count, 0, 0..1);
}

/// Draws the occluders from the light into the mask.
fn mask_pass(
    encoder: &mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    pipelines: &Pipelines,
    uniforms: &wgpu::BindGroup,
    occluders: Option<&MeshBuffers>,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadowmap projective occluder mask"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: clear(wgpu::Color::TRANSPARENT),
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    if let Some(mesh) = occluders {
        pass.set_pipeline(&pipelines.occluder_mask);
        pass.set_bind_group(0, uniforms, &[]);
        draw(&mut pass, mesh);
    }
}

/// Draws the camera's view: occluders lit, receivers through the mask.
fn camera_pass(
    encoder: &mut wgpu::CommandEncoder,
    (class_view, depth_view, reversed_z): (&wgpu::TextureView, &wgpu::TextureView, bool),
    pipelines: &Pipelines,
    [uniforms, mask]: [&wgpu::BindGroup; 2],
    [occluders, receivers]: [Option<&MeshBuffers>; 2],
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadowmap projective camera"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: class_view,
            depth_slice: None,
            resolve_target: None,
            ops: clear(wgpu::Color::TRANSPARENT),
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth_view,
            depth_ops: Some(clear(if reversed_z { 0.0 } else { 1.0 })),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let reversed = usize::from(reversed_z);
    pass.set_bind_group(0, uniforms, &[]);
    pass.set_bind_group(1, mask, &[]);
    for (mesh, pipeline) in [
        (occluders, &pipelines.occluders[reversed]),
        (receivers, &pipelines.receivers[reversed]),
    ] {
        if let Some(mesh) = mesh {
            pass.set_pipeline(pipeline);
            draw(&mut pass, mesh);
        }
    }
}
