//! The robustness sweep's verdict: every technique against its light's baseline on
//! every random configuration, counted as wins, ties and losses.
//!
//! The measure is the p95 of the aliasing error `m` over the measured pixels. On a
//! case, a technique *wins* when its p95 is below the baseline's divided by
//! [`TIE_BAND`], *loses* when it is above the baseline's times [`TIE_BAND`], and ties
//! otherwise; a technique or baseline without a p95 (n/a, nothing measured) counts
//! as unmeasured. Each technique meets the baseline of its family
//! ([`TechniqueKind::baseline`]): the uniform fit for the directional techniques,
//! the spot fit for the spot warps and RTW over it, DPSM for the paraboloid maps
//! (IPSM, RTW over its paraboloid), the focused cube maps for RTW over their faces,
//! and the engines' cube maps (unfocused, equal faces) for the focused ones. The
//! baselines themselves (uniform, spot, DPSM, the engines' cube maps) and the RTW
//! oracle (a bound, not a technique) are not counted.

use std::fmt::Write as _;

use crate::technique::TechniqueKind;

use super::{ConfigSummary, Row};

/// A loss is a p95 `m` more than this factor above the baseline's; a win one more
/// than this factor below.
pub const TIE_BAND: f64 = 1.1;

/// The case where a technique fared worst against its baseline.
#[derive(Clone, Debug, PartialEq)]
pub struct WorstCase {
    /// The sweep case (configuration name).
    pub config: String,
    /// Its camera and light, in words.
    pub description: String,
    /// The technique's p95 `m`.
    pub p95: f64,
    /// The baseline it was measured against ([`TechniqueKind::baseline`]).
    pub baseline: TechniqueKind,
    /// The baseline's p95 `m`.
    pub baseline_p95: f64,
}

impl WorstCase {
    /// `p95 / baseline_p95`: above [`TIE_BAND`] is a loss.
    #[must_use]
    pub fn ratio(&self) -> f64 {
        self.p95 / self.baseline_p95
    }
}

/// One technique's record over the sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepTally {
    /// The technique.
    pub technique: TechniqueKind,
    /// Cases where it beat its baseline by more than [`TIE_BAND`].
    pub wins: usize,
    /// Cases within [`TIE_BAND`] of its baseline.
    pub ties: usize,
    /// Cases where it lost to its baseline by more than [`TIE_BAND`].
    pub losses: usize,
    /// Cases without a p95 for it or its baseline.
    pub unmeasured: usize,
    /// The case with the largest ratio to the baseline.
    pub worst: Option<WorstCase>,
}

/// The sweep's verdict, one tally per technique that has a baseline to meet.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSummary {
    /// Cases in the sweep.
    pub cases: usize,
    /// Per technique, in [`TechniqueKind::ALL`] order.
    pub tallies: Vec<SweepTally>,
}

/// The baseline among `techniques` (those of one light) that the best of them is
/// shown against: the uniform fit for a directional light, the spot's own fit for a
/// spot light (or the uniform fit where it applies), the focused cube maps for a
/// point light (DPSM where they are not among the techniques).
#[must_use]
pub fn baseline_of(techniques: &[TechniqueKind]) -> Option<TechniqueKind> {
    [
        TechniqueKind::UniformFocused,
        TechniqueKind::SpotFit,
        TechniqueKind::Cube,
        TechniqueKind::Dpsm,
    ]
    .into_iter()
    .find(|k| techniques.contains(k))
}

fn p95(row: &Row) -> Option<f64> {
    row.outcome
        .as_ref()
        .ok()
        .and_then(|r| r.aliasing.m)
        .map(|m| m.p95)
        .filter(|v| v.is_finite() && *v > 0.0)
}

/// Counts every technique of every case in `cases` against its baseline.
/// The baselines are looked up among `rows` and `references` (the engines' cube maps,
/// the bar of the focused ones).
pub(super) fn summarize(cases: &[ConfigSummary], rows: &[Row], references: &[Row]) -> SweepSummary {
    let mut tallies: Vec<SweepTally> = Vec::new();
    for case in cases {
        let case_rows: Vec<&Row> = rows.iter().filter(|r| r.config == case.name).collect();
        for row in &case_rows {
            let Some(baseline) = row.technique.baseline() else {
                continue;
            };
            let base = case_rows
                .iter()
                .copied()
                .chain(references.iter().filter(|r| r.config == case.name))
                .find(|r| r.technique == baseline)
                .and_then(p95);
            let tally = match tallies
                .iter_mut()
                .position(|t| t.technique == row.technique)
            {
                Some(i) => &mut tallies[i],
                None => {
                    tallies.push(SweepTally {
                        technique: row.technique,
                        wins: 0,
                        ties: 0,
                        losses: 0,
                        unmeasured: 0,
                        worst: None,
                    });
                    tallies.last_mut().expect("just pushed")
                }
            };
            let (Some(p), Some(b)) = (p95(row), base) else {
                tally.unmeasured += 1;
                continue;
            };
            let ratio = p / b;
            if ratio > TIE_BAND {
                tally.losses += 1;
            } else if ratio < 1.0 / TIE_BAND {
                tally.wins += 1;
            } else {
                tally.ties += 1;
            }
            if tally.worst.as_ref().is_none_or(|w| ratio > w.ratio()) {
                tally.worst = Some(WorstCase {
                    config: case.name.clone(),
                    description: case.description.clone(),
                    p95: p,
                    baseline,
                    baseline_p95: b,
                });
            }
        }
    }
    tallies.sort_by_key(|t| TechniqueKind::ALL.iter().position(|k| *k == t.technique));
    SweepSummary {
        cases: cases.len(),
        tallies,
    }
}

/// The sweep's table (plain text when `markdown` is false), then the worst case of
/// each technique.
pub(super) fn sweep_table(summary: &SweepSummary, markdown: bool) -> String {
    let mut s = String::new();
    let header = [
        "technique",
        "wins",
        "ties",
        "losses",
        "n/a",
        "worst p95 m / baseline",
        "worst case",
    ];
    if markdown {
        let _ = writeln!(s, "| {} |", header.join(" | "));
        let _ = writeln!(s, "|---|---|---|---|---|---|---|");
    } else {
        let _ = writeln!(
            s,
            "{:<16} {:>5} {:>5} {:>6} {:>5} {:>22}  {}",
            header[0], header[1], header[2], header[3], header[4], header[5], header[6]
        );
    }
    for t in &summary.tallies {
        let (ratio, case) = t.worst.as_ref().map_or_else(
            || ("-".to_string(), "-".to_string()),
            |w| {
                (
                    format!(
                        "{:.2} ({:.2} / {} {:.2})",
                        w.ratio(),
                        w.p95,
                        w.baseline.name(),
                        w.baseline_p95
                    ),
                    w.config.clone(),
                )
            },
        );
        let name = t.technique.name();
        if markdown {
            let _ = writeln!(
                s,
                "| {name} | {} | {} | {} | {} | {ratio} | {case} |",
                t.wins, t.ties, t.losses, t.unmeasured
            );
        } else {
            let _ = writeln!(
                s,
                "{name:<16} {:>5} {:>5} {:>6} {:>5} {ratio:>22}  {case}",
                t.wins, t.ties, t.losses, t.unmeasured
            );
        }
    }
    s.push('\n');
    for t in &summary.tallies {
        if let Some(w) = &t.worst {
            let bullet = if markdown { "- " } else { "" };
            let _ = writeln!(
                s,
                "{bullet}{}: worst case {}: {}",
                t.technique.name(),
                w.config,
                w.description
            );
        }
    }
    s
}
