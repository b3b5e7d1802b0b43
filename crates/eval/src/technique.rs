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
//! | directional | uniform focused, stable and tight cascades (PSSM over the depth bounds), LiSPSM, XPSM, TSM, warped cascades (PSSM + LiSPSM), auto (the candidate with the lowest predicted error), RTW (backward importance), RTW oracle |
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
    Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, DepthBounds, Light, SceneBounds,
    ShadowMapping, ShadowSample, ShadowTransform, SplitScheme, fit_spot,
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
    LispsmOptions, TsmOptions, UniformOptions, XpsmOptions, lispsm, tsm, uniform_focused,
    warped_cascades, xpsm,
};

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

pub use auto::AUTO_CANDIDATES;

/// Every technique of the comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TechniqueKind {
    /// Orthographic fit of frustum ∩ receivers (`shadowmap_warp::uniform_focused`).
    UniformFocused,
    /// PSSM, stable: `CascadeSet::fit` with the stable fit clipped to the receivers on a
    /// ladder of sizes; practical splits of the eye's depth bounds, cascade count from
    /// their ratio (see `cascade_splits`).
    StableCascades,
    /// PSSM, tight (SDSM-style): `CascadeSet::fit` with the tight fit to slice ∩
    /// receivers over the same splits as [`TechniqueKind::StableCascades`].
    TightCascades,
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
    pub const ALL: [Self; 14] = [
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
            Self::TightCascades => "tight_cascades",
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
                    | Self::TightCascades
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
        let focus = frame.scene;
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
            TechniqueKind::StableCascades | TechniqueKind::TightCascades => {
                let splits =
                    cascade_splits(camera, frame.eye_samples, options).map_err(|x| e(&x))?;
                let layers = u32::try_from(splits.count()).unwrap_or(u32::MAX);
                let side = options.layer_side(layers);
                let fit = CascadeOptions::default()
                    .with_resolution(side)
                    .with_scene(Some(frame.scene));
                let fit = if kind == TechniqueKind::StableCascades {
                    fit.with_stable_size_step(Some(STABLE_SIZE_STEP))
                } else {
                    fit.with_fit(CascadeFit::Tight)
                };
                let set = CascadeSet::fit(camera, direction, &splits, &fit).map_err(|x| e(&x))?;
                (Inner::Cascades(Box::new(set)), layers, side)
            }
            TechniqueKind::WarpedCascades => {
                // The same split rule as the unwarped cascades: count and range from
                // the eye's depth bounds, so no cascade is spent on empty depth.
                let splits =
                    cascade_splits(camera, frame.eye_samples, options).map_err(|x| e(&x))?;
                let count = splits.count();
                let layers = u32::try_from(count).unwrap_or(u32::MAX);
                let side = options.layer_side(layers);
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

/// Ladder step of the stable cascades' sizes: a rung every half octave.
const STABLE_SIZE_STEP: f32 = core::f32::consts::SQRT_2;

/// Splits of the cascaded matrix techniques: practical splits of the eye's depth
/// bounds (the camera's range without samples), so no cascade covers empty depth.
/// The count follows the bounds' ratio `r = max / min`: with `k` maps sharing the
/// budget, a logarithmic split leaves each cascade a depth ratio `r^(1/k)` on
/// `side(k)` texels, so the count minimizing `r^(1/k) / side(k)` is taken, among the
/// counts up to `options.cascades` whose side is a power of two when there are any
/// (the stable fit's whole-texel motion is exact in `f32` only there).
fn cascade_splits(
    camera: &Camera,
    samples: &[EyeSample],
    options: &TechniqueOptions,
) -> Result<CascadeSplits, shadowmap_frustum::FrustumError> {
    let (near, far) = match depth_bounds(camera, samples) {
        Some(bounds) => bounds.clamped_to(camera)?,
        None => camera.depth_range()?,
    };
    let ratio = f64::from(far) / f64::from(near);
    let max = options.cascades.clamp(1, shadowmap_frustum::MAX_CASCADES);
    let power_of_two = |k: &usize| options.layer_side(*k as u32).is_power_of_two();
    let any_power = (1..=max).any(|k| power_of_two(&k));
    let cost = |k: usize| ratio.powf(1.0 / k as f64) / f64::from(options.layer_side(k as u32));
    let count = (1..=max)
        .filter(|k| !any_power || power_of_two(k))
        .min_by(|a, b| cost(*a).total_cmp(&cost(*b)))
        .unwrap_or(1);
    CascadeSplits::new(
        &SplitScheme::Practical {
            lambda: options.split_lambda,
        },
        count,
        near,
        far,
    )
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
