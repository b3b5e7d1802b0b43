//! Tiled cube maps (`shadowmap_paraboloid::TiledCube`) in the backend: the blocks
//! of the atlas's depth pass, one per tile, and the lookup's block and tile data.
//!
//! The depth pass draws every tile into its square of one depth layer (a viewport
//! and scissor of the tile's side, its face's projection cropped to the tile,
//! [`TiledCube::tile_clip_from_world`]); the atlas is stored in the top-left corner
//! of a square texture of the atlas's larger side. The lookup (`lookup_tiles.wgsl`)
//! selects the face, the cell and its tile, and reads the tile's square. Each tile
//! draws only the casters that can touch it ([`tile_bins`]), so the pass costs
//! about one draw of the casters in all, not one per tile.
//!
//! ```
//! use shadowmap_wgpu::tiles::TiledLookupRaw;
//! // Six face matrices, then the counts and parameters: whole 16-byte rows.
//! assert_eq!(core::mem::size_of::<TiledLookupRaw>(), 6 * 64 + 32);
//! ```

use core::ops::Range;

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
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

/// The scene's caster triangles binned by tile: for each tile, the vertex indices
/// (triangle `t`: `3t`, `3t + 1`, `3t + 2`, as
/// [`MeshBuffers::from_triangles`](crate::depth::MeshBuffers::from_triangles) lays
/// them out) of the triangles whose projection onto the tile's face can reach the
/// tile's cells or border.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TileBins {
    /// Every tile's indices, tile after tile.
    pub indices: Vec<u32>,
    /// Each tile's range in `indices`, in tile order.
    pub ranges: Vec<Range<u32>>,
}

/// Margin added to a triangle's bounding rectangle in face `uv`: the `f32`
/// projection's rounding.
const BIN_MARGIN: f32 = 1e-4;

/// Bins `triangles` into the tiles of `tiled` (conservatively: by the bounding
/// rectangle of the triangle's projection onto each kept face, widened by the
/// widest border of the face's tiles; a triangle that crosses a face's plane goes
/// to every tile of that face).
#[must_use]
pub fn tile_bins(tiled: &TiledCube, triangles: &[[Vec3; 3]]) -> TileBins {
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); tiled.tiles.len()];
    let mut last = vec![u32::MAX; tiled.tiles.len()];
    let g = tiled.grid.max(1);
    for layer in 0..tiled.cube.layers() {
        let Some(transform) = tiled.cube.transform(layer) else {
            continue;
        };
        let pad = face_border(tiled, layer) + BIN_MARGIN;
        for (t, tri) in (0u32..).zip(triangles) {
            let Some((lo, hi)) = face_rect(transform.uv_from_world, tri) else {
                continue;
            };
            let (lo, hi) = (lo - pad, hi + pad);
            if hi.cmplt(Vec2::ZERO).any() || lo.cmpgt(Vec2::ONE).any() {
                continue;
            }
            let cell = |x: f32| ((x * g as f32).floor().max(0.0) as u32).min(g - 1);
            for row in cell(lo.y)..=cell(hi.y) {
                for col in cell(lo.x)..=cell(hi.x) {
                    let entry = ((layer * g + row) * g + col) as usize;
                    let Some(&tile) = tiled.table.get(entry) else {
                        continue;
                    };
                    let tile = tile as usize;
                    if tile < lists.len() && last[tile] != t {
                        last[tile] = t;
                        lists[tile].extend([3 * t, 3 * t + 1, 3 * t + 2]);
                    }
                }
            }
        }
    }
    let mut bins = TileBins {
        indices: Vec::with_capacity(lists.iter().map(Vec::len).sum()),
        ranges: Vec::with_capacity(lists.len()),
    };
    for list in lists {
        let start = bins.indices.len() as u32;
        bins.indices.extend(list);
        bins.ranges.push(start..bins.indices.len() as u32);
    }
    bins
}

/// The widest border of the tiles of face `layer`, in face `uv`.
fn face_border(tiled: &TiledCube, layer: u32) -> f32 {
    let g = tiled.grid.max(1) as f32;
    tiled
        .tiles
        .iter()
        .filter(|t| t.layer == layer)
        .map(|t| tiled.border as f32 * t.span as f32 / (t.side.max(1) as f32 * g))
        .fold(0.0, f32::max)
}

/// The bounding rectangle in face `uv` of a triangle's projection by
/// `uv_from_world` (divide by `w`): `None` when it lies behind the face's plane, the
/// whole face when it crosses it.
fn face_rect(uv_from_world: glam::Mat4, tri: &[Vec3; 3]) -> Option<(Vec2, Vec2)> {
    let h = tri.map(|p| uv_from_world * p.extend(1.0));
    if h.iter().all(|h| !(h.w > 0.0)) {
        return None;
    }
    if !h.iter().all(|h| h.w > 0.0) {
        return Some((Vec2::ZERO, Vec2::ONE));
    }
    let uv = h.map(|h| Vec2::new(h.x, h.y) / h.w);
    let lo = uv[0].min(uv[1]).min(uv[2]);
    let hi = uv[0].max(uv[1]).max(uv[2]);
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}
