//! [`Shadow`]: a fitted technique, owning the math crates' own result types.

use alloc::vec::Vec;

use glam::{DVec2, DVec3, Vec3};
use shadowmap_frustum::{
    CascadeSet, ShadowMapping, ShadowSample, ShadowTransform, SpotShadow,
    uv_differentials_by_points,
};
use shadowmap_paraboloid::{CubeMap, IpsmPlan, ParaboloidMap, TiledCube};
use shadowmap_rtw::{RtwShadow, WarpMaps};
use shadowmap_warp::{
    LispsmShadow, SpotWarpShadow, TsmShadow, WarpedCascades, WarpedCascadesView, XpsmShadow,
};

use crate::Technique;

/// The result of one fit, as the math crate that built it returns it.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
// Cascade sets and warped cascades keep their fixed-capacity arrays inline, so a fit
// allocates nothing (RTW's tables aside); a `Shadow` is built once per frame.
#[expect(
    clippy::large_enum_variant,
    reason = "inline cascades keep fitting allocation-free"
)]
pub enum Fitted {
    /// Uniform focused (`shadowmap_warp::uniform_focused`).
    Uniform(ShadowTransform),
    /// Stable or tight cascades, one layer per cascade.
    Cascades(CascadeSet),
    /// LiSPSM.
    Lispsm(LispsmShadow),
    /// XPSM, with its warped-space Z bias.
    Xpsm(XpsmShadow),
    /// TSM.
    Tsm(TsmShadow),
    /// Warped cascades with the camera they were fitted for (selection by view
    /// depth, see [`WarpedCascades::view`]).
    WarpedCascades {
        /// The cascades.
        cascades: WarpedCascades,
        /// The camera's eye.
        eye: Vec3,
        /// The camera's unit viewing direction.
        forward: Vec3,
    },
    /// RTW and the RTW oracle (over the uniform fit), RTW over the spot fit: the base
    /// fit and the warp tables.
    Rtw {
        /// The fit that is warped (orthographic or perspective).
        base: ShadowTransform,
        /// The warp tables.
        warps: WarpMaps,
    },
    /// The spot fit.
    Spot(SpotShadow),
    /// LiSPSM or TSM in the spot light's post-projective space.
    SpotWarp(SpotWarpShadow),
    /// The dual paraboloid map.
    Dpsm(ParaboloidMap),
    /// The IPSM plan (its map is single or dual).
    Ipsm(IpsmPlan),
    /// Cube shadow maps, one layer per kept face.
    Cube(CubeMap),
    /// RTW over the focused faces of a cube map: the cube (its faces in an atlas)
    /// and one pair of warp tables per kept face, in face order.
    CubeRtw {
        /// The cube map whose faces are warped.
        cube: CubeMap,
        /// Each face's tables.
        warps: Vec<WarpMaps>,
    },
    /// Tiled cube maps: the focused faces' tiles in one atlas.
    TiledCube(TiledCube),
    /// RTW over the IPSM paraboloid: the plan and one pair of warp tables per side.
    PointRtw {
        /// The paraboloid plan whose sides are warped.
        plan: IpsmPlan,
        /// The front side's tables.
        front: WarpMaps,
        /// The back side's tables (a dual map only).
        back: Option<WarpMaps>,
    },
}

/// A technique fitted to one frame by [`fit`](crate::fit): what was asked for, what
/// was fitted (the candidate `auto` chose), the math crate's result, and the layers
/// (cascades, paraboloid sides) of equal square size sharing the texel budget.
///
/// It is a [`ShadowMapping`]: world point to `(uv, depth, layer)`, the same lookup a
/// shader does.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "ShadowData"))]
#[derive(Clone, Debug, PartialEq)]
pub struct Shadow {
    pub(crate) requested: Technique,
    pub(crate) technique: Technique,
    pub(crate) fitted: Fitted,
    pub(crate) layers: u32,
    pub(crate) layer_side: u32,
}

impl Shadow {
    /// The technique that was fitted: the one asked for, or for
    /// [`Technique::Auto`] the candidate it chose.
    #[must_use]
    pub const fn technique(&self) -> &Technique {
        &self.technique
    }

    /// The technique asked for (may be [`Technique::Auto`]).
    #[must_use]
    pub const fn requested(&self) -> &Technique {
        &self.requested
    }

    /// The math crate's result.
    #[must_use]
    pub const fn fitted(&self) -> &Fitted {
        &self.fitted
    }

    /// Number of layers: cascades, paraboloid sides, cube faces, 1 for a single map.
    #[must_use]
    pub const fn layers(&self) -> u32 {
        self.layers
    }

    /// Side in texels of each (square) layer; for cube maps, the largest face's
    /// (their faces may differ: see [`CubeMap::faces`]); for tiled cube maps, the
    /// atlas's larger side (the texture that holds every tile).
    #[must_use]
    pub const fn layer_side(&self) -> u32 {
        self.layer_side
    }

    /// Texels over all layers (at most the budget): for cube maps, their atlas.
    #[must_use]
    pub fn texels(&self) -> u64 {
        if let Fitted::TiledCube(tiled) = &self.fitted {
            return tiled.texels();
        }
        match self.cube() {
            Some(cube) => cube.texels(),
            _ => u64::from(self.layer_side) * u64::from(self.layer_side) * u64::from(self.layers),
        }
    }

    /// The single matrix pair of a one-map matrix technique (uniform, LiSPSM, XPSM,
    /// TSM, spot); `None` for cascades, paraboloids and RTW.
    #[must_use]
    pub const fn transform(&self) -> Option<&ShadowTransform> {
        match &self.fitted {
            Fitted::Uniform(t) => Some(t),
            Fitted::Lispsm(s) => Some(&s.transform),
            Fitted::Xpsm(s) => Some(&s.transform),
            Fitted::Tsm(s) => Some(&s.transform),
            Fitted::Spot(s) => Some(&s.transform),
            Fitted::SpotWarp(s) => Some(&s.transform),
            _ => None,
        }
    }

    /// The paraboloid map of DPSM and IPSM.
    #[must_use]
    pub const fn paraboloid(&self) -> Option<&ParaboloidMap> {
        match &self.fitted {
            Fitted::Dpsm(map) => Some(map),
            Fitted::Ipsm(plan) => Some(&plan.map),
            _ => None,
        }
    }

    /// The cube map of [`Technique::CubeMaps`] and of RTW over its faces
    /// ([`Technique::CubeRtw`]).
    #[must_use]
    pub const fn cube(&self) -> Option<&CubeMap> {
        match &self.fitted {
            Fitted::Cube(cube) | Fitted::CubeRtw { cube, .. } => Some(cube),
            _ => None,
        }
    }

    /// The tiles of [`Technique::TiledCube`].
    #[must_use]
    pub const fn tiled_cube(&self) -> Option<&TiledCube> {
        match &self.fitted {
            Fitted::TiledCube(tiled) => Some(tiled),
            _ => None,
        }
    }

    /// RTW's base fit and tables, borrowed as the rtw crate's [`RtwShadow`].
    #[must_use]
    pub const fn rtw(&self) -> Option<RtwShadow<'_>> {
        match &self.fitted {
            Fitted::Rtw { base, warps } => Some(RtwShadow { base: *base, warps }),
            _ => None,
        }
    }

    /// Warped cascades with their camera, as a mapping.
    #[must_use]
    pub const fn warped_cascades(&self) -> Option<WarpedCascadesView<'_>> {
        match &self.fitted {
            Fitted::WarpedCascades {
                cascades,
                eye,
                forward,
            } => Some(cascades.view(*eye, *forward)),
            _ => None,
        }
    }
}

impl Fitted {
    /// The layer side a result sets itself (cube maps: their largest face), `None`
    /// where the layers share the budget equally.
    pub(crate) fn own_layer_side(&self) -> Option<u32> {
        match self {
            Self::Cube(cube) | Self::CubeRtw { cube, .. } => {
                Some(cube.largest_side()).filter(|side| *side > 0)
            }
            Self::TiledCube(tiled) => {
                Some(tiled.atlas[0].max(tiled.atlas[1])).filter(|side| *side > 0)
            }
            _ => None,
        }
    }

    /// Layers of this result: cascades, paraboloid sides, 1 for a single map.
    #[must_use]
    pub fn layer_count(&self) -> u32 {
        let count = match self {
            Self::Cascades(set) => set.cascades.len(),
            Self::WarpedCascades { cascades, .. } => cascades.cascades.len(),
            Self::Dpsm(map) => map.layers() as usize,
            Self::Ipsm(plan) | Self::PointRtw { plan, .. } => plan.map.layers() as usize,
            Self::Cube(cube) | Self::CubeRtw { cube, .. } => cube.faces.len(),
            Self::TiledCube(tiled) => tiled.tiles.len(),
            _ => 1,
        };
        u32::try_from(count).unwrap_or(u32::MAX)
    }
}

/// A [`Shadow`] as read from a serialized payload, checked before it becomes one.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct ShadowData {
    requested: Technique,
    technique: Technique,
    fitted: Fitted,
    layers: u32,
    layer_side: u32,
}

#[cfg(feature = "serde")]
impl TryFrom<ShadowData> for Shadow {
    type Error = &'static str;

    /// The layer count must be the result's, the side a map side `fit` can make
    /// (`4..=65536`), and the fitted technique the requested one unless `auto` chose.
    fn try_from(data: ShadowData) -> Result<Self, Self::Error> {
        if data.layers != data.fitted.layer_count() {
            return Err("layers do not match the fitted result");
        }
        if !(4..=shadowmap_frustum::MAX_RESOLUTION).contains(&data.layer_side) {
            return Err("layer side out of range");
        }
        let auto = matches!(data.requested, Technique::Auto(_));
        if !auto && data.requested != data.technique {
            return Err("fitted technique differs from the requested one");
        }
        Ok(Self {
            requested: data.requested,
            technique: data.technique,
            fitted: data.fitted,
            layers: data.layers,
            layer_side: data.layer_side,
        })
    }
}

impl ShadowMapping for Shadow {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        match &self.fitted {
            Fitted::Cascades(set) => set.map_point(world),
            Fitted::WarpedCascades {
                cascades,
                eye,
                forward,
            } => cascades.view(*eye, *forward).map_point(world),
            Fitted::Rtw { base, warps } => RtwShadow { base: *base, warps }.map_point(world),
            Fitted::Dpsm(map) => map.map_point(world),
            Fitted::Ipsm(plan) => plan.map.map_point(world),
            Fitted::Cube(cube) => cube.map_point(world),
            Fitted::TiledCube(tiled) => tiled.map_point(world),
            Fitted::CubeRtw { cube, warps } => {
                let s = cube.map_point(world)?;
                warps.get(s.layer as usize)?.warp_sample(s)
            }
            Fitted::PointRtw { plan, front, back } => crate::point_fit::WarpedParaboloid {
                map: &plan.map,
                front,
                back: back.as_ref(),
            }
            .map_point(world),
            Fitted::Uniform(t) => t.map_point(world),
            Fitted::Lispsm(LispsmShadow { transform, .. })
            | Fitted::Xpsm(XpsmShadow { transform, .. })
            | Fitted::Tsm(TsmShadow { transform, .. })
            | Fitted::Spot(SpotShadow { transform, .. })
            | Fitted::SpotWarp(SpotWarpShadow { transform, .. }) => transform.map_point(world),
        }
    }

    /// The fitted technique's own differentials (the derivative of its matrix, for
    /// the matrix techniques).
    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        match &self.fitted {
            Fitted::Cascades(set) => set.uv_differentials(centre, around),
            Fitted::WarpedCascades {
                cascades,
                eye,
                forward,
            } => cascades
                .view(*eye, *forward)
                .uv_differentials(centre, around),
            Fitted::Uniform(t) => t.uv_differentials(centre, around),
            Fitted::Lispsm(LispsmShadow { transform, .. })
            | Fitted::Xpsm(XpsmShadow { transform, .. })
            | Fitted::Tsm(TsmShadow { transform, .. })
            | Fitted::Spot(SpotShadow { transform, .. })
            | Fitted::SpotWarp(SpotWarpShadow { transform, .. }) => {
                transform.uv_differentials(centre, around)
            }
            _ => uv_differentials_by_points(self, centre, around),
        }
    }
}
