//! The predicted aliasing error of a fit over the focus body, and
//! the warp strength every warp of this crate chooses from it.
//!
//! A warp's strength (LiSPSM's `n`, TSM's trapezoid, XPSM's projection vector) is
//! set by a formula that assumes a particular layout: the visible region starts at
//! the viewer and runs along the view direction, made perpendicular to the light
//! (Wimmer et al.'s `n_opt`, Martin and Tan's 80% rule, Gusev's `coef / cos γ`).
//! Where the layout differs (a camera looking down, a light near the view axis, a
//! focus body much larger than what is seen, a projection vector clipped at the
//! back-projection singularity) the formula over-warps, and the warp can lose badly
//! to the uniform fit. So each warp evaluates its own fit at a few strengths on a
//! fixed set of probe points of the focus body and takes the strength of least
//! predicted error, which is the uniform fit where warping does not pay.
//!
//! The probe points: a grid of view rays through the frustum (of the camera or of
//! one cascade slice), each meeting the box around frustum ∩ receivers where a
//! rendered pixel would most likely see a surface: the face it enters through (eye
//! outside the box), else the inner face it leaves through (eye inside: floor,
//! walls, ground), with that face's normal; where it leaves through the far plane
//! instead, points at log-spaced depths along its segment in the box, facing the
//! bisector of the eye and light directions. At each point the error is the
//! aliasing error of Lloyd, Tuft, Yoon and Manocha (*Warping and Partitioning for
//! Low Error Shadow Maps*, EGSR 2006), the size of a texel in pixels:
//!
//! ```text
//! J = d(shadow-map ndc) / d(pixel)     2x2
//! m = 1 / s_min(J)                     (in units common to every candidate)
//! E = (Σ w_i m_i^P / Σ w_i)^(1/P)      P = 8; weights fade rays that graze the box
//!                                      and faces within about 3° of the light
//! ```
//!
//! Only front-lit faces of the box count (their weight fades with the light's angle
//! to them). Where few are lit (a light grazing the ground, which then lights walls,
//! fences and trunks the box does not have) the same points facing the bisector of
//! the eye and light directions decide instead, blended by the lit share of the
//! weight ([`Probe::strength`]): the error of the parameterization alone, Lloyd et
//! al.'s perspective aliasing, which needs no lit surface.
//!
//! Every ingredient is a continuous function of the camera and the light (weights
//! fade points in and out; only a ray that stops meeting the box altogether drops
//! out, by then at a small floor weight), and so is the chosen strength (below):
//! the fits do not pop.

use arrayvec::ArrayVec;
use glam::{DMat4, DVec2, DVec3};
use shadowmap_frustum::math::{self, max_num, min_num};

use crate::focus::{Bounds, Focus, View, smoothstep};

/// Rays across and down the view.
const COLUMNS: usize = 8;
const ROWS: usize = 6;
/// Probe points per ray.
const DEPTHS: usize = 4;
// `ray_points` spaces them by the eighth root of the depth ratio (three square roots).
const _: () = assert!(DEPTHS == 4);
/// Exponent of the power mean over the probe points (between a mean and a maximum,
/// close to the high percentiles by which the quality report ranks techniques).
const POWER: i32 = 8;
// `points_error` raises `1 / s²` to the fourth power.
const _: () = assert!(POWER == 8);
/// Smallest weight of a ray that meets the box.
const RAY_WEIGHT_FLOOR: f64 = 1e-3;
/// Screen step (a fraction of the screen height) of the probe points' Jacobians:
/// a unit common to every candidate, so its size only scales the error.
const STEP: f64 = 1e-3;

/// One probe point: the world point, the world displacements of one screen step in
/// x and y on the plane through it facing the bisector, its weight, and the factor
/// its error counts with.
#[derive(Clone, Copy, Debug)]
struct Point {
    p: DVec3,
    dx: DVec3,
    dy: DVec3,
    weight: f64,
    /// The lit fade of a face point (1 elsewhere), applied to its error `m` as
    /// well as to its weight: under a power mean of exponent [`POWER`] a weight
    /// bounds a point's share only as its eighth root, so a face lit at a grazing
    /// angle, whose texels stretch along it, would decide the mean at any weight
    /// but 0. Two floor points lit at 3.4°, at 6.5% weight and 4.5 times the
    /// error of the wall the camera faced, chose LiSPSM's and XPSM's full warps
    /// (1.55 and 1.61 times the uniform fit's measured error, `compare --seed 105
    /// --sweep 64`, random_indoor_room_051); faded in error too, the uniform fit.
    fade: f64,
}

/// The ray through one screen position and how it moves with the screen: its
/// origin on the near face, its direction (to the far face), and their derivatives
/// per unit of normalized screen `x` and `y`.
#[derive(Clone, Copy)]
struct Ray {
    origin: DVec3,
    dir: DVec3,
    d_origin: [DVec3; 2],
    d_dir: [DVec3; 2],
}

/// Probe rays.
const RAYS: usize = COLUMNS * ROWS;
/// Most probe points of a focus body.
const MAX_POINTS: usize = RAYS * DEPTHS;

/// Probe points stored by coordinate (one array per component of [`Point`]), so
/// that [`points_error`]'s loop runs on several points at once (SIMD lanes), which
/// an array of points does not let the compiler do.
#[derive(Clone, Debug, Default)]
struct ProbePoints {
    p: [ArrayVec<f64, MAX_POINTS>; 3],
    dx: [ArrayVec<f64, MAX_POINTS>; 3],
    dy: [ArrayVec<f64, MAX_POINTS>; 3],
    weight: ArrayVec<f64, MAX_POINTS>,
    fade: ArrayVec<f64, MAX_POINTS>,
    /// The sum of `weight`, in the points' order (every error divides by it).
    weight_sum: f64,
}

impl ProbePoints {
    fn new() -> Self {
        Self {
            p: [ArrayVec::new(), ArrayVec::new(), ArrayVec::new()],
            dx: [ArrayVec::new(), ArrayVec::new(), ArrayVec::new()],
            dy: [ArrayVec::new(), ArrayVec::new(), ArrayVec::new()],
            weight: ArrayVec::new(),
            fade: ArrayVec::new(),
            weight_sum: 0.0,
        }
    }

    fn len(&self) -> usize {
        self.weight.len()
    }

    fn clear(&mut self) {
        for column in self.p.iter_mut().chain(&mut self.dx).chain(&mut self.dy) {
            column.clear();
        }
        self.weight.clear();
        self.fade.clear();
        self.weight_sum = 0.0;
    }

    /// Adds `q` unless the set is full.
    fn push(&mut self, q: &Point) {
        if self.weight.is_full() {
            return;
        }
        for axis in 0..3 {
            self.p[axis].push(q.p[axis]);
            self.dx[axis].push(q.dx[axis]);
            self.dy[axis].push(q.dy[axis]);
        }
        self.weight.push(q.weight);
        self.fade.push(q.fade);
        self.weight_sum += q.weight;
    }
}

/// The probe points of a focus body: `points` with the normals of the receivers'
/// box faces they lie on, weighted by how front-lit those faces are. Where few
/// faces are front-lit ([`Probe::confidence`] below 1) the same places facing the
/// bisector of the eye and light directions, at their whole weight (the error of
/// the parameterization alone, which needs no lit surface), are cast again from the
/// rays kept in `rays` when a strength is chosen.
///
/// The probe depends on the body alone (its view, receivers and light), so a
/// [`FocusBody`](crate::FocusBody) fills it once and every warp fitted from that
/// body chooses its strength on the same points.
#[derive(Clone, Debug)]
pub(crate) struct Probe {
    points: ProbePoints,
    /// The weight the points would carry if every surface were front-lit.
    geometric: f64,
    /// What the rays were cast from, for the perspective pass.
    rays: Option<Rays>,
}

/// What a probe's rays are cast from: the screen, the receivers' box, the screen
/// step and the light.
#[derive(Clone, Debug)]
struct Rays {
    screen: Screen,
    receivers: Bounds,
    step: DVec2,
    light: DVec3,
}

impl Rays {
    /// Adds the points of `pass` of every ray to `out`, row by row; returns the sum
    /// of the rays' weights.
    fn cast(&self, pass: Pass, out: &mut ProbePoints) -> f64 {
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
        for w in &planned {
            if let Some(q) = point_at(&rays[w.ray], self.step, w.s, w.n, w.weight, w.fade) {
                out.push(&q);
            }
        }
        geometric
    }
}

/// Which of a probe's two point sets a pass over the rays adds to.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Face points with the faces' normals and lit weights, and the volume points.
    Lit,
    /// The same places facing the bisector of the eye and light directions.
    Perspective,
}

/// The view frustum as a screen: rays by normalized position, `(0, 0)` bottom left.
#[derive(Clone, Debug)]
struct Screen {
    near: [DVec3; 4],
    far: [DVec3; 4],
    forward: DVec3,
    eye: DVec3,
}

impl Screen {
    /// The ray through `(x, y)`: the bilinear interpolation of the near and of the
    /// far face's corners, and its exact derivatives in `x` and `y`.
    #[cfg(test)]
    fn ray(&self, x: f64, y: f64) -> Ray {
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

    /// The point at height `y` and its derivatives in `x` and `y`.
    fn at(&self, y: f64) -> (DVec3, [DVec3; 2]) {
        let along_x = self.along_bottom.lerp(self.along_top, y);
        (self.point(y), [along_x, self.up])
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
        let (origin, d_origin) = self.near.at(y);
        let (far, d_far) = self.far.at(y);
        Ray {
            origin,
            dir: far - origin,
            d_origin,
            d_dir: [d_far[0] - d_origin[0], d_far[1] - d_origin[1]],
        }
    }
}

impl Probe {
    /// No probe points; [`Probe::fill`] casts them. (A probe is large: it is filled
    /// where it lives rather than moved.)
    pub(crate) fn new() -> Self {
        Self {
            points: ProbePoints::new(),
            geometric: 0.0,
            rays: None,
        }
    }

    /// Whether [`Probe::fill`] has cast the points.
    pub(crate) fn is_filled(&self) -> bool {
        self.rays.is_some()
    }

    /// Casts the probe points of `f` seen from `view` (the face-normal set; the
    /// perspective set is cast when [`Probe::strength`] needs it), replacing any.
    pub(crate) fn fill(&mut self, view: &View, f: &Focus) {
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
        let rays = Rays {
            screen,
            receivers,
            step,
            light: f.light,
        };
        self.points.clear();
        self.geometric = rays.cast(Pass::Lit, &mut self.points);
        self.rays = Some(rays);
    }

    /// The fraction `t` in `[0, 1]` of a warp's formula strength to use, from its
    /// fit at a strength `t` (`None` where the fit fails) and that fit's clip
    /// matrix: [`choose`] on the predicted error, blended by [`Probe::confidence`]
    /// with [`choose`] on the perspective-only error (every point facing the
    /// bisector of the eye and light directions). Where the receivers' box shows few
    /// front-lit faces (a light that grazes the ground, whose visible surfaces are
    /// then walls, fences and trunks the box does not have) the parameterization
    /// alone decides: falling back to the formula instead kept XPSM's length at a
    /// fence lit from 3° above the horizon, predicted 2x the uniform fit's error and
    /// measured 1.57x. Each fit is made once for both errors, and the one at the
    /// chosen `t` is returned where it was made (`t` one of the grid's, the usual
    /// case: the formula's strength or the uniform fit), so the warp need not fit
    /// it again.
    pub(crate) fn strength<T>(
        &self,
        fit_at: impl FnMut(f64) -> Option<T>,
        clip: impl Fn(&T) -> &DMat4,
    ) -> (f64, Option<T>) {
        self.strength_with(fit_at, clip, |out| {
            if let Some(rays) = &self.rays {
                rays.cast(Pass::Perspective, out);
            }
        })
    }

    /// [`Probe::strength`] with the perspective set cast by `perspective` (only
    /// where the confidence is below 1).
    fn strength_with<T>(
        &self,
        mut fit_at: impl FnMut(f64) -> Option<T>,
        clip: impl Fn(&T) -> &DMat4,
        perspective: impl FnOnce(&mut ProbePoints),
    ) -> (f64, Option<T>) {
        let confidence = self.confidence();
        let mut fits: [Option<Option<T>>; GRID] = [const { None }; GRID];
        let grid_index = |t: f64| (math::round(t * (GRID - 1) as f64) as usize).min(GRID - 1);
        let mut error_at = |t: f64, points: &ProbePoints| {
            fits[grid_index(t)]
                .get_or_insert_with(|| fit_at(t))
                .as_ref()
                .map_or(f64::INFINITY, |fit| points_error(points, clip(fit)))
        };
        let lit = (confidence > 0.0).then(|| choose(|t| error_at(t, &self.points)));
        let t = match lit {
            Some(t) if confidence >= 1.0 => t,
            _ => {
                let mut points = ProbePoints::new();
                perspective(&mut points);
                let perspective = choose(|t| error_at(t, &points));
                lit.map_or(perspective, |t| {
                    perspective + (t - perspective) * confidence
                })
            }
        };
        let i = grid_index(t);
        let on_grid = t == i as f64 / (GRID - 1) as f64;
        (
            t,
            if on_grid {
                fits[i].take().flatten()
            } else {
                None
            },
        )
    }

    /// How far the prediction is to be trusted, in `[0, 1]`: 0 when no probe point
    /// is front-lit (or none meets the receivers), 1 from a tenth of the probe's
    /// weight on, smooth in between, so that a fit can blend from its formula to the
    /// predicted choice continuously as surfaces turn toward the light.
    pub(crate) fn confidence(&self) -> f64 {
        let lit = self.points.weight_sum;
        if self.geometric > 0.0 {
            smoothstep(0.0, 0.1, lit / self.geometric)
        } else {
            0.0
        }
    }
}

/// The power mean `E` of the aliasing error over `points` for `clip_from_world`
/// (see the module's documentation), infinite when a point falls behind the
/// projection centre.
fn points_error(points: &ProbePoints, clip_from_world: &DMat4) -> f64 {
    // Only clip x, y and w matter: the columns' (x, y, w), multiplied and summed
    // in the order of the matrix product (a direction's zero `w` term left out).
    let m = clip_from_world;
    let [cx, cy, cz, cw] =
        [m.x_axis, m.y_axis, m.z_axis, m.w_axis].map(|c| DVec3::new(c.x, c.y, c.w));
    let n = points.len().min(MAX_POINTS);
    let [px, py, pz] = points.p.each_ref().map(|c| &c[..n]);
    let [dxx, dxy, dxz] = points.dx.each_ref().map(|c| &c[..n]);
    let [dyx, dyy, dyz] = points.dy.each_ref().map(|c| &c[..n]);
    let (weight, fade) = (&points.weight[..n], &points.fade[..n]);
    // Each point's term first, with no branch, so the loop runs on several points
    // at once; then their sum.
    let mut terms = [0.0; MAX_POINTS];
    let mut behind = false;
    let dx = |i: usize| DVec3::new(dxx[i], dxy[i], dxz[i]);
    let dy = |i: usize| DVec3::new(dyx[i], dyy[i], dyz[i]);
    // The term of point `i` from `1 / s²` of its screen steps' moves in ndc.
    let term = |i: usize, inv_s2: f64| {
        (
            weight[i] * pow4(inv_s2 * fade[i] * fade[i]),
            !(inv_s2 < f64::INFINITY),
        )
    };
    if cx.z == 0.0 && cy.z == 0.0 && cz.z == 0.0 && cw.z == 1.0 {
        // An affine clip (every orthographic fit: a warp at strength 0) moves ndc
        // by its x and y rows alone: `w = 1` and `dw = 0` exactly, so the general
        // form below gives the same values, without the point's own `h` and `w⁴`.
        let ndc = |d: DVec3| {
            let dh = cx * d.x + cy * d.y + cz * d.z;
            DVec2::new(dh.x, dh.y)
        };
        for (i, slot) in terms[..n].iter_mut().enumerate() {
            let inv_s2 = math::inverse_square_smaller_singular_value(ndc(dx(i)), ndc(dy(i)));
            let (t, bad) = term(i, inv_s2);
            *slot = t;
            behind |= bad;
        }
    } else {
        for (i, slot) in terms[..n].iter_mut().enumerate() {
            let h = cx * px[i] + cy * py[i] + cz * pz[i] + cw;
            let hw = h.z;
            // A move in ndc is `(dh.xy w - h.xy dh.w) / w²`: its `1 / s²` is that
            // of the numerators times `w⁴` (one division a point, not five).
            let moved = |d: DVec3| {
                let dh = cx * d.x + cy * d.y + cz * d.z;
                DVec2::new(dh.x, dh.y) * hw - DVec2::new(h.x, h.y) * dh.z
            };
            let w2 = hw * hw;
            let inv_s2 =
                math::inverse_square_smaller_singular_value(moved(dx(i)), moved(dy(i))) * (w2 * w2);
            let (t, bad) = term(i, inv_s2);
            *slot = t;
            behind |= !(hw > 0.0) | bad;
        }
    }
    if behind {
        return f64::INFINITY;
    }
    // Four interleaved partial sums (point `i` in sum `i % 4`), so the additions
    // run side by side rather than as one chain through every point.
    let mut lanes = [0.0f64; 4];
    let chunks = terms[..n].chunks_exact(4);
    for (lane, term) in lanes.iter_mut().zip(chunks.remainder()) {
        *lane += term;
    }
    for chunk in chunks {
        for (lane, term) in lanes.iter_mut().zip(chunk) {
            *lane += term;
        }
    }
    let sum = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
    let weights = points.weight_sum;
    if weights > 0.0 {
        math::powf(sum / weights, 1.0 / f64::from(POWER))
    } else {
        0.0
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
    let bisector = || {
        let bisector = -d.normalize_or_zero() - light;
        let facing = bisector.length();
        (bisector / facing, smoothstep(0.0, 0.1, facing))
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
fn log_step(num: f64, den: f64) -> f64 {
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
fn point_at(ray: &Ray, step: DVec2, s: f64, n: DVec3, weight: f64, fade: f64) -> Option<Point> {
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

/// `x^4` (`m^P` from `1 / s²`, `P = 8`).
fn pow4(x: f64) -> f64 {
    let x2 = x * x;
    x2 * x2
}

/// Strengths at which a warp is evaluated, as fractions of its formula's warp in
/// `ln(1 + s d)` (0: the uniform fit, 1: the formula's).
const GRID: usize = 5;

/// Predicted error of full warp over the uniform fit's below which the formula's
/// strength is kept as it is.
const KEEP_BELOW: f64 = 0.9;

/// The fraction `t` in `[0, 1]` of a warp's formula strength to use, from the
/// predicted errors `error(t)` at `t = 0, 1/4, ..., 1`.
///
/// Where the full warp is predicted at most [`KEEP_BELOW`] times the uniform fit's
/// error, the formula's strength is kept (`t = 1`): the paper's parameter where it
/// clearly pays. Otherwise `t` is the minimum of the parabola through the smallest
/// predicted error and its two neighbours on the grid, blended toward 1 as the
/// ratio falls from 1 to [`KEEP_BELOW`]. Each step is continuous in the predicted
/// errors (the parabola's minimum moves continuously as the smallest grid point
/// changes, since the two parabolas then agree at the midpoint), so the strength is
/// continuous in the camera and the light.
pub(crate) fn choose(mut error: impl FnMut(f64) -> f64) -> f64 {
    let at = |i: usize| i as f64 / (GRID - 1) as f64;
    let mut e = [0.0f64; GRID];
    // The ends first: they alone decide the usual cases.
    e[0] = error(at(0));
    e[GRID - 1] = error(at(GRID - 1));
    let q = e[GRID - 1] / e[0];
    if !(e[0].is_finite() && e[0] > 0.0) {
        // No usable prediction for the uniform fit: keep the formula (it is then the
        // only information there is), unless the warp is unusable too.
        return if e[GRID - 1].is_finite() { 1.0 } else { 0.0 };
    }
    if q <= KEEP_BELOW {
        return 1.0;
    }
    for (i, slot) in e.iter_mut().enumerate().take(GRID - 1).skip(1) {
        *slot = error(at(i));
    }
    let t_opt = parabola_min(&e) / (GRID - 1) as f64;
    let keep = 1.0 - smoothstep(KEEP_BELOW, 1.0, q);
    (t_opt + (1.0 - t_opt) * keep).clamp(0.0, 1.0)
}

/// The grid position (in `[0, GRID - 1]`) of the minimum of the parabola through
/// the smallest entry of `e` and its neighbours (the end triple at the ends).
fn parabola_min(e: &[f64; GRID]) -> f64 {
    let mut best = 0;
    for i in 1..GRID {
        if e[i] < e[best] {
            best = i;
        }
    }
    if !e[best].is_finite() {
        return 0.0;
    }
    let j = best.clamp(1, GRID - 2);
    let (a, b, c) = (e[j - 1], e[j], e[j + 1]);
    let curvature = a - 2.0 * b + c;
    let x = if curvature > 0.0 && a.is_finite() && c.is_finite() {
        j as f64 + 0.5 * (a - c) / curvature
    } else {
        best as f64
    };
    x.clamp((j - 1) as f64, (j + 1) as f64)
}

#[cfg(test)]
mod tests;
