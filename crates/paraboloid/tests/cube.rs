//! Property tests of the cube shadow maps, driven by the shared generators of
//! `shadowmap_testgen::cube`.

use proptest::prelude::*;
use shadowmap_testgen::cube::{check_cube, cube_input, cube_input_raw};
use shadowmap_testgen::strategy;

proptest! {
    #![proptest_config(shadowmap_testgen::proptest_config())]

    /// Valid input: coverage of the visible receivers by the kept faces, casters not
    /// clipped, finite non-singular matrices (see `check_cube`).
    #[test]
    fn cube_covers_the_visible_receivers(input in strategy(cube_input)) {
        check_cube(&input, true).map_err(TestCaseError::fail)?;
    }

    /// Any input: a typed error or a map that keeps the contract.
    #[test]
    fn cube_never_panics_or_returns_nan(input in strategy(cube_input_raw)) {
        check_cube(&input, false).map_err(TestCaseError::fail)?;
    }
}

/// The generator exercises the checks: most valid inputs fit a map with visible
/// receivers to check, some with the light inside the view and a caster's bounds,
/// both face counts below and at six occur, and turned cubes too.
#[test]
fn the_generator_reaches_the_interesting_cases() {
    use shadowmap_frustum::Light;
    use shadowmap_paraboloid::CubeMap;
    use shadowmap_testgen::arbitrary::Unstructured;
    use shadowmap_testgen::cube::visible_points;

    let (mut fitted, mut inside_caster, mut all_six, mut fewer, mut turned) = (0, 0, 0, 0, 0);
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    for _ in 0..400 {
        let bytes = shadowmap_testgen::xorshift_bytes(&mut state, 256);
        let Ok(input) = cube_input(&mut Unstructured::new(&bytes)) else {
            continue;
        };
        let fit = CubeMap::fit(
            &input.light,
            &input.camera,
            input.bounds,
            &input.scene,
            &input.options,
        );
        let (Ok(cube), Light::Point { position, .. }) = (fit, input.light) else {
            continue;
        };
        if visible_points(&input).is_empty() {
            continue;
        }
        fitted += 1;
        inside_caster += usize::from(input.scene.casters.contains(position));
        all_six += usize::from(cube.layers() == 6);
        fewer += usize::from(cube.layers() < 6);
        turned += usize::from(cube.orientation() != glam::Quat::IDENTITY);
    }
    assert!(fitted >= 200, "only {fitted} of 400 inputs fitted");
    assert!(
        inside_caster >= 20 && all_six >= 10 && fewer >= 50 && turned >= 40,
        "{inside_caster} {all_six} {fewer} {turned}"
    );
}
