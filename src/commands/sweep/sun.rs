//! Sun-angle sweeps: `--sun-azimuth` and `--sun-elevation` (or `[sweep] sun_azimuth` and
//! `sun_elevation`) run every setting of a grid under every sun position of the two axes.
//!
//! The sun is a condition the shadows must hold under, not a knob a user picks: a setting is
//! judged by its **worst** sun angle. For each setting the rows of all its sun angles are
//! reduced to one judged row ([`judge`]):
//!
//! - its metrics are those of the sun angle where the objective is highest (ties: the first
//!   angle in grid order), and that angle is the setting's **worst sun**;
//! - the values the recommendation rule tests or breaks ties with are the worst over every
//!   angle: the objective (by construction), `max_aliasing`, `screen_aliasing_max` (the worst
//!   case with geometry), `coverage_violations`,
//!   `shimmer_snapped` and `shimmer` (highest of each), so the stability and coverage gates
//!   must hold at every sun angle.
//!
//! The recommendation, the Pareto front, the alternatives and the rivals then work on the
//! judged rows exactly as in a sweep without the sun. `sweep.csv` keeps every (sun, setting)
//! row, each equal to `analyze` of the config with that light direction.
//!
//! Row order: elevation (outermost), then azimuth, then the setting grid of
//! [`crate::commands::sweep::grid::Grid::settings`]: all settings of one light direction are consecutive, so
//! the rows of one direction share one visibility pass.

use crate::commands::sweep::grid::Setting;
use crate::commands::sweep::run::Row;
use crate::config::Config;
use crate::metric::SummaryMetric;

/// Every (sun, setting) row of a sun sweep and, per setting, where its worst sun is.
#[derive(Debug, Clone, PartialEq)]
pub struct SunRows {
    /// Every row in grid order (in a whole grid, row `k * settings + j` is setting `j` under
    /// sun `k`; a shard holds a slice).
    pub all: Vec<Row>,
    /// Per row of `all`, its setting: the index of its judged row.
    pub setting_of: Vec<usize>,
    /// Per setting, the index in `all` of its worst sun's row.
    pub worst: Vec<usize>,
}

impl SunRows {
    /// The indices in `all` of setting `j`'s rows, one per sun angle, in sun order.
    pub(crate) fn rows_of(&self, j: usize) -> Vec<usize> {
        (0..self.all.len()).filter(|&i| self.setting_of[i] == j).collect()
    }
}

/// Reduces the rows of a sun sweep (in grid order) to one judged row per setting, in the order
/// settings first appear, by the worst-sun rule of this module.
pub(crate) fn judge(all: Vec<Row>, objective: SummaryMetric) -> (Vec<Row>, SunRows) {
    // A setting is its values without the sun (f64s by their exact Debug text).
    let mut ids: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    let setting_of: Vec<usize> = all
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let key = format!("{:?}", Setting { sun: None, ..r.setting });
            let j = *ids.entry(key).or_insert_with(|| {
                members.push(Vec::new());
                members.len() - 1
            });
            members[j].push(i);
            j
        })
        .collect();
    let mut judged = Vec::with_capacity(members.len());
    let mut worst = Vec::with_capacity(members.len());
    for idx in &members {
        // The worst angle among those that need cascades (all of them, or none, in practice:
        // whether the scene needs cascades does not depend on the light).
        let needed: Vec<usize> = idx
            .iter()
            .copied()
            .filter(|&i| all[i].summary.cascades_needed)
            .collect();
        let pool = if needed.is_empty() { idx } else { &needed };
        let w = pool.iter().copied().fold(pool[0], |best, i| {
            if objective.value(&all[i].summary) > objective.value(&all[best].summary) {
                i
            } else {
                best
            }
        });
        let mut row = all[w].clone();
        let s = &mut row.summary;
        for &i in pool {
            let x = &all[i].summary;
            s.max_aliasing = s.max_aliasing.max(x.max_aliasing);
            // The worst case on screen (`screen_aliasing_max`), which breaks ties with geometry.
            if let (Some(st), Some(xs)) = (s.screen.as_mut(), x.screen.as_ref()) {
                st.aliasing_max = st.aliasing_max.max(xs.aliasing_max);
            }
            s.coverage_violations = s.coverage_violations.max(x.coverage_violations);
            s.shimmer_snapped = s.shimmer_snapped.max(x.shimmer_snapped);
            s.shimmer = s.shimmer.max(x.shimmer);
            if let (Some(l), Some(xl)) = (s.light.as_mut(), x.light) {
                // The stability gate under a moving light reads the crawl (`snapped_drift`).
                l.crawl_snapped = l.crawl_snapped.max(xl.crawl_snapped);
                l.crawl = l.crawl.max(xl.crawl);
            }
        }
        judged.push(row);
        worst.push(w);
    }
    (judged, SunRows { all, setting_of, worst })
}

/// The worst-sun rule in words (reports, `recommendation.json`).
pub(crate) const SUN_RULE: &str =
    "the sun is a condition, not a setting: each setting is judged by its worst sun angle \
(the metrics of the angle where its objective is highest, with max_aliasing, screen_aliasing_max, \
coverage_violations, shimmer and shimmer_snapped the highest over every angle), so the recommendation, the Pareto front and the alternatives hold \
at every sun angle swept; sweep.csv has every (sun, setting) row";

/// What a bounds-only sun sweep says about the metrics the light cannot change, for stdout,
/// the report and the docs. None when the sweep has scene geometry (the visibility pass then
/// depends on the light).
pub(crate) fn bounds_only_note(config: &Config, fits: &[crate::config::Fit]) -> Option<String> {
    if config.geometry.is_some() {
        return None;
    }
    let sphere_only = fits.iter().all(|f| *f == crate::config::Fit::Sphere);
    Some(format!(
        "bounds only: the depth range, the splits and the memory cannot depend on the light, and with a sphere \
         fit neither can the texel size, so neither can the texel density and aliasing metrics (max_aliasing, \
         mean_aliasing, mean_log_aliasing, undersampled_fraction); what the sun changes is the light-space depth \
         range, the windows of AABB fits (and with them their aliasing, coverage and shimmer) and the unsnapped \
         shimmer of every fit{}",
        if sphere_only {
            ". Every setting here has a sphere fit: its aliasing is the same at every sun angle"
        } else {
            ""
        }
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::Summary;
    use crate::commands::sweep::grid::Sun;
    use crate::config::{Fit, SplitRange};

    fn row(cascades: usize, sun: Sun, mean: f64, shimmer: f64, misses: u64) -> Row {
        Row {
            setting: Setting {
                lambda: 0.5,
                cascades,
                resolution: 1024,
                fit: Fit::Sphere,
                split_range: SplitRange::Bounds,
                knob: None,
                distance: None,
                sun: Some(sun),
                light_update: None,
                update_every: None,
            },
            summary: Summary {
                cascades_needed: true,
                z_lo: 1.0,
                z_hi: 2.0,
                max_aliasing: 10.0 - mean,
                mean_aliasing: mean,
                mean_log_aliasing: mean,
                shimmer,
                shimmer_snapped: shimmer,
                shimmer_unsnapped: 0.3,
                coverage_violations: misses,
                ..Summary::nothing_needed(cascades as u64 * 4 * 1024 * 1024)
            },
        }
    }

    #[test]
    fn judging_takes_the_worst_angle_and_the_worst_gate_values_of_each_setting() {
        let mut rng = csm_core::rng::SplitMix64::new(3);
        let suns: Vec<Sun> = (0..6)
            .map(|k| Sun {
                azimuth_deg: 60.0 * k as f64,
                elevation_deg: 30.0,
            })
            .collect();
        for _ in 0..100 {
            let all: Vec<Row> = suns
                .iter()
                .flat_map(|&sun| {
                    (1..=3)
                        .map(|c| {
                            // Ties on purpose: means on a coarse grid.
                            let mean = (rng.unit() * 4.0).round();
                            let shimmer = if rng.unit() < 0.2 { 0.01 } else { 0.0 };
                            let misses = u64::from(rng.unit() < 0.1);
                            row(c, sun, mean, shimmer, misses)
                        })
                        .collect::<Vec<_>>()
                })
                .collect();
            let (judged, sun_rows) = judge(all.clone(), SummaryMetric::named("mean_aliasing"));
            assert_eq!(judged.len(), 3);
            assert_eq!(sun_rows.setting_of, (0..all.len()).map(|i| i % 3).collect::<Vec<_>>());
            for (j, x) in judged.iter().enumerate() {
                let mine: Vec<&Row> = all.iter().filter(|r| r.setting.cascades == j + 1).collect();
                let max = mine.iter().map(|r| r.summary.mean_aliasing).fold(f64::MIN, f64::max);
                // The first angle (in sun order) with the largest objective.
                let first = mine.iter().position(|r| r.summary.mean_aliasing == max).unwrap();
                assert_eq!(x.setting.sun, Some(suns[first]));
                assert_eq!(sun_rows.worst[j], first * 3 + j);
                assert_eq!(x.summary.mean_aliasing, max);
                let most = |f: fn(&Row) -> f64| mine.iter().map(|r| f(r)).fold(f64::MIN, f64::max);
                assert_eq!(x.summary.max_aliasing, most(|r| r.summary.max_aliasing));
                assert_eq!(x.summary.shimmer_snapped, most(|r| r.summary.shimmer_snapped));
                assert_eq!(x.summary.shimmer, most(|r| r.summary.shimmer));
                assert_eq!(
                    x.summary.coverage_violations as f64,
                    most(|r| r.summary.coverage_violations as f64)
                );
                assert_eq!(sun_rows.rows_of(j).len(), 6);
            }
        }
    }
}
