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
    /// Run several engine presets on one scene and compare them (CSV, plots, HTML, Markdown).
    Compare(CompareArgs),
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
    /// Reproduce an engine's cascades instead of csm-lab's own (overrides shadow.preset):
    /// dart, threejs, unity-sample, eevee, learnopengl, bevy, godot, unreal, unity, unity-urp, filament.
    #[arg(long)]
    pub preset: Option<String>,
}

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// Scene file (TOML); its camera, screen, light, scene and motion are shared by every preset.
    pub config: PathBuf,
    /// Comma-separated presets to compare [default: all].
    #[arg(long)]
    pub presets: Option<String>,
    /// Every preset at its own defaults: ignore shadow.cascades, shadow.resolution and shadow.max_distance.
    #[arg(long)]
    pub defaults: bool,
    /// Output directory [default: reports/<config name>/].
    #[arg(long)]
    pub out: Option<PathBuf>,
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
        Command::Compare(args) => run_compare(&args),
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
    let choice = crate::presets::PresetChoice {
        name: args
            .preset
            .as_deref()
            .map(|s| crate::presets::parse_flag("--preset", s))
            .transpose()?,
        ..Default::default()
    };
    let config = Config::load_with_preset(&args.config, &choice)?;
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

fn run_compare(args: &CompareArgs) -> Result<Outcome> {
    let presets = match &args.presets {
        Some(list) => crate::presets::parse_list("--presets", list)?,
        None => crate::presets::PresetName::ALL.to_vec(),
    };
    let comparison = crate::compare::run(&args.config, &presets, args.defaults)?;
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&comparison.analyses[0].config));
    let written = output::export_all(&dir, &comparison, &crate::compare::exporters())?;
    print!("{}", crate::compare::summary_table(&comparison));
    println!("wrote {} files to {}", written.len(), dir.display());
    Ok(Outcome::Success)
}
