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
use shadowmap_frustum::math;

use crate::focus::{Focus, View, smoothstep};
use rays::{Pass, Rays};

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
// `points_error` raises `1 / s²` to the fourth power and takes the mean's eighth
// root as three square roots.
const _: () = assert!(POWER == 8);

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

/// Probe rays.
const RAYS: usize = COLUMNS * ROWS;
/// Most probe points of a focus body.
const MAX_POINTS: usize = RAYS * DEPTHS;

/// Probe points stored by coordinate (one array per component of [`Point`]), so
/// that [`points_error`]'s loop runs on several points at once (SIMD lanes), which
/// an array of points does not let the compiler do.
///
/// The points and their screen steps are kept in the light frame
/// ([`Focus::rot`](crate::focus::Focus)), `x` and `y` alone: a directional light's
/// texel coordinates and `w` do not depend on the light-frame `z` (the depth along
/// the light), so every fit's error reads those two (see [`points_error`]).
#[derive(Clone, Debug, Default)]
struct ProbePoints {
    p: [ArrayVec<f64, MAX_POINTS>; 2],
    dx: [ArrayVec<f64, MAX_POINTS>; 2],
    dy: [ArrayVec<f64, MAX_POINTS>; 2],
    weight: ArrayVec<f64, MAX_POINTS>,
    fade: ArrayVec<f64, MAX_POINTS>,
    /// The sum of `weight`, in the points' order (every error divides by it).
    weight_sum: f64,
}

impl ProbePoints {
    fn new() -> Self {
        Self {
            p: [ArrayVec::new(), ArrayVec::new()],
            dx: [ArrayVec::new(), ArrayVec::new()],
            dy: [ArrayVec::new(), ArrayVec::new()],
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

    /// Adds `q` (in the world) in the light frame `light_from_world` (a rotation:
    /// its `x` and `y` rows), unless the set is full.
    fn push(&mut self, q: &Point, light_from_world: &DMat4) {
        if self.weight.is_full() {
            return;
        }
        let m = light_from_world;
        let rows = [
            DVec3::new(m.x_axis.x, m.y_axis.x, m.z_axis.x),
            DVec3::new(m.x_axis.y, m.y_axis.y, m.z_axis.y),
        ];
        for (axis, row) in rows.iter().enumerate() {
            self.p[axis].push(row.dot(q.p));
            self.dx[axis].push(row.dot(q.dx));
            self.dy[axis].push(row.dot(q.dy));
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
/// the parameterization alone, which needs no lit surface), are `perspective`.
///
/// The probe depends on the body alone (its view, receivers and light), so a
/// [`FocusBody`](crate::FocusBody) fills it once and every warp fitted from that
/// body chooses its strength on the same points.
#[derive(Clone, Debug)]
pub(crate) struct Probe {
    points: ProbePoints,
    /// The perspective set, cast only where the confidence is below 1.
    perspective: ProbePoints,
    /// The weight the points would carry if every surface were front-lit.
    geometric: f64,
    /// The uniform fit's error ([`points_error`]) over `points` and over
    /// `perspective` (infinite where that fit fails or the set was not cast): every
    /// warp's strength 0, so computed once with the points (see [`Probe::fill`]).
    uniform_error: [f64; 2],
    /// Whether [`Probe::fill`] has cast the points.
    filled: bool,
}

impl Probe {
    /// No probe points; [`Probe::fill`] casts them. (A probe is large: it is filled
    /// where it lives rather than moved.)
    pub(crate) fn new() -> Self {
        Self {
            points: ProbePoints::new(),
            perspective: ProbePoints::new(),
            geometric: 0.0,
            uniform_error: [f64::INFINITY; 2],
            filled: false,
        }
    }

    /// Whether [`Probe::fill`] has cast the points.
    pub(crate) fn is_filled(&self) -> bool {
        self.filled
    }

    /// Casts the probe points of `f` seen from `view` (the face-normal set, and
    /// the perspective set where the confidence is below 1), replacing any, and
    /// predicts the error of the uniform fit, whose clip matrix from the light frame
    /// is `uniform_clip_from_light` (`None` where it fails), over each.
    ///
    /// Every warp at strength 0 is that fit: LiSPSM's and TSM's exactly (the same
    /// [`warp_clip`](crate::lispsm::warp_clip)), XPSM's orthographic fit of the
    /// same footprint, cut by the caster box where that box is narrower (then
    /// finer, never coarser). So the baseline each warp's strength is judged
    /// against ([`choose`]'s ratio) is the uniform fit's, made once per body rather
    /// than once per warp.
    pub(crate) fn fill(&mut self, view: &View, f: &Focus, uniform_clip_from_light: Option<&DMat4>) {
        let rays = Rays::new(view, f);
        self.points.clear();
        self.perspective.clear();
        self.geometric = rays.cast(Pass::Lit, &mut self.points);
        let cast_perspective = self.confidence() < 1.0;
        if cast_perspective {
            rays.cast(Pass::Perspective, &mut self.perspective);
        }
        self.uniform_error = [f64::INFINITY; 2];
        if let Some(clip) = uniform_clip_from_light {
            if self.confidence() > 0.0 {
                self.uniform_error[0] = points_error(&self.points, clip);
            }
            if cast_perspective {
                self.uniform_error[1] = points_error(&self.perspective, clip);
            }
        }
        self.filled = true;
    }

    /// The fraction `t` in `[0, 1]` of a warp's formula strength to use, from its
    /// fit at a strength `t` (`None` where the fit fails) and that fit's clip
    /// matrix from the light frame (`clip_from_light`, see [`points_error`]):
    /// [`choose`] on the predicted error, blended by [`Probe::confidence`]
    /// with [`choose`] on the perspective-only error (every point facing the
    /// bisector of the eye and light directions). Where the receivers' box shows few
    /// front-lit faces (a light that grazes the ground, whose visible surfaces are
    /// then walls, fences and trunks the box does not have) the parameterization
    /// alone decides: falling back to the formula instead kept XPSM's length at a
    /// fence lit from 3° above the horizon, predicted 2x the uniform fit's error and
    /// measured 1.57x. Each fit is made once for both errors and kept in `fits`,
    /// where the warp reads the one at the chosen `t` ([`Fits::at`]: `t` one of
    /// the grid's, the usual case: the formula's strength or the uniform fit)
    /// rather than fitting it again.
    pub(crate) fn strength<T>(
        &self,
        fits: &mut Fits<T>,
        fit_at: impl FnMut(f64) -> Option<T>,
        clip_from_light: impl Fn(&T) -> &DMat4,
    ) -> f64 {
        self.strength_with(
            fits,
            fit_at,
            clip_from_light,
            (&self.perspective, self.uniform_error),
        )
    }

    /// [`Probe::strength`] with the perspective set `perspective` (read only where
    /// the confidence is below 1) and the errors at strength 0 over the two sets,
    /// `uniform_error` (the warp's fits start at the next strength of the grid).
    fn strength_with<T>(
        &self,
        fits: &mut Fits<T>,
        mut fit_at: impl FnMut(f64) -> Option<T>,
        clip_from_light: impl Fn(&T) -> &DMat4,
        (perspective, uniform_error): (&ProbePoints, [f64; 2]),
    ) -> f64 {
        let confidence = self.confidence();
        let mut error_at = |t: f64, points: &ProbePoints, uniform: f64| {
            if t == 0.0 {
                return uniform;
            }
            fits.get_or_make(grid_index(t), || fit_at(t))
                .map_or(f64::INFINITY, |fit| {
                    points_error(points, clip_from_light(fit))
                })
        };
        let lit =
            (confidence > 0.0).then(|| choose(|t| error_at(t, &self.points, uniform_error[0])));
        match lit {
            Some(t) if confidence >= 1.0 => t,
            _ => {
                let perspective = choose(|t| error_at(t, perspective, uniform_error[1]));
                lit.map_or(perspective, |t| {
                    perspective + (t - perspective) * confidence
                })
            }
        }
    }

    /// The predicted error of the fit whose clip matrix from the light frame is
    /// `clip_from_light` over the face-normal set, and the uniform fit's there (as
    /// [`Probe::fill`] predicted it).
    #[cfg(test)]
    pub(crate) fn lit_errors(&self, clip_from_light: &DMat4) -> (f64, f64) {
        (
            points_error(&self.points, clip_from_light),
            self.uniform_error[0],
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

/// The power mean `E` of the aliasing error over `points` for `clip_from_light`
/// (see the module's documentation), infinite when a point falls behind the
/// projection centre.
///
/// `clip_from_light` is a fit's clip matrix from the light frame, whose `x`, `y`
/// and `w` rows do not read the light-frame `z` (true of every fit of a
/// directional light: its `z` column reaches clip `z` alone); the points are in
/// that frame ([`ProbePoints`]).
fn points_error(points: &ProbePoints, clip_from_light: &DMat4) -> f64 {
    // Only clip x, y and w matter: the columns' (x, y, w) of light-frame x, y and
    // the translation, multiplied and summed in the order of the matrix product
    // (a direction's zero `w` term left out).
    let m = clip_from_light;
    debug_assert!(m.z_axis.x == 0.0 && m.z_axis.y == 0.0 && m.z_axis.w == 0.0);
    let [cx, cy, cw] = [m.x_axis, m.y_axis, m.w_axis].map(|c| DVec3::new(c.x, c.y, c.w));
    let n = points.len().min(MAX_POINTS);
    let [px, py] = points.p.each_ref().map(|c| &c[..n]);
    let [dxx, dxy] = points.dx.each_ref().map(|c| &c[..n]);
    let [dyx, dyy] = points.dy.each_ref().map(|c| &c[..n]);
    let (weight, fade) = (&points.weight[..n], &points.fade[..n]);
    // Each point's term first, with no branch, so the loop runs on several points
    // at once; then their sum.
    let mut terms = [0.0; MAX_POINTS];
    let mut behind = false;
    let dx = |i: usize| DVec2::new(dxx[i], dxy[i]);
    let dy = |i: usize| DVec2::new(dyx[i], dyy[i]);
    // The term of point `i` from `1 / s²` of its screen steps' moves in ndc.
    let term = |i: usize, inv_s2: f64| {
        (
            weight[i] * pow4(inv_s2 * fade[i] * fade[i]),
            !(inv_s2 < f64::INFINITY),
        )
    };
    if cx.z == 0.0 && cy.z == 0.0 && cw.z == 1.0 {
        // An affine clip (every orthographic fit: a warp at strength 0) moves ndc
        // by its x and y rows alone: `w = 1` and `dw = 0` exactly, so the general
        // form below gives the same values, without the point's own `h` and `w⁴`.
        let ndc = |d: DVec2| {
            let dh = cx * d.x + cy * d.y;
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
            let h = cx * px[i] + cy * py[i] + cw;
            let hw = h.z;
            // A move in ndc is `(dh.xy w - h.xy dh.w) / w²`: its `1 / s²` is that
            // of the numerators times `w⁴` (one division a point, not five).
            let moved = |d: DVec2| {
                let dh = cx * d.x + cy * d.y;
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
        // The eighth root as three square roots (to an ulp or two of `powf`'s, in
        // a third of its time).
        math::sqrt(math::sqrt(math::sqrt(sum / weights)))
    } else {
        0.0
    }
}

/// `x^4` (`m^P` from `1 / s²`, `P = 8`).
fn pow4(x: f64) -> f64 {
    let x2 = x * x;
    x2 * x2
}

/// Strengths at which a warp is evaluated, as fractions of its formula's warp in
/// `ln(1 + s d)` (0: the uniform fit, 1: the formula's).
const GRID: usize = 5;

/// The grid strength nearest `t` (by index).
fn grid_index(t: f64) -> usize {
    (math::round(t * (GRID - 1) as f64) as usize).min(GRID - 1)
}

/// The fits a warp's strength choice made ([`Probe::strength`]), one per grid
/// strength at most (`None` where the fit failed), held by the warp: the fit it
/// keeps is read where it was made, not moved out (a fit is a few hundred bytes;
/// the fixed-capacity list is not initialized, where an array of them would be).
pub(crate) struct Fits<T>(ArrayVec<(usize, Option<T>), GRID>);

impl<T> Fits<T> {
    /// No fits yet.
    pub(crate) const fn new() -> Self {
        Self(ArrayVec::new_const())
    }

    /// The fit at grid strength `index`, made by `make` unless it was made before.
    fn get_or_make(&mut self, index: usize, make: impl FnOnce() -> Option<T>) -> Option<&T> {
        let slot = match self.0.iter().position(|(i, _)| *i == index) {
            Some(slot) => slot,
            None => {
                // One fit per grid strength: never full.
                self.0.try_push((index, make())).ok()?;
                self.0.len() - 1
            }
        };
        self.0.get(slot)?.1.as_ref()
    }

    /// The fit made at `t`, where `t` is a grid strength the choice fitted at and
    /// the fit succeeded.
    pub(crate) fn at(&self, t: f64) -> Option<&T> {
        let index = grid_index(t);
        let on_grid = t == index as f64 / (GRID - 1) as f64;
        let (_, fit) = self.0.iter().find(|(i, _)| on_grid && *i == index)?;
        fit.as_ref()
    }
}

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

mod rays;
#[cfg(test)]
mod tests;
