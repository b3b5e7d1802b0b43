use glam::{DMat4, DVec2, DVec3, Mat4, Vec3, Vec4};

use crate::math;

/// Texture coordinates from WebGPU clip coordinates: `u = x/2 + 1/2`, `v = 1/2 - y/2`
/// (texture `v` grows downward), depth unchanged.
pub const UV_FROM_CLIP: Mat4 = Mat4::from_cols(
    Vec4::new(0.5, 0.0, 0.0, 0.0),
    Vec4::new(0.0, -0.5, 0.0, 0.0),
    Vec4::new(0.0, 0.0, 1.0, 0.0),
    Vec4::new(0.5, 0.5, 0.0, 1.0),
);

/// [`UV_FROM_CLIP`] times `m`, row by row: `u = (x + w) / 2`, `v = (w - y) / 2`, as
/// the product computes them (its other terms are exact zeros) in a quarter of the
/// operations.
fn uv_from_clip_times(m: &Mat4) -> Mat4 {
    let col = |c: Vec4| {
        c * Vec4::new(0.5, -0.5, 1.0, 1.0) + Vec4::splat(c.w) * Vec4::new(0.5, 0.5, 0.0, 0.0)
    };
    Mat4::from_cols(col(m.x_axis), col(m.y_axis), col(m.z_axis), col(m.w_axis))
}

/// Where a world point lands in a shadow map: texture coordinates, depth and layer.
///
/// `f64` so that the evaluation harness can take accurate Jacobians.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ShadowSample {
    /// Texture coordinates, `[0, 1]²` inside the map, `v` down.
    pub uv: DVec2,
    /// Depth stored in the map, `[0, 1]` inside the depth range (reversed if the
    /// technique uses reversed-Z).
    pub depth: f64,
    /// Array layer (cascade index, paraboloid side); 0 for single maps.
    pub layer: u32,
}

/// The one trait worth having: a technique maps a world point to where it is stored
/// in the shadow map, so the evaluation harness and the backend treat every
/// technique alike.
pub trait ShadowMapping {
    /// The sample for a world point, `None` where the technique does not cover it
    /// (behind a perspective light, beyond the last cascade, ...).
    fn map_point(&self, world: DVec3) -> Option<ShadowSample>;

    /// How texture coordinates change across a pixel: the central differences
    /// `(uv(around[0]) - uv(around[1])) / 2` and `(uv(around[2]) - uv(around[3])) / 2`
    /// of four points around `centre` (where a pixel's neighbours meet its surface:
    /// the Jacobian of an aliasing error), `None` unless the technique covers all
    /// five points in one layer. The default maps each point with
    /// [`map_point`](Self::map_point) ([`uv_differentials_by_points`]); a projective
    /// technique applies its derivative at `centre` to the half-differences of the
    /// points ([`projective_uv_differentials`]: one division where five mapped
    /// points take fifteen; equal for an affine map, within the square of the step
    /// relative to the light-space depth for a perspective one).
    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        uv_differentials_by_points(self, centre, around)
    }
}

/// [`ShadowMapping::uv_differentials`] from each point mapped with
/// [`ShadowMapping::map_point`].
pub fn uv_differentials_by_points<M: ShadowMapping + ?Sized>(
    mapping: &M,
    centre: DVec3,
    around: &[DVec3; 4],
) -> Option<[DVec2; 2]> {
    let layer = mapping.map_point(centre)?.layer;
    let mut uv = [DVec2::ZERO; 4];
    for (uv, p) in uv.iter_mut().zip(around) {
        let s = mapping.map_point(*p)?;
        if s.layer != layer {
            return None;
        }
        *uv = s.uv;
    }
    Some([(uv[0] - uv[1]) * 0.5, (uv[2] - uv[3]) * 0.5])
}

/// [`ShadowMapping::uv_differentials`] of the projective map `uv_from_world`, for
/// points its layer holds: `None` where [`ShadowMapping::map_point`] would refuse a
/// point (behind the projection centre, `w <= 0`, or not finite), else the
/// derivative at `centre`, `d uv = (d h_xy - uv d h_w) / h_w`, applied to the
/// half-differences of the two pairs of points.
pub fn projective_uv_differentials(
    uv_from_world: &DMat4,
    centre: DVec3,
    around: &[DVec3; 4],
) -> Option<[DVec2; 2]> {
    let m = uv_from_world;
    if !bounded(m, centre, around) {
        mapped_uv_differentials(m, centre, around)
    } else if m.x_axis.w == 0.0 && m.y_axis.w == 0.0 && m.z_axis.w == 0.0 && m.w_axis.w == 1.0 {
        Some(affine_uv_differentials(m, around))
    } else {
        perspective_uv_differentials(m, centre, around)
    }
}

/// Entries and coordinates at most this large: a product of a matrix row and a
/// point is at most `4e200`, finite.
const PRODUCT_BOUND: f64 = 1e100;

/// Whether the entries of `m` and the points are within [`PRODUCT_BOUND`] (a NaN
/// is not).
fn bounded(m: &DMat4, centre: DVec3, around: &[DVec3; 4]) -> bool {
    let bound = glam::DVec4::splat(PRODUCT_BOUND);
    let within = |v: glam::DVec4| v.abs().cmple(bound).all();
    [m.x_axis, m.y_axis, m.z_axis, m.w_axis]
        .into_iter()
        .all(within)
        && core::iter::once(&centre)
            .chain(around)
            .all(|p| within(p.extend(0.0)))
}

/// [`projective_uv_differentials`] in general: the points mapped for their
/// coverage (`w > 0` and finite), the derivative at `centre`.
fn mapped_uv_differentials(
    uv_from_world: &DMat4,
    centre: DVec3,
    around: &[DVec3; 4],
) -> Option<[DVec2; 2]> {
    let covered = |h: glam::DVec4| h.w > 0.0 && h.is_finite();
    let h = *uv_from_world * centre.extend(1.0);
    if !covered(h)
        || !around
            .iter()
            .all(|p| covered(*uv_from_world * p.extend(1.0)))
    {
        return None;
    }
    Some(derivative_at(uv_from_world, h, around))
}

/// [`projective_uv_differentials`] of an affine map (last row exactly `(0, 0, 0,
/// 1)`: the orthographic maps of the uniform fit and the cascades) for entries and
/// points within [`PRODUCT_BOUND`]: every point is covered (`w` is exactly 1 and
/// every product finite), and the derivative is the map's `x` and `y` rows applied
/// to the half-differences (the general form's `uv dw` is a zero and its `1 / w`
/// is 1: the same values, up to the sign of a zero).
fn affine_uv_differentials(m: &DMat4, around: &[DVec3; 4]) -> [DVec2; 2] {
    let column = |a: DVec3, b: DVec3| {
        let dh = *m * ((a - b) * 0.5).extend(0.0);
        DVec2::new(dh.x, dh.y)
    };
    [column(around[0], around[1]), column(around[2], around[3])]
}

/// [`projective_uv_differentials`] of a perspective map for entries and points
/// within [`PRODUCT_BOUND`]: every product is finite, so a point is covered where
/// its `w` is positive, and the four points around need their `w` alone (computed
/// as the product computes it); the centre is mapped.
#[inline(never)]
fn perspective_uv_differentials(
    m: &DMat4,
    centre: DVec3,
    around: &[DVec3; 4],
) -> Option<[DVec2; 2]> {
    let w_of = |p: DVec3| m.x_axis.w * p.x + m.y_axis.w * p.y + m.z_axis.w * p.z + m.w_axis.w;
    let h = *m * centre.extend(1.0);
    if !(h.w > 0.0 && around.iter().all(|p| w_of(*p) > 0.0)) {
        return None;
    }
    Some(derivative_at(m, h, around))
}

/// The derivative of `uv_from_world` at a covered centre it maps to `h`, applied to
/// the half-differences of the two pairs of points `around`.
fn derivative_at(uv_from_world: &DMat4, h: glam::DVec4, around: &[DVec3; 4]) -> [DVec2; 2] {
    let inv_w = 1.0 / h.w;
    let uv = DVec2::new(h.x, h.y) * inv_w;
    let column = |a: DVec3, b: DVec3| {
        let dh = *uv_from_world * ((a - b) * 0.5).extend(0.0);
        (DVec2::new(dh.x, dh.y) - uv * dh.w) * inv_w
    };
    [column(around[0], around[1]), column(around[2], around[3])]
}

/// Which way is "toward the light" for depth bias.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum LightDirection {
    /// A directional light; the vector is the (unit) direction the light travels.
    Directional(Vec3),
    /// A positional light at this world position.
    Position(Vec3),
}

impl LightDirection {
    /// The unit vector from `world` toward the light: against a directional light's
    /// travel, toward a positional light's position; zero at that position (or for
    /// a zero direction).
    #[must_use]
    pub fn toward(self, world: DVec3) -> DVec3 {
        match self {
            Self::Directional(d) => -d.as_dvec3(),
            Self::Position(at) => at.as_dvec3() - world,
        }
        .normalize_or_zero()
    }
}

/// The matrices of a matrix-based shadow technique (uniform, one cascade, spot,
/// LiSPSM, XPSM, TSM).
///
/// `clip_from_world` renders the depth pass; `uv_from_world` is
/// [`UV_FROM_CLIP`] times it, for the lookup (divide by `w` for perspective
/// techniques).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ShadowTransform {
    /// The light's frame: light looks down `-Z`.
    pub light_from_world: Mat4,
    /// Depth pass, WebGPU clip space.
    pub clip_from_world: Mat4,
    /// Lookup, texture space (`uv`, depth, `w`).
    pub uv_from_world: Mat4,
    /// Whether depth runs 1 (near) to 0 (far).
    pub reversed_z: bool,
    /// Where the light is, for bias.
    pub light: LightDirection,
}

impl ShadowTransform {
    /// The transform for a depth-pass matrix; computes `uv_from_world`.
    #[must_use]
    #[inline]
    pub fn new(
        light_from_world: Mat4,
        clip_from_world: Mat4,
        reversed_z: bool,
        light: LightDirection,
    ) -> Self {
        Self {
            light_from_world,
            clip_from_world,
            uv_from_world: uv_from_clip_times(&clip_from_world),
            reversed_z,
            light,
        }
    }

    /// Texture coordinates and depth of a world point (`None` behind a perspective
    /// light, where `w <= 0`).
    #[must_use]
    pub fn project(&self, world: Vec3) -> Option<ShadowSample> {
        project_dmat(&self.uv_from_world.as_dmat4(), world.as_dvec3())
    }

    /// The unit direction toward the light at `world`.
    #[must_use]
    pub fn toward_light(&self, world: Vec3) -> Vec3 {
        match self.light {
            LightDirection::Directional(d) => -d.normalize_or_zero(),
            LightDirection::Position(p) => (p - world).normalize_or_zero(),
        }
    }

    /// The change in stored depth when `world` moves `world_bias` units toward the
    /// light (negative for standard depth, positive for reversed-Z), evaluated through
    /// the full projective mapping, so it is exact for warped techniques too.
    #[must_use]
    pub fn depth_bias(&self, world: Vec3, world_bias: f32) -> Option<f32> {
        let m = self.uv_from_world.as_dmat4();
        let p = world.as_dvec3();
        let moved = p + self.toward_light(world).as_dvec3() * f64::from(world_bias);
        let a = project_dmat(&m, p)?;
        let b = project_dmat(&m, moved)?;
        let bias = (b.depth - a.depth) as f32;
        bias.is_finite().then_some(bias)
    }

    /// World size of one texel at `world` for a map of `resolution²` texels: the
    /// largest extent of the texel's footprint, `1 / (resolution * s_min)` with
    /// `s_min` the smaller singular value of the 2x3 Jacobian `d uv / d world`. Use it
    /// for normal-offset bias. `None` where the mapping is degenerate.
    #[must_use]
    pub fn texel_world_size(&self, world: Vec3, resolution: u32) -> Option<f32> {
        let s = uv_jacobian_singular_values(&self.uv_from_world.as_dmat4(), world.as_dvec3())?;
        let size = 1.0 / (f64::from(resolution) * s.1);
        (size.is_finite() && size > 0.0).then_some(size as f32)
    }
}

impl ShadowMapping for ShadowTransform {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        project_dmat(&self.uv_from_world.as_dmat4(), world)
    }

    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        projective_uv_differentials(&self.uv_from_world.as_dmat4(), centre, around)
    }
}

/// Whether an `f32` matrix is finite and invertible with rows that `f32` can tell
/// apart, for world coordinates of magnitude up to `world_scale`: a nonzero
/// determinant, and no two rows of `m * diag(s, s, s, 1)` (s = `world_scale`) within
/// `1e-6` rad of parallel. That is the failure `f32` rounding produces, e.g. a depth
/// row equal to the `w` row for a tiny near plane far from the origin; scaling by the
/// world's magnitude keeps the test independent of the world's units.
pub fn is_invertible(m: &Mat4, world_scale: f32) -> bool {
    is_invertible_at(m, &[world_scale])
}

/// [`is_invertible`] for world coordinates of each magnitude in `world_scales` (a
/// matrix evaluated over two regions of different reach, e.g. its fitted region and
/// the receivers it is looked up at): the conversion, the finiteness and the
/// determinant made once. `true` for no scales when `m` is finite and invertible.
pub fn is_invertible_at(m: &Mat4, world_scales: &[f32]) -> bool {
    if !m.is_finite() {
        return false;
    }
    let d = m.as_dmat4();
    if !world_scales.iter().all(|&s| rows_apart(&d, s)) {
        return false;
    }
    let det = d.determinant();
    det != 0.0 && det.is_finite()
}

/// No two rows of `d * diag(s, s, s, 1)` (s = `world_scale`) within `1e-6` rad of
/// parallel, and none zero (see [`is_invertible`]).
fn rows_apart(d: &DMat4, world_scale: f32) -> bool {
    use glam::Vec4Swizzles;
    let s = f64::from(world_scale.abs()).max(f64::MIN_POSITIVE);
    let s2 = s * s;
    // The Gram matrix of the scaled rows, `sum_c w_c col_c col_c^T` over the columns
    // (`w_c = s²` for x, y, z and 1 for the translation): its diagonal holds the
    // rows' squared norms, `pairs` the dot products of rows (0, 1), (0, 2), (0, 3),
    // (1, 2) and `pairs_3` those of rows (1, 3), (2, 3).
    let w = d.w_axis;
    let (mut norms, mut pairs, mut pairs_3) = (w * w, w.xxxy() * w.yzwz(), w.yz() * w.ww());
    for c in [d.x_axis, d.y_axis, d.z_axis] {
        norms += c * c * s2;
        pairs += c.xxxy() * c.yzwz() * s2;
        pairs_3 += c.yz() * c.ww() * s2;
    }
    if norms.cmpeq(glam::DVec4::ZERO).any() {
        return false;
    }
    let dots = [pairs.x, pairs.y, pairs.z, pairs.w, pairs_3.x, pairs_3.y];
    let products = [
        norms.x * norms.y,
        norms.x * norms.z,
        norms.x * norms.w,
        norms.y * norms.z,
        norms.y * norms.w,
        norms.z * norms.w,
    ];
    // sin² of the angle between two rows below 1e-12, without a division.
    !dots
        .iter()
        .zip(&products)
        .any(|(dot, nn)| nn - dot * dot < 1e-12 * nn)
}

/// Whether [`is_invertible`] accepts, for every world scale of at least
/// `world_scale`, the `f32` rounding of an orthographic projection (row scales
/// `scale`, offsets `offset`, see `projection::orthographic_rows`) times a rotation,
/// decided from those six numbers alone. `false` means "not certain": run
/// [`is_invertible`] on the matrix.
///
/// Why `true` is certain: the rounded matrix has rows `(a_i (R_i + e_i), o_i)`
/// (`R_i` orthonormal, `|e_i| <= 2^-23` while `1e-30 <= |a_i| <= 1e30`, so no entry
/// leaves the normal range by more than rounding) and the exact last row `(0, 0, 0, 1)`.
/// Scaled by the world scale `s`, with `u_i = o_i / (s a_i)` and `|u_i| <= 64`:
///
/// ```text
/// rows i, j < 3:  cos <= 4e-7 + |u_i u_j| / sqrt((1 + u_i²)(1 + u_j²)) <= 1 - 2e-4
/// rows i, 3:      sin² = 1 / (1 + u_i²) >= 2e-4
/// det = det of the 3x3 block = a_0 a_1 a_2 det(R + E), |det(R + E)| >= 0.99
/// ```
///
/// so every pair of rows is far from parallel (`sin² >= 1e-4 > 1e-12`), the
/// determinant is finite and non-zero, and `1e-60 <= s |a_i| <= 1e60` keeps the
/// squared norms and their products finite and non-zero.
///
/// Inline: a dozen comparisons, once per cascade, where a call costs as much.
#[inline(always)]
pub(crate) fn ortho_rotation_invertible(scale: DVec3, offset: DVec3, world_scale: f64) -> bool {
    // One row at a time, every comparison false for NaN.
    let row = |a: f64, o: f64| {
        let (a, o) = (a.abs(), o.abs());
        let sa = a * world_scale;
        (1e-30..=1e30).contains(&a) & (1e-60..=1e60).contains(&sa) & (o <= 1e30) & (o <= 64.0 * sa)
    };
    row(scale.x, offset.x) & row(scale.y, offset.y) & row(scale.z, offset.z)
}

pub(crate) fn project_dmat(uv_from_world: &DMat4, p: DVec3) -> Option<ShadowSample> {
    let h = *uv_from_world * p.extend(1.0);
    if !(h.w > 0.0 && h.is_finite()) {
        return None;
    }
    Some(ShadowSample {
        uv: DVec2::new(h.x / h.w, h.y / h.w),
        depth: h.z / h.w,
        layer: 0,
    })
}

/// Singular values `(s_max, s_min)` of `d(uv)/d(world)` for a projective map.
pub(crate) fn uv_jacobian_singular_values(m: &DMat4, p: DVec3) -> Option<(f64, f64)> {
    let h = *m * p.extend(1.0);
    if !(h.w > 0.0 && h.is_finite()) {
        return None;
    }
    let row = |r: usize| DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]);
    let (rx, ry, rw) = (row(0), row(1), row(3));
    let w2 = h.w * h.w;
    let du = (rx * h.w - rw * h.x) / w2;
    let dv = (ry * h.w - rw * h.y) / w2;
    // Eigenvalues of J J^T (2x2, symmetric).
    let (a, b, c) = (du.dot(du), du.dot(dv), dv.dot(dv));
    let mean = 0.5 * (a + c);
    let disc = math::sqrt((0.25 * (a - c) * (a - c) + b * b).max(0.0));
    let (l1, l2) = (mean + disc, (mean - disc).max(0.0));
    let (s1, s2) = (math::sqrt(l1), math::sqrt(l2));
    (s1.is_finite() && s2 > 0.0).then_some((s1, s2))
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, Vec3};
    use proptest::prelude::*;

    use super::{is_invertible, ortho_rotation_invertible};
    use crate::projection::{light_rotation, orthographic_rows, rows_times_affine};

    /// `10^e` for a generated exponent: magnitudes from tiny to huge.
    fn magnitude(e: f64) -> f64 {
        10f64.powf(e)
    }

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// The shortcuts of `projective_uv_differentials` for bounded entries and
        /// points give the general form's values and coverage, for affine maps
        /// and perspective ones (points in front of and behind the projection
        /// centre).
        #[test]
        fn the_bounded_shortcuts_are_the_mapped_form(
            rows in proptest::array::uniform12(-1.0f64..1.0),
            scale in -6.0f64..6.0,
            points in proptest::array::uniform15(-1.0f64..1.0),
            reach in -3.0f64..6.0,
            w_row in proptest::array::uniform4(-1.0f64..1.0),
            perspective in any::<bool>(),
        ) {
            let k = magnitude(scale);
            let r = magnitude(reach);
            // A perspective row `w = 1.5 w_3 + row · p / r`: points on both sides.
            let w = if perspective {
                [w_row[0] / r, w_row[1] / r, w_row[2] / r, 1.5 * w_row[3]]
            } else {
                [0.0, 0.0, 0.0, 1.0]
            };
            let m = glam::DMat4::from_cols_array(&[
                rows[0] * k, rows[1] * k, rows[2] * k, w[0],
                rows[3] * k, rows[4] * k, rows[5] * k, w[1],
                rows[6] * k, rows[7] * k, rows[8] * k, w[2],
                rows[9] * k, rows[10] * k, rows[11] * k, w[3],
            ]);
            let p = |i: usize| DVec3::new(points[3 * i], points[3 * i + 1], points[3 * i + 2]) * r;
            let (centre, around) = (p(0), [p(1), p(2), p(3), p(4)]);
            prop_assert!(super::bounded(&m, centre, &around));
            let fast = super::projective_uv_differentials(&m, centre, &around);
            prop_assert_eq!(fast, super::mapped_uv_differentials(&m, centre, &around));
            prop_assert!(perspective || fast.is_some());
        }

        /// Where `ortho_rotation_invertible` is certain, `is_invertible` agrees at
        /// that world scale and above; and an ordinary fit is decided without it.
        #[test]
        fn ortho_rotation_invertible_implies_is_invertible(
            dir in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            center in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            e_center in -40.0f64..40.0,
            e_size in (-40.0f64..40.0, -40.0f64..40.0, -40.0f64..40.0),
            e_scale in -40.0f64..40.0,
            reversed_z: bool,
        ) {
            let Some(dir) = DVec3::new(dir.0, dir.1, dir.2).try_normalize() else {
                return Ok(());
            };
            let rotation = light_rotation(dir, Vec3::Y);
            let c = DVec3::new(center.0, center.1, center.2) * magnitude(e_center);
            let half = DVec3::new(magnitude(e_size.0), magnitude(e_size.1), magnitude(e_size.2));
            let (lo, hi) = (c - half, c + half);
            let (scale, offset) =
                orthographic_rows(lo.truncate(), hi.truncate(), lo.z, hi.z, reversed_z);
            let m = rows_times_affine(scale, offset, &rotation).as_mat4();
            let world = magnitude(e_scale);
            if ortho_rotation_invertible(scale.truncate(), offset.truncate(), world) {
                for s in [world, world * 3.0, world * 1e6] {
                    prop_assert!(is_invertible(&m, s as f32), "{m:?} at {s}");
                }
            }
            // A box of ordinary size around points at most its world scale away.
            let (lo, hi) = (DVec3::new(-3.0, 1.0, -50.0), DVec3::new(7.0, 12.0, -0.5));
            let (scale, offset) =
                orthographic_rows(lo.truncate(), hi.truncate(), lo.z, hi.z, reversed_z);
            prop_assert!(ortho_rotation_invertible(scale.truncate(), offset.truncate(), 50.0));
        }
    }
}
