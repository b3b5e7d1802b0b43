//! The shared first stage of every technique: input checks, the light frame, and the
//! focus body (frustum ∩ receivers, extruded toward the light for the casters).

use arrayvec::ArrayVec;
use core::cell::{Ref, RefCell};
use glam::{DMat4, DVec3, DVec4, Mat4, Vec3};
use shadowmap_frustum::{
    Aabb, Camera, ConvexBody, Frustum, LightDirection, LightPrism, MAX_BODY_VERTICES,
    MAX_FRUSTUM_AABB_VERTICES, SceneBounds, ShadowTransform, ValidCamera, math,
};

use crate::WarpError;
use crate::predict::Probe;

/// Largest warp ratio `1 + s d` (near-to-far texel scale along the warp axis) a
/// LiSPSM, TSM or XPSM fit uses; stronger warps are clamped to it so `f32` matrices
/// keep precision. The warp strength `s` is also limited to `MAX_WARP_RATIO / L`, `L`
/// the largest light-space coordinate of the focus body (the world's distance from
/// its origin matters: render camera-relative to lift the limit).
pub const MAX_WARP_RATIO: f64 = 1.0e4;

/// The band of angles between the view and the light over which a warp fades to the
/// uniform fit: full strength above `start_deg`, exactly uniform below `end_deg`, a
/// cubic smoothstep of the sine of the angle in between, so the fit changes
/// continuously as the light turns parallel to the view (where every perspective warp
/// of a directional light degenerates; Filament guards the same case). Shared by
/// LiSPSM and TSM.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ParallelFade {
    /// Angle (degrees) between view and light above which the warp has full strength.
    pub start_deg: f32,
    /// Angle (degrees) below which the fit is exactly uniform.
    pub end_deg: f32,
}

impl Default for ParallelFade {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ParallelFade {
    /// Fade between 10 and 3 degrees.
    pub const DEFAULT: Self = Self {
        start_deg: 10.0,
        end_deg: 3.0,
    };

    /// A band from `start_deg` down to `end_deg`.
    #[must_use]
    pub const fn new(start_deg: f32, end_deg: f32) -> Self {
        Self { start_deg, end_deg }
    }

    /// `0 <= end_deg < start_deg <= 90` (false for NaN).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.end_deg >= 0.0 && self.start_deg > self.end_deg && self.start_deg <= 90.0
    }

    /// Warp weight in `[0, 1]` for the sine of the angle between view and light.
    pub(crate) fn weight(&self, sin_gamma: f64) -> f64 {
        let deg = core::f64::consts::PI / 180.0;
        smoothstep(
            math::sin(f64::from(self.end_deg) * deg),
            math::sin(f64::from(self.start_deg) * deg),
            sin_gamma,
        )
    }
}

/// Amplitude of the camera-up term of the light frame (`sin 1°`), used while the
/// light is within 1 degree of the viewing direction (see [`frame`]).
pub(crate) const FRAME_UP_WEIGHT: f64 = 0.017_452_406_437_283_51; // sin 1°
/// `sin` of the angle where the camera-up term starts to fade out (1 degree).
pub(crate) const FRAME_BLEND_LO: f64 = 0.017_452_406_437_283_51; // sin 1°
/// `sin` of the angle above which the light frame follows the view direction only
/// (3 degrees, the default end of every warp's parallel-light fade).
pub(crate) const FRAME_BLEND_HI: f64 = 0.052_335_956_242_943_83; // sin 3°

/// Cubic smoothstep of `x` between `lo < hi`.
pub(crate) fn smoothstep(lo: f64, hi: f64, x: f64) -> f64 {
    if !(hi > lo) {
        return if x >= hi { 1.0 } else { 0.0 };
    }
    // The clamped ends without the division (rounding is monotonic, so the quotient
    // clamps the same way).
    if x <= lo {
        return 0.0;
    }
    if x >= hi {
        return 1.0;
    }
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The view a technique serves: a frustum (the whole camera or one slice), the eye,
/// and the camera's axes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct View {
    pub(crate) frustum: Frustum,
    pub(crate) eye: DVec3,
    pub(crate) forward: DVec3,
    pub(crate) up: DVec3,
}

impl View {
    pub(crate) fn camera(camera: &Camera) -> Result<Self, WarpError> {
        let frustum = camera.frustum()?;
        Self::with_frustum(camera, frustum)
    }

    pub(crate) fn with_frustum(camera: &Camera, frustum: Frustum) -> Result<Self, WarpError> {
        let eye = camera.eye().as_dvec3();
        let forward = camera.forward().as_dvec3().try_normalize();
        let up = camera
            .world_from_view
            .y_axis
            .truncate()
            .as_dvec3()
            .try_normalize();
        match (forward, up) {
            (Some(forward), Some(up)) if eye.is_finite() => Ok(Self {
                frustum,
                eye,
                forward,
                up,
            }),
            _ => Err(WarpError::Degenerate),
        }
    }
}

/// Unit light travel direction in `f64`.
pub(crate) fn light_unit(direction: Vec3) -> Result<DVec3, WarpError> {
    if !direction.is_finite() {
        return Err(WarpError::NonFinite);
    }
    direction
        .as_dvec3()
        .try_normalize()
        .filter(|d| d.length_squared() > 0.5)
        .ok_or(WarpError::ZeroDirection)
}

/// The light frame shared by every technique: rotation only, light looking down `-Z`,
/// `+Y` the warp axis.
///
/// Returns the rotation and `sin γ`, `γ` the angle between view and light direction.
///
/// With `g` the view direction made perpendicular to the light (`|g| = sin γ`) and
/// `u` the camera's up vector made perpendicular to the light, the warp axis is
///
/// ```text
/// a = g + c(|g|) u,   c(x) = sin 1° · (1 - smoothstep(sin 1°, sin 3°, x))
/// ```
///
/// Why this form: a warp must push texels toward the viewer, so its axis must agree
/// in sign with `g` wherever the warp has strength; and the frame must turn
/// continuously with the light. `a · g = |g|² + c (u · g) ≥ |g| (|g| - c(|g|))`, and
/// since `c` decreases, `a · g > 0` and `a ≠ 0` for every `|g| > g*`, `g*` the one
/// solution of `c(g*) = g*` (`g* = sin 1°`). Above 3 degrees `a = g` exactly.
/// No tangent field on the sphere of light directions is free of zeros (the
/// hairy-ball theorem); this one vanishes only at the two light directions `g*` from
/// the view axis (and from its opposite) on the side of `-u`, where every warp of
/// this crate has faded to the uniform fit with its default options (LiSPSM and TSM
/// fade below 3 degrees, XPSM below about 5.7). Near those two points, and only
/// there, the uniform fit turns fast about the light axis. (A blend that gives the
/// up term full weight far from the view axis cancels where the warps are strong,
/// and points the warp backward on one side of that point.)
pub(crate) fn frame(light: DVec3, forward: DVec3, cam_up: DVec3) -> (DMat4, f64) {
    let (rot, sin_g, _) = frame_and_axis(light, forward, cam_up);
    (rot, sin_g)
}

/// [`frame`] and the length of its raw axis ([`frame_axis`]).
fn frame_and_axis(light: DVec3, forward: DVec3, cam_up: DVec3) -> (DMat4, f64, f64) {
    let (up, sin_g) = frame_axis(light, forward, cam_up);
    let axis_length = up.length();
    let up = up.try_normalize().unwrap_or_else(|| {
        // Only on the two (measure-zero) directions where the blend cancels: any
        // axis perpendicular to the light keeps the frame valid.
        light.any_orthonormal_vector()
    });
    let z = -light;
    let x = up.cross(z).normalize();
    let y = z.cross(x);
    let rot = DMat4::from_cols(
        DVec4::new(x.x, y.x, z.x, 0.0),
        DVec4::new(x.y, y.y, z.y, 0.0),
        DVec4::new(x.z, y.z, z.z, 0.0),
        DVec4::W,
    );
    (rot, sin_g, axis_length)
}

/// The warp axis of [`frame`] before it is normalized, `a = g + c(|g|) u` made
/// perpendicular to the light, and `sin γ = |g|`. Its length is the distance (in
/// radians, for small ones) of the light from the two directions where the frame
/// has no axis: near them the frame turns about the light as fast as one over it.
pub(crate) fn frame_axis(light: DVec3, forward: DVec3, cam_up: DVec3) -> (DVec3, f64) {
    let v_perp = forward - light * forward.dot(light);
    let sin_g = v_perp.length().min(1.0);
    let u_perp = cam_up - light * cam_up.dot(light);
    let c = FRAME_UP_WEIGHT * (1.0 - smoothstep(FRAME_BLEND_LO, FRAME_BLEND_HI, sin_g));
    let up = v_perp + u_perp.normalize_or_zero() * c;
    (up - light * up.dot(light), sin_g)
}

/// Checked scene boxes.
pub(crate) fn check_scene(scene: &SceneBounds) -> Result<(Aabb, Aabb), WarpError> {
    let (r, c) = (scene.receivers, scene.casters);
    if !(r.is_finite() && c.is_finite()) {
        return Err(WarpError::NonFinite);
    }
    if !r.is_valid() {
        return Err(WarpError::EmptyReceivers);
    }
    if !c.is_valid() {
        return Err(WarpError::EmptyCasters);
    }
    Ok((r, c))
}

/// Points of a convex body (fixed capacity).
pub(crate) type Points = ArrayVec<DVec3, MAX_BODY_VERTICES>;

/// Vertices of frustum ∩ receivers: a smaller capacity, so the body is cheap to move.
pub(crate) type ReceiverPoints = ArrayVec<DVec3, MAX_FRUSTUM_AABB_VERTICES>;

/// The focus body of a view and light.
#[derive(Clone, Debug)]
pub(crate) struct Focus {
    pub(crate) light: DVec3,
    /// Light frame (rotation only).
    pub(crate) rot: DMat4,
    /// The same in `f32`, the output's `light_from_world` (checked once per body).
    pub(crate) light_from_world: Mat4,
    pub(crate) sin_gamma: f64,
    /// Vertices of frustum ∩ receivers (world).
    pub(crate) receivers: ReceiverPoints,
    /// The same extruded toward the light, clipped by the scene box (world); contains
    /// `receivers`.
    pub(crate) casters: Points,
    /// The checked caster box.
    pub(crate) caster_box: Aabb,
    /// What every fit of the body reads, whatever its warp, computed once: the
    /// light-space bounds of `casters`, ...
    pub(crate) light_bounds: Bounds,
    /// ... the largest coordinate of `casters` ([`scale_of`]) in world and in light
    /// space and of `receivers` in world space, ...
    pub(crate) caster_scale: f64,
    pub(crate) light_caster_scale: f64,
    pub(crate) receiver_scale: f64,
    /// ... the light-space bounds of `receivers` (their footprint across the
    /// light) and their view-depth range (nearest and farthest distance along the
    /// view direction), which the warps' strength formulas read, ...
    pub(crate) footprint: Bounds,
    pub(crate) receiver_depth: (f64, f64),
    /// ... how far the receivers' footprint is from thin ([`footprint_weight`]) ...
    pub(crate) wide: f64,
    /// ... and how far the fitted boxes are widened toward turn-invariance near the
    /// light frame's two zeros (see `turn_invariant`).
    pub(crate) turn_weight: f64,
}

impl Focus {
    /// Smallest and largest light-space `y` (the warp axis) of the caster body.
    pub(crate) fn warp_axis_range(&self) -> (f64, f64) {
        (self.light_bounds.min.y, self.light_bounds.max.y)
    }
}

/// The focus body of `view` and `light`, written where it is returned (the body is
/// tens of kilobytes of fixed-capacity arrays: built field by field in place, not
/// moved).
fn focus(view: View, light: Vec3, scene: &SceneBounds) -> Result<FocusBody, WarpError> {
    let dir = light_unit(light)?;
    let (receiver_box, caster_box) = check_scene(scene)?;
    // The vertices of the body alone: its planes are not needed here.
    let body = ConvexBody::frustum_aabb_vertices(&view.frustum, &receiver_box)?;
    if body.is_empty() {
        return Err(WarpError::NoVisibleReceivers);
    }
    let (rot, sin_gamma, axis_length) = frame_and_axis(dir, view.forward, view.up);
    let light_from_world = rot.as_mat4();
    if !matrix_ok(&light_from_world) {
        return Err(WarpError::Degenerate);
    }
    // Filled where they live (an array collected is then moved: a copy).
    let mut receivers = ReceiverPoints::new();
    for v in &body {
        let _ = receivers.try_push(v.as_dvec3());
    }
    // The receivers' light-space bounds: the caster prism's and the footprint's.
    let mut footprint = Bounds::EMPTY;
    let mut light_caster_scale = f64::MIN_POSITIVE;
    let mut receiver_depth = (f64::INFINITY, f64::NEG_INFINITY);
    for p in &receivers {
        let q = rot.transform_point3(*p);
        footprint.add(q);
        light_caster_scale = light_caster_scale.max(q.abs().max_element());
        let d = (*p - view.eye).dot(view.forward);
        receiver_depth = (receiver_depth.0.min(d), receiver_depth.1.max(d));
    }
    let mut casters = Points::new();
    caster_points(&rot, &receivers, &footprint, &caster_box, &mut casters);
    // The casters start with the receivers.
    let mut light_bounds = footprint;
    for p in &casters[receivers.len()..] {
        let q = rot.transform_point3(*p);
        light_bounds.add(q);
        light_caster_scale = light_caster_scale.max(q.abs().max_element());
    }
    let receiver_scale = scale_of(&receivers);
    Ok(FocusBody {
        probe: RefCell::new(Probe::new()),
        view,
        focus: Focus {
            light: dir,
            rot,
            light_from_world,
            sin_gamma,
            wide: footprint_weight(&footprint, receiver_scale),
            footprint,
            receiver_depth,
            turn_weight: crate::lispsm::turn_invariant_weight(axis_length),
            caster_scale: scale_of(&casters),
            light_caster_scale,
            receiver_scale,
            light_bounds,
            receivers,
            casters,
            caster_box: scene.casters,
        },
    })
}

/// The first stage of every technique, built once per frame and shared: the checked
/// camera (or one slice of it), light and scene, the light frame
/// ([`light_frame`](crate::light_frame)) and the focus body (frustum ∩ receivers,
/// and the casters that can shadow it).
///
/// Build it with [`FocusBody::new`], then fit any number of techniques from it
/// ([`FocusBody::uniform`], [`FocusBody::lispsm`], [`FocusBody::xpsm`],
/// [`FocusBody::tsm`]) without repeating the validation, the clipping or the frame.
/// The warps choose their strengths on the predicted aliasing error at probe points
/// of the body (most of a warp's time); the body fills those points when the first
/// warp needs them, with the uniform fit's predicted error on them (every warp's
/// strength 0, the baseline its strength is judged against), and keeps them, so
/// LiSPSM, XPSM and TSM from one body (or one warp at several strength scales)
/// cast the probe rays and fit the baseline once. That cache makes a
/// body `Send` but not `Sync`: fit from one thread, or clone it per thread. The
/// points are fixed-capacity arrays (no allocation), so a body is about 28 KB:
/// build it where it is used, or keep one per light, rather than moving it.
/// The free functions ([`uniform_focused`](crate::uniform_focused),
/// [`lispsm`](crate::lispsm), ...) build one and call these.
///
/// ```
/// use glam::Vec3;
/// use shadowmap_frustum::{Aabb, Camera, Projection};
/// use shadowmap_warp::{FocusBody, SceneBounds, LispsmOptions, TsmOptions};
///
/// let camera = Camera::look_to(
///     Vec3::new(0.0, 2.0, 0.0),
///     Vec3::NEG_Z,
///     Vec3::Y,
///     Projection::perspective(1.0, 1.5, 0.5, 100.0),
/// )?;
/// // A ground slab with casters up to 10 m.
/// let ground = Aabb::new(Vec3::new(-50.0, -1.0, -100.0), Vec3::new(50.0, 0.0, 10.0));
/// let casters = Aabb::new(Vec3::new(-50.0, -1.0, -100.0), Vec3::new(50.0, 10.0, 10.0));
/// let scene = SceneBounds::new(ground, casters);
/// let body = FocusBody::new(&camera, Vec3::new(0.3, -1.0, -0.2), &scene)?;
/// let l = body.lispsm(&LispsmOptions::default())?;
/// let t = body.tsm(&TsmOptions::default())?;
/// assert!(l.n.is_finite() && t.eta.is_finite());
/// # Ok::<(), shadowmap_warp::WarpError>(())
/// ```
#[derive(Clone, Debug)]
pub struct FocusBody {
    pub(crate) view: View,
    pub(crate) focus: Focus,
    /// The error prediction's probe points, filled by the first warp that needs them.
    probe: RefCell<Probe>,
}

impl FocusBody {
    /// The probe points the warps choose their strengths on, with the uniform fit's
    /// error on them, made on first use.
    pub(crate) fn probe(&self) -> Ref<'_, Probe> {
        if !self.probe.borrow().is_filled() {
            // Filled where it lives: a probe is too large to build and move. No
            // borrow is held here (a probe is only read while a warp chooses its
            // strength, and filled before), so the mutable borrow cannot fail.
            let uniform = crate::lispsm::warp_clip(&self.focus, &self.view, 0.0, false);
            let uniform = uniform.ok().map(|fit| fit.clip_from_light);
            self.probe
                .borrow_mut()
                .fill(&self.view, &self.focus, uniform.as_ref());
        }
        self.probe.borrow()
    }

    /// The focus body of a camera's whole frustum.
    ///
    /// # Errors
    /// [`WarpError::Frustum`] for an invalid camera; [`WarpError::NonFinite`],
    /// [`WarpError::ZeroDirection`] for the light; [`WarpError::EmptyReceivers`],
    /// [`WarpError::EmptyCasters`] for inverted boxes;
    /// [`WarpError::NoVisibleReceivers`] when the receivers miss the frustum;
    /// [`WarpError::Degenerate`] where the light frame's `f32` matrix is not
    /// invertible (every fit of the body would be refused).
    pub fn new(
        camera: &Camera,
        light_direction: Vec3,
        scene: &SceneBounds,
    ) -> Result<Self, WarpError> {
        Self::new_valid(&ValidCamera::new(camera)?, light_direction, scene)
    }

    /// `fit` applied to the focus body of a camera's whole frustum, read where it was
    /// built: the body is tens of kilobytes of fixed-capacity arrays, and moving it
    /// out of its `Result` first would copy them (what the free functions
    /// [`uniform_focused`](crate::uniform_focused), [`lispsm`](crate::lispsm), ...
    /// call).
    pub(crate) fn fit_from<T>(
        camera: &Camera,
        light_direction: Vec3,
        scene: &SceneBounds,
        fit: impl FnOnce(&Self) -> Result<T, WarpError>,
    ) -> Result<T, WarpError> {
        Self::new(camera, light_direction, scene)
            .as_ref()
            .map_err(|e| *e)
            .and_then(fit)
    }

    /// As [`FocusBody::new`] for a camera validated once per frame (see
    /// [`ValidCamera`]): the same body, without checking the camera again.
    ///
    /// # Errors
    /// As [`FocusBody::new`], except the camera's.
    pub fn new_valid(
        camera: &ValidCamera,
        light_direction: Vec3,
        scene: &SceneBounds,
    ) -> Result<Self, WarpError> {
        focus(
            View::with_frustum(camera.camera(), camera.frustum())?,
            light_direction,
            scene,
        )
    }

    /// The focus body of the slice of a camera's frustum between view depths
    /// `near < far` (one cascade).
    ///
    /// # Errors
    /// As [`FocusBody::new`], and [`WarpError::Frustum`] for a slice outside the
    /// camera's depth range.
    pub fn slice(
        camera: &Camera,
        near: f32,
        far: f32,
        light_direction: Vec3,
        scene: &SceneBounds,
    ) -> Result<Self, WarpError> {
        Self::slice_valid(
            &ValidCamera::new(camera)?,
            near,
            far,
            light_direction,
            scene,
        )
    }

    /// As [`FocusBody::slice`] for a camera validated once per frame (see
    /// [`ValidCamera`]).
    ///
    /// # Errors
    /// As [`FocusBody::slice`], except the camera's.
    pub fn slice_valid(
        camera: &ValidCamera,
        near: f32,
        far: f32,
        light_direction: Vec3,
        scene: &SceneBounds,
    ) -> Result<Self, WarpError> {
        focus(
            View::with_frustum(camera.camera(), camera.slice(near, far)?)?,
            light_direction,
            scene,
        )
    }

    /// The light frame (rotation only, see [`light_frame`](crate::light_frame)).
    #[must_use]
    pub fn light_frame(&self) -> Mat4 {
        self.focus.light_from_world
    }

    /// `sin γ`, `γ` the angle between the viewing and the light direction.
    #[must_use]
    pub fn sin_gamma(&self) -> f32 {
        self.focus.sin_gamma as f32
    }
}

/// Largest shadow-map side (texels) whose texels every fit of this crate keeps
/// resolvable in `f32` (see [`MIN_RELATIVE_EXTENT`]).
pub const MAX_MAP_SIDE: u32 = 16384;

/// Smallest extent of a focus region across the light (light-space `x` and `y`),
/// relative to `L`, the largest world coordinate of the focus body: `2^-7`.
///
/// A shader evaluates `uv_from_world` in `f32` at world coordinates of magnitude `L`,
/// with a rounding error of about 4 ulps, `4 · 2^-24 L` in world units. For that to
/// stay within half a texel of a [`MAX_MAP_SIDE`] (`2^14`) map, a texel must be at
/// least `8 · 2^-24 L` wide, so the region at least `2^14 · 8 · 2^-24 L = 2^-7 L`.
/// Thinner regions (a point receiver, a tiny scene far from the origin, a flat sheet
/// of receivers seen edge-on) get the uniform fit, widened about their centre to
/// this extent: at 2048² and `L = 1000`, a point receiver's map covers 7.8 world
/// units. Between four times and once this extent the warp fades out and the widening
/// fades in, so nothing pops. Render camera-relative to shrink `L`.
pub const MIN_RELATIVE_EXTENT: f64 = 0.007_812_5;

/// Smallest extent of the other axes of a fit (depth, and warped coordinates),
/// relative to `L`: enough for `f32` matrices to stay invertible.
const MIN_PAD_EXTENT: f64 = 1e-5;

/// How far the light-space footprint (`x`, `y`) `b` of points is from thin, in
/// `[0, 1]`: 0 when its smaller side is at most [`MIN_RELATIVE_EXTENT`] times
/// `scale`, 1 from four times that, smooth between. Fits scale their warp by it and widen
/// the footprint by `1 -` it, so a region that thins out turns continuously into the
/// widened uniform fit.
pub(crate) fn footprint_weight(b: &Bounds, scale: f64) -> f64 {
    let ext = b.max - b.min;
    let min = MIN_RELATIVE_EXTENT * scale;
    let t = smoothstep(1.0, 4.0, ext.x.min(ext.y) / min);
    if t.is_finite() { t } else { 0.0 }
}

/// Writes to `out` (filled where it lives, not returned: an array moved is copied)
/// the receivers' vertices plus the vertices of `caster box ∩ prism`, the prism being
/// the receivers' light-space xy bounds extended along the light: every caster point
/// that can shadow a visible receiver lies in that intersection, so the largest
/// light-space `z` (toward the light) of these points bounds the casters that matter.
///
/// (`ConvexBody::extruded_toward_light` of `shadowmap-frustum` is not used: its hull
/// misses casters when the ray toward the light leaves the scene box through a side
/// face.)
fn caster_points(
    rot: &DMat4,
    receivers: &[DVec3],
    b: &Bounds,
    caster_box: &Aabb,
    out: &mut Points,
) {
    out.clear();
    for p in receivers {
        let _ = out.try_push(*p);
    }
    let (lo, hi) = (caster_box.min.as_dvec3(), caster_box.max.as_dvec3());
    let scale = lo
        .abs()
        .max(hi.abs())
        .max_element()
        .max(scale_of(receivers));
    let prism = LightPrism::new(rot, b.min.truncate(), b.max.truncate());
    let mut cands: ArrayVec<DVec3, 128> = ArrayVec::new();
    prism.box_vertices(caster_box, 1e-9 * scale, |p| {
        let _ = cands.try_push(p);
    });
    // Keep the candidates that matter for the depth range: the highest toward the
    // light (all of them when they fit).
    let z_of = |p: &DVec3| prism.light_z(*p);
    for p in &cands {
        if out.try_push(*p).is_err() {
            // Full: replace the lowest point if this one is higher.
            if let Some((idx, _)) = out
                .iter()
                .enumerate()
                .skip(receivers.len())
                .min_by(|a, b| z_of(a.1).total_cmp(&z_of(b.1)))
                && z_of(&out[idx]) < z_of(p)
            {
                out[idx] = *p;
            }
        }
    }
}

/// Axis-aligned bounds of points in `f64`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bounds {
    pub(crate) min: DVec3,
    pub(crate) max: DVec3,
}

impl Bounds {
    pub(crate) const EMPTY: Self = Self {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    pub(crate) fn add(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    pub(crate) fn is_empty(&self) -> bool {
        !(self.min.cmple(self.max).all())
    }

    /// Widens thin axes to at least `MIN_PAD_EXTENT * scale` (`x` and `y` to
    /// `thin * MIN_RELATIVE_EXTENT * scale`, `thin = 1 -` [`footprint_weight`]: the
    /// documented thin-region fallback), and every axis by a relative margin so that
    /// rounding keeps points inside.
    pub(crate) fn padded(mut self, scale: f64, thin: f64) -> Self {
        for axis in 0..3 {
            let rel = if axis < 2 {
                (thin * MIN_RELATIVE_EXTENT).max(MIN_PAD_EXTENT)
            } else {
                MIN_PAD_EXTENT
            };
            let min_extent = rel * scale;
            let (lo, hi) = (self.min[axis], self.max[axis]);
            let ext = hi - lo;
            let pad = if ext < min_extent {
                0.5 * (min_extent - ext)
            } else {
                0.0
            } + 1e-6 * ext.max(min_extent);
            self.min[axis] = lo - pad;
            self.max[axis] = hi + pad;
        }
        self
    }
}

/// Largest absolute coordinate of the points (at least a tiny positive number).
pub(crate) fn scale_of(points: &[DVec3]) -> f64 {
    points
        .iter()
        .map(|p| p.abs().max_element())
        .fold(f64::MIN_POSITIVE, f64::max)
}

/// Orthographic fit of light-space bounds (`z` toward the light): x, y to the box,
/// depth from the nearest (largest `z`) to the farthest.
pub(crate) fn ortho_fit(b: &Bounds, reversed_z: bool) -> DMat4 {
    shadowmap_frustum::projection::orthographic(
        b.min.x, b.max.x, b.min.y, b.max.y, -b.max.z, -b.min.z, reversed_z,
    )
}

/// Converts a fit of `f` to the `f32` output, refusing non-finite or singular
/// results: the matrix must be invertible for world coordinates up to each of
/// `world_scales` (`shadowmap_frustum::is_invertible_at`: the fit's reach, and
/// where they differ the receivers' it is looked up at). (The light frame's `f32`
/// matrix was checked when the body was built.)
pub(crate) fn finish(
    f: &Focus,
    clip_from_world: DMat4,
    reversed_z: bool,
    world_scales: &[f32],
) -> Result<ShadowTransform, WarpError> {
    let clip = clip_from_world.as_mat4();
    let scales_ok = world_scales.iter().all(|s| s.is_finite());
    if !(matrix_ok(&clip) && scales_ok && shadowmap_frustum::is_invertible_at(&clip, world_scales))
    {
        return Err(WarpError::Degenerate);
    }
    let t = ShadowTransform::new(
        f.light_from_world,
        clip,
        reversed_z,
        LightDirection::Directional(f.light.as_vec3()),
    );
    if !matrix_ok(&t.uv_from_world) {
        return Err(WarpError::Degenerate);
    }
    Ok(t)
}

/// Finite, with a finite non-zero determinant and a finite inverse.
pub(crate) fn matrix_ok(m: &Mat4) -> bool {
    if !m.is_finite() {
        return false;
    }
    let det = m.as_dmat4().determinant();
    det.is_finite() && det != 0.0 && (det as f32) != 0.0 && m.inverse().is_finite()
}

/// `sqrt` that never returns NaN for tiny negative rounding.
pub(crate) fn sqrt0(x: f64) -> f64 {
    math::sqrt(x.max(0.0))
}
