//! Caster refinement on the GPU: the per-frame caster subdivision of the depth passes
//! that project vertices non-linearly, as a compute pass that writes indirect draws,
//! so the CPU does no per-triangle work per frame. Two rules, each the twin of its
//! CPU reference:
//!
//! - **RTW** (Rosen, *Rectilinear Texture Warping for Fast Adaptive Shadow Mapping*,
//!   I3D 2012), over a matrix base (the uniform or the spot fit), over the kept faces
//!   of a cube map (`cube_rtw`, casters cut to each face's window frustum first) or
//!   over a paraboloid side (`point_rtw`, casters cut at the side's plane):
//!   [`shadowmap_rtw::subdivide_for_rtw_clipped`], its options clamped by the same
//!   [`RtwSubdivision::split_rule`]. Edges are halved; an edge's decision
//!   depends on its two endpoints alone and is symmetric in them, so shared edges
//!   split alike and a conforming mesh stays crack-free. Casters with a vertex the
//!   base cannot map (behind a perspective light, at a paraboloid's light) are
//!   dropped, as on the CPU.
//! - **Paraboloid grid** (Brabec et al., DPSM; IPSM): [`subdivide_triangle`], with the
//!   rule of [`SubdivisionOptions::split_rule`] and
//!   [`shadowmap_paraboloid::DEVIATION_SAMPLES`]: each caster becomes the `n²` pieces
//!   of its barycentric grid, `n` the most segments any of its edges needs on the
//!   side.
//!
//! [`GpuRefine`] holds the casters in a storage buffer uploaded once. Each frame,
//! [`GpuRefine::encode`] records three dispatches of `shaders/refine.wgsl` for the
//! technique of its [`DepthUniforms`] (RTW tables from the CPU, or built on the GPU
//! by [`crate::rtw::GpuRtw`]; one layer per paraboloid side), and
//! [`crate::depth::ShadowDepthPass::encode_refined`] draws each layer with
//! `draw_indirect`:
//!
//! ```text
//! count   one invocation per (caster, layer): its pieces at every cap c in
//!         0..=levels (RTW: c halvings; grid: at most 2^c segments per edge),
//!         added to 64-bit totals per layer and cap
//! choose  one invocation: the finest cap whose total over the layers fits
//!         `capacity`; each layer's draw arguments (its pieces after the previous
//!         layer's) and the stats
//! emit    one invocation per (caster, layer): refine to the chosen cap, reserve
//!         the pieces with one atomic add, write them (9 floats per triangle)
//! ```
//!
//! The GPU draws the CPU's mesh up to `f32` rounding (an RTW edge whose error is
//! within an ulp of the bound, a paraboloid edge whose deviation is): the tests
//! compare the two depth maps. Every caster gets the same cap: when the finest
//! refinement would overflow the capacity, the whole mesh is refined one level
//! coarser (and so on down to the casters themselves), never truncated, and
//! [`RefineStats::overflowed`] says so.
//!
//! The pass uses no workgroup memory and no subgroup operations; invocations meet only
//! in integer atomics, so its output is the same set of triangles whatever the
//! subgroup size or scheduling (only the order within a layer varies, which the depth
//! test's minimum does not see).
//!
//! [`subdivide_triangle`]: shadowmap_paraboloid::subdivide_triangle

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use shadowmap_paraboloid::{ParaboloidUniform, SubdivisionOptions};
use shadowmap_rtw::RtwSubdivision;

use crate::depth::{DepthUniforms, rtw_table_texels, table_buffer};
use crate::uniforms::{ParaboloidLayerRaw, RtwShadowRaw};
use crate::{BackendError, GpuContext, compose};

/// Deepest refinement the pass supports: RTW's `max_segments` up to 1024, as
/// [`RtwSubdivision`] allows (the grid needs at most 8: 256 segments).
pub const MAX_LEVELS: u32 = 10;
/// Layers one refinement feeds (the faces of a cube map; a dual paraboloid has two
/// sides).
pub const MAX_LAYERS: u32 = 6;
/// Counts kept per caster and layer (one per cap `0..=MAX_LEVELS`).
const CAPS: u64 = MAX_LEVELS as u64 + 1;
/// Words of the state buffer (totals per layer and cap, cursors, stats); see the
/// shader.
const STATE_WORDS: u64 = 146;
/// Stats words in the state buffer: the chosen cap, then the pieces of each layer,
/// then the overflow flag.
const CHOSEN_WORD: usize = 138;
const DRAWN_WORD: usize = 139;
const OVERFLOW_WORD: usize = 145;
/// Casters per workgroup of `count` and `emit`.
const WORKGROUP: u32 = 64;
/// Bytes of one refined (or original) triangle: three `vec3<f32>`.
const TRIANGLE_BYTES: u64 = 36;
/// Bytes of one layer's indirect draw arguments.
const DRAW_BYTES: u64 = 16;
/// Shader mode bits: the base is a paraboloid side; the grid rule; casters cut to
/// each layer's window frustum.
const MODE_PARABOLOID: u32 = 1;
const MODE_GRID: u32 = 2;
const MODE_WINDOW: u32 = 4;

/// Byte offset of `layer`'s draw arguments in [`GpuRefine::draw_buffer`].
#[must_use]
pub const fn draw_offset(layer: usize) -> u64 {
    layer as u64 * DRAW_BYTES
}

/// What [`GpuRefine::new`] builds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RefineOptions {
    /// The RTW split rule, as on the CPU ([`shadowmap_rtw::subdivide_for_rtw`]); its
    /// `resolution` is the depth pass's map side.
    pub subdivision: RtwSubdivision,
    /// The paraboloid rule, as on the CPU
    /// ([`shadowmap_paraboloid::subdivide_triangle`]); its `resolution` is the depth
    /// pass's map side.
    pub paraboloid: SubdivisionOptions,
    /// Most triangles the refined buffer holds over all layers, at least the caster
    /// count and at most what the device's storage buffers allow. Default 2^20 (36
    /// MiB): the city block over 256-cell tables into a 2048² map takes 0.72 M.
    pub capacity: u32,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            subdivision: RtwSubdivision::default(),
            paraboloid: SubdivisionOptions::default(),
            capacity: 1 << 20,
        }
    }
}

impl RefineOptions {
    /// With this RTW split rule.
    #[must_use]
    pub const fn with_subdivision(mut self, subdivision: RtwSubdivision) -> Self {
        self.subdivision = subdivision;
        self
    }
    /// With this paraboloid rule.
    #[must_use]
    pub const fn with_paraboloid(mut self, paraboloid: SubdivisionOptions) -> Self {
        self.paraboloid = paraboloid;
        self
    }
    /// Both rules for a map of this many texels per side.
    #[must_use]
    pub const fn with_resolution(mut self, resolution: u32) -> Self {
        self.subdivision = self.subdivision.with_resolution(resolution);
        self.paraboloid = self.paraboloid.with_resolution(resolution);
        self
    }
    /// With room for this many refined triangles.
    #[must_use]
    pub const fn with_capacity(mut self, capacity: u32) -> Self {
        self.capacity = capacity;
        self
    }
}

/// What the last submitted refinement drew ([`GpuRefine::read_stats`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RefineStats {
    /// Triangles written (and drawn), over all layers.
    pub triangles: u32,
    /// Triangles of each layer (layer 0 first in the buffer); 0 past the layers.
    pub layer_triangles: [u32; MAX_LAYERS as usize],
    /// The cap that fitted: RTW halvings per original edge, or `log2` of the grid's
    /// most segments per edge.
    pub levels: u32,
    /// The cap asked for (`ceil(log2(max_segments))` of the rule).
    pub requested_levels: u32,
    /// Whether the full refinement would have overflowed the capacity, so a coarser
    /// one was drawn.
    pub overflowed: bool,
}

/// One layer of WGSL `RefineParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct RefineLayerRaw {
    /// The layer's base in the matrix mode.
    uv_from_world: [[f32; 4]; 4],
    /// Table offsets and texels: `u` offset, `u` texels, `v` offset, `v` texels.
    tables: [u32; 4],
    /// Pieces per unit of base `u` and `v`, error scale; the paraboloid side, or the
    /// window's near plane (`w` of the base).
    rule: [f32; 4],
}

/// WGSL `RefineParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct RefineParamsRaw {
    paraboloid: ParaboloidUniform,
    /// Grid rule: texels per side, tolerance, most segments; unused.
    grid: [f32; 4],
    /// Mode bits, levels, casters, layers.
    sizes: [u32; 4],
    /// Capacity in triangles, unused.
    limits: [u32; 4],
    layers: [RefineLayerRaw; MAX_LAYERS as usize],
}

/// Casters on the GPU and the compute pass that refines them for a depth pass.
#[derive(Debug)]
pub struct GpuRefine {
    options: RefineOptions,
    casters: u32,
    /// Layers and requested levels of the last [`GpuRefine::encode`].
    layers: u32,
    requested_levels: u32,
    count: wgpu::ComputePipeline,
    choose: wgpu::ComputePipeline,
    emit: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    tables: wgpu::Buffer,
    caster_buffer: wgpu::Buffer,
    state: wgpu::Buffer,
    piece_counts: wgpu::Buffer,
    refined: wgpu::Buffer,
    draw: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl GpuRefine {
    /// Uploads the casters (a triangle soup) and compiles the pass.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for no casters, a capacity below the caster
    /// count, paraboloid options out of range, or buffers or dispatches past the
    /// device's limits; [`BackendError::Wgpu`] if wgpu rejects a resource.
    pub fn new(
        ctx: &GpuContext,
        casters: &[[Vec3; 3]],
        options: &RefineOptions,
    ) -> Result<Self, BackendError> {
        let n = u32::try_from(casters.len())
            .map_err(|_| BackendError::InvalidInput("refine: too many casters"))?;
        if n == 0 {
            return Err(BackendError::InvalidInput("refine: no casters"));
        }
        if options.capacity < n || options.capacity > u32::MAX / 3 {
            return Err(BackendError::InvalidInput(
                "refine: capacity below the caster count or above u32::MAX / 3",
            ));
        }
        options
            .paraboloid
            .split_rule()
            .map_err(|_| BackendError::InvalidInput("refine: paraboloid options out of range"))?;
        let limits = ctx.device.limits();
        let largest = u64::from(options.capacity) * TRIANGLE_BYTES;
        let counts = u64::from(n) * u64::from(MAX_LAYERS) * CAPS * 4;
        if largest.max(counts)
            > limits
                .max_storage_buffer_binding_size
                .min(limits.max_buffer_size)
            || n.div_ceil(WORKGROUP) > limits.max_compute_workgroups_per_dimension
        {
            return Err(BackendError::InvalidInput(
                "refine: casters or capacity past the device's limits",
            ));
        }
        ctx.scoped(|ctx| Self::create(ctx, casters, n, options))
    }

    fn create(
        ctx: &GpuContext,
        casters: &[[Vec3; 3]],
        n: u32,
        options: &RefineOptions,
    ) -> Result<Self, BackendError> {
        use wgpu::BufferUsages as U;
        let device = &ctx.device;
        let buffer = |label: &str, bytes: u64, usage: U| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        let params = buffer(
            "shadowmap refine params",
            size_of::<RefineParamsRaw>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let caster_buffer = buffer(
            "shadowmap refine casters",
            u64::from(n) * TRIANGLE_BYTES,
            U::STORAGE | U::COPY_DST,
        );
        ctx.queue
            .write_buffer(&caster_buffer, 0, bytemuck::cast_slice(casters));
        let state = buffer(
            "shadowmap refine state",
            STATE_WORDS * 4,
            U::STORAGE | U::COPY_SRC | U::COPY_DST,
        );
        let piece_counts = buffer(
            "shadowmap refine piece counts",
            u64::from(n) * u64::from(MAX_LAYERS) * CAPS * 4,
            U::STORAGE,
        );
        let refined = buffer(
            "shadowmap refined casters",
            u64::from(options.capacity) * TRIANGLE_BYTES,
            U::STORAGE | U::VERTEX | U::COPY_SRC,
        );
        let draw = buffer(
            "shadowmap refine draw",
            u64::from(MAX_LAYERS) * DRAW_BYTES,
            U::STORAGE | U::INDIRECT | U::COPY_SRC,
        );
        let tables = table_buffer(device, 4);
        let layout = bind_group_layout(device);
        let [count, choose, emit] = pipelines(device, &layout)?;
        let bind_group = make_bind_group(
            device,
            &layout,
            [
                &params,
                &tables,
                &caster_buffer,
                &state,
                &piece_counts,
                &refined,
                &draw,
            ],
        );
        Ok(Self {
            options: *options,
            casters: n,
            layers: 1,
            requested_levels: 0,
            count,
            choose,
            emit,
            bind_group,
            layout,
            params,
            tables,
            caster_buffer,
            state,
            piece_counts,
            refined,
            draw,
        })
    }

    /// What the pass was built with.
    #[must_use]
    pub const fn options(&self) -> &RefineOptions {
        &self.options
    }

    /// Number of casters.
    #[must_use]
    pub const fn caster_count(&self) -> u32 {
        self.casters
    }

    /// Layers of the last [`GpuRefine::encode`] (1 before any).
    #[must_use]
    pub const fn layers(&self) -> u32 {
        self.layers
    }

    /// The refined triangles (a `VERTEX` buffer of `vec3<f32>`, three per triangle;
    /// each layer's after the previous layer's).
    #[must_use]
    pub const fn vertices(&self) -> &wgpu::Buffer {
        &self.refined
    }

    /// The indirect draw arguments, one set per layer at [`draw_offset`]
    /// (`vertex_count, instance_count, first_vertex, first_instance`), written by
    /// the pass.
    #[must_use]
    pub const fn draw_buffer(&self) -> &wgpu::Buffer {
        &self.draw
    }

    /// Records one refinement for the technique of `uniforms`: RTW over a matrix base
    /// ([`DepthUniforms::Rtw`], [`DepthUniforms::RtwGpuTables`]; tables from a slice
    /// are queued, tables in a GPU buffer are copied inside `encoder`, so a build
    /// recorded earlier in it is what the pass sees), RTW over cube faces
    /// ([`DepthUniforms::WarpedCube`]), RTW over paraboloid sides
    /// ([`DepthUniforms::WarpedParaboloid`]) or the paraboloid grid
    /// ([`DepthUniforms::Paraboloid`]). The parameters go through
    /// `queue.write_buffer`: record at most one `encode` per submission.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for matrix uniforms, no layer or more than
    /// [`MAX_LAYERS`], or tables shorter than their sizes (or a table buffer without
    /// `COPY_SRC`).
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &DepthUniforms<'_>,
    ) -> Result<(), BackendError> {
        let mut params = self.params_for(uniforms)?;
        self.upload_tables(ctx, encoder, uniforms)?;
        params.sizes[2] = self.casters;
        params.limits[0] = self.options.capacity;
        self.layers = params.sizes[3];
        self.requested_levels = params.sizes[1];
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        encoder.clear_buffer(&self.state, 0, None);
        let groups = self.casters.div_ceil(WORKGROUP);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadowmap refine"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_pipeline(&self.count);
        pass.dispatch_workgroups(groups, self.layers, 1);
        pass.set_pipeline(&self.choose);
        pass.dispatch_workgroups(1, 1, 1);
        pass.set_pipeline(&self.emit);
        pass.dispatch_workgroups(groups, self.layers, 1);
        Ok(())
    }

    /// The parameters for `uniforms` (casters and capacity filled in by the caller).
    fn params_for(&self, uniforms: &DepthUniforms<'_>) -> Result<RefineParamsRaw, BackendError> {
        let mut params = RefineParamsRaw::zeroed();
        match uniforms {
            DepthUniforms::Rtw { raw, .. } | DepthUniforms::RtwGpuTables { raw, .. } => {
                let rule = self.rtw_layer(raw, &self.options.subdivision, 0.0);
                params.sizes = [0, rule.1, 0, 1];
                params.layers[0] = rule.0;
            }
            DepthUniforms::WarpedCube { layers, .. } => {
                params.sizes = [MODE_WINDOW, 0, 0, checked_layers(layers.len())?];
                for (slot, raw) in params.layers.iter_mut().zip(layers.iter()) {
                    // As eval's reference: each face split for its own map side,
                    // with enough pieces an edge to cross its whole window.
                    let [u, v, ..] = raw.sizes;
                    let side =
                        raw.layer[0].max(raw.layer[1]) * self.options.subdivision.resolution as f32;
                    let subdivision = self
                        .options
                        .subdivision
                        .with_resolution(side.round().max(1.0) as u32)
                        .with_segments_for_extent(1.0, u.max(v) as usize);
                    let (layer, levels) = self.rtw_layer(raw, &subdivision, raw.layer[2]);
                    *slot = layer;
                    params.sizes[1] = params.sizes[1].max(levels);
                }
            }
            DepthUniforms::Paraboloid(layers) => {
                let rule = self
                    .options
                    .paraboloid
                    .split_rule()
                    .map_err(|_| BackendError::InvalidInput("refine: paraboloid options"))?;
                paraboloid_params(&mut params, layers, MODE_GRID, rule.levels)?;
                params.grid = [
                    rule.resolution as f32,
                    rule.tolerance_texels as f32,
                    rule.max_segments as f32,
                    0.0,
                ];
            }
            DepthUniforms::WarpedParaboloid { layers, .. } => {
                // As eval's reference: enough pieces an edge to cross the side's
                // whole disc (diameter `1 / zoom` of base texture space) in pieces
                // of the span bound.
                let zoom = layers
                    .first()
                    .map_or(1.0, |l| l.map.far_zoom_reversed_dual[1]);
                let subdivision = |layer: &ParaboloidLayerRaw| {
                    let [_, u, _, v] = layer.warp;
                    self.options
                        .subdivision
                        .with_segments_for_extent(1.0 / f64::from(zoom), u.max(v) as usize)
                };
                let levels = layers
                    .iter()
                    .map(|l| subdivision(l).split_rule(1, 1).levels)
                    .max()
                    .unwrap_or(0);
                paraboloid_params(&mut params, layers, 0, levels)?;
                for (slot, layer) in params.layers.iter_mut().zip(layers.iter()) {
                    let [_, u, _, v] = layer.warp;
                    let rule = subdivision(layer).split_rule(u as usize, v as usize);
                    slot.tables = layer.warp;
                    slot.rule = [
                        rule.pieces.x as f32,
                        rule.pieces.y as f32,
                        rule.error_scale as f32,
                        layer.side[0],
                    ];
                }
            }
            DepthUniforms::Matrix(_) => {
                return Err(BackendError::InvalidInput(
                    "refine: matrix techniques need no refinement",
                ));
            }
        }
        Ok(params)
    }

    /// One layer of RTW over the matrix base of `raw` (its tables at their offsets)
    /// with the split rule of `subdivision`, `near` in the rule's last slot; and the
    /// rule's levels.
    fn rtw_layer(
        &self,
        raw: &RtwShadowRaw,
        subdivision: &RtwSubdivision,
        near: f32,
    ) -> (RefineLayerRaw, u32) {
        let [u, v, ..] = raw.sizes;
        let rule = subdivision.split_rule(u as usize, v as usize);
        let layer = RefineLayerRaw {
            uv_from_world: raw.uv_from_world,
            tables: [raw.table_offsets[0], u, raw.table_offsets[1], v],
            rule: [
                rule.pieces.x as f32,
                rule.pieces.y as f32,
                rule.error_scale as f32,
                near,
            ],
        };
        (layer, rule.levels)
    }

    /// Brings the tables of `uniforms` into the pass's table buffer (queued from a
    /// slice, copied inside `encoder` from a GPU buffer).
    fn upload_tables(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &DepthUniforms<'_>,
    ) -> Result<(), BackendError> {
        if let DepthUniforms::RtwGpuTables { raw, tables } = uniforms {
            let bytes = (rtw_table_texels(raw).max(1) * 4) as u64;
            if tables.size() < bytes || !tables.usage().contains(wgpu::BufferUsages::COPY_SRC) {
                return Err(BackendError::InvalidInput(
                    "RTW table buffer shorter than its sizes or without COPY_SRC",
                ));
            }
            self.grow_tables(ctx, bytes);
            encoder.copy_buffer_to_buffer(tables, 0, &self.tables, 0, bytes);
            return Ok(());
        }
        let Some(tables) = uniforms.cpu_tables()? else {
            return Ok(());
        };
        let bytes: &[u8] = bytemuck::cast_slice(tables);
        self.grow_tables(ctx, bytes.len() as u64);
        ctx.queue.write_buffer(&self.tables, 0, bytes);
        Ok(())
    }

    /// Reads the stats of the last submitted refinement. Blocks until the GPU is
    /// done (a test and debug path).
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<RefineStats, BackendError> {
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&self.state)?);
        let word = |i: usize| {
            words
                .get(i)
                .copied()
                .ok_or_else(|| BackendError::Readback("short refine stats".into()))
        };
        let mut layer_triangles = [0; MAX_LAYERS as usize];
        for (layer, drawn) in layer_triangles.iter_mut().enumerate() {
            *drawn = word(DRAWN_WORD + layer)?;
        }
        Ok(RefineStats {
            triangles: layer_triangles.iter().sum(),
            layer_triangles,
            levels: word(CHOSEN_WORD)?,
            requested_levels: self.requested_levels,
            overflowed: word(OVERFLOW_WORD)? != 0,
        })
    }

    /// Reads the refined triangles of the last submitted refinement, every layer's
    /// in layer order ([`RefineStats::layer_triangles`] splits them; a test and debug
    /// path: it allocates and blocks).
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_triangles(&self, ctx: &GpuContext) -> Result<Vec<[Vec3; 3]>, BackendError> {
        let drawn = self.read_stats(ctx)?.triangles as usize;
        let floats: Vec<f32> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&self.refined)?);
        Ok(floats
            .chunks_exact(9)
            .take(drawn)
            .map(|t| {
                [
                    Vec3::new(t[0], t[1], t[2]),
                    Vec3::new(t[3], t[4], t[5]),
                    Vec3::new(t[6], t[7], t[8]),
                ]
            })
            .collect())
    }

    /// The table buffer, grown (with a new bind group) to hold `bytes`.
    fn grow_tables(&mut self, ctx: &GpuContext, bytes: u64) {
        if self.tables.size() < bytes {
            self.tables = table_buffer(&ctx.device, bytes);
            self.bind_group = make_bind_group(
                &ctx.device,
                &self.layout,
                [
                    &self.params,
                    &self.tables,
                    &self.caster_buffer,
                    &self.state,
                    &self.piece_counts,
                    &self.refined,
                    &self.draw,
                ],
            );
        }
    }
}

/// A layer count of one refinement: 1 to [`MAX_LAYERS`].
fn checked_layers(count: usize) -> Result<u32, BackendError> {
    u32::try_from(count)
        .ok()
        .filter(|n| (1..=MAX_LAYERS).contains(n))
        .ok_or(BackendError::InvalidInput("refine: one to six layers"))
}

/// The paraboloid base of `layers` (one map, one side per layer) into `params`.
fn paraboloid_params(
    params: &mut RefineParamsRaw,
    layers: &[ParaboloidLayerRaw],
    mode: u32,
    levels: u32,
) -> Result<(), BackendError> {
    let count = u32::try_from(layers.len()).unwrap_or(u32::MAX);
    let Some(first) = layers.first().filter(|_| count <= 2) else {
        return Err(BackendError::InvalidInput(
            "refine: one or two paraboloid layers",
        ));
    };
    params.paraboloid = first.map;
    params.sizes = [MODE_PARABOLOID | mode, levels, 0, count];
    for (slot, layer) in params.layers.iter_mut().zip(layers) {
        slot.rule[3] = layer.side[0];
    }
    Ok(())
}

/// The `count`, `choose` and `emit` pipelines of `refine.wgsl` (its shared functions
/// composed in) over `layout`.
fn pipelines(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
) -> Result<[wgpu::ComputePipeline; 3], BackendError> {
    let source = compose::refine()?;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap refine"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadowmap refine"),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    Ok(["count", "choose", "emit"].map(|entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    }))
}

/// Binding 0 the parameters, 1 the tables, 2 the casters (read-only), 3 the state,
/// 4 the per-caster counts, 5 the refined triangles, 6 the draw arguments.
fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entry =
        |binding: u32, ty: wgpu::BufferBindingType, bytes: u64| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: NonZeroU64::new(bytes),
            },
            count: None,
        };
    let read = wgpu::BufferBindingType::Storage { read_only: true };
    let write = wgpu::BufferBindingType::Storage { read_only: false };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadowmap refine"),
        entries: &[
            entry(
                0,
                wgpu::BufferBindingType::Uniform,
                size_of::<RefineParamsRaw>() as u64,
            ),
            entry(1, read, 4),
            entry(2, read, 4),
            entry(3, write, STATE_WORDS * 4),
            entry(4, write, 4),
            entry(5, write, 4),
            entry(6, write, u64::from(MAX_LAYERS) * DRAW_BYTES),
        ],
    })
}

/// The bind group of [`bind_group_layout`]: `buffers[i]` at binding `i`.
fn make_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: [&wgpu::Buffer; 7],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .zip(0..)
        .map(|(buffer, binding)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadowmap refine"),
        layout,
        entries: &entries,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `RefineParamsRaw` has the span naga computes for WGSL `RefineParams`, and the
    /// shader's limits are this module's.
    #[test]
    fn params_and_limits_match_the_shader() {
        let source = compose::refine().unwrap();
        let module = naga::front::wgsl::parse_str(&source).expect("parses");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("layout");
        let span = module
            .types
            .iter()
            .find(|(_, ty)| ty.name.as_deref() == Some("RefineParams"))
            .map(|(handle, _)| layouter[handle].size)
            .expect("RefineParams");
        assert_eq!(span as usize, size_of::<RefineParamsRaw>());
        for (name, value) in [
            ("MAX_LEVELS", u64::from(MAX_LEVELS)),
            ("CAPS", CAPS),
            ("MAX_LAYERS", u64::from(MAX_LAYERS)),
            ("CHOSEN", CHOSEN_WORD as u64),
            ("DRAWN", DRAWN_WORD as u64),
            ("OVERFLOW", OVERFLOW_WORD as u64),
            ("MODE_PARABOLOID", u64::from(MODE_PARABOLOID)),
            ("MODE_GRID", u64::from(MODE_GRID)),
            ("MODE_WINDOW", u64::from(MODE_WINDOW)),
        ] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(source.contains(&line), "shader lacks `{line}`");
        }
        let samples = shadowmap_paraboloid::DEVIATION_SAMPLES.map(|f| format!("{f:?}"));
        let line = format!(
            "const DEVIATION_SAMPLES = array<f32, 3>({});",
            samples.join(", ")
        );
        assert!(source.contains(&line), "shader lacks `{line}`");
        assert!(source.contains(&format!("array<u32, {}>", 4 * MAX_LAYERS)));
        assert!(source.contains(&format!("array<atomic<u32>, {STATE_WORDS}>")));
        assert!(source.contains(&format!("@workgroup_size({WORKGROUP})")));
    }
}
