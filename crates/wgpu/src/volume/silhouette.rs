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

/// A closed mesh uploaded once, the pipeline that finds its silhouette, and the
/// light uniform and output buffers that every [`GpuSilhouette::find`] rewrites in
/// place (a call allocates nothing on the GPU).
#[derive(Debug)]
pub struct GpuSilhouette {
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    light: wgpu::Buffer,
    found: wgpu::Buffer,
    silhouette: wgpu::Buffer,
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

/// The bind group layout and the pipeline of `find_silhouette`.
fn pipeline(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::ComputePipeline) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap volume_silhouette"),
        source: wgpu::ShaderSource::Wgsl(shaders::VOLUME_SILHOUETTE.into()),
    });
    let light = wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: NonZeroU64::new(size_of::<LightRaw>() as u64),
        },
        count: None,
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap silhouette"),
        entries: &[
            light,
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
    (layout, pipeline)
}

/// The mesh as the shader reads it, each element padded to 16 bytes.
struct MeshArrays {
    positions: Vec<[f32; 4]>,
    triangles: Vec<[u32; 4]>,
    edges: Vec<[u32; 4]>,
}

fn mesh_arrays(mesh: &EdgeMesh) -> MeshArrays {
    let positions = mesh
        .positions
        .iter()
        .map(|p| p.as_vec3().extend(1.0).to_array())
        .collect();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| [t[0], t[1], t[2], 0])
        .collect();
    let edges = mesh
        .edges
        .iter()
        .map(|e| [e.vertices[0], e.vertices[1], e.triangles[0], e.triangles[1]])
        .collect();
    MeshArrays {
        positions,
        triangles,
        edges,
    }
}

impl GpuSilhouette {
    /// Uploads the mesh's welded positions, triangles and edges, and makes the
    /// buffers that [`find`](Self::find) reuses.
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
            let buffer = |label, contents: &[u8], usage| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    // One element at least: empty storage bindings are invalid.
                    contents: if contents.is_empty() {
                        &[0; 16]
                    } else {
                        contents
                    },
                    usage,
                })
            };
            let read = wgpu::BufferUsages::STORAGE;
            let written = read | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
            let MeshArrays {
                positions,
                triangles,
                edges,
            } = mesh_arrays(mesh);
            let inputs = [
                buffer(
                    "shadowmap silhouette positions",
                    bytemuck::cast_slice(&positions),
                    read,
                ),
                buffer(
                    "shadowmap silhouette triangles",
                    bytemuck::cast_slice(&triangles),
                    read,
                ),
                buffer(
                    "shadowmap silhouette edges",
                    bytemuck::cast_slice(&edges),
                    read,
                ),
            ];
            let light = buffer(
                "shadowmap silhouette light",
                bytemuck::bytes_of(&LightRaw::zeroed()),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            );
            let found = buffer("shadowmap silhouette count", &[0; 4], written);
            let silhouette = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadowmap silhouette edges found"),
                size: 8 * u64::from(edge_count.max(1)),
                usage: written,
                mapped_at_creation: false,
            });
            let (layout, pipeline) = pipeline(device);
            let bound = [
                &light,
                &inputs[0],
                &inputs[1],
                &inputs[2],
                &found,
                &silhouette,
            ];
            let entries: Vec<wgpu::BindGroupEntry<'_>> = bound
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry {
                    binding: i as u32,
                    resource: b.as_entire_binding(),
                })
                .collect();
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("shadowmap silhouette"),
                layout: &layout,
                entries: &entries,
            });
            Ok(Self {
                pipeline,
                group,
                light,
                found,
                silhouette,
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
            ctx.queue
                .write_buffer(&self.light, 0, bytemuck::bytes_of(&raw));
            ctx.queue.write_buffer(&self.found, 0, &[0; 4]);
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.group, &[]);
                pass.dispatch_workgroups(self.edge_count.div_ceil(WORKGROUP), 1, 1);
            }
            ctx.queue.submit([encoder.finish()]);
            let count: u32 = bytemuck::pod_read_unaligned(&ctx.read_buffer(&self.found)?);
            let edges: Vec<[u32; 2]> =
                bytemuck::pod_collect_to_vec(&ctx.read_buffer(&self.silhouette)?);
            Ok(edges[..(count as usize).min(edges.len())].to_vec())
        })
    }
}
