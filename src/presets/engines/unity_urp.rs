//! Unity's Universal Render Pipeline (`UniversalRenderPipelineAsset.cs`, `Shadows.hlsl`):
//! fractions of the shadow distance, one atlas of 2048 (tiles of 1024 from two cascades on),
//! modelled like Unity's built-in pipeline for the fit and snap.

use crate::presets::{Described, check_range, complete_fractions, distance_fractions, fractions, minimal_sphere_scheme, Counts, Dims, Engine,
    EngineScheme, Fields, Fitting, KnobContext, Layout, Target, Terms, Values,
};
use serde::{Deserialize, Serialize};

use crate::error::Result;

use crate::presets::bias::{BiasModel, EngineBias};
use crate::presets::free_splits::{
    as_given, keep, shadow_distance_space, unity_vector_setting, FreeSplitKnob, FreeSplits, OF_SHADOW_DISTANCE,
};
use csm_core::truth::BiasRule;

pub struct UnityUrp;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnityUrpTable {
    cascade2_split: Option<f64>,
    cascade3_split: Option<Vec<f64>>,
    cascade4_split: Option<Vec<f64>>,
}

/// Unity URP asset (shadow distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnityUrpKnobs {
    pub cascade2_split: f64,
    pub cascade3_split: [f64; 2],
    pub cascade4_split: [f64; 3],
}

impl Engine for UnityUrp {
    type Knobs = UnityUrpKnobs;
    type Table = UnityUrpTable;
    const NAME: &'static str = "unity-urp";
    const SOURCE: &'static str = "Unity URP UniversalRenderPipelineAsset.cs, Shadows.hlsl";

    /// Depth and normal bias scale with each cascade's texel size; defaults 1 and 1.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::Texels {
                depth_texels: 1.0,
                normal_texels: 1.0,
            },
            "Depth Bias",
            "texels of the cascade",
        ))
    }

    const FREE_SPLITS: Option<FreeSplits<UnityUrpKnobs>> = Some(FreeSplits {
        knob: |cascades| match cascades {
            2 => FreeSplitKnob {
                key: "unity-urp.cascade2_split",
                term: "UniversalRenderPipelineAsset.cascade2Split",
                of: OF_SHADOW_DISTANCE,
            },
            3 => FreeSplitKnob {
                key: "unity-urp.cascade3_split",
                term: "UniversalRenderPipelineAsset.cascade3Split",
                of: OF_SHADOW_DISTANCE,
            },
            _ => FreeSplitKnob {
                key: "unity-urp.cascade4_split",
                term: "UniversalRenderPipelineAsset.cascade4Split",
                of: OF_SHADOW_DISTANCE,
            },
        },
        space: shadow_distance_space,
        configured: |k, cascades, _| match cascades {
            2 => vec![k.cascade2_split],
            3 => k.cascade3_split.to_vec(),
            _ => k.cascade4_split.to_vec(),
        },
        values: as_given,
        set: |k, cascades, v| match cascades {
            2 => k.cascade2_split = v[0],
            3 => k.cascade3_split = [v[0], v[1]],
            _ => k.cascade4_split = [v[0], v[1], v[2]],
        },
        setting: unity_vector_setting,
        paste_prefix: "",
        scalar_when_one: true,
        fit_count: keep,
    });

    fn knobs(t: &UnityUrpTable, cx: &KnobContext<'_>) -> Result<UnityUrpKnobs> {
        let v = cx.v;
        let s2 = t.cascade2_split.unwrap_or(0.25);
        Ok(UnityUrpKnobs {
            cascade2_split: check_range(v, "unity-urp.cascade2_split", s2, 0.0, 1.0, true, true)?,
            cascade3_split: fractions::<2>(v, "unity-urp.cascade3_split", t.cascade3_split.as_ref(), [0.1, 0.3])?,
            cascade4_split: fractions::<3>(
                v,
                "unity-urp.cascade4_split",
                t.cascade4_split.as_ref(),
                [0.067, 0.2, 0.467],
            )?,
        })
    }

    fn defaults(_: &UnityUrpKnobs, _camera_far: f64) -> (usize, f64) {
        (1, 50.0)
    }

    /// URP renders all cascades into one 2048 atlas: 2x2 tiles of 1024 from two cascades on.
    fn default_resolution(_: &UnityUrpKnobs, cascades: usize) -> u32 {
        if cascades > 1 {
            1024
        } else {
            2048
        }
    }

    fn counts(_: &UnityUrpKnobs) -> Counts {
        Counts::Allowed(vec![1, 2, 3, 4])
    }

    fn layout(k: &UnityUrpKnobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
        let fractions = (&k.cascade2_split, &k.cascade3_split[..], &k.cascade4_split[..]);
        distance_fractions(cascades, near, far, max_distance, fractions)
    }

    fn scheme(_: &UnityUrpKnobs, f: &Fitting<'_>) -> EngineScheme {
        minimal_sphere_scheme(f)
    }

    fn split_rule(k: &UnityUrpKnobs) -> String {
        format!(
            "fractions of the shadow distance (2: {}; 3: {:?}; 4: {:?})",
            k.cascade2_split, k.cascade3_split, k.cascade4_split
        )
    }

    const LIGHT_DEPTH: Described<UnityUrpKnobs> = Described::Fixed("engine side: modelled as fitted to the scene");

    const TERMS: Terms = Terms {
        comment: "//",
        language: "C#, Unity URP: the UniversalRenderPipelineAsset's shadow fields",
        template: "\
var urp = (UniversalRenderPipelineAsset)GraphicsSettings.currentRenderPipeline;
urp.mainLightShadowmapResolution = {{mainLightShadowmapResolution}};
urp.shadowDistance = {{shadowDistance}}f;
urp.shadowCascadeCount = {{shadowCascadeCount}};
urp.cascade2Split = {{cascade2Split}}f;
urp.cascade3Split = new Vector2({{cascade3Split.x}}f, {{cascade3Split.y}}f);
urp.cascade4Split = new Vector3({{cascade4Split.x}}f, {{cascade4Split.y}}f, {{cascade4Split.z}}f);",
    };

    /// The main light's atlas: one tile for 1 cascade, 2 × 2 tiles from 2 on.
    fn terms(k: &UnityUrpKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        let per = if d.cascades > 1 { 2 } else { 1 };
        Values::new()
            .int("mainLightShadowmapResolution", d.resolution * per)
            .num("shadowDistance", d.max_distance.unwrap_or(50.0))
            .int("shadowCascadeCount", d.cascades)
            .num("cascade2Split", k.cascade2_split)
            .num("cascade3Split.x", k.cascade3_split[0])
            .num("cascade3Split.y", k.cascade3_split[1])
            .num("cascade4Split.x", k.cascade4_split[0])
            .num("cascade4Split.y", k.cascade4_split[1])
            .num("cascade4Split.z", k.cascade4_split[2])
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(UnityUrpKnobs, Dims)> {
        let (k3, k4) = ("unity-urp.cascade3_split", "unity-urp.cascade4_split");
        let table = UnityUrpTable {
            cascade2_split: Some(f.num("cascade2Split", "unity-urp.cascade2_split")?),
            cascade3_split: Some(vec![f.num("cascade3Split.x", k3)?, f.num("cascade3Split.y", k3)?]),
            cascade4_split: Some(vec![
                f.num("cascade4Split.x", k4)?,
                f.num("cascade4Split.y", k4)?,
                f.num("cascade4Split.z", k4)?,
            ]),
        };
        let cascades = f.count("shadowCascadeCount", "shadow.cascades")?;
        let dims = Dims {
            cascades,
            resolution: f.tile(
                "mainLightShadowmapResolution",
                "shadow.resolution",
                if cascades > 1 { 2 } else { 1 },
            )?,
            max_distance: Some(f.num("shadowDistance", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }

    /// Fractions of the shadow distance: csm-lab's boundaries exactly.
    fn match_ends(k: &mut UnityUrpKnobs, t: &Target<'_>) {
        let fr = t.fractions(0.0, t.far.min(t.distance));
        match t.cascades() {
            2 => k.cascade2_split = fr[0],
            3 => k.cascade3_split = complete_fractions(&fr, k.cascade3_split),
            4 => k.cascade4_split = complete_fractions(&fr, k.cascade4_split),
            _ => {}
        }
    }
}
