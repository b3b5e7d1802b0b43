//! Light cones: the paper's averaged-axis fit and the exact minimal enclosing cone.

use glam::{DVec3, Vec3};
use shadowmap_frustum::math;

use crate::ParaboloidError;

/// Most directions a cone fit takes (the plan uses 8, the frustum border points).
pub const MAX_CONE_DIRECTIONS: usize = 16;

/// Which cone fit a plan uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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

/// Half-angles from here up count as "no cone under 90 degrees": `pi/2 - 1e-6`, so that
/// the `f32` half-angle, rounded up, stays under 90 degrees.
pub(crate) const NO_CONE_ANGLE: f64 = core::f64::consts::FRAC_PI_2 - 1e-6;

/// The minimum-norm point of the plane through three unit directions (the
/// circumcentre of their triangle) if it lies inside the triangle, else `None`.
///
/// From the plane's normal, well conditioned even for slivers. `p*` has strictly
/// positive barycentric weights on its support set, so a triple whose point falls
/// outside its triangle cannot support the minimal cone: this test skips most
/// triples before scoring.
fn triangle_min_norm(a: DVec3, b: DVec3, c: DVec3, best_cos: f64) -> Option<DVec3> {
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let nn = n.length_squared();
    let scale = e1.length_squared() * e2.length_squared();
    if !(nn > 1e-30 * scale && nn > 1e-300) {
        return None;
    }
    let na = n.dot(a);
    // |p| = |n . a| / |n| is the cosine of the subset's own directions with the
    // candidate axis, an upper bound of its score.
    if na * na <= best_cos.max(0.0) * best_cos.abs() * nn {
        return None;
    }
    let p = n * (na / nn);
    let r = p - a;
    let wb = r.cross(e2).dot(n) / nn;
    let wc = e1.cross(r).dot(n) / nn;
    let tol = -1e-9;
    (wb >= tol && wc >= tol && 1.0 - wb - wc >= tol).then_some(p)
}

/// The exact minimal enclosing cone of unit directions, or `None` when no cone under
/// 90 degrees contains them.
///
/// The optimal axis is `p* / |p*|` with `p*` the minimum-norm point of the convex hull
/// of the directions, and `cos(half_angle) = |p*|` (minimax duality). `p*` is the
/// minimum-norm point of the affine hull of its support set (one, two or three
/// directions: it lies on a face of the hull, with positive barycentric weights), so
/// the axis is among the axes of the affine minimum-norm points of all subsets of size
/// 1 to 3 that fall inside their subset; the one with the largest smallest cosine is
/// optimal. The paper's axis is a candidate too, so the result is never wider than
/// the paper's cone. For unit directions the points are the directions themselves, the
/// midpoints of pairs and the circumcentres of triangles; a subset's own directions
/// have cosine `|p|` with its axis, an upper bound that skips a candidate before its
/// `O(n)` scoring.
pub(crate) fn minimal_fit(dirs: &[DVec3]) -> Option<DCone> {
    let n = dirs.len();
    let mut best_axis = DVec3::ZERO;
    let mut best_cos = f64::NEG_INFINITY;
    let mut consider = |p: DVec3, best_cos: &mut f64| {
        let len = p.length();
        if !(len > 1e-15 && len.is_finite()) {
            return;
        }
        let axis = p / len;
        let min_cos = dirs
            .iter()
            .map(|&d| axis.dot(d))
            .fold(f64::INFINITY, f64::min);
        if min_cos > *best_cos {
            *best_cos = min_cos;
            best_axis = axis;
        }
    };
    let sum: DVec3 = dirs.iter().copied().sum();
    if let Some(axis) = sum.try_normalize() {
        consider(axis, &mut best_cos);
    }
    // Singles, then pairs, then triples: the best cosine so far rises before the
    // many triples are bounded against it.
    for &d in dirs {
        consider(d, &mut best_cos);
    }
    for i in 0..n {
        for j in i + 1..n {
            let mid = dirs[i] + dirs[j];
            if 0.5 * mid.length() > best_cos {
                consider(mid, &mut best_cos);
            }
        }
    }
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                if let Some(p) = triangle_min_norm(dirs[i], dirs[j], dirs[k], best_cos) {
                    consider(p, &mut best_cos);
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
