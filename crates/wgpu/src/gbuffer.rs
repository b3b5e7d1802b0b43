//! The eye-space G-buffer of RTW's backward analysis rendered on the GPU
//! ([`RtwGBufferPass`]), so a frame's whole analysis (G-buffer, importance, tables)
//! runs without read-back: `shaders/rtw_gbuffer.wgsl` draws the scene from the camera
//! into the two textures [`crate::rtw::GpuRtw::encode`] reads (world position and eye
//! distance; face normal and the sample flag; background cleared to flag 0). An
//! engine with a deferred renderer would hand its own G-buffer over instead.
//!
//! ```no_run
//! use glam::Vec3;
//! use shadowmap_frustum::{Camera, Projection};
//! use shadowmap_wgpu::GpuContext;
//! use shadowmap_wgpu::depth::MeshBuffers;
//! use shadowmap_wgpu::gbuffer::RtwGBufferPass;
//!
//! let ctx = GpuContext::new_headless()?;
//! let camera = Camera::look_at(Vec3::new(0.0, 5.0, 15.0), Vec3::ZERO, Vec3::Y,
//!     Projection::perspective(1.0, 1.0, 0.5, 50.0)).unwrap();
//! let mesh = MeshBuffers::from_triangles(&ctx, &[[Vec3::ZERO, Vec3::X, Vec3::Y]])?;
//! let mut pass = RtwGBufferPass::new(&ctx, 480, 270, camera.reversed_z)?;
//! let mut encoder = ctx.device.create_command_encoder(&Default::default());
//! pass.encode(&ctx, &mut encoder, &mesh, &camera)?;
//! ctx.queue.submit([encoder.finish()]);
//! let gbuffer = pass.gbuffer(); // for GpuRtw::encode
//! # let _ = gbuffer;
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use bytemuck::{Pod, Zeroable};
use glam::Vec4;
use shadowmap_frustum::Camera;

use crate::context::mesh_pipeline;
use crate::depth::{DepthBias, MeshBuffers, depth_state};
use crate::rtw::{GBUFFER_FORMAT, RtwGBuffer};
use crate::{BackendError, GpuContext, shaders};

/// WGSL `GBufferFrame`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct GBufferFrameRaw {
    clip_from_world: [[f32; 4]; 4],
    eye: [f32; 4],
}

/// The G-buffer pass and its targets of one size.
#[derive(Debug)]
pub struct RtwGBufferPass {
    pipeline: wgpu::RenderPipeline,
    frame: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    reversed_z: bool,
    textures: [wgpu::Texture; 2],
    position: wgpu::TextureView,
    normal: wgpu::TextureView,
    depth: wgpu::TextureView,
}

impl RtwGBufferPass {
    /// The pipeline and `width x height` targets for cameras with this depth
    /// direction.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a zero size or one above the device's 2-D
    /// texture limit; [`BackendError::Wgpu`] if wgpu rejects a resource.
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        reversed_z: bool,
    ) -> Result<Self, BackendError> {
        let limit = ctx.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > limit || height > limit {
            return Err(BackendError::InvalidInput(
                "G-buffer: size zero or too large",
            ));
        }
        ctx.scoped(|ctx| Ok(Self::create(&ctx.device, width, height, reversed_z)))
    }

    fn create(device: &wgpu::Device, width: u32, height: u32, reversed_z: bool) -> Self {
        let target = |label: &str, format: wgpu::TextureFormat| {
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC;
            crate::context::texture_2d(device, label, (width, height), format, usage)
        };
        let textures = [
            target("rtw gbuffer position_distance", GBUFFER_FORMAT),
            target("rtw gbuffer normal_flags", GBUFFER_FORMAT),
        ];
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let frame = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("rtw gbuffer frame"),
            size: size_of::<GBufferFrameRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let pipeline = pipeline(device, reversed_z);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("rtw gbuffer"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: frame.as_entire_binding(),
            }],
        });
        Self {
            pipeline,
            frame,
            bind_group,
            reversed_z,
            position: view(&textures[0]),
            normal: view(&textures[1]),
            depth: view(&target("rtw gbuffer depth", crate::depth::DEPTH_FORMAT)),
            textures,
        }
    }

    /// Records the pass: `mesh` from `camera` into the targets (the frame's block is
    /// queued: record at most one `encode` per submission).
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for an invalid camera or one whose depth
    /// direction differs from the pass's.
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        mesh: &MeshBuffers,
        camera: &Camera,
    ) -> Result<(), BackendError> {
        let clip_from_world = camera
            .clip_from_world()
            .map_err(|_| BackendError::InvalidInput("invalid camera"))?;
        if camera.reversed_z != self.reversed_z {
            return Err(BackendError::InvalidInput(
                "G-buffer: the camera's depth direction differs from the pass's",
            ));
        }
        let raw = GBufferFrameRaw {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
        };
        ctx.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&raw));
        let clear = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("rtw gbuffer"),
            color_attachments: &[clear(&self.position), clear(&self.normal)],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(if self.reversed_z { 0.0 } else { 1.0 }),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, mesh.vertices.slice(..));
        pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..mesh.index_count, 0, 0..1);
        Ok(())
    }

    /// Reads both targets of the last submitted pass back, row-major (row 0 at the
    /// top): `(position and eye distance, normal and flag)`. Blocks until the GPU is
    /// done (a test and debug path).
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read(&self, ctx: &GpuContext) -> Result<(Vec<Vec4>, Vec<Vec4>), BackendError> {
        let [position, normal] = &self.textures;
        let read = |t| -> Result<Vec<Vec4>, BackendError> {
            let bytes = ctx.read_texture(t, wgpu::TextureAspect::All)?;
            Ok(bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(&bytes)
                .into_iter()
                .map(Vec4::from_array)
                .collect())
        };
        Ok((read(position)?, read(normal)?))
    }

    /// The targets, as [`crate::rtw::GpuRtw::encode`] reads them.
    #[must_use]
    pub const fn gbuffer(&self) -> RtwGBuffer<'_> {
        RtwGBuffer {
            position_distance: &self.position,
            normal_flags: &self.normal,
        }
    }
}

/// The G-buffer pipeline: both faces, the camera's depth test, two `Rgba32Float`
/// targets.
fn pipeline(device: &wgpu::Device, reversed_z: bool) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("rtw gbuffer"),
        source: wgpu::ShaderSource::Wgsl(shaders::RTW_GBUFFER.into()),
    });
    let targets = [Some(GBUFFER_FORMAT.into()), Some(GBUFFER_FORMAT.into())];
    mesh_pipeline(
        device,
        ("rtw gbuffer", None, &module),
        depth_state(reversed_z, DepthBias::default()),
        Some(&targets),
    )
}
