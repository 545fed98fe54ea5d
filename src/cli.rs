//! Command-line interface: the argument types (clap derive) and the dispatch to each
//! command's module in [`crate::commands`]. `main.rs` only parses, calls [`run`] and maps the
//! [`Outcome`] or error to an exit code.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::app::{analyze, bench, check, compare, merge, stress, sweep};
use crate::error::Result;

pub use crate::app::Format;
pub(crate) use crate::app::Outcome;

#[derive(Debug, Parser)]
#[command(
    name = "csm-lab",
    version,
    about = "Measure cascaded shadow maps (texel density, aliasing, shimmer, coverage) before rendering a frame",
    long_about = None
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// When another csm-lab run is writing the output directory, stop with an error (exit 2)
    /// instead of waiting for it to finish.
    #[arg(long, global = true)]
    pub no_wait: bool,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Build the cascades of one scene and shadow setting, measure them, write CSV/JSON/SVG.
    Analyze(analyze::AnalyzeRequest),
    /// Sweep λ × cascades × resolution (× fit) in parallel; write CSV, plots and a report.
    Sweep(Box<SweepArgs>),
    /// Gate on quality: judge threshold rules and compare with a baseline (exit 1 on failure).
    Check(CheckArgs),
    /// Run a battery of pathological inputs through validation and analysis, check invariants,
    /// write stress.csv; exit 1 if an invariant fails.
    Stress(stress::StressRequest),
    /// Time against error of every sampled metric; writes bench.csv and bench.svg.
    Bench(bench::BenchRequest),
    /// Run several engine presets on one scene and compare them (CSV, plots, HTML, Markdown).
    Compare(compare::CompareRequest),
    /// Join the shards of a sweep (`sweep --shard K/N`) into the files the unsharded sweep writes.
    Merge(merge::MergeRequest),
}

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Scene and shadow settings (TOML); its `[sweep]` table gives the grid.
    pub config: PathBuf,
    /// Output directory [default: out/<config name>/sweep/, or sweep-<engine>/ with --preset].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The grid's axes (each overrides its `[sweep]` key) and `--preset`.
    #[command(flatten)]
    pub grid: crate::commands::sweep::grid::GridFlags,
    /// Worker threads, 1..=256 [default: one per core]. Results are identical at any count.
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u16).range(1..=256))]
    pub threads: Option<u16>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Skip the SVG/PNG figures (the report is written without them).
    #[arg(long)]
    pub no_plots: bool,
    /// What to print on stdout.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
    /// Run only the K-th of N disjoint slices of the grid (K from 1 to N; row i goes to shard
    /// i mod N + 1); `csm-lab merge` joins the N shard directories [default --out:
    /// out/<config name>/sweep/shard-K-of-N/, in sweep-<engine>/ with --preset].
    #[arg(long, value_name = "K/N", allow_hyphen_values = true)]
    pub shard: Option<String>,
    /// Also find the free split fractions that minimise the objective for each cascade count
    /// and resolution, starting from the best λ (csm-lab's own pipeline and the unity,
    /// unity-urp, godot and filament presets); writes optimized_splits.csv. Also
    /// `[sweep] optimize_splits = true`.
    #[arg(long)]
    pub optimize_splits: bool,
    /// Also measure the shadow-map flicker S5 of a sample of the rows (every row of a grid of
    /// at most 12, else 12 rows spread over the grid, with the recommended one) beside S3 and S4;
    /// writes flicker.csv and flicker_vs_shimmer.svg/png. Needs scene geometry. Also
    /// `[sweep] ground_truth = true`.
    #[arg(long)]
    pub ground_truth: bool,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Scene and shadow settings (TOML).
    pub config: PathBuf,
    /// Rules and baseline tolerances (TOML; see docs/check.md).
    #[arg(long, required_unless_present = "init", conflicts_with = "init")]
    pub thresholds: Option<PathBuf>,
    /// Write a thresholds file here from the config's current values (with --headroom), and
    /// its baseline beside it (`NAME.baseline.json`); then commit both.
    #[arg(long, value_name = "FILE")]
    pub init: Option<PathBuf>,
    /// With --init: room each limit leaves over today's value, as a fraction (0.05 = 5 %).
    #[arg(long, default_value_t = 0.05, requires = "init")]
    pub headroom: f64,
    /// An earlier summary.json (or, with --sweep, sweep.csv) to compare against [default: the
    /// thresholds file's `[baseline] file`].
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// Judge sweep rows (summary metrics only) instead of the one configuration.
    #[arg(long)]
    pub sweep: bool,
    /// With --sweep: judge the rows of this sweep.csv instead of running the sweep (e.g. the
    /// output of `csm-lab merge`); its configurations must be the config's `[sweep]` grid.
    #[arg(long, value_name = "FILE", requires = "sweep")]
    pub sweep_csv: Option<PathBuf>,
    /// With --sweep: list every configuration instead of a summary.
    #[arg(long)]
    pub verbose: bool,
    /// With --sweep: gate every configuration of the grid, not only what the sweep decides
    /// (the recommendation and the configured setting).
    #[arg(long, requires = "sweep")]
    pub all_rows: bool,
    /// Also write a JUnit XML report to this file.
    #[arg(long)]
    pub junit: Option<PathBuf>,
    /// What to print on stdout.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
}

/// Runs the parsed command.
pub fn run(cli: Cli) -> Result<Outcome> {
    crate::output::set_wait_for_lock(!cli.no_wait);
    match cli.command {
        Command::Analyze(request) => analyze::execute(&request),
        Command::Sweep(args) => sweep::execute(&sweep::SweepRequest {
            config: args.config,
            out: args.out,
            grid: args.grid,
            threads: args.threads,
            quiet: args.quiet,
            no_plots: args.no_plots,
            format: args.format,
            shard: args.shard,
            optimize_splits: args.optimize_splits,
            ground_truth: args.ground_truth,
        }),
        Command::Check(args) => match (&args.init, &args.thresholds) {
            (Some(file), _) => check::init(&check::InitRequest {
                config: &args.config,
                file,
                headroom: args.headroom,
            }),
            (None, Some(thresholds)) => check::execute(&check::CheckRequest {
                config: &args.config,
                thresholds,
                baseline: args.baseline.as_deref(),
                sweep: args.sweep,
                sweep_csv: args.sweep_csv.as_deref(),
                verbose: args.verbose,
                all_rows: args.all_rows,
                junit: args.junit.as_deref(),
                format: args.format,
            }),
            (None, None) => unreachable!("clap requires --thresholds unless --init"),
        },
        Command::Stress(request) => stress::execute(&request),
        Command::Bench(request) => bench::execute(&request),
        Command::Merge(request) => merge::execute(&request),
        Command::Compare(request) => compare::execute(&request),
    }
}
