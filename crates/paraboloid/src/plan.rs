//! The IPSM plan: truncated frustum, light cone, rotation, cut, single or dual.

use glam::{DVec3, Vec3};
use shadowmap_frustum::{Camera, DepthBounds, Light, ShadowMapping, ShadowSample, ValidCamera};

use crate::ParaboloidError;
use crate::cone::{
    Cone, ConeFit, DCone, MIN_ZOOM, minimal_fit, paper_fit, round_up_f32, zoom_for_half_angle,
};
use crate::map::{MapOptions, ParaboloidMap, ParaboloidMode, Side, check_depth_range};
use crate::orient::{dual_axis, dual_axis_below, samples, single_cost};

/// Knobs of [`IpsmPlan`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct IpsmOptions {
    /// Which cone fit decides the rotation, the cut and single versus dual. Default
    /// [`ConeFit::Exact`].
    pub fit: ConeFit,
    /// Distance from the light mapped to depth 0 (1 with reversed-Z); the far distance
    /// is the light's range. Default `0.05`.
    pub near: f32,
    /// Angle (radians) added to the fitted half-angle, e.g. for filter kernels at the
    /// cone's rim. Default 0.
    pub margin: f32,
    /// Largest cone half-angle (margin included) rendered with one paraboloid; wider
    /// cones give a dual map. In `(0, pi/2]`, default `pi/2` (strictly below 90 degrees
    /// is single).
    pub max_single_half_angle: f32,
    /// Orients the light frame (see [`MapOptions::up_hint`]). Default `Y`.
    pub up_hint: Vec3,
    /// Reversed-Z depth. Default `false`.
    pub reversed_z: bool,
}

impl Default for IpsmOptions {
    fn default() -> Self {
        Self {
            fit: ConeFit::Exact,
            near: 0.05,
            margin: 0.0,
            max_single_half_angle: core::f32::consts::FRAC_PI_2,
            up_hint: Vec3::Y,
            reversed_z: false,
        }
    }
}

impl IpsmOptions {
    /// With this cone fit.
    #[must_use]
    pub const fn with_fit(mut self, fit: ConeFit) -> Self {
        self.fit = fit;
        self
    }
    /// With this near distance.
    #[must_use]
    pub const fn with_near(mut self, near: f32) -> Self {
        self.near = near;
        self
    }
    /// With this angular margin.
    #[must_use]
    pub const fn with_margin(mut self, margin: f32) -> Self {
        self.margin = margin;
        self
    }
    /// With this largest single-paraboloid half-angle.
    #[must_use]
    pub const fn with_max_single_half_angle(mut self, angle: f32) -> Self {
        self.max_single_half_angle = angle;
        self
    }
    /// With this up hint.
    #[must_use]
    pub const fn with_up_hint(mut self, up_hint: Vec3) -> Self {
        self.up_hint = up_hint;
        self
    }
    /// With reversed-Z depth.
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), ParaboloidError> {
        let m = self.margin;
        let a = self.max_single_half_angle;
        if !(m.is_finite() && a.is_finite() && self.near.is_finite() && self.up_hint.is_finite()) {
            return Err(ParaboloidError::NonFinite);
        }
        let ok = m >= 0.0 && a > 0.0 && a <= core::f32::consts::FRAC_PI_2 && self.near > 0.0;
        if ok {
            Ok(())
        } else {
            Err(ParaboloidError::InvalidOptions)
        }
    }
}

/// Why a plan renders two paraboloids.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum DualReason {
    /// The light lies inside the truncated frustum (exact fit: the origin is in the
    /// convex hull of the directions; paper fit: inside all six planes).
    LightInsideFrustum,
    /// The light lies on a frustum border point (within `f32` rounding).
    LightOnFrustumPoint,
    /// Paper fit only: the directions sum to zero, so there is no averaged axis.
    DirectionsCancel,
    /// The fitted cone (margin included) is wider than
    /// [`IpsmOptions::max_single_half_angle`].
    ConeTooWide,
    /// The cone fits one paraboloid, but a wide cut spends the single map's texels
    /// at its sparse centre: the dual map (each side half the texels, its seam
    /// through the view) is predicted to sample the truncated frustum more finely.
    DualFiner,
}

/// An improved paraboloid shadow map plan (Vanek et al.): the paper's four steps.
///
/// 1. truncated view frustum between the measured min/max view depth;
/// 2. the light cone around its 8 border points ([`ConeFit`]);
/// 3. the paraboloid turned so the front faces the cone axis;
/// 4. the cut `zoom = tan(half_angle / 2)`;
///
/// and the decision: one paraboloid when the cone's half-angle is under
/// [`IpsmOptions::max_single_half_angle`], else a regular DPSM with its seam through
/// the view.
///
/// The dual map is not turned toward the view as the paper suggests: a paraboloid's
/// texels are sparsest along its axis (half the linear density of its rim), so the
/// plan picks the axis whose seam carries the view (see the crate docs, "The dual
/// fallback").
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct IpsmPlan {
    /// The map to render (single or dual) and to look up.
    pub map: ParaboloidMap,
    /// The fitted cone (without margin); `None` when the fit has none (light inside
    /// the frustum for the exact fit, cancelling directions for the paper's).
    pub cone: Option<Cone>,
    /// Why the plan is dual; `None` for a single paraboloid.
    pub dual_reason: Option<DualReason>,
    /// The 8 border points of the truncated frustum (near then far; BL, BR, TR, TL).
    pub border_points: [Vec3; 8],
    /// The view-depth range of the truncated frustum.
    pub depth_range: (f32, f32),
}

/// The position and range of a checked point or spot light (a spot is planned as
/// a point light at its position).
fn point_light(light: &Light) -> Result<(Vec3, f32), ParaboloidError> {
    light.validate()?;
    match *light {
        Light::Point { position, range }
        | Light::Spot {
            position, range, ..
        } => Ok((position, range)),
        Light::Directional { .. } => Err(ParaboloidError::UnsupportedLight),
    }
}

impl IpsmPlan {
    /// Plans the paraboloid map of a point or spot light for `camera`, truncated to the
    /// measured `bounds` (or the camera's whole depth range when `None`; bounds are
    /// clamped as in [`DepthBounds::clamped_to`]). The light's range is the far
    /// distance. A spot light is planned as a point light at its position (the cone is
    /// fitted to the view, not to the spot).
    ///
    /// Documented fallbacks (a dual map, see [`IpsmPlan::dual_reason`]): light inside
    /// the truncated frustum or on one of its border points, cancelling directions
    /// (paper fit), a cone too wide for one paraboloid. The dual map's axis minimizes
    /// the largest predicted texel-to-pixel ratio over the truncated frustum (the
    /// view's directions near the seam, where a paraboloid is densest), its front on
    /// the side of the frustum's centroid; the up hint's axis is kept on ties.
    ///
    /// # Errors
    /// [`ParaboloidError::Frustum`] for an invalid light or camera;
    /// [`ParaboloidError::UnsupportedLight`] for a directional light;
    /// [`ParaboloidError::NonFinite`] / [`ParaboloidError::InvalidOptions`] for bad
    /// options; [`ParaboloidError::InvalidDepthRange`] unless
    /// `0 < options.near < range`; [`ParaboloidError::DegenerateFrustum`] when the
    /// border points (nearly) coincide; [`ParaboloidError::NonFinite`] for NaN bounds
    /// and [`ParaboloidError::InvalidDepthBounds`] for `bounds.min > bounds.max`
    /// (infinite bounds and bounds outside the camera's range are clamped to it, equal
    /// ones give the camera's range).
    pub fn new(
        light: &Light,
        camera: &Camera,
        bounds: Option<DepthBounds>,
        options: &IpsmOptions,
    ) -> Result<Self, ParaboloidError> {
        let (position, range) = point_light(light)?;
        // Checked once; the depth range and the slice reuse it.
        Self::plan_valid(
            position,
            range,
            &ValidCamera::new_validated(camera)?,
            bounds,
            options,
        )
    }

    /// [`IpsmPlan::new`] for a camera checked once per frame ([`ValidCamera`]), as
    /// the cascades take it: what a frame that plans several lights, or refits
    /// other techniques for the same view, pays per light.
    ///
    /// # Errors
    /// As [`IpsmPlan::new`], without the camera's.
    ///
    /// ```
    /// use glam::Vec3;
    /// use shadowmap_frustum::{Camera, Light, Projection, ValidCamera};
    /// use shadowmap_paraboloid::{IpsmOptions, IpsmPlan};
    ///
    /// let camera = Camera::look_to(
    ///     Vec3::new(0.0, 1.7, 0.0),
    ///     Vec3::NEG_Z,
    ///     Vec3::Y,
    ///     Projection::perspective(1.0, 1.6, 0.1, 60.0),
    /// )?;
    /// let valid = ValidCamera::new(&camera)?;
    /// let lamp = Light::Point { position: Vec3::new(2.0, 3.0, -8.0), range: 40.0 };
    /// let plan = IpsmPlan::new_valid(&lamp, &valid, None, &IpsmOptions::default())?;
    /// assert_eq!(
    ///     plan,
    ///     IpsmPlan::new(&lamp, &camera, None, &IpsmOptions::default())?
    /// );
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new_valid(
        light: &Light,
        camera: &ValidCamera,
        bounds: Option<DepthBounds>,
        options: &IpsmOptions,
    ) -> Result<Self, ParaboloidError> {
        let (position, range) = point_light(light)?;
        Self::plan_valid(position, range, camera, bounds, options)
    }

    /// The plan of a point light at `position` with `range` for a checked camera
    /// (the light checked by [`point_light`]).
    fn plan_valid(
        position: Vec3,
        range: f32,
        valid: &ValidCamera,
        bounds: Option<DepthBounds>,
        options: &IpsmOptions,
    ) -> Result<Self, ParaboloidError> {
        let (lo, hi) = match bounds {
            Some(b) if b.min.is_nan() || b.max.is_nan() => return Err(ParaboloidError::NonFinite),
            Some(b) if b.min > b.max => {
                return Err(ParaboloidError::InvalidDepthBounds {
                    min: b.min,
                    max: b.max,
                });
            }
            Some(b) => b.clamped_to_valid(valid),
            None => valid.depth_range(),
        };
        let corners = valid.slice_corners(lo, hi)?;
        let forward = valid.camera().forward();
        let mut plan = Self::from_points(position, range, &corners, forward, options)?;
        plan.depth_range = (lo, hi);
        Ok(plan)
    }

    /// The plan for explicit border points (near then far; BL, BR, TR, TL) of a
    /// truncated frustum; `forward` is the last-resort axis of a dual map (the
    /// camera's viewing direction). [`IpsmPlan::depth_range`] is `(0, 0)`.
    ///
    /// # Errors
    /// As [`IpsmPlan::new`] (without the light and camera errors);
    /// [`ParaboloidError::NonFinite`] for non-finite points or position.
    pub fn from_points(
        light_position: Vec3,
        range: f32,
        points: &[Vec3; 8],
        forward: Vec3,
        options: &IpsmOptions,
    ) -> Result<Self, ParaboloidError> {
        options.validate()?;
        if !(light_position.is_finite() && points.iter().all(|p| p.is_finite())) {
            return Err(ParaboloidError::NonFinite);
        }
        check_depth_range(options.near, range)?;
        let l = light_position.as_dvec3();
        let pts = points.map(Vec3::as_dvec3);
        let extent = pts.iter().map(|p| p.distance(pts[0])).fold(0.0, f64::max);
        let magnitude = pts.iter().map(|p| p.length()).fold(l.length(), f64::max);
        if extent.is_nan() || extent <= 1e-9 * (1.0 + magnitude) {
            return Err(ParaboloidError::DegenerateFrustum);
        }
        let on_point_tol = 1e-6 * extent + 2.5e-7 * magnitude;
        let mut on_point = false;
        let dirs = pts.map(|p| {
            let v = p - l;
            let len = v.length();
            if len <= on_point_tol {
                on_point = true;
                DVec3::ZERO
            } else {
                v / len
            }
        });
        let up_hint = options
            .up_hint
            .as_dvec3()
            .try_normalize()
            .unwrap_or(DVec3::ZERO);
        let map_options = MapOptions::default()
            .with_up_hint(options.up_hint)
            .with_reversed_z(options.reversed_z);
        let centroid = pts.iter().copied().sum::<DVec3>() / 8.0;
        let fallback_axis = [centroid - l, forward.as_dvec3(), DVec3::NEG_Z]
            .into_iter()
            .find_map(|a| a.is_finite().then(|| a.try_normalize()).flatten())
            .unwrap_or(DVec3::NEG_Z);

        let margin = f64::from(options.margin);
        let max_single = f64::from(options.max_single_half_angle);
        let (cone, reason): (Option<DCone>, Option<DualReason>) = if on_point {
            (None, Some(DualReason::LightOnFrustumPoint))
        } else {
            match options.fit {
                ConeFit::Exact => match minimal_fit(&dirs) {
                    Some(c) => (Some(c), None),
                    None => (None, Some(DualReason::LightInsideFrustum)),
                },
                ConeFit::Paper => {
                    if light_inside(l, &pts) {
                        (paper_fit(&dirs), Some(DualReason::LightInsideFrustum))
                    } else {
                        match paper_fit(&dirs) {
                            Some(c) => (Some(c), None),
                            None => (None, Some(DualReason::DirectionsCancel)),
                        }
                    }
                }
            }
        };
        // The dual map's axis search, run at most once (the single-or-dual decision
        // and the dual map both need it).
        let dual_found = core::cell::Cell::new(None);
        let dual = || {
            dual_found.get().unwrap_or_else(|| {
                let axis = dual_axis(l, &pts, up_hint, fallback_axis, fallback_axis);
                dual_found.set(Some(axis));
                axis
            })
        };
        let reason = match (reason, cone) {
            (None, Some(c)) if c.half_angle + margin >= max_single => Some(DualReason::ConeTooWide),
            (None, Some(c)) => {
                // The dual map wins where some axis costs less than the cut map.
                let samples = samples(l, &pts);
                let single = single_cost(&samples, c, margin);
                dual_axis_below(&samples, up_hint, fallback_axis, fallback_axis, single).map(
                    |axis| {
                        dual_found.set(Some(axis));
                        DualReason::DualFiner
                    },
                )
            }
            (r, _) => r,
        };
        let map = match (reason, cone) {
            (None, Some(c)) => ParaboloidMap::build(
                light_position,
                c.axis.as_vec3(),
                options.near,
                range,
                zoom_for_half_angle(c.half_angle + margin),
                ParaboloidMode::Single,
                &map_options,
            )?,
            _ => ParaboloidMap::build(
                light_position,
                dual().as_vec3(),
                options.near,
                range,
                1.0,
                ParaboloidMode::Dual,
                &map_options,
            )?,
        };
        let mut map = map;
        if map.mode == ParaboloidMode::Single {
            // Measure the cut on the built map: its f32 rotation moves directions by
            // about 1e-7 rad, which matters for narrow cones.
            let widest = pts
                .iter()
                .filter_map(|&p| ParaboloidMap::disc_point(map.to_light(p), Side::Front))
                .map(|d| d.disc.length())
                .fold(f64::from(map.zoom), f64::max);
            map.zoom = round_up_f32(widest * (1.0 + 1e-7)).clamp(MIN_ZOOM, 1.0);
        }
        let live: arrayvec::ArrayVec<DVec3, 8> =
            dirs.into_iter().filter(|d| *d != DVec3::ZERO).collect();
        Ok(Self {
            map,
            cone: cone.map(|c| c.to_f32(&live)),
            dual_reason: reason,
            border_points: *points,
            depth_range: (0.0, 0.0),
        })
    }

    /// Whether the plan renders one paraboloid.
    #[must_use]
    pub fn is_single(&self) -> bool {
        self.map.mode == ParaboloidMode::Single
    }

    /// The cut factor (1 for a dual map).
    #[must_use]
    pub fn zoom(&self) -> f32 {
        self.map.zoom
    }

    /// This plan with a dual map: front axis `axis` (world, any length), or the
    /// plan's own dual axis (the seam through the view, see [`IpsmPlan::new`]) when
    /// `None`; the light, depth range, cone and border points kept. For a renderer
    /// that measures the candidates on its own samples (a dual map of this plan's
    /// axis, or of a DPSM's fixed axis). A single plan becomes dual with
    /// [`DualReason::DualFiner`].
    ///
    /// # Errors
    /// As [`IpsmPlan::new`] for bad `options`; [`ParaboloidError::ZeroDirection`] /
    /// [`ParaboloidError::NonFinite`] for a bad `axis`.
    pub fn with_dual(
        &self,
        axis: Option<Vec3>,
        options: &IpsmOptions,
    ) -> Result<Self, ParaboloidError> {
        options.validate()?;
        let l = self.map.position.as_dvec3();
        let pts = self.border_points.map(Vec3::as_dvec3);
        let up_hint = options
            .up_hint
            .as_dvec3()
            .try_normalize()
            .unwrap_or(DVec3::ZERO);
        let axis = match axis {
            Some(a) => a,
            None => {
                let centroid = pts.iter().copied().sum::<DVec3>() / 8.0;
                let fallback = (centroid - l).try_normalize().unwrap_or(DVec3::NEG_Z);
                dual_axis(l, &pts, up_hint, fallback, fallback).as_vec3()
            }
        };
        let map_options = MapOptions::default()
            .with_up_hint(options.up_hint)
            .with_reversed_z(options.reversed_z);
        let map = ParaboloidMap::dual(
            self.map.position,
            axis,
            self.map.near,
            self.map.far,
            &map_options,
        )?;
        Ok(Self {
            map,
            dual_reason: self.dual_reason.or(Some(DualReason::DualFiner)),
            ..*self
        })
    }
}

impl ShadowMapping for IpsmPlan {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        self.map.map_point(world)
    }
}

/// Corner indices of each face of a frustum.
const FACES: [[usize; 3]; 6] = [
    [0, 3, 7],
    [1, 5, 6],
    [0, 4, 5],
    [3, 2, 6],
    [0, 1, 2],
    [4, 7, 6],
];

/// Whether `l` lies inside (or on) the frustum with these corners: the paper's test.
fn light_inside(l: DVec3, pts: &[DVec3; 8]) -> bool {
    let centroid = pts.iter().copied().sum::<DVec3>() / 8.0;
    FACES.iter().all(|&[a, b, c]| {
        let n = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
        let Some(n) = n.try_normalize() else {
            return true;
        };
        let n = if n.dot(centroid - pts[a]) < 0.0 {
            -n
        } else {
            n
        };
        n.dot(l - pts[a]) >= 0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowmap_frustum::Projection;

    fn camera() -> Camera {
        Camera::look_to(
            Vec3::ZERO,
            Vec3::NEG_Z,
            Vec3::Y,
            Projection::perspective(1.0, 1.5, 0.1, 100.0),
        )
        .unwrap()
    }

    #[test]
    fn light_outside_gives_a_single_cut_map_covering_the_frustum() {
        let light = Light::Point {
            position: Vec3::new(0.0, 50.0, -50.0),
            range: 500.0,
        };
        let bounds = DepthBounds {
            min: 5.0,
            max: 40.0,
        };
        let plan = IpsmPlan::new(&light, &camera(), Some(bounds), &IpsmOptions::default()).unwrap();
        assert!(plan.is_single());
        assert!(plan.zoom() < 1.0);
        for p in plan.border_points {
            let s = plan.map_point(p.as_dvec3()).unwrap();
            assert!((s.uv - glam::DVec2::splat(0.5)).length() <= 0.5 + 1e-5);
        }
        let paper = IpsmPlan::new(
            &light,
            &camera(),
            Some(bounds),
            &IpsmOptions::default().with_fit(ConeFit::Paper),
        )
        .unwrap();
        assert!(paper.zoom() >= plan.zoom());
    }

    #[test]
    fn light_inside_gives_a_dual_map() {
        let light = Light::Point {
            position: Vec3::new(0.0, 0.0, -20.0),
            range: 500.0,
        };
        for fit in [ConeFit::Exact, ConeFit::Paper] {
            let plan = IpsmPlan::new(
                &light,
                &camera(),
                None,
                &IpsmOptions::default().with_fit(fit),
            )
            .unwrap();
            assert!(!plan.is_single());
            assert_eq!(plan.dual_reason, Some(DualReason::LightInsideFrustum));
            assert_eq!(plan.zoom(), 1.0);
        }
    }

    #[test]
    fn dual_fallback_puts_the_view_on_the_seam() {
        // A light inside the view, ahead of and above the camera.
        let light = Light::Point {
            position: Vec3::new(3.0, 8.0, -40.0),
            range: 500.0,
        };
        let cam = camera();
        let plan = IpsmPlan::new(&light, &cam, None, &IpsmOptions::default()).unwrap();
        assert!(!plan.is_single());
        let l = DVec3::new(3.0, 8.0, -40.0);
        let pts = cam.slice(0.1, 100.0).unwrap().corners.map(Vec3::as_dvec3);
        let samples = crate::orient::samples(l, &pts);
        let cost = |a: DVec3| crate::orient::cost(a, &samples);
        let chosen = cost(plan.map.axis().as_dvec3());
        // Never worse than a DPSM facing down (the up hint's axis) ...
        assert!(chosen <= cost(DVec3::Y) * (1.0 + 1e-6));
        // ... and clearly better than facing the view's centroid (the paper's turn).
        let centroid = pts.iter().copied().sum::<DVec3>() / 8.0;
        assert!(chosen < 0.9 * cost((centroid - l).normalize()));
    }

    #[test]
    fn light_on_a_corner_falls_back_to_dual() {
        let f = camera().slice(1.0, 10.0).unwrap();
        let plan = IpsmPlan::from_points(
            f.corners[5],
            100.0,
            &f.corners,
            Vec3::NEG_Z,
            &IpsmOptions::default(),
        )
        .unwrap();
        assert_eq!(plan.dual_reason, Some(DualReason::LightOnFrustumPoint));
    }

    #[test]
    fn bad_input_is_typed() {
        let light = Light::Directional {
            direction: Vec3::NEG_Y,
        };
        assert_eq!(
            IpsmPlan::new(&light, &camera(), None, &IpsmOptions::default()),
            Err(ParaboloidError::UnsupportedLight)
        );
        let point = Light::Point {
            position: Vec3::new(0.0, 50.0, -50.0),
            range: 500.0,
        };
        let p = [Vec3::ONE; 8];
        assert_eq!(
            IpsmPlan::from_points(Vec3::ZERO, 10.0, &p, Vec3::NEG_Z, &IpsmOptions::default()),
            Err(ParaboloidError::DegenerateFrustum)
        );
        let swapped = DepthBounds {
            min: 40.0,
            max: 5.0,
        };
        assert_eq!(
            IpsmPlan::new(&point, &camera(), Some(swapped), &IpsmOptions::default()),
            Err(ParaboloidError::InvalidDepthBounds {
                min: 40.0,
                max: 5.0
            })
        );
        let nan = DepthBounds {
            min: f32::NAN,
            max: 5.0,
        };
        assert_eq!(
            IpsmPlan::new(&point, &camera(), Some(nan), &IpsmOptions::default()),
            Err(ParaboloidError::NonFinite)
        );
        // Ordered bounds are accepted and truncate the frustum.
        let ordered = DepthBounds {
            min: 5.0,
            max: 40.0,
        };
        let plan = IpsmPlan::new(&point, &camera(), Some(ordered), &IpsmOptions::default());
        assert_eq!(plan.map(|p| p.depth_range), Ok((5.0, 40.0)));
        let o = IpsmOptions::default().with_margin(-1.0);
        let f = camera().slice(1.0, 10.0).unwrap();
        assert_eq!(
            IpsmPlan::from_points(Vec3::Y * 50.0, 100.0, &f.corners, Vec3::NEG_Z, &o),
            Err(ParaboloidError::InvalidOptions)
        );
    }
}
