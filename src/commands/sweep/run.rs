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
    run_settings(base, &grid.settings(), threads, on_done)
}

/// [`run`] over some settings of a grid (a shard's slice), in their order.
pub(crate) fn run_settings(
    base: &Config,
    settings: &[Setting],
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
    for s in settings {
        // The visibility pass is made once, before the parallel part, and shared by every row.
        // Under swept sun angles only its rays are: each angle shades them in the parallel
        // part (the rows of one angle are consecutive and share that shading).
        let setup = point(s)?.setup();
        if s.sun.is_some() {
            let _ = setup.visibility_hits();
        } else {
            let _ = setup.visibility();
        }
    }
    let work = || {
        settings
            .par_iter()
            .map(|s| {
                let a = analyze(&point(s)?, &AnalysisOptions::summary_only());
                on_done();
                Ok(Row {
                    setting: *s,
                    summary: a.summary,
                })
            })
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
