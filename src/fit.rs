//! [`fit`]: one entry point for every technique, the same inputs for all.

use alloc::vec::Vec;
use core::fmt;

use glam::{DVec3, Vec3};
use shadowmap_frustum::math::{floor, sqrt};
use shadowmap_frustum::{
    Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, CascadeState, DepthBounds,
    FrustumError, Light, MAX_CASCADES, SceneBounds, ShadowMapping, ShadowTransform, SplitScheme,
    TechniqueSelector, ValidCamera, fit_spot,
};
use shadowmap_paraboloid::{CubeMap, IpsmOptions, IpsmPlan, ParaboloidError, ParaboloidMap, Side};
use shadowmap_rtw::{BasePoint, EyeSample, ImportanceMap, OracleAxis, RtwError, WarpMaps};
use shadowmap_warp::{
    LispsmOptions, WarpError, lispsm, tsm, uniform_focused, warped_cascades, xpsm,
};

use crate::shadow::{Fitted, Shadow};
use crate::technique::{CascadePlan, DpsmOptions, RtwPlan, Technique};

/// What a technique may look at in one frame: the same for every technique.
///
/// Required: camera, light, scene bounds, texel budget. Optional, read only by the
/// techniques that need them (see the crate docs' table):
/// [`eye_samples`](Self::eye_samples) (RTW and the RTW oracle, required there),
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
    fit_stateful(technique, input, selector, &mut CascadeState::new())
}

/// What a renderer keeps from one frame to the next for one light and view:
/// `auto`'s choice and the stable cascades' held sizes and count. Start with
/// `FitState::default()` and pass the same value to [`fit_with_state`] every frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FitState {
    /// `auto`'s current choice, kept with hysteresis.
    pub selector: TechniqueSelector,
    /// The stable cascades' sizes (and the cascaded techniques' count), kept with
    /// hysteresis.
    pub cascades: CascadeState,
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
    fit_stateful(technique, input, &mut state.selector, &mut state.cascades)
}

/// [`fit_with_state`] with its two parts of the state apart.
pub(crate) fn fit_stateful(
    technique: &Technique,
    input: &FitInput<'_>,
    selector: &mut TechniqueSelector,
    cascades: &mut CascadeState,
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
        return crate::auto::fit_auto(plan, input, selector, cascades);
    }
    let (fitted, layers) = fit_one(technique, input, cascades)?;
    Ok(Shadow {
        requested: *technique,
        technique: *technique,
        fitted,
        layers,
        layer_side: input.layer_side(layers),
    })
}

/// The result and layer count of every technique but `auto`.
fn fit_one(
    technique: &Technique,
    input: &FitInput<'_>,
    state: &mut CascadeState,
) -> Result<(Fitted, u32), FitError> {
    let (camera, scene) = (input.camera, &input.scene);
    let direction = match *input.light {
        Light::Directional { direction } => direction,
        _ => Vec3::ZERO,
    };
    Ok(match technique {
        Technique::UniformFocused(o) => (
            Fitted::Uniform(uniform_focused(camera, direction, scene, o)?),
            1,
        ),
        Technique::Lispsm(o) => (Fitted::Lispsm(lispsm(camera, direction, scene, o)?), 1),
        Technique::Xpsm(o) => (Fitted::Xpsm(xpsm(camera, direction, scene, o)?), 1),
        Technique::Tsm(o) => (Fitted::Tsm(tsm(camera, direction, scene, o)?), 1),
        Technique::StableCascades(plan) | Technique::TightCascades(plan) => {
            let stable = matches!(technique, Technique::StableCascades(_));
            fit_cascades(plan, stable, direction, input, state)?
        }
        Technique::WarpedCascades { plan, lispsm } => {
            fit_warped(plan, lispsm, direction, input, state)?
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
        Technique::Dpsm(o) => (Fitted::Dpsm(fit_dpsm(o, input.light)?), 2),
        Technique::Ipsm(o) => {
            let plan = IpsmPlan::new(input.light, camera, input.depth_bounds, o)?;
            let layers = plan.map.layers();
            (Fitted::Ipsm(plan), layers)
        }
        Technique::CubeMaps(o) => {
            let cube = CubeMap::fit(input.light, camera, input.depth_bounds, scene, o)?;
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
            let fitted = fit_point_rtw(ipsm, rtw, input)?;
            let layers = fitted.layer_count();
            (fitted, layers)
        }
    })
}

fn fit_cascades(
    plan: &CascadePlan,
    stable: bool,
    direction: Vec3,
    input: &FitInput<'_>,
    state: &mut CascadeState,
) -> Result<(Fitted, u32), FitError> {
    let splits = cascade_splits(plan, input, state)?;
    let layers = u32::try_from(splits.count()).unwrap_or(u32::MAX);
    let fit = CascadeOptions::default()
        .with_resolution(input.layer_side(layers))
        .with_reversed_z(plan.reversed_z)
        .with_scene(Some(input.scene))
        .with_fit(if stable {
            CascadeFit::Stable
        } else {
            CascadeFit::Tight
        });
    let camera = ValidCamera::new(input.camera)?;
    let set = CascadeSet::fit_with_state(&camera, direction, &splits, &fit, state)?;
    Ok((Fitted::Cascades(set), layers))
}

fn fit_warped(
    plan: &CascadePlan,
    options: &LispsmOptions,
    direction: Vec3,
    input: &FitInput<'_>,
    state: &mut CascadeState,
) -> Result<(Fitted, u32), FitError> {
    // The same split rule as the unwarped cascades: count and range from the depth
    // bounds, so no cascade is spent on empty depth.
    let splits = cascade_splits(plan, input, state)?;
    let count = splits.count();
    let etas = [options.eta; MAX_CASCADES];
    let cascades = warped_cascades(
        input.camera,
        direction,
        &input.scene,
        &splits,
        etas.get(..count).unwrap_or(&[]),
        options,
    )?;
    let fitted = Fitted::WarpedCascades {
        cascades,
        eye: input.camera.eye(),
        forward: input.camera.forward(),
    };
    Ok((fitted, u32::try_from(count).unwrap_or(u32::MAX)))
}

/// A count kept from the previous frame stays while its score is within this factor
/// of the best count's (see [`cascade_splits`]).
const COUNT_KEEP_RATIO: f64 = 1.1;

/// Splits of the cascaded techniques: practical splits of the depth bounds (the
/// camera's range without them), so no cascade covers empty depth.
///
/// The count is the one whose coarsest cascade is finest where it matters: the
/// perspective aliasing of a cascade is largest at its near end, where a texel of
/// world size `t` covers the most pixels, in proportion to `t / z_near`. For each
/// count `k` up to `plan.max_cascades` (only those whose map side is a power of two
/// when there are any: the stable fit's whole-texel motion is exact in `f32` only
/// there), the slices are fitted tight to slice ∩ receivers on `side(k)` texels and
/// scored by the largest `t / z_near` over the cascades that meet the receivers; the
/// lowest score wins. Where the receivers bound the view (a room), the far slices'
/// footprints stop growing with depth and fewer, larger maps win; over open ground
/// the footprint grows with depth and more cascades win (Zhang et al.'s reasoning
/// for parallel splits). The count of the previous frame (held in `state`) is kept
/// while its score is within [`COUNT_KEEP_RATIO`] of the best, so a view near the
/// boundary between two counts does not re-size every map from one frame to the
/// next.
fn cascade_splits(
    plan: &CascadePlan,
    input: &FitInput<'_>,
    state: &mut CascadeState,
) -> Result<CascadeSplits, FitError> {
    let camera = input.camera;
    let (near, far) = match input.depth_bounds {
        Some(bounds) => bounds.clamped_to(camera)?,
        None => camera.depth_range()?,
    };
    let max = plan.max_cascades.clamp(1, MAX_CASCADES);
    let side = |k: usize| input.layer_side(u32::try_from(k).unwrap_or(u32::MAX));
    let any_power = (1..=max).any(|k| side(k).is_power_of_two());
    let allowed = |k: usize| (1..=max).contains(&k) && (!any_power || side(k).is_power_of_two());
    let scheme = SplitScheme::Practical {
        lambda: plan.split_lambda,
    };
    let splits_of = |k: usize| -> Result<CascadeSplits, FitError> {
        Ok(CascadeSplits::new(&scheme, k, near, far)?.with_overlap(plan.overlap)?)
    };
    let valid = ValidCamera::new(camera)?;
    let direction = match *input.light {
        Light::Directional { direction } => direction,
        _ => Vec3::ZERO,
    };
    let mut scores = [f64::INFINITY; MAX_CASCADES + 1];
    for (k, score) in scores.iter_mut().enumerate() {
        if allowed(k) {
            let splits = splits_of(k)?;
            *score = coarseness(&valid, direction, &splits, side(k), &input.scene);
        }
    }
    let best = (1..=max)
        .filter(|k| allowed(*k))
        .min_by(|a, b| scores[*a].total_cmp(&scores[*b]).then(b.cmp(a)))
        .unwrap_or(1);
    let kept = state.count();
    let keep = allowed(kept) && scores[kept] <= scores[best] * COUNT_KEEP_RATIO;
    let count = if keep { kept } else { best };
    state.set_count(count);
    splits_of(count)
}

/// The score of a split in [`cascade_splits`]: the largest texel size over near
/// depth, `t / z_near`, of its cascades fitted tight to slice ∩ receivers on
/// `side`-texel maps, over the cascades that meet the receivers (infinite when the
/// fit fails or none does).
fn coarseness(
    camera: &ValidCamera,
    direction: Vec3,
    splits: &CascadeSplits,
    side: u32,
    scene: &SceneBounds,
) -> f64 {
    let options = CascadeOptions::default()
        .with_resolution(side)
        .with_fit(CascadeFit::Tight)
        .with_scene(Some(*scene));
    let Ok(set) = CascadeSet::fit_valid(camera, direction, splits, &options) else {
        return f64::INFINITY;
    };
    set.cascades
        .iter()
        .filter(|c| !c.receivers_missed)
        .map(|c| f64::from(c.texel_world_size) / f64::from(c.view_depth.0))
        .filter(|s| s.is_finite())
        .max_by(f64::total_cmp)
        .unwrap_or(f64::INFINITY)
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
    let camera = input.camera;
    let n = plan.importance_side;
    let mut map = ImportanceMap::new(n, n)?;
    let mut warps = WarpMaps::new(n, n)?;
    if oracle {
        let pixels_per_radian = input
            .pixels_per_radian
            .ok_or_else(|| missing("pixels_per_radian"))?;
        // The oracle of a separable warp: each axis gets the density that axis needs
        // (an isotropic requirement would spend texels on the axis that does not need
        // them). Perspective-only (zero normal): true-normal requirements of surfaces
        // seen edge-on are unbounded and, once normalized, starve the rest of the map.
        let mut map_v = ImportanceMap::new(n, n)?;
        let flat: Vec<EyeSample> = samples
            .iter()
            .map(|s| EyeSample {
                normal: Vec3::ZERO,
                ..*s
            })
            .collect();
        for (axis, m) in [(OracleAxis::U, &mut map), (OracleAxis::V, &mut map_v)] {
            m.accumulate_oracle_axis(axis, &base, camera, pixels_per_radian, &flat)?;
        }
        warps.build_separable(&map, &map_v, &plan.warp)?;
    } else {
        map.accumulate_backward(&base, samples, None, &plan.importance)?;
        warps.build(&map, &plan.warp)?;
    }
    Ok(Fitted::Rtw { base, warps })
}

/// RTW over the IPSM paraboloid: per side, importance from the eye samples that side
/// stores, in its `uv`, scaled by the paraboloid's footprint there (world extent of a
/// unit of `uv` across the ray: `distance / sqrt(uv² per steradian)`), then that
/// side's tables.
fn fit_point_rtw(
    ipsm: &IpsmOptions,
    plan: &RtwPlan,
    input: &FitInput<'_>,
) -> Result<Fitted, FitError> {
    let samples = input.eye_samples.ok_or(FitError::MissingInput {
        technique: "point_rtw",
        input: "eye_samples",
    })?;
    let ipsm = IpsmPlan::new(input.light, input.camera, input.depth_bounds, ipsm)?;
    let map = ipsm.map;
    let n = plan.importance_side;
    let side_warps = |side: Side| -> Result<WarpMaps, FitError> {
        let project = |p: DVec3| {
            let s = map.map_point(p).filter(|s| s.layer == side.layer())?;
            let world = p.as_vec3();
            let per_sr = f64::from(map.texels_per_steradian(world, 1)?);
            let toward_light = map.position.as_dvec3() - p;
            Some(BasePoint {
                uv: s.uv,
                footprint: toward_light.length() / sqrt(per_sr),
                toward_light,
            })
        };
        let mut importance = ImportanceMap::new(n, n)?;
        importance.accumulate_backward_with(project, samples, None, &plan.importance)?;
        let mut warps = WarpMaps::new(n, n)?;
        warps.build(&importance, &plan.warp)?;
        Ok(warps)
    };
    let front = side_warps(Side::Front)?;
    let back = if map.layers() == 2 {
        Some(side_warps(Side::Back)?)
    } else {
        None
    };
    Ok(Fitted::PointRtw {
        plan: ipsm,
        front,
        back,
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
    use crate::Fitted;
    use proptest::prelude::*;
    use shadowmap_testgen::point_rtw::{PointRtwCase, check_point_rtw, point_rtw_case};
    use shadowmap_testgen::strategy;

    /// Fits RTW over the paraboloid to a case and checks its coverage; the number of
    /// samples checked (0 when the fit refuses the case, e.g. a spot light).
    fn fit_and_check(case: &PointRtwCase) -> usize {
        let input = FitInput::new(
            &case.plan.camera,
            &case.plan.light,
            // IPSM reads the camera and depth bounds, not the scene.
            SceneBounds::whole(shadowmap_frustum::Aabb::new(Vec3::splat(-1.0), Vec3::ONE)),
            1 << 16,
        )
        .with_eye_samples(&case.samples)
        .with_depth_bounds(case.plan.bounds);
        let technique = Technique::PointRtw {
            ipsm: case.plan.options,
            rtw: RtwPlan::default().with_importance_side(32),
        };
        let Ok(shadow) = fit(&technique, &input) else {
            return 0;
        };
        let Fitted::PointRtw { plan, .. } = shadow.fitted() else {
            panic!("point_rtw fitted something else");
        };
        assert_eq!(shadow.layers(), plan.map.layers());
        check_point_rtw(case, &plan.map, &shadow)
    }

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// Every sample the IPSM paraboloid stores is stored by RTW over it, in the
        /// same layer, with the same depth, inside the map.
        #[test]
        fn point_rtw_covers_what_the_paraboloid_covers(case in strategy(point_rtw_case)) {
            fit_and_check(&case);
        }
    }
}
