//! `csm-lab analyze`: one scene and shadow setting, built and measured, written as CSV, JSON
//! and SVG, with a summary on stdout.

use super::{default_out_dir, load_with_engine_settings, load_with_preset_flag, print_result, Format, Outcome};
use crate::analysis::{analyze_with_progress, frames_walked, AnalysisOptions};
use crate::error::{ConfigError, Error, Result};
use crate::output;
use crate::report;
use csm_core::scene::Precision;
use std::path::PathBuf;

/// What `analyze` was asked to do (the command line's flags, as plain values).
#[derive(Debug, Clone)]
pub struct AnalyzeRequest {
    pub config: PathBuf,
    pub out: Option<PathBuf>,
    pub format: Format,
    pub precision: Option<Precision>,
    pub preset: Option<String>,
    /// No progress bar.
    pub quiet: bool,
    /// `--all-frames`: `shimmer.csv` with every frame, streamed.
    pub all_frames: bool,
    /// `--engine-settings FILE`: an engine's `recommendation.<engine>.txt` in place of its
    /// table and the `[shadow]` count, map size and distance.
    pub engine_settings: Option<PathBuf>,
    /// `--ground-truth`: run the ground-truth pass (as `[analysis] ground_truth = true`).
    pub ground_truth: bool,
    /// `--raw-bias`: the pass samples with no bias (as `[shadow] bias = "none"`).
    pub raw_bias: bool,
}

/// The `analyze` command.
pub fn execute(args: &AnalyzeRequest) -> Result<Outcome> {
    let mut config = match &args.engine_settings {
        Some(file) => load_with_engine_settings(&args.config, args.preset.as_deref(), file)?,
        None => load_with_preset_flag(&args.config, args.preset.as_deref())?,
    };
    if let Some(p) = args.precision {
        // Through the validating constructor; a refusal names the flag that asked for it.
        config = config.with_precision(p).map_err(|e| match e {
            Error::Config(ConfigError::Invalid { allowed, .. }) => Error::flag("--precision", p.name(), allowed),
            other => other,
        })?;
    }
    if args.ground_truth {
        crate::commands::sweep::flicker::refuse_ground_truth(&config, "--ground-truth")?;
        config.truth.enabled = true;
    }
    if args.raw_bias {
        if config.truth.bias_written() {
            return Err(Error::flag(
                "--raw-bias",
                "",
                "not with shadow.depth_bias, shadow.slope_bias or shadow.normal_bias set: those keys are the bias",
            ));
        }
        config.truth.bias_mode = Some(crate::config::BiasMode::None);
    }
    let progress = super::progress::Progress::new(args.quiet, frames_walked(&config), "frames");
    let analysis = analyze_with_progress(&config, &AnalysisOptions::full(), &|n| progress.inc(n));
    progress.writing();
    let dir = args.out.clone().unwrap_or_else(|| default_out_dir(&config));
    let written = if args.all_frames {
        // Every output but shimmer.csv is rendered as usual; shimmer.csv is streamed into the
        // same all-or-nothing set.
        let files = report::analyze::exporters_for(&analysis)
            .into_iter()
            .filter(|e| e.file_name() != "shimmer.csv")
            .map(|e| Ok((e.file_name().to_string(), e.render(&analysis)?)))
            .collect::<Result<Vec<_>>>()?;
        output::write_files_streamed(&dir, &files, &[&report::analyze::FullShimmerCsv(&config)])?
    } else {
        output::export_all(&dir, &analysis, &report::analyze::exporters_for(&analysis))?
    };
    progress.finish();
    print_result(
        args.format,
        || report::analyze::summary_table(&analysis),
        || output::json_bytes("summary", &report::analyze::summary_value(&analysis)),
        written.len(),
        &dir,
    )?;
    Ok(Outcome::Success)
}
