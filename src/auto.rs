//! `auto`: the candidate technique with the lowest predicted aliasing error.

use arrayvec::ArrayVec;
use shadowmap_frustum::{LightDirection, ShadowMapping};
use shadowmap_warp::{LispsmOptions, TsmOptions, UniformOptions, XpsmOptions};

use crate::cascaded::CountChoice;
use crate::fit::{FitError, FitInput, FitState, fit_candidate_with, predicted_percentiles};
use crate::sample_error::{Samples, sample_error};
use crate::shadow::Shadow;
use crate::technique::{CascadePlan, Technique};
use crate::warp_fit::directional_samples;

/// Number of candidates of [`Technique::Auto`] ([`auto_candidates`]).
pub const AUTO_CANDIDATE_COUNT: usize = 7;

/// The candidates of [`Technique::Auto`] with this cascade plan, from the most to the
/// least preferred when predictions tie: uniform, LiSPSM, TSM, XPSM (default
/// options), tight, warped and stable cascades. A
/// [`TechniqueSelector`](shadowmap_frustum::TechniqueSelector) indexes this
/// list.
#[must_use]
pub fn auto_candidates(plan: &CascadePlan) -> [Technique; AUTO_CANDIDATE_COUNT] {
    [
        Technique::UniformFocused(UniformOptions::default()),
        Technique::Lispsm(LispsmOptions::default()),
        Technique::Tsm(TsmOptions::default()),
        Technique::Xpsm(XpsmOptions::default()),
        Technique::TightCascades(*plan),
        Technique::WarpedCascades {
            plan: *plan,
            lispsm: LispsmOptions::default(),
        },
        Technique::StableCascades(*plan),
    ]
}

/// Most eye samples `auto` measures each candidate on (a regular subset of the
/// frame's): over the quality report's random sweep 512 choose as well as 1024 or
/// 4096 (no view more than 1.08 times the best), in about 0.35 ms for the seven
/// candidates (one derivative of each matrix per sample). With the tight cascades'
/// count and the warps' strengths measured on the same samples, `auto` on a 160 x
/// 90 G-buffer's samples takes about 1.4 ms a frame in all (`cargo bench --bench
/// fit_state`: `auto_on_samples`, 455 times the uniform fit; 0.8 ms with the warps
/// at their predicted strength only, which measured 1.2 times the best technique
/// over a fence at seed 14).
pub const AUTO_MAX_SAMPLES: usize = 512;

/// `auto`: fits every candidate, ranks them by their 95th-percentile aliasing error,
/// and lets `selector` pick (the lowest, unless the current choice is within its
/// margin).
///
/// The error is measured on the eye samples when the frame has them (and the
/// image's focal length): the report's measure `m` on a regular subset of at most
/// [`AUTO_MAX_SAMPLES`] front-lit samples, each candidate on the samples it
/// covers, as the IPSM fit chooses its map. Without them (or without a front-lit
/// sample any candidate covers) it is predicted
/// from the camera, the light and the bounds alone
/// (`shadowmap_frustum::predict_errors`: the receivers' box stands in for the
/// surfaces; a ray counts where every fitted candidate covers it). The box cannot
/// say where a street ends in sky, or which facades a ray really meets: over the
/// quality report's random sweep (seeds 1 to 5, 440 directional views) the
/// prediction picked a candidate more than 1.15 times the best measured one in 32
/// views (up to 3.0 times), the samples in none (at most 1.08 times).
pub(crate) fn fit_auto(
    plan: &CascadePlan,
    input: &FitInput<'_>,
    state: &mut FitState,
) -> Result<Shadow, FitError> {
    let candidates = auto_candidates(plan);
    let mut fitted: [Option<Shadow>; AUTO_CANDIDATE_COUNT] = Default::default();
    let mut tight_fitted = false;
    // The warps and warped cascades back off on the samples as they do alone
    // (half their warp ratio, or none): fitted at their predicted strength only, a
    // warp the samples would back off half way is not among the candidates, and
    // `auto` measured 1.2 times TSM (which did) over a fence at seed 14.
    for (slot, technique) in fitted.iter_mut().zip(&candidates) {
        // The stable cascades' count is predicted by the same tight fits as the
        // tight cascades': fitted after them, they keep the count just chosen.
        let count = match technique {
            Technique::StableCascades(_) if tight_fitted => CountChoice::Keep,
            _ => CountChoice::Predict,
        };
        *slot = fit_candidate_with(technique, input, state, count).ok();
        if matches!(technique, Technique::TightCascades(_)) {
            tight_fitted = slot.is_some();
        }
    }
    let percentiles = match directional_samples(input) {
        Some((samples, light)) if !samples.samples.is_empty() => {
            let measured = measure(&fitted, &samples, light);
            if measured.iter().any(Option::is_some) {
                measured
            } else {
                // No candidate covers a front-lit sample: the prediction decides.
                predict(&fitted, input)?
            }
        }
        _ => predict(&fitted, input)?,
    };
    let chosen = state
        .selector
        .choose(&percentiles)
        .ok_or(FitError::NoCandidate)?;
    let mut shadow = fitted
        .get_mut(chosen)
        .and_then(Option::take)
        .ok_or(FitError::NoCandidate)?;
    shadow.requested = Technique::Auto(*plan);
    Ok(shadow)
}

/// Each fitted candidate's 95th percentile on the eye `samples`, at its index in
/// the candidate list (`None`: not fitted, or covering no sample).
fn measure(
    fitted: &[Option<Shadow>; AUTO_CANDIDATE_COUNT],
    samples: &Samples<'_>,
    light: LightDirection,
) -> [Option<f64>; AUTO_CANDIDATE_COUNT] {
    fitted.each_ref().map(|shadow| {
        let shadow = shadow.as_ref()?;
        let side = f64::from(shadow.layer_side);
        sample_error(shadow, side, samples, light, 0.95)
    })
}

/// Each fitted candidate's predicted 95th percentile, at its index in the candidate
/// list (`None`: not fitted or not predicted).
fn predict(
    fitted: &[Option<Shadow>; AUTO_CANDIDATE_COUNT],
    input: &FitInput<'_>,
) -> Result<[Option<f64>; AUTO_CANDIDATE_COUNT], FitError> {
    let mut index = ArrayVec::<usize, AUTO_CANDIDATE_COUNT>::new();
    let mut mappings = ArrayVec::<(&dyn ShadowMapping, u32), AUTO_CANDIDATE_COUNT>::new();
    for (i, shadow) in fitted.iter().enumerate() {
        if let Some(s) = shadow {
            index.push(i);
            mappings.push((s as &dyn ShadowMapping, s.layer_side));
        }
    }
    let mut predicted = [None; AUTO_CANDIDATE_COUNT];
    predicted_percentiles(input, &mappings, &mut predicted)?;
    let mut percentiles = [None; AUTO_CANDIDATE_COUNT];
    for (i, p) in index.iter().zip(predicted) {
        percentiles[*i] = p;
    }
    Ok(percentiles)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds};

    use super::*;
    use crate::fit::{depth_bounds_of, fit};
    use crate::sample_error::Unlit;
    use crate::test_views::street_samples;

    /// With the eye samples, `auto` keeps the candidate whose aliasing error on
    /// them is the lowest, each candidate measured as the quality report measures
    /// (front-lit samples, the report's `m`); at the end of a street under a tall
    /// receivers' box the box's prediction alone picks one that is worse there.
    #[test]
    fn with_eye_samples_auto_keeps_the_candidate_finest_on_them() {
        let camera = Camera::look_to(
            Vec3::new(0.0, 1.7, 0.0),
            Vec3::new(0.05, 0.05, -1.0),
            Vec3::Y,
            Projection::perspective(1.0, 1.5, 0.3, 300.0),
        )
        .unwrap();
        let direction = Vec3::new(0.0, -1.0, -0.2);
        let light = Light::Directional { direction };
        let street = Aabb::new(Vec3::new(-40.0, -1.0, -300.0), Vec3::new(40.0, 40.0, 10.0));
        let samples = street_samples(&camera, 96, 64, -40.0);
        let boxed = FitInput::new(&camera, &light, SceneBounds::whole(street), 512 * 512)
            .with_depth_bounds(depth_bounds_of(&camera, &samples));
        let input = boxed
            .with_eye_samples(&samples)
            .with_pixels_per_radian(400.0);
        let plan = CascadePlan::default();
        let measured = |shadow: &Shadow| {
            let side = f64::from(shadow.layer_side);
            let samples = Samples {
                most: AUTO_MAX_SAMPLES,
                unlit: Unlit::Skipped,
                ..Samples::new(&camera, 400.0, &samples)
            };
            let light = LightDirection::Directional(direction);
            sample_error(shadow, side, &samples, light, 0.95).unwrap()
        };
        let errors: Vec<f64> = auto_candidates(&plan)
            .iter()
            .map(|t| measured(&fit(t, &input).unwrap()))
            .collect();
        let best = errors.iter().copied().fold(f64::INFINITY, f64::min);
        let chosen = fit(&Technique::Auto(plan), &input).unwrap();
        assert_eq!(
            measured(&chosen),
            best,
            "{:?}: {errors:?}",
            chosen.technique()
        );
        let predicted = fit(&Technique::Auto(plan), &boxed).unwrap();
        assert!(
            measured(&predicted) > 1.05 * best,
            "{:?} predicted, {:?} measured: {errors:?}",
            predicted.technique(),
            chosen.technique()
        );
    }
}
