//! Running a command: load the config, compute the result ([`crate::commands`]), hand it to the
//! report layer ([`crate::report`], [`crate::figures`]), write the files atomically, print, and
//! say how the run ended. One module per command; `cli` only parses flags into the request
//! structs defined here and dispatches.

pub mod analyze;
pub(crate) mod bench;
pub(crate) mod check;
pub(crate) mod compare;
pub(crate) mod merge;
pub(crate) mod progress;
pub(crate) mod stress;
pub mod sweep;

use std::path::{Path, PathBuf};

use crate::config::Config;
use crate::error::Result;

/// What a command prints on stdout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    Table,
    Json,
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
pub(crate) fn load_with_preset_flag(path: &Path, preset: Option<&str>) -> Result<Config> {
    let choice = crate::presets::PresetChoice {
        name: preset.map(|s| crate::presets::parse_flag("--preset", s)).transpose()?,
        ..Default::default()
    };
    Config::load_with_preset(path, &choice)
}

/// Loads a config with an engine settings file (`recommendation.<engine>.txt`, as `sweep`
/// and `compare` write it) in place of the engine's table and the `[shadow]` count, map size
/// and shadow distance: the preset is the file's engine (`--preset`, when given, must name
/// the same one).
pub fn load_with_engine_settings(path: &Path, preset: Option<&str>, settings: &Path) -> Result<Config> {
    let text = crate::config::read_bounded(settings, crate::config::MAX_TEXT_FILE_BYTES, "an engine settings file")?;
    let label = settings.display().to_string();
    let named = crate::presets::engine_of(&text, &label)?;
    if let Some(p) = preset.map(|s| crate::presets::parse_flag("--preset", s)).transpose()? {
        if p != named {
            return Err(crate::error::Error::flag(
                "--engine-settings",
                &label,
                format!("the file holds {named} settings, but --preset is {p}; drop --preset or give the {p} file"),
            ));
        }
    }
    let choice = crate::presets::PresetChoice {
        name: Some(named),
        lenient_overrides: true,
        ..Default::default()
    };
    let mut config = Config::load_with_preset(path, &choice)?;
    crate::presets::apply_terms(&mut config, &text, &label)?;
    config.rechecked()
}

/// The same for `sweep --preset`: a `[shadow]` count or map size the engine does not offer
/// falls back to the engine's default with a note (the sweep covers the engine's own axes
/// anyway), so every preset sweeps every scene.
pub(crate) fn load_for_preset_sweep(path: &Path, preset: Option<&str>) -> Result<Config> {
    let choice = crate::presets::PresetChoice {
        name: preset.map(|s| crate::presets::parse_flag("--preset", s)).transpose()?,
        lenient_overrides: preset.is_some(),
        ..Default::default()
    };
    Config::load_with_preset(path, &choice)
}

/// Prints a command's result: with `--format table` the table, then the "wrote" line, on
/// stdout; with `--format json` the JSON document on stdout and the "wrote" line on stderr, so
/// that stdout is exactly one document.
pub(crate) fn print_result(
    format: Format,
    table: impl FnOnce() -> String,
    json: impl FnOnce() -> Result<Vec<u8>>,
    written: usize,
    dir: &Path,
) -> Result<()> {
    match format {
        Format::Table => {
            print!("{}", table());
            println!("wrote {written} files to {}", dir.display());
        }
        Format::Json => {
            print!("{}", String::from_utf8_lossy(&json()?));
            eprintln!("wrote {written} files to {}", dir.display());
        }
    }
    Ok(())
}

/// Where commands write without `--out`: `out/`, ignored by git, so running a command never
/// changes the committed samples under `reports/` (those are written on purpose, by
/// `scripts/regen-samples.sh`).
pub(crate) const DEFAULT_OUT_ROOT: &str = "out";

/// The default output directory of one command on a config: `out/<config name>/<folder>/`,
/// one folder per command and preset flag ([`out_folder`]), so that two commands run one
/// after the other never overwrite each other's files (`compare`'s
/// `recommendation.unity.txt` is not `sweep --preset unity`'s).
pub(crate) fn default_out_dir(config: &Config, folder: &str) -> PathBuf {
    Path::new(DEFAULT_OUT_ROOT).join(&config.name).join(folder)
}

/// The folder a command writes under `out/<config name>/`: the command's name, and
/// `<command>-<engine>` when a flag chose the engine (`sweep --preset unity` writes
/// `sweep-unity/`; `analyze --engine-settings` of a bevy file writes `analyze-bevy-settings/`).
/// A preset named in the config file itself adds nothing: the config name already says it.
pub(crate) fn out_folder(command: &str, flag_preset: Option<crate::presets::PresetName>, settings: bool) -> String {
    match (flag_preset, settings) {
        (Some(p), true) => format!("{command}-{}-settings", p.as_str()),
        (Some(p), false) => format!("{command}-{}", p.as_str()),
        (None, _) => command.to_string(),
    }
}

/// The engine preset applied to a loaded config, if any.
pub(crate) fn applied_preset(config: &Config) -> Option<crate::presets::PresetName> {
    config
        .shadow
        .preset
        .as_ref()
        .and_then(|p| p.downcast_ref::<crate::presets::Preset>())
        .map(|p| p.name)
}
