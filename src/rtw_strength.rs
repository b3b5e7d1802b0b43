//! The strength of RTW's warp over its base (a directional light's uniform fit, a
//! spot light's perspective fit), measured at the eye samples it was built from.

use shadowmap_frustum::{Camera, LightDirection, ShadowMapping, ShadowTransform};
use shadowmap_rtw::{EyeSample, ImportanceMap, RtwShadow, WarpMaps, WarpOptions};

use crate::fit::FitError;
use crate::sample_error::{Samples, sample_error};

/// Strengths tried, as exponents of the importance (0: the uniform fit, 1: the
/// importance as accumulated).
const STRENGTHS: [f32; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];

/// The angular size of a pixel the measure assumes: any, since it scales every
/// strength's error alike and only their ranking is used.
const PIXELS_PER_RADIAN: f32 = 1e3;

/// Builds `warps` from `importance` raised to the strength of least measured error.
///
/// Backward analysis models the texel density each sample needs (`1 / d` and an
/// orientation term); where the model is off (a room seen along the light: a floor
/// lit and seen at the same grazing angle needs no more texels than a wall facing
/// both, yet the orientation term asks for 1.7 times more) the full warp can starve
/// what the eye sees and lose to the uniform fit it warps. The eye samples are at
/// hand, so the warp is measured on them instead of trusted: for each strength `t`
/// in [`STRENGTHS`] (importance`^t`, `t = 0` the uniform fit), the 95th percentile
/// over the front-lit samples of the aliasing error `m = 1 / s_min(J)` (Lloyd et
/// al.'s measure: `J` maps one pixel step on the sample's tangent plane to shadow
/// texels; the pixel's angular size is a constant factor that does not change the
/// ranking) is taken, and the strength of the smallest wins (the strongest on ties).
/// So RTW is never worse than its base on the samples it was given.
///
/// # Errors
/// The warp builder's errors.
pub(crate) fn build_measured(
    base: &ShadowTransform,
    importance: &ImportanceMap,
    samples: &[EyeSample],
    camera: &Camera,
    light: LightDirection,
    options: &WarpOptions,
    warps: &mut WarpMaps,
) -> Result<(), FitError> {
    let measure = |warps: &WarpMaps| {
        let mapping = RtwShadow { base: *base, warps };
        warped_error(&mapping, samples, camera, light)
    };
    build_measured_by(importance, None, options, warps, measure)
}

/// The measure [`build_measured`] ranks strengths by: the 95th percentile of `m`
/// over the samples `mapping` covers, infinite where it covers none.
pub(crate) fn warped_error(
    mapping: &dyn ShadowMapping,
    samples: &[EyeSample],
    camera: &Camera,
    light: LightDirection,
) -> f64 {
    sample_error(
        mapping,
        1.0,
        &Samples::new(camera, PIXELS_PER_RADIAN, samples),
        light,
        0.95,
    )
    .unwrap_or(f64::INFINITY)
}

/// Builds `warps` from `importance`, or from `alternative` where one is given,
/// raised to the strength in [`STRENGTHS`] whose warps `measure` finds the least
/// error (the strongest on ties, `importance` on ties of both; `importance`'s full
/// warp where nothing measures finite): [`build_measured`] over any base, a
/// paraboloid side's included, with a choice between two importance maps where the
/// samples to accumulate are open to question.
///
/// # Errors
/// The warp builder's errors.
pub(crate) fn build_measured_by(
    importance: &ImportanceMap,
    alternative: Option<&ImportanceMap>,
    options: &WarpOptions,
    warps: &mut WarpMaps,
    measure: impl Fn(&WarpMaps) -> f64,
) -> Result<(), FitError> {
    let mut raised = ImportanceMap::new(importance.width(), importance.height())?;
    let candidates = [Some(importance), alternative];
    let mut best: Option<(f64, usize, f32)> = None;
    for (c, map) in candidates.iter().enumerate() {
        let Some(map) = map else { continue };
        for t in STRENGTHS {
            raise(map, t, &mut raised)?;
            warps.build(&raised, options)?;
            let error = measure(warps);
            if best.is_none_or(|(e, b, _)| error < e || (error == e && c == b)) {
                best = Some((error, c, t));
            }
        }
    }
    let (map, t) = match best {
        Some((e, 1, t)) if e.is_finite() => (alternative.unwrap_or(importance), t),
        Some((e, _, t)) if e.is_finite() => (importance, t),
        _ => (importance, 1.0),
    };
    raise(map, t, &mut raised)?;
    warps.build(&raised, options)?;
    Ok(())
}

/// `out` = `map` with every cell raised to the power `t`; `t = 0` gives every cell
/// 1, the identity warp (the uniform fit).
fn raise(map: &ImportanceMap, t: f32, out: &mut ImportanceMap) -> Result<(), FitError> {
    let width = map.width();
    for (i, v) in map.as_slice().iter().enumerate() {
        let (x, y) = ((i as u32) % width, (i as u32) / width);
        let value = if t == 0.0 {
            1.0
        } else if *v > 0.0 {
            v.powf(t)
        } else {
            0.0
        };
        out.set(x, y, value)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use glam::Vec3;

    /// A camera 10 m over a ground plane looking down at 45°, the sun straight down,
    /// and the eye samples of a grid of ground points it sees.
    fn ground() -> (Camera, Vec3, ShadowTransform, Vec<EyeSample>) {
        let (camera, light, base) = crate::test_views::looking_down_at_the_ground();
        let mut samples = Vec::new();
        for i in 0..40 {
            for j in 0..40 {
                let p = Vec3::new(-10.0 + 0.5 * i as f32, 0.0, -2.0 - 0.5 * j as f32);
                samples.push(EyeSample {
                    position: p,
                    normal: Vec3::Y,
                    eye_distance: (p - camera.eye()).length(),
                });
            }
        }
        (camera, light, base, samples)
    }

    /// The measure `build_measured` ranks strengths by.
    fn measured(camera: &Camera, light: Vec3, samples: &[EyeSample], m: &RtwShadow<'_>) -> f64 {
        let light = LightDirection::Directional(light);
        let samples = Samples::new(camera, PIXELS_PER_RADIAN, samples);
        sample_error(m, 1.0, &samples, light, 0.95).unwrap_or(f64::INFINITY)
    }

    #[test]
    fn the_measured_warp_is_never_worse_than_the_uniform_fit_on_the_samples() {
        let (camera, light, base, samples) = ground();
        let options = WarpOptions::default();
        let mut identity = WarpMaps::new(64, 64).unwrap();
        let mut ones = ImportanceMap::new(64, 64).unwrap();
        raise(&ImportanceMap::new(64, 64).unwrap(), 0.0, &mut ones).unwrap();
        identity.build(&ones, &options).unwrap();
        let warps = &identity;
        let uniform = measured(&camera, light, &samples, &RtwShadow { base, warps });
        assert!(uniform.is_finite());
        // Importance in one corner cell, where no sample is: the full warp spends the
        // map there; the measured one must not.
        let mut spike = ImportanceMap::new(64, 64).unwrap();
        spike.set(0, 0, 100.0).unwrap();
        spike.set(63, 63, 1e-3).unwrap();
        let mut full = WarpMaps::new(64, 64).unwrap();
        full.build(&spike, &options).unwrap();
        let warps = &full;
        let starved = measured(&camera, light, &samples, &RtwShadow { base, warps });
        assert!(starved > 1.5 * uniform, "{starved} vs {uniform}");
        let mut chosen = WarpMaps::new(64, 64).unwrap();
        build_measured(
            &base,
            &spike,
            &samples,
            &camera,
            LightDirection::Directional(light),
            &options,
            &mut chosen,
        )
        .unwrap();
        let warps = &chosen;
        let chosen = measured(&camera, light, &samples, &RtwShadow { base, warps });
        assert!(chosen <= uniform * (1.0 + 1e-9), "{chosen} vs {uniform}");
    }

    #[test]
    fn without_samples_the_full_warp_is_kept() {
        let (camera, light, base, samples) = ground();
        let options = WarpOptions::default();
        let mut importance = ImportanceMap::new(64, 64).unwrap();
        importance
            .accumulate_backward(&base, &samples, None, &Default::default())
            .unwrap();
        let (mut full, mut chosen) = (
            WarpMaps::new(64, 64).unwrap(),
            WarpMaps::new(64, 64).unwrap(),
        );
        full.build(&importance, &options).unwrap();
        build_measured(
            &base,
            &importance,
            &[],
            &camera,
            LightDirection::Directional(light),
            &options,
            &mut chosen,
        )
        .unwrap();
        assert_eq!(full.x_table(), chosen.x_table());
        assert_eq!(full.y_table(), chosen.y_table());
    }
}
