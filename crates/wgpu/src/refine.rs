//! RTW caster refinement on the GPU: the per-frame caster subdivision of RTW's depth
//! pass (Rosen, *Rectilinear Texture Warping for Fast Adaptive Shadow Mapping*, I3D
//! 2012) as a compute pass that writes an indirect draw, so the CPU does no
//! per-triangle work per frame.
//!
//! [`GpuRefine`] holds the casters in a storage buffer uploaded once. Each frame,
//! [`GpuRefine::encode`] records three dispatches of `shaders/rtw_refine.wgsl` against
//! the current warp tables (from the CPU, or built on the GPU by
//! [`crate::rtw::GpuRtw`]), and [`crate::depth::ShadowDepthPass::encode_refined`]
//! draws the result with `draw_indirect`:
//!
//! ```text
//! count   one invocation per caster: refine to `levels` halvings (the rule of
//!         shadowmap_rtw::subdivide_for_rtw, evaluated in f32), count the pieces
//!         at every cap c in 0..=levels, add them to 64-bit totals per cap
//! choose  one invocation: the finest cap whose total fits `capacity`; write
//!         the draw arguments (3 x pieces vertices) and the stats
//! emit    one invocation per caster: refine to the chosen cap, reserve its pieces
//!         with one atomic add, write them (9 floats per triangle)
//! ```
//!
//! The split rule, the recursion and the pieces are those of the CPU reference
//! [`shadowmap_rtw::subdivide_for_rtw`] (a WGSL twin, with the options clamped by the
//! same [`RtwSubdivision::split_rule`]): the GPU draws the same mesh as the CPU path,
//! up to `f32` rounding where an edge's error is within an ulp of the bound. An edge's
//! decision depends on its two endpoints alone and is symmetric in them, so shared
//! edges split alike and a conforming mesh stays crack-free. Every caster gets the
//! same cap: when the finest refinement would overflow the capacity, the whole
//! mesh is refined one level coarser (and so on down to the casters themselves),
//! never truncated, and [`RefineStats::overflowed`] says so.
//!
//! Casters with a vertex the base cannot map (behind a perspective light) or with
//! non-finite coordinates are drawn unsplit, as on the CPU.

use std::num::NonZeroU64;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use shadowmap_rtw::RtwSubdivision;

use crate::depth::{DepthUniforms, rtw_table_texels, table_buffer};
use crate::uniforms::RtwShadowRaw;
use crate::{BackendError, GpuContext, compose};

/// Deepest refinement the pass supports: `max_segments` up to 1024, as
/// [`RtwSubdivision`] allows.
pub const MAX_LEVELS: u32 = 10;
/// Counts kept per caster (one per cap `0..=MAX_LEVELS`).
const CAPS: u64 = MAX_LEVELS as u64 + 1;
/// Words of the state buffer (totals per cap, cursor, stats); see the shader.
const STATE_WORDS: u64 = 32;
/// First stats word in the state buffer: chosen cap, pieces drawn, overflow flag.
const STATS_WORD: usize = 23;
/// Casters per workgroup of `count` and `emit`.
const WORKGROUP: u32 = 64;
/// Bytes of one refined (or original) triangle: three `vec3<f32>`.
const TRIANGLE_BYTES: u64 = 36;

/// What [`GpuRefine::new`] builds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RefineOptions {
    /// The split rule, as on the CPU ([`shadowmap_rtw::subdivide_for_rtw`]); its
    /// `resolution` is the depth pass's map side.
    pub subdivision: RtwSubdivision,
    /// Most triangles the refined buffer holds, at least the caster count and at
    /// most what the device's storage buffers allow. Default 2^20 (36 MiB): the
    /// city block over 256-cell tables into a 2048² map takes 0.72 M.
    pub capacity: u32,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            subdivision: RtwSubdivision::default(),
            capacity: 1 << 20,
        }
    }
}

impl RefineOptions {
    /// With this split rule.
    #[must_use]
    pub const fn with_subdivision(mut self, subdivision: RtwSubdivision) -> Self {
        self.subdivision = subdivision;
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
    /// Triangles written (and drawn).
    pub triangles: u32,
    /// Halvings per original edge that fitted the capacity.
    pub levels: u32,
    /// Halvings asked for (`ceil(log2(max_segments))`).
    pub requested_levels: u32,
    /// Whether the full refinement would have overflowed the capacity, so a coarser
    /// one was drawn.
    pub overflowed: bool,
}

/// WGSL `RefineParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct RefineParamsRaw {
    uv_from_world: [[f32; 4]; 4],
    /// Pieces per unit of base `u` and `v`, error scale, unused.
    rule: [f32; 4],
    /// Table texels `u`, `v`, halvings, casters.
    sizes: [u32; 4],
    /// Capacity in triangles, unused.
    limits: [u32; 4],
}

/// Casters on the GPU and the compute pass that refines them for RTW's depth pass.
#[derive(Debug)]
pub struct GpuRefine {
    options: RefineOptions,
    casters: u32,
    levels: u32,
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
    /// count, or buffers or dispatches past the device's limits;
    /// [`BackendError::Wgpu`] if wgpu rejects a resource.
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
        let limits = ctx.device.limits();
        let largest = u64::from(options.capacity) * TRIANGLE_BYTES;
        let counts = u64::from(n) * CAPS * 4;
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
            u64::from(n) * CAPS * 4,
            U::STORAGE,
        );
        let refined = buffer(
            "shadowmap refined casters",
            u64::from(options.capacity) * TRIANGLE_BYTES,
            U::STORAGE | U::VERTEX | U::COPY_SRC,
        );
        let draw = buffer(
            "shadowmap refine draw",
            16,
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
            levels: options.subdivision.split_rule(1, 1).levels,
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

    /// The refined triangles (a `VERTEX` buffer of `vec3<f32>`, three per triangle).
    #[must_use]
    pub const fn vertices(&self) -> &wgpu::Buffer {
        &self.refined
    }

    /// The indirect draw arguments (`vertex_count, instance_count, first_vertex,
    /// first_instance`), written by the pass.
    #[must_use]
    pub const fn draw_buffer(&self) -> &wgpu::Buffer {
        &self.draw
    }

    /// Records one refinement against the base and tables of `uniforms` (an RTW
    /// [`DepthUniforms`]: tables from a slice are queued, tables in a GPU buffer are
    /// copied inside `encoder`, so a build recorded earlier in it is what the pass
    /// sees). The parameters go through `queue.write_buffer`: record at most one
    /// `encode` per submission.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for uniforms of another technique or tables
    /// shorter than their sizes (or a table buffer without `COPY_SRC`).
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &DepthUniforms<'_>,
    ) -> Result<(), BackendError> {
        let raw = self.upload_tables(ctx, encoder, uniforms)?;
        let rule = self
            .options
            .subdivision
            .split_rule(raw.sizes[0] as usize, raw.sizes[1] as usize);
        let params = RefineParamsRaw {
            uv_from_world: raw.uv_from_world,
            rule: [
                rule.pieces.x as f32,
                rule.pieces.y as f32,
                rule.error_scale as f32,
                0.0,
            ],
            sizes: [raw.sizes[0], raw.sizes[1], rule.levels, self.casters],
            limits: [self.options.capacity, 0, 0, 0],
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        encoder.clear_buffer(&self.state, 0, None);
        let groups = self.casters.div_ceil(WORKGROUP);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadowmap rtw refine"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_pipeline(&self.count);
        pass.dispatch_workgroups(groups, 1, 1);
        pass.set_pipeline(&self.choose);
        pass.dispatch_workgroups(1, 1, 1);
        pass.set_pipeline(&self.emit);
        pass.dispatch_workgroups(groups, 1, 1);
        Ok(())
    }

    /// Brings the RTW tables of `uniforms` into the pass's table buffer (queued from
    /// a slice, copied inside `encoder` from a GPU buffer) and returns their block.
    fn upload_tables<'u>(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &'u DepthUniforms<'_>,
    ) -> Result<&'u RtwShadowRaw, BackendError> {
        match uniforms {
            DepthUniforms::Rtw { raw, tables } => {
                if tables.len() < rtw_table_texels(raw).max(1) {
                    return Err(BackendError::InvalidInput(
                        "RTW tables shorter than their sizes",
                    ));
                }
                let bytes: &[u8] = bytemuck::cast_slice(tables);
                self.grow_tables(ctx, bytes.len() as u64);
                ctx.queue.write_buffer(&self.tables, 0, bytes);
                Ok(raw)
            }
            DepthUniforms::RtwGpuTables { raw, tables } => {
                let bytes = (rtw_table_texels(raw).max(1) * 4) as u64;
                if tables.size() < bytes || !tables.usage().contains(wgpu::BufferUsages::COPY_SRC) {
                    return Err(BackendError::InvalidInput(
                        "RTW table buffer shorter than its sizes or without COPY_SRC",
                    ));
                }
                self.grow_tables(ctx, bytes);
                encoder.copy_buffer_to_buffer(tables, 0, &self.tables, 0, bytes);
                Ok(raw)
            }
            DepthUniforms::Matrix(_) | DepthUniforms::Paraboloid(_) => {
                Err(BackendError::InvalidInput("refine: uniforms are not RTW's"))
            }
        }
    }

    /// Reads the stats of the last submitted refinement. Blocks until the GPU is
    /// done (a test and debug path).
    ///
    /// # Errors
    /// [`BackendError::Readback`].
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<RefineStats, BackendError> {
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&self.state)?);
        match words.get(STATS_WORD..STATS_WORD + 3) {
            Some(&[levels, triangles, overflowed]) => Ok(RefineStats {
                triangles,
                levels,
                requested_levels: self.levels,
                overflowed: overflowed != 0,
            }),
            _ => Err(BackendError::Readback("short refine stats".into())),
        }
    }

    /// Reads the refined triangles of the last submitted refinement (a test and
    /// debug path: it allocates and blocks).
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

/// The `count`, `choose` and `emit` pipelines of `rtw_refine.wgsl` (its table
/// sampler composed in) over `layout`.
fn pipelines(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
) -> Result<[wgpu::ComputePipeline; 3], BackendError> {
    let source = compose::rtw_refine()?;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("shadowmap rtw refine"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadowmap rtw refine"),
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
        label: Some("shadowmap rtw refine"),
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
            entry(6, write, 16),
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
        label: Some("shadowmap rtw refine"),
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
        let source = compose::rtw_refine().unwrap();
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
            ("CHOSEN", STATS_WORD as u64),
        ] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(source.contains(&line), "shader lacks `{line}`");
        }
        assert!(source.contains(&format!("array<atomic<u32>, {STATE_WORDS}>")));
        assert!(source.contains(&format!("@workgroup_size({WORKGROUP})")));
    }
}
