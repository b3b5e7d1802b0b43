//! Warped cascades: LiSPSM (or uniform, or PSM-like) per parallel split.

use arrayvec::ArrayVec;
use glam::Vec3;
use shadowmap_frustum::{Camera, CascadeSplits, MAX_CASCADES, ValidCamera};

use crate::{FocusBody, LispsmOptions, LispsmShadow, SceneBounds, WarpError};

/// One cascade of a warped-cascade fit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WarpedCascade {
    /// View depth where the cascade starts (including the blend band it shares with
    /// its predecessor).
    pub near: f32,
    /// View depth where it ends.
    pub far: f32,
    /// The fit, `None` when the slice misses the receivers (nothing to shadow there:
    /// sample as lit).
    pub shadow: Option<LispsmShadow>,
}

/// The cascades of [`warped_cascades`], near to far.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WarpedCascades {
    /// One entry per split.
    pub cascades: ArrayVec<WarpedCascade, MAX_CASCADES>,
}

/// Parallel-split shadow maps with a LiSPSM warp per cascade (PSSM + LiSPSM): each
/// slice of `splits` (with its blend band) is fitted by [`lispsm`](crate::lispsm) on
/// that slice, with strength `etas[i]` (`-1` uniform, `0` LiSPSM, `1` PSM-like); the
/// other options are shared.
///
/// # Errors
/// [`WarpError::InvalidCascades`] when `etas.len() != splits.count()`;
/// [`WarpError::InvalidOption`] for options or an `eta` out of range;
/// [`WarpError::Frustum`] when a split lies outside the camera's depth range; the
/// errors of [`lispsm`](crate::lispsm) except [`WarpError::NoVisibleReceivers`] for a
/// single slice, which gives `shadow: None` (if every slice misses the receivers,
/// that error is returned).
pub fn warped_cascades(
    camera: &Camera,
    light_direction: Vec3,
    scene: &SceneBounds,
    splits: &CascadeSplits,
    etas: &[f32],
    options: &LispsmOptions,
) -> Result<WarpedCascades, WarpError> {
    if etas.len() != splits.count() || etas.is_empty() {
        return Err(WarpError::InvalidCascades);
    }
    let mut cascades = ArrayVec::new();
    let mut any = false;
    // Validated once, at its first use (so errors come in the same order as when
    // each slice checked the camera).
    let mut valid: Option<ValidCamera> = None;
    for (i, eta) in etas.iter().enumerate() {
        let (near, far) = splits.cascade_range(i).ok_or(WarpError::InvalidCascades)?;
        let opts = options.with_eta(*eta);
        opts.check()?;
        let camera = match valid {
            Some(v) => v,
            None => *valid.insert(ValidCamera::new(camera)?),
        };
        // Read where it was built (see `FocusBody::fit_from`).
        let shadow = match FocusBody::slice_valid(&camera, near, far, light_direction, scene)
            .as_ref()
            .map_err(|e| *e)
            .and_then(|body| body.lispsm(&opts))
        {
            Ok(s) => {
                any = true;
                Some(s)
            }
            Err(WarpError::NoVisibleReceivers) => None,
            Err(e) => return Err(e),
        };
        cascades
            .try_push(WarpedCascade { near, far, shadow })
            .map_err(|_| WarpError::InvalidCascades)?;
    }
    if any {
        Ok(WarpedCascades { cascades })
    } else {
        Err(WarpError::NoVisibleReceivers)
    }
}
