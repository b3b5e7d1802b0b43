//! `auto`: the candidate technique with the lowest predicted aliasing error.

use shadowmap_frustum::{PredictOptions, ShadowMapping, TechniqueSelector, predict_errors};

use super::{FrameContext, Technique, TechniqueKind, TechniqueOptions, fail};
use crate::EvalError;

/// The candidates of [`TechniqueKind::Auto`], from the most to the least preferred
/// when predictions tie.
pub const AUTO_CANDIDATES: [TechniqueKind; 7] = [
    TechniqueKind::UniformFocused,
    TechniqueKind::Lispsm,
    TechniqueKind::Tsm,
    TechniqueKind::Xpsm,
    TechniqueKind::TightCascades,
    TechniqueKind::WarpedCascades,
    TechniqueKind::StableCascades,
];

impl Technique {
    /// `auto`: fits every candidate, predicts each one's 95th-percentile aliasing
    /// error on the same rays (the receivers' box standing in for the surfaces; a ray
    /// counts where every candidate covers it), and keeps the lowest. The report fits
    /// each frame on its own, so the selector's hysteresis (which a renderer keeps
    /// across frames) does not apply here.
    pub(super) fn build_auto(
        frame: &FrameContext<'_>,
        options: &TechniqueOptions,
    ) -> Result<Self, EvalError> {
        let mut fitted: Vec<Self> = AUTO_CANDIDATES
            .iter()
            .filter_map(|kind| Self::build(*kind, frame, options).ok())
            .collect();
        let candidates: Vec<(&dyn ShadowMapping, u32)> = fitted
            .iter()
            .map(|t| (t as &dyn ShadowMapping, t.side))
            .collect();
        let mut predicted = vec![None; candidates.len()];
        predict_errors(
            frame.camera,
            &frame.scene.receivers,
            &candidates,
            &PredictOptions::default(),
            &mut predicted,
        )
        .map_err(|x| fail(TechniqueKind::Auto, &x))?;
        let predictions: Vec<Option<f64>> =
            predicted.iter().map(|p| p.map(|p| p.percentile)).collect();
        let index = TechniqueSelector::new()
            .choose(&predictions)
            .ok_or_else(|| fail(TechniqueKind::Auto, &"no candidate could be fitted"))?;
        let chosen = fitted.swap_remove(index);
        Ok(Self {
            kind: TechniqueKind::Auto,
            ..chosen
        })
    }
}
