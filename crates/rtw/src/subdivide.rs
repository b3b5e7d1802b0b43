//! Caster subdivision for RTW's depth pass.
//!
//! The depth pass of rectilinear texture warping (Rosen, *Rectilinear Texture Warping
//! for Fast Adaptive Shadow Mapping*, I3D 2012) warps vertices only, and the warp is
//! piecewise linear between the tables' texel centres, so a long caster edge stays
//! straight where the warped map bends it. [`subdivide_for_rtw`] splits edges until
//! their straight warped images follow the warp within a bound in map texels. The
//! split of an edge depends on its two endpoints alone, so shared edges split alike and
//! a conforming mesh stays conforming (no T-junctions, hence no cracks): the same
//! property as the paraboloid subdivision of `shadowmap-paraboloid`. Both the CPU
//! reference rasterizer and the GPU depth pass render the mesh this function returns;
//! the compute refinement of `shadowmap-wgpu` is its twin on the GPU (the same rule,
//! [`RtwSubdivision::split_rule`], and the same pieces, evaluated in `f32`).

use alloc::vec::Vec;

use arrayvec::ArrayVec;
use glam::{DVec2, Vec3};

use crate::{RtwShadow, WarpMaps, forward_warp_f64};

/// How finely [`subdivide_for_rtw`] splits casters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
#[non_exhaustive]
pub struct RtwSubdivision {
    /// Texels per side of the shadow map the casters are rendered into (the error
    /// bound is in its texels), `>= 1`. Default 1024.
    pub resolution: u32,
    /// Largest distance, in map texels, between the warped midpoint of an edge
    /// and the midpoint of its straight warped image, `>= 1/64`. Default 0.25:
    /// straight pieces that miss the bent warp by more leave acne smudges on steep
    /// receivers (the slope-scaled bias absorbs less).
    pub max_error_texels: f64,
    /// Longest piece, in warp-table cells (`max(|du| N_u, |dv| N_v)` in base texture
    /// space), `>= 1/64`, whatever the midpoint error: a midpoint test cannot see
    /// kinks that cancel out over a long edge. Default 2.
    pub max_span_cells: f64,
    /// Most pieces an original edge is cut into, in `1..=1024` (rounded up to a power
    /// of two): caps the triangle count at `max_segments²` per caster. Default 32.
    /// The cost is real: the city block (5264 triangles) over 256-cell tables into a
    /// 2048² map under a strong warp becomes 0.72 M triangles in 64 ms with the
    /// defaults, 4.8 M in 1.1 s with a cap of 256 (`cargo bench -p shadowmap-wgpu --bench frame`).
    pub max_segments: u32,
}

impl Default for RtwSubdivision {
    fn default() -> Self {
        Self {
            resolution: 1024,
            max_error_texels: 0.25,
            max_span_cells: 2.0,
            max_segments: 32,
        }
    }
}

impl RtwSubdivision {
    /// For a map of this many texels per side.
    #[must_use]
    pub const fn with_resolution(mut self, resolution: u32) -> Self {
        self.resolution = resolution;
        self
    }
    /// With this midpoint error bound, in map texels.
    #[must_use]
    pub const fn with_max_error_texels(mut self, texels: f64) -> Self {
        self.max_error_texels = texels;
        self
    }
    /// With this longest piece, in table cells.
    #[must_use]
    pub const fn with_max_span_cells(mut self, cells: f64) -> Self {
        self.max_span_cells = cells;
        self
    }
    /// With this cap on pieces per edge.
    #[must_use]
    pub const fn with_max_segments(mut self, max_segments: u32) -> Self {
        self.max_segments = max_segments;
        self
    }

    /// With the cap on pieces per edge that lets an edge spanning `extent` units of
    /// base texture space (per axis) reach the span bound over tables of `cells`
    /// texels: `ceil(extent * cells / max_span_cells)` pieces, at least the
    /// current cap, at most 1024.
    ///
    /// The default cap suits a base whose visible part fits the map (an orthographic
    /// or spot fit). A base whose casters span more of it, such as a paraboloid side
    /// whose front hemisphere fills a disc of diameter `1 / zoom`, needs more: with
    /// the default, a ground tile under a point light stays in pieces many cells
    /// long whose straight warped images miss the warp by texels, and the surface
    /// shadows itself.
    #[must_use]
    pub fn with_segments_for_extent(mut self, extent: f64, cells: usize) -> Self {
        let defaults = Self::default();
        let span = if self.max_span_cells.is_nan() {
            defaults.max_span_cells
        } else {
            self.max_span_cells.max(1.0 / 64.0)
        };
        let need = shadowmap_frustum::math::ceil(extent * cells as f64 / span);
        if need.is_finite() && need > f64::from(self.max_segments) {
            self.max_segments = need.min(1024.0) as u32;
        }
        self
    }
}

/// The numbers the split rule of [`subdivide_for_rtw`] runs on, its options clamped
/// to their documented ranges: what a GPU twin of the subdivision (the compute
/// refinement of `shadowmap-wgpu`) needs to decide exactly as the CPU does.
///
/// ```text
/// split edge a b  <=>  max(|du| pieces.x, |dv| pieces.y) > 1
///                  or  max|W(uv(mid)) - (W(uv(a)) + W(uv(b))) / 2| * error_scale > 1
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RtwSplitRule {
    /// Pieces per unit of base texture space along `u` and `v`: table texels over
    /// the longest piece in cells.
    pub pieces: DVec2,
    /// Map texels over the error bound (warped-uv error times this above 1 splits).
    pub error_scale: f64,
    /// Halvings of an original edge, `ceil(log2(max_segments))`, in `0..=10`.
    pub levels: u32,
}

impl RtwSubdivision {
    /// The split rule for tables of `u_texels` and `v_texels` texels. Out-of-range
    /// options are clamped (NaN: the default), as in [`subdivide_for_rtw`].
    #[must_use]
    pub fn split_rule(&self, u_texels: usize, v_texels: usize) -> RtwSplitRule {
        let defaults = Self::default();
        let at_least = |x: f64, default: f64| {
            if x.is_nan() {
                default
            } else {
                x.clamp(1.0 / 64.0, f64::MAX)
            }
        };
        let max_span = at_least(self.max_span_cells, defaults.max_span_cells);
        let max_error = at_least(self.max_error_texels, defaults.max_error_texels);
        RtwSplitRule {
            pieces: DVec2::new(u_texels as f64, v_texels as f64) / max_span,
            error_scale: f64::from(self.resolution.max(1)) / max_error,
            levels: self
                .max_segments
                .clamp(1, 1024)
                .next_power_of_two()
                .trailing_zeros(),
        }
    }
}

/// Splits triangles for the RTW depth pass, which warps only vertices: the warp is
/// piecewise linear between the tables' texel centres, so a long edge stays straight
/// where the warped map bends it. An edge is halved when it spans more than
/// `max_span_cells` table cells or its warped midpoint lies more than
/// `max_error_texels` map texels from the midpoint of its straight warped image;
/// the pieces are tested again, until the original edge has been halved
/// `ceil(log2(max_segments))` times. Out-of-range options are clamped to their
/// documented ranges (NaN: the default). Writes into `out` (cleared first) and
/// returns its length.
///
/// Whether an edge splits depends on its two endpoints alone, and its midpoint is
/// symmetric in them, so two triangles sharing an edge split it identically: a
/// conforming mesh stays conforming (no T-junctions, hence no cracks between warped
/// neighbours). A triangle with one edge split becomes 2, two edges 3, three edges
/// 4 (the midpoint triangle), each recursed into.
///
/// Triangles with a vertex the base projection cannot map (behind a perspective
/// light) or with non-finite vertices are dropped: a depth pass that warps vertices
/// cannot place them (a perspective base wraps them around), and the reference
/// rasterizer of `shadowmap-eval` drops them too.
pub fn subdivide_for_rtw(
    shadow: &RtwShadow<'_>,
    triangles: &[[Vec3; 3]],
    options: &RtwSubdivision,
    out: &mut Vec<[Vec3; 3]>,
) -> usize {
    let base = |p: Vec3| shadow.base.project(p).map(|s| s.uv);
    subdivide_for_rtw_with(base, shadow.warps, triangles, options, out)
}

/// [`subdivide_for_rtw`] over any base mapping: `base_uv` gives a world point's
/// texture coordinates in the base map (one paraboloid side, one cube face, ...),
/// `None` where it cannot map it; `warps` are that map's tables. The split rule
/// measures the warped image of the base, so it also follows a curved base (a
/// paraboloid) as far as the pieces and the error bound allow.
pub fn subdivide_for_rtw_with(
    base_uv: impl Fn(Vec3) -> Option<DVec2>,
    warps: &WarpMaps,
    triangles: &[[Vec3; 3]],
    options: &RtwSubdivision,
    out: &mut Vec<[Vec3; 3]>,
) -> usize {
    subdivide_for_rtw_clipped(base_uv, &[], warps, triangles, options, out)
}

/// Most clip planes of [`subdivide_for_rtw_clipped`].
pub const MAX_CLIP_PLANES: usize = 6;

/// A clip plane of [`subdivide_for_rtw_clipped`]: the signed distance of a world
/// point to the plane (any positive scale), an affine function of the point,
/// negative on the side that is clipped.
pub type ClipPlane<'a> = &'a dyn Fn(Vec3) -> f64;

/// [`subdivide_for_rtw_with`] for a base that stores only the region in front of some
/// planes (a paraboloid side: in front of the light's plane; a perspective face:
/// inside its window's frustum). `planes` (the first [`MAX_CLIP_PLANES`]) bound that
/// region ([`ClipPlane`]).
///
/// Triangles wholly behind a plane are left out; triangles across one are clipped
/// first (their part in front of every plane, a convex polygon of at most
/// `3 + planes` vertices, as the fan of triangles from its first vertex), then
/// split. Behind a paraboloid side the base coordinates run off toward the pole,
/// behind a perspective base they do not exist, and beside a perspective window they
/// only cost pieces the depth pass clips: the split rule would spend levels of every
/// edge on geometry the depth pass discards, or leave a caster unsplit. An edge is
/// cut at the point interpolated from its end in front, so two triangles sharing it
/// cut it alike (no cracks).
pub fn subdivide_for_rtw_clipped(
    base_uv: impl Fn(Vec3) -> Option<DVec2>,
    planes: &[ClipPlane<'_>],
    warps: &WarpMaps,
    triangles: &[[Vec3; 3]],
    options: &RtwSubdivision,
    out: &mut Vec<[Vec3; 3]>,
) -> usize {
    out.clear();
    let rule = options.split_rule(warps.x_table().len(), warps.y_table().len());
    let splitter = RtwSplitter {
        base_uv,
        warps,
        pieces: rule.pieces,
        error_scale: rule.error_scale,
    };
    let levels = rule.levels;
    let planes = planes.get(..MAX_CLIP_PLANES).unwrap_or(planes);
    for &t in triangles {
        for piece in cut_at_planes(t, planes) {
            if piece
                .iter()
                .all(|p| p.is_finite() && splitter.uv(*p).is_some())
            {
                splitter.split(piece, levels, out);
            }
        }
    }
    out.len()
}

/// Most vertices of a triangle clipped by [`MAX_CLIP_PLANES`] planes (each plane
/// adds at most one to a convex polygon).
const MAX_CLIPPED_VERTICES: usize = 3 + MAX_CLIP_PLANES;

/// The part of a triangle in front of every plane, as the fan of its clipped
/// polygon from the polygon's first vertex (same winding; nothing when no part is
/// in front).
fn cut_at_planes(
    t: [Vec3; 3],
    planes: &[ClipPlane<'_>],
) -> impl Iterator<Item = [Vec3; 3]> + use<> {
    let mut polygon: ArrayVec<Vec3, MAX_CLIPPED_VERTICES> = t.into_iter().collect();
    for plane in planes {
        polygon = clip_polygon(&polygon, *plane);
    }
    let first = polygon.first().copied().unwrap_or(Vec3::ZERO);
    (1..polygon.len().saturating_sub(1)).map(move |k| [first, polygon[k], polygon[k + 1]])
}

/// One Sutherland-Hodgman step: the part of a convex polygon in front of the plane
/// where `distance >= 0`, walking its edges in order and keeping the vertices in
/// front and the crossings, each interpolated from the edge's end in front (so two
/// triangles sharing an edge cut it at the same point). For a triangle this is the
/// triangle itself, nothing, or the triangle or quad whose fan is one or two
/// triangles.
fn clip_polygon(polygon: &[Vec3], distance: ClipPlane<'_>) -> ArrayVec<Vec3, MAX_CLIPPED_VERTICES> {
    let mut out = ArrayVec::new();
    let n = polygon.len();
    let mut d: ArrayVec<f64, MAX_CLIPPED_VERTICES> = ArrayVec::new();
    d.extend(polygon.iter().map(|p| distance(*p)));
    for i in 0..n {
        let j = (i + 1) % n;
        let (front_i, front_j) = (d[i] >= 0.0, d[j] >= 0.0);
        if front_i {
            let _ = out.try_push(polygon[i]);
        }
        if front_i != front_j {
            let (a, b, da, db) = if front_i {
                (polygon[i], polygon[j], d[i], d[j])
            } else {
                (polygon[j], polygon[i], d[j], d[i])
            };
            let s = da / (da - db);
            let _ = out.try_push((a.as_dvec3() + (b.as_dvec3() - a.as_dvec3()) * s).as_vec3());
        }
    }
    out
}

/// The per-edge split rule of [`subdivide_for_rtw`].
struct RtwSplitter<'a, F> {
    base_uv: F,
    warps: &'a WarpMaps,
    /// Pieces per unit of base texture space along `u` and `v` (table texels over
    /// the longest piece in cells).
    pieces: DVec2,
    /// Map texels over the error bound: warped-uv error times this above 1 splits.
    error_scale: f64,
}

impl<F: Fn(Vec3) -> Option<DVec2>> RtwSplitter<'_, F> {
    fn uv(&self, p: Vec3) -> Option<DVec2> {
        (self.base_uv)(p).filter(|uv| uv.is_finite())
    }

    fn warp(&self, uv: DVec2) -> DVec2 {
        DVec2::new(
            forward_warp_f64(self.warps.x_table(), uv.x),
            forward_warp_f64(self.warps.y_table(), uv.y),
        )
    }

    /// The midpoint of `a b` if the edge is longer than a piece or its straight
    /// warped image misses the warped midpoint by more than the bound. Symmetric
    /// in `a, b`: both triangles of a shared edge decide alike and get the same
    /// point.
    fn midpoint(&self, a: Vec3, b: Vec3) -> Option<Vec3> {
        let (ua, ub) = (self.uv(a)?, self.uv(b)?);
        let mid = ((a.as_dvec3() + b.as_dvec3()) * 0.5).as_vec3();
        let span = ((ub - ua).abs() * self.pieces).max_element();
        if span > 1.0 {
            return Some(mid);
        }
        let chord = (self.warp(ua) + self.warp(ub)) * 0.5;
        let error = (self.warp(self.uv(mid)?) - chord).abs().max_element();
        (error * self.error_scale > 1.0).then_some(mid)
    }

    fn split(&self, t: [Vec3; 3], levels: u32, out: &mut Vec<[Vec3; 3]>) {
        let [a, b, c] = t;
        if levels == 0 {
            out.push(t);
            return;
        }
        let next = levels - 1;
        let mid = [
            self.midpoint(a, b),
            self.midpoint(b, c),
            self.midpoint(c, a),
        ];
        // Rotate so the split edges come first (same winding throughout).
        match mid {
            [None, None, None] => out.push(t),
            [Some(m), None, None] => self.split_one([a, b, c], m, next, out),
            [None, Some(m), None] => self.split_one([b, c, a], m, next, out),
            [None, None, Some(m)] => self.split_one([c, a, b], m, next, out),
            [Some(m), Some(n), None] => self.split_two([a, b, c], m, n, next, out),
            [None, Some(m), Some(n)] => self.split_two([b, c, a], m, n, next, out),
            [Some(n), None, Some(m)] => self.split_two([c, a, b], m, n, next, out),
            [Some(ab), Some(bc), Some(ca)] => {
                for piece in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                    self.split(piece, next, out);
                }
            }
        }
    }

    /// `[a, b, c]` with `m` the midpoint of `a b`.
    fn split_one(&self, [a, b, c]: [Vec3; 3], m: Vec3, levels: u32, out: &mut Vec<[Vec3; 3]>) {
        self.split([a, m, c], levels, out);
        self.split([m, b, c], levels, out);
    }

    /// `[a, b, c]` with `m` the midpoint of `a b` and `n` that of `b c`: the corner
    /// `m b n`, and the quad `a m n c` cut along its shorter diagonal.
    fn split_two(
        &self,
        [a, b, c]: [Vec3; 3],
        m: Vec3,
        n: Vec3,
        levels: u32,
        out: &mut Vec<[Vec3; 3]>,
    ) {
        self.split([m, b, n], levels, out);
        if a.distance_squared(n) <= m.distance_squared(c) {
            self.split([a, m, n], levels, out);
            self.split([a, n, c], levels, out);
        } else {
            self.split([a, m, c], levels, out);
            self.split([m, n, c], levels, out);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ImportanceMap, RtwShadow, WarpMaps, WarpOptions};
    use glam::{Mat4, Vec2};
    use shadowmap_frustum::{LightDirection, ShadowTransform};

    /// An identity base (`uv = (x, y)` for `x, y` in `[0, 1]`) over 16 x 8 tables.
    fn warps() -> WarpMaps {
        let mut importance = ImportanceMap::new(16, 8).unwrap();
        importance.splat(Vec2::new(0.3, 0.6), 1.0).unwrap();
        let mut warps = WarpMaps::new(16, 8).unwrap();
        warps.build(&importance, &WarpOptions::default()).unwrap();
        warps
    }

    fn shadow(warps: &WarpMaps) -> RtwShadow<'_> {
        // clip x = 2u - 1, y = 1 - 2v: uv_from_world is the identity on x, y.
        let clip_from_world = Mat4::from_cols_array(&[
            2.0, 0.0, 0.0, 0.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0,
        ]);
        let base = ShadowTransform::new(
            Mat4::IDENTITY,
            clip_from_world,
            false,
            LightDirection::Directional(Vec3::NEG_Z),
        );
        RtwShadow { base, warps }
    }

    fn area(t: &[Vec3; 3]) -> f32 {
        0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
    }

    #[test]
    fn pieces_span_at_most_one_cell_and_keep_the_area() {
        let warps = warps();
        let shadow = shadow(&warps);
        let t = [
            Vec3::new(0.05, 0.1, 0.5),
            Vec3::new(0.95, 0.2, 0.5),
            Vec3::new(0.4, 0.9, 0.5),
        ];
        let mut out = Vec::new();
        // Span alone (a huge error bound).
        let one_cell = RtwSubdivision::default()
            .with_max_span_cells(1.0)
            .with_max_error_texels(1e9);
        let n = subdivide_for_rtw(&shadow, &[t], &one_cell, &mut out);
        assert!(n > 16, "split into {n}");
        for piece in &out {
            for (p, q) in [
                (piece[0], piece[1]),
                (piece[1], piece[2]),
                (piece[2], piece[0]),
            ] {
                let span = ((q.x - p.x).abs() * 16.0).max((q.y - p.y).abs() * 8.0);
                assert!(span <= 1.0 + 1e-5, "edge spans {span} cells");
            }
        }
        let total: f32 = out.iter().map(area).sum();
        assert!((total - area(&t)).abs() < 1e-5 * area(&t).max(1.0));
        // The error bound splits further on a fine map; on a one-texel map with a
        // one-texel bound (the warp stays in [0, 1]) it never splits.
        let fine = one_cell.with_max_error_texels(0.25).with_resolution(4096);
        assert!(subdivide_for_rtw(&shadow, &[t], &fine, &mut out) > n);
        let coarse = one_cell.with_max_error_texels(1.0).with_resolution(1);
        assert_eq!(subdivide_for_rtw(&shadow, &[t], &coarse, &mut out), n);
        // Capped: at most 2 halvings per edge, so at most 4^2 pieces.
        let capped = one_cell.with_max_segments(4);
        assert!(subdivide_for_rtw(&shadow, &[t], &capped, &mut out) <= 16);
        let unsplit = one_cell.with_max_segments(1);
        assert_eq!(subdivide_for_rtw(&shadow, &[t], &unsplit, &mut out), 1);
    }

    #[test]
    fn a_shared_edge_splits_identically_on_both_sides() {
        let warps = warps();
        let shadow = shadow(&warps);
        let (p, q) = (Vec3::new(0.1, 0.1, 0.0), Vec3::new(0.9, 0.8, 0.0));
        // Very different third vertices: one side would split far more if the edge
        // were decided per triangle.
        let left = [p, q, Vec3::new(0.12, 0.75, 0.0)];
        let right = [q, p, Vec3::new(0.99, 0.02, 0.0)];
        let on_edge = |tris: &[[Vec3; 3]]| {
            let mut v: Vec<[u32; 3]> = tris
                .iter()
                .flatten()
                .filter(|x| {
                    let d = (q - p).cross(**x - p).length();
                    d < 1e-6
                })
                .map(|x| x.to_array().map(f32::to_bits))
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let mut a = Vec::new();
        let mut b = Vec::new();
        let options = RtwSubdivision::default();
        subdivide_for_rtw(&shadow, &[left], &options, &mut a);
        subdivide_for_rtw(&shadow, &[right], &options, &mut b);
        let (ea, eb) = (on_edge(&a), on_edge(&b));
        assert!(ea.len() > 2, "the shared edge was split");
        assert_eq!(ea, eb);
    }

    /// Pieces wholly behind the clip plane are left out, those in front are kept
    /// and split as without clipping, and a triangle across the plane is cut at it:
    /// its two halves cover it, every piece on its own side.
    #[test]
    fn clipped_pieces_are_left_out_or_cut() {
        let warps = warps();
        let shadow = shadow(&warps);
        let base = |p: Vec3| shadow.base.project(p).map(|s| s.uv);
        let plane = |p: Vec3| f64::from(p.x) - 0.5;
        let options = RtwSubdivision::default().with_max_span_cells(1.0);
        let (mut clipped, mut plain) = (Vec::new(), Vec::new());
        let front = [
            Vec3::new(0.6, 0.1, 0.5),
            Vec3::new(0.9, 0.2, 0.5),
            Vec3::new(0.7, 0.9, 0.5),
        ];
        let behind = front.map(|p| Vec3::new(1.0 - p.x, p.y, p.z));
        let n =
            subdivide_for_rtw_clipped(base, &[&plane], &warps, &[front], &options, &mut clipped);
        assert_eq!(
            n,
            subdivide_for_rtw(&shadow, &[front], &options, &mut plain)
        );
        assert_eq!(clipped, plain);
        let both = [front, behind];
        subdivide_for_rtw_clipped(base, &[&plane], &warps, &both, &options, &mut clipped);
        assert_eq!(clipped, plain);
        let across = [
            Vec3::new(0.1, 0.1, 0.5),
            Vec3::new(0.9, 0.2, 0.5),
            Vec3::new(0.5, 0.9, 0.5),
        ];
        let mut halves = 0.0;
        for side in [1.0, -1.0] {
            let signed = |p: Vec3| side * plane(p);
            subdivide_for_rtw_clipped(base, &[&signed], &warps, &[across], &options, &mut clipped);
            assert!(clipped.len() > 4);
            assert!(clipped.iter().flatten().all(|p| signed(*p) >= -1e-6));
            // Same winding as the input.
            let normal = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).z;
            assert!(clipped.iter().all(|t| normal(t) >= 0.0) && normal(&across) > 0.0);
            halves += clipped.iter().map(area).sum::<f32>();
        }
        assert!((halves - area(&across)).abs() < 1e-5, "{halves}");
    }

    /// A triangle across a window's four sides is clipped once to the window, not
    /// cut plane by plane: its pieces are the fan of the clipped polygon (at most
    /// seven vertices here, so at most five triangles), all inside the window,
    /// same winding, covering exactly the triangle's part inside it.
    #[test]
    fn a_triangle_across_a_window_is_the_fan_of_its_clipped_polygon() {
        let warps = warps();
        let shadow = shadow(&warps);
        let base = |p: Vec3| shadow.base.project(p).map(|s| s.uv);
        let sides: [&dyn Fn(Vec3) -> f64; 4] = [
            &|p| f64::from(p.x) - 0.2,
            &|p| 0.8 - f64::from(p.x),
            &|p| f64::from(p.y) - 0.2,
            &|p| 0.8 - f64::from(p.y),
        ];
        let across = [
            Vec3::new(0.5, -0.3, 0.5),
            Vec3::new(1.3, 0.6, 0.5),
            Vec3::new(-0.2, 1.0, 0.5),
        ];
        // Coarse enough that nothing splits: the pieces are the fan itself.
        let options = RtwSubdivision::default()
            .with_max_span_cells(64.0)
            .with_max_error_texels(64.0)
            .with_max_segments(1);
        let mut pieces = Vec::new();
        subdivide_for_rtw_clipped(base, &sides, &warps, &[across], &options, &mut pieces);
        assert!((3..=5).contains(&pieces.len()), "{} pieces", pieces.len());
        assert!(
            pieces
                .iter()
                .flatten()
                .all(|p| sides.iter().all(|d| d(*p) >= -1e-6))
        );
        let normal = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).z;
        assert!(pieces.iter().all(|t| normal(t) >= 0.0) && normal(&across) > 0.0);
        // The window's corners (0.2, 0.2) and (0.8, 0.2) lie outside the triangle,
        // the rest of the square inside: compare with a grid count of the part.
        let inside = |x: f32, y: f32| {
            let p = Vec3::new(x, y, 0.5);
            let edge = |a: Vec3, b: Vec3| (b - a).cross(p - a).z >= 0.0;
            edge(across[0], across[1]) && edge(across[1], across[2]) && edge(across[2], across[0])
        };
        let n = 400;
        let cell = 0.6 / n as f32;
        let hits = (0..n * n)
            .filter(|k| {
                inside(
                    0.2 + (k % n) as f32 * cell + cell / 2.0,
                    0.2 + (k / n) as f32 * cell + cell / 2.0,
                )
            })
            .count();
        let expected = hits as f32 * cell * cell;
        let covered = pieces.iter().map(area).sum::<f32>();
        assert!((covered - expected).abs() < 2e-3, "{covered} vs {expected}");
    }

    #[test]
    fn the_cap_covers_the_extent_in_pieces_of_the_span_bound() {
        let o = RtwSubdivision::default();
        assert_eq!(o.with_segments_for_extent(1.0, 256).max_segments, 128);
        assert_eq!(o.with_segments_for_extent(2.5, 256).max_segments, 320);
        // Never below the current cap, never above 1024; NaN changes nothing.
        assert_eq!(o.with_segments_for_extent(0.1, 256).max_segments, 32);
        assert_eq!(o.with_segments_for_extent(1e9, 256).max_segments, 1024);
        assert_eq!(o.with_segments_for_extent(f64::NAN, 256).max_segments, 32);
        let rule = o.with_segments_for_extent(1.0, 256).split_rule(256, 256);
        assert_eq!(rule.levels, 7);
    }

    #[test]
    fn unmappable_or_non_finite_triangles_are_dropped() {
        let warps = warps();
        let shadow = shadow(&warps);
        let good = [
            Vec3::new(0.1, 0.1, 0.5),
            Vec3::new(0.2, 0.1, 0.5),
            Vec3::new(0.1, 0.2, 0.5),
        ];
        let bad = [Vec3::NAN, Vec3::X, Vec3::Y];
        let mut out = Vec::new();
        let options = RtwSubdivision::default();
        let kept = subdivide_for_rtw(&shadow, &[good], &options, &mut out);
        assert!(kept >= 1);
        assert_eq!(
            subdivide_for_rtw(&shadow, &[bad, good], &options, &mut out),
            kept
        );
        assert!(out.iter().flatten().all(|p| p.is_finite()));
        // Behind a perspective light (w <= 0): dropped.
        let base = ShadowTransform::new(
            Mat4::IDENTITY,
            // w = -z: the light at the origin looking down -z.
            Mat4::from_cols_array(&[
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0, -0.1, 0.0,
            ]),
            false,
            LightDirection::Position(Vec3::ZERO),
        );
        let spot = RtwShadow {
            base,
            warps: &warps,
        };
        let behind = [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.1, 0.0, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        assert_eq!(subdivide_for_rtw(&spot, &[behind], &options, &mut out), 0);
    }
}
