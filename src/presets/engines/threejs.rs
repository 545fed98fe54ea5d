//! three.js: the CSM addon (r185 and later): breaks of min(far, maxFar), slice-diameter windows
//! at the light-space box centre, floor snapping, fixed light near/far with a margin; with
//! `fade` (a property set after construction) blend bands between cascades and grown windows.

use crate::presets::{Described, log_misfit, non_negative, ordered, snap, Counts, Dims, Engine, EngineScheme, Fields, Fitting, KnobContext, Layout,
    Target, Terms, Values,
};
use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::error::Result;
use csm_core::cascades::{LightDepthRule, WindowRule};
use csm_core::fitting::slice_diameter;
use csm_core::snapping::{SnapMode, SnapRule};

use crate::presets::bias::{BiasModel, EngineBias};
use crate::presets::shared::signed_distance;
use csm_core::truth::{BiasRule, NormalOffset};

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
    fade: Option<bool>,
}

/// three.js CSM (constructor parameters, and `fade`, set on the object after construction).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ThreejsKnobs {
    pub mode: ThreejsMode,
    pub light_margin: f64,
    pub light_near: f64,
    pub light_far: f64,
    /// `csm.fade`: blend bands between cascades and windows grown by the fade margin. Not
    /// serialised when off, so reports of settings without it read as before.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub fade: bool,
}

/// The fade band around a break `b` (a fraction of `F`, read as linear depth `ld = d/(F − n)`):
/// `[b − b²/8, b + b²/8]` in linear depth, where the shader reads both neighbouring cascades
/// (margin `b²/4`, half of it on each side of the break).
pub(crate) fn threejs_fade_band(b: f64) -> (f64, f64) {
    let half = 0.125 * b * b;
    (b - half, b + half)
}

/// How much fade grows a cascade's window side: `0.25·(z/(Fmax − n))²·(Fmax − n)` for a
/// cascade ending at view depth `z`, with `Fmax = max(camera far, maxFar)`.
pub(crate) fn threejs_fade_growth(z_far: f64, near: f64, far: f64, max_far: f64) -> f64 {
    let span = far.max(max_far) - near;
    let ld = z_far / span;
    0.25 * ld * ld * span
}

/// three.js `breaks`: far end of each cascade as a fraction of `far`, the last one 1.
pub(crate) fn threejs_breaks(mode: ThreejsMode, cascades: usize, near: f64, far: f64) -> Vec<f64> {
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

    /// shadowBias 1e-6 in normalised depth: a fraction of the light depth range.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::RangeFraction {
                fraction: 1e-6,
                normal_texels: 0.0,
                offset: NormalOffset::Along,
            },
            "CSM shadowBias",
            "normalised depth",
        ))
    }

    fn knobs(t: &ThreejsTable, cx: &KnobContext<'_>) -> Result<ThreejsKnobs> {
        let v = cx.v;
        // three.js falls back to the default for any falsy value, 0 included.
        let falsy = |x: Option<f64>, d: f64| x.filter(|x| *x != 0.0).unwrap_or(d);
        let light_margin = non_negative(v, "threejs.light_margin", falsy(t.light_margin, 200.0))?;
        let light_near = signed_distance(v, "threejs.light_near", falsy(t.light_near, 1.0))?;
        let light_far = signed_distance(v, "threejs.light_far", falsy(t.light_far, 2000.0))?;
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
            fade: t.fade.unwrap_or(false),
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
        if !k.fade || cascades < 2 {
            return Layout { fitted, selection };
        }
        // With fade, cascade i is read on [x − x²/8, y + y²/8) in linear depth (x, y its
        // breaks; the last one up to the end of the shadows, where it fades out): around each
        // interior break both neighbours are read, and the coarser one counts for selection.
        let u = f - near;
        let bands: Vec<(f64, f64)> = b[..cascades - 1]
            .iter()
            .map(|&x| {
                let (lo, hi) = threejs_fade_band(x);
                (lo * u, hi * u)
            })
            .collect();
        let fitted = (0..cascades)
            .map(|i| {
                let lo = if i == 0 { near } else { bands[i - 1].0 };
                let hi = if i + 1 == cascades { f } else { bands[i].1 };
                (lo, hi)
            })
            .collect();
        for (j, band) in bands.iter().enumerate() {
            selection[j + 1] = band.0;
        }
        Layout { fitted, selection }
    }

    fn snap_rule(_: &ThreejsKnobs) -> SnapRule {
        snap(SnapMode::Floor, 1)
    }

    fn scheme(k: &ThreejsKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        let sides = if k.fade {
            // The side is the diameter of the cascade's own slice [b_{i-1} F, b_i F] (not of
            // the faded interval the layout fits), grown by the fade margin of its far end.
            let m = f.fitted.len();
            let fe = f.far.min(f.max_distance);
            let b = threejs_breaks(k.mode, m, f.near, fe);
            (0..m)
                .map(|i| {
                    let (a, z) = (if i == 0 { f.near } else { b[i - 1] * fe }, b[i] * fe);
                    slice_diameter(a, z, k2) + threejs_fade_growth(z, f.near, f.far, f.max_distance)
                })
                .collect()
        } else {
            f.each(|a, b| slice_diameter(a, b, k2))
        };
        EngineScheme::fixed(
            "diameter",
            WindowRule::BoxCentred,
            sides,
            LightDepthRule::Margin {
                margin: k.light_margin,
                near: k.light_near,
                far: k.light_far,
            },
        )
    }

    fn split_rule(k: &ThreejsKnobs) -> String {
        let rule = match k.mode {
            ThreejsMode::Practical => "practical, λ fixed at 0.5, breaks of min(far, maxFar) (r185)".to_string(),
            ThreejsMode::Uniform => "uniform breaks of min(far, maxFar) (r185)".to_string(),
            ThreejsMode::Logarithmic => "logarithmic breaks of min(far, maxFar) (r185)".to_string(),
        };
        if k.fade {
            format!("{rule}; fade on: bands b ± b²/8 of linear depth, windows grown by the fade margin")
        } else {
            rule
        }
    }

    const LIGHT_DEPTH: Described<ThreejsKnobs> = Described::From(|k| format!(
            "fixed {} to {} from a light {} in front of the slice",
            k.light_near, k.light_far, k.light_margin
        ));

    const TERMS: Terms = Terms {
        comment: "//",
        language: "JavaScript, three.js: the CSM addon's constructor options and its fade property",
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
});
csm.fade = {{fade}};
csm.updateFrustums();",
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
            .bool("fade", k.fade)
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
            fade: Some(f.bool("fade", "threejs.fade")?),
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
