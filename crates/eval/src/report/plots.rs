//! The report's plots, drawn with `plotters` into SVG (text is SVG text, set by the
//! viewer's sans-serif font, so drawing needs no font files):
//!
//! - per configuration, the aliasing error against view depth of every technique,
//!   with the pixel-matched limit `m = 1` and the logarithmic limit drawn as
//!   horizontal lines, in the manner of the error plots of Lloyd, Tuft, Yoon and
//!   Manocha (*Warping and Partitioning for Low Error Shadow Maps*, EGSR 2006);
//! - the robustness sweep's wins, ties and losses per technique;
//! - the numbered colour bar of the heatmaps.

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::technique::TechniqueKind;

use super::image::heat_colour;
use super::sweep::{SweepSummary, TIE_BAND};

/// Depth slices of a profile, logarithmically spaced from the near to the far plane.
const DEPTH_SLICES: usize = 24;
/// A slice with fewer measured pixels than this is left out of a profile.
const MIN_SLICE_PIXELS: usize = 4;

/// One technique's aliasing error along the view depth: `(depth, p95 m)` per depth
/// slice that holds enough measured pixels, in increasing depth.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct DepthProfile {
    pub(super) technique: TechniqueKind,
    pub(super) points: Vec<(f64, f64)>,
}

impl DepthProfile {
    /// The 95th percentile of `m` in each logarithmic depth slice of `near..far`;
    /// `samples` are `(view depth, m)` of the measured pixels.
    pub(super) fn new(
        technique: TechniqueKind,
        near: f64,
        far: f64,
        samples: impl Iterator<Item = (f64, f64)>,
    ) -> Self {
        let mut slices: Vec<Vec<f64>> = vec![Vec::new(); DEPTH_SLICES];
        let valid = near > 0.0 && far > near && near.is_finite() && far.is_finite();
        let span = if valid { (far / near).ln() } else { 1.0 };
        for (depth, m) in samples {
            if !(valid && depth > 0.0 && m.is_finite() && m > 0.0) {
                continue;
            }
            let t = (depth / near).ln() / span;
            let k = ((t * DEPTH_SLICES as f64).floor().max(0.0) as usize).min(DEPTH_SLICES - 1);
            slices[k].push(m);
        }
        let points = slices
            .iter_mut()
            .enumerate()
            .filter(|(_, s)| s.len() >= MIN_SLICE_PIXELS)
            .map(|(k, s)| {
                s.sort_by(f64::total_cmp);
                let p95 = s[((s.len() - 1) as f64 * 0.95).round() as usize];
                let centre = near * (span * (k as f64 + 0.5) / DEPTH_SLICES as f64).exp();
                (centre, p95)
            })
            .collect();
        Self { technique, points }
    }
}

/// What the depth plot of one configuration shows besides the profiles.
pub(super) struct DepthPlot<'a> {
    /// Configuration name (the title).
    pub(super) config: &'a str,
    /// The techniques' profiles.
    pub(super) profiles: &'a [DepthProfile],
    /// The `m` a logarithmic parameterization with the same texels would reach at
    /// every depth (`sqrt(K ln(f/n) * pixels / texels)`), when known.
    pub(super) log_limit: Option<f64>,
}

type PlotResult = Result<(), String>;

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// One colour per technique of [`TechniqueKind::ALL`], distinct on white.
const TECHNIQUE_COLOURS: [RGBColor; 18] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(188, 189, 34),
    RGBColor(0, 0, 128),
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(140, 86, 75),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// The colour of a technique (its position in [`TechniqueKind::ALL`]; the point
/// lights' and the spot light's techniques never share a plot with the others).
fn technique_colour(kind: TechniqueKind) -> RGBColor {
    let i = TechniqueKind::ALL
        .iter()
        .position(|k| *k == kind)
        .unwrap_or(0);
    TECHNIQUE_COLOURS[i % TECHNIQUE_COLOURS.len()]
}

/// `auto` (which coincides with the technique it picked) and the RTW oracle (a
/// bound) are drawn dashed, so that a line they cover stays visible.
fn is_dashed(kind: TechniqueKind) -> bool {
    matches!(kind, TechniqueKind::Auto | TechniqueKind::RtwOracle)
}

/// A tick label: no more digits than the value needs.
fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return "0".into();
    }
    if v.abs() >= 1e5 || v.abs() < 1e-3 {
        return format!("{v:.0e}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).clamp(0, 4) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

const LABEL_SIZE: u32 = 15;

/// Tick values for a logarithmic axis over `lo..hi`: 1, 2 and 5 times the powers
/// of ten inside the range, or every integer multiple where that gives fewer
/// than four ticks.
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        (first..=last)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let coarse = ticks(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 4 {
        coarse
    } else {
        ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    }
}

/// The aliasing error against view depth as an SVG document.
pub(super) fn depth_plot_svg(plot: &DepthPlot<'_>) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (960, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (left, right) = root.split_horizontally(740);
        draw_depth_chart(&left, plot)?;
        let mut legend: Vec<(String, RGBColor, Mark)> = plot
            .profiles
            .iter()
            .filter(|p| !p.points.is_empty())
            .map(|p| {
                (
                    p.technique.name().to_string(),
                    technique_colour(p.technique),
                    if is_dashed(p.technique) {
                        Mark::Dashed
                    } else {
                        Mark::Line
                    },
                )
            })
            .collect();
        legend.push(("m = 1 (pixel-matched)".into(), BLACK, Mark::Dashed));
        if plot.log_limit.is_some() {
            legend.push((
                "logarithmic limit".into(),
                RGBColor(120, 120, 120),
                Mark::Dashed,
            ));
        }
        draw_legend(&right, &legend)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

fn draw_depth_chart(area: &DrawingArea<SVGBackend<'_>, Shift>, plot: &DepthPlot<'_>) -> PlotResult {
    let points = plot.profiles.iter().flat_map(|p| p.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, 1.0f64, 1.0f64);
    for &(x, y) in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if let Some(l) = plot.log_limit {
        y0 = y0.min(l);
        y1 = y1.max(l);
    }
    if !(x0.is_finite() && x1 > x0) {
        (x0, x1) = (1.0, 10.0);
    }
    let (x0, x1, y0, y1) = (x0 / 1.2, x1 * 1.2, y0 / 1.5, y1 * 1.5);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{}: aliasing error against view depth", plot.config),
            ("sans-serif", 24),
        )
        .margin(12)
        .x_label_area_size(52)
        .y_label_area_size(72)
        .build_cartesian_2d(
            (x0..x1).log_scale().with_key_points(log_ticks(x0, x1)),
            (y0..y1).log_scale().with_key_points(log_ticks(y0, y1)),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("view depth (world units along the view direction, log scale)")
        .y_desc("p95 of m per depth slice (pixels, log scale)")
        .label_style(("sans-serif", LABEL_SIZE))
        .axis_desc_style(("sans-serif", LABEL_SIZE))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    let dashed = |y: f64, colour: RGBColor| {
        DashedLineSeries::new([(x0, y), (x1, y)], 8, 5, colour.stroke_width(2))
    };
    chart.draw_series(dashed(1.0, BLACK)).map_err(err)?;
    if let Some(l) = plot.log_limit {
        chart
            .draw_series(dashed(l, RGBColor(120, 120, 120)))
            .map_err(err)?;
    }
    for p in plot.profiles {
        let colour = technique_colour(p.technique);
        if is_dashed(p.technique) {
            chart
                .draw_series(DashedLineSeries::new(
                    p.points.iter().copied(),
                    6,
                    4,
                    colour.stroke_width(2),
                ))
                .map_err(err)?;
        } else {
            chart
                .draw_series(LineSeries::new(
                    p.points.iter().copied(),
                    colour.stroke_width(2),
                ))
                .map_err(err)?;
        }
        chart
            .draw_series(p.points.iter().map(|&c| Circle::new(c, 3, colour.filled())))
            .map_err(err)?;
    }
    Ok(())
}

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
enum Mark {
    Line,
    Dashed,
    Box,
}

/// A legend column: a sample of the mark and the label per entry.
fn draw_legend(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    entries: &[(String, RGBColor, Mark)],
) -> PlotResult {
    let style = ("sans-serif", LABEL_SIZE).into_font().color(&BLACK);
    area.draw_text(
        "legend",
        &("sans-serif", 17).into_font().color(&BLACK),
        (8, 40),
    )
    .map_err(err)?;
    for (i, (label, colour, mark)) in entries.iter().enumerate() {
        let y = 70 + 24 * i as i32;
        match mark {
            Mark::Dashed => {
                for x in [8, 20] {
                    area.draw(&PathElement::new(
                        [(x, y), (x + 8, y)],
                        colour.stroke_width(2),
                    ))
                    .map_err(err)?;
                }
            }
            Mark::Line => {
                area.draw(&PathElement::new([(8, y), (30, y)], colour.stroke_width(2)))
                    .map_err(err)?;
                area.draw(&Circle::new((19, y), 3, colour.filled()))
                    .map_err(err)?;
            }
            Mark::Box => {
                area.draw(&Rectangle::new([(10, y - 7), (28, y + 7)], colour.filled()))
                    .map_err(err)?;
            }
        }
        area.draw_text(label, &style, (38, y - 8)).map_err(err)?;
    }
    Ok(())
}

/// The sweep's wins, ties, losses and unmeasured cases per technique as stacked
/// horizontal bars, an SVG document.
pub(super) fn sweep_plot_svg(summary: &SweepSummary) -> Result<String, String> {
    let mut svg = String::new();
    let rows = summary.tallies.len().max(1);
    let height = 110 + 30 * rows as u32;
    {
        let root = SVGBackend::with_string(&mut svg, (960, height)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (left, right) = root.split_horizontally(780);
        let max = summary
            .tallies
            .iter()
            .map(|t| t.wins + t.ties + t.losses + t.unmeasured)
            .max()
            .unwrap_or(1)
            .max(1);
        let names: Vec<&str> = summary.tallies.iter().map(|t| t.technique.name()).collect();
        let mut chart = ChartBuilder::on(&left)
            .caption(
                format!(
                    "Robustness sweep: p95 m against the baseline over {} random cases",
                    summary.cases
                ),
                ("sans-serif", 22),
            )
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(150)
            .build_cartesian_2d(0.0..max as f64, -0.5..rows as f64 - 0.5)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .x_desc("sweep cases the technique applies to (its light's kind)")
            .label_style(("sans-serif", LABEL_SIZE))
            .axis_desc_style(("sans-serif", LABEL_SIZE))
            .x_labels((max + 1).min(11))
            .x_label_formatter(&|v| {
                if (v - v.round()).abs() < 1e-6 {
                    format!("{v:.0}")
                } else {
                    String::new()
                }
            })
            .y_labels(rows)
            .y_label_formatter(&|v| {
                // The first technique at the top.
                let i = (rows - 1) as f64 - v.round();
                if (v - v.round()).abs() < 1e-6 && i >= 0.0 {
                    names.get(i as usize).copied().unwrap_or("").to_string()
                } else {
                    String::new()
                }
            })
            .draw()
            .map_err(err)?;
        let parts = sweep_parts();
        let colours: [RGBColor; 4] = parts.each_ref().map(|p| p.1);
        let bars = summary.tallies.iter().enumerate().flat_map(|(row, t)| {
            let y = (rows - 1 - row) as f64;
            let counts = [t.wins, t.ties, t.losses, t.unmeasured];
            (0..counts.len())
                .filter(move |&k| counts[k] > 0)
                .map(move |k| {
                    let start: usize = counts[..k].iter().sum();
                    let end = start + counts[k];
                    Rectangle::new(
                        [(start as f64, y - 0.35), (end as f64, y + 0.35)],
                        colours[k].filled(),
                    )
                })
        });
        chart.draw_series(bars).map_err(err)?;
        let legend: Vec<(String, RGBColor, Mark)> = parts
            .iter()
            .map(|(label, colour)| (label.clone(), *colour, Mark::Box))
            .collect();
        draw_legend(&right, &legend)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

fn sweep_parts() -> [(String, RGBColor); 4] {
    [
        (
            format!("win (< 1/{TIE_BAND} x baseline)"),
            RGBColor(60, 160, 80),
        ),
        ("tie".into(), RGBColor(190, 190, 190)),
        (
            format!("loss (> {TIE_BAND} x baseline)"),
            RGBColor(210, 60, 50),
        ),
        ("n/a (no measure)".into(), RGBColor(120, 120, 160)),
    ]
}

/// The heatmaps' colour bar, numbered from 1 to 10 on a log scale, with the colour
/// above the scale; an SVG document.
pub(super) fn colour_bar_svg() -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (520, 96)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (bar, above) = root.split_horizontally(450);
        let ticks = vec![1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 7.0, 10.0];
        let mut chart = ChartBuilder::on(&bar)
            .margin_left(14)
            .margin_right(14)
            .margin_top(6)
            .x_label_area_size(52)
            .build_cartesian_2d((1.0f64..10.0).log_scale().with_key_points(ticks), 0.0..1.0)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .disable_y_axis()
            .label_style(("sans-serif", LABEL_SIZE))
            .axis_desc_style(("sans-serif", LABEL_SIZE))
            .x_label_formatter(&|v| tick(*v))
            .x_desc("aliasing error m (texel extent in pixels, log scale)")
            .draw()
            .map_err(err)?;
        let steps = 120;
        chart
            .draw_series((0..steps).map(|k| {
                let a = 10f64.powf(k as f64 / steps as f64);
                let b = 10f64.powf((k + 1) as f64 / steps as f64);
                let [r, g, bl] = heat_colour((a * b).sqrt());
                Rectangle::new([(a, 0.0), (b, 1.0)], RGBColor(r, g, bl).filled())
            }))
            .map_err(err)?;
        let [r, g, b] = heat_colour(11.0);
        above
            .draw(&Rectangle::new(
                [(4, 6), (40, 44)],
                RGBColor(r, g, b).filled(),
            ))
            .map_err(err)?;
        above
            .draw_text(
                "> 10",
                &("sans-serif", 14).into_font().color(&BLACK),
                (6, 52),
            )
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_takes_the_p95_of_each_slice() {
        // 100 pixels at depth 2 with m = 1..=100, 2 pixels at depth 50 (too few).
        let samples = (1..=100)
            .map(|m| (2.0, f64::from(m)))
            .chain([(50.0, 7.0), (50.0, 8.0)]);
        let p = DepthProfile::new(TechniqueKind::UniformFocused, 1.0, 100.0, samples);
        assert_eq!(p.points.len(), 1);
        let (depth, p95) = p.points[0];
        assert_eq!(p95, 95.0);
        // The slice centre is within one slice width of the samples' depth.
        let width = (100f64).ln() / DEPTH_SLICES as f64;
        assert!((depth / 2.0).ln().abs() <= width, "{depth}");
    }

    #[test]
    fn profile_ignores_bad_input() {
        let samples = [(f64::NAN, 1.0), (-1.0, 2.0), (2.0, f64::INFINITY)].into_iter();
        let p = DepthProfile::new(TechniqueKind::UniformFocused, 1.0, 100.0, samples);
        assert!(p.points.is_empty());
        let p = DepthProfile::new(
            TechniqueKind::UniformFocused,
            0.0,
            100.0,
            std::iter::repeat_n((2.0, 1.0), 10),
        );
        assert!(p.points.is_empty(), "no valid depth range");
    }

    #[test]
    fn log_ticks_cover_the_range() {
        assert_eq!(log_ticks(3.0, 300.0), [5.0, 10.0, 20.0, 50.0, 100.0, 200.0]);
        // A short range gets every integer multiple.
        assert_eq!(log_ticks(2.5, 9.5), [3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        assert!(log_ticks(0.0, 1.0).is_empty());
        assert!(log_ticks(5.0, 1.0).is_empty());
    }

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(1.0), "1");
        assert_eq!(tick(1.5), "1.5");
        assert_eq!(tick(100.0), "100");
        assert_eq!(tick(20_000.0), "20000");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(2.0e6), "2e6");
    }

    #[test]
    fn plots_are_labelled_svg() {
        let profiles = [DepthProfile::new(
            TechniqueKind::UniformFocused,
            1.0,
            100.0,
            (1..=50).map(|k| (f64::from(k) * 2.0, f64::from(k))),
        )];
        let svg = depth_plot_svg(&DepthPlot {
            config: "overhead",
            profiles: &profiles,
            log_limit: Some(2.0),
        })
        .unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..40]);
        for text in [
            "overhead: aliasing error against view depth",
            "view depth",
            "logarithmic limit",
            "m = 1 (pixel-matched)",
            TechniqueKind::UniformFocused.name(),
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
        let bar = colour_bar_svg().unwrap();
        assert!(bar.contains("aliasing error m") && bar.contains("&gt; 10"));
    }
}
