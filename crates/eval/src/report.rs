//! The `compare` report: every technique on every configuration, side by side.
//!
//! [`run`] is what the `compare` binary calls. For each configuration it traces
//! the G-buffer of every frame of the camera path, the ray-traced shadow mask of
//! frame 0, and for each technique that applies to the light:
//!
//! - frame 0: the aliasing metrics of every visible pixel ([`crate::metrics`]), the
//!   depth map from the reference rasterizer, the shadow mask and its
//!   misclassification against the ray-traced mask (over front-lit pixels, see
//!   [`metrics::FRONT_LIT_MIN_COS`]), and the images;
//! - every frame: the technique refitted to the moved camera, its sub-texel phase at
//!   fixed world points (front-lit points of frame 0, every
//!   [`Settings::temporal_stride`]-th pixel) and their shadow test, for the phase
//!   jitter and the flip rate.
//!
//! The depth pass uses a slope-scaled bias (1.5 texels of slope plus 16 units of the
//! smallest resolvable depth, the same for every technique) and the lookup
//! `1e-5` depth units; nearest-texel lookups, no filtering.
//!
//! Output in [`Options::out`]: `report.md`, `metrics.csv`, `legend.png`, and per
//! technique and configuration `heatmap_<config>_<technique>.png` (aliasing error
//! over the screen) and `mask_<config>_<technique>.png` (three panels: the
//! technique's shadow mask, the ray-traced mask, the misclassified pixels).
//!
//! `metrics.csv` is deterministic: fixed row order (configurations, then techniques
//! in [`TechniqueKind::ALL`] order), fixed float formatting (`{:.6e}`), no timings,
//! no paths; work is spread over threads but merged in that order, so two runs with
//! the same options write identical bytes.
//!
//! # Heatmap colour scale
//!
//! `m` on a logarithmic scale from 1 to 10, colormap *viridis* (dark blue at
//! `m <= 1`, through teal and green, to yellow at `m = 10`; a piecewise-linear fit
//! through 9 of viridis' colours); `m > 10` is red; background grey
//! `(128, 128, 128)`; visible pixels without a true-normal `m` dark grey
//! `(48, 48, 48)`: surfaces that are not front-lit (see
//! [`metrics::FRONT_LIT_MIN_COS`]), points the technique does not cover, degenerate
//! Jacobians. `legend.png` shows the scale.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use glam::DVec2;
use shadowmap_frustum::{Camera, SceneBounds, ShadowMapping};

use crate::EvalError;
use crate::bvh::Bvh;
use crate::config::{ConfigOptions, Configuration, mesh_configuration, standard_configurations};
use crate::mask::{GBuffer, ShadowMask};
use crate::metrics::{
    self, AliasingStats, ScreenGeometry, Summary, SurfacePoint, aliasing_stats, flip_rate,
    misclassification, phase_jitter,
};
use crate::raster::RasterOptions;
use crate::technique::{FrameContext, Technique, TechniqueKind, TechniqueOptions, eye_samples};

/// What to run.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Options {
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// Small images, short paths and a small budget (for tests and CI).
    pub quick: bool,
    /// Seed of the procedural scenes.
    pub seed: u64,
    /// A user mesh (OBJ / glTF) to add as a configuration.
    pub mesh: Option<PathBuf>,
    /// Worker threads (at least 1).
    pub threads: usize,
    /// Show a progress bar on stderr.
    pub progress: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            out: PathBuf::from("target/shadowmap-report"),
            quick: false,
            seed: DEFAULT_SEED,
            mesh: None,
            threads: 2,
            progress: false,
        }
    }
}

impl Options {
    /// Writing to `out`.
    #[must_use]
    pub fn with_out(mut self, out: impl Into<PathBuf>) -> Self {
        self.out = out.into();
        self
    }
    /// Quick or full.
    #[must_use]
    pub const fn with_quick(mut self, quick: bool) -> Self {
        self.quick = quick;
        self
    }
    /// With this scene seed.
    #[must_use]
    pub const fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// With a user mesh.
    #[must_use]
    pub fn with_mesh(mut self, mesh: Option<PathBuf>) -> Self {
        self.mesh = mesh;
        self
    }
    /// With this many worker threads.
    #[must_use]
    pub const fn with_threads(mut self, threads: usize) -> Self {
        self.threads = threads;
        self
    }
    /// With or without a progress bar.
    #[must_use]
    pub const fn with_progress(mut self, progress: bool) -> Self {
        self.progress = progress;
        self
    }
}

/// The default scene seed.
pub const DEFAULT_SEED: u64 = 1;

/// The sizes a run uses, from [`Options::quick`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Frames per camera path.
    pub path_frames: usize,
    /// Texels per technique, all layers together.
    pub texel_budget: u64,
    /// RTW importance-map side.
    pub rtw_side: u32,
    /// Every `stride`-th pixel (in x and y) of frame 0 gives a fixed world point for
    /// the temporal metrics.
    pub temporal_stride: u32,
}

impl Settings {
    /// The sizes of a full or quick run.
    #[must_use]
    pub const fn new(quick: bool) -> Self {
        if quick {
            Self {
                width: 64,
                height: 36,
                path_frames: 3,
                texel_budget: 128 * 128,
                rtw_side: 32,
                temporal_stride: 2,
            }
        } else {
            Self {
                width: 480,
                height: 270,
                path_frames: 6,
                texel_budget: 1024 * 1024,
                rtw_side: 256,
                temporal_stride: 4,
            }
        }
    }
}

/// Depth bias of the reference depth pass: slope-scaled, so that a receiver's
/// depth at its exact position never lies behind the stored depth of its own texel
/// (half a texel in each axis is at most one texel of slope).
const SLOPE_BIAS: f64 = 1.5;
/// Constant part of the depth pass bias, in units of the smallest resolvable depth.
const CONSTANT_BIAS: f64 = 16.0;
/// Lookup bias in depth units (toward the light).
const LOOKUP_BIAS: f64 = 1e-5;

/// The measures of one technique on one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RowMetrics {
    /// Layers of the map.
    pub layers: u32,
    /// Side of each layer in texels.
    pub layer_side: u32,
    /// Texels over all layers.
    pub texels: u64,
    /// Aliasing measures of frame 0.
    pub aliasing: AliasingStats,
    /// Misclassified fraction of the visible pixels (frame 0).
    pub misclassification: Option<f64>,
    /// Mean sub-texel phase change of fixed world points per frame.
    pub phase_jitter: Option<f64>,
    /// Fraction of fixed points whose shadow test flips between frames.
    pub flip_rate: Option<f64>,
}

/// One technique on one configuration: its measures or why it has none.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Configuration name.
    pub config: String,
    /// Technique.
    pub technique: TechniqueKind,
    /// The measures, or the reason the technique is not available ("n/a").
    pub outcome: Result<RowMetrics, String>,
}

/// A configuration as the report describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigSummary {
    /// Name.
    pub name: String,
    /// One line.
    pub description: String,
    /// Scene name.
    pub scene: String,
    /// `directional`, `spot` or `point`.
    pub light_kind: &'static str,
    /// Near and far plane.
    pub depth_range: (f64, f64),
    /// `K ln(f / n)`.
    pub log_bound: Option<f64>,
    /// Visible pixels of frame 0.
    pub visible_pixels: usize,
}

/// Everything a run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// The sizes used.
    pub settings: Settings,
    /// The seed used.
    pub seed: u64,
    /// The configurations, in order.
    pub configs: Vec<ConfigSummary>,
    /// One row per configuration and applicable technique, in order.
    pub rows: Vec<Row>,
    /// Files written, relative to the output directory, sorted.
    pub files: Vec<PathBuf>,
}

/// Runs the comparison and writes the report into `options.out`.
///
/// # Errors
/// [`EvalError::Write`] when the output cannot be written; the import errors for a
/// bad `--mesh`; [`EvalError::InvalidView`] / [`EvalError::InvalidMesh`] for a
/// configuration that cannot be traced. A technique that cannot be built is not an
/// error: its row says "n/a (reason)".
pub fn run(options: &Options) -> Result<Report, EvalError> {
    let settings = Settings::new(options.quick);
    let config_options = ConfigOptions::default()
        .with_seed(options.seed)
        .with_path_frames(settings.path_frames)
        .with_aspect(settings.width as f32 / settings.height as f32);
    let mut configs = standard_configurations(&config_options)?;
    if let Some(path) = &options.mesh {
        let mesh = crate::import::load_mesh(path)?;
        let name = path
            .file_stem()
            .map_or_else(|| "mesh".to_string(), |s| s.to_string_lossy().into_owned());
        configs.push(mesh_configuration(&name, mesh, &config_options)?);
    }
    std::fs::create_dir_all(&options.out).map_err(|source| EvalError::Write {
        path: options.out.clone(),
        source,
    })?;

    let units: usize = configs
        .iter()
        .map(|c| TechniqueKind::for_light(&c.light).len())
        .sum();
    let bar = if options.progress {
        indicatif::ProgressBar::with_draw_target(
            Some(units as u64),
            indicatif::ProgressDrawTarget::stderr(),
        )
    } else {
        indicatif::ProgressBar::hidden()
    };

    // Bounding volume hierarchies, one per distinct scene.
    let mut bvhs: Vec<(*const crate::scene::Scene, Arc<Bvh>)> = Vec::new();
    let mut config_bvh = Vec::new();
    for c in &configs {
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
                    let out =
                        evaluate_config(config, &config_bvh[i], &settings, &options.out, &bar);
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(out);
                    }
                }
            });
        }
    });
    bar.finish_and_clear();

    let mut report = Report {
        settings,
        seed: options.seed,
        configs: Vec::new(),
        rows: Vec::new(),
        files: Vec::new(),
    };
    let results = results.into_inner().unwrap_or_default();
    for r in results {
        let out = r.ok_or_else(|| EvalError::InvalidView {
            message: "a worker thread stopped".into(),
        })??;
        report.configs.push(out.summary);
        report.rows.extend(out.rows);
        report.files.extend(out.files);
    }
    let legend = PathBuf::from("legend.png");
    write_png(&options.out.join(&legend), &legend_image())?;
    report.files.push(legend);
    let csv = PathBuf::from("metrics.csv");
    write_file(&options.out.join(&csv), &metrics_csv(&report))?;
    report.files.push(csv);
    let md = PathBuf::from("report.md");
    report.files.push(md.clone());
    report.files.sort();
    write_file(&options.out.join(&md), &markdown(&report))?;
    Ok(report)
}

struct ConfigOutput {
    summary: ConfigSummary,
    rows: Vec<Row>,
    files: Vec<PathBuf>,
}

/// One frame of a configuration, traced once and shared by the techniques.
struct Frame {
    camera: Camera,
    gbuffer: GBuffer,
    samples: Vec<shadowmap_rtw::EyeSample>,
    screen: ScreenGeometry,
}

fn evaluate_config(
    config: &Configuration,
    bvh: &Bvh,
    settings: &Settings,
    out: &Path,
    bar: &indicatif::ProgressBar,
) -> Result<ConfigOutput, EvalError> {
    let (w, h) = (settings.width, settings.height);
    let frames: Vec<Frame> = config
        .path
        .iter()
        .map(|camera| {
            let gbuffer = GBuffer::trace(bvh, camera, w, h)?;
            let samples = eye_samples(&gbuffer, camera);
            let screen = ScreenGeometry::new(camera, w, h)?;
            Ok(Frame {
                camera: *camera,
                gbuffer,
                samples,
                screen,
            })
        })
        .collect::<Result<_, EvalError>>()?;
    let first = &frames[0];
    let truth = ShadowMask::ray_traced(&first.gbuffer, bvh, &config.light)?;
    let surfaces: Vec<Option<SurfacePoint>> = first
        .gbuffer
        .surfaces
        .iter()
        .map(|s| {
            s.as_ref().map(|s| SurfacePoint {
                position: s.position,
                normal: s.normal,
            })
        })
        .collect();
    // Misclassification counts front-lit pixels only: elsewhere shading darkens the
    // surface whatever the map says (see metrics::FRONT_LIT_MIN_COS).
    let truth_front_lit: Vec<Option<bool>> = truth
        .lit
        .iter()
        .zip(&surfaces)
        .map(|(t, s)| t.filter(|_| s.is_some_and(|s| metrics::is_front_lit(&config.light, &s))))
        .collect();
    // Fixed world points for the temporal measures: a regular subset of the
    // front-lit points of frame 0 (on surfaces parallel to the light the shadow
    // test is a coin toss that shading hides).
    let stride = settings.temporal_stride.max(1);
    let fixed: Vec<glam::DVec3> = (0..h)
        .step_by(stride as usize)
        .flat_map(|y| (0..w).step_by(stride as usize).map(move |x| (x, y)))
        .filter_map(|(x, y)| surfaces[(y * w + x) as usize])
        .filter(|s| metrics::is_front_lit(&config.light, s))
        .map(|s| s.position)
        .collect();
    let scene_bounds = config
        .scene
        .scene_bounds()
        .ok_or_else(|| EvalError::InvalidMesh {
            message: format!("{}: scene has no bounds", config.scene.name),
        })?;
    let (near, far) = config
        .camera()
        .depth_range()
        .map(|(n, f)| (f64::from(n), f64::from(f)))
        .unwrap_or((f64::NAN, f64::NAN));
    let summary = ConfigSummary {
        name: config.name.clone(),
        description: config.description.clone(),
        scene: config.scene.name.clone(),
        light_kind: config.light_kind(),
        depth_range: (near, far),
        log_bound: metrics::log_bound(config.camera()),
        visible_pixels: first.gbuffer.visible_count(),
    };
    let technique_options = TechniqueOptions::default()
        .with_texel_budget(settings.texel_budget)
        .with_rtw_importance_side(settings.rtw_side);
    let raster = RasterOptions::default().with_depth_bias(CONSTANT_BIAS, SLOPE_BIAS);
    let mut rows = Vec::new();
    let mut files = Vec::new();
    for kind in TechniqueKind::for_light(&config.light) {
        let outcome = (|| -> Result<RowMetrics, EvalError> {
            let technique = Technique::build(
                kind,
                &context(first, config, scene_bounds),
                &technique_options,
            )?;
            let (aliasing, pixels) = aliasing_stats(
                &technique,
                &technique.layer_sizes(),
                &first.screen,
                &config.light,
                &surfaces,
            );
            let map = technique.rasterize(&config.scene.mesh, &raster)?;
            let mask = ShadowMask::from_map(&first.gbuffer, &technique, &map, LOOKUP_BIAS);
            let miss = misclassification(&mask.lit, &truth_front_lit);
            let base = format!("{}_{}", config.name, kind.name());
            let heat = PathBuf::from(format!("heatmap_{base}.png"));
            write_png(
                &out.join(&heat),
                &heatmap_image(w, h, &first.gbuffer, &pixels.m),
            )?;
            let masks = PathBuf::from(format!("mask_{base}.png"));
            write_png(&out.join(&masks), &mask_image(w, h, &mask.lit, &truth.lit))?;
            files.push(heat);
            files.push(masks);
            // Temporal: refit per frame, follow the fixed points.
            let mut texels = vec![texels_of(&technique, &fixed)];
            let mut lit = vec![lit_of(&technique, &map, &fixed)];
            let mut temporal_ok = true;
            for f in &frames[1..] {
                let Ok(t) =
                    Technique::build(kind, &context(f, config, scene_bounds), &technique_options)
                else {
                    temporal_ok = false;
                    break;
                };
                let Ok(m) = t.rasterize(&config.scene.mesh, &raster) else {
                    temporal_ok = false;
                    break;
                };
                texels.push(texels_of(&t, &fixed));
                lit.push(lit_of(&t, &m, &fixed));
            }
            Ok(RowMetrics {
                layers: technique.layers(),
                layer_side: technique.layer_sizes().first().map_or(0, |s| s.0),
                texels: technique.texels(),
                aliasing,
                misclassification: miss,
                phase_jitter: if temporal_ok {
                    phase_jitter(&texels)
                } else {
                    None
                },
                flip_rate: if temporal_ok { flip_rate(&lit) } else { None },
            })
        })();
        rows.push(Row {
            config: config.name.clone(),
            technique: kind,
            outcome: outcome.map_err(|e| match e {
                EvalError::Technique { reason, .. } => reason,
                other => other.to_string(),
            }),
        });
        bar.inc(1);
    }
    Ok(ConfigOutput {
        summary,
        rows,
        files,
    })
}

fn context<'a>(f: &'a Frame, config: &'a Configuration, scene: SceneBounds) -> FrameContext<'a> {
    FrameContext {
        camera: &f.camera,
        light: &config.light,
        scene,
        eye_samples: &f.samples,
        pixels_per_radian: f.screen.pixels_per_radian().unwrap_or(1.0) as f32,
    }
}

fn texels_of(t: &Technique, points: &[glam::DVec3]) -> Vec<Option<(DVec2, u32)>> {
    let sizes = t.layer_sizes();
    points
        .iter()
        .map(|&p| {
            let s = t.map_point(p)?;
            let (w, h) = *sizes.get(s.layer as usize)?;
            Some((s.uv * DVec2::new(f64::from(w), f64::from(h)), s.layer))
        })
        .collect()
}

fn lit_of(
    t: &Technique,
    map: &crate::raster::DepthMap,
    points: &[glam::DVec3],
) -> Vec<Option<bool>> {
    points
        .iter()
        .map(|&p| t.map_point(p).and_then(|s| map.is_lit(&s, LOOKUP_BIAS)))
        .collect()
}

// ---------------------------------------------------------------- images

/// An RGB image.
struct Image {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

const BACKGROUND: [u8; 3] = [128, 128, 128];
const UNCOVERED: [u8; 3] = [48, 48, 48];
const ABOVE_SCALE: [u8; 3] = [220, 30, 30];

/// Viridis at 9 evenly spaced points (0, 1/8, ..., 1).
const VIRIDIS: [[u8; 3]; 9] = [
    [68, 1, 84],
    [71, 44, 122],
    [59, 81, 139],
    [44, 113, 142],
    [33, 144, 141],
    [39, 173, 129],
    [92, 200, 99],
    [170, 220, 50],
    [253, 231, 37],
];

/// The heatmap colour of an aliasing error (see the module docs).
#[must_use]
pub fn heat_colour(m: f64) -> [u8; 3] {
    if m.is_nan() {
        return UNCOVERED;
    }
    if m > 10.0 {
        return ABOVE_SCALE;
    }
    let t = m.max(1.0).log10().clamp(0.0, 1.0) * 8.0;
    let i = (t.floor() as usize).min(7);
    let f = t - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    core::array::from_fn(|k| {
        (f64::from(a[k]) + (f64::from(b[k]) - f64::from(a[k])) * f).round() as u8
    })
}

fn heatmap_image(w: u32, h: u32, gbuffer: &GBuffer, m: &[Option<f64>]) -> Image {
    let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
    for (s, e) in gbuffer.surfaces.iter().zip(m) {
        let c = match (s, e) {
            (None, _) => BACKGROUND,
            (Some(_), None) => UNCOVERED,
            (Some(_), Some(e)) => heat_colour(*e),
        };
        rgb.extend_from_slice(&c);
    }
    Image {
        width: w,
        height: h,
        rgb,
    }
}

/// Three panels: technique, ray-traced truth, differences (red: lit but should be in
/// shadow; blue: shadowed but should be lit), separated by 2-pixel white bars.
fn mask_image(w: u32, h: u32, technique: &[Option<bool>], truth: &[Option<bool>]) -> Image {
    const LIT: [u8; 3] = [235, 225, 200];
    const SHADOW: [u8; 3] = [40, 50, 80];
    const GAP: u32 = 2;
    let width = 3 * w + 2 * GAP;
    let mut rgb = vec![255u8; width as usize * h as usize * 3];
    let class = |l: Option<bool>| match l {
        Some(true) => LIT,
        Some(false) => SHADOW,
        None => BACKGROUND,
    };
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let (t, g) = (technique[i], truth[i]);
            let diff = match (g, t.unwrap_or(true)) {
                (None, _) => BACKGROUND,
                (Some(false), true) => [220, 40, 40],
                (Some(true), false) => [40, 90, 230],
                (Some(_), _) => [200, 200, 200],
            };
            // An uncovered visible pixel reads as lit, like the shader.
            let t_shown = if g.is_some() {
                class(Some(t.unwrap_or(true)))
            } else {
                BACKGROUND
            };
            for (panel, c) in [(0, t_shown), (1, class(g)), (2, diff)] {
                let px = panel * (w + GAP) + x;
                let k = (y * width + px) as usize * 3;
                rgb[k..k + 3].copy_from_slice(&c);
            }
        }
    }
    Image {
        width,
        height: h,
        rgb,
    }
}

fn legend_image() -> Image {
    let (w, h) = (330u32, 20u32);
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for _ in 0..h {
        for x in 0..w {
            // 0..300: m from 1 to 10 (log); 300..330: above 10.
            let c = if x < 300 {
                heat_colour(10f64.powf(f64::from(x) / 299.0))
            } else {
                ABOVE_SCALE
            };
            rgb.extend_from_slice(&c);
        }
    }
    Image {
        width: w,
        height: h,
        rgb,
    }
}

fn write_png(path: &Path, image: &Image) -> Result<(), EvalError> {
    let err = |source: std::io::Error| EvalError::Write {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(err)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), image.width, image.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder
        .write_header()
        .map_err(|e| err(std::io::Error::other(e)))?;
    writer
        .write_image_data(&image.rgb)
        .map_err(|e| err(std::io::Error::other(e)))?;
    writer.finish().map_err(|e| err(std::io::Error::other(e)))
}

fn write_file(path: &Path, text: &str) -> Result<(), EvalError> {
    let err = |source| EvalError::Write {
        path: path.to_path_buf(),
        source,
    };
    let mut f = std::fs::File::create(path).map_err(err)?;
    f.write_all(text.as_bytes()).map_err(err)
}

// ---------------------------------------------------------------- tables

fn sci(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.6e}"),
        _ => String::new(),
    }
}

/// The CSV of a report (see the module docs for its guarantees).
#[must_use]
pub fn metrics_csv(report: &Report) -> String {
    let mut s = String::from(
        "config,technique,status,layers,layer_side,texels,visible_pixels,measured_pixels,\
         m_mean,m_median,m_p95,m_max,m_persp_median,m_persp_p95,m_persp_max,\
         storage_factor,storage_factor_persp,storage_factor_sep_persp,used_texel_fraction,\
         misclassification,phase_jitter,flip_rate,log_bound\n",
    );
    for row in &report.rows {
        let bound = report
            .configs
            .iter()
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

fn short(x: Option<f64>) -> String {
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

fn percent(x: Option<f64>) -> String {
    x.filter(|v| v.is_finite())
        .map_or_else(|| "-".into(), |v| format!("{:.2}%", v * 100.0))
}

/// The summary table printed by `compare`: per configuration, each technique's
/// median and max `m`, `S` and misclassification.
#[must_use]
pub fn summary_table(report: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<14} {:<16} {:>10} {:>10} {:>10} {:>9}",
        "config", "technique", "median m", "max m", "S", "misclass"
    );
    for row in &report.rows {
        match &row.outcome {
            Ok(r) => {
                let m = r.aliasing.m;
                let _ = writeln!(
                    s,
                    "{:<14} {:<16} {:>10} {:>10} {:>10} {:>9}",
                    row.config,
                    row.technique.name(),
                    short(m.map(|m| m.median)),
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

fn markdown(report: &Report) -> String {
    let st = &report.settings;
    let mut s = String::new();
    let _ = writeln!(s, "# Shadow-map technique comparison\n");
    let _ = writeln!(
        s,
        "Image {}×{} pixels; texel budget {} texels per technique (all layers); camera \
         paths of {} frames; scene seed {}. Produced by \
         `cargo run --release -p shadowmap-eval --bin compare`.\n",
        st.width, st.height, st.texel_budget, st.path_frames, report.seed
    );
    s.push_str(
        "Columns (GUIDE §5; definitions in `shadowmap_eval::metrics`): `m` is the aliasing \
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
         blue: shadowed but lit).\n\n",
    );
    for c in &report.configs {
        let _ = writeln!(s, "## {}\n", c.name);
        let _ = writeln!(
            s,
            "{} Scene `{}`, {} light, depth range {} – {}, {} visible pixels.\n",
            c.description,
            c.scene,
            c.light_kind,
            c.depth_range.0,
            c.depth_range.1,
            c.visible_pixels
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
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_scale_ends() {
        assert_eq!(heat_colour(0.5), VIRIDIS[0]);
        assert_eq!(heat_colour(1.0), VIRIDIS[0]);
        assert_eq!(heat_colour(10.0), VIRIDIS[8]);
        assert_eq!(heat_colour(10.5), ABOVE_SCALE);
        assert_eq!(heat_colour(f64::NAN), UNCOVERED);
        // Monotone in the green channel over the scale.
        let g: Vec<u8> = (0..=20)
            .map(|k| heat_colour(10f64.powf(f64::from(k) / 20.0))[1])
            .collect();
        assert!(g.windows(2).all(|w| w[0] <= w[1]));
    }
}
