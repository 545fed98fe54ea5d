//! Running a sweep: every setting of a grid analysed in parallel. Rows come out in grid order
//! whatever the thread count (rayon's indexed `collect` keeps order), so files are
//! byte-identical.

use rayon::prelude::*;

use crate::analysis::{analyze, AnalysisOptions, Summary, ViewDetail};
use crate::commands::sweep::grid::{Grid, Setting};
use crate::config::Config;
use crate::error::{Error, GridError, Result};

/// One row of `sweep.csv`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Row {
    pub setting: Setting,
    pub summary: Summary,
}

/// Runs the full analysis of every setting in parallel. `threads` = None uses rayon's default
/// pool; `on_done` is called once per finished configuration (progress bars).
pub fn run(base: &Config, grid: &Grid, threads: Option<usize>, on_done: &(dyn Fn() + Sync)) -> Result<Vec<Row>> {
    run_settings(base, &grid.settings(), cost_means(base, grid), threads, on_done)
}

/// Whether a sweep's rows measure the cost counts' means over the camera path
/// (`AnalysisOptions::cost_means`): when `[sweep] cost_means = true`, or when a setting of the
/// grid caches cascades (`shadow.update_every` in the config or on the axis), whose saving the
/// means show. Decided for the whole grid, so every row (and every shard) has the same columns.
pub(crate) fn cost_means(base: &Config, grid: &Grid) -> bool {
    base.sweep.as_ref().is_some_and(|s| s.cost_means)
        || base.shadow.update_every.is_some()
        || grid
            .update_every
            .as_ref()
            .is_some_and(|a| a.values.iter().any(|u| u.update_every().caching().is_some()))
}

/// [`run`] over some settings of a grid (a shard's slice), in their order; `cost_means` as
/// [`cost_means`] decided it for the whole grid.
pub(crate) fn run_settings(
    base: &Config,
    settings: &[Setting],
    cost_means: bool,
    threads: Option<usize>,
    on_done: &(dyn Fn() + Sync),
) -> Result<Vec<Row>> {
    // Every point is built and checked before any analysis runs: a setting the config could
    // not hold (an f32 window that collapses at this fit, say) is refused like the file would be.
    // The configs are built again in the parallel part rather than kept: a 100,000-point grid
    // would otherwise hold 100,000 configs at once.
    let point = |s: &Setting| {
        s.apply(base).map_err(|e| {
            Error::from(GridError::Point {
                point: s.label(),
                source: Box::new(e),
            })
        })
    };
    // A level's rows keep of each view only what the ranking of the views reads: its own
    // value of the statistic the sweep's objective is, its worst case and whether it sees a
    // receiver (the one row that shows the views is measured in full by `SweepResult::new`).
    let views = ViewDetail::Ranking(crate::metric::sweep_objective(base).screen_statistic());
    let mut warmed_views = None;
    // Without scene geometry and views there is nothing to warm: the points are built once,
    // in the parallel part, whose first refused point in grid order is the error (the same
    // error this loop would stop at).
    let warm = base.geometry.is_some() || !base.views.is_empty();
    for s in settings.iter().filter(|_| warm) {
        // The visibility pass is made once, before the parallel part, and shared by every row.
        // Under swept sun angles only its rays are: each angle shades them in the parallel
        // part (the rows of one angle are consecutive and share that shading).
        let config = point(s)?;
        let setup = config.setup();
        if s.sun.is_some() {
            let _ = setup.visibility_hits();
        } else {
            let _ = setup.visibility();
        }
        // A level's views: one pass per view (per sun angle: its rays), for every row.
        if !config.views.is_empty() && warmed_views != Some(s.sun) {
            crate::analysis::warm_views(&config, s.sun.is_some());
            warmed_views = Some(s.sun);
        }
    }
    // The settings that differ in resolution alone are evaluated together, one after the
    // other on one thread: their cascades serve the same pixels (the splits do not depend on
    // the resolution), which each thread keeps for the next (csm_core::screen). The rows are
    // placed back by index, so they come out in grid order whatever the grouping.
    let groups = resolution_groups(settings);
    let work = || {
        let done = groups
            .par_iter()
            .map(|group| {
                let configs: Vec<_> = group.iter().map(|&k| point(&settings[k])).collect();
                // Their frame-0 render-cost counts in one walk per cascade (docs/cost.md).
                crate::analysis::cost::count_together(&configs.iter().flatten().collect::<Vec<_>>());
                let mut last = None;
                let rows = group
                    .iter()
                    .zip(configs)
                    .map(|(&k, config)| {
                        let s = &settings[k];
                        let opts = AnalysisOptions {
                            cost_means,
                            views,
                            ..AnalysisOptions::summary_only()
                        };
                        let row = config.map(|config| {
                            let row = Row {
                                setting: *s,
                                summary: analyze(&config, &opts).summary,
                            };
                            last = Some(config);
                            row
                        });
                        on_done();
                        (k, row)
                    })
                    .collect::<Vec<_>>();
                crate::analysis::cost::count_together(&[]);
                // The split set is done: what its pools kept for its other resolutions goes.
                if let Some(config) = last {
                    crate::analysis::split_set_done(&config);
                }
                rows
            })
            .collect::<Vec<_>>();
        // Every row is placed at its index; the first refused point in grid order is the error.
        let mut rows: Vec<Option<Result<Row>>> = (0..settings.len()).map(|_| None).collect();
        for (k, row) in done.into_iter().flatten() {
            rows[k] = Some(row);
        }
        rows.into_iter().flatten().collect::<Result<Vec<_>>>()
    };
    in_pool(threads, work)
}

/// The indices of `settings` grouped by every axis but the resolution: the groups in the order
/// of their first setting, each group's settings in their order.
fn resolution_groups(settings: &[Setting]) -> Vec<Vec<usize>> {
    let mut at: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, s) in settings.iter().enumerate() {
        // Debug prints every float so that it reads back exactly: equal keys, equal settings.
        let key = format!("{:?}", Setting { resolution: 0, ..*s });
        let g = *at.entry(key).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(k);
    }
    groups
}

/// Runs `work` in a pool of `threads` threads (`--threads`), or in rayon's default pool. The
/// one place a command builds a pool; a failure names the flag.
pub(crate) fn in_pool<T: Send>(threads: Option<usize>, work: impl FnOnce() -> Result<T> + Send) -> Result<T> {
    match threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| {
                Error::flag(
                    "--threads",
                    &n.to_string(),
                    format!("cannot start the thread pool: {e}"),
                )
            })?
            .install(work),
        None => work(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Fit;

    /// The groups are a partition of the settings: each setting once, a group's settings equal
    /// but for the resolution and in their order, no two groups equal but for the resolution,
    /// and the groups in the order of their first settings; over a grid with resolution
    /// between other axes and a value repeated.
    #[test]
    fn resolution_groups_partition_the_settings_by_every_other_axis() {
        let mut settings = Vec::new();
        for fit in [Fit::Sphere, Fit::Aabb] {
            for res in [512, 1024, 2048] {
                for cascades in [1, 3] {
                    for lambda in [0.1, 0.5, 0.1 + 0.2] {
                        settings.push(Setting::plain(lambda, cascades, res, fit));
                    }
                }
            }
        }
        settings.push(Setting::plain(0.5, 3, 4096, Fit::Sphere));
        let groups = resolution_groups(&settings);
        let mut seen = vec![0; settings.len()];
        let strip = |s: &Setting| Setting { resolution: 0, ..*s };
        for g in &groups {
            assert!(g.windows(2).all(|w| w[0] < w[1]), "{g:?}");
            for &k in g {
                seen[k] += 1;
                assert_eq!(strip(&settings[k]), strip(&settings[g[0]]));
            }
        }
        assert!(seen.iter().all(|&n| n == 1), "{seen:?}");
        for (a, ga) in groups.iter().enumerate() {
            for gb in &groups[a + 1..] {
                assert_ne!(strip(&settings[ga[0]]), strip(&settings[gb[0]]));
                assert!(ga[0] < gb[0]);
            }
        }
        // 2 fits x 2 cascade counts x 3 λ; the one 4096 setting joins its 512..2048 group.
        assert_eq!(groups.len(), 12);
        let with_4096 = groups.iter().find(|g| g.contains(&(settings.len() - 1))).unwrap();
        assert_eq!(with_4096.len(), 4);
    }
}
