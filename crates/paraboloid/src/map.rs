//! The paraboloid map (Brabec et al.): forward and inverse maps, density, usable disc.

use glam::{DMat4, DVec2, DVec3, Mat4, Vec2, Vec3};
use shadowmap_frustum::{ShadowMapping, ShadowSample, math};

use crate::ParaboloidError;
use crate::cone::{MIN_ZOOM, zoom_for_half_angle};

/// Which paraboloid of a map.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Side {
    /// The paraboloid facing along the map's axis (light-space `-Z`); layer 0.
    Front,
    /// The paraboloid facing away from the axis (light-space `+Z`); layer 1.
    Back,
}

impl Side {
    /// Texture-array layer: 0 front, 1 back.
    #[must_use]
    pub const fn layer(self) -> u32 {
        match self {
            Self::Front => 0,
            Self::Back => 1,
        }
    }
}

/// How many paraboloids a map renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ParaboloidMode {
    /// One front paraboloid, cut by the zoom factor to the light cone.
    Single,
    /// Front and back paraboloids (regular DPSM, zoom 1), front turned along the axis.
    Dual,
}

/// Knobs of [`ParaboloidMap`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[non_exhaustive]
pub struct MapOptions {
    /// Orients the light frame's `Y` axis; when (nearly) parallel to the axis, the world
    /// axis least aligned with it is used. Default `Y`.
    pub up_hint: Vec3,
    /// Store depth as 1 at `near` and 0 at `far`. Default `false`.
    pub reversed_z: bool,
}

impl Default for MapOptions {
    fn default() -> Self {
        Self {
            up_hint: Vec3::Y,
            reversed_z: false,
        }
    }
}

impl MapOptions {
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
}

/// The disc of a paraboloid map's texture where the map is guaranteed meaningful: the
/// image of the light cone (of the hemisphere for a dual map).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct UsableDisc {
    /// Centre in texture coordinates, `(0.5, 0.5)`.
    pub center: Vec2,
    /// Radius in texture coordinates, `0.5`.
    pub radius: f32,
    /// Half-angle (radians, from the axis) of the directions mapped onto the disc.
    pub half_angle: f32,
}

impl UsableDisc {
    /// Whether texture coordinates `uv` lie in the disc.
    #[must_use]
    pub fn contains(&self, uv: Vec2) -> bool {
        uv.distance_squared(self.center) <= self.radius * self.radius
    }
}

/// A paraboloid shadow map around a point light: one cut front paraboloid, or a
/// front/back pair.
///
/// `light_from_world` is rigid (rotation and translation): the light at the origin,
/// the front paraboloid facing `-Z`. A world point `P` maps as
///
/// ```text
/// q = light_from_world * P              d = q / |q|
/// front: s = -d.z   disc = ( d.x, d.y) / (1 + s)
/// back:  s =  d.z   disc = (-d.x, d.y) / (1 + s)
/// ndc   = disc / zoom                     (zoom = tan(cone half-angle / 2), 1 for DPSM)
/// uv    = (0.5 + 0.5 ndc.x, 0.5 - 0.5 ndc.y)                        (v down)
/// depth = (|q| - near) / (far - near)     (1 - that with reversed-Z)
/// ```
///
/// The back map mirrors `x`, so each side looks like a camera facing its way with
/// the same up vector.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ParaboloidMap {
    /// Rigid light frame; the front paraboloid faces `-Z`.
    pub light_from_world: Mat4,
    /// Light position in world space.
    pub position: Vec3,
    /// Distance from the light mapped to depth 0 (1 with reversed-Z).
    pub near: f32,
    /// Distance from the light mapped to depth 1 (0 with reversed-Z).
    pub far: f32,
    /// Cut factor `Z` in `[MIN_ZOOM, 1]`: the disc of radius `Z` fills the texture.
    pub zoom: f32,
    /// Whether depth is reversed.
    pub reversed_z: bool,
    /// One or two paraboloids.
    pub mode: ParaboloidMode,
}

/// Where a direction lands on one paraboloid, in `f64`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DiscPoint {
    /// Unzoomed disc coordinates.
    pub(crate) disc: DVec2,
    /// Distance from the light.
    pub(crate) distance: f64,
}

impl ParaboloidMap {
    /// A regular dual-paraboloid map (DPSM, zoom 1) at `position` with the front
    /// paraboloid facing `axis`, depth over `[near, far]` distance from the light.
    ///
    /// # Errors
    /// [`ParaboloidError::NonFinite`] (also for a position so large that the frame's
    /// translation overflows `f32`), [`ParaboloidError::ZeroDirection`] for a zero
    /// axis, [`ParaboloidError::InvalidDepthRange`] unless `0 < near < far` with
    /// `(far - near) > 1e-5 far`.
    pub fn dual(
        position: Vec3,
        axis: Vec3,
        near: f32,
        far: f32,
        options: &MapOptions,
    ) -> Result<Self, ParaboloidError> {
        Self::build(
            position,
            axis,
            near,
            far,
            1.0,
            ParaboloidMode::Dual,
            options,
        )
    }

    /// A single paraboloid facing `axis`, cut to a cone of `half_angle` radians
    /// (`zoom = tan(half_angle / 2)`, see [`MIN_ZOOM`](crate::MIN_ZOOM)).
    ///
    /// # Errors
    /// As [`ParaboloidMap::dual`], and [`ParaboloidError::InvalidZoom`] for a
    /// half-angle outside `(0, pi/2]` (`pi/2` as `f32`, `std::f32::consts::FRAC_PI_2`,
    /// included: it gives zoom 1).
    pub fn single(
        position: Vec3,
        axis: Vec3,
        half_angle: f32,
        near: f32,
        far: f32,
        options: &MapOptions,
    ) -> Result<Self, ParaboloidError> {
        if !half_angle.is_finite() {
            return Err(ParaboloidError::NonFinite);
        }
        // Compared in `f32`: `f32::consts::FRAC_PI_2` rounds above the `f64` value, and
        // the caller's pi/2 must be accepted; the cut is then exactly the hemisphere.
        if !(half_angle > 0.0 && half_angle <= core::f32::consts::FRAC_PI_2) {
            return Err(ParaboloidError::InvalidZoom);
        }
        let h = f64::from(half_angle).min(core::f64::consts::FRAC_PI_2);
        let zoom = zoom_for_half_angle(h);
        Self::build(
            position,
            axis,
            near,
            far,
            zoom,
            ParaboloidMode::Single,
            options,
        )
    }

    pub(crate) fn build(
        position: Vec3,
        axis: Vec3,
        near: f32,
        far: f32,
        zoom: f64,
        mode: ParaboloidMode,
        options: &MapOptions,
    ) -> Result<Self, ParaboloidError> {
        if !(position.is_finite() && axis.is_finite() && near.is_finite() && far.is_finite()) {
            return Err(ParaboloidError::NonFinite);
        }
        check_depth_range(near, far)?;
        let dir = axis
            .as_dvec3()
            .try_normalize()
            .filter(|d| d.length_squared() > 0.5)
            .ok_or(ParaboloidError::ZeroDirection)?;
        let rot = shadowmap_frustum::projection::light_rotation(dir, options.up_hint);
        let light_from_world = rot * DMat4::from_translation(-position.as_dvec3());
        if !light_from_world.as_mat4().is_finite() {
            return Err(ParaboloidError::NonFinite);
        }
        let zoom = (zoom.clamp(f64::from(MIN_ZOOM), 1.0)) as f32;
        Ok(Self {
            light_from_world: light_from_world.as_mat4(),
            position,
            near,
            far,
            zoom,
            reversed_z: options.reversed_z,
            mode,
        })
    }

    /// The front axis in world space (unit).
    #[must_use]
    pub fn axis(&self) -> Vec3 {
        let m = self.light_from_world;
        -Vec3::new(m.x_axis.z, m.y_axis.z, m.z_axis.z).normalize_or(Vec3::NEG_Z)
    }

    /// Number of texture-array layers the map uses (1 or 2).
    #[must_use]
    pub const fn layers(&self) -> u32 {
        match self.mode {
            ParaboloidMode::Single => 1,
            ParaboloidMode::Dual => 2,
        }
    }

    /// The paraboloid that stores `world`: the front one when `world` lies on the
    /// axis side of the light's plane (or the map is single), else the back one.
    ///
    /// ```text
    /// side = front  if mode == Single or -(light_from_world * P).z >= 0
    /// ```
    #[must_use]
    pub fn side_of(&self, world: Vec3) -> Side {
        self.side_of_light(self.to_light(world.as_dvec3()))
    }

    fn side_of_light(&self, q: DVec3) -> Side {
        if self.mode == ParaboloidMode::Single || -q.z >= 0.0 {
            Side::Front
        } else {
            Side::Back
        }
    }

    /// Light-space point: the rotation of `light_from_world` applied to
    /// `world - position` in `f64`, so that no `f32` translation rounding moves points
    /// next to the light.
    pub(crate) fn to_light(self, world: DVec3) -> DVec3 {
        self.light_from_world
            .as_dmat4()
            .transform_vector3(world - self.position.as_dvec3())
    }

    /// Disc coordinates of a light-space point on one side; `None` at the light or
    /// at the side's pole (straight behind).
    pub(crate) fn disc_point(q: DVec3, side: Side) -> Option<DiscPoint> {
        let distance = q.length();
        if !(distance > 0.0 && distance.is_finite()) {
            return None;
        }
        let d = q / distance;
        let (x, s) = match side {
            Side::Front => (d.x, -d.z),
            Side::Back => (-d.x, d.z),
        };
        // 1 + s, accurate also near the pole: (1 + s)(1 - s) = x^2 + y^2.
        let denom = if s >= 0.0 {
            1.0 + s
        } else {
            (x * x + d.y * d.y) / (1.0 - s)
        };
        if denom.is_nan() || denom <= 1e-300 {
            return None;
        }
        let disc = DVec2::new(x, d.y) / denom;
        disc.is_finite().then_some(DiscPoint { disc, distance })
    }

    pub(crate) fn uv_of_disc(&self, disc: DVec2) -> DVec2 {
        let ndc = disc / f64::from(self.zoom);
        DVec2::new(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y)
    }

    fn depth_of(&self, distance: f64) -> f64 {
        let (n, f) = (f64::from(self.near), f64::from(self.far));
        let d = (distance - n) / (f - n);
        if self.reversed_z { 1.0 - d } else { d }
    }

    /// The sample for a light-space point on a given side, without coverage checks.
    pub(crate) fn sample_on(&self, q: DVec3, side: Side) -> Option<ShadowSample> {
        let p = Self::disc_point(q, side)?;
        let sample = ShadowSample {
            uv: self.uv_of_disc(p.disc),
            depth: self.depth_of(p.distance),
            layer: side.layer(),
        };
        (sample.uv.is_finite() && sample.depth.is_finite()).then_some(sample)
    }

    /// Where `world` lands on the paraboloid `side` (the depth pass of that side):
    /// texture coordinates (outside `[0, 1]²` when outside the cut), depth, and
    /// layer. `None` at the light itself and straight behind the side's axis.
    #[must_use]
    pub fn project(&self, world: Vec3, side: Side) -> Option<ShadowSample> {
        self.sample_on(self.to_light(world.as_dvec3()), side)
    }

    /// The depth pass's user clip distance of `world` on `side`: the cosine of its
    /// angle from the side's plane through the light, positive in front of the side
    /// (toward its axis), negative behind it, 0 at the light.
    ///
    /// ```text
    /// q = light_from_world * (P - position)
    /// front: -q.z / |q|      back: q.z / |q|
    /// ```
    #[must_use]
    pub fn clip_distance(&self, world: Vec3, side: Side) -> f64 {
        let len = self.to_light(world.as_dvec3()).length();
        if !(len > 0.0 && len.is_finite()) {
            return 0.0;
        }
        self.plane_distance(world, side) / len
    }

    /// The signed distance of `world` to the side's plane through the light (`-q.z`
    /// on the front side, `q.z` on the back), an affine function of the point with
    /// the sign of [`clip_distance`](Self::clip_distance): a triangle whose three
    /// vertices lie behind the side lies behind it whole, and one across the plane
    /// is cut where this is 0.
    #[must_use]
    pub fn plane_distance(&self, world: Vec3, side: Side) -> f64 {
        let z = self.to_light(world.as_dvec3()).z;
        match side {
            Side::Front => -z,
            Side::Back => z,
        }
    }

    /// The shadow lookup, mirrored by the shader: picks the side with
    /// [`ParaboloidMap::side_of`], then projects. `None` at the light, and for a
    /// single map where `uv` falls outside `[0, 1]²` (outside the cut).
    #[must_use]
    pub fn lookup(&self, world: Vec3) -> Option<ShadowSample> {
        self.map_point(world.as_dvec3())
    }

    /// The world point stored at texture coordinates `uv` and `depth` on `side`: the
    /// inverse of [`ParaboloidMap::project`].
    ///
    /// ```text
    /// disc = zoom * (2u - 1, 1 - 2v)      r2 = |disc|^2
    /// front: d = ( 2 disc.x, 2 disc.y, -(1 - r2)) / (1 + r2)
    /// back:  d = (-2 disc.x, 2 disc.y,  (1 - r2)) / (1 + r2)
    /// P = world_from_light * (d * (near + depth' (far - near)))
    /// ```
    ///
    /// `None` for non-finite input or a singular frame.
    #[must_use]
    pub fn unproject(&self, uv: Vec2, depth: f32, side: Side) -> Option<Vec3> {
        self.unproject_f64(uv.as_dvec2(), f64::from(depth), side)
            .map(DVec3::as_vec3)
            .filter(|p| p.is_finite())
    }

    pub(crate) fn unproject_f64(&self, uv: DVec2, depth: f64, side: Side) -> Option<DVec3> {
        if !(uv.is_finite() && depth.is_finite()) {
            return None;
        }
        let disc = DVec2::new(2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y) * f64::from(self.zoom);
        let r2 = disc.length_squared();
        let k = 1.0 / (1.0 + r2);
        let d = match side {
            Side::Front => DVec3::new(2.0 * disc.x, 2.0 * disc.y, -(1.0 - r2)) * k,
            Side::Back => DVec3::new(-2.0 * disc.x, 2.0 * disc.y, 1.0 - r2) * k,
        };
        let depth = if self.reversed_z { 1.0 - depth } else { depth };
        let (n, f) = (f64::from(self.near), f64::from(self.far));
        let q = d * (n + depth * (f - n));
        let m = glam::DMat3::from_mat4(self.light_from_world.as_dmat4());
        let det = m.determinant();
        if det.is_nan() || det.abs() <= 1e-12 {
            return None;
        }
        let p = self.position.as_dvec3() + m.inverse() * q;
        p.is_finite().then_some(p)
    }

    /// Texel density at `world` on its side for a map of `resolution²` texels, in
    /// texels per steradian of directions from the light.
    ///
    /// ```text
    /// texels / sr = resolution^2 / (4 zoom^2 (1 + cos theta)^2)
    /// ```
    ///
    /// with `theta` the angle from the side's axis: 4 times denser at the rim than at
    /// the centre for a DPSM, and `1 / zoom²` denser everywhere for a cut map. `None`
    /// at the light, straight behind, or for a zero resolution.
    #[must_use]
    pub fn texels_per_steradian(&self, world: Vec3, resolution: u32) -> Option<f32> {
        let q = self.to_light(world.as_dvec3());
        let p = Self::disc_point(q, self.side_of_light(q))?;
        let one_plus = 2.0 / (1.0 + p.disc.length_squared());
        let z = f64::from(self.zoom);
        let n = f64::from(resolution);
        let density = n * n / (4.0 * z * z * one_plus * one_plus);
        (density.is_finite() && density > 0.0).then_some(density as f32)
    }

    /// The disc of the texture where the map is meaningful (the image of the cone
    /// for a single map, of the hemisphere for a dual map).
    #[must_use]
    pub fn usable_disc(&self) -> UsableDisc {
        let half = 2.0 * math::atan(f64::from(self.zoom));
        UsableDisc {
            center: Vec2::splat(0.5),
            radius: 0.5,
            half_angle: half as f32,
        }
    }
}

/// The map as a uniform block for the shader (`#[repr(C)]`, 96 bytes, `f32` only): the
/// WGSL lookup mirrors [`ParaboloidMap::lookup`] with these fields.
///
/// ```text
/// q = (rotation * vec4(P - position_near.xyz, 0)).xyz
/// side = front if dual == 0 or -q.z >= 0; front: disc = (q.x, q.y) / (|q| - q.z),
/// back: disc = (-q.x, q.y) / (|q| + q.z); uv = 0.5 + (0.5, -0.5) * disc / zoom
/// depth = (|q| - near) / (far - near), 1 - depth if reversed
/// ```
///
/// Six 16-byte rows with no padding, so `#[repr(C)]` matches WGSL's uniform layout;
/// with the `bytemuck` feature the block is `Pod` and `Zeroable` and uploads as is
/// (`bytemuck::bytes_of`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "bytemuck", derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct ParaboloidUniform {
    /// `light_from_world` with its translation column cleared, column-major.
    pub rotation: [[f32; 4]; 4],
    /// Light position (xyz) and near distance (w).
    pub position_near: [f32; 4],
    /// Far distance, zoom, reversed-Z (0 or 1), dual (0 or 1).
    pub far_zoom_reversed_dual: [f32; 4],
}

impl ParaboloidMap {
    /// The uniform block for the shader.
    #[must_use]
    pub fn to_raw(&self) -> ParaboloidUniform {
        let mut rotation = self.light_from_world;
        rotation.w_axis = glam::Vec4::W;
        ParaboloidUniform {
            rotation: rotation.to_cols_array_2d(),
            position_near: self.position.extend(self.near).to_array(),
            far_zoom_reversed_dual: [
                self.far,
                self.zoom,
                f32::from(u8::from(self.reversed_z)),
                f32::from(u8::from(self.mode == ParaboloidMode::Dual)),
            ],
        }
    }
}

impl ShadowMapping for ParaboloidMap {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let q = self.to_light(world);
        let side = self.side_of_light(q);
        let s = self.sample_on(q, side)?;
        match self.mode {
            ParaboloidMode::Dual => Some(s),
            ParaboloidMode::Single => {
                let inside = (0.0..=1.0).contains(&s.uv.x) && (0.0..=1.0).contains(&s.uv.y);
                inside.then_some(s)
            }
        }
    }
}

/// Checks a light depth range.
pub(crate) fn check_depth_range(near: f32, far: f32) -> Result<(), ParaboloidError> {
    if !(near.is_finite() && far.is_finite()) {
        return Err(ParaboloidError::NonFinite);
    }
    let ok = near > 0.0 && far > near && f64::from(far) - f64::from(near) > 1e-5 * f64::from(far);
    if ok {
        Ok(())
    } else {
        Err(ParaboloidError::InvalidDepthRange { near, far })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> ParaboloidMap {
        ParaboloidMap::dual(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::X,
            0.1,
            100.0,
            &MapOptions::default(),
        )
        .unwrap()
    }

    #[test]
    fn axis_maps_to_the_centre_and_rim_to_the_unit_circle() {
        let m = map();
        let s = m.project(Vec3::new(11.0, 2.0, 3.0), Side::Front).unwrap();
        assert!((s.uv - DVec2::splat(0.5)).length() < 1e-6);
        assert!((s.depth - (10.0 - 0.1) / 99.9).abs() < 1e-6);
        // 90 degrees off the axis lands on the disc's rim.
        let s = m.project(Vec3::new(1.0, 12.0, 3.0), Side::Front).unwrap();
        assert!(((s.uv - DVec2::splat(0.5)).length() - 0.5).abs() < 1e-6);
        // Up (world Y) is up in the texture: v decreases.
        assert!(s.uv.y < 0.5);
        let b = m.project(Vec3::new(-9.0, 2.0, 3.0), Side::Back).unwrap();
        assert!((b.uv - DVec2::splat(0.5)).length() < 1e-6);
        assert_eq!(m.side_of(Vec3::new(-9.0, 2.0, 3.0)), Side::Back);
    }

    /// The clip distance is the cosine from the side's plane: 1 on the axis, 0 on the
    /// rim, the opposite sign on the other side, and it keeps what the side stores.
    #[test]
    fn clip_distance_is_the_cosine_from_the_plane() {
        let m = map();
        let on_axis = Vec3::new(11.0, 2.0, 3.0);
        assert!((m.clip_distance(on_axis, Side::Front) - 1.0).abs() < 1e-6);
        assert!((m.clip_distance(on_axis, Side::Back) + 1.0).abs() < 1e-6);
        assert!(
            m.clip_distance(Vec3::new(1.0, 12.0, 3.0), Side::Front)
                .abs()
                < 1e-6
        );
        let p = Vec3::new(4.0, -1.0, 7.0);
        let c = m.clip_distance(p, Side::Front);
        assert!((c - 3.0 / 34.0_f64.sqrt()).abs() < 1e-6, "{c}");
        assert_eq!(m.side_of(p), Side::Front);
        assert_eq!(m.clip_distance(m.position, Side::Front), 0.0);
        assert!((m.plane_distance(p, Side::Front) - 3.0).abs() < 1e-6);
        assert!((m.plane_distance(p, Side::Back) + 3.0).abs() < 1e-6);
    }

    #[test]
    fn unproject_inverts_project() {
        let m = map();
        let p = Vec3::new(-4.0, 7.0, 1.0);
        for side in [Side::Front, Side::Back] {
            let s = m.project(p, side).unwrap();
            let back = m.unproject(s.uv.as_vec2(), s.depth as f32, side).unwrap();
            assert!((back - p).length() < 1e-4, "{side:?} {back}");
        }
    }

    #[test]
    fn uniform_mirrors_the_lookup() {
        let m = map();
        let raw = m.to_raw();
        let p = Vec3::new(-4.0, 7.0, 1.0);
        let rot = Mat4::from_cols_array_2d(&raw.rotation);
        let pos = Vec3::from_slice(&raw.position_near[..3]);
        let q = rot.transform_vector3(p - pos).as_dvec3();
        let len = q.length();
        let front = raw.far_zoom_reversed_dual[3] == 0.0 || -q.z >= 0.0;
        let disc = if front {
            DVec2::new(q.x, q.y) / (len - q.z)
        } else {
            DVec2::new(-q.x, q.y) / (len + q.z)
        };
        let zoom = f64::from(raw.far_zoom_reversed_dual[1]);
        let uv = DVec2::new(0.5 + 0.5 * disc.x / zoom, 0.5 - 0.5 * disc.y / zoom);
        let s = m.lookup(p).unwrap();
        assert_eq!(s.layer, u32::from(!front));
        assert!((s.uv - uv).length() < 1e-6, "{} vs {uv}", s.uv);
    }

    #[test]
    fn density_is_four_times_higher_at_the_rim() {
        let m = map();
        let centre = m
            .texels_per_steradian(Vec3::new(11.0, 2.0, 3.0), 1024)
            .unwrap();
        let rim = m
            .texels_per_steradian(Vec3::new(1.0, 12.0, 3.0), 1024)
            .unwrap();
        assert!((rim / centre - 4.0).abs() < 1e-3);
        assert!((centre - 1024.0 * 1024.0 / 16.0).abs() < 1.0);
    }

    #[test]
    fn single_map_rejects_points_outside_the_cut() {
        let m = ParaboloidMap::single(
            Vec3::ZERO,
            Vec3::NEG_Z,
            0.5,
            0.1,
            10.0,
            &MapOptions::default(),
        )
        .unwrap();
        assert!(m.lookup(Vec3::new(0.0, 0.0, -5.0)).is_some());
        assert!(m.lookup(Vec3::new(0.0, 5.0, -0.1)).is_none());
        assert_eq!(m.layers(), 1);
        assert!((m.usable_disc().half_angle - 0.5).abs() < 1e-6);
    }

    #[test]
    fn bad_input_is_typed() {
        let o = MapOptions::default();
        assert_eq!(
            ParaboloidMap::dual(Vec3::ZERO, Vec3::ZERO, 0.1, 1.0, &o),
            Err(ParaboloidError::ZeroDirection)
        );
        assert!(matches!(
            ParaboloidMap::dual(Vec3::ZERO, Vec3::X, 1.0, 1.0, &o),
            Err(ParaboloidError::InvalidDepthRange { .. })
        ));
        assert_eq!(
            ParaboloidMap::single(Vec3::ZERO, Vec3::X, 2.0, 0.1, 1.0, &o),
            Err(ParaboloidError::InvalidZoom)
        );
        assert_eq!(
            ParaboloidMap::dual(Vec3::NAN, Vec3::X, 0.1, 1.0, &o),
            Err(ParaboloidError::NonFinite)
        );
        assert_eq!(
            ParaboloidMap::single(Vec3::ZERO, Vec3::X, 0.0, 0.1, 1.0, &o),
            Err(ParaboloidError::InvalidZoom)
        );
        let above = f32::from_bits(core::f32::consts::FRAC_PI_2.to_bits() + 1);
        assert_eq!(
            ParaboloidMap::single(Vec3::ZERO, Vec3::X, above, 0.1, 1.0, &o),
            Err(ParaboloidError::InvalidZoom)
        );
    }

    #[test]
    fn half_angle_pi_over_2_in_f32_is_the_whole_hemisphere() {
        // f32 pi/2 rounds above f64 pi/2; the documented range (0, pi/2] includes it.
        assert!(f64::from(core::f32::consts::FRAC_PI_2) > core::f64::consts::FRAC_PI_2);
        let m = ParaboloidMap::single(
            Vec3::ZERO,
            Vec3::NEG_Z,
            core::f32::consts::FRAC_PI_2,
            0.1,
            10.0,
            &MapOptions::default(),
        )
        .unwrap();
        assert_eq!(m.zoom, 1.0);
        assert_eq!(m.mode, ParaboloidMode::Single);
        // A direction 90 degrees off the axis lands on the rim of the texture.
        let s = m.project(Vec3::new(0.0, 5.0, 0.0), Side::Front).unwrap();
        assert!(((s.uv - DVec2::splat(0.5)).length() - 0.5).abs() < 1e-6);
    }
}
