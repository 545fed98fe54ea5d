//! Parameter sweeps: every combination of λ × cascade count × resolution (× fit) of one
//! scene, analysed in parallel, then reduced to a Pareto front and a recommendation.
//!
//! Axes come from the config's `[sweep]` table and can be overridden on the command line.
//! Ranges are decimal-exact: `0 to 1 step 0.05` is computed in scaled integers and gives
//! exactly 21 values, the last one exactly 1.0. Rows come out in grid order whatever the
//! thread count (rayon's indexed `collect` keeps order), so files are byte-identical.

use std::collections::BTreeSet;

use rayon::prelude::*;

use crate::analysis::{analyze, AnalysisOptions, Summary};
use crate::config::{Config, Fit, SplitRange};
use crate::error::{Error, GridError, Result};
use crate::metric::SummaryMetric;
use csm_core::light_motion::LightUpdate;

pub use crate::commands::sun_sweep::{parse_sun_azimuth_spec, parse_sun_elevation_spec, Sun, SunGrid, SunRows};

pub use crate::config::sweep_spec::{
    cascades_ok, check_values, decimal_range, fmt_list, lambda_ok, resolution_ok, Axis, SweepSpec, DEFAULT_BUDGET_MIB,
    DEFAULT_MAX_CONFIGS,
};

/// The grid of a sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    pub lambda: Axis<f64>,
    pub cascades: Axis<usize>,
    pub resolution: Axis<u32>,
    pub fit: Axis<Fit>,
    /// Splits on the bounds' depth range and/or on the visible depths (scene geometry only).
    pub split_range: Axis<SplitRange>,
    /// The preset's split knob (Unreal's exponent, Bevy's first far bound), when it has one.
    pub knob: Option<Axis<f64>>,
    /// Shadow distances (`shadow.max_distance`), when swept.
    pub distance: Option<Axis<f64>>,
    /// Sun angles (`--sun-azimuth`, `--sun-elevation`), when swept: every setting runs under
    /// every sun position ([`crate::commands::sun_sweep`]).
    pub sun: Option<SunGrid>,
    /// The light update rule (`shadow.light_update`), when swept (a moving light only).
    pub light_update: Option<Axis<LightUpdate>>,
    /// What was left out of the `[sweep]` table because the preset has no such axis or value.
    pub notes: Vec<String>,
}

// ---------------------------------------------------------------------------------------------
// Command-line specs
// ---------------------------------------------------------------------------------------------

/// `--lambda 0:1:0.05` (start:end:step, inclusive), `--lambda 0,0.5,1` or `--lambda 0.75`.
pub fn parse_lambda_spec(spec: &str) -> Result<Axis<f64>> {
    parse_numbers("--lambda", spec, ("0:1:0.05", "0,0.5,1"), "[0, 1]", lambda_ok)
}

fn parse_int_list<T>(flag: &str, spec: &str, allowed: &str, ok: impl Fn(T) -> bool, ranges: bool) -> Result<Axis<T>>
where
    T: std::str::FromStr + Copy + PartialOrd + std::fmt::Display + TryFrom<u64>,
{
    let err = |m: String| Error::flag(flag, spec, m);
    let one = |s: &str| {
        s.trim().parse::<T>().map_err(|_| {
            err(format!(
                "{s:?} is not a whole number; use {}",
                if ranges {
                    "a range (1..8) or a list (2,4)"
                } else {
                    "a list (1024,2048)"
                }
            ))
        })
    };
    let values: Vec<T> = if ranges && spec.contains("..") {
        let (a, b) = spec.split_once("..").expect("checked");
        let b = b.strip_prefix('=').unwrap_or(b);
        let (lo, hi): (u64, u64) = (
            a.trim()
                .parse()
                .map_err(|_| err("a range is first..last, e.g. 1..8".into()))?,
            b.trim()
                .parse()
                .map_err(|_| err("a range is first..last, e.g. 1..8".into()))?,
        );
        if hi < lo {
            return Err(err(format!("the range ends ({hi}) before it starts ({lo})")));
        }
        if hi - lo > 100_000 {
            return Err(err("the range is far too long".into()));
        }
        (lo..=hi)
            .map(|i| T::try_from(i).map_err(|_| err(format!("{i} is outside {allowed}"))))
            .collect::<Result<Vec<T>>>()?
    } else {
        spec.split(',').map(one).collect::<Result<Vec<T>>>()?
    };
    check_values(&values, allowed, ok).map_err(err)?;
    Ok(Axis {
        values,
        spec: spec.to_string(),
    })
}

/// `--knob 1,2,3` or `--knob 1:5:0.5` (values of a preset's split knob; range checked
/// against the engine in [`Grid::resolve`]), and likewise `--distance 50,100,150`.
pub fn parse_number_spec(flag: &str, spec: &str, allowed: &str, ok: impl Fn(f64) -> bool) -> Result<Axis<f64>> {
    parse_numbers(flag, spec, ("1:5:0.5", "1,2,3"), allowed, ok)
}

/// A decimal-exact range `start:end:step` or a comma list of numbers for `flag`, each value
/// `ok`; `(range, list)` are the examples its errors show.
fn parse_numbers(
    flag: &str,
    spec: &str,
    (range, list): (&str, &str),
    allowed: &str,
    ok: impl Fn(f64) -> bool,
) -> Result<Axis<f64>> {
    let err = |m: String| Error::flag(flag, spec, m);
    let num = |s: &str| {
        s.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
            err(format!(
                "{s:?} is not a number; use start:end:step ({range}) or a list ({list})"
            ))
        })
    };
    let values = if spec.contains(':') {
        let parts: Vec<&str> = spec.split(':').collect();
        if parts.len() != 3 {
            return Err(err(format!("a range is start:end:step, e.g. {range}")));
        }
        decimal_range(num(parts[0])?, num(parts[1])?, num(parts[2])?).map_err(err)?
    } else {
        spec.split(',').map(num).collect::<Result<Vec<_>>>()?
    };
    check_values(&values, allowed, ok).map_err(err)?;
    Ok(Axis {
        values,
        spec: spec.to_string(),
    })
}

/// `--knob VALUES`: the preset's split knob.
pub fn parse_knob_spec(spec: &str) -> Result<Axis<f64>> {
    parse_number_spec("--knob", spec, "finite numbers", f64::is_finite)
}

/// `--light-update RULES`: `every:1,2,4,8`, `quantize:0.1,0.25,0.5`, or both.
pub fn parse_light_update_spec(spec: &str) -> Result<Axis<LightUpdate>> {
    crate::config::parse_light_update_list(spec)
        .map(|values| Axis {
            values,
            spec: spec.to_string(),
        })
        .map_err(|why| Error::flag("--light-update", spec, why))
}

/// `--distance VALUES`: shadow distances in world units.
pub fn parse_distance_spec(spec: &str) -> Result<Axis<f64>> {
    parse_number_spec("--distance", spec, "(0, 1e9]", crate::config::sweep_spec::distance_ok)
}

/// `--cascades 1..8` (inclusive), `--cascades 2,4` or `--cascades 4`.
pub fn parse_cascades_spec(spec: &str) -> Result<Axis<usize>> {
    parse_int_list("--cascades", spec, "1..=16", cascades_ok, true)
}

/// `--resolution 1024,2048` or `--resolution 2048`.
pub fn parse_resolution_spec(spec: &str) -> Result<Axis<u32>> {
    parse_int_list("--resolution", spec, "16..=16384", resolution_ok, false)
}

/// A comma-separated list of named values (`--fit sphere,aabb`): each one of `choices`, none
/// twice. Errors name `flag`.
fn parse_named_list<T: Copy>(flag: &str, spec: &str, noun: &str, choices: &[(&str, T)]) -> Result<Axis<T>> {
    let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
    let picked = spec
        .split(',')
        .map(|s| {
            let s = s.trim();
            choices.iter().find(|c| c.0 == s).ok_or_else(|| {
                Error::flag(
                    flag,
                    spec,
                    format!("{s:?} is not a {noun}; use {} or {}", names.join(", "), names.join(",")),
                )
            })
        })
        .collect::<Result<Vec<_>>>()?;
    check_values(
        &picked.iter().map(|c| c.0).collect::<Vec<_>>(),
        &names.join(", "),
        |_| true,
    )
    .map_err(|m| Error::flag(flag, spec, m))?;
    Ok(Axis {
        values: picked.iter().map(|c| c.1).collect(),
        spec: spec.to_string(),
    })
}

/// `--fit sphere,aabb`.
pub fn parse_fit_spec(spec: &str) -> Result<Axis<Fit>> {
    parse_named_list("--fit", spec, "fit", &[("sphere", Fit::Sphere), ("aabb", Fit::Aabb)])
}

/// `--split-range bounds,visible`: splits on the bounds' depth range, on the visible depths,
/// or both side by side (scene geometry only; checked in [`Grid::resolve`]).
pub fn parse_split_range_spec(spec: &str) -> Result<Axis<SplitRange>> {
    parse_named_list(
        "--split-range",
        spec,
        "split range",
        &[("bounds", SplitRange::Bounds), ("visible", SplitRange::Visible)],
    )
}

/// The grid flags of a sweep as given on the command line (`--preset`, `--lambda`,
/// `--cascades`, `--resolution`, `--fit`, `--split-range`, `--knob`, `--distance`), unparsed:
/// what `sweep` reads and what a shard's manifest records for `merge` to replay.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GridFlags {
    pub preset: Option<String>,
    pub lambda: Option<String>,
    pub cascades: Option<String>,
    pub resolution: Option<String>,
    pub fit: Option<String>,
    pub split_range: Option<String>,
    /// `--knob`: the preset's split knob.
    pub knob: Option<String>,
    /// `--distance`: shadow distances.
    pub distance: Option<String>,
    /// `--sun-azimuth`: sun compass bearings, degrees.
    pub sun_azimuth: Option<String>,
    /// `--sun-elevation`: sun elevations, degrees.
    pub sun_elevation: Option<String>,
    /// `--light-update`: the light update rules.
    pub light_update: Option<String>,
}

impl GridFlags {
    /// The flags' names without dashes, in the order of [`GridFlags::values`].
    pub const KEYS: [&'static str; 11] = [
        "preset",
        "lambda",
        "cascades",
        "resolution",
        "fit",
        "split_range",
        "knob",
        "distance",
        "sun_azimuth",
        "sun_elevation",
        "light_update",
    ];

    pub fn values(&self) -> [&Option<String>; 11] {
        [
            &self.preset,
            &self.lambda,
            &self.cascades,
            &self.resolution,
            &self.fit,
            &self.split_range,
            &self.knob,
            &self.distance,
            &self.sun_azimuth,
            &self.sun_elevation,
            &self.light_update,
        ]
    }

    /// The flags from `get(key)` for each of [`GridFlags::KEYS`].
    pub fn from_keys(get: impl Fn(&str) -> Option<String>) -> Self {
        GridFlags {
            preset: get("preset"),
            lambda: get("lambda"),
            cascades: get("cascades"),
            resolution: get("resolution"),
            fit: get("fit"),
            split_range: get("split_range"),
            knob: get("knob"),
            distance: get("distance"),
            sun_azimuth: get("sun_azimuth"),
            sun_elevation: get("sun_elevation"),
            light_update: get("light_update"),
        }
    }

    /// The axis flags parsed; an error names its flag.
    pub fn overrides(&self) -> Result<GridOverrides> {
        Ok(GridOverrides {
            lambda: self.lambda.as_deref().map(parse_lambda_spec).transpose()?,
            cascades: self.cascades.as_deref().map(parse_cascades_spec).transpose()?,
            resolution: self.resolution.as_deref().map(parse_resolution_spec).transpose()?,
            fit: self.fit.as_deref().map(parse_fit_spec).transpose()?,
            split_range: self.split_range.as_deref().map(parse_split_range_spec).transpose()?,
            knob: self.knob.as_deref().map(parse_knob_spec).transpose()?,
            distance: self.distance.as_deref().map(parse_distance_spec).transpose()?,
            sun_azimuth: self.sun_azimuth.as_deref().map(parse_sun_azimuth_spec).transpose()?,
            sun_elevation: self
                .sun_elevation
                .as_deref()
                .map(parse_sun_elevation_spec)
                .transpose()?,
            light_update: self.light_update.as_deref().map(parse_light_update_spec).transpose()?,
        })
    }
}

/// `--split-range` = `spec` (`ranges` parsed) is refused when it asks for visible splits
/// without scene geometry.
pub fn check_split_ranges(config: &Config, ranges: &[SplitRange], spec: &str) -> Result<()> {
    if config.geometry.is_none() && ranges.contains(&SplitRange::Visible) {
        return Err(Error::flag(
            "--split-range",
            spec,
            "\"visible\" needs scene geometry (scene.ground, [[scene.box]] or scene.gltf): \
             the bounds alone show no visible depth; use bounds"
                .to_string(),
        ));
    }
    Ok(())
}

/// Command-line overrides of the grid.
#[derive(Debug, Clone, Default)]
pub struct GridOverrides {
    pub lambda: Option<Axis<f64>>,
    pub cascades: Option<Axis<usize>>,
    pub resolution: Option<Axis<u32>>,
    pub fit: Option<Axis<Fit>>,
    pub split_range: Option<Axis<SplitRange>>,
    pub knob: Option<Axis<f64>>,
    pub distance: Option<Axis<f64>>,
    pub sun_azimuth: Option<Axis<f64>>,
    pub sun_elevation: Option<Axis<f64>>,
    pub light_update: Option<Axis<LightUpdate>>,
}

impl Grid {
    /// The grid for a config: CLI overrides, then the `[sweep]` table, then the defaults
    /// (λ 0:1:0.05, cascades 1..8, resolution 512,1024,2048,4096, the config's own fit).
    ///
    /// With an engine preset the grid sweeps the axes that engine has: λ only where its split
    /// rule has one (otherwise the single value it uses), its allowed cascade counts, its map
    /// sizes; the fit is the preset's. Every point is checked here, before any work starts.
    pub fn resolve(config: &Config, overrides: &GridOverrides) -> Result<Grid> {
        let spec = config.sweep.clone().unwrap_or_default();
        let max_configs = if config.sweep.is_some() {
            spec.max_configs
        } else {
            DEFAULT_MAX_CONFIGS
        };
        let axes = crate::presets::axes(config);
        let preset = config.shadow.preset.as_ref();
        let source = |flag_given: bool, flag: &str, key: &str| {
            if flag_given {
                flag.to_string()
            } else {
                key.to_string()
            }
        };
        let mut notes = Vec::new();
        // Axes from the [sweep] table were written for csm-lab's own pipeline: with a preset,
        // what that engine lacks is dropped with a note. Axes given as flags must apply.
        let lambda_source = source(overrides.lambda.is_some(), "--lambda", "sweep.lambda");
        let lambda_axis = match (overrides.lambda.clone(), preset, axes.lambda) {
            (Some(axis), Some(p), None) => {
                return Err(Error::flag(
                    "--lambda",
                    &axis.spec,
                    format!(
                        "the {} preset has no λ to sweep ({}); drop --lambda",
                        p.name,
                        crate::presets::split_rule(&p.knobs)
                    ),
                ))
            }
            (Some(axis), _, _) => Some(axis),
            (None, Some(p), None) => {
                if let Some(axis) = &spec.lambda {
                    notes.push(format!(
                        "sweep.lambda = {} left out: the {} preset has no λ ({})",
                        axis.spec,
                        p.name,
                        crate::presets::split_rule(&p.knobs)
                    ));
                }
                None
            }
            (None, _, _) => spec.lambda.clone(),
        };
        let lambda = match (lambda_axis, preset, axes.lambda) {
            (Some(axis), _, _) => axis,
            (None, Some(p), None) => {
                let v = crate::presets::lambda_value(&p.knobs).unwrap_or(config.shadow.lambda);
                Axis {
                    values: vec![v],
                    spec: v.to_string(),
                }
            }
            (None, _, _) => Axis {
                values: decimal_range(0.0, 1.0, 0.05).expect("valid"),
                spec: "0:1:0.05".into(),
            },
        };
        let table_cascades = match (&spec.cascades, preset) {
            (Some(axis), Some(p)) => {
                let values: Vec<usize> = axis
                    .values
                    .iter()
                    .copied()
                    .filter(|n| axes.cascades.contains(n))
                    .collect();
                if values.len() < axis.values.len() {
                    notes.push(format!(
                        "sweep.cascades: {} left out: the {} preset takes {}",
                        fmt_list(
                            &axis
                                .values
                                .iter()
                                .filter(|n| !axes.cascades.contains(n))
                                .collect::<Vec<_>>()
                        ),
                        p.name,
                        fmt_list(&axes.cascades)
                    ));
                }
                (!values.is_empty()).then(|| Axis {
                    spec: fmt_list(&values),
                    values,
                })
            }
            (table, _) => table.clone(),
        };
        let cascades = overrides.cascades.clone().or(table_cascades).unwrap_or_else(|| {
            let mut values: Vec<usize> = (1..=8).filter(|n| axes.cascades.contains(n)).collect();
            if values.is_empty() {
                values = axes.cascades.clone();
            }
            Axis {
                spec: fmt_list(&values),
                values,
            }
        });
        let resolution = overrides
            .resolution
            .clone()
            .or(spec.resolution)
            .unwrap_or_else(|| Axis {
                values: vec![512, 1024, 2048, 4096],
                spec: "512,1024,2048,4096".into(),
            });
        let fit = match (overrides.fit.clone(), &spec.fit, preset) {
            (Some(axis), _, Some(p)) => {
                return Err(Error::flag(
                    "--fit",
                    &axis.spec,
                    format!(
                        "the {} preset fixes its fit ({}); drop --fit",
                        p.name, config.shadow.fit
                    ),
                ))
            }
            (Some(axis), _, None) => axis,
            (None, Some(axis), Some(p)) => {
                notes.push(format!(
                    "sweep.fit = {} left out: the {} preset fixes its fit",
                    axis.spec, p.name
                ));
                Axis {
                    values: vec![config.shadow.fit],
                    spec: config.shadow.fit.name().into(),
                }
            }
            (None, Some(axis), None) => axis.clone(),
            (None, None, _) => Axis {
                values: vec![config.shadow.fit],
                spec: config.shadow.fit.name().into(),
            },
        };
        let configured = SplitRange::of(config.shadow.fit_depth_to_visible);
        let split_range = match (overrides.split_range.clone(), &spec.split_range, preset) {
            (Some(axis), _, Some(p)) => {
                return Err(Error::flag(
                    "--split-range",
                    &axis.spec,
                    format!(
                        "the {} preset fixes its split range ({configured}); drop --split-range",
                        p.name
                    ),
                ))
            }
            (Some(axis), _, None) => {
                check_split_ranges(config, &axis.values, &axis.spec)?;
                axis
            }
            (None, Some(axis), Some(p)) => {
                notes.push(format!(
                    "sweep.split_range = {} left out: the {} preset fixes its split range",
                    axis.spec, p.name
                ));
                Axis {
                    values: vec![configured],
                    spec: configured.name().into(),
                }
            }
            (None, Some(axis), None) => axis.clone(),
            (None, None, _) => Axis {
                values: vec![configured],
                spec: configured.name().into(),
            },
        };
        let knob_source = source(overrides.knob.is_some(), "--knob", "sweep.knob");
        let knob = match (overrides.knob.clone().or(spec.knob.clone()), &axes.knob) {
            (Some(axis), None) => {
                let name = preset.map_or("csm-lab's own pipeline".to_string(), |p| {
                    format!("the {} preset", p.name)
                });
                return Err(Error::flag(
                    &knob_source,
                    &axis.spec,
                    format!(
                        "{name} has no split knob to sweep (only unreal and bevy have one; λ is --lambda); drop {knob_source}"
                    ),
                ));
            }
            (Some(axis), Some(_)) => Some(axis),
            (None, Some(k)) => Some(Axis {
                spec: fmt_list(&k.sweep),
                values: k.sweep.clone(),
            }),
            (None, None) => None,
        };
        let distance_source = source(overrides.distance.is_some(), "--distance", "sweep.distance");
        let distance = overrides.distance.clone().or(spec.distance.clone());
        if let (Some(axis), Some(p)) = (&distance, preset) {
            if !axes.distance {
                return Err(Error::flag(
                    &distance_source,
                    &axis.spec,
                    format!(
                        "the {} preset has no shadow distance (it shadows to camera.far); drop {distance_source}",
                        p.name
                    ),
                ));
            }
        }
        let light_source = source(overrides.light_update.is_some(), "--light-update", "sweep.light_update");
        let light_update = overrides.light_update.clone().or(spec.light_update.clone());
        if let Some(axis) = &light_update {
            if !config.motion.light.moves() {
                return Err(Error::flag(
                    &light_source,
                    &axis.spec,
                    "needs a moving light (motion.light_path = \"sun\" or \"file\"): a still light is \
                     never re-aimed; set motion.light_path or drop the light update axis"
                        .to_string(),
                ));
            }
        }
        let grid = Grid {
            lambda,
            cascades,
            resolution,
            fit,
            split_range,
            knob,
            distance,
            sun: SunGrid::resolve(config, overrides.sun_azimuth.clone(), overrides.sun_elevation.clone()),
            light_update,
            notes,
        };
        let n = grid.len();
        if n > max_configs {
            let (mut extra, mut more_flags) = (String::new(), String::new());
            if let Some(k) = &grid.knob {
                extra.push_str(&format!(" × {} knob values", k.values.len()));
                more_flags.push_str(", --knob");
            }
            if let Some(d) = &grid.distance {
                extra.push_str(&format!(" × {} distances", d.values.len()));
                more_flags.push_str(", --distance");
            }
            if let Some(sun) = &grid.sun {
                extra.push_str(&format!(" × {} sun angles", sun.len()));
                more_flags.push_str(", --sun-azimuth, --sun-elevation");
            }
            if let Some(u) = &grid.light_update {
                extra.push_str(&format!(" × {} light updates", u.values.len()));
                more_flags.push_str(", --light-update");
            }
            return Err(GridError::TooLarge {
                configs: n,
                lambdas: grid.lambda.values.len(),
                counts: grid.cascades.values.len(),
                resolutions: grid.resolution.values.len(),
                fits: grid.fit.values.len() * grid.split_range.values.len(),
                extra,
                more_flags,
                max: max_configs,
            }
            .into());
        }
        if preset.is_some() {
            // Each axis value must be one the engine accepts: say which axis and which value.
            let mut c = config.clone();
            let cascades_source = source(overrides.cascades.is_some(), "--cascades", "sweep.cascades");
            let resolution_source = source(overrides.resolution.is_some(), "--resolution", "sweep.resolution");
            for &v in &grid.cascades.values {
                crate::presets::set_cascades(&mut c, v)
                    .map_err(|e| axis_error(&cascades_source, &grid.cascades.spec, e))?;
            }
            for &v in &grid.resolution.values {
                crate::presets::set_resolution(&mut c, v)
                    .map_err(|e| axis_error(&resolution_source, &grid.resolution.spec, e))?;
            }
            if axes.lambda.is_some() {
                for &v in &grid.lambda.values {
                    crate::presets::set_lambda(&mut c, v)
                        .map_err(|e| axis_error(&lambda_source, &grid.lambda.spec, e))?;
                }
            }
            if let Some(k) = &grid.knob {
                for &v in &k.values {
                    crate::presets::set_knob(&mut c, v).map_err(|e| axis_error(&knob_source, &k.spec, e))?;
                }
            }
        }
        if let Some(d) = &grid.distance {
            let mut c = config.clone();
            for &v in &d.values {
                crate::presets::set_distance(&mut c, v).map_err(|e| axis_error(&distance_source, &d.spec, e))?;
            }
        }
        Ok(grid)
    }

    pub fn len(&self) -> usize {
        self.lambda.values.len()
            * self.cascades.values.len()
            * self.resolution.values.len()
            * self.fit.values.len()
            * self.split_range.values.len()
            * self.knob.as_ref().map_or(1, |a| a.values.len())
            * self.distance.as_ref().map_or(1, |a| a.values.len())
            * self.sun.as_ref().map_or(1, SunGrid::len)
            * self.light_update.as_ref().map_or(1, |a| a.values.len())
    }

    /// Settings per sun angle: the grid without its sun axes.
    pub fn settings_per_sun(&self) -> usize {
        self.len() / self.sun.as_ref().map_or(1, SunGrid::len).max(1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// All settings in row order: the sun's elevation and azimuth when swept (outermost), then
    /// split range, then fit, then distance, then resolution, then cascades, then the knob,
    /// then the light update, then λ (innermost).
    pub fn settings(&self) -> Vec<Setting> {
        let base = self.settings_without_sun();
        match &self.sun {
            None => base,
            Some(sun) => sun
                .suns()
                .into_iter()
                .flat_map(|sun| base.iter().map(move |s| Setting { sun: Some(sun), ..*s }))
                .collect(),
        }
    }

    /// [`Grid::settings`] under the configured light only (every setting once).
    pub fn settings_without_sun(&self) -> Vec<Setting> {
        let opt = |a: &Option<Axis<f64>>| {
            a.as_ref()
                .map_or(vec![None], |a| a.values.iter().map(|&v| Some(v)).collect())
        };
        let (knobs, distances) = (opt(&self.knob), opt(&self.distance));
        let updates: Vec<Option<LightUpdate>> = self
            .light_update
            .as_ref()
            .map_or(vec![None], |a| a.values.iter().map(|&v| Some(v)).collect());
        let mut out = Vec::with_capacity(self.len());
        for &split_range in &self.split_range.values {
            for &fit in &self.fit.values {
                for &distance in &distances {
                    for &resolution in &self.resolution.values {
                        for &cascades in &self.cascades.values {
                            for &knob in &knobs {
                                for &light_update in &updates {
                                    for &lambda in &self.lambda.values {
                                        out.push(Setting {
                                            lambda,
                                            cascades,
                                            resolution,
                                            fit,
                                            split_range,
                                            knob,
                                            distance,
                                            light_update,
                                            sun: None,
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// The CLI arguments that reproduce this grid for `config` (a preset sweep names only the
    /// axes its engine has).
    pub fn cli_args(&self, config: &Config) -> String {
        let axes = crate::presets::axes(config);
        let mut out = String::new();
        if axes.lambda.is_some() {
            out.push_str(&format!("--lambda {} ", self.lambda.spec));
        }
        out.push_str(&format!(
            "--cascades {} --resolution {}",
            self.cascades.spec, self.resolution.spec
        ));
        if axes.fit {
            out.push_str(&format!(" --fit {}", self.fit.spec));
        }
        if self.split_range.values.len() > 1 || self.split_range.values.contains(&SplitRange::Visible) {
            out.push_str(&format!(" --split-range {}", self.split_range.spec));
        }
        if let Some(k) = &self.knob {
            out.push_str(&format!(" --knob {}", k.spec));
        }
        if let Some(d) = &self.distance {
            out.push_str(&format!(" --distance {}", d.spec));
        }
        if let Some(sun) = &self.sun {
            out.push_str(&sun.cli_args());
        }
        if let Some(u) = &self.light_update {
            out.push_str(&format!(" --light-update {}", u.spec));
        }
        out
    }
}

/// One point of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setting {
    pub lambda: f64,
    pub cascades: usize,
    pub resolution: u32,
    pub fit: Fit,
    pub split_range: SplitRange,
    /// The preset's split knob (None: not swept).
    pub knob: Option<f64>,
    /// The shadow distance (None: not swept; the config's own).
    pub distance: Option<f64>,
    /// The sun position (None: not swept; the configured light).
    pub sun: Option<Sun>,
    /// The light update rule (None: not swept; the config's own).
    pub light_update: Option<LightUpdate>,
}

impl Setting {
    /// The base config with this setting applied. With a preset, λ goes to the engine's own
    /// λ-like knob (when it has one) and the count and map size are checked against the
    /// engine's; [`Grid::resolve`] has already checked every point, so this does not fail for
    /// a resolved grid.
    pub fn apply(&self, base: &Config) -> Result<Config> {
        let mut c = self.apply_shadow(base)?;
        if let Some(u) = self.light_update {
            c.motion.light.update = u;
        }
        match self.sun {
            None => Ok(c),
            Some(sun) => c.with_light_direction(sun.light_direction()),
        }
    }

    /// [`Setting::apply`] without the light update rule and the sun (neither changes a value
    /// the shadow checks look at).
    fn apply_shadow(&self, base: &Config) -> Result<Config> {
        if base.shadow.preset.is_none() {
            let c = base.with_sweep_point(self.lambda, self.cascades, self.resolution, self.fit, self.split_range)?;
            return match self.distance {
                None => Ok(c),
                Some(d) => {
                    let mut c = c;
                    crate::presets::set_distance(&mut c, d)?;
                    c.rechecked()
                }
            };
        }
        let mut c = base.clone();
        if crate::presets::axes(&c).lambda.is_some() {
            crate::presets::set_lambda(&mut c, self.lambda)?;
        }
        crate::presets::set_cascades(&mut c, self.cascades)?;
        crate::presets::set_resolution(&mut c, self.resolution)?;
        if let Some(k) = self.knob {
            crate::presets::set_knob(&mut c, k)?;
        }
        if let Some(d) = self.distance {
            crate::presets::set_distance(&mut c, d)?;
        }
        if self.knob.is_some() || self.distance.is_some() {
            crate::presets::check_point(&c)?;
        }
        // The engine checked its own knobs; the set-up as a whole is checked again here.
        c.rechecked()
    }

    pub fn label(&self) -> String {
        let range = match self.split_range {
            SplitRange::Bounds => "",
            SplitRange::Visible => ", splits on the visible depths",
        };
        let mut extra = String::new();
        if let Some(k) = self.knob {
            extra.push_str(&format!(", knob {k}"));
        }
        if let Some(d) = self.distance {
            extra.push_str(&format!(", distance {d}"));
        }
        if let Some(sun) = self.sun {
            extra.push_str(&format!(", sun {}", sun.label()));
        }
        if let Some(u) = self.light_update {
            extra.push_str(&format!(", light update {}", crate::config::light_update_label(u)));
        }
        format!(
            "{} x {}^2, lambda {}, {}{range}{extra}",
            self.cascades, self.resolution, self.lambda, self.fit
        )
    }
}

/// One row of `sweep.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub setting: Setting,
    pub summary: Summary,
}

/// Runs the full analysis of every setting in parallel. `threads` = None uses rayon's default
/// pool; `on_done` is called once per finished configuration (progress bars).
pub fn run(base: &Config, grid: &Grid, threads: Option<usize>, on_done: &(dyn Fn() + Sync)) -> Result<Vec<Row>> {
    run_settings(base, &grid.settings(), threads, on_done)
}

/// [`run`] over some settings of a grid (a shard's slice), in their order.
pub fn run_settings(
    base: &Config,
    settings: &[Setting],
    threads: Option<usize>,
    on_done: &(dyn Fn() + Sync),
) -> Result<Vec<Row>> {
    // Every point is built and checked before any analysis runs: a setting the config could
    // not hold (an f32 window that collapses at this fit, say) is refused like the file would be.
    // The configs are built again in the parallel part rather than kept: a 100,000-point grid
    // would otherwise hold 100,000 configs at once.
    let point = |s: &Setting| {
        s.apply(base).map_err(|e| {
            Error::from(GridError::Point {
                point: s.label(),
                source: Box::new(e),
            })
        })
    };
    for s in settings {
        // The visibility pass is made once, before the parallel part, and shared by every row.
        // Under swept sun angles only its rays are: each angle shades them in the parallel
        // part (the rows of one angle are consecutive and share that shading).
        let setup = point(s)?.setup();
        if s.sun.is_some() {
            let _ = setup.visibility_hits();
        } else {
            let _ = setup.visibility();
        }
    }
    let work = || {
        settings
            .par_iter()
            .map(|s| {
                let a = analyze(&point(s)?, &AnalysisOptions::summary_only());
                on_done();
                Ok(Row {
                    setting: *s,
                    summary: a.summary,
                })
            })
            .collect::<Result<Vec<_>>>()
    };
    in_pool(threads, work)
}

/// Runs `work` in a pool of `threads` threads (`--threads`), or in rayon's default pool. The
/// one place a command builds a pool; a failure names the flag.
pub fn in_pool<T: Send>(threads: Option<usize>, work: impl FnOnce() -> Result<T> + Send) -> Result<T> {
    match threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| {
                Error::flag(
                    "--threads",
                    &n.to_string(),
                    format!("cannot start the thread pool: {e}"),
                )
            })?
            .install(work),
        None => work(),
    }
}

// ---------------------------------------------------------------------------------------------
// Pareto front and recommendation
// ---------------------------------------------------------------------------------------------

/// Indices of the rows on the Pareto front of memory against mean aliasing (both minimised),
/// ordered by memory. Among exact ties the first row in grid order is kept. Rows whose scene
/// needs no cascades are left out.
pub fn pareto_front(rows: &[Row]) -> Vec<usize> {
    pareto_front_by(rows, SummaryMetric::named("mean_aliasing"))
}

/// [`pareto_front`] of memory against any objective metric.
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
    let mut idx: Vec<usize> = candidates.collect();
    idx.sort_by(|&a, &b| {
        let (ra, rb) = (&rows[a].summary, &rows[b].summary);
        ra.memory_bytes
            .cmp(&rb.memory_bytes)
            .then(objective.value(ra).total_cmp(&objective.value(rb)))
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
pub const OBJECTIVE: &str = "lowest mean aliasing (the average shadow-texel-to-pixel ratio over the depth range) \
among configurations that fit the memory budget, cover every slice (coverage_violations = 0) and are stable when \
snapped (shimmer_snapped <= 1e-3 texel); means within 1% of the lowest count as equal, and among those the lowest \
max aliasing wins, then less memory, then fewer cascades";

/// The objective of a sweep: `[sweep] objective` if written, else the contrast-weighted 95th
/// percentile of the per-pixel aliasing on screen (`visible_aliasing_p95`) when the scene has
/// geometry, else the mean aliasing over depth.
pub fn default_objective(config: &Config) -> SummaryMetric {
    // The name was checked against the registry when the file was loaded.
    if let Some(m) = config.sweep.as_ref().and_then(|s| s.objective.as_deref()) {
        return SummaryMetric::named(m);
    }
    SummaryMetric::named(if config.geometry.is_some() {
        "visible_aliasing_p95"
    } else {
        "mean_aliasing"
    })
}

/// [`OBJECTIVE`] for the mean aliasing; the same rule in words for any other objective.
pub fn objective_text(objective: SummaryMetric) -> String {
    if objective.name() == "mean_aliasing" {
        return OBJECTIVE.to_string();
    }
    format!(
        "lowest {} ({}) among configurations that fit the memory budget, cover every slice \
         (coverage_violations = 0) and are stable when snapped (shimmer_snapped <= 1e-3 texel); values within 1% of \
         the lowest count as equal, and among those the lowest max aliasing wins, then less memory, then fewer cascades",
        objective.name(),
        objective.description()
    )
}

/// Mean aliasing within this fraction of the best counts as equal: a 0.2% better mean is not
/// worth a 20% worse worst case, so near-ties are decided by max aliasing.
pub const MEAN_TOLERANCE: f64 = 0.01;

/// The recommended row and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Recommendation {
    pub index: usize,
    pub budget_bytes: u64,
    /// False when nothing fits the budget: the cheapest acceptable configuration is returned.
    pub within_budget: bool,
}

/// Whether a row may be recommended: its scene needs cascades, it covers every slice
/// (`coverage_violations` = 0) and it is stable when snapped (`shimmer_snapped` <=
/// [`STABLE_SHIMMER`]; under a moving light, the snapped crawl between updates:
/// [`Summary::snapped_drift`]).
pub fn acceptable(r: &Row) -> bool {
    r.summary.cascades_needed && r.summary.coverage_violations == 0 && r.summary.snapped_drift() <= STABLE_SHIMMER
}

/// Picks the recommendation by [`OBJECTIVE`]. None when no row needs cascades or none is
/// acceptable.
pub fn recommend(rows: &[Row], budget_mib: f64) -> Option<Recommendation> {
    recommend_by(rows, budget_mib, SummaryMetric::named("mean_aliasing"))
}

/// [`recommend`] minimising any objective metric.
pub fn recommend_by(rows: &[Row], budget_mib: f64, objective: SummaryMetric) -> Option<Recommendation> {
    let budget_bytes = (budget_mib * 1024.0 * 1024.0).floor() as u64;
    let ok: Vec<usize> = (0..rows.len()).filter(|&i| acceptable(&rows[i])).collect();
    let within: Vec<usize> = ok
        .iter()
        .copied()
        .filter(|&i| rows[i].summary.memory_bytes <= budget_bytes)
        .collect();
    if let Some(index) = pick(rows, &within, objective) {
        return Some(Recommendation {
            index,
            budget_bytes,
            within_budget: true,
        });
    }
    // Nothing fits the budget: the cheapest acceptable configurations, best among them.
    let cheapest = ok.iter().map(|&i| rows[i].summary.memory_bytes).min()?;
    let cheap: Vec<usize> = ok
        .into_iter()
        .filter(|&i| rows[i].summary.memory_bytes == cheapest)
        .collect();
    pick(rows, &cheap, objective).map(|index| Recommendation {
        index,
        budget_bytes,
        within_budget: false,
    })
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
    let budget_bytes = (budget_mib * 1024.0 * 1024.0).floor() as u64;
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
/// lowest mean aliasing, then the lowest max aliasing, less memory, fewer cascades, grid order.
fn pick(rows: &[Row], candidates: &[usize], objective: SummaryMetric) -> Option<usize> {
    let best = candidates
        .iter()
        .map(|&i| objective.value(&rows[i].summary))
        .min_by(f64::total_cmp)?;
    candidates
        .iter()
        .copied()
        .filter(|&i| objective.value(&rows[i].summary) <= best * (1.0 + MEAN_TOLERANCE))
        .min_by(|&a, &b| {
            let (x, y) = (&rows[a].summary, &rows[b].summary);
            x.max_aliasing
                .total_cmp(&y.max_aliasing)
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
pub enum AlternativeKind {
    /// Less memory, for a higher objective.
    Cheaper,
    /// A lower objective, for more memory.
    Sharper,
    /// Less shimmer in the configured snap mode.
    MoreStable,
}

impl AlternativeKind {
    /// The `kind` of `recommendation.json`'s `alternatives`.
    pub fn name(self) -> &'static str {
        match self {
            AlternativeKind::Cheaper => "cheaper",
            AlternativeKind::Sharper => "sharper",
            AlternativeKind::MoreStable => "more_stable",
        }
    }

    /// The rule that picks it, in words (reports and `recommendation.json`).
    pub fn rule(self) -> &'static str {
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
        }
    }
}

/// One alternative to the recommendation: the row and why it was picked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Alternative {
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
pub fn alternatives(rows: &[Row], rec: &Recommendation, objective: SummaryMetric) -> Vec<Alternative> {
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
        .filter(|&i| rows[i].summary.memory_bytes <= limit && rows[i].summary.shimmer < r.shimmer)
        .min_by(|&a, &b| {
            let (x, y) = (&rows[a].summary, &rows[b].summary);
            x.shimmer
                .total_cmp(&y.shimmer)
                .then(objective.value(x).total_cmp(&objective.value(y)))
                .then(x.memory_bytes.cmp(&y.memory_bytes))
                .then(a.cmp(&b))
        });
    for (kind, pick) in [
        (AlternativeKind::Cheaper, cheaper),
        (AlternativeKind::Sharper, sharper),
        (AlternativeKind::MoreStable, stabler),
    ] {
        if let Some(index) = pick.filter(|&i| i != rec.index && !out.iter().any(|a: &Alternative| a.index == i)) {
            out.push(Alternative { kind, index });
        }
    }
    out
}

/// Which rival a row is: the best row of a group the recommendation beat.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RivalKind {
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
    pub fn name(self) -> &'static str {
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
pub enum Loss {
    /// Slice corners outside their windows (the count).
    CoverageMisses(u64),
    /// Snapped shimmer above [`STABLE_SHIMMER`] (the value).
    Unstable(f64),
    /// Over the memory budget, which the recommendation fits.
    OverBudget,
    /// Nothing fits the budget and the rival needs more memory than the recommendation.
    MoreMemory,
    /// A higher objective, beyond the [`MEAN_TOLERANCE`] tie.
    Objective,
    /// Tied on the objective; a higher max aliasing.
    MaxAliasing,
    /// Tied on the objective and max aliasing; more memory.
    TieMemory,
    /// Tied on everything above; more cascades or later in grid order.
    TieOrder,
}

/// A rival and why it lost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rival {
    pub kind: RivalKind,
    pub index: usize,
    pub loss: Loss,
}

/// Why row `x` lost to the recommendation `rec`, by the rule of [`recommend_by`].
pub fn loss(rows: &[Row], rec: &Recommendation, x: usize, objective: SummaryMetric) -> Loss {
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
    if !rec.within_budget && s.memory_bytes > r.memory_bytes {
        return Loss::MoreMemory;
    }
    // The shortlist of the rule: within MEAN_TOLERANCE of the best objective among the rows
    // the recommendation was picked from.
    let pool = |i: usize| {
        acceptable(&rows[i])
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
    } else if s.max_aliasing > r.max_aliasing {
        Loss::MaxAliasing
    } else if s.memory_bytes > r.memory_bytes {
        Loss::TieMemory
    } else {
        Loss::TieOrder
    }
}

/// A fit and the depths its splits divide: what figures draw a panel or series for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct FitGroup {
    pub split_range: SplitRange,
    pub fit: Fit,
}

impl std::fmt::Display for FitGroup {
    /// "sphere", or "sphere, visible splits" when the splits divide the visible depths.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.split_range {
            SplitRange::Bounds => write!(f, "{}", self.fit),
            SplitRange::Visible => write!(f, "{}, visible splits", self.fit),
        }
    }
}

impl Setting {
    pub fn fit_group(&self) -> FitGroup {
        FitGroup {
            split_range: self.split_range,
            fit: self.fit,
        }
    }
}

/// Distinct fit groups of the rows, in order (for plots).
pub fn fits_in(rows: &[Row]) -> Vec<FitGroup> {
    rows.iter()
        .map(|r| r.setting.fit_group())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect()
}

/// An axis value the engine preset refuses, naming the axis's flag or key and its spec.
fn axis_error(source_key: &str, spec: &str, e: Error) -> Error {
    GridError::Axis {
        source_key: source_key.to_string(),
        spec: spec.to_string(),
        message: e.to_string(),
    }
    .into()
}

/// Everything a sweep produced, ready to be written.
#[derive(Debug, Clone)]
pub struct SweepResult {
    pub config: Config,
    pub grid: Grid,
    /// One row per setting. In a sun sweep, each setting's judged row (its worst sun angle,
    /// [`crate::commands::sun_sweep::judge`]); every (sun, setting) row is in [`Self::sun`].
    pub rows: Vec<Row>,
    /// Every row of a sun sweep and each setting's worst sun; None without sun axes.
    pub sun: Option<SunRows>,
    pub front: Vec<usize>,
    pub recommendation: Option<Recommendation>,
    pub budget_mib: f64,
    /// The command that reproduces the sweep.
    pub command: String,
    /// The metric the recommendation minimises ([`default_objective`]).
    pub objective: SummaryMetric,
    /// The free split fractions of `--optimize-splits`, when asked for.
    pub optimized: Option<super::optimize::Optimized>,
    /// S3, S4 and the measured flicker S5 of a sample of the rows (`--ground-truth`).
    pub flicker: Option<super::flicker_sample::FlickerSample>,
}

impl SweepResult {
    /// The result of a sweep's rows, in grid order ([`Grid::settings`]; with sun axes every
    /// (sun, setting) row, judged here per setting by its worst sun angle).
    pub fn new(config: Config, grid: Grid, rows: Vec<Row>, command: String) -> Self {
        let budget_mib = config
            .sweep
            .as_ref()
            .and_then(|s| s.memory_budget_mib)
            .unwrap_or(DEFAULT_BUDGET_MIB);
        let objective = default_objective(&config);
        let (rows, sun) = match &grid.sun {
            None => (rows, None),
            Some(_) => {
                let (judged, sun) = crate::commands::sun_sweep::judge(rows, objective);
                (judged, Some(sun))
            }
        };
        let front = pareto_front_by(&rows, objective);
        let recommendation = recommend_by(&rows, budget_mib, objective);
        SweepResult {
            objective,
            config,
            grid,
            rows,
            sun,
            front,
            recommendation,
            budget_mib,
            command,
            optimized: None,
            flicker: None,
        }
    }

    pub fn recommended(&self) -> Option<&Row> {
        self.recommendation.as_ref().map(|r| &self.rows[r.index])
    }

    /// The row of the configured setting (the config's own λ, cascade count, resolution and
    /// fit, and the preset's knob and shadow distance when swept), when the grid has it.
    pub fn configured(&self) -> Option<usize> {
        let c = &self.config.shadow;
        let knob = crate::presets::axes(&self.config).knob.map(|k| k.value);
        self.rows.iter().position(|x| {
            x.setting.knob.is_none_or(|k| Some(k) == knob)
                && x.setting.distance.is_none_or(|d| d == c.max_distance)
                && x.setting.lambda == c.lambda
                && x.setting.cascades == c.cascades
                && x.setting.resolution == c.resolution
                && x.setting.fit == c.fit
                && x.setting.split_range.is_visible() == c.fit_depth_to_visible
        })
    }

    /// The alternatives to the recommendation ([`alternatives`]); empty without one.
    pub fn alternatives(&self) -> Vec<Alternative> {
        self.recommendation
            .as_ref()
            .map_or_else(Vec::new, |r| alternatives(&self.rows, r, self.objective))
    }

    /// The main rivals of the recommendation and why each lost: the recommendation's setting with
    /// λ = 1 (when λ is swept), the best row (in [`Self::ranked`] order) with another cascade
    /// count, with another resolution,
    /// with the other fit, and the configured setting; each row once (the first group names
    /// it), never the recommendation. Empty without a recommendation.
    pub fn rivals(&self) -> Vec<Rival> {
        let Some(rec) = &self.recommendation else {
            return Vec::new();
        };
        let r = self.rows[rec.index].setting;
        let ranked = self.ranked();
        let best = |f: &dyn Fn(&Setting) -> bool| ranked.iter().copied().find(|&i| f(&self.rows[i].setting));
        let lambda_swept = self.grid.lambda.values.len() > 1;
        let groups: [(RivalKind, Option<usize>); 5] = [
            (
                RivalKind::LambdaOne,
                if lambda_swept && r.lambda != 1.0 && r.cascades > 1 {
                    best(&|s| {
                        s.lambda == 1.0 && s.cascades == r.cascades && s.resolution == r.resolution && s.fit == r.fit
                    })
                } else {
                    None
                },
            ),
            (RivalKind::OtherCascades, best(&|s| s.cascades != r.cascades)),
            (RivalKind::OtherResolution, best(&|s| s.resolution != r.resolution)),
            (RivalKind::OtherFit, best(&|s| s.fit != r.fit)),
            (
                RivalKind::Configured,
                self.configured().filter(|&i| self.rows[i].summary.cascades_needed),
            ),
        ];
        let mut out: Vec<Rival> = Vec::new();
        for (kind, index) in groups {
            if let Some(index) = index.filter(|&i| i != rec.index && !out.iter().any(|x| x.index == i)) {
                out.push(Rival {
                    kind,
                    index,
                    loss: loss(&self.rows, rec, index, self.objective),
                });
            }
        }
        out
    }

    /// Rows in objective order (acceptable within budget first), for the "top" tables.
    pub fn ranked(&self) -> Vec<usize> {
        let budget = self
            .recommendation
            .as_ref()
            .map_or((self.budget_mib * 1048576.0) as u64, |r| r.budget_bytes);
        let mut idx: Vec<usize> = (0..self.rows.len())
            .filter(|&i| self.rows[i].summary.cascades_needed)
            .collect();
        let key = |i: usize| {
            let s = &self.rows[i].summary;
            let ok = s.coverage_violations == 0 && s.snapped_drift() <= STABLE_SHIMMER && s.memory_bytes <= budget;
            (!ok, self.objective.value(s), s.max_aliasing, s.memory_bytes, i)
        };
        idx.sort_by(|&a, &b| {
            let (ka, kb) = (key(a), key(b));
            ka.0.cmp(&kb.0)
                .then(ka.1.total_cmp(&kb.1))
                .then(ka.2.total_cmp(&kb.2))
                .then(ka.3.cmp(&kb.3))
                .then(ka.4.cmp(&kb.4))
        });
        // The recommendation heads the table (near-ties in mean are decided by max aliasing).
        if let Some(r) = &self.recommendation {
            idx.retain(|&i| i != r.index);
            idx.insert(0, r.index);
        }
        idx
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_decimal_exact() {
        let v = decimal_range(0.0, 1.0, 0.05).unwrap();
        assert_eq!(v.len(), 21);
        assert_eq!(v[20], 1.0);
        assert_eq!(v[3], 0.15);
        assert_eq!(v[7], 0.35);
        for (i, x) in v.iter().enumerate() {
            // Each value is the double nearest the decimal i/20, as if typed.
            assert_eq!(*x, format!("{}", i as f64 / 20.0).parse::<f64>().unwrap());
        }
        // Naive accumulation would drift (0.1 + 0.2 != 0.3); decimal steps do not.
        let w = decimal_range(0.1, 0.7, 0.1).unwrap();
        assert_eq!(w, vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]);
        // An end off the grid is not included.
        assert_eq!(decimal_range(0.0, 1.0, 0.3).unwrap(), vec![0.0, 0.3, 0.6, 0.9]);
        assert_eq!(decimal_range(2.0, 2.0, 1.0).unwrap(), vec![2.0]);
        assert!(decimal_range(0.0, 1.0, 0.0).is_err());
        assert!(decimal_range(0.0, 1.0, -0.1).is_err());
        assert!(decimal_range(1.0, 0.0, 0.1).is_err());
        assert!(decimal_range(0.0, f64::NAN, 0.1).is_err());
    }

    #[test]
    fn cli_specs_parse_and_bad_specs_name_the_flag() {
        assert_eq!(parse_lambda_spec("0:1:0.05").unwrap().values.len(), 21);
        assert_eq!(parse_lambda_spec("0,0.5,1").unwrap().values, vec![0.0, 0.5, 1.0]);
        assert_eq!(parse_lambda_spec("0.75").unwrap().values, vec![0.75]);
        assert_eq!(parse_cascades_spec("1..8").unwrap().values, (1..=8).collect::<Vec<_>>());
        assert_eq!(parse_cascades_spec("1..=3").unwrap().values, vec![1, 2, 3]);
        assert_eq!(parse_cascades_spec("2,4").unwrap().values, vec![2, 4]);
        assert_eq!(parse_resolution_spec("1024,2048").unwrap().values, vec![1024, 2048]);
        assert_eq!(
            parse_fit_spec("sphere,aabb").unwrap().values,
            vec![Fit::Sphere, Fit::Aabb]
        );
        for (r, flag) in [
            (parse_lambda_spec("0:1").map(|_| ()), "--lambda"),
            (parse_lambda_spec("0:1:0").map(|_| ()), "--lambda"),
            (parse_lambda_spec("1:0:0.1").map(|_| ()), "--lambda"),
            (parse_lambda_spec("0,x").map(|_| ()), "--lambda"),
            (parse_lambda_spec("0,1.5").map(|_| ()), "--lambda"),
            (parse_lambda_spec("").map(|_| ()), "--lambda"),
            (parse_cascades_spec("8..1").map(|_| ()), "--cascades"),
            (parse_cascades_spec("0,4").map(|_| ()), "--cascades"),
            (parse_cascades_spec("1..17").map(|_| ()), "--cascades"),
            (parse_cascades_spec("2,2").map(|_| ()), "--cascades"),
            (parse_resolution_spec("1024,abc").map(|_| ()), "--resolution"),
            (parse_resolution_spec("8").map(|_| ()), "--resolution"),
            (parse_fit_spec("box").map(|_| ()), "--fit"),
            (parse_split_range_spec("depth").map(|_| ()), "--split-range"),
            (parse_split_range_spec("bounds,bounds").map(|_| ()), "--split-range"),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(e.starts_with(flag), "{e}");
        }
    }

    fn row(memory: u64, mean: f64, cascades_needed: bool) -> Row {
        Row {
            setting: Setting {
                lambda: 0.5,
                cascades: 1,
                resolution: 512,
                fit: Fit::Sphere,
                split_range: SplitRange::Bounds,
                knob: None,
                distance: None,
                sun: None,
                light_update: None,
            },
            summary: Summary {
                cascades_needed,
                z_lo: 1.0,
                z_hi: 2.0,
                max_aliasing: mean * 2.0,
                mean_aliasing: mean,
                mean_log_aliasing: mean,
                undersampled_fraction: 0.0,
                shimmer: 0.0,
                shimmer_snapped: 0.0,
                shimmer_unsnapped: 0.3,
                size_jitter: 0.0,
                coverage_violations: 0,
                memory_bytes: memory,
                lookup_error_max: 0.0,
                lookup_error_rms: 0.0,
                overlap_area_fraction: 0.0,
                band_pixel_share: 0.0,
                seam_crossings: None,
                screen: None,
                light: None,
                truth: None,
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
            let front = pareto_front(&rows);
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
            let Some(rec) = recommend_by(&rows, budget, objective) else {
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
                match loss(&rows, &rec, x, objective) {
                    Loss::CoverageMisses(n) => assert_eq!(n, s.coverage_violations),
                    Loss::Unstable(v) => assert!(v > STABLE_SHIMMER && s.coverage_violations == 0),
                    Loss::OverBudget => assert!(rec.within_budget && s.memory_bytes > rec.budget_bytes),
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
        let rows = vec![
            row(80 * mib, 1.0, true),
            row(32 * mib, 2.0, true),
            row(64 * mib, 1.5, true),
        ];
        let r = recommend(&rows, 64.0).unwrap();
        assert_eq!((r.index, r.within_budget), (2, true));
        let r = recommend(&rows, 16.0).unwrap();
        assert_eq!((r.index, r.within_budget), (1, false));
        let mut unstable = rows.clone();
        unstable[2].summary.shimmer_snapped = 0.2;
        assert_eq!(recommend(&unstable, 64.0).unwrap().index, 1);
        assert!(recommend(&[row(mib, 1.0, false)], 64.0).is_none());
        // Means within 1% are a tie decided by the worst case; beyond 1% the mean decides.
        let mut near = vec![row(mib, 1.0, true), row(mib, 1.009, true), row(mib, 1.02, true)];
        near[0].summary.max_aliasing = 10.0;
        near[1].summary.max_aliasing = 5.0;
        near[2].summary.max_aliasing = 1.0;
        assert_eq!(recommend(&near, 64.0).unwrap().index, 1);
    }
}
