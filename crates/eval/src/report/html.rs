//! `index.html`: the report as one self-contained page that opens from disk (no
//! network: styles and the table-sorting script are inline, the pictures are files
//! of the report directory referenced by relative paths).
//!
//! Per configuration: its description and limits, the best technique, the sortable
//! table, the aliasing error against view depth, the heatmaps with a numbered
//! colour bar, and the labelled shadow masks with their key. Then the robustness
//! sweep when it ran, the backend's rendered images when present, and notes on
//! results that look surprising at first sight.

use std::fmt::Write as _;

use crate::technique::TechniqueKind;

use super::image::heat_colour;
use super::sweep::{SweepSummary, TIE_BAND, baseline_of};
use super::text::{best_technique, short};
use super::{ConfigSummary, Report, Row};

/// Escapes text for HTML content and attribute values.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

fn rgb(c: [u8; 3]) -> String {
    format!("rgb({},{},{})", c[0], c[1], c[2])
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;margin:1.5em auto;max-width:1100px;\
padding:0 1em;color:#222;line-height:1.4}\
h2{border-top:2px solid #ccc;padding-top:.6em;margin-top:2em}\
table{border-collapse:collapse;font-size:.9em;margin:.5em 0}\
th,td{border:1px solid #ccc;padding:.2em .5em;text-align:right}\
td:first-child,th:first-child,.t{text-align:left}\
th{background:#f0f0f0;cursor:pointer;user-select:none}\
th.asc::after{content:' \\25B2'}th.desc::after{content:' \\25BC'}\
tr.best td{background:#eef7ee;font-weight:600}\
.grid{display:flex;flex-wrap:wrap;gap:1em}\
figure{margin:0}figcaption{font-size:.85em;color:#444}\
img.px{image-rendering:pixelated}\
img.heat{width:320px}img.mask{width:660px}img.plot{max-width:100%}\
.panels{display:grid;grid-template-columns:1fr 1fr 1fr;width:660px;font-size:.85em;\
font-weight:600;text-align:center}\
.key span.sw{display:inline-block;width:1em;height:1em;border:1px solid #888;\
vertical-align:middle;margin:0 .3em 0 1em}\
dl.defs dt{font-weight:600}dl.defs dd{margin:0 0 .4em 1.5em}";

const SCRIPT: &str = "document.querySelectorAll('table.sortable').forEach(function(t){\
var hs=t.tHead.rows[0].cells;Array.prototype.forEach.call(hs,function(th,i){\
th.title='click to sort';th.addEventListener('click',function(){\
var asc=!th.classList.contains('asc');\
Array.prototype.forEach.call(hs,function(h){h.classList.remove('asc','desc');});\
th.classList.add(asc?'asc':'desc');var b=t.tBodies[0];var rows=Array.from(b.rows);\
rows.sort(function(x,y){var a=x.cells[i].dataset.v,c=y.cells[i].dataset.v;\
var an=a===undefined||a==='',cn=c===undefined||c==='';if(an||cn){return an-cn;}\
var p=parseFloat(a),q=parseFloat(c);var r=(isNaN(p)||isNaN(q))?a.localeCompare(c):p-q;\
return asc?r:-r;});rows.forEach(function(r){b.appendChild(r);});});});});";

/// The page. `rendered` lists the backend's images (relative paths) to show.
pub(super) fn index_html(report: &Report, rendered: &[String]) -> String {
    let mut s = String::new();
    s.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    s.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    s.push_str("<title>Shadow-map technique comparison</title>\n");
    let _ = writeln!(s, "<style>{STYLE}</style>\n</head>\n<body>");
    header(&mut s, report);
    for c in &report.configs {
        config_section(&mut s, report, c);
    }
    if let Some(sweep) = &report.sweep {
        sweep_section(&mut s, sweep);
    }
    if !rendered.is_empty() {
        rendered_section(&mut s, rendered);
    }
    notes(&mut s);
    let _ = writeln!(s, "<script>{SCRIPT}</script>\n</body>\n</html>");
    s
}

fn header(s: &mut String, report: &Report) {
    let st = &report.settings;
    let _ = writeln!(
        s,
        "<h1>Shadow-map technique comparison</h1>\n<p>Every shadow-map parameterization \
         on the same scenes at the same texel budget: image {}×{} pixels, {} texels per \
         technique (all layers together), camera paths of {} frames, scene seed {}. \
         Written by <code>cargo run --release -p shadowmap-eval --bin compare</code>; \
         <code>report.md</code> and <code>metrics.csv</code> beside this page hold the \
         same numbers. The definitions are in <code>docs/quality.md</code> of the \
         repository.</p>",
        st.width, st.height, st.texel_budget, st.path_frames, report.seed
    );
    overview(s, report);
    s.push_str(
        "<h2 id=\"definitions\">What the columns mean</h2>\n<dl class=\"defs\">\n\
         <dt>m — aliasing error</dt><dd>the largest extent of one shadow-map texel on \
         the screen, in pixels, at each visible, front-lit pixel: 1 is pixel-matched, \
         above 1 the map undersamples (jagged shadow edges). Lower is better.</dd>\n\
         <dt>p95</dt><dd>the 95th percentile of m over the measured pixels: 5% of them \
         are worse.</dd>\n\
         <dt>m⊥</dt><dd>m with the surface normal replaced by the bisector of the eye \
         and light directions: the error of the parameterization alone.</dd>\n\
         <dt>S — storage factor</dt><dd>texels per visible pixel × (max m)²: the texels \
         this parameterization would need so that no texel is larger than a pixel. \
         S⊥ is the same for m⊥, S_sep Lloyd's separable storage factor.</dd>\n\
         <dt>used, miss, jitter, flips</dt><dd>the fraction of texels some pixel samples; \
         the fraction of front-lit pixels whose shadow test disagrees with ray tracing; \
         the mean sub-texel phase change of fixed world points per frame; the fraction \
         of shadow tests that change between frames along the camera path.</dd>\n\
         <dt>limits</dt><dd>m = 1 (pixel-matched) and the logarithmic bound K·ln(f/n) on \
         the storage factor of separable parameterizations (K = 1 / (2 tan(fovY/2))); \
         in the depth plots the latter is drawn as the m a logarithmic parameterization \
         with the same texels would reach at every depth, √(K·ln(f/n) · pixels / \
         texels). The rtw_oracle row is RTW fed the exact density m⊥ requires.</dd>\n\
         </dl>\n",
    );
}

/// The best technique of every configuration against its baseline, one table.
fn overview(s: &mut String, report: &Report) {
    s.push_str(
        "<h2 id=\"overview\">At a glance</h2>\n<p>The technique with the lowest p95 of the \
         aliasing error m per configuration (the RTW oracle, a bound, left out), against \
         the light's baseline; click a configuration for its tables and pictures, a \
         column header to sort. Then: <a href=\"#definitions\">what the columns mean</a>",
    );
    if report.sweep.is_some() {
        s.push_str(", <a href=\"#sweep\">the robustness sweep</a>");
    }
    s.push_str(
        ", <a href=\"#notes\">notes on surprising results</a>.</p>\n\
         <table class=\"sortable\">\n<thead><tr><th>configuration</th><th class=\"t\">light</th>\
         <th class=\"t\">best technique</th><th>its p95 m</th><th class=\"t\">baseline</th><th>baseline p95 m</th>\
         <th>baseline / best</th></tr></thead>\n<tbody>\n",
    );
    for c in &report.configs {
        let name = esc(&c.name);
        let rows: Vec<&Row> = report.rows.iter().filter(|r| r.config == c.name).collect();
        let kinds: Vec<TechniqueKind> = rows.iter().map(|r| r.technique).collect();
        let baseline = baseline_of(&kinds);
        let base_p95 = rows
            .iter()
            .find(|r| Some(r.technique) == baseline)
            .and_then(|r| r.outcome.as_ref().ok()?.aliasing.m)
            .map(|m| m.p95);
        let best = best_technique(report, &c.name);
        let num = |v: Option<f64>| {
            let v = v.filter(|v| v.is_finite());
            format!(
                "<td data-v=\"{}\">{}</td>",
                v.map(|v| format!("{v:e}")).unwrap_or_default(),
                short(v)
            )
        };
        let _ = writeln!(
            s,
            "<tr><td data-v=\"{0}\"><a href=\"#{0}\">{0}</a></td><td class=\"t\" data-v=\"{1}\">{1}</td>\
             <td class=\"t\" data-v=\"{2}\"><strong>{2}</strong></td>{3}<td class=\"t\" data-v=\"{4}\">{4}</td>{5}{6}</tr>",
            name,
            c.light_kind,
            best.map_or("–", |b| b.0.name()),
            num(best.map(|b| b.1)),
            baseline.map_or("–", TechniqueKind::name),
            num(base_p95),
            num(base_p95.zip(best).map(|(b, (_, p))| b / p)),
        );
    }
    s.push_str("</tbody>\n</table>\n");
}

/// Table columns: header, and per measured row the sort value and the shown text.
type Column = (
    &'static str,
    fn(&super::RowMetrics) -> (Option<f64>, String),
);

fn columns() -> [Column; 13] {
    use super::text::percent;
    fn m_of(r: &super::RowMetrics, f: fn(&crate::metrics::Summary) -> f64) -> Option<f64> {
        r.aliasing.m.as_ref().map(f)
    }
    [
        ("layers", |r| {
            (
                Some(f64::from(r.layers)),
                format!("{}×{}²", r.layers, r.layer_side),
            )
        }),
        ("median m", |r| {
            let v = m_of(r, |m| m.median);
            (v, short(v))
        }),
        ("p95 m", |r| {
            let v = m_of(r, |m| m.p95);
            (v, short(v))
        }),
        ("max m", |r| {
            let v = m_of(r, |m| m.max);
            (v, short(v))
        }),
        ("median m⊥", |r| {
            let v = r.aliasing.m_perspective.map(|m| m.median);
            (v, short(v))
        }),
        ("S", |r| {
            let v = Some(r.aliasing.storage_factor);
            (v, short(v))
        }),
        ("S⊥", |r| {
            let v = Some(r.aliasing.storage_factor_perspective);
            (v, short(v))
        }),
        ("S_sep", |r| {
            let v = Some(r.aliasing.separable_storage_factor_perspective);
            (v, short(v))
        }),
        ("used", |r| {
            let v = Some(r.aliasing.used_texel_fraction);
            (v, percent(v))
        }),
        ("miss", |r| {
            (r.misclassification, percent(r.misclassification))
        }),
        ("jitter", |r| (r.phase_jitter, short(r.phase_jitter))),
        ("flips", |r| (r.flip_rate, percent(r.flip_rate))),
        ("pixels measured", |r| {
            let v = r.aliasing.measured_pixels;
            (Some(v as f64), v.to_string())
        }),
    ]
}

fn table(s: &mut String, rows: &[&Row], best: Option<TechniqueKind>) {
    let cols = columns();
    s.push_str("<table class=\"sortable\">\n<thead><tr><th>technique</th>");
    for (h, _) in &cols {
        let _ = write!(s, "<th>{}</th>", esc(h));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for row in rows {
        let name = row.technique.name();
        let class = if Some(row.technique) == best {
            " class=\"best\""
        } else {
            ""
        };
        let _ = write!(s, "<tr{class}><td data-v=\"{name}\">{name}</td>");
        match &row.outcome {
            Ok(r) => {
                for (_, f) in &cols {
                    let (v, text) = f(r);
                    let v = v.filter(|v| v.is_finite()).map(|v| format!("{v:e}"));
                    let _ = write!(
                        s,
                        "<td data-v=\"{}\">{}</td>",
                        v.unwrap_or_default(),
                        esc(&text)
                    );
                }
            }
            Err(reason) => {
                let _ = write!(
                    s,
                    "<td data-v=\"\" colspan=\"1\" title=\"{}\">n/a</td>",
                    esc(reason)
                );
                for _ in 1..cols.len() {
                    s.push_str("<td data-v=\"\">–</td>");
                }
            }
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    let missing: Vec<String> = rows
        .iter()
        .filter_map(|r| {
            let reason = r.outcome.as_ref().err()?;
            Some(format!("{}: {}", r.technique.name(), esc(reason)))
        })
        .collect();
    if !missing.is_empty() {
        let _ = writeln!(s, "<p>Not available: {}.</p>", missing.join("; "));
    }
}

fn config_section(s: &mut String, report: &Report, c: &ConfigSummary) {
    let name = esc(&c.name);
    let _ = writeln!(s, "<section id=\"{name}\">\n<h2>{name}</h2>");
    let _ = writeln!(
        s,
        "<p>{} Scene <code>{}</code>, {} light, view depth {} – {}, {} visible pixels. \
         Limits: m = 1; log bound K·ln(f/n) = {}.</p>",
        esc(&c.description),
        esc(&c.scene),
        c.light_kind,
        c.depth_range.0,
        c.depth_range.1,
        c.visible_pixels,
        short(c.log_bound)
    );
    let best = best_technique(report, &c.name);
    if let Some((kind, p95)) = best {
        let _ = writeln!(
            s,
            "<p><strong>Best: {}</strong> (lowest p95 m, {}; highlighted). Click a column \
             header to sort.</p>",
            kind.name(),
            short(Some(p95))
        );
    }
    let rows: Vec<&Row> = report.rows.iter().filter(|r| r.config == c.name).collect();
    table(s, &rows, best.map(|b| b.0));
    for line in super::text::reference_lines(report, &c.name) {
        let _ = writeln!(s, "<p>{}</p>", esc(&line));
    }
    let measured: Vec<&Row> = rows.iter().copied().filter(|r| r.outcome.is_ok()).collect();
    pictures(s, c, &measured);
}

/// The depth plot, the heatmaps and the masks of one configuration's `measured`
/// techniques; closes its section.
fn pictures(s: &mut String, c: &ConfigSummary, measured: &[&Row]) {
    let name = esc(&c.name);
    let file = |prefix: &str, t: TechniqueKind| format!("{prefix}_{}_{}.png", c.name, t.name());
    let _ = writeln!(
        s,
        "<h3>Aliasing error against view depth</h3>\n<figure><img class=\"plot\" \
         src=\"aliasing_{name}.svg\" alt=\"{name}: p95 of m per view-depth slice for \
         every technique\"><figcaption>The 95th percentile of m in each of 24 \
         logarithmic slices of the view depth (slices with fewer than 4 measured \
         pixels left out), frame 0; dashed: the pixel-matched limit m = 1 and the \
         logarithmic limit.</figcaption></figure>"
    );
    let _ = writeln!(
        s,
        "<h3>Heatmaps of m</h3>\n<p>m per pixel of frame 0 on the colour bar below \
         (log scale); {} red above 10, {} grey background, {} dark grey: visible but not \
         measured (not front-lit, or not covered by the map).</p>\n\
         <img class=\"plot\" src=\"colorbar.svg\" alt=\"colour bar: m from 1 to 10, \
         log scale\">\n<div class=\"grid\">",
        swatch(heat_colour(11.0)),
        swatch([128, 128, 128]),
        swatch(heat_colour(f64::NAN)),
    );
    for r in measured {
        let t = r.technique.name();
        let _ = writeln!(
            s,
            "<figure><img class=\"heat px\" src=\"{}\" alt=\"{t}: heatmap of m\">\
             <figcaption><strong>{t}</strong>: aliasing error m over the screen</figcaption>\
             </figure>",
            esc(&file("heatmap", r.technique))
        );
    }
    s.push_str("</div>\n");
    let _ = writeln!(
        s,
        "<h3>Shadow masks</h3>\n<p class=\"key\">Over the pixels <em>miss</em> counts \
         (visible and front-lit; others grey): {}lit {}in shadow; differences: {}agree \
         {}lit but in shadow by ray tracing {}shadowed but lit by ray tracing.</p>\n\
         <div class=\"grid\">",
        swatch([235, 225, 200]),
        swatch([40, 50, 80]),
        swatch([200, 200, 200]),
        swatch([220, 40, 40]),
        swatch([40, 90, 230]),
    );
    for r in measured {
        let t = r.technique.name();
        let _ = writeln!(
            s,
            "<figure><div class=\"panels\"><span>{t}</span><span>ray traced</span>\
             <span>differences</span></div><img class=\"mask px\" src=\"{}\" \
             alt=\"{t}: shadow masks\"><figcaption><strong>{t}</strong>: its shadow \
             test, the ray-traced truth, and where they differ</figcaption></figure>",
            esc(&file("mask", r.technique))
        );
    }
    s.push_str("</div>\n</section>\n");
}

fn swatch(c: [u8; 3]) -> String {
    format!("<span class=\"sw\" style=\"background:{}\"></span>", rgb(c))
}

fn sweep_section(s: &mut String, sweep: &SweepSummary) {
    let _ = writeln!(
        s,
        "<section id=\"sweep\">\n<h2>Robustness sweep</h2>\n<p>{} random camera and \
         light configurations over the scenes. Each technique's p95 m against its \
         family's baseline (uniform fit for the directional techniques, the spot fit \
         for the spot techniques, DPSM for the paraboloid maps, the focused cube maps \
         for RTW over them, the engines' unfocused cube maps for the focused ones): \
         a win is more than {TIE_BAND}× lower, a loss \
         more than {TIE_BAND}× higher, a tie in between.</p>\n<figure><img class=\"plot\" \
         src=\"sweep.svg\" alt=\"wins, ties and losses per technique\"><figcaption>Cases \
         per technique by outcome against the baseline.</figcaption></figure>",
        sweep.cases
    );
    s.push_str(
        "<table class=\"sortable\">\n<thead><tr><th>technique</th><th>wins</th>\
         <th>ties</th><th>losses</th><th>n/a</th><th>worst p95 m / baseline</th>\
         <th>worst case</th></tr></thead>\n<tbody>\n",
    );
    for t in &sweep.tallies {
        let _ = write!(
            s,
            "<tr><td data-v=\"{0}\">{0}</td><td data-v=\"{1}\">{1}</td><td data-v=\"{2}\">{2}</td>\
             <td data-v=\"{3}\">{3}</td><td data-v=\"{4}\">{4}</td>",
            t.technique.name(),
            t.wins,
            t.ties,
            t.losses,
            t.unmeasured
        );
        match &t.worst {
            Some(w) => {
                let _ = writeln!(
                    s,
                    "<td data-v=\"{0:e}\">{0:.2} (vs {3})</td><td data-v=\"{1}\" \
                     title=\"{2}\">{1}</td></tr>",
                    w.ratio(),
                    esc(&w.config),
                    esc(&w.description),
                    w.baseline.name()
                );
            }
            None => s.push_str("<td data-v=\"\">–</td><td data-v=\"\">–</td></tr>\n"),
        }
    }
    s.push_str("</tbody>\n</table>\n</section>\n");
}

fn rendered_section(s: &mut String, rendered: &[String]) {
    s.push_str(
        "<section id=\"rendered\">\n<h2>Rendered with the wgpu backend</h2>\n<p>The city \
         block rendered by <code>cargo run -p shadowmap-wgpu --example render_scene</code> \
         with each technique (a 2048² map, 3×3 PCF unless named otherwise).</p>\n\
         <div class=\"grid\">\n",
    );
    for r in rendered {
        let label = r
            .rsplit('/')
            .next()
            .unwrap_or(r)
            .trim_end_matches(".png")
            .to_string();
        let _ = writeln!(
            s,
            "<figure><img class=\"heat\" src=\"{0}\" alt=\"{1}\"><figcaption><strong>{1}\
             </strong></figcaption></figure>",
            esc(r),
            esc(&label)
        );
    }
    s.push_str("</div>\n</section>\n");
}

fn notes(s: &mut String) {
    s.push_str(
        "<section id=\"notes\">\n<h2>Notes on results that look like bugs</h2>\n<ul>\n\
         <li><strong>lispsm and xpsm are within a few percent of each other</strong> where \
         the light is perpendicular to the view direction (<code>overhead</code>): both \
         warp along the view direction projected into light space, with nearly the same \
         strength there; they part where the light tilts toward or away from the \
         viewer (<code>behind</code>, <code>grazing</code>).</li>\n\
         <li><strong>auto equals another row</strong>: it picks one of the matrix \
         techniques or cascades per frame, so its numbers are those of its pick (its \
         line in the depth plots is dashed so that both stay visible).</li>\n\
         <li><strong>rtw_oracle can be worse than rtw</strong>: the oracle is fed the \
         exact density of the perspective-only error m⊥ for a separable warp, so it is a \
         bound on S⊥ and S_sep, not on the true-normal m, which adds the projective \
         error of surfaces seen at a grazing angle from the light and which RTW's \
         importance from the eye's samples partly follows.</li>\n\
         <li><strong>S can be huge while the median m is small</strong>: S uses the \
         largest m of any pixel, so a few pixels at grazing light angles dominate it.</li>\n\
         <li><strong>cascades show more layers</strong>: the texel budget is split \
         over the layers, so every technique stores the same number of texels.</li>\n\
         </ul>\n</section>\n",
    );
}
