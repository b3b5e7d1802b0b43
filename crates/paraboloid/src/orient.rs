//! The axis of a dual map: where to put the seam of the two paraboloids.
//!
//! A paraboloid stores the direction at angle `theta` from its axis with a linear
//! texel density (texels per radian) proportional to `1 / (1 + cos theta)`: the rim
//! (`theta` = 90 degrees, the seam of a dual map) is twice as dense as the centre. A
//! dual map therefore samples the view best when the directions toward the view lie
//! near the seam, not around the axis. Facing the front paraboloid toward the view
//! puts the view on the sparsest texels of the map, up to half the linear density of
//! a DPSM whose seam happens to pass through the view.
//!
//! The axis is chosen to minimize the largest predicted texel-to-pixel ratio over
//! sample points of the truncated frustum (corners and centres of its near, middle
//! and far cross-sections):
//!
//! ```text
//! cost(a) = max_i (|v_i| + |a . v_i|) / s_i       v_i = P_i - L
//! ```
//!
//! where `|v_i| (1 + |a . v_i| / |v_i|)` is proportional to the world size of a texel at
//! `P_i` and `s_i`, the diagonal of the cross-section through `P_i`, to the world size
//! of a pixel there. The candidates are the `up_hint` axis (a DPSM's fixed
//! orientation, kept on ties) and every axis perpendicular to two sample directions
//! (which puts both on the seam).

use arrayvec::ArrayVec;
use glam::DVec3;
use shadowmap_frustum::math;

use crate::cone::{DCone, zoom_for_half_angle};

/// Number of sample points: 3 cross-sections of 4 corners and a centre.
const SAMPLES: usize = 15;

/// One sample: the vector from the light and the reciprocal pixel size there.
#[derive(Clone, Copy)]
pub(crate) struct Sample {
    v: DVec3,
    length: f64,
    inv_size: f64,
}

/// The predicted largest texel-to-pixel ratio of a dual map with axis `a` (unit).
#[cfg(test)]
pub(crate) fn cost(a: DVec3, samples: &[Sample]) -> f64 {
    cost_below(a, samples, f64::INFINITY)
}

/// `cost`, stopping early (with some value `>= limit`) once it reaches `limit`.
fn cost_below(a: DVec3, samples: &[Sample], limit: f64) -> f64 {
    let mut c = 0.0f64;
    for s in samples {
        c = c.max((s.length + a.dot(s.v).abs()) * s.inv_size);
        if c >= limit {
            break;
        }
    }
    c
}

/// Sample points of the truncated frustum with corners `pts` (near then far).
pub(crate) fn samples(l: DVec3, pts: &[DVec3; 8]) -> ArrayVec<Sample, SAMPLES> {
    let size_n = pts[0].distance(pts[2]);
    let size_f = pts[4].distance(pts[6]);
    let floor = 1e-9 * size_n.max(size_f);
    // The cross-section at the geometric mean depth (perspective: depth grows
    // linearly with the quad size, so the ratio of sizes is the ratio of depths).
    let k = size_f / size_n.max(floor);
    let t_mid = if k.is_finite() {
        1.0 / (math::sqrt(k) + 1.0)
    } else {
        0.5
    };
    let mut out = ArrayVec::new();
    for t in [0.0, t_mid, 1.0] {
        let quad: [DVec3; 4] = core::array::from_fn(|i| pts[i].lerp(pts[i + 4], t));
        let size = (size_n + t * (size_f - size_n)).max(floor);
        let centre = (quad[0] + quad[1] + quad[2] + quad[3]) * 0.25;
        for p in quad.into_iter().chain([centre]) {
            let v = p - l;
            let inv_size = 1.0 / size;
            let length = v.length();
            if v.is_finite() && inv_size.is_finite() && length > floor {
                out.push(Sample {
                    v,
                    length,
                    inv_size,
                });
            }
        }
    }
    out
}

/// The front axis of a dual map at `l` for the truncated frustum `pts` (near then far;
/// BL, BR, TR, TL): the candidate with the smallest [`cost`], signed so the front faces
/// `toward` (else away from `up_hint`). `up_hint` (unit or zero) is the first
/// candidate; `fallback` is returned when nothing else is usable.
pub(crate) fn dual_axis(
    l: DVec3,
    pts: &[DVec3; 8],
    up_hint: DVec3,
    toward: DVec3,
    fallback: DVec3,
) -> DVec3 {
    dual_axis_below(&samples(l, pts), up_hint, toward, fallback, f64::INFINITY)
        .unwrap_or_else(|| facing(fallback, toward, up_hint))
}

/// [`dual_axis`] where its [`cost`] is below `bound`, else `None`, from the
/// [`samples`] of the light and the frustum. The search starts from the bound, so
/// a candidate stops being costed once it reaches it: deciding between one cut
/// paraboloid and a dual map ([`single_cost`]) costs less than finding the dual
/// map's axis.
pub(crate) fn dual_axis_below(
    samples: &[Sample],
    up_hint: DVec3,
    toward: DVec3,
    fallback: DVec3,
    bound: f64,
) -> Option<DVec3> {
    // Every axis costs at least `max_i |v_i| / s_i` (its `|a . v_i|` term is not
    // negative): when that reaches the bound, no candidate can beat it.
    let floor = samples
        .iter()
        .map(|s| s.length * s.inv_size)
        .fold(0.0, f64::max);
    if !(floor < bound) {
        return None;
    }
    let mut best = None;
    let mut best_cost = bound;
    let mut usable = false;
    let mut consider = |a: DVec3| {
        let Some(a) = a.try_normalize() else {
            return;
        };
        usable = true;
        // The running maximum only grows: stop once it cannot win.
        let c = cost_below(a, samples, best_cost);
        if c < best_cost {
            best_cost = c;
            best = Some(a);
        }
    };
    consider(up_hint);
    for (i, a) in samples.iter().enumerate() {
        for b in &samples[i + 1..] {
            let n = a.v.cross(b.v);
            // Skip nearly parallel pairs: their normal is rounding noise.
            if n.length_squared() > 1e-12 * a.v.length_squared() * b.v.length_squared() {
                consider(n);
            }
        }
    }
    // Without any usable candidate, the fallback (if it beats the bound).
    let best = match best {
        Some(a) => a,
        None if !usable && cost_below(fallback, samples, bound) < bound => fallback,
        None => return None,
    };
    Some(facing(best, toward, up_hint))
}

/// `axis` signed so that it faces `toward` (else away from `up_hint`).
fn facing(axis: DVec3, toward: DVec3, up_hint: DVec3) -> DVec3 {
    let s = axis.dot(toward);
    let flip = if s == 0.0 {
        axis.dot(up_hint) > 0.0
    } else {
        s < 0.0
    };
    if flip { -axis } else { axis }
}

/// Side of one paraboloid over the side of each of a dual map's two at the same
/// texel budget (`k` layers of side `sqrt(budget / k)`).
const SINGLE_SIDE_GAIN: f64 = core::f64::consts::SQRT_2;

/// The predicted cost of one cut paraboloid (front axis the cone's, cut to the cone
/// widened by `margin`: `zoom = tan((half_angle + margin) / 2)`) over the
/// [`samples`] of the truncated frustum, comparable with a dual map's [`cost`] at the same texel budget: the
/// cut map samples at least as finely as the dual map unless that map's cost is
/// below it ([`dual_axis_below`]). A cut map's texel at angle `theta` from its
/// axis spans `zoom (1 + cos theta)` times what a dual map's spans at its centre, and
/// it has [`SINGLE_SIDE_GAIN`] times the texels per side:
///
/// ```text
/// single: max_i zoom (|v_i| + a . v_i) / s_i / sqrt(2)
/// dual:   max_i (|v_i| + |a' . v_i|) / s_i          (the cost of `dual_axis`)
/// ```
pub(crate) fn single_cost(samples: &[Sample], cone: DCone, margin: f64) -> f64 {
    let (axis, zoom) = (cone.axis, zoom_for_half_angle(cone.half_angle + margin));
    samples
        .iter()
        .map(|s| zoom * (s.length + axis.dot(s.v)) * s.inv_size)
        .fold(0.0, f64::max)
        / SINGLE_SIDE_GAIN
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frustum looking down -Z from the origin, depths 1 to 10, square, 90 degrees.
    fn frustum() -> [DVec3; 8] {
        let q = |d: f64| {
            [
                DVec3::new(-d, -d, -d),
                DVec3::new(d, -d, -d),
                DVec3::new(d, d, -d),
                DVec3::new(-d, d, -d),
            ]
        };
        let (n, f) = (q(1.0), q(10.0));
        [n[0], n[1], n[2], n[3], f[0], f[1], f[2], f[3]]
    }

    #[test]
    fn the_seam_passes_through_the_view() {
        // Light above the middle of the frustum: the view's directions spread over
        // the lower hemisphere, and the best axis keeps them off the centres.
        let pts = frustum();
        let l = DVec3::new(0.0, 0.0, -5.0);
        let a = dual_axis(l, &pts, DVec3::Y, DVec3::NEG_Z, DVec3::NEG_Z);
        let samples = samples(l, &pts);
        let chosen = cost(a, &samples);
        for other in [
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            DVec3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            assert!(chosen <= cost(other, &samples) + 1e-12, "{a} vs {other}");
        }
        // Facing the view (the old fallback) is strictly worse.
        assert!(chosen < cost(DVec3::Z, &samples) * 0.9);
        assert!((a.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn an_overhead_light_gets_its_seam_through_the_view() {
        let pts = frustum();
        let l = DVec3::new(0.0, 50.0, -5.0);
        let a = dual_axis(l, &pts, DVec3::Y, DVec3::NEG_Y, DVec3::NEG_Z);
        assert!(a.is_finite() && (a.length() - 1.0).abs() < 1e-12);
        assert!(a.dot(DVec3::NEG_Y) >= 0.0);
        let samples = samples(l, &pts);
        assert!(cost(a, &samples) <= cost(DVec3::Y, &samples));
        // A light far above the frustum: the view's directions lie around -Y, so the
        // axis is close to horizontal (the view on the seam).
        assert!(a.dot(DVec3::Y).abs() < 0.2, "{a}");
    }
}
