//! The atlas pass of a tiled cube map: every tile drawn into its square of one depth
//! layer, each with only the casters binned to it ([`crate::tiles::tile_bins`]).

use super::{DepthTechnique, MeshBuffers, ShadowDepthPass, make_bind_group};
use crate::tiles::{TileBins, TileDraw};
use crate::{BackendError, GpuContext};

impl ShadowDepthPass {
    /// Draws the tiles of an atlas (a tiled cube map,
    /// [`crate::tiles::tiled_uniforms`]) into layer 0 of a one-layer matrix pass:
    /// one render pass, cleared once, each tile through its own block into its
    /// square (viewport and scissor). With `bins`, each tile draws only its range of
    /// the bins' indices into `mesh` (the casters that can touch it); without, the
    /// whole mesh. The uniform buffer grows to one block per tile.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a pass that is not a one-layer matrix pass,
    /// no tiles, a tile past the texture, or bins for another tile count.
    pub fn encode_tiles(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        mesh: &MeshBuffers,
        draws: &[TileDraw],
        bins: Option<&TileBins>,
    ) -> Result<(), BackendError> {
        self.check_tiles(draws, bins)?;
        self.upload_tiles(ctx, draws, bins);
        let mut pass = self.begin_layer(encoder, 0);
        pass.set_vertex_buffer(0, mesh.vertices.slice(..));
        match (bins, &self.tile_indices) {
            (Some(_), Some(indices)) => {
                pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
            }
            _ => pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32),
        }
        for (i, d) in draws.iter().enumerate() {
            let range = bins.map_or(0..mesh.index_count, |b| b.ranges[i].clone());
            if range.is_empty() {
                continue;
            }
            let [x, y] = d.offset;
            pass.set_viewport(x as f32, y as f32, d.side as f32, d.side as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, d.side, d.side);
            pass.set_bind_group(0, &self.bind_group, &[(self.slot * i as u64) as u32]);
            pass.draw_indexed(range, 0, 0..1);
        }
        Ok(())
    }

    /// The checks of [`ShadowDepthPass::encode_tiles`].
    fn check_tiles(&self, draws: &[TileDraw], bins: Option<&TileBins>) -> Result<(), BackendError> {
        if self.desc.technique != DepthTechnique::Matrix || self.desc.layers != 1 {
            return Err(BackendError::InvalidInput(
                "tiles are drawn by a one-layer matrix pass",
            ));
        }
        let side = self.desc.resolution;
        let inside = |d: &TileDraw| {
            d.side > 0
                && d.offset
                    .iter()
                    .all(|&o| o.checked_add(d.side).is_some_and(|e| e <= side))
        };
        if draws.is_empty() || !draws.iter().all(inside) {
            return Err(BackendError::InvalidInput(
                "a tile outside the depth texture",
            ));
        }
        let count = bins.map_or(draws.len(), |b| b.ranges.len());
        let in_bins = |b: &TileBins| b.ranges.iter().all(|r| r.end as usize <= b.indices.len());
        if count != draws.len() || !bins.is_none_or(in_bins) {
            return Err(BackendError::InvalidInput("bins for another tile count"));
        }
        Ok(())
    }

    /// Queues one block per tile (growing the uniform buffer) and the bins' indices
    /// (growing their buffer).
    fn upload_tiles(&mut self, ctx: &GpuContext, draws: &[TileDraw], bins: Option<&TileBins>) {
        let bytes = self.slot * draws.len() as u64;
        if self.uniforms.size() < bytes {
            self.uniforms = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadowmap depth uniforms"),
                size: bytes,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            self.bind_group =
                make_bind_group(&ctx.device, &self.layout, &self.uniforms, self.block, None);
        }
        let mut blocks = vec![0u8; bytes as usize];
        for (chunk, d) in blocks.chunks_mut(self.slot as usize).zip(draws) {
            let raw = bytemuck::bytes_of(&d.block);
            chunk[..raw.len()].copy_from_slice(raw);
        }
        ctx.queue.write_buffer(&self.uniforms, 0, &blocks);
        let Some(bins) = bins.filter(|b| !b.indices.is_empty()) else {
            return;
        };
        let bytes: &[u8] = bytemuck::cast_slice(&bins.indices);
        let size = self.tile_indices.as_ref().map_or(0, wgpu::Buffer::size);
        if size < bytes.len() as u64 {
            self.tile_indices = Some(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadowmap tile indices"),
                size: (bytes.len() as u64).next_multiple_of(4),
                usage: wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        if let Some(buffer) = &self.tile_indices {
            ctx.queue.write_buffer(buffer, 0, bytes);
        }
    }
}
