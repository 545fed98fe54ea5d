//! What `sweep` writes: `sweep.csv`, `recommendation.json`, four figures (SVG and PNG) and a
//! design-review report as one self-contained `report.html` (inline SVG and CSS) and as
//! `report.md`.

use std::fmt::Write as _;

use super::{defs, html, markdown};
use crate::analysis::mib;
use crate::commands::sweep::rank::{AlternativeKind, Loss, Rival, RivalKind, STABLE_SHIMMER};
use crate::commands::sweep::run::Row;
use crate::commands::sweep::sun::SUN_RULE;
use crate::commands::sweep::SweepResult;
use crate::config::Config;
use crate::error::Result;
use crate::figures::sweep::{HeatmapFigure, LambdaDensityFigure, ParetoFigure, ShimmerSweepFigure};
use crate::figures::Figure;
use crate::metric;
use crate::metric::worst_words;
use crate::output::{count, json_bytes, num, percent_change, short_number as n, signed_percent};

/// `sweep.csv`: [`metric::summary_columns`], then these.
pub(crate) const SWEEP_EXTRA_COLUMNS: [&str; 4] = ["cascades_needed", "pareto", "recommended", "preset"];

/// `sweep.csv`'s last columns in a sun sweep: the sun's angles and whether the row is its
/// setting's worst sun angle.
pub(crate) const SUN_COLUMNS: [&str; 3] = ["sun_azimuth_deg", "sun_elevation_deg", "worst_sun"];

/// `sweep.csv` streamed into the output set: each row is encoded as it is written, so a
/// 100,000-configuration sweep holds no copy of its CSV text.
pub(crate) struct SweepCsvFile<'a>(pub &'a SweepResult);

impl crate::output::StreamedFile for SweepCsvFile<'_> {
    fn file_name(&self) -> &str {
        "sweep.csv"
    }

    fn write_to(&self, out: &mut dyn std::io::Write) -> Result<()> {
        write_sweep_csv(self.0, out)
    }
}

/// `sweep.csv`, one row per configuration in grid order, written row by row to `out`.
fn write_sweep_csv(r: &SweepResult, out: &mut dyn std::io::Write) -> Result<()> {
    let rec = r.recommendation.as_ref().map(|x| x.index);
    // Empty for csm-lab's own pipeline.
    let preset = r
        .config
        .shadow
        .preset
        .as_ref()
        .map(|p| p.name.to_string())
        .unwrap_or_default();
    let mut on_front = vec![false; r.rows.len()];
    for &i in &r.front {
        on_front[i] = true;
    }
    // The knob and distance columns exist only when swept (csm-lab's own sweeps and presets
    // without them keep their columns): named by the config key they set.
    let knob_key = r
        .grid
        .knob
        .as_ref()
        .and(crate::presets::axes(&r.config).knob.map(|k| k.key));
    let distance = r.grid.distance.is_some();
    // A moving light adds its crawl and jump (configured snapping); a swept update rule its
    // column.
    let light = r.config.motion.light.moves();
    let light_update = r.grid.light_update.is_some();
    let update_every = r.grid.update_every.is_some();
    // A sun sweep writes every (sun, setting) row; `pareto` and `recommended` mark every row of
    // the setting, `worst_sun` the setting's worst angle.
    let (all, setting_of, worst): (&[Row], Vec<usize>, Vec<bool>) = match &r.sun {
        None => (&r.rows, (0..r.rows.len()).collect(), Vec::new()),
        Some(sun) => {
            let mut worst = vec![false; sun.all.len()];
            for &w in &sun.worst {
                worst[w] = true;
            }
            (&sun.all, sun.setting_of.clone(), worst)
        }
    };
    let cols = row_columns(r);
    let rows = all.iter().enumerate().map(|(k, row)| {
        let i = setting_of[k];
        let st = &row.setting;
        let mut fields = metric::summary_fields(
            num("lambda", st.lambda)?,
            st.cascades,
            st.resolution,
            st.fit.name(),
            st.split_range,
            &row.summary,
            cols,
        )?;
        // A shard's slice decides nothing: its pareto and recommended cells are empty.
        let decided = |b: bool| {
            if r.slice.is_some() {
                String::new()
            } else {
                b.to_string()
            }
        };
        fields.extend([
            row.summary.cascades_needed.to_string(),
            decided(on_front[i]),
            decided(rec == Some(i)),
            preset.clone(),
        ]);
        if let (Some(_), Some(k)) = (knob_key, st.knob) {
            fields.push(num("knob", k)?);
        }
        if let (true, Some(d)) = (distance, st.distance) {
            fields.push(num("distance", d)?);
        }
        if light {
            let l = row.summary.light.unwrap_or_default();
            fields.push(num("light_crawl", l.crawl)?);
            fields.push(num("light_jump", l.jump)?);
        }
        if let (true, Some(u)) = (light_update, st.light_update) {
            fields.push(crate::config::light_update_label(u));
        }
        if let (true, Some(u)) = (update_every, st.update_every) {
            fields.push(u.label());
        }
        if let Some(sun) = st.sun.filter(|_| r.sun.is_some()) {
            fields.push(num("sun_azimuth_deg", sun.azimuth_deg)?);
            fields.push(num("sun_elevation_deg", sun.elevation_deg)?);
            fields.push(decided(worst[k]));
        }
        Ok(fields)
    });
    let header: Vec<&str> = metric::summary_columns(cols)
        .into_iter()
        .chain(SWEEP_EXTRA_COLUMNS)
        .chain(knob_key)
        .chain(distance.then_some("shadow.max_distance"))
        .chain(light.then_some(["light_crawl", "light_jump"]).into_iter().flatten())
        .chain(light_update.then_some(crate::commands::check::sweep::LIGHT_UPDATE_COLUMN))
        .chain(update_every.then_some(crate::commands::check::sweep::UPDATE_EVERY_COLUMN))
        .chain(r.sun.iter().flat_map(|_| SUN_COLUMNS))
        .collect();
    crate::output::csv_write_from(out, &header, rows)
}

/// The optional columns of `sweep.csv`: the screen and cost columns with scene geometry,
/// `shadow_ms` when calibrated, the means over the path when the rows measured them.
pub(crate) fn row_columns(r: &SweepResult) -> metric::RowColumns {
    let screen = r.config.geometry.is_some();
    let rows = r.sun.as_ref().map_or(&r.rows[..], |s| &s.all[..]);
    metric::RowColumns {
        screen,
        calibrated: screen && r.config.cost.calibration.is_some(),
        means: rows.iter().any(|x| x.summary.cost.means.is_some()),
        cache: rows.iter().any(|x| x.summary.cache.is_some()),
    }
}

fn row_json(row: &Row) -> serde_json::Value {
    let mut v = serde_json::json!({
        "lambda": row.setting.lambda,
        "cascades": row.setting.cascades,
        "resolution": row.setting.resolution,
        "fit": row.setting.fit,
    });
    if row.summary.screen.is_some() {
        v["split_range"] = serde_json::json!(row.setting.split_range);
    }
    if let Some(k) = row.setting.knob {
        v["knob"] = serde_json::json!(k);
    }
    if let Some(d) = row.setting.distance {
        v["distance"] = serde_json::json!(d);
    }
    if let Some(sun) = row.setting.sun {
        v["worst_sun"] = serde_json::json!({
            "azimuth_deg": sun.azimuth_deg,
            "elevation_deg": sun.elevation_deg,
        });
    }
    if let Some(u) = row.setting.light_update {
        v["light_update"] = serde_json::json!(crate::config::light_update_label(u));
    }
    if let Some(u) = row.setting.update_every {
        v["update_every"] = serde_json::json!(u.label());
    }
    for (k, x) in metric::summary_json(&row.summary) {
        v[k] = x;
    }
    v
}

pub(crate) fn recommendation_value(r: &SweepResult) -> serde_json::Value {
    let mut v = serde_json::json!({
        "tool": format!("csm-lab {}", env!("CARGO_PKG_VERSION")),
        "name": r.config.name,
        "command": r.command,
        "configurations": r.rows.len(),
        "objective": r.objective_text,
        "objective_metric": r.objective.name(),
        "memory_budget_mib": r.budget_mib,
        "pareto_front": r.front.iter().map(|&i| row_json(&r.rows[i])).collect::<Vec<_>>(),
    });
    if let Some(b) = r.cost_limit.index {
        v["cost_budget"] = b.into();
    }
    if let Some(b) = r.cost_limit.ms {
        v["shadow_ms_budget"] = b.into();
    }
    if !r.cost_front.is_empty() {
        v["cost_pareto_front"] = r
            .cost_front
            .iter()
            .map(|&i| row_json(&r.rows[i]))
            .collect::<Vec<_>>()
            .into();
    }
    if let Some(o) = &r.optimized {
        v["optimized_splits"] = super::optimize::json(r, o);
    }
    if let (Some(sun), Some(grid)) = (&r.sun, &r.grid.sun) {
        v["sun_angles"] = grid.len().into();
        v["sun_rows"] = sun.all.len().into();
        v["sun_rule"] = SUN_RULE.into();
        if let Some(note) = &r.sun_note {
            v["light_independent"] = note.as_str().into();
        }
    }
    // The swept axes the recommendation sits at the first or last value of (empty when none,
    // and without a recommendation); each with the range to try next.
    v["range_edges"] = r.range_edges.iter().map(|e| e.axis).collect::<Vec<_>>().into();
    if !r.range_edges.is_empty() {
        v["range_edge_suggestions"] = r
            .range_edges
            .iter()
            .map(|e| {
                serde_json::json!({
                    "axis": e.axis,
                    "value": e.value,
                    "edge": if e.high { "last" } else { "first" },
                    "try": e.suggestion(),
                })
            })
            .collect::<Vec<_>>()
            .into();
    }
    match (r.recommendation.as_ref(), r.recommended()) {
        (Some(rec), Some(row)) => {
            v["within_budget"] = rec.within_budget.into();
            v["recommended"] = row_json(row);
            if r.cost_limit.is_set() {
                v["within_cost_budget"] = rec.within_cost.into();
                v["cost_budget_effect"] = cost_budget_text(r).trim().into();
                if let Some(i) = r.without_cost_budget {
                    let free = &r.rows[i];
                    let mut j = serde_json::json!({ "configuration": row_json(free) });
                    if let Some(p) = percent_change(r.objective.value(&free.summary), r.objective.value(&row.summary)) {
                        j["objective_change_percent"] = p.into();
                    }
                    v["without_cost_budget"] = j;
                }
            }
            v["alternatives"] = r
                .alternatives
                .iter()
                .map(|a| {
                    let x = &r.rows[a.index];
                    let mut j = serde_json::json!({
                        "kind": a.kind.name(),
                        "rule": a.kind.rule(),
                        "within_budget": x.summary.memory_bytes <= rec.budget_bytes,
                    });
                    for (key, base, value) in [
                        (
                            "memory_change_percent",
                            row.summary.memory_bytes as f64,
                            x.summary.memory_bytes as f64,
                        ),
                        (
                            "objective_change_percent",
                            r.objective.value(&row.summary),
                            r.objective.value(&x.summary),
                        ),
                        (
                            // Named after the worst case it compares: `max_aliasing` without
                            // geometry, `screen_aliasing_max` with it.
                            worst_change_key(r),
                            r.worst.value(&row.summary),
                            r.worst.value(&x.summary),
                        ),
                        ("shimmer_change_percent", row.summary.shimmer, x.summary.shimmer),
                        (
                            "cost_index_change_percent",
                            row.summary.cost.cost_index.unwrap_or(0.0),
                            x.summary.cost.cost_index.unwrap_or(0.0),
                        ),
                    ] {
                        // Absent when the recommendation's value is 0 (no relative change).
                        if let Some(p) = percent_change(base, value) {
                            j[key] = p.into();
                        }
                    }
                    j["shimmer_change_texels"] = (x.summary.shimmer - row.summary.shimmer).into();
                    j["configuration"] = row_json(x);
                    j
                })
                .collect::<Vec<_>>()
                .into();
            v["rivals"] = r
                .rivals
                .iter()
                .map(|x| {
                    serde_json::json!({
                        "kind": x.kind.name(),
                        "lost_on": loss_name(r, x.loss),
                        "why": rival_text(r, x),
                        "configuration": row_json(&r.rows[x.index]),
                    })
                })
                .collect::<Vec<_>>()
                .into();
        }
        _ => {
            // No null (every number must be finite): the reasons and the closest row instead.
            let n = &r.no_recommendation;
            let mut none = serde_json::json!({
                "why": why_text(r),
                "configurations_without_cascades": n.no_cascades,
                "configurations_with_coverage_misses": n.coverage_misses,
                "configurations_unstable_when_snapped": n.unstable,
            });
            if let Some(i) = n.closest {
                none["closest"] = row_json(&r.rows[i]);
            }
            v["no_recommendation"] = none;
        }
    }
    if let Some(views) = super::views::sweep_json(r) {
        v["views"] = views;
    }
    if let Some(c) = &r.light_update {
        // A kind none of whose steps stays calm (or that was not swept) has no key: no null.
        let mut u = serde_json::json!({
            "why": c.sentence,
            "at": row_json(&r.rows[c.at]),
        });
        for (key, x) in [("largest_calm_every", c.every), ("largest_calm_quantize", c.quantize)] {
            if let Some(x) = x {
                u[key] = serde_json::json!({
                    "rule": crate::config::light_update_label(x.update),
                    "light_jump": x.jump,
                    "light_crawl": x.crawl,
                });
            }
        }
        v["light_update"] = u;
    }
    v
}

// ---------------------------------------------------------------------------------------------
// Reports
// ---------------------------------------------------------------------------------------------

fn v3(v: glam::DVec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

/// The scene and camera in words and numbers, as (label, text) pairs.
fn scene_facts(c: &Config, rows: &[Row]) -> Vec<(String, String)> {
    let cam = &c.camera;
    let dir = (cam.target - cam.position).normalize();
    let pitch = dir.y.asin().to_degrees();
    let l = c.light_direction;
    let elevation = (-l.y).asin().to_degrees();
    let size = c.scene.max - c.scene.min;
    let mut v = vec![
        (
            "Camera".to_string(),
            format!(
                "at {} looking toward {} ({:.1}° {} the horizon), vertical field of view {}°, near {}, far {}",
                v3(cam.position),
                v3(cam.target),
                pitch.abs(),
                if pitch < 0.0 { "below" } else { "above" },
                cam.fov_y_deg,
                cam.near,
                cam.far
            ),
        ),
        (
            "Screen".to_string(),
            format!("{} × {} pixels", c.screen.width, c.screen.height),
        ),
        (
            "Light".to_string(),
            format!(
                "travels along {} (normalised {}), {:.1}° above the horizon",
                v3(c.light_direction_as_written),
                format_args!("({:.4}, {:.4}, {:.4})", l.x, l.y, l.z),
                elevation
            ),
        ),
        (
            "Scene bounds".to_string(),
            format!(
                "{} to {} ({} × {} × {} world units)",
                v3(c.scene.min),
                v3(c.scene.max),
                size.x,
                size.y,
                size.z
            ),
        ),
        (
            "Shadow distance".to_string(),
            format!(
                "{} ({})",
                c.shadow.max_distance,
                if c.shadow.fit_depth_to_scene {
                    "split range clipped to where the scene is visible"
                } else {
                    "split range from the near plane"
                }
            ),
        ),
        (
            "Motion for shimmer".to_string(),
            format!(
                "{} over {} frames, step {} {}",
                c.motion.path.name(),
                c.motion.frames,
                c.motion.step_as_written,
                if c.motion.path.is_translation() {
                    "world units per frame"
                } else {
                    "degrees per frame"
                }
            ),
        ),
    ];
    if let Some(p) = &c.shadow.preset {
        v.push((
            "Engine preset".to_string(),
            format!(
                "{} ({}); the sweep varies only the axes this engine has",
                p.name,
                crate::presets::split_rule(&p.knobs)
            ),
        ));
    }
    if let Some(r) = rows.iter().find(|r| r.summary.cascades_needed) {
        v.push((
            "Depth range split".to_string(),
            format!("{} to {}", n(r.summary.z_lo), n(r.summary.z_hi)),
        ));
    }
    v
}

fn why_text(r: &SweepResult) -> String {
    let Some(rec) = r.recommended() else {
        let nr = &r.no_recommendation;
        let Some(c) = nr.closest else {
            return "The scene is not visible within the shadow distance: no cascades are needed.".to_string();
        };
        let x = &r.rows[c];
        let total = r.rows.len();
        return format!(
            "Nothing qualifies: of {}, {} miss slice corners (coverage_violations > 0) and {} shimmer when snapped (shimmer_snapped > {} texel){}. Closest: {}: {}, snapped shimmer {}, mean aliasing {}, {} MiB.",
            count(total as u64, "configuration"),
            nr.coverage_misses,
            nr.unstable,
            n(STABLE_SHIMMER),
            if nr.no_cascades > 0 {
                format!(", {} need no cascades", nr.no_cascades)
            } else {
                String::new()
            },
            setting_text(r, x),
            count(x.summary.coverage_violations, "coverage violation"),
            n(x.summary.shimmer_snapped),
            n(x.summary.mean_aliasing),
            n(mib(x.summary.memory_bytes)),
        );
    };
    let s = &rec.summary;
    let acceptable_within = r
        .rows
        .iter()
        .filter(|x| {
            x.summary.cascades_needed
                && x.summary.coverage_violations == 0
                && x.summary.snapped_drift() <= STABLE_SHIMMER
                && x.summary.memory_bytes as f64 <= r.budget_mib * 1048576.0
        })
        .count();
    let screen = r.objective.name() != "mean_aliasing";
    let mut t = if let Some(st) = s.screen.as_ref().filter(|_| screen) {
        format!(
            "{}: {} {} on screen (per-pixel aliasing: median {}, worst {}; {} % of the receiver \
             pixels under-sampled), {} MiB. ",
            setting_text(r, rec),
            r.objective.name(),
            n(r.objective.value(s)),
            n(st.aliasing_p50),
            n(st.aliasing_max),
            n(100.0 * st.undersampled_fraction),
            n(mib(s.memory_bytes))
        )
    } else {
        format!(
            "{}: mean aliasing {}, worst {} {}, {} % of the depth range \
             under-sampled, {} MiB. ",
            setting_text(r, rec),
            n(s.mean_aliasing),
            n(r.worst.value(s)),
            if s.screen.is_some() {
                "on screen"
            } else {
                "at a cascade's near edge"
            },
            n(100.0 * s.undersampled_fraction),
            n(mib(s.memory_bytes))
        )
    };
    if r.recommendation.as_ref().is_some_and(|x| x.within_budget) {
        let _ = write!(
            t,
            "Of {}, {} fit the {} MiB budget, cover every slice and are stable when snapped; \
             this one has the lowest {} among them (within 1 %, the lowest worst case).",
            count(r.rows.len() as u64, "configuration"),
            acceptable_within,
            n(r.budget_mib),
            if screen { r.objective.name() } else { "mean aliasing" }
        );
    } else {
        let _ = write!(
            t,
            "Nothing fits the {} MiB budget; this is the cheapest configuration that covers every slice and is stable.",
            n(r.budget_mib)
        );
    }
    t.push_str(&cost_budget_text(r));
    if let Some(o) = r.configured.map(|i| &r.rows[i]) {
        let change = changes(r, o, rec);
        if !change.is_empty() && screen {
            let _ = write!(
                t,
                " To get it, change {} (the configured setting has {} {}, {} MiB).",
                change.join(", "),
                r.objective.name(),
                n(r.objective.value(&o.summary)),
                n(mib(o.summary.memory_bytes))
            );
        } else if !change.is_empty() {
            let _ = write!(
                t,
                " To get it, change {} (the configured setting has mean aliasing {}, worst {}, {} MiB).",
                change.join(", "),
                n(o.summary.mean_aliasing),
                n(r.worst.value(&o.summary)),
                n(mib(o.summary.memory_bytes))
            );
        } else {
            t.push_str(" It is the configured setting: keep it.");
        }
    }
    t
}

/// The ground-truth pictures of a pass (`shadow.png`, `flicker.png`, the animation when small
/// enough to embed) as a report section.
fn truth_pictures(g: &crate::analysis::ground_truth::GroundTruth, label: &str) -> String {
    use super::ground_truth::{animation_of, flicker_png_of, shadow_png_of};
    use super::truth::{section, Animation, TruthPictures, INLINE_ANIMATION_LIMIT};
    let pictures = TruthPictures {
        shadow_png: shadow_png_of(g).ok(),
        flicker_png: flicker_png_of(g).ok(),
        animation: animation_of(g)
            .ok()
            .filter(|b| b.len() <= INLINE_ANIMATION_LIMIT)
            .map(Animation::Bytes),
    };
    section(label, &pictures)
}

/// "3 cascades of 2048² texels, λ = 0.8, sphere fit": a row's setting in the sweep's words.
fn setting_text(r: &SweepResult, x: &Row) -> String {
    format!(
        "{} of {}² texels, {}",
        count(x.setting.cascades as u64, "cascade"),
        x.setting.resolution,
        setting_knobs(r, x)
    )
}

/// The key of an alternative's change in the worst case in `recommendation.json`.
fn worst_change_key(r: &SweepResult) -> &'static str {
    if r.worst.name() == "max_aliasing" {
        "max_aliasing_change_percent"
    } else {
        "screen_aliasing_max_change_percent"
    }
}

/// "name value (+16 %)": a metric of `x` against the recommendation's `base`.
fn versus(name: &str, base: f64, value: f64) -> String {
    match percent_change(base, value) {
        _ if base == value => format!("{name} {} (the same)", n(value)),
        Some(p) => format!("{name} {} ({})", n(value), signed_percent(p)),
        None => format!("{name} {} (recommendation: {})", n(value), n(base)),
    }
}

/// What choosing `x` instead of the recommendation `rec` costs and gains.
fn cost_text(r: &SweepResult, rec: &Row, x: &Row) -> String {
    let (a, b) = (&rec.summary, &x.summary);
    let mut parts = vec![format!(
        "{} MiB ({} memory{})",
        n(mib(b.memory_bytes)),
        percent_change(a.memory_bytes as f64, b.memory_bytes as f64).map_or("same".into(), signed_percent),
        if b.memory_bytes as f64 > r.budget_mib * 1048576.0 {
            format!(", over the {} MiB budget", n(r.budget_mib))
        } else {
            String::new()
        }
    )];
    parts.push(versus(r.objective.name(), r.objective.value(a), r.objective.value(b)));
    if r.objective != r.worst {
        parts.push(versus(worst_words(r.worst).0, r.worst.value(a), r.worst.value(b)));
    }
    parts.push(versus("shimmer", a.shimmer, b.shimmer));
    parts.join(", ")
}

/// What the render-cost budget did to the recommendation, one or two sentences (empty
/// without a cost budget).
pub(crate) fn cost_budget_text(r: &SweepResult) -> String {
    let (Some(rec), Some(row)) = (r.recommendation.as_ref(), r.recommended()) else {
        return String::new();
    };
    if !r.cost_limit.is_set() {
        return String::new();
    }
    let own = row.summary.cost.cost_index.map_or("n/a".to_string(), n);
    if !rec.within_cost {
        return format!(
            " Nothing within the memory budget fits the render-cost budget ({}): this is the cheapest to render (cost_index {own}).",
            cost_budget_words(r)
        );
    }
    match r.without_cost_budget.map(|i| &r.rows[i]) {
        None => format!(
            " It fits the render-cost budget ({}) at cost_index {own}, and the budget changed nothing.",
            cost_budget_words(r)
        ),
        Some(free) => {
            let (a, b) = (r.objective.value(&free.summary), r.objective.value(&row.summary));
            format!(
                " The render-cost budget ({}) cost quality: without it the recommendation would be {} ({} {}, cost_index {}); within it {} {} at cost_index {own}{}.",
                cost_budget_words(r),
                setting_text(r, free),
                r.objective.name(),
                n(a),
                free.summary.cost.cost_index.map_or("n/a".to_string(), n),
                r.objective.name(),
                n(b),
                percent_change(a, b).map_or(String::new(), |p| format!(" ({})", signed_percent(p)))
            )
        }
    }
}

/// The render-cost budget in words: "cost_index 0.8" and/or "shadow_ms 1.2 ms".
pub(crate) fn cost_budget_words(r: &SweepResult) -> String {
    let l = &r.cost_limit;
    let mut parts = Vec::new();
    if let Some(b) = l.index {
        parts.push(format!("cost_index {}", n(b)));
    }
    if let Some(b) = l.ms {
        parts.push(format!("shadow_ms {} ms", n(b)));
    }
    parts.join(" and ")
}

/// What rendering `x` instead of the recommendation `rec` saves and what it loses in quality.
fn render_text(r: &SweepResult, rec: &Row, x: &Row) -> String {
    let (a, b) = (&rec.summary, &x.summary);
    let mut parts = Vec::new();
    if let (Some(ca), Some(cb)) = (a.cost.cost_index, b.cost.cost_index) {
        let saving = percent_change(ca, cb).map_or(String::new(), |p| {
            format!(", saves {}", signed_percent(-p).trim_start_matches('+'))
        });
        parts.push(format!("cost_index {} against {}{saving}", n(cb), n(ca)));
    }
    if let (Some(ma), Some(mb)) = (a.cost.shadow_ms, b.cost.shadow_ms) {
        parts.push(format!("shadow_ms {} against {}", n(mb), n(ma)));
    }
    if let (Some(ka), Some(kb)) = (a.cost.counts, b.cost.counts) {
        parts.push(format!("{} draws against {}", kb.caster_objects, ka.caster_objects));
    }
    parts.push(format!(
        "quality lost: {}",
        versus(r.objective.name(), r.objective.value(a), r.objective.value(b))
    ));
    parts.join(", ")
}

/// One line per alternative kind: the alternative and its cost, or why there is none.
fn alternative_lines(r: &SweepResult) -> Vec<String> {
    let Some(rec) = r.recommended() else {
        return Vec::new();
    };
    let alts = &r.alternatives;
    let kinds: &[AlternativeKind] = if rec.summary.cost.cost_index.is_some() {
        &[
            AlternativeKind::Cheaper,
            AlternativeKind::Sharper,
            AlternativeKind::MoreStable,
            AlternativeKind::CheaperToRender,
        ]
    } else {
        &[
            AlternativeKind::Cheaper,
            AlternativeKind::Sharper,
            AlternativeKind::MoreStable,
        ]
    };
    kinds
    .iter()
    .map(|&kind| {
        let head = match kind {
            AlternativeKind::Cheaper => "Cheaper",
            AlternativeKind::Sharper => "Sharper",
            AlternativeKind::MoreStable => "More stable",
            AlternativeKind::CheaperToRender => "Cheaper to render",
        };
        match alts.iter().find(|a| a.kind == kind) {
            Some(a) if kind == AlternativeKind::CheaperToRender => {
                let x = &r.rows[a.index];
                format!("{head}: {}: {}.", setting_text(r, x), render_text(r, rec, x))
            }
            Some(a) => {
                let x = &r.rows[a.index];
                format!("{head}: {}: {}.", setting_text(r, x), cost_text(r, rec, x))
            }
            None => format!(
                "{head}: none. {}",
                match kind {
                    AlternativeKind::Cheaper =>
                        "No configuration that covers every slice and is stable needs less memory.".to_string(),
                    AlternativeKind::Sharper => format!(
                        "No configuration that covers every slice and is stable has a {} more than 1 % lower.",
                        r.objective.name()
                    ),
                    AlternativeKind::MoreStable => format!(
                        "No configuration within the budget that covers every slice shimmers less (the recommendation's shimmer is {} texel per frame).",
                        n(rec.summary.shimmer)
                    ),
                    AlternativeKind::CheaperToRender => format!(
                        "No configuration within the memory budget that covers every slice and is stable costs less to render (the recommendation's cost_index is {}).",
                        rec.summary.cost.cost_index.map_or("n/a".to_string(), n)
                    ),
                }
            ),
        }
    })
    .collect()
}

/// The `lost_on` word of `recommendation.json`'s rivals (a tie lost on the worst case is named
/// after that metric: `max_aliasing`, or `screen_aliasing_max` with geometry).
fn loss_name(r: &SweepResult, l: Loss) -> &'static str {
    match l {
        Loss::CoverageMisses(_) => "coverage",
        Loss::Unstable(_) => "stability",
        Loss::OverBudget => "memory_budget",
        Loss::OverCostBudget => "cost_budget",
        Loss::MoreMemory => "memory",
        Loss::Objective => "objective",
        Loss::MaxAliasing => r.worst.name(),
        Loss::TieMemory => "memory_tie",
        Loss::TieOrder => "order_tie",
    }
}

/// One sentence: which rival, and the budget or metric it lost on, by how much.
fn rival_text(r: &SweepResult, x: &Rival) -> String {
    let rec = r.recommended().expect("rivals need a recommendation");
    let row = &r.rows[x.index];
    let (a, b) = (&rec.summary, &row.summary);
    let who = match x.kind {
        RivalKind::LambdaOne => "The same setting with λ = 1",
        RivalKind::OtherCascades => "The best setting with another cascade count",
        RivalKind::OtherResolution => "The best setting with another resolution",
        RivalKind::OtherFit => "The best setting with the other fit",
        RivalKind::Configured => "The configured setting",
    };
    // A group's best that is also the configured setting says so (it is listed once).
    let who = if x.kind != RivalKind::Configured && r.configured == Some(x.index) {
        format!("{who}, which is the configured setting")
    } else {
        who.to_string()
    };
    let obj = r.objective.name();
    let (va, vb) = (r.objective.value(a), r.objective.value(b));
    let pct = |base: f64, v: f64| percent_change(base, v).map_or(String::new(), |p| format!(", {}", signed_percent(p)));
    let why = match x.loss {
        Loss::CoverageMisses(c) => format!(
            "lost on coverage: {} outside their windows along the path (the recommendation has none)",
            count(c, "slice corner")
        ),
        Loss::Unstable(v) => format!(
            "lost on stability: it shimmers {} texel per frame when snapped, above the {} texel limit",
            n(v),
            n(STABLE_SHIMMER)
        ),
        Loss::OverBudget => format!(
            "lost on the memory budget: it needs {} MiB, over the {} MiB budget (the recommendation {} MiB), for {} {} against {}{}",
            n(mib(b.memory_bytes)),
            n(r.budget_mib),
            n(mib(a.memory_bytes)),
            obj,
            n(vb),
            n(va),
            pct(va, vb)
        ),
        Loss::OverCostBudget => format!(
            "lost on the render-cost budget: cost_index {}{}, over the budget ({}), for {} {} against {}{}",
            b.cost.cost_index.map_or("n/a".to_string(), n),
            b.cost.shadow_ms.map_or(String::new(), |ms| format!(" ({} ms)", n(ms))),
            cost_budget_words(r),
            obj,
            n(vb),
            n(va),
            pct(va, vb)
        ),
        Loss::MoreMemory => format!(
            "lost on memory: nothing fits the budget, and it needs {} MiB where the recommendation needs {} MiB",
            n(mib(b.memory_bytes)),
            n(mib(a.memory_bytes))
        ),
        Loss::Objective => format!("lost on {obj}: {} against {}{}", n(vb), n(va), pct(va, vb)),
        Loss::MaxAliasing => format!(
            "tied on {obj} (within 1 %) and lost on {}: {} against {}{}",
            worst_words(r.worst).0,
            n(r.worst.value(b)),
            n(r.worst.value(a)),
            pct(r.worst.value(a), r.worst.value(b))
        ),
        Loss::TieMemory => format!(
            "tied on {obj} and {}, and needs more memory: {} MiB against {} MiB",
            worst_words(r.worst).0,
            n(mib(b.memory_bytes)),
            n(mib(a.memory_bytes))
        ),
        Loss::TieOrder => {
            "tied on every measure; the recommendation has fewer cascades or comes first in the grid".to_string()
        }
    };
    format!("{who} ({}) {why}.", setting_text(r, row))
}

/// One sentence per swept axis the recommendation sits at the edge of
/// ([`SweepResult::range_edges`]).
pub(crate) fn edge_lines(r: &SweepResult) -> Vec<String> {
    r.range_edges.iter().map(|e| e.text()).collect()
}

/// One sentence per main rival ([`SweepResult::rivals`]).
fn rival_lines(r: &SweepResult) -> Vec<String> {
    r.rivals.iter().map(|x| rival_text(r, x)).collect()
}

const TOP: usize = 15;

/// The figures of a sweep as (file stem, title, SVG bytes), rendered once.
pub(crate) fn render_figures(r: &SweepResult) -> Result<Vec<(&'static str, String, Vec<u8>)>> {
    // The four figures are independent: drawn concurrently (the first error in this order wins).
    let ((heatmap, density), (shimmer, pareto)) = rayon::join(
        || rayon::join(|| HeatmapFigure(r).to_svg(), || LambdaDensityFigure::new(r).to_svg()),
        || rayon::join(|| ShimmerSweepFigure(r).to_svg(), || ParetoFigure(r).to_svg()),
    );
    let captions = figure_captions(r);
    let mut out = vec![
        ("heatmap", captions[0].clone(), heatmap?),
        ("density_lambda", captions[1].clone(), density?),
        ("shimmer_sweep", captions[2].clone(), shimmer?),
        ("pareto", captions[3].clone(), pareto?),
    ];
    // Only a sun sweep has the sun figure (other sweeps keep their files).
    // Only a sweep with a ground-truth sample has the flicker scatter.
    // Only a sweep whose rows have a render cost (scene geometry) has the cost figure.
    if !r.cost_front.is_empty() {
        out.push((
            "cost_pareto",
            "Pareto front of the render cost (cost_index) against the objective".to_string(),
            crate::figures::sweep::CostParetoFigure(r).to_svg()?,
        ));
    }
    out.extend(super::flicker_sample::figure(r)?);
    if r.sun.is_some() {
        out.push((
            "quality_vs_sun",
            format!(
                "{} (the objective) over sun azimuth × elevation for the recommended setting, its worst sun marked",
                r.objective.name()
            ),
            crate::figures::sun::QualityVsSunFigure(r).to_svg()?,
        ));
    }
    Ok(out)
}

/// The captions of the heat map, the λ density, the shimmer and the Pareto figures, from the
/// metrics the figures draw: the objective the verdict minimises and the worst case it breaks
/// ties on ([`SweepResult::objective`], [`SweepResult::worst`]), so a caption never names a
/// metric its figure does not show.
pub(crate) fn figure_captions(r: &SweepResult) -> [String; 4] {
    let x = match (r.grid.lambda.values.len() > 1, crate::presets::axes(&r.config).knob) {
        (true, _) => "λ".to_string(),
        (false, Some(k)) if r.grid.knob.as_ref().is_some_and(|v| v.values.len() > 1) => k.term.to_string(),
        _ => "resolution".to_string(),
    };
    let metrics: Vec<&str> = {
        let mut v = Vec::new();
        if r.objective.name() != "mean_aliasing" {
            v.push(r.objective.name());
        }
        v.push("mean_aliasing");
        v.push(r.worst.name());
        v
    };
    let worst = if r.worst.name() == "max_aliasing" {
        "max"
    } else {
        "worst on screen"
    };
    [
        format!(
            "{} over {x} × cascade count, one panel each (the objective: {})",
            metrics.join(", "),
            r.objective.name()
        ),
        format!(
            "Texels per pixel against depth for several λ at the recommended count and resolution (legend: mean aliasing and {worst} per λ)"
        ),
        "Shimmer snapped vs unsnapped for every configuration".to_string(),
        format!("Pareto front of memory against {} (the objective)", r.objective.name()),
    ]
}

/// The largest number of Pareto rows a report table shows (the rest are in `sweep.csv`).
const TOP_FRONT: usize = 40;

/// A row's standing in one word or two: recommended, an alternative, acceptable, or what
/// rules it out.
fn status(r: &SweepResult, i: usize) -> String {
    if r.recommendation.as_ref().is_some_and(|x| x.index == i) {
        return "recommended".into();
    }
    if let Some(a) = r.alternatives.iter().find(|a| a.index == i) {
        return format!("{} alternative", a.kind.name().replace('_', " "));
    }
    let s = &r.rows[i].summary;
    if s.coverage_violations > 0 {
        "misses slice corners".into()
    } else if s.snapped_drift() > STABLE_SHIMMER {
        "unstable when snapped".into()
    } else if s.memory_bytes as f64 > r.budget_mib * 1048576.0 {
        "over budget".into()
    } else {
        "acceptable".into()
    }
}

/// What [`config_table`] returns.
type ConfigTable = (Vec<&'static str>, Vec<Vec<String>>, Vec<usize>, Vec<(String, String)>);

/// A table of configurations: (header, rows, left-aligned columns, definitions). λ and fit
/// appear only when the sweep's settings have them; the objective when it is not the mean.
fn config_table(r: &SweepResult, idx: &[usize]) -> ConfigTable {
    let lambda = has_lambda(r);
    let fit = r.config.shadow.preset.is_none();
    let screen = r.objective.name() != "mean_aliasing";
    let mut head = vec!["cascades", "resolution"];
    let mut left = Vec::new();
    if lambda {
        head.push("λ");
    }
    if fit {
        left.push(head.len());
        head.push("fit");
    }
    if let Some(&i) = idx.first() {
        head.extend(axis_cells(r, &r.rows[i]).into_iter().map(|(h, _)| h));
    }
    if screen {
        head.push(r.objective.name());
    }
    head.extend([
        "mean aliasing",
        worst_words(r.worst).0,
        "shimmer",
        "shimmer snapped",
        "coverage misses",
        "MiB",
    ]);
    left.push(head.len());
    head.push("status");
    let rows = idx
        .iter()
        .map(|&i| {
            let x = &r.rows[i];
            let s = &x.summary;
            let mut v = vec![x.setting.cascades.to_string(), x.setting.resolution.to_string()];
            if lambda {
                v.push(n(x.setting.lambda));
            }
            if fit {
                v.push(fit_cell(x));
            }
            v.extend(axis_cells(r, x).into_iter().map(|(_, c)| c));
            if screen {
                v.push(n(r.objective.value(s)));
            }
            v.extend([
                n(s.mean_aliasing),
                n(r.worst.value(s)),
                n(s.shimmer),
                n(s.shimmer_snapped),
                s.coverage_violations.to_string(),
                n(mib(s.memory_bytes)),
                status(r, i),
            ]);
            v
        })
        .collect();
    let mut d = defs::settings(lambda, fit);
    if screen {
        d.push(defs::metric(r.objective.name(), r.objective.name()));
    }
    d.extend([
        defs::metric("mean aliasing", "mean_aliasing"),
        defs::metric(worst_words(r.worst).0, r.worst.name()),
        defs::metric("shimmer", "shimmer"),
        defs::metric("shimmer snapped", "shimmer_snapped"),
        defs::metric("coverage misses", "coverage_violations"),
        defs::memory("MiB"),
        defs::other(
            "status",
            &format!(
                "recommended, one of the alternatives, acceptable (covers every slice, snapped shimmer at most {} texel, within the {} MiB budget), or what rules it out",
                n(STABLE_SHIMMER),
                n(r.budget_mib)
            ),
        ),
    ]);
    (head, rows, left, d)
}

/// The Pareto rows a report shows (at most [`TOP_FRONT`]) and how many are left out.
fn front_shown(r: &SweepResult) -> (Vec<usize>, usize) {
    let shown: Vec<usize> = r.front.iter().copied().take(TOP_FRONT).collect();
    let left = r.front.len() - shown.len();
    (shown, left)
}

/// The top rows by the recommendation rule, at most [`TOP`].
fn top_shown(r: &SweepResult) -> Vec<usize> {
    r.ranked.iter().copied().take(TOP).collect()
}

/// "N configurations: a λ values × b cascade counts × …, each analysed in full".
fn grid_sentence(r: &SweepResult) -> String {
    format!(
        "{}: {}, each analysed in full",
        count(r.rows.len() as u64, "configuration"),
        grid_factors(r)
    )
}

/// The grid's axes as factors: "a λ values × b cascade counts × c resolutions × d fits…".
fn grid_factors(r: &SweepResult) -> String {
    format!(
        "{} × {} × {} × {}{}",
        count(r.grid.lambda.values.len() as u64, "λ value"),
        count(r.grid.cascades.values.len() as u64, "cascade count"),
        count(r.grid.resolution.values.len() as u64, "resolution"),
        count(r.grid.fit.values.len() as u64, "fit"),
        ranges_factor(r)
    )
}

/// The sentence under the tables: what they leave out, and where the rest is.
fn rest_sentence(r: &SweepResult, front_left: usize) -> String {
    format!(
        "The tables show the Pareto front{} and the top {} by the recommendation rule; all {} are in sweep.csv (one row each, with pareto and recommended columns).",
        if front_left > 0 {
            format!(" (first {TOP_FRONT} of {} rows)", r.front.len())
        } else {
            String::new()
        },
        TOP.min(r.rows.len()),
        count(r.rows.len() as u64, "configuration")
    )
}

/// `report.html`: one self-contained, well-formed (XHTML-compatible) document in the shared
/// report look ([`html::page`]). It opens with the verdict, the alternatives and why the main
/// rivals lost; its tables show the Pareto front and the top rows, with every metric defined
/// under them; a figure too large to inline as SVG is inlined as a downscaled PNG linked to its
/// files ([`html::figure_bounded`]), so the page stays small at any grid size and shows every
/// figure when sent on its own. A level's contact sheet (`views.png`) is shown in its "Views"
/// section when one was drawn.
pub(crate) fn report_html(
    r: &SweepResult,
    figures: &[(&str, String, Vec<u8>)],
    inline: &[Option<(Vec<u8>, u32)>],
    sheet: Option<&[u8]>,
    plan: Option<&[u8]>,
) -> Result<Vec<u8>> {
    let mut h = String::new();
    h.push_str("<h2>Verdict</h2>\n");
    let _ = writeln!(h, "<div class=\"rec-box\"><p>{}</p>", html::escape(&why_text(r)));
    let _ = writeln!(
        h,
        "<p><em>Objective:</em> {}.</p></div>",
        html::escape(&r.objective_text)
    );
    let edges = edge_lines(r);
    if !edges.is_empty() {
        h.push_str("<h2>Edges of the range</h2>\n");
        h.push_str(&html::list(&edges, None));
    }
    let alts = alternative_lines(r);
    if !alts.is_empty() {
        h.push_str("<h2>Alternatives</h2>\n");
        h.push_str(&html::list(&alts, None));
    }
    let rivals = rival_lines(r);
    if !rivals.is_empty() {
        h.push_str("<h2>Why the main rivals lost</h2>\n");
        h.push_str(&html::list(&rivals, None));
    }
    h.push_str(&super::optimize::html_section(r));
    h.push_str(&super::flicker_sample::html_section(r));
    let sun = sun_lines(r);
    if !sun.is_empty() {
        h.push_str("<h2>Sun angles</h2>\n");
        h.push_str(&html::list(&sun, None));
    }
    let views = super::views::sweep_lines(r);
    if !views.is_empty() {
        h.push_str("<h2>Views</h2>\n");
        h.push_str(&html::list(&views, None));
        h.push_str(
            "<p>Each view's own screen metrics at the level's choice: <a href=\"views.csv\">views.csv</a>.</p>\n",
        );
        if let Some(png) = sheet {
            h.push_str(&html::png_figures(&[(
                png.to_vec(),
                "views.png: every view's per-pixel aliasing at the level's choice, one colour scale; the worst view framed in red".to_string(),
            )]));
        }
    }
    let _ = writeln!(
        h,
        "<h2>Sweep</h2>\n<p>{} (closed-form aliasing, shimmer with and without snapping along the motion path, coverage).</p>",
        html::escape(&grid_sentence(r))
    );
    h.push_str("<h2>Scene</h2>\n");
    h.push_str(&html::facts(&scene_facts(&r.config, &r.rows)));
    // Where the views stand (plan.png), with scene geometry.
    if let Some(png) = plan {
        // A level's views are coloured by their objective at the level's choice.
        let coloured = r.level.as_ref().map(|_| r.objective.name());
        h.push_str(&html::png_figures(&[(
            png.to_vec(),
            crate::figures::plan::caption(&r.config, coloured),
        )]));
    }
    // The camera view of the recommended configuration, with scene geometry.
    if let (Some(rec), Some(_)) = (r.recommended(), &r.config.geometry) {
        if let Ok(cfg) = rec.setting.apply(&r.config) {
            let a = crate::analysis::analyze(&cfg, &crate::analysis::AnalysisOptions::summary_only());
            let label = format!("recommended ({})", setting_text(r, rec));
            let images = crate::figures::screen::captioned(&a, &label);
            h.push_str(&html::png_figures(&images));
            // A ground-truth sweep shows what the recommended setting's maps do on screen (the
            // pass its sample already ran).
            if let Some(g) = r.flicker.as_ref().and_then(|f| f.recommended_truth.as_deref()) {
                h.push_str(&truth_pictures(g, &label));
            }
            // A level: the worst view at the recommended setting.
            if let Some(c) = &r.level {
                let view = &cfg.views[c.worst];
                let wa = crate::analysis::analyze(
                    &crate::analysis::config_for_view(&cfg, view),
                    &crate::analysis::AnalysisOptions::summary_only(),
                );
                let label = format!("the worst view, {}, at the recommended setting", view.name);
                h.push_str(&html::png_figures(&crate::figures::screen::captioned(&wa, &label)));
            }
        }
    }
    if !figures.is_empty() {
        h.push_str("<h2>Plots</h2>\n");
        for (i, (stem, caption, svg)) in figures.iter().enumerate() {
            h.push_str(&html::figure_bounded(
                stem,
                svg,
                caption,
                inline.get(i).and_then(Option::as_ref),
            ));
        }
    }
    let (front, front_left) = front_shown(r);
    if !front.is_empty() {
        let _ = writeln!(
            h,
            "<h2>Pareto front</h2>\n<p>Memory against {}: no other configuration has both less memory and a lower value.</p>",
            html::escape(r.objective.name())
        );
        html_config_table(&mut h, r, &front);
    }
    h.push_str("<h2>Top configurations</h2>\n");
    html_config_table(&mut h, r, &top_shown(r));
    let _ = writeln!(
        h,
        "<p>{}</p>",
        html::escape(&rest_sentence(r, front_left)).replace("sweep.csv", "<a href=\"sweep.csv\">sweep.csv</a>")
    );
    h.push_str("<h2>Reproduce</h2>\n");
    let _ = writeln!(h, "<pre>{}</pre>", html::escape(&r.command));
    let name = &r.config.name;
    Ok(html::page(
        &format!("csm-lab sweep: {name}"),
        &format!("Cascaded shadow map sweep: {name}"),
        &h,
        "Every row of <code>sweep.csv</code> equals what <code>csm-lab analyze</code> reports for that setting.",
    ))
}

/// The HTML table of the sweep rows `shown` (the recommendation highlighted when among them)
/// and its definitions.
fn html_config_table(h: &mut String, r: &SweepResult, shown: &[usize]) {
    let rec = r.recommendation.as_ref().map(|x| x.index);
    let (head, rows, left, d) = config_table(r, shown);
    h.push_str(&html::table(
        &head,
        &rows,
        &left,
        shown.iter().position(|&i| Some(i) == rec),
    ));
    h.push_str(&html::definitions(&d));
}

/// A Markdown section `## heading` listing `lines` as bullets; nothing when there are none.
fn md_list(m: &mut String, heading: &str, lines: &[String]) {
    if !lines.is_empty() {
        let _ = writeln!(m, "## {heading}\n");
        for l in lines {
            let _ = writeln!(m, "- {l}");
        }
        m.push('\n');
    }
}

/// `report.md`: the same content for pasting into a review document. A level's contact sheet
/// (`views.png`) and plan (`plan.png`, `plan`) are linked in its "Views" section when drawn.
pub(crate) fn report_md(r: &SweepResult, figures: &[(&str, String, Vec<u8>)], sheet: bool, plan: bool) -> Vec<u8> {
    let mut m = String::new();
    let _ = writeln!(m, "# Cascaded shadow map sweep: {}\n", r.config.name);
    let _ = writeln!(
        m,
        "## Verdict\n\n{}\n\n*Objective:* {}.\n",
        why_text(r),
        r.objective_text
    );
    if let Some(c) = &r.light_update {
        let _ = writeln!(m, "{}\n", c.sentence);
    }
    let edges = edge_lines(r);
    md_list(&mut m, "Edges of the range", &edges);
    let alts = alternative_lines(r);
    md_list(&mut m, "Alternatives", &alts);
    let rivals = rival_lines(r);
    md_list(&mut m, "Why the main rivals lost", &rivals);
    m.push_str(&super::optimize::md_section(r));
    m.push_str(&super::flicker_sample::md_section(r));
    let sun = sun_lines(r);
    md_list(&mut m, "Sun angles", &sun);
    let views = super::views::sweep_lines(r);
    md_list(&mut m, "Views", &views);
    if !views.is_empty() {
        m.push_str("Each view's own screen metrics at the level's choice: [views.csv](views.csv).\n\n");
        if sheet {
            m.push_str("![Every view's per-pixel aliasing at the level's choice, one colour scale; the worst view framed in red](views.png)\n\n");
        }
        if plan {
            let _ = writeln!(
                m,
                "![{}](plan.png)\n",
                crate::figures::plan::caption(&r.config, Some(r.objective.name()))
            );
        }
    }
    let _ = writeln!(m, "## Sweep\n\n{}.\n", grid_sentence(r));
    m.push_str("## Scene\n\n| | |\n|---|---|\n");
    for (k, v) in scene_facts(&r.config, &r.rows) {
        let _ = writeln!(m, "| {k} | {v} |");
    }
    m.push('\n');
    if !figures.is_empty() {
        m.push_str("## Plots\n\n");
        for (stem, caption, _) in figures {
            let _ = writeln!(m, "![{caption}]({stem}.svg)\n\n*{caption}* ([PNG]({stem}.png))\n");
        }
    }
    let (front, front_left) = front_shown(r);
    let mut d = Vec::new();
    if !front.is_empty() {
        let _ = writeln!(
            m,
            "## Pareto front\n\nMemory against {}: no other configuration has both less memory and a lower value.\n",
            r.objective.name()
        );
        let (head, rows, left, defs) = config_table(r, &front);
        m.push_str(&markdown::table(&head, &rows, &left));
        m.push('\n');
        d = defs;
    }
    m.push_str("## Top configurations\n\n");
    let (head, rows, left, defs) = config_table(r, &top_shown(r));
    m.push_str(&markdown::table(&head, &rows, &left));
    if d.is_empty() {
        d = defs;
    }
    let _ = writeln!(
        m,
        "\n{}\n\n{}",
        defs::markdown(&d),
        rest_sentence(r, front_left).replace("sweep.csv", "[sweep.csv](sweep.csv)")
    );
    let _ = writeln!(m, "\n## Reproduce\n\n```sh\n{}\n```", r.command);
    m.into_bytes()
}

/// Every file of a sweep but `sweep.csv`, rendered in memory: (file name, bytes). The
/// commands stream `sweep.csv` into the same set ([`SweepCsvFile`]).
pub(crate) fn render_all_but_csv(r: &SweepResult, plots: bool) -> Result<crate::output::RenderedFiles> {
    let mut files = vec![(
        "recommendation.json".to_string(),
        json_bytes("recommendation", &recommendation_value(r))?,
    )];
    let figures = if plots { render_figures(r)? } else { Vec::new() };
    // The plan of the level's views, with scene geometry and plots, each view coloured by its
    // objective at the level's choice and the worst ringed; drawn at its own size, the size
    // the page shows it, so the report inlines the file itself.
    // A view that sees no receiver has no objective: not a number, drawn neutral.
    let per_view: Option<Vec<f64>> = r.level.as_ref().map(|c| {
        c.views
            .iter()
            .map(|v| if v.seen { v.objective_at_level } else { f64::NAN })
            .collect()
    });
    let values = per_view.as_deref().map(|v| (r.objective.name(), v));
    let worst = r.level.as_ref().map(|c| c.worst);
    // Rasterising is most of the figures' time: each SVG is parsed and rasterised once, at
    // the size the page shows it (`figures::png_scale`), and that PNG file is also the page's
    // copy when the SVG is too large to inline; the figures and the plan go in parallel
    // (rayon keeps their order, so the files are the same at any thread count).
    let (pngs, plan) = rayon::join(
        || {
            use rayon::prelude::*;
            figures
                .par_iter()
                .map(|(_, _, svg)| {
                    let tree = crate::figures::ParsedSvg::parse(svg)?;
                    let pixmap = tree.pixmap(crate::figures::png_scale(tree.size()))?;
                    let file = crate::figures::encode_figure_pixmap(&pixmap)?;
                    let inline = html::inline_png(svg, &file, pixmap.width());
                    Ok((file, inline))
                })
                .collect::<Result<Vec<_>>>()
        },
        || {
            if plots {
                crate::figures::plan::plan_png(&r.config, values, worst, 1.0)
            } else {
                Ok(None)
            }
        },
    );
    let (pngs, plan) = (pngs?, plan?);
    let mut inline = Vec::with_capacity(pngs.len());
    for ((stem, _, svg), (png, page_png)) in figures.iter().zip(pngs) {
        files.push((format!("{stem}.svg"), svg.clone()));
        files.push((format!("{stem}.png"), png));
        inline.push(page_png);
    }
    if let Some(o) = &r.optimized {
        files.push((super::optimize::FILE.to_string(), super::optimize::csv(r, o)?));
    }
    if let Some(s) = &r.flicker {
        files.push((
            super::flicker_sample::FILE.to_string(),
            super::flicker_sample::csv(r, s)?,
        ));
    }
    let mut sheet = None;
    if let Some(c) = &r.level {
        let at = &r.rows[c.at].summary;
        files.push((
            super::views::FILE.to_string(),
            super::views::csv(&r.config, at, r.objective, Some((r, c)))?,
        ));
        if plots {
            sheet = super::views::sweep_sheet(r)?;
        }
    }
    if let Some(png) = &sheet {
        files.push((super::views::SHEET.to_string(), png.clone()));
    }
    // The plan's file is drawn at the size the page shows it, so the page inlines the same
    // bytes.
    if let Some(png) = &plan {
        files.push((crate::figures::plan::FILE.to_string(), png.clone()));
    }
    files.push((
        "report.html".to_string(),
        report_html(r, &figures, &inline, sheet.as_deref(), plan.as_deref())?,
    ));
    let level_plan = r.level.is_some() && plan.is_some();
    files.push((
        "report.md".to_string(),
        report_md(r, &figures, sheet.is_some(), level_plan),
    ));
    if let Some(s) = &r.engine_setting {
        files.push(super::terms::file(s));
    }
    Ok(files)
}

/// " × 2 split ranges" when the sweep puts bounds and visible splits side by side.
fn ranges_factor(r: &SweepResult) -> String {
    let mut out = match r.grid.split_range.values.len() {
        1 => String::new(),
        n => format!(" × {n} split ranges"),
    };
    if let (Some(a), Some(k)) = (&r.grid.knob, crate::presets::axes(&r.config).knob) {
        let _ = write!(out, " × {}", count(a.values.len() as u64, &format!("{} value", k.term)));
    }
    if let Some(a) = &r.grid.distance {
        let _ = write!(out, " × {}", count(a.values.len() as u64, "shadow distance"));
    }
    if let Some(sun) = &r.grid.sun {
        let _ = write!(
            out,
            ", each under {} ({} × {})",
            count(sun.len() as u64, "sun angle"),
            count(sun.azimuths().len() as u64, "azimuth"),
            count(sun.elevations().len() as u64, "elevation")
        );
    }
    out
}

/// The swept engine knob's and distance's column names and cells of a row (tables).
fn axis_cells(r: &SweepResult, x: &Row) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    if let (Some(k), Some(v)) = (crate::presets::axes(&r.config).knob, x.setting.knob) {
        out.push((k.term, n(v)));
    }
    if let Some(d) = x.setting.distance {
        out.push(("shadow distance", n(d)));
    }
    out
}

/// The short table printed on stdout.
/// What `sweep --shard K/N` prints: which configurations of the grid it ran (1-based, in
/// `sweep.csv` order), and that it decides nothing.
pub(crate) fn slice_text(name: &str, shard: crate::commands::sweep::shard::Shard, total: usize) -> String {
    let rows: Vec<usize> = shard.indices(total).map(|i| i + 1).collect();
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    let which = if shard.n == 1 {
        format!("configurations {first}–{last} of {total}")
    } else if rows.len() <= 3 {
        let list: Vec<String> = rows.iter().map(ToString::to_string).collect();
        format!("configurations {} of {total}", list.join(", "))
    } else {
        format!(
            "configurations {first}, {}, {}, …, {last} of {total} ({} rows: every {} in grid order)",
            rows[1],
            rows[2],
            rows.len(),
            ordinal(shard.n)
        )
    };
    format!(
        "{name}: shard {} of {}: {which}\n\
         no Pareto front, recommendation or report: a shard holds part of the grid; \
         `csm-lab merge` of all {} shard directories decides\n",
        shard.k, shard.n, shard.n
    )
}

/// "2nd", "3rd", "11th", "21st".
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

pub(crate) fn stdout_table(r: &SweepResult) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {} ({})",
        r.config.name,
        count(r.rows.len() as u64, "configuration"),
        grid_factors(r)
    );
    if r.front.is_empty() {
        let _ = writeln!(
            out,
            "no cascades needed: the scene is not visible within the shadow distance"
        );
        return out;
    }
    let screen = r.objective.name() != "mean_aliasing";
    if screen {
        let _ = writeln!(out, "Pareto front (memory against {}):", r.objective.name());
    } else {
        let _ = writeln!(out, "Pareto front (memory against mean aliasing):");
    }
    // The fit column is as wide as its widest cell ("sphere", "sphere (visible)").
    let fw = r
        .front
        .iter()
        .map(|&i| fit_cell(&r.rows[i]).chars().count())
        .fold(6, usize::max);
    let _ = write!(
        out,
        "  {:>9} {:>8} {:>6} {:>6} {:>fw$} {:>10} {:>10} {:>10}",
        "MiB",
        "cascades",
        "res",
        "λ",
        "fit",
        "mean",
        worst_words(r.worst).1,
        "shimmer"
    );
    if screen {
        let _ = write!(out, " {:>10}", "objective");
    }
    if let Some(&i) = r.front.first() {
        for (h, _) in axis_cells(r, &r.rows[i]) {
            let _ = write!(out, " {h:>10}");
        }
    }
    let _ = writeln!(out);
    let rec = r.recommendation.as_ref().map(|x| x.index);
    for &i in &r.front {
        let x = &r.rows[i];
        let s = &x.summary;
        let _ = writeln!(
            out,
            "{} {:>9} {:>8} {:>6} {:>6} {:>fw$} {:>10} {:>10} {:>10}",
            if Some(i) == rec { "*" } else { " " },
            n(mib(s.memory_bytes)),
            x.setting.cascades,
            x.setting.resolution,
            // A preset's table shows only the knobs it has.
            if has_lambda(r) {
                n(x.setting.lambda)
            } else {
                "-".to_string()
            },
            if r.config.shadow.preset.is_none() {
                fit_cell(x)
            } else {
                "-".to_string()
            },
            n(s.mean_aliasing),
            n(r.worst.value(s)),
            n(s.shimmer_snapped)
        );
        if screen {
            out.pop();
            let _ = writeln!(out, " {:>10}", n(r.objective.value(s)));
        }
        let cells = axis_cells(r, x);
        if !cells.is_empty() {
            out.pop();
            for (_, c) in cells {
                let _ = write!(out, " {c:>10}");
            }
            out.push('\n');
        }
    }
    let _ = writeln!(out, "recommended (budget {} MiB): {}", n(r.budget_mib), why_text(r));
    for l in edge_lines(r) {
        let _ = writeln!(out, "range edge: {l}");
    }
    for l in alternative_lines(r) {
        let _ = writeln!(out, "  {l}");
    }
    if let Some(v) = super::optimize::verdict(r) {
        let _ = writeln!(out, "  {v}");
    }
    out.push_str(&super::optimize::stdout(r));
    for l in sun_lines(r) {
        let _ = writeln!(out, "note: {l}");
    }
    if let Some(c) = &r.light_update {
        let _ = writeln!(out, "{}", c.sentence);
    }
    let views = super::views::sweep_lines(r);
    if let Some((first, rest)) = views.split_first() {
        let _ = writeln!(out, "views: {first}");
        for l in rest {
            let _ = writeln!(out, "  {l}");
        }
    }
    out
}

/// What a sun sweep adds to the verdict: the recommended setting's worst sun angle, the
/// worst-case rule, and (bounds only) which metrics cannot depend on the light. Empty without
/// sun axes.
pub(crate) fn sun_lines(r: &SweepResult) -> Vec<String> {
    let (Some(sun), Some(grid)) = (&r.sun, &r.grid.sun) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    if let Some(rec) = &r.recommendation {
        let rows = sun.rows_of(rec.index);
        let worst = &sun.all[sun.worst[rec.index]];
        let best = rows
            .iter()
            .copied()
            .min_by(|&a, &b| {
                r.objective
                    .value(&sun.all[a].summary)
                    .total_cmp(&r.objective.value(&sun.all[b].summary))
                    .then(a.cmp(&b))
            })
            .map(|i| &sun.all[i]);
        if let (Some(w), Some(b)) = (worst.setting.sun, best) {
            let bs = b.setting.sun.map(|s| s.label()).unwrap_or_default();
            out.push(format!(
                "the recommended setting is judged at its worst of {}: sun {} ({} {}; at its best angle, {}, {})",
                count(grid.len() as u64, "sun angle"),
                w.label(),
                r.objective.name(),
                n(r.objective.value(&worst.summary)),
                bs,
                n(r.objective.value(&b.summary))
            ));
        }
    }
    out.push(SUN_RULE.to_string());
    out.extend(r.sun_note.clone());
    out
}

/// A row's λ and fit in the words of the sweep: a preset's own knobs only (a preset without a
/// practical λ or a choice of fit shows neither).
fn setting_knobs(r: &SweepResult, x: &Row) -> String {
    match &r.config.shadow.preset {
        None => format!(
            "λ = {}, {} fit{}{}",
            x.setting.lambda,
            x.setting.fit,
            range_words(r, x.setting.split_range),
            knob_words(r, x)
        ),
        Some(p) if has_lambda(r) => format!(
            "the {} preset with λ = {}{}",
            p.name,
            x.setting.lambda,
            knob_words(r, x)
        ),
        Some(p) => format!("the {} preset{}", p.name, knob_words(r, x)),
    }
}

/// ", CascadeDistributionExponent 2.5" / ", shadow distance 100" for the swept engine knob and
/// distance, in the engine's terms; empty when neither is swept.
fn knob_words(r: &SweepResult, x: &Row) -> String {
    let mut out = String::new();
    if let (Some(k), Some(v)) = (crate::presets::axes(&r.config).knob, x.setting.knob) {
        let _ = write!(out, ", {} {}", k.term, v);
    }
    if let Some(d) = x.setting.distance {
        let _ = write!(out, ", shadow distance {d}");
    }
    out
}

/// A table's fit cell: the fit, and "visible" when the splits divide the visible depths.
fn fit_cell(x: &Row) -> String {
    if x.setting.split_range.is_visible() {
        format!("{} (visible)", x.setting.fit)
    } else {
        x.setting.fit.to_string()
    }
}

/// ", splits on the visible depths" (or "... on the bounds' depth range") when the sweep puts
/// both side by side or the config fits the splits to what is visible; empty otherwise.
fn range_words(r: &SweepResult, range: crate::config::SplitRange) -> &'static str {
    let shown = r.grid.split_range.values.len() > 1 || range.is_visible();
    match (shown, range.is_visible()) {
        (false, _) => "",
        (true, true) => ", splits on the visible depths",
        (true, false) => ", splits on the bounds' depth range",
    }
}

/// Whether the sweep's settings have a practical λ: csm-lab's own pipeline, or a preset whose
/// split rule has one.
fn has_lambda(r: &SweepResult) -> bool {
    r.config
        .shadow
        .preset
        .as_ref()
        .is_none_or(|p| crate::presets::lambda_value(&p.knobs).is_some())
}

/// What to change from the configured setting `o` to reach `x`, in the knobs the settings have
/// ("cascades 4 → 3, resolution 2048 → 1024"); empty when nothing differs.
fn changes(r: &SweepResult, o: &Row, x: &Row) -> Vec<String> {
    let mut out = Vec::new();
    if o.setting.cascades != x.setting.cascades {
        out.push(format!("cascades {} → {}", o.setting.cascades, x.setting.cascades));
    }
    if o.setting.resolution != x.setting.resolution {
        out.push(format!(
            "resolution {} → {}",
            o.setting.resolution, x.setting.resolution
        ));
    }
    if has_lambda(r) && o.setting.lambda != x.setting.lambda {
        out.push(format!("λ {} → {}", o.setting.lambda, x.setting.lambda));
    }
    if r.config.shadow.preset.is_none() && o.setting.fit != x.setting.fit {
        out.push(format!("fit {} → {}", o.setting.fit, x.setting.fit));
    }
    if let (Some(k), Some(a), Some(b)) = (crate::presets::axes(&r.config).knob, o.setting.knob, x.setting.knob) {
        if a != b {
            out.push(format!("{} {a} → {b}", k.term));
        }
    }
    if let (Some(a), Some(b)) = (o.setting.distance, x.setting.distance) {
        if a != b {
            out.push(format!("shadow distance {a} → {b}"));
        }
    }
    if o.setting.split_range != x.setting.split_range {
        out.push(format!(
            "fit_depth_to_visible {} → {}",
            o.setting.split_range.is_visible(),
            x.setting.split_range.is_visible()
        ));
    }
    out
}

#[cfg(test)]
mod slice_tests {
    use super::*;
    use crate::commands::sweep::shard::Shard;

    #[test]
    fn a_shard_names_its_rows_one_based_and_decides_nothing() {
        // Brute force: the 1-based rows r of 1..=672 with (r - 1) mod 3 == 1.
        let rows: Vec<usize> = (1..=672).filter(|r| (r - 1) % 3 == 1).collect();
        assert_eq!((rows.len(), rows[0], rows[rows.len() - 1]), (224, 2, 671));
        let t = slice_text("default", Shard { k: 2, n: 3 }, 672);
        assert_eq!(
            t.lines().next().unwrap(),
            "default: shard 2 of 3: configurations 2, 5, 8, …, 671 of 672 (224 rows: every 3rd in grid order)"
        );
        assert!(t.contains("`csm-lab merge` of all 3 shard directories decides"));
        assert!(slice_text("d", Shard { k: 1, n: 1 }, 5).starts_with("d: shard 1 of 1: configurations 1–5 of 5\n"));
        assert!(slice_text("d", Shard { k: 3, n: 4 }, 10).starts_with("d: shard 3 of 4: configurations 3, 7 of 10\n"));
        let names: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 101, 111].map(ordinal).to_vec();
        assert_eq!(
            names,
            ["1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "101st", "111th"]
        );
    }
}
