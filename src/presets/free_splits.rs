//! Presets whose splits are free fractions (`sweep --optimize-splits`): which knob holds the
//! fractions for a cascade count, what they are fractions of, and setting them. Each engine
//! whose splits are free says so in its own file ([`super::Engine::FREE_SPLITS`], a [`FreeSplits`]);
//! the functions here ask the preset's engine.
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

use super::{Knobs, PresetName};

/// How an engine holds free split fractions: given by the engine's file as
/// [`super::Engine::FREE_SPLITS`]; every part must be given.
pub struct FreeSplits<K> {
    /// The knob that holds the fractions of `cascades` (at least 2) cascades.
    pub knob: fn(cascades: usize) -> FreeSplitKnob,
    /// What the fractions are fractions of, for the camera planes and the shadow distance
    /// (checked to be a non-empty range with a positive start by the caller).
    pub space: fn(k: &K, p: Planes) -> FractionSpace,
    /// The fractions the knob holds now for `cascades` cascades.
    pub configured: fn(k: &K, cascades: usize, p: Planes) -> Vec<f64>,
    /// The knob's values for `fractions` of `cascades` cascades ([`as_given`] when it holds the
    /// fractions themselves).
    pub values: fn(k: &K, cascades: usize, max_distance: f64, fractions: &[f64]) -> Vec<f64>,
    /// Stores the knob's values (as [`FreeSplits::values`] gives them).
    pub set: fn(k: &mut K, cascades: usize, values: Vec<f64>),
    /// The setting in the engine's own terms, from the knob's values and the fractions.
    pub setting: fn(k: &K, s: &Setting<'_>) -> String,
    /// Lines the engine's table needs before the knob in pasted config lines (Filament's
    /// split mode); usually empty.
    pub paste_prefix: &'static str,
    /// Whether a single value is pasted as a number (else always as a list).
    pub scalar_when_one: bool,
    /// Drops configured values that do not fit `cascades` cascades (a sweep point with another
    /// count); [`keep`] when the knob holds one value per count.
    pub fit_count: fn(k: &mut K, cascades: usize),
}

/// The camera planes and the shadow distance a fraction space is taken from.
#[derive(Debug, Clone, Copy)]
pub struct Planes {
    pub near: f64,
    pub far: f64,
    pub max_distance: f64,
}

/// What an engine writes its split setting from.
pub struct Setting<'a> {
    pub knob: &'a FreeSplitKnob,
    pub cascades: usize,
    pub max_distance: f64,
    /// The knob's values ([`FreeSplits::values`]).
    pub values: &'a [f64],
    /// The fractions.
    pub fractions: &'a [f64],
}

/// [`FreeSplits::values`] for a knob that holds the fractions themselves.
pub(crate) fn as_given<K>(_: &K, _: usize, _: f64, fractions: &[f64]) -> Vec<f64> {
    fractions.to_vec()
}

/// [`FreeSplits::fit_count`] for a knob that needs no change with the count.
pub(crate) fn keep<K>(_: &mut K, _: usize) {}

/// [`FreeSplits::values`] of a knob holding three fractions whatever the count (Godot's
/// splits, Filament's positions): the fractions, followed by the configured entries after them
/// when those still increase, else by entries spread evenly between the last fraction and 1
/// (the engine reads only the first ones).
pub(crate) fn padded_to_three(configured: [f64; 3], cascades: usize, fractions: &[f64]) -> Vec<f64> {
    let mut out = fractions.to_vec();
    let tail = &configured[cascades - 1..];
    let last = fractions.last().copied().unwrap_or(0.0);
    if tail.first().is_none_or(|&t| t > last) {
        out.extend_from_slice(tail);
    } else {
        let n = tail.len();
        out.extend((1..=n).map(|i| last + (1.0 - last) * i as f64 / (n + 1) as f64));
    }
    out
}

/// What Unity's and URP's split knobs hold.
pub(crate) const OF_SHADOW_DISTANCE: &str = "fractions of the shadow distance";

/// [`FreeSplits::space`] of fractions of the shadow distance (Unity, URP): from 0 to the
/// shadow distance (at most the far plane), the first cascade starting at the near plane.
pub(crate) fn shadow_distance_space<K>(_: &K, p: Planes) -> FractionSpace {
    FractionSpace {
        lo: 0.0,
        hi: p.far.min(p.max_distance),
        start: p.near,
    }
}

/// [`FreeSplits::setting`] of Unity's and URP's split knobs: a float, a `Vector2` or a
/// `Vector3` by the number of values.
pub(crate) fn unity_vector_setting<K>(_: &K, s: &Setting<'_>) -> String {
    let floats = |v: &[f64]| v.iter().map(|x| format!("{x}f")).collect::<Vec<_>>().join(", ");
    let term = s.knob.term;
    match s.values.len() {
        1 => format!("{term} = {}f", s.values[0]),
        2 => format!("{term} = new Vector2({})", floats(s.values)),
        _ => format!("{term} = new Vector3({})", floats(s.values)),
    }
}

/// The engines whose split positions are free fractions, in registry order.
pub(crate) fn free_split_engines() -> Vec<PresetName> {
    PresetName::ALL.into_iter().filter(|p| has_free_splits(*p)).collect()
}

/// Whether the engine's splits are free fractions.
pub(crate) fn has_free_splits(name: PresetName) -> bool {
    name.engine().has_free_splits()
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
pub(crate) fn free_split_knob(knobs: &Knobs, cascades: usize) -> Option<FreeSplitKnob> {
    if cascades < 2 {
        return None;
    }
    knobs.engine().free_split_knob(cascades)
}

/// What a preset's split fractions are fractions of, for the config's count and distance.
pub(crate) fn preset_fraction_space(config: &Config, knobs: &Knobs) -> Option<FractionSpace> {
    knobs
        .engine()
        .fraction_space(knobs, planes(config))
        .filter(|s| s.start > 0.0 && s.hi > s.start)
}

fn planes(config: &Config) -> Planes {
    Planes {
        near: config.camera.near,
        far: config.camera.far,
        max_distance: config.shadow.max_distance,
    }
}

/// The value the knob holds for `fractions` of `cascades` cascades ([`FreeSplits::values`]).
fn knob_values(knobs: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Vec<f64> {
    knobs.engine().fraction_values(knobs, cascades, max_distance, fractions)
}

/// Sets a preset's split fractions for its configured count (and, for Filament, its split mode
/// to explicit positions). Refused when the engine's splits are not free or the fractions are
/// not `cascades − 1` values strictly increasing inside (0, 1).
pub(crate) fn set_fractions(knobs: &mut Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Result<()> {
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
    knobs.engine().set_fraction_values(knobs, cascades, v);
    Ok(())
}

/// The fractions the preset uses now for `cascades` cascades (Filament's helpers evaluated on
/// `[near, shadowFar]`); None when its splits are not free.
pub(crate) fn configured_fractions(config: &Config, knobs: &Knobs, cascades: usize) -> Option<Vec<f64>> {
    free_split_knob(knobs, cascades)?;
    knobs.engine().configured_fractions(knobs, cascades, planes(config))
}

/// The lines to paste into the config file (the engine's table) to use `fractions`.
pub fn paste_lines(knobs: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Option<String> {
    let knob = free_split_knob(knobs, cascades)?;
    let (prefix, scalar_when_one) = knobs.engine().paste_form()?;
    let values = knob_values(knobs, cascades, max_distance, fractions);
    let list = |v: &[f64]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(", ");
    let (table, key) = knob.key.split_once('.').expect("engine.key");
    let value = if values.len() == 1 && scalar_when_one {
        values[0].to_string()
    } else {
        format!("[{}]", list(&values))
    };
    Some(format!("[{table}]\n{prefix}{key} = {value}"))
}

/// The setting in the engine's own terms (`QualitySettings.shadowCascade4Split = new
/// Vector3(0.05f, 0.15f, 0.4f)`).
pub fn engine_setting(knobs: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Option<String> {
    let knob = free_split_knob(knobs, cascades)?;
    let values = knob_values(knobs, cascades, max_distance, fractions);
    let s = Setting {
        knob: &knob,
        cascades,
        max_distance,
        values: &values,
        fractions,
    };
    knobs.engine().fractions_setting(knobs, &s)
}

/// Drops configured split values that do not fit `cascades` cascades (`bevy.bounds` not
/// holding `cascades − 1` values): a sweep point with another count uses the engine's own split
/// series.
pub(crate) fn drop_stale_bounds(knobs: &mut Knobs, cascades: usize) {
    knobs.engine().fit_fractions_to_count(knobs, cascades);
}
