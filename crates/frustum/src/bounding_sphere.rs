//! The rotation-invariant bounding sphere of a frustum slice, used by the stable
//! cascade fit.

use glam::DVec3;

use crate::math;

/// The minimal bounding sphere of a slice among those centred on the segment between
/// its near and far face centroids, from its view-space corners. It depends only on
/// the projection and the depths, never on the camera's pose, so its radius is exactly
/// invariant under camera rotation.
///
/// With `c(t)` the point at `t` along the segment `d` (from the near centroid `c_n`
/// to the far centroid `c_f`) and `p_i` the corners, the squared distances share
/// their quadratic term:
///
/// ```text
/// |c(t) - p_i|^2 = |d|^2 t^2 - 2 t d.(p_i - c_n) + |p_i - c_n|^2
/// ```
///
/// so their maximum is `|d|^2 t^2` plus an upper envelope of lines, a convex function.
/// When the segment is perpendicular to both faces and each face's corners are
/// equidistant from its centroid (every symmetric perspective slice and every
/// orthographic one), only two of those lines differ and the minimum is closed-form:
///
/// ```text
/// t = clamp((|d|^2 + r_f^2 - r_n^2) / (2 |d|^2), 0, 1)
/// ```
///
/// `r_n`, `r_f` the face radii. For a symmetric perspective slice with half-angle
/// tangents `t_x`, `t_y` between depths `n` and `f` that is the centre depth
/// `min(f, (n + f) (1 + t_x^2 + t_y^2) / 2)`. Other slices (an off-centre custom
/// projection) take the exact minimum of the envelope: the least of its values at
/// the segment's ends, at each line's own vertex and at each crossing of two lines.
/// Either way the radius is the distance to the farthest corner, so the sphere
/// encloses the slice.
pub(crate) fn bounding_sphere(corners: &[DVec3; 8]) -> (DVec3, f64) {
    let near_c = (corners[0] + corners[1] + corners[2] + corners[3]) * 0.25;
    let far_c = (corners[4] + corners[5] + corners[6] + corners[7]) * 0.25;
    let d = far_c - near_c;
    let dd = d.length_squared();
    let farthest = |c: DVec3| {
        corners
            .iter()
            .map(|p| p.distance_squared(c))
            .fold(0.0, f64::max)
    };
    if !(dd > 0.0) {
        return (near_c, math::sqrt(farthest(near_c)));
    }
    let t = match two_face_parameter(corners, near_c, far_c, d, dd) {
        Some(t) => t,
        None => envelope_minimum(corners, near_c, d, dd),
    };
    let center = near_c + d * t;
    (center, math::sqrt(farthest(center)))
}

/// [`bounding_sphere`] of the slice between view depths `near < far` of a symmetric
/// pinhole camera: every ray from the eye, corner `(±t_x d, ±t_y d, -d)` at depth `d`,
/// `k = t_x^2 + t_y^2`. Returns the centre's view depth (the centre lies on the view
/// axis) and the radius, from the closed form of [`bounding_sphere`] without the
/// corners:
///
/// ```text
/// c = min(f, (n + f)(1 + k) / 2)      r^2 = max(k n^2 + (c - n)^2, k f^2 + (f - c)^2)
/// ```
///
/// (the two distances are equal unless `c` is clamped to `f`).
pub(crate) fn symmetric_slice_sphere(k: f64, near: f64, far: f64) -> (f64, f64) {
    // Finite depths of a checked camera: no NaN for `min_num` and `max_num`.
    let c = math::min_num(0.5 * (near + far) * (1.0 + k), far);
    let (dn, df) = (c - near, far - c);
    let r2 = math::max_num(k * near * near + dn * dn, k * far * far + df * df);
    (c, math::sqrt(r2))
}

/// The closed-form parameter of [`bounding_sphere`] when the segment is perpendicular
/// to both faces and each face's corners are equidistant from its centroid (to a
/// relative `1e-12`); `None` otherwise.
fn two_face_parameter(
    corners: &[DVec3; 8],
    near_c: DVec3,
    far_c: DVec3,
    d: DVec3,
    dd: f64,
) -> Option<f64> {
    const TOL: f64 = 1e-12;
    let mut r2 = [(f64::INFINITY, 0.0f64); 2];
    let mut skew = 0.0f64;
    for (i, p) in corners.iter().enumerate() {
        let e = *p - if i < 4 { near_c } else { far_c };
        let e2 = e.length_squared();
        let r = &mut r2[i / 4];
        *r = (r.0.min(e2), r.1.max(e2));
        skew = skew.max(d.dot(e).abs());
    }
    let scale = dd.max(r2[0].1).max(r2[1].1);
    let equidistant = r2.iter().all(|(lo, hi)| hi - lo <= TOL * scale);
    // |d.e| <= |d| |e| sin(tolerance): compare squares to avoid a root.
    if !(equidistant && skew * skew <= TOL * TOL * dd * scale) {
        return None;
    }
    Some(((dd + r2[1].1 - r2[0].1) / (2.0 * dd)).clamp(0.0, 1.0))
}

/// The exact minimizer over `t` in `[0, 1]` of `dd t^2 + max_i (a_i t + b_i)`, the
/// farthest-corner squared distance along the centroid segment (see
/// [`bounding_sphere`]).
fn envelope_minimum(corners: &[DVec3; 8], near_c: DVec3, d: DVec3, dd: f64) -> f64 {
    let lines: [(f64, f64); 8] = core::array::from_fn(|i| {
        let e = corners[i] - near_c;
        (-2.0 * d.dot(e), e.length_squared())
    });
    let value = |t: f64| {
        dd * t * t
            + lines
                .iter()
                .map(|(a, b)| a * t + b)
                .fold(f64::MIN, f64::max)
    };
    let mut best = (value(0.0), 0.0);
    let mut consider = |t: f64| {
        if (0.0..=1.0).contains(&t) {
            let v = value(t);
            if v < best.0 {
                best = (v, t);
            }
        }
    };
    consider(1.0);
    for (i, (ai, bi)) in lines.iter().enumerate() {
        consider(-ai / (2.0 * dd));
        for (aj, bj) in &lines[i + 1..] {
            if ai != aj {
                consider((bj - bi) / (ai - aj));
            }
        }
    }
    best.1
}

/// The previous bounding-sphere search: an 80-step ternary search along the centroid
/// segment. Kept as the reference the closed form is tested against.
#[cfg(test)]
pub(crate) fn bounding_sphere_search(corners: &[DVec3; 8]) -> (DVec3, f64) {
    let near_c = (corners[0] + corners[1] + corners[2] + corners[3]) * 0.25;
    let far_c = (corners[4] + corners[5] + corners[6] + corners[7]) * 0.25;
    let radius_at = |t: f64| {
        let c = near_c.lerp(far_c, t);
        corners
            .iter()
            .map(|p| p.distance_squared(c))
            .fold(0.0, f64::max)
    };
    let (mut a, mut b) = (0.0f64, 1.0f64);
    for _ in 0..80 {
        let m1 = a + (b - a) / 3.0;
        let m2 = b - (b - a) / 3.0;
        if radius_at(m1) <= radius_at(m2) {
            b = m2;
        } else {
            a = m1;
        }
    }
    let t = 0.5 * (a + b);
    (near_c.lerp(far_c, t), math::sqrt(radius_at(t)))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::{bounding_sphere, bounding_sphere_search, symmetric_slice_sphere};
    use glam::DVec3;
    use proptest::prelude::*;
    use shadowmap_testgen::{arbitrary::Unstructured, camera, in_range, strategy};

    /// This crate's camera from the generators' (they link the library build).
    pub(crate) fn local(c: &shadowmap_testgen::frustum::built::Camera) -> crate::Camera {
        use crate::Projection as P;
        use shadowmap_testgen::frustum::built::Projection as Q;
        let projection = match c.projection {
            Q::Perspective {
                fov_y,
                aspect,
                near,
                far,
            } => P::Perspective {
                fov_y,
                aspect,
                near,
                far,
            },
            Q::InfinitePerspective {
                fov_y,
                aspect,
                near,
                shadow_distance,
            } => P::InfinitePerspective {
                fov_y,
                aspect,
                near,
                shadow_distance,
            },
            Q::Orthographic {
                left,
                right,
                bottom,
                top,
                near,
                far,
            } => P::Orthographic {
                left,
                right,
                bottom,
                top,
                near,
                far,
            },
            Q::Custom {
                clip_from_view,
                shadow_distance,
            } => P::Custom {
                clip_from_view,
                shadow_distance,
            },
        };
        crate::Camera {
            world_from_view: c.world_from_view,
            projection,
            reversed_z: c.reversed_z,
        }
    }

    /// View-space corners of a random slice of a random valid camera (any projection,
    /// near-degenerate ones included).
    fn slice_corners(u: &mut Unstructured<'_>) -> shadowmap_testgen::GenResult<[DVec3; 8]> {
        slice(u).map(|(g, n, f)| g.view_corners(n, f))
    }

    /// A random valid camera's geometry and a slice `(near, far)` of its depth range.
    fn slice(
        u: &mut Unstructured<'_>,
    ) -> shadowmap_testgen::GenResult<(crate::camera::CameraGeometry, f64, f64)> {
        let camera = local(&camera(u)?);
        let g = camera
            .geometry()
            .map_err(|_| shadowmap_testgen::arbitrary::Error::IncorrectFormat)?;
        let a = f64::from(in_range(u, 0.0, 1.0)?);
        let b = f64::from(in_range(u, 0.0, 1.0)?);
        let (a, b) = (a.min(b), a.max(b).max(a.min(b) + 1e-3).min(1.0));
        let depth = |t: f64| g.near + (g.far - g.near) * t;
        let (n, f) = (depth(a), depth(b));
        if !(f > n) {
            return Err(shadowmap_testgen::arbitrary::Error::IncorrectFormat);
        }
        Ok((g, n, f))
    }

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// The closed form (or the exact envelope minimum) gives the search's sphere:
        /// the same radius within 1e-6 relative, and it encloses every corner.
        #[test]
        fn bounding_sphere_matches_search(corners in strategy(slice_corners)) {
            let (c, r) = bounding_sphere(&corners);
            let (c_ref, r_ref) = bounding_sphere_search(&corners);
            prop_assert!(r.is_finite() && r > 0.0);
            prop_assert!((r - r_ref).abs() <= 1e-6 * r_ref, "{r} vs {r_ref}");
            let scale = corners.iter().map(|p| p.length()).fold(r, f64::max);
            prop_assert!((c - c_ref).length() <= 1e-3 * scale + 1e-6 * scale, "{c} vs {c_ref}");
            for p in &corners {
                prop_assert!(p.distance(c) <= r * (1.0 + 1e-12));
            }
        }
    }

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// The symmetric pinhole closed form (no corners) gives the sphere of
        /// `bounding_sphere` on the slice's corners, to rounding.
        #[test]
        fn symmetric_slice_sphere_matches_corners((g, n, f) in strategy(slice)) {
            if let Some(k) = g.symmetric_k {
                let (depth, r) = symmetric_slice_sphere(k, n, f);
                let (c, r_ref) = bounding_sphere(&g.view_corners(n, f));
                prop_assert!((r - r_ref).abs() <= 1e-12 * r_ref, "{r} vs {r_ref}");
                prop_assert!((-c.z - depth).abs() <= 1e-12 * r_ref, "{depth} vs {c}");
                prop_assert!(c.x == 0.0 && c.y == 0.0, "{c}");
            }
        }
    }

    /// The symmetric closed form: centre depth `min(f, (n + f)(1 + tx^2 + ty^2) / 2)`.
    #[test]
    fn symmetric_slice_centre_depth() {
        let (tx, ty) = (0.7f64, 0.4f64);
        let k = tx * tx + ty * ty;
        for (n, f) in [(0.1, 10.0), (8.0, 24.7), (50.0, 60.0), (1.0, 1000.0)] {
            let corner = |d: f64, sx: f64, sy: f64| DVec3::new(sx * tx * d, sy * ty * d, -d);
            let signs = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            let corners: [DVec3; 8] = core::array::from_fn(|i| {
                let (sx, sy) = signs[i % 4];
                corner(if i < 4 { n } else { f }, sx, sy)
            });
            let (c, r) = bounding_sphere(&corners);
            let depth = f64::min(f, (n + f) * (1.0 + k) / 2.0);
            assert!((-c.z - depth).abs() < 1e-9 * f, "{n} {f}: {c}");
            assert!(c.x.abs() < 1e-12 && c.y.abs() < 1e-12);
            let expect = ((f - depth).powi(2) + f * f * k).sqrt();
            assert!((r - expect).abs() < 1e-9 * f, "{r} vs {expect}");
        }
    }
}
