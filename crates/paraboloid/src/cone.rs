//! Light cones: the paper's averaged-axis fit and the exact minimal enclosing cone.

use arrayvec::ArrayVec;
use glam::{DVec3, Vec3};
use shadowmap_frustum::math;

use crate::ParaboloidError;

/// Most directions a cone fit takes (the plan uses 8, the frustum border points).
pub const MAX_CONE_DIRECTIONS: usize = 16;

/// Which cone fit a plan uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ConeFit {
    /// The paper's fit: axis = normalized sum of the unit directions, half-angle = the
    /// largest angle from that axis (Vanek et al., Eqs. 1 and 2). Not minimal.
    Paper,
    /// The exact minimal enclosing cone: axis along the minimum-norm point of the convex
    /// hull of the unit directions.
    #[default]
    Exact,
}

/// A circular cone with its apex at the light: every direction within `half_angle` of
/// `axis` is inside.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cone {
    /// Unit axis (world space).
    pub axis: Vec3,
    /// Half-angle in radians, in `[0, pi]`. Rounded up after the axis was rounded to
    /// `f32`, so every fitted direction is inside even in `f32`.
    pub half_angle: f32,
}

impl Cone {
    /// Whether `direction` (any length, non-zero) lies inside the cone, up to
    /// `tolerance` radians.
    #[must_use]
    pub fn contains(&self, direction: Vec3, tolerance: f32) -> bool {
        let Some(d) = direction.as_dvec3().try_normalize() else {
            return false;
        };
        angle_between(self.axis.as_dvec3(), d) <= f64::from(self.half_angle) + f64::from(tolerance)
    }

    /// The paraboloid cut (zoom) factor `Z = tan(half_angle / 2)` for this cone, or
    /// `None` when the half-angle is not under 90 degrees (no single paraboloid cut
    /// covers it).
    #[must_use]
    pub fn zoom(&self) -> Option<f32> {
        let h = f64::from(self.half_angle);
        (h < core::f64::consts::FRAC_PI_2).then(|| zoom_for_half_angle(h) as f32)
    }
}

/// Smallest zoom factor any builder produces: cones narrower than about `2e-6` rad are
/// widened to it, so the uv scale `1 / Z` stays finite in `f32`.
pub const MIN_ZOOM: f32 = 1e-6;

/// `tan(half / 2)`, clamped to `[MIN_ZOOM, 1]`.
pub(crate) fn zoom_for_half_angle(half: f64) -> f64 {
    math::tan(0.5 * half).clamp(f64::from(MIN_ZOOM), 1.0)
}

/// Angle between two unit vectors, accurate for tiny and near-straight angles.
pub(crate) fn angle_between(a: DVec3, b: DVec3) -> f64 {
    math::atan2(a.cross(b).length(), a.dot(b))
}

/// A cone in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DCone {
    pub(crate) axis: DVec3,
    pub(crate) half_angle: f64,
}

impl DCone {
    /// The `f32` cone, its half-angle recomputed for the rounded axis and rounded up.
    pub(crate) fn to_f32(self, dirs: &[DVec3]) -> Cone {
        let axis32 = self.axis.as_vec3().normalize_or(Vec3::NEG_Z);
        let axis = axis32.as_dvec3();
        let half = max_angle(axis, dirs).max(self.half_angle);
        Cone {
            axis: axis32,
            half_angle: round_up_f32(half).min(core::f32::consts::PI),
        }
    }
}

/// The smallest `f32` not below `x` (finite `x`).
pub(crate) fn round_up_f32(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x { next_up(y) } else { y }
}

fn next_up(x: f32) -> f32 {
    if x.is_nan() || x == f32::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f32::from_bits(1);
    }
    let bits = x.to_bits();
    f32::from_bits(if x > 0.0 { bits + 1 } else { bits - 1 })
}

/// The largest angle from `axis` to any direction (0 for none): the largest
/// [`angle_between`], with one `atan2` for the widest direction rather than one per
/// direction.
///
/// The angle of `(y, x) = (|a × d|, a · d)` grows with `y x' - x y'` against any other
/// pair `(y', x')` (both angles lie in `[0, pi]`), so one pass keeps the widest
/// direction by comparing those products. A direction the products cannot order
/// beyond doubt against the widest so far (a product within a relative `1e-9` of
/// zero, where rounding could order the two either way, or angles 0 and `pi`) gets
/// its own `atan2`. The widest direction is then either the one kept (each
/// replacement is wider beyond doubt) or one of those, so the result is exactly
/// the maximum of the per-direction angles.
pub(crate) fn max_angle(axis: DVec3, dirs: &[DVec3]) -> f64 {
    let mut widest: Option<(f64, f64)> = None;
    let mut tied = 0.0f64;
    for d in dirs {
        let p = (axis.cross(*d).length(), axis.dot(*d));
        let Some(w) = widest else {
            widest = Some(p);
            continue;
        };
        let (a, b) = (p.0 * w.1, w.0 * p.1);
        let gap = a - b;
        if gap.abs() > 1e-9 * (a.abs() + b.abs()) {
            if gap > 0.0 {
                widest = Some(p);
            }
        } else if p != w {
            tied = tied.max(math::atan2(p.0, p.1));
        }
    }
    widest.map_or(0.0, |w| math::atan2(w.0, w.1).max(tied).max(0.0))
}

/// The paper's fit on unit directions; `None` when their sum (nearly) vanishes.
pub(crate) fn paper_fit(dirs: &[DVec3]) -> Option<DCone> {
    let sum: DVec3 = dirs.iter().copied().sum();
    if sum.length().partial_cmp(&(1e-9 * dirs.len() as f64)) != Some(core::cmp::Ordering::Greater) {
        return None;
    }
    let axis = sum.normalize();
    Some(DCone {
        axis,
        half_angle: max_angle(axis, dirs),
    })
}

/// Half-angles from here up count as "no cone under 90 degrees": `pi/2 - 1e-6`, so that
/// the `f32` half-angle, rounded up, stays under 90 degrees.
pub(crate) const NO_CONE_ANGLE: f64 = core::f64::consts::FRAC_PI_2 - 1e-6;

/// The minimum-norm point of the plane through three unit directions (the
/// circumcentre of their triangle) if it lies inside the triangle, else `None`; also
/// `None` when its norm cannot beat `best_cos` (`f64::NEG_INFINITY`: no bound).
///
/// From the plane's normal, well conditioned even for slivers. `p*` has strictly
/// positive barycentric weights on its support set, so a triple whose point falls
/// outside its triangle cannot support the minimal cone: this test skips most
/// triples before scoring.
fn triangle_min_norm(a: DVec3, b: DVec3, c: DVec3, best_cos: f64) -> Option<DVec3> {
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let nn = n.length_squared();
    let scale = e1.length_squared() * e2.length_squared();
    if !(nn > 1e-30 * scale && nn > 1e-300) {
        return None;
    }
    let na = n.dot(a);
    // |p| = |n . a| / |n| is the cosine of the subset's own directions with the
    // candidate axis, an upper bound of its score.
    if na * na <= best_cos.max(0.0) * best_cos.abs() * nn {
        return None;
    }
    let p = n * (na / nn);
    let r = p - a;
    let wb = r.cross(e2).dot(n) / nn;
    let wc = e1.cross(r).dot(n) / nn;
    let tol = -1e-9;
    (wb >= tol && wc >= tol && 1.0 - wb - wc >= tol).then_some(p)
}

/// How far (in cosine) inside the rim of the cone from [`min_norm_support`] a
/// direction may lie and still be searched as a support direction: far more than the
/// iteration's error (rounding, up to about `1e-7` in angle where its simplex is a
/// sliver of nearly equal and nearly opposite directions), far less than the spacing
/// of the rim directions of any but a degenerate set.
const RIM_BAND: f64 = 1e-5;

/// The exact minimal enclosing cone of unit directions, or `None` when no cone under
/// 90 degrees contains them.
///
/// The optimal axis is `p* / |p*|` with `p*` the minimum-norm point of the convex hull
/// of the directions, and `cos(half_angle) = |p*|` (minimax duality). `p*` is the
/// minimum-norm point of the affine hull of its support set (one, two or three
/// directions on the rim of the cone: it lies on a face of the hull, with positive
/// barycentric weights). Gilbert's iteration ([`min_norm_support`]) finds `p*` and
/// its support set; the closed form of the support set's point (the direction itself,
/// the midpoint of a pair, the circumcentre of a triangle) is exact to rounding, and
/// when its cone holds every direction it is the answer (the usual case, certified by
/// one pass over the directions). Where the iteration's point is not exact (a sliver
/// triangle of nearly equal and nearly opposite directions) the support set is
/// searched among the directions on the rim of its cone (within [`RIM_BAND`]),
/// usually a few, or among all of them within that band of 90 degrees. The paper's axis is a candidate too, so the
/// result is never wider than the paper's cone: of the candidates, the one with the
/// largest smallest cosine wins.
pub(crate) fn minimal_fit(dirs: &[DVec3]) -> Option<DCone> {
    // The origin in the hull (or within 1e-12 of it: a cone wider than
    // `NO_CONE_ANGLE` in any case): no cone.
    let (v, support) = min_norm_support(dirs)?;
    let mut best = Best::new(dirs);
    best.consider(dirs.iter().copied().sum());
    best.consider(v);
    // The support set's own cone (its closed form) is the minimal cone when it holds
    // every direction: its cosine to each is at least `|p|`, the cosine to the
    // support (to rounding: the half-angle is then optimal to `1e-15 / sin h`).
    if let Some(p) = support_point(dirs, &support)
        && best.consider(p) >= p.length() * (1.0 - 1e-15)
    {
        return best.cone();
    }
    if best.cos > RIM_BAND {
        let rim: ArrayVec<DVec3, MAX_CONE_DIRECTIONS> = dirs
            .iter()
            .copied()
            .filter(|d| best.axis.dot(*d) <= best.cos + RIM_BAND)
            .collect();
        best.search_subsets(&rim);
    } else {
        // Within the band of 90 degrees the iteration's cone may be too wide to
        // find the rim by: search every subset.
        best.search_subsets(dirs);
    }
    best.cone()
}

/// The minimum-norm point of the affine hull of a support set in closed form (the
/// direction, the midpoint of a pair, the circumcentre of a triangle), `None` for a
/// triangle whose point falls outside it.
fn support_point(dirs: &[DVec3], support: &Support) -> Option<DVec3> {
    let d = |k: usize| dirs[support[k]];
    match support.len() {
        1 => Some(d(0)),
        2 => Some(0.5 * (d(0) + d(1))),
        3 => triangle_min_norm(d(0), d(1), d(2), f64::NEG_INFINITY),
        _ => None,
    }
}

/// The best axis so far of a minimal-cone search: the one with the largest smallest
/// cosine to the directions.
struct Best<'a> {
    dirs: &'a [DVec3],
    axis: DVec3,
    cos: f64,
}

impl<'a> Best<'a> {
    fn new(dirs: &'a [DVec3]) -> Self {
        Self {
            dirs,
            axis: DVec3::ZERO,
            cos: f64::NEG_INFINITY,
        }
    }

    /// Scores the axis along `p` (any length; ignored when zero or not finite).
    /// Returns the smallest cosine of that axis (`-inf` when ignored).
    fn consider(&mut self, p: DVec3) -> f64 {
        let len = p.length();
        if !(len > 1e-15 && len.is_finite()) {
            return f64::NEG_INFINITY;
        }
        let axis = p / len;
        let min_cos = self
            .dirs
            .iter()
            .map(|&d| axis.dot(d))
            .fold(f64::INFINITY, f64::min);
        if min_cos > self.cos {
            self.cos = min_cos;
            self.axis = axis;
        }
        min_cos
    }

    /// Scores the axes of the minimum-norm points of every subset of one to three of
    /// `candidates` that falls inside its subset (singles, then pairs, then triples:
    /// the best cosine so far rises before the many triples are bounded against it;
    /// a subset's own directions have cosine `|p|` with its axis, an upper bound that
    /// skips a candidate before its `O(n)` scoring).
    fn search_subsets(&mut self, candidates: &[DVec3]) {
        let n = candidates.len();
        for &d in candidates {
            self.consider(d);
        }
        for i in 0..n {
            for j in i + 1..n {
                let mid = candidates[i] + candidates[j];
                if 0.5 * mid.length() > self.cos {
                    self.consider(mid);
                }
            }
        }
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    let (a, b, c) = (candidates[i], candidates[j], candidates[k]);
                    if let Some(p) = triangle_min_norm(a, b, c, self.cos) {
                        self.consider(p);
                    }
                }
            }
        }
    }

    /// The cone around the best axis, `None` when it is not under 90 degrees.
    fn cone(&self) -> Option<DCone> {
        if self.cos.is_nan() || self.cos <= 0.0 {
            return None;
        }
        let half_angle = max_angle(self.axis, self.dirs);
        (half_angle < NO_CONE_ANGLE).then_some(DCone {
            axis: self.axis,
            half_angle,
        })
    }
}

/// Most iterations of [`min_norm_support`]: each adds a direction that lowers `|v|`
/// strictly, and with at most [`MAX_CONE_DIRECTIONS`] directions the support set
/// settles in a few; the bound only guards against cycling on rounding.
const MAX_MIN_NORM_ITERATIONS: usize = 64;

/// A support set: indices of one to four directions.
type Support = arrayvec::ArrayVec<usize, 4>;

/// The minimum-norm point `v` of the convex hull of unit directions by Gilbert's
/// iteration (the distance algorithm of Gilbert, Johnson and Keerthi, with the origin
/// as the query point), with its support set (the one to three directions whose
/// hull holds it). `None` when the origin lies in the hull: inside a tetrahedron
/// of directions by more than `1e-9`, or within `1e-12` of the iteration's point (no
/// cone under 90 degrees either way; nearer the hull's boundary the point is returned,
/// as good as rounding allows).
///
/// Each step takes the direction `w` that minimizes `w . v` (the hull's support point
/// toward the origin), stops when it cannot lower `|v|` beyond rounding
/// (`(v - w) . v <= 1e-15 |v - w| |v|`: the optimality condition `w . v >= |v|²` for
/// every direction, measured by angle so that it holds its precision however small
/// the hull), and otherwise replaces `v` by the point of `conv(support + w)` nearest
/// the origin, keeping only the directions that point needs.
fn min_norm_support(dirs: &[DVec3]) -> Option<(DVec3, Support)> {
    let mut support = Support::new();
    support.push(0);
    let mut v = dirs[0];
    for _ in 0..MAX_MIN_NORM_ITERATIONS {
        let vv = v.dot(v);
        if !(vv > 1e-24) {
            return None;
        }
        // Differences to the first direction keep the comparisons exact to rounding
        // for nearly equal directions (a hull much smaller than its distance from the
        // origin), where `d . v` would agree to the last bits.
        let (w, _) = dirs
            .iter()
            .enumerate()
            .map(|(i, d)| (i, (*d - dirs[0]).dot(v)))
            .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
        let gap = v - dirs[w];
        if gap.dot(v) <= 1e-15 * gap.length() * v.length() || support.contains(&w) {
            return Some((v, support));
        }
        support.push(w);
        v = nearest_on_simplex(dirs, &mut support)?;
    }
    Some((v, support))
}

/// The point of the simplex `conv(dirs[support])` (two to four points) nearest the
/// origin; `support` is reduced to the points it needs. `None` when the origin lies
/// inside a tetrahedron (by more than `1e-9`).
fn nearest_on_simplex(dirs: &[DVec3], support: &mut Support) -> Option<DVec3> {
    let p = |k: usize| dirs[support[k]];
    let (v, keep): (DVec3, Support) = match support.len() {
        2 => nearest_on_segment(p(0), p(1), [0, 1]),
        3 => nearest_on_triangle(p(0), p(1), p(2), [0, 1, 2]),
        _ => nearest_on_tetrahedron([p(0), p(1), p(2), p(3)])?,
    };
    *support = keep.iter().map(|&k| support[k]).collect();
    Some(v)
}

/// The point of segment `ab` nearest the origin and the endpoints it needs (`ids`
/// names `a` and `b`).
fn nearest_on_segment(a: DVec3, b: DVec3, ids: [usize; 2]) -> (DVec3, Support) {
    let ab = b - a;
    let t = -a.dot(ab) / ab.dot(ab);
    if !(t > 0.0) {
        (a, Support::from_iter([ids[0]]))
    } else if t >= 1.0 {
        (b, Support::from_iter([ids[1]]))
    } else {
        (a + ab * t, Support::from_iter(ids))
    }
}

/// The point of triangle `abc` nearest the origin and the corners it needs: the
/// minimum-norm point of its plane from the plane's normal when it falls inside (see
/// [`triangle_min_norm`]: well conditioned for the slivers of nearly equal directions
/// where barycentric formulas cancel), else the nearest point of its edges.
fn nearest_on_triangle(a: DVec3, b: DVec3, c: DVec3, ids: [usize; 3]) -> (DVec3, Support) {
    if let Some(p) = triangle_min_norm(a, b, c, f64::NEG_INFINITY) {
        return (p, Support::from_iter(ids));
    }
    [([0, 1], a, b), ([0, 2], a, c), ([1, 2], b, c)]
        .into_iter()
        .map(|(e, p, q)| nearest_on_segment(p, q, [ids[e[0]], ids[e[1]]]))
        .min_by(|x, y| x.0.length_squared().total_cmp(&y.0.length_squared()))
        .unwrap_or((a, Support::from_iter([ids[0]])))
}

/// The point of a tetrahedron nearest the origin and the corners it needs (indices
/// into `t`), `None` when the origin lies inside (by more than `1e-9`).
fn nearest_on_tetrahedron(t: [DVec3; 4]) -> Option<(DVec3, Support)> {
    const FACES: [([usize; 3], usize); 4] = [
        ([0, 1, 2], 3),
        ([0, 1, 3], 2),
        ([0, 2, 3], 1),
        ([1, 2, 3], 0),
    ];
    let mut best: Option<(DVec3, Support)> = None;
    for (f, opposite) in FACES {
        let (a, b, c) = (t[f[0]], t[f[1]], t[f[2]]);
        let n = (b - a).cross(c - a);
        // The origin is inside this face's half-space when it lies on the side of
        // the opposite corner, by more than rounding (`1e-9`; a flat tetrahedron has
        // no inside: every face is tried). Inside all four: no nearest point.
        let (so, sd) = (-n.dot(a), n.dot(t[opposite] - a));
        if so * sd > 0.0 && so.abs() > 1e-9 * n.length() {
            continue;
        }
        let cand = nearest_on_triangle(a, b, c, f);
        if best
            .as_ref()
            .is_none_or(|b| cand.0.length_squared() < b.0.length_squared())
        {
            best = Some(cand);
        }
    }
    best
}

/// Checks and normalizes the directions into a fixed array.
fn unit_directions(
    directions: &[Vec3],
) -> Result<arrayvec::ArrayVec<DVec3, MAX_CONE_DIRECTIONS>, ParaboloidError> {
    if directions.is_empty() || directions.len() > MAX_CONE_DIRECTIONS {
        return Err(ParaboloidError::InvalidDirectionCount);
    }
    let mut out = arrayvec::ArrayVec::new();
    for d in directions {
        if !d.is_finite() {
            return Err(ParaboloidError::NonFinite);
        }
        let u = d
            .as_dvec3()
            .try_normalize()
            .ok_or(ParaboloidError::ZeroDirection)?;
        out.push(u);
    }
    Ok(out)
}

/// The paper's light cone (Vanek et al., Eqs. 1 and 2) around `directions` (any
/// non-zero lengths): axis = normalized sum of the unit directions, half-angle = the
/// largest angle from it. The half-angle may reach 180 degrees.
///
/// ```text
/// C = norm(sum_j D_j / |D_j|)        half_angle = max_j angle(D_j, C)
/// ```
///
/// # Errors
/// [`ParaboloidError::InvalidDirectionCount`] for no directions or more than
/// [`MAX_CONE_DIRECTIONS`]; [`ParaboloidError::NonFinite`];
/// [`ParaboloidError::ZeroDirection`] for a zero direction;
/// [`ParaboloidError::DirectionsCancel`] when the unit directions sum to (nearly) zero.
pub fn fit_paper_cone(directions: &[Vec3]) -> Result<Cone, ParaboloidError> {
    let dirs = unit_directions(directions)?;
    let cone = paper_fit(&dirs).ok_or(ParaboloidError::DirectionsCancel)?;
    Ok(cone.to_f32(&dirs))
}

/// The exact minimal cone around `directions` (any non-zero lengths).
///
/// ```text
/// p* = argmin { |p| : p in conv(D_j / |D_j|) }
/// axis = p* / |p*|                   cos(half_angle) = |p*|
/// ```
///
/// No cone under 90 degrees exists exactly when `p* = 0`, i.e. when the origin lies in
/// the convex hull (for frustum border points: when the light lies in the truncated
/// frustum).
///
/// # Errors
/// As [`fit_paper_cone`] (except `DirectionsCancel`), and
/// [`ParaboloidError::NoConeUnder90`] when no cone under 90 degrees contains the
/// directions (cones within `1e-6` rad of 90 degrees count as none).
pub fn fit_minimal_cone(directions: &[Vec3]) -> Result<Cone, ParaboloidError> {
    let dirs = unit_directions(directions)?;
    let cone = minimal_fit(&dirs).ok_or(ParaboloidError::NoConeUnder90)?;
    Ok(cone.to_f32(&dirs))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use shadowmap_testgen::paraboloid::cone_directions;
    use shadowmap_testgen::strategy;

    /// The search [`minimal_fit`] replaces, kept as its test oracle: the exact minimal
    /// enclosing cone of unit directions, or `None` when no cone under 90 degrees
    /// contains them.
    ///
    /// The optimal axis is `p* / |p*|` with `p*` the minimum-norm point of the convex hull
    /// of the directions, and `cos(half_angle) = |p*|` (minimax duality). `p*` is the
    /// minimum-norm point of the affine hull of its support set (one, two or three
    /// directions: it lies on a face of the hull, with positive barycentric weights), so
    /// the axis is among the axes of the affine minimum-norm points of all subsets of size
    /// 1 to 3 that fall inside their subset; the one with the largest smallest cosine is
    /// optimal. The paper's axis is a candidate too, so the result is never wider than
    /// the paper's cone. For unit directions the points are the directions themselves, the
    /// midpoints of pairs and the circumcentres of triangles; a subset's own directions
    /// have cosine `|p|` with its axis, an upper bound that skips a candidate before its
    /// `O(n)` scoring.
    fn minimal_fit_by_subsets(dirs: &[DVec3]) -> Option<DCone> {
        let mut best = Best::new(dirs);
        best.consider(dirs.iter().copied().sum());
        best.search_subsets(dirs);
        best.cone()
    }

    proptest! {
        #![proptest_config(shadowmap_testgen::proptest_config())]

        /// The iteration finds the cone the search over every subset of one to three
        /// directions finds: the same half-angle to 1e-9 rad, or none for both (either
        /// answer within a microradian of the no-cone threshold). Both
        /// rank axes by the cosine of the half-angle `h`, which resolves `h` only to
        /// about `epsilon / h` (`cos h = 1 - h²/2` in `f64`): for cones under a few
        /// microradians (directions a few `f32` ulps apart) that is the tolerance.
        #[test]
        fn iteration_equals_the_subset_search(dirs in strategy(cone_directions)) {
            let Ok(dirs) = unit_directions(&dirs) else { return Ok(()) };
            match (minimal_fit(&dirs), minimal_fit_by_subsets(&dirs)) {
                (Some(a), Some(b)) => {
                    let (a, b) = (a.half_angle, b.half_angle);
                    let tol = 1e-9 + 8.0 * f64::EPSILON / b.max(f64::MIN_POSITIVE);
                    prop_assert!((a - b).abs() <= tol, "{a} vs {b}");
                }
                (None, None) => {}
                // Within rounding of 90 degrees either answer is right.
                (Some(c), None) | (None, Some(c)) => {
                    prop_assert!(c.half_angle > NO_CONE_ANGLE - 1e-6, "{c:?}");
                }
            }
        }

        /// The widest direction found by comparing products, then one `atan2`,
        /// gives exactly the largest angle of every direction, about the fitted
        /// axis and about one of the directions (many ties at 0).
        #[test]
        fn max_angle_is_the_largest_angle_between(dirs in strategy(cone_directions)) {
            let Ok(dirs) = unit_directions(&dirs) else { return Ok(()) };
            let sum: DVec3 = dirs.iter().copied().sum();
            for axis in [sum.normalize_or(DVec3::Z), dirs[0], -dirs[0]] {
                let each = dirs
                    .iter()
                    .map(|&d| angle_between(axis, d))
                    .fold(0.0, f64::max);
                prop_assert_eq!(max_angle(axis, &dirs), each);
            }
        }
    }

    #[test]
    fn two_directions_give_the_bisector() {
        let c = fit_minimal_cone(&[Vec3::X, Vec3::Y]).unwrap();
        assert!((c.axis - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        assert!((c.half_angle - core::f32::consts::FRAC_PI_4).abs() < 1e-6);
    }

    #[test]
    fn minimal_beats_paper_on_a_skewed_set() {
        // Many directions clustered near X pull the paper's axis away from the middle.
        let dirs = [
            Vec3::X,
            Vec3::new(1.0, 0.01, 0.0),
            Vec3::new(1.0, 0.0, 0.01),
            Vec3::Y,
        ];
        let exact = fit_minimal_cone(&dirs).unwrap();
        let paper = fit_paper_cone(&dirs).unwrap();
        assert!(exact.half_angle < paper.half_angle - 0.1);
        for d in dirs {
            assert!(exact.contains(d, 0.0));
            assert!(paper.contains(d, 0.0));
        }
    }

    #[test]
    fn octahedron_has_no_cone() {
        let dirs = [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ];
        assert_eq!(fit_minimal_cone(&dirs), Err(ParaboloidError::NoConeUnder90));
        assert_eq!(
            fit_paper_cone(&dirs),
            Err(ParaboloidError::DirectionsCancel)
        );
    }

    #[test]
    fn bad_input_is_typed() {
        assert_eq!(
            fit_minimal_cone(&[]),
            Err(ParaboloidError::InvalidDirectionCount)
        );
        assert_eq!(
            fit_minimal_cone(&[Vec3::ZERO]),
            Err(ParaboloidError::ZeroDirection)
        );
        assert_eq!(
            fit_paper_cone(&[Vec3::NAN]),
            Err(ParaboloidError::NonFinite)
        );
    }

    #[test]
    fn single_direction_is_a_zero_cone() {
        let c = fit_minimal_cone(&[Vec3::new(0.0, 3.0, 4.0)]).unwrap();
        assert!(c.half_angle < 1e-6);
        assert!(c.zoom().unwrap() >= MIN_ZOOM);
    }
}
