//! Applying a preset to a validated config: choosing it (flag over file), checking the engine
//! tables, resolving the knobs, and the engine's defaults and `[shadow]` overrides.

use crate::config::{Config, PresetInput, Validator, Written};
use crate::error::{ConfigError, Error, Result};

use super::*;

/// How the preset is chosen when a config is loaded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PresetChoice {
    /// Overrides `shadow.preset` (the `--preset` flag).
    pub name: Option<PresetName>,
    /// Engine tables allowed besides the selected preset's (`compare` runs several presets on
    /// one file).
    pub also_allowed: Vec<PresetName>,
    /// Ignore `[shadow] cascades`, `resolution` and `max_distance`: the preset's own defaults
    /// (`compare --defaults`).
    pub engine_defaults: bool,
    /// A `[shadow]` count or map size the preset does not offer falls back to the preset's
    /// default with a note instead of being an error (`compare`, where one file's settings meet
    /// several engines).
    pub lenient_overrides: bool,
}

fn table_error(v: &Validator<'_>, table: &str, allowed: String) -> Error {
    let location = match crate::config::locate_table(v.text, table) {
        Some((line, column)) if !v.path.is_empty() => format!("{}:{line}:{column}: ", v.path),
        Some((line, column)) => format!("line {line}, column {column}: "),
        None if !v.path.is_empty() => format!("{}: ", v.path),
        None => String::new(),
    };
    Error::from(ConfigError::Invalid {
        location,
        key: format!("[{table}]"),
        value: "(engine table)".to_string(),
        allowed,
        excerpt: header_excerpt(v.text, table),
    })
}

/// The excerpt under a table's name in its header (or under the key of an inline table).
fn header_excerpt(text: &str, table: &str) -> String {
    crate::config::locate(text, table).map_or_else(String::new, |p| crate::config::excerpt(text, p.key))
}

/// A top-level table that is neither csm-lab's nor an engine's.
fn unknown_table(v: &Validator<'_>, name: &str) -> Error {
    let (line, column) = crate::config::locate_table(v.text, name)
        .or_else(|| crate::config::locate_key(v.text, name))
        .unwrap_or((1, 1));
    let expected: Vec<String> = crate::config::SECTIONS
        .iter()
        .copied()
        .chain(PresetName::ALL.map(|p| p.as_str()))
        .map(|n| format!("`{n}`"))
        .collect();
    Error::from(ConfigError::Toml {
        path: v.path.to_string(),
        line,
        column,
        message: format!("unknown field `{name}`, expected one of {}", expected.join(", ")),
        excerpt: header_excerpt(v.text, name),
    })
}

/// Applies the preset of `config` (chosen as in `choice`) to it: writes the effective values
/// into `config.shadow` (cascades, resolution, max_distance, lambda, fit family, snap, no scene
/// clipping) and the resolved preset into `config.shadow.preset`. Leaves the settings untouched
/// when no preset is selected; engine tables without their preset are errors.
pub fn apply(config: &mut Config, choice: &PresetChoice) -> Result<()> {
    let input = config.preset_input.clone();
    let v = input.validator();
    let name = match (&choice.name, &input.preset) {
        (Some(p), _) => Some(*p),
        (None, Some(s)) => Some(PresetName::parse(s).ok_or_else(|| {
            let list: Vec<String> = PresetName::ALL.iter().map(|p| format!("\"{p}\"")).collect();
            v.invalid(
                "shadow.preset",
                format!("{s:?}"),
                &format!("one of {}; did you mean \"{}\"?", list.join(", "), closest_name(s)),
            )
        })?),
        (None, None) => None,
    };
    for table in &input.other_tables {
        let Some(t) = PresetName::parse(table) else {
            return Err(unknown_table(&v, table));
        };
        if Some(t) == name || choice.also_allowed.contains(&t) {
            continue;
        }
        let allowed = match name {
            None => format!(
                "an engine table only takes effect with its preset: add shadow.preset = \"{t}\" (or --preset {t}), or remove the table"
            ),
            Some(p) => {
                let from = if choice.name.is_some() {
                    "selected with --preset"
                } else {
                    "selected by shadow.preset"
                };
                format!("the preset is \"{p}\" ({from}), so [{t}] would have no effect: remove it or select the \"{t}\" preset")
            }
        };
        return Err(table_error(&v, table, allowed));
    }
    let Some(name) = name else {
        return Ok(());
    };
    let preset = resolve(name, config, &input, choice, &v)?;
    config.shadow.preset = Some(preset.into());
    Ok(())
}

fn resolve(
    name: PresetName,
    config: &mut Config,
    input: &PresetInput,
    choice: &PresetChoice,
    v: &Validator<'_>,
) -> Result<Preset> {
    let engine = name.engine();
    let mut notes = Vec::new();
    let w = if choice.engine_defaults {
        Written {
            max_distance: false,
            cascades: false,
            resolution: false,
            ..input.written
        }
    } else {
        input.written
    };
    for (written, key, what) in [
        (w.lambda, "shadow.lambda", "the preset's own split rule applies"),
        (w.splits, "shadow.splits", "the preset's own split knobs apply"),
        (w.fit, "shadow.fit", "the preset's own fit applies"),
        (w.snap, "shadow.snap", "the preset's own snapping applies"),
        (
            w.fit_depth_to_scene,
            "shadow.fit_depth_to_scene",
            "the preset does not clip its range to the scene",
        ),
    ] {
        if written {
            notes.push(format!("{key} ignored: {what}"));
        }
    }
    let cx = KnobContext {
        v,
        scene: &config.scene,
        light_direction: config.light_direction,
    };
    let (knobs, table_notes) = engine.resolve(&input.text, &input.label, &cx)?;
    let (default_cascades, default_distance) = engine.defaults(&knobs, config.camera.far);
    let shadow = &mut config.shadow;

    // Cascades.
    let mut cascades = default_cascades;
    if w.cascades {
        match engine.counts(&knobs) {
            Counts::Fixed(n) if shadow.cascades != n => notes.push(format!(
                "shadow.cascades = {} ignored: the {name} preset has a fixed {n} cascades",
                shadow.cascades
            )),
            Counts::Fixed(_) => {}
            Counts::Clamped(lo, hi) => {
                cascades = shadow.cascades.clamp(lo, hi);
                if cascades != shadow.cascades {
                    notes.push(format!(
                        "shadow.cascades = {} clamped to {cascades} as the engine does ({lo}..={hi})",
                        shadow.cascades
                    ));
                }
            }
            Counts::Allowed(list) => {
                if list.contains(&shadow.cascades) {
                    cascades = shadow.cascades;
                } else if choice.lenient_overrides {
                    notes.push(format!(
                        "shadow.cascades = {} is not offered by {name} ({}): its default {cascades} is used",
                        shadow.cascades,
                        join(&list)
                    ));
                } else {
                    return Err(v.invalid(
                        "shadow.cascades",
                        shadow.cascades,
                        &format!("one of {} for the {name} preset", join(&list)),
                    ));
                }
            }
        }
    }
    // Map size.
    let mut resolution = engine.default_resolution(&knobs, cascades);
    if w.resolution {
        if !engine.power_of_two_maps() || shadow.resolution.is_power_of_two() {
            resolution = shadow.resolution;
        } else if choice.lenient_overrides {
            notes.push(format!(
                "shadow.resolution = {} is not a power of two, which {name} requires: its default {resolution} is used",
                shadow.resolution
            ));
        } else {
            return Err(v.invalid(
                "shadow.resolution",
                shadow.resolution,
                &format!("a power of two for the {name} preset (the engine requires it)"),
            ));
        }
    }
    // Shadow distance.
    let mut max_distance = default_distance;
    if w.max_distance {
        if engine.has_distance() {
            max_distance = shadow.max_distance;
        } else {
            notes.push(format!(
                "shadow.max_distance = {} ignored: the {name} preset has no shadow distance (it uses camera.far)",
                shadow.max_distance
            ));
        }
    }
    notes.extend(table_notes);
    engine.check(&knobs, cascades, max_distance, v)?;

    // The layout must be a proper set of cascades.
    let camera = &config.camera;
    let lay = engine.layout(&knobs, cascades, max_distance, camera.near, camera.far);
    for (i, &(a, b)) in lay.fitted.iter().enumerate() {
        if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a) {
            return Err(v.invalid(
                "shadow.preset",
                format!("\"{name}\""),
                &format!(
                    "settings that give every cascade a slice with 0 < near < far; cascade {i} would be [{a}, {b}] (check camera.near/far, shadow.max_distance and [{name}])"
                ),
            ));
        }
    }
    shadow.cascades = lay.fitted.len();
    shadow.resolution = resolution;
    shadow.max_distance = max_distance;
    if let Some(l) = engine.lambda(&knobs) {
        shadow.lambda = l;
    }
    shadow.fit = engine.fit();
    shadow.snap = engine.snaps();
    shadow.fit_depth_to_scene = false;
    Ok(Preset { name, knobs, notes })
}
