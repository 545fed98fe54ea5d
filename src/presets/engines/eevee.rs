//! Blender EEVEE (2017, `eevee_shadow_cascade_setup`): practical split with a fade overlap,
//! far-cap-centred spheres, round snapping on a grid through the lamp, the lamp's clip range.

use crate::presets::{Described, centre, half_extent_along, non_negative, ordered, point_or, unit, Counts, Dims, Engine, EngineScheme, Fields,
    Fitting, KnobContext, Layout, Terms, Values,
};
use serde::{Deserialize, Serialize};

use glam::DVec3;

use crate::error::Result;
use csm_core::cascades::{BasisRule, LightDepthRule};
use csm_core::fitting::far_cap_sphere;

use crate::presets::bias::{BiasModel, EngineBias};
use crate::presets::shared::signed_distance;
use csm_core::truth::{BiasRule, NormalOffset};

pub struct Eevee;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EeveeTable {
    cascade_exponent: Option<f64>,
    fade: Option<f64>,
    #[serde(default, deserialize_with = "crate::config::opt_vec3")]
    lamp_position: Option<[f64; 3]>,
    clip_start: Option<f64>,
    clip_end: Option<f64>,
}

/// EEVEE 2017 lamp settings (Blender's DNA defaults) and the lamp's position.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EeveeKnobs {
    /// "Distribution": λ of the practical split.
    pub cascade_exponent: f64,
    pub fade: f64,
    pub lamp_position: DVec3,
    pub clip_start: f64,
    pub clip_end: f64,
}

/// EEVEE 2017 split ends and (fade-overlapped) starts on `[start, end]`.
pub(crate) fn eevee_starts_ends(start: f64, end: f64, cascades: usize, lambda: f64, fade: f64) -> (Vec<f64>, Vec<f64>) {
    let m = cascades;
    let mut starts = vec![start; m];
    let mut ends = vec![end; m];
    let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
    for c in 1..m {
        let r = c as f64 / m as f64;
        let linear = lerp(r, start, end);
        let exp = start * (end / start).powf(r);
        ends[c - 1] = lerp(lambda, linear, exp);
        let prev = if c > 1 { ends[c - 2] } else { starts[0] };
        starts[c] = lerp(fade, ends[c - 1], prev);
    }
    (starts, ends)
}

impl Engine for Eevee {
    type Knobs = EeveeKnobs;
    type Table = EeveeTable;
    const NAME: &'static str = "eevee";
    const SOURCE: &'static str = "Blender EEVEE (2017) eevee_shadow_cascade_setup";

    /// The 2017 cascade code: 0.05 x the lamp's bias (default 1) in depth normalised over
    /// the lamp's clip range.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::RangeFraction {
                fraction: EEVEE_BIAS_FACTOR * EEVEE_LAMP_BIAS,
                normal_texels: 0.0,
                offset: NormalOffset::Along,
            },
            "Lamp bias (shadow_buffer_bias)",
            "lamp bias (1 = 0.05 of the lamp's clip range)",
        )
        .scaled(1.0 / EEVEE_BIAS_FACTOR))
    }

    fn knobs(t: &EeveeTable, cx: &KnobContext<'_>) -> Result<EeveeKnobs> {
        let v = cx.v;
        let l = cx.light_direction;
        let cascade_exponent = unit(v, "eevee.cascade_exponent", t.cascade_exponent.unwrap_or(0.8))?;
        let fade = unit(v, "eevee.fade", t.fade.unwrap_or(0.1))?;
        let clip_start = non_negative(v, "eevee.clip_start", t.clip_start.unwrap_or(0.05))?;
        let clip_end = signed_distance(v, "eevee.clip_end", t.clip_end.unwrap_or(40.0))?;
        ordered(v, "eevee.clip_start", clip_start, "eevee.clip_end", clip_end)?;
        // Default lamp: up-sun of the scene, so the scene's point nearest the light sits
        // exactly at clip_start (the best a user can place a lamp for this clip range).
        let default = centre(cx.scene) - l * (half_extent_along(cx.scene, l) + clip_start);
        Ok(EeveeKnobs {
            cascade_exponent,
            fade,
            lamp_position: point_or(v, "eevee.lamp_position", t.lamp_position, default)?,
            clip_start,
            clip_end,
        })
    }

    fn defaults(_: &EeveeKnobs, _camera_far: f64) -> (usize, f64) {
        (4, 200.0)
    }

    fn default_resolution(_: &EeveeKnobs, _cascades: usize) -> u32 {
        1024
    }

    fn counts(_: &EeveeKnobs) -> Counts {
        Counts::Allowed(vec![1, 2, 3, 4])
    }

    fn lambda(k: &EeveeKnobs) -> Option<f64> {
        Some(k.cascade_exponent)
    }

    fn lambda_key(_: &EeveeKnobs) -> Option<&'static str> {
        Some("eevee.cascade_exponent")
    }

    fn set_lambda(k: &mut EeveeKnobs, lambda: f64) {
        k.cascade_exponent = lambda;
    }

    fn layout(k: &EeveeKnobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
        let end = near.max(far.min(max_distance));
        let (starts, ends) = eevee_starts_ends(near, end, cascades, k.cascade_exponent, k.fade);
        // In the fade band [start_c, end_{c-1}] both cascades are read: the coarser (c)
        // counts for selection.
        let mut selection = starts.clone();
        selection.push(end);
        Layout {
            fitted: starts.into_iter().zip(ends).collect(),
            selection,
        }
    }

    fn scheme(k: &EeveeKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        let s = f.spheres(|a, b| far_cap_sphere(a, b, k2));
        EngineScheme {
            label: "sphere-far-cap",
            window: Fitting::axis(&s),
            sides: f.on(&s, f.resolution as f64),
            basis: BasisRule::Fixed,
            anchor: f.light.to_light_xy(k.lamp_position),
            depth: LightDepthRule::FromPoint {
                point: k.lamp_position,
                near: k.clip_start,
                far: k.clip_end,
            },
        }
    }

    fn split_rule(k: &EeveeKnobs) -> String {
        format!(
            "practical, λ {} on [near, min(far, max_distance)], fade {} overlap",
            k.cascade_exponent, k.fade
        )
    }

    fn snap_anchor(_: &EeveeKnobs) -> &'static str {
        "grid through the lamp position"
    }

    const LIGHT_DEPTH: Described<EeveeKnobs> = Described::From(|k| format!("lamp clip {} to {}", k.clip_start, k.clip_end));

    const TERMS: Terms = Terms {
        comment: "#",
        language: "TOML: csm-lab's [shadow] and [eevee] tables (csm-lab's world axes, not Blender's)",
        template: "\
[shadow]
preset = \"eevee\"
cascades = {{cascades}}
resolution = {{resolution}}
max_distance = {{max_distance}}
[eevee]
cascade_exponent = {{cascade_exponent}}
fade = {{fade}}
lamp_position = [{{lamp_position}}]
clip_start = {{clip_start}}
clip_end = {{clip_end}}",
    };

    fn terms(k: &EeveeKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        Values::new()
            .int("cascades", d.cascades)
            .int("resolution", d.resolution)
            .num("max_distance", d.max_distance.unwrap_or(200.0))
            .num("cascade_exponent", k.cascade_exponent)
            .num("fade", k.fade)
            .nums("lamp_position", &k.lamp_position.to_array())
            .num("clip_start", k.clip_start)
            .num("clip_end", k.clip_end)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(EeveeKnobs, Dims)> {
        let table = EeveeTable {
            cascade_exponent: Some(f.num("cascade_exponent", "eevee.cascade_exponent")?),
            fade: Some(f.num("fade", "eevee.fade")?),
            lamp_position: Some(f.vec3("lamp_position", "eevee.lamp_position")?),
            clip_start: Some(f.num("clip_start", "eevee.clip_start")?),
            clip_end: Some(f.num("clip_end", "eevee.clip_end")?),
        };
        let dims = Dims {
            cascades: f.count("cascades", "shadow.cascades")?,
            resolution: f.size("resolution", "shadow.resolution")?,
            max_distance: Some(f.num("max_distance", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }
}

/// EEVEE's factor on the lamp bias (normalised depth per unit of bias).
const EEVEE_BIAS_FACTOR: f64 = 0.05;

/// Blender's default lamp bias.
const EEVEE_LAMP_BIAS: f64 = 1.0;
