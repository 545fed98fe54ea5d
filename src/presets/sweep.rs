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
}

/// The sweep axes of a preset.
pub fn preset_axes(p: &Preset) -> Axes {
    let engine = p.knobs.engine();
    Axes {
        lambda: engine.lambda_key(&p.knobs),
        cascades: engine.counts(&p.knobs).list(),
        resolution_power_of_two: engine.power_of_two_maps(),
        fit: false,
    }
}

/// The sweep axes of a config: its preset's, or csm-lab's own (every axis).
pub fn axes(config: &Config) -> Axes {
    match &config.shadow.preset {
        Some(p) => preset_axes(p),
        None => Axes {
            lambda: Some("shadow.lambda"),
            cascades: (1..=16).collect(),
            resolution_power_of_two: false,
            fit: true,
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
        let ax = preset_axes(p);
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
