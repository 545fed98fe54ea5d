//! Each engine's shadow bias as csm-lab's ground truth models it: the engine's default rule,
//! converted per cascade to world units ([`BiasRule`]), and the name and unit of the setting a
//! user changes, so a recommended world-unit bias can be given back in the engine's terms.
//! The conversions are documented in `docs/presets.md`.

use crate::core::truth::{BiasRule, NormalOffset};

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
    /// Whether the engine sets one value for every cascade (then the recommendation is the
    /// largest cascade's).
    pub one_for_all: bool,
}

impl EngineBias {
    /// A world-unit depth bias in the engine's own setting for a cascade.
    pub fn own_value(&self, world: f64, texel: f64, range: f64) -> f64 {
        self.rule.depth_in_own_units(world, texel, range) * self.scale
    }
}

/// The modelled engines' default bias; None for the others (their bias is not modelled: the
/// `[shadow]` bias keys apply, 0 by default).
pub fn engine_bias(name: PresetName) -> Option<EngineBias> {
    match name {
        // Receiver moved by normal x normal_bias x texel (normal_bias pre-multiplied by sqrt 2)
        // and by depth_bias toward the light; defaults 0.02 and 1.8.
        PresetName::Bevy => Some(EngineBias {
            rule: BiasRule::World {
                depth: 0.02,
                slope: 0.0,
                normal_texels: 1.8 * std::f64::consts::SQRT_2,
                offset: NormalOffset::Along,
            },
            setting: "DirectionalLight::shadow_depth_bias",
            unit: "world units",
            scale: 1.0,
            one_for_all: true,
        }),
        // Depth bias = bias / 100 x the cascade's depth range; normal bias x texel x
        // (1 - max(0, N.L)) with its part along the light removed; defaults 0.1 and 2.0.
        PresetName::Godot => Some(EngineBias {
            rule: BiasRule::RangeFraction {
                fraction: 0.1 / 100.0,
                normal_texels: 2.0,
                offset: NormalOffset::Lateral,
            },
            setting: "DirectionalLight3D.shadow_bias",
            unit: "percent of the cascade's depth range",
            scale: 100.0,
            one_for_all: true,
        }),
        // Light camera moved by constantBias (world units); normal bias 0.5 x normalBias x
        // texel; polygon offset slope 2 (its constant 0.5 is in depth-buffer steps: left out).
        PresetName::Filament => Some(EngineBias {
            rule: BiasRule::World {
                depth: 0.001,
                slope: 2.0,
                normal_texels: 0.5,
                offset: NormalOffset::Along,
            },
            setting: "ShadowOptions.constantBias",
            unit: "world units",
            scale: 1.0,
            one_for_all: true,
        }),
        // Depth and normal bias scale with each cascade's texel size; defaults 1 and 1.
        PresetName::UnityUrp => Some(EngineBias {
            rule: BiasRule::Texels {
                depth_texels: 1.0,
                normal_texels: 1.0,
            },
            setting: "Depth Bias",
            unit: "texels of the cascade",
            scale: 1.0,
            one_for_all: true,
        }),
        // shadowBias 1e-6 in normalised depth: a fraction of the light depth range.
        PresetName::Threejs => Some(EngineBias {
            rule: BiasRule::RangeFraction {
                fraction: 1e-6,
                normal_texels: 0.0,
                offset: NormalOffset::Along,
            },
            setting: "CSM shadowBias",
            unit: "normalised depth",
            scale: 1.0,
            one_for_all: true,
        }),
        _ => None,
    }
}
