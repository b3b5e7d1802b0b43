//! The whole RTW pipeline on the GPU: importance from an eye-space G-buffer (backward
//! analysis), collapse to column and row maxima, blur, normalization, temporal
//! smoothing, floor, and the two warp tables, in three compute dispatches.
//!
//! It reproduces [`shadowmap_rtw::ImportanceMap::accumulate_backward`] followed by
//! [`shadowmap_rtw::WarpMaps::build`] (same formulas, same table semantics; see
//! `shaders/rtw_importance.wgsl` and `shaders/rtw_warp.wgsl`), in `f32` where the CPU
//! uses `f64`: the tables agree to about `1e-6`. A sample within an `f32` rounding of a
//! cell border may land in the neighbouring cell.
//!
//! ```text
//! splat     (16x16 per workgroup, one invocation per G-buffer texel)  -> importance map
//! collapse  (one workgroup per map row)                               -> column, row maxima
//! build     (one 256-wide workgroup per axis)                         -> density, tables
//! ```
//!
//! # G-buffer
//! Two `Rgba32Float` textures of the same size ([`RtwGBuffer`]): world position and
//! eye distance; normal and a flag (`0` no sample, `1` sample, `2` sample on a shadow
//! edge). [`RtwGBufferTextures::from_samples`] builds them from
//! [`EyeSample`]s on the CPU. Samples with a non-finite component are skipped and
//! counted (the CPU refuses the whole batch instead).
//!
//! # Output layout
//! [`GpuRtw::tables_buffer`] is a storage buffer of `width + height` `f32`: the `u`
//! table (`width` texels), then the `v` table (`height` texels), each with the exact
//! semantics of [`shadowmap_rtw::WarpMaps::x_table`] (`T[0] = T[N-1] = 0`, texel `i`
//! holds the offset at `u = (i + 0.5) / N`, sampled as in
//! [`shadowmap_rtw::forward_warp`]). Bind it as `var<storage, read> array<f32>`.
//!
//! # Temporal smoothing
//! As on the CPU: the first build after [`GpuRtw::new`] or [`GpuRtw::reset_history`]
//! uses no history; later builds mix in the previous density with weight
//! `WarpOptions::temporal`. The history flag lives on the GPU, so several builds in
//! one submission chain correctly.
//!
//! # Memory, barriers, subgroups, reduction order
//!
//! The NVIDIA failure of an earlier version (an H100 reported `identity_fallback =
//! [true, true]` for a 64x48 map with importance near `f32::MAX`) was a division by a
//! peak above 2^126, where WGSL guarantees `x / y` only for `|y|` in `[2^-126,
//! 2^126]` and NVIDIA's reciprocal flushes to zero; `rtw_warp.wgsl` now scales by
//! exponent bits instead. The other suspects were audited:
//!
//! - **Workgroup memory.** Every workgroup variable is written before a barrier and
//!   read after it (the counters and maxima by invocation 0, the scan by every
//!   invocation). The pipelines are compiled with wgpu's zero-initialization of
//!   workgroup memory off, so the tests run the shaders as a driver that leaves it
//!   uninitialized would.
//! - **Storage memory.** The cells, maxima and counts are cleared by the encoder
//!   every frame. The density history was read (times a zero weight) on the first
//!   build, and `0 * NaN` is NaN: it is now read only when there is history, and a
//!   test fills a fresh history with NaN first.
//! - **Barriers.** The only reads of storage written by another invocation (the
//!   scan's chunks read the densities of neighbouring texels) follow a
//!   `storageBarrier` and a `workgroupBarrier`; every barrier is in uniform control
//!   flow (the early exit of a constant density goes through `workgroupUniformLoad`).
//! - **Subgroups.** None are used: no result depends on the subgroup size (32 on
//!   NVIDIA, 8 to 64 elsewhere).
//! - **Reduction order.** Maxima and minima are integer atomics on float bits (order
//!   free for the finite, non-negative values they hold), counts integer atomics; the
//!   one floating-point sum (the trapezoid cumulative sum) is a fixed chunked
//!   Hillis-Steele scan over the workgroup's 256 lanes, the same order on every GPU.
//! - **Sizes.** Every loop strides by its workgroup size and every invocation checks
//!   its bounds; the tests cover maps from 3x2 to 1000x5 (257 wide: one lane past the
//!   build's workgroup) and G-buffers that are not multiples of the 16x16 splat
//!   workgroup.
//!
//! # Example
//! ```no_run
//! use glam::{Mat4, Vec3};
//! use shadowmap_frustum::{LightDirection, ShadowTransform};
//! use shadowmap_rtw::{EyeSample, ImportanceOptions, WarpOptions};
//! use shadowmap_wgpu::GpuContext;
//! use shadowmap_wgpu::rtw::{GpuRtw, RtwGBufferTextures};
//!
//! let ctx = GpuContext::new_headless()?;
//! # let base = ShadowTransform::new(Mat4::IDENTITY, Mat4::IDENTITY, false,
//! #     LightDirection::Directional(Vec3::NEG_Y));
//! let mut rtw = GpuRtw::new(&ctx, 256, 256, &WarpOptions::default(), &ImportanceOptions::default())?;
//! let sample = EyeSample { position: Vec3::new(0.1, 0.0, -2.0), normal: Vec3::Y, eye_distance: 2.0 };
//! let gbuffer = RtwGBufferTextures::from_samples(&ctx, 1, 1, &[Some(sample)], None)?;
//! let mut encoder = ctx.device.create_command_encoder(&Default::default());
//! rtw.encode(&ctx, &mut encoder, &gbuffer.as_gbuffer(), &base)?;
//! ctx.queue.submit([encoder.finish()]);
//! let (u_table, v_table) = rtw.read_tables(&ctx)?;
//! assert_eq!((u_table.len(), v_table.len()), (256, 256));
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use bytemuck::{Pod, Zeroable};
use glam::Vec4;
use shadowmap_frustum::{LightDirection, ShadowTransform};
use shadowmap_rtw::{
    EyeSample, ImportanceOptions, MAX_BLUR_RADIUS, MAX_MAP_CELLS, MAX_MAP_SIDE, WarpOptions,
};

use crate::{BackendError, GpuContext};

/// Format of both G-buffer textures.
pub const GBUFFER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// `normal_flags.w` of a texel with no sample (background).
pub const FLAG_NO_SAMPLE: f32 = 0.0;
/// `normal_flags.w` of a sample.
pub const FLAG_SAMPLE: f32 = 1.0;
/// `normal_flags.w` of a sample on a shadow edge (gets `edge_weight`).
pub const FLAG_EDGE_SAMPLE: f32 = 2.0;

/// An eye-space G-buffer, the input of [`GpuRtw::encode`]: two views of
/// [`GBUFFER_FORMAT`] textures of the same size with `TEXTURE_BINDING` usage.
#[derive(Clone, Copy, Debug)]
pub struct RtwGBuffer<'a> {
    /// `xyz`: world position, `w`: distance from the eye.
    pub position_distance: &'a wgpu::TextureView,
    /// `xyz`: surface normal (zero: unknown, neutral orientation term), `w`: one of
    /// [`FLAG_NO_SAMPLE`], [`FLAG_SAMPLE`], [`FLAG_EDGE_SAMPLE`].
    pub normal_flags: &'a wgpu::TextureView,
}

/// G-buffer textures filled from CPU samples (tests, benches, CPU-side sampling).
#[derive(Debug)]
pub struct RtwGBufferTextures {
    /// The position and eye-distance texture.
    pub position_distance: wgpu::Texture,
    /// The normal and flag texture.
    pub normal_flags: wgpu::Texture,
    position_view: wgpu::TextureView,
    normal_view: wgpu::TextureView,
}

impl RtwGBufferTextures {
    /// Uploads `width x height` texels, row-major: `Some(sample)` is a sample, `None`
    /// no sample. With an edge mask (one flag per texel), flagged samples are on a
    /// shadow edge.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a zero or too large size (above the
    /// device's 2-D texture limit) or slices of another length.
    pub fn from_samples(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        samples: &[Option<EyeSample>],
        edge_mask: Option<&[bool]>,
    ) -> Result<Self, BackendError> {
        let max_side = ctx.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max_side || height > max_side {
            return Err(BackendError::InvalidInput(
                "G-buffer: size zero or too large",
            ));
        }
        let len = width as usize * height as usize;
        if samples.len() != len || edge_mask.is_some_and(|m| m.len() != len) {
            return Err(BackendError::InvalidInput(
                "G-buffer: slice length != width * height",
            ));
        }
        let mut position_distance = Vec::with_capacity(len);
        let mut normal_flags = Vec::with_capacity(len);
        for (i, sample) in samples.iter().enumerate() {
            match sample {
                Some(s) => {
                    let edge = edge_mask.is_some_and(|m| m.get(i).copied().unwrap_or(false));
                    let flag = if edge { FLAG_EDGE_SAMPLE } else { FLAG_SAMPLE };
                    position_distance.push(s.position.extend(s.eye_distance));
                    normal_flags.push(s.normal.extend(flag));
                }
                None => {
                    position_distance.push(Vec4::ZERO);
                    normal_flags.push(Vec4::new(0.0, 0.0, 0.0, FLAG_NO_SAMPLE));
                }
            }
        }
        let texture = |label: &str, texels: &[Vec4]| {
            let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
            let texture = crate::context::texture_2d(
                &ctx.device,
                label,
                (width, height),
                GBUFFER_FORMAT,
                usage,
            );
            ctx.queue.write_texture(
                texture.as_image_copy(),
                bytemuck::cast_slice(texels),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(width * 16),
                    rows_per_image: Some(height),
                },
                texture.size(),
            );
            texture
        };
        let position_distance = texture("rtw gbuffer position_distance", &position_distance);
        let normal_flags = texture("rtw gbuffer normal_flags", &normal_flags);
        Ok(Self {
            position_view: position_distance.create_view(&Default::default()),
            normal_view: normal_flags.create_view(&Default::default()),
            position_distance,
            normal_flags,
        })
    }

    /// Views of both textures, for [`GpuRtw::encode`].
    #[must_use]
    pub fn as_gbuffer(&self) -> RtwGBuffer<'_> {
        RtwGBuffer {
            position_distance: &self.position_view,
            normal_flags: &self.normal_view,
        }
    }
}

/// What the last submitted build did, read back by [`GpuRtw::read_stats`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuRtwStats {
    /// Samples written into a cell.
    pub accepted: u32,
    /// Samples skipped: outside the base map, behind a perspective light, or with a
    /// non-finite component.
    pub skipped: u32,
    /// Whether the `u` and `v` tables fell back to the identity (zero importance).
    pub identity_fallback: [bool; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ImportanceParamsRaw {
    uv_from_world: [[f32; 4]; 4],
    light: [f32; 4],
    distance: [f32; 4],
    edge: [f32; 4],
    map_size: [u32; 4],
}

/// Gaussian weights `w_0..=w_radius`, four per vector.
const WEIGHT_VECTORS: usize = (MAX_BLUR_RADIUS as usize + 1).div_ceil(4);

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct WarpParamsRaw {
    sizes: [u32; 4],
    knobs: [f32; 4],
    weights: [[f32; 4]; WEIGHT_VECTORS],
}

/// The Gaussian weights of `shadowmap_rtw::WarpMaps::build`, packed into `vec4`s.
fn gaussian_weights(radius: u32) -> [[f32; 4]; WEIGHT_VECTORS] {
    let mut packed = [[0.0f32; 4]; WEIGHT_VECTORS];
    for (k, &wk) in shadowmap_rtw::gaussian_weights(radius).iter().enumerate() {
        packed[k / 4][k % 4] = wk as f32;
    }
    packed
}

/// The GPU RTW pipeline for one importance-map size: pipelines, buffers, bind groups.
///
/// Created once; [`GpuRtw::encode`] allocates nothing but the bind group of its
/// G-buffer views.
#[derive(Debug)]
pub struct GpuRtw {
    width: u32,
    height: u32,
    importance: ImportanceOptions,
    splat: wgpu::ComputePipeline,
    collapse: wgpu::ComputePipeline,
    build: wgpu::ComputePipeline,
    importance_params: wgpu::Buffer,
    cells: wgpu::Buffer,
    maxima: wgpu::Buffer,
    counts: wgpu::Buffer,
    density: wgpu::Buffer,
    tables: wgpu::Buffer,
    state: wgpu::Buffer,
    collapse_group: wgpu::BindGroup,
    build_group: wgpu::BindGroup,
}

fn option_error(_: shadowmap_rtw::RtwError) -> BackendError {
    BackendError::InvalidInput("RTW: option out of its documented range")
}

impl GpuRtw {
    /// Compiles the pipeline for a `width x height` importance map (the `u` table has
    /// `width` texels, the `v` table `height`).
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a zero side, a map above
    /// [`MAX_MAP_SIDE`] / [`MAX_MAP_CELLS`] or the device's storage-buffer and
    /// dispatch limits, or options outside their documented ranges
    /// ([`WarpOptions::validate`], [`ImportanceOptions::validate`]).
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        warp: &WarpOptions,
        importance: &ImportanceOptions,
    ) -> Result<Self, BackendError> {
        warp.validate().map_err(option_error)?;
        importance.validate().map_err(option_error)?;
        if width == 0 || height == 0 {
            return Err(BackendError::InvalidInput("RTW: empty importance map"));
        }
        let cells = width as usize * height as usize;
        let limits = ctx.device.limits();
        if width > MAX_MAP_SIDE
            || height > MAX_MAP_SIDE
            || cells > MAX_MAP_CELLS
            || cells as u64 * 4 > limits.max_storage_buffer_binding_size
            || height > limits.max_compute_workgroups_per_dimension
        {
            return Err(BackendError::InvalidInput(
                "RTW: importance map too large for the device",
            ));
        }
        let device = &ctx.device;
        let storage = |label: &str, bytes: u64, extra: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            })
        };
        let copy = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let axes_bytes = (u64::from(width) + u64::from(height)) * 4;
        let cells_buffer = storage("rtw cells", cells as u64 * 4, copy);
        let maxima = storage("rtw maxima", axes_bytes, copy);
        let counts = storage("rtw counts", 8, copy);
        let scratch = storage("rtw scratch", axes_bytes, wgpu::BufferUsages::empty());
        let density = storage("rtw density", axes_bytes, copy);
        let tables = storage("rtw tables", axes_bytes, copy);
        let state = storage("rtw state", 16, copy);
        let uniform = |label: &str, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let importance_params = uniform(
            "rtw importance params",
            size_of::<ImportanceParamsRaw>() as u64,
        );
        let warp_params = uniform("rtw warp params", size_of::<WarpParamsRaw>() as u64);
        let warp_raw = WarpParamsRaw {
            sizes: [width, height, warp.blur_radius, 0],
            knobs: [warp.floor, warp.temporal, 0.0, 0.0],
            weights: gaussian_weights(warp.blur_radius),
        };
        ctx.queue
            .write_buffer(&warp_params, 0, bytemuck::bytes_of(&warp_raw));

        let pipeline = |source: &str, label: &str, entry: &str| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    // Every workgroup variable is written before it is read (see
                    // "Memory" in the module docs); the tests run without the zeroing.
                    zero_initialize_workgroup_memory: false,
                    ..Default::default()
                },
                cache: None,
            })
        };
        let importance_source = crate::shaders::RTW_IMPORTANCE;
        let splat = pipeline(importance_source, "rtw_importance", "splat");
        let collapse = pipeline(importance_source, "rtw_importance", "collapse");
        let build = pipeline(crate::shaders::RTW_WARP, "rtw_warp", "build_axis");

        fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
            wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            }
        }
        let collapse_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("rtw collapse"),
            layout: &collapse.get_bind_group_layout(0),
            entries: &[
                entry(0, &importance_params),
                entry(3, &cells_buffer),
                entry(4, &maxima),
            ],
        });
        let build_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("rtw build"),
            layout: &build.get_bind_group_layout(0),
            entries: &[
                entry(0, &warp_params),
                entry(1, &maxima),
                entry(2, &scratch),
                entry(3, &density),
                entry(4, &tables),
                entry(5, &state),
            ],
        });
        Ok(Self {
            width,
            height,
            importance: *importance,
            splat,
            collapse,
            build,
            importance_params,
            cells: cells_buffer,
            maxima,
            counts,
            density,
            tables,
            state,
            collapse_group,
            build_group,
        })
    }

    /// Width of the importance map (texels of the `u` table).
    #[must_use]
    pub const fn width(&self) -> u32 {
        self.width
    }

    /// Height of the importance map (texels of the `v` table).
    #[must_use]
    pub const fn height(&self) -> u32 {
        self.height
    }

    /// The warp tables, `width + height` `f32`: the `u` table, then the `v` table
    /// (usage `STORAGE | COPY_SRC | COPY_DST`).
    #[must_use]
    pub const fn tables_buffer(&self) -> &wgpu::Buffer {
        &self.tables
    }

    /// The RTW depth pass's inputs for these tables over `base` (the transform
    /// given to [`GpuRtw::encode`]): the pass copies the tables inside its encoder,
    /// so record it after the build, in the same or a later submission.
    ///
    /// ```no_run
    /// # use glam::{Mat4, Vec3};
    /// # use shadowmap_frustum::{LightDirection, ShadowTransform};
    /// # use shadowmap_rtw::{ImportanceOptions, WarpOptions};
    /// # use shadowmap_wgpu::GpuContext;
    /// # use shadowmap_wgpu::depth::{DepthPassDesc, DepthTechnique, MeshBuffers, ShadowDepthPass};
    /// # use shadowmap_wgpu::rtw::{GpuRtw, RtwGBufferTextures};
    /// # let ctx = GpuContext::new_headless()?;
    /// # let base = ShadowTransform::new(Mat4::IDENTITY, Mat4::IDENTITY, false,
    /// #     LightDirection::Directional(Vec3::NEG_Y));
    /// # let gbuffer = RtwGBufferTextures::from_samples(&ctx, 1, 1, &[None], None)?;
    /// # let mesh = MeshBuffers::from_triangles(&ctx, &[[Vec3::ZERO, Vec3::X, Vec3::Y]])?;
    /// let rtw = GpuRtw::new(&ctx, 64, 64, &WarpOptions::default(), &ImportanceOptions::default())?;
    /// let mut pass = ShadowDepthPass::new(&ctx, &DepthPassDesc::new(DepthTechnique::Rtw, 512))?;
    /// let mut encoder = ctx.device.create_command_encoder(&Default::default());
    /// rtw.encode(&ctx, &mut encoder, &gbuffer.as_gbuffer(), &base)?;
    /// pass.encode(&ctx, &mut encoder, &[&mesh], &rtw.depth_uniforms(&base))?;
    /// ctx.queue.submit([encoder.finish()]);
    /// # Ok::<(), shadowmap_wgpu::BackendError>(())
    /// ```
    #[must_use]
    pub fn depth_uniforms(&self, base: &ShadowTransform) -> crate::depth::DepthUniforms<'_> {
        crate::depth::DepthUniforms::RtwGpuTables {
            raw: crate::uniforms::RtwShadowRaw::from_base(base, self.width, self.height),
            tables: &self.tables,
        }
    }

    /// Forgets the previous frame (no temporal smoothing in the next build), for
    /// camera cuts. Takes effect at the next queue submission.
    pub fn reset_history(&self, ctx: &GpuContext) {
        ctx.queue
            .write_buffer(&self.state, 0, bytemuck::cast_slice(&[0u32; 2]));
    }

    /// Records one frame: clear, splat the G-buffer over `base`, collapse, build the
    /// tables ([`GpuRtw::encode_importance`] then [`GpuRtw::encode_tables`]).
    ///
    /// The base transform goes to a uniform buffer through `queue.write_buffer`, which
    /// lands before the next submission: record at most one `encode` per submission.
    ///
    /// # Errors
    /// As [`GpuRtw::encode_importance`].
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer: &RtwGBuffer<'_>,
        base: &ShadowTransform,
    ) -> Result<(), BackendError> {
        self.encode_importance(ctx, encoder, gbuffer, base)?;
        self.encode_tables(encoder);
        Ok(())
    }

    /// Records the analysis's first half in its own compute pass: clear, splat the
    /// G-buffer over `base` into the importance map, collapse it to column and row
    /// maxima. Follow it with [`GpuRtw::encode_tables`] (the split lets a profiler
    /// time the two halves).
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a non-finite base transform or light, G-buffer
    /// views of another format or of different sizes, or a G-buffer too large to
    /// dispatch.
    pub fn encode_importance(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer: &RtwGBuffer<'_>,
        base: &ShadowTransform,
    ) -> Result<(), BackendError> {
        let light = match base.light {
            LightDirection::Directional(d) => d.extend(0.0),
            LightDirection::Position(p) => p.extend(1.0),
        };
        if !base.uv_from_world.is_finite()
            || !base.light_from_world.is_finite()
            || !light.is_finite()
        {
            return Err(BackendError::InvalidInput(
                "RTW: non-finite base transform or light",
            ));
        }
        let (position, normal) = (
            gbuffer.position_distance.texture(),
            gbuffer.normal_flags.texture(),
        );
        if position.format() != GBUFFER_FORMAT || normal.format() != GBUFFER_FORMAT {
            return Err(BackendError::InvalidInput(
                "RTW: G-buffer must be Rgba32Float",
            ));
        }
        if position.size() != normal.size() {
            return Err(BackendError::InvalidInput(
                "RTW: G-buffer textures differ in size",
            ));
        }
        let (groups_x, groups_y) = (
            position.width().div_ceil(16),
            position.height().div_ceil(16),
        );
        let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension;
        if groups_x > max_groups || groups_y > max_groups {
            return Err(BackendError::InvalidInput(
                "RTW: G-buffer too large to dispatch",
            ));
        }
        let o = &self.importance;
        let raw = ImportanceParamsRaw {
            uv_from_world: base.uv_from_world.to_cols_array_2d(),
            light: light.to_array(),
            distance: [
                o.reference_distance,
                o.min_distance,
                o.distance_exponent,
                o.orientation_weight,
            ],
            edge: [o.edge_weight, 0.0, 0.0, 0.0],
            map_size: [self.width, self.height, 0, 0],
        };
        ctx.queue
            .write_buffer(&self.importance_params, 0, bytemuck::bytes_of(&raw));
        let splat_group = self.splat_group(&ctx.device, gbuffer);
        encoder.clear_buffer(&self.cells, 0, None);
        encoder.clear_buffer(&self.maxima, 0, None);
        encoder.clear_buffer(&self.counts, 0, None);
        let mut pass = compute_pass(encoder, "rtw importance");
        pass.set_pipeline(&self.splat);
        pass.set_bind_group(0, &splat_group, &[]);
        pass.dispatch_workgroups(groups_x, groups_y, 1);
        pass.set_pipeline(&self.collapse);
        pass.set_bind_group(0, &self.collapse_group, &[]);
        pass.dispatch_workgroups(self.height, 1, 1);
        Ok(())
    }

    /// The splat's bind group over this frame's G-buffer views.
    fn splat_group(&self, device: &wgpu::Device, gbuffer: &RtwGBuffer<'_>) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("rtw splat"),
            layout: &self.splat.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.importance_params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(gbuffer.position_distance),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(gbuffer.normal_flags),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: self.cells.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: self.counts.as_entire_binding(),
                },
            ],
        })
    }

    /// Records the analysis's second half in its own compute pass: blur,
    /// normalization, temporal smoothing, floor and the two tables, from the maxima
    /// of the last [`GpuRtw::encode_importance`].
    pub fn encode_tables(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = compute_pass(encoder, "rtw tables");
        pass.set_pipeline(&self.build);
        pass.set_bind_group(0, &self.build_group, &[]);
        pass.dispatch_workgroups(2, 1, 1);
    }

    /// Reads the warp tables of the last submitted build back: `(u table, v table)`.
    /// Blocks until the GPU is done; allocates a staging buffer (a test and debug path).
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_tables(&self, ctx: &GpuContext) -> Result<(Vec<f32>, Vec<f32>), BackendError> {
        self.read_axes(ctx, &self.tables)
    }

    /// Reads the final densities back: `(along u, along v)`, as
    /// [`shadowmap_rtw::WarpMaps::density_x`] / `density_y`.
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_densities(&self, ctx: &GpuContext) -> Result<(Vec<f32>, Vec<f32>), BackendError> {
        self.read_axes(ctx, &self.density)
    }

    /// Reads the importance map back (`width * height` cells, row-major), e.g. to load
    /// it into a [`shadowmap_rtw::ImportanceMap`] with `copy_from_slice`.
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_importance(&self, ctx: &GpuContext) -> Result<Vec<f32>, BackendError> {
        Ok(f32_words(&read_copy(ctx, &self.cells)?))
    }

    /// Reads the sample counts and fallback flags of the last submitted build.
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<GpuRtwStats, BackendError> {
        let counts = read_copy(ctx, &self.counts)?;
        let state = read_copy(ctx, &self.state)?;
        match (counts.as_slice(), state.as_slice()) {
            ([accepted, skipped, ..], [_, _, fallback_u, fallback_v, ..]) => Ok(GpuRtwStats {
                accepted: *accepted,
                skipped: *skipped,
                identity_fallback: [*fallback_u != 0, *fallback_v != 0],
            }),
            _ => Err(BackendError::Readback("short RTW stats".into())),
        }
    }

    fn read_axes(
        &self,
        ctx: &GpuContext,
        buffer: &wgpu::Buffer,
    ) -> Result<(Vec<f32>, Vec<f32>), BackendError> {
        let mut u = f32_words(&read_copy(ctx, buffer)?);
        if u.len() != (self.width + self.height) as usize {
            return Err(BackendError::Readback(
                "RTW tables of the wrong length".into(),
            ));
        }
        let v = u.split_off(self.width as usize);
        Ok((u, v))
    }
}

/// A compute pass without timestamp writes.
fn compute_pass<'e>(encoder: &'e mut wgpu::CommandEncoder, label: &str) -> wgpu::ComputePass<'e> {
    encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    })
}

fn f32_words(words: &[u32]) -> Vec<f32> {
    words.iter().map(|&w| f32::from_bits(w)).collect()
}

/// A whole `COPY_SRC` buffer as `u32` words ([`GpuContext::read_buffer`]).
fn read_copy(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u32>, BackendError> {
    Ok(bytemuck::pod_collect_to_vec(&ctx.read_buffer(buffer)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_normalized_and_packed() {
        for r in [0, 1, 2, 7, MAX_BLUR_RADIUS] {
            let w = gaussian_weights(r);
            let flat: Vec<f64> = w.iter().flatten().map(|&x| f64::from(x)).collect();
            let total = flat[0] + 2.0 * flat[1..].iter().sum::<f64>();
            assert!((total - 1.0).abs() < 1e-6, "radius {r}: {total}");
            assert!(flat[r as usize + 1..].iter().all(|&x| x == 0.0));
            assert!(flat[..=r as usize].windows(2).all(|p| p[0] >= p[1]));
        }
    }

    /// A fresh (or reset) history may hold anything: the first build must not read
    /// it. The density buffer is filled with NaN, then the tables must be the CPU's
    /// first build, with temporal smoothing on.
    #[test]
    fn a_first_build_ignores_whatever_the_history_holds() {
        use glam::{Mat4, Vec3};
        use shadowmap_rtw::{ImportanceMap, WarpMaps};
        let Some(ctx) =
            crate::context::test_context("a_first_build_ignores_whatever_the_history_holds")
        else {
            return;
        };
        // uv = (x, y) for x, y in [0, 1].
        let clip_from_world = Mat4::from_cols_array(&[
            2.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0,
        ]);
        let base = ShadowTransform::new(
            Mat4::IDENTITY,
            clip_from_world,
            false,
            LightDirection::Directional(Vec3::NEG_Z),
        );
        let (width, height) = (37, 29);
        let warp = WarpOptions::default().with_temporal(0.5);
        let importance = ImportanceOptions::default();
        let rtw = GpuRtw::new(&ctx, width, height, &warp, &importance).unwrap();
        let nan = vec![f32::NAN; (width + height) as usize];
        ctx.queue
            .write_buffer(&rtw.density, 0, bytemuck::cast_slice(&nan));
        let samples: Vec<EyeSample> = (0..15)
            .map(|i| EyeSample {
                position: Vec3::new(0.05 + 0.06 * i as f32, 0.9 - 0.05 * i as f32, 0.5),
                normal: Vec3::Z,
                eye_distance: 1.0 + i as f32,
            })
            .collect();
        let texels: Vec<Option<EyeSample>> = samples.iter().copied().map(Some).collect();
        let gbuffer = RtwGBufferTextures::from_samples(&ctx, 5, 3, &texels, None).unwrap();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        rtw.encode(&ctx, &mut encoder, &gbuffer.as_gbuffer(), &base)
            .unwrap();
        ctx.queue.submit([encoder.finish()]);
        let (u, v) = rtw.read_tables(&ctx).unwrap();

        let mut map = ImportanceMap::new(width, height).unwrap();
        map.accumulate_backward(&base, &samples, None, &importance)
            .unwrap();
        let mut cpu = WarpMaps::new(width, height).unwrap();
        cpu.build(&map, &warp).unwrap();
        for (gpu, cpu) in [(&u, cpu.x_table()), (&v, cpu.y_table())] {
            assert!(gpu.iter().all(|t| t.is_finite()), "{gpu:?}");
            let worst = gpu
                .iter()
                .zip(cpu)
                .map(|(g, c)| (g - c).abs())
                .fold(0.0f32, f32::max);
            assert!(worst < 1e-4, "tables differ by {worst}");
        }
        assert!(u.iter().any(|t| t.abs() > 1e-3), "a real warp");
    }

    #[test]
    fn uniform_layouts_match_the_wgsl_structs() {
        // WGSL: mat4x4 (64) + 3 vec4<f32> (48) + vec4<u32> (16).
        assert_eq!(size_of::<ImportanceParamsRaw>(), 128);
        // WGSL: 2 vec4 (32) + array<vec4<f32>, 17> (272).
        assert_eq!(size_of::<WarpParamsRaw>(), 32 + 16 * WEIGHT_VECTORS);
        assert_eq!(WEIGHT_VECTORS, 17);
    }
}
