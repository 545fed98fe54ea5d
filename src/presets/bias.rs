//! Each engine's shadow bias as csm-lab's ground truth models it: the engine's default rule,
//! converted per cascade to world units ([`BiasRule`]), and the name and unit of the setting a
//! user changes, so a recommended world-unit bias can be given back in the engine's terms.
//! The conversions are documented in `docs/presets.md`.

use csm_core::truth::{BiasRule, NormalOffset};

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

/// The modelled engines' default bias; None for the others (Unity built-in, whose defaults and
/// per-cascade scaling are not published, and the Dart engine, whose documents state no bias:
/// the `[shadow]` bias keys apply, 0 by default).
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
        // Per cascade: CSMDepthBias (10) x ShadowBias (0.5) x sphere radius / resolution, and
        // that times CSMSlopeScaleDepthBias (3) x ShadowSlopeBias (0.5) x the tangent of the
        // receiver's angle to the light, capped at 1. The radius over the resolution is half a
        // texel, so 2.5 texels plus 3.75 texels x min(tan, 1).
        PresetName::Unreal => Some(EngineBias {
            rule: BiasRule::TexelsTangent {
                depth_texels: UNREAL_CSM_DEPTH_BIAS * UNREAL_SHADOW_BIAS / 2.0,
                tangent_texels: UNREAL_CSM_DEPTH_BIAS * UNREAL_SHADOW_BIAS / 2.0
                    * UNREAL_CSM_SLOPE_SCALE
                    * UNREAL_SHADOW_SLOPE_BIAS,
                cap: UNREAL_MAX_SLOPE,
            },
            setting: "DirectionalLight Shadow Bias (ShadowBias)",
            unit: "Unreal's Shadow Bias (1 = r.Shadow.CSMDepthBias 10 x half a texel of the cascade)",
            scale: 2.0 / UNREAL_CSM_DEPTH_BIAS,
            one_for_all: true,
        }),
        // The 2017 cascade code: 0.05 x the lamp's bias (default 1) in depth normalised over
        // the lamp's clip range.
        PresetName::Eevee => Some(EngineBias {
            rule: BiasRule::RangeFraction {
                fraction: EEVEE_BIAS_FACTOR * EEVEE_LAMP_BIAS,
                normal_texels: 0.0,
                offset: NormalOffset::Along,
            },
            setting: "Lamp bias (shadow_buffer_bias)",
            unit: "lamp bias (1 = 0.05 of the lamp's clip range)",
            scale: 1.0 / EEVEE_BIAS_FACTOR,
            one_for_all: true,
        }),
        // The seed's shader: max(0.05 (1 - N.L), 0.005) in depth normalised over each cascade's
        // padded light depth range.
        PresetName::LearnOpenGl => Some(EngineBias {
            rule: BiasRule::RangeFacing {
                factor: 0.05,
                floor: 0.005,
            },
            setting: "the 0.005 floor of max(0.05 (1 - N.L), 0.005)",
            unit: "normalised depth",
            scale: 1.0,
            one_for_all: true,
        }),
        // The sample adds 0.005 to the casters' clip-space z; on OpenGL (z in [-1, 1]) that is
        // 0.0025 of the cascade's light depth range away from the light.
        PresetName::UnitySample => Some(EngineBias {
            rule: BiasRule::RangeFraction {
                fraction: UNITY_SAMPLE_CLIP_BIAS / 2.0,
                normal_texels: 0.0,
                offset: NormalOffset::Along,
            },
            setting: "_gShadowBias",
            unit: "clip-space z on OpenGL (2 x normalised depth)",
            scale: 2.0,
            one_for_all: true,
        }),
        _ => None,
    }
}

/// Unreal's `r.Shadow.CSMDepthBias` default.
pub const UNREAL_CSM_DEPTH_BIAS: f64 = 10.0;
/// Unreal's `r.Shadow.CSMSlopeScaleDepthBias` default.
pub const UNREAL_CSM_SLOPE_SCALE: f64 = 3.0;
/// The directional light's `ShadowBias` default.
pub const UNREAL_SHADOW_BIAS: f64 = 0.5;
/// The directional light's `ShadowSlopeBias` default.
pub const UNREAL_SHADOW_SLOPE_BIAS: f64 = 0.5;
/// Unreal's `r.Shadow.ShadowMaxSlopeScaleDepthBias` default: the tangent's cap.
pub const UNREAL_MAX_SLOPE: f64 = 1.0;
/// EEVEE's factor on the lamp bias (normalised depth per unit of bias).
pub const EEVEE_BIAS_FACTOR: f64 = 0.05;
/// Blender's default lamp bias.
pub const EEVEE_LAMP_BIAS: f64 = 1.0;
/// The Unity sample's clip-space bias.
pub const UNITY_SAMPLE_CLIP_BIAS: f64 = 0.005;

/// The filter of an engine's shadow lookups (docs/presets.md, "Filter"): the two seeds that
/// compare point-sampled texels read nearest; engines sample with a comparison sampler and
/// linear filtering (hardware PCF), as csm-lab's own pipeline does.
pub fn engine_filter(name: PresetName) -> csm_core::truth::PcfFilter {
    use csm_core::truth::PcfFilter;
    match name {
        PresetName::LearnOpenGl | PresetName::UnitySample => PcfFilter::Nearest,
        _ => PcfFilter::Bilinear,
    }
}
