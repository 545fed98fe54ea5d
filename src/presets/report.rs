//! Each preset's rules in words, and what an analysis reports about a preset.

use serde::Serialize;

use crate::cascades::{LightDepth, LightPose, Rig};
use crate::geometry::Aabb;
use crate::snapping::SnapMode;

use super::*;

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
