//! What `compare` writes besides its figures: `compare.csv`, `compare.html`, `compare.md`
//! and the table printed on stdout.

use std::fmt::Write as _;

use super::{defs, html, markdown};

use crate::analysis::{mib, Analysis};
use crate::commands::compare::{coverage_extremes, fit_label, invalid_reason, label, preset_of, Comparison};
use crate::error::Result;
use crate::figures::compare::{DensityOverlay, DensityPng, DensitySvg, ShimmerCoverageBars, ShimmerPng, ShimmerSvg};
use crate::figures::Figure;
use crate::metric;
use crate::output::{count, csv_bytes, num, short_number as short, Exporter};
use crate::presets::{is_generic_note, lambda_value};

/// `compare.csv`: `preset`, the sweep columns ([`metric::summary_columns`]), then these
/// extra findings.
pub(crate) const EXTRA_COLUMNS: [&str; 5] = [
    "snaps",
    "coverage_worst_texels",
    "min_slack_texels",
    "receivers_outside_depth",
    "casters_outside_depth",
];

/// The header of `compare.csv`.
pub(crate) fn columns(cols: metric::RowColumns) -> Vec<&'static str> {
    std::iter::once("preset")
        .chain(metric::summary_columns(cols))
        .chain(EXTRA_COLUMNS)
        .collect()
}

/// The optional columns of `compare.csv`: the screen and cost columns with scene geometry,
/// `shadow_ms` when calibrated, the means over the path when some preset measured them.
pub(crate) fn row_columns(c: &Comparison) -> metric::RowColumns {
    let screen = c.analyses.iter().any(|a| a.config.geometry.is_some());
    metric::RowColumns {
        screen,
        calibrated: screen && c.analyses.iter().any(|a| a.config.cost.calibration.is_some()),
        means: c.analyses.iter().any(|a| a.summary.cost.means.is_some()),
        cache: c.analyses.iter().any(|a| a.summary.cache.is_some()),
    }
}

/// One CSV row per preset.
pub(crate) fn rows(c: &Comparison) -> Result<Vec<Vec<String>>> {
    let cols = row_columns(c);
    c.analyses
        .iter()
        .map(|a| {
            let s = &a.summary;
            let p = a.preset.as_ref();
            let (worst, slack) = coverage_extremes(a);
            let lambda = match a.config.shadow.preset.as_ref().and_then(|p| lambda_value(&p.knobs)) {
                Some(l) => num("lambda", l)?,
                None => String::new(),
            };
            let cascades = a.rig().map_or(a.config.shadow.cascades, |r| r.cascade_count());
            let mut fields = vec![preset_of(a).map_or_else(String::new, |p| p.to_string())];
            fields.extend(metric::summary_fields(
                lambda,
                cascades,
                a.config.shadow.resolution,
                &fit_label(a),
                crate::config::SplitRange::of(a.config.shadow.fit_depth_to_visible),
                s,
                cols,
            )?);
            fields.extend([
                a.config.shadow.snap.to_string(),
                num("coverage_worst_texels", worst)?,
                num("min_slack_texels", slack)?,
                num("receivers_outside_depth", p.map_or(0.0, |p| p.receivers_outside_depth))?,
                num("casters_outside_depth", p.map_or(0.0, |p| p.casters_outside_depth))?,
            ]);
            Ok(fields)
        })
        .collect()
}

pub(crate) struct CompareCsv;

impl Exporter<Comparison> for CompareCsv {
    fn file_name(&self) -> &'static str {
        "compare.csv"
    }

    fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
        csv_bytes(&columns(row_columns(c)), &rows(c)?)
    }
}

// ---------------------------------------------------------------------------------------------
// Reports
// ---------------------------------------------------------------------------------------------

/// The scene in one paragraph (shared by the HTML and Markdown reports).
fn scene_lines(c: &Comparison) -> Vec<String> {
    let cfg = &c.analyses[0].config;
    let cam = &cfg.camera;
    vec![
        format!(
            "Camera at {:?} looking at {:?}, vertical field of view {}°, near {}, far {}, screen {}×{}.",
            cam.position.to_array(),
            cam.target.to_array(),
            cam.fov_y_deg,
            cam.near,
            cam.far,
            cfg.screen.width,
            cfg.screen.height
        ),
        format!(
            "Light travelling along {:?}; scene bounds {:?} to {:?}.",
            cfg.light_direction_as_written.to_array(),
            cfg.scene.min.to_array(),
            cfg.scene.max.to_array()
        ),
        format!(
            "Shimmer measured along a {} path of {} frames (step {}).",
            cfg.motion.path.name(),
            cfg.motion.frames,
            cfg.motion.step_as_written
        ),
        if c.own.is_empty() {
            "csm-lab's own [shadow] lambda, fit, snap and fit_depth_to_scene do not apply: each preset has its own rules."
                .to_string()
        } else {
            "csm-lab's own [shadow] lambda, fit, snap and fit_depth_to_scene apply only to the csm-lab rows (--split-range): each preset has its own rules."
                .to_string()
        },
        if c.engine_defaults {
            "Every preset runs at its own defaults (--defaults).".to_string()
        } else {
            "[shadow] cascades, resolution and max_distance of the file override each preset's defaults where the preset has them."
                .to_string()
        },
    ]
}

/// Definitions of the results table's columns (the registry's texts where it has the metric).
fn table_definitions(c: &Comparison) -> Vec<(String, String)> {
    let mut d = vec![
        defs::other("preset", "the engine preset; INVALID when its windows miss slice corners or clip receivers, so its other numbers do not describe a working set-up"),
        defs::other("cascades × map", "cascade count × side of each square shadow map, in texels"),
        defs::other("fit", "how the preset encloses each slice in its window"),
        defs::other("snap", "how the preset keeps its windows on the texel grid"),
        defs::metric(max_label(c), "max_aliasing"),
        defs::metric("mean aliasing", "mean_aliasing"),
        defs::metric("shimmer snapped", "shimmer_snapped"),
        defs::metric("shimmer unsnapped", "shimmer_unsnapped"),
        {
            let (l, t) = defs::metric("coverage misses (worst, texels)", "coverage_violations");
            (l, format!("{t} In brackets: how far the worst missed corner lies outside its window, in texels."))
        },
        defs::other(
            "receivers / casters outside light depth",
            "largest depth (world units) of receivers beyond, and of casters in front of, a cascade's light depth range; receivers beyond it are clipped",
        ),
        defs::memory("memory (MiB)"),
    ];
    if has_screen(c) {
        let o = c.verdict.objective;
        d.push(defs::metric(o.name(), o.name()));
        let worst = crate::metric::worst_aliasing(true);
        d.push(defs::metric(crate::metric::worst_words(worst).0, worst.name()));
    }
    d
}

/// The label of the `max_aliasing` column: with geometry it is named the bounds metric it is
/// (the near edge of each cascade over the bounds' depth range, where nothing may be drawn),
/// beside the worst case on screen.
fn max_label(c: &Comparison) -> &'static str {
    if has_screen(c) {
        "bounds max aliasing"
    } else {
        "max aliasing"
    }
}

/// Whether the comparison has screen metrics (the scene has geometry).
fn has_screen(c: &Comparison) -> bool {
    c.analyses.iter().any(|a| a.summary.screen.is_some())
}

/// Table cells shared by both reports: (header, per-row values).
fn table(c: &Comparison) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let mut header = vec![
        "preset",
        "cascades × map",
        "fit",
        "snap",
        max_label(c),
        "mean aliasing",
        "shimmer snapped",
        "shimmer unsnapped",
        "coverage misses (worst, texels)",
        "receivers / casters outside light depth",
        "memory (MiB)",
    ];
    let screen = has_screen(c);
    let worst_on_screen = crate::metric::worst_aliasing(true);
    if screen {
        header.push(c.verdict.objective.name());
        header.push(crate::metric::worst_words(worst_on_screen).0);
    }
    let rows = c
        .analyses
        .iter()
        .map(|a| {
            let s = &a.summary;
            let p = a.preset.as_ref();
            let (worst, _) = coverage_extremes(a);
            let name = label(a);
            let mut row = vec![
                match invalid_reason(a) {
                    Some(why) => format!("{name} (INVALID: {why})"),
                    None => name,
                },
                format!(
                    "{} × {}",
                    a.rig().map_or(0, |r| r.cascade_count()),
                    a.config.shadow.resolution
                ),
                fit_label(a),
                p.map_or_else(String::new, |p| p.snap.clone()),
                short(s.max_aliasing),
                short(s.mean_aliasing),
                short(s.shimmer_snapped),
                short(s.shimmer_unsnapped),
                format!("{} ({})", s.coverage_violations, short(worst)),
                format!(
                    "{} / {}",
                    short(p.map_or(0.0, |p| p.receivers_outside_depth)),
                    short(p.map_or(0.0, |p| p.casters_outside_depth))
                ),
                short(mib(s.memory_bytes)),
            ];
            if screen {
                row.push(short(c.verdict.objective.value(s)));
                row.push(short(worst_on_screen.value(s)));
            }
            row
        })
        .collect();
    (header, rows)
}

/// Per-preset description lines: rules, source, notes.
fn preset_lines(a: &Analysis) -> Vec<String> {
    let Some(p) = &a.preset else {
        return Vec::new();
    };
    let mut out = vec![
        format!("split: {}", p.split_rule),
        format!("fit: {}; snap: {}", p.fit, p.snap),
        format!("light depth: {}", p.light_depth_rule),
        format!("source: {}", p.source),
    ];
    if !a.summary.cascades_needed {
        out.push("no visible depth reads any cascade: nothing to measure".to_string());
    }
    out.extend(
        p.notes
            .iter()
            .filter(|n| !is_generic_note(n))
            .map(|n| format!("note: {n}")),
    );
    out
}

pub(crate) struct CompareHtml;

impl Exporter<Comparison> for CompareHtml {
    fn file_name(&self) -> &'static str {
        "compare.html"
    }

    fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
        let (header, rows) = table(c);
        let mut h = String::new();
        let _ = writeln!(h, "<p>Reproduce: <code>{}</code></p>", html::escape(&c.command()));
        h.push_str("<h2>Verdict</h2>\n");
        let _ = writeln!(
            h,
            "<div class=\"rec-box\"><p>{}</p><p><em>Ranked by</em> {}.</p></div>",
            html::escape(&c.verdict.line(&c.analyses)),
            html::escape(&ranking_text(c))
        );
        let invalid = c.verdict.invalid_lines(&c.analyses);
        if !invalid.is_empty() {
            h.push_str("<h3>Invalid, not ranked</h3>\n");
            h.push_str(&html::list(&invalid, None));
        }
        h.push_str("<h2>Scene</h2>\n");
        h.push_str(&html::list(&scene_lines(c), None));
        h.push_str("<h2>Results</h2>\n");
        h.push_str(&html::table(&header, &rows, &[0, 2, 3], None));
        h.push_str(&html::definitions(&table_definitions(c)));
        let _ = writeln!(h, "<p>{}</p>", html::escape(RESULTS_NOTE));
        h.push_str(&html::figure(&DensityOverlay(c).to_svg()?, DENSITY_CAPTION));
        h.push_str(&html::figure(&ShimmerCoverageBars(c).to_svg()?, SHIMMER_CAPTION));
        h.push_str("<h2>Presets</h2>\n");
        for (i, a) in c.analyses.iter().enumerate() {
            let _ = writeln!(h, "<h3>{}</h3>", html::escape(label(a).as_str()));
            if let Some((_, why)) = c.verdict.invalid.iter().find(|(j, _)| *j == i) {
                let _ = writeln!(
                    h,
                    "<p style=\"background:#fff3e0;border-left:5px solid #d9480f;padding:0.5em 1em\"><strong>INVALID, not ranked:</strong> {} (its pictures below show what it draws, not a usable result)</p>",
                    html::escape(why)
                );
            }
            h.push_str(&html::list(&preset_lines(a), Some("notes")));
            let name = label(a);
            let images = crate::figures::screen::captioned(a, &name);
            if !images.is_empty() {
                h.push_str(&html::png_figures(&images));
            }
        }
        Ok(html::page(
            &format!("csm-lab compare: {}", c.name),
            &format!("Cascaded shadow maps by engine: {}", c.name),
            &h,
            "",
        ))
    }
}

/// How the verdict ranks, in words.
fn ranking_text(c: &Comparison) -> String {
    let o = c.verdict.objective;
    format!(
        "the lowest {} ({}) among the valid entries: every slice corner covered, no receiver clipped by the light's depth range",
        o.name(),
        o.description()
    )
}

/// What the columns of the results table measure.
const RESULTS_NOTE: &str = "Aliasing is measured over the depths that read each preset's cascades; coverage checks each fitted slice and selection interval over the path, and missed corners read \"lit\". docs/metrics.md gives the formulas.";

const DENSITY_CAPTION: &str = "Texels per pixel against view depth, one line per preset";
const SHIMMER_CAPTION: &str = "Shimmer snapped and unsnapped, and coverage misses, per preset";

pub(crate) struct CompareMd;

impl Exporter<Comparison> for CompareMd {
    fn file_name(&self) -> &'static str {
        "compare.md"
    }

    fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
        let (header, rows) = table(c);
        let mut m = String::new();
        let _ = writeln!(m, "# Cascaded shadow maps by engine: {}\n", c.name);
        let _ = writeln!(m, "Reproduce: `{}`\n", c.command());
        let _ = writeln!(
            m,
            "## Verdict\n\n{}\n\n*Ranked by* {}.\n",
            c.verdict.line(&c.analyses),
            ranking_text(c)
        );
        let invalid = c.verdict.invalid_lines(&c.analyses);
        if !invalid.is_empty() {
            let _ = writeln!(m, "Invalid, not ranked:\n");
            for l in invalid {
                let _ = writeln!(m, "- {l}");
            }
            let _ = writeln!(m);
        }
        let _ = writeln!(m, "## Scene\n");
        for l in scene_lines(c) {
            let _ = writeln!(m, "- {l}");
        }
        let _ = writeln!(m, "\n## Results\n");
        m.push_str(&markdown::table(&header, &rows, &[0]));
        let _ = writeln!(m, "\n{}\n{}", defs::markdown(&table_definitions(c)), RESULTS_NOTE);
        let _ = writeln!(
            m,
            "\n![texels per pixel against depth](compare_density.svg)\n\n![shimmer and coverage](compare_shimmer.svg)\n"
        );
        let _ = writeln!(m, "## Presets\n");
        for a in &c.analyses {
            let _ = writeln!(m, "### {}\n", label(a).as_str());
            for l in preset_lines(a) {
                let _ = writeln!(m, "- {l}");
            }
            let _ = writeln!(m);
        }
        Ok(m.into_bytes())
    }
}

/// The exporters `compare` writes, in order.
pub(crate) fn exporters() -> Vec<&'static dyn Exporter<Comparison>> {
    vec![
        &CompareCsv,
        &DensitySvg,
        &DensityPng,
        &ShimmerSvg,
        &ShimmerPng,
        &CompareHtml,
        &CompareMd,
    ]
}

/// The lines `compare` prints about the engine settings files: each engine's file and how
/// near its cascades end to csm-lab's (the last comment line of the file).
pub(crate) fn settings_lines(settings: &[crate::commands::terms::EngineSetting]) -> String {
    if settings.is_empty() {
        return String::new();
    }
    let mut out = String::from("each engine's setting closest to csm-lab's own cascades (its cascades' far ends):\n");
    for s in settings {
        let how = s
            .comments
            .iter()
            .find_map(|c| c.strip_prefix("these settings' cascades end at "))
            .unwrap_or("the setting compared (csm-lab's own pipeline has no cascades to match here)");
        let _ = writeln!(out, "  {}: {how}", s.file_name());
    }
    out
}

/// The terminal summary of a comparison.
pub(crate) fn summary_table(c: &Comparison) -> String {
    let mut out = String::new();
    let presets = c.analyses.len() - c.own.len();
    let _ = writeln!(
        out,
        "{}: {}{}{}",
        c.name,
        count(presets as u64, "preset"),
        if c.engine_defaults {
            " at their own defaults"
        } else {
            ""
        },
        match c.own.len() {
            0 => String::new(),
            n => format!(" and csm-lab's own pipeline with {}", count(n as u64, "split range")),
        }
    );
    // The first column fits the longest name ("csm-lab (visible)"); the screen column appears
    // with scene geometry.
    let w = c.analyses.iter().map(|a| label(a).chars().count()).fold(13, usize::max);
    let screen = c.analyses.iter().any(|a| a.summary.screen.is_some());
    let _ = write!(
        out,
        "{:<w$} {:>11} {:<22} {:>10} {:>9} {:>10} {:>10} {:>9} {:>8} {:>10}",
        "preset",
        "cascades",
        "fit",
        if screen { "bounds max" } else { "max alias" },
        "mean",
        "shim snap",
        "shim raw",
        "coverage",
        "worst",
        "depth out"
    );
    let worst_on_screen = crate::metric::worst_aliasing(true);
    let _ = if screen {
        writeln!(out, " {:>10} {:>10}", "objective", "scr worst")
    } else {
        writeln!(out)
    };
    for a in &c.analyses {
        let s = &a.summary;
        let (worst, _) = coverage_extremes(a);
        let depth_out = a
            .preset
            .as_ref()
            .map_or(0.0, |p| p.receivers_outside_depth.max(p.casters_outside_depth));
        let _ = write!(
            out,
            "{:<w$} {:>11} {:<22} {:>10} {:>9} {:>10} {:>10} {:>9} {:>8} {:>10}",
            label(a).as_str(),
            format!(
                "{}x{}",
                a.rig().map_or(0, |r| r.cascade_count()),
                a.config.shadow.resolution
            ),
            fit_label(a),
            short(s.max_aliasing),
            short(s.mean_aliasing),
            short(s.shimmer_snapped),
            short(s.shimmer_unsnapped),
            s.coverage_violations,
            short(worst),
            short(depth_out),
        );
        if screen {
            let _ = write!(
                out,
                " {:>10} {:>10}",
                short(c.verdict.objective.value(s)),
                short(worst_on_screen.value(s))
            );
        }
        let _ = writeln!(
            out,
            "{}",
            invalid_reason(a).map_or(String::new(), |w| format!("  INVALID: {w}"))
        );
    }
    let _ = writeln!(out, "{}", c.verdict.line(&c.analyses));
    for l in c.verdict.invalid_lines(&c.analyses) {
        let _ = writeln!(out, "  not ranked: {l}");
    }
    out.push_str(&cost_table(c, w));
    out
}

/// Each preset's render cost on stdout (frame 0, as `compare.csv` has it): draw calls,
/// triangles (all, and inside the caster volumes), fragments, cleared texels, `cost_index`
/// against the scene file's own setting, `shadow_ms` when calibrated, and `cost_index_mean`
/// when the means over the path were measured. Empty without scene geometry (nothing to count).
fn cost_table(c: &Comparison, w: usize) -> String {
    let mut out = String::new();
    if c.analyses.iter().all(|a| a.summary.cost.counts.is_none()) {
        return out;
    }
    let ms = c.analyses.iter().any(|a| a.summary.cost.shadow_ms.is_some());
    let means = c.analyses.iter().any(|a| a.summary.cost.means.is_some());
    let na = |x: Option<f64>| x.map_or("n/a".to_string(), short);
    let _ = writeln!(
        out,
        "render cost (frame 0; cost_index against the scene file's own setting; docs/cost.md):"
    );
    let _ = write!(
        out,
        "{:<w$} {:>7} {:>10} {:>10} {:>12} {:>12} {:>10}",
        "preset", "draws", "triangles", "inside", "fragments", "cleared", "cost_index"
    );
    if ms {
        let _ = write!(out, " {:>10}", "shadow_ms");
    }
    if means {
        let _ = write!(out, " {:>10}", "path mean");
    }
    let _ = writeln!(out);
    for a in &c.analyses {
        let s = &a.summary.cost;
        let k = s.counts.unwrap_or_default();
        let _ = write!(
            out,
            "{:<w$} {:>7} {:>10} {:>10} {:>12} {:>12} {:>10}",
            label(a).as_str(),
            k.caster_objects,
            k.caster_triangles,
            k.caster_triangles_inside,
            short(k.raster_fragments),
            s.texels_cleared,
            na(s.cost_index)
        );
        if ms {
            let _ = write!(out, " {:>10}", na(s.shadow_ms));
        }
        if means {
            let _ = write!(out, " {:>10}", na(s.means.and_then(|m| m.cost_index_mean)));
        }
        let _ = writeln!(out);
    }
    if means {
        let _ = writeln!(
            out,
            "  path mean: cost_index_mean, the cost per frame on average over the camera path (n/a: not measured for a light basis that follows the camera)"
        );
    }
    out
}
