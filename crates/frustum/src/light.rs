use glam::{DVec3, Vec3};

use crate::{FrustumError, math};

/// A light source.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Light {
    /// Parallel rays, e.g. the sun.
    Directional {
        /// Direction the light travels (from the light toward the scene).
        direction: Vec3,
    },
    /// A cone of light.
    Spot {
        /// World position.
        position: Vec3,
        /// Axis of the cone, the direction the light travels.
        direction: Vec3,
        /// Half-angle of the cone in radians, in `(0, pi/2)`.
        half_angle: f32,
        /// Distance beyond which the light has no effect, positive.
        range: f32,
    },
    /// Light in every direction.
    Point {
        /// World position.
        position: Vec3,
        /// Distance beyond which the light has no effect, positive.
        range: f32,
    },
}

impl Light {
    /// Checks every field.
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`], [`FrustumError::ZeroDirection`],
    /// [`FrustumError::InvalidLight`] for a spot angle outside `(0, pi/2)` or a range
    /// outside `[1e-6, 1e15]` (the near plane, a fraction of the range, must stay a
    /// normal `f32`).
    pub fn validate(&self) -> Result<(), FrustumError> {
        match *self {
            Self::Directional { direction } => unit(direction).map(|_| ()),
            Self::Spot {
                position,
                direction,
                half_angle,
                range,
            } => {
                if !(position.is_finite() && half_angle.is_finite() && range.is_finite()) {
                    return Err(FrustumError::NonFinite);
                }
                unit(direction)?;
                let max = core::f32::consts::FRAC_PI_2 - 1e-4;
                if !(half_angle > 1e-5
                    && half_angle < max
                    && (MIN_RANGE..=MAX_RANGE).contains(&range))
                {
                    return Err(FrustumError::InvalidLight);
                }
                Ok(())
            }
            Self::Point { position, range } => {
                if !(position.is_finite() && range.is_finite()) {
                    return Err(FrustumError::NonFinite);
                }
                if (MIN_RANGE..=MAX_RANGE).contains(&range) {
                    Ok(())
                } else {
                    Err(FrustumError::InvalidLight)
                }
            }
        }
    }
}

/// Smallest accepted light range.
const MIN_RANGE: f32 = 1e-6;
/// Largest accepted light range.
const MAX_RANGE: f32 = 1e15;

/// The unit vector along `v` in `f64`.
pub(crate) fn unit(v: Vec3) -> Result<DVec3, FrustumError> {
    if !v.is_finite() {
        return Err(FrustumError::NonFinite);
    }
    // `DVec3::try_normalize`, with its reciprocal length tested in integer
    // comparisons ([`math::positive_finite`]) rather than a float classification.
    let d = v.as_dvec3();
    let rcp = 1.0 / d.length();
    let u = d * rcp;
    if math::positive_finite(rcp) && u.length_squared() > 0.5 {
        Ok(u)
    } else {
        Err(FrustumError::ZeroDirection)
    }
}

/// Rotation-only light frame looking along `direction` (light space looks down `-Z`).
///
/// `up_hint` orients the frame; when it is (nearly) parallel to the light, the world
/// axis least aligned with the light is used instead. This is the documented fallback
/// for "light parallel to the up vector": the frame stays well defined and depends
/// only on the light, so stable cascades stay stable.
///
/// # Errors
/// [`FrustumError::NonFinite`], [`FrustumError::ZeroDirection`].
pub fn directional_light_from_world(
    direction: Vec3,
    up_hint: Vec3,
) -> Result<glam::Mat4, FrustumError> {
    Ok(crate::projection::light_rotation(unit(direction)?, up_hint).as_mat4())
}
