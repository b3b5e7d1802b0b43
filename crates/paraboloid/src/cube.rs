//! Cube shadow maps for point lights: six 90-degree perspective faces, the faces that
//! miss the visible receivers skipped, each kept face focused on them.

use arrayvec::ArrayVec;
use glam::{DMat4, DQuat, DVec2, DVec3, Mat4, Quat, Vec2, Vec3};
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
}

/// A face's axes in world space: its [`CubeFaceId`] axes turned by the cube's
/// orientation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FaceAxes {
    pub(crate) right: DVec3,
    pub(crate) up: DVec3,
    pub(crate) forward: DVec3,
}

impl FaceAxes {
    /// The axes of `face` of a cube turned by `orientation` (world from cube).
    pub(crate) fn new(face: CubeFaceId, orientation: DQuat) -> Self {
        let forward = orientation * face.forward().as_dvec3();
        let up = orientation * face.up().as_dvec3();
        Self {
            right: forward.cross(up),
            up,
            forward,
        }
    }

    /// `(right, up, forward)` coordinates of a light-relative world vector.
    pub(crate) fn coords(&self, q: DVec3) -> DVec3 {
        DVec3::new(q.dot(self.right), q.dot(self.up), q.dot(self.forward))
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
    /// How the cube is turned. Default [`CubeOrientation::WorldAxes`].
    pub orientation: CubeOrientation,
}

/// How [`CubeMap::fit`] turns the cube's faces.
///
/// The faces of a cube map cover every direction whatever the cube's orientation, so
/// the orientation is free, and it decides how the visible receivers fall across the
/// faces: split over several faces, each face's window a part of them and each face
/// with its own minimum size and place in the atlas; or held by one face, its window
/// centred where a perspective face samples most evenly. Neither wins everywhere:
/// world-axis faces fit the edges of axis-aligned walls and ground exactly, which a
/// turned face's window can only bound.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum CubeOrientation {
    /// Faces along the world axes ([`CubeFaceId`]), as a hardware cube map samples.
    #[default]
    WorldAxes,
    /// Turned about the world's `Y` axis (by at most 45 degrees) so that the side face
    /// nearest the visible receivers' centre, seen from the light, looks straight at
    /// it; the up and down faces stay level. Receivers spread less than 90 degrees
    /// around the light then fall in one side face (and the down or up face), where
    /// world-axis faces may split them over two or three. World axes when the centre
    /// lies straight above or below the light. The turn follows the centre
    /// continuously (a quarter turn maps the cube onto itself).
    TowardReceivers,
    /// Stood on a corner: the cube's diagonal along the world's `Y` axis, turned
    /// about it so that the lower face nearest the visible receivers' centre, seen
    /// from the light, faces it across the level (by at most 60 degrees; a third of
    /// a turn maps the cube onto itself). A light among receivers spread around it
    /// near its own height (a lamp over a street or a clearing) sees most of them
    /// near its horizon, which a level cube's side faces cut through their
    /// centres, where a face's texel covers the most solid angle (a fifth of what
    /// it covers at the face's corners); stood on a corner, the horizon crosses
    /// every face away from its centre (at most 0.54 times the solid angle of a
    /// level face's centre texel). The level frame's turn when the centre lies
    /// straight above or below the light.
    CornerUp,
    /// Of [`WorldAxes`](Self::WorldAxes) and
    /// [`TowardReceivers`](Self::TowardReceivers), the one with the smaller predicted
    /// error at the budget: the largest over the kept faces of the 95th percentile of
    /// `m` predicted from the camera and the receivers' box (as
    /// [`FaceSizes::ByNeed`] predicts it), over the face's side. Fits the faces
    /// twice and predicts twice: about 34 times the cost of either orientation alone
    /// with equal faces (322 us against 9.5 us, `cargo bench --bench paraboloid --
    /// cube_fit`), so not the default; `shadowmap::fit` measures both orientations
    /// and [`CornerUp`](Self::CornerUp) on the eye's samples instead when it has
    /// them.
    Predicted,
}

impl CubeOrientation {
    /// The turn of [`CornerUp`](Self::CornerUp) (world from cube) for the visible
    /// receivers' vertices given relative to the light, rounded to `f32` as the map
    /// stores it.
    fn turn_corner_up(relative: &[DVec3]) -> Quat {
        let stand = DQuat::from_rotation_arc(DVec3::ONE.normalize(), DVec3::Y);
        let Some(toward) = level_toward(relative) else {
            return rounded_turn(stand);
        };
        // The lower faces' normals, a third of a turn apart about the diagonal.
        let level = |v: DVec3| DVec3::new(v.x, 0.0, v.z).normalize_or_zero();
        let lower = [DVec3::NEG_X, DVec3::NEG_Y, DVec3::NEG_Z].map(|n| level(stand * n));
        let nearest = lower
            .into_iter()
            .max_by(|a, b| a.dot(toward).total_cmp(&b.dot(toward)))
            .unwrap_or(DVec3::X);
        rounded_turn(DQuat::from_rotation_arc(nearest, toward) * stand)
    }

    /// The turn of [`TowardReceivers`](Self::TowardReceivers) (world from cube) for
    /// the visible receivers' vertices given relative to the light, rounded to `f32`
    /// as the map stores it.
    fn turn_toward(relative: &[DVec3]) -> Quat {
        let Some(toward) = level_toward(relative) else {
            return Quat::IDENTITY;
        };
        let side = if toward.x.abs() >= toward.z.abs() {
            DVec3::new(toward.x.signum(), 0.0, 0.0)
        } else {
            DVec3::new(0.0, 0.0, toward.z.signum())
        };
        rounded_turn(DQuat::from_rotation_arc(side, toward))
    }
}

/// The level (XZ) unit direction from the light toward the centre of the
/// receivers' vertices `relative` to it; `None` where there are none or the
/// centre stands (nearly) straight above or below the light.
fn level_toward(relative: &[DVec3]) -> Option<DVec3> {
    if relative.is_empty() {
        return None;
    }
    let sum = relative.iter().fold(DVec3::ZERO, |a, v| a + *v);
    let scale = relative
        .iter()
        .fold(0.0_f64, |a, v| a.max(v.abs().max_element()));
    let centre = sum / relative.len() as f64;
    let level = DVec3::new(centre.x, 0.0, centre.z);
    let length = level.length();
    (length > 1e-6 * scale).then(|| level / length)
}

/// `turn` rounded to `f32` as a map stores it, or the identity where that is not
/// finite.
fn rounded_turn(turn: DQuat) -> Quat {
    let turn = turn.as_quat().normalize();
    if turn.is_finite() {
        turn
    } else {
        Quat::IDENTITY
    }
}

impl Default for CubeOptions {
    fn default() -> Self {
        Self {
            near: 0.05,
            focused: true,
            reversed_z: false,
            texel_budget: 1024 * 1024,
            sizes: FaceSizes::Equal,
            orientation: CubeOrientation::WorldAxes,
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
    /// With this orientation of the cube.
    #[must_use]
    pub const fn with_orientation(mut self, orientation: CubeOrientation) -> Self {
        self.orientation = orientation;
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
    /// Which face of the cube.
    pub face: CubeFaceId,
    /// The cube's orientation, world from cube: the face's [`CubeFaceId`] axes turned
    /// by it are its axes in world space (the same for every face of a map; see
    /// [`CubeOrientation`]).
    pub orientation: Quat,
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
    /// The face's axes in world space.
    pub(crate) fn axes(&self) -> FaceAxes {
        FaceAxes::new(self.face, self.orientation.as_dquat())
    }

    /// The face's view: light at the origin looking down `-Z` along the face.
    fn view_from_world(axes: &FaceAxes, position: DVec3) -> DMat4 {
        projection::look_to(position, axes.forward, axes.up)
    }

    fn new(
        face: CubeFaceId,
        orientation: Quat,
        position: DVec3,
        extent: &FaceExtent,
        reversed_z: bool,
    ) -> Result<Self, ParaboloidError> {
        let axes = FaceAxes::new(face, orientation.as_dquat());
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
        let clip_from_world = (clip_from_view * Self::view_from_world(&axes, position)).as_mat4();
        let near = extent.near as f32;
        let far = extent.far as f32;
        check_depth_range(near, far)?;
        let det = clip_from_world.as_dmat4().determinant();
        if !clip_from_world.is_finite() || !det.is_finite() || det == 0.0 {
            return Err(ParaboloidError::NonFinite);
        }
        Ok(Self {
            face,
            orientation,
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
        let c = self.axes().coords(relative);
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
        let frame = FrameGeometry {
            position,
            relative: &relative,
            casters: casters.as_ref(),
            near: effective_near(options.near, range, position),
            range: f64::from(range),
        };
        let turned = CubeOrientation::turn_toward(&relative);
        let orientation = match options.orientation {
            CubeOrientation::WorldAxes => Quat::IDENTITY,
            CubeOrientation::TowardReceivers | CubeOrientation::Predicted => turned,
            CubeOrientation::CornerUp => CubeOrientation::turn_corner_up(&relative),
        };
        let mut cube = frame.cube(orientation, options)?;
        let predict = options.orientation == CubeOrientation::Predicted && turned != Quat::IDENTITY;
        let error = cube.share_budget(camera, &scene.receivers, options, predict);
        if predict {
            let mut world = frame.cube(Quat::IDENTITY, options)?;
            let world_error = world.share_budget(camera, &scene.receivers, options, true);
            // Turned only where the prediction says it is better.
            if !matches!((error, world_error), (Some(t), Some(w)) if t < w) {
                cube = world;
            }
        }
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
        let narrowed = CubeFace::new(f.face, f.orientation, position, &extent, reversed_z)?;
        *f = CubeFace {
            size: f.size,
            offset: f.offset,
            ..narrowed
        };
        Ok(())
    }

    /// The cube's orientation, world from cube (its faces share it; see
    /// [`CubeOrientation`]).
    #[must_use]
    pub fn orientation(&self) -> Quat {
        self.faces.first().map_or(Quat::IDENTITY, |f| f.orientation)
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
        let view = CubeFace::view_from_world(&f.axes(), self.position.as_dvec3()).as_mat4();
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

/// What [`CubeMap::fit`] fits the faces of one orientation to.
struct FrameGeometry<'a> {
    position: Vec3,
    /// The visible receivers' vertices relative to the light.
    relative: &'a [DVec3],
    /// The casters in range.
    casters: Option<&'a Aabb>,
    /// The smallest near plane ([`effective_near`]).
    near: f64,
    range: f64,
}

impl FrameGeometry<'_> {
    /// The kept faces of a cube turned by `orientation` (world from cube), not yet
    /// sized.
    fn cube(&self, orientation: Quat, options: &CubeOptions) -> Result<CubeMap, ParaboloidError> {
        let light_at = self.position.as_dvec3();
        let mut faces = ArrayVec::new();
        for face in CubeFaceId::ALL {
            let axes = FaceAxes::new(face, orientation.as_dquat());
            let Some(mut extent) = face_extent(self.relative, &axes, self.near) else {
                continue;
            };
            extent.choose_depth(
                options.focused,
                orientation != Quat::IDENTITY,
                self.near,
                self.range,
                self.casters.map(|c| (c, light_at, &axes)),
                MIN_TAN_EXTENT,
            );
            let kept = CubeFace::new(face, orientation, light_at, &extent, options.reversed_z)?;
            faces.push(kept);
        }
        if faces.is_empty() {
            return Err(FrustumError::SliceOutsideScene.into());
        }
        Ok(CubeMap {
            position: self.position,
            faces,
            reversed_z: options.reversed_z,
            atlas: [0, 0],
        })
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
        let major = CubeFaceId::major(self.orientation().as_dquat().inverse() * q);
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
        orientation: super::CubeOrientation,
    }

    shadowmap_frustum::__deserialize_checked!(
        /// Checked as [`CubeMap::fit`](super::CubeMap::fit) checks it.
        CubeOptions,
        CubeOptionsDef,
        |options| options.validate()
    );
}

#[cfg(test)]
pub(crate) mod tests;
