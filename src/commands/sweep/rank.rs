//! Ranking a sweep's rows: the objective, the Pareto front, the recommendation (or why there is
//! none), its alternatives and rivals, and the fit groups the figures draw.

use std::collections::BTreeSet;

use crate::analysis::Summary;
use crate::commands::sweep::grid::{FitGroup, Grid, Setting};
use crate::commands::sweep::run::Row;
use crate::config::Config;
use crate::metric::SummaryMetric;

// ---------------------------------------------------------------------------------------------
// Pareto front and recommendation
// ---------------------------------------------------------------------------------------------

/// Indices of the rows on the Pareto front of memory against the objective (both minimised),
/// ordered by memory. Among exact ties the first row in grid order is kept. Rows whose scene
/// needs no cascades are left out.
pub fn pareto_front_by(rows: &[Row], objective: SummaryMetric) -> Vec<usize> {
    front_of(
        rows,
        (0..rows.len()).filter(|&i| rows[i].summary.cascades_needed),
        objective,
    )
}

/// The Pareto front of memory against `objective` over the rows `candidates`, ordered by memory
/// (among exact ties the first row in grid order is kept).
fn front_of(rows: &[Row], candidates: impl Iterator<Item = usize>, objective: SummaryMetric) -> Vec<usize> {
    // Bytes below 2^53 are exact as f64, so the order is the integers' order.
    front_over(rows, candidates, |s| Some(s.memory_bytes as f64), objective)
}

/// Indices of the rows on the Pareto front of `cost_index` against the objective (both
/// minimised), ordered by cost; rows without a measured cost or cascades are left out.
pub fn cost_front(rows: &[Row], objective: SummaryMetric) -> Vec<usize> {
    front_over(
        rows,
        (0..rows.len()).filter(|&i| rows[i].summary.cascades_needed),
        |s| s.cost.cost_index,
        objective,
    )
}

/// The Pareto front of `price` (rows where it is None are left out) against `objective` over
/// the rows `candidates`, both minimised, ordered by price; among exact ties the first row in
/// grid order is kept.
fn front_over(
    rows: &[Row],
    candidates: impl Iterator<Item = usize>,
    price: impl Fn(&Summary) -> Option<f64>,
    objective: SummaryMetric,
) -> Vec<usize> {
    let mut idx: Vec<usize> = candidates.filter(|&i| price(&rows[i].summary).is_some()).collect();
    let p = |i: usize| price(&rows[i].summary).unwrap_or(f64::INFINITY);
    idx.sort_by(|&a, &b| {
        p(a).total_cmp(&p(b))
            .then(
                objective
                    .value(&rows[a].summary)
                    .total_cmp(&objective.value(&rows[b].summary)),
            )
            .then(a.cmp(&b))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        let m = objective.value(&rows[i].summary);
        if m < best {
            best = m;
            front.push(i);
        }
    }
    front
}

/// Largest shimmer (RMS texels per frame, snapped) a configuration may have to be recommended.
pub const STABLE_SHIMMER: f64 = 1e-3;

/// What the recommendation optimises, in words (printed in reports).
pub(crate) const OBJECTIVE: &str =
    "lowest mean aliasing (the average shadow-texel-to-pixel ratio over the depth range) \
among configurations that fit the memory budget, cover every slice (coverage_violations = 0) and are stable when \
snapped (shimmer_snapped <= 1e-3 texel); means within 1% of the lowest count as equal, and among those the lowest \
max aliasing wins, then less memory, then fewer cascades";

/// The objective of a sweep: `[sweep] objective` if written, else the contrast-weighted 95th
/// percentile of the per-pixel aliasing on screen (`visible_aliasing_p95`) when the scene has
/// geometry, else the mean aliasing over depth.
pub fn default_objective(config: &Config) -> SummaryMetric {
    crate::metric::sweep_objective(config)
}

/// [`OBJECTIVE`] for the mean aliasing without geometry; the same rule in words for any other
/// objective, naming the worst case that breaks near-ties (`worst`).
pub(crate) fn objective_text(objective: SummaryMetric, worst: SummaryMetric) -> String {
    if objective.name() == "mean_aliasing" && worst.name() == "max_aliasing" {
        return OBJECTIVE.to_string();
    }
    format!(
        "lowest {} ({}) among configurations that fit the memory budget, cover every slice \
         (coverage_violations = 0) and are stable when snapped (shimmer_snapped <= 1e-3 texel); values within 1% of \
         the lowest count as equal, and among those the lowest {} ({}) wins, then less memory, then fewer cascades",
        objective.name(),
        objective.description(),
        worst.name(),
        worst.description()
    )
}

/// Mean aliasing within this fraction of the best counts as equal: a 0.2% better mean is not
/// worth a 20% worse worst case, so near-ties are decided by max aliasing.
pub(crate) const MEAN_TOLERANCE: f64 = 0.01;

/// The render-cost budget of a recommendation (`[sweep] cost_budget`, `shadow_ms_budget`):
/// the largest `cost_index` and `shadow_ms` it may have; no limit where None.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CostLimit {
    pub index: Option<f64>,
    pub ms: Option<f64>,
}

impl CostLimit {
    /// No cost budget.
    pub const NONE: CostLimit = CostLimit { index: None, ms: None };

    /// The budgets of a config's `[sweep]` table.
    pub fn of(config: &Config) -> Self {
        config.sweep.as_ref().map_or(Self::NONE, |s| CostLimit {
            index: s.cost_budget,
            ms: s.shadow_ms_budget,
        })
    }

    pub fn is_set(&self) -> bool {
        self.index.is_some() || self.ms.is_some()
    }

    /// Whether a row's cost fits (an unmeasured cost never fits a set budget).
    pub fn fits(&self, s: &Summary) -> bool {
        let within = |limit: Option<f64>, value: Option<f64>| limit.is_none_or(|b| value.is_some_and(|v| v <= b));
        within(self.index, s.cost.cost_index) && within(self.ms, s.cost.shadow_ms)
    }
}

/// A memory budget in MiB as the largest number of bytes a row may take (whole bytes, rounded
/// down).
pub(crate) fn budget_bytes(budget_mib: f64) -> u64 {
    (budget_mib * 1024.0 * 1024.0).floor() as u64
}

/// The recommended row and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Recommendation {
    pub index: usize,
    pub budget_bytes: u64,
    /// False when nothing fits the budget: the cheapest acceptable configuration is returned.
    pub within_budget: bool,
    /// The render-cost budget the recommendation was picked under.
    pub cost_limit: CostLimit,
    /// False when no acceptable row within the memory budget fits the cost budget: the one
    /// cheapest to render is returned.
    pub within_cost: bool,
}

/// Whether a row may be recommended: its scene needs cascades, it covers every slice
/// (`coverage_violations` = 0) and it is stable when snapped (`shimmer_snapped` <=
/// [`STABLE_SHIMMER`]; under a moving light, the snapped crawl between updates:
/// [`Summary::snapped_drift`]).
pub fn acceptable(r: &Row) -> bool {
    r.summary.cascades_needed && r.summary.coverage_violations == 0 && r.summary.snapped_drift() <= STABLE_SHIMMER
}

/// Picks the recommendation minimising `objective`: the best acceptable row within the budget,
/// else the best acceptable row. None when no row needs cascades or none is acceptable.
/// Near-ties are decided by `worst`, the worst case ([`crate::metric::worst_aliasing`]: on
/// screen with geometry, else `max_aliasing`).
pub fn recommend_by(
    rows: &[Row],
    budget_mib: f64,
    objective: SummaryMetric,
    worst: SummaryMetric,
) -> Option<Recommendation> {
    recommend_within(rows, budget_mib, CostLimit::NONE, objective, worst)
}

/// [`recommend_by`] under a render-cost budget too: the best acceptable row within both
/// budgets; when no row within the memory budget fits the cost budget, the one with the lowest
/// `cost_index` among them (best objective among equals); when none fits the memory budget,
/// the cheapest in memory.
pub fn recommend_within(
    rows: &[Row],
    budget_mib: f64,
    cost: CostLimit,
    objective: SummaryMetric,
    worst: SummaryMetric,
) -> Option<Recommendation> {
    let objective_of = |i: usize| objective.value(&rows[i].summary);
    let worst_of = |i: usize| worst.value(&rows[i].summary);
    recommend_with(rows, budget_mib, cost, &objective_of, &worst_of)
}

/// [`recommend_within`] with each row's objective and worst case given by `objective` and
/// `worst` (by row index) rather than read from its summary: a view of a level alone is
/// ranked on its own values ([`super::level::choose`]), everything else on the row's.
pub(crate) fn recommend_with(
    rows: &[Row],
    budget_mib: f64,
    cost: CostLimit,
    objective: &dyn Fn(usize) -> f64,
    worst: &dyn Fn(usize) -> f64,
) -> Option<Recommendation> {
    let budget_bytes = budget_bytes(budget_mib);
    let ok: Vec<usize> = (0..rows.len()).filter(|&i| acceptable(&rows[i])).collect();
    let within: Vec<usize> = ok
        .iter()
        .copied()
        .filter(|&i| rows[i].summary.memory_bytes <= budget_bytes)
        .collect();
    let both: Vec<usize> = within
        .iter()
        .copied()
        .filter(|&i| cost.fits(&rows[i].summary))
        .collect();
    let made = |index: usize, within_budget: bool| Recommendation {
        index,
        budget_bytes,
        within_budget,
        cost_limit: cost,
        within_cost: cost.fits(&rows[index].summary),
    };
    if let Some(index) = pick(rows, &both, objective, worst) {
        return Some(made(index, true));
    }
    if !within.is_empty() {
        // Nothing within the memory budget fits the cost budget: the cheapest to render.
        let key = |i: usize| rows[i].summary.cost.cost_index.unwrap_or(f64::INFINITY);
        let least = within.iter().map(|&i| key(i)).min_by(f64::total_cmp)?;
        let cheap: Vec<usize> = within.iter().copied().filter(|&i| key(i) == least).collect();
        return pick(rows, &cheap, objective, worst).map(|index| made(index, true));
    }
    // Nothing fits the budget: the cheapest acceptable configurations, best among them.
    let cheapest = ok.iter().map(|&i| rows[i].summary.memory_bytes).min()?;
    let cheap: Vec<usize> = ok
        .into_iter()
        .filter(|&i| rows[i].summary.memory_bytes == cheapest)
        .collect();
    pick(rows, &cheap, objective, worst).map(|index| made(index, false))
}

/// Why no configuration qualified, and which one comes closest.
#[derive(Debug, Clone, PartialEq)]
pub struct NoRecommendation {
    /// Rows whose scene needs no cascades.
    pub no_cascades: usize,
    /// Rows with slice corners outside their windows.
    pub coverage_misses: usize,
    /// Rows that shimmer when snapped (> [`STABLE_SHIMMER`]).
    pub unstable: usize,
    /// The closest row: the fewest coverage violations, then the least snapped shimmer, then
    /// within the budget, then the objective. None when no row needs cascades.
    pub closest: Option<usize>,
}

/// The failure analysis of a sweep without a recommendation.
pub fn no_recommendation(rows: &[Row], budget_mib: f64, objective: SummaryMetric) -> NoRecommendation {
    let budget_bytes = budget_bytes(budget_mib);
    let needed: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].summary.cascades_needed).collect();
    let closest = needed.iter().copied().min_by(|&a, &b| {
        let (x, y) = (&rows[a].summary, &rows[b].summary);
        x.coverage_violations
            .cmp(&y.coverage_violations)
            .then(x.snapped_drift().total_cmp(&y.snapped_drift()))
            .then((x.memory_bytes > budget_bytes).cmp(&(y.memory_bytes > budget_bytes)))
            .then(objective.value(x).total_cmp(&objective.value(y)))
            .then(a.cmp(&b))
    });
    NoRecommendation {
        no_cascades: rows.len() - needed.len(),
        coverage_misses: needed
            .iter()
            .filter(|&&i| rows[i].summary.coverage_violations > 0)
            .count(),
        unstable: needed
            .iter()
            .filter(|&&i| rows[i].summary.snapped_drift() > STABLE_SHIMMER)
            .count(),
        closest,
    }
}

/// The best of `candidates` by [`OBJECTIVE`]: the shortlist within [`MEAN_TOLERANCE`] of the
/// lowest objective, then the lowest worst case (`worst`), less memory, fewer cascades, grid
/// order.
fn pick(
    rows: &[Row],
    candidates: &[usize],
    objective: &dyn Fn(usize) -> f64,
    worst: &dyn Fn(usize) -> f64,
) -> Option<usize> {
    let best = candidates.iter().map(|&i| objective(i)).min_by(f64::total_cmp)?;
    candidates
        .iter()
        .copied()
        .filter(|&i| objective(i) <= best * (1.0 + MEAN_TOLERANCE))
        .min_by(|&a, &b| {
            let (x, y) = (&rows[a].summary, &rows[b].summary);
            worst(a)
                .total_cmp(&worst(b))
                .then(x.memory_bytes.cmp(&y.memory_bytes))
                .then(rows[a].setting.cascades.cmp(&rows[b].setting.cascades))
                .then(a.cmp(&b))
        })
}

// ---------------------------------------------------------------------------------------------
// Alternatives and rivals
// ---------------------------------------------------------------------------------------------

/// Which way an alternative departs from the recommendation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum AlternativeKind {
    /// Less memory, for a higher objective.
    Cheaper,
    /// A lower objective, for more memory.
    Sharper,
    /// Less shimmer in the configured snap mode.
    MoreStable,
    /// A lower render cost (`cost_index`), for a higher objective.
    CheaperToRender,
}

impl AlternativeKind {
    /// The `kind` of `recommendation.json`'s `alternatives`.
    pub(crate) fn name(self) -> &'static str {
        match self {
            AlternativeKind::Cheaper => "cheaper",
            AlternativeKind::Sharper => "sharper",
            AlternativeKind::MoreStable => "more_stable",
            AlternativeKind::CheaperToRender => "cheaper_to_render",
        }
    }

    /// The rule that picks it, in words (reports and `recommendation.json`).
    pub(crate) fn rule(self) -> &'static str {
        match self {
            AlternativeKind::Cheaper => {
                "the acceptable Pareto row with the most memory below the recommendation's:                  the lowest objective for less memory"
            }
            AlternativeKind::Sharper => {
                "the acceptable Pareto row with the least memory whose objective is more than 1%                  below the recommendation's: the cheapest real improvement"
            }
            AlternativeKind::MoreStable => {
                "the acceptable row within the budget with the least shimmer (configured snap mode),                  when that is below the recommendation's; ties go to the lower objective, then less memory"
            }
            AlternativeKind::CheaperToRender => {
                "the acceptable row within the memory budget on the Pareto front of cost_index against the objective                  with the highest cost_index below the recommendation's: the lowest objective for a cheaper render"
            }
        }
    }
}

/// One alternative to the recommendation: the row and why it was picked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Alternative {
    pub kind: AlternativeKind,
    pub index: usize,
}

/// The alternatives to a recommendation, at most one of each kind, in the order cheaper,
/// sharper, more stable. Each comes from the rows [`acceptable`] for a recommendation:
///
/// - **cheaper**: on the Pareto front of memory against the objective over the acceptable rows,
///   the row with the most memory below the recommendation's; that is the lowest objective
///   any acceptable row with less memory reaches (ties: less memory, then grid order);
/// - **sharper**: on the same front, the row with the least memory whose objective is below the
///   recommendation's by more than [`MEAN_TOLERANCE`] (smaller gains count as a tie);
/// - **more stable**: among the acceptable rows within the budget (within the recommendation's
///   memory when nothing fits the budget), the row with the least `shimmer` (the configured snap
///   mode's), when that is below the recommendation's; ties go to the lower objective, then less
///   memory, then grid order.
pub(crate) fn alternatives(rows: &[Row], rec: &Recommendation, objective: SummaryMetric) -> Vec<Alternative> {
    let r = &rows[rec.index].summary;
    let ok = || (0..rows.len()).filter(|&i| acceptable(&rows[i]));
    let front = front_of(rows, ok(), objective);
    let mut out = Vec::new();
    let cheaper = front
        .iter()
        .copied()
        .rfind(|&i| rows[i].summary.memory_bytes < r.memory_bytes);
    let bound = objective.value(r) * (1.0 - MEAN_TOLERANCE);
    let sharper = front
        .iter()
        .copied()
        .find(|&i| objective.value(&rows[i].summary) < bound);
    let limit = if rec.within_budget {
        rec.budget_bytes
    } else {
        r.memory_bytes
    };
    let stabler = ok()
        .filter(|&i| {
            rows[i].summary.memory_bytes <= limit
                && rows[i].summary.shimmer < r.shimmer
                && (!rec.within_cost || rec.cost_limit.fits(&rows[i].summary))
        })
        .min_by(|&a, &b| {
            let (x, y) = (&rows[a].summary, &rows[b].summary);
            x.shimmer
                .total_cmp(&y.shimmer)
                .then(objective.value(x).total_cmp(&objective.value(y)))
                .then(x.memory_bytes.cmp(&y.memory_bytes))
                .then(a.cmp(&b))
        });
    let render = r.cost.cost_index.and_then(|own| {
        let pool = ok().filter(|&i| !rec.within_budget || rows[i].summary.memory_bytes <= rec.budget_bytes);
        front_over(rows, pool, |s| s.cost.cost_index, objective)
            .into_iter()
            .rfind(|&i| rows[i].summary.cost.cost_index.is_some_and(|c| c < own))
    });
    for (kind, pick) in [
        (AlternativeKind::Cheaper, cheaper),
        (AlternativeKind::Sharper, sharper),
        (AlternativeKind::MoreStable, stabler),
        (AlternativeKind::CheaperToRender, render),
    ] {
        if let Some(index) = pick.filter(|&i| i != rec.index && !out.iter().any(|a: &Alternative| a.index == i)) {
            out.push(Alternative { kind, index });
        }
    }
    out
}

/// Which rival a row is: the best row of a group the recommendation beat.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RivalKind {
    /// The recommendation with λ = 1 (purely logarithmic splits) instead of its own λ, when λ
    /// is swept and the recommendation has more than one cascade.
    LambdaOne,
    /// The best row with another cascade count.
    OtherCascades,
    /// The best row with another resolution.
    OtherResolution,
    /// The best row with the other fit.
    OtherFit,
    /// The configured setting itself.
    Configured,
}

impl RivalKind {
    pub(crate) fn name(self) -> &'static str {
        match self {
            RivalKind::LambdaOne => "best_lambda_1",
            RivalKind::OtherCascades => "best_other_cascade_count",
            RivalKind::OtherResolution => "best_other_resolution",
            RivalKind::OtherFit => "best_other_fit",
            RivalKind::Configured => "configured",
        }
    }
}

/// Why a rival lost to the recommendation: the first test of the recommendation rule it failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Loss {
    /// Slice corners outside their windows (the count).
    CoverageMisses(u64),
    /// Snapped shimmer above [`STABLE_SHIMMER`] (the value).
    Unstable(f64),
    /// Over the memory budget, which the recommendation fits.
    OverBudget,
    /// Over the render-cost budget, which the recommendation fits.
    OverCostBudget,
    /// Nothing fits the budget and the rival needs more memory than the recommendation.
    MoreMemory,
    /// A higher objective, beyond the [`MEAN_TOLERANCE`] tie.
    Objective,
    /// Tied on the objective; a higher worst case (the sweep's `worst` metric).
    MaxAliasing,
    /// Tied on the objective and the worst case; more memory.
    TieMemory,
    /// Tied on everything above; more cascades or later in grid order.
    TieOrder,
}

/// A rival and why it lost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rival {
    pub kind: RivalKind,
    pub index: usize,
    pub loss: Loss,
}

/// Why row `x` lost to the recommendation `rec`, by the rule of [`recommend_by`].
pub(crate) fn loss(
    rows: &[Row],
    rec: &Recommendation,
    x: usize,
    objective: SummaryMetric,
    worst: SummaryMetric,
) -> Loss {
    let s = &rows[x].summary;
    let r = &rows[rec.index].summary;
    if s.coverage_violations > 0 {
        return Loss::CoverageMisses(s.coverage_violations);
    }
    if !acceptable(&rows[x]) {
        return Loss::Unstable(s.snapped_drift());
    }
    if rec.within_budget && s.memory_bytes > rec.budget_bytes {
        return Loss::OverBudget;
    }
    if rec.within_cost && !rec.cost_limit.fits(s) {
        return Loss::OverCostBudget;
    }
    if !rec.within_budget && s.memory_bytes > r.memory_bytes {
        return Loss::MoreMemory;
    }
    // The shortlist of the rule: within MEAN_TOLERANCE of the best objective among the rows
    // the recommendation was picked from.
    let pool = |i: usize| {
        acceptable(&rows[i])
            && (!rec.within_cost || rec.cost_limit.fits(&rows[i].summary))
            && if rec.within_budget {
                rows[i].summary.memory_bytes <= rec.budget_bytes
            } else {
                rows[i].summary.memory_bytes == r.memory_bytes
            }
    };
    let best = (0..rows.len())
        .filter(|&i| pool(i))
        .map(|i| objective.value(&rows[i].summary))
        .min_by(f64::total_cmp)
        .unwrap_or(objective.value(r));
    if objective.value(s) > best * (1.0 + MEAN_TOLERANCE) {
        Loss::Objective
    } else if worst.value(s) > worst.value(r) {
        Loss::MaxAliasing
    } else if s.memory_bytes > r.memory_bytes {
        Loss::TieMemory
    } else {
        Loss::TieOrder
    }
}

/// Distinct fit groups of the rows, in order (for plots).
pub(crate) fn fits_in(rows: &[Row]) -> Vec<FitGroup> {
    rows.iter()
        .map(|r| r.setting.fit_group())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect()
}

/// The row of the configured setting (the config's own λ, cascade count, resolution and
/// fit, and the preset's knob and shadow distance when swept), when the grid has it.
pub(crate) fn configured(config: &Config, rows: &[Row]) -> Option<usize> {
    let c = &config.shadow;
    let knob = crate::presets::axes(config).knob.map(|k| k.value);
    rows.iter().position(|x| {
        x.setting.knob.is_none_or(|k| Some(k) == knob)
            && x.setting.distance.is_none_or(|d| d == c.max_distance)
            && x.setting.lambda == c.lambda
            && x.setting.cascades == c.cascades
            && x.setting.resolution == c.resolution
            && x.setting.fit == c.fit
            && x.setting.split_range.is_visible() == c.fit_depth_to_visible
    })
}

/// Rows in objective order (acceptable within budget first), for the "top" tables; the
/// recommendation heads them (near-ties in the objective are decided by the worst case).
pub(crate) fn ranked(
    rows: &[Row],
    rec: Option<&Recommendation>,
    budget_mib: f64,
    objective: SummaryMetric,
    worst: SummaryMetric,
) -> Vec<usize> {
    let budget = rec.map_or(budget_bytes(budget_mib), |r| r.budget_bytes);
    let mut idx: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].summary.cascades_needed).collect();
    let key = |i: usize| {
        let s = &rows[i].summary;
        let ok = s.coverage_violations == 0
            && s.snapped_drift() <= STABLE_SHIMMER
            && s.memory_bytes <= budget
            && rec.is_none_or(|r| !r.within_cost || r.cost_limit.fits(s));
        (!ok, objective.value(s), worst.value(s), s.memory_bytes, i)
    };
    idx.sort_by(|&a, &b| {
        let (ka, kb) = (key(a), key(b));
        ka.0.cmp(&kb.0)
            .then(ka.1.total_cmp(&kb.1))
            .then(ka.2.total_cmp(&kb.2))
            .then(ka.3.cmp(&kb.3))
            .then(ka.4.cmp(&kb.4))
    });
    if let Some(r) = rec {
        idx.retain(|&i| i != r.index);
        idx.insert(0, r.index);
    }
    idx
}

/// The main rivals of the recommendation `rec` and why each lost: the recommendation's setting
/// with λ = 1 (when λ is swept), the best row (in `ranked` order) with another cascade count,
/// with another resolution, with the other fit, and the `configured` setting; each row once
/// (the first group names it), never the recommendation.
pub(crate) fn rivals(
    rows: &[Row],
    rec: &Recommendation,
    ranked: &[usize],
    configured: Option<usize>,
    lambda_swept: bool,
    objective: SummaryMetric,
    worst: SummaryMetric,
) -> Vec<Rival> {
    let r = rows[rec.index].setting;
    let best = |f: &dyn Fn(&Setting) -> bool| ranked.iter().copied().find(|&i| f(&rows[i].setting));
    let groups: [(RivalKind, Option<usize>); 5] = [
        (
            RivalKind::LambdaOne,
            if lambda_swept && r.lambda != 1.0 && r.cascades > 1 {
                best(&|s| s.lambda == 1.0 && s.cascades == r.cascades && s.resolution == r.resolution && s.fit == r.fit)
            } else {
                None
            },
        ),
        (RivalKind::OtherCascades, best(&|s| s.cascades != r.cascades)),
        (RivalKind::OtherResolution, best(&|s| s.resolution != r.resolution)),
        (RivalKind::OtherFit, best(&|s| s.fit != r.fit)),
        (
            RivalKind::Configured,
            configured.filter(|&i| rows[i].summary.cascades_needed),
        ),
    ];
    let mut out: Vec<Rival> = Vec::new();
    for (kind, index) in groups {
        if let Some(index) = index.filter(|&i| i != rec.index && !out.iter().any(|x| x.index == i)) {
            out.push(Rival {
                kind,
                index,
                loss: loss(rows, rec, index, objective, worst),
            });
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Edges of the swept range
// ---------------------------------------------------------------------------------------------

/// A swept axis whose recommended value is its smallest or largest value, with allowed values
/// beyond it: the best may lie outside the range swept.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeEdge {
    /// The axis as `sweep.csv` names its column (`lambda`, `cascades`, `resolution`, the
    /// preset's knob key, `shadow.max_distance`).
    pub axis: &'static str,
    /// The flag that sweeps it (`--lambda`, `--knob`, ...).
    pub flag: &'static str,
    /// The recommended value, as written in the axis.
    pub value: String,
    /// True at the largest value swept, false at the smallest.
    pub high: bool,
    /// The values to sweep next: the edge and up to five steps beyond it, inside what the axis
    /// allows (and, for more cascades or texels, inside the memory budget).
    pub next: Vec<String>,
}

impl RangeEdge {
    /// "largest" or "smallest".
    pub(crate) fn side(&self) -> &'static str {
        if self.high {
            "largest"
        } else {
            "smallest"
        }
    }

    /// The flag and values to try (`--knob 20,25,30`).
    pub(crate) fn suggestion(&self) -> String {
        format!("{} {}", self.flag, self.next.join(","))
    }

    /// One sentence for the reports.
    pub(crate) fn text(&self) -> String {
        format!(
            "{} {} is the {} value swept: the best may lie beyond it; try {}",
            self.axis,
            self.value,
            self.side(),
            self.suggestion()
        )
    }
}

/// An axis, its flag, the recommended value and, when at an edge, (high, the values to try).
type FoundEdge = (&'static str, &'static str, String, Option<(bool, Vec<String>)>);

/// Most values beyond the edge a suggestion lists.
const NEXT_STEPS: usize = 5;

/// Rounds away binary noise of `edge ± k × step` (`0.1 × 3`), keeping 9 decimals.
fn tidy(x: f64) -> f64 {
    let r = (x * 1e9).round() / 1e9;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// A number axis: the edge the value `v` is at among `values` (None inside or with one value),
/// and the values to try beyond it, spaced by the step next to the edge, while `allowed`. None
/// when nothing allowed lies beyond.
fn number_edge(values: &[f64], v: f64, allowed: impl Fn(f64) -> bool) -> Option<(bool, Vec<f64>)> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    let n = sorted.len();
    if n < 2 {
        return None;
    }
    let high = if v == sorted[n - 1] {
        true
    } else if v == sorted[0] {
        false
    } else {
        return None;
    };
    let (step, dir) = if high {
        (sorted[n - 1] - sorted[n - 2], 1.0)
    } else {
        (sorted[1] - sorted[0], -1.0)
    };
    let beyond: Vec<f64> = (1..=NEXT_STEPS.min(n.max(2)))
        .map(|k| tidy(v + dir * step * k as f64))
        .take_while(|&x| allowed(x))
        .collect();
    if beyond.is_empty() {
        return None;
    }
    let mut next: Vec<f64> = std::iter::once(v).chain(beyond).collect();
    next.sort_by(f64::total_cmp);
    Some((high, next))
}

/// An ordered axis of whole values: the edge the value `v` is at among `values`, and the
/// allowed values beyond it (`candidates`, ascending), for which `fits` holds.
fn list_edge<T: Copy + PartialOrd>(
    values: &[T],
    v: T,
    candidates: &[T],
    fits: impl Fn(T) -> bool,
) -> Option<(bool, Vec<T>)> {
    let min = values.iter().copied().reduce(|a, b| if b < a { b } else { a })?;
    let max = values.iter().copied().reduce(|a, b| if b > a { b } else { a })?;
    if min.partial_cmp(&max) != Some(std::cmp::Ordering::Less) {
        return None;
    }
    let high = if v == max {
        true
    } else if v == min {
        false
    } else {
        return None;
    };
    let beyond: Vec<T> = if high {
        candidates
            .iter()
            .copied()
            .filter(|&c| c > v)
            .take_while(|&c| fits(c))
            .take(NEXT_STEPS)
            .collect()
    } else {
        let below: Vec<T> = candidates.iter().copied().filter(|&c| c < v).collect();
        below
            .into_iter()
            .rev()
            .take_while(|&c| fits(c))
            .take(NEXT_STEPS)
            .collect()
    };
    if beyond.is_empty() {
        return None;
    }
    let mut next: Vec<T> = std::iter::once(v).chain(beyond).collect();
    next.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    Some((high, next))
}

/// The swept axes (more than one value) at whose smallest or largest value the recommended row
/// sits, with room beyond: values the recommended setting accepts with only that axis changed
/// ([`Setting::apply`]: λ in [0, 1], the counts and map sizes the pipeline or preset allows, the
/// preset's knob inside its bounds, a shadow distance above 0), resolutions by doubling or
/// halving, and more cascades or texels only while the recommendation's memory, scaled by the
/// count or the texel area, stays within the budget. The fit, split range, sun and light update
/// axes are choices, not ranges. Empty without a recommendation.
pub(crate) fn range_edges(config: &Config, grid: &Grid, rows: &[Row], rec: Option<&Recommendation>) -> Vec<RangeEdge> {
    let Some(rec) = rec else {
        return Vec::new();
    };
    let row = &rows[rec.index];
    let st = row.setting;
    let memory = row.summary.memory_bytes as f64;
    let budget = rec.budget_bytes as f64;
    let axes = crate::presets::axes(config);
    // The recommended setting with one axis changed still applies to the config.
    let applies = |s: Setting| s.apply(config).is_ok();
    let num = |x: f64| x.to_string();
    let texts = |found: Option<(bool, Vec<f64>)>| found.map(|(h, v)| (h, v.into_iter().map(num).collect()));
    let whole =
        |found: Option<(bool, Vec<usize>)>| found.map(|(h, v)| (h, v.iter().map(ToString::to_string).collect()));
    let mut found: Vec<FoundEdge> = Vec::new();
    if axes.lambda.is_some() {
        let edge = number_edge(&grid.lambda.values, st.lambda, |x| {
            (0.0..=1.0).contains(&x) && applies(Setting { lambda: x, ..st })
        });
        found.push(("lambda", "--lambda", num(st.lambda), texts(edge)));
    }
    let edge = list_edge(&grid.cascades.values, st.cascades, &axes.cascades, |c| {
        (c < st.cascades || memory * c as f64 / st.cascades as f64 <= budget) && applies(Setting { cascades: c, ..st })
    });
    found.push(("cascades", "--cascades", st.cascades.to_string(), whole(edge)));
    let ladder: Vec<usize> = (4..=14).map(|p| 1usize << p).collect();
    let res = st.resolution as usize;
    let resolutions: Vec<usize> = grid.resolution.values.iter().map(|&r| r as usize).collect();
    let edge = list_edge(&resolutions, res, &ladder, |r| {
        (r < res || memory * (r as f64 / res as f64).powi(2) <= budget)
            && u32::try_from(r).is_ok_and(|r| applies(Setting { resolution: r, ..st }))
    });
    found.push(("resolution", "--resolution", res.to_string(), whole(edge)));
    if let (Some(axis), Some(knob), Some(v)) = (&grid.knob, &axes.knob, st.knob) {
        let edge = number_edge(&axis.values, v, |x| {
            (knob.min..=knob.max).contains(&x) && applies(Setting { knob: Some(x), ..st })
        });
        found.push((knob.key, "--knob", num(v), texts(edge)));
    }
    if let (Some(axis), Some(v)) = (&grid.distance, st.distance) {
        let edge = number_edge(&axis.values, v, |x| {
            x > 0.0
                && x <= 1e9
                && applies(Setting {
                    distance: Some(x),
                    ..st
                })
        });
        found.push(("shadow.max_distance", "--distance", num(v), texts(edge)));
    }
    found
        .into_iter()
        .filter_map(|(axis, flag, value, edge)| {
            edge.map(|(high, next)| RangeEdge {
                axis,
                flag,
                value,
                high,
                next,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::Summary;
    use crate::config::Fit;

    fn row(memory: u64, mean: f64, cascades_needed: bool) -> Row {
        Row {
            setting: Setting::plain(0.5, 1, 512, Fit::Sphere),
            summary: Summary {
                cascades_needed,
                z_lo: 1.0,
                z_hi: 2.0,
                max_aliasing: mean * 2.0,
                mean_aliasing: mean,
                mean_log_aliasing: mean,
                shimmer_unsnapped: 0.3,
                ..Summary::nothing_needed(memory)
            },
        }
    }

    #[test]
    fn pareto_front_is_exactly_the_non_dominated_rows() {
        let mut rng = csm_core::rng::SplitMix64::new(11);
        for _ in 0..50 {
            let rows: Vec<Row> = (0..60)
                .map(|_| {
                    row(
                        1 + (rng.unit() * 8.0) as u64,
                        (rng.unit() * 20.0).round() / 4.0,
                        rng.unit() > 0.1,
                    )
                })
                .collect();
            let front = pareto_front_by(&rows, SummaryMetric::named("mean_aliasing"));
            let dominated = |i: usize| {
                rows.iter().enumerate().any(|(j, r)| {
                    j != i
                        && r.summary.cascades_needed
                        && r.summary.memory_bytes <= rows[i].summary.memory_bytes
                        && r.summary.mean_aliasing <= rows[i].summary.mean_aliasing
                        && (r.summary.memory_bytes < rows[i].summary.memory_bytes
                            || r.summary.mean_aliasing < rows[i].summary.mean_aliasing)
                })
            };
            for &i in &front {
                assert!(rows[i].summary.cascades_needed && !dominated(i));
            }
            // Every non-dominated row is on the front or an exact duplicate of a front row.
            for i in 0..rows.len() {
                if rows[i].summary.cascades_needed && !dominated(i) {
                    assert!(front
                        .iter()
                        .any(|&f| rows[f].summary.memory_bytes == rows[i].summary.memory_bytes
                            && rows[f].summary.mean_aliasing == rows[i].summary.mean_aliasing));
                }
            }
        }
    }

    /// Random rows with ties in memory, objective and shimmer, some unacceptable.
    fn random_rows(rng: &mut csm_core::rng::SplitMix64, n: usize) -> Vec<Row> {
        let mib = 1024 * 1024;
        (0..n)
            .map(|_| {
                let mut r = row(
                    (1 + (rng.unit() * 8.0) as u64) * mib,
                    (1.0 + rng.unit() * 20.0).round() / 4.0,
                    rng.unit() > 0.05,
                );
                r.summary.max_aliasing = r.summary.mean_aliasing * (1.0 + (rng.unit() * 4.0).round() / 4.0);
                r.summary.shimmer = (rng.unit() * 4.0).round() / 8.0;
                if rng.unit() < 0.1 {
                    r.summary.coverage_violations = 1 + (rng.unit() * 5.0) as u64;
                }
                if rng.unit() < 0.1 {
                    r.summary.shimmer_snapped = 0.01;
                }
                r
            })
            .collect()
    }

    #[test]
    fn alternatives_are_what_a_brute_force_search_finds() {
        let objective = SummaryMetric::named("mean_aliasing");
        let obj = |r: &Row| r.summary.mean_aliasing;
        let mut rng = csm_core::rng::SplitMix64::new(5);
        let mut seen = [0usize; 3];
        for round in 0..400 {
            let rows = random_rows(&mut rng, 5 + round % 40);
            let budget = 1.0 + (rng.unit() * 8.0).floor();
            let Some(rec) = recommend_by(&rows, budget, objective, SummaryMetric::named("max_aliasing")) else {
                continue;
            };
            let r = &rows[rec.index];
            let ok: Vec<usize> = (0..rows.len()).filter(|&i| acceptable(&rows[i])).collect();
            // Cheaper: the lowest objective among acceptable rows with less memory (then less
            // memory, then grid order).
            let cheaper = ok
                .iter()
                .copied()
                .filter(|&i| rows[i].summary.memory_bytes < r.summary.memory_bytes)
                .min_by(|&a, &b| {
                    obj(&rows[a])
                        .total_cmp(&obj(&rows[b]))
                        .then(rows[a].summary.memory_bytes.cmp(&rows[b].summary.memory_bytes))
                        .then(a.cmp(&b))
                });
            // Sharper: the least memory among acceptable rows more than 1% below (then the
            // lower objective, then grid order).
            let sharper = ok
                .iter()
                .copied()
                .filter(|&i| obj(&rows[i]) < obj(r) * 0.99)
                .min_by(|&a, &b| {
                    rows[a]
                        .summary
                        .memory_bytes
                        .cmp(&rows[b].summary.memory_bytes)
                        .then(obj(&rows[a]).total_cmp(&obj(&rows[b])))
                        .then(a.cmp(&b))
                });
            // More stable: the least shimmer within the budget, below the recommendation's.
            let limit = if rec.within_budget {
                rec.budget_bytes
            } else {
                r.summary.memory_bytes
            };
            let stabler = ok
                .iter()
                .copied()
                .filter(|&i| rows[i].summary.memory_bytes <= limit && rows[i].summary.shimmer < r.summary.shimmer)
                .min_by(|&a, &b| {
                    rows[a]
                        .summary
                        .shimmer
                        .total_cmp(&rows[b].summary.shimmer)
                        .then(obj(&rows[a]).total_cmp(&obj(&rows[b])))
                        .then(rows[a].summary.memory_bytes.cmp(&rows[b].summary.memory_bytes))
                        .then(a.cmp(&b))
                });
            let got = alternatives(&rows, &rec, objective);
            let find = |k: AlternativeKind| got.iter().find(|a| a.kind == k).map(|a| a.index);
            let mut expected = Vec::new();
            for (k, want) in [
                (AlternativeKind::Cheaper, cheaper),
                (AlternativeKind::Sharper, sharper),
                (AlternativeKind::MoreStable, stabler),
            ] {
                if let Some(i) = want.filter(|&i| !expected.contains(&i)) {
                    expected.push(i);
                    assert_eq!(find(k), Some(i), "{k:?} in round {round}");
                    seen[k as usize] += 1;
                } else {
                    assert_eq!(find(k), None, "{k:?} in round {round}");
                }
            }
            // The cheaper and sharper rows are on the Pareto front of the acceptable rows.
            for i in [cheaper, sharper].into_iter().flatten() {
                assert!(!ok.iter().any(|&j| {
                    let (a, b) = (&rows[j].summary, &rows[i].summary);
                    a.memory_bytes <= b.memory_bytes
                        && a.mean_aliasing <= b.mean_aliasing
                        && (a.memory_bytes < b.memory_bytes || a.mean_aliasing < b.mean_aliasing)
                }));
            }
            // Why every other row lost, by the rule that picked the recommendation.
            for x in (0..rows.len()).filter(|&i| i != rec.index && rows[i].summary.cascades_needed) {
                let s = &rows[x].summary;
                match loss(&rows, &rec, x, objective, SummaryMetric::named("max_aliasing")) {
                    Loss::CoverageMisses(n) => assert_eq!(n, s.coverage_violations),
                    Loss::Unstable(v) => assert!(v > STABLE_SHIMMER && s.coverage_violations == 0),
                    Loss::OverBudget => assert!(rec.within_budget && s.memory_bytes > rec.budget_bytes),
                    Loss::OverCostBudget => panic!("no cost budget here"),
                    Loss::MoreMemory => assert!(!rec.within_budget && s.memory_bytes > r.summary.memory_bytes),
                    Loss::Objective => assert!(obj(&rows[x]) > obj(r) && acceptable(&rows[x])),
                    Loss::MaxAliasing => {
                        assert!(s.max_aliasing > r.summary.max_aliasing && obj(&rows[x]) <= obj(r) * 1.0101)
                    }
                    Loss::TieMemory => {
                        assert!(s.max_aliasing == r.summary.max_aliasing && s.memory_bytes > r.summary.memory_bytes)
                    }
                    Loss::TieOrder => {
                        assert!(s.max_aliasing == r.summary.max_aliasing && s.memory_bytes == r.summary.memory_bytes)
                    }
                }
            }
        }
        // Every kind was exercised, and so was its absence.
        assert!(seen.iter().all(|&n| n > 20), "{seen:?}");
    }

    #[test]
    fn recommendation_respects_the_budget_and_falls_back_to_the_cheapest() {
        let mib = 1024 * 1024;
        let mean = SummaryMetric::named("mean_aliasing");
        let max = SummaryMetric::named("max_aliasing");
        let rows = vec![
            row(80 * mib, 1.0, true),
            row(32 * mib, 2.0, true),
            row(64 * mib, 1.5, true),
        ];
        let r = recommend_by(&rows, 64.0, mean, max).unwrap();
        assert_eq!((r.index, r.within_budget), (2, true));
        let r = recommend_by(&rows, 16.0, mean, max).unwrap();
        assert_eq!((r.index, r.within_budget), (1, false));
        let mut unstable = rows.clone();
        unstable[2].summary.shimmer_snapped = 0.2;
        assert_eq!(recommend_by(&unstable, 64.0, mean, max).unwrap().index, 1);
        assert!(recommend_by(&[row(mib, 1.0, false)], 64.0, mean, max).is_none());
        // Means within 1% are a tie decided by the worst case; beyond 1% the mean decides.
        let mut near = vec![row(mib, 1.0, true), row(mib, 1.009, true), row(mib, 1.02, true)];
        near[0].summary.max_aliasing = 10.0;
        near[1].summary.max_aliasing = 5.0;
        near[2].summary.max_aliasing = 1.0;
        assert_eq!(recommend_by(&near, 64.0, mean, max).unwrap().index, 1);
    }

    /// With screen metrics the near-tie is decided by the worst case on screen, not by the
    /// bounds' `max_aliasing` at the near plane: the two orders disagree here on purpose.
    #[test]
    fn with_geometry_near_ties_go_to_the_lowest_worst_case_on_screen() {
        let mib = 1024 * 1024;
        let objective = SummaryMetric::named("visible_aliasing_p95");
        let worst = crate::metric::worst_aliasing(true);
        assert_eq!(worst.name(), "screen_aliasing_max");
        // (visible p95, screen max, bounds max): rows 0 and 1 tie on the objective (0.5 %).
        let rows: Vec<Row> = [(4.0, 9.0, 100.0), (4.02, 7.0, 300.0), (4.5, 5.0, 50.0)]
            .iter()
            .map(|&(p95, screen_max, bounds_max)| {
                let mut x = row(mib, 1.0, true);
                x.summary.max_aliasing = bounds_max;
                x.summary.screen = Some(screen_stats(p95, screen_max));
                x
            })
            .collect();
        let rec = recommend_by(&rows, 64.0, objective, worst).unwrap();
        assert_eq!(
            rec.index, 1,
            "screen max 7 beats 9; the bounds max (300 against 100) has no say"
        );
        assert_eq!(loss(&rows, &rec, 0, objective, worst), Loss::MaxAliasing);
        assert_eq!(loss(&rows, &rec, 2, objective, worst), Loss::Objective);
        assert_eq!(ranked(&rows, Some(&rec), 64.0, objective, worst), [1, 0, 2]);
        // The bounds rule on the same rows picks the other one of the tie.
        let bounds = recommend_by(&rows, 64.0, objective, SummaryMetric::named("max_aliasing")).unwrap();
        assert_eq!(bounds.index, 0);
    }

    fn screen_stats(p95: f64, max: f64) -> csm_core::screen::ScreenStats {
        csm_core::screen::ScreenStats {
            receiver_fraction: 0.5,
            self_shadowed_fraction: 0.1,
            aliasing_mean: 1.0,
            aliasing_p50: 1.0,
            aliasing_p95: p95,
            aliasing_p99: p95,
            aliasing_max: max,
            undersampled_fraction: 0.5,
            visible_mean: 1.0,
            visible_p50: 1.0,
            visible_p95: p95,
            visible_p99: p95,
            visible_max: max,
            visible_z_lo: 1.0,
            visible_z_hi: 2.0,
            cascade_pixels: vec![1.0],
        }
    }

    #[test]
    fn number_edges_extend_the_range_by_its_edge_step_inside_the_domain() {
        let unit = |x: f64| (0.0..=1.0).contains(&x);
        let positive = |x: f64| x > 0.0;
        // Inside the range, or a one-value axis: no edge.
        assert_eq!(number_edge(&[0.2, 0.4, 0.6], 0.4, unit), None);
        assert_eq!(number_edge(&[0.4], 0.4, unit), None);
        // At the largest of 2.5, 5, 7.5, 10, 15, 20 (step 5 next to it): 20 and five steps up.
        let knob = [2.5, 5.0, 7.5, 10.0, 15.0, 20.0];
        assert_eq!(
            number_edge(&knob, 20.0, positive),
            Some((true, vec![20.0, 25.0, 30.0, 35.0, 40.0, 45.0]))
        );
        // The domain ends the suggestion: 0.8 of 0.6, 0.7, 0.8 steps to 0.9 and 1 only.
        assert_eq!(
            number_edge(&[0.8, 0.6, 0.7], 0.8, unit),
            Some((true, vec![0.8, 0.9, 1.0]))
        );
        // At the domain's own end nothing lies beyond: not an edge to report.
        assert_eq!(number_edge(&[0.5, 0.75, 1.0], 1.0, unit), None);
        assert_eq!(number_edge(&[0.0, 0.5], 0.0, unit), None);
        // The smallest value, an open lower bound: 50 of 50, 100 steps down to 0 (excluded).
        assert_eq!(number_edge(&[50.0, 100.0], 50.0, positive), None);
        assert_eq!(
            number_edge(&[40.0, 60.0, 80.0], 40.0, positive),
            Some((false, vec![20.0, 40.0]))
        );
    }

    #[test]
    fn whole_value_edges_stop_at_the_allowed_values_and_the_budget() {
        let counts: Vec<usize> = (1..=16).collect();
        assert_eq!(
            list_edge(&[2, 4], 4, &counts, |_| true),
            Some((true, vec![4, 5, 6, 7, 8, 9]))
        );
        assert_eq!(list_edge(&[2, 4], 4, &counts, |c| c <= 5), Some((true, vec![4, 5])));
        assert_eq!(list_edge(&[2, 4], 4, &counts, |c| c <= 4), None);
        assert_eq!(list_edge(&[2, 4], 2, &counts, |c| c < 2), Some((false, vec![1, 2])));
        assert_eq!(list_edge(&[2, 4], 2, &counts, |_| false), None);
        assert_eq!(list_edge(&[2, 3, 4], 3, &counts, |_| true), None);
        assert_eq!(list_edge(&[4], 4, &counts, |_| true), None);
        // A preset allowing 1..=4 cascades has nothing above 4.
        assert_eq!(list_edge(&[2, 4], 4, &[1, 2, 3, 4], |_| true), None);
    }
}
