//! The outcome of a check: rule results, baseline comparisons and their counts. The report
//! layer renders it ([`crate::report::check`], [`crate::report::junit`]).

use super::baseline::{Comparison, Tolerances, Verdict};
use super::evaluate::{RuleResult, Status};
use super::sweep::{RowReport, SweepComparison};

/// A single configuration's baseline comparison.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SummaryBaseline {
    pub file: String,
    pub comparisons: Vec<Comparison>,
}

/// A sweep table's baseline comparison.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SweepBaseline {
    pub file: String,
    pub comparison: SweepComparison,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Body {
    /// One configuration: every rule, and optionally a summary.json baseline.
    Single {
        results: Vec<RuleResult>,
        baseline: Option<SummaryBaseline>,
    },
    /// Sweep rows: the rules per configuration, and optionally a sweep.csv baseline.
    Sweep {
        rows: Vec<RowReport>,
        baseline: Option<SweepBaseline>,
        /// Which rows the rules judge, in one sentence ([`super::sweep::gated_rows`]).
        gated: String,
    },
}

/// Everything a check found.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CheckReport {
    /// The config file (or its name).
    pub config: String,
    /// The config's name (file stem).
    pub name: String,
    pub thresholds: String,
    pub tolerances: Tolerances,
    pub body: Body,
}

/// Counts over the whole report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counts {
    pub rules: usize,
    pub pass: usize,
    pub fail: usize,
    pub not_applicable: usize,
    pub regressed: usize,
    pub improved: usize,
}

fn count_results<'a>(c: &mut Counts, results: impl IntoIterator<Item = &'a RuleResult>) {
    for r in results {
        c.rules += 1;
        match r.status {
            Status::Pass => c.pass += 1,
            Status::Fail => c.fail += 1,
            Status::NotApplicable => c.not_applicable += 1,
        }
    }
}

fn count_comparisons<'a>(c: &mut Counts, comparisons: impl IntoIterator<Item = &'a Comparison>) {
    for x in comparisons {
        match x.verdict {
            Verdict::Regressed => c.regressed += 1,
            Verdict::Improved => c.improved += 1,
            _ => {}
        }
    }
}

impl CheckReport {
    /// Rule results summed over every configuration, and baseline verdicts.
    pub(crate) fn counts(&self) -> Counts {
        let mut c = Counts::default();
        match &self.body {
            Body::Single { results, baseline } => {
                count_results(&mut c, results);
                if let Some(b) = baseline {
                    count_comparisons(&mut c, &b.comparisons);
                }
            }
            Body::Sweep { rows, baseline, .. } => {
                count_results(&mut c, rows.iter().flat_map(|r| &r.results));
                if let Some(b) = baseline {
                    count_comparisons(&mut c, b.comparison.matched.iter().flat_map(|r| &r.comparisons));
                }
            }
        }
        c
    }

    /// No rule failed and nothing regressed (exit code 0).
    pub(crate) fn passed(&self) -> bool {
        let c = self.counts();
        c.fail == 0 && c.regressed == 0
    }
}
