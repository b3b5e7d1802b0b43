//! The camera's infinite-far projection for shadow volumes, and the matrices of
//! projective shadows.
//!
//! Shadow volumes reach infinity (`w = 0` points), so the camera that draws them
//! needs a far plane at infinity. This crate uses the **reversed-Z** infinite
//! perspective of `shadowmap_frustum::projection::perspective_infinite`: with
//! `d = -z` the view depth,
//!
//! ```text
//! depth = near / d            (1 at the near plane, 0 at infinity)
//! (x, y, z, 0)  ->  clip z = 0, clip w = -z   (depth exactly 0, never clipped away
//!                                              when in front of the eye)
//! ```
//!
//! so a point at infinity lands exactly on the far plane with no epsilon, and the
//! depth test of every volume pass is `Greater` (or `GreaterEqual`) with the depth
//! buffer cleared to 0.
//!
//! Projective shadows (Blinn, *Me and my (fake) shadow*, 1988; the occluder texture
//! as in Segal et al., *Fast shadows and lighting effects using texture mapping*,
//! 1992) draw the occluders black on white from the light with `clip_from_world`,
//! then look that mask up at each receiver point `p` through the homogeneous
//! texture matrix:
//!
//! ```text
//! (s, t, _, q) = uv_from_world * (p, 1)
//! uv = (s / q, t / q)          v down, [0, 1]^2 covers the mask; q <= 0: behind the light
//! ```

use glam::{DMat4, DVec4, Mat4, Vec2, Vec3};
use shadowmap_frustum::{Aabb, Camera, Light, Projection, math, projection};

use crate::VolumeError;

/// The reversed-Z, infinite-far `clip_from_world` of a perspective camera (the same
/// view, field of view, aspect and near plane; the far plane at infinity).
///
/// # Errors
/// [`VolumeError::InvalidCamera`] for a camera that fails validation;
/// [`VolumeError::UnsupportedProjection`] for an orthographic or custom projection.
pub fn infinite_clip_from_world(camera: &Camera) -> Result<Mat4, VolumeError> {
    camera.validate().map_err(VolumeError::InvalidCamera)?;
    let (fov_y, aspect, near) = match camera.projection {
        Projection::Perspective {
            fov_y,
            aspect,
            near,
            ..
        }
        | Projection::InfinitePerspective {
            fov_y,
            aspect,
            near,
            ..
        } => (fov_y, aspect, near),
        _ => return Err(VolumeError::UnsupportedProjection),
    };
    let view_from_world = camera
        .view_from_world()
        .map_err(VolumeError::InvalidCamera)?
        .as_dmat4();
    let clip_from_view = projection::perspective_infinite(
        f64::from(fov_y),
        f64::from(aspect),
        f64::from(near),
        true,
    );
    Ok((clip_from_view * view_from_world).as_mat4())
}

/// Clip space `[-1, 1]^2` to texture space `[0, 1]^2` with `v` down.
const UV_FROM_CLIP: DMat4 = DMat4::from_cols(
    DVec4::new(0.5, 0.0, 0.0, 0.0),
    DVec4::new(0.0, -0.5, 0.0, 0.0),
    DVec4::new(0.0, 0.0, 1.0, 0.0),
    DVec4::new(0.5, 0.5, 0.0, 1.0),
);

/// The two matrices of a projective shadow: the light's view of the occluders and
/// the receivers' homogeneous texture coordinates into it.
///
/// The light frames the occluders' bounding sphere: an orthographic box for a
/// directional light, a square perspective cone from the light's position for point
/// and spot lights (the spot's own cone does not limit it). The depth range is
/// `[0, 1]` over the sphere (standard Z), though the mask ignores depth.
///
/// Limits of the algorithm, as a renderer using it must accept: occluders and
/// receivers are separate sets, so there is no self-shadowing and occluders are
/// drawn fully lit; a receiver between the light and an occluder is darkened too
/// (the mask has no depth); receivers behind a point or spot light (`q <= 0`) are
/// left lit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectiveShadow {
    /// The light's clip space from world space: draws the occluder mask.
    pub clip_from_world: Mat4,
    /// Homogeneous mask texture coordinates from world space (see the module docs).
    pub uv_from_world: Mat4,
}

impl ProjectiveShadow {
    /// Frames `occluders` (world bounds) from `light`.
    ///
    /// # Errors
    /// [`VolumeError::InvalidLight`] for a light that fails validation;
    /// [`VolumeError::InvalidOccluders`] for non-finite or inverted bounds, or a
    /// point or spot light inside (or on) the bounds' circumscribed sphere.
    pub fn new(light: &Light, occluders: &Aabb) -> Result<Self, VolumeError> {
        light.validate().map_err(VolumeError::InvalidLight)?;
        if !(occluders.is_finite() && occluders.is_valid()) {
            return Err(VolumeError::InvalidOccluders);
        }
        let center = occluders.center().as_dvec3();
        let radius =
            (0.5 * occluders.size().as_dvec3().length()).max(1e-6 * (1.0 + center.length()));
        let clip_from_world = match *light {
            Light::Directional { direction } => {
                let dir = direction.as_dvec3().normalize();
                let up = projection::least_aligned_axis(dir);
                let view = projection::look_to(center, dir, up);
                let r = radius;
                projection::orthographic(-r, r, -r, r, -r, r, false) * view
            }
            Light::Spot { position, .. } | Light::Point { position, .. } => {
                let eye = position.as_dvec3();
                let to = center - eye;
                let dist = to.length();
                if !(dist > radius * (1.0 + 1e-6)) {
                    return Err(VolumeError::InvalidOccluders);
                }
                let dir = to / dist;
                let view = projection::look_to(eye, dir, projection::least_aligned_axis(dir));
                let half = math::asin(radius / dist);
                let near = (dist - radius).max(dist * 1e-6);
                projection::perspective(2.0 * half, 1.0, near, dist + radius, false) * view
            }
        };
        if !clip_from_world.is_finite() || clip_from_world.determinant().abs() < 1e-300 {
            return Err(VolumeError::InvalidOccluders);
        }
        Ok(Self {
            clip_from_world: clip_from_world.as_mat4(),
            uv_from_world: (UV_FROM_CLIP * clip_from_world).as_mat4(),
        })
    }

    /// The mask coordinates of a world point (`v` down), `None` behind a point or
    /// spot light (`q <= 0`). Inside the mask when both lie in `[0, 1]`.
    #[must_use]
    pub fn uv(&self, world: Vec3) -> Option<Vec2> {
        let h = self.uv_from_world.as_dmat4() * world.as_dvec3().extend(1.0);
        (h.w > 0.0).then(|| (h.truncate().truncate() / h.w).as_vec2())
    }
}
