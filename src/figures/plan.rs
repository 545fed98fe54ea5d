//! `plan.png`: the level seen from above, and where every view stands.
//!
//! The ground is the scene's geometry seen straight down: a vertical ray per cell of a grid
//! over the scene's x/z extent (at most [`GRID`] cells along the longer side) finds the highest
//! surface, shaded by its height (darker is higher) with a dark edge where the height jumps
//! (walls). On top, drawn as SVG with the house font: each view as a dot at its eye with its
//! frustum (the four corner rays and the far rectangle, cut at a stated distance so near views
//! stay readable), coloured by a per-view value when one is given (the objective, on the
//! colour map of every figure) or one colour otherwise; the worst view ringed in red; the
//! light's direction as an arrow (its horizontal part, with its elevation). The page's up is
//! −Z (x to the right), as a map with north up.
//!
//! The overlay is plotters' SVG on a transparent background, rasterised by resvg over the
//! height image, so text and lines are those of every other figure.

use std::fmt::Write as _;

use glam::DVec3;
use plotters::coord::Shift;
use plotters::prelude::*;
use rayon::prelude::*;

use super::{colormap, house_mesh, palette, series_color, tick, DrawError, PlotResult, FONT};
use crate::config::{Config, ViewSettings};
use crate::error::{PlotError, Result};
use csm_core::geometry::{Aabb, CameraPose, Lens};
use csm_core::visibility::SceneGeometry;

/// Cells of the height image along the scene's longer side.
pub(crate) const GRID: usize = 256;
/// The figure's size in SVG units and the PNG's in pixels (a report page shows it at that size).
const SIZE: (u32, u32) = (1000, 860);
/// Width of the key at the right.
const KEY_W: u32 = 230;
/// Where in its cell the height image's ray goes down, from the cell's centre (cell units).
const JITTER: (f64, f64) = (0.137, -0.211);
/// Names are written beside the dots up to this many views.
const MOST_LABELS: usize = 24;

/// What the plan shows: the geometry, the views and what colours them.
pub(crate) struct Plan<'a> {
    pub(crate) title: String,
    pub(crate) scene: &'a SceneGeometry,
    /// The x/z extent drawn (the scene's bounds).
    pub(crate) bounds: Aabb,
    pub(crate) views: &'a [ViewSettings],
    /// The screen's aspect ratio (every view's).
    pub(crate) aspect: f64,
    /// A value per view (same order) and its name, e.g. the objective; None: one colour. A
    /// value that is not a number marks a view without one (drawn grey).
    pub(crate) values: Option<(&'a str, &'a [f64])>,
    /// The index of the worst view, ringed.
    pub(crate) worst: Option<usize>,
    /// Unit direction the light travels.
    pub(crate) light: DVec3,
}

/// `plan.png` of `config`'s level views, or None without scene geometry. `values` (a name and
/// one number per view of [`Config::level_views`]) colour the views; `worst` rings one.
/// `scale` is PNG pixels per SVG unit: 1 for the file and the copy a report inlines (the size
/// a page shows it, as every figure's PNG: [`super::png_scale`]).
pub(crate) fn plan_png(
    config: &Config,
    values: Option<(&str, &[f64])>,
    worst: Option<usize>,
    scale: f32,
) -> Result<Option<Vec<u8>>> {
    Ok(plan_pngs(config, values, worst, &[scale])?.map(|mut v| v.remove(0)))
}

/// [`plan_png`] at each of `scales`, from one height image and one parsed overlay.
pub(crate) fn plan_pngs(
    config: &Config,
    values: Option<(&str, &[f64])>,
    worst: Option<usize>,
    scales: &[f32],
) -> Result<Option<Vec<Vec<u8>>>> {
    let Some(g) = &config.geometry else {
        return Ok(None);
    };
    let views = config.level_views();
    let plan = Plan {
        title: format!(
            "Plan: {} from above, {} view{}",
            config.name,
            views.len(),
            if views.len() == 1 { "" } else { "s" }
        ),
        scene: &g.scene,
        bounds: config.scene,
        views: &views,
        aspect: config.screen.aspect(),
        values,
        worst,
        light: config.light_direction,
    };
    plan.pngs(scales).map(Some)
}

/// The height image: (columns, rows, height of the top surface per cell, row-major from −Z to
/// +Z and −X to +X; None where nothing is hit).
struct Heights {
    cols: usize,
    rows: usize,
    /// The world x/z rectangle the cells cover: (x0, x1, z0, z1).
    rect: (f64, f64, f64, f64),
    h: Vec<Option<f64>>,
}

fn heights(scene: &SceneGeometry, rect: (f64, f64, f64, f64), top: f64, bottom: f64) -> Heights {
    let (x0, x1, z0, z1) = rect;
    let (ex, ez) = (x1 - x0, z1 - z0);
    let cell = ex.max(ez) / GRID as f64;
    let cols = ((ex / cell).round() as usize).clamp(1, GRID);
    let rows = ((ez / cell).round() as usize).clamp(1, GRID);
    let reach = top - bottom + 2.0;
    // Off the cell centres by unequal fractions, so no ray runs down the shared edge of two
    // triangles (a square ground's diagonal at x = z), where the binary32 BVH may find
    // neither. Every ray goes straight down from above the scene: the scene answers them all
    // at once, each the hit its own ray would find.
    let xs: Vec<f64> = (0..cols)
        .map(|i| x0 + (i as f64 + 0.5 + JITTER.0) * ex / cols as f64)
        .collect();
    let zs: Vec<f64> = (0..rows)
        .map(|j| z0 + (j as f64 + 0.5 + JITTER.1) * ez / rows as f64)
        .collect();
    let y = top + 1.0;
    let h = scene
        .first_hits_down(&xs, &zs, y, 0.0, reach)
        .into_iter()
        .map(|hit| hit.map(|hit| y - hit.t))
        .collect();
    Heights { cols, rows, rect, h }
}

/// Shading of the height image: light grey low, dark grey high, white where nothing is hit,
/// darker where the height jumps to a neighbour by more than `jump`.
fn shade(hm: &Heights) -> Vec<[u8; 3]> {
    let (lo, hi) =
        hm.h.iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| (a.min(y), b.max(y)));
    let span = (hi - lo).max(1e-9);
    let jump = 0.02 * span.max(1.0);
    let at = |i: usize, j: usize| hm.h[j * hm.cols + i];
    (0..hm.cols * hm.rows)
        .map(|k| {
            let (i, j) = (k % hm.cols, k / hm.cols);
            let Some(y) = hm.h[k] else {
                return [255, 255, 255];
            };
            let t = (y - lo) / span;
            let mut g = 228.0 - 118.0 * t;
            let step = |n: Option<f64>| n.is_some_and(|n| (n - y).abs() > jump);
            let edge = (i + 1 < hm.cols && step(at(i + 1, j))) || (j + 1 < hm.rows && step(at(i, j + 1)));
            if edge {
                g *= 0.55;
            }
            let g = g.round() as u8;
            [g, g, g.saturating_add(6)]
        })
        .collect()
}

/// The x/z rectangle drawn: the bounds' extent grown to hold every view's eye, with a margin.
fn drawn_rect(bounds: &Aabb, views: &[ViewSettings]) -> (f64, f64, f64, f64) {
    let (mut x0, mut x1, mut z0, mut z1) = (bounds.min.x, bounds.max.x, bounds.min.z, bounds.max.z);
    for v in views {
        let p = v.camera.position;
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
        z0 = z0.min(p.z);
        z1 = z1.max(p.z);
    }
    let m = 0.03 * (x1 - x0).max(z1 - z0).max(1.0);
    (x0 - m, x1 + m, z0 - m, z1 + m)
}

/// The view's colour: by its value on the colour map, neutral grey ([`palette::NO_DATA`]) for
/// a view without one (not a number: a view that sees no receiver has no objective), or one
/// colour when no values are given.
fn view_colour(values: Option<(&str, &[f64])>, k: usize) -> RGBColor {
    match values {
        Some((_, v)) => {
            let (lo, hi) = value_range(v);
            match v.get(k).copied().filter(|x| x.is_finite()) {
                Some(x) => colormap(if hi > lo { (x - lo) / (hi - lo) } else { 0.5 }),
                None => palette::NO_DATA,
            }
        }
        None => series_color(0),
    }
}

/// Whether some view has no value (drawn neutral grey, and said in the key).
fn some_without_value(values: Option<(&str, &[f64])>) -> bool {
    values.is_some_and(|(_, v)| v.iter().any(|x| !x.is_finite()))
}

fn value_range(v: &[f64]) -> (f64, f64) {
    v.iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)))
}

impl Plan<'_> {
    /// The frustum's drawn depth: the far plane, at most a sixth of the drawn extent, shorter
    /// with many views (divided by √(n / 3) past three views) so they stay apart.
    fn frustum_depth(&self, rect: (f64, f64, f64, f64), far: f64) -> f64 {
        let crowd = (self.views.len() as f64 / 3.0).max(1.0).sqrt();
        far.min((rect.1 - rect.0).max(rect.3 - rect.2) / (6.0 * crowd))
    }

    /// The overlay SVG, the pixel rectangle of its plotting area (left, top, right, bottom) and
    /// the world x/z rectangle that area spans.
    #[allow(clippy::type_complexity)]
    fn overlay(
        &self,
        rect: (f64, f64, f64, f64),
    ) -> std::result::Result<(String, [i32; 4], (f64, f64, f64, f64)), DrawError> {
        super::init_fonts();
        // The plotting area's pixels do not depend on the ranges: measured on a scratch canvas,
        // they give the padding that makes both axes one scale.
        let area = {
            let mut scratch = String::new();
            let root = SVGBackend::with_string(&mut scratch, SIZE).into_drawing_area();
            let (plot, _) = root.split_horizontally(SIZE.0 - KEY_W);
            let chart = super::chart_frame(&plot, &self.title, 20, 70).build_cartesian_2d(0.0..1.0, 0.0..1.0)?;
            let (xr, yr) = chart.plotting_area().get_pixel_range();
            [xr.start, yr.start, xr.end, yr.end]
        };
        let (x0, x1, z0, z1) = rect;
        let (aw, ah) = (f64::from(area[2] - area[0]), f64::from(area[3] - area[1]));
        let (ex, ez) = (x1 - x0, z1 - z0);
        let scale = (aw / ex).min(ah / ez);
        let (px, pz) = ((aw / scale - ex) / 2.0, (ah / scale - ez) / 2.0);
        let padded = (x0 - px, x1 + px, z0 - pz, z1 + pz);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
            let (plot, key) = root.split_horizontally(SIZE.0 - KEY_W);
            self.draw_plot(&plot, rect, padded)?;
            self.draw_key(&key, rect)?;
            root.present()?;
        }
        Ok((svg, area, padded))
    }

    fn draw_plot<DB: DrawingBackend>(
        &self,
        plot: &DrawingArea<DB, Shift>,
        rect: (f64, f64, f64, f64),
        padded: (f64, f64, f64, f64),
    ) -> PlotResult {
        let (cx0, cx1, cz0, cz1) = padded;
        let mut chart = super::chart_frame(plot, &self.title, 20, 70)
            .build_cartesian_2d(super::linear_axis(cx0, cx1), super::linear_axis(-cz1, -cz0))?;
        house_mesh(&mut chart, "x (world units)", "z (world units; up the page is −z)")
            .disable_mesh()
            .y_label_formatter(&|v| tick(-*v))
            .draw()?;
        let at = |p: DVec3| (p.x, -p.z);
        let n = self.views.len();
        for (k, v) in self.views.iter().enumerate() {
            let c = &v.camera;
            let colour = view_colour(self.values, k);
            if let Some(pose) = CameraPose::look_at(c.position, c.target, c.up) {
                let lens = Lens::new(c.fov_y(), self.aspect);
                let d = self.frustum_depth(rect, c.far);
                let corners: Vec<DVec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .iter()
                    .map(|&(sx, sy)| pose.point(sx * lens.tan_h, sy * lens.tan_v, d))
                    .collect();
                let style = colour.mix(0.9).stroke_width(2);
                for q in &corners {
                    chart.draw_series(LineSeries::new([at(c.position), at(*q)], style))?;
                }
                let mut ring: Vec<(f64, f64)> = corners.iter().map(|q| at(*q)).collect();
                ring.push(ring[0]);
                chart.draw_series(LineSeries::new(ring, style))?;
            }
        }
        for (k, v) in self.views.iter().enumerate() {
            let colour = view_colour(self.values, k);
            let p = at(v.camera.position);
            chart.draw_series([Circle::new(p, 6, colour.filled())])?;
            chart.draw_series([Circle::new(p, 6, BLACK.stroke_width(1))])?;
            if self.worst == Some(k) {
                chart.draw_series([Circle::new(p, 13, palette::MARKED.stroke_width(3))])?;
            }
            if n <= MOST_LABELS {
                chart
                    .draw_series([EmptyElement::at(p) + Text::new(v.name.clone(), (9, -18), (FONT, 13).into_font())])?;
            }
        }
        // The light: its horizontal direction as an arrow in the top right corner.
        let flat = DVec3::new(self.light.x, 0.0, self.light.z);
        let elevation = (-self.light.y).clamp(-1.0, 1.0).asin().to_degrees();
        let len = 0.08 * (cx1 - cx0);
        let centre = (cx1 - 1.6 * len, -cz0 - 1.6 * len);
        let style = palette::MISS.stroke_width(3);
        if flat.length() > 1e-6 {
            let u = flat.normalize();
            let (dx, dy) = (u.x * len, -u.z * len);
            let tail = (centre.0 - dx / 2.0, centre.1 - dy / 2.0);
            let head = (centre.0 + dx / 2.0, centre.1 + dy / 2.0);
            chart.draw_series(LineSeries::new([tail, head], style))?;
            for turn in [2.6f64, -2.6] {
                let (s, co) = turn.sin_cos();
                let back = (dx * co - dy * s, dx * s + dy * co);
                chart.draw_series(LineSeries::new(
                    [head, (head.0 + 0.35 * back.0, head.1 + 0.35 * back.1)],
                    style,
                ))?;
            }
        } else {
            chart.draw_series([Circle::new(centre, 6, palette::MISS.filled())])?;
        }
        chart.draw_series([Text::new(
            format!("light, {:.0}° up", elevation),
            (centre.0 - 0.9 * len, centre.1 - 0.75 * len),
            (FONT, 13).into_font().color(&palette::MISS),
        )])?;
        Ok(())
    }

    fn draw_key<DB: DrawingBackend>(
        &self,
        key: &DrawingArea<DB, Shift>,
        rect: (f64, f64, f64, f64),
    ) -> std::result::Result<(), DrawError> {
        let text = |s: String, x: i32, y: i32| Text::new(s, (x, y), (FONT, 13).into_font());
        let mut y = 60;
        let far = self.views.iter().map(|v| v.camera.far).fold(f64::INFINITY, f64::min);
        let lines = [
            "Dot: a view's eye; lines: its".to_string(),
            format!("frustum, drawn to {} world", tick_len(self.frustum_depth(rect, far))),
            "units of depth.".to_string(),
            "Ground: the top surface,".to_string(),
            "darker is higher; dark edges".to_string(),
            "where the height jumps.".to_string(),
        ];
        for l in lines {
            key.draw(&text(l, 8, y))?;
            y += 18;
        }
        y += 10;
        if self.worst.is_some() {
            key.draw(&Circle::new((20, y + 4), 9, palette::MARKED.stroke_width(3)))?;
            key.draw(&text("worst view".to_string(), 38, y - 3))?;
            y += 30;
        }
        key.draw(&PathElement::new(
            vec![(10, y + 4), (32, y + 4)],
            palette::MISS.stroke_width(3),
        ))?;
        key.draw(&text("light (horizontal part)".to_string(), 38, y - 3))?;
        y += 34;
        match self.values {
            Some((name, v)) => {
                let (lo, hi) = value_range(v);
                key.draw(&text(name.replace('_', " "), 8, y))?;
                y += 22;
                let h = 200;
                for i in 0..h {
                    let t = 1.0 - f64::from(i) / f64::from(h - 1);
                    key.draw(&Rectangle::new([(10, y + i), (34, y + i + 1)], colormap(t).filled()))?;
                }
                key.draw(&Rectangle::new([(10, y), (34, y + h)], BLACK.stroke_width(1)))?;
                key.draw(&text(super::short(hi), 42, y - 6))?;
                key.draw(&text(super::short(lo), 42, y + h - 8))?;
                if some_without_value(self.values) {
                    let y = y + h + 30;
                    key.draw(&Circle::new((20, y + 4), 6, palette::NO_DATA.filled()))?;
                    key.draw(&Circle::new((20, y + 4), 6, BLACK.stroke_width(1)))?;
                    key.draw(&text("sees no receiver:".to_string(), 38, y - 3))?;
                    key.draw(&text("no value".to_string(), 38, y + 15))?;
                }
            }
            None => {
                key.draw(&Circle::new((20, y + 4), 6, series_color(0).filled()))?;
                key.draw(&text("view".to_string(), 38, y - 3))?;
            }
        }
        Ok(())
    }

    /// The figure as PNG bytes: the height image under the SVG overlay, `scale` pixels per SVG
    /// unit.
    #[cfg(test)]
    pub(crate) fn png(&self, scale: f32) -> Result<Vec<u8>> {
        let mut v = self.pngs(&[scale])?;
        Ok(v.remove(0))
    }

    /// The plan as a PNG at each of `scales`: the overlay, the height image and its shading
    /// are made and parsed once, then painted and rasterised per scale (in parallel).
    pub(crate) fn pngs(&self, scales: &[f32]) -> Result<Vec<Vec<u8>>> {
        let rect = drawn_rect(&self.bounds, self.views);
        let (svg, area, padded) = self.overlay(rect).map_err(|e| PlotError::Draw(e.0))?;
        let hm = heights(self.scene, rect, self.bounds.max.y, self.bounds.min.y);
        let colours = shade(&hm);
        let tree = super::ParsedSvg::parse(svg.as_bytes())?;
        scales
            .par_iter()
            .map(|&scale| {
                let (w, h) = (
                    (SIZE.0 as f32 * scale).ceil() as u32,
                    (SIZE.1 as f32 * scale).ceil() as u32,
                );
                let mut pixmap = resvg::tiny_skia::Pixmap::new(w, h)
                    .ok_or_else(|| PlotError::Rasterise(format!("bad size {w}x{h}")))?;
                pixmap.fill(resvg::tiny_skia::Color::WHITE);
                paint_heights(&mut pixmap, &hm, &colours, area, padded, scale);
                tree.render(
                    resvg::tiny_skia::Transform::from_scale(scale, scale),
                    &mut pixmap.as_mut(),
                );
                super::encode_figure_pixmap(&pixmap)
            })
            .collect()
    }
}

/// A length for the key: a whole number when large.
fn tick_len(d: f64) -> String {
    if d >= 10.0 {
        format!("{}", d.round())
    } else {
        tick((d * 10.0).round() / 10.0)
    }
}

/// Paints the height image into the plotting area `area` (SVG pixels, scaled by `scale`),
/// whose axes span `padded` (x0, x1, z0, z1): x runs left to right, z top to bottom.
fn paint_heights(
    pixmap: &mut resvg::tiny_skia::Pixmap,
    hm: &Heights,
    colours: &[[u8; 3]],
    area: [i32; 4],
    padded: (f64, f64, f64, f64),
    scale: f32,
) {
    let (x0, x1, z0, z1) = padded;
    let [l, t, r, b] = area.map(|v| f64::from(v) * f64::from(scale));
    let (hx0, hx1, hz0, hz1) = hm.rect;
    let w = pixmap.width() as usize;
    let data = pixmap.data_mut();
    let (py0, py1) = (t.max(0.0) as usize, b.max(0.0) as usize);
    let (px0, px1) = (l.max(0.0) as usize, r.max(0.0) as usize);
    // A pixel's column of cells depends on its x alone and its row on its y alone: each is
    // worked out once per pixel column and row, not once per pixel.
    let columns: Vec<(usize, usize)> = (px0..px1.min(w))
        .filter_map(|px| Some((px, cell_index(px, (l, r), (x0, x1), (hx0, hx1), hm.cols)?)))
        .collect();
    for py in py0..py1 {
        let Some(j) = cell_index(py, (t, b), (z0, z1), (hz0, hz1), hm.rows) else {
            continue;
        };
        let row = &colours[j * hm.cols..][..hm.cols];
        for &(px, i) in &columns {
            let o = (py * w + px) * 4;
            if o + 3 < data.len() {
                data[o..o + 3].copy_from_slice(&row[i]);
                data[o + 3] = 255;
            }
        }
    }
}

/// The cell along one axis under pixel `p`, whose centre maps from the pixels `px` (from, to)
/// onto the axis' span `axis`, over `n` cells covering `cells` (from, to); None outside them.
fn cell_index(p: usize, px: (f64, f64), axis: (f64, f64), cells: (f64, f64), n: usize) -> Option<usize> {
    let v = axis.0 + (p as f64 + 0.5 - px.0) / (px.1 - px.0) * (axis.1 - axis.0);
    if v < cells.0 || v >= cells.1 {
        return None;
    }
    Some(((((v - cells.0) / (cells.1 - cells.0)) * n as f64) as usize).min(n - 1))
}

/// A caption for the report: how many views and what colours them.
pub(crate) fn caption(config: &Config, values: Option<&str>) -> String {
    let n = config.level_views().len();
    let mut s = String::new();
    let _ = write!(
        s,
        "The level from above: {} view{} (dot and frustum), the light's direction (arrow)",
        n,
        if n == 1 { "" } else { "s" }
    );
    if let Some(v) = values {
        let _ = write!(s, ", views coloured by {}", v.replace('_', " "));
    }
    s
}

/// `plan.png` of `analyze` (written with scene geometry): the configured level's views; for a
/// level, each coloured by its objective at the analysed setting (grey when it sees no
/// receiver) and the worst view ringed, as `views.csv` names it.
pub(crate) struct PlanPng;

impl crate::output::Exporter<crate::analysis::Analysis> for PlanPng {
    fn file_name(&self) -> &'static str {
        FILE
    }
    fn render(&self, a: &crate::analysis::Analysis) -> Result<Vec<u8>> {
        let Some((name, values, worst)) = level_values(&a.summary, &a.config) else {
            return Ok(plan_png(&a.config, None, None, 1.0)?.unwrap_or_default());
        };
        Ok(plan_png(&a.config, Some((name, &values)), worst, 1.0)?.unwrap_or_default())
    }
}

/// A level's per-view objective (not a number for a view that sees no receiver), the
/// objective's name and the worst view (None when no view sees a receiver); None without
/// views.
fn level_values(s: &crate::analysis::Summary, config: &Config) -> Option<(&'static str, Vec<f64>, Option<usize>)> {
    use crate::commands::sweep::level::{sees_receivers, view_summary, worst_of};
    if s.views.is_empty() {
        return None;
    }
    let objective = crate::commands::sweep::rank::default_objective(config);
    let seen: Vec<bool> = (0..s.views.len()).map(|k| sees_receivers(s, k)).collect();
    let values: Vec<f64> = (0..s.views.len())
        .map(|k| {
            if seen[k] {
                objective.value(&view_summary(s, k))
            } else {
                f64::NAN
            }
        })
        .collect();
    let worst = seen.iter().any(|&x| x).then(|| worst_of(&values, &seen, objective));
    Some((objective.name(), values, worst))
}

/// The plan's file name.
pub(crate) const FILE: &str = "plan.png";

#[cfg(test)]
mod tests {
    use super::*;
    use csm_core::mesh::Mesh;
    use proptest::prelude::*;

    /// [`paint_heights`] pixel by pixel, each pixel's cell looked up on its own.
    fn paint_heights_per_pixel(
        pixmap: &mut resvg::tiny_skia::Pixmap,
        hm: &Heights,
        colours: &[[u8; 3]],
        area: [i32; 4],
        padded: (f64, f64, f64, f64),
        scale: f32,
    ) {
        let [l, t, r, b] = area.map(|v| f64::from(v) * f64::from(scale));
        let (w, h) = (pixmap.width() as usize, pixmap.height() as usize);
        for (py, px) in (0..h).flat_map(|py| (0..w).map(move |px| (py, px))) {
            let inside = |p: usize, lo: f64, hi: f64| p >= lo.max(0.0) as usize && p < hi.max(0.0) as usize;
            if !(inside(px, l, r) && inside(py, t, b)) {
                continue;
            }
            let i = cell_index(px, (l, r), (padded.0, padded.1), (hm.rect.0, hm.rect.1), hm.cols);
            let j = cell_index(py, (t, b), (padded.2, padded.3), (hm.rect.2, hm.rect.3), hm.rows);
            if let (Some(i), Some(j)) = (i, j) {
                let o = 4 * (py * w + px);
                let c = colours[j * hm.cols + i];
                pixmap.data_mut()[o..o + 4].copy_from_slice(&[c[0], c[1], c[2], 255]);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn the_height_image_paints_each_pixel_as_its_own_cell_lookup_does(
            (cols, rows) in (1usize..40, 1usize..40),
            (w, h) in (1u32..120, 1u32..120),
            area in (-20i32..60, -20i32..60, 20i32..160, 20i32..160),
            padded in (-50.0..0.0f64, 1.0..50.0f64, -50.0..0.0f64, 1.0..50.0f64),
            rect in (-60.0..10.0f64, 0.5..60.0f64, -60.0..10.0f64, 0.5..60.0f64),
            scale in prop::sample::select(vec![0.5f32, 1.0, 1.5, 2.0]),
        ) {
            let hm = Heights { cols, rows, rect: (rect.0, rect.0 + rect.1, rect.2, rect.2 + rect.3), h: vec![None; cols * rows] };
            let colours: Vec<[u8; 3]> = (0..cols * rows).map(|k| [k as u8, (k >> 8) as u8, 7]).collect();
            let area = [area.0, area.1, area.0 + area.2, area.1 + area.3];
            let mut ours = resvg::tiny_skia::Pixmap::new(w, h).unwrap();
            let mut theirs = ours.clone();
            paint_heights(&mut ours, &hm, &colours, area, padded, scale);
            paint_heights_per_pixel(&mut theirs, &hm, &colours, area, padded, scale);
            prop_assert!(ours.data() == theirs.data());
        }
    }

    #[test]
    fn the_height_image_holds_the_top_surface_of_every_cell() {
        // A ground at 0 over [-10, 10]² and a box 5 high over [-2, 3] x [1, 4].
        let mut m = Mesh::default();
        m.add_ground(0.0, -10.0, 10.0, -10.0, 10.0);
        m.add_box(&Aabb::new(DVec3::new(-2.0, 0.0, 1.0), DVec3::new(3.0, 5.0, 4.0)));
        let s = SceneGeometry::new(m);
        let hm = heights(&s, (-10.0, 10.0, -10.0, 10.0), 5.0, 0.0);
        assert_eq!((hm.cols, hm.rows), (GRID, GRID));
        let cell = 20.0 / GRID as f64;
        for j in 0..hm.rows {
            for i in 0..hm.cols {
                let x = -10.0 + (i as f64 + 0.5 + JITTER.0) * cell;
                let z = -10.0 + (j as f64 + 0.5 + JITTER.1) * cell;
                let on_box = (-2.0..=3.0).contains(&x) && (1.0..=4.0).contains(&z);
                let want = if on_box { 5.0 } else { 0.0 };
                let got = hm.h[j * hm.cols + i].unwrap_or_else(|| panic!("cell {i},{j} missed"));
                assert!((got - want).abs() < 1e-9, "cell {i},{j} at ({x}, {z}): {got}");
            }
        }
        // Shaded: the box darker than the ground, its rim darkest, nothing white.
        let c = shade(&hm);
        let at = |x: f64, z: f64| {
            let (i, j) = (((x + 10.0) / cell) as usize, ((z + 10.0) / cell) as usize);
            c[j * hm.cols + i][0]
        };
        assert!(at(0.5, 2.5) < at(-8.0, -8.0));
        assert!(c.iter().all(|p| p[0] < 255));
    }

    /// The centre of the pixels of exactly `colour` left of the key, in SVG units (the PNG is
    /// drawn at scale 1), and their count.
    fn centroid(png: &[u8], colour: [u8; 3]) -> ((f64, f64), usize) {
        let mut reader = png::Decoder::new(std::io::Cursor::new(png)).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0);
        for y in 0..info.height {
            for x in 0..(SIZE.0 - KEY_W) {
                let o = ((y * info.width + x) * 3) as usize;
                if buf[o..o + 3] == colour {
                    sx += f64::from(x);
                    sy += f64::from(y);
                    n += 1;
                }
            }
        }
        ((sx / n.max(1) as f64, sy / n.max(1) as f64), n)
    }

    /// A 100 × 100 ground around the origin.
    fn ground() -> SceneGeometry {
        let mut m = Mesh::default();
        m.add_ground(0.0, -50.0, 50.0, -50.0, 50.0);
        SceneGeometry::new(m)
    }

    /// A view named `name` 2 units up at x, looking down at the ground 20 units ahead.
    fn camera(name: &str, x: f64) -> ViewSettings {
        ViewSettings {
            name: name.to_string(),
            camera: crate::config::CameraSettings {
                position: DVec3::new(x, 2.0, 20.0),
                target: DVec3::new(x, 0.0, 0.0),
                up: DVec3::Y,
                fov_y_deg: 50.0,
                near: 0.1,
                far: 100.0,
            },
            weight: 1.0,
        }
    }

    /// The plan of `views` over `scene` with their `values` (the objective) and `worst` ringed,
    /// as a PNG at scale 1.
    fn plan_png_of(scene: &SceneGeometry, views: &[ViewSettings], values: &[f64], worst: Option<usize>) -> Vec<u8> {
        let plan = Plan {
            title: "test".to_string(),
            scene,
            bounds: scene.mesh.bounds().unwrap(),
            views,
            aspect: 16.0 / 9.0,
            values: Some(("objective", values)),
            worst,
            light: DVec3::new(0.3, -1.0, 0.2).normalize(),
        };
        plan.png(1.0).unwrap()
    }

    #[test]
    fn views_take_the_colour_of_their_value_and_the_worst_is_ringed() {
        let scene = ground();
        let views = [camera("low", -30.0), camera("high", 30.0)];
        let png = plan_png_of(&scene, &views, &[1.0, 3.0], Some(1));
        let rgb = |c: RGBColor| [c.0, c.1, c.2];
        // The lowest value takes the colour map's start, the highest its end, each at its eye.
        let ((lx, ly), n_low) = centroid(&png, rgb(colormap(0.0)));
        let ((hx, hy), n_high) = centroid(&png, rgb(colormap(1.0)));
        assert!(n_low > 20 && n_high > 20, "{n_low} {n_high}");
        // 60 world units apart in x, on one row: the high view to the right.
        assert!(hx - lx > 100.0 && (hy - ly).abs() < 1.0, "({lx}, {ly}) ({hx}, {hy})");
        // The red ring goes round the worst (high) view.
        let ((rx, ry), n_ring) = centroid(&png, rgb(palette::MARKED));
        assert!(n_ring > 20, "{n_ring}");
        assert!(
            (rx - hx).abs() < 1.5 && (ry - hy).abs() < 1.5,
            "ring ({rx}, {ry}) dot ({hx}, {hy})"
        );
    }

    /// `analyze`'s plan of a level colours each view by its objective (the colour map's ends
    /// at the lowest and highest) and rings the worst, the view `views.csv` marks.
    #[test]
    fn analyzes_plan_of_a_level_colours_the_views_and_rings_the_worst() {
        use crate::output::Exporter;
        let text = crate::analysis::views_truth::TEST_LEVEL;
        let c = Config::from_toml_str(text, "t.toml", None).unwrap();
        let a = crate::analysis::analyze(&c, &crate::analysis::AnalysisOptions::summary_only());
        let (name, values, worst) = level_values(&a.summary, &c).unwrap();
        assert_eq!(name, "visible_aliasing_p95");
        // Each view's own visible p95, and the largest of them (every view sees the ground).
        let own: Vec<f64> = a.summary.views.iter().map(|v| v.screen.visible_p95).collect();
        assert_eq!(values, own);
        let largest = (0..own.len()).fold(0, |w, k| if own[k] > own[w] { k } else { w });
        assert_eq!(worst, Some(largest));
        assert!(own.iter().any(|&x| x != own[largest]), "{own:?}");
        let png = PlanPng.render(&a).unwrap();
        // At scale 1 (the size the report shows it) the key starts at SIZE.0 − KEY_W pixels.
        let mut reader = png::Decoder::new(std::io::Cursor::new(&png)).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let count = |c: RGBColor| {
            (0..info.height)
                .flat_map(|y| (0..SIZE.0 - KEY_W).map(move |x| ((y * info.width + x) * 3) as usize))
                .filter(|&o| buf[o..o + 3] == [c.0, c.1, c.2])
                .count()
        };
        assert!(count(colormap(0.0)) > 50 && count(colormap(1.0)) > 50);
        assert!(count(palette::MARKED) > 50);
        assert_eq!(count(series_color(0)), 0, "no view in the single colour");
        // Without views: no values, so one colour and nothing ringed.
        let plain = Config::from_toml_str(text.split("[[view]]").next().unwrap(), "t.toml", None).unwrap();
        let b = crate::analysis::analyze(&plain, &crate::analysis::AnalysisOptions::summary_only());
        assert!(level_values(&b.summary, &plain).is_none());
    }

    /// A view without a value (it sees no receiver) is drawn neutral grey, not at the colour
    /// map's low end, and the key says so; the others keep the colour map's ends.
    #[test]
    fn a_view_without_a_value_is_grey_not_the_lowest_colour() {
        let scene = ground();
        let views = [camera("low", -30.0), camera("sky", 0.0), camera("high", 30.0)];
        let rgb = |c: RGBColor| [c.0, c.1, c.2];
        let png_with = |values: &[f64]| plan_png_of(&scene, &views, values, None);
        let png = png_with(&[1.0, f64::NAN, 3.0]);
        let ((gx, gy), n_grey) = centroid(&png, rgb(palette::NO_DATA));
        let ((lx, _), n_low) = centroid(&png, rgb(colormap(0.0)));
        let ((hx, _), n_high) = centroid(&png, rgb(colormap(1.0)));
        assert!(n_grey > 20 && n_low > 20 && n_high > 20, "{n_grey} {n_low} {n_high}");
        // The grey dot is the middle view's, half way between the others.
        assert!((gx - (lx + hx) / 2.0).abs() < 1.5, "{gx} between {lx} and {hx}");
        // With a value of 0 instead, that view takes the colour map's low end: no grey dot.
        let png = png_with(&[1.0, 0.0, 3.0]);
        let (_, n_grey) = centroid(&png, rgb(palette::NO_DATA));
        assert_eq!(n_grey, 0);
        let ((zx, zy), _) = centroid(&png, rgb(colormap(0.0)));
        // The grey dot is where that view's dot is (the grey of its frustum's thin lines, where
        // they are drawn unblended, pulls the centre up the page a little).
        assert!(
            (zx - gx).abs() < 1.5 && (zy - gy).abs() < 25.0,
            "grey ({gx}, {gy}), the view's dot ({zx}, {zy})"
        );
        // The key names the grey dot only when some view has no value.
        assert!(some_without_value(Some(("o", &[1.0, f64::NAN]))));
        assert!(!some_without_value(Some(("o", &[1.0, 0.0]))));
    }
}
