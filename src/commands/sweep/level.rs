//! A sweep over a level of views: what each view alone would choose, what the level's choice
//! costs it, and the level's worst view. The level's rows already hold the pooled screen
//! metrics ([`crate::analysis::level_screen`]) and each view's own ([`Summary::views`]): a
//! view's rows are the level's with its own screen metrics in place of the pooled ones, ranked
//! by the same rule.

use crate::analysis::Summary;
use crate::commands::sweep::rank::{self, Recommendation};
use crate::commands::sweep::run::Row;
use crate::metric::{Direction, SummaryMetric};

/// One view of a level sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewChoice {
    pub name: String,
    /// The row this view alone would be recommended (None when nothing is acceptable).
    pub alone: Option<usize>,
    /// The objective of this view at its own choice and at the level's (the row
    /// [`LevelChoice::at`]).
    pub objective_alone: Option<f64>,
    pub objective_at_level: f64,
    /// `objective_at_level / objective_alone - 1` (in the objective's worse direction): what
    /// the level's choice costs this view; None without its own choice or when its objective
    /// there is 0.
    pub cost: Option<f64>,
    /// The view sees a lit-facing receiver (its pass has one; the same at every setting). A
    /// view that sees none has no screen statistics of its own: no choice, never the worst.
    pub seen: bool,
}

/// Every view's choice beside the level's.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelChoice {
    /// The level's row the views are judged at: the recommendation, else the configured
    /// setting's row, else the first.
    pub at: usize,
    pub views: Vec<ViewChoice>,
    /// The view with the worst objective at [`Self::at`] (the first of equals).
    pub worst: usize,
}

/// `summary` with view `k`'s own screen metrics in place of the level's pooled ones.
pub(crate) fn view_summary(summary: &Summary, k: usize) -> Summary {
    let v = &summary.views[k];
    Summary {
        screen: Some(v.screen.clone()),
        band_pixel_share: v.band_pixel_share,
        views: Vec::new(),
        ..summary.clone()
    }
}

/// Whether view `k` of a summary sees any lit-facing receiver (its own screen statistics
/// measure something).
pub(crate) fn sees_receivers(summary: &Summary, k: usize) -> bool {
    summary.views[k].screen.receiver_fraction > 0.0
}

/// The index of the worst of `values` by `objective`'s direction among those `seen` (the first
/// of equals; the first value when none is seen).
pub(crate) fn worst_of(values: &[f64], seen: &[bool], objective: SummaryMetric) -> usize {
    let Some(mut worst) = seen.iter().position(|&s| s) else {
        return 0;
    };
    for (k, &x) in values.iter().enumerate() {
        if !seen[k] {
            continue;
        }
        let worse = match objective.direction() {
            Direction::LowerIsWorse => x < values[worst],
            _ => x > values[worst],
        };
        if worse {
            worst = k;
        }
    }
    worst
}

/// Each view's own choice and the level's cost to it; None when the rows hold no views.
pub(crate) fn choose(
    rows: &[Row],
    rec: Option<&Recommendation>,
    configured: Option<usize>,
    budget_mib: f64,
    objective: SummaryMetric,
) -> Option<LevelChoice> {
    let count = rows.first()?.summary.views.len();
    if count == 0 {
        return None;
    }
    let at = rec.map(|r| r.index).or(configured).unwrap_or(0);
    let views: Vec<ViewChoice> = (0..count)
        .map(|k| {
            let own: Vec<Row> = rows
                .iter()
                .map(|r| Row {
                    setting: r.setting,
                    summary: view_summary(&r.summary, k),
                })
                .collect();
            // Views exist only with geometry: the worst case is on screen. A view that sees no
            // receiver has no statistics to choose by.
            let seen = sees_receivers(&rows[at].summary, k);
            let alone = rank::recommend_by(&own, budget_mib, objective, crate::metric::worst_aliasing(true))
                .map(|r| r.index)
                .filter(|_| seen);
            let objective_alone = alone.map(|i| objective.value(&own[i].summary));
            let objective_at_level = objective.value(&own[at].summary);
            let cost = objective_alone
                .filter(|&x| x != 0.0)
                .map(|x| match objective.direction() {
                    Direction::LowerIsWorse => x / objective_at_level - 1.0,
                    _ => objective_at_level / x - 1.0,
                });
            ViewChoice {
                name: rows[at].summary.views[k].name.clone(),
                alone,
                objective_alone,
                objective_at_level,
                cost: cost.filter(|c| c.is_finite()),
                seen,
            }
        })
        .collect();
    let values: Vec<f64> = views.iter().map(|v| v.objective_at_level).collect();
    let seen: Vec<bool> = views.iter().map(|v| v.seen).collect();
    Some(LevelChoice {
        at,
        worst: worst_of(&values, &seen, objective),
        views,
    })
}
