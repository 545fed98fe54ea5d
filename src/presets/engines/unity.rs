//! Unity's built-in render pipeline (vendor documentation; closed source): fractions of the
//! shadow distance, Stable Fit modelled as csm-lab's minimal sphere with round snapping.

use crate::presets::{Described, check_range, complete_fractions, distance_fractions, fractions, minimal_sphere_scheme, Counts, Dims, Engine,
    EngineScheme, Fields, Fitting, KnobContext, Layout, Target, Terms, Values,
};
use serde::{Deserialize, Serialize};

use crate::error::Result;

use crate::presets::bias::BiasModel;
use crate::presets::free_splits::{
    as_given, keep, shadow_distance_space, unity_vector_setting, FreeSplitKnob, FreeSplits, OF_SHADOW_DISTANCE,
};

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

    fn bias() -> BiasModel {
        BiasModel::NotModelled(concat!(
            "Unity built-in's default bias and its per-cascade scaling are not published; ",
            "the [shadow] bias keys apply (0 by default)"
        ))
    }

    const FREE_SPLITS: Option<FreeSplits<UnityKnobs>> = Some(FreeSplits {
        knob: |cascades| match cascades {
            2 => FreeSplitKnob {
                key: "unity.cascade2_split",
                term: "QualitySettings.shadowCascade2Split",
                of: OF_SHADOW_DISTANCE,
            },
            _ => FreeSplitKnob {
                key: "unity.cascade4_split",
                term: "QualitySettings.shadowCascade4Split",
                of: OF_SHADOW_DISTANCE,
            },
        },
        space: shadow_distance_space,
        configured: |k, cascades, _| match cascades {
            2 => vec![k.cascade2_split],
            _ => k.cascade4_split.to_vec(),
        },
        values: as_given,
        set: |k, cascades, v| match cascades {
            2 => k.cascade2_split = v[0],
            _ => k.cascade4_split = [v[0], v[1], v[2]],
        },
        setting: unity_vector_setting,
        paste_prefix: "",
        scalar_when_one: true,
        fit_count: keep,
    });

    fn knobs(t: &UnityTable, cx: &KnobContext<'_>) -> Result<UnityKnobs> {
        let v = cx.v;
        let s2 = t.cascade2_split.unwrap_or(1.0 / 3.0);
        Ok(UnityKnobs {
            cascade2_split: check_range(v, "unity.cascade2_split", s2, 0.0, 1.0, true, true)?,
            cascade4_split: fractions::<3>(
                v,
                "unity.cascade4_split",
                t.cascade4_split.as_ref(),
                [0.067, 0.2, 0.467],
            )?,
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

    const LIGHT_DEPTH: Described<UnityKnobs> = Described::Fixed("engine side: modelled as fitted to the scene");

    const TERMS: Terms = Terms {
        comment: "//",
        language: "C#, Unity built-in render pipeline: QualitySettings and the Light `sun`",
        template: "\
QualitySettings.shadowProjection = ShadowProjection.StableFit;
QualitySettings.shadowDistance = {{shadowDistance}}f;
QualitySettings.shadowCascades = {{shadowCascades}};
QualitySettings.shadowCascade2Split = {{shadowCascade2Split}}f;
QualitySettings.shadowCascade4Split = new Vector3({{shadowCascade4Split.x}}f, {{shadowCascade4Split.y}}f, {{shadowCascade4Split.z}}f);
sun.shadowCustomResolution = {{shadowCustomResolution}};",
    };

    /// The shadow map is an atlas: one tile for 1 cascade, 2 × 2 tiles from 2 on (csm-lab's
    /// map size is a tile's).
    fn terms(k: &UnityKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        let per = if d.cascades > 1 { 2 } else { 1 };
        Values::new()
            .num("shadowDistance", d.max_distance.unwrap_or(150.0))
            .int("shadowCascades", d.cascades)
            .num("shadowCascade2Split", k.cascade2_split)
            .num("shadowCascade4Split.x", k.cascade4_split[0])
            .num("shadowCascade4Split.y", k.cascade4_split[1])
            .num("shadowCascade4Split.z", k.cascade4_split[2])
            .int("shadowCustomResolution", d.resolution * per)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(UnityKnobs, Dims)> {
        let key = "unity.cascade4_split";
        let table = UnityTable {
            cascade2_split: Some(f.num("shadowCascade2Split", "unity.cascade2_split")?),
            cascade4_split: Some(vec![
                f.num("shadowCascade4Split.x", key)?,
                f.num("shadowCascade4Split.y", key)?,
                f.num("shadowCascade4Split.z", key)?,
            ]),
        };
        let cascades = f.count("shadowCascades", "shadow.cascades")?;
        let dims = Dims {
            cascades,
            resolution: f.tile(
                "shadowCustomResolution",
                "shadow.resolution",
                if cascades > 1 { 2 } else { 1 },
            )?,
            max_distance: Some(f.num("shadowDistance", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }

    /// Fractions of the shadow distance: csm-lab's boundaries exactly.
    fn match_ends(k: &mut UnityKnobs, t: &Target<'_>) {
        let fr = t.fractions(0.0, t.far.min(t.distance));
        match t.cascades() {
            2 => k.cascade2_split = fr[0],
            4 => k.cascade4_split = complete_fractions(&fr, k.cascade4_split),
            _ => {}
        }
    }
}
