//! Predicted aliasing error of a shadow mapping, from the camera and the receivers'
//! bounds alone: no rendering, no allocation. It lets a renderer choose a technique per
//! frame ([`TechniqueSelector`](crate::TechniqueSelector)) before drawing anything.
//!
//! The receivers' box stands in for the unknown surfaces: a grid of view rays is cast
//! through the frustum, and each ray stops where it first meets a face of the box (the
//! face it enters from outside, or the inner face it leaves through from inside), a
//! plane with that face's normal. There, as for a rendered pixel, the aliasing error is
//! the size of one texel in pixels (Lloyd, Tuft, Yoon and Manocha, *Warping and
//! Partitioning for Low Error Shadow Maps*, EGSR 2006):
//!
//! ```text
//! J = d(texel) / d(pixel)     2x2: one-pixel steps on the screen, moved along the
//!                             face's plane, mapped by the technique (texels = uv * N)
//! m = 1 / s_min(J)            the largest extent of a texel, in pixels (1: matched)
//! ```
//!
//! Where the visible depth range is known (a depth reduction,
//! [`PredictOptions::depth_range`]), each ray's point is kept within it: a face that
//! lies nearer or farther than anything visible is not what the pixel sees, and the
//! ray then stands for the worst of a few points over its visible stretch, facing
//! as the face does (the receivers' box of a terrain reaches below and beyond the
//! ground the camera sees, and its top lies at the tree tops).
//!
//! The prediction is a percentile of `m` over the rays that meet the box (the
//! quality report ranks techniques by the 95th percentile of the same quantity over
//! the rendered pixels). Rays whose neighbours fall into another map layer (a cascade
//! boundary) or outside the map are left out.

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3, Vec3};

use crate::{Aabb, Camera, FrustumError, LightDirection, ShadowMapping, math};

/// Most rays [`predict_error`] casts (`grid_columns * grid_rows` at most this).
pub const MAX_PREDICT_RAYS: usize = 1024;

/// Options of [`predict_error`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct PredictOptions {
    /// Height of the viewport in pixels (the unit of the error). Default 1080.
    pub viewport_height: u32,
    /// Rays across the screen. Default 16.
    pub grid_columns: u32,
    /// Rays down the screen. Default 9.
    pub grid_rows: u32,
    /// The percentile of the error over the rays, in `(0, 1]`. Default 0.95.
    pub percentile: f64,
    /// The direction a directional light travels, if known. Rays that meet a face
    /// of the box turned away from the light, or within 3° of parallel to it
    /// (`n · l` below [`FRONT_LIT_MIN_COS`], `l` toward the light), are left out:
    /// shading darkens such surfaces whatever the map holds, and their true-normal
    /// error grows without bound as the texel stretches along them, so counting
    /// them would rank techniques by surfaces nobody sees shadowed. When no ray
    /// meets a front-lit face, every ray counts. Default `None` (every ray).
    pub light_direction: Option<Vec3>,
    /// The position of a spot or point light, if known: as
    /// [`light_direction`](Self::light_direction), with `l` toward the position
    /// from the point the ray meets. Takes precedence over `light_direction`.
    /// Default `None`.
    pub light_position: Option<Vec3>,
    /// View depths `(near, far)` of the visible surfaces, if known (a depth
    /// reduction, see `DepthBounds`). Each ray's point is kept inside this range:
    /// a face met nearer than `near` or farther than `far` is not what the pixel
    /// sees (the receivers' box is only a bound), so the ray's error is the largest
    /// at a few points over the stretch of it inside the box and the range, facing
    /// as the face does (where along the ray the surface lies is unknown: the
    /// prediction takes the worst the bounds allow); a ray whose segment in the box
    /// lies wholly outside the range is left out. Default `None`.
    pub depth_range: Option<(f32, f32)>,
}

/// Smallest `n · l` of a face that counts as lit (see
/// [`PredictOptions::light_direction`]).
pub const FRONT_LIT_MIN_COS: f64 = 0.05;

impl Default for PredictOptions {
    fn default() -> Self {
        Self::new()
    }
}

impl PredictOptions {
    /// Defaults: a 1080-pixel viewport, a 16 x 9 grid, the 95th percentile.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            viewport_height: 1080,
            grid_columns: 16,
            grid_rows: 9,
            percentile: 0.95,
            light_direction: None,
            light_position: None,
            depth_range: None,
        }
    }

    /// Sets [`depth_range`](Self::depth_range) (`near < far`, both finite and
    /// positive, else none).
    #[must_use]
    pub fn with_depth_range(mut self, near: f32, far: f32) -> Self {
        let ok = near.is_finite() && far.is_finite() && near > 0.0 && far > near;
        self.depth_range = ok.then_some((near, far));
        self
    }

    /// Sets [`light_direction`](Self::light_direction) (a zero or non-finite
    /// direction: none).
    #[must_use]
    pub fn with_light_direction(mut self, direction: Vec3) -> Self {
        self.light_direction = direction.try_normalize();
        self
    }

    /// Sets [`light_position`](Self::light_position) (a non-finite position: none).
    #[must_use]
    pub fn with_light_position(mut self, position: Vec3) -> Self {
        self.light_position = position.is_finite().then_some(position);
        self
    }

    /// Sets [`viewport_height`](Self::viewport_height).
    #[must_use]
    pub const fn with_viewport_height(mut self, pixels: u32) -> Self {
        self.viewport_height = pixels;
        self
    }

    /// Sets the ray grid.
    #[must_use]
    pub const fn with_grid(mut self, columns: u32, rows: u32) -> Self {
        self.grid_columns = columns;
        self.grid_rows = rows;
        self
    }

    /// Sets [`percentile`](Self::percentile).
    #[must_use]
    pub const fn with_percentile(mut self, percentile: f64) -> Self {
        self.percentile = percentile;
        self
    }

    pub(crate) fn check(&self) -> Result<(), FrustumError> {
        let rays = u64::from(self.grid_columns) * u64::from(self.grid_rows);
        let ok = self.viewport_height > 0
            && rays > 0
            && rays <= MAX_PREDICT_RAYS as u64
            && self.percentile > 0.0
            && self.percentile <= 1.0
            && self.light_direction.is_none_or(Vec3::is_finite)
            && self.light_position.is_none_or(Vec3::is_finite)
            && self
                .depth_range
                .is_none_or(|(n, f)| n.is_finite() && f.is_finite() && n > 0.0 && f > n);
        if ok {
            Ok(())
        } else {
            Err(FrustumError::InvalidResolution)
        }
    }
}

/// The predicted aliasing error of a mapping.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PredictedError {
    /// `m` at the requested percentile, in pixels per texel extent.
    pub percentile: f64,
    /// The largest `m` over the rays.
    pub max: f64,
    /// Rays that met the receivers and were measured.
    pub rays: u32,
}

/// Predicts the aliasing error of `mapping` (a map of `texels_per_side²` texels per
/// layer) for `camera`, with the receivers' box standing in for the visible surfaces
/// (see the module docs). `Ok(None)` when no ray meets the box inside the frustum or
/// the mapping covers none of the points met.
///
/// # Errors
/// The camera's errors ([`Camera::frustum`]); [`FrustumError::EmptyBounds`] for an
/// invalid or non-finite box; [`FrustumError::InvalidResolution`] for a zero map
/// side or options out of range.
pub fn predict_error<M: ShadowMapping>(
    camera: &Camera,
    receivers: &Aabb,
    mapping: &M,
    texels_per_side: u32,
    options: &PredictOptions,
) -> Result<Option<PredictedError>, FrustumError> {
    let mut out = [None];
    predict_errors(
        camera,
        receivers,
        &[(mapping as &dyn ShadowMapping, texels_per_side)],
        options,
        &mut out,
    )?;
    Ok(out[0])
}

/// Most candidates [`predict_errors`] compares at once.
pub const MAX_PREDICT_CANDIDATES: usize = 8;

/// Predicts the error of several candidates `(mapping, texels per side)` on the same
/// rays, for choosing among them: a ray counts only where every candidate covers its
/// pixel, so a technique that covers less (cascades fitted to measured depth bounds,
/// say) is not excused from points the others are charged for. When no ray is covered
/// by all, each candidate is predicted on its own rays. Writes one prediction per
/// candidate into `out` (`None`: the candidate covers none of the points met).
///
/// # Errors
/// As [`predict_error`]; [`FrustumError::InvalidResolution`] also for more than
/// [`MAX_PREDICT_CANDIDATES`] candidates or an `out` of another length.
pub fn predict_errors(
    camera: &Camera,
    receivers: &Aabb,
    candidates: &[(&dyn ShadowMapping, u32)],
    options: &PredictOptions,
    out: &mut [Option<PredictedError>],
) -> Result<(), FrustumError> {
    options.check()?;
    let n = candidates.len();
    if n > MAX_PREDICT_CANDIDATES || out.len() != n || candidates.iter().any(|c| c.1 == 0) {
        return Err(FrustumError::InvalidResolution);
    }
    if !(receivers.is_finite() && receivers.is_valid()) {
        return Err(FrustumError::EmptyBounds);
    }
    let light = match (options.light_position, options.light_direction) {
        (Some(position), _) => Some(LightDirection::Position(position)),
        (None, Some(direction)) => direction.try_normalize().map(LightDirection::Directional),
        (None, None) => None,
    };
    let screen =
        Screen::new(camera, options.viewport_height)?.with_depth_range(options.depth_range);
    // Uninitialized storage: only what a pass writes is read.
    let mut errors: [RayErrors; MAX_PREDICT_CANDIDATES] =
        core::array::from_fn(|_| RayErrors::new());
    // Front-lit shared rays first (without a light: every shared ray, twice); then
    // every shared ray; then each candidate's own rays.
    let passes = [(light, true), (None, true), (None, false)];
    for (lit_by, shared) in passes {
        errors.iter_mut().for_each(ArrayVec::clear);
        let pass = Pass {
            screen: &screen,
            receivers,
            grid: (options.grid_columns, options.grid_rows),
            lit_by,
            shared,
        };
        pass.run(candidates, &mut errors);
        if errors[..n].iter().any(|e| !e.is_empty()) {
            break;
        }
    }
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = summarize(&mut errors[i], options.percentile);
    }
    Ok(())
}

/// One candidate's errors, one per ray, squared (`m²`: the square root is taken
/// of the percentile and the maximum only, which it leaves in their places).
type RayErrors = ArrayVec<f64, MAX_PREDICT_RAYS>;

/// One pass of [`predict_errors`] over the ray grid.
struct Pass<'a> {
    screen: &'a Screen,
    receivers: &'a Aabb,
    grid: (u32, u32),
    /// Only rays meeting a face this light lights from the front.
    lit_by: Option<LightDirection>,
    /// Only rays every candidate covers.
    shared: bool,
}

impl Pass<'_> {
    fn run(
        &self,
        candidates: &[(&dyn ShadowMapping, u32)],
        errors: &mut [RayErrors; MAX_PREDICT_CANDIDATES],
    ) {
        let n = candidates.len();
        let (columns, rows) = self.grid;
        for row in 0..rows {
            for column in 0..columns {
                let at = DVec2::new(
                    (f64::from(column) + 0.5) / f64::from(columns),
                    (f64::from(row) + 0.5) / f64::from(rows),
                );
                let Some(hit) = self.screen.hit(at, self.receivers) else {
                    continue;
                };
                if self
                    .lit_by
                    .is_some_and(|l| hit.normal().dot(l.toward(hit.point())) < FRONT_LIT_MIN_COS)
                {
                    continue;
                }
                // Where the neighbouring pixels' rays meet each point's plane: the
                // same for every candidate, computed once.
                let pixel_rays = self.screen.pixel_rays(at);
                let mut steps = [None; DEPTH_POINTS];
                hit.map(&mut steps, |point, normal| {
                    pixel_steps(&pixel_rays, point, normal)
                });
                // Every candidate's differentials at the hit's points first, then
                // the errors: their square roots and divisions (most of a
                // candidate's time) run side by side, not each after its
                // candidate's matrix products.
                let mut differentials = [[None; DEPTH_POINTS]; MAX_PREDICT_CANDIDATES];
                for (d, &(mapping, side)) in differentials.iter_mut().zip(candidates) {
                    hit.map_with(&steps, d, |point, steps| {
                        texel_differentials(point, steps.as_ref()?, mapping, f64::from(side))
                    });
                }
                let mut ray = [None; MAX_PREDICT_CANDIDATES];
                for (m, d) in ray.iter_mut().zip(&differentials[..n]) {
                    *m = hit.error(d, |_, d| error_of(d.as_ref()?));
                }
                if self.shared && ray[..n].iter().any(Option::is_none) {
                    continue;
                }
                for (i, m) in ray[..n].iter().enumerate() {
                    if let Some(m) = m {
                        // At most one error per ray, `MAX_PREDICT_RAYS` rays.
                        let _ = errors[i].try_push(*m);
                    }
                }
            }
        }
    }
}

/// Points of a ray moved into the visible depth range (see [`Screen::hit`]).
const DEPTH_POINTS: usize = 4;

/// What a ray of the prediction meets.
enum Hit {
    /// A face of the receivers' box: the point and the face's normal.
    Face(DVec3, DVec3),
    /// No face within the visible depth range: points over the range along the ray,
    /// and the normal they face.
    Range([DVec3; DEPTH_POINTS], DVec3),
}

impl Hit {
    fn normal(&self) -> DVec3 {
        match self {
            Self::Face(_, n) | Self::Range(_, n) => *n,
        }
    }

    /// The point met (the nearest, for a range).
    fn point(&self) -> DVec3 {
        match self {
            Self::Face(p, _) => *p,
            Self::Range(points, _) => points[0],
        }
    }

    /// `f(point, normal)` for each of the hit's points (one for a face), written
    /// to `out` (filled where it lives: the caller's arrays are not moved).
    fn map<T>(&self, out: &mut [T; DEPTH_POINTS], mut f: impl FnMut(DVec3, DVec3) -> T) {
        self.map_with(&[self.normal(); DEPTH_POINTS], out, |p, n| f(p, *n));
    }

    /// `f(point, data)` for each of the hit's points, `data` the point's entry of
    /// `per_point`, written to `out` ([`Hit::map`]).
    fn map_with<T, U>(
        &self,
        per_point: &[T; DEPTH_POINTS],
        out: &mut [U; DEPTH_POINTS],
        mut f: impl FnMut(DVec3, &T) -> U,
    ) {
        match self {
            Self::Face(p, _) => out[0] = f(*p, &per_point[0]),
            Self::Range(points, _) => {
                for ((o, p), data) in out.iter_mut().zip(points).zip(per_point) {
                    *o = f(*p, data);
                }
            }
        }
    }

    /// The error of the ray from `error_at(point, data)`, `data` the point's entry
    /// of `per_point` ([`Hit::map`]): at the face, or the largest over the points in
    /// range (where on the ray the surface lies is unknown: the prediction takes the
    /// worst the depth bounds allow); `None` if any point is not covered.
    fn error<T>(
        &self,
        per_point: &[T; DEPTH_POINTS],
        mut error_at: impl FnMut(DVec3, &T) -> Option<f64>,
    ) -> Option<f64> {
        match self {
            Self::Face(p, _) => error_at(*p, &per_point[0]),
            Self::Range(points, _) => {
                let mut worst = 0.0f64;
                for (p, data) in points.iter().zip(per_point) {
                    worst = worst.max(error_at(*p, data)?);
                }
                Some(worst)
            }
        }
    }
}

/// The percentile and maximum of the errors from their squares (reordered in
/// place: the percentile is selected, not the whole list sorted).
fn summarize(squares: &mut [f64], percentile: f64) -> Option<PredictedError> {
    let count = squares.len();
    if count == 0 {
        return None;
    }
    let max = squares
        .iter()
        .copied()
        .max_by(f64::total_cmp)
        .unwrap_or(f64::NAN);
    let rank = math::ceil(percentile * count as f64) as usize;
    let (_, at, _) = squares.select_nth_unstable_by(rank.clamp(1, count) - 1, f64::total_cmp);
    Some(PredictedError {
        percentile: math::sqrt(*at),
        max: math::sqrt(max),
        rays: count as u32,
    })
}

/// The view frustum as a screen: rays by normalized screen position and the size of a
/// pixel in those units.
struct Screen {
    near: [DVec3; 4],
    far: [DVec3; 4],
    /// View depths of the near and far planes.
    near_depth: f64,
    far_depth: f64,
    /// One pixel in normalized screen units, `(1 / width, 1 / height)`.
    pixel: DVec2,
    /// The range of the ray parameter `s` (0 at the near plane, 1 at the far plane)
    /// where the visible surfaces lie ([`PredictOptions::depth_range`]), if given.
    visible: Option<(f64, f64)>,
}

impl Screen {
    fn new(camera: &Camera, viewport_height: u32) -> Result<Self, FrustumError> {
        let frustum = camera.frustum()?;
        let c = frustum.corners.map(Vec3::as_dvec3);
        let near = [c[0], c[1], c[2], c[3]];
        let far = [c[4], c[5], c[6], c[7]];
        // Square pixels: the width in pixels follows the near rectangle's aspect.
        let aspect = (near[1] - near[0]).length() / (near[3] - near[0]).length();
        let height = f64::from(viewport_height);
        let width = (height * aspect).max(1.0);
        if !(width.is_finite() && aspect > 0.0) {
            return Err(FrustumError::DegenerateFrustum);
        }
        let (near_depth, far_depth) = camera.depth_range()?;
        Ok(Self {
            near,
            far,
            near_depth: f64::from(near_depth),
            far_depth: f64::from(far_depth),
            pixel: DVec2::new(1.0 / width, 1.0 / height),
            visible: None,
        })
    }

    /// With the visible depth range `range` (view depths; the rays run from the
    /// near plane, `s = 0`, to the far plane, `s = 1`, so view depth is linear in
    /// `s`).
    fn with_depth_range(mut self, range: Option<(f32, f32)>) -> Self {
        let (zn, zf) = (self.near_depth, self.far_depth);
        if let Some((lo, hi)) = range.filter(|_| zf > zn) {
            let s = |z: f32| (f64::from(z) - zn) / (zf - zn);
            self.visible = Some((s(lo).max(0.0), s(hi).min(1.0)));
        }
        self
    }

    /// The ray through normalized screen position `at` (`(0, 0)` bottom left): the
    /// point on the near plane and the step to the far plane.
    fn ray(&self, at: DVec2) -> (DVec3, DVec3) {
        self.column(at.x).ray(at.y)
    }

    /// The near and far faces' bottom and top edge points at screen `x`, which
    /// every ray at that `x` interpolates.
    fn column(&self, x: f64) -> Column {
        let edge = |q: &[DVec3; 4]| (q[0].lerp(q[1], x), q[3].lerp(q[2], x));
        Column {
            near: edge(&self.near),
            far: edge(&self.far),
        }
    }

    /// Where the ray through `at` first meets the box inside the visible depth
    /// range: the face point and its normal, or, where that face lies outside the
    /// range (see [`PredictOptions::depth_range`]), [`DEPTH_POINTS`] points
    /// log-spaced in depth over the part of the ray in the box and in range, facing
    /// as that face does (the box's faces stand for the surfaces' orientation: the
    /// ground under a box whose floor lies below it, the walls of a street).
    fn hit(&self, at: DVec2, receivers: &Aabb) -> Option<Hit> {
        let (origin, step) = self.ray(at);
        let (s, segment, normal) = first_face_hit(origin, step, receivers)?;
        let Some(visible) = self.visible else {
            // Without a depth range, the face the ray meets between the camera's
            // planes.
            return (0.0..=1.0)
                .contains(&s)
                .then(|| Hit::Face(origin + step * s, normal));
        };
        let (lo, hi) = (segment.0.max(visible.0), segment.1.min(visible.1));
        if !(lo <= hi) {
            return None;
        }
        if (lo..=hi).contains(&s) {
            return Some(Hit::Face(origin + step * s, normal));
        }
        // View depth is linear in `s`: log-spaced depths are log-spaced in
        // `s + s0`, `s0 = zn / (zf - zn)`.
        let s0 = self.near_depth / (self.far_depth - self.near_depth);
        let (a, b) = (math::ln(lo + s0), math::ln(hi + s0));
        let points = core::array::from_fn(|k| {
            let t = (k as f64 + 0.5) / DEPTH_POINTS as f64;
            origin + step * (math::exp(a + (b - a) * t) - s0)
        });
        Some(Hit::Range(points, normal))
    }

    /// The rays one pixel away from `at` (`+x`, `-x`, `+y`, `-y`), as
    /// [`Screen::ray`] makes them (the two across `y` share their edge points at
    /// `at.x`, computed once).
    fn pixel_rays(&self, at: DVec2) -> [(DVec3, DVec3); 4] {
        let (dx, dy) = (self.pixel.x, self.pixel.y);
        let column = self.column(at.x);
        [
            self.column(at.x + dx).ray(at.y),
            self.column(at.x - dx).ray(at.y),
            column.ray(at.y + dy),
            column.ray(at.y - dy),
        ]
    }
}

/// A screen column's edge points ([`Screen::column`]): `(bottom, top)` on the near
/// and on the far face.
struct Column {
    near: (DVec3, DVec3),
    far: (DVec3, DVec3),
}

impl Column {
    /// The ray at screen height `y`: the point on the near plane and the step to
    /// the far plane.
    fn ray(&self, y: f64) -> (DVec3, DVec3) {
        let origin = self.near.0.lerp(self.near.1, y);
        (origin, self.far.0.lerp(self.far.1, y) - origin)
    }
}

/// Where the rays one pixel away from a ray ([`Screen::pixel_rays`]) meet the plane
/// through `point` with `normal`; `None` if one runs parallel to it.
fn pixel_steps(rays: &[(DVec3, DVec3); 4], point: DVec3, normal: DVec3) -> Option<PixelSteps> {
    let mut steps = [DVec3::ZERO; 4];
    for (step, &(o, d)) in steps.iter_mut().zip(rays) {
        *step = plane_hit(o, d, point, normal)?;
    }
    Some(steps)
}

/// The points one pixel away on a probe point's plane ([`pixel_steps`]).
type PixelSteps = [DVec3; 4];

/// The map's differentials in texels at `point` for the neighbouring pixels'
/// points `steps` (its [`error_of`]), if the mapping covers the pixel and its
/// neighbours in one layer.
fn texel_differentials(
    point: DVec3,
    steps: &PixelSteps,
    mapping: &dyn ShadowMapping,
    texels: f64,
) -> Option<[DVec2; 2]> {
    let [du, dv] = mapping.uv_differentials(point, steps)?;
    Some([du * texels, dv * texels])
}

/// `m²` of the texel differentials `[du, dv]` ([`texel_differentials`]), if finite
/// and positive.
fn error_of(&[du, dv]: &[DVec2; 2]) -> Option<f64> {
    let m2 = math::inverse_square_smaller_singular_value(du, dv);
    (m2.is_finite() && m2 > 0.0).then_some(m2)
}

/// Where the segment `origin + s step`, `s` in `[0, 1]`, first meets a face of the box
/// (the parameter `s`), the part of the segment inside the box, and that face's
/// normal turned toward the segment's start.
fn first_face_hit(origin: DVec3, step: DVec3, b: &Aabb) -> Option<(f64, (f64, f64), DVec3)> {
    let (lo, hi) = (b.min.as_dvec3(), b.max.as_dvec3());
    let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
    let (mut enter_axis, mut exit_axis) = (None, None);
    for axis in 0..3 {
        let (o, d) = (origin[axis], step[axis]);
        if d == 0.0 {
            if o < lo[axis] || o > hi[axis] {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
        let (near, far) = (t0.min(t1), t0.max(t1));
        if near > enter {
            enter = near;
            enter_axis = Some(axis);
        }
        if far < exit {
            exit = far;
            exit_axis = Some(axis);
        }
    }
    if !(enter <= exit) {
        return None;
    }
    // Outside: the face it enters; inside: the inner face it leaves through.
    let (s, axis) = if enter > 0.0 {
        (enter, enter_axis?)
    } else {
        (exit, exit_axis?)
    };
    let mut normal = DVec3::ZERO;
    normal[axis] = -step[axis].signum();
    Some((s, (enter.max(0.0), exit.min(1.0)), normal))
}

/// Where the line `origin + s dir` meets the plane through `point` with `normal`.
fn plane_hit(origin: DVec3, dir: DVec3, point: DVec3, normal: DVec3) -> Option<DVec3> {
    let denom = normal.dot(dir);
    // `|denom| <= 1e-12 |dir|`, squared: no square root per neighbouring ray.
    if denom * denom <= 1e-24 * dir.length_squared() {
        return None;
    }
    let s = normal.dot(point - origin) / denom;
    let p = origin + dir * s;
    p.is_finite().then_some(p)
}

#[cfg(test)]
mod tests;
