//! Bevy (`bevy_light/src/cascade.rs` at 4805ca792c3e): geometric far bounds with an overlap
//! band, windows of the slice diameter rounded up to whole units, floor snapping, and the
//! light's own look-to basis (x mirrored against csm-lab's).

use crate::presets::{Described, around, check_range, non_negative, positive, snap, Counts, Dims, Engine, EngineScheme, Fields, Fitting, Knob,
    KnobContext, Layout, Terms, Values,
};
use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::config::Validator;
use crate::error::Result;
use csm_core::cascades::{LightDepthRule, WindowRule};
use csm_core::fitting::slice_diameter;
use csm_core::geometry::LightBasis;
use csm_core::snapping::{SnapMode, SnapRule};

use crate::presets::bias::{BiasModel, EngineBias};
use crate::presets::free_splits::{FreeSplitKnob, FreeSplits};
use csm_core::free_splits::FractionSpace;
use csm_core::truth::{BiasRule, NormalOffset};

pub struct Bevy;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BevyTable {
    minimum_distance: Option<f64>,
    first_cascade_far_bound: Option<f64>,
    overlap_proportion: Option<f64>,
    bounds: Option<Vec<f64>>,
}

/// Bevy `CascadeShadowConfigBuilder` (maximum_distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BevyKnobs {
    pub minimum_distance: f64,
    pub first_cascade_far_bound: f64,
    pub overlap_proportion: f64,
    /// Explicit far bounds of every cascade but the last (Bevy's `CascadeShadowConfig::bounds`
    /// without the maximum distance), strictly increasing; used when they hold cascades − 1
    /// values, instead of the geometric series (`sweep --optimize-splits` finds them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounds: Option<Vec<f64>>,
}

/// Bevy far bounds: `first·(max/first)^(i/(N−1))`, or just `max` for one cascade.
pub(crate) fn bevy_far_bounds(cascades: usize, first: f64, max: f64) -> Vec<f64> {
    if cascades == 1 {
        return vec![max];
    }
    (0..cascades)
        .map(|i| first * (max / first).powf(i as f64 / (cascades - 1) as f64))
        .collect()
}

/// Bevy's window side: the slice diameter rounded up to a whole world unit.
pub(crate) fn bevy_window_side(near: f64, far: f64, k2: f64) -> f64 {
    slice_diameter(near, far, k2).ceil()
}

/// The light's basis as Bevy builds it: `Transform::looking_to(direction, Vec3::Y)`, i.e.
/// back = −direction, right = normalize(Y × back), up = back × right; light-space x = right,
/// y = up, and csm-lab's z (the way light travels) = direction. Only when Y × back is exactly
/// zero (the light exactly vertical) does `try_normalize` fail, and Bevy takes
/// `Y.any_orthonormal_vector()` = (−0, 0, −1) as right (`vertical_fallback` is then set).
pub fn bevy_light_basis(direction: DVec3) -> LightBasis {
    let z = direction.normalize();
    let back = -z;
    let (right, vertical_fallback) = match DVec3::Y.cross(back).try_normalize() {
        Some(r) => (r, false),
        None => (DVec3::Y.any_orthonormal_vector(), true),
    };
    LightBasis {
        x: right,
        y: back.cross(right),
        z,
        vertical_fallback,
    }
}

impl Engine for Bevy {
    type Knobs = BevyKnobs;
    type Table = BevyTable;
    const NAME: &'static str = "bevy";
    const SOURCE: &'static str = "Bevy bevy_light/src/cascade.rs @ 4805ca792c3e";
    const POWER_OF_TWO_MAPS: bool = true;

    /// Receiver moved by normal x normal_bias x texel (normal_bias pre-multiplied by sqrt 2)
    /// and by depth_bias toward the light; defaults 0.02 and 1.8.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::World {
                depth: 0.02,
                slope: 0.0,
                normal_texels: 1.8 * std::f64::consts::SQRT_2,
                offset: NormalOffset::Along,
            },
            "DirectionalLight::shadow_depth_bias",
            "world units",
        ))
    }

    /// `CascadeShadowConfig::bounds`: the far bounds of every cascade but the last, as fractions
    /// of the maximum distance (the knob holds distances).
    const FREE_SPLITS: Option<FreeSplits<BevyKnobs>> = Some(FreeSplits {
        knob: |_| FreeSplitKnob {
            key: "bevy.bounds",
            term: "CascadeShadowConfig.bounds",
            of: "far bounds as fractions of the maximum distance",
        },
        space: |k, p| FractionSpace {
            lo: 0.0,
            hi: p.max_distance,
            start: k.minimum_distance.max(p.near),
        },
        configured: |k, cascades, p| {
            let max = p.max_distance;
            let fars = match k.bounds.as_ref().filter(|b| b.len() + 1 == cascades) {
                Some(b) => b.clone(),
                None => bevy_far_bounds(cascades, k.first_cascade_far_bound, max)[..cascades - 1].to_vec(),
            };
            fars.iter().map(|d| d / max).collect()
        },
        values: |_, _, max_distance, fractions| fractions.iter().map(|p| p * max_distance).collect(),
        set: |k, _, v| k.bounds = Some(v),
        setting: |k, s| {
            format!(
                "CascadeShadowConfig {{ bounds: vec![{}, {}], overlap_proportion: {}, minimum_distance: {} }}",
                s.values.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(", "),
                s.max_distance,
                k.overlap_proportion,
                k.minimum_distance
            )
        },
        paste_prefix: "",
        scalar_when_one: false,
        fit_count: |k, cascades| {
            if k.bounds.as_ref().is_some_and(|b| b.len() + 1 != cascades) {
                k.bounds = None;
            }
        },
    });

    fn knobs(t: &BevyTable, cx: &KnobContext<'_>) -> Result<BevyKnobs> {
        let v = cx.v;
        Ok(BevyKnobs {
            minimum_distance: non_negative(v, "bevy.minimum_distance", t.minimum_distance.unwrap_or(0.1))?,
            first_cascade_far_bound: positive(
                v,
                "bevy.first_cascade_far_bound",
                t.first_cascade_far_bound.unwrap_or(10.0),
            )?,
            overlap_proportion: check_range(
                v,
                "bevy.overlap_proportion",
                t.overlap_proportion.unwrap_or(0.2),
                0.0,
                1.0,
                false,
                true,
            )?,
            bounds: match &t.bounds {
                None => None,
                Some(b) => {
                    let ok = !b.is_empty()
                        && b.len() < 16
                        && b.iter()
                            .all(|x| x.is_finite() && *x > 0.0 && *x <= crate::config::MAX_WORLD)
                        && b.windows(2).all(|w| w[0] < w[1]);
                    if !ok {
                        return Err(v.invalid(
                            "bevy.bounds",
                            format!("{b:?}"),
                            "the far bounds of every cascade but the last: 1 to 15 distances, strictly increasing, in (0, 1e9]",
                        ));
                    }
                    Some(b.clone())
                }
            },
        })
    }

    fn defaults(_: &BevyKnobs, _camera_far: f64) -> (usize, f64) {
        (4, 150.0)
    }

    fn counts(_: &BevyKnobs) -> Counts {
        Counts::Allowed(vec![1, 2, 3, 4])
    }

    /// Bevy's builder checks (min < first far bound when N > 1, max > min), plus increasing far
    /// bounds (first < max), which the geometric series needs.
    fn check(k: &BevyKnobs, cascades: usize, max_distance: f64, v: &Validator<'_>) -> Result<()> {
        if max_distance <= k.minimum_distance {
            return Err(v.invalid(
                "shadow.max_distance",
                max_distance,
                &format!(
                    "a number greater than bevy.minimum_distance ({}) for the bevy preset",
                    k.minimum_distance
                ),
            ));
        }
        if cascades > 1 && !(k.minimum_distance < k.first_cascade_far_bound && k.first_cascade_far_bound < max_distance)
        {
            return Err(v.invalid(
                "bevy.first_cascade_far_bound",
                k.first_cascade_far_bound,
                &format!(
                    "a number between bevy.minimum_distance ({}) and the maximum distance ({max_distance}) when there is more than one cascade",
                    k.minimum_distance
                ),
            ));
        }
        if let Some(b) = &k.bounds {
            if b.len() + 1 != cascades {
                return Err(v.invalid(
                    "bevy.bounds",
                    format!("{b:?}"),
                    &format!(
                        "{} far bounds (one per cascade but the last) for {cascades} cascades",
                        cascades - 1
                    ),
                ));
            }
            if !(b[0] > k.minimum_distance && b[b.len() - 1] < max_distance) {
                return Err(v.invalid(
                    "bevy.bounds",
                    format!("{b:?}"),
                    &format!(
                        "far bounds between bevy.minimum_distance ({}) and the maximum distance ({max_distance})",
                        k.minimum_distance
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The first far bound, swept at ¼ to 2× the configured one, those inside
    /// (minimum_distance, max_distance); given values outside are refused by [`Engine::check`].
    fn knob(k: &BevyKnobs, max_distance: f64) -> Option<Knob> {
        let f = k.first_cascade_far_bound;
        let mults = [0.25, 0.5, 0.75, 1.0, 1.5, 2.0];
        Some(Knob {
            key: "bevy.first_cascade_far_bound",
            term: "first_cascade_far_bound",
            value: f,
            min: k.minimum_distance,
            max: 1e9,
            sweep: around(f, &mults.map(|m| m * f), k.minimum_distance, 1e9)
                .into_iter()
                .filter(|&x| x < max_distance)
                .collect(),
        })
    }

    fn set_knob(k: &mut BevyKnobs, value: f64) {
        k.first_cascade_far_bound = value;
    }

    fn layout(k: &BevyKnobs, cascades: usize, max_distance: f64, _near: f64, _far: f64) -> Layout {
        let fars = match k.bounds.as_ref().filter(|b| b.len() + 1 == cascades) {
            Some(b) => b.iter().copied().chain([max_distance]).collect(),
            None => bevy_far_bounds(cascades, k.first_cascade_far_bound, max_distance),
        };
        let nears: Vec<f64> = (0..cascades)
            .map(|i| {
                if i == 0 {
                    k.minimum_distance
                } else {
                    (1.0 - k.overlap_proportion) * fars[i - 1]
                }
            })
            .collect();
        // Cascade 0 serves everything nearer than its far bound; in the blend band
        // [(1 - p) far_i, far_i] the coarser cascade i + 1 counts; nothing beyond the last.
        let mut selection = vec![f64::NEG_INFINITY];
        selection.extend_from_slice(&nears[1..]);
        selection.push(fars[cascades - 1]);
        Layout {
            fitted: nears.into_iter().zip(fars).collect(),
            selection,
        }
    }

    fn snap_rule(_: &BevyKnobs) -> SnapRule {
        snap(SnapMode::Floor, 1)
    }

    fn light_basis(direction: DVec3) -> LightBasis {
        bevy_light_basis(direction)
    }

    fn scheme(_: &BevyKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        EngineScheme::fixed(
            "diameter-ceil",
            WindowRule::BoxCentred,
            f.each(|a, b| bevy_window_side(a, b, k2)),
            LightDepthRule::Slice { keeps_casters: true },
        )
    }

    fn split_rule(k: &BevyKnobs) -> String {
        if let Some(b) = &k.bounds {
            return format!(
                "far bounds {b:?} then max_distance ({} cascades; otherwise geometric from {}), cascade 0 from {}, overlap {}",
                b.len() + 1,
                k.first_cascade_far_bound,
                k.minimum_distance,
                k.overlap_proportion
            );
        }
        format!(
            "geometric from {} to max_distance, cascade 0 from {}, overlap {}",
            k.first_cascade_far_bound, k.minimum_distance, k.overlap_proportion
        )
    }

    const LIGHT_DEPTH: Described<BevyKnobs> = Described::Fixed("slice's own z extent; casters kept (unclipped depth)");

    const TERMS: Terms = Terms {
        comment: "//",
        language: "Rust: the shadow map resource and the DirectionalLight's CascadeShadowConfig",
        template: "\
app.insert_resource(DirectionalLightShadowMap { size: {{size}} });
let cascade_shadow_config = CascadeShadowConfigBuilder {
    num_cascades: {{num_cascades}},
    minimum_distance: {{minimum_distance}},
    maximum_distance: {{maximum_distance}},
    first_cascade_far_bound: {{first_cascade_far_bound}},
    overlap_proportion: {{overlap_proportion}},
}
.build();",
    };

    fn terms(k: &BevyKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        Values::new()
            .int("size", d.resolution)
            .int("num_cascades", d.cascades)
            .num("minimum_distance", k.minimum_distance)
            .num("maximum_distance", d.max_distance.unwrap_or(150.0))
            .num("first_cascade_far_bound", k.first_cascade_far_bound)
            .num("overlap_proportion", k.overlap_proportion)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(BevyKnobs, Dims)> {
        let table = BevyTable {
            minimum_distance: Some(f.num("minimum_distance", "bevy.minimum_distance")?),
            first_cascade_far_bound: Some(f.num("first_cascade_far_bound", "bevy.first_cascade_far_bound")?),
            overlap_proportion: Some(f.num("overlap_proportion", "bevy.overlap_proportion")?),
            // The builder's file holds the geometric series only; explicit `bounds` are not
            // written (see `terms`).
            bounds: None,
        };
        let dims = Dims {
            cascades: f.count("num_cascades", "shadow.cascades")?,
            resolution: f.size("size", "shadow.resolution")?,
            max_distance: Some(f.num("maximum_distance", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }
}
