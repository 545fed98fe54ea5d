//! `csm-lab merge`: joins the shards of a sweep (`sweep --shard K/N`) into the files the
//! unsharded sweep writes, byte for byte: the rows come back exactly from each shard's
//! lossless rows file, and the Pareto front, recommendation, figures and reports are made by
//! the same code as `sweep`'s.

use std::path::{Path, PathBuf};

use super::sweep::{plan, shard_hash, SweepRequest};
use super::{default_out_dir, Format, Outcome};
use crate::commands::sweep::shard::{self, Manifest, ShardInput};
use crate::commands::sweep::{flicker, optimize, SweepResult};
use crate::error::{Error, Result, ShardError};
use crate::output;
use crate::report;

/// What `merge` was asked to do.
#[derive(clap::Args, Debug, Clone)]
pub struct MergeRequest {
    /// The output directories of every `sweep --shard K/N` run of one sweep (any order).
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Output directory [default: out/<config name>/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Skip the SVG/PNG figures, as `sweep --no-plots` does.
    #[arg(long)]
    pub no_plots: bool,
    /// No notes on stderr.
    #[arg(long)]
    pub quiet: bool,
    /// What to print on stdout.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
}

/// Largest shard file merge reads (a 100,000-row shard's rows are about 40 MB).
const MAX_SHARD_FILE: u64 = 1 << 30;

fn read_text(dir: &Path, name: &str) -> Result<String> {
    let path = dir.join(name);
    if let Err(e) = std::fs::metadata(&path) {
        if e.kind() == std::io::ErrorKind::NotFound {
            return Err(ShardError::dir(
                dir,
                format!("not a shard of a sweep: it has no {name} (`csm-lab sweep --shard K/N` writes one)"),
            )
            .into());
        }
    }
    // A regular file of at most MAX_SHARD_FILE bytes (a link to /dev/zero or a FIFO is refused
    // before it is read).
    crate::config::read_bounded(&path, MAX_SHARD_FILE, "a shard file")
}

/// Reads one shard directory.
pub(crate) fn read_shard(dir: &Path) -> Result<ShardInput> {
    if !dir.is_dir() {
        return Err(ShardError::dir(
            dir,
            "not a directory (give the output directories of `sweep --shard K/N`)",
        )
        .into());
    }
    let manifest = Manifest::from_json(dir, &read_text(dir, shard::MANIFEST_FILE)?)?;
    let rows = shard::parse_rows(
        &dir.join(shard::ROWS_FILE),
        &read_text(dir, shard::ROWS_FILE)?,
        &manifest,
    )?;
    Ok(ShardInput {
        dir: dir.to_path_buf(),
        manifest,
        rows,
    })
}

/// Merges as the CLI does, without printing: (result, rendered files but `sweep.csv`, which
/// [`execute`] streams into the set).
pub(crate) fn merge_files(args: &MergeRequest) -> Result<(SweepResult, output::RenderedFiles)> {
    let shards = args.dirs.iter().map(|d| read_shard(d)).collect::<Result<Vec<_>>>()?;
    let m = shard::check_set(&shards)?.clone();
    // The config is loaded again from where the shards read it, and must still be the same.
    let request = SweepRequest {
        config: PathBuf::from(&m.config),
        out: None,
        grid: m.flags.clone(),
        threads: None,
        quiet: args.quiet,
        no_plots: args.no_plots,
        format: args.format,
        shard: None,
        optimize_splits: false,
        ground_truth: false,
    };
    let (config, grid, command) = plan(&request).map_err(|e| {
        Error::from(ShardError::Set(format!(
            "the shards ran {}; merge loads that config again, relative to this directory, and it failed: {e}",
            m.command
        )))
    })?;
    let hash = shard_hash(&request.config, &config, &grid, &command)?;
    if hash != m.config_hash || command != m.command || grid.len() != m.grid_configurations {
        return Err(ShardError::Set(format!(
            "{} (or its grid) is not what the shards ran: its config_hash is {hash} now and {} in the shards; \
             run the shards again, or merge where the config is as they saw it",
            m.config, m.config_hash
        ))
        .into());
    }
    let rows = shard::join(shards, &grid)?;
    let mut result = SweepResult::new(config, grid, rows, command)?;
    // `[sweep] optimize_splits`, which each shard left out, runs on the joined rows, as the
    // unsharded sweep runs it.
    if result.config.sweep.as_ref().is_some_and(|s| s.optimize_splits) {
        optimize::check_free(&result.config, "sweep.optimize_splits")?;
        result.optimized = Some(optimize::optimize(
            &result.config,
            &result.grid,
            &result.rows,
            result.objective,
            None,
        )?);
    }
    // So does `[sweep] ground_truth`'s sample, which is drawn from all the rows.
    if result.config.sweep.as_ref().is_some_and(|s| s.ground_truth) {
        flicker::refuse_ground_truth(&result.config, "sweep.ground_truth")?;
        result.flicker = Some(flicker::measure(
            &result.config,
            &result.rows,
            result.recommendation.as_ref().map(|r| r.index),
            None,
        )?);
    }
    // sweep.csv is streamed when the set is written (execute).
    let files = report::sweep::render_all_but_csv(&result, !args.no_plots)?;
    Ok((result, files))
}

/// The `merge` command.
pub(crate) fn execute(args: &MergeRequest) -> Result<Outcome> {
    let (result, files) = merge_files(args)?;
    let dir = args.out.clone().unwrap_or_else(|| default_out_dir(&result.config));
    let written = output::write_files_streamed(&dir, &files, &[&report::sweep::SweepCsvFile(&result)])?;
    if !args.quiet {
        eprintln!(
            "merged {} shards: {} configurations",
            args.dirs.len(),
            result.rows.len()
        );
    }
    super::sweep::print_decision(args.format, &result, written.len(), &dir)?;
    Ok(Outcome::Success)
}
