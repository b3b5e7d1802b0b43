//! The four edge rays of a camera's frustum, kept by axis so that the corners of a
//! slice are computed four at a time, and the symmetric pinhole test of the stable
//! fit's closed-form sphere.

use glam::{DMat4, DVec3};

use crate::math::{max_num, min_num};

/// The four edge rays of a frustum in some space, by axis (`origin[axis][ray]`), so
/// that the corners of a slice are computed four at a time.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rays {
    origin: [[f64; 4]; 3],
    dir: [[f64; 4]; 3],
}

impl Rays {
    /// The view-space rays `origin[i] + d * dir[i]` mapped by the affine `m`.
    pub(crate) fn new(m: &DMat4, origin: &[DVec3; 4], dir: &[DVec3; 4]) -> Self {
        let by_axis = |v: &[DVec3; 4]| [0, 1, 2].map(|axis| v.map(|p| p[axis]));
        Self {
            origin: by_axis(origin),
            dir: by_axis(dir),
        }
        .mapped(m, 0..3)
    }

    /// These rays mapped by the affine `m`, for the output axes `axes` only (the
    /// others are left zero: read only those). Four rays at a time, axis by axis, in
    /// the order of operations of `transform_point3` and `transform_vector3`: a frame
    /// change of the world-space rays without a product of matrices.
    #[inline]
    pub(crate) fn mapped(&self, m: &DMat4, axes: core::ops::Range<usize>) -> Self {
        let mut rays = Self {
            origin: [[0.0; 4]; 3],
            dir: [[0.0; 4]; 3],
        };
        let (o, d) = (&self.origin, &self.dir);
        for axis in axes {
            let (x, y, z, w) = (
                m.x_axis[axis],
                m.y_axis[axis],
                m.z_axis[axis],
                m.w_axis[axis],
            );
            rays.origin[axis] =
                core::array::from_fn(|i| w + (z * o[2][i] + (y * o[1][i] + x * o[0][i])));
            rays.dir[axis] = core::array::from_fn(|i| z * d[2][i] + (y * d[1][i] + x * d[0][i]));
        }
        rays
    }

    /// The smallest and largest coordinates of the eight corners at depths `n` and
    /// `f`. (The corners of a checked camera are finite: `min_num` and `max_num`
    /// stand in for the NaN-aware `min` and `max`.) Inline: returned through memory,
    /// its result reached the tight cascade fit through a stalled load.
    #[inline(always)]
    pub(crate) fn bounds(&self, n: f64, f: f64) -> (DVec3, DVec3) {
        let (x, y, z) = (
            self.range(0, n, f),
            self.range(1, n, f),
            self.range(2, n, f),
        );
        (DVec3::new(x.0, y.0, z.0), DVec3::new(x.1, y.1, z.1))
    }

    /// The smallest and largest coordinate `axis` of the eight corners at depths `n`
    /// and `f`. (Inline: a few vector operations, once per slice.)
    #[inline(always)]
    pub(crate) fn range(&self, axis: usize, n: f64, f: f64) -> (f64, f64) {
        let (o, d) = (&self.origin[axis], &self.dir[axis]);
        let near: [f64; 4] = core::array::from_fn(|i| o[i] + d[i] * n);
        let far: [f64; 4] = core::array::from_fn(|i| o[i] + d[i] * f);
        let small: [f64; 4] = core::array::from_fn(|i| min_num(near[i], far[i]));
        let large: [f64; 4] = core::array::from_fn(|i| max_num(near[i], far[i]));
        (
            min_num(min_num(small[0], small[1]), min_num(small[2], small[3])),
            max_num(max_num(large[0], large[1]), max_num(large[2], large[3])),
        )
    }

    /// The largest absolute coordinate of the eight corners at depths `n` and `f`.
    pub(crate) fn max_abs(&self, n: f64, f: f64) -> f64 {
        let (lo, hi) = self.bounds(n, f);
        lo.abs().max(hi.abs()).max_element()
    }
}

/// `t_x^2 + t_y^2` of rays `(±t_x, ±t_y, -1)` from the eye (see
/// `CameraGeometry::symmetric_k`), `None` for any other rays.
pub(crate) fn symmetric_k(origin: &[DVec3; 4], dir: &[DVec3; 4]) -> Option<f64> {
    let a = dir[2];
    let mirrored = [
        DVec3::new(-a.x, -a.y, a.z),
        DVec3::new(a.x, -a.y, a.z),
        a,
        DVec3::new(-a.x, a.y, a.z),
    ];
    let pinhole = origin.iter().all(|o| *o == DVec3::ZERO) && *dir == mirrored;
    (pinhole && a.z == -1.0).then_some(a.x * a.x + a.y * a.y)
}
