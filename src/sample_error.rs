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
/// says. Where one neighbour half a pixel away along an image axis falls outside
/// the map or into another layer, the difference to the other one is taken
/// ([`differentials`]); a sample with neither is left out. The pixel steps are
/// `shadowmap_rtw::PixelSteps`, the footprint the RTW oracle uses; the texture
/// coordinates' differences are the mapping's
/// [`uv_differentials`](ShadowMapping::uv_differentials) (the derivative of a matrix
/// technique's matrix).
pub(crate) fn sample_error(
    mapping: &dyn ShadowMapping,
    texels: f64,
    samples: &Samples<'_>,
    light: LightDirection,
    percentile: f64,
) -> Option<f64> {
    let mut errors = ArrayVec::new();
    sample_errors(mapping, texels, samples, light, &mut errors);
    percentile_of(&mut errors, percentile)
}

/// The errors `m` that [`sample_error`] takes its percentile of, into `errors`
/// (cleared first): one per sample `mapping` covers, in the samples' order.
pub(crate) fn sample_errors(
    mapping: &dyn ShadowMapping,
    texels: f64,
    samples: &Samples<'_>,
    light: LightDirection,
    errors: &mut ArrayVec<f64, MAX_SAMPLES>,
) {
    let probe = Probe {
        steps: PixelSteps::new(samples.camera),
        pixels_per_radian: f64::from(samples.pixels_per_radian),
        light,
        unlit: samples.unlit,
    };
    let most = samples.most.clamp(1, MAX_SAMPLES);
    let stride = samples.samples.len().div_ceil(most).max(1);
    errors.clear();
    errors.extend(
        samples
            .samples
            .iter()
            .step_by(stride)
            .filter_map(|s| probe.error(mapping, texels, s))
            .take(most),
    );
}

/// Whether the `percentile` of the population `errors` were drawn from lies at or
/// below `threshold` beyond the sampling noise of the count above it: at most a
/// share `1 - percentile` of the errors exceed it by one standard deviation of that
/// count (`sqrt(n p (1 - p))`, binomial) or more. Where a candidate's errors have a
/// knee near the percentile (a few percent of the pixels, a wall seen at a grazing
/// angle, far coarser than the rest), a subset's percentile lands on either side of
/// the knee by chance; a choice made on it is then a coin toss, and this says so.
pub(crate) fn confidently_at_most(errors: &[f64], threshold: f64, percentile: f64) -> bool {
    let n = errors.len() as f64;
    let above = errors.iter().filter(|e| **e > threshold).count() as f64;
    let tail = 1.0 - percentile;
    n > 0.0 && above <= n * tail - math::sqrt(n * tail * percentile)
}

/// A percentile measured on a subset, with the values at the ranks one binomial
/// standard deviation below and above its own (`sqrt(n p (1 - p))` ranks): where
/// the errors have a knee near the percentile, `low` and `high` lie far apart, and
/// a subset's `value` may sit on either side of the knee by chance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PercentileBand {
    pub(crate) low: f64,
    pub(crate) value: f64,
    pub(crate) high: f64,
}

/// The half-differences of `mapping`'s texture coordinates across the steps `dx`
/// and `dy` at `p`: central where `p ± dx` and `p ± dy` fall in `p`'s layer, else,
/// along an axis whose one neighbour falls in another layer (a sample beside a
/// paraboloid map's seam or a cube map's edge), the one-sided difference to the
/// other neighbour, as the quality report differentiates there. Leaving such
/// samples out drops the rim of a dual paraboloid map, its densest texels, from
/// every measure of a map whose seam crosses the view.
fn differentials(
    mapping: &dyn ShadowMapping,
    p: DVec3,
    dx: DVec3,
    dy: DVec3,
) -> Option<[DVec2; 2]> {
    if let Some(j) = mapping.uv_differentials(p, &[p + dx, p - dx, p + dy, p - dy]) {
        return Some(j);
    }
    let layer = mapping.map_point(p)?.layer;
    let same = |q: DVec3| mapping.map_point(q).is_some_and(|s| s.layer == layer);
    // Each axis's pair (a one-sided pair spans half the central pair's step).
    let pair = |d: DVec3| match (same(p + d), same(p - d)) {
        (true, true) => Some((p + d, p - d, 1.0)),
        (true, false) => Some((p + d, p, 2.0)),
        (false, true) => Some((p, p - d, 2.0)),
        (false, false) => None,
    };
    let (x0, x1, sx) = pair(dx)?;
    let (y0, y1, sy) = pair(dy)?;
    let [jx, jy] = mapping.uv_differentials(p, &[x0, x1, y0, y1])?;
    Some([jx * sx, jy * sy])
}

/// The `percentile` of `values` (reordered) with its band ([`PercentileBand`]),
/// `None` where [`percentile_of`] is.
pub(crate) fn percentile_band(values: &mut [f64], percentile: f64) -> Option<PercentileBand> {
    let n = values.len() as f64;
    let spread = math::sqrt(percentile * (1.0 - percentile) / n.max(1.0));
    let value = percentile_of(values, percentile)?;
    let low = percentile_of(values, (percentile - spread).max(0.0)).unwrap_or(value);
    let high = percentile_of(values, (percentile + spread).min(1.0)).unwrap_or(value);
    Some(PercentileBand { low, value, high })
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
        let [jx, jy] = differentials(mapping, p, dx, dy)?;
        let m = 1.0 / math::smaller_singular_value(jx * 2.0 * texels, jy * 2.0 * texels);
        (m.is_finite() && m > 0.0).then_some(m)
    }
}

/// The `percentile` of `values` (reordered), `None` when empty or not positive and
/// finite.
pub(crate) fn percentile_of(values: &mut [f64], percentile: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let rank = percentile_rank(values.len(), percentile);
    let (_, x, _) = values.select_nth_unstable_by(rank, f64::total_cmp);
    (x.is_finite() && *x > 0.0).then_some(*x)
}

/// The index, in ascending order, of the `percentile` of `count > 0` values: the
/// smallest value with at least that share of the values at or below it.
pub(crate) fn percentile_rank(count: usize, percentile: f64) -> usize {
    ((percentile * count as f64).ceil() as usize).clamp(1, count.max(1)) - 1
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

    /// A sample beside a dual paraboloid map's seam, whose neighbour half a pixel
    /// below lies in the other layer, is measured with the one-sided difference (as
    /// the quality report measures it), and its error continues that of a sample
    /// a dozen pixels from the seam. Left out, the rim of a dual map, its densest
    /// texels, dropped out of every measure of a map whose seam crosses the view.
    #[test]
    fn a_sample_beside_a_seam_is_measured_one_sided() {
        use shadowmap_frustum::Projection;
        use shadowmap_paraboloid::{MapOptions, ParaboloidMap};
        let map = ParaboloidMap::dual(Vec3::ZERO, Vec3::NEG_Y, 0.1, 100.0, &MapOptions::default())
            .unwrap();
        let camera = Camera::look_to(
            Vec3::new(0.0, 0.5, 5.0),
            Vec3::NEG_Z,
            Vec3::Y,
            Projection::perspective(1.0, 1.0, 0.1, 100.0),
        )
        .unwrap();
        let light = LightDirection::Position(Vec3::ZERO);
        // A wall facing the light; one pixel there spans 15 mm.
        let error = |y: f32| {
            let wall = [sample(Vec3::new(0.3, y, -10.0), Vec3::Z)];
            sample_error(&map, 512.0, &Samples::new(&camera, 1e3, &wall), light, 0.95)
        };
        let beside = error(1e-4).expect("a sample beside the seam is measured");
        let away = error(0.2).unwrap();
        assert!(
            (beside / away - 1.0).abs() < 0.05,
            "{beside} against {away}"
        );
    }

    /// A percentile below a threshold by a clear share of the samples is confident;
    /// one whose count above it is within the count's noise of the percentile's
    /// share is not, though the sample's own percentile lies below it (the knee of
    /// a subset of 239 samples, ten of them coarse).
    #[test]
    fn confidence_needs_the_count_above_the_threshold_clear_of_its_noise() {
        let knee = |coarse: usize| -> Vec<f64> {
            (0..239)
                .map(|i| {
                    if i < coarse {
                        6.0
                    } else {
                        3.0 + i as f64 * 1e-3
                    }
                })
                .collect()
        };
        let mut ten = knee(10);
        // 10 of 239 above 4.0: the sample's 95th percentile is below it...
        assert!(percentile_of(&mut ten, 0.95).unwrap() < 4.0);
        // ... but 10 is within one standard deviation (3.4) of 5% (12).
        assert!(!confidently_at_most(&ten, 4.0, 0.95));
        // Two above it are clear of the noise; none at all, of course.
        assert!(confidently_at_most(&knee(2), 4.0, 0.95));
        assert!(confidently_at_most(&knee(0), 4.0, 0.95));
        // Past the threshold, or with no samples: not at most.
        assert!(!confidently_at_most(&knee(0), 2.0, 0.95));
        assert!(!confidently_at_most(&[], 4.0, 0.95));
    }
}
