use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, Mat4, Vec3};

use crate::body::ConvexBody;
use crate::camera::CameraGeometry;
use crate::light::unit;
use crate::mapping::{LightDirection, ShadowSample, ShadowTransform, project_dmat};
use crate::split::CascadeBlend;
use crate::{Aabb, Camera, CascadeSplits, FrustumError, MAX_CASCADES, ShadowMapping, math};

/// Largest accepted shadow-map resolution (texels per side).
pub const MAX_RESOLUTION: u32 = 65536;

/// What casts and what receives shadows, as world-space boxes: the scene input of
/// every scene-dependent fit in the library (cascades, spot fit, the warps' focus
/// body, IPSM).
///
/// `receivers` bounds every surface that must look up the map; `casters` bounds every
/// surface that is drawn into it. Often both are the scene bounds
/// ([`SceneBounds::whole`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SceneBounds {
    /// Everything that receives shadows.
    pub receivers: Aabb,
    /// Everything that casts shadows.
    pub casters: Aabb,
}

impl SceneBounds {
    /// Receivers and casters given separately.
    #[must_use]
    pub const fn new(receivers: Aabb, casters: Aabb) -> Self {
        Self { receivers, casters }
    }

    /// One box that both casts and receives.
    #[must_use]
    pub const fn whole(scene: Aabb) -> Self {
        Self {
            receivers: scene,
            casters: scene,
        }
    }
}

/// How a cascade's light-space rectangle is chosen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CascadeFit {
    /// The light-space box of the slice (or of slice ∩ receivers): the most texels on
    /// the slice, but the map's size and texel grid change as the camera moves or
    /// turns, so shadow edges shimmer.
    Tight,
    /// The box of the slice's bounding sphere, snapped to whole texels against a fixed
    /// world anchor: the size is invariant under camera rotation and camera motion
    /// moves the map by whole texels, so shadow edges do not shimmer. With a
    /// power-of-two resolution the `f32` matrices keep the motion exact (the snapped
    /// offset `k / resolution` is representable); other resolutions drift by about
    /// `f32::EPSILON * k` texels after `k` texels of travel.
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
        let fitter = Fitter::new(camera, light_direction, options)?;
        let mut cascades = ArrayVec::new();
        for i in 0..splits.count() {
            let (near, far) = splits
                .cascade_range(i)
                .ok_or(FrustumError::InvalidCascadeCount)?;
            let cascade = match fitter.fit(near, far) {
                Err(FrustumError::SliceOutsideScene) => {
                    let mut c = fitter.fit_without_receivers(near, far)?;
                    c.receivers_missed = true;
                    c
                }
                other => other?,
            };
            cascades.push(cascade);
        }
        Ok(Self {
            cascades,
            splits: splits.clone(),
            view_from_world: fitter.camera.view_from_world().as_mat4(),
            resolution: options.resolution,
        })
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
    let fitter = Fitter::new(camera, light_direction, options)?;
    let (n, f) = fitter.camera.check_slice(near_depth, far_depth)?;
    fitter.fit(n as f32, f as f32)
}

/// Everything a cascade fit needs that does not depend on the slice, computed once
/// per call of [`CascadeSet::fit`].
struct Fitter {
    camera: CameraGeometry,
    light_dir: DVec3,
    light_from_world: DMat4,
    /// `light_from_world` in `f32`, as stored in every cascade.
    light_from_world32: Mat4,
    /// `light_from_world * world_from_view`: slice corners go to light space in one step.
    light_from_view: DMat4,
    /// The camera's edge rays in light space (see [`CameraGeometry`]).
    light_ray_origin: [DVec3; 4],
    light_ray_dir: [DVec3; 4],
    /// The camera's edge rays in world space.
    world_ray_origin: [DVec3; 4],
    world_ray_dir: [DVec3; 4],
    options: CascadeOptions,
    scene: Option<SceneBounds>,
}

impl Fitter {
    fn new(
        camera: &Camera,
        light_direction: Vec3,
        options: &CascadeOptions,
    ) -> Result<Self, FrustumError> {
        let camera = camera.geometry()?;
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
        let light_from_world = crate::projection::light_rotation(light_dir, options.up_hint);
        let light_from_view = light_from_world * camera.world_from_view;
        Ok(Self {
            camera,
            light_dir,
            light_from_world,
            light_from_world32: light_from_world.as_mat4(),
            light_from_view,
            light_ray_origin: camera
                .ray_origin
                .map(|o| light_from_view.transform_point3(o)),
            light_ray_dir: camera.ray_dir.map(|d| light_from_view.transform_vector3(d)),
            world_ray_origin: camera
                .ray_origin
                .map(|o| camera.world_from_view.transform_point3(o)),
            world_ray_dir: camera
                .ray_dir
                .map(|d| camera.world_from_view.transform_vector3(d)),
            options: *options,
            scene,
        })
    }

    /// The stable size ladder's step, when it applies (stable fit with scene bounds).
    fn ladder_step(&self) -> Option<f64> {
        match (self.options.fit, &self.scene, self.options.stable_size_step) {
            (CascadeFit::Stable, Some(_), Some(step)) => Some(f64::from(step)),
            _ => None,
        }
    }

    fn fit_without_receivers(&self, near: f32, far: f32) -> Result<Cascade, FrustumError> {
        let receiverless = Self {
            scene: None,
            ..*self
        };
        receiverless.fit(near, far)
    }

    fn fit(&self, near: f32, far: f32) -> Result<Cascade, FrustumError> {
        let (n, f) = self.camera.check_slice(near, far)?;
        let light = &self.light_from_world;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        // Largest world coordinate of the fitted points, for the invertibility test.
        let mut reach = 0.0f64;
        match &self.scene {
            Some(scene) => {
                // A slice too thin to clip reliably is treated like one that misses
                // the receivers: the caller falls back to the whole slice.
                let corners = self.camera.world_corners(n, f);
                let body = ConvexBody::from_dcorners_aabb(&corners, &scene.receivers).map_err(
                    |e| match e {
                        FrustumError::DegenerateFrustum => FrustumError::SliceOutsideScene,
                        e => e,
                    },
                )?;
                if body.is_empty() {
                    return Err(FrustumError::SliceOutsideScene);
                }
                for v in body.vertices() {
                    let p = v.as_dvec3();
                    reach = reach.max(p.abs().max_element());
                    let q = light.transform_point3(p);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
            None => {
                for i in 0..4 {
                    let (o, d) = (self.light_ray_origin[i], self.light_ray_dir[i]);
                    let (wo, wd) = (self.world_ray_origin[i], self.world_ray_dir[i]);
                    for depth in [n, f] {
                        let q = o + d * depth;
                        lo = lo.min(q);
                        hi = hi.max(q);
                        reach = reach.max((wo + wd * depth).abs().max_element());
                    }
                }
            }
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
                let (center_view, radius) = bounding_sphere(&self.camera.view_corners(n, f));
                let center = self.light_from_view.transform_point3(center_view);
                // One texel of slack on each side absorbs the snap (at most half a texel).
                let texel = 2.0 * radius / (res - 2.0);
                if !(texel > 0.0 && texel.is_finite()) {
                    return Err(FrustumError::EmptyBounds);
                }
                let snapped = (center.truncate() / texel).round() * texel;
                let half = DVec2::splat(0.5 * res * texel);
                (snapped - half, snapped + half, texel)
            }
        };
        // Light space looks down -Z: distance from the light is -z.
        let mut near_dist = -hi.z;
        let far_dist = -lo.z;
        let mut caster_depth = None;
        if let Some(scene) = &self.scene {
            if let Some((c_near, c_far)) = caster_depth_over(light, &scene.casters, xy_lo, xy_hi)? {
                caster_depth = Some((c_near as f32, c_far as f32));
                near_dist = near_dist.min(c_near);
            }
        }
        let depth_scale = near_dist.abs().max(far_dist.abs()).max(1e-30);
        let min_thickness = 1e-5 * depth_scale;
        let (near_dist, far_dist) = if far_dist - near_dist < min_thickness {
            let mid = 0.5 * (near_dist + far_dist);
            (mid - min_thickness, mid + min_thickness)
        } else {
            (near_dist, far_dist)
        };
        let clip_from_light = crate::projection::orthographic(
            xy_lo.x,
            xy_hi.x,
            xy_lo.y,
            xy_hi.y,
            near_dist,
            far_dist,
            self.options.reversed_z,
        );
        let clip_from_world = (clip_from_light * *light).as_mat4();
        if !crate::is_invertible(&clip_from_world, reach.max(depth_scale) as f32) {
            return Err(FrustumError::DegenerateFrustum);
        }
        let transform = ShadowTransform::new(
            self.light_from_world32,
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
    use crate::geometry::DPlane;
    let row = |r: usize| {
        let m = light_from_world;
        DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r])
    };
    let (rx, ry, rz) = (row(0), row(1), row(2));
    let boxed = casters.transformed(&light_from_world.as_mat4());
    let pad = 1.0 + f64::from(boxed.size().max_element());
    // The light frame is a rotation, so light-space coordinates are dot products.
    let prism = [
        DPlane::new(rx, -xy_lo.x),
        DPlane::new(-rx, xy_hi.x),
        DPlane::new(ry, -xy_lo.y),
        DPlane::new(-ry, xy_hi.y),
        DPlane::new(rz, -(f64::from(boxed.min.z) - pad)),
        DPlane::new(-rz, f64::from(boxed.max.z) + pad),
    ];
    let body = ConvexBody::from_planes_aabb(&prism, &casters.corners(), casters)?;
    let mut range: Option<(f64, f64)> = None;
    for v in body.vertices() {
        let d = -rz.dot(v.as_dvec3());
        range = Some(range.map_or((d, d), |(a, b)| (a.min(d), b.max(d))));
    }
    Ok(range)
}

/// The minimal bounding sphere of a slice among those centred on the segment between
/// its near and far face centroids, from its view-space corners. It depends only on
/// the projection and the depths, never on the camera's pose, so its radius is exactly
/// invariant under camera rotation.
///
/// With `c(t)` the point at `t` along the segment `d` (from the near centroid `c_n`
/// to the far centroid `c_f`) and `p_i` the corners, the squared distances share
/// their quadratic term:
///
/// ```text
/// |c(t) - p_i|^2 = |d|^2 t^2 - 2 t d.(p_i - c_n) + |p_i - c_n|^2
/// ```
///
/// so their maximum is `|d|^2 t^2` plus an upper envelope of lines, a convex function.
/// When the segment is perpendicular to both faces and each face's corners are
/// equidistant from its centroid (every symmetric perspective slice and every
/// orthographic one), only two of those lines differ and the minimum is closed-form:
///
/// ```text
/// t = clamp((|d|^2 + r_f^2 - r_n^2) / (2 |d|^2), 0, 1)
/// ```
///
/// `r_n`, `r_f` the face radii. For a symmetric perspective slice with half-angle
/// tangents `t_x`, `t_y` between depths `n` and `f` that is the centre depth
/// `min(f, (n + f) (1 + t_x^2 + t_y^2) / 2)`. Other slices (an off-centre custom
/// projection) take the exact minimum of the envelope: the least of its values at
/// the segment's ends, at each line's own vertex and at each crossing of two lines.
/// Either way the radius is the distance to the farthest corner, so the sphere
/// encloses the slice.
pub(crate) fn bounding_sphere(corners: &[DVec3; 8]) -> (DVec3, f64) {
    let near_c = (corners[0] + corners[1] + corners[2] + corners[3]) * 0.25;
    let far_c = (corners[4] + corners[5] + corners[6] + corners[7]) * 0.25;
    let d = far_c - near_c;
    let dd = d.length_squared();
    let farthest = |c: DVec3| {
        corners
            .iter()
            .map(|p| p.distance_squared(c))
            .fold(0.0, f64::max)
    };
    if !(dd > 0.0) {
        return (near_c, math::sqrt(farthest(near_c)));
    }
    let t = match two_face_parameter(corners, near_c, far_c, d, dd) {
        Some(t) => t,
        None => envelope_minimum(corners, near_c, d, dd),
    };
    let center = near_c + d * t;
    (center, math::sqrt(farthest(center)))
}

/// The closed-form parameter of [`bounding_sphere`] when the segment is perpendicular
/// to both faces and each face's corners are equidistant from its centroid (to a
/// relative `1e-12`); `None` otherwise.
fn two_face_parameter(
    corners: &[DVec3; 8],
    near_c: DVec3,
    far_c: DVec3,
    d: DVec3,
    dd: f64,
) -> Option<f64> {
    const TOL: f64 = 1e-12;
    let mut r2 = [(f64::INFINITY, 0.0f64); 2];
    let mut skew = 0.0f64;
    for (i, p) in corners.iter().enumerate() {
        let e = *p - if i < 4 { near_c } else { far_c };
        let e2 = e.length_squared();
        let r = &mut r2[i / 4];
        *r = (r.0.min(e2), r.1.max(e2));
        skew = skew.max(d.dot(e).abs());
    }
    let scale = dd.max(r2[0].1).max(r2[1].1);
    let equidistant = r2.iter().all(|(lo, hi)| hi - lo <= TOL * scale);
    // |d.e| <= |d| |e| sin(tolerance): compare squares to avoid a root.
    if !(equidistant && skew * skew <= TOL * TOL * dd * scale) {
        return None;
    }
    Some(((dd + r2[1].1 - r2[0].1) / (2.0 * dd)).clamp(0.0, 1.0))
}

/// The exact minimizer over `t` in `[0, 1]` of `dd t^2 + max_i (a_i t + b_i)`, the
/// farthest-corner squared distance along the centroid segment (see
/// [`bounding_sphere`]).
fn envelope_minimum(corners: &[DVec3; 8], near_c: DVec3, d: DVec3, dd: f64) -> f64 {
    let lines: [(f64, f64); 8] = core::array::from_fn(|i| {
        let e = corners[i] - near_c;
        (-2.0 * d.dot(e), e.length_squared())
    });
    let value = |t: f64| {
        dd * t * t
            + lines
                .iter()
                .map(|(a, b)| a * t + b)
                .fold(f64::MIN, f64::max)
    };
    let mut best = (value(0.0), 0.0);
    let mut consider = |t: f64| {
        if (0.0..=1.0).contains(&t) {
            let v = value(t);
            if v < best.0 {
                best = (v, t);
            }
        }
    };
    consider(1.0);
    for (i, (ai, bi)) in lines.iter().enumerate() {
        consider(-ai / (2.0 * dd));
        for (aj, bj) in &lines[i + 1..] {
            if ai != aj {
                consider((bj - bi) / (ai - aj));
            }
        }
    }
    best.1
}

/// The previous bounding-sphere search: an 80-step ternary search along the centroid
/// segment. Kept as the reference the closed form is tested against.
#[cfg(test)]
pub(crate) fn bounding_sphere_search(corners: &[DVec3; 8]) -> (DVec3, f64) {
    let near_c = (corners[0] + corners[1] + corners[2] + corners[3]) * 0.25;
    let far_c = (corners[4] + corners[5] + corners[6] + corners[7]) * 0.25;
    let radius_at = |t: f64| {
        let c = near_c.lerp(far_c, t);
        corners
            .iter()
            .map(|p| p.distance_squared(c))
            .fold(0.0, f64::max)
    };
    let (mut a, mut b) = (0.0f64, 1.0f64);
    for _ in 0..80 {
        let m1 = a + (b - a) / 3.0;
        let m2 = b - (b - a) / 3.0;
        if radius_at(m1) <= radius_at(m2) {
            b = m2;
        } else {
            a = m1;
        }
    }
    let t = 0.5 * (a + b);
    (near_c.lerp(far_c, t), math::sqrt(radius_at(t)))
}

#[cfg(test)]
mod tests {
    use super::{bounding_sphere, bounding_sphere_search};
    use glam::DVec3;
    use proptest::prelude::*;
    use shadowmap_testgen::{arbitrary::Unstructured, camera, in_range, strategy};

    /// This crate's camera from the generators' (they link the library build).
    fn local(c: &shadowmap_testgen::frustum::built::Camera) -> crate::Camera {
        use crate::Projection as P;
        use shadowmap_testgen::frustum::built::Projection as Q;
        let projection = match c.projection {
            Q::Perspective {
                fov_y,
                aspect,
                near,
                far,
            } => P::Perspective {
                fov_y,
                aspect,
                near,
                far,
            },
            Q::InfinitePerspective {
                fov_y,
                aspect,
                near,
                shadow_distance,
            } => P::InfinitePerspective {
                fov_y,
                aspect,
                near,
                shadow_distance,
            },
            Q::Orthographic {
                left,
                right,
                bottom,
                top,
                near,
                far,
            } => P::Orthographic {
                left,
                right,
                bottom,
                top,
                near,
                far,
            },
            Q::Custom {
                clip_from_view,
                shadow_distance,
            } => P::Custom {
                clip_from_view,
                shadow_distance,
            },
        };
        crate::Camera {
            world_from_view: c.world_from_view,
            projection,
            reversed_z: c.reversed_z,
        }
    }

    /// View-space corners of a random slice of a random valid camera (any projection,
    /// near-degenerate ones included).
    fn slice_corners(u: &mut Unstructured<'_>) -> shadowmap_testgen::GenResult<[DVec3; 8]> {
        let camera = local(&camera(u)?);
        let g = camera
            .geometry()
            .map_err(|_| shadowmap_testgen::arbitrary::Error::IncorrectFormat)?;
        let a = f64::from(in_range(u, 0.0, 1.0)?);
        let b = f64::from(in_range(u, 0.0, 1.0)?);
        let (a, b) = (a.min(b), a.max(b).max(a.min(b) + 1e-3).min(1.0));
        let depth = |t: f64| g.near + (g.far - g.near) * t;
        let (n, f) = (depth(a), depth(b));
        if !(f > n) {
            return Err(shadowmap_testgen::arbitrary::Error::IncorrectFormat);
        }
        Ok(g.view_corners(n, f))
    }

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// The closed form (or the exact envelope minimum) gives the search's sphere:
        /// the same radius within 1e-6 relative, and it encloses every corner.
        #[test]
        fn bounding_sphere_matches_search(corners in strategy(slice_corners)) {
            let (c, r) = bounding_sphere(&corners);
            let (c_ref, r_ref) = bounding_sphere_search(&corners);
            prop_assert!(r.is_finite() && r > 0.0);
            prop_assert!((r - r_ref).abs() <= 1e-6 * r_ref, "{r} vs {r_ref}");
            let scale = corners.iter().map(|p| p.length()).fold(r, f64::max);
            prop_assert!((c - c_ref).length() <= 1e-3 * scale + 1e-6 * scale, "{c} vs {c_ref}");
            for p in &corners {
                prop_assert!(p.distance(c) <= r * (1.0 + 1e-12));
            }
        }
    }

    /// The symmetric closed form: centre depth `min(f, (n + f)(1 + tx^2 + ty^2) / 2)`.
    #[test]
    fn symmetric_slice_centre_depth() {
        let (tx, ty) = (0.7f64, 0.4f64);
        let k = tx * tx + ty * ty;
        for (n, f) in [(0.1, 10.0), (8.0, 24.7), (50.0, 60.0), (1.0, 1000.0)] {
            let corner = |d: f64, sx: f64, sy: f64| DVec3::new(sx * tx * d, sy * ty * d, -d);
            let signs = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            let corners: [DVec3; 8] = core::array::from_fn(|i| {
                let (sx, sy) = signs[i % 4];
                corner(if i < 4 { n } else { f }, sx, sy)
            });
            let (c, r) = bounding_sphere(&corners);
            let depth = f64::min(f, (n + f) * (1.0 + k) / 2.0);
            assert!((-c.z - depth).abs() < 1e-9 * f, "{n} {f}: {c}");
            assert!(c.x.abs() < 1e-12 && c.y.abs() < 1e-12);
            let expect = ((f - depth).powi(2) + f * f * k).sqrt();
            assert!((r - expect).abs() < 1e-9 * f, "{r} vs {expect}");
        }
    }
}
