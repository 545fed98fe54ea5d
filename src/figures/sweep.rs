//! The figures `sweep` writes: aliasing heatmaps over λ × cascade count, texel density for
//! several λ, shimmer of every configuration, and the Pareto front of memory against aliasing.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    chart_frame, colormap, draw_legend, draw_message, log_range, palette, series_color, texels_per_pixel_chart, Figure,
    PlotResult, FONT,
};
use crate::analysis::{analyze, mib, Analysis, AnalysisOptions};
use crate::config::Fit;
use crate::metric::SummaryMetric;
use crate::sweep::{self, Row, Setting, SweepResult};

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
    fn rows_of_panels(&self) -> Vec<(Fit, SummaryMetric)> {
        let mut v = Vec::new();
        for fit in sweep::fits_in(&self.0.rows) {
            v.push((fit, SummaryMetric::named("max_aliasing")));
            v.push((fit, SummaryMetric::named("mean_aliasing")));
        }
        v
    }
}

fn metric_of(row: &Row, metric: &SummaryMetric) -> f64 {
    metric.value(&row.summary)
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
                    .caption(
                        format!("{} · {res}² · {fit}", metric.name().replace('_', " ")),
                        (FONT, 15),
                    )
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
                        palette::NO_DATA
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
                            palette::MARKED.stroke_width(3),
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
            return draw_message(root, "Texels per pixel vs depth", "No recommendation: nothing to plot.");
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
        let mut chart =
            chart_frame(root, &title, 20, 70).build_cartesian_2d(-0.5..(n as f64 - 0.5).max(0.5), 0.0..ymax)?;
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
                    palette::SEPARATOR.stroke_width(1),
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

/// Pareto front of memory against the sweep's objective (mean aliasing without geometry).
pub struct ParetoFigure<'a>(pub &'a SweepResult);

impl Figure for ParetoFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.0;
        let obj = r.objective;
        let bounds_only = obj.name() == "mean_aliasing";
        let title = if bounds_only {
            format!("Memory against mean aliasing: {}", r.config.name)
        } else {
            format!("Memory against {}: {}", obj.name(), r.config.name)
        };
        let pts: Vec<(f64, f64)> = r
            .rows
            .iter()
            .filter(|x| x.summary.cascades_needed)
            .map(|x| (mib(x.summary.memory_bytes), obj.value(&x.summary)))
            .collect();
        if pts.is_empty() {
            return draw_message(root, &title, "No cascades needed for any configuration.");
        }
        let (xmin, xmax) = pts
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
        let (ymin, ymax) = pts
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.1), b.max(p.1)));
        let (x0, x1) = log_range(xmin.min(r.budget_mib), xmax.max(r.budget_mib));
        let (y0, y1) = log_range(ymin, ymax);
        let mut chart =
            chart_frame(root, &title, 22, 70).build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("shadow map memory (MiB, log; cascades × resolution² × 4 bytes)")
            .y_desc(if bounds_only {
                "mean aliasing (texel/pixel, log; lower is better)".to_string()
            } else {
                format!("{} (log; lower is better)", obj.name())
            })
            .max_light_lines(3)
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .draw()?;
        let grey = palette::POINT;
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 3, grey.filled())))?
            .label("configuration")
            .legend(move |(x, y)| Circle::new((x + 8, y), 3, grey.filled()));
        let budget = palette::LIMIT.stroke_width(2);
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
            .map(|&i| (mib(r.rows[i].summary.memory_bytes), obj.value(&r.rows[i].summary)))
            .collect();
        chart
            .draw_series(LineSeries::new(front.clone(), orange.stroke_width(3)))?
            .label("Pareto front (nothing is both cheaper and sharper)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], orange.stroke_width(3)));
        chart.draw_series(front.iter().map(|p| Circle::new(*p, 5, orange.filled())))?;
        if let Some(rec) = r.recommended() {
            let p = (mib(rec.summary.memory_bytes), obj.value(&rec.summary));
            let red = palette::RECOMMENDED;
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
