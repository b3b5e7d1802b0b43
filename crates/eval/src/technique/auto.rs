//! `auto`: the candidate technique with the lowest predicted aliasing error, fitted
//! by the umbrella crate (`shadowmap::fit` with `shadowmap::Technique::Auto`).

use super::TechniqueKind;

/// The candidates of [`TechniqueKind::Auto`], from the most to the least preferred
/// when predictions tie: the kinds of `shadowmap::auto_candidates`, in its order.
/// The report fits each frame on its own, so the selector's hysteresis (which a
/// renderer keeps across frames) does not apply here.
pub const AUTO_CANDIDATES: [TechniqueKind; shadowmap::AUTO_CANDIDATE_COUNT] = [
    TechniqueKind::UniformFocused,
    TechniqueKind::Lispsm,
    TechniqueKind::Tsm,
    TechniqueKind::Xpsm,
    TechniqueKind::TightCascades,
    TechniqueKind::WarpedCascades,
    TechniqueKind::StableCascades,
];
