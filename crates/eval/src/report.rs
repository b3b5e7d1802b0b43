//! The `compare` report: every technique on every configuration, side by side.
//!
//! [`run`] is what the `compare` binary calls. For each configuration it traces
//! the G-buffer of every frame of the camera path, the ray-traced shadow mask of
//! frame 0, and for each technique that applies to the light:
//!
//! - frame 0: the aliasing metrics of every visible pixel ([`crate::metrics`]), the
//!   depth map from the reference rasterizer, the shadow mask and its
//!   misclassification against the ray-traced mask (over front-lit pixels, see
//!   [`crate::metrics::FRONT_LIT_MIN_COS`]), and the images;
//! - every frame: the technique refitted to the moved camera, its sub-texel phase at
//!   fixed world points (front-lit points of frame 0, every
//!   [`Settings::temporal_stride`]-th pixel) and their shadow test, for the phase
//!   jitter and the flip rate.
//!
//! The depth pass uses a slope-scaled bias (1.5 texels of slope plus 16 units of the
//! smallest resolvable depth, the same for every technique) and the lookup
//! `1e-5` depth units; nearest-texel lookups, no filtering.
//!
//! Output in [`Options::out`]: `index.html` (the page to read: every table,
//! picture and plot below, labelled, with the definitions; self-contained, it opens
//! from disk), `report.md`, `metrics.csv` (the techniques), `references.csv` (the
//! references of [`TechniqueKind::is_reference`], same columns: the engines' cube
//! maps, the bar of the focused cube maps, named in a line under each point
//! configuration's table, not in it), `legend.png` and `colorbar.svg` (the
//! heatmaps' colour scale), per configuration `aliasing_<config>.svg` (the p95 of
//! the aliasing error per view-depth slice of every technique, with the
//! pixel-matched and logarithmic limits, drawn with `plotters`), and per technique
//! and configuration `heatmap_<config>_<technique>.png` (aliasing error over the
//! screen) and `mask_<config>_<technique>.png` (three panels: the technique's
//! shadow mask, the ray-traced mask, the misclassified pixels, over the pixels the
//! misclassification counts; the others background grey). With
//! [`Options::sweep`], the sweep's rows join the two CSVs (their `config` is the
//! sweep case, `random_<scene>_<k>`), `report.md` ends with the sweep's wins, ties
//! and losses per technique and `sweep.svg` plots them; the sweep writes no other
//! pictures. The images the wgpu backend's `render_scene` example writes into
//! `rendered/` of the report directory are kept from one report to the next and
//! shown on the page.
//!
//! The output is all or nothing: every input (options, mesh file, output directory)
//! is checked before the first configuration is evaluated, the files are written
//! into a staging directory beside [`Options::out`], and that directory replaces
//! the previous report only when every file is complete. A failed run leaves the
//! previous report as it was and no partial files; a successful one leaves no file
//! of an earlier run. An existing [`Options::out`] that holds anything other than
//! report files is refused rather than replaced.
//!
//! The CSVs are deterministic: fixed row order (configurations, then techniques
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
//! [`crate::metrics::FRONT_LIT_MIN_COS`]), points the technique does not cover, degenerate
//! Jacobians. `legend.png` shows the scale.

mod evaluate;
mod html;
mod image;
mod output;
mod plots;
mod runner;
mod sweep;
mod text;

use std::path::PathBuf;

use crate::metrics::AliasingStats;
use crate::technique::TechniqueKind;

pub use image::heat_colour;
pub use runner::run;
pub use sweep::{SweepSummary, SweepTally, TIE_BAND, WorstCase, baseline_of};
pub use text::{metrics_csv, references_csv, summary_table};

/// What to run.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Options {
    /// Output directory: created, or replaced as a whole when it holds a previous
    /// report.
    pub out: PathBuf,
    /// Small images, short paths and a small budget (for tests and CI).
    pub quick: bool,
    /// Seed of the procedural scenes.
    pub seed: u64,
    /// A user mesh (OBJ / glTF) to add as a configuration.
    pub mesh: Option<PathBuf>,
    /// Random configurations per scene for the robustness sweep (0: no sweep; see
    /// [`crate::config::sweep_configurations`]), measured at [`Settings::sweep`].
    pub sweep: usize,
    /// Worker threads (at least 1).
    pub threads: usize,
    /// Only the configurations (standard and sweep) whose name contains one of
    /// these strings; every configuration when empty. To re-measure a sweep's
    /// worst case alone: `compare --sweep 64 --only random_city_block_006`.
    pub only: Vec<String>,
    /// Show a progress bar on stderr (for a terminal): the current configuration
    /// and technique, and an estimate of the time left.
    pub progress: bool,
    /// Print one line on stderr per finished configuration (for logs and pipes,
    /// where a bar would not show).
    pub progress_lines: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            out: PathBuf::from("target/shadowmap-report"),
            quick: false,
            seed: DEFAULT_SEED,
            mesh: None,
            sweep: 0,
            threads: 2,
            only: Vec::new(),
            progress: false,
            progress_lines: false,
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
    /// Only the configurations whose name contains one of `names` (all when empty).
    #[must_use]
    pub fn with_only(mut self, names: Vec<String>) -> Self {
        self.only = names;
        self
    }
    /// With a robustness sweep of `cases` random configurations per scene.
    #[must_use]
    pub const fn with_sweep(mut self, cases: usize) -> Self {
        self.sweep = cases;
        self
    }
    /// With or without a progress bar.
    #[must_use]
    pub const fn with_progress(mut self, progress: bool) -> Self {
        self.progress = progress;
        self
    }
    /// With or without one progress line per finished configuration.
    #[must_use]
    pub const fn with_progress_lines(mut self, lines: bool) -> Self {
        self.progress_lines = lines;
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

    /// The sizes of each sweep case: the quick run's image, budget and RTW side
    /// (the ratio of texels to pixels is close to a full run's), one frame (the
    /// sweep compares aliasing, not temporal stability).
    #[must_use]
    pub const fn sweep() -> Self {
        Self {
            path_frames: 1,
            ..Self::new(true)
        }
    }
}

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
    /// One row per configuration and applicable technique, in order; the sweep's
    /// rows follow the configurations' (their `config` is the sweep case).
    pub rows: Vec<Row>,
    /// The rows of the references ([`TechniqueKind::is_reference`]: the engines'
    /// cube maps), per configuration and sweep case, in the rows' order; in
    /// `references.csv`, not among the techniques.
    pub references: Vec<Row>,
    /// The sweep's cases, in order (empty without a sweep).
    pub sweep_configs: Vec<ConfigSummary>,
    /// Wins, ties and losses of each technique against its baseline over the sweep.
    pub sweep: Option<SweepSummary>,
    /// Files written, relative to the output directory, sorted.
    pub files: Vec<PathBuf>,
}
