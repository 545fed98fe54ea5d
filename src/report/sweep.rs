//! What `sweep` writes: `sweep.csv`, `recommendation.json`, four figures (SVG and PNG) and a
//! design-review report as one self-contained `report.html` (inline SVG and CSS) and as
//! `report.md`.

use std::fmt::Write as _;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::analysis::{analyze, Analysis, AnalysisOptions, Summary};
use crate::config::{Config, Fit};
use crate::error::Result;
use crate::output::{csv_bytes, json_bytes, num};
use crate::plots::{
    draw_legend, log_range, series_color, svg_to_png, texels_per_pixel_chart, Figure, PlotResult, FONT,
};
use crate::sweep::{self, Grid, Recommendation, Row, Setting};

/// Everything a sweep produced, ready to be written.
#[derive(Debug, Clone)]
pub struct SweepResult {
    pub config: Config,
    pub grid: Grid,
    pub rows: Vec<Row>,
    pub front: Vec<usize>,
    pub recommendation: Option<Recommendation>,
    pub budget_mib: f64,
    /// The command that reproduces the sweep.
    pub command: String,
}

impl SweepResult {
    pub fn new(config: Config, grid: Grid, rows: Vec<Row>, command: String) -> Self {
        let budget_mib = config
            .sweep
            .as_ref()
            .and_then(|s| s.memory_budget_mib)
            .unwrap_or(sweep::DEFAULT_BUDGET_MIB);
        let front = sweep::pareto_front(&rows);
        let recommendation = sweep::recommend(&rows, budget_mib);
        SweepResult {
            config,
            grid,
            rows,
            front,
            recommendation,
            budget_mib,
            command,
        }
    }

    pub fn recommended(&self) -> Option<&Row> {
        self.recommendation.as_ref().map(|r| &self.rows[r.index])
    }

    /// Rows in objective order (acceptable within budget first), for the "top" tables.
    pub fn ranked(&self) -> Vec<usize> {
        let budget = self
            .recommendation
            .as_ref()
            .map_or((self.budget_mib * 1048576.0) as u64, |r| r.budget_bytes);
        let mut idx: Vec<usize> = (0..self.rows.len())
            .filter(|&i| self.rows[i].summary.cascades_needed)
            .collect();
        let key = |i: usize| {
            let s = &self.rows[i].summary;
            let ok =
                s.coverage_violations == 0 && s.shimmer_snapped <= sweep::STABLE_SHIMMER && s.memory_bytes <= budget;
            (!ok, s.mean_aliasing, s.max_aliasing, s.memory_bytes, i)
        };
        idx.sort_by(|&a, &b| {
            let (ka, kb) = (key(a), key(b));
            ka.0.cmp(&kb.0)
                .then(ka.1.total_cmp(&kb.1))
                .then(ka.2.total_cmp(&kb.2))
                .then(ka.3.cmp(&kb.3))
                .then(ka.4.cmp(&kb.4))
        });
        // The recommendation heads the table (near-ties in mean are decided by max aliasing).
        if let Some(r) = &self.recommendation {
            idx.retain(|&i| i != r.index);
            idx.insert(0, r.index);
        }
        idx
    }
}

/// The columns every per-configuration table shares (`sweep.csv`, `compare.csv`): the setting,
/// then the summary metrics. A contract: users' scripts and CI baselines read them by name.
pub const SUMMARY_COLUMNS: [&str; 15] = [
    "lambda",
    "cascades",
    "resolution",
    "fit",
    "z_lo",
    "z_hi",
    "max_aliasing",
    "mean_aliasing",
    "mean_log_aliasing",
    "undersampled_fraction",
    "shimmer_snapped",
    "shimmer_unsnapped",
    "size_jitter",
    "coverage_violations",
    "memory_bytes",
];

/// The fields of [`SUMMARY_COLUMNS`] for one configuration (`lambda` may be empty where a split
/// rule has none).
pub fn summary_fields(lambda: String, cascades: usize, resolution: u32, fit: &str, s: &Summary) -> Result<Vec<String>> {
    Ok(vec![
        lambda,
        cascades.to_string(),
        resolution.to_string(),
        fit.to_string(),
        num("z_lo", s.z_lo)?,
        num("z_hi", s.z_hi)?,
        num("max_aliasing", s.max_aliasing)?,
        num("mean_aliasing", s.mean_aliasing)?,
        num("mean_log_aliasing", s.mean_log_aliasing)?,
        num("undersampled_fraction", s.undersampled_fraction)?,
        num("shimmer_snapped", s.shimmer_snapped)?,
        num("shimmer_unsnapped", s.shimmer_unsnapped)?,
        num("size_jitter", s.size_jitter)?,
        s.coverage_violations.to_string(),
        s.memory_bytes.to_string(),
    ])
}

/// `sweep.csv`: [`SUMMARY_COLUMNS`], then these.
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
    let rows = r
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let st = &row.setting;
            let mut fields = summary_fields(
                num("lambda", st.lambda)?,
                st.cascades,
                st.resolution,
                st.fit.name(),
                &row.summary,
            )?;
            fields.extend([
                row.summary.cascades_needed.to_string(),
                r.front.contains(&i).to_string(),
                (rec == Some(i)).to_string(),
                preset.clone(),
            ]);
            Ok(fields)
        })
        .collect::<Result<Vec<_>>>()?;
    let header: Vec<&str> = SUMMARY_COLUMNS.iter().chain(&SWEEP_EXTRA_COLUMNS).copied().collect();
    csv_bytes(&header, &rows)
}

fn row_json(row: &Row) -> serde_json::Value {
    let mut v = serde_json::json!({
        "lambda": row.setting.lambda,
        "cascades": row.setting.cascades,
        "resolution": row.setting.resolution,
        "fit": row.setting.fit,
    });
    let s = serde_json::to_value(&row.summary).expect("plain struct");
    for (k, x) in s.as_object().expect("object") {
        v[k] = x.clone();
    }
    v
}

pub fn recommendation_value(r: &SweepResult) -> serde_json::Value {
    serde_json::json!({
        "tool": format!("csm-lab {}", env!("CARGO_PKG_VERSION")),
        "name": r.config.name,
        "command": r.command,
        "configurations": r.rows.len(),
        "objective": sweep::OBJECTIVE,
        "memory_budget_mib": r.budget_mib,
        "within_budget": r.recommendation.as_ref().map(|x| x.within_budget),
        "recommended": r.recommended().map(row_json),
        "pareto_front": r.front.iter().map(|&i| row_json(&r.rows[i])).collect::<Vec<_>>(),
    })
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

// ---------------------------------------------------------------------------------------------
// Figures
// ---------------------------------------------------------------------------------------------

/// Sequential colour map (viridis-like stops), t in [0, 1].
fn colormap(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    let x = t * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let lerp = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(lerp(a.0, b.0), lerp(a.1, b.1), lerp(a.2, b.2))
}

/// A number with 3 significant digits and no trailing zeros ("1000", "12.5", "0.0431").
pub fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Max and mean aliasing over λ × cascade count, one panel per resolution (and fit).
pub struct HeatmapFigure<'a>(pub &'a SweepResult);

impl HeatmapFigure<'_> {
    fn rows_of_panels(&self) -> Vec<(Fit, &'static str)> {
        let mut v = Vec::new();
        for fit in sweep::fits_in(&self.0.rows) {
            v.push((fit, "max_aliasing"));
            v.push((fit, "mean_aliasing"));
        }
        v
    }
}

fn metric_of(row: &Row, metric: &str) -> f64 {
    match metric {
        "max_aliasing" => row.summary.max_aliasing,
        _ => row.summary.mean_aliasing,
    }
}

impl Figure for HeatmapFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let cols = self.0.grid.resolution.values.len() as u32;
        let rows = self.rows_of_panels().len() as u32;
        (120 + 330 * cols, 70 + 300 * rows)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.0;
        let lambdas = &r.grid.lambda.values;
        let counts = &r.grid.cascades.values;
        let resolutions = &r.grid.resolution.values;
        let title = format!(
            "Aliasing (shadow texel / screen pixel, lower is better) over λ × cascades: {}",
            r.config.name
        );
        let root = root.titled(&title, (FONT, 22))?;
        let panel_rows = self.rows_of_panels();
        let bands = root.split_evenly((panel_rows.len(), 1));
        let rec = r.recommended().map(|x| x.setting);
        for (band, (fit, metric)) in bands.iter().zip(&panel_rows) {
            let (w, _) = band.dim_in_pixel();
            let (panels_area, bar_area) = band.split_horizontally(w.saturating_sub(110));
            // One colour scale per band (metric and fit), on log values.
            let values: Vec<f64> = r
                .rows
                .iter()
                .filter(|x| x.setting.fit == *fit && x.summary.cascades_needed)
                .map(|x| metric_of(x, metric))
                .filter(|v| *v > 0.0)
                .collect();
            let lo = values.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = values.iter().cloned().fold(0.0, f64::max);
            let (lo, hi) = if lo.is_finite() && hi > lo {
                (lo, hi)
            } else {
                (1.0, 10.0)
            };
            let t_of = |v: f64| (v.ln() - lo.ln()) / (hi.ln() - lo.ln());
            let panels = panels_area.split_evenly((1, resolutions.len()));
            for (panel, &res) in panels.iter().zip(resolutions) {
                let label_every = lambdas.len().div_ceil(6).max(1);
                let mut chart = ChartBuilder::on(panel)
                    .caption(format!("{} · {res}² · {fit}", metric.replace('_', " ")), (FONT, 15))
                    .margin(6)
                    .x_label_area_size(38)
                    .y_label_area_size(42)
                    // plotters' segmented ranges include their end value: 0..n-1 gives n cells.
                    .build_cartesian_2d(
                        (0..lambdas.len().saturating_sub(1)).into_segmented(),
                        (0..counts.len().saturating_sub(1)).into_segmented(),
                    )?;
                chart
                    .configure_mesh()
                    .disable_mesh()
                    .x_desc("λ (0 uniform → 1 log)")
                    .y_desc("cascades")
                    .axis_desc_style((FONT, 12))
                    .label_style((FONT, 11))
                    .x_labels(lambdas.len())
                    .y_labels(counts.len())
                    .x_label_formatter(&|v| match v {
                        SegmentValue::CenterOf(i) if *i < lambdas.len() && i % label_every == 0 => {
                            format!("{}", lambdas[*i])
                        }
                        _ => String::new(),
                    })
                    .y_label_formatter(&|v| match v {
                        SegmentValue::CenterOf(i) if *i < counts.len() => counts[*i].to_string(),
                        _ => String::new(),
                    })
                    .draw()?;
                for row in r
                    .rows
                    .iter()
                    .filter(|x| x.setting.fit == *fit && x.setting.resolution == res)
                {
                    let (Some(i), Some(j)) = (
                        lambdas.iter().position(|l| *l == row.setting.lambda),
                        counts.iter().position(|c| *c == row.setting.cascades),
                    ) else {
                        continue;
                    };
                    let color = if row.summary.cascades_needed {
                        colormap(t_of(metric_of(row, metric)))
                    } else {
                        RGBColor(220, 220, 220)
                    };
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [
                            (SegmentValue::Exact(i), SegmentValue::Exact(j)),
                            (SegmentValue::Exact(i + 1), SegmentValue::Exact(j + 1)),
                        ],
                        color.filled(),
                    )))?;
                    if Some(row.setting) == rec {
                        chart.draw_series(std::iter::once(Rectangle::new(
                            [
                                (SegmentValue::Exact(i), SegmentValue::Exact(j)),
                                (SegmentValue::Exact(i + 1), SegmentValue::Exact(j + 1)),
                            ],
                            RED.stroke_width(3),
                        )))?;
                    }
                }
            }
            // Colour bar.
            let mut bar = ChartBuilder::on(&bar_area)
                .margin_top(30)
                .margin_bottom(45)
                .margin_right(8)
                .y_label_area_size(55)
                .build_cartesian_2d(0.0..1.0, (lo..hi).log_scale())?;
            bar.configure_mesh()
                .disable_x_mesh()
                .disable_x_axis()
                .disable_y_mesh()
                .label_style((FONT, 11))
                .y_labels(6)
                .y_label_formatter(&|v| significant(*v))
                .draw()?;
            let steps = 60;
            bar.draw_series((0..steps).map(|k| {
                let a = lo * (hi / lo).powf(k as f64 / steps as f64);
                let b = lo * (hi / lo).powf((k + 1) as f64 / steps as f64);
                Rectangle::new([(0.0, a), (1.0, b)], colormap((k as f64 + 0.5) / steps as f64).filled())
            }))?;
        }
        Ok(())
    }
}

/// Texels per pixel against depth for a handful of λ at the recommended count/resolution/fit.
pub struct LambdaDensityFigure<'a> {
    pub result: &'a SweepResult,
    pub analyses: Vec<Analysis>,
}

impl<'a> LambdaDensityFigure<'a> {
    /// Picks λ values near 0, 0.25, 0.5, 0.75, 1 (and the recommended one) from the grid.
    pub fn new(result: &'a SweepResult) -> Self {
        let Some(rec) = result.recommended() else {
            return LambdaDensityFigure {
                result,
                analyses: Vec::new(),
            };
        };
        let grid = &result.grid.lambda.values;
        let mut picks: Vec<f64> = [0.0, 0.25, 0.5, 0.75, 1.0, rec.setting.lambda]
            .iter()
            .map(|t| {
                *grid
                    .iter()
                    .min_by(|a, b| (*a - t).abs().total_cmp(&(*b - t).abs()))
                    .expect("non-empty axis")
            })
            .collect();
        picks.sort_by(f64::total_cmp);
        picks.dedup();
        let opts = AnalysisOptions {
            density_profile: true,
            ..AnalysisOptions::summary_only()
        };
        let analyses = picks
            .iter()
            .filter_map(|&lambda| Setting { lambda, ..rec.setting }.apply(&result.config).ok())
            .map(|c| analyze(&c, &opts))
            .collect();
        LambdaDensityFigure { result, analyses }
    }
}

impl Figure for LambdaDensityFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.result;
        let Some(rec) = r.recommended() else {
            return crate::plots::draw_message(
                root,
                "Texels per pixel vs depth",
                "No recommendation: nothing to plot.",
            );
        };
        let title = format!(
            "Texels per pixel vs depth for several λ: {} cascades × {}², {} fit",
            rec.setting.cascades, rec.setting.resolution, rec.setting.fit
        );
        let (mut chart, (y0, y1)) = texels_per_pixel_chart(
            root,
            &title,
            20,
            (rec.summary.z_lo, rec.summary.z_hi),
            self.analyses
                .iter()
                .flat_map(|a| a.density.iter().map(|d| d.texels_per_pixel)),
        )?;
        for (k, a) in self.analyses.iter().enumerate() {
            let color = series_color(k);
            let width = if a.config.shadow.lambda == rec.setting.lambda {
                4
            } else {
                2
            };
            // One polyline per cascade, so the jumps at the splits stay vertical gaps.
            let m = a.cascades.len();
            for i in 0..m {
                let pts: Vec<(f64, f64)> = a
                    .density
                    .iter()
                    .filter(|d| d.cascade == i)
                    .map(|d| (d.depth, d.texels_per_pixel))
                    .collect();
                let s = chart.draw_series(LineSeries::new(pts, color.stroke_width(width)))?;
                if i == 0 {
                    let label = format!(
                        "λ = {}: mean aliasing {:.3}, max {:.3}{}",
                        a.config.shadow.lambda,
                        a.summary.mean_aliasing,
                        a.summary.max_aliasing,
                        if width == 4 { " (recommended)" } else { "" }
                    );
                    s.label(label)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(width)));
                }
            }
            // Split depths as short ticks at the bottom, in the λ's colour.
            if let Some(rig) = a.rig() {
                for s in &rig.splits[1..rig.splits.len() - 1] {
                    chart.draw_series(std::iter::once(PathElement::new(
                        vec![(*s, y0), (*s, y0 * (y1 / y0).powf(0.06))],
                        color.stroke_width(2),
                    )))?;
                }
            }
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, 13)?;
        Ok(())
    }
}

/// Shimmer snapped vs unsnapped for every configuration.
pub struct ShimmerSweepFigure<'a>(pub &'a SweepResult);

impl Figure for ShimmerSweepFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.0;
        let title = format!(
            "Shimmer of every configuration ({} path): snapped vs unsnapped",
            r.config.motion.path.name()
        );
        let n = r.rows.len();
        let max_un = r
            .rows
            .iter()
            .map(|x| x.summary.shimmer_unsnapped)
            .fold(0.0f64, f64::max);
        let max_sn = r.rows.iter().map(|x| x.summary.shimmer_snapped).fold(0.0f64, f64::max);
        let ymax = max_un.max(max_sn).max(0.05) * 1.12;
        let mut chart = ChartBuilder::on(root)
            .caption(&title, (FONT, 20))
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5).max(0.5), 0.0..ymax)?;
        chart
            .configure_mesh()
            .x_desc("configuration (fit, resolution, cascades; λ varies fastest)")
            .y_desc("RMS sub-texel drift per frame (texels)")
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 12))
            .draw()?;
        // Group separators: each (fit, resolution) block.
        let mut last = None;
        for (i, row) in r.rows.iter().enumerate() {
            let key = (row.setting.fit, row.setting.resolution);
            if last.is_some() && last != Some(key) {
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(i as f64 - 0.5, 0.0), (i as f64 - 0.5, ymax)],
                    RGBColor(200, 200, 200).stroke_width(1),
                )))?;
            }
            last = Some(key);
        }
        let orange = series_color(1);
        let blue = series_color(0);
        chart
            .draw_series(r.rows.iter().enumerate().map(|(i, x)| {
                Rectangle::new(
                    [(i as f64 - 0.4, 0.0), (i as f64 + 0.4, x.summary.shimmer_unsnapped)],
                    orange.mix(0.7).filled(),
                )
            }))?
            .label(format!("unsnapped (largest {max_un:.3} texels)"))
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], orange.filled()));
        chart
            .draw_series(
                r.rows
                    .iter()
                    .enumerate()
                    .map(|(i, x)| Circle::new((i as f64, x.summary.shimmer_snapped), 3, blue.filled())),
            )?
            .label(if max_sn <= sweep::STABLE_SHIMMER {
                format!("snapped (largest {max_sn:.1e} texels: stable, dots sit on zero)")
            } else {
                format!("snapped (largest {max_sn:.3} texels: NOT stable)")
            })
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, blue.filled()));
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 14)?;
        Ok(())
    }
}

/// Pareto front of memory against mean aliasing.
pub struct ParetoFigure<'a>(pub &'a SweepResult);

impl Figure for ParetoFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.0;
        let title = format!("Memory against mean aliasing: {}", r.config.name);
        let pts: Vec<(f64, f64)> = r
            .rows
            .iter()
            .filter(|x| x.summary.cascades_needed)
            .map(|x| (mib(x.summary.memory_bytes), x.summary.mean_aliasing))
            .collect();
        if pts.is_empty() {
            return crate::plots::draw_message(root, &title, "No cascades needed for any configuration.");
        }
        let (xmin, xmax) = pts
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
        let (ymin, ymax) = pts
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
        let (x0, x1) = log_range(xmin.min(r.budget_mib), xmax.max(r.budget_mib));
        let (y0, y1) = log_range(ymin, ymax);
        let mut chart = ChartBuilder::on(root)
            .caption(&title, (FONT, 22))
            .margin(14)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("shadow map memory (MiB, log; cascades × resolution² × 4 bytes)")
            .y_desc("mean aliasing (texel/pixel, log; lower is better)")
            .max_light_lines(3)
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .draw()?;
        let grey = RGBColor(170, 170, 170);
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 3, grey.filled())))?
            .label("configuration")
            .legend(move |(x, y)| Circle::new((x + 8, y), 3, grey.filled()));
        let budget = RGBColor(120, 120, 120).stroke_width(2);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(r.budget_mib, y0), (r.budget_mib, y1)],
                6,
                4,
                budget,
            ))?
            .label(format!("memory budget {} MiB", r.budget_mib))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], budget));
        let orange = series_color(1);
        let front: Vec<(f64, f64)> = r
            .front
            .iter()
            .map(|&i| (mib(r.rows[i].summary.memory_bytes), r.rows[i].summary.mean_aliasing))
            .collect();
        chart
            .draw_series(LineSeries::new(front.clone(), orange.stroke_width(3)))?
            .label("Pareto front (nothing is both cheaper and sharper)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], orange.stroke_width(3)));
        chart.draw_series(front.iter().map(|p| Circle::new(*p, 5, orange.filled())))?;
        if let Some(rec) = r.recommended() {
            let p = (mib(rec.summary.memory_bytes), rec.summary.mean_aliasing);
            let red = RGBColor(200, 0, 0);
            chart
                .draw_series(std::iter::once(Circle::new(p, 9, red.stroke_width(3))))?
                .label("recommended")
                .legend(move |(x, y)| Circle::new((x + 8, y), 6, red.stroke_width(2)));
            // The label sits up and to the right of the marker, in pixels, clear of it.
            chart.draw_series(std::iter::once(
                EmptyElement::at(p)
                    + Text::new(
                        format!(
                            "recommended: {} × {}², λ {} ({})",
                            rec.setting.cascades, rec.setting.resolution, rec.setting.lambda, rec.setting.fit
                        ),
                        (14, -30),
                        (FONT, 15).into_font().color(&red),
                    ),
            ))?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 13)?;
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Reports
// ---------------------------------------------------------------------------------------------

/// Escapes text for HTML/XML.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

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
        return if r.rows.iter().any(|x| x.summary.cascades_needed) {
            "No configuration covers every slice and stays stable when snapped; see the table below.".to_string()
        } else {
            "The scene is not visible within the shadow distance: no cascades are needed.".to_string()
        };
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
    let mut t = format!(
        "{} cascades of {}² texels, λ = {}, {} fit: mean aliasing {:.3}, worst {:.3} at a cascade's near edge, \
         {:.0}% of the depth range under-sampled, {} MiB. ",
        rec.setting.cascades,
        rec.setting.resolution,
        rec.setting.lambda,
        rec.setting.fit,
        s.mean_aliasing,
        s.max_aliasing,
        100.0 * s.undersampled_fraction,
        mib(s.memory_bytes)
    );
    if r.recommendation.as_ref().is_some_and(|x| x.within_budget) {
        let _ = write!(
            t,
            "Of {} configurations, {} fit the {} MiB budget, cover every slice and are stable when snapped; \
             this one has the lowest mean aliasing among them (within 1%, the lowest worst case).",
            r.rows.len(),
            acceptable_within,
            r.budget_mib
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
    });
    if let Some(o) = own {
        if o.setting != rec.setting {
            let _ = write!(
                t,
                " The configured setting ({}) has mean aliasing {:.3}, worst {:.3}, {} MiB.",
                o.setting.label(),
                o.summary.mean_aliasing,
                o.summary.max_aliasing,
                mib(o.summary.memory_bytes)
            );
        } else {
            t.push_str(" It is the configured setting.");
        }
    }
    t
}

const TOP: usize = 15;

/// The figures of a sweep as (file stem, title, SVG bytes), rendered once.
pub fn render_figures(r: &SweepResult) -> Result<Vec<(&'static str, &'static str, Vec<u8>)>> {
    Ok(vec![
        (
            "heatmap",
            "Max and mean aliasing over λ × cascade count, per resolution",
            HeatmapFigure(r).to_svg()?,
        ),
        (
            "density_lambda",
            "Texels per pixel against depth for several λ at the recommended count and resolution",
            LambdaDensityFigure::new(r).to_svg()?,
        ),
        (
            "shimmer_sweep",
            "Shimmer snapped vs unsnapped for every configuration",
            ShimmerSweepFigure(r).to_svg()?,
        ),
        (
            "pareto",
            "Pareto front of memory against mean aliasing",
            ParetoFigure(r).to_svg()?,
        ),
    ])
}

fn table_rows(r: &SweepResult) -> Vec<[String; 10]> {
    r.ranked()
        .into_iter()
        .take(TOP)
        .map(|i| {
            let x = &r.rows[i];
            let s = &x.summary;
            [
                x.setting.cascades.to_string(),
                x.setting.resolution.to_string(),
                x.setting.lambda.to_string(),
                x.setting.fit.to_string(),
                format!("{:.4}", s.mean_aliasing),
                format!("{:.4}", s.max_aliasing),
                format!("{:.4}", s.mean_log_aliasing),
                format!("{:.2e}", s.shimmer_snapped),
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

const CSS: &str = "body{font-family:'DejaVu Sans',Helvetica,Arial,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}\
h1{font-size:1.6em}h2{margin-top:1.8em;border-bottom:1px solid #ddd}\
table{border-collapse:collapse;font-size:0.92em}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}\
th{background:#f3f3f3}td.l,th.l{text-align:left}tr.rec{background:#ffecec;font-weight:bold}\
.rec-box{background:#f6fbf6;border-left:5px solid #2a9d4a;padding:0.8em 1em}\
figure{margin:1.5em 0}figure svg{max-width:100%;height:auto;border:1px solid #eee}figcaption{color:#555;font-size:0.92em}\
pre{background:#f5f5f5;padding:0.8em;overflow-x:auto}";

/// `report.html`: one self-contained, well-formed (XHTML-compatible) document.
pub fn report_html(r: &SweepResult, figures: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    let mut h = String::new();
    let name = escape(&r.config.name);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"/>\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"/>\
         <title>csm-lab sweep: {name}</title><style>{CSS}</style></head><body>\n"
    );
    let _ = writeln!(h, "<h1>Cascaded shadow map sweep: {name}</h1>");
    let _ = writeln!(
        h,
        "<p>{} configurations: {} λ values × {} cascade counts × {} resolutions × {} fits, each analysed in full \
         (closed-form aliasing, shimmer with and without snapping along the motion path, coverage).</p>",
        r.rows.len(),
        r.grid.lambda.values.len(),
        r.grid.cascades.values.len(),
        r.grid.resolution.values.len(),
        r.grid.fit.values.len()
    );
    h.push_str("<h2>Scene</h2>\n<table>");
    for (k, v) in scene_facts(&r.config, &r.rows) {
        let _ = write!(
            h,
            "<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>",
            escape(&k),
            escape(&v)
        );
    }
    h.push_str("</table>\n<h2>Recommendation</h2>\n");
    let _ = writeln!(h, "<div class=\"rec-box\"><p>{}</p>", escape(&why_text(r)));
    let _ = writeln!(h, "<p><em>Objective:</em> {}.</p></div>", escape(sweep::OBJECTIVE));
    if !figures.is_empty() {
        h.push_str("<h2>Plots</h2>\n");
        for (_, caption, svg) in figures {
            let svg = String::from_utf8_lossy(svg);
            let svg = svg.trim_start_matches(|c: char| c != '<');
            let svg = match svg.strip_prefix("<?xml") {
                Some(rest) => rest.split_once("?>").map_or(rest, |x| x.1),
                None => svg,
            };
            let _ = writeln!(
                h,
                "<figure>{}<figcaption>{}</figcaption></figure>",
                svg.trim(),
                escape(caption)
            );
        }
    }
    let _ = writeln!(h, "<h2>Top configurations</h2>\n<table><tr>");
    for c in TABLE_HEAD {
        let _ = write!(h, "<th>{}</th>", escape(c));
    }
    h.push_str("</tr>\n");
    let rec = r.recommended().map(|x| x.setting);
    for (k, row) in table_rows(r).into_iter().enumerate() {
        let is_rec = r
            .ranked()
            .get(k)
            .map(|&i| Some(r.rows[i].setting) == rec)
            .unwrap_or(false);
        let _ = write!(h, "<tr{}>", if is_rec { " class=\"rec\"" } else { "" });
        for (j, cell) in row.iter().enumerate() {
            let class = if j == 3 { " class=\"l\"" } else { "" };
            let _ = write!(h, "<td{class}>{}</td>", escape(cell));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n<h2>Reproduce</h2>\n");
    let _ = writeln!(h, "<pre>{}</pre>", escape(&r.command));
    let _ = writeln!(
        h,
        "<p>Generated by csm-lab {}. Every row of <code>sweep.csv</code> equals what <code>csm-lab analyze</code> \
         reports for that setting.</p></body></html>",
        env!("CARGO_PKG_VERSION")
    );
    h.into_bytes()
}

/// `report.md`: the same content for pasting into a review document.
pub fn report_md(r: &SweepResult, figures: &[(&str, &str, Vec<u8>)]) -> Vec<u8> {
    let mut m = String::new();
    let _ = writeln!(m, "# Cascaded shadow map sweep: {}\n", r.config.name);
    let _ = writeln!(
        m,
        "{} configurations: {} λ values × {} cascade counts × {} resolutions × {} fits, each analysed in full.\n",
        r.rows.len(),
        r.grid.lambda.values.len(),
        r.grid.cascades.values.len(),
        r.grid.resolution.values.len(),
        r.grid.fit.values.len()
    );
    m.push_str("## Scene\n\n| | |\n|---|---|\n");
    for (k, v) in scene_facts(&r.config, &r.rows) {
        let _ = writeln!(m, "| {k} | {v} |");
    }
    let _ = writeln!(
        m,
        "\n## Recommendation\n\n{}\n\n*Objective:* {}.\n",
        why_text(r),
        sweep::OBJECTIVE
    );
    if !figures.is_empty() {
        m.push_str("## Plots\n\n");
        for (stem, caption, _) in figures {
            let _ = writeln!(m, "![{caption}]({stem}.svg)\n\n*{caption}* ([PNG]({stem}.png))\n");
        }
    }
    m.push_str("## Top configurations\n\n|");
    for c in TABLE_HEAD {
        let _ = write!(m, " {c} |");
    }
    m.push_str("\n|");
    for _ in TABLE_HEAD {
        m.push_str("---:|");
    }
    m.push('\n');
    for row in table_rows(r) {
        m.push('|');
        for cell in row {
            let _ = write!(m, " {cell} |");
        }
        m.push('\n');
    }
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
    for (stem, _, svg) in &figures {
        files.push((format!("{stem}.svg"), svg.clone()));
        files.push((format!("{stem}.png"), svg_to_png(svg, 2.0)?));
    }
    files.push(("report.html".to_string(), report_html(r, &figures)));
    files.push(("report.md".to_string(), report_md(r, &figures)));
    Ok(files)
}

/// The short table printed on stdout.
pub fn stdout_table(r: &SweepResult) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {} configurations ({} λ × {} cascade counts × {} resolutions × {} fits)",
        r.config.name,
        r.rows.len(),
        r.grid.lambda.values.len(),
        r.grid.cascades.values.len(),
        r.grid.resolution.values.len(),
        r.grid.fit.values.len()
    );
    if r.front.is_empty() {
        let _ = writeln!(
            out,
            "no cascades needed: the scene is not visible within the shadow distance"
        );
        return out;
    }
    let _ = writeln!(out, "Pareto front (memory against mean aliasing):");
    let _ = writeln!(
        out,
        "  {:>9} {:>8} {:>6} {:>6} {:>6} {:>10} {:>10} {:>10}",
        "MiB", "cascades", "res", "λ", "fit", "mean", "max", "shimmer"
    );
    let rec = r.recommendation.as_ref().map(|x| x.index);
    for &i in &r.front {
        let x = &r.rows[i];
        let s = &x.summary;
        let _ = writeln!(
            out,
            "{} {:>9} {:>8} {:>6} {:>6} {:>6} {:>10.4} {:>10.4} {:>10.2e}",
            if Some(i) == rec { "*" } else { " " },
            mib(s.memory_bytes),
            x.setting.cascades,
            x.setting.resolution,
            x.setting.lambda,
            x.setting.fit.name(),
            s.mean_aliasing,
            s.max_aliasing,
            s.shimmer_snapped
        );
    }
    let _ = writeln!(out, "recommended (budget {} MiB): {}", r.budget_mib, why_text(r));
    out
}
