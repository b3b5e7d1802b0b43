//! Tiled cube maps: each kept face of a focused [`CubeMap`] cut into a grid of tiles,
//! each tile as many texels as the eye's samples in it need, all tiles packed into
//! one atlas (Arvo, *Tiled Shadow Maps*, CGI 2004; the page-based virtual shadow maps
//! of current engines choose each page's resolution the same way).
//!
//! A cube map, even with faces sized by need, gives every texel of a face the same
//! size, and a warp of the face (RTW) only moves texels along whole rows and columns:
//! the texels a row needs for its nearest receiver are spent along the whole row,
//! over walls the eye never sees. A tile spends its texels on its own cell only.
//!
//! ```text
//! cell c of face f:  uv in [col, col + 1] / grid  x  [row, row + 1] / grid
//! side_c = clamp(ceil(k * density_c / grid), 1, ..)     interior texels per side
//! tile_c = side_c + 2 * border                           texels per side, stored
//! ```
//!
//! with `density_c` the texels per unit of the face's `uv` the cell needs (the
//! caller's measure, e.g. the largest extent of one unit of `uv` on the screen over
//! the samples of the cell, in pixels) and `k` the largest scale whose packed atlas
//! fits the budget. Every cell of a kept face has a tile (at least one texel
//! inside), so the tiles cover the face's window as the face does. The border is
//! the same projection continued past the cell: a filter that reaches up to
//! `border` texels beyond a cell reads depths of its own neighbourhood.

use alloc::vec::Vec;

use glam::{DMat4, DVec2, DVec3, DVec4, Mat4};
use shadowmap_frustum::{ShadowMapping, ShadowSample, math};

use crate::ParaboloidError;
use crate::cube::CubeMap;
use crate::cube_sizes::{area, shelves};

/// Largest tile grid per face side.
pub const MAX_TILE_GRID: u32 = 64;

/// Largest guard border of a tile, in texels.
pub const MAX_TILE_BORDER: u32 = 8;

/// Largest atlas side, in texels.
const MAX_SIDE: u32 = shadowmap_frustum::MAX_RESOLUTION;

/// How [`TiledCube::new`] cuts the faces into tiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TileOptions {
    /// Cells per face side, a power of two in `1..=`[`MAX_TILE_GRID`]. Default 16.
    pub grid: u32,
    /// Guard texels around each tile's cells, `0..=`[`MAX_TILE_BORDER`]: the depth of
    /// the surroundings, for filters that reach past the cells (hardware 2x2
    /// comparison needs 1, a PCF of 2x2 comparisons over a radius of `r` texels
    /// `r + 1`). Default 2.
    pub border: u32,
}

impl Default for TileOptions {
    fn default() -> Self {
        Self {
            grid: 16,
            border: 2,
        }
    }
}

impl TileOptions {
    /// With this many cells per face side.
    #[must_use]
    pub const fn with_grid(mut self, grid: u32) -> Self {
        self.grid = grid;
        self
    }

    /// With this guard border.
    #[must_use]
    pub const fn with_border(mut self, border: u32) -> Self {
        self.border = border;
        self
    }

    /// # Errors
    /// [`ParaboloidError::InvalidOptions`] for a grid that is not a power of two in
    /// `1..=`[`MAX_TILE_GRID`] or a border above [`MAX_TILE_BORDER`].
    pub fn validate(&self) -> Result<(), ParaboloidError> {
        if self.grid.is_power_of_two()
            && self.grid <= MAX_TILE_GRID
            && self.border <= MAX_TILE_BORDER
        {
            Ok(())
        } else {
            Err(ParaboloidError::InvalidOptions)
        }
    }
}

/// One tile of a [`TiledCube`]: a square block of a face's cells, stored as a square
/// of the atlas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CubeTile {
    /// The face's layer in the cube.
    pub layer: u32,
    /// Column and row of the tile's first (top-left) cell.
    pub cell: [u32; 2],
    /// Cells per side of the tile (a power of two).
    pub span: u32,
    /// Texels per side inside the border, at least 1.
    pub side: u32,
    /// Top-left corner of the tile, border included, in atlas texels.
    pub offset: [u32; 2],
}

/// A cube map whose kept faces are each cut into `grid x grid` cells, the cells
/// grouped into square tiles of their own sizes, packed into one atlas (see the
/// module docs).
///
/// [`ShadowMapping::map_point`] gives the tile's texture coordinates with the tile's
/// index as the layer (the cube's face and `uv`, the cell under it, the cell's tile);
/// [`TiledCube::atlas_sample`] places them in the atlas.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TiledCube {
    /// The cube map: its faces' windows, matrices and depth ranges (its own sizes
    /// and atlas are not used).
    pub cube: CubeMap,
    /// Cells per face side.
    pub grid: u32,
    /// Guard texels around each tile.
    pub border: u32,
    /// The tiles.
    pub tiles: Vec<CubeTile>,
    /// The tile of every cell, face by face (layer order), rows top to bottom,
    /// columns left to right: entry `(layer * grid + row) * grid + col`.
    pub table: Vec<u32>,
    /// Width and height of the atlas in texels; its area is what the map costs
    /// ([`TiledCube::texels`]). A renderer that stores it in a square texture of
    /// its larger side (as `shadowmap-wgpu` does) allocates more.
    pub atlas: [u32; 2],
}

impl TiledCube {
    /// Cuts the faces of `cube` into cells with the texel densities `densities` (one
    /// per cell, in [`TiledCube::table`] order: the texels per unit of face `uv` the
    /// cell needs; zero, negative, non-finite or missing: no need, the smallest
    /// tile), groups them into tiles and packs the tiles into an atlas of at most
    /// `budget` texels.
    ///
    /// Four neighbouring tiles of one face (a quadtree's children) become one
    /// tile, at the largest of their densities, where that costs no more texels at
    /// the scale the separate cells would get: uniform regions pay one border, not
    /// one per cell. Of the grids from `options.grid` down to one cell per face
    /// (halving; a coarser cell needs the most of the cells it covers), the one whose
    /// tiles get the most texels per unit of need is kept: with a small budget the
    /// borders of many small tiles cost more than coarser cells waste. A grid whose
    /// smallest tiles would take more than half the budget is not tried.
    ///
    /// # Errors
    /// [`ParaboloidError::InvalidOptions`] for invalid `options` or a budget below
    /// twice one smallest tile per face.
    pub fn new(
        cube: CubeMap,
        options: &TileOptions,
        densities: &[f64],
        budget: u64,
    ) -> Result<Self, ParaboloidError> {
        options.validate()?;
        let faces = cube.faces.len();
        let border = options.border;
        let smallest = |g: u32| faces as u64 * u64::from(g * g) * u64::from(1 + 2 * border).pow(2);
        let mut best: Option<Built> = None;
        let mut grid = options.grid;
        loop {
            if faces > 0 && 2 * smallest(grid) <= budget {
                let built = Built::new(densities, faces, options, grid, budget);
                if best.as_ref().is_none_or(|b| built.scale > b.scale) {
                    best = Some(built);
                }
            }
            if grid <= 1 {
                break;
            }
            grid /= 2;
        }
        let built = best.ok_or(ParaboloidError::InvalidOptions)?;
        Ok(Self {
            cube,
            grid: built.grid,
            border,
            tiles: built.tiles,
            table: built.table,
            atlas: built.atlas,
        })
    }

    /// Layers of [`ShadowMapping::map_point`]'s samples: one per tile.
    #[must_use]
    pub fn layers(&self) -> u32 {
        u32::try_from(self.tiles.len()).unwrap_or(u32::MAX)
    }

    /// The largest stored side of a tile (border included), in texels.
    #[must_use]
    pub fn largest_tile(&self) -> u32 {
        self.tiles
            .iter()
            .map(|t| t.side + 2 * self.border)
            .max()
            .unwrap_or(0)
    }

    /// Texels of the atlas: what the map costs, gaps between the tiles included.
    #[must_use]
    pub fn texels(&self) -> u64 {
        area(self.atlas)
    }

    /// The index of the tile holding face `uv` of `layer` (clamped to the face's
    /// cells); `None` past the last layer or the table (a value read from elsewhere).
    #[must_use]
    pub fn tile_index(&self, layer: u32, uv: DVec2) -> Option<usize> {
        if layer >= self.cube.layers() || self.grid == 0 {
            return None;
        }
        let g = f64::from(self.grid);
        let cell = |x: f64| (math::floor(x * g).max(0.0) as u32).min(self.grid - 1);
        let (col, row) = (cell(uv.x), cell(uv.y));
        let entry = self
            .table
            .get(((layer * self.grid + row) * self.grid + col) as usize)?;
        Some(*entry as usize)
    }

    /// The face `uv` rectangle tile `index` stores, border included (`min`, `max`).
    fn stored_uv(&self, index: usize) -> Option<(DVec2, DVec2)> {
        let t = self.tiles.get(index)?;
        let g = f64::from(self.grid);
        let span = f64::from(t.span);
        let border = f64::from(self.border) * span / (f64::from(t.side) * g);
        let lo = DVec2::new(f64::from(t.cell[0]), f64::from(t.cell[1])) / g;
        Some((lo - border, lo + span / g + border))
    }

    /// The depth pass of tile `index`: its face's `clip_from_world` cropped to the
    /// tile (cells and border), for a viewport of the tile's square in the atlas
    /// ([`TiledCube::tile_viewport`]):
    ///
    /// ```text
    /// ndc' = (ndc - centre) / half      centre, half: the stored rectangle in ndc
    /// ```
    #[must_use]
    pub fn tile_clip_from_world(&self, index: usize) -> Option<Mat4> {
        let (lo, hi) = self.stored_uv(index)?;
        let face = self.cube.faces.get(self.tiles.get(index)?.layer as usize)?;
        // uv -> ndc: x = 2u - 1, y = 1 - 2v.
        let ndc = |uv: DVec2| DVec2::new(2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y);
        let (a, b) = (ndc(lo), ndc(hi));
        let centre = (a + b) * 0.5;
        let half = (b - a).abs() * 0.5;
        let crop = DMat4::from_cols(
            DVec4::new(1.0 / half.x, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / half.y, 0.0, 0.0),
            DVec4::Z,
            DVec4::new(-centre.x / half.x, -centre.y / half.y, 0.0, 1.0),
        );
        let clip = (crop * face.clip_from_world.as_dmat4()).as_mat4();
        clip.is_finite().then_some(clip)
    }

    /// The square of tile `index` in the atlas, border included: top-left corner
    /// and side, in texels.
    #[must_use]
    pub fn tile_viewport(&self, index: usize) -> Option<([u32; 2], u32)> {
        let t = self.tiles.get(index)?;
        Some((t.offset, t.side + 2 * self.border))
    }

    /// A face sample of the cube ([`CubeMap`]'s `map_point`: face `uv`, its layer)
    /// in its tile: the tile's index as the layer, `uv` across the tile's stored
    /// square (border included):
    ///
    /// ```text
    /// uv_tile = (border + (uv * grid - cell) / span * side) / (side + 2 border)
    /// ```
    #[must_use]
    pub fn tile_sample(&self, sample: ShadowSample) -> Option<ShadowSample> {
        let index = self.tile_index(sample.layer, sample.uv)?;
        let t = self.tiles.get(index)?;
        let g = f64::from(self.grid);
        let cell = DVec2::new(f64::from(t.cell[0]), f64::from(t.cell[1]));
        let within = (sample.uv * g - cell) / f64::from(t.span);
        let border = f64::from(self.border);
        let side = f64::from(t.side);
        let uv = (within * side + border) / (side + 2.0 * border);
        let layer = u32::try_from(index).ok()?;
        uv.is_finite().then_some(ShadowSample {
            uv,
            layer,
            ..sample
        })
    }

    /// A sample of [`ShadowMapping::map_point`] (a tile's `uv`, the tile as its
    /// layer) in the atlas's texture coordinates, layer 0:
    ///
    /// ```text
    /// uv_atlas = (offset + uv_tile * (side + 2 border)) / atlas
    /// ```
    #[must_use]
    pub fn atlas_sample(&self, sample: ShadowSample) -> Option<ShadowSample> {
        let tile = self.tiles.get(sample.layer as usize)?;
        let pair = |p: [u32; 2]| DVec2::new(f64::from(p[0]), f64::from(p[1]));
        let stored = f64::from(tile.side + 2 * self.border);
        let uv = (pair(tile.offset) + sample.uv * stored) / pair(self.atlas);
        uv.is_finite().then_some(ShadowSample {
            uv,
            layer: 0,
            ..sample
        })
    }
}

impl ShadowMapping for TiledCube {
    /// The cube's sample ([`CubeMap`]'s face selection) in its tile
    /// ([`TiledCube::tile_sample`]: each tile is a layer of its own, the atlas is
    /// where they are stored, [`TiledCube::atlas_sample`]).
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        self.tile_sample(self.cube.map_point(world)?)
    }
}

/// The tiles of one grid, merged and packed.
struct Built {
    grid: u32,
    /// Interior texels per side per unit of a tile's wanted side: the texels per
    /// unit of need every tile gets.
    scale: f64,
    tiles: Vec<CubeTile>,
    table: Vec<u32>,
    atlas: [u32; 2],
}

impl Built {
    /// The cells of `grid x grid` per face (densities given for `options.grid`),
    /// merged where that saves texels, packed into the budget.
    fn new(densities: &[f64], faces: usize, options: &TileOptions, grid: u32, budget: u64) -> Self {
        let border = options.border;
        let cells = coarse_densities(densities, faces, options.grid, grid);
        // The scale every cell on its own would get decides the merges.
        let unit = |d: f64, span: u32| d * f64::from(span) / f64::from(grid);
        let alone: Vec<f64> = cells.iter().map(|d| unit(*d, 1)).collect();
        let scale = Layout::fit(&alone, border, budget).scale;
        let price = |t: &mut Node| {
            let side = math::ceil(scale * unit(t.density, t.span)).max(1.0) + f64::from(2 * border);
            t.cost = side * side;
        };
        let mut found = Vec::new();
        let per_face = (grid * grid) as usize;
        for layer in 0..faces as u32 {
            let first = layer as usize * per_face;
            merge_face(
                &cells[first..first + per_face],
                grid,
                price,
                &mut |cell, span, density| {
                    found.push((layer, cell, span, density));
                },
            );
        }
        let wanted: Vec<f64> = found.iter().map(|t| unit(t.3, t.2)).collect();
        let layout = Layout::fit(&wanted, border, budget);
        let tiles: Vec<CubeTile> = found
            .iter()
            .zip(&layout.placed)
            .map(|(&(layer, cell, span, _), &(side, offset))| CubeTile {
                layer,
                cell,
                span,
                side,
                offset,
            })
            .collect();
        let mut table = alloc::vec![0u32; faces * per_face];
        for (i, t) in tiles.iter().enumerate() {
            for row in t.cell[1]..t.cell[1] + t.span {
                for col in t.cell[0]..t.cell[0] + t.span {
                    table[((t.layer * grid + row) * grid + col) as usize] = i as u32;
                }
            }
        }
        Self {
            grid,
            scale: layout.scale,
            tiles,
            table,
            atlas: layout.atlas,
        }
    }
}

/// The densities of `faces` faces of `grid x grid` cells from those of `given x
/// given` cells (`given` a multiple of `grid`): each cell the largest valid density
/// of the cells it covers, 0 without one.
fn coarse_densities(densities: &[f64], faces: usize, given: u32, grid: u32) -> Vec<f64> {
    let ratio = given / grid;
    let mut out = alloc::vec![0.0f64; faces * (grid * grid) as usize];
    for (i, d) in out.iter_mut().enumerate() {
        let per_face = (grid * grid) as usize;
        let layer = (i / per_face) as u32;
        let (row, col) = (
            ((i % per_face) as u32) / grid,
            ((i % per_face) as u32) % grid,
        );
        for r in row * ratio..(row + 1) * ratio {
            for c in col * ratio..(col + 1) * ratio {
                let at = ((layer * given + r) * given + c) as usize;
                let x = densities.get(at).copied().unwrap_or(0.0);
                if x.is_finite() && x > 0.0 {
                    *d = d.max(x);
                }
            }
        }
    }
    out
}

/// Places the tiles of `placed` (interior side, corner) in `order` on shelves of
/// `width` texels ([`shelves`], borders included); returns the shelves' height.
fn place_tiles(placed: &mut [(u32, [u32; 2])], order: &[usize], border: u32, width: u64) -> u64 {
    let stored: Vec<u64> = placed.iter().map(|p| u64::from(p.0 + 2 * border)).collect();
    shelves(
        order,
        |i| [stored[i], stored[i]],
        width,
        |i, at| placed[i].1 = at,
    )
}

/// A tile of the quadtree while [`merge_face`] builds it.
#[derive(Clone, Copy, Debug, Default)]
struct Node {
    density: f64,
    span: u32,
    /// Texels of the tile as it is, border included.
    cost: f64,
}

/// Groups the cells of one face (`grid x grid` densities) bottom-up into square
/// tiles: four sibling tiles become their parent, at the largest of their
/// densities, where the parent costs no more texels than they do together
/// (`price` fills a node's costs). Calls `emit(first cell, span, density)` for each
/// final tile.
fn merge_face(
    cells: &[f64],
    grid: u32,
    price: impl Fn(&mut Node),
    emit: &mut impl FnMut([u32; 2], u32, f64),
) {
    // Nodes of the current level, `None` where the level's block was split.
    let mut level: Vec<Option<Node>> = cells
        .iter()
        .map(|&density| {
            let mut n = Node {
                density,
                span: 1,
                ..Node::default()
            };
            price(&mut n);
            Some(n)
        })
        .collect();
    let mut side = grid;
    while side > 1 {
        let half = side / 2;
        let mut parents = Vec::with_capacity((half * half) as usize);
        for row in 0..half {
            for col in 0..half {
                let at = |r: u32, c: u32| level[((2 * row + r) * side + 2 * col + c) as usize];
                let kids = [at(0, 0), at(0, 1), at(1, 0), at(1, 1)];
                let parent = merged(&kids, &price);
                if parent.is_none() {
                    for (k, kid) in kids.iter().enumerate() {
                        if let Some(n) = kid {
                            let (r, c) = (2 * row + k as u32 / 2, 2 * col + k as u32 % 2);
                            emit([c * n.span, r * n.span], n.span, n.density);
                        }
                    }
                }
                parents.push(parent);
            }
        }
        level = parents;
        side = half;
    }
    if let Some(Some(root)) = level.first() {
        emit([0, 0], root.span, root.density);
    }
}

/// The parent of four sibling tiles, `None` unless all four are whole tiles and
/// the parent at their largest density costs no more than they do.
fn merged(kids: &[Option<Node>; 4], price: &impl Fn(&mut Node)) -> Option<Node> {
    let mut density = 0.0f64;
    let mut apart = 0.0;
    for kid in kids {
        let n = (*kid)?;
        density = density.max(n.density);
        apart += n.cost;
    }
    let span = kids[0]?.span * 2;
    let mut parent = Node {
        density,
        span,
        ..Node::default()
    };
    price(&mut parent);
    (parent.cost <= apart).then_some(parent)
}

/// Tile sides and places of one scale.
struct Layout {
    /// The scale: interior texels per side per unit of a tile's wanted side.
    scale: f64,
    /// Per tile: interior side and top-left corner (border included).
    placed: Vec<(u32, [u32; 2])>,
    atlas: [u32; 2],
}

impl Layout {
    /// The largest scale `k` of `wanted` (interior texels per side at `k = 1`)
    /// whose packed atlas fits `budget`; the smallest tiles when none does.
    fn fit(wanted: &[f64], border: u32, budget: u64) -> Self {
        // Highest tiles first: the order does not depend on the scale.
        let mut order: Vec<usize> = (0..wanted.len()).collect();
        order.sort_by(|a, b| wanted[*b].total_cmp(&wanted[*a]).then(a.cmp(b)));
        let at = |k: f64| Self::pack(wanted, &order, k, border);
        let fits = |l: &Self| l.atlas[0] > 0 && area(l.atlas) <= budget;
        let total: f64 = wanted.iter().map(|d| d * d).sum();
        let mut hi = if total > 0.0 {
            math::sqrt(budget as f64 / total) + 1.0
        } else {
            1.0
        };
        let mut lo = 0.0;
        while fits(&at(hi)) && hi < 1e30 {
            lo = hi;
            hi *= 2.0;
        }
        for _ in 0..32 {
            let mid = 0.5 * (lo + hi);
            if fits(&at(mid)) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        at(lo)
    }

    /// Shelf packing of the tiles at scale `k` in `order` (highest first): of the
    /// shelf widths from the side of a square of the tiles' area up to twice it, the
    /// one whose atlas is smallest (then the squarest). `atlas` is `[0, 0]` past the
    /// largest texture side.
    fn pack(wanted: &[f64], order: &[usize], k: f64, border: u32) -> Self {
        let side = |d: f64| -> u32 {
            let s = math::ceil(k * d);
            if s.is_finite() && s >= 1.0 {
                (s.min(f64::from(MAX_SIDE))) as u32
            } else {
                1
            }
        };
        let mut placed: Vec<(u32, [u32; 2])> = wanted.iter().map(|d| (side(*d), [0, 0])).collect();
        let stored = |s: u32| u64::from(s + 2 * border);
        let total: u64 = placed.iter().map(|p| stored(p.0) * stored(p.0)).sum();
        let widest = placed.iter().map(|p| stored(p.0)).max().unwrap_or(1);
        let square = (math::ceil(math::sqrt(total as f64)) as u64).max(widest);
        let width = (0..=10)
            .map(|step| square + square * step / 10)
            .min_by_key(|&w| {
                let height = place_tiles(&mut placed, order, border, w);
                (w * height, w.max(height), w)
            })
            .unwrap_or(square);
        let height = place_tiles(&mut placed, order, border, width);
        let max = u64::from(MAX_SIDE);
        let atlas = if width <= max && height <= max {
            [width as u32, height as u32]
        } else {
            [0, 0]
        };
        Self {
            scale: k,
            placed,
            atlas,
        }
    }
}

#[cfg(test)]
mod tests;
