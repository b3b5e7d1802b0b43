//! Where a box meets a prism swept along a directional light: the part of a caster
//! box that can shadow a footprint, in closed form.

use glam::{DMat4, DVec2, DVec3};

use crate::Aabb;

/// The infinite prism of world points whose light-space `x` and `y` lie in a
/// footprint `[min, max]`: everything a directional light passes through on its way
/// to the footprint. Light space is a rotation of world space (`light_from_world`'s
/// rows), `z` pointing toward the light.
///
/// A fit bounds its casters by the light-space depth range of `caster box ∩ prism`
/// ([`LightPrism::box_depth_range`]); the vertices of that intersection
/// ([`LightPrism::box_vertices`]) are enumerated directly, without clipping one
/// polytope by the other:
/// a vertex is a box corner inside the prism, a box edge crossing a side of the
/// prism, or one of the prism's four edges (lines along the light) crossing a face
/// of the box.
///
/// ```
/// use glam::{DMat4, DVec2, Vec3};
/// use shadowmap_frustum::{Aabb, LightPrism};
///
/// // A light straight down (light-space z is world y): the prism over the
/// // footprint [0, 1]² meets a 10 m tall box between heights 0 and 10.
/// let light_from_world = DMat4::from_cols_array(&[
///     1.0, 0.0, 0.0, 0.0, //
///     0.0, 0.0, 1.0, 0.0, //
///     0.0, -1.0, 0.0, 0.0, //
///     0.0, 0.0, 0.0, 1.0,
/// ]);
/// let prism = LightPrism::new(&light_from_world, DVec2::ZERO, DVec2::ONE);
/// let casters = Aabb::new(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 10.0, 5.0));
/// assert_eq!(prism.box_depth_range(&casters, 1e-9), Some((0.0, 10.0)));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPrism {
    /// Light-space `x`, `y` and `z` of a world point are dot products with these.
    rows: [DVec3; 3],
    min: DVec2,
    max: DVec2,
}

impl LightPrism {
    /// The prism over the light-space footprint `[min, max]`; the upper-left 3x3 of
    /// `light_from_world` must be a rotation.
    #[must_use]
    pub fn new(light_from_world: &DMat4, min: DVec2, max: DVec2) -> Self {
        let m = light_from_world;
        let row = |r: usize| DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]);
        Self {
            rows: [row(0), row(1), row(2)],
            min,
            max,
        }
    }

    /// Light-space `z` (toward the light) of a world point.
    #[must_use]
    pub fn light_z(&self, world: DVec3) -> f64 {
        self.rows[2].dot(world)
    }

    /// Calls `each` with every vertex of `b ∩ prism`, points within `tolerance`
    /// world units of both counting as inside (a vertex may come more than once).
    /// Nothing when they do not meet.
    pub fn box_vertices(&self, b: &Aabb, tolerance: f64, mut each: impl FnMut(DVec3)) {
        let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
        let [rx, ry, rz] = self.rows;
        let tol = tolerance;
        let in_prism_xy = |x: f64, y: f64| {
            x >= self.min.x - tol
                && x <= self.max.x + tol
                && y >= self.min.y - tol
                && y <= self.max.y + tol
        };
        let in_prism = |p: DVec3| in_prism_xy(rx.dot(p), ry.dot(p));
        let in_box = |p: DVec3| {
            p.cmpge(lo - DVec3::splat(tol)).all() && p.cmple(hi + DVec3::splat(tol)).all()
        };
        let corner = |i: usize| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        };
        // The corners' light-space x and y, shared by the edges that end there.
        let light_xy: [[f64; 2]; 8] =
            core::array::from_fn(|i| [rx.dot(corner(i)), ry.dot(corner(i))]);
        let sides = [
            (0, self.min.x),
            (0, self.max.x),
            (1, self.min.y),
            (1, self.max.y),
        ];
        for i in 0..8 {
            let p = corner(i);
            if in_prism_xy(light_xy[i][0], light_xy[i][1]) {
                each(p);
            }
            for bit in [1usize, 2, 4] {
                if i & bit != 0 {
                    continue;
                }
                let q = corner(i | bit);
                for (axis, value) in sides {
                    let (a, c) = (light_xy[i][axis], light_xy[i | bit][axis]);
                    if (a - value) * (c - value) < 0.0 {
                        let x = p + (q - p) * ((value - a) / (c - a));
                        if in_prism(x) {
                            each(x);
                        }
                    }
                }
            }
        }
        for (x, y) in [
            (self.min.x, self.min.y),
            (self.max.x, self.min.y),
            (self.min.x, self.max.y),
            (self.max.x, self.max.y),
        ] {
            // The world line rx x + ry y + rz t (the rows are orthonormal).
            let base = rx * x + ry * y;
            for axis in 0..3 {
                if rz[axis].abs() < 1e-12 {
                    continue;
                }
                for value in [lo[axis], hi[axis]] {
                    let p = base + rz * ((value - base[axis]) / rz[axis]);
                    if p.is_finite() && in_box(p) {
                        each(p);
                    }
                }
            }
        }
    }

    /// The smallest and largest light-space `z` of `b ∩ prism` (see
    /// [`LightPrism::box_vertices`]), `None` when they do not meet.
    #[must_use]
    pub fn box_depth_range(&self, b: &Aabb, tolerance: f64) -> Option<(f64, f64)> {
        let mut range: Option<(f64, f64)> = None;
        self.box_vertices(b, tolerance, |p| {
            let z = self.light_z(p);
            range = Some(range.map_or((z, z), |(lo, hi)| (lo.min(z), hi.max(z))));
        });
        range
    }
}

#[cfg(test)]
mod tests {
    use glam::{DQuat, Vec3};
    use proptest::prelude::*;

    use super::*;

    fn rotation(axis: (f64, f64, f64), angle: f64) -> DMat4 {
        let axis = DVec3::new(axis.0, axis.1, axis.2)
            .try_normalize()
            .unwrap_or(DVec3::Y);
        DMat4::from_quat(DQuat::from_axis_angle(axis, angle))
    }

    proptest! {
        /// Every vertex lies in the box and the prism; every point of the box inside
        /// the prism has its light-space z within the depth range (on a grid of
        /// the box's points); and a box with such a point has a range.
        #[test]
        fn the_depth_range_bounds_the_box_inside_the_prism(
            axis in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            angle in -3.2f64..3.2,
            lo in (-20.0f32..20.0, -20.0f32..20.0, -20.0f32..20.0),
            size in (0.1f32..30.0, 0.1f32..30.0, 0.1f32..30.0),
            foot in (-30.0f64..30.0, -30.0f64..30.0, 0.0f64..30.0, 0.0f64..30.0),
        ) {
            let light_from_world = rotation(axis, angle);
            let min = DVec2::new(foot.0, foot.1);
            let max = min + DVec2::new(foot.2, foot.3);
            let prism = LightPrism::new(&light_from_world, min, max);
            let b = Aabb::new(
                Vec3::new(lo.0, lo.1, lo.2),
                Vec3::new(lo.0 + size.0, lo.1 + size.1, lo.2 + size.2),
            );
            let tol = 1e-9;
            let light = |p: DVec3| light_from_world.transform_point3(p);
            prism.box_vertices(&b, tol, |p| {
                let q = light(p);
                let slack = 1e-6;
                assert!(q.x >= min.x - slack && q.x <= max.x + slack, "{q}");
                assert!(q.y >= min.y - slack && q.y <= max.y + slack, "{q}");
                assert!(p.cmpge(b.min.as_dvec3() - slack).all(), "{p}");
                assert!(p.cmple(b.max.as_dvec3() + slack).all(), "{p}");
            });
            let range = prism.box_depth_range(&b, tol);
            let n = 12;
            for i in 0..=n {
                for j in 0..=n {
                    for k in 0..=n {
                        let t = DVec3::new(f64::from(i), f64::from(j), f64::from(k)) / f64::from(n);
                        // The box's extent in f64: its f32 difference rounds the far
                        // corner off the box by a few ulps.
                        let p = b.min.as_dvec3() + (b.max.as_dvec3() - b.min.as_dvec3()) * t;
                        let q = light(p);
                        if q.x >= min.x && q.x <= max.x && q.y >= min.y && q.y <= max.y {
                            let (z_lo, z_hi) = range.expect("the box meets the prism");
                            prop_assert!(q.z >= z_lo - 1e-6 && q.z <= z_hi + 1e-6);
                        }
                    }
                }
            }
        }
    }
}
