//! `auto`: the candidate technique with the lowest predicted aliasing error, fitted
//! by the umbrella crate (`shadowmap::fit` with `shadowmap::Technique::Auto`).

use super::TechniqueKind;

/// The candidates of [`TechniqueKind::Auto`], from the most to the least preferred
/// when predictions tie: the kinds of `shadowmap::auto_candidates`, in its order.
/// The report threads one `shadowmap::FitState` through a camera path, as a
/// renderer would, so the selector's hysteresis applies from the second frame on.
pub const AUTO_CANDIDATES: [TechniqueKind; shadowmap::AUTO_CANDIDATE_COUNT] = [
    TechniqueKind::UniformFocused,
    TechniqueKind::Lispsm,
    TechniqueKind::Tsm,
    TechniqueKind::Xpsm,
    TechniqueKind::TightCascades,
    TechniqueKind::WarpedCascades,
    TechniqueKind::StableCascades,
];
