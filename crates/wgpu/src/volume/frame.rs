//! What a shadow-volume frame keeps on the GPU from one frame to the next: the
//! attachments (recreated only when the size changes), the frame uniform and its
//! bind group (rewritten in place), and the vertex buffers (grown by doubling and
//! rewritten in place; the scene's surfaces only when the scene changes). A steady
//! stream of frames at one size allocates nothing on the GPU after the first.

use glam::Vec4;

use super::pipelines::{CLASS_FORMAT, DEPTH_STENCIL_FORMAT, VolumeFrameRaw, VolumePipelines};

/// The frame's attachments.
#[derive(Debug)]
pub(super) struct Targets {
    size: (u32, u32),
    pub(super) class: wgpu::Texture,
    pub(super) class_view: wgpu::TextureView,
    pub(super) depth_view: wgpu::TextureView,
}

impl Targets {
    fn new(device: &wgpu::Device, (width, height): (u32, u32)) -> Self {
        let target = |format, usage, label| {
            crate::context::texture_2d(device, label, (width, height), format, usage)
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let class = target(
            CLASS_FORMAT,
            attach | wgpu::TextureUsages::COPY_SRC,
            "shadowmap volume classes",
        );
        let depth = target(
            DEPTH_STENCIL_FORMAT,
            attach,
            "shadowmap volume depth-stencil",
        );
        Self {
            size: (width, height),
            class_view: class.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            class,
        }
    }
}

/// A vertex buffer of `Vec4` positions that grows by doubling and is rewritten in
/// place.
#[derive(Debug, Default)]
pub(super) struct VertexStream {
    buffer: Option<wgpu::Buffer>,
    vertices: u32,
}

impl VertexStream {
    /// Writes `vertices` (allocating only when they outgrow the buffer).
    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, label: &str, data: &[Vec4]) {
        self.vertices = u32::try_from(data.len()).unwrap_or(u32::MAX);
        if data.is_empty() {
            return;
        }
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let needed = bytes.len() as u64;
        if self.buffer.as_ref().is_none_or(|b| b.size() < needed) {
            self.buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: needed.next_power_of_two(),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        if let Some(buffer) = &self.buffer {
            queue.write_buffer(buffer, 0, bytes);
        }
    }

    /// The buffer slice and vertex count to draw, if there is anything to draw.
    pub(super) fn drawable(&self) -> Option<(wgpu::BufferSlice<'_>, u32)> {
        let buffer = self.buffer.as_ref().filter(|_| self.vertices > 0)?;
        Some((buffer.slice(..u64::from(self.vertices) * 16), self.vertices))
    }
}

/// Everything a frame reuses; see the module docs.
#[derive(Debug)]
pub(super) struct FrameResources {
    targets: Option<Targets>,
    buffers: FrameBuffers,
}

/// The frame's uniform, bind group and vertex streams.
#[derive(Debug)]
pub(super) struct FrameBuffers {
    uniform: wgpu::Buffer,
    pub(super) group: wgpu::BindGroup,
    pub(super) surfaces: VertexStream,
    /// The [`super::VolumeScene`] whose surfaces `surfaces` holds.
    surfaces_of: Option<u64>,
    pub(super) volume: VertexStream,
}

impl FrameResources {
    pub(super) fn new(device: &wgpu::Device, pipelines: &VolumePipelines) -> Self {
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadowmap volume frame"),
            size: size_of::<VolumeFrameRaw>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadowmap volume frame"),
            layout: &pipelines.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            }],
        });
        Self {
            targets: None,
            buffers: FrameBuffers {
                uniform,
                group,
                surfaces: VertexStream::default(),
                surfaces_of: None,
                volume: VertexStream::default(),
            },
        }
    }

    /// Brings the resources up to date for one frame: attachments of `size`, the
    /// frame uniform, the surfaces of scene `scene_id` (uploaded only when the
    /// scene changed) and this frame's volume geometry.
    pub(super) fn prepare(
        &mut self,
        (device, queue): (&wgpu::Device, &wgpu::Queue),
        size: (u32, u32),
        frame: &VolumeFrameRaw,
        (scene_id, surfaces): (u64, &[Vec4]),
        volume: &[Vec4],
    ) -> (&Targets, &FrameBuffers) {
        let buffers = &mut self.buffers;
        queue.write_buffer(&buffers.uniform, 0, bytemuck::bytes_of(frame));
        if buffers.surfaces_of != Some(scene_id) {
            buffers
                .surfaces
                .write(device, queue, "shadowmap volume surfaces", surfaces);
            buffers.surfaces_of = Some(scene_id);
        }
        buffers
            .volume
            .write(device, queue, "shadowmap volume geometry", volume);
        if self.targets.as_ref().is_some_and(|t| t.size != size) {
            self.targets = None;
        }
        let targets = self
            .targets
            .get_or_insert_with(|| Targets::new(device, size));
        (targets, &self.buffers)
    }
}
