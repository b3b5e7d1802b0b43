//! The frame's passes: the technique's depth pass (casters refined on the GPU where
//! its projection is not linear), VSM moments and blur, and the scene pass.

use wgpu::util::DeviceExt;

use super::cache::DepthCache;
use super::image::SceneTargets;
use super::pipelines::{ScenePipeline, VsmPipelines, create_vsm_pipelines, moments_texture};
use super::{RenderOptions, ShadowFilter, ShadowTechnique, timed};
use crate::depth::{
    DepthBias, DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, ShadowDepthPass,
    table_buffer,
};
use crate::profile::GpuProfiler;
use crate::refine::RefineOptions;
use crate::tiles::{tile_bins, tiled_uniforms};
use crate::uniforms::{
    FrameRaw, RtwShadowRaw, ToRaw, paraboloid_layers, warped_cube, warped_paraboloid,
};
use crate::{BackendError, GpuContext};

/// The tables the lookup reads (RTW's, a warped paraboloid's).
pub(super) enum LookupTables<'a> {
    /// None: the lookup has no table binding.
    None,
    /// From the CPU.
    Owned(Vec<f32>),
    /// Built on the GPU ([`crate::rtw::GpuRtw::tables_buffer`]).
    Buffer(&'a wgpu::Buffer),
}

/// A recorded depth pass (its index in the [`DepthCache`]) and the tables the
/// lookup reads.
pub(super) struct DepthOutput<'a> {
    pub(super) pass: usize,
    pub(super) tables: LookupTables<'a>,
}

/// What every depth pass of a frame shares.
pub(super) struct DepthJob<'a> {
    pub(super) options: &'a RenderOptions,
    pub(super) bias: DepthBias,
    pub(super) reversed: bool,
}

impl DepthJob<'_> {
    fn desc(&self, technique: DepthTechnique, layers: usize) -> DepthPassDesc {
        DepthPassDesc::new(technique, self.options.shadow_resolution)
            .with_layers(u32::try_from(layers).unwrap_or(u32::MAX))
            .with_reversed_z(self.reversed)
            .with_bias(self.bias)
    }

    /// Records the technique's depth pass into `encoder`: the scene mesh for the
    /// matrix techniques; for the paraboloid and RTW passes the casters refined on
    /// the GPU ([`crate::refine::GpuRefine`], the twin of the CPU references
    /// `subdivide_triangles` and `subdivide_for_rtw`) and drawn indirectly, in scopes
    /// `refine` and `depth` of `profiler`.
    pub(super) fn encode<'t>(
        &self,
        (ctx, encoder): (&GpuContext, &mut wgpu::CommandEncoder),
        cache: &mut DepthCache,
        technique: &ShadowTechnique<'t>,
        profiler: &mut Option<&mut GpuProfiler>,
    ) -> Result<DepthOutput<'t>, BackendError> {
        if let Some(blocks) = technique.matrix_layers() {
            let index = cache.pass_index(ctx, &self.desc(DepthTechnique::Matrix, blocks.len()))?;
            let (pass, mesh, _) = cache.parts(ctx, index, None)?;
            timed(profiler, encoder, "depth", |e| {
                pass.encode(ctx, e, &[mesh], &DepthUniforms::Matrix(&blocks))
            })?;
            return Ok(DepthOutput {
                pass: index,
                tables: LookupTables::None,
            });
        }
        if let ShadowTechnique::TiledCube(tiled) = technique {
            let uniforms = tiled_uniforms(tiled, self.options.shadow_resolution);
            let bins = tile_bins(tiled, cache.triangles()?);
            let index = cache.pass_index(ctx, &self.desc(DepthTechnique::Matrix, 1))?;
            let (pass, mesh, _) = cache.parts(ctx, index, None)?;
            timed(profiler, encoder, "depth", |e| {
                pass.encode_tiles(ctx, e, mesh, &uniforms.draws, Some(&bins))
            })?;
            return Ok(DepthOutput {
                pass: index,
                tables: LookupTables::Owned(uniforms.data),
            });
        }
        let refine = RefineOptions::default()
            .with_subdivision(self.options.rtw_subdivision)
            .with_paraboloid(self.options.subdivision)
            .with_resolution(self.options.shadow_resolution);
        let job = RefinedJob {
            ctx,
            cache,
            refine: &refine,
        };
        let rtw_desc = self.desc(DepthTechnique::Rtw, 1);
        match technique {
            ShadowTechnique::Paraboloid(map) => {
                let layers = paraboloid_layers(map);
                let uniforms = DepthUniforms::Paraboloid(&layers);
                let desc = self.desc(DepthTechnique::Paraboloid, layers.len());
                let pass = job.record(encoder, &desc, &uniforms, profiler)?;
                Ok(DepthOutput {
                    pass,
                    tables: LookupTables::Owned(vec![0.0]),
                })
            }
            ShadowTechnique::ParaboloidRtw { map, front, back } => {
                let warped = warped_paraboloid(map, Some(front), *back);
                let uniforms = DepthUniforms::WarpedParaboloid {
                    layers: &warped.layers,
                    tables: &warped.tables,
                };
                let desc = self.desc(DepthTechnique::Paraboloid, warped.layers.len());
                let pass = job.record(encoder, &desc, &uniforms, profiler)?;
                Ok(DepthOutput {
                    pass,
                    tables: LookupTables::Owned(warped.tables),
                })
            }
            ShadowTechnique::CubeRtw { cube, warps } => {
                let warped = warped_cube(cube, warps);
                let uniforms = DepthUniforms::WarpedCube {
                    layers: &warped.layers,
                    tables: &warped.tables,
                };
                let desc = self.desc(DepthTechnique::Rtw, warped.layers.len());
                let pass = job.record(encoder, &desc, &uniforms, profiler)?;
                Ok(DepthOutput {
                    pass,
                    tables: LookupTables::Owned(warped.tables),
                })
            }
            ShadowTechnique::Rtw(shadow) => {
                let tables = RtwShadowRaw::tables(shadow);
                let uniforms = DepthUniforms::Rtw {
                    raw: shadow.to_raw(),
                    tables: &tables,
                };
                let pass = job.record(encoder, &rtw_desc, &uniforms, profiler)?;
                Ok(DepthOutput {
                    pass,
                    tables: LookupTables::Owned(tables),
                })
            }
            ShadowTechnique::RtwGpu { base, rtw } => {
                let uniforms = rtw.depth_uniforms(base);
                let pass = job.record(encoder, &rtw_desc, &uniforms, profiler)?;
                Ok(DepthOutput {
                    pass,
                    tables: LookupTables::Buffer(rtw.tables_buffer()),
                })
            }
            _ => Err(BackendError::InvalidInput("technique without a depth pass")),
        }
    }
}

/// A depth pass drawn from casters refined on the GPU.
struct RefinedJob<'c> {
    ctx: &'c GpuContext,
    cache: &'c mut DepthCache,
    refine: &'c RefineOptions,
}

impl RefinedJob<'_> {
    /// Records the refinement (scope `refine`) and the indirect depth pass (scope
    /// `depth`); returns the pass's index in the cache.
    fn record(
        self,
        encoder: &mut wgpu::CommandEncoder,
        desc: &DepthPassDesc,
        uniforms: &DepthUniforms<'_>,
        profiler: &mut Option<&mut GpuProfiler>,
    ) -> Result<usize, BackendError> {
        let ctx = self.ctx;
        let index = self.cache.pass_index(ctx, desc)?;
        let (pass, _, refine) = self.cache.parts(ctx, index, Some(self.refine))?;
        let refine = refine.ok_or(BackendError::InvalidInput("no refinement"))?;
        timed(profiler, encoder, "refine", |e| {
            refine.encode(ctx, e, uniforms)
        })?;
        timed(profiler, encoder, "depth", |e| {
            pass.encode_refined(ctx, e, refine, uniforms)
        })?;
        Ok(index)
    }
}

/// One full-screen VSM step: `input` (all layers) into one layer of `output`.
struct VsmStep<'a> {
    pipeline: &'a wgpu::RenderPipeline,
    input: &'a wgpu::TextureView,
    output: &'a wgpu::Texture,
    direction: [u32; 2],
}

/// The moments texture: blurred moments for VSM, else a 1×1 placeholder; `cache`
/// holds the VSM pipelines across frames.
pub(super) fn encode_vsm(
    cache: &mut Option<VsmPipelines>,
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    depth: &ShadowDepthPass,
    options: &RenderOptions,
    reversed: bool,
) -> Result<wgpu::Texture, BackendError> {
    let device = &ctx.device;
    let desc = depth.desc();
    let ShadowFilter::Vsm { blur_radius } = options.filter else {
        return Ok(moments_texture(device, 1, 1));
    };
    let vsm: &VsmPipelines = cache.get_or_insert_with(|| create_vsm_pipelines(device));
    let a = moments_texture(device, desc.resolution, desc.layers);
    let b = moments_texture(device, desc.resolution, desc.layers);
    let (a_all, b_all) = (array_view(&a), array_view(&b));
    for layer in 0..desc.layers {
        // moments -> a, blur x: a -> b, blur y: b -> a.
        let steps = [
            (&vsm.moments, &b_all, &a, [0, 0]),
            (&vsm.blur, &a_all, &b, [1, 0]),
            (&vsm.blur, &b_all, &a, [0, 1]),
        ];
        for (pipeline, input, output, direction) in steps {
            let step = VsmStep {
                pipeline,
                input,
                output,
                direction,
            };
            let params = [layer, blur_radius.min(32), u32::from(reversed)];
            record_vsm_step(device, encoder, vsm, depth, &step, params);
        }
    }
    Ok(a)
}

fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// Records one VSM step; `params` = (layer, blur radius, reversed-Z).
fn record_vsm_step(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    vsm: &VsmPipelines,
    depth: &ShadowDepthPass,
    step: &VsmStep<'_>,
    [layer, radius, reversed]: [u32; 3],
) {
    let [dx, dy] = step.direction;
    let params: [u32; 8] = [layer, radius, reversed, 0, dx, dy, 0, 0];
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("shadowmap vsm params"),
        contents: bytemuck::cast_slice(&params),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadowmap vsm"),
        layout: &vsm.layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(depth.array_view()),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(step.input),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: buffer.as_entire_binding(),
            },
        ],
    });
    let view = step.output.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    });
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadowmap vsm"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(step.pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.draw(0..3, 0..1);
}

/// What the scene pass reads.
pub(super) struct SceneInputs<'a> {
    pub(super) frame: FrameRaw,
    pub(super) lookup: Vec<u8>,
    pub(super) tables: &'a LookupTables<'a>,
    pub(super) depth: &'a ShadowDepthPass,
    pub(super) moments: &'a wgpu::Texture,
    pub(super) reversed: bool,
}

/// The scene pass's bind groups: frame, lookup, maps.
fn scene_bind_groups(
    ctx: &GpuContext,
    pipeline: &ScenePipeline,
    inputs: &SceneInputs<'_>,
) -> [wgpu::BindGroup; 3] {
    let device = &ctx.device;
    let uniform = |label, contents: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::UNIFORM,
        })
    };
    let frame_buffer = uniform("shadowmap frame", bytemuck::bytes_of(&inputs.frame));
    let lookup_buffer = uniform("shadowmap lookup", &inputs.lookup);
    let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadowmap frame"),
        layout: &pipeline.frame_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: frame_buffer.as_entire_binding(),
        }],
    });
    let owned = match inputs.tables {
        LookupTables::Owned(t) => {
            let b = table_buffer(device, (t.len() * 4) as u64);
            ctx.queue.write_buffer(&b, 0, bytemuck::cast_slice(t));
            Some(b)
        }
        LookupTables::None | LookupTables::Buffer(_) => None,
    };
    let table_buf = match inputs.tables {
        LookupTables::Buffer(b) => Some(*b),
        LookupTables::Owned(_) | LookupTables::None => owned.as_ref(),
    };
    let mut lookup_entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: lookup_buffer.as_entire_binding(),
    }];
    if let Some(b) = table_buf {
        lookup_entries.push(wgpu::BindGroupEntry {
            binding: 1,
            resource: b.as_entire_binding(),
        });
    }
    let lookup_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadowmap lookup"),
        layout: &pipeline.lookup_layout,
        entries: &lookup_entries,
    });
    [
        frame_group,
        lookup_group,
        maps_group(device, pipeline, inputs),
    ]
}

/// The depth array, its comparison sampler, and the VSM moments.
fn maps_group(
    device: &wgpu::Device,
    pipeline: &ScenePipeline,
    inputs: &SceneInputs<'_>,
) -> wgpu::BindGroup {
    let compare = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("shadowmap compare"),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        compare: Some(if inputs.reversed {
            wgpu::CompareFunction::GreaterEqual
        } else {
            wgpu::CompareFunction::LessEqual
        }),
        ..Default::default()
    });
    let moments_view = array_view(inputs.moments);
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadowmap maps"),
        layout: &pipeline.maps_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(inputs.depth.array_view()),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::Sampler(&compare),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(&moments_view),
            },
        ],
    })
}

/// Records the scene pass: `mesh` from the camera into `targets`, the camera's
/// depth cleared for its direction.
pub(super) fn record_scene(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &ScenePipeline,
    inputs: &SceneInputs<'_>,
    (mesh, targets, camera_reversed_z): (&MeshBuffers, &SceneTargets, bool),
) {
    let groups = scene_bind_groups(ctx, pipeline, inputs);
    let color_view = targets.color.create_view(&Default::default());
    let mask_view = targets.mask.create_view(&Default::default());
    let depth_view = targets.depth.create_view(&Default::default());
    let attachment = |view, clear| {
        Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear),
                store: wgpu::StoreOp::Store,
            },
        })
    };
    let sky = wgpu::Color {
        r: 0.55,
        g: 0.7,
        b: 0.9,
        a: 1.0,
    };
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadowmap scene"),
        color_attachments: &[
            attachment(&color_view, sky),
            attachment(&mask_view, wgpu::Color::TRANSPARENT),
        ],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth_view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(if camera_reversed_z { 0.0 } else { 1.0 }),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(&pipeline.pipeline);
    for (i, group) in groups.iter().enumerate() {
        pass.set_bind_group(i as u32, group, &[]);
    }
    pass.set_vertex_buffer(0, mesh.vertices.slice(..));
    pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
    pass.draw_indexed(0..mesh.index_count, 0, 0..1);
}
