//! `auto`: the candidate technique with the lowest predicted aliasing error.

use shadowmap_frustum::{PredictOptions, TechniqueSelector, predict_error};

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
    /// error with the receivers' box standing in for the surfaces, and keeps the
    /// lowest. The report fits each frame on its own, so the selector's hysteresis
    /// (which a renderer keeps across frames) does not apply here.
    pub(super) fn build_auto(
        frame: &FrameContext<'_>,
        options: &TechniqueOptions,
    ) -> Result<Self, EvalError> {
        let mut fitted: Vec<Option<Self>> = Vec::with_capacity(AUTO_CANDIDATES.len());
        let mut predictions = Vec::with_capacity(AUTO_CANDIDATES.len());
        for kind in AUTO_CANDIDATES {
            let technique = Self::build(kind, frame, options).ok();
            let prediction = technique.as_ref().and_then(|t| {
                predict_error(
                    frame.camera,
                    &frame.scene.receivers,
                    t,
                    t.side,
                    &PredictOptions::default(),
                )
                .ok()
                .flatten()
                .map(|p| p.percentile)
            });
            fitted.push(technique);
            predictions.push(prediction);
        }
        let index = TechniqueSelector::new()
            .choose(&predictions)
            .ok_or_else(|| fail(TechniqueKind::Auto, &"no candidate could be fitted"))?;
        let chosen = fitted[index]
            .take()
            .ok_or_else(|| fail(TechniqueKind::Auto, &"no candidate could be fitted"))?;
        Ok(Self {
            kind: TechniqueKind::Auto,
            ..chosen
        })
    }
}
