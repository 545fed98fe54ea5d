//! One engine's setting, ready to be written in its own terms (`recommendation.<engine>.txt`;
//! the text itself is the engine's own, [`crate::presets::render`]). Which setting a command
//! writes is its own decision: `sweep`'s in [`crate::commands::sweep::terms`], `compare`'s in
//! [`crate::commands::compare::engine_settings`]; `docs/presets.md`, "Engine settings files",
//! states both rules.

use crate::config::Config;
use crate::presets::{Dims, Knobs, PresetName};

/// One engine's setting, ready to be written in its own terms.
#[derive(Debug, Clone, PartialEq)]
pub struct EngineSetting {
    pub preset: PresetName,
    pub knobs: Knobs,
    pub dims: Dims,
    /// The camera planes (split rules that depend on them).
    pub near: f64,
    pub far: f64,
    /// Comment lines: where the setting comes from, and how close it comes.
    pub comments: Vec<String>,
}

impl EngineSetting {
    /// The setting of a config with a preset applied.
    pub fn of(config: &Config, comments: Vec<String>) -> Option<EngineSetting> {
        let p = config.shadow.preset.as_ref()?;
        Some(EngineSetting {
            preset: p.name,
            knobs: p.knobs.clone(),
            dims: Dims::of(config),
            near: config.camera.near,
            far: config.camera.far,
            comments,
        })
    }

    /// `recommendation.<engine>.txt`.
    pub(crate) fn file_name(&self) -> String {
        file_name(self.preset)
    }
}

/// `recommendation.<engine>.txt`.
pub(crate) fn file_name(p: PresetName) -> String {
    format!("recommendation.{p}.txt")
}
