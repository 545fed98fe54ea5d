//! Parameter sweeps: every combination of λ × cascade count × resolution (× fit, × the other
//! axes) of one scene, analysed in parallel, then reduced to a Pareto front and a
//! recommendation.
//!
//! The folder points one way: [`grid`] (the axes and their points) is at the bottom, [`run`]
//! (parallel evaluation) uses it, [`rank`] (objective, front, recommendation) uses both; the
//! sun, light update, split optimisation, flicker sample, shard and engine-terms parts use
//! those three and never each other's parent; this file holds [`SweepResult`], every decision
//! of a sweep computed once, and is the only one that uses the children.

pub(crate) mod feasible;
pub mod flicker;
pub mod grid;
pub mod level;
pub(crate) mod light;
pub mod optimize;
pub mod rank;
pub mod run;
pub(crate) mod shard;
pub(crate) mod sun;
pub(crate) mod terms;

use crate::commands::terms::EngineSetting;
use crate::config::sweep_spec::DEFAULT_BUDGET_MIB;
use crate::config::Config;
use crate::error::Result;
use crate::metric::SummaryMetric;

use self::flicker::FlickerSample;
use self::grid::{FitGroup, Grid};
use self::light::UpdateChoice;
use self::optimize::Optimized;
use self::rank::{Alternative, NoRecommendation, RangeEdge, Recommendation, Rival};
use self::run::Row;
use self::sun::SunRows;

/// Everything a sweep produced, every decision made once ([`SweepResult::new`]): the reports
/// and figures only read these fields.
#[derive(Debug, Clone)]
pub struct SweepResult {
    pub config: Config,
    pub grid: Grid,
    /// One row per setting. In a sun sweep, each setting's judged row (its worst sun angle,
    /// [`sun::judge`]); every (sun, setting) row is in [`Self::sun`].
    pub rows: Vec<Row>,
    /// Every row of a sun sweep and each setting's worst sun; None without sun axes.
    pub sun: Option<SunRows>,
    /// A sun sweep without scene geometry: what the light cannot change ([`sun::bounds_only_note`]).
    pub(crate) sun_note: Option<String>,
    pub front: Vec<usize>,
    pub recommendation: Option<Recommendation>,
    /// How many rows fail each test of the recommendation rule, and the row that comes
    /// closest ([`rank::no_recommendation`]): what the reports say when nothing is recommended.
    pub(crate) no_recommendation: NoRecommendation,
    pub budget_mib: f64,
    /// The render-cost budget (`[sweep] cost_budget`, `shadow_ms_budget`).
    pub cost_limit: rank::CostLimit,
    /// With a cost budget that changed the recommendation: the row recommended without it
    /// (what the budget cost in quality is the difference).
    pub(crate) without_cost_budget: Option<usize>,
    /// The Pareto front of `cost_index` against the objective (`cost_pareto.png`); empty
    /// without scene geometry.
    pub cost_front: Vec<usize>,
    /// The command that reproduces the sweep.
    pub command: String,
    /// The metric the recommendation minimises ([`rank::default_objective`]).
    pub objective: SummaryMetric,
    /// The worst case the recommendation breaks near-ties on and the reports print as "worst"
    /// ([`crate::metric::worst_aliasing`]): on screen with geometry, else the bounds'
    /// `max_aliasing`.
    pub(crate) worst: SummaryMetric,
    /// The recommendation rule in words ([`rank::objective_text`]).
    pub(crate) objective_text: String,
    /// The row of the configured setting, when the grid has it ([`rank::configured`]).
    pub(crate) configured: Option<usize>,
    /// Rows in objective order, the recommendation first ([`rank::ranked`]).
    pub(crate) ranked: Vec<usize>,
    /// The alternatives to the recommendation ([`rank::alternatives`]); empty without one.
    pub(crate) alternatives: Vec<Alternative>,
    /// The main rivals of the recommendation and why each lost ([`rank::rivals`]); empty
    /// without one.
    pub(crate) rivals: Vec<Rival>,
    /// The swept axes at whose first or last value the recommendation sits, with the range to
    /// try next ([`rank::range_edges`]); empty without a recommendation or when none is.
    pub range_edges: Vec<RangeEdge>,
    /// The distinct fit groups of the rows, in order (one panel or series each in the figures).
    pub(crate) fit_groups: Vec<FitGroup>,
    /// The light update choice of a sweep with a light update axis ([`light::choose`]).
    pub light_update: Option<UpdateChoice>,
    /// The engine setting `recommendation.<engine>.txt` holds, for a sweep over a preset
    /// ([`terms::for_sweep`]).
    pub engine_setting: Option<EngineSetting>,
    /// The free split fractions of `--optimize-splits`, when asked for.
    pub optimized: Option<Optimized>,
    /// S3, S4 and the measured flicker S5 of a sample of the rows (`--ground-truth`).
    pub flicker: Option<FlickerSample>,
    /// A level of views: each view's own choice, the level's cost to it and the worst view
    /// ([`level::choose`]); None without configured views or scene geometry.
    pub level: Option<level::LevelChoice>,
    /// `--shard K/N`: these rows are one slice of the grid, which decides nothing (only `merge`
    /// of every slice does): the shard writes its rows, and no front, recommendation, report
    /// or worst sun is read from it ([`SweepResult::into_slice`]).
    pub slice: Option<shard::Shard>,
}

impl SweepResult {
    /// The result of a sweep's rows, in grid order ([`Grid::settings`]; with sun axes every
    /// (sun, setting) row, judged here per setting by its worst sun angle). With a level of
    /// views, the row at the level's choice ([`level::LevelChoice::at`]) gets every view's own
    /// screen metrics in full ([`crate::analysis::Summary::views`]; the rows keep only what the
    /// ranking reads). Fails only when the engine setting to write cannot be built or the
    /// shown row's setting no longer applies to `config`.
    pub fn new(config: Config, grid: Grid, mut rows: Vec<Row>, command: String) -> Result<Self> {
        // Every row's cost against the configured setting's (1 = as configured).
        let reference = crate::analysis::cost::configured_model(&config);
        for r in rows.iter_mut() {
            r.summary.cost.normalise(reference);
        }
        let cost_limit = rank::CostLimit::of(&config);
        let budget_mib = config
            .sweep
            .as_ref()
            .and_then(|s| s.memory_budget_mib)
            .unwrap_or(DEFAULT_BUDGET_MIB);
        let objective = rank::default_objective(&config);
        let worst = crate::metric::worst_aliasing(config.geometry.is_some());
        let (rows, sun, sun_note) = match &grid.sun {
            None => (rows, None, None),
            Some(_) => {
                let (judged, sun) = sun::judge(rows, objective);
                (judged, Some(sun), sun::bounds_only_note(&config, &grid.fit.values))
            }
        };
        let front = rank::pareto_front_by(&rows, objective);
        let cost_front = rank::cost_front(&rows, objective);
        let recommendation = rank::recommend_within(&rows, budget_mib, cost_limit, objective, worst);
        let without_cost_budget = if cost_limit.is_set() {
            rank::recommend_by(&rows, budget_mib, objective, worst)
                .map(|r| r.index)
                .filter(|&i| Some(i) != recommendation.as_ref().map(|r| r.index))
        } else {
            None
        };
        let no_recommendation = rank::no_recommendation(&rows, budget_mib, objective);
        let configured = rank::configured(&config, &rows);
        let ranked = rank::ranked(&rows, recommendation.as_ref(), budget_mib, objective, worst);
        let (alternatives, rivals) = match &recommendation {
            None => (Vec::new(), Vec::new()),
            Some(rec) => (
                rank::alternatives(&rows, rec, objective),
                rank::rivals(
                    &rows,
                    rec,
                    &ranked,
                    configured,
                    grid.lambda.values.len() > 1,
                    objective,
                    worst,
                ),
            ),
        };
        let range_edges = rank::range_edges(&config, &grid, &rows, recommendation.as_ref());
        let at = recommendation.as_ref().map(|x| x.index).or(configured).unwrap_or(0);
        let light_update = light::choose(&grid, &rows, at);
        let level = level::choose(
            &rows,
            recommendation.as_ref(),
            configured,
            budget_mib,
            cost_limit,
            objective,
            &config.views,
        );
        // The rows keep of each view only what the ranking reads; the one row that shows every
        // view's own metrics (`views.csv`, the report's views) has them measured in full here,
        // at its setting (its sun angle included), as `analyze` measures them.
        let mut rows = rows;
        if let Some(c) = &level {
            let shown = rows[c.at].setting.apply(&config)?;
            rows[c.at].summary.views = crate::analysis::level_views(&shown).unwrap_or_default();
        }
        let engine_setting = terms::for_sweep(
            &config,
            &command,
            objective,
            &rows,
            recommendation.as_ref(),
            &no_recommendation,
        )?;
        Ok(SweepResult {
            objective_text: rank::objective_text(objective, worst),
            worst,
            fit_groups: rank::fits_in(&rows),
            objective,
            config,
            grid,
            rows,
            sun,
            sun_note,
            front,
            recommendation,
            no_recommendation,
            budget_mib,
            cost_limit,
            without_cost_budget,
            cost_front,
            command,
            configured,
            ranked,
            alternatives,
            rivals,
            range_edges,
            light_update,
            engine_setting,
            optimized: None,
            flicker: None,
            level,
            slice: None,
        })
    }

    /// The result of shard `shard`'s rows: `new`'s, marked as a slice ([`Self::slice`]).
    pub(crate) fn into_slice(mut self, shard: shard::Shard) -> Self {
        self.slice = Some(shard);
        self
    }

    pub fn recommended(&self) -> Option<&Row> {
        self.recommendation.as_ref().map(|r| &self.rows[r.index])
    }
}
