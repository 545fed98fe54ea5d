//! Unity's Universal Render Pipeline (`UniversalRenderPipelineAsset.cs`, `Shadows.hlsl`):
//! fractions of the shadow distance, one atlas of 2048 (tiles of 1024 from two cascades on),
//! modelled like Unity's built-in pipeline for the fit and snap.

use serde::{Deserialize, Serialize};

use crate::error::Result;

use super::*;

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

    fn light_depth_rule(_: &UnityUrpKnobs) -> String {
        "engine side: modelled as fitted to the scene".to_string()
    }
}
