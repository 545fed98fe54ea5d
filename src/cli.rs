//! Command-line interface: argument types (clap derive) and dispatch. `main.rs` only parses,
//! calls [`run`] and maps the [`Outcome`] or error to an exit code.

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::analysis::{analyze, AnalysisOptions};
use crate::config::Config;
use crate::error::Result;
use crate::output::{self, Exporter};
use crate::plots;
use crate::precision::Precision;

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
    /// Sweep λ × cascades × resolution (× fit) in parallel; write CSV, plots and a report.
    Sweep(SweepArgs),
    /// Gate on quality: judge threshold rules and compare with a baseline (exit 1 on failure).
    Check(CheckArgs),
    /// Run a battery of pathological inputs through validation and analysis, check invariants,
    /// write stress.csv; exit 1 if an invariant fails.
    Stress(StressArgs),
    /// Time against error of every sampled metric; writes bench.csv and bench.svg.
    Bench(BenchArgs),
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
    /// Arithmetic of the cascade pipeline, overriding `[shadow] precision`: f64 (exact) or f32
    /// (an engine's binary32 pipeline, emulated; see `snap_space`).
    #[arg(long, value_parser = precision_parser())]
    pub precision: Option<Precision>,
    /// Reproduce an engine's cascades instead of csm-lab's own (overrides shadow.preset):
    /// dart, threejs, unity-sample, eevee, learnopengl, bevy, godot, unreal, unity, unity-urp, filament.
    #[arg(long)]
    pub preset: Option<String>,
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

#[derive(Debug, Args)]
pub struct SweepArgs {
    /// Scene and shadow settings (TOML); its `[sweep]` table gives the grid.
    pub config: PathBuf,
    /// Output directory [default: reports/<config name>/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// λ axis: start:end:step (0:1:0.05) or a list (0,0.5,1).
    #[arg(long, value_name = "SPEC")]
    pub lambda: Option<String>,
    /// Cascade counts: a range (1..8) or a list (2,4).
    #[arg(long, value_name = "SPEC")]
    pub cascades: Option<String>,
    /// Resolutions: a list (1024,2048).
    #[arg(long, value_name = "SPEC")]
    pub resolution: Option<String>,
    /// Fits: sphere, aabb or sphere,aabb.
    #[arg(long, value_name = "SPEC")]
    pub fit: Option<String>,
    /// Worker threads [default: one per core]. Results are identical at any count.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    pub threads: Option<u16>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Skip the SVG/PNG figures (the report is written without them).
    #[arg(long)]
    pub no_plots: bool,
    /// Sweep an engine preset's own axes (overrides shadow.preset); see `analyze --preset`.
    #[arg(long)]
    pub preset: Option<String>,
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

/// Loads a config, with `--preset NAME` (when given) overriding `shadow.preset`.
fn load_with_preset_flag(path: &Path, preset: Option<&str>) -> Result<Config> {
    let choice = crate::presets::PresetChoice {
        name: preset.map(|s| crate::presets::parse_flag("--preset", s)).transpose()?,
        ..Default::default()
    };
    Config::load_with_preset(path, &choice)
}

/// The default output directory for a config: `reports/<name>/`.
pub fn default_out_dir(config: &Config) -> PathBuf {
    Path::new("reports").join(&config.name)
}

pub fn run(cli: Cli) -> Result<Outcome> {
    match cli.command {
        Command::Analyze(args) => run_analyze(&args),
        Command::Sweep(args) => run_sweep(&args),
        Command::Check(args) => crate::check::run_check(&args),
        Command::Stress(args) => run_stress(&args),
        Command::Bench(args) => run_bench(&args),
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

/// `--precision`: the core's [`Precision`], listed with a line of help per value.
fn precision_parser() -> impl clap::builder::TypedValueParser<Value = Precision> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new([
        PossibleValue::new("f64").help("Exact: texel-unit windows, snapped shimmer exactly 0 at any world offset"),
        PossibleValue::new("f32").help("An engine's binary32 pipeline, emulated operation by operation"),
    ])
    .map(|s| Precision::from_name(&s).expect("one of the listed values"))
}

fn run_analyze(args: &AnalyzeArgs) -> Result<Outcome> {
    let mut config = load_with_preset_flag(&args.config, args.preset.as_deref())?;
    if let Some(p) = args.precision {
        // Through the validating constructor; a refusal names the flag that asked for it.
        config = config.with_precision(p).map_err(|e| match e {
            crate::error::Error::Invalid { allowed, .. } => crate::error::Error::flag("--precision", p.name(), allowed),
            other => other,
        })?;
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

/// Runs a sweep as the CLI does, without printing: (result, rendered files).
pub fn sweep_files(args: &SweepArgs) -> Result<(crate::report::SweepResult, output::RenderedFiles)> {
    use crate::sweep::{self, Grid, GridOverrides};
    let config = load_with_preset_flag(&args.config, args.preset.as_deref())?;
    let overrides = GridOverrides {
        lambda: args.lambda.as_deref().map(sweep::parse_lambda_spec).transpose()?,
        cascades: args.cascades.as_deref().map(sweep::parse_cascades_spec).transpose()?,
        resolution: args
            .resolution
            .as_deref()
            .map(sweep::parse_resolution_spec)
            .transpose()?,
        fit: args.fit.as_deref().map(sweep::parse_fit_spec).transpose()?,
    };
    let grid = Grid::resolve(&config, &overrides)?;
    if !args.quiet {
        for note in &grid.notes {
            eprintln!("note: {note}");
        }
    }
    let show_progress = !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bar = if show_progress {
        let bar = indicatif::ProgressBar::new(grid.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} sweeping {pos}/{len} configurations {wide_bar} {eta}")
                .expect("valid template"),
        );
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    let start = std::time::Instant::now();
    let rows = sweep::run(&config, &grid, args.threads.map(usize::from), &|| bar.inc(1))?;
    bar.finish_and_clear();
    let compute = start.elapsed();
    let preset = match &config.shadow.preset {
        Some(p) => format!(" --preset {}", p.name),
        None => String::new(),
    };
    let command = format!(
        "csm-lab sweep {}{preset} {}",
        args.config.display(),
        grid.cli_args(&config)
    );
    let result = crate::report::SweepResult::new(config, grid, rows, command);
    let files = crate::report::render_all(&result, !args.no_plots)?;
    if !args.quiet {
        eprintln!(
            "analysed {} configurations in {:.1} ms",
            result.rows.len(),
            compute.as_secs_f64() * 1e3
        );
    }
    Ok((result, files))
}

fn run_sweep(args: &SweepArgs) -> Result<Outcome> {
    let (result, files) = sweep_files(args)?;
    let dir = args.out.clone().unwrap_or_else(|| default_out_dir(&result.config));
    let written = output::write_files(&dir, &files)?;
    match args.format {
        Format::Table => {
            print!("{}", crate::report::stdout_table(&result));
            println!("wrote {} files to {}", written.len(), dir.display());
        }
        Format::Json => {
            let bytes = output::json_bytes("recommendation", &crate::report::recommendation_value(&result))?;
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
