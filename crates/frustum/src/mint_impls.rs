//! Conversions between the plain geometric values of this crate and [`mint`] types,
//! for engines whose math library is not glam. (glam's own `mint` conversions cover
//! the vectors and matrices, e.g. `mint::ColumnMatrix4::from(transform.clip_from_world)`.)

use glam::{Vec3, Vec4};

use crate::{Aabb, Plane, Sphere};

/// The box as its `[min, max]` corners.
impl From<Aabb> for [mint::Point3<f32>; 2] {
    fn from(aabb: Aabb) -> Self {
        [aabb.min.into(), aabb.max.into()]
    }
}

/// A box from its `[min, max]` corners.
impl From<[mint::Point3<f32>; 2]> for Aabb {
    fn from([min, max]: [mint::Point3<f32>; 2]) -> Self {
        Self::new(Vec3::from(min), Vec3::from(max))
    }
}

/// The plane as `(normal.x, normal.y, normal.z, d)`, the vector a shader dots with
/// `(p, 1)`.
impl From<Plane> for mint::Vector4<f32> {
    fn from(plane: Plane) -> Self {
        plane.normal.extend(plane.d).into()
    }
}

/// A plane from `(normal.x, normal.y, normal.z, d)`, taken as given (not normalized).
impl From<mint::Vector4<f32>> for Plane {
    fn from(v: mint::Vector4<f32>) -> Self {
        let v = Vec4::from(v);
        Self::new(v.truncate(), v.w)
    }
}

/// The sphere as `(center.x, center.y, center.z, radius)`.
impl From<Sphere> for mint::Vector4<f32> {
    fn from(sphere: Sphere) -> Self {
        sphere.center.extend(sphere.radius).into()
    }
}

/// A sphere from `(center.x, center.y, center.z, radius)`.
impl From<mint::Vector4<f32>> for Sphere {
    fn from(v: mint::Vector4<f32>) -> Self {
        let v = Vec4::from(v);
        Self::new(v.truncate(), v.w)
    }
}
