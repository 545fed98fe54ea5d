//! Comparing summary metrics with an earlier run: what got worse, what improved.
//!
//! A change counts when it exceeds the metric's tolerance, `max(absolute, relative *
//! |baseline|)`: the relative part scales with the metric, the absolute part keeps a metric
//! whose baseline is 0 (shimmer with snapping, coverage violations) from flagging rounding
//! noise. A change in the worse direction (see [`super::metric`]) beyond the tolerance is a
//! regression; in the better direction, an improvement. Metrics without a worse direction
//! (`z_lo`, `z_hi`) are reported as changed, never as regressions.

use crate::error::IoError;
use std::collections::BTreeMap;
use std::path::Path;

use super::metric::SummaryMetric;
use crate::error::{BaselineError, Error, Result};

/// How much a metric may change before it counts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Tolerance {
    /// Fraction of |baseline|.
    pub relative: f64,
    /// In the metric's own units.
    pub absolute: f64,
}

impl Tolerance {
    /// The largest change that does not count: `max(absolute, relative * |baseline|)`.
    pub(crate) fn allowed(&self, baseline: f64) -> f64 {
        // Clamped to the largest finite value: a huge tolerance allows everything, it does not
        // overflow into a NaN margin or a non-finite number in the JSON report.
        self.absolute.max(self.relative * baseline.abs()).min(f64::MAX)
    }
}

/// The `[baseline]` table: a default and per-metric overrides.
#[derive(Debug, Clone, PartialEq)]
pub struct Tolerances {
    pub default: Tolerance,
    pub per_metric: BTreeMap<SummaryMetric, Tolerance>,
}

impl Default for Tolerances {
    /// 2 % relative, 1e-9 absolute.
    fn default() -> Self {
        Tolerances {
            default: Tolerance {
                relative: 0.02,
                absolute: 1e-9,
            },
            per_metric: BTreeMap::new(),
        }
    }
}

impl Tolerances {
    pub(crate) fn for_metric(&self, m: SummaryMetric) -> Tolerance {
        self.per_metric.get(&m).copied().unwrap_or(self.default)
    }
}

/// What happened to one metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Worse by more than the tolerance.
    Regressed,
    /// Better by more than the tolerance.
    Improved,
    /// Within the tolerance.
    Unchanged,
    /// A metric without a worse direction moved by more than the tolerance.
    Changed,
    /// The baseline has no value for this metric.
    NotInBaseline,
    /// The current run has no value for this metric.
    NotInCurrent,
}

impl Verdict {
    pub(crate) fn label(self) -> &'static str {
        match self {
            Verdict::Regressed => "REGRESSED",
            Verdict::Improved => "improved",
            Verdict::Unchanged => "unchanged",
            Verdict::Changed => "changed",
            Verdict::NotInBaseline => "not in baseline",
            Verdict::NotInCurrent => "not in current",
        }
    }
}

/// One metric compared.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    pub metric: SummaryMetric,
    pub baseline: Option<f64>,
    pub current: Option<f64>,
    /// The allowed change for this metric and baseline value.
    pub tolerance: f64,
    pub verdict: Verdict,
}

impl Comparison {
    /// current - baseline, when both exist.
    pub(crate) fn change(&self) -> Option<f64> {
        Some(self.current? - self.baseline?)
    }

    /// (current - baseline) / |baseline|, when both exist and the baseline is not 0.
    pub(crate) fn relative_change(&self) -> Option<f64> {
        let (b, c) = (self.baseline?, self.current?);
        (b != 0.0).then(|| (c - b) / b.abs())
    }
}

/// Judges one metric.
pub(crate) fn compare_one(
    metric: SummaryMetric,
    baseline: Option<f64>,
    current: Option<f64>,
    tol: &Tolerances,
) -> Comparison {
    let t = tol.for_metric(metric);
    let (verdict, tolerance) = match (baseline, current) {
        (None, _) => (Verdict::NotInBaseline, t.allowed(0.0)),
        (Some(b), None) => (Verdict::NotInCurrent, t.allowed(b)),
        (Some(b), Some(c)) => {
            let allowed = t.allowed(b);
            let verdict = match metric.direction().worsening(b, c) {
                Some(w) if w > allowed => Verdict::Regressed,
                Some(w) if -w > allowed => Verdict::Improved,
                Some(_) => Verdict::Unchanged,
                None if (c - b).abs() > allowed => Verdict::Changed,
                None => Verdict::Unchanged,
            };
            (verdict, allowed)
        }
    };
    Comparison {
        metric,
        baseline,
        current,
        tolerance,
        verdict,
    }
}

/// Compares every summary metric, in registry order. The maps need not hold
/// every metric: a missing value gives [`Verdict::NotInBaseline`] / [`Verdict::NotInCurrent`].
pub(crate) fn compare(
    current: &BTreeMap<SummaryMetric, f64>,
    baseline: &BTreeMap<SummaryMetric, f64>,
    tol: &Tolerances,
) -> Vec<Comparison> {
    SummaryMetric::all()
        .filter(|m| current.contains_key(m) || baseline.contains_key(m))
        .map(|m| compare_one(m, baseline.get(&m).copied(), current.get(&m).copied(), tol))
        .collect()
}

/// The summary metrics of a `summary.json` document (as `analyze` writes it): the flat
/// top-level keys named like the metrics. Booleans read 1/0. Metrics absent from the document
/// are absent from the map (an older file); a metric with a non-numeric value, or a document
/// with none of the metrics, is an error.
pub(crate) fn summary_from_json(value: &serde_json::Value, label: &str) -> Result<BTreeMap<SummaryMetric, f64>> {
    let invalid = |message: String| -> Error {
        BaselineError::Invalid {
            label: label.to_string(),
            message,
        }
        .into()
    };
    let obj = value.as_object().ok_or_else(|| {
        invalid("the baseline is not a summary.json object (write one with `csm-lab analyze`)".to_string())
    })?;
    let mut out = BTreeMap::new();
    for m in SummaryMetric::all() {
        let Some(v) = obj.get(m.name()) else { continue };
        let x = match v {
            serde_json::Value::Bool(b) => f64::from(u8::from(*b)),
            serde_json::Value::Number(n) => n
                .as_f64()
                .filter(|x| x.is_finite() && x.abs() <= MAX_BASELINE_VALUE)
                .ok_or_else(|| {
                    invalid(format!(
                        "`{}` = {n} is not a number csm-lab writes (finite, at most {MAX_BASELINE_VALUE:e} in magnitude)",
                        m.name()
                    ))
                })?,
            other => {
                return Err(invalid(format!(
                    "`{}` = {other} is not a number; a summary.json from `csm-lab analyze` is expected",
                    m.name()
                )))
            }
        };
        out.insert(m, x);
    }
    if out.is_empty() {
        return Err(invalid(format!(
            "none of the summary metrics ({}) is in this JSON; a summary.json from `csm-lab analyze` is expected",
            SummaryMetric::all().map(|m| m.name()).collect::<Vec<_>>().join(", ")
        )));
    }
    Ok(out)
}

/// No summary metric csm-lab writes comes near this; a larger baseline value was edited or
/// corrupted, and comparing with it would overflow the tolerance arithmetic.
pub(crate) const MAX_BASELINE_VALUE: f64 = 1e100;

/// The `scene_hash` of a `summary.json` document, if it has one (files written before the
/// hash existed have none).
pub(crate) fn scene_hash_of(value: &serde_json::Value) -> Option<&str> {
    value.get("scene_hash").and_then(|h| h.as_str())
}

/// Reads a `summary.json` baseline, refusing one made from a scene other than `scene_hash`'s.
pub(crate) fn read_summary_json_for(path: &Path, scene_hash: &str) -> Result<BTreeMap<SummaryMetric, f64>> {
    let text = crate::config::read_bounded(path, 256 << 20, "a baseline file")?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        Error::from(IoError::DataFile {
            path: path.to_path_buf(),
            line: e.line(),
            message: format!("not valid JSON ({e}); a summary.json from `csm-lab analyze` is expected"),
        })
    })?;
    if let Some(h) = scene_hash_of(&value) {
        if h != scene_hash {
            return Err(BaselineError::Mismatch {
                path: path.to_path_buf(),
                message: format!(
                    "this baseline was made from another scene (scene_hash {h}; this config's is {scene_hash}): \
                     camera, screen, light, scene bounds or motion differ. Write a baseline from this config \
                     with `csm-lab analyze`"
                ),
            }
            .into());
        }
    }
    summary_from_json(&value, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tol(relative: f64, absolute: f64) -> Tolerances {
        Tolerances {
            default: Tolerance { relative, absolute },
            per_metric: BTreeMap::new(),
        }
    }

    #[test]
    fn verdicts_follow_direction_and_tolerance() {
        let t = tol(0.1, 0.01);
        // Higher is worse: +20 % regresses, -20 % improves, +5 % is within 10 %.
        let m = SummaryMetric::named("max_aliasing");
        assert_eq!(compare_one(m, Some(10.0), Some(12.0), &t).verdict, Verdict::Regressed);
        assert_eq!(compare_one(m, Some(10.0), Some(8.0), &t).verdict, Verdict::Improved);
        assert_eq!(compare_one(m, Some(10.0), Some(10.5), &t).verdict, Verdict::Unchanged);
        assert_eq!(compare_one(m, Some(10.0), Some(11.0), &t).tolerance, 1.0);
        // Lower is worse.
        let m = SummaryMetric::named("cascades_needed");
        assert_eq!(compare_one(m, Some(1.0), Some(0.0), &t).verdict, Verdict::Regressed);
        assert_eq!(compare_one(m, Some(0.0), Some(1.0), &t).verdict, Verdict::Improved);
        // A zero baseline falls back to the absolute tolerance.
        let m = SummaryMetric::named("shimmer_snapped");
        assert_eq!(compare_one(m, Some(0.0), Some(0.005), &t).verdict, Verdict::Unchanged);
        assert_eq!(compare_one(m, Some(0.0), Some(0.02), &t).verdict, Verdict::Regressed);
        // No direction: changed, never regressed.
        let m = SummaryMetric::named("z_hi");
        assert_eq!(compare_one(m, Some(100.0), Some(50.0), &t).verdict, Verdict::Changed);
        assert_eq!(compare_one(m, Some(100.0), Some(101.0), &t).verdict, Verdict::Unchanged);
        let c = compare_one(SummaryMetric::named("mean_aliasing"), Some(2.0), Some(3.0), &t);
        assert_eq!((c.change(), c.relative_change()), (Some(1.0), Some(0.5)));
    }

    #[test]
    fn missing_values_are_reported_not_compared() {
        let t = Tolerances::default();
        let cur = BTreeMap::from([
            (SummaryMetric::named("max_aliasing"), 1.0),
            (SummaryMetric::named("size_jitter"), 0.0),
        ]);
        let base = BTreeMap::from([
            (SummaryMetric::named("max_aliasing"), 1.0),
            (SummaryMetric::named("memory_bytes"), 4.0),
        ]);
        let c = compare(&cur, &base, &t);
        let got: Vec<(SummaryMetric, Verdict)> = c.iter().map(|c| (c.metric, c.verdict)).collect();
        assert_eq!(
            got,
            vec![
                (SummaryMetric::named("max_aliasing"), Verdict::Unchanged),
                (SummaryMetric::named("size_jitter"), Verdict::NotInBaseline),
                (SummaryMetric::named("memory_bytes"), Verdict::NotInCurrent),
            ]
        );
    }

    #[test]
    fn summary_json_reading_accepts_booleans_and_rejects_strings() {
        let v = serde_json::json!({"cascades_needed": true, "max_aliasing": 2.5, "memory_bytes": 64, "name": "x"});
        let m = summary_from_json(&v, "b.json").unwrap();
        assert_eq!(m[&SummaryMetric::named("cascades_needed")], 1.0);
        assert_eq!(m[&SummaryMetric::named("max_aliasing")], 2.5);
        assert_eq!(m[&SummaryMetric::named("memory_bytes")], 64.0);
        assert_eq!(m.len(), 3);
        let e = summary_from_json(&serde_json::json!({"max_aliasing": "2"}), "b.json").unwrap_err();
        assert!(e.to_string().contains("max_aliasing"), "{e}");
        let e = summary_from_json(&serde_json::json!({"other": 1}), "b.json").unwrap_err();
        assert!(e.to_string().contains("none of the summary metrics"), "{e}");
        assert!(summary_from_json(&serde_json::json!([1, 2]), "b.json").is_err());
    }
}
