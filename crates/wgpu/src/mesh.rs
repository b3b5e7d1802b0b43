//! Caster meshes on the GPU: positions and indices the depth passes and the scene
//! pass draw.

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::{BackendError, GpuContext};

/// Positions (`vec3<f32>`, location 0) and `u32` indices on the GPU.
#[derive(Debug)]
pub struct MeshBuffers {
    /// Vertex positions.
    pub vertices: wgpu::Buffer,
    /// Triangle-list indices.
    pub indices: wgpu::Buffer,
    /// Number of indices.
    pub index_count: u32,
}

impl MeshBuffers {
    /// Uploads an indexed triangle mesh.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for an empty mesh, an index out of range, a
    /// non-finite position, or a mesh past the device's largest buffer.
    pub fn new(
        ctx: &GpuContext,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<Self, BackendError> {
        if positions.is_empty() || triangles.is_empty() {
            return Err(BackendError::InvalidInput("empty mesh"));
        }
        if !positions.iter().all(|p| p.is_finite()) {
            return Err(BackendError::InvalidInput("non-finite vertex position"));
        }
        let n = positions.len();
        if triangles.iter().flatten().any(|&i| i as usize >= n) {
            return Err(BackendError::InvalidInput("vertex index out of range"));
        }
        let index_count = u32::try_from(triangles.len() * 3)
            .map_err(|_| BackendError::InvalidInput("too many triangles"))?;
        // wgpu panics (not an error scope) on a buffer past the device's limit.
        let max = ctx.device.limits().max_buffer_size;
        if (positions.len() as u64).saturating_mul(12) > max
            || u64::from(index_count).saturating_mul(4) > max
        {
            return Err(BackendError::InvalidInput(
                "mesh larger than the device's largest buffer",
            ));
        }
        let vertices = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadowmap mesh vertices"),
                contents: bytemuck::cast_slice(positions),
                usage: wgpu::BufferUsages::VERTEX,
            });
        let indices = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadowmap mesh indices"),
                contents: bytemuck::cast_slice(triangles),
                usage: wgpu::BufferUsages::INDEX,
            });
        Ok(Self {
            vertices,
            indices,
            index_count,
        })
    }

    /// Uploads a triangle soup (three vertices per triangle, no sharing).
    ///
    /// # Errors
    /// As [`MeshBuffers::new`].
    pub fn from_triangles(ctx: &GpuContext, triangles: &[[Vec3; 3]]) -> Result<Self, BackendError> {
        let positions: Vec<Vec3> = triangles.iter().flatten().copied().collect();
        let indices: Vec<[u32; 3]> = (0..triangles.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        Self::new(ctx, &positions, &indices)
    }

    /// The vertex layout: one `vec3<f32>` at location 0.
    #[must_use]
    pub const fn layout() -> wgpu::VertexBufferLayout<'static> {
        wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 0,
            }],
        }
    }
}
