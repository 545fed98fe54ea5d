//! `csm-lab sweep`: every configuration of the grid, the Pareto front and the recommendation,
//! written as CSV, JSON, figures and a report.

use std::path::PathBuf;

use super::{default_out_dir, load_for_preset_sweep, print_result, Format, Outcome};
use crate::commands::sweep::*;
use crate::error::Result;
use crate::output;
use crate::report;

/// Runs a sweep as the CLI does, without printing: (result, rendered files, the progress bar,
/// left up for the writing).
pub fn sweep_files(args: &SweepRequest) -> Result<(SweepResult, output::RenderedFiles, super::progress::Progress)> {
    let config = load_for_preset_sweep(&args.config, args.preset.as_deref())?;
    let overrides = GridOverrides {
        lambda: args.lambda.as_deref().map(parse_lambda_spec).transpose()?,
        cascades: args.cascades.as_deref().map(parse_cascades_spec).transpose()?,
        resolution: args.resolution.as_deref().map(parse_resolution_spec).transpose()?,
        fit: args.fit.as_deref().map(parse_fit_spec).transpose()?,
    };
    let grid = Grid::resolve(&config, &overrides)?;
    if !args.quiet {
        for note in &grid.notes {
            eprintln!("note: {note}");
        }
    }
    let progress = super::progress::Progress::new(args.quiet, grid.len() as u64, "configurations");
    let start = std::time::Instant::now();
    let rows = run(&config, &grid, args.threads.map(usize::from), &|| progress.inc(1))?;
    let compute = start.elapsed();
    progress.writing();
    let preset = match &config.shadow.preset {
        Some(p) => format!(" --preset {}", p.name),
        None => String::new(),
    };
    let command = format!(
        "csm-lab sweep {}{preset} {}",
        args.config.display(),
        grid.cli_args(&config)
    );
    let result = SweepResult::new(config, grid, rows, command);
    let files = report::sweep::render_all(&result, !args.no_plots)?;
    if !args.quiet {
        progress.note(&format!(
            "analysed {} configurations in {:.1} ms",
            result.rows.len(),
            compute.as_secs_f64() * 1e3
        ));
    }
    Ok((result, files, progress))
}

/// What `sweep` was asked to do (the command line's flags, as plain values; specs unparsed).
#[derive(Debug, Clone)]
pub struct SweepRequest {
    pub config: PathBuf,
    pub out: Option<PathBuf>,
    pub lambda: Option<String>,
    pub cascades: Option<String>,
    pub resolution: Option<String>,
    pub fit: Option<String>,
    pub threads: Option<u16>,
    pub quiet: bool,
    pub no_plots: bool,
    pub preset: Option<String>,
    pub format: Format,
}

/// The `sweep` command.
pub fn execute(args: &SweepRequest) -> Result<Outcome> {
    let (result, files, progress) = sweep_files(args)?;
    let dir = args.out.clone().unwrap_or_else(|| default_out_dir(&result.config));
    let written = output::write_files(&dir, &files)?;
    progress.finish();
    print_result(
        args.format,
        || report::sweep::stdout_table(&result),
        || output::json_bytes("recommendation", &report::sweep::recommendation_value(&result)),
        written.len(),
        &dir,
    )?;
    Ok(Outcome::Success)
}
