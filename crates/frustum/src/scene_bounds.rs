//! The scene input of the scene-dependent fits, and the largest map they make.

use crate::Aabb;

/// Largest accepted shadow-map resolution (texels per side).
pub const MAX_RESOLUTION: u32 = 65536;

/// What casts and what receives shadows, as world-space boxes: the scene input of
/// every scene-dependent fit in the library (cascades, spot fit, the warps' focus
/// body, IPSM).
///
/// `receivers` bounds every surface that must look up the map; `casters` bounds every
/// surface that is drawn into it. Often both are the scene bounds
/// ([`SceneBounds::whole`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SceneBounds {
    /// Everything that receives shadows.
    pub receivers: Aabb,
    /// Everything that casts shadows.
    pub casters: Aabb,
}

impl SceneBounds {
    /// Receivers and casters given separately.
    #[must_use]
    pub const fn new(receivers: Aabb, casters: Aabb) -> Self {
        Self { receivers, casters }
    }

    /// One box that both casts and receives.
    #[must_use]
    pub const fn whole(scene: Aabb) -> Self {
        Self {
            receivers: scene,
            casters: scene,
        }
    }
}
