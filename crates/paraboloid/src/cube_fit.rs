//! The focusing geometry of [`CubeMap::fit`](crate::CubeMap::fit): the window of one
//! face on the visible receivers, and its depth range.
//!
//! The visible receivers form a convex body `B` (vertices only). Its part inside a
//! face's pyramid, in front of the near plane `d = n`, projects onto the face plane
//! as the convex polygon
//!
//! ```text
//! proj(B ∩ {d >= n}) ∩ [-1, 1]²        proj(a, b, d) = (a / d, b / d)
//! ```
//!
//! since a central projection maps the convex set `B ∩ {d >= n}` (all in front of
//! the light) to a convex set, and the pyramid is the preimage of the square. The
//! vertices of `B ∩ {d >= n}` are those of `B` with `d >= n` and the points where
//! `B`'s edges cross `d = n`; without `B`'s edges, every vertex pair that crosses the
//! plane is cut there (the chords lie in `B`, and the edges are among them), so the
//! hull is exact. The window is the bounding rectangle of that hull clipped to the
//! square (Sutherland-Hodgman against its four sides).

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3};
use shadowmap_frustum::{Aabb, ConvexBody, Frustum, MAX_BODY_VERTICES};

use crate::cube::FaceAxes;

/// Most projected points of one face: the body's vertices and the crossings of
/// vertex pairs (at most `(V / 2)²` pairs straddle the plane).
const MAX_POINTS: usize = MAX_BODY_VERTICES + (MAX_BODY_VERTICES / 2) * (MAX_BODY_VERTICES / 2);

/// Slack of a window around the projected receivers and past the face's edge, in
/// tangents: covers the rounding of the `f32` body vertices and of the stored
/// window, so a receiver on the window's edge stays inside it.
const WINDOW_MARGIN: f64 = 1.0 / 65536.0;

/// Smallest near plane, relative to the light's range and its coordinates' magnitude:
/// below it the `f32` depth row loses the near-plane term to the translation's rounding
/// (the matrix turns singular) and perspective depth no longer resolves the range.
pub(crate) const NEAR_FLOOR: f64 = 1.0 / 131_072.0;

/// The smallest near plane: `near`, raised to [`NEAR_FLOOR`] times the larger of
/// the range and the light's largest coordinate magnitude.
pub(crate) fn effective_near(near: f32, range: f32, position: glam::Vec3) -> f64 {
    let scale = f64::from(range).max(f64::from(position.abs().max_element()));
    f64::from(near).max(NEAR_FLOOR * scale)
}

type Points = ArrayVec<DVec2, { MAX_POINTS + 8 }>;

/// One face's window and depth range, in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FaceExtent {
    /// Lower-left corner of the window in tangents.
    pub(crate) tan_min: DVec2,
    /// Upper-right corner.
    pub(crate) tan_max: DVec2,
    /// Smallest face depth of the receivers in front of the near plane.
    pub(crate) receivers_min: f64,
    /// Largest.
    pub(crate) receivers_max: f64,
    /// The near plane (set by [`FaceExtent::choose_depth`]).
    pub(crate) near: f64,
    /// The far plane.
    pub(crate) far: f64,
}

impl FaceExtent {
    /// The final window and depth range.
    ///
    /// `near` is the smallest near plane ([`effective_near`]).
    /// Unfocused: the whole face over `[near, range]`, widened by [`WINDOW_MARGIN`]
    /// where the cube is `turned` (its axes are rounded, and a point on the edge
    /// between two faces could land just outside both). Focused: the window
    /// widened by [`WINDOW_MARGIN`] and to at least `min_extent` per axis (about its
    /// centre, kept inside the face), far at the receivers' largest depth (at most
    /// `range`), near at the smallest face depth of the casters (the casters ∩ range
    /// box, given as `casters`) inside the window's frustum up to that far plane,
    /// but no farther than the receivers and no closer than `near`; far at least
    /// `1.001 near` so that `f32` depth resolves the range.
    ///
    /// Taking the casters inside the window, not the whole caster box, keeps the near
    /// plane off the light when the box holds it (a lamp among buildings): the
    /// perspective depth `far (d - near) / ((far - near) d)` spends its precision
    /// near `near`, so a tiny near plane leaves a depth bias of a few `1e-5` metres'
    /// worth at the receivers.
    pub(crate) fn choose_depth(
        &mut self,
        focused: bool,
        turned: bool,
        near: f64,
        range: f64,
        casters: Option<(&Aabb, DVec3, &FaceAxes)>,
        min_extent: f64,
    ) {
        if !focused {
            let whole = if turned { 1.0 + WINDOW_MARGIN } else { 1.0 };
            self.tan_min = DVec2::splat(-whole);
            self.tan_max = DVec2::splat(whole);
            self.near = near;
            self.far = range.max(near * 1.001);
            return;
        }
        let edge = 1.0 + WINDOW_MARGIN;
        let centre = 0.5 * (self.tan_min + self.tan_max);
        let half = (0.5 * (self.tan_max - self.tan_min) + WINDOW_MARGIN)
            .max(DVec2::splat(0.5 * min_extent));
        // Keep the widened window inside the face: shift it back from the edge.
        let centre = centre.clamp(DVec2::splat(-edge) + half, DVec2::splat(edge) - half);
        self.tan_min = (centre - half).max(DVec2::splat(-edge));
        self.tan_max = (centre + half).min(DVec2::splat(edge));
        let receivers_near = self.receivers_min.max(near);
        let far = self.receivers_max.min(range).max(receivers_near * 1.001);
        let casters_min = casters.and_then(|(b, light, face)| {
            casters_min_depth(b, light, face, (self.tan_min, self.tan_max), near, far)
        });
        self.near = casters_min
            .map_or(receivers_near, |c| c.min(receivers_near))
            .max(near);
        self.far = far.max(self.near * 1.001);
    }
}

/// The smallest face depth of `casters` inside the window frustum `window` over
/// `[near, far]`; `None` when no caster is inside it; the whole box's smallest
/// depth when the frustum is too thin for the clipping.
fn casters_min_depth(
    casters: &Aabb,
    light: DVec3,
    face: &FaceAxes,
    window: (DVec2, DVec2),
    near: f64,
    far: f64,
) -> Option<f64> {
    let (lo, hi) = window;
    let (f, u, r) = (face.forward, face.up, face.right);
    let corner = |d: f64, x: f64, y: f64| (light + (r * x + u * y + f) * d).as_vec3();
    let at = |d: f64| {
        [
            corner(d, lo.x, lo.y),
            corner(d, hi.x, lo.y),
            corner(d, hi.x, hi.y),
            corner(d, lo.x, hi.y),
        ]
    };
    let (n, fa) = (at(near), at(far));
    let corners = [n[0], n[1], n[2], n[3], fa[0], fa[1], fa[2], fa[3]];
    let body =
        Frustum::from_corners(corners).and_then(|fr| ConvexBody::from_frustum_aabb(&fr, casters));
    let Ok(body) = body else {
        return Some(min_depth_of_box(casters, light, face));
    };
    // The vertices are `f32`: allow their rounding.
    let scale = body
        .vertices()
        .iter()
        .map(|v| f64::from(v.abs().max_element()))
        .fold(0.0, f64::max);
    body.vertices()
        .iter()
        .map(|v| face.coords(v.as_dvec3() - light).z)
        .reduce(f64::min)
        .map(|d| d - 8.0 * f64::from(f32::EPSILON) * scale)
}

/// The window of `face` on a convex body given by its vertices relative to the
/// light, in front of the plane at face depth `near` (see the module docs); `None`
/// when the body misses the face's pyramid there.
pub(crate) fn face_extent(relative: &[DVec3], face: &FaceAxes, near: f64) -> Option<FaceExtent> {
    let coords: ArrayVec<DVec3, MAX_BODY_VERTICES> = relative
        .iter()
        .take(MAX_BODY_VERTICES)
        .map(|q| face.coords(*q))
        .collect();
    let mut points = Points::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for c in &coords {
        if c.z >= near {
            let _ = points.try_push(DVec2::new(c.x, c.y) / c.z);
            lo = lo.min(c.z);
            hi = hi.max(c.z);
        }
    }
    for (i, a) in coords.iter().enumerate() {
        for b in &coords[i + 1..] {
            if (a.z - near) * (b.z - near) < 0.0 {
                let t = (near - a.z) / (b.z - a.z);
                let p = *a + (*b - *a) * t;
                let _ = points.try_push(DVec2::new(p.x, p.y) / near);
                lo = lo.min(near);
            }
        }
    }
    if points.is_empty() {
        return None;
    }
    let hull = convex_hull(&mut points);
    let clipped = clip_to_square(&hull);
    let first = *clipped.first()?;
    let (tan_min, tan_max) = clipped
        .iter()
        .fold((first, first), |(a, b), p| (a.min(*p), b.max(*p)));
    (tan_min.is_finite() && tan_max.is_finite()).then_some(FaceExtent {
        tan_min,
        tan_max,
        receivers_min: lo,
        receivers_max: hi,
        near: lo,
        far: hi,
    })
}

/// The smallest face depth of a box's corners relative to the light (exact for the
/// box: depth is linear).
pub(crate) fn min_depth_of_box(aabb: &Aabb, light: DVec3, face: &FaceAxes) -> f64 {
    aabb.corners()
        .iter()
        .map(|c| face.coords(c.as_dvec3() - light).z)
        .fold(f64::INFINITY, f64::min)
}

/// Andrew's monotone chain: the hull in counter-clockwise order (sorts `points`).
///
/// Zeros are made positive first: the total order puts `-0.0` before `0.0`, and
/// points on the line `x = 0` split between the two would reach the chain out of
/// order, which drops a hull vertex among them (a receiver straight along a face's
/// axis from a light at the frustum's corner).
fn convex_hull(points: &mut Points) -> Points {
    for p in points.iter_mut() {
        *p += DVec2::ZERO;
    }
    points.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let mut hull = Points::new();
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    for pass in 0..2 {
        let start = hull.len();
        let push = |p: DVec2, hull: &mut Points| {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            let _ = hull.try_push(p);
        };
        if pass == 0 {
            points.iter().for_each(|p| push(*p, &mut hull));
        } else {
            points.iter().rev().for_each(|p| push(*p, &mut hull));
        }
        // The last point of each chain is the first of the next.
        hull.pop();
    }
    if hull.is_empty() {
        // A single (repeated) point.
        if let Some(p) = points.first() {
            let _ = hull.try_push(*p);
        }
    }
    hull
}

/// A convex polygon clipped to `[-1, 1]²` (Sutherland-Hodgman); empty when they do
/// not meet.
fn clip_to_square(polygon: &Points) -> Points {
    let mut current = polygon.clone();
    // Inside when `axis_value * sign <= 1`.
    for (axis, sign) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)] {
        let inside = |p: DVec2| p[axis] * sign <= 1.0;
        let mut next = Points::new();
        let n = current.len();
        for i in 0..n {
            let (p, q) = (current[i], current[(i + 1) % n]);
            if inside(p) {
                let _ = next.try_push(p);
            }
            if inside(p) != inside(q) {
                let t = (sign - p[axis]) / (q[axis] - p[axis]);
                let _ = next.try_push(p + (q - p) * t);
            }
        }
        current = next;
        if current.is_empty() {
            break;
        }
    }
    current
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_with_an_inner_point_is_the_square() {
        let mut pts = Points::new();
        for p in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.5, 0.5)] {
            pts.push(DVec2::new(p.0, p.1));
        }
        let hull = convex_hull(&mut pts);
        assert_eq!(hull.len(), 4);
        assert!(!hull.contains(&DVec2::splat(0.5)));
    }

    /// A light at a corner of the view's far face, the receivers the view's
    /// frustum: the far face's other corner along `-X` lies on the `x = 0` edge of
    /// the `-X` face's hull with crossings of the near plane, some of them at `-0.0`
    /// and some at `0.0`. The window still reaches it.
    #[test]
    fn a_receiver_along_the_face_axis_stays_in_the_window() {
        let relative = [
            [-82.02732, -54.685318, 99.9],
            [-81.86343, -54.685318, 99.9],
            [-81.86343, -54.576057, 99.9],
            [-82.02732, -54.576057, 99.9],
            [-163.89075, -109.26094, 0.0],
            [0.0, -109.26094, 0.0],
            [0.0, -0.000_434_875_5, 0.0],
            [-163.89075, -0.000_434_875_5, 0.0f32],
        ]
        .map(|a| glam::Vec3::from(a).as_dvec3());
        let neg_x = FaceAxes::new(crate::CubeFaceId::NegX, glam::DQuat::IDENTITY);
        let e = face_extent(&relative, &neg_x, 0.003_927_745).expect("in front");
        let along_axis = neg_x.coords(relative[7]);
        assert!(e.tan_max.y >= along_axis.y / along_axis.z, "{e:?}");
    }

    #[test]
    fn clipping_keeps_only_the_part_inside_the_square() {
        let mut tri = Points::new();
        for p in [(0.5, 0.5), (3.0, 0.5), (0.5, 3.0)] {
            tri.push(DVec2::new(p.0, p.1));
        }
        let c = clip_to_square(&tri);
        let (lo, hi) = c
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(a, b), p| {
                (a.min(*p), b.max(*p))
            });
        assert_eq!(lo, DVec2::splat(0.5));
        assert_eq!(hi, DVec2::ONE);
        let mut far = Points::new();
        far.push(DVec2::splat(2.0));
        assert!(clip_to_square(&far).is_empty());
    }

    #[test]
    fn a_body_straddling_the_light_plane_is_cut_at_the_near_plane() {
        // A segment from behind the light to in front, off the axis: the crossing
        // at d = 1 projects to (2, 0) / 1, outside; the front end to (0.2, 0).
        let rel = [DVec3::new(2.0, 0.0, 1.0), DVec3::new(2.0, 0.0, -10.0)];
        // NegZ looks along -Z: d = -z.
        let neg_z = FaceAxes::new(crate::CubeFaceId::NegZ, glam::DQuat::IDENTITY);
        let e = face_extent(&rel, &neg_z, 1.0).expect("in front");
        assert!((e.receivers_max - 10.0).abs() < 1e-12);
        assert!((e.receivers_min - 1.0).abs() < 1e-12);
        // right of NegZ is +X: a = x.
        assert!((e.tan_max.x - 1.0).abs() < 1e-12 && (e.tan_min.x - 0.2).abs() < 1e-12);
    }
}
