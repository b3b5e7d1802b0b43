//! The runner: builds the configurations, shares one BVH per scene, evaluates the
//! configurations on worker threads and merges their outputs in order.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::EvalError;
use crate::bvh::Bvh;
use crate::config::{
    ConfigOptions, Configuration, mesh_configuration, standard_configurations, sweep_configurations,
};
use crate::technique::TechniqueKind;

use super::evaluate::{ConfigOutput, evaluate_config};
use super::html::index_html;
use super::image::{legend_image, write_png};
use super::output::{Staging, rendered_images};
use super::plots::{colour_bar_svg, sweep_plot_svg};
use super::sweep::summarize;
use super::text::{markdown, metrics_csv, references_csv};
use super::{Options, Report, Row, Settings};

/// Runs the comparison and writes the report into `options.out`.
///
/// The output is all or nothing: the files are written into a staging directory
/// beside `options.out` and replace the previous report only when all of them are
/// complete; on any error the previous report is left as it was.
///
/// # Errors
/// [`EvalError::InvalidOption`] for zero threads; [`EvalError::Write`] (with the
/// path and the reason) when `options.out` cannot be created or replaced, or a
/// file cannot be written; the import errors for a
/// bad `--mesh`, [`EvalError::UnusableMesh`] for one without area or too large for
/// an `f32` camera; [`EvalError::InvalidView`] / [`EvalError::InvalidMesh`] for a
/// configuration that cannot be traced. A technique that cannot be built is not an
/// error: its row says "n/a (reason)".
pub fn run(options: &Options) -> Result<Report, EvalError> {
    if options.threads == 0 {
        return Err(EvalError::InvalidOption {
            message: "--threads must be at least 1".into(),
        });
    }
    let settings = Settings::new(options.quick);
    // Every input is checked before the first configuration is evaluated.
    let configs = configurations(options, &settings)?;
    let sweep_settings = Settings::sweep();
    let mut sweep_configs = if options.sweep > 0 {
        sweep_configurations(&config_options(options, &sweep_settings), options.sweep)?
    } else {
        Vec::new()
    };
    sweep_configs.retain(|c| options.selects(&c.name));
    if configs.is_empty() && sweep_configs.is_empty() {
        return Err(EvalError::InvalidOption {
            message: format!(
                "--only {:?}: no configuration has such a name",
                options.only
            ),
        });
    }
    let staging = Staging::create(&options.out)?;
    let outputs = evaluate_all(&configs, &settings, options, staging.path(), true)?;
    let sweep_outputs = evaluate_all(
        &sweep_configs,
        &sweep_settings,
        options,
        staging.path(),
        false,
    )?;
    let rendered = rendered_images(&options.out);
    let mut report = Report {
        settings,
        seed: options.seed,
        configs: Vec::new(),
        rows: Vec::new(),
        references: Vec::new(),
        files: Vec::new(),
        sweep_configs: Vec::new(),
        sweep: None,
    };
    for out in outputs {
        report.configs.push(out.summary);
        report.add_rows(out.rows);
        report.files.extend(out.files);
    }
    for out in sweep_outputs {
        report.sweep_configs.push(out.summary);
        report.add_rows(out.rows);
    }
    if options.sweep > 0 {
        report.sweep = Some(summarize(
            &report.sweep_configs,
            &report.rows,
            &report.references,
        ));
    }
    write_report_files(&mut report, staging.path(), &rendered)?;
    staging.commit()?;
    Ok(report)
}

impl Report {
    /// Files `rows` under the techniques or the references.
    fn add_rows(&mut self, rows: Vec<Row>) {
        for row in rows {
            if row.technique.is_reference() {
                self.references.push(row);
            } else {
                self.rows.push(row);
            }
        }
    }
}

/// The standard configurations, plus the user mesh's.
fn configurations(options: &Options, settings: &Settings) -> Result<Vec<Configuration>, EvalError> {
    let config_options = config_options(options, settings);
    let mut configs = standard_configurations(&config_options)?;
    if let Some(path) = &options.mesh {
        configs.push(user_mesh_configuration(path, &config_options)?);
    }
    configs.retain(|c| options.selects(&c.name));
    Ok(configs)
}

impl Options {
    /// Whether the configuration `name` is measured ([`Options::only`]).
    fn selects(&self, name: &str) -> bool {
        self.only.is_empty() || self.only.iter().any(|part| name.contains(part.as_str()))
    }
}

/// The configuration of a user mesh; every error names the file.
fn user_mesh_configuration(
    path: &Path,
    config_options: &ConfigOptions,
) -> Result<Configuration, EvalError> {
    let mesh = crate::import::load_mesh(path)?;
    let unusable = |message: String| EvalError::UnusableMesh {
        path: path.to_path_buf(),
        message,
    };
    let area: f64 = mesh
        .triangles()
        .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).length())
        .sum();
    if !(area > 0.0) {
        return Err(unusable(format!(
            "all {} triangle(s) have zero area: nothing casts or receives a shadow",
            mesh.triangle_count()
        )));
    }
    let name = path
        .file_stem()
        .map_or_else(|| "mesh".to_string(), |s| s.to_string_lossy().into_owned());
    // The configuration keeps the file's name (it names the pictures, so only
    // letters, digits, '-' and '_'), apart from the standard configurations'.
    let config_name = format!(
        "mesh_{}",
        name.chars()
            .map(|c| if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            })
            .collect::<String>()
    );
    let extent = mesh.bounds().map_or_else(String::new, |b| {
        let v = |p: glam::Vec3| format!("({:.3e}, {:.3e}, {:.3e})", p.x, p.y, p.z);
        format!(" (bounds {} to {})", v(b.min), v(b.max))
    });
    let mut config = mesh_configuration(&name, mesh, config_options).map_err(|e| match e {
        EvalError::InvalidMesh { message } | EvalError::InvalidView { message } => {
            unusable(format!("cannot frame it{extent} with a camera: {message}"))
        }
        other => other,
    })?;
    config.name = config_name;
    Ok(config)
}

fn config_options(options: &Options, settings: &Settings) -> ConfigOptions {
    ConfigOptions::default()
        .with_seed(options.seed)
        .with_path_frames(settings.path_frames)
        .with_aspect(settings.width as f32 / settings.height as f32)
}

/// One BVH per distinct scene, in configuration order.
fn scene_bvhs(configs: &[Configuration]) -> Result<Vec<Arc<Bvh>>, EvalError> {
    let mut bvhs: Vec<(*const crate::scene::Scene, Arc<Bvh>)> = Vec::new();
    let mut config_bvh = Vec::new();
    for c in configs {
        let key = Arc::as_ptr(&c.scene);
        let bvh = if let Some((_, b)) = bvhs.iter().find(|(k, _)| *k == key) {
            Arc::clone(b)
        } else {
            let b = Arc::new(Bvh::build(&c.scene.mesh)?);
            bvhs.push((key, Arc::clone(&b)));
            b
        };
        config_bvh.push(bvh);
    }
    Ok(config_bvh)
}

/// A bar over every technique of every configuration, labelled `label`, with the
/// current configuration and technique as its message and an estimate of the time
/// left; hidden unless `show`.
fn progress_bar(configs: &[Configuration], show: bool, label: &str) -> indicatif::ProgressBar {
    if !show || configs.is_empty() {
        return indicatif::ProgressBar::hidden();
    }
    let units: usize = configs
        .iter()
        .map(|c| TechniqueKind::for_light(&c.light).len())
        .sum();
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(units as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:20}] {pos}/{len} techniques, ETA {eta}: {wide_msg}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(label.to_string());
    bar
}

/// Progress for logs and pipes: one line per finished configuration.
struct ProgressLines {
    show: bool,
    label: &'static str,
    total: usize,
    done: AtomicUsize,
    start: std::time::Instant,
}

impl ProgressLines {
    fn finished(&self, config: &Configuration, ok: bool) {
        if !self.show {
            return;
        }
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        let elapsed = self.start.elapsed().as_secs_f64();
        let left = elapsed / done as f64 * (self.total - done) as f64;
        let status = if ok { "done" } else { "failed" };
        eprintln!(
            "compare: {} {done}/{}: {} {status} ({:.0} s elapsed, about {:.0} s left)",
            self.label, self.total, config.name, elapsed, left
        );
    }
}

/// Evaluates every configuration on `options.threads` workers, writing pictures
/// into `out` when `pictures`; the outputs come back in configuration order.
fn evaluate_all(
    configs: &[Configuration],
    settings: &Settings,
    options: &Options,
    out: &Path,
    pictures: bool,
) -> Result<Vec<ConfigOutput>, EvalError> {
    let config_bvh = scene_bvhs(configs)?;
    let label = if pictures {
        "configuration"
    } else {
        "sweep case"
    };
    let bar = progress_bar(
        configs,
        options.progress,
        if pictures { "compare" } else { "sweep" },
    );
    let lines = ProgressLines {
        show: options.progress_lines,
        label,
        total: configs.len(),
        done: AtomicUsize::new(0),
        start: std::time::Instant::now(),
    };
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<ConfigOutput, EvalError>>>> =
        Mutex::new((0..configs.len()).map(|_| None).collect());
    let threads = options.threads.clamp(1, configs.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(config) = configs.get(i) else { break };
                    let pictures = pictures.then_some(out);
                    let output = evaluate_config(config, &config_bvh[i], settings, pictures, &bar);
                    lines.finished(config, output.is_ok());
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(output);
                    }
                }
            });
        }
    });
    bar.finish_and_clear();
    results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| {
            r.ok_or_else(|| EvalError::InvalidView {
                message: "a worker thread stopped".into(),
            })?
        })
        .collect()
}

/// Writes the legend, the colour bar, the sweep's plot, `metrics.csv`, `report.md`
/// and `index.html` (showing the `rendered` images), and lists them in the report.
fn write_report_files(
    report: &mut Report,
    out: &Path,
    rendered: &[String],
) -> Result<(), EvalError> {
    let legend = PathBuf::from("legend.png");
    write_png(&out.join(&legend), &legend_image())?;
    report.files.push(legend);
    let mut svgs = vec![("colorbar.svg", colour_bar_svg())];
    if let Some(sweep) = &report.sweep {
        svgs.push(("sweep.svg", sweep_plot_svg(sweep)));
    }
    for (name, svg) in svgs {
        let path = out.join(name);
        let svg = svg.map_err(|e| EvalError::Write {
            path: path.clone(),
            source: std::io::Error::other(e),
        })?;
        write_file(&path, &svg)?;
        report.files.push(PathBuf::from(name));
    }
    let html = PathBuf::from("index.html");
    report.files.push(html.clone());
    let csv = PathBuf::from("metrics.csv");
    write_file(&out.join(&csv), &metrics_csv(report))?;
    let references = PathBuf::from("references.csv");
    write_file(&out.join(&references), &references_csv(report))?;
    report.files.push(csv);
    report.files.push(references);
    let md = PathBuf::from("report.md");
    report.files.push(md.clone());
    report.files.sort();
    write_file(&out.join(&md), &markdown(report))?;
    write_file(&out.join(&html), &index_html(report, rendered))
}

pub(super) fn write_file(path: &Path, text: &str) -> Result<(), EvalError> {
    let err = |source| EvalError::Write {
        path: path.to_path_buf(),
        source,
    };
    std::fs::write(path, text.as_bytes()).map_err(err)
}
