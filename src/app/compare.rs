//! `csm-lab compare`: engine presets side by side on one scene.

use std::path::PathBuf;

use super::{default_out_dir, Outcome};
use crate::commands::compare::*;
use crate::error::Result;
use crate::output;
use crate::report;

/// What `compare` was asked to do (the command line's flags, as plain values).
#[derive(clap::Args, Debug, Clone)]
pub struct CompareRequest {
    /// Scene file (TOML); its camera, screen, light, scene and motion are shared by every preset.
    pub config: PathBuf,
    /// Comma-separated presets to compare [default: all].
    #[arg(long)]
    pub presets: Option<String>,
    /// Every preset at its own defaults: ignore shadow.cascades, shadow.resolution and shadow.max_distance.
    #[arg(long)]
    pub defaults: bool,
    /// Add csm-lab's own pipeline (the file's [shadow]) with its splits on these depth ranges:
    /// bounds, visible or bounds,visible (visible needs scene geometry).
    #[arg(long, value_name = "SPEC")]
    pub split_range: Option<String>,
    /// Output directory [default: out/<config name>/compare/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar (it shows only on a terminal, after about a second).
    #[arg(long)]
    pub quiet: bool,
}

/// The `compare` command.
pub(crate) fn execute(args: &CompareRequest) -> Result<Outcome> {
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
        .unwrap_or_else(|| default_out_dir(&comparison.analyses[0].config, "compare"));
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
