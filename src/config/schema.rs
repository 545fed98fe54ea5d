//! The scene file as TOML gives it: one raw struct per table, before any check. Engine tables
//! (`[bevy]`, `[godot]`, ...) are not read here: `crate::presets` parses each from the text, and
//! the names of the other top-level tables are kept so it can reject unknown ones.

use serde::Deserialize;
use toml::Spanned;

/// csm-lab's own top-level tables.
pub(crate) const SECTIONS: [&str; 11] = [
    "camera", "screen", "light", "scene", "shadow", "motion", "analysis", "sweep", "view", "views", "cost",
];

/// The whole file: csm-lab's tables, and every other top-level key (engine tables or unknown).
#[derive(Debug)]
pub(crate) struct RawFile {
    pub(crate) config: RawConfig,
    pub(crate) others: Vec<String>,
}

impl RawFile {
    /// Parses the text; TOML syntax and type errors carry the line and column.
    pub fn parse(text: &str) -> Result<RawFile, toml::de::Error> {
        let config: RawConfig = toml::from_str(text)?;
        let table: toml::Table = toml::from_str(text)?;
        let others = table
            .keys()
            .filter(|k| !SECTIONS.contains(&k.as_str()))
            .cloned()
            .collect();
        Ok(RawFile { config, others })
    }
}

/// Exactly three numbers: `[0, 10, 0, 1]` is an error, not a silently dropped fourth number.
pub(crate) fn vec3<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    struct V;
    impl<'de> serde::de::Visitor<'de> for V {
        type Value = [f64; 3];
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an array of exactly three numbers [x, y, z]")
        }
        fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<[f64; 3], A::Error> {
            let mut out = [0.0; 3];
            for (i, slot) in out.iter_mut().enumerate() {
                *slot = seq
                    .next_element::<f64>()?
                    .ok_or_else(|| serde::de::Error::invalid_length(i, &self))?;
            }
            let mut n = 3;
            while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                n += 1;
            }
            if n != 3 {
                return Err(serde::de::Error::invalid_length(n, &self));
            }
            Ok(out)
        }
    }
    d.deserialize_seq(V)
}

pub(crate) fn opt_vec3<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    vec3(d).map(Some)
}

#[derive(Debug, Deserialize)]
pub(crate) struct RawConfig {
    pub(crate) camera: RawCamera,
    pub(crate) screen: RawScreen,
    pub(crate) light: RawLight,
    pub(crate) scene: RawScene,
    #[serde(default)]
    pub(crate) shadow: RawShadow,
    #[serde(default)]
    pub(crate) motion: RawMotion,
    #[serde(default)]
    pub(crate) analysis: RawAnalysis,
    pub(crate) sweep: Option<super::sweep_spec::RawSweep>,
    /// `[[view]]`: the level's named views (issue 22); none keeps `[camera]` as the one view.
    #[serde(default)]
    pub(crate) view: Vec<RawView>,
    /// `[views]`: views from the glTF's cameras, a recorded path, or sampled player positions.
    pub(crate) views: Option<RawViews>,
    #[serde(default)]
    pub(crate) cost: RawCost,
}

/// One `[[view]]`: a named camera pose; `[camera]` gives what it leaves out (up, field of
/// view, and always the near and far planes).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawView {
    pub(crate) name: Spanned<String>,
    #[serde(deserialize_with = "vec3")]
    pub(crate) position: [f64; 3],
    #[serde(deserialize_with = "vec3")]
    pub(crate) target: [f64; 3],
    #[serde(default, deserialize_with = "opt_vec3")]
    pub(crate) up: Option<[f64; 3]>,
    pub(crate) fov_y_deg: Option<f64>,
    pub(crate) weight: Option<f64>,
}

/// `[views]`: where the level's views come from besides `[[view]]` entries.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawViews {
    /// Every perspective camera node of `scene.gltf`.
    pub(crate) from_gltf: Option<bool>,
    /// A path file (`"file.csv"`, columns px,py,pz,tx,ty,tz) or `true`: the configured motion path.
    pub(crate) from_path: Option<toml::Value>,
    /// Every k-th pose of the path (default 1).
    pub(crate) every: Option<i64>,
    /// Player positions sampled on walkable surfaces.
    pub(crate) sample: Option<i64>,
    pub(crate) seed: Option<i64>,
    pub(crate) eye_height: Option<f64>,
    pub(crate) max_slope_deg: Option<f64>,
    /// `[lo, hi]` degrees, positive looks up.
    pub(crate) pitch_deg: Option<Vec<f64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCamera {
    #[serde(deserialize_with = "vec3")]
    pub(crate) position: [f64; 3],
    #[serde(deserialize_with = "vec3")]
    pub(crate) target: [f64; 3],
    #[serde(default, deserialize_with = "opt_vec3")]
    pub(crate) up: Option<[f64; 3]>,
    pub(crate) fov_y_deg: f64,
    pub(crate) near: f64,
    pub(crate) far: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScreen {
    pub(crate) width: i64,
    pub(crate) height: i64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLight {
    #[serde(default, deserialize_with = "opt_vec3")]
    pub(crate) direction: Option<[f64; 3]>,
    /// The first `KHR_lights_punctual` directional light of `scene.gltf` instead of `direction`.
    pub(crate) from_gltf: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    #[serde(default, deserialize_with = "opt_vec3")]
    pub(crate) min: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "opt_vec3")]
    pub(crate) max: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "opt_vec3")]
    pub(crate) world_offset: Option<[f64; 3]>,
    pub(crate) ground: Option<f64>,
    #[serde(rename = "box")]
    pub(crate) boxes: Option<Vec<RawBox>>,
    pub(crate) gltf: Option<String>,
    /// Lets a glTF's buffer URIs leave its folder (absolute paths, `..`).
    #[serde(default)]
    pub(crate) gltf_outside_buffers: bool,
}

/// One `[[scene.box]]`: a solid box.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBox {
    #[serde(deserialize_with = "vec3")]
    pub(crate) min: [f64; 3],
    #[serde(deserialize_with = "vec3")]
    pub(crate) max: [f64; 3],
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawShadow {
    pub(crate) max_distance: Option<f64>,
    pub(crate) cascades: Option<i64>,
    pub(crate) lambda: Option<f64>,
    /// Explicit split fractions of the split range (instead of λ).
    pub(crate) splits: Option<Vec<f64>>,
    pub(crate) resolution: Option<i64>,
    pub(crate) fit: Option<Spanned<String>>,
    pub(crate) snap: Option<bool>,
    pub(crate) fit_depth_to_scene: Option<bool>,
    pub(crate) fit_depth_to_visible: Option<bool>,
    pub(crate) precision: Option<String>,
    pub(crate) snap_space: Option<String>,
    pub(crate) preset: Option<String>,
    pub(crate) light_update: Option<RawLightUpdate>,
    /// Ground truth's bias model (`csm_core::truth`).
    pub(crate) depth_bias: Option<f64>,
    pub(crate) slope_bias: Option<f64>,
    pub(crate) normal_bias: Option<f64>,
    pub(crate) depth_format: Option<Spanned<String>>,
    pub(crate) pcf: Option<i64>,
    pub(crate) pcf_filter: Option<Spanned<String>>,
    /// `"none"` (zero bias) or `"recommended"` (csm-lab's per-cascade bias).
    pub(crate) bias: Option<Spanned<String>>,
    /// Frames between two renders of a cascade: an integer, or one per cascade.
    pub(crate) update_every: Option<toml::Value>,
}

/// `[shadow] light_update = { every_frames = K }` or `{ quantize_deg = Q }`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLightUpdate {
    pub(crate) every_frames: Option<i64>,
    pub(crate) quantize_deg: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawMotion {
    pub(crate) path: Option<String>,
    /// Several paths, judged together (the summary takes the worst); excludes `path`.
    pub(crate) paths: Option<Vec<String>>,
    /// One step per entry of `paths` (default: `step` for every path).
    pub(crate) steps: Option<Vec<f64>>,
    pub(crate) frames: Option<i64>,
    pub(crate) step: Option<f64>,
    pub(crate) file: Option<String>,
    /// The light's path: "still" (default), "sun" or "file".
    pub(crate) light_path: Option<String>,
    pub(crate) sun_azimuth_step_deg: Option<f64>,
    pub(crate) sun_elevation_step_deg: Option<f64>,
    pub(crate) light_file: Option<String>,
}

/// `[cost]`: receiver-aware culling and the calibration of the cost model (docs/cost.md).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCost {
    pub(crate) counts: Option<bool>,
    pub(crate) cull: Option<String>,
    pub(crate) ns_per_draw: Option<f64>,
    pub(crate) ns_per_triangle: Option<f64>,
    pub(crate) ns_per_fragment: Option<f64>,
    pub(crate) ns_per_texel_cleared: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAnalysis {
    pub(crate) density_samples: Option<i64>,
    pub(crate) probes: Option<i64>,
    pub(crate) screen_scale: Option<f64>,
    pub(crate) ground_truth: Option<bool>,
}
