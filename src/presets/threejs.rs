//! three.js: the CSM addon (r185 and later): breaks of min(far, maxFar), slice-diameter windows
//! at the light-space box centre, floor snapping, fixed light near/far with a margin.

use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::cascades::{LightDepthRule, WindowRule};
use crate::error::Result;
use crate::fitting::slice_diameter;
use crate::snapping::{SnapMode, SnapRule};

use super::*;

pub struct Threejs;

/// three.js split modes (`mode` of the CSM constructor; the custom callback is not modelled).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ThreejsMode {
    Uniform,
    Logarithmic,
    Practical,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThreejsTable {
    mode: Option<Spanned<String>>,
    light_margin: Option<f64>,
    light_near: Option<f64>,
    light_far: Option<f64>,
}

/// three.js CSM (constructor parameters).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ThreejsKnobs {
    pub mode: ThreejsMode,
    pub light_margin: f64,
    pub light_near: f64,
    pub light_far: f64,
}

/// three.js `breaks`: far end of each cascade as a fraction of `far`, the last one 1.
pub fn threejs_breaks(mode: ThreejsMode, cascades: usize, near: f64, far: f64) -> Vec<f64> {
    let m = cascades as f64;
    let uniform = |i: f64| (near + (far - near) * i / m) / far;
    let log = |i: f64| near * (far / near).powf(i / m) / far;
    let mut b: Vec<f64> = (1..cascades)
        .map(|i| {
            let i = i as f64;
            match mode {
                ThreejsMode::Uniform => uniform(i),
                ThreejsMode::Logarithmic => log(i),
                // lerp(uniform, log, 0.5)
                ThreejsMode::Practical => 0.5 * uniform(i) + 0.5 * log(i),
            }
        })
        .collect();
    b.push(1.0);
    b
}

impl Engine for Threejs {
    type Knobs = ThreejsKnobs;
    type Table = ThreejsTable;
    const NAME: &'static str = "threejs";
    const SOURCE: &'static str = "three.js CSM addon, r185 and later";

    fn knobs(t: &ThreejsTable, cx: &KnobContext<'_>) -> Result<ThreejsKnobs> {
        let v = cx.v;
        // three.js falls back to the default for any falsy value, 0 included.
        let falsy = |x: Option<f64>, d: f64| x.filter(|x| *x != 0.0).unwrap_or(d);
        let light_margin = non_negative(v, "threejs.light_margin", falsy(t.light_margin, 200.0))?;
        let light_near = v.finite("threejs.light_near", falsy(t.light_near, 1.0))?;
        let light_far = v.finite("threejs.light_far", falsy(t.light_far, 2000.0))?;
        ordered(v, "threejs.light_near", light_near, "threejs.light_far", light_far)?;
        let mode = match &t.mode {
            Some(m) => v.one_of(
                "threejs.mode",
                m,
                &[
                    ("uniform", ThreejsMode::Uniform),
                    ("logarithmic", ThreejsMode::Logarithmic),
                    ("practical", ThreejsMode::Practical),
                ],
            )?,
            None => ThreejsMode::Practical,
        };
        Ok(ThreejsKnobs {
            mode,
            light_margin,
            light_near,
            light_far,
        })
    }

    /// three.js replaces falsy constructor values (0) by its defaults: say so when it happened.
    fn table_notes(t: &ThreejsTable, k: &ThreejsKnobs) -> Vec<String> {
        let mut out = Vec::new();
        for (raw, key, used) in [
            (t.light_margin, "light_margin", k.light_margin),
            (t.light_near, "light_near", k.light_near),
            (t.light_far, "light_far", k.light_far),
        ] {
            if raw == Some(0.0) {
                out.push(format!(
                    "threejs.{key} = 0 replaced by {used}: three.js treats 0 as unset (falsy fallback)"
                ));
            }
        }
        out
    }

    fn defaults(_: &ThreejsKnobs, _camera_far: f64) -> (usize, f64) {
        (3, 1e5)
    }

    fn counts(_: &ThreejsKnobs) -> Counts {
        Counts::Allowed((1..=16).collect())
    }

    fn lambda(k: &ThreejsKnobs) -> Option<f64> {
        Some(match k.mode {
            ThreejsMode::Uniform => 0.0,
            ThreejsMode::Logarithmic => 1.0,
            ThreejsMode::Practical => 0.5,
        })
    }

    fn layout(k: &ThreejsKnobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
        let f = far.min(max_distance);
        let b = threejs_breaks(k.mode, cascades, near, f);
        // r185: cascade i spans [b_{i-1} F, b_i F], the first starting at the near plane;
        // the WebGL shader selects on [b_{i-1} (F - n), b_i (F - n)).
        let fitted = (0..cascades)
            .map(|i| (if i == 0 { near } else { b[i - 1] * f }, b[i] * f))
            .collect();
        let mut selection = vec![f64::NEG_INFINITY];
        selection.extend(b.iter().map(|x| x * (f - near)));
        Layout { fitted, selection }
    }

    fn snap_rule(_: &ThreejsKnobs) -> SnapRule {
        snap(SnapMode::Floor, 1)
    }

    fn scheme(k: &ThreejsKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        EngineScheme::fixed(
            "diameter",
            WindowRule::BoxCentred,
            f.each(|a, b| slice_diameter(a, b, k2)),
            LightDepthRule::Margin {
                margin: k.light_margin,
                near: k.light_near,
                far: k.light_far,
            },
        )
    }

    fn split_rule(k: &ThreejsKnobs) -> String {
        match k.mode {
            ThreejsMode::Practical => "practical, λ fixed at 0.5, breaks of min(far, maxFar) (r185)".to_string(),
            ThreejsMode::Uniform => "uniform breaks of min(far, maxFar) (r185)".to_string(),
            ThreejsMode::Logarithmic => "logarithmic breaks of min(far, maxFar) (r185)".to_string(),
        }
    }

    fn light_depth_rule(k: &ThreejsKnobs) -> String {
        format!(
            "fixed {} to {} from a light {} in front of the slice",
            k.light_near, k.light_far, k.light_margin
        )
    }

    const TERMS: Terms = Terms {
        comment: "//",
        language: "JavaScript, three.js: the CSM addon's constructor options",
        template: "\
const csm = new CSM({
  maxFar: {{maxFar}},
  cascades: {{cascades}},
  mode: '{{mode}}',
  shadowMapSize: {{shadowMapSize}},
  lightNear: {{lightNear}},
  lightFar: {{lightFar}},
  lightMargin: {{lightMargin}},
  parent: scene,
  camera: camera,
  lightDirection: lightDirection,
});",
    };

    fn terms(k: &ThreejsKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        let mode = match k.mode {
            ThreejsMode::Uniform => "uniform",
            ThreejsMode::Logarithmic => "logarithmic",
            ThreejsMode::Practical => "practical",
        };
        Values::new()
            .num("maxFar", d.max_distance.unwrap_or(1e5))
            .int("cascades", d.cascades)
            .word("mode", mode)
            .int("shadowMapSize", d.resolution)
            .num("lightNear", k.light_near)
            .num("lightFar", k.light_far)
            .num("lightMargin", k.light_margin)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(ThreejsKnobs, Dims)> {
        let mode = f.word(
            "mode",
            "threejs.mode",
            &[
                ("uniform", "uniform"),
                ("logarithmic", "logarithmic"),
                ("practical", "practical"),
            ],
        )?;
        let table = ThreejsTable {
            mode: Some(Spanned::new(0..0, mode.to_string())),
            light_margin: Some(f.num("lightMargin", "threejs.light_margin")?),
            light_near: Some(f.num("lightNear", "threejs.light_near")?),
            light_far: Some(f.num("lightFar", "threejs.light_far")?),
        };
        let dims = Dims {
            cascades: f.count("cascades", "shadow.cascades")?,
            resolution: f.size("shadowMapSize", "shadow.resolution")?,
            max_distance: Some(f.num("maxFar", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }

    /// The split mode is the only split knob: the one whose cascades end nearest csm-lab's
    /// (least [`log_misfit`]; uniform, logarithmic, practical in that order on a tie).
    fn match_ends(k: &mut ThreejsKnobs, t: &Target<'_>) {
        let best = [ThreejsMode::Uniform, ThreejsMode::Logarithmic, ThreejsMode::Practical]
            .into_iter()
            .map(|mode| ThreejsKnobs { mode, ..k.clone() })
            .min_by(|a, b| log_misfit::<Threejs>(a, t).total_cmp(&log_misfit::<Threejs>(b, t)));
        if let Some(b) = best {
            *k = b;
        }
    }
}
