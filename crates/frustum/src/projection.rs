//! Projection matrices in `f64`, WebGPU clip space (depth in `[0, 1]`), right-handed
//! (the eye looks down `-Z`), each with a reversed-Z option.
//!
//! With `d = -z` the distance in front of the eye:
//!
//! ```text
//! orthographic   x_ndc = (2x - (r + l)) / (r - l)        depth = (d - n) / (f - n)
//! perspective    x_ndc = (2x/d - (r + l)) / (r - l)      depth = f (d - n) / (d (f - n))
//! ```
//!
//! For perspective `l, r, b, t` are tangents of the side planes (`x/d` at the edges).
//! Reversed-Z swaps the roles of `n` and `f` in the depth row, giving depth 1 at the
//! near plane and 0 at the far plane.

use glam::{DMat4, DVec2, DVec3, DVec4, Vec3};

use crate::math;

/// Orthographic projection of the box `[l, r] x [b, t]` between distances `near` and
/// `far` (`near != far`; either may be negative).
#[must_use]
pub fn orthographic(
    l: f64,
    r: f64,
    b: f64,
    t: f64,
    near: f64,
    far: f64,
    reversed_z: bool,
) -> DMat4 {
    let (scale, offset) =
        orthographic_rows(DVec2::new(l, b), DVec2::new(r, t), near, far, reversed_z);
    DMat4::from_cols(
        DVec4::new(scale.x, 0.0, 0.0, 0.0),
        DVec4::new(0.0, scale.y, 0.0, 0.0),
        DVec4::new(0.0, 0.0, scale.z, 0.0),
        offset,
    )
}

/// `orthographic(l, r, b, t, near, far, reversed_z) * light_from_affine` for an affine
/// `light_from_affine` (last row `0, 0, 0, 1`), without the general product: the
/// orthographic matrix only scales and offsets rows, so each output row is one scaled
/// row of `light_from_affine` plus an offset (the same values the product gives).
#[must_use]
#[allow(clippy::too_many_arguments)] // The orthographic box plus the matrix it applies to.
pub fn orthographic_times_affine(
    l: f64,
    r: f64,
    b: f64,
    t: f64,
    near: f64,
    far: f64,
    reversed_z: bool,
    light_from_affine: &DMat4,
) -> DMat4 {
    let (scale, offset) =
        orthographic_rows(DVec2::new(l, b), DVec2::new(r, t), near, far, reversed_z);
    rows_times_affine(scale, offset, light_from_affine)
}

/// The orthographic matrix of rows `scale`, `offset` ([`orthographic_rows`]) times
/// the affine `m`.
pub(crate) fn rows_times_affine(scale: DVec4, offset: DVec4, m: &DMat4) -> DMat4 {
    DMat4::from_cols(
        m.x_axis * scale,
        m.y_axis * scale,
        m.z_axis * scale,
        m.w_axis * scale + offset,
    )
}

/// The rows of `orthographic(lo.x, hi.x, lo.y, hi.y, near, far, reversed_z)` as a
/// scale and an offset: clip coordinate `i` of a point `p` is
/// `scale[i] * p[i] + offset[i]` (`w`: scale 0, offset 1).
pub(crate) fn orthographic_rows(
    lo: DVec2,
    hi: DVec2,
    near: f64,
    far: f64,
    reversed_z: bool,
) -> (DVec4, DVec4) {
    let (l, r, b, t) = (lo.x, hi.x, lo.y, hi.y);
    let (n, f) = if reversed_z { (far, near) } else { (near, far) };
    let rcp = 1.0 / (n - f);
    let scale = DVec4::new(2.0 / (r - l), 2.0 / (t - b), rcp, 0.0);
    let offset = DVec4::new(-(r + l) / (r - l), -(t + b) / (t - b), rcp * n, 1.0);
    (scale, offset)
}

/// Off-centre perspective from the tangents of the side planes, between distances
/// `0 < near < far`.
#[must_use]
pub fn perspective_off_center(
    l: f64,
    r: f64,
    b: f64,
    t: f64,
    near: f64,
    far: f64,
    reversed_z: bool,
) -> DMat4 {
    let (n, f) = if reversed_z { (far, near) } else { (near, far) };
    let a = f / (n - f);
    DMat4::from_cols(
        DVec4::new(2.0 / (r - l), 0.0, 0.0, 0.0),
        DVec4::new(0.0, 2.0 / (t - b), 0.0, 0.0),
        DVec4::new((r + l) / (r - l), (t + b) / (t - b), a, -1.0),
        DVec4::new(0.0, 0.0, a * n, 0.0),
    )
}

/// Symmetric perspective from a vertical field of view and aspect ratio.
#[must_use]
pub fn perspective(fov_y: f64, aspect: f64, near: f64, far: f64, reversed_z: bool) -> DMat4 {
    let ty = math::tan(0.5 * fov_y);
    let tx = ty * aspect;
    perspective_off_center(-tx, tx, -ty, ty, near, far, reversed_z)
}

/// Symmetric perspective with the far plane at infinity.
#[must_use]
pub fn perspective_infinite(fov_y: f64, aspect: f64, near: f64, reversed_z: bool) -> DMat4 {
    let ty = math::tan(0.5 * fov_y);
    let tx = ty * aspect;
    // Limits of the depth row of `perspective` as far -> infinity.
    let (a, b) = if reversed_z {
        (0.0, near)
    } else {
        (-1.0, -near)
    };
    DMat4::from_cols(
        DVec4::new(1.0 / tx, 0.0, 0.0, 0.0),
        DVec4::new(0.0, 1.0 / ty, 0.0, 0.0),
        DVec4::new(0.0, 0.0, a, -1.0),
        DVec4::new(0.0, 0.0, b, 0.0),
    )
}

/// `view_from_world` looking from `eye` along the unit direction `dir`, with `up` not
/// parallel to `dir` (right-handed, the view looks down `-Z`).
#[must_use]
pub fn look_to(eye: DVec3, dir: DVec3, up: DVec3) -> DMat4 {
    look_to_side(eye, dir, dir.cross(up).normalize())
}

/// [`look_to`] from its unit side axis `s = normalize(dir × up)`.
fn look_to_side(eye: DVec3, dir: DVec3, s: DVec3) -> DMat4 {
    let f = dir;
    let u = s.cross(f);
    DMat4::from_cols(
        DVec4::new(s.x, u.x, -f.x, 0.0),
        DVec4::new(s.y, u.y, -f.y, 0.0),
        DVec4::new(s.z, u.z, -f.z, 0.0),
        DVec4::new(-eye.dot(s), -eye.dot(u), eye.dot(f), 1.0),
    )
}

/// The world axis least aligned with `dir`: an up vector that is never parallel to it.
#[must_use]
pub fn least_aligned_axis(dir: DVec3) -> DVec3 {
    let a = dir.abs();
    if a.x <= a.y && a.x <= a.z {
        DVec3::X
    } else if a.y <= a.z {
        DVec3::Y
    } else {
        DVec3::Z
    }
}

/// Rotation-only light frame looking along the unit direction `dir`, oriented by
/// `up_hint`; when the hint is non-finite, zero or within about 1e-3 rad of `dir`,
/// the world axis least aligned with `dir` orients it instead. It depends only on its
/// arguments, so frames built from it are stable as the camera moves.
#[must_use]
pub fn light_rotation(dir: DVec3, up_hint: Vec3) -> DMat4 {
    light_rotation_inline(dir, up_hint)
}

/// [`light_rotation`], inline where a fit builds its frame once per call: returned
/// from a call, the frame reaches the fit through memory.
#[inline(always)]
pub(crate) fn light_rotation_inline(dir: DVec3, up_hint: Vec3) -> DMat4 {
    // `look_to`'s side axis is `dir × up` normalized, whatever the hint's length: it
    // is taken from the hint as given, normalized once. The hint orients the frame
    // where `|dir × up| > 1e-3 |up|` (the sine of their angle), compared squared; an
    // `f32` hint's squares neither overflow nor vanish in `f64`, and a non-finite
    // hint fails the first comparison.
    let up = up_hint.as_dvec3();
    let side = dir.cross(up);
    let (side2, up2) = (side.length_squared(), up.length_squared());
    if up2 < f64::INFINITY && side2 > 1e-6 * up2 {
        return look_to_side(DVec3::ZERO, dir, side * (1.0 / math::sqrt(side2)));
    }
    look_to(DVec3::ZERO, dir, least_aligned_axis(dir))
}
