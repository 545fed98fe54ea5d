//! Dart: the reference `computeCascades` (API documentation): practical split on
//! [near, shadow distance] with the last boundary from the formula, corner-average spheres.

use crate::presets::{Described, unit, Counts, Dims, Engine, EngineScheme, Fields, Fitting, KnobContext, Layout, Terms, Values};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use csm_core::cascades::LightDepthRule;
use csm_core::fitting::corner_average_sphere;

use crate::presets::bias::BiasModel;

pub struct Dart;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DartTable {
    lambda: Option<f64>,
}

/// λ is `shadowCascadeSplitLambda` (the reference gives no default: 0.5 chosen).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DartKnobs {
    pub lambda: f64,
}

/// Practical split exactly as the reference writes it: the last boundary also from the formula.
pub(crate) fn dart_splits(near: f64, far: f64, cascades: usize, lambda: f64) -> Vec<f64> {
    let count = cascades.clamp(1, 4);
    let mut s = vec![near];
    for i in 1..=count {
        let ratio = i as f64 / count as f64;
        let log = near * (far / near).powf(ratio);
        let uni = near + (far - near) * ratio;
        s.push(lambda * log + (1.0 - lambda) * uni);
    }
    s
}

impl Engine for Dart {
    type Knobs = DartKnobs;
    type Table = DartTable;
    const NAME: &'static str = "dart";
    const SOURCE: &'static str = "Dart computeCascades (API documentation)";

    fn bias() -> BiasModel {
        BiasModel::NotModelled(concat!(
            "the Dart engine's documents state no shadow bias; ",
            "the [shadow] bias keys apply (0 by default)"
        ))
    }

    fn knobs(t: &DartTable, cx: &KnobContext<'_>) -> Result<DartKnobs> {
        Ok(DartKnobs {
            lambda: unit(cx.v, "dart.lambda", t.lambda.unwrap_or(0.5))?,
        })
    }

    fn defaults(_: &DartKnobs, camera_far: f64) -> (usize, f64) {
        (4, camera_far)
    }

    fn counts(_: &DartKnobs) -> Counts {
        Counts::Clamped(1, 4)
    }

    fn lambda(k: &DartKnobs) -> Option<f64> {
        Some(k.lambda)
    }

    fn lambda_key(_: &DartKnobs) -> Option<&'static str> {
        Some("dart.lambda")
    }

    fn set_lambda(k: &mut DartKnobs, lambda: f64) {
        k.lambda = lambda;
    }

    fn layout(k: &DartKnobs, cascades: usize, max_distance: f64, near: f64, _far: f64) -> Layout {
        Layout::contiguous(dart_splits(near, max_distance, cascades, k.lambda))
    }

    fn scheme(_: &DartKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        let s = f.spheres(|a, b| corner_average_sphere(a, b, k2));
        EngineScheme::fixed(
            "sphere-average",
            Fitting::axis(&s),
            f.on(&s, f.resolution as f64),
            LightDepthRule::Scene,
        )
    }

    fn split_rule(k: &DartKnobs) -> String {
        format!("practical, λ {} on [near, max_distance], 1..4 cascades", k.lambda)
    }

    const LIGHT_DEPTH: Described<DartKnobs> = Described::Fixed("not shown in the reference: modelled as fitted to the scene");

    const TERMS: Terms = Terms {
        comment: "#",
        language: "TOML: csm-lab's [shadow] and [dart] tables (the reference takes these as arguments)",
        template: "\
[shadow]
preset = \"dart\"
cascades = {{cascades}}
resolution = {{resolution}}
max_distance = {{max_distance}}
[dart]
lambda = {{lambda}}",
    };

    fn terms(k: &DartKnobs, d: &Dims, _near: f64, far: f64) -> Values {
        Values::new()
            .int("cascades", d.cascades)
            .int("resolution", d.resolution)
            .num("max_distance", d.max_distance.unwrap_or(far))
            .num("lambda", k.lambda)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(DartKnobs, Dims)> {
        let table = DartTable {
            lambda: Some(f.num("lambda", "dart.lambda")?),
        };
        let dims = Dims {
            cascades: f.count("cascades", "shadow.cascades")?,
            resolution: f.size("resolution", "shadow.resolution")?,
            max_distance: Some(f.num("max_distance", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }
}
