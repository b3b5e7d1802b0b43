//! Property tests of the spot warps (LiSPSM and TSM in the spot light's
//! post-projective space), driven by `shadowmap_testgen::spot_warp`.

use proptest::prelude::*;
use shadowmap_testgen::spot_warp::{check_spot_warp, spot_warp_case};
use shadowmap_testgen::strategy;

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// What the spot fit stores the warp stores, inside its map, each ray on one
    /// texel with depth growing away from the light; matrices finite and invertible.
    #[test]
    fn spot_warps_keep_what_the_spot_fit_stores(case in strategy(spot_warp_case)) {
        check_spot_warp(&case).map_err(TestCaseError::fail)?;
    }
}

/// A spot 7 from the origin with receivers 1.3 mm from it (the camera at the
/// light): LiSPSM's formula asks for a warp f32 cannot hold there (ray ends 2e-4
/// apart in the map, the depth along a ray reversed); the strength is limited to
/// what it resolves, and the warp keeps what the spot fit stores.
#[test]
fn a_warp_f32_cannot_hold_near_the_light_is_weakened() {
    use glam::{Mat4, Vec3, Vec4};
    use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds};
    use shadowmap_testgen::spot_warp::SpotWarpCase;
    use shadowmap_warp::{SpotWarpKind, SpotWarpOptions, spot_warp};
    let position = Vec3::new(-3.1845953, -4.4273043, -3.9811594);
    let receivers = Aabb::new(
        Vec3::new(-3.191339, -4.4266453, -4.048091),
        Vec3::new(-3.138978, -4.3395076, -3.981229),
    );
    let case = SpotWarpCase {
        light: Light::Spot {
            position,
            direction: Vec3::new(0.2509941, 0.8505368, -0.462157),
            half_angle: 1.2852015,
            range: 0.060552612,
        },
        camera: Camera {
            world_from_view: Mat4::from_cols(
                Vec4::new(-0.9590938, 0.28308836, 0.0, 0.0),
                Vec4::new(-0.13082929, -0.4432452, -0.8868018, 0.0),
                Vec4::new(-0.25104326, -0.8505261, 0.46214998, 0.0),
                Vec4::new(-3.1845973, -4.4273043, -3.9811594, 1.0),
            ),
            projection: Projection::perspective(0.8516727, 0.6407938, 0.0011615366, 0.07743174),
            reversed_z: false,
        },
        bounds: None,
        scene: SceneBounds::new(receivers, receivers),
        options: SpotWarpOptions::default()
            .with_kind(SpotWarpKind::Lispsm)
            .with_focus(0.01),
    };
    let checked = check_spot_warp(&case).unwrap();
    assert!(checked > 0);
    let fit = spot_warp(
        &case.light,
        &case.camera,
        case.bounds,
        &case.scene,
        &case.options,
    )
    .unwrap();
    assert!(fit.strength < 100.0, "strength {}", fit.strength);
}

/// The fuzzed scene of the next two tests: a camera at the origin (reversed-Z) over
/// a receiver slab, TSM's strongest focus, a wide spot at `position` looking along
/// `direction`.
fn fuzzed_slab_case(
    position: glam::Vec3,
    direction: glam::Vec3,
    range: f32,
) -> shadowmap_testgen::spot_warp::SpotWarpCase {
    use glam::{Mat4, Vec3};
    use shadowmap_frustum::{Aabb, Camera, Light, Projection, SceneBounds};
    use shadowmap_warp::{SpotWarpKind, SpotWarpOptions};
    let receivers = Aabb::new(
        Vec3::new(-81.94537, -54.63025, -100.0),
        Vec3::new(81.94537, -53.537643, -0.1),
    );
    let casters = Aabb::new(
        Vec3::new(-81.94537, -54.63025, -100.0),
        Vec3::new(81.94537, 54.63025, -0.1),
    );
    shadowmap_testgen::spot_warp::SpotWarpCase {
        light: Light::Spot {
            position,
            direction,
            half_angle: 1.4090196,
            range,
        },
        camera: Camera {
            world_from_view: Mat4::IDENTITY,
            projection: Projection::perspective(1.0, 1.5, 0.1, 100.0),
            reversed_z: true,
        },
        bounds: None,
        scene: SceneBounds::new(receivers, casters),
        options: SpotWarpOptions::default()
            .with_kind(SpotWarpKind::Tsm)
            .with_focus(0.01),
    }
}

/// Found by fuzzing (`fuzz/fuzz_targets/warp_spot.rs`): a wide spot 150 from the
/// origin over a receiver slab 185 away, TSM's strongest focus warping along the
/// window's narrow side. The lookup matrix (`uv_from_world`, `clip_from_world`'s
/// rows summed in `f32`) missed the light's position by 0.05, which put a ray's
/// ends 1.5e-4 apart at the map's edge; the strength is limited by both matrices.
#[test]
fn a_warp_whose_lookup_matrix_f32_cannot_hold_is_weakened() {
    let case = fuzzed_slab_case(glam::Vec3::splat(87.45098), glam::Vec3::NEG_Z, 205.7327);
    assert!(check_spot_warp(&case).unwrap() > 0);
}

/// Found by fuzzing the same way: TSM warping along a spot window 0.02 rad wide,
/// the receivers 100 from the light. Depth is `z / w` with `z` nearly `w` (the
/// warp compresses it toward the far value), so the rounding of the two rows,
/// each as large as the warp, stored a depth 1.8e-4 past the far plane; the
/// strength is limited by every stored row's rounding per unit of distance from
/// the light, not only by what is left at the light.
#[test]
fn a_warp_whose_depth_f32_cannot_hold_is_weakened() {
    let direction = glam::Vec3::new(-0.00015511537, -0.99999607, -0.0027950564);
    let case = fuzzed_slab_case(glam::Vec3::splat(48.235294), direction, 205.73256);
    assert!(check_spot_warp(&case).unwrap() > 0);
}

/// The generator reaches fitted warps with points to check, warped and not.
#[test]
fn the_generator_reaches_warped_fits() {
    use shadowmap_testgen::arbitrary::Unstructured;
    use shadowmap_warp::spot_warp;
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let (mut checked, mut warped) = (0, 0);
    for _ in 0..400 {
        let bytes = shadowmap_testgen::xorshift_bytes(&mut state, 256);
        let Ok(case) = spot_warp_case(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        checked += usize::from(check_spot_warp(&case).unwrap() > 0);
        let fit = spot_warp(
            &case.light,
            &case.camera,
            case.bounds,
            &case.scene,
            &case.options,
        );
        warped += usize::from(fit.is_ok_and(|w| w.strength > 0.0));
    }
    assert!(
        checked > 50 && warped > 10,
        "{checked} checked, {warped} warped"
    );
}

/// The data feature: options and fits round-trip, a focus outside (0, 1) is refused.
#[cfg(feature = "serde")]
#[test]
fn spot_warps_round_trip() {
    use shadowmap_testgen::arbitrary::Unstructured;
    use shadowmap_testgen::serde_check::{rejects_with, round_trip};
    use shadowmap_warp::{SpotWarpKind, SpotWarpOptions, WarpError, spot_warp};
    for kind in [SpotWarpKind::Lispsm, SpotWarpKind::Tsm] {
        round_trip(&SpotWarpOptions::default().with_kind(kind).with_focus(0.3));
    }
    rejects_with::<SpotWarpOptions>(r#"{"focus": 1.0}"#, WarpError::InvalidOption);
    let mut fitted = 0;
    for seed in 0..64u8 {
        let bytes: Vec<u8> = (0..256u32)
            .map(|i| (i as u8).wrapping_mul(31) ^ seed)
            .collect();
        let Ok(case) = spot_warp_case(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        if let Ok(w) = spot_warp(
            &case.light,
            &case.camera,
            case.bounds,
            &case.scene,
            &case.options,
        ) {
            round_trip(&w);
            fitted += 1;
        }
    }
    assert!(fitted > 0);
}
