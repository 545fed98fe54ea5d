//! The analysis the free-split search evaluates (`sweep --optimize-splits`, docs/optimize.md):
//! only what its cost reads of a point.
//!
//! The search's cost of a point reads four values of its summary: whether the scene needs
//! cascades, the coverage misses and the snapped drift (whether the point is acceptable), and
//! the objective. Each evaluation used to be the whole analysis a sweep row gets; most of that
//! is read by no one during the search: the render-cost counts, the screen statistics other
//! than the objective's, the preset's report. [`summary`] leaves them out and computes the rest
//! exactly as [`super::analyze`] does (the same functions on the same values), so every field
//! it computes is the full analysis' value bit for bit (`tests/it/optimize.rs` checks the
//! objective and the acceptance on random split vectors for every metric of the registry).
//! The points the search reports (the start, the preset's configured split, the optimum as
//! printed) are analysed in full.

use std::sync::Arc;

use super::{analyze, analyze_camera, visible_depths, AnalysisOptions, Detail, Summary};
use crate::config::Config;
use csm_core::depth_range::{self, DepthRange};
use csm_core::screen::{self, ScreenStats, Statistic};
use csm_core::visibility::Visibility;

/// What every point of one group of the search has in common, computed once for the group
/// instead of once (or, for the split range, four times) per point: the points of a group
/// differ only in their split fractions, and none of these reads them.
///
/// - the split range of csm-lab's own pipeline (`depth_range::for_setup`: the camera, the
///   shadow distance, the scene's bounds and the fit flags; a preset's range follows its own
///   rig, so it is computed per point as before);
/// - the visibility pass and the visible depth range within the bounds' range.
///
/// (The camera path's poses are shared too, by `walk_path`'s per-thread held path.)
///
/// Each is the value the point's own analysis computes from the same inputs, so a point
/// analysed with them is bit for bit the point analysed alone (tested on random split
/// vectors, `commands::sweep::optimize`).
pub(crate) struct Shared {
    range: Option<DepthRange>,
    visibility: Option<Arc<Visibility>>,
    visible: Option<(f64, f64)>,
}

impl Shared {
    /// For the points of `point`'s group (`point` with any split fractions).
    pub(crate) fn of(point: &Config) -> Shared {
        let setup = point.setup();
        let visibility = setup.visibility();
        Shared {
            range: point.shadow.preset.is_none().then(|| depth_range::for_setup(&setup)),
            visible: visible_depths(&setup, visibility.as_deref()),
            visibility,
        }
    }

    /// The split range of `config` (one of the group's points), when it is shared.
    pub(super) fn range(&self, config: &Config) -> Option<DepthRange> {
        self.range.filter(|_| config.shadow.preset.is_none())
    }

    /// The visibility pass and the visible depth range.
    pub(super) fn visibility(&self) -> (Option<Arc<Visibility>>, Option<(f64, f64)>) {
        (self.visibility.clone(), self.visible)
    }
}

/// What the search's objective reads of a point's analysis, beyond the walk along the camera
/// path and the closed-form aggregates (which every evaluation computes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Reads {
    /// One screen statistic (and nothing else of the screen).
    Screen(Statistic),
    /// No screen statistic and no render-cost count.
    Path,
    /// Anything else (render-cost counts, the receiver fractions, the visible depth range):
    /// the full analysis.
    Everything,
}

/// The summary of `config` with every field `reads` needs as [`analyze`] with
/// [`AnalysisOptions::summary_only`] gives it, bit for bit: `cascades_needed`,
/// `coverage_violations`, `shimmer_snapped` (and the moving light's crawl), the walk's and the
/// aggregates' metrics, and per `reads` the one screen statistic. Without [`Reads::Everything`]
/// the render-cost counts are left at their default and the other screen statistics at 0 (no
/// screen statistics at all for [`Reads::Path`]): such a summary is for the search's cost only,
/// never for an output. A level of views (its screen statistics pooled over the views) is
/// analysed in full. `shared`: what `config`'s search group has in common ([`Shared::of`] of
/// any point of the group), or None to compute it here.
pub(crate) fn summary(config: &Config, reads: Reads, shared: Option<&Shared>) -> Summary {
    let opts = AnalysisOptions::summary_only();
    let screen = match reads {
        Reads::Screen(s) => Some(s),
        Reads::Path => None,
        Reads::Everything => return analyze(config, &opts).summary,
    };
    if !config.views.is_empty() {
        return analyze(config, &opts).summary;
    }
    analyze_camera(config, &opts, &|_| (), true, Detail::Search { screen, shared }).summary
}

/// Screen statistics with only `which` measured ([`screen::statistic`]), every other value 0
/// and each cascade's pixel share 0.
pub(super) fn one_statistic(vis: &Visibility, splits: &[f64], texel: &[f64], which: Statistic) -> ScreenStats {
    let mut st = ScreenStats {
        cascade_pixels: vec![0.0; texel.len()],
        ..ScreenStats::default()
    };
    *which.field(&mut st) = screen::statistic(vis, splits, texel, which);
    st
}
