//! Command-line interface: argument types (clap derive) and dispatch. `main.rs` only parses,
//! calls [`run`] and maps the [`Outcome`] or error to an exit code.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::analysis::{analyze, AnalysisOptions};
use crate::config::Config;
use crate::error::Result;
use crate::output::{self, Exporter};
use crate::plots;
use crate::precision::{self, Precision};

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
    /// Run a battery of pathological inputs through validation and analysis, check invariants,
    /// write stress.csv; exit 1 if an invariant fails.
    Stress(StressArgs),
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
    /// Arithmetic of the cascade pipeline, overriding `[shadow] precision`: f64 (exact) or f32
    /// (an engine's binary32 pipeline, emulated; see `snap_space`).
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
}

#[derive(Debug, Args)]
pub struct StressArgs {
    /// Output directory for stress.csv.
    #[arg(long, default_value = "reports/stress")]
    pub out: PathBuf,
    /// Random cases added to the fixed battery (0..=100000).
    #[arg(long, default_value_t = 32)]
    pub cases: u64,
    /// Seed of the random cases (same seed, same cases, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Also fail a case whose f32 drift (texels per frame, either snap space) exceeds this.
    /// By default f32 residuals are reported, not judged.
    #[arg(long, value_name = "TEXELS", allow_negative_numbers = true)]
    pub max_f32_drift: Option<f64>,
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
        Command::Stress(args) => run_stress(&args),
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
    let mut config = Config::load(&args.config)?;
    if let Some(p) = args.precision {
        config.shadow.precision = p;
        if p == Precision::F32 {
            if let Some(why) = precision::f32_range_problem(&config) {
                return Err(crate::error::Error::flag("--precision", "f32", why));
            }
        }
    }
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

fn run_stress(args: &StressArgs) -> Result<Outcome> {
    use crate::error::Error;
    use crate::stress;
    if args.cases > 100_000 {
        return Err(Error::flag(
            "--cases",
            &args.cases.to_string(),
            "at most 100000 random cases",
        ));
    }
    if let Some(limit) = args.max_f32_drift {
        if !(limit.is_finite() && limit >= 0.0) {
            return Err(Error::flag(
                "--max-f32-drift",
                &limit.to_string(),
                "a finite number of texels >= 0",
            ));
        }
    }
    let mut cases = stress::battery();
    cases.extend(stress::random_cases(args.cases as usize, args.seed));
    let opts = stress::StressOptions {
        max_f32_drift: args.max_f32_drift,
    };
    let results = stress::run(&cases, &opts);
    let bytes = stress::csv(&results)?;
    output::write_files(&args.out, &[("stress.csv", bytes)])?;
    print!("{}", stress::table(&results));
    println!("wrote {}", args.out.join("stress.csv").display());
    Ok(if results.iter().all(|r| r.pass()) {
        Outcome::Success
    } else {
        Outcome::ThresholdViolated
    })
}
