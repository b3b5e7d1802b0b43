//! `compare`: every shadow-map technique on every evaluation configuration.
//!
//! ```text
//! cargo run --release -p shadowmap-eval --bin compare -- [--out DIR] [--quick] [--seed N] [--mesh PATH] [--sweep N] [--only NAME] [--threads N]
//! ```
//!
//! Prints what `m`, `p95` and `S` mean, a summary table (median, p95 and max
//! aliasing error, storage factor, misclassification), the best technique per
//! configuration, and writes `index.html` (the page to open: every table, picture
//! and plot, labelled), `report.md`, `metrics.csv` and the images into `--out`
//! (default `target/shadowmap-report`). See `shadowmap_eval::report`. Progress goes
//! to stderr: a bar on a terminal, one line per finished configuration otherwise.
//!
//! Every input is checked before the run starts; the report is written into a
//! staging directory and replaces the previous one only when complete. Exit status
//! 0 on success, 1 with a message naming the file and the reason on any error, 2
//! for a bad command line.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use shadowmap_eval::report::{self, DEFAULT_SEED, Options};

/// Compares every shadow-map technique on the same scenes at the same texel budget
/// and writes a report to read in a browser (OUT/index.html).
///
/// Measures per technique and configuration the aliasing error m (the largest
/// extent of a shadow-map texel on the screen, in pixels), the storage factor S,
/// the misclassification against ray tracing and the temporal stability along a
/// camera path. A full run takes about 2 minutes on 2 cores.
#[derive(Parser, Debug)]
#[command(version)]
struct Args {
    /// Output directory for index.html, report.md, metrics.csv, the images and
    /// the plots (replaced as a whole; render_scene's rendered/ is kept).
    #[arg(long, default_value = "target/shadowmap-report")]
    out: PathBuf,
    /// Small images, short paths, small budget (about 3 s; for tests and CI).
    #[arg(long)]
    quick: bool,
    /// Seed of the procedural scenes.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    seed: u64,
    /// Also evaluate a mesh (.obj, .gltf, .glb) with an automatic camera and light
    /// (a configuration named mesh_NAME after the file NAME.obj).
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Robustness sweep: this many random camera/light configurations per scene,
    /// every technique against its baseline (0: none).
    #[arg(long, default_value_t = 0)]
    sweep: usize,
    /// Only the configurations (standard and sweep) whose name contains NAME
    /// (repeat for several), e.g. a sweep's worst case:
    /// `--sweep 64 --only random_city_block_006`.
    #[arg(long, value_name = "NAME")]
    only: Vec<String>,
    /// Worker threads (at least 1).
    #[arg(long, default_value_t = 2, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    threads: usize,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let options = Options::default()
        .with_out(args.out.clone())
        .with_quick(args.quick)
        .with_seed(args.seed)
        .with_mesh(args.mesh)
        .with_threads(args.threads)
        .with_sweep(args.sweep)
        .with_only(args.only)
        .with_progress(std::io::stderr().is_terminal())
        .with_progress_lines(!std::io::stderr().is_terminal());
    match report::run(&options) {
        Ok(r) => {
            #[allow(clippy::print_stdout)] // The table is the binary's output.
            {
                print!("{}", report::summary_table(&r));
                println!("\nwrote {} files to {}", r.files.len(), args.out.display());
                println!(
                    "open {} to read the report",
                    args.out.join("index.html").display()
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("compare: {e}");
            ExitCode::FAILURE
        }
    }
}
