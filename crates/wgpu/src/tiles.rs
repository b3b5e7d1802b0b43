//! Tiled cube maps (`shadowmap_paraboloid::TiledCube`) in the backend: the blocks
//! of the atlas's depth pass, one per tile, and the lookup's block and tile data.
//!
//! The depth pass draws every tile into its square of one depth layer (a viewport
//! and scissor of the tile's side, its face's projection cropped to the tile,
//! [`TiledCube::tile_clip_from_world`]); the atlas is stored in the top-left corner
//! of a square texture of the atlas's larger side. The lookup (`lookup_tiles.wgsl`)
//! selects the face, the cell and its tile, and reads the tile's square.
//!
//! ```
//! use shadowmap_wgpu::tiles::TiledLookupRaw;
//! // Six face matrices, then the counts and parameters: whole 16-byte rows.
//! assert_eq!(core::mem::size_of::<TiledLookupRaw>(), 6 * 64 + 32);
//! ```

use bytemuck::{Pod, Zeroable};
use shadowmap_paraboloid::TiledCube;

use crate::uniforms::{MatrixShadowRaw, ToRaw};

/// Values per tile in the lookup's tile data.
pub const TILE_VALUES: usize = 8;

/// The lookup block of a tiled cube map: WGSL `TiledShadow`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TiledLookupRaw {
    /// Each kept face's lookup matrix (texture space, divide by `w`), layer order;
    /// unused entries zero.
    pub uv_from_world: [[[f32; 4]; 4]; 6],
    /// `x`: kept faces; `y`: cells per face side; `z`: where the cell table starts
    /// in the tile data; `w`: 0.
    pub counts: [u32; 4],
    /// `x`: guard border in texels; `y`: the depth texture's side in texels.
    pub params: [f32; 4],
}

/// One tile's draw in the atlas's depth pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileDraw {
    /// The tile's block: its cropped projection (`clip_from_world`) and its face's
    /// lookup matrix.
    pub block: MatrixShadowRaw,
    /// Top-left corner of the tile's square (border included), in texels.
    pub offset: [u32; 2],
    /// Side of the square, in texels.
    pub side: u32,
}

/// What the backend uploads for a tiled cube map.
#[derive(Clone, Debug, PartialEq)]
pub struct TiledUniforms {
    /// The lookup's block.
    pub lookup: TiledLookupRaw,
    /// The lookup's tile data: [`TILE_VALUES`] per tile (offset x, y, interior side,
    /// span, first cell column, row, 0, 0), then each cell's tile index (face by
    /// face, rows top to bottom), all whole numbers.
    pub data: Vec<f32>,
    /// One draw per tile, in tile order.
    pub draws: Vec<TileDraw>,
}

/// The blocks of `tiled` for a depth texture of `texture_side` texels per side (at
/// least the atlas's larger side).
#[must_use]
pub fn tiled_uniforms(tiled: &TiledCube, texture_side: u32) -> TiledUniforms {
    let mut lookup = TiledLookupRaw::zeroed();
    let faces = tiled.cube.layers().min(6);
    for (layer, m) in (0..faces).zip(&mut lookup.uv_from_world) {
        if let Some(t) = tiled.cube.transform(layer) {
            *m = t.uv_from_world.to_cols_array_2d();
        }
    }
    let table_start = tiled.tiles.len() * TILE_VALUES;
    lookup.counts = [faces, tiled.grid, table_start as u32, 0];
    lookup.params = [tiled.border as f32, texture_side.max(1) as f32, 0.0, 0.0];
    let mut data = Vec::with_capacity(table_start + tiled.table.len());
    for t in &tiled.tiles {
        data.extend(
            [
                t.offset[0],
                t.offset[1],
                t.side,
                t.span,
                t.cell[0],
                t.cell[1],
                0,
                0,
            ]
            .map(|x| x as f32),
        );
    }
    data.extend(tiled.table.iter().map(|&i| i as f32));
    let draws = (0..tiled.tiles.len())
        .filter_map(|i| {
            let t = tiled.tiles.get(i)?;
            let mut block = tiled.cube.transform(t.layer)?.to_raw();
            block.clip_from_world = tiled.tile_clip_from_world(i)?.to_cols_array_2d();
            let (offset, side) = tiled.tile_viewport(i)?;
            Some(TileDraw {
                block,
                offset,
                side,
            })
        })
        .collect();
    TiledUniforms {
        lookup,
        data,
        draws,
    }
}
