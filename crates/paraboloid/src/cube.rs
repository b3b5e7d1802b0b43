//! Cube shadow maps for point lights: six 90-degree perspective faces, the faces that
//! miss the visible receivers skipped, each kept face focused on them.

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3, Mat4, Vec2, Vec3};
use shadowmap_frustum::{
    Aabb, Camera, ConvexBody, DepthBounds, FrustumError, Light, LightDirection, SceneBounds,
    ShadowMapping, ShadowSample, ShadowTransform, projection,
};

use crate::ParaboloidError;
use crate::cube_fit::{FaceExtent, effective_near, face_extent};
use crate::cube_sizes::FaceSizes;
use crate::map::check_depth_range;

/// One face of a cube map: the direction it looks along, world axis aligned.
///
/// Each face is a camera at the light looking along [`forward`](Self::forward) with
/// [`up`](Self::up) as its up vector (right-handed, looking down its own `-Z`); its
/// right vector is `forward × up`:
///
/// | face | forward | up | right |
/// |---|---|---|---|
/// | `PosX` | `+X` | `+Y` | `+Z` |
/// | `NegX` | `-X` | `+Y` | `-Z` |
/// | `PosY` | `+Y` | `+Z` | `+X` |
/// | `NegY` | `-Y` | `+Z` | `-X` |
/// | `PosZ` | `+Z` | `+Y` | `-X` |
/// | `NegZ` | `-Z` | `+Y` | `+X` |
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum CubeFaceId {
    /// Looks along `+X`.
    PosX,
    /// Looks along `-X`.
    NegX,
    /// Looks along `+Y`.
    PosY,
    /// Looks along `-Y`.
    NegY,
    /// Looks along `+Z`.
    PosZ,
    /// Looks along `-Z`.
    NegZ,
}

impl CubeFaceId {
    /// The six faces in layer order (a kept face's layer is its rank among the kept
    /// faces in this order).
    pub const ALL: [Self; 6] = [
        Self::PosX,
        Self::NegX,
        Self::PosY,
        Self::NegY,
        Self::PosZ,
        Self::NegZ,
    ];

    /// The unit direction the face looks along.
    #[must_use]
    pub const fn forward(self) -> Vec3 {
        match self {
            Self::PosX => Vec3::X,
            Self::NegX => Vec3::NEG_X,
            Self::PosY => Vec3::Y,
            Self::NegY => Vec3::NEG_Y,
            Self::PosZ => Vec3::Z,
            Self::NegZ => Vec3::NEG_Z,
        }
    }

    /// The face's up vector.
    #[must_use]
    pub const fn up(self) -> Vec3 {
        match self {
            Self::PosY | Self::NegY => Vec3::Z,
            _ => Vec3::Y,
        }
    }

    /// The face's right vector, `forward × up`.
    #[must_use]
    pub fn right(self) -> Vec3 {
        self.forward().cross(self.up())
    }

    /// The face whose pyramid holds direction `d`: its largest component by magnitude
    /// (ties go to the earlier face of [`ALL`](Self::ALL)); `PosX` for a zero or NaN
    /// direction.
    #[must_use]
    pub fn major(d: DVec3) -> Self {
        let a = d.abs();
        if a.x >= a.y && a.x >= a.z {
            if d.x < 0.0 { Self::NegX } else { Self::PosX }
        } else if a.y >= a.z {
            if d.y < 0.0 { Self::NegY } else { Self::PosY }
        } else if d.z < 0.0 {
            Self::NegZ
        } else {
            Self::PosZ
        }
    }

    /// `(right, up, forward)` coordinates of a light-relative vector.
    pub(crate) fn coords(self, q: DVec3) -> DVec3 {
        let f = self.forward().as_dvec3();
        let u = self.up().as_dvec3();
        DVec3::new(q.dot(f.cross(u)), q.dot(u), q.dot(f))
    }
}

/// Knobs of [`CubeMap::fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct CubeOptions {
    /// Smallest distance along a face's axis that is stored (the unfocused faces'
    /// near plane, the focused faces' lower limit). Default 0.05, as
    /// [`IpsmOptions`](crate::IpsmOptions).
    pub near: f32,
    /// Tighten each kept face to the visible receivers (and its depth range to the
    /// casters and receivers). `false`: every kept face spans its full 90 degrees
    /// over `[near, range]`. Default `true`.
    pub focused: bool,
    /// Store depth as 1 at the near plane and 0 at the far plane. Default `false`.
    pub reversed_z: bool,
    /// Texels over all kept faces (the whole atlas), at least 1. Default `1024²`.
    /// `shadowmap::fit` sets it from its input's budget.
    pub texel_budget: u64,
    /// How the kept faces share the budget. Default [`FaceSizes::Equal`] (what
    /// engines render: a texture array of equal layers). The `shadowmap-wgpu` pass
    /// renders both, faces sized by need in the corners of layers of the largest
    /// face's side ([`CubeFace::clip_from_world_in_layer`]).
    pub sizes: FaceSizes,
}

impl Default for CubeOptions {
    fn default() -> Self {
        Self {
            near: 0.05,
            focused: true,
            reversed_z: false,
            texel_budget: 1024 * 1024,
            sizes: FaceSizes::Equal,
        }
    }
}

impl CubeOptions {
    /// With this near distance.
    #[must_use]
    pub const fn with_near(mut self, near: f32) -> Self {
        self.near = near;
        self
    }
    /// Focused (`true`) or full 90-degree faces.
    #[must_use]
    pub const fn with_focused(mut self, focused: bool) -> Self {
        self.focused = focused;
        self
    }
    /// With reversed-Z depth.
    #[must_use]
    pub const fn with_reversed_z(mut self, reversed_z: bool) -> Self {
        self.reversed_z = reversed_z;
        self
    }
    /// With this many texels over all faces.
    #[must_use]
    pub const fn with_texel_budget(mut self, texels: u64) -> Self {
        self.texel_budget = texels;
        self
    }
    /// With this sharing of the budget.
    #[must_use]
    pub const fn with_sizes(mut self, sizes: FaceSizes) -> Self {
        self.sizes = sizes;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), ParaboloidError> {
        if !self.near.is_finite() {
            Err(ParaboloidError::NonFinite)
        } else if self.near > 0.0 && self.texel_budget > 0 {
            Ok(())
        } else {
            Err(ParaboloidError::InvalidOptions)
        }
    }
}

/// One kept face of a [`CubeMap`]: an off-centre perspective inside the face's
/// 90-degree pyramid.
///
/// The window is given by tangents: a light-relative point with face coordinates
/// `(a, b, d)` ([`CubeFaceId`]: right, up, forward) projects to `(a / d, b / d)`,
/// and the face stores `tan_min <= (a / d, b / d) <= tan_max` (inside `[-1, 1]²`,
/// the whole face).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CubeFace {
    /// Which face.
    pub face: CubeFaceId,
    /// Depth pass, WebGPU clip space (perspective: divide by `w`).
    pub clip_from_world: Mat4,
    /// Lower-left corner of the window, in tangents.
    pub tan_min: Vec2,
    /// Upper-right corner of the window, in tangents.
    pub tan_max: Vec2,
    /// Distance along the face's axis mapped to depth 0 (1 with reversed-Z).
    pub near: f32,
    /// Distance along the face's axis mapped to depth 1 (0 with reversed-Z).
    pub far: f32,
    /// Width and height in texels of the face's map (square unless a warp asked for
    /// more texels along one axis, see [`CubeMap::set_sizes_by_need`]).
    pub size: [u32; 2],
    /// Texel offset of the face's map in the cube's atlas ([`CubeMap::atlas`]).
    pub offset: [u32; 2],
}

impl CubeFace {
    /// The face's view: light at the origin looking down `-Z` along the face.
    fn view_from_world(face: CubeFaceId, position: DVec3) -> DMat4 {
        projection::look_to(position, face.forward().as_dvec3(), face.up().as_dvec3())
    }

    fn new(
        face: CubeFaceId,
        position: DVec3,
        extent: &FaceExtent,
        reversed_z: bool,
    ) -> Result<Self, ParaboloidError> {
        let (lo, hi) = (extent.tan_min, extent.tan_max);
        let clip_from_view = projection::perspective_off_center(
            lo.x,
            hi.x,
            lo.y,
            hi.y,
            extent.near,
            extent.far,
            reversed_z,
        );
        let clip_from_world = (clip_from_view * Self::view_from_world(face, position)).as_mat4();
        let near = extent.near as f32;
        let far = extent.far as f32;
        check_depth_range(near, far)?;
        let det = clip_from_world.as_dmat4().determinant();
        if !clip_from_world.is_finite() || !det.is_finite() || det == 0.0 {
            return Err(ParaboloidError::NonFinite);
        }
        Ok(Self {
            face,
            clip_from_world,
            tan_min: lo.as_vec2(),
            tan_max: hi.as_vec2(),
            near,
            far,
            size: [0, 0],
            offset: [0, 0],
        })
    }

    /// The sample of a light-relative point on this face (any layer number), `None`
    /// when it lies behind the light's plane or outside the window.
    ///
    /// ```text
    /// (a, b, d) = face coordinates of P - L          s = (a / d, b / d)
    /// ndc = (2 s - (tan_min + tan_max)) / (tan_max - tan_min)
    /// uv = (1/2 + ndc.x / 2, 1/2 - ndc.y / 2)
    /// depth = far (d - near) / ((far - near) d)       (1 - that with reversed-Z)
    /// ```
    #[must_use]
    pub fn sample(&self, relative: DVec3, reversed_z: bool, layer: u32) -> Option<ShadowSample> {
        let c = self.face.coords(relative);
        if !(c.z > 0.0) {
            return None;
        }
        let s = DVec2::new(c.x, c.y) / c.z;
        let (lo, hi) = (self.tan_min.as_dvec2(), self.tan_max.as_dvec2());
        let ndc = (2.0 * s - (lo + hi)) / (hi - lo);
        let uv = DVec2::new(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
        let inside = (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y);
        let (n, f) = (f64::from(self.near), f64::from(self.far));
        let depth = f * (c.z - n) / ((f - n) * c.z);
        let depth = if reversed_z { 1.0 - depth } else { depth };
        (inside && depth.is_finite()).then_some(ShadowSample { uv, depth, layer })
    }
}

/// A cube shadow map around a point light: the kept faces, one texture-array layer
/// each, in [`CubeFaceId::ALL`] order.
///
/// Built by [`CubeMap::fit`] from the visible receivers: the view frustum (truncated
/// by measured depth bounds) ∩ the receiver box ∩ the box of the light's range. A
/// face whose pyramid misses them is skipped; a focused face's window is the
/// bounding rectangle of their projection onto it, its near plane pulled back to
/// the casters and its far plane at the farthest receiver.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct CubeMap {
    /// Light position in world space.
    pub position: Vec3,
    /// The kept faces; face `i` is layer `i` of [`ShadowMapping::map_point`]'s samples.
    pub faces: ArrayVec<CubeFace, 6>,
    /// Whether depth is reversed.
    pub reversed_z: bool,
    /// Width and height in texels of the atlas holding every face's map (a column
    /// of equal tiles with [`FaceSizes::Equal`]); its area is what the map costs.
    pub atlas: [u32; 2],
}

/// Smallest extent of a window, in tangents: a window spans at least
/// `1e-3` (0.06 degrees at the face centre), so that `f32` resolves its texels.
const MIN_TAN_EXTENT: f64 = 1e-3;

impl CubeMap {
    /// Fits the cube map of a point light (or a spot light's position and range) to
    /// the frame.
    ///
    /// The visible receivers are `slice ∩ scene.receivers ∩ range box`, where `slice`
    /// is the camera frustum between the depth bounds (clamped as
    /// [`DepthBounds::clamped_to`]; the camera's range without them) and the range box
    /// the cube `position ± range` around the light. The face near planes
    /// are at least `options.near` (a receiver closer than that along a face axis is
    /// not stored, as with any near plane); documented fallback: at least `2^-17`
    /// times the larger of `range` and the light's largest coordinate, so that the
    /// `f32` depth row stays regular and resolves the range.
    ///
    /// # Errors
    /// [`ParaboloidError::NonFinite`] for a NaN or infinite light or option,
    /// [`ParaboloidError::InvalidOptions`] for `options.near <= 0`,
    /// [`ParaboloidError::InvalidDepthRange`] unless `options.near < range` (and
    /// resolvable in `f32`), [`ParaboloidError::UnsupportedLight`] for a directional
    /// light, [`ParaboloidError::Frustum`] for the camera's or the scene's errors
    /// ([`FrustumError::SliceOutsideScene`] when no visible receiver is in range:
    /// nothing to shadow).
    pub fn fit(
        light: &Light,
        camera: &Camera,
        bounds: Option<DepthBounds>,
        scene: &SceneBounds,
        options: &CubeOptions,
    ) -> Result<Self, ParaboloidError> {
        let (position, range) = match *light {
            Light::Point { position, range }
            | Light::Spot {
                position, range, ..
            } => (position, range),
            Light::Directional { .. } => return Err(ParaboloidError::UnsupportedLight),
        };
        options.validate()?;
        if !position.is_finite() {
            return Err(ParaboloidError::NonFinite);
        }
        check_depth_range(options.near, range)?;
        let body = visible_receivers(camera, bounds, scene, position, range)?;
        let light_at = position.as_dvec3();
        let mut relative: ArrayVec<DVec3, { shadowmap_frustum::MAX_BODY_VERTICES }> =
            ArrayVec::new();
        relative.extend(body.vertices().iter().map(|v| v.as_dvec3() - light_at));
        let casters = scene
            .casters
            .validate()?
            .intersection(&range_box(position, range)?);
        let near = effective_near(options.near, range, position);
        let mut faces = ArrayVec::new();
        for face in CubeFaceId::ALL {
            let Some(mut extent) = face_extent(&relative, face, near) else {
                continue;
            };
            extent.choose_depth(
                options.focused,
                near,
                f64::from(range),
                casters.as_ref().map(|c| (c, light_at, face)),
                MIN_TAN_EXTENT,
            );
            faces.push(CubeFace::new(face, light_at, &extent, options.reversed_z)?);
        }
        if faces.is_empty() {
            return Err(FrustumError::SliceOutsideScene.into());
        }
        let mut cube = Self {
            position,
            faces,
            reversed_z: options.reversed_z,
            atlas: [0, 0],
        };
        cube.share_budget(camera, &scene.receivers, options);
        Ok(cube)
    }

    /// Narrows the window of the face in `layer` to the part of it between texture
    /// coordinates `uv_min` and `uv_max` (a rectangle of its current `uv`, `v` down;
    /// clamped to `[0, 1]²`, at least `1e-3` wide in tangents), keeping its depth
    /// range, size and place in the atlas: for a renderer that knows which part of a
    /// face its visible samples use (sample distribution focusing). Nothing changes
    /// for a layer past the last or an empty or non-finite rectangle.
    ///
    /// # Errors
    /// [`ParaboloidError::NonFinite`] when the narrowed face's matrix is not finite
    /// (the face is then unchanged).
    pub fn narrow_to_uv(
        &mut self,
        layer: u32,
        uv_min: DVec2,
        uv_max: DVec2,
    ) -> Result<(), ParaboloidError> {
        let position = self.position.as_dvec3();
        let reversed_z = self.reversed_z;
        let Some(f) = self.faces.get_mut(layer as usize) else {
            return Ok(());
        };
        let (lo, hi) = (
            uv_min.clamp(DVec2::ZERO, DVec2::ONE),
            uv_max.clamp(DVec2::ZERO, DVec2::ONE),
        );
        if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
            return Ok(());
        }
        let (t_lo, t_hi) = (f.tan_min.as_dvec2(), f.tan_max.as_dvec2());
        let at = |uv: DVec2| t_lo + DVec2::new(uv.x, 1.0 - uv.y) * (t_hi - t_lo);
        let (a, b) = (at(lo), at(hi));
        let (mut tan_min, mut tan_max) = (a.min(b), a.max(b));
        let grow = (DVec2::splat(MIN_TAN_EXTENT) - (tan_max - tan_min)).max(DVec2::ZERO) * 0.5;
        tan_min -= grow;
        tan_max += grow;
        let extent = FaceExtent {
            tan_min,
            tan_max,
            receivers_min: f64::from(f.near),
            receivers_max: f64::from(f.far),
            near: f64::from(f.near),
            far: f64::from(f.far),
        };
        let narrowed = CubeFace::new(f.face, position, &extent, reversed_z)?;
        *f = CubeFace {
            size: f.size,
            offset: f.offset,
            ..narrowed
        };
        Ok(())
    }

    /// Number of texture-array layers (kept faces), 1 to 6.
    #[must_use]
    pub fn layers(&self) -> u32 {
        self.faces.len() as u32
    }

    /// The matrices of the face in `layer` for a matrix depth pass and lookup
    /// (`light_from_world` is the face's view, looking down its `-Z`); `None` past the
    /// last layer.
    #[must_use]
    pub fn transform(&self, layer: u32) -> Option<ShadowTransform> {
        let f = self.faces.get(layer as usize)?;
        let view = CubeFace::view_from_world(f.face, self.position.as_dvec3()).as_mat4();
        let light = LightDirection::Position(self.position);
        Some(ShadowTransform::new(
            view,
            f.clip_from_world,
            self.reversed_z,
            light,
        ))
    }

    /// The layer of a face, `None` when the face was skipped.
    #[must_use]
    pub fn layer_of(&self, face: CubeFaceId) -> Option<u32> {
        self.faces
            .iter()
            .position(|f| f.face == face)
            .map(|i| i as u32)
    }
}

/// The visible receivers as a convex body (see [`CubeMap::fit`]).
fn visible_receivers(
    camera: &Camera,
    bounds: Option<DepthBounds>,
    scene: &SceneBounds,
    position: Vec3,
    range: f32,
) -> Result<ConvexBody, ParaboloidError> {
    let (near, far) = match bounds {
        Some(b) => b.clamped_to(camera)?,
        None => camera.depth_range()?,
    };
    let slice = camera.slice(near, far)?;
    let receivers = scene.receivers.validate()?;
    let in_range = receivers
        .intersection(&range_box(position, range)?)
        .ok_or(FrustumError::SliceOutsideScene)?;
    let body = ConvexBody::from_frustum_aabb(&slice, &in_range)?;
    if body.is_empty() {
        return Err(FrustumError::SliceOutsideScene.into());
    }
    Ok(body)
}

/// The box `position ± range`.
fn range_box(position: Vec3, range: f32) -> Result<Aabb, ParaboloidError> {
    let b = Aabb::from_center_half_extents(position, Vec3::splat(range));
    if b.is_finite() {
        Ok(b)
    } else {
        Err(ParaboloidError::NonFinite)
    }
}

impl ShadowMapping for CubeMap {
    /// The kept face whose window holds the point: the major-axis face first, then
    /// the others in layer order (a focused window may reach past its pyramid's
    /// edge only by rounding, so this is the major-axis face for every point not on
    /// a face boundary); `None` when no kept face holds it.
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let q = world - self.position.as_dvec3();
        let major = CubeFaceId::major(q);
        let first = self.layer_of(major);
        let at = |layer: u32| {
            self.faces
                .get(layer as usize)
                .and_then(|f| f.sample(q, self.reversed_z, layer))
        };
        if let Some(s) = first.and_then(at) {
            return Some(s);
        }
        (0..self.layers())
            .filter(|l| Some(*l) != first)
            .find_map(at)
    }
}

#[cfg(feature = "serde")]
mod serde_impls {
    use serde::Deserialize;

    use super::CubeOptions;

    #[derive(Deserialize)]
    #[serde(remote = "CubeOptions", default = "CubeOptions::default")]
    struct CubeOptionsDef {
        near: f32,
        focused: bool,
        reversed_z: bool,
        texel_budget: u64,
        sizes: crate::FaceSizes,
    }

    shadowmap_frustum::__deserialize_checked!(
        /// Checked as [`CubeMap::fit`](super::CubeMap::fit) checks it.
        CubeOptions,
        CubeOptionsDef,
        |options| options.validate()
    );
}

#[cfg(test)]
pub(crate) mod tests {
    use glam::Vec4;
    use shadowmap_frustum::Projection;

    use super::*;

    /// A street under a lamp ahead of the eye (five faces kept); shared with the
    /// tiled cube map's tests.
    pub(crate) fn street() -> (Camera, Light, SceneBounds) {
        let camera = Camera::look_to(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(0.0, -0.2, -1.0),
            Vec3::Y,
            Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
        )
        .unwrap();
        let light = Light::Point {
            position: Vec3::new(5.0, 6.0, -30.0),
            range: 200.0,
        };
        let ground = Aabb::new(Vec3::new(-150.0, 0.0, -320.0), Vec3::new(150.0, 1.0, 20.0));
        let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 30.0 * Vec3::Y));
        (camera, light, scene)
    }

    /// The depth pass (the `f32` clip matrix, divided by `w`) puts a point where the
    /// lookup does, for both depth conventions.
    #[test]
    fn clip_matrix_agrees_with_the_lookup() {
        let (camera, light, scene) = street();
        for reversed in [false, true] {
            let options = CubeOptions::default().with_reversed_z(reversed);
            let cube = CubeMap::fit(&light, &camera, None, &scene, &options).unwrap();
            let mut checked = 0;
            for x in [-40.0, -5.0, 0.0, 7.0, 30.0] {
                for z in [-200.0, -60.0, -31.0, -29.0, -10.0] {
                    let p = Vec3::new(x, 0.5, z);
                    let Some(s) = cube.map_point(p.as_dvec3()) else {
                        continue;
                    };
                    let face = &cube.faces[s.layer as usize];
                    let c = face.clip_from_world * Vec4::new(p.x, p.y, p.z, 1.0);
                    let ndc = c.truncate() / c.w;
                    let uv = DVec2::new(0.5 + 0.5 * f64::from(ndc.x), 0.5 - 0.5 * f64::from(ndc.y));
                    assert!(
                        (uv - s.uv).abs().max_element() < 1e-5,
                        "{p}: {uv} {:?}",
                        s.uv
                    );
                    assert!(
                        (f64::from(ndc.z) - s.depth).abs() < 1e-5,
                        "{p}: {} {}",
                        ndc.z,
                        s.depth
                    );
                    checked += 1;
                }
            }
            assert!(checked >= 20, "{checked}");
        }
    }

    /// Focused windows lie in the face and the unfocused map keeps the same faces;
    /// the up face, seeing nothing visible, is skipped by both.
    #[test]
    fn focused_windows_are_inside_the_same_faces() {
        let (camera, light, scene) = street();
        let focused = CubeMap::fit(&light, &camera, None, &scene, &CubeOptions::default()).unwrap();
        let options = CubeOptions::default().with_focused(false);
        let full = CubeMap::fit(&light, &camera, None, &scene, &options).unwrap();
        let ids = |c: &CubeMap| c.faces.iter().map(|f| f.face).collect::<Vec<_>>();
        assert_eq!(ids(&focused), ids(&full));
        assert_eq!(focused.layer_of(CubeFaceId::PosY), None);
        for (f, u) in focused.faces.iter().zip(&full.faces) {
            assert!(
                f.tan_min.cmpge(u.tan_min - 1e-4).all() && f.tan_max.cmple(u.tan_max + 1e-4).all()
            );
            assert!(f.near >= u.near && f.far <= u.far);
        }
        // The face looking away from the view (+Z, behind the camera) sees less.
        let area = |f: &CubeFace| (f.tan_max - f.tan_min).element_product();
        assert!(focused.faces.iter().any(|f| area(f) < 2.0));
    }

    /// Equal sides make a column of layers; sides by need give the face toward the
    /// eye's near ground (the light's `+Z` face, the camera being behind it along
    /// `+Z`) the most texels; both stay within the budget, their tiles apart, and a
    /// sample lands in its face's tile of the atlas.
    #[test]
    fn faces_share_the_budget() {
        let (camera, light, scene) = street();
        let budget = 512 * 512;
        let equal = CubeOptions::default()
            .with_texel_budget(budget)
            .with_sizes(FaceSizes::Equal);
        let cube = CubeMap::fit(&light, &camera, None, &scene, &equal).unwrap();
        assert!(cube.has_equal_faces());
        let [side, _] = cube.faces[0].size;
        assert_eq!(cube.atlas, [side, side * cube.layers()]);
        let by_need = equal.with_sizes(FaceSizes::ByNeed);
        let cube = CubeMap::fit(&light, &camera, None, &scene, &by_need).unwrap();
        assert!(!cube.has_equal_faces());
        assert!(
            cube.texels() <= budget && cube.texels() > budget / 2,
            "{}",
            cube.texels()
        );
        assert!(cube.faces.iter().all(|f| f.size[0] == f.size[1]));
        let largest = cube.faces.iter().max_by_key(|f| f.size[0]).unwrap();
        assert_eq!(largest.face, CubeFaceId::PosZ, "{:?}", cube.faces);
        let p = DVec3::new(1.0, 0.5, -10.0);
        let s = cube.map_point(p).unwrap();
        let a = cube.atlas_sample(s).unwrap();
        let f = &cube.faces[s.layer as usize];
        let pair = |p: [u32; 2]| DVec2::new(f64::from(p[0]), f64::from(p[1]));
        let texel = a.uv * pair(cube.atlas);
        let lo = pair(f.offset);
        assert!(texel.cmpge(lo).all() && texel.cmple(lo + pair(f.size)).all());
        assert_eq!((a.layer, a.depth), (0, s.depth));
    }

    /// A face drawn into the corner of a layer of the largest face's side lands
    /// where its own `uv`, scaled by its share of the layer, says: the corner
    /// clip matrix and the scaled lookup agree, and the face keeps its texels.
    #[test]
    fn faces_drawn_into_layer_corners_keep_their_uv() {
        let (camera, light, scene) = street();
        let by_need = CubeOptions::default().with_sizes(FaceSizes::ByNeed);
        let cube = CubeMap::fit(&light, &camera, None, &scene, &by_need).unwrap();
        let side = cube.largest_side();
        for f in &cube.faces {
            let texels = f.uv_scale_in_layer(side).as_dvec2() * f64::from(side);
            let size = DVec2::new(f64::from(f.size[0]), f64::from(f.size[1]));
            assert!(
                (texels - size).abs().max_element() < 1e-3,
                "{texels} {size}"
            );
        }
        let mut checked = 0;
        for x in [-40.0, -5.0, 0.0, 7.0, 30.0] {
            for z in [-200.0, -60.0, -31.0, -29.0, -10.0] {
                let p = DVec3::new(x, 0.5, z);
                let Some(s) = cube.map_point(p) else {
                    continue;
                };
                let face = &cube.faces[s.layer as usize];
                let c = face.clip_from_world_in_layer(side).as_dmat4() * p.extend(1.0);
                let ndc = c.truncate() / c.w;
                let uv = DVec2::new(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
                let scaled = s.uv * face.uv_scale_in_layer(side).as_dvec2();
                assert!(
                    (uv - scaled).abs().max_element() < 1e-5,
                    "{p}: {uv} {scaled}"
                );
                checked += 1;
            }
        }
        assert!(checked >= 20, "{checked}");
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let (camera, light, scene) = street();
        let o = CubeOptions::default();
        let sun = Light::Directional {
            direction: Vec3::NEG_Y,
        };
        assert_eq!(
            CubeMap::fit(&sun, &camera, None, &scene, &o),
            Err(ParaboloidError::UnsupportedLight)
        );
        let nan = Light::Point {
            position: Vec3::NAN,
            range: 10.0,
        };
        assert_eq!(
            CubeMap::fit(&nan, &camera, None, &scene, &o),
            Err(ParaboloidError::NonFinite)
        );
        for bad in [o.with_near(0.0), o.with_texel_budget(0)] {
            assert_eq!(
                CubeMap::fit(&light, &camera, None, &scene, &bad),
                Err(ParaboloidError::InvalidOptions)
            );
        }
        let short = Light::Point {
            position: Vec3::new(0.0, 100.0, 300.0),
            range: 1.0,
        };
        assert_eq!(
            CubeMap::fit(&short, &camera, None, &scene, &o),
            Err(ParaboloidError::Frustum(FrustumError::SliceOutsideScene))
        );
        let tiny = Light::Point {
            position: Vec3::ZERO,
            range: 0.01,
        };
        assert!(matches!(
            CubeMap::fit(&tiny, &camera, None, &scene, &o),
            Err(ParaboloidError::InvalidDepthRange { .. })
        ));
    }
}
