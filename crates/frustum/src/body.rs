use arrayvec::ArrayVec;
use glam::{DVec3, Vec3};

use crate::geometry::DPlane;
use crate::{Aabb, Frustum, FrustumError};

/// Most vertices a [`ConvexBody`] holds: twice the 20 vertices a polyhedron of 12
/// planes can have, so an extruded frustum-box intersection always fits.
pub const MAX_BODY_VERTICES: usize = 64;

/// A convex polyhedron given by its vertices (fixed capacity, no heap allocation).
///
/// Built as a frustum intersected with a box, optionally extruded toward a
/// directional light and clipped by a scene box: the body `B` of LiSPSM
/// (Wimmer et al. 2004) whose light-space bounds focus a shadow map.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexBody {
    vertices: ArrayVec<Vec3, MAX_BODY_VERTICES>,
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
        let planes = crate::camera::dplanes(corners, 0.0)?;
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
        let mut planes = [fplanes[0]; 12];
        planes[..6].copy_from_slice(fplanes);
        for (dst, p) in planes[6..].iter_mut().zip(aabb.planes()) {
            *dst = DPlane::from_plane(&p);
        }
        let scale = corners
            .iter()
            .chain(&aabb.corners())
            .map(|c| c.abs().max_element())
            .fold(0.0f32, f32::max)
            .max(f32::MIN_POSITIVE);
        let mut body = Self {
            vertices: ArrayVec::new(),
        };
        let scale = f64::from(scale);
        // The corners are f32, so a frustum face is planar only to about f32 epsilon
        // times the scale: accept vertices that far outside, and merge closer ones.
        let inside_tol = 8.0 * f64::from(f32::EPSILON) * scale;
        let merge_tol = 2.0 * inside_tol;
        for i in 0..12 {
            for j in i + 1..12 {
                for k in j + 1..12 {
                    let Some(p) = intersect3(&planes[i], &planes[j], &planes[k]) else {
                        continue;
                    };
                    if planes.iter().all(|pl| pl.distance(p) >= -inside_tol) {
                        body.push_unique(p, merge_tol);
                    }
                }
            }
        }
        Ok(body)
    }

    /// The body extruded toward a directional light and clipped by `scene`: every
    /// vertex `v` adds the point where the ray from `v` toward the light leaves the
    /// scene box. `light_direction` is the direction the light travels.
    ///
    /// Casters that shadow the body lie in the convex hull of the result.
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
        let to_light = (-light_direction.as_dvec3())
            .try_normalize()
            .ok_or(FrustumError::ZeroDirection)?;
        let (lo, hi) = (scene.min.as_dvec3(), scene.max.as_dvec3());
        let scale = f64::from(scene.min.abs().max(scene.max.abs()).max_element()).max(1e-30);
        let mut out = self.clone();
        for v in &self.vertices {
            let v = v.as_dvec3();
            let t = ray_exit(v, to_light, lo, hi);
            if t > 1e-9 * scale {
                let p = (v + to_light * t).clamp(lo, hi);
                out.push_unique(p, 1e-7 * scale);
            }
        }
        Ok(out)
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
            // Capacity is a proven bound (see MAX_BODY_VERTICES); ignore overflow rather
            // than panic if rounding ever produced near-duplicates beyond it.
            let _ = self.vertices.try_push(p32);
        }
    }
}

/// Intersection point of three planes, `None` when (nearly) dependent.
fn intersect3(a: &DPlane, b: &DPlane, c: &DPlane) -> Option<DVec3> {
    let bc = b.normal.cross(c.normal);
    let det = a.normal.dot(bc);
    if det.abs() < 1e-12 {
        return None;
    }
    let p = (bc * -a.d + c.normal.cross(a.normal) * -b.d + a.normal.cross(b.normal) * -c.d) / det;
    p.is_finite().then_some(p)
}

/// Distance along `dir` at which a ray from `origin` (inside the box) leaves it.
fn ray_exit(origin: DVec3, dir: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    let mut t = f64::INFINITY;
    for axis in 0..3 {
        let d = dir[axis];
        if d > 1e-15 {
            t = t.min((hi[axis] - origin[axis]) / d);
        } else if d < -1e-15 {
            t = t.min((lo[axis] - origin[axis]) / d);
        }
    }
    if t.is_finite() { t.max(0.0) } else { 0.0 }
}
