//! `csm-lab compare`: several engine presets on one scene, side by side.
//!
//! The config file is read once; each preset is applied to it (its `[shadow]` overrides and its own
//! engine table apply, unless `--defaults` asks for every preset's own defaults) and analysed
//! exactly as `analyze` would. The outputs ([`crate::report::compare`],
//! [`crate::figures::compare`]), rendered in memory and then written atomically:
//!
//! * `compare.csv`: one row per preset: `preset` then the sweep columns, then the coverage and
//!   light-depth findings;
//! * `compare_density.svg/.png`: texels per pixel against view depth, one line per preset;
//! * `compare_shimmer.svg/.png`: shimmer with and without snapping, and coverage, per preset;
//! * `compare.html` (self-contained: inline CSS and SVG, nothing fetched) and `compare.md`.
//!
//! `--split-range bounds,visible` adds csm-lab's own pipeline (the file's `[shadow]` settings)
//! after the presets, once with its splits on the bounds' depth range and once on the visible
//! depths (scene geometry only): the two placements side by side with the engines.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::analysis::{analyze, Analysis, AnalysisOptions};
use crate::commands::terms::EngineSetting;
use crate::config::{Config, SplitRange};
use crate::error::{Error, Result};
use crate::output::short_number;
use crate::presets::{Dims, PresetChoice, PresetName, Target};

/// The presets compared and their analyses, in the order given.
#[derive(Debug, Clone)]
pub struct Comparison {
    pub config_path: PathBuf,
    /// The config file's stem.
    pub name: String,
    /// True when every preset ran at its own defaults (`--defaults`).
    pub engine_defaults: bool,
    /// The split ranges of csm-lab's own pipeline added after the presets (`--split-range`).
    pub own: Vec<SplitRange>,
    pub analyses: Vec<Analysis>,
    /// Which valid entry is best by the objective, and why the others are left out
    /// ([`verdict`]): the reports only read it.
    pub verdict: Verdict,
}

/// What `compare` decides: the valid entries (every slice corner covered, no receiver clipped,
/// cascades needed) ranked by the objective a sweep of this scene minimises, and the invalid
/// ones apart with their reasons.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// The metric ranked on ([`crate::commands::sweep::rank::default_objective`]).
    pub objective: crate::metric::SummaryMetric,
    /// Indices into `analyses` of the valid entries, best (lowest objective) first; ties keep
    /// the order given.
    pub ranked: Vec<usize>,
    /// Indices into `analyses` of the invalid entries and why, in the order given.
    pub invalid: Vec<(usize, String)>,
}

impl Verdict {
    /// The verdict in one line: the best and by how much it beats the runner-up.
    pub(crate) fn line(&self, analyses: &[Analysis]) -> String {
        let name = self.objective.name();
        let value = |i: usize| self.objective.value(&analyses[i].summary);
        match self.ranked.as_slice() {
            [] => format!(
                "no best: none of the {} entries is valid (every one misses slice corners, clips receivers or needs no cascades)",
                analyses.len()
            ),
            [b] => format!(
                "best: {} ({name} {}), the only valid entry",
                label(&analyses[*b]),
                short_number(value(*b))
            ),
            [b, r, ..] => {
                let (vb, vr) = (value(*b), value(*r));
                // Entries that give the same maps (unity and unity-urp) tie.
                let by = if vr > vb {
                    format!("{} % lower than", short_number(100.0 * (vr - vb) / vr))
                } else {
                    "tied with".to_string()
                };
                format!(
                    "best: {} ({name} {}), {by} the runner-up {} ({}), of {} valid entries",
                    label(&analyses[*b]),
                    short_number(vb),
                    label(&analyses[*r]),
                    short_number(vr),
                    self.ranked.len()
                )
            }
        }
    }

    /// One line per invalid entry: its name and why it is left out.
    pub(crate) fn invalid_lines(&self, analyses: &[Analysis]) -> Vec<String> {
        self.invalid
            .iter()
            .map(|(i, why)| format!("{}: {why}", label(&analyses[*i])))
            .collect()
    }
}

/// Ranks the valid analyses by the objective of `scene` (lowest first) and sets the invalid
/// apart ([`invalid_reason`]; an entry whose scene needs no cascades is not valid either).
pub(crate) fn verdict(scene: &Config, analyses: &[Analysis]) -> Verdict {
    let objective = crate::commands::sweep::rank::default_objective(scene);
    let mut invalid = Vec::new();
    let mut ranked = Vec::new();
    for (i, a) in analyses.iter().enumerate() {
        let why = invalid_reason(a).or_else(|| {
            (!a.summary.cascades_needed)
                .then(|| "no cascades: the scene is not visible within its shadow distance".to_string())
        });
        match why {
            Some(w) => invalid.push((i, w)),
            None => ranked.push(i),
        }
    }
    ranked.sort_by(|&a, &b| {
        objective
            .value(&analyses[a].summary)
            .total_cmp(&objective.value(&analyses[b].summary))
            .then(a.cmp(&b))
    });
    Verdict {
        objective,
        ranked,
        invalid,
    }
}

impl Comparison {
    /// The command line that reproduces this comparison.
    pub fn command(&self) -> String {
        let names: Vec<&str> = self
            .analyses
            .iter()
            .filter_map(|a| preset_of(a).map(|p| p.as_str()))
            .collect();
        let own = match self.own.as_slice() {
            [] => String::new(),
            r => format!(
                " --split-range {}",
                r.iter().map(|x| x.name()).collect::<Vec<_>>().join(",")
            ),
        };
        format!(
            "csm-lab compare {} --presets {}{}{own}",
            self.config_path.display(),
            names.join(","),
            if self.engine_defaults { " --defaults" } else { "" }
        )
    }
}

/// How reports name an analysis: its preset, or csm-lab's own pipeline with the depths its
/// splits divide (`csm-lab (bounds)`, `csm-lab (visible)`).
pub fn label(a: &Analysis) -> String {
    match preset_of(a) {
        Some(p) => p.to_string(),
        None => format!(
            "csm-lab ({})",
            crate::config::SplitRange::of(a.config.shadow.fit_depth_to_visible)
        ),
    }
}

/// Why a preset's result cannot be used as it stands: slice corners its windows miss (those
/// points read "lit"), or receivers outside its light depth range (clipped). None when valid.
pub(crate) fn invalid_reason(a: &Analysis) -> Option<String> {
    let mut why = Vec::new();
    let misses = a.summary.coverage_violations;
    if misses > 0 {
        why.push(format!("{} missed", crate::output::count(misses, "slice corner")));
    }
    let clipped = a.preset.as_ref().map_or(0.0, |p| p.receivers_outside_depth);
    if clipped > 0.0 {
        why.push(format!(
            "receivers clipped by {} world units of light depth",
            short_number(clipped)
        ));
    }
    (!why.is_empty()).then(|| why.join("; "))
}

/// The preset an analysis ran, if any.
pub(crate) fn preset_of(a: &Analysis) -> Option<PresetName> {
    a.config.shadow.preset.as_ref().map(|p| p.name)
}

/// Loads and validates the config once, applies each preset to a copy (its engine table from
/// the file still applies) and analyses each (in parallel, results in input order).
pub fn run(path: &Path, presets: &[PresetName], engine_defaults: bool, own: &[SplitRange]) -> Result<Comparison> {
    run_with_progress(path, presets, engine_defaults, own, &|| ())
}

/// [`run`], calling `on_done` after each analysis (from any thread).
pub(crate) fn run_with_progress(
    path: &Path,
    presets: &[PresetName],
    engine_defaults: bool,
    own: &[SplitRange],
    on_done: &(dyn Fn() + Sync),
) -> Result<Comparison> {
    if presets.is_empty() {
        return Err(Error::flag("--presets", "", "give at least one preset"));
    }
    let scene = Config::load_scene(path)?;
    let configs = presets
        .iter()
        .map(|p| {
            let choice = PresetChoice {
                name: Some(*p),
                also_allowed: presets.to_vec(),
                engine_defaults,
                lenient_overrides: true,
            };
            let mut config = scene.clone();
            crate::load::apply_preset(&mut config, &choice)?;
            Ok(config)
        })
        .collect::<Result<Vec<_>>>()?;
    let mut configs = configs;
    for &range in own {
        crate::commands::sweep::grid::check_split_ranges(&scene, &[range], range.name())?;
        let mut own_config = scene.clone();
        own_config.shadow.preset = None;
        configs.push(own_config.with_split_range(range)?);
    }
    let name = configs[0].name.clone();
    // One visibility pass, made before the parallel part and shared by every preset.
    for c in &configs {
        let _ = c.setup().visibility();
    }
    let analyses = configs
        .par_iter()
        .map(|c| {
            let a = analyze(c, &AnalysisOptions::full());
            on_done();
            a
        })
        .collect();
    let mut analyses: Vec<Analysis> = analyses;
    // Each preset's render cost against the scene file's own setting (its cost_index 1).
    let reference = crate::analysis::cost::configured_model(&scene);
    for a in analyses.iter_mut() {
        a.summary.cost.normalise(reference);
    }
    Ok(Comparison {
        config_path: path.to_path_buf(),
        name,
        engine_defaults,
        own: own.to_vec(),
        verdict: verdict(&scene, &analyses),
        analyses,
    })
}

/// Worst coverage miss (texels) and smallest slack over the configured snap mode's path.
pub(crate) fn coverage_extremes(a: &Analysis) -> (f64, f64) {
    a.configured_path().map_or((0.0, 0.0), |p| {
        (
            p.coverage.worst_texels.iter().cloned().fold(0.0, f64::max),
            p.coverage
                .min_slack_texels
                .iter()
                .cloned()
                .fold(f64::INFINITY, f64::min),
        )
    })
}

/// The fit as the preset names it (csm-lab's own fit without a preset).
pub(crate) fn fit_label(a: &Analysis) -> String {
    a.rig()
        .map_or_else(|| a.config.shadow.fit.to_string(), |r| r.scheme.fit_label.clone())
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
pub fn engine_settings(c: &Comparison, scene: &Config) -> Result<Vec<EngineSetting>> {
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
