//! Property tests of the paraboloid map, the cone fits and the IPSM plan, driven by the
//! shared generators of `shadowmap_testgen::paraboloid`.

use core::f64::consts::FRAC_PI_2;

use glam::{DVec2, Vec3};
use proptest::prelude::*;
use shadowmap_frustum::ShadowMapping;
use shadowmap_paraboloid::{
    ConeFit, DualReason, IpsmPlan, ParaboloidMode, Side, fit_minimal_cone, fit_paper_cone,
};
use shadowmap_testgen::paraboloid::{
    PlanInput, brute_force_min_cone, build_map, cone_directions, map_input, plan_input,
};
use shadowmap_testgen::strategy;

/// The truncated frustum's border points and the light position of a plan input, or
/// `None` when the input is rejected by the plan (or the light sits on a point).
fn border_directions(input: &PlanInput) -> Option<(IpsmPlan, Vec<Vec3>)> {
    let plan = IpsmPlan::new(&input.light, &input.camera, input.bounds, &input.options).ok()?;
    if plan.dual_reason == Some(DualReason::LightOnFrustumPoint) {
        return None;
    }
    let dirs: Vec<Vec3> = plan
        .border_points
        .iter()
        .map(|p| *p - plan.map.position)
        .collect();
    Some((plan, dirs))
}

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// Every frustum border point lies inside the fitted cone, for both fits, both as
    /// fitted by the plan and by the stand-alone functions.
    #[test]
    fn border_points_inside_both_cones(input in strategy(plan_input)) {
        let Some((plan, dirs)) = border_directions(&input) else { return Ok(()) };
        // `p - light` in f32 rounds by about 1.2e-7 (|p| + |light|): that much angle.
        let light = plan.map.position;
        let tol = |d: Vec3| 1.2e-7 * (d.length() + 2.0 * light.length()) / d.length();
        if let Some(cone) = plan.cone {
            for &d in &dirs {
                prop_assert!(cone.contains(d, tol(d)), "{d} outside plan cone {cone:?}");
            }
        }
        for cone in [fit_minimal_cone(&dirs), fit_paper_cone(&dirs)].into_iter().flatten() {
            for &d in &dirs {
                prop_assert!(cone.contains(d, 0.0), "{d} outside {cone:?}");
            }
        }
    }

    /// The minimal half-angle never exceeds the paper's, on frustum directions and on
    /// arbitrary direction sets.
    #[test]
    fn minimal_never_wider_than_paper(dirs in strategy(cone_directions), input in strategy(plan_input)) {
        let frustum_dirs = border_directions(&input).map(|(_, d)| d).unwrap_or_default();
        for set in [dirs, frustum_dirs] {
            if set.is_empty() { continue; }
            let (Ok(e), Ok(p)) = (fit_minimal_cone(&set), fit_paper_cone(&set)) else { continue };
            prop_assert!(e.half_angle <= p.half_angle + 1e-6, "{e:?} vs {p:?}");
        }
    }

    /// The exact fit equals brute-force enumeration of support sets within 1e-6 rad,
    /// including agreeing on whether a cone under 90 degrees exists.
    #[test]
    fn exact_fit_equals_brute_force(dirs in strategy(cone_directions), input in strategy(plan_input)) {
        let frustum_dirs = border_directions(&input).map(|(_, d)| d).unwrap_or_default();
        for set in [dirs, frustum_dirs] {
            if set.is_empty() { continue; }
            let exact = fit_minimal_cone(&set);
            match (exact, brute_force_min_cone(&set)) {
                (Ok(e), Some((_, h))) => {
                    prop_assert!((f64::from(e.half_angle) - h).abs() < 1e-6, "{e:?} vs brute {h}");
                }
                (Err(_), None) => {}
                // Within rounding of 90 degrees either answer is right.
                // (The exact fit counts cones within 1e-6 rad of 90 degrees as none.)
                (Ok(e), None) => prop_assert!(f64::from(e.half_angle) > FRAC_PI_2 - 2e-6, "{e:?}"),
                (Err(err), Some((_, h))) => prop_assert!(h > FRAC_PI_2 - 2e-6, "{err} vs brute {h}"),
            }
        }
    }

    /// Map then unmap returns the point, on both sides, single and dual maps.
    #[test]
    fn map_then_unmap_returns_the_point(input in strategy(map_input)) {
        let map = build_map(&input).unwrap();
        for &p in &input.points {
            for side in [Side::Front, Side::Back] {
                let Some(s) = map.project(p, side) else { continue };
                let back = map.unproject(s.uv.as_vec2(), s.depth as f32, side).unwrap();
                let dist = p.distance(map.position);
                let tol = 1e-5 * (1.0 + p.length() + map.position.length()) + 1e-4 * dist + 1e-6 * map.far;
                // Near the pole the f32 uv cannot hold the direction: skip far outside the disc.
                if (s.uv - DVec2::splat(0.5)).length() * f64::from(map.zoom) > 50.0 { continue; }
                prop_assert!(back.distance(p) <= tol, "{p} -> {s:?} -> {back} ({side:?})");
            }
        }
    }

    /// Points of the front hemisphere land inside the unit disc of a dual map, on the
    /// front layer, and their back-hemisphere mirror images on the back layer.
    #[test]
    fn front_hemisphere_inside_unit_disc(input in strategy(map_input)) {
        let mut input = input;
        input.half_angle = None;
        let map = build_map(&input).unwrap();
        prop_assert_eq!(map.mode, ParaboloidMode::Dual);
        let axis = map.axis();
        for &p in &input.points {
            let d = p - map.position;
            let front = map.project(p, Side::Front);
            let r = front.map_or(f64::INFINITY, |s| (s.uv - DVec2::splat(0.5)).length());
            if d.dot(axis) >= 1e-4 * d.length() {
                prop_assert!(r <= 0.5 + 1e-6, "front point {p} at r = {r}");
                prop_assert_eq!(map.lookup(p).unwrap().layer, 0);
            } else if d.dot(axis) <= -1e-4 * d.length() {
                prop_assert!(r > 0.5 - 1e-6, "back point {p} inside the front disc, r = {r}");
                let l = map.lookup(p).unwrap();
                prop_assert_eq!(l.layer, 1);
                prop_assert!((l.uv - DVec2::splat(0.5)).length() <= 0.5 + 1e-6);
            }
        }
    }

    /// The exact plan's single/dual decision agrees with brute force: single only
    /// when the brute-force minimal cone plus margin is under the threshold, and a
    /// cone under it is dual only where the dual map is predicted finer.
    #[test]
    fn single_dual_decision_agrees_with_brute_force(input in strategy(plan_input)) {
        let mut input = input;
        input.options = input.options.with_fit(ConeFit::Exact);
        let Some((plan, dirs)) = border_directions(&input) else { return Ok(()) };
        let limit = f64::from(input.options.max_single_half_angle) - f64::from(input.options.margin);
        match brute_force_min_cone(&dirs) {
            // A tie within rounding (the exact fit counts cones within 1e-6 rad of 90
            // degrees as none).
            Some((_, h)) if (h - limit).abs() < 1e-6 || h > FRAC_PI_2 - 2e-6 => {}
            Some((_, h)) if h < limit => prop_assert!(
                plan.is_single() || plan.dual_reason == Some(DualReason::DualFiner),
                "brute {} limit {} reason {:?}", h, limit, plan.dual_reason
            ),
            Some((_, h)) => prop_assert!(!plan.is_single(), "brute {} limit {}", h, limit),
            None => prop_assert!(!plan.is_single()),
        }
        if plan.is_single() {
            for p in plan.border_points {
                let s = plan.map_point(p.as_dvec3());
                prop_assert!(s.is_some(), "{p} not covered");
            }
        }
    }
}
