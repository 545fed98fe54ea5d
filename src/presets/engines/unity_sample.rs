//! The Unity C# sample (a blog's cascade code): fixed fractions of the far plane, tight boxes
//! whose centre is discarded (the window sits on the light axis through the world origin).

use crate::presets::{Described, Counts, Dims, Engine, EngineScheme, Fields, Fitting, KnobContext, Layout, Terms, Values};
use serde::{Deserialize, Serialize};

use crate::config::Fit;
use crate::error::Result;
use csm_core::cascades::{LightDepthRule, WindowRule};
use csm_core::fitting::minimal_sphere;

use crate::presets::bias::{BiasModel, EngineBias};
use csm_core::truth::{BiasRule, NormalOffset};

pub struct UnitySample;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnitySampleTable {
    centre_on_slice: Option<bool>,
}

/// `centre_on_slice = true` repairs the discarded window centre (default: reproduce).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnitySampleKnobs {
    pub centre_on_slice: bool,
}

impl Engine for UnitySample {
    type Knobs = UnitySampleKnobs;
    type Table = UnitySampleTable;
    const NAME: &'static str = "unity-sample";
    const SOURCE: &'static str = "Unity C# cascade sample (soramamenatan blog #113)";
    const HAS_DISTANCE: bool = false;
    const FIT: Fit = Fit::Aabb;
    const SNAPS: bool = false;

    /// The sample adds 0.005 to the casters' clip-space z; on OpenGL (z in [-1, 1]) that is
    /// 0.0025 of the cascade's light depth range away from the light.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::RangeFraction {
                fraction: UNITY_SAMPLE_CLIP_BIAS / 2.0,
                normal_texels: 0.0,
                offset: NormalOffset::Along,
            },
            "_gShadowBias",
            "clip-space z on OpenGL (2 x normalised depth)",
        )
        .scaled(2.0))
    }

    fn knobs(t: &UnitySampleTable, _cx: &KnobContext<'_>) -> Result<UnitySampleKnobs> {
        Ok(UnitySampleKnobs {
            centre_on_slice: t.centre_on_slice.unwrap_or(false),
        })
    }

    fn defaults(_: &UnitySampleKnobs, camera_far: f64) -> (usize, f64) {
        (4, camera_far)
    }

    fn default_resolution(_: &UnitySampleKnobs, _cascades: usize) -> u32 {
        1024
    }

    fn counts(_: &UnitySampleKnobs) -> Counts {
        Counts::Fixed(4)
    }

    fn layout(_: &UnitySampleKnobs, _cascades: usize, _max_distance: f64, near: f64, far: f64) -> Layout {
        // Accumulated in the sample's own order (far * p + ... + near).
        let (n, f) = (near, far);
        let e = [
            f * 0.067 + n,
            f * 0.133 + f * 0.067 + n,
            f * 0.267 + f * 0.133 + f * 0.067 + n,
        ];
        Layout::contiguous(vec![n, e[0], e[1], e[2], f])
    }

    fn scheme(k: &UnitySampleKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        EngineScheme::fixed(
            if k.centre_on_slice { "aabb" } else { "aabb-at-origin" },
            if k.centre_on_slice {
                WindowRule::Tight {
                    pad: 0.0,
                    border: false,
                }
            } else {
                WindowRule::TightAtOrigin
            },
            f.each(|a, b| 2.0 * minimal_sphere(a, b, k2).radius),
            LightDepthRule::Slice { keeps_casters: false },
        )
    }

    fn split_rule(_: &UnitySampleKnobs) -> String {
        "near + {0.067, 0.2, 0.467}·far, 4 cascades".to_string()
    }

    const LIGHT_DEPTH: Described<UnitySampleKnobs> = Described::Fixed("slice's own z extent; casters in front are lost");

    const TERMS: Terms = Terms {
        comment: "#",
        language: "TOML: csm-lab's [shadow] and [unity-sample] tables (the sample's splits are fixed)",
        template: "\
[shadow]
preset = \"unity-sample\"
resolution = {{resolution}}
[unity-sample]
centre_on_slice = {{centre_on_slice}}",
    };

    fn terms(k: &UnitySampleKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        Values::new()
            .int("resolution", d.resolution)
            .bool("centre_on_slice", k.centre_on_slice)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(UnitySampleKnobs, Dims)> {
        let table = UnitySampleTable {
            centre_on_slice: Some(f.bool("centre_on_slice", "unity-sample.centre_on_slice")?),
        };
        let dims = Dims {
            cascades: 4,
            resolution: f.size("resolution", "shadow.resolution")?,
            max_distance: None,
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }
}

/// The Unity sample's clip-space bias.
const UNITY_SAMPLE_CLIP_BIAS: f64 = 0.005;
