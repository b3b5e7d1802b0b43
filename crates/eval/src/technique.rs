//! The techniques under comparison, built for one frame of a configuration at an
//! equal texel budget.
//!
//! [`TechniqueKind`] lists them, each an umbrella [`shadowmap::Technique`] value
//! ([`TechniqueKind::technique`]); [`Technique::build`] fits one to a frame
//! ([`FrameContext`]: camera, light, scene bounds, the eye's visible samples) with
//! [`shadowmap::fit`] and returns something that is both a [`ShadowMapping`] (the
//! lookup the metrics measure) and a depth pass for the reference rasterizer
//! ([`Technique::rasterize`]), with its per-layer resolution.
//!
//! | light | techniques |
//! |---|---|
//! | directional | uniform focused, stable and tight cascades (PSSM over the depth bounds), LiSPSM, XPSM, TSM, warped cascades (PSSM + LiSPSM), auto (the candidate with the lowest error on the eye samples), RTW (backward importance), RTW oracle |
//! | spot | spot fit, LiSPSM and TSM in the spot's post-projective space, RTW over the spot fit |
//! | point | DPSM, IPSM with the paper's cone, IPSM with the exact minimal cone (both measured on the eye's samples against their dual alternatives), cube maps focused on the visible receivers with faces sized by the samples' needs (world-axis or turned toward the receivers, whichever the samples measure finer), the engines' cube maps (equal full faces: a reference, not one of the library's techniques), RTW over the IPSM paraboloid (the plan's own or the one the IPSM rows keep, whichever warps finer on the samples), RTW over the focused cube faces |
//!
//! Budget: `texel_budget` texels in total ([`TechniqueOptions`], default `1024²`),
//! split evenly over the layers: one `1024²` map, four cascades of `512²`, a dual
//! paraboloid of `2 x 724²` (an IPSM plan that falls back to dual gets `2 x 724²`
//! too); the engines' cube maps share it over their kept faces,
//! `k x floor(sqrt(1024² / k))²`, the focused cube maps and RTW over them as tiles of
//! one atlas whose area (gaps included) is within the budget and is the `texels`
//! counted (the metrics count the faces' own texels). A technique that cannot handle a frame returns
//! [`EvalError::Technique`] with the math crate's reason, never panics.

use glam::{DMat4, DVec2, DVec3, DVec4, Vec3};
use shadowmap::paraboloid::{
    ConeFit, CubeMap, CubeOptions, CubeOrientation, FaceSizes, IpsmOptions, Side,
    SubdivisionOptions, TileOptions, TiledCube, subdivide_triangles,
};
use shadowmap::rtw::{
    EyeSample, RtwSubdivision, WarpMaps, subdivide_for_rtw, subdivide_for_rtw_clipped,
};
use shadowmap::warp::{SpotWarpKind, SpotWarpOptions};
use shadowmap::{
    CascadePlan, FitInput, FitState, Fitted, RtwPlan, Shadow, depth_bounds_of, fit_with_state,
};
use shadowmap_frustum::{Camera, Light, SceneBounds, ShadowMapping, ShadowSample};

use crate::EvalError;
use crate::mask::GBuffer;
use crate::raster::{
    DepthMap, DepthProjector, MatrixProjector, ParaboloidProjector, RasterOptions, RtwProjector,
    rasterize_depth,
};
use crate::scene::Mesh;

mod auto;
#[cfg(test)]
mod tests;
mod warped;

use warped::WarpedProjector;

pub use auto::AUTO_CANDIDATES;

/// Every technique of the comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TechniqueKind {
    /// Orthographic fit of frustum ∩ receivers (`shadowmap_warp::uniform_focused`).
    UniformFocused,
    /// PSSM, stable: `CascadeSet::fit_with_state`, each map fitted to slice ∩
    /// receivers with a margin for a small turn and growth, its extents and
    /// orientation held along the camera path with hysteresis; practical splits of
    /// the eye's depth bounds, the count from the predicted error (see
    /// `shadowmap::fit_with_state`).
    StableCascades,
    /// PSSM, tight (SDSM-style): `CascadeSet::fit` with the tight fit to slice ∩
    /// receivers over the same splits as [`TechniqueKind::StableCascades`]; one
    /// cascade is the uniform fit narrowed to the depth bounds.
    TightCascades,
    /// Light space perspective shadow maps, `eta = 0`.
    Lispsm,
    /// Extended perspective shadow maps.
    Xpsm,
    /// Trapezoidal shadow maps.
    Tsm,
    /// PSSM with LiSPSM per cascade (`shadowmap_warp::warped_cascades`), the count
    /// from its own predicted error.
    WarpedCascades,
    /// Rectilinear texture warping over the uniform fit, importance from the eye's
    /// samples the light reaches (backward analysis).
    Rtw,
    /// Picks, per frame, the matrix technique or cascades with the lowest error
    /// predicted from the camera, light and bounds alone
    /// (`shadowmap_frustum::predict_error`; candidates in [`AUTO_CANDIDATES`]).
    Auto,
    /// RTW fed the exact perspective-only density each axis requires
    /// (`ImportanceMap::accumulate_oracle_axis`, `WarpMaps::build_separable`).
    RtwOracle,
    /// Perspective fit of a spot light (`shadowmap_frustum::fit_spot`).
    SpotFit,
    /// LiSPSM in the spot light's post-projective space
    /// (`shadowmap_warp::spot_warp`).
    SpotLispsm,
    /// TSM in the spot light's post-projective space.
    SpotTsm,
    /// Dual paraboloid (front facing world `-Y`), not view-dependent.
    Dpsm,
    /// IPSM with the paper's averaged cone.
    IpsmPaper,
    /// IPSM with the exact minimal cone.
    IpsmExact,
    /// Cube maps: the faces that see visible receivers, each focused on them
    /// (`shadowmap_paraboloid::CubeMap`), sized by the density the eye's samples
    /// need, the cube along the world axes or turned toward the receivers, whichever
    /// the samples measure finer.
    Cube,
    /// The engines' cube maps: the world-axis faces that see visible receivers at
    /// their full 90 degrees over the light's range, equal sides (one texture-array
    /// layer each). A reference row, not one of the library's techniques.
    CubeUnfocused,
    /// Rectilinear texture warping over the spot fit (a perspective base), importance
    /// from the eye's samples.
    SpotRtw,
    /// Rectilinear texture warping over each side of the IPSM paraboloid (exact
    /// cone), importance from the eye's samples.
    PointRtw,
    /// Rectilinear texture warping over each focused face of the cube map,
    /// importance from the eye's samples, the faces sized by the error their warps
    /// leave.
    CubeRtw,
    /// Tiled cube maps: each focused face cut into a grid of tiles, each tile's
    /// resolution from the needs of the eye's samples in it, one atlas.
    CubeTiled,
}

impl TechniqueKind {
    /// All techniques, in report order.
    pub const ALL: [Self; 22] = [
        Self::UniformFocused,
        Self::StableCascades,
        Self::TightCascades,
        Self::Lispsm,
        Self::Xpsm,
        Self::Tsm,
        Self::WarpedCascades,
        Self::Auto,
        Self::Rtw,
        Self::RtwOracle,
        Self::SpotFit,
        Self::SpotLispsm,
        Self::SpotTsm,
        Self::Dpsm,
        Self::IpsmPaper,
        Self::IpsmExact,
        Self::Cube,
        Self::CubeUnfocused,
        Self::SpotRtw,
        Self::PointRtw,
        Self::CubeRtw,
        Self::CubeTiled,
    ];

    /// The technique this one must not lose to, of its own family: the uniform fit
    /// for the directional techniques, the spot fit for the spot warps and RTW over
    /// it, DPSM for the paraboloid maps (IPSM, RTW over its paraboloid), the focused
    /// cube maps for RTW over their faces, the engines' cube maps (unfocused, equal
    /// faces) for the focused ones. `None` for the baselines themselves and the RTW
    /// oracle (a bound, not a technique).
    #[must_use]
    pub const fn baseline(self) -> Option<Self> {
        match self {
            Self::StableCascades
            | Self::TightCascades
            | Self::Lispsm
            | Self::Xpsm
            | Self::Tsm
            | Self::WarpedCascades
            | Self::Auto
            | Self::Rtw => Some(Self::UniformFocused),
            Self::SpotLispsm | Self::SpotTsm | Self::SpotRtw => Some(Self::SpotFit),
            Self::IpsmPaper | Self::IpsmExact | Self::PointRtw => Some(Self::Dpsm),
            Self::Cube => Some(Self::CubeUnfocused),
            Self::CubeRtw | Self::CubeTiled => Some(Self::Cube),
            Self::UniformFocused
            | Self::RtwOracle
            | Self::SpotFit
            | Self::Dpsm
            | Self::CubeUnfocused => None,
        }
    }

    /// Whether the kind is a reference the report measures beside the techniques
    /// rather than one of them: the engines' cube maps (full faces of one size), the
    /// bar the library's focused cube maps must meet. Its rows go to
    /// `references.csv` and the reference lines of the report, not to the technique
    /// tables, `metrics.csv` or the pictures.
    #[must_use]
    pub const fn is_reference(self) -> bool {
        matches!(self, Self::CubeUnfocused)
    }

    /// Short identifier for tables and file names.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::UniformFocused => "uniform",
            Self::StableCascades => "cascades",
            Self::TightCascades => "tight_cascades",
            Self::Lispsm => "lispsm",
            Self::Xpsm => "xpsm",
            Self::Tsm => "tsm",
            Self::WarpedCascades => "warped_cascades",
            Self::Auto => "auto",
            Self::Rtw => "rtw",
            Self::RtwOracle => "rtw_oracle",
            Self::SpotFit => "spot",
            Self::SpotLispsm => "spot_lispsm",
            Self::SpotTsm => "spot_tsm",
            Self::Dpsm => "dpsm",
            Self::IpsmPaper => "ipsm_paper",
            Self::IpsmExact => "ipsm_exact",
            Self::Cube => "cube",
            Self::CubeUnfocused => "cube_unfocused",
            Self::SpotRtw => "spot_rtw",
            Self::PointRtw => "point_rtw",
            Self::CubeRtw => "cube_rtw",
            Self::CubeTiled => "cube_tiled",
        }
    }

    /// Whether the technique is meant for this kind of light.
    #[must_use]
    pub fn applies_to(self, light: &Light) -> bool {
        self.technique(&TechniqueOptions::default())
            .applies_to(light)
    }

    /// The umbrella crate's technique value for this kind, with the comparison's
    /// options (default options of each builder; cascades, splits and RTW's map side
    /// from `options`).
    #[must_use]
    pub fn technique(self, options: &TechniqueOptions) -> shadowmap::Technique {
        use shadowmap::Technique as T;
        let plan = CascadePlan::default()
            .with_max_cascades(options.cascades)
            .with_split_lambda(options.split_lambda);
        let rtw = RtwPlan::default().with_importance_side(options.rtw_importance_side);
        let ipsm = |fit| T::Ipsm(IpsmOptions::default().with_fit(fit));
        match self {
            Self::UniformFocused => T::UniformFocused(Default::default()),
            Self::StableCascades => T::StableCascades(plan),
            Self::TightCascades => T::TightCascades(plan),
            Self::Lispsm => T::Lispsm(Default::default()),
            Self::Xpsm => T::Xpsm(Default::default()),
            Self::Tsm => T::Tsm(Default::default()),
            Self::WarpedCascades => T::WarpedCascades {
                plan,
                lispsm: Default::default(),
            },
            Self::Auto => T::Auto(plan),
            Self::Rtw => T::Rtw(rtw),
            Self::RtwOracle => T::RtwOracle(rtw),
            Self::SpotFit => T::SpotFit { reversed_z: false },
            Self::SpotLispsm => T::SpotWarp(SpotWarpOptions::default()),
            Self::SpotTsm => T::SpotWarp(SpotWarpOptions::default().with_kind(SpotWarpKind::Tsm)),
            Self::Dpsm => T::Dpsm(Default::default()),
            Self::IpsmPaper => ipsm(ConeFit::Paper),
            Self::IpsmExact => ipsm(ConeFit::Exact),
            Self::Cube => T::CubeMaps(
                CubeOptions::default()
                    .with_sizes(FaceSizes::ByNeed)
                    .with_orientation(CubeOrientation::Predicted),
            ),
            Self::CubeUnfocused => T::CubeMaps(
                CubeOptions::default()
                    .with_focused(false)
                    .with_sizes(FaceSizes::Equal)
                    .with_orientation(CubeOrientation::WorldAxes),
            ),
            Self::CubeRtw => T::CubeRtw {
                cube: CubeOptions::default(),
                rtw,
            },
            Self::CubeTiled => T::TiledCube {
                cube: CubeOptions::default(),
                tiles: TileOptions::default(),
            },
            Self::SpotRtw => T::SpotRtw(rtw),
            Self::PointRtw => T::PointRtw {
                ipsm: IpsmOptions::default().with_fit(ConeFit::Exact),
                rtw,
            },
        }
    }

    /// The kind of an umbrella technique value (by [`shadowmap::Technique::name`]).
    #[must_use]
    pub fn of(technique: &shadowmap::Technique) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == technique.name())
    }

    /// The techniques for a light, in report order.
    #[must_use]
    pub fn for_light(light: &Light) -> Vec<Self> {
        Self::ALL
            .into_iter()
            .filter(|k| k.applies_to(light))
            .collect()
    }
}

/// Knobs shared by every technique.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct TechniqueOptions {
    /// Texels in total over all layers. Default `1024²`.
    pub texel_budget: u64,
    /// Cascades of the cascaded techniques. Default 4.
    pub cascades: usize,
    /// Practical split weight (0 uniform, 1 logarithmic). Default 0.5.
    pub split_lambda: f32,
    /// Side of RTW's importance map and warp tables. Default 256.
    pub rtw_importance_side: u32,
}

impl Default for TechniqueOptions {
    fn default() -> Self {
        Self {
            texel_budget: 1024 * 1024,
            cascades: 4,
            split_lambda: 0.5,
            rtw_importance_side: 256,
        }
    }
}

impl TechniqueOptions {
    /// With this total texel budget.
    #[must_use]
    pub const fn with_texel_budget(mut self, texels: u64) -> Self {
        self.texel_budget = texels;
        self
    }
    /// With this practical-split weight (1: logarithmic splits).
    #[must_use]
    pub const fn with_split_lambda(mut self, lambda: f32) -> Self {
        self.split_lambda = lambda;
        self
    }
    /// With this RTW importance-map side.
    #[must_use]
    pub const fn with_rtw_importance_side(mut self, side: u32) -> Self {
        self.rtw_importance_side = side;
        self
    }

    /// Side of each of `layers` square maps sharing the budget.
    #[must_use]
    pub fn layer_side(&self, layers: u32) -> u32 {
        shadowmap::layer_side(self.texel_budget, layers)
    }
}

/// What a technique may look at in one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameContext<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// The light.
    pub light: &'a Light,
    /// Receiver and caster bounds.
    pub scene: SceneBounds,
    /// The surfaces the eye sees (RTW's backward analysis and oracle, IPSM's depth
    /// bounds).
    pub eye_samples: &'a [EyeSample],
    /// Vertical focal length of the measured image in pixels (RTW oracle).
    pub pixels_per_radian: f32,
}

/// The eye samples of a G-buffer (every visible pixel).
#[must_use]
pub fn eye_samples(gbuffer: &GBuffer, camera: &Camera) -> Vec<EyeSample> {
    let eye = camera.eye().as_dvec3();
    gbuffer
        .surfaces
        .iter()
        .flatten()
        .map(|s| EyeSample {
            position: s.position.as_vec3(),
            normal: s.normal.as_vec3(),
            eye_distance: (s.position - eye).length() as f32,
        })
        .collect()
}

/// A technique fitted to one frame through [`shadowmap::fit`], with its depth pass
/// for the reference rasterizer.
#[derive(Debug)]
pub struct Technique {
    kind: TechniqueKind,
    /// The technique that was fitted: `kind` itself, or the candidate `auto` chose.
    chosen: TechniqueKind,
    shadow: Shadow,
}

/// A depth-pass matrix that clips everything (unused cascade layers).
const CLIP_ALL: DMat4 = DMat4::from_cols(
    DVec4::ZERO,
    DVec4::ZERO,
    DVec4::ZERO,
    DVec4::new(0.0, 0.0, -1.0, 1.0),
);

fn fail(kind: TechniqueKind, reason: &dyn core::fmt::Display) -> EvalError {
    EvalError::Technique {
        technique: kind.name(),
        reason: reason.to_string(),
    }
}

impl Technique {
    /// Fits `kind` to a single frame with [`shadowmap::fit`] (eye samples, their depth
    /// bounds and the image's focal length as the optional inputs).
    ///
    /// # Errors
    /// [`EvalError::Technique`] when the technique does not apply to the light or its
    /// builder refuses the frame (the reason is the math crate's error).
    pub fn build(
        kind: TechniqueKind,
        frame: &FrameContext<'_>,
        options: &TechniqueOptions,
    ) -> Result<Self, EvalError> {
        Self::build_with_state(kind, frame, options, &mut FitState::default())
    }

    /// As [`Technique::build`], for one frame of a sequence: `state` carries what a
    /// renderer keeps from frame to frame ([`shadowmap::fit_with_state`]: `auto`'s
    /// choice, the stable cascades' held sizes, the cascade count).
    ///
    /// # Errors
    /// As [`Technique::build`].
    pub fn build_with_state(
        kind: TechniqueKind,
        frame: &FrameContext<'_>,
        options: &TechniqueOptions,
        state: &mut FitState,
    ) -> Result<Self, EvalError> {
        let input = FitInput::new(frame.camera, frame.light, frame.scene, options.texel_budget)
            .with_eye_samples(frame.eye_samples)
            .with_depth_bounds(depth_bounds_of(frame.camera, frame.eye_samples))
            .with_pixels_per_radian(frame.pixels_per_radian);
        let shadow =
            fit_with_state(&kind.technique(options), &input, state).map_err(|e| fail(kind, &e))?;
        let chosen = TechniqueKind::of(shadow.technique()).unwrap_or(kind);
        Ok(Self {
            kind,
            chosen,
            shadow,
        })
    }

    /// Which technique this is.
    #[must_use]
    pub const fn kind(&self) -> TechniqueKind {
        self.kind
    }

    /// The technique actually fitted: [`kind`](Self::kind), or for
    /// [`TechniqueKind::Auto`] the candidate it chose.
    #[must_use]
    pub const fn chosen(&self) -> TechniqueKind {
        self.chosen
    }

    /// The fitted shadow.
    #[must_use]
    pub const fn shadow(&self) -> &Shadow {
        &self.shadow
    }

    /// Number of layers (cascades, paraboloid sides).
    #[must_use]
    pub const fn layers(&self) -> u32 {
        self.shadow.layers()
    }

    /// Resolution `(width, height)` of each layer (a cube map's faces may differ).
    #[must_use]
    pub fn layer_sizes(&self) -> Vec<(u32, u32)> {
        if let Some(cube) = self.shadow.cube() {
            return cube.faces.iter().map(|f| (f.size[0], f.size[1])).collect();
        }
        if let Some(tiled) = self.shadow.tiled_cube() {
            let stored = |t: &shadowmap::paraboloid::CubeTile| t.side + 2 * tiled.border;
            return tiled.tiles.iter().map(|t| (stored(t), stored(t))).collect();
        }
        let side = self.shadow.layer_side();
        vec![(side, side); self.layers() as usize]
    }

    /// Texels over all layers (a cube map's whole atlas).
    #[must_use]
    pub fn texels(&self) -> u64 {
        self.shadow.texels()
    }

    /// The paraboloid map, for paraboloid techniques (e.g. to tell single from dual).
    #[must_use]
    pub const fn paraboloid(&self) -> Option<&shadowmap::paraboloid::ParaboloidMap> {
        self.shadow.paraboloid()
    }

    /// Renders the technique's depth map of `mesh` with the reference rasterizer.
    /// Paraboloid layers are rendered from a subdivided mesh (wgpu has no
    /// tessellation; see `shadowmap_paraboloid::subdivide_triangles`), each side on
    /// its own.
    ///
    /// # Errors
    /// The rasterizer's errors; [`EvalError::Technique`] when subdivision fails.
    pub fn rasterize(&self, mesh: &Mesh, options: &RasterOptions) -> Result<DepthMap, EvalError> {
        let side = self.shadow.layer_side();
        let options = options.with_size(side, side);
        if let Some(t) = self.shadow.transform() {
            return rasterize_depth(mesh, &MatrixProjector::from(t), &options);
        }
        if let Some(map) = self.shadow.paraboloid() {
            return self.rasterize_paraboloid(map, [None, None], mesh, &options);
        }
        if let Some(shadow) = self.shadow.rtw() {
            // The depth pass warps vertices only: the same crack-free caster
            // subdivision as the GPU depth pass, for a map of this side.
            let triangles: Vec<[Vec3; 3]> = mesh.triangles_f32();
            let subdivision = RtwSubdivision::default().with_resolution(side);
            let mut pieces = Vec::new();
            subdivide_for_rtw(&shadow, &triangles, &subdivision, &mut pieces);
            return rasterize_depth(&mesh_of(&pieces), &RtwProjector::from(shadow), &options);
        }
        match self.shadow.fitted() {
            Fitted::Cascades(set) => rasterize_depth(mesh, &MatrixProjector::from(set), &options),
            Fitted::Cube(cube) => rasterize_cube(cube, None, mesh, &options),
            Fitted::CubeRtw { cube, warps } => rasterize_cube(cube, Some(warps), mesh, &options),
            Fitted::TiledCube(tiled) => rasterize_tiles(tiled, mesh, &options),
            Fitted::WarpedCascades { cascades, .. } => {
                let matrices = cascades
                    .cascades
                    .iter()
                    .map(|c| {
                        c.shadow
                            .map_or(CLIP_ALL, |s| s.transform.clip_from_world.as_dmat4())
                    })
                    .collect();
                rasterize_depth(mesh, &MatrixProjector::new(matrices, false), &options)
            }
            Fitted::PointRtw { plan, front, back } => {
                self.rasterize_paraboloid(&plan.map, [Some(front), back.as_ref()], mesh, &options)
            }
            _ => Err(fail(self.kind, &"no depth pass for this result")),
        }
    }

    /// Each side of a paraboloid map from its subdivided mesh; a side with warp
    /// tables (RTW over the paraboloid) is subdivided by the RTW rule measured on the
    /// side's warped projection instead, and its vertices warped.
    fn rasterize_paraboloid(
        &self,
        map: &shadowmap::paraboloid::ParaboloidMap,
        warps: [Option<&WarpMaps>; 2],
        mesh: &Mesh,
        options: &RasterOptions,
    ) -> Result<DepthMap, EvalError> {
        let side = self.shadow.layer_side();
        let layers = self.layers();
        let triangles: Vec<[Vec3; 3]> = mesh.triangles_f32();
        let sub = SubdivisionOptions::default().with_resolution(side);
        let mut out = DepthMap::cleared(side, side, layers, map.reversed_z)?;
        let per_layer = side as usize * side as usize;
        let mut pieces = Vec::new();
        for layer in 0..layers {
            let which = if layer == 0 { Side::Front } else { Side::Back };
            let one = OneLayer {
                inner: ParaboloidProjector::from(map),
                layer,
            };
            let d = if let Some(warps) = warps.get(layer as usize).copied().flatten() {
                // One pass of the RTW rule over the casters: it measures the warped
                // image of the curved side, so it follows the paraboloid's curvature
                // and the warp together (subdividing the paraboloid's pieces again
                // would multiply the two limits: up to 16² x 32² pieces a caster).
                // Casters are cut at the side's plane (the part behind is clipped),
                // and an edge may be cut finely enough to cross the side's whole
                // disc in pieces of the span bound.
                let uv = |p: Vec3| map.project(p, which).map(|s| s.uv);
                let clip = |p: Vec3| map.plane_distance(p, which);
                let cells = warps.x_table().len().max(warps.y_table().len());
                let rtw = RtwSubdivision::default()
                    .with_resolution(side)
                    .with_segments_for_extent(1.0 / f64::from(map.zoom), cells);
                subdivide_for_rtw_clipped(uv, &[&clip], warps, &triangles, &rtw, &mut pieces);
                let inner = WarpedProjector { inner: one, warps };
                rasterize_depth(&mesh_of(&pieces), &inner, options)?
            } else {
                subdivide_triangles(map, which, &triangles, &sub, &mut pieces)
                    .map_err(|x| fail(self.kind, &x))?;
                rasterize_depth(&mesh_of(&pieces), &one, options)?
            };
            let at = layer as usize * per_layer;
            out.depth[at..at + per_layer].copy_from_slice(&d.depth);
        }
        Ok(out)
    }
}

/// The faces of a cube map, each rendered by the matrix depth pass at its own side,
/// one layer each (they are the tiles of the cube's atlas; the metrics count their
/// texels, the report the atlas's). With warp tables (RTW over the faces), each
/// face's casters are cut to its window's frustum, subdivided by the RTW rule and
/// their vertices warped.
fn rasterize_cube(
    cube: &CubeMap,
    warps: Option<&[WarpMaps]>,
    mesh: &Mesh,
    options: &RasterOptions,
) -> Result<DepthMap, EvalError> {
    let triangles: Vec<[Vec3; 3]> = mesh.triangles_f32();
    let mut pieces = Vec::new();
    let mut faces = Vec::with_capacity(cube.faces.len());
    for (i, f) in cube.faces.iter().enumerate() {
        let clip = f.clip_from_world.as_dmat4();
        let face_options = options.with_size(f.size[0], f.size[1]);
        faces.push(match warps.and_then(|w| w.get(i)) {
            Some(w) => {
                let side = f.size[0].max(f.size[1]);
                warped::face_pieces(clip, f.near, w, side, &triangles, &mut pieces);
                let inner = warped::DividedProjector {
                    clip_from_world: clip,
                    reversed_z: cube.reversed_z,
                };
                let projector = WarpedProjector { inner, warps: w };
                rasterize_depth(&mesh_of(&pieces), &projector, &face_options)?
            }
            None => {
                let projector = MatrixProjector::new(vec![clip], cube.reversed_z);
                rasterize_depth(mesh, &projector, &face_options)?
            }
        });
    }
    DepthMap::from_layers(faces)
}

/// The tiles of a tiled cube map, one layer each, each rendered through its face's
/// projection cropped to the tile (as the GPU pass draws each tile into its square
/// of the atlas).
fn rasterize_tiles(
    tiled: &TiledCube,
    mesh: &Mesh,
    options: &RasterOptions,
) -> Result<DepthMap, EvalError> {
    let reversed_z = tiled.cube.reversed_z;
    let mut tiles = Vec::with_capacity(tiled.tiles.len());
    for index in 0..tiled.tiles.len() {
        let (Some(clip), Some((_, side))) = (
            tiled.tile_clip_from_world(index),
            tiled.tile_viewport(index),
        ) else {
            return Err(EvalError::Technique {
                technique: "cube_tiled",
                reason: "a tile without a projection".into(),
            });
        };
        let projector = MatrixProjector::new(vec![clip.as_dmat4()], reversed_z);
        tiles.push(rasterize_depth(
            mesh,
            &projector,
            &options.with_size(side, side),
        )?);
    }
    DepthMap::from_layers(tiles)
}

/// A mesh of `f32` triangles.
fn mesh_of(triangles: &[[Vec3; 3]]) -> Mesh {
    let mut mesh = Mesh::new();
    for t in triangles {
        mesh.push_triangle(t.map(Vec3::as_dvec3));
    }
    mesh
}

/// One layer of a projector, as layer 0.
struct OneLayer<P> {
    inner: P,
    layer: u32,
}

impl<P: DepthProjector> DepthProjector for OneLayer<P> {
    fn layers(&self) -> u32 {
        1
    }
    fn reversed_z(&self) -> bool {
        self.inner.reversed_z()
    }
    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<crate::raster::ClipVertex> {
        (layer == 0)
            .then(|| self.inner.project_vertex(self.layer, world))
            .flatten()
    }
}

impl ShadowMapping for Technique {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        self.shadow.map_point(world)
    }

    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        self.shadow.uv_differentials(centre, around)
    }
}
