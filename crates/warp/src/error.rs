use core::fmt;

use shadowmap_frustum::FrustumError;

/// Why a builder of this crate refused its input.
///
/// Every builder documents which variants it returns. None of them panics, and none
/// returns a NaN or a singular matrix instead of an error.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum WarpError {
    /// The camera (or a slice of it) was rejected by `shadowmap-frustum`.
    Frustum(FrustumError),
    /// The light direction or a scene box had a NaN or infinite component.
    NonFinite,
    /// The light direction had (nearly) zero length.
    ZeroDirection,
    /// The receiver box is inverted (`min > max` on some axis).
    EmptyReceivers,
    /// The caster box is inverted (`min > max` on some axis).
    EmptyCasters,
    /// The receivers do not meet the view frustum: nothing visible needs a shadow.
    NoVisibleReceivers,
    /// XPSM only: the casters' and receivers' boxes do not overlap in post-projective
    /// light space, so no visible receiver can be shadowed.
    EmptyFocusRegion,
    /// An option is out of range (see the option's documentation).
    InvalidOption,
    /// The slice list of a warped-cascade fit is empty or does not match the
    /// strengths given.
    InvalidCascades,
    /// The input is so extreme (magnitudes near the `f32` limits) that the resulting
    /// `f32` matrix would be non-finite or singular.
    Degenerate,
}

impl From<FrustumError> for WarpError {
    fn from(e: FrustumError) -> Self {
        Self::Frustum(e)
    }
}

impl fmt::Display for WarpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Frustum(e) => write!(f, "invalid camera: {e}"),
            Self::NonFinite => f.write_str("input has a NaN or infinite component"),
            Self::ZeroDirection => f.write_str("light direction has zero length"),
            Self::EmptyReceivers => f.write_str("receiver box is inverted"),
            Self::EmptyCasters => f.write_str("caster box is inverted"),
            Self::NoVisibleReceivers => f.write_str("receivers do not meet the view frustum"),
            Self::EmptyFocusRegion => {
                f.write_str("caster and receiver boxes do not overlap in light space")
            }
            Self::InvalidOption => f.write_str("option out of range"),
            Self::InvalidCascades => f.write_str("invalid cascade slices or strengths"),
            Self::Degenerate => f.write_str("input too extreme for a finite f32 matrix"),
        }
    }
}

impl core::error::Error for WarpError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Frustum(e) => Some(e),
            _ => None,
        }
    }
}
