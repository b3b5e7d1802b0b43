//! Caster subdivision: wgpu has no tessellation stage, so edges are split until their
//! linearly rasterized image stays near the true paraboloid curve. This is the
//! reference; the compute refinement of `shadowmap-wgpu` is its twin on the GPU (the
//! same rule, [`SubdivisionOptions::split_rule`] and [`DEVIATION_SAMPLES`], and the
//! same pieces, evaluated in `f32`).

use glam::{DVec2, DVec3, Vec3};

use crate::ParaboloidError;
use crate::map::{ParaboloidMap, Side};

/// Knobs of [`edge_subdivisions`] and [`subdivide_triangle`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct SubdivisionOptions {
    /// Shadow-map resolution (texels per side), in `1..=65536`. Default 1024.
    pub resolution: u32,
    /// Largest allowed distance, in texels, between the linear raster of a segment and
    /// the true image curve. Positive and finite. Default `0.5`.
    pub tolerance_texels: f32,
    /// Most segments per edge, in `1..=256`; triangles get at most its square of
    /// pieces. Default 16.
    pub max_segments: u32,
}

impl Default for SubdivisionOptions {
    fn default() -> Self {
        Self {
            resolution: 1024,
            tolerance_texels: 0.5,
            max_segments: 16,
        }
    }
}

impl SubdivisionOptions {
    /// With this resolution.
    #[must_use]
    pub const fn with_resolution(mut self, resolution: u32) -> Self {
        self.resolution = resolution;
        self
    }
    /// With this tolerance in texels.
    #[must_use]
    pub const fn with_tolerance_texels(mut self, tolerance: f32) -> Self {
        self.tolerance_texels = tolerance;
        self
    }
    /// With this segment limit.
    #[must_use]
    pub const fn with_max_segments(mut self, max_segments: u32) -> Self {
        self.max_segments = max_segments;
        self
    }

    pub(crate) fn validate(&self) -> Result<(), ParaboloidError> {
        let t = self.tolerance_texels;
        if !t.is_finite() {
            return Err(ParaboloidError::NonFinite);
        }
        let ok = t > 0.0
            && (1..=65536).contains(&self.resolution)
            && (1..=256).contains(&self.max_segments);
        if ok {
            Ok(())
        } else {
            Err(ParaboloidError::InvalidSubdivision)
        }
    }
}

/// Fractions of a segment at which [`edge_subdivisions`] measures the distance of the
/// image curve from the segment's straight raster (its chord).
pub const DEVIATION_SAMPLES: [f64; 3] = [0.25, 0.5, 0.75];

/// The numbers the edge rule of [`edge_subdivisions`] runs on, checked: what a GPU
/// twin of the subdivision (the compute refinement of `shadowmap-wgpu`) needs to
/// decide as the CPU does.
///
/// ```text
/// c(t) = resolution * uv(a + t (b - a))
/// n = 1
/// loop:
///     dev = max over k < n, f in DEVIATION_SAMPLES of dist(c((k + f) / n), chord k)
///           (max_segments where c is undefined: through the light or the pole)
///     if dev <= tolerance_texels or n >= max_segments: return min(n, max_segments)
///     n = min(max(floor(n sqrt(dev / tolerance_texels)), n + 1), max_segments)
/// triangle: n = max over its edges; the n² pieces of the barycentric grid
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParaboloidSplitRule {
    /// Texels per side of the map: `c(t)` is in texels.
    pub resolution: f64,
    /// The deviation bound, in texels.
    pub tolerance_texels: f64,
    /// Most segments per edge.
    pub max_segments: u32,
    /// `ceil(log2(max_segments))`, in `0..=8`: a triangle is cut into at most
    /// `2^levels` segments per edge.
    pub levels: u32,
}

impl SubdivisionOptions {
    /// The checked split rule of these options.
    ///
    /// # Errors
    /// [`ParaboloidError::NonFinite`] for a non-finite tolerance;
    /// [`ParaboloidError::InvalidSubdivision`] for options out of range.
    pub fn split_rule(&self) -> Result<ParaboloidSplitRule, ParaboloidError> {
        self.validate()?;
        Ok(ParaboloidSplitRule {
            resolution: f64::from(self.resolution),
            tolerance_texels: f64::from(self.tolerance_texels),
            max_segments: self.max_segments,
            levels: self.max_segments.next_power_of_two().trailing_zeros(),
        })
    }
}

/// Texel-space image of a light-space point on `side`.
fn texel(map: &ParaboloidMap, side: Side, q: DVec3, resolution: f64) -> Option<DVec2> {
    let p = ParaboloidMap::disc_point(q, side)?;
    Some(map.uv_of_disc(p.disc) * resolution)
}

fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Largest measured deviation (texels) of `n` equal segments from the curve, sampled at
/// the quarter points of every segment; `None` where the curve is undefined.
fn deviation(map: &ParaboloidMap, side: Side, a: DVec3, b: DVec3, n: u32, res: f64) -> Option<f64> {
    let at = |t: f64| texel(map, side, a + (b - a) * t, res);
    let mut worst: f64 = 0.0;
    let mut prev = at(0.0)?;
    let step = 1.0 / f64::from(n);
    for k in 0..n {
        let t0 = f64::from(k) * step;
        let next = at(t0 + step)?;
        for f in DEVIATION_SAMPLES {
            let m = at(t0 + f * step)?;
            worst = worst.max(segment_distance(m, prev, next));
        }
        prev = next;
    }
    worst.is_finite().then_some(worst)
}

fn edge_count(map: &ParaboloidMap, side: Side, a: DVec3, b: DVec3, o: &ParaboloidSplitRule) -> u32 {
    let (res, tol) = (o.resolution, o.tolerance_texels);
    let mut n = 1u32;
    loop {
        let Some(dev) = deviation(map, side, a, b, n, res) else {
            return o.max_segments;
        };
        if dev <= tol || n >= o.max_segments {
            return n.min(o.max_segments);
        }
        // The deviation of a smooth curve falls as 1/n^2.
        let guess = f64::from(n) * shadowmap_frustum::math::sqrt(dev / tol);
        let guess = if guess.is_finite() {
            guess.min(f64::from(o.max_segments))
        } else {
            f64::from(o.max_segments)
        };
        n = (guess as u32).max(n + 1).min(o.max_segments);
    }
}

/// The number of equal segments (in `1..=max_segments`) the world edge `a`-`b` needs so
/// that the linear raster of each segment's image on `side` stays within
/// `tolerance_texels` of the true image curve.
///
/// ```text
/// c(t) = resolution * uv(a + t (b - a))       (the paraboloid image, a curve)
/// n    = smallest n with  max_k max_{f in 1/4, 1/2, 3/4} dist(c((k+f)/n), chord_k) <= tol
/// ```
///
/// The deviation is measured at the quarter points of each segment, starting from
/// `n = 1` and refining with the `1/n²` law. Edges through the light or the side's
/// pole (where the curve is undefined) get `max_segments`; so does an edge that still
/// misses at `max_segments`.
///
/// # Errors
/// [`ParaboloidError::NonFinite`] for non-finite points or tolerance;
/// [`ParaboloidError::InvalidSubdivision`] for options out of range.
pub fn edge_subdivisions(
    map: &ParaboloidMap,
    side: Side,
    a: Vec3,
    b: Vec3,
    options: &SubdivisionOptions,
) -> Result<u32, ParaboloidError> {
    let rule = options.split_rule()?;
    if !(a.is_finite() && b.is_finite()) {
        return Err(ParaboloidError::NonFinite);
    }
    let (qa, qb) = (map.to_light(a.as_dvec3()), map.to_light(b.as_dvec3()));
    Ok(edge_count(map, side, qa, qb, &rule))
}

/// Splits a world triangle for rendering into paraboloid `side`: with `n` the largest
/// [`edge_subdivisions`] of its three edges, emits the `n²` triangles of the uniform
/// barycentric grid (same winding as the input) and returns `n²`.
///
/// ```text
/// p(i, j) = a + (i / n)(b - a) + (j / n)(c - a),   i + j <= n
/// ```
///
/// # Errors
/// As [`edge_subdivisions`]; nothing is emitted on error.
pub fn subdivide_triangle(
    map: &ParaboloidMap,
    side: Side,
    triangle: [Vec3; 3],
    options: &SubdivisionOptions,
    mut emit: impl FnMut([Vec3; 3]),
) -> Result<u32, ParaboloidError> {
    let rule = options.split_rule()?;
    if !triangle.iter().all(|p| p.is_finite()) {
        return Err(ParaboloidError::NonFinite);
    }
    let [a, b, c] = triangle.map(Vec3::as_dvec3);
    let q = triangle.map(|p| map.to_light(p.as_dvec3()));
    let n = [(0, 1), (1, 2), (2, 0)]
        .into_iter()
        .map(|(i, j)| edge_count(map, side, q[i], q[j], &rule))
        .max()
        .unwrap_or(1);
    let nf = f64::from(n);
    let (e1, e2) = ((b - a) / nf, (c - a) / nf);
    let p = |i: u32, j: u32| (a + e1 * f64::from(i) + e2 * f64::from(j)).as_vec3();
    for j in 0..n {
        for i in 0..n - j {
            emit([p(i, j), p(i + 1, j), p(i, j + 1)]);
            if i + j + 1 < n {
                emit([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
    }
    Ok(n * n)
}

/// [`subdivide_triangle`] over a triangle list, appending to `out` (cleared first).
/// Returns the number of triangles written.
///
/// # Errors
/// As [`subdivide_triangle`]; `out` holds the triangles of the input triangles before
/// the failing one.
pub fn subdivide_triangles(
    map: &ParaboloidMap,
    side: Side,
    triangles: &[[Vec3; 3]],
    options: &SubdivisionOptions,
    out: &mut alloc::vec::Vec<[Vec3; 3]>,
) -> Result<usize, ParaboloidError> {
    out.clear();
    for &t in triangles {
        subdivide_triangle(map, side, t, options, |s| out.push(s))?;
    }
    Ok(out.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::MapOptions;

    fn map() -> ParaboloidMap {
        ParaboloidMap::dual(Vec3::ZERO, Vec3::NEG_Z, 0.1, 100.0, &MapOptions::default()).unwrap()
    }

    #[test]
    fn radial_edges_need_no_split_and_wide_edges_do() {
        let o = SubdivisionOptions::default();
        // A ray from the light maps to a straight line.
        let n = edge_subdivisions(
            &map(),
            Side::Front,
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(5.0, 0.0, -5.0),
            &o,
        )
        .unwrap();
        assert_eq!(n, 1);
        // A long edge across the hemisphere curves strongly.
        let n = edge_subdivisions(
            &map(),
            Side::Front,
            Vec3::new(-10.0, 1.0, -1.0),
            Vec3::new(10.0, 1.0, -1.0),
            &o,
        )
        .unwrap();
        assert!(n > 4, "{n}");
    }

    #[test]
    fn triangle_grid_has_n_squared_pieces_of_the_same_area() {
        let m = map();
        let tri = [
            Vec3::new(-10.0, -1.0, -1.0),
            Vec3::new(10.0, -1.0, -1.0),
            Vec3::new(0.0, 5.0, -1.0),
        ];
        let mut out = alloc::vec::Vec::new();
        let count = subdivide_triangles(
            &m,
            Side::Front,
            &[tri],
            &SubdivisionOptions::default(),
            &mut out,
        )
        .unwrap();
        assert_eq!(count, out.len());
        let n = f32::sqrt(count as f32).round() as usize;
        assert_eq!(n * n, count);
        let area = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]);
        let total: Vec3 = out.iter().map(area).sum();
        assert!((total - area(&tri)).length() < 1e-3 * area(&tri).length());
    }

    #[test]
    fn split_rule_levels_cover_max_segments() {
        for (max_segments, levels) in [(1, 0), (2, 1), (16, 4), (17, 5), (256, 8)] {
            let rule = SubdivisionOptions::default()
                .with_max_segments(max_segments)
                .split_rule()
                .unwrap();
            assert_eq!(rule.levels, levels, "{max_segments}");
            assert!(1u32 << rule.levels >= max_segments);
        }
        let bad = SubdivisionOptions::default().with_tolerance_texels(0.0);
        assert_eq!(bad.split_rule(), Err(ParaboloidError::InvalidSubdivision));
    }

    #[test]
    fn bad_options_are_typed() {
        let o = SubdivisionOptions::default().with_max_segments(0);
        assert_eq!(
            edge_subdivisions(&map(), Side::Front, Vec3::X, Vec3::Y, &o),
            Err(ParaboloidError::InvalidSubdivision)
        );
        assert_eq!(
            edge_subdivisions(
                &map(),
                Side::Front,
                Vec3::NAN,
                Vec3::Y,
                &SubdivisionOptions::default()
            ),
            Err(ParaboloidError::NonFinite)
        );
    }
}
