//! `auto`: the candidate technique with the lowest predicted aliasing error.

use arrayvec::ArrayVec;
use shadowmap_frustum::{LightDirection, ShadowMapping};
use shadowmap_warp::{FocusBody, LispsmOptions, TsmOptions, UniformOptions, XpsmOptions};

use crate::fit::{FitError, FitInput, FitState, fit_candidate, predicted_percentiles};
use crate::sample_error::{PercentileBand, Samples, percentile_band, sample_error, sample_errors};
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

/// Most eye samples `auto` measures each candidate on first (a regular subset of
/// the frame's): the candidates that could still be the best within that subset's
/// noise are then measured again on more ([`AUTO_CONFIRM_SAMPLES`]; a frame with no
/// more samples than that is measured whole at once). With the cascades' counts,
/// the stable maps' orientations and the warps' strengths measured on the same
/// samples, `auto` on a 160 x 90 G-buffer's samples takes about 1.26 ms a frame in
/// all (`cargo bench --bench fit_state`: `auto_on_samples`, about 660 times the
/// uniform fit). The warps at their predicted strength only took 0.8 ms against
/// 1.4 ms when that was measured, and measured 1.2 times the best technique over
/// a fence at seed 14.
pub const AUTO_MAX_SAMPLES: usize = 512;

/// `auto`: fits every candidate, ranks them by their 95th-percentile aliasing error,
/// and lets `selector` pick (the lowest, unless the current choice is within its
/// margin).
///
/// The error is measured on the eye samples when the frame has them (and the
/// image's focal length): the report's measure `m` on a regular subset of at most
/// [`AUTO_MAX_SAMPLES`] front-lit samples, each candidate on the samples it
/// covers, as the IPSM fit chooses its map, and the close ones again on more
/// (see `measure`). Without them (or without a front-lit
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
    // The warps and warped cascades back off on the samples as they do alone
    // (half their warp ratio, or none): fitted at their predicted strength only, a
    // warp the samples would back off half way is not among the candidates, and
    // `auto` measured 1.2 times TSM (which did) over a fence at seed 14. The stable
    // cascades choose their count on their own error, as alone: with the tight
    // cascades' count instead, a stable map turned along a fence's footprint (one
    // map, 2.6) stood in `auto` as four maps (4.5, `compare --seed 81 --sweep 64`,
    // random_fence_018).
    // One focus body for the uniform fit and the three warps, so the warps cast its
    // probe points once (`auto` is for directional lights alone; the body is read
    // where it was built: it is large).
    let built = FocusBody::new(input.camera, input.light_direction(), &input.scene);
    let body = built.as_ref().ok();
    for (slot, technique) in fitted.iter_mut().zip(&candidates) {
        *slot = fit_candidate(technique, input, state, body).ok();
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

/// Most eye samples `auto` measures its contenders on a second time: the
/// candidates whose 95th percentile on the first subset ([`AUTO_MAX_SAMPLES`]) could
/// still be the lowest within that subset's noise (a percentile band of one binomial
/// standard deviation of rank each way).
pub const AUTO_CONFIRM_SAMPLES: usize = 4096;

/// Each fitted candidate's 95th percentile on the eye `samples`, at its index in
/// the candidate list (`None`: not fitted, covering no sample, or out of the
/// running). Measured on a subset of at most [`AUTO_MAX_SAMPLES`] first; where more
/// than one candidate could be the lowest within that subset's noise, those alone
/// stay in the running, measured again on at most [`AUTO_CONFIRM_SAMPLES`]. A
/// percentile near a knee of the errors (a few percent of the pixels on a wall seen
/// edge-on, far coarser than the rest) lands on either side of it by chance on a
/// small subset: TSM measured 2.10 on 478 samples of a view where it has 1.01 on
/// 3,680 (and the next best 1.28). The second measure takes most samples, not a
/// middle count: a regular subset can fall in step with the image's rows, and a
/// 2,048-sample one measured three candidates of a view 1.4 times their 95th
/// percentile on 4,096. A frame with at most [`AUTO_CONFIRM_SAMPLES`] samples is
/// measured whole at once: a regular subset of a small image is as much in step
/// with its rows (every fifth of a room's 2,132 samples put the tight cascades at
/// 3.52 where all of them have 4.36, a bias no band shows, and `auto` took them at
/// 1.02 times the uniform fit).
fn measure(
    fitted: &[Option<Shadow>; AUTO_CANDIDATE_COUNT],
    samples: &Samples<'_>,
    light: LightDirection,
) -> [Option<f64>; AUTO_CANDIDATE_COUNT] {
    let more = Samples {
        most: AUTO_CONFIRM_SAMPLES,
        ..*samples
    };
    // A small frame: every sample at once, and no second measure.
    let samples = if samples.samples.len() <= AUTO_CONFIRM_SAMPLES {
        &more
    } else {
        samples
    };
    let mut errors = ArrayVec::new();
    let bands = fitted.each_ref().map(|shadow| {
        let shadow = shadow.as_ref()?;
        sample_errors(
            shadow,
            f64::from(shadow.layer_side),
            samples,
            light,
            &mut errors,
        );
        percentile_band(&mut errors, 0.95)
    });
    let measured = bands.map(|band| band.map(|b| b.value));
    let contenders = contenders(&bands);
    let again = contenders
        .iter()
        .filter(|c| **c == Contender::Again)
        .count();
    if samples.samples.len() <= samples.most || again < 2 {
        return measured;
    }
    let mut confirmed = [None; AUTO_CANDIDATE_COUNT];
    for (i, shadow) in fitted.iter().enumerate() {
        if let (Contender::Again, Some(shadow)) = (contenders[i], shadow) {
            let side = f64::from(shadow.layer_side);
            confirmed[i] = sample_error(shadow, side, &more, light, 0.95).or(measured[i]);
        }
    }
    for i in 0..AUTO_CANDIDATE_COUNT {
        if let Contender::TwinOf(j) = contenders[i] {
            confirmed[i] = confirmed[j];
        }
    }
    confirmed
}

/// Most candidates `auto` measures a second time. Where the warps back off to the
/// uniform fit and one map covers the view, every candidate can be within the
/// first subset's noise of the others (in a room seen on 2,304 samples, bands from
/// 1.1 to 3.4 wide); measuring them all again would cost up to seven times one
/// measure on the larger subset.
pub const AUTO_CONFIRM_CANDIDATES: usize = 3;

/// What `measure` does with a candidate after the first subset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Contender {
    /// Out of the running: it cannot be the lowest within the subset's noise, or
    /// [`AUTO_CONFIRM_CANDIDATES`] more likely ones are measured again.
    Out,
    /// Measured again on more samples.
    Again,
    /// The same band as the candidate at this index, measured again: one
    /// fit under two names (a warp backed off to the uniform fit), given its value.
    TwinOf(usize),
}

/// The candidates whose percentile band reaches below the top of the lowest band
/// (within the subset's noise, each of them could be the lowest): the one with the
/// lowest percentile first, then those with the lowest bottoms, at most
/// [`AUTO_CONFIRM_CANDIDATES`] of them measured again; a candidate with exactly the
/// band of one measured again is its twin.
fn contenders(
    bands: &[Option<PercentileBand>; AUTO_CANDIDATE_COUNT],
) -> [Contender; AUTO_CANDIDATE_COUNT] {
    let lowest_high = bands
        .iter()
        .flatten()
        .map(|b| b.high)
        .fold(f64::INFINITY, f64::min);
    let value = |i: usize| bands[i].map_or(f64::INFINITY, |b| b.value);
    let low = |i: usize| bands[i].map_or(f64::INFINITY, |b| b.low);
    let lowest = (0..AUTO_CANDIDATE_COUNT)
        .min_by(|a, b| value(*a).total_cmp(&value(*b)).then(a.cmp(b)))
        .unwrap_or(0);
    let mut order: [usize; AUTO_CANDIDATE_COUNT] = core::array::from_fn(|i| i);
    order.sort_by(|a, b| {
        (*a != lowest)
            .cmp(&(*b != lowest))
            .then(low(*a).total_cmp(&low(*b)))
            .then(a.cmp(b))
    });
    let mut contenders = [Contender::Out; AUTO_CANDIDATE_COUNT];
    let mut again = 0;
    for i in order {
        if bands[i].is_none() || low(i) > lowest_high {
            continue;
        }
        let twin = (0..AUTO_CANDIDATE_COUNT)
            .find(|j| contenders[*j] == Contender::Again && bands[*j] == bands[i]);
        contenders[i] = match twin {
            Some(j) => Contender::TwinOf(j),
            _ if again < AUTO_CONFIRM_CANDIDATES => {
                again += 1;
                Contender::Again
            }
            _ => Contender::Out,
        };
    }
    contenders
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

    /// An eye at head height looking along `forward` down a street 300 m long under
    /// a receivers' box 40 m tall ([`street_samples`] draws what it sees).
    fn street_view(forward: Vec3) -> (Camera, Aabb) {
        let camera = Camera::look_to(
            Vec3::new(0.0, 1.7, 0.0),
            forward,
            Vec3::Y,
            Projection::perspective(1.0, 1.5, 0.3, 300.0),
        )
        .unwrap();
        let street = Aabb::new(Vec3::new(-40.0, -1.0, -300.0), Vec3::new(40.0, 40.0, 10.0));
        (camera, street)
    }

    /// A candidate whose subset percentile lies past a knee of its errors (94% of
    /// them fine, the rest twice as coarse) could be the lowest within the subset's
    /// noise, and so could a candidate just above the knee's foot; one far above
    /// both could not.
    #[test]
    fn a_percentile_past_a_knee_leaves_the_choice_to_more_samples() {
        let band = |mut errors: Vec<f64>| percentile_band(&mut errors, 0.95);
        let knee = band((0..478).map(|i| if i < 450 { 1.0 } else { 2.1 }).collect());
        let knee_band = knee.unwrap();
        assert_eq!((knee_band.low, knee_band.value), (1.0, 2.1));
        let steady = band((0..478).map(|i| 1.2 + f64::from(i) * 1e-4).collect());
        let coarse = band(vec![6.0; 478]);
        let mut bands = [None; AUTO_CANDIDATE_COUNT];
        bands[..3].copy_from_slice(&[knee, steady, coarse]);
        use Contender::{Again, Out, TwinOf};
        assert_eq!(contenders(&bands)[..3], [Again, Again, Out]);
        // Without the knee the fine candidate alone is a contender.
        bands[0] = band(vec![1.0; 478]);
        assert_eq!(contenders(&bands)[..3], [Again, Out, Out]);
        // Seven candidates within each other's noise: the lowest percentile, then
        // the lowest bottoms; a candidate with the band of one measured again is
        // its twin.
        let spread = |k: usize| {
            band(
                (0..478)
                    .map(|i| 2.0 - 1e-4 * k as f64 + f64::from(i) * 1e-4)
                    .collect(),
            )
        };
        let mut bands: [Option<PercentileBand>; AUTO_CANDIDATE_COUNT] =
            core::array::from_fn(spread);
        assert_eq!(
            contenders(&bands),
            [Out, Out, Out, Out, Again, Again, Again]
        );
        // A knee puts one candidate's bottom lowest, the lowest percentile stays.
        bands[1] = knee;
        bands[2] = knee;
        let expected = [Out, Again, TwinOf(1), Out, Out, Again, Again];
        assert_eq!(contenders(&bands), expected);
    }

    /// A frame with few samples is measured whole: each candidate's value is its
    /// 95th percentile over every front-lit sample, not over a subset.
    #[test]
    fn a_small_frame_is_measured_whole() {
        let (camera, street) = street_view(Vec3::new(0.05, -0.2, -1.0));
        let direction = Vec3::new(0.3, -1.0, -0.4);
        let light = Light::Directional { direction };
        let eye = street_samples(&camera, 48, 32, -40.0);
        assert!(eye.len() > AUTO_MAX_SAMPLES && eye.len() <= AUTO_CONFIRM_SAMPLES);
        let input = FitInput::new(&camera, &light, SceneBounds::whole(street), 512 * 512);
        let fitted = auto_candidates(&CascadePlan::default()).map(|t| fit(&t, &input).ok());
        let samples = Samples {
            most: AUTO_MAX_SAMPLES,
            unlit: Unlit::Skipped,
            ..Samples::new(&camera, 400.0, &eye)
        };
        let light = LightDirection::Directional(direction);
        let measured = measure(&fitted, &samples, light);
        let whole = Samples {
            most: AUTO_CONFIRM_SAMPLES,
            ..samples
        };
        for (shadow, value) in fitted.iter().zip(measured) {
            let shadow = shadow.as_ref().unwrap();
            let side = f64::from(shadow.layer_side);
            assert_eq!(value, sample_error(shadow, side, &whole, light, 0.95));
        }
    }

    /// With the eye samples, `auto` keeps the candidate whose aliasing error on
    /// them is the lowest, each candidate measured as the quality report measures
    /// (front-lit samples, the report's `m`); at the end of a street under a tall
    /// receivers' box the box's prediction alone picks one that is worse there.
    #[test]
    fn with_eye_samples_auto_keeps_the_candidate_finest_on_them() {
        let (camera, street) = street_view(Vec3::new(0.05, 0.05, -1.0));
        let direction = Vec3::new(0.0, -1.0, -0.2);
        let light = Light::Directional { direction };
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
