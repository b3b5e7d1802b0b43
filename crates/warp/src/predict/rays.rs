//! The probe's rays and points (see the parent module): a grid of view rays
//! through the frustum, each meeting the box around frustum ∩ receivers, and the
//! points where a rendered pixel would most likely see a surface, with how far a
//! point moves on its surface for one step on the screen.

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3};
use shadowmap_frustum::math::{self, max_num, min_num};

use super::{COLUMNS, DEPTHS, Point, ProbePoints, RAYS, ROWS};
use crate::focus::{Bounds, Focus, View, smoothstep};

/// Smallest weight of a ray that meets the box.
const RAY_WEIGHT_FLOOR: f64 = 1e-3;
/// Screen step (a fraction of the screen height) of the probe points' Jacobians:
/// a unit common to every candidate, so its size only scales the error.
const STEP: f64 = 1e-3;

/// The ray through one screen position and how it moves with the screen: its
/// origin on the near face, its direction (to the far face), and their derivatives
/// per unit of normalized screen `x` and `y`.
#[derive(Clone, Copy)]
pub(super) struct Ray {
    pub(super) origin: DVec3,
    pub(super) dir: DVec3,
    d_origin: [DVec3; 2],
    d_dir: [DVec3; 2],
}

/// What a probe's rays are cast from: the screen, the receivers' box, the screen
/// step, the light and the light frame the points are kept in.
pub(super) struct Rays {
    screen: Screen,
    receivers: Bounds,
    step: DVec2,
    light: DVec3,
    light_from_world: DMat4,
}

impl Rays {
    /// The rays of `view` through the receivers' box of `f`.
    pub(super) fn new(view: &View, f: &Focus) -> Self {
        let c = view.frustum.corners.map(glam::Vec3::as_dvec3);
        let screen = Screen {
            near: [c[0], c[1], c[2], c[3]],
            far: [c[4], c[5], c[6], c[7]],
            forward: view.forward,
            eye: view.eye,
        };
        let aspect = (c[1] - c[0]).length() / (c[3] - c[0]).length();
        let step = DVec2::new(STEP / aspect.max(1e-12), STEP);
        let mut receivers = Bounds::EMPTY;
        for p in &f.receivers {
            receivers.add(*p);
        }
        Self {
            screen,
            receivers,
            step,
            light: f.light,
            light_from_world: f.rot,
        }
    }

    /// Adds the points of `pass` of every ray to `out`, row by row, in the light
    /// frame; returns the sum of the rays' weights.
    pub(super) fn cast(&self, pass: Pass, out: &mut ProbePoints) -> f64 {
        let columns: [Column; COLUMNS] = core::array::from_fn(|column| {
            self.screen.column((column as f64 + 0.5) / COLUMNS as f64)
        });
        // Every ray's segment first: the rays are independent, so their chains of
        // divisions overlap, where one ray's points after another's would wait on
        // each in turn. Only the rays that meet the box need their derivatives.
        let mut segments: ArrayVec<(usize, f64, Segment), RAYS> = ArrayVec::new();
        for row in 0..ROWS {
            let y = (row as f64 + 0.5) / ROWS as f64;
            for (i, column) in columns.iter().enumerate() {
                let (origin, dir) = column.line(y);
                if let Some(segment) = Segment::new(origin, dir, &self.screen, &self.receivers) {
                    segments.push((i, y, segment));
                }
            }
        }
        // Where every ray's points lie first, then the points themselves: a point's
        // divisions wait on its ray's choices (face, normal, weight), and made in a
        // loop of their own, the divisions of several points run at once.
        let mut geometric = 0.0;
        let mut rays: ArrayVec<Ray, RAYS> = ArrayVec::new();
        let mut planned: ArrayVec<PlannedPoint, { RAYS * (DEPTHS + 2) }> = ArrayVec::new();
        for (i, y, segment) in &segments {
            let ray = columns[*i].ray(*y);
            geometric += ray_points(self, &ray, rays.len(), segment, pass, &mut planned);
            rays.push(ray);
        }
        for plan in &planned {
            let ray = &rays[plan.ray];
            if let Some(q) = point_at(ray, self.step, plan.s, plan.n, plan.weight, plan.fade) {
                out.push(&q, &self.light_from_world);
            }
        }
        geometric
    }
}

/// Which of a probe's two point sets a pass over the rays adds to.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Pass {
    /// Face points with the faces' normals and lit weights, and the volume points.
    Lit,
    /// The same places facing the bisector of the eye and light directions.
    Perspective,
}

/// The view frustum as a screen: rays by normalized position, `(0, 0)` bottom left.
#[derive(Clone, Debug)]
pub(super) struct Screen {
    pub(super) near: [DVec3; 4],
    pub(super) far: [DVec3; 4],
    pub(super) forward: DVec3,
    pub(super) eye: DVec3,
}

impl Screen {
    /// The ray through `(x, y)`: the bilinear interpolation of the near and of the
    /// far face's corners, and its exact derivatives in `x` and `y`.
    #[cfg(test)]
    pub(super) fn ray(&self, x: f64, y: f64) -> Ray {
        self.column(x).ray(y)
    }

    /// What the rays at screen `x` share: each face's points at `x` on its bottom
    /// and top edges.
    fn column(&self, x: f64) -> Column {
        let at = |q: &[DVec3; 4]| {
            let (bottom, top) = (q[0].lerp(q[1], x), q[3].lerp(q[2], x));
            ColumnFace {
                bottom,
                top,
                up: top - bottom,
                along_bottom: q[1] - q[0],
                along_top: q[2] - q[3],
            }
        };
        Column {
            near: at(&self.near),
            far: at(&self.far),
        }
    }

    fn depth(&self, p: DVec3) -> f64 {
        (p - self.eye).dot(self.forward)
    }
}

/// The rays through one screen column ([`Screen::column`]).
struct Column {
    near: ColumnFace,
    far: ColumnFace,
}

/// One face of the frustum at a screen column: its points on the bottom and top
/// edges, the step between them, and the edges' directions.
struct ColumnFace {
    bottom: DVec3,
    top: DVec3,
    up: DVec3,
    along_bottom: DVec3,
    along_top: DVec3,
}

impl ColumnFace {
    /// The point at height `y`.
    fn point(&self, y: f64) -> DVec3 {
        self.bottom.lerp(self.top, y)
    }

    /// The derivatives in `x` and `y` of the point at height `y`.
    fn derivatives(&self, y: f64) -> [DVec3; 2] {
        [self.along_bottom.lerp(self.along_top, y), self.up]
    }
}

impl Column {
    /// The origin and direction of the ray at height `y` (those of
    /// [`Column::ray`], without its derivatives).
    fn line(&self, y: f64) -> (DVec3, DVec3) {
        let origin = self.near.point(y);
        (origin, self.far.point(y) - origin)
    }

    /// The ray at height `y`: the bilinear interpolation of the near and of the far
    /// face's corners, and its exact derivatives in `x` and `y`.
    fn ray(&self, y: f64) -> Ray {
        let (origin, dir) = self.line(y);
        let (d_origin, d_far) = (self.near.derivatives(y), self.far.derivatives(y));
        Ray {
            origin,
            dir,
            d_origin,
            d_dir: [d_far[0] - d_origin[0], d_far[1] - d_origin[1]],
        }
    }
}

/// The probe points of `ray`, whose segment in the receivers' box is `seg` (see
/// [`Probe::fill`]).
///
/// Where the surface a pixel sees lies is unknown; the receivers' box stands in for
/// it: the face the ray enters through (eye outside the box), else the inner face
/// it leaves through (eye inside: the floor, walls and ground of a scene seen from
/// within), each with that face's normal; where the ray leaves through the far plane
/// instead, `DEPTHS` points at log-spaced depths along its segment inside the box,
/// facing the bisector of the eye and light directions. Between these cases the
/// weights blend over a 5% band of depth, and a face's normal over a 2% band near
/// the box's edges, so every weight and normal is continuous.
///
/// The points are added to `out` as planned (of the ray numbered `index`), to be
/// made by [`point_at`] once every ray's are planned.
fn ray_points(
    rays: &Rays,
    ray: &Ray,
    index: usize,
    seg: &Segment,
    pass: Pass,
    out: &mut ArrayVec<PlannedPoint, { RAYS * (DEPTHS + 2) }>,
) -> f64 {
    let d = ray.dir;
    let light = rays.light;
    let mut push = |s: f64, n: DVec3, weight: f64, fade: f64| {
        // At most two face points and `DEPTHS` volume points a ray: never full.
        let _ = out.try_push(PlannedPoint {
            ray: index,
            s,
            n,
            weight,
            fade,
        });
    };
    // The bisector of the eye and light directions; where the light comes straight
    // at the viewer it vanishes, and the points facing it fade out.
    let mut facing_bisector = None;
    let mut bisector = || {
        *facing_bisector.get_or_insert_with(|| {
            let bisector = -d.normalize_or_zero() - light;
            let facing = bisector.length();
            (bisector / facing, smoothstep(0.0, 0.1, facing))
        })
    };
    // A face point: on the face with its normal where front-lit (only front-lit
    // surfaces matter: within about 3° of parallel to the light shading darkens a
    // surface whatever the map says, and its texels stretch without bound, so such
    // faces fade out between sin 3° and sin 6°, in weight and in error: see
    // `Point::fade`), or facing the bisector.
    let mut face_point = |s: f64, slabs: &[f64; 3], weight: f64| match pass {
        Pass::Lit => {
            let n = seg.face_normal(s, slabs, d);
            let lit = smoothstep(0.05, 0.1, -n.dot(light));
            push(s, n, weight * lit, lit);
        }
        Pass::Perspective => {
            let (n_bisector, w_bisector) = bisector();
            push(s, n_bisector, weight * w_bisector, 1.0);
        }
    };
    let (ray_weight, alpha, beta) = (seg.ray_weight, seg.alpha, seg.beta);
    if alpha > 0.0 {
        face_point(seg.s0, &seg.enter, ray_weight * alpha);
    }
    let w_exit = ray_weight * (1.0 - alpha) * beta;
    if w_exit > 0.0 {
        face_point(seg.s1, &seg.exit, w_exit);
    }
    let w_segment = ray_weight * (1.0 - alpha) * (1.0 - beta) / DEPTHS as f64;
    if !(w_segment > 0.0) {
        return ray_weight;
    }
    let (n_bisector, w_bisector) = bisector();
    let w_volume = w_segment * w_bisector;
    if !(w_volume > 0.0) {
        return ray_weight;
    }
    // Depths `z0 (z1 / z0)^((k + 1/2) / DEPTHS)`: odd powers of the eighth root.
    let (z0, z1, zn, zf) = (seg.z0, seg.z1, seg.zn, seg.zf);
    let root = math::sqrt(math::sqrt(math::sqrt(z1 / z0)));
    let mut z = z0 * root;
    for _ in 0..DEPTHS {
        push((z - zn) / (zf - zn), n_bisector, w_volume, 1.0);
        z *= root * root;
    }
    ray_weight
}

/// A probe point to be made by [`point_at`]: its ray (by number), its parameter
/// on the ray, the normal of the plane it lies on, its weight and its fade.
struct PlannedPoint {
    ray: usize,
    s: f64,
    n: DVec3,
    weight: f64,
    fade: f64,
}

/// A probe ray's segment inside the receivers' box: its parameters (`s`, 0 at the
/// near face and 1 at the far face) and view depths, the slabs' entry and exit
/// parameters, and the weights of [`ray_points`].
struct Segment {
    enter: [f64; 3],
    exit: [f64; 3],
    s0: f64,
    s1: f64,
    zn: f64,
    zf: f64,
    z0: f64,
    z1: f64,
    /// The ray's weight: rays that graze the box fade out (the clipped segment
    /// shrinks to a point) to a small floor, which is every ray's weight on a flat
    /// box.
    ray_weight: f64,
    /// The share of the face it enters through (the eye outside the box) ...
    alpha: f64,
    /// ... and of the face it leaves through before the far plane.
    beta: f64,
}

impl Segment {
    /// The segment in box `b` of the ray from `o` along `d`; `None` where it misses
    /// the box.
    fn new(o: DVec3, d: DVec3, screen: &Screen, b: &Bounds) -> Option<Self> {
        let (mut enter, mut exit) = ([f64::NEG_INFINITY; 3], [f64::INFINITY; 3]);
        for axis in 0..3 {
            if d[axis] == 0.0 {
                if o[axis] < b.min[axis] || o[axis] > b.max[axis] {
                    return None;
                }
                continue;
            }
            // Finite bounds and ray, `d != 0`: no NaN for `min_num` and `max_num`.
            let t0 = (b.min[axis] - o[axis]) / d[axis];
            let t1 = (b.max[axis] - o[axis]) / d[axis];
            enter[axis] = min_num(t0, t1);
            exit[axis] = max_num(t0, t1);
        }
        let s_enter = max_num(max_num(enter[0], enter[1]), enter[2]);
        let s_exit = min_num(min_num(exit[0], exit[1]), exit[2]);
        let (s0, s1) = (max_num(s_enter, 0.0), min_num(s_exit, 1.0));
        let (zn, zf) = (screen.depth(o), screen.depth(o + d));
        let depth = |s: f64| zn + s * (zf - zn);
        let (z0, z1) = (depth(s0), depth(s1));
        if !(s0 <= s1 && z0 > 0.0 && z1 >= z0 && zf > zn) {
            return None;
        }
        Some(Self {
            enter,
            exit,
            s0,
            s1,
            zn,
            zf,
            z0,
            z1,
            ray_weight: log_step(z1, z0).max(RAY_WEIGHT_FLOOR),
            alpha: if s_enter > 0.0 { log_step(z0, zn) } else { 0.0 },
            beta: if s_exit < 1.0 { log_step(zf, z1) } else { 0.0 },
        })
    }

    /// The normal of the box face at parameter `s_face` (where `slabs` holds the
    /// slabs' parameters there), blended with its neighbours' within 2% of depth of
    /// an edge so that it turns continuously; `d` the ray's direction.
    fn face_normal(&self, s_face: f64, slabs: &[f64; 3], d: DVec3) -> DVec3 {
        let mut n = DVec3::ZERO;
        let mut blended = 0;
        let depth_face = self.zn + s_face * (self.zf - self.zn);
        for axis in 0..3 {
            let apart = (s_face - slabs[axis]).abs() * (self.zf - self.zn);
            // Slabs far from this face's (a relative depth above 0.02 by more than
            // rounding) add nothing: skip the division.
            if apart >= FACE_BAND_SATURATED * depth_face {
                continue;
            }
            let rel = apart / depth_face;
            let mut e = DVec3::ZERO;
            e[axis] = -d[axis].signum();
            let w = 1.0 - smoothstep(0.0, 0.02, rel);
            n += e * w;
            blended += usize::from(w != 1.0);
        }
        // Away from the box's edges the normal is one axis at full weight, a unit
        // vector already (normalizing it would return it unchanged).
        if blended == 0 && n.length_squared() == 1.0 {
            n
        } else {
            n.normalize_or_zero()
        }
    }
}

/// Above this relative depth a slab's face blend is surely 0 (see `ray_points`):
/// `0.02` raised by a relative `1e-9`, far beyond rounding.
const FACE_BAND_SATURATED: f64 = 0.020_000_000_02;

/// `smoothstep(0, 0.05, ln(num / den))`, the logarithm skipped where the step is
/// 1: above `e^0.05` by a relative `1e-12` the logarithm exceeds `0.05` whatever
/// its last bit. That test compares `num` with `den` scaled (for `den > 0`), so a
/// ray's branch does not wait on the division: where the product and the
/// quotient round to opposite sides, the ratio is within a few units in the last
/// place of the bound, and the logarithm's step is 1 there too.
pub(super) fn log_step(num: f64, den: f64) -> f64 {
    const SATURATED: f64 = 1.051_271_096_377_2; // e^0.05 (1 + 1.1e-12)
    if den > 0.0 && num >= SATURATED * den {
        1.0
    } else {
        smoothstep(0.0, 0.05, math::ln(num / den))
    }
}

/// The probe point at parameter `s` of `ray`, on the plane through it with normal
/// `n`: its screen steps are how far the point moves on that plane when the ray
/// moves by `step` on the screen.
///
/// With `p(u) = o(u) + d(u) t(u)` the hit of the plane, `t` its ray parameter, the
/// derivative in a screen coordinate `u` is `P (o' + d' t)`, `P = I - d nᵀ / (n·d)`
/// the projection along the ray onto the plane: what the neighbouring pixels'
/// rays meet the plane at, in the limit of a small step.
#[inline]
pub(super) fn point_at(
    ray: &Ray,
    step: DVec2,
    s: f64,
    n: DVec3,
    weight: f64,
    fade: f64,
) -> Option<Point> {
    if !(weight > 0.0) {
        return None;
    }
    let d = ray.dir;
    let denom = n.dot(d);
    if !(denom.abs() > 1e-12 * d.length()) {
        return None;
    }
    let moved = |axis: usize, h: f64| {
        let v = (ray.d_origin[axis] + ray.d_dir[axis] * s) * h;
        v - d * (n.dot(v) / denom)
    };
    let q = Point {
        p: ray.origin + d * s,
        dx: moved(0, step.x),
        dy: moved(1, step.y),
        weight,
        fade,
    };
    (q.p.is_finite() && q.dx.is_finite() && q.dy.is_finite()).then_some(q)
}
