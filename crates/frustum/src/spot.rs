use crate::body::ConvexBody;
use crate::light::unit;
use crate::mapping::{LightDirection, ShadowTransform};
use crate::projection::{least_aligned_axis, look_to};
use crate::{Frustum, FrustumError, Light, SceneBounds, math};

/// A perspective shadow map for a spot light, fitted to what the camera sees.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SpotShadow {
    /// The matrices.
    pub transform: ShadowTransform,
    /// Near and far distance along the spot axis mapped to the depth range.
    pub light_depth: (f32, f32),
    /// Tangents of the (possibly off-centre) fitted frustum: left, right, bottom, top.
    pub tangents: [f32; 4],
    /// Nearest and farthest distance along the spot axis of the region the window
    /// was fitted to (`frustum ∩ receivers`, the frustum without a scene) in front
    /// of the light; the nearest is the light's near limit where the region reaches
    /// behind it. Lookups happen there: a warp of the map reads it to keep `f32`
    /// rounding small at the nearest receivers.
    pub receiver_depth: (f32, f32),
}

/// Fits a spot light's perspective projection to `frustum ∩ receivers`, clamped to the
/// light's cone, with the near plane pulled back to the casters.
///
/// When the region reaches behind the light's plane, the fit uses the whole cone on
/// every side (the visible part then lies inside the cone, which is all a spot can
/// light).
///
/// A window narrower than `f32` resolves (a receiver seen edge-on, a sliver far
/// from the origin) is widened about its middle, within the cone, to 1/500 of the
/// scene's largest coordinate at its nearest receiver: there a texel of a `1024²`
/// map spans at least 16 `f32` steps, and both ends of a light ray land on one
/// texel to a tenth of it.
///
/// # Errors
/// [`FrustumError::UnsupportedLight`] for a non-spot light; errors of
/// [`Light::validate`]; [`FrustumError::EmptyBounds`] / [`FrustumError::NonFinite`] for
/// bad bounds; [`FrustumError::SliceOutsideScene`] when nothing of the region lies in
/// front of the light within its range.
pub fn fit_spot(
    light: &Light,
    frustum: &Frustum,
    scene: Option<&SceneBounds>,
    reversed_z: bool,
) -> Result<SpotShadow, FrustumError> {
    light.validate()?;
    let Light::Spot {
        position,
        direction,
        half_angle,
        range,
    } = *light
    else {
        return Err(FrustumError::UnsupportedLight);
    };
    let dir = unit(direction)?;
    let pos = position.as_dvec3();
    let up = least_aligned_axis(dir);
    let light_from_world = look_to(pos, dir, up);
    let cone_tan = math::tan(f64::from(half_angle));
    let range = f64::from(range);
    let near_min = range * 1e-4;

    let body;
    let points: &[glam::Vec3] = match scene {
        Some(s) => {
            body = ConvexBody::from_frustum_aabb(frustum, &s.receivers.validate()?)?;
            if body.is_empty() {
                return Err(FrustumError::SliceOutsideScene);
            }
            body.vertices()
        }
        None => &frustum.corners,
    };
    let reach = points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(position.abs().max_element(), f32::max);
    let window = Window::over(points, &light_from_world, near_min)?;
    let (nearest, [l, r, b, t]) = if window.straddles {
        (near_min, [-cone_tan, cone_tan, -cone_tan, cone_tan])
    } else {
        (
            window.nearest,
            window.resolvable(f64::from(reach), cone_tan),
        )
    };
    if !(r > l && t > b) {
        return Err(FrustumError::SliceOutsideScene);
    }
    let receiver_depth = (nearest as f32, window.farthest.min(range) as f32);
    // A region reaching behind the light takes the light's whole reach.
    let d_max = if window.straddles {
        window.farthest.max(range)
    } else {
        window.farthest
    };
    let mut d_min = nearest;
    if let Some(s) = scene {
        let casters = s.casters.validate()?;
        for c in casters.corners() {
            let d = -light_from_world.transform_point3(c.as_dvec3()).z;
            d_min = d_min.min(d.max(near_min));
        }
    }
    let near = d_min.max(near_min);
    let far = d_max.min(range);
    if !(far > near * (1.0 + 1e-5)) {
        return Err(FrustumError::SliceOutsideScene);
    }
    let clip_from_light =
        crate::projection::perspective_off_center(l, r, b, t, near, far, reversed_z);
    let clip_from_world = (clip_from_light * light_from_world).as_mat4();
    if !crate::is_invertible(&clip_from_world, reach) {
        return Err(FrustumError::DegenerateFrustum);
    }
    Ok(SpotShadow {
        transform: ShadowTransform::new(
            light_from_world.as_mat4(),
            clip_from_world,
            reversed_z,
            LightDirection::Position(position),
        ),
        light_depth: (near as f32, far as f32),
        tangents: [l as f32, r as f32, b as f32, t as f32],
        receiver_depth,
    })
}

/// The smallest width of a fitted window at its nearest receiver, as a fraction of
/// the scene's largest coordinate: a texel of a `1024²` map there spans at least 16
/// `f32` steps of the coordinates, so the rounding of the `f32` matrix and points
/// moves a lookup by under a tenth of a texel. (A perspective map divides that
/// rounding by the distance from the light: the window of a receiver seen edge-on
/// 3 mm from a light 0.05 from the origin, 300 `f32` steps wide, put the two ends
/// of one light ray 0.4 texels apart.)
const MIN_WINDOW: f64 = 2e-3;

/// The tangents of the directions to a region's points, seen from the light.
struct Window {
    /// Smallest and largest `x / d` and `y / d` (`d` the distance along the axis)
    /// over the points in front of the light's near limit: left, right, bottom, top.
    tangents: [f64; 4],
    /// Nearest and farthest such distances.
    nearest: f64,
    farthest: f64,
    /// Whether a point lies at or behind the near limit.
    straddles: bool,
}

impl Window {
    /// The window of `points` (world) in the light frame `light_from_world`, points
    /// nearer than `near_min` marking it as straddling the light's plane.
    ///
    /// # Errors
    /// [`FrustumError::SliceOutsideScene`] when no point lies in front of the light.
    fn over(
        points: &[glam::Vec3],
        light_from_world: &glam::DMat4,
        near_min: f64,
    ) -> Result<Self, FrustumError> {
        let mut w = Self {
            tangents: [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ],
            nearest: f64::INFINITY,
            farthest: 0.0,
            straddles: false,
        };
        for p in points {
            let q = light_from_world.transform_point3(p.as_dvec3());
            let d = -q.z;
            if d <= near_min {
                w.straddles = true;
                continue;
            }
            let [l, r, b, t] = &mut w.tangents;
            (*l, *r) = (l.min(q.x / d), r.max(q.x / d));
            (*b, *t) = (b.min(q.y / d), t.max(q.y / d));
            w.nearest = w.nearest.min(d);
            w.farthest = w.farthest.max(d);
        }
        // Nothing in front of the light: the region lies wholly behind it.
        if w.nearest.is_finite() {
            Ok(w)
        } else {
            Err(FrustumError::SliceOutsideScene)
        }
    }

    /// The tangents clamped to the cone `[-cone_tan, cone_tan]²`, each side widened
    /// about its middle (within the cone) to at least [`MIN_WINDOW`] `reach` at the
    /// nearest point, `reach` the scene's largest coordinate.
    fn resolvable(&self, reach: f64, cone_tan: f64) -> [f64; 4] {
        let least = MIN_WINDOW * reach / self.nearest;
        let [l, r, b, t] = self.tangents;
        let (l, r) = widen(l.max(-cone_tan), r.min(cone_tan), least, cone_tan);
        let (b, t) = widen(b.max(-cone_tan), t.min(cone_tan), least, cone_tan);
        [l, r, b, t]
    }
}

/// `[lo, hi]` widened about its middle to at least `least`, kept within
/// `[-limit, limit]` (moved away from a limit it meets; the whole of it when it is
/// narrower than `least`). An empty interval stays empty.
fn widen(lo: f64, hi: f64, least: f64, limit: f64) -> (f64, f64) {
    if !(hi > lo) || hi - lo >= least {
        return (lo, hi);
    }
    if least >= 2.0 * limit {
        return (-limit, limit);
    }
    let middle = 0.5 * (lo + hi);
    let start = (middle - 0.5 * least).clamp(-limit, limit - least);
    (start, start + least)
}
