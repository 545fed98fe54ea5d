//! Command-line interface: argument types (clap derive) and dispatch. `main.rs` only parses,
//! calls [`run`] and maps the [`Outcome`] or error to an exit code.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::analysis::{analyze, AnalysisOptions};
use crate::config::Config;
use crate::error::Result;
use crate::output::{self, Exporter};
use crate::plots;

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
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Build the cascades of one scene and shadow setting, measure them, write CSV/JSON/SVG.
    Analyze(AnalyzeArgs),
    /// Gate on quality: judge threshold rules and compare with a baseline (exit 1 on failure).
    Check(CheckArgs),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Table,
    Json,
}

#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// Scene and shadow settings (TOML).
    pub config: PathBuf,
    /// Output directory [default: reports/<config name>/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// What to print on stdout.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
}

#[derive(Debug, Args)]
pub struct CheckArgs {
    /// Scene and shadow settings (TOML).
    pub config: PathBuf,
    /// Rules and baseline tolerances (TOML; see docs/check.md).
    #[arg(long)]
    pub thresholds: PathBuf,
    /// An earlier summary.json (or, with --sweep, sweep.csv) to compare against.
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// Judge sweep rows (summary metrics only) instead of the one configuration.
    #[arg(long)]
    pub sweep: bool,
    /// Also write a JUnit XML report to this file.
    #[arg(long)]
    pub junit: Option<PathBuf>,
    /// What to print on stdout.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
}

/// How a successful run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Exit code 0.
    Success,
    /// A quality threshold was violated: exit code 1.
    ThresholdViolated,
}

impl Outcome {
    pub fn exit_code(self) -> i32 {
        match self {
            Outcome::Success => 0,
            Outcome::ThresholdViolated => 1,
        }
    }
}

/// The default output directory for a config: `reports/<name>/`.
pub fn default_out_dir(config: &Config) -> PathBuf {
    Path::new("reports").join(&config.name)
}

pub fn run(cli: Cli) -> Result<Outcome> {
    match cli.command {
        Command::Analyze(args) => run_analyze(&args),
        Command::Check(args) => crate::check::run_check(&args),
    }
}

/// The exporters `analyze` writes, in order.
pub fn analyze_exporters() -> Vec<&'static dyn Exporter<crate::analysis::Analysis>> {
    vec![
        &output::CascadesCsv,
        &output::DensityCsv,
        &output::ShimmerCsv,
        &output::SummaryJson,
        &plots::DensitySvg,
        &plots::ShimmerSvg,
        &plots::CascadesSvg,
    ]
}

fn run_analyze(args: &AnalyzeArgs) -> Result<Outcome> {
    let config = Config::load(&args.config)?;
    let analysis = analyze(&config, &AnalysisOptions::full());
    let dir = args.out.clone().unwrap_or_else(|| default_out_dir(&config));
    let written = output::export_all(&dir, &analysis, &analyze_exporters())?;
    match args.format {
        Format::Table => {
            print!("{}", output::summary_table(&analysis));
            println!("wrote {} files to {}", written.len(), dir.display());
        }
        Format::Json => {
            let bytes = output::json_bytes("summary", &output::summary_value(&analysis))?;
            print!("{}", String::from_utf8_lossy(&bytes));
            eprintln!("wrote {} files to {}", written.len(), dir.display());
        }
    }
    Ok(Outcome::Success)
}
