//! `sweep --ground-truth`: the measured flicker S5 beside the shimmer proxies S3 and S4 for a
//! sample of the sweep's rows (docs/ground-truth.md, "In a sweep").
//!
//! The ground-truth pass casts rays per receiver and frame, so a sweep runs it on at most
//! [`SAMPLE_MAX`] rows: every row of a small grid, else `SAMPLE_MAX` rows spread over the grid with the
//! recommended row among them ([`sample_indices`]). Nothing here writes a file.

use rayon::prelude::*;

use crate::analysis::ground_truth::{analyze_for_flicker, points_of, FlickerPoint};
use crate::commands::sweep::run::{in_pool, Row};
use crate::config::Config;
use crate::error::{GridError, Result};

/// The most rows a sweep computes S5 for (each row is a ground-truth pass; docs/speed.md gives
/// what a row costs on the default scene).
pub(crate) const SAMPLE_MAX: usize = 12;

/// The golden-ratio step (√5 − 1)/2 of the sample's low-discrepancy sequence.
pub(crate) const GOLDEN_STEP: f64 = 0.618_033_988_749_894_9;

/// The rows (indices into the sweep's rows, ascending) whose S5 a sweep computes: all of them
/// when there are at most [`SAMPLE_MAX`] (M rows, N = `SAMPLE_MAX`). Else, for k = 0..N in
/// turn, row `floor(M · frac(k · GOLDEN_STEP))`, moved on to the next row not yet taken
/// (wrapping to 0) when already taken; this spreads the sample over every axis of the grid,
/// where an even stride can fall on one λ value only (the default grid's 672 rows are 32 × 21
/// λ values). When the recommended row is not among them, the sampled row nearest to it (the
/// lower one on a tie) is replaced by it. The count is min(M, N) either way.
pub fn sample_indices(rows: usize, recommended: Option<usize>) -> Vec<usize> {
    if rows <= SAMPLE_MAX {
        return (0..rows).collect();
    }
    let mut s: Vec<usize> = Vec::with_capacity(SAMPLE_MAX);
    for k in 0..SAMPLE_MAX {
        let mut i = ((rows as f64 * (k as f64 * GOLDEN_STEP).fract()).floor() as usize).min(rows - 1);
        while s.contains(&i) {
            i = (i + 1) % rows;
        }
        s.push(i);
    }
    s.sort_unstable();
    if let Some(r) = recommended.filter(|&r| r < rows) {
        if !s.contains(&r) {
            // The first of the nearest: strictly smaller distances only replace it.
            let mut best = 0;
            for (j, &x) in s.iter().enumerate() {
                if x.abs_diff(r) < s[best].abs_diff(r) {
                    best = j;
                }
            }
            s[best] = r;
        }
    }
    s
}

/// One sampled row's proxies and measured flicker in both snap modes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampledRow {
    /// Index into the sweep's rows.
    pub index: usize,
    pub snapped: FlickerPoint,
    pub unsnapped: FlickerPoint,
}

/// The flicker of a sweep's sample.
#[derive(Debug, Clone)]
pub struct FlickerSample {
    /// The sweep's row count (M).
    pub rows: usize,
    /// The sampled rows ([`sample_indices`]).
    pub indices: Vec<usize>,
    /// The sampled rows that have cascades (a row whose scene needs none has no S5), in
    /// index order.
    pub measured: Vec<SampledRow>,
    /// The recommended row's ground-truth pass (its pictures go into the report), when the
    /// sweep recommends a row.
    pub recommended_truth: Option<std::sync::Arc<crate::analysis::ground_truth::GroundTruth>>,
    /// A level of views: the names of the views each row's S5 pools (the judged views,
    /// `crate::analysis::views_truth::judged`) and how many views the level has; empty and 0
    /// without configured views.
    pub views: Vec<String>,
    pub view_count: usize,
}

impl FlickerSample {
    /// "S5 computed for K of M rows: ..." (the stdout note and the reports' sentence).
    pub(crate) fn sentence(&self) -> String {
        let k = self.indices.len();
        let rule = if k == self.rows {
            format!("every row (the grid has at most {SAMPLE_MAX})")
        } else {
            format!(
                "rows {} (0-based, grid order), spread over the grid by the golden-ratio rule, with the recommended row among them",
                self.indices.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(", ")
            )
        };
        let missing = k - self.measured.len();
        let tail = if missing > 0 {
            format!("; {missing} of them need no cascades and have no S5")
        } else {
            String::new()
        };
        format!(
            "S5 computed for {k} of {} rows: {rule}{tail}{}",
            self.rows,
            self.views_clause()
        )
    }

    /// "; each row's S5 pools the ground truth of K of N views (names)" for a level; empty
    /// without views.
    pub(crate) fn views_clause(&self) -> String {
        if self.views.is_empty() {
            return String::new();
        }
        let all = crate::analysis::views_truth::chosen(self.views.len(), self.view_count);
        format!(
            "; each row's S5 pools the ground truth of {} of the level's {} views ({all}: {})",
            self.views.len(),
            self.view_count,
            self.views.join(", ")
        )
    }

    /// The snapped and unsnapped points, in row order (snapped first per row).
    pub(crate) fn points(&self) -> impl Iterator<Item = &FlickerPoint> {
        self.measured.iter().flat_map(|r| [&r.snapped, &r.unsnapped])
    }
}

/// Refuses `--ground-truth` (or `sweep.ground_truth`, named by `source`) for a config the pass
/// cannot sample: one without scene geometry, or one whose light moves.
pub(crate) fn refuse_ground_truth(result_config: &Config, source: &str) -> Result<()> {
    if result_config.geometry.is_none() {
        return Err(GridError::Unusable {
            context: source.to_string(),
            message: "the ground truth samples the shadow maps at receivers on scene geometry, and this config has \
                      none; add scene.ground, [[scene.box]] or scene.gltf, or leave it out"
                .to_string(),
        }
        .into());
    }
    if result_config.motion.light.moves() {
        return Err(GridError::Unusable {
            context: source.to_string(),
            message: format!("{MOVING_LIGHT}; leave it out or set motion.light_path = \"still\""),
        }
        .into());
    }
    crate::analysis::ground_truth::cost_fits(result_config, source)
}

/// Why the ground-truth pass refuses a moving light.
pub(crate) const MOVING_LIGHT: &str =
    "the ground-truth pass samples the maps under one still light, and motion.light_path moves the light";

/// Runs the ground-truth pass on the sampled rows of a finished sweep of `config` (its rows, and
/// the index of the recommended one), in `threads` threads or rayon's default pool, in index
/// order whatever the thread count.
pub(crate) fn measure(
    config: &Config,
    rows: &[Row],
    recommended: Option<usize>,
    threads: Option<usize>,
) -> Result<FlickerSample> {
    let indices = sample_indices(rows.len(), recommended);
    let work = || {
        indices
            .par_iter()
            .map(|&i| {
                let a = analyze_for_flicker(&rows[i].setting.apply(config)?);
                let row = match points_of(&a).as_slice() {
                    [s, u] => Some(SampledRow {
                        index: i,
                        snapped: *s,
                        unsnapped: *u,
                    }),
                    _ => None,
                };
                // The recommended row is always sampled: its pass is kept for the report's
                // pictures rather than run again.
                let truth = (Some(i) == recommended).then_some(a.ground_truth).flatten();
                Ok((row, truth))
            })
            .collect::<Result<Vec<_>>>()
    };
    let (mut sampled, mut recommended_truth) = (Vec::new(), None);
    for (row, truth) in in_pool(threads, work)? {
        sampled.extend(row);
        recommended_truth = recommended_truth.or(truth.map(std::sync::Arc::new));
    }
    Ok(FlickerSample {
        rows: rows.len(),
        indices,
        measured: sampled,
        recommended_truth,
        views: crate::analysis::views_truth::judged_names(config),
        view_count: config.views.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_grid_is_sampled_whole() {
        assert_eq!(sample_indices(5, Some(3)), vec![0, 1, 2, 3, 4]);
        assert_eq!(sample_indices(SAMPLE_MAX, None).len(), SAMPLE_MAX);
        assert!(sample_indices(0, None).is_empty());
    }

    #[test]
    fn a_large_grid_is_spread_with_the_recommended_row() {
        // 672 rows (the default grid): floor(672 · frac(k · 0.618...)), k = 0..12, sorted.
        let plain = [0, 60, 121, 158, 219, 317, 377, 415, 475, 536, 573, 634];
        assert_eq!(sample_indices(672, Some(415)), plain);
        assert_eq!(sample_indices(672, None), plain);
        // Row 90 is 30 from 60 and 31 from 121: 60 goes; 140 is 18 from 158: 158 goes.
        assert_eq!(&sample_indices(672, Some(90))[..3], &[0, 90, 121]);
        assert_eq!(&sample_indices(672, Some(140))[..5], &[0, 60, 121, 140, 219]);
        // A tie replaces the lower: row 30 is 30 from both 0 and 60.
        assert_eq!(&sample_indices(672, Some(30))[..3], &[30, 60, 121]);
        // Beyond the last sample.
        assert_eq!(sample_indices(672, Some(671))[11], 671);
        // Just above N rows the sequence collides and moves on: still N distinct rows.
        let s = sample_indices(13, None);
        assert_eq!(s, [0, 1, 2, 3, 4, 6, 7, 8, 9, 10, 11, 12]);
        assert!(s.windows(2).all(|w| w[0] < w[1]));
    }
}
