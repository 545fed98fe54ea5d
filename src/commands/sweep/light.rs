//! A sweep over the light update rule (`--light-update`, `[sweep] light_update`): the largest
//! update step whose jumps stay under one texel.

use crate::commands::sweep::grid::{Grid, Setting};
use crate::commands::sweep::run::Row;
use csm_core::light_motion::LightUpdate;

/// A jump under this many texels is no visible jump.
pub(crate) const CALM_JUMP: f64 = 1.0;

/// One update rule of the reference setting: its `light_jump` and `light_crawl`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateRow {
    pub update: LightUpdate,
    pub jump: f64,
    pub crawl: f64,
}

/// The light update axis at one setting of the other axes.
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateChoice {
    /// The grid index of the setting the rules were compared at (the recommended row's setting
    /// when there is one, else the configured setting's, else the first row's).
    pub at: usize,
    /// Every swept rule there, in axis order.
    pub rows: Vec<UpdateRow>,
    /// Per kind (every K frames, then a q-degree grid), the largest step whose `light_jump`
    /// stays under [`CALM_JUMP`]; None for a kind none of whose steps does.
    pub every: Option<UpdateRow>,
    pub quantize: Option<UpdateRow>,
    /// The choice in one sentence for stdout and the reports.
    pub(crate) sentence: String,
}

/// The step of a rule: K frames, or q radians.
fn step(u: LightUpdate) -> f64 {
    match u {
        LightUpdate::EveryFrame => 1.0,
        LightUpdate::EveryFrames(k) => k as f64,
        LightUpdate::Quantize(q) => q,
    }
}

/// The choice of a sweep with a light update axis (None without one), made at row `at` of the
/// (judged) `rows`: the recommended row when there is one, else the configured setting's, else
/// the first row.
pub(crate) fn choose(grid: &Grid, rows: &[Row], at: usize) -> Option<UpdateChoice> {
    grid.light_update.as_ref()?;
    let base = rows.get(at)?.setting;
    let same = |s: &Setting| {
        Setting {
            light_update: base.light_update,
            ..*s
        } == base
    };
    let rows: Vec<UpdateRow> = rows
        .iter()
        .filter(|x| same(&x.setting))
        .filter_map(|x| {
            let l = x.summary.light?;
            Some(UpdateRow {
                update: x.setting.light_update?,
                jump: l.jump,
                crawl: l.crawl,
            })
        })
        .collect();
    let largest = |every: bool| {
        rows.iter()
            .filter(|x| matches!(x.update, LightUpdate::Quantize(_)) != every && x.jump < CALM_JUMP)
            .max_by(|a, b| step(a.update).total_cmp(&step(b.update)))
            .copied()
    };
    let (every, quantize) = (largest(true), largest(false));
    Some(UpdateChoice {
        sentence: text(&rows, every, quantize),
        at,
        every,
        quantize,
        rows,
    })
}

/// The choice in one sentence: the largest calm step of each kind swept among `rows`.
fn text(rows: &[UpdateRow], every: Option<UpdateRow>, quantize: Option<UpdateRow>) -> String {
    let label = |x: &UpdateRow| crate::config::light_update_label(x.update);
    let mut parts = Vec::new();
    let kinds = [
        ("every", every, "re-aiming every K frames"),
        ("quantize", quantize, "a q-degree grid"),
    ];
    for (kind, best, words) in kinds {
        let swept = rows.iter().any(|x| label(x).starts_with(kind));
        match (swept, best) {
            (false, _) => {}
            (true, Some(x)) => parts.push(format!(
                "{} is the largest step of {words} whose jumps stay under {CALM_JUMP} texel (light_jump {:.3}, light_crawl {:.3})",
                label(&x),
                x.jump,
                x.crawl
            )),
            (true, None) => parts.push(format!(
                "no step of {words} keeps its jumps under {CALM_JUMP} texel (smallest light_jump {:.3})",
                rows.iter()
                    .filter(|x| label(x).starts_with(kind))
                    .map(|x| x.jump)
                    .fold(f64::INFINITY, f64::min)
            )),
        }
    }
    format!("light update: {}.", parts.join("; "))
}
