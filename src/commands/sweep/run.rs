//! Running a sweep: every setting of a grid analysed in parallel. Rows come out in grid order
//! whatever the thread count (rayon's indexed `collect` keeps order), so files are
//! byte-identical.

use rayon::prelude::*;

use crate::analysis::{analyze, AnalysisOptions, Summary};
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
    let work = || {
        settings
            .par_iter()
            .map(|s| {
                let opts = AnalysisOptions {
                    cost_means,
                    ..AnalysisOptions::summary_only()
                };
                let a = analyze(&point(s)?, &opts);
                on_done();
                Ok(Row {
                    setting: *s,
                    summary: a.summary,
                })
            })
            .collect::<Vec<Result<Row>>>()
            .into_iter()
            .collect::<Result<Vec<_>>>()
    };
    in_pool(threads, work)
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
