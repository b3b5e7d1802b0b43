//! Light space perspective shadow maps (LiSPSM).

use glam::{DMat4, DVec4, Vec3};
use shadowmap_frustum::{Camera, ShadowTransform, math};

use crate::WarpError;
use crate::focus::{Bounds, Focus, FocusBody, View, finish, ortho_fit, smoothstep, sqrt0};
use crate::predict::Fits;
use crate::{MAX_WARP_RATIO, ParallelFade, SceneBounds};

/// Options of [`lispsm`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct LispsmOptions {
    /// Depth 1 at the light's near plane and 0 at its far plane.
    pub reversed_z: bool,
    /// Warp strength in `[-1, 1]`: `-1` uniform, `0` LiSPSM (`n_opt`), `1` PSM-like
    /// (projection centre at the eye). Default 0.
    pub eta: f32,
    /// View depth below which shadows matter little (Filament's "near hint"): `n_opt`
    /// uses `max(z_near, near_hint)`. Default 0 (none).
    pub near_hint: f32,
    /// View depth beyond which shadows matter little: `n_opt` uses
    /// `min(z_far, far_hint)`. Default infinity (none). Must not be below
    /// [`near_hint`](Self::near_hint) ([`WarpError::InvalidOption`]).
    #[cfg_attr(
        feature = "serde",
        serde(with = "crate::serde_impls::infinite_as_none")
    )]
    pub far_hint: f32,
    /// The parallel-light fade band (default: full strength above 10 degrees,
    /// uniform below 3).
    pub fade: ParallelFade,
    /// The share of the chosen warp to apply, in `[0, 1]`: its warp ratio is raised
    /// to this power (1, the default: the strength the error prediction chose; 0:
    /// the uniform fit with focusing). For a renderer that measures the fit on its
    /// own view samples and backs off where the prediction, made on the receivers'
    /// box, misjudges what the eye sees (`shadowmap::fit` does, given the eye's
    /// samples). At 0 the prediction, most of the fit's time, is skipped.
    pub strength_scale: f32,
}

impl Default for LispsmOptions {
    fn default() -> Self {
        Self::new()
    }
}

impl LispsmOptions {
    /// Defaults: standard depth, `eta = 0`, no hints, fade between 10 and 3 degrees.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            reversed_z: false,
            eta: 0.0,
            near_hint: 0.0,
            far_hint: f32::INFINITY,
            fade: ParallelFade::DEFAULT,
            strength_scale: 1.0,
        }
    }

    /// Sets [`reversed_z`](Self::reversed_z).
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }

    /// Sets [`eta`](Self::eta).
    #[must_use]
    pub const fn with_eta(mut self, eta: f32) -> Self {
        self.eta = eta;
        self
    }

    /// Sets [`near_hint`](Self::near_hint) and [`far_hint`](Self::far_hint).
    #[must_use]
    pub const fn with_hints(mut self, near_hint: f32, far_hint: f32) -> Self {
        self.near_hint = near_hint;
        self.far_hint = far_hint;
        self
    }

    /// Sets the parallel-light fade band, in degrees (`end < start`).
    #[must_use]
    pub const fn with_fade(mut self, start_deg: f32, end_deg: f32) -> Self {
        self.fade = ParallelFade::new(start_deg, end_deg);
        self
    }

    /// Sets [`strength_scale`](Self::strength_scale).
    #[must_use]
    pub const fn with_strength_scale(mut self, strength_scale: f32) -> Self {
        self.strength_scale = strength_scale;
        self
    }

    pub(crate) fn check(&self) -> Result<(), WarpError> {
        let ok = (-1.0..=1.0).contains(&self.eta)
            && (0.0..=1.0).contains(&self.strength_scale)
            && self.near_hint >= 0.0
            && self.near_hint.is_finite()
            && self.far_hint > 0.0
            && self.far_hint >= self.near_hint
            && self.fade.is_valid();
        if ok {
            Ok(())
        } else {
            Err(WarpError::InvalidOption)
        }
    }
}

/// A LiSPSM fit: the matrices and the warp it chose.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LispsmShadow {
    /// The matrices (depth pass and lookup).
    pub transform: ShadowTransform,
    /// Distance `n` from the projection centre to the near face of the body along
    /// the warp axis; infinite when the fit is uniform.
    #[cfg_attr(
        feature = "serde",
        serde(with = "crate::serde_impls::infinite_as_none")
    )]
    pub n: f32,
    /// Parallel-light fade weight in `[0, 1]` (1: full warp, 0: uniform).
    pub fade: f32,
}

/// Light space perspective shadow map (Wimmer, Scherzer and Purgathofer 2004) with the
/// strength parameter of Lloyd et al. (2006).
///
/// The strength is never worse than the uniform fit by prediction: `n_opt` assumes
/// the visible receivers fill the view frustum from the near plane on, so a camera
/// standing in a large scene (whose nearest surfaces are metres away, not at the
/// near plane), looking down, or seeing a wall the light grazes gets a warp that
/// starves what it actually sees (the quality report's random sweep measured up to
/// 11 times the uniform fit's 95th-percentile error). So the fit predicts its own
/// aliasing error over the focus body at a few fractions of the formula's warp
/// ratio, `ln(1 + s d)`, and keeps the formula's strength where it is predicted
/// clearly better than the uniform fit (at most 0.9 times its error); elsewhere it
/// takes the strength of least predicted error, down to the uniform fit. The
/// prediction (points where view rays meet the receivers' box, the
/// perspective-only error of Lloyd et al. where the box gives no surface) and the
/// choice are continuous in the camera and the light, so nothing pops. For
/// `eta > 0` the same choice is made between the uniform fit and the requested
/// strength.
///
/// # Errors
/// As [`uniform_focused`](crate::uniform_focused), and [`WarpError::InvalidOption`] for options out of range.
pub fn lispsm(
    camera: &Camera,
    light_direction: Vec3,
    scene: &SceneBounds,
    options: &LispsmOptions,
) -> Result<LispsmShadow, WarpError> {
    options.check()?;
    FocusBody::fit_from(camera, light_direction, scene, |body| body.lispsm(options))
}

impl FocusBody {
    /// The LiSPSM fit of this body (see [`lispsm`]).
    ///
    /// # Errors
    /// [`WarpError::InvalidOption`]; [`WarpError::Degenerate`].
    pub fn lispsm(&self, options: &LispsmOptions) -> Result<LispsmShadow, WarpError> {
        options.check()?;
        let (s, fade) = warp_strength(&self.focus, options);
        let (transform, s) = fit_chosen(self, s, options.strength_scale, options.reversed_z)?;
        Ok(LispsmShadow {
            transform,
            n: if s > 0.0 {
                (1.0 / s) as f32
            } else {
                f32::INFINITY
            },
            fade: fade as f32,
        })
    }
}

/// The warp strength `s = 1/n` and the fade weight.
fn warp_strength(f: &Focus, o: &LispsmOptions) -> (f64, f64) {
    let fade = o.fade.weight(f.sin_gamma);
    let hints = (f64::from(o.near_hint), f64::from(o.far_hint));
    (strength(f, f64::from(o.eta), hints, fade), fade)
}

/// LiSPSM's warp strength `s = 1/n` for strength parameter `eta`, view-depth hints
/// `(near, far)` and parallel-light fade weight `fade` (0 when the fit is uniform).
///
/// `ln(1 + s d)`, `d` the body's extent along the warp axis, is interpolated in
/// `eta` between uniform, `n_opt` and `n_psm`, clamped to `ln MAX_WARP_RATIO` and
/// scaled by `fade`, so the warp ratio goes continuously to 1 as `fade` goes to 0.
pub(crate) fn strength(f: &Focus, eta: f64, hints: (f64, f64), fade: f64) -> f64 {
    if fade <= 0.0 || eta <= -1.0 {
        return 0.0;
    }
    // View-depth range of the visible receivers, narrowed by the hints.
    let (mut z_n, mut z_f) = f.receiver_depth;
    let z_scale = z_f.abs().max(z_n.abs()).max(f64::MIN_POSITIVE);
    z_n = z_n.max(hints.0).max(1e-6 * z_scale);
    z_f = z_f.min(hints.1).max(z_n);
    // Extent of the body along the warp axis.
    let (y0, y1) = f.warp_axis_range();
    let d = (y1 - y0).max(0.0);
    if !(d > 0.0) {
        return 0.0;
    }
    let sin_g = f.sin_gamma;
    // Wimmer et al.: n_opt = (z_n + sqrt(z_n z_f)) / sin(gamma); PSM: n = z_n / sin(gamma).
    let s_lisp = sin_g / (z_n + sqrt0(z_n * z_f));
    let s_psm = sin_g / z_n;
    let ln_r_lisp = ln_1p(s_lisp * d);
    let ln_r_psm = ln_1p(s_psm * d);
    let ln_r = if eta <= 0.0 {
        (1.0 + eta) * ln_r_lisp
    } else {
        ln_r_lisp + eta * (ln_r_psm - ln_r_lisp)
    };
    let ln_r = ln_r.min(math::ln(MAX_WARP_RATIO)) * fade;
    let s = (math::exp(ln_r) - 1.0) / d;
    if s.is_finite() && s > 0.0 { s } else { 0.0 }
}

fn ln_1p(x: f64) -> f64 {
    if x < 1e-4 {
        x - 0.5 * x * x + x * x * x / 3.0
    } else {
        math::ln(1.0 + x)
    }
}

/// The warp: light-space `(x, y, z)` to `(x - x_c, y - y_0, z - z_c, 1 + s (y - y_0))`,
/// then an orthographic fit of the warped body. `s = 0` is the uniform fit.
///
/// `s` is limited to `MAX_WARP_RATIO / L`, `L` the largest light-space coordinate of
/// the body: the `f32` matrix computes `w = 1 + s y - s y_0` in world coordinates, so
/// this keeps the rounding of `w` near `1e-3` relative. Returns the `s` used.
pub(crate) fn warp_fit(
    f: &Focus,
    view: &View,
    s: f64,
    reversed_z: bool,
) -> Result<(ShadowTransform, f64), WarpError> {
    let fit = warp_clip(f, view, s, reversed_z)?;
    finish(
        f,
        fit.clip_from_world,
        reversed_z,
        &[fit.world_scale as f32],
    )
    .map(|t| (t, fit.s))
}

/// A fit of [`warp_clip`]: its `f64` clip matrices, the `s` used and the world
/// scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WarpClip {
    pub(crate) clip_from_world: DMat4,
    /// The same from the light frame (`Focus::rot`), which the error prediction
    /// reads.
    pub(crate) clip_from_light: DMat4,
    pub(crate) s: f64,
    pub(crate) world_scale: f64,
}

/// The fit of [`warp_fit`] before its `f32` output.
pub(crate) fn warp_clip(
    f: &Focus,
    view: &View,
    s: f64,
    reversed_z: bool,
) -> Result<WarpClip, WarpError> {
    let lb = &f.light_bounds;
    let scale = f.caster_scale;
    // A footprint too thin for f32 texels gets the widened uniform fit.
    let wide = f.wide;
    let s = (s * wide)
        .min(MAX_WARP_RATIO / f.light_caster_scale)
        .max(0.0);
    let eye = f.rot.transform_point3(view.eye);
    let x_c = eye.x.max(lb.min.x).min(lb.max.x);
    let y0 = lb.min.y;
    let z_c = 0.5 * (lb.min.z + lb.max.z);
    let warp = DMat4::from_cols(
        DVec4::new(1.0, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.0, 0.0, s),
        DVec4::new(0.0, 0.0, 1.0, 0.0),
        DVec4::new(-x_c, -y0, -z_c, 1.0 - s * y0),
    );
    let warp_from_world = warp * f.rot;
    // x, y and the far plane from the receivers; the near plane from the casters.
    // At `s = 0` every `w` is exactly 1 and the divisions by it return their
    // numerators: the uniform fit (and every warp's prediction at strength 0)
    // skips them.
    let affine = s == 0.0;
    let mut b = Bounds::EMPTY;
    for p in &f.receivers {
        b.add(if affine {
            warp_from_world.transform_point3(*p)
        } else {
            warp_from_world.project_point3(*p)
        });
    }
    // The projected depth alone, as `project_point3` computes it.
    let m = &warp_from_world;
    let (zr, wr) = (
        DVec4::new(m.x_axis.z, m.y_axis.z, m.z_axis.z, m.w_axis.z),
        DVec4::new(m.x_axis.w, m.y_axis.w, m.z_axis.w, m.w_axis.w),
    );
    for p in &f.casters {
        let z = zr.x * p.x + zr.y * p.y + zr.z * p.z + zr.w;
        let w = wr.x * p.x + wr.y * p.y + wr.z * p.z + wr.w;
        b.max.z = b.max.z.max(if affine { z } else { z / w });
    }
    if b.is_empty() || !(b.min.is_finite() && b.max.is_finite()) {
        return Err(WarpError::Degenerate);
    }
    let b = turn_invariant(b, f, || warp_from_world).padded(scale, 1.0 - wide);
    let clip_from_warp = ortho_fit(&b, reversed_z);
    Ok(WarpClip {
        clip_from_world: clip_from_warp * warp_from_world,
        clip_from_light: clip_from_warp * warp,
        s,
        world_scale: scale,
    })
}

/// Length of the light frame's raw axis
/// ([`frame_axis`](crate::focus::frame_axis)) below which the box of a
/// fit is fully turn-invariant, and above which it is the plain box (see
/// [`turn_invariant`]); radians, for small ones.
const TURN_INVARIANT_BAND: (f64, f64) = (0.01, 0.02);

/// The fitted bounds `b` widened, near the two light directions where the light
/// frame has no axis, toward a box whose extents do not depend on how the frame is
/// turned about the light: both sides the diameter of the receivers' footprint.
///
/// No frame field on the sphere of light directions is free of zeros (the
/// hairy-ball theorem), so near its two zeros (1° from the view axis, see
/// [`frame`](crate::focus)) the frame turns about the light fast, and the box of the
/// footprint, whose sides depend on that turn, with it: a step of 1e-4 rad of light
/// passing 0.005° from a zero changed the uniform fit's texel size by 31%. A set of
/// diameter `D` fits a box of side `D` in any orientation, so blending the sides
/// toward `D` as the raw axis gets shorter than [`TURN_INVARIANT_BAND`] makes the
/// texel size continuous there (the matrices still turn: no frame can avoid that).
/// Every warp has faded to the uniform fit there, and the box is at most `sqrt 2`
/// times larger, only within about a degree of one direction.
///
/// `warp_from_world` gives the fit's matrix before its box (made only where the
/// box is widened).
pub(crate) fn turn_invariant(
    mut b: Bounds,
    f: &Focus,
    warp_from_world: impl FnOnce() -> DMat4,
) -> Bounds {
    let w = f.turn_weight;
    if !(w > 0.0) {
        return b;
    }
    let warp_from_world = warp_from_world();
    let mut diameter = 0.0f64;
    for (i, p) in f.receivers.iter().enumerate() {
        let p = warp_from_world.project_point3(*p).truncate();
        for q in &f.receivers[i + 1..] {
            let q = warp_from_world.project_point3(*q).truncate();
            diameter = diameter.max((p - q).length());
        }
    }
    for axis in 0..2 {
        let (lo, hi) = (b.min[axis], b.max[axis]);
        let grow = 0.5 * w * (diameter - (hi - lo)).max(0.0);
        b.min[axis] = lo - grow;
        b.max[axis] = hi + grow;
    }
    b
}

/// The weight of [`turn_invariant`]'s widening (once per focus body) for a light
/// frame whose raw axis ([`frame_axis`](crate::focus::frame_axis)) is
/// `axis_length` long: 1 within the first bound of [`TURN_INVARIANT_BAND`], 0
/// beyond the second, smooth between.
pub(crate) fn turn_invariant_weight(axis_length: f64) -> f64 {
    1.0 - smoothstep(TURN_INVARIANT_BAND.0, TURN_INVARIANT_BAND.1, axis_length)
}

/// The strength `s` with its warp ratio `1 + s d` raised to `scale` (`d` the focus
/// body's extent along the warp axis; see `strength_scale` of the options): 1 keeps
/// it, 0 is the uniform fit.
pub(crate) fn scaled_strength(f: &Focus, s: f64, scale: f32) -> f64 {
    let (y0, y1) = f.warp_axis_range();
    crate::xpsm::faded_length(s, (y1 - y0).max(0.0), f64::from(scale))
}

/// The fit of `body` at its chosen strength ([`chosen_strength`]) and the `s` used:
/// the prediction's own fit at that strength where it made one (the chosen
/// strength is one of its grid's, unscaled), else [`warp_fit`] again.
pub(crate) fn fit_chosen(
    body: &FocusBody,
    s_formula: f64,
    scale: f32,
    reversed_z: bool,
) -> Result<(ShadowTransform, f64), WarpError> {
    let (f, view) = (&body.focus, &body.view);
    let mut fits = Fits::new();
    let chosen = chosen_strength(body, s_formula, scale, reversed_z, &mut fits);
    match chosen.kept.and_then(|t| fits.at(t)) {
        Some(fit) => finish(
            f,
            fit.clip_from_world,
            reversed_z,
            &[fit.world_scale as f32],
        )
        .map(|t| (t, fit.s)),
        None => warp_fit(f, view, chosen.s, reversed_z),
    }
}

/// A warp's chosen strength `s`, and the prediction's `t` whose fit
/// ([`warp_clip`]'s, in the prediction's [`Fits`]) is kept where it made one.
struct Chosen {
    s: f64,
    kept: Option<f64>,
}

/// The strength a warp of `body` fits at: [`predicted_strength`] for its formula's
/// `s_formula`, scaled by `scale` ([`scaled_strength`]). At `scale` 0 that is the
/// uniform fit whatever the prediction, so the prediction (most of a warp's cost) is
/// skipped.
fn chosen_strength(
    body: &FocusBody,
    s_formula: f64,
    scale: f32,
    reversed_z: bool,
    fits: &mut Fits<WarpClip>,
) -> Chosen {
    if scale <= 0.0 {
        return Chosen { s: 0.0, kept: None };
    }
    let (s, t) = predicted_strength(body, s_formula, reversed_z, fits);
    // A scale of 1 keeps `s` exactly (`scaled_strength`), and the prediction's fit
    // with it.
    if scale >= 1.0 {
        Chosen { s, kept: t }
    } else {
        Chosen {
            s: scaled_strength(&body.focus, s, scale),
            kept: None,
        }
    }
}

/// The strength to use for a warp whose formula asks for `s_formula`: the fraction
/// of its warp ratio, `ln(1 + s d)`, of least predicted error on the body's probe
/// (see [`Probe::strength`](crate::predict)), so that the fit degrades continuously
/// to the uniform fit where the formula's warp does not pay; and the fraction `t`
/// chosen, where the prediction ran (its [`warp_clip`] fits, depth as `reversed_z`
/// asks, are in `fits`: the prediction reads only the clip's `x`, `y` and `w`).
fn predicted_strength(
    body: &FocusBody,
    s_formula: f64,
    reversed_z: bool,
    fits: &mut Fits<WarpClip>,
) -> (f64, Option<f64>) {
    if !(s_formula > 0.0) {
        return (0.0, None);
    }
    let (f, view) = (&body.focus, &body.view);
    let (y0, y1) = f.warp_axis_range();
    let d = (y1 - y0).max(0.0);
    let ln_r = ln_1p(s_formula * d);
    if !(d > 0.0 && ln_r.is_finite() && ln_r > 0.0) {
        return (s_formula, None);
    }
    let s_at = |t: f64| {
        if t >= 1.0 {
            s_formula
        } else {
            (math::exp(t * ln_r) - 1.0) / d
        }
    };
    let t = body.probe().strength(
        fits,
        |t| warp_clip(f, view, s_at(t), reversed_z).ok(),
        |fit| &fit.clip_from_light,
    );
    (s_at(t), Some(t))
}

#[cfg(test)]
pub(crate) mod tests;
