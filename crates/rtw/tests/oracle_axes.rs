//! Per-axis oracle importance (`ImportanceMap::accumulate_oracle_axis`) and
//! `WarpMaps::build_separable`.

use glam::Vec3;
use shadowmap_frustum::{Camera, CascadeFit, CascadeOptions, Projection, fit_cascade};
use shadowmap_rtw::{EyeSample, ImportanceMap, OracleAxis, WarpMaps, WarpOptions};

fn scene() -> (Camera, shadowmap_frustum::ShadowTransform, Vec<EyeSample>) {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, -0.2, -1.0).normalize(),
        Vec3::Y,
        Projection::perspective(60f32.to_radians(), 1.5, 0.5, 300.0),
    )
    .unwrap();
    let options = CascadeOptions::default().with_fit(CascadeFit::Tight);
    let light = Vec3::new(0.3, -1.0, 0.2).normalize();
    let base = fit_cascade(&camera, light, 0.5, 300.0, &options)
        .unwrap()
        .transform;
    // Ground points (normal up) in front of the camera, from near to far.
    let mut samples = Vec::new();
    for k in 0..60 {
        let z = 3.0 + 2.0 * k as f32;
        for j in -5..=5 {
            let p = Vec3::new(0.5 * z * j as f32 / 5.0, 0.0, -z);
            samples.push(EyeSample {
                position: p,
                normal: Vec3::Y,
                eye_distance: p.distance(camera.eye()),
            });
        }
    }
    (camera, base, samples)
}

fn oracle(axis: OracleAxis) -> ImportanceMap {
    let (camera, base, samples) = scene();
    let mut map = ImportanceMap::new(32, 24).unwrap();
    let stats = map
        .accumulate_oracle_axis(axis, &base, &camera, 500.0, &samples)
        .unwrap();
    assert_eq!(stats.skipped, 0, "{stats:?}");
    map
}

#[test]
fn axis_requirements_are_bounded_by_the_isotropic_one() {
    let (iso, u, v) = (
        oracle(OracleAxis::Isotropic),
        oracle(OracleAxis::U),
        oracle(OracleAxis::V),
    );
    let mut occupied = 0;
    let mut unequal = 0;
    for ((&i, &a), &b) in iso.as_slice().iter().zip(u.as_slice()).zip(v.as_slice()) {
        if i == 0.0 {
            assert_eq!((a, b), (0.0, 0.0));
            continue;
        }
        occupied += 1;
        // ‖J⁻¹‖₂ bounds each column norm, and the Frobenius norm bounds ‖J⁻¹‖₂.
        assert!(
            a <= i * (1.0 + 1e-5) && b <= i * (1.0 + 1e-5),
            "{a} {b} {i}"
        );
        assert!(a.hypot(b) >= i * (1.0 - 1e-5), "{a} {b} {i}");
        if (a - b).abs() > 0.1 * i {
            unequal += 1;
        }
    }
    assert!(occupied >= 30, "{occupied}");
    // A receding ground plane needs different densities on the two axes.
    assert!(unequal > occupied / 4, "{unequal} of {occupied}");
}

#[test]
fn separable_build_of_one_map_equals_build() {
    let map = oracle(OracleAxis::Isotropic);
    let options = WarpOptions::default();
    let mut a = WarpMaps::new(32, 24).unwrap();
    a.build(&map, &options).unwrap();
    let mut b = WarpMaps::new(32, 24).unwrap();
    b.build_separable(&map, &map, &options).unwrap();
    assert_eq!(a.x_table(), b.x_table());
    assert_eq!(a.y_table(), b.y_table());
    assert_eq!(a.density_x(), b.density_x());
    assert_eq!(a.density_y(), b.density_y());
}

#[test]
fn separable_build_takes_u_from_columns_and_v_from_rows() {
    let (u, v) = (oracle(OracleAxis::U), oracle(OracleAxis::V));
    let options = WarpOptions::default();
    let mut sep = WarpMaps::new(32, 24).unwrap();
    sep.build_separable(&u, &v, &options).unwrap();
    let mut from_u = WarpMaps::new(32, 24).unwrap();
    from_u.build(&u, &options).unwrap();
    let mut from_v = WarpMaps::new(32, 24).unwrap();
    from_v.build(&v, &options).unwrap();
    assert_eq!(sep.x_table(), from_u.x_table());
    assert_eq!(sep.y_table(), from_v.y_table());
    assert_ne!(sep.x_table(), from_v.x_table());
}

#[test]
fn separable_build_rejects_mismatched_maps() {
    let a = ImportanceMap::new(32, 24).unwrap();
    let b = ImportanceMap::new(24, 32).unwrap();
    let mut w = WarpMaps::new(32, 24).unwrap();
    assert!(w.build_separable(&a, &b, &WarpOptions::default()).is_err());
    assert!(w.build_separable(&b, &a, &WarpOptions::default()).is_err());
}
