//! The frame's passes: the technique's depth pass (casters subdivided where its
//! projection is not linear), VSM moments and blur, and the scene pass.

use glam::Vec3;
use shadowmap_paraboloid::{ParaboloidMap, Side, subdivide_triangles};
use shadowmap_rtw::RtwShadow;
use wgpu::util::DeviceExt;

use super::image::SceneTargets;
use super::pipelines::{ScenePipeline, VsmPipelines, create_vsm_pipelines, moments_texture};
use super::{RenderOptions, ShadowFilter, ShadowTechnique};
use crate::depth::{
    DepthBias, DepthPassDesc, DepthTechnique, DepthUniforms, MeshBuffers, ShadowDepthPass,
    table_buffer,
};
use crate::refine::{GpuRefine, RefineOptions};
use crate::uniforms::{FrameRaw, RtwShadowRaw, ToRaw, paraboloid_layers};
use crate::{BackendError, GpuContext};

/// A recorded depth pass, with the RTW tables the lookup reads too.
pub(super) struct DepthOutput {
    pub(super) pass: ShadowDepthPass,
    pub(super) tables: Option<Vec<f32>>,
}

/// What every depth pass of a frame shares.
pub(super) struct DepthJob<'a> {
    pub(super) triangles: &'a [[Vec3; 3]],
    pub(super) scene_mesh: &'a MeshBuffers,
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

    /// Records the technique's depth pass into `encoder`.
    pub(super) fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        technique: &ShadowTechnique<'_>,
    ) -> Result<DepthOutput, BackendError> {
        if let Some(blocks) = technique.matrix_layers() {
            let mut pass =
                ShadowDepthPass::new(ctx, &self.desc(DepthTechnique::Matrix, blocks.len()))?;
            let uniforms = DepthUniforms::Matrix(&blocks);
            pass.encode(ctx, encoder, &[self.scene_mesh], &uniforms)?;
            return Ok(DepthOutput { pass, tables: None });
        }
        match technique {
            ShadowTechnique::Paraboloid(map) => self.paraboloid(ctx, encoder, map),
            ShadowTechnique::Rtw(shadow) => self.rtw(ctx, encoder, shadow),
            _ => Err(BackendError::InvalidInput("technique without a depth pass")),
        }
    }

    /// One layer per side, each from casters subdivided for that side.
    fn paraboloid(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        map: &ParaboloidMap,
    ) -> Result<DepthOutput, BackendError> {
        let sub = self
            .options
            .subdivision
            .with_resolution(self.options.shadow_resolution);
        let blocks = paraboloid_layers(map);
        let mut meshes = Vec::new();
        let mut out = Vec::new();
        for side in [Side::Front, Side::Back].into_iter().take(blocks.len()) {
            subdivide_triangles(map, side, self.triangles, &sub, &mut out)
                .map_err(|_| BackendError::InvalidInput("paraboloid subdivision failed"))?;
            meshes.push(MeshBuffers::from_triangles(ctx, &out)?);
        }
        let refs: Vec<&MeshBuffers> = meshes.iter().collect();
        let mut pass =
            ShadowDepthPass::new(ctx, &self.desc(DepthTechnique::Paraboloid, blocks.len()))?;
        pass.encode(ctx, encoder, &refs, &DepthUniforms::Paraboloid(&blocks))?;
        Ok(DepthOutput { pass, tables: None })
    }

    /// One layer from casters refined against the warp tables on the GPU
    /// ([`GpuRefine`], the twin of the CPU reference `subdivide_for_rtw`), drawn
    /// indirectly.
    fn rtw(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        shadow: &RtwShadow<'_>,
    ) -> Result<DepthOutput, BackendError> {
        let sub = self
            .options
            .rtw_subdivision
            .with_resolution(self.options.shadow_resolution);
        let mut refine = GpuRefine::new(
            ctx,
            self.triangles,
            &RefineOptions::default().with_subdivision(sub),
        )?;
        let tables = RtwShadowRaw::tables(shadow);
        let mut pass = ShadowDepthPass::new(ctx, &self.desc(DepthTechnique::Rtw, 1))?;
        let uniforms = DepthUniforms::Rtw {
            raw: shadow.to_raw(),
            tables: &tables,
        };
        refine.encode(ctx, encoder, &uniforms)?;
        pass.encode_refined(ctx, encoder, &refine, &uniforms)?;
        Ok(DepthOutput {
            pass,
            tables: Some(tables),
        })
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
    pub(super) tables: Option<&'a [f32]>,
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
    let table_buf = inputs.tables.map(|t| {
        let b = table_buffer(device, (t.len() * 4) as u64);
        ctx.queue.write_buffer(&b, 0, bytemuck::cast_slice(t));
        b
    });
    let mut lookup_entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: lookup_buffer.as_entire_binding(),
    }];
    if let Some(b) = &table_buf {
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
