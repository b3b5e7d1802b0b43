//! Silhouette edges on the GPU: one compute invocation per edge of a closed mesh
//! (`volume_silhouette.wgsl`), the same test as the CPU reference
//! (`shadowmap_volume::ShadowVolume::update`), in `f32`.

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};
use shadowmap_frustum::Light;
use shadowmap_volume::EdgeMesh;
use wgpu::util::DeviceExt;

use crate::{BackendError, GpuContext, shaders};

const WORKGROUP: u32 = 64;

/// `Light` of `volume_silhouette.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct LightRaw {
    source: [f32; 4],
    counts: [u32; 4],
}

/// A closed mesh uploaded once, and the pipeline that finds its silhouette.
#[derive(Debug)]
pub struct GpuSilhouette {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    positions: wgpu::Buffer,
    triangles: wgpu::Buffer,
    edges: wgpu::Buffer,
    edge_count: u32,
}

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl GpuSilhouette {
    /// Uploads the mesh's welded positions, triangles and edges.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for more edges than one dispatch covers;
    /// [`BackendError::Wgpu`] for GPU errors.
    pub fn new(ctx: &GpuContext, mesh: &EdgeMesh) -> Result<Self, BackendError> {
        let limit = ctx.device.limits().max_compute_workgroups_per_dimension;
        let edge_count = u32::try_from(mesh.edges.len())
            .ok()
            .filter(|&n| n.div_ceil(WORKGROUP) <= limit)
            .ok_or(BackendError::InvalidInput(
                "too many edges for one dispatch",
            ))?;
        ctx.scoped(|ctx| {
            let device = &ctx.device;
            let upload = |label, contents: &[u8]| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    // One element at least: empty storage bindings are invalid.
                    contents: if contents.is_empty() {
                        &[0; 16]
                    } else {
                        contents
                    },
                    usage: wgpu::BufferUsages::STORAGE,
                })
            };
            let positions: Vec<[f32; 4]> = mesh
                .positions
                .iter()
                .map(|p| p.as_vec3().extend(1.0).to_array())
                .collect();
            let triangles: Vec<[u32; 4]> = mesh
                .triangles
                .iter()
                .map(|t| [t[0], t[1], t[2], 0])
                .collect();
            let edges: Vec<[u32; 4]> = mesh
                .edges
                .iter()
                .map(|e| [e.vertices[0], e.vertices[1], e.triangles[0], e.triangles[1]])
                .collect();
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("shadowmap volume_silhouette"),
                source: wgpu::ShaderSource::Wgsl(shaders::VOLUME_SILHOUETTE.into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("shadowmap silhouette"),
                entries: &[
                    wgpu::BindGroupLayoutEntry {
                        binding: 0,
                        visibility: wgpu::ShaderStages::COMPUTE,
                        ty: wgpu::BindingType::Buffer {
                            ty: wgpu::BufferBindingType::Uniform,
                            has_dynamic_offset: false,
                            min_binding_size: NonZeroU64::new(size_of::<LightRaw>() as u64),
                        },
                        count: None,
                    },
                    storage(1, true),
                    storage(2, true),
                    storage(3, true),
                    storage(4, false),
                    storage(5, false),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("shadowmap silhouette"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("shadowmap silhouette"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("find_silhouette"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            });
            Ok(Self {
                pipeline,
                layout,
                positions: upload(
                    "shadowmap silhouette positions",
                    bytemuck::cast_slice(&positions),
                ),
                triangles: upload(
                    "shadowmap silhouette triangles",
                    bytemuck::cast_slice(&triangles),
                ),
                edges: upload("shadowmap silhouette edges", bytemuck::cast_slice(&edges)),
                edge_count,
            })
        })
    }

    /// The silhouette edges for `light` (welded vertex indices, oriented as the
    /// light-facing triangle runs along them), in no particular order. Spot lights
    /// count as point lights. Waits for the GPU.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a light that fails validation;
    /// [`BackendError::Wgpu`] and [`BackendError::Readback`] for GPU errors.
    pub fn find(&self, ctx: &GpuContext, light: &Light) -> Result<Vec<[u32; 2]>, BackendError> {
        light
            .validate()
            .map_err(|_| BackendError::InvalidInput("the light fails validation"))?;
        let source = match *light {
            Light::Directional { direction } => direction.normalize().extend(0.0),
            Light::Spot { position, .. } | Light::Point { position, .. } => position.extend(1.0),
        };
        let raw = LightRaw {
            source: source.to_array(),
            counts: [self.edge_count, 0, 0, 0],
        };
        ctx.scoped(|ctx| {
            let device = &ctx.device;
            let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadowmap silhouette light"),
                contents: bytemuck::bytes_of(&raw),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let out_usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
            let found = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadowmap silhouette count"),
                contents: &[0; 4],
                usage: out_usage,
            });
            let silhouette = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadowmap silhouette edges found"),
                size: 8 * u64::from(self.edge_count.max(1)),
                usage: out_usage,
                mapped_at_creation: false,
            });
            let buffers = [
                &uniform,
                &self.positions,
                &self.triangles,
                &self.edges,
                &found,
                &silhouette,
            ];
            let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadowmap silhouette"),
                layout: &self.layout,
                entries: &entries,
            });
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(self.edge_count.div_ceil(WORKGROUP), 1, 1);
            }
            ctx.queue.submit([encoder.finish()]);
            let count: u32 = bytemuck::pod_read_unaligned(&ctx.read_buffer(&found)?);
            let edges: Vec<[u32; 2]> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&silhouette)?);
            Ok(edges[..(count as usize).min(edges.len())].to_vec())
        })
    }
}
