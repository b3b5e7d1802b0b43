//! The single warps of [`fit`](crate::fit) (LiSPSM, XPSM, TSM): the warp crate's fit
//! at the strength its error prediction chooses, backed off where the eye's samples
//! measure it worse.

use glam::Vec3;
use shadowmap_frustum::{Light, LightDirection, ShadowMapping};
use shadowmap_warp::{FocusBody, lispsm, tsm, xpsm};

use crate::auto::AUTO_MAX_SAMPLES;
use crate::fit::{FitError, FitInput};
use crate::sample_error::{Samples, Unlit, sample_error};
use crate::shadow::Fitted;
use crate::technique::Technique;

/// Shares of the predicted warp tried on the eye's samples (the options'
/// `strength_scale`, times the caller's): the prediction's strength, half its warp
/// ratio, and none (the uniform fit with focusing).
const SCALES: [f32; 3] = [1.0, 0.5, 0.0];

/// LiSPSM, XPSM or TSM (`technique`) for a light travelling along `direction`.
///
/// The warp crate chooses each warp's strength on a prediction over the receivers'
/// box, which stands in for the surfaces the eye sees. Where the frame has the eye's
/// samples (and the image's focal length), the warp is also fitted at half its warp
/// ratio and at none, each measured on them as the quality report measures
/// (`sample_error`: the 95th percentile of `m` over at most [`AUTO_MAX_SAMPLES`]
/// front-lit samples, as `auto` first ranks its candidates), and the finest is kept (the
/// strongest on ties). So a warp is never worse than the uniform fit on the
/// samples it was given: in a small room seen looking down, under a light from
/// above, the box predicted the full warps 0.67 to 0.7 times the uniform fit's
/// error and they measured 1.56 to 1.85 times it (the room's walls and furniture,
/// not its floor, hold the largest errors). From `shared` where given (`auto`
/// fits its warps from one body), else from a body of its own.
pub(crate) fn fit_warp(
    technique: &Technique,
    direction: Vec3,
    input: &FitInput<'_>,
    shared: Option<&FocusBody>,
) -> Result<Fitted, FitError> {
    if shared.is_some() {
        return fit_warp_from(technique, direction, input, shared);
    }
    // Read where it was built: a body is large (its probe points), and a body
    // assigned to a variable declared before is built elsewhere and copied.
    let built = FocusBody::new(input.camera, direction, &input.scene);
    fit_warp_from(technique, direction, input, built.as_ref().ok())
}

/// [`fit_warp`] from `body`, one focus body for every strength tried, so its probe
/// points are cast once. Where there is none (it failed), the warp's own entry
/// point reports the error it reports (an invalid option before the body's).
fn fit_warp_from(
    technique: &Technique,
    direction: Vec3,
    input: &FitInput<'_>,
    body: Option<&FocusBody>,
) -> Result<Fitted, FitError> {
    let (camera, scene) = (input.camera, &input.scene);
    let fit_at = |scale: f32| -> Result<Fitted, FitError> {
        Ok(match technique {
            Technique::Lispsm(o) => {
                let o = o.with_strength_scale(o.strength_scale * scale);
                Fitted::Lispsm(match body {
                    Some(body) => body.lispsm(&o)?,
                    None => lispsm(camera, direction, scene, &o)?,
                })
            }
            Technique::Xpsm(o) => {
                let o = o.with_strength_scale(o.strength_scale * scale);
                Fitted::Xpsm(match body {
                    Some(body) => body.xpsm(&o)?,
                    None => xpsm(camera, direction, scene, &o)?,
                })
            }
            Technique::Tsm(o) => {
                let o = o.with_strength_scale(o.strength_scale * scale);
                Fitted::Tsm(match body {
                    Some(body) => body.tsm(&o)?,
                    None => tsm(camera, direction, scene, &o)?,
                })
            }
            _ => return Err(FitError::NoCandidate),
        })
    };
    let samples = directional_samples(input);
    let error = samples.as_ref().map(|(samples, light)| {
        |fitted: &Fitted| {
            let mapping: &dyn ShadowMapping = match fitted {
                Fitted::Lispsm(s) => &s.transform,
                Fitted::Xpsm(s) => &s.transform,
                Fitted::Tsm(s) => &s.transform,
                _ => return None,
            };
            sample_error(mapping, 1.0, samples, *light, 0.95)
        }
    });
    finest_strength(fit_at(SCALES[0])?, fit_at, error)
}

/// The eye samples of `input` as the warps and `auto` measure on them (at most
/// [`AUTO_MAX_SAMPLES`], unlit ones skipped) and the light, `None` without samples,
/// the image's focal length or a directional light.
pub(crate) fn directional_samples<'a>(
    input: &FitInput<'a>,
) -> Option<(Samples<'a>, LightDirection)> {
    let (Some(samples), Some(ppr), Light::Directional { direction }) =
        (input.eye_samples, input.pixels_per_radian, *input.light)
    else {
        return None;
    };
    let samples = Samples {
        most: AUTO_MAX_SAMPLES,
        unlit: Unlit::Skipped,
        ..Samples::new(input.camera, ppr, samples)
    };
    Some((samples, LightDirection::Directional(direction)))
}

/// The finest of a warp fitted at each share of its predicted strength in
/// [`SCALES`] (`predicted`, the fit at the first share, then `fit_at(scale)` at the
/// others), by `error` (the 95th percentile over the eye's samples); `predicted`
/// alone without `error` or where it measures nothing. Ties keep the stronger warp.
pub(crate) fn finest_strength<T>(
    predicted: T,
    fit_at: impl Fn(f32) -> Result<T, FitError>,
    error: Option<impl Fn(&T) -> Option<f64>>,
) -> Result<T, FitError> {
    let Some(error) = error else {
        return Ok(predicted);
    };
    let Some(mut least) = error(&predicted) else {
        return Ok(predicted);
    };
    let mut best = predicted;
    for scale in SCALES.into_iter().skip(1) {
        let Ok(fitted) = fit_at(scale) else { continue };
        if let Some(e) = error(&fitted).filter(|e| *e < least) {
            (least, best) = (e, fitted);
        }
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use shadowmap_frustum::{Aabb, Camera, Light, LightDirection, Projection, SceneBounds};
    use shadowmap_warp::{LispsmOptions, TsmOptions, XpsmOptions};

    use super::*;
    use crate::fit::{depth_bounds_of, fit};
    use crate::technique::CascadePlan;
    use crate::test_views::{room_samples, unit_random};

    /// With the eye's samples, LiSPSM, XPSM and TSM are never measured worse on them
    /// than their own uniform fit (the strength scaled to 0), over views of a room
    /// from its corners under lights from above at every angle; and the prediction
    /// alone is, in some of them (not a test that always warps in full).
    #[test]
    fn with_eye_samples_a_warp_is_never_worse_than_its_uniform_fit_on_them() {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || unit_random(&mut state);
        let room = Aabb::new(Vec3::new(-3.0, 0.0, -4.0), Vec3::new(3.0, 2.8, 4.0));
        let (mut checked, mut backed_off, mut warped_backed_off) = (0, 0, 0);
        for _ in 0..60 {
            let eye = Vec3::new(4.0 * next() - 2.0, 1.2 + next(), 6.0 * next() - 3.0);
            let heading = core::f32::consts::TAU * next();
            let forward = Vec3::new(heading.sin(), -0.6 * next(), heading.cos());
            let camera = Camera::look_to(
                eye,
                forward,
                Vec3::Y,
                Projection::perspective(1.0, 1.5, 0.1, 20.0),
            )
            .unwrap();
            let tilt = 0.7 * next();
            let azimuth = core::f32::consts::TAU * next();
            let direction = Vec3::new(tilt * azimuth.cos(), -1.0, tilt * azimuth.sin());
            let light = Light::Directional { direction };
            let samples = room_samples(&camera, &room, 64, 48);
            let boxed = crate::FitInput::new(&camera, &light, SceneBounds::whole(room), 1 << 14)
                .with_depth_bounds(depth_bounds_of(&camera, &samples));
            let input = boxed
                .with_eye_samples(&samples)
                .with_pixels_per_radian(48.0);
            let measured = |shadow: &crate::Shadow| {
                let samples = Samples {
                    unlit: Unlit::Skipped,
                    most: AUTO_MAX_SAMPLES,
                    ..Samples::new(&camera, 48.0, &samples)
                };
                let light = LightDirection::Directional(direction);
                sample_error(shadow, 1.0, &samples, light, 0.95)
            };
            // One warped cascade: the count cannot differ between the two.
            let one = CascadePlan {
                max_cascades: 1,
                ..CascadePlan::default()
            };
            let warped = |lispsm: LispsmOptions| Technique::WarpedCascades { plan: one, lispsm };
            for (full, none) in [
                (
                    Technique::Lispsm(LispsmOptions::default()),
                    Technique::Lispsm(LispsmOptions::default().with_strength_scale(0.0)),
                ),
                (
                    Technique::Xpsm(XpsmOptions::default()),
                    Technique::Xpsm(XpsmOptions::default().with_strength_scale(0.0)),
                ),
                (
                    Technique::Tsm(TsmOptions::default()),
                    Technique::Tsm(TsmOptions::default().with_strength_scale(0.0)),
                ),
                (
                    warped(LispsmOptions::default()),
                    warped(LispsmOptions::default().with_strength_scale(0.0)),
                ),
            ] {
                let (Ok(chosen), Ok(uniform), Ok(predicted)) =
                    (fit(&full, &input), fit(&none, &input), fit(&full, &boxed))
                else {
                    continue;
                };
                let (Some(c), Some(u), Some(p)) =
                    (measured(&chosen), measured(&uniform), measured(&predicted))
                else {
                    continue;
                };
                assert!(c <= u * (1.0 + 1e-9), "{}: {c} vs {u}", full.name());
                checked += 1;
                backed_off += usize::from(p > u * 1.05);
                warped_backed_off +=
                    usize::from(matches!(full, Technique::WarpedCascades { .. }) && p > u * 1.05);
            }
        }
        assert!(
            checked > 130 && backed_off > 0 && warped_backed_off > 0,
            "{checked} checked, {backed_off} ({warped_backed_off} warped cascades)"
        );
    }
}
