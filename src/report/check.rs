//! `check`'s outcome as the terminal table and as JSON (stdout), and the message texts the
//! JUnit report shares.

use std::fmt::Write as _;

use serde_json::{json, Map, Value};

use crate::commands::check::baseline::{Comparison, Tolerances, Verdict};
use crate::commands::check::evaluate::{short, Bound, RuleResult, Status};
use crate::commands::check::report::{Body, CheckReport};
use crate::commands::check::sweep::SweepKey;
use crate::commands::check::thresholds::{CascadeSelection, Target};

/// Offenders listed per rule and regressions listed in the `--sweep` summary.
const WORST_LISTED: usize = 3;

impl CheckReport {
    /// The terminal table: with `--sweep`, a summary (counts per rule, the worst offenders)
    /// unless `verbose`, which lists every configuration.
    pub(crate) fn table_with(&self, verbose: bool) -> String {
        match &self.body {
            Body::Sweep { rows, baseline, gated } if !verbose => self.sweep_summary(rows, baseline.as_ref(), gated),
            _ => self.table(),
        }
    }

    /// `check --sweep`'s summary: one line per rule with its counts over the configurations
    /// and its worst offenders, each distinct note once, the baseline's counts per metric and
    /// its largest regressions.
    fn sweep_summary(
        &self,
        rows: &[crate::commands::check::sweep::RowReport],
        baseline: Option<&crate::commands::check::report::SweepBaseline>,
        gated: &str,
    ) -> String {
        let mut out = String::new();
        let c = self.counts();
        let _ = writeln!(
            out,
            "check --sweep {} against {}: {} configuration{} (summary; --verbose lists every one)",
            self.config,
            self.thresholds,
            rows.len(),
            plural(rows.len())
        );
        let _ = writeln!(out, "{gated}");
        let rule_count = rows.first().map_or(0, |r| r.results.len());
        // Each distinct note once, with the rules it concerns.
        let mut notes: Vec<(String, Vec<String>)> = Vec::new();
        let mut table = vec![vec![
            "rule".to_string(),
            "metric".to_string(),
            "limit".to_string(),
            "pass".to_string(),
            "fail".to_string(),
            "n/a".to_string(),
            "worst".to_string(),
        ]];
        let mut offenders: Vec<String> = Vec::new();
        for k in 0..rule_count {
            let results: Vec<(&crate::commands::check::sweep::SweepKey, &RuleResult)> =
                rows.iter().map(|r| (&r.key, &r.results[k])).collect();
            let first = results[0].1;
            let n = |s: Status| results.iter().filter(|(_, r)| r.status == s).count();
            let mut judged: Vec<_> = results
                .iter()
                .filter_map(|(key, r)| r.judgement.as_ref().map(|j| (*key, j)))
                .collect();
            judged.sort_by(|a, b| a.1.margin.total_cmp(&b.1.margin).then_with(|| a.0.cmp(b.0)));
            for (_, r) in &results {
                if r.status == Status::NotApplicable {
                    if let Some(note) = &r.note {
                        let rule = format!("{} ({})", first.rule.index, first.rule.target.metric_name());
                        match notes.iter_mut().find(|(n, _)| n == note) {
                            Some((_, rules)) if rules.contains(&rule) => {}
                            Some((_, rules)) => rules.push(rule),
                            None => notes.push((note.clone(), vec![rule])),
                        }
                    }
                }
            }
            table.push(vec![
                first.rule.index.to_string(),
                first.rule.target.metric_name().to_string(),
                limit_text(first),
                n(Status::Pass).to_string(),
                n(Status::Fail).to_string(),
                n(Status::NotApplicable).to_string(),
                judged.first().map_or("-".to_string(), |(_, j)| short(j.actual.value)),
            ]);
            for (key, j) in judged.iter().filter(|(_, j)| j.margin < 0.0).take(WORST_LISTED) {
                offenders.push(format!(
                    "rule {} ({} {}): {} = {}, over by {}",
                    first.rule.index,
                    first.rule.target.metric_name(),
                    limit_text(first),
                    key.label(),
                    short(j.actual.value),
                    short(-j.margin)
                ));
            }
        }
        out.push_str(&grid(&table, &[true, false, false, true, true, true, true], "  "));
        if !offenders.is_empty() {
            let _ = writeln!(out, "worst offenders (up to {WORST_LISTED} per rule):");
            for o in &offenders {
                let _ = writeln!(out, "  {o}");
            }
        }
        for (note, rules) in &notes {
            let _ = writeln!(
                out,
                "note: rule{} {} not applicable: {note}",
                plural(rules.len()),
                rules.join(", ")
            );
        }
        let passing = rows.iter().filter(|r| r.passed()).count();
        let _ = writeln!(out, "{passing} of {} configurations pass", rows.len());
        if let Some(b) = baseline {
            let cmp = &b.comparison;
            out.push_str(&sweep_baseline_line(b));
            if !cmp.columns_not_in_baseline.is_empty() {
                let _ = writeln!(
                    out,
                    "note: not compared (the baseline has no such column): {}",
                    cmp.columns_not_in_baseline.join(", ")
                );
            }
            out.push_str(&tolerance_line(&self.tolerances));
            let mut regressions: Vec<(&crate::commands::check::sweep::SweepKey, &Comparison)> = cmp
                .matched
                .iter()
                .flat_map(|r| r.comparisons.iter().map(move |x| (&r.key, x)))
                .filter(|(_, x)| x.verdict == Verdict::Regressed)
                .collect();
            let mut per_metric: std::collections::BTreeMap<&str, usize> = Default::default();
            for (_, x) in &regressions {
                *per_metric.entry(x.metric.name()).or_default() += 1;
            }
            for (m, n) in &per_metric {
                let _ = writeln!(out, "  {m}: regressed in {n} configuration{}", plural(*n));
            }
            // Largest relative worsening first.
            let rel = |x: &Comparison| {
                let w = x
                    .metric
                    .direction()
                    .worsening(x.baseline.unwrap_or(0.0), x.current.unwrap_or(0.0));
                w.unwrap_or(0.0) / x.baseline.unwrap_or(0.0).abs().max(1e-300)
            };
            regressions.sort_by(|a, b| rel(b.1).total_cmp(&rel(a.1)).then_with(|| a.0.cmp(b.0)));
            for (key, x) in regressions.iter().take(2 * WORST_LISTED) {
                let _ = writeln!(
                    out,
                    "  {}: {} {} -> {}",
                    key.label(),
                    x.metric.name(),
                    short(x.baseline.unwrap_or(0.0)),
                    short(x.current.unwrap_or(0.0))
                );
            }
            let all: Vec<Comparison> = cmp.matched.iter().flat_map(|r| r.comparisons.clone()).collect();
            out.push_str(&verdict_counts(&all));
        }
        let _ = writeln!(out, "result: {}", self.result_text(&c));
        out
    }

    fn result_text(&self, c: &crate::commands::check::report::Counts) -> String {
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
    }

    /// The terminal table.
    pub(crate) fn table(&self) -> String {
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
            Body::Sweep { rows, baseline, gated } => {
                let _ = writeln!(
                    out,
                    "check --sweep {} against {}: {} configuration{}",
                    self.config,
                    self.thresholds,
                    rows.len(),
                    plural(rows.len())
                );
                let _ = writeln!(out, "{gated}");
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
                    let _ = write!(out, "\n{}", sweep_baseline_line(b));
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
                    if !cmp.columns_not_in_baseline.is_empty() {
                        let _ = writeln!(
                            out,
                            "note: not compared (the baseline has no such column): {}",
                            cmp.columns_not_in_baseline.join(", ")
                        );
                    }
                    let all: Vec<Comparison> = cmp.matched.iter().flat_map(|r| r.comparisons.clone()).collect();
                    out.push_str(&verdict_counts(&all));
                }
            }
        }
        let _ = writeln!(out, "result: {}", self.result_text(&c));
        out
    }

    /// The same content as JSON (every number at full precision).
    pub(crate) fn json(&self) -> Value {
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
            Body::Sweep { rows, baseline, gated } => {
                obj.insert("mode".into(), "sweep".into());
                obj.insert("gated".into(), gated.as_str().into());
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
                            "columns_not_in_baseline": cmp.columns_not_in_baseline,
                        }),
                    );
                }
            }
        }
        v
    }
}

pub(crate) fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

/// `<= 8`, `>= 0.25`, `in [1, 8]`
pub(crate) fn limit_text(r: &RuleResult) -> String {
    match (r.rule.min, r.rule.max) {
        (Some(lo), Some(hi)) => format!("in [{}, {}]", short(lo), short(hi)),
        (Some(lo), None) => format!(">= {}", short(lo)),
        (None, Some(hi)) => format!("<= {}", short(hi)),
        (None, None) => String::new(),
    }
}

/// One sentence with the numbers, for failure messages.
pub(crate) fn rule_message(r: &RuleResult) -> String {
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

/// How a sweep matched its baseline: rows matched, new, and gone, one line.
fn sweep_baseline_line(b: &crate::commands::check::report::SweepBaseline) -> String {
    let cmp = &b.comparison;
    format!(
        "baseline {}: {} configuration{} matched, {} new, {} not in the current sweep\n",
        b.file,
        cmp.matched.len(),
        plural(cmp.matched.len()),
        cmp.only_current.len(),
        cmp.only_baseline.len()
    )
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
    let mut v = json!({"lambda": k.lambda, "cascades": k.cascades, "resolution": k.resolution, "fit": k.fit});
    if let Some(x) = k.knob {
        v["knob"] = json!(x);
    }
    if let Some(x) = k.distance {
        v["distance"] = json!(x);
    }
    if let Some(x) = &k.light_update {
        v["light_update"] = json!(x);
    }
    v
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
    o.insert("location".into(), (*r.rule.location).into());
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
