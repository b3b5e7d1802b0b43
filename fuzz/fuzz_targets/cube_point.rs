#![no_main]
//! The point-light techniques over the cube map's faces (`shadowmap::fit` of
//! `Technique::CubeMaps` sized by need, `Technique::CubeRtw` and
//! `Technique::TiledCube`) on any cube input with eye samples: a typed error, or
//! every sample the cube's windows store mapped into the technique's own layer,
//! inside it, at the cube's depth, within the budget
//! (`shadowmap_testgen::point_rtw::{check_cube_samples, check_tiled_samples}`).

use libfuzzer_sys::fuzz_target;
use shadowmap::paraboloid::{FaceSizes, TileOptions};
use shadowmap::{FitInput, RtwPlan, Technique, fit};
use shadowmap_testgen::arbitrary::Unstructured;
use shadowmap_testgen::point_rtw::{check_cube_samples, check_tiled_samples, cube_samples_case};

fuzz_target!(|data: &[u8]| {
    let Ok(case) = cube_samples_case(&mut Unstructured::new(data)) else {
        return;
    };
    let c = &case.cube;
    let budget = 1 << 16;
    let input = FitInput::new(&c.camera, &c.light, c.scene, budget)
        .with_eye_samples(&case.samples)
        .with_depth_bounds(c.bounds)
        .with_pixels_per_radian(case.pixels_per_radian);
    let techniques = [
        Technique::CubeMaps(c.options.with_sizes(FaceSizes::ByNeed)),
        Technique::CubeRtw {
            cube: c.options,
            rtw: RtwPlan::default().with_importance_side(32),
        },
        Technique::TiledCube {
            cube: c.options,
            tiles: TileOptions::default(),
        },
    ];
    for technique in &techniques {
        let Ok(shadow) = fit(technique, &input) else {
            continue;
        };
        let checked = match (shadow.tiled_cube(), shadow.cube()) {
            (Some(tiled), _) => check_tiled_samples(&case, tiled, &shadow, budget),
            (None, Some(cube)) => check_cube_samples(&case, cube, &shadow, budget),
            (None, None) => Err("a cube technique without a cube".into()),
        };
        if let Err(e) = checked {
            panic!("{}: {e}: {case:?}", technique.name());
        }
    }
});
