//! Presets whose splits are free fractions (`sweep --optimize-splits`): which engines, which
//! knob holds the fractions for a cascade count, what they are fractions of, and setting them.
//!
//! Free: Unity and URP (a split knob per count, fractions of the shadow distance), Godot
//! (`split_1..3`, fractions of [near, max distance]) and Filament (`cascadeSplitPositions`,
//! fractions of [near, shadowFar]) and Bevy (`CascadeShadowConfig::bounds`, the far bounds of
//! every cascade but the last, as fractions of the maximum distance: `bevy.bounds`). Not
//! free: Unreal (one distribution exponent), three.js, EEVEE, Dart (a λ or exponent),
//! LearnOpenGL and the Unity sample (fixed fractions in code).

use crate::config::Config;
use crate::error::Result;
use csm_core::free_splits::{valid, FractionSpace};

use super::filament::FilamentSplit;
use super::*;

/// The engines whose split positions are free fractions.
pub const FREE_SPLIT_ENGINES: [PresetName; 5] = [
    PresetName::Unity,
    PresetName::UnityUrp,
    PresetName::Godot,
    PresetName::Filament,
    PresetName::Bevy,
];

/// Whether the engine's splits are free fractions.
pub fn has_free_splits(name: PresetName) -> bool {
    FREE_SPLIT_ENGINES.contains(&name)
}

/// The engine knob that holds the split fractions for one cascade count.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeSplitKnob {
    /// The config key (`unity.cascade4_split`).
    pub key: &'static str,
    /// The setting in the engine's own terms (`QualitySettings.shadowCascade4Split`).
    pub term: &'static str,
    /// What the fractions are fractions of, in words.
    pub of: &'static str,
}

/// The knob holding the fractions of `cascades` cascades; None with one cascade (no split) or
/// an engine whose splits are not free.
pub fn free_split_knob(knobs: &Knobs, cascades: usize) -> Option<FreeSplitKnob> {
    let (key, term, of) = match (knobs.name(), cascades) {
        (_, 0 | 1) => return None,
        (PresetName::Unity, 2) => (
            "unity.cascade2_split",
            "QualitySettings.shadowCascade2Split",
            "fractions of the shadow distance",
        ),
        (PresetName::Unity, _) => (
            "unity.cascade4_split",
            "QualitySettings.shadowCascade4Split",
            "fractions of the shadow distance",
        ),
        (PresetName::UnityUrp, 2) => (
            "unity-urp.cascade2_split",
            "UniversalRenderPipelineAsset.cascade2Split",
            "fractions of the shadow distance",
        ),
        (PresetName::UnityUrp, 3) => (
            "unity-urp.cascade3_split",
            "UniversalRenderPipelineAsset.cascade3Split",
            "fractions of the shadow distance",
        ),
        (PresetName::UnityUrp, _) => (
            "unity-urp.cascade4_split",
            "UniversalRenderPipelineAsset.cascade4Split",
            "fractions of the shadow distance",
        ),
        (PresetName::Godot, _) => (
            "godot.splits",
            "DirectionalLight3D.directional_shadow_split_1..3",
            "fractions of [near, max distance]",
        ),
        (PresetName::Filament, _) => (
            "filament.split_positions",
            "ShadowOptions.cascadeSplitPositions",
            "fractions of [near, shadowFar]",
        ),
        (PresetName::Bevy, _) => (
            "bevy.bounds",
            "CascadeShadowConfig.bounds",
            "far bounds as fractions of the maximum distance",
        ),
        _ => return None,
    };
    Some(FreeSplitKnob { key, term, of })
}

/// What a preset's split fractions are fractions of, for the config's count and distance.
pub fn preset_fraction_space(config: &Config, knobs: &Knobs) -> Option<FractionSpace> {
    let (near, far, dist) = (config.camera.near, config.camera.far, config.shadow.max_distance);
    match knobs.name() {
        PresetName::Unity | PresetName::UnityUrp => Some(FractionSpace {
            lo: 0.0,
            hi: far.min(dist),
            start: near,
        }),
        PresetName::Godot => {
            let max_d = far.min(dist).max(near + 0.001);
            let min_d = near.min(max_d);
            Some(FractionSpace {
                lo: min_d,
                hi: max_d,
                start: min_d,
            })
        }
        PresetName::Filament => Some(FractionSpace {
            lo: near,
            hi: dist,
            start: near,
        }),
        PresetName::Bevy => {
            let min = match knobs {
                Knobs::Bevy(k) => k.minimum_distance,
                _ => 0.0,
            };
            Some(FractionSpace {
                lo: 0.0,
                hi: dist,
                start: min.max(near),
            })
        }
        _ => None,
    }
    .filter(|s| s.start > 0.0 && s.hi > s.start)
}

/// The value the knob holds for `fractions` of `cascades` cascades: the fractions themselves
/// (Bevy: times the maximum distance),
/// or (Godot's three splits, Filament's three positions, with fewer cascades) the fractions
/// followed by the configured entries after them when those still increase, else by entries
/// spread evenly between the last fraction and 1 (the engine reads only the first ones).
pub fn knob_values(knobs: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Vec<f64> {
    if knobs.name() == PresetName::Bevy {
        // Bevy's bounds are distances.
        return fractions.iter().map(|p| p * max_distance).collect();
    }
    let configured: Option<[f64; 3]> = match knobs {
        Knobs::Godot(k) => Some(k.splits),
        Knobs::Filament(k) => Some(k.split_positions),
        _ => None,
    };
    let Some(conf) = configured else {
        return fractions.to_vec();
    };
    let used = cascades - 1;
    let mut out = fractions.to_vec();
    let tail = &conf[used..];
    let last = fractions.last().copied().unwrap_or(0.0);
    if tail.first().is_none_or(|&t| t > last) {
        out.extend_from_slice(tail);
    } else {
        let n = tail.len();
        out.extend((1..=n).map(|i| last + (1.0 - last) * i as f64 / (n + 1) as f64));
    }
    out
}

/// Sets a preset's split fractions for its configured count (and, for Filament, its split mode
/// to explicit positions). Refused when the engine's splits are not free or the fractions are
/// not `cascades − 1` values strictly increasing inside (0, 1).
pub fn set_fractions(knobs: &mut Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Result<()> {
    let name = knobs.name();
    let Some(knob) = free_split_knob(knobs, cascades) else {
        return Err(crate::error::PresetError::NoKnob {
            preset: name.to_string(),
        }
        .into());
    };
    if fractions.len() + 1 != cascades || !valid(fractions) {
        return Err(crate::error::PresetError::KnobRange {
            key: knob.key,
            value: format!("{fractions:?}"),
            range: format!("{} fractions strictly increasing inside (0, 1)", cascades - 1),
        }
        .into());
    }
    let v = knob_values(knobs, cascades, max_distance, fractions);
    let arr = |i: usize| v[i];
    match knobs {
        Knobs::Unity(k) if cascades == 2 => k.cascade2_split = v[0],
        Knobs::Unity(k) => k.cascade4_split = [arr(0), arr(1), arr(2)],
        Knobs::UnityUrp(k) if cascades == 2 => k.cascade2_split = v[0],
        Knobs::UnityUrp(k) if cascades == 3 => k.cascade3_split = [arr(0), arr(1)],
        Knobs::UnityUrp(k) => k.cascade4_split = [arr(0), arr(1), arr(2)],
        Knobs::Godot(k) => k.splits = [arr(0), arr(1), arr(2)],
        Knobs::Filament(k) => {
            k.split_mode = FilamentSplit::Positions;
            k.split_positions = [arr(0), arr(1), arr(2)];
        }
        Knobs::Bevy(k) => k.bounds = Some(v),
        _ => unreachable!("free_split_knob is None for other engines"),
    }
    Ok(())
}

/// The fractions the preset uses now for `cascades` cascades (Filament's helpers evaluated on
/// `[near, shadowFar]`); None when its splits are not free.
pub fn configured_fractions(config: &Config, knobs: &Knobs, cascades: usize) -> Option<Vec<f64>> {
    free_split_knob(knobs, cascades)?;
    let used = cascades - 1;
    Some(match knobs {
        Knobs::Unity(k) if cascades == 2 => vec![k.cascade2_split],
        Knobs::Unity(k) => k.cascade4_split.to_vec(),
        Knobs::UnityUrp(k) if cascades == 2 => vec![k.cascade2_split],
        Knobs::UnityUrp(k) if cascades == 3 => k.cascade3_split.to_vec(),
        Knobs::UnityUrp(k) => k.cascade4_split.to_vec(),
        Knobs::Godot(k) => k.splits[..used].to_vec(),
        Knobs::Filament(k) => filament::filament_positions(k, cascades, config.camera.near, config.shadow.max_distance),
        Knobs::Bevy(k) => {
            let max = config.shadow.max_distance;
            let fars = match k.bounds.as_ref().filter(|b| b.len() + 1 == cascades) {
                Some(b) => b.clone(),
                None => bevy::bevy_far_bounds(cascades, k.first_cascade_far_bound, max)[..used].to_vec(),
            };
            fars.iter().map(|d| d / max).collect()
        }
        _ => return None,
    })
}

/// The lines to paste into the config file (the engine's table) to use `fractions`.
pub fn paste_lines(knobs: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Option<String> {
    let knob = free_split_knob(knobs, cascades)?;
    let values = knob_values(knobs, cascades, max_distance, fractions);
    let list = |v: &[f64]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(", ");
    let (table, key) = knob.key.split_once('.').expect("engine.key");
    let value = if values.len() == 1 && knobs.name() != PresetName::Bevy {
        values[0].to_string()
    } else {
        format!("[{}]", list(&values))
    };
    let mode = if knobs.name() == PresetName::Filament {
        "split_mode = \"positions\"\n"
    } else {
        ""
    };
    Some(format!("[{table}]\n{mode}{key} = {value}"))
}

/// The setting in the engine's own terms (`QualitySettings.shadowCascade4Split = new
/// Vector3(0.05f, 0.15f, 0.4f)`).
pub fn engine_setting(knobs: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Option<String> {
    let knob = free_split_knob(knobs, cascades)?;
    let values = knob_values(knobs, cascades, max_distance, fractions);
    let floats = |v: &[f64]| v.iter().map(|x| format!("{x}f")).collect::<Vec<_>>().join(", ");
    Some(match knobs.name() {
        PresetName::Unity | PresetName::UnityUrp => match values.len() {
            1 => format!("{} = {}f", knob.term, values[0]),
            2 => format!("{} = new Vector2({})", knob.term, floats(&values)),
            _ => format!("{} = new Vector3({})", knob.term, floats(&values)),
        },
        PresetName::Godot => values
            .iter()
            .take(cascades - 1)
            .enumerate()
            .map(|(i, v)| format!("directional_shadow_split_{} = {v}", i + 1))
            .collect::<Vec<_>>()
            .join(", "),
        PresetName::Filament => format!(
            "ShadowOptions.cascadeSplitPositions = {{ {} }}",
            fractions.iter().map(|x| format!("{x}f")).collect::<Vec<_>>().join(", ")
        ),
        PresetName::Bevy => {
            let (min, overlap) = match knobs {
                Knobs::Bevy(k) => (k.minimum_distance, k.overlap_proportion),
                _ => (0.0, 0.0),
            };
            format!(
                "CascadeShadowConfig {{ bounds: vec![{}, {max_distance}], overlap_proportion: {overlap}, minimum_distance: {min} }}",
                values.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(", ")
            )
        }
        _ => return None,
    })
}

/// Drops explicit far bounds (`bevy.bounds`) that do not hold `cascades − 1` values: a sweep
/// point with another count uses the engine's own split series.
pub fn drop_stale_bounds(knobs: &mut Knobs, cascades: usize) {
    if let Knobs::Bevy(k) = knobs {
        if k.bounds.as_ref().is_some_and(|b| b.len() + 1 != cascades) {
            k.bounds = None;
        }
    }
}
