//! A sweep over a level of views: what each view alone would choose, what the level's choice
//! costs it, and the level's worst view. The level's rows already hold the pooled screen
//! metrics ([`crate::analysis::level_screen`]) and of each view what the ranking reads
//! ([`Summary::view_ranks`]: its own value of the objective, its worst case, whether it sees a
//! receiver): a view's rows are the level's ranked by the same rule on the view's own values.

use crate::analysis::Summary;
use crate::commands::sweep::rank::{self, Recommendation};
use crate::commands::sweep::run::Row;
use crate::config::ViewSettings;
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
    let mut own = without_views(summary);
    put_view(&mut own, summary, k);
    own
}

/// `summary` with no views (`views` and `view_ranks` empty), made without copying its views'
/// metrics (a clone would copy every view's, only to drop them).
fn without_views(summary: &Summary) -> Summary {
    // Every field named, so that a field added to `Summary` is added here too.
    let Summary {
        cascades_needed,
        z_lo,
        z_hi,
        max_aliasing,
        mean_aliasing,
        mean_log_aliasing,
        undersampled_fraction,
        shimmer,
        shimmer_snapped,
        shimmer_unsnapped,
        size_jitter,
        coverage_violations,
        memory_bytes,
        lookup_error_max,
        lookup_error_rms,
        overlap_area_fraction,
        band_pixel_share,
        seam_crossings,
        screen,
        light,
        truth,
        views: _,
        view_ranks: _,
        cache,
        cost,
    } = summary;
    Summary {
        cascades_needed: *cascades_needed,
        z_lo: *z_lo,
        z_hi: *z_hi,
        max_aliasing: *max_aliasing,
        mean_aliasing: *mean_aliasing,
        mean_log_aliasing: *mean_log_aliasing,
        undersampled_fraction: *undersampled_fraction,
        shimmer: *shimmer,
        shimmer_snapped: *shimmer_snapped,
        shimmer_unsnapped: *shimmer_unsnapped,
        size_jitter: *size_jitter,
        coverage_violations: *coverage_violations,
        memory_bytes: *memory_bytes,
        lookup_error_max: *lookup_error_max,
        lookup_error_rms: *lookup_error_rms,
        overlap_area_fraction: *overlap_area_fraction,
        band_pixel_share: *band_pixel_share,
        seam_crossings: *seam_crossings,
        screen: screen.clone(),
        light: *light,
        truth: *truth,
        views: Vec::new(),
        view_ranks: Vec::new(),
        cache: *cache,
        cost: *cost,
    }
}

/// Puts view `k`'s own screen metrics of `level` (a row's summary) into `own`, a summary
/// without views of the same row: `own` becomes [`view_summary`]`(level, k)`, in place.
fn put_view(own: &mut Summary, level: &Summary, k: usize) {
    let v = &level.views[k];
    own.screen = Some(v.screen.clone());
    own.band_pixel_share = v.band_pixel_share;
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

/// Each view's own choice and the level's cost to it, from what the rows keep of each view
/// ([`Summary::view_ranks`], measured for `objective`: the sweep's); None when the rows hold no
/// views. `views` are the config's (their names). A view alone is judged under the level's
/// budgets: `budget_mib` and `cost_limit` (a row's memory and render cost are the same for every
/// view), so that what the level's choice costs a view is measured against a setting the team
/// could ship.
pub(crate) fn choose(
    rows: &[Row],
    rec: Option<&Recommendation>,
    configured: Option<usize>,
    budget_mib: f64,
    cost_limit: rank::CostLimit,
    objective: SummaryMetric,
    views: &[ViewSettings],
) -> Option<LevelChoice> {
    let count = rows.first()?.summary.view_ranks.len();
    if count == 0 {
        return None;
    }
    let at = rec.map(|r| r.index).or(configured).unwrap_or(0);
    let views: Vec<ViewChoice> = (0..count)
        .map(|k| {
            // The view's rows: the level's, ranked on the view's own value of the objective
            // (the level's where the objective is none of a view's statistics) and its own worst
            // case on screen (views exist only with geometry).
            let value = |i: usize| {
                let s = &rows[i].summary;
                s.view_ranks[k].objective.unwrap_or_else(|| objective.value(s))
            };
            let worst = |i: usize| rows[i].summary.view_ranks[k].worst;
            // A view that sees no receiver has no statistics to choose by.
            let seen = rows[at].summary.view_ranks[k].seen;
            let alone = rank::recommend_with(rows, budget_mib, cost_limit, &value, &worst)
                .map(|r| r.index)
                .filter(|_| seen);
            let objective_alone = alone.map(value);
            let objective_at_level = value(at);
            let cost = objective_alone
                .filter(|&x| x != 0.0)
                .map(|x| match objective.direction() {
                    Direction::LowerIsWorse => x / objective_at_level - 1.0,
                    _ => objective_at_level / x - 1.0,
                });
            ViewChoice {
                name: views.get(k).map_or_else(String::new, |v| v.name.clone()),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::{ViewRank, ViewScreen};
    use crate::commands::sweep::grid::Setting;
    use crate::config::Fit;
    use csm_core::screen::ScreenStats;

    /// The direct form: the whole summary cloned, its views dropped.
    fn cloned_view_summary(summary: &Summary, k: usize) -> Summary {
        let v = &summary.views[k];
        Summary {
            screen: Some(v.screen.clone()),
            band_pixel_share: v.band_pixel_share,
            views: Vec::new(),
            ..summary.clone()
        }
    }

    fn stats(rng: &mut csm_core::rng::SplitMix64, cascades: usize) -> ScreenStats {
        let mut x = || (rng.unit() * 16.0).round() / 4.0;
        ScreenStats {
            receiver_fraction: if x() > 0.5 { x() } else { 0.0 },
            aliasing_mean: x(),
            aliasing_p50: x(),
            aliasing_p95: x(),
            aliasing_p99: x(),
            aliasing_max: x(),
            visible_p95: x(),
            visible_z_hi: x(),
            cascade_pixels: (0..cascades).map(|_| x()).collect(),
            ..ScreenStats::default()
        }
    }

    /// Random rows of a level of `views` views: settings, memory, the level's and each view's
    /// screen metrics (ties likely: values on a grid of quarters).
    fn rows(seed: u64, n: usize, views: usize) -> Vec<Row> {
        let mut rng = csm_core::rng::SplitMix64::new(seed);
        (0..n)
            .map(|i| {
                let cascades = 1 + i % 4;
                let level = stats(&mut rng, cascades);
                let views = (0..views)
                    .map(|k| ViewScreen {
                        name: format!("view {k}"),
                        weight: 1.0 + k as f64,
                        screen: stats(&mut rng, cascades),
                        band_pixel_share: rng.unit(),
                        judged: k % 2 == 0,
                        truth: None,
                    })
                    .collect();
                let memory = 1 + (rng.unit() * 8.0) as u64;
                // A render cost on a grid of tenths (ties likely), unmeasured in one row of ten.
                let cost_index = (i % 10 != 9).then(|| (rng.unit() * 20.0).round() / 10.0);
                Row {
                    setting: Setting::plain(0.25 * (1 + i % 3) as f64, cascades, 512 << (i % 3), Fit::Sphere),
                    summary: Summary {
                        cascades_needed: rng.unit() > 0.1,
                        z_lo: 1.0,
                        z_hi: 2.0 + rng.unit(),
                        max_aliasing: rng.unit() * 4.0,
                        mean_aliasing: rng.unit(),
                        shimmer_unsnapped: rng.unit(),
                        band_pixel_share: rng.unit(),
                        screen: Some(level),
                        views,
                        cost: crate::analysis::cost::CostSummary {
                            cost_index,
                            ..Default::default()
                        },
                        ..Summary::nothing_needed(memory << 20)
                    },
                }
            })
            .collect()
    }

    /// A view's summary made without copying the views equals the whole summary cloned with
    /// the view's metrics put in, field for field.
    #[test]
    fn a_views_summary_equals_the_cloned_one() {
        for seed in 0..20 {
            for r in rows(seed, 8, 5) {
                for k in 0..5 {
                    assert_eq!(view_summary(&r.summary, k), cloned_view_summary(&r.summary, k));
                }
            }
        }
    }

    /// What the rows of a sweep keep of each view for `objective`, from each view's full
    /// metrics: its own value of the statistic the objective is (or none), its largest `m`,
    /// whether it sees a receiver (the direct form of the analysis' ranking record).
    fn with_ranks(mut rows: Vec<Row>, objective: SummaryMetric) -> Vec<Row> {
        for r in rows.iter_mut() {
            r.summary.view_ranks = r
                .summary
                .views
                .iter()
                .map(|v| {
                    let mut st = v.screen.clone();
                    ViewRank {
                        objective: objective.screen_statistic().map(|s| *s.field(&mut st)),
                        worst: v.screen.aliasing_max,
                        seen: v.screen.receiver_fraction > 0.0,
                    }
                })
                .collect();
        }
        rows
    }

    /// Views named "view k", at the default config's camera.
    fn named_views(n: usize) -> Vec<ViewSettings> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/default.toml");
        let camera = crate::config::Config::load(&path).expect("loads").camera.clone();
        (0..n)
            .map(|k| ViewSettings {
                name: format!("view {k}"),
                camera: camera.clone(),
                weight: 1.0,
            })
            .collect()
    }

    /// The direct form of a level's choice: for each view, every row's summary cloned with the
    /// view's full metrics in place of the level's, ranked by [`rank::recommend_within`] under
    /// the level's budgets.
    fn choose_over_full_rows(
        rows: &[Row],
        rec: Option<&Recommendation>,
        configured: usize,
        budget: f64,
        cost_limit: rank::CostLimit,
        objective: SummaryMetric,
    ) -> Vec<ViewChoice> {
        let at = rec.map_or(configured, |r| r.index);
        (0..rows[0].summary.views.len())
            .map(|k| {
                let own: Vec<Row> = rows
                    .iter()
                    .map(|r| Row {
                        setting: r.setting,
                        summary: cloned_view_summary(&r.summary, k),
                    })
                    .collect();
                let seen = rows[at].summary.views[k].screen.receiver_fraction > 0.0;
                let alone =
                    rank::recommend_within(&own, budget, cost_limit, objective, crate::metric::worst_aliasing(true))
                        .map(|r| r.index)
                        .filter(|_| seen);
                let objective_alone = alone.map(|i| objective.value(&own[i].summary));
                let objective_at_level = objective.value(&own[at].summary);
                let cost = objective_alone
                    .filter(|&x| x != 0.0)
                    .map(|x| objective_at_level / x - 1.0)
                    .filter(|c| c.is_finite());
                ViewChoice {
                    name: rows[at].summary.views[k].name.clone(),
                    alone,
                    objective_alone,
                    objective_at_level,
                    cost,
                    seen,
                }
            })
            .collect()
    }

    /// The objectives a sweep may have (`[sweep] objective`: a metric to minimise) that the
    /// tests rank views by: screen statistics (percentiles, means, maxima, the undersampled
    /// share) and metrics that are none of a view's (the bounds' mean aliasing, shimmer).
    const OBJECTIVES: [&str; 8] = [
        "visible_aliasing_p95",
        "screen_aliasing_p95",
        "screen_aliasing_mean",
        "screen_aliasing_max",
        "screen_aliasing_p50",
        "screen_undersampled_fraction",
        "mean_aliasing",
        "shimmer_unsnapped",
    ];

    /// The cost budgets the tests judge levels under: none, a `cost_budget` (`cost_index` at
    /// most 0.6 or 1.2 of the configured setting's) and a `shadow_ms_budget` (no row here is
    /// calibrated, so none fits it: the cheapest rows win).
    const COST_LIMITS: [rank::CostLimit; 4] = [
        rank::CostLimit::NONE,
        rank::CostLimit {
            index: Some(0.6),
            ms: None,
        },
        rank::CostLimit {
            index: Some(1.2),
            ms: None,
        },
        rank::CostLimit {
            index: None,
            ms: Some(2.0),
        },
    ];

    /// Each view's choice from what the rows keep for the ranking equals the choice over that
    /// view's rows with its full metrics, each cloned afresh (the direct form), for random
    /// levels, memory budgets, cost budgets and objectives.
    #[test]
    fn choices_from_the_ranks_equal_those_over_the_full_rows() {
        for seed in 0..160 {
            let views = 1 + (seed as usize % 6);
            let objective = SummaryMetric::named(OBJECTIVES[seed as usize % OBJECTIVES.len()]);
            let rows = with_ranks(rows(seed, 24, views), objective);
            let budget = 2.0 + (seed % 7) as f64;
            let limit = COST_LIMITS[(seed as usize / 3) % COST_LIMITS.len()];
            let worst = crate::metric::worst_aliasing(true);
            let rec = rank::recommend_within(&rows, budget, limit, objective, worst);
            let got = choose(
                &rows,
                rec.as_ref(),
                Some(3),
                budget,
                limit,
                objective,
                &named_views(views),
            )
            .unwrap();
            assert_eq!(got.at, rec.as_ref().map_or(3, |r| r.index));
            let want = choose_over_full_rows(&rows, rec.as_ref(), 3, budget, limit, objective);
            assert_eq!(got.views, want, "seed {seed}, {}, {limit:?}", objective.name());
        }
    }

    /// Under a cost budget a view alone is held to it as the level is: wherever some acceptable
    /// row fits both budgets, every view's own choice fits them too, and a view's own choice
    /// is never better than its best over the rows that fit (brute force over the rows).
    #[test]
    fn a_views_own_choice_keeps_the_levels_cost_budget() {
        let objective = SummaryMetric::named("visible_aliasing_p95");
        let mut checked = 0;
        for seed in 0..60 {
            let views = 2 + (seed as usize % 4);
            let rows = with_ranks(rows(seed, 24, views), objective);
            let budget = 4.0 + (seed % 5) as f64;
            let limit = rank::CostLimit {
                index: Some(0.8),
                ms: None,
            };
            let bytes = rank::budget_bytes(budget);
            let fits = |i: usize| {
                rank::acceptable(&rows[i]) && rows[i].summary.memory_bytes <= bytes && limit.fits(&rows[i].summary)
            };
            if !(0..rows.len()).any(fits) {
                continue;
            }
            let rec = rank::recommend_within(&rows, budget, limit, objective, crate::metric::worst_aliasing(true));
            let got = choose(
                &rows,
                rec.as_ref(),
                Some(0),
                budget,
                limit,
                objective,
                &named_views(views),
            )
            .unwrap();
            for (k, v) in got.views.iter().enumerate() {
                let Some(i) = v.alone else { continue };
                assert!(fits(i), "seed {seed}: view {k} alone picks row {i}, over a budget");
                let best = (0..rows.len())
                    .filter(|&j| fits(j))
                    .map(|j| rows[j].summary.view_ranks[k].objective.unwrap())
                    .fold(f64::INFINITY, f64::min);
                let own = rows[i].summary.view_ranks[k].objective.unwrap();
                // Values within 1 % of the best are equal for the ranking (ties go to the worst case).
                assert!(
                    own <= best * (1.0 + rank::MEAN_TOLERANCE) + 1e-12,
                    "seed {seed}: view {k}: {own} against {best}"
                );
                checked += 1;
            }
        }
        assert!(checked > 50, "only {checked} views checked");
    }

    /// Every metric a sweep may minimise reads, of a view's summary, either the one screen
    /// statistic [`SummaryMetric::screen_statistic`] names (the field the rows keep per view)
    /// or nothing of the view's (its value is the level's): so the ranking record holds all an
    /// objective reads.
    #[test]
    fn an_objective_reads_of_a_view_only_its_screen_statistic() {
        let objectives = SummaryMetric::all().filter(|m| m.direction() == Direction::HigherIsWorse);
        let rows = rows(7, 6, 3);
        for m in objectives {
            for r in &rows {
                for (k, v) in r.summary.views.iter().enumerate() {
                    let got = m.value(&view_summary(&r.summary, k));
                    let want = match m.screen_statistic() {
                        Some(s) => *s.field(&mut v.screen.clone()),
                        None => m.value(&r.summary),
                    };
                    assert_eq!(got.to_bits(), want.to_bits(), "{}", m.name());
                }
            }
        }
    }

    /// On a level config (20 views of the default scene, a small grid), the rows the sweep
    /// keeps give every view the choice the rows with each view's full metrics give; each
    /// view's kept values are its full metrics' fields bit for bit; and the row at the level's
    /// choice is completed with every view's full metrics, equal to a full pool of the views at
    /// its setting.
    #[test]
    fn on_a_level_config_the_ranks_choose_as_the_full_statistics() {
        use crate::analysis::{analyze, AnalysisOptions, ViewDetail};
        use crate::commands::sweep::grid::Grid;
        use crate::config::sweep_spec::SweepAxes;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/default_20_views.toml");
        let text = std::fs::read_to_string(&path)
            .expect("the bench config")
            .replace(
                "lambda = { start = 0.0, end = 1.0, step = 0.05 }",
                "lambda = [0.25, 0.75]",
            )
            .replace("cascades = [1, 2, 3, 4, 5, 6, 7, 8]", "cascades = [1, 3]")
            .replace("resolution = [512, 1024, 2048, 4096]", "resolution = [512, 2048]");
        let base = crate::config::Config::from_toml_str(&text, "views.toml", None).expect("the bench config loads");
        let grid = Grid::resolve(&base, &SweepAxes::default()).expect("a grid");
        assert_eq!(grid.len(), 8);
        let objective = rank::default_objective(&base);
        assert_eq!(objective.name(), "visible_aliasing_p95");
        let rows = crate::commands::sweep::run::run(&base, &grid, Some(1), &|| {}).expect("rows");
        let full: Vec<Row> = grid
            .settings()
            .iter()
            .map(|s| Row {
                setting: *s,
                summary: analyze(
                    &s.apply(&base).expect("a point"),
                    &AnalysisOptions {
                        views: ViewDetail::Full,
                        ..AnalysisOptions::summary_only()
                    },
                )
                .summary,
            })
            .collect();
        for (r, f) in rows.iter().zip(&full) {
            assert!(r.summary.views.is_empty());
            assert_eq!(r.summary.view_ranks.len(), 20);
            // The same row but for what it keeps of the views.
            assert_eq!(without_views(&r.summary), without_views(&f.summary));
            let want = with_ranks(vec![f.clone()], objective);
            assert_eq!(r.summary.view_ranks, want[0].summary.view_ranks);
        }
        let budget = 64.0;
        let rec = rank::recommend_by(&rows, budget, objective, crate::metric::worst_aliasing(true));
        let configured = rank::configured(&base, &rows).unwrap_or(0);
        let got = choose(
            &rows,
            rec.as_ref(),
            Some(configured),
            budget,
            rank::CostLimit::NONE,
            objective,
            &base.views,
        )
        .unwrap();
        let want = choose_over_full_rows(
            &full,
            rec.as_ref(),
            configured,
            budget,
            rank::CostLimit::NONE,
            objective,
        );
        assert_eq!(got.views, want);
        assert!(
            got.views.iter().any(|v| v.alone != Some(got.at)),
            "the views choose alike"
        );
        // The sweep's result completes the shown row: every view's full metrics, those of the
        // full pool at its setting.
        let result = crate::commands::sweep::SweepResult::new(base.clone(), grid, rows, String::new()).unwrap();
        let c = result.level.as_ref().expect("a level");
        assert_eq!(c.views, got.views);
        let shown = &result.rows[c.at];
        assert_eq!(shown.summary.views, full[c.at].summary.views);
        let pooled = crate::analysis::full_pool(&shown.setting.apply(&base).unwrap()).unwrap();
        let screens: Vec<&ScreenStats> = shown.summary.views.iter().map(|v| &v.screen).collect();
        assert_eq!(screens, pooled.views.iter().collect::<Vec<_>>());
        assert!(result
            .rows
            .iter()
            .enumerate()
            .all(|(i, r)| (i == c.at) != r.summary.views.is_empty()));
    }
}
