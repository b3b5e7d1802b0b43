use core::fmt;

use shadowmap_frustum::FrustumError;

/// Why an operation of this crate refused its input.
///
/// Every public function documents which variants it returns. None of them panics,
/// and none returns a NaN instead of an error.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum RtwError {
    /// A map or table with zero width or zero height.
    EmptyMap,
    /// A map larger than [`MAX_MAP_SIDE`](crate::MAX_MAP_SIDE) on a side or
    /// [`MAX_MAP_CELLS`](crate::MAX_MAP_CELLS) in all.
    MapTooLarge,
    /// A sample or value had a NaN or infinite component.
    NonFinite,
    /// An importance value below zero.
    NegativeImportance,
    /// A slice whose length does not match the map (or the samples) it goes with.
    SizeMismatch {
        /// The length expected.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// The warp maps were created for a different importance-map size.
    ShapeMismatch,
    /// An option outside its documented range (blur radius, floor, temporal weight,
    /// importance knobs).
    InvalidOption,
    /// A cell index outside the map.
    OutOfBounds,
    /// The base transform (or the camera) cannot be used: non-finite or singular.
    Frustum(FrustumError),
}

impl fmt::Display for RtwError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::EmptyMap => f.write_str("importance map or warp table is empty"),
            Self::MapTooLarge => f.write_str("importance map is too large"),
            Self::NonFinite => f.write_str("input has a NaN or infinite component"),
            Self::NegativeImportance => f.write_str("importance is negative"),
            Self::SizeMismatch { expected, got } => {
                write!(
                    f,
                    "slice length {got} does not match the expected {expected}"
                )
            }
            Self::ShapeMismatch => {
                f.write_str("warp maps were created for a different importance-map size")
            }
            Self::InvalidOption => f.write_str("option outside its valid range"),
            Self::OutOfBounds => f.write_str("cell index outside the map"),
            Self::Frustum(e) => write!(f, "invalid transform or camera: {e}"),
        }
    }
}

impl core::error::Error for RtwError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Frustum(e) => Some(e),
            _ => None,
        }
    }
}

impl From<FrustumError> for RtwError {
    fn from(e: FrustumError) -> Self {
        Self::Frustum(e)
    }
}
