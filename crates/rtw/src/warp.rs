use alloc::vec;
use alloc::vec::Vec;

use arrayvec::ArrayVec;
use glam::{DVec3, Vec2};
use shadowmap_frustum::{ShadowMapping, ShadowSample, ShadowTransform, math};

use crate::RtwError;
use crate::importance::{ImportanceMap, MAX_MAP_CELLS, MAX_MAP_SIDE};
use crate::table::{forward_warp, forward_warp_f64, inverse_warp, warp_slope};

#[cfg(feature = "serde")]
mod serde_impls;

/// Largest accepted blur radius (cells).
pub const MAX_BLUR_RADIUS: u32 = 64;
/// Smallest accepted importance floor.
pub const MIN_FLOOR: f32 = 1e-6;

/// Knobs of the importance-to-warp step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct WarpOptions {
    /// Radius of the Gaussian blur of each 1-D map, in cells, `0..=`[`MAX_BLUR_RADIUS`]
    /// (0: no blur). The kernel is `exp(-k² / (2 sigma²))`, `sigma = radius / 2`,
    /// `|k| <= radius`, normalized, clamp-to-edge.
    pub blur_radius: u32,
    /// Smallest density relative to the 1-D map's maximum, in
    /// `[`[`MIN_FLOOR`]`, 1]`: no region gets zero texels, and the densest region gets at
    /// most `1 / floor` times the texels of the sparsest. The `f32` round trip
    /// `inverse(forward(u))` is accurate to about `1e-7 / floor`.
    pub floor: f32,
    /// Weight of the previous frame's density, in `[0, 1)` (0: no temporal smoothing).
    pub temporal: f32,
}

impl Default for WarpOptions {
    fn default() -> Self {
        Self {
            blur_radius: 2,
            floor: 1e-3,
            temporal: 0.0,
        }
    }
}

impl WarpOptions {
    /// With this blur radius.
    #[must_use]
    pub const fn with_blur_radius(mut self, radius: u32) -> Self {
        self.blur_radius = radius;
        self
    }
    /// With this floor.
    #[must_use]
    pub const fn with_floor(mut self, floor: f32) -> Self {
        self.floor = floor;
        self
    }
    /// With this temporal weight.
    #[must_use]
    pub const fn with_temporal(mut self, temporal: f32) -> Self {
        self.temporal = temporal;
        self
    }

    /// `Ok` if every knob is in its documented range.
    ///
    /// # Errors
    /// [`RtwError::InvalidOption`].
    pub fn validate(&self) -> Result<(), RtwError> {
        let ok = self.blur_radius <= MAX_BLUR_RADIUS
            && (MIN_FLOOR..=1.0).contains(&self.floor)
            && (0.0..1.0).contains(&self.temporal);
        if ok {
            Ok(())
        } else {
            Err(RtwError::InvalidOption)
        }
    }
}

/// The two 1-D warp tables of an RTW shadow map, plus the buffers that build them.
///
/// Created once per importance-map size; [`WarpMaps::build`] reuses every buffer, so
/// per-frame work does not allocate. The `x` table has one texel per importance-map
/// column and warps `u`; the `y` table one per row and warps `v`.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct WarpMaps {
    x: Vec<f32>,
    y: Vec<f32>,
    col_max: Vec<f32>,
    row_max: Vec<f32>,
    density_x: Vec<f32>,
    density_y: Vec<f32>,
    #[cfg_attr(feature = "serde", serde(skip))]
    scratch: Vec<f64>,
    has_history: bool,
    fallback: [bool; 2],
}

impl WarpMaps {
    /// Identity warps for a `width x height` importance map.
    ///
    /// # Errors
    /// [`RtwError::EmptyMap`], [`RtwError::MapTooLarge`] (as [`ImportanceMap::new`]).
    pub fn new(width: u32, height: u32) -> Result<Self, RtwError> {
        if width == 0 || height == 0 {
            return Err(RtwError::EmptyMap);
        }
        if width > MAX_MAP_SIDE
            || height > MAX_MAP_SIDE
            || width as usize * height as usize > MAX_MAP_CELLS
        {
            return Err(RtwError::MapTooLarge);
        }
        let (w, h) = (width as usize, height as usize);
        Ok(Self {
            x: vec![0.0; w],
            y: vec![0.0; h],
            col_max: vec![0.0; w],
            row_max: vec![0.0; h],
            density_x: vec![1.0; w],
            density_y: vec![1.0; h],
            scratch: vec![0.0; w.max(h)],
            has_history: false,
            fallback: [false; 2],
        })
    }

    /// The `u` warp table (`width` texels): texel `i` holds `warp(u)` at
    /// `u = (i + 0.5) / width`. Upload as an `R32Float` 1-D texture.
    #[must_use]
    pub fn x_table(&self) -> &[f32] {
        &self.x
    }

    /// The `v` warp table (`height` texels).
    #[must_use]
    pub fn y_table(&self) -> &[f32] {
        &self.y
    }

    /// Number of texels of the `u` table (the importance map's width).
    #[must_use]
    pub fn width(&self) -> usize {
        self.x.len()
    }

    /// Number of texels of the `v` table (the importance map's height).
    #[must_use]
    pub fn height(&self) -> usize {
        self.y.len()
    }

    /// The final 1-D density along `u` (collapsed, blurred, normalized to a maximum
    /// of 1, temporally smoothed, floored) the `u` table was built from.
    #[must_use]
    pub fn density_x(&self) -> &[f32] {
        &self.density_x
    }

    /// The final 1-D density along `v`.
    #[must_use]
    pub fn density_y(&self) -> &[f32] {
        &self.density_y
    }

    /// The collapsed importance along `u` (the maximum of each column) of the last build.
    #[must_use]
    pub fn column_max(&self) -> &[f32] {
        &self.col_max
    }

    /// The collapsed importance along `v` (the maximum of each row) of the last build.
    #[must_use]
    pub fn row_max(&self) -> &[f32] {
        &self.row_max
    }

    /// Whether the last build fell back to the identity warp along `u` and `v`
    /// because the importance along that axis was zero everywhere.
    #[must_use]
    pub fn identity_fallback(&self) -> [bool; 2] {
        self.fallback
    }

    /// Forgets the previous frame (no temporal smoothing on the next build), for
    /// camera cuts.
    pub fn reset_history(&mut self) {
        self.has_history = false;
    }

    /// Warped texture coordinates `(u + warp_x(u), v + warp_y(v))`, in `f32` exactly
    /// as the shader computes them (see [`forward_warp`]).
    #[must_use]
    pub fn warp_uv(&self, uv: Vec2) -> Vec2 {
        Vec2::new(forward_warp(&self.x, uv.x), forward_warp(&self.y, uv.y))
    }

    /// Base texture coordinates of warped ones (see [`inverse_warp`]).
    #[must_use]
    pub fn unwarp_uv(&self, warped: Vec2) -> Vec2 {
        Vec2::new(
            inverse_warp(&self.x, warped.x),
            inverse_warp(&self.y, warped.y),
        )
    }

    /// Builds both warp tables from an importance map: one streaming pass collapses
    /// it to the column and row maxima, then per axis (1-D, cheap): Gaussian blur,
    /// normalization to a maximum of 1, temporal smoothing with the previous
    /// frame's density, floor, and Rosen's warp (see the crate docs).
    ///
    /// An axis whose importance is zero everywhere falls back to the identity warp
    /// ([`identity_fallback`](Self::identity_fallback)). On error nothing changes.
    ///
    /// # Errors
    /// [`RtwError::ShapeMismatch`] if the map's size differs from the one these warp
    /// maps were created for; [`RtwError::InvalidOption`] for bad options.
    pub fn build(&mut self, map: &ImportanceMap, options: &WarpOptions) -> Result<(), RtwError> {
        options.validate()?;
        if map.width() as usize != self.x.len() || map.height() as usize != self.y.len() {
            return Err(RtwError::ShapeMismatch);
        }
        collapse(map.as_slice(), &mut self.col_max, &mut self.row_max);
        self.build_from_collapsed(options);
        Ok(())
    }

    /// [`build`](Self::build) with separate importance per axis: the `u` warp from the
    /// column maxima of `map_u`, the `v` warp from the row maxima of `map_v` (for
    /// example the two maps of [`ImportanceMap::accumulate_oracle_axis`]).
    ///
    /// # Errors
    /// As [`build`](Self::build), for either map.
    pub fn build_separable(
        &mut self,
        map_u: &ImportanceMap,
        map_v: &ImportanceMap,
        options: &WarpOptions,
    ) -> Result<(), RtwError> {
        options.validate()?;
        for map in [map_u, map_v] {
            if map.width() as usize != self.x.len() || map.height() as usize != self.y.len() {
                return Err(RtwError::ShapeMismatch);
            }
        }
        // Only the column maxima of the u map and the row maxima of the v map feed a
        // warp; the other halves of the two collapses are not computed.
        let w = self.col_max.len();
        self.col_max.fill(0.0);
        for row in map_u.as_slice().chunks_exact(w) {
            for (c, &x) in self.col_max.iter_mut().zip(row) {
                *c = mx(*c, x);
            }
        }
        for (r, row) in self
            .row_max
            .iter_mut()
            .zip(map_v.as_slice().chunks_exact(w))
        {
            *r = row.iter().copied().fold(0.0, mx);
        }
        self.build_from_collapsed(options);
        Ok(())
    }

    fn build_from_collapsed(&mut self, options: &WarpOptions) {
        let weights = gaussian_weights(options.blur_radius);
        let history = self.has_history;
        self.fallback[0] = axis(
            &self.col_max,
            &weights,
            options,
            history,
            &mut self.scratch,
            &mut self.density_x,
            &mut self.x,
        );
        self.fallback[1] = axis(
            &self.row_max,
            &weights,
            options,
            history,
            &mut self.scratch,
            &mut self.density_y,
            &mut self.y,
        );
        self.has_history = true;
    }
}

/// Column maxima and row maxima in one streaming pass. Values are finite and
/// non-negative (an [`ImportanceMap`] invariant), so a plain compare is a max.
///
/// Each element is loaded once and goes into two maxima: its column's (the column
/// accumulator, a few KiB, stays in L1) and its row's (sixteen independent lanes, so
/// the loop vectorizes and is not bound by the latency of one dependency chain).
fn collapse(cells: &[f32], col_max: &mut [f32], row_max: &mut [f32]) {
    let w = col_max.len();
    col_max.fill(0.0);
    if w == 0 {
        return;
    }
    for (row, out) in cells.chunks_exact(w).zip(row_max.iter_mut()) {
        *out = collapse_row(row, col_max);
    }
}

#[inline(always)]
fn mx(a: f32, b: f32) -> f32 {
    if b > a { b } else { a }
}

type V4 = [f32; 4];

#[inline(always)]
fn v4(chunk: &[f32]) -> V4 {
    // Chunks come from `chunks_exact(4)`: the fallback is never taken.
    chunk.try_into().unwrap_or([0.0; 4])
}

#[inline(always)]
fn vmax(a: V4, b: V4) -> V4 {
    [
        mx(a[0], b[0]),
        mx(a[1], b[1]),
        mx(a[2], b[2]),
        mx(a[3], b[3]),
    ]
}

fn collapse_row(row: &[f32], col_max: &mut [f32]) -> f32 {
    let mut acc = [[0.0f32; 4]; 4];
    let mut cols = col_max.chunks_exact_mut(16);
    let mut vals = row.chunks_exact(16);
    for (c, x) in (&mut cols).zip(&mut vals) {
        let (c0, c) = c.split_at_mut(4);
        let (c1, c) = c.split_at_mut(4);
        let (c2, c3) = c.split_at_mut(4);
        let (x0, x1, x2, x3) = (v4(&x[..4]), v4(&x[4..8]), v4(&x[8..12]), v4(&x[12..]));
        acc[0] = vmax(acc[0], x0);
        acc[1] = vmax(acc[1], x1);
        acc[2] = vmax(acc[2], x2);
        acc[3] = vmax(acc[3], x3);
        c0.copy_from_slice(&vmax(v4(c0), x0));
        c1.copy_from_slice(&vmax(v4(c1), x1));
        c2.copy_from_slice(&vmax(v4(c2), x2));
        c3.copy_from_slice(&vmax(v4(c3), x3));
    }
    let a = vmax(vmax(acc[0], acc[1]), vmax(acc[2], acc[3]));
    let mut m = mx(mx(a[0], a[1]), mx(a[2], a[3]));
    for (c, &x) in cols.into_remainder().iter_mut().zip(vals.remainder()) {
        m = mx(m, x);
        *c = mx(*c, x);
    }
    m
}

/// The blur of [`WarpMaps::build`]: normalized Gaussian weights `w[0..=radius]` of a
/// symmetric kernel, so a GPU port can upload exactly the weights the CPU uses.
///
/// ```text
/// w_k = exp(-k² / (2 sigma²)) / total,   sigma = radius / 2,   w_0 + 2 Σ_{k≥1} w_k = 1
/// ```
///
/// `radius` is clamped to [`MAX_BLUR_RADIUS`]; radius 0 gives `[1]`.
#[must_use]
pub fn gaussian_weights(radius: u32) -> ArrayVec<f64, { MAX_BLUR_RADIUS as usize + 1 }> {
    let r = radius.min(MAX_BLUR_RADIUS) as usize;
    let mut w = ArrayVec::new();
    if r == 0 {
        w.push(1.0);
        return w;
    }
    let sigma = r as f64 / 2.0;
    for k in 0..=r {
        let k = k as f64;
        w.push(math::exp(-k * k / (2.0 * sigma * sigma)));
    }
    let total: f64 = w[0] + 2.0 * w[1..].iter().sum::<f64>();
    for x in &mut w {
        *x /= total;
    }
    w
}

/// One axis: blur, normalize, temporal, floor into `density`, then the table.
/// Returns whether it fell back to the identity (zero importance).
fn axis(
    src: &[f32],
    weights: &[f64],
    options: &WarpOptions,
    history: bool,
    scratch: &mut [f64],
    density: &mut [f32],
    table: &mut [f32],
) -> bool {
    let n = src.len();
    let Some(scratch) = scratch.get_mut(..n) else {
        return false;
    };
    let last = n as isize - 1;
    let mut max = 0.0f64;
    let r = weights.len().saturating_sub(1);
    for (i, out) in scratch.iter_mut().enumerate() {
        let acc = match (weights.split_first(), i.checked_sub(r), src.get(i + r)) {
            // Interior: no clamping.
            (Some((&w0, rest)), Some(_), Some(_)) => {
                let mut acc = w0 * f64::from(src[i]);
                for (k, &wk) in rest.iter().enumerate() {
                    acc += wk * (f64::from(src[i - k - 1]) + f64::from(src[i + k + 1]));
                }
                acc
            }
            _ => {
                let at = |j: isize| f64::from(src[j.clamp(0, last) as usize]);
                let mut acc = 0.0;
                for (k, &wk) in weights.iter().enumerate() {
                    let (i, k) = (i as isize, k as isize);
                    acc += if k == 0 {
                        wk * at(i)
                    } else {
                        wk * (at(i - k) + at(i + k))
                    };
                }
                acc
            }
        };
        *out = acc;
        max = max.max(acc);
    }
    let fallback = !(max > 0.0 && max.is_finite());
    let alpha = if history {
        f64::from(options.temporal)
    } else {
        0.0
    };
    let floor = f64::from(options.floor);
    for (d, &s) in density.iter_mut().zip(scratch.iter()) {
        let cur = if fallback { 1.0 } else { s / max };
        let mixed = alpha * f64::from(*d) + (1.0 - alpha) * cur;
        *d = mixed.max(floor).min(1.0) as f32;
    }
    build_table(density, table);
    fallback
}

/// Rosen's warp for a density `d` of `N` cells, with the clamp-to-edge texture
/// semantics (see the crate docs): knots `W_i` at the texel centres `c_i`, `W_0 = c_0`,
/// `W_{N-1} = c_{N-1}`, slope on `[c_k, c_{k+1}]` proportional to `(d_k + d_{k+1}) / 2`.
fn build_table(density: &[f32], table: &mut [f32]) {
    let n = table.len().min(density.len());
    table.fill(0.0);
    if n < 2 {
        return;
    }
    let first = density[0];
    if density[..n].iter().all(|&d| d == first) {
        return; // constant importance: exactly the identity
    }
    let nf = n as f64;
    let total: f64 = density[..n]
        .windows(2)
        .map(|p| 0.5 * (f64::from(p[0]) + f64::from(p[1])))
        .sum();
    if !(total > 0.0 && total.is_finite()) {
        return;
    }
    let scale = ((nf - 1.0) / nf) / total;
    let c = |i: usize| (i as f64 + 0.5) / nf;
    let c0 = c(0);
    let end = c(n - 1);
    // Knots from the cumulative sum (f64), stored as offsets in f32.
    let mut cum = 0.0;
    for (k, (t, pair)) in table[1..n - 1]
        .iter_mut()
        .zip(density.windows(2))
        .enumerate()
    {
        cum += 0.5 * (f64::from(pair[0]) + f64::from(pair[1]));
        *t = (c0 + cum * scale - c(k + 1)) as f32;
    }
    // Rounding to f32 must not reorder the knots or pass the last one. Where the
    // warp is nearly flat, consecutive knots are closer than an ulp of their offset, so
    // repair in two passes: forward, raise a knot below its predecessor; backward,
    // lower a knot above its successor (the last knot is `end`). Neither pass has a
    // loop-carried dependency unless a repair is needed, which is rare.
    let mut prev_knot = c0;
    for (k, t) in table.iter_mut().enumerate().take(n - 1).skip(1) {
        let ck = c(k);
        if ck + f64::from(*t) < prev_knot {
            *t = offset_at_least(ck, prev_knot);
        }
        prev_knot = ck + f64::from(*t);
    }
    let mut next_knot = end;
    for (k, t) in table.iter_mut().enumerate().take(n - 1).skip(1).rev() {
        let ck = c(k);
        if ck + f64::from(*t) > next_knot {
            *t = offset_at_most(ck, next_knot);
        }
        next_knot = ck + f64::from(*t);
    }
}

/// The smallest `f32` offset `t` with `c + t >= target`.
fn offset_at_least(c: f64, target: f64) -> f32 {
    let mut t = (target - c) as f32;
    for _ in 0..8 {
        if c + f64::from(t) >= target {
            break;
        }
        t = next_toward(t, true);
    }
    t
}

/// The largest `f32` offset `t` with `c + t <= target`.
fn offset_at_most(c: f64, target: f64) -> f32 {
    let mut t = (target - c) as f32;
    for _ in 0..8 {
        if c + f64::from(t) <= target {
            break;
        }
        t = next_toward(t, false);
    }
    t
}

/// The next `f32` up (`up`) or down from a finite `x`.
fn next_toward(x: f32, up: bool) -> f32 {
    if x == 0.0 {
        let tiny = f32::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    let bits = x.to_bits();
    let away = (x > 0.0) == up;
    f32::from_bits(if away { bits + 1 } else { bits - 1 })
}

/// An RTW shadow map as a technique: the base projection, then each texture axis
/// warped by its table. Depth comes from the base projection unchanged.
///
/// [`ShadowMapping::map_point`] evaluates the warp in `f64` ([`forward_warp_f64`],
/// the same piecewise-linear function the shader evaluates in `f32`) so the
/// evaluation harness gets accurate Jacobians.
#[derive(Clone, Copy, Debug)]
pub struct RtwShadow<'a> {
    /// The base (uniform, focused) projection.
    pub base: ShadowTransform,
    /// The warp tables.
    pub warps: &'a WarpMaps,
}

impl ShadowMapping for RtwShadow<'_> {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        self.warps.warp_sample(self.base.map_point(world)?)
    }
}

impl WarpMaps {
    /// How much the warp magnifies base texture space at `uv`: the slopes
    /// `(d u' / d u, d v' / d v)` of the piecewise-linear warp there (1 outside the
    /// tables' texel centres, where it is a translation). A map of `N` texels per side
    /// has `N` times these texels per unit of base `uv`.
    #[must_use]
    pub fn magnification(&self, uv: glam::DVec2) -> glam::DVec2 {
        glam::DVec2::new(warp_slope(&self.x, uv.x), warp_slope(&self.y, uv.y))
    }

    /// A base map's sample with its `uv` warped by these tables (in `f64`, the
    /// function the shader evaluates in `f32`); depth and layer unchanged. `None` for
    /// a non-finite result. Any base mapping (a matrix, a paraboloid side) is warped
    /// this way.
    #[must_use]
    pub fn warp_sample(&self, sample: ShadowSample) -> Option<ShadowSample> {
        let uv = glam::DVec2::new(
            forward_warp_f64(&self.x, sample.uv.x),
            forward_warp_f64(&self.y, sample.uv.y),
        );
        uv.is_finite().then_some(ShadowSample { uv, ..sample })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collapse_takes_row_and_column_maxima() {
        for (w, h) in [(11, 3), (11, 9), (16, 4), (1, 5), (25, 1)] {
            check_collapse(w, h);
        }
    }

    fn check_collapse(w: usize, h: usize) {
        let cells: Vec<f32> = (0..w * h).map(|i| ((i * 7) % 13) as f32).collect();
        let mut cm = vec![0.0; w];
        let mut rm = vec![0.0; h];
        collapse(&cells, &mut cm, &mut rm);
        for x in 0..w {
            let m = (0..h).map(|y| cells[y * w + x]).fold(0.0, f32::max);
            assert_eq!(cm[x], m);
        }
        for y in 0..h {
            let m = cells[y * w..(y + 1) * w]
                .iter()
                .copied()
                .fold(0.0, f32::max);
            assert_eq!(rm[y], m);
        }
    }

    #[test]
    fn gaussian_weights_sum_to_one() {
        for r in [0, 1, 5, MAX_BLUR_RADIUS] {
            let w = gaussian_weights(r);
            let s = w[0] + 2.0 * w[1..].iter().sum::<f64>();
            assert!((s - 1.0).abs() < 1e-12);
            assert_eq!(w.len(), r as usize + 1);
        }
    }

    #[test]
    fn zero_importance_falls_back_to_identity() {
        let map = ImportanceMap::new(8, 5).unwrap();
        let mut w = WarpMaps::new(8, 5).unwrap();
        w.build(&map, &WarpOptions::default()).unwrap();
        assert_eq!(w.identity_fallback(), [true, true]);
        assert!(w.x_table().iter().chain(w.y_table()).all(|&t| t == 0.0));
    }

    #[test]
    fn bad_options_and_shapes_are_errors() {
        let map = ImportanceMap::new(8, 5).unwrap();
        let mut w = WarpMaps::new(8, 4).unwrap();
        assert_eq!(
            w.build(&map, &WarpOptions::default()),
            Err(RtwError::ShapeMismatch)
        );
        let mut w = WarpMaps::new(8, 5).unwrap();
        for o in [
            WarpOptions::default().with_floor(0.0),
            WarpOptions::default().with_floor(f32::NAN),
            WarpOptions::default().with_temporal(1.0),
            WarpOptions::default().with_blur_radius(MAX_BLUR_RADIUS + 1),
        ] {
            assert_eq!(w.build(&map, &o), Err(RtwError::InvalidOption));
        }
        assert_eq!(WarpMaps::new(0, 1), Err(RtwError::EmptyMap));
    }

    #[test]
    fn spike_gets_more_texels_and_ends_are_fixed() {
        let mut map = ImportanceMap::new(16, 1).unwrap();
        map.set(5, 0, 1.0).unwrap();
        let mut w = WarpMaps::new(16, 1).unwrap();
        w.build(
            &map,
            &WarpOptions::default().with_blur_radius(0).with_floor(0.01),
        )
        .unwrap();
        let t = w.x_table();
        assert_eq!((t[0], t[15]), (0.0, 0.0));
        assert_eq!(forward_warp(t, 0.0), 0.0);
        assert_eq!(forward_warp(t, 1.0), 1.0);
        // The segments between the centres of cells 4 and 6 touch the spike: they get
        // (1.01 / 1.14) * 15/16 of the warped range.
        let span = forward_warp_f64(t, 6.5 / 16.0) - forward_warp_f64(t, 4.5 / 16.0);
        assert!(
            (span - 1.01 / 1.14 * 15.0 / 16.0).abs() < 1e-6,
            "span {span}"
        );
    }

    #[test]
    fn temporal_smoothing_mixes_frames() {
        let mut a = ImportanceMap::new(4, 1).unwrap();
        a.copy_from_slice(&[1.0, 0.0, 0.0, 0.0]).unwrap();
        let mut b = ImportanceMap::new(4, 1).unwrap();
        b.copy_from_slice(&[0.0, 0.0, 0.0, 1.0]).unwrap();
        let opts = WarpOptions::default()
            .with_blur_radius(0)
            .with_floor(0.1)
            .with_temporal(0.5);
        let mut w = WarpMaps::new(4, 1).unwrap();
        w.build(&a, &opts).unwrap();
        assert_eq!(w.density_x(), &[1.0, 0.1, 0.1, 0.1]);
        w.build(&b, &opts).unwrap();
        assert_eq!(w.density_x(), &[0.5, 0.1, 0.1, 0.55]);
        w.reset_history();
        w.build(&b, &opts).unwrap();
        assert_eq!(w.density_x(), &[0.1, 0.1, 0.1, 1.0]);
    }

    /// The magnification is the warp's slope: it follows the density (the warp gives
    /// a cell a share of the map in proportion to its density) and is 1 outside the
    /// texel centres.
    #[test]
    fn magnification_is_the_slope_of_the_warp() {
        let mut m = ImportanceMap::new(8, 2).unwrap();
        m.copy_from_slice(&[
            4.0, 4.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
        ])
        .unwrap();
        let opts = WarpOptions::default().with_blur_radius(0).with_floor(0.01);
        let mut w = WarpMaps::new(8, 2).unwrap();
        w.build(&m, &opts).unwrap();
        for u in [0.2, 0.33, 0.5, 0.61, 0.8] {
            let h = 1e-7;
            let slope = (forward_warp_f64(w.x_table(), u + h)
                - forward_warp_f64(w.x_table(), u - h))
                / (2.0 * h);
            let mag = w.magnification(glam::DVec2::new(u, 0.5));
            assert!((mag.x - slope).abs() < 1e-6, "{u}: {mag} {slope}");
        }
        // Dense columns (0, 1) get four times the texels of the others.
        let dense = w.magnification(glam::DVec2::new(0.125, 0.5)).x;
        let sparse = w.magnification(glam::DVec2::new(0.7, 0.5)).x;
        assert!((dense / sparse - 4.0).abs() < 0.05, "{dense} {sparse}");
        assert_eq!(
            w.magnification(glam::DVec2::new(0.01, 0.9)),
            glam::DVec2::ONE
        );
    }

    /// Fuzz regression: a nearly flat tail (floor 1e-6) packs many knots closer than
    /// an ulp of their offsets just below the last knot.
    #[test]
    fn flat_tail_keeps_knots_ordered() {
        let mut density = vec![1e-6f32; 229];
        density[..30].fill(1.0);
        let mut table = vec![0.0; 229];
        build_table(&density, &mut table);
        let n = table.len() as f64;
        let knots: Vec<f64> = (0..table.len())
            .map(|i| (i as f64 + 0.5) / n + f64::from(table[i]))
            .collect();
        assert!(knots.windows(2).all(|k| k[0] <= k[1]), "{knots:?}");
        assert_eq!((table[0], table[228]), (0.0, 0.0));
    }

    #[test]
    fn technique_warps_the_base_uv() {
        use glam::{Mat4, Vec3};
        use shadowmap_frustum::LightDirection;
        // uv = (x, y) directly.
        let clip = Mat4::from_cols_array(&[
            2.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0,
        ]);
        let dir = LightDirection::Directional(Vec3::NEG_Z);
        let base = ShadowTransform::new(Mat4::IDENTITY, clip, false, dir);
        let mut map = ImportanceMap::new(8, 8).unwrap();
        map.splat(Vec2::new(0.3, 0.8), 1.0).unwrap();
        let mut warps = WarpMaps::new(8, 8).unwrap();
        warps.build(&map, &WarpOptions::default()).unwrap();
        let rtw = RtwShadow {
            base,
            warps: &warps,
        };
        let s = rtw.map_point(DVec3::new(0.3, 0.6, 0.25)).unwrap();
        let b = base.map_point(DVec3::new(0.3, 0.6, 0.25)).unwrap();
        assert!((s.uv.x - forward_warp_f64(warps.x_table(), b.uv.x)).abs() < 1e-15);
        assert!((s.uv.y - forward_warp_f64(warps.y_table(), b.uv.y)).abs() < 1e-15);
        assert!((s.uv.x - b.uv.x).abs() > 1e-3, "the warp moved u");
        assert_eq!(s.depth, b.depth);
        let w = warps.warp_uv(Vec2::new(0.3, 0.6));
        assert!(
            (warps.unwarp_uv(w) - Vec2::new(0.3, 0.6))
                .abs()
                .max_element()
                < 1e-5
        );
    }

    #[test]
    fn next_toward_steps_one_ulp() {
        assert!(next_toward(1.0, true) > 1.0);
        assert!(next_toward(-1.0, true) > -1.0);
        assert!(next_toward(0.0, false) < 0.0);
        assert!(next_toward(1.0, false) < 1.0);
    }
}
