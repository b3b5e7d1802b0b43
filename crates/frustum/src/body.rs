use arrayvec::ArrayVec;
use glam::{DVec3, Vec3};

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
        Self::from_planes_aabb(&frustum.dplanes()?, &frustum.corners, aabb)
    }

    /// The body from a frustum's exact `f64` corners (the builders' path: no `f32`
    /// rounding of the corners before clipping).
    pub(crate) fn from_dcorners_aabb(
        corners: &[DVec3; 8],
        aabb: &Aabb,
    ) -> Result<Self, FrustumError> {
        let planes = crate::frustum::dplanes(corners, 0.0)?;
        Self::from_planes_aabb(&planes, &corners.map(DVec3::as_vec3), aabb)
    }

    /// `planes ∩ aabb` for any six planes bounding a convex region; `corners` set the
    /// rounding scale.
    pub(crate) fn from_planes_aabb(
        fplanes: &[DPlane; 6],
        corners: &[Vec3; 8],
        aabb: &Aabb,
    ) -> Result<Self, FrustumError> {
        let aabb = aabb.validate()?;
        let scale = corners
            .iter()
            .chain(&aabb.corners())
            .map(|c| c.abs().max_element())
            .fold(0.0f32, f32::max)
            .max(f32::MIN_POSITIVE);
        let mut planes = ArrayVec::new();
        planes.extend(fplanes.iter().copied());
        planes.extend(aabb.planes().iter().map(DPlane::from_plane));
        Ok(Self::from_planes(planes, f64::from(scale)))
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
        let n = body.planes.len();
        for i in 0..n {
            let a = body.planes[i];
            // `c × a` for every later plane `c`, shared by all triples that start at `a`.
            let ca: ArrayVec<DVec3, MAX_BODY_PLANES> = body.planes[i + 1..]
                .iter()
                .map(|c| c.normal.cross(a.normal))
                .collect();
            for j in i + 1..n {
                let b = body.planes[j];
                let ab = a.normal.cross(b.normal);
                for k in j + 1..n {
                    let c = &body.planes[k];
                    let Some(p) = intersect3(&a, &b, c, ca[k - i - 1], ab) else {
                        continue;
                    };
                    if body.planes.iter().all(|pl| pl.distance(p) >= -inside_tol) {
                        body.push_unique(p, merge_tol);
                    }
                }
            }
        }
        body
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

/// Intersection point of three planes, `None` when (nearly) dependent; `ca` and `ab`
/// are the cross products `c × a` and `a × b` of their normals (shared between
/// triples by the caller).
fn intersect3(a: &DPlane, b: &DPlane, c: &DPlane, ca: DVec3, ab: DVec3) -> Option<DVec3> {
    let bc = b.normal.cross(c.normal);
    let det = a.normal.dot(bc);
    if det.abs() < 1e-12 {
        return None;
    }
    let p = (bc * -a.d + ca * -b.d + ab * -c.d) / det;
    p.is_finite().then_some(p)
}
