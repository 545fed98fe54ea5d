//! Unity's built-in render pipeline (vendor documentation; closed source): fractions of the
//! shadow distance, Stable Fit modelled as csm-lab's minimal sphere with round snapping.

use serde::{Deserialize, Serialize};

use crate::error::Result;

use super::*;

pub struct Unity;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnityTable {
    cascade2_split: Option<f64>,
    cascade4_split: Option<Vec<f64>>,
}

/// Unity built-in quality settings (shadow distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnityKnobs {
    pub cascade2_split: f64,
    pub cascade4_split: [f64; 3],
}

impl Engine for Unity {
    type Knobs = UnityKnobs;
    type Table = UnityTable;
    const NAME: &'static str = "unity";
    const SOURCE: &'static str = "Unity built-in render pipeline, Stable Fit (vendor documentation)";

    fn knobs(t: &UnityTable, cx: &KnobContext<'_>) -> Result<UnityKnobs> {
        let v = cx.v;
        let s2 = t.cascade2_split.unwrap_or(1.0 / 3.0);
        Ok(UnityKnobs {
            cascade2_split: check_range(v, "unity.cascade2_split", s2, 0.0, 1.0, true, true)?,
            cascade4_split: fractions::<3>(v, "unity.cascade4_split", t.cascade4_split.as_ref(), [0.067, 0.2, 0.467])?,
        })
    }

    fn defaults(_: &UnityKnobs, _camera_far: f64) -> (usize, f64) {
        (4, 150.0)
    }

    fn counts(_: &UnityKnobs) -> Counts {
        Counts::Allowed(vec![1, 2, 4])
    }

    fn layout(k: &UnityKnobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
        // Unity offers 1, 2 or 4 cascades: a count of 3 never reaches here.
        let four = &k.cascade4_split[..];
        distance_fractions(cascades, near, far, max_distance, (&k.cascade2_split, four, four))
    }

    fn scheme(_: &UnityKnobs, f: &Fitting<'_>) -> EngineScheme {
        minimal_sphere_scheme(f)
    }

    fn split_rule(k: &UnityKnobs) -> String {
        format!(
            "fractions of the shadow distance (2: {:.3}; 4: {:?})",
            k.cascade2_split, k.cascade4_split
        )
    }

    fn light_depth_rule(_: &UnityKnobs) -> String {
        "engine side: modelled as fitted to the scene".to_string()
    }
}
