//! The report's text: the deterministic `metrics.csv`, the summary table that
//! `compare` prints and the Markdown report.

use std::fmt::Write as _;

use crate::metrics::Summary;
use crate::technique::TechniqueKind;

use super::sweep::{SweepSummary, TIE_BAND, sweep_table};
use super::{ConfigSummary, Report, Row, Settings};

fn sci(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.6e}"),
        _ => String::new(),
    }
}

/// The CSV of a report's technique rows (see the module docs for its guarantees).
#[must_use]
pub fn metrics_csv(report: &Report) -> String {
    rows_csv(report, &report.rows)
}

/// The CSV of a report's reference rows ([`TechniqueKind::is_reference`]), in the
/// columns of [`metrics_csv`].
#[must_use]
pub fn references_csv(report: &Report) -> String {
    rows_csv(report, &report.references)
}

fn rows_csv(report: &Report, rows: &[Row]) -> String {
    let mut s = String::from(
        "config,technique,status,layers,layer_side,texels,visible_pixels,measured_pixels,\
         m_mean,m_median,m_p95,m_max,m_persp_median,m_persp_p95,m_persp_max,\
         storage_factor,storage_factor_persp,storage_factor_sep_persp,used_texel_fraction,\
         misclassification,phase_jitter,flip_rate,log_bound\n",
    );
    for row in rows {
        let bound = report
            .configs
            .iter()
            .chain(&report.sweep_configs)
            .find(|c| c.name == row.config)
            .and_then(|c| c.log_bound);
        match &row.outcome {
            Ok(r) => {
                let a = &r.aliasing;
                let m = |f: fn(&Summary) -> f64| a.m.as_ref().map(f);
                let mp = |f: fn(&Summary) -> f64| a.m_perspective.as_ref().map(f);
                let _ = writeln!(
                    s,
                    "{},{},ok,{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                    row.config,
                    row.technique.name(),
                    r.layers,
                    r.layer_side,
                    r.texels,
                    a.visible_pixels,
                    a.measured_pixels,
                    sci(m(|s| s.mean)),
                    sci(m(|s| s.median)),
                    sci(m(|s| s.p95)),
                    sci(m(|s| s.max)),
                    sci(mp(|s| s.median)),
                    sci(mp(|s| s.p95)),
                    sci(mp(|s| s.max)),
                    sci(Some(a.storage_factor)),
                    sci(Some(a.storage_factor_perspective)),
                    sci(Some(a.separable_storage_factor_perspective)),
                    sci(Some(a.used_texel_fraction)),
                    sci(r.misclassification),
                    sci(r.phase_jitter),
                    sci(r.flip_rate),
                    sci(bound),
                );
            }
            Err(reason) => {
                let _ = writeln!(
                    s,
                    "{},{},\"n/a ({})\",,,,,,,,,,,,,,,,,,,,{}",
                    row.config,
                    row.technique.name(),
                    reason.replace('"', "'"),
                    sci(bound)
                );
            }
        }
    }
    s
}

pub(super) fn short(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => {
            if v != 0.0 && (v.abs() >= 1e4 || v.abs() < 1e-2) {
                format!("{v:.2e}")
            } else {
                format!("{v:.2}")
            }
        }
        _ => "-".into(),
    }
}

pub(super) fn percent(x: Option<f64>) -> String {
    x.filter(|v| v.is_finite())
        .map_or_else(|| "-".into(), |v| format!("{:.2}%", v * 100.0))
}

/// The technique of `config` with the lowest p95 `m` (ties: the lower `S`), and
/// that p95; the RTW oracle is a bound, not a technique, and is not a candidate.
pub(super) fn best_technique(report: &Report, config: &str) -> Option<(TechniqueKind, f64)> {
    report
        .rows
        .iter()
        .filter(|r| r.config == config && r.technique != TechniqueKind::RtwOracle)
        .filter_map(|r| {
            let m = r.outcome.as_ref().ok()?;
            let p95 = m.aliasing.m?.p95;
            p95.is_finite()
                .then_some((r.technique, p95, m.aliasing.storage_factor))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.2.total_cmp(&b.2)))
        .map(|(t, p95, _)| (t, p95))
}

/// One line per measure of the summary table.
pub(super) const MEASURES: [&str; 3] = [
    "m    aliasing error: the largest extent of one shadow-map texel on the screen, in \
     pixels (1 = pixel-matched, above 1 undersampled; lower is better)",
    "p95  the 95th percentile of m over the visible, front-lit pixels (5% are worse)",
    "S    storage factor: texels per visible pixel x (max m)^2, the texels needed so that \
     no texel is larger than a pixel",
];

/// The summary table printed by `compare`: what `m`, `p95` and `S` mean, then per
/// configuration each technique's median, p95 and max `m`, `S` and
/// misclassification; the best technique of each configuration; then the sweep's
/// wins, ties and losses when there is one.
#[must_use]
pub fn summary_table(report: &Report) -> String {
    let mut s = String::new();
    for line in MEASURES {
        let _ = writeln!(s, "{line}");
    }
    s.push('\n');
    s.push_str(&configuration_table(report));
    s.push_str("\nbest (lowest p95 m) per configuration:\n");
    for c in &report.configs {
        match best_technique(report, &c.name) {
            Some((kind, p95)) => {
                let _ = writeln!(
                    s,
                    "  {:<14} {} (p95 m {})",
                    c.name,
                    kind.name(),
                    short(Some(p95))
                );
            }
            None => {
                let _ = writeln!(s, "  {:<14} - (no technique measured)", c.name);
            }
        }
    }
    if let Some(sweep) = &report.sweep {
        let _ = writeln!(
            s,
            "\nsweep: {} random cases, p95 m against its family's baseline (win below 1/{TIE_BAND}, \
             loss above {TIE_BAND} times)",
            sweep.cases
        );
        s.push_str(&sweep_table(sweep, false));
    }
    s
}

fn configuration_table(report: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<14} {:<16} {:>10} {:>10} {:>10} {:>10} {:>9}",
        "config", "technique", "median m", "p95 m", "max m", "S", "misclass"
    );
    let standard = |r: &&Row| report.configs.iter().any(|c| c.name == r.config);
    for row in report.rows.iter().filter(standard) {
        match &row.outcome {
            Ok(r) => {
                let m = r.aliasing.m;
                let _ = writeln!(
                    s,
                    "{:<14} {:<16} {:>10} {:>10} {:>10} {:>10} {:>9}",
                    row.config,
                    row.technique.name(),
                    short(m.map(|m| m.median)),
                    short(m.map(|m| m.p95)),
                    short(m.map(|m| m.max)),
                    short(Some(r.aliasing.storage_factor)),
                    percent(r.misclassification),
                );
            }
            Err(reason) => {
                let _ = writeln!(
                    s,
                    "{:<14} {:<16} n/a ({reason})",
                    row.config,
                    row.technique.name()
                );
            }
        }
    }
    s
}

pub(super) fn markdown(report: &Report) -> String {
    let mut s = markdown_header(report);
    for c in &report.configs {
        config_section(&mut s, report, c);
    }
    if let Some(sweep) = &report.sweep {
        sweep_section(&mut s, sweep);
    }
    s
}

/// The robustness sweep: what it is, and each technique's record.
fn sweep_section(s: &mut String, sweep: &SweepSummary) {
    let _ = writeln!(
        s,
        "## Robustness sweep
"
    );
    let _ = writeln!(
        s,
        "{} random camera and light configurations over the four scenes (directional, \
         spot and point lights in turn; `random_*` rows of `metrics.csv`), each at the \
         sweep's sizes (image {}×{}, {} texels, one frame). Every technique's p95 `m` \
         against its family's baseline (uniform fit for the directional techniques, the \
         spot fit for the spot techniques, DPSM for the paraboloid maps, the focused \
         cube maps for RTW over them, the engines' unfocused cube maps for the focused \
         ones): a win is more than {TIE_BAND}× lower, a loss more than \
         {TIE_BAND}× higher, a tie in between; n/a where either has no measure.\n",
        sweep.cases,
        Settings::sweep().width,
        Settings::sweep().height,
        Settings::sweep().texel_budget,
    );
    s.push_str(&sweep_table(sweep, true));
    s.push('\n');
}

/// The title, the settings and the legend of the columns and pictures.
fn markdown_header(report: &Report) -> String {
    let st = &report.settings;
    let mut s = String::new();
    let _ = writeln!(s, "# Shadow-map technique comparison\n");
    let _ = writeln!(
        s,
        "Image {}×{} pixels; texel budget {} texels per technique (all layers); camera \
         paths of {} frames; scene seed {}. Produced by \
         `cargo run --release -p shadowmap-eval --bin compare`. `index.html` beside \
         this file shows the same report with plots, labelled pictures and sortable \
         tables.\n",
        st.width, st.height, st.texel_budget, st.path_frames, report.seed
    );
    s.push_str(
        "Columns (definitions in `shadowmap_eval::metrics`): `m` is the aliasing \
         error per visible pixel (largest extent of a texel in pixels, 1 is ideal), \
         `m⊥` the perspective-only error (normal = bisector of eye and light), `S` the \
         storage factor `texels / visible pixels · max(m)²`, `S⊥` the same for `m⊥`, \
         `S_sep` Lloyd's separable storage factor of `m⊥`, `used` the fraction of texels \
         some visible pixel samples, `miss` the misclassification against ray-traced \
         visibility, `jitter` the mean sub-texel phase change of fixed world points per \
         frame, `flips` the fraction of shadow tests that change between frames.\n\n",
    );
    s.push_str(
        "Limits beside every table: pixel-matched `m = 1` (so `S = texels / visible \
         pixels` at best for a map that matches the screen), the logarithmic bound \
         `K ln(f/n)` on Lloyd's storage factor of separable parameterizations \
         (`K = 1 / (2 tan(fovY/2))`), and the RTW oracle row (RTW fed the exact \
         perspective-only density each texture axis requires, measured on the same \
         visible pixels; directional lights only).\n\n",
    );
    s.push_str(
        "Heatmaps: `m` on a logarithmic scale from 1 (dark blue) to 10 (yellow), \
         colormap viridis, red above 10, background grey, dark grey where `m` is not \
         measured (surface not front-lit, i.e. `n·l < 0.05`, or not covered by the map). \
         The true-normal `m`, `S` and `miss` are taken over front-lit pixels, `m⊥` over \
         every covered pixel. Scale: ![legend](legend.png)\n\n\
         Mask images: technique | ray traced | differences (red: lit but in shadow, \
         blue: shadowed but lit), over the pixels `miss` counts (front-lit); the \
         others are background grey.\n\n",
    );
    s
}

/// One configuration: its description, its table and its pictures.
/// The reference rows of configuration `config` in a sentence each: the reference's
/// p95 `m` and the technique that must meet it, with their ratio.
pub(super) fn reference_lines(report: &Report, config: &str) -> Vec<String> {
    let p95 = |row: &Row| row.outcome.as_ref().ok()?.aliasing.m.map(|m| m.p95);
    report
        .references
        .iter()
        .filter(|r| r.config == config)
        .map(|reference| {
            let bar = TechniqueKind::ALL
                .into_iter()
                .find(|k| k.baseline() == Some(reference.technique));
            let held = bar.and_then(|k| {
                let row = report
                    .rows
                    .iter()
                    .find(|r| r.config == config && r.technique == k)?;
                Some((k, p95(row)?))
            });
            let mut line = format!(
                "Reference, not a technique: {} (the engines' cube maps, full faces of \
                 one size), p95 m {}",
                reference.technique.name(),
                short(p95(reference))
            );
            if let (Some((k, v)), Some(r)) = (held, p95(reference)) {
                let _ = write!(line, "; {} {} ({:.2}x)", k.name(), short(Some(v)), v / r);
            }
            line.push('.');
            line
        })
        .collect()
}

fn config_section(s: &mut String, report: &Report, c: &ConfigSummary) {
    let _ = writeln!(s, "## {}\n", c.name);
    let _ = writeln!(
        s,
        "{} Scene `{}`, {} light, depth range {} – {}, {} visible pixels.\n",
        c.description, c.scene, c.light_kind, c.depth_range.0, c.depth_range.1, c.visible_pixels
    );
    let _ = writeln!(
        s,
        "Limits: m = 1; log bound K·ln(f/n) = {}.\n",
        short(c.log_bound)
    );
    s.push_str(
        "| technique | layers | median m | p95 m | max m | median m⊥ | S | S⊥ | S_sep | used | miss | jitter | flips |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for row in report.rows.iter().filter(|r| r.config == c.name) {
        match &row.outcome {
            Ok(r) => {
                let a = &r.aliasing;
                let _ = writeln!(
                    s,
                    "| {} | {}×{}² | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    row.technique.name(),
                    r.layers,
                    r.layer_side,
                    short(a.m.map(|m| m.median)),
                    short(a.m.map(|m| m.p95)),
                    short(a.m.map(|m| m.max)),
                    short(a.m_perspective.map(|m| m.median)),
                    short(Some(a.storage_factor)),
                    short(Some(a.storage_factor_perspective)),
                    short(Some(a.separable_storage_factor_perspective)),
                    percent(Some(a.used_texel_fraction)),
                    percent(r.misclassification),
                    short(r.phase_jitter),
                    percent(r.flip_rate),
                );
            }
            Err(reason) => {
                let _ = writeln!(
                    s,
                    "| {} | n/a ({}) |  |  |  |  |  |  |  |  |  |  |  |",
                    row.technique.name(),
                    reason.replace('|', "/")
                );
            }
        }
    }
    s.push('\n');
    for line in reference_lines(report, &c.name) {
        let _ = writeln!(s, "{line}\n");
    }
    for row in report
        .rows
        .iter()
        .filter(|r| r.config == c.name && r.outcome.is_ok())
    {
        let base = format!("{}_{}", c.name, row.technique.name());
        let _ = writeln!(
            s,
            "{}: ![m](heatmap_{base}.png) ![masks](mask_{base}.png)\n",
            row.technique.name()
        );
    }
}
