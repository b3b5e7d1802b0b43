//! [`fit`]: one entry point for every technique, the same inputs for all.

use alloc::vec::Vec;
use core::fmt;

use glam::Vec3;
use shadowmap_frustum::math::{floor, sqrt};
use shadowmap_frustum::{
    Camera, CascadeState, DepthBounds, FRONT_LIT_MIN_COS, FrustumError, Light, LightDirection,
    MAX_PREDICT_CANDIDATES, PredictOptions, PredictedError, SceneBounds, ShadowMapping,
    ShadowTransform, TechniqueSelector, fit_spot, predict_errors,
};
use shadowmap_paraboloid::{ParaboloidError, ParaboloidMap};
use shadowmap_rtw::{EyeSample, ImportanceMap, OracleAxis, RtwError, RtwShadow, WarpMaps};
use shadowmap_warp::{FocusBody, WarpError, spot_warp, uniform_focused};

use crate::cascaded::{fit_cascades, fit_warped};
use crate::point_fit;
use crate::rtw_strength::{LitSplit, build_measured_by, warped_error};
use crate::shadow::{Fitted, Shadow};
use crate::technique::{DpsmOptions, RtwPlan, Technique};
use crate::warp_fit::fit_warp;

/// What a technique may look at in one frame: the same for every technique.
///
/// Required: camera, light, scene bounds, texel budget. Optional, read only by the
/// techniques that need them (see the crate docs' table):
/// [`eye_samples`](Self::eye_samples) (RTW and the RTW oracle, required there;
/// `auto` and IPSM measure their candidates on them with
/// [`pixels_per_radian`](Self::pixels_per_radian)),
/// [`pixels_per_radian`](Self::pixels_per_radian) (RTW oracle, required there),
/// [`depth_bounds`](Self::depth_bounds) (cascades, warped cascades, auto, IPSM, cube maps; the
/// camera's depth range without them).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct FitInput<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// The light.
    pub light: &'a Light,
    /// Receiver and caster bounds.
    pub scene: SceneBounds,
    /// Texels over all layers; each of `k` layers gets a square of side
    /// `floor(sqrt(budget / k))` (at least 4).
    pub texel_budget: u64,
    /// The surfaces the eye sees (e.g. a G-buffer's visible pixels).
    pub eye_samples: Option<&'a [EyeSample]>,
    /// Min/max view depth of the visible surfaces (e.g. a depth reduction, or
    /// [`depth_bounds_of`] the eye samples).
    pub depth_bounds: Option<DepthBounds>,
    /// Vertical focal length of the image in pixels.
    pub pixels_per_radian: Option<f32>,
}

impl<'a> FitInput<'a> {
    /// The direction a directional light travels; zero for a point or spot light
    /// (which every directional builder refuses with its own error).
    pub(crate) const fn light_direction(&self) -> Vec3 {
        match *self.light {
            Light::Directional { direction } => direction,
            _ => Vec3::ZERO,
        }
    }

    /// The inputs every technique needs, none of the optional ones.
    #[must_use]
    pub const fn new(
        camera: &'a Camera,
        light: &'a Light,
        scene: SceneBounds,
        texel_budget: u64,
    ) -> Self {
        Self {
            camera,
            light,
            scene,
            texel_budget,
            eye_samples: None,
            depth_bounds: None,
            pixels_per_radian: None,
        }
    }
    /// With the eye's visible surfaces.
    #[must_use]
    pub const fn with_eye_samples(mut self, samples: &'a [EyeSample]) -> Self {
        self.eye_samples = Some(samples);
        self
    }
    /// With measured depth bounds (`None`: the camera's range).
    #[must_use]
    pub const fn with_depth_bounds(mut self, bounds: Option<DepthBounds>) -> Self {
        self.depth_bounds = bounds;
        self
    }
    /// With the image's vertical focal length in pixels.
    #[must_use]
    pub const fn with_pixels_per_radian(mut self, pixels_per_radian: f32) -> Self {
        self.pixels_per_radian = Some(pixels_per_radian);
        self
    }

    /// Side of each of `layers` square maps sharing the budget ([`layer_side`]).
    #[must_use]
    pub fn layer_side(&self, layers: u32) -> u32 {
        layer_side(self.texel_budget, layers)
    }
}

/// Side of each of `layers` square maps sharing `texel_budget` texels:
/// `floor(sqrt(budget / layers))`, at least 4.
#[must_use]
pub fn layer_side(texel_budget: u64, layers: u32) -> u32 {
    let per = texel_budget / u64::from(layers.max(1));
    (floor(sqrt(per as f64)) as u32).max(4)
}

/// Why [`fit`] refused a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum FitError {
    /// The technique is for another kind of light.
    WrongLight {
        /// [`Technique::name`].
        technique: &'static str,
    },
    /// A [`FitInput`] field the technique needs is `None`.
    MissingInput {
        /// [`Technique::name`].
        technique: &'static str,
        /// The field's name.
        input: &'static str,
    },
    /// A zero texel budget.
    InvalidBudget,
    /// `auto`: no candidate could be fitted and predicted.
    NoCandidate,
    /// From `shadowmap-frustum` (cameras, lights, cascades, spot fit).
    Frustum(FrustumError),
    /// From `shadowmap-warp` (uniform, LiSPSM, XPSM, TSM, warped cascades).
    Warp(WarpError),
    /// From `shadowmap-paraboloid` (DPSM, IPSM, cube maps).
    Paraboloid(ParaboloidError),
    /// From `shadowmap-rtw` (importance, warp tables).
    Rtw(RtwError),
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::WrongLight { .. } => f.write_str("not for this kind of light"),
            Self::MissingInput { input, .. } => write!(f, "missing input: {input}"),
            Self::InvalidBudget => f.write_str("texel budget is zero"),
            Self::NoCandidate => f.write_str("no candidate could be fitted"),
            Self::Frustum(e) => e.fmt(f),
            Self::Warp(e) => e.fmt(f),
            Self::Paraboloid(e) => e.fmt(f),
            Self::Rtw(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for FitError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Frustum(e) => Some(e),
            Self::Warp(e) => Some(e),
            Self::Paraboloid(e) => Some(e),
            Self::Rtw(e) => Some(e),
            _ => None,
        }
    }
}

impl From<FrustumError> for FitError {
    fn from(e: FrustumError) -> Self {
        Self::Frustum(e)
    }
}
impl From<WarpError> for FitError {
    fn from(e: WarpError) -> Self {
        Self::Warp(e)
    }
}
impl From<ParaboloidError> for FitError {
    fn from(e: ParaboloidError) -> Self {
        Self::Paraboloid(e)
    }
}
impl From<RtwError> for FitError {
    fn from(e: RtwError) -> Self {
        Self::Rtw(e)
    }
}

/// Fits `technique` to one frame. `auto` picks on this frame alone; a renderer that
/// keeps its choice across frames uses [`fit_with_selector`].
///
/// # Errors
/// [`FitError::WrongLight`] when the technique is for another kind of light;
/// [`FitError::MissingInput`] when an input it needs is `None`;
/// [`FitError::InvalidBudget`] for a zero budget; [`FitError::NoCandidate`] when no
/// `auto` candidate fits; otherwise the builder's own error, wrapped.
pub fn fit(technique: &Technique, input: &FitInput<'_>) -> Result<Shadow, FitError> {
    fit_with_selector(technique, input, &mut TechniqueSelector::new())
}

/// [`fit`], with the caller's `selector` keeping `auto`'s choice across frames
/// (hysteresis: it switches only when another candidate is predicted better by the
/// selector's margin). Other techniques ignore the selector; stable cascades start
/// from a fresh [`CascadeState`] (use [`fit_with_state`] to keep their sizes).
///
/// # Errors
/// As [`fit`].
pub fn fit_with_selector(
    technique: &Technique,
    input: &FitInput<'_>,
    selector: &mut TechniqueSelector,
) -> Result<Shadow, FitError> {
    let mut state = FitState {
        selector: *selector,
        ..FitState::default()
    };
    let shadow = fit_with_state(technique, input, &mut state);
    *selector = state.selector;
    shadow
}

/// What a renderer keeps from one frame to the next for one light and view:
/// `auto`'s choice, the stable cascades' held maps, and the cascade counts. Start
/// with `FitState::default()` and pass the same value to [`fit_with_state`] every
/// frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FitState {
    /// `auto`'s current choice, kept with hysteresis.
    pub selector: TechniqueSelector,
    /// The stable cascades' maps, of every count the count prediction fits, and
    /// their count, kept with hysteresis.
    pub cascades: CascadeState,
    /// The tight cascades' count, kept with hysteresis (their maps are not held):
    /// apart from the stable cascades', so that `auto`, which fits both each
    /// frame, does not hand one's count to the other.
    pub tight: CascadeState,
    /// The warped cascades' count, kept with hysteresis (their maps are not held).
    pub warped: CascadeState,
}

/// [`fit`], with the caller-held `state` threaded through the frames: `auto` keeps
/// its choice ([`TechniqueSelector`]), the stable cascades keep each map's size while
/// it still covers slice ∩ receivers and is not too big (so the maps move by whole
/// texels and do not shimmer), and the cascaded techniques keep their count unless
/// another count is clearly better. Other techniques ignore the state.
///
/// # Errors
/// As [`fit`].
pub fn fit_with_state(
    technique: &Technique,
    input: &FitInput<'_>,
    state: &mut FitState,
) -> Result<Shadow, FitError> {
    if !technique.applies_to(input.light) {
        return Err(FitError::WrongLight {
            technique: technique.name(),
        });
    }
    if input.texel_budget == 0 {
        return Err(FitError::InvalidBudget);
    }
    if let Technique::Auto(plan) = technique {
        return crate::auto::fit_auto(plan, input, state);
    }
    fit_candidate(technique, input, state, None)
}

/// [`fit_with_state`] for every technique but `auto`, its inputs checked; the
/// uniform fit and the warps of a directional light fit from `body` where given
/// (`auto` builds one for its candidates, so they cast its probe points once).
pub(crate) fn fit_candidate(
    technique: &Technique,
    input: &FitInput<'_>,
    state: &mut FitState,
    body: Option<&FocusBody>,
) -> Result<Shadow, FitError> {
    let (fitted, layers) = fit_one(technique, input, state, body)?;
    let layer_side = fitted
        .own_layer_side()
        .unwrap_or_else(|| input.layer_side(layers));
    Ok(Shadow {
        requested: *technique,
        technique: *technique,
        fitted,
        layers,
        layer_side,
    })
}

/// The result and layer count of every technique but `auto` (the uniform fit and
/// the warps from `body` where given).
fn fit_one(
    technique: &Technique,
    input: &FitInput<'_>,
    state: &mut FitState,
    body: Option<&FocusBody>,
) -> Result<(Fitted, u32), FitError> {
    let (camera, scene) = (input.camera, &input.scene);
    let direction = input.light_direction();
    Ok(match technique {
        Technique::UniformFocused(o) => (
            Fitted::Uniform(match body {
                Some(body) => body.uniform(o)?,
                None => uniform_focused(camera, direction, scene, o)?,
            }),
            1,
        ),
        Technique::Lispsm(_) | Technique::Xpsm(_) | Technique::Tsm(_) => {
            (fit_warp(technique, direction, input, body)?, 1)
        }
        Technique::StableCascades(plan) => {
            fit_cascades(plan, true, direction, input, &mut state.cascades)?
        }
        Technique::TightCascades(plan) => {
            fit_cascades(plan, false, direction, input, &mut state.tight)?
        }
        Technique::WarpedCascades { plan, lispsm } => {
            fit_warped(plan, lispsm, direction, input, &mut state.warped)?
        }
        Technique::Rtw(plan) | Technique::RtwOracle(plan) => {
            let base = uniform_focused(camera, direction, scene, &Default::default())?;
            let oracle = matches!(technique, Technique::RtwOracle(_));
            (fit_rtw(plan, oracle, technique.name(), base, input)?, 1)
        }
        Technique::SpotFit { reversed_z } => {
            let frustum = camera.frustum()?;
            let s = fit_spot(input.light, &frustum, Some(scene), *reversed_z)?;
            (Fitted::Spot(s), 1)
        }
        Technique::SpotWarp(o) => {
            let s = spot_warp(input.light, camera, input.depth_bounds, scene, o)?;
            (Fitted::SpotWarp(s), 1)
        }
        Technique::Dpsm(o) => (Fitted::Dpsm(fit_dpsm(o, input.light)?), 2),
        Technique::Ipsm(o) => {
            let plan = point_fit::fit_ipsm(o, input)?;
            let layers = plan.map.layers();
            (Fitted::Ipsm(plan), layers)
        }
        Technique::CubeMaps(o) => {
            let cube = point_fit::fit_cube(o, input)?;
            let layers = cube.layers();
            (Fitted::Cube(cube), layers)
        }
        // `fit_with_selector` handles `auto` before coming here.
        Technique::Auto(_) => return Err(FitError::NoCandidate),
        Technique::SpotRtw(plan) => {
            let frustum = camera.frustum()?;
            let base = fit_spot(input.light, &frustum, Some(scene), false)?.transform;
            (fit_rtw(plan, false, technique.name(), base, input)?, 1)
        }
        Technique::PointRtw { ipsm, rtw } => {
            let fitted = point_fit::fit_point_rtw(ipsm, rtw, input)?;
            let layers = fitted.layer_count();
            (fitted, layers)
        }
        Technique::CubeRtw { cube, rtw } => {
            let fitted = point_fit::fit_cube_rtw(cube, rtw, input)?;
            let layers = fitted.layer_count();
            (fitted, layers)
        }
        Technique::TiledCube { cube, tiles } => {
            let fitted = point_fit::fit_tiled_cube(cube, tiles, input)?;
            let layers = fitted.layer_count();
            (fitted, layers)
        }
    })
}

/// The predicted 95th percentile of each of `mappings` (mapping, texels per side),
/// all on the same rays (`shadowmap_frustum::predict_errors` with
/// [`predict_options`]), into `out` (`None`: not predicted).
///
/// # Errors
/// The prediction's errors; [`FitError::NoCandidate`] for more mappings than it
/// compares at once.
pub(crate) fn predicted_percentiles(
    input: &FitInput<'_>,
    mappings: &[(&dyn ShadowMapping, u32)],
    out: &mut [Option<f64>],
) -> Result<(), FitError> {
    let mut predicted = [None::<PredictedError>; MAX_PREDICT_CANDIDATES];
    predictions(input, mappings, &mut predicted)?;
    for (slot, p) in out.iter_mut().zip(predicted.iter()) {
        *slot = p.map(|p| p.percentile);
    }
    Ok(())
}

/// The predicted errors of `mappings` for a frame, all on the same rays, into the
/// first `mappings.len()` slots of `out`.
pub(crate) fn predictions(
    input: &FitInput<'_>,
    mappings: &[(&dyn ShadowMapping, u32)],
    out: &mut [Option<PredictedError>; MAX_PREDICT_CANDIDATES],
) -> Result<(), FitError> {
    let out = out.get_mut(..mappings.len()).ok_or(FitError::NoCandidate)?;
    predict_errors(
        input.camera,
        &input.scene.receivers,
        mappings,
        &predict_options(input),
        out,
    )?;
    Ok(())
}

/// Options of the error prediction for a frame: surfaces the light does not face
/// are dark whatever the map holds, so a directional light's prediction ranks on
/// the lit faces of the receivers' box; and the visible surfaces lie within the
/// depth bounds (when given), so no predicted point lies outside them.
fn predict_options(input: &FitInput<'_>) -> PredictOptions {
    let mut options = PredictOptions::default();
    if let Light::Directional { direction } = *input.light {
        options = options.with_light_direction(direction);
    }
    if let Some(bounds) = input.depth_bounds {
        if let Ok((near, far)) = bounds.clamped_to(input.camera) {
            options = options.with_depth_range(near, far);
        }
    }
    options
}

/// RTW over `base` (the uniform fit of a directional light, the spot fit of a spot
/// light): importance from the eye samples, or the oracle's exact density.
fn fit_rtw(
    plan: &RtwPlan,
    oracle: bool,
    name: &'static str,
    base: ShadowTransform,
    input: &FitInput<'_>,
) -> Result<Fitted, FitError> {
    let missing = |what| FitError::MissingInput {
        technique: name,
        input: what,
    };
    let samples = input.eye_samples.ok_or_else(|| missing("eye_samples"))?;
    let n = plan.importance_side;
    let mut warps = WarpMaps::new(n, n)?;
    if oracle {
        let pixels_per_radian = input
            .pixels_per_radian
            .ok_or_else(|| missing("pixels_per_radian"))?;
        oracle_warps(
            plan,
            &base,
            input.camera,
            pixels_per_radian,
            samples,
            &mut warps,
        )?;
    } else {
        sampled_warps(plan, &base, input, samples, &mut warps)?;
    }
    Ok(Fitted::Rtw { base, warps })
}

/// The oracle of a separable warp: each axis gets the density that axis needs (an
/// isotropic requirement would spend texels on the axis that does not need them).
/// Perspective-only (zero normal): true-normal requirements of surfaces seen
/// edge-on are unbounded and, once normalized, starve the rest of the map.
fn oracle_warps(
    plan: &RtwPlan,
    base: &ShadowTransform,
    camera: &Camera,
    pixels_per_radian: f32,
    samples: &[EyeSample],
    warps: &mut WarpMaps,
) -> Result<(), FitError> {
    let n = plan.importance_side;
    let (mut map_u, mut map_v) = (ImportanceMap::new(n, n)?, ImportanceMap::new(n, n)?);
    let flat: Vec<EyeSample> = samples
        .iter()
        .map(|s| EyeSample {
            normal: Vec3::ZERO,
            ..*s
        })
        .collect();
    for (axis, m) in [(OracleAxis::U, &mut map_u), (OracleAxis::V, &mut map_v)] {
        m.accumulate_oracle_axis(axis, base, camera, pixels_per_radian, &flat)?;
    }
    warps.build_separable(&map_u, &map_v, &plan.warp)?;
    Ok(())
}

/// RTW's tables from the backward importance of the eye samples. Under a
/// directional or spot light, from the importance of the front-lit samples or of
/// all of them, whichever measures the finer on the front-lit ones at its best
/// strength ([`build_measured_by`]; over `compare --sweep 64` at seeds 1 to 32 and
/// 49 to 60 the choice made 189 of 4,312 RTW rows and 149 of 3,740 spot RTW rows
/// finer, by up to 1.46x, and 7 coarser by at most 0.2%, the fit measuring on at
/// most 4,096 samples and the report on all); under a point light (over a map that
/// ignores where it is), from all of them at full strength.
fn sampled_warps(
    plan: &RtwPlan,
    base: &ShadowTransform,
    input: &FitInput<'_>,
    samples: &[EyeSample],
    warps: &mut WarpMaps,
) -> Result<(), FitError> {
    let n = plan.importance_side;
    let accumulate = |from: &[EyeSample], map: &mut ImportanceMap| -> Result<(), FitError> {
        map.accumulate_backward(base, from, None, &plan.importance)?;
        Ok(())
    };
    let light = match *input.light {
        Light::Directional { direction } => LightDirection::Directional(direction),
        Light::Spot { position, .. } => LightDirection::Position(position),
        Light::Point { .. } => {
            let mut importance = ImportanceMap::new(n, n)?;
            accumulate(samples, &mut importance)?;
            warps.build(&importance, &plan.warp)?;
            return Ok(());
        }
    };
    let (lit, unlit): (Vec<EyeSample>, Vec<EyeSample>) =
        samples.iter().partition(|s| is_front_lit(s, light));
    let split = LitSplit {
        lit: &lit,
        unlit: &unlit,
    };
    build_measured_by(n, split, accumulate, &plan.warp, warps, |warps| {
        let mapping = RtwShadow { base: *base, warps };
        warped_error(&mapping, &lit, input.camera, light)
    })
}

/// The eye samples `light` reaches from the side the eye sees: normal (facing the
/// eye, as a G-buffer's) with `n . l` at least `shadowmap_frustum::FRONT_LIT_MIN_COS`
/// (`l` toward the light: against a directional light's travel, toward a spot's
/// position), or unknown (zero). The others are dark whatever the map holds (the
/// quality measure leaves them out too), and a surface turned away from the light
/// close to the eye would otherwise claim the densest rows and columns of the warp
/// (twice the uniform fit's error in a room seen along the light).
pub(crate) fn front_lit(samples: &[EyeSample], light: LightDirection) -> Vec<EyeSample> {
    samples
        .iter()
        .filter(|s| is_front_lit(s, light))
        .copied()
        .collect()
}

/// Whether [`front_lit`] keeps `sample`.
pub(crate) fn is_front_lit(sample: &EyeSample, light: LightDirection) -> bool {
    sample.normal.try_normalize().is_none_or(|n| {
        n.as_dvec3().dot(light.toward(sample.position.as_dvec3())) >= FRONT_LIT_MIN_COS
    })
}

fn fit_dpsm(options: &DpsmOptions, light: &Light) -> Result<ParaboloidMap, FitError> {
    let Light::Point { position, range } = *light else {
        return Err(FitError::Paraboloid(ParaboloidError::UnsupportedLight));
    };
    Ok(ParaboloidMap::dual(
        position,
        options.axis,
        options.near,
        range,
        &options.map,
    )?)
}

/// Min/max view depth of eye samples (IPSM's truncated frustum, the cascades' split
/// range), `None` without samples or when they span no depth.
#[must_use]
pub fn depth_bounds_of(camera: &Camera, samples: &[EyeSample]) -> Option<DepthBounds> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rtw_keeps_only_the_samples_the_light_reaches() {
        let sample = |normal: Vec3| EyeSample {
            position: Vec3::ZERO,
            normal,
            eye_distance: 1.0,
        };
        let down = Vec3::new(0.0, -1.0, 0.0);
        let samples = [
            sample(Vec3::Y),                   // lit head-on
            sample(Vec3::new(1.0, 0.1, 0.0)),  // lit at about 6 degrees
            sample(Vec3::new(1.0, 0.01, 0.0)), // within 3 degrees of edge-on
            sample(Vec3::NEG_Y),               // turned away
            sample(Vec3::ZERO),                // unknown: kept
        ];
        let kept = front_lit(&samples, LightDirection::Directional(down));
        assert_eq!(kept, vec![samples[0], samples[1], samples[4]]);
        // A light above at a position: the same samples, seen from it.
        let above = LightDirection::Position(Vec3::new(0.0, 5.0, 0.0));
        assert_eq!(front_lit(&samples, above), kept);
        // A light at a sample's own position lights nothing with a known normal.
        let at = LightDirection::Position(Vec3::ZERO);
        assert_eq!(front_lit(&samples, at), vec![samples[4]]);
    }
}
