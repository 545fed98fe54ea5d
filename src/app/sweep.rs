//! `csm-lab sweep`: every configuration of the grid, the Pareto front and the recommendation,
//! written as CSV, JSON, figures and a report.

use std::path::{Path, PathBuf};

use super::{default_out_dir, load_for_preset_sweep, print_result, Format, Outcome};
use crate::commands::sweep::grid::{Grid, GridFlags};
use crate::commands::sweep::run::run_settings;
use crate::commands::sweep::shard::{self, Shard};
use crate::commands::sweep::{flicker, optimize, SweepResult};
use crate::config::Config;
use crate::error::{Error, Result};
use crate::output;
use crate::report;

/// The loaded config, the resolved grid and the command that reproduces the (unsharded) sweep.
pub(crate) fn plan(args: &SweepRequest) -> Result<(Config, Grid, String)> {
    let config = load_for_preset_sweep(&args.config, args.grid.preset.as_deref())?;
    let overrides = args.grid.overrides()?;
    let grid = Grid::resolve(&config, &overrides)?;
    if !args.quiet {
        for note in &grid.notes {
            eprintln!("note: {note}");
        }
    }
    let preset = match &config.shadow.preset {
        Some(p) => format!(" --preset {}", p.name),
        None => String::new(),
    };
    let command = format!(
        "csm-lab sweep {}{preset} {}",
        args.config.display(),
        grid.cli_args(&config)
    );
    Ok((config, grid, command))
}

/// [`shard::config_hash`] of a planned sweep, reading the config file (and its glTF) again.
pub(crate) fn shard_hash(path: &Path, config: &Config, grid: &Grid, command: &str) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::read(path, e))?;
    let gltf = match config.geometry.as_ref().and_then(|g| g.gltf.as_deref()) {
        Some(p) => Some(std::fs::read(p).map_err(|e| Error::read(p, e))?),
        None => None,
    };
    Ok(shard::config_hash(&bytes, gltf.as_deref(), config, grid, command))
}

/// Runs a sweep as the CLI does, without printing: (result, rendered files; `sweep.csv` is not
/// among them: [`execute`] streams it into the set). With `--shard` the result holds the
/// shard's slice ([`SweepResult::slice`]), and the files are only the shard's manifest and rows.
/// The progress bar is returned still up, for the writing.
pub fn sweep_files(args: &SweepRequest) -> Result<(SweepResult, output::RenderedFiles, super::progress::Progress)> {
    let shard = args.shard.as_deref().map(Shard::parse).transpose()?;
    let (config, grid, command) = plan(args)?;
    // --optimize-splits (or `[sweep] optimize_splits`): refused before any work for a preset
    // whose splits are not free; a shard holds part of each group, so it leaves it to the
    // unsharded sweep.
    let optimize_source = if args.optimize_splits {
        Some("--optimize-splits")
    } else if config.sweep.as_ref().is_some_and(|s| s.optimize_splits) {
        Some("sweep.optimize_splits")
    } else {
        None
    };
    if let Some(source) = optimize_source {
        optimize::check_free(&config, source)?;
        if shard.is_some() {
            if args.optimize_splits {
                return Err(Error::flag(
                    "--optimize-splits",
                    "",
                    "a shard holds only part of each cascade count's λ values; run --optimize-splits on the unsharded sweep",
                ));
            }
            if !args.quiet {
                eprintln!("note: sweep.optimize_splits left out: a shard holds only part of the grid");
            }
        }
    }
    let optimize = optimize_source.is_some() && shard.is_none();
    // --ground-truth (or `[sweep] ground_truth`): refused before any work without geometry; a
    // shard holds only part of the rows, so the sample is left to the unsharded sweep.
    let truth_source = if args.ground_truth {
        Some("--ground-truth")
    } else if config.sweep.as_ref().is_some_and(|s| s.ground_truth) {
        Some("sweep.ground_truth")
    } else {
        None
    };
    if let Some(source) = truth_source {
        flicker::refuse_ground_truth(&config, source)?;
        if shard.is_some() {
            if args.ground_truth {
                return Err(Error::flag(
                    "--ground-truth",
                    "",
                    "a shard holds only part of the rows the sample is drawn from; run --ground-truth on the unsharded sweep",
                ));
            }
            if !args.quiet {
                eprintln!("note: sweep.ground_truth left out: a shard holds only part of the grid");
            }
        }
    }
    let ground_truth = truth_source.is_some() && shard.is_none();
    let mut settings = grid.settings();
    let mut indices = Vec::new();
    if let Some(s) = shard {
        s.check_grid(settings.len())?;
        indices = s.indices(settings.len()).collect();
        settings = indices.iter().map(|&i| settings[i]).collect();
    }
    // When the first frames of the path prove that no row can qualify, say so before the sweep
    // (the whole grid, unsharded, with no split search that could leave the grid). csm-lab's own
    // pipeline stops there; a preset sweep runs on, since the engine settings file of its
    // closest row (marked NOT RECOMMENDED) is what it is run for.
    if shard.is_none() && !optimize {
        if let Some(f) = crate::commands::sweep::feasible::infeasible(&config, &settings)? {
            if config.shadow.preset.is_none() {
                return Err(crate::error::GridError::Unusable {
                    context: args.config.display().to_string(),
                    message: f.message(),
                }
                .into());
            }
            if !args.quiet {
                eprintln!(
                    "note: {}; the sweep runs on for the closest engine setting",
                    f.sentence()
                );
            }
        }
    }
    let progress = super::progress::Progress::new(args.quiet, settings.len() as u64, "configurations");
    let start = std::time::Instant::now();
    let means = crate::commands::sweep::run::cost_means(&config, &grid);
    let rows = run_settings(&config, &settings, means, args.threads.map(usize::from), &|| {
        progress.inc(1)
    })?;
    let compute = start.elapsed();
    let analysed = rows.len();
    progress.writing();
    let manifest = match shard {
        Some(s) => Some(shard::Manifest {
            tool: shard::tool(),
            shard: s,
            grid_configurations: grid.len(),
            config: args.config.display().to_string(),
            flags: args.grid.clone(),
            config_hash: shard_hash(&args.config, &config, &grid, &command)?,
            command: command.clone(),
        }),
        None => None,
    };
    let shown_command = match shard {
        Some(s) => format!("{command} --shard {}/{}", s.k, s.n),
        None => command,
    };
    let mut result = SweepResult::new(config, grid, rows, shown_command)?;
    if optimize {
        let start = std::time::Instant::now();
        let found = optimize::optimize(
            &result.config,
            &result.grid,
            &result.rows,
            result.objective,
            args.threads.map(usize::from),
        )?;
        if !args.quiet {
            progress.note(&format!(
                "optimised the splits of {} groups ({} analyses) in {:.1} ms",
                found.groups.len(),
                found.groups.iter().map(|g| g.evaluations).sum::<usize>(),
                start.elapsed().as_secs_f64() * 1e3
            ));
        }
        result.optimized = Some(found);
    }
    if ground_truth {
        let start = std::time::Instant::now();
        let sample = flicker::measure(
            &result.config,
            &result.rows,
            result.recommendation.as_ref().map(|r| r.index),
            args.threads.map(usize::from),
        )?;
        if !args.quiet {
            progress.note(&format!(
                "measured the ground truth of {} rows in {:.1} ms",
                sample.indices.len(),
                start.elapsed().as_secs_f64() * 1e3
            ));
        }
        result.flicker = Some(sample);
    }
    // sweep.csv is streamed when the set is written (execute), not rendered here. A shard
    // decides nothing: it writes its rows and manifest, and only `merge` writes the rest.
    let mut files = match shard {
        Some(s) => {
            result = result.into_slice(s);
            Vec::new()
        }
        None => report::sweep::render_all_but_csv(&result, !args.no_plots)?,
    };
    if let Some(m) = manifest {
        files.push((
            shard::MANIFEST_FILE.to_string(),
            output::json_bytes("shard manifest", &m.to_json())?,
        ));
        files.push((
            shard::ROWS_FILE.to_string(),
            // Every row the shard ran (in a sun sweep, each (sun, setting) row).
            shard::rows_text(
                &m,
                indices
                    .iter()
                    .copied()
                    .zip(result.sun.as_ref().map_or(&result.rows, |s| &s.all)),
            )
            .into_bytes(),
        ));
    }
    if !args.quiet {
        progress.note(&format!(
            "analysed {} configurations in {:.1} ms",
            analysed,
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
    /// `--preset` and the grid's axis flags.
    pub grid: GridFlags,
    pub threads: Option<u16>,
    pub quiet: bool,
    pub no_plots: bool,
    pub format: Format,
    /// `--shard K/N`, unparsed.
    pub shard: Option<String>,
    /// `--optimize-splits`.
    pub optimize_splits: bool,
    /// `--ground-truth`.
    pub ground_truth: bool,
}

/// The `sweep` command.
pub(crate) fn execute(args: &SweepRequest) -> Result<Outcome> {
    let (result, files, progress) = sweep_files(args)?;
    let dir = match (&args.out, args.shard.as_deref().map(Shard::parse).transpose()?) {
        (Some(dir), _) => dir.clone(),
        (None, Some(s)) => {
            sweep_out_dir(&result.config, args.grid.preset.is_some()).join(format!("shard-{}-of-{}", s.k, s.n))
        }
        (None, None) => sweep_out_dir(&result.config, args.grid.preset.is_some()),
    };
    let written = output::write_files_streamed(&dir, &files, &[&report::sweep::SweepCsvFile(&result)])?;
    progress.finish();
    if let Some(s) = result.slice {
        // The slice and where the decision is made; no verdict.
        let total = result.grid.len();
        print_result(
            args.format,
            || report::sweep::slice_text(&result.config.name, s, total),
            // The JSON output is the shard's manifest (always among its files).
            || {
                Ok(files
                    .iter()
                    .find(|(name, _)| name == shard::MANIFEST_FILE)
                    .map(|(_, bytes)| bytes.clone())
                    .unwrap_or_default())
            },
            written.len(),
            &dir,
        )?;
        return Ok(Outcome::Success);
    }
    print_decision(args.format, &result, written.len(), &dir)?;
    Ok(Outcome::Success)
}

/// Where a sweep (or the merge of its shards) writes without `--out`: `out/<config name>/sweep/`,
/// or `sweep-<engine>/` for `--preset <engine>`; a shard writes `shard-K-of-N/` inside it.
pub(crate) fn sweep_out_dir(config: &crate::config::Config, preset_flag: bool) -> std::path::PathBuf {
    let preset = super::applied_preset(config).filter(|_| preset_flag);
    default_out_dir(config, &super::out_folder("sweep", preset, false))
}

/// What `sweep` and `merge` print once the files are written: the table and verdict (or the
/// recommendation as JSON), then in the table output the engine's settings
/// (`recommendation.<engine>.txt`, with a preset) and which rows have S5 and how well S3 and S4
/// predict it (the JSON output stays one document).
pub(crate) fn print_decision(format: Format, result: &SweepResult, written: usize, dir: &Path) -> Result<()> {
    print_result(
        format,
        || report::sweep::stdout_table(result),
        || output::json_bytes("recommendation", &report::sweep::recommendation_value(result)),
        written,
        dir,
    )?;
    if format == Format::Table {
        if let Some(s) = &result.engine_setting {
            print!("\n{}:\n{}", s.file_name(), report::terms::text(s));
        }
        if let Some(s) = &result.flicker {
            println!("\nground truth:");
            for l in report::flicker_sample::lines(s) {
                println!("  {l}");
            }
        }
    }
    Ok(())
}
