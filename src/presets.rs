//! Presets: the whole cascade set-up of a real engine or of one of the seed implementations,
//! so its windows go through the same metrics as csm-lab's own pipeline.
//!
//! A preset fixes the split rule and where the split range starts and ends, the overlap or
//! blend band, the fit (window size and centre), the snapping rule (rounding mode, step in
//! texels, border, grid anchor), the light basis, the light depth range and the defaults
//! (cascades, map size, shadow distance). Nothing is clipped to the scene bounds unless the
//! engine does so (none of these does for its splits).
//!
//! | preset | split rule | fit | snap | defaults (cascades, map, distance) | source |
//! |---|---|---|---|---|---|
//! | `dart` | practical λ on [near, distance], count clamped to 1..4 | corner-average sphere, box 2r | round, 1 texel, world origin (chosen) | 4, 2048, camera far (chosen; λ 0.5) | seed 000 |
//! | `threejs` | breaks of min(far, maxFar), practical λ 0.5 (r185) | slice diameter at the light-space box centre | floor, 1 texel, world origin | 3, 2048, maxFar 1e5 | seed 001, engines.md 3.7 |
//! | `unity-sample` | near + {0.067, 0.2, 0.467}·far, 4 cascades | tight box, centred on the origin axis (defect) | none | 4, 1024, camera far | seed 002 |
//! | `eevee` | practical λ 0.8, fade 0.1 overlap | far-cap-centred sphere | round, 1 texel, lamp position | 4, 1024, 200 | seed 003, engines.md 3.8 |
//! | `learnopengl` | fixed planes {5, 15, 30, 100}, off-by-one selection | box padded 2 (x/y), look-at from a light position | none | 3, 2048, camera far | seed 004 |
//! | `bevy` | geometric from first far bound to max, overlap 0.2 | ceil(slice diameter) at the box centre | floor, 1 texel, world origin | 4, 2048, 150 | engines.md 3.1 |
//! | `godot` | fractions 0.1/0.2/0.5 of [near, max] | corner-average sphere × N/(N−2) | round, 2 texels, world origin | 4, 2048, 100 | engines.md 3.2 |
//! | `unreal` | geometric weights, exponent 3, transition 0.1 | minimal sphere (Unreal's formula) + 4-texel border | fmod (trunc), 4 texels, world origin | 3, 2048, 200 | engines.md 3.4 |
//! | `unity` | 0.067/0.2/0.467 of the shadow distance | sphere (modelled as minimal) | round, 1 texel (modelled) | 4, 2048, 150 | engines.md 3.5 (docs) |
//! | `unity-urp` | fractions of 50 m (1 cascade by default) | sphere (modelled as minimal) | round, 1 texel (modelled) | 1, 2048, 50 | engines.md 3.6 |
//! | `filament` | positions 0.125/0.25/0.5 of [near, shadowFar or far] | corner-average sphere on mapSize − 2 texels | fmod (trunc), 2 texels, camera-oriented basis | 1, 1024, camera far | engines.md 3.3 (stable mode) |
//!
//! Units: 1 world unit = 1 metre; Unreal's centimetre constants are converted (shadow distance
//! 200 m, caster range ±50 m, radius at least 1 cm).
//!
//! **Selection vs fitted.** Each preset yields its fitted slices (what each window is built
//! around) and its selection boundaries (which cascade a view depth reads; in a blend band the
//! coarser cascade counts). Selection starts at the camera near plane and ends at the camera far
//! plane at most. Coverage is checked for both: the fitted slice and the part of the selection
//! interval outside it, so a cascade read where its window does not reach shows up as coverage
//! violations (seed 004's off-by-one selection, seed 002's centring defect).
//!
//! **Light depth.** Each preset renders a light depth range by its own rule; the report gives
//! the receiver depth (the cascade's slice within the scene bounds) and the caster depth (scene
//! within the window's prism, toward the light) that falls outside it, e.g. three.js's fixed
//! `lightNear`/`lightFar` with its margin.
//!
//! **Modelling choices** (not stated by the sources): seed 000's snap rule and defaults, Unity's
//! sphere and snap (closed source: modelled as csm-lab's minimal sphere with round snapping),
//! the default light positions of `eevee` and `learnopengl`, the light depth range where the
//! source does not show it (fitted to the scene: no clipping reported). Each is documented on
//! its knob or in `docs/presets.md`.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::cascades::{BasisRule, LightDepth, LightDepthRule, LightPose, Rig, Scheme, WindowRule};
use crate::config::{CameraSettings, Config, Fit, ShadowSettings, Validator};
use crate::error::{Error, Result};
use crate::fitting::{corner_average_sphere, far_cap_sphere, minimal_sphere, slice_diameter, Sphere, Window};
use crate::geometry::{Aabb, Lens, LightBasis};
use crate::snapping::{SnapMode, SnapRule};

// ---------------------------------------------------------------------------------------------
// Names
// ---------------------------------------------------------------------------------------------

/// The implementations csm-lab reproduces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PresetName {
    Dart,
    Threejs,
    UnitySample,
    Eevee,
    LearnOpenGl,
    Bevy,
    Godot,
    Unreal,
    Unity,
    UnityUrp,
    Filament,
}

impl PresetName {
    pub const ALL: [PresetName; 11] = [
        PresetName::Dart,
        PresetName::Threejs,
        PresetName::UnitySample,
        PresetName::Eevee,
        PresetName::LearnOpenGl,
        PresetName::Bevy,
        PresetName::Godot,
        PresetName::Unreal,
        PresetName::Unity,
        PresetName::UnityUrp,
        PresetName::Filament,
    ];

    /// The name used in configs, on the command line and as the engine table's name.
    pub fn as_str(self) -> &'static str {
        match self {
            PresetName::Dart => "dart",
            PresetName::Threejs => "threejs",
            PresetName::UnitySample => "unity-sample",
            PresetName::Eevee => "eevee",
            PresetName::LearnOpenGl => "learnopengl",
            PresetName::Bevy => "bevy",
            PresetName::Godot => "godot",
            PresetName::Unreal => "unreal",
            PresetName::Unity => "unity",
            PresetName::UnityUrp => "unity-urp",
            PresetName::Filament => "filament",
        }
    }

    pub fn parse(s: &str) -> Option<PresetName> {
        PresetName::ALL.into_iter().find(|p| p.as_str() == s)
    }

    /// Where the preset's behaviour comes from.
    pub fn source(self) -> &'static str {
        match self {
            PresetName::Dart => "seed 000: Dart computeCascades (API docs)",
            PresetName::Threejs => "seed 001 and three.js CSM addon r185+ (engines.md 3.7)",
            PresetName::UnitySample => "seed 002: Unity C# sample (soramamenatan blog #113)",
            PresetName::Eevee => "seed 003: Blender EEVEE 2017 eevee_shadow_cascade_setup (engines.md 3.8)",
            PresetName::LearnOpenGl => "seed 004: C++/OpenGL LearnOpenGL-style tutorial",
            PresetName::Bevy => "Bevy bevy_light/src/cascade.rs @ 4805ca792c3e (engines.md 3.1)",
            PresetName::Godot => "Godot 4 renderer_scene_cull.cpp, light_3d.cpp (engines.md 3.2)",
            PresetName::Unreal => "Unreal Engine CSM: DirectionalLightComponent.cpp, ShadowSetup.cpp (engines.md 3.4)",
            PresetName::Unity => "Unity built-in render pipeline, Stable Fit (vendor docs; engines.md 3.5)",
            PresetName::UnityUrp => "Unity URP UniversalRenderPipelineAsset.cs, Shadows.hlsl (engines.md 3.6)",
            PresetName::Filament => "Filament ShadowMap.cpp, ShadowMapManager.cpp, stable mode (engines.md 3.3)",
        }
    }
}

impl std::fmt::Display for PresetName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl Serialize for PresetName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

/// Every preset name, comma-separated, for messages.
pub fn valid_names() -> String {
    PresetName::ALL.map(|p| p.as_str()).join(", ")
}

/// Levenshtein distance (for "did you mean").
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

/// The preset name closest to `s`.
pub fn closest_name(s: &str) -> PresetName {
    let s = s.to_ascii_lowercase();
    PresetName::ALL
        .into_iter()
        .min_by_key(|p| edit_distance(&s, p.as_str()))
        .expect("non-empty")
}

/// "valid presets: ...; did you mean ...?"
pub fn unknown_name_message(s: &str) -> String {
    format!(
        "valid presets are {}; did you mean \"{}\"?",
        valid_names(),
        closest_name(s)
    )
}

/// Parses a preset name given on the command line.
pub fn parse_flag(flag: &str, s: &str) -> Result<PresetName> {
    PresetName::parse(s).ok_or_else(|| Error::flag(flag, s, format!("unknown preset; {}", unknown_name_message(s))))
}

/// Parses a comma-separated list of preset names (`--presets bevy,godot`).
pub fn parse_list(flag: &str, s: &str) -> Result<Vec<PresetName>> {
    let mut out = Vec::new();
    for part in s.split(',').map(str::trim) {
        if part.is_empty() {
            return Err(Error::flag(
                flag,
                s,
                format!("empty preset name in the list; valid presets are {}", valid_names()),
            ));
        }
        let p = parse_flag(flag, part)?;
        if out.contains(&p) {
            return Err(Error::flag(flag, s, format!("\"{p}\" is listed twice")));
        }
        out.push(p);
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Knobs (resolved) and their raw TOML tables
// ---------------------------------------------------------------------------------------------

/// three.js split modes (`mode` of the CSM constructor; the custom callback is not modelled).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ThreejsMode {
    Uniform,
    Logarithmic,
    Practical,
}

/// Filament split positions: given directly, or from one of the `ShadowCascades` helpers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FilamentSplit {
    Positions,
    Uniform,
    Logarithmic,
    Practical,
}

/// Seed 000. λ is `shadowCascadeSplitLambda` (default not in the seed: 0.5 chosen).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DartKnobs {
    pub lambda: f64,
}

/// three.js CSM (constructor parameters).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ThreejsKnobs {
    pub mode: ThreejsMode,
    pub light_margin: f64,
    pub light_near: f64,
    pub light_far: f64,
}

/// Seed 002. `centre_on_slice = true` repairs the discarded window centre (default: reproduce).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnitySampleKnobs {
    pub centre_on_slice: bool,
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

/// Seed 004.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LearnOpenGlKnobs {
    pub planes: Vec<f64>,
    pub pad_xy: f64,
    pub pad_z: f64,
    pub light_position: DVec3,
}

/// Bevy `CascadeShadowConfigBuilder` (maximum_distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BevyKnobs {
    pub minimum_distance: f64,
    pub first_cascade_far_bound: f64,
    pub overlap_proportion: f64,
}

/// Godot DirectionalLight3D (`max_distance` is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GodotKnobs {
    /// split_1, split_2, split_3 (PSSM2 uses split_1 only).
    pub splits: [f64; 3],
    pub blend_splits: bool,
    pub pancake_size: f64,
}

/// Unreal directional light (dynamic shadow distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnrealKnobs {
    pub cascade_distribution_exponent: f64,
    pub transition_fraction: f64,
}

/// Unity built-in quality settings (shadow distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnityKnobs {
    pub cascade2_split: f64,
    pub cascade4_split: [f64; 3],
}

/// Unity URP asset (shadow distance is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnityUrpKnobs {
    pub cascade2_split: f64,
    pub cascade3_split: [f64; 2],
    pub cascade4_split: [f64; 3],
}

/// Filament `ShadowOptions` in stable mode (`shadowFar` is `shadow.max_distance`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FilamentKnobs {
    pub split_mode: FilamentSplit,
    /// λ of the practical helper (used with `split_mode = "practical"`).
    pub lambda: f64,
    pub split_positions: [f64; 3],
}

/// A preset's engine knobs, resolved (defaults applied, validated).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Knobs {
    Dart(DartKnobs),
    Threejs(ThreejsKnobs),
    UnitySample(UnitySampleKnobs),
    Eevee(EeveeKnobs),
    #[serde(rename = "learnopengl")]
    LearnOpenGl(LearnOpenGlKnobs),
    Bevy(BevyKnobs),
    Godot(GodotKnobs),
    Unreal(UnrealKnobs),
    Unity(UnityKnobs),
    UnityUrp(UnityUrpKnobs),
    Filament(FilamentKnobs),
}

impl Knobs {
    pub fn name(&self) -> PresetName {
        match self {
            Knobs::Dart(_) => PresetName::Dart,
            Knobs::Threejs(_) => PresetName::Threejs,
            Knobs::UnitySample(_) => PresetName::UnitySample,
            Knobs::Eevee(_) => PresetName::Eevee,
            Knobs::LearnOpenGl(_) => PresetName::LearnOpenGl,
            Knobs::Bevy(_) => PresetName::Bevy,
            Knobs::Godot(_) => PresetName::Godot,
            Knobs::Unreal(_) => PresetName::Unreal,
            Knobs::Unity(_) => PresetName::Unity,
            Knobs::UnityUrp(_) => PresetName::UnityUrp,
            Knobs::Filament(_) => PresetName::Filament,
        }
    }
}

/// A resolved preset: which implementation, its knobs, and notes about the resolution
/// (settings it ignored or clamped the way the engine does).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Preset {
    pub name: PresetName,
    pub knobs: Knobs,
    pub notes: Vec<String>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawDart {
    lambda: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawThreejs {
    mode: Option<ThreejsMode>,
    light_margin: Option<f64>,
    light_near: Option<f64>,
    light_far: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawUnitySample {
    centre_on_slice: Option<bool>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawEevee {
    cascade_exponent: Option<f64>,
    fade: Option<f64>,
    lamp_position: Option<[f64; 3]>,
    clip_start: Option<f64>,
    clip_end: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLearnOpenGl {
    planes: Option<Vec<f64>>,
    pad_xy: Option<f64>,
    pad_z: Option<f64>,
    light_position: Option<[f64; 3]>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawBevy {
    minimum_distance: Option<f64>,
    first_cascade_far_bound: Option<f64>,
    overlap_proportion: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawGodot {
    splits: Option<Vec<f64>>,
    blend_splits: Option<bool>,
    pancake_size: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawUnreal {
    cascade_distribution_exponent: Option<f64>,
    transition_fraction: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawUnity {
    cascade2_split: Option<f64>,
    cascade4_split: Option<Vec<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawUnityUrp {
    cascade2_split: Option<f64>,
    cascade3_split: Option<Vec<f64>>,
    cascade4_split: Option<Vec<f64>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawFilament {
    split_mode: Option<FilamentSplit>,
    lambda: Option<f64>,
    split_positions: Option<Vec<f64>>,
}

/// The engine tables of a config file, as parsed (any of them may be absent).
#[derive(Debug, Default)]
pub struct RawTables {
    pub dart: Option<RawDart>,
    pub threejs: Option<RawThreejs>,
    pub unity_sample: Option<RawUnitySample>,
    pub eevee: Option<RawEevee>,
    pub learnopengl: Option<RawLearnOpenGl>,
    pub bevy: Option<RawBevy>,
    pub godot: Option<RawGodot>,
    pub unreal: Option<RawUnreal>,
    pub unity: Option<RawUnity>,
    pub unity_urp: Option<RawUnityUrp>,
    pub filament: Option<RawFilament>,
}

impl RawTables {
    /// The presets whose table is present.
    fn present(&self) -> Vec<PresetName> {
        let flags = [
            self.dart.is_some(),
            self.threejs.is_some(),
            self.unity_sample.is_some(),
            self.eevee.is_some(),
            self.learnopengl.is_some(),
            self.bevy.is_some(),
            self.godot.is_some(),
            self.unreal.is_some(),
            self.unity.is_some(),
            self.unity_urp.is_some(),
            self.filament.is_some(),
        ];
        PresetName::ALL
            .into_iter()
            .zip(flags)
            .filter_map(|(p, f)| f.then_some(p))
            .collect()
    }
}

/// How the preset is chosen when a config is loaded.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PresetChoice {
    /// Overrides `shadow.preset` (the `--preset` flag).
    pub name: Option<PresetName>,
    /// Engine tables allowed besides the selected preset's (`compare` runs several presets on
    /// one file).
    pub also_allowed: Vec<PresetName>,
    /// Ignore `[shadow] cascades`, `resolution` and `max_distance`: the preset's own defaults
    /// (`compare --defaults`).
    pub engine_defaults: bool,
}

/// Which `[shadow]` keys the file wrote (their values are already validated in
/// [`ShadowSettings`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Written {
    pub max_distance: bool,
    pub cascades: bool,
    pub resolution: bool,
    pub lambda: bool,
    pub fit: bool,
    pub snap: bool,
    pub fit_depth_to_scene: bool,
}

/// Everything [`resolve`] needs from the rest of the config.
pub struct ResolveContext<'a> {
    pub choice: &'a PresetChoice,
    /// `shadow.preset` as written.
    pub file_preset: Option<String>,
    pub written: Written,
    pub tables: RawTables,
    pub camera: &'a CameraSettings,
    pub light_direction: DVec3,
    pub scene: &'a Aabb,
}

/// 1-based line and column of a `[name]` table header.
fn locate_table(text: &str, name: &str) -> Option<(usize, usize)> {
    text.lines().enumerate().find_map(|(i, line)| {
        let t = line.trim_start();
        let rest = t.strip_prefix('[')?;
        let end = rest.find(']')?;
        (rest[..end].trim() == name).then(|| (i + 1, line.len() - t.len() + 1))
    })
}

fn table_error(v: &Validator<'_>, table: PresetName, allowed: String) -> Error {
    let location = match locate_table(v.text, table.as_str()) {
        Some((line, column)) if !v.path.is_empty() => format!("{}:{line}:{column}: ", v.path),
        Some((line, column)) => format!("line {line}, column {column}: "),
        None if !v.path.is_empty() => format!("{}: ", v.path),
        None => String::new(),
    };
    Error::Invalid {
        location,
        key: format!("[{table}]"),
        value: "(engine table)".to_string(),
        allowed,
    }
}

/// Resolves the preset of a config: picks it (flag over file), checks the engine tables, applies
/// defaults and `[shadow]` overrides, validates every knob, and writes the effective values into
/// `shadow` (cascades, resolution, max_distance, lambda, fit family, snap, no scene clipping).
/// Leaves `shadow` untouched when no preset is selected.
pub fn resolve(cx: ResolveContext<'_>, shadow: &mut ShadowSettings, v: &Validator<'_>) -> Result<()> {
    let name = match (&cx.choice.name, &cx.file_preset) {
        (Some(p), _) => Some(*p),
        (None, Some(s)) => Some(
            PresetName::parse(s)
                .ok_or_else(|| v.invalid("shadow.preset", format!("{s:?}"), &unknown_name_message(s)))?,
        ),
        (None, None) => None,
    };
    for table in cx.tables.present() {
        if Some(table) == name || cx.choice.also_allowed.contains(&table) {
            continue;
        }
        let allowed = match name {
            None => format!(
                "an engine table only takes effect with its preset: add shadow.preset = \"{table}\" (or --preset {table}), or remove the table"
            ),
            Some(p) => {
                let from = if cx.choice.name.is_some() {
                    "selected with --preset"
                } else {
                    "selected by shadow.preset"
                };
                format!("the preset is \"{p}\" ({from}), so [{table}] would have no effect: remove it or select the \"{table}\" preset")
            }
        };
        return Err(table_error(v, table, allowed));
    }
    let Some(name) = name else {
        return Ok(());
    };
    let mut notes = Vec::new();
    let w = if cx.choice.engine_defaults {
        Written {
            max_distance: false,
            cascades: false,
            resolution: false,
            ..cx.written
        }
    } else {
        cx.written
    };
    for (written, key, what) in [
        (w.lambda, "shadow.lambda", "the preset's own split rule applies"),
        (w.fit, "shadow.fit", "the preset's own fit applies"),
        (w.snap, "shadow.snap", "the preset's own snapping applies"),
        (
            w.fit_depth_to_scene,
            "shadow.fit_depth_to_scene",
            "the preset does not clip its range to the scene",
        ),
    ] {
        if written {
            notes.push(format!("{key} ignored: {what}"));
        }
    }
    let knobs = resolve_knobs(name, &cx, v)?;
    let d = defaults(&knobs, cx.camera.far);

    // Cascades.
    let mut cascades = d.cascades;
    if w.cascades {
        match counts(&knobs) {
            Counts::Fixed(n) if shadow.cascades != n => notes.push(format!(
                "shadow.cascades = {} ignored: the {name} preset has a fixed {n} cascades",
                shadow.cascades
            )),
            Counts::Fixed(_) => {}
            Counts::Clamped(lo, hi) => {
                cascades = shadow.cascades.clamp(lo, hi);
                if cascades != shadow.cascades {
                    notes.push(format!(
                        "shadow.cascades = {} clamped to {cascades} as the engine does ({lo}..={hi})",
                        shadow.cascades
                    ));
                }
            }
            Counts::Allowed(list) => {
                if !list.contains(&shadow.cascades) {
                    return Err(v.invalid(
                        "shadow.cascades",
                        shadow.cascades,
                        &format!(
                            "one of {} for the {name} preset{}",
                            join(&list),
                            if cx.choice.also_allowed.is_empty() {
                                ""
                            } else {
                                " (compare --defaults runs every preset at its own defaults)"
                            }
                        ),
                    ));
                }
                cascades = shadow.cascades;
            }
        }
    }
    // Map size.
    let mut resolution = default_resolution(&knobs, cascades);
    if w.resolution {
        resolution = shadow.resolution;
        if power_of_two_maps(name) && !resolution.is_power_of_two() {
            return Err(v.invalid(
                "shadow.resolution",
                resolution,
                &format!("a power of two for the {name} preset (the engine requires it)"),
            ));
        }
    }
    // Shadow distance.
    let mut max_distance = d.max_distance;
    if w.max_distance {
        if has_distance(name) {
            max_distance = shadow.max_distance;
        } else {
            notes.push(format!(
                "shadow.max_distance = {} ignored: the {name} preset has no shadow distance (it uses camera.far)",
                shadow.max_distance
            ));
        }
    }
    if name == PresetName::Threejs {
        if let Knobs::Threejs(k) = &knobs {
            notes.extend(threejs_falsy_notes(&cx.tables, k));
        }
    }

    if let Knobs::Bevy(b) = &knobs {
        check_bevy(b, cascades, max_distance, v)?;
    }
    // The layout must be a proper set of cascades.
    let lay = layout(&knobs, cascades, max_distance, cx.camera.near, cx.camera.far);
    for (i, &(a, b)) in lay.fitted.iter().enumerate() {
        if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a) {
            return Err(v.invalid(
                "shadow.preset",
                format!("\"{name}\""),
                &format!(
                    "settings that give every cascade a slice with 0 < near < far; cascade {i} would be [{a}, {b}] (check camera.near/far, shadow.max_distance and [{name}])"
                ),
            ));
        }
    }
    shadow.cascades = lay.fitted.len();
    shadow.resolution = resolution;
    shadow.max_distance = max_distance;
    if let Some(l) = lambda_value(&knobs) {
        shadow.lambda = l;
    }
    shadow.fit = fit_family(&knobs);
    shadow.snap = snaps(&knobs);
    shadow.fit_depth_to_scene = false;
    shadow.preset = Some(Preset { name, knobs, notes });
    Ok(())
}

/// Bevy's builder checks (min < first far bound when N > 1, max > min), plus increasing far
/// bounds (first < max), which the geometric series needs.
fn check_bevy(b: &BevyKnobs, cascades: usize, max_distance: f64, v: &Validator<'_>) -> Result<()> {
    if max_distance <= b.minimum_distance {
        return Err(v.invalid(
            "shadow.max_distance",
            max_distance,
            &format!(
                "a number greater than bevy.minimum_distance ({}) for the bevy preset",
                b.minimum_distance
            ),
        ));
    }
    if cascades > 1 && !(b.minimum_distance < b.first_cascade_far_bound && b.first_cascade_far_bound < max_distance) {
        return Err(v.invalid(
            "bevy.first_cascade_far_bound",
            b.first_cascade_far_bound,
            &format!(
                "a number between bevy.minimum_distance ({}) and the maximum distance ({max_distance}) when there is more than one cascade",
                b.minimum_distance
            ),
        ));
    }
    Ok(())
}

/// Notes every preset gets alike (csm-lab's own `[shadow]` settings it ignores); reports that
/// list several presets say this once instead.
pub fn is_generic_note(note: &str) -> bool {
    [
        "shadow.lambda ",
        "shadow.fit ",
        "shadow.snap ",
        "shadow.fit_depth_to_scene ",
    ]
    .iter()
    .any(|k| note.starts_with(k))
}

fn join(list: &[usize]) -> String {
    list.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ")
}

/// three.js replaces falsy constructor values (0) by its defaults: say so when it happened.
fn threejs_falsy_notes(tables: &RawTables, k: &ThreejsKnobs) -> Vec<String> {
    let Some(t) = &tables.threejs else {
        return Vec::new();
    };
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

fn check_range(v: &Validator<'_>, key: &str, x: f64, lo: f64, hi: f64, lo_open: bool, hi_open: bool) -> Result<f64> {
    let x = v.finite(key, x)?;
    let ok_lo = if lo_open { x > lo } else { x >= lo };
    let ok_hi = if hi_open { x < hi } else { x <= hi };
    if ok_lo && ok_hi {
        Ok(x)
    } else {
        let l = if lo_open { "(" } else { "[" };
        let h = if hi_open { ")" } else { "]" };
        let hi_text = if hi.is_infinite() {
            "inf".to_string()
        } else {
            hi.to_string()
        };
        Err(v.invalid(key, x, &format!("a number in {l}{lo}, {hi_text}{h}")))
    }
}

fn positive(v: &Validator<'_>, key: &str, x: f64) -> Result<f64> {
    check_range(v, key, x, 0.0, f64::INFINITY, true, true)
}

/// Fractions strictly increasing inside (0, 1), `len` of them.
fn fractions<const N: usize>(v: &Validator<'_>, key: &str, x: &[f64]) -> Result<[f64; N]> {
    let ok =
        x.len() == N && x.iter().all(|f| f.is_finite() && *f > 0.0 && *f < 1.0) && x.windows(2).all(|w| w[0] < w[1]);
    if ok {
        Ok(std::array::from_fn(|i| x[i]))
    } else {
        Err(v.invalid(
            key,
            format!("{x:?}"),
            &format!("{N} increasing fractions strictly between 0 and 1"),
        ))
    }
}

fn vec3(v: &Validator<'_>, key: &str, x: Option<[f64; 3]>, default: DVec3) -> Result<DVec3> {
    match x {
        Some(a) => v.vec3(key, a),
        None => Ok(default),
    }
}

/// Half the extent of a box along a unit direction (its support function about the centre).
fn half_extent_along(scene: &Aabb, dir: DVec3) -> f64 {
    let h = 0.5 * (scene.max - scene.min);
    h.x * dir.x.abs() + h.y * dir.y.abs() + h.z * dir.z.abs()
}

fn resolve_knobs(name: PresetName, cx: &ResolveContext<'_>, v: &Validator<'_>) -> Result<Knobs> {
    let t = &cx.tables;
    let centre = 0.5 * (cx.scene.min + cx.scene.max);
    let l = cx.light_direction;
    Ok(match name {
        PresetName::Dart => {
            let r = t.dart.as_ref();
            let lambda = r.and_then(|r| r.lambda).unwrap_or(0.5);
            Knobs::Dart(DartKnobs {
                lambda: check_range(v, "dart.lambda", lambda, 0.0, 1.0, false, false)?,
            })
        }
        PresetName::Threejs => {
            let r = t.threejs.as_ref();
            // three.js falls back to the default for any falsy value, 0 included.
            let falsy = |x: Option<f64>, d: f64| x.filter(|x| *x != 0.0).unwrap_or(d);
            let light_margin = falsy(r.and_then(|r| r.light_margin), 200.0);
            let light_near = falsy(r.and_then(|r| r.light_near), 1.0);
            let light_far = falsy(r.and_then(|r| r.light_far), 2000.0);
            let light_margin = check_range(v, "threejs.light_margin", light_margin, 0.0, f64::INFINITY, false, true)?;
            let light_near = v.finite("threejs.light_near", light_near)?;
            let light_far = v.finite("threejs.light_far", light_far)?;
            if light_far <= light_near {
                return Err(v.invalid(
                    "threejs.light_far",
                    light_far,
                    &format!("a number greater than threejs.light_near ({light_near})"),
                ));
            }
            Knobs::Threejs(ThreejsKnobs {
                mode: r.and_then(|r| r.mode).unwrap_or(ThreejsMode::Practical),
                light_margin,
                light_near,
                light_far,
            })
        }
        PresetName::UnitySample => Knobs::UnitySample(UnitySampleKnobs {
            centre_on_slice: t.unity_sample.as_ref().and_then(|r| r.centre_on_slice).unwrap_or(false),
        }),
        PresetName::Eevee => {
            let r = t.eevee.as_ref();
            let cascade_exponent = r.and_then(|r| r.cascade_exponent).unwrap_or(0.8);
            let cascade_exponent = check_range(v, "eevee.cascade_exponent", cascade_exponent, 0.0, 1.0, false, false)?;
            let fade = check_range(
                v,
                "eevee.fade",
                r.and_then(|r| r.fade).unwrap_or(0.1),
                0.0,
                1.0,
                false,
                false,
            )?;
            let clip_start = r.and_then(|r| r.clip_start).unwrap_or(0.05);
            let clip_start = check_range(v, "eevee.clip_start", clip_start, 0.0, f64::INFINITY, false, true)?;
            let clip_end = v.finite("eevee.clip_end", r.and_then(|r| r.clip_end).unwrap_or(40.0))?;
            if clip_end <= clip_start {
                return Err(v.invalid(
                    "eevee.clip_end",
                    clip_end,
                    &format!("a number greater than eevee.clip_start ({clip_start})"),
                ));
            }
            // Default lamp: up-sun of the scene, so the scene's point nearest the light sits
            // exactly at clip_start (the best a user can place a lamp for this clip range).
            let default = centre - l * (half_extent_along(cx.scene, l) + clip_start);
            Knobs::Eevee(EeveeKnobs {
                cascade_exponent,
                fade,
                lamp_position: vec3(v, "eevee.lamp_position", r.and_then(|r| r.lamp_position), default)?,
                clip_start,
                clip_end,
            })
        }
        PresetName::LearnOpenGl => {
            let r = t.learnopengl.as_ref();
            let planes = r
                .and_then(|r| r.planes.clone())
                .unwrap_or_else(|| vec![5.0, 15.0, 30.0, 100.0]);
            let ok = planes.len() >= 2
                && planes.len() <= 17
                && planes.iter().all(|p| p.is_finite() && *p > 0.0)
                && planes.windows(2).all(|w| w[0] < w[1]);
            if !ok {
                return Err(v.invalid(
                    "learnopengl.planes",
                    format!("{planes:?}"),
                    "2 to 17 increasing positive view depths (cascade i spans planes[i]..planes[i+1])",
                ));
            }
            let pad_xy = check_range(
                v,
                "learnopengl.pad_xy",
                r.and_then(|r| r.pad_xy).unwrap_or(2.0),
                0.0,
                f64::INFINITY,
                false,
                true,
            )?;
            let pad_z = check_range(
                v,
                "learnopengl.pad_z",
                r.and_then(|r| r.pad_z).unwrap_or(10.0),
                0.0,
                f64::INFINITY,
                false,
                true,
            )?;
            // Default light: up-sun of the scene centre at half the scene's diagonal, so the
            // direction to the scene centre is the configured light direction.
            let dist = (0.5 * (cx.scene.max - cx.scene.min).length()).max(1.0);
            let light_position = vec3(
                v,
                "learnopengl.light_position",
                r.and_then(|r| r.light_position),
                centre - l * dist,
            )?;
            Knobs::LearnOpenGl(LearnOpenGlKnobs {
                planes,
                pad_xy,
                pad_z,
                light_position,
            })
        }
        PresetName::Bevy => {
            let r = t.bevy.as_ref();
            let min = r.and_then(|r| r.minimum_distance).unwrap_or(0.1);
            let minimum_distance = check_range(v, "bevy.minimum_distance", min, 0.0, f64::INFINITY, false, true)?;
            let first = r.and_then(|r| r.first_cascade_far_bound).unwrap_or(10.0);
            let first_cascade_far_bound = positive(v, "bevy.first_cascade_far_bound", first)?;
            let overlap = r.and_then(|r| r.overlap_proportion).unwrap_or(0.2);
            let overlap_proportion = check_range(v, "bevy.overlap_proportion", overlap, 0.0, 1.0, false, true)?;
            Knobs::Bevy(BevyKnobs {
                minimum_distance,
                first_cascade_far_bound,
                overlap_proportion,
            })
        }
        PresetName::Godot => {
            let r = t.godot.as_ref();
            let splits = match r.and_then(|r| r.splits.clone()) {
                Some(s) => fractions::<3>(v, "godot.splits", &s)?,
                None => [0.1, 0.2, 0.5],
            };
            let pancake = r.and_then(|r| r.pancake_size).unwrap_or(20.0);
            Knobs::Godot(GodotKnobs {
                splits,
                blend_splits: r.and_then(|r| r.blend_splits).unwrap_or(false),
                pancake_size: check_range(v, "godot.pancake_size", pancake, 0.0, f64::INFINITY, false, true)?,
            })
        }
        PresetName::Unreal => {
            let r = t.unreal.as_ref();
            let e = r.and_then(|r| r.cascade_distribution_exponent).unwrap_or(3.0);
            let tr = r.and_then(|r| r.transition_fraction).unwrap_or(0.1);
            Knobs::Unreal(UnrealKnobs {
                cascade_distribution_exponent: check_range(
                    v,
                    "unreal.cascade_distribution_exponent",
                    e,
                    0.1,
                    10.0,
                    false,
                    false,
                )?,
                transition_fraction: check_range(v, "unreal.transition_fraction", tr, 0.0, 0.3, false, false)?,
            })
        }
        PresetName::Unity => {
            let r = t.unity.as_ref();
            let s2 = r.and_then(|r| r.cascade2_split).unwrap_or(1.0 / 3.0);
            Knobs::Unity(UnityKnobs {
                cascade2_split: check_range(v, "unity.cascade2_split", s2, 0.0, 1.0, true, true)?,
                cascade4_split: match r.and_then(|r| r.cascade4_split.clone()) {
                    Some(s) => fractions::<3>(v, "unity.cascade4_split", &s)?,
                    None => [0.067, 0.2, 0.467],
                },
            })
        }
        PresetName::UnityUrp => {
            let r = t.unity_urp.as_ref();
            let s2 = r.and_then(|r| r.cascade2_split).unwrap_or(0.25);
            Knobs::UnityUrp(UnityUrpKnobs {
                cascade2_split: check_range(v, "unity-urp.cascade2_split", s2, 0.0, 1.0, true, true)?,
                cascade3_split: match r.and_then(|r| r.cascade3_split.clone()) {
                    Some(s) => fractions::<2>(v, "unity-urp.cascade3_split", &s)?,
                    None => [0.1, 0.3],
                },
                cascade4_split: match r.and_then(|r| r.cascade4_split.clone()) {
                    Some(s) => fractions::<3>(v, "unity-urp.cascade4_split", &s)?,
                    None => [0.067, 0.2, 0.467],
                },
            })
        }
        PresetName::Filament => {
            let r = t.filament.as_ref();
            let lambda = r.and_then(|r| r.lambda).unwrap_or(0.5);
            Knobs::Filament(FilamentKnobs {
                split_mode: r.and_then(|r| r.split_mode).unwrap_or(FilamentSplit::Positions),
                lambda: check_range(v, "filament.lambda", lambda, 0.0, 1.0, false, false)?,
                split_positions: match r.and_then(|r| r.split_positions.clone()) {
                    Some(s) => fractions::<3>(v, "filament.split_positions", &s)?,
                    None => [0.125, 0.25, 0.5],
                },
            })
        }
    })
}

// ---------------------------------------------------------------------------------------------
// Defaults and axes
// ---------------------------------------------------------------------------------------------

struct Defaults {
    cascades: usize,
    max_distance: f64,
}

fn defaults(k: &Knobs, camera_far: f64) -> Defaults {
    let (cascades, max_distance) = match k {
        Knobs::Dart(_) => (4, camera_far),
        Knobs::Threejs(_) => (3, 1e5),
        Knobs::UnitySample(_) => (4, camera_far),
        Knobs::Eevee(_) => (4, 200.0),
        Knobs::LearnOpenGl(l) => (l.planes.len() - 1, camera_far),
        Knobs::Bevy(_) => (4, 150.0),
        Knobs::Godot(_) => (4, 100.0),
        Knobs::Unreal(_) => (3, 200.0),
        Knobs::Unity(_) => (4, 150.0),
        Knobs::UnityUrp(_) => (1, 50.0),
        // shadowFar 0 means "use the camera far plane".
        Knobs::Filament(_) => (1, camera_far),
    };
    Defaults { cascades, max_distance }
}

/// Map size per cascade when not configured.
fn default_resolution(k: &Knobs, cascades: usize) -> u32 {
    match k {
        Knobs::UnitySample(_) | Knobs::Eevee(_) | Knobs::Filament(_) => 1024,
        // URP renders all cascades into one 2048 atlas: 2x2 tiles of 1024 from two cascades on.
        Knobs::UnityUrp(_) if cascades > 1 => 1024,
        _ => 2048,
    }
}

fn power_of_two_maps(name: PresetName) -> bool {
    matches!(name, PresetName::Bevy | PresetName::Filament)
}

fn has_distance(name: PresetName) -> bool {
    !matches!(name, PresetName::UnitySample | PresetName::LearnOpenGl)
}

/// Which cascade counts a preset takes.
#[derive(Debug, Clone, PartialEq)]
pub enum Counts {
    /// Any count in the range; larger or smaller counts are clamped (seed 000) or rejected.
    Clamped(usize, usize),
    /// Only these counts.
    Allowed(Vec<usize>),
    /// Hard-coded by the implementation.
    Fixed(usize),
}

fn counts(k: &Knobs) -> Counts {
    match k {
        Knobs::Dart(_) => Counts::Clamped(1, 4),
        Knobs::Threejs(_) => Counts::Allowed((1..=16).collect()),
        Knobs::UnitySample(_) => Counts::Fixed(4),
        Knobs::Eevee(_) | Knobs::Bevy(_) | Knobs::UnityUrp(_) | Knobs::Filament(_) => Counts::Allowed(vec![1, 2, 3, 4]),
        Knobs::LearnOpenGl(l) => Counts::Fixed(l.planes.len() - 1),
        Knobs::Godot(_) | Knobs::Unity(_) => Counts::Allowed(vec![1, 2, 4]),
        Knobs::Unreal(_) => Counts::Allowed((1..=10).collect()),
    }
}

/// The λ of a preset whose split rule is the practical scheme (λ weighting the log split).
pub fn lambda_value(k: &Knobs) -> Option<f64> {
    match k {
        Knobs::Dart(d) => Some(d.lambda),
        Knobs::Eevee(e) => Some(e.cascade_exponent),
        Knobs::Threejs(t) => Some(match t.mode {
            ThreejsMode::Uniform => 0.0,
            ThreejsMode::Logarithmic => 1.0,
            ThreejsMode::Practical => 0.5,
        }),
        Knobs::Filament(f) => match f.split_mode {
            FilamentSplit::Practical => Some(f.lambda),
            FilamentSplit::Uniform => Some(0.0),
            FilamentSplit::Logarithmic => Some(1.0),
            FilamentSplit::Positions => None,
        },
        _ => None,
    }
}

/// The sweep axes a configuration has (csm-lab's own pipeline or its preset's).
#[derive(Debug, Clone, PartialEq)]
pub struct Axes {
    /// The config key a λ sweep sets (`shadow.lambda`, `dart.lambda`, `eevee.cascade_exponent`,
    /// `filament.lambda`), or None when the split rule has no λ to sweep.
    pub lambda: Option<&'static str>,
    /// Cascade counts a sweep may use.
    pub cascades: Vec<usize>,
    /// Only powers of two are valid map sizes.
    pub resolution_power_of_two: bool,
    /// The fit can be swept (csm-lab's own pipeline only: a preset fixes its fit).
    pub fit: bool,
}

/// The sweep axes of a preset.
pub fn preset_axes(p: &Preset) -> Axes {
    let lambda = match &p.knobs {
        Knobs::Dart(_) => Some("dart.lambda"),
        Knobs::Eevee(_) => Some("eevee.cascade_exponent"),
        Knobs::Filament(f) if f.split_mode == FilamentSplit::Practical => Some("filament.lambda"),
        _ => None,
    };
    let cascades = match counts(&p.knobs) {
        Counts::Clamped(lo, hi) => (lo..=hi).collect(),
        Counts::Allowed(v) => v,
        Counts::Fixed(n) => vec![n],
    };
    Axes {
        lambda,
        cascades,
        resolution_power_of_two: power_of_two_maps(p.name),
        fit: false,
    }
}

/// The sweep axes of a config: its preset's, or csm-lab's own (every axis).
pub fn axes(config: &Config) -> Axes {
    match &config.shadow.preset {
        Some(p) => preset_axes(p),
        None => Axes {
            lambda: Some("shadow.lambda"),
            cascades: (1..=16).collect(),
            resolution_power_of_two: false,
            fit: true,
        },
    }
}

/// Sets λ for a sweep point: `shadow.lambda`, or the preset's λ-like knob.
pub fn set_lambda(config: &mut Config, lambda: f64) -> Result<()> {
    if !(0.0..=1.0).contains(&lambda) {
        return Err(Error::Other(format!("lambda {lambda} is outside [0, 1]")));
    }
    let Some(p) = &mut config.shadow.preset else {
        config.shadow.lambda = lambda;
        return Ok(());
    };
    match &mut p.knobs {
        Knobs::Dart(d) => d.lambda = lambda,
        Knobs::Eevee(e) => e.cascade_exponent = lambda,
        Knobs::Filament(f) if f.split_mode == FilamentSplit::Practical => f.lambda = lambda,
        _ => {
            return Err(Error::Other(format!(
                "the {} preset has no λ to sweep ({}); remove the lambda axis",
                p.name,
                split_rule(&p.knobs)
            )))
        }
    }
    config.shadow.lambda = lambda;
    Ok(())
}

/// Sets the cascade count for a sweep point, checking the preset accepts it.
pub fn set_cascades(config: &mut Config, n: usize) -> Result<()> {
    if let Some(p) = &config.shadow.preset {
        let ax = preset_axes(p);
        if !ax.cascades.contains(&n) {
            return Err(Error::Other(format!(
                "the {} preset does not take {n} cascades (valid: {})",
                p.name,
                join(&ax.cascades)
            )));
        }
    } else if !(1..=16).contains(&n) {
        return Err(Error::Other(format!("{n} cascades is outside 1..=16")));
    }
    config.shadow.cascades = n;
    Ok(())
}

/// Sets the map size for a sweep point, checking the preset accepts it.
pub fn set_resolution(config: &mut Config, n: u32) -> Result<()> {
    if !(16..=16384).contains(&n) {
        return Err(Error::Other(format!("resolution {n} is outside 16..=16384")));
    }
    if let Some(p) = &config.shadow.preset {
        if power_of_two_maps(p.name) && !n.is_power_of_two() {
            return Err(Error::Other(format!(
                "the {} preset takes power-of-two map sizes only, not {n}",
                p.name
            )));
        }
    }
    config.shadow.resolution = n;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Layout: fitted slices and selection boundaries
// ---------------------------------------------------------------------------------------------

/// Where a preset's cascades are, before the camera's planes clip the selection.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Fitted slices, near to far: what each window is built around.
    pub fitted: Vec<(f64, f64)>,
    /// Selection boundaries (one more than cascades): cascade `i` serves view depths
    /// `[selection[i], selection[i+1])`; ±infinity where the engine has no bound.
    pub selection: Vec<f64>,
}

impl Layout {
    /// Consecutive boundaries as both fitted slices and selection.
    pub fn contiguous(splits: Vec<f64>) -> Layout {
        Layout {
            fitted: splits.windows(2).map(|w| (w[0], w[1])).collect(),
            selection: splits,
        }
    }
}

/// Practical split exactly as seed 000 writes it: the last boundary also from the formula.
pub fn dart_splits(near: f64, far: f64, cascades: usize, lambda: f64) -> Vec<f64> {
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

/// Bevy far bounds: `first·(max/first)^(i/(N−1))`, or just `max` for one cascade.
pub fn bevy_far_bounds(cascades: usize, first: f64, max: f64) -> Vec<f64> {
    if cascades == 1 {
        return vec![max];
    }
    (0..cascades)
        .map(|i| first * (max / first).powf(i as f64 / (cascades - 1) as f64))
        .collect()
}

/// EEVEE 2017 split ends and (fade-overlapped) starts on `[start, end]`.
pub fn eevee_starts_ends(start: f64, end: f64, cascades: usize, lambda: f64, fade: f64) -> (Vec<f64>, Vec<f64>) {
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

/// Unreal split distances: `near + (Σ_{k<i} e^k / Σ_{k<N} e^k)·(distance − near)`.
pub fn unreal_splits(cascades: usize, exponent: f64, near: f64, distance: f64) -> Vec<f64> {
    let total: f64 = (0..cascades).map(|k| exponent.powi(k as i32)).sum();
    let mut acc = 0.0;
    let mut out = vec![near];
    for i in 1..cascades {
        acc += exponent.powi(i as i32 - 1);
        out.push(near + acc / total * (distance - near));
    }
    out.push(distance);
    out
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

/// The fitted slices and selection boundaries of a preset. `max_distance` is the engine's
/// shadow distance (unused by presets without one); `near`/`far` are the camera planes.
pub fn layout(knobs: &Knobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
    let inf = f64::INFINITY;
    match knobs {
        Knobs::Dart(d) => Layout::contiguous(dart_splits(near, max_distance, cascades, d.lambda)),
        Knobs::Threejs(t) => {
            let f = far.min(max_distance);
            let b = threejs_breaks(t.mode, cascades, near, f);
            // r185: cascade i spans [b_{i-1} F, b_i F], the first starting at the near plane;
            // the WebGL shader selects on [b_{i-1} (F - n), b_i (F - n)).
            let fitted = (0..cascades)
                .map(|i| (if i == 0 { near } else { b[i - 1] * f }, b[i] * f))
                .collect();
            let mut selection = vec![-inf];
            selection.extend(b.iter().map(|x| x * (f - near)));
            Layout { fitted, selection }
        }
        Knobs::UnitySample(_) => {
            // Accumulated in the seed's own order (far * p + ... + near).
            let (n, f) = (near, far);
            let e = [
                f * 0.067 + n,
                f * 0.133 + f * 0.067 + n,
                f * 0.267 + f * 0.133 + f * 0.067 + n,
            ];
            Layout::contiguous(vec![n, e[0], e[1], e[2], f])
        }
        Knobs::Eevee(e) => {
            let end = near.max(far.min(max_distance));
            let (starts, ends) = eevee_starts_ends(near, end, cascades, e.cascade_exponent, e.fade);
            // In the fade band [start_c, end_{c-1}] both cascades are read: the coarser (c)
            // counts for selection.
            let mut selection = starts.clone();
            selection.push(end);
            Layout {
                fitted: starts.into_iter().zip(ends).collect(),
                selection,
            }
        }
        Knobs::LearnOpenGl(l) => {
            let p = &l.planes;
            let m = p.len() - 1;
            // index = #(planes[0..m] below the depth), clamped to m - 1: depth <= p0 reads
            // cascade 0 (slice [p0, p1]), (p0, p1] reads cascade 1, ..., beyond p_{m-2} the last.
            let mut selection = vec![-inf];
            selection.extend_from_slice(&p[..m - 1]);
            selection.push(inf);
            Layout {
                fitted: p.windows(2).map(|w| (w[0], w[1])).collect(),
                selection,
            }
        }
        Knobs::Bevy(b) => {
            let fars = bevy_far_bounds(cascades, b.first_cascade_far_bound, max_distance);
            let nears: Vec<f64> = (0..cascades)
                .map(|i| {
                    if i == 0 {
                        b.minimum_distance
                    } else {
                        (1.0 - b.overlap_proportion) * fars[i - 1]
                    }
                })
                .collect();
            // Cascade 0 serves everything nearer than its far bound; in the blend band
            // [(1 - p) far_i, far_i] the coarser cascade i + 1 counts; nothing beyond the last.
            let mut selection = vec![-inf];
            selection.extend_from_slice(&nears[1..]);
            selection.push(fars[cascades - 1]);
            Layout {
                fitted: nears.into_iter().zip(fars).collect(),
                selection,
            }
        }
        Knobs::Godot(g) => {
            let max_d = far.min(max_distance).max(near + 0.001);
            let min_d = near.min(max_d);
            let used: &[f64] = match cascades {
                1 => &[],
                2 => &g.splits[..1],
                _ => &g.splits[..],
            };
            let mut d = vec![min_d];
            d.extend(used.iter().map(|s| min_d + s * (max_d - min_d)));
            d.push(max_d);
            if g.blend_splits {
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
        Knobs::Unreal(u) => {
            let s = unreal_splits(cascades, u.cascade_distribution_exponent, near, max_distance);
            let m = cascades;
            let fitted = (0..m)
                .map(|i| {
                    let (a, b) = (s[i], s[i + 1]);
                    // Every far end but the last is extended by the transition band.
                    let ext = if i + 1 < m {
                        (b - a) * u.transition_fraction
                    } else {
                        0.0
                    };
                    (a, b + ext)
                })
                .collect();
            Layout { fitted, selection: s }
        }
        Knobs::Unity(u) => {
            let dist = far.min(max_distance);
            let fr: &[f64] = match cascades {
                1 => &[],
                2 => std::slice::from_ref(&u.cascade2_split),
                _ => &u.cascade4_split[..],
            };
            Layout::contiguous(fraction_splits(near, dist, fr))
        }
        Knobs::UnityUrp(u) => {
            let dist = far.min(max_distance);
            let fr: &[f64] = match cascades {
                1 => &[],
                2 => std::slice::from_ref(&u.cascade2_split),
                3 => &u.cascade3_split[..],
                _ => &u.cascade4_split[..],
            };
            Layout::contiguous(fraction_splits(near, dist, fr))
        }
        Knobs::Filament(k) => {
            let f = max_distance;
            let p = filament_positions(k, cascades, near, f);
            let mut s = vec![near];
            s.extend(p.iter().map(|p| near + (f - near) * p));
            s.push(f);
            Layout::contiguous(s)
        }
    }
}

/// Unity's cascade boundaries: fractions of the shadow distance measured from the eye, the
/// first cascade starting at the near plane.
fn fraction_splits(near: f64, distance: f64, fractions: &[f64]) -> Vec<f64> {
    let mut s = vec![near];
    s.extend(fractions.iter().map(|f| f * distance));
    s.push(distance);
    s
}

/// Clips selection boundaries to the visible depths `[near, far]`, keeping them
/// non-decreasing; None when no visible depth reads any cascade.
pub fn clip_selection(selection: &[f64], near: f64, far: f64) -> Option<Vec<f64>> {
    let lo = near.max(selection[0]);
    let hi = far.min(selection[selection.len() - 1]);
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let mut out = Vec::with_capacity(selection.len());
    out.push(lo);
    let mut prev = lo;
    for s in &selection[1..selection.len() - 1] {
        prev = s.clamp(lo, hi).max(prev);
        out.push(prev);
    }
    out.push(hi);
    Some(out)
}

// ---------------------------------------------------------------------------------------------
// Fits, snapping, light depth: the scheme of a preset
// ---------------------------------------------------------------------------------------------

/// Unreal's bounding sphere of a slice: centre depth `far − offset` clamped to the slice, with
/// `offset = (Db² − Da²)/(2L) + L/2`, radius the largest corner distance, at least 1 cm.
pub fn unreal_sphere(near: f64, far: f64, lens: &Lens) -> Sphere {
    let da2 = (lens.tan_h * far).powi(2) + (lens.tan_v * far).powi(2);
    let db2 = (lens.tan_h * near).powi(2) + (lens.tan_v * near).powi(2);
    let l = far - near;
    let offset = (db2 - da2) / (2.0 * l) + 0.5 * l;
    let c = (far - offset).clamp(near, far);
    let r_near = (db2 + (c - near).powi(2)).sqrt();
    let r_far = (da2 + (far - c).powi(2)).sqrt();
    Sphere {
        centre_depth: c,
        radius: r_near.max(r_far).max(0.01),
    }
}

/// Unreal's border per side, in texels (modelled as the 4-texel snap step).
pub const UNREAL_BORDER_TEXELS: f64 = 4.0;

/// Bevy's window side: the slice diameter rounded up to a whole world unit.
pub fn bevy_window_side(near: f64, far: f64, k2: f64) -> f64 {
    slice_diameter(near, far, k2).ceil()
}

/// The family of csm-lab's fits a preset's window belongs to.
fn fit_family(k: &Knobs) -> Fit {
    match k {
        Knobs::UnitySample(_) | Knobs::LearnOpenGl(_) => Fit::Aabb,
        _ => Fit::Sphere,
    }
}

fn snaps(k: &Knobs) -> bool {
    !matches!(k, Knobs::UnitySample(_) | Knobs::LearnOpenGl(_))
}

fn snap_rule(k: &Knobs) -> SnapRule {
    let (mode, step) = match k {
        Knobs::Threejs(_) | Knobs::Bevy(_) => (SnapMode::Floor, 1),
        Knobs::Godot(_) => (SnapMode::Round, 2),
        Knobs::Unreal(_) => (SnapMode::Trunc, 4),
        Knobs::Filament(_) => (SnapMode::Trunc, 2),
        _ => (SnapMode::Round, 1),
    };
    SnapRule {
        mode,
        step_texels: step,
    }
}

/// Builds a preset's rig for a layout. `light` is the configured light basis; `near`/`far`
/// the camera planes. None when no visible depth reads any cascade.
pub fn rig_for_layout(
    knobs: &Knobs,
    lens: Lens,
    light: LightBasis,
    resolution: u32,
    lay: &Layout,
    near: f64,
    far: f64,
) -> Option<Rig> {
    let selection = clip_selection(&lay.selection, near, far)?;
    let k2 = lens.k2();
    let n = resolution as f64;
    let fitted = &lay.fitted;
    let each = |f: &dyn Fn(f64, f64) -> f64| -> Vec<f64> { fitted.iter().map(|&(a, b)| f(a, b)).collect() };
    let spheres = |f: &dyn Fn(f64, f64) -> Sphere| -> Vec<Sphere> { fitted.iter().map(|&(a, b)| f(a, b)).collect() };
    let rule = snap_rule(knobs);
    let axis = |s: &[Sphere]| WindowRule::AxisCentred {
        centre_depth: s.iter().map(|s| s.centre_depth).collect(),
    };
    // A sphere of radius r on `usable` of the map's N texels: window side 2r·N/usable.
    let on = |s: &[Sphere], usable: f64| -> Vec<f64> { s.iter().map(|s| 2.0 * s.radius * n / usable).collect() };
    let (label, window, sides, basis, anchor, depth) = match knobs {
        Knobs::Dart(_) => {
            let s = spheres(&|a, b| corner_average_sphere(a, b, k2));
            (
                "sphere-average",
                axis(&s),
                on(&s, n),
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Scene,
            )
        }
        Knobs::Threejs(t) => (
            "diameter",
            WindowRule::BoxCentred,
            each(&|a, b| slice_diameter(a, b, k2)),
            BasisRule::Fixed,
            DVec2::ZERO,
            LightDepthRule::Margin {
                margin: t.light_margin,
                near: t.light_near,
                far: t.light_far,
            },
        ),
        Knobs::UnitySample(u) => (
            if u.centre_on_slice { "aabb" } else { "aabb-at-origin" },
            if u.centre_on_slice {
                WindowRule::Tight {
                    pad: 0.0,
                    border: false,
                }
            } else {
                WindowRule::TightAtOrigin
            },
            each(&|a, b| 2.0 * minimal_sphere(a, b, k2).radius),
            BasisRule::Fixed,
            DVec2::ZERO,
            LightDepthRule::Slice { keeps_casters: false },
        ),
        Knobs::Eevee(e) => {
            let s = spheres(&|a, b| far_cap_sphere(a, b, k2));
            (
                "sphere-far-cap",
                axis(&s),
                on(&s, n),
                BasisRule::Fixed,
                light.to_light_xy(e.lamp_position),
                LightDepthRule::FromPoint {
                    point: e.lamp_position,
                    near: e.clip_start,
                    far: e.clip_end,
                },
            )
        }
        Knobs::LearnOpenGl(l) => (
            "aabb-padded",
            WindowRule::Tight {
                pad: l.pad_xy,
                border: false,
            },
            each(&|a, b| 2.0 * minimal_sphere(a, b, k2).radius),
            BasisRule::LookAtFrom(l.light_position),
            DVec2::ZERO,
            LightDepthRule::Mirrored {
                eye: l.light_position,
                pad: l.pad_z,
            },
        ),
        Knobs::Bevy(_) => (
            "diameter-ceil",
            WindowRule::BoxCentred,
            each(&|a, b| bevy_window_side(a, b, k2)),
            BasisRule::Fixed,
            DVec2::ZERO,
            LightDepthRule::Slice { keeps_casters: true },
        ),
        Knobs::Godot(g) => {
            let s = spheres(&|a, b| corner_average_sphere(a, b, k2));
            // r·T/(T − 2): one texel of border per side.
            let sides = on(&s, n - 2.0);
            (
                "sphere-average+border",
                axis(&s),
                sides.clone(),
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Sphere {
                    radius: sides.iter().map(|w| 0.5 * w).collect(),
                    toward_light: g.pancake_size,
                    min_half: 0.0,
                },
            )
        }
        Knobs::Unreal(_) => {
            let s = spheres(&|a, b| unreal_sphere(a, b, &lens));
            (
                "sphere-minimal+border",
                axis(&s),
                on(&s, n - 2.0 * UNREAL_BORDER_TEXELS),
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Sphere {
                    radius: s.iter().map(|s| s.radius).collect(),
                    toward_light: 0.0,
                    min_half: 50.0,
                },
            )
        }
        Knobs::Unity(_) | Knobs::UnityUrp(_) => {
            let s = spheres(&|a, b| minimal_sphere(a, b, k2));
            let sides = s
                .iter()
                .map(|s| Window::side_with_border(2.0 * s.radius, resolution, rule.max_shift_texels()))
                .collect();
            (
                "sphere",
                axis(&s),
                sides,
                BasisRule::Fixed,
                DVec2::ZERO,
                LightDepthRule::Scene,
            )
        }
        Knobs::Filament(_) => {
            let s = spheres(&|a, b| corner_average_sphere(a, b, k2));
            (
                "sphere-average+border",
                axis(&s),
                // mapSize − 2 usable texels: one texel of border per side.
                on(&s, n - 2.0),
                BasisRule::CameraRight,
                DVec2::ZERO,
                LightDepthRule::Scene,
            )
        }
    };
    Some(Rig::with_scheme(
        lens,
        light,
        fit_family(knobs),
        resolution,
        rule,
        selection,
        fitted,
        sides,
        Scheme {
            fit_label: label.to_string(),
            basis,
            window,
            snaps: snaps(knobs),
            snap_anchor: anchor,
            depth,
        },
    ))
}

/// The rig of a config whose preset is `preset`, or None when no visible depth reads a cascade.
pub fn rig(config: &Config, preset: &Preset) -> Option<Rig> {
    let s = &config.shadow;
    let cam = &config.camera;
    let lay = layout(&preset.knobs, s.cascades, s.max_distance, cam.near, cam.far);
    let lens = Lens::new(cam.fov_y(), config.screen.aspect());
    rig_for_layout(
        &preset.knobs,
        lens,
        LightBasis::new(config.light_direction),
        s.resolution,
        &lay,
        cam.near,
        cam.far,
    )
}

// ---------------------------------------------------------------------------------------------
// Descriptions and the per-analysis report
// ---------------------------------------------------------------------------------------------

/// The split rule in words.
pub fn split_rule(k: &Knobs) -> String {
    match k {
        Knobs::Dart(d) => format!("practical, λ {} on [near, max_distance], 1..4 cascades", d.lambda),
        Knobs::Threejs(t) => match t.mode {
            ThreejsMode::Practical => "practical, λ fixed at 0.5, breaks of min(far, maxFar) (r185)".to_string(),
            ThreejsMode::Uniform => "uniform breaks of min(far, maxFar) (r185)".to_string(),
            ThreejsMode::Logarithmic => "logarithmic breaks of min(far, maxFar) (r185)".to_string(),
        },
        Knobs::UnitySample(_) => "near + {0.067, 0.2, 0.467}·far, 4 cascades".to_string(),
        Knobs::Eevee(e) => format!(
            "practical, λ {} on [near, min(far, max_distance)], fade {} overlap",
            e.cascade_exponent, e.fade
        ),
        Knobs::LearnOpenGl(l) => format!("fixed planes {:?}, off-by-one selection", l.planes),
        Knobs::Bevy(b) => format!(
            "geometric from {} to max_distance, cascade 0 from {}, overlap {}",
            b.first_cascade_far_bound, b.minimum_distance, b.overlap_proportion
        ),
        Knobs::Godot(g) => format!(
            "fractions {:?} of [near, min(far, max_distance)]{}",
            g.splits,
            if g.blend_splits { ", blend_splits" } else { "" }
        ),
        Knobs::Unreal(u) => format!(
            "geometric weights, exponent {}, transition {}",
            u.cascade_distribution_exponent, u.transition_fraction
        ),
        Knobs::Unity(u) => format!(
            "fractions of the shadow distance (2: {:.3}; 4: {:?})",
            u.cascade2_split, u.cascade4_split
        ),
        Knobs::UnityUrp(u) => format!(
            "fractions of the shadow distance (2: {}; 3: {:?}; 4: {:?})",
            u.cascade2_split, u.cascade3_split, u.cascade4_split
        ),
        Knobs::Filament(f) => match f.split_mode {
            FilamentSplit::Positions => format!("positions {:?} of [near, shadowFar or far]", f.split_positions),
            FilamentSplit::Uniform => "uniform helper on [near, shadowFar or far]".to_string(),
            FilamentSplit::Logarithmic => "logarithmic helper on [near, shadowFar or far]".to_string(),
            FilamentSplit::Practical => format!("practical helper, λ {}", f.lambda),
        },
    }
}

/// The snapping rule in words.
pub fn snap_description(k: &Knobs) -> String {
    if !snaps(k) {
        return "none".to_string();
    }
    let r = snap_rule(k);
    let mode = match r.mode {
        SnapMode::Round => "round",
        SnapMode::Floor => "floor",
        SnapMode::Trunc => "fmod (toward zero)",
    };
    let unit = if r.step_texels == 1 { "texel" } else { "texels" };
    let anchor = match k {
        Knobs::Eevee(_) => "grid through the lamp position",
        Knobs::Filament(_) => "world origin, basis turns with the camera",
        _ => "world origin",
    };
    format!("{mode}, {} {unit}, {anchor}", r.step_texels)
}

/// The light depth rule in words.
pub fn light_depth_description(k: &Knobs) -> String {
    match k {
        Knobs::Dart(_) => "not shown in the seed: modelled as fitted to the scene".to_string(),
        Knobs::Threejs(t) => format!(
            "fixed {} to {} from a light {} in front of the slice",
            t.light_near, t.light_far, t.light_margin
        ),
        Knobs::UnitySample(_) => "slice's own z extent; casters in front are lost".to_string(),
        Knobs::Eevee(e) => format!("lamp clip {} to {}", e.clip_start, e.clip_end),
        Knobs::LearnOpenGl(l) => format!("mirrored: light-view z ± {} passed as distances", l.pad_z),
        Knobs::Bevy(_) => "slice's own z extent; casters kept (unclipped depth)".to_string(),
        Knobs::Godot(g) => format!("sphere ± r, {} toward the light; casters pancaked", g.pancake_size),
        Knobs::Unreal(_) => "sphere ± max(r, 50 m); casters kept".to_string(),
        Knobs::Unity(_) | Knobs::UnityUrp(_) => "engine side: modelled as fitted to the scene".to_string(),
        Knobs::Filament(_) => "from receiver and caster bounds".to_string(),
    }
}

/// What an analysis reports about a preset (in `summary.json` and `compare`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PresetReport {
    pub name: PresetName,
    pub source: &'static str,
    pub split_rule: String,
    pub fit: String,
    pub snap: String,
    pub light_depth_rule: String,
    pub knobs: Knobs,
    /// Per cascade: the fitted slice `[near, far]`.
    pub fitted: Vec<[f64; 2]>,
    /// Per cascade: the view depths that read it (after clipping to the camera's planes).
    pub selection: Vec<[f64; 2]>,
    /// Per cascade, for the configured camera: the rendered light depth range and what falls
    /// outside it.
    pub light_depth: Vec<LightDepth>,
    /// Largest over cascades of the receiver depth outside the light depth range (world units).
    pub receivers_outside_depth: f64,
    /// Largest over cascades of the caster depth lost in front of the light depth range.
    pub casters_outside_depth: f64,
    pub notes: Vec<String>,
}

/// The report of a preset for the configured camera (frame 0), with `depths` computed from
/// the windows of that frame ([`Rig::light_depth`]).
pub fn report(preset: &Preset, rig: Option<&Rig>, depths: Vec<LightDepth>) -> PresetReport {
    let (fitted, selection, fit) = match rig {
        Some(r) => (
            r.slices.iter().map(|s| [s.near, s.far]).collect(),
            (0..r.cascade_count()).map(|i| [r.splits[i], r.splits[i + 1]]).collect(),
            r.scheme.fit_label.clone(),
        ),
        None => (Vec::new(), Vec::new(), String::new()),
    };
    let max = |f: &dyn Fn(&LightDepth) -> f64| depths.iter().map(f).fold(0.0, f64::max);
    PresetReport {
        name: preset.name,
        source: preset.name.source(),
        split_rule: split_rule(&preset.knobs),
        fit,
        snap: snap_description(&preset.knobs),
        light_depth_rule: light_depth_description(&preset.knobs),
        knobs: preset.knobs.clone(),
        fitted,
        selection,
        receivers_outside_depth: max(&|d| d.receivers_outside),
        casters_outside_depth: max(&|d| d.casters_outside),
        light_depth: depths,
        notes: preset.notes.clone(),
    }
}

/// Light depth of every cascade for one camera frame, with the configured snap mode.
pub fn light_depths(rig: &Rig, lp: &LightPose, snapped: bool, scene: &Aabb) -> Vec<LightDepth> {
    (0..rig.cascade_count())
        .map(|i| rig.light_depth(i, lp, &rig.window(i, lp, snapped), scene))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_names_and_list_parsing() {
        assert_eq!(closest_name("bevvy"), PresetName::Bevy);
        assert_eq!(closest_name("unity_urp"), PresetName::UnityUrp);
        assert_eq!(closest_name("three"), PresetName::Threejs);
        assert_eq!(
            parse_list("--presets", "bevy, godot").unwrap(),
            vec![PresetName::Bevy, PresetName::Godot]
        );
        let e = parse_list("--presets", "bevy,gdot").unwrap_err().to_string();
        assert!(
            e.contains("--presets") && e.contains("\"godot\"") && e.contains("unity-urp"),
            "{e}"
        );
        assert!(parse_list("--presets", "bevy,bevy").is_err());
        assert!(parse_list("--presets", "bevy,").is_err());
        for p in PresetName::ALL {
            assert_eq!(PresetName::parse(p.as_str()), Some(p));
        }
    }

    #[test]
    fn selection_clipping_keeps_boundaries_ordered_inside_the_camera_range() {
        let s = clip_selection(&[f64::NEG_INFINITY, 5.0, 15.0, f64::INFINITY], 1.0, 150.0).unwrap();
        assert_eq!(s, vec![1.0, 5.0, 15.0, 150.0]);
        let s = clip_selection(&[0.1, 10.0, 50.0, 1000.0], 20.0, 150.0).unwrap();
        assert_eq!(s, vec![20.0, 20.0, 50.0, 150.0]);
        assert!(clip_selection(&[0.1, 10.0, 150.0], 200.0, 300.0).is_none());
    }

    #[test]
    fn unreal_sphere_is_the_minimal_sphere() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for _ in 0..200 {
            let lens = Lens::new(rng.range(0.1, 2.0), rng.range(0.3, 3.0));
            let n = rng.range(0.05, 50.0);
            let f = n * rng.range(1.01, 100.0);
            let u = unreal_sphere(n, f, &lens);
            let m = minimal_sphere(n, f, lens.k2());
            assert!((u.radius - m.radius).abs() <= 1e-9 * m.radius, "{u:?} {m:?}");
            assert!((u.centre_depth - m.centre_depth).abs() <= 1e-9 * f);
        }
    }
}
