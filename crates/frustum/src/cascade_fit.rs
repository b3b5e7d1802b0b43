//! The fit of one cascade: everything a slice's fit needs that does not depend on
//! the slice (light frame, the camera's edge rays in light space, checked options),
//! then each slice's light-space box (tight, stable sphere, stable ladder, or held
//! across frames), its depth range pulled back to the casters, and its matrices.

use glam::{DMat4, DVec2, DVec3, Mat4, Vec3};

use crate::body::ConvexBody;
use crate::bounding_sphere::{bounding_sphere, symmetric_slice_sphere};
use crate::camera::CameraGeometry;
use crate::cascade::{Cascade, CascadeFit, CascadeOptions};
use crate::cascade_state::{HeldSlot, held_box};
use crate::light::unit;
use crate::light_prism::LightPrism;
use crate::mapping::{LightDirection, ShadowTransform};
use crate::rays::Rays;
use crate::{Aabb, Camera, FrustumError, MAX_RESOLUTION, SceneBounds, math};

/// Fits a single cascade covering view depths `[near_depth, far_depth]`.
///
/// # Errors
/// As [`CascadeSet::fit`](crate::CascadeSet::fit), plus [`FrustumError::SliceOutsideScene`] when scene bounds
/// are given and the slice misses the receivers.
pub fn fit_cascade(
    camera: &Camera,
    light_direction: Vec3,
    near_depth: f32,
    far_depth: f32,
    options: &CascadeOptions,
) -> Result<Cascade, FrustumError> {
    let geometry = camera.geometry()?;
    let fitter = Fitter::new(&geometry, Fitter::check(light_direction, options)?, options);
    let (n, f) = fitter.camera.check_slice(near_depth, far_depth)?;
    fitter.fit(n as f32, f as f32, None)
}

/// Everything a cascade fit needs that does not depend on the slice, computed once
/// per call of [`CascadeSet::fit`](crate::CascadeSet::fit).
pub(crate) struct Fitter<'a> {
    camera: &'a CameraGeometry,
    light_dir: DVec3,
    light_from_world: DMat4,
    /// `light_from_world` in `f32`, as stored in every cascade.
    light_from_world32: Mat4,
    /// `light_from_world * world_from_view`: slice corners go to light space in one step.
    light_from_view: DMat4,
    /// The camera's edge rays in light space (see [`CameraGeometry`]).
    light_rays: Rays,
    options: CascadeOptions,
    scene: Option<SceneBounds>,
}

impl<'a> Fitter<'a> {
    /// Checks the light and the options: the unit light direction and the checked
    /// scene bounds.
    pub(crate) fn check(
        light_direction: Vec3,
        options: &CascadeOptions,
    ) -> Result<(DVec3, Option<SceneBounds>), FrustumError> {
        let light_dir = unit(light_direction)?;
        if !(4..=MAX_RESOLUTION).contains(&options.resolution) {
            return Err(FrustumError::InvalidResolution);
        }
        if let Some(step) = options.stable_size_step {
            if !(step > 1.0 && step <= 16.0) {
                return Err(FrustumError::InvalidSplitParameter);
            }
        }
        let scene = match options.scene {
            Some(s) => Some(SceneBounds {
                receivers: s.receivers.validate()?,
                casters: s.casters.validate()?,
            }),
            None => None,
        };
        Ok((light_dir, scene))
    }

    /// The fitter of checked input ([`Fitter::check`]); infallible, so it is built
    /// where it is used rather than moved out of a `Result`.
    pub(crate) fn new(
        camera: &'a CameraGeometry,
        (light_dir, scene): (DVec3, Option<SceneBounds>),
        options: &CascadeOptions,
    ) -> Self {
        let light_from_world = crate::projection::light_rotation(light_dir, options.up_hint);
        let light_from_view = light_from_world * camera.world_from_view;
        Self {
            camera,
            light_dir,
            light_from_world,
            light_from_world32: light_from_world.as_mat4(),
            light_from_view,
            // The stable fit reads only the light depth of the slice's corners.
            light_rays: Rays::axes(
                &light_from_view,
                &camera.ray_origin,
                &camera.ray_dir,
                if options.fit == CascadeFit::Stable {
                    2..3
                } else {
                    0..3
                },
            ),
            options: *options,
            scene,
        }
    }

    /// The stable size ladder's step, when it applies (stable fit with scene bounds).
    fn ladder_step(&self) -> Option<f64> {
        match (self.options.fit, &self.scene, self.options.stable_size_step) {
            (CascadeFit::Stable, Some(_), Some(step)) => Some(f64::from(step)),
            _ => None,
        }
    }

    pub(crate) fn fit_without_receivers(
        &self,
        near: f32,
        far: f32,
        out: &mut Cascade,
    ) -> Result<(), FrustumError> {
        let receiverless = Self {
            scene: None,
            ..*self
        };
        receiverless.fit_into(near, far, None, out)
    }

    /// The bounding sphere of the slice between view depths `n < f`
    /// ([`bounding_sphere`]), its centre in light space: in closed form for a
    /// symmetric pinhole camera, whose centre lies on the view axis.
    fn slice_sphere(&self, n: f64, f: f64) -> (DVec3, f64) {
        match self.camera.symmetric_k {
            Some(k) => {
                let (depth, radius) = symmetric_slice_sphere(k, n, f);
                // View-space (0, 0, -depth) in light space.
                let m = &self.light_from_view;
                (m.w_axis.truncate() - m.z_axis.truncate() * depth, radius)
            }
            None => {
                let (center, radius) = bounding_sphere(&self.camera.view_corners(n, f));
                (self.light_from_view.transform_point3(center), radius)
            }
        }
    }

    /// Fits the slice `[near, far]`; `held` is the caller-held map of the stable
    /// fit (see [`CascadeState`]), used only with the stable fit and scene bounds.
    fn fit(
        &self,
        near: f32,
        far: f32,
        held: Option<HeldSlot<'_>>,
    ) -> Result<Cascade, FrustumError> {
        let mut cascade = Cascade::PLACEHOLDER;
        self.fit_into(near, far, held, &mut cascade)?;
        Ok(cascade)
    }

    /// [`Fitter::fit`] into `out` (unchanged on error).
    pub(crate) fn fit_into(
        &self,
        near: f32,
        far: f32,
        held: Option<HeldSlot<'_>>,
        out: &mut Cascade,
    ) -> Result<(), FrustumError> {
        let (n, f) = self.camera.check_slice(near, far)?;
        if let (Some(scene), CascadeFit::Stable, Some(mut held)) =
            (&self.scene, self.options.fit, held)
        {
            return self.fit_held(n, f, scene, &mut held, out);
        }
        let light = &self.light_from_world;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        // Largest world coordinate of the fitted points, for the invertibility test
        // (of the slice's corners, computed only if that test needs it).
        let mut reach = None;
        match &self.scene {
            Some(scene) => {
                let body = self.receivers_body(n, f, scene)?;
                let mut max_abs = 0.0f64;
                for v in body.vertices() {
                    let p = v.as_dvec3();
                    max_abs = max_abs.max(p.abs().max_element());
                    let q = light.transform_point3(p);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
                reach = Some(max_abs);
            }
            // The stable fit sizes the box by the slice's sphere: only the depth range
            // is needed.
            None if self.options.fit == CascadeFit::Stable => {
                (lo.z, hi.z) = self.light_rays.range(2, n, f);
            }
            None => (lo, hi) = self.light_rays.bounds(n, f),
        }
        let res = f64::from(self.options.resolution);
        let (xy_lo, xy_hi, texel) = match self.options.fit {
            CascadeFit::Tight => {
                let size = (hi - lo).truncate();
                let scale = lo.abs().max(hi.abs()).max_element().max(1e-30);
                // A slice seen edge-on from the light is flat: give it a sliver of area.
                let pad = (DVec2::splat(1e-6 * scale) - size).max(DVec2::ZERO) * 0.5;
                let (a, b) = (lo.truncate() - pad, hi.truncate() + pad);
                (a, b, (b - a).max_element() / res)
            }
            CascadeFit::Stable if self.ladder_step().is_some() => {
                let step = self.ladder_step().unwrap_or(2.0);
                ladder_box(lo.truncate(), hi.truncate(), step, res)?
            }
            CascadeFit::Stable => {
                let (center, radius) = self.slice_sphere(n, f);
                // One texel of slack on each side absorbs the snap (at most half a texel).
                let texel = 2.0 * radius / (res - 2.0);
                if !(texel > 0.0 && texel.is_finite()) {
                    return Err(FrustumError::EmptyBounds);
                }
                let snapped =
                    DVec2::new(math::round(center.x / texel), math::round(center.y / texel))
                        * texel;
                let half = DVec2::splat(0.5 * res * texel);
                (snapped - half, snapped + half, texel)
            }
        };
        let frame = Frame {
            light_from_world: *light,
            light_from_world32: self.light_from_world32,
        };
        let fitted = FittedBox {
            xy_lo,
            xy_hi,
            texel,
            depth: (-hi.z, -lo.z),
            reach,
        };
        self.finish(n, f, &frame, &fitted, out)
    }

    /// The vertices of slice `[n, f]` ∩ receivers. A slice too thin to clip
    /// reliably is treated like one that misses the receivers
    /// ([`FrustumError::SliceOutsideScene`]): the caller falls back to the whole
    /// slice.
    fn receivers_body(
        &self,
        n: f64,
        f: f64,
        scene: &SceneBounds,
    ) -> Result<ConvexBody, FrustumError> {
        let corners = self.camera.world_corners(n, f);
        let body =
            ConvexBody::from_dcorners_aabb(&corners, &scene.receivers).map_err(|e| match e {
                FrustumError::DegenerateFrustum => FrustumError::SliceOutsideScene,
                e => e,
            })?;
        if body.is_empty() {
            return Err(FrustumError::SliceOutsideScene);
        }
        Ok(body)
    }

    /// The stable fit with a caller-held map ([`held_box`]): a square over
    /// slice ∩ receivers whose side and orientation are kept across frames.
    fn fit_held(
        &self,
        n: f64,
        f: f64,
        scene: &SceneBounds,
        held: &mut HeldSlot<'_>,
        out: &mut Cascade,
    ) -> Result<(), FrustumError> {
        let body = self.receivers_body(n, f, scene)?;
        let points = body.vertices().iter().map(|v| v.as_dvec3());
        let b = held_box(
            &points,
            self.light_dir,
            &self.light_from_world,
            f64::from(self.options.resolution),
            held,
        )?;
        let (mut z_lo, mut z_hi, mut reach) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for p in points {
            reach = reach.max(p.abs().max_element());
            let z = b.light_from_world.transform_point3(p).z;
            z_lo = z_lo.min(z);
            z_hi = z_hi.max(z);
        }
        let frame = Frame {
            light_from_world: b.light_from_world,
            light_from_world32: b.light_from_world.as_mat4(),
        };
        let fitted = FittedBox {
            xy_lo: b.lo,
            xy_hi: b.hi,
            texel: b.texel,
            depth: (-z_hi, -z_lo),
            reach: Some(reach),
        };
        self.finish(n, f, &frame, &fitted, out)
    }

    /// The cascade of slice `[n, f]` for the light-space rectangle of `fitted` in
    /// `frame`: depth range pulled back to the casters over it, matrices, checks.
    fn finish(
        &self,
        n: f64,
        f: f64,
        frame: &Frame,
        fitted: &FittedBox,
        out: &mut Cascade,
    ) -> Result<(), FrustumError> {
        let light = &frame.light_from_world;
        let FittedBox {
            xy_lo,
            xy_hi,
            texel,
            reach,
            ..
        } = *fitted;
        // Light space looks down -Z: distance from the light is -z.
        let (mut near_dist, far_dist) = fitted.depth;
        let mut caster_depth = None;
        if let Some(scene) = &self.scene {
            if let Some((c_near, c_far)) = caster_depth_over(light, &scene.casters, xy_lo, xy_hi)? {
                caster_depth = Some((c_near as f32, c_far as f32));
                near_dist = near_dist.min(c_near);
            }
        }
        // Finite distances (of finite points and bounds): no NaN for `max_num`.
        let depth_scale = math::max_num(math::max_num(near_dist.abs(), far_dist.abs()), 1e-30);
        let min_thickness = 1e-5 * depth_scale;
        let (near_dist, far_dist) = if far_dist - near_dist < min_thickness {
            let mid = 0.5 * (near_dist + far_dist);
            (mid - min_thickness, mid + min_thickness)
        } else {
            (near_dist, far_dist)
        };
        let (scale, offset) = crate::projection::orthographic_rows(
            xy_lo,
            xy_hi,
            near_dist,
            far_dist,
            self.options.reversed_z,
        );
        let clip_from_world = crate::projection::rows_times_affine(scale, offset, light).as_mat4();
        // The light frame is a rotation: most fits are invertible by
        // `ortho_rotation_invertible` at a lower bound of the world scale, without the
        // general test (and without the slice's world extent).
        let certain = crate::mapping::ortho_rotation_invertible(
            scale.truncate(),
            offset.truncate(),
            depth_scale.max(reach.unwrap_or(0.0)),
        );
        let reach = || reach.unwrap_or_else(|| self.camera.world_rays.max_abs(n, f));
        if !(certain || crate::is_invertible(&clip_from_world, reach().max(depth_scale) as f32)) {
            return Err(FrustumError::DegenerateFrustum);
        }
        let transform = ShadowTransform::new(
            frame.light_from_world32,
            clip_from_world,
            self.options.reversed_z,
            LightDirection::Directional(self.light_dir.as_vec3()),
        );
        *out = Cascade {
            view_depth: (n as f32, f as f32),
            transform,
            texel_world_size: texel as f32,
            light_depth: (near_dist as f32, far_dist as f32),
            caster_depth,
            receivers_missed: false,
        };
        Ok(())
    }
}

/// The light frame a cascade is fitted in.
struct Frame {
    light_from_world: DMat4,
    /// `light_from_world` in `f32`, as stored in the cascade.
    light_from_world32: Mat4,
}

/// A cascade's fitted light-space rectangle and depth range, before the casters.
struct FittedBox {
    xy_lo: DVec2,
    xy_hi: DVec2,
    /// World size of one texel (the larger side).
    texel: f64,
    /// Light-space distances `(near, far)` of the receivers.
    depth: (f64, f64),
    /// Largest world coordinate of the fitted points, for the invertibility test
    /// (`None`: not computed; the slice's extent is then read if the test needs it).
    reach: Option<f64>,
}

/// The stable box over the light-space footprint `[lo, hi]` with a ladder of sizes:
/// side `step^ceil(log_step(s))` for the needed side `s` (the footprint's larger side
/// plus one texel of slack on each side for the snap), centre snapped to whole texels.
/// Returns the box and its texel size.
fn ladder_box(
    lo: DVec2,
    hi: DVec2,
    step: f64,
    res: f64,
) -> Result<(DVec2, DVec2, f64), FrustumError> {
    let needed = (hi - lo).max_element() * res / (res - 2.0);
    let scale = lo.abs().max(hi.abs()).max_element();
    // A footprint seen edge-on still gets a box f32 can resolve around it.
    let needed = needed.max(1e-5 * scale);
    if !(needed > 0.0 && needed.is_finite()) {
        return Err(FrustumError::EmptyBounds);
    }
    let rung = math::ceil(math::ln(needed) / math::ln(step));
    let mut side = math::powf(step, rung);
    // Rounding of the logarithm may land one rung low.
    if side < needed {
        side *= step;
    }
    let texel = side / (res - 2.0);
    let center = (lo + hi) * 0.5;
    let snapped = (center / texel).round() * texel;
    let half = DVec2::splat(0.5 * res * texel);
    Ok((snapped - half, snapped + half, texel))
}

/// Light-space distance range of the part of the caster box that lies over the
/// footprint `[xy_lo, xy_hi]` (the prism swept along the light), `None` if none does.
fn caster_depth_over(
    light_from_world: &DMat4,
    casters: &Aabb,
    xy_lo: DVec2,
    xy_hi: DVec2,
) -> Result<Option<(f64, f64)>, FrustumError> {
    let casters = casters.validate()?;
    // Points within f32 rounding of the box and the prism count as inside.
    let scale = casters.min.abs().max(casters.max.abs()).max_element();
    let tolerance = 8.0 * f64::from(f32::EPSILON) * f64::from(scale.max(f32::MIN_POSITIVE));
    let prism = LightPrism::new(light_from_world, xy_lo, xy_hi);
    // Distance is minus the light-space z (which points toward the light).
    Ok(prism
        .box_depth_range(&casters, tolerance)
        .map(|(z_lo, z_hi)| (-z_hi, -z_lo)))
}
