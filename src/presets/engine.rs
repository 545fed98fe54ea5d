//! What an engine preset is: the [`Engine`] trait each engine file implements, and
//! [`DynEngine`], the same rules behind a `&dyn` for code that holds a [`Knobs`] value.

use glam::{DVec2, DVec3};
use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::config::{Fit, Validator};
use crate::error::Result;
use csm_core::cascades::{BasisRule, LightDepthRule, WindowRule};
use csm_core::fitting::Sphere;
use csm_core::geometry::{Aabb, Lens, LightBasis};
use csm_core::snapping::{SnapMode, SnapRule};

use super::bias::BiasModel;
use super::free_splits::{FreeSplitKnob, FreeSplits, Planes, Setting};
use super::{fit_split_knob, Dims, Fields, Knobs, Layout, Target, Terms, Values};
use csm_core::free_splits::FractionSpace;

/// Which cascade counts a preset takes.
#[derive(Debug, Clone, PartialEq)]
pub enum Counts {
    /// Any count in the range; larger or smaller counts are clamped (Dart) or rejected.
    Clamped(usize, usize),
    /// Only these counts.
    Allowed(Vec<usize>),
    /// Hard-coded by the implementation.
    Fixed(usize),
}

impl Counts {
    /// Every count the preset takes.
    pub fn list(&self) -> Vec<usize> {
        match self {
            Counts::Clamped(lo, hi) => (*lo..=*hi).collect(),
            Counts::Allowed(v) => v.clone(),
            Counts::Fixed(n) => vec![*n],
        }
    }
}

/// What an engine's knobs are resolved against: the validator (for errors naming the key), and
/// the scene and light that default light positions are placed from.
pub struct KnobContext<'a> {
    pub v: &'a Validator<'a>,
    pub scene: &'a Aabb,
    /// Unit direction light travels.
    pub light_direction: DVec3,
}

/// What a window rule is built from: the lens, the engine's light basis, the map size, the
/// fitted slices, the snap rule, the camera planes and the shadow distance.
pub struct Fitting<'a> {
    pub lens: Lens,
    pub light: LightBasis,
    pub resolution: u32,
    pub fitted: &'a [(f64, f64)],
    pub snap_rule: SnapRule,
    /// Camera near and far planes.
    pub near: f64,
    pub far: f64,
    /// The shadow distance (as [`Engine::layout`] got it).
    pub max_distance: f64,
}

impl Fitting<'_> {
    /// One number per fitted slice.
    pub(crate) fn each(&self, f: impl Fn(f64, f64) -> f64) -> Vec<f64> {
        self.fitted.iter().map(|&(a, b)| f(a, b)).collect()
    }

    /// One sphere per fitted slice.
    pub(crate) fn spheres(&self, f: impl Fn(f64, f64) -> Sphere) -> Vec<Sphere> {
        self.fitted.iter().map(|&(a, b)| f(a, b)).collect()
    }

    /// Windows centred on the view-axis point of each sphere.
    pub(crate) fn axis(spheres: &[Sphere]) -> WindowRule {
        WindowRule::AxisCentred {
            centre_depth: spheres.iter().map(|s| s.centre_depth).collect(),
        }
    }

    /// A sphere of radius r on `usable` of the map's N texels: window side 2r·N/usable.
    pub(crate) fn on(&self, spheres: &[Sphere], usable: f64) -> Vec<f64> {
        let n = self.resolution as f64;
        spheres.iter().map(|s| 2.0 * s.radius * n / usable).collect()
    }
}

/// How an engine sizes, centres and places its windows, and which light depth it renders.
pub struct EngineScheme {
    /// The fit's name in reports.
    pub label: &'static str,
    pub window: WindowRule,
    /// Constant window side per cascade (ignored by box fits).
    pub sides: Vec<f64>,
    pub basis: BasisRule,
    /// Light-space x/y the snap grid passes through.
    pub anchor: DVec2,
    pub depth: LightDepthRule,
}

impl EngineScheme {
    /// A scheme in the engine's fixed light basis, snapped on the grid through the world origin.
    pub(crate) fn fixed(label: &'static str, window: WindowRule, sides: Vec<f64>, depth: LightDepthRule) -> Self {
        EngineScheme {
            label,
            window,
            sides,
            basis: BasisRule::Fixed,
            anchor: DVec2::ZERO,
            depth,
        }
    }
}

/// A rule in words for the reports: a fixed sentence, or one written from the engine's knobs.
pub enum Described<K: 'static> {
    Fixed(&'static str),
    From(fn(&K) -> String),
}

impl<K> Described<K> {
    pub fn text(&self, k: &K) -> String {
        match self {
            Described::Fixed(s) => (*s).to_string(),
            Described::From(f) => f(k),
        }
    }
}

/// A snap rule: rounding mode and step in texels.
pub fn snap(mode: SnapMode, step_texels: u32) -> SnapRule {
    SnapRule { mode, step_texels }
}

/// An engine's own split knob that a sweep can vary (`docs/presets.md`, "Sweep axes").
#[derive(Debug, Clone, PartialEq)]
pub struct Knob {
    /// The config key, as in the engine's table (`unreal.cascade_distribution_exponent`).
    pub key: &'static str,
    /// The knob's name in the engine's own terms (reports, figures).
    pub term: &'static str,
    /// The configured value.
    pub value: f64,
    /// Allowed values: `min..=max`.
    pub min: f64,
    pub max: f64,
    /// What a sweep varies when no values are given: values around the configured one.
    pub sweep: Vec<f64>,
}

/// One engine's whole cascade set-up. Implemented by a unit struct per engine file.
pub trait Engine: Sync + 'static {
    /// Resolved knobs (defaults applied, validated).
    type Knobs: std::fmt::Debug + Clone + PartialEq + Serialize + Send + Sync;
    /// The `[<name>]` table as written (`#[serde(deny_unknown_fields)]`).
    type Table: DeserializeOwned + Default;

    /// The name in configs, on the command line, and of the engine table.
    const NAME: &'static str;
    /// Where the rules come from.
    const SOURCE: &'static str;
    /// Map sizes must be powers of two.
    const POWER_OF_TWO_MAPS: bool = false;
    /// The engine has a shadow distance (`shadow.max_distance`); otherwise it uses camera.far.
    const HAS_DISTANCE: bool = true;
    /// The family of csm-lab's fits its window belongs to.
    const FIT: Fit = Fit::Sphere;
    /// Whether windows move in whole texels.
    const SNAPS: bool = true;

    /// Validates the table and applies defaults.
    fn knobs(table: &Self::Table, cx: &KnobContext<'_>) -> Result<Self::Knobs>;
    /// Notes about how the table was read (after the generic ones).
    fn table_notes(_table: &Self::Table, _k: &Self::Knobs) -> Vec<String> {
        Vec::new()
    }
    /// Default cascade count and shadow distance.
    fn defaults(k: &Self::Knobs, camera_far: f64) -> (usize, f64);
    /// Map size per cascade when not configured.
    fn default_resolution(_k: &Self::Knobs, _cascades: usize) -> u32 {
        2048
    }
    fn counts(k: &Self::Knobs) -> Counts;
    /// Checks of the engine that involve the count or the shadow distance.
    fn check(_k: &Self::Knobs, _cascades: usize, _max_distance: f64, _v: &Validator<'_>) -> Result<()> {
        Ok(())
    }

    /// λ of a practical split rule, if it has one.
    fn lambda(_k: &Self::Knobs) -> Option<f64> {
        None
    }
    /// The config key a λ sweep sets, if λ can be swept.
    fn lambda_key(_k: &Self::Knobs) -> Option<&'static str> {
        None
    }
    /// Sets the λ knob (only called when [`Engine::lambda_key`] is Some).
    fn set_lambda(_k: &mut Self::Knobs, _lambda: f64) {}

    /// The engine's split knob a sweep can vary, if it has a scalar one besides λ; its default
    /// sweep values fit the shadow distance `max_distance`.
    fn knob(_k: &Self::Knobs, _max_distance: f64) -> Option<Knob> {
        None
    }
    /// Sets the split knob (only called when [`Engine::knob`] is Some, with a value in range).
    fn set_knob(_k: &mut Self::Knobs, _value: f64) {}

    /// Fitted slices and selection boundaries. `max_distance` is the shadow distance (unused
    /// without one); `near`/`far` are the camera planes.
    fn layout(k: &Self::Knobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout;
    /// Rounding mode and step of the snap.
    fn snap_rule(_k: &Self::Knobs) -> SnapRule {
        snap(SnapMode::Round, 1)
    }
    /// The light's basis for a unit light direction: csm-lab's unless the engine's own rule
    /// is known (see `docs/presets.md`).
    fn light_basis(direction: DVec3) -> LightBasis {
        LightBasis::new(direction)
    }
    /// Window sizes and centres, light basis rule, snap anchor and light depth.
    fn scheme(k: &Self::Knobs, f: &Fitting<'_>) -> EngineScheme;

    /// The split rule in words.
    fn split_rule(k: &Self::Knobs) -> String;
    /// What the snap grid is anchored to, in words.
    fn snap_anchor(_k: &Self::Knobs) -> &'static str {
        "world origin"
    }
    /// The light depth rule in words.
    const LIGHT_DEPTH: Described<Self::Knobs>;

    /// The engine's default shadow bias as the ground truth models it, or why it models none
    /// (no default: an engine must answer).
    fn bias() -> BiasModel;

    /// How the engine holds its split positions as free fractions (`sweep --optimize-splits`);
    /// None (the default) when its splits are not free fractions.
    const FREE_SPLITS: Option<FreeSplits<Self::Knobs>> = None;

    /// How the engine writes a setting in its own configuration language
    /// (`recommendation.<engine>.txt`; [`super::terms`]).
    const TERMS: Terms;
    /// The values of [`Engine::TERMS`]'s placeholders for knobs `k` at `d`; `near`/`far` are
    /// the camera planes (for split rules that depend on them).
    fn terms(k: &Self::Knobs, d: &Dims, near: f64, far: f64) -> Values;
    /// Reads the placeholders back: the knobs, validated as [`Engine::knobs`] validates the
    /// engine's table, and the count, map size and shadow distance.
    fn from_terms(f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(Self::Knobs, Dims)>;
    /// Sets the split knobs so that the cascades end as near csm-lab's `t.ends` as the engine
    /// allows: exactly for free split fractions; by default a 1-D fit of the split knob or λ
    /// ([`fit_split_knob`]); left alone when the engine has neither.
    fn match_ends(k: &mut Self::Knobs, t: &Target<'_>) {
        fit_split_knob::<Self>(k, t);
    }
}

/// Finding an engine's knobs in [`Knobs`] (implemented by the registry).
pub trait KnobsOf: Engine {
    fn get(k: &Knobs) -> Option<&Self::Knobs>;
    fn get_mut(k: &mut Knobs) -> Option<&mut Self::Knobs>;
    fn wrap(k: Self::Knobs) -> Knobs;
}

/// An [`Engine`] behind a `&dyn`: every rule takes the preset's [`Knobs`].
pub trait DynEngine: Sync {
    fn name(&self) -> &'static str;
    fn source(&self) -> &'static str;
    fn power_of_two_maps(&self) -> bool;
    fn has_distance(&self) -> bool;
    fn fit(&self) -> Fit;
    fn snaps(&self) -> bool;
    /// Parses the engine's table from the config text (if present) and resolves the knobs,
    /// with the notes the table gives.
    fn resolve(&self, text: &str, label: &str, cx: &KnobContext<'_>) -> Result<(Knobs, Vec<String>)>;
    fn defaults(&self, k: &Knobs, camera_far: f64) -> (usize, f64);
    fn default_resolution(&self, k: &Knobs, cascades: usize) -> u32;
    fn counts(&self, k: &Knobs) -> Counts;
    fn check(&self, k: &Knobs, cascades: usize, max_distance: f64, v: &Validator<'_>) -> Result<()>;
    fn lambda(&self, k: &Knobs) -> Option<f64>;
    fn lambda_key(&self, k: &Knobs) -> Option<&'static str>;
    fn set_lambda(&self, k: &mut Knobs, lambda: f64);
    fn knob(&self, k: &Knobs, max_distance: f64) -> Option<Knob>;
    fn set_knob(&self, k: &mut Knobs, value: f64);
    fn layout(&self, k: &Knobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout;
    fn snap_rule(&self, k: &Knobs) -> SnapRule;
    fn light_basis(&self, direction: DVec3) -> LightBasis;
    /// [`DynEngine::light_basis`] as a function, for a walk under a moving light.
    fn light_basis_fn(&self) -> fn(DVec3) -> LightBasis;
    fn scheme(&self, k: &Knobs, f: &Fitting<'_>) -> EngineScheme;
    fn split_rule(&self, k: &Knobs) -> String;
    fn snap_anchor(&self, k: &Knobs) -> &'static str;
    fn light_depth_rule(&self, k: &Knobs) -> String;
    fn bias(&self) -> BiasModel;
    fn has_free_splits(&self) -> bool;
    /// The knob holding the fractions of `cascades` (at least 2) cascades.
    fn free_split_knob(&self, cascades: usize) -> Option<FreeSplitKnob>;
    fn fraction_space(&self, k: &Knobs, p: Planes) -> Option<FractionSpace>;
    fn configured_fractions(&self, k: &Knobs, cascades: usize, p: Planes) -> Option<Vec<f64>>;
    /// The knob's values for `fractions` (the fractions themselves when the splits are not free).
    fn fraction_values(&self, k: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Vec<f64>;
    fn set_fraction_values(&self, k: &mut Knobs, cascades: usize, values: Vec<f64>);
    fn fractions_setting(&self, k: &Knobs, s: &Setting<'_>) -> Option<String>;
    /// [`FreeSplits::paste_prefix`] and [`FreeSplits::scalar_when_one`].
    fn paste_form(&self) -> Option<(&'static str, bool)>;
    fn fit_fractions_to_count(&self, k: &mut Knobs, cascades: usize);
    fn terms(&self) -> &'static Terms;
    fn terms_values(&self, k: &Knobs, d: &Dims, near: f64, far: f64) -> Values;
    fn read_terms(&self, f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(Knobs, Dims)>;
    fn match_ends(&self, k: &mut Knobs, t: &Target<'_>);
}

fn own<E: KnobsOf>(k: &Knobs) -> &E::Knobs {
    E::get(k).unwrap_or_else(|| panic!("{} rules called with {} knobs", E::NAME, k.name()))
}

impl<E: KnobsOf> DynEngine for E {
    fn name(&self) -> &'static str {
        E::NAME
    }

    fn source(&self) -> &'static str {
        E::SOURCE
    }

    fn power_of_two_maps(&self) -> bool {
        E::POWER_OF_TWO_MAPS
    }

    fn has_distance(&self) -> bool {
        E::HAS_DISTANCE
    }

    fn fit(&self) -> Fit {
        E::FIT
    }

    fn snaps(&self) -> bool {
        E::SNAPS
    }

    fn resolve(&self, text: &str, label: &str, cx: &KnobContext<'_>) -> Result<(Knobs, Vec<String>)> {
        let table: E::Table = super::shared::engine_table(text, label, E::NAME)?.unwrap_or_default();
        let k = E::knobs(&table, cx)?;
        let notes = E::table_notes(&table, &k);
        Ok((E::wrap(k), notes))
    }

    fn defaults(&self, k: &Knobs, camera_far: f64) -> (usize, f64) {
        E::defaults(own::<E>(k), camera_far)
    }

    fn default_resolution(&self, k: &Knobs, cascades: usize) -> u32 {
        E::default_resolution(own::<E>(k), cascades)
    }

    fn counts(&self, k: &Knobs) -> Counts {
        E::counts(own::<E>(k))
    }

    fn check(&self, k: &Knobs, cascades: usize, max_distance: f64, v: &Validator<'_>) -> Result<()> {
        E::check(own::<E>(k), cascades, max_distance, v)
    }

    fn lambda(&self, k: &Knobs) -> Option<f64> {
        E::lambda(own::<E>(k))
    }

    fn lambda_key(&self, k: &Knobs) -> Option<&'static str> {
        E::lambda_key(own::<E>(k))
    }

    fn set_lambda(&self, k: &mut Knobs, lambda: f64) {
        if let Some(k) = E::get_mut(k) {
            E::set_lambda(k, lambda);
        }
    }

    fn knob(&self, k: &Knobs, max_distance: f64) -> Option<Knob> {
        E::knob(own::<E>(k), max_distance)
    }

    fn set_knob(&self, k: &mut Knobs, value: f64) {
        if let Some(k) = E::get_mut(k) {
            E::set_knob(k, value);
        }
    }

    fn layout(&self, k: &Knobs, cascades: usize, max_distance: f64, near: f64, far: f64) -> Layout {
        E::layout(own::<E>(k), cascades, max_distance, near, far)
    }

    fn snap_rule(&self, k: &Knobs) -> SnapRule {
        E::snap_rule(own::<E>(k))
    }

    fn light_basis(&self, direction: DVec3) -> LightBasis {
        E::light_basis(direction)
    }

    fn light_basis_fn(&self) -> fn(DVec3) -> LightBasis {
        E::light_basis
    }

    fn scheme(&self, k: &Knobs, f: &Fitting<'_>) -> EngineScheme {
        E::scheme(own::<E>(k), f)
    }

    fn split_rule(&self, k: &Knobs) -> String {
        E::split_rule(own::<E>(k))
    }

    fn snap_anchor(&self, k: &Knobs) -> &'static str {
        E::snap_anchor(own::<E>(k))
    }

    fn light_depth_rule(&self, k: &Knobs) -> String {
        E::LIGHT_DEPTH.text(own::<E>(k))
    }

    fn bias(&self) -> BiasModel {
        E::bias()
    }

    fn has_free_splits(&self) -> bool {
        E::FREE_SPLITS.is_some()
    }

    fn free_split_knob(&self, cascades: usize) -> Option<FreeSplitKnob> {
        E::FREE_SPLITS.map(|f| (f.knob)(cascades))
    }

    fn fraction_space(&self, k: &Knobs, p: Planes) -> Option<FractionSpace> {
        E::FREE_SPLITS.map(|f| (f.space)(own::<E>(k), p))
    }

    fn configured_fractions(&self, k: &Knobs, cascades: usize, p: Planes) -> Option<Vec<f64>> {
        E::FREE_SPLITS.map(|f| (f.configured)(own::<E>(k), cascades, p))
    }

    fn fraction_values(&self, k: &Knobs, cascades: usize, max_distance: f64, fractions: &[f64]) -> Vec<f64> {
        match E::FREE_SPLITS {
            Some(f) => (f.values)(own::<E>(k), cascades, max_distance, fractions),
            None => fractions.to_vec(),
        }
    }

    fn set_fraction_values(&self, k: &mut Knobs, cascades: usize, values: Vec<f64>) {
        if let (Some(f), Some(k)) = (E::FREE_SPLITS, E::get_mut(k)) {
            (f.set)(k, cascades, values);
        }
    }

    fn fractions_setting(&self, k: &Knobs, s: &Setting<'_>) -> Option<String> {
        E::FREE_SPLITS.map(|f| (f.setting)(own::<E>(k), s))
    }

    fn paste_form(&self) -> Option<(&'static str, bool)> {
        E::FREE_SPLITS.map(|f| (f.paste_prefix, f.scalar_when_one))
    }

    fn fit_fractions_to_count(&self, k: &mut Knobs, cascades: usize) {
        if let (Some(f), Some(k)) = (E::FREE_SPLITS, E::get_mut(k)) {
            (f.fit_count)(k, cascades);
        }
    }

    fn terms(&self) -> &'static Terms {
        &E::TERMS
    }

    fn terms_values(&self, k: &Knobs, d: &Dims, near: f64, far: f64) -> Values {
        E::terms(own::<E>(k), d, near, far)
    }

    fn read_terms(&self, f: &Fields<'_>, cx: &KnobContext<'_>) -> Result<(Knobs, Dims)> {
        let (k, d) = E::from_terms(f, cx)?;
        Ok((E::wrap(k), d))
    }

    fn match_ends(&self, k: &mut Knobs, t: &Target<'_>) {
        if let Some(k) = E::get_mut(k) {
            E::match_ends(k, t);
        }
    }
}
