//! `check`'s outcome as the terminal table and as JSON (stdout), and the message texts the
//! JUnit report shares.

use std::fmt::Write as _;

use serde_json::{json, Map, Value};

use crate::check::baseline::{Comparison, Tolerances, Verdict};
use crate::check::evaluate::{short, Bound, RuleResult, Status};
use crate::check::report::{Body, CheckReport};
use crate::check::sweep::SweepKey;
use crate::check::thresholds::{CascadeSelection, Target};

impl CheckReport {
    /// The terminal table.
    pub fn table(&self) -> String {
        let mut out = String::new();
        let c = self.counts();
        match &self.body {
            Body::Single { results, baseline } => {
                let _ = writeln!(out, "check {} against {}", self.config, self.thresholds);
                out.push_str(&rules_table(results, "  "));
                let _ = writeln!(
                    out,
                    "{} rule{}: {} pass, {} fail, {} not applicable",
                    c.rules,
                    plural(c.rules),
                    c.pass,
                    c.fail,
                    c.not_applicable
                );
                if let Some(b) = baseline {
                    let _ = writeln!(out, "\nbaseline {}", b.file);
                    out.push_str(&tolerance_line(&self.tolerances));
                    out.push_str(&comparisons_table(&b.comparisons, "  ", true));
                    out.push_str(&verdict_counts(&b.comparisons));
                    if b.comparisons.iter().any(|x| {
                        x.metric == crate::metric::SummaryMetric::named("cascades_needed")
                            && x.verdict == Verdict::Regressed
                    }) {
                        out.push_str(
                            "  note: the scene no longer needs cascades, so every other metric reads 0; \
                             their 'improvements' mean nothing\n",
                        );
                    }
                }
            }
            Body::Sweep { rows, baseline } => {
                let _ = writeln!(
                    out,
                    "check --sweep {} against {}: {} configuration{}",
                    self.config,
                    self.thresholds,
                    rows.len(),
                    plural(rows.len())
                );
                for row in rows {
                    let _ = writeln!(
                        out,
                        "{}: {} ({} pass, {} fail, {} not applicable)",
                        row.key.label(),
                        if row.passed() { "PASS" } else { "FAIL" },
                        row.count(Status::Pass),
                        row.count(Status::Fail),
                        row.count(Status::NotApplicable)
                    );
                    out.push_str(&rules_table(&row.results, "  "));
                }
                let passing = rows.iter().filter(|r| r.passed()).count();
                let _ = writeln!(out, "{passing} of {} configurations pass", rows.len());
                if let Some(b) = baseline {
                    let cmp = &b.comparison;
                    let _ = writeln!(
                        out,
                        "\nbaseline {}: {} configuration{} matched, {} new, {} not in the current sweep",
                        b.file,
                        cmp.matched.len(),
                        plural(cmp.matched.len()),
                        cmp.only_current.len(),
                        cmp.only_baseline.len()
                    );
                    out.push_str(&tolerance_line(&self.tolerances));
                    for row in &cmp.matched {
                        let _ = writeln!(out, "{}:", row.key.label());
                        // Only what moved, to keep a large sweep readable.
                        let moved: Vec<Comparison> = row
                            .comparisons
                            .iter()
                            .filter(|x| x.verdict != Verdict::Unchanged)
                            .copied()
                            .collect();
                        if moved.is_empty() {
                            out.push_str("  every metric within tolerance\n");
                        } else {
                            out.push_str(&comparisons_table(&moved, "  ", false));
                        }
                    }
                    for k in &cmp.only_current {
                        let _ = writeln!(out, "{}: new (not in the baseline)", k.label());
                    }
                    for k in &cmp.only_baseline {
                        let _ = writeln!(out, "{}: not in the current sweep", k.label());
                    }
                    let all: Vec<Comparison> = cmp.matched.iter().flat_map(|r| r.comparisons.clone()).collect();
                    out.push_str(&verdict_counts(&all));
                }
            }
        }
        let _ = writeln!(
            out,
            "result: {}",
            if self.passed() {
                "PASS".to_string()
            } else {
                let mut why = Vec::new();
                if c.fail > 0 {
                    why.push(format!("{} rule check{} failed", c.fail, plural(c.fail)));
                }
                if c.regressed > 0 {
                    why.push(format!("{} metric{} regressed", c.regressed, plural(c.regressed)));
                }
                format!("FAIL ({})", why.join(", "))
            }
        );
        out
    }

    /// The same content as JSON (every number at full precision).
    pub fn json(&self) -> Value {
        let c = self.counts();
        let mut v = json!({
            "tool": format!("csm-lab {}", env!("CARGO_PKG_VERSION")),
            "config": self.config,
            "thresholds": self.thresholds,
            "passed": self.passed(),
            "counts": {
                "rules": c.rules,
                "pass": c.pass,
                "fail": c.fail,
                "not_applicable": c.not_applicable,
                "regressed": c.regressed,
                "improved": c.improved,
            },
        });
        let obj = v.as_object_mut().expect("object");
        match &self.body {
            Body::Single { results, baseline } => {
                obj.insert("mode".into(), "single".into());
                obj.insert("rules".into(), results.iter().map(rule_json).collect());
                if let Some(b) = baseline {
                    obj.insert(
                        "baseline".into(),
                        json!({
                            "file": b.file,
                            "tolerance": tolerances_json(&self.tolerances),
                            "comparisons": b.comparisons.iter().map(comparison_json).collect::<Vec<_>>(),
                        }),
                    );
                }
            }
            Body::Sweep { rows, baseline } => {
                obj.insert("mode".into(), "sweep".into());
                obj.insert(
                    "configurations".into(),
                    rows.iter()
                        .map(|r| {
                            json!({
                                "key": key_json(&r.key),
                                "label": r.key.label(),
                                "passed": r.passed(),
                                "rules": r.results.iter().map(rule_json).collect::<Vec<_>>(),
                            })
                        })
                        .collect(),
                );
                if let Some(b) = baseline {
                    let cmp = &b.comparison;
                    obj.insert(
                        "baseline".into(),
                        json!({
                            "file": b.file,
                            "tolerance": tolerances_json(&self.tolerances),
                            "matched": cmp.matched.iter().map(|r| json!({
                                "key": key_json(&r.key),
                                "label": r.key.label(),
                                "comparisons": r.comparisons.iter().map(comparison_json).collect::<Vec<_>>(),
                            })).collect::<Vec<_>>(),
                            "only_current": cmp.only_current.iter().map(key_json).collect::<Vec<_>>(),
                            "only_baseline": cmp.only_baseline.iter().map(key_json).collect::<Vec<_>>(),
                        }),
                    );
                }
            }
        }
        v
    }
}

pub fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// `<= 8`, `>= 0.25`, `in [1, 8]`
pub fn limit_text(r: &RuleResult) -> String {
    match (r.rule.min, r.rule.max) {
        (Some(lo), Some(hi)) => format!("in [{}, {}]", short(lo), short(hi)),
        (Some(lo), None) => format!(">= {}", short(lo)),
        (None, Some(hi)) => format!("<= {}", short(hi)),
        (None, None) => String::new(),
    }
}

/// One sentence with the numbers, for failure messages.
pub fn rule_message(r: &RuleResult) -> String {
    let metric = r.rule.target.metric_name();
    match (&r.judgement, r.status) {
        (None, _) => format!("{metric}: not applicable: {}", r.note.as_deref().unwrap_or("no data")),
        (Some(j), status) => {
            let side = match (j.bound, status) {
                (Bound::Max, Status::Fail) => format!("is above the max {} by {}", short(j.limit), short(-j.margin)),
                (Bound::Min, Status::Fail) => format!("is below the min {} by {}", short(j.limit), short(-j.margin)),
                (Bound::Max, _) => format!("is within the max {} by {}", short(j.limit), short(j.margin)),
                (Bound::Min, _) => format!("is within the min {} by {}", short(j.limit), short(j.margin)),
            };
            let mut s = format!("{metric} = {} ({}) {side}", short(j.actual.value), r.place());
            if let Some(n) = &r.note {
                let _ = write!(s, "; {n}");
            }
            s
        }
    }
}

/// Pads cells to their column's width; `right[i]` right-aligns column i.
fn grid(rows: &[Vec<String>], right: &[bool], indent: &str) -> String {
    let cols = rows.iter().map(|r| r.len()).max().unwrap_or(0);
    let width: Vec<usize> = (0..cols)
        .map(|i| {
            rows.iter()
                .filter_map(|r| r.get(i))
                .map(|s| s.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for r in rows {
        let mut line = String::from(indent);
        for (i, cell) in r.iter().enumerate() {
            if i > 0 {
                line.push_str("  ");
            }
            let pad = width[i] - cell.chars().count();
            if right.get(i).copied().unwrap_or(false) {
                line.push_str(&" ".repeat(pad));
                line.push_str(cell);
            } else {
                line.push_str(cell);
                line.push_str(&" ".repeat(pad));
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

fn rules_table(results: &[RuleResult], indent: &str) -> String {
    let mut rows = vec![vec![
        "#".to_string(),
        "metric".into(),
        "where".into(),
        "actual".into(),
        "limit".into(),
        "margin".into(),
        "result".into(),
    ]];
    let mut notes = Vec::new();
    for r in results {
        let (actual, margin) = match &r.judgement {
            Some(j) => (short(j.actual.value), short(j.margin)),
            None => ("-".to_string(), "-".to_string()),
        };
        rows.push(vec![
            r.rule.index.to_string(),
            r.rule.target.metric_name().to_string(),
            r.place(),
            actual,
            limit_text(r),
            margin,
            r.status.label().to_string(),
        ]);
        if let Some(n) = &r.note {
            notes.push(format!("{indent}  rule {}: {n}\n", r.rule.index));
        }
    }
    let mut out = grid(&rows, &[true, false, false, true, false, true, false], indent);
    for n in notes {
        out.push_str(&n);
    }
    out
}

fn tolerance_line(t: &Tolerances) -> String {
    let mut s = format!(
        "  tolerance: max(absolute {}, relative {} x |baseline|)",
        short(t.default.absolute),
        short(t.default.relative)
    );
    for (m, x) in &t.per_metric {
        let _ = write!(
            s,
            "; {}: absolute {}, relative {}",
            m.name(),
            short(x.absolute),
            short(x.relative)
        );
    }
    s.push('\n');
    s
}

fn comparisons_table(comparisons: &[Comparison], indent: &str, header: bool) -> String {
    let mut rows = Vec::new();
    if header {
        rows.push(vec![
            "metric".to_string(),
            "baseline".into(),
            "current".into(),
            "change".into(),
            "tolerance".into(),
            "verdict".into(),
        ]);
    }
    let opt = |v: Option<f64>| v.map_or("-".to_string(), short);
    for c in comparisons {
        let change = match (c.change(), c.relative_change()) {
            (Some(d), Some(r)) => format!("{}{} ({:+.1}%)", if d >= 0.0 { "+" } else { "" }, short(d), 100.0 * r),
            (Some(d), None) => format!("{}{}", if d >= 0.0 { "+" } else { "" }, short(d)),
            _ => "-".to_string(),
        };
        rows.push(vec![
            c.metric.name().to_string(),
            opt(c.baseline),
            opt(c.current),
            change,
            match c.verdict {
                Verdict::NotInBaseline | Verdict::NotInCurrent => "-".to_string(),
                _ => short(c.tolerance),
            },
            c.verdict.label().to_string(),
        ]);
    }
    grid(&rows, &[false, true, true, true, true, false], indent)
}

fn verdict_counts(comparisons: &[Comparison]) -> String {
    let n = |v: Verdict| comparisons.iter().filter(|c| c.verdict == v).count();
    format!(
        "baseline: {} regressed, {} improved, {} unchanged, {} changed (no worse direction), {} missing\n",
        n(Verdict::Regressed),
        n(Verdict::Improved),
        n(Verdict::Unchanged),
        n(Verdict::Changed),
        n(Verdict::NotInBaseline) + n(Verdict::NotInCurrent)
    )
}

fn key_json(k: &SweepKey) -> Value {
    json!({"lambda": k.lambda, "cascades": k.cascades, "resolution": k.resolution, "fit": k.fit})
}

fn tolerances_json(t: &Tolerances) -> Value {
    let mut per = Map::new();
    for (m, x) in &t.per_metric {
        per.insert(m.name().to_string(), json!(x));
    }
    json!({"relative": t.default.relative, "absolute": t.default.absolute, "metric": per})
}

fn comparison_json(c: &Comparison) -> Value {
    let mut o = Map::new();
    o.insert("metric".into(), c.metric.name().into());
    o.insert("direction".into(), json!(c.metric.direction()));
    if let Some(b) = c.baseline {
        o.insert("baseline".into(), json!(b));
    }
    if let Some(x) = c.current {
        o.insert("current".into(), json!(x));
    }
    if let Some(d) = c.change() {
        o.insert("change".into(), json!(d));
    }
    if let Some(r) = c.relative_change() {
        o.insert("relative_change".into(), json!(r));
    }
    o.insert("tolerance".into(), json!(c.tolerance));
    o.insert("verdict".into(), json!(c.verdict));
    Value::Object(o)
}

fn rule_json(r: &RuleResult) -> Value {
    let mut o = Map::new();
    o.insert("rule".into(), json!(r.rule.index));
    o.insert("metric".into(), r.rule.target.metric_name().into());
    o.insert("kind".into(), r.rule.target.kind().into());
    o.insert("location".into(), r.rule.location.clone().into());
    match r.rule.target {
        Target::Cascade(_, CascadeSelection::One(i)) => {
            o.insert("cascade".into(), json!(i));
        }
        Target::Cascade(_, CascadeSelection::All) => {
            o.insert("cascade".into(), "all".into());
        }
        Target::Depth(_, Some((lo, hi))) => {
            o.insert("depth".into(), json!([lo, hi]));
        }
        _ => {}
    }
    if let Some(x) = r.rule.min {
        o.insert("min".into(), json!(x));
    }
    if let Some(x) = r.rule.max {
        o.insert("max".into(), json!(x));
    }
    o.insert("where".into(), r.place().into());
    o.insert("status".into(), json!(r.status));
    if let Some(j) = &r.judgement {
        o.insert("actual".into(), json!(j.actual.value));
        o.insert("bound".into(), json!(j.bound));
        o.insert("limit".into(), json!(j.limit));
        o.insert("margin".into(), json!(j.margin));
        if let Some(c) = j.actual.cascade {
            o.insert("at_cascade".into(), json!(c));
        }
        if let Some(d) = j.actual.depth {
            o.insert("at_depth".into(), json!(d));
        }
    }
    if let Some(n) = r.cascades_examined {
        o.insert("cascades_examined".into(), json!(n));
    }
    if let Some((lo, hi)) = r.evaluated_range {
        o.insert("evaluated_depth".into(), json!([lo, hi]));
    }
    if let Some(n) = &r.note {
        o.insert("note".into(), n.clone().into());
    }
    Value::Object(o)
}
