//! Judging rules against an analysis (or a bare set of summary values).
//!
//! A rule may look at many values: every cascade, or a depth range. Against a `max` it judges
//! the largest of them, against a `min` the smallest, and when it has both it reports the
//! side with the smaller margin. The margin is the distance to the limit, positive when the
//! rule passes (`max - actual`, `actual - min`); a value equal to its limit passes.
//!
//! Scenes that need no cascades: summary metrics are all 0 (see [`crate::analysis::Summary`])
//! and are judged as such; per-cascade and per-depth rules are not applicable (there is
//! nothing to measure) and are reported so, never silently passed. A rule
//! `cascades_needed >= 1` makes such a scene fail.
//!
//! Depth ranges: a range partly outside the split range `[z_lo, z_hi]` is evaluated over the
//! overlap, and the result says so; nothing beyond the split range is shadowed, so there is no
//! aliasing to measure there. A range entirely outside it, and a cascade index the config does
//! not have, are errors.

use super::depth;
use super::thresholds::{CascadeSelection, Rule, Target};
use crate::analysis::Analysis;
use crate::error::ConfigError;
use crate::error::{Error, Result};

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Pass,
    Fail,
    /// The rule needs data the subject does not have (see the note).
    NotApplicable,
}

impl Status {
    pub(crate) fn label(self) -> &'static str {
        match self {
            Status::Pass => "PASS",
            Status::Fail => "FAIL",
            Status::NotApplicable => "N/A",
        }
    }
}

/// Which limit the reported value was judged against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    Min,
    Max,
}

/// A value and where it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Located {
    pub value: f64,
    pub cascade: Option<usize>,
    pub depth: Option<f64>,
}

impl Located {
    pub(crate) fn bare(value: f64) -> Self {
        Located {
            value,
            cascade: None,
            depth: None,
        }
    }
}

/// The verdict on one limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Judgement {
    pub bound: Bound,
    pub limit: f64,
    /// The value judged (the largest for a max, the smallest for a min) and where it is.
    pub actual: Located,
    /// `limit - actual` for a max, `actual - limit` for a min: >= 0 passes.
    pub margin: f64,
}

/// The outcome of one rule.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleResult {
    pub rule: Rule,
    pub status: Status,
    /// None when not applicable.
    pub judgement: Option<Judgement>,
    /// Number of cascades a `cascade = "all"` rule looked at.
    pub cascades_examined: Option<usize>,
    /// The depth range actually evaluated by a per-depth rule.
    pub evaluated_range: Option<(f64, f64)>,
    /// Why a rule is not applicable, or that its depth range was clipped.
    pub note: Option<String>,
}

impl RuleResult {
    pub(crate) fn not_applicable(rule: &Rule, why: impl Into<String>) -> Self {
        RuleResult {
            rule: rule.clone(),
            status: Status::NotApplicable,
            judgement: None,
            cascades_examined: None,
            evaluated_range: None,
            note: Some(why.into()),
        }
    }

    /// "summary", "cascade 2", "cascade 3 (worst of 4)", "depth 5..60 at 9.86 (cascade 1)".
    pub(crate) fn place(&self) -> String {
        let j = self.judgement.as_ref();
        match (&self.rule.target, j) {
            (_, None) => self.rule.scope_text(),
            (Target::Summary(_), _) => "summary".to_string(),
            (Target::Cascade(_, CascadeSelection::One(i)), _) => format!("cascade {i}"),
            (Target::Cascade(_, CascadeSelection::All), Some(j)) => format!(
                "cascade {} (worst of {})",
                j.actual.cascade.unwrap_or(0),
                self.cascades_examined.unwrap_or(0)
            ),
            (Target::Depth(..), Some(j)) => {
                let (lo, hi) = self.evaluated_range.unwrap_or((0.0, 0.0));
                format!(
                    "depth {}..{} at {} (cascade {})",
                    short(lo),
                    short(hi),
                    short(j.actual.depth.unwrap_or(0.0)),
                    j.actual.cascade.unwrap_or(0)
                )
            }
        }
    }
}

/// A number with 6 significant digits and no trailing zeros, for tables and messages.
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if v.fract() == 0.0 && v.abs() < 1e15 {
        // Counts and byte sizes read best whole.
        return format!("{}", v as i64);
    }
    let mag = v.abs().log10().floor() as i32;
    if (-4..6).contains(&mag) {
        let decimals = (5 - mag).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        let s = format!("{v:.5e}");
        // "1.50000e-7" -> "1.5e-7"
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            _ => s,
        }
    }
}

/// Judges a rule's limits given the largest and the smallest value it looks at.
pub(crate) fn judge(rule: &Rule, largest: Located, smallest: Located) -> (Status, Judgement) {
    let mut checks = Vec::with_capacity(2);
    if let Some(max) = rule.max {
        checks.push(Judgement {
            bound: Bound::Max,
            limit: max,
            actual: largest,
            margin: max - largest.value,
        });
    }
    if let Some(min) = rule.min {
        checks.push(Judgement {
            bound: Bound::Min,
            limit: min,
            actual: smallest,
            margin: smallest.value - min,
        });
    }
    // The tighter side; the max side on ties. NaN margins (never expected) count as failing.
    let j = checks
        .into_iter()
        .reduce(|a, b| if b.margin < a.margin { b } else { a })
        .expect("a validated rule has a limit");
    let status = if j.margin >= 0.0 { Status::Pass } else { Status::Fail };
    (status, j)
}

/// Judges a rule that looks at one value.
pub(crate) fn judge_value(rule: &Rule, v: Located) -> RuleResult {
    let (status, j) = judge(rule, v, v);
    RuleResult {
        rule: rule.clone(),
        status,
        judgement: Some(j),
        cascades_examined: None,
        evaluated_range: None,
        note: None,
    }
}

/// Evaluates one rule against an analysis. Errors: a cascade index the config does not have,
/// a depth range entirely outside the split range.
pub fn evaluate(rule: &Rule, a: &Analysis) -> Result<RuleResult> {
    let no_cascades = "no cascades: the scene is not visible within the shadow distance";
    match rule.target {
        // A rule on a metric this analysis did not measure cannot be judged: passing it on a
        // 0 would hide a gate that checks nothing.
        Target::Summary(m) if !m.measured(&a.summary) => Err(unmeasured(rule, m, &a.config.name)),
        Target::Summary(m) => Ok(judge_value(rule, Located::bare(m.value(&a.summary)))),
        Target::Cascade(m, _) if a.cascades.iter().any(|c| !m.measured(c)) => Err(Error::from(ConfigError::Invalid {
            location: format!("{}: ", rule.location),
            key: format!("rule[{}].metric", rule.index),
            value: format!("\"{}\"", m.name()),
            allowed: format!(
                "a metric the analysis of {} measures: the per-cascade `{}` was not measured, and a rule on it \
                 would judge nothing; {}, or remove the rule",
                a.config.name,
                m.name(),
                m.how_to_measure()
            ),
            excerpt: String::new(),
        })),
        Target::Cascade(..) | Target::Depth(..) if !a.summary.cascades_needed => {
            Ok(RuleResult::not_applicable(rule, no_cascades))
        }
        Target::Cascade(m, CascadeSelection::One(i)) => {
            let count = a.cascades.len();
            // A rule written for a scene with more cascades does not apply to this one: it is
            // skipped with a note (a scene with fewer cascades is not an error of the gate).
            let Some(c) = a.cascades.get(i) else {
                return Ok(RuleResult::not_applicable(
                    rule,
                    format!(
                        "skipped: {} has {count} cascade{} (indices 0..={}), the rule names cascade {i}",
                        a.config.name,
                        if count == 1 { "" } else { "s" },
                        count.saturating_sub(1)
                    ),
                ));
            };
            let v = Located {
                value: m.value(c),
                cascade: Some(i),
                depth: None,
            };
            Ok(judge_value(rule, v))
        }
        Target::Cascade(m, CascadeSelection::All) => {
            let values: Vec<Located> = a
                .cascades
                .iter()
                .map(|c| Located {
                    value: m.value(c),
                    cascade: Some(c.cascade),
                    depth: None,
                })
                .collect();
            // The first cascade on ties, so the report is deterministic.
            let largest = values
                .iter()
                .copied()
                .reduce(|x, y| if y.value > x.value { y } else { x })
                .expect("cascades needed implies at least one");
            let smallest = values
                .iter()
                .copied()
                .reduce(|x, y| if y.value < x.value { y } else { x })
                .expect("cascades needed implies at least one");
            let (status, j) = judge(rule, largest, smallest);
            Ok(RuleResult {
                rule: rule.clone(),
                status,
                judgement: Some(j),
                cascades_examined: Some(values.len()),
                evaluated_range: None,
                note: None,
            })
        }
        Target::Depth(m, range) => {
            let rig = a.rig().expect("cascades needed implies a rig");
            let (z_lo, z_hi) = (a.summary.z_lo, a.summary.z_hi);
            let (lo, hi) = range.unwrap_or((z_lo, z_hi));
            let (elo, ehi) = (lo.max(z_lo), hi.min(z_hi));
            if elo > ehi {
                return Err(Error::from(ConfigError::Invalid {
                    location: format!("{}: ", rule.scope_location.as_ref().unwrap_or(&rule.location)),
                    key: format!("rule[{}].depth", rule.index),
                    value: format!("[{lo}, {hi}]"),
                    allowed: format!(
                        "a range that overlaps the split range [{z_lo}, {z_hi}] of {} (nothing outside it is shadowed)",
                        a.config.name
                    ),
                    excerpt: String::new(),
                }));
            }
            let note = ((elo, ehi) != (lo, hi)).then(|| {
                format!(
                    "depth [{}, {}] clipped to the split range [{}, {}]",
                    short(lo),
                    short(hi),
                    short(z_lo),
                    short(z_hi)
                )
            });
            let texel: Vec<f64> = a.cascades.iter().map(|c| c.texel_size).collect();
            let k = rig.lens.pixels_per_unit_slope(a.config.screen.height);
            let e = depth::extremes(m, &rig.splits, &texel, k, elo, ehi);
            let loc = |x: depth::DepthExtreme| Located {
                value: x.value,
                cascade: Some(x.cascade),
                depth: Some(x.depth),
            };
            let (status, j) = judge(rule, loc(e.max), loc(e.min));
            Ok(RuleResult {
                rule: rule.clone(),
                status,
                judgement: Some(j),
                cascades_examined: None,
                evaluated_range: Some((elo, ehi)),
                note,
            })
        }
    }
}

/// The error of a rule on a summary metric `config` did not measure: the rule, its place and
/// how to measure the metric.
fn unmeasured(rule: &Rule, m: crate::metric::SummaryMetric, config: &str) -> Error {
    Error::from(ConfigError::Invalid {
        location: format!("{}: ", rule.location),
        key: format!("rule[{}].metric", rule.index),
        value: format!("\"{}\"", m.name()),
        allowed: format!(
            "a metric the analysis of {config} measures: `{}` was not measured, and a rule on it would judge \
             nothing; {}, or remove the rule",
            m.name(),
            m.how_to_measure().unwrap_or("it is not measured for this config")
        ),
        excerpt: String::new(),
    })
}

/// Evaluates every rule, in file order.
pub(crate) fn evaluate_all(rules: &[Rule], a: &Analysis) -> Result<Vec<RuleResult>> {
    rules.iter().map(|r| evaluate(r, a)).collect()
}

/// Evaluates a rule against bare summary values, looked up by metric name (a sweep row).
/// Per-cascade and per-depth rules are not applicable; so is a summary rule whose metric the
/// values lack.
pub(crate) fn evaluate_values(rule: &Rule, values: &std::collections::BTreeMap<&'static str, f64>) -> RuleResult {
    match rule.target {
        Target::Summary(m) => match values.get(m.name()) {
            Some(&v) => judge_value(rule, Located::bare(v)),
            None => RuleResult::not_applicable(rule, format!("the row has no `{}` value", m.name())),
        },
        Target::Cascade(..) => RuleResult::not_applicable(
            rule,
            "a per-cascade rule needs the cascades, which a sweep row does not have",
        ),
        Target::Depth(..) => RuleResult::not_applicable(
            rule,
            "a per-depth rule needs the splits and texel sizes, which a sweep row does not have",
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::check::metric::{CascadeMetric, DepthMetric};
    use crate::metric::SummaryMetric;

    fn rule(target: Target, min: Option<f64>, max: Option<f64>) -> Rule {
        Rule {
            index: 1,
            target,
            min,
            max,
            location: "t.toml:1:1".into(),
            scope_location: None,
        }
    }

    #[test]
    fn judging_picks_the_tighter_limit_and_signs_the_margin() {
        let r = rule(
            Target::Summary(SummaryMetric::named("max_aliasing")),
            Some(1.0),
            Some(10.0),
        );
        let (s, j) = judge(&r, Located::bare(9.0), Located::bare(9.0));
        assert_eq!((s, j.bound, j.margin), (Status::Pass, Bound::Max, 1.0));
        let (s, j) = judge(&r, Located::bare(2.0), Located::bare(2.0));
        assert_eq!((s, j.bound, j.margin), (Status::Pass, Bound::Min, 1.0));
        let (s, j) = judge(&r, Located::bare(12.0), Located::bare(0.5));
        assert_eq!((s, j.bound, j.margin), (Status::Fail, Bound::Max, -2.0));
        let (s, j) = judge(&r, Located::bare(10.0), Located::bare(10.0));
        assert_eq!((s, j.margin), (Status::Pass, 0.0), "equal to the limit passes");
        let r = rule(
            Target::Summary(SummaryMetric::named("cascades_needed")),
            Some(1.0),
            None,
        );
        let (s, j) = judge(&r, Located::bare(0.0), Located::bare(0.0));
        assert_eq!((s, j.bound, j.limit, j.margin), (Status::Fail, Bound::Min, 1.0, -1.0));
    }

    #[test]
    fn sweep_values_judge_only_summary_rules() {
        let values = std::collections::BTreeMap::from([("max_aliasing", 3.0)]);
        let r = evaluate_values(
            &rule(Target::Summary(SummaryMetric::named("max_aliasing")), None, Some(2.0)),
            &values,
        );
        assert_eq!(r.status, Status::Fail);
        assert_eq!(r.judgement.unwrap().margin, -1.0);
        let r = evaluate_values(
            &rule(Target::Summary(SummaryMetric::named("size_jitter")), None, Some(2.0)),
            &values,
        );
        assert_eq!(r.status, Status::NotApplicable);
        let r = evaluate_values(
            &rule(
                Target::Cascade(CascadeMetric::named("texel_size"), CascadeSelection::All),
                None,
                Some(2.0),
            ),
            &values,
        );
        assert_eq!(r.status, Status::NotApplicable);
        let r = evaluate_values(
            &rule(Target::Depth(DepthMetric::Aliasing, None), None, Some(2.0)),
            &values,
        );
        assert_eq!(r.status, Status::NotApplicable);
    }

    #[test]
    fn short_numbers_keep_six_significant_digits() {
        assert_eq!(short(106.1151224345197), "106.115");
        assert_eq!(short(0.011345480463455564), "0.0113455");
        assert_eq!(short(2.0), "2");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(67108864.0), "67108864");
        assert_eq!(short(1234567.5), "1.23457e6");
        assert_eq!(short(1.5e-7), "1.5e-7");
        assert_eq!(short(-3.25), "-3.25");
    }
}
