//! Pieces several engines share: the [`Layout`] of slices, fraction splits, clipping the
//! selection to the camera, reading an engine table from the config text and checking knobs.

use std::marker::PhantomData;

use glam::DVec3;
use serde::de::{DeserializeOwned, DeserializeSeed, IgnoredAny, MapAccess, Visitor};

use crate::config::{toml_error, Validator};
use crate::error::Result;
use csm_core::geometry::Aabb;

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

/// The fitted slices and selection boundaries of a preset. `max_distance` is the engine's
/// shadow distance (unused by presets without one); `near`/`far` are the camera planes.
pub fn layout(knobs: &super::Knobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
    knobs.engine().layout(knobs, cascades, max_distance, near, far)
}

/// Boundaries at fractions of a distance measured from the eye, the first cascade starting at
/// the near plane (Unity, URP).
pub(crate) fn fraction_splits(near: f64, distance: f64, fractions: &[f64]) -> Vec<f64> {
    let mut s = vec![near];
    s.extend(fractions.iter().map(|f| f * distance));
    s.push(distance);
    s
}

/// Unity's and URP's layout: boundaries at fractions of the shadow distance min(far, max),
/// the fractions chosen by count (none for 1, `two` for 2, `three` for 3, `four` from 4 on).
pub(crate) fn distance_fractions(
    cascades: usize,
    near: f64,
    far: f64,
    max_distance: f64,
    (two, three, four): (&f64, &[f64], &[f64]),
) -> Layout {
    let dist = far.min(max_distance);
    let fr = match cascades {
        1 => &[],
        2 => std::slice::from_ref(two),
        3 => three,
        _ => four,
    };
    Layout::contiguous(fraction_splits(near, dist, fr))
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

/// Reads the top-level table `name` of a TOML document into `T`, with TOML's line and column
/// on errors; None when the file has no such table.
pub(crate) fn engine_table<T: DeserializeOwned>(text: &str, label: &str, name: &str) -> Result<Option<T>> {
    struct Pick<'n, T> {
        name: &'n str,
        out: PhantomData<T>,
    }
    impl<'de, T: DeserializeOwned> Visitor<'de> for Pick<'_, T> {
        type Value = Option<T>;

        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a TOML document")
        }

        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Option<T>, A::Error> {
            let mut out = None;
            while let Some(key) = map.next_key::<String>()? {
                if key == self.name {
                    out = Some(map.next_value::<T>()?);
                } else {
                    map.next_value::<IgnoredAny>()?;
                }
            }
            Ok(out)
        }
    }
    impl<'de, T: DeserializeOwned> DeserializeSeed<'de> for Pick<'_, T> {
        type Value = Option<T>;

        fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> std::result::Result<Option<T>, D::Error> {
            d.deserialize_map(self)
        }
    }
    let err = |e: toml::de::Error| toml_error(label, text, &e);
    let de = toml::Deserializer::parse(text).map_err(err)?;
    Pick { name, out: PhantomData }.deserialize(de).map_err(err)
}

/// Notes every preset gets alike (csm-lab's own `[shadow]` settings it ignores); reports that
/// list several presets say this once instead.
pub(crate) fn is_generic_note(note: &str) -> bool {
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

/// `x` in the interval from `lo` to `hi`, each end open or closed.
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

/// A number in [0, 1].
pub fn unit(v: &Validator<'_>, key: &str, x: f64) -> Result<f64> {
    check_range(v, key, x, 0.0, 1.0, false, false)
}

/// A distance >= 0, at most 1e9 world units (the world's bound: beyond it the arithmetic of
/// the fit can no longer carry the value, e.g. `pad_xy = 1e300`).
pub(crate) fn non_negative(v: &Validator<'_>, key: &str, x: f64) -> Result<f64> {
    check_range(v, key, x, 0.0, crate::config::MAX_WORLD, false, false)
}

/// A signed distance (a clip plane may sit behind the light), within ±1e9 world units.
pub(crate) fn signed_distance(v: &Validator<'_>, key: &str, x: f64) -> Result<f64> {
    check_range(
        v,
        key,
        x,
        -crate::config::MAX_WORLD,
        crate::config::MAX_WORLD,
        false,
        false,
    )
}

/// A distance > 0, at most 1e9 world units.
pub fn positive(v: &Validator<'_>, key: &str, x: f64) -> Result<f64> {
    check_range(v, key, x, 0.0, crate::config::MAX_WORLD, true, false)
}

/// `N` fractions strictly increasing inside (0, 1), or `default` when not written.
pub fn fractions<const N: usize>(
    v: &Validator<'_>,
    key: &str,
    x: Option<&Vec<f64>>,
    default: [f64; N],
) -> Result<[f64; N]> {
    let Some(x) = x else {
        return Ok(default);
    };
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

/// A point, or `default` when not written.
pub(crate) fn point_or(v: &Validator<'_>, key: &str, x: Option<[f64; 3]>, default: DVec3) -> Result<DVec3> {
    match x {
        // Bounded like every world position: 1e308 was accepted, then the fit's centre was NaN.
        Some(a) => v.point(key, a),
        None => Ok(default),
    }
}

/// `lower` < `upper`, else an error at `upper_key`.
pub fn ordered(v: &Validator<'_>, lower_key: &str, lower: f64, upper_key: &str, upper: f64) -> Result<()> {
    if upper <= lower {
        return Err(v.invalid(
            upper_key,
            upper,
            &format!("a number greater than {lower_key} ({lower})"),
        ));
    }
    Ok(())
}

/// Half the extent of a box along a unit direction (its support function about the centre).
pub(crate) fn half_extent_along(scene: &Aabb, dir: DVec3) -> f64 {
    let h = 0.5 * (scene.max - scene.min);
    h.x * dir.x.abs() + h.y * dir.y.abs() + h.z * dir.z.abs()
}

/// The centre of a box.
pub fn centre(scene: &Aabb) -> DVec3 {
    0.5 * (scene.min + scene.max)
}

/// csm-lab's minimal sphere, grown by the snap rule's largest shift, on the world-origin grid,
/// light depth fitted to the scene: how the closed-source Unity pipelines are modelled.
pub(crate) fn minimal_sphere_scheme(f: &super::Fitting<'_>) -> super::EngineScheme {
    let k2 = f.lens.k2();
    let s = f.spheres(|a, b| csm_core::fitting::minimal_sphere(a, b, k2));
    let sides = s
        .iter()
        .map(|s| {
            csm_core::fitting::Window::side_with_border(2.0 * s.radius, f.resolution, f.snap_rule.max_shift_texels())
        })
        .collect();
    super::EngineScheme::fixed(
        "sphere",
        super::Fitting::axis(&s),
        sides,
        csm_core::cascades::LightDepthRule::Scene,
    )
}

/// A knob's default sweep: the candidates and the configured value, those in `(lo, hi]`,
/// sorted, without repeats.
pub fn around(value: f64, candidates: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    let mut v: Vec<f64> = candidates
        .iter()
        .copied()
        .chain([value])
        .filter(|x| x.is_finite() && *x > lo && *x <= hi)
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}
