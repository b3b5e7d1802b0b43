use crate::body::ConvexBody;
use crate::light::unit;
use crate::mapping::{LightDirection, ShadowTransform};
use crate::projection::{least_aligned_axis, look_to};
use crate::{Frustum, FrustumError, Light, SPOT_ROUNDING_BUDGET, SceneBounds, SpotRounding, math};

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
/// A window finer than `f32` resolves (a receiver seen edge-on, a sliver far from
/// the origin) is widened about its middle, within the cone, until the rounding of
/// its `f32` matrices separates the two ends of a light ray at the nearest
/// receiver by at most a tenth of a texel of a `1024²` map; a cone too narrow for
/// that keeps its whole width if it holds them within a texel, and is refused
/// otherwise.
///
/// # Errors
/// [`FrustumError::UnsupportedLight`] for a non-spot light; errors of
/// [`Light::validate`]; [`FrustumError::EmptyBounds`] / [`FrustumError::NonFinite`] for
/// bad bounds; [`FrustumError::SliceOutsideScene`] when nothing of the region lies in
/// front of the light within its range; [`FrustumError::DegenerateFrustum`] when
/// even the whole cone is too narrow at the nearest receiver for `f32` (the two
/// ends of a light ray more than a texel of a `1024²` map apart) or the matrix is
/// singular.
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
        let rounding = |tangents: [f64; 4]| {
            ray_rounding(tangents, &light_from_world, position, window.nearest)
        };
        (window.nearest, window.resolvable(cone_tan, rounding)?)
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

/// How far the rounding of the `f32` matrices of the window `tangents` (left,
/// right, bottom, top) moves a lookup's texture coordinates, and the two ends of a
/// light ray apart, at the distance `nearest` along the axis
/// ([`SpotRounding::texel`]). Near and far do not enter those rows; the depth's
/// rounding, which no window changes, is not bounded here.
fn ray_rounding(
    tangents: [f64; 4],
    light_from_world: &glam::DMat4,
    light: glam::Vec3,
    nearest: f64,
) -> f64 {
    let [l, r, b, t] = tangents;
    let clip =
        crate::projection::perspective_off_center(l, r, b, t, 1.0, 2.0, false) * *light_from_world;
    let map = ShadowTransform::new(
        glam::Mat4::IDENTITY,
        clip.as_mat4(),
        false,
        LightDirection::Position(light),
    );
    SpotRounding::new(light, tangents, nearest).texel(&clip, &map)
}

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

    /// The tangents clamped to the cone `[-cone_tan, cone_tan]²`, where their
    /// `rounding` (a window's [`ray_rounding`]) exceeds [`SPOT_ROUNDING_BUDGET`] widened
    /// about their middles (within the cone), both sides by the least factor that
    /// keeps it within (bisection on its logarithm); the whole cone where even it
    /// does not, if it keeps the rounding within a texel.
    ///
    /// # Errors
    /// [`FrustumError::DegenerateFrustum`] where even the whole cone leaves more
    /// than a texel.
    fn resolvable(
        &self,
        cone_tan: f64,
        rounding: impl Fn([f64; 4]) -> f64,
    ) -> Result<[f64; 4], FrustumError> {
        let [l, r, b, t] = self.tangents;
        let (l, r, b, t) = (
            l.max(-cone_tan),
            r.min(cone_tan),
            b.max(-cone_tan),
            t.min(cone_tan),
        );
        if !(r > l && t > b) || rounding([l, r, b, t]) <= SPOT_ROUNDING_BUDGET {
            return Ok([l, r, b, t]);
        }
        let scaled = |factor: f64| {
            let (l, r) = widen(l, r, (r - l) * factor, cone_tan);
            let (b, t) = widen(b, t, (t - b) * factor, cone_tan);
            [l, r, b, t]
        };
        let full = (2.0 * cone_tan / (r - l)).max(2.0 * cone_tan / (t - b));
        let at_full = rounding(scaled(full));
        if !(at_full <= SPOT_ROUNDING_BUDGET) {
            return if at_full <= 10.0 * SPOT_ROUNDING_BUDGET {
                Ok(scaled(full))
            } else {
                Err(FrustumError::DegenerateFrustum)
            };
        }
        let (mut narrow, mut wide) = (0.0, math::ln(full));
        for _ in 0..30 {
            let middle = 0.5 * (narrow + wide);
            if rounding(scaled(math::exp(middle))) <= SPOT_ROUNDING_BUDGET {
                wide = middle;
            } else {
                narrow = middle;
            }
        }
        Ok(scaled(math::exp(wide)))
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
