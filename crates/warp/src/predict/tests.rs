//! The probe's strength choice and screen steps.

use super::rays::{Screen, log_step, point_at};
use super::*;

/// A probe whose points face the bisector only (`lit` of their weight on the
/// box's faces): a grazing light, where no face of the receivers' box is lit.
fn probe(lit: f64) -> (Probe, Vec<Point>) {
    let mut probe = Probe::new();
    let mut perspective = Vec::new();
    for k in 0..4 {
        // Steps across x are the smaller on the bisector's plane...
        let q = Point {
            p: DVec3::new(f64::from(k), 0.5, -2.0),
            dx: DVec3::new(1e-3, 0.0, 0.0),
            dy: DVec3::new(0.0, 1.0, 0.0),
            weight: 1.0,
            fade: 1.0,
        };
        perspective.push(q);
        if lit > 0.0 {
            // ... and down y on the lit faces.
            probe.points.push(
                &Point {
                    weight: lit,
                    dx: DVec3::new(1.0, 0.0, 0.0),
                    dy: DVec3::new(0.0, 1e-3, 0.0),
                    ..q
                },
                &DMat4::IDENTITY,
            );
        }
        probe.geometric += 1.0;
    }
    (probe, perspective)
}

/// [`Probe::strength`] of `probe` with its perspective set.
fn strength(
    (probe, perspective): &(Probe, Vec<Point>),
    mut clip: impl FnMut(f64) -> Option<DMat4>,
) -> f64 {
    let mut points = ProbePoints::new();
    for q in perspective {
        points.push(q, &DMat4::IDENTITY);
    }
    // Strength 0's errors, as `Probe::fill` predicts them for the uniform fit.
    let uniform = clip(0.0).expect("the fit at strength 0");
    let uniform_error = [&probe.points, &points].map(|set| points_error(set, &uniform));
    probe.strength_with(&mut Fits::new(), clip, |c| c, (&points, uniform_error))
}

/// With no front-lit face the strength is the one of least perspective-only
/// error, not the formula's: a warp whose full strength doubles the texels'
/// size (here the map shrinks as `t` grows) is not taken.
#[test]
fn without_lit_faces_the_perspective_error_chooses() {
    let clip = |t: f64| Some(DMat4::from_scale(DVec3::new(2.0 - t, 2.0 - t, 1.0)));
    let unlit = probe(0.0);
    assert_eq!(unlit.0.confidence(), 0.0);
    let t = strength(&unlit, clip);
    assert!(t < 0.05, "{t}");
    // Fully confident, the lit faces' error decides: a map that grows along y
    // and shrinks along x as `t` grows serves them best at `t = 1`, the
    // bisector's plane at `t = 0`.
    let squeeze = |t: f64| Some(DMat4::from_scale(DVec3::new(2.0 - t, 0.5 + t, 1.0)));
    let lit = probe(1.0);
    assert_eq!(lit.0.confidence(), 1.0);
    assert!(strength(&lit, squeeze) > 0.95);
    assert!(strength(&unlit, squeeze) < 0.5);
}

/// Where the ray through screen position `(x, y)` meets the plane through `p`
/// with normal `n`.
fn hit(screen: &Screen, x: f64, y: f64, p: DVec3, n: DVec3) -> DVec3 {
    let r = screen.ray(x, y);
    r.origin + r.dir * (n.dot(p - r.origin) / n.dot(r.dir))
}

/// The closed-form screen steps equal the central differences of the
/// neighbouring rays' hits on the probe plane, to the difference's own error.
#[test]
fn screen_steps_are_the_derivative_of_the_plane_hits() {
    // A skewed frustum: no face is a rectangle, so the rays are bilinear.
    let screen = Screen {
        near: [
            DVec3::new(-1.0, -0.5, -1.0),
            DVec3::new(1.2, -0.6, -1.1),
            DVec3::new(0.9, 0.7, -0.9),
            DVec3::new(-1.1, 0.4, -1.0),
        ],
        far: [
            DVec3::new(-60.0, -35.0, -100.0),
            DVec3::new(70.0, -30.0, -95.0),
            DVec3::new(55.0, 40.0, -105.0),
            DVec3::new(-65.0, 30.0, -100.0),
        ],
        forward: DVec3::NEG_Z,
        eye: DVec3::ZERO,
    };
    let step = DVec2::new(1e-3, 1e-3);
    for (x, y, s, n) in [
        (0.3, 0.2, 0.4, DVec3::Y),
        (0.8, 0.6, 0.1, DVec3::new(0.3, 0.2, 0.93).normalize()),
        (0.5, 0.9, 0.75, DVec3::new(-0.7, 0.1, 0.7).normalize()),
    ] {
        let ray = screen.ray(x, y);
        let q = point_at(&ray, step, s, n, 1.0, 1.0).unwrap();
        assert!(q.p.distance(ray.origin + ray.dir * s) < 1e-12);
        let h = 1e-4;
        let dx = (hit(&screen, x + h, y, q.p, n) - hit(&screen, x - h, y, q.p, n)) / (2.0 * h);
        let dy = (hit(&screen, x, y + h, q.p, n) - hit(&screen, x, y - h, q.p, n)) / (2.0 * h);
        for (closed, differenced) in [(q.dx, dx * step.x), (q.dy, dy * step.y)] {
            let error = (closed - differenced).length() / closed.length();
            assert!(error < 1e-6, "{closed} vs {differenced}: {error}");
            assert!(
                closed.dot(n).abs() < 1e-9 * closed.length(),
                "off the plane"
            );
        }
    }
}

/// The predicted error read off its definition: each point's ndc steps by the
/// quotient rule, the smaller singular value of that Jacobian, and the power mean of
/// `fade / s_min` weighted by `weight` (summed in the points' order).
fn error_by_definition(points: &[Point], clip_from_world: &DMat4) -> f64 {
    let (mut sum, mut weights) = (0.0, 0.0);
    for q in points {
        let h = *clip_from_world * q.p.extend(1.0);
        let ndc = |d: DVec3| {
            let dh = *clip_from_world * d.extend(0.0);
            (DVec2::new(dh.x, dh.y) * h.w - DVec2::new(h.x, h.y) * dh.w) / (h.w * h.w)
        };
        let s_min = math::smaller_singular_value(ndc(q.dx), ndc(q.dy));
        sum += q.weight * (q.fade / s_min).powi(POWER);
        weights += q.weight;
    }
    (sum / weights).powf(1.0 / f64::from(POWER))
}

proptest::proptest! {
    /// `points_error` (the Jacobian's `1 / s²` from the numerators of the
    /// quotient rule times `w⁴`, the terms summed four at a time, on the points'
    /// light-frame `x` and `y`) is the error of its definition on the world points
    /// to rounding, for perspective clips (a LiSPSM-like warp of any strength
    /// along any axis across the light) and affine ones, in a light frame of any
    /// direction.
    #[test]
    fn the_error_is_its_definition(
        seed in proptest::collection::vec(-1.0f64..1.0, 7 * 23),
        strength in 0.0f64..2.0,
        axis in proptest::sample::select(vec![DVec3::X, DVec3::Y, DVec3::new(0.6, 0.8, 0.0)]),
        n in 1usize..23,
        light in proptest::array::uniform3(-1.0f64..1.0),
        turn in 0.0f64..6.3,
    ) {
        // A light frame: `z` against the light, turned about it by `turn`.
        let z = DVec3::from(light).try_normalize().unwrap_or(DVec3::Z);
        let x = z.any_orthonormal_vector();
        let x = x * turn.cos() + z.cross(x) * turn.sin();
        let rot = DMat4::from_cols(
            x.extend(0.0),
            z.cross(x).extend(0.0),
            z.extend(0.0),
            glam::DVec4::W,
        )
        .transpose();
        // The points made in the light frame (their steps well apart across the
        // light, whatever its direction), then turned to the world.
        let world = |v: DVec3| rot.transpose().transform_vector3(v);
        let points: Vec<Point> = seed
            .chunks_exact(7)
            .take(n)
            .map(|c| Point {
                p: world(DVec3::new(c[0], c[1], c[2]) * 5.0),
                dx: world(DVec3::new(1e-3, c[3] * 1e-3, c[5] * 1e-3)),
                dy: world(DVec3::new(c[4] * 1e-3, 1e-3, c[5] * 1e-4)),
                weight: 0.5 + 0.5 * c[6].abs(),
                fade: 0.2 + 0.8 * c[6].abs(),
            })
            .collect();
        let mut probe = ProbePoints::new();
        for q in &points {
            probe.push(q, &rot);
        }
        // A depth along `axis` of 3.5 to 17.5 divides x and y:
        // `w = 1 + s (axis·p + 10.5)`, `|axis·p| <= 7`; x, y and w do not read
        // the light-frame z.
        let w_row = (axis * strength).extend(1.0 + 10.5 * strength);
        let clip = DMat4::from_cols_array_2d(&[
            [0.1, 0.02, 0.0, w_row.x],
            [-0.03, 0.12, 0.0, w_row.y],
            [0.0, 0.0, 0.05, 0.0],
            [0.2, -0.1, 0.5, w_row.w],
        ]);
        for clip_from_light in [clip, DMat4::from_scale(DVec3::new(0.1, 0.07, 0.05))] {
            let fast = points_error(&probe, &clip_from_light);
            let reference = error_by_definition(&points, &(clip_from_light * rot));
            proptest::prop_assert!(
                (fast - reference).abs() <= 1e-12 * reference,
                "{fast} vs {reference}"
            );
        }
    }
}

/// The ray weights' step saturates on a product test (no wait on the division):
/// it agrees bit for bit with the step of the quotient, also within a few units in
/// the last place of the bound, where the two tests can disagree.
#[test]
fn the_log_step_saturation_is_the_quotients() {
    const SATURATED: f64 = 1.051_271_096_377_2;
    let by_quotient = |num: f64, den: f64| smoothstep(0.0, 0.05, math::ln(num / den));
    for den in [1e-4, 0.37, 1.0, 3.3, 7.1e3, 2.5e6] {
        let near_bound = (-16..=16).map(|k| SATURATED * (1.0 + f64::from(k) * f64::EPSILON));
        let spread = (0..200).map(|k| 1.0 + f64::from(k) * 0.0005);
        for ratio in near_bound.chain(spread) {
            let num = ratio * den;
            assert_eq!(
                log_step(num, den).to_bits(),
                by_quotient(num, den).to_bits(),
                "{num} / {den}"
            );
        }
    }
}
