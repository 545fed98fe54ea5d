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
//!
//! Parts (all re-exported here): `resolve` (config tables, defaults and overrides), `layout`
//! (split rules: fitted slices and selection boundaries), `scheme` (fits, snapping, light basis
//! and depth: the rig), `report` (descriptions and what an analysis reports), `sweep` (axes for
//! sweeps).

mod layout;
mod report;
mod resolve;
mod scheme;
mod sweep;

pub use layout::*;
pub use report::*;
pub use resolve::*;
pub use scheme::*;
pub use sweep::*;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

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

/// The preset name closest to `s`.
pub fn closest_name(s: &str) -> PresetName {
    let s = s.to_ascii_lowercase();
    PresetName::ALL
        .into_iter()
        .min_by_key(|p| crate::suggest::edit_distance(&s, p.as_str()))
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

// ---------------------------------------------------------------------------------------------
// Defaults and axes
// ---------------------------------------------------------------------------------------------

pub(crate) struct Defaults {
    pub(crate) cascades: usize,
    pub(crate) max_distance: f64,
}

pub(crate) fn defaults(k: &Knobs, camera_far: f64) -> Defaults {
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
pub(crate) fn default_resolution(k: &Knobs, cascades: usize) -> u32 {
    match k {
        Knobs::UnitySample(_) | Knobs::Eevee(_) | Knobs::Filament(_) => 1024,
        // URP renders all cascades into one 2048 atlas: 2x2 tiles of 1024 from two cascades on.
        Knobs::UnityUrp(_) if cascades > 1 => 1024,
        _ => 2048,
    }
}

pub(crate) fn power_of_two_maps(name: PresetName) -> bool {
    matches!(name, PresetName::Bevy | PresetName::Filament)
}

pub(crate) fn has_distance(name: PresetName) -> bool {
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

pub(crate) fn counts(k: &Knobs) -> Counts {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fitting::minimal_sphere;
    use crate::geometry::Lens;

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
