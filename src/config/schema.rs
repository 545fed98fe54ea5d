//! The scene file as TOML gives it: one raw struct per table, before any check. Engine tables
//! (`[bevy]`, `[godot]`, ...) are not read here: `crate::presets` parses each from the text, and
//! the names of the other top-level tables are kept so it can reject unknown ones.

use serde::Deserialize;
use toml::Spanned;

/// csm-lab's own top-level tables.
pub const SECTIONS: [&str; 8] = [
    "camera", "screen", "light", "scene", "shadow", "motion", "analysis", "sweep",
];

/// The whole file: csm-lab's tables, and every other top-level key (engine tables or unknown).
#[derive(Debug)]
pub(crate) struct RawFile {
    pub(crate) config: RawConfig,
    pub(crate) others: Vec<String>,
}

impl RawFile {
    /// Parses the text; TOML syntax and type errors carry the line and column.
    pub(crate) fn parse(text: &str) -> Result<RawFile, toml::de::Error> {
        let config: RawConfig = toml::from_str(text)?;
        let table: toml::Table = toml::from_str(text)?;
        let others = table
            .keys()
            .filter(|k| !SECTIONS.contains(&k.as_str()))
            .cloned()
            .collect();
        Ok(RawFile { config, others })
    }
}

#[derive(Debug, Deserialize)]
pub(crate) struct RawConfig {
    pub(crate) camera: RawCamera,
    pub(crate) screen: RawScreen,
    pub(crate) light: RawLight,
    pub(crate) scene: RawScene,
    #[serde(default)]
    pub(crate) shadow: RawShadow,
    #[serde(default)]
    pub(crate) motion: RawMotion,
    #[serde(default)]
    pub(crate) analysis: RawAnalysis,
    pub(crate) sweep: Option<super::sweep_spec::RawSweep>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCamera {
    pub(crate) position: [f64; 3],
    pub(crate) target: [f64; 3],
    pub(crate) up: Option<[f64; 3]>,
    pub(crate) fov_y_deg: f64,
    pub(crate) near: f64,
    pub(crate) far: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScreen {
    pub(crate) width: i64,
    pub(crate) height: i64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLight {
    pub(crate) direction: [f64; 3],
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    pub(crate) min: [f64; 3],
    pub(crate) max: [f64; 3],
    pub(crate) world_offset: Option<[f64; 3]>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawShadow {
    pub(crate) max_distance: Option<f64>,
    pub(crate) cascades: Option<i64>,
    pub(crate) lambda: Option<f64>,
    pub(crate) resolution: Option<i64>,
    pub(crate) fit: Option<Spanned<String>>,
    pub(crate) snap: Option<bool>,
    pub(crate) fit_depth_to_scene: Option<bool>,
    pub(crate) precision: Option<String>,
    pub(crate) snap_space: Option<String>,
    pub(crate) preset: Option<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMotion {
    pub(crate) path: Option<String>,
    /// Several paths, judged together (the summary takes the worst); excludes `path`.
    pub(crate) paths: Option<Vec<String>>,
    /// One step per entry of `paths` (default: `step` for every path).
    pub(crate) steps: Option<Vec<f64>>,
    pub(crate) frames: Option<i64>,
    pub(crate) step: Option<f64>,
    pub(crate) file: Option<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAnalysis {
    pub(crate) density_samples: Option<i64>,
    pub(crate) probes: Option<i64>,
}
