//! `csm-lab analyze`: one scene and shadow setting, built and measured, written as CSV, JSON
//! and SVG, with a summary on stdout.

use super::{
    applied_preset, default_out_dir, load_with_engine_settings, load_with_preset_flag, out_folder, print_result,
    Format, Outcome,
};
use crate::analysis::{analyze_with_progress, frames_walked_with, AnalysisOptions};
use crate::error::{ConfigError, Error, Result};
use crate::output;
use crate::report;
use csm_core::scene::Precision;
use std::path::PathBuf;

/// What `analyze` was asked to do (the command line's flags, as plain values).
#[derive(clap::Args, Debug, Clone)]
pub struct AnalyzeRequest {
    /// Scene and shadow settings (TOML).
    pub config: PathBuf,
    /// Output directory [default: out/<config name>/analyze/, analyze-<engine>/ with --preset,
    /// analyze-<engine>-settings/ with --engine-settings].
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
    /// No progress bar (it shows only on a terminal, after about a second).
    #[arg(long)]
    pub quiet: bool,
    /// shimmer.csv with every frame's rows, streamed to the file as the path is walked
    /// (by default a path longer than 1,000 frames keeps every k-th frame's rows).
    #[arg(long)]
    pub all_frames: bool,
    /// An engine settings file as `sweep --preset` and `compare` write it
    /// (recommendation.<engine>.txt): its engine's cascades with exactly those settings, in
    /// place of the engine's table and the [shadow] count, map size and shadow distance.
    #[arg(long, value_name = "FILE")]
    pub engine_settings: Option<PathBuf>,
    /// Sample the shadow maps against the exact answer (acne, leaks, S5 flicker, the bias
    /// needed per cascade; bias.csv); as [analysis] ground_truth = true. Needs scene geometry.
    #[arg(long)]
    pub ground_truth: bool,
    /// With --ground-truth: sample the maps with no bias at all (as [shadow] bias = "none"),
    /// instead of the configured, engine or recommended bias.
    #[arg(long)]
    pub raw_bias: bool,
}

/// The `analyze` command.
pub(crate) fn execute(args: &AnalyzeRequest) -> Result<Outcome> {
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
    if config.truth.enabled {
        let source = if args.ground_truth {
            "--ground-truth"
        } else {
            "analysis.ground_truth"
        };
        crate::analysis::ground_truth::cost_fits(&config, source)?;
    }
    let progress = super::progress::Progress::new(
        args.quiet,
        frames_walked_with(&config, &AnalysisOptions::full()),
        "frames",
    );
    let analysis = analyze_with_progress(&config, &AnalysisOptions::full(), &|n| progress.inc(n));
    progress.writing();
    let dir = args.out.clone().unwrap_or_else(|| {
        let by_flag = args.preset.is_some() || args.engine_settings.is_some();
        let preset = applied_preset(&config).filter(|_| by_flag);
        default_out_dir(&config, &out_folder("analyze", preset, args.engine_settings.is_some()))
    });
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

/// `--precision`: the core's [`Precision`], listed with a line of help per value.
fn precision_parser() -> impl clap::builder::TypedValueParser<Value = Precision> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new([
        PossibleValue::new("f64").help("Exact: texel-unit windows, snapped shimmer exactly 0 at any world offset"),
        PossibleValue::new("f32").help("An engine's binary32 pipeline, emulated operation by operation"),
    ])
    .map(|s| Precision::from_name(&s).expect("one of the listed values"))
}
