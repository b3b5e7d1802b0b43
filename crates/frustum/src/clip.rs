//! The vertices of a frustum clipped by an axis-aligned box, without a search over
//! plane triples.
//!
//! A vertex of the intersection of two convex polyhedra lies on three of their faces,
//! two of them from the same polyhedron, so it is a corner of one polyhedron inside the
//! other, or a point where an edge of one crosses a face of the other. With an
//! axis-aligned box the candidates are cheap: a frustum edge crosses a box face where
//! one coordinate reaches a bound (and then lies inside the box when its other two
//! coordinates do), a box edge crosses a frustum face where the signed distances of its
//! ends change sign (and lies inside the frustum when the other five planes agree).
//! Every candidate is a linear interpolation along an edge: 24 corner tests and at most
//! 144 sign tests, against the 220 plane triples of a frustum and a box.

use arrayvec::ArrayVec;
use glam::{DVec3, Vec3};

use crate::geometry::DPlane;

/// Most vertices of a frustum ∩ box that [`ConvexBody::frustum_aabb_vertices`]
/// reports: an intersection of two hexahedra has at most `2 * 12 - 4 = 20`; the rest
/// is room for rounding.
///
/// [`ConvexBody::frustum_aabb_vertices`]: crate::ConvexBody::frustum_aabb_vertices
pub const MAX_FRUSTUM_AABB_VERTICES: usize = 32;

/// Corner index pairs of a frustum's 12 edges (corners in [`Frustum`](crate::Frustum)
/// order: near face 0..4, far face 4..8).
const FRUSTUM_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// The planes (left, right, bottom, top, near, far) that end each edge of
/// [`FRUSTUM_EDGES`] at its first and at its second corner: the one plane of the
/// corner that does not hold the edge.
const EDGE_END_PLANES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (1, 0),
    (3, 2),
    (0, 1),
    (2, 3),
    (1, 0),
    (3, 2),
    (4, 5),
    (4, 5),
    (4, 5),
    (4, 5),
];

/// A frustum (its corners and inward planes) and a box (`lo`, `hi`), with the
/// tolerances of [`ConvexBody`](crate::ConvexBody): a point counts as inside a plane
/// within `inside_tol`, and points closer than `merge_tol` (in every coordinate) are
/// one vertex.
pub(crate) struct FrustumBox<'a> {
    pub(crate) corners: &'a [DVec3; 8],
    pub(crate) planes: &'a [DPlane; 6],
    pub(crate) lo: DVec3,
    pub(crate) hi: DVec3,
    pub(crate) inside_tol: f64,
    pub(crate) merge_tol: f64,
    /// Rounding scale of the coordinates (largest magnitude involved).
    pub(crate) scale: f64,
}

impl FrustumBox<'_> {
    /// Appends the vertices of `frustum ∩ box` to `out` (nothing when they do not meet),
    /// rounded to `f32` and merged within `merge_tol`; non-finite points are skipped.
    ///
    /// The frustum's corners are taken as the triple intersections of its planes, so
    /// every candidate is (up to rounding) one of the points the search over every
    /// plane triple would try, accepted by the same test: inside every plane within
    /// `inside_tol`. Crossings just past an edge's ends are tried as well, as that
    /// search tries them.
    pub(crate) fn vertices<const N: usize>(&self, out: &mut ArrayVec<Vec3, N>) {
        let c = self.plane_corners();
        // Bounding boxes apart by more than the tolerance allows (the planes grown by
        // it reach past the corners near a sharp corner: a wide margin): nothing to clip.
        let margin = DVec3::splat(16.0 * self.inside_tol);
        let (fmin, fmax) = c[1..]
            .iter()
            .fold((c[0], c[0]), |(a, b), p| (a.min(*p), b.max(*p)));
        if !(fmin.cmple(self.hi + margin).all() && fmax.cmpge(self.lo - margin).all()) {
            return;
        }
        let start = out.len();
        let mut push = |p: DVec3| push_unique(out, start, p, self.merge_tol);
        // Frustum corners inside the box. (Even when all are, an edge can cross a
        // box face within the tolerance, and a box corner can pass the test: no early
        // exit.)
        for p in &c {
            if self.in_box(*p) {
                push(*p);
            }
        }
        // Box corners inside the frustum, from their distances to the frustum planes.
        let bc: [DVec3; 8] = core::array::from_fn(|i| {
            DVec3::select(
                glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                self.hi,
                self.lo,
            )
        });
        let dist: [[f64; 6]; 8] = bc.map(|p| core::array::from_fn(|k| self.planes[k].distance(p)));
        for (p, d) in bc.iter().zip(&dist) {
            if d.iter().all(|x| *x >= -self.inside_tol) {
                push(*p);
            }
        }
        self.frustum_edges(&c, &mut push);
        self.box_edges(&bc, &dist, &mut push);
        self.opposite_planes(&c, &mut push);
    }

    /// The box grown by `inside_tol`.
    fn box_with_tolerance(&self) -> (DVec3, DVec3) {
        let tol = DVec3::splat(self.inside_tol);
        (self.lo - tol, self.hi + tol)
    }

    fn in_box(&self, p: DVec3) -> bool {
        let (lo, hi) = self.box_with_tolerance();
        (p.x >= lo.x)
            & (p.y >= lo.y)
            & (p.z >= lo.z)
            & (p.x <= hi.x)
            & (p.y <= hi.y)
            & (p.z <= hi.z)
    }

    fn in_frustum(&self, p: DVec3) -> bool {
        self.planes
            .iter()
            .all(|pl| pl.distance(p) >= -self.inside_tol)
    }

    /// The frustum's corners as triple intersections of its planes (the given corners
    /// where the planes do not meet in a point).
    fn plane_corners(&self) -> [DVec3; 8] {
        let p = &self.planes;
        // The cross products of the side, bottom/top and near/far normals, each shared
        // by the two corners on both planes.
        let n = |k: usize| p[k].normal;
        let xy: [[DVec3; 2]; 2] =
            core::array::from_fn(|x| core::array::from_fn(|y| n(x).cross(n(2 + y))));
        let yz: [[DVec3; 2]; 2] =
            core::array::from_fn(|y| core::array::from_fn(|z| n(2 + y).cross(n(4 + z))));
        let zx: [[DVec3; 2]; 2] =
            core::array::from_fn(|z| core::array::from_fn(|x| n(4 + z).cross(n(x))));
        core::array::from_fn(|i| {
            let (x, y, z) = ([0, 1, 1, 0][i & 3], i >> 1 & 1, i >> 2);
            let (a, b, c) = (&p[x], &p[2 + y], &p[4 + z]);
            intersect3_crossed(a, b, c, yz[y][z], zx[z][x], xy[x][y]).unwrap_or(self.corners[i])
        })
    }

    /// Points where a frustum edge's line crosses a box face, inside the box; past the
    /// edge's ends only when inside the frustum as well. Past end `p` the line leaves
    /// the frustum through the plane that ends the edge there, at a rate of `L` (the
    /// other end's distance from that plane) per unit of the edge parameter, so only
    /// crossings within `tol / L` of an end can pass (twice that is tried).
    fn frustum_edges(&self, c: &[DVec3; 8], push: &mut impl FnMut(DVec3)) {
        let bounds = [self.lo.to_array(), self.hi.to_array()];
        for (&(i, j), &(end_i, end_j)) in FRUSTUM_EDGES.iter().zip(&EDGE_END_PLANES) {
            let (p, q) = (c[i], c[j]);
            let (pa, qa) = (p.to_array(), q.to_array());
            // The range past the ends, needed only for crossings off the edge.
            let mut range = None;
            let mut past = || {
                *range.get_or_insert_with(|| {
                    (
                        -2.0 * self.inside_tol / self.planes[end_i].distance(q),
                        1.0 + 2.0 * self.inside_tol / self.planes[end_j].distance(p),
                    )
                })
            };
            for axis in 0..3 {
                for v in [bounds[0][axis], bounds[1][axis]] {
                    let (dp, dq) = (pa[axis] - v, qa[axis] - v);
                    if dp == dq {
                        continue;
                    }
                    let t = dp / (dp - dq);
                    let on_edge = (0.0..=1.0).contains(&t);
                    // Written so that NaN bounds (an edge of length 0) skip too.
                    if !on_edge {
                        let (before, after) = past();
                        if !(t >= before && t <= after) {
                            continue;
                        }
                    }
                    let mut x = (p + (q - p) * t).to_array();
                    x[axis] = v;
                    let x = DVec3::from(x);
                    if self.in_box(x) && (on_edge || self.in_frustum(x)) {
                        push(x);
                    }
                }
            }
        }
    }

    /// Points where a box edge's line crosses a frustum face, inside the frustum and
    /// (past the edge's ends, by at most twice the tolerance) the box. The distances
    /// of a point of the edge to the frustum planes are interpolated from its ends'.
    fn box_edges(&self, bc: &[DVec3; 8], dist: &[[f64; 6]; 8], push: &mut impl FnMut(DVec3)) {
        let (lo, hi) = (self.lo.to_array(), self.hi.to_array());
        for axis in 0..3 {
            let slack = 2.0 * self.inside_tol / (hi[axis] - lo[axis]);
            for i in (0..8).filter(|i| i & 1 << axis == 0) {
                let j = i | 1 << axis;
                let (dist_i, dist_j) = (&dist[i], &dist[j]);
                for k in 0..6 {
                    let (di, dj) = (dist_i[k], dist_j[k]);
                    if di == dj {
                        continue;
                    }
                    let t = di / (di - dj);
                    if !(t >= -slack && t <= 1.0 + slack) {
                        continue;
                    }
                    let inside = (0..6).all(|m| {
                        let (a, b) = (dist_i[m], dist_j[m]);
                        a + (b - a) * t >= -self.inside_tol
                    });
                    if inside {
                        let (a, b) = (bc[i].to_array(), bc[j].to_array());
                        let mut x = a;
                        x[axis] += (b[axis] - a[axis]) * t;
                        let x = DVec3::from(x);
                        if self.in_box(x) {
                            push(x);
                        }
                    }
                }
            }
        }
    }

    /// Two opposite frustum planes that are not parallel (its sides) meet on a line
    /// outside the frustum, but a point of it can still pass the acceptance test within
    /// its tolerance (the eye of a frustum with a tiny near face). Tried only when a
    /// corner on one of the two lies that close to the other.
    fn opposite_planes(&self, c: &[DVec3; 8], push: &mut impl FnMut(DVec3)) {
        let near = 16.0 * self.inside_tol;
        for i in (0..6).step_by(2) {
            let (a, b) = (&self.planes[i], &self.planes[i + 1]);
            let ab = a.normal.cross(b.normal);
            let close = c.iter().any(|p| a.distance(*p) + b.distance(*p) <= near);
            if !close || ab.length_squared() < 1e-24 {
                continue;
            }
            let others = self
                .planes
                .iter()
                .enumerate()
                .filter(|(k, _)| k / 2 != i / 2);
            let box_planes = box_planes(self.lo, self.hi);
            for k_plane in others.map(|(_, pl)| pl).chain(&box_planes) {
                let ca = k_plane.normal.cross(a.normal);
                if let Some(x) = intersect3(a, b, k_plane, ca, ab)
                    && self.in_frustum(x)
                    && self.in_box(x)
                {
                    push(x);
                }
            }
        }
    }
}

/// The six inward planes of the box `lo..hi` (`-x`, `+x`, `-y`, `+y`, `-z`, `+z`).
fn box_planes(lo: DVec3, hi: DVec3) -> [DPlane; 6] {
    [
        DPlane::new(DVec3::X, -lo.x),
        DPlane::new(DVec3::NEG_X, hi.x),
        DPlane::new(DVec3::Y, -lo.y),
        DPlane::new(DVec3::NEG_Y, hi.y),
        DPlane::new(DVec3::Z, -lo.z),
        DPlane::new(DVec3::NEG_Z, hi.z),
    ]
}

/// Intersection point of three planes, `None` when (nearly) dependent; `ca` and `ab`
/// are the cross products `c × a` and `a × b` of their normals (shared between
/// triples by the caller).
pub(crate) fn intersect3(
    a: &DPlane,
    b: &DPlane,
    c: &DPlane,
    ca: DVec3,
    ab: DVec3,
) -> Option<DVec3> {
    intersect3_crossed(a, b, c, b.normal.cross(c.normal), ca, ab)
}

/// [`intersect3`] with all three cross products given (`bc = b × c` as well).
fn intersect3_crossed(
    a: &DPlane,
    b: &DPlane,
    c: &DPlane,
    bc: DVec3,
    ca: DVec3,
    ab: DVec3,
) -> Option<DVec3> {
    let det = a.normal.dot(bc);
    if det.abs() < 1e-12 {
        return None;
    }
    let p = (bc * -a.d + ca * -b.d + ab * -c.d) / det;
    p.is_finite().then_some(p)
}

/// Appends `p` (rounded to `f32`) unless it is not finite or lies within `tol` of a
/// point of `out[start..]` in every coordinate. Overflow is ignored: the capacity
/// holds every vertex an intersection can have.
fn push_unique<const N: usize>(out: &mut ArrayVec<Vec3, N>, start: usize, p: DVec3, tol: f64) {
    let p32 = p.as_vec3();
    if !p32.is_finite() {
        return;
    }
    let dup = out[start..]
        .iter()
        .any(|v| (v.as_dvec3() - p).abs().max_element() <= tol);
    if !dup {
        let _ = out.try_push(p32);
    }
}
