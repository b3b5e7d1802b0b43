//! The three pipelines of a shadow-volume frame and their attachments.

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};

use super::VolumeMethod;
use crate::shaders;

/// Depth and stencil of the camera: reversed-Z depth, 8-bit stencil count.
pub(super) const DEPTH_STENCIL_FORMAT: wgpu::TextureFormat =
    wgpu::TextureFormat::Depth24PlusStencil8;
/// The classification: 0 background, 1 lit, 2 shadowed.
pub(super) const CLASS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Uint;

/// `Frame` of `volume_stencil.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub(super) struct VolumeFrameRaw {
    pub(super) clip_from_world: [[f32; 4]; 4],
    /// Eye (xyz) and the largest view depth that counts (w).
    pub(super) eye: [f32; 4],
    /// Unit view direction (xyz).
    pub(super) forward: [f32; 4],
}

/// The pipelines, created once per device.
#[derive(Debug)]
pub(super) struct VolumePipelines {
    pub(super) layout: wgpu::BindGroupLayout,
    pub(super) surface: wgpu::RenderPipeline,
    pub(super) z_pass: wgpu::RenderPipeline,
    pub(super) z_fail: wgpu::RenderPipeline,
    pub(super) classify: wgpu::RenderPipeline,
}

const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
    array_stride: 16,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &[wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x4,
        offset: 0,
        shader_location: 0,
    }],
};

fn face(
    compare: wgpu::CompareFunction,
    pass_op: wgpu::StencilOperation,
    depth_fail_op: wgpu::StencilOperation,
) -> wgpu::StencilFaceState {
    wgpu::StencilFaceState {
        compare,
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op,
        pass_op,
    }
}

/// The two-sided stencil state of a volume pass: front faces (entering the
/// volume) and back faces count with opposite signs, on depth pass (z-pass) or
/// depth fail (z-fail, with the signs swapped: behind the surface, leaving counts).
fn volume_stencil(method: VolumeMethod) -> wgpu::StencilState {
    use wgpu::StencilOperation::{DecrementWrap as Dec, IncrementWrap as Inc, Keep};
    let always = wgpu::CompareFunction::Always;
    let (front, back) = match method {
        VolumeMethod::ZPass => (face(always, Inc, Keep), face(always, Dec, Keep)),
        VolumeMethod::ZFail => (face(always, Keep, Dec), face(always, Keep, Inc)),
    };
    wgpu::StencilState {
        front,
        back,
        read_mask: 0xff,
        write_mask: 0xff,
    }
}

fn depth_stencil(
    write: bool,
    compare: wgpu::CompareFunction,
    stencil: wgpu::StencilState,
) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_STENCIL_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil,
        bias: wgpu::DepthBiasState::default(),
    }
}

struct Stage<'a> {
    vertex: &'a str,
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    fragment: Option<&'a str>,
    depth_stencil: wgpu::DepthStencilState,
}

impl VolumePipelines {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadowmap volume_stencil"),
            source: wgpu::ShaderSource::Wgsl(shaders::VOLUME_STENCIL.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadowmap volume frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: NonZeroU64::new(size_of::<VolumeFrameRaw>() as u64),
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shadowmap volume"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let create = |label: &str, stage: Stage<'_>| {
            let targets = [Some(wgpu::ColorTargetState::from(CLASS_FORMAT))];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(stage.vertex),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers: stage.buffers,
                },
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..wgpu::PrimitiveState::default()
                },
                depth_stencil: Some(stage.depth_stencil),
                multisample: wgpu::MultisampleState::default(),
                fragment: stage.fragment.map(|entry| wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let greater = wgpu::CompareFunction::Greater;
        let volume = |label, method| {
            create(
                label,
                Stage {
                    vertex: "vs_volume",
                    buffers: &[Some(VERTEX_LAYOUT)],
                    fragment: None,
                    depth_stencil: depth_stencil(false, greater, volume_stencil(method)),
                },
            )
        };
        let not_zero = face(
            wgpu::CompareFunction::NotEqual,
            wgpu::StencilOperation::Keep,
            wgpu::StencilOperation::Keep,
        );
        Self {
            surface: create(
                "shadowmap volume surfaces",
                Stage {
                    vertex: "vs_surface",
                    buffers: &[Some(VERTEX_LAYOUT)],
                    fragment: Some("fs_surface"),
                    depth_stencil: depth_stencil(true, greater, wgpu::StencilState::default()),
                },
            ),
            z_pass: volume("shadowmap volume z-pass", VolumeMethod::ZPass),
            z_fail: volume("shadowmap volume z-fail", VolumeMethod::ZFail),
            classify: create(
                "shadowmap volume classify",
                Stage {
                    vertex: "vs_fullscreen",
                    buffers: &[],
                    fragment: Some("fs_shadowed"),
                    depth_stencil: depth_stencil(
                        false,
                        wgpu::CompareFunction::Less,
                        wgpu::StencilState {
                            front: not_zero,
                            back: not_zero,
                            read_mask: 0xff,
                            write_mask: 0,
                        },
                    ),
                },
            ),
            layout,
        }
    }
}
