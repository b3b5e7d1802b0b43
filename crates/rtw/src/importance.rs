use alloc::vec;
use alloc::vec::Vec;

use glam::{DMat4, DVec2, DVec3, DVec4, Vec2, Vec3};
use shadowmap_frustum::{Camera, LightDirection, ShadowTransform, math};

use crate::RtwError;
use crate::table::inverse_warp_f64;

/// Largest accepted side of an importance map.
pub const MAX_MAP_SIDE: u32 = 16384;
/// Largest accepted number of cells of an importance map (`4096²`).
pub const MAX_MAP_CELLS: usize = 1 << 24;

/// A surface point seen by the eye, for backward analysis and the oracle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "bytemuck", derive(bytemuck::Pod, bytemuck::Zeroable))]
pub struct EyeSample {
    /// World position.
    pub position: Vec3,
    /// Surface normal (need not be unit length). A zero normal means "unknown":
    /// the orientation term is then neutral, and the oracle uses the bisector of the
    /// eye and light directions (the perspective-only measure of the guide).
    pub normal: Vec3,
    /// Distance from the eye, positive.
    pub eye_distance: f32,
}

/// Knobs of backward and forward analysis.
///
/// ```text
/// importance = (reference_distance / max(d, min_distance))^distance_exponent
///            * w                                              (backward)
///            * (1 + orientation_weight * (1 - |n . l|))      (backward, normal given)
///            * edge_weight                                    (backward, on an edge)
/// ```
///
/// with `d` the eye distance (backward) or view depth (forward), `n` the unit normal,
/// `l` the unit direction toward the light and `w` the sample's homogeneous `w` in the
/// base projection: 1 for an orthographic base, the light depth for a perspective
/// one (a spot fit), whose texels grow with the distance from the light, so the
/// importance stays the texel density the sample needs in the base's `uv`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct ImportanceOptions {
    /// Distance at which the distance term is 1; positive and finite.
    pub reference_distance: f32,
    /// Distances below this are clamped to it; positive and finite.
    pub min_distance: f32,
    /// Exponent of the distance term, in `[0, 8]`.
    pub distance_exponent: f32,
    /// Weight of the orientation term, in `[0, 1e3]`: surfaces lit at grazing angles
    /// need more texels.
    pub orientation_weight: f32,
    /// Factor for samples on a shadow edge, in `[1, 1e3]`.
    pub edge_weight: f32,
}

impl Default for ImportanceOptions {
    fn default() -> Self {
        Self {
            reference_distance: 1.0,
            min_distance: 1e-3,
            distance_exponent: 1.0,
            orientation_weight: 1.0,
            edge_weight: 4.0,
        }
    }
}

impl ImportanceOptions {
    /// With this reference distance.
    #[must_use]
    pub const fn with_reference_distance(mut self, d: f32) -> Self {
        self.reference_distance = d;
        self
    }
    /// With this minimum distance.
    #[must_use]
    pub const fn with_min_distance(mut self, d: f32) -> Self {
        self.min_distance = d;
        self
    }
    /// With this distance exponent.
    #[must_use]
    pub const fn with_distance_exponent(mut self, e: f32) -> Self {
        self.distance_exponent = e;
        self
    }
    /// With this orientation weight.
    #[must_use]
    pub const fn with_orientation_weight(mut self, w: f32) -> Self {
        self.orientation_weight = w;
        self
    }
    /// With this shadow-edge factor.
    #[must_use]
    pub const fn with_edge_weight(mut self, w: f32) -> Self {
        self.edge_weight = w;
        self
    }

    /// `Ok` if every knot is in its documented range, else [`RtwError::InvalidOption`].
    ///
    /// # Errors
    /// [`RtwError::InvalidOption`].
    pub fn validate(&self) -> Result<(), RtwError> {
        let ok = self.reference_distance.is_finite()
            && self.reference_distance > 0.0
            && self.min_distance.is_finite()
            && self.min_distance > 0.0
            && (0.0..=8.0).contains(&self.distance_exponent)
            && (0.0..=1e3).contains(&self.orientation_weight)
            && (1.0..=1e3).contains(&self.edge_weight);
        if ok {
            Ok(())
        } else {
            Err(RtwError::InvalidOption)
        }
    }

    fn distance_term(&self, d: f64) -> f64 {
        let d = d.max(f64::from(self.min_distance));
        let r = f64::from(self.reference_distance) / d;
        if self.distance_exponent == 1.0 {
            r
        } else {
            math::powf(r, f64::from(self.distance_exponent))
        }
    }
}

/// What an accumulation did with its samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AccumulateStats {
    /// Samples written into a cell.
    pub accepted: usize,
    /// Samples that fell outside the base map (or behind a perspective light, or
    /// outside the eye's view in forward analysis), skipped.
    pub skipped: usize,
}

/// Where a world point falls in the base map of an importance map, for
/// [`ImportanceMap::accumulate_backward_with`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BasePoint {
    /// Base texture coordinates.
    pub uv: DVec2,
    /// World extent of one unit of base `uv` at the point, across the light's ray (any
    /// constant factor: the warp normalizes): 1 for an orthographic base, the light
    /// depth for a perspective one, `distance / sqrt(uv² per steradian)` in general.
    /// Positive and finite, else the sample is skipped.
    pub footprint: f64,
    /// Direction toward the light (need not be unit length), for the orientation
    /// term.
    pub toward_light: DVec3,
}

impl BasePoint {
    fn is_valid(&self) -> bool {
        self.uv.is_finite()
            && self.footprint.is_finite()
            && self.footprint > 0.0
            && self.toward_light.is_finite()
    }
}

/// The base projection, checked and prepared once per accumulation.
struct Base {
    uv_from_world: DMat4,
    light: LightDirection,
}

impl Base {
    fn new(base: &ShadowTransform) -> Result<Self, RtwError> {
        let m = base.uv_from_world.as_dmat4();
        if !m.is_finite() || !base.light_from_world.is_finite() {
            return Err(RtwError::NonFinite);
        }
        let light = match base.light {
            LightDirection::Directional(d) if d.is_finite() => {
                LightDirection::Directional(d.normalize_or_zero())
            }
            LightDirection::Position(p) if p.is_finite() => LightDirection::Position(p),
            _ => return Err(RtwError::NonFinite),
        };
        Ok(Self {
            uv_from_world: m,
            light,
        })
    }

    /// Texture coordinates of `p` in the base map and `w` (for the Jacobian).
    fn project(&self, p: DVec3) -> Option<(DVec2, DVec4)> {
        let h = self.uv_from_world * p.extend(1.0);
        if !(h.w > 0.0 && h.is_finite()) {
            return None;
        }
        Some((DVec2::new(h.x / h.w, h.y / h.w), h))
    }

    fn toward_light(&self, p: DVec3) -> DVec3 {
        match self.light {
            LightDirection::Directional(d) => -d.as_dvec3(),
            LightDirection::Position(l) => (l.as_dvec3() - p).normalize_or_zero(),
        }
    }

    /// `d uv / d world` at `p` (rows `du`, `dv`), given `h = M p`.
    fn jacobian(&self, h: DVec4) -> (DVec3, DVec3) {
        let m = &self.uv_from_world;
        let row = |r: usize| DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]);
        let (rx, ry, rw) = (row(0), row(1), row(3));
        let w2 = h.w * h.w;
        ((rx * h.w - rw * h.x) / w2, (ry * h.w - rw * h.y) / w2)
    }
}

/// A `width x height` grid of importance over the base light projection's texture
/// space: cell `(x, y)` covers `u in [x/W, (x+1)/W)`, `v in [y/H, (y+1)/H)` (`v` down,
/// row-major, row `y` at `y * W`).
///
/// Values are always finite and non-negative (every writer checks), so the warp
/// builder need not. Accumulation keeps the maximum per cell.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct ImportanceMap {
    width: u32,
    height: u32,
    cells: Vec<f32>,
}

impl ImportanceMap {
    /// A zeroed map; the only allocation of its life.
    ///
    /// # Errors
    /// [`RtwError::EmptyMap`] for a zero side, [`RtwError::MapTooLarge`] above
    /// [`MAX_MAP_SIDE`] or [`MAX_MAP_CELLS`].
    pub fn new(width: u32, height: u32) -> Result<Self, RtwError> {
        let len = check_size(width, height)?;
        Ok(Self {
            width,
            height,
            cells: vec![0.0; len],
        })
    }

    /// Width (cells along `u`).
    #[must_use]
    pub const fn width(&self) -> u32 {
        self.width
    }

    /// Height (cells along `v`).
    #[must_use]
    pub const fn height(&self) -> u32 {
        self.height
    }

    /// The cells, row-major.
    #[must_use]
    pub fn as_slice(&self) -> &[f32] {
        &self.cells
    }

    /// Sets every cell to zero (start of a frame).
    pub fn clear(&mut self) {
        self.cells.fill(0.0);
    }

    /// The cell at `(x, y)`, `None` outside.
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Option<f32> {
        if x < self.width && y < self.height {
            self.cells
                .get(y as usize * self.width as usize + x as usize)
                .copied()
        } else {
            None
        }
    }

    /// Sets the cell at `(x, y)`.
    ///
    /// # Errors
    /// [`RtwError::OutOfBounds`], [`RtwError::NonFinite`], [`RtwError::NegativeImportance`].
    pub fn set(&mut self, x: u32, y: u32, value: f32) -> Result<(), RtwError> {
        check_value(value)?;
        if x >= self.width || y >= self.height {
            return Err(RtwError::OutOfBounds);
        }
        let i = y as usize * self.width as usize + x as usize;
        let cell = self.cells.get_mut(i).ok_or(RtwError::OutOfBounds)?;
        *cell = value;
        Ok(())
    }

    /// Copies a whole map (for example one computed on the GPU and read back).
    /// On error the map is unchanged.
    ///
    /// # Errors
    /// [`RtwError::SizeMismatch`], [`RtwError::NonFinite`], [`RtwError::NegativeImportance`].
    pub fn copy_from_slice(&mut self, values: &[f32]) -> Result<(), RtwError> {
        if values.len() != self.cells.len() {
            return Err(RtwError::SizeMismatch {
                expected: self.cells.len(),
                got: values.len(),
            });
        }
        for &v in values {
            check_value(v)?;
        }
        self.cells.copy_from_slice(values);
        Ok(())
    }

    /// Raises the cell holding texture coordinates `uv` to at least `importance`.
    /// Returns whether `uv` was inside `[0, 1)²`.
    ///
    /// # Errors
    /// [`RtwError::NonFinite`] (for `uv` or `importance`), [`RtwError::NegativeImportance`].
    pub fn splat(&mut self, uv: Vec2, importance: f32) -> Result<bool, RtwError> {
        check_value(importance)?;
        if !uv.is_finite() {
            return Err(RtwError::NonFinite);
        }
        Ok(self.splat_f64(uv.as_dvec2(), f64::from(importance)))
    }

    fn splat_f64(&mut self, uv: DVec2, importance: f64) -> bool {
        if !(uv.x >= 0.0 && uv.x < 1.0 && uv.y >= 0.0 && uv.y < 1.0) {
            return false;
        }
        let x = ((uv.x * f64::from(self.width)) as usize).min(self.width as usize - 1);
        let y = ((uv.y * f64::from(self.height)) as usize).min(self.height as usize - 1);
        let value = importance.min(f64::from(f32::MAX)) as f32;
        if let Some(cell) = self.cells.get_mut(y * self.width as usize + x) {
            *cell = cell.max(value);
            true
        } else {
            false
        }
    }

    /// Backward analysis: every eye sample raises its base-map cell to its
    /// importance (see [`ImportanceOptions`] for the formula). With an edge mask
    /// (one flag per sample), flagged samples get the edge factor.
    ///
    /// Inputs are checked before any cell is written, so on error the map is
    /// unchanged.
    ///
    /// # Errors
    /// [`RtwError::NonFinite`] for a sample with a non-finite position, normal or
    /// distance, or a non-finite base transform; [`RtwError::SizeMismatch`] for an
    /// edge mask of another length; [`RtwError::InvalidOption`] for bad options. A
    /// negative distance is clamped to `min_distance`.
    pub fn accumulate_backward(
        &mut self,
        base: &ShadowTransform,
        samples: &[EyeSample],
        edge_mask: Option<&[bool]>,
        options: &ImportanceOptions,
    ) -> Result<AccumulateStats, RtwError> {
        options.validate()?;
        let base = Base::new(base)?;
        // Texels per unit of base `uv` the sample needs: its texels per world unit
        // times the world extent of one unit of base `uv`, which is constant for an
        // orthographic base (`w = 1`) and grows as `w` (the light depth) for a
        // perspective one.
        let project = |p: DVec3| {
            let (uv, h) = base.project(p)?;
            Some(BasePoint {
                uv,
                footprint: h.w,
                toward_light: base.toward_light(p),
            })
        };
        self.accumulate_backward_with(project, samples, edge_mask, options)
    }

    /// Backward analysis over any base mapping (a paraboloid side, a cube face, ...):
    /// `project` says where a world point falls in this map's base ([`BasePoint`]),
    /// `None` where the base does not store it. The importance of a sample is that of
    /// [`ImportanceOptions`] times the base's footprint there, so it is the density
    /// the sample needs in base `uv` whatever the base's own texel distribution.
    /// [`accumulate_backward`](Self::accumulate_backward) is this over a matrix base.
    ///
    /// # Errors
    /// As [`accumulate_backward`](Self::accumulate_backward) (a non-finite
    /// [`BasePoint`] is skipped, not an error).
    pub fn accumulate_backward_with(
        &mut self,
        project: impl Fn(DVec3) -> Option<BasePoint>,
        samples: &[EyeSample],
        edge_mask: Option<&[bool]>,
        options: &ImportanceOptions,
    ) -> Result<AccumulateStats, RtwError> {
        options.validate()?;
        if let Some(mask) = edge_mask {
            if mask.len() != samples.len() {
                return Err(RtwError::SizeMismatch {
                    expected: samples.len(),
                    got: mask.len(),
                });
            }
        }
        check_samples(samples)?;
        let mut stats = AccumulateStats::default();
        for (i, s) in samples.iter().enumerate() {
            let p = s.position.as_dvec3();
            let Some(b) = project(p).filter(BasePoint::is_valid) else {
                stats.skipped += 1;
                continue;
            };
            let mut imp = options.distance_term(f64::from(s.eye_distance)) * b.footprint;
            let n = s.normal.as_dvec3().normalize_or_zero();
            if n != DVec3::ZERO {
                let cos = n.dot(b.toward_light.normalize_or_zero()).abs().min(1.0);
                imp *= 1.0 + f64::from(options.orientation_weight) * (1.0 - cos);
            }
            if edge_mask.is_some_and(|m| m.get(i).copied().unwrap_or(false)) {
                imp *= f64::from(options.edge_weight);
            }
            if self.splat_f64(b.uv, imp) {
                stats.accepted += 1;
            } else {
                stats.skipped += 1;
            }
        }
        Ok(stats)
    }

    /// Forward analysis: every texel of the previous frame's shadow map
    /// (`depths`, `depth_width x depth_height`, row-major, rendered with
    /// `previous` and, if it was warped, with `previous_warps`) is lifted back to
    /// the world; texels the eye sees (inside the camera's clip volume) raise their
    /// cell of *this* map (over `base`) to `(reference_distance / view_depth)^exponent`.
    ///
    /// Texels holding the clear value (depth `>= 1`, or `<= 0` with reversed-Z) are
    /// empty and skipped, as are non-finite depths.
    ///
    /// # Errors
    /// [`RtwError::EmptyMap`] for a zero depth-map side; [`RtwError::SizeMismatch`]
    /// if `depths.len() != depth_width * depth_height`; [`RtwError::NonFinite`] for a
    /// non-finite or singular `previous` / `base` transform;
    /// [`RtwError::Frustum`] for an invalid camera; [`RtwError::InvalidOption`].
    pub fn accumulate_forward(
        &mut self,
        base: &ShadowTransform,
        previous: &ShadowTransform,
        previous_warps: Option<&crate::WarpMaps>,
        depths: &[f32],
        depth_width: u32,
        depth_height: u32,
        camera: &Camera,
        options: &ImportanceOptions,
    ) -> Result<AccumulateStats, RtwError> {
        options.validate()?;
        let expected = check_size(depth_width, depth_height)?;
        if depths.len() != expected {
            return Err(RtwError::SizeMismatch {
                expected,
                got: depths.len(),
            });
        }
        let base = Base::new(base)?;
        let prev = Base::new(previous)?;
        let world_from_uv = prev.uv_from_world.inverse();
        if !world_from_uv.is_finite() || prev.uv_from_world.determinant().abs() < 1e-300 {
            return Err(RtwError::NonFinite);
        }
        let clip_from_world = camera.clip_from_world()?.as_dmat4();
        let eye = camera.eye().as_dvec3();
        let forward = camera.forward().as_dvec3();
        let reversed = previous.reversed_z;
        let mut stats = AccumulateStats::default();
        let (dw, dh) = (f64::from(depth_width), f64::from(depth_height));
        for (j, row) in depths.chunks_exact(depth_width as usize).enumerate() {
            let wv = (j as f64 + 0.5) / dh;
            let v = previous_warps.map_or(wv, |w| inverse_warp_f64(w.y_table(), wv));
            for (i, &d) in row.iter().enumerate() {
                let empty = if reversed { d <= 0.0 } else { d >= 1.0 };
                if empty || !d.is_finite() {
                    stats.skipped += 1;
                    continue;
                }
                let wu = (i as f64 + 0.5) / dw;
                let u = previous_warps.map_or(wu, |w| inverse_warp_f64(w.x_table(), wu));
                let h = world_from_uv * DVec4::new(u, v, f64::from(d), 1.0);
                if h.w.is_nan() || h.w.abs() <= 1e-300 {
                    stats.skipped += 1;
                    continue;
                }
                let p = h.truncate() / h.w;
                let c = clip_from_world * p.extend(1.0);
                let seen =
                    c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w;
                let depth = (p - eye).dot(forward);
                let accepted = seen
                    && depth.is_finite()
                    && base
                        .project(p)
                        .is_some_and(|(uv, _)| self.splat_f64(uv, options.distance_term(depth)));
                if accepted {
                    stats.accepted += 1;
                } else {
                    stats.skipped += 1;
                }
            }
        }
        Ok(stats)
    }

    /// Oracle importance: each eye sample raises its cell to the exact texel density
    /// it requires, in texels per unit of base texture coordinate for a map of one
    /// texel (multiply by `1 / N` for a map of `N` texels per side):
    ///
    /// ```text
    /// J = d(base uv) / d(screen pixel)   (2x2: pixel steps carried onto the surface
    ///                                      plane along the view ray, then into uv)
    /// oracle = 1 / s_min(J)
    /// ```
    ///
    /// so that an isotropic density `rho >= oracle / N` makes every texel at most one
    /// pixel wide (aliasing error `m <= 1`). `pixels_per_radian` is the camera's focal
    /// length in pixels (`screen_height / (2 tan(fov_y / 2))` for a symmetric
    /// perspective). A zero normal uses the bisector of the eye and light directions
    /// (the perspective-only measure). Grazing samples (`|n . ray| < 1e-6`) and
    /// degenerate Jacobians are skipped.
    ///
    /// # Errors
    /// [`RtwError::NonFinite`] for non-finite samples or transform;
    /// [`RtwError::InvalidOption`] for a `pixels_per_radian` that is not positive and
    /// finite; [`RtwError::Frustum`] for an invalid camera.
    pub fn accumulate_oracle(
        &mut self,
        base: &ShadowTransform,
        camera: &Camera,
        pixels_per_radian: f32,
        samples: &[EyeSample],
    ) -> Result<AccumulateStats, RtwError> {
        self.accumulate_oracle_axis(
            OracleAxis::Isotropic,
            base,
            camera,
            pixels_per_radian,
            samples,
        )
    }

    /// Oracle importance for one texture axis of a separable warp.
    ///
    /// With `J` as in [`accumulate_oracle`](Self::accumulate_oracle), the columns of
    /// `J⁻¹` are the screen-space extents (in pixels) of one unit of base `u` and of
    /// base `v`. A separable warp scales each axis on its own, so each axis needs its
    /// own density:
    ///
    /// ```text
    /// OracleAxis::U:         |J⁻¹ e_u|   (pixels per unit u)
    /// OracleAxis::V:         |J⁻¹ e_v|   (pixels per unit v)
    /// OracleAxis::Isotropic: 1 / s_min(J) = ‖J⁻¹‖ ≥ both
    /// ```
    ///
    /// Densities `rho_u ≥ |J⁻¹ e_u| / N`, `rho_v ≥ |J⁻¹ e_v| / N` make both texel edges at
    /// most one pixel long (aliasing error `m ≤ √2`). The isotropic value asks for the
    /// larger requirement on both axes, which wastes texels on the axis that does not
    /// need them (a far ground plane needs density along the view, not across it).
    /// Feed a `U` map and a `V` map to [`WarpMaps::build_separable`](crate::WarpMaps::build_separable).
    ///
    /// # Errors
    /// As [`accumulate_oracle`](Self::accumulate_oracle).
    pub fn accumulate_oracle_axis(
        &mut self,
        axis: OracleAxis,
        base: &ShadowTransform,
        camera: &Camera,
        pixels_per_radian: f32,
        samples: &[EyeSample],
    ) -> Result<AccumulateStats, RtwError> {
        let mut stats = AccumulateStats::default();
        let skipped = oracle::oracle_needs(base, camera, pixels_per_radian, samples, |_, need| {
            let q = match axis {
                OracleAxis::Isotropic => need.isotropic,
                OracleAxis::U => need.u,
                OracleAxis::V => need.v,
            };
            if self.splat_f64(need.uv, q) {
                stats.accepted += 1;
            } else {
                stats.skipped += 1;
            }
        })?;
        stats.skipped += skipped;
        Ok(stats)
    }

    /// Raises the cell holding base coordinates `uv` to at least `importance` (a
    /// finite, non-negative value; others are ignored). Returns whether `uv` was
    /// inside `[0, 1)²` and the value was written.
    pub fn splat_need(&mut self, uv: DVec2, importance: f64) -> bool {
        uv.is_finite()
            && importance.is_finite()
            && importance >= 0.0
            && self.splat_f64(uv, importance)
    }
}

/// Which requirement [`ImportanceMap::accumulate_oracle_axis`] records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum OracleAxis {
    /// The same density on both axes: `1 / s_min(J)`.
    Isotropic,
    /// The density the `u` axis needs.
    U,
    /// The density the `v` axis needs.
    V,
}

fn check_size(width: u32, height: u32) -> Result<usize, RtwError> {
    if width == 0 || height == 0 {
        return Err(RtwError::EmptyMap);
    }
    if width > MAX_MAP_SIDE || height > MAX_MAP_SIDE {
        return Err(RtwError::MapTooLarge);
    }
    let len = width as usize * height as usize;
    if len > MAX_MAP_CELLS {
        return Err(RtwError::MapTooLarge);
    }
    Ok(len)
}

pub(crate) fn check_value(v: f32) -> Result<(), RtwError> {
    if !v.is_finite() {
        Err(RtwError::NonFinite)
    } else if v < 0.0 {
        Err(RtwError::NegativeImportance)
    } else {
        Ok(())
    }
}

fn check_samples(samples: &[EyeSample]) -> Result<(), RtwError> {
    let ok = samples
        .iter()
        .all(|s| s.position.is_finite() && s.normal.is_finite() && s.eye_distance.is_finite());
    if ok { Ok(()) } else { Err(RtwError::NonFinite) }
}

mod oracle;
#[cfg(test)]
mod tests;

pub use oracle::{AxisNeed, PixelSteps, oracle_needs, oracle_needs_of, oracle_needs_where};
