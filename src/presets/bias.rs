//! Each engine's shadow bias as csm-lab's ground truth models it: the engine's default rule,
//! converted per cascade to world units ([`BiasRule`]), and the name and unit of the setting a
//! user changes, so a recommended world-unit bias can be given back in the engine's terms.
//! Each engine's rule is in its own file (`presets/engines/<engine>.rs`, [`super::Engine::bias`]);
//! the conversions are documented in `docs/presets.md`.

use csm_core::truth::BiasRule;

use super::PresetName;

/// An engine's default bias and the setting that holds its depth term.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngineBias {
    pub rule: BiasRule,
    /// The engine's name for the depth bias setting.
    pub setting: &'static str,
    /// Its unit, in words.
    pub unit: &'static str,
    /// The setting's value is the rule's own unit times this (Godot's bias is in percent of
    /// the depth range).
    pub scale: f64,
}

/// Every engine modelled sets one depth bias for all its cascades, so the value to give back
/// is the largest cascade's (the report says so).
impl EngineBias {
    /// A rule whose setting is in the rule's own unit.
    pub(crate) const fn new(rule: BiasRule, setting: &'static str, unit: &'static str) -> Self {
        EngineBias {
            rule,
            setting,
            unit,
            scale: 1.0,
        }
    }

    /// The same rule with the setting's value the rule's own unit times `scale`.
    pub(crate) const fn scaled(self, scale: f64) -> Self {
        EngineBias { scale, ..self }
    }

    /// A world-unit depth bias in the engine's own setting for a cascade.
    pub fn own_value(&self, world: f64, texel: f64, range: f64) -> f64 {
        self.rule.depth_in_own_units(world, texel, range) * self.scale
    }
}

/// An engine's answer to "what is your default shadow bias?" ([`super::Engine::bias`]): the
/// rule csm-lab's ground truth models, or the reason it models none. Every engine gives one of
/// the two; there is no default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BiasModel {
    Rule(EngineBias),
    /// No rule is modelled, and why: the `[shadow]` bias keys apply (0 by default).
    NotModelled(&'static str),
}

impl BiasModel {
    /// The rule, if one is modelled.
    pub(crate) fn rule(self) -> Option<EngineBias> {
        match self {
            BiasModel::Rule(b) => Some(b),
            BiasModel::NotModelled(_) => None,
        }
    }
}

/// The engine's default bias; None when it models none (its [`BiasModel::NotModelled`] says
/// why).
pub fn engine_bias(name: PresetName) -> Option<EngineBias> {
    name.engine().bias().rule()
}

/// The filter of an engine's shadow lookups (docs/presets.md, "Filter"): the two seeds that
/// compare point-sampled texels read nearest; engines sample with a comparison sampler and
/// linear filtering (hardware PCF), as csm-lab's own pipeline does.
pub(crate) fn engine_filter(name: PresetName) -> csm_core::truth::PcfFilter {
    use csm_core::truth::PcfFilter;
    match name {
        PresetName::LearnOpenGl | PresetName::UnitySample => PcfFilter::Nearest,
        _ => PcfFilter::Bilinear,
    }
}
