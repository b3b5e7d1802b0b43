//! Every technique through the one `fit`: over the shared generators, every visible
//! receiver point lands inside the fitted map (uv in `[0, 1]²`, depth in `[0, 1]`, a
//! layer the shadow has), up to `f32` rounding; missing inputs are typed errors.

use glam::{DVec3, Vec3};
use proptest::prelude::*;
use shadowmap::frustum::{
    Aabb, Camera, ConvexBody, DepthBounds, Light, Projection, SceneBounds, ShadowMapping,
    ShadowTransform, TechniqueSelector,
};
use shadowmap::rtw::EyeSample;
use shadowmap::{
    CascadePlan, FitError, FitInput, FitState, Fitted, LightKind, Shadow, Technique,
    depth_bounds_of, fit, fit_with_selector, fit_with_state,
};
use shadowmap_testgen::arbitrary::Unstructured;
use shadowmap_testgen::paraboloid::plan_input;
use shadowmap_testgen::warp::{WarpCase, f32_rounding, receiver_samples, warp_case};
use shadowmap_testgen::{proptest_config, strategy};

const BUDGET: u64 = 512 * 512;

/// The matrix that maps `layer` of a matrix-based shadow (RTW: its base, whose warp
/// keeps `[0, 1]` and clamps to the edge outside).
fn layer_transform(shadow: &Shadow, layer: u32) -> Option<ShadowTransform> {
    if let Some(t) = shadow.transform() {
        return Some(*t);
    }
    if let Some(r) = shadow.rtw() {
        return Some(r.base);
    }
    match shadow.fitted() {
        Fitted::Cascades(set) => set.cascades.get(layer as usize).map(|c| c.transform),
        Fitted::WarpedCascades { cascades, .. } => cascades
            .cascades
            .get(layer as usize)
            .and_then(|c| c.shadow)
            .map(|s| s.transform),
        _ => None,
    }
}

/// The view-depth range a cascaded shadow covers (`None`: not cascaded).
fn cascaded_range(shadow: &Shadow) -> Option<(f32, f32)> {
    match shadow.fitted() {
        Fitted::Cascades(set) => Some((
            set.splits.cascade_range(0)?.0,
            set.splits.cascade_range(set.splits.count() - 1)?.1,
        )),
        Fitted::WarpedCascades { cascades, .. } => Some((
            cascades.cascades.first()?.near,
            cascades.cascades.last()?.far,
        )),
        _ => None,
    }
}

/// Checks that every point maps inside the shadow, with tolerance `tol(layer, p)`.
fn assert_inside(
    shadow: &Shadow,
    points: &[Vec3],
    camera: &Camera,
    tol: impl Fn(u32, DVec3) -> f64,
) -> Result<(), TestCaseError> {
    let name = shadow.technique().name();
    for p in points {
        let world = p.as_dvec3();
        let Some(s) = shadow.map_point(world) else {
            // Cascades select by view depth: a point at the first cascade's near or
            // the last one's far depth may round out of them.
            let d = camera.view_depth(*p);
            let at_end = cascaded_range(shadow).is_some_and(|(near, far)| {
                let edge = 1e-4 * far.abs().max(near.abs());
                (d - near).abs() < edge || (d - far).abs() < edge
            });
            prop_assert!(at_end, "{name}: receiver {p} at depth {d} not mapped");
            continue;
        };
        prop_assert!(s.layer < shadow.layers(), "{name}: layer {}", s.layer);
        let tol = tol(s.layer, world);
        let inside = |x: f64| (-tol..=1.0 + tol).contains(&x);
        prop_assert!(
            inside(s.uv.x) && inside(s.uv.y) && inside(s.depth),
            "{name}: receiver {p} at uv {:?} depth {} (tol {tol})",
            s.uv,
            s.depth
        );
    }
    Ok(())
}

fn eye_samples(camera: &Camera, points: &[Vec3]) -> Vec<EyeSample> {
    points
        .iter()
        .map(|p| EyeSample {
            position: *p,
            normal: Vec3::ZERO,
            eye_distance: p.distance(camera.eye()),
        })
        .collect()
}

fn of_kind(kind: LightKind) -> impl Iterator<Item = Technique> {
    Technique::all_default()
        .into_iter()
        .filter(move |t| t.light_kind() == kind)
}

/// Fits every directional technique to a case and checks coverage of the visible
/// receivers. Returns how many fits were checked.
fn check_directional(case: &WarpCase, points: &[Vec3]) -> Result<usize, TestCaseError> {
    let light = Light::Directional {
        direction: case.light,
    };
    let samples = eye_samples(&case.camera, points);
    let input = FitInput::new(&case.camera, &light, case.scene, BUDGET)
        .with_eye_samples(&samples)
        .with_pixels_per_radian(500.0);
    let (r, c) = (case.scene.receivers, case.scene.casters);
    let casters_hold_receivers = c.min.cmple(r.min).all() && r.max.cmple(c.max).all();
    let mut checked = 0;
    for technique in of_kind(LightKind::Directional) {
        let result = fit(&technique, &input);
        let shadow = match result {
            Ok(s) => s,
            // The plain matrix fits always succeed on visible receivers.
            Err(e) => {
                prop_assert!(
                    !matches!(
                        technique,
                        Technique::UniformFocused(_) | Technique::Lispsm(_) | Technique::Tsm(_)
                    ),
                    "{}: {e}",
                    technique.name()
                );
                continue;
            }
        };
        // XPSM covers the receivers inside the casters' footprint only (documented).
        let fitted_xpsm = matches!(shadow.fitted(), Fitted::Xpsm(_));
        if fitted_xpsm && !casters_hold_receivers {
            continue;
        }
        let tol = |layer, p| layer_transform(&shadow, layer).map_or(1e-4, |t| f32_rounding(&t, p));
        assert_inside(&shadow, points, &case.camera, tol)?;
        checked += 1;
    }
    Ok(checked)
}

proptest! {
    #![proptest_config(proptest_config())]

    #[test]
    fn directional_techniques_cover_visible_receivers(
        case in strategy(warp_case),
        bytes in proptest::collection::vec(any::<u8>(), 0..256),
    ) {
        let Some(points) = receiver_samples(&case, &mut Unstructured::new(&bytes)) else {
            return Ok(());
        };
        // Visible: within the camera's depth range too (the body's clipping rounds).
        let (near, far) = case.camera.depth_range().unwrap();
        let points: Vec<Vec3> = points
            .into_iter()
            .filter(|p| (near..=far).contains(&case.camera.view_depth(*p)))
            .collect();
        check_directional(&case, &points)?;
    }

    #[test]
    fn point_techniques_cover_the_truncated_frustum(input in strategy(plan_input)) {
        let (position, range) = match input.light {
            Light::Point { position, range } | Light::Spot { position, range, .. } => {
                (position, range)
            }
            Light::Directional { .. } => return Ok(()),
        };
        let light = Light::Point { position, range };
        let camera = &input.camera;
        let scene = SceneBounds::whole(Aabb::new(Vec3::splat(-1.0), Vec3::ONE));
        let fit_input = FitInput::new(camera, &light, scene, BUDGET).with_depth_bounds(input.bounds);
        let Ok((near, far)) = input.bounds.map_or(camera.depth_range(), |b| b.clamped_to(camera))
        else {
            return Ok(());
        };
        let Ok(slice) = camera.slice(near, far) else { return Ok(()) };
        for technique in of_kind(LightKind::Point) {
            let Ok(shadow) = fit(&technique, &fit_input) else { continue };
            // Cube maps cover the visible receivers, not the whole truncated frustum:
            // their own property tests check them.
            let Some(map) = shadow.paraboloid() else { continue };
            // The truncated frustum's corners and centre, where the light reaches them.
            let centre = slice.corners.iter().copied().sum::<Vec3>() / 8.0;
            let lit: Vec<Vec3> = slice
                .corners
                .iter()
                .copied()
                .chain([centre])
                .filter(|p| {
                    let d = p.distance(position);
                    d > 1.01 * map.near && d < 0.99 * range
                })
                .collect();
            assert_inside(&shadow, &lit, camera, |_, _| 1e-3)?;
        }
    }
}

/// A street-level camera over open ground.
fn street() -> (Camera, SceneBounds) {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
    )
    .unwrap();
    let ground = Aabb::new(Vec3::new(-150.0, 0.0, -320.0), Vec3::new(150.0, 1.0, 20.0));
    let scene = SceneBounds::new(ground, Aabb::new(ground.min, ground.max + 30.0 * Vec3::Y));
    (camera, scene)
}

/// The visible ground: vertices of frustum ∩ receivers and points between them.
fn visible_ground(camera: &Camera, scene: &SceneBounds) -> Vec<Vec3> {
    let body = ConvexBody::from_frustum_aabb(&camera.frustum().unwrap(), &scene.receivers).unwrap();
    let v = body.vertices();
    let mut points = v.to_vec();
    for (i, a) in v.iter().enumerate() {
        for b in &v[i + 1..] {
            points.push(a.lerp(*b, 0.5));
        }
    }
    points
}

#[test]
fn every_directional_technique_fits_a_street_view() {
    let (camera, scene) = street();
    let points = visible_ground(&camera, &scene);
    let case = WarpCase {
        camera,
        light: Vec3::new(0.4, -1.0, 0.3),
        scene,
        eta: 0.0,
        reversed_z: false,
    };
    let checked = check_directional(&case, &points).unwrap();
    assert_eq!(checked, of_kind(LightKind::Directional).count());
}

#[test]
fn depth_bounds_shrink_the_cascades_to_the_samples() {
    let (camera, scene) = street();
    let light = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let points = visible_ground(&camera, &scene);
    let near: Vec<Vec3> = points
        .into_iter()
        .filter(|p| camera.view_depth(*p) < 40.0)
        .collect();
    let samples = eye_samples(&camera, &near);
    let bounds = depth_bounds_of(&camera, &samples).unwrap();
    assert!(bounds.max < 40.0 && bounds.min < bounds.max);
    let input = FitInput::new(&camera, &light, scene, BUDGET)
        .with_eye_samples(&samples)
        .with_depth_bounds(Some(bounds));
    for technique in [
        Technique::StableCascades(Default::default()),
        Technique::TightCascades(Default::default()),
        Technique::WarpedCascades {
            plan: Default::default(),
            lispsm: Default::default(),
        },
    ] {
        let shadow = fit(&technique, &input).unwrap();
        let tol = |layer, p| layer_transform(&shadow, layer).map_or(1e-4, |t| f32_rounding(&t, p));
        assert_inside(&shadow, &near, &camera, tol).unwrap();
        // Nothing beyond the bounds is mapped: the cascades end there.
        let far = camera.eye() + camera.forward() * (bounds.max * 1.5);
        assert!(shadow.map_point(far.as_dvec3()).is_none());
    }
}

#[test]
fn spot_fit_covers_the_lit_view() {
    let (camera, scene) = street();
    let light = Light::Spot {
        position: Vec3::new(0.0, 40.0, -30.0),
        direction: Vec3::NEG_Y,
        half_angle: 1.2,
        range: 200.0,
    };
    let shadow = fit(
        &Technique::SpotFit { reversed_z: false },
        &FitInput::new(&camera, &light, scene, BUDGET),
    )
    .unwrap();
    assert_eq!((shadow.layers(), shadow.layer_side()), (1, 512));
    // Visible ground inside the cone and range.
    let lit: Vec<Vec3> = visible_ground(&camera, &scene)
        .into_iter()
        .filter(|p| {
            let d = *p - Vec3::new(0.0, 40.0, -30.0);
            d.length() < 199.0 && d.normalize().dot(Vec3::NEG_Y) > 1.19f32.cos()
        })
        .collect();
    assert!(lit.len() > 3);
    let t = *shadow.transform().unwrap();
    assert_inside(&shadow, &lit, &camera, |_, p| f32_rounding(&t, p)).unwrap();
}

#[test]
fn missing_inputs_and_wrong_lights_are_typed_errors() {
    let (camera, scene) = street();
    let sun = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let input = FitInput::new(&camera, &sun, scene, BUDGET);
    assert_eq!(
        fit(&Technique::Rtw(Default::default()), &input).unwrap_err(),
        FitError::MissingInput {
            technique: "rtw",
            input: "eye_samples"
        }
    );
    let samples = eye_samples(&camera, &visible_ground(&camera, &scene));
    let with_samples = input.with_eye_samples(&samples);
    assert!(fit(&Technique::Rtw(Default::default()), &with_samples).is_ok());
    assert_eq!(
        fit(&Technique::RtwOracle(Default::default()), &with_samples).unwrap_err(),
        FitError::MissingInput {
            technique: "rtw_oracle",
            input: "pixels_per_radian"
        }
    );
    for technique in Technique::all_default() {
        let wrong = !technique.applies_to(&sun);
        let r = fit(&technique, &with_samples.with_pixels_per_radian(400.0));
        assert_eq!(wrong, r.is_err(), "{}", technique.name());
        if wrong {
            assert_eq!(
                r.unwrap_err(),
                FitError::WrongLight {
                    technique: technique.name()
                }
            );
        }
    }
    let none = FitInput::new(&camera, &sun, scene, 0);
    assert_eq!(
        fit(&Technique::Lispsm(Default::default()), &none).unwrap_err(),
        FitError::InvalidBudget
    );
    // The math crate's own error, wrapped.
    let nan = Light::Directional {
        direction: Vec3::NAN,
    };
    let r = fit(
        &Technique::Xpsm(Default::default()),
        &FitInput::new(&camera, &nan, scene, BUDGET),
    );
    assert!(matches!(r, Err(FitError::Warp(_))), "{r:?}");
}

#[test]
fn auto_reports_its_choice_and_keeps_it_with_a_selector() {
    let (camera, scene) = street();
    let sun = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let input = FitInput::new(&camera, &sun, scene, BUDGET);
    let auto = Technique::Auto(Default::default());
    let chosen = fit(&auto, &input).unwrap();
    assert_eq!(chosen.requested(), &auto);
    assert_ne!(chosen.technique(), &auto);
    // A perspective view over open ground: a warp or cascades beat the uniform fit.
    assert!(!matches!(chosen.technique(), Technique::UniformFocused(_)));
    let same = fit(chosen.technique(), &input).unwrap();
    let p = DVec3::new(1.0, 0.0, -20.0);
    assert_eq!(chosen.map_point(p), same.map_point(p));
    // A selector that holds the uniform fit with a wide margin keeps it.
    let mut selector = TechniqueSelector::new().with_switch_margin(0.999);
    selector.current = Some(0);
    let kept = fit_with_selector(&auto, &input, &mut selector).unwrap();
    assert!(matches!(kept.technique(), Technique::UniformFocused(_)));
    assert_eq!(selector.current, Some(0));
}

/// The stable cascades of a camera walking and turning down the street, fitted with
/// one `FitState` threaded through the frames, and the tight cascades of frame 0.
fn street_walk() -> (Vec<Shadow>, Shadow, Vec<Vec3>) {
    street_walk_with(|_, bounds| bounds)
}

/// [`street_walk`] with frame `k`'s depth bounds `bounds_at(k, frame 0's)`.
fn street_walk_with(
    bounds_at: impl Fn(usize, DepthBounds) -> DepthBounds,
) -> (Vec<Shadow>, Shadow, Vec<Vec3>) {
    let (first, scene) = street();
    let light = Light::Directional {
        direction: Vec3::new(0.4, -1.0, 0.3),
    };
    let points = visible_ground(&first, &scene);
    let bounds = depth_bounds_of(&first, &eye_samples(&first, &points));
    let plan = CascadePlan::default();
    let mut state = FitState::default();
    let stable: Vec<Shadow> = (0..6)
        .map(|k| {
            let t = k as f32;
            let forward = Vec3::new(0.004 * t, -0.2, -1.0);
            let camera = Camera::look_to(
                Vec3::new(0.3 * t, 2.0, -1.1 * t),
                forward,
                Vec3::Y,
                Projection::perspective(1.0, 16.0 / 9.0, 0.5, 300.0),
            )
            .unwrap();
            let input = FitInput::new(&camera, &light, scene, BUDGET)
                .with_depth_bounds(bounds.map(|b| bounds_at(k, b)));
            fit_with_state(&Technique::StableCascades(plan), &input, &mut state).unwrap()
        })
        .collect();
    let input = FitInput::new(&first, &light, scene, BUDGET).with_depth_bounds(bounds);
    let tight = fit(&Technique::TightCascades(plan), &input).unwrap();
    (stable, tight, points)
}

fn cascades(shadow: &Shadow) -> &shadowmap::frustum::CascadeSet {
    match shadow.fitted() {
        Fitted::Cascades(set) => set,
        other => panic!("not cascades: {other:?}"),
    }
}

#[test]
fn stable_cascades_with_a_fit_state_hold_their_size_and_move_by_whole_texels() {
    let (stable, _, points) = street_walk();
    assert_whole_texel_moves(&stable, &points);
}

/// The depth bounds jump (a near receiver leaves the view) and creep (the far end
/// recedes as the camera walks): the stable cascades split a held range, so their
/// maps keep their size and still move by whole texels. Splitting each frame's
/// bounds re-sized them.
#[test]
fn stable_cascades_hold_their_size_while_the_depth_bounds_jump_and_creep() {
    // Frame 0's bounds reach the far plane; half of it leaves room to recede.
    let (stable, _, points) = street_walk_with(|k, b| DepthBounds {
        min: if k >= 2 { b.min * 1.2 } else { b.min },
        max: 0.5 * b.max * 1.03f32.powi(k as i32),
    });
    assert_whole_texel_moves(&stable, &points);
}

fn assert_whole_texel_moves(stable: &[Shadow], points: &[Vec3]) {
    let side = f64::from(stable[0].layer_side());
    for pair in stable.windows(2) {
        let (a, b) = (cascades(&pair[0]), cascades(&pair[1]));
        assert_eq!(a.cascades.len(), b.cascades.len());
        for (ca, cb) in a.cascades.iter().zip(&b.cascades) {
            assert_eq!(ca.texel_world_size, cb.texel_world_size);
            for p in points {
                let (Some(sa), Some(sb)) = (ca.transform.project(*p), cb.transform.project(*p))
                else {
                    continue;
                };
                let moved = (sb.uv - sa.uv) * side;
                let phase = moved - moved.round();
                assert!(phase.abs().max_element() < 1e-3, "moved {moved} texels");
            }
        }
    }
}

#[test]
fn stable_cascades_cost_at_most_the_headroom_over_tight_ones() {
    let (stable, tight, _) = street_walk();
    let (s, t) = (cascades(&stable[0]), cascades(&tight));
    assert_eq!(s.cascades.len(), t.cascades.len());
    // The larger side of a box turned by phi grows by at most cos phi + sin phi, or
    // the headroom where that is more; then the short-mantissa rounding and the
    // snap's texel.
    let light_y = Vec3::new(0.4, -1.0, 0.3).normalize().y;
    let phi = shadowmap::frustum::STABLE_TURN * f64::from(light_y.abs());
    let side = f64::from(stable[0].layer_side());
    let turned = (phi.cos() + phi.sin()).max(shadowmap::frustum::STABLE_HEADROOM);
    let bound = turned * (1.0 + 1.0 / 64.0) * side / (side - 1.0);
    for (cs, ct) in s.cascades.iter().zip(&t.cascades) {
        let ratio = f64::from(cs.texel_world_size / ct.texel_world_size);
        assert!(
            ratio >= 1.0 && ratio <= bound,
            "stable/tight texel {ratio}, bound {bound}"
        );
    }
}

#[test]
fn a_small_room_gets_fewer_cascades_than_open_ground() {
    let light = Light::Directional {
        direction: Vec3::new(0.3, -1.0, 0.2),
    };
    let count = |camera: &Camera, scene: SceneBounds, near: f32, far: f32| {
        let bounds = DepthBounds {
            min: near,
            max: far,
        };
        let input = FitInput::new(camera, &light, scene, BUDGET).with_depth_bounds(Some(bounds));
        fit(&Technique::TightCascades(CascadePlan::default()), &input)
            .unwrap()
            .layers()
    };
    let (street, ground) = street();
    assert_eq!(count(&street, ground, 1.0, 300.0), 4);
    // Inside a 6 m room seen from 2 m to 6 m every slice spans the room's width: one
    // map of the budget is finer everywhere than four maps of a quarter each.
    let room = Aabb::new(Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 3.0, 3.0));
    let camera = Camera::look_to(
        Vec3::new(0.0, 1.6, 2.5),
        Vec3::new(0.0, -0.3, -1.0),
        Vec3::Y,
        Projection::perspective(1.2, 16.0 / 9.0, 0.1, 100.0),
    )
    .unwrap();
    assert_eq!(count(&camera, SceneBounds::whole(room), 2.0, 6.0), 1);
}

/// A sweep case of the quality report in the indoor room (10 x 3 x 8 m) at 128²
/// texels: the camera at `eye` looking along `forward` (60° vertical field of view,
/// 16:9), its depth range and the eye samples' depth bounds, the sun along
/// `light`. The layers of each technique's fit.
struct RoomCase {
    eye: Vec3,
    forward: Vec3,
    range: (f32, f32),
    bounds: (f32, f32),
    light: Vec3,
}

impl RoomCase {
    fn layers(&self, technique: &Technique) -> u32 {
        self.layers_in_turn(&[*technique])[0]
    }

    /// The layers of each technique's fit, fitted in turn with one [`FitState`]
    /// (as `auto` fits its candidates each frame).
    fn layers_in_turn(&self, techniques: &[Technique]) -> Vec<u32> {
        let room = Aabb::new(Vec3::new(-5.0, 0.0, -4.0), Vec3::new(5.0, 3.0, 4.0));
        let (near, far) = self.range;
        let projection = Projection::perspective(60f32.to_radians(), 16.0 / 9.0, near, far);
        let camera = Camera::look_to(self.eye, self.forward, Vec3::Y, projection).unwrap();
        let light = Light::Directional {
            direction: self.light,
        };
        let (min, max) = self.bounds;
        let input = FitInput::new(&camera, &light, SceneBounds::whole(room), 128 * 128)
            .with_depth_bounds(Some(DepthBounds { min, max }));
        let mut state = FitState::default();
        techniques
            .iter()
            .map(|t| fit_with_state(t, &input, &mut state).unwrap().layers())
            .collect()
    }
}

/// A sweep case of the quality report: a room, the camera looking 43° down, the light
/// 10° off the view. Each slice's map then covers nearly the whole footprint, so four
/// maps of a quarter of the budget give the far slices coarser texels than one map:
/// measured, four cascades were 1.68x worse than the uniform fit. Their predicted
/// 95th percentile was 14% lower than one cascade's, their predicted largest error
/// 1.54x higher; the tail rule keeps one cascade.
#[test]
fn a_light_along_the_view_in_a_room_keeps_one_cascade() {
    let case = RoomCase {
        eye: Vec3::new(2.571_319_3, 1.0, 3.643_666_3),
        forward: Vec3::new(0.216_262_62, -0.681_482_14, -0.699_151_3),
        range: (0.754_495_1, 15.783_536),
        bounds: (0.915_524_24, 3.694_208_9),
        light: Vec3::new(0.223_679_5, -0.773_996_2, -0.592_365_9),
    };
    for technique in [
        Technique::TightCascades(CascadePlan::default()),
        Technique::StableCascades(CascadePlan::default()),
    ] {
        assert_eq!(case.layers(&technique), 1, "{technique:?}");
    }
}

/// A sweep case of the quality report: a room at 128² texels, the camera looking
/// 45° down toward the room's middle, the sun 35° off the vertical. The tight
/// cascades predict one map best, and one tight map is the uniform fit. One stable
/// map, newly sized, takes its margins for the camera's turn and walk: over this
/// footprint 8% and 14% on its sides, which measured 1.12x the uniform fit's
/// 95th-percentile error. Four stable maps of a quarter of the texels each cost
/// less (1.01x): the stable cascades choose their count on their own predicted
/// error.
#[test]
fn in_a_room_the_stable_cascades_choose_their_count_on_their_own_error() {
    let case = RoomCase {
        eye: Vec3::new(-4.550_791_7, 1.0, 1.037_736_5),
        forward: Vec3::new(0.081_558_75, -0.700_386_6, 0.709_088_7),
        range: (0.503_045_8, 15.783_536),
        bounds: (0.503_220_9, 3.079_653_7),
        light: Vec3::new(0.180_986_85, -0.822_822, -0.538_709_34),
    };
    assert_eq!(
        case.layers(&Technique::TightCascades(CascadePlan::default())),
        1
    );
    assert_eq!(
        case.layers(&Technique::StableCascades(CascadePlan::default())),
        4
    );
    // Fitted after the tight cascades with one state, as `auto` fits its
    // candidates, they still choose their own count (a shared count once handed
    // the tight cascades' one map to them, and `auto` took a candidate 1.12 times
    // the stable cascades' error at seed 137 of the sweep).
    let plan = CascadePlan::default();
    let in_turn = [
        Technique::TightCascades(plan),
        Technique::StableCascades(plan),
    ];
    assert_eq!(case.layers_in_turn(&in_turn), [1, 4]);
    assert_eq!(case.layers_in_turn(&[in_turn[1], in_turn[0]]), [4, 1]);
}
