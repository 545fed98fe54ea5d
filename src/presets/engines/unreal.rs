//! Unreal Engine (`DirectionalLightComponent.cpp`, `ShadowSetup.cpp`): geometric split weights
//! with a transition band, Unreal's bounding sphere with a 4-texel border, fmod snapping.
//! Centimetre constants are converted to metres.

use crate::presets::{Described, around, check_range, snap, Counts, Dims, Engine, EngineScheme, Fields, Fitting, Knob, KnobContext, Layout, Terms,
    Values,
};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use csm_core::cascades::LightDepthRule;
use csm_core::fitting::Sphere;
use csm_core::geometry::Lens;
use csm_core::snapping::{SnapMode, SnapRule};

use crate::presets::bias::{BiasModel, EngineBias};
use csm_core::truth::BiasRule;

pub struct Unreal;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnrealTable {
    cascade_distribution_exponent: Option<f64>,
    transition_fraction: Option<f64>,
}

/// Unreal directional light (dynamic shadow distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnrealKnobs {
    pub cascade_distribution_exponent: f64,
    pub transition_fraction: f64,
}

/// Unreal split distances: `near + (Σ_{k<i} e^k / Σ_{k<N} e^k)·(distance − near)`.
pub(crate) fn unreal_splits(cascades: usize, exponent: f64, near: f64, distance: f64) -> Vec<f64> {
    let total: f64 = (0..cascades).map(|k| exponent.powi(k as i32)).sum();
    let mut acc = 0.0;
    let mut out = vec![near];
    for i in 1..cascades {
        acc += exponent.powi(i as i32 - 1);
        out.push(near + acc / total * (distance - near));
    }
    out.push(distance);
    out
}

/// Unreal's bounding sphere of a slice: centre depth `far − offset` clamped to the slice, with
/// `offset = (Db² − Da²)/(2L) + L/2`, radius the largest corner distance, at least 1 cm.
pub fn unreal_sphere(near: f64, far: f64, lens: &Lens) -> Sphere {
    let da2 = (lens.tan_h * far).powi(2) + (lens.tan_v * far).powi(2);
    let db2 = (lens.tan_h * near).powi(2) + (lens.tan_v * near).powi(2);
    let l = far - near;
    let offset = (db2 - da2) / (2.0 * l) + 0.5 * l;
    let c = (far - offset).clamp(near, far);
    let r_near = (db2 + (c - near).powi(2)).sqrt();
    let r_far = (da2 + (far - c).powi(2)).sqrt();
    Sphere {
        centre_depth: c,
        radius: r_near.max(r_far).max(0.01),
    }
}

/// Unreal's border per side, in texels (modelled as the 4-texel snap step).
pub(crate) const UNREAL_BORDER_TEXELS: f64 = 4.0;

impl Engine for Unreal {
    type Knobs = UnrealKnobs;
    type Table = UnrealTable;
    const NAME: &'static str = "unreal";
    const SOURCE: &'static str = "Unreal Engine CSM: DirectionalLightComponent.cpp, ShadowSetup.cpp";

    /// Per cascade: CSMDepthBias (10) x ShadowBias (0.5) x sphere radius / resolution, and
    /// that times CSMSlopeScaleDepthBias (3) x ShadowSlopeBias (0.5) x the tangent of the
    /// receiver's angle to the light, capped at 1. The radius over the resolution is half a
    /// texel, so 2.5 texels plus 3.75 texels x min(tan, 1).
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::TexelsTangent {
                depth_texels: UNREAL_CSM_DEPTH_BIAS * UNREAL_SHADOW_BIAS / 2.0,
                tangent_texels: UNREAL_CSM_DEPTH_BIAS * UNREAL_SHADOW_BIAS / 2.0
                    * UNREAL_CSM_SLOPE_SCALE
                    * UNREAL_SHADOW_SLOPE_BIAS,
                cap: UNREAL_MAX_SLOPE,
            },
            "DirectionalLight Shadow Bias (ShadowBias)",
            "Unreal's Shadow Bias (1 = r.Shadow.CSMDepthBias 10 x half a texel of the cascade)",
        )
        .scaled(2.0 / UNREAL_CSM_DEPTH_BIAS))
    }

    fn knobs(t: &UnrealTable, cx: &KnobContext<'_>) -> Result<UnrealKnobs> {
        let v = cx.v;
        let e = t.cascade_distribution_exponent.unwrap_or(3.0);
        let tr = t.transition_fraction.unwrap_or(0.1);
        Ok(UnrealKnobs {
            cascade_distribution_exponent: check_range(
                v,
                "unreal.cascade_distribution_exponent",
                e,
                0.1,
                10.0,
                false,
                false,
            )?,
            transition_fraction: check_range(v, "unreal.transition_fraction", tr, 0.0, 0.3, false, false)?,
        })
    }

    fn defaults(_: &UnrealKnobs, _camera_far: f64) -> (usize, f64) {
        (3, 200.0)
    }

    fn counts(_: &UnrealKnobs) -> Counts {
        Counts::Allowed((1..=10).collect())
    }

    fn knob(k: &UnrealKnobs, _max_distance: f64) -> Option<Knob> {
        let e = k.cascade_distribution_exponent;
        Some(Knob {
            key: "unreal.cascade_distribution_exponent",
            term: "CascadeDistributionExponent",
            value: e,
            min: 0.1,
            max: 10.0,
            sweep: around(e, &[1.0, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0], 0.1, 10.0),
        })
    }

    fn set_knob(k: &mut UnrealKnobs, value: f64) {
        k.cascade_distribution_exponent = value;
    }

    fn layout(k: &UnrealKnobs, cascades: usize, max_distance: f64, near: f64, _far: f64) -> Layout {
        let s = unreal_splits(cascades, k.cascade_distribution_exponent, near, max_distance);
        let m = cascades;
        let fitted = (0..m)
            .map(|i| {
                let (a, b) = (s[i], s[i + 1]);
                // Every far end but the last is extended by the transition band.
                let ext = if i + 1 < m {
                    (b - a) * k.transition_fraction
                } else {
                    0.0
                };
                (a, b + ext)
            })
            .collect();
        Layout { fitted, selection: s }
    }

    fn snap_rule(_: &UnrealKnobs) -> SnapRule {
        snap(SnapMode::Trunc, 4)
    }

    fn scheme(_: &UnrealKnobs, f: &Fitting<'_>) -> EngineScheme {
        let s = f.spheres(|a, b| unreal_sphere(a, b, &f.lens));
        EngineScheme::fixed(
            "sphere-minimal+border",
            Fitting::axis(&s),
            f.on(&s, f.resolution as f64 - 2.0 * UNREAL_BORDER_TEXELS),
            LightDepthRule::Sphere {
                radius: s.iter().map(|s| s.radius).collect(),
                toward_light: 0.0,
                min_half: 50.0,
            },
        )
    }

    fn split_rule(k: &UnrealKnobs) -> String {
        format!(
            "geometric weights, exponent {}, transition {}",
            k.cascade_distribution_exponent, k.transition_fraction
        )
    }

    const LIGHT_DEPTH: Described<UnrealKnobs> = Described::Fixed("sphere ± max(r, 50 m); casters kept");

    const TERMS: Terms = Terms {
        comment: ";",
        language:
            "Unreal Engine: DefaultEngine.ini and the DirectionalLightComponent's properties, distances in centimetres",
        template: "\
[SystemSettings]
r.Shadow.MaxCSMResolution={{r.Shadow.MaxCSMResolution}}
Begin Object Class=/Script/Engine.DirectionalLightComponent Name=\"LightComponent0\"
   DynamicShadowDistanceMovableLight={{DynamicShadowDistanceMovableLight}}
   DynamicShadowCascades={{DynamicShadowCascades}}
   CascadeDistributionExponent={{CascadeDistributionExponent}}
   CascadeTransitionFraction={{CascadeTransitionFraction}}
End Object",
    };

    /// Unreal's distances are in centimetres: csm-lab's metres × 100.
    fn terms(k: &UnrealKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        Values::new()
            .int("r.Shadow.MaxCSMResolution", d.resolution)
            .num(
                "DynamicShadowDistanceMovableLight",
                d.max_distance.unwrap_or(200.0) * 100.0,
            )
            .int("DynamicShadowCascades", d.cascades)
            .num("CascadeDistributionExponent", k.cascade_distribution_exponent)
            .num("CascadeTransitionFraction", k.transition_fraction)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(UnrealKnobs, Dims)> {
        let table = UnrealTable {
            cascade_distribution_exponent: Some(
                f.num("CascadeDistributionExponent", "unreal.cascade_distribution_exponent")?,
            ),
            transition_fraction: Some(f.num("CascadeTransitionFraction", "unreal.transition_fraction")?),
        };
        let dims = Dims {
            cascades: f.count("DynamicShadowCascades", "shadow.cascades")?,
            resolution: f.size("r.Shadow.MaxCSMResolution", "shadow.resolution")?,
            max_distance: Some(f.num("DynamicShadowDistanceMovableLight", "shadow.max_distance")? / 100.0),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }
}

/// Unreal's `r.Shadow.CSMDepthBias` default.
const UNREAL_CSM_DEPTH_BIAS: f64 = 10.0;

/// Unreal's `r.Shadow.CSMSlopeScaleDepthBias` default.
const UNREAL_CSM_SLOPE_SCALE: f64 = 3.0;

/// The directional light's `ShadowBias` default.
const UNREAL_SHADOW_BIAS: f64 = 0.5;

/// The directional light's `ShadowSlopeBias` default.
const UNREAL_SHADOW_SLOPE_BIAS: f64 = 0.5;

/// Unreal's `r.Shadow.ShadowMaxSlopeScaleDepthBias` default: the tangent's cap.
const UNREAL_MAX_SLOPE: f64 = 1.0;
