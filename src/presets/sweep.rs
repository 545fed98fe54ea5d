//! What a parameter sweep over a preset may vary, and setting one sweep point.

use crate::config::Config;
use crate::error::{Error, Result};

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
    let lambda = match &p.knobs {
        Knobs::Dart(_) => Some("dart.lambda"),
        Knobs::Eevee(_) => Some("eevee.cascade_exponent"),
        Knobs::Filament(f) if f.split_mode == FilamentSplit::Practical => Some("filament.lambda"),
        _ => None,
    };
    let cascades = match counts(&p.knobs) {
        Counts::Clamped(lo, hi) => (lo..=hi).collect(),
        Counts::Allowed(v) => v,
        Counts::Fixed(n) => vec![n],
    };
    Axes {
        lambda,
        cascades,
        resolution_power_of_two: power_of_two_maps(p.name),
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
        return Err(Error::Other(format!("lambda {lambda} is outside [0, 1]")));
    }
    let Some(p) = &mut config.shadow.preset else {
        *config = config.with_lambda(lambda)?;
        return Ok(());
    };
    match &mut p.knobs {
        Knobs::Dart(d) => d.lambda = lambda,
        Knobs::Eevee(e) => e.cascade_exponent = lambda,
        Knobs::Filament(f) if f.split_mode == FilamentSplit::Practical => f.lambda = lambda,
        _ => {
            return Err(Error::Other(format!(
                "the {} preset has no λ to sweep ({}); remove the lambda axis",
                p.name,
                split_rule(&p.knobs)
            )))
        }
    }
    // TODO(presets): a validating constructor for preset knobs; until then the knob is set
    // above and `with_lambda` sets shadow.lambda and re-runs the cross-checks (camera path,
    // binary32 range) on the changed config.
    *config = config.with_lambda(lambda)?;
    Ok(())
}

/// Sets the cascade count for a sweep point, checking the preset accepts it.
pub fn set_cascades(config: &mut Config, n: usize) -> Result<()> {
    if let Some(p) = &config.shadow.preset {
        let ax = preset_axes(p);
        if !ax.cascades.contains(&n) {
            return Err(Error::Other(format!(
                "the {} preset does not take {n} cascades (valid: {})",
                p.name,
                join(&ax.cascades)
            )));
        }
    } else if !(1..=16).contains(&n) {
        return Err(Error::Other(format!("{n} cascades is outside 1..=16")));
    }
    *config = config.with_cascades(n)?;
    Ok(())
}

/// Sets the map size for a sweep point, checking the preset accepts it.
pub fn set_resolution(config: &mut Config, n: u32) -> Result<()> {
    if !(16..=16384).contains(&n) {
        return Err(Error::Other(format!("resolution {n} is outside 16..=16384")));
    }
    if let Some(p) = &config.shadow.preset {
        if power_of_two_maps(p.name) && !n.is_power_of_two() {
            return Err(Error::Other(format!(
                "the {} preset takes power-of-two map sizes only, not {n}",
                p.name
            )));
        }
    }
    *config = config.with_resolution(n)?;
    Ok(())
}
