//! `csm-lab compare`: engine presets side by side on one scene.

use std::path::PathBuf;

use super::{default_out_dir, Outcome};
use crate::commands::compare::*;
use crate::error::Result;
use crate::output;
use crate::report;

/// What `compare` was asked to do (the command line's flags, as plain values).
#[derive(Debug, Clone)]
pub struct CompareRequest {
    pub config: PathBuf,
    pub presets: Option<String>,
    pub defaults: bool,
    pub out: Option<PathBuf>,
    /// `--split-range`: csm-lab's own pipeline added with its splits on these ranges.
    pub split_range: Option<String>,
    /// No progress bar.
    pub quiet: bool,
}

/// The `compare` command.
pub fn execute(args: &CompareRequest) -> Result<Outcome> {
    let presets = match &args.presets {
        Some(list) => crate::presets::parse_list("--presets", list)?,
        None => crate::presets::PresetName::ALL.to_vec(),
    };
    let own = match &args.split_range {
        Some(spec) => crate::commands::sweep::grid::parse_split_range_spec(spec)?.values,
        None => Vec::new(),
    };
    let progress = super::progress::Progress::new(args.quiet, (presets.len() + own.len()) as u64, "presets");
    let comparison = run_with_progress(&args.config, &presets, args.defaults, &own, &|| progress.inc(1))?;
    progress.writing();
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&comparison.analyses[0].config));
    let scene = crate::config::Config::load_scene(&args.config)?;
    let settings = crate::commands::compare::engine_settings(&comparison, &scene)?;
    let mut files = report::compare::exporters()
        .iter()
        .map(|e| Ok((e.file_name().to_string(), e.render(&comparison)?)))
        .collect::<Result<Vec<_>>>()?;
    files.extend(settings.iter().map(report::terms::file));
    let written = output::write_files(&dir, &files)?;
    progress.finish();
    print!("{}", report::compare::summary_table(&comparison));
    print!("{}", report::compare::settings_lines(&settings));
    println!("wrote {} files to {}", written.len(), dir.display());
    Ok(Outcome::Success)
}
