//! Shadow depth passes: matrix techniques (uniform, cascades, LiSPSM, XPSM, TSM),
//! paraboloid (front and back layers), and RTW (warped vertices).
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

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::uniforms::{MatrixShadowRaw, ParaboloidLayerRaw, RtwShadowRaw};
use crate::{BackendError, GpuContext, shaders};

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
}

impl DepthUniforms<'_> {
    fn technique(&self) -> DepthTechnique {
        match self {
            Self::Matrix(_) => DepthTechnique::Matrix,
            Self::Paraboloid(_) => DepthTechnique::Paraboloid,
            Self::Rtw { .. } | Self::RtwGpuTables { .. } => DepthTechnique::Rtw,
        }
    }

    fn layer_count(&self) -> usize {
        match self {
            Self::Matrix(m) => m.len(),
            Self::Paraboloid(p) => p.len(),
            Self::Rtw { .. } | Self::RtwGpuTables { .. } => 1,
        }
    }

    /// The block of `layer`; paraboloid and RTW blocks get the map resolution
    /// (`side.y`, `sizes.w`) for the vertex shader's subpixel snap.
    fn layer_bytes(&self, layer: usize, resolution: u32) -> Vec<u8> {
        match self {
            Self::Matrix(m) => bytemuck::bytes_of(&m[layer]).to_vec(),
            Self::Paraboloid(p) => {
                let mut raw = p[layer];
                raw.side[1] = resolution as f32;
                bytemuck::bytes_of(&raw).to_vec()
            }
            Self::Rtw { raw, .. } | Self::RtwGpuTables { raw, .. } => {
                let mut raw = *raw;
                raw.sizes[3] = resolution;
                bytemuck::bytes_of(&raw).to_vec()
            }
        }
    }
}

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

/// A shadow depth pass and its `Depth32Float` array texture.
#[derive(Debug)]
pub struct ShadowDepthPass {
    desc: DepthPassDesc,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    slot: u64,
    tables: Option<wgpu::Buffer>,
    bind_group: wgpu::BindGroup,
    texture: wgpu::Texture,
    array_view: wgpu::TextureView,
    layer_views: Vec<wgpu::TextureView>,
}

/// Bytes reserved per layer in the uniform buffer (before alignment).
const BLOCK_BYTES: u64 = 256;

impl ShadowDepthPass {
    /// Creates the texture and the pipeline.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a resolution or layer count of 0 or above the
    /// device's limits, or more than one layer for RTW;
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
        if desc.technique == DepthTechnique::Rtw && desc.layers != 1 {
            return Err(BackendError::InvalidInput("RTW renders one layer"));
        }
        if !(desc.bias.slope_scale.is_finite() && desc.bias.clamp.is_finite()) {
            return Err(BackendError::InvalidInput("non-finite depth bias"));
        }
        ctx.scoped(|ctx| Ok(Self::create(ctx, desc)))
    }

    fn create(ctx: &GpuContext, desc: &DepthPassDesc) -> Self {
        let device = &ctx.device;
        let align = u64::from(device.limits().min_uniform_buffer_offset_alignment.max(1));
        let slot = BLOCK_BYTES.div_ceil(align) * align;
        let (source, label, block, fragment) = match desc.technique {
            DepthTechnique::Matrix => (
                shaders::DEPTH_MATRIX,
                "shadowmap depth matrix",
                size_of::<MatrixShadowRaw>(),
                false,
            ),
            DepthTechnique::Paraboloid => (
                shaders::DEPTH_PARABOLOID,
                "shadowmap depth paraboloid",
                size_of::<ParaboloidLayerRaw>(),
                true,
            ),
            DepthTechnique::Rtw => (
                shaders::DEPTH_RTW,
                "shadowmap depth rtw",
                size_of::<RtwShadowRaw>(),
                false,
            ),
        };
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: NonZeroU64::new(block as u64),
            },
            count: None,
        }];
        if desc.technique == DepthTechnique::Rtw {
            entries.push(storage_entry(1, wgpu::ShaderStages::VERTEX));
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(MeshBuffers::layout())],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(if desc.reversed_z {
                    wgpu::CompareFunction::Greater
                } else {
                    wgpu::CompareFunction::Less
                }),
                stencil: Default::default(),
                bias: wgpu::DepthBiasState {
                    constant: desc.bias.constant,
                    slope_scale: desc.bias.slope_scale,
                    clamp: desc.bias.clamp,
                },
            }),
            multisample: Default::default(),
            fragment: fragment.then(|| wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadowmap depth uniforms"),
            size: slot * u64::from(desc.layers),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let tables = (desc.technique == DepthTechnique::Rtw).then(|| table_buffer(device, 1));
        let bind_group = make_bind_group(device, &layout, &uniforms, block as u64, tables.as_ref());
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
        Self {
            desc: *desc,
            pipeline,
            layout,
            uniforms,
            slot,
            tables,
            bind_group,
            texture,
            array_view,
            layer_views,
        }
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
        if uniforms.technique() != self.desc.technique {
            return Err(BackendError::InvalidInput("uniforms of another technique"));
        }
        let layers = self.desc.layers as usize;
        if uniforms.layer_count() != layers {
            return Err(BackendError::InvalidInput(
                "uniform layer count differs from the pass",
            ));
        }
        if !(meshes.len() == 1 || meshes.len() == layers) {
            return Err(BackendError::InvalidInput(
                "need one mesh, or one per layer",
            ));
        }
        match uniforms {
            DepthUniforms::Rtw { raw, tables } => {
                let needed = rtw_table_texels(raw);
                if tables.len() < needed.max(1) {
                    return Err(BackendError::InvalidInput(
                        "RTW tables shorter than their sizes",
                    ));
                }
                let bytes: &[u8] = bytemuck::cast_slice(tables);
                let buffer = self.rtw_table_buffer(ctx, bytes.len() as u64);
                ctx.queue.write_buffer(buffer, 0, bytes);
            }
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
            DepthUniforms::Matrix(_) | DepthUniforms::Paraboloid(_) => {}
        }
        for layer in 0..layers {
            ctx.queue.write_buffer(
                &self.uniforms,
                self.slot * layer as u64,
                &uniforms.layer_bytes(layer, self.desc.resolution),
            );
        }
        self.record(encoder, meshes);
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
                size_of::<RtwShadowRaw>() as u64,
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
        let clear = if self.desc.reversed_z { 0.0 } else { 1.0 };
        for (layer, view) in self.layer_views.iter().enumerate() {
            let Some(mesh) = meshes.get(layer).or_else(|| meshes.first()) else {
                return;
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadowmap depth pass"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view,
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
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.index_count, 0, 0..1);
        }
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

/// Texels of both RTW tables a block declares.
fn rtw_table_texels(raw: &RtwShadowRaw) -> usize {
    (raw.sizes[0] as usize).saturating_add(raw.sizes[1] as usize)
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

/// Copies `layers` layers of a texture into tightly packed rows (layer-major) and
/// waits for them.
pub(crate) fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
    width: u32,
    height: u32,
    layers: u32,
    texel_bytes: u32,
) -> Result<Vec<u8>, BackendError> {
    let row = width * texel_bytes;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let size = u64::from(padded) * u64::from(height) * u64::from(layers);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shadowmap readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("shadowmap readback"),
        });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: layers,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    ctx.read_mapped(&buffer, |mapped| {
        let mut out = Vec::with_capacity((row * height * layers) as usize);
        for chunk in mapped.chunks(padded as usize) {
            out.extend_from_slice(&chunk[..row as usize]);
        }
        out
    })
}

/// How finely [`subdivide_for_rtw`] splits casters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RtwSubdivision {
    /// Texels per side of the shadow map the casters are rendered into (the error
    /// bound is in its texels), `>= 1`. Default 1024.
    pub resolution: u32,
    /// Largest distance, in map texels, between the warped midpoint of an edge
    /// and the midpoint of its straight warped image, `>= 1/64`. Default 0.25:
    /// straight pieces that miss the bent warp by more leave acne smudges on steep
    /// receivers (the slope-scaled bias absorbs less).
    pub max_error_texels: f64,
    /// Longest piece, in warp-table cells (`max(|du| N_u, |dv| N_v)` in base texture
    /// space), `>= 1/64`, whatever the midpoint error: a midpoint test cannot see
    /// kinks that cancel out over a long edge. Default 2.
    pub max_span_cells: f64,
    /// Most pieces an original edge is cut into, in `1..=1024` (rounded up to a power
    /// of two): caps the triangle count at `max_segments²` per caster. Default 32.
    /// The cost is real: the city block (5264 triangles) over 256-cell tables into a
    /// 2048² map under a strong warp becomes 0.72 M triangles in 64 ms with the
    /// defaults, 4.8 M in 1.1 s with a cap of 256 (`cargo bench --bench frame`).
    pub max_segments: u32,
}

impl Default for RtwSubdivision {
    fn default() -> Self {
        Self {
            resolution: 1024,
            max_error_texels: 0.25,
            max_span_cells: 2.0,
            max_segments: 32,
        }
    }
}

impl RtwSubdivision {
    /// For a map of this many texels per side.
    #[must_use]
    pub const fn with_resolution(mut self, resolution: u32) -> Self {
        self.resolution = resolution;
        self
    }
    /// With this midpoint error bound, in map texels.
    #[must_use]
    pub const fn with_max_error_texels(mut self, texels: f64) -> Self {
        self.max_error_texels = texels;
        self
    }
    /// With this longest piece, in table cells.
    #[must_use]
    pub const fn with_max_span_cells(mut self, cells: f64) -> Self {
        self.max_span_cells = cells;
        self
    }
    /// With this cap on pieces per edge.
    #[must_use]
    pub const fn with_max_segments(mut self, max_segments: u32) -> Self {
        self.max_segments = max_segments;
        self
    }
}

/// Splits triangles for the RTW depth pass, which warps only vertices: the warp is
/// piecewise linear between the tables' texel centres, so a long edge stays straight
/// where the warped map bends it. An edge is halved when it spans more than
/// `max_span_cells` table cells or its warped midpoint lies more than
/// `max_error_texels` map texels from the midpoint of its straight warped image;
/// the pieces are tested again, until the original edge has been halved
/// `ceil(log2(max_segments))` times. Out-of-range options are clamped to their
/// documented ranges (NaN: the default). Writes into `out` (cleared first) and
/// returns its length.
///
/// Whether an edge splits depends on its two endpoints alone, and its midpoint is
/// symmetric in them, so two triangles sharing an edge split it identically: a
/// conforming mesh stays conforming (no T-junctions, hence no cracks between warped
/// neighbours). A triangle with one edge split becomes 2, two edges 3, three edges
/// 4 (the midpoint triangle), each recursed into.
///
/// Triangles with a vertex the base projection cannot map (behind a perspective
/// light) or with non-finite vertices are passed through unsplit.
pub fn subdivide_for_rtw(
    shadow: &shadowmap_rtw::RtwShadow<'_>,
    triangles: &[[Vec3; 3]],
    options: &RtwSubdivision,
    out: &mut Vec<[Vec3; 3]>,
) -> usize {
    out.clear();
    let defaults = RtwSubdivision::default();
    let at_least = |x: f64, default: f64| {
        if x.is_nan() {
            default
        } else {
            x.clamp(1.0 / 64.0, f64::MAX)
        }
    };
    let max_span = at_least(options.max_span_cells, defaults.max_span_cells);
    let max_error = at_least(options.max_error_texels, defaults.max_error_texels);
    let splitter = RtwSplitter {
        shadow,
        pieces: glam::DVec2::new(
            shadow.warps.x_table().len() as f64,
            shadow.warps.y_table().len() as f64,
        ) / max_span,
        error_scale: f64::from(options.resolution.max(1)) / max_error,
    };
    let levels = options
        .max_segments
        .clamp(1, 1024)
        .next_power_of_two()
        .trailing_zeros();
    for &t in triangles {
        if t.iter().all(|p| p.is_finite() && splitter.uv(*p).is_some()) {
            splitter.split(t, levels, out);
        } else {
            out.push(t);
        }
    }
    out.len()
}

/// The per-edge split rule of [`subdivide_for_rtw`].
struct RtwSplitter<'a, 'b> {
    shadow: &'a shadowmap_rtw::RtwShadow<'b>,
    /// Pieces per unit of base texture space along `u` and `v` (table texels over
    /// the longest piece in cells).
    pieces: glam::DVec2,
    /// Map texels over the error bound: warped-uv error times this above 1 splits.
    error_scale: f64,
}

impl RtwSplitter<'_, '_> {
    fn uv(&self, p: Vec3) -> Option<glam::DVec2> {
        self.shadow
            .base
            .project(p)
            .map(|s| s.uv)
            .filter(|uv| uv.is_finite())
    }

    fn warp(&self, uv: glam::DVec2) -> glam::DVec2 {
        glam::DVec2::new(
            shadowmap_rtw::forward_warp_f64(self.shadow.warps.x_table(), uv.x),
            shadowmap_rtw::forward_warp_f64(self.shadow.warps.y_table(), uv.y),
        )
    }

    /// The midpoint of `a b` if the edge is longer than a piece or its straight
    /// warped image misses the warped midpoint by more than the bound. Symmetric
    /// in `a, b`: both triangles of a shared edge decide alike and get the same
    /// point.
    fn midpoint(&self, a: Vec3, b: Vec3) -> Option<Vec3> {
        let (ua, ub) = (self.uv(a)?, self.uv(b)?);
        let mid = ((a.as_dvec3() + b.as_dvec3()) * 0.5).as_vec3();
        let span = ((ub - ua).abs() * self.pieces).max_element();
        if span > 1.0 {
            return Some(mid);
        }
        let chord = (self.warp(ua) + self.warp(ub)) * 0.5;
        let error = (self.warp(self.uv(mid)?) - chord).abs().max_element();
        (error * self.error_scale > 1.0).then_some(mid)
    }

    fn split(&self, t: [Vec3; 3], levels: u32, out: &mut Vec<[Vec3; 3]>) {
        let [a, b, c] = t;
        if levels == 0 {
            out.push(t);
            return;
        }
        let next = levels - 1;
        let mid = [
            self.midpoint(a, b),
            self.midpoint(b, c),
            self.midpoint(c, a),
        ];
        // Rotate so the split edges come first (same winding throughout).
        match mid {
            [None, None, None] => out.push(t),
            [Some(m), None, None] => self.split_one([a, b, c], m, next, out),
            [None, Some(m), None] => self.split_one([b, c, a], m, next, out),
            [None, None, Some(m)] => self.split_one([c, a, b], m, next, out),
            [Some(m), Some(n), None] => self.split_two([a, b, c], m, n, next, out),
            [None, Some(m), Some(n)] => self.split_two([b, c, a], m, n, next, out),
            [Some(n), None, Some(m)] => self.split_two([c, a, b], m, n, next, out),
            [Some(ab), Some(bc), Some(ca)] => {
                for piece in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                    self.split(piece, next, out);
                }
            }
        }
    }

    /// `[a, b, c]` with `m` the midpoint of `a b`.
    fn split_one(&self, [a, b, c]: [Vec3; 3], m: Vec3, levels: u32, out: &mut Vec<[Vec3; 3]>) {
        self.split([a, m, c], levels, out);
        self.split([m, b, c], levels, out);
    }

    /// `[a, b, c]` with `m` the midpoint of `a b` and `n` that of `b c`: the corner
    /// `m b n`, and the quad `a m n c` cut along its shorter diagonal.
    fn split_two(
        &self,
        [a, b, c]: [Vec3; 3],
        m: Vec3,
        n: Vec3,
        levels: u32,
        out: &mut Vec<[Vec3; 3]>,
    ) {
        self.split([m, b, n], levels, out);
        if a.distance_squared(n) <= m.distance_squared(c) {
            self.split([a, m, n], levels, out);
            self.split([a, n, c], levels, out);
        } else {
            self.split([a, m, c], levels, out);
            self.split([m, n, c], levels, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec2};
    use shadowmap_frustum::{LightDirection, ShadowTransform};
    use shadowmap_rtw::{ImportanceMap, RtwShadow, WarpMaps, WarpOptions};

    /// An identity base (`uv = (x, y)` for `x, y` in `[0, 1]`) over 16 x 8 tables.
    fn warps() -> WarpMaps {
        let mut importance = ImportanceMap::new(16, 8).unwrap();
        importance.splat(Vec2::new(0.3, 0.6), 1.0).unwrap();
        let mut warps = WarpMaps::new(16, 8).unwrap();
        warps.build(&importance, &WarpOptions::default()).unwrap();
        warps
    }

    fn shadow(warps: &WarpMaps) -> RtwShadow<'_> {
        // clip x = 2u - 1, y = 1 - 2v: uv_from_world is the identity on x, y.
        let clip_from_world = Mat4::from_cols_array(&[
            2.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0,
        ]);
        let base = ShadowTransform::new(
            Mat4::IDENTITY,
            clip_from_world,
            false,
            LightDirection::Directional(Vec3::NEG_Z),
        );
        RtwShadow { base, warps }
    }

    fn area(t: &[Vec3; 3]) -> f32 {
        0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
    }

    #[test]
    fn pieces_span_at_most_one_cell_and_keep_the_area() {
        let warps = warps();
        let shadow = shadow(&warps);
        let t = [
            Vec3::new(0.05, 0.1, 0.5),
            Vec3::new(0.95, 0.2, 0.5),
            Vec3::new(0.4, 0.9, 0.5),
        ];
        let mut out = Vec::new();
        // Span alone (a huge error bound).
        let one_cell = RtwSubdivision::default()
            .with_max_span_cells(1.0)
            .with_max_error_texels(1e9);
        let n = subdivide_for_rtw(&shadow, &[t], &one_cell, &mut out);
        assert!(n > 16, "split into {n}");
        for piece in &out {
            for (p, q) in [
                (piece[0], piece[1]),
                (piece[1], piece[2]),
                (piece[2], piece[0]),
            ] {
                let span = ((q.x - p.x).abs() * 16.0).max((q.y - p.y).abs() * 8.0);
                assert!(span <= 1.0 + 1e-5, "edge spans {span} cells");
            }
        }
        let total: f32 = out.iter().map(area).sum();
        assert!((total - area(&t)).abs() < 1e-5 * area(&t).max(1.0));
        // The error bound splits further on a fine map; on a one-texel map with a
        // one-texel bound (the warp stays in [0, 1]) it never splits.
        let fine = one_cell.with_max_error_texels(0.25).with_resolution(4096);
        assert!(subdivide_for_rtw(&shadow, &[t], &fine, &mut out) > n);
        let coarse = one_cell.with_max_error_texels(1.0).with_resolution(1);
        assert_eq!(subdivide_for_rtw(&shadow, &[t], &coarse, &mut out), n);
        // Capped: at most 2 halvings per edge, so at most 4^2 pieces.
        let capped = one_cell.with_max_segments(4);
        assert!(subdivide_for_rtw(&shadow, &[t], &capped, &mut out) <= 16);
        let unsplit = one_cell.with_max_segments(1);
        assert_eq!(subdivide_for_rtw(&shadow, &[t], &unsplit, &mut out), 1);
    }

    #[test]
    fn a_shared_edge_splits_identically_on_both_sides() {
        let warps = warps();
        let shadow = shadow(&warps);
        let (p, q) = (Vec3::new(0.1, 0.1, 0.0), Vec3::new(0.9, 0.8, 0.0));
        // Very different third vertices: one side would split far more if the edge
        // were decided per triangle.
        let left = [p, q, Vec3::new(0.12, 0.75, 0.0)];
        let right = [q, p, Vec3::new(0.99, 0.02, 0.0)];
        let on_edge = |tris: &[[Vec3; 3]]| {
            let mut v: Vec<[u32; 3]> = tris
                .iter()
                .flatten()
                .filter(|x| {
                    let d = (q - p).cross(**x - p).length();
                    d < 1e-6
                })
                .map(|x| x.to_array().map(f32::to_bits))
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let mut a = Vec::new();
        let mut b = Vec::new();
        let options = RtwSubdivision::default();
        subdivide_for_rtw(&shadow, &[left], &options, &mut a);
        subdivide_for_rtw(&shadow, &[right], &options, &mut b);
        let (ea, eb) = (on_edge(&a), on_edge(&b));
        assert!(ea.len() > 2, "the shared edge was split");
        assert_eq!(ea, eb);
    }

    #[test]
    fn unmappable_or_non_finite_triangles_pass_through() {
        let warps = warps();
        let shadow = shadow(&warps);
        let bad = [Vec3::NAN, Vec3::X, Vec3::Y];
        let mut out = Vec::new();
        let options = RtwSubdivision::default();
        assert_eq!(subdivide_for_rtw(&shadow, &[bad], &options, &mut out), 1);
        assert!(out[0][0].is_nan());
    }
}
