//! Loading a scene file: parse and validate it ([`crate::config`]), then apply the file's or
//! the command line's engine preset ([`crate::presets`]).

use std::path::Path;

use crate::config::Config;
use crate::error::{Error, Result};
use crate::presets::PresetChoice;

impl Config {
    /// Reads and validates a config file. Relative paths inside it (the motion path file)
    /// are resolved against the file's directory.
    pub fn load(path: &Path) -> Result<Config> {
        Config::load_with_preset(path, &PresetChoice::default())
    }

    /// Reads and validates a config file without applying a preset: apply one (or several, to
    /// clones) with [`crate::presets::apply`].
    pub fn load_scene(path: &Path) -> Result<Config> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "config".to_string());
        let mut config = crate::config::parse(&text, &path.display().to_string(), path.parent())?;
        config.name = name;
        config.path = Some(path.to_path_buf());
        Ok(config)
    }

    /// [`Config::load`] with the preset chosen (or overridden) as in `choice`.
    pub fn load_with_preset(path: &Path, choice: &PresetChoice) -> Result<Config> {
        let mut config = Config::load_scene(path)?;
        crate::presets::apply(&mut config, choice)?;
        Ok(config)
    }

    /// Parses and validates config text. `label` names the source in messages; `base_dir`
    /// resolves a relative motion path file.
    pub fn from_toml_str(text: &str, label: &str, base_dir: Option<&Path>) -> Result<Config> {
        Config::from_toml_str_with_preset(text, label, base_dir, &PresetChoice::default())
    }

    /// [`Config::from_toml_str`] with the preset chosen (or overridden) as in `choice`.
    pub fn from_toml_str_with_preset(
        text: &str,
        label: &str,
        base_dir: Option<&Path>,
        choice: &PresetChoice,
    ) -> Result<Config> {
        let mut config = crate::config::parse(text, label, base_dir)?;
        crate::presets::apply(&mut config, choice)?;
        Ok(config)
    }
}
