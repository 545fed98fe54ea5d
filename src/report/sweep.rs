//! What `sweep` writes: `sweep.csv`, `recommendation.json`, four figures (SVG and PNG) and a
//! design-review report as one self-contained `report.html` (inline SVG and CSS) and as
//! `report.md`.

use std::fmt::Write as _;

use super::{html, markdown};
use crate::analysis::mib;
use crate::config::Config;
use crate::error::Result;
use crate::figures::sweep::{HeatmapFigure, LambdaDensityFigure, ParetoFigure, ShimmerSweepFigure};
use crate::figures::{svg_to_png, Figure};
use crate::metric;
use crate::output::{csv_bytes_from, json_bytes, num};
use crate::sweep::{self, Row, SweepResult};

/// `sweep.csv`: [`metric::summary_columns`], then these.
pub const SWEEP_EXTRA_COLUMNS: [&str; 4] = ["cascades_needed", "pareto", "recommended", "preset"];

pub fn sweep_csv(r: &SweepResult) -> Result<Vec<u8>> {
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
    let rows = r.rows.iter().enumerate().map(|(i, row)| {
        let st = &row.setting;
        let mut fields = metric::summary_fields(
            num("lambda", st.lambda)?,
            st.cascades,
            st.resolution,
            st.fit.name(),
            st.split_range,
            &row.summary,
        )?;
        fields.extend([
            row.summary.cascades_needed.to_string(),
            on_front[i].to_string(),
            (rec == Some(i)).to_string(),
            preset.clone(),
        ]);
        Ok(fields)
    });
    let header: Vec<&str> = metric::summary_columns(r.config.geometry.is_some())
        .into_iter()
        .chain(SWEEP_EXTRA_COLUMNS)
        .collect();
    csv_bytes_from(&header, rows)
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
    for (k, x) in metric::summary_json(&row.summary) {
        v[k] = x;
    }
    v
}

pub fn recommendation_value(r: &SweepResult) -> serde_json::Value {
    let mut v = serde_json::json!({
        "tool": format!("csm-lab {}", env!("CARGO_PKG_VERSION")),
        "name": r.config.name,
        "command": r.command,
        "configurations": r.rows.len(),
        "objective": sweep::objective_text(r.objective),
        "memory_budget_mib": r.budget_mib,
        "pareto_front": r.front.iter().map(|&i| row_json(&r.rows[i])).collect::<Vec<_>>(),
    });
    match (r.recommendation.as_ref(), r.recommended()) {
        (Some(rec), Some(row)) => {
            v["within_budget"] = rec.within_budget.into();
            v["recommended"] = row_json(row);
        }
        _ => {
            // No null (every number must be finite): the reasons and the closest row instead.
            let n = sweep::no_recommendation(&r.rows, r.budget_mib, r.objective);
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
            format!("{:.4} to {:.4}", r.summary.z_lo, r.summary.z_hi),
        ));
    }
    v
}

fn why_text(r: &SweepResult) -> String {
    let Some(rec) = r.recommended() else {
        let n = sweep::no_recommendation(&r.rows, r.budget_mib, r.objective);
        let Some(c) = n.closest else {
            return "The scene is not visible within the shadow distance: no cascades are needed.".to_string();
        };
        let x = &r.rows[c];
        let total = r.rows.len();
        return format!(
            "Nothing qualifies: of {total} configuration{}, {} miss slice corners (coverage_violations > 0) and {} shimmer when snapped (shimmer_snapped > {} texel){}. Closest: {} cascade{} of {}² texels, {}: {} coverage violation{}, snapped shimmer {}, mean aliasing {}, {} MiB.",
            crate::report::check::plural(total),
            n.coverage_misses,
            n.unstable,
            sweep::STABLE_SHIMMER,
            if n.no_cascades > 0 {
                format!(", {} need no cascades", n.no_cascades)
            } else {
                String::new()
            },
            x.setting.cascades,
            crate::report::check::plural(x.setting.cascades),
            x.setting.resolution,
            setting_knobs(r, x),
            x.summary.coverage_violations,
            crate::report::check::plural(x.summary.coverage_violations as usize),
            crate::output::short_number(x.summary.shimmer_snapped),
            crate::output::short_number(x.summary.mean_aliasing),
            crate::output::short_number(mib(x.summary.memory_bytes)),
        );
    };
    let s = &rec.summary;
    let acceptable_within = r
        .rows
        .iter()
        .filter(|x| {
            x.summary.cascades_needed
                && x.summary.coverage_violations == 0
                && x.summary.shimmer_snapped <= sweep::STABLE_SHIMMER
                && x.summary.memory_bytes as f64 <= r.budget_mib * 1048576.0
        })
        .count();
    let screen = r.objective.name() != "mean_aliasing";
    let mut t = if let Some(st) = s.screen.as_ref().filter(|_| screen) {
        format!(
            "{} cascade{} of {}² texels, {}: {} {:.3} on screen (per-pixel aliasing: median {:.3}, \
             worst {:.3}; {:.0}% of the receiver pixels under-sampled), {} MiB. ",
            rec.setting.cascades,
            crate::report::check::plural(rec.setting.cascades),
            rec.setting.resolution,
            setting_knobs(r, rec),
            r.objective.name(),
            r.objective.value(s),
            st.aliasing_p50,
            st.aliasing_max,
            100.0 * st.undersampled_fraction,
            mib(s.memory_bytes)
        )
    } else {
        format!(
            "{} cascade{} of {}² texels, {}: mean aliasing {:.3}, worst {:.3} at a cascade's near edge, \
             {:.0}% of the depth range under-sampled, {} MiB. ",
            rec.setting.cascades,
            crate::report::check::plural(rec.setting.cascades),
            rec.setting.resolution,
            setting_knobs(r, rec),
            s.mean_aliasing,
            s.max_aliasing,
            100.0 * s.undersampled_fraction,
            mib(s.memory_bytes)
        )
    };
    if r.recommendation.as_ref().is_some_and(|x| x.within_budget) {
        let _ = write!(
            t,
            "Of {} configurations, {} fit the {} MiB budget, cover every slice and are stable when snapped; \
             this one has the lowest {} among them (within 1%, the lowest worst case).",
            r.rows.len(),
            acceptable_within,
            r.budget_mib,
            if screen { r.objective.name() } else { "mean aliasing" }
        );
    } else {
        let _ = write!(
            t,
            "Nothing fits the {} MiB budget; this is the cheapest configuration that covers every slice and is stable.",
            r.budget_mib
        );
    }
    let own = r.rows.iter().find(|x| {
        x.setting.lambda == r.config.shadow.lambda
            && x.setting.cascades == r.config.shadow.cascades
            && x.setting.resolution == r.config.shadow.resolution
            && x.setting.fit == r.config.shadow.fit
            && x.setting.split_range.is_visible() == r.config.shadow.fit_depth_to_visible
    });
    if let Some(o) = own {
        let change = changes(r, o, rec);
        if !change.is_empty() && screen {
            let _ = write!(
                t,
                " To get it, change {} (the configured setting has {} {:.3}, {} MiB).",
                change.join(", "),
                r.objective.name(),
                r.objective.value(&o.summary),
                mib(o.summary.memory_bytes)
            );
        } else if !change.is_empty() {
            let _ = write!(
                t,
                " To get it, change {} (the configured setting has mean aliasing {:.3}, worst {:.3}, {} MiB).",
                change.join(", "),
                o.summary.mean_aliasing,
                o.summary.max_aliasing,
                mib(o.summary.memory_bytes)
            );
        } else {
            t.push_str(" It is the configured setting: keep it.");
        }
    }
    t
}

const TOP: usize = 15;

/// The figures of a sweep as (file stem, title, SVG bytes), rendered once.
pub fn render_figures(r: &SweepResult) -> Result<Vec<(&'static str, &'static str, Vec<u8>)>> {
    // The four figures are independent: drawn concurrently (the first error in this order wins).
    let ((heatmap, density), (shimmer, pareto)) = rayon::join(
        || rayon::join(|| HeatmapFigure(r).to_svg(), || LambdaDensityFigure::new(r).to_svg()),
        || rayon::join(|| ShimmerSweepFigure(r).to_svg(), || ParetoFigure(r).to_svg()),
    );
    Ok(vec![
        (
            "heatmap",
            "Max and mean aliasing over λ × cascade count, per resolution",
            heatmap?,
        ),
        (
            "density_lambda",
            "Texels per pixel against depth for several λ at the recommended count and resolution",
            density?,
        ),
        (
            "shimmer_sweep",
            "Shimmer snapped vs unsnapped for every configuration",
            shimmer?,
        ),
        ("pareto", "Pareto front of memory against mean aliasing", pareto?),
    ])
}

fn table_rows(r: &SweepResult) -> Vec<Vec<String>> {
    r.ranked()
        .into_iter()
        .take(TOP)
        .map(|i| {
            let x = &r.rows[i];
            let s = &x.summary;
            vec![
                x.setting.cascades.to_string(),
                x.setting.resolution.to_string(),
                x.setting.lambda.to_string(),
                fit_cell(x),
                format!("{:.4}", s.mean_aliasing),
                format!("{:.4}", s.max_aliasing),
                format!("{:.4}", s.mean_log_aliasing),
                crate::output::short_number(s.shimmer_snapped),
                s.coverage_violations.to_string(),
                format!("{}", mib(s.memory_bytes)),
            ]
        })
        .collect()
}

const TABLE_HEAD: [&str; 10] = [
    "cascades",
    "resolution",
    "λ",
    "fit",
    "mean aliasing",
    "max aliasing",
    "mean log aliasing",
    "shimmer snapped",
    "coverage misses",
    "MiB",
];

/// "N configurations: a λ values × b cascade counts × …, each analysed in full".
fn grid_sentence(r: &SweepResult) -> String {
    format!(
        "{} configurations: {} λ values × {} cascade counts × {} resolutions × {} fits{}, each analysed in full",
        r.rows.len(),
        r.grid.lambda.values.len(),
        r.grid.cascades.values.len(),
        r.grid.resolution.values.len(),
        r.grid.fit.values.len(),
        ranges_factor(r)
    )
}

/// `report.html`: one self-contained, well-formed (XHTML-compatible) document in the shared
/// report look ([`html::page`]).
pub fn report_html(r: &SweepResult, figures: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<p>{} (closed-form aliasing, shimmer with and without snapping along the motion path, coverage).</p>",
        grid_sentence(r)
    );
    h.push_str("<h2>Scene</h2>\n");
    h.push_str(&html::facts(&scene_facts(&r.config, &r.rows)));
    h.push_str("<h2>Recommendation</h2>\n");
    let _ = writeln!(h, "<div class=\"rec-box\"><p>{}</p>", html::escape(&why_text(r)));
    let _ = writeln!(
        h,
        "<p><em>Objective:</em> {}.</p></div>",
        html::escape(&sweep::objective_text(r.objective))
    );
    // The camera view of the recommended configuration, with scene geometry.
    if let (Some(rec), Some(_)) = (r.recommended(), &r.config.geometry) {
        if let Ok(cfg) = rec.setting.apply(&r.config) {
            let a = crate::analysis::analyze(&cfg, &crate::analysis::AnalysisOptions::summary_only());
            let images = crate::figures::screen::captioned(&a, &format!("recommended ({})", rec.setting.label()));
            h.push_str(&html::png_figures(&images));
        }
    }
    if !figures.is_empty() {
        h.push_str("<h2>Plots</h2>\n");
        for (_, caption, svg) in figures {
            h.push_str(&html::figure(svg, caption));
        }
    }
    h.push_str("<h2>Top configurations</h2>\n");
    let rec = r.recommended().map(|x| x.setting);
    let highlight = r
        .ranked()
        .into_iter()
        .take(TOP)
        .position(|i| Some(r.rows[i].setting) == rec);
    h.push_str(&html::table(&TABLE_HEAD, &table_rows(r), &[3], highlight));
    h.push_str("<h2>Reproduce</h2>\n");
    let _ = writeln!(h, "<pre>{}</pre>", html::escape(&r.command));
    let name = &r.config.name;
    html::page(
        &format!("csm-lab sweep: {name}"),
        &format!("Cascaded shadow map sweep: {name}"),
        &h,
        "Every row of <code>sweep.csv</code> equals what <code>csm-lab analyze</code> reports for that setting.",
    )
}

/// `report.md`: the same content for pasting into a review document.
pub fn report_md(r: &SweepResult, figures: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    let mut m = String::new();
    let _ = writeln!(m, "# Cascaded shadow map sweep: {}\n", r.config.name);
    let _ = writeln!(m, "{}.\n", grid_sentence(r));
    m.push_str("## Scene\n\n| | |\n|---|---|\n");
    for (k, v) in scene_facts(&r.config, &r.rows) {
        let _ = writeln!(m, "| {k} | {v} |");
    }
    let _ = writeln!(
        m,
        "\n## Recommendation\n\n{}\n\n*Objective:* {}.\n",
        why_text(r),
        sweep::objective_text(r.objective)
    );
    if !figures.is_empty() {
        m.push_str("## Plots\n\n");
        for (stem, caption, _) in figures {
            let _ = writeln!(m, "![{caption}]({stem}.svg)\n\n*{caption}* ([PNG]({stem}.png))\n");
        }
    }
    m.push_str("## Top configurations\n\n");
    m.push_str(&markdown::table(&TABLE_HEAD, &table_rows(r), &[]));
    let _ = writeln!(m, "\n## Reproduce\n\n```sh\n{}\n```", r.command);
    m.into_bytes()
}

/// Every file of a sweep, rendered in memory: (file name, bytes).
pub fn render_all(r: &SweepResult, plots: bool) -> Result<crate::output::RenderedFiles> {
    let mut files = vec![
        ("sweep.csv".to_string(), sweep_csv(r)?),
        (
            "recommendation.json".to_string(),
            json_bytes("recommendation", &recommendation_value(r))?,
        ),
    ];
    let figures = if plots { render_figures(r)? } else { Vec::new() };
    // Rasterising is most of the time of a small sweep: the figures go to PNG in parallel
    // (rayon keeps their order, so the files are the same at any thread count).
    let pngs = {
        use rayon::prelude::*;
        figures
            .par_iter()
            .map(|(_, _, svg)| svg_to_png(svg, 2.0))
            .collect::<Result<Vec<_>>>()?
    };
    for ((stem, _, svg), png) in figures.iter().zip(pngs) {
        files.push((format!("{stem}.svg"), svg.clone()));
        files.push((format!("{stem}.png"), png));
    }
    files.push(("report.html".to_string(), report_html(r, &figures)));
    files.push(("report.md".to_string(), report_md(r, &figures)));
    Ok(files)
}

/// " × 2 split ranges" when the sweep puts bounds and visible splits side by side.
fn ranges_factor(r: &SweepResult) -> String {
    match r.grid.split_range.values.len() {
        1 => String::new(),
        n => format!(" × {n} split ranges"),
    }
}

/// The short table printed on stdout.
pub fn stdout_table(r: &SweepResult) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {} configurations ({} λ × {} cascade counts × {} resolutions × {} fits{})",
        r.config.name,
        r.rows.len(),
        r.grid.lambda.values.len(),
        r.grid.cascades.values.len(),
        r.grid.resolution.values.len(),
        r.grid.fit.values.len(),
        ranges_factor(r)
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
        "MiB", "cascades", "res", "λ", "fit", "mean", "max", "shimmer"
    );
    let _ = if screen {
        writeln!(out, " {:>10}", "objective")
    } else {
        writeln!(out)
    };
    let rec = r.recommendation.as_ref().map(|x| x.index);
    for &i in &r.front {
        let x = &r.rows[i];
        let s = &x.summary;
        let _ = writeln!(
            out,
            "{} {:>9} {:>8} {:>6} {:>6} {:>fw$} {:>10.4} {:>10.4} {:>10}",
            if Some(i) == rec { "*" } else { " " },
            mib(s.memory_bytes),
            x.setting.cascades,
            x.setting.resolution,
            // A preset's table shows only the knobs it has.
            if has_lambda(r) {
                x.setting.lambda.to_string()
            } else {
                "-".to_string()
            },
            if r.config.shadow.preset.is_none() {
                fit_cell(x)
            } else {
                "-".to_string()
            },
            s.mean_aliasing,
            s.max_aliasing,
            crate::output::short_number(s.shimmer_snapped)
        );
        if screen {
            out.pop();
            let _ = writeln!(out, " {:>10.4}", r.objective.value(s));
        }
    }
    let _ = writeln!(out, "recommended (budget {} MiB): {}", r.budget_mib, why_text(r));
    out
}

/// A row's λ and fit in the words of the sweep: a preset's own knobs only (a preset without a
/// practical λ or a choice of fit shows neither).
fn setting_knobs(r: &SweepResult, x: &Row) -> String {
    match &r.config.shadow.preset {
        None => format!(
            "λ = {}, {} fit{}",
            x.setting.lambda,
            x.setting.fit,
            range_words(r, x.setting.split_range)
        ),
        Some(p) if has_lambda(r) => format!("the {} preset with λ = {}", p.name, x.setting.lambda),
        Some(p) => format!("the {} preset", p.name),
    }
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
    if o.setting.split_range != x.setting.split_range {
        out.push(format!(
            "fit_depth_to_visible {} → {}",
            o.setting.split_range.is_visible(),
            x.setting.split_range.is_visible()
        ));
    }
    out
}
