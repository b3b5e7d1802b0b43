//! A camera checked once per frame and shared by every builder.

use glam::{Mat4, Vec3};

use crate::camera::CameraGeometry;
use crate::{Camera, Frustum, FrustumError};

/// A camera whose pose and projection have been checked and converted to `f64` once:
/// its frame, depth range, the edge rays of its frustum, and the frustum's corners
/// and planes.
///
/// Every builder that takes a [`Camera`] runs these checks at its door. Per frame, an
/// engine that fits several things for one camera (cascades for each light, a focus
/// body, a spot fit) can build a `ValidCamera` once and pass it to the `_valid` entry
/// points ([`CascadeSet::fit_valid`](crate::CascadeSet::fit_valid), and the warps'
/// `FocusBody::new_valid` in `shadowmap-warp`), which then neither re-validate nor
/// re-derive it. The results are the same as from the [`Camera`] entry points.
///
/// ```
/// use glam::Vec3;
/// use shadowmap_frustum::{Camera, CascadeOptions, CascadeSet, CascadeSplits, Projection,
///     SplitScheme, ValidCamera};
///
/// let camera = Camera::look_to(
///     Vec3::new(0.0, 2.0, 0.0),
///     Vec3::NEG_Z,
///     Vec3::Y,
///     Projection::perspective(1.0, 1.5, 0.1, 200.0),
/// )?;
/// let valid = ValidCamera::new(&camera)?; // once per frame
/// let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 200.0)?;
/// let sun = CascadeSet::fit_valid(&valid, Vec3::new(0.3, -1.0, 0.2), &splits,
///     &CascadeOptions::default())?;
/// assert_eq!(sun, CascadeSet::fit(&camera, Vec3::new(0.3, -1.0, 0.2), &splits,
///     &CascadeOptions::default())?);
/// # Ok::<(), shadowmap_frustum::FrustumError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct ValidCamera {
    camera: Camera,
    pub(crate) geometry: CameraGeometry,
}

impl ValidCamera {
    /// Checks `camera` the way every builder does.
    ///
    /// # Errors
    /// The errors of [`Camera::validate`] about the pose, the projection and the
    /// frustum's volume (`Camera::validate` also checks that the `f32`
    /// `clip_from_world` keeps near and far apart, which builders do not need).
    pub fn new(camera: &Camera) -> Result<Self, FrustumError> {
        Ok(Self {
            camera: *camera,
            geometry: camera.geometry()?,
        })
    }

    /// As [`ValidCamera::new`], with every check of [`Camera::validate`] (the `f32`
    /// `clip_from_world` too), computing the geometry once.
    ///
    /// # Errors
    /// The errors of [`Camera::validate`].
    pub fn new_validated(camera: &Camera) -> Result<Self, FrustumError> {
        Ok(Self {
            camera: *camera,
            geometry: camera.checked_geometry()?,
        })
    }

    /// The camera that was checked.
    #[must_use]
    pub const fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The frustum between the near plane and the far plane (or shadow distance), as
    /// [`Camera::frustum`].
    #[must_use]
    pub fn frustum(&self) -> Frustum {
        self.geometry.frustum()
    }

    /// The sub-frustum between two view depths, as [`Camera::slice`].
    ///
    /// # Errors
    /// [`FrustumError::InvalidDepthRange`] for a depth pair that is non-finite,
    /// inverted, too thin, or outside the camera's range; as [`Camera::slice`] for a
    /// slice without volume.
    pub fn slice(&self, near_depth: f32, far_depth: f32) -> Result<Frustum, FrustumError> {
        let (n, f) = self.geometry.check_slice(near_depth, far_depth)?;
        self.geometry.slice(n, f)
    }

    /// The corners of [`ValidCamera::slice`] (near then far; bottom-left,
    /// bottom-right, top-right, top-left) without its planes, for a builder that
    /// reads only the corners.
    ///
    /// # Errors
    /// As [`ValidCamera::slice`] for the depth pair; [`FrustumError::NonFinite`]
    /// when a corner overflows `f32`.
    pub fn slice_corners(
        &self,
        near_depth: f32,
        far_depth: f32,
    ) -> Result<[Vec3; 8], FrustumError> {
        let (n, f) = self.geometry.check_slice(near_depth, far_depth)?;
        let corners = self.geometry.world_corners(n, f).map(glam::DVec3::as_vec3);
        if corners.iter().all(|c| c.is_finite()) {
            Ok(corners)
        } else {
            Err(FrustumError::NonFinite)
        }
    }

    /// Near and far view depth over which shadows are computed, as
    /// [`Camera::depth_range`].
    #[must_use]
    pub fn depth_range(&self) -> (f32, f32) {
        (self.geometry.near as f32, self.geometry.far as f32)
    }

    /// World space to view space, as [`Camera::view_from_world`].
    #[must_use]
    pub fn view_from_world(&self) -> Mat4 {
        self.geometry.view_from_world32
    }

    /// Camera position in world space.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.camera.eye()
    }
}
