//! The figures `analyze` writes: texel density against depth (`density.svg`), shimmer per
//! frame (`shimmer.svg`) and the cascades seen from the light (`cascades.svg`).

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    draw_legend_below, draw_message, house_mesh, legend_frame, legend_height, linear_axis, palette, series_color,
    size_with_legend, texels_per_pixel_chart, Figure, Legend, PlotResult, FONT, LEGEND_FONT,
};
use crate::analysis::Analysis;
use crate::error::Result;
use crate::output::Exporter;
use csm_core::cascades::{bounds_2d, LightPose};

/// Texels per pixel against view depth, log-log, with split lines and the ideal 1.
pub(crate) struct DensityFigure<'a>(pub &'a Analysis);

impl DensityFigure<'_> {
    /// Legend entries: the ideal line, the split depths (with two or more cascades), a cascade each.
    fn legend_lines(&self) -> usize {
        let m = self.0.cascades.len();
        super::depth_chart_legend_lines(super::visible_depths(&self.0.summary)) + usize::from(m > 1) + m
    }
}

impl Figure for DensityFigure<'_> {
    fn size(&self) -> (u32, u32) {
        size_with_legend(self.legend_lines())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let a = self.0;
        let title = format!("Shadow texels per screen pixel vs depth: {}", a.config.name);
        let Some(rig) = a.rig() else {
            return draw_message(
                root,
                &title,
                "No cascades needed: the scene is not visible within the shadow distance.",
            );
        };
        let (mut chart, (y0, y1)) = texels_per_pixel_chart(
            root,
            &title,
            22,
            (a.summary.z_lo, a.summary.z_hi),
            a.density.iter().map(|d| d.texels_per_pixel),
            self.legend_lines(),
            &mut legend,
            super::visible_depths(&a.summary),
        )?;
        for (i, s) in rig.splits[1..rig.splits.len() - 1].iter().enumerate() {
            let style = palette::SPLIT.stroke_width(1);
            chart.draw_series(DashedLineSeries::new(vec![(*s, y0), (*s, y1)], 5, 4, style))?;
            if i == 0 {
                legend.add("split depths", move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], style)
                });
            }
        }
        for (i, c) in a.cascades.iter().enumerate() {
            let color = series_color(i);
            let pts: Vec<(f64, f64)> = a
                .density
                .iter()
                .filter(|d| d.cascade == i)
                .map(|d| (d.depth, d.texels_per_pixel))
                .collect();
            chart.draw_series(LineSeries::new(pts, color.stroke_width(3)))?;
            legend.add(
                format!("cascade {i}: {:.3}..{:.3}, texel {:.4}", c.near, c.far, c.texel_size),
                move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3)),
            );
        }
        draw_legend_below(root, legend, self.legend_lines())?;
        Ok(())
    }
}

/// Per-frame RMS phase drift over all cascades, snapped vs unsnapped.
pub(crate) struct ShimmerFigure<'a>(pub &'a Analysis);

impl Figure for ShimmerFigure<'_> {
    fn size(&self) -> (u32, u32) {
        size_with_legend(2)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let a = self.0;
        let title = format!(
            "Sub-texel drift per frame ({} path, {} fit): {}",
            a.config.motion.path.name(),
            a.config.shadow.fit,
            a.config.name
        );
        let (Some(sn), Some(un)) = (a.snapped(), a.unsnapped()) else {
            return draw_message(root, &title, "No cascades needed: nothing can shimmer.");
        };
        let frames = a.config.motion.frames;
        let per_frame = |p: &csm_core::shimmer::PathResult| -> Vec<(f64, f64)> {
            let m = a.cascades.len().max(1);
            // Long paths keep every stride-th frame's rows (see `frame_row_stride`).
            let stride = csm_core::shimmer::frame_row_stride(frames);
            let mut acc = vec![0.0; frames / stride + 1];
            for f in &p.frames {
                acc[f.frame / stride] += f.phase_drift_rms * f.phase_drift_rms / m as f64;
            }
            (1..frames)
                .filter(|t| t % stride == 0)
                .map(|t| (t as f64, acc[t / stride].sqrt()))
                .collect()
        };
        let s_pts = per_frame(sn);
        let u_pts = per_frame(un);
        let ymax = u_pts.iter().chain(&s_pts).map(|p| p.1).fold(0.0f64, f64::max).max(0.05) * 1.15;
        let mut chart = legend_frame(root, &title, 22, 70, 2, LEGEND_FONT)
            .build_cartesian_2d(linear_axis(0.0, (frames.max(2) - 1) as f64), linear_axis(0.0, ymax))?;
        house_mesh(&mut chart, "frame", "RMS phase drift over cascades (texels)").draw()?;
        let red = series_color(1);
        let blue = series_color(0);
        chart.draw_series(LineSeries::new(u_pts, red.stroke_width(2)))?;
        legend.add(format!("unsnapped (RMS {:.3e} texels)", un.stats.rms), move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 18, y)], red.stroke_width(2))
        });
        chart.draw_series(LineSeries::new(s_pts, blue.stroke_width(4)))?;
        legend.add(format!("snapped (RMS {:.3e} texels)", sn.stats.rms), move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 18, y)], blue.stroke_width(4))
        });
        draw_legend_below(root, legend, 2)?;
        Ok(())
    }
}

/// Andrew's monotone chain convex hull, counter-clockwise.
pub(crate) fn convex_hull(mut pts: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0 {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Top-down view from the light: each slice's footprint and its window (frame 0).
pub(crate) struct CascadesFigure<'a>(pub &'a Analysis);

impl Figure for CascadesFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let lines = self.0.cascades.len() + 1;
        (860, 760 + legend_height(lines, LEGEND_FONT))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let a = self.0;
        let title = format!("Slices and windows seen from the light: {}", a.config.name);
        let Some(rig) = a.rig() else {
            return draw_message(root, &title, "No cascades needed.");
        };
        let pose = a.config.camera.pose();
        let lp = LightPose::new(&rig.light, &pose);
        let mut all = Vec::new();
        let mut items = Vec::new();
        for i in 0..rig.cascade_count() {
            let w = rig.window(i, &lp, a.config.shadow.snap);
            let s = &rig.slices[i];
            // Windows are in each cascade's own basis (the same for all but a few presets).
            let lpi = LightPose::new(&rig.basis(i, &lp), &pose);
            let corners = lpi.corners(&rig.lens, s.near, s.far);
            let lo = w.min();
            let hi = lo + glam::DVec2::new(w.width(), w.height());
            all.extend_from_slice(&corners);
            all.push(lo);
            all.push(hi);
            items.push((corners, lo, hi));
        }
        all.push(lp.position);
        let (lo, hi) = bounds_2d(&all);
        // Equal scales on both axes so shapes are not distorted.
        let c = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo).max_element() * 1.06;
        let lines = rig.cascade_count() + 1;
        let mut chart = legend_frame(root, &title, 20, 70, lines, LEGEND_FONT)
            .x_label_area_size(48)
            .build_cartesian_2d(linear_axis(c.x - half, c.x + half), linear_axis(c.y - half, c.y + half))?;
        house_mesh(&mut chart, "light-space x (world units)", "light-space y (world units)")
            .label_style((FONT, 12))
            .draw()?;
        for (i, (corners, wlo, whi)) in items.iter().enumerate().rev() {
            let color = series_color(i);
            let hull = convex_hull(corners.iter().map(|p| (p.x, p.y)).collect());
            chart.draw_series(std::iter::once(Polygon::new(hull.clone(), color.mix(0.25).filled())))?;
            let mut outline = hull.clone();
            outline.push(hull[0]);
            chart.draw_series(std::iter::once(PathElement::new(outline, color.stroke_width(1))))?;
            chart.draw_series(std::iter::once(Rectangle::new(
                [(wlo.x, wlo.y), (whi.x, whi.y)],
                color.stroke_width(2),
            )))?;
            legend.add(
                format!("cascade {i}: window {:.3} x {:.3}", whi.x - wlo.x, whi.y - wlo.y),
                move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], color.mix(0.5).filled()),
            );
        }
        chart.draw_series(std::iter::once(Circle::new(
            (lp.position.x, lp.position.y),
            5,
            BLACK.filled(),
        )))?;
        legend.add("camera", |(x, y)| Circle::new((x + 8, y), 4, BLACK.filled()));
        draw_legend_below(root, legend, lines)?;
        Ok(())
    }
}

pub(crate) struct DensitySvg;
pub(crate) struct ShimmerSvg;
pub(crate) struct CascadesSvg;

impl Exporter<Analysis> for DensitySvg {
    fn file_name(&self) -> &'static str {
        "density.svg"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        DensityFigure(a).to_svg()
    }
}

impl Exporter<Analysis> for ShimmerSvg {
    fn file_name(&self) -> &'static str {
        "shimmer.svg"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        ShimmerFigure(a).to_svg()
    }
}

impl Exporter<Analysis> for CascadesSvg {
    fn file_name(&self) -> &'static str {
        "cascades.svg"
    }
    fn render(&self, a: &Analysis) -> Result<Vec<u8>> {
        CascadesFigure(a).to_svg()
    }
}
