//! The uniform focused fit: the orthographic baseline every warp is measured against
//! and degrades to.

use glam::Vec3;
use shadowmap_frustum::{Camera, ShadowTransform};

use crate::focus::FocusBody;
use crate::lispsm::warp_fit;
use crate::{SceneBounds, WarpError};

/// Options of [`uniform_focused`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[non_exhaustive]
pub struct UniformOptions {
    /// Depth 1 at the light's near plane and 0 at its far plane.
    pub reversed_z: bool,
}

impl Default for UniformOptions {
    fn default() -> Self {
        Self::new()
    }
}

impl UniformOptions {
    /// Standard depth.
    #[must_use]
    pub const fn new() -> Self {
        Self { reversed_z: false }
    }

    /// Sets [`reversed_z`](Self::reversed_z).
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }
}

/// Uniform focused shadow map of a directional light (the baseline every other
/// technique is compared with).
///
/// An orthographic projection in the light frame (see [`light_frame`](crate::light_frame))
/// fitted to frustum ∩ receivers, its near plane pulled back to the casters that can
/// shadow them (the body extruded toward the light, clipped by
/// `casters ∪ receivers`).
///
/// # Errors
/// [`WarpError::Frustum`] for an invalid camera; [`WarpError::NonFinite`],
/// [`WarpError::ZeroDirection`] for the light; [`WarpError::EmptyReceivers`],
/// [`WarpError::EmptyCasters`] for inverted boxes; [`WarpError::NoVisibleReceivers`]
/// when the receivers miss the frustum; [`WarpError::Degenerate`] when the `f32`
/// result would be singular or non-finite. A focus region of zero area (a point or
/// line of receivers) is widened (see the crate docs), not refused.
pub fn uniform_focused(
    camera: &Camera,
    light_direction: Vec3,
    scene: &SceneBounds,
    options: &UniformOptions,
) -> Result<ShadowTransform, WarpError> {
    FocusBody::fit_from(camera, light_direction, scene, |body| body.uniform(options))
}

impl FocusBody {
    /// The uniform focused fit of this body (see [`uniform_focused`]).
    ///
    /// # Errors
    /// [`WarpError::Degenerate`] when the `f32` result would be singular.
    pub fn uniform(&self, options: &UniformOptions) -> Result<ShadowTransform, WarpError> {
        warp_fit(&self.focus, &self.view, 0.0, options.reversed_z).map(|(t, _)| t)
    }
}
