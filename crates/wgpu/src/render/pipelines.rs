//! The renderer's pipelines: the scene pass (a lookup and a filter composed into
//! `render_scene.wgsl`) and the VSM moments and blur passes.

use std::num::NonZeroU64;

use super::ShadowFilter;
use super::image::{COLOR_FORMAT, MASK_FORMAT};
use super::technique::Lookup;
use crate::compose::compose_scene_shader;
use crate::context::mesh_pipeline;
use crate::depth::{DepthBias, depth_state};
use crate::uniforms::FrameRaw;
use crate::{BackendError, shaders};

pub(super) const MOMENTS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The scene pipeline of one (lookup, filter, camera depth direction).
#[derive(Debug)]
pub(super) struct ScenePipeline {
    pub(super) pipeline: wgpu::RenderPipeline,
    pub(super) frame_layout: wgpu::BindGroupLayout,
    pub(super) lookup_layout: wgpu::BindGroupLayout,
    pub(super) maps_layout: wgpu::BindGroupLayout,
}

/// The VSM moments and blur pipelines.
#[derive(Debug)]
pub(super) struct VsmPipelines {
    pub(super) moments: wgpu::RenderPipeline,
    pub(super) blur: wgpu::RenderPipeline,
    pub(super) layout: wgpu::BindGroupLayout,
}

pub(super) fn moments_texture(
    device: &wgpu::Device,
    resolution: u32,
    layers: u32,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shadowmap moments"),
        size: wgpu::Extent3d {
            width: resolution,
            height: resolution,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: MOMENTS_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

pub(super) fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2Array,
            multisampled: false,
        },
        count: None,
    }
}

pub(super) fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    size: usize,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: NonZeroU64::new(size as u64),
        },
        count: None,
    }
}

pub(super) fn create_vsm_pipelines(device: &wgpu::Device) -> VsmPipelines {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap vsm"),
        entries: &[
            texture_entry(0, wgpu::TextureSampleType::Depth),
            texture_entry(1, wgpu::TextureSampleType::Float { filterable: false }),
            uniform_entry(2, wgpu::ShaderStages::FRAGMENT, 32),
        ],
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadowmap vsm"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap vsm"),
        source: wgpu::ShaderSource::Wgsl(shaders::FILTER_VSM_MOMENTS.into()),
    });
    let make = |entry: &str| {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("shadowmap vsm"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                targets: &[Some(MOMENTS_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        })
    };
    VsmPipelines {
        moments: make("fs_moments"),
        blur: make("fs_blur"),
        layout,
    }
}

/// The scene pass's bind group layouts: frame, lookup (with the warp tables of RTW
/// and the paraboloid), maps.
fn scene_layouts(device: &wgpu::Device, lookup: Lookup) -> [wgpu::BindGroupLayout; 3] {
    let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap frame"),
        entries: &[uniform_entry(
            0,
            wgpu::ShaderStages::VERTEX_FRAGMENT,
            size_of::<FrameRaw>(),
        )],
    });
    // The block size depends on the technique: no minimum.
    let mut lookup_entries = vec![uniform_entry(0, wgpu::ShaderStages::FRAGMENT, 0)];
    if matches!(lookup, Lookup::Rtw | Lookup::Paraboloid | Lookup::Tiles) {
        lookup_entries.push(wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: NonZeroU64::new(4),
            },
            count: None,
        });
    }
    let lookup_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap lookup"),
        entries: &lookup_entries,
    });
    let maps_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap maps"),
        entries: &[
            texture_entry(0, wgpu::TextureSampleType::Depth),
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                count: None,
            },
            texture_entry(2, wgpu::TextureSampleType::Float { filterable: false }),
        ],
    });
    [frame_layout, lookup_layout, maps_layout]
}

/// The scene pipeline of one (lookup, filter, camera depth direction).
pub(super) fn create_scene_pipeline(
    device: &wgpu::Device,
    lookup: Lookup,
    filter: ShadowFilter,
    camera_reversed_z: bool,
) -> Result<ScenePipeline, BackendError> {
    let source = compose_scene_shader(&lookup.source()?, filter.source())?;
    let [frame_layout, lookup_layout, maps_layout] = scene_layouts(device, lookup);
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadowmap scene"),
        bind_group_layouts: &[
            Some(&frame_layout),
            Some(&lookup_layout),
            Some(&maps_layout),
        ],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap scene"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let targets = [Some(COLOR_FORMAT.into()), Some(MASK_FORMAT.into())];
    let pipeline = mesh_pipeline(
        device,
        ("shadowmap scene", Some(&pipeline_layout), &module),
        depth_state(camera_reversed_z, DepthBias::default()),
        Some(&targets),
    );
    Ok(ScenePipeline {
        pipeline,
        frame_layout,
        lookup_layout,
        maps_layout,
    })
}
