//! Each preset's rules in words, and what an analysis reports about a preset.

use serde::Serialize;

use csm_core::cascades::{LightDepth, Rig};
use csm_core::snapping::SnapMode;

use super::*;

/// The split rule in words.
pub fn split_rule(k: &Knobs) -> String {
    k.engine().split_rule(k)
}

/// The snapping rule in words.
pub(crate) fn snap_description(k: &Knobs) -> String {
    let engine = k.engine();
    if !engine.snaps() {
        return "none".to_string();
    }
    let r = engine.snap_rule(k);
    let mode = match r.mode {
        SnapMode::Round => "round",
        SnapMode::Floor => "floor",
        SnapMode::Trunc => "fmod (toward zero)",
    };
    let unit = if r.step_texels == 1 { "texel" } else { "texels" };
    format!("{mode}, {} {unit}, {}", r.step_texels, engine.snap_anchor(k))
}

/// The light depth rule in words.
pub(crate) fn light_depth_description(k: &Knobs) -> String {
    k.engine().light_depth_rule(k)
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
