use arrayvec::ArrayVec;
use glam::{DVec2, DVec3, Mat4, Vec3};

use crate::cascade_fit::{FittedBox, Fitter};
use crate::cascade_state::CascadeState;
use crate::mapping::{ShadowSample, ShadowTransform, project_dmat, projective_uv_differentials};
use crate::split::CascadeBlend;
use crate::{
    Camera, CascadeSplits, FrustumError, MAX_CASCADES, SceneBounds, ShadowMapping, ValidCamera,
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

/// A caller's measure of a stable cascade's candidate maps: the error of one
/// candidate cascade over its slice, lower is finer (not finite: not measured,
/// never preferred); see [`CascadeSet::fit_with_state_ranked`].
pub type CascadeMeasure<'a> = &'a dyn Fn(&Cascade) -> f64;

/// What the stable fit holds across frames, and the caller's measure of new
/// maps (see [`CascadeSet::fit_with_state_ranked`]).
struct Held<'a> {
    state: &'a mut CascadeState,
    measure: Option<CascadeMeasure<'a>>,
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
        Self::fit_held(camera, light_direction, splits, options, state, None)
    }

    /// As [`CascadeSet::fit_with_state`], with the caller measuring a stable
    /// cascade's candidate maps where a new one is chosen: `measure` is asked for
    /// the cascade over the slice in this frame's orientation (first, the one
    /// [`CascadeSet::fit_with_state`] keeps) and in up to
    /// [`MAX_HELD_CANDIDATES`](crate::MAX_HELD_CANDIDATES)` - 1` others that box
    /// the slice ∩ receivers in less area, each with a side along an edge of its
    /// outline across the light (the least-area rectangle around a convex polygon
    /// has one: Freeman and Shapira, 1975); the least error is kept (the first on
    /// ties). Where the turn allowance ([`STABLE_TURN`](crate::STABLE_TURN))
    /// widens the kept map, it is asked for the tight box of the slice in this
    /// frame's orientation, and where the kept map measures more than
    /// [`STABLE_MAX_OVER_TIGHT`](crate::STABLE_MAX_OVER_TIGHT) times that, for
    /// the kept orientation's map without the allowance, kept instead where finer.
    ///
    /// A frame that follows the view boxes a footprint cut by a room's walls at
    /// whatever angle the view makes with them; a frame along the walls can hold
    /// the same footprint, turn allowance included, in half the area. Less area
    /// is not always finer where the eye looks (the texels' shape and orientation
    /// against the view count too), so the measure is the caller's: a renderer with
    /// the frame's visible samples (a depth and normal buffer) measures each
    /// candidate's error on them, as `shadowmap::fit` does.
    ///
    /// # Errors
    /// As [`CascadeSet::fit_with_state`].
    pub fn fit_with_state_ranked(
        camera: &ValidCamera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
        state: &mut CascadeState,
        measure: CascadeMeasure<'_>,
    ) -> Result<Self, FrustumError> {
        Self::fit_held(
            camera,
            light_direction,
            splits,
            options,
            state,
            Some(measure),
        )
    }

    fn fit_held(
        camera: &ValidCamera,
        light_direction: Vec3,
        splits: &CascadeSplits,
        options: &CascadeOptions,
        state: &mut CascadeState,
        measure: Option<CascadeMeasure<'_>>,
    ) -> Result<Self, FrustumError> {
        let mut next = *state;
        let held = Some(Held {
            state: &mut next,
            measure,
        });
        let set = Self::fit_inner(camera, light_direction, splits, options, held)?;
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
        held: Option<Held<'_>>,
    ) -> Result<Self, FrustumError> {
        // The result is made first and filled in place: the set is large.
        let mut out = Ok(Self {
            cascades: ArrayVec::new(),
            splits: splits.clone(),
            view_from_world: camera.geometry.view_from_world32,
            resolution: options.resolution,
        });
        if let Ok(set) = &mut out
            && let Err(e) = set.fill(camera, light_direction, options, held)
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
        held: Option<Held<'_>>,
    ) -> Result<(), FrustumError> {
        let checked = Fitter::check(light_direction, options)?;
        let mut fitter = Fitter::new(&camera.geometry, checked, options);
        let mut state = None;
        if let Some(held) = held {
            state = Some(held.state);
            if let Some(measure) = held.measure {
                fitter.measure_with(measure);
            }
        }
        let (splits, set) = (&self.splits, &mut self.cascades);
        // Cascades of an earlier fit (a refit) are overwritten where they are: every
        // fit writes every field.
        set.truncate(splits.count());
        if !fitter.has_scene() {
            return fill_slices(&fitter, splits, set);
        }
        for i in 0..splits.count() {
            let (near, far) = splits
                .cascade_range(i)
                .ok_or(FrustumError::InvalidCascadeCount)?;
            let held = state.as_deref_mut().and_then(|s| s.slot(splits.count(), i));
            keep(set, i, fitter.fit_or_whole(near, far, held)?)?;
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

/// The cascades of whole slices (no scene bounds) into `set`. The stable fit's
/// slices are fitted in two passes, every slice's box first, then every slice's
/// matrices: each box is a chain of dependent square roots and divisions, and in
/// two passes the chains of different slices are near enough in the instruction
/// stream to overlap (a 4-cascade stable refit 0.88x the time of the Bevy
/// transcription in `cargo bench --bench builders`, the median of seven runs, from
/// about 1.02x in one pass). The tight box is a few minima and maxima: one pass,
/// without storing the boxes, measured faster there.
#[inline(always)]
fn fill_slices(
    fitter: &Fitter<'_>,
    splits: &CascadeSplits,
    set: &mut ArrayVec<Cascade, MAX_CASCADES>,
) -> Result<(), FrustumError> {
    let range = |i: usize| -> Result<(f64, f64), FrustumError> {
        let (near, far) = splits
            .cascade_range(i)
            .ok_or(FrustumError::InvalidCascadeCount)?;
        fitter.check_slice(near, far)
    };
    if !fitter.is_stable() {
        for i in 0..splits.count() {
            let (n, f) = range(i)?;
            // By value: inline, its fields go straight to the set.
            keep(set, i, fitter.fit_slice(n, f, None)?)?;
        }
        return Ok(());
    }
    let mut boxes = ArrayVec::<(f64, f64, FittedBox), MAX_CASCADES>::new();
    for i in 0..splits.count() {
        let (n, f) = range(i)?;
        let b = fitter.slice_box(n, f)?;
        boxes
            .try_push((n, f, b))
            .map_err(|_| FrustumError::InvalidCascadeCount)?;
    }
    for (i, (n, f, b)) in boxes.iter().enumerate() {
        keep(set, i, fitter.finish_slice(*n, *f, b, None)?)?;
    }
    Ok(())
}

/// Stores cascade `i` of a set being fitted: over the one an earlier fit left there,
/// or as the next.
#[inline(always)]
fn keep(
    set: &mut ArrayVec<Cascade, MAX_CASCADES>,
    i: usize,
    cascade: Cascade,
) -> Result<(), FrustumError> {
    match set.get_mut(i) {
        Some(kept) => *kept = cascade,
        None => set
            .try_push(cascade)
            .map_err(|_| FrustumError::InvalidCascadeCount)?,
    }
    Ok(())
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

    /// The derivative of the cascade that stores `centre` (selected by view depth),
    /// whichever cascades store the points `around` it: the texel footprint at a
    /// point is that of its own map. (Leaving out the points whose neighbours cross
    /// into another cascade leaves out, at a coarse sampling of the image, most
    /// points of the far cascades, whose slices are deep.)
    fn uv_differentials(&self, centre: DVec3, around: &[DVec3; 4]) -> Option<[DVec2; 2]> {
        let index = self.select_by_depth(centre.as_vec3())?.index;
        let cascade = self.cascades.get(index)?;
        projective_uv_differentials(&cascade.transform.uv_from_world.as_dmat4(), centre, around)
    }
}
