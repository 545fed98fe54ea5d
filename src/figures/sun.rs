//! `quality_vs_sun.svg`: the objective over sun azimuth × elevation for the recommended setting
//! of a sun sweep, its worst sun angle marked, and where every setting's worst sun lies.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::sweep::{draw_heat_panel, focus, metric_unit, setting_words, HeatPanel};
use super::{draw_message, tick, Figure, PlotResult, FONT};
use crate::commands::sweep::SweepResult;

/// The objective over the sun angles of a sun sweep ([`crate::commands::sun_sweep`]).
pub(crate) struct QualityVsSunFigure<'a>(pub &'a SweepResult);

/// Every k-th of `n` labels (about `most` of them), the rest empty.
fn thinned(labels: Vec<String>, most: usize) -> Vec<(usize, String)> {
    let k = labels.len().div_ceil(most.max(1)).max(1);
    labels.into_iter().enumerate().filter(|(i, _)| i % k == 0).collect()
}

impl QualityVsSunFigure<'_> {
    /// The panels: the focus setting's objective per angle; with more than one setting, how
    /// many settings have their worst sun at each angle.
    fn panels(&self) -> Vec<HeatPanel> {
        let r = self.0;
        let (Some(sun), Some(grid)) = (&r.sun, &r.grid.sun) else {
            return Vec::new();
        };
        let Some((focus_row, _)) = focus(r) else {
            return Vec::new();
        };
        let Some(j) = r.rows.iter().position(|x| std::ptr::eq(x, focus_row)) else {
            return Vec::new();
        };
        let (azimuths, elevations) = (grid.azimuths(), grid.elevations());
        let x_ticks = thinned(azimuths.iter().map(|a| tick(*a)).collect(), 12);
        let y_thin = thinned(elevations.iter().map(|e| tick(*e)).collect(), 18);
        let y_labels: Vec<String> = (0..elevations.len())
            .map(|i| {
                y_thin
                    .iter()
                    .find(|t| t.0 == i)
                    .map(|t| t.1.clone())
                    .unwrap_or_default()
            })
            .collect();
        let cell_of = |i: usize| {
            let s = sun.all[i].setting.sun?;
            Some((
                azimuths.iter().position(|a| *a == s.azimuth_deg)?,
                elevations.iter().position(|e| *e == s.elevation_deg)?,
            ))
        };
        let mut cells = Vec::new();
        for i in sun.rows_of(j) {
            let row = &sun.all[i];
            if let Some((c, e)) = cell_of(i) {
                let v = row.summary.cascades_needed.then(|| r.objective.value(&row.summary));
                cells.push((c, e, v, true));
            }
        }
        let mut out = vec![HeatPanel {
            caption: format!(
                "{} · {}",
                r.objective.name().replace('_', " "),
                setting_words(r, &focus_row.setting)
            ),
            x_desc: "sun azimuth, degrees from north toward east".to_string(),
            y_desc: "sun elevation, degrees".to_string(),
            nx: azimuths.len(),
            x_ticks: x_ticks.clone(),
            y_labels: y_labels.clone(),
            cells,
            marked: cell_of(sun.worst[j]),
            unit: metric_unit(&r.objective),
        }];
        if r.rows.len() > 1 {
            let mut counts = vec![0usize; azimuths.len() * elevations.len()];
            for &w in &sun.worst {
                if let Some((c, e)) = cell_of(w) {
                    counts[e * azimuths.len() + c] += 1;
                }
            }
            let cells = counts
                .iter()
                .enumerate()
                .map(|(k, &n)| {
                    (
                        k % azimuths.len(),
                        k / azimuths.len(),
                        (n > 0).then_some(n as f64),
                        true,
                    )
                })
                .collect();
            out.push(HeatPanel {
                caption: format!("settings whose worst sun is here (of {})", r.rows.len()),
                x_desc: "sun azimuth, degrees from north toward east".to_string(),
                y_desc: "sun elevation, degrees".to_string(),
                nx: azimuths.len(),
                x_ticks,
                y_labels,
                cells,
                marked: None,
                unit: "settings (count)".to_string(),
            });
        }
        out
    }
}

impl Figure for QualityVsSunFigure<'_> {
    fn size(&self) -> (u32, u32) {
        let panels = if self.0.rows.len() > 1 { 2 } else { 1 };
        (40 + 640 * panels, 130 + 560)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> PlotResult {
        let r = self.0;
        let title = format!("{} over the sun's angles: {}", r.objective.name(), r.config.name);
        let root = root.titled(&title, (FONT, 22))?;
        let (note_area, grid_area) = root.split_vertically(60);
        let panels = self.panels();
        if panels.is_empty() {
            let why = if r.sun.is_none() {
                "No sun axis was swept (--sun-azimuth, --sun-elevation)."
            } else {
                "No configuration needs cascades: the scene is not visible within the shadow distance."
            };
            return draw_message(&grid_area, "", why);
        }
        let worst = focus(r).and_then(|(x, _)| x.setting.sun);
        let lines = [
            format!(
                "Lower is better. Red ring: the worst sun angle of the {} setting{}, the angle it is judged at.",
                match focus(r) {
                    Some((_, true)) => "recommended",
                    _ => "closest (nothing qualifies)",
                },
                worst.map_or_else(String::new, |s| format!(" ({})", s.label()))
            ),
            "Each panel has its own colour scale. Grey: no cascades needed (left), or no setting's worst sun (right)."
                .to_string(),
        ];
        for (k, l) in lines.iter().enumerate() {
            note_area.draw(&Text::new(l.clone(), (14, 6 + 22 * k as i32), (FONT, 13).into_font()))?;
        }
        let areas = grid_area.split_evenly((1, panels.len()));
        let k = super::legible_scale(root.dim_in_pixel().0);
        for (area, panel) in areas.iter().zip(&panels) {
            draw_heat_panel(area, panel, k)?;
        }
        Ok(())
    }
}
