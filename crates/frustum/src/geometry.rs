use glam::{DVec3, Mat4, Vec3};

use crate::FrustumError;

/// An axis-aligned bounding box, `min <= max` on every axis when valid.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "bytemuck", derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box with the given corners (not checked; see [`Aabb::validate`]).
    #[must_use]
    pub const fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The box centred on `center` with half extents `half`.
    #[must_use]
    pub fn from_center_half_extents(center: Vec3, half: Vec3) -> Self {
        Self::new(center - half, center + half)
    }

    /// The smallest box holding every point, or `None` for an empty slice or a
    /// non-finite point.
    #[must_use]
    pub fn from_points(points: &[Vec3]) -> Option<Self> {
        let (first, rest) = points.split_first()?;
        let mut aabb = Self::new(*first, *first);
        for p in rest {
            aabb.min = aabb.min.min(*p);
            aabb.max = aabb.max.max(*p);
        }
        aabb.is_finite().then_some(aabb)
    }

    /// Whether every coordinate is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Whether the box is finite with `min <= max` on every axis (a point or a flat
    /// box is valid).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.is_finite() && self.min.cmple(self.max).all()
    }

    /// `Ok(self)` if [`is_valid`](Self::is_valid), else [`FrustumError::NonFinite`] or
    /// [`FrustumError::EmptyBounds`].
    pub fn validate(self) -> Result<Self, FrustumError> {
        if !self.is_finite() {
            Err(FrustumError::NonFinite)
        } else if !self.min.cmple(self.max).all() {
            Err(FrustumError::EmptyBounds)
        } else {
            Ok(self)
        }
    }

    /// Centre point.
    #[must_use]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Full size along each axis.
    #[must_use]
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }

    /// The eight corners; bit 0 of the index selects max x, bit 1 max y, bit 2 max z.
    #[must_use]
    pub fn corners(&self) -> [Vec3; 8] {
        core::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// Whether `p` lies inside or on the boundary.
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// The smallest box holding both.
    #[must_use]
    pub fn union(&self, other: &Self) -> Self {
        Self::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// The overlap of both boxes, or `None` if they are disjoint.
    #[must_use]
    pub fn intersection(&self, other: &Self) -> Option<Self> {
        let aabb = Self::new(self.min.max(other.min), self.max.min(other.max));
        aabb.min.cmple(aabb.max).all().then_some(aabb)
    }

    /// The six inward planes: `-x`, `+x`, `-y`, `+y`, `-z`, `+z` faces.
    #[must_use]
    pub fn planes(&self) -> [Plane; 6] {
        [
            Plane::new(Vec3::X, -self.min.x),
            Plane::new(Vec3::NEG_X, self.max.x),
            Plane::new(Vec3::Y, -self.min.y),
            Plane::new(Vec3::NEG_Y, self.max.y),
            Plane::new(Vec3::Z, -self.min.z),
            Plane::new(Vec3::NEG_Z, self.max.z),
        ]
    }

    /// The box around this box's corners after an affine transform.
    #[must_use]
    pub fn transformed(&self, dst_from_src: &Mat4) -> Self {
        let corners = self.corners().map(|c| dst_from_src.transform_point3(c));
        let mut aabb = Self::new(corners[0], corners[0]);
        for c in &corners[1..] {
            aabb.min = aabb.min.min(*c);
            aabb.max = aabb.max.max(*c);
        }
        aabb
    }
}

/// A plane `normal . p + d = 0`; points with `normal . p + d >= 0` are inside.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "bytemuck", derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct Plane {
    /// Unit normal pointing to the inside half-space.
    pub normal: Vec3,
    /// Offset: `-normal . q` for any point `q` on the plane.
    pub d: f32,
}

impl Plane {
    /// A plane from its normal and offset (not normalized).
    #[must_use]
    pub const fn new(normal: Vec3, d: f32) -> Self {
        Self { normal, d }
    }

    /// The plane through `point` with inward `normal` (normalized here), or `None` for
    /// a zero or non-finite normal.
    #[must_use]
    pub fn from_point_normal(point: Vec3, normal: Vec3) -> Option<Self> {
        let n = normal.try_normalize()?;
        Some(Self::new(n, -n.dot(point)))
    }

    /// Signed distance of `p`: positive inside.
    #[must_use]
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) + self.d
    }
}

/// A sphere.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "bytemuck", derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius, non-negative.
    pub radius: f32,
}

impl Sphere {
    /// A sphere from centre and radius.
    #[must_use]
    pub const fn new(center: Vec3, radius: f32) -> Self {
        Self { center, radius }
    }

    /// Whether `p` is inside or on the sphere, with a relative tolerance `rel_eps`.
    #[must_use]
    pub fn contains(&self, p: Vec3, rel_eps: f32) -> bool {
        p.distance(self.center) <= self.radius * (1.0 + rel_eps)
    }
}

/// A plane in `f64`, used inside the builders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DPlane {
    pub(crate) normal: DVec3,
    pub(crate) d: f64,
}

impl DPlane {
    pub(crate) fn from_plane(p: &Plane) -> Self {
        let n = p.normal.as_dvec3();
        let len = n.length();
        Self {
            normal: n / len,
            d: f64::from(p.d) / len,
        }
    }

    /// The half-space `normal . p + d >= 0` (normal need not be unit).
    pub(crate) fn new(normal: DVec3, d: f64) -> Self {
        let len = normal.length();
        Self {
            normal: normal / len,
            d: d / len,
        }
    }

    pub(crate) fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) + self.d
    }

    pub(crate) fn flipped(self) -> Self {
        Self {
            normal: -self.normal,
            d: -self.d,
        }
    }

    pub(crate) fn to_plane(self) -> Plane {
        Plane::new(self.normal.as_vec3(), self.d as f32)
    }
}
