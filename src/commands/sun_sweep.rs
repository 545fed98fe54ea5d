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
//!   angle: the objective (by construction), `max_aliasing`, `coverage_violations`,
//!   `shimmer_snapped` and `shimmer` (highest of each), so the stability and coverage gates
//!   must hold at every sun angle.
//!
//! The recommendation, the Pareto front, the alternatives and the rivals then work on the
//! judged rows exactly as in a sweep without the sun. `sweep.csv` keeps every (sun, setting)
//! row, each equal to `analyze` of the config with that light direction.
//!
//! Row order: elevation (outermost), then azimuth, then the setting grid of
//! [`super::sweep::Grid::settings`]: all settings of one light direction are consecutive, so
//! the rows of one direction share one visibility pass.

use glam::DVec3;

use super::sweep::{parse_number_spec, Axis, Row};
use crate::config::sweep_spec::{sun_azimuth_ok, sun_elevation_ok};
use crate::config::Config;
use crate::error::Result;
use crate::metric::SummaryMetric;
use csm_core::sun::SunAngles;

/// A sun position of a sweep, in degrees as written on the command line or in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    /// Compass bearing from north (−Z) toward east (+X), degrees in [0, 360).
    pub azimuth_deg: f64,
    /// Angle above the horizon, degrees in (0, 90].
    pub elevation_deg: f64,
}

impl Sun {
    pub fn angles(self) -> SunAngles {
        SunAngles {
            azimuth: self.azimuth_deg.to_radians(),
            elevation: self.elevation_deg.to_radians(),
        }
    }

    /// The unit direction the light travels in under this sun ([`SunAngles::light_direction`]),
    /// with the components the degrees make exactly zero set to zero: at azimuth 90° the
    /// radians give cos = 6e-17, not 0, and a wall parallel to the light would then count as
    /// lit at a grazing angle (aliasing at the clamp, 1e6) at 270° but not at 90°.
    pub fn light_direction(self) -> DVec3 {
        let mut d = self.angles().light_direction();
        let whole = |x: f64, m: f64| x.rem_euclid(m) == 0.0;
        if whole(self.azimuth_deg, 180.0) || self.elevation_deg == 90.0 {
            d.x = 0.0; // sin a = 0 (north or south), or cos e = 0 (zenith)
        }
        if whole(self.azimuth_deg - 90.0, 180.0) || self.elevation_deg == 90.0 {
            d.z = 0.0; // cos a = 0 (east or west), or cos e = 0 (zenith)
        }
        d
    }

    /// The sun of a config's light (azimuth brought into [0, 360)).
    pub fn of_config(config: &Config) -> Sun {
        let a = SunAngles::of_light_direction(config.light_direction);
        let mut azimuth_deg = a.azimuth.to_degrees();
        if azimuth_deg < 0.0 {
            azimuth_deg += 360.0;
        }
        if azimuth_deg >= 360.0 {
            azimuth_deg = 0.0;
        }
        Sun {
            azimuth_deg,
            elevation_deg: a.elevation.to_degrees(),
        }
    }

    /// `azimuth 135°, elevation 40°`.
    pub fn label(self) -> String {
        format!("azimuth {}°, elevation {}°", self.azimuth_deg, self.elevation_deg)
    }
}

/// `--sun-azimuth 0:345:15` or a list, degrees in [0, 360).
pub fn parse_sun_azimuth_spec(spec: &str) -> Result<Axis<f64>> {
    parse_number_spec(
        "--sun-azimuth",
        spec,
        "[0, 360) degrees (compass bearing from north toward east)",
        sun_azimuth_ok,
    )
}

/// `--sun-elevation 5:85:5` or a list, degrees in (0, 90].
pub fn parse_sun_elevation_spec(spec: &str) -> Result<Axis<f64>> {
    parse_number_spec(
        "--sun-elevation",
        spec,
        "(0, 90] degrees above the horizon",
        sun_elevation_ok,
    )
}

/// The sun axes of a grid: what was swept (None: the configured light's angle) and the
/// configured sun.
#[derive(Debug, Clone, PartialEq)]
pub struct SunGrid {
    pub azimuth: Option<Axis<f64>>,
    pub elevation: Option<Axis<f64>>,
    /// The configured light's sun, for the axis not swept.
    pub configured: Sun,
}

impl SunGrid {
    /// The sun axes from the flags, else the `[sweep]` table; None when neither sweeps the sun.
    pub fn resolve(config: &Config, azimuth: Option<Axis<f64>>, elevation: Option<Axis<f64>>) -> Option<SunGrid> {
        let spec = config.sweep.as_ref();
        let azimuth = azimuth.or_else(|| spec.and_then(|s| s.sun_azimuth.clone()));
        let elevation = elevation.or_else(|| spec.and_then(|s| s.sun_elevation.clone()));
        (azimuth.is_some() || elevation.is_some()).then(|| SunGrid {
            azimuth,
            elevation,
            configured: Sun::of_config(config),
        })
    }

    pub fn azimuths(&self) -> Vec<f64> {
        self.azimuth
            .as_ref()
            .map_or_else(|| vec![self.configured.azimuth_deg], |a| a.values.clone())
    }

    pub fn elevations(&self) -> Vec<f64> {
        self.elevation
            .as_ref()
            .map_or_else(|| vec![self.configured.elevation_deg], |a| a.values.clone())
    }

    /// Every sun position in row order: elevation outer, azimuth inner.
    pub fn suns(&self) -> Vec<Sun> {
        let azimuths = self.azimuths();
        self.elevations()
            .into_iter()
            .flat_map(|e| {
                azimuths.iter().map(move |&a| Sun {
                    azimuth_deg: a,
                    elevation_deg: e,
                })
            })
            .collect()
    }

    pub fn len(&self) -> usize {
        self.azimuths().len() * self.elevations().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// ` --sun-azimuth A --sun-elevation E` for the swept axes.
    pub fn cli_args(&self) -> String {
        let mut out = String::new();
        if let Some(a) = &self.azimuth {
            out.push_str(&format!(" --sun-azimuth {}", a.spec));
        }
        if let Some(e) = &self.elevation {
            out.push_str(&format!(" --sun-elevation {}", e.spec));
        }
        out
    }
}

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
    pub fn rows_of(&self, j: usize) -> Vec<usize> {
        (0..self.all.len()).filter(|&i| self.setting_of[i] == j).collect()
    }
}

/// Reduces the rows of a sun sweep (in grid order) to one judged row per setting, in the order
/// settings first appear, by the worst-sun rule of this module.
pub fn judge(all: Vec<Row>, objective: SummaryMetric) -> (Vec<Row>, SunRows) {
    // A setting is its values without the sun (f64s by their exact Debug text).
    let mut ids: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut members: Vec<Vec<usize>> = Vec::new();
    let setting_of: Vec<usize> = all
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let key = format!("{:?}", super::sweep::Setting { sun: None, ..r.setting });
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
pub const SUN_RULE: &str = "the sun is a condition, not a setting: each setting is judged by its worst sun angle \
(the metrics of the angle where its objective is highest, with max_aliasing, coverage_violations, shimmer and \
shimmer_snapped the highest over every angle), so the recommendation, the Pareto front and the alternatives hold \
at every sun angle swept; sweep.csv has every (sun, setting) row";

/// What a bounds-only sun sweep says about the metrics the light cannot change, for stdout,
/// the report and the docs. None when the sweep has scene geometry (the visibility pass then
/// depends on the light).
pub fn bounds_only_note(config: &Config, fits: &[crate::config::Fit]) -> Option<String> {
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
    use crate::commands::sweep::Setting;
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
            },
            summary: Summary {
                light: None,
                truth: None,
                cascades_needed: true,
                z_lo: 1.0,
                z_hi: 2.0,
                max_aliasing: 10.0 - mean,
                mean_aliasing: mean,
                mean_log_aliasing: mean,
                undersampled_fraction: 0.0,
                shimmer,
                shimmer_snapped: shimmer,
                shimmer_unsnapped: 0.3,
                size_jitter: 0.0,
                coverage_violations: misses,
                memory_bytes: cascades as u64 * 4 * 1024 * 1024,
                lookup_error_max: 0.0,
                lookup_error_rms: 0.0,
                overlap_area_fraction: 0.0,
                band_pixel_share: 0.0,
                seam_crossings: None,
                screen: None,
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

    #[test]
    fn compass_points_give_exact_zeros_and_agree_with_the_core_convention() {
        let (s30, c30) = (0.5f64, 3f64.sqrt() / 2.0);
        for (a, want) in [
            (0.0, DVec3::new(0.0, -s30, c30)),
            (90.0, DVec3::new(-c30, -s30, 0.0)),
            (180.0, DVec3::new(0.0, -s30, -c30)),
            (270.0, DVec3::new(c30, -s30, 0.0)),
        ] {
            let d = Sun {
                azimuth_deg: a,
                elevation_deg: 30.0,
            }
            .light_direction();
            assert!((d - want).length() < 1e-15, "{a}: {d}");
            // The zero components are exactly zero.
            assert_eq!(d.x == 0.0, want.x == 0.0, "{a}: {d}");
            assert_eq!(d.z == 0.0, want.z == 0.0, "{a}: {d}");
        }
        let zenith = Sun {
            azimuth_deg: 45.0,
            elevation_deg: 90.0,
        }
        .light_direction();
        assert_eq!(zenith, DVec3::new(0.0, -1.0, 0.0));
        // Elsewhere it is the core's direction, bit for bit.
        let s = Sun {
            azimuth_deg: 135.0,
            elevation_deg: 40.0,
        };
        assert_eq!(s.light_direction(), s.angles().light_direction());
    }

    #[test]
    fn the_configured_sun_round_trips_and_specs_name_their_flag() {
        let text = include_str!("../../configs/default.toml")
            .replace("direction = [-0.4, -1.0, -0.3]", "direction = [0.4, -1.0, 0.3]");
        assert!(text.contains("[0.4, -1.0, 0.3]"));
        let config = crate::config::Config::from_toml_str(&text, "t.toml", None).unwrap();
        let sun = Sun::of_config(&config);
        // The sun stands north-west (toward −X and −Z): atan2(−0.4, 0.3) = −53.13°, wrapped.
        let want = 360.0 + (-0.4f64).atan2(0.3).to_degrees();
        assert!((sun.azimuth_deg - want).abs() < 1e-9 && want > 270.0, "{sun:?}");
        assert!((sun.light_direction() - config.light_direction).length() < 1e-12);
        assert_eq!(parse_sun_azimuth_spec("0:345:15").unwrap().values.len(), 24);
        assert_eq!(parse_sun_elevation_spec("5:85:5").unwrap().values.len(), 17);
        assert_eq!(parse_sun_elevation_spec("5:85:5").unwrap().values[16], 85.0);
        for (r, flag) in [
            (parse_sun_elevation_spec("0"), "--sun-elevation"),
            (parse_sun_elevation_spec("90.5"), "--sun-elevation"),
            (parse_sun_azimuth_spec("360"), "--sun-azimuth"),
            (parse_sun_azimuth_spec("0:90:0"), "--sun-azimuth"),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(e.starts_with(flag), "{e}");
        }
    }
}
