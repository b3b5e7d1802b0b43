//! Generators and checks for `shadowmap-warp` (fuzz targets and property tests).
//!
//! [`warp_case`] gives valid scenes whose receivers meet the view frustum, biased to
//! extreme cameras, flat or point-like boxes and lights nearly parallel to the view;
//! [`warp_case_raw`] gives anything. The `check_*` functions assert the contract of
//! each builder: no panic, an `Ok` output finite and invertible, else a typed error.

use arbitrary::Unstructured;
use glam::{DVec3, Vec3};
use shadowmap_frustum::{Aabb, Camera, CascadeSplits, ConvexBody, ShadowTransform, SplitScheme};
use shadowmap_warp::{
    LispsmOptions, SceneBounds, TsmOptions, UniformOptions, WarpError, XpsmOptions, lispsm, tsm,
    uniform_focused, warped_cascades, xpsm,
};

use crate::{
    GenResult, aabb_raw, any_f32, any_vec3, camera, camera_raw, in_range, light_direction,
    log_uniform,
};

/// One input of every warp builder.
#[derive(Clone, Copy, Debug)]
pub struct WarpCase {
    /// The camera.
    pub camera: Camera,
    /// Direction the light travels.
    pub light: Vec3,
    /// Receivers and casters.
    pub scene: SceneBounds,
    /// LiSPSM strength.
    pub eta: f32,
    /// Depth convention of the shadow map.
    pub reversed_z: bool,
}

/// A valid case: the receivers meet the view frustum; the casters usually contain
/// them, sometimes are an unrelated box.
///
/// Receivers are a box around a random point of the frustum, sometimes flat (a
/// ground slab), a point, or a box holding the whole frustum.
pub fn warp_case(u: &mut Unstructured<'_>) -> GenResult<WarpCase> {
    let camera = camera(u)?;
    let frustum = camera
        .frustum()
        .map_err(|_| arbitrary::Error::IncorrectFormat)?;
    let fa = frustum.aabb();
    let size = fa.size().max_element().max(1e-6);
    let mut w = [0f32; 8];
    for wi in &mut w {
        *wi = in_range(u, 0.0, 1.0)?.powi(3);
    }
    let total: f32 = w.iter().sum::<f32>().max(1e-12);
    let center = frustum
        .corners
        .iter()
        .zip(w)
        .fold(Vec3::ZERO, |acc, (c, wi)| acc + *c * (wi / total));
    let receivers = match u.int_in_range(0u8..=5)? {
        0 => Aabb::new(fa.min - size * 0.1, fa.max + size * 0.1),
        1 => Aabb::from_center_half_extents(center, Vec3::ZERO),
        2 => {
            let h = log_uniform(u, 1e-3, 1.0)? * size;
            Aabb::from_center_half_extents(center, Vec3::new(h, 0.0, h))
        }
        _ => {
            let h = Vec3::new(
                log_uniform(u, 1e-4, 1.0)?,
                log_uniform(u, 1e-4, 1.0)?,
                log_uniform(u, 1e-4, 1.0)?,
            ) * size;
            Aabb::from_center_half_extents(center, h)
        }
    };
    let casters = match u.int_in_range(0u8..=3)? {
        0 => receivers,
        3 => {
            // An unrelated box somewhere around the frustum (may miss the receivers).
            let c = frustum.corners[usize::from(u.int_in_range(0u8..=7)?)];
            let h = log_uniform(u, 1e-3, 1.0)? * size;
            Aabb::from_center_half_extents(c.lerp(center, in_range(u, 0.0, 1.0)?), Vec3::splat(h))
        }
        1 => {
            let grow = log_uniform(u, 1e-3, 10.0)? * size;
            Aabb::new(receivers.min - grow, receivers.max + grow)
        }
        _ => {
            // A tall box reaching up toward the sky, as scene geometry would.
            let up = log_uniform(u, 1e-3, 10.0)? * size;
            Aabb::new(receivers.min, receivers.max + Vec3::new(0.0, up, 0.0))
        }
    };
    let light = light_direction(u, &camera)?;
    let eta = match u.int_in_range(0u8..=4)? {
        0 => -1.0,
        1 => 0.0,
        2 => 1.0,
        _ => in_range(u, -1.0, 1.0)?,
    };
    Ok(WarpCase {
        camera,
        light,
        scene: SceneBounds::new(receivers, casters),
        eta,
        reversed_z: u.arbitrary()?,
    })
}

/// Any case: invalid cameras, NaN or zero lights, inverted or non-finite boxes,
/// strengths out of range.
pub fn warp_case_raw(u: &mut Unstructured<'_>) -> GenResult<WarpCase> {
    let mut case = warp_case(u)?;
    match u.int_in_range(0u8..=6)? {
        0 => case.camera = camera_raw(u)?,
        1 => case.light = any_vec3(u)?,
        2 => case.scene.receivers = aabb_raw(u)?,
        3 => case.scene.casters = aabb_raw(u)?,
        4 => case.eta = any_f32(u)?,
        _ => {}
    }
    Ok(case)
}

/// Points of frustum ∩ receivers: its vertices and convex combinations of them
/// (`None` when the receivers miss the frustum).
pub fn receiver_samples(case: &WarpCase, u: &mut Unstructured<'_>) -> Option<Vec<Vec3>> {
    let body =
        ConvexBody::from_frustum_aabb(&case.camera.frustum().ok()?, &case.scene.receivers).ok()?;
    let v = body.vertices();
    if v.is_empty() {
        return None;
    }
    let mut out: Vec<Vec3> = v.to_vec();
    for _ in 0..16 {
        let mut acc = DVec3::ZERO;
        let mut total = 0.0;
        for p in v {
            let wi = f64::from(u.int_in_range(0u8..=255).unwrap_or(1)).powi(2);
            acc += p.as_dvec3() * wi;
            total += wi;
        }
        if total > 0.0 {
            out.push((acc / total).as_vec3());
        }
    }
    Some(out)
}

/// Asserts a transform is finite and invertible.
///
/// # Panics
/// When it is not.
pub fn check_transform(t: &ShadowTransform) {
    for m in [t.clip_from_world, t.uv_from_world, t.light_from_world] {
        assert!(m.is_finite(), "non-finite matrix {m:?}");
        let det = m.as_dmat4().determinant();
        assert!(det.is_finite() && det != 0.0, "singular matrix {m:?}");
        assert!(
            m.inverse().is_finite(),
            "matrix without finite inverse {m:?}"
        );
    }
}

fn check_error(e: &WarpError) {
    use core::fmt::Write;
    let mut s = String::new();
    let _ = write!(s, "{e}");
    assert!(!s.is_empty());
}

/// Runs [`uniform_focused`] and asserts its contract.
///
/// # Panics
/// When an `Ok` output is not finite and invertible.
pub fn check_uniform(case: &WarpCase) -> Result<ShadowTransform, WarpError> {
    let r = uniform_focused(
        &case.camera,
        case.light,
        &case.scene,
        &UniformOptions::default().with_reversed_z(case.reversed_z),
    );
    match &r {
        Ok(t) => check_transform(t),
        Err(e) => check_error(e),
    }
    r
}

/// Runs [`lispsm`] and asserts its contract.
///
/// # Panics
/// When an `Ok` output is not finite and invertible, or its `n` is not positive.
pub fn check_lispsm(case: &WarpCase) -> Result<ShadowTransform, WarpError> {
    let r = lispsm(
        &case.camera,
        case.light,
        &case.scene,
        &LispsmOptions::default()
            .with_eta(case.eta)
            .with_reversed_z(case.reversed_z),
    );
    match &r {
        Ok(s) => {
            check_transform(&s.transform);
            assert!(s.n > 0.0 && (0.0..=1.0).contains(&s.fade));
        }
        Err(e) => check_error(e),
    }
    r.map(|s| s.transform)
}

/// Runs [`xpsm`] and asserts its contract.
///
/// # Panics
/// When an `Ok` output is not finite and invertible or its bias scale is not positive.
pub fn check_xpsm(case: &WarpCase) -> Result<ShadowTransform, WarpError> {
    let r = xpsm(
        &case.camera,
        case.light,
        &case.scene,
        &XpsmOptions::default().with_reversed_z(case.reversed_z),
    );
    match &r {
        Ok(s) => {
            check_transform(&s.transform);
            assert!(s.z_bias_scale.is_finite() && s.z_bias_scale > 0.0);
            assert!(s.length_p.is_finite() && s.length_p >= 0.0);
        }
        Err(e) => check_error(e),
    }
    r.map(|s| s.transform)
}

/// Runs [`tsm`] (focus from `eta`, mapped to `(0, 1)`) and asserts its contract.
///
/// # Panics
/// When an `Ok` output is not finite and invertible, or its `eta` is not positive.
pub fn check_tsm(case: &WarpCase) -> Result<ShadowTransform, WarpError> {
    let focus = if case.eta.is_finite() {
        (0.5 + 0.45 * case.eta).clamp(0.01, 0.99)
    } else {
        case.eta
    };
    let r = tsm(
        &case.camera,
        case.light,
        &case.scene,
        &TsmOptions::default()
            .with_focus(focus)
            .with_reversed_z(case.reversed_z),
    );
    match &r {
        Ok(s) => {
            check_transform(&s.transform);
            assert!(s.eta > 0.0);
        }
        Err(e) => check_error(e),
    }
    r.map(|s| s.transform)
}

/// Runs [`warped_cascades`] on four practical splits with strengths from `eta`, and
/// asserts its contract.
///
/// # Panics
/// When an `Ok` cascade is not finite and invertible.
pub fn check_cascades(case: &WarpCase) -> Result<usize, WarpError> {
    let Ok((near, far)) = case.camera.depth_range() else {
        return Err(WarpError::InvalidCascades);
    };
    let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.7 }, 4, near, far)?;
    let e = if case.eta.is_finite() { case.eta } else { 0.0 };
    let etas = [e, e * 0.5, e * 0.25, e * 0.1];
    let r = warped_cascades(
        &case.camera,
        case.light,
        &case.scene,
        &splits,
        &etas,
        &LispsmOptions::default().with_reversed_z(case.reversed_z),
    );
    match &r {
        Ok(c) => {
            assert_eq!(c.cascades.len(), 4);
            for s in c.cascades.iter().filter_map(|c| c.shadow) {
                check_transform(&s.transform);
            }
        }
        Err(e) => check_error(e),
    }
    r.map(|c| c.cascades.len())
}

/// Bound on the `f32` rounding of `uv_from_world * p` in uv / depth units (a dot
/// product of four terms per row, then the division by `w`), for checks that a point
/// lands inside the map "up to `f32` rounding": `64 eps Σ|m_ij p_j| / w` per coordinate, plus the
/// error of `w` carried through the division.
#[must_use]
pub fn f32_rounding(t: &ShadowTransform, p: DVec3) -> f64 {
    let m = t.uv_from_world.as_dmat4();
    let h = p.extend(1.0);
    let abs_row = |r: usize| {
        (m.x_axis[r] * h.x).abs()
            + (m.y_axis[r] * h.y).abs()
            + (m.z_axis[r] * h.z).abs()
            + m.w_axis[r].abs()
    };
    let hw = m * h;
    let eps = 64.0 * f64::from(f32::EPSILON);
    let w_err = eps * abs_row(3) / hw.w.abs();
    let mut worst = 0.0f64;
    for r in 0..3 {
        let v = (hw[r] / hw.w).abs();
        worst = worst.max(eps * abs_row(r) / hw.w.abs() + v * w_err);
    }
    1e-6 + worst
}
