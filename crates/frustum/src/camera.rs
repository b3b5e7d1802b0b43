use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};

use crate::frustum::{dplanes, f32_min_distance};
use crate::geometry::DPlane;
use crate::math::{max_num, min_num};
use crate::rays::{Rays, symmetric_k};
use crate::{Frustum, FrustumError, math, projection};

/// Smallest accepted relative thickness `(far - near) / far` of a depth range: below
/// this, `f32` depth cannot tell the two planes apart.
pub(crate) const MIN_RELATIVE_DEPTH_RANGE: f64 = 1e-5;

/// How a camera projects view space; the view looks down `-Z`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Projection {
    /// Symmetric perspective with a finite far plane.
    Perspective {
        /// Vertical field of view in radians, in `(0, pi)`.
        fov_y: f32,
        /// Width over height, positive.
        aspect: f32,
        /// Near plane distance, positive.
        near: f32,
        /// Far plane distance, above `near`.
        far: f32,
    },
    /// Symmetric perspective with the far plane at infinity; shadows are cast up to
    /// `shadow_distance`.
    InfinitePerspective {
        /// Vertical field of view in radians, in `(0, pi)`.
        fov_y: f32,
        /// Width over height, positive.
        aspect: f32,
        /// Near plane distance, positive.
        near: f32,
        /// View depth up to which shadows are computed, above `near`.
        shadow_distance: f32,
    },
    /// Orthographic box `[left, right] x [bottom, top]` between view depths `near` and `far`.
    Orthographic {
        /// Left edge in view units.
        left: f32,
        /// Right edge, above `left`.
        right: f32,
        /// Bottom edge.
        bottom: f32,
        /// Top edge, above `bottom`.
        top: f32,
        /// Near view depth (may be zero or negative).
        near: f32,
        /// Far view depth, above `near`.
        far: f32,
    },
    /// Any projection matrix in WebGPU clip space (depth in `[0, 1]`, reversed when the
    /// camera's `reversed_z` is set), possibly off-centre or with an infinite far plane.
    /// Shadows are cast up to `shadow_distance` or the matrix's far plane, whichever
    /// is nearer.
    Custom {
        /// The projection, WebGPU clip space from view space.
        clip_from_view: Mat4,
        /// View depth up to which shadows are computed.
        shadow_distance: f32,
    },
}

impl Projection {
    /// A symmetric perspective projection.
    #[must_use]
    pub const fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Self {
        Self::Perspective {
            fov_y,
            aspect,
            near,
            far,
        }
    }
}

/// A camera: a rigid view transform and a projection.
///
/// View space is right-handed and looks down `-Z`; "view depth" is the distance along
/// the viewing direction, `-z_view`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Camera {
    /// Rigid transform from view space to world space (the camera's pose).
    pub world_from_view: Mat4,
    /// The projection.
    pub projection: Projection,
    /// Whether clip depth runs from 1 at the near plane to 0 at the far plane.
    pub reversed_z: bool,
}

impl Camera {
    /// A camera at `eye` looking along `forward` with `up` roughly up.
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`], [`FrustumError::ZeroDirection`],
    /// [`FrustumError::UpParallelToView`], or any error of the projection (see
    /// [`Camera::validate`]).
    pub fn look_to(
        eye: Vec3,
        forward: Vec3,
        up: Vec3,
        projection: Projection,
    ) -> Result<Self, FrustumError> {
        let world_from_view = world_from_view_look_to(eye, forward, up)?;
        let camera = Self {
            world_from_view,
            projection,
            reversed_z: false,
        };
        camera.validate()?;
        Ok(camera)
    }

    /// As [`Camera::look_to`] for a reversed-Z camera: validated with the depth
    /// convention it will be used with (a custom reversed-Z matrix is read with its
    /// near plane at depth 1), which `look_to(..)?.with_reversed_z(true)` cannot do.
    ///
    /// # Errors
    /// As [`Camera::look_to`].
    pub fn look_to_reversed_z(
        eye: Vec3,
        forward: Vec3,
        up: Vec3,
        projection: Projection,
    ) -> Result<Self, FrustumError> {
        let camera = Self {
            world_from_view: world_from_view_look_to(eye, forward, up)?,
            projection,
            reversed_z: true,
        };
        camera.validate()?;
        Ok(camera)
    }

    /// A camera at `eye` looking at `target`.
    ///
    /// # Errors
    /// As [`Camera::look_to`]; `target == eye` gives [`FrustumError::ZeroDirection`].
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        projection: Projection,
    ) -> Result<Self, FrustumError> {
        Self::look_to(eye, target - eye, up, projection)
    }

    /// This camera with reversed-Z clip depth.
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }

    /// Checks the pose and the projection.
    ///
    /// # Errors
    /// [`FrustumError::NonFinite`] for NaN or infinite values,
    /// [`FrustumError::ZeroDirection`] / [`FrustumError::UpParallelToView`] for a
    /// degenerate pose, [`FrustumError::InvalidFov`], [`FrustumError::InvalidAspect`],
    /// [`FrustumError::InvalidDepthRange`] (near <= 0 for perspective, far <= near, or
    /// a range too thin for `f32`), [`FrustumError::InvalidProjection`] for a custom
    /// matrix that is singular or does not look down `-Z`,
    /// [`FrustumError::DegenerateFrustum`] for a frustum with no volume at `f32`
    /// precision, with a corner farther than 1e15 from the origin, or whose `f32`
    /// `clip_from_world` cannot keep its near and far planes apart. A wide depth range
    /// is not degenerate: far / near of 1e6 and beyond validates with either depth
    /// convention. Validation uses the camera's own `reversed_z` (see
    /// [`Camera::look_to_reversed_z`]).
    pub fn validate(&self) -> Result<(), FrustumError> {
        self.clip_from_world().map(|_| ())
    }

    /// Transform from world space to view space: the inverse of the pose after
    /// re-orthonormalization (so a slightly non-rigid pose still gives a rigid inverse).
    ///
    /// # Errors
    /// As [`Camera::validate`].
    pub fn view_from_world(&self) -> Result<Mat4, FrustumError> {
        Ok(self.geometry()?.view_from_world().as_mat4())
    }

    /// Camera position in world space.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.world_from_view.w_axis.truncate()
    }

    /// Unit viewing direction in world space.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        (-self.world_from_view.z_axis.truncate()).normalize_or_zero()
    }

    /// View depth (distance along the viewing direction) of a world point.
    #[must_use]
    pub fn view_depth(&self, world: Vec3) -> f32 {
        (world - self.eye()).dot(self.forward())
    }

    /// Near and far view depth over which shadows are computed (the far plane, or the
    /// shadow distance for infinite and custom projections).
    ///
    /// # Errors
    /// As [`Camera::validate`].
    pub fn depth_range(&self) -> Result<(f32, f32), FrustumError> {
        let g = self.geometry()?;
        Ok((g.near as f32, g.far as f32))
    }

    /// The projection matrix, WebGPU clip space from view space.
    ///
    /// # Errors
    /// As [`Camera::validate`].
    pub fn clip_from_view(&self) -> Result<Mat4, FrustumError> {
        self.geometry()?;
        Ok(self.projection_matrix())
    }

    /// The projection matrix of a camera whose geometry has been validated.
    fn projection_matrix(&self) -> Mat4 {
        let rev = self.reversed_z;
        match self.projection {
            Projection::Perspective {
                fov_y,
                aspect,
                near,
                far,
            } => projection::perspective(
                f64::from(fov_y),
                f64::from(aspect),
                f64::from(near),
                f64::from(far),
                rev,
            )
            .as_mat4(),
            Projection::InfinitePerspective {
                fov_y,
                aspect,
                near,
                ..
            } => projection::perspective_infinite(
                f64::from(fov_y),
                f64::from(aspect),
                f64::from(near),
                rev,
            )
            .as_mat4(),
            Projection::Orthographic {
                left,
                right,
                bottom,
                top,
                near,
                far,
            } => projection::orthographic(
                f64::from(left),
                f64::from(right),
                f64::from(bottom),
                f64::from(top),
                f64::from(near),
                f64::from(far),
                rev,
            )
            .as_mat4(),
            Projection::Custom { clip_from_view, .. } => clip_from_view,
        }
    }

    /// `clip_from_view * view_from_world`.
    ///
    /// # Errors
    /// As [`Camera::validate`].
    pub fn clip_from_world(&self) -> Result<Mat4, FrustumError> {
        self.clip_from_geometry(&self.geometry()?)
    }

    /// The geometry with every check of [`Camera::validate`] passed (computed once).
    pub(crate) fn checked_geometry(&self) -> Result<CameraGeometry, FrustumError> {
        let g = self.geometry()?;
        self.clip_from_geometry(&g)?;
        Ok(g)
    }

    /// [`Camera::clip_from_world`] from this camera's geometry.
    fn clip_from_geometry(&self, g: &CameraGeometry) -> Result<Mat4, FrustumError> {
        let exact = self.projection_matrix().as_dmat4() * g.view_from_world();
        let m = exact.as_mat4();
        if resolves_depth_range(&m, &exact, &g.world_corners(g.near, g.far)) {
            Ok(m)
        } else {
            Err(FrustumError::DegenerateFrustum)
        }
    }

    /// The frustum between the near plane and the far plane (or shadow distance).
    ///
    /// # Errors
    /// As [`Camera::validate`].
    pub fn frustum(&self) -> Result<Frustum, FrustumError> {
        Ok(self.geometry()?.frustum())
    }

    /// The sub-frustum between view depths `near_depth < far_depth`, which must lie
    /// inside the camera's depth range (a relative tolerance of `1e-6` is allowed).
    ///
    /// # Errors
    /// As [`Camera::validate`], and [`FrustumError::InvalidDepthRange`] for a depth
    /// pair that is non-finite, inverted, too thin, or outside the camera's range.
    pub fn slice(&self, near_depth: f32, far_depth: f32) -> Result<Frustum, FrustumError> {
        let g = self.geometry()?;
        let (n, f) = g.check_slice(near_depth, far_depth)?;
        g.slice(n, f)
    }

    /// Validated `f64` geometry used by every builder.
    pub(crate) fn geometry(&self) -> Result<CameraGeometry, FrustumError> {
        CameraGeometry::new(self)
    }
}

/// Whether the `f32` camera matrix `m` (rounded from `exact`) resolves the depth
/// range: it is finite and invertible, and evaluated in `f32` it puts every corner in
/// front of the eye and within a quarter of the near-to-far depth separation of the
/// depth `exact` gives it, so near and far stay apart and in order. Far from the
/// origin with a tiny near plane the depth row rounds onto the `w` row and the near
/// corners land anywhere; a wide depth range alone does not fail (standard depth
/// only loses precision near the far plane, reversed-Z hardly any).
fn resolves_depth_range(m: &Mat4, exact: &DMat4, corners: &[DVec3; 8]) -> bool {
    if !m.is_finite() {
        return false;
    }
    let det = m.as_dmat4().determinant();
    if !(det != 0.0 && det.is_finite()) {
        return false;
    }
    let depth64 = |c: DVec3| {
        let h = *exact * c.extend(1.0);
        h.z / h.w
    };
    let depth32 = |c: DVec3| {
        let h = *m * c.as_vec3().extend(1.0);
        (h.w > 0.0).then_some(f64::from(h.z / h.w))
    };
    (0..4).all(|i| {
        let (near, far) = (corners[i], corners[i + 4]);
        let (e_near, e_far) = (depth64(near), depth64(far));
        let separation = (e_far - e_near).abs();
        let close = |c: DVec3, e: f64| {
            depth32(c).is_some_and(|d| d.is_finite() && (d - e).abs() <= 0.25 * separation)
        };
        separation > 0.0 && separation.is_finite() && close(near, e_near) && close(far, e_far)
    })
}

fn world_from_view_look_to(eye: Vec3, forward: Vec3, up: Vec3) -> Result<Mat4, FrustumError> {
    if !(eye.is_finite() && forward.is_finite() && up.is_finite()) {
        return Err(FrustumError::NonFinite);
    }
    let f = forward.as_dvec3();
    let u = up.as_dvec3();
    let fwd = f.try_normalize().ok_or(FrustumError::ZeroDirection)?;
    let up = u.try_normalize().ok_or(FrustumError::ZeroDirection)?;
    let right = fwd.cross(up);
    if right.length() < 1e-6 {
        return Err(FrustumError::UpParallelToView);
    }
    let right = right.normalize();
    let true_up = right.cross(fwd);
    let m = DMat4::from_cols(
        right.extend(0.0),
        true_up.extend(0.0),
        (-fwd).extend(0.0),
        eye.as_dvec3().extend(1.0),
    );
    Ok(m.as_mat4())
}

/// A camera checked and converted to `f64`: its pose, depth range, and the four edge
/// rays of its frustum in view space.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CameraGeometry {
    pub(crate) world_from_view: DMat4,
    pub(crate) near: f64,
    pub(crate) far: f64,
    /// Corner `i` of the slice at view depth `d` is `ray_origin[i] + d * ray_dir[i]`
    /// (view space, `ray_dir[i].z == -1`), in the order bottom-left, bottom-right,
    /// top-right, top-left.
    pub(crate) ray_origin: [DVec3; 4],
    pub(crate) ray_dir: [DVec3; 4],
    /// The same rays in world space.
    pub(crate) world_rays: Rays,
    /// [`CameraGeometry::view_from_world`] in `f32`, as every cascade set stores it.
    pub(crate) view_from_world32: Mat4,
    /// How far outside `near..far` a slice may reach (`1e-6` relative).
    slice_tolerance: f64,
    /// `t_x^2 + t_y^2` when every ray starts at the eye and the rays are mirror
    /// images about the view axis (`(±t_x, ±t_y, -1)`: a symmetric pinhole camera),
    /// so a slice's bounding sphere has a closed form
    /// ([`symmetric_slice_sphere`](crate::bounding_sphere::symmetric_slice_sphere)).
    pub(crate) symmetric_k: Option<f64>,
    /// World corners of the whole depth range (`world_corners(near, far)`).
    corners: [DVec3; 8],
    /// Their inward planes (`dplanes(&corners, 0.0)`), as validation found them.
    planes: [DPlane; 6],
}

fn finite(x: f32) -> Result<f64, FrustumError> {
    if x.is_finite() {
        Ok(f64::from(x))
    } else {
        Err(FrustumError::NonFinite)
    }
}

fn check_range(near: f64, far: f64, allow_non_positive_near: bool) -> Result<(), FrustumError> {
    let err = FrustumError::InvalidDepthRange {
        near: near as f32,
        far: far as f32,
    };
    if (!allow_non_positive_near && near <= 0.0) || far <= near {
        return Err(err);
    }
    // Finite here (checked by every caller): no NaN for `max_num`.
    let scale = max_num(far.abs(), near.abs());
    if (far - near) < MIN_RELATIVE_DEPTH_RANGE * scale {
        return Err(err);
    }
    Ok(())
}

fn symmetric_rays(fov_y: f32, aspect: f32) -> Result<([DVec3; 4], [DVec3; 4]), FrustumError> {
    let fov = finite(fov_y)?;
    let aspect = finite(aspect)?;
    if !(fov > 1e-6 && fov < core::f64::consts::PI - 1e-6) {
        return Err(FrustumError::InvalidFov);
    }
    if !(aspect > 1e-6 && aspect < 1e6) {
        return Err(FrustumError::InvalidAspect);
    }
    let ty = math::tan(fov * 0.5);
    let tx = ty * aspect;
    let dir = [
        DVec3::new(-tx, -ty, -1.0),
        DVec3::new(tx, -ty, -1.0),
        DVec3::new(tx, ty, -1.0),
        DVec3::new(-tx, ty, -1.0),
    ];
    Ok(([DVec3::ZERO; 4], dir))
}

/// Largest accepted world coordinate of a frustum corner: squared distances must stay
/// finite in `f32`.
const MAX_COORDINATE: f64 = 1e15;

const NDC_XY: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];

fn unproject(view_from_clip: &DMat4, x: f64, y: f64, z: f64) -> Option<DVec3> {
    let h = *view_from_clip * DVec4::new(x, y, z, 1.0);
    (h.w.abs() > 1e-300 && h.is_finite()).then(|| h.truncate() / h.w)
}

impl CameraGeometry {
    fn new(camera: &Camera) -> Result<Self, FrustumError> {
        let m = camera.world_from_view.as_dmat4();
        if !m.is_finite() {
            return Err(FrustumError::NonFinite);
        }
        // Re-orthonormalize so that slightly non-rigid input stays usable.
        let back = m.z_axis.truncate();
        let up = m.y_axis.truncate();
        let fwd = (-back).try_normalize().ok_or(FrustumError::ZeroDirection)?;
        let up = up.try_normalize().ok_or(FrustumError::ZeroDirection)?;
        let right = fwd.cross(up);
        if right.length() < 1e-6 {
            return Err(FrustumError::UpParallelToView);
        }
        let right = right.normalize();
        let world_from_view = DMat4::from_cols(
            right.extend(0.0),
            right.cross(fwd).extend(0.0),
            (-fwd).extend(0.0),
            m.w_axis.truncate().extend(1.0),
        );

        let (near, far, ray_origin, ray_dir) = match camera.projection {
            Projection::Perspective {
                fov_y,
                aspect,
                near,
                far,
            } => {
                let (n, f) = (finite(near)?, finite(far)?);
                check_range(n, f, false)?;
                let (o, d) = symmetric_rays(fov_y, aspect)?;
                (n, f, o, d)
            }
            Projection::InfinitePerspective {
                fov_y,
                aspect,
                near,
                shadow_distance,
            } => {
                let (n, f) = (finite(near)?, finite(shadow_distance)?);
                check_range(n, f, false)?;
                let (o, d) = symmetric_rays(fov_y, aspect)?;
                (n, f, o, d)
            }
            Projection::Orthographic {
                left,
                right,
                bottom,
                top,
                near,
                far,
            } => {
                let (l, r, b, t) = (finite(left)?, finite(right)?, finite(bottom)?, finite(top)?);
                let (n, f) = (finite(near)?, finite(far)?);
                check_range(n, f, true)?;
                if !(r > l && t > b) || (r - l) < 1e-7 * r.abs().max(l.abs()) {
                    return Err(FrustumError::EmptyBounds);
                }
                if (t - b) < 1e-7 * t.abs().max(b.abs()) {
                    return Err(FrustumError::EmptyBounds);
                }
                let o = [
                    DVec3::new(l, b, 0.0),
                    DVec3::new(r, b, 0.0),
                    DVec3::new(r, t, 0.0),
                    DVec3::new(l, t, 0.0),
                ];
                (n, f, o, [DVec3::NEG_Z; 4])
            }
            Projection::Custom {
                clip_from_view,
                shadow_distance,
            } => Self::custom_rays(&clip_from_view, shadow_distance, camera.reversed_z)?,
        };
        let mut geometry = Self {
            world_from_view,
            near,
            far,
            ray_origin,
            ray_dir,
            world_rays: Rays::new(&world_from_view, &ray_origin, &ray_dir),
            view_from_world32: Mat4::IDENTITY,
            slice_tolerance: 1e-6 * far.abs().max(near.abs()).max(1e-30),
            symmetric_k: symmetric_k(&ray_origin, &ray_dir),
            corners: [DVec3::ZERO; 8],
            planes: [DPlane {
                normal: DVec3::Z,
                d: 0.0,
            }; 6],
        };
        // The frustum must keep its volume once its corners are rounded to f32.
        let corners = geometry.world_corners(near, far);
        if !corners.iter().all(|c| c.as_vec3().is_finite()) {
            return Err(FrustumError::NonFinite);
        }
        if corners
            .iter()
            .any(|c| c.abs().max_element() > MAX_COORDINATE)
        {
            return Err(FrustumError::DegenerateFrustum);
        }
        let rounded = corners.map(|c| c.as_vec3().as_dvec3());
        dplanes(&rounded, f32_min_distance(&rounded))?;
        // ...and every builder's own construction of it must succeed too (the `f32`
        // corners are finite, checked above).
        geometry.planes = dplanes(&corners, 0.0)?;
        geometry.corners = corners;
        geometry.view_from_world32 = geometry.view_from_world().as_mat4();
        Ok(geometry)
    }

    fn custom_rays(
        clip_from_view: &Mat4,
        shadow_distance: f32,
        reversed_z: bool,
    ) -> Result<(f64, f64, [DVec3; 4], [DVec3; 4]), FrustumError> {
        let m = clip_from_view.as_dmat4();
        let shadow = finite(shadow_distance)?;
        if !m.is_finite() {
            return Err(FrustumError::NonFinite);
        }
        let det = m.determinant();
        if !det.is_finite() || det.abs() < 1e-30 {
            return Err(FrustumError::InvalidProjection);
        }
        let view_from_clip = m.inverse();
        let (z_near, z_mid, z_far) = if reversed_z {
            (1.0, 0.5, 0.0)
        } else {
            (0.0, 0.5, 1.0)
        };
        let near_center =
            unproject(&view_from_clip, 0.0, 0.0, z_near).ok_or(FrustumError::InvalidProjection)?;
        let near = -near_center.z;
        // The far plane may be at infinity (w = 0): then only the shadow distance bounds it.
        let far_plane = unproject(&view_from_clip, 0.0, 0.0, z_far)
            .map(|p| -p.z)
            .filter(|d| d.is_finite() && *d > near);
        let far = far_plane.map_or(shadow, |d| d.min(shadow));
        // The depth range must lie in front of the eye (use `Orthographic` for a box
        // that reaches behind it).
        check_range(near, far, false)?;
        let mut origin = [DVec3::ZERO; 4];
        let mut dir = [DVec3::ZERO; 4];
        for (i, (x, y)) in NDC_XY.iter().enumerate() {
            let a = unproject(&view_from_clip, *x, *y, z_near)
                .ok_or(FrustumError::InvalidProjection)?;
            let b =
                unproject(&view_from_clip, *x, *y, z_mid).ok_or(FrustumError::InvalidProjection)?;
            let (da, db) = (-a.z, -b.z);
            if !(db > da) {
                return Err(FrustumError::InvalidProjection);
            }
            dir[i] = (b - a) / (db - da);
            origin[i] = a - dir[i] * da;
        }
        // Every slice face must be a convex quad with one winding (either, so mirrored
        // projections are fine) all the way from near to far: a matrix that mixes x or
        // y into w can twist it. A vertex's turn is quadratic in depth, so its sign is
        // checked at both ends and at its extremum.
        let turn = |i: usize, d: f64| {
            let q = |k: usize| (origin[k % 4] + dir[k % 4] * d).truncate();
            (q(i + 1) - q(i)).perp_dot(q(i + 2) - q(i + 1))
        };
        let sign = turn(0, near).signum();
        let mid = 0.5 * (near + far);
        for i in 0..4 {
            let (t0, t1, t2) = (turn(i, near), turn(i, mid), turn(i, far));
            // t(d) = a x^2 + b x + c with x = (d - mid) / (far - mid).
            let a = 0.5 * (t0 + t2) - t1;
            let b = 0.5 * (t2 - t0);
            if sign == 0.0 || [t0, t1, t2].iter().any(|t| t * sign <= 0.0) {
                return Err(FrustumError::InvalidProjection);
            }
            // For a pinhole or affine projection the turn is k (d - d_c)^2 or constant:
            // an extremum inside the range means the centre of projection lies between
            // near and far, where the slice collapses to a point.
            let size = t0.abs().max(t1.abs()).max(t2.abs());
            if a.abs() > 1e-9 * size && (b / (2.0 * a)).abs() < 1.0 {
                return Err(FrustumError::InvalidProjection);
            }
        }
        Ok((near, far, origin, dir))
    }

    /// The inverse of the (orthonormal) pose: the transposed rotation and the
    /// rotated, negated eye, exact where a general inverse would round.
    pub(crate) fn view_from_world(&self) -> DMat4 {
        let m = &self.world_from_view;
        let (x, y, z) = (
            m.x_axis.truncate(),
            m.y_axis.truncate(),
            m.z_axis.truncate(),
        );
        let eye = m.w_axis.truncate();
        DMat4::from_cols(
            DVec4::new(x.x, y.x, z.x, 0.0),
            DVec4::new(x.y, y.y, z.y, 0.0),
            DVec4::new(x.z, y.z, z.z, 0.0),
            DVec4::new(-x.dot(eye), -y.dot(eye), -z.dot(eye), 1.0),
        )
    }

    /// Clamps and checks a requested slice against the camera's range.
    pub(crate) fn check_slice(&self, near: f32, far: f32) -> Result<(f64, f64), FrustumError> {
        let (n, f) = (finite(near)?, finite(far)?);
        let tol = self.slice_tolerance;
        let err = FrustumError::InvalidDepthRange { near, far };
        if n < self.near - tol || f > self.far + tol {
            return Err(err);
        }
        let (n, f) = (max_num(n, self.near), min_num(f, self.far));
        check_range(n, f, true)?;
        Ok((n, f))
    }

    /// The eight view-space corners of the slice between two depths.
    pub(crate) fn view_corners(&self, near: f64, far: f64) -> [DVec3; 8] {
        core::array::from_fn(|i| {
            let d = if i < 4 { near } else { far };
            self.ray_origin[i % 4] + self.ray_dir[i % 4] * d
        })
    }

    /// The eight world-space corners of the slice between two depths.
    pub(crate) fn world_corners(&self, near: f64, far: f64) -> [DVec3; 8] {
        self.view_corners(near, far)
            .map(|c| self.world_from_view.transform_point3(c))
    }

    /// The frustum of the whole depth range, from the corners and planes validation
    /// computed (the same values [`CameraGeometry::slice`] gives for it).
    pub(crate) fn frustum(&self) -> Frustum {
        Frustum {
            corners: self.corners.map(DVec3::as_vec3),
            planes: self.planes.map(DPlane::to_plane),
        }
    }

    pub(crate) fn slice(&self, near: f64, far: f64) -> Result<Frustum, FrustumError> {
        let corners = self.world_corners(near, far);
        let frustum = Frustum::from_dcorners(&corners)?;
        Ok(frustum)
    }
}
