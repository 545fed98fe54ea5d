//! Presets: the whole cascade set-up of a real engine or of a reference implementation, so its
//! windows go through the same metrics as csm-lab's own pipeline.
//!
//! Each engine is one file implementing [`Engine`] (name, source, knob table, defaults, split
//! rule, fit, snapping, light basis, light depth, descriptions); the `engines!` line below is
//! its only other mention. The rules of every engine, and why, are in `docs/presets.md`.
//!
//! Parts: `engine` (the trait and its object-safe form), `shared` (split, fit and validation
//! helpers several engines use), `apply` (choosing a preset and applying it to a validated
//! config), `rig` (the [`csm_core::cascades::Rig`] of a preset), `report` (what an analysis reports
//! about a preset), `sweep` (the axes a sweep may vary), `terms` (a setting written in the
//! engine's own configuration language, and read back) and `closest` (the engine's split
//! knobs matched to csm-lab's cascades).

mod apply;
pub mod bias;
mod closest;
mod engine;
pub mod engines;
mod free_splits;
mod report;
mod rig;
mod shared;
mod sweep;
mod terms;

pub use apply::{apply, PresetChoice};
pub use closest::Target;
pub(crate) use closest::{complete_fractions, fit_split_knob, log_misfit};
pub use engine::{snap, Counts, Described, Engine, Fitting, Knob};
pub(crate) use engine::{DynEngine, EngineScheme, KnobContext, KnobsOf};
pub use engines::{Knobs, PresetName};
pub(crate) use free_splits::free_split_engines;
pub(crate) use free_splits::{
    configured_fractions, drop_stale_bounds, free_split_knob, has_free_splits, preset_fraction_space, set_fractions,
};
pub use free_splits::{engine_setting, paste_lines, Setting};
pub(crate) use report::PresetReport;
pub use report::{report, split_rule};
pub(crate) use rig::light_basis_rule;
pub use rig::{rig, rig_for_layout};
pub(crate) use shared::join;
pub use shared::{around, centre, clip_selection, fractions, layout, ordered, positive, unit, Layout};
pub(crate) use shared::{
    check_range, distance_fractions, half_extent_along, is_generic_note, minimal_sphere_scheme, non_negative, point_or,
};
pub(crate) use sweep::set_distance;
pub use sweep::{axes, check_point, set_cascades, set_knob, set_lambda, set_resolution, Axes};
pub use terms::{apply_terms, number, read, render, Values};
pub(crate) use terms::{engine_of, Dims, Fields, Terms};

use serde::Serialize;

use crate::error::{Error, Result};

// ---------------------------------------------------------------------------------------------
// Names
// ---------------------------------------------------------------------------------------------

impl PresetName {
    /// The name used in configs, on the command line and as the engine table's name.
    pub fn as_str(self) -> &'static str {
        self.engine().name()
    }

    pub fn parse(s: &str) -> Option<PresetName> {
        PresetName::ALL.into_iter().find(|p| p.as_str() == s)
    }

    /// Where the preset's behaviour comes from.
    pub(crate) fn source(self) -> &'static str {
        self.engine().source()
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
pub(crate) fn valid_names() -> String {
    PresetName::ALL.map(|p| p.as_str()).join(", ")
}

/// The preset name closest to `s`.
pub(crate) fn closest_name(s: &str) -> PresetName {
    let s = s.to_ascii_lowercase();
    PresetName::ALL
        .into_iter()
        .min_by_key(|p| crate::suggest::edit_distance(&s, p.as_str()))
        .expect("non-empty")
}

/// "valid presets: ...; did you mean ...?"
pub(crate) fn unknown_name_message(s: &str) -> String {
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
pub(crate) fn parse_list(flag: &str, s: &str) -> Result<Vec<PresetName>> {
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
// A resolved preset
// ---------------------------------------------------------------------------------------------

impl Knobs {
    /// The engine whose knobs these are.
    pub(crate) fn engine(&self) -> &'static dyn DynEngine {
        self.name().engine()
    }

    /// The knobs of engine `E`, if these are its.
    pub fn get<E: KnobsOf>(&self) -> Option<&E::Knobs> {
        E::get(self)
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

impl crate::config::PresetValue for Preset {
    fn clone_value(&self) -> Box<dyn crate::config::PresetValue> {
        Box::new(self.clone())
    }

    fn eq_value(&self, other: &dyn crate::config::PresetValue) -> bool {
        other.as_any().downcast_ref::<Preset>() == Some(self)
    }

    fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self).expect("a preset serialises")
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}

/// Typed access to the preset a config carries.
impl std::ops::Deref for crate::config::AppliedPreset {
    type Target = Preset;

    fn deref(&self) -> &Preset {
        self.downcast_ref().expect("only presets::Preset is ever applied")
    }
}

impl std::ops::DerefMut for crate::config::AppliedPreset {
    fn deref_mut(&mut self) -> &mut Preset {
        self.downcast_mut().expect("only presets::Preset is ever applied")
    }
}

impl From<Preset> for crate::config::AppliedPreset {
    fn from(p: Preset) -> Self {
        crate::config::AppliedPreset::new(p)
    }
}

/// The λ of a preset whose split rule is the practical scheme (λ weighting the log split).
pub(crate) fn lambda_value(k: &Knobs) -> Option<f64> {
    k.engine().lambda(k)
}

#[cfg(test)]
mod tests {
    use super::*;
    use csm_core::fitting::minimal_sphere;
    use csm_core::geometry::Lens;

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
            assert_eq!(p.engine().name(), p.as_str());
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
        let mut rng = csm_core::rng::SplitMix64::new(11);
        for _ in 0..200 {
            let lens = Lens::new(rng.range(0.1, 2.0), rng.range(0.3, 3.0));
            let n = rng.range(0.05, 50.0);
            let f = n * rng.range(1.01, 100.0);
            let u = engines::unreal::unreal_sphere(n, f, &lens);
            let m = minimal_sphere(n, f, lens.k2());
            assert!((u.radius - m.radius).abs() <= 1e-9 * m.radius, "{u:?} {m:?}");
            assert!((u.centre_depth - m.centre_depth).abs() <= 1e-9 * f);
        }
    }
}
