use crate::{Camera, CascadeSplits, FrustumError, SplitScheme, ValidCamera};

/// View-depth bounds of the visible samples, measured by a min/max reduction of the
/// depth buffer (SDSM, Lauritzen et al. 2011; the truncated view frustum of IPSM).
///
/// Splitting `[min, max]` instead of `[near, far]` spends no texels on empty depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthBounds {
    /// Smallest visible view depth.
    pub min: f32,
    /// Largest visible view depth.
    pub max: f32,
}

impl DepthBounds {
    /// The bounds clamped into the camera's depth range.
    ///
    /// Documented fallbacks: a NaN bound is replaced by the camera's own; bounds that
    /// are inverted or thinner than `f32` can resolve (an empty reduction, a frame that
    /// sees only sky) give the camera's whole range, so a renderer never has to
    /// special-case them.
    ///
    /// # Errors
    /// Only errors of [`Camera::validate`].
    pub fn clamped_to(&self, camera: &Camera) -> Result<(f32, f32), FrustumError> {
        Ok(self.clamped_to_valid(&ValidCamera::new(camera)?))
    }

    /// As [`DepthBounds::clamped_to`] for a camera validated once per frame.
    #[must_use]
    pub fn clamped_to_valid(&self, camera: &ValidCamera) -> (f32, f32) {
        let (near, far) = camera.depth_range();
        let (lo, hi) = (self.min.max(near), self.max.min(far));
        let thin = !(hi - lo > 1e-5 * hi.abs().max(lo.abs()));
        if !(lo.is_finite() && hi.is_finite()) || thin {
            return (near, far);
        }
        (lo, hi)
    }
}

impl CascadeSplits {
    /// Splits the measured depth bounds (clamped to the camera, see
    /// [`DepthBounds::clamped_to`]) instead of the camera's whole range.
    ///
    /// # Errors
    /// As [`CascadeSplits::new`] and [`Camera::validate`].
    pub fn from_depth_bounds(
        scheme: &SplitScheme,
        count: usize,
        camera: &Camera,
        bounds: DepthBounds,
    ) -> Result<Self, FrustumError> {
        let (lo, hi) = bounds.clamped_to(camera)?;
        Self::new(scheme, count, lo, hi)
    }
}
