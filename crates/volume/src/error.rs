use core::fmt;

use glam::Vec3;
use shadowmap_frustum::FrustumError;

/// Why a function of this crate refused its input.
///
/// Nothing in this crate panics on bad input or returns a NaN or singular matrix
/// instead of one of these.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum VolumeError {
    /// A vertex position had a NaN or infinite component.
    NonFinite {
        /// Index of the first such vertex.
        vertex: usize,
    },
    /// A triangle indexed past the vertex list.
    IndexOutOfRange {
        /// Index of the first such triangle.
        triangle: usize,
    },
    /// More vertices or triangles than `u32` indices address.
    TooLarge,
    /// The mesh is not closed: this directed edge of `triangle` has no partner edge
    /// running the other way (an open border, a crack, or inconsistent winding). The
    /// shadow volume of such a mesh would leak, so it is refused.
    OpenEdge {
        /// Start of the edge, as in `triangle`.
        from: Vec3,
        /// End of the edge.
        to: Vec3,
        /// Index of the triangle (in the input) the edge belongs to.
        triangle: usize,
    },
    /// The light failed [`shadowmap_frustum::Light::validate`].
    InvalidLight(FrustumError),
    /// The camera failed [`shadowmap_frustum::Camera::validate`].
    InvalidCamera(FrustumError),
    /// The camera's projection has no infinite-far form that keeps points at
    /// infinity in front of the eye (orthographic and custom projections).
    UnsupportedProjection,
    /// No occluder geometry, or occluders the light cannot frame (a point or spot
    /// light inside the occluders' bounding sphere).
    InvalidOccluders,
}

impl fmt::Display for VolumeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NonFinite { vertex } => write!(f, "vertex {vertex} is not finite"),
            Self::IndexOutOfRange { triangle } => {
                write!(f, "triangle {triangle} indexes past the vertices")
            }
            Self::TooLarge => write!(f, "more vertices or triangles than u32 addresses"),
            Self::OpenEdge { from, to, triangle } => write!(
                f,
                "mesh is not closed: edge {from} -> {to} of triangle {triangle} has no opposite edge"
            ),
            Self::InvalidLight(e) => write!(f, "invalid light: {e}"),
            Self::InvalidCamera(e) => write!(f, "invalid camera: {e}"),
            Self::UnsupportedProjection => {
                write!(
                    f,
                    "only perspective cameras have an infinite-far projection"
                )
            }
            Self::InvalidOccluders => write!(f, "no occluders, or the light is inside them"),
        }
    }
}

impl core::error::Error for VolumeError {}
