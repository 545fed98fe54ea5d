//! Loading a scene file: parse and validate it ([`crate::config`]), apply the file's or the
//! command line's engine preset ([`crate::presets`]), then run the checks that need the
//! finished cascade set-up (binary32 range). [`Config::with_lambda`] and the other
//! constructors in `with` change a loaded config through the same checks.

mod with;

use std::path::Path;

use crate::config::{Config, Precision, Validator};
use crate::error::Result;
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
        let text = crate::config::read_bounded(path, crate::config::MAX_TEXT_FILE_BYTES, "a config file")?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            // The name becomes a directory under the output root: a stem of only dots
            // (`...toml` has the stem `..`) would climb out of it.
            .filter(|s| !s.trim_matches('.').is_empty())
            .unwrap_or_else(|| "config".to_string());
        let mut config = crate::config::parse(&text, &path.display().to_string(), path.parent())?;
        for w in &config.warnings {
            eprintln!("warning: {}: {w}", path.display());
        }
        config.name = name;
        config.path = Some(path.to_path_buf());
        if let Some(g) = &config.geometry {
            let d = g.scene.bvh_dropped();
            if d.duplicates + d.degenerate > 0 {
                eprintln!(
                    "warning: {}: the scene's BVH leaves out {} duplicate triangle(s) (the same three vertices as an \
                     earlier one) and {} of zero area in binary32; rays cannot tell them apart, so no result changes",
                    path.display(),
                    d.duplicates,
                    d.degenerate
                );
            }
        }
        Ok(config)
    }

    /// [`Config::load`] with the preset chosen (or overridden) as in `choice`.
    pub fn load_with_preset(path: &Path, choice: &PresetChoice) -> Result<Config> {
        let mut config = Config::load_scene(path)?;
        apply_preset(&mut config, choice)?;
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
        apply_preset(&mut config, choice)?;
        Ok(config)
    }
}

/// Applies the preset chosen in `choice` (or the file's) to a parsed scene and checks the
/// result: the one way a preset reaches a config.
pub(crate) fn apply_preset(config: &mut Config, choice: &PresetChoice) -> Result<()> {
    crate::presets::apply(config, choice)?;
    let input = config.preset_input.clone();
    let v = input.validator();
    sweep_objective(config, &v)?;
    f64_windows(config, &v, true)?;
    binary32_range(config, &v)?;
    update_every(config, &v)
}

/// Every cascade window along the camera paths can be built in f64 (see
/// [`crate::analysis::f64_window_problem`]); the key named is `camera.near`. `all_frames`:
/// every frame (a loaded config, a new path), or frame 0 only (a sweep point that kept the
/// path: a path moves the camera by far less than its coordinates, so the f64 step at them
/// hardly changes, and walking every point's path again would cost a sweep a path per point).
pub(super) fn f64_windows(config: &Config, v: &Validator<'_>, all_frames: bool) -> Result<()> {
    match crate::analysis::f64_window_problem(config, all_frames) {
        Some(why) => Err(v.invalid("camera.near", config.camera.near, &why)),
        None => Ok(()),
    }
}

/// `[sweep] objective` names a summary metric of the registry that is worse when higher, and
/// a screen metric only when the scene has geometry.
fn sweep_objective(config: &Config, v: &Validator<'_>) -> Result<()> {
    use crate::metric::{Direction, SummaryMetric};
    let Some(name) = config.sweep.as_ref().and_then(|s| s.objective.as_deref()) else {
        return Ok(());
    };
    let allowed: Vec<&str> = SummaryMetric::all()
        .filter(|m| m.direction() == Direction::HigherIsWorse)
        .map(|m| m.name())
        .collect();
    match SummaryMetric::from_name(name) {
        Some(m) if allowed.contains(&m.name()) => {
            if m.def().screen && config.geometry.is_none() {
                return Err(v.invalid(
                    "sweep.objective",
                    format!("{name:?}"),
                    "a metric of the bounds-only mode: screen metrics need scene geometry (scene.ground, \
                     [[scene.box]] or scene.gltf)",
                ));
            }
            Ok(())
        }
        _ => Err(v.invalid(
            "sweep.objective",
            format!("{name:?}"),
            &format!("the name of a metric to minimise, one of {}", allowed.join(", ")),
        )),
    }
}

/// binary32 must be able to hold every texel coordinate the emulated pipeline computes.
fn binary32_range(config: &Config, v: &Validator<'_>) -> Result<()> {
    if config.shadow.precision == Precision::F32 {
        if config.motion.light.moves() {
            return Err(v.invalid(
                "shadow.precision",
                "\"f32\"",
                &format!(
                    "\"f64\" when the light moves (motion.light_path = {:?}): the binary32 pipeline is \
                     measured under a still light only",
                    config.motion.light.path.name()
                ),
            ));
        }
        if let Some(why) = crate::analysis::f32_range_problem(config) {
            return Err(v.invalid("shadow.precision", "\"f32\"", &why));
        }
    }
    Ok(())
}

/// The checks that involve several settings at once, run again by every constructor that
/// changes a loaded config: a valid camera in every frame, and the binary32 range.
fn cross_checks(config: &Config, v: &Validator<'_>) -> Result<()> {
    crate::config::check_camera_path(config, v)?;
    f64_windows(config, v, true)?;
    binary32_range(config, v)?;
    update_every(config, v)
}

/// `[shadow] update_every` once the cascades are known: one value, or one per cascade; and a
/// pipeline whose held windows stay valid (binary64, a still light, a light basis that does
/// not follow the camera: a held map keeps the light basis it was rendered with).
pub(crate) fn update_every(config: &Config, v: &Validator<'_>) -> Result<()> {
    let Some(every) = &config.shadow.update_every else {
        return Ok(());
    };
    let key = "shadow.update_every";
    let m = config.shadow.cascades;
    if every.per_cascade(m).is_none() {
        return Err(v.invalid(
            key,
            every.label(),
            &format!("a single integer, or one integer per cascade ({m} here), nearest first"),
        ));
    }
    if config.shadow.precision == Precision::F32 {
        return Err(v.invalid(
            key,
            every.label(),
            "1 (every frame) with precision = \"f32\": cached cascades are measured with the f64 pipeline only",
        ));
    }
    if config.motion.light.moves() {
        return Err(v.invalid(
            key,
            every.label(),
            &format!(
                "1 (every frame) when the light moves (motion.light_path = {:?}): a held map keeps the light \
                 direction it was rendered with, which is not modelled",
                config.motion.light.path.name()
            ),
        ));
    }
    if crate::analysis::rig(config).is_some_and(|r| !r.fixed_basis()) {
        return Err(v.invalid(
            key,
            every.label(),
            "1 (every frame) for a pipeline whose light basis follows the camera (this preset's): a held map \
             keeps the basis it was rendered with, which is not modelled",
        ));
    }
    Ok(())
}
