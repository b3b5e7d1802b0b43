//! Which technique the renderer draws: its lookup shader, light, depth direction
//! and uniform blocks, chosen in one match per question.

use glam::Mat4;
use shadowmap_frustum::{CascadeSet, LightDirection, ShadowTransform};
use shadowmap_paraboloid::{CubeMap, ParaboloidMap, TiledCube};
use shadowmap_rtw::{RtwShadow, WarpMaps};
use shadowmap_warp::{WarpedCascades, XpsmShadow};

use crate::rtw::GpuRtw;
use crate::tiles::tiled_uniforms;
use crate::uniforms::{
    CascadeShadowRaw, MatrixShadowRaw, ParaboloidLookupRaw, RtwLookupRaw, RtwShadowRaw, ToRaw,
    cascade_layers, cube_layers, warped_cascade_layers, warped_cube, warped_paraboloid,
};
use crate::{BackendError, compose, shaders};

/// The technique whose shadow the renderer draws.
#[derive(Clone, Copy, Debug)]
pub enum ShadowTechnique<'a> {
    /// Uniform, LiSPSM, TSM, spot (one matrix).
    Matrix(&'a ShadowTransform),
    /// XPSM, with its warped-space Z bias.
    Xpsm(&'a XpsmShadow),
    /// Cascaded shadow maps, one layer per cascade, selected by view depth with the
    /// blend band.
    Cascades(&'a CascadeSet),
    /// Cascaded shadow maps selected by projection with this margin in texels.
    CascadesByProjection(&'a CascadeSet, f32),
    /// A paraboloid map (DPSM or cut IPSM map).
    Paraboloid(&'a ParaboloidMap),
    /// Rectilinear texture warping over an orthographic base (the uniform fit) or a
    /// perspective one (the spot fit), tables from the CPU.
    Rtw(&'a RtwShadow<'a>),
    /// Rectilinear texture warping with the tables [`GpuRtw`] built on the GPU over
    /// `base` (record and submit its `encode` before the frame).
    RtwGpu {
        /// The base fit the tables were built over.
        base: &'a ShadowTransform,
        /// The GPU analysis holding the tables.
        rtw: &'a GpuRtw,
    },
    /// Rectilinear texture warping over each side of a paraboloid map (`point_rtw`):
    /// the side's projection, then its tables; a side without tables is not warped.
    ParaboloidRtw {
        /// The map (IPSM's).
        map: &'a ParaboloidMap,
        /// The front side's tables.
        front: &'a WarpMaps,
        /// The back side's tables (a dual map).
        back: Option<&'a WarpMaps>,
    },
    /// Parallel-split cascades with a LiSPSM warp each
    /// (`shadowmap_warp::warped_cascades`): one layer per cascade rendered with its
    /// perspective matrix, the cascade selected by view depth with the blend band
    /// where neighbours overlap, the lookup divided by `w`. A cascade without a fit
    /// (its slice has no receivers) renders nothing and reads as not covered.
    WarpedCascades(&'a WarpedCascades),
    /// Cube shadow maps (`shadowmap_paraboloid::CubeMap`): one layer per kept face,
    /// rendered with the face's perspective matrix into the top-left corner of a
    /// layer of the largest face's side (faces sized by need keep their texel
    /// densities; render at `CubeMap::largest_side`, as `render_shadow` does); the
    /// lookup is the cascades' selection by projection (the first face whose window
    /// holds the point, the windows being disjoint up to rounding) with the `uv`
    /// divided by `w` and scaled to the face's corner.
    Cube(&'a CubeMap),
    /// Rectilinear texture warping over the kept faces of a cube map (`cube_rtw`):
    /// one layer per face, each face's casters cut to its window frustum and refined
    /// on the GPU, drawn through the face's perspective base and tables into the
    /// top-left corner of a layer of the largest face's side (render at
    /// `CubeMap::largest_side`); the lookup selects the face by projection, as
    /// [`ShadowTechnique::Cube`] does, then warps.
    CubeRtw {
        /// The cube map whose faces are warped.
        cube: &'a CubeMap,
        /// One pair of tables per kept face, in face order (a face without tables
        /// is not warped).
        warps: &'a [WarpMaps],
    },
    /// Tiled cube maps (`shadowmap_paraboloid::TiledCube`): every tile drawn into
    /// its square of one atlas layer through its face's projection cropped to it
    /// (render at the atlas's larger side, as `render_shadow` does); the lookup
    /// selects the face by projection, then the cell's tile.
    TiledCube(&'a TiledCube),
}

/// Which lookup shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Lookup {
    Matrix,
    Cascades,
    Paraboloid,
    Rtw,
    Tiles,
}

impl Lookup {
    /// The lookup's WGSL, with its shared functions composed in.
    pub(super) fn source(self) -> Result<String, BackendError> {
        match self {
            Self::Matrix => Ok(shaders::LOOKUP_MATRIX.to_owned()),
            Self::Cascades => Ok(shaders::LOOKUP_CASCADES.to_owned()),
            Self::Paraboloid => compose::lookup_paraboloid(),
            Self::Rtw => compose::lookup_rtw(),
            Self::Tiles => Ok(shaders::LOOKUP_TILES.to_owned()),
        }
    }
}

impl ShadowTechnique<'_> {
    pub(super) fn lookup(&self) -> Lookup {
        match self {
            Self::Matrix(_) | Self::Xpsm(_) => Lookup::Matrix,
            Self::Cascades(_)
            | Self::CascadesByProjection(..)
            | Self::WarpedCascades(_)
            | Self::Cube(_) => Lookup::Cascades,
            Self::Paraboloid(_) | Self::ParaboloidRtw { .. } => Lookup::Paraboloid,
            Self::Rtw(_) | Self::RtwGpu { .. } | Self::CubeRtw { .. } => Lookup::Rtw,
            Self::TiledCube(_) => Lookup::Tiles,
        }
    }

    /// The transform that carries the light and the depth direction: the first
    /// cascade (the first fitted one for warped cascades), or the technique's own;
    /// `None` for a paraboloid map and for a cascade set without a cascade.
    fn first_transform(&self) -> Option<&ShadowTransform> {
        match self {
            Self::Matrix(t) => Some(t),
            Self::Xpsm(x) => Some(&x.transform),
            Self::Cascades(s) | Self::CascadesByProjection(s, _) => {
                s.cascades.first().map(|c| &c.transform)
            }
            Self::WarpedCascades(w) => w
                .cascades
                .iter()
                .find_map(|c| c.shadow.as_ref())
                .map(|s| &s.transform),
            Self::Rtw(r) => Some(&r.base),
            Self::RtwGpu { base, .. } => Some(base),
            Self::Paraboloid(_)
            | Self::ParaboloidRtw { .. }
            | Self::Cube(_)
            | Self::CubeRtw { .. }
            | Self::TiledCube(_) => None,
        }
    }

    /// The light the scene pass shades with.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a cascade set without a (fitted) cascade:
    /// there is no light to read, and none is made up.
    pub(super) fn light(&self) -> Result<LightDirection, BackendError> {
        match self {
            Self::Paraboloid(m) | Self::ParaboloidRtw { map: m, .. } => {
                Ok(LightDirection::Position(m.position))
            }
            Self::Cube(c) | Self::CubeRtw { cube: c, .. } => {
                Ok(LightDirection::Position(c.position))
            }
            Self::TiledCube(t) => Ok(LightDirection::Position(t.cube.position)),
            _ => self
                .first_transform()
                .map(|t| t.light)
                .ok_or(BackendError::InvalidInput("empty cascade set")),
        }
    }

    /// Whether the technique stores perspective depth seen from a light position
    /// (cube faces; the spot fit, the spot warps and RTW over the spot fit), whose
    /// stored-depth units near 1 span a distance growing as its square.
    pub(super) fn perspective_depth(&self) -> bool {
        match self {
            Self::Cube(_) | Self::CubeRtw { .. } | Self::TiledCube(_) => true,
            Self::Paraboloid(_) | Self::ParaboloidRtw { .. } => false,
            _ => self
                .first_transform()
                .is_some_and(|t| matches!(t.light, LightDirection::Position(_))),
        }
    }

    pub(super) fn reversed_z(&self) -> bool {
        match self {
            Self::Paraboloid(m) | Self::ParaboloidRtw { map: m, .. } => m.reversed_z,
            Self::Cube(c) | Self::CubeRtw { cube: c, .. } => c.reversed_z,
            Self::TiledCube(t) => t.cube.reversed_z,
            _ => self.first_transform().is_some_and(|t| t.reversed_z),
        }
    }

    /// The depth-pass blocks of the matrix techniques, one per layer; `None` for
    /// the paraboloid and RTW passes.
    pub(super) fn matrix_layers(&self) -> Option<Vec<MatrixShadowRaw>> {
        match self {
            Self::Matrix(t) => Some(vec![t.to_raw()]),
            Self::Xpsm(x) => Some(vec![x.to_raw()]),
            Self::Cascades(s) | Self::CascadesByProjection(s, _) => Some(cascade_layers(s)),
            Self::WarpedCascades(w) => Some(warped_cascade_layers(w)),
            Self::Cube(c) => Some(cube_layers(c)),
            Self::Paraboloid(_)
            | Self::ParaboloidRtw { .. }
            | Self::Rtw(_)
            | Self::RtwGpu { .. }
            | Self::CubeRtw { .. }
            | Self::TiledCube(_) => None,
        }
    }

    /// The lookup's uniform block, as bytes; `view_from_world` is the camera's
    /// (warped cascades select by its view depth), `texture_side` the depth
    /// texture's (tiled cube maps place the atlas in its corner).
    pub(super) fn lookup_bytes(&self, view_from_world: Mat4, texture_side: u32) -> Vec<u8> {
        match self {
            Self::TiledCube(t) => {
                bytemuck::bytes_of(&tiled_uniforms(t, texture_side).lookup).to_vec()
            }
            Self::Matrix(t) => bytemuck::bytes_of(&t.to_raw()).to_vec(),
            Self::Xpsm(x) => bytemuck::bytes_of(&x.to_raw()).to_vec(),
            Self::Cascades(s) => bytemuck::bytes_of(&s.to_raw()).to_vec(),
            Self::CascadesByProjection(s, margin) => bytemuck::bytes_of(
                &s.to_raw()
                    .with_selection_by_projection(*margin, s.resolution),
            )
            .to_vec(),
            Self::WarpedCascades(w) => {
                bytemuck::bytes_of(&CascadeShadowRaw::from_warped(w, view_from_world)).to_vec()
            }
            Self::Paraboloid(m) => bytemuck::bytes_of(&ParaboloidLookupRaw::new(m)).to_vec(),
            Self::ParaboloidRtw { map, front, back } => {
                bytemuck::bytes_of(&warped_paraboloid(map, Some(front), *back).lookup).to_vec()
            }
            Self::Cube(c) => bytemuck::bytes_of(&CascadeShadowRaw::from_cube(c)).to_vec(),
            Self::CubeRtw { cube, warps } => {
                bytemuck::bytes_of(&warped_cube(cube, warps).lookup).to_vec()
            }
            Self::Rtw(r) => bytemuck::bytes_of(&RtwLookupRaw::one(r.to_raw())).to_vec(),
            Self::RtwGpu { base, rtw } => bytemuck::bytes_of(&RtwLookupRaw::one(
                RtwShadowRaw::from_base(base, rtw.width(), rtw.height()),
            ))
            .to_vec(),
        }
    }
}
