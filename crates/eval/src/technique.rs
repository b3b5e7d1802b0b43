//! The techniques under comparison, built for one frame of a configuration at an
//! equal texel budget.
//!
//! [`TechniqueKind`] lists them; [`Technique::build`] fits one to a frame
//! ([`FrameContext`]: camera, light, scene bounds, the eye's visible samples) and
//! returns something that is both a [`ShadowMapping`] (the lookup the metrics
//! measure) and a depth pass for the reference rasterizer
//! ([`Technique::rasterize`]), with its per-layer resolution.
//!
//! | light | techniques |
//! |---|---|
//! | directional | uniform focused, stable cascades (PSSM, practical split), LiSPSM, XPSM, TSM, warped cascades (PSSM + LiSPSM), auto (the candidate with the lowest predicted error), RTW (backward importance), RTW oracle |
//! | spot | spot fit |
//! | point | DPSM, IPSM with the paper's cone, IPSM with the exact minimal cone |
//!
//! Budget: `texel_budget` texels in total ([`TechniqueOptions`], default `1024²`),
//! split evenly over the layers: one `1024²` map, four cascades of `512²`, a dual
//! paraboloid of `2 x 724²` (an IPSM plan that falls back to dual gets `2 x 724²`
//! too). A technique that cannot handle a frame returns
//! [`EvalError::Technique`] with the math crate's reason, never panics.

use glam::{DMat4, DVec3, DVec4, Vec3};
use shadowmap_frustum::{
    Camera, CascadeOptions, CascadeSet, CascadeSplits, DepthBounds, Light, PredictOptions,
    SceneBounds, ShadowMapping, ShadowSample, ShadowTransform, SplitScheme, TechniqueSelector,
    fit_spot, predict_error,
};
use shadowmap_paraboloid::{
    ConeFit, IpsmOptions, IpsmPlan, MapOptions, ParaboloidMap, Side, SubdivisionOptions,
    subdivide_triangles,
};
use shadowmap_rtw::{
    EyeSample, ImportanceMap, ImportanceOptions, OracleAxis, RtwShadow, RtwSubdivision, WarpMaps,
    WarpOptions, subdivide_for_rtw,
};
use shadowmap_warp::{
    FocusScene, LispsmOptions, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
};

use crate::EvalError;
use crate::mask::GBuffer;
use crate::raster::{
    DepthMap, DepthProjector, MatrixProjector, ParaboloidProjector, RasterOptions, RtwProjector,
    rasterize_depth,
};
use crate::scene::Mesh;

/// Every technique of the comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TechniqueKind {
    /// Orthographic fit of frustum ∩ receivers (`shadowmap_warp::uniform_focused`).
    UniformFocused,
    /// PSSM: `CascadeSet::fit`, practical split, stable fit.
    StableCascades,
    /// Light space perspective shadow maps, `eta = 0`.
    Lispsm,
    /// Extended perspective shadow maps.
    Xpsm,
    /// Trapezoidal shadow maps.
    Tsm,
    /// PSSM with LiSPSM per cascade (`shadowmap_warp::warped_cascades`).
    WarpedCascades,
    /// Rectilinear texture warping over the uniform fit, importance from the eye's
    /// samples (backward analysis).
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
    /// Dual paraboloid (front facing world `-Y`), not view-dependent.
    Dpsm,
    /// IPSM with the paper's averaged cone.
    IpsmPaper,
    /// IPSM with the exact minimal cone.
    IpsmExact,
}

impl TechniqueKind {
    /// All techniques, in report order.
    pub const ALL: [Self; 13] = [
        Self::UniformFocused,
        Self::StableCascades,
        Self::Lispsm,
        Self::Xpsm,
        Self::Tsm,
        Self::WarpedCascades,
        Self::Auto,
        Self::Rtw,
        Self::RtwOracle,
        Self::SpotFit,
        Self::Dpsm,
        Self::IpsmPaper,
        Self::IpsmExact,
    ];

    /// Short identifier for tables and file names.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::UniformFocused => "uniform",
            Self::StableCascades => "cascades",
            Self::Lispsm => "lispsm",
            Self::Xpsm => "xpsm",
            Self::Tsm => "tsm",
            Self::WarpedCascades => "warped_cascades",
            Self::Auto => "auto",
            Self::Rtw => "rtw",
            Self::RtwOracle => "rtw_oracle",
            Self::SpotFit => "spot",
            Self::Dpsm => "dpsm",
            Self::IpsmPaper => "ipsm_paper",
            Self::IpsmExact => "ipsm_exact",
        }
    }

    /// Whether the technique is meant for this kind of light.
    #[must_use]
    pub const fn applies_to(self, light: &Light) -> bool {
        match light {
            Light::Directional { .. } => matches!(
                self,
                Self::UniformFocused
                    | Self::StableCascades
                    | Self::Lispsm
                    | Self::Xpsm
                    | Self::Tsm
                    | Self::WarpedCascades
                    | Self::Auto
                    | Self::Rtw
                    | Self::RtwOracle
            ),
            Light::Spot { .. } => matches!(self, Self::SpotFit),
            Light::Point { .. } => matches!(self, Self::Dpsm | Self::IpsmPaper | Self::IpsmExact),
        }
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
        let per = self.texel_budget / u64::from(layers.max(1));
        ((per as f64).sqrt().floor() as u32).max(4)
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

enum Inner {
    /// One matrix map.
    Matrix(ShadowTransform),
    /// Stable cascades.
    Cascades(Box<CascadeSet>),
    /// Warped cascades: view-depth ranges and fits (`None`: slice without receivers).
    Warped {
        eye: DVec3,
        forward: DVec3,
        cascades: Vec<((f64, f64), Option<ShadowTransform>)>,
    },
    /// A paraboloid map (single or dual).
    Paraboloid(ParaboloidMap),
    /// RTW: base fit and warp tables.
    Rtw {
        base: ShadowTransform,
        warps: Box<WarpMaps>,
    },
}

/// The candidates of [`TechniqueKind::Auto`], from the most to the least preferred
/// when predictions tie.
pub const AUTO_CANDIDATES: [TechniqueKind; 6] = [
    TechniqueKind::UniformFocused,
    TechniqueKind::Lispsm,
    TechniqueKind::Tsm,
    TechniqueKind::Xpsm,
    TechniqueKind::WarpedCascades,
    TechniqueKind::StableCascades,
];

/// A technique fitted to one frame.
pub struct Technique {
    kind: TechniqueKind,
    /// The technique that was fitted: `kind` itself, or the candidate `auto` chose.
    chosen: TechniqueKind,
    inner: Inner,
    layers: u32,
    side: u32,
}

impl core::fmt::Debug for Technique {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Technique")
            .field("kind", &self.kind)
            .field("chosen", &self.chosen)
            .field("layers", &self.layers)
            .field("side", &self.side)
            .finish_non_exhaustive()
    }
}

fn fail(kind: TechniqueKind, reason: &dyn core::fmt::Display) -> EvalError {
    EvalError::Technique {
        technique: kind.name(),
        reason: reason.to_string(),
    }
}

/// A depth-pass matrix that clips everything (unused cascade layers).
const CLIP_ALL: DMat4 = DMat4::from_cols(
    DVec4::ZERO,
    DVec4::ZERO,
    DVec4::ZERO,
    DVec4::new(0.0, 0.0, -1.0, 1.0),
);

impl Technique {
    /// Fits `kind` to a frame.
    ///
    /// # Errors
    /// [`EvalError::Technique`] when the technique does not apply to the light or its
    /// builder refuses the frame (the reason is the math crate's error).
    pub fn build(
        kind: TechniqueKind,
        frame: &FrameContext<'_>,
        options: &TechniqueOptions,
    ) -> Result<Self, EvalError> {
        if !kind.applies_to(frame.light) {
            return Err(fail(kind, &"not for this kind of light"));
        }
        if kind == TechniqueKind::Auto {
            return Self::build_auto(frame, options);
        }
        let focus = FocusScene::new(frame.scene.receivers, frame.scene.casters);
        let camera = frame.camera;
        let direction = match *frame.light {
            Light::Directional { direction } => direction,
            _ => Vec3::ZERO,
        };
        let single = options.layer_side(1);
        let e = |err: &dyn core::fmt::Display| fail(kind, err);
        let (inner, layers, side) = match kind {
            TechniqueKind::UniformFocused => {
                let t = uniform_focused(camera, direction, &focus, &UniformOptions::default())
                    .map_err(|x| e(&x))?;
                (Inner::Matrix(t), 1, single)
            }
            TechniqueKind::Lispsm => {
                let t = lispsm(camera, direction, &focus, &LispsmOptions::default())
                    .map_err(|x| e(&x))?;
                (Inner::Matrix(t.transform), 1, single)
            }
            TechniqueKind::Xpsm => {
                let t =
                    xpsm(camera, direction, &focus, &XpsmOptions::default()).map_err(|x| e(&x))?;
                (Inner::Matrix(t.transform), 1, single)
            }
            TechniqueKind::Tsm => {
                let t =
                    tsm(camera, direction, &focus, &TsmOptions::default()).map_err(|x| e(&x))?;
                (Inner::Matrix(t.transform), 1, single)
            }
            TechniqueKind::StableCascades | TechniqueKind::WarpedCascades => {
                let count = options.cascades;
                let layers = u32::try_from(count).unwrap_or(u32::MAX);
                let side = options.layer_side(layers);
                let (near, far) = camera.depth_range().map_err(|x| e(&x))?;
                let splits = CascadeSplits::new(
                    &SplitScheme::Practical {
                        lambda: options.split_lambda,
                    },
                    count,
                    near,
                    far,
                )
                .and_then(|s| s.with_overlap(0.0))
                .map_err(|x| e(&x))?;
                if kind == TechniqueKind::StableCascades {
                    let set = CascadeSet::fit(
                        camera,
                        direction,
                        &splits,
                        &CascadeOptions::default()
                            .with_resolution(side)
                            .with_scene(Some(frame.scene)),
                    )
                    .map_err(|x| e(&x))?;
                    (Inner::Cascades(Box::new(set)), layers, side)
                } else {
                    let etas = vec![0.0; count];
                    let w = warped_cascades(
                        camera,
                        direction,
                        &focus,
                        &splits,
                        &etas,
                        &LispsmOptions::default(),
                    )
                    .map_err(|x| e(&x))?;
                    let cascades = w
                        .cascades
                        .iter()
                        .map(|c| {
                            (
                                (f64::from(c.near), f64::from(c.far)),
                                c.shadow.map(|s| s.transform),
                            )
                        })
                        .collect();
                    (
                        Inner::Warped {
                            eye: camera.eye().as_dvec3(),
                            forward: camera.forward().as_dvec3(),
                            cascades,
                        },
                        layers,
                        side,
                    )
                }
            }
            TechniqueKind::Auto => return Self::build_auto(frame, options),
            TechniqueKind::Rtw | TechniqueKind::RtwOracle => {
                let base = uniform_focused(camera, direction, &focus, &UniformOptions::default())
                    .map_err(|x| e(&x))?;
                let n = options.rtw_importance_side;
                let mut map = ImportanceMap::new(n, n).map_err(|x| e(&x))?;
                let mut warps = Box::new(WarpMaps::new(n, n).map_err(|x| e(&x))?);
                if kind == TechniqueKind::Rtw {
                    map.accumulate_backward(
                        &base,
                        frame.eye_samples,
                        None,
                        &ImportanceOptions::default(),
                    )
                    .map_err(|x| e(&x))?;
                    warps
                        .build(&map, &WarpOptions::default())
                        .map_err(|x| e(&x))?;
                } else {
                    // The oracle of a separable warp: each axis gets the density that
                    // axis needs (an isotropic requirement would spend texels on the
                    // axis that does not need them). Perspective-only (zero normal):
                    // true-normal requirements of surfaces seen edge-on are unbounded
                    // and, once normalized, starve the rest of the map.
                    let mut map_v = ImportanceMap::new(n, n).map_err(|x| e(&x))?;
                    let flat: Vec<EyeSample> = frame
                        .eye_samples
                        .iter()
                        .map(|s| EyeSample {
                            normal: glam::Vec3::ZERO,
                            ..*s
                        })
                        .collect();
                    for (axis, m) in [(OracleAxis::U, &mut map), (OracleAxis::V, &mut map_v)] {
                        m.accumulate_oracle_axis(
                            axis,
                            &base,
                            camera,
                            frame.pixels_per_radian,
                            &flat,
                        )
                        .map_err(|x| e(&x))?;
                    }
                    warps
                        .build_separable(&map, &map_v, &WarpOptions::default())
                        .map_err(|x| e(&x))?;
                }
                (Inner::Rtw { base, warps }, 1, single)
            }
            TechniqueKind::SpotFit => {
                let frustum = camera.frustum().map_err(|x| e(&x))?;
                let s = fit_spot(frame.light, &frustum, Some(&frame.scene), false)
                    .map_err(|x| e(&x))?;
                (Inner::Matrix(s.transform), 1, single)
            }
            TechniqueKind::Dpsm => {
                let (position, range) =
                    point_of(frame.light).ok_or_else(|| e(&"not a point light"))?;
                let map = ParaboloidMap::dual(
                    position,
                    Vec3::NEG_Y,
                    IpsmOptions::default().near,
                    range,
                    &MapOptions::default(),
                )
                .map_err(|x| e(&x))?;
                (Inner::Paraboloid(map), 2, options.layer_side(2))
            }
            TechniqueKind::IpsmPaper | TechniqueKind::IpsmExact => {
                let fit = if kind == TechniqueKind::IpsmPaper {
                    ConeFit::Paper
                } else {
                    ConeFit::Exact
                };
                let bounds = depth_bounds(camera, frame.eye_samples);
                let plan = IpsmPlan::new(
                    frame.light,
                    camera,
                    bounds,
                    &IpsmOptions::default().with_fit(fit),
                )
                .map_err(|x| e(&x))?;
                let layers = plan.map.layers();
                (
                    Inner::Paraboloid(plan.map),
                    layers,
                    options.layer_side(layers),
                )
            }
        };
        Ok(Self {
            kind,
            chosen: kind,
            inner,
            layers,
            side,
        })
    }

    /// `auto`: fits every candidate, predicts each one's 95th-percentile aliasing
    /// error with the receivers' box standing in for the surfaces, and keeps the
    /// lowest. The report fits each frame on its own, so the selector's hysteresis
    /// (which a renderer keeps across frames) does not apply here.
    fn build_auto(frame: &FrameContext<'_>, options: &TechniqueOptions) -> Result<Self, EvalError> {
        let mut fitted: Vec<Option<Self>> = Vec::with_capacity(AUTO_CANDIDATES.len());
        let mut predictions = Vec::with_capacity(AUTO_CANDIDATES.len());
        for kind in AUTO_CANDIDATES {
            let technique = Self::build(kind, frame, options).ok();
            let prediction = technique.as_ref().and_then(|t| {
                predict_error(
                    frame.camera,
                    &frame.scene.receivers,
                    t,
                    t.side,
                    &PredictOptions::default(),
                )
                .ok()
                .flatten()
                .map(|p| p.percentile)
            });
            fitted.push(technique);
            predictions.push(prediction);
        }
        let index = TechniqueSelector::new()
            .choose(&predictions)
            .ok_or_else(|| fail(TechniqueKind::Auto, &"no candidate could be fitted"))?;
        let chosen = fitted[index]
            .take()
            .ok_or_else(|| fail(TechniqueKind::Auto, &"no candidate could be fitted"))?;
        Ok(Self {
            kind: TechniqueKind::Auto,
            ..chosen
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

    /// Number of layers (cascades, paraboloid sides).
    #[must_use]
    pub const fn layers(&self) -> u32 {
        self.layers
    }

    /// Resolution `(width, height)` of each layer.
    #[must_use]
    pub fn layer_sizes(&self) -> Vec<(u32, u32)> {
        vec![(self.side, self.side); self.layers as usize]
    }

    /// Texels over all layers.
    #[must_use]
    pub fn texels(&self) -> u64 {
        u64::from(self.side) * u64::from(self.side) * u64::from(self.layers)
    }

    /// The paraboloid map, for paraboloid techniques (e.g. to tell single from dual).
    #[must_use]
    pub const fn paraboloid(&self) -> Option<&ParaboloidMap> {
        match &self.inner {
            Inner::Paraboloid(m) => Some(m),
            _ => None,
        }
    }

    /// Renders the technique's depth map of `mesh` with the reference rasterizer.
    /// Paraboloid layers are rendered from a subdivided mesh (wgpu has no
    /// tessellation; see `shadowmap_paraboloid::subdivide_triangles`), each side on
    /// its own.
    ///
    /// # Errors
    /// The rasterizer's errors; [`EvalError::Technique`] when subdivision fails.
    pub fn rasterize(&self, mesh: &Mesh, options: &RasterOptions) -> Result<DepthMap, EvalError> {
        let options = options.with_size(self.side, self.side);
        match &self.inner {
            Inner::Matrix(t) => rasterize_depth(mesh, &MatrixProjector::from(t), &options),
            Inner::Cascades(set) => {
                rasterize_depth(mesh, &MatrixProjector::from(set.as_ref()), &options)
            }
            Inner::Warped { cascades, .. } => {
                let matrices = cascades
                    .iter()
                    .map(|(_, t)| t.map_or(CLIP_ALL, |t| t.clip_from_world.as_dmat4()))
                    .collect();
                rasterize_depth(mesh, &MatrixProjector::new(matrices, false), &options)
            }
            Inner::Rtw { base, warps } => {
                let shadow = RtwShadow {
                    base: *base,
                    warps: warps.as_ref(),
                };
                // The depth pass warps vertices only: the same crack-free caster
                // subdivision as the GPU depth pass, for a map of this side.
                let triangles: Vec<[Vec3; 3]> =
                    mesh.triangles().map(|t| t.map(DVec3::as_vec3)).collect();
                let subdivision = RtwSubdivision::default().with_resolution(self.side);
                let mut pieces = Vec::new();
                subdivide_for_rtw(&shadow, &triangles, &subdivision, &mut pieces);
                let mut fine = Mesh::new();
                for t in &pieces {
                    fine.push_triangle(t.map(Vec3::as_dvec3));
                }
                rasterize_depth(&fine, &RtwProjector::from(shadow), &options)
            }
            Inner::Paraboloid(map) => self.rasterize_paraboloid(map, mesh, &options),
        }
    }

    fn rasterize_paraboloid(
        &self,
        map: &ParaboloidMap,
        mesh: &Mesh,
        options: &RasterOptions,
    ) -> Result<DepthMap, EvalError> {
        let triangles: Vec<[Vec3; 3]> = mesh.triangles().map(|t| t.map(DVec3::as_vec3)).collect();
        let sub = SubdivisionOptions::default().with_resolution(self.side);
        let mut out = DepthMap::cleared(self.side, self.side, self.layers, map.reversed_z)?;
        let per_layer = self.side as usize * self.side as usize;
        let mut pieces = Vec::new();
        for layer in 0..self.layers {
            let side = if layer == 0 { Side::Front } else { Side::Back };
            subdivide_triangles(map, side, &triangles, &sub, &mut pieces)
                .map_err(|x| fail(self.kind, &x))?;
            let mut fine = Mesh::new();
            for t in &pieces {
                fine.push_triangle(t.map(Vec3::as_dvec3));
            }
            let one = OneLayer {
                inner: ParaboloidProjector::from(map),
                layer,
            };
            let d = rasterize_depth(&fine, &one, options)?;
            let at = layer as usize * per_layer;
            out.depth[at..at + per_layer].copy_from_slice(&d.depth);
        }
        Ok(out)
    }
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

fn point_of(light: &Light) -> Option<(Vec3, f32)> {
    match *light {
        Light::Point { position, range }
        | Light::Spot {
            position, range, ..
        } => Some((position, range)),
        Light::Directional { .. } => None,
    }
}

/// Min/max view depth of the eye's samples (IPSM's truncated frustum), `None`
/// without samples.
fn depth_bounds(camera: &Camera, samples: &[EyeSample]) -> Option<DepthBounds> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for s in samples {
        let d = camera.view_depth(s.position);
        if d.is_finite() {
            lo = lo.min(d);
            hi = hi.max(d);
        }
    }
    (lo < hi).then_some(DepthBounds { min: lo, max: hi })
}

impl ShadowMapping for Technique {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        match &self.inner {
            Inner::Matrix(t) => t.map_point(world),
            Inner::Cascades(set) => set.map_point(world),
            Inner::Warped {
                eye,
                forward,
                cascades,
            } => {
                let depth = (world - *eye).dot(*forward);
                let (i, (_, t)) = cascades
                    .iter()
                    .enumerate()
                    .find(|(_, ((n, f), _))| depth >= *n && depth <= *f)?;
                let mut s = t.as_ref()?.map_point(world)?;
                s.layer = u32::try_from(i).ok()?;
                Some(s)
            }
            Inner::Paraboloid(map) => map.map_point(world),
            Inner::Rtw { base, warps } => RtwShadow {
                base: *base,
                warps: warps.as_ref(),
            }
            .map_point(world),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_is_shared_evenly() {
        let o = TechniqueOptions::default();
        assert_eq!(o.layer_side(1), 1024);
        assert_eq!(o.layer_side(4), 512);
        assert_eq!(o.layer_side(2), 724);
    }

    #[test]
    fn every_light_has_techniques() {
        let d = Light::Directional {
            direction: Vec3::NEG_Y,
        };
        let p = Light::Point {
            position: Vec3::Y,
            range: 10.0,
        };
        assert_eq!(TechniqueKind::for_light(&d).len(), 9);
        assert_eq!(TechniqueKind::for_light(&p).len(), 3);
        assert!(!TechniqueKind::SpotFit.applies_to(&d));
    }

    #[test]
    fn auto_is_the_candidate_with_the_lowest_prediction() {
        let camera = Camera::look_to(
            Vec3::new(0.0, 10.0, 0.0),
            Vec3::NEG_Z,
            Vec3::Y,
            shadowmap_frustum::Projection::perspective(1.0, 1.5, 1.0, 300.0),
        )
        .unwrap();
        let light = Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.1),
        };
        let b = shadowmap_frustum::Aabb::new(
            Vec3::new(-300.0, 0.0, -320.0),
            Vec3::new(300.0, 30.0, 20.0),
        );
        let frame = FrameContext {
            camera: &camera,
            light: &light,
            scene: SceneBounds {
                receivers: b,
                casters: b,
            },
            eye_samples: &[],
            pixels_per_radian: 100.0,
        };
        let o = TechniqueOptions::default().with_texel_budget(256 * 256);
        let auto = Technique::build(TechniqueKind::Auto, &frame, &o).unwrap();
        assert_eq!(auto.kind(), TechniqueKind::Auto);
        assert!(AUTO_CANDIDATES.contains(&auto.chosen()));
        let predicted = |t: &Technique| {
            predict_error(&camera, &b, t, t.side, &PredictOptions::default())
                .unwrap()
                .unwrap()
                .percentile
        };
        let chosen = Technique::build(auto.chosen(), &frame, &o).unwrap();
        let best = AUTO_CANDIDATES
            .iter()
            .filter_map(|k| Technique::build(*k, &frame, &o).ok())
            .map(|t| predicted(&t))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(predicted(&auto), predicted(&chosen));
        assert_eq!(predicted(&chosen), best);
        // A perspective view over open ground: a warp beats the uniform fit.
        assert_ne!(auto.chosen(), TechniqueKind::UniformFocused);
        let p = DVec3::new(1.0, 0.0, -20.0);
        assert_eq!(auto.map_point(p), chosen.map_point(p));
    }

    #[test]
    fn wrong_light_or_bad_frame_is_a_typed_error() {
        let camera = Camera::look_to(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::NEG_Z,
            Vec3::Y,
            shadowmap_frustum::Projection::perspective(1.0, 1.5, 0.5, 100.0),
        )
        .unwrap();
        let light = Light::Directional {
            direction: Vec3::NEG_Y,
        };
        let b = shadowmap_frustum::Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0));
        let frame = FrameContext {
            camera: &camera,
            light: &light,
            scene: SceneBounds {
                receivers: b,
                casters: b,
            },
            eye_samples: &[],
            pixels_per_radian: 100.0,
        };
        let o = TechniqueOptions::default().with_texel_budget(64 * 64);
        let err = Technique::build(TechniqueKind::IpsmExact, &frame, &o).unwrap_err();
        assert!(matches!(
            err,
            EvalError::Technique {
                technique: "ipsm_exact",
                ..
            }
        ));
        // Receivers behind the camera: the warp crate's error, not a panic.
        let behind =
            shadowmap_frustum::Aabb::new(Vec3::new(-5.0, -5.0, 10.0), Vec3::new(5.0, 5.0, 20.0));
        let frame = FrameContext {
            scene: SceneBounds {
                receivers: behind,
                casters: behind,
            },
            ..frame
        };
        // (Stable cascades have a documented fallback instead: the whole slice.)
        for kind in TechniqueKind::for_light(&light) {
            if kind == TechniqueKind::StableCascades {
                assert!(Technique::build(kind, &frame, &o).is_ok());
                continue;
            }
            match Technique::build(kind, &frame, &o) {
                Err(EvalError::Technique { reason, .. }) => assert!(!reason.is_empty()),
                other => panic!("{}: {other:?}", kind.name()),
            }
        }
        // A valid frame builds every directional technique within the budget.
        let t = Technique::build(
            TechniqueKind::StableCascades,
            &FrameContext {
                scene: SceneBounds {
                    receivers: b,
                    casters: b,
                },
                ..frame
            },
            &o,
        )
        .unwrap();
        assert_eq!((t.layers(), t.texels()), (4, 4 * 32 * 32));
    }
}
