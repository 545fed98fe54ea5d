//! The figures `compare` writes: texels per pixel against depth with one line per preset
//! (`compare_density`), and shimmer and coverage bars per preset (`compare_shimmer`).

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{
    draw_legend_below, draw_message, linear_axis, log_range, palette, preset_color, series_color, short,
    size_with_legend, texels_per_pixel_chart, tick, Figure, Legend, PlotResult, FONT,
};
use crate::analysis::Analysis;
use crate::commands::compare::{coverage_extremes, invalid_reason, label, Comparison};
use crate::error::Result;
use crate::output::Exporter;

/// Texels per pixel against view depth, log-log, one line per preset.
pub(crate) struct DensityOverlay<'a>(pub &'a Comparison);

impl DensityOverlay<'_> {
    /// Legend entries: the ideal line and one per preset with cascades.
    fn legend_lines(&self) -> usize {
        super::depth_chart_legend_lines(self.visible())
            + self.0.analyses.iter().filter(|a| !a.density.is_empty()).count()
    }

    /// The depths of the visible geometry over every entry (the same camera and scene; each
    /// clips them to its own split range): from the nearest to the farthest.
    fn visible(&self) -> Option<(f64, f64)> {
        self.0
            .analyses
            .iter()
            .filter_map(|a| super::visible_depths(&a.summary))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }
}

impl Figure for DensityOverlay<'_> {
    fn size(&self) -> (u32, u32) {
        size_with_legend(self.legend_lines())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
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
            self.legend_lines(),
            &mut legend,
            self.visible(),
        )?;
        for (i, a) in c.analyses.iter().enumerate() {
            if a.density.is_empty() {
                continue;
            }
            let color = preset_color(i);
            // Samples are sorted by depth with both sides of every split: the line shows the
            // sawtooth's jumps as vertical segments.
            let pts: Vec<(f64, f64)> = a.density.iter().map(|d| (d.depth, d.texels_per_pixel)).collect();
            // An invalid preset is drawn dashed and thin, and says why in the legend.
            let invalid = invalid_reason(a);
            let style = color.stroke_width(if invalid.is_some() { 2 } else { 3 });
            // The worst case: on screen with geometry, else the bounds' max aliasing.
            let worst = crate::metric::worst_aliasing(a.summary.screen.is_some());
            let label = format!(
                "{}: {} x {}, {} {}{}",
                label(a),
                a.rig().map_or(0, |r| r.cascade_count()),
                a.config.shadow.resolution,
                crate::metric::worst_words(worst).0,
                short(worst.value(&a.summary)),
                invalid
                    .as_ref()
                    .map_or(String::new(), |r| format!(" - INVALID: {r} (dashed)"))
            );
            if invalid.is_some() {
                chart.draw_series(DashedLineSeries::new(pts, 7, 5, style))?;
            } else {
                chart.draw_series(LineSeries::new(pts, style))?;
            }
            let swatch = if invalid.is_some() { 9 } else { 18 };
            legend.add(label, move |(x, y)| {
                PathElement::new(vec![(x, y), (x + swatch, y)], style)
            });
        }
        draw_legend_below(root, legend, self.legend_lines())?;
        Ok(())
    }
}

/// Horizontal bars: shimmer snapped/unsnapped per preset, and coverage per preset.
pub(crate) struct ShimmerCoverageBars<'a>(pub &'a Comparison);

impl ShimmerCoverageBars<'_> {
    fn names(&self) -> Vec<String> {
        self.0
            .analyses
            .iter()
            .map(|a| {
                let name = label(a);
                if invalid_reason(a).is_some() {
                    format!("{name} (INVALID)")
                } else {
                    name
                }
            })
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
        let (left, right) = root.split_horizontally(740);

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
            .y_label_area_size(250)
            .build_cartesian_2d(linear_axis(0.0, xmax), rows_axis(rows).into_segmented())?;
        chart
            .configure_mesh()
            .x_label_formatter(&|v| tick(*v))
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
            * 2.8;
        let mut chart = ChartBuilder::on(&right)
            .margin(12)
            .x_label_area_size(46)
            .y_label_area_size(190)
            .build_cartesian_2d(linear_axis(0.0, cmax), rows_axis(n).into_segmented())?;
        chart
            .configure_mesh()
            .x_label_formatter(&|v| tick(*v))
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
                palette::MISS.filled(),
            );
            bar.set_margin(6, 6, 0, 0);
            chart.draw_series(std::iter::once(bar))?;
            let text = if v == 0.0 {
                "0".to_string()
            } else {
                format!("{} (worst {} texels): INVALID", v as u64, short(worst))
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
