//! A C++/OpenGL tutorial-style implementation (LearnOpenGL's cascade chapter): fixed planes,
//! an off-by-one cascade selection, padded boxes seen from a light position.

use crate::presets::{Described, centre, non_negative, point_or, Counts, Dims, Engine, EngineScheme, Fields, Fitting, KnobContext, Layout, Target,
    Terms, Values,
};
use serde::{Deserialize, Serialize};

use glam::{DVec2, DVec3};

use crate::config::Fit;
use crate::error::Result;
use csm_core::cascades::{BasisRule, LightDepthRule, WindowRule};
use csm_core::fitting::minimal_sphere;

use crate::presets::bias::{BiasModel, EngineBias};
use csm_core::truth::BiasRule;

pub struct LearnOpenGl;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LearnOpenGlTable {
    planes: Option<Vec<f64>>,
    pad_xy: Option<f64>,
    pad_z: Option<f64>,
    #[serde(default, deserialize_with = "crate::config::opt_vec3")]
    light_position: Option<[f64; 3]>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LearnOpenGlKnobs {
    pub planes: Vec<f64>,
    pub pad_xy: f64,
    pub pad_z: f64,
    pub light_position: DVec3,
}

impl Engine for LearnOpenGl {
    type Knobs = LearnOpenGlKnobs;
    type Table = LearnOpenGlTable;
    const NAME: &'static str = "learnopengl";
    const SOURCE: &'static str = "C++/OpenGL cascade code in the style of the LearnOpenGL tutorial";
    const HAS_DISTANCE: bool = false;
    const FIT: Fit = Fit::Aabb;
    const SNAPS: bool = false;

    /// The seed's shader: max(0.05 (1 - N.L), 0.005) in depth normalised over each cascade's
    /// padded light depth range.
    fn bias() -> BiasModel {
        BiasModel::Rule(EngineBias::new(
            BiasRule::RangeFacing {
                factor: 0.05,
                floor: 0.005,
            },
            "the 0.005 floor of max(0.05 (1 - N.L), 0.005)",
            "normalised depth",
        ))
    }

    fn knobs(t: &LearnOpenGlTable, cx: &KnobContext<'_>) -> Result<LearnOpenGlKnobs> {
        let v = cx.v;
        let planes = t.planes.clone().unwrap_or_else(|| vec![5.0, 15.0, 30.0, 100.0]);
        let ok = planes.len() >= 2
            && planes.len() <= 17
            && planes.iter().all(|p| p.is_finite() && *p > 0.0 && *p <= crate::config::MAX_WORLD)
            && planes.windows(2).all(|w| w[0] < w[1]);
        if !ok {
            return Err(v.invalid(
                "learnopengl.planes",
                format!("{planes:?}"),
                "2 to 17 increasing positive view depths, at most 1e9 (cascade i spans planes[i]..planes[i+1])",
            ));
        }
        let pad_xy = non_negative(v, "learnopengl.pad_xy", t.pad_xy.unwrap_or(2.0))?;
        let pad_z = non_negative(v, "learnopengl.pad_z", t.pad_z.unwrap_or(10.0))?;
        // Default light: up-sun of the scene centre at half the scene's diagonal, so the
        // direction to the scene centre is the configured light direction.
        let dist = (0.5 * (cx.scene.max - cx.scene.min).length()).max(1.0);
        let default = centre(cx.scene) - cx.light_direction * dist;
        let light_position = point_or(v, "learnopengl.light_position", t.light_position, default)?;
        Ok(LearnOpenGlKnobs {
            planes,
            pad_xy,
            pad_z,
            light_position,
        })
    }

    fn defaults(k: &LearnOpenGlKnobs, camera_far: f64) -> (usize, f64) {
        (k.planes.len() - 1, camera_far)
    }

    fn counts(k: &LearnOpenGlKnobs) -> Counts {
        Counts::Fixed(k.planes.len() - 1)
    }

    fn layout(k: &LearnOpenGlKnobs, _cascades: usize, _max_distance: f64, _near: f64, _far: f64) -> Layout {
        let p = &k.planes;
        let m = p.len() - 1;
        // index = #(planes[0..m] below the depth), clamped to m - 1: depth <= p0 reads
        // cascade 0 (slice [p0, p1]), (p0, p1] reads cascade 1, ..., beyond p_{m-2} the last.
        let mut selection = vec![f64::NEG_INFINITY];
        selection.extend_from_slice(&p[..m - 1]);
        selection.push(f64::INFINITY);
        Layout {
            fitted: p.windows(2).map(|w| (w[0], w[1])).collect(),
            selection,
        }
    }

    fn scheme(k: &LearnOpenGlKnobs, f: &Fitting<'_>) -> EngineScheme {
        let k2 = f.lens.k2();
        EngineScheme {
            label: "aabb-padded",
            window: WindowRule::Tight {
                pad: k.pad_xy,
                border: false,
            },
            sides: f.each(|a, b| 2.0 * minimal_sphere(a, b, k2).radius),
            basis: BasisRule::LookAtFrom(k.light_position),
            anchor: DVec2::ZERO,
            depth: LightDepthRule::Mirrored {
                eye: k.light_position,
                pad: k.pad_z,
            },
        }
    }

    fn split_rule(k: &LearnOpenGlKnobs) -> String {
        format!("fixed planes {:?}, off-by-one selection", k.planes)
    }

    const LIGHT_DEPTH: Described<LearnOpenGlKnobs> = Described::From(|k| format!("mirrored: light-view z ± {} passed as distances", k.pad_z));

    const TERMS: Terms = Terms {
        comment: "#",
        language: "TOML: csm-lab's [shadow] and [learnopengl] tables (the tutorial code's constants)",
        template: "\
[shadow]
preset = \"learnopengl\"
resolution = {{resolution}}
[learnopengl]
planes = [{{planes}}]
pad_xy = {{pad_xy}}
pad_z = {{pad_z}}
light_position = [{{light_position}}]",
    };

    fn terms(k: &LearnOpenGlKnobs, d: &Dims, _near: f64, _far: f64) -> Values {
        Values::new()
            .int("resolution", d.resolution)
            .nums("planes", &k.planes)
            .num("pad_xy", k.pad_xy)
            .num("pad_z", k.pad_z)
            .nums("light_position", &k.light_position.to_array())
    }

    /// The count is the planes' (one cascade between each two).
    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(LearnOpenGlKnobs, Dims)> {
        let table = LearnOpenGlTable {
            planes: Some(f.nums("planes", "learnopengl.planes")?),
            pad_xy: Some(f.num("pad_xy", "learnopengl.pad_xy")?),
            pad_z: Some(f.num("pad_z", "learnopengl.pad_z")?),
            light_position: Some(f.vec3("light_position", "learnopengl.light_position")?),
        };
        let k = Self::knobs(&table, cx)?;
        let dims = Dims {
            cascades: k.planes.len() - 1,
            resolution: f.size("resolution", "shadow.resolution")?,
            max_distance: None,
        };
        Ok((k, dims))
    }

    /// The planes are free: csm-lab's boundaries exactly (at the planes' count).
    fn match_ends(k: &mut LearnOpenGlKnobs, t: &Target<'_>) {
        if t.ends.len() >= 2 && t.ends[0] > 0.0 {
            k.planes = t.ends.to_vec();
        }
    }
}
