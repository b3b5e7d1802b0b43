//! Trapezoidal shadow maps (Martin and Tan 2004).

use arrayvec::ArrayVec;
use glam::Vec3;
use shadowmap_frustum::{Camera, MAX_BODY_VERTICES, ShadowTransform};

use crate::FocusBody;
use crate::lispsm::fit_chosen;
use crate::{MAX_WARP_RATIO, WarpError};
use crate::{ParallelFade, SceneBounds};

/// Options of [`tsm`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct TsmOptions {
    /// Depth 1 at the light's near plane and 0 at its far plane.
    pub reversed_z: bool,
    /// Where the focus point sits, as a fraction in `(0, 1)` of the visible
    /// receivers' view-depth range: the region up to it gets 80% of the map (the
    /// "80% rule"). Default 0.1.
    pub focus: f32,
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

impl Default for TsmOptions {
    fn default() -> Self {
        Self::new()
    }
}

impl TsmOptions {
    /// Defaults: standard depth, focus 0.1, fade between 10 and 3 degrees.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            reversed_z: false,
            focus: 0.1,
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

    /// Sets [`focus`](Self::focus).
    #[must_use]
    pub const fn with_focus(mut self, focus: f32) -> Self {
        self.focus = focus;
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
        let ok = self.focus > 0.0
            && self.focus < 1.0
            && self.fade.is_valid()
            && (0.0..=1.0).contains(&self.strength_scale);
        if ok {
            Ok(())
        } else {
            Err(WarpError::InvalidOption)
        }
    }
}

/// A TSM fit: the matrices and the trapezoid's projection distance.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TsmShadow {
    /// The matrices (depth pass and lookup).
    pub transform: ShadowTransform,
    /// `η`: distance from the trapezoid's apex (the projection centre) to its top
    /// edge along the centre line; infinite when the trapezoid is a rectangle.
    #[cfg_attr(
        feature = "serde",
        serde(with = "crate::serde_impls::infinite_as_none")
    )]
    pub eta: f32,
}

/// Trapezoidal shadow map (Martin and Tan 2004) of a directional light.
///
/// In the light's post-projective (here: orthographic, light frame) space the centre
/// line runs along the view direction, which is the light frame's `+Y`
/// ([`light_frame`](crate::light_frame)); the top and base edges of the trapezoid
/// are perpendicular to it and touch the visible receivers (frustum ∩ receivers) on
/// the near and far side, `λ` apart. The focus region, the visible receivers nearer
/// than the focus depth (see [`TsmOptions::focus`]), reaches `δ'` from the top edge
/// and is mapped inside the 80% line (`ξ = -0.6`):
///
/// ```text
/// η = λ δ' (1 + ξ) / (λ (1 - ξ) - 2 δ')      (rectangle when δ' >= 0.8 λ)
/// ```
///
/// and the sides are the tangents from the apex, `η` before the top edge, to the
/// receivers. When the view depth orders the receivers along the centre line (the
/// usual case: the near plane projects onto the top edge) the focus region ends at
/// the focus point on the centre line, as in the paper. When it does not (a camera
/// looking down, or toward the light) the nearest receivers spread over the whole
/// trapezoid, `δ'` reaches `0.8 λ` and the trapezoid becomes the rectangle of the
/// uniform fit instead of magnifying a strip that is no nearer than the rest. The trapezoid-to-square map is the projective warp of
/// [`lispsm`](crate::lispsm) with `n = η`, followed by the same fit, so depth is
/// handled as in LiSPSM (linear along every light ray, casters kept) rather than
/// with TSM's separate depth pass.
///
/// The 80% rule assumes the focus region is where the eye needs texels; in a small
/// room, or a camera over a large scene, the trapezoid magnifies a strip of floor
/// near the viewer and starves the walls and the distance (the quality report's
/// random sweep measured up to 12 times the uniform fit's 95th-percentile error).
/// So, as in [`lispsm`](crate::lispsm), the trapezoid's warp ratio is scaled by the
/// fraction of least predicted error over the focus body where the full trapezoid
/// is not predicted clearly better than the uniform fit, continuously down to the
/// rectangle of the uniform fit.
///
/// # Errors
/// As [`uniform_focused`](crate::uniform_focused), and [`WarpError::InvalidOption`].
pub fn tsm(
    camera: &Camera,
    light_direction: Vec3,
    scene: &SceneBounds,
    options: &TsmOptions,
) -> Result<TsmShadow, WarpError> {
    options.check()?;
    FocusBody::fit_from(camera, light_direction, scene, |body| body.tsm(options))
}

impl FocusBody {
    /// The TSM fit of this body (see [`tsm`]).
    ///
    /// # Errors
    /// [`WarpError::InvalidOption`]; [`WarpError::Degenerate`].
    pub fn tsm(&self, options: &TsmOptions) -> Result<TsmShadow, WarpError> {
        options.check()?;
        tsm_body(self, options)
    }
}

fn tsm_body(body: &FocusBody, options: &TsmOptions) -> Result<TsmShadow, WarpError> {
    let (view, f) = (&body.view, &body.focus);
    let fade = options.fade.weight(f.sin_gamma);
    // Top and base edges: the receivers' extent along the centre line (their
    // light-space footprint's), and their view-depth range.
    let (y0, y1) = (f.footprint.min.y, f.footprint.max.y);
    let (z_n, z_f) = f.receiver_depth;
    let mut yd: ArrayVec<(f64, f64), MAX_BODY_VERTICES> = ArrayVec::new();
    for p in &f.receivers {
        let y = f.rot.transform_point3(*p).y;
        let d = (*p - view.eye).dot(view.forward);
        yd.push((y, d));
    }
    let lambda = y1 - y0;
    // The focus region: the visible receivers nearer than the focus depth; the
    // 80% line must hold all of it.
    let z_focus = z_n + f64::from(options.focus) * (z_f - z_n);
    let delta = (focus_region_top(&yd, z_focus) - y0).clamp(0.0, lambda.max(0.0));
    const XI: f64 = -0.6;
    let denom = lambda * (1.0 - XI) - 2.0 * delta;
    let mut s = if lambda > 0.0 && denom > 0.0 && delta > 0.0 {
        denom / (lambda * delta * (1.0 + XI))
    } else {
        0.0
    };
    // Precision guard as in LiSPSM, then the parallel-light fade.
    if lambda > 0.0 {
        s = s.min((MAX_WARP_RATIO - 1.0) / lambda);
    }
    let s = if s.is_finite() { s * fade } else { 0.0 };
    let (transform, s) = fit_chosen(body, s, options.strength_scale, options.reversed_z)?;
    Ok(TsmShadow {
        transform,
        eta: if s > 0.0 {
            (1.0 / s) as f32
        } else {
            f32::INFINITY
        },
    })
}

/// Largest `y` over the part of a convex body with depth `d <= z`, from the body's
/// vertices as `(y, d)`: the maximum of a linear function over the body clipped by a
/// half-space lies at a vertex inside it or where an edge crosses the plane, and every
/// segment between two vertices lies in the body, so the vertex pairs cover it.
fn focus_region_top(yd: &[(f64, f64)], z: f64) -> f64 {
    let mut top = f64::NEG_INFINITY;
    for &(ya, da) in yd.iter().filter(|(_, d)| *d <= z) {
        top = top.max(ya);
        for &(yb, db) in yd.iter().filter(|(_, d)| *d > z) {
            let t = (z - da) / (db - da);
            top = top.max(ya + (yb - ya) * t);
        }
    }
    top
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};
    use shadowmap_frustum::ShadowMapping;

    use super::*;

    #[test]
    fn the_focus_point_lands_on_the_80_percent_line() {
        let (eye, camera, scene) = crate::lispsm::tests::overhead_view();
        for focus in [0.05f32, 0.1, 0.3, 0.6] {
            let t = tsm(
                &camera,
                Vec3::NEG_Y,
                &scene,
                &TsmOptions::default().with_focus(focus),
            )
            .unwrap();
            assert!(t.eta.is_finite());
            let depth = 1.0 + f64::from(focus) * 999.0;
            let v = |z: f64| {
                t.transform
                    .map_point(eye.as_dvec3() + DVec3::new(0.0, 0.0, -z))
                    .unwrap()
                    .uv
                    .y
            };
            // Fraction of the map's height from the near edge to the focus point.
            let frac = (v(1.0) - v(depth)) / (v(1.0) - v(1000.0));
            assert!((frac - 0.8).abs() < 1e-3, "focus {focus}: {frac}");
        }
        // Beyond 80% the trapezoid is a rectangle: the uniform fit.
        let t = tsm(
            &camera,
            Vec3::NEG_Y,
            &scene,
            &TsmOptions::default().with_focus(0.9),
        )
        .unwrap();
        assert!(t.eta.is_infinite());
        assert_eq!(
            tsm(
                &camera,
                Vec3::NEG_Y,
                &scene,
                &TsmOptions::default().with_focus(1.0)
            )
            .err(),
            Some(WarpError::InvalidOption)
        );
    }
}
