//! `sweep --optimize-splits`: free split positions that minimise the sweep's objective.
//!
//! For each group of the grid that differs only in λ (cascade count × resolution × fit ×
//! split range × distance), with more than one cascade, the search starts from the best
//! practical-λ split of that group and moves the split fractions with Nelder-Mead (argmin) in
//! the coordinates of [`FractionSpace::from_params`] (log-depth gaps, always strictly
//! increasing). Every evaluation is the same analysis a sweep row gets (the point's config with
//! explicit fractions, [`analyze`] with the summary only), so the numbers compare one to one;
//! a configuration that is not acceptable for a recommendation (coverage misses, unstable when
//! snapped) costs +∞. The points Nelder-Mead tries only need that cost: they are analysed with
//! [`search::summary`], which computes what the cost reads (bit for bit the full analysis'
//! values) and leaves out the render-cost counts and the screen statistics the objective does
//! not read; the points reported (the start, a preset's configured split, the optimum) are
//! analysed in full. The best point is then printed to 4 significant digits (more when 4 lose
//! more than 0.1 % or the rounded point is no longer better than the start): the reported
//! objective is that of the printed fractions, so they paste back to the same value.
//!
//! Method, stopping rule and cost: `docs/optimize.md`.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;

use crate::analysis::search::{self, Reads};
use crate::analysis::{analyze, AnalysisOptions, Summary};
use crate::config::Config;
use crate::error::{GridError, Result};
use crate::metric::SummaryMetric;
use csm_core::free_splits::{round_significant, valid, FractionSpace};

use crate::commands::sweep::grid::{Grid, Setting};
use crate::commands::sweep::rank::acceptable;
use crate::commands::sweep::run::{in_pool, Row};
use crate::config::sweep_spec::decimal_range;

/// Nelder-Mead iterations per run, per free split (two runs: the second restarts from the
/// best point of the first with a smaller simplex).
pub(crate) const ITERATIONS_PER_SPLIT: u64 = 60;
/// The first simplex: each vertex moves one log-depth gap by this much (in log units).
pub(crate) const FIRST_STEP: f64 = 0.5;
/// A run stops when the objective's standard deviation over the simplex falls below this
/// fraction of the start's objective.
pub(crate) const RELATIVE_TOLERANCE: f64 = 1e-6;
/// Printed fractions may cost at most this fraction of the optimum's objective.
pub(crate) const ROUNDING_LOSS: f64 = 1e-3;

/// Where the free-split search runs: csm-lab's own pipeline or a preset with free fractions.
/// Refused (naming the flag or key and the preset) for a preset whose splits are not free.
pub(crate) fn check_free(config: &Config, source: &str) -> Result<()> {
    if let Some(p) = &config.shadow.preset {
        if !crate::presets::has_free_splits(p.name) {
            let free = crate::presets::free_split_engines()
                .iter()
                .map(|e| e.as_str())
                .collect::<Vec<_>>()
                .join(", ");
            return Err(GridError::Unusable {
                context: format!("{source} with the {} preset", p.name),
                message: format!(
                    "its splits are not free fractions ({}); split fractions can be optimised for csm-lab's own \
                     pipeline (no preset) and the presets {free}",
                    crate::presets::split_rule(&p.knobs)
                ),
            }
            .into());
        }
    }
    Ok(())
}

/// A split the search evaluated: fractions and the analysis' summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluated {
    pub fractions: Vec<f64>,
    pub summary: Summary,
}

/// The free-split optimum of one group of the grid.
#[derive(Debug, Clone, PartialEq)]
pub struct OptimizedGroup {
    /// The group's setting with the λ of the best practical split.
    pub setting: Setting,
    /// What the fractions are fractions of.
    pub space: FractionSpace,
    /// The best practical-λ split (the start), and its λ.
    pub start_lambda: f64,
    pub start: Evaluated,
    /// The sweep row of the start, for csm-lab's own pipeline (None for a preset, whose
    /// practical splits are evaluated here).
    pub start_row: Option<usize>,
    /// The preset's configured split for this count (None for csm-lab's own pipeline).
    pub configured: Option<Evaluated>,
    /// The optimum, as printed.
    pub best: Evaluated,
    /// Analyses run for this group.
    pub evaluations: usize,
}

impl OptimizedGroup {
    /// The objective of the start and of the optimum.
    pub(crate) fn values(&self, objective: SummaryMetric) -> (f64, f64) {
        (
            objective.value(&self.start.summary),
            objective.value(&self.best.summary),
        )
    }
}

/// Everything `--optimize-splits` found.
#[derive(Debug, Clone, PartialEq)]
pub struct Optimized {
    pub groups: Vec<OptimizedGroup>,
    /// The λ values the start was chosen from, as a spec (`0:1:0.05`).
    pub lambdas: String,
    /// Groups left out, and why (one cascade: no split; no cascade needed; nothing acceptable).
    pub notes: Vec<String>,
}

/// The point's config with split fractions: `shadow.splits`, or the preset's split knob.
pub(crate) fn with_fractions(point: &Config, fractions: &[f64]) -> Result<Config> {
    match &point.shadow.preset {
        None => point.with_splits(fractions),
        Some(_) => {
            let mut c = point.clone();
            let n = c.shadow.cascades;
            let max_distance = c.shadow.max_distance;
            let p = c.shadow.preset.as_mut().expect("checked");
            crate::presets::set_fractions(&mut p.knobs, n, max_distance, fractions)?;
            crate::presets::check_point(&c)?;
            c.rechecked()
        }
    }
}

/// Analyses the point with `fractions` (the summary a sweep row would have); None when the
/// fractions are not a valid split for it.
pub fn evaluate(point: &Config, fractions: &[f64]) -> Option<Summary> {
    if !valid(fractions) {
        return None;
    }
    let c = with_fractions(point, fractions).ok()?;
    Some(analyze(&c, &AnalysisOptions::summary_only()).summary)
}

/// What the search's cost reads of a point's analysis with `objective` (see [`search`]): one
/// screen statistic, the walk's and the aggregates' metrics alone, or everything (the
/// render-cost counts, the receiver fractions, the visible depth range, and any metric not
/// listed here).
pub(crate) fn reads(objective: SummaryMetric) -> Reads {
    if let Some(s) = objective.screen_statistic() {
        return Reads::Screen(s);
    }
    match objective.name() {
        "cascades_needed"
        | "z_lo"
        | "z_hi"
        | "max_aliasing"
        | "mean_aliasing"
        | "mean_log_aliasing"
        | "undersampled_fraction"
        | "shimmer"
        | "shimmer_snapped"
        | "shimmer_unsnapped"
        | "size_jitter"
        | "coverage_violations"
        | "memory_bytes"
        | "lookup_error_max"
        | "lookup_error_rms"
        | "overlap_area_fraction"
        | "screen_band_pixel_share"
        | "light_crawl"
        | "light_crawl_snapped"
        | "light_crawl_unsnapped"
        | "light_jump"
        | "light_jump_snapped"
        | "light_jump_unsnapped"
        | "renders_per_frame"
        | "stale_coverage_violations"
        | "stale_coverage_fraction"
        | "stale_margin"
        | "stale_margin_world"
        | "update_drift" => Reads::Path,
        _ => Reads::Everything,
    }
}

/// [`evaluate`] for the search's cost alone ([`search::summary`] with what `reads` names):
/// None when the fractions are not a valid split for the point. `shared`: what the point's
/// group has in common ([`search::Shared::of`] the point), or None to compute it per call.
pub(crate) fn evaluate_for_cost(
    point: &Config,
    fractions: &[f64],
    reads: Reads,
    shared: Option<&search::Shared>,
) -> Option<Summary> {
    if !valid(fractions) {
        return None;
    }
    let c = with_fractions(point, fractions).ok()?;
    Some(search::summary(&c, reads, shared))
}

/// The search's cost: the objective of an acceptable configuration, +∞ otherwise.
fn cost(setting: &Setting, summary: &Summary, objective: SummaryMetric) -> f64 {
    let row = Row {
        setting: *setting,
        summary: summary.clone(),
    };
    if acceptable(&row) {
        objective.value(summary)
    } else {
        f64::INFINITY
    }
}

struct Problem<'a> {
    f: &'a (dyn Fn(&[f64]) -> f64 + Sync),
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, y: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        // Nelder-Mead orders vertices by cost: +∞ sorts last, as the largest finite value does.
        Ok((self.f)(y).min(f64::MAX))
    }
}

/// Nelder-Mead from `y0` with a first simplex of side `step`, at most `iters` iterations:
/// the best point and its cost.
fn nelder_mead(f: &(dyn Fn(&[f64]) -> f64 + Sync), y0: &[f64], step: f64, iters: u64, tol: f64) -> (Vec<f64>, f64) {
    let mut simplex = vec![y0.to_vec()];
    for i in 0..y0.len() {
        let mut v = y0.to_vec();
        v[i] += step;
        simplex.push(v);
    }
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(tol)
        .expect("a positive tolerance");
    let fallback = (y0.to_vec(), f(y0));
    match Executor::new(Problem { f }, solver)
        .configure(|s| s.max_iters(iters))
        .run()
    {
        Ok(res) => {
            let state = res.state();
            match state.get_best_param() {
                Some(p) if state.get_best_cost() <= fallback.1 => (p.clone(), state.get_best_cost()),
                _ => fallback,
            }
        }
        Err(_) => fallback,
    }
}

/// The costs of the points one group's search has evaluated, by their coordinates' bits: the
/// cost is a function of the point alone (the same analysis of the same config), so a point
/// asked for again costs what it cost the first time, bit for bit, without its analysis.
#[derive(Default)]
struct PointMemo {
    seen: Mutex<HashMap<Vec<u64>, f64>>,
    /// Points looked up instead of analysed.
    hits: AtomicUsize,
}

impl PointMemo {
    /// The cost of `y`: `analyse()` when `y` is new, else the cost recorded for it (and
    /// `analyse` is not called).
    fn cost(&self, y: &[f64], analyse: impl FnOnce() -> f64) -> f64 {
        let key: Vec<u64> = y.iter().map(|v| v.to_bits()).collect();
        if let Some(&c) = self.seen.lock().expect("one search per group").get(&key) {
            self.hits.fetch_add(1, Ordering::Relaxed);
            return c;
        }
        let c = analyse();
        self.seen.lock().expect("one search per group").insert(key, c);
        c
    }

    fn hits(&self) -> usize {
        self.hits.load(Ordering::Relaxed)
    }
}

/// The settings of the grid grouped by everything but λ (and a preset's split knob, which the
/// free fractions replace: Bevy's first far bound), in grid order, with their row indices.
fn groups(settings: &[Setting], preset: bool) -> Vec<Vec<usize>> {
    let key = |s: &Setting| Setting {
        lambda: 0.0,
        knob: if preset { None } else { s.knob },
        ..*s
    };
    let mut out: Vec<(Setting, Vec<usize>)> = Vec::new();
    for (i, s) in settings.iter().enumerate() {
        match out.iter_mut().find(|(k, _)| *k == key(s)) {
            Some((_, v)) => v.push(i),
            None => out.push((key(s), vec![i])),
        }
    }
    out.into_iter().map(|(_, v)| v).collect()
}

/// The λ values a preset's practical starting splits are drawn from.
pub(crate) const PRESET_LAMBDAS: &str = "0:1:0.05";

/// Optimises the split fractions of every group of `rows` (the sweep's rows, in grid order).
pub fn optimize(
    base: &Config,
    grid: &Grid,
    rows: &[Row],
    objective: SummaryMetric,
    threads: Option<usize>,
) -> Result<Optimized> {
    let preset = base.shadow.preset.is_some();
    let groups = groups(&rows.iter().map(|r| r.setting).collect::<Vec<_>>(), preset);
    let work = || {
        groups
            .par_iter()
            .map(|g| optimize_group(base, rows, g, objective))
            .collect::<Result<Vec<_>>>()
    };
    let found = in_pool(threads, work)?;
    let mut out = Optimized {
        groups: Vec::new(),
        lambdas: if preset {
            PRESET_LAMBDAS.to_string()
        } else {
            grid.lambda.spec.clone()
        },
        notes: Vec::new(),
    };
    let mut single = false;
    for f in found {
        match f {
            GroupOutcome::Done(g) => out.groups.push(*g),
            GroupOutcome::OneCascade => single = true,
            GroupOutcome::Skipped(why) => out.notes.push(why),
        }
    }
    if single {
        out.notes.insert(
            0,
            "one cascade has no split to place: counts of 1 are left out".to_string(),
        );
    }
    Ok(out)
}

enum GroupOutcome {
    Done(Box<OptimizedGroup>),
    OneCascade,
    Skipped(String),
}

fn optimize_group(base: &Config, rows: &[Row], group: &[usize], objective: SummaryMetric) -> Result<GroupOutcome> {
    let first = rows[group[0]].setting;
    let m = first.cascades;
    if m < 2 {
        return Ok(GroupOutcome::OneCascade);
    }
    let label = |s: &Setting| {
        let mut l = s.label();
        // "4 x 2048^2, lambda 0.4, sphere" → without the λ, which the group varies.
        if let Some(i) = l.find(", lambda ") {
            let rest = &l[i + 9..];
            let end = rest.find(',').map_or(l.len(), |j| i + 9 + j);
            l.replace_range(i..end, "");
        }
        l
    };
    let point = first.apply(base)?;
    let evaluations = AtomicUsize::new(0);
    let eval = |fr: &[f64]| {
        evaluations.fetch_add(1, Ordering::Relaxed);
        evaluate(&point, fr)
    };
    // A point only the cost reads: the lighter analysis (counted the same), with what the
    // group's points have in common computed once.
    let reads = reads(objective);
    let shared = search::Shared::of(&point);
    let eval_cost = |fr: &[f64]| {
        evaluations.fetch_add(1, Ordering::Relaxed);
        evaluate_for_cost(&point, fr, reads, Some(&shared))
    };
    // The start: the best practical-λ split (acceptable first, then the objective).
    let rank = |s: &Summary| {
        let ok = acceptable(&Row {
            setting: first,
            summary: s.clone(),
        });
        (!ok, objective.value(s))
    };
    let better = |a: &Summary, b: &Summary| {
        let (x, y) = (rank(a), rank(b));
        x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)).is_lt()
    };
    let (space, start_lambda, start, start_row, configured) = match &base.shadow.preset {
        None => {
            let needed: Vec<usize> = group
                .iter()
                .copied()
                .filter(|&i| rows[i].summary.cascades_needed)
                .collect();
            let Some(&best) = needed.iter().reduce(|a, b| {
                if better(&rows[*b].summary, &rows[*a].summary) {
                    b
                } else {
                    a
                }
            }) else {
                return Ok(GroupOutcome::Skipped(format!(
                    "{}: the scene needs no cascades",
                    label(&first)
                )));
            };
            let s = &rows[best].summary;
            let space = FractionSpace {
                lo: s.z_lo,
                hi: s.z_hi,
                start: s.z_lo,
            };
            let lambda = rows[best].setting.lambda;
            let fr = space.practical(m, lambda);
            (
                space,
                lambda,
                Evaluated {
                    fractions: fr,
                    summary: s.clone(),
                },
                Some(best),
                None,
            )
        }
        Some(p) => {
            let Some(space) = crate::presets::preset_fraction_space(&point, &p.knobs) else {
                return Ok(GroupOutcome::Skipped(format!(
                    "{}: the shadow range is empty",
                    label(&first)
                )));
            };
            // The practical splits compared by the cost's values, the best analysed in full.
            let mut best: Option<(f64, Evaluated)> = None;
            for lambda in decimal_range(0.0, 1.0, 0.05).expect("valid") {
                let fr = space.practical(m, lambda);
                if let Some(s) = eval_cost(&fr) {
                    if best.as_ref().is_none_or(|(_, b)| better(&s, &b.summary)) {
                        best = Some((
                            lambda,
                            Evaluated {
                                fractions: fr,
                                summary: s,
                            },
                        ));
                    }
                }
            }
            let best = best.map(|(lambda, e)| {
                let summary = evaluate(&point, &e.fractions).expect("a valid split, evaluated above");
                (
                    lambda,
                    Evaluated {
                        fractions: e.fractions,
                        summary,
                    },
                )
            });
            let configured = crate::presets::configured_fractions(&point, &p.knobs, m).and_then(|fr| {
                eval(&fr).map(|s| Evaluated {
                    fractions: fr,
                    summary: s,
                })
            });
            let Some((lambda, start)) = best else {
                return Ok(GroupOutcome::Skipped(format!(
                    "{}: no practical split is a valid split for the engine",
                    label(&first)
                )));
            };
            (space, lambda, start, None, configured)
        }
    };
    if !start.summary.cascades_needed {
        return Ok(GroupOutcome::Skipped(format!(
            "{}: the scene needs no cascades",
            label(&first)
        )));
    }
    let setting = Setting {
        lambda: start_lambda,
        ..first
    };
    let start_cost = cost(&setting, &start.summary, objective);
    if !start_cost.is_finite() {
        return Ok(GroupOutcome::Skipped(format!(
            "{}: no practical split is acceptable (coverage misses or shimmer when snapped), so there is no start",
            label(&first)
        )));
    }
    let Some(y0) = space.to_params(&start.fractions) else {
        return Ok(GroupOutcome::Skipped(format!(
            "{}: the start's first split lies before the first cascade",
            label(&first)
        )));
    };
    // A point asked for again (each run's start is evaluated twice, the second run starts at
    // the first's best, a collapsed simplex repeats vertices) costs what it cost: looked up,
    // not analysed again, and counted as an evaluation all the same (`evaluations`).
    let memo = PointMemo::default();
    let f = |y: &[f64]| {
        memo.cost(y, || {
            let fr = space.from_params(y);
            match eval_cost(&fr) {
                Some(s) => cost(&setting, &s, objective),
                None => f64::INFINITY,
            }
        })
    };
    let tol = RELATIVE_TOLERANCE * start_cost.abs().max(1e-300);
    let iters = ITERATIONS_PER_SPLIT * (m as u64 - 1);
    let (y1, c1) = nelder_mead(&f, &y0, FIRST_STEP, iters, tol);
    let (y2, c2) = nelder_mead(&f, &y1, FIRST_STEP / 4.0, iters, tol);
    let (y, c) = if c2 <= c1 { (y2, c2) } else { (y1, c1) };
    // The optimum as printed: the fewest significant digits (from 4) that keep it within
    // ROUNDING_LOSS of the unrounded optimum and strictly better than the start.
    let mut best = start.clone();
    if c < start_cost {
        let exact = space.from_params(&y);
        for digits in (4..=17).chain([0]) {
            let fr: Vec<f64> = if digits == 0 {
                exact.clone()
            } else {
                exact.iter().map(|&p| round_significant(p, digits)).collect()
            };
            let Some(s) = eval(&fr) else { continue };
            let v = cost(&setting, &s, objective);
            if v < start_cost && (v <= c + ROUNDING_LOSS * c.abs() || digits == 0) {
                best = Evaluated {
                    fractions: fr,
                    summary: s,
                };
                break;
            }
        }
    }
    Ok(GroupOutcome::Done(Box::new(OptimizedGroup {
        setting,
        space,
        start_lambda,
        start,
        start_row,
        configured,
        best,
        // A repeated point counts as the analysis it stands for.
        evaluations: evaluations.load(Ordering::Relaxed) + memo.hits(),
    })))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::SUMMARY;
    use csm_core::screen::Statistic;
    use proptest::prelude::*;
    use std::sync::OnceLock;

    /// The default scene at a small screen, and variants that take the walk's other ways:
    /// without snapping, a box fit (probes), an engine preset with free splits, a moving
    /// light, the binary32 pipeline, cached cascades, and no scene geometry (bounds only).
    fn points() -> &'static [Config] {
        static POINTS: OnceLock<Vec<Config>> = OnceLock::new();
        POINTS.get_or_init(|| {
            let base = include_str!("../../../configs/default.toml")
                .replace("width = 1920", "width = 320")
                .replace("height = 1080", "height = 180")
                .replace("frames = 240", "frames = 40");
            let variants = [
                base.clone(),
                base.replace("snap = true", "snap = false"),
                base.replace("fit = \"sphere\"\n", "fit = \"aabb\"\n"),
                base.replace("[shadow]\n", "[shadow]\npreset = \"bevy\"\n"),
                base.replace(
                    "step = 0.05\n",
                    "step = 0.05\nlight_path = \"sun\"\nsun_azimuth_step_deg = 0.05\n",
                ),
                base.replace("[shadow]\n", "[shadow]\nprecision = \"f32\"\n"),
                base.replace("[shadow]\n", "[shadow]\nupdate_every = [1, 2, 2, 4]\n"),
                bounds_only(&base),
            ];
            variants
                .iter()
                .map(|t| Config::from_toml_str(t, "test.toml", None).unwrap_or_else(|e| panic!("{e}\n{t}")))
                .collect()
        })
    }

    /// The config without its ground and boxes: bounds only, no screen statistics.
    fn bounds_only(text: &str) -> String {
        let mut out = Vec::new();
        let mut skip = 0;
        for l in text.lines() {
            if l.starts_with("[[scene.box]]") {
                skip = 3;
            }
            if skip > 0 {
                skip -= 1;
                continue;
            }
            out.push(if l.starts_with("ground =") { "" } else { l });
        }
        out.join("\n")
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        /// On random split vectors of every variant, for every metric of the registry as the
        /// objective: the lighter evaluation gives the objective, the three values the
        /// acceptance reads, and so the search's cost, of the full analysis, bit for bit;
        /// alone and with what its group shares computed once ([`search::Shared`]) for
        /// another point of the group.
        #[test]
        fn the_search_evaluation_equals_the_full_analysis(
            k in 0usize..8,
            raw in prop::collection::vec(0.0005f64..0.9995, 3),
            with_shared: bool,
        ) {
            let point = &points()[k];
            let mut fractions = raw.clone();
            fractions.sort_by(f64::total_cmp);
            prop_assume!(valid(&fractions));
            let full = evaluate(point, &fractions);
            let setting = Setting::plain(0.0, 4, 2048, point.shadow.fit);
            let shared = with_shared.then(|| search::Shared::of(point));
            let mut light: Vec<(Reads, Option<Summary>)> = Vec::new();
            for def in SUMMARY {
                let objective = SummaryMetric::named(def.name);
                let r = reads(objective);
                let at = match light.iter().position(|(x, _)| *x == r) {
                    Some(i) => i,
                    None => {
                        light.push((r, evaluate_for_cost(point, &fractions, r, shared.as_ref())));
                        light.len() - 1
                    }
                };
                let (full, light) = match (&full, &light[at].1) {
                    (Some(f), Some(l)) => (f, l),
                    (None, None) => continue,
                    other => panic!("valid for one and not the other: {other:?}"),
                };
                let name = def.name;
                prop_assert_eq!(light.cascades_needed, full.cascades_needed, "{} {:?}", name, fractions);
                prop_assert_eq!(light.coverage_violations, full.coverage_violations, "{}", name);
                prop_assert_eq!(light.snapped_drift().to_bits(), full.snapped_drift().to_bits(), "{}", name);
                prop_assert_eq!(
                    objective.value(light).to_bits(),
                    objective.value(full).to_bits(),
                    "{} on variant {}: {} vs {}",
                    name,
                    k,
                    objective.value(light),
                    objective.value(full)
                );
                prop_assert_eq!(
                    cost(&setting, light, objective).to_bits(),
                    cost(&setting, full, objective).to_bits(),
                    "{}",
                    name
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// The memo of a group's points, as the search uses it (the lighter evaluation with
        /// what the group shares): over a random sequence of points with repeats, every cost
        /// it gives equals the cost of the full analysis of that point, bit for bit, for a
        /// random objective of the registry, and each distinct point is analysed once.
        #[test]
        fn the_point_memo_gives_the_full_analysis_cost(
            k in 0usize..8,
            metric in 0usize..SUMMARY.len(),
            ys in prop::collection::vec(prop::collection::vec(-2.0f64..2.0, 3), 1..5),
            picks in prop::collection::vec(0usize..64, 1..12),
        ) {
            let point = &points()[k];
            let objective = SummaryMetric::named(SUMMARY[metric].name);
            let r = reads(objective);
            let setting = Setting::plain(0.0, 4, 2048, point.shadow.fit);
            let space = FractionSpace { lo: 0.1, hi: 150.0, start: 0.1 };
            let shared = search::Shared::of(point);
            let memo = PointMemo::default();
            let analysed = AtomicUsize::new(0);
            let mut distinct: Vec<Vec<u64>> = Vec::new();
            for &p in &picks {
                let y = &ys[p % ys.len()];
                let fr = space.from_params(y);
                let got = memo.cost(y, || {
                    analysed.fetch_add(1, Ordering::Relaxed);
                    evaluate_for_cost(point, &fr, r, Some(&shared)).map_or(f64::INFINITY, |s| cost(&setting, &s, objective))
                });
                let want = evaluate(point, &fr).map_or(f64::INFINITY, |s| cost(&setting, &s, objective));
                prop_assert_eq!(got.to_bits(), want.to_bits(), "{} on variant {} at {:?}", SUMMARY[metric].name, k, fr);
                let bits: Vec<u64> = y.iter().map(|v| v.to_bits()).collect();
                if !distinct.contains(&bits) {
                    distinct.push(bits);
                }
            }
            prop_assert_eq!(analysed.load(Ordering::Relaxed), distinct.len());
            prop_assert_eq!(memo.hits(), picks.len() - distinct.len());
        }
    }

    /// The lighter evaluation leaves out what the search does not read: the render-cost
    /// counts and, for a screen objective, every other screen statistic (so a test that
    /// compared only equal values could not pass by computing everything).
    #[test]
    fn the_search_evaluation_leaves_out_the_cost_counts_and_other_statistics() {
        let point = &points()[0];
        let fractions = [0.1, 0.3, 0.5];
        let full = evaluate(point, &fractions).expect("valid");
        let light = evaluate_for_cost(point, &fractions, Reads::Screen(Statistic::VisibleP95), None).expect("valid");
        assert!(full.cost.counts.is_some());
        assert_eq!(light.cost, crate::analysis::cost::CostSummary::default());
        let (f, l) = (full.screen.expect("geometry"), light.screen.expect("geometry"));
        assert_eq!(l.visible_p95, f.visible_p95);
        assert!(f.visible_p95 > 0.0 && f.aliasing_p95 > 0.0);
        assert_eq!(l.aliasing_p95, 0.0);
        let path = evaluate_for_cost(point, &fractions, Reads::Path, None).expect("valid");
        assert!(path.screen.is_none());
        assert_eq!(path.max_aliasing, full.max_aliasing);
    }
}
