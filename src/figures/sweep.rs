//! The figures `sweep` writes: aliasing heatmaps over λ × cascade count, texel density for
//! several λ, shimmer of every configuration, and the Pareto front of memory against aliasing.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{
    colormap, draw_legend_below, draw_message, house_mesh, legend_frame, legend_height, linear_axis, log_axis,
    log_axis_with, log_range, nice_ticks, palette, series_color, size_with_legend, texels_per_pixel_chart, tick,
    ticked_axis, DrawError, Figure, Legend, LogAxis, PlotResult, FONT, LEGEND_FONT,
};
use crate::analysis::{analyze, mib, Analysis, AnalysisOptions};
use crate::commands::sweep::grid::Setting;
use crate::commands::sweep::rank::STABLE_SHIMMER;
use crate::commands::sweep::run::Row;
use crate::commands::sweep::SweepResult;
use crate::metric::SummaryMetric;
use plotters::coord::cartesian::Cartesian2d;

/// The configuration the figures single out: the recommended one, or when nothing qualifies the
/// one that comes closest (false), or None when no configuration needs cascades.
pub(crate) fn focus(r: &SweepResult) -> Option<(&Row, bool)> {
    match r.recommended() {
        Some(x) => Some((x, true)),
        None => r.no_recommendation.closest.map(|i| (&r.rows[i], false)),
    }
}

/// "recommended" or "closest (nothing qualifies)".
fn focus_word(recommended: bool) -> &'static str {
    if recommended {
        "recommended"
    } else {
        "closest (nothing qualifies)"
    }
}

/// A setting in the sweep's own knobs: an engine preset has no λ or fit to print.
pub(crate) fn setting_words(r: &SweepResult, s: &Setting) -> String {
    if r.config.shadow.preset.is_some() {
        let mut out = format!("{} × {}²", s.cascades, s.resolution);
        if let (Some(k), Some(v)) = (crate::presets::axes(&r.config).knob, s.knob) {
            out.push_str(&format!(", {} {}", k.term, tick(v)));
        }
        if let Some(d) = s.distance {
            out.push_str(&format!(", distance {}", tick(d)));
        }
        out
    } else {
        format!(
            "{} × {}², λ {} ({})",
            s.cascades,
            s.resolution,
            tick(s.lambda),
            s.fit_group()
        )
    }
}

/// The most λ columns a heat-map panel draws; a longer λ axis is binned (each column shows the
/// lowest value among adjacent λ), which keeps the SVG bounded at any grid size.
pub(crate) const MAX_HEAT_COLUMNS: usize = 48;

/// The most resolutions a heat map draws panels for (its panel columns when λ is the x axis).
/// A longer resolution axis shows the resolution of the figures' focus (the recommendation, or
/// the closest row) and an even spread of the others, and says so in the figure's note; every
/// row stays in `sweep.csv`. This bounds the figure's size, and so its memory, at any grid size.
pub(crate) const MAX_HEAT_RESOLUTIONS: usize = 6;

/// The resolutions a heat map draws: all of `resolutions` when there are at most `most`;
/// otherwise `most` of them in grid order: `focus` (when given) and an even spread over the
/// axis (its first and last included), the spread's pick nearest `focus` replaced by it.
pub(crate) fn shown_resolutions(resolutions: &[u32], focus: Option<u32>, most: usize) -> Vec<u32> {
    let n = resolutions.len();
    if n <= most {
        return resolutions.to_vec();
    }
    assert!(most >= 2, "a spread needs its two ends");
    let mut picks: Vec<usize> = (0..most).map(|i| (i * (n - 1) + (most - 1) / 2) / (most - 1)).collect();
    if let Some(f) = focus.and_then(|f| resolutions.iter().position(|&r| r == f)) {
        if !picks.contains(&f) {
            let nearest = (0..most).min_by_key(|&k| picks[k].abs_diff(f)).expect("most >= 2");
            picks[nearest] = f;
            picks.sort_unstable();
        }
    }
    picks.into_iter().map(|i| resolutions[i]).collect()
}

/// Aliasing over λ × cascade count, one panel per metric, resolution and fit (or over resolution ×
/// cascade count when the grid has one λ, as for engine presets). Each panel has its own colour
/// scale, so the effect of λ shows within every resolution.
pub(crate) struct HeatmapFigure<'a>(pub &'a SweepResult);

/// One heat-map panel: labelled columns × rows of cells.
pub(crate) struct HeatPanel {
    pub caption: String,
    pub x_desc: String,
    /// What the rows are ("cascades").
    pub y_desc: String,
    /// Columns.
    pub nx: usize,
    /// Labelled columns: (column, label).
    pub x_ticks: Vec<(usize, String)>,
    pub y_labels: Vec<String>,
    /// (column, row, value, within the memory budget); value None: no cascades needed.
    pub cells: Vec<(usize, usize, Option<f64>, bool)>,
    /// The recommended cell, when it is in this panel.
    pub marked: Option<(usize, usize)>,
    pub unit: String,
}

/// The heat-map rows of panels: the objective when it is not mean aliasing, then the mean and
/// the worst case ([`SweepResult::worst`]: on screen with geometry, else the bounds' max).
fn heat_metrics(r: &SweepResult) -> Vec<SummaryMetric> {
    let mut v = Vec::new();
    if r.objective.name() != "mean_aliasing" {
        v.push(r.objective);
    }
    v.push(SummaryMetric::named("mean_aliasing"));
    // The worst case: on screen with geometry, else the bounds' max aliasing.
    v.push(r.worst);
    v
}

impl HeatmapFigure<'_> {
    /// True when λ (or, for a preset without λ, its swept split knob) is an axis of the grid;
    /// otherwise resolution is the panels' x axis.
    fn lambda_axis(&self) -> bool {
        self.x_values().len() > 1
    }

    /// The swept engine knob's name, when it is the x axis (λ has one value).
    fn knob_x(&self) -> Option<&'static str> {
        let g = &self.0.grid;
        if g.lambda.values.len() > 1 || g.knob.as_ref().is_none_or(|k| k.values.len() < 2) {
            return None;
        }
        crate::presets::axes(&self.0.config).knob.map(|k| k.term)
    }

    /// The x axis values: λ, or the engine knob's (see [`Self::knob_x`]).
    fn x_values(&self) -> &[f64] {
        match (self.knob_x(), &self.0.grid.knob) {
            (Some(_), Some(k)) => &k.values,
            _ => &self.0.grid.lambda.values,
        }
    }

    /// λ columns: the grid's λ values in groups of at most [`MAX_HEAT_COLUMNS`] columns.
    fn lambda_bins(&self) -> (usize, usize) {
        let n = self.x_values().len().max(1);
        let per = n.div_ceil(MAX_HEAT_COLUMNS);
        (n.div_ceil(per), per)
    }

    /// The resolutions with panels ([`shown_resolutions`]; every one unless λ is the x axis
    /// and the grid has more than [`MAX_HEAT_RESOLUTIONS`]).
    fn resolutions(&self) -> Vec<u32> {
        let all = &self.0.grid.resolution.values;
        if !self.lambda_axis() {
            return all.clone();
        }
        shown_resolutions(all, focus(self.0).map(|x| x.0.setting.resolution), MAX_HEAT_RESOLUTIONS)
    }

    /// (panel columns, panel rows).
    fn layout(&self) -> (usize, usize) {
        let fits = self.0.fit_groups.len().max(1);
        let metrics = heat_metrics(self.0).len();
        if self.lambda_axis() {
            (self.resolutions().len().max(1), metrics * fits)
        } else {
            (metrics, fits)
        }
    }

    fn panels(&self) -> Vec<HeatPanel> {
        let r = self.0;
        let lambdas = self.x_values();
        let knob = self.knob_x();
        let x_of = |x: &Row| match knob {
            Some(_) => x.setting.knob.unwrap_or(f64::NAN),
            None => x.setting.lambda,
        };
        let counts = &r.grid.cascades.values;
        let resolutions = &self.resolutions();
        let rec = focus(r).map(|x| x.0.setting);
        let y_labels: Vec<String> = counts.iter().map(|c| c.to_string()).collect();
        let within = |x: &Row| mib(x.summary.memory_bytes) <= r.budget_mib;
        let mut out = Vec::new();
        let fits = &r.fit_groups;
        if self.lambda_axis() {
            let (cols, per) = self.lambda_bins();
            // Every few columns its λ; binned, round λ values at the column that holds them.
            let x_ticks: Vec<(usize, String)> = if per == 1 {
                (0..cols)
                    .step_by(cols.div_ceil(6).max(1))
                    .map(|c| (c, tick(lambdas[c])))
                    .collect()
            } else {
                let (first, last) = (lambdas[0], lambdas[lambdas.len() - 1]);
                nice_ticks(first.min(last), first.max(last), false)
                    .into_iter()
                    .filter_map(|t| {
                        let i = lambdas
                            .iter()
                            .position(|l| (*l - t).abs() <= 0.5 * (last - first).abs() / lambdas.len() as f64)?;
                        Some((i / per, tick(t)))
                    })
                    .collect()
            };
            for fit in fits {
                for metric in heat_metrics(r) {
                    for &res in resolutions {
                        let mut cells: Vec<(usize, usize, Option<f64>, bool)> = Vec::new();
                        let mut marked = None;
                        for row in r
                            .rows
                            .iter()
                            .filter(|x| x.setting.fit_group() == *fit && x.setting.resolution == res)
                        {
                            let (Some(i), Some(j)) = (
                                lambdas.iter().position(|l| *l == x_of(row)),
                                counts.iter().position(|c| *c == row.setting.cascades),
                            ) else {
                                continue;
                            };
                            let col = i / per;
                            let v = row.summary.cascades_needed.then(|| metric.value(&row.summary));
                            if Some(row.setting) == rec {
                                marked = Some((col, j));
                            }
                            // A binned column keeps the lowest value of its λ values.
                            match cells.iter_mut().find(|c| c.0 == col && c.1 == j) {
                                Some(c) => {
                                    c.2 = match (c.2, v) {
                                        (Some(p), Some(q)) => Some(p.min(q)),
                                        (p, q) => p.or(q),
                                    };
                                    c.3 |= within(row);
                                }
                                None => cells.push((col, j, v, within(row))),
                            }
                        }
                        out.push(HeatPanel {
                            caption: format!("{} · {res}² · {fit}", metric.name().replace('_', " ")),
                            x_desc: match (knob, per) {
                                (Some(term), _) => term.to_string(),
                                (None, 1) => "λ (0 uniform → 1 log)".to_string(),
                                (None, _) => format!("λ (0 uniform → 1 log); a column: the lowest of {per} λ"),
                            },
                            nx: cols,
                            y_desc: "cascades".to_string(),
                            x_ticks: x_ticks.clone(),
                            y_labels: y_labels.clone(),
                            cells,
                            marked,
                            unit: metric_unit(&metric),
                        });
                    }
                }
            }
        } else {
            let x_ticks: Vec<(usize, String)> = resolutions
                .iter()
                .enumerate()
                .map(|(i, r)| (i, r.to_string()))
                .collect();
            for fit in fits {
                for metric in heat_metrics(r) {
                    let mut cells = Vec::new();
                    let mut marked = None;
                    for row in r.rows.iter().filter(|x| x.setting.fit_group() == *fit) {
                        let (Some(i), Some(j)) = (
                            resolutions.iter().position(|l| *l == row.setting.resolution),
                            counts.iter().position(|c| *c == row.setting.cascades),
                        ) else {
                            continue;
                        };
                        if Some(row.setting) == rec {
                            marked = Some((i, j));
                        }
                        let v = row.summary.cascades_needed.then(|| metric.value(&row.summary));
                        cells.push((i, j, v, within(row)));
                    }
                    let caption = if r.config.shadow.preset.is_some() {
                        format!("{} · the preset's own splits", metric.name().replace('_', " "))
                    } else {
                        format!("{} · λ {} · {fit}", metric.name().replace('_', " "), tick(lambdas[0]))
                    };
                    out.push(HeatPanel {
                        caption,
                        x_desc: "resolution (texels per side)".to_string(),
                        nx: resolutions.len(),
                        y_desc: "cascades".to_string(),
                        x_ticks: x_ticks.clone(),
                        y_labels: y_labels.clone(),
                        cells,
                        marked,
                        unit: metric_unit(&metric),
                    });
                }
            }
        }
        out
    }
}

/// The colour bar's title: the metric's unit (the panel's caption names the metric).
pub(crate) fn metric_unit(m: &SummaryMetric) -> String {
    if m.name().contains("aliasing") {
        "texel/pixel, log".to_string()
    } else {
        "log scale".to_string()
    }
}

impl Figure for HeatmapFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let (cols, rows) = self.layout();
        (40 + 400 * cols as u32, 110 + 300 * rows as u32)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.0;
        let title = format!(
            "Aliasing over {} × cascades: {}",
            match (self.lambda_axis(), self.knob_x()) {
                (true, Some(term)) => term,
                (true, None) => "λ",
                (false, _) => "resolution",
            },
            r.config.name
        );
        // Drawn wider than a page, the text is drawn larger so that it reads at the page's width.
        let k = super::legible_scale(root.dim_in_pixel().0);
        let root = root.titled(&title, (FONT, super::scaled(22, k)))?;
        let (w, _) = root.dim_in_pixel();
        let (note_area, grid_area) = root.split_vertically(super::scaled(40, k));
        let rec = match focus(r) {
            Some((x, ok)) => format!("Red ring: {} ({})", focus_word(ok), setting_words(r, &x.setting)),
            None => "No configuration needs cascades: nothing is marked".to_string(),
        };
        let mut note = format!(
            "Lower is better; each panel has its own colour scale. {rec}. White line: {} MiB memory budget (cells above or right of it exceed it). Grey: no cascades needed.",
            tick(r.budget_mib)
        );
        let (shown, all) = (self.resolutions().len(), r.grid.resolution.values.len());
        if shown < all {
            note.push_str(&format!(
                " Panels for {shown} of the {all} resolutions ({} and an even spread; sweep.csv has every row).",
                match focus(r) {
                    Some((x, _)) => format!("the red ring's {}²", x.setting.resolution),
                    None => "the first and last".to_string(),
                }
            ));
        }
        let font = if note.len() as f64 * 7.0 * k > f64::from(w) {
            12
        } else {
            13
        };
        note_area.draw(&Text::new(note, (14, 8), (FONT, super::scaled(font, k)).into_font()))?;
        let panels = self.panels();
        if panels.is_empty() || panels.iter().all(|p| p.cells.is_empty()) {
            return draw_message(&grid_area, "", "No configuration to draw: the sweep has no rows.");
        }
        let (cols, rows) = self.layout();
        let areas = grid_area.split_evenly((rows, cols));
        for (area, panel) in areas.iter().zip(&panels) {
            draw_heat_panel(area, panel, k)?;
        }
        Ok(())
    }
}

/// Draws one heat-map panel with its own log colour bar (titled with the unit), the budget line
/// and the recommendation ring. Cells overlap their neighbours by a pixel, so no seam shows
/// when a browser scales the SVG. Text and the label areas are `k` times their nominal size
/// ([`super::legible_scale`] of the whole figure's width).
pub(crate) fn draw_heat_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &HeatPanel, k: f64) -> PlotResult {
    let s = |v: u32| super::scaled(v, k);
    let (w, _) = area.dim_in_pixel();
    let (cells_area, bar_area) = area.split_horizontally(w.saturating_sub(s(100)));
    let values: Vec<f64> = p
        .cells
        .iter()
        .filter_map(|c| c.2)
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    let lo = values.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = values.iter().cloned().fold(0.0, f64::max);
    let (lo, hi) = if !lo.is_finite() {
        (1.0, 10.0)
    } else if hi <= lo * 1.001 {
        (lo / 1.05, lo * 1.05)
    } else {
        (lo, hi)
    };
    let t_of = |v: f64| (v.ln() - lo.ln()) / (hi.ln() - lo.ln());
    let (nx, ny) = (p.nx.max(1), p.y_labels.len().max(1));
    let mut chart = ChartBuilder::on(&cells_area)
        .caption(&p.caption, (FONT, s(13)))
        .margin(6)
        .x_label_area_size(s(38))
        .y_label_area_size(s(42))
        .build_cartesian_2d(
            ticked_axis(0.0, nx as f64, p.x_ticks.iter().map(|t| t.0 as f64 + 0.5).collect()),
            ticked_axis(0.0, ny as f64, (0..ny).map(|j| j as f64 + 0.5).collect()),
        )?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(p.x_desc.as_str())
        .y_desc(p.y_desc.as_str())
        .axis_desc_style((FONT, s(12)))
        .label_style((FONT, s(12)))
        .x_label_formatter(&|v| {
            let c = v.floor() as usize;
            p.x_ticks
                .iter()
                .find(|t| t.0 == c)
                .map(|t| t.1.clone())
                .unwrap_or_default()
        })
        .y_label_formatter(&|v| p.y_labels.get(v.floor() as usize).cloned().unwrap_or_default())
        .draw()?;
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    // One pixel in data units: cells reach a pixel into their right and upper neighbours.
    let (ox, oy) = (nx as f64 / pw.max(1) as f64, ny as f64 / ph.max(1) as f64);
    super::rects::draw_filled(
        &chart,
        p.cells.iter().map(|&(i, j, v, _)| {
            let color = match v {
                Some(v) => colormap(t_of(v)),
                None => palette::NO_DATA,
            };
            let x1 = if i + 1 < nx { i as f64 + 1.0 + ox } else { nx as f64 };
            let y1 = if j + 1 < ny { j as f64 + 1.0 + oy } else { ny as f64 };
            ((i as f64, j as f64), (x1, y1), color)
        }),
    )?;
    // The budget line: the edges between a cell within the budget and its neighbour above or to
    // the right that exceeds it.
    let within = |i: usize, j: usize| p.cells.iter().find(|c| c.0 == i && c.1 == j).map(|c| c.3);
    let mut edges = Vec::new();
    for &(i, j, _, ok) in &p.cells {
        if !ok {
            continue;
        }
        if within(i, j + 1) == Some(false) {
            edges.push(vec![(i as f64, (j + 1) as f64), ((i + 1) as f64, (j + 1) as f64)]);
        }
        if within(i + 1, j) == Some(false) {
            edges.push(vec![((i + 1) as f64, j as f64), ((i + 1) as f64, (j + 1) as f64)]);
        }
    }
    chart.draw_series(edges.into_iter().map(|e| PathElement::new(e, WHITE.stroke_width(3))))?;
    if let Some((i, j)) = p.marked {
        let c = (i as f64 + 0.5, j as f64 + 0.5);
        chart.draw_series(std::iter::once(Circle::new(c, 8, WHITE.stroke_width(5))))?;
        chart.draw_series(std::iter::once(Circle::new(c, 8, palette::MARKED.stroke_width(3))))?;
    }
    // The colour bar, titled with the metric and unit. Counts (every value whole) get whole
    // ticks only: a bar of "1.02 settings" says nothing.
    let mut ticks = nice_ticks(lo, hi, true);
    if values.iter().all(|v| v.fract() == 0.0) {
        ticks.retain(|t| t.fract() == 0.0);
        for v in [lo.ceil(), hi.floor()] {
            if v >= lo && v <= hi && !ticks.contains(&v) {
                ticks.push(v);
            }
        }
        ticks.sort_by(f64::total_cmp);
    }
    // Tick labels and the title sit right of the bar, clear of the cells and of the bar itself.
    let mut bar = ChartBuilder::on(&bar_area)
        .caption(&p.unit, (FONT, s(12)))
        .margin_top(8)
        .margin_bottom(s(44))
        .margin_left(6)
        .set_label_area_size(LabelAreaPosition::Right, s(44))
        .build_cartesian_2d(0.0..1.0, log_axis_with(lo, hi, ticks))?;
    bar.configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .disable_y_mesh()
        .label_style((FONT, s(12)))
        .y_label_formatter(&|v| tick(*v))
        .draw()?;
    let steps = 40;
    super::rects::draw_filled(
        &bar,
        (0..steps).map(|k| {
            // Each step reaches a little into the next one, so no seam shows between them.
            let a = lo * (hi / lo).powf(k as f64 / steps as f64);
            let b = (lo * (hi / lo).powf((k as f64 + 1.3) / steps as f64)).min(hi);
            ((0.0, a), (1.0, b), colormap((k as f64 + 0.5) / steps as f64))
        }),
    )?;
    Ok(())
}

/// Texels per pixel against depth for a handful of λ at the recommended count/resolution/fit.
pub(crate) struct LambdaDensityFigure<'a> {
    pub result: &'a SweepResult,
    pub analyses: Vec<Analysis>,
}

impl<'a> LambdaDensityFigure<'a> {
    /// Picks λ values near 0, 0.25, 0.5, 0.75, 1 (and the recommended one) from the grid.
    pub(crate) fn new(result: &'a SweepResult) -> Self {
        let Some((rec, _)) = focus(result) else {
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
    fn size(&self) -> (u32, u32) {
        let visible = focus(self.result).and_then(|(rec, _)| super::visible_depths(&rec.summary));
        (
            960,
            540 + legend_height(
                self.analyses.len() + super::depth_chart_legend_lines(visible),
                LEGEND_FONT,
            ),
        )
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let r = self.result;
        let Some((rec, ok)) = focus(r) else {
            return draw_message(
                root,
                "Texels per pixel vs depth",
                "No configuration needs cascades (the scene is outside the shadow distance): nothing to plot.",
            );
        };
        let preset = r.config.shadow.preset.is_some();
        let title = if preset {
            format!(
                "Texels per pixel vs depth, {}: {} cascades × {}²",
                focus_word(ok),
                rec.setting.cascades,
                rec.setting.resolution
            )
        } else {
            format!(
                "Texels per pixel vs depth for several λ: {} cascades × {}², {} fit",
                rec.setting.cascades, rec.setting.resolution, rec.setting.fit
            )
        };
        let (mut chart, (y0, y1)) = texels_per_pixel_chart(
            root,
            &title,
            20,
            (rec.summary.z_lo, rec.summary.z_hi),
            self.analyses
                .iter()
                .flat_map(|a| a.density.iter().map(|d| d.texels_per_pixel)),
            self.analyses.len() + super::depth_chart_legend_lines(super::visible_depths(&rec.summary)),
            &mut legend,
            super::visible_depths(&rec.summary),
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
                chart.draw_series(LineSeries::new(pts, color.stroke_width(width)))?;
                if i == 0 {
                    // The worst case from the sweep's row of this λ (its screen metrics with
                    // geometry; this figure's own analyses measure depth only).
                    let same = Setting {
                        lambda: a.config.shadow.lambda,
                        ..rec.setting
                    };
                    let worst = r
                        .rows
                        .iter()
                        .find(|x| x.setting == same)
                        .map_or(a.summary.max_aliasing, |x| r.worst.value(&x.summary));
                    let label = format!(
                        "{}: mean aliasing {}, {} {}{}",
                        if preset {
                            "the preset's own splits".to_string()
                        } else {
                            format!("λ = {}", tick(a.config.shadow.lambda))
                        },
                        super::short(a.summary.mean_aliasing),
                        if r.worst.name() == "max_aliasing" {
                            "max"
                        } else {
                            "worst on screen"
                        },
                        super::short(worst),
                        if width == 4 {
                            format!(" ({})", focus_word(ok))
                        } else {
                            String::new()
                        }
                    );
                    legend.add(label, move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(width))
                    });
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
        draw_legend_below(
            root,
            legend,
            self.analyses.len() + super::depth_chart_legend_lines(super::visible_depths(&rec.summary)),
        )?;
        Ok(())
    }
}

/// The five-number summary of `v` (min, lower quartile, median, upper quartile, max), or None
/// when `v` is empty. Quartiles by linear interpolation between order statistics.
pub(crate) fn five_numbers(v: &[f64]) -> Option<[f64; 5]> {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return None;
    }
    s.sort_by(f64::total_cmp);
    let q = |p: f64| {
        let x = p * (s.len() - 1) as f64;
        let (i, f) = (x.floor() as usize, x - x.floor());
        if i + 1 < s.len() {
            s[i] + f * (s[i + 1] - s[i])
        } else {
            s[i]
        }
    };
    Some([s[0], q(0.25), q(0.5), q(0.75), s[s.len() - 1]])
}

/// Shimmer snapped vs unsnapped as distributions: one box per cascade count over every λ,
/// resolution and fit of the grid (whiskers: min and max; box: quartiles; bar: median), with the
/// recommended configuration marked. Bounded at any grid size.
pub(crate) struct ShimmerSweepFigure<'a>(pub &'a SweepResult);

impl Figure for ShimmerSweepFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 520 + legend_height(3, LEGEND_FONT))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let r = self.0;
        let counts = &r.grid.cascades.values;
        let title = format!(
            "Shimmer per cascade count over {} configurations ({} path): snapped vs unsnapped",
            r.rows.len(),
            r.config.motion.path.name()
        );
        let max_un = r
            .rows
            .iter()
            .map(|x| x.summary.shimmer_unsnapped)
            .fold(0.0f64, f64::max);
        let max_sn = r.rows.iter().map(|x| x.summary.shimmer_snapped).fold(0.0f64, f64::max);
        let ymax = max_un.max(max_sn).max(0.05) * 1.12;
        let n = counts.len().max(1);
        let mut chart = legend_frame(root, &title, 20, 70, 3, LEGEND_FONT).build_cartesian_2d(
            ticked_axis(0.0, n as f64, (0..n).map(|i| i as f64 + 0.5).collect()),
            linear_axis(0.0, ymax),
        )?;
        house_mesh(
            &mut chart,
            "cascades (each box: every λ, resolution and fit with that count)",
            "RMS sub-texel drift per frame (texels)",
        )
        .disable_x_mesh()
        .x_label_formatter(&|v| counts.get(v.floor() as usize).map_or(String::new(), |c| c.to_string()))
        .draw()?;
        let orange = series_color(1);
        let blue = series_color(0);
        // Unsnapped boxes left of each count's centre, snapped right of it.
        for (k, (color, offset, snapped)) in [(orange, 0.27, false), (blue, 0.73, true)].into_iter().enumerate() {
            let mut elements: Vec<DynElement<DB, (f64, f64)>> = Vec::new();
            for (i, &c) in counts.iter().enumerate() {
                let v: Vec<f64> = r
                    .rows
                    .iter()
                    .filter(|x| x.setting.cascades == c)
                    .map(|x| {
                        if snapped {
                            x.summary.shimmer_snapped
                        } else {
                            x.summary.shimmer_unsnapped
                        }
                    })
                    .collect();
                let Some([lo, q1, med, q3, hi]) = five_numbers(&v) else {
                    continue;
                };
                let x = i as f64 + offset;
                let half = 0.17;
                elements.push(PathElement::new(vec![(x, lo), (x, hi)], color.stroke_width(2)).into_dyn());
                elements.push(PathElement::new(vec![(x - 0.08, lo), (x + 0.08, lo)], color.stroke_width(2)).into_dyn());
                elements.push(PathElement::new(vec![(x - 0.08, hi), (x + 0.08, hi)], color.stroke_width(2)).into_dyn());
                elements.push(Rectangle::new([(x - half, q1), (x + half, q3)], color.mix(0.45).filled()).into_dyn());
                elements.push(Rectangle::new([(x - half, q1), (x + half, q3)], color.stroke_width(1)).into_dyn());
                elements
                    .push(PathElement::new(vec![(x - half, med), (x + half, med)], color.stroke_width(3)).into_dyn());
            }
            let label = match (snapped, max_sn <= STABLE_SHIMMER) {
                (false, _) => format!("unsnapped (largest {} texels)", super::short(max_un)),
                (true, true) => format!(
                    "snapped (largest {}: stable, boxes sit on zero)",
                    crate::output::short_number(max_sn)
                ),
                (true, false) => format!("snapped (largest {} texels: NOT stable)", super::short(max_sn)),
            };
            let _ = k;
            chart.draw_series(elements)?;
            legend.add(label, move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 16, y + 5)], color.filled())
            });
        }
        if let Some((rec, ok)) = focus(r) {
            if let Some(i) = counts.iter().position(|c| *c == rec.setting.cascades) {
                let red = palette::RECOMMENDED;
                let pts = [
                    (i as f64 + 0.27, rec.summary.shimmer_unsnapped),
                    (i as f64 + 0.73, rec.summary.shimmer_snapped),
                ];
                chart.draw_series(pts.iter().map(|p| Circle::new(*p, 6, red.stroke_width(2))))?;
                legend.add(
                    format!("{}: {}", focus_word(ok), setting_words(r, &rec.setting)),
                    move |(x, y)| Circle::new((x + 8, y), 5, red.stroke_width(2)),
                );
            }
        }
        draw_legend_below(root, legend, 3)?;
        Ok(())
    }
}

/// Pareto front of memory against the sweep's objective (mean aliasing without geometry).
pub(crate) struct ParetoFigure<'a>(pub &'a SweepResult);

impl Figure for ParetoFigure<'_> {
    fn size(&self) -> (u32, u32) {
        size_with_legend(4)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
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
        let ((xmin, xmax), (ymin, ymax)) = extent(&pts);
        let (x0, x1) = log_range(xmin.min(r.budget_mib), xmax.max(r.budget_mib));
        let (y0, y1) = log_range(ymin, ymax);
        let lines = 3 + usize::from(focus(r).is_some());
        let y_desc = if bounds_only {
            "mean aliasing (texel/pixel, log; lower is better)".to_string()
        } else {
            format!("{} (log; lower is better)", obj.name())
        };
        let x_desc = "shadow map memory (MiB, log; cascades × resolution² × 4 bytes)";
        let mut chart = configurations_chart(
            root,
            &title,
            lines,
            (x0, x1),
            (y0, y1),
            (x_desc, y_desc),
            &pts,
            &mut legend,
        )?;
        let budget = format!("memory budget {} MiB", tick(r.budget_mib));
        draw_limit(&mut chart, &mut legend, r.budget_mib, (y0, y1), budget)?;
        let front: Vec<(f64, f64)> = r
            .front
            .iter()
            .map(|&i| (mib(r.rows[i].summary.memory_bytes), obj.value(&r.rows[i].summary)))
            .collect();
        let at = focus(r).map(|(rec, ok)| ((mib(rec.summary.memory_bytes), obj.value(&rec.summary)), rec, ok));
        draw_front_and_focus(
            &mut chart,
            &mut legend,
            r,
            front,
            "Pareto front (nothing is both cheaper and sharper)",
            at,
        )?;
        draw_legend_below(root, legend, lines)?;
        Ok(())
    }
}

/// The ranges `((x_min, x_max), (y_min, y_max))` of positive points.
fn extent(pts: &[(f64, f64)]) -> ((f64, f64), (f64, f64)) {
    pts.iter().fold(
        ((f64::INFINITY, 0.0f64), (f64::INFINITY, 0.0f64)),
        |((a, b), (c, d)), p| ((a.min(p.0), b.max(p.0)), (c.min(p.1), d.max(p.1))),
    )
}

/// Every configuration as a grey dot on a log-log chart, one dot per 2-pixel cell (a large
/// sweep draws what can be seen, not every point), with its legend entry.
fn draw_configurations<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<LogAxis, LogAxis>>,
    pts: &[(f64, f64)],
    legend: &mut Legend<DB>,
) -> PlotResult {
    let grey = palette::POINT;
    let mut seen = std::collections::HashSet::new();
    let shown: Vec<(f64, f64)> = pts
        .iter()
        .filter(|p| {
            let (x, y) = chart.backend_coord(p);
            seen.insert((x / 2, y / 2))
        })
        .copied()
        .collect();
    chart.draw_series(shown.iter().map(|p| Circle::new(*p, 3, grey.filled())))?;
    legend.add("configuration", move |(x, y)| Circle::new((x + 8, y), 3, grey.filled()));
    Ok(())
}

/// The log-log chart both Pareto figures draw on: the house frame with room for `lines` legend
/// entries, the mesh with `desc` (x, y) and every configuration as a grey dot.
#[allow(clippy::too_many_arguments)]
fn configurations_chart<'a, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, Shift>,
    title: &str,
    lines: usize,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
    (x_desc, y_desc): (&str, String),
    pts: &[(f64, f64)],
    legend: &mut Legend<DB>,
) -> Result<ChartContext<'a, DB, Cartesian2d<LogAxis, LogAxis>>, DrawError> {
    let mut chart =
        legend_frame(root, title, 22, 70, lines, LEGEND_FONT).build_cartesian_2d(log_axis(x0, x1), log_axis(y0, y1))?;
    house_mesh(&mut chart, x_desc, y_desc).max_light_lines(3).draw()?;
    draw_configurations(&mut chart, pts, legend)?;
    Ok(chart)
}

/// A dashed vertical line at `x` across `y0..y1` (a budget, or the configured setting's
/// cost) with its legend entry `label`.
fn draw_limit<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<LogAxis, LogAxis>>,
    legend: &mut Legend<DB>,
    x: f64,
    (y0, y1): (f64, f64),
    label: String,
) -> PlotResult {
    let limit = palette::LIMIT.stroke_width(2);
    chart.draw_series(DashedLineSeries::new(vec![(x, y0), (x, y1)], 6, 4, limit))?;
    legend.add(label, move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], limit));
    Ok(())
}

/// The Pareto front `front` (a thick line through dots) with its legend entry `label`, then, at
/// `focus` (its point, row and whether it is the recommendation), a ring with its legend entry
/// and the setting's words beside it.
fn draw_front_and_focus<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<LogAxis, LogAxis>>,
    legend: &mut Legend<DB>,
    r: &SweepResult,
    front: Vec<(f64, f64)>,
    label: &str,
    focus: Option<((f64, f64), &Row, bool)>,
) -> PlotResult {
    let orange = series_color(1);
    chart.draw_series(LineSeries::new(front.clone(), orange.stroke_width(3)))?;
    legend.add(label, move |(x, y)| {
        PathElement::new(vec![(x, y), (x + 18, y)], orange.stroke_width(3))
    });
    chart.draw_series(front.iter().map(|p| Circle::new(*p, 5, orange.filled())))?;
    if let Some((p, rec, ok)) = focus {
        let red = palette::RECOMMENDED;
        chart.draw_series(std::iter::once(Circle::new(p, 9, red.stroke_width(3))))?;
        legend.add(focus_word(ok), move |(x, y)| {
            Circle::new((x + 8, y), 6, red.stroke_width(2))
        });
        // The label sits up and to the right of the marker, in pixels, clear of it.
        chart.draw_series(std::iter::once(
            EmptyElement::at(p)
                + Text::new(
                    format!("{}: {}", focus_word(ok), setting_words(r, &rec.setting)),
                    (14, -30),
                    (FONT, 15).into_font().color(&red),
                ),
        ))?;
    }
    Ok(())
}

/// Pareto front of the render cost (`cost_index`, the configured setting = 1) against the
/// sweep's objective (`cost_pareto.png`; only with scene geometry, where the cost is counted).
pub(crate) struct CostParetoFigure<'a>(pub &'a SweepResult);

impl Figure for CostParetoFigure<'_> {
    fn size(&self) -> (u32, u32) {
        size_with_legend(4)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let mut legend = Legend::default();
        let r = self.0;
        let obj = r.objective;
        let title = format!("Render cost against {}: {}", obj.name(), r.config.name);
        let pts: Vec<(f64, f64)> = r
            .rows
            .iter()
            .filter(|x| x.summary.cascades_needed)
            .filter_map(|x| Some((x.summary.cost.cost_index.filter(|c| *c > 0.0)?, obj.value(&x.summary))))
            .filter(|p| p.1 > 0.0)
            .collect();
        if pts.is_empty() {
            return draw_message(root, &title, "No configuration has a measured render cost.");
        }
        let ((xmin, xmax), (ymin, ymax)) = extent(&pts);
        let budget = r.cost_limit.index;
        let (x0, x1) = log_range(xmin.min(budget.unwrap_or(xmin)), xmax.max(budget.unwrap_or(xmax)));
        let (y0, y1) = log_range(ymin, ymax);
        let lines = 3 + usize::from(focus(r).is_some());
        let x_desc = "cost_index (log; draws, triangles, fragments and cleared texels; configured setting = 1)";
        let y_desc = format!("{} (log; lower is better)", obj.name());
        let mut chart = configurations_chart(
            root,
            &title,
            lines,
            (x0, x1),
            (y0, y1),
            (x_desc, y_desc),
            &pts,
            &mut legend,
        )?;
        match budget {
            Some(b) => draw_limit(&mut chart, &mut legend, b, (y0, y1), format!("cost budget {}", tick(b)))?,
            None => draw_limit(
                &mut chart,
                &mut legend,
                1.0,
                (y0, y1),
                "the configured setting's cost (1)".into(),
            )?,
        }
        let front: Vec<(f64, f64)> = r
            .cost_front
            .iter()
            .filter_map(|&i| Some((r.rows[i].summary.cost.cost_index?, obj.value(&r.rows[i].summary))))
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
            .collect();
        let at = focus(r).and_then(|(rec, ok)| {
            let c = rec.summary.cost.cost_index.filter(|c| *c > 0.0)?;
            Some(((c, obj.value(&rec.summary)), rec, ok))
        });
        draw_front_and_focus(
            &mut chart,
            &mut legend,
            r,
            front,
            "Pareto front (nothing is both cheaper to render and sharper)",
            at,
        )?;
        draw_legend_below(root, legend, lines)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_heat_map_shows_every_resolution_up_to_six_then_the_focus_and_an_even_spread() {
        let all: Vec<u32> = (0..60).map(|i| 256 + 64 * i).collect();
        for n in 1..=all.len() {
            let axis = &all[..n];
            for focus in std::iter::once(None).chain(axis.iter().copied().map(Some)) {
                let shown = shown_resolutions(axis, focus, 6);
                if n <= 6 {
                    assert_eq!(shown, axis);
                    continue;
                }
                assert_eq!(shown.len(), 6, "n {n}, focus {focus:?}");
                let at: Vec<usize> = shown
                    .iter()
                    .map(|r| axis.iter().position(|a| a == r).unwrap())
                    .collect();
                assert!(at.windows(2).all(|w| w[0] < w[1]), "in grid order, distinct: {at:?}");
                if let Some(f) = focus {
                    assert!(shown.contains(&f), "n {n}: {f} missing from {shown:?}");
                }
                // Brute force: the even spread is the nearest index to i (n − 1) / 5.
                let spread: Vec<usize> = (0..6)
                    .map(|i| (i as f64 * (n - 1) as f64 / 5.0).round() as usize)
                    .collect();
                let differ = at.iter().filter(|i| !spread.contains(i)).count();
                match focus.map(|f| axis.iter().position(|&a| a == f).unwrap()) {
                    Some(f) if !spread.contains(&f) => assert_eq!(differ, 1, "only the focus replaces a pick"),
                    _ => assert_eq!(at, spread, "n {n}"),
                }
            }
        }
    }

    #[test]
    fn five_numbers_are_min_quartiles_median_max() {
        assert_eq!(
            five_numbers(&[5.0, 1.0, 4.0, 2.0, 3.0]),
            Some([1.0, 2.0, 3.0, 4.0, 5.0])
        );
        // Quartiles interpolate between order statistics.
        assert_eq!(five_numbers(&[10.0, 0.0]), Some([0.0, 2.5, 5.0, 7.5, 10.0]));
        assert_eq!(five_numbers(&[0.3]), Some([0.3; 5]));
        assert_eq!(five_numbers(&[f64::NAN, 2.0]), Some([2.0; 5]));
        assert_eq!(five_numbers(&[]), None);
    }
}
