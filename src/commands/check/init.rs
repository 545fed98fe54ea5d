//! `check --init`: a thresholds file written from a configuration's current values.
//!
//! Every summary metric the analysis measured, with a worse direction, gets a rule that can
//! fail: today's value plus `headroom` (a fraction of it) for higher-is-worse metrics, minus it
//! for lower-is-worse ones, with a floor of 1e-9 so a metric that reads 0 today stays at 0.
//! Counts (memory, coverage violations) are discrete: their rule is today's value exactly. A
//! fraction already at its worst bound (e.g. `undersampled_fraction` = 1) gets no rule (none
//! could fail), and a fraction's limit stays inside [0, 1] (halfway to the bound when the
//! headroom would reach it). Unmeasured metrics (no ground truth, no geometry, a still light)
//! get no rule: a rule on them is an error of `check`. `shimmer_snapped` and
//! `shimmer_unsnapped` are information (the gate limits `shimmer`, the configured snap mode's
//! value), and positions (`z_lo`, `z_hi`) are never limited. The baseline section names the
//! baseline file written beside it.

use std::fmt::Write as _;

use crate::analysis::Analysis;
use crate::metric::{Direction, SummaryMetric, Value};
use crate::output::short_number;

/// Metrics `--init` does not limit: information only.
const INFORMATION: &[&str] = &["shimmer_snapped", "shimmer_unsnapped"];

/// The absolute room of a real-valued limit.
const FLOOR: f64 = 1e-9;

/// The limit for a metric's current value (None: not limited).
pub(crate) fn limit(m: SummaryMetric, value: Value, headroom: f64) -> Option<(&'static str, String)> {
    if INFORMATION.contains(&m.name()) {
        return None;
    }
    let room = |v: f64| (headroom * v.abs()).max(FLOOR);
    let fraction = m.is_fraction();
    match (m.direction(), value) {
        // Nothing measured: nothing to limit.
        (Direction::Neither, _) | (_, Value::Missing) => None,
        // Discrete: any change is a change (memory_bytes moves in whole maps).
        (Direction::HigherIsWorse, Value::Count(n)) => Some(("max", n.to_string())),
        (Direction::LowerIsWorse, Value::Count(n)) => Some(("min", n.to_string())),
        (Direction::HigherIsWorse, Value::Flag(b)) => Some(("max", u8::from(b).to_string())),
        (Direction::LowerIsWorse, Value::Flag(b)) => Some(("min", u8::from(b).to_string())),
        // A fraction at its worst bound: no limit could fail.
        (Direction::HigherIsWorse, Value::Real(v)) if fraction && v >= 1.0 => None,
        (Direction::LowerIsWorse, Value::Real(v)) if fraction && v <= 0.0 => None,
        (Direction::HigherIsWorse, Value::Real(v)) if fraction => {
            Some(("max", format!("{:e}", (v + room(v)).min((v + 1.0) / 2.0))))
        }
        (Direction::LowerIsWorse, Value::Real(v)) if fraction => {
            Some(("min", format!("{:e}", (v - room(v)).max(v / 2.0))))
        }
        (Direction::HigherIsWorse, Value::Real(v)) => Some(("max", format!("{:e}", v + room(v)))),
        (Direction::LowerIsWorse, Value::Real(v)) => Some(("min", format!("{:e}", v - room(v)))),
    }
}

/// The thresholds file's text.
pub(crate) fn thresholds_text(a: &Analysis, config: &str, baseline_file: &str, headroom: f64) -> String {
    let pct = short_number(headroom * 100.0);
    let mut t = String::new();
    let _ = writeln!(t, "# Quality gate for {config}, written by");
    let _ = writeln!(t, "#   csm-lab check {config} --init <this file> --headroom {headroom}");
    let _ = writeln!(
        t,
        "# Each limit is today's value with {pct} % of room (at least 1e-9; counts exactly), so rounding noise passes and a"
    );
    let _ = writeln!(t, "# change that makes shadows {pct} % worse fails. Run it in CI with:");
    let _ = writeln!(t, "#   csm-lab check {config} --thresholds <this file>");
    let _ = writeln!(
        t,
        "# Every metric: docs/check.md. Edit freely; `--init` again starts over."
    );
    let mut unmeasured = Vec::new();
    for m in SummaryMetric::all() {
        if !m.measured(&a.summary) {
            if m.direction() != Direction::Neither {
                unmeasured.push(m.name());
            }
            continue;
        }
        let v = m.typed(&a.summary);
        let Some((bound, lim)) = limit(m, v, headroom) else {
            continue;
        };
        let _ = writeln!(t, "\n# {} (today {})", m.description(), short_number(v.as_f64()));
        let _ = writeln!(t, "[[rule]]\nmetric = \"{}\"\n{bound} = {lim}", m.name());
    }
    if !unmeasured.is_empty() {
        let _ = writeln!(
            t,
            "\n# Not measured for this config, so not limited (a rule on them is an error): {}.",
            unmeasured.join(", ")
        );
    }
    let _ = writeln!(
        t,
        "\n# Regressions against the baseline recorded beside this file (a summary.json):\n\
         # a metric more than 2 % worse than it fails, even within the limits above."
    );
    let _ = writeln!(
        t,
        "[baseline]\nfile = \"{baseline_file}\"\nrelative = 0.02\nabsolute = 1e-9"
    );
    let _ = writeln!(
        t,
        "# Information, not the configured setting: drift of the other snap mode depends on where\n\
         # the probes land between texels; allow more."
    );
    for m in INFORMATION {
        let _ = writeln!(t, "[baseline.metric.{m}]\nrelative = 0.10");
    }
    t
}
