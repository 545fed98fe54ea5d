//! The thresholds file: `[[rule]]` entries and the `[baseline]` tolerances.
//!
//! ```toml
//! [[rule]]
//! metric = "max_aliasing"      # a summary metric
//! max = 8.0
//! [[rule]]
//! metric = "texel_size"        # a per-cascade metric: one cascade, or all (the default)
//! cascade = 0                  # or "all"
//! max = 0.02
//! [[rule]]
//! metric = "aliasing"          # a per-depth metric over [lo, hi] (default: the split range)
//! depth = [5.0, 60.0]
//! max = 2.0
//!
//! [baseline]
//! relative = 0.02
//! absolute = 1e-9
//! [baseline.metric.max_aliasing]
//! relative = 0.05
//! ```
//!
//! Unknown keys, wrong types and TOML syntax errors carry the line and column; values that
//! parse but are not allowed (an unknown metric, `min > max`, a non-finite limit) name the key
//! as `rule[N].key` (1-based, in file order) with its line and column.

use crate::error::ConfigError;
use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use super::baseline::{Tolerance, Tolerances};
use super::metric::{all_names, CascadeMetric, DepthMetric, SummaryMetric};
use crate::config::toml_error;
use crate::error::{Error, Result};

/// Which cascades a per-cascade rule looks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CascadeSelection {
    One(usize),
    /// Every cascade; the rule reports the worst one.
    All,
}

/// What a rule measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    Summary(SummaryMetric),
    Cascade(CascadeMetric, CascadeSelection),
    /// A per-depth metric over `[lo, hi]`, or over the whole split range when None.
    Depth(DepthMetric, Option<(f64, f64)>),
}

impl Target {
    /// "summary", "cascade" or "depth".
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            Target::Summary(_) => "summary",
            Target::Cascade(..) => "cascade",
            Target::Depth(..) => "depth",
        }
    }

    pub fn metric_name(&self) -> &'static str {
        match self {
            Target::Summary(m) => m.name(),
            Target::Cascade(m, _) => m.name(),
            Target::Depth(m, _) => m.name(),
        }
    }
}

/// One validated rule: at least one of `min` and `max`, both finite, `min <= max`.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    /// 1-based position in the file.
    pub index: usize,
    pub target: Target,
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// `file:line:column` of the rule's `[[rule]]` header, for messages. Shared, not copied:
    /// every row of a sweep's report holds its rules.
    pub location: std::sync::Arc<str>,
    /// `file:line:column` of the rule's `cascade` or `depth` value, when written (errors that
    /// depend on the analysed config point there).
    pub scope_location: Option<std::sync::Arc<str>>,
}

impl Rule {
    /// The scope as written: "summary", "cascade 0", "every cascade", "depth 5..60",
    /// "the split range". Stable across runs (JUnit test names use it).
    pub(crate) fn scope_text(&self) -> String {
        match self.target {
            Target::Summary(_) => "summary".to_string(),
            Target::Cascade(_, CascadeSelection::One(i)) => format!("cascade {i}"),
            Target::Cascade(_, CascadeSelection::All) => "every cascade".to_string(),
            Target::Depth(_, Some((lo, hi))) => format!("depth {lo}..{hi}"),
            Target::Depth(_, None) => "the split range".to_string(),
        }
    }

    /// `min <= metric <= max` as written, e.g. `texel_size <= 0.02`.
    pub(crate) fn limits_text(&self) -> String {
        let name = self.target.metric_name();
        match (self.min, self.max) {
            (Some(lo), Some(hi)) => format!("{lo} <= {name} <= {hi}"),
            (Some(lo), None) => format!("{name} >= {lo}"),
            (None, Some(hi)) => format!("{name} <= {hi}"),
            (None, None) => name.to_string(),
        }
    }
}

/// A parsed thresholds file.
#[derive(Debug, Clone, PartialEq)]
pub struct Thresholds {
    /// Where it was read from (for messages).
    pub label: String,
    pub rules: Vec<Rule>,
    pub tolerances: Tolerances,
    /// `[baseline] file`, resolved against the thresholds file's directory.
    pub baseline_file: Option<std::path::PathBuf>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawThresholds {
    #[serde(default)]
    rule: Vec<Spanned<RawRule>>,
    baseline: Option<RawBaseline>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRule {
    metric: Spanned<String>,
    min: Option<Spanned<f64>>,
    max: Option<Spanned<f64>>,
    cascade: Option<Spanned<toml::Value>>,
    depth: Option<Spanned<Vec<f64>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBaseline {
    /// The baseline file (a `summary.json`, or with `--sweep` a `sweep.csv`), relative to the
    /// thresholds file; `--baseline` overrides it.
    file: Option<String>,
    relative: Option<Spanned<f64>>,
    absolute: Option<Spanned<f64>>,
    #[serde(default)]
    metric: BTreeMap<Spanned<String>, RawTolerance>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTolerance {
    relative: Option<Spanned<f64>>,
    absolute: Option<Spanned<f64>>,
}

/// Builds errors that point at a span of the thresholds text.
struct At<'a> {
    label: &'a str,
    text: &'a str,
    /// Byte offset of each line's start: a location is a binary search, so a file of many
    /// rules is read in O(n log n), not O(n²).
    line_starts: Vec<usize>,
}

impl<'a> At<'a> {
    fn new(label: &'a str, text: &'a str) -> At<'a> {
        let line_starts = std::iter::once(0)
            .chain(text.match_indices('\n').map(|(i, _)| i + 1))
            .collect();
        At {
            label,
            text,
            line_starts,
        }
    }

    fn location(&self, span: std::ops::Range<usize>) -> String {
        let offset = span.start.min(self.text.len());
        let line = self.line_starts.partition_point(|&s| s <= offset).max(1);
        let start = self.line_starts[line - 1];
        let column = self.text.get(start..offset).map_or(1, |t| t.chars().count() + 1);
        format!("{}:{line}:{column}", self.label)
    }

    fn invalid(&self, span: std::ops::Range<usize>, key: &str, value: impl std::fmt::Display, allowed: &str) -> Error {
        Error::from(ConfigError::Invalid {
            location: format!("{}: ", self.location(span.clone())),
            key: key.to_string(),
            value: value.to_string(),
            allowed: allowed.to_string(),
            excerpt: crate::config::excerpt(self.text, span),
        })
    }

    fn finite(&self, v: &Spanned<f64>, key: &str) -> Result<f64> {
        let x = *v.get_ref();
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(v.span(), key, x, "a finite number"))
        }
    }

    fn non_negative(&self, v: &Spanned<f64>, key: &str) -> Result<f64> {
        let x = self.finite(v, key)?;
        if x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(v.span(), key, x, "a finite number >= 0"))
        }
    }
}

/// Most `[[rule]]` entries a thresholds file may hold (checked before any is validated).
pub const MAX_RULES: usize = 10_000;

impl Thresholds {
    pub fn load(path: &Path) -> Result<Thresholds> {
        let text = crate::config::read_bounded(path, crate::config::MAX_TEXT_FILE_BYTES, "a thresholds file")?;
        let mut t = Thresholds::from_toml_str(&text, &path.display().to_string())?;
        if let Some(f) = t.baseline_file.take() {
            let dir = path.parent().unwrap_or(Path::new(""));
            t.baseline_file = Some(if f.is_relative() { dir.join(f) } else { f });
        }
        Ok(t)
    }

    /// Parses and validates thresholds text; `label` names the source in messages.
    pub fn from_toml_str(text: &str, label: &str) -> Result<Thresholds> {
        let raw: RawThresholds = toml::from_str(text).map_err(|e| toml_error(label, text, &e))?;
        if raw.rule.len() > MAX_RULES {
            return Err(ConfigError::Invalid {
                location: format!("{label}: "),
                key: "rule".to_string(),
                value: format!("{} rules", raw.rule.len()),
                allowed: format!("at most {MAX_RULES} [[rule]] entries"),
                excerpt: String::new(),
            }
            .into());
        }
        let at = At::new(label, text);
        let rules = raw
            .rule
            .iter()
            .enumerate()
            .map(|(i, r)| rule(&at, i + 1, r))
            .collect::<Result<Vec<_>>>()?;
        let tolerances = match &raw.baseline {
            Some(b) => tolerances(&at, b)?,
            None => Tolerances::default(),
        };
        Ok(Thresholds {
            baseline_file: raw
                .baseline
                .as_ref()
                .and_then(|b| b.file.as_ref())
                .map(std::path::PathBuf::from),
            label: label.to_string(),
            rules,
            tolerances,
        })
    }
}

fn unknown_metric(at: &At<'_>, span: std::ops::Range<usize>, key: &str, name: &str, names: &[&str]) -> Error {
    let suggestion = crate::suggest::metric_suggestion(name, names).unwrap_or("max_aliasing");
    at.invalid(
        span,
        key,
        format!("{name:?}"),
        &format!(
            "a known metric; did you mean \"{suggestion}\"? Known metrics: {}",
            names.join(", ")
        ),
    )
}

fn rule(at: &At<'_>, index: usize, spanned: &Spanned<RawRule>) -> Result<Rule> {
    let r = spanned.get_ref();
    let key = |k: &str| format!("rule[{index}].{k}");
    let name = r.metric.get_ref().as_str();
    let summary = SummaryMetric::from_name(name);
    let cascade = CascadeMetric::from_name(name);
    let depth = DepthMetric::from_name(name);
    if summary.is_none() && cascade.is_none() && depth.is_none() {
        return Err(unknown_metric(at, r.metric.span(), &key("metric"), name, &all_names()));
    }

    let selection = match &r.cascade {
        None => None,
        Some(v) => {
            let allowed = "a cascade index (0 is the nearest) or \"all\"";
            Some(match v.get_ref() {
                toml::Value::Integer(i) if *i >= 0 => CascadeSelection::One(*i as usize),
                toml::Value::String(s) if s == "all" => CascadeSelection::All,
                other => return Err(at.invalid(v.span(), &key("cascade"), other, allowed)),
            })
        }
    };
    let range = match &r.depth {
        None => None,
        Some(v) => {
            let d = v.get_ref();
            let allowed = "[lo, hi]: two finite view depths with 0 < lo <= hi";
            let ok = d.len() == 2 && d.iter().all(|x| x.is_finite()) && d[0] > 0.0 && d[0] <= d[1];
            if !ok {
                return Err(at.invalid(v.span(), &key("depth"), format!("{d:?}"), allowed));
            }
            Some((d[0], d[1]))
        }
    };

    let target = if let Some(m) = depth {
        if let Some(c) = &r.cascade {
            return Err(at.invalid(
                c.span(),
                &key("cascade"),
                c.get_ref(),
                &format!("no `cascade` on the per-depth metric \"{name}\": limit a depth range with depth = [lo, hi]"),
            ));
        }
        Target::Depth(m, range)
    } else {
        if let Some(d) = &r.depth {
            return Err(at.invalid(
                d.span(),
                &key("depth"),
                format!("{:?}", d.get_ref()),
                &format!(
                    "no `depth` on \"{name}\", which is not a function of depth (the per-depth metrics are {})",
                    DepthMetric::ALL.map(|m| format!("\"{}\"", m.name())).join(" and ")
                ),
            ));
        }
        match (summary, cascade, selection) {
            // Without `cascade`, a name that is both a summary and a per-cascade metric
            // (max_aliasing, coverage_violations) means the summary one.
            (Some(m), _, None) => Target::Summary(m),
            (_, Some(m), sel) => Target::Cascade(m, sel.unwrap_or(CascadeSelection::All)),
            (Some(_), None, Some(_)) => {
                let c = r.cascade.as_ref().expect("a selection comes from `cascade`");
                return Err(at.invalid(
                    c.span(),
                    &key("cascade"),
                    c.get_ref(),
                    &format!("no `cascade` on the summary metric \"{name}\", which has one value per configuration"),
                ));
            }
            (None, None, _) => unreachable!("unknown names were rejected above"),
        }
    };

    let min = r.min.as_ref().map(|v| at.finite(v, &key("min"))).transpose()?;
    let max = r.max.as_ref().map(|v| at.finite(v, &key("max"))).transpose()?;
    match (min, max) {
        (None, None) => {
            return Err(at.invalid(
                spanned.span(),
                &format!("rule[{index}]"),
                format!("metric = {name:?} without a limit"),
                "a rule with `min`, `max` or both",
            ))
        }
        (Some(lo), Some(hi)) if lo > hi => {
            let span = r.max.as_ref().expect("max").span();
            return Err(at.invalid(span, &key("max"), hi, &format!("a number >= rule[{index}].min ({lo})")));
        }
        _ => {}
    }
    let scope_span = r
        .cascade
        .as_ref()
        .map(|c| c.span())
        .or_else(|| r.depth.as_ref().map(|d| d.span()));
    Ok(Rule {
        index,
        target,
        min,
        max,
        location: at.location(spanned.span()).into(),
        scope_location: scope_span.map(|s| at.location(s).into()),
    })
}

fn tolerance(at: &At<'_>, prefix: &str, raw: &RawTolerance, inherit: Tolerance) -> Result<Tolerance> {
    Ok(Tolerance {
        relative: match &raw.relative {
            Some(v) => at.non_negative(v, &format!("{prefix}.relative"))?,
            None => inherit.relative,
        },
        absolute: match &raw.absolute {
            Some(v) => at.non_negative(v, &format!("{prefix}.absolute"))?,
            None => inherit.absolute,
        },
    })
}

fn tolerances(at: &At<'_>, b: &RawBaseline) -> Result<Tolerances> {
    let top = RawTolerance {
        relative: b.relative.clone(),
        absolute: b.absolute.clone(),
    };
    let default = tolerance(at, "baseline", &top, Tolerances::default().default)?;
    let summary_names: Vec<&str> = SummaryMetric::all().map(|m| m.name()).collect();
    let mut per_metric = BTreeMap::new();
    for (name, raw) in &b.metric {
        let Some(m) = SummaryMetric::from_name(name.get_ref()) else {
            let key = format!("baseline.metric.{}", name.get_ref());
            let mut err = unknown_metric(at, name.span(), &key, name.get_ref(), &summary_names);
            if let Error::Config(ConfigError::Invalid { allowed, .. }) = &mut err {
                *allowed = format!("{allowed} (a baseline compares summary metrics only)");
            }
            return Err(err);
        };
        let t = tolerance(at, &format!("baseline.metric.{}", m.name()), raw, default)?;
        per_metric.insert(m, t);
    }
    Ok(Tolerances { default, per_metric })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Thresholds> {
        Thresholds::from_toml_str(text, "t.toml")
    }

    fn err(text: &str) -> String {
        parse(text).expect_err(text).to_string()
    }

    #[test]
    fn every_rule_kind_parses_with_its_target() {
        let t = parse(
            r#"
[[rule]]
metric = "max_aliasing"
max = 8
[[rule]]
metric = "max_aliasing"
cascade = 2
min = 0.5
max = 9.5
[[rule]]
metric = "texel_size"
max = 0.02
[[rule]]
metric = "coverage_violations"
cascade = "all"
max = 0
[[rule]]
metric = "aliasing"
depth = [5.0, 60]
max = 2.0
[[rule]]
metric = "texels_per_pixel"
min = 0.25
"#,
        )
        .unwrap();
        let targets: Vec<Target> = t.rules.iter().map(|r| r.target).collect();
        assert_eq!(
            targets,
            vec![
                Target::Summary(SummaryMetric::named("max_aliasing")),
                Target::Cascade(CascadeMetric::named("max_aliasing"), CascadeSelection::One(2)),
                Target::Cascade(CascadeMetric::named("texel_size"), CascadeSelection::All),
                Target::Cascade(CascadeMetric::named("coverage_violations"), CascadeSelection::All),
                Target::Depth(DepthMetric::Aliasing, Some((5.0, 60.0))),
                Target::Depth(DepthMetric::TexelsPerPixel, None),
            ]
        );
        assert_eq!((t.rules[1].min, t.rules[1].max), (Some(0.5), Some(9.5)));
        assert_eq!(t.rules[0].max, Some(8.0));
        assert_eq!(&*t.rules[2].location, "t.toml:10:1");
        assert_eq!(t.tolerances, Tolerances::default());
    }

    #[test]
    fn baseline_tolerances_inherit_the_defaults() {
        let t = parse(
            r#"
[baseline]
relative = 0.1
absolute = 0.5
[baseline.metric.max_aliasing]
relative = 0.3
[baseline.metric.memory_bytes]
absolute = 0
"#,
        )
        .unwrap();
        let tol = &t.tolerances;
        assert_eq!(
            tol.default,
            Tolerance {
                relative: 0.1,
                absolute: 0.5
            }
        );
        assert_eq!(
            tol.for_metric(SummaryMetric::named("max_aliasing")),
            Tolerance {
                relative: 0.3,
                absolute: 0.5
            }
        );
        assert_eq!(
            tol.for_metric(SummaryMetric::named("memory_bytes")),
            Tolerance {
                relative: 0.1,
                absolute: 0.0
            }
        );
        assert_eq!(tol.for_metric(SummaryMetric::named("mean_aliasing")), tol.default);
    }

    #[test]
    fn bad_rules_name_the_key_and_the_position() {
        let e = err("[[rule]]\nmetric = \"max_alising\"\nmax = 1\n");
        assert!(
            e.contains("t.toml:2:10") && e.contains("rule[1].metric") && e.contains("did you mean \"max_aliasing\""),
            "{e}"
        );
        let e = err("[[rule]]\nmetric = \"max_aliasing\"\nmaxx = 1\n");
        assert!(e.contains("t.toml:3:1") && e.contains("maxx"), "{e}");
        let e = err("[[rule]]\nmetric = \"max_aliasing\"\n");
        assert!(
            e.contains("rule[1]") && e.contains("min") && e.contains("t.toml:1:1"),
            "{e}"
        );
        let e = err("[[rule]]\nmetric = \"max_aliasing\"\nmin = 3\nmax = 2\n");
        assert!(e.contains("rule[1].max") && e.contains("t.toml:4:7"), "{e}");
        let e = err("[[rule]]\nmetric = \"max_aliasing\"\nmax = nan\n");
        assert!(e.contains("rule[1].max") && e.contains("finite"), "{e}");
        let e = err("[[rule]]\nmetric = \"texel_size\"\ncascade = -1\nmax = 1\n");
        assert!(e.contains("rule[1].cascade") && e.contains("-1"), "{e}");
        let e = err("[[rule]]\nmetric = \"texel_size\"\ncascade = \"first\"\nmax = 1\n");
        assert!(e.contains("rule[1].cascade") && e.contains("\"all\""), "{e}");
        let e = err("[[rule]]\nmetric = \"aliasing\"\ndepth = [5.0]\nmax = 1\n");
        assert!(e.contains("rule[1].depth") && e.contains("t.toml:3:9"), "{e}");
        let e = err("[[rule]]\nmetric = \"aliasing\"\ndepth = [9.0, 5.0]\nmax = 1\n");
        assert!(e.contains("rule[1].depth") && e.contains("lo <= hi"), "{e}");
        let e = err("[[rule]]\nmetric = \"aliasing\"\ncascade = 1\nmax = 1\n");
        assert!(e.contains("rule[1].cascade") && e.contains("depth = [lo, hi]"), "{e}");
        let e = err("[[rule]]\nmetric = \"mean_aliasing\"\ncascade = 1\nmax = 1\n");
        assert!(e.contains("rule[1].cascade") && e.contains("summary metric"), "{e}");
        let e = err("[[rule]]\nmetric = \"texel_size\"\ndepth = [1, 2]\nmax = 1\n");
        assert!(e.contains("rule[1].depth") && e.contains("\"aliasing\""), "{e}");
        let e = err("[baseline]\nrelative = -0.1\n");
        assert!(e.contains("baseline.relative") && e.contains(">= 0"), "{e}");
        let e = err("[baseline.metric.texel_size]\nrelative = 0.1\n");
        assert!(
            e.contains("baseline.metric.texel_size") && e.contains("summary metrics only"),
            "{e}"
        );
        let e = err("[baseline.metric.max_aliasing]\nrelativ = 0.1\n");
        assert!(e.contains("t.toml:2:1") && e.contains("relativ"), "{e}");
        let e = err("[[rule]\nmetric = 1\n");
        assert!(e.starts_with("t.toml:1:"), "{e}");
    }
}
