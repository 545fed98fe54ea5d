//! Which setting `recommendation.<engine>.txt` holds after a `sweep` over a preset: the
//! recommended row's setting; when no row is acceptable, the closest row's (said in a comment
//! line); when no row needs cascades, the configured one.

use crate::commands::sweep::grid::Setting;
use crate::commands::sweep::rank::{NoRecommendation, Recommendation};
use crate::commands::sweep::run::Row;
use crate::commands::terms::EngineSetting;
use crate::config::Config;
use crate::error::Result;
use crate::metric::SummaryMetric;
use crate::output::short_number;

/// The setting a sweep over a preset (`config`, run as `command`) recommends; None without a
/// preset. `rows` are the sweep's (judged) rows, `recommendation` and `no_recommendation` its
/// decisions ([`crate::commands::sweep::rank`]).
pub(crate) fn for_sweep(
    config: &Config,
    command: &str,
    objective: SummaryMetric,
    rows: &[Row],
    recommendation: Option<&Recommendation>,
    no_recommendation: &NoRecommendation,
) -> Result<Option<EngineSetting>> {
    if config.shadow.preset.is_none() {
        return Ok(None);
    }
    let mut comments = vec![format!("from: {command}")];
    let row = match recommendation.map(|r| &rows[r.index]) {
        Some(row) => {
            comments.push(format!(
                "the recommended setting: {} ({} {}{})",
                setting_words(config, &row.setting),
                objective.name(),
                short_number(objective.value(&row.summary)),
                if recommendation.is_some_and(|x| !x.within_budget) {
                    "; nothing fits the memory budget, so the cheapest acceptable"
                } else {
                    ""
                }
            ));
            Some(row)
        }
        None => match no_recommendation.closest {
            Some(i) => {
                let row = &rows[i];
                comments.push(format!(
                    "NOT RECOMMENDED: no configuration is acceptable (covers every slice and is stable when snapped); \
                         this is the closest one: {} ({} slice corners missed, snapped shimmer {} texel)",
                    setting_words(config, &row.setting),
                    row.summary.coverage_violations,
                    short_number(row.summary.shimmer_snapped)
                ));
                Some(row)
            }
            None => {
                comments.push(
                    "NOT RECOMMENDED: the scene needs no cascades in any configuration; this is the configured setting"
                        .to_string(),
                );
                None
            }
        },
    };
    let config = match row {
        Some(row) => row.setting.apply(config)?,
        None => config.clone(),
    };
    Ok(EngineSetting::of(&config, comments))
}

/// "4 x 2048^2, first_cascade_far_bound 7.5": a sweep row's setting in the knobs the swept
/// pipeline has (never a λ or fit an engine lacks).
fn setting_words(config: &Config, s: &Setting) -> String {
    let axes = crate::presets::axes(config);
    let mut words = format!("{} x {}^2", s.cascades, s.resolution);
    if let Some(key) = axes.lambda {
        words.push_str(&format!(", {key} {}", s.lambda));
    }
    if axes.fit {
        words.push_str(&format!(", {} fit", s.fit));
    }
    if let (Some(k), Some(v)) = (axes.knob, s.knob) {
        words.push_str(&format!(", {} {v}", k.term));
    }
    if let Some(d) = s.distance {
        words.push_str(&format!(", shadow distance {d}"));
    }
    words
}
