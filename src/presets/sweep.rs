//! What a parameter sweep over a preset may vary, and setting one sweep point.

use crate::config::Config;
use crate::error::{PresetError, Result};

use super::*;

/// The sweep axes a configuration has (csm-lab's own pipeline or its preset's).
#[derive(Debug, Clone, PartialEq)]
pub struct Axes {
    /// The config key a λ sweep sets (`shadow.lambda`, `dart.lambda`, `eevee.cascade_exponent`,
    /// `filament.lambda`), or None when the split rule has no λ to sweep.
    pub lambda: Option<&'static str>,
    /// Cascade counts a sweep may use.
    pub cascades: Vec<usize>,
    /// Only powers of two are valid map sizes.
    pub resolution_power_of_two: bool,
    /// The fit can be swept (csm-lab's own pipeline only: a preset fixes its fit).
    pub fit: bool,
    /// The engine's own split knob (Unreal's distribution exponent, Bevy's first far bound).
    pub knob: Option<Knob>,
    /// The shadow distance (`shadow.max_distance`) can be swept.
    pub distance: bool,
}

/// The sweep axes of a preset at the shadow distance `max_distance`.
pub(crate) fn preset_axes(p: &Preset, max_distance: f64) -> Axes {
    let engine = p.knobs.engine();
    Axes {
        lambda: engine.lambda_key(&p.knobs),
        cascades: engine.counts(&p.knobs).list(),
        resolution_power_of_two: engine.power_of_two_maps(),
        fit: false,
        knob: engine.knob(&p.knobs, max_distance),
        distance: engine.has_distance(),
    }
}

/// The sweep axes of a config: its preset's, or csm-lab's own (every axis).
pub fn axes(config: &Config) -> Axes {
    match &config.shadow.preset {
        Some(p) => preset_axes(p, config.shadow.max_distance),
        None => Axes {
            lambda: Some("shadow.lambda"),
            cascades: (1..=16).collect(),
            resolution_power_of_two: false,
            fit: true,
            knob: None,
            distance: true,
        },
    }
}

/// Sets λ for a sweep point: `shadow.lambda`, or the preset's λ-like knob.
pub fn set_lambda(config: &mut Config, lambda: f64) -> Result<()> {
    if !(0.0..=1.0).contains(&lambda) {
        return Err(PresetError::OutOfRange {
            axis: "lambda",
            value: lambda.to_string(),
            range: "[0, 1]",
        }
        .into());
    }
    let Some(p) = &mut config.shadow.preset else {
        config.shadow.lambda = lambda;
        return Ok(());
    };
    let engine = p.knobs.engine();
    if engine.lambda_key(&p.knobs).is_none() {
        return Err(PresetError::NoLambda {
            preset: p.name.to_string(),
            split_rule: split_rule(&p.knobs),
        }
        .into());
    }
    engine.set_lambda(&mut p.knobs, lambda);
    config.shadow.lambda = lambda;
    Ok(())
}

/// Sets the cascade count for a sweep point, checking the preset accepts it.
pub fn set_cascades(config: &mut Config, n: usize) -> Result<()> {
    if let Some(p) = &config.shadow.preset {
        let ax = preset_axes(p, config.shadow.max_distance);
        if !ax.cascades.contains(&n) {
            return Err(PresetError::Cascades {
                preset: p.name.to_string(),
                count: n,
                valid: join(&ax.cascades),
            }
            .into());
        }
    } else if !(1..=16).contains(&n) {
        return Err(PresetError::CascadeCount { count: n }.into());
    }
    config.shadow.cascades = n;
    // Explicit far bounds (Bevy's) hold for one count only.
    if let Some(p) = &mut config.shadow.preset {
        drop_stale_bounds(&mut p.knobs, n);
    }
    Ok(())
}

/// Sets the map size for a sweep point, checking the preset accepts it.
pub fn set_resolution(config: &mut Config, n: u32) -> Result<()> {
    if !(16..=16384).contains(&n) {
        return Err(PresetError::OutOfRange {
            axis: "resolution",
            value: n.to_string(),
            range: "16..=16384",
        }
        .into());
    }
    if let Some(p) = &config.shadow.preset {
        if p.knobs.engine().power_of_two_maps() && !n.is_power_of_two() {
            return Err(PresetError::MapSize {
                preset: p.name.to_string(),
                size: n,
            }
            .into());
        }
    }
    config.shadow.resolution = n;
    Ok(())
}

/// Sets the preset's split knob for a sweep point, checking the engine's range.
pub fn set_knob(config: &mut Config, value: f64) -> Result<()> {
    let max_distance = config.shadow.max_distance;
    let Some(p) = &mut config.shadow.preset else {
        return Err(PresetError::NoKnob {
            preset: "csm-lab".to_string(),
        }
        .into());
    };
    let engine = p.knobs.engine();
    let Some(knob) = engine.knob(&p.knobs, max_distance) else {
        return Err(PresetError::NoKnob {
            preset: p.name.to_string(),
        }
        .into());
    };
    if !(value.is_finite() && value > knob.min && value <= knob.max) {
        return Err(PresetError::KnobRange {
            key: knob.key,
            value: value.to_string(),
            range: format!("({}, {}]", knob.min, knob.max),
        }
        .into());
    }
    engine.set_knob(&mut p.knobs, value);
    Ok(())
}

/// Sets the shadow distance for a sweep point (`shadow.max_distance`), checking it against
/// the preset's own rules.
pub(crate) fn set_distance(config: &mut Config, distance: f64) -> Result<()> {
    if !(distance.is_finite() && distance > 0.0 && distance <= 1e9) {
        return Err(PresetError::OutOfRange {
            axis: "distance",
            value: distance.to_string(),
            range: "(0, 1e9]",
        }
        .into());
    }
    if let Some(p) = &config.shadow.preset {
        if !p.knobs.engine().has_distance() {
            return Err(PresetError::NoDistance {
                preset: p.name.to_string(),
            }
            .into());
        }
    }
    config.shadow.max_distance = distance;
    Ok(())
}

/// Runs the engine's own checks that involve the count and the shadow distance (after a sweep
/// point changed the knob or the distance).
pub fn check_point(config: &Config) -> Result<()> {
    if let Some(p) = &config.shadow.preset {
        let label = config
            .path
            .as_ref()
            .map_or_else(|| config.name.clone(), |p| p.display().to_string());
        let v = crate::config::Validator { path: &label, text: "" };
        p.knobs
            .engine()
            .check(&p.knobs, config.shadow.cascades, config.shadow.max_distance, &v)?;
    }
    Ok(())
}
