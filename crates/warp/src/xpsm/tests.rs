//! XPSM's steps: the miner's lamp, the projection vector's clip, the focus region
//! and the faded length.

use glam::Vec3;
use shadowmap_frustum::{Aabb, Camera, Projection, ShadowMapping};

use super::*;
use crate::SceneBounds;

fn camera() -> Camera {
    Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap()
}

#[test]
fn miner_lamp_is_orthographic() {
    let cam = camera();
    let scene = SceneBounds::whole(Aabb::new(Vec3::splat(-150.0), Vec3::splat(150.0)));
    let x = xpsm(&cam, cam.forward(), &scene, &XpsmOptions::default()).unwrap();
    assert_eq!(x.warp_weight, 0.0);
    assert_eq!(x.length_p, 0.0);
    let m = x.transform.clip_from_world;
    assert_eq!(
        glam::Vec4::new(m.x_axis.w, m.y_axis.w, m.z_axis.w, m.w_axis.w),
        glam::Vec4::W
    );
}

#[test]
fn casters_behind_the_viewer_clip_the_projection_vector() {
    // Light from behind the camera; the caster box reaches far behind the viewer
    // (the camera is inside the caster volume).
    let cam = camera();
    let receivers = Aabb::new(Vec3::new(-100.0, -1.0, -100.0), Vec3::new(100.0, 0.0, 0.0));
    let casters = Aabb::new(
        Vec3::new(-100.0, -1.0, -100.0),
        Vec3::new(100.0, 30.0, 400.0),
    );
    let scene = SceneBounds::new(receivers, casters);
    let light = Vec3::new(0.1, -0.6, -1.0);
    let o = XpsmOptions::default().with_coef(10.0);
    let x = xpsm(&cam, light, &scene, &o).unwrap();
    assert!(x.max_length_p.is_finite() && x.max_length_p > 0.0, "{x:?}");
    assert_eq!(x.length_p, x.max_length_p);
    // Every visible receiver keeps w >= epsilonW and lands in the map.
    let body =
        shadowmap_frustum::ConvexBody::from_frustum_aabb(&cam.frustum().unwrap(), &receivers)
            .unwrap();
    let m = x.transform.clip_from_world.as_dmat4();
    for v in body.vertices() {
        let h = m * v.as_dvec3().extend(1.0);
        assert!(h.w >= 0.1 * (1.0 - 1e-5), "w = {}", h.w);
        let s = x.transform.map_point(v.as_dvec3()).unwrap();
        assert!(
            (-1e-4..=1.0001).contains(&s.uv.x) && (-1e-4..=1.0001).contains(&s.uv.y),
            "{s:?}"
        );
    }
    // Without the casters behind, the same coef is not clipped.
    let front = SceneBounds::new(
        receivers,
        Aabb::new(receivers.min, Vec3::new(100.0, 30.0, 0.0)),
    );
    let y = xpsm(&cam, light, &front, &o).unwrap();
    assert!(y.length_p >= x.length_p);
}

#[test]
fn disjoint_boxes_have_no_focus_region() {
    let cam = camera();
    let receivers = Aabb::new(Vec3::new(-10.0, -1.0, -50.0), Vec3::new(10.0, 0.0, -1.0));
    let casters = Aabb::new(Vec3::new(500.0, 0.0, -50.0), Vec3::new(510.0, 5.0, -40.0));
    let r = xpsm(
        &cam,
        Vec3::NEG_Y,
        &SceneBounds::new(receivers, casters),
        &XpsmOptions::default(),
    );
    assert_eq!(r.err(), Some(WarpError::EmptyFocusRegion));
    for bad in [
        XpsmOptions::default().with_epsilon_w(0.0),
        XpsmOptions::default().with_coef(f32::NAN),
    ] {
        let r = xpsm(&cam, Vec3::NEG_Y, &SceneBounds::whole(receivers), &bad);
        assert_eq!(r.err(), Some(WarpError::InvalidOption));
    }
}

/// In the miner's-lamp band the warp ratio `1 + lengthP D` is the full ratio
/// raised to the weight: a ratio of 50 is 7.07 at half weight and 1.34 at
/// 0.075 (where scaling `lengthP` kept 4.7), and it grows with the weight.
#[test]
fn the_warp_ratio_fades_as_a_power_of_the_weight() {
    let (d, full) = (100.0, 0.49);
    let ratio = |w: f64| 1.0 + faded_length(full, d, w) * d;
    assert_eq!(faded_length(full, d, 0.0), 0.0);
    assert_eq!(faded_length(full, d, 1.0), full);
    assert!((ratio(0.5) - 50f64.sqrt()).abs() < 1e-9);
    assert!((ratio(0.075) - 50f64.powf(0.075)).abs() < 1e-9);
    let mut last = 1.0;
    for i in 1..=100 {
        let r = ratio(f64::from(i) / 100.0);
        assert!(r > last, "ratio {r} at weight {i}/100 after {last}");
        last = r;
    }
    assert!((last - 50.0).abs() < 1e-9);
}

proptest::proptest! {
    /// The PPLS point made without the matrix is the matrix's product, value for
    /// value, whatever the length (0 included: the orthographic fit).
    #[test]
    fn the_ppls_point_is_the_matrix_product(
        p in proptest::array::uniform3(-1e4f64..1e4),
        length_p in proptest::prop_oneof![proptest::strategy::Just(0.0), 0.0f64..10.0],
    ) {
        let ppls = Ppls { length_p };
        let p = DVec3::from(p);
        proptest::prop_assert_eq!(ppls.hom(p), ppls.matrix() * p.extend(1.0));
    }
}

/// The baseline every warp's strength is judged against, predicted once per body
/// (`Probe::fill`), is each warp's own fit at strength 0: LiSPSM's and TSM's
/// exactly (the same fit), XPSM's orthographic fit to rounding where the caster
/// box holds the receivers' footprint, and finer where that box cuts it.
#[test]
fn the_bodys_uniform_error_is_every_warps_strength_zero() {
    let cam = camera();
    let ground = Aabb::new(Vec3::new(-100.0, -1.0, -100.0), Vec3::new(100.0, 0.0, 0.0));
    let tall = Aabb::new(Vec3::new(-100.0, -1.0, -100.0), Vec3::new(100.0, 20.0, 0.0));
    // Casters on one side of the street only: their box cuts the footprint.
    let one_side = Aabb::new(Vec3::new(0.0, -1.0, -100.0), Vec3::new(100.0, 20.0, 0.0));
    let lights = [
        Vec3::new(0.3, -1.0, 0.6),
        Vec3::new(0.0, -0.3, -1.0),
        Vec3::new(1.0, -0.4, 0.1),
        Vec3::new(-0.2, -1.0, 0.05),
    ];
    let mut cut = 0;
    for (casters, cuts) in [(tall, false), (one_side, true)] {
        let scene = SceneBounds::new(ground, casters);
        for light in lights {
            let body = FocusBody::new(&cam, light, &scene).unwrap();
            let (f, view) = (&body.focus, &body.view);
            let probe = body.probe();
            let uniform = crate::lispsm::warp_clip(f, view, 0.0, true).unwrap();
            let (lispsm, baseline) = probe.lit_errors(&uniform.clip_from_light);
            assert!(baseline.is_finite() && baseline > 0.0, "{light}");
            assert_eq!(lispsm, baseline, "{light}");
            let options = XpsmOptions::default();
            let thr = f64::from(options.miner_lamp_threshold);
            let weight = smoothstep(thr, 2.0 * thr, f.sin_gamma);
            let (_, shift) = auto_length(f, view, weight);
            let space = XpsmSpace::new(view, f, &options, shift);
            let fit = xpsm_fit(&space, f, &options, 0.0).unwrap();
            let (xpsm, _) = probe.lit_errors(&fit.clip_from_light);
            let ratio = xpsm / baseline;
            if cuts {
                assert!(ratio <= 1.0 + 1e-9, "{light}: {ratio}");
                cut += usize::from(ratio < 0.99);
            } else {
                assert!((ratio - 1.0).abs() < 1e-9, "{light}: {ratio}");
            }
        }
    }
    assert!(cut >= 2, "{cut}");
}

/// A caster box 1e30 from the receivers (found by the fuzz target `warp_xpsm`):
/// the focus region's scale and offset overflow, and the prediction read a clip
/// matrix of NaNs (a debug assertion on its structure failed). The fit refuses it
/// with a typed error, as the whole call does.
#[test]
fn a_caster_box_beyond_f64_is_refused_before_the_prediction() {
    let camera = Camera {
        world_from_view: glam::Mat4::IDENTITY,
        projection: Projection::perspective(1.0, 1.5, 0.1, 100.0),
        reversed_z: true,
    };
    let receivers = Aabb::new(
        Vec3::new(-2.22786, -2.22786, -52.27786),
        Vec3::new(2.22786, 2.22786, -47.82214),
    );
    let casters = Aabb::new(
        Vec3::splat(-2.396108e30),
        Vec3::new(-2.396108e30, -2.396108e30, 3.3003e-41),
    );
    let light = Vec3::new(0.00015502599, -1.0, -3.295181e-5);
    let scene = SceneBounds::new(receivers, casters);
    let fitted = xpsm(&camera, light, &scene, &XpsmOptions::default());
    assert!(fitted.is_err(), "{fitted:?}");
}
