//! The `[sweep]` table of a scene file: the grid axes a sweep runs over (λ, cascade count,
//! map size, fit), the memory budget and the grid-size limit. Ranges are decimal-exact:
//! `{ start = 0.0, end = 1.0, step = 0.05 }` is exactly 21 values ending at 1.0.

use serde::Deserialize;

use super::{Fit, SplitRange, Validator};
use crate::error::Result;

/// One axis: its values in order, and the canonical spec that reproduces it on the CLI.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis<T> {
    pub values: Vec<T>,
    pub spec: String,
}

/// The axes of a sweep, each None when not given. The one list of axes: the `[sweep]` table
/// holds one ([`SweepSpec::axes`]) and the command line's flags parse into another
/// (`commands::sweep::grid::GridFlags::overrides`); `Grid::resolve` merges the two, a flag
/// over its key.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SweepAxes {
    pub lambda: Option<Axis<f64>>,
    pub cascades: Option<Axis<usize>>,
    pub resolution: Option<Axis<u32>>,
    pub fit: Option<Axis<Fit>>,
    /// `split_range = ["bounds", "visible"]`: splits on the bounds' depth range and/or on the
    /// visible depths (scene geometry only), side by side in one sweep.
    pub split_range: Option<Axis<SplitRange>>,
    /// `knob = [...]`: values of the preset's split knob (`docs/presets.md`, "Sweep axes").
    pub knob: Option<Axis<f64>>,
    /// `distance = [...]`: shadow distances (`shadow.max_distance`), world units.
    pub distance: Option<Axis<f64>>,
    /// `sun_azimuth = [...]`: compass bearings of the sun, degrees in [0, 360) (a condition the
    /// recommendation must hold under, not a setting; see `docs/geometry.md`, "Sun angles").
    pub sun_azimuth: Option<Axis<f64>>,
    /// `sun_elevation = [...]`: the sun's angle above the horizon, degrees in (0, 90].
    pub sun_elevation: Option<Axis<f64>>,
    /// `light_update = ["every:1", "every:4", "quantize:0.5"]`: the engine's light update rule
    /// (a moving light only).
    pub light_update: Option<Axis<csm_core::light_motion::LightUpdate>>,
    /// `update_every = [1, 2, "1/1/2/4"]`: cached cascades (`shadow.update_every`), one
    /// cadence for every cascade or one per cascade written `1/1/2/4`.
    pub update_every: Option<Axis<super::SweptCadence>>,
}

/// The `[sweep]` table as validated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SweepSpec {
    /// The axes the table sweeps.
    pub axes: SweepAxes,
    /// Memory budget for the recommendation, MiB (2^20 bytes).
    pub memory_budget_mib: Option<f64>,
    /// `cost_budget`: the largest `cost_index` (the configured setting's cost = 1) the
    /// recommendation may have (docs/cost.md).
    pub cost_budget: Option<f64>,
    /// `shadow_ms_budget`: the largest `shadow_ms` (calibrated cost model only).
    pub shadow_ms_budget: Option<f64>,
    /// A larger grid is an error, not an out-of-memory.
    pub max_configs: usize,
    /// `objective`: the name of the summary metric the recommendation minimises (None: the
    /// default). The name is checked against the metric registry when the file is loaded.
    pub objective: Option<String>,
    /// `optimize_splits = true`: also search free split fractions (`sweep --optimize-splits`).
    pub optimize_splits: bool,
    /// `ground_truth = true`: also measure the flicker S5 of a sample of the rows
    /// (`sweep --ground-truth`).
    pub ground_truth: bool,
    /// `cost_means = true`: every row also measures the cost counts' means over the camera
    /// path (`*_mean` columns; on anyway when a setting caches cascades). docs/cost.md.
    pub cost_means: bool,
}

pub(crate) const DEFAULT_MAX_CONFIGS: usize = 100_000;
/// Budget used for the recommendation when none is configured.
pub(crate) const DEFAULT_BUDGET_MIB: f64 = 64.0;

// ---------------------------------------------------------------------------------------------
// Decimal-exact ranges
// ---------------------------------------------------------------------------------------------

/// Most values one range may expand to (the largest `max_configs`); checked from the spec,
/// before anything is expanded.
pub const MAX_RANGE_VALUES: u64 = 10_000_000;

/// A finite f64 as an exact decimal `mantissa * 10^exponent`, from its shortest round-trip
/// representation ("0.05" -> (5, -2), "1e-35" -> (1, -35)). At most 17 significant digits.
fn to_decimal(x: f64) -> (i128, i32) {
    let s = format!("{x:e}");
    let (mant, exp) = s.split_once('e').unwrap_or((s.as_str(), "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let (neg, mant) = match mant.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, mant),
    };
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    let digits: i128 = format!("{int}{frac}").parse().unwrap_or(0);
    (if neg { -digits } else { digits }, exp - frac.len() as i32)
}

/// `m * 10^k` for k >= 0, or None when it does not fit an i128.
fn scaled(m: i128, k: i32) -> Option<i128> {
    10i128.checked_pow(u32::try_from(k).ok()?)?.checked_mul(m)
}

/// `start, start + step, ...` up to and including `end` when it is on the grid, computed in
/// decimal so that 0:1:0.05 has 21 values ending exactly at 1.0. Each value is the f64 nearest
/// to the exact decimal, i.e. the same number a user would get by typing it.
///
/// All arithmetic is checked integer arithmetic: no input panics or wraps. The number of values
/// is known (and bounded by [`MAX_RANGE_VALUES`]) before any is produced.
pub fn decimal_range(start: f64, end: f64, step: f64) -> std::result::Result<Vec<f64>, String> {
    if !(start.is_finite() && end.is_finite() && step.is_finite()) {
        return Err("start, end and step must be finite numbers".into());
    }
    if step <= 0.0 {
        return Err(format!("step must be > 0 (got {step})"));
    }
    if end < start {
        return Err(format!("end ({end}) must be >= start ({start})"));
    }
    if end == start {
        return Ok(vec![start]);
    }
    let (s, es) = to_decimal(start);
    let (e, ee) = to_decimal(end);
    let (p, ep) = to_decimal(step);
    let d = es.min(ee).min(ep);
    let exact = (|| {
        let (s, e, p) = (scaled(s, es - d)?, scaled(e, ee - d)?, scaled(p, ep - d)?);
        Some((s, e.checked_sub(s)? / p, p))
    })();
    let too_many = |n: String| {
        Err(format!(
            "the range has {n} values; at most {MAX_RANGE_VALUES} (use a larger step)"
        ))
    };
    match exact {
        Some((s, n, p)) => {
            if n >= MAX_RANGE_VALUES as i128 {
                return too_many(format!("{}", n.saturating_add(1)));
            }
            (0..=n)
                .map(|i| {
                    let m = s + i * p;
                    format!("{m}e{d}")
                        .parse::<f64>()
                        .map_err(|_| format!("{m}e{d} is not a number"))
                })
                .collect()
        }
        // The three numbers' magnitudes are more than ~20 decades apart, so the exact form
        // does not fit an i128: a step beyond the span gives the start alone; anything else
        // cannot be computed exactly and is refused (it was once accepted with values in
        // binary floating point, silently off the decimal grid).
        None => {
            let approx = ((end - start) / step).floor();
            if approx.is_nan() || approx >= MAX_RANGE_VALUES as f64 {
                return too_many(format!("{approx:e}"));
            }
            if approx >= 1.0 {
                return Err(format!(
                    "start {start}, end {end} and step {step} are too many decades apart to count the range's \
                     values exactly (the count does not fit a 128-bit integer); list the values instead"
                ));
            }
            Ok(vec![start])
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Config table
// ---------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
#[serde(try_from = "toml::Value")]
pub(crate) enum RawAxis {
    List(Vec<f64>),
    Range(RawRange),
}

#[derive(Debug)]
pub(crate) struct RawRange {
    start: f64,
    end: f64,
    step: f64,
}

const AXIS_FORMS: &str =
    "a list of numbers such as [0.5, 0.75] or a range such as { start = 0.0, end = 1.0, step = 0.05 }";

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

impl TryFrom<toml::Value> for RawAxis {
    type Error = String;
    fn try_from(v: toml::Value) -> std::result::Result<RawAxis, String> {
        match v {
            toml::Value::Array(items) => items
                .iter()
                .map(|x| number(x).ok_or_else(|| format!("{x} is not a number; expected {AXIS_FORMS}")))
                .collect::<std::result::Result<Vec<f64>, String>>()
                .map(RawAxis::List),
            toml::Value::Table(t) => {
                if let Some(k) = t.keys().find(|k| !["start", "end", "step"].contains(&k.as_str())) {
                    return Err(format!("unknown key {k:?} in a range; a range has start, end and step"));
                }
                let get = |k: &str| {
                    t.get(k)
                        .ok_or_else(|| format!("the range has no {k}; a range has start, end and step"))
                        .and_then(|x| number(x).ok_or_else(|| format!("{k} = {x} is not a number")))
                };
                Ok(RawAxis::Range(RawRange {
                    start: get("start")?,
                    end: get("end")?,
                    step: get("step")?,
                }))
            }
            other => Err(format!("{other} is not {AXIS_FORMS}")),
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSweep {
    lambda: Option<RawAxis>,
    cascades: Option<RawAxis>,
    resolution: Option<RawAxis>,
    fit: Option<Vec<Fit>>,
    split_range: Option<Vec<SplitRange>>,
    knob: Option<RawAxis>,
    distance: Option<RawAxis>,
    sun_azimuth: Option<RawAxis>,
    sun_elevation: Option<RawAxis>,
    light_update: Option<Vec<String>>,
    update_every: Option<Vec<RawCadence>>,
    memory_budget_mib: Option<f64>,
    cost_budget: Option<f64>,
    shadow_ms_budget: Option<f64>,
    max_configs: Option<i64>,
    objective: Option<String>,
    optimize_splits: Option<bool>,
    ground_truth: Option<bool>,
    cost_means: Option<bool>,
}

/// One value of `[sweep] update_every`: a whole number (every cascade) or a per-cascade
/// cadence written as a string, `"1/1/2/4"`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawCadence {
    Int(i64),
    Text(String),
}

pub(crate) fn fmt_list<T: std::fmt::Display>(v: &[T]) -> String {
    v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(",")
}

/// Checks an axis' values: not empty, no duplicates, each allowed.
pub(crate) fn check_values<T: PartialOrd + Copy + std::fmt::Display>(
    values: &[T],
    allowed: &str,
    ok: impl Fn(T) -> bool,
) -> std::result::Result<(), String> {
    if values.is_empty() {
        return Err("the axis is empty; give at least one value".into());
    }
    if let Some(bad) = values.iter().find(|v| !ok(**v)) {
        return Err(format!("{bad} is outside {allowed}"));
    }
    // O(n log n): a sorted copy's neighbours (a 10⁷-value range is checked in a second).
    let mut sorted: Vec<(usize, T)> = values.iter().copied().enumerate().collect();
    sorted.sort_by(|a, b| {
        a.1.partial_cmp(&b.1)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(a.0.cmp(&b.0))
    });
    // The first value (in the user's order) that repeats an earlier one.
    if let Some(dup) = sorted
        .windows(2)
        .filter(|w| w[0].1 == w[1].1)
        .map(|w| w[1])
        .min_by_key(|d| d.0)
    {
        return Err(format!("{} is listed twice", dup.1));
    }
    Ok(())
}

pub(crate) fn lambda_ok(x: f64) -> bool {
    (0.0..=1.0).contains(&x)
}

pub(crate) fn cascades_ok(x: usize) -> bool {
    (1..=16).contains(&x)
}

pub(crate) fn resolution_ok(x: u32) -> bool {
    (16..=16384).contains(&x)
}

/// A number axis (`lambda`, `knob`, `distance`, the sun angles): a list or a decimal-exact
/// range, each value `ok`.
fn raw_numbers(raw: RawAxis, allowed: &str, ok: impl Fn(f64) -> bool) -> std::result::Result<Axis<f64>, String> {
    let axis = match raw {
        RawAxis::List(values) => Axis {
            spec: fmt_list(&values),
            values,
        },
        RawAxis::Range(r) => Axis {
            values: decimal_range(r.start, r.end, r.step)?,
            spec: format!("{}:{}:{}", r.start, r.end, r.step),
        },
    };
    check_values(&axis.values, allowed, ok)?;
    Ok(axis)
}

/// A sun azimuth a sweep may use, degrees: a compass bearing in [0, 360).
pub(crate) fn sun_azimuth_ok(x: f64) -> bool {
    (0.0..360.0).contains(&x)
}

/// A sun elevation a sweep may use, degrees: above the horizon, at most the zenith.
pub(crate) fn sun_elevation_ok(x: f64) -> bool {
    x > 0.0 && x <= 90.0
}

/// A shadow distance a sweep may use.
pub(crate) fn distance_ok(x: f64) -> bool {
    x.is_finite() && x > 0.0 && x <= 1e9
}

fn whole(values: Vec<f64>) -> std::result::Result<Vec<i64>, String> {
    values
        .into_iter()
        .map(|v| {
            if v.fract() == 0.0 && v.abs() < 1e15 {
                Ok(v as i64)
            } else {
                Err(format!("{v} is not a whole number"))
            }
        })
        .collect()
}

fn raw_ints(raw: RawAxis) -> std::result::Result<Vec<i64>, String> {
    match raw {
        RawAxis::List(v) => whole(v),
        RawAxis::Range(r) => whole(decimal_range(r.start, r.end, r.step)?),
    }
}

fn int_axis<T: TryFrom<i64> + Copy + PartialOrd + std::fmt::Display>(
    raw: RawAxis,
    allowed: &str,
    ok: impl Fn(T) -> bool,
) -> std::result::Result<Axis<T>, String> {
    let ints = raw_ints(raw)?;
    let values = ints
        .iter()
        .map(|&i| T::try_from(i).map_err(|_| format!("{i} is outside {allowed}")))
        .collect::<std::result::Result<Vec<T>, String>>()?;
    check_values(&values, allowed, ok)?;
    Ok(Axis {
        spec: fmt_list(&values),
        values,
    })
}

pub(crate) fn validate_raw(raw: RawSweep, v: &Validator<'_>, has_geometry: bool) -> Result<SweepSpec> {
    let lambda = raw
        .lambda
        .map(|r| raw_numbers(r, "[0, 1]", lambda_ok))
        .transpose()
        .map_err(|why| v.invalid("sweep.lambda", "as written", &format!("values in [0, 1]: {why}")))?;
    let cascades = raw
        .cascades
        .map(|r| int_axis::<usize>(r, "1..=16", cascades_ok))
        .transpose()
        .map_err(|why| {
            v.invalid(
                "sweep.cascades",
                "as written",
                &format!("whole numbers in 1..=16: {why}"),
            )
        })?;
    let resolution = raw
        .resolution
        .map(|r| int_axis::<u32>(r, "16..=16384", resolution_ok))
        .transpose()
        .map_err(|why| {
            v.invalid(
                "sweep.resolution",
                "as written",
                &format!("whole numbers in 16..=16384: {why}"),
            )
        })?;
    let fit = match raw.fit {
        Some(f) => {
            check_values(&f.iter().map(|x| x.name()).collect::<Vec<_>>(), "sphere, aabb", |_| {
                true
            })
            .map_err(|why| {
                v.invalid(
                    "sweep.fit",
                    format!("{f:?}"),
                    &format!("\"sphere\" and/or \"aabb\": {why}"),
                )
            })?;
            Some(Axis {
                spec: fmt_list(&f),
                values: f,
            })
        }
        None => None,
    };
    let split_range = match raw.split_range {
        Some(r) => {
            check_values(
                &r.iter().map(|x| x.name()).collect::<Vec<_>>(),
                "bounds, visible",
                |_| true,
            )
            .map_err(|why| {
                v.invalid(
                    "sweep.split_range",
                    format!("{r:?}"),
                    &format!("\"bounds\" and/or \"visible\": {why}"),
                )
            })?;
            if !has_geometry && r.contains(&SplitRange::Visible) {
                return Err(v.invalid(
                    "sweep.split_range",
                    format!("{r:?}"),
                    "[\"bounds\"] without scene geometry: add scene.ground, [[scene.box]] or scene.gltf \
                     (the bounds alone show no visible depth)",
                ));
            }
            Some(Axis {
                spec: fmt_list(&r),
                values: r,
            })
        }
        None => None,
    };
    let memory_budget_mib = match raw.memory_budget_mib {
        Some(b) if !(b.is_finite() && b > 0.0) => {
            return Err(v.invalid("sweep.memory_budget_mib", b, "a number of MiB > 0"));
        }
        b => b,
    };
    // The cost budgets need the counts, which need scene geometry.
    let cost_budget = |key: &str, b: Option<f64>, what: &str| {
        match b {
        Some(b) if !(b.is_finite() && b > 0.0) => Err(v.invalid(key, b, what)),
        Some(b) if !has_geometry => Err(v.invalid(
            key,
            b,
            "a budget only with scene geometry: the cost counts need the scene's objects (give scene.ground, [[scene.box]] or scene.gltf)",
        )),
        b => Ok(b),
    }
    };
    let shadow_ms_budget = cost_budget(
        "sweep.shadow_ms_budget",
        raw.shadow_ms_budget,
        "a number of milliseconds > 0",
    )?;
    let cost_budget = cost_budget(
        "sweep.cost_budget",
        raw.cost_budget,
        "a cost_index > 0 (the configured setting's cost is 1)",
    )?;
    let max_configs = v.int_range(
        "sweep.max_configs",
        raw.max_configs.unwrap_or(DEFAULT_MAX_CONFIGS as i64),
        1,
        10_000_000,
    )? as usize;
    let knob = raw
        .knob
        .map(|r| raw_numbers(r, "finite numbers", f64::is_finite))
        .transpose()
        .map_err(|why| v.invalid("sweep.knob", "as written", &format!("finite numbers: {why}")))?;
    let distance = raw
        .distance
        .map(|r| raw_numbers(r, "(0, 1e9]", distance_ok))
        .transpose()
        .map_err(|why| v.invalid("sweep.distance", "as written", &format!("distances in (0, 1e9]: {why}")))?;
    let sun_azimuth = raw
        .sun_azimuth
        .map(|r| raw_numbers(r, "[0, 360)", sun_azimuth_ok))
        .transpose()
        .map_err(|why| {
            v.invalid(
                "sweep.sun_azimuth",
                "as written",
                &format!("compass bearings in degrees, [0, 360): {why}"),
            )
        })?;
    let sun_elevation = raw
        .sun_elevation
        .map(|r| raw_numbers(r, "(0, 90]", sun_elevation_ok))
        .transpose()
        .map_err(|why| {
            v.invalid(
                "sweep.sun_elevation",
                "as written",
                &format!("degrees above the horizon, (0, 90]: {why}"),
            )
        })?;
    let light_update = raw
        .light_update
        .map(|list| {
            let spec = list.join(",");
            super::parse_light_update_list(&spec)
                .map(|values| Axis { values, spec })
                .map_err(|why| {
                    v.invalid(
                        "sweep.light_update",
                        format!("{list:?}"),
                        &format!("rules every:K or quantize:DEG, each once: {why}"),
                    )
                })
        })
        .transpose()?;
    let update_every = raw
        .update_every
        .map(|list| {
            let spec = list
                .iter()
                .map(|x| match x {
                    RawCadence::Int(k) => k.to_string(),
                    RawCadence::Text(t) => t.trim().to_string(),
                })
                .collect::<Vec<_>>()
                .join(",");
            super::parse_update_every_list(&spec)
                .map(|values| Axis {
                    values,
                    spec: spec.clone(),
                })
                .map_err(|why| {
                    v.invalid(
                        "sweep.update_every",
                        format!("[{spec}]"),
                        &format!(
                            "frames between renders in 1..=256: one per value for every cascade (2) or one per cascade as a string (\"1/1/2/4\"), each value once: {why}"
                        ),
                    )
                })
        })
        .transpose()?;
    Ok(SweepSpec {
        axes: SweepAxes {
            lambda,
            cascades,
            resolution,
            fit,
            split_range,
            knob,
            distance,
            sun_azimuth,
            sun_elevation,
            light_update,
            update_every,
        },
        memory_budget_mib,
        cost_budget,
        shadow_ms_budget,
        max_configs,
        objective: raw.objective,
        optimize_splits: raw.optimize_splits.unwrap_or(false),
        ground_truth: raw.ground_truth.unwrap_or(false),
        cost_means: raw.cost_means.unwrap_or(false),
    })
}
