//! The reference rasterizer: renders a technique's shadow depth map the way a GPU
//! (Vulkan, llvmpipe) does, in `f64`, so the evaluation sees the very texels a real
//! depth pass would store.
//!
//! ```text
//! per layer, per triangle (no culling: both faces cast):
//!   project the 3 vertices (DepthProjector); any None drops the triangle
//!   clip the polygon (Sutherland–Hodgman, homogeneous) against
//!       0 <= z <= w,  clip_distance >= 0,  |x|, |y| <= G w   (G: guard band, >= 8)
//!   fan into triangles; divide by w
//!   viewport: x_px = (x_ndc + 1)/2 W,  y_px = (1 - y_ndc)/2 H   (row 0 is v = 0)
//!   snap to 1/2^subpixel_bits, round to nearest (i64 fixed point)
//!   cover pixel centres (x + 1/2, y + 1/2): exact integer edge functions with the
//!       top-left fill rule
//!   z = z_ndc interpolated with screen-space barycentrics (f64), + bias, clamped
//!       to [0, 1], stored as f32 if it passes LESS (GREATER with reversed-Z)
//! bias = slope_scale * max(|dz/dx|, |dz/dy|) + constant * r,  r = 2^(e - 23)
//!       (Vulkan's rule for a floating-point depth buffer, e = exponent of the
//!        largest depth of the primitive)
//! ```
//!
//! The guard band is what a GPU does too: clipping only far outside the viewport
//! keeps the edges of visible triangles exact (no new vertices near pixels), and
//! bounds the fixed-point coordinates so the edge functions fit in `i64`.
//!
//! # Example
//!
//! ```
//! use glam::{DMat4, DVec3};
//! use shadowmap_eval::raster::{MatrixProjector, RasterOptions, rasterize_depth};
//! use shadowmap_eval::scene::Mesh;
//!
//! // A quad covering the left half of an 8×8 map at depth 0.25 (orthographic, w = 1).
//! let mut mesh = Mesh::new();
//! let z = 0.25;
//! mesh.push_quad([
//!     DVec3::new(-1.0, -1.0, z),
//!     DVec3::new(0.0, -1.0, z),
//!     DVec3::new(0.0, 1.0, z),
//!     DVec3::new(-1.0, 1.0, z),
//! ]);
//! let projector = MatrixProjector::new(vec![DMat4::IDENTITY], false);
//! let map = rasterize_depth(&mesh, &projector, &RasterOptions::default().with_size(8, 8))?;
//! assert_eq!(map.get(0, 3, 5), 0.25);
//! assert_eq!(map.get(0, 4, 5), map.clear_value());
//! # Ok::<(), shadowmap_eval::EvalError>(())
//! ```

use glam::{DMat4, DVec3, DVec4};
use shadowmap_frustum::{CascadeSet, ShadowSample, ShadowTransform};
use shadowmap_paraboloid::{ParaboloidMap, Side};
use shadowmap_rtw::{RtwShadow, forward_warp_f64};

use crate::EvalError;
use crate::scene::Mesh;

/// Largest width or height the rasterizer accepts.
pub const MAX_RASTER_SIDE: u32 = 32768;
/// Largest number of texels (all layers) the rasterizer allocates.
pub const MAX_RASTER_TEXELS: u64 = 1 << 30;

mod layers;

/// A projected vertex: WebGPU clip coordinates and a user clip distance.
///
/// The parts of a triangle where the linearly interpolated `clip_distance` is negative
/// are discarded (the paraboloid hemisphere). Use 1.0 when unused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVertex {
    /// Clip coordinates: `x, y` in `[-w, w]`, depth `z` in `[0, w]` inside.
    pub clip: DVec4,
    /// Kept where `>= 0`.
    pub clip_distance: f64,
}

impl ClipVertex {
    /// A vertex with a clip distance.
    #[must_use]
    pub const fn new(clip: DVec4, clip_distance: f64) -> Self {
        Self {
            clip,
            clip_distance,
        }
    }

    /// A vertex without user clipping (`clip_distance` 1).
    #[must_use]
    pub const fn unclipped(clip: DVec4) -> Self {
        Self::new(clip, 1.0)
    }

    fn lerp(self, other: Self, t: f64) -> Self {
        Self {
            clip: self.clip.lerp(other.clip, t),
            clip_distance: self.clip_distance + (other.clip_distance - self.clip_distance) * t,
        }
    }
}

/// How a technique's depth pass projects world points, layer by layer.
pub trait DepthProjector {
    /// Number of layers (cascades, paraboloid sides), at least 1.
    fn layers(&self) -> u32;
    /// Whether depth is reversed (clear 0, test GREATER).
    fn reversed_z(&self) -> bool;
    /// The clip-space vertex of `world` in `layer`; `None` drops every triangle using
    /// the vertex from that layer.
    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<ClipVertex>;
}

/// Knobs of [`rasterize_depth`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct RasterOptions {
    /// Map width in texels. Default 1024.
    pub width: u32,
    /// Map height in texels. Default 1024.
    pub height: u32,
    /// Subpixel precision, `1..=16` bits. Default 8, as Vulkan implementations.
    pub subpixel_bits: u32,
    /// Constant depth bias in units of the minimum resolvable difference `r`.
    /// Default 0.
    pub depth_bias_constant: f64,
    /// Slope-scaled depth bias factor. Default 0.
    pub depth_bias_slope_scale: f64,
}

impl Default for RasterOptions {
    fn default() -> Self {
        Self {
            width: 1024,
            height: 1024,
            subpixel_bits: 8,
            depth_bias_constant: 0.0,
            depth_bias_slope_scale: 0.0,
        }
    }
}

impl RasterOptions {
    /// With this map size.
    #[must_use]
    pub const fn with_size(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    /// With this subpixel precision.
    #[must_use]
    pub const fn with_subpixel_bits(mut self, bits: u32) -> Self {
        self.subpixel_bits = bits;
        self
    }

    /// With this constant and slope-scaled depth bias.
    #[must_use]
    pub const fn with_depth_bias(mut self, constant: f64, slope_scale: f64) -> Self {
        self.depth_bias_constant = constant;
        self.depth_bias_slope_scale = slope_scale;
        self
    }
}

/// A rendered depth map (array).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthMap {
    /// Width in texels (of the widest layer, see [`DepthMap::layer_size`]).
    pub width: u32,
    /// Height in texels (of the highest layer).
    pub height: u32,
    /// Number of layers.
    pub layers: u32,
    /// Whether depth is reversed (clear 0, nearer is larger).
    pub reversed_z: bool,
    /// Depth, layer-major then row-major; row 0 is `v = 0` (top).
    pub depth: Vec<f32>,
    /// Each layer's size, when they differ ([`DepthMap::from_layers`]).
    sizes: Option<Vec<(u32, u32)>>,
}

impl DepthMap {
    /// A map filled with the clear value.
    ///
    /// # Errors
    /// [`EvalError::InvalidRasterSize`] for a zero size or one past
    /// [`MAX_RASTER_SIDE`] / [`MAX_RASTER_TEXELS`].
    pub fn cleared(
        width: u32,
        height: u32,
        layers: u32,
        reversed_z: bool,
    ) -> Result<Self, EvalError> {
        let bad = EvalError::InvalidRasterSize {
            width,
            height,
            layers,
        };
        let texels = u64::from(width) * u64::from(height) * u64::from(layers);
        if width == 0
            || height == 0
            || layers == 0
            || width > MAX_RASTER_SIDE
            || height > MAX_RASTER_SIDE
            || texels > MAX_RASTER_TEXELS
        {
            return Err(bad);
        }
        let clear = if reversed_z { 0.0 } else { 1.0 };
        Ok(Self {
            width,
            height,
            layers,
            reversed_z,
            depth: vec![clear; texels as usize],
            sizes: None,
        })
    }

    /// Stored depth of texel `(x, y)` in `layer`.
    ///
    /// # Panics
    /// Out of range, like slice indexing; see [`DepthMap::try_get`].
    #[must_use]
    pub fn get(&self, layer: u32, x: u32, y: u32) -> f32 {
        self.try_get(layer, x, y)
            .expect("DepthMap::get: texel out of range")
    }

    /// Stored depth of texel `(x, y)` in `layer`, `None` out of range.
    #[must_use]
    pub fn try_get(&self, layer: u32, x: u32, y: u32) -> Option<f32> {
        let (w, h) = self.layer_size(layer);
        (layer < self.layers && x < w && y < h).then(|| self.depth[self.index(layer, x, y)])
    }

    fn index(&self, layer: u32, x: u32, y: u32) -> usize {
        let (w, _) = self.layer_size(layer);
        self.layer_offset(layer) + y as usize * w as usize + x as usize
    }

    /// The depth a cleared texel holds: 1, or 0 with reversed-Z.
    #[must_use]
    pub const fn clear_value(&self) -> f32 {
        if self.reversed_z { 0.0 } else { 1.0 }
    }

    /// The texel `(x, y)` a sample reads with nearest filtering: `floor(uv * size)`,
    /// `u = 1` and `v = 1` reading the last texel. `None` outside `[0, 1]²`, for a
    /// non-finite `uv` or a layer past the end.
    #[must_use]
    pub fn texel_of(&self, sample: &ShadowSample) -> Option<(u32, u32)> {
        let uv = sample.uv;
        let (w, h) = self.layer_size(sample.layer);
        if !(sample.layer < self.layers
            && w > 0
            && h > 0
            && (0.0..=1.0).contains(&uv.x)
            && (0.0..=1.0).contains(&uv.y))
        {
            return None;
        }
        let x = ((uv.x * f64::from(w)) as u32).min(w - 1);
        let y = ((uv.y * f64::from(h)) as u32).min(h - 1);
        Some((x, y))
    }

    /// Stored depth at a sample (nearest texel, see [`DepthMap::texel_of`]).
    #[must_use]
    pub fn lookup(&self, sample: &ShadowSample) -> Option<f32> {
        let (x, y) = self.texel_of(sample)?;
        Some(self.depth[self.index(sample.layer, x, y)])
    }

    /// The shadow test: the sample's depth moved `bias` toward the light (minus `bias`,
    /// plus with reversed-Z), clamped to `[0, 1]` like the depth pass and rounded to
    /// `f32` like a shader's reference depth, compared with the stored depth: lit when
    /// not farther (`<=`, `>=` reversed). `None` where [`DepthMap::lookup`] is `None`
    /// or the depth is NaN.
    #[must_use]
    pub fn is_lit(&self, sample: &ShadowSample, bias: f64) -> Option<bool> {
        let stored = self.lookup(sample)?;
        if sample.depth.is_nan() || bias.is_nan() {
            return None;
        }
        Some(if self.reversed_z {
            (sample.depth + bias).clamp(0.0, 1.0) as f32 >= stored
        } else {
            (sample.depth - bias).clamp(0.0, 1.0) as f32 <= stored
        })
    }

    /// [`DepthMap::is_lit`], but `None` also where the answer would change if the
    /// sample moved up to `radius` texels (in each axis, clamped to the map): the
    /// sample is then within `radius` texels of a shadow boundary, where a half-texel
    /// difference between two renderings legitimately flips it.
    #[must_use]
    pub fn is_lit_unambiguous(
        &self,
        sample: &ShadowSample,
        bias: f64,
        radius: u32,
    ) -> Option<bool> {
        let lit = self.is_lit(sample, bias)?;
        let (x, y) = self.texel_of(sample)?;
        let (w, h) = self.layer_size(sample.layer);
        let r = radius;
        for ny in y.saturating_sub(r)..=(y.saturating_add(r)).min(h - 1) {
            for nx in x.saturating_sub(r)..=(x.saturating_add(r)).min(w - 1) {
                let uv = glam::DVec2::new(
                    (f64::from(nx) + 0.5) / f64::from(w),
                    (f64::from(ny) + 0.5) / f64::from(h),
                );
                if self.is_lit(&ShadowSample { uv, ..*sample }, bias) != Some(lit) {
                    return None;
                }
            }
        }
        Some(lit)
    }
}

/// Renders the depth map of `mesh` through `projector`, every layer independently,
/// as described in the [module docs](self).
///
/// # Errors
/// [`EvalError::InvalidRasterSize`] for a zero or too large size, zero layers, a
/// subpixel precision outside `1..=16`, a size whose fixed-point coordinates would
/// not fit (`max(width, height) * 2^subpixel_bits > 2^24`) or a non-finite bias;
/// [`EvalError::InvalidMesh`] for a bad mesh (see [`Mesh::validate`]).
pub fn rasterize_depth(
    mesh: &Mesh,
    projector: &dyn DepthProjector,
    options: &RasterOptions,
) -> Result<DepthMap, EvalError> {
    let layers = projector.layers();
    let mut map = DepthMap::cleared(
        options.width,
        options.height,
        layers,
        projector.reversed_z(),
    )?;
    let side = u64::from(options.width.max(options.height));
    if !(1..=16).contains(&options.subpixel_bits)
        || (side << options.subpixel_bits) > (1 << 24)
        || !options.depth_bias_constant.is_finite()
        || !options.depth_bias_slope_scale.is_finite()
    {
        return Err(EvalError::InvalidRasterSize {
            width: options.width,
            height: options.height,
            layers,
        });
    }
    mesh.validate()?;
    let raster = Rasterizer::new(options, map.reversed_z);
    let texels = options.width as usize * options.height as usize;
    let mut projected = Vec::with_capacity(mesh.positions.len());
    for (layer, plane) in (0..layers).zip(map.depth.chunks_exact_mut(texels)) {
        projected.clear();
        projected.extend(mesh.positions.iter().map(|&p| {
            projector
                .project_vertex(layer, p)
                .filter(|v| v.clip.is_finite() && !v.clip_distance.is_nan())
        }));
        for t in &mesh.indices {
            if let [Some(a), Some(b), Some(c)] = t.map(|k| projected[k as usize]) {
                raster.polygon(&[a, b, c], plane);
            }
        }
    }
    Ok(map)
}

/// Most vertices a triangle can have after clipping against 7 planes.
const MAX_POLY: usize = 3 + 7;

/// Fixed-point triangle setup and traversal for one map size.
struct Rasterizer {
    width: u32,
    height: u32,
    reversed_z: bool,
    /// `2^subpixel_bits`: one pixel in fixed point.
    one: i64,
    /// Guard band half-extent in NDC.
    guard: f64,
    bias_constant: f64,
    bias_slope: f64,
}

#[derive(Clone, Copy, Debug)]
struct ScreenVertex {
    x: i64,
    y: i64,
    z: f64,
}

impl Rasterizer {
    fn new(options: &RasterOptions, reversed_z: bool) -> Self {
        let one = 1i64 << options.subpixel_bits;
        let side = f64::from(options.width.max(options.height));
        // |x_px| * one <= 2^27 keeps edge-function products below 2^58.
        let guard = (f64::from(1u32 << 27) / (side * one as f64)).max(1.0);
        Self {
            width: options.width,
            height: options.height,
            reversed_z,
            one,
            guard,
            bias_constant: options.depth_bias_constant,
            bias_slope: options.depth_bias_slope_scale,
        }
    }

    /// Signed distance of a vertex to clip plane `k` (inside where `>= 0`).
    fn plane_distance(&self, k: usize, v: &ClipVertex) -> f64 {
        let c = v.clip;
        match k {
            0 => c.z,
            1 => c.w - c.z,
            2 => v.clip_distance,
            3 => self.guard * c.w + c.x,
            4 => self.guard * c.w - c.x,
            5 => self.guard * c.w + c.y,
            _ => self.guard * c.w - c.y,
        }
    }

    fn polygon(&self, triangle: &[ClipVertex; 3], plane: &mut [f32]) {
        let mut buf_a = [triangle[0]; MAX_POLY];
        let mut buf_b = [triangle[0]; MAX_POLY];
        buf_a[..3].copy_from_slice(triangle);
        let mut n = 3;
        for k in 0..7 {
            let d: [f64; 3] = core::array::from_fn(|i| self.plane_distance(k, &triangle[i]));
            if d.iter().all(|&x| x < 0.0) {
                return;
            }
            if d.iter().all(|&x| x >= 0.0) {
                continue;
            }
            n = self.clip_polygon(k, &buf_a[..n], &mut buf_b);
            if n < 3 {
                return;
            }
            buf_a[..n].copy_from_slice(&buf_b[..n]);
        }
        let mut screen = [ScreenVertex { x: 0, y: 0, z: 0.0 }; MAX_POLY];
        for (s, v) in screen.iter_mut().zip(&buf_a[..n]) {
            match self.to_screen(v) {
                Some(p) => *s = p,
                None => return,
            }
        }
        for i in 1..n - 1 {
            self.triangle([screen[0], screen[i], screen[i + 1]], plane);
        }
    }

    /// Sutherland–Hodgman against plane `k`; returns the output vertex count.
    fn clip_polygon(
        &self,
        k: usize,
        input: &[ClipVertex],
        out: &mut [ClipVertex; MAX_POLY],
    ) -> usize {
        let mut n = 0;
        let mut push = |v: ClipVertex| {
            if n < MAX_POLY {
                out[n] = v;
                n += 1;
            }
        };
        for i in 0..input.len() {
            let prev = input[(i + input.len() - 1) % input.len()];
            let cur = input[i];
            let (dp, dc) = (self.plane_distance(k, &prev), self.plane_distance(k, &cur));
            match (dp >= 0.0, dc >= 0.0) {
                (true, true) => push(cur),
                (false, true) => {
                    // Always interpolate from the inside vertex, so the edge shared by
                    // two triangles is cut at the same point in both.
                    push(cur.lerp(prev, dc / (dc - dp)));
                    push(cur);
                }
                (true, false) => push(prev.lerp(cur, dp / (dp - dc))),
                (false, false) => {}
            }
        }
        n
    }

    fn to_screen(&self, v: &ClipVertex) -> Option<ScreenVertex> {
        let c = v.clip;
        if !(c.w > 0.0) {
            return None;
        }
        let (x, y, z) = (c.x / c.w, c.y / c.w, c.z / c.w);
        let fx = (x + 1.0) * 0.5 * f64::from(self.width) * self.one as f64;
        let fy = (1.0 - y) * 0.5 * f64::from(self.height) * self.one as f64;
        if !(fx.is_finite() && fy.is_finite() && z.is_finite()) {
            return None;
        }
        Some(ScreenVertex {
            x: fx.round() as i64,
            y: fy.round() as i64,
            z: z.clamp(0.0, 1.0),
        })
    }

    fn triangle(&self, v: [ScreenVertex; 3], plane: &mut [f32]) {
        let [v0, mut v1, mut v2] = v;
        let mut area = edge(v0, v1, v2.x, v2.y);
        if area == 0 {
            return;
        }
        if area < 0 {
            core::mem::swap(&mut v1, &mut v2);
            area = -area;
        }
        let one = self.one;
        let half = one / 2;
        let min_x = v0.x.min(v1.x).min(v2.x);
        let max_x = v0.x.max(v1.x).max(v2.x);
        let min_y = v0.y.min(v1.y).min(v2.y);
        let max_y = v0.y.max(v1.y).max(v2.y);
        // Pixels whose centre x * one + half lies in [min, max].
        let x_lo = ceil_div(min_x - half, one).max(0);
        let x_hi = (max_x - half)
            .div_euclid(one)
            .min(i64::from(self.width) - 1);
        let y_lo = ceil_div(min_y - half, one).max(0);
        let y_hi = (max_y - half)
            .div_euclid(one)
            .min(i64::from(self.height) - 1);
        if x_lo > x_hi || y_lo > y_hi {
            return;
        }
        // Edge i is opposite vertex i; its function is vertex i's barycentric weight.
        let edges = [(v1, v2), (v2, v0), (v0, v1)];
        let fill_bias = edges.map(|(a, b)| i64::from(!is_top_left(a, b)));
        let step_x = edges.map(|(a, b)| -(b.y - a.y) * one);
        let step_y = edges.map(|(a, b)| (b.x - a.x) * one);
        let (px0, py0) = (x_lo * one + half, y_lo * one + half);
        let mut row = edges.map(|(a, b)| edge(a, b, px0, py0));

        let inv_area = 1.0 / area as f64;
        let z = [v0.z, v1.z, v2.z];
        let bias = self.depth_bias(z, step_x, step_y, inv_area);
        let width = self.width as usize;
        for y in y_lo..=y_hi {
            let mut e = row;
            let line = &mut plane[y as usize * width..][..width];
            for x in x_lo..=x_hi {
                if e[0] >= fill_bias[0] && e[1] >= fill_bias[1] && e[2] >= fill_bias[2] {
                    let depth =
                        (e[0] as f64 * z[0] + e[1] as f64 * z[1] + e[2] as f64 * z[2]) * inv_area;
                    let depth = ((depth + bias).clamp(0.0, 1.0)) as f32;
                    let stored = &mut line[x as usize];
                    let pass = if self.reversed_z {
                        depth > *stored
                    } else {
                        depth < *stored
                    };
                    if pass {
                        *stored = depth;
                    }
                }
                for i in 0..3 {
                    e[i] += step_x[i];
                }
            }
            for i in 0..3 {
                row[i] += step_y[i];
            }
        }
    }

    /// Vulkan depth bias: `slope_scale * max(|dz/dx|, |dz/dy|) + constant * r`.
    fn depth_bias(&self, z: [f64; 3], step_x: [i64; 3], step_y: [i64; 3], inv_area: f64) -> f64 {
        if self.bias_constant == 0.0 && self.bias_slope == 0.0 {
            return 0.0;
        }
        // d(weight_i)/d(pixel) = step_i / area.
        let dzdx: f64 = (0..3).map(|i| step_x[i] as f64 * z[i]).sum::<f64>() * inv_area;
        let dzdy: f64 = (0..3).map(|i| step_y[i] as f64 * z[i]).sum::<f64>() * inv_area;
        let slope = dzdx.abs().max(dzdy.abs());
        let max_z = z[0].max(z[1]).max(z[2]).max(f64::from(f32::MIN_POSITIVE));
        let r = (max_z.log2().floor() - 23.0).exp2();
        self.bias_slope * slope + self.bias_constant * r
    }
}

/// `(b - a) x (p - a)` in y-down pixels: positive inside a triangle with positive area.
fn edge(a: ScreenVertex, b: ScreenVertex, px: i64, py: i64) -> i64 {
    (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x)
}

/// Top edge (horizontal, interior below) or left edge (going up, interior to its
/// right), for a triangle with positive [`edge`] area in y-down coordinates.
fn is_top_left(a: ScreenVertex, b: ScreenVertex) -> bool {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    dy < 0 || (dy == 0 && dx > 0)
}

fn ceil_div(a: i64, b: i64) -> i64 {
    -((-a).div_euclid(b))
}

/// Plain matrix techniques (uniform, cascades, spot, LiSPSM, XPSM, TSM): one
/// `clip_from_world` per layer, no user clipping.
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixProjector {
    /// Depth-pass matrix of each layer.
    pub clip_from_world: Vec<DMat4>,
    /// Whether depth is reversed.
    pub reversed_z: bool,
}

impl MatrixProjector {
    /// A projector with one layer per matrix.
    #[must_use]
    pub const fn new(clip_from_world: Vec<DMat4>, reversed_z: bool) -> Self {
        Self {
            clip_from_world,
            reversed_z,
        }
    }
}

impl From<&ShadowTransform> for MatrixProjector {
    fn from(t: &ShadowTransform) -> Self {
        Self::new(vec![t.clip_from_world.as_dmat4()], t.reversed_z)
    }
}

impl From<&CascadeSet> for MatrixProjector {
    /// One layer per cascade (`cascade.transform.clip_from_world`).
    fn from(set: &CascadeSet) -> Self {
        Self::new(
            set.cascades
                .iter()
                .map(|c| c.transform.clip_from_world.as_dmat4())
                .collect(),
            set.cascades.first().is_some_and(|c| c.transform.reversed_z),
        )
    }
}

impl DepthProjector for MatrixProjector {
    fn layers(&self) -> u32 {
        u32::try_from(self.clip_from_world.len()).unwrap_or(u32::MAX)
    }

    fn reversed_z(&self) -> bool {
        self.reversed_z
    }

    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<ClipVertex> {
        let m = self.clip_from_world.get(layer as usize)?;
        Some(ClipVertex::unclipped(*m * world.extend(1.0)))
    }
}

/// A paraboloid map (DPSM, IPSM): layer 0 the front side, layer 1 the back side of a
/// dual map. Each vertex goes through [`ParaboloidMap::project`] for the layer's side
/// (`w = 1`, `x = 2u - 1`, `y = 1 - 2v`, `z` = its depth); `clip_distance` is the
/// cosine of the angle from the side's axis, so the side's hemisphere is kept:
///
/// ```text
/// q = light_from_world * P        front: -q.z / |q|     back: q.z / |q|
/// ```
///
/// A vertex at the light or straight behind the side's axis (where `project` is
/// `None`) drops its triangle from that layer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParaboloidProjector {
    /// The map.
    pub map: ParaboloidMap,
}

impl From<ParaboloidMap> for ParaboloidProjector {
    fn from(map: ParaboloidMap) -> Self {
        Self { map }
    }
}

impl From<&ParaboloidMap> for ParaboloidProjector {
    fn from(map: &ParaboloidMap) -> Self {
        Self { map: *map }
    }
}

impl DepthProjector for ParaboloidProjector {
    fn layers(&self) -> u32 {
        self.map.layers()
    }

    fn reversed_z(&self) -> bool {
        self.map.reversed_z
    }

    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<ClipVertex> {
        let side = match layer {
            0 => Side::Front,
            1 if self.map.layers() == 2 => Side::Back,
            _ => return None,
        };
        let s = self.map.project(world.as_vec3(), side)?;
        let cos = self.map.clip_distance(world.as_vec3(), side);
        let clip = DVec4::new(2.0 * s.uv.x - 1.0, 1.0 - 2.0 * s.uv.y, s.depth, 1.0);
        Some(ClipVertex::new(clip, cos))
    }
}

/// A rectilinear texture warping map: the base projection, then each texture axis
/// through its warp table ([`forward_warp_f64`]), depth unchanged. The base is an
/// orthographic (`w = 1`) fit; a perspective base is divided by `w` first.
///
/// Warping only the vertices is what the GPU depth pass does: edges stay straight in
/// the warped map, so the texels along a long edge can differ from
/// [`RtwShadow`]'s exact per-point mapping by up to the warp's curvature.
#[derive(Clone, Copy, Debug)]
pub struct RtwProjector<'a> {
    /// The RTW technique.
    pub shadow: RtwShadow<'a>,
}

impl<'a> From<RtwShadow<'a>> for RtwProjector<'a> {
    fn from(shadow: RtwShadow<'a>) -> Self {
        Self { shadow }
    }
}

impl DepthProjector for RtwProjector<'_> {
    fn layers(&self) -> u32 {
        1
    }

    fn reversed_z(&self) -> bool {
        self.shadow.base.reversed_z
    }

    fn project_vertex(&self, layer: u32, world: DVec3) -> Option<ClipVertex> {
        if layer != 0 {
            return None;
        }
        let h = self.shadow.base.clip_from_world.as_dmat4() * world.extend(1.0);
        if !(h.w > 0.0) {
            return None;
        }
        let ndc = h.truncate() / h.w;
        let u = forward_warp_f64(self.shadow.warps.x_table(), 0.5 + 0.5 * ndc.x);
        let v = forward_warp_f64(self.shadow.warps.y_table(), 0.5 - 0.5 * ndc.y);
        let clip = DVec4::new(2.0 * u - 1.0, 1.0 - 2.0 * v, ndc.z, 1.0);
        clip.is_finite().then_some(ClipVertex::unclipped(clip))
    }
}
