//! Generators and checks for the cube shadow maps of `shadowmap-paraboloid`
//! ([`CubeMap::fit`]): fuzz target and property tests.
//!
//! The valid generator places the light as [`plan_input`] does (inside the truncated
//! view frustum, on or next to a corner, at the centroid, just outside, far away),
//! and adds receiver and caster boxes: the frustum's box, a random box in it, a thin
//! ground slab, sometimes casters grown to hold the light; the light's range
//! sometimes falls short of the frustum.

use arbitrary::Unstructured;
use glam::{DVec2, DVec3, Vec2, Vec3};
use shadowmap_frustum::{Aabb, Camera, ConvexBody, DepthBounds, Light, SceneBounds, ShadowMapping};
use shadowmap_paraboloid::{
    CubeFace, CubeFaceId, CubeMap, CubeOptions, CubeOrientation, ParaboloidError,
};

use crate::paraboloid::plan_input;
use crate::{GenResult, aabb_raw, any_f32, any_vec3, camera_raw, in_range, log_uniform};

/// Input of [`CubeMap::fit`].
#[derive(Clone, Debug)]
pub struct CubeInput {
    /// The light.
    pub light: Light,
    /// The camera.
    pub camera: Camera,
    /// Measured depth bounds, if any.
    pub bounds: Option<DepthBounds>,
    /// Receivers and casters.
    pub scene: SceneBounds,
    /// Options.
    pub options: CubeOptions,
}

/// A random point of a box.
fn point_in(u: &mut Unstructured<'_>, b: &Aabb) -> GenResult<Vec3> {
    let t = Vec3::new(
        in_range(u, 0.0, 1.0)?,
        in_range(u, 0.0, 1.0)?,
        in_range(u, 0.0, 1.0)?,
    );
    Ok(b.min + (b.max - b.min) * t)
}

/// A valid input (see the module docs).
pub fn cube_input(u: &mut Unstructured<'_>) -> GenResult<CubeInput> {
    let plan = plan_input(u)?;
    let (position, reach) = match plan.light {
        Light::Point { position, range }
        | Light::Spot {
            position, range, ..
        } => (position, range),
        Light::Directional { .. } => (Vec3::ZERO, 10.0),
    };
    let (near, far) = plan.camera.depth_range().unwrap_or((0.1, 100.0));
    let view = plan
        .camera
        .slice(near, far)
        .map_or(Aabb::new(Vec3::splat(-1.0), Vec3::ONE), |f| f.aabb());
    let receivers = match u.int_in_range(0u8..=3)? {
        0 => view,
        1 => {
            let (a, b) = (point_in(u, &view)?, point_in(u, &view)?);
            Aabb::new(a.min(b), a.max(b))
        }
        2 => {
            // A ground slab through a random point of the view.
            let p = point_in(u, &view)?;
            let thick = (view.max.y - view.min.y) * log_uniform(u, 1e-4, 0.1)?;
            Aabb::new(
                Vec3::new(view.min.x, p.y, view.min.z),
                Vec3::new(view.max.x, p.y + thick, view.max.z),
            )
        }
        _ => view.union(&Aabb::new(position, position)),
    };
    let casters = match u.int_in_range(0u8..=2)? {
        0 => receivers,
        // The light inside a caster's bounds.
        1 => receivers.union(&Aabb::from_center_half_extents(position, Vec3::splat(1.0))),
        _ => {
            let (a, b) = (point_in(u, &view)?, point_in(u, &view)?);
            Aabb::new(a.min(b), a.max(b))
        }
    };
    let options = CubeOptions::default()
        .with_near(log_uniform(u, 1e-3, 0.5)?)
        .with_focused(u.arbitrary()?)
        .with_reversed_z(u.arbitrary()?)
        .with_orientation(match u.int_in_range(0u8..=3)? {
            0 => CubeOrientation::WorldAxes,
            1 => CubeOrientation::TowardReceivers,
            2 => CubeOrientation::CornerUp,
            _ => CubeOrientation::Predicted,
        });
    // The range sometimes stops short of the view.
    let range = if u.arbitrary()? {
        reach
    } else {
        (reach * in_range(u, 0.05, 1.0)?).max(2.0 * options.near + 1.0)
    };
    Ok(CubeInput {
        light: Light::Point { position, range },
        camera: plan.camera,
        bounds: plan.bounds,
        scene: SceneBounds::new(receivers, casters),
        options,
    })
}

/// Any input, often invalid (NaN light, bad camera, bounds, scene or options).
pub fn cube_input_raw(u: &mut Unstructured<'_>) -> GenResult<CubeInput> {
    let mut input = cube_input(u)?;
    match u.int_in_range(0u8..=6)? {
        0 => input.camera = camera_raw(u)?,
        1 => {
            input.light = Light::Point {
                position: any_vec3(u)?,
                range: any_f32(u)?,
            };
        }
        2 => {
            input.bounds = Some(DepthBounds {
                min: any_f32(u)?,
                max: any_f32(u)?,
            });
        }
        3 => input.scene = SceneBounds::new(aabb_raw(u)?, aabb_raw(u)?),
        4 => input.options = input.options.with_near(any_f32(u)?),
        5 => {
            input.light = Light::Directional {
                direction: any_vec3(u)?,
            }
        }
        _ => {}
    }
    Ok(input)
}

/// The visible receivers of an input, by definition (view slice ∩ receivers ∩ the
/// range box), as points: the body's vertices, its centroid and the midpoints of
/// vertex pairs. Empty when the body is.
#[must_use]
pub fn visible_points(input: &CubeInput) -> Vec<Vec3> {
    let Light::Point { position, range } = input.light else {
        return Vec::new();
    };
    let camera = &input.camera;
    let Ok((near, far)) = input
        .bounds
        .map_or(camera.depth_range(), |b| b.clamped_to(camera))
    else {
        return Vec::new();
    };
    let range_box = Aabb::from_center_half_extents(position, Vec3::splat(range));
    let Some(b) = input.scene.receivers.intersection(&range_box) else {
        return Vec::new();
    };
    let Ok(body) = camera
        .slice(near, far)
        .and_then(|s| ConvexBody::from_frustum_aabb(&s, &b))
    else {
        return Vec::new();
    };
    let v = body.vertices();
    let mut points = v.to_vec();
    if !v.is_empty() {
        points.push(v.iter().copied().sum::<Vec3>() / v.len() as f32);
    }
    for (i, a) in v.iter().enumerate() {
        for c in &v[i + 1..] {
            points.push((*a + *c) * 0.5);
        }
    }
    points
}

/// Where a light-relative point lands on a face by the documented formula, without
/// the window test: `(uv, face depth)`, `None` behind the light's plane.
fn face_uv(face: &CubeFace, q: DVec3) -> Option<(DVec2, f64)> {
    let turn = face.orientation.as_dquat();
    let f = turn * face.face.forward().as_dvec3();
    let up = turn * face.face.up().as_dvec3();
    let (a, b, d) = (q.dot(f.cross(up)), q.dot(up), q.dot(f));
    if !(d > 0.0) {
        return None;
    }
    let (lo, hi) = (face.tan_min.as_dvec2(), face.tan_max.as_dvec2());
    let ndc = (2.0 * DVec2::new(a, b) / d - (lo + hi)) / (hi - lo);
    Some((DVec2::new(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y), d))
}

/// Runs [`CubeMap::fit`] and checks the contract. An error is typed (valid input
/// fails only with the camera's or scene's error, e.g. no visible receiver). An
/// `Ok` map has 1 to 6 faces in [`CubeFaceId::ALL`] order sharing one orientation
/// (a turn about the world's `Y` axis), finite non-singular
/// matrices, windows inside the face (up to rounding), `near < far`; every visible
/// receiver point beyond the near plane lands in a kept face, inside its window, at
/// a depth in `[0, 1]` when within range; casters in a window are not clipped by the
/// near plane.
///
/// # Errors
/// A description of the violated clause.
pub fn check_cube(input: &CubeInput, valid: bool) -> Result<(), String> {
    let result = CubeMap::fit(
        &input.light,
        &input.camera,
        input.bounds,
        &input.scene,
        &input.options,
    );
    let cube = match result {
        Ok(cube) => cube,
        Err(ParaboloidError::Frustum(_)) => return Ok(()),
        Err(e) if valid => return Err(format!("valid input refused: {e}")),
        Err(_) => return Ok(()),
    };
    let Light::Point { position, range } = input.light else {
        return Err("fitted a cube for a non-point light".into());
    };
    check_faces(&cube, input.options.orientation)?;
    for p in visible_points(input) {
        check_receiver(&cube, input, p, position, range)?;
    }
    check_casters(&cube, input, position, range)
}

/// The smallest near plane of any face, as [`CubeMap::fit`] documents it.
pub(crate) fn near_floor(input: &CubeInput, position: Vec3, range: f32) -> f64 {
    let scale = range.max(position.abs().max_element());
    f64::from(input.options.near).max(f64::from(scale) / 131_072.0)
}

fn check_faces(cube: &CubeMap, orientation: CubeOrientation) -> Result<(), String> {
    if cube.faces.is_empty() {
        return Err("no face kept".into());
    }
    let order: Vec<usize> = cube
        .faces
        .iter()
        .map(|f| {
            CubeFaceId::ALL
                .iter()
                .position(|x| *x == f.face)
                .unwrap_or(9)
        })
        .collect();
    if order.windows(2).any(|w| w[0] >= w[1]) {
        return Err(format!("faces out of order: {order:?}"));
    }
    // One orientation for all faces: a turn about the world's Y axis, or stood on
    // a corner, the cube's diagonal along it.
    let turn = cube.orientation();
    let up = match orientation {
        CubeOrientation::CornerUp => Vec3::ONE.normalize(),
        _ => Vec3::Y,
    };
    let level = (turn * up - Vec3::Y).length() < 1e-5;
    if !turn.is_normalized() || !level || cube.faces.iter().any(|f| f.orientation != turn) {
        return Err(format!("bad orientation {turn:?}"));
    }
    for f in &cube.faces {
        let m = f.clip_from_world;
        let det = m.as_dmat4().determinant();
        if !m.is_finite() || det == 0.0 || !det.is_finite() {
            return Err(format!("{:?}: bad matrix {m:?}", f.face));
        }
        let edge = 1.0 + 1e-4;
        let ok = f.tan_min.cmpge(Vec2::splat(-edge)).all()
            && f.tan_max.cmple(Vec2::splat(edge)).all()
            && f.tan_min.cmplt(f.tan_max).all()
            && f.near > 0.0
            && f.near < f.far;
        if !ok {
            return Err(format!("{:?}: bad window or range {f:?}", f.face));
        }
    }
    Ok(())
}

fn check_receiver(
    cube: &CubeMap,
    input: &CubeInput,
    p: Vec3,
    position: Vec3,
    range: f32,
) -> Result<(), String> {
    let q = p.as_dvec3() - position.as_dvec3();
    // Closer than the near plane along every face axis (the cube's, turned): not
    // stored.
    let along_faces = cube.orientation().as_dquat().inverse() * q;
    if along_faces.abs().max_element() <= 1.01 * near_floor(input, position, range) {
        return Ok(());
    }
    // f32 rounding of the point and of the body's vertices, as a tangent.
    let scale = f64::from(p.abs().max_element().max(position.abs().max_element()));
    let tan_tol = 1e-5 + 64.0 * f64::from(f32::EPSILON) * scale / q.abs().max_element();
    let hit = cube.faces.iter().enumerate().find_map(|(layer, f)| {
        let (uv, d) = face_uv(f, q)?;
        let tol = tan_tol / f64::from((f.tan_max - f.tan_min).min_element());
        let inside = uv.cmpge(DVec2::splat(-tol)).all() && uv.cmple(DVec2::splat(1.0 + tol)).all();
        (inside && d > 0.0).then_some((layer, d))
    });
    let Some((layer, _)) = hit else {
        return Err(format!("visible receiver {p} in no kept window"));
    };
    if let Some(s) = cube.map_point(p.as_dvec3()) {
        if s.layer >= cube.layers() || !s.uv.is_finite() {
            return Err(format!("bad sample {s:?} for {p}"));
        }
        let within = q.length() < 0.99 * f64::from(range);
        let d_tol = 1e-3;
        if within && !(-d_tol..=1.0 + d_tol).contains(&s.depth) {
            return Err(format!("receiver {p} at depth {} (layer {layer})", s.depth));
        }
    } else if tan_tol < 1e-4 {
        // Rounding aside, `map_point` must find the window found above.
        return Err(format!("map_point misses visible receiver {p}"));
    }
    Ok(())
}

fn check_casters(
    cube: &CubeMap,
    input: &CubeInput,
    position: Vec3,
    range: f32,
) -> Result<(), String> {
    let range_box = Aabb::from_center_half_extents(position, Vec3::splat(range));
    let Some(c) = input.scene.casters.intersection(&range_box) else {
        return Ok(());
    };
    let near = near_floor(input, position, range);
    for p in c.corners().into_iter().chain([c.center()]) {
        let q = p.as_dvec3() - position.as_dvec3();
        for f in &cube.faces {
            let Some((uv, d)) = face_uv(f, q) else {
                continue;
            };
            let inside = uv.cmpge(DVec2::ZERO).all() && uv.cmple(DVec2::ONE).all();
            let scale = f64::from(p.abs().max_element().max(position.abs().max_element()));
            let tol = 1e-5 * (1.0 + d) + 64.0 * f64::from(f32::EPSILON) * scale;
            if inside && d >= near + tol && d < f64::from(f.near) - tol {
                return Err(format!(
                    "caster {p} at face depth {d} clipped by {:?} near {}",
                    f.face, f.near
                ));
            }
        }
    }
    Ok(())
}
