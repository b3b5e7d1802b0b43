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
}

/// Fits a spot light's perspective projection to `frustum ∩ receivers`, clamped to the
/// light's cone, with the near plane pulled back to the casters.
///
/// When the region reaches behind the light's plane, the fit uses the whole cone on
/// every side (the visible part then lies inside the cone, which is all a spot can
/// light).
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
    let mut tangents = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut straddles = false;
    let (mut d_min, mut d_max) = (f64::INFINITY, 0.0f64);
    for p in points {
        let q = light_from_world.transform_point3(p.as_dvec3());
        let d = -q.z;
        if d <= near_min {
            straddles = true;
            continue;
        }
        tangents[0] = tangents[0].min(q.x / d);
        tangents[1] = tangents[1].max(q.x / d);
        tangents[2] = tangents[2].min(q.y / d);
        tangents[3] = tangents[3].max(q.y / d);
        d_min = d_min.min(d);
        d_max = d_max.max(d);
    }
    // Nothing in front of the light: the region lies wholly behind it.
    if !d_min.is_finite() {
        return Err(FrustumError::SliceOutsideScene);
    }
    if straddles {
        tangents = [-cone_tan, cone_tan, -cone_tan, cone_tan];
        d_min = near_min;
        d_max = d_max.max(range);
    }
    let [l, r, b, t] = [
        tangents[0].max(-cone_tan),
        tangents[1].min(cone_tan),
        tangents[2].max(-cone_tan),
        tangents[3].min(cone_tan),
    ];
    if !(r > l && t > b) {
        return Err(FrustumError::SliceOutsideScene);
    }
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
    let reach = points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(position.abs().max_element(), f32::max);
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
    })
}
