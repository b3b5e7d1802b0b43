//! [`TechniqueSelector`]: a choice among candidates by predicted error, kept across
//! frames with hysteresis.

/// Chooses among candidate techniques by predicted error, with hysteresis: the current
/// choice is kept until another candidate's prediction is lower by more than
/// [`switch_margin`](Self::switch_margin) (relative), so the choice does not flip
/// every frame when two candidates are close. Keep one per light across frames.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TechniqueSelector {
    /// The index chosen last, if any.
    pub current: Option<usize>,
    /// Relative improvement needed to switch. Default 0.1.
    pub switch_margin: f64,
}

impl Default for TechniqueSelector {
    fn default() -> Self {
        Self::new()
    }
}

impl TechniqueSelector {
    /// No choice yet; a 10% margin.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            current: None,
            switch_margin: 0.1,
        }
    }

    /// Sets [`switch_margin`](Self::switch_margin) (negative or NaN: 0).
    #[must_use]
    pub const fn with_switch_margin(mut self, margin: f64) -> Self {
        self.switch_margin = margin;
        self
    }

    /// Picks the index of the lowest prediction (`None` entries are candidates that
    /// could not be fitted or predicted), keeping the current choice unless the best
    /// beats it by the margin. `None` when no candidate has a prediction. Ties go to
    /// the lower index, so list candidates from the most to the least preferred.
    pub fn choose(&mut self, predictions: &[Option<f64>]) -> Option<usize> {
        let best = predictions
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.filter(|v| v.is_finite()).map(|v| (i, v)))
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
        let margin = if self.switch_margin > 0.0 {
            self.switch_margin
        } else {
            0.0
        };
        let keep = self
            .current
            .and_then(|i| predictions.get(i).copied().flatten().map(|v| (i, v)))
            .filter(|(_, v)| v.is_finite() && best.1 >= *v * (1.0 - margin));
        let (index, _) = keep.unwrap_or(best);
        self.current = Some(index);
        Some(index)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_selector_switches_only_past_its_margin() {
        let mut s = TechniqueSelector::new();
        assert_eq!(s.choose(&[None, None]), None);
        assert_eq!(s.choose(&[Some(2.0), Some(1.0)]), Some(1));
        // 0 is now 5% better than 1: not enough to switch.
        assert_eq!(s.choose(&[Some(0.95), Some(1.0)]), Some(1));
        // 20% better: switch.
        assert_eq!(s.choose(&[Some(0.8), Some(1.0)]), Some(0));
        // The current one disappears: take the best.
        assert_eq!(s.choose(&[None, Some(3.0), Some(2.0)]), Some(2));
        // NaN predictions never win; ties go to the lower index.
        let mut fresh = TechniqueSelector::new().with_switch_margin(f64::NAN);
        assert_eq!(
            fresh.choose(&[Some(f64::NAN), Some(1.0), Some(1.0)]),
            Some(1)
        );
    }
}
