//! Overhead-light golden case (`docs/quality.md`): camera looking horizontally, light straight
//! down, n = 1, f = 1000, fovY = 60°. Fed the oracle importance with no blur, the RTW
//! warp's texel density along the view direction follows the ideal `1/z` profile.

use glam::{DVec3, Vec3};
use shadowmap_frustum::{
    Camera, CascadeFit, CascadeOptions, Projection, ShadowMapping, ShadowTransform, fit_cascade,
};
use shadowmap_rtw::{EyeSample, ImportanceMap, RtwShadow, WarpMaps, WarpOptions};

const NEAR: f32 = 1.0;
const FAR: f32 = 1000.0;

struct Setup {
    camera: Camera,
    base: ShadowTransform,
    /// Which base texture axis the view direction runs along (0 = u, 1 = v).
    view_axis: usize,
}

fn setup() -> Setup {
    let camera = Camera::look_to(
        Vec3::ZERO,
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 1.0, NEAR, FAR),
    )
    .unwrap();
    let options = CascadeOptions::default()
        .with_fit(CascadeFit::Tight)
        .with_up_hint(Vec3::Z);
    let base = fit_cascade(&camera, Vec3::NEG_Y, NEAR, FAR, &options)
        .unwrap()
        .transform;
    let a = base.project(Vec3::new(0.0, 0.0, -NEAR)).unwrap().uv;
    let b = base.project(Vec3::new(0.0, 0.0, -FAR)).unwrap().uv;
    let d = (b - a).abs();
    let view_axis = usize::from(d.y > d.x);
    Setup {
        camera,
        base,
        view_axis,
    }
}

/// Eye samples filling the frustum: 2 per importance cell along the view direction,
/// 9 lateral positions, zero normal (the perspective-only oracle).
fn samples(camera: &Camera, cells: u32) -> Vec<EyeSample> {
    let tan = (30f32.to_radians()).tan();
    let depths = 2 * cells as usize;
    let mut out = Vec::with_capacity(depths * 9);
    for k in 0..=depths {
        let z = NEAR + (FAR - NEAR) * k as f32 / depths as f32;
        for j in -4..=4 {
            let x = 0.999 * z * tan * j as f32 / 4.0;
            let p = Vec3::new(x, 0.0, -z);
            out.push(EyeSample {
                position: p,
                normal: Vec3::ZERO,
                eye_distance: p.distance(camera.eye()),
            });
        }
    }
    out
}

/// Builds the oracle warp with `cells` importance cells along the view direction and
/// returns the worst relative deviation `(r - 1, z)` of the density from the ideal
/// over `z in [z_lo, far - 3 cells]`.
fn worst_deviation(cells: u32, z_lo_cells: Option<f64>, z_lo: f64) -> (f64, f64) {
    let s = setup();
    let (w, h) = if s.view_axis == 1 {
        (8, cells)
    } else {
        (cells, 8)
    };
    let mut map = ImportanceMap::new(w, h).unwrap();
    let pixels_per_radian = 1080.0 / (2.0 * 30f32.to_radians().tan());
    let stats = map
        .accumulate_oracle(
            &s.base,
            &s.camera,
            pixels_per_radian,
            &samples(&s.camera, cells),
        )
        .unwrap();
    assert!(stats.accepted > stats.skipped * 100, "{stats:?}");
    let mut warps = WarpMaps::new(w, h).unwrap();
    warps
        .build(
            &map,
            &WarpOptions::default().with_blur_radius(0).with_floor(1e-4),
        )
        .unwrap();
    let rtw = RtwShadow {
        base: s.base,
        warps: &warps,
    };

    // Warped coordinate along the view direction, oriented to grow with z.
    let coord = |z: f64| rtw.map_point(DVec3::new(0.0, 0.0, -z)).unwrap().uv[s.view_axis];
    let sign = (coord(f64::from(FAR)) - coord(f64::from(NEAR))).signum();
    let ideal_k = 1.0 / (f64::from(FAR) / f64::from(NEAR)).ln();
    // Density r(z) = du'/dz * z / K, 1 for the ideal profile.
    let cell = f64::from(FAR - NEAR) / f64::from(cells);
    let ratio = |z: f64| {
        let dz = 2.0 * cell;
        sign * (coord(z + dz) - coord(z - dz)) / (2.0 * dz) * z / ideal_k
    };
    let mut worst = (0.0f64, 0.0f64);
    let mut report = Vec::new();
    let steps = 400;
    let z_lo = z_lo_cells.map_or(z_lo, |k| f64::from(NEAR) + k * cell);
    let z_hi = f64::from(FAR) - 3.0 * cell;
    for i in 0..=steps {
        let z = z_lo * (z_hi / z_lo).powf(f64::from(i) / f64::from(steps));
        let r = ratio(z);
        if (r - 1.0).abs() > worst.0.abs() {
            worst = (r - 1.0, z);
        }
        if i % 50 == 0 {
            report.push(format!("z={z:.1}: {r:.4}"));
        }
    }
    eprintln!(
        "{cells} cells, density / ideal along the view direction: {}",
        report.join(", ")
    );
    eprintln!(
        "{cells} cells: worst deviation {:.4} at z = {:.2}",
        worst.0, worst.1
    );
    // The warped coordinate itself follows the logarithmic ideal over the whole range.
    // (measured from z_lo, where the discretization of the first cells is behind us).
    for z in [10.0f64, 100.0, 500.0, z_hi] {
        let got = sign * (coord(z) - coord(z_lo));
        let want = (z / z_lo).ln() * ideal_k;
        eprintln!("{cells} cells: u'({z:.1}) - u'({z_lo:.2}) = {got:.5}, ideal {want:.5}");
        assert!((got - want).abs() <= 0.01, "u'({z}) = {got}, ideal {want}");
    }
    worst
}

/// 16384 cells along the view direction: within 5% of the ideal over the whole
/// frustum but the three outermost cells at each end (z in [1.18, 999.8]).
#[test]
fn overhead_light_oracle_gives_one_over_z() {
    let (dev, z) = worst_deviation(16384, Some(3.0), 0.0);
    assert!(
        dev.abs() <= 0.05,
        "density deviates {dev:.4} from 1/z at z = {z:.2}"
    );
}

/// 1024 cells (about one world unit each): the max-per-cell oracle over-allocates
/// the nearest cells, where 1/z changes by a factor of several within one cell;
/// from z = 20 on the density is within 5% of the ideal.
#[test]
fn overhead_light_oracle_1024_cells() {
    let (dev, z) = worst_deviation(1024, None, 20.0);
    assert!(
        dev.abs() <= 0.05,
        "density deviates {dev:.4} from 1/z at z = {z:.2}"
    );
}
