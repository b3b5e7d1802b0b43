//! The headless renderer: a scene from a camera, shadowed by one technique, into an
//! RGBA8 image (and a PNG) plus a per-pixel shadow mask for tests.
//!
//! Each frame renders the technique's depth pass (casters refined on the GPU for the
//! paraboloid and RTW passes, [`crate::refine::GpuRefine`], and drawn indirectly),
//! the moments and blur passes for VSM, then the scene pass, whose fragment shader
//! is `render_scene.wgsl` with the technique's `lookup_*.wgsl` and the filter's
//! `filter_*.wgsl` composed in ([`compose_scene_shader`]). The mask is the plain
//! nearest-texel depth test (`shadowmap_eval`'s `DepthMap::is_lit`), whatever the
//! filter.
//!
//! The renderer is for tests, reports and examples: it waits for the GPU and reads
//! the image back. It keeps its pipelines, its depth passes (texture and pipeline per
//! description) and the scene's casters with their refinement across frames (the
//! casters are compared by value each frame), so a repeated frame records commands
//! and writes uniforms only. An engine would keep the
//! [`ShadowDepthPass`](crate::depth::ShadowDepthPass), the refinement and the lookup
//! shaders and drop the rest.
//!
//! ```no_run
//! use glam::Vec3;
//! use shadowmap_frustum::{Aabb, Camera, Projection};
//! use shadowmap_warp::{SceneBounds, UniformOptions, uniform_focused};
//! use shadowmap_wgpu::GpuContext;
//! use shadowmap_wgpu::render::{HeadlessRenderer, RenderOptions, ShadowTechnique};
//!
//! let ctx = GpuContext::new_headless()?;
//! let ground = [[Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 0.0, -10.0), Vec3::new(0.0, 0.0, 10.0)]];
//! let camera = Camera::look_at(Vec3::new(0.0, 5.0, 15.0), Vec3::ZERO, Vec3::Y,
//!     Projection::perspective(1.0, 1.0, 0.5, 50.0)).unwrap();
//! let scene = SceneBounds::whole(Aabb::new(Vec3::new(-10.0, 0.0, -10.0), Vec3::new(10.0, 1.0, 10.0)));
//! let light = uniform_focused(&camera, Vec3::new(0.3, -1.0, 0.2), &scene, &UniformOptions::default()).unwrap();
//! let mut renderer = HeadlessRenderer::new();
//! let frame = renderer.render(&ctx, &ground, &camera, &ShadowTechnique::Matrix(&light), &RenderOptions::default())?;
//! frame.image.save_png("shadow.png")?;
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

mod cache;
mod image;
mod options;
mod passes;
mod pipelines;
mod technique;

use std::collections::HashMap;

use glam::{Mat4, Vec3};
use shadowmap_frustum::Camera;

pub use self::image::{Image, MaskValue, RenderedFrame, ShadowMask};
pub use self::options::{RenderOptions, ShadowBias, ShadowFilter};
pub use self::technique::ShadowTechnique;
pub use crate::compose::{compose_scene_shader, composed_shaders};

use self::cache::DepthCache;
use self::image::SceneTargets;
use self::passes::{DepthJob, SceneInputs, record_scene};
use self::pipelines::{ScenePipeline, VsmPipelines, create_scene_pipeline};
use self::technique::Lookup;
use crate::profile::GpuProfiler;
use crate::uniforms::FrameRaw;
use crate::{BackendError, GpuContext};

/// Renders scenes headlessly; keeps its pipelines, depth passes and the scene's
/// casters (with their refinement) across frames.
#[derive(Debug, Default)]
pub struct HeadlessRenderer {
    scene: HashMap<(Lookup, u8, bool), ScenePipeline>,
    vsm: Option<VsmPipelines>,
    depth: DepthCache,
}

impl HeadlessRenderer {
    /// An empty renderer (pipelines are created on first use).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Renders `triangles` (every triangle casts and receives) from `camera` with the
    /// shadow of `technique`, waits for the GPU and reads the image and the mask back.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for an empty or non-finite scene, a zero or too
    /// large image or map, an invalid camera, a cascade set without a (fitted)
    /// cascade, or caster refinement failing; [`BackendError::Wgpu`] for any wgpu
    /// error; [`BackendError::Readback`].
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        triangles: &[[Vec3; 3]],
        camera: &Camera,
        technique: &ShadowTechnique<'_>,
        options: &RenderOptions,
    ) -> Result<RenderedFrame, BackendError> {
        self.render_with(ctx, (triangles, camera), technique, options, None)
    }

    /// [`HeadlessRenderer::render`], profiled where `profiler` is given.
    fn render_with(
        &mut self,
        ctx: &GpuContext,
        (triangles, camera): (&[[Vec3; 3]], &Camera),
        technique: &ShadowTechnique<'_>,
        options: &RenderOptions,
        profiler: Option<&mut GpuProfiler>,
    ) -> Result<RenderedFrame, BackendError> {
        let limit = ctx.device.limits().max_texture_dimension_2d;
        if options.width == 0
            || options.height == 0
            || options.width > limit
            || options.height > limit
        {
            return Err(BackendError::InvalidInput("image size out of range"));
        }
        if !options.bias.is_none_or(|b| b.is_finite()) {
            return Err(BackendError::InvalidInput("non-finite bias"));
        }
        let clip_from_world = camera
            .clip_from_world()
            .map_err(|_| BackendError::InvalidInput("invalid camera"))?;
        let view_from_world = camera
            .view_from_world()
            .map_err(|_| BackendError::InvalidInput("invalid camera"))?;
        let frame = FrameView {
            camera,
            clip_from_world,
            view_from_world,
            light: FrameRaw::light_vector(technique.light()?),
        };
        ctx.scoped(|ctx| self.render_scoped(ctx, (triangles, &frame), technique, options, profiler))
    }

    /// [`HeadlessRenderer::render`] with the GPU time of its passes recorded by
    /// `profiler` in scopes `refine` (the paraboloid and RTW caster refinement),
    /// `depth` (every layer), `vsm` (VSM filter only) and `scene`; read them with
    /// [`GpuProfiler::read`] after this returns.
    ///
    /// # Errors
    /// As [`HeadlessRenderer::render`].
    pub fn render_profiled(
        &mut self,
        ctx: &GpuContext,
        triangles: &[[Vec3; 3]],
        camera: &Camera,
        technique: &ShadowTechnique<'_>,
        options: &RenderOptions,
        profiler: &mut GpuProfiler,
    ) -> Result<RenderedFrame, BackendError> {
        let scene = (triangles, camera);
        self.render_with(ctx, scene, technique, options, Some(profiler))
    }

    fn render_scoped(
        &mut self,
        ctx: &GpuContext,
        (triangles, view): (&[[Vec3; 3]], &FrameView<'_>),
        technique: &ShadowTechnique<'_>,
        options: &RenderOptions,
        mut profiler: Option<&mut GpuProfiler>,
    ) -> Result<RenderedFrame, BackendError> {
        let reversed = technique.reversed_z();
        let bias = options
            .bias
            .unwrap_or_else(|| ShadowBias::default_for(technique, options.filter));
        self.depth.use_scene(ctx, triangles)?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        // 1. The depth pass, casters refined where the projection is not linear.
        let job = DepthJob {
            options,
            bias: bias.raster_for(reversed),
            reversed,
        };
        let output = job.encode(
            (ctx, &mut encoder),
            &mut self.depth,
            technique,
            &mut profiler,
        )?;
        let depth = self
            .depth
            .pass(output.pass)
            .ok_or(BackendError::InvalidInput("no depth pass"))?;
        // 2. VSM moments and blur (a 1x1 placeholder for the other filters).
        let vsm = &mut self.vsm;
        let moments = if matches!(options.filter, ShadowFilter::Vsm { .. }) {
            timed(&mut profiler, &mut encoder, "vsm", |e| {
                passes::encode_vsm(vsm, ctx, e, depth, options, reversed)
            })?
        } else {
            passes::encode_vsm(vsm, ctx, &mut encoder, depth, options, reversed)?
        };
        // 3. The scene pass.
        let (radius, taps) = options.filter.params();
        let resolution = options.shadow_resolution as f32;
        let frame = FrameRaw {
            clip_from_world: view.clip_from_world.to_cols_array_2d(),
            view_from_world: view.view_from_world.to_cols_array_2d(),
            light: view.light,
            bias: [
                bias.depth,
                bias.world,
                radius,
                f32::from(u8::from(reversed)),
            ],
            shadow_size: [resolution, resolution, depth.desc().layers as f32, taps],
            eye: view.camera.eye().extend(1.0).to_array(),
        };
        let inputs = SceneInputs {
            frame,
            lookup: technique.lookup_bytes(view.view_from_world, options.shadow_resolution),
            tables: &output.tables,
            depth,
            moments: &moments,
            reversed,
        };
        let camera_reversed = view.camera.reversed_z;
        let key = (technique.lookup(), options.filter.key(), camera_reversed);
        let pipeline = scene_pipeline(&mut self.scene, &ctx.device, key, options.filter)?;
        let targets = SceneTargets::new(&ctx.device, options.width, options.height);
        let job = (self.depth.mesh()?, &targets, camera_reversed);
        timed(&mut profiler, &mut encoder, "scene", |e| {
            record_scene(ctx, e, pipeline, &inputs, job);
        });
        if let Some(p) = profiler {
            p.resolve(&mut encoder);
        }
        ctx.queue.submit([encoder.finish()]);
        targets.read(ctx)
    }
}

/// The cached scene pipeline of (lookup, filter key, camera reversed-Z), created on
/// first use.
fn scene_pipeline<'c>(
    cache: &'c mut HashMap<(Lookup, u8, bool), ScenePipeline>,
    device: &wgpu::Device,
    key: (Lookup, u8, bool),
    filter: ShadowFilter,
) -> Result<&'c ScenePipeline, BackendError> {
    Ok(match cache.entry(key) {
        std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
        std::collections::hash_map::Entry::Vacant(v) => {
            v.insert(create_scene_pipeline(device, key.0, filter, key.2)?)
        }
    })
}

/// `record` inside the profiler's scope `label`, or plainly without a profiler.
pub(super) fn timed<T>(
    profiler: &mut Option<&mut GpuProfiler>,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    record: impl FnOnce(&mut wgpu::CommandEncoder) -> T,
) -> T {
    match profiler {
        Some(p) => p.scope(encoder, label, record),
        None => record(encoder),
    }
}

/// The camera's side of a frame, checked before any GPU work.
struct FrameView<'a> {
    camera: &'a Camera,
    clip_from_world: Mat4,
    view_from_world: Mat4,
    /// [`FrameRaw::light`].
    light: [f32; 4],
}
