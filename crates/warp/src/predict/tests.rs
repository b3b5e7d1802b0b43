//! The probe's strength choice and screen steps.

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
            probe.points.push(&Point {
                weight: lit,
                dx: DVec3::new(1.0, 0.0, 0.0),
                dy: DVec3::new(0.0, 1e-3, 0.0),
                ..q
            });
        }
        probe.geometric += 1.0;
    }
    (probe, perspective)
}

/// [`Probe::strength`] of `probe` with its perspective set.
fn strength(
    (probe, perspective): &(Probe, Vec<Point>),
    clip: impl FnMut(f64) -> Option<DMat4>,
) -> f64 {
    let perspective = |out: &mut ProbePoints| {
        for q in perspective {
            out.push(q);
        }
    };
    probe.strength_with(clip, |c| c, perspective).0
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
