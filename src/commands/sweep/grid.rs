//! The grid of a sweep: its axes (λ, cascade count, map size, fit, split range, the preset's
//! knob, shadow distance, sun angles, light update rule), parsed from the command line and
//! merged with the config's `[sweep]` table ([`Grid::resolve`]), and its points ([`Setting`]).
//!
//! Ranges are decimal-exact: `0 to 1 step 0.05` is computed in scaled integers and gives
//! exactly 21 values, the last one exactly 1.0.

use glam::DVec3;

use crate::config::sweep_spec::{
    cascades_ok, check_values, decimal_range, fmt_list, lambda_ok, resolution_ok, sun_azimuth_ok, sun_elevation_ok,
    Axis, SweepAxes, DEFAULT_MAX_CONFIGS,
};
use crate::config::{Config, Fit, SplitRange, SweptCadence};
use crate::error::{Error, GridError, Result};
use csm_core::light_motion::LightUpdate;
use csm_core::sun::SunAngles;

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
    /// Cached cascades (`shadow.update_every`), when swept.
    pub update_every: Option<Axis<SweptCadence>>,
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
pub(crate) fn parse_number_spec(flag: &str, spec: &str, allowed: &str, ok: impl Fn(f64) -> bool) -> Result<Axis<f64>> {
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

/// `--update-every VALUES`: cached cascades (`shadow.update_every`), `2,4` (every cascade) or
/// `1/1/2/4` (one cadence per cascade, nearest first), or both.
pub fn parse_update_every_spec(spec: &str) -> Result<Axis<SweptCadence>> {
    crate::config::parse_update_every_list(spec)
        .map(|values| Axis {
            values,
            spec: spec.to_string(),
        })
        .map_err(|why| Error::flag("--update-every", spec, why))
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

/// The grid's axes as flags: each axis once, with its `--flag` help and its spec parser. The
/// macro below makes of this one list the command line's flags ([`GridFlags`], a clap group
/// flattened into `sweep`), the keys a shard's manifest records them under, and the parsed
/// [`SweepAxes`] a flag overrides its `[sweep]` key with. A new axis adds one line here, its
/// field in [`SweepAxes`] and its `[sweep]` key (`config/sweep_spec.rs`), and its place in
/// [`Grid`] and [`Setting`] (docs/architecture.md, "Add a sweep axis").
macro_rules! grid_flags {
    ($( $(#[doc = $doc:literal])* $name:ident => $parse:path ),* $(,)?) => {
        /// The grid flags of a sweep as given on the command line, unparsed: what `sweep`
        /// reads and what a shard's manifest records for `merge` to replay.
        #[derive(Debug, Clone, Default, PartialEq, clap::Args)]
        pub struct GridFlags {
            /// Sweep an engine preset's own axes (overrides shadow.preset); see `analyze --preset`.
            #[arg(long)]
            pub preset: Option<String>,
            $(
                $(#[doc = $doc])*
                #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
                pub $name: Option<String>,
            )*
        }

        impl GridFlags {
            /// The flags' names without dashes, in the order of [`GridFlags::values`].
            pub(crate) const KEYS: &'static [&'static str] = &["preset", $(stringify!($name)),*];

            pub(crate) fn values(&self) -> Vec<&Option<String>> {
                vec![&self.preset, $(&self.$name),*]
            }

            /// The flags from `get(key)` for each of [`GridFlags::KEYS`].
            pub(crate) fn from_keys(get: impl Fn(&str) -> Option<String>) -> Self {
                GridFlags {
                    preset: get("preset"),
                    $($name: get(stringify!($name)),)*
                }
            }

            /// The axis flags parsed; an error names its flag.
            pub fn overrides(&self) -> Result<SweepAxes> {
                Ok(SweepAxes {
                    $($name: self.$name.as_deref().map($parse).transpose()?,)*
                })
            }
        }
    };
}

grid_flags! {
    /// λ axis: start:end:step (0:1:0.05) or a list (0,0.5,1).
    lambda => parse_lambda_spec,
    /// Cascade counts: a range (1..8) or a list (2,4).
    cascades => parse_cascades_spec,
    /// Resolutions: a list (1024,2048).
    resolution => parse_resolution_spec,
    /// Fits: sphere, aabb or sphere,aabb.
    fit => parse_fit_spec,
    /// Split ranges: bounds, visible or bounds,visible (side by side; scene geometry only).
    split_range => parse_split_range_spec,
    /// The preset's own split knob (unreal: CascadeDistributionExponent; bevy:
    /// first_cascade_far_bound): a range (1:5:0.5) or a list (2,3,4) [default: around its value].
    knob => parse_knob_spec,
    /// Shadow distances (shadow.max_distance), world units: a range (50:200:50) or a list (50,100,150).
    distance => parse_distance_spec,
    /// Sun compass bearings, degrees from north toward east, in [0, 360): a range (0:345:15) or a
    /// list (90,180). Every setting runs under every sun angle and is judged by its worst.
    sun_azimuth => parse_sun_azimuth_spec,
    /// Sun elevations, degrees above the horizon, in (0, 90]: a range (5:85:5) or a list (20,60).
    /// The axis not given stays at the configured light's angle.
    sun_elevation => parse_sun_elevation_spec,
    /// Light update rules of a moving light (shadow.light_update): every:1,2,4,8 and/or
    /// quantize:0.1,0.25,0.5 (degrees).
    light_update => parse_light_update_spec,
    /// Cached cascades (shadow.update_every): frames between two renders, one value for every
    /// cascade (1,2,4) or one per cascade nearest first (1/1/2/4), or both (1,1/1/2/4).
    update_every => parse_update_every_spec,
}

/// `--split-range` = `spec` (`ranges` parsed) is refused when it asks for visible splits
/// without scene geometry.
pub(crate) fn check_split_ranges(config: &Config, ranges: &[SplitRange], spec: &str) -> Result<()> {
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

impl Grid {
    /// The grid for a config: CLI overrides, then the `[sweep]` table, then the defaults
    /// (λ 0:1:0.05, cascades 1..8, resolution 512,1024,2048,4096, the config's own fit).
    ///
    /// With an engine preset the grid sweeps the axes that engine has: λ only where its split
    /// rule has one (otherwise the single value it uses), its allowed cascade counts, its map
    /// sizes; the fit is the preset's. Every point is checked here, before any work starts.
    pub fn resolve(config: &Config, overrides: &SweepAxes) -> Result<Grid> {
        let none = SweepAxes::default();
        let max_configs = config.sweep.as_ref().map_or(DEFAULT_MAX_CONFIGS, |s| s.max_configs);
        let mut r = Resolve {
            config,
            flags: overrides,
            table: config.sweep.as_ref().map_or(&none, |s| &s.axes),
            axes: crate::presets::axes(config),
            notes: Vec::new(),
        };
        // The steps run in field order: the first axis at fault is the one an error names.
        let grid = Grid {
            lambda: r.lambda()?,
            cascades: r.cascades(),
            resolution: r.resolution(),
            fit: r.fit()?,
            split_range: r.split_range()?,
            knob: r.knob()?,
            distance: r.distance()?,
            sun: SunGrid::resolve(config, overrides.sun_azimuth.clone(), overrides.sun_elevation.clone()),
            light_update: r.light_update()?,
            update_every: r.update_every(),
            notes: r.notes,
        };
        grid.check_size(max_configs)?;
        grid.check_engine_values(config, overrides)?;
        Ok(grid)
    }

    /// A grid of more than `max_configs` points is refused, naming each axis's share.
    fn check_size(&self, max_configs: usize) -> Result<()> {
        let n = self.len();
        if n <= max_configs {
            return Ok(());
        }
        let (mut extra, mut more_flags) = (String::new(), String::new());
        if let Some(k) = &self.knob {
            extra.push_str(&format!(" × {} knob values", k.values.len()));
            more_flags.push_str(", --knob");
        }
        if let Some(d) = &self.distance {
            extra.push_str(&format!(" × {} distances", d.values.len()));
            more_flags.push_str(", --distance");
        }
        if let Some(sun) = &self.sun {
            extra.push_str(&format!(" × {} sun angles", sun.len()));
            more_flags.push_str(", --sun-azimuth, --sun-elevation");
        }
        if let Some(u) = &self.light_update {
            extra.push_str(&format!(" × {} light updates", u.values.len()));
            more_flags.push_str(", --light-update");
        }
        if let Some(u) = &self.update_every {
            extra.push_str(&format!(" × {} update cadences", u.values.len()));
            more_flags.push_str(", --update-every");
        }
        Err(GridError::TooLarge {
            configs: n,
            lambdas: self.lambda.values.len(),
            counts: self.cascades.values.len(),
            resolutions: self.resolution.values.len(),
            fits: self.fit.values.len() * self.split_range.values.len(),
            extra,
            more_flags,
            max: max_configs,
        }
        .into())
    }

    /// Each axis value must be one the engine preset accepts (and each distance one the config
    /// takes): an error names the axis's flag or key and the value.
    fn check_engine_values(&self, config: &Config, flags: &SweepAxes) -> Result<()> {
        fn each<T: Copy>(
            c: &mut Config,
            axis: &Axis<T>,
            source: &str,
            set: impl Fn(&mut Config, T) -> Result<()>,
        ) -> Result<()> {
            for &v in &axis.values {
                set(c, v).map_err(|e| axis_error(source, &axis.spec, e))?;
            }
            Ok(())
        }
        if config.shadow.preset.is_some() {
            let mut c = config.clone();
            each(
                &mut c,
                &self.cascades,
                &source(flags.cascades.is_some(), "cascades"),
                crate::presets::set_cascades,
            )?;
            each(
                &mut c,
                &self.resolution,
                &source(flags.resolution.is_some(), "resolution"),
                crate::presets::set_resolution,
            )?;
            if crate::presets::axes(config).lambda.is_some() {
                each(
                    &mut c,
                    &self.lambda,
                    &source(flags.lambda.is_some(), "lambda"),
                    crate::presets::set_lambda,
                )?;
            }
            if let Some(k) = &self.knob {
                each(
                    &mut c,
                    k,
                    &source(flags.knob.is_some(), "knob"),
                    crate::presets::set_knob,
                )?;
            }
        }
        if let Some(d) = &self.distance {
            each(
                &mut config.clone(),
                d,
                &source(flags.distance.is_some(), "distance"),
                crate::presets::set_distance,
            )?;
        }
        Ok(())
    }
}

/// Where an axis came from, as errors name it: its flag (`--light-update`) when given on the
/// command line, else its `[sweep]` key (`sweep.light_update`).
fn source(flag_given: bool, key: &str) -> String {
    if flag_given {
        format!("--{}", key.replace('_', "-"))
    } else {
        format!("sweep.{key}")
    }
}

/// One [`Grid::resolve`] in progress: the config, the axes given as flags and in the `[sweep]`
/// table, what the config's pipeline (csm-lab's own or an engine preset) can sweep, and the notes
/// about table axes left out. Axes from the table were written for csm-lab's own pipeline:
/// with a preset, what that engine lacks is dropped with a note. Axes given as flags must apply.
struct Resolve<'a> {
    config: &'a Config,
    flags: &'a SweepAxes,
    table: &'a SweepAxes,
    axes: crate::presets::Axes,
    notes: Vec<String>,
}

impl Resolve<'_> {
    /// "the unreal preset", or None for csm-lab's own pipeline.
    fn preset_name(&self) -> Option<String> {
        self.config.shadow.preset.as_ref().map(|p| p.name.to_string())
    }

    /// The axis a value fixed by the config stands for: one value, its spec being its name.
    fn fixed<T: Copy>(value: T, name: &str) -> Axis<T> {
        Axis {
            values: vec![value],
            spec: name.into(),
        }
    }

    /// λ: the flag, else the table's (left out with a note for a preset without λ), else the
    /// preset's own single value, else 0:1:0.05.
    fn lambda(&mut self) -> Result<Axis<f64>> {
        let preset = self.config.shadow.preset.as_ref();
        let given = match (self.flags.lambda.clone(), preset, self.axes.lambda) {
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
                if let Some(axis) = &self.table.lambda {
                    self.notes.push(format!(
                        "sweep.lambda = {} left out: the {} preset has no λ ({})",
                        axis.spec,
                        p.name,
                        crate::presets::split_rule(&p.knobs)
                    ));
                }
                None
            }
            (None, _, _) => self.table.lambda.clone(),
        };
        Ok(match (given, preset, self.axes.lambda) {
            (Some(axis), _, _) => axis,
            (None, Some(p), None) => {
                let v = crate::presets::lambda_value(&p.knobs).unwrap_or(self.config.shadow.lambda);
                Self::fixed(v, &v.to_string())
            }
            (None, _, _) => Axis {
                values: decimal_range(0.0, 1.0, 0.05).expect("valid"),
                spec: "0:1:0.05".into(),
            },
        })
    }

    /// Cascade counts: the flag, else the table's (the counts a preset does not take left out
    /// with a note), else 1..8 as far as the pipeline takes them.
    fn cascades(&mut self) -> Axis<usize> {
        let allowed = &self.axes.cascades;
        let table = match (&self.table.cascades, self.preset_name()) {
            (Some(axis), Some(name)) => {
                let (kept, dropped): (Vec<usize>, Vec<usize>) = axis.values.iter().partition(|n| allowed.contains(n));
                if !dropped.is_empty() {
                    self.notes.push(format!(
                        "sweep.cascades: {} left out: the {name} preset takes {}",
                        fmt_list(&dropped),
                        fmt_list(allowed)
                    ));
                }
                (!kept.is_empty()).then(|| Axis {
                    spec: fmt_list(&kept),
                    values: kept,
                })
            }
            (table, _) => table.clone(),
        };
        self.flags.cascades.clone().or(table).unwrap_or_else(|| {
            let mut values: Vec<usize> = (1..=8).filter(|n| allowed.contains(n)).collect();
            if values.is_empty() {
                values = allowed.clone();
            }
            Axis {
                spec: fmt_list(&values),
                values,
            }
        })
    }

    /// Map sizes: the flag, else the table's, else 512,1024,2048,4096.
    fn resolution(&self) -> Axis<u32> {
        self.flags
            .resolution
            .clone()
            .or(self.table.resolution.clone())
            .unwrap_or_else(|| Axis {
                values: vec![512, 1024, 2048, 4096],
                spec: "512,1024,2048,4096".into(),
            })
    }

    /// An axis a preset fixes (the fit, the split range): with a preset the flag is refused
    /// and the table's axis left out with a note; otherwise the flag, else the table's. Without
    /// either, the config's own value `configured`. `what` names the axis in messages ("split
    /// range"), `key` is its table key (`split_range`).
    fn fixed_by_preset<T: Copy + std::fmt::Display>(
        &mut self,
        flag: Option<&Axis<T>>,
        table: Option<&Axis<T>>,
        (what, key): (&str, &str),
        configured: T,
    ) -> Result<Axis<T>> {
        let own = || Self::fixed(configured, &configured.to_string());
        let Some(name) = self.preset_name() else {
            return Ok(flag.or(table).cloned().unwrap_or_else(own));
        };
        if let Some(axis) = flag {
            let flag = source(true, key);
            return Err(Error::flag(
                &flag,
                &axis.spec,
                format!("the {name} preset fixes its {what} ({configured}); drop {flag}"),
            ));
        }
        if let Some(axis) = table {
            self.notes.push(format!(
                "sweep.{key} = {} left out: the {name} preset fixes its {what}",
                axis.spec
            ));
        }
        Ok(own())
    }

    /// Fits: the flag, else the table's, else the config's own (a preset fixes its fit).
    fn fit(&mut self) -> Result<Axis<Fit>> {
        let flags = self.flags;
        let table = self.table;
        self.fixed_by_preset(
            flags.fit.as_ref(),
            table.fit.as_ref(),
            ("fit", "fit"),
            self.config.shadow.fit,
        )
    }

    /// Split ranges: as [`Resolve::fit`]; visible splits given as a flag need scene geometry.
    fn split_range(&mut self) -> Result<Axis<SplitRange>> {
        let (flags, table) = (self.flags, self.table);
        let configured = SplitRange::of(self.config.shadow.fit_depth_to_visible);
        let axis = self.fixed_by_preset(
            flags.split_range.as_ref(),
            table.split_range.as_ref(),
            ("split range", "split_range"),
            configured,
        )?;
        if let Some(flag) = &flags.split_range {
            check_split_ranges(self.config, &flag.values, &flag.spec)?;
        }
        Ok(axis)
    }

    /// The preset's split knob: the flag, else the table's, else the engine's own sweep of it;
    /// refused for a pipeline without one.
    fn knob(&self) -> Result<Option<Axis<f64>>> {
        let knob_source = source(self.flags.knob.is_some(), "knob");
        match (self.flags.knob.clone().or(self.table.knob.clone()), &self.axes.knob) {
            (Some(axis), None) => {
                let name = self
                    .preset_name()
                    .map_or("csm-lab's own pipeline".to_string(), |p| format!("the {p} preset"));
                Err(Error::flag(
                    &knob_source,
                    &axis.spec,
                    format!(
                        "{name} has no split knob to sweep (only unreal and bevy have one; λ is --lambda); drop {knob_source}"
                    ),
                ))
            }
            (Some(axis), Some(_)) => Ok(Some(axis)),
            (None, Some(k)) => Ok(Some(Axis {
                spec: fmt_list(&k.sweep),
                values: k.sweep.clone(),
            })),
            (None, None) => Ok(None),
        }
    }

    /// Shadow distances: the flag, else the table's; refused for a preset without one.
    fn distance(&self) -> Result<Option<Axis<f64>>> {
        let distance = self.flags.distance.clone().or(self.table.distance.clone());
        if let (Some(axis), Some(name), false) = (&distance, self.preset_name(), self.axes.distance) {
            let from = source(self.flags.distance.is_some(), "distance");
            return Err(Error::flag(
                &from,
                &axis.spec,
                format!("the {name} preset has no shadow distance (it shadows to camera.far); drop {from}"),
            ));
        }
        Ok(distance)
    }

    /// Light update rules: the flag, else the table's; refused for a still light.
    fn light_update(&self) -> Result<Option<Axis<LightUpdate>>> {
        let light_update = self.flags.light_update.clone().or(self.table.light_update.clone());
        if let Some(axis) = &light_update {
            if !self.config.motion.light.moves() {
                return Err(Error::flag(
                    &source(self.flags.light_update.is_some(), "light_update"),
                    &axis.spec,
                    "needs a moving light (motion.light_path = \"sun\" or \"file\"): a still light is \
                     never re-aimed; set motion.light_path or drop the light update axis"
                        .to_string(),
                ));
            }
        }
        Ok(light_update)
    }

    /// Cached-cascade cadences: the flag, else the table's. A value the pipeline cannot cache
    /// with (binary32, a moving light, a basis that follows the camera, a per-cascade list of
    /// another count) is refused when its points are built, naming `shadow.update_every`.
    fn update_every(&self) -> Option<Axis<SweptCadence>> {
        self.flags.update_every.clone().or(self.table.update_every.clone())
    }
}

impl Grid {
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
            * self.update_every.as_ref().map_or(1, |a| a.values.len())
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
    /// then the light update, then the update cadence, then λ (innermost).
    pub(crate) fn settings(&self) -> Vec<Setting> {
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
    pub(crate) fn settings_without_sun(&self) -> Vec<Setting> {
        let opt = |a: &Option<Axis<f64>>| {
            a.as_ref()
                .map_or(vec![None], |a| a.values.iter().map(|&v| Some(v)).collect())
        };
        let (knobs, distances) = (opt(&self.knob), opt(&self.distance));
        let updates: Vec<Option<LightUpdate>> = self
            .light_update
            .as_ref()
            .map_or(vec![None], |a| a.values.iter().map(|&v| Some(v)).collect());
        let cadences: Vec<Option<SweptCadence>> = self
            .update_every
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
                                    for &update_every in &cadences {
                                        for &lambda in &self.lambda.values {
                                            out.push(Setting {
                                                split_range,
                                                knob,
                                                distance,
                                                light_update,
                                                update_every,
                                                ..Setting::plain(lambda, cascades, resolution, fit)
                                            });
                                        }
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
    pub(crate) fn cli_args(&self, config: &Config) -> String {
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
        if let Some(u) = &self.update_every {
            out.push_str(&format!(" --update-every {}", u.spec));
        }
        out
    }
}

/// One point of the grid.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// Cached cascades (None: not swept; the config's own `shadow.update_every`).
    #[serde(default)]
    pub update_every: Option<SweptCadence>,
}

impl Setting {
    /// λ, cascade count, resolution and fit on the bounds' depth range, every other axis not
    /// swept (the config's own).
    pub(crate) fn plain(lambda: f64, cascades: usize, resolution: u32, fit: Fit) -> Setting {
        Setting {
            lambda,
            cascades,
            resolution,
            fit,
            split_range: SplitRange::Bounds,
            knob: None,
            distance: None,
            sun: None,
            light_update: None,
            update_every: None,
        }
    }

    /// The base config with this setting applied. With a preset, λ goes to the engine's own
    /// λ-like knob (when it has one) and the count and map size are checked against the
    /// engine's; [`Grid::resolve`] has already checked every point, so this does not fail for
    /// a resolved grid.
    pub fn apply(&self, base: &Config) -> Result<Config> {
        // The cadence first: a per-cascade cadence fits one cascade count, which the shadow
        // steps check.
        let cached;
        let base = match self.update_every {
            None => base,
            Some(u) => {
                let mut c = base.clone();
                c.shadow.update_every = u.update_every().caching();
                cached = c;
                &cached
            }
        };
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
        if let Some(u) = self.update_every {
            extra.push_str(&format!(", update every {}", u.label()));
        }
        format!(
            "{} x {}^2, lambda {}, {}{range}{extra}",
            self.cascades, self.resolution, self.lambda, self.fit
        )
    }
}

/// A fit and the depths its splits divide: what figures draw a panel or series for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) struct FitGroup {
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
    pub(crate) fn fit_group(&self) -> FitGroup {
        FitGroup {
            split_range: self.split_range,
            fit: self.fit,
        }
    }
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

/// A sun position of a sweep, in degrees as written on the command line or in the file.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sun {
    /// Compass bearing from north (−Z) toward east (+X), degrees in [0, 360).
    pub azimuth_deg: f64,
    /// Angle above the horizon, degrees in (0, 90].
    pub elevation_deg: f64,
}

impl Sun {
    pub(crate) fn angles(self) -> SunAngles {
        SunAngles {
            azimuth: self.azimuth_deg.to_radians(),
            elevation: self.elevation_deg.to_radians(),
        }
    }

    /// The unit direction the light travels in under this sun ([`SunAngles::light_direction`]),
    /// with the components the degrees make exactly zero set to zero: at azimuth 90° the
    /// radians give cos = 6e-17, not 0, and a wall parallel to the light would then count as
    /// lit at a grazing angle (aliasing at the clamp, 1e6) at 270° but not at 90°.
    pub fn light_direction(self) -> DVec3 {
        let mut d = self.angles().light_direction();
        let whole = |x: f64, m: f64| x.rem_euclid(m) == 0.0;
        if whole(self.azimuth_deg, 180.0) || self.elevation_deg == 90.0 {
            d.x = 0.0; // sin a = 0 (north or south), or cos e = 0 (zenith)
        }
        if whole(self.azimuth_deg - 90.0, 180.0) || self.elevation_deg == 90.0 {
            d.z = 0.0; // cos a = 0 (east or west), or cos e = 0 (zenith)
        }
        d
    }

    /// The sun of a config's light (azimuth brought into [0, 360)).
    pub(crate) fn of_config(config: &Config) -> Sun {
        let a = SunAngles::of_light_direction(config.light_direction);
        let mut azimuth_deg = a.azimuth.to_degrees();
        if azimuth_deg < 0.0 {
            azimuth_deg += 360.0;
        }
        if azimuth_deg >= 360.0 {
            azimuth_deg = 0.0;
        }
        Sun {
            azimuth_deg,
            elevation_deg: a.elevation.to_degrees(),
        }
    }

    /// `azimuth 135°, elevation 40°`.
    pub(crate) fn label(self) -> String {
        format!("azimuth {}°, elevation {}°", self.azimuth_deg, self.elevation_deg)
    }
}

/// `--sun-azimuth 0:345:15` or a list, degrees in [0, 360).
pub(crate) fn parse_sun_azimuth_spec(spec: &str) -> Result<Axis<f64>> {
    parse_number_spec(
        "--sun-azimuth",
        spec,
        "[0, 360) degrees (compass bearing from north toward east)",
        sun_azimuth_ok,
    )
}

/// `--sun-elevation 5:85:5` or a list, degrees in (0, 90].
pub(crate) fn parse_sun_elevation_spec(spec: &str) -> Result<Axis<f64>> {
    parse_number_spec(
        "--sun-elevation",
        spec,
        "(0, 90] degrees above the horizon",
        sun_elevation_ok,
    )
}

/// The sun axes of a grid: what was swept (None: the configured light's angle) and the
/// configured sun.
#[derive(Debug, Clone, PartialEq)]
pub struct SunGrid {
    pub azimuth: Option<Axis<f64>>,
    pub elevation: Option<Axis<f64>>,
    /// The configured light's sun, for the axis not swept.
    pub configured: Sun,
}

impl SunGrid {
    /// The sun axes from the flags, else the `[sweep]` table; None when neither sweeps the sun.
    pub(crate) fn resolve(
        config: &Config,
        azimuth: Option<Axis<f64>>,
        elevation: Option<Axis<f64>>,
    ) -> Option<SunGrid> {
        let spec = config.sweep.as_ref();
        let azimuth = azimuth.or_else(|| spec.and_then(|s| s.axes.sun_azimuth.clone()));
        let elevation = elevation.or_else(|| spec.and_then(|s| s.axes.sun_elevation.clone()));
        (azimuth.is_some() || elevation.is_some()).then(|| SunGrid {
            azimuth,
            elevation,
            configured: Sun::of_config(config),
        })
    }

    pub(crate) fn azimuths(&self) -> Vec<f64> {
        self.azimuth
            .as_ref()
            .map_or_else(|| vec![self.configured.azimuth_deg], |a| a.values.clone())
    }

    pub(crate) fn elevations(&self) -> Vec<f64> {
        self.elevation
            .as_ref()
            .map_or_else(|| vec![self.configured.elevation_deg], |a| a.values.clone())
    }

    /// Every sun position in row order: elevation outer, azimuth inner.
    pub(crate) fn suns(&self) -> Vec<Sun> {
        let azimuths = self.azimuths();
        self.elevations()
            .into_iter()
            .flat_map(|e| {
                azimuths.iter().map(move |&a| Sun {
                    azimuth_deg: a,
                    elevation_deg: e,
                })
            })
            .collect()
    }

    pub(crate) fn len(&self) -> usize {
        self.azimuths().len() * self.elevations().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// ` --sun-azimuth A --sun-elevation E` for the swept axes.
    pub(crate) fn cli_args(&self) -> String {
        let mut out = String::new();
        if let Some(a) = &self.azimuth {
            out.push_str(&format!(" --sun-azimuth {}", a.spec));
        }
        if let Some(e) = &self.elevation {
            out.push_str(&format!(" --sun-elevation {}", e.spec));
        }
        out
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

    #[test]
    fn compass_points_give_exact_zeros_and_agree_with_the_core_convention() {
        let (s30, c30) = (0.5f64, 3f64.sqrt() / 2.0);
        for (a, want) in [
            (0.0, DVec3::new(0.0, -s30, c30)),
            (90.0, DVec3::new(-c30, -s30, 0.0)),
            (180.0, DVec3::new(0.0, -s30, -c30)),
            (270.0, DVec3::new(c30, -s30, 0.0)),
        ] {
            let d = Sun {
                azimuth_deg: a,
                elevation_deg: 30.0,
            }
            .light_direction();
            assert!((d - want).length() < 1e-15, "{a}: {d}");
            // The zero components are exactly zero.
            assert_eq!(d.x == 0.0, want.x == 0.0, "{a}: {d}");
            assert_eq!(d.z == 0.0, want.z == 0.0, "{a}: {d}");
        }
        let zenith = Sun {
            azimuth_deg: 45.0,
            elevation_deg: 90.0,
        }
        .light_direction();
        assert_eq!(zenith, DVec3::new(0.0, -1.0, 0.0));
        // Elsewhere it is the core's direction, bit for bit.
        let s = Sun {
            azimuth_deg: 135.0,
            elevation_deg: 40.0,
        };
        assert_eq!(s.light_direction(), s.angles().light_direction());
    }

    #[test]
    fn the_configured_sun_round_trips_and_specs_name_their_flag() {
        let text = include_str!("../../../configs/default.toml")
            .replace("direction = [-0.4, -1.0, -0.3]", "direction = [0.4, -1.0, 0.3]");
        assert!(text.contains("[0.4, -1.0, 0.3]"));
        let config = crate::config::Config::from_toml_str(&text, "t.toml", None).unwrap();
        let sun = Sun::of_config(&config);
        // The sun stands north-west (toward −X and −Z): atan2(−0.4, 0.3) = −53.13°, wrapped.
        let want = 360.0 + (-0.4f64).atan2(0.3).to_degrees();
        assert!((sun.azimuth_deg - want).abs() < 1e-9 && want > 270.0, "{sun:?}");
        assert!((sun.light_direction() - config.light_direction).length() < 1e-12);
        assert_eq!(parse_sun_azimuth_spec("0:345:15").unwrap().values.len(), 24);
        assert_eq!(parse_sun_elevation_spec("5:85:5").unwrap().values.len(), 17);
        assert_eq!(parse_sun_elevation_spec("5:85:5").unwrap().values[16], 85.0);
        for (r, flag) in [
            (parse_sun_elevation_spec("0"), "--sun-elevation"),
            (parse_sun_elevation_spec("90.5"), "--sun-elevation"),
            (parse_sun_azimuth_spec("360"), "--sun-azimuth"),
            (parse_sun_azimuth_spec("0:90:0"), "--sun-azimuth"),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(e.starts_with(flag), "{e}");
        }
    }
}
