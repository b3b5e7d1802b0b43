use arrayvec::ArrayVec;
use glam::{DVec3, Vec3};

use crate::clip::{FrustumBox, MAX_FRUSTUM_AABB_VERTICES, intersect3};
use crate::geometry::DPlane;
use crate::{Aabb, Frustum, FrustumError};

/// Most vertices a [`ConvexBody`] holds.
pub const MAX_BODY_VERTICES: usize = 64;

/// Most bounding planes a [`ConvexBody`] keeps: the 12 of a frustum-box intersection,
/// or, after extrusion, its light-facing planes, one plane per silhouette edge, and
/// the scene box.
const MAX_BODY_PLANES: usize = 48;

/// A convex polyhedron: its vertices and the half-spaces that bound it (fixed
/// capacity, no heap allocation).
///
/// Built as a frustum intersected with a box, optionally extruded toward a
/// directional light and clipped by a scene box: the body `B` of LiSPSM
/// (Wimmer et al. 2004) whose light-space bounds focus a shadow map.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexBody {
    vertices: ArrayVec<Vec3, MAX_BODY_VERTICES>,
    planes: ArrayVec<DPlane, MAX_BODY_PLANES>,
    /// Rounding scale of the coordinates (largest magnitude involved).
    scale: f64,
}

impl ConvexBody {
    /// The vertices of `frustum ∩ aabb`. The body is empty (no vertices) when they
    /// do not meet.
    ///
    /// Every vertex lies inside both (up to rounding), and every corner of either
    /// shape that lies inside the other is a vertex.
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`], [`FrustumError::EmptyBounds`] for an inverted box
    /// or a frustum without volume.
    pub fn from_frustum_aabb(frustum: &Frustum, aabb: &Aabb) -> Result<Self, FrustumError> {
        let planes = frustum.dplanes()?;
        Self::from_frustum_parts(&planes, &frustum.corners.map(Vec3::as_dvec3), aabb)
    }

    /// The vertices of `frustum ∩ aabb` alone, as [`ConvexBody::from_frustum_aabb`]
    /// finds them (the same points in the same order), without the bounding planes:
    /// what a fit needs of the body, in a small fixed array.
    ///
    /// # Errors
    /// As [`ConvexBody::from_frustum_aabb`].
    pub fn frustum_aabb_vertices(
        frustum: &Frustum,
        aabb: &Aabb,
    ) -> Result<ArrayVec<Vec3, MAX_FRUSTUM_AABB_VERTICES>, FrustumError> {
        let planes = frustum.dplanes()?;
        let corners = frustum.corners.map(Vec3::as_dvec3);
        let aabb = aabb.validate()?;
        let mut out = ArrayVec::new();
        frustum_clip(&planes, &corners, &aabb).vertices(&mut out);
        Ok(out)
    }

    /// The vertices of `frustum ∩ aabb` from a frustum's exact `f64` corners (the
    /// builders' path: no `f32` rounding of the corners before clipping), as
    /// [`ConvexBody::frustum_aabb_vertices`] finds them.
    pub(crate) fn dcorners_aabb_vertices(
        corners: &[DVec3; 8],
        aabb: &Aabb,
    ) -> Result<ArrayVec<Vec3, MAX_FRUSTUM_AABB_VERTICES>, FrustumError> {
        let planes = crate::frustum::dplanes(corners, 0.0)?;
        let aabb = aabb.validate()?;
        let mut out = ArrayVec::new();
        frustum_clip(&planes, corners, &aabb).vertices(&mut out);
        Ok(out)
    }

    /// `frustum ∩ aabb` from the frustum's planes and corners (see [`crate::clip`]).
    fn from_frustum_parts(
        fplanes: &[DPlane; 6],
        corners: &[DVec3; 8],
        aabb: &Aabb,
    ) -> Result<Self, FrustumError> {
        let aabb = aabb.validate()?;
        let clip = frustum_clip(fplanes, corners, &aabb);
        let mut planes = ArrayVec::new();
        planes.extend(fplanes.iter().copied());
        planes.extend(aabb.planes().iter().map(DPlane::from_plane));
        let mut body = Self {
            vertices: ArrayVec::new(),
            planes,
            scale: clip.scale,
        };
        clip.vertices(&mut body.vertices);
        Ok(body)
    }

    /// The vertices of the region bounded by `planes`: every triple intersection that
    /// lies inside all of them.
    fn from_planes(planes: ArrayVec<DPlane, MAX_BODY_PLANES>, scale: f64) -> Self {
        // The corners are f32, so a frustum face is planar only to about f32 epsilon
        // times the scale: accept vertices that far outside, and merge closer ones.
        let inside_tol = 8.0 * f64::from(f32::EPSILON) * scale;
        let merge_tol = 2.0 * inside_tol;
        let mut body = Self {
            vertices: ArrayVec::new(),
            planes,
            scale,
        };
        if !(body.planes.len() == 12 && body.two_hexahedra(inside_tol, merge_tol)) {
            body.every_triple(inside_tol, merge_tol);
        }
        body
    }

    /// Adds every triple intersection of the planes that lies inside all of them.
    fn every_triple(&mut self, inside_tol: f64, merge_tol: f64) {
        let n = self.planes.len();
        for i in 0..n {
            let a = self.planes[i];
            // `c × a` for every later plane `c`, shared by all triples that start at `a`.
            let ca: ArrayVec<DVec3, MAX_BODY_PLANES> = self.planes[i + 1..]
                .iter()
                .map(|c| c.normal.cross(a.normal))
                .collect();
            for j in i + 1..n {
                let b = self.planes[j];
                let ab = a.normal.cross(b.normal);
                for k in j + 1..n {
                    let c = &self.planes[k];
                    let Some(p) = intersect3(&a, &b, c, ca[k - i - 1], ab) else {
                        continue;
                    };
                    if self.planes.iter().all(|pl| pl.distance(p) >= -inside_tol) {
                        self.push_unique(p, merge_tol);
                    }
                }
            }
        }
    }

    /// The vertices of the intersection of two hexahedra, each given by three pairs of
    /// opposite planes (`planes[0..6]` and `planes[6..12]`, pairs `(0, 1)`, `(2, 3)`,
    /// `(4, 5)` in each: a frustum or a light-space prism, and a box), without trying
    /// every triple of planes: a vertex of the intersection is a corner of one inside
    /// the other, or an edge of one crossing a face of the other. Each candidate is
    /// the same triple intersection, accepted by the same test, as in the search over
    /// every triple (or on the line of two opposite, non-parallel planes). Corner `c`
    /// of hexahedron `h` lies on planes `6h + (c & 1)`, `6h + 2 + (c >> 1 & 1)` and
    /// `6h + 4 + (c >> 2 & 1)`. Returns `false` (with no vertex added) when a
    /// hexahedron's corners do not lie inside its own planes, i.e. the planes do not
    /// bound a hexahedron.
    fn two_hexahedra(&mut self, inside_tol: f64, merge_tol: f64) -> bool {
        let Some(corners) = self.hexahedron_corners(inside_tol) else {
            return false;
        };
        for (h, hex) in corners.iter().enumerate() {
            self.clip_edges(h, hex, inside_tol, merge_tol);
        }
        // Two opposite planes that are not parallel (a frustum's sides) meet on a line
        // outside the hexahedron, but a point of it can still pass the acceptance test
        // within its tolerance (the eye of a frustum with a tiny near plane): try
        // those triples as well. (Parallel ones, `|a × b| < 1e-12`, never intersect.)
        for i in (0..12).step_by(2) {
            let (a, b) = (self.planes[i].normal, self.planes[i + 1].normal);
            if a.cross(b).length_squared() < 1e-24 {
                continue;
            }
            for k in (0..12).filter(|k| *k != i && *k != i + 1) {
                let triple = if k < i { [k, i, i + 1] } else { [i, i + 1, k] };
                self.push_vertex_of(triple, inside_tol, merge_tol);
            }
        }
        true
    }

    /// The corners of both hexahedra, `None` when one does not lie inside its own
    /// planes.
    fn hexahedron_corners(&self, inside_tol: f64) -> Option<[[DVec3; 8]; 2]> {
        let mut corners = [[DVec3::ZERO; 8]; 2];
        for (h, hex) in corners.iter_mut().enumerate() {
            let own = &self.planes[6 * h..6 * h + 6];
            for (c, corner) in hex.iter_mut().enumerate() {
                let p = self.triple(corner_planes(h, c))?;
                if !own.iter().all(|pl| pl.distance(p) >= -inside_tol) {
                    return None;
                }
                *corner = p;
            }
        }
        Some(corners)
    }

    /// Adds the corners of hexahedron `h` that lie inside the other one, and the
    /// points where its edges cross the other's planes (when inside every plane).
    fn clip_edges(&mut self, h: usize, hex: &[DVec3; 8], inside_tol: f64, merge_tol: f64) {
        let other = 6 * (1 - h);
        let dist: [[f64; 6]; 8] =
            hex.map(|p| core::array::from_fn(|q| self.planes[other + q].distance(p)));
        for (c, (p, d)) in hex.iter().zip(&dist).enumerate() {
            if d.iter().all(|x| *x >= -inside_tol) {
                self.push_unique(*p, merge_tol);
            }
            let [x, y, z] = corner_planes(h, c);
            for (axis, shared) in [(0, [y, z]), (1, [x, z]), (2, [x, y])] {
                let end = c | 1 << axis;
                if end == c {
                    continue;
                }
                // A point of the edge's line is accepted only within `inside_tol` of
                // the planes that end the edge, so at most `inside_tol / s` past its
                // ends (`s` the sine of the angle between edge and end plane), where
                // its distance from any plane differs from the nearer end's by at most
                // as much. (`band` is infinite or NaN for a degenerate edge: then
                // every plane is tried.)
                let u = (hex[end] - *p).normalize_or_zero();
                let ends = (
                    &self.planes[6 * h + 2 * axis],
                    &self.planes[6 * h + 2 * axis + 1],
                );
                let s = ends.0.normal.dot(u).abs().min(ends.1.normal.dot(u).abs());
                let band = inside_tol + inside_tol / s;
                for (q, (da, db)) in d.iter().zip(&dist[end]).enumerate() {
                    if da.min(*db) > band || da.max(*db) < -band {
                        continue;
                    }
                    let k = other + q;
                    let triple = if k < shared[0] {
                        [k, shared[0], shared[1]]
                    } else {
                        [shared[0], shared[1], k]
                    };
                    self.push_vertex_of(triple, inside_tol, merge_tol);
                }
            }
        }
    }

    /// The intersection of planes `i < j < k` ([`intersect3`] on them in that order).
    fn triple(&self, [i, j, k]: [usize; 3]) -> Option<DVec3> {
        let (a, b, c) = (&self.planes[i], &self.planes[j], &self.planes[k]);
        intersect3(a, b, c, c.normal.cross(a.normal), a.normal.cross(b.normal))
    }

    /// Adds the intersection of planes `i < j < k` when it lies inside every plane.
    fn push_vertex_of(&mut self, triple: [usize; 3], inside_tol: f64, merge_tol: f64) {
        if let Some(p) = self.triple(triple) {
            if self.planes.iter().all(|pl| pl.distance(p) >= -inside_tol) {
                self.push_unique(p, merge_tol);
            }
        }
    }

    /// The part of the scene from which light reaches the body: every point `x` of
    /// `scene` such that `x - t u` lies in the body for some `t >= 0`, with `u` the
    /// unit direction toward the light (`-light_direction`). Casters that shadow the
    /// body lie in it.
    ///
    /// Exact, by eliminating `t` (Fourier-Motzkin): with inward planes
    /// `n_i . x + d_i >= 0` of the body and `a_i = n_i . u`,
    ///
    /// ```text
    /// keep       n_i . x + d_i >= 0                                   for a_i >= 0
    /// add        (a_i n_j - a_j n_i) . x + (a_i d_j - a_j d_i) >= 0    for a_i > 0 > a_j
    /// ```
    ///
    /// then clip by the scene box. A pair plane is parallel to `u`; only pairs that
    /// share an edge of the body (its silhouette) are needed, and any pair plane is a
    /// valid bound, so the edge test only saves work.
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`], [`FrustumError::ZeroDirection`],
    /// [`FrustumError::EmptyBounds`].
    pub fn extruded_toward_light(
        &self,
        light_direction: Vec3,
        scene: &Aabb,
    ) -> Result<Self, FrustumError> {
        let scene = scene.validate()?;
        if !light_direction.is_finite() {
            return Err(FrustumError::NonFinite);
        }
        let u = (-light_direction.as_dvec3())
            .try_normalize()
            .ok_or(FrustumError::ZeroDirection)?;
        let scale = self.scale.max(f64::from(
            scene.min.abs().max(scene.max.abs()).max_element(),
        ));
        if self.is_empty() {
            return Ok(Self {
                vertices: ArrayVec::new(),
                planes: ArrayVec::new(),
                scale,
            });
        }
        let tol = 8.0 * f64::from(f32::EPSILON) * scale;
        // A plane whose normal turns away from the light by less than this sweeps
        // less than `tol` across the scene: treat it as parallel.
        let extent = f64::from(scene.size().length()).max(1e-30);
        let parallel = tol / extent;
        // Which planes each vertex lies on, to find the body's edges.
        let tight: ArrayVec<u64, MAX_BODY_VERTICES> = self
            .vertices
            .iter()
            .map(|v| {
                let v = v.as_dvec3();
                self.planes
                    .iter()
                    .enumerate()
                    .filter(|(_, p)| p.distance(v).abs() <= 4.0 * tol)
                    .fold(0u64, |m, (i, _)| m | (1 << i))
            })
            .collect();
        let shares_edge = |i: usize, j: usize| {
            let both = (1u64 << i) | (1u64 << j);
            tight.iter().filter(|m| *m & both == both).count() >= 2
        };
        // The vertices were accepted up to the construction tolerance: relax the planes
        // by as much, so every vertex is inside the region that is swept.
        let relax = 8.0 * f64::from(f32::EPSILON) * self.scale;
        let body_planes: ArrayVec<DPlane, MAX_BODY_PLANES> = self
            .planes
            .iter()
            .map(|p| DPlane {
                normal: p.normal,
                d: p.d + relax,
            })
            .collect();
        let mut planes: ArrayVec<DPlane, MAX_BODY_PLANES> = ArrayVec::new();
        let a: ArrayVec<f64, MAX_BODY_PLANES> =
            body_planes.iter().map(|p| p.normal.dot(u)).collect();
        for (i, p) in body_planes.iter().enumerate() {
            if a[i] >= -parallel {
                push_plane(&mut planes, *p);
            }
        }
        for i in 0..body_planes.len() {
            for j in 0..body_planes.len() {
                if a[i] > parallel && a[j] < -parallel && shares_edge(i, j) {
                    let (pi, pj) = (&body_planes[i], &body_planes[j]);
                    let normal = pj.normal * a[i] - pi.normal * a[j];
                    if normal.length_squared() > 0.0 {
                        push_plane(&mut planes, DPlane::new(normal, pj.d * a[i] - pi.d * a[j]));
                    }
                }
            }
        }
        for p in scene.planes() {
            push_plane(&mut planes, DPlane::from_plane(&p));
        }
        Ok(Self::from_planes(planes, scale))
    }

    /// The vertices.
    #[must_use]
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Whether the body has no vertex (the shapes did not meet).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Whether `p` lies inside every bounding plane, allowing `tolerance` world units.
    /// Always `false` for an empty body.
    #[must_use]
    pub fn contains(&self, p: Vec3, tolerance: f32) -> bool {
        let p = p.as_dvec3();
        !self.is_empty()
            && self
                .planes
                .iter()
                .all(|pl| pl.distance(p) >= -f64::from(tolerance))
    }

    /// The box around the vertices, `None` when empty.
    #[must_use]
    pub fn aabb(&self) -> Option<Aabb> {
        Aabb::from_points(&self.vertices)
    }

    fn push_unique(&mut self, p: DVec3, tol: f64) {
        let p32 = p.as_vec3();
        if !p32.is_finite() {
            return;
        }
        let dup = self
            .vertices
            .iter()
            .any(|v| (v.as_dvec3() - p).abs().max_element() <= tol);
        if !dup {
            // A polyhedron with F faces has at most 2F - 4 vertices, which the
            // capacities allow; ignore overflow rather than panic if rounding ever
            // produced near-duplicates beyond it.
            let _ = self.vertices.try_push(p32);
        }
    }
}

/// The clip of a frustum (planes and corners) by a checked box, with the tolerances
/// of [`ConvexBody::from_planes`]: the rounding scale is the largest coordinate of the
/// frustum's `f32` corners and the box.
fn frustum_clip<'a>(
    planes: &'a [DPlane; 6],
    corners: &'a [DVec3; 8],
    aabb: &Aabb,
) -> FrustumBox<'a> {
    let scale = corners
        .iter()
        .map(|c| c.as_vec3())
        .chain(aabb.corners())
        .map(|c| c.abs().max_element())
        .fold(0.0f32, f32::max)
        .max(f32::MIN_POSITIVE);
    let scale = f64::from(scale);
    let inside_tol = 8.0 * f64::from(f32::EPSILON) * scale;
    FrustumBox {
        corners,
        planes,
        lo: aabb.min.as_dvec3(),
        hi: aabb.max.as_dvec3(),
        inside_tol,
        merge_tol: 2.0 * inside_tol,
        scale,
    }
}

/// The planes through corner `c` of hexahedron `h` (see
/// [`ConvexBody::two_hexahedra`]), ascending: one of each opposite pair, chosen by the
/// bits of `c`.
fn corner_planes(h: usize, c: usize) -> [usize; 3] {
    [
        6 * h + (c & 1),
        6 * h + 2 + (c >> 1 & 1),
        6 * h + 4 + (c >> 2 & 1),
    ]
}

/// Adds a plane unless an equal one is already there (or there is no room: the
/// capacity covers every plane the builders produce).
fn push_plane(planes: &mut ArrayVec<DPlane, MAX_BODY_PLANES>, p: DPlane) {
    let same = planes.iter().any(|q| {
        (q.normal - p.normal).length_squared() < 1e-24
            && (q.d - p.d).abs() < 1e-12 * p.d.abs().max(1.0)
    });
    if !same {
        let _ = planes.try_push(p);
    }
}

#[cfg(test)]
mod tests {
    use super::ConvexBody;
    use crate::Aabb;
    use crate::bounding_sphere::tests::local;
    use proptest::prelude::*;
    use shadowmap_testgen::frustum::body_case;
    use shadowmap_testgen::strategy;

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// The frustum-box clip (edge crossings) finds the vertices the search over
        /// every triple of planes finds, each within the merge tolerance of one of the
        /// other's.
        #[test]
        fn hexahedra_path_matches_every_triple(case in strategy(body_case)) {
            let camera = local(&case.camera);
            let frustum = camera.frustum().unwrap();
            let aabb = Aabb::new(case.aabb.min, case.aabb.max);
            let fast = ConvexBody::from_frustum_aabb(&frustum, &aabb).unwrap();
            let mut slow = ConvexBody { vertices: Default::default(), ..fast.clone() };
            let inside_tol = 8.0 * f64::from(f32::EPSILON) * fast.scale;
            slow.every_triple(inside_tol, 2.0 * inside_tol);
            let near = |a: &ConvexBody, b: &ConvexBody| {
                a.vertices.iter().all(|v| {
                    b.vertices.iter().any(|w| {
                        (v.as_dvec3() - w.as_dvec3()).abs().max_element() <= 4.0 * inside_tol
                    })
                })
            };
            prop_assert_eq!(fast.is_empty(), slow.is_empty());
            prop_assert!(near(&fast, &slow), "{:?}\nvs\n{:?}", fast.vertices, slow.vertices);
            prop_assert!(near(&slow, &fast), "{:?}\nvs\n{:?}", slow.vertices, fast.vertices);
        }
    }
}
