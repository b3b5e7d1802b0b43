//! The aliasing error a shadow mapping is predicted to leave on the eye's samples:
//! the quality report's measure, `m = 1 / s_min(J)` with `J` the screen-to-texel
//! Jacobian through the sample's surface, evaluated on (a regular subset of) the
//! samples instead of rendered pixels.

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3};
use shadowmap_frustum::{Camera, FRONT_LIT_MIN_COS, LightDirection, ShadowMapping, math};
use shadowmap_rtw::{EyeSample, PixelSteps};

/// Most samples measured: larger sets are thinned to a regular subset (so the
/// measure needs no heap).
pub(crate) const MAX_SAMPLES: usize = 4096;

/// The `percentile` (in `(0, 1]`) of `m` over the samples `mapping` covers, its
/// layer `l` having `side(l)` texels per side; `None` when it covers none. A sample's
/// surface is its own where the light reaches it from the front (`n . l` at least
/// `FRONT_LIT_MIN_COS`, as the report measures `m`), the plane facing the bisector
/// of the eye and light directions elsewhere; a sample whose one-pixel neighbours
/// fall outside the map or into another layer is left out. The pixel steps are
/// `shadowmap_rtw::PixelSteps`, the footprint the RTW oracle uses.
pub(crate) fn sample_error(
    mapping: &dyn ShadowMapping,
    side: &dyn Fn(u32) -> f64,
    camera: &Camera,
    pixels_per_radian: f32,
    samples: &[EyeSample],
    light: LightDirection,
    percentile: f64,
) -> Option<f64> {
    let probe = Probe {
        steps: PixelSteps::new(camera),
        pixels_per_radian: f64::from(pixels_per_radian),
        light,
    };
    let stride = samples.len().div_ceil(MAX_SAMPLES).max(1);
    let mut errors: ArrayVec<f64, MAX_SAMPLES> = samples
        .iter()
        .step_by(stride)
        .filter_map(|s| probe.error(mapping, side, s))
        .take(MAX_SAMPLES)
        .collect();
    percentile_of(&mut errors, percentile)
}

/// What [`sample_error`] measures a sample with.
struct Probe {
    steps: PixelSteps,
    pixels_per_radian: f64,
    light: LightDirection,
}

impl Probe {
    fn error(
        &self,
        mapping: &dyn ShadowMapping,
        side: &dyn Fn(u32) -> f64,
        s: &EyeSample,
    ) -> Option<f64> {
        let p = s.position.as_dvec3();
        let to_eye = -self.steps.ray(p)?;
        let to_light = self.light.toward(p);
        let n = s.normal.as_dvec3().normalize_or_zero();
        let n = if n.dot(to_light) >= FRONT_LIT_MIN_COS {
            n
        } else {
            (to_eye + to_light).normalize_or_zero()
        };
        // Half-pixel steps each way: the central difference of one pixel.
        let (dx, dy) = self.steps.at(p, n, 2.0 * self.pixels_per_radian)?;
        let centre = mapping.map_point(p)?;
        let texels = side(centre.layer);
        let column = |d: DVec3| -> Option<DVec2> {
            let (a, b) = (mapping.map_point(p + d)?, mapping.map_point(p - d)?);
            (a.layer == centre.layer && b.layer == centre.layer).then(|| (a.uv - b.uv) * texels)
        };
        let (jx, jy) = (column(dx)?, column(dy)?);
        let m = 1.0 / math::smaller_singular_value(jx, jy);
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
            sample_error(&map, &|_| side, &camera, 1e3, samples, l, 0.95)
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
