use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, Mat4, Vec3};

use crate::body::ConvexBody;
use crate::bounding_sphere::{bounding_sphere, symmetric_slice_sphere};
use crate::camera::CameraGeometry;
use crate::cascade_state::{CascadeState, HeldSlot, held_box};
use crate::light::unit;
use crate::light_prism::LightPrism;
use crate::mapping::{
    LightDirection, ShadowSample, ShadowTransform, project_dmat, projective_uv_differentials,
};
use crate::rays::Rays;
use crate::split::CascadeBlend;
use crate::{
    Aabb, Camera, CascadeSplits, FrustumError, MAX_CASCADES, MAX_RESOLUTION, SceneBounds,
    ShadowMapping, ValidCamera, math,
};

/// How a cascade's light-space rectangle is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CascadeFit {
    /// The light-space box of the slice (or of slice ∩ receivers): the most texels on
    /// the slice, but the map's size and texel grid change as the camera moves or
    /// turns, so shadow edges shimmer.
    Tight,
    /// Shimmer-free. Without a caller-held state: the box of the slice's bounding
    /// sphere, snapped to whole texels against a fixed world anchor: the size is
    /// invariant under camera rotation and camera motion moves the map by whole
    /// texels. With one ([`CascadeSet::fit_with_state`], scene bounds): the box of
    /// slice ∩ receivers with a small margin for turning and growth, its extents and
    /// orientation held across frames with hysteresis ([`CascadeState`]), snapped
    /// likewise, so it pays a few percent over the tight fit instead of the sphere.
    /// With a power-of-two resolution the `f32` matrices keep the motion exact (the
    /// snapped offset `k / resolution` is representable); other resolutions drift by
    /// about `f32::EPSILON * k` texels after `k` texels of travel.
    #[default]
    Stable,
}

/// Knobs of the directional cascade fit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[non_exhaustive]
pub struct CascadeOptions {
    /// Texels per side of each cascade's map, in `4..=65536`.
    pub resolution: u32,
    /// Tight or stable.
    pub fit: CascadeFit,
    /// Reversed-Z depth (1 at the light's near plane).
    pub reversed_z: bool,
    /// Orients the light frame (see [`directional_light_from_world`](crate::directional_light_from_world)).
    /// The stable fit with a caller-held state takes it only when it (re)sizes a
    /// map, and then holds that orientation.
    pub up_hint: Vec3,
    /// Scene bounds for scene-dependent fitting.
    pub scene: Option<SceneBounds>,
    /// Stable fit with scene bounds only. `None` (the default): every cascade is sized
    /// by the bounding sphere of its whole slice. `Some(step)`, `step` in
    /// `(1, 16]`: the box is fitted to the slice ∩ receivers and its side is
    /// rounded up to the next power of `step` in world units, `step^ceil(log_step(s))`
    /// for a needed side `s` (a stateless ladder of sizes). The size then stays fixed
    /// while the needed side moves within one rung, so the texel grid keeps its
    /// whole-texel motion, and it is never more than `step` times the needed side,
    /// where the whole slice's sphere can be many times the visible receivers.
    pub stable_size_step: Option<f32>,
}

impl Default for CascadeOptions {
    fn default() -> Self {
        Self {
            resolution: 2048,
            fit: CascadeFit::Stable,
            reversed_z: false,
            up_hint: Vec3::Y,
            scene: None,
            stable_size_step: None,
        }
    }
}

impl CascadeOptions {
    /// With this resolution.
    #[must_use]
    pub const fn with_resolution(mut self, resolution: u32) -> Self {
        self.resolution = resolution;
        self
    }
    /// With this fit.
    #[must_use]
    pub const fn with_fit(mut self, fit: CascadeFit) -> Self {
        self.fit = fit;
        self
    }
    /// With reversed-Z on or off.
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }
    /// With this up hint for the light frame.
    #[must_use]
    pub const fn with_up_hint(mut self, up_hint: Vec3) -> Self {
        self.up_hint = up_hint;
        self
    }
    /// With scene bounds (scene-dependent fit).
    #[must_use]
    pub const fn with_scene(mut self, scene: Option<SceneBounds>) -> Self {
        self.scene = scene;
        self
    }
    /// With this size ladder for the stable fit (see
    /// [`CascadeOptions::stable_size_step`]).
    #[must_use]
    pub const fn with_stable_size_step(mut self, step: Option<f32>) -> Self {
        self.stable_size_step = step;
        self
    }
}

/// One fitted cascade.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cascade {
    /// View depths `(near, far)` this cascade covers, blend band included.
    pub view_depth: (f32, f32),
    /// The matrices.
    pub transform: ShadowTransform,
    /// World size of one texel (the larger side for a non-square tight fit).
    pub texel_world_size: f32,
    /// Light-space distances mapped to the near and far end of the depth range.
    pub light_depth: (f32, f32),
    /// Light-space distance range of the casters that overlap this cascade, if scene
    /// bounds were given. Casters nearer than `light_depth.0` cannot occur (the near
    /// plane is pulled back to them); a renderer that instead keeps the receivers'
    /// near plane can clamp depth ("pancaking") over this range.
    pub caster_depth: Option<(f32, f32)>,
    /// The scene-dependent fit found no receivers in the slice and fell back to the
    /// whole slice.
    pub receivers_missed: bool,
}

impl Cascade {
    /// A cascade's place before it is fitted (zeros: cheap to write).
    const PLACEHOLDER: Self = Self {
        view_depth: (0.0, 0.0),
        transform: ShadowTransform {
            light_from_world: Mat4::ZERO,
            clip_from_world: Mat4::ZERO,
            uv_from_world: Mat4::ZERO,
            reversed_z: false,
            light: LightDirection::Directional(Vec3::ZERO),
        },
        texel_world_size: 0.0,
        light_depth: (0.0, 0.0),
        caster_depth: None,
        receivers_missed: false,
    };
}

/// A fitted set of cascades for a directional light.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CascadeSet {
    /// One cascade per split, near to far.
    pub cascades: ArrayVec<Cascade, MAX_CASCADES>,
    /// The splits they were fitted to.
    pub splits: CascadeSplits,
    /// The camera's view transform, for selection by depth.
    pub view_from_world: Mat4,
    /// The resolution of each cascade.
    pub resolution: u32,
}

impl CascadeSet {
    /// Fits one cascade per split of `splits` for a directional light travelling along
    /// `light_direction`.
    ///
    /// With scene bounds, a slice that misses the receivers falls back to the whole
    /// slice and sets [`Cascade::receivers_missed`]; the set is still valid.
    ///
    /// # Errors
    /// Any error of [`Camera::validate`]; [`FrustumError::NonFinite`] or
    /// [`FrustumError::ZeroDirection`] for the light; [`FrustumError::InvalidResolution`];
    /// [`FrustumError::InvalidDepthRange`] if the splits leave the camera's range;
    /// [`FrustumError::EmptyBounds`] / [`FrustumError::NonFinite`] for bad scene bounds;
    /// [`FrustumError::InvalidSplitParameter`] for a
    /// [`CascadeOptions::stable_size_step`] outside `(1, 16]`.
    pub fn fit(
        camera: &Camera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
    ) -> Result<Self, FrustumError> {
        Self::fit_valid(&ValidCamera::new(camera)?, light_direction, splits, options)
    }

    /// As [`CascadeSet::fit`] for a camera validated once per frame (see
    /// [`ValidCamera`]): the same cascades, without checking the camera again.
    ///
    /// # Errors
    /// As [`CascadeSet::fit`], except the camera's.
    #[inline]
    pub fn fit_valid(
        camera: &ValidCamera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
    ) -> Result<Self, FrustumError> {
        Self::fit_inner(camera, light_direction, splits, options, None)
    }

    /// [`CascadeSet::fit_valid`] into this set, in place: what a renderer that keeps
    /// one set per light and refits it every frame calls, without moving a new set
    /// (it holds room for [`MAX_CASCADES`] cascades) out of a `Result` into its
    /// place. The same cascades as [`CascadeSet::fit_valid`].
    ///
    /// ```
    /// use glam::Vec3;
    /// use shadowmap_frustum::{Camera, CascadeOptions, CascadeSet, CascadeSplits, Projection,
    ///     SplitScheme, ValidCamera};
    ///
    /// let camera = Camera::look_to(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Z, Vec3::Y,
    ///     Projection::perspective(1.0, 1.5, 0.1, 200.0))?;
    /// let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, 4, 0.1, 200.0)?;
    /// let (sun, options) = (Vec3::new(0.3, -1.0, 0.2), CascadeOptions::default());
    /// let valid = ValidCamera::new(&camera)?;
    /// let mut set = CascadeSet::fit_valid(&valid, sun, &splits, &options)?; // first frame
    /// set.refit_valid(&valid, sun, &splits, &options)?; // every later frame
    /// assert_eq!(set, CascadeSet::fit_valid(&valid, sun, &splits, &options)?);
    /// # Ok::<(), shadowmap_frustum::FrustumError>(())
    /// ```
    ///
    /// # Errors
    /// As [`CascadeSet::fit_valid`]; the set is then left without cascades.
    pub fn refit_valid(
        &mut self,
        camera: &ValidCamera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
    ) -> Result<(), FrustumError> {
        self.cascades.clear();
        self.splits.clone_from(splits);
        self.view_from_world = camera.geometry.view_from_world32;
        self.resolution = options.resolution;
        let fitted = self.fill(camera, light_direction, options, None);
        if fitted.is_err() {
            self.cascades.clear();
        }
        fitted
    }

    /// As [`CascadeSet::fit_valid`], with the stable fit's sizes held across frames
    /// in `state` (see [`CascadeState`]): with [`CascadeFit::Stable`] and scene
    /// bounds, each cascade's box is fitted to its slice ∩ receivers and keeps its
    /// size from the previous frame while it covers the footprint and is not too
    /// big (hysteresis), so the map moves by whole texels. This takes precedence
    /// over [`CascadeOptions::stable_size_step`]. Other fits leave `state` alone.
    ///
    /// # Errors
    /// As [`CascadeSet::fit_valid`]; `state` is unchanged on error.
    pub fn fit_with_state(
        camera: &ValidCamera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
        state: &mut CascadeState,
    ) -> Result<Self, FrustumError> {
        let mut next = *state;
        let set = Self::fit_inner(camera, light_direction, splits, options, Some(&mut next))?;
        *state = next;
        Ok(set)
    }

    /// The set, its cascades fitted by [`CascadeSet::fill`]; inline, so that a caller
    /// receives the large set where it keeps it rather than through copies.
    #[inline(always)]
    fn fit_inner(
        camera: &ValidCamera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
        state: Option<&mut CascadeState>,
    ) -> Result<Self, FrustumError> {
        // The result is made first and filled in place: the set is large.
        let mut out = Ok(Self {
            cascades: ArrayVec::new(),
            splits: splits.clone(),
            view_from_world: camera.geometry.view_from_world32,
            resolution: options.resolution,
        });
        if let Ok(set) = &mut out
            && let Err(e) = set.fill(camera, light_direction, options, state)
        {
            out = Err(e);
        }
        out
    }

    /// Fits one cascade per split of `self.splits` into `self.cascades`.
    fn fill(
        &mut self,
        camera: &ValidCamera,
        light_direction: Vec3,
        options: &CascadeOptions,
        mut state: Option<&mut CascadeState>,
    ) -> Result<(), FrustumError> {
        let checked = Fitter::check(light_direction, options)?;
        let fitter = Fitter::new(&camera.geometry, checked, options);
        let (splits, set) = (&self.splits, &mut self.cascades);
        for i in 0..splits.count() {
            let (near, far) = splits
                .cascade_range(i)
                .ok_or(FrustumError::InvalidCascadeCount)?;
            let held = state.as_deref_mut().and_then(|s| s.slot(i));
            // Fitted where it is kept: a cascade is large, and moving it out of a
            // `Result` and into the set would copy it twice.
            set.try_push(Cascade::PLACEHOLDER)
                .map_err(|_| FrustumError::InvalidCascadeCount)?;
            let Some(cascade) = set.last_mut() else {
                return Err(FrustumError::InvalidCascadeCount);
            };
            match fitter.fit_into(near, far, held, cascade) {
                Err(FrustumError::SliceOutsideScene) => {
                    fitter.fit_without_receivers(near, far, cascade)?;
                    cascade.receivers_missed = true;
                }
                other => other?,
            }
        }
        Ok(())
    }

    /// The cascade for a world point by its view depth, with the blend weight toward
    /// the next cascade.
    #[must_use]
    pub fn select_by_depth(&self, world: Vec3) -> Option<CascadeBlend> {
        let depth = -self.view_from_world.transform_point3(world).z;
        self.splits.select(depth)
    }

    /// The first cascade whose map contains the point (`uv` in `[0, 1]²` at least
    /// `margin_texels` from the border, depth in `[0, 1]`): selection by projection,
    /// which uses the finest map available where cascades overlap.
    #[must_use]
    pub fn select_by_projection(&self, world: Vec3, margin_texels: f32) -> Option<usize> {
        let margin = f64::from(margin_texels) / f64::from(self.resolution.max(1));
        self.cascades.iter().position(|c| {
            c.transform.project(world).is_some_and(|s| {
                let inside = |x: f64| x >= margin && x <= 1.0 - margin;
                inside(s.uv.x) && inside(s.uv.y) && (0.0..=1.0).contains(&s.depth)
            })
        })
    }
}

impl ShadowMapping for CascadeSet {
    /// Selects by view depth; the layer is the cascade index.
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let blend = self.select_by_depth(world.as_vec3())?;
        let cascade = self.cascades.get(blend.index)?;
        let mut s = project_dmat(&cascade.transform.uv_from_world.as_dmat4(), world)?;
        s.layer = blend.index as u32;
        Some(s)
    }

    /// Every point selected by view depth, all in one cascade; that cascade's
    /// derivative.
    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        let index = self.select_by_depth(centre.as_vec3())?.index;
        for p in around {
            if self.select_by_depth(p.as_vec3())?.index != index {
                return None;
            }
        }
        let cascade = self.cascades.get(index)?;
        projective_uv_differentials(&cascade.transform.uv_from_world.as_dmat4(), centre, around)
    }
}

/// Fits a single cascade covering view depths `[near_depth, far_depth]`.
///
/// # Errors
/// As [`CascadeSet::fit`], plus [`FrustumError::SliceOutsideScene`] when scene bounds
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
/// per call of [`CascadeSet::fit`].
struct Fitter<'a> {
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
    fn check(
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
    fn new(
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

    fn fit_without_receivers(
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
    fn fit_into(
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
