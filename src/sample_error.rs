//! The aliasing error a shadow mapping is predicted to leave on the eye's samples:
//! the quality report's measure, `m = 1 / s_min(J)` with `J` the screen-to-texel
//! Jacobian through the sample's surface, evaluated on (a regular subset of) the
//! samples instead of rendered pixels.

use arrayvec::ArrayVec;
use shadowmap_frustum::{Camera, FRONT_LIT_MIN_COS, LightDirection, ShadowMapping, math};
use shadowmap_rtw::{EyeSample, PixelSteps};

/// Most samples measured: larger sets are thinned to a regular subset (so the
/// measure needs no heap).
pub(crate) const MAX_SAMPLES: usize = 4096;

/// The surface a sample's error is measured on where the light does not reach it
/// from the front (`n . l` below `FRONT_LIT_MIN_COS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Unlit {
    /// Left out, as the quality report measures `m` (`auto`'s ranking).
    Skipped,
    /// The plane facing the bisector of the eye and light directions (a map's need
    /// there still matters to the fits that size or warp it).
    Bisector,
}

/// What [`sample_error`] measures: the samples, how many at most, and their image.
#[derive(Clone, Copy)]
pub(crate) struct Samples<'a> {
    pub(crate) camera: &'a Camera,
    pub(crate) pixels_per_radian: f32,
    pub(crate) samples: &'a [EyeSample],
    /// A regular subset of at most this many (at most [`MAX_SAMPLES`]).
    pub(crate) most: usize,
    pub(crate) unlit: Unlit,
}

impl<'a> Samples<'a> {
    /// Every sample (up to [`MAX_SAMPLES`]), the unlit ones on the bisector's plane.
    pub(crate) fn new(
        camera: &'a Camera,
        pixels_per_radian: f32,
        samples: &'a [EyeSample],
    ) -> Self {
        Self {
            camera,
            pixels_per_radian,
            samples,
            most: MAX_SAMPLES,
            unlit: Unlit::Bisector,
        }
    }
}

/// The `percentile` (in `(0, 1]`) of `m` over the samples `mapping` covers, each of
/// its layers having `texels` texels per side; `None` when it covers none. A sample's
/// surface is its own where the light reaches it from the front (`n . l` at least
/// `FRONT_LIT_MIN_COS`, as the report measures `m`); elsewhere as `samples.unlit`
/// says. A sample whose one-pixel neighbours fall outside the map or into another
/// layer is left out. The pixel steps are `shadowmap_rtw::PixelSteps`, the footprint
/// the RTW oracle uses; the texture coordinates' differences are the mapping's
/// [`uv_differentials`](ShadowMapping::uv_differentials) (the derivative of a matrix
/// technique's matrix).
pub(crate) fn sample_error(
    mapping: &dyn ShadowMapping,
    texels: f64,
    samples: &Samples<'_>,
    light: LightDirection,
    percentile: f64,
) -> Option<f64> {
    let probe = Probe {
        steps: PixelSteps::new(samples.camera),
        pixels_per_radian: f64::from(samples.pixels_per_radian),
        light,
        unlit: samples.unlit,
    };
    let most = samples.most.clamp(1, MAX_SAMPLES);
    let stride = samples.samples.len().div_ceil(most).max(1);
    let mut errors: ArrayVec<f64, MAX_SAMPLES> = samples
        .samples
        .iter()
        .step_by(stride)
        .filter_map(|s| probe.error(mapping, texels, s))
        .take(most)
        .collect();
    percentile_of(&mut errors, percentile)
}

/// What [`sample_error`] measures a sample with.
struct Probe {
    steps: PixelSteps,
    pixels_per_radian: f64,
    light: LightDirection,
    unlit: Unlit,
}

impl Probe {
    fn error(&self, mapping: &dyn ShadowMapping, texels: f64, s: &EyeSample) -> Option<f64> {
        let p = s.position.as_dvec3();
        let to_eye = -self.steps.ray(p)?;
        let to_light = self.light.toward(p);
        let n = s.normal.as_dvec3().normalize_or_zero();
        let n = if n.dot(to_light) >= FRONT_LIT_MIN_COS {
            n
        } else if self.unlit == Unlit::Skipped {
            return None;
        } else {
            (to_eye + to_light).normalize_or_zero()
        };
        // Half-pixel steps each way: the difference across one pixel, twice the
        // mapping's half-differences (an exact doubling).
        let (dx, dy) = self.steps.at(p, n, 2.0 * self.pixels_per_radian)?;
        let [jx, jy] = mapping.uv_differentials(p, &[p + dx, p - dx, p + dy, p - dy])?;
        let m = 1.0 / math::smaller_singular_value(jx * 2.0 * texels, jy * 2.0 * texels);
        (m.is_finite() && m > 0.0).then_some(m)
    }
}

/// The `percentile` of `values` (reordered), `None` when empty or not positive and
/// finite.
pub(crate) fn percentile_of(values: &mut [f64], percentile: f64) -> Option<f64> {
    let count = values.len();
    if count == 0 {
        return None;
    }
    let rank = ((percentile * count as f64).ceil() as usize).clamp(1, count) - 1;
    let (_, x, _) = values.select_nth_unstable_by(rank, f64::total_cmp);
    (x.is_finite() && *x > 0.0).then_some(*x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn sample(position: Vec3, normal: Vec3) -> EyeSample {
        EyeSample {
            position,
            normal,
            eye_distance: position.length(),
        }
    }

    /// The error scales with one over the map's side, leaves out what the eye cannot
    /// see, and still measures a surface the light does not reach (on the bisector's plane).
    #[test]
    fn the_error_follows_the_side_and_the_coverage() {
        let (camera, light, map) = crate::test_views::looking_down_at_the_ground();
        let lit = [sample(Vec3::new(0.0, 0.0, -10.0), Vec3::Y)];
        let error = |samples: &[EyeSample], side: f64| {
            let l = LightDirection::Directional(light);
            sample_error(&map, side, &Samples::new(&camera, 1e3, samples), l, 0.95)
        };
        let m = error(&lit, 1024.0).unwrap();
        assert!((error(&lit, 2048.0).unwrap() - 0.5 * m).abs() < 1e-9 * m);
        assert_eq!(error(&[], 1024.0), None);
        let behind_the_eye = [sample(Vec3::new(0.0, 0.0, 10.0), Vec3::Y)];
        assert_eq!(error(&behind_the_eye, 1024.0), None);
        let turned_away = [sample(Vec3::new(0.0, 0.0, -10.0), Vec3::NEG_Y)];
        assert!(error(&turned_away, 1024.0).is_some_and(f64::is_finite));
    }
}
