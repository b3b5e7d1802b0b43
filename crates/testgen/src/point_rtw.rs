//! Generators and checks for RTW over the IPSM paraboloid (fitted by the umbrella
//! crate's `fit`; the fuzz target and the property test pass the fitted mapping in).

use arbitrary::Unstructured;
use glam::DVec2;
use shadowmap_frustum::ShadowMapping;
use shadowmap_paraboloid::ParaboloidMap;
use shadowmap_rtw::EyeSample;

use crate::GenResult;
use crate::paraboloid::{PlanInput, plan_input};
use crate::rtw::frustum_samples;

/// Input of [`check_point_rtw`]: an IPSM plan input and eye samples in its camera's
/// frustum.
#[derive(Clone, Debug)]
pub struct PointRtwCase {
    /// Light (point or spot: the fit refuses a spot), camera, depth bounds, options.
    pub plan: PlanInput,
    /// What the eye sees.
    pub samples: Vec<EyeSample>,
}

/// A valid plan input (the light inside, next to or far from the truncated
/// frustum) with up to 64 samples in the camera's frustum.
pub fn point_rtw_case(u: &mut Unstructured<'_>) -> GenResult<PointRtwCase> {
    let plan = plan_input(u)?;
    let count = u.int_in_range(0usize..=64)?;
    let samples = frustum_samples(u, &plan.camera, count)?;
    Ok(PointRtwCase { plan, samples })
}

/// RTW over the paraboloid `map` (`rtw`, the fitted technique) on a case: every
/// sample the paraboloid stores (inside the cut) is mapped by RTW into the same
/// layer's `[0, 1]²` with the paraboloid's depth (coverage; finite). Returns how many
/// samples were checked.
pub fn check_point_rtw(
    case: &PointRtwCase,
    map: &ParaboloidMap,
    rtw: &impl ShadowMapping,
) -> usize {
    let inside = |uv: DVec2| uv.cmpge(DVec2::ZERO).all() && uv.cmple(DVec2::ONE).all();
    let mut checked = 0;
    for s in &case.samples {
        let p = s.position.as_dvec3();
        let Some(b) = map.map_point(p).filter(|b| inside(b.uv)) else {
            continue;
        };
        let r = rtw
            .map_point(p)
            .expect("stored by the paraboloid, mapped by RTW");
        assert!(r.uv.is_finite() && inside(r.uv), "{:?} left the map", r.uv);
        assert_eq!(
            (r.layer, r.depth),
            (b.layer, b.depth),
            "layer or depth changed"
        );
        checked += 1;
    }
    checked
}
