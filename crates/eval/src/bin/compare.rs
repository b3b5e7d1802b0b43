//! `compare`: every shadow-map technique on every evaluation configuration.
//!
//! ```text
//! cargo run --release -p shadowmap-eval --bin compare -- [--out DIR] [--quick] [--seed N] [--mesh PATH]
//! ```
//!
//! Prints a summary table (median and max aliasing error, storage factor,
//! misclassification) and writes `report.md`, `metrics.csv` and the PNG images into
//! `--out` (default `target/shadowmap-report`). See `shadowmap_eval::report`.

use std::io::IsTerminal as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use shadowmap_eval::report::{self, DEFAULT_SEED, Options};

/// Compare shadow-map parameterizations: aliasing error, storage factor,
/// misclassification and temporal stability on fixed scenes.
#[derive(Parser, Debug)]
#[command(version, about)]
struct Args {
    /// Output directory for report.md, metrics.csv and the images.
    #[arg(long, default_value = "target/shadowmap-report")]
    out: PathBuf,
    /// Small images, short paths, small budget (about 30 s; for tests and CI).
    #[arg(long)]
    quick: bool,
    /// Seed of the procedural scenes.
    #[arg(long, default_value_t = DEFAULT_SEED)]
    seed: u64,
    /// Also evaluate a mesh (.obj, .gltf, .glb) with an automatic camera and light.
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Worker threads.
    #[arg(long, default_value_t = 2)]
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
        .with_progress(std::io::stderr().is_terminal());
    match report::run(&options) {
        Ok(r) => {
            #[allow(clippy::print_stdout)] // The table is the binary's output.
            {
                print!("{}", report::summary_table(&r));
                println!("\nwrote {} files to {}", r.files.len(), args.out.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("compare: {e}");
            ExitCode::FAILURE
        }
    }
}
