//! The convex frustum of a camera or a slice of it: corners and inward planes.

use glam::{DVec3, Vec3};

use crate::geometry::{DPlane, Plane};
use crate::{Aabb, FrustumError};

/// A convex frustum: eight corners and six inward planes.
///
/// Corners: indices 0..4 lie on the near plane and 4..8 on the far plane, each in the
/// order bottom-left, bottom-right, top-right, top-left as seen by the camera.
/// Planes, inward: left, right, bottom, top, near, far.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Corners in the documented order.
    pub corners: [Vec3; 8],
    /// Inward planes: left, right, bottom, top, near, far.
    pub planes: [Plane; 6],
}

impl Frustum {
    /// A frustum from its corners in the documented order.
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`], or [`FrustumError::DegenerateFrustum`] when the
    /// corners do not span a volume.
    pub fn from_corners(corners: [Vec3; 8]) -> Result<Self, FrustumError> {
        if !corners.iter().all(|c| c.is_finite()) {
            return Err(FrustumError::NonFinite);
        }
        let dcorners = corners.map(Vec3::as_dvec3);
        dplanes(&dcorners, f32_min_distance(&dcorners))?;
        Self::from_dcorners(&dcorners)
    }

    pub(crate) fn from_dcorners(corners: &[DVec3; 8]) -> Result<Self, FrustumError> {
        // Exact f64 corners from a validated camera: thin slices are fine.
        let planes = dplanes(corners, 0.0)?;
        let corners32 = corners.map(DVec3::as_vec3);
        if !corners32.iter().all(|c| c.is_finite()) {
            return Err(FrustumError::NonFinite);
        }
        Ok(Self {
            corners: corners32,
            planes: planes.map(DPlane::to_plane),
        })
    }

    /// Planes in `f64`, recomputed from the corners for accuracy.
    /// The stored planes in `f64`: the same planes [`Frustum::contains`] uses.
    pub(crate) fn dplanes(&self) -> Result<[DPlane; 6], FrustumError> {
        let mut planes = [DPlane::from_plane(&self.planes[0]); 6];
        for (dst, p) in planes.iter_mut().zip(&self.planes) {
            if !(p.normal.is_finite() && p.d.is_finite() && p.normal.length() > 0.5) {
                return Err(FrustumError::DegenerateFrustum);
            }
            *dst = DPlane::from_plane(p);
        }
        Ok(planes)
    }

    /// Whether `p` lies inside or on the frustum, allowing `tolerance` world units.
    #[must_use]
    pub fn contains(&self, p: Vec3, tolerance: f32) -> bool {
        self.planes
            .iter()
            .all(|pl| pl.signed_distance(p) >= -tolerance)
    }

    /// The axis-aligned box around the corners.
    #[must_use]
    pub fn aabb(&self) -> Aabb {
        let mut aabb = Aabb::new(self.corners[0], self.corners[0]);
        for c in &self.corners[1..] {
            aabb.min = aabb.min.min(*c);
            aabb.max = aabb.max.max(*c);
        }
        aabb
    }

    /// Mean of the corners.
    #[must_use]
    pub fn centroid(&self) -> Vec3 {
        self.corners
            .iter()
            .fold(glam::DVec3::ZERO, |s, c| s + c.as_dvec3())
            .as_vec3()
            / 8.0
    }
}

/// Inward planes of a frustum's faces. `min_distance` is the smallest accepted
/// distance of the centroid from a face.
pub(crate) fn dplanes(
    corners: &[DVec3; 8],
    min_distance: f64,
) -> Result<[DPlane; 6], FrustumError> {
    let centroid = corners.iter().fold(DVec3::ZERO, |s, c| s + *c) / 8.0;
    let scale = corners
        .iter()
        .map(|c| (*c - centroid).length_squared())
        .fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(FrustumError::DegenerateFrustum);
    }
    let mut planes = [DPlane {
        normal: DVec3::Z,
        d: 0.0,
    }; 6];
    for (plane, face) in planes.iter_mut().zip(FACES) {
        let quad = face.map(|i| corners[i]);
        // The quad's area vector is half the cross product of its diagonals (Newell's
        // normal in closed form): it uses all four corners, so a face with one tiny edge
        // (the near face of a frustum with a small near distance) is as well conditioned
        // as its long edges allow; the plane passes through the corners' mean.
        let normal = (quad[2] - quad[0])
            .cross(quad[3] - quad[1])
            .try_normalize()
            .ok_or(FrustumError::DegenerateFrustum)?;
        let mean = (quad[0] + quad[1] + quad[2] + quad[3]) * 0.25;
        let p = DPlane {
            normal,
            d: -normal.dot(mean),
        };
        *plane = if p.distance(centroid) < 0.0 {
            p.flipped()
        } else {
            p
        };
        if plane.distance(centroid) <= min_distance {
            return Err(FrustumError::DegenerateFrustum);
        }
    }
    Ok(planes)
}

/// Corner indices of each face (left, right, bottom, top, near, far), in order around it.
const FACES: [[usize; 4]; 6] = [
    [0, 3, 7, 4],
    [1, 5, 6, 2],
    [0, 4, 5, 1],
    [3, 2, 6, 7],
    [0, 1, 2, 3],
    [4, 7, 6, 5],
];

/// Smallest accepted distance of an `f32` frustum's centroid from any of its faces:
/// 1024 ulps of its largest coordinate, so that rounding the corners turns no face
/// plane by more than about a milliradian.
pub(crate) fn f32_min_distance(corners: &[DVec3; 8]) -> f64 {
    let max = corners
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0, f64::max);
    1024.0 * f64::from(f32::EPSILON) * max
}
