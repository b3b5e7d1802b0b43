use core::fmt;

use shadowmap_frustum::FrustumError;

/// Why a builder of this crate refused its input.
///
/// Every public builder documents which variants it returns. None of them panics,
/// and none returns a NaN instead of an error.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ParaboloidError {
    /// An error of `shadowmap-frustum` (invalid camera, light or slice).
    Frustum(FrustumError),
    /// An input had a NaN or infinite component.
    NonFinite,
    /// A direction (paraboloid axis) had (nearly) zero length.
    ZeroDirection,
    /// The light lies on (or within rounding of) a frustum border point, so the
    /// direction toward that point is undefined.
    LightOnFrustumPoint,
    /// The directions toward the frustum border points sum to (nearly) zero: the light
    /// sits at their centroid and the paper's averaged axis is undefined.
    DirectionsCancel,
    /// No cone with a half-angle under 90 degrees contains the directions (the
    /// origin lies in their convex hull: the light is inside the truncated frustum).
    NoConeUnder90,
    /// The truncated frustum has no extent (all border points coincide).
    DegenerateFrustum,
    /// The light's depth range is invalid: `near <= 0`, `far <= near`, or too thin for
    /// `f32` depth.
    InvalidDepthRange {
        /// The near distance given.
        near: f32,
        /// The far distance given.
        far: f32,
    },
    /// Measured depth bounds with `min > max` (a near hint beyond the far hint).
    InvalidDepthBounds {
        /// The minimum view depth given.
        min: f32,
        /// The maximum view depth given.
        max: f32,
    },
    /// No directions, or more than [`MAX_CONE_DIRECTIONS`](crate::MAX_CONE_DIRECTIONS).
    InvalidDirectionCount,
    /// An option out of range (negative or non-finite margin, a largest single
    /// half-angle outside `(0, pi/2]`, a non-positive near distance).
    InvalidOptions,
    /// A zoom (cut) factor outside `(0, 1]`, or a half-angle outside `(0, pi/2]`.
    InvalidZoom,
    /// A subdivision option out of range (tolerance not positive, resolution or
    /// segment limit zero or too large).
    InvalidSubdivision,
    /// A light kind the builder does not handle (directional lights: use a matrix
    /// technique of `shadowmap-warp` or `shadowmap-frustum`).
    UnsupportedLight,
}

impl From<FrustumError> for ParaboloidError {
    fn from(e: FrustumError) -> Self {
        Self::Frustum(e)
    }
}

impl fmt::Display for ParaboloidError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Frustum(e) => write!(f, "frustum: {e}"),
            Self::NonFinite => f.write_str("input has a NaN or infinite component"),
            Self::ZeroDirection => f.write_str("direction has zero length"),
            Self::LightOnFrustumPoint => f.write_str("light lies on a frustum border point"),
            Self::DirectionsCancel => {
                f.write_str("directions to the frustum border points sum to zero")
            }
            Self::NoConeUnder90 => f.write_str("no cone under 90 degrees contains the directions"),
            Self::DegenerateFrustum => f.write_str("truncated frustum has no extent"),
            Self::InvalidDepthRange { near, far } => {
                write!(f, "invalid light depth range: near = {near}, far = {far}")
            }
            Self::InvalidDepthBounds { min, max } => {
                write!(f, "depth bounds with min = {min} > max = {max}")
            }
            Self::InvalidDirectionCount => f.write_str("no directions, or too many"),
            Self::InvalidOptions => f.write_str("option out of range"),
            Self::InvalidZoom => f.write_str("zoom factor outside (0, 1]"),
            Self::InvalidSubdivision => f.write_str("subdivision option out of range"),
            Self::UnsupportedLight => f.write_str("light kind not supported by this builder"),
        }
    }
}

impl core::error::Error for ParaboloidError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Frustum(e) => Some(e),
            _ => None,
        }
    }
}
