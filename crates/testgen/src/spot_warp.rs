//! Generators and checks for the warps of a spot light's shadow map in its
//! post-projective space (`shadowmap_warp::spot_warp`): property tests and fuzzing.

use arbitrary::Unstructured;
use glam::{DVec2, Vec3};
use shadowmap_frustum::{
    Aabb, Camera, ConvexBody, DepthBounds, Light, SceneBounds, ShadowMapping, ShadowSample,
};
use shadowmap_warp::{SpotWarpKind, SpotWarpOptions, spot_warp};

use crate::frustum::{assert_invertible, spot_ray_tolerance};
use crate::{GenResult, camera, in_range, log_uniform, unit_vec3};

/// Input of [`check_spot_warp`].
#[derive(Clone, Debug)]
pub struct SpotWarpCase {
    /// A spot light near the camera (sometimes aimed at it, sometimes along it).
    pub light: Light,
    /// The camera.
    pub camera: Camera,
    /// Measured depth bounds, if any.
    pub bounds: Option<DepthBounds>,
    /// Receivers and casters.
    pub scene: SceneBounds,
    /// Options.
    pub options: SpotWarpOptions,
}

/// A valid case: the spot within the camera's reach, aimed anywhere, at the view's
/// middle, or along the view (the warp's fallback); receivers the view's box or a
/// slab through it.
pub fn spot_warp_case(u: &mut Unstructured<'_>) -> GenResult<SpotWarpCase> {
    let camera = camera(u)?;
    let (near, far) = camera.depth_range().unwrap_or((0.1, 100.0));
    let scale = far.min(1e4).max(near);
    let view = camera
        .frustum()
        .map_or(Aabb::new(Vec3::splat(-1.0), Vec3::ONE), |f| f.aabb());
    let position = camera.eye() + crate::position(u, scale)?;
    let middle = camera.eye() + camera.forward() * (0.5 * (near + far.min(1e4)));
    let direction = match u.int_in_range(0u8..=2)? {
        0 => unit_vec3(u)?,
        1 => (middle - position).normalize_or(Vec3::NEG_Y),
        _ => camera.forward(),
    };
    let light = Light::Spot {
        position,
        direction,
        half_angle: in_range(u, 0.05, 1.5)?,
        range: log_uniform(u, 1e-2, (4.0 * scale).max(0.02))?,
    };
    let receivers = if u.arbitrary()? {
        view
    } else {
        let y = in_range(u, view.min.y, view.max.y)?;
        Aabb::new(
            Vec3::new(view.min.x, y, view.min.z),
            Vec3::new(view.max.x, y + 0.01 * (view.max.y - view.min.y), view.max.z),
        )
    };
    let bounds = crate::depth_bounds_in(u, near, far)?;
    let kind = if u.arbitrary()? {
        SpotWarpKind::Lispsm
    } else {
        SpotWarpKind::Tsm
    };
    Ok(SpotWarpCase {
        light,
        camera,
        bounds,
        scene: SceneBounds::new(receivers, receivers.union(&view)),
        options: SpotWarpOptions::default()
            .with_kind(kind)
            .with_focus(in_range(u, 0.01, 0.99)?)
            .with_reversed_z(u.arbitrary()?),
    })
}

/// [`spot_warp`] on a case: a refusal is a typed error; a fit has a finite
/// invertible matrix and a finite strength, and every point of the visible
/// receivers (frustum ∩ receivers: its vertices, centroid and vertex midpoints) the
/// spot fit stores inside its map is stored inside the warped map with a depth in
/// `[0, 1]`, and the point halfway to the light on its ray lands on the same texel
/// nearer the light (both to [`spot_ray_tolerance`]). Returns how many points were
/// checked.
///
/// # Errors
/// A description of the violated clause.
pub fn check_spot_warp(case: &SpotWarpCase) -> Result<usize, String> {
    let Ok(w) = spot_warp(
        &case.light,
        &case.camera,
        case.bounds,
        &case.scene,
        &case.options,
    ) else {
        return Ok(0);
    };
    assert_invertible(&w.transform.clip_from_world, "spot warp clip_from_world");
    if !(w.strength.is_finite() && w.strength >= 0.0) {
        return Err(format!("strength {}", w.strength));
    }
    let Light::Spot {
        position,
        half_angle,
        ..
    } = case.light
    else {
        return Err("a spot warp for another light".into());
    };
    let Ok(body) = case
        .camera
        .frustum()
        .and_then(|f| ConvexBody::from_frustum_aabb(&f, &case.scene.receivers))
    else {
        return Ok(0);
    };
    let v = body.vertices();
    let mut points: Vec<Vec3> = v.to_vec();
    for (i, a) in v.iter().enumerate() {
        points.extend(v[i + 1..].iter().map(|b| (*a + *b) * 0.5));
    }
    let inside = |s: &ShadowSample, tol: f64| {
        s.uv.cmpge(DVec2::splat(-tol)).all()
            && s.uv.cmple(DVec2::splat(1.0 + tol)).all()
            && (-tol..=1.0 + tol).contains(&s.depth)
    };
    let mut checked = 0;
    for p in points {
        let p = p.as_dvec3();
        let l = position.as_dvec3();
        let half = l + (p - l) * 0.5;
        let (Some(b), Some(bh)) = (
            w.base.transform.map_point(p),
            w.base.transform.map_point(half),
        ) else {
            continue;
        };
        if !(inside(&b, 0.0) && inside(&bh, 0.0)) {
            continue;
        }
        let (Some(s), Some(sh)) = (w.transform.map_point(p), w.transform.map_point(half)) else {
            return Err(format!("{p}: stored by the spot fit, not by the warp"));
        };
        let tol = spot_ray_tolerance(&w.base, half_angle, l, p);
        if !inside(&s, tol) || (s.uv - sh.uv).abs().max_element() > tol {
            return Err(format!("{p}: {s:?}, halfway {sh:?}"));
        }
        let nearer = if w.transform.reversed_z {
            sh.depth >= s.depth
        } else {
            sh.depth <= s.depth
        };
        if !nearer && (b.depth - bh.depth).abs() > 1e-6 {
            return Err(format!(
                "{p}: depth {} behind the halfway point's {}",
                s.depth, sh.depth
            ));
        }
        checked += 1;
    }
    Ok(checked)
}
