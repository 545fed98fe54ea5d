//! What `sweep --optimize-splits` adds: `optimized_splits.csv`, the `optimized_splits` section
//! of `recommendation.json`, a stdout table, a report section and the verdict's sentence.

use std::fmt::Write as _;

use super::html;
use crate::commands::sweep::optimize::{Optimized, OptimizedGroup};
use crate::commands::sweep::SweepResult;
use crate::config::Config;
use crate::error::Result;
use crate::output::{csv_bytes, num, percent_change, short_number as n, signed_percent};

/// The file name.
pub(crate) const FILE: &str = "optimized_splits.csv";

/// `a, b, c` with each fraction as printed (shortest round trip: it pastes back exactly).
fn list(fr: &[f64]) -> String {
    fr.iter().map(|x| x.to_string()).collect::<Vec<_>>().join(", ")
}

/// The group's shadow distance.
fn max_distance(config: &Config, g: &OptimizedGroup) -> f64 {
    g.setting.distance.unwrap_or(config.shadow.max_distance)
}

/// The lines to paste into the config to use the group's optimum.
pub(crate) fn paste_text(config: &Config, g: &OptimizedGroup) -> String {
    match &config.shadow.preset {
        Some(p) => {
            crate::presets::paste_lines(&p.knobs, g.setting.cascades, max_distance(config, g), &g.best.fractions)
                .unwrap_or_default()
        }
        None => format!(
            "[shadow]\ncascades = {}\nresolution = {}\nsplits = [{}]",
            g.setting.cascades,
            g.setting.resolution,
            list(&g.best.fractions)
        ),
    }
}

/// The optimum in the engine's own terms (csm-lab: the `shadow.splits` key).
pub(crate) fn setting_text(config: &Config, g: &OptimizedGroup) -> String {
    match &config.shadow.preset {
        Some(p) => {
            crate::presets::engine_setting(&p.knobs, g.setting.cascades, max_distance(config, g), &g.best.fractions)
                .unwrap_or_default()
        }
        None => format!("shadow.splits = [{}]", list(&g.best.fractions)),
    }
}

/// What the fractions are fractions of, in words.
pub(crate) fn of_text(config: &Config, g: &OptimizedGroup) -> String {
    match &config.shadow.preset {
        Some(p) => {
            crate::presets::free_split_knob(&p.knobs, g.setting.cascades).map_or_else(String::new, |k| k.of.to_string())
        }
        None => format!("fractions of the split range [{}, {}]", n(g.space.lo), n(g.space.hi)),
    }
}

/// The group's gain: (start − optimum, the change in percent).
fn gain(r: &SweepResult, g: &OptimizedGroup) -> (f64, f64) {
    let (a, b) = g.values(r.objective);
    (a - b, percent_change(a, b).unwrap_or(0.0))
}

const HEADER: [&str; 22] = [
    "cascades",
    "resolution",
    "fit",
    "split_range",
    "distance",
    "fractions_of",
    "range_lo",
    "range_hi",
    "start_lambda",
    "start_fractions",
    "start_objective",
    "fractions",
    "objective",
    "improvement",
    "improvement_percent",
    "max_aliasing",
    "mean_aliasing",
    "shimmer",
    "coverage_violations",
    "evaluations",
    "setting",
    "objective_metric",
];

/// `optimized_splits.csv`: one row per cascade count × resolution (× fit, split range,
/// distance) with more than one cascade.
pub(crate) fn csv(r: &SweepResult, o: &Optimized) -> Result<Vec<u8>> {
    let rows = o
        .groups
        .iter()
        .map(|g| {
            let (a, b) = g.values(r.objective);
            let (d, p) = gain(r, g);
            let s = &g.best.summary;
            Ok(vec![
                g.setting.cascades.to_string(),
                g.setting.resolution.to_string(),
                g.setting.fit.name().to_string(),
                g.setting.split_range.name().to_string(),
                num("distance", g.setting.distance.unwrap_or(r.config.shadow.max_distance))?,
                of_text(&r.config, g),
                num("range_lo", g.space.lo)?,
                num("range_hi", g.space.hi)?,
                num("start_lambda", g.start_lambda)?,
                list(&g.start.fractions).replace(", ", " "),
                num("start_objective", a)?,
                list(&g.best.fractions).replace(", ", " "),
                num("objective", b)?,
                num("improvement", d)?,
                num("improvement_percent", -p)?,
                num("max_aliasing", s.max_aliasing)?,
                num("mean_aliasing", s.mean_aliasing)?,
                num("shimmer", s.shimmer)?,
                s.coverage_violations.to_string(),
                g.evaluations.to_string(),
                setting_text(&r.config, g),
                r.objective.name().to_string(),
            ])
        })
        .collect::<Result<Vec<_>>>()?;
    csv_bytes(&HEADER, &rows)
}

/// The `optimized_splits` section of `recommendation.json`.
pub(crate) fn json(r: &SweepResult, o: &Optimized) -> serde_json::Value {
    let groups: Vec<serde_json::Value> = o
        .groups
        .iter()
        .map(|g| {
            let (a, b) = g.values(r.objective);
            let (d, p) = gain(r, g);
            let mut v = serde_json::json!({
                "cascades": g.setting.cascades,
                "resolution": g.setting.resolution,
                "fit": g.setting.fit.name(),
                "split_range": g.setting.split_range.name(),
                "fractions_of": of_text(&r.config, g),
                "range": [g.space.lo, g.space.hi],
                "start": { "lambda": g.start_lambda, "fractions": g.start.fractions, "objective": a },
                "fractions": g.best.fractions,
                "objective": b,
                "improvement": d,
                "improvement_percent": -p,
                "setting": setting_text(&r.config, g),
                "paste": paste_text(&r.config, g),
                "evaluations": g.evaluations,
                "summary": crate::metric::summary_json(&g.best.summary)
                    .into_iter()
                    .map(|(k, v)| (k.to_string(), v))
                    .collect::<serde_json::Map<_, _>>(),
            });
            if let Some(d) = g.setting.distance {
                v["distance"] = d.into();
            }
            if let Some(c) = &g.configured {
                v["configured"] = serde_json::json!({
                    "fractions": c.fractions,
                    "objective": r.objective.value(&c.summary),
                });
            }
            v
        })
        .collect();
    serde_json::json!({
        "objective_metric": r.objective.name(),
        "start": format!("the best practical split over λ = {} of each group", o.lambdas),
        "method": "Nelder-Mead (argmin) on log-depth gaps; see docs/optimize.md",
        "groups": groups,
        "notes": o.notes,
    })
}

/// The group of the recommended row, when it was optimised and the optimum is better.
pub(crate) fn recommended_group<'a>(r: &SweepResult, o: &'a Optimized) -> Option<&'a OptimizedGroup> {
    let rec = r.recommended()?.setting;
    o.groups.iter().find(|g| {
        let s = g.setting;
        s.cascades == rec.cascades
            && s.resolution == rec.resolution
            && s.fit == rec.fit
            && s.split_range == rec.split_range
            && s.knob == rec.knob
            && s.distance == rec.distance
    })
}

/// The verdict's sentence on free splits: the recommended count and resolution with the
/// optimised split fractions, when they win.
pub(crate) fn verdict(r: &SweepResult) -> Option<String> {
    let o = r.optimized.as_ref()?;
    let g = recommended_group(r, o)?;
    let (a, b) = g.values(r.objective);
    // A preset has no λ: its start is named by its fractions.
    let start = start_text(r, g);
    if b >= a {
        return Some(format!(
            "Free split fractions do not beat {start} at this count and resolution."
        ));
    }
    let (_, p) = gain(r, g);
    // What the engine's configured split gives, relative to which the change is made.
    let configured = g.configured.as_ref().map_or_else(String::new, |c| {
        format!(
            "; the configured split ({}) gives {}",
            list(
                &c.fractions
                    .iter()
                    .map(|&x| csm_core::free_splits::round_significant(x, 4))
                    .collect::<Vec<_>>()
            ),
            n(r.objective.value(&c.summary))
        )
    });
    Some(format!(
        "With free splits, split fractions ({}) ({}; {}) bring {} from {} to {} ({}) against {start}{configured}.",
        list(&g.best.fractions),
        of_text(&r.config, g),
        setting_text(&r.config, g),
        r.objective.name(),
        n(a),
        n(b),
        signed_percent(p)
    ))
}

/// The start in words: "λ = 0.4" for csm-lab's own pipeline; "the best practical split
/// (0.05, 0.15, 0.4)" for a preset, which has no λ to set.
fn start_text(r: &SweepResult, g: &OptimizedGroup) -> String {
    match &r.config.shadow.preset {
        Some(_) => format!("the best practical split ({})", short_list(&g.start.fractions)),
        None => format!("λ = {}", g.start_lambda),
    }
}

/// Fractions to 4 significant digits, for reading.
fn short_list(fr: &[f64]) -> String {
    fr.iter().map(|&x| n(x)).collect::<Vec<_>>().join(", ")
}

fn rows(r: &SweepResult, o: &Optimized) -> Vec<Vec<String>> {
    o.groups
        .iter()
        .map(|g| {
            let (a, b) = g.values(r.objective);
            let (d, p) = gain(r, g);
            vec![
                g.setting.cascades.to_string(),
                g.setting.resolution.to_string(),
                if r.config.shadow.preset.is_some() {
                    short_list(&g.start.fractions)
                } else {
                    n(g.start_lambda)
                },
                n(a),
                list(&g.best.fractions),
                n(b),
                n(d),
                signed_percent(p),
            ]
        })
        .collect()
}

/// The table's header; a preset's start column holds fractions ("start split"), not a λ.
fn table_head(r: &SweepResult) -> [&'static str; 8] {
    let mut h = TABLE_HEAD;
    if r.config.shadow.preset.is_some() {
        h[2] = "start split";
    }
    h
}

const TABLE_HEAD: [&str; 8] = [
    "cascades",
    "res",
    "start λ",
    "start",
    "split fractions",
    "optimised",
    "gain",
    "change",
];

/// The stdout table.
pub(crate) fn stdout(r: &SweepResult) -> String {
    let Some(o) = &r.optimized else {
        return String::new();
    };
    let mut out = String::new();
    let what = o
        .groups
        .first()
        .map_or_else(String::new, |g| format!(", {}", of_text(&r.config, g)));
    let _ = writeln!(
        out,
        "Free splits ({} against the best practical split of each count and resolution{what}):",
        r.objective.name()
    );
    let rows = rows(r, o);
    let head = table_head(r);
    let widths: Vec<usize> = (0..head.len())
        .map(|c| {
            rows.iter()
                .map(|x| x[c].chars().count())
                .chain([head[c].chars().count()])
                .max()
                .unwrap_or(0)
        })
        .collect();
    let line = |cells: &[&str]| {
        let mut l = String::from(" ");
        for (c, cell) in cells.iter().enumerate() {
            let pad = widths[c] - cell.chars().count();
            if c == 4 {
                let _ = write!(l, " {cell}{}", " ".repeat(pad));
            } else {
                let _ = write!(l, " {}{cell}", " ".repeat(pad));
            }
        }
        l.trim_end().to_string()
    };
    let _ = writeln!(out, "{}", line(&head));
    for row in &rows {
        let cells: Vec<&str> = row.iter().map(String::as_str).collect();
        let _ = writeln!(out, "{}", line(&cells));
    }
    for note in &o.notes {
        let _ = writeln!(out, "  note: {note}");
    }
    out
}

/// The report section (HTML).
pub(crate) fn html_section(r: &SweepResult) -> String {
    let Some(o) = &r.optimized else {
        return String::new();
    };
    let mut h = String::from("<h2>Free splits</h2>\n");
    let _ = writeln!(
        h,
        "<p>For each cascade count and resolution, the split fractions that minimise {} (Nelder-Mead from the best \
         practical split over λ = {}; every point is the same analysis as a sweep row). Full table: \
         <a href=\"{FILE}\">{FILE}</a>.</p>",
        html::escape(r.objective.name()),
        html::escape(&o.lambdas)
    );
    if let Some(v) = verdict(r) {
        let _ = writeln!(h, "<p>{}</p>", html::escape(&v));
    }
    let rows = rows(r, o);
    h.push_str(&html::table(&table_head(r), &rows, &[4], None));
    if let Some(g) = recommended_group(r, o) {
        let _ = writeln!(
            h,
            "<p>To use the optimum at the recommended count and resolution, paste:</p>\n<pre>{}</pre>",
            html::escape(&paste_text(&r.config, g))
        );
    }
    if !o.notes.is_empty() {
        h.push_str(&html::list(&o.notes, None));
    }
    h
}

/// The report section (Markdown).
pub(crate) fn md_section(r: &SweepResult) -> String {
    let Some(o) = &r.optimized else {
        return String::new();
    };
    let mut m = String::from("## Free splits\n\n");
    if let Some(v) = verdict(r) {
        let _ = writeln!(m, "{v}\n");
    }
    m.push_str(&super::markdown::table(&table_head(r), &rows(r, o), &[4]));
    let _ = writeln!(m, "\nFull table: [{FILE}]({FILE}).\n");
    m
}
