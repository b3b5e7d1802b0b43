use core::fmt;

/// Why a builder of this crate refused its input.
///
/// Every public builder documents which variants it returns. None of them panics,
/// and none returns a NaN or a singular matrix instead of an error.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum FrustumError {
    /// An input had a NaN or infinite component.
    NonFinite,
    /// A direction (view, light, up) had (nearly) zero length.
    ZeroDirection,
    /// The up vector is parallel to the view direction, so no view frame exists.
    UpParallelToView,
    /// `near <= 0`, `far <= near`, or the range is too thin to resolve in `f32`.
    InvalidDepthRange {
        /// The near distance given.
        near: f32,
        /// The far distance given.
        far: f32,
    },
    /// A vertical field of view outside `(0, pi)`.
    InvalidFov,
    /// An aspect ratio that is not positive and finite.
    InvalidAspect,
    /// A projection matrix that is singular or does not look down `-Z`.
    InvalidProjection,
    /// A bounding box with `min > max` on some axis, or with no volume where one is needed.
    EmptyBounds,
    /// The slice does not meet the scene (receiver) bounds.
    SliceOutsideScene,
    /// A cascade count of zero or above [`MAX_CASCADES`](crate::MAX_CASCADES).
    InvalidCascadeCount,
    /// A split parameter outside its range (lambda outside `[0, 1]`, overlap outside `[0, 1)`).
    InvalidSplitParameter,
    /// Custom split depths that are not strictly increasing inside `(near, far)`.
    InvalidCustomSplits,
    /// A shadow-map resolution of zero or above 65536.
    InvalidResolution,
    /// A spot cone angle outside `(0, pi/2)` or a non-positive range.
    InvalidLight,
    /// The light lies inside (or on) the region it must cover, so no projection
    /// from its position can see all of it.
    LightInsideRegion,
    /// The frustum (or slice) has no volume at `f32` precision: it is too small for its
    /// distance from the world origin, or its corners are coplanar.
    DegenerateFrustum,
    /// A light kind the builder does not handle (for example a point light given to
    /// the directional cascade fit).
    UnsupportedLight,
}

impl fmt::Display for FrustumError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite => f.write_str("input has a NaN or infinite component"),
            Self::ZeroDirection => f.write_str("direction has zero length"),
            Self::UpParallelToView => f.write_str("up vector is parallel to the view direction"),
            Self::InvalidDepthRange { near, far } => {
                write!(f, "invalid depth range: near = {near}, far = {far}")
            }
            Self::InvalidFov => f.write_str("field of view outside (0, pi)"),
            Self::InvalidAspect => f.write_str("aspect ratio is not positive and finite"),
            Self::InvalidProjection => {
                f.write_str("projection is singular or does not look down -Z")
            }
            Self::EmptyBounds => f.write_str("bounding box is empty or inverted"),
            Self::SliceOutsideScene => f.write_str("slice does not intersect the scene bounds"),
            Self::InvalidCascadeCount => f.write_str("cascade count is zero or too large"),
            Self::InvalidSplitParameter => f.write_str("split parameter out of range"),
            Self::InvalidCustomSplits => {
                f.write_str("custom split depths are not increasing inside (near, far)")
            }
            Self::InvalidResolution => f.write_str("shadow-map resolution is zero or too large"),
            Self::InvalidLight => f.write_str("light parameters out of range"),
            Self::LightInsideRegion => f.write_str("light lies inside the region to cover"),
            Self::DegenerateFrustum => f.write_str("frustum has no volume at f32 precision"),
            Self::UnsupportedLight => f.write_str("light kind not supported by this builder"),
        }
    }
}

impl core::error::Error for FrustumError {}
