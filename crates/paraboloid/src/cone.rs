//! Light cones: the paper's averaged-axis fit and the exact minimal enclosing cone.

use glam::{DVec3, Vec3};
use shadowmap_frustum::math;

use crate::ParaboloidError;

/// Most directions a cone fit takes (the plan uses 8, the frustum border points).
pub const MAX_CONE_DIRECTIONS: usize = 16;

/// Which cone fit a plan uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ConeFit {
    /// The paper's fit: axis = normalized sum of the unit directions, half-angle = the
    /// largest angle from that axis (Vanek et al., Eqs. 1 and 2). Not minimal.
    Paper,
    /// The exact minimal enclosing cone: axis along the minimum-norm point of the convex
    /// hull of the unit directions.
    #[default]
    Exact,
}

/// A circular cone with its apex at the light: every direction within `half_angle` of
/// `axis` is inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit axis (world space).
    pub axis: Vec3,
    /// Half-angle in radians, in `[0, pi]`. Rounded up after the axis was rounded to
    /// `f32`, so every fitted direction is inside even in `f32`.
    pub half_angle: f32,
}

impl Cone {
    /// Whether `direction` (any length, non-zero) lies inside the cone, up to
    /// `tolerance` radians.
    #[must_use]
    pub fn contains(&self, direction: Vec3, tolerance: f32) -> bool {
        let Some(d) = direction.as_dvec3().try_normalize() else {
            return false;
        };
        angle_between(self.axis.as_dvec3(), d) <= f64::from(self.half_angle) + f64::from(tolerance)
    }

    /// The paraboloid cut (zoom) factor `Z = tan(half_angle / 2)` for this cone, or
    /// `None` when the half-angle is not under 90 degrees (no single paraboloid cut
    /// covers it).
    #[must_use]
    pub fn zoom(&self) -> Option<f32> {
        let h = f64::from(self.half_angle);
        (h < core::f64::consts::FRAC_PI_2).then(|| zoom_for_half_angle(h) as f32)
    }
}

/// Smallest zoom factor any builder produces: cones narrower than about `2e-6` rad are
/// widened to it, so the uv scale `1 / Z` stays finite in `f32`.
pub const MIN_ZOOM: f32 = 1e-6;

/// `tan(half / 2)`, clamped to `[MIN_ZOOM, 1]`.
pub(crate) fn zoom_for_half_angle(half: f64) -> f64 {
    math::tan(0.5 * half).clamp(f64::from(MIN_ZOOM), 1.0)
}

/// Angle between two unit vectors, accurate for tiny and near-straight angles.
pub(crate) fn angle_between(a: DVec3, b: DVec3) -> f64 {
    math::atan2(a.cross(b).length(), a.dot(b))
}

/// A cone in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DCone {
    pub(crate) axis: DVec3,
    pub(crate) half_angle: f64,
}

impl DCone {
    /// The `f32` cone, its half-angle recomputed for the rounded axis and rounded up.
    pub(crate) fn to_f32(self, dirs: &[DVec3]) -> Cone {
        let axis32 = self.axis.as_vec3().normalize_or(Vec3::NEG_Z);
        let axis = axis32.as_dvec3();
        let half = dirs
            .iter()
            .map(|&d| angle_between(axis, d))
            .fold(self.half_angle, f64::max);
        Cone {
            axis: axis32,
            half_angle: round_up_f32(half).min(core::f32::consts::PI),
        }
    }
}

/// The smallest `f32` not below `x` (finite `x`).
pub(crate) fn round_up_f32(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x { next_up(y) } else { y }
}

fn next_up(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f32::from_bits(1);
    }
    let bits = x.to_bits();
    f32::from_bits(if x > 0.0 { bits + 1 } else { bits - 1 })
}

/// The largest angle from `axis` to any direction.
fn max_angle(axis: DVec3, dirs: &[DVec3]) -> f64 {
    dirs.iter()
        .map(|&d| angle_between(axis, d))
        .fold(0.0, f64::max)
}

/// The paper's fit on unit directions; `None` when their sum (nearly) vanishes.
pub(crate) fn paper_fit(dirs: &[DVec3]) -> Option<DCone> {
    let sum: DVec3 = dirs.iter().copied().sum();
    if sum.length().partial_cmp(&(1e-9 * dirs.len() as f64)) != Some(core::cmp::Ordering::Greater) {
        return None;
    }
    let axis = sum.normalize();
    Some(DCone {
        axis,
        half_angle: max_angle(axis, dirs),
    })
}

/// The minimum-norm point of the affine hull of 1, 2 or 3 points, if the set is
/// not degenerate.
fn affine_min_norm(points: &[DVec3]) -> Option<DVec3> {
    match *points {
        [a] => Some(a),
        [a, b] => {
            let e = b - a;
            let ee = e.length_squared();
            (ee > 1e-300).then(|| a + e * (-a.dot(e) / ee))
        }
        [a, b, c] => {
            // The point of the plane closest to the origin, from the plane's normal:
            // well conditioned even for slivers, unlike the 2x2 Gram system.
            let n = (b - a).cross(c - a);
            let nn = n.length_squared();
            let scale = (b - a).length_squared() * (c - a).length_squared();
            (nn > 1e-30 * scale && nn > 1e-300).then(|| n * (n.dot(a) / nn))
        }
        _ => None,
    }
}

/// Half-angles from here up count as "no cone under 90 degrees": `pi/2 - 1e-6`, so that
/// the `f32` half-angle, rounded up, stays under 90 degrees.
pub(crate) const NO_CONE_ANGLE: f64 = core::f64::consts::FRAC_PI_2 - 1e-6;

/// The exact minimal enclosing cone of unit directions, or `None` when no cone under
/// 90 degrees contains them.
///
/// The optimal axis is `p* / |p*|` with `p*` the minimum-norm point of the convex hull
/// of the directions, and `cos(half_angle) = |p*|` (minimax duality). `p*` is the
/// minimum-norm point of the affine hull of its support set (one, two or three
/// directions: it lies on a face of the hull), so the axis is among the axes of the
/// affine minimum-norm points of all subsets of size 1 to 3; the one with the largest
/// smallest cosine is optimal. The paper's axis is a candidate too, so the result is
/// never wider than the paper's cone.
pub(crate) fn minimal_fit(dirs: &[DVec3]) -> Option<DCone> {
    let n = dirs.len();
    let mut best_axis = DVec3::ZERO;
    let mut best_cos = f64::NEG_INFINITY;
    let mut consider = |p: DVec3| {
        let len = p.length();
        // Every direction of the subset has `axis . d = |p|`, so `|p|` bounds the
        // candidate's smallest cosine: skip candidates that cannot win.
        if !(len > 1e-15 && len.is_finite()) || len <= best_cos {
            return;
        }
        let axis = p / len;
        let min_cos = dirs
            .iter()
            .map(|&d| axis.dot(d))
            .fold(f64::INFINITY, f64::min);
        if min_cos > best_cos {
            best_cos = min_cos;
            best_axis = axis;
        }
    };
    let sum: DVec3 = dirs.iter().copied().sum();
    if let Some(axis) = sum.try_normalize() {
        consider(axis);
    }
    for i in 0..n {
        consider(dirs[i]);
        for j in i + 1..n {
            if let Some(p) = affine_min_norm(&[dirs[i], dirs[j]]) {
                consider(p);
            }
            for k in j + 1..n {
                if let Some(p) = affine_min_norm(&[dirs[i], dirs[j], dirs[k]]) {
                    consider(p);
                }
            }
        }
    }
    if best_cos.is_nan() || best_cos <= 0.0 {
        return None;
    }
    let half_angle = max_angle(best_axis, dirs);
    (half_angle < NO_CONE_ANGLE).then_some(DCone {
        axis: best_axis,
        half_angle,
    })
}

/// Checks and normalizes the directions into a fixed array.
fn unit_directions(
    directions: &[Vec3],
) -> Result<arrayvec::ArrayVec<DVec3, MAX_CONE_DIRECTIONS>, ParaboloidError> {
    if directions.is_empty() || directions.len() > MAX_CONE_DIRECTIONS {
        return Err(ParaboloidError::InvalidDirectionCount);
    }
    let mut out = arrayvec::ArrayVec::new();
    for d in directions {
        if !d.is_finite() {
            return Err(ParaboloidError::NonFinite);
        }
        let u = d
            .as_dvec3()
            .try_normalize()
            .ok_or(ParaboloidError::ZeroDirection)?;
        out.push(u);
    }
    Ok(out)
}

/// The paper's light cone (Vanek et al., Eqs. 1 and 2) around `directions` (any
/// non-zero lengths): axis = normalized sum of the unit directions, half-angle = the
/// largest angle from it. The half-angle may reach 180 degrees.
///
/// ```text
/// C = norm(sum_j D_j / |D_j|)        half_angle = max_j angle(D_j, C)
/// ```
///
/// # Errors
/// [`ParaboloidError::InvalidDirectionCount`] for no directions or more than
/// [`MAX_CONE_DIRECTIONS`]; [`ParaboloidError::NonFinite`];
/// [`ParaboloidError::ZeroDirection`] for a zero direction;
/// [`ParaboloidError::DirectionsCancel`] when the unit directions sum to (nearly) zero.
pub fn fit_paper_cone(directions: &[Vec3]) -> Result<Cone, ParaboloidError> {
    let dirs = unit_directions(directions)?;
    let cone = paper_fit(&dirs).ok_or(ParaboloidError::DirectionsCancel)?;
    Ok(cone.to_f32(&dirs))
}

/// The exact minimal cone around `directions` (any non-zero lengths).
///
/// ```text
/// p* = argmin { |p| : p in conv(D_j / |D_j|) }
/// axis = p* / |p*|                   cos(half_angle) = |p*|
/// ```
///
/// No cone under 90 degrees exists exactly when `p* = 0`, i.e. when the origin lies in
/// the convex hull (for frustum border points: when the light lies in the truncated
/// frustum).
///
/// # Errors
/// As [`fit_paper_cone`] (except `DirectionsCancel`), and
/// [`ParaboloidError::NoConeUnder90`] when no cone under 90 degrees contains the
/// directions (cones within `1e-6` rad of 90 degrees count as none).
pub fn fit_minimal_cone(directions: &[Vec3]) -> Result<Cone, ParaboloidError> {
    let dirs = unit_directions(directions)?;
    let cone = minimal_fit(&dirs).ok_or(ParaboloidError::NoConeUnder90)?;
    Ok(cone.to_f32(&dirs))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_directions_give_the_bisector() {
        let c = fit_minimal_cone(&[Vec3::X, Vec3::Y]).unwrap();
        assert!((c.axis - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        assert!((c.half_angle - core::f32::consts::FRAC_PI_4).abs() < 1e-6);
    }

    #[test]
    fn minimal_beats_paper_on_a_skewed_set() {
        // Many directions clustered near X pull the paper's axis away from the middle.
        let dirs = [
            Vec3::X,
            Vec3::new(1.0, 0.01, 0.0),
            Vec3::new(1.0, 0.0, 0.01),
            Vec3::Y,
        ];
        let exact = fit_minimal_cone(&dirs).unwrap();
        let paper = fit_paper_cone(&dirs).unwrap();
        assert!(exact.half_angle < paper.half_angle - 0.1);
        for d in dirs {
            assert!(exact.contains(d, 0.0));
            assert!(paper.contains(d, 0.0));
        }
    }

    #[test]
    fn octahedron_has_no_cone() {
        let dirs = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ];
        assert_eq!(fit_minimal_cone(&dirs), Err(ParaboloidError::NoConeUnder90));
        assert_eq!(
            fit_paper_cone(&dirs),
            Err(ParaboloidError::DirectionsCancel)
        );
    }

    #[test]
    fn bad_input_is_typed() {
        assert_eq!(
            fit_minimal_cone(&[]),
            Err(ParaboloidError::InvalidDirectionCount)
        );
        assert_eq!(
            fit_minimal_cone(&[Vec3::ZERO]),
            Err(ParaboloidError::ZeroDirection)
        );
        assert_eq!(
            fit_paper_cone(&[Vec3::NAN]),
            Err(ParaboloidError::NonFinite)
        );
    }

    #[test]
    fn single_direction_is_a_zero_cone() {
        let c = fit_minimal_cone(&[Vec3::new(0.0, 3.0, 4.0)]).unwrap();
        assert!(c.half_angle < 1e-6);
        assert!(c.zoom().unwrap() >= MIN_ZOOM);
    }
}
