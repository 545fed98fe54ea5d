//! JUnit XML, the test-report format GitHub Actions (via a reporter action), GitLab
//! (`artifacts:reports:junit`) and Jenkins (`junit` step) display.
//!
//! One `<testsuite>` for the rules (one per configuration with `--sweep`), one `<testcase>`
//! per rule; a failing rule carries a `<failure>` whose message has the numbers, a rule that
//! does not apply carries `<skipped>`. With a baseline, one more suite holds a testcase per
//! compared metric, failing when it regressed. Every text and attribute is escaped, and
//! characters XML 1.0 cannot carry at all are replaced by U+FFFD.

use std::fmt::Write as _;

use super::check::{limit_text, rule_message};
use super::html::escape;
use crate::commands::check::baseline::{Comparison, Verdict};
use crate::commands::check::evaluate::{short, Bound, RuleResult, Status};
use crate::commands::check::report::{Body, CheckReport};

/// A test case to write.
struct Case {
    name: String,
    classname: String,
    outcome: Outcome,
}

enum Outcome {
    Pass,
    Failure { message: String, body: String },
    Skipped { message: String },
}

struct Suite {
    name: String,
    cases: Vec<Case>,
}

impl Suite {
    fn count(&self, f: impl Fn(&Outcome) -> bool) -> usize {
        self.cases.iter().filter(|c| f(&c.outcome)).count()
    }
}

fn is_failure(o: &Outcome) -> bool {
    matches!(o, Outcome::Failure { .. })
}

fn is_skipped(o: &Outcome) -> bool {
    matches!(o, Outcome::Skipped { .. })
}

fn rule_case(r: &RuleResult, classname: &str, thresholds: &str) -> Case {
    let name = format!(
        "rule {}: {} {} ({})",
        r.rule.index,
        r.rule.target.metric_name(),
        limit_text(r),
        r.rule.scope_text()
    );
    let outcome = match r.status {
        Status::Pass => Outcome::Pass,
        Status::NotApplicable => Outcome::Skipped {
            message: rule_message(r),
        },
        Status::Fail => {
            let j = r.judgement.as_ref().expect("a failed rule was judged");
            let bound = match j.bound {
                Bound::Max => "max",
                Bound::Min => "min",
            };
            let mut body = format!(
                "{}\nrule {} ({}) in {thresholds}: {}\nactual {}, {bound} {}, margin {}",
                rule_message(r),
                r.rule.index,
                r.rule.location,
                r.rule.limits_text(),
                j.actual.value,
                j.limit,
                j.margin
            );
            if let Some(d) = j.actual.depth {
                let _ = write!(body, "\nat view depth {d}");
            }
            Outcome::Failure {
                message: rule_message(r),
                body,
            }
        }
    };
    Case {
        name,
        classname: classname.to_string(),
        outcome,
    }
}

fn comparison_case(c: &Comparison, prefix: &str, classname: &str) -> Case {
    let name = format!("{prefix}{}", c.metric.name());
    let numbers = || {
        format!(
            "{}: baseline {} -> current {} (change {}{}, tolerance {})",
            c.metric.name(),
            c.baseline.map_or("-".into(), short),
            c.current.map_or("-".into(), short),
            c.change().map_or("-".into(), short),
            c.relative_change()
                .map_or(String::new(), |r| format!(", {:+.2}%", 100.0 * r)),
            short(c.tolerance)
        )
    };
    let outcome = match c.verdict {
        Verdict::Regressed => Outcome::Failure {
            message: format!("regressed: {}", numbers()),
            body: format!(
                "{} got worse by more than its tolerance ({}).\nbaseline {}, current {}, tolerance {}",
                c.metric.name(),
                c.metric.direction().describe(),
                c.baseline.unwrap_or(0.0),
                c.current.unwrap_or(0.0),
                c.tolerance
            ),
        },
        Verdict::NotInBaseline | Verdict::NotInCurrent => Outcome::Skipped {
            message: format!("{}: {}", c.metric.name(), c.verdict.label()),
        },
        _ => Outcome::Pass,
    };
    Case {
        name,
        classname: classname.to_string(),
        outcome,
    }
}

fn suites(report: &CheckReport) -> Vec<Suite> {
    let class = format!("csm-lab.check.{}", report.name);
    let mut out = Vec::new();
    match &report.body {
        Body::Single { results, baseline } => {
            out.push(Suite {
                name: format!("thresholds {} on {}", report.thresholds, report.config),
                cases: results
                    .iter()
                    .map(|r| rule_case(r, &class, &report.thresholds))
                    .collect(),
            });
            if let Some(b) = baseline {
                out.push(Suite {
                    name: format!("baseline {}", b.file),
                    cases: b
                        .comparisons
                        .iter()
                        .map(|c| comparison_case(c, "", &format!("{class}.baseline")))
                        .collect(),
                });
            }
        }
        Body::Sweep { rows, baseline, .. } => {
            for row in rows {
                out.push(Suite {
                    name: format!("thresholds {} on {}", report.thresholds, row.key.label()),
                    cases: row
                        .results
                        .iter()
                        .map(|r| rule_case(r, &format!("{class}.sweep"), &report.thresholds))
                        .collect(),
                });
            }
            if let Some(b) = baseline {
                let mut cases = Vec::new();
                for row in &b.comparison.matched {
                    let prefix = format!("{}: ", row.key.label());
                    cases.extend(
                        row.comparisons
                            .iter()
                            .map(|c| comparison_case(c, &prefix, &format!("{class}.baseline"))),
                    );
                }
                out.push(Suite {
                    name: format!("baseline {}", b.file),
                    cases,
                });
            }
        }
    }
    out
}

/// The JUnit XML document of a report.
pub fn render(report: &CheckReport) -> String {
    let suites = suites(report);
    let total: usize = suites.iter().map(|s| s.cases.len()).sum();
    let failures: usize = suites.iter().map(|s| s.count(is_failure)).sum();
    let skipped: usize = suites.iter().map(|s| s.count(is_skipped)).sum();
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        x,
        "<testsuites name=\"csm-lab check\" tests=\"{total}\" failures=\"{failures}\" errors=\"0\" skipped=\"{skipped}\" time=\"0\">"
    );
    for s in &suites {
        let _ = writeln!(
            x,
            "  <testsuite name=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"0\" skipped=\"{}\" time=\"0\">",
            escape(&s.name),
            s.cases.len(),
            s.count(is_failure),
            s.count(is_skipped)
        );
        for c in &s.cases {
            let open = format!(
                "    <testcase classname=\"{}\" name=\"{}\" time=\"0\"",
                escape(&c.classname),
                escape(&c.name)
            );
            match &c.outcome {
                Outcome::Pass => {
                    let _ = writeln!(x, "{open}/>");
                }
                Outcome::Skipped { message } => {
                    let _ = writeln!(
                        x,
                        "{open}>\n      <skipped message=\"{}\"/>\n    </testcase>",
                        escape(message)
                    );
                }
                Outcome::Failure { message, body } => {
                    // Newlines in the body are kept as references; parsers give them back.
                    let _ = writeln!(
                        x,
                        "{open}>\n      <failure message=\"{}\" type=\"threshold\">{}</failure>\n    </testcase>",
                        escape(message),
                        escape(body)
                    );
                }
            }
        }
        x.push_str("  </testsuite>\n");
    }
    x.push_str("</testsuites>\n");
    x
}

/// The JUnit document of a `check` that could not run (exit 2): one test case in error, with
/// the message, so a CI step publishing the file never shows an earlier pass.
pub(crate) fn render_error(config: &str, message: &str) -> String {
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    x.push_str(
        "<testsuites name=\"csm-lab check\" tests=\"1\" failures=\"0\" errors=\"1\" skipped=\"0\" time=\"0\">\n",
    );
    let _ = writeln!(
        x,
        "  <testsuite name=\"check {}\" tests=\"1\" failures=\"0\" errors=\"1\" skipped=\"0\" time=\"0\">",
        escape(config)
    );
    let _ = writeln!(
        x,
        "    <testcase classname=\"csm-lab.check\" name=\"check could not run\" time=\"0\">\n      <error message=\"{}\" type=\"error\">exit code 2: {}</error>\n    </testcase>",
        escape(message),
        escape(message)
    );
    x.push_str("  </testsuite>\n</testsuites>\n");
    x
}
