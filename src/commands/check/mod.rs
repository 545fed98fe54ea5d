//! `csm-lab check`: quality thresholds and regression gates for CI.
//!
//! A thresholds file ([`thresholds`]) holds rules on summary, per-cascade and per-depth
//! metrics ([`metric`]); [`evaluate`] judges them against an analysis (per-depth extremes in
//! closed form, [`depth`]), [`baseline`] compares the summary metrics with an earlier
//! `summary.json`, [`sweep`] does both for sweep rows, and [`report`] holds the outcome, which
//! [`crate::report::check`] and [`crate::report::junit`] render. Exit codes: 0 everything passes, 1 a rule failed or a metric regressed, 2 an error.

pub mod baseline;
pub(crate) mod depth;
pub mod evaluate;
pub(crate) mod init;
pub mod metric;
pub mod report;
pub mod sweep;
pub mod thresholds;

use std::collections::BTreeMap;

use crate::analysis::{Analysis, AnalysisOptions};
use crate::config::Config;
use crate::error::{Error, Result};

pub(crate) use report::{Body, CheckReport};
pub use thresholds::{Rule, Thresholds};

/// What `check` computes: the summary (independent of the options), and the per-cascade
/// light depths a rule may limit; no per-frame rows, density samples or cell flips.
pub fn check_options() -> AnalysisOptions {
    AnalysisOptions {
        light_depth: true,
        seams: true,
        ground_truth: true,
        cost_means: true,
        ..AnalysisOptions::summary_only()
    }
}

/// Judges one analysed configuration: every rule, and the baseline summary if given.
pub(crate) fn check_analysis(
    analysis: &Analysis,
    thresholds: &Thresholds,
    baseline: Option<(&str, &BTreeMap<metric::SummaryMetric, f64>)>,
) -> Result<CheckReport> {
    let results = evaluate::evaluate_all(&thresholds.rules, analysis)?;
    let baseline = baseline.map(|(file, values)| {
        let current: BTreeMap<_, _> = metric::summary_values(&analysis.summary).into_iter().collect();
        report::SummaryBaseline {
            file: file.to_string(),
            comparisons: baseline::compare(&current, values, &thresholds.tolerances),
        }
    });
    Ok(CheckReport {
        config: config_label(&analysis.config),
        name: analysis.config.name.clone(),
        thresholds: thresholds.label.clone(),
        tolerances: thresholds.tolerances.clone(),
        body: Body::Single { results, baseline },
    })
}

/// Judges sweep rows: the rules per row, and the baseline rows if given.
pub(crate) fn check_rows(
    config: &Config,
    rows: &[sweep::SweepRow],
    thresholds: &Thresholds,
    baseline: Option<(&str, &[sweep::SweepRow])>,
    all_rows: bool,
) -> Result<CheckReport> {
    // A rule on a metric no row measured judges nothing: an error, as for one configuration.
    for rule in &thresholds.rules {
        if let thresholds::Target::Summary(m) = rule.target {
            if !rows.is_empty() && rows.iter().all(|r| !r.metrics.contains_key(m.name())) {
                return Err(crate::error::ConfigError::Invalid {
                    location: format!("{}: ", rule.location),
                    key: format!("rule[{}].metric", rule.index),
                    value: format!("\"{}\"", m.name()),
                    allowed: format!(
                        "a metric the sweep rows of {} measure: `{}` was not measured in any row, and a rule on it \
                         would judge nothing; {}, or remove the rule",
                        config.name,
                        m.name(),
                        m.how_to_measure().unwrap_or("it is not a sweep column")
                    ),
                    excerpt: String::new(),
                }
                .into());
            }
        }
    }
    // What the sweep decides is gated; the baseline still compares every row.
    let (gated_rows, gated) = sweep::gated_rows(config, rows.to_vec(), all_rows);
    let reports = sweep::evaluate_rows(&thresholds.rules, &gated_rows);
    let baseline = baseline
        .map(|(file, base)| {
            Ok::<_, Error>(report::SweepBaseline {
                file: file.to_string(),
                comparison: sweep::compare_rows(rows, base, &thresholds.tolerances)?,
            })
        })
        .transpose()?;
    Ok(CheckReport {
        config: config_label(config),
        name: config.name.clone(),
        thresholds: thresholds.label.clone(),
        tolerances: thresholds.tolerances.clone(),
        body: Body::Sweep {
            rows: reports,
            baseline,
            gated,
        },
    })
}

fn config_label(config: &Config) -> String {
    config
        .path
        .as_ref()
        .map_or_else(|| config.name.clone(), |p| p.display().to_string())
}
