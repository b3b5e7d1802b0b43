//! The oracle's requirement of one eye sample: the texel density it needs along each
//! axis of a base map, from the screen-to-texture Jacobian through its surface.

use glam::{DVec2, DVec3};
use shadowmap_frustum::{Camera, FRONT_LIT_MIN_COS, ShadowTransform, math};

use super::{Base, EyeSample, check_samples};
use crate::RtwError;

/// What one eye sample needs of a base map: where it falls, and the texels per unit
/// of base `u` and `v` that keep its texels at most one pixel long (see
/// [`ImportanceMap::accumulate_oracle_axis`](super::ImportanceMap::accumulate_oracle_axis)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisNeed {
    /// Base texture coordinates.
    pub uv: DVec2,
    /// Pixels per unit of base `u`: `|J⁻¹ e_u|`.
    pub u: f64,
    /// Pixels per unit of base `v`: `|J⁻¹ e_v|`.
    pub v: f64,
    /// Both axes at once: `1 / s_min(J)`.
    pub isotropic: f64,
}

/// Calls `each(index, need)` for every sample the base maps (in front of a
/// perspective base, in front of the eye) whose Jacobian is regular, and returns how
/// many samples it skipped. A zero normal uses the bisector of the eye and light
/// directions (the perspective-only measure), and so does a surface the light does
/// not reach from the front (`n . l` below `FRONT_LIT_MIN_COS`): shading darkens it
/// whatever the map holds, and its true-normal requirement grows without bound as
/// the light grazes it. Samples seen edge-on (`|n . ray| < 1e-6`) are skipped.
///
/// # Errors
/// [`RtwError::NonFinite`] for non-finite samples or transform;
/// [`RtwError::InvalidOption`] for a `pixels_per_radian` that is not positive and
/// finite; [`RtwError::Frustum`] for an invalid camera. Nothing is called on error.
pub fn oracle_needs(
    base: &ShadowTransform,
    camera: &Camera,
    pixels_per_radian: f32,
    samples: &[EyeSample],
    each: impl FnMut(usize, AxisNeed),
) -> Result<usize, RtwError> {
    // Every sample checked before any is measured: nothing is called on error.
    check_samples(samples)?;
    oracle_needs_where(base, camera, pixels_per_radian, samples, |_, _| true, each)
}

/// [`oracle_needs`] of the samples for which `keep(index, sample)` holds, the others
/// neither computed nor counted as skipped: for a caller that uses a subset (every
/// k-th sample, the samples one cube face stores) and would otherwise pay for the
/// need of every sample and throw most away. No allocation.
///
/// # Errors
/// As [`oracle_needs`], for the kept samples ([`RtwError::NonFinite`] when one is not
/// finite; nothing is called after it).
pub fn oracle_needs_where(
    base: &ShadowTransform,
    camera: &Camera,
    pixels_per_radian: f32,
    samples: &[EyeSample],
    mut keep: impl FnMut(usize, &EyeSample) -> bool,
    each: impl FnMut(usize, AxisNeed),
) -> Result<usize, RtwError> {
    let kept = samples.iter().enumerate().filter(|(i, s)| keep(*i, s));
    oracle_needs_of(base, camera, pixels_per_radian, kept, each)
}

/// [`oracle_needs`] of the samples a caller has already picked, each with the index
/// `each` is given: for a subset known without looking at every sample (every k-th
/// sample of those one cube face stores, its faces found once), which
/// [`oracle_needs_where`] would find by testing them all. No allocation.
///
/// # Errors
/// As [`oracle_needs_where`].
pub fn oracle_needs_of<'a>(
    base: &ShadowTransform,
    camera: &Camera,
    pixels_per_radian: f32,
    samples: impl IntoIterator<Item = (usize, &'a EyeSample)>,
    mut each: impl FnMut(usize, AxisNeed),
) -> Result<usize, RtwError> {
    if !(pixels_per_radian.is_finite() && pixels_per_radian > 0.0) {
        return Err(RtwError::InvalidOption);
    }
    camera.validate()?;
    let base = Base::new(base)?;
    let view = View::new(camera, pixels_per_radian);
    let mut skipped = 0;
    for (i, s) in samples {
        check_samples(core::slice::from_ref(s))?;
        match view.need(&base, s) {
            Some(need) => each(i, need),
            None => skipped += 1,
        }
    }
    Ok(skipped)
}

/// A camera's pixel geometry: the world extent of one pixel on a surface, the
/// pixel footprint of Lloyd et al.'s aliasing error (used by the oracle, and by
/// whoever measures a warp on the eye samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelSteps {
    eye: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
}

impl PixelSteps {
    /// The pixel geometry of `camera` (its eye and axes).
    #[must_use]
    pub fn new(camera: &Camera) -> Self {
        let axis = |v: glam::Vec4| v.truncate().as_dvec3().normalize_or_zero();
        Self {
            eye: camera.eye().as_dvec3(),
            forward: camera.forward().as_dvec3(),
            right: axis(camera.world_from_view.x_axis),
            up: axis(camera.world_from_view.y_axis),
        }
    }

    /// The unit view ray from the eye to `p`, `None` at the eye.
    #[must_use]
    pub fn ray(&self, p: DVec3) -> Option<DVec3> {
        (p - self.eye).try_normalize()
    }

    /// The world displacements of one pixel step along the image's x and y at the
    /// surface point `p` with unit normal `n`, for `pixels_per_radian`: the steps
    /// at `p`'s view depth `z` (`z / pixels_per_radian` along the camera's right and
    /// up), carried along the view ray onto the surface's plane. `None` for a point
    /// at or behind the eye, or a plane seen edge-on.
    #[must_use]
    pub fn at(&self, p: DVec3, n: DVec3, pixels_per_radian: f64) -> Option<(DVec3, DVec3)> {
        let ray = self.ray(p)?;
        let z = (p - self.eye).dot(self.forward);
        let nr = n.dot(ray);
        if !(z > 0.0) || n == DVec3::ZERO || !(nr.abs() >= 1e-6) {
            return None;
        }
        let on_plane = |d: DVec3| d - ray * (n.dot(d) / nr);
        let step = z / pixels_per_radian;
        Some((on_plane(self.right * step), on_plane(self.up * step)))
    }
}

/// A camera's pixel steps at a given angular pixel size: the oracle's view.
struct View {
    steps: PixelSteps,
    pixels_per_radian: f64,
}

impl View {
    fn new(camera: &Camera, pixels_per_radian: f32) -> Self {
        Self {
            steps: PixelSteps::new(camera),
            pixels_per_radian: f64::from(pixels_per_radian),
        }
    }

    fn need(&self, base: &Base, s: &EyeSample) -> Option<AxisNeed> {
        let p = s.position.as_dvec3();
        let (uv, h) = base.project(p)?;
        let ray = self.steps.ray(p)?;
        let toward_light = base.toward_light(p);
        let mut n = s.normal.as_dvec3().normalize_or_zero();
        if n.dot(toward_light.normalize_or_zero()) < FRONT_LIT_MIN_COS {
            n = (toward_light - ray).normalize_or_zero();
        }
        let (dx, dy) = self.steps.at(p, n, self.pixels_per_radian)?;
        let (ju, jv) = base.jacobian(h);
        let (a, b, c, d) = (ju.dot(dx), ju.dot(dy), jv.dot(dx), jv.dot(dy));
        // J⁻¹ = [[d, -b], [-c, a]] / det: its columns are the pixel extents of a
        // unit step in u and in v.
        let det = (a * d - b * c).abs();
        let s_min = math::smaller_singular_value(DVec2::new(a, c), DVec2::new(b, d));
        let need = AxisNeed {
            uv,
            u: math::sqrt(d * d + c * c) / det,
            v: math::sqrt(b * b + a * a) / det,
            isotropic: 1.0 / s_min,
        };
        let ok = [need.u, need.v, need.isotropic]
            .iter()
            .all(|q| q.is_finite() && *q > 0.0);
        ok.then_some(need)
    }
}
