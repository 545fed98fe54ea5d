//! A level of views in the reports: `views.csv` (one row per view: its pose, weight and own
//! screen metrics; in a sweep also its own choice and what the level's choice costs it), the
//! worst view's name in `summary.json`/`recommendation.json` and on stdout, and the sweep
//! report's "Views" section.

use std::fmt::Write as _;

use crate::analysis::Summary;
use crate::commands::sweep::level::{sees_receivers, view_summary, worst_of, LevelChoice};
use crate::commands::sweep::SweepResult;
use crate::config::Config;
use crate::error::Result;
use crate::metric::{SummaryMetric, SUMMARY};
use crate::output::{csv_bytes, num, short_number as n, signed_percent};

/// `views.csv`'s name.
pub(crate) const FILE: &str = "views.csv";

/// The per-view screen metrics: every screen metric of the rows' columns, in registry order.
fn view_metrics() -> Vec<SummaryMetric> {
    SUMMARY
        .iter()
        .filter(|d| d.screen && d.in_rows && !crate::metric::optional_row_column(d.name))
        .map(|d| SummaryMetric::named(d.name))
        .collect()
}

/// The worst view of a summary with views by `objective` (index, name, value); None without
/// views.
pub(crate) fn worst_view(s: &Summary, objective: SummaryMetric) -> Option<(usize, &str, f64)> {
    if s.views.is_empty() {
        return None;
    }
    let values: Vec<f64> = (0..s.views.len())
        .map(|k| objective.value(&view_summary(s, k)))
        .collect();
    let seen: Vec<bool> = (0..s.views.len()).map(|k| sees_receivers(s, k)).collect();
    let k = worst_of(&values, &seen, objective);
    Some((k, s.views[k].name.as_str(), values[k]))
}

/// `views.csv` for a summary with views: name, the pose as written (the world offset taken
/// off), weight, whether it is the worst by `objective`, and its own screen metrics; with a
/// sweep's [`LevelChoice`], also the objective at the level's choice, the view's own choice,
/// its objective there and the level's cost in percent (empty when it has no choice).
pub(crate) fn csv(
    config: &Config,
    s: &Summary,
    objective: SummaryMetric,
    choice: Option<(&SweepResult, &LevelChoice)>,
) -> Result<Vec<u8>> {
    let metrics = view_metrics();
    let mut head: Vec<&str> = vec!["name"];
    head.extend(super::POSE_COLUMNS);
    head.push("weight");
    head.push("worst");
    head.extend(metrics.iter().map(|m| m.name()));
    // With the ground truth over the views: whether each view was judged, and its own values.
    let truth = s.views.iter().any(|v| v.judged);
    let truth_metrics: Vec<SummaryMetric> = crate::metric::TRUTH_SUMMARY
        .iter()
        .map(|n| SummaryMetric::named(n))
        .collect();
    if truth {
        head.push("ground_truth_judged");
        head.extend(truth_metrics.iter().map(|m| m.name()));
    }
    if choice.is_some() {
        head.extend([
            "objective_at_level",
            "alone_setting",
            "alone_objective",
            "level_cost_percent",
        ]);
    }
    let worst = worst_view(s, objective).map(|w| w.0);
    let off = config.world_offset;
    let mut rows = Vec::new();
    for (k, v) in s.views.iter().enumerate() {
        let cam = &config.views[k].camera;
        let (p, t) = (cam.position - off, cam.target - off);
        let mut row = vec![v.name.clone()];
        let pose = super::POSE_COLUMNS.into_iter().zip([p.x, p.y, p.z, t.x, t.y, t.z]);
        for (what, x) in pose.chain([("weight", v.weight)]) {
            row.push(num(what, x)?);
        }
        row.push((worst == Some(k)).to_string());
        let own = view_summary(s, k);
        let seen = sees_receivers(s, k);
        for m in &metrics {
            // A view that sees no receiver measured its fractions only: no statistic of m.
            let measured = seen || matches!(m.name(), "screen_receiver_fraction" | "screen_self_shadowed_fraction");
            row.push(if measured {
                m.typed(&own).csv(m.name())?
            } else {
                String::new()
            });
        }
        if truth {
            row.push(v.judged.to_string());
            let own = Summary { truth: v.truth, ..own };
            for m in &truth_metrics {
                row.push(if v.truth.is_some() {
                    m.typed(&own).csv(m.name())?
                } else {
                    String::new()
                });
            }
        }
        if let Some((r, c)) = choice {
            let x = &c.views[k];
            row.push(if x.seen {
                num("objective_at_level", x.objective_at_level)?
            } else {
                String::new()
            });
            row.push(x.alone.map_or(String::new(), |i| r.rows[i].setting.label()));
            row.push(match x.objective_alone {
                Some(o) => num("alone_objective", o)?,
                None => String::new(),
            });
            row.push(match x.cost {
                Some(c) => num("level_cost_percent", 100.0 * c)?,
                None => String::new(),
            });
        }
        rows.push(row);
    }
    csv_bytes(&head, &rows)
}

/// `summary.json`'s keys for a level: how many views, the objective the worst is judged by and
/// the worst view with its value.
pub(crate) fn json(s: &Summary, objective: SummaryMetric) -> Option<serde_json::Value> {
    let (_, name, value) = worst_view(s, objective)?;
    Some(serde_json::json!({
        "count": s.views.len(),
        "pooled": "the screen metrics pool every view's receiver pixels, each carrying its view's weight",
        "worst_view": name,
        "worst_by": objective.name(),
        "worst_value": value,
        "names": s.views.iter().map(|v| v.name.as_str()).collect::<Vec<_>>(),
    }))
}

/// `summary.json`'s `ground_truth_views` for a level whose views the ground truth judged: the
/// judged views' names, how many of how many, the rule that chose them and what is pooled.
pub(crate) fn truth_json(s: &Summary) -> Option<serde_json::Value> {
    let names = judged_names(s)?;
    Some(serde_json::json!({
        "count": names.len(),
        "of": s.views.len(),
        "names": names,
        "rule": crate::analysis::views_truth::RULE,
        "pooled": TRUTH_POOLED,
    }))
}

/// What the level's ground-truth keys hold, and what stays `[camera]`'s.
const TRUTH_POOLED: &str = "acne_fraction, edge_error_fraction, leak_fraction and the flicker_* keys pool the judged \
                            views' receivers, each view weighted; bias_source, pcf_filter, bias.csv, cascades.csv's \
                            ground-truth columns and the shadow pictures are [camera]'s pass";

/// The judged views' names, in the config's order; None when the ground truth judged none.
fn judged_names(s: &Summary) -> Option<Vec<&str>> {
    let names: Vec<&str> = s.views.iter().filter(|v| v.judged).map(|v| v.name.as_str()).collect();
    (!names.is_empty()).then_some(names)
}

/// `analyze`'s stdout line for the ground truth over a level: "ground truth pooled over K of N
/// views: a, b, c (...)"; None when no view was judged.
pub(crate) fn truth_line(s: &Summary) -> Option<String> {
    let names = judged_names(s)?;
    let chosen = crate::analysis::views_truth::chosen(names.len(), s.views.len());
    Some(format!(
        "ground truth over the level: acne, edge, leak and flicker above pool {} of {} views ({chosen}: {}); each view's own in views.csv; the bias, receivers and pictures below are [camera]'s",
        names.len(),
        s.views.len(),
        names.join(", ")
    ))
}

/// The stdout line of a level: "views: 3 pooled; worst view: NAME (objective X; level Y)".
pub(crate) fn worst_line(s: &Summary, objective: SummaryMetric) -> Option<String> {
    let (_, name, value) = worst_view(s, objective)?;
    Some(format!(
        "views: {} pooled; worst view: {name} ({} {}; the level's {})",
        s.views.len(),
        objective.name(),
        n(value),
        n(objective.value(s))
    ))
}

/// The sweep's words on a level: how the views alone would choose and what the level's choice
/// costs each ("the high view alone picks λ 0.1; the level's choice costs it +8 %").
pub(crate) fn sweep_lines(r: &SweepResult) -> Vec<String> {
    let Some(c) = &r.level else {
        return Vec::new();
    };
    let at = &r.rows[c.at];
    let mut lines = vec![format!(
        "The level's {} pools {} views' receiver pixels; at its choice ({}) the worst view is {} ({} {}).",
        r.objective.name(),
        c.views.len(),
        at.setting.label(),
        c.views[c.worst].name,
        r.objective.name(),
        n(c.views[c.worst].objective_at_level)
    )];
    for v in &c.views {
        if !v.seen {
            lines.push(format!(
                "{}: sees no receiver (no surface facing the light on its screen): no screen metrics of its own",
                v.name
            ));
            continue;
        }
        let mut l = format!(
            "{}: {} {} at the level's choice",
            v.name,
            r.objective.name(),
            n(v.objective_at_level)
        );
        match (v.alone, v.objective_alone) {
            (Some(i), Some(o)) if i == c.at => {
                let _ = write!(l, "; alone it picks the same setting ({})", n(o));
            }
            (Some(i), Some(o)) => {
                let _ = write!(l, "; alone it picks {} ({})", r.rows[i].setting.label(), n(o));
                if let Some(cost) = v.cost {
                    let _ = write!(l, "; the level's choice costs it {}", signed_percent(100.0 * cost));
                }
            }
            _ => l.push_str("; alone nothing is acceptable"),
        }
        lines.push(l);
    }
    lines
}

/// `recommendation.json`'s `views`: each view's own choice beside the level's.
pub(crate) fn sweep_json(r: &SweepResult) -> Option<serde_json::Value> {
    let c = r.level.as_ref()?;
    Some(serde_json::json!({
        "count": c.views.len(),
        "worst_view": c.views[c.worst].name,
        "at": r.rows[c.at].setting.label(),
        "views": c.views.iter().map(|v| {
            let mut j = serde_json::json!({ "name": v.name });
            if v.seen {
                j["objective_at_level"] = v.objective_at_level.into();
            } else {
                j["sees_no_receiver"] = true.into();
            }
            if let (Some(i), Some(o)) = (v.alone, v.objective_alone) {
                j["alone"] = r.rows[i].setting.label().into();
                j["alone_objective"] = o.into();
            }
            if let Some(cost) = v.cost {
                j["level_cost_percent"] = (100.0 * cost).into();
            }
            j
        }).collect::<Vec<_>>(),
    }))
}

/// `views.csv` of `analyze`: each view at the analysed setting.
pub(crate) struct ViewsCsv;

impl crate::output::Exporter<crate::analysis::Analysis> for ViewsCsv {
    fn file_name(&self) -> &'static str {
        FILE
    }

    fn render(&self, a: &crate::analysis::Analysis) -> Result<Vec<u8>> {
        let objective = crate::commands::sweep::rank::default_objective(&a.config);
        csv(&a.config, &a.summary, objective, None)
    }
}

/// `views.png`'s name.
pub(crate) const SHEET: &str = "views.png";

/// `views.png` of `analyze` (two views or more): the contact sheet at the analysed setting.
pub(crate) struct ViewsPng;

impl crate::output::Exporter<crate::analysis::Analysis> for ViewsPng {
    fn file_name(&self) -> &'static str {
        SHEET
    }

    fn render(&self, a: &crate::analysis::Analysis) -> Result<Vec<u8>> {
        let objective = crate::commands::sweep::rank::default_objective(&a.config);
        let worst = worst_view(&a.summary, objective).map(|w| w.0);
        crate::figures::views::views_png(&a.config, worst)
    }
}

/// The sweep's `views.png` (two views or more): the sheet at the level's choice.
pub(crate) fn sweep_sheet(r: &SweepResult) -> Result<Option<Vec<u8>>> {
    let Some(c) = r.level.as_ref().filter(|c| c.views.len() >= 2) else {
        return Ok(None);
    };
    let config = r.rows[c.at].setting.apply(&r.config)?;
    crate::figures::views::views_png(&config, Some(c.worst)).map(Some)
}
