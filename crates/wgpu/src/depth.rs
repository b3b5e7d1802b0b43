//! Shadow depth passes: matrix techniques (uniform, cascades, LiSPSM, XPSM, TSM),
//! paraboloid (front and back layers, optionally warped by RTW tables per side), and
//! RTW (warped vertices over an orthographic or perspective base). The paraboloid and
//! RTW passes draw casters subdivided on the CPU ([`ShadowDepthPass::encode`]) or
//! refined on the GPU and drawn indirectly ([`ShadowDepthPass::encode_refined`]).
//!
//! One [`ShadowDepthPass`] owns a `Depth32Float` 2-D array texture (one layer per
//! cascade or paraboloid side), its pipeline, and a uniform buffer with one block per
//! layer (bound with a dynamic offset). Depth runs `[0, 1]` (cleared to 1, test
//! `Less`) or reversed (cleared to 0, test `Greater`); an optional slope-scaled bias
//! is wgpu's [`wgpu::DepthBiasState`]. Both faces of every triangle cast.
//!
//! The paraboloid and RTW vertex shaders snap their projected positions to the
//! rasterizer's 1/256-pixel grid (the pass writes its resolution into the block):
//! where those maps compress, casters become slivers with depth slopes near one per
//! texel, and a rasterizer that derives the depth plane from unsnapped positions
//! (Mesa's llvmpipe) would otherwise store depths up to `slope / 512` away from one
//! that uses the snapped positions (the reference rasterizer of `shadowmap-eval`).
//!
//! ```no_run
//! use glam::{Mat4, Vec3};
//! use shadowmap_frustum::{LightDirection, ShadowTransform};
//! use shadowmap_wgpu::depth::{DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, ShadowDepthPass};
//! use shadowmap_wgpu::{GpuContext, uniforms::ToRaw};
//!
//! let ctx = GpuContext::new_headless()?;
//! let mesh = MeshBuffers::from_triangles(&ctx, &[[Vec3::ZERO, Vec3::X, Vec3::Y]])?;
//! let light = ShadowTransform::new(Mat4::IDENTITY, Mat4::IDENTITY, false, LightDirection::Directional(Vec3::NEG_Z));
//! let mut pass = ShadowDepthPass::new(&ctx, &DepthPassDesc::new(DepthTechnique::Matrix, 256))?;
//! let mut encoder = ctx.device.create_command_encoder(&Default::default());
//! pass.encode(&ctx, &mut encoder, &[&mesh], &DepthUniforms::Matrix(&[light.to_raw()]))?;
//! ctx.queue.submit([encoder.finish()]);
//! let depth: Vec<f32> = pass.readback_depth(&ctx)?;
//! assert_eq!(depth.len(), 256 * 256);
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use std::num::NonZeroU64;

use crate::uniforms::{MatrixShadowRaw, ParaboloidLayerRaw, RtwShadowRaw};

mod atlas;
use crate::{BackendError, GpuContext, compose, shaders};

/// The caster subdivision of RTW's depth pass lives beside the warp tables in
/// `shadowmap-rtw` (one algorithm for the CPU reference and this backend).
pub use shadowmap_rtw::{RtwSubdivision, subdivide_for_rtw};

pub use crate::mesh::MeshBuffers;

/// The depth format of every shadow map.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Which depth pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DepthTechnique {
    /// A matrix per layer: uniform, cascades, LiSPSM, XPSM, TSM.
    Matrix,
    /// Paraboloid projection per vertex; layer 0 front, layer 1 back.
    Paraboloid,
    /// Base projection, then each axis through the RTW warp tables.
    Rtw,
}

/// Rasterizer depth bias (wgpu's [`wgpu::DepthBiasState`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthBias {
    /// Constant bias in units of the smallest resolvable depth difference.
    pub constant: i32,
    /// Bias per unit of depth slope (`max(|dz/dx|, |dz/dy|)`, per texel).
    pub slope_scale: f32,
    /// Largest bias magnitude (0: no clamp).
    pub clamp: f32,
}

/// What [`ShadowDepthPass::new`] builds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct DepthPassDesc {
    /// Which pass.
    pub technique: DepthTechnique,
    /// Texels per side, in `1..=max_texture_dimension_2d`.
    pub resolution: u32,
    /// Array layers (cascades, paraboloid sides), in `1..=max_texture_array_layers`.
    pub layers: u32,
    /// Reversed-Z: clear to 0, keep the greater depth.
    pub reversed_z: bool,
    /// Rasterizer bias. With reversed-Z give it the opposite sign.
    pub bias: DepthBias,
}

impl DepthPassDesc {
    /// One layer, standard depth, no bias.
    #[must_use]
    pub const fn new(technique: DepthTechnique, resolution: u32) -> Self {
        Self {
            technique,
            resolution,
            layers: 1,
            reversed_z: false,
            bias: DepthBias {
                constant: 0,
                slope_scale: 0.0,
                clamp: 0.0,
            },
        }
    }
    /// With this many layers.
    #[must_use]
    pub const fn with_layers(mut self, layers: u32) -> Self {
        self.layers = layers;
        self
    }
    /// With reversed-Z on or off.
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }
    /// With this rasterizer bias.
    #[must_use]
    pub const fn with_bias(mut self, bias: DepthBias) -> Self {
        self.bias = bias;
        self
    }
}

/// The per-frame inputs of a depth pass, one block per layer.
#[derive(Clone, Copy, Debug)]
pub enum DepthUniforms<'a> {
    /// One matrix block per layer (a cascade set: [`crate::uniforms::cascade_layers`]).
    Matrix(&'a [MatrixShadowRaw]),
    /// One block per side ([`crate::uniforms::paraboloid_layers`]).
    Paraboloid(&'a [ParaboloidLayerRaw]),
    /// One block per side whose `warp` places the side's RTW tables in `tables`
    /// (RTW over the paraboloid, [`crate::uniforms::warped_paraboloid`]).
    WarpedParaboloid {
        /// One block per side.
        layers: &'a [ParaboloidLayerRaw],
        /// Every side's tables.
        tables: &'a [f32],
    },
    /// The base projection and the tables (`u` then `v`,
    /// [`RtwShadowRaw::tables`]); one layer.
    Rtw {
        /// The block.
        raw: RtwShadowRaw,
        /// The `u` table followed by the `v` table.
        tables: &'a [f32],
    },
    /// The base projection and tables already on the GPU, e.g.
    /// [`crate::rtw::GpuRtw::tables_buffer`] (see
    /// [`crate::rtw::GpuRtw::depth_uniforms`]): the pass copies them into its own
    /// table buffer inside the encoder, so a build recorded earlier in the same
    /// encoder is what the pass sees.
    RtwGpuTables {
        /// The block (`sizes.x + sizes.y` tables texels, `u` then `v`).
        raw: RtwShadowRaw,
        /// A buffer with `COPY_SRC` usage holding at least `sizes.x + sizes.y` `f32`.
        tables: &'a wgpu::Buffer,
    },
    /// RTW over the kept faces of a cube map ([`crate::uniforms::warped_cube`]): one
    /// block per face (its perspective base, where its tables start in `tables`,
    /// its layer's corner and near plane), one layer each. Refined casters are cut
    /// to each face's window frustum first.
    WarpedCube {
        /// One block per kept face, at most [`crate::refine::MAX_LAYERS`].
        layers: &'a [RtwShadowRaw],
        /// Every face's tables.
        tables: &'a [f32],
    },
}

impl DepthUniforms<'_> {
    fn technique(&self) -> DepthTechnique {
        match self {
            Self::Matrix(_) => DepthTechnique::Matrix,
            Self::Paraboloid(_) | Self::WarpedParaboloid { .. } => DepthTechnique::Paraboloid,
            Self::Rtw { .. } | Self::RtwGpuTables { .. } | Self::WarpedCube { .. } => {
                DepthTechnique::Rtw
            }
        }
    }

    /// The warp tables given as a slice (RTW, cube faces, paraboloid sides), checked
    /// against the offsets and sizes the blocks read; `None` for the techniques
    /// without tables or with tables in a GPU buffer.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for tables shorter than a block reads.
    pub(crate) fn cpu_tables(&self) -> Result<Option<&[f32]>, BackendError> {
        let (tables, needed) = match self {
            Self::Rtw { raw, tables } => (*tables, rtw_table_texels(raw)),
            Self::WarpedCube { layers, tables } => (
                *tables,
                layers.iter().map(rtw_table_texels).max().unwrap_or(0),
            ),
            Self::WarpedParaboloid { layers, tables } => (
                *tables,
                layers
                    .iter()
                    .map(|l| warp_table_end(&l.warp))
                    .max()
                    .unwrap_or(0),
            ),
            Self::Matrix(_) | Self::Paraboloid(_) | Self::RtwGpuTables { .. } => return Ok(None),
        };
        if tables.len() < needed.max(1) {
            return Err(BackendError::InvalidInput(
                "warp tables shorter than their blocks' offsets and sizes",
            ));
        }
        Ok(Some(tables))
    }

    fn layer_count(&self) -> usize {
        match self {
            Self::Matrix(m) => m.len(),
            Self::Paraboloid(p) | Self::WarpedParaboloid { layers: p, .. } => p.len(),
            Self::Rtw { .. } | Self::RtwGpuTables { .. } => 1,
            Self::WarpedCube { layers, .. } => layers.len(),
        }
    }

    /// The block of `layer`; paraboloid and RTW blocks get the map resolution
    /// (`side.y`, `sizes.w`) for the vertex shader's subpixel snap.
    fn layer_bytes(&self, layer: usize, resolution: u32) -> Vec<u8> {
        match self {
            Self::Matrix(m) => bytemuck::bytes_of(&m[layer]).to_vec(),
            Self::Paraboloid(p) | Self::WarpedParaboloid { layers: p, .. } => {
                let mut raw = p[layer];
                raw.side[1] = resolution as f32;
                bytemuck::bytes_of(&raw).to_vec()
            }
            Self::Rtw { raw, .. } | Self::RtwGpuTables { raw, .. } => {
                let mut raw = *raw;
                raw.sizes[3] = resolution;
                bytemuck::bytes_of(&raw).to_vec()
            }
            Self::WarpedCube { layers, .. } => {
                let mut raw = layers[layer];
                raw.sizes[3] = resolution;
                bytemuck::bytes_of(&raw).to_vec()
            }
        }
    }
}

/// A shadow depth pass and its `Depth32Float` array texture.
#[derive(Debug)]
pub struct ShadowDepthPass {
    desc: DepthPassDesc,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    slot: u64,
    block: u64,
    tables: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
    texture: wgpu::Texture,
    array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
    /// The tiles' caster indices of an atlas pass ([`ShadowDepthPass::encode_tiles`]).
    tile_indices: Option<wgpu::Buffer>,
}

/// Bytes reserved per layer in the uniform buffer (before alignment).
const BLOCK_BYTES: u64 = 256;

impl ShadowDepthPass {
    /// Creates the texture and the pipeline.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a resolution or layer count of 0 or above the
    /// device's limits, or more RTW layers than one refinement feeds
    /// ([`crate::refine::MAX_LAYERS`]);
    /// [`BackendError::Wgpu`] if wgpu rejects a resource.
    pub fn new(ctx: &GpuContext, desc: &DepthPassDesc) -> Result<Self, BackendError> {
        let limits = ctx.device.limits();
        if desc.resolution == 0 || desc.resolution > limits.max_texture_dimension_2d {
            return Err(BackendError::InvalidInput(
                "shadow-map resolution out of range",
            ));
        }
        if desc.layers == 0 || desc.layers > limits.max_texture_array_layers {
            return Err(BackendError::InvalidInput("layer count out of range"));
        }
        if desc.technique == DepthTechnique::Rtw && desc.layers > crate::refine::MAX_LAYERS {
            return Err(BackendError::InvalidInput(
                "RTW renders at most one layer per cube face",
            ));
        }
        if !(desc.bias.slope_scale.is_finite() && desc.bias.clamp.is_finite()) {
            return Err(BackendError::InvalidInput("non-finite depth bias"));
        }
        ctx.scoped(|ctx| Self::create(ctx, desc))
    }

    fn create(ctx: &GpuContext, desc: &DepthPassDesc) -> Result<Self, BackendError> {
        let device = &ctx.device;
        let align = u64::from(device.limits().min_uniform_buffer_offset_alignment.max(1));
        let slot = BLOCK_BYTES.div_ceil(align) * align;
        let block = match desc.technique {
            DepthTechnique::Matrix => size_of::<MatrixShadowRaw>(),
            DepthTechnique::Paraboloid => size_of::<ParaboloidLayerRaw>(),
            DepthTechnique::Rtw => size_of::<RtwShadowRaw>(),
        } as u64;
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: NonZeroU64::new(block),
            },
            count: None,
        }];
        let warped = desc.technique != DepthTechnique::Matrix;
        if warped {
            entries.push(storage_entry(1, wgpu::ShaderStages::VERTEX));
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadowmap depth"),
            entries: &entries,
        });
        let pipeline = create_pipeline(device, desc, &layout)?;
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadowmap depth uniforms"),
            size: slot * u64::from(desc.layers),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let tables = warped.then(|| table_buffer(device, 1));
        let bind_group = make_bind_group(device, &layout, &uniforms, block, tables.as_ref());
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadowmap depth"),
            size: wgpu::Extent3d {
                width: desc.resolution,
                height: desc.resolution,
                depth_or_array_layers: desc.layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let array_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("shadowmap depth array"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let layer_views = (0..desc.layers)
            .map(|i| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("shadowmap depth layer"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: i,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        Ok(Self {
            desc: *desc,
            pipeline,
            layout,
            uniforms,
            slot,
            block,
            tables,
            bind_group,
            texture,
            array_view,
            layer_views,
            tile_indices: None,
        })
    }

    /// What the pass was built with.
    #[must_use]
    pub fn desc(&self) -> &DepthPassDesc {
        &self.desc
    }

    /// The depth texture (all layers).
    #[must_use]
    pub fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    /// A `D2Array` view of all layers, for sampling.
    #[must_use]
    pub fn array_view(&self) -> &wgpu::TextureView {
        &self.array_view
    }

    /// Writes the layers' uniform blocks (queued: they take effect at the next
    /// submit) and records one render pass per layer. `meshes` holds one mesh for
    /// every layer, or one per layer (paraboloid sides subdivide differently). RTW
    /// tables from a slice are queued like the blocks; tables in a GPU buffer
    /// ([`DepthUniforms::RtwGpuTables`]) are copied inside `encoder`, before the pass.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] when the uniforms are for another technique,
    /// their layer count differs from the pass's, `meshes` has the wrong length, or
    /// the RTW tables are shorter than the block's sizes (or their buffer lacks
    /// `COPY_SRC`).
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        meshes: &[&MeshBuffers],
        uniforms: &DepthUniforms<'_>,
    ) -> Result<(), BackendError> {
        if !(meshes.len() == 1 || meshes.len() == self.desc.layers as usize) {
            return Err(BackendError::InvalidInput(
                "need one mesh, or one per layer",
            ));
        }
        self.upload(ctx, encoder, uniforms)?;
        self.record(encoder, meshes);
        Ok(())
    }

    /// [`ShadowDepthPass::encode`] for casters refined on the GPU: uploads the
    /// uniforms as `encode` does and draws each layer's refined triangles of
    /// `refined` with `draw_indirect` (the counts the refinement wrote). Record it
    /// after [`crate::refine::GpuRefine::encode`] with the same uniforms, in the same
    /// or a later submission.
    ///
    /// # Errors
    /// As [`ShadowDepthPass::encode`]; also [`BackendError::InvalidInput`] for a
    /// matrix pass (nothing to refine) or a refinement last recorded for another
    /// layer count.
    pub fn encode_refined(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        refined: &crate::refine::GpuRefine,
        uniforms: &DepthUniforms<'_>,
    ) -> Result<(), BackendError> {
        if self.desc.technique == DepthTechnique::Matrix {
            return Err(BackendError::InvalidInput(
                "refined casters are drawn by the RTW and paraboloid passes",
            ));
        }
        if refined.layers() != self.desc.layers {
            return Err(BackendError::InvalidInput(
                "the refinement was recorded for another layer count",
            ));
        }
        self.upload(ctx, encoder, uniforms)?;
        self.record_refined(encoder, refined);
        Ok(())
    }

    /// Records the passes of the refined casters with the uniforms already written.
    pub fn record_refined(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        refined: &crate::refine::GpuRefine,
    ) {
        for layer in 0..self.layer_views.len() {
            let mut pass = self.begin_layer(encoder, layer);
            pass.set_vertex_buffer(0, refined.vertices().slice(..));
            pass.draw_indirect(refined.draw_buffer(), crate::refine::draw_offset(layer));
        }
    }

    /// Checks `uniforms` against the pass, queues the layers' blocks and brings the
    /// RTW tables into the pass's table buffer.
    fn upload(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &DepthUniforms<'_>,
    ) -> Result<(), BackendError> {
        if uniforms.technique() != self.desc.technique {
            return Err(BackendError::InvalidInput("uniforms of another technique"));
        }
        let layers = self.desc.layers as usize;
        if uniforms.layer_count() != layers {
            return Err(BackendError::InvalidInput(
                "uniform layer count differs from the pass",
            ));
        }
        match uniforms {
            DepthUniforms::RtwGpuTables { raw, tables } => {
                let bytes = (rtw_table_texels(raw).max(1) * 4) as u64;
                if tables.size() < bytes {
                    return Err(BackendError::InvalidInput(
                        "RTW table buffer shorter than its sizes",
                    ));
                }
                if !tables.usage().contains(wgpu::BufferUsages::COPY_SRC) {
                    return Err(BackendError::InvalidInput(
                        "RTW table buffer lacks COPY_SRC usage",
                    ));
                }
                let buffer = self.rtw_table_buffer(ctx, bytes);
                encoder.copy_buffer_to_buffer(tables, 0, buffer, 0, bytes);
            }
            _ => {
                if let Some(tables) = uniforms.cpu_tables()? {
                    let bytes: &[u8] = bytemuck::cast_slice(tables);
                    let buffer = self.rtw_table_buffer(ctx, bytes.len() as u64);
                    ctx.queue.write_buffer(buffer, 0, bytes);
                }
            }
        }
        for layer in 0..layers {
            ctx.queue.write_buffer(
                &self.uniforms,
                self.slot * layer as u64,
                &uniforms.layer_bytes(layer, self.desc.resolution),
            );
        }
        Ok(())
    }

    /// The pass's table buffer, grown (with a new bind group) to hold `bytes`.
    fn rtw_table_buffer(&mut self, ctx: &GpuContext, bytes: u64) -> &wgpu::Buffer {
        let current = self.tables.as_ref().map_or(0, wgpu::Buffer::size);
        if current < bytes {
            let buffer = table_buffer(&ctx.device, bytes);
            self.bind_group = make_bind_group(
                &ctx.device,
                &self.layout,
                &self.uniforms,
                self.block,
                Some(&buffer),
            );
            self.tables = Some(buffer);
        }
        self.tables
            .get_or_insert_with(|| table_buffer(&ctx.device, bytes))
    }

    /// Records the passes with the uniforms already written (the per-frame GPU work
    /// without any upload).
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, meshes: &[&MeshBuffers]) {
        for layer in 0..self.layer_views.len() {
            let Some(mesh) = meshes.get(layer).or_else(|| meshes.first()) else {
                return;
            };
            let mut pass = self.begin_layer(encoder, layer);
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.index_count, 0, 0..1);
        }
    }

    /// Begins the render pass of `layer` (cleared) with the pipeline and the layer's
    /// block bound.
    fn begin_layer<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        layer: usize,
    ) -> wgpu::RenderPass<'e> {
        let clear = if self.desc.reversed_z { 0.0 } else { 1.0 };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadowmap depth pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.layer_views[layer],
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[(self.slot * layer as u64) as u32]);
        pass
    }

    /// Reads the whole depth texture back: layer-major, then row-major, row 0 at
    /// `v = 0` (top). Waits for the GPU.
    ///
    /// # Errors
    /// [`BackendError::Readback`] if mapping fails.
    pub fn readback_depth(&self, ctx: &GpuContext) -> Result<Vec<f32>, BackendError> {
        ctx.read_depth_texture(&self.texture)
    }
}

/// One past the last table texel an RTW block reads (its `u` and `v` tables at
/// their offsets).
pub(crate) fn rtw_table_texels(raw: &RtwShadowRaw) -> usize {
    warp_table_end(&[
        raw.table_offsets[0],
        raw.sizes[0],
        raw.table_offsets[1],
        raw.sizes[1],
    ])
}

/// One past the last texel a paraboloid side's warp (`u` offset, `u` texels, `v`
/// offset, `v` texels) reads.
pub(crate) fn warp_table_end(warp: &[u32; 4]) -> usize {
    let end = |offset: u32, texels: u32| (offset as usize).saturating_add(texels as usize);
    end(warp[0], warp[1]).max(end(warp[2], warp[3]))
}

/// The depth pipeline of a pass: the technique's vertex shader (RTW's with its table
/// sampler composed in), a fragment stage only where the paraboloid clips, the
/// depth test and rasterizer bias of `desc`.
fn create_pipeline(
    device: &wgpu::Device,
    desc: &DepthPassDesc,
    layout: &wgpu::BindGroupLayout,
) -> Result<wgpu::RenderPipeline, BackendError> {
    let (source, label, fragment) = match desc.technique {
        DepthTechnique::Matrix => (
            shaders::DEPTH_MATRIX.to_owned(),
            "shadowmap depth matrix",
            false,
        ),
        DepthTechnique::Paraboloid => (
            compose::depth_paraboloid()?,
            "shadowmap depth paraboloid",
            true,
        ),
        DepthTechnique::Rtw => (compose::depth_rtw()?, "shadowmap depth rtw", false),
    };
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let targets = fragment.then_some(&[][..]);
    Ok(crate::context::mesh_pipeline(
        device,
        (label, Some(&pipeline_layout), &module),
        depth_state(desc.reversed_z, desc.bias),
        targets,
    ))
}

/// A [`DEPTH_FORMAT`] attachment that keeps the nearer depth (`Less`, or `Greater`
/// with reversed-Z) and writes it with this rasterizer bias.
pub(crate) fn depth_state(reversed_z: bool, bias: DepthBias) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(if reversed_z {
            wgpu::CompareFunction::Greater
        } else {
            wgpu::CompareFunction::Less
        }),
        stencil: Default::default(),
        bias: wgpu::DepthBiasState {
            constant: bias.constant,
            slope_scale: bias.slope_scale,
            clamp: bias.clamp,
        },
    }
}

fn storage_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: NonZeroU64::new(4),
        },
        count: None,
    }
}

pub(crate) fn table_buffer(device: &wgpu::Device, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shadowmap rtw tables"),
        size: bytes.max(4).next_multiple_of(4),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn make_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    uniforms: &wgpu::Buffer,
    block: u64,
    tables: Option<&wgpu::Buffer>,
) -> wgpu::BindGroup {
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: uniforms,
            offset: 0,
            size: NonZeroU64::new(block),
        }),
    }];
    if let Some(t) = tables {
        entries.push(wgpu::BindGroupEntry {
            binding: 1,
            resource: t.as_entire_binding(),
        });
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadowmap depth bind group"),
        layout,
        entries: &entries,
    })
}
