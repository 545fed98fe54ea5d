//! Filament (`ShadowMap.cpp`, `ShadowMapManager.cpp`) in stable mode: split positions of
//! [near, shadowFar or far], corner-average spheres on mapSize − 2 texels, fmod snapping in a
//! light basis fixed in the world: a look-to along the light with the world-origin transform's
//! x axis (+X) as the up reference, as `computeDirectionalShadowBounds` builds it.

use crate::presets::{Described, complete_fractions, fractions, snap, unit, Counts, Dims, Engine, EngineScheme, Fields, Fitting, KnobContext,
    Layout, Target, Terms, Values,
};
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};
use toml::Spanned;

use crate::error::Result;
use csm_core::cascades::{BasisRule, LightDepthRule};
use csm_core::fitting::corner_average_sphere;
use csm_core::snapping::{SnapMode, SnapRule};

use crate::presets::bias::{BiasModel, EngineBias};
use crate::presets::free_splits::{keep, padded_to_three, FreeSplitKnob, FreeSplits};
use csm_core::free_splits::FractionSpace;
use csm_core::truth::{BiasRule, NormalOffset};

pub struct Filament;

/// Filament split positions: given directly, or from one of the `ShadowCascades` helpers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FilamentSplit {
    Positions,
    Uniform,
    Logarithmic,
    Practical,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilamentTable {
    split_mode: Option<Spanned<String>>,
    lambda: Option<f64>,
    split_positions: Option<Vec<f64>>,
}

/// Filament `ShadowOptions` in stable mode (`shadowFar` is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FilamentKnobs {
    pub split_mode: FilamentSplit,
    /// λ of the practical helper (used with `split_mode = "practical"`).
    pub lambda: f64,
    pub split_positions: [f64; 3],
}

/// Filament split positions in (0, 1) for `cascades`.
pub fn filament_positions(k: &FilamentKnobs, cascades: usize, near: f64, far: f64) -> Vec<f64> {
    let m = cascades as f64;
    (1..cascades)
        .map(|c| {
            let c = c as f64;
            let uniform = c / m;
            let log = (near * (far / near).powf(c / m) - near) / (far - near);
            match k.split_mode {
                FilamentSplit::Positions => k.split_positions[c as usize - 1],
                FilamentSplit::Uniform => uniform,
                FilamentSplit::Logarithmic => log,
                FilamentSplit::Practical => k.lambda * log + (1.0 - k.lambda) * uniform,
            }
        })
        .collect()
}

impl Engine for Filament {
    type Knobs = FilamentKnobs;
    type Table = FilamentTable;
    const NAME: &'static str = "filament";
    const SOURCE: &'static str = "Filament ShadowMap.cpp, ShadowMapManager.cpp, stable mode";
    const POWER_OF_TWO_MAPS: bool = true;

    /// Light camera moved by constantBias (world units); normal bias 0.5 x normalBias x
    /// texel; polygon offset slope 2 (its constant 0.5 is in depth-buffer steps: left out).
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::World {
                depth: 0.001,
                slope: 2.0,
                normal_texels: 0.5,
                offset: NormalOffset::Along,
            },
            "ShadowOptions.constantBias",
            "world units",
        ))
    }

    /// `cascadeSplitPositions`: fractions of [near, shadowFar]; setting them switches the split
    /// mode to explicit positions.
    const FREE_SPLITS: Option<FreeSplits<FilamentKnobs>> = Some(FreeSplits {
        knob: |_| FreeSplitKnob {
            key: "filament.split_positions",
            term: "ShadowOptions.cascadeSplitPositions",
            of: "fractions of [near, shadowFar]",
        },
        space: |_, p| FractionSpace {
            lo: p.near,
            hi: p.max_distance,
            start: p.near,
        },
        configured: |k, cascades, p| filament_positions(k, cascades, p.near, p.max_distance),
        values: |k, cascades, _, fractions| padded_to_three(k.split_positions, cascades, fractions),
        set: |k, _, v| {
            k.split_mode = FilamentSplit::Positions;
            k.split_positions = [v[0], v[1], v[2]];
        },
        setting: |_, s| {
            format!(
                "ShadowOptions.cascadeSplitPositions = {{ {} }}",
                s.fractions
                    .iter()
                    .map(|x| format!("{x}f"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        },
        paste_prefix: "split_mode = \"positions\"\n",
        scalar_when_one: true,
        fit_count: keep,
    });

    fn knobs(t: &FilamentTable, cx: &KnobContext<'_>) -> Result<FilamentKnobs> {
        let v = cx.v;
        let split_mode = match &t.split_mode {
            Some(m) => v.one_of(
                "filament.split_mode",
                m,
                &[
                    ("positions", FilamentSplit::Positions),
                    ("uniform", FilamentSplit::Uniform),
                    ("logarithmic", FilamentSplit::Logarithmic),
                    ("practical", FilamentSplit::Practical),
                ],
            )?,
            None => FilamentSplit::Positions,
        };
        Ok(FilamentKnobs {
            split_mode,
            lambda: unit(v, "filament.lambda", t.lambda.unwrap_or(0.5))?,
            split_positions: fractions::<3>(
                v,
                "filament.split_positions",
                t.split_positions.as_ref(),
                [0.125, 0.25, 0.5],
            )?,
        })
    }

    // shadowFar 0 means "use the camera far plane".
    fn defaults(_: &FilamentKnobs, camera_far: f64) -> (usize, f64) {
        (1, camera_far)
    }

    fn default_resolution(_: &FilamentKnobs, _cascades: usize) -> u32 {
        1024
    }

    fn counts(_: &FilamentKnobs) -> Counts {
        Counts::Allowed(vec![1, 2, 3, 4])
    }

    fn lambda(k: &FilamentKnobs) -> Option<f64> {
        match k.split_mode {
            FilamentSplit::Practical => Some(k.lambda),
            FilamentSplit::Uniform => Some(0.0),
            FilamentSplit::Logarithmic => Some(1.0),
            FilamentSplit::Positions => None,
        }
    }

    fn lambda_key(k: &FilamentKnobs) -> Option<&'static str> {
        (k.split_mode == FilamentSplit::Practical).then_some("filament.lambda")
    }

    fn set_lambda(k: &mut FilamentKnobs, lambda: f64) {
        k.lambda = lambda;
    }

    fn layout(k: &FilamentKnobs, cascades: usize, max_distance: f64, near: f64, _far: f64) -> Layout {
        let f = max_distance;
        let p = filament_positions(k, cascades, near, f);
        let mut s = vec![near];
        s.extend(p.iter().map(|p| near + (f - near) * p));
        s.push(f);
        Layout::contiguous(s)
    }

    fn snap_rule(_: &FilamentKnobs) -> SnapRule {
        snap(SnapMode::Trunc, 2)
    }

    fn scheme(_: &FilamentKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        let s = f.spheres(|a, b| corner_average_sphere(a, b, k2));
        EngineScheme {
            label: "sphere-average+border",
            window: Fitting::axis(&s),
            // mapSize − 2 usable texels: one texel of border per side.
            sides: f.on(&s, f.resolution as f64 - 2.0),
            // Up reference: the world-origin transform's x axis (the identity's +X).
            basis: BasisRule::LookToUp(DVec3::X),
            anchor: DVec2::ZERO,
            depth: LightDepthRule::Scene,
        }
    }

    fn split_rule(k: &FilamentKnobs) -> String {
        match k.split_mode {
            FilamentSplit::Positions => format!("positions {:?} of [near, shadowFar or far]", k.split_positions),
            FilamentSplit::Uniform => "uniform helper on [near, shadowFar or far]".to_string(),
            FilamentSplit::Logarithmic => "logarithmic helper on [near, shadowFar or far]".to_string(),
            FilamentSplit::Practical => format!("practical helper, λ {}", k.lambda),
        }
    }

    fn snap_anchor(_: &FilamentKnobs) -> &'static str {
        "world origin, basis from +X (fixed in the world)"
    }

    const LIGHT_DEPTH: Described<FilamentKnobs> = Described::Fixed("from receiver and caster bounds");

    const TERMS: Terms = Terms {
        comment: "//",
        language: "C++, Filament: the sun's LightManager::ShadowOptions, stable mode",
        template: "\
LightManager::ShadowOptions options;
options.mapSize = {{mapSize}};
options.shadowCascades = {{shadowCascades}};
options.cascadeSplitPositions[0] = {{cascadeSplitPositions[0]}};
options.cascadeSplitPositions[1] = {{cascadeSplitPositions[1]}};
options.cascadeSplitPositions[2] = {{cascadeSplitPositions[2]}};
options.shadowFar = {{shadowFar}};
options.stable = true;",
    };

    /// The positions the knobs give at this count (a helper's, computed as Filament's
    /// `ShadowCascades` helpers do); the slots the count does not read keep valid values.
    fn terms(k: &FilamentKnobs, d: &Dims, near: f64, far: f64) -> Values {
        let distance = d.max_distance.unwrap_or(far);
        let p = complete_fractions(&filament_positions(k, d.cascades, near, distance), k.split_positions);
        Values::new()
            .int("mapSize", d.resolution)
            .int("shadowCascades", d.cascades)
            .num("cascadeSplitPositions[0]", p[0])
            .num("cascadeSplitPositions[1]", p[1])
            .num("cascadeSplitPositions[2]", p[2])
            .num("shadowFar", distance)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(FilamentKnobs, Dims)> {
        let key = "filament.split_positions";
        let table = FilamentTable {
            split_mode: None,
            lambda: None,
            split_positions: Some(vec![
                f.num("cascadeSplitPositions[0]", key)?,
                f.num("cascadeSplitPositions[1]", key)?,
                f.num("cascadeSplitPositions[2]", key)?,
            ]),
        };
        let dims = Dims {
            cascades: f.count("shadowCascades", "shadow.cascades")?,
            resolution: f.size("mapSize", "shadow.resolution")?,
            max_distance: Some(f.num("shadowFar", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }

    /// Split positions of [near, shadowFar]: csm-lab's boundaries exactly.
    fn match_ends(k: &mut FilamentKnobs, t: &Target<'_>) {
        if t.cascades() < 2 {
            return;
        }
        k.split_mode = FilamentSplit::Positions;
        k.split_positions = complete_fractions(&t.fractions(t.near, t.distance), k.split_positions);
    }
}
