//! Property tests of every builder, driven by the generators of
//! `shadowmap_testgen::warp` (shared with the fuzz targets).

use arbitrary::Unstructured;
use glam::{DVec3, Vec3};
use proptest::prelude::*;
use shadowmap_frustum::{CascadeSplits, ConvexBody, ShadowMapping, ShadowTransform, SplitScheme};
use shadowmap_testgen::arbitrary;
use shadowmap_testgen::strategy;
use shadowmap_testgen::warp::{
    WarpCase, check_cascades, check_lispsm, check_transform, check_tsm, check_uniform, check_xpsm,
    f32_rounding, receiver_samples, warp_case, warp_case_raw,
};
use shadowmap_warp::{
    LispsmOptions, UniformOptions, WarpError, XpsmOptions, light_frame, lispsm, uniform_focused,
    warped_cascades, xpsm,
};

/// Every visible receiver lands in `[0, 1]²` with depth in `[0, 1]`; every caster
/// point above a visible receiver (toward the light, inside the caster box) lies in
/// the depth range, nearer the light than the receiver. Up to `f32` rounding
/// ([`f32_rounding`]).
fn assert_covers(case: &WarpCase, t: &ShadowTransform, bytes: &[u8]) -> Result<(), TestCaseError> {
    let mut u = Unstructured::new(bytes);
    let Some(samples) = receiver_samples(case, &mut u) else {
        return Ok(());
    };
    assert_covers_samples(case, t, &samples)
}

/// [`assert_covers`] for given receiver points.
fn assert_covers_samples(
    case: &WarpCase,
    t: &ShadowTransform,
    samples: &[Vec3],
) -> Result<(), TestCaseError> {
    let to_light = -case.light.normalize().as_dvec3();
    let cb = case.scene.casters;
    for &p in samples {
        let s = t.map_point(p.as_dvec3());
        prop_assert!(s.is_some(), "receiver {p} not mapped");
        let s = s.unwrap();
        let tol = f32_rounding(t, p.as_dvec3());
        let inside = |x: f64| (-tol..=1.0 + tol).contains(&x);
        prop_assert!(
            inside(s.uv.x) && inside(s.uv.y),
            "receiver {p} at uv {:?} (tol {tol})",
            s.uv
        );
        prop_assert!(
            inside(s.depth),
            "receiver {p} at depth {} (tol {tol})",
            s.depth
        );
        // Where the ray toward the light leaves the caster box.
        let (lo, hi) = (cb.min.as_dvec3(), cb.max.as_dvec3());
        let p = p.as_dvec3();
        if !(p.cmpge(lo).all() && p.cmple(hi).all()) {
            continue;
        }
        let mut exit = f64::INFINITY;
        for a in 0..3 {
            let d = to_light[a];
            if d > 1e-12 {
                exit = exit.min((hi[a] - p[a]) / d);
            } else if d < -1e-12 {
                exit = exit.min((lo[a] - p[a]) / d);
            }
        }
        if !exit.is_finite() {
            continue;
        }
        for k in 1..=4 {
            let c = p + to_light * (exit * f64::from(k) / 4.0);
            let sc = t.map_point(c);
            prop_assert!(sc.is_some(), "caster {c} not mapped");
            let sc = sc.unwrap();
            let tol = tol + f32_rounding(t, c);
            let inside = |x: f64| (-tol..=1.0 + tol).contains(&x);
            prop_assert!(
                inside(sc.depth),
                "caster {c} above receiver at depth {} (tol {tol})",
                sc.depth
            );
            // Closer to the light than the receiver.
            if t.reversed_z {
                prop_assert!(sc.depth >= s.depth - tol);
            } else {
                prop_assert!(sc.depth <= s.depth + tol);
            }
        }
    }
    Ok(())
}

/// Whether the receivers meet the view frustum (the generator aims at it, rounding
/// sometimes misses a point-like box).
fn visible(case: &WarpCase) -> bool {
    receiver_samples(case, &mut Unstructured::new(&[])).is_some()
}

fn bytes() -> impl Strategy<Value = Vec<u8>> {
    proptest::collection::vec(any::<u8>(), 64..256)
}

/// Largest singular value of `d uv / d world` at `p` (texture units per world unit).
fn stretch(t: &ShadowTransform, p: DVec3) -> f64 {
    let m = t.uv_from_world.as_dmat4();
    let h = m * p.extend(1.0);
    let row = |r: usize| DVec3::new(m.x_axis[r], m.y_axis[r], m.z_axis[r]);
    let du = (row(0) * h.w - row(3) * h.x) / (h.w * h.w);
    let dv = (row(1) * h.w - row(3) * h.y) / (h.w * h.w);
    let (a, b, c) = (du.dot(du), du.dot(dv), dv.dot(dv));
    (0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt()).sqrt()
}

/// Angle (radians) between the warp axes of the light frames of two lights.
fn frame_turn(case: &WarpCase, l2: Vec3) -> f64 {
    let (Ok(a), Ok(b)) = (
        light_frame(&case.camera, case.light),
        light_frame(&case.camera, l2),
    ) else {
        return 0.0;
    };
    let ya = Vec3::new(a.x_axis.y, a.y_axis.y, a.z_axis.y).as_dvec3();
    let yb = Vec3::new(b.x_axis.y, b.y_axis.y, b.z_axis.y).as_dvec3();
    ya.angle_between(yb)
}

/// Degrees between a light and the viewing direction (or its opposite).
fn view_light_angle(case: &WarpCase, l: Vec3) -> f64 {
    let c = case
        .camera
        .forward()
        .as_dvec3()
        .dot(l.normalize().as_dvec3())
        .abs()
        .min(1.0);
    c.acos().to_degrees()
}

/// Shadow-map resolution for motion measurements.
const RES: f64 = 2048.0;

/// Turning the light by `δ = 0.1°` moves a visible point by at most
/// `C (δ + θ) D s` of the map: the fit turns with the light and its frame (by `θ`
/// about the light), every point of receivers and casters (diameter `D`) moves by at most
/// that times the map's largest stretch `s` over the region (largest singular value
/// of the uv Jacobian). `C = 16` leaves room for the refit of the bounds and the warp strength.
/// The frame itself turns by at most 20 δ, except close to its two singular
/// directions, 1 degree from the view: within 3.5 degrees of the view it may turn faster.
fn check_motion(
    case: &WarpCase,
    build: &dyn Fn(&WarpCase) -> Result<ShadowTransform, WarpError>,
    axis_pick: f32,
    bytes: &[u8],
) -> Result<(), TestCaseError> {
    let Ok(a) = build(case) else { return Ok(()) };
    let l = case.light.normalize();
    let (p, q) = l.any_orthonormal_pair();
    let axis = p * axis_pick.cos() + q * axis_pick.sin();
    let delta = 0.1f64.to_radians();
    let l2 = (l.as_dvec3() * delta.cos() + axis.as_dvec3() * delta.sin())
        .normalize()
        .as_vec3();
    let b = match build(&WarpCase { light: l2, ..*case }) {
        Ok(b) => b,
        // XPSM: the caster and receiver boxes may stop overlapping in light space.
        Err(WarpError::EmptyFocusRegion) => return Ok(()),
        Err(e) => return Err(TestCaseError::fail(format!("turned light failed: {e}"))),
    };
    let theta = frame_turn(case, l2);
    let ang = view_light_angle(case, case.light).min(view_light_angle(case, l2));
    prop_assert!(
        theta <= 20.0 * delta || ang <= 3.5,
        "frame turned {theta} rad at {ang} deg"
    );
    let mut u = Unstructured::new(bytes);
    let Some(samples) = receiver_samples(case, &mut u) else {
        return Ok(());
    };
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for s in &samples {
        lo = lo.min(s.as_dvec3());
        hi = hi.max(s.as_dvec3());
    }
    // The fit depends on the receivers and (depth, XPSM's focus region) the casters.
    for c in case.scene.casters.corners() {
        lo = lo.min(c.as_dvec3());
        hi = hi.max(c.as_dvec3());
    }
    let diam = (hi - lo).length();
    // The fit's change (bounds, warp strength) moves every point by at most the
    // largest stretch of the map over the region times the region's motion.
    let max_stretch = samples
        .iter()
        .map(|s| stretch(&a, s.as_dvec3()).max(stretch(&b, s.as_dvec3())))
        .fold(0.0, f64::max);
    for s in &samples {
        let p = s.as_dvec3();
        let (Some(x), Some(y)) = (a.map_point(p), b.map_point(p)) else {
            continue;
        };
        // Only points the map serves (XPSM leaves receivers outside the casters'
        // footprint out of the map: they are lit, wherever they land).
        let in_map = |uv: glam::DVec2| {
            uv.cmpge(glam::DVec2::splat(-0.01)).all() && uv.cmple(glam::DVec2::splat(1.01)).all()
        };
        if !(in_map(x.uv) && in_map(y.uv)) {
            continue;
        }
        let moved = (x.uv - y.uv).abs().max_element();
        let bound = 16.0 * (delta + theta) * diam * max_stretch
            + 4.0 * (f32_rounding(&a, p) + f32_rounding(&b, p))
            + 8.0 / RES;
        prop_assert!(
            moved <= bound,
            "moved {} texels, bound {} (frame turn {theta}, {ang} deg)",
            moved * RES,
            bound * RES
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    #[test]
    fn uniform_covers_receivers_and_casters(case in strategy(warp_case), b in bytes()) {
        let t = check_uniform(&case);
        if visible(&case) {
            prop_assert!(t.is_ok(), "{:?}", t);
            assert_covers(&case, &t.unwrap(), &b)?;
        } else {
            prop_assert_eq!(t.err(), Some(WarpError::NoVisibleReceivers));
        }
    }

    #[test]
    fn lispsm_covers_receivers_and_casters(case in strategy(warp_case), b in bytes()) {
        let t = check_lispsm(&case);
        if visible(&case) {
            prop_assert!(t.is_ok(), "{:?}", t);
            assert_covers(&case, &t.unwrap(), &b)?;
        } else {
            prop_assert_eq!(t.err(), Some(WarpError::NoVisibleReceivers));
        }
    }

    #[test]
    fn xpsm_covers_receivers_and_casters(case in strategy(warp_case), b in bytes()) {
        let t = check_xpsm(&case);
        let (r, c) = (case.scene.receivers, case.scene.casters);
        if !(c.min.cmple(r.min).all() && r.max.cmple(c.max).all()) {
            // Receivers outside the casters' footprint are not covered (documented):
            // only the contract holds.
            prop_assert!(t.is_ok() || matches!(t, Err(WarpError::EmptyFocusRegion | WarpError::NoVisibleReceivers)), "{:?}", t);
            return Ok(());
        }
        if visible(&case) {
            prop_assert!(t.is_ok(), "{:?}", t);
            assert_covers(&case, &t.unwrap(), &b)?;
        } else {
            prop_assert_eq!(t.err(), Some(WarpError::NoVisibleReceivers));
        }
    }

    #[test]
    fn tsm_covers_receivers_and_casters(case in strategy(warp_case), b in bytes()) {
        let t = check_tsm(&case);
        if visible(&case) {
            prop_assert!(t.is_ok(), "{:?}", t);
            assert_covers(&case, &t.unwrap(), &b)?;
        } else {
            prop_assert_eq!(t.err(), Some(WarpError::NoVisibleReceivers));
        }
    }

    #[test]
    fn raw_inputs_give_valid_output_or_typed_error(case in strategy(warp_case_raw)) {
        let _ = check_uniform(&case);
        let _ = check_tsm(&case);
        let _ = check_lispsm(&case);
        let _ = check_xpsm(&case);
        let _ = check_cascades(&case);
    }

    #[test]
    fn cascades_cover_their_slices(case in strategy(warp_case), b in bytes()) {
        // Every cascade that has a fit maps its own slice's visible receivers inside,
        // with the casters above them in its depth range.
        let (near, far) = case.camera.depth_range().unwrap();
        let splits = CascadeSplits::new(&SplitScheme::Practical { lambda: 0.7 }, 3, near, far)
            .unwrap()
            .with_overlap(0.1)
            .unwrap();
        let etas = [case.eta, 0.5 * case.eta, 0.0];
        let r = warped_cascades(&case.camera, case.light, &case.scene, &splits, &etas, &LispsmOptions::default());
        if !visible(&case) {
            prop_assert!(r.is_err());
            return Ok(());
        }
        let Ok(set) = r else {
            // Rounding can put a point-like receiver box in no slice.
            prop_assert!(matches!(r, Err(WarpError::NoVisibleReceivers)), "{:?}", r);
            return Ok(());
        };
        prop_assert_eq!(set.cascades.len(), 3);
        let mut u = Unstructured::new(&b);
        for c in &set.cascades {
            let Ok(slice) = case.camera.slice(c.near, c.far) else { continue };
            let body = ConvexBody::from_frustum_aabb(&slice, &case.scene.receivers).unwrap();
            let Some(s) = c.shadow else {
                prop_assert!(body.vertices().len() <= 1, "slice with receivers but no fit");
                continue;
            };
            check_transform(&s.transform);
            // The slice's visible receivers (vertices and points between them) and
            // the casters above them.
            let v = body.vertices();
            let mut samples = v.to_vec();
            for a in v {
                let w = f32::from(u.int_in_range(0u8..=255).unwrap_or(0)) / 255.0;
                samples.push(a.lerp(v[(v.len() / 2).min(v.len() - 1)], w));
            }
            assert_covers_samples(&case, &s.transform, &samples)?;
        }
    }

    #[test]
    fn eta_minus_one_is_uniform(case in strategy(warp_case), b in bytes()) {
        let u = uniform_focused(&case.camera, case.light, &case.scene, &UniformOptions::default());
        let l = lispsm(&case.camera, case.light, &case.scene, &LispsmOptions::default().with_eta(-1.0));
        if !visible(&case) {
            return Ok(());
        }
        let (Ok(u), Ok(l)) = (u, l) else { return Err(TestCaseError::fail("builder failed")) };
        prop_assert!(l.n.is_infinite());
        let mut un = Unstructured::new(&b);
        for p in receiver_samples(&case, &mut un).unwrap_or_default() {
            let tol = 4.0 * f32_rounding(&u, p.as_dvec3());
            let (a, c) = (u.map_point(p.as_dvec3()).unwrap(), l.transform.map_point(p.as_dvec3()).unwrap());
            prop_assert!((a.uv - c.uv).abs().max_element() < tol, "{:?} vs {:?}", a.uv, c.uv);
            prop_assert!((a.depth - c.depth).abs() < tol);
            // Same texel footprint.
            let (su, sl) = (u.texel_world_size(p, 1024), l.transform.texel_world_size(p, 1024));
            if let (Some(su), Some(sl)) = (su, sl) {
                prop_assert!((su - sl).abs() <= 1e-3 * su.max(sl) + 1e-30);
            }
        }
    }

    #[test]
    fn turning_the_light_moves_uniform_texels_little(case in strategy(warp_case), b in bytes(), pick in 0f32..core::f32::consts::TAU) {
        check_motion(&case, &|c| check_uniform(c), pick, &b)?;
    }

    #[test]
    fn turning_the_light_moves_lispsm_texels_little(case in strategy(warp_case), b in bytes(), pick in 0f32..core::f32::consts::TAU) {
        check_motion(&case, &|c| check_lispsm(c), pick, &b)?;
    }

    #[test]
    fn turning_the_light_moves_tsm_texels_little(case in strategy(warp_case), b in bytes(), pick in 0f32..core::f32::consts::TAU) {
        check_motion(&case, &|c| check_tsm(c), pick, &b)?;
    }

    #[test]
    fn turning_the_light_moves_xpsm_texels_little(case in strategy(warp_case), b in bytes(), pick in 0f32..core::f32::consts::TAU) {
        check_motion(&case, &|c| check_xpsm(c), pick, &b)?;
    }
}

#[test]
fn xpsm_z_bias_matches_the_paper() {
    // Step 18: biasing a point by b toward the light changes clip z by -b/(MaxZ-MinZ).
    let camera = shadowmap_frustum::Camera::look_to(
        Vec3::new(0.0, 5.0, 0.0),
        Vec3::new(0.0, -0.3, -1.0),
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.5, 0.5, 200.0),
    )
    .unwrap();
    let scene = shadowmap_warp::SceneBounds::whole(shadowmap_frustum::Aabb::new(
        Vec3::new(-300.0, 0.0, -300.0),
        Vec3::new(300.0, 30.0, 50.0),
    ));
    for reversed in [false, true] {
        let x = xpsm(
            &camera,
            Vec3::new(0.4, -1.0, 0.3),
            &scene,
            &XpsmOptions::default().with_reversed_z(reversed),
        )
        .unwrap();
        assert!(x.length_p > 0.0, "warp expected: {x:?}");
        let m = x.transform.uv_from_world.as_dmat4();
        let to_light = -Vec3::new(0.4, -1.0, 0.3).normalize();
        for p in [
            Vec3::new(1.0, 0.0, -10.0),
            Vec3::new(-20.0, 3.0, -80.0),
            Vec3::new(5.0, 1.0, -3.0),
        ] {
            for bias in [0.01f32, 0.5, 2.0] {
                let h = m * p.as_dvec3().extend(1.0);
                let expected = f64::from(x.biased_clip_z(h.z as f32, bias)) / h.w;
                let moved = x
                    .transform
                    .map_point((p + to_light * bias).as_dvec3())
                    .unwrap();
                assert!(
                    (moved.depth - expected).abs() < 1e-5,
                    "bias {bias} at {p}: {} vs {expected}",
                    moved.depth
                );
                // And it moved the right way.
                let before = x.transform.map_point(p.as_dvec3()).unwrap().depth;
                assert!(if reversed {
                    moved.depth > before
                } else {
                    moved.depth < before
                });
            }
        }
    }
}

/// Largest uv step of a fixed point while the light sweeps from `from` to `to` degrees
/// (off the view direction, sideways) in steps of `step` degrees.
fn sweep(technique: usize, from: f32, to: f32, step: f32) -> f64 {
    let camera = shadowmap_frustum::Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.5, -1.0),
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap();
    let scene = shadowmap_warp::SceneBounds::whole(shadowmap_frustum::Aabb::new(
        Vec3::new(-200.0, -1.0, -200.0),
        Vec3::new(200.0, 5.0, 20.0),
    ));
    let fwd = camera.forward();
    let side = Vec3::X;
    let p = DVec3::new(1.0, 0.0, -8.0);
    let mut prev: Option<glam::DVec2> = None;
    let mut worst = 0.0f64;
    let n = ((to - from) / step).round() as i32;
    for i in 0..=n {
        let a = (from + i as f32 * step).to_radians();
        let l = (fwd * a.cos() + side * a.sin()).normalize();
        let t = match technique {
            0 => {
                lispsm(&camera, l, &scene, &LispsmOptions::default())
                    .unwrap()
                    .transform
            }
            3 => {
                shadowmap_warp::tsm(&camera, l, &scene, &shadowmap_warp::TsmOptions::default())
                    .unwrap()
                    .transform
            }
            1 => {
                xpsm(&camera, l, &scene, &XpsmOptions::default())
                    .unwrap()
                    .transform
            }
            _ => uniform_focused(&camera, l, &scene, &UniformOptions::default()).unwrap(),
        };
        let cur = t.map_point(p).unwrap().uv;
        if let Some(pr) = prev {
            worst = worst.max((cur - pr).abs().max_element());
        }
        prev = Some(cur);
    }
    worst
}

#[test]
fn fade_has_no_pop_near_parallel() {
    // Through the view direction and the whole fade band: a pop would keep its size
    // as the step shrinks; continuous motion shrinks with the step.
    // XPSM's focus region can follow points close to w = epsilonW, where it moves
    // fast (but continuously): it is resolved with finer steps.
    for (technique, step) in [(0, 0.01), (1, 0.0005), (2, 0.01), (3, 0.01)] {
        let coarse = sweep(technique, -10.0, 10.0, step);
        let fine = sweep(technique, -10.0, 10.0, step / 4.0);
        assert!(
            fine < 0.4 * coarse && coarse * RES < 64.0,
            "technique {technique}: step {step} deg moves {} texels, a quarter of it {}",
            coarse * RES,
            fine * RES
        );
    }
}

#[test]
fn lispsm_is_uniform_below_the_fade() {
    let camera = shadowmap_frustum::Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.5, -1.0),
        Vec3::Y,
        shadowmap_frustum::Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap();
    let scene = shadowmap_warp::SceneBounds::whole(shadowmap_frustum::Aabb::new(
        Vec3::new(-200.0, -1.0, -200.0),
        Vec3::new(200.0, 5.0, 20.0),
    ));
    let a = 2.5f32.to_radians();
    let l = (camera.forward() * a.cos() + Vec3::X * a.sin()).normalize();
    let w = lispsm(&camera, l, &scene, &LispsmOptions::default()).unwrap();
    let u = uniform_focused(&camera, l, &scene, &UniformOptions::default()).unwrap();
    assert!(w.n.is_infinite() && w.fade == 0.0);
    let p = DVec3::new(1.0, 0.0, -8.0);
    assert!(
        (w.transform.map_point(p).unwrap().uv - u.map_point(p).unwrap().uv)
            .abs()
            .max_element()
            < 1e-5
    );
    // And warps at 30 degrees.
    let a = 30f32.to_radians();
    let l = (camera.forward() * a.cos() + Vec3::X * a.sin()).normalize();
    let w = lispsm(&camera, l, &scene, &LispsmOptions::default()).unwrap();
    assert!(w.n.is_finite() && w.fade == 1.0);
}
