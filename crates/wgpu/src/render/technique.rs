//! Which technique the renderer draws: its lookup shader, light, depth direction
//! and uniform blocks, chosen in one match per question.

use bytemuck::Zeroable;
use glam::Mat4;
use shadowmap_frustum::{CascadeSet, LightDirection, ShadowTransform};
use shadowmap_paraboloid::{CubeMap, ParaboloidMap};
use shadowmap_rtw::RtwShadow;
use shadowmap_warp::{WarpedCascades, XpsmShadow};

use crate::uniforms::{
    CascadeShadowRaw, MatrixShadowRaw, ToRaw, cascade_layers, warped_cascade_layers,
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
    /// Rectilinear texture warping.
    Rtw(&'a RtwShadow<'a>),
    /// Parallel-split cascades with a LiSPSM warp each
    /// (`shadowmap_warp::warped_cascades`): one layer per cascade rendered with its
    /// perspective matrix, the cascade selected by view depth with the blend band
    /// where neighbours overlap, the lookup divided by `w`. A cascade without a fit
    /// (its slice has no receivers) renders nothing and reads as not covered.
    WarpedCascades(&'a WarpedCascades),
    /// Cube shadow maps (`shadowmap_paraboloid::CubeMap`): one layer per kept face,
    /// rendered with the face's perspective matrix; the lookup is the cascades'
    /// selection by projection (the first face whose window holds the point, the
    /// windows being disjoint up to rounding) with the `uv` divided by `w`.
    Cube(&'a CubeMap),
}

/// Which lookup shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Lookup {
    Matrix,
    Cascades,
    Paraboloid,
    Rtw,
}

impl Lookup {
    /// The lookup's WGSL, with its shared functions composed in.
    pub(super) fn source(self) -> Result<String, BackendError> {
        match self {
            Self::Matrix => Ok(shaders::LOOKUP_MATRIX.to_owned()),
            Self::Cascades => Ok(shaders::LOOKUP_CASCADES.to_owned()),
            Self::Paraboloid => Ok(shaders::LOOKUP_PARABOLOID.to_owned()),
            Self::Rtw => compose::lookup_rtw(),
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
            Self::Paraboloid(_) => Lookup::Paraboloid,
            Self::Rtw(_) => Lookup::Rtw,
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
            Self::Paraboloid(_) | Self::Cube(_) => None,
        }
    }

    /// The light the scene pass shades with.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a cascade set without a (fitted) cascade:
    /// there is no light to read, and none is made up.
    pub(super) fn light(&self) -> Result<LightDirection, BackendError> {
        match self {
            Self::Paraboloid(m) => Ok(LightDirection::Position(m.position)),
            Self::Cube(c) => Ok(LightDirection::Position(c.position)),
            _ => self
                .first_transform()
                .map(|t| t.light)
                .ok_or(BackendError::InvalidInput("empty cascade set")),
        }
    }

    pub(super) fn reversed_z(&self) -> bool {
        match self {
            Self::Paraboloid(m) => m.reversed_z,
            Self::Cube(c) => c.reversed_z,
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
            Self::Cube(c) => Some(
                (0..c.layers())
                    .filter_map(|layer| c.transform(layer))
                    .map(|t| t.to_raw())
                    .collect(),
            ),
            Self::Paraboloid(_) | Self::Rtw(_) => None,
        }
    }

    /// The lookup's uniform block, as bytes; `view_from_world` is the camera's
    /// (warped cascades select by its view depth).
    pub(super) fn lookup_bytes(&self, view_from_world: Mat4) -> Vec<u8> {
        match self {
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
            Self::Paraboloid(m) => bytemuck::bytes_of(&m.to_raw()).to_vec(),
            Self::Cube(c) => bytemuck::bytes_of(&cube_lookup(c)).to_vec(),
            Self::Rtw(r) => bytemuck::bytes_of(&r.to_raw()).to_vec(),
        }
    }
}

/// The cascades lookup block of a cube map: one perspective `uv_from_world` per kept
/// face, selected by projection without a margin (adjacent windows meet at the face
/// edges).
fn cube_lookup(cube: &CubeMap) -> CascadeShadowRaw {
    let mut raw = CascadeShadowRaw::zeroed();
    let n = raw.uv_from_world.len();
    for (slot, layer) in raw.uv_from_world.iter_mut().zip(0..cube.layers()) {
        if let Some(t) = cube.transform(layer) {
            *slot = t.uv_from_world.to_cols_array_2d();
        }
    }
    raw.count = cube.layers().min(n as u32);
    raw.reversed_z = u32::from(cube.reversed_z);
    raw.select_by_projection = 1;
    raw
}
