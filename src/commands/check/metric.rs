//! The metrics a threshold rule can limit, what each one means, and which direction is worse.
//!
//! Three kinds:
//! - **summary** metrics: one number per configuration, every field of
//!   [`crate::analysis::Summary`], defined in the registry [`crate::metric`];
//! - **per-cascade** metrics: one number per cascade, fields of
//!   [`crate::analysis::CascadeReport`], also in the registry;
//! - **per-depth** metrics: functions of view depth (`aliasing`, `texels_per_pixel`), limited
//!   over a depth range and evaluated exactly by [`super::depth`].
//!
//! `max_aliasing`, `coverage_violations`, `lookup_error_max` and `lookup_error_rms` exist both as
//! summary and as per-cascade metrics;
//! a rule picks the per-cascade one only when it says `cascade = ...`.
//!
//! The "worse" direction is what a baseline comparison uses to call a change a regression or
//! an improvement. [`Direction::Neither`] marks positions (depths, light-space depths) that
//! describe where something is rather than how good it is: they can still be limited by rules,
//! and a baseline reports their changes, but never as regressions.

pub use crate::metric::{summary_values, SummaryMetric};
pub(crate) use crate::metric::{CascadeMetric, Direction};

/// A function of view depth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthMetric {
    /// `a(d) = K T_i / d`: shadow texel size over screen pixel size. Higher is worse (blockier).
    Aliasing,
    /// `1 / a(d)`: texels per pixel along one axis. Lower is worse.
    TexelsPerPixel,
}

impl DepthMetric {
    pub(crate) const ALL: [DepthMetric; 2] = [DepthMetric::Aliasing, DepthMetric::TexelsPerPixel];

    pub(crate) fn name(self) -> &'static str {
        match self {
            DepthMetric::Aliasing => "aliasing",
            DepthMetric::TexelsPerPixel => "texels_per_pixel",
        }
    }

    pub(crate) fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    pub fn direction(self) -> Direction {
        match self {
            DepthMetric::Aliasing => Direction::HigherIsWorse,
            DepthMetric::TexelsPerPixel => Direction::LowerIsWorse,
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            DepthMetric::Aliasing => "shadow texel size over screen pixel size at a view depth",
            DepthMetric::TexelsPerPixel => "screen pixel size over shadow texel size at a view depth",
        }
    }
}

/// Every metric name a rule may use, each once, in catalogue order.
pub(crate) fn all_names() -> Vec<&'static str> {
    let mut names: Vec<&'static str> = SummaryMetric::all().map(|m| m.name()).collect();
    for n in CascadeMetric::all().map(|m| m.name()) {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    names.extend(DepthMetric::ALL.iter().map(|m| m.name()));
    names
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{CascadeReport, Summary};
    use crate::suggest::{closest, edit_distance};

    #[test]
    fn closest_name_recovers_single_typos() {
        let names = all_names();
        for n in &names {
            let mid = n.len() / 2;
            // Drop one character, or double it: one edit away from the original.
            for typo in [
                format!("{}{}", &n[..mid], &n[mid + 1..]),
                format!("{}{}", &n[..=mid], &n[mid..]),
            ] {
                let got = closest(&typo, &names).unwrap();
                let at_one: Vec<&str> = names.iter().copied().filter(|c| edit_distance(&typo, c) == 1).collect();
                assert!(at_one.contains(n), "{typo}");
                assert!(names.iter().all(|c| edit_distance(&typo, c) >= 1));
                assert!(at_one.contains(&got), "{typo} -> {got}");
                if at_one.len() == 1 {
                    assert_eq!(got, *n, "{typo}");
                }
            }
        }
        assert_eq!(closest("texel_sise", &names), Some("texel_size"));
        assert_eq!(closest("texel_per_pixel", &names), Some("texels_per_pixel"));
    }

    #[test]
    fn summary_metrics_are_exactly_the_fields_of_summary() {
        let s = Summary {
            cascades_needed: true,
            z_lo: 1.0,
            z_hi: 2.0,
            max_aliasing: 3.0,
            mean_aliasing: 4.0,
            mean_log_aliasing: 5.0,
            undersampled_fraction: 0.25,
            shimmer: 6.0,
            shimmer_snapped: 6.0,
            shimmer_unsnapped: 7.0,
            size_jitter: 8.0,
            coverage_violations: 9,
            memory_bytes: 10,
            lookup_error_max: 11.0,
            lookup_error_rms: 12.0,
            overlap_area_fraction: 0.125,
            band_pixel_share: 0.0,
            seam_crossings: Some(0.375),
            screen: None,
            light: Some(crate::analysis::LightSummary {
                crawl: 0.5,
                crawl_snapped: 0.5,
                crawl_unsnapped: 0.75,
                jump: 1.5,
                jump_snapped: 1.5,
                jump_unsnapped: 1.25,
            }),
            truth: None,
            views: Vec::new(),
            view_ranks: Vec::new(),
            cache: Some(crate::analysis::CacheSummary {
                renders_per_frame: 2.75,
                figures: crate::analysis::StaleFigures {
                    stale_coverage_violations: 13,
                    stale_coverage_fraction: 0.0625,
                    stale_margin: 14.5,
                    stale_margin_world: 15.5,
                    update_drift: 0.4375,
                    update_flicker: None,
                },
            }),
            cost: Default::default(),
        };
        let json = serde_json::to_value(&s).unwrap();
        // The registry writes every key as serde would (same JSON type: bool, integer, float).
        for (k, v) in crate::metric::summary_json(&s) {
            assert_eq!(json[k], v, "{k}");
        }
        // Without scene geometry the screen metrics are not written (serde, which stores shard
        // rows losslessly, keeps the band share; the registry leaves it out here).
        let keys: Vec<&str> = json
            .as_object()
            .unwrap()
            .keys()
            .map(|k| k.as_str())
            .filter(|k| *k != "screen_band_pixel_share")
            .collect();
        let mut names: Vec<&str> = SummaryMetric::all()
            .filter(|m| !m.def().screen)
            .map(|m| m.name())
            .collect();
        names.sort_unstable();
        let mut keys_sorted = keys.clone();
        keys_sorted.sort_unstable();
        assert_eq!(keys_sorted, names);
        for (m, v) in summary_values(&s).into_iter().filter(|(m, _)| !m.def().screen) {
            let j = &json[m.name()];
            let expected = j.as_f64().or_else(|| j.as_bool().map(|b| if b { 1.0 } else { 0.0 }));
            assert_eq!(Some(v), expected, "{}", m.name());
        }
    }

    #[test]
    fn cascade_metrics_are_the_numeric_fields_of_cascade_report() {
        let c = CascadeReport {
            cascade: 0,
            near: 1.0,
            far: 2.0,
            radius: 3.0,
            width: 4.0,
            height: 5.0,
            texel_size: 6.0,
            // Window centres: positions, reported beside the metrics.
            centre_x: 0.25,
            centre_y: 0.5,
            centre_x_texels: 0.75,
            centre_y_texels: 1.25,
            light_near: 7.0,
            light_far: 8.0,
            coverage_violations: 9,
            coverage_worst_texels: 10.0,
            min_slack_texels: 11.0,
            max_aliasing: 12.0,
            min_aliasing: 13.0,
            lookup_error_max: 14.0,
            lookup_error_rms: 15.0,
            split_jump: 16.0,
            band_near: 17.0,
            band_far: 18.0,
            overlap_area_fraction: 0.5,
            screen: None,
            light: Some(crate::analysis::CascadeLight {
                crawl: 0.25,
                jump: 1.75,
            }),
            truth: None,
            cache: Some(crate::analysis::CascadeCache {
                update_every: 4,
                update_rate: 0.25,
                figures: crate::analysis::StaleFigures {
                    stale_coverage_violations: 19,
                    stale_coverage_fraction: 0.0078125,
                    stale_margin: 20.5,
                    stale_margin_world: 21.5,
                    update_drift: 0.3125,
                    update_flicker: None,
                },
            }),
            cost: Default::default(),
        };
        let json = serde_json::to_value(&c).unwrap();
        let obj = json.as_object().unwrap();
        let plain = || CascadeMetric::all().filter(|m| !m.def().screen);
        assert_eq!(obj.len(), plain().count() + 1, "every field but `cascade`");
        for m in plain() {
            assert_eq!(obj[m.name()].as_f64(), Some(m.value(&c)), "{}", m.name());
        }
    }

    #[test]
    fn every_name_resolves_to_its_own_metric() {
        for m in SummaryMetric::all() {
            assert_eq!(SummaryMetric::from_name(m.name()), Some(m));
        }
        for m in CascadeMetric::all() {
            assert_eq!(CascadeMetric::from_name(m.name()), Some(m));
        }
        for m in DepthMetric::ALL {
            assert_eq!(DepthMetric::from_name(m.name()), Some(m));
        }
        let names = all_names();
        let mut dedup = names.clone();
        dedup.sort_unstable();
        dedup.dedup();
        assert_eq!(dedup.len(), names.len());
        // Thirty-one names are both summary and per-cascade metrics (max_aliasing,
        // coverage_violations, lookup_error_max, lookup_error_rms, overlap_area_fraction,
        // light_crawl, light_jump, acne_fraction, edge_error_fraction, leak_fraction, the
        // cached cascades' stale_coverage_violations, stale_coverage_fraction, stale_margin,
        // stale_margin_world, update_drift, update_flicker, the eight cost metrics:
        // caster_objects, caster_triangles, caster_triangles_inside, raster_fragments,
        // texels_cleared, bytes_written, cost_index, shadow_ms, and their seven means over the
        // path: caster_objects_mean, ..., texels_cleared_mean, cost_index_mean, shadow_ms_mean).
        assert_eq!(
            names.len(),
            SummaryMetric::all().count() + CascadeMetric::all().count() - 31 + DepthMetric::ALL.len()
        );
    }

    #[test]
    fn worsening_follows_the_direction() {
        assert_eq!(Direction::HigherIsWorse.worsening(1.0, 3.0), Some(2.0));
        assert_eq!(Direction::LowerIsWorse.worsening(1.0, 3.0), Some(-2.0));
        assert_eq!(Direction::Neither.worsening(1.0, 3.0), None);
        assert_eq!(
            CascadeMetric::named("min_slack_texels").direction(),
            Direction::LowerIsWorse
        );
        assert_eq!(DepthMetric::TexelsPerPixel.direction(), Direction::LowerIsWorse);
        assert_eq!(
            SummaryMetric::named("max_aliasing").direction(),
            Direction::HigherIsWorse
        );
    }
}
