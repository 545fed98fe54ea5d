//! `csm-lab compare`: several engine presets on one scene, side by side.
//!
//! Each preset is loaded from the same config file (its `[shadow]` overrides and its own
//! engine table apply, unless `--defaults` asks for every preset's own defaults) and analysed
//! exactly as `analyze` would. The outputs, rendered in memory and then written atomically:
//!
//! * `compare.csv`: one row per preset: `preset` then the sweep columns, then the coverage and
//!   light-depth findings;
//! * `compare_density.svg/.png`: texels per pixel against view depth, one line per preset;
//! * `compare_shimmer.svg/.png`: shimmer with and without snapping, and coverage, per preset;
//! * `compare.html` (self-contained: inline CSS and SVG, nothing fetched) and `compare.md`.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rayon::prelude::*;

use crate::analysis::{analyze, Analysis, AnalysisOptions};
use crate::config::Config;
use crate::error::{Error, Result};
use crate::output::{csv_bytes, num, Exporter};
use crate::plots::{
    draw_legend, draw_message, log_range, series_color, texels_per_pixel_chart, Figure, PlotResult, FONT,
};
use crate::presets::{is_generic_note, lambda_value, PresetChoice, PresetName};

/// The presets compared and their analyses, in the order given.
#[derive(Debug, Clone)]
pub struct Comparison {
    pub config_path: PathBuf,
    /// The config file's stem.
    pub name: String,
    /// True when every preset ran at its own defaults (`--defaults`).
    pub engine_defaults: bool,
    pub analyses: Vec<Analysis>,
}

impl Comparison {
    /// The command line that reproduces this comparison.
    pub fn command(&self) -> String {
        let names: Vec<&str> = self
            .analyses
            .iter()
            .filter_map(|a| preset_of(a).map(|p| p.as_str()))
            .collect();
        format!(
            "csm-lab compare {} --presets {}{}",
            self.config_path.display(),
            names.join(","),
            if self.engine_defaults { " --defaults" } else { "" }
        )
    }
}

fn preset_of(a: &Analysis) -> Option<PresetName> {
    a.config.shadow.preset.as_ref().map(|p| p.name)
}

/// Loads the config once per preset and analyses each (in parallel, results in input order).
pub fn run(path: &Path, presets: &[PresetName], engine_defaults: bool) -> Result<Comparison> {
    if presets.is_empty() {
        return Err(Error::flag("--presets", "", "give at least one preset"));
    }
    let configs = presets
        .iter()
        .map(|p| {
            let choice = PresetChoice {
                name: Some(*p),
                also_allowed: presets.to_vec(),
                engine_defaults,
                lenient_overrides: true,
            };
            Config::load_with_preset(path, &choice)
        })
        .collect::<Result<Vec<_>>>()?;
    let name = configs[0].name.clone();
    let analyses = configs
        .par_iter()
        .map(|c| analyze(c, &AnalysisOptions::full()))
        .collect();
    Ok(Comparison {
        config_path: path.to_path_buf(),
        name,
        engine_defaults,
        analyses,
    })
}

/// `compare.csv`: `preset`, the sweep columns ([`crate::report::SUMMARY_COLUMNS`]), then these
/// extra findings.
pub const EXTRA_COLUMNS: [&str; 5] = [
    "snaps",
    "coverage_worst_texels",
    "min_slack_texels",
    "receivers_outside_depth",
    "casters_outside_depth",
];

/// The header of `compare.csv`.
pub fn columns() -> Vec<&'static str> {
    std::iter::once("preset")
        .chain(crate::report::SUMMARY_COLUMNS)
        .chain(EXTRA_COLUMNS)
        .collect()
}

/// Worst coverage miss (texels) and smallest slack over the configured snap mode's path.
fn coverage_extremes(a: &Analysis) -> (f64, f64) {
    a.configured_path().map_or((0.0, 0.0), |p| {
        (
            p.coverage.worst_texels.iter().cloned().fold(0.0, f64::max),
            p.coverage
                .min_slack_texels
                .iter()
                .cloned()
                .fold(f64::INFINITY, f64::min),
        )
    })
}

fn fit_label(a: &Analysis) -> String {
    a.rig()
        .map_or_else(|| a.config.shadow.fit.to_string(), |r| r.scheme.fit_label.clone())
}

/// One CSV row per preset.
pub fn rows(c: &Comparison) -> Result<Vec<Vec<String>>> {
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
            fields.extend(crate::report::summary_fields(
                lambda,
                cascades,
                a.config.shadow.resolution,
                &fit_label(a),
                s,
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

pub struct CompareCsv;

impl Exporter<Comparison> for CompareCsv {
    fn file_name(&self) -> &'static str {
        "compare.csv"
    }

    fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
        csv_bytes(&columns(), &rows(c)?)
    }
}

// ---------------------------------------------------------------------------------------------
// Figures
// ---------------------------------------------------------------------------------------------

/// Texels per pixel against view depth, log-log, one line per preset.
pub struct DensityOverlay<'a>(pub &'a Comparison);

impl Figure for DensityOverlay<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let c = self.0;
        let title = format!("Shadow texels per screen pixel vs depth, by preset: {}", c.name);
        let with_cascades: Vec<&Analysis> = c.analyses.iter().filter(|a| !a.density.is_empty()).collect();
        if with_cascades.is_empty() {
            return draw_message(root, &title, "No preset builds cascades for this scene.");
        }
        let z_lo = with_cascades
            .iter()
            .map(|a| a.summary.z_lo)
            .fold(f64::INFINITY, f64::min);
        let z_hi = with_cascades.iter().map(|a| a.summary.z_hi).fold(0.0, f64::max);
        let (mut chart, _) = texels_per_pixel_chart(
            root,
            &title,
            22,
            log_range(z_lo, z_hi),
            with_cascades
                .iter()
                .flat_map(|a| a.density.iter().map(|d| d.texels_per_pixel)),
        )?;
        for (i, a) in c.analyses.iter().enumerate() {
            if a.density.is_empty() {
                continue;
            }
            let color = preset_color(i);
            // Samples are sorted by depth with both sides of every split: the line shows the
            // sawtooth's jumps as vertical segments.
            let pts: Vec<(f64, f64)> = a.density.iter().map(|d| (d.depth, d.texels_per_pixel)).collect();
            let style = color.stroke_width(3);
            chart
                .draw_series(LineSeries::new(pts, style))?
                .label(format!(
                    "{}: {} x {}, max aliasing {:.3}",
                    preset_of(a).map_or("?", |p| p.as_str()),
                    a.rig().map_or(0, |r| r.cascade_count()),
                    a.config.shadow.resolution,
                    a.summary.max_aliasing
                ))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, 13)?;
        Ok(())
    }
}

/// Horizontal bars: shimmer snapped/unsnapped per preset, and coverage per preset.
pub struct ShimmerCoverageBars<'a>(pub &'a Comparison);

impl ShimmerCoverageBars<'_> {
    fn names(&self) -> Vec<String> {
        self.0
            .analyses
            .iter()
            .map(|a| preset_of(a).map_or_else(|| "?".to_string(), |p| p.to_string()))
            .collect()
    }
}

/// A segmented axis of exactly `n` rows (plotters includes the end of an integer range).
fn rows_axis(n: usize) -> std::ops::Range<usize> {
    if n >= 2 {
        0..n - 1
    } else {
        0..1
    }
}

/// Eleven distinguishable colours, one per preset.
pub fn preset_color(i: usize) -> RGBColor {
    const C: [RGBColor; 11] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
        RGBColor(0, 0, 128),
    ];
    C[i % C.len()]
}

/// Value labels: "0" for exact zeros, 3 significant digits otherwise.
fn short(v: f64) -> String {
    if v == 0.0 {
        "0".to_string()
    } else if (1e-2..1e4).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.2e}")
    }
}

impl Figure for ShimmerCoverageBars<'_> {
    fn size(&self) -> (u32, u32) {
        let n = self.0.analyses.len() as u32;
        (1280, 200 + 56 * n)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let c = self.0;
        let names = self.names();
        let n = names.len();
        let root = root.titled(
            &format!(
                "Shimmer and coverage by preset ({} path, {} frames): {}",
                c.analyses[0].config.motion.path.name(),
                c.analyses[0].config.motion.frames,
                c.name
            ),
            (FONT, 22),
        )?;
        let (left, right) = root.split_horizontally(700);

        // Shimmer: two rows per preset.
        let rows = 2 * n;
        let xmax = c
            .analyses
            .iter()
            .flat_map(|a| [a.summary.shimmer_snapped, a.summary.shimmer_unsnapped])
            .fold(0.0f64, f64::max)
            .max(0.05)
            * 1.3;
        // Row r (preset r / 2, snapped then unsnapped) is drawn top-down.
        let pos = |r: usize| rows - 1 - r;
        let snaps: Vec<bool> = c.analyses.iter().map(|a| a.config.shadow.snap).collect();
        let label_of = |p: usize| {
            let r = rows - 1 - p;
            let kind = match (r % 2, snaps[r / 2]) {
                (0, true) => "snapped",
                (0, false) => "(never snaps)",
                _ => "unsnapped",
            };
            format!("{} {kind}", names[r / 2])
        };
        let mut chart = ChartBuilder::on(&left)
            .margin(12)
            .x_label_area_size(46)
            .y_label_area_size(190)
            .build_cartesian_2d(0.0..xmax, rows_axis(rows).into_segmented())?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(rows)
            .y_label_formatter(&|v| match v {
                SegmentValue::CenterOf(r) | SegmentValue::Exact(r) if *r < rows => label_of(*r),
                _ => String::new(),
            })
            .x_desc("RMS sub-texel drift per frame (texels); 0 = stable")
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .draw()?;
        for (i, a) in c.analyses.iter().enumerate() {
            for (k, v) in [a.summary.shimmer_snapped, a.summary.shimmer_unsnapped]
                .into_iter()
                .enumerate()
            {
                let r = pos(2 * i + k);
                let color = if k == 0 { series_color(0) } else { series_color(1) };
                let mut bar = Rectangle::new(
                    [(0.0, SegmentValue::Exact(r)), (v, SegmentValue::Exact(r + 1))],
                    color.filled(),
                );
                bar.set_margin(3, 3, 0, 0);
                chart.draw_series(std::iter::once(bar))?;
                chart.draw_series(std::iter::once(Text::new(
                    short(v),
                    (v + 0.01 * xmax, SegmentValue::CenterOf(r)),
                    TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Left, VPos::Center)),
                )))?;
            }
        }

        // Coverage: one row per preset, violations with the worst miss in texels.
        let cmax = c
            .analyses
            .iter()
            .map(|a| a.summary.coverage_violations as f64)
            .fold(0.0f64, f64::max)
            .max(1.0)
            * 2.0;
        let mut chart = ChartBuilder::on(&right)
            .margin(12)
            .x_label_area_size(46)
            .y_label_area_size(110)
            .build_cartesian_2d(0.0..cmax, rows_axis(n).into_segmented())?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(n)
            .y_label_formatter(&|v| match v {
                SegmentValue::CenterOf(r) | SegmentValue::Exact(r) if *r < n => names[n - 1 - *r].clone(),
                _ => String::new(),
            })
            .x_desc("slice corners outside their window (count over the path)")
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .draw()?;
        for (i, a) in c.analyses.iter().enumerate() {
            let v = a.summary.coverage_violations as f64;
            let (worst, _) = coverage_extremes(a);
            let i = n - 1 - i;
            let mut bar = Rectangle::new(
                [(0.0, SegmentValue::Exact(i)), (v, SegmentValue::Exact(i + 1))],
                RGBColor(214, 39, 40).filled(),
            );
            bar.set_margin(6, 6, 0, 0);
            chart.draw_series(std::iter::once(bar))?;
            let text = if v == 0.0 {
                "0".to_string()
            } else {
                format!("{} (worst {} texels)", v as u64, short(worst))
            };
            chart.draw_series(std::iter::once(Text::new(
                text,
                (v + 0.01 * cmax, SegmentValue::CenterOf(i)),
                TextStyle::from((FONT, 12).into_font()).pos(Pos::new(HPos::Left, VPos::Center)),
            )))?;
        }
        Ok(())
    }
}

macro_rules! figure_exporter {
    ($name:ident, $fig:ident, $file:literal, $method:ident) => {
        pub struct $name;
        impl Exporter<Comparison> for $name {
            fn file_name(&self) -> &'static str {
                $file
            }
            fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
                $fig(c).$method()
            }
        }
    };
}

figure_exporter!(DensitySvg, DensityOverlay, "compare_density.svg", to_svg);
figure_exporter!(DensityPng, DensityOverlay, "compare_density.png", to_png);
figure_exporter!(ShimmerSvg, ShimmerCoverageBars, "compare_shimmer.svg", to_svg);
figure_exporter!(ShimmerPng, ShimmerCoverageBars, "compare_shimmer.png", to_png);

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
        "csm-lab's own [shadow] lambda, fit, snap and fit_depth_to_scene do not apply: each preset has its own rules."
            .to_string(),
        if c.engine_defaults {
            "Every preset runs at its own defaults (--defaults).".to_string()
        } else {
            "[shadow] cascades, resolution and max_distance of the file override each preset's defaults where the preset has them."
                .to_string()
        },
    ]
}

/// Table cells shared by both reports: (header, per-row values).
fn table(c: &Comparison) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let header = vec![
        "preset",
        "cascades × map",
        "fit",
        "snap",
        "max aliasing",
        "mean aliasing",
        "shimmer snapped",
        "shimmer unsnapped",
        "coverage misses (worst, texels)",
        "receivers / casters outside light depth",
        "memory (MiB)",
    ];
    let rows = c
        .analyses
        .iter()
        .map(|a| {
            let s = &a.summary;
            let p = a.preset.as_ref();
            let (worst, _) = coverage_extremes(a);
            vec![
                preset_of(a).map_or_else(String::new, |p| p.to_string()),
                format!(
                    "{} × {}",
                    a.rig().map_or(0, |r| r.cascade_count()),
                    a.config.shadow.resolution
                ),
                fit_label(a),
                p.map_or_else(String::new, |p| p.snap.clone()),
                format!("{:.3}", s.max_aliasing),
                format!("{:.3}", s.mean_aliasing),
                short(s.shimmer_snapped),
                short(s.shimmer_unsnapped),
                format!("{} ({})", s.coverage_violations, short(worst)),
                format!(
                    "{} / {}",
                    short(p.map_or(0.0, |p| p.receivers_outside_depth)),
                    short(p.map_or(0.0, |p| p.casters_outside_depth))
                ),
                format!("{:.1}", s.memory_bytes as f64 / (1024.0 * 1024.0)),
            ]
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

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An SVG document made fit for inlining in HTML: no XML declaration, no namespace URIs.
fn inline_svg(svg: &[u8]) -> String {
    let text = String::from_utf8_lossy(svg);
    let text = match text.find("<svg") {
        Some(i) => &text[i..],
        None => &text[..],
    };
    text.replace(" xmlns=\"http://www.w3.org/2000/svg\"", "")
        .replace(" xmlns:xlink=\"http://www.w3.org/1999/xlink\"", "")
}

pub struct CompareHtml;

impl Exporter<Comparison> for CompareHtml {
    fn file_name(&self) -> &'static str {
        "compare.html"
    }

    fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
        use std::fmt::Write as _;
        let density = inline_svg(&DensityOverlay(c).to_svg()?);
        let bars = inline_svg(&ShimmerCoverageBars(c).to_svg()?);
        let (header, rows) = table(c);
        let mut h = String::new();
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>csm-lab compare: {}</title>\n<style>\n\
body {{ font-family: sans-serif; margin: 2em auto; max-width: 1320px; color: #222; }}\n\
table {{ border-collapse: collapse; font-size: 14px; margin: 1em 0; }}\n\
th, td {{ border: 1px solid #bbb; padding: 4px 8px; text-align: right; }}\n\
th {{ background: #eee; }} td:first-child, th:first-child {{ text-align: left; }}\n\
code {{ background: #f3f3f3; padding: 2px 4px; }} .figure {{ margin: 1.5em 0; }}\n\
ul.notes {{ font-size: 14px; }}\n</style>\n</head>\n<body>\n",
            html_escape(&c.name)
        );
        let _ = writeln!(h, "<h1>Cascaded shadow maps by engine: {}</h1>", html_escape(&c.name));
        let _ = writeln!(h, "<p>Reproduce: <code>{}</code></p>", html_escape(&c.command()));
        let _ = writeln!(h, "<h2>Scene</h2>\n<ul>");
        for l in scene_lines(c) {
            let _ = writeln!(h, "<li>{}</li>", html_escape(&l));
        }
        let _ = writeln!(h, "</ul>\n<h2>Results</h2>\n<table>\n<tr>");
        for col in &header {
            let _ = write!(h, "<th>{}</th>", html_escape(col));
        }
        let _ = writeln!(h, "</tr>");
        for r in &rows {
            let _ = write!(h, "<tr>");
            for v in r {
                let _ = write!(h, "<td>{}</td>", html_escape(v));
            }
            let _ = writeln!(h, "</tr>");
        }
        let _ = writeln!(h, "</table>");
        let _ = writeln!(
            h,
            "<p>Aliasing is shadow texel size over screen pixel size at each view depth (above 1: blocky), over the depths that read each preset's cascades. Shimmer is the RMS sub-texel drift of world-fixed points per frame. Coverage counts slice corners (fitted slice and selection interval) outside their window over the path; those points read \"lit\".</p>"
        );
        let _ = writeln!(
            h,
            "<div class=\"figure\">{density}</div>\n<div class=\"figure\">{bars}</div>"
        );
        let _ = writeln!(h, "<h2>Presets</h2>");
        for a in &c.analyses {
            let _ = writeln!(
                h,
                "<h3>{}</h3>\n<ul class=\"notes\">",
                html_escape(preset_of(a).map_or("?", |p| p.as_str()))
            );
            for l in preset_lines(a) {
                let _ = writeln!(h, "<li>{}</li>", html_escape(&l));
            }
            let _ = writeln!(h, "</ul>");
        }
        let _ = writeln!(
            h,
            "<p>Generated by csm-lab {}.</p>\n</body>\n</html>",
            env!("CARGO_PKG_VERSION")
        );
        Ok(h.into_bytes())
    }
}

pub struct CompareMd;

impl Exporter<Comparison> for CompareMd {
    fn file_name(&self) -> &'static str {
        "compare.md"
    }

    fn render(&self, c: &Comparison) -> Result<Vec<u8>> {
        use std::fmt::Write as _;
        let cell = |s: &str| s.replace('|', "\\|");
        let (header, rows) = table(c);
        let mut m = String::new();
        let _ = writeln!(m, "# Cascaded shadow maps by engine: {}\n", c.name);
        let _ = writeln!(m, "Reproduce: `{}`\n", c.command());
        let _ = writeln!(m, "## Scene\n");
        for l in scene_lines(c) {
            let _ = writeln!(m, "- {l}");
        }
        let _ = writeln!(m, "\n## Results\n");
        let _ = writeln!(
            m,
            "| {} |",
            header.iter().map(|h| cell(h)).collect::<Vec<_>>().join(" | ")
        );
        let _ = writeln!(
            m,
            "|{}|",
            header
                .iter()
                .enumerate()
                .map(|(i, _)| if i == 0 { "---" } else { "---:" })
                .collect::<Vec<_>>()
                .join("|")
        );
        for r in &rows {
            let _ = writeln!(m, "| {} |", r.iter().map(|v| cell(v)).collect::<Vec<_>>().join(" | "));
        }
        let _ = writeln!(
            m,
            "\n![texels per pixel against depth](compare_density.svg)\n\n![shimmer and coverage](compare_shimmer.svg)\n"
        );
        let _ = writeln!(m, "## Presets\n");
        for a in &c.analyses {
            let _ = writeln!(m, "### {}\n", preset_of(a).map_or("?", |p| p.as_str()));
            for l in preset_lines(a) {
                let _ = writeln!(m, "- {l}");
            }
            let _ = writeln!(m);
        }
        Ok(m.into_bytes())
    }
}

/// The exporters `compare` writes, in order.
pub fn exporters() -> Vec<&'static dyn Exporter<Comparison>> {
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

/// The terminal summary of a comparison.
pub fn summary_table(c: &Comparison) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {} presets{}",
        c.name,
        c.analyses.len(),
        if c.engine_defaults {
            " at their own defaults"
        } else {
            ""
        }
    );
    let _ = writeln!(
        out,
        "{:<13} {:>11} {:<22} {:>10} {:>9} {:>10} {:>10} {:>9} {:>8} {:>10}",
        "preset", "cascades", "fit", "max alias", "mean", "shim snap", "shim raw", "coverage", "worst", "depth out"
    );
    for a in &c.analyses {
        let s = &a.summary;
        let (worst, _) = coverage_extremes(a);
        let depth_out = a
            .preset
            .as_ref()
            .map_or(0.0, |p| p.receivers_outside_depth.max(p.casters_outside_depth));
        let _ = writeln!(
            out,
            "{:<13} {:>11} {:<22} {:>10.3} {:>9.3} {:>10.2e} {:>10.2e} {:>9} {:>8.3} {:>10.3}",
            preset_of(a).map_or("?", |p| p.as_str()),
            format!(
                "{}x{}",
                a.rig().map_or(0, |r| r.cascade_count()),
                a.config.shadow.resolution
            ),
            fit_label(a),
            s.max_aliasing,
            s.mean_aliasing,
            s.shimmer_snapped,
            s.shimmer_unsnapped,
            s.coverage_violations,
            worst,
            depth_out
        );
    }
    out
}
