//! Aliasing metrics, per visible pixel, in `f64`.
//!
//! For a visible surface point `p` seen through pixel `x`, let `u(p)` be a technique's
//! full mapping to shadow-map texels (matrices, cascade choice, paraboloid, RTW warp;
//! `texel = uv * resolution` of the layer that stores `p`). The Jacobian
//!
//! ```text
//! J = d texel / d pixel      (2x2, texels per screen pixel)
//! ```
//!
//! is taken through the tangent plane of the visible surface: the pixel position is
//! moved by `±h` (`h` = [`JACOBIAN_STEP_PIXELS`]) along x and y, the ray through the
//! moved position is intersected with the plane through `p` with normal `n`
//! (analytic from the camera), and the intersections are mapped with
//! [`ShadowMapping::map_point`]; central differences in `f64` give the columns of
//! `J` (one-sided when a neighbour lands on another layer, e.g. across a cascade
//! border). With the singular values `s1 >= s2` of `J`:
//!
//! ```text
//! m        = 1 / s2                   largest extent of one texel, in pixels (1 ideal)
//! m_u, m_v = |J^-1 e_u|, |J^-1 e_v|   extent of one texel step along u / v, in pixels
//! m_persp  = m with n replaced by the bisector of the eye and light directions
//! S        = (texels / visible pixels) * max(m)^2
//! S_sep    = (texels / visible pixels) * max(m_u) * max(m_v)   (Lloyd et al.)
//! ```
//!
//! `S` is the number of texels (per visible pixel) a map with this parameterization
//! needs so that no texel is larger than a pixel, when the map is scaled by the same
//! factor along both axes. Lloyd, Tuft, Yoon and Manocha (*Warping and Partitioning
//! for Low Error Shadow Maps*, EGSR 2006) scale each axis of a separable
//! parameterization on its own, which gives `S_sep <= S` (`m >= max(m_u, m_v)`);
//! their closed forms are `S_sep` of the perspective-only error along the view
//! direction from `n` to `f` ([`frustum_samples`] with one ray through the image
//! centre, [`frustum_storage_factor`]; `tests/golden.rs` reproduces them to about
//! 1e-5, 0.6% for the cascades):
//!
//! ```text
//! K = 1 / (2 tan(fovY / 2))
//! uniform   S_sep = K (f - n) f / n^2
//! LiSPSM    S_sep = K (f - n) / n            (overhead light, n_opt)
//! 4 log-split cascades with LiSPSM:
//!           S_sep = 4 K ((f / n)^(1/4) - 1)  (each cascade scaled on its own)
//! log bound S_sep = K ln(f / n)              (best separable parameterization)
//! ```
//!
//! Derivation (overhead light, horizontal view, a point at view depth `z` with the
//! bisector normal, so that one pixel step carries the point `z / f_px` across the
//! light's rays, `f_px = K * H` pixels per radian): a uniform map of `R_v` texels over
//! the depth extent `f - n` and `R_u` texels over the far plane's width
//! `2 f tan(fovX/2)` has `m_v = K H (f - n) / (R_v z)` and `m_u = W f / (R_u z)`, both
//! largest at `z = n`; `S_sep = R_u R_v m_u(n) m_v(n) / (W H) = K (f - n) f / n^2`.
//! LiSPSM's `n_opt = n + sqrt(n f)` balances `m_v` at `z = n` and `z = f` and gives
//! `K (f - n) / n`; a logarithmic `v` with a perspective `u` makes both constant,
//! `K ln(f / n)` ([`LogParameterization`]).
//!
//! Other measures: used-texel fraction ([`used_texel_fraction`]), misclassification
//! against ray-traced visibility ([`misclassification`]), and along a camera path
//! the sub-texel phase jitter of fixed world points ([`phase_jitter`]) and the
//! shadow-test flip rate ([`flip_rate`]).

use glam::{DMat2, DMat4, DVec2, DVec3, DVec4};
use shadowmap_frustum::{Camera, Light, Projection, ShadowMapping, ShadowSample};

use crate::error::EvalError;

/// Step of the central differences, in pixels. Small against a pixel, so the
/// Jacobian is local (RTW's piecewise-linear warp is measured segment by segment),
/// and large enough that `f64` rounding stays far below the measured values.
pub const JACOBIAN_STEP_PIXELS: f64 = 1.0 / 64.0;

/// The screen of a camera: pixel rays and the projection of world points to pixels.
///
/// Pixel coordinates: `x` right, `y` down, pixel `(i, j)` covers
/// `[i, i + 1) x [j, j + 1)` and its centre is `(i + 0.5, j + 0.5)`.
#[derive(Clone, Copy, Debug)]
pub struct ScreenGeometry {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The camera's `clip_from_world` in `f64`.
    pub clip_from_world: DMat4,
    /// Its inverse.
    pub world_from_clip: DMat4,
    /// Clip depth of the near plane (0, or 1 with reversed-Z).
    near_clip_depth: f64,
    /// Focal length in pixels (vertical), for a perspective camera.
    pixels_per_radian: Option<f64>,
}

impl ScreenGeometry {
    /// The screen of `camera` at `width x height` pixels.
    ///
    /// # Errors
    /// [`EvalError::InvalidRasterSize`] for a zero size; [`EvalError::InvalidView`] for
    /// a camera `shadowmap-frustum` rejects or whose matrix is not invertible.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Result<Self, EvalError> {
        if width == 0 || height == 0 {
            return Err(EvalError::InvalidRasterSize {
                width,
                height,
                layers: 1,
            });
        }
        let clip_from_world = camera
            .clip_from_world()
            .map_err(|e| EvalError::InvalidView {
                message: e.to_string(),
            })?
            .as_dmat4();
        let world_from_clip = clip_from_world.inverse();
        if !world_from_clip.is_finite() {
            return Err(EvalError::InvalidView {
                message: "camera matrix is not invertible".into(),
            });
        }
        let pixels_per_radian = match camera.projection {
            Projection::Perspective { fov_y, .. }
            | Projection::InfinitePerspective { fov_y, .. } => {
                Some(f64::from(height) / (2.0 * (f64::from(fov_y) * 0.5).tan()))
            }
            _ => None,
        };
        Ok(Self {
            width,
            height,
            clip_from_world,
            world_from_clip,
            near_clip_depth: if camera.reversed_z { 1.0 } else { 0.0 },
            pixels_per_radian,
        })
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Vertical focal length in pixels, `H / (2 tan(fovY / 2))`, for perspective
    /// cameras (`None` otherwise).
    #[must_use]
    pub const fn pixels_per_radian(&self) -> Option<f64> {
        self.pixels_per_radian
    }

    /// The ray through a pixel position: origin on the near plane, unit direction.
    /// `None` if the camera matrix cannot unproject it.
    #[must_use]
    pub fn ray(&self, pixel: DVec2) -> Option<(DVec3, DVec3)> {
        let ndc = DVec2::new(
            2.0 * pixel.x / f64::from(self.width) - 1.0,
            1.0 - 2.0 * pixel.y / f64::from(self.height),
        );
        let z0 = self.near_clip_depth;
        let z1 = 0.5;
        let a = unproject(&self.world_from_clip, ndc.extend(z0))?;
        let b = unproject(&self.world_from_clip, ndc.extend(z1))?;
        let dir = (b - a).try_normalize()?;
        Some((a, dir))
    }

    /// The pixel position of a world point, `None` behind the camera.
    #[must_use]
    pub fn project(&self, world: DVec3) -> Option<DVec2> {
        let h = self.clip_from_world * world.extend(1.0);
        if !(h.w > 0.0 && h.is_finite()) {
            return None;
        }
        let ndc = DVec2::new(h.x / h.w, h.y / h.w);
        Some(DVec2::new(
            (ndc.x + 1.0) * 0.5 * f64::from(self.width),
            (1.0 - ndc.y) * 0.5 * f64::from(self.height),
        ))
    }
}

fn unproject(world_from_clip: &DMat4, ndc: DVec3) -> Option<DVec3> {
    let h = *world_from_clip * DVec4::new(ndc.x, ndc.y, ndc.z, 1.0);
    (h.w.abs() > 1e-300 && h.is_finite()).then(|| h.truncate() / h.w)
}

/// A visible surface point: world position and (geometric) normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// World position.
    pub position: DVec3,
    /// Surface normal (any length; the side does not matter).
    pub normal: DVec3,
}

/// The unit direction from `world` toward the light (`None` at a positional light).
#[must_use]
pub fn toward_light(light: &Light, world: DVec3) -> Option<DVec3> {
    match *light {
        Light::Directional { direction } => (-direction.as_dvec3()).try_normalize(),
        Light::Spot { position, .. } | Light::Point { position, .. } => {
            (position.as_dvec3() - world).try_normalize()
        }
    }
}

/// The normal of the perspective-only measure at `world`: the bisector of the
/// directions toward the eye (`-ray`) and toward the light. `None` when they are
/// opposite (light straight behind the surface point as seen from the eye).
#[must_use]
pub fn bisector_normal(ray: DVec3, light: &Light, world: DVec3) -> Option<DVec3> {
    let l = toward_light(light, world)?;
    (l - ray.normalize_or_zero()).try_normalize()
}

/// The texel-space Jacobian of a technique at one visible point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelFootprint {
    /// `d texel / d pixel`: column 0 per pixel step in x, column 1 per step in y.
    pub jacobian: DMat2,
    /// Texel coordinates of the point (`uv * resolution`).
    pub texel: DVec2,
    /// Layer that stores the point.
    pub layer: u32,
}

impl TexelFootprint {
    /// Singular values `(s1, s2)`, `s1 >= s2 >= 0`, of the Jacobian.
    #[must_use]
    pub fn singular_values(&self) -> (f64, f64) {
        singular_values(&self.jacobian)
    }

    /// Aliasing error `m = 1 / s2`: the largest extent of one texel, in pixels.
    /// Infinite for a singular Jacobian.
    #[must_use]
    pub fn aliasing_error(&self) -> f64 {
        let (_, s2) = self.singular_values();
        if s2 > 0.0 { 1.0 / s2 } else { f64::INFINITY }
    }

    /// Extents in pixels of one texel step along `u` and along `v`:
    /// `(|J^-1 e_u|, |J^-1 e_v|)`. Infinite for a singular Jacobian.
    #[must_use]
    pub fn axis_errors(&self) -> (f64, f64) {
        let det = self.jacobian.determinant();
        if det == 0.0 || !det.is_finite() {
            return (f64::INFINITY, f64::INFINITY);
        }
        let inv = self.jacobian.inverse();
        (inv.x_axis.length(), inv.y_axis.length())
    }
}

/// Singular values `(s1, s2)`, `s1 >= s2 >= 0`, of a 2x2 matrix.
#[must_use]
pub fn singular_values(m: &DMat2) -> (f64, f64) {
    let (a, c) = (m.x_axis.x, m.x_axis.y);
    let (b, d) = (m.y_axis.x, m.y_axis.y);
    let (p, q, r) = (a * a + c * c, a * b + c * d, b * b + d * d);
    let mean = 0.5 * (p + r);
    let disc = (0.25 * (p - r) * (p - r) + q * q).max(0.0).sqrt();
    let s1 = (mean + disc).max(0.0).sqrt();
    // s1 * s2 = |det| is more accurate than sqrt(mean - disc).
    let det = (a * d - b * c).abs();
    let s2 = if s1 > 0.0 { det / s1 } else { 0.0 };
    (s1, s2.min(s1))
}

/// Texel coordinates of a sample: `uv * resolution` of its layer.
fn texel_of(sample: &ShadowSample, layer_sizes: &[(u32, u32)]) -> Option<DVec2> {
    let size = layer_sizes.get(sample.layer as usize)?;
    let t = sample.uv * DVec2::new(f64::from(size.0), f64::from(size.1));
    t.is_finite().then_some(t)
}

/// The Jacobian `d texel / d pixel` of `mapping` at a visible surface point, through
/// the tangent plane of the surface (see the module docs). `layer_sizes[l]` is the
/// resolution `(width, height)` of layer `l` in texels.
///
/// `None` where the mapping does not cover the point or a neighbour on the plane
/// (outside the map, behind the light), where the tangent plane contains the view
/// ray, or where the point is behind the camera.
#[must_use]
pub fn texel_footprint(
    mapping: &dyn ShadowMapping,
    layer_sizes: &[(u32, u32)],
    screen: &ScreenGeometry,
    surface: &SurfacePoint,
) -> Option<TexelFootprint> {
    let pixel = screen.project(surface.position)?;
    let n = surface.normal.try_normalize()?;
    let centre = mapping.map_point(surface.position)?;
    let texel = texel_of(&centre, layer_sizes)?;
    let h = JACOBIAN_STEP_PIXELS;
    // Texel coordinates at the plane point under a displaced pixel position, if it
    // lands on the same layer.
    let at = |offset: DVec2| -> Option<DVec2> {
        let (o, d) = screen.ray(pixel + offset)?;
        let nd = n.dot(d);
        if nd.abs() < 1e-12 {
            return None;
        }
        let t = n.dot(surface.position - o) / nd;
        let p = o + d * t;
        let s = mapping.map_point(p)?;
        if s.layer != centre.layer {
            return None;
        }
        texel_of(&s, layer_sizes)
    };
    let derivative = |axis: DVec2| -> Option<DVec2> {
        match (at(axis * h), at(-axis * h)) {
            (Some(a), Some(b)) => Some((a - b) / (2.0 * h)),
            (Some(a), None) => Some((a - texel) / h),
            (None, Some(b)) => Some((texel - b) / h),
            (None, None) => None,
        }
    };
    let dx = derivative(DVec2::X)?;
    let dy = derivative(DVec2::Y)?;
    let jacobian = DMat2::from_cols(dx, dy);
    jacobian.is_finite().then_some(TexelFootprint {
        jacobian,
        texel,
        layer: centre.layer,
    })
}

/// Mean, median, 95th percentile and maximum of a set of values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    /// Number of values.
    pub count: usize,
    /// Arithmetic mean.
    pub mean: f64,
    /// Median (nearest rank).
    pub median: f64,
    /// 95th percentile (nearest rank).
    pub p95: f64,
    /// Maximum.
    pub max: f64,
}

impl Summary {
    /// The summary of `values` (non-finite values are dropped); `None` if none is
    /// left.
    #[must_use]
    pub fn of(values: &[f64]) -> Option<Self> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let rank = |p: f64| {
            let i = (p * v.len() as f64).ceil() as usize;
            v[i.clamp(1, v.len()) - 1]
        };
        Some(Self {
            count: v.len(),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            median: rank(0.5),
            p95: rank(0.95),
            max: v[v.len() - 1],
        })
    }
}

/// Storage factor: `(texels / pixels) * m_max²`, the texels per pixel a
/// map scaled uniformly needs for `m <= 1` everywhere.
#[must_use]
pub fn storage_factor(texels: u64, pixels: usize, m_max: f64) -> f64 {
    if pixels == 0 {
        return f64::NAN;
    }
    texels as f64 / pixels as f64 * m_max * m_max
}

/// Lloyd et al.'s storage factor of a separable parameterization,
/// `(texels / pixels) * max(m_u) * max(m_v)`: each texture axis is scaled on its own.
#[must_use]
pub fn separable_storage_factor(texels: u64, pixels: usize, m_u_max: f64, m_v_max: f64) -> f64 {
    if pixels == 0 {
        return f64::NAN;
    }
    texels as f64 / pixels as f64 * m_u_max * m_v_max
}

/// `K = 1 / (2 tan(fovY / 2))` and the camera's depth range `(n, f)`, for a
/// perspective camera.
#[must_use]
pub fn perspective_constants(camera: &Camera) -> Option<(f64, f64, f64)> {
    let (fov_y, near, far) = match camera.projection {
        Projection::Perspective {
            fov_y, near, far, ..
        } => (fov_y, near, far),
        Projection::InfinitePerspective {
            fov_y,
            near,
            shadow_distance,
            ..
        } => (fov_y, near, shadow_distance),
        _ => return None,
    };
    let k = 1.0 / (2.0 * (f64::from(fov_y) * 0.5).tan());
    Some((k, f64::from(near), f64::from(far)))
}

/// The logarithmic bound on the storage factor of separable parameterizations,
/// `K ln(f / n)` (Lloyd et al. 2006), for a perspective camera.
#[must_use]
pub fn log_bound(camera: &Camera) -> Option<f64> {
    let (k, n, f) = perspective_constants(camera)?;
    Some(k * (f / n).ln())
}

/// Smallest `n . l` (cosine between the surface normal and the direction toward the
/// light) of a *front-lit* surface. Surfaces below it face away from the light or
/// are within 3° of parallel to it: shading (`n . l`) darkens them whatever the
/// shadow map says, and their `m` with the true normal grows without bound (a texel
/// stretches along a surface parallel to the light), so the true-normal error and
/// the misclassification are taken over front-lit pixels only.
pub const FRONT_LIT_MIN_COS: f64 = 0.05;

/// Whether a surface faces the light (see [`FRONT_LIT_MIN_COS`]): `n . l` at least
/// that, with the normal as given (the G-buffer's normals face the camera, so a
/// surface seen from its unlit side is not front-lit).
#[must_use]
pub fn is_front_lit(light: &Light, surface: &SurfacePoint) -> bool {
    let Some(l) = toward_light(light, surface.position) else {
        return false;
    };
    surface
        .normal
        .try_normalize()
        .is_some_and(|n| n.dot(l) >= FRONT_LIT_MIN_COS)
}

/// The aliasing measures of one technique over the visible pixels of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AliasingStats {
    /// Visible pixels (surface hit by the primary ray).
    pub visible_pixels: usize,
    /// Front-lit visible pixels the technique covers with a usable Jacobian (the
    /// pixels of `m`).
    pub measured_pixels: usize,
    /// `m` over the measured pixels (true normals, front-lit pixels only; see
    /// [`FRONT_LIT_MIN_COS`]).
    pub m: Option<Summary>,
    /// Perspective-only `m` (bisector normals) over every covered visible pixel.
    pub m_perspective: Option<Summary>,
    /// `S = texels / visible pixels * max(m)^2`.
    pub storage_factor: f64,
    /// `S` of the perspective-only error.
    pub storage_factor_perspective: f64,
    /// Lloyd's separable storage factor of the perspective-only error.
    pub separable_storage_factor_perspective: f64,
    /// Fraction of the map's texels that some visible pixel samples.
    pub used_texel_fraction: f64,
}

/// Per-pixel results of [`aliasing_stats`], for images.
#[derive(Clone, Debug, PartialEq)]
pub struct PixelErrors {
    /// `m` per pixel (row-major), `None` for background, pixels that are not
    /// front-lit, and unmeasured pixels.
    pub m: Vec<Option<f64>>,
}

/// Measures `mapping` at every visible pixel: `surfaces[i]` is the surface seen by
/// pixel `i` (row-major over `screen`), `None` for background.
///
/// Pixels the technique does not cover, or where the Jacobian is degenerate, are
/// left out of the error statistics but count as visible pixels in `S` (the map had
/// to serve them). The true-normal `m` is taken over front-lit pixels only
/// ([`FRONT_LIT_MIN_COS`]); the perspective-only `m` over every covered pixel.
#[must_use]
pub fn aliasing_stats(
    mapping: &dyn ShadowMapping,
    layer_sizes: &[(u32, u32)],
    screen: &ScreenGeometry,
    light: &Light,
    surfaces: &[Option<SurfacePoint>],
) -> (AliasingStats, PixelErrors) {
    let texels: u64 = layer_sizes
        .iter()
        .map(|s| u64::from(s.0) * u64::from(s.1))
        .sum();
    let mut used = vec![false; usize::try_from(texels).unwrap_or(0)];
    let mut m = Vec::new();
    let mut mp = Vec::new();
    let (mut mu_max, mut mv_max) = (0.0f64, 0.0f64);
    let mut per_pixel = vec![None; surfaces.len()];
    let mut visible = 0;
    for (i, s) in surfaces.iter().enumerate() {
        let Some(s) = s else { continue };
        visible += 1;
        if let Some(sample) = mapping.map_point(s.position) {
            if let Some(t) = texel_of(&sample, layer_sizes) {
                mark_used(&mut used, layer_sizes, t, sample.layer);
            }
        }
        let Some(fp) = texel_footprint(mapping, layer_sizes, screen, s) else {
            continue;
        };
        let e = fp.aliasing_error();
        if e.is_finite() && is_front_lit(light, s) {
            m.push(e);
            per_pixel[i] = Some(e);
        }
        let bisector = screen
            .project(s.position)
            .and_then(|px| screen.ray(px))
            .and_then(|(_, ray)| bisector_normal(ray, light, s.position));
        if let Some(nb) = bisector {
            let sp = SurfacePoint {
                position: s.position,
                normal: nb,
            };
            if let Some(fpp) = texel_footprint(mapping, layer_sizes, screen, &sp) {
                let e = fpp.aliasing_error();
                let (mu, mv) = fpp.axis_errors();
                if e.is_finite() && mu.is_finite() && mv.is_finite() {
                    mp.push(e);
                    mu_max = mu_max.max(mu);
                    mv_max = mv_max.max(mv);
                }
            }
        }
    }
    let m_sum = Summary::of(&m);
    let mp_sum = Summary::of(&mp);
    let used_count = used.iter().filter(|&&u| u).count();
    let stats = AliasingStats {
        visible_pixels: visible,
        measured_pixels: m.len(),
        m: m_sum,
        m_perspective: mp_sum,
        storage_factor: m_sum.map_or(f64::NAN, |s| storage_factor(texels, visible, s.max)),
        storage_factor_perspective: mp_sum
            .map_or(f64::NAN, |s| storage_factor(texels, visible, s.max)),
        separable_storage_factor_perspective: if mp.is_empty() {
            f64::NAN
        } else {
            separable_storage_factor(texels, visible, mu_max, mv_max)
        },
        used_texel_fraction: if texels == 0 {
            0.0
        } else {
            used_count as f64 / texels as f64
        },
    };
    (stats, PixelErrors { m: per_pixel })
}

fn mark_used(used: &mut [bool], layer_sizes: &[(u32, u32)], texel: DVec2, layer: u32) {
    let Some(size) = layer_sizes.get(layer as usize) else {
        return;
    };
    let (x, y) = (texel.x.floor(), texel.y.floor());
    if !(x >= 0.0 && y >= 0.0 && x < f64::from(size.0) && y < f64::from(size.1)) {
        return;
    }
    let offset: u64 = layer_sizes[..layer as usize]
        .iter()
        .map(|s| u64::from(s.0) * u64::from(s.1))
        .sum();
    let index = offset + y as u64 * u64::from(size.0) + x as u64;
    if let Some(u) = usize::try_from(index).ok().and_then(|i| used.get_mut(i)) {
        *u = true;
    }
}

/// Fraction of a map's texels that some of `texels` (texel coordinates and layer)
/// falls in.
#[must_use]
pub fn used_texel_fraction(
    texels: impl IntoIterator<Item = (DVec2, u32)>,
    layer_sizes: &[(u32, u32)],
) -> f64 {
    let total: u64 = layer_sizes
        .iter()
        .map(|s| u64::from(s.0) * u64::from(s.1))
        .sum();
    if total == 0 {
        return 0.0;
    }
    let mut used = vec![false; usize::try_from(total).unwrap_or(0)];
    for (t, l) in texels {
        mark_used(&mut used, layer_sizes, t, l);
    }
    used.iter().filter(|&&u| u).count() as f64 / total as f64
}

/// Misclassification rate of a technique's shadow mask against the ray-traced one:
/// the fraction of pixels with a ground truth (`truth[i]` is `Some`) whose
/// technique result differs. A pixel the technique does not cover (`None`) counts
/// as lit, as a renderer samples outside the map. `None` if no pixel has a ground
/// truth or the lengths differ.
#[must_use]
pub fn misclassification(technique: &[Option<bool>], truth: &[Option<bool>]) -> Option<f64> {
    if technique.len() != truth.len() {
        return None;
    }
    let mut total = 0usize;
    let mut wrong = 0usize;
    for (t, g) in technique.iter().zip(truth) {
        if let Some(g) = g {
            total += 1;
            if t.unwrap_or(true) != *g {
                wrong += 1;
            }
        }
    }
    (total > 0).then(|| wrong as f64 / total as f64)
}

/// Sub-texel phase jitter along a path: `texels[f][i]` is where fixed world point
/// `i` lands in frame `f` (texel coordinates and layer). For every point and pair of
/// consecutive frames on the same layer, the change of the fractional texel position,
/// each axis wrapped to `[-1/2, 1/2]`, and its length are taken; the result is the
/// mean length (0: the map moves by whole texels or not at all; about 0.38 for random
/// phases). `None` without any such pair.
#[must_use]
pub fn phase_jitter(texels: &[Vec<Option<(DVec2, u32)>>]) -> Option<f64> {
    let mut sum = 0.0;
    let mut count = 0usize;
    for pair in texels.windows(2) {
        for (a, b) in pair[0].iter().zip(&pair[1]) {
            if let (Some((ta, la)), Some((tb, lb))) = (a, b) {
                if la != lb {
                    continue;
                }
                let wrap = |x: f64| x - x.round();
                let d = DVec2::new(wrap(tb.x - ta.x), wrap(tb.y - ta.y));
                if d.is_finite() {
                    sum += d.length();
                    count += 1;
                }
            }
        }
    }
    (count > 0).then(|| sum / count as f64)
}

/// Shadow-test flip rate along a path: `lit[f][i]` is the shadow test of fixed world
/// point `i` in frame `f` (`None`: not covered). The fraction of (point, consecutive
/// frame pair) with both tests known whose result changes. With a static scene and
/// light every flip is an artefact. `None` without any such pair.
#[must_use]
pub fn flip_rate(lit: &[Vec<Option<bool>>]) -> Option<f64> {
    let mut flips = 0usize;
    let mut count = 0usize;
    for pair in lit.windows(2) {
        for (a, b) in pair[0].iter().zip(&pair[1]) {
            if let (Some(a), Some(b)) = (a, b) {
                count += 1;
                if a != b {
                    flips += 1;
                }
            }
        }
    }
    (count > 0).then(|| flips as f64 / count as f64)
}

mod limits;
#[cfg(test)]
mod tests;

pub use limits::{LogParameterization, frustum_samples, frustum_storage_factor};
