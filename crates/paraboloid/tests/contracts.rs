//! The fuzz targets' contracts, run as property tests on the same generators.

use proptest::prelude::*;
use shadowmap_testgen::paraboloid::{
    check_cone, check_map, check_plan, check_subdivide, cone_directions_raw, map_input_raw,
    plan_input, plan_input_raw, subdivide_input, subdivide_input_raw,
};
use shadowmap_testgen::strategy;

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// `IpsmPlan::new` on anything: a typed error or a finite, covering plan.
    #[test]
    fn plan_contract(input in strategy(plan_input_raw)) {
        prop_assert_eq!(check_plan(&input), Ok(()));
    }

    /// On valid input the plan always succeeds.
    #[test]
    fn plan_valid_input_is_accepted(input in strategy(plan_input)) {
        let plan = shadowmap_paraboloid::IpsmPlan::new(&input.light, &input.camera, input.bounds, &input.options);
        prop_assert!(plan.is_ok(), "{:?}", plan);
        prop_assert_eq!(check_plan(&input), Ok(()));
    }

    /// Both cone fits on anything.
    #[test]
    fn cone_contract(dirs in strategy(cone_directions_raw)) {
        prop_assert_eq!(check_cone(&dirs), Ok(()));
    }

    /// Map builders and lookups on anything.
    #[test]
    fn map_contract(input in strategy(map_input_raw)) {
        prop_assert_eq!(check_map(&input), Ok(()));
    }

    /// Subdivision on anything.
    #[test]
    fn subdivide_contract(input in strategy(subdivide_input_raw)) {
        prop_assert_eq!(check_subdivide(&input), Ok(()));
    }

    /// Subdivision on valid input always succeeds.
    #[test]
    fn subdivide_valid_input_is_accepted(input in strategy(subdivide_input)) {
        let map = shadowmap_testgen::paraboloid::build_map(&input.map).unwrap();
        let r = shadowmap_paraboloid::subdivide_triangle(&map, input.side, input.triangle, &input.options, |_| {});
        prop_assert!(r.is_ok(), "{:?}", r);
        prop_assert_eq!(check_subdivide(&input), Ok(()));
    }
}

/// Inputs the fuzz targets found (kept as regressions of the checks).
mod fuzz_regressions {
    use glam::Vec3;
    use shadowmap_paraboloid::{MapOptions, Side, SubdivisionOptions};
    use shadowmap_testgen::paraboloid::{MapInput, SubdivideInput, check_map, check_subdivide};

    /// A huge depth range: the round trip error must be measured without `f32` overflow.
    #[test]
    fn huge_depth_range_round_trip() {
        let input = MapInput {
            position: Vec3::ZERO,
            axis: Vec3::X,
            half_angle: None,
            near: 1.622_840_5e32,
            far: 3.111_560_2e32,
            options: MapOptions::default().with_up_hint(Vec3::NEG_X),
            points: vec![Vec3::new(-0.001_507_971, 0.0, 0.0)],
        };
        assert_eq!(check_map(&input), Ok(()));
    }

    /// A tiny triangle straight behind the front paraboloid (near its pole).
    #[test]
    fn triangle_at_the_front_pole() {
        let map = MapInput {
            position: Vec3::new(4.369_102_7e-26, -2.176_758_3e-9, -10.0),
            axis: Vec3::NEG_Z,
            half_angle: None,
            near: 0.002_942_727_2,
            far: 0.009_713_292,
            options: MapOptions::default()
                .with_up_hint(Vec3::new(0.438_810_44, 0.169_996_07, -0.882_352_95))
                .with_reversed_z(true),
            points: vec![],
        };
        let input = SubdivideInput {
            map,
            side: Side::Front,
            triangle: [
                Vec3::new(0.000_619_568_5, 0.000_240_022_13, -0.001_245_818_3),
                Vec3::new(0.000_617_164_8, 0.000_239_152_07, -0.001_241_026_3),
                Vec3::new(0.008_943_311, 0.0, 0.0),
            ],
            options: SubdivisionOptions::default()
                .with_resolution(836)
                .with_tolerance_texels(0.269_372_73)
                .with_max_segments(3),
        };
        assert_eq!(check_subdivide(&input), Ok(()));
    }
}
