//! The `[sweep]` table of a scene file: the grid axes a sweep runs over (λ, cascade count,
//! map size, fit), the memory budget and the grid-size limit. Ranges are decimal-exact:
//! `{ start = 0.0, end = 1.0, step = 0.05 }` is exactly 21 values ending at 1.0.

use serde::Deserialize;

use super::{Fit, Validator};
use crate::error::Result;

/// One axis: its values in order, and the canonical spec that reproduces it on the CLI.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis<T> {
    pub values: Vec<T>,
    pub spec: String,
}

/// The `[sweep]` table as validated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SweepSpec {
    pub lambda: Option<Axis<f64>>,
    pub cascades: Option<Axis<usize>>,
    pub resolution: Option<Axis<u32>>,
    pub fit: Option<Axis<Fit>>,
    /// Memory budget for the recommendation, MiB (2^20 bytes).
    pub memory_budget_mib: Option<f64>,
    /// A larger grid is an error, not an out-of-memory.
    pub max_configs: usize,
}

pub const DEFAULT_MAX_CONFIGS: usize = 100_000;
/// Budget used for the recommendation when none is configured.
pub const DEFAULT_BUDGET_MIB: f64 = 64.0;

// ---------------------------------------------------------------------------------------------
// Decimal-exact ranges
// ---------------------------------------------------------------------------------------------

/// A finite f64 as an exact decimal `mantissa * 10^-scale`, from its shortest round-trip
/// representation ("0.05" -> (5, 2)). None when it needs more digits than an i128 holds.
fn to_decimal(x: f64) -> Option<(i128, u32)> {
    let s = format!("{x}");
    let (neg, s) = match s.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, s.as_str()),
    };
    let (int, frac) = s.split_once('.').unwrap_or((s, ""));
    if int.len() + frac.len() > 36 {
        return None;
    }
    let digits: i128 = format!("{int}{frac}").parse().ok()?;
    Some((if neg { -digits } else { digits }, frac.len() as u32))
}

/// `start, start + step, ...` up to and including `end` when it is on the grid, computed in
/// decimal so that 0:1:0.05 has 21 values ending exactly at 1.0. Each value is the f64 nearest
/// to the exact decimal, i.e. the same number a user would get by typing it.
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
    let approx_count = ((end - start) / step).floor() + 1.0;
    if approx_count > 1e7 {
        return Err(format!("{approx_count} values is far too many"));
    }
    match (to_decimal(start), to_decimal(end), to_decimal(step)) {
        (Some((s, ds)), Some((e, de)), Some((p, dp))) => {
            let d = ds.max(de).max(dp);
            let scale = |m: i128, k: u32| m * 10i128.pow(d - k);
            let (s, e, p) = (scale(s, ds), scale(e, de), scale(p, dp));
            let n = (e - s) / p;
            Ok((0..=n)
                .map(|i| {
                    let m = s + i * p;
                    format!("{m}e-{d}").parse::<f64>().expect("a decimal literal parses")
                })
                .collect())
        }
        // Numbers too long for exact decimals: fall back to multiplication (no accumulation).
        _ => {
            let n = approx_count as i64;
            Ok((0..n).map(|i| (start + i as f64 * step).min(end)).collect())
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Config table
// ---------------------------------------------------------------------------------------------

#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub(crate) enum RawAxis {
    List(Vec<f64>),
    Range(RawRange),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawRange {
    start: f64,
    end: f64,
    step: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSweep {
    lambda: Option<RawAxis>,
    cascades: Option<RawAxis>,
    resolution: Option<RawAxis>,
    fit: Option<Vec<Fit>>,
    memory_budget_mib: Option<f64>,
    max_configs: Option<i64>,
}

pub fn fmt_list<T: std::fmt::Display>(v: &[T]) -> String {
    v.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(",")
}

/// Checks an axis' values: not empty, no duplicates, each allowed.
pub fn check_values<T: PartialEq + Copy + std::fmt::Display>(
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
    for (i, a) in values.iter().enumerate() {
        if values[..i].contains(a) {
            return Err(format!("{a} is listed twice"));
        }
    }
    Ok(())
}

pub fn lambda_ok(x: f64) -> bool {
    (0.0..=1.0).contains(&x)
}

pub fn cascades_ok(x: usize) -> bool {
    (1..=16).contains(&x)
}

pub fn resolution_ok(x: u32) -> bool {
    (16..=16384).contains(&x)
}

fn raw_lambda(raw: RawAxis) -> std::result::Result<Axis<f64>, String> {
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
    check_values(&axis.values, "[0, 1]", lambda_ok)?;
    Ok(axis)
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

fn int_axis<T: TryFrom<i64> + Copy + PartialEq + std::fmt::Display>(
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

pub(crate) fn validate_raw(raw: RawSweep, v: &Validator<'_>) -> Result<SweepSpec> {
    let lambda = raw
        .lambda
        .map(raw_lambda)
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
    let memory_budget_mib = match raw.memory_budget_mib {
        Some(b) if !(b.is_finite() && b > 0.0) => {
            return Err(v.invalid("sweep.memory_budget_mib", b, "a number of MiB > 0"));
        }
        b => b,
    };
    let max_configs = v.int_range(
        "sweep.max_configs",
        raw.max_configs.unwrap_or(DEFAULT_MAX_CONFIGS as i64),
        1,
        10_000_000,
    )? as usize;
    Ok(SweepSpec {
        lambda,
        cascades,
        resolution,
        fit,
        memory_budget_mib,
        max_configs,
    })
}
