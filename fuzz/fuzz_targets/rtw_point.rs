#![no_main]
//! RTW over the IPSM paraboloid (`shadowmap::fit` of `Technique::PointRtw`) on any
//! plan input: a typed error, or every sample the paraboloid stores mapped into the
//! same layer with the same depth (`shadowmap_testgen::point_rtw::check_point_rtw`).

use libfuzzer_sys::fuzz_target;
use shadowmap::{FitInput, Fitted, RtwPlan, Technique, fit};
use shadowmap_testgen::arbitrary::Unstructured;
use shadowmap_testgen::point_rtw::{check_point_rtw, point_rtw_case};

fuzz_target!(|data: &[u8]| {
    let Ok(case) = point_rtw_case(&mut Unstructured::new(data)) else {
        return;
    };
    let unit = shadowmap::frustum::Aabb::new(glam::Vec3::splat(-1.0), glam::Vec3::ONE);
    let input = FitInput::new(
        &case.plan.camera,
        &case.plan.light,
        shadowmap::frustum::SceneBounds::whole(unit),
        1 << 16,
    )
    .with_eye_samples(&case.samples)
    .with_depth_bounds(case.plan.bounds);
    let technique = Technique::PointRtw {
        ipsm: case.plan.options,
        rtw: RtwPlan::default().with_importance_side(32),
    };
    if let Ok(shadow) = fit(&technique, &input) {
        if let Fitted::PointRtw { plan, .. } = shadow.fitted() {
            check_point_rtw(&case, &plan.map, &shadow);
        }
    }
});
