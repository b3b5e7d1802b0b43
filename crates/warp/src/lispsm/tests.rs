//! LiSPSM's strength, fade and fits, and the warps' shared fitting steps.

use glam::{DVec3, Vec3};
use shadowmap_frustum::{Aabb, Camera, Projection, ShadowMapping, ShadowTransform};

use super::*;
use crate::{UniformOptions, uniform_focused};

/// The overhead case: a camera 10 m up looking level along `-z` (fovY 60°,
/// n = 1, f = 1000) over receivers and casters that hold its whole frustum.
pub(crate) fn overhead_view() -> (Vec3, Camera, SceneBounds) {
    let eye = Vec3::new(0.0, 10.0, 0.0);
    let camera = Camera::look_to(
        eye,
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 1.0, 1.0, 1000.0),
    )
    .unwrap();
    let scene = SceneBounds::whole(Aabb::new(
        Vec3::new(-800.0, -800.0, -1100.0),
        Vec3::new(800.0, 800.0, 10.0),
    ));
    (eye, camera, scene)
}

/// Texel density (texture units per world unit) along the view axis and across
/// it, at view depth `z`, by central differences.
fn density(t: &ShadowTransform, eye: DVec3, z: f64) -> (f64, f64) {
    let p = eye + DVec3::new(0.0, 0.0, -z);
    let h = 1e-4 * z;
    let uv = |q: DVec3| t.map_point(q).unwrap().uv;
    let along =
        (uv(p + DVec3::new(0.0, 0.0, -h)) - uv(p - DVec3::new(0.0, 0.0, -h))).length() / (2.0 * h);
    let across = (uv(p + DVec3::X * h) - uv(p - DVec3::X * h)).length() / (2.0 * h);
    (along, across)
}

/// Storage factor of a fit for the overhead case (see `overhead_light_golden_ratios`).
fn storage_factor(
    camera: &Camera,
    light: Vec3,
    scene: &SceneBounds,
    eta: f32,
    n: f64,
    f: f64,
    tan: f64,
) -> f64 {
    let t = lispsm(
        camera,
        light,
        scene,
        &LispsmOptions::default().with_eta(eta),
    )
    .unwrap()
    .transform;
    let eye = camera.eye().as_dvec3();
    let (mut mx, mut my) = (0.0f64, 0.0f64);
    for i in 0..=400 {
        let z = n * (f / n).powf(f64::from(i) / 400.0);
        let (along, across) = density(&t, eye, z);
        mx = mx.max(1.0 / (2.0 * tan * z * across));
        my = my.max(1.0 / (2.0 * tan * z * along));
    }
    let v = |z: f64| t.map_point(eye + DVec3::new(0.0, 0.0, -z)).unwrap().uv.y;
    mx * my * (v(f) - v(n)).abs()
}

/// Overhead light, horizontal camera, n = 1, f = 1000, fovY = 60°: the near/far
/// density ratios are the closed forms of the 1-D analysis (Wimmer et al. 2004,
/// Lloyd et al. 2006): `r = 1 + s d` is 1 (uniform), `sqrt(f/n)` (LiSPSM) and
/// `f/n` (PSM); along the view the ratio is `r²`, across it `r`. The storage
/// factors are those of `docs/quality.md`: uniform `K (f - n) f / n²`, LiSPSM `K (f - n) / n`
/// (and PSM the same as LiSPSM in this separable 1-D measure).
#[test]
fn overhead_light_golden_ratios() {
    let (n, f) = (1.0f32, 1000.0f32);
    let eye = Vec3::new(0.0, 10.0, 0.0);
    let camera = Camera::look_to(
        eye,
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 1.0, n, f),
    )
    .unwrap();
    // Receivers and casters hold the whole frustum, so the body is the frustum.
    let scene = SceneBounds::whole(Aabb::new(
        Vec3::new(-800.0, -800.0, -1100.0),
        Vec3::new(800.0, 800.0, 10.0),
    ));
    let light = Vec3::NEG_Y;
    let ratio = |r: f64| (r * r, r);
    let fo = f64::from(f / n);
    let cases = [
        (-1.0, ratio(1.0)),
        (0.0, ratio(fo.sqrt())),
        (1.0, ratio(fo)),
    ];
    for (eta, (want_along, want_across)) in cases {
        let t = lispsm(
            &camera,
            light,
            &scene,
            &LispsmOptions::default().with_eta(eta),
        )
        .unwrap()
        .transform;
        let (a0, c0) = density(&t, eye.as_dvec3(), f64::from(n));
        let (a1, c1) = density(&t, eye.as_dvec3(), f64::from(f));
        let (along, across) = (a0 / a1, c0 / c1);
        eprintln!(
            "golden: eta {eta}: density ratio n/f along {along:.4} (closed form {want_along:.4}), across {across:.4} ({want_across:.4})"
        );
        assert!(
            (along / want_along - 1.0).abs() < 0.02,
            "eta {eta}: along {along} vs {want_along}"
        );
        assert!(
            (across / want_across - 1.0).abs() < 0.02,
            "eta {eta}: across {across} vs {want_across}"
        );
    }
    // The storage factors of `docs/quality.md` from the measured densities (perspective-only,
    // separable): S = max_z m_x(z) * max_z m_y(z) * (texels across the map) with
    // m = (pixel density 1/(2 t z)) / (texel density), t = tan(fovY / 2).
    let tan = (30f64).to_radians().tan();
    let k = 1.0 / (2.0 * tan);
    let (nf, ff) = (f64::from(n), f64::from(f));
    for (eta, want) in [
        (-1.0, k * (ff - nf) * ff / (nf * nf)),
        (0.0, k * (ff - nf) / nf),
        (1.0, k * (ff - nf) / nf),
    ] {
        let s = storage_factor(&camera, light, &scene, eta, nf, ff, tan);
        eprintln!("golden: eta {eta}: storage factor S = {s:.4e} (closed form {want:.4e})");
        assert!(
            (s / want - 1.0).abs() < 0.02,
            "eta {eta}: S = {s} vs {want}"
        );
    }
    // n_opt = n + sqrt(n f).
    let l = lispsm(&camera, light, &scene, &LispsmOptions::default()).unwrap();
    let n_opt = 1.0 + 1000f32.sqrt();
    assert!((l.n / n_opt - 1.0).abs() < 1e-3, "n = {} vs {n_opt}", l.n);
    // The uniform fit is the eta = -1 fit.
    let u = uniform_focused(&camera, light, &scene, &UniformOptions::default()).unwrap();
    let (a0, _) = density(&u, eye.as_dvec3(), 1.0);
    let (a1, _) = density(&u, eye.as_dvec3(), 1000.0);
    assert!((a0 / a1 - 1.0).abs() < 1e-3);
}

/// `strength_scale` raises the chosen warp ratio to its power: over the overhead
/// case (warp ratio `sqrt(f / n)` across the view, its square along it), half
/// the scale gives the ratio's square root and none the uniform fit, for
/// LiSPSM, TSM and XPSM alike; a scale outside `[0, 1]` is refused.
#[test]
fn strength_scale_raises_the_warp_ratio_to_its_power() {
    use crate::{TsmOptions, XpsmOptions, tsm, xpsm};
    let (eye, camera, scene) = overhead_view();
    let light = Vec3::NEG_Y;
    // The warp ratio across the view between view depths 1 and 1000.
    let across = |t: &ShadowTransform| {
        let (near, far) = (
            density(t, eye.as_dvec3(), 1.0),
            density(t, eye.as_dvec3(), 1000.0),
        );
        near.1 / far.1
    };
    let fits = |scale: f32| {
        [
            lispsm(
                &camera,
                light,
                &scene,
                &LispsmOptions::default().with_strength_scale(scale),
            )
            .map(|s| s.transform),
            tsm(
                &camera,
                light,
                &scene,
                &TsmOptions::default().with_strength_scale(scale),
            )
            .map(|s| s.transform),
            xpsm(
                &camera,
                light,
                &scene,
                &XpsmOptions::default().with_strength_scale(scale),
            )
            .map(|s| s.transform),
        ]
    };
    for ((full, half), none) in fits(1.0).iter().zip(fits(0.5)).zip(fits(0.0)) {
        let (full, half, none) = (
            across(full.as_ref().unwrap()),
            across(&half.unwrap()),
            across(&none.unwrap()),
        );
        assert!(full > 5.0, "{full}");
        assert!((half / full.sqrt() - 1.0).abs() < 0.02, "{half} vs {full}");
        assert!((none - 1.0).abs() < 1e-3, "{none}");
    }
    for scale in [-0.1, 1.5, f32::NAN] {
        assert!(
            fits(scale)
                .iter()
                .all(|f| matches!(f, Err(WarpError::InvalidOption)))
        );
    }
    // The default is the full chosen strength.
    assert_eq!(
        fits(1.0)[0],
        lispsm(&camera, light, &scene, &LispsmOptions::default()).map(|s| s.transform)
    );
}

/// The prediction's own fit at the chosen strength, which the warp keeps
/// instead of fitting again, is the fit `warp_clip` makes at that strength (in
/// either depth convention: the prediction reads only clip `x`, `y` and `w`).
#[test]
fn the_predictions_fit_is_the_fit_at_the_chosen_strength() {
    let (_, camera, scene) = overhead_view();
    let mut kept = 0;
    for light in [
        Vec3::new(0.3, -1.0, 0.6),
        Vec3::new(0.0, -0.3, -1.0),
        Vec3::new(1.0, -0.2, 0.1),
    ] {
        let body = FocusBody::new(&camera, light, &scene).unwrap();
        for reversed_z in [false, true] {
            let o = LispsmOptions::default().with_reversed_z(reversed_z);
            let (s, _) = warp_strength(&body.focus, &o);
            let mut fits = Fits::new();
            let chosen = chosen_strength(&body, s, 1.0, reversed_z, &mut fits);
            let Some(fitted) = chosen.kept.and_then(|t| fits.at(t)) else {
                continue;
            };
            let fresh = warp_clip(&body.focus, &body.view, chosen.s, reversed_z).unwrap();
            assert_eq!(*fitted, fresh, "{light} {reversed_z}");
            kept += 1;
        }
    }
    assert!(kept >= 2, "{kept}");
}

/// At scale 0 every strength scales to the uniform fit's, exactly: what lets
/// `chosen_strength` skip the prediction there.
#[test]
fn scale_zero_is_the_uniform_strength_whatever_the_prediction() {
    let (_, camera, scene) = overhead_view();
    for light in [
        Vec3::NEG_Y,
        Vec3::new(0.3, -1.0, 0.6),
        Vec3::new(1.0, -0.05, 0.0),
    ] {
        let body = FocusBody::new(&camera, light, &scene).unwrap();
        for s in [0.0, 1e-9, 0.01, 3.0, 1e12, f64::MAX] {
            assert_eq!(scaled_strength(&body.focus, s, 0.0), 0.0, "{s}");
        }
        let o = LispsmOptions::default();
        let (s, _) = warp_strength(&body.focus, &o);
        assert_eq!(
            chosen_strength(&body, s, 0.0, false, &mut Fits::new()).s,
            0.0
        );
    }
}

#[test]
fn options_out_of_range_are_refused() {
    let camera = Camera::look_to(
        Vec3::ZERO,
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(1.0, 1.0, 0.1, 10.0),
    )
    .unwrap();
    let scene = SceneBounds::whole(Aabb::new(Vec3::splat(-20.0), Vec3::splat(20.0)));
    for o in [
        LispsmOptions::default().with_eta(1.5),
        LispsmOptions::default().with_eta(f32::NAN),
        LispsmOptions::default().with_fade(3.0, 10.0),
        LispsmOptions::default().with_hints(-1.0, 10.0),
        LispsmOptions::default().with_hints(5.0, 2.0),
        LispsmOptions::default().with_hints(0.0, f32::NAN),
    ] {
        assert_eq!(
            lispsm(&camera, Vec3::NEG_Y, &scene, &o).err(),
            Some(WarpError::InvalidOption)
        );
    }
    assert_eq!(
        lispsm(&camera, Vec3::ZERO, &scene, &LispsmOptions::default()).err(),
        Some(WarpError::ZeroDirection)
    );
    assert_eq!(
        lispsm(
            &camera,
            Vec3::new(f32::NAN, 0.0, 0.0),
            &scene,
            &LispsmOptions::default()
        )
        .err(),
        Some(WarpError::NonFinite)
    );
    let inverted = SceneBounds::new(Aabb::new(Vec3::ONE, Vec3::ZERO), scene.casters);
    assert_eq!(
        uniform_focused(&camera, Vec3::NEG_Y, &inverted, &UniformOptions::default()).err(),
        Some(WarpError::EmptyReceivers)
    );
    let inverted = SceneBounds::new(scene.receivers, Aabb::new(Vec3::ONE, Vec3::ZERO));
    assert_eq!(
        uniform_focused(&camera, Vec3::NEG_Y, &inverted, &UniformOptions::default()).err(),
        Some(WarpError::EmptyCasters)
    );
    let away = SceneBounds::whole(Aabb::new(Vec3::splat(100.0), Vec3::splat(101.0)));
    assert_eq!(
        uniform_focused(&camera, Vec3::NEG_Y, &away, &UniformOptions::default()).err(),
        Some(WarpError::NoVisibleReceivers)
    );
    // Near/far hints narrow n_opt's depth range: a far hint strengthens the warp.
    let base = lispsm(&camera, Vec3::NEG_Y, &scene, &LispsmOptions::default()).unwrap();
    let hinted = lispsm(
        &camera,
        Vec3::NEG_Y,
        &scene,
        &LispsmOptions::default().with_hints(0.0, 2.0),
    )
    .unwrap();
    assert!(hinted.n < base.n);
}
