//! `auto`: the candidate technique with the lowest predicted aliasing error.

use arrayvec::ArrayVec;
use shadowmap_frustum::ShadowMapping;
use shadowmap_warp::{LispsmOptions, TsmOptions, UniformOptions, XpsmOptions};

use crate::cascaded::CountChoice;
use crate::fit::{FitError, FitInput, FitState, fit_candidate_with, predicted_percentiles};
use crate::shadow::Shadow;
use crate::technique::{CascadePlan, Technique};

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

/// `auto`: fits every candidate, predicts each one's 95th-percentile aliasing error
/// on the same rays (`shadowmap_frustum::predict_errors`: the receivers' box stands
/// in for the surfaces; a ray counts where every fitted candidate covers it), and
/// lets `selector` pick (the lowest, unless the current choice is within its margin).
pub(crate) fn fit_auto(
    plan: &CascadePlan,
    input: &FitInput<'_>,
    state: &mut FitState,
) -> Result<Shadow, FitError> {
    let candidates = auto_candidates(plan);
    let mut fitted: [Option<Shadow>; AUTO_CANDIDATE_COUNT] = Default::default();
    let mut tight_fitted = false;
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
    let percentiles = predict(&fitted, input)?;
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
