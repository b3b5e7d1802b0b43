//! Regression tests for inputs at the numerical limits: every builder returns a
//! typed error or a documented fallback, never a singular matrix or texels finer
//! than `f32` resolves.

use glam::{DVec3, Vec3, Vec4};
use shadowmap_frustum::{Aabb, Camera, Projection, ShadowMapping, ShadowTransform, is_invertible};
use shadowmap_warp::{
    LispsmOptions, MAX_MAP_SIDE, SceneBounds, TsmOptions, UniformOptions, WarpError, XpsmOptions,
    lispsm, tsm, uniform_focused, xpsm,
};

fn camera(eye: Vec3) -> Camera {
    Camera::look_to(
        eye,
        Vec3::new(0.0, -0.3, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.5, 200.0),
    )
    .unwrap()
}

/// Every technique on one input, as transforms (errors kept).
fn all(
    cam: &Camera,
    light: Vec3,
    scene: &SceneBounds,
    xo: &XpsmOptions,
) -> [(&'static str, Result<ShadowTransform, WarpError>); 4] {
    [
        (
            "uniform",
            uniform_focused(cam, light, scene, &UniformOptions::default()),
        ),
        (
            "lispsm",
            lispsm(cam, light, scene, &LispsmOptions::default()).map(|s| s.transform),
        ),
        (
            "tsm",
            tsm(cam, light, scene, &TsmOptions::default()).map(|s| s.transform),
        ),
        ("xpsm", xpsm(cam, light, scene, xo).map(|s| s.transform)),
    ]
}

/// Casters absurdly tall, or `epsilon_w` at its smallest: each result is either
/// `Degenerate` or a matrix invertible at the receivers' magnitude.
#[test]
fn huge_casters_and_tiny_epsilon_w_give_invertible_matrices_or_degenerate() {
    let cam = camera(Vec3::new(0.0, 2.0, 0.0));
    let ground = Aabb::new(Vec3::new(-100.0, -1.0, -150.0), Vec3::new(100.0, 0.0, 10.0));
    let mut checked = 0;
    for height in [1e6f32, 1e20, 1e30] {
        let tall = Aabb::new(
            Vec3::new(-100.0, -1.0, -150.0),
            Vec3::new(100.0, height, 10.0),
        );
        for light in [Vec3::new(0.3, -1.0, -0.4), Vec3::new(0.1, -0.6, 1.0)] {
            for eps_w in [0.1f32, 1e-7] {
                let xo = XpsmOptions::default().with_epsilon_w(eps_w);
                for (name, r) in all(&cam, light, &SceneBounds::new(ground, tall), &xo) {
                    match r {
                        Ok(t) => {
                            assert!(
                                is_invertible(&t.clip_from_world, 200.0)
                                    && is_invertible(&t.uv_from_world, 200.0),
                                "{name}: height {height}, eps_w {eps_w}: singular {:?}",
                                t.clip_from_world
                            );
                            checked += 1;
                        }
                        Err(e) => assert_eq!(e, WarpError::Degenerate, "{name}: {height}"),
                    }
                }
            }
        }
    }
    assert!(checked > 0);
}

/// `uv` of a world point evaluated in `f32` (as a shader does), in texels of a
/// `side`-texel map, minus the exact value.
fn f32_error_texels(t: &ShadowTransform, p: Vec3, side: u32) -> f64 {
    let h = t.uv_from_world * Vec4::new(p.x, p.y, p.z, 1.0);
    let uv32 = glam::DVec2::new(f64::from(h.x / h.w), f64::from(h.y / h.w));
    let exact = t.map_point(p.as_dvec3()).unwrap().uv;
    (uv32 - exact).abs().max_element() * f64::from(side)
}

/// A point receiver, or a scene 1e-6 wide, far from the origin: the map is widened so
/// that a shader's `f32` evaluation of `uv_from_world` stays within half a texel at
/// the largest supported map size.
#[test]
fn tiny_receivers_keep_texels_resolvable_in_f32() {
    for origin in [Vec3::new(3.0, 0.0, -20.0), Vec3::new(1000.0, 0.0, -1020.0)] {
        let cam = camera(origin + Vec3::new(0.0, 2.0, 20.0));
        let casters = Aabb::new(origin - Vec3::splat(50.0), origin + Vec3::splat(50.0));
        for width in [0.0f32, 1e-6, 1e-3] {
            let receivers = Aabb::new(origin, origin + Vec3::splat(width));
            let scene = SceneBounds::new(receivers, casters);
            let mut checked = 0;
            for (name, r) in all(
                &cam,
                Vec3::new(0.3, -1.0, -0.4),
                &scene,
                &XpsmOptions::default(),
            ) {
                let t = r.unwrap_or_else(|e| panic!("{name}: {e}"));
                for corner in receivers.corners() {
                    let err = f32_error_texels(&t, corner, MAX_MAP_SIDE);
                    assert!(err < 0.5, "{name}: width {width} at {origin}: {err} texels");
                    checked += 1;
                }
                // The texel is at least the f32 spacing of the coordinates, many times over.
                let size = t.texel_world_size(origin, MAX_MAP_SIDE).unwrap();
                let ulp = f64::from(origin.abs().max_element()).max(1.0) * f64::EPSILON.max(1.2e-7);
                assert!(f64::from(size) > 4.0 * ulp, "{name}: texel {size}");
            }
            assert!(checked > 0);
        }
    }
}

/// Hints that contradict each other are refused.
#[test]
fn inverted_hints_are_refused() {
    let cam = camera(Vec3::new(0.0, 2.0, 0.0));
    let scene = SceneBounds::whole(Aabb::new(Vec3::splat(-50.0), Vec3::splat(50.0)));
    let r = lispsm(
        &cam,
        Vec3::NEG_Y,
        &scene,
        &LispsmOptions::default().with_hints(10.0, 5.0),
    );
    assert_eq!(r.err(), Some(WarpError::InvalidOption));
    let p = DVec3::new(0.0, 0.0, -10.0);
    let ok = lispsm(
        &cam,
        Vec3::NEG_Y,
        &scene,
        &LispsmOptions::default().with_hints(5.0, 10.0),
    )
    .unwrap();
    assert!(ok.transform.map_point(p).is_some());
}
