//! The orientations a stable cascade's map is (re)chosen among: this frame's and
//! those of the least-area rectangles around its footprint.
//!
//! Of the rectangles around a convex polygon, the one of least area has a side
//! along an edge of the polygon (Freeman and Shapira, *Determining the
//! minimum-area encasing rectangle for an arbitrary closed curve*, Communications
//! of the ACM 18(7), 1975), so the edge directions of the footprint's convex hull
//! across the light are the orientations worth trying. A frame that follows the
//! view instead (the uniform and tight fits') boxes a footprint cut by a room's
//! walls at whatever angle the view makes with them, and pays up to twice the
//! area where the walls run diagonally across the view.

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, Vec3};

use crate::MAX_FRUSTUM_AABB_VERTICES;

/// Most hull vertices (and so candidate orientations besides the frame's own).
pub(crate) const MAX_HULL: usize = MAX_FRUSTUM_AABB_VERTICES;

/// The vertices of the convex hull of `points` seen along the light, in the
/// light frame `light_from_world`, counter-clockwise and without collinear
/// vertices: each with its world point (the hull's extents in any frame about the
/// light are those of every point, reached at its vertices). Andrew's monotone
/// chain; points past [`MAX_HULL`] are ignored.
pub(crate) fn hull_across(
    points: impl Iterator<Item = DVec3>,
    light_from_world: &DMat4,
) -> ArrayVec<(DVec2, DVec3), MAX_HULL> {
    let mut sorted: ArrayVec<(DVec2, DVec3), MAX_HULL> = points
        .take(MAX_HULL)
        .map(|p| (light_from_world.transform_point3(p).truncate(), p))
        .filter(|(q, _)| q.is_finite())
        .collect();
    sorted.sort_unstable_by(|a, b| a.0.x.total_cmp(&b.0.x).then(a.0.y.total_cmp(&b.0.y)));
    // Twice the room of the input: the lower chain, then the upper one.
    let mut hull: ArrayVec<(DVec2, DVec3), { 2 * MAX_HULL }> = ArrayVec::new();
    let turns_left = |h: &ArrayVec<(DVec2, DVec3), { 2 * MAX_HULL }>, keep: usize, q: DVec2| {
        let n = h.len();
        n < keep + 2 || (h[n - 1].0 - h[n - 2].0).perp_dot(q - h[n - 2].0) > 0.0
    };
    for p in &sorted {
        while !turns_left(&hull, 0, p.0) {
            hull.pop();
        }
        hull.push(*p);
    }
    let lower = hull.len();
    for p in sorted.iter().rev().skip(1) {
        while !turns_left(&hull, lower - 1, p.0) {
            hull.pop();
        }
        hull.push(*p);
    }
    // The last point closes the chain on the first.
    hull.pop();
    hull.into_iter().take(MAX_HULL).collect()
}

/// The up vectors (world, for [`light_rotation`](crate::projection::light_rotation))
/// of the frames about the light whose x axis runs along an edge of `hull`
/// (vertices in the frame `light_from_world`): the orientations of the hull's
/// least-area rectangle and its rivals. None for a hull of fewer than three
/// vertices (a footprint seen edge-on has no area to save).
pub(crate) fn edge_ups(
    hull: &[(DVec2, DVec3)],
    light_from_world: &DMat4,
) -> ArrayVec<Vec3, MAX_HULL> {
    let mut ups = ArrayVec::new();
    if hull.len() < 3 {
        return ups;
    }
    // The frame's x and y axes in world space: the rotation's first two rows.
    let row = |i: usize| {
        let m = light_from_world;
        DVec3::new(m.x_axis[i], m.y_axis[i], m.z_axis[i])
    };
    let (x, y) = (row(0), row(1));
    for (i, a) in hull.iter().enumerate() {
        let b = hull[(i + 1) % hull.len()];
        let Some(edge) = (b.0 - a.0).try_normalize() else {
            continue;
        };
        // The new y axis: the edge turned a quarter counter-clockwise.
        let up = (x * -edge.y + y * edge.x).as_vec3();
        if up.is_finite() {
            ups.push(up);
        }
    }
    ups
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::projection::light_rotation;

    fn down() -> DMat4 {
        light_rotation(DVec3::NEG_Y, Vec3::Z)
    }

    #[test]
    fn the_hull_drops_inner_and_collinear_points() {
        let points = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 5.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 3.0),
            DVec3::new(0.0, 1.0, 3.0),
            DVec3::new(1.0, -2.0, 1.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 1.5),
        ];
        let hull = hull_across(points.into_iter(), &down());
        let mut corners: ArrayVec<(i64, i64), MAX_HULL> = hull
            .iter()
            .map(|(_, p)| (p.x.round() as i64, p.z.round() as i64))
            .collect();
        corners.sort_unstable();
        assert_eq!(corners.as_slice(), [(0, 0), (0, 3), (4, 0), (4, 3)]);
        // Counter-clockwise: every turn is to the left.
        for i in 0..hull.len() {
            let (a, b, c) = (hull[i].0, hull[(i + 1) % 4].0, hull[(i + 2) % 4].0);
            assert!((b - a).perp_dot(c - b) > 0.0);
        }
    }

    #[test]
    fn an_edge_frame_boxes_a_turned_rectangle_exactly() {
        // A 6 x 2 rectangle on the ground, turned 30° about the vertical.
        let (s, c) = 30f64.to_radians().sin_cos();
        let corners = [(-3.0, -1.0), (3.0, -1.0), (3.0, 1.0), (-3.0, 1.0)]
            .map(|(u, v): (f64, f64)| DVec3::new(u * c - v * s, 0.0, u * s + v * c));
        let frame = down();
        let hull = hull_across(corners.into_iter(), &frame);
        let ups = edge_ups(&hull, &frame);
        assert_eq!(ups.len(), 4);
        let area = |light: DMat4| {
            let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
            for p in corners {
                let q = light.transform_point3(p).truncate();
                (lo, hi) = (lo.min(q), hi.max(q));
            }
            (hi - lo).x * (hi - lo).y
        };
        assert!(area(frame) > 12.0 * 1.5);
        // Exact but for the up vectors' rounding to f32 (the held frames are
        // rebuilt from them).
        for up in ups {
            let a = area(light_rotation(DVec3::NEG_Y, up));
            assert!((a - 12.0).abs() < 1e-5, "{a}");
        }
    }

    #[test]
    fn a_footprint_seen_edge_on_has_no_candidates() {
        let line = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        let hull = hull_across(line.into_iter(), &down());
        assert!(hull.len() < 3);
        assert!(edge_ups(&hull, &down()).is_empty());
        assert!(hull_across(core::iter::empty(), &down()).is_empty());
    }
}
