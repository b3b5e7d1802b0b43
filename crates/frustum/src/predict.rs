//! Predicted aliasing error of a shadow mapping, from the camera and the receivers'
//! bounds alone: no rendering, no allocation. It lets a renderer choose a technique per
//! frame ([`TechniqueSelector`]) before drawing anything.
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
//! and the prediction is a percentile of `m` over the rays that meet the box (the
//! quality report ranks techniques by the 95th percentile of the same quantity over
//! the rendered pixels). Rays whose neighbours fall into another map layer (a cascade
//! boundary) or outside the map are left out.

use glam::{DVec2, DVec3, Vec3};

use crate::{Aabb, Camera, FrustumError, ShadowMapping, math};

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
        }
    }

    /// Sets [`light_direction`](Self::light_direction) (a zero or non-finite
    /// direction: none).
    #[must_use]
    pub fn with_light_direction(mut self, direction: Vec3) -> Self {
        self.light_direction = direction.try_normalize();
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
            && self.light_direction.is_none_or(Vec3::is_finite);
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
    let screen = Screen::new(camera, options.viewport_height)?;
    let toward_light = options
        .light_direction
        .and_then(Vec3::try_normalize)
        .map(|d| -d.as_dvec3());
    let mut errors = [[0.0f64; MAX_PREDICT_RAYS]; MAX_PREDICT_CANDIDATES];
    let mut counts = [0usize; MAX_PREDICT_CANDIDATES];
    // Front-lit shared rays first (without a light: every shared ray, twice); then
    // every shared ray; then each candidate's own rays.
    let passes = [(toward_light, true), (None, true), (None, false)];
    for (lit_by, shared) in passes {
        counts = [0; MAX_PREDICT_CANDIDATES];
        let pass = Pass {
            screen: &screen,
            receivers,
            grid: (options.grid_columns, options.grid_rows),
            lit_by,
            shared,
        };
        pass.run(candidates, &mut errors, &mut counts);
        if counts[..n].iter().any(|&c| c > 0) {
            break;
        }
    }
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = summarize(&mut errors[i][..counts[i]], options.percentile);
    }
    Ok(())
}

/// One pass of [`predict_errors`] over the ray grid.
struct Pass<'a> {
    screen: &'a Screen,
    receivers: &'a Aabb,
    grid: (u32, u32),
    /// Only rays meeting a face lit from this direction (toward the light).
    lit_by: Option<DVec3>,
    /// Only rays every candidate covers.
    shared: bool,
}

impl Pass<'_> {
    fn run(
        &self,
        candidates: &[(&dyn ShadowMapping, u32)],
        errors: &mut [[f64; MAX_PREDICT_RAYS]; MAX_PREDICT_CANDIDATES],
        counts: &mut [usize; MAX_PREDICT_CANDIDATES],
    ) {
        let n = candidates.len();
        let (columns, rows) = self.grid;
        for row in 0..rows {
            for column in 0..columns {
                let at = DVec2::new(
                    (f64::from(column) + 0.5) / f64::from(columns),
                    (f64::from(row) + 0.5) / f64::from(rows),
                );
                let Some((point, normal)) = self.screen.hit(at, self.receivers) else {
                    continue;
                };
                if self
                    .lit_by
                    .is_some_and(|l| normal.dot(l) < FRONT_LIT_MIN_COS)
                {
                    continue;
                }
                let mut ray = [None; MAX_PREDICT_CANDIDATES];
                for (m, &(mapping, side)) in ray.iter_mut().zip(candidates) {
                    *m = self
                        .screen
                        .error_at(at, point, normal, mapping, f64::from(side));
                }
                if self.shared && ray[..n].iter().any(Option::is_none) {
                    continue;
                }
                for (i, m) in ray[..n].iter().enumerate() {
                    if let Some(m) = m {
                        errors[i][counts[i]] = *m;
                        counts[i] += 1;
                    }
                }
            }
        }
    }
}

/// The percentile and maximum of the errors (sorted in place).
fn summarize(errors: &mut [f64], percentile: f64) -> Option<PredictedError> {
    let count = errors.len();
    if count == 0 {
        return None;
    }
    errors.sort_unstable_by(f64::total_cmp);
    let rank = math::ceil(percentile * count as f64) as usize;
    Some(PredictedError {
        percentile: errors[rank.clamp(1, count) - 1],
        max: errors[count - 1],
        rays: count as u32,
    })
}

/// The view frustum as a screen: rays by normalized screen position and the size of a
/// pixel in those units.
struct Screen {
    near: [DVec3; 4],
    far: [DVec3; 4],
    /// One pixel in normalized screen units, `(1 / width, 1 / height)`.
    pixel: DVec2,
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
        Ok(Self {
            near,
            far,
            pixel: DVec2::new(1.0 / width, 1.0 / height),
        })
    }

    /// The ray through normalized screen position `at` (`(0, 0)` bottom left): the
    /// point on the near plane and the step to the far plane.
    fn ray(&self, at: DVec2) -> (DVec3, DVec3) {
        let bilerp = |q: &[DVec3; 4]| {
            let bottom = q[0].lerp(q[1], at.x);
            let top = q[3].lerp(q[2], at.x);
            bottom.lerp(top, at.y)
        };
        let origin = bilerp(&self.near);
        (origin, bilerp(&self.far) - origin)
    }

    /// Where the ray through `at` first meets the box, and that face's normal.
    fn hit(&self, at: DVec2, receivers: &Aabb) -> Option<(DVec3, DVec3)> {
        let (origin, step) = self.ray(at);
        first_face_hit(origin, step, receivers)
    }

    /// `m` at `point` on the face with `normal` met by the ray through `at`, if the
    /// mapping covers the pixel and its neighbours in one layer.
    fn error_at(
        &self,
        at: DVec2,
        point: DVec3,
        normal: DVec3,
        mapping: &dyn ShadowMapping,
        texels: f64,
    ) -> Option<f64> {
        let centre = mapping.map_point(point)?;
        let mut columns = [DVec2::ZERO; 2];
        for (axis, column) in columns.iter_mut().enumerate() {
            let mut offset = DVec2::ZERO;
            offset[axis] = self.pixel[axis];
            let mut ends = [DVec2::ZERO; 2];
            for (end, sign) in ends.iter_mut().zip([1.0, -1.0]) {
                let (o, d) = self.ray(at + offset * sign);
                let p = plane_hit(o, d, point, normal)?;
                let s = mapping.map_point(p)?;
                if s.layer != centre.layer {
                    return None;
                }
                *end = s.uv * texels;
            }
            *column = (ends[0] - ends[1]) * 0.5;
        }
        let m = 1.0 / math::smaller_singular_value(columns[0], columns[1]);
        (m.is_finite() && m > 0.0).then_some(m)
    }
}

/// Where the segment `origin + s step`, `s` in `[0, 1]`, first meets a face of the box,
/// and that face's normal turned toward the segment's start.
fn first_face_hit(origin: DVec3, step: DVec3, b: &Aabb) -> Option<(DVec3, DVec3)> {
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
    if !(0.0..=1.0).contains(&s) {
        return None;
    }
    let mut normal = DVec3::ZERO;
    normal[axis] = -step[axis].signum();
    Some((origin + step * s, normal))
}

/// Where the line `origin + s dir` meets the plane through `point` with `normal`.
fn plane_hit(origin: DVec3, dir: DVec3, point: DVec3, normal: DVec3) -> Option<DVec3> {
    let denom = normal.dot(dir);
    if denom.abs() <= 1e-12 * dir.length() {
        return None;
    }
    let s = normal.dot(point - origin) / denom;
    let p = origin + dir * s;
    p.is_finite().then_some(p)
}

/// Chooses among candidate techniques by predicted error, with hysteresis: the current
/// choice is kept until another candidate's prediction is lower by more than
/// [`switch_margin`](Self::switch_margin) (relative), so the choice does not flip
/// every frame when two candidates are close. Keep one per light across frames.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TechniqueSelector {
    /// The index chosen last, if any.
    pub current: Option<usize>,
    /// Relative improvement needed to switch. Default 0.1.
    pub switch_margin: f64,
}

impl Default for TechniqueSelector {
    fn default() -> Self {
        Self::new()
    }
}

impl TechniqueSelector {
    /// No choice yet; a 10% margin.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            current: None,
            switch_margin: 0.1,
        }
    }

    /// Sets [`switch_margin`](Self::switch_margin) (negative or NaN: 0).
    #[must_use]
    pub const fn with_switch_margin(mut self, margin: f64) -> Self {
        self.switch_margin = margin;
        self
    }

    /// Picks the index of the lowest prediction (`None` entries are candidates that
    /// could not be fitted or predicted), keeping the current choice unless the best
    /// beats it by the margin. `None` when no candidate has a prediction. Ties go to
    /// the lower index, so list candidates from the most to the least preferred.
    pub fn choose(&mut self, predictions: &[Option<f64>]) -> Option<usize> {
        let best = predictions
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.filter(|v| v.is_finite()).map(|v| (i, v)))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
        let margin = if self.switch_margin > 0.0 {
            self.switch_margin
        } else {
            0.0
        };
        let keep = self
            .current
            .and_then(|i| predictions.get(i).copied().flatten().map(|v| (i, v)))
            .filter(|(_, v)| v.is_finite() && best.1 >= *v * (1.0 - margin));
        let (index, _) = keep.unwrap_or(best);
        self.current = Some(index);
        Some(index)
    }
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, Vec3};

    use super::*;
    use crate::{LightDirection, Projection, ShadowTransform};

    fn camera() -> Camera {
        Camera::look_to(
            Vec3::new(0.0, 10.0, 0.0),
            Vec3::NEG_Z,
            Vec3::Y,
            Projection::perspective(60f32.to_radians(), 16.0 / 9.0, 1.0, 200.0),
        )
        .unwrap()
    }

    /// An overhead orthographic map of `[-a, a]²` in x, z.
    fn overhead(a: f32) -> ShadowTransform {
        let clip_from_world = Mat4::from_cols(
            glam::Vec4::new(1.0 / a, 0.0, 0.0, 0.0),
            glam::Vec4::new(0.0, 0.0, -0.001, 0.0),
            glam::Vec4::new(0.0, -1.0 / a, 0.0, 0.0),
            glam::Vec4::new(0.0, 0.0, 0.5, 1.0),
        );
        ShadowTransform::new(
            Mat4::IDENTITY,
            clip_from_world,
            false,
            LightDirection::Directional(Vec3::NEG_Y),
        )
    }

    fn ground() -> Aabb {
        Aabb::new(Vec3::new(-200.0, 0.0, -210.0), Vec3::new(200.0, 30.0, 10.0))
    }

    #[test]
    fn faces_the_light_does_not_face_are_left_out() {
        // From inside the box the rays leave through the floor (lit from above), the
        // far wall and the ceiling (not lit).
        let map = overhead(400.0);
        let predict = |options: PredictOptions| {
            predict_error(&camera(), &ground(), &map, 1024, &options)
                .unwrap()
                .unwrap()
        };
        let all = predict(PredictOptions::default());
        let lit = predict(PredictOptions::default().with_light_direction(Vec3::NEG_Y));
        assert!(
            lit.rays > 0 && lit.rays < all.rays,
            "{} of {}",
            lit.rays,
            all.rays
        );
        // Lit from below, only the ceiling counts.
        let below = predict(PredictOptions::default().with_light_direction(Vec3::Y));
        assert!(below.rays > 0 && below.rays < all.rays);
        // A zero direction is no light: every ray.
        let none = predict(PredictOptions::default().with_light_direction(Vec3::ZERO));
        assert_eq!(none, all);
    }

    #[test]
    fn a_finer_map_predicts_a_proportionally_smaller_error() {
        let (c, g, map) = (camera(), ground(), overhead(250.0));
        let o = PredictOptions::default();
        let coarse = predict_error(&c, &g, &map, 512, &o).unwrap().unwrap();
        let fine = predict_error(&c, &g, &map, 2048, &o).unwrap().unwrap();
        assert!(coarse.rays > 50, "{coarse:?}");
        assert!((coarse.percentile / fine.percentile - 4.0).abs() < 1e-6);
        assert!(coarse.max >= coarse.percentile);
        // A map four times larger in world units has four times larger texels.
        let wide = predict_error(&c, &g, &overhead(1000.0), 2048, &o)
            .unwrap()
            .unwrap();
        assert!((wide.percentile / fine.percentile - 4.0).abs() < 1e-3);
    }

    #[test]
    fn the_ground_under_an_overhead_map_has_the_textbook_error() {
        // A level pinhole camera 10 m above the ground: a pixel at view depth z is
        // 2 z tan(30°) / 1080 wide, and an overhead map of 500 m over 2048 texels has
        // 2048 / 500 texels per metre, so m >= 1080 / (2 z tan 30°) / (2048 / 500),
        // with equality for the width of the pixel (the foreshortened height is longer).
        // The largest m is at the lowest row of rays, the nearest ground.
        let (c, g, map) = (camera(), ground(), overhead(250.0));
        let o = PredictOptions::default().with_percentile(1.0);
        let p = predict_error(&c, &g, &map, 2048, &o).unwrap().unwrap();
        assert_eq!(p.percentile, p.max);
        let tan = 30f64.to_radians().tan();
        let lowest = ((8.0 / 9.0) * tan).atan();
        let z = 10.0 / lowest.tan();
        let across = 1080.0 / (2.0 * z * tan) / (2048.0 / 500.0);
        assert!(
            p.max >= 0.999 * across && p.max <= 1.5 * across,
            "{} vs {across}",
            p.max
        );
    }

    #[test]
    fn nothing_met_or_bad_input_is_reported() {
        let (c, map) = (camera(), overhead(250.0));
        let away = Aabb::new(Vec3::splat(1000.0), Vec3::splat(1001.0));
        let o = PredictOptions::default();
        assert_eq!(predict_error(&c, &away, &map, 1024, &o), Ok(None));
        let inverted = Aabb::new(Vec3::ONE, Vec3::ZERO);
        assert_eq!(
            predict_error(&c, &inverted, &map, 1024, &o),
            Err(FrustumError::EmptyBounds)
        );
        assert_eq!(
            predict_error(&c, &ground(), &map, 0, &o),
            Err(FrustumError::InvalidResolution)
        );
        for bad in [
            o.with_grid(0, 4),
            o.with_grid(64, 64),
            o.with_percentile(0.0),
            o.with_percentile(f64::NAN),
            o.with_viewport_height(0),
        ] {
            assert_eq!(
                predict_error(&c, &ground(), &map, 1024, &bad),
                Err(FrustumError::InvalidResolution)
            );
        }
    }

    /// A mapping that covers only points nearer than `depth` in front of the camera.
    struct NearOnly(ShadowTransform, f64);

    impl ShadowMapping for NearOnly {
        fn map_point(&self, world: glam::DVec3) -> Option<crate::ShadowSample> {
            (-world.z < self.1)
                .then(|| self.0.map_point(world))
                .flatten()
        }
    }

    #[test]
    fn candidates_are_compared_on_the_rays_all_of_them_cover() {
        let (c, g, map) = (camera(), ground(), overhead(250.0));
        let near = NearOnly(map, 40.0);
        let o = PredictOptions::default();
        let mut out = [None; 2];
        predict_errors(&c, &g, &[(&map, 1024), (&near, 1024)], &o, &mut out).unwrap();
        let (all, near_only) = (out[0].unwrap(), out[1].unwrap());
        // The same rays, the same mapping there: the same prediction.
        assert_eq!(all, near_only);
        let alone = predict_error(&c, &g, &map, 1024, &o).unwrap().unwrap();
        assert!(all.rays < alone.rays, "{all:?} vs {alone:?}");
        // No shared ray: each on its own rays.
        let nowhere = NearOnly(map, 0.0);
        predict_errors(&c, &g, &[(&map, 1024), (&nowhere, 1024)], &o, &mut out).unwrap();
        assert_eq!(out, [Some(alone), None]);
        // Too many candidates, or an output of another length.
        let many = [(&map as &dyn ShadowMapping, 1024u32); MAX_PREDICT_CANDIDATES + 1];
        let mut nine = [None; MAX_PREDICT_CANDIDATES + 1];
        assert_eq!(
            predict_errors(&c, &g, &many, &o, &mut nine),
            Err(FrustumError::InvalidResolution)
        );
        assert_eq!(
            predict_errors(&c, &g, &[(&map, 1024)], &o, &mut out),
            Err(FrustumError::InvalidResolution)
        );
    }

    #[test]
    fn the_selector_switches_only_past_its_margin() {
        let mut s = TechniqueSelector::new();
        assert_eq!(s.choose(&[None, None]), None);
        assert_eq!(s.choose(&[Some(2.0), Some(1.0)]), Some(1));
        // 0 is now 5% better than 1: not enough to switch.
        assert_eq!(s.choose(&[Some(0.95), Some(1.0)]), Some(1));
        // 20% better: switch.
        assert_eq!(s.choose(&[Some(0.8), Some(1.0)]), Some(0));
        // The current one disappears: take the best.
        assert_eq!(s.choose(&[None, Some(3.0), Some(2.0)]), Some(2));
        // NaN predictions never win; ties go to the lower index.
        let mut fresh = TechniqueSelector::new().with_switch_margin(f64::NAN);
        assert_eq!(
            fresh.choose(&[Some(f64::NAN), Some(1.0), Some(1.0)]),
            Some(1)
        );
    }
}
