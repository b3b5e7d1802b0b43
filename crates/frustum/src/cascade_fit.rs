//! The fit of one cascade: everything a slice's fit needs that does not depend on
//! the slice (light frame, the camera's edge rays in light space, checked options),
//! then each slice's light-space box (tight, stable sphere, stable ladder, or held
//! across frames), its depth range pulled back to the casters, and its matrices.

use core::cell::RefCell;

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, Mat4, Vec3};

use crate::body::ConvexBody;
use crate::bounding_sphere::{bounding_sphere, symmetric_slice_sphere};
use crate::camera::CameraGeometry;
use crate::cascade::{Cascade, CascadeFit, CascadeMeasure, CascadeOptions};
use crate::cascade_state::{HeldBox, HeldSlot, MAX_HELD_CANDIDATES, MeasureBox, held_box};
use crate::light::unit;
use crate::light_prism::LightPrism;
use crate::mapping::{LightDirection, ShadowTransform};
use crate::rays::Rays;
use crate::{
    Aabb, Camera, FrustumError, MAX_FRUSTUM_AABB_VERTICES, MAX_RESOLUTION, SceneBounds, math,
};

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
    /// The caller's measure of a stable cascade's candidate maps (see
    /// [`CascadeSet::fit_with_state_ranked`](crate::CascadeSet::fit_with_state_ranked)).
    measure: Option<CascadeMeasure<'a>>,
    light_dir: DVec3,
    light_from_world: DMat4,
    /// `light_from_world` in `f32`, as stored in every cascade.
    light_from_world32: Mat4,
    /// The eye and the view axis (view-space `+Z`) in light space: the centre of a
    /// symmetric pinhole slice's sphere lies on that axis.
    eye_light: DVec3,
    axis_light: DVec3,
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
    /// where it is used rather than moved out of a `Result`, and inline, so that its
    /// parts are computed where the fitter is kept rather than copied there.
    #[inline(always)]
    pub(crate) fn new(
        camera: &'a CameraGeometry,
        (light_dir, scene): (DVec3, Option<SceneBounds>),
        options: &CascadeOptions,
    ) -> Self {
        let light_from_world = crate::projection::light_rotation_inline(light_dir, options.up_hint);
        let view = &camera.world_from_view;
        Self {
            camera,
            measure: None,
            light_dir,
            light_from_world,
            light_from_world32: light_from_world.as_mat4(),
            eye_light: light_from_world.transform_point3(view.w_axis.truncate()),
            axis_light: light_from_world.transform_vector3(view.z_axis.truncate()),
            // The stable fit reads only the light depth of the slice's corners.
            light_rays: camera.world_rays.mapped(
                &light_from_world,
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

    /// Gives the stable fit the caller's measure of candidate maps.
    pub(crate) fn measure_with(&mut self, measure: CascadeMeasure<'a>) {
        self.measure = Some(measure);
    }

    /// The view depths `[near, far]` checked against the camera's range, in `f64`.
    #[inline(always)]
    pub(crate) fn check_slice(&self, near: f32, far: f32) -> Result<(f64, f64), FrustumError> {
        self.camera.check_slice(near, far)
    }

    /// Whether the fit is the stable one.
    #[inline(always)]
    pub(crate) fn is_stable(&self) -> bool {
        self.options.fit == CascadeFit::Stable
    }

    /// Whether the fit has scene bounds.
    pub(crate) fn has_scene(&self) -> bool {
        self.scene.is_some()
    }

    /// [`Fitter::fit`], falling back to the whole slice, without the receivers and
    /// casters of the scene bounds, for a slice that misses the receivers (marked
    /// [`Cascade::receivers_missed`]).
    #[inline(never)]
    pub(crate) fn fit_or_whole(
        &self,
        near: f32,
        far: f32,
        held: Option<HeldSlot<'_>>,
    ) -> Result<Cascade, FrustumError> {
        match self.fit(near, far, held) {
            Err(FrustumError::SliceOutsideScene) => {
                let (n, f) = self.camera.check_slice(near, far)?;
                let mut whole = self.fit_slice(n, f, None)?;
                whole.receivers_missed = true;
                Ok(whole)
            }
            fitted => fitted,
        }
    }

    /// The bounding sphere of the slice between view depths `n < f`
    /// ([`bounding_sphere`]), its centre in light space: in closed form for a
    /// symmetric pinhole camera, whose centre lies on the view axis.
    #[inline(always)]
    fn slice_sphere(&self, n: f64, f: f64) -> (DVec3, f64) {
        match self.camera.symmetric_k {
            Some(k) => {
                let (depth, radius) = symmetric_slice_sphere(k, n, f);
                // View-space (0, 0, -depth) in light space.
                (self.eye_light - self.axis_light * depth, radius)
            }
            None => {
                let (center, radius) = bounding_sphere(&self.camera.view_corners(n, f));
                let world = self.camera.world_from_view.transform_point3(center);
                (self.light_from_world.transform_point3(world), radius)
            }
        }
    }

    /// Fits the slice `[near, far]`; `held` is the caller-held map of the stable
    /// fit (see [`CascadeState`]), used only with the stable fit and scene bounds.
    /// Inline, by value: without scene bounds the cascade's fields are written
    /// straight to where the caller keeps it.
    #[inline(always)]
    pub(crate) fn fit(
        &self,
        near: f32,
        far: f32,
        held: Option<HeldSlot<'_>>,
    ) -> Result<Cascade, FrustumError> {
        let (n, f) = self.camera.check_slice(near, far)?;
        match &self.scene {
            Some(scene) => self.fit_scene(n, f, scene, held),
            None => self.fit_slice(n, f, None),
        }
    }

    /// The whole slice `[n, f]`: the light-space box of its corners (tight) or of
    /// its bounding sphere (stable), its near plane pulled back to `casters`.
    #[inline(always)]
    pub(crate) fn fit_slice(
        &self,
        n: f64,
        f: f64,
        casters: Option<&Aabb>,
    ) -> Result<Cascade, FrustumError> {
        let fitted = self.slice_box(n, f)?;
        self.finish_slice(n, f, &fitted, casters)
    }

    /// The light-space box of the whole slice `[n, f]`: of its corners (tight) or
    /// of its bounding sphere (stable). Inline: the fit of a set without scene
    /// bounds is this and [`Fitter::finish_slice`] once per slice, and calls cost
    /// more than their steps.
    #[inline(always)]
    pub(crate) fn slice_box(&self, n: f64, f: f64) -> Result<FittedBox, FrustumError> {
        let res = f64::from(self.options.resolution);
        let (xy_lo, xy_hi, texel, z) = match self.options.fit {
            CascadeFit::Stable => {
                // The sphere sizes the box: of the corners only the depth range is read.
                let z = self.light_rays.range(2, n, f);
                let (center, radius) = self.slice_sphere(n, f);
                let (a, b, texel) = sphere_box(center.truncate(), radius, res)?;
                (a, b, texel, z)
            }
            CascadeFit::Tight => {
                let (lo, hi) = self.light_rays.bounds(n, f);
                let (a, b, texel) = tight_box(lo, hi, res);
                (a, b, texel, (lo.z, hi.z))
            }
        };
        Ok(FittedBox {
            xy_lo,
            xy_hi,
            texel,
            depth: (-z.1, -z.0),
            // The slice's corners, read only if the invertibility test needs them.
            reach: None,
        })
    }

    /// The cascade of the whole slice `[n, f]` in the fitter's light frame for its
    /// box `fitted` ([`Fitter::slice_box`]), near plane pulled back to `casters`.
    #[inline(always)]
    pub(crate) fn finish_slice(
        &self,
        n: f64,
        f: f64,
        fitted: &FittedBox,
        casters: Option<&Aabb>,
    ) -> Result<Cascade, FrustumError> {
        let frame = Frame {
            light_from_world: &self.light_from_world,
            light_from_world32: &self.light_from_world32,
        };
        self.finish(n, f, &frame, fitted, casters)
    }

    /// The slice `[n, f]` ∩ receivers: held across frames ([`Fitter::fit_held`]),
    /// or its light-space box (tight), the box of the slice's sphere (stable), or a
    /// rung of the size ladder over it (stable with
    /// [`CascadeOptions::stable_size_step`]).
    fn fit_scene(
        &self,
        n: f64,
        f: f64,
        scene: &SceneBounds,
        held: Option<HeldSlot<'_>>,
    ) -> Result<Cascade, FrustumError> {
        if let (CascadeFit::Stable, Some(mut held)) = (self.options.fit, held) {
            return self.fit_held(n, f, scene, &mut held);
        }
        let light = &self.light_from_world;
        let body = self.receivers_body(n, f, scene)?;
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        // Largest world coordinate of the fitted points, for the invertibility test.
        let mut reach = 0.0f64;
        for v in &body {
            let p = v.as_dvec3();
            reach = reach.max(p.abs().max_element());
            let q = light.transform_point3(p);
            lo = lo.min(q);
            hi = hi.max(q);
        }
        let res = f64::from(self.options.resolution);
        let (xy_lo, xy_hi, texel) = match (self.options.fit, self.options.stable_size_step) {
            (CascadeFit::Tight, _) => tight_box(lo, hi, res),
            (CascadeFit::Stable, Some(step)) => {
                ladder_box(lo.truncate(), hi.truncate(), f64::from(step), res)?
            }
            (CascadeFit::Stable, None) => {
                let (center, radius) = self.slice_sphere(n, f);
                sphere_box(center.truncate(), radius, res)?
            }
        };
        let frame = Frame {
            light_from_world: light,
            light_from_world32: &self.light_from_world32,
        };
        let fitted = FittedBox {
            xy_lo,
            xy_hi,
            texel,
            depth: (-hi.z, -lo.z),
            reach: Some(reach),
        };
        self.finish_scene(n, f, &frame, &fitted, scene)
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
    ) -> Result<ArrayVec<Vec3, MAX_FRUSTUM_AABB_VERTICES>, FrustumError> {
        let corners = self.camera.world_corners(n, f);
        let body =
            ConvexBody::dcorners_aabb_vertices(&corners, &scene.receivers).map_err(
                |e| match e {
                    FrustumError::DegenerateFrustum => FrustumError::SliceOutsideScene,
                    e => e,
                },
            )?;
        if body.is_empty() {
            return Err(FrustumError::SliceOutsideScene);
        }
        Ok(body)
    }

    /// The stable fit with a caller-held map ([`held_box`]): a box over
    /// slice ∩ receivers whose extents and orientation are kept across frames.
    /// Where a new map is chosen, the caller's measure (see
    /// [`CascadeSet::fit_with_state_ranked`](crate::CascadeSet::fit_with_state_ranked))
    /// chooses among this frame's orientation and frames along the footprint's
    /// edges, and prices the turn allowance; without one, this frame's.
    fn fit_held(
        &self,
        n: f64,
        f: f64,
        scene: &SceneBounds,
        held: &mut HeldSlot<'_>,
    ) -> Result<Cascade, FrustumError> {
        let body = self.receivers_body(n, f, scene)?;
        let points = body.iter().map(|v| v.as_dvec3());
        // The cascades the measure built, so that the kept one is not built again.
        let measured: RefCell<ArrayVec<(HeldBox, Cascade), MEASURED>> = RefCell::default();
        let measure = |b: &HeldBox| {
            let Some(measure) = self.measure else {
                return f64::INFINITY;
            };
            let Ok(cascade) = self.held_cascade(n, f, &points, b, scene) else {
                return f64::INFINITY;
            };
            let mut measured = measured.borrow_mut();
            if measured.is_full() {
                measured.remove(0);
            }
            measured.push((*b, cascade));
            measure(&cascade)
        };
        let b = held_box(
            &points,
            &scene.receivers,
            self.light_dir,
            &self.light_from_world,
            f64::from(self.options.resolution),
            held,
            self.measure.map(|_| &measure as MeasureBox<'_>),
        )?;
        let built = measured.borrow().iter().find(|(m, _)| *m == b).map(|m| m.1);
        match built {
            Some(cascade) => Ok(cascade),
            None => self.held_cascade(n, f, &points, &b, scene),
        }
    }

    /// The cascade of slice `[n, f]` over `points` (slice ∩ receivers) in the
    /// stable box `b`.
    fn held_cascade(
        &self,
        n: f64,
        f: f64,
        points: &(impl Iterator<Item = DVec3> + Clone),
        b: &HeldBox,
        scene: &SceneBounds,
    ) -> Result<Cascade, FrustumError> {
        let (mut z_lo, mut z_hi, mut reach) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
        for p in points.clone() {
            reach = reach.max(p.abs().max_element());
            let z = b.light_from_world.transform_point3(p).z;
            z_lo = z_lo.min(z);
            z_hi = z_hi.max(z);
        }
        let frame = Frame {
            light_from_world: &b.light_from_world,
            light_from_world32: &b.light_from_world.as_mat4(),
        };
        let fitted = FittedBox {
            xy_lo: b.lo,
            xy_hi: b.hi,
            texel: b.texel,
            depth: (-z_hi, -z_lo),
            reach: Some(reach),
        };
        self.finish_scene(n, f, &frame, &fitted, scene)
    }

    /// [`Fitter::finish`] with the scene's casters, in one place for the fits with
    /// scene bounds.
    #[inline(never)]
    fn finish_scene(
        &self,
        n: f64,
        f: f64,
        frame: &Frame<'_>,
        fitted: &FittedBox,
        scene: &SceneBounds,
    ) -> Result<Cascade, FrustumError> {
        self.finish(n, f, frame, fitted, Some(&scene.casters))
    }

    /// The cascade of slice `[n, f]` for the light-space rectangle of `fitted` in
    /// `frame`: depth range pulled back to the casters over it, matrices, checks.
    #[inline(always)]
    fn finish(
        &self,
        n: f64,
        f: f64,
        frame: &Frame<'_>,
        fitted: &FittedBox,
        casters: Option<&Aabb>,
    ) -> Result<Cascade, FrustumError> {
        let light = frame.light_from_world;
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
        if let Some(casters) = casters {
            if let Some((c_near, c_far)) = caster_depth_over(light, casters, xy_lo, xy_hi)? {
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
            *frame.light_from_world32,
            clip_from_world,
            self.options.reversed_z,
            LightDirection::Directional(self.light_dir.as_vec3()),
        );
        Ok(Cascade {
            view_depth: (n as f32, f as f32),
            transform,
            texel_world_size: texel as f32,
            light_depth: (near_dist as f32, far_dist as f32),
            caster_depth,
            receivers_missed: false,
        })
    }
}

/// The light frame a cascade is fitted in (borrowed: a fit reads it, and copying it
/// for every slice costs more than the reads).
struct Frame<'m> {
    light_from_world: &'m DMat4,
    /// `light_from_world` in `f32`, as stored in the cascade.
    light_from_world32: &'m Mat4,
}

/// A cascade's fitted light-space rectangle and depth range, before the casters.
pub(crate) struct FittedBox {
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

/// Most measured cascades a stable fit keeps to return the chosen one from:
/// every orientation's and the chosen one's without the turn allowance.
const MEASURED: usize = MAX_HELD_CANDIDATES + 2;

/// The tight box of the light-space bounds `[lo, hi]` (a footprint seen edge-on
/// given a sliver of area) and its texel size (the larger side's).
fn tight_box(lo: DVec3, hi: DVec3, res: f64) -> (DVec2, DVec2, f64) {
    let size = (hi - lo).truncate();
    let scale = lo.abs().max(hi.abs()).max_element().max(1e-30);
    let pad = (DVec2::splat(1e-6 * scale) - size).max(DVec2::ZERO) * 0.5;
    let (a, b) = (lo.truncate() - pad, hi.truncate() + pad);
    (a, b, (b - a).max_element() / res)
}

/// The stable box of a sphere, light-space centre `center` (x, y) and `radius`:
/// side `res` texels of `2 radius / (res - 2)` (one texel of slack on each side
/// absorbs the snap, at most half a texel), centre snapped to whole texels. Returns
/// the box and its texel size.
#[inline]
fn sphere_box(center: DVec2, radius: f64, res: f64) -> Result<(DVec2, DVec2, f64), FrustumError> {
    let texel = 2.0 * radius / (res - 2.0);
    if !math::positive_finite(texel) {
        return Err(FrustumError::EmptyBounds);
    }
    let q = center / texel;
    let snapped = DVec2::new(math::round(q.x), math::round(q.y)) * texel;
    let half = DVec2::splat(0.5 * res * texel);
    Ok((snapped - half, snapped + half, texel))
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
