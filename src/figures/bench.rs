//! The figure `bench` writes: error against run time, log-log, one line per sampled metric.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    draw_legend_below, house_mesh, legend_frame, legend_height, log_axis, log_range, series_color, Figure, Legend,
    PlotResult, LEGEND_FONT,
};
use crate::commands::bench::{BenchReport, BenchRow, TARGET_ERROR};
use crate::error::Result;
use crate::output::Exporter;

/// `bench.svg`: error against time, log-log, one line per metric.
pub(crate) struct BenchSvg;

impl Exporter<BenchReport> for BenchSvg {
    fn file_name(&self) -> &'static str {
        "bench.svg"
    }

    fn render(&self, report: &BenchReport) -> Result<Vec<u8>> {
        BenchFigure(report).to_svg()
    }
}

/// The chart behind `bench.svg`.
pub(crate) struct BenchFigure<'a>(pub &'a BenchReport);

impl Figure for BenchFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1040, 600 + legend_height(self.0.metrics.len() + 1, LEGEND_FONT))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let report = self.0;
        // Exact (zero-error) points have no place on a log axis: they are left out.
        let plotted = |r: &&BenchRow| r.error > 0.0 && r.seconds > 0.0;
        let pts: Vec<&BenchRow> = report.rows.iter().filter(plotted).collect();
        let (tmin, tmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
            (lo.min(r.seconds), hi.max(r.seconds))
        });
        let (emin, emax) = pts.iter().fold((TARGET_ERROR, TARGET_ERROR), |(lo, hi), r| {
            (lo.min(r.error), hi.max(r.error))
        });
        let (x0, x1) = if pts.is_empty() {
            (1e-7, 1.0)
        } else {
            log_range(tmin, tmax)
        };
        let (y0, y1) = log_range(emin, emax);
        let title = format!("Accuracy against run time of the sampled metrics: {}", report.scene);
        let lines = report.metrics.len() + 1;
        let mut chart = legend_frame(root, &title, 22, 80, lines, LEGEND_FONT)
            .build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1))?;
        house_mesh(
            &mut chart,
            "time per evaluation (seconds, log; best of repeated runs)",
            "relative error (log)",
        )
        .draw()?;
        let target = BLACK.stroke_width(2);
        chart.draw_series(DashedLineSeries::new(
            vec![(x0, TARGET_ERROR), (x1, TARGET_ERROR)],
            8,
            5,
            target,
        ))?;
        legend.add(format!("target: relative error {TARGET_ERROR:.0e}"), move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 18, y)], target)
        });
        for (i, m) in report.metrics.iter().enumerate() {
            let color = series_color(i);
            let line: Vec<(f64, f64)> = report
                .rows_of(m.name)
                .filter(|r| plotted(r))
                .map(|r| (r.seconds, r.error))
                .collect();
            chart.draw_series(line.iter().map(|p| Circle::new(*p, 3, color.filled())))?;
            chart.draw_series(LineSeries::new(line, color.stroke_width(2)))?;
            legend.add(format!("{} ({})", m.name, m.unit), move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        }
        draw_legend_below(root, legend, lines)?;
        Ok(())
    }
}
