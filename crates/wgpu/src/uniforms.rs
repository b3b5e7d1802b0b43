//! Uniform blocks (`#[repr(C)]`, [`bytemuck::Pod`]) built from the math crates'
//! outputs by [`ToRaw::to_raw`].
//!
//! No math is repeated here: every field is copied from what a builder of
//! `shadowmap-frustum`, `shadowmap-warp`, `shadowmap-paraboloid` or `shadowmap-rtw`
//! computed; the WGSL evaluates only what must be evaluated per vertex or per pixel.
//!
//! Layout: every block is a whole number of 16-byte rows (`mat4x4<f32>` columns and
//! `vec4` rows), so `#[repr(C)]` and WGSL's uniform layout agree without hidden
//! padding; `tests/uniforms.rs` checks each size and offset against naga's layouter
//! and the WGSL struct of the same name.
//!
//! ```
//! use glam::{Mat4, Vec3};
//! use shadowmap_frustum::{LightDirection, ShadowTransform};
//! use shadowmap_wgpu::uniforms::ToRaw;
//!
//! let t = ShadowTransform::new(Mat4::IDENTITY, Mat4::IDENTITY, false, LightDirection::Directional(Vec3::NEG_Y));
//! let raw = t.to_raw();
//! assert_eq!(raw.uv_from_world, t.uv_from_world.to_cols_array_2d());
//! assert_eq!(bytemuck::bytes_of(&raw).len(), 144);
//! ```

use bytemuck::{Pod, Zeroable};
use glam::Mat4;
use shadowmap_frustum::{CascadeSet, LightDirection, MAX_CASCADES, ShadowTransform};
use shadowmap_paraboloid::{CubeMap, ParaboloidMap, ParaboloidUniform, Side};
use shadowmap_rtw::{RtwShadow, WarpMaps};
use shadowmap_warp::{LispsmShadow, TsmShadow, WarpedCascades, XpsmShadow};

/// Converts a math-crate result into the uniform block its shaders read.
pub trait ToRaw {
    /// The `#[repr(C)]` block.
    type Raw: Pod;
    /// The block.
    fn to_raw(&self) -> Self::Raw;
}

fn cols(m: &Mat4) -> [[f32; 4]; 4] {
    m.to_cols_array_2d()
}

fn flag(b: bool) -> f32 {
    f32::from(u8::from(b))
}

/// A matrix technique (uniform, one cascade, LiSPSM, XPSM, TSM): WGSL `MatrixShadow`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct MatrixShadowRaw {
    /// Depth pass, WebGPU clip space.
    pub clip_from_world: [[f32; 4]; 4],
    /// Lookup, texture space (divide by `w`).
    pub uv_from_world: [[f32; 4]; 4],
    /// `x`: reversed-Z (0 or 1); `y`: XPSM's `z_bias_scale = 1 / (MaxZ - MinZ)` (0 for
    /// the other techniques: their bias is applied in depth units after the
    /// division); `z`, `w`: 0.
    pub params: [f32; 4],
}

impl ToRaw for ShadowTransform {
    type Raw = MatrixShadowRaw;
    fn to_raw(&self) -> MatrixShadowRaw {
        MatrixShadowRaw {
            clip_from_world: cols(&self.clip_from_world),
            uv_from_world: cols(&self.uv_from_world),
            params: [flag(self.reversed_z), 0.0, 0.0, 0.0],
        }
    }
}

impl ToRaw for LispsmShadow {
    type Raw = MatrixShadowRaw;
    fn to_raw(&self) -> MatrixShadowRaw {
        self.transform.to_raw()
    }
}

impl ToRaw for TsmShadow {
    type Raw = MatrixShadowRaw;
    fn to_raw(&self) -> MatrixShadowRaw {
        self.transform.to_raw()
    }
}

impl ToRaw for XpsmShadow {
    type Raw = MatrixShadowRaw;
    /// With the step-18 Z bias scale in `params.y`: the lookup moves clip `z` by
    /// `-bias * z_bias_scale` (`+` reversed) before dividing by `w`, as
    /// [`XpsmShadow::biased_clip_z`] does.
    fn to_raw(&self) -> MatrixShadowRaw {
        let mut raw = self.transform.to_raw();
        raw.params[1] = self.z_bias_scale;
        raw
    }
}

/// Cascaded shadow maps for the lookup: WGSL `CascadeShadow`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct CascadeShadowRaw {
    /// One lookup matrix per cascade (unused entries zero).
    pub uv_from_world: [[[f32; 4]; 4]; MAX_CASCADES],
    /// Row 2 of the camera's `view_from_world`: view depth is `-dot(row, (P, 1))`.
    pub view_z_row: [f32; 4],
    /// Far split depth of cascade `i` (`CascadeSplits::depths()[i + 1]`), 4 per row.
    pub split_far: [[f32; 4]; 2],
    /// Blend band at the far end of cascade `i` (`CascadeSplits::band_width(i)`).
    pub band_width: [[f32; 4]; 2],
    /// Scale of layer `i`'s `uv` where its map fills only the top-left corner of
    /// the layer (cube faces of different sizes, see
    /// `CubeFace::clip_from_world_in_layer`): `(x, y)` of layer `2k` then of
    /// `2k + 1` in row `k`; 1 where the map fills the layer. Selection reads the
    /// unscaled `uv`.
    pub layer_uv_scale: [[f32; 4]; MAX_CASCADES / 2],
    /// Number of cascades.
    pub count: u32,
    /// Reversed-Z (0 or 1).
    pub reversed_z: u32,
    /// Cascade selection: 0 by view depth (with the blend band), 1 by projection.
    pub select_by_projection: u32,
    /// Margin for selection by projection, in texture coordinates (the margin in
    /// texels of `CascadeSet::select_by_projection` over the resolution).
    pub margin_uv: f32,
}

impl CascadeShadowRaw {
    /// No layer, every layer's map filling its layer (`layer_uv_scale` 1).
    #[must_use]
    pub fn unscaled() -> Self {
        Self {
            layer_uv_scale: [[1.0; 4]; MAX_CASCADES / 2],
            ..Self::zeroed()
        }
    }

    /// The cascades lookup of a cube map: one perspective `uv_from_world` per kept
    /// face, selected by projection without a margin (adjacent windows meet at the
    /// face edges), each face's `uv` scaled to its corner of a layer of the largest
    /// face's side ([`cube_layers`]).
    #[must_use]
    pub fn from_cube(cube: &CubeMap) -> Self {
        let mut raw = Self::unscaled();
        let side = cube.largest_side();
        for (layer, face) in cube.faces.iter().enumerate().take(MAX_CASCADES) {
            if let Some(t) = cube.transform(layer as u32) {
                raw.uv_from_world[layer] = cols(&t.uv_from_world);
            }
            let scale = face.uv_scale_in_layer(side);
            let row = &mut raw.layer_uv_scale[layer / 2];
            row[2 * (layer % 2)] = scale.x;
            row[2 * (layer % 2) + 1] = scale.y;
        }
        raw.count = cube.layers().min(MAX_CASCADES as u32);
        raw.reversed_z = u32::from(cube.reversed_z);
        raw.select_by_projection = 1;
        raw
    }

    /// Selection by projection (the finest map containing the point) instead of by
    /// view depth, with a margin of `margin_texels` texels of a `resolution²` map,
    /// as `CascadeSet::select_by_projection`. A non-finite or negative margin, or a
    /// zero resolution, gives no margin.
    #[must_use]
    pub fn with_selection_by_projection(mut self, margin_texels: f32, resolution: u32) -> Self {
        self.select_by_projection = 1;
        let m = f64::from(margin_texels) / f64::from(resolution.max(1));
        self.margin_uv = if m.is_finite() && resolution > 0 {
            m.max(0.0) as f32
        } else {
            0.0
        };
        self
    }
}

impl ToRaw for CascadeSet {
    type Raw = CascadeShadowRaw;
    fn to_raw(&self) -> CascadeShadowRaw {
        let mut raw = CascadeShadowRaw::unscaled();
        let depths = self.splits.depths();
        for (i, c) in self.cascades.iter().enumerate().take(MAX_CASCADES) {
            raw.uv_from_world[i] = cols(&c.transform.uv_from_world);
            raw.split_far[i / 4][i % 4] = depths.get(i + 1).copied().unwrap_or(f32::MAX);
            raw.band_width[i / 4][i % 4] = self.splits.band_width(i);
        }
        let row = self.view_from_world.row(2);
        raw.view_z_row = row.to_array();
        raw.count = self.cascades.len() as u32;
        raw.reversed_z = u32::from(
            self.cascades
                .first()
                .is_some_and(|c| c.transform.reversed_z),
        );
        raw
    }
}

/// The per-layer depth-pass blocks of a cascade set: one [`MatrixShadowRaw`] per
/// cascade (layer `i` = cascade `i`).
#[must_use]
pub fn cascade_layers(set: &CascadeSet) -> Vec<MatrixShadowRaw> {
    set.cascades.iter().map(|c| c.transform.to_raw()).collect()
}

/// The per-layer depth-pass blocks of a cube map: one [`MatrixShadowRaw`] per kept
/// face (layer `i` = face `i`), each face drawn into the top-left corner of a layer
/// of the largest face's side (`CubeFace::clip_from_world_in_layer`), so faces
/// sized by need keep their own texel density; with equal faces every face fills
/// its layer. Render at `CubeMap::largest_side` texels per layer for the fit's
/// densities.
#[must_use]
pub fn cube_layers(cube: &CubeMap) -> Vec<MatrixShadowRaw> {
    let side = cube.largest_side();
    (0..cube.layers())
        .zip(&cube.faces)
        .filter_map(|(layer, face)| {
            let mut raw = cube.transform(layer)?.to_raw();
            raw.clip_from_world = cols(&face.clip_from_world_in_layer(side));
            Some(raw)
        })
        .collect()
}

/// A depth-pass `clip_from_world` that sends every vertex to `(0, 0, -1, 1)`,
/// outside the clip volume: the layer of a warped cascade without a fit stays clear.
const CLIP_ALL: [[f32; 4]; 4] = [[0.0; 4], [0.0; 4], [0.0; 4], [0.0, 0.0, -1.0, 1.0]];

/// The per-layer depth-pass blocks of warped cascades: one [`MatrixShadowRaw`] per
/// cascade (layer `i` = cascade `i`) with its LiSPSM matrices; a cascade without a
/// fit draws nothing (its `clip_from_world` clips every vertex).
#[must_use]
pub fn warped_cascade_layers(set: &WarpedCascades) -> Vec<MatrixShadowRaw> {
    set.cascades
        .iter()
        .map(|c| {
            c.shadow.map_or(
                MatrixShadowRaw {
                    clip_from_world: CLIP_ALL,
                    ..MatrixShadowRaw::zeroed()
                },
                |s| s.to_raw(),
            )
        })
        .collect()
}

impl CascadeShadowRaw {
    /// The cascades lookup for warped cascades (`shadowmap_warp::warped_cascades`)
    /// seen by a camera with this `view_from_world`: cascade `i` is selected by view
    /// depth up to its `far`, blends toward `i + 1` across the band they share
    /// (`far_i - near_(i+1)`), and its perspective `uv_from_world` is divided by `w`
    /// in the lookup. A cascade without a fit keeps a zero matrix (`w = 0`: the
    /// lookup reports the point as not covered).
    #[must_use]
    pub fn from_warped(set: &WarpedCascades, view_from_world: Mat4) -> Self {
        let mut raw = Self::unscaled();
        for (i, c) in set.cascades.iter().enumerate().take(MAX_CASCADES) {
            if let Some(s) = &c.shadow {
                raw.uv_from_world[i] = cols(&s.transform.uv_from_world);
            }
            raw.split_far[i / 4][i % 4] = c.far;
            let band = set
                .cascades
                .get(i + 1)
                .map_or(0.0, |next| c.far - next.near);
            raw.band_width[i / 4][i % 4] = if band > 0.0 { band } else { 0.0 };
        }
        raw.view_z_row = view_from_world.row(2).to_array();
        raw.count = set.cascades.len().min(MAX_CASCADES) as u32;
        raw.reversed_z = u32::from(
            set.cascades
                .iter()
                .find_map(|c| c.shadow.as_ref())
                .is_some_and(|s| s.transform.reversed_z),
        );
        raw
    }
}

/// A paraboloid map: WGSL `Paraboloid` is
/// [`shadowmap_paraboloid::ParaboloidUniform`] itself (`Pod` through that crate's
/// `bytemuck` feature), built by [`ParaboloidMap::to_raw`].
impl ToRaw for ParaboloidMap {
    type Raw = ParaboloidUniform;
    fn to_raw(&self) -> ParaboloidUniform {
        ParaboloidMap::to_raw(self)
    }
}

/// One layer of the paraboloid depth pass: WGSL `ParaboloidLayer`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ParaboloidLayerRaw {
    /// The map.
    pub map: ParaboloidUniform,
    /// `x`: the side rendered, 0 front, 1 back; `y`: 0 from
    /// [`ParaboloidLayerRaw::new`], the depth pass writes its map resolution there
    /// (the vertex shader snaps to its subpixel grid); `z`, `w`: 0.
    pub side: [f32; 4],
    /// The side's warp tables in the pass's table buffer (RTW over the side,
    /// [`warped_paraboloid`]): `u` offset, `u` texels, `v` offset, `v` texels; all 0
    /// (no warp) from [`ParaboloidLayerRaw::new`].
    pub warp: [u32; 4],
}

impl ParaboloidLayerRaw {
    /// The block for one side of a map.
    #[must_use]
    pub fn new(map: &ParaboloidMap, side: Side) -> Self {
        Self {
            map: ToRaw::to_raw(map),
            side: [side.layer() as f32, 0.0, 0.0, 0.0],
            warp: [0; 4],
        }
    }
}

/// The depth-pass blocks of a paraboloid map, one per layer (front, then back for a
/// dual map).
#[must_use]
pub fn paraboloid_layers(map: &ParaboloidMap) -> Vec<ParaboloidLayerRaw> {
    let mut v = vec![ParaboloidLayerRaw::new(map, Side::Front)];
    if map.layers() > 1 {
        v.push(ParaboloidLayerRaw::new(map, Side::Back));
    }
    v
}

/// The lookup of a paraboloid map: WGSL `ParaboloidLookup`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ParaboloidLookupRaw {
    /// The map.
    pub map: ParaboloidUniform,
    /// Per side (front, back): its warp tables, as [`ParaboloidLayerRaw::warp`].
    pub warp: [[u32; 4]; 2],
}

impl ParaboloidLookupRaw {
    /// The lookup of an unwarped map (DPSM, IPSM).
    #[must_use]
    pub fn new(map: &ParaboloidMap) -> Self {
        Self {
            map: ToRaw::to_raw(map),
            warp: [[0; 4]; 2],
        }
    }
}

/// RTW over the sides of a paraboloid map (`point_rtw`): the depth pass's blocks, the
/// lookup's block and the one table buffer both read.
#[derive(Clone, Debug, PartialEq)]
pub struct WarpedParaboloid {
    /// One block per layer (front, then back for a dual map).
    pub layers: Vec<ParaboloidLayerRaw>,
    /// The lookup.
    pub lookup: ParaboloidLookupRaw,
    /// The tables: front `u`, front `v`, then back `u`, back `v` (one zero when
    /// there are none).
    pub tables: Vec<f32>,
}

/// The blocks and tables of a paraboloid map whose sides are warped by `front` and
/// (for a dual map) `back`; a side without tables is not warped.
#[must_use]
pub fn warped_paraboloid(
    map: &ParaboloidMap,
    front: Option<&WarpMaps>,
    back: Option<&WarpMaps>,
) -> WarpedParaboloid {
    let mut layers = paraboloid_layers(map);
    let mut lookup = ParaboloidLookupRaw::new(map);
    let mut tables = Vec::new();
    for (i, warps) in [front, back].into_iter().enumerate().take(layers.len()) {
        let Some(warps) = warps else { continue };
        let (x, y) = (warps.x_table(), warps.y_table());
        let at = tables.len() as u32;
        let warp = [at, x.len() as u32, at + x.len() as u32, y.len() as u32];
        tables.extend_from_slice(x);
        tables.extend_from_slice(y);
        layers[i].warp = warp;
        lookup.warp[i] = warp;
    }
    if tables.is_empty() {
        tables.push(0.0);
    }
    WarpedParaboloid {
        layers,
        lookup,
        tables,
    }
}

/// Rectilinear texture warping: WGSL `RtwShadow`. The tables themselves travel in a
/// storage buffer (`x` table, then `y` table, `f32`), see
/// [`RtwShadowRaw::tables`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RtwShadowRaw {
    /// Base projection, WebGPU clip space.
    pub clip_from_world: [[f32; 4]; 4],
    /// Base projection, texture space.
    pub uv_from_world: [[f32; 4]; 4],
    /// `x`: texels of the `u` table; `y`: texels of the `v` table; `z`: reversed-Z
    /// (0 or 1); `w`: 0 from [`ToRaw::to_raw`]. The depth pass writes its map
    /// resolution into `w` (the vertex shader snaps to its subpixel grid, see
    /// `shaders/depth_rtw.wgsl`); the lookup ignores it.
    pub sizes: [u32; 4],
    /// `x`, `y`: where the `u` and the `v` table start in the table buffer (0 and
    /// `sizes.x` for one map; several layers share one buffer); `z`, `w`: 0.
    pub table_offsets: [u32; 4],
    /// `x`, `y`: scale of the warped `uv` into the top-left corner of its layer (1
    /// where the map fills the layer; cube faces of different sizes,
    /// `CubeFace::uv_scale_in_layer`); `z`: the base's near plane as its clip `w`
    /// (a perspective window whose casters the GPU refinement cuts to its frustum,
    /// as `shadowmap_rtw::subdivide_for_rtw_clipped`), 0 for a base that is not
    /// cut; `w`: 0.
    pub layer: [f32; 4],
}

impl ToRaw for RtwShadow<'_> {
    type Raw = RtwShadowRaw;
    fn to_raw(&self) -> RtwShadowRaw {
        RtwShadowRaw::from_base(
            &self.base,
            self.warps.x_table().len() as u32,
            self.warps.y_table().len() as u32,
        )
    }
}

impl RtwShadowRaw {
    /// The block for a base projection and tables of `u_texels` and `v_texels`
    /// texels held elsewhere (e.g. built on the GPU by
    /// [`crate::rtw::GpuRtw`]).
    #[must_use]
    pub fn from_base(base: &ShadowTransform, u_texels: u32, v_texels: u32) -> Self {
        Self {
            clip_from_world: cols(&base.clip_from_world),
            uv_from_world: cols(&base.uv_from_world),
            sizes: [u_texels, v_texels, u32::from(base.reversed_z), 0],
            table_offsets: [0, u_texels, 0, 0],
            layer: [1.0, 1.0, 0.0, 0.0],
        }
    }

    /// The storage-buffer contents for the tables of `shadow`: the `u` table then the
    /// `v` table. An empty table set becomes one zero (WebGPU rejects empty buffers;
    /// an empty table reads as offset 0 anyway).
    #[must_use]
    pub fn tables(shadow: &RtwShadow<'_>) -> Vec<f32> {
        let mut v = Vec::with_capacity(shadow.warps.x_table().len() + shadow.warps.y_table().len());
        v.extend_from_slice(shadow.warps.x_table());
        v.extend_from_slice(shadow.warps.y_table());
        if v.is_empty() {
            v.push(0.0);
        }
        v
    }
}

/// Most bases of [`RtwLookupRaw`]: the faces of a cube map.
pub const RTW_LOOKUP_BASES: usize = 6;

/// The lookup of RTW: WGSL `RtwLookup`. Over one base (the uniform or the spot fit,
/// [`RtwLookupRaw::one`]) every point is looked up in it; over several (the kept
/// faces of a cube map, [`warped_cube`]) in the first whose window holds it (the
/// windows are disjoint up to rounding, as the cube lookup selects), then warped
/// through that base's tables and scaled into its layer's corner.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RtwLookupRaw {
    /// One block per base, in layer order (unused entries zero).
    pub bases: [RtwShadowRaw; RTW_LOOKUP_BASES],
    /// `x`: bases in use; `y`, `z`, `w`: 0.
    pub count: [u32; 4],
}

impl RtwLookupRaw {
    /// The lookup of one base.
    #[must_use]
    pub fn one(base: RtwShadowRaw) -> Self {
        let mut raw = Self::zeroed();
        raw.bases[0] = base;
        raw.count[0] = 1;
        raw
    }
}

/// RTW over the kept faces of a cube map (`cube_rtw`): the depth pass's blocks, the
/// lookup's block and the one table buffer both read.
#[derive(Clone, Debug, PartialEq)]
pub struct WarpedCube {
    /// One block per kept face (its perspective base, tables and corner).
    pub layers: Vec<RtwShadowRaw>,
    /// The lookup.
    pub lookup: RtwLookupRaw,
    /// The tables: face 0's `u` then `v`, face 1's, ... (one zero when there are
    /// none).
    pub tables: Vec<f32>,
}

/// The blocks and tables of a cube map whose kept faces are warped by `warps` (one
/// pair of tables per face, in face order; a face without tables is not warped).
/// Each face renders into the top-left corner of a layer of the largest face's side
/// (render at `CubeMap::largest_side`), its casters cut to its window's frustum.
#[must_use]
pub fn warped_cube(cube: &CubeMap, warps: &[WarpMaps]) -> WarpedCube {
    let side = cube.largest_side();
    let mut layers = Vec::with_capacity(cube.faces.len());
    let mut tables = Vec::new();
    for (layer, face) in cube.faces.iter().enumerate() {
        let Some(base) = cube.transform(layer as u32) else {
            continue;
        };
        let (x, y): (&[f32], &[f32]) = warps
            .get(layer)
            .map_or((&[], &[]), |w| (w.x_table(), w.y_table()));
        let mut raw = RtwShadowRaw::from_base(&base, x.len() as u32, y.len() as u32);
        let at = tables.len() as u32;
        raw.table_offsets = [at, at + x.len() as u32, 0, 0];
        let scale = face.uv_scale_in_layer(side);
        raw.layer = [scale.x, scale.y, face.near, 0.0];
        tables.extend_from_slice(x);
        tables.extend_from_slice(y);
        layers.push(raw);
    }
    if tables.is_empty() {
        tables.push(0.0);
    }
    let mut lookup = RtwLookupRaw::zeroed();
    for (slot, raw) in lookup.bases.iter_mut().zip(&layers) {
        *slot = *raw;
    }
    lookup.count[0] = layers.len().min(RTW_LOOKUP_BASES) as u32;
    WarpedCube {
        layers,
        lookup,
        tables,
    }
}

/// Per-frame data of the headless renderer: WGSL `Frame`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FrameRaw {
    /// The camera's `clip_from_world`.
    pub clip_from_world: [[f32; 4]; 4],
    /// The camera's `view_from_world` (view depth `-z`).
    pub view_from_world: [[f32; 4]; 4],
    /// Directional light: the direction light travels, `w = 0`; point light: its
    /// position, `w = 1`.
    pub light: [f32; 4],
    /// `x`: depth bias in stored-depth units (toward the light, sign flipped for
    /// reversed-Z); `y`: world-units bias (XPSM's warped Z bias); `z`: filter radius
    /// in texels; `w`: reversed-Z of the shadow map (0 or 1).
    pub bias: [f32; 4],
    /// `x`, `y`, `z`: shadow map width, height, layers; `w`: filter taps per side
    /// (PCF).
    pub shadow_size: [f32; 4],
    /// Camera position (`xyz`), `w = 1`.
    pub eye: [f32; 4],
}

impl FrameRaw {
    /// The light vector of a [`LightDirection`].
    #[must_use]
    pub fn light_vector(light: LightDirection) -> [f32; 4] {
        match light {
            LightDirection::Directional(d) => d.extend(0.0).to_array(),
            LightDirection::Position(p) => p.extend(1.0).to_array(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn xpsm_bias_scale_lands_in_params() {
        let t = ShadowTransform::new(
            Mat4::IDENTITY,
            Mat4::from_scale(Vec3::splat(2.0)),
            true,
            LightDirection::Directional(Vec3::NEG_Y),
        );
        let raw = t.to_raw();
        assert_eq!(raw.params, [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(raw.clip_from_world[0][0], 2.0);
    }
}
