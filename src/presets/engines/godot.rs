//! Godot 4 (`renderer_scene_cull.cpp`, `light_3d.cpp`): fractions of [near, max distance],
//! optional blend splits, corner-average spheres with a texel of border, 2-texel round snap,
//! a pancaked caster range.

use crate::presets::{Described, complete_fractions, fractions, non_negative, snap, Counts, Dims, Engine, EngineScheme, Fields, Fitting,
    KnobContext, Layout, Target, Terms, Values,
};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use csm_core::cascades::LightDepthRule;
use csm_core::fitting::corner_average_sphere;
use csm_core::snapping::{SnapMode, SnapRule};

use crate::presets::bias::{BiasModel, EngineBias};
use crate::presets::free_splits::{keep, padded_to_three, FreeSplitKnob, FreeSplits};
use csm_core::free_splits::FractionSpace;
use csm_core::truth::{BiasRule, NormalOffset};

pub struct Godot;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GodotTable {
    splits: Option<Vec<f64>>,
    blend_splits: Option<bool>,
    pancake_size: Option<f64>,
}

/// Godot DirectionalLight3D (`max_distance` is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GodotKnobs {
    /// split_1, split_2, split_3 (PSSM2 uses split_1 only).
    pub splits: [f64; 3],
    pub blend_splits: bool,
    pub pancake_size: f64,
}

impl Engine for Godot {
    type Knobs = GodotKnobs;
    type Table = GodotTable;
    const NAME: &'static str = "godot";
    const SOURCE: &'static str = "Godot 4 renderer_scene_cull.cpp, light_3d.cpp";

    /// Depth bias = bias / 100 x the cascade's depth range; normal bias x texel x
    /// (1 - max(0, N.L)) with its part along the light removed; defaults 0.1 and 2.0.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::RangeFraction {
                fraction: 0.1 / 100.0,
                normal_texels: 2.0,
                offset: NormalOffset::Lateral,
            },
            "DirectionalLight3D.shadow_bias",
            "percent of the cascade's depth range",
        )
        .scaled(100.0))
    }

    /// `directional_shadow_split_1..3`: fractions of [near, max distance].
    const FREE_SPLITS: Option<FreeSplits<GodotKnobs>> = Some(FreeSplits {
        knob: |_| FreeSplitKnob {
            key: "godot.splits",
            term: "DirectionalLight3D.directional_shadow_split_1..3",
            of: "fractions of [near, max distance]",
        },
        space: |_, p| {
            let max_d = p.far.min(p.max_distance).max(p.near + 0.001);
            let min_d = p.near.min(max_d);
            FractionSpace {
                lo: min_d,
                hi: max_d,
                start: min_d,
            }
        },
        configured: |k, cascades, _| k.splits[..cascades - 1].to_vec(),
        values: |k, cascades, _, fractions| padded_to_three(k.splits, cascades, fractions),
        set: |k, _, v| k.splits = [v[0], v[1], v[2]],
        setting: |_, s| {
            s.values
                .iter()
                .take(s.cascades - 1)
                .enumerate()
                .map(|(i, v)| format!("directional_shadow_split_{} = {v}", i + 1))
                .collect::<Vec<_>>()
                .join(", ")
        },
        paste_prefix: "",
        scalar_when_one: true,
        fit_count: keep,
    });

    fn knobs(t: &GodotTable, cx: &KnobContext<'_>) -> Result<GodotKnobs> {
        let v = cx.v;
        let splits = fractions::<3>(v, "godot.splits", t.splits.as_ref(), [0.1, 0.2, 0.5])?;
        Ok(GodotKnobs {
            splits,
            blend_splits: t.blend_splits.unwrap_or(false),
            pancake_size: non_negative(v, "godot.pancake_size", t.pancake_size.unwrap_or(20.0))?,
        })
    }

    fn defaults(_: &GodotKnobs, _camera_far: f64) -> (usize, f64) {
        (4, 100.0)
    }

    fn counts(_: &GodotKnobs) -> Counts {
        Counts::Allowed(vec![1, 2, 4])
    }

    fn layout(k: &GodotKnobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
        let max_d = far.min(max_distance).max(near + 0.001);
        let min_d = near.min(max_d);
        let used: &[f64] = match cascades {
            1 => &[],
            2 => &k.splits[..1],
            _ => &k.splits[..],
        };
        let mut d = vec![min_d];
        d.extend(used.iter().map(|s| min_d + s * (max_d - min_d)));
        d.push(max_d);
        if k.blend_splits {
            // Each cascade after the first also covers the previous one; the last 10 % of
            // each interval blends toward the next (coarser) cascade.
            let m = d.len() - 1;
            let fitted = (0..m).map(|i| (d[i.saturating_sub(1)], d[i + 1])).collect();
            let mut selection = vec![d[0]];
            selection.extend(d[1..m].iter().map(|x| 0.9 * x));
            selection.push(d[m]);
            Layout { fitted, selection }
        } else {
            Layout::contiguous(d)
        }
    }

    fn snap_rule(_: &GodotKnobs) -> SnapRule {
        snap(SnapMode::Round, 2)
    }

    fn scheme(k: &GodotKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        let s = f.spheres(|a, b| corner_average_sphere(a, b, k2));
        // r·T/(T − 2): one texel of border per side.
        let sides = f.on(&s, f.resolution as f64 - 2.0);
        let depth = LightDepthRule::Sphere {
            radius: sides.iter().map(|w| 0.5 * w).collect(),
            toward_light: k.pancake_size,
            min_half: 0.0,
        };
        EngineScheme::fixed("sphere-average+border", Fitting::axis(&s), sides, depth)
    }

    fn split_rule(k: &GodotKnobs) -> String {
        format!(
            "fractions {:?} of [near, min(far, max_distance)]{}",
            k.splits,
            if k.blend_splits { ", blend_splits" } else { "" }
        )
    }

    const LIGHT_DEPTH: Described<GodotKnobs> = Described::From(|k| format!("sphere ± r, {} toward the light; casters pancaked", k.pancake_size));

    const TERMS: Terms = Terms {
        comment: "#",
        language: "GDScript, Godot 4: the directional shadow atlas and the DirectionalLight3D `light`",
        template: "\
RenderingServer.directional_shadow_atlas_set_size({{directional_shadow_size}}, true)
light.directional_shadow_mode = DirectionalLight3D.{{directional_shadow_mode}}
light.directional_shadow_split_1 = {{directional_shadow_split_1}}
light.directional_shadow_split_2 = {{directional_shadow_split_2}}
light.directional_shadow_split_3 = {{directional_shadow_split_3}}
light.directional_shadow_blend_splits = {{directional_shadow_blend_splits}}
light.directional_shadow_max_distance = {{directional_shadow_max_distance}}
light.directional_shadow_pancake_size = {{directional_shadow_pancake_size}}",
    };

    /// The atlas holds one map per cascade's tile: the whole atlas for 1 cascade, a half
    /// (full width) for 2, a quarter for 4; a tile's size is the larger side of its rect.
    fn terms(k: &GodotKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        let (mode, per) = match d.cascades {
            1 => ("SHADOW_ORTHOGONAL", 1),
            2 => ("SHADOW_PARALLEL_2_SPLITS", 1),
            _ => ("SHADOW_PARALLEL_4_SPLITS", 2),
        };
        Values::new()
            .int("directional_shadow_size", d.resolution * per)
            .word("directional_shadow_mode", mode)
            .num("directional_shadow_split_1", k.splits[0])
            .num("directional_shadow_split_2", k.splits[1])
            .num("directional_shadow_split_3", k.splits[2])
            .bool("directional_shadow_blend_splits", k.blend_splits)
            .num("directional_shadow_max_distance", d.max_distance.unwrap_or(100.0))
            .num("directional_shadow_pancake_size", k.pancake_size)
    }

    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(GodotKnobs, Dims)> {
        let cascades = f.word(
            "directional_shadow_mode",
            "shadow.cascades",
            &[
                ("SHADOW_ORTHOGONAL", 1),
                ("SHADOW_PARALLEL_2_SPLITS", 2),
                ("SHADOW_PARALLEL_4_SPLITS", 4),
            ],
        )?;
        let per = if cascades == 4 { 2 } else { 1 };
        let key = "godot.splits";
        let table = GodotTable {
            splits: Some(vec![
                f.num("directional_shadow_split_1", key)?,
                f.num("directional_shadow_split_2", key)?,
                f.num("directional_shadow_split_3", key)?,
            ]),
            blend_splits: Some(f.bool("directional_shadow_blend_splits", "godot.blend_splits")?),
            pancake_size: Some(f.num("directional_shadow_pancake_size", "godot.pancake_size")?),
        };
        let dims = Dims {
            cascades,
            resolution: f.tile("directional_shadow_size", "shadow.resolution", per)?,
            max_distance: Some(f.num("directional_shadow_max_distance", "shadow.max_distance")?),
        };
        Ok((Self::knobs(&table, cx)?, dims))
    }

    /// Fractions of [near, min(far, max distance)]: csm-lab's boundaries exactly.
    fn match_ends(k: &mut GodotKnobs, t: &Target<'_>) {
        let max_d = t.far.min(t.distance).max(t.near + 0.001);
        let min_d = t.near.min(max_d);
        k.splits = complete_fractions(&t.fractions(min_d, max_d), k.splits);
    }
}
