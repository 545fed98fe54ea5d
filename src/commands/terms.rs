//! Which setting `recommendation.<engine>.txt` holds (the text itself is the engine's own,
//! [`crate::presets::render`]):
//!
//! * `sweep` over a preset: the recommended row's setting; when no row is acceptable, the
//!   closest row's (said in a comment line); when no row needs cascades, the configured one.
//! * `compare`: for each engine compared, its setting closest to csm-lab's own cascades for the
//!   file's `[shadow]` settings: the engine's count nearest the file's, the shadow distance at
//!   the far end of csm-lab's last cascade, and the split knobs matched to csm-lab's boundaries
//!   ([`crate::presets::DynEngine::match_ends`]: exactly for free fractions, by a 1-D fit
//!   otherwise). `docs/presets.md`, "Engine settings files", states the rule.

use crate::config::Config;
use crate::error::Result;
use crate::output::short_number;
use crate::presets::{Dims, Knobs, PresetName, Target};

use super::compare::{preset_of, Comparison};
use super::sweep::{no_recommendation, Row, SweepResult};

/// One engine's setting, ready to be written in its own terms.
#[derive(Debug, Clone, PartialEq)]
pub struct EngineSetting {
    pub preset: PresetName,
    pub knobs: Knobs,
    pub dims: Dims,
    /// The camera planes (split rules that depend on them).
    pub near: f64,
    pub far: f64,
    /// Comment lines: where the setting comes from, and how close it comes.
    pub comments: Vec<String>,
}

impl EngineSetting {
    /// The setting of a config with a preset applied.
    pub fn of(config: &Config, comments: Vec<String>) -> Option<EngineSetting> {
        let p = config.shadow.preset.as_ref()?;
        Some(EngineSetting {
            preset: p.name,
            knobs: p.knobs.clone(),
            dims: Dims::of(config),
            near: config.camera.near,
            far: config.camera.far,
            comments,
        })
    }

    /// `recommendation.<engine>.txt`.
    pub fn file_name(&self) -> String {
        file_name(self.preset)
    }
}

/// `recommendation.<engine>.txt`.
pub fn file_name(p: PresetName) -> String {
    format!("recommendation.{p}.txt")
}

/// The setting a sweep over a preset recommends (None without a preset).
pub fn for_sweep(r: &SweepResult) -> Result<Option<EngineSetting>> {
    if r.config.shadow.preset.is_none() {
        return Ok(None);
    }
    let mut comments = vec![format!("from: {}", r.command)];
    let row = match r.recommended() {
        Some(row) => {
            comments.push(format!(
                "the recommended setting: {} ({} {}{})",
                setting_words(r, row),
                r.objective.name(),
                short_number(r.objective.value(&row.summary)),
                if r.recommendation.as_ref().is_some_and(|x| !x.within_budget) {
                    "; nothing fits the memory budget, so the cheapest acceptable"
                } else {
                    ""
                }
            ));
            Some(row)
        }
        None => {
            let nr = no_recommendation(&r.rows, r.budget_mib, r.objective);
            match nr.closest {
                Some(i) => {
                    let row = &r.rows[i];
                    comments.push(format!(
                        "NOT RECOMMENDED: no configuration is acceptable (covers every slice and is stable when snapped); \
                         this is the closest one: {} ({} slice corners missed, snapped shimmer {} texel)",
                        setting_words(r, row),
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
            }
        }
    };
    let config = match row {
        Some(row) => row.setting.apply(&r.config)?,
        None => r.config.clone(),
    };
    Ok(EngineSetting::of(&config, comments))
}

/// "4 x 2048^2, first_cascade_far_bound 7.5": a sweep row's setting in the knobs the swept
/// pipeline has (never a λ or fit an engine lacks).
fn setting_words(r: &SweepResult, row: &Row) -> String {
    let axes = crate::presets::axes(&r.config);
    let s = &row.setting;
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

/// The count of `list` nearest `n` (the larger on a tie).
fn nearest_count(list: &[usize], n: usize) -> usize {
    list.iter()
        .copied()
        .min_by_key(|&c| (c.abs_diff(n), std::cmp::Reverse(c)))
        .unwrap_or(n)
}

/// A power of two near `n`: `n` itself when it is one, else the next.
fn power_of_two(n: u32) -> u32 {
    n.checked_next_power_of_two().unwrap_or(1 << 31)
}

fn list(xs: &[f64]) -> String {
    xs.iter().map(|x| short_number(*x)).collect::<Vec<_>>().join(", ")
}

/// Each compared engine's setting closest to csm-lab's own cascades for the file's `[shadow]`
/// settings (`scene`: the file without a preset applied). Analyses without a preset (csm-lab's
/// own, `--split-range`) give none.
pub fn for_compare(c: &Comparison, scene: &Config) -> Result<Vec<EngineSetting>> {
    let mut out = Vec::new();
    for a in &c.analyses {
        let Some(name) = preset_of(a) else { continue };
        let config = &a.config;
        let engine = name.engine();
        let preset = config.shadow.preset.as_ref().expect("a preset");
        let mut knobs = preset.knobs.clone();
        let counts = engine.counts(&knobs).list();
        let n = nearest_count(&counts, scene.shadow.cascades);
        let mut own = scene.clone();
        own.shadow.preset = None;
        // csm-lab's own cascades at the engine's count; when there are none (the scene is not
        // visible, or the count does not fit the file's binary32 range), the setting compared.
        let own_rig = own.with_cascades(n).map(|o| crate::analysis::rig(&o));
        let Ok(Some(rig)) = own_rig else {
            let why = match own_rig {
                Err(e) => format!("csm-lab's own pipeline cannot run at {n} cascades here ({e})"),
                _ => "csm-lab's own pipeline needs no cascades for this scene".to_string(),
            };
            let comments = vec![
                format!("from: {}", c.command()),
                format!("{why}: this is the setting compared"),
            ];
            out.extend(EngineSetting::of(config, comments));
            continue;
        };
        let mut ends = vec![rig.slices[0].near];
        ends.extend(rig.slices.iter().map(|s| s.far));
        let (near, far) = (config.camera.near, config.camera.far);
        let distance = *ends.last().expect("a cascade");
        let engine_distance = if engine.has_distance() {
            distance
        } else {
            config.shadow.max_distance
        };
        let target = Target {
            ends: &ends,
            distance: engine_distance,
            near,
            far,
        };
        engine.match_ends(&mut knobs, &target);
        let resolution = if engine.power_of_two_maps() {
            power_of_two(scene.shadow.resolution)
        } else {
            scene.shadow.resolution
        };
        let cascades = engine.counts(&knobs).list();
        let n_used = nearest_count(&cascades, n);
        let dims = Dims {
            cascades: n_used,
            resolution,
            max_distance: engine.has_distance().then_some(distance),
        };
        let lay = engine.layout(&knobs, n_used, engine_distance, near, far);
        let engine_ends: Vec<f64> = lay.fitted.iter().map(|s| s.1).collect();
        let worst = engine_ends
            .iter()
            .zip(&ends[1..])
            .map(|(e, d)| ((e - d) / d).abs())
            .fold(0.0, f64::max);
        let mut comments = vec![
            format!("from: {}", c.command()),
            format!(
                "the setting of {name} closest to csm-lab's own cascades for this file's [shadow] settings \
                 (λ {}, {} cascades of {}², shadow distance {})",
                short_number(scene.shadow.lambda),
                n,
                resolution,
                short_number(scene.shadow.max_distance)
            ),
            format!("csm-lab's cascades end at {}", list(&ends[1..])),
            format!(
                "these settings' cascades end at {} (largest difference {} %)",
                list(&engine_ends),
                short_number(100.0 * worst)
            ),
        ];
        if n != scene.shadow.cascades {
            comments.push(format!(
                "{name} does not take {} cascades: {n}, the nearest count it takes",
                scene.shadow.cascades
            ));
        }
        if n_used != n {
            comments.push(format!("the split knobs fix the count at {n_used}"));
        }
        if resolution != scene.shadow.resolution {
            comments.push(format!(
                "{name} takes power-of-two maps only: {resolution} for the file's {}",
                scene.shadow.resolution
            ));
        }
        out.push(EngineSetting {
            preset: name,
            knobs,
            dims,
            near,
            far,
            comments,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_counts_prefer_the_larger_on_a_tie() {
        assert_eq!(nearest_count(&[1, 2, 4], 3), 4);
        assert_eq!(nearest_count(&[1, 2, 4], 8), 4);
        assert_eq!(nearest_count(&[1, 2, 3, 4], 3), 3);
        assert_eq!(nearest_count(&[4], 1), 4);
        assert_eq!(power_of_two(1000), 1024);
        assert_eq!(power_of_two(2048), 2048);
    }
}
