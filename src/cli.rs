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
    /// Time against error of every sampled metric; writes bench.csv and bench.svg.
    Bench(BenchArgs),
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
pub struct BenchArgs {
    /// Output directory [default: reports/bench/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Scene to measure [default: the built-in configs/default.toml].
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Timed repetitions per point; the best is kept (1..=1000).
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
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
        Command::Bench(args) => run_bench(&args),
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

/// The scene `bench` measures when no `--config` is given.
pub const DEFAULT_SCENE: &str = include_str!("../configs/default.toml");

fn run_bench(args: &BenchArgs) -> Result<Outcome> {
    if !(1..=1000).contains(&args.repeats) {
        return Err(crate::error::Error::flag(
            "--repeats",
            &args.repeats.to_string(),
            "allowed: an integer in 1..=1000",
        ));
    }
    let config = match &args.config {
        Some(path) => Config::load(path)?,
        None => {
            let mut c = Config::from_toml_str(DEFAULT_SCENE, "configs/default.toml (built in)", None)?;
            c.name = "default".to_string();
            c
        }
    };
    let report = crate::bench::run(&config, args.repeats as usize)?;
    let dir = args.out.clone().unwrap_or_else(|| Path::new("reports").join("bench"));
    let exporters: [&dyn Exporter<crate::bench::BenchReport>; 2] = [&crate::bench::BenchCsv, &crate::bench::BenchSvg];
    let written = output::export_all(&dir, &report, &exporters)?;
    print!("{}", report.table());
    println!("wrote {} files to {}", written.len(), dir.display());
    Ok(Outcome::Success)
}
