//! Stencil shadow volumes: exact per-pixel shadows of closed casters, the backend's
//! ground truth for how wrong a shadow map is at the render resolution.
//!
//! A frame ([`VolumeRenderer::render_mask`]) has three passes over one
//! `Depth24PlusStencil8` target, with the camera's reversed-Z, infinite-far
//! projection (`shadowmap_volume::infinite_clip_from_world`):
//!
//! 1. **surfaces**: every scene triangle, depth test and write, marking each pixel
//!    that sees a surface inside the camera's depth range;
//! 2. **volumes**: the shadow volumes of the closed casters (silhouettes and caps
//!    from `shadowmap_volume::ShadowVolume`, uploaded each frame), no depth write,
//!    two-sided stencil in one draw (Crow 1977; Everitt and Kilgard, *Practical and
//!    Robust Stenciled Shadow Volumes*, 2002):
//!
//!    ```text
//!    z-pass  depth passes:  front face +1, back face -1   (sides only; eye outside every volume)
//!    z-fail  depth fails:   back face +1, front face -1   (sides and both caps; any eye)
//!    ```
//!
//!    with wrapping increments, so the count is the number of volumes the surface
//!    point is in (mod 256);
//! 3. **classify**: a full-screen triangle on the far plane, where a surface is and
//!    the stencil is not zero, marks the pixel shadowed.
//!
//! The scene is split once ([`VolumeScene::new`]) into its closed parts, which cast
//! volumes, and open parts (ground planes, single-sided walls), which only receive;
//! [`VolumeScene::first_open_edge`] names the first open edge so a caster that is
//! not closed is reported, never silently dropped.
//!
//! [`GpuSilhouette`] finds the silhouette edges in a compute pass instead (the same
//! edge set as the CPU). [`ProjectiveRenderer`] draws projective shadows, the overview's third system.
//! [`misclassification`] compares a shadow map's mask from
//! [`crate::render::HeadlessRenderer`] with the volumes' mask pixel by pixel.

mod compare;
mod frame;
mod pipelines;
mod projective;
mod silhouette;

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{Vec3, Vec4};
use shadowmap_frustum::{Camera, Light};
use shadowmap_volume::{EdgeMesh, Partition, ShadowVolume, VolumeError, infinite_clip_from_world};

pub use self::compare::{Misclassification, misclassification};
use self::frame::{FrameBuffers, FrameResources, Targets};
use self::pipelines::{VolumeFrameRaw, VolumePipelines};
pub use self::projective::ProjectiveRenderer;
pub use self::silhouette::GpuSilhouette;
use crate::render::{MaskValue, ShadowMask};
use crate::{BackendError, GpuContext};

/// Which stencil count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VolumeMethod {
    /// Count volume faces in front of the surface (sides only): right only when the
    /// camera is outside every volume.
    ZPass,
    /// Count volume faces behind the surface (Carmack's reverse, sides and caps):
    /// right wherever the camera is.
    ZFail,
}

/// A scene prepared for shadow volumes: its surfaces, and its closed casters with
/// their edge adjacency (built once).
#[derive(Clone, Debug)]
pub struct VolumeScene {
    /// Tells scenes apart, so a renderer uploads a scene's surfaces once.
    id: u64,
    surfaces: Vec<Vec4>,
    casters: EdgeMesh,
    open_triangles: usize,
    first_open_edge: Option<VolumeError>,
    volume: ShadowVolume,
}

/// The id of the next [`VolumeScene`].
static NEXT_SCENE_ID: AtomicU64 = AtomicU64::new(0);

fn volume_error(e: VolumeError) -> BackendError {
    BackendError::InvalidInput(match e {
        VolumeError::NonFinite { .. } => "a scene vertex is not finite",
        VolumeError::TooLarge => "more triangles than u32 indices address",
        VolumeError::InvalidLight(_) => "the light fails validation",
        VolumeError::InvalidCamera(_) => "the camera fails validation",
        VolumeError::UnsupportedProjection => {
            "shadow volumes need a perspective camera (infinite far plane)"
        }
        _ => "invalid shadow-volume input",
    })
}

impl VolumeScene {
    /// Splits the triangles into closed casters and open receivers and pairs the
    /// casters' edges.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a non-finite vertex or more triangles
    /// than `u32` indices address.
    pub fn new(triangles: &[[Vec3; 3]]) -> Result<Self, BackendError> {
        let positions: Vec<Vec3> = triangles.iter().flatten().copied().collect();
        let count = u32::try_from(triangles.len())
            .ok()
            .filter(|&n| n < u32::MAX / 3)
            .ok_or(volume_error(VolumeError::TooLarge))?;
        let indices: Vec<[u32; 3]> = (0..count).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let part = Partition::new(&positions, &indices).map_err(volume_error)?;
        let casters = EdgeMesh::new(&positions, &part.closed).map_err(volume_error)?;
        Ok(Self {
            id: NEXT_SCENE_ID.fetch_add(1, Ordering::Relaxed),
            surfaces: positions.iter().map(|p| p.extend(1.0)).collect(),
            casters,
            open_triangles: part.open.len(),
            first_open_edge: part.first_open_edge,
            volume: ShadowVolume::new(),
        })
    }

    /// The closed casters with their adjacency.
    #[must_use]
    pub const fn casters(&self) -> &EdgeMesh {
        &self.casters
    }

    /// Number of triangles in open parts (receivers that cast no volume).
    #[must_use]
    pub const fn open_triangles(&self) -> usize {
        self.open_triangles
    }

    /// The first open edge, as `shadowmap_volume::VolumeError::OpenEdge`, when
    /// some part of the scene is not closed.
    #[must_use]
    pub const fn first_open_edge(&self) -> Option<VolumeError> {
        self.first_open_edge
    }

    /// The volume of the last frame (facing flags, silhouette, geometry).
    #[must_use]
    pub const fn volume(&self) -> &ShadowVolume {
        &self.volume
    }
}

/// Renders shadow-volume masks. Keeps its pipelines, attachments, uniform and
/// vertex buffers across frames (see [`VolumeRenderer::render_mask`]), all on the
/// device of its first frame.
#[derive(Debug, Default)]
pub struct VolumeRenderer {
    pipelines: Option<VolumePipelines>,
    frame: Option<FrameResources>,
}

impl VolumeRenderer {
    /// A renderer with no pipelines yet.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            pipelines: None,
            frame: None,
        }
    }

    /// The shadow-volume mask of `scene` lit by `light`, seen by `camera`, at
    /// `width x height` (rows top to bottom): [`MaskValue::Lit`] or
    /// [`MaskValue::Shadowed`] where a surface is seen within the camera's depth
    /// range, [`MaskValue::Background`] elsewhere. Spot lights shadow like point
    /// lights (visibility only, the cone does not darken).
    ///
    /// Frame after frame at one size, the only uploads are the frame uniform and the
    /// volume geometry (into buffers that grow by doubling); the scene's surfaces are
    /// uploaded when the scene changes, the attachments made when the size changes.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a size of zero or past the device's
    /// limit, an invalid light, or a camera that is invalid or not perspective;
    /// [`BackendError::Wgpu`] for GPU errors.
    pub fn render_mask(
        &mut self,
        ctx: &GpuContext,
        scene: &mut VolumeScene,
        camera: &Camera,
        light: &Light,
        (width, height): (u32, u32),
        method: VolumeMethod,
    ) -> Result<ShadowMask, BackendError> {
        let max = ctx.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(BackendError::InvalidInput("mask size is zero or too large"));
        }
        let clip_from_world = infinite_clip_from_world(camera).map_err(volume_error)?;
        let (_, far) = camera
            .depth_range()
            .map_err(|e| volume_error(VolumeError::InvalidCamera(e)))?;
        scene
            .volume
            .update(&scene.casters, light)
            .map_err(volume_error)?;
        let frame = VolumeFrameRaw {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            eye: camera.eye().extend(far).to_array(),
            forward: camera.forward().extend(0.0).to_array(),
        };
        let volume = match method {
            VolumeMethod::ZPass => scene.volume.sides(),
            VolumeMethod::ZFail => scene.volume.closed(),
        };
        ctx.scoped(|ctx| {
            let pipelines = self
                .pipelines
                .get_or_insert_with(|| VolumePipelines::new(&ctx.device));
            let resources = self
                .frame
                .get_or_insert_with(|| FrameResources::new(&ctx.device, pipelines));
            let (targets, buffers) = resources.prepare(
                (&ctx.device, &ctx.queue),
                (width, height),
                &frame,
                (scene.id, &scene.surfaces),
                volume,
            );
            let mut encoder = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("shadowmap volumes"),
                });
            record(pipelines, &mut encoder, targets, buffers, method);
            ctx.queue.submit([encoder.finish()]);
            let classes = ctx.read_texture(&targets.class, wgpu::TextureAspect::All)?;
            Ok(decode(width, height, &classes))
        })
    }
}

/// Records the surface, volume and classification passes.
fn record(
    pipelines: &VolumePipelines,
    encoder: &mut wgpu::CommandEncoder,
    targets: &Targets,
    buffers: &FrameBuffers,
    method: VolumeMethod,
) {
    let (class_view, depth_view, group) =
        (&targets.class_view, &targets.depth_view, &buffers.group);
    let color = |ops| {
        [Some(wgpu::RenderPassColorAttachment {
            view: class_view,
            depth_slice: None,
            resolve_target: None,
            ops,
        })]
    };
    {
        let colors = color(wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        });
        let mut p = begin(
            encoder,
            "shadowmap volume surfaces",
            &colors,
            (depth_view, clear(0.0), clear(0)),
        );
        if let Some((slice, vertices)) = buffers.surfaces.drawable() {
            p.set_pipeline(&pipelines.surface);
            p.set_bind_group(0, group, &[]);
            p.set_vertex_buffer(0, slice);
            p.draw(0..vertices, 0..1);
        }
    }
    if let Some((slice, vertices)) = buffers.volume.drawable() {
        let mut p = begin(
            encoder,
            "shadowmap volume stencil",
            &[],
            (depth_view, load(), load()),
        );
        p.set_pipeline(match method {
            VolumeMethod::ZPass => &pipelines.z_pass,
            VolumeMethod::ZFail => &pipelines.z_fail,
        });
        p.set_bind_group(0, group, &[]);
        p.set_vertex_buffer(0, slice);
        p.draw(0..vertices, 0..1);
    }
    let colors = color(load());
    let mut p = begin(
        encoder,
        "shadowmap volume classify",
        &colors,
        (depth_view, load(), load()),
    );
    p.set_pipeline(&pipelines.classify);
    p.set_bind_group(0, group, &[]);
    p.set_stencil_reference(0);
    p.draw(0..3, 0..1);
}

/// Begins a pass on the colour targets and the depth-stencil view.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    colors: &[Option<wgpu::RenderPassColorAttachment<'_>>],
    (view, depth, stencil): (
        &wgpu::TextureView,
        wgpu::Operations<f32>,
        wgpu::Operations<u32>,
    ),
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colors,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(depth),
            stencil_ops: Some(stencil),
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

const fn load<T>() -> wgpu::Operations<T> {
    wgpu::Operations {
        load: wgpu::LoadOp::Load,
        store: wgpu::StoreOp::Store,
    }
}

const fn clear<T>(value: T) -> wgpu::Operations<T> {
    wgpu::Operations {
        load: wgpu::LoadOp::Clear(value),
        store: wgpu::StoreOp::Store,
    }
}

/// The mask of a class texture: 1 lit, 2 shadowed, anything else background.
fn decode(width: u32, height: u32, classes: &[u8]) -> ShadowMask {
    ShadowMask {
        width,
        height,
        values: classes
            .iter()
            .map(|c| match c {
                1 => MaskValue::Lit,
                2 => MaskValue::Shadowed,
                _ => MaskValue::Background,
            })
            .collect(),
    }
}
