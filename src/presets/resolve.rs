//! Reading a preset from a config: the engine tables, defaults, `[shadow]` overrides and
//! validation of every knob.

use crate::error::ConfigError;
use glam::DVec3;
use serde::Deserialize;

use crate::config::{CameraSettings, ShadowSettings, Validator};
use crate::error::{Error, Result};
use crate::geometry::Aabb;

use super::*;

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
    /// A `[shadow]` count or map size the preset does not offer falls back to the preset's
    /// default with a note instead of being an error (`compare`, where one file's settings meet
    /// several engines).
    pub lenient_overrides: bool,
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
    Error::from(ConfigError::Invalid {
        location,
        key: format!("[{table}]"),
        value: "(engine table)".to_string(),
        allowed,
    })
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
                if list.contains(&shadow.cascades) {
                    cascades = shadow.cascades;
                } else if cx.choice.lenient_overrides {
                    notes.push(format!(
                        "shadow.cascades = {} is not offered by {name} ({}): its default {cascades} is used",
                        shadow.cascades,
                        join(&list)
                    ));
                } else {
                    return Err(v.invalid(
                        "shadow.cascades",
                        shadow.cascades,
                        &format!("one of {} for the {name} preset", join(&list)),
                    ));
                }
            }
        }
    }
    // Map size.
    let mut resolution = default_resolution(&knobs, cascades);
    if w.resolution {
        if !power_of_two_maps(name) || shadow.resolution.is_power_of_two() {
            resolution = shadow.resolution;
        } else if cx.choice.lenient_overrides {
            notes.push(format!(
                "shadow.resolution = {} is not a power of two, which {name} requires: its default {resolution} is used",
                shadow.resolution
            ));
        } else {
            return Err(v.invalid(
                "shadow.resolution",
                shadow.resolution,
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

pub(crate) fn join(list: &[usize]) -> String {
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

pub(crate) fn check_range(
    v: &Validator<'_>,
    key: &str,
    x: f64,
    lo: f64,
    hi: f64,
    lo_open: bool,
    hi_open: bool,
) -> Result<f64> {
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

pub(crate) fn positive(v: &Validator<'_>, key: &str, x: f64) -> Result<f64> {
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
