//! Perspective warps of a spot light's shadow map, in the light's own post-projective
//! space: LiSPSM (Wimmer, Scherzer and Purgathofer) and TSM (Martin and Tan) for a
//! perspective light.
//!
//! After the spot's projection (the spot fit, [`fit_spot`]) every light ray is a line
//! of constant `(x, y)` in its normalized device coordinates: the light has become a
//! directional one along `z`, the case the directional warps are built for (as the
//! XPSM paper puts it, any light reduces to a light along `z` in light space). A
//! warp of the `(x, y)` plane by a homography keeps every ray on one texel and every
//! straight edge straight, so the warped map is still one matrix: the spot fit's
//! followed by
//!
//! ```text
//! t = d . (x, y),  s = d⊥ . (x, y)      d: the view's centre line, projected
//! q = 1 + sigma (t - t0)                 t0, L: the window's extent along d
//! a = s / q,  b = (t - t0) (1 + sigma L) / (L q)      then a, b fitted to [-1, 1]
//! depth' = far + (depth - far) / q       (far: 1, or 0 with reversed-Z; linear
//!                                         along every ray, in [0, 1])
//! ```
//!
//! `sigma = 1 / n` is the warp's strength (`n` the distance of its projection centre
//! before the window's near edge, in device units); 0 is the spot fit turned to `d`.
//! LiSPSM takes `n` from its optimum `n_opt = z_n + sqrt(z_n z_f)` (view depths of the
//! near and far ends of the centre line, scaled to device units by the centre line's
//! projected length over its depth range); TSM places the focus point (the
//! [`SpotWarpOptions::focus`] fraction of the view depth range along the centre
//! line) on the trapezoid's 80% line: `n = L δ' (1 + ξ) / (L (1 - ξ) - 2 δ')`,
//! `ξ = -0.6`, `δ'` the focus point's distance from the near edge.
//!
//! Both formulas assume the view depth orders the receivers along the centre line.
//! As the directional warps do, the fit keeps the formula's warp where the error
//! predicted from the camera and the receivers' box, over the faces the spot lights
//! from the front ([`predict_errors`](shadowmap_frustum::predict_errors) with the
//! light's position: faces it does not light from the front are dark whatever the
//! map holds, and counting them made a warp measured 1.23x worse than the spot fit in
//! a room predict 1.5x better), is within 10% of the best of a few weaker warps, and
//! takes that best otherwise; and it keeps the spot fit unless the warp is predicted
//! at least 10% better than it;
//! so the warp fades to the spot fit where it does not pay (the view along the
//! light's rays, a room seen from inside).
//!
//! A warp magnifies the map near its projection centre, and with it the rounding of
//! its `f32` matrices, which a point near the light divides by its small `w`, and
//! compresses depth toward the far value, where `z` and `w` nearly cancel: the
//! strength is limited to what keeps that rounding under a tenth of a texel of a
//! `1024²` map at the visible receivers, in texture coordinates, between the two
//! ends of a light ray and in depth (a light far from the origin, receivers a hair
//! from it, a warp along a window's narrow side).

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec4, Mat4, Vec2};
use shadowmap_frustum::{
    Camera, DepthBounds, Light, LightDirection, PredictOptions, SPOT_ROUNDING_BUDGET, SceneBounds,
    ShadowMapping, ShadowTransform, SpotRounding, SpotShadow, fit_spot, math, predict_errors,
};

use crate::{MAX_WARP_RATIO, WarpError};

/// Which warp [`spot_warp`] fits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SpotWarpKind {
    /// LiSPSM's perspective warp with its optimal projection distance.
    Lispsm,
    /// TSM's trapezoid with the 80% rule.
    Tsm,
}

/// Options of [`spot_warp`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct SpotWarpOptions {
    /// LiSPSM or TSM. Default LiSPSM.
    pub kind: SpotWarpKind,
    /// TSM's focus point, a fraction in `(0, 1)` of the view depth range along the
    /// centre line. Default 0.1 (as [`TsmOptions`](crate::TsmOptions)).
    pub focus: f32,
    /// Depth 1 at the light's near plane and 0 at its far plane. Default `false`.
    pub reversed_z: bool,
}

impl Default for SpotWarpOptions {
    fn default() -> Self {
        Self {
            kind: SpotWarpKind::Lispsm,
            focus: 0.1,
            reversed_z: false,
        }
    }
}

impl SpotWarpOptions {
    /// With this warp.
    #[must_use]
    pub const fn with_kind(mut self, kind: SpotWarpKind) -> Self {
        self.kind = kind;
        self
    }
    /// With this TSM focus fraction.
    #[must_use]
    pub const fn with_focus(mut self, focus: f32) -> Self {
        self.focus = focus;
        self
    }
    /// With reversed-Z depth.
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }

    pub(crate) fn check(&self) -> Result<(), WarpError> {
        if self.focus > 0.0 && self.focus < 1.0 {
            Ok(())
        } else {
            Err(WarpError::InvalidOption)
        }
    }
}

/// A warped spot shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SpotWarpShadow {
    /// The matrices (depth pass and lookup): the spot fit's, then the warp.
    pub transform: ShadowTransform,
    /// The spot fit the warp works in.
    pub base: SpotShadow,
    /// The warp's strength `sigma` (per device unit); 0 with [`direction`](Self::direction)
    /// zero: the spot fit itself.
    pub strength: f32,
    /// The view's centre line in the spot fit's device coordinates (unit; zero when
    /// the spot fit is kept as it is).
    pub direction: Vec2,
}

/// The warp of a spot light's shadow map in its post-projective space (see the
/// module docs). `bounds` are the visible surfaces' view depths (the camera's range
/// without them; clamped as [`DepthBounds::clamped_to`]).
///
/// # Errors
/// The spot fit's errors ([`fit_spot`], e.g. a light that is not a spot, nothing
/// visible in its cone), the camera's, [`WarpError::InvalidOption`] for a focus
/// outside `(0, 1)`, [`WarpError::Degenerate`] for a matrix that is not finite.
pub fn spot_warp(
    light: &Light,
    camera: &Camera,
    bounds: Option<DepthBounds>,
    scene: &SceneBounds,
    options: &SpotWarpOptions,
) -> Result<SpotWarpShadow, WarpError> {
    options.check()?;
    let base = fit_spot(light, &camera.frustum()?, Some(scene), options.reversed_z)?;
    let (near, far) = match bounds {
        Some(b) => b.clamped_to(camera)?,
        None => camera.depth_range()?,
    };
    let keep = SpotWarpShadow {
        transform: base.transform,
        base,
        strength: 0.0,
        direction: Vec2::ZERO,
    };
    let clip = base.transform.clip_from_world.as_dmat4();
    let Some(line) = CentreLine::new(&clip, camera, f64::from(near), f64::from(far)) else {
        return Ok(keep);
    };
    let window = Window::new(line.direction);
    let formula = match options.kind {
        SpotWarpKind::Lispsm => window.lispsm_strength(&line),
        SpotWarpKind::Tsm => window.tsm_strength(&line, f64::from(options.focus)),
    };
    let LightDirection::Position(position) = base.transform.light else {
        return Ok(keep);
    };
    let rounding = SpotRounding::new(
        position,
        base.tangents.map(f64::from),
        f64::from(base.receiver_depth.0),
    );
    let (formula, formula_map) = window.resolved(formula, &base, &rounding);
    // The formula's warp, weaker ones, the spot fit turned to the centre line, each
    // where f32 resolves it (the formula's by `resolved`, which made its map; the
    // others may round differently), then the spot fit itself.
    let mut strengths: ArrayVec<f64, 5> = ArrayVec::new();
    let mut candidates: ArrayVec<ShadowTransform, 6> = ArrayVec::new();
    for (k, sigma) in [1.0, 0.5, 0.25, 0.125, 0.0].map(|k| (k, k * formula)) {
        let map = match formula_map {
            Some(map) if k == 1.0 => Some(map),
            _ => window.candidate(sigma, &base, &rounding)?,
        };
        if let Some(map) = map {
            strengths.push(sigma);
            candidates.push(map);
        }
    }
    candidates.push(base.transform);
    let chosen = choose(camera, scene, light, &candidates);
    let (transform, strength, direction) = match strengths.get(chosen) {
        Some(sigma) => (candidates[chosen], *sigma, line.direction.as_vec2()),
        None => (base.transform, 0.0, Vec2::ZERO),
    };
    Ok(SpotWarpShadow {
        transform,
        base,
        strength: strength as f32,
        direction,
    })
}

/// A weaker warp replaces the formula's where the formula is predicted more than
/// this times its error.
const KEEP_FORMULA: f64 = 1.1;

/// A warp replaces the spot fit only where predicted at most this times its error:
/// where the two are close the prediction cannot tell them apart (in a room, a warp
/// predicted 4% better than the spot fit measured 1.18x worse), and the spot fit is
/// the safe side, as one cascade is for the cascades' count.
const WARP_GAIN: f64 = 0.9;

/// The index of the candidate to keep (`candidates` are the warps, strongest
/// first, then the spot fit): the formula's warp while its predicted error is within
/// [`KEEP_FORMULA`] of the best warp's, else that best; and the spot fit instead
/// where that warp is not predicted at most [`WARP_GAIN`] times its error. The
/// formula's warp when nothing can be predicted.
fn choose(
    camera: &Camera,
    scene: &SceneBounds,
    light: &Light,
    candidates: &[ShadowTransform],
) -> usize {
    let list: ArrayVec<(&dyn ShadowMapping, u32), 6> = candidates
        .iter()
        .map(|c| (c as &dyn ShadowMapping, 1024))
        .collect();
    let mut out = [None; 6];
    let n = list.len();
    let mut options = PredictOptions::new();
    if let Light::Spot { position, .. } | Light::Point { position, .. } = *light {
        // Rank on the faces the spot lights from the front, as a directional
        // light's prediction does.
        options = options.with_light_position(position);
    }
    if n < 2 || predict_errors(camera, &scene.receivers, &list, &options, &mut out[..n]).is_err() {
        return 0;
    }
    let error = |i: usize| out[i].map_or(f64::INFINITY, |p| p.percentile);
    let spot = n - 1;
    let best_warp = (0..spot)
        .min_by(|a, b| error(*a).total_cmp(&error(*b)))
        .unwrap_or(0);
    let warp = if error(0) <= KEEP_FORMULA * error(best_warp) {
        0
    } else {
        best_warp
    };
    if error(spot).is_finite() && !(error(warp) <= WARP_GAIN * error(spot)) {
        spot
    } else {
        warp
    }
}

/// The view's centre line in the spot fit's device coordinates.
struct CentreLine {
    /// Unit direction from the near end to the far end, in `(x, y)`.
    direction: DVec2,
    /// Device position of the near end.
    start: DVec2,
    /// Device units along `direction` per unit of view depth.
    scale: f64,
    /// View depths of the near and far ends.
    depths: (f64, f64),
}

impl CentreLine {
    /// The part of the camera's axis between view depths `near` and `far` that the
    /// spot fit's window shows (in front of the light, inside `[-1, 1]²`); `None`
    /// when none of it does or its image is (nearly) a point (the view along the
    /// light's rays).
    fn new(clip: &DMat4, camera: &Camera, near: f64, far: f64) -> Option<Self> {
        let eye = camera.eye().as_dvec3();
        let forward = camera.forward().as_dvec3();
        let depth = |k: f64| near + (far - near) * k;
        let ndc = |k: f64| {
            let h = *clip * (eye + forward * depth(k)).extend(1.0);
            (h.w > 0.0).then(|| DVec2::new(h.x, h.y) / h.w)
        };
        let inside = |k: f64| ndc(k).is_some_and(|p| p.abs().max_element() <= 1.0);
        // The image of the axis is one segment, the part in the window one interval:
        // find a point of it, then its ends by bisection.
        const STEPS: u32 = 64;
        let hit = (0..=STEPS)
            .map(|i| f64::from(i) / f64::from(STEPS))
            .find(|k| inside(*k))?;
        let end = |toward: f64| {
            let (mut a, mut b) = (hit, toward);
            if inside(b) {
                return b;
            }
            for _ in 0..40 {
                let m = 0.5 * (a + b);
                if inside(m) {
                    a = m;
                } else {
                    b = m;
                }
            }
            a
        };
        let (lo, hi) = (end(0.0), end(1.0));
        let (a, b) = (ndc(lo)?, ndc(hi)?);
        let span = b - a;
        let length = span.length();
        let (z_n, z_f) = (depth(lo), depth(hi));
        (length > 1e-6 && length.is_finite() && z_f > z_n).then(|| Self {
            direction: span / length,
            start: a,
            scale: length / (z_f - z_n),
            depths: (z_n, z_f),
        })
    }
}

/// The spot fit's window `[-1, 1]²` seen along a direction.
struct Window {
    along: DVec2,
    across: DVec2,
    /// Smallest `t` over the window's corners.
    t0: f64,
    /// Extent of the window along `t`.
    length: f64,
}

const CORNERS: [DVec2; 4] = [
    DVec2::new(-1.0, -1.0),
    DVec2::new(1.0, -1.0),
    DVec2::new(1.0, 1.0),
    DVec2::new(-1.0, 1.0),
];

impl Window {
    fn new(direction: DVec2) -> Self {
        let across = direction.perp();
        let ts = CORNERS.map(|c| c.dot(direction));
        let t0 = ts.iter().copied().fold(f64::INFINITY, f64::min);
        let t1 = ts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Self {
            along: direction,
            across,
            t0,
            length: t1 - t0,
        }
    }

    /// Largest strength that keeps `q` within [`MAX_WARP_RATIO`] over the window.
    fn clamp(&self, sigma: f64) -> f64 {
        if sigma.is_finite() && sigma > 0.0 {
            sigma.min((MAX_WARP_RATIO - 1.0) / self.length)
        } else {
            0.0
        }
    }

    /// LiSPSM: `n = z_n + sqrt(z_n z_f)` in view depth, to device units.
    fn lispsm_strength(&self, line: &CentreLine) -> f64 {
        let (z_n, z_f) = line.depths;
        let n = line.scale * (z_n + math::sqrt(z_n * z_f));
        self.clamp(1.0 / n)
    }

    /// TSM: the focus point on the 80% line.
    fn tsm_strength(&self, line: &CentreLine, focus: f64) -> f64 {
        let (z_n, z_f) = line.depths;
        let focus_t =
            (line.start + line.direction * (line.scale * focus * (z_f - z_n))).dot(self.along);
        let lambda = self.length;
        let delta = (focus_t - self.t0).clamp(0.0, lambda);
        const XI: f64 = -0.6;
        let denom = lambda * (1.0 - XI) - 2.0 * delta;
        if denom > 0.0 && delta > 0.0 {
            self.clamp(denom / (lambda * delta * (1.0 + XI)))
        } else {
            0.0
        }
    }

    /// The strongest strength up to `sigma` whose warped map `f32` resolves at the
    /// receivers ([`Window::candidate`]), found by bisection on its logarithm (to a
    /// millionth of it), with its map; 0 when even a millionth of `sigma` does not
    /// resolve, and `sigma` itself, unchecked, where it is not positive (both
    /// without a map).
    fn resolved(
        &self,
        sigma: f64,
        base: &SpotShadow,
        rounding: &SpotRounding,
    ) -> (f64, Option<ShadowTransform>) {
        let resolves = |sigma: f64| self.candidate(sigma, base, rounding).ok().flatten();
        if !(sigma > 0.0) {
            return (sigma, None);
        }
        if let Some(map) = resolves(sigma) {
            return (sigma, Some(map));
        }
        // A warp 1e-6 times as strong is the spot fit turned, to rounding.
        let (mut weak, mut strong) = (
            math::ln(sigma) - 6.0 * core::f64::consts::LN_10,
            math::ln(sigma),
        );
        let Some(mut kept) = resolves(math::exp(weak)) else {
            return (0.0, None);
        };
        for _ in 0..24 {
            let middle = 0.5 * (weak + strong);
            match resolves(math::exp(middle)) {
                Some(map) => {
                    weak = middle;
                    kept = map;
                }
                None => strong = middle,
            }
        }
        (math::exp(weak), Some(kept))
    }

    /// The map of the warp of strength `sigma`, stored in `f32`, where `f32`
    /// resolves it at the receivers (`rounding`'s bound within
    /// [`SPOT_ROUNDING_BUDGET`]); `None` where it does not.
    ///
    /// # Errors
    /// [`WarpError::Degenerate`] where the warp or its stored matrix is.
    fn candidate(
        &self,
        sigma: f64,
        base: &SpotShadow,
        rounding: &SpotRounding,
    ) -> Result<Option<ShadowTransform>, WarpError> {
        let clip = self.clip(base, sigma)?;
        let map = stored(base, &clip)?;
        Ok((rounding.bound(&clip, &map) <= SPOT_ROUNDING_BUDGET).then_some(map))
    }

    /// The clip matrix of the warp of strength `sigma` after the spot fit (see the
    /// module docs), exact, before its rounding to `f32` ([`stored`]).
    fn clip(&self, base: &SpotShadow, sigma: f64) -> Result<DMat4, WarpError> {
        let warp = self.warp(sigma, base.transform.reversed_z)?;
        Ok(warp * base.transform.clip_from_world.as_dmat4())
    }

    /// The warp of strength `sigma`, from the spot fit's clip coordinates to the
    /// warped map's (see the module docs).
    fn warp(&self, sigma: f64, reversed_z: bool) -> Result<DMat4, WarpError> {
        let (d, e, t0, l) = (self.along, self.across, self.t0, self.length);
        let q = |c: DVec2| 1.0 + sigma * (c.dot(d) - t0);
        let a = CORNERS.map(|c| c.dot(e) / q(c));
        let a_min = a.iter().copied().fold(f64::INFINITY, f64::min);
        let a_max = a.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let da = a_max - a_min;
        if !(da > 0.0 && l > 0.0) {
            return Err(WarpError::Degenerate);
        }
        // Rows acting on the spot's clip coordinates (x, y, z, w).
        let r_w = DVec4::new(sigma * d.x, sigma * d.y, 0.0, 1.0 - sigma * t0);
        let r_s = DVec4::new(e.x, e.y, 0.0, 0.0);
        let r_t = DVec4::new(d.x, d.y, 0.0, -t0) * ((1.0 + sigma * l) / l);
        let x = r_s * (2.0 / da) - r_w * (2.0 * a_min / da + 1.0);
        let y = r_t * 2.0 - r_w;
        // Depth measured from the far value (1, 0 with reversed-Z), divided by `q`:
        // `depth' = far + (depth - far) / q`. Perspective depth crowds toward the far
        // value, so the `1 / q` across the map barely tilts it (a depth `depth / q`
        // would slope by `1 / q`'s gradient and take the slope-scaled bias with it).
        let z = if reversed_z {
            DVec4::new(0.0, 0.0, 1.0, 0.0)
        } else {
            r_w + DVec4::new(0.0, 0.0, 1.0, -1.0)
        };
        Ok(DMat4::from_cols(x, y, z, r_w).transpose())
    }
}

/// The map that stores the clip matrix `clip` in `f32`, after the spot fit `base`.
///
/// # Errors
/// [`WarpError::Degenerate`] where the rounded matrix is not finite or singular.
fn stored(base: &SpotShadow, clip: &DMat4) -> Result<ShadowTransform, WarpError> {
    let clip_from_world: Mat4 = clip.as_mat4();
    let det = clip_from_world.as_dmat4().determinant();
    if !clip_from_world.is_finite() || !det.is_finite() || det == 0.0 {
        return Err(WarpError::Degenerate);
    }
    Ok(ShadowTransform::new(
        base.transform.light_from_world,
        clip_from_world,
        base.transform.reversed_z,
        base.transform.light,
    ))
}

#[cfg(feature = "serde")]
mod serde_impls {
    use serde::Deserialize;

    use super::{SpotWarpKind, SpotWarpOptions};

    #[derive(Deserialize)]
    #[serde(remote = "SpotWarpOptions", default = "SpotWarpOptions::default")]
    struct SpotWarpOptionsDef {
        kind: SpotWarpKind,
        focus: f32,
        reversed_z: bool,
    }

    shadowmap_frustum::__deserialize_checked!(
        /// Checked as [`spot_warp`](super::spot_warp) checks it.
        SpotWarpOptions,
        SpotWarpOptionsDef,
        |options| options.check()
    );
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};
    use shadowmap_frustum::{Aabb, Projection};

    use super::*;

    fn street() -> (Camera, SceneBounds) {
        let camera = Camera::look_to(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, -0.1, -1.0),
            Vec3::Y,
            Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
        )
        .unwrap();
        let ground = Aabb::new(Vec3::new(-150.0, 0.0, -320.0), Vec3::new(150.0, 1.0, 20.0));
        (camera, SceneBounds::whole(ground))
    }

    /// A spot high above the street, aimed down the road ahead: the view's near
    /// ground needs more texels than the far, and LiSPSM's warp gives it more than
    /// the spot fit does (the centre line's near end is magnified).
    #[test]
    fn a_spot_over_the_street_is_warped_toward_the_viewer() {
        let (camera, scene) = street();
        let light = Light::Spot {
            position: Vec3::new(0.0, 60.0, -20.0),
            direction: Vec3::new(0.0, -1.0, -1.5).normalize(),
            half_angle: 1.2,
            range: 500.0,
        };
        let o = SpotWarpOptions::default();
        let w = spot_warp(&light, &camera, None, &scene, &o).unwrap();
        assert!(w.strength > 0.0, "not warped");
        // Texels per metre at a near and a far ground point, warp over fit.
        let density = |t: &ShadowTransform, z: f64| {
            let a = t.map_point(DVec3::new(0.0, 0.0, z)).unwrap().uv;
            let b = t.map_point(DVec3::new(0.0, 0.0, z - 0.01)).unwrap().uv;
            (a - b).length()
        };
        let gain = |z| density(&w.transform, z) / density(&w.base.transform, z);
        assert!(
            gain(-5.0) > 1.2 * gain(-150.0),
            "{} {}",
            gain(-5.0),
            gain(-150.0)
        );
    }

    /// Looking straight along the spot's axis the centre line is a point: the spot
    /// fit itself; a light that is not a spot and a focus outside (0, 1) are typed
    /// errors.
    #[test]
    fn a_view_along_the_rays_keeps_the_fit_and_bad_input_is_typed() {
        let (camera, scene) = street();
        let behind = Light::Spot {
            position: Vec3::new(0.0, 3.0, 10.0),
            direction: camera.forward(),
            half_angle: 0.8,
            range: 500.0,
        };
        let w = spot_warp(&behind, &camera, None, &scene, &SpotWarpOptions::default()).unwrap();
        assert_eq!((w.strength, w.direction), (0.0, Vec2::ZERO));
        assert_eq!(w.transform, w.base.transform);
        let point = Light::Point {
            position: Vec3::Y,
            range: 10.0,
        };
        assert!(spot_warp(&point, &camera, None, &scene, &SpotWarpOptions::default()).is_err());
        let bad = SpotWarpOptions::default().with_focus(1.0);
        assert_eq!(
            spot_warp(&behind, &camera, None, &scene, &bad),
            Err(WarpError::InvalidOption)
        );
    }
}
