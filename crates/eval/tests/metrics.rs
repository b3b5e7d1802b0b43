//! The metric is right: mappings with a known Jacobian give the hand-computed `m`
//! and `S`.

use glam::{DVec2, DVec3, Vec3};
use shadowmap_eval::metrics::{
    self, ScreenGeometry, SurfacePoint, aliasing_stats, texel_footprint,
};
use shadowmap_frustum::{Camera, Light, Projection, ShadowMapping, ShadowSample};

const W: u32 = 64;
const H: u32 = 48;
/// World units per pixel of the orthographic camera.
const PIXEL: f64 = 0.25;

/// An orthographic camera at the origin looking down `-Z`, one pixel = `PIXEL` units.
fn ortho_camera() -> Camera {
    let (hw, hh) = (0.5 * f64::from(W) * PIXEL, 0.5 * f64::from(H) * PIXEL);
    Camera::look_to(
        Vec3::ZERO,
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::Orthographic {
            left: -hw as f32,
            right: hw as f32,
            bottom: -hh as f32,
            top: hh as f32,
            near: 0.1,
            far: 100.0,
        },
    )
    .unwrap()
}

/// The texel grid is the screen's pixel grid scaled by `scale`: `J = scale * I`.
struct ScreenScaled {
    screen: ScreenGeometry,
    scale: f64,
    resolution: u32,
}

impl ShadowMapping for ScreenScaled {
    fn map_point(&self, world: DVec3) -> Option<ShadowSample> {
        let px = self.screen.project(world)?;
        Some(ShadowSample {
            uv: px * self.scale / f64::from(self.resolution),
            depth: 0.5,
            layer: 0,
        })
    }
}

/// A pinhole projection from the origin: `uv = (1/2 + c x / z, 1/2 - c y / z)`,
/// `z = -world.z`.
struct Pinhole {
    c: f64,
}

impl ShadowMapping for Pinhole {
    fn map_point(&self, p: DVec3) -> Option<ShadowSample> {
        let z = -p.z;
        (z > 0.0).then(|| ShadowSample {
            uv: DVec2::new(0.5 + self.c * p.x / z, 0.5 - self.c * p.y / z),
            depth: 0.5,
            layer: 0,
        })
    }
}

/// One surface per pixel centre, on the plane `z = -(d + a x)` (normal `(a, 0, 1)`).
fn plane_surfaces(screen: &ScreenGeometry, d: f64, a: f64) -> Vec<Option<SurfacePoint>> {
    let normal = DVec3::new(a, 0.0, 1.0);
    let mut out = Vec::new();
    for j in 0..H {
        for i in 0..W {
            let (o, dir) = screen
                .ray(DVec2::new(f64::from(i) + 0.5, f64::from(j) + 0.5))
                .unwrap();
            let t = normal.dot(DVec3::new(0.0, 0.0, -d) - o) / normal.dot(dir);
            out.push(Some(SurfacePoint {
                position: o + dir * t,
                normal,
            }));
        }
    }
    out
}

#[test]
fn scaled_identity_gives_one_over_scale() {
    let camera = ortho_camera();
    let screen = ScreenGeometry::new(&camera, W, H).unwrap();
    let light = Light::Directional {
        direction: Vec3::new(0.3, -0.2, -1.0),
    };
    for scale in [0.5, 2.0, 3.0] {
        let resolution = 256;
        let mapping = ScreenScaled {
            screen,
            scale,
            resolution,
        };
        // A tilted plane: the tangent-plane construction must not change J here.
        let surfaces = plane_surfaces(&screen, 10.0, 0.3);
        let fp = texel_footprint(
            &mapping,
            &[(resolution, resolution)],
            &screen,
            &surfaces[100].unwrap(),
        )
        .unwrap();
        let (s1, s2) = fp.singular_values();
        assert!(
            (s1 - scale).abs() < 1e-6 && (s2 - scale).abs() < 1e-6,
            "{s1} {s2}"
        );
        assert!((fp.aliasing_error() - 1.0 / scale).abs() < 1e-6);

        let (stats, pixels) = aliasing_stats(
            &mapping,
            &[(resolution, resolution)],
            &screen,
            &light,
            &surfaces,
        );
        let m = stats.m.unwrap();
        assert_eq!(stats.visible_pixels, (W * H) as usize);
        assert_eq!(m.count, (W * H) as usize);
        for v in [m.mean, m.median, m.p95, m.max] {
            assert!((v - 1.0 / scale).abs() < 1e-6, "m = {v}, scale {scale}");
        }
        // The bisector normal does not matter for a screen-aligned map either.
        assert!((stats.m_perspective.unwrap().max - 1.0 / scale).abs() < 1e-6);
        // S = texels / pixels * m_max^2, by hand.
        let expected = f64::from(resolution * resolution) / f64::from(W * H) / (scale * scale);
        assert!((stats.storage_factor / expected - 1.0).abs() < 1e-6);
        assert!((stats.separable_storage_factor_perspective / expected - 1.0).abs() < 1e-6);
        assert!(pixels.m.iter().all(Option::is_some));
    }
}

#[test]
fn used_texels_of_scaled_identity() {
    let camera = ortho_camera();
    let screen = ScreenGeometry::new(&camera, W, H).unwrap();
    let light = Light::Directional {
        direction: Vec3::NEG_Z,
    };
    // Scale 2: pixel centre (i + 1/2, j + 1/2) lands in texel (2i + 1, 2j + 1), one
    // texel in four of the 128 x 96 block, none outside it.
    let mapping = ScreenScaled {
        screen,
        scale: 2.0,
        resolution: 128,
    };
    let surfaces = plane_surfaces(&screen, 10.0, 0.0);
    let (stats, _) = aliasing_stats(&mapping, &[(128, 128)], &screen, &light, &surfaces);
    let expected = f64::from(W * H) / (128.0 * 128.0);
    assert!((stats.used_texel_fraction - expected).abs() < 1e-12);
}

#[test]
fn pure_perspective_matches_the_hand_computed_jacobian() {
    let camera = ortho_camera();
    let screen = ScreenGeometry::new(&camera, W, H).unwrap();
    let (d, a, c, res) = (10.0, 0.4, 0.7, 512.0);
    let mapping = Pinhole { c };
    let surfaces = plane_surfaces(&screen, d, a);
    let light = Light::Directional {
        direction: Vec3::NEG_Z,
    };
    let mut m_max = 0.0f64;
    for s in surfaces.iter().flatten() {
        let (x, y) = (s.position.x, s.position.y);
        let z = d + a * x;
        // d(texel)/d(pixel): world moves PIXEL per pixel in x, -PIXEL in y (y down).
        let j11 = res * c * d / (z * z) * PIXEL;
        let j21 = res * c * y * a / (z * z) * PIXEL;
        let j22 = res * c / z * PIXEL;
        // Singular values from the eigenvalues of J^T J, by hand.
        let (p, q, r) = (j11 * j11 + j21 * j21, j21 * j22, j22 * j22);
        let l_min = 0.5 * (p + r) - (0.25 * (p - r) * (p - r) + q * q).sqrt();
        let m_expected = 1.0 / l_min.sqrt();
        m_max = m_max.max(m_expected);
        let fp = texel_footprint(&mapping, &[(512, 512)], &screen, s).unwrap();
        assert!(
            (fp.aliasing_error() / m_expected - 1.0).abs() < 1e-6,
            "at ({x}, {y}): {} vs {m_expected}",
            fp.aliasing_error()
        );
        // On the row y = 0 the Jacobian is diagonal: the axis errors are 1 / diag.
        if y.abs() < 1e-9 {
            let (mu, mv) = fp.axis_errors();
            assert!((mu - 1.0 / j11).abs() < 1e-6 * mu && (mv - 1.0 / j22).abs() < 1e-6 * mv);
        }
    }
    let (stats, _) = aliasing_stats(&mapping, &[(512, 512)], &screen, &light, &surfaces);
    let expected_s = 512.0 * 512.0 / f64::from(W * H) * m_max * m_max;
    assert!((stats.storage_factor / expected_s - 1.0).abs() < 1e-5);
    assert!((stats.m.unwrap().max / m_max - 1.0).abs() < 1e-6);
}

#[test]
fn uncovered_and_background_pixels() {
    let camera = ortho_camera();
    let screen = ScreenGeometry::new(&camera, W, H).unwrap();
    let light = Light::Directional {
        direction: Vec3::NEG_Z,
    };
    let mut surfaces = plane_surfaces(&screen, 10.0, 0.0);
    surfaces[0] = None;
    // Behind the pinhole: not covered, still a visible pixel for S.
    surfaces[1] = Some(SurfacePoint {
        position: DVec3::new(0.0, 0.0, 5.0),
        normal: DVec3::Z,
    });
    let (stats, pixels) =
        aliasing_stats(&Pinhole { c: 0.5 }, &[(64, 64)], &screen, &light, &surfaces);
    assert_eq!(stats.visible_pixels, (W * H) as usize - 1);
    assert_eq!(stats.measured_pixels, (W * H) as usize - 2);
    assert_eq!((pixels.m[0], pixels.m[1]), (None, None));
    assert!(metrics::storage_factor(10, 0, 1.0).is_nan());
    assert!(ScreenGeometry::new(&camera, 0, 4).is_err());
}
