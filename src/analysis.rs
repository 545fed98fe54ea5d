//! One configuration, measured end to end: depth range, splits, windows, density, closed-form
//! aggregates, shimmer with and without snapping, coverage and light depth ranges.

use crate::config::Config;
use csm_core::cascades::{LightPose, Rig};
use csm_core::depth_range::{self, DepthRange};
use csm_core::geometry::CameraPose;
use csm_core::metrics::{self, Aggregates, DensitySample};
use csm_core::precision::{self, LookupError};
use csm_core::rig_path;
use csm_core::scene::Precision;
use csm_core::screen::{self, ScreenStats};
use csm_core::seams;
use csm_core::shimmer::{PathResult, ShimmerOptions, StaleStats};
use csm_core::visibility::Visibility;
use csm_core::walk::Cadence;
use glam::DVec2;

pub mod cost;
pub mod ground_truth;
pub(crate) mod search;
pub(crate) mod views_truth;

/// Which optional parts to compute. The summary metrics are always computed and never depend
/// on these switches (but `seams`, which adds `seam_crossings` or leaves it out), so a sweep
/// row equals what `analyze` reports for the same config.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalysisOptions {
    /// S4 cell flips per probe (the only per-probe work when window sizes are fixed).
    pub cell_flips: bool,
    /// Keep per-frame shimmer rows (`shimmer.csv`).
    pub frame_rows: bool,
    /// Sample the density profile (`density.csv`).
    pub density_profile: bool,
    /// Light near/far per cascade (`cascades.csv`).
    pub light_depth: bool,
    /// `seam_crossings`: every receiver point over every frame of the motion paths (the only
    /// summary metric that depends on a switch: without it the summary holds None and every
    /// output leaves the key out).
    pub seams: bool,
    /// The ground-truth pass, when the config asks for it (`[analysis] ground_truth`); sweeps
    /// leave it out.
    pub ground_truth: bool,
    /// The cost counts' means over the camera path (`*_mean`, docs/cost.md), where they can
    /// be measured ([`cost::means_measurable`]); a sweep asks for them with
    /// `[sweep] cost_means` or when a setting caches cascades.
    pub cost_means: bool,
    /// The ground-truth pass's texel reads and rays (`analyze` prints them): counting the rays
    /// keeps a set of the texels read per map grid. Without it the pass's counts are 0.
    pub texel_counts: bool,
    /// What a level of views keeps of each view's own screen metrics ([`ViewDetail`]).
    pub views: ViewDetail,
}

/// What the analysis of a level of views keeps of each view's own screen metrics
/// (docs/views.md, "What a row keeps of each view").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewDetail {
    /// Every view's own screen metrics in full ([`Summary::views`]): what `views.csv`,
    /// `summary.json` and the report show.
    Full,
    /// Only what a sweep's ranking of the views reads ([`Summary::view_ranks`]): each view's
    /// own value of the statistic its objective is (None: the objective is none of a view's
    /// statistics, and a view's rows take the level's value), its largest `m` and whether it
    /// sees a receiver.
    Ranking(Option<screen::Statistic>),
}

impl AnalysisOptions {
    /// Everything, as `analyze` writes it.
    pub fn full() -> Self {
        AnalysisOptions {
            cell_flips: true,
            frame_rows: true,
            density_profile: true,
            light_depth: true,
            seams: true,
            ground_truth: true,
            cost_means: true,
            texel_counts: true,
            views: ViewDetail::Full,
        }
    }

    /// Only what a sweep row needs.
    pub fn summary_only() -> Self {
        AnalysisOptions {
            cell_flips: false,
            frame_rows: false,
            density_profile: false,
            light_depth: false,
            seams: false,
            ground_truth: false,
            cost_means: false,
            texel_counts: false,
            views: ViewDetail::Full,
        }
    }
}

/// The flat summary: the metric names users' scripts and CI thresholds read.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Summary {
    /// False when the scene is not visible within the shadow distance; then every metric below
    /// is 0 and no cascade is built.
    pub cascades_needed: bool,
    pub z_lo: f64,
    pub z_hi: f64,
    pub max_aliasing: f64,
    pub mean_aliasing: f64,
    pub mean_log_aliasing: f64,
    pub undersampled_fraction: f64,
    /// RMS sub-texel phase drift (S3) with the configured snapping (`shadow.snap`): what the
    /// configured setting shows. The worst over the motion paths.
    pub shimmer: f64,
    /// RMS sub-texel phase drift (S3) over the path with snapping, in texels.
    pub shimmer_snapped: f64,
    /// The same without snapping.
    pub shimmer_unsnapped: f64,
    /// Largest relative texel-size change between frames (S1).
    pub size_jitter: f64,
    /// Slice corners outside their window, over every frame, with the configured snapping.
    pub coverage_violations: u64,
    /// cascades x resolution^2 x 4 bytes (32-bit depth).
    pub memory_bytes: u64,
    /// S7, static lookup error of the binary32 pipeline against its f64 evaluation, largest
    /// over the path, cascades and probes (texels; 0 with precision = "f64").
    pub lookup_error_max: f64,
    /// RMS of S7 over the same set (texels; 0 with precision = "f64").
    pub lookup_error_rms: f64,
    /// Extra shadow-map texels the blend bands cost (every split), over all maps' texels.
    pub overlap_area_fraction: f64,
    /// Share of the lit-facing receiver pixels inside a blend band (every split; 0 without
    /// geometry, where it is not reported). A screen metric (`screen_band_pixel_share`): the
    /// registry writes it with the other screen metrics, and only with geometry.
    #[serde(rename = "screen_band_pixel_share")]
    pub band_pixel_share: f64,
    /// Fraction of world-fixed receiver points that change cascade per frame, the worst over
    /// the motion paths; None when not computed ([`AnalysisOptions::seams`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seam_crossings: Option<f64>,
    /// The screen metrics (per-pixel aliasing of the visible receivers); None in the
    /// bounds-only mode, and then absent from every output.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub screen: Option<ScreenStats>,
    /// Crawl and jumps of a moving light; None under a still light, and then absent from
    /// every output.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub light: Option<LightSummary>,
    /// The ground-truth metrics (acne, leaks, S5), when the pass ran; the registry writes them.
    #[serde(skip)]
    pub truth: Option<ground_truth::TruthSummary>,
    /// With configured views (`[[view]]`, `[views]`) and scene geometry, where they are shown
    /// ([`ViewDetail::Full`]: `analyze`, and a sweep's row at the level's choice): each view's
    /// own screen metrics in full, in the config's order, while [`Summary::screen`] and
    /// [`Summary::band_pixel_share`] hold the level's, pooled over the views
    /// ([`level_screen`]). Empty otherwise (no views, or a sweep row that shows none), and never
    /// in the serde form: a shard's rows carry [`Summary::view_ranks`], and `merge` measures
    /// the shown row's views again as the sweep does.
    #[serde(skip)]
    pub views: Vec<ViewScreen>,
    /// A sweep's row of a level ([`ViewDetail::Ranking`]): per view, in the config's order,
    /// what the ranking of the views reads. Empty otherwise, and then absent from the serde
    /// form.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub view_ranks: Vec<ViewRank>,
    /// Cached cascades (`[shadow] update_every`), when some cascade is held between updates;
    /// None otherwise, and then absent from every output.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub cache: Option<CacheSummary>,
    /// What the setting costs to render (frame 0; docs/cost.md), flat under the registry's
    /// names.
    #[serde(flatten)]
    pub cost: cost::CostSummary,
}

/// What a sweep's ranking reads of one view of a level at one setting ([`ViewDetail::Ranking`]):
/// the view alone is ranked by the same rule as the level, on its own value of the objective
/// and its own worst case (`level::choose`). Every field is measured; a view's other
/// statistics are not (they are shown only at the level's choice, measured there in full).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ViewRank {
    /// The view's own value of the statistic the sweep's objective is (bit for bit that field
    /// of its [`ScreenStats`]); None when the objective is none of a view's screen statistics
    /// (a cost, the bounds' mean aliasing, ...): the view's value is then the level's.
    pub objective: Option<f64>,
    /// The view's own `screen_aliasing_max`, the near-tie breaker.
    pub worst: f64,
    /// The view sees a lit-facing receiver (`screen_receiver_fraction` above 0).
    pub seen: bool,
}

/// One view's own screen metrics in a level of views (`views.csv`).
#[derive(Debug, Clone, PartialEq)]
pub struct ViewScreen {
    pub name: String,
    pub weight: f64,
    pub screen: ScreenStats,
    /// Share of the view's lit-facing receiver pixels inside a blend band (every split).
    pub band_pixel_share: f64,
    /// The ground-truth pass judged this view (`analyze` with ground truth; at most
    /// [`views_truth::MAX_JUDGED`] views of a level are).
    pub judged: bool,
    /// A judged view's own ground-truth metrics (None when not judged, or when the view needs
    /// no cascades).
    pub truth: Option<ground_truth::TruthSummary>,
}

/// What cached cascades cost and save, over the motion paths with the configured snapping
/// (see [`csm_core::shimmer::StaleStats`] and `docs/cost.md`, "Cached cascades").
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct CacheSummary {
    /// Cascade renders per frame on average: the sum over cascades of 1 / update_every
    /// (the cascade count without caching).
    pub renders_per_frame: f64,
    /// Stale-window figures over every cascade: the violations summed (over cascades and
    /// paths), every other figure the worst cascade's.
    #[serde(flatten)]
    pub figures: StaleFigures,
}

/// One cascade's cached-cascade figures (see [`CacheSummary`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct CascadeCache {
    pub update_every: u64,
    /// 1 / update_every: the share of frames that render this cascade.
    pub update_rate: f64,
    /// This cascade's own stale-window figures.
    #[serde(flatten)]
    pub figures: StaleFigures,
}

/// What holding a cascade's window between its updates costs (written flat, beside the
/// fields of [`CacheSummary`] or [`CascadeCache`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct StaleFigures {
    /// Stale frames whose slice the held window does not cover.
    pub stale_coverage_violations: u64,
    /// The share of frames walked with such a hole.
    pub stale_coverage_fraction: f64,
    /// The largest growth, in texels per side of the cascade's own window, a held window
    /// needs to cover every stale frame.
    pub stale_margin: f64,
    /// The same in world units.
    pub stale_margin_world: f64,
    /// RMS S3 over the update pairs (texels).
    pub update_drift: f64,
    /// S5 over the receiver steps served at the updates (ground truth only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub update_flicker: Option<f64>,
}

impl Summary {
    /// The summary of a scene that needs no cascades: every metric 0 (nothing to measure: no
    /// map, no texel, no drift), `memory_bytes` as given, and nothing optional measured.
    pub(crate) fn nothing_needed(memory_bytes: u64) -> Summary {
        Summary {
            cascades_needed: false,
            z_lo: 0.0,
            z_hi: 0.0,
            max_aliasing: 0.0,
            mean_aliasing: 0.0,
            mean_log_aliasing: 0.0,
            undersampled_fraction: 0.0,
            shimmer: 0.0,
            shimmer_snapped: 0.0,
            shimmer_unsnapped: 0.0,
            size_jitter: 0.0,
            coverage_violations: 0,
            memory_bytes,
            lookup_error_max: 0.0,
            lookup_error_rms: 0.0,
            overlap_area_fraction: 0.0,
            band_pixel_share: 0.0,
            seam_crossings: None,
            screen: None,
            light: None,
            truth: None,
            views: Vec::new(),
            view_ranks: Vec::new(),
            cache: None,
            cost: cost::CostSummary::default(),
        }
    }
}

/// Crawl and jumps of a moving light, the worst over the motion paths (texels; see
/// `docs/metrics.md`).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct LightSummary {
    /// RMS S3 over the frame pairs between updates, with the configured snapping.
    #[serde(rename = "light_crawl")]
    pub crawl: f64,
    #[serde(rename = "light_crawl_snapped")]
    pub crawl_snapped: f64,
    #[serde(rename = "light_crawl_unsnapped")]
    pub crawl_unsnapped: f64,
    /// Largest probe move (not wrapped) at an update, in windows without snapping (the
    /// visible part; see `docs/metrics.md`).
    #[serde(rename = "light_jump")]
    pub jump: f64,
    #[serde(rename = "light_jump_snapped")]
    pub jump_snapped: f64,
    #[serde(rename = "light_jump_unsnapped")]
    pub jump_unsnapped: f64,
}

impl Summary {
    /// The snapped shimmer the recommendation's stability rule reads: `shimmer_snapped`, or
    /// under a moving light the snapped crawl between light updates (`light_crawl_snapped`). An
    /// update moves every shadow on purpose; how far is `light_jump`, judged on its own by the
    /// light-update axis, so it does not make every setting "unstable".
    pub fn snapped_drift(&self) -> f64 {
        self.light.map_or(self.shimmer_snapped, |l| l.crawl_snapped)
    }
}

impl LightSummary {
    /// From the two snap modes' walks of the paths (the worst over the paths); None when no
    /// walk measured a moving light.
    fn of<'a>(snap: bool, paths: impl IntoIterator<Item = (&'a PathResult, &'a PathResult)>) -> Option<Self> {
        let mut out: Option<LightSummary> = None;
        for (s, u) in paths {
            let (Some(s), Some(u)) = (&s.light, &u.light) else {
                continue;
            };
            let o = out.get_or_insert_with(LightSummary::default);
            o.crawl_snapped = o.crawl_snapped.max(s.crawl_rms);
            o.crawl_unsnapped = o.crawl_unsnapped.max(u.crawl_rms);
            o.jump_snapped = o.jump_snapped.max(s.jump_max);
            o.jump_unsnapped = o.jump_unsnapped.max(u.jump_max);
        }
        out.map(|mut o| {
            o.crawl = if snap { o.crawl_snapped } else { o.crawl_unsnapped };
            // The snapped windows' jump adds their whole-texel re-snap, which moves no shadow
            // on the ground (the grid stays world-anchored): the visible jump is the
            // unsnapped one whatever the snapping.
            o.jump = o.jump_unsnapped;
            o
        })
    }
}

/// One cascade as built for the configured camera (frame 0).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CascadeReport {
    pub cascade: usize,
    pub near: f64,
    pub far: f64,
    /// Minimal bounding-sphere radius of the slice, whatever the fit.
    pub radius: f64,
    pub width: f64,
    pub height: f64,
    pub texel_size: f64,
    /// The window's centre in the cascade's light space (frame 0, snapped as configured):
    /// world units along light x and y, and the same in texels (centre / texel size), so a
    /// window can be compared with an engine's directly.
    pub centre_x: f64,
    pub centre_y: f64,
    pub centre_x_texels: f64,
    pub centre_y_texels: f64,
    pub light_near: f64,
    pub light_far: f64,
    pub coverage_violations: u64,
    pub coverage_worst_texels: f64,
    pub min_slack_texels: f64,
    pub max_aliasing: f64,
    pub min_aliasing: f64,
    /// S7 of this cascade over the path (texels; 0 with precision = "f64").
    pub lookup_error_max: f64,
    pub lookup_error_rms: f64,
    /// Texel size of the next cascade over this one's (the jump at this cascade's far split;
    /// 0 for the last cascade).
    pub split_jump: f64,
    /// The blend band at this cascade's far split (view depths; equal ends when none).
    pub band_near: f64,
    pub band_far: f64,
    /// Texels of this cascade's map spent on its far band, over all maps' texels.
    pub overlap_area_fraction: f64,
    /// With scene geometry: the share of receiver pixels this cascade serves, and the area of
    /// the light-space rectangle around its receiver points over its window's area.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub screen: Option<CascadeScreen>,
    /// A moving light: this cascade's crawl and jump (see [`LightSummary`]); None under a
    /// still light, and then absent from every output.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub light: Option<CascadeLight>,
    /// This cascade's ground truth at frame 0, when the pass ran; the registry writes it.
    #[serde(skip)]
    pub truth: Option<csm_core::truth::CascadeTruth>,
    /// Cached cascades: this cascade's figures, when some cascade is held; None otherwise, and
    /// then absent from every output.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub cache: Option<CascadeCache>,
    /// What this cascade costs to render (frame 0), flat under the registry's names.
    #[serde(flatten)]
    pub cost: cost::CascadeCost,
}

/// One cascade's crawl (configured snapping) and jump (windows without snapping) under a
/// moving light, the worst over the motion paths (texels).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct CascadeLight {
    #[serde(rename = "light_crawl")]
    pub crawl: f64,
    #[serde(rename = "light_jump")]
    pub jump: f64,
}

impl CascadeLight {
    /// Cascade `i`'s values from the two snap modes' walks of the paths; None when no walk
    /// measured a moving light.
    fn of<'a>(snap: bool, i: usize, paths: impl IntoIterator<Item = (&'a PathResult, &'a PathResult)>) -> Option<Self> {
        let mut out: Option<CascadeLight> = None;
        for (s, u) in paths {
            let (Some(s), Some(u)) = (&s.light, &u.light) else {
                continue;
            };
            let o = out.get_or_insert_with(CascadeLight::default);
            let crawl = if snap { s } else { u }
                .cascade_crawl_rms
                .get(i)
                .copied()
                .unwrap_or(0.0);
            o.crawl = o.crawl.max(crawl);
            o.jump = o.jump.max(u.cascade_jump_max.get(i).copied().unwrap_or(0.0));
        }
        out
    }
}

/// The per-cascade screen metrics (scene geometry only).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CascadeScreen {
    pub pixels: f64,
    /// Share of the receiver pixels inside the blend band at this cascade's far split.
    pub band_pixels: f64,
    /// 0 when not computed (sweeps) or when the cascade serves no receiver pixel.
    pub texel_utilization: f64,
}

#[derive(Debug, Clone)]
pub struct Analysis {
    pub config: Config,
    pub range: DepthRange,
    /// Per cascade, frame 0 (empty when no cascade is needed).
    pub cascades: Vec<CascadeReport>,
    /// The density profile (empty when not asked for, or when no cascade is needed).
    pub density: Vec<DensitySample>,
    /// What was measured: cascades, or the scene needs none.
    pub outcome: Outcome,
    /// The flat metrics; all zero (except the memory) when no cascade is needed.
    pub summary: Summary,
    /// The preset's split/fit/snap rules, selection and light-depth findings (None without a preset).
    pub preset: Option<crate::presets::PresetReport>,
    /// The ground-truth pass (`[analysis] ground_truth`), when it ran.
    pub ground_truth: Option<ground_truth::GroundTruth>,
}

/// The result of an analysis: the scene is not visible within the shadow distance, or the
/// cascades were built and measured.
#[derive(Debug, Clone)]
pub enum Outcome {
    NoCascades,
    Cascades(Box<Measured>),
}

/// Everything measured about the cascades of a scene that needs them.
#[derive(Debug, Clone)]
pub struct Measured {
    pub rig: Rig,
    pub aggregates: Aggregates,
    pub snapped: PathResult,
    pub unsnapped: PathResult,
    /// S7 for the configured snap setting, when precision = "f32".
    pub lookup_error: Option<LookupError>,
    /// The further paths of `motion.paths` (empty with a single path).
    pub extra: Vec<ExtraPathResult>,
}

/// One further motion path of `motion.paths`, walked in both snap modes.
#[derive(Debug, Clone)]
pub struct ExtraPathResult {
    pub name: &'static str,
    pub snapped: PathResult,
    pub unsnapped: PathResult,
    pub lookup_error: Option<LookupError>,
}

impl Analysis {
    /// The cascades' measurements, or None when the scene needs no cascade.
    pub(crate) fn measured(&self) -> Option<&Measured> {
        match &self.outcome {
            Outcome::Cascades(m) => Some(m),
            Outcome::NoCascades => None,
        }
    }

    pub fn rig(&self) -> Option<&Rig> {
        self.measured().map(|m| &m.rig)
    }

    pub fn aggregates(&self) -> Option<&Aggregates> {
        self.measured().map(|m| &m.aggregates)
    }

    /// The path with snapping.
    pub fn snapped(&self) -> Option<&PathResult> {
        self.measured().map(|m| &m.snapped)
    }

    /// The path without snapping.
    pub fn unsnapped(&self) -> Option<&PathResult> {
        self.measured().map(|m| &m.unsnapped)
    }

    /// The path result of the configured snap mode.
    pub fn configured_path(&self) -> Option<&PathResult> {
        if self.config.shadow.snap {
            self.snapped()
        } else {
            self.unsnapped()
        }
    }
}

pub(crate) fn memory_bytes(cascades: usize, resolution: u32) -> u64 {
    cascades as u64 * resolution as u64 * resolution as u64 * 4
}

/// Bytes in MiB.
pub(crate) fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// Why a config's cascade windows cannot be built in f64 along its camera paths, or None: a
/// slice thinner than f64 resolves at its coordinates (a near plane of 1e-9 a billion units
/// from the origin) collapses a box-shaped window to zero size, and every texel coordinate
/// after it is not a number. Checks every frame of every path (`all_frames`) or frame 0 of
/// each, both snap modes. The message completes "... is not allowed: ".
pub(crate) fn f64_window_problem(config: &Config, all_frames: bool) -> Option<String> {
    let rig = rig(config)?;
    let setup = config.setup();
    let mut motions = vec![setup.motion.clone()];
    motions.extend(config.extra_motions().into_iter().map(|(_, m)| m));
    for motion in &motions {
        let frames = if all_frames { usize::MAX } else { 1 };
        for (t, pose) in csm_core::motion::poses(&setup.camera, motion)
            .map_while(|p| p.ok())
            .take(frames)
            .enumerate()
        {
            let lp = LightPose::new(&rig.light, &pose);
            for i in 0..rig.cascade_count() {
                for snapped in [true, false] {
                    let w = rig.window(i, &lp, snapped);
                    let ok = w.texel.is_finite() && w.texel.min_element() > 0.0 && w.origin_texels.is_finite();
                    if !ok {
                        let s = &rig.slices[i];
                        let at = pose.position.abs().max_element() + s.far;
                        return Some(format!(
                            "a near plane and splits whose slices f64 can tell apart at the camera's coordinates: in \
                             frame {t} cascade {i}'s window collapses (its slice spans view depths {:e} .. {:e}, and f64 \
                             steps by {:e} at coordinates of {:e}); raise camera.near, lower shadow.lambda or \
                             shadow.cascades, or move the scene toward the origin",
                            s.near,
                            s.far,
                            f64::EPSILON * at,
                            at
                        ));
                    }
                }
            }
        }
    }
    None
}

/// The rig of a config: its engine preset's, or csm-lab's own pipeline built from the
/// config's domain values. None when the scene needs no cascades.
pub fn rig(config: &Config) -> Option<Rig> {
    match &config.shadow.preset {
        Some(preset) => crate::presets::rig(config, preset),
        None => {
            let setup = config.setup();
            Rig::for_setup_in(&setup, split_range(&setup))
        }
    }
}

/// The light of every frame as the walks read it, when the light moves (None under a still
/// light): the used direction of each frame, turned into a basis by the pipeline's rule.
pub fn light_track(config: &Config, first_frame: usize) -> Option<csm_core::light_motion::LightTrack<'_>> {
    config.motion.light.moves().then(|| csm_core::light_motion::LightTrack {
        motion: &config.motion.light,
        start: config.light_direction,
        basis: match &config.shadow.preset {
            Some(p) => crate::presets::light_basis_rule(p),
            None => csm_core::geometry::LightBasis::new,
        },
        first_frame,
    })
}

/// Why a config cannot run with the binary32 pipeline (completes "use precision = ..."), or
/// None; see [`precision::f32_range_problem`].
pub fn f32_range_problem(config: &Config) -> Option<String> {
    let rig = rig(config)?;
    // An invalid path is reported by its own check; the poses are generated, not kept.
    let setup = config.setup();
    let poses = csm_core::motion::poses(&setup.camera, &setup.motion);
    if poses.clone().any(|p| p.is_err()) {
        return None;
    }
    let poses = poses.map_while(|p| p.ok());
    precision::f32_range_problem(&rig, poses, &config.scene, config.shadow.snap_space)
}

/// Frames per walk of [`each_frame_row`]: at most this many frames' rows are in memory.
const FULL_SERIES_CHUNK: usize = csm_core::shimmer::MAX_FRAME_ROWS;

/// Every frame's shimmer rows of every motion path, in `shimmer.csv`'s order (path, then the
/// snapped and the unsnapped mode, then frame, then cascade), handed to `emit` as they are
/// produced. A row depends only on its frame and the one before, so each path is walked in
/// chunks of [`FULL_SERIES_CHUNK`] frames that overlap by one frame: memory stays that of one
/// chunk whatever the path's length, and the rows are those of one walk of the whole path.
/// Without cascades there are no rows.
pub(crate) fn each_frame_row(
    config: &Config,
    opts: &AnalysisOptions,
    emit: &mut dyn FnMut(&'static str, &csm_core::shimmer::FrameShimmer) -> crate::error::Result<()>,
) -> crate::error::Result<()> {
    let Some(rig) = rig(config) else {
        return Ok(());
    };
    let pose0: CameraPose = config.camera.pose();
    let sopts = ShimmerOptions {
        cell_flips: opts.cell_flips,
        probe_drift: false,
        frame_rows: true,
    };
    let probes = if config.shadow.precision == Precision::F32
        || config.motion.light.moves()
        || rig_path::needs_probes(&rig, sopts)
    {
        rig_path::probes(&rig, &pose0, &config.scene, config.analysis.probes)
    } else {
        Vec::new()
    };
    let setup = config.setup();
    let every = cadence(config, &rig);
    let paths = std::iter::once((config.motion.path.name(), setup.motion.clone())).chain(config.extra_motions());
    for (name, motion) in paths {
        let frames = csm_core::motion::poses(&setup.camera, &motion).len();
        for snapped in [true, false] {
            let mut start = 0;
            while start + 1 < frames {
                // Cached cascades: the walk starts at the earliest of the cascades' last
                // updates at or before `start`, so every cascade holds at `start` the window it
                // holds in one walk of the whole path; the rows up to `start` are dropped.
                let from = every.iter().map(|&k| start / k * k).min().unwrap_or(start);
                let take = (FULL_SERIES_CHUNK - (start - from)).min(frames - start);
                let poses = csm_core::motion::poses(&setup.camera, &motion)
                    .skip(from)
                    .take(take + (start - from))
                    .map(|p| p.expect("validated when the config was loaded"));
                let rows = match config.shadow.precision {
                    Precision::F64 if !every.is_empty() => {
                        let cadence = Cadence {
                            every: &every,
                            first_frame: from,
                        };
                        let [walked] = rig_path::along_path_cached(&rig, poses, &probes, cadence, [snapped], sopts);
                        walked
                            .frames
                            .into_iter()
                            // Frames counted from `start`, as the other walks give them.
                            .filter(|r| from + r.frame > start)
                            .map(|mut r| {
                                r.frame = from + r.frame - start;
                                r
                            })
                            .collect()
                    }
                    Precision::F64 => {
                        let light = light_track(config, start);
                        rig_path::along_path_lit(&rig, poses, &probes, light, snapped, sopts).frames
                    }
                    Precision::F32 => {
                        let space = config.shadow.snap_space;
                        precision::along_path(&rig, poses, &probes, space, snapped, sopts)
                            .path
                            .frames
                    }
                };
                for mut row in rows {
                    row.frame += start;
                    emit(name, &row)?;
                }
                start += take - 1;
            }
        }
    }
    Ok(())
}

/// Each cascade's `[shadow] update_every` for this rig, or empty when every cascade is
/// rendered every frame (the key absent, or all ones).
pub(crate) fn cadence(config: &Config, rig: &Rig) -> Vec<usize> {
    config
        .shadow
        .update_every
        .as_ref()
        .and_then(|u| u.per_cascade(rig.cascade_count()))
        .filter(|v| v.iter().any(|&k| k > 1))
        .unwrap_or_default()
}

/// Paths of up to this many frames are generated once per analysis and held (a pose is a
/// few dozen bytes); longer ones are generated as they are walked.
const HELD_POSES: usize = 1 << 14;

/// An iterator of a known length (a chain of a held and a streamed part reports none).
/// The poses as they are read, each also handed to the seam counter (when there is one).
struct Counted<'a, 'c, I> {
    poses: I,
    counter: &'a mut Option<seams::SeamCounter<'c>>,
}

fn counted<'a, 'c, I: ExactSizeIterator<Item = CameraPose>>(
    poses: I,
    counter: &'a mut Option<seams::SeamCounter<'c>>,
) -> Counted<'a, 'c, I> {
    Counted { poses, counter }
}

impl<I: Iterator<Item = CameraPose>> Iterator for Counted<'_, '_, I> {
    type Item = CameraPose;
    fn next(&mut self) -> Option<CameraPose> {
        let p = self.poses.next()?;
        if let Some(c) = self.counter.as_mut() {
            c.frame(&p);
        }
        Some(p)
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        self.poses.size_hint()
    }
}

impl<I: ExactSizeIterator<Item = CameraPose>> ExactSizeIterator for Counted<'_, '_, I> {}

struct ExactLen<I>(I, usize);

impl<I: Iterator> Iterator for ExactLen<I> {
    type Item = I::Item;
    fn next(&mut self) -> Option<I::Item> {
        let x = self.0.next();
        self.1 = self.1.saturating_sub(usize::from(x.is_some()));
        x
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.1, Some(self.1))
    }
}

impl<I: Iterator> ExactSizeIterator for ExactLen<I> {}

/// Runs the analysis of one validated config.
pub fn analyze(config: &Config, opts: &AnalysisOptions) -> Analysis {
    analyze_with_progress(config, opts, &|_| ())
}

/// How many frames [`analyze_with_progress`] walks: every frame of every motion path, once per
/// snap mode.
pub(crate) fn frames_walked(config: &Config) -> u64 {
    // A path file has as many frames as rows; every further path has `motion.frames`.
    let setup = config.setup();
    let first = csm_core::motion::poses(&setup.camera, &setup.motion).len() as u64;
    2 * (first + config.motion.extra.len() as u64 * config.motion.frames as u64)
}

/// [`frames_walked`] plus the ground-truth pass's frames (both snap modes of the first path,
/// for `[camera]` and each judged view of a level) when it runs: the progress bar's length for [`analyze_with_progress`] with `opts`.
pub(crate) fn frames_walked_with(config: &Config, opts: &AnalysisOptions) -> u64 {
    let truth = if ground_truth_runs(config, opts) {
        let setup = config.setup();
        2 * csm_core::motion::poses(&setup.camera, &setup.motion).len() as u64 + views_truth::frames(config)
    } else {
        0
    };
    frames_walked(config) + truth
}

/// Probes per cascade that `seam_crossings` follows without scene geometry.
const SEAM_PROBES: usize = 64;

/// Receiver pixels `seam_crossings` follows at most with scene geometry (every k-th one).
const SEAM_RECEIVERS: usize = 4096;

/// Frames walked between two progress reports.
const PROGRESS_FRAMES: usize = 4096;

/// [`analyze`], reporting the frames walked to `on_frames` as it goes (in batches; they add up
/// to [`frames_walked`] when the scene needs cascades).
pub(crate) fn analyze_with_progress(
    config: &Config,
    opts: &AnalysisOptions,
    on_frames: &(dyn Fn(u64) + Sync),
) -> Analysis {
    let level = level_screen_with(config, opts.views);
    let mut a = analyze_camera(config, opts, on_frames, level.is_none(), Detail::Full);
    if let Some(level) = level {
        a.summary.screen = Some(level.screen);
        a.summary.band_pixel_share = level.band_pixel_share;
        a.summary.views = level.views;
        a.summary.view_ranks = level.ranks;
        // Ground truth over the level: the judged views pooled (the camera's pass stays for
        // cascades.csv, bias.csv and the pictures).
        if ground_truth_runs(config, opts) {
            views_truth::apply(config, &mut a.summary, a.ground_truth.as_ref(), on_frames);
        }
    }
    a
}

/// Whether an analysis with `opts` runs the ground-truth pass (on `[camera]`, and on the
/// judged views of a level).
fn ground_truth_runs(config: &Config, opts: &AnalysisOptions) -> bool {
    config.truth.enabled && opts.ground_truth && config.geometry.is_some()
}

/// The level's screen metrics, pooled over its configured views, and each view's own (in full
/// or as a ranking reads them, [`ViewDetail`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LevelScreen {
    pub screen: ScreenStats,
    pub band_pixel_share: f64,
    /// Each view's own metrics in full ([`ViewDetail::Full`]); empty otherwise.
    pub views: Vec<ViewScreen>,
    /// What a ranking reads of each view ([`ViewDetail::Ranking`]); empty otherwise.
    pub ranks: Vec<ViewRank>,
}

/// The config as seen from one of its views: `[camera]` replaced by the view's camera, and no
/// views of its own (the view is its one camera; so a level's views are not copied once per
/// view, and an analysis of it measures that view alone).
pub(crate) fn config_for_view(config: &Config, view: &crate::config::ViewSettings) -> Config {
    // The views list is shared (an `Arc`): the clone copies no view.
    Config {
        camera: view.camera.clone(),
        views: Default::default(),
        warnings: Vec::new(),
        ..config.clone()
    }
}

/// What one view's screen statistics read: its pass, and the selection splits, texel sizes
/// and blend bands of the cascades the setting builds for that view's pose (frame 0), with the
/// count of the pass's receivers in each band.
struct ScreenInputs {
    vis: std::sync::Arc<Visibility>,
    splits: Vec<f64>,
    texel: Vec<f64>,
    visible: Option<(f64, f64)>,
    bands: Vec<(f64, f64)>,
    band_counts: Vec<u64>,
}

impl ScreenInputs {
    /// Each band's share of the pass's receivers: [`seams::band_shares`] from the counts.
    fn band_shares(&self) -> Vec<f64> {
        let n = self.vis.receivers.len();
        if n == 0 {
            return vec![0.0; self.bands.len()];
        }
        self.band_counts.iter().map(|&c| c as f64 / n as f64).collect()
    }
}

/// A config's screen inputs, computed as [`analyze`] computes them for `[camera]` (the same
/// rig, windows and visible range); None without scene geometry. The direct form the views'
/// inputs are checked against.
#[cfg(test)]
fn screen_inputs(config: &Config) -> Option<ScreenInputs> {
    screen_inputs_seen_by(config, &config.camera, |_| rig(config))
}

/// Each view's part of a level's pool: its pass, splits, texel sizes and visible range from
/// `inputs` (one per view, in order) and its weight from `views`.
fn pool_parts<'a>(inputs: &'a [ScreenInputs], views: &[crate::config::ViewSettings]) -> Vec<screen::PoolPart<'a>> {
    inputs
        .iter()
        .zip(views)
        .map(|(x, v)| screen::PoolPart {
            vis: &x.vis,
            splits: &x.splits,
            texel: &x.texel,
            visible: x.visible,
            steps: screen::view_weight_steps(v.weight),
        })
        .collect()
}

/// [`screen_inputs`] of the config as `view` sees it (`config_for_view`), without copying the
/// config: the set-up is built with the view's camera, and so is the rig (an engine preset's
/// reads a whole config: that one is built from the view's config).
///
/// For csm-lab's own rig, what does not read the resolution is made once per view and split
/// set on each thread ([`SplitSetInputs`]) and read by every resolution of it: the pass, the
/// visible range, the rig (moved to each resolution, [`Rig::set_resolution`]), its splits, bands
/// and band counts; only the texel sizes are made per call. The result is the direct
/// computation's bit for bit.
fn view_screen_inputs(config: &Config, view: &crate::config::ViewSettings) -> Option<ScreenInputs> {
    if config.shadow.preset.is_some() {
        return screen_inputs_seen_by(config, &view.camera, |_| rig(&config_for_view(config, view)));
    }
    let setup = config.setup_seen_by(&view.camera);
    let snap = config.shadow.snap;
    SPLIT_SETS.with(|held| {
        let mut held = held.borrow_mut();
        // The entries are of one split set (and scene: an entry keeps its scene alive): another
        // split set's setting starts them again.
        if held.entries.first().is_some_and(|h| !h.same_split_set(&setup, snap)) {
            held.entries.clear();
        }
        // So the view's entry is the one of its camera: looked for from the entry after the
        // last one read (a level's views are read in order).
        let n = held.entries.len();
        let found = (0..n)
            .map(|k| (held.next + k) % n)
            .find(|&k| held.entries[k].setup.camera == setup.camera);
        let at = match found {
            Some(at) => at,
            None => {
                let made = SplitSetInputs::new(setup.clone(), snap, &view.camera)?;
                // At most two per view of the level, then the thread starts again.
                if n >= (2 * config.views.len()).max(HELD_SPLIT_SETS) {
                    held.entries.clear();
                }
                held.entries.push(made);
                held.entries.len() - 1
            }
        };
        held.next = at + 1;
        Some(held.entries[at].inputs(setup.shadow.resolution))
    })
}

/// Split-set entries a thread keeps at least (see [`view_screen_inputs`]).
const HELD_SPLIT_SETS: usize = 64;

thread_local! {
    /// What each view's screen inputs at a split set share between its resolutions.
    static SPLIT_SETS: std::cell::RefCell<HeldSplitSet> = const {
        std::cell::RefCell::new(HeldSplitSet {
            entries: Vec::new(),
            next: 0,
        })
    };
}

/// A thread's [`SplitSetInputs`]: one split set's, one entry per view (camera) read, and
/// where the next look-up starts.
struct HeldSplitSet {
    entries: Vec<SplitSetInputs>,
    next: usize,
}

/// One view's screen inputs at one split set (settings equal but for the resolution) without
/// the texel sizes: made as [`screen_inputs_seen_by`] makes them, with csm-lab's own rig.
struct SplitSetInputs {
    /// The set-up seen by the view, its resolution 0 (the key).
    setup: csm_core::scene::Setup,
    /// `[shadow] snap` of the windows the texel sizes are read from (part of the key).
    snap: bool,
    vis: std::sync::Arc<Visibility>,
    visible: Option<(f64, f64)>,
    /// The rig and the light's pose at the view's frame 0; None when the scene needs no cascades.
    rig: Option<(Rig, LightPose)>,
    bands: Vec<(f64, f64)>,
    band_counts: Vec<u64>,
}

impl SplitSetInputs {
    fn new(
        mut setup: csm_core::scene::Setup,
        snap: bool,
        camera: &crate::config::CameraSettings,
    ) -> Option<SplitSetInputs> {
        let vis = setup.visibility()?;
        let visible = visible_depths(&setup, Some(&vis));
        let rig = Rig::for_setup_in(&setup, split_range(&setup)).map(|rig| {
            let lp0 = LightPose::new(&rig.light, &camera.pose());
            (rig, lp0)
        });
        let bands = rig.as_ref().map(|(r, _)| seams::bands(r)).unwrap_or_default();
        let band_counts = band_counts(&vis, &bands);
        setup.shadow.resolution = 0;
        Some(SplitSetInputs {
            setup,
            snap,
            vis,
            visible,
            rig,
            bands,
            band_counts,
        })
    }

    /// Whether this entry is of `setup`'s split set with `snap`, whatever its camera: equal
    /// set-ups but for the camera and the resolution, the same scene (by identity: the entry
    /// keeps it alive, so no other scene can take its address) seen at the same screen
    /// sampling. With equal cameras, the entry is `setup`'s.
    fn same_split_set(&self, setup: &csm_core::scene::Setup, snap: bool) -> bool {
        let (a, b) = (&self.setup, setup);
        let geometry = match (&a.geometry, &b.geometry) {
            (Some(x), Some(y)) => {
                std::sync::Arc::ptr_eq(&x.scene, &y.scene)
                    && x.screen_width == y.screen_width
                    && x.screen_scale == y.screen_scale
            }
            (None, None) => true,
            _ => false,
        };
        let shadow = csm_core::scene::ShadowParams {
            resolution: 0,
            ..b.shadow
        };
        self.snap == snap
            && a.shadow == shadow
            && a.light_direction == b.light_direction
            && a.bounds == b.bounds
            && geometry
            && a.motion == b.motion
            && a.light == b.light
    }

    /// The screen inputs at `resolution`: the rig moved to it, its windows' texel sizes.
    fn inputs(&mut self, resolution: u32) -> ScreenInputs {
        let (splits, texel) = match &mut self.rig {
            None => (vec![0.0, 0.0], vec![0.0]),
            Some((rig, lp0)) => {
                if rig.resolution != resolution {
                    rig.set_resolution(resolution);
                }
                let texel = (0..rig.cascade_count())
                    .map(|i| rig.window(i, lp0, self.snap).texel_size())
                    .collect();
                (rig.splits.clone(), texel)
            }
        };
        ScreenInputs {
            vis: self.vis.clone(),
            splits,
            texel,
            visible: self.visible,
            bands: self.bands.clone(),
            band_counts: self.band_counts.clone(),
        }
    }
}

/// The count of `vis`'s receivers (depth-ordered) in each band `[lo, hi)`.
fn band_counts(vis: &Visibility, bands: &[(f64, f64)]) -> Vec<u64> {
    let r = &vis.receivers;
    bands
        .iter()
        .map(|&(lo, hi)| (r.partition_point(|&(d, _)| d < hi) - r.partition_point(|&(d, _)| d < lo)) as u64)
        .collect()
}

/// The screen inputs of `config` seen from `camera`, whose rig `rig` builds from the set-up
/// seen by `camera` (made once for both).
fn screen_inputs_seen_by(
    config: &Config,
    camera: &crate::config::CameraSettings,
    rig: impl FnOnce(&csm_core::scene::Setup) -> Option<Rig>,
) -> Option<ScreenInputs> {
    let setup = config.setup_seen_by(camera);
    let vis = setup.visibility()?;
    let visible = visible_depths(&setup, Some(&vis));
    let (splits, texel, bands) = match rig(&setup) {
        None => (vec![0.0, 0.0], vec![0.0], Vec::new()),
        Some(rig) => {
            let pose0 = camera.pose();
            let lp0 = LightPose::new(&rig.light, &pose0);
            let texel = (0..rig.cascade_count())
                .map(|i| rig.window(i, &lp0, config.shadow.snap).texel_size())
                .collect();
            let bands = seams::bands(&rig);
            // The splits move out of the rig, which is dropped here.
            (rig.splits, texel, bands)
        }
    };
    // Each band's receivers (depth-ordered): the level's pooled band share and the view's own
    // read the same counts.
    let band_counts = band_counts(&vis, &bands);
    Some(ScreenInputs {
        vis,
        splits,
        texel,
        visible,
        bands,
        band_counts,
    })
}

/// The level's screen metrics when the config names views and has scene geometry: every
/// view's receiver pixels pooled, each carrying its view's weight (`csm_core::screen::pool`),
/// the cascades built for each view's own pose; the blend-band share pooled the same way,
/// band by band; each view's own metrics in full. None without configured views (`[camera]`
/// is then the one view and [`analyze`] measures it as always) or without geometry.
pub fn level_screen(config: &Config) -> Option<LevelScreen> {
    level_screen_with(config, ViewDetail::Full)
}

/// [`level_screen`] with each view's own metrics as `detail` asks: in full, or only what a
/// sweep's ranking reads (the pool then selects of each view's percentiles only the one its
/// objective is, if any).
fn level_screen_with(config: &Config, detail: ViewDetail) -> Option<LevelScreen> {
    let (geometry, inputs) = level_inputs(config)?;
    let parts = pool_parts(&inputs, &config.views);
    let asked = match detail {
        ViewDetail::Full => None,
        ViewDetail::Ranking(asked) => asked,
    };
    let pooled = screen::pool_memo(&parts, &geometry.pool_memo, asked);
    // Band k's receivers of each view, pooled band by band (a view without that band has none).
    let band_count = |x: &ScreenInputs, k: usize| -> u64 { x.band_counts.get(k).copied().unwrap_or(0) };
    let bands = inputs.iter().map(|x| x.bands.len()).max().unwrap_or(0);
    let band_pixel_share = (0..bands)
        .map(|k| {
            let counts: Vec<(u64, u64, u64)> = inputs
                .iter()
                .zip(&parts)
                .map(|(x, p)| (band_count(x, k), x.vis.receivers.len() as u64, p.steps))
                .collect();
            screen::pooled_share(&counts)
        })
        .sum();
    let (views, ranks) = match detail {
        ViewDetail::Full => (full_views(config, &inputs), Vec::new()),
        ViewDetail::Ranking(_) => {
            let ranks = inputs
                .iter()
                .zip(&pooled.views)
                .map(|(x, r)| ViewRank {
                    objective: r.asked.map(|a| a.1),
                    worst: r.max,
                    seen: !x.vis.receivers.is_empty(),
                })
                .collect();
            (Vec::new(), ranks)
        }
    };
    LAST_LEVEL.with(|l| *l.borrow_mut() = Some(inputs));
    Some(LevelScreen {
        screen: pooled.level,
        band_pixel_share,
        views,
        ranks,
    })
}

/// Each view's own screen metrics in full from its inputs (one per view, in order): its
/// statistics alone ([`screen::stats`], what [`screen::pool`] gives each view) and its blend-band
/// share.
fn full_views(config: &Config, inputs: &[ScreenInputs]) -> Vec<ViewScreen> {
    config
        .views
        .iter()
        .zip(inputs)
        .map(|(v, x)| ViewScreen {
            name: v.name.clone(),
            weight: v.weight,
            screen: screen::stats(&x.vis, &x.splits, &x.texel, x.visible),
            band_pixel_share: x.band_shares().iter().sum(),
            judged: false,
            truth: None,
        })
        .collect()
}

/// The full pool of `config`'s views at its setting ([`screen::pool`]: the level's statistics
/// and each view's in full), the direct form the views' statistics are checked against.
#[cfg(test)]
pub(crate) fn full_pool(config: &Config) -> Option<screen::Pooled> {
    let inputs = views_inputs(config)?;
    Some(screen::pool(&pool_parts(&inputs, &config.views)))
}

/// Each configured view's screen inputs at `config`'s setting ([`view_screen_inputs`]); None
/// when a view has none (no geometry).
fn views_inputs(config: &Config) -> Option<Vec<ScreenInputs>> {
    config.views.iter().map(|v| view_screen_inputs(config, v)).collect()
}

/// A level's scene geometry and each view's screen inputs ([`views_inputs`]); None without
/// configured views or geometry. The scene keeps every view's pass (one per view, shared by
/// every setting of a sweep: none may be evicted).
fn level_inputs(config: &Config) -> Option<(&crate::config::GeometrySettings, Vec<ScreenInputs>)> {
    if config.views.is_empty() {
        return None;
    }
    let geometry = config.geometry.as_ref()?;
    geometry.scene.keep_at_least(2 * config.views.len() + 8);
    // Each view's inputs are the config's seen by the view's camera (no config is copied).
    Some((geometry, views_inputs(config)?))
}

/// Every view's own screen metrics in full at `config`'s setting (what [`analyze`] with
/// [`ViewDetail::Full`] puts in [`Summary::views`]), without the level's pool: for the one row
/// of a sweep that shows them, whose rows kept only what the ranking reads. None without
/// configured views or geometry.
pub(crate) fn level_views(config: &Config) -> Option<Vec<ViewScreen>> {
    let (_, inputs) = level_inputs(config)?;
    Some(full_views(config, &inputs))
}

thread_local! {
    /// The views' screen inputs of the last level this thread pooled ([`level_screen`]), for
    /// [`split_set_done`].
    static LAST_LEVEL: std::cell::RefCell<Option<Vec<ScreenInputs>>> = const { std::cell::RefCell::new(None) };
}

/// Tells the level's pools that the sweep has evaluated every resolution of `config`'s split
/// set (its settings that differ in resolution alone): what they kept for the other
/// resolutions (each percentile's window, each view's served parts) is dropped
/// ([`screen::split_set_done`]). Memory only; nothing without views or geometry.
pub(crate) fn split_set_done(config: &Config) {
    let Some(geometry) = config.geometry.as_ref().filter(|_| !config.views.is_empty()) else {
        return;
    };
    // The inputs this thread's last level read (the split set's last resolution, evaluated
    // just before on this thread), else made again. Should a pool of another split set have
    // run on this thread in between (rayon runs another job while one waits), its windows
    // go instead: memory and time only, never a result.
    let held = LAST_LEVEL.with(|l| l.borrow_mut().take());
    let inputs = match held {
        Some(inputs) if inputs.len() == config.views.len() => inputs,
        _ => match views_inputs(config) {
            Some(inputs) => inputs,
            None => return,
        },
    };
    let parts = pool_parts(&inputs, &config.views);
    screen::split_set_done(&parts, &geometry.pool_memo);
}

/// One sampled pixel of a view's picture: None (nothing hit), or (lit-facing, the aliasing `m`
/// where a cascade serves it).
pub(crate) type ViewPixel = Option<(bool, Option<f64>)>;

/// What each sampled pixel of configured view `k` shows at this setting, for pictures: None
/// (nothing hit), or (lit-facing, the aliasing `m` where a cascade serves it); with the
/// sampled grid's columns and rows. None without geometry or such a view.
pub(crate) fn view_pixels(config: &Config, k: usize) -> Option<(u32, u32, Vec<ViewPixel>)> {
    let x = view_screen_inputs(config, config.views.get(k)?)?;
    let m = x.texel.len();
    let px = x
        .vis
        .samples
        .iter()
        .map(|s| {
            s.map(|s| {
                let served = s.lit && s.depth >= x.splits[0] && s.depth <= x.splits[m] && x.texel[0] > 0.0;
                (
                    s.lit,
                    served.then(|| x.texel[metrics::cascade_at(&x.splits, s.depth)] * s.factor),
                )
            })
        })
        .collect();
    Some((x.vis.cols, x.vis.rows, px))
}

/// Makes each configured view's pass (or, with `rays_only`, its cast rays: a sun sweep shades
/// them per angle) before a parallel batch reads them, so no two rows cast one view's rays.
pub(crate) fn warm_views(config: &Config, rays_only: bool) {
    let Some(geometry) = config.geometry.as_ref() else {
        return;
    };
    geometry.scene.keep_at_least(2 * config.views.len() + 8);
    for v in config.views.iter() {
        let setup = config.setup_seen_by(&v.camera);
        if rays_only {
            let _ = setup.visibility_hits();
        } else {
            let _ = setup.visibility();
        }
    }
}

/// How much of a setting [`analyze_camera`] measures.
#[derive(Clone, Copy)]
enum Detail<'a> {
    /// Everything `opts` asks for: what every output reads.
    Full,
    /// What the free-split search's cost reads ([`search`]): no render-cost counts (the
    /// summary's `cost` is left at its default), no preset report, and of the screen statistics
    /// only `screen` (None: no screen statistics at all). Every other summary field is
    /// computed as for [`Detail::Full`]. `shared`: what every point of the search's group has
    /// in common, computed once for the group ([`search::Shared`]; the same values the point's
    /// own analysis computes).
    Search {
        screen: Option<screen::Statistic>,
        shared: Option<&'a search::Shared>,
    },
}

/// [`analyze_with_progress`] for `[camera]` alone: every metric of the camera and its path.
/// `camera_screen`: measure `[camera]`'s screen statistics (a level of views replaces them
/// with its pooled ones, so only the cascades' pixel shares are counted then).
fn analyze_camera(
    config: &Config,
    opts: &AnalysisOptions,
    on_frames: &(dyn Fn(u64) + Sync),
    camera_screen: bool,
    detail: Detail<'_>,
) -> Analysis {
    let setup = config.setup();
    let shared = match detail {
        Detail::Search { shared, .. } => shared,
        Detail::Full => None,
    };
    let (rig, range) = match shared.and_then(|s| s.range(config)) {
        Some(range) => (Rig::for_setup_in(&setup, range), range),
        None => {
            let rig = rig(config);
            let range = analysed_range(config, rig.as_ref());
            (rig, range)
        }
    };
    let memory = match &rig {
        Some(r) => memory_bytes(r.cascade_count(), r.resolution),
        None => memory_bytes(config.shadow.cascades, config.shadow.resolution),
    };
    let (visibility, visible) = match shared {
        Some(s) => s.visibility(),
        None => {
            let visibility = setup.visibility();
            let visible = visible_depths(&setup, visibility.as_deref());
            (visibility, visible)
        }
    };
    let Some(rig) = rig else {
        return no_cascades(config, opts, range, memory, visibility.as_deref(), visible);
    };
    let (z_lo, z_hi) = range.bounds().expect("a rig implies a range");
    let frame0 = Frame0::of(config, &rig);
    let k = rig.lens.pixels_per_unit_slope(config.screen.height);
    let aggregates = metrics::aggregates(&rig.splits, &frame0.texel, k);
    let density = if opts.density_profile {
        metrics::density_profile(
            &rig.splits,
            &frame0.texel,
            &rig.lens,
            config.screen.height,
            config.analysis.density_samples,
        )
    } else {
        Vec::new()
    };
    let walks = walk_every_path(
        config,
        opts,
        &setup,
        &rig,
        &frame0.pose,
        visibility.as_deref(),
        on_frames,
    );
    let truth = if config.truth.enabled && opts.ground_truth {
        ground_truth::run(config, &rig, opts.texel_counts, on_frames)
    } else {
        None
    };
    let vis = visibility.as_deref();
    // Light depth ranges: always for a preset (its report needs them), else when asked for.
    let full = matches!(detail, Detail::Full);
    let depths = (opts.light_depth || (full && config.shadow.preset.is_some())).then(|| {
        (frame0.windows.iter().enumerate())
            .map(|(i, w)| rig.light_depth(i, &frame0.light, w, &config.scene))
            .collect::<Vec<_>>()
    });
    let bands = seams::bands(&rig);
    let cache = cache_figures(
        walks.totals.stale.as_ref(),
        truth
            .as_ref()
            .map(|t| if config.shadow.snap { &t.snapped } else { &t.unsnapped }),
    );
    let (cascade_costs, cost) = if full {
        let cost_means = (opts.cost_means && cost::means_measurable(config, Some(&rig)))
            .then(|| cost::path_means(config, &rig, &cadence(config, &rig)));
        cost::measure(config, &rig, &frame0.light, &frame0.windows, vis, cost_means)
    } else {
        (
            vec![cost::CascadeCost::default(); rig.cascade_count()],
            cost::CostSummary::default(),
        )
    };
    let parts = CameraParts {
        config,
        rig: &rig,
        aggregates: &aggregates,
        walks: &walks,
        screen: match detail {
            Detail::Full => vis.map(|v| {
                if camera_screen {
                    screen::stats(v, &rig.splits, &frame0.texel, visible)
                } else {
                    screen::cascade_shares_only(v, &rig.splits, &frame0.texel)
                }
            }),
            Detail::Search { screen: which, .. } => vis
                .zip(which)
                .map(|(v, which)| search::one_statistic(v, &rig.splits, &frame0.texel, which)),
        },
        utilization: match (vis, opts.light_depth) {
            (Some(v), true) => texel_utilization(v, &rig, &frame0.light, &frame0.windows),
            _ => vec![0.0; rig.cascade_count()],
        },
        overlap: seams::overlap_area(&rig, &frame0.light, &frame0.windows, &bands),
        band_pixels: vis.map_or_else(|| vec![0.0; bands.len()], |v| seams::band_shares(v, &bands)),
        bands,
        light_depths: depths.as_deref().filter(|_| opts.light_depth),
        truth: truth.as_ref(),
        cache: cache.as_ref(),
        cascade_costs: &cascade_costs,
    };
    let cascades = (frame0.windows.iter().enumerate())
        .map(|(i, w)| parts.cascade(i, w))
        .collect();
    let summary = parts.summary(z_lo, z_hi, memory, cost);
    let preset = (config.shadow.preset.as_ref())
        .filter(|_| full)
        .map(|p| crate::presets::report(p, Some(&rig), depths.unwrap_or_default()));
    let Walks {
        snapped,
        unsnapped,
        extra,
        totals,
        ..
    } = walks;
    Analysis {
        config: config.clone(),
        range,
        preset,
        cascades,
        density,
        ground_truth: truth,
        outcome: Outcome::Cascades(Box::new(Measured {
            rig,
            aggregates,
            snapped,
            unsnapped,
            lookup_error: totals.lookup_error,
            extra,
        })),
        summary,
    }
}

/// The view depths an analysis reads its cascades over. A preset has its own range (no scene
/// clipping).
fn analysed_range(config: &Config, rig: Option<&Rig>) -> DepthRange {
    match (&config.shadow.preset, rig) {
        (None, _) => split_range(&config.setup()),
        (Some(_), Some(r)) => DepthRange::Range {
            z_lo: r.splits[0],
            z_hi: r.splits[r.cascade_count()],
        },
        (Some(_), None) => DepthRange::Empty,
    }
}

/// The visible depths within the bounds' range (the same range with or without fitting the
/// splits to them).
fn visible_depths(setup: &csm_core::scene::Setup, vis: Option<&Visibility>) -> Option<(f64, f64)> {
    let vis = vis?;
    let (lo, hi) = bounds_range(setup).bounds()?;
    screen::visible_range(vis, lo, hi)
}

/// The configured camera's first frame: its pose, the light's pose, the cascades' windows and
/// their texel sizes.
struct Frame0 {
    pose: CameraPose,
    light: LightPose,
    windows: Vec<csm_core::fitting::Window>,
    texel: Vec<f64>,
}

impl Frame0 {
    fn of(config: &Config, rig: &Rig) -> Frame0 {
        let pose = config.camera.pose();
        let light = LightPose::new(&rig.light, &pose);
        let windows: Vec<_> = (0..rig.cascade_count())
            .map(|i| rig.window(i, &light, config.shadow.snap))
            .collect();
        let texel = windows.iter().map(|w| w.texel_size()).collect();
        Frame0 {
            pose,
            light,
            windows,
            texel,
        }
    }
}

/// Every camera path walked in both snap modes: the configured path, the extra ones, and
/// their totals.
struct Walks {
    snapped: PathResult,
    unsnapped: PathResult,
    extra: Vec<ExtraPathResult>,
    /// The most crossings of any path.
    seam_crossings: Option<f64>,
    totals: PathTotals,
}

/// Walks the configured path and every extra one (`walk_path`), and totals them.
fn walk_every_path(
    config: &Config,
    opts: &AnalysisOptions,
    setup: &csm_core::scene::Setup,
    rig: &Rig,
    pose0: &CameraPose,
    vis: Option<&Visibility>,
    on_frames: &(dyn Fn(u64) + Sync),
) -> Walks {
    let sopts = ShimmerOptions {
        cell_flips: opts.cell_flips,
        probe_drift: false,
        frame_rows: opts.frame_rows,
    };
    // Probes cost more than the rest of a sphere-fit analysis; place them only when used
    // (the f32 emulation always looks probes up: its drift and lookup error are per probe).
    let probes = probes(config, rig, pose0, sopts);
    let seam_points = seam_points(config, opts.seams, rig, pose0, vis);
    let every = cadence(config, rig);
    let walker = Walker {
        config,
        setup,
        rig,
        cadence: &every,
        probes: &probes,
        seam_points: &seam_points,
        sopts,
        seams: opts.seams,
        on_frames,
    };
    let first = walk_path(&walker, &setup.motion);
    let mut seam_crossings = first.crossings;
    let extra: Vec<ExtraPathResult> = config
        .extra_motions()
        .into_iter()
        .map(|(name, motion)| {
            let w = walk_path(&walker, &motion);
            if let (Some(c), Some(x)) = (seam_crossings.as_mut(), w.crossings) {
                *c = c.max(x);
            }
            ExtraPathResult {
                name,
                snapped: w.snapped,
                unsnapped: w.unsnapped,
                lookup_error: w.lookup_error,
            }
        })
        .collect();
    let totals = path_totals(
        config.shadow.snap,
        &first.snapped,
        &first.unsnapped,
        first.lookup_error,
        &extra,
    );
    Walks {
        snapped: first.snapped,
        unsnapped: first.unsnapped,
        extra,
        seam_crossings,
        totals,
    }
}

/// What one camera's analysis measured, laid out per cascade ([`CascadeReport`]) and in all
/// ([`Summary`]).
struct CameraParts<'a> {
    config: &'a Config,
    rig: &'a Rig,
    aggregates: &'a Aggregates,
    walks: &'a Walks,
    screen: Option<ScreenStats>,
    utilization: Vec<f64>,
    bands: Vec<(f64, f64)>,
    overlap: Vec<f64>,
    band_pixels: Vec<f64>,
    /// Each cascade's light depth range, when asked for.
    light_depths: Option<&'a [csm_core::cascades::LightDepth]>,
    truth: Option<&'a ground_truth::GroundTruth>,
    cache: Option<&'a (CacheSummary, Vec<CascadeCache>)>,
    cascade_costs: &'a [cost::CascadeCost],
}

impl CameraParts<'_> {
    /// Every path's results in both snap modes, the configured one first.
    fn paths(&self) -> impl Iterator<Item = (&PathResult, &PathResult)> {
        let w = self.walks;
        std::iter::once((&w.snapped, &w.unsnapped)).chain(w.extra.iter().map(|e| (&e.snapped, &e.unsnapped)))
    }

    fn cascade(&self, i: usize, w: &csm_core::fitting::Window) -> CascadeReport {
        let (rig, a, t) = (self.rig, self.aggregates, &self.walks.totals);
        let at_split = |v: &[f64]| v.get(i).copied().unwrap_or(0.0);
        let (light_near, light_far) = self.light_depths.map_or((0.0, 0.0), |d| (d[i].near, d[i].far));
        let (lookup_error_max, lookup_error_rms) =
            (t.lookup_error.as_ref()).map_or((0.0, 0.0), |l| (l.cascade_max[i], l.cascade_rms[i]));
        CascadeReport {
            cascade: i,
            near: rig.slices[i].near,
            far: rig.slices[i].far,
            radius: rig.slices[i].sphere.radius,
            width: w.width(),
            height: w.height(),
            texel_size: w.texel_size(),
            centre_x: w.centre().x,
            centre_y: w.centre().y,
            centre_x_texels: w.origin_texels.x + 0.5 * w.resolution as f64,
            centre_y_texels: w.origin_texels.y + 0.5 * w.resolution as f64,
            light_near,
            light_far,
            coverage_violations: t.coverage.violations[i],
            coverage_worst_texels: t.coverage.worst_texels[i],
            min_slack_texels: t.coverage.min_slack_texels[i],
            max_aliasing: a.cascade_max_aliasing[i],
            min_aliasing: a.cascade_min_aliasing[i],
            lookup_error_max,
            lookup_error_rms,
            split_jump: at_split(&a.split_jumps),
            band_near: self.bands.get(i).map_or(rig.slices[i].far, |b| b.0),
            band_far: self.bands.get(i).map_or(rig.slices[i].far, |b| b.1),
            overlap_area_fraction: at_split(&self.overlap),
            screen: self.screen.as_ref().map(|st| CascadeScreen {
                pixels: st.cascade_pixels[i],
                band_pixels: at_split(&self.band_pixels),
                texel_utilization: self.utilization[i],
            }),
            light: CascadeLight::of(self.config.shadow.snap, i, self.paths()),
            truth: self.truth.map(|t| t.cascades[i].clone()),
            cache: self.cache.map(|c| c.1[i]),
            cost: self.cascade_costs[i],
        }
    }

    fn summary(self, z_lo: f64, z_hi: f64, memory_bytes: u64, cost: cost::CostSummary) -> Summary {
        let (a, t) = (self.aggregates, &self.walks.totals);
        Summary {
            cascades_needed: true,
            z_lo,
            z_hi,
            max_aliasing: a.max_aliasing,
            mean_aliasing: a.mean_aliasing,
            mean_log_aliasing: a.mean_log_aliasing,
            undersampled_fraction: a.undersampled_fraction,
            shimmer: if self.config.shadow.snap {
                t.worst_snapped
            } else {
                t.worst_unsnapped
            },
            shimmer_snapped: t.worst_snapped,
            shimmer_unsnapped: t.worst_unsnapped,
            size_jitter: t.jitter,
            coverage_violations: t.coverage.total(),
            memory_bytes,
            lookup_error_max: t.lookup_error.as_ref().map_or(0.0, |l| l.max),
            lookup_error_rms: t.lookup_error.as_ref().map_or(0.0, |l| l.rms),
            overlap_area_fraction: self.overlap.iter().sum(),
            band_pixel_share: self.band_pixels.iter().sum(),
            seam_crossings: self.walks.seam_crossings,
            light: LightSummary::of(self.config.shadow.snap, self.paths()),
            truth: self.truth.map(|t| t.summary),
            views: Vec::new(),
            view_ranks: Vec::new(),
            cache: self.cache.map(|c| c.0),
            cost,
            screen: self.screen,
        }
    }
}

/// The analysis of a setting that needs no cascades: nothing measured but the memory and,
/// with geometry, the screen.
fn no_cascades(
    config: &Config,
    opts: &AnalysisOptions,
    range: DepthRange,
    memory: u64,
    visibility: Option<&Visibility>,
    visible: Option<(f64, f64)>,
) -> Analysis {
    Analysis {
        config: config.clone(),
        range,
        cascades: Vec::new(),
        density: Vec::new(),
        outcome: Outcome::NoCascades,
        summary: Summary {
            seam_crossings: opts.seams.then_some(0.0),
            screen: visibility
                .as_ref()
                .map(|vis| screen::stats(vis, &[0.0, 0.0], &[0.0], visible)),
            light: config.motion.light.moves().then(LightSummary::default),
            cost: cost::nothing(config, opts.cost_means),
            ..Summary::nothing_needed(memory)
        },
        ground_truth: None,
        preset: config
            .shadow
            .preset
            .as_ref()
            .map(|p| crate::presets::report(p, None, Vec::new())),
    }
}

/// The probes the walk follows: placed only when used (they cost more than the rest of a
/// sphere-fit analysis; the f32 emulation always looks probes up: its drift and lookup error
/// are per probe).
fn probes(config: &Config, rig: &Rig, pose0: &CameraPose, sopts: ShimmerOptions) -> Vec<Vec<glam::DVec3>> {
    if config.shadow.precision == Precision::F32 || config.motion.light.moves() || rig_path::needs_probes(rig, sopts) {
        rig_path::probes(rig, pose0, &config.scene, config.analysis.probes)
    } else {
        Vec::new()
    }
}

/// The receivers `seam_crossings` follows: frame 0's lit-facing pixels with geometry, else the
/// first probes of each cascade; none when seams are not measured.
fn seam_points(
    config: &Config,
    seams: bool,
    rig: &Rig,
    pose0: &CameraPose,
    visibility: Option<&Visibility>,
) -> Vec<glam::DVec3> {
    if !seams {
        Vec::new()
    } else if let Some(vis) = visibility {
        let all = seams::receiver_points(vis, &rig.splits);
        // Every k-th receiver, at most SEAM_RECEIVERS of them (a fixed, deterministic subset).
        let k = all.len().div_ceil(SEAM_RECEIVERS).max(1);
        all.into_iter().step_by(k).collect()
    } else {
        rig_path::probes(rig, pose0, &config.scene, SEAM_PROBES.min(config.analysis.probes))
            .into_iter()
            .flatten()
            .collect()
    }
}

/// What every camera path's walk reads.
struct Walker<'a> {
    config: &'a Config,
    setup: &'a csm_core::scene::Setup,
    rig: &'a Rig,
    /// Each cascade's update cadence (empty: every frame).
    cadence: &'a [usize],
    probes: &'a [Vec<glam::DVec3>],
    seam_points: &'a [glam::DVec3],
    sopts: ShimmerOptions,
    seams: bool,
    on_frames: &'a (dyn Fn(u64) + Sync),
}

/// One camera path walked in both snap modes.
struct PathWalk {
    snapped: PathResult,
    unsnapped: PathResult,
    lookup_error: Option<LookupError>,
    crossings: Option<f64>,
}

/// Walks one camera path in both snap modes. With precision = "f32" every path metric
/// measures the emulated binary32 pipeline. The poses are generated as the walk reads them (a
/// long path is never held), and the two snap modes walk on their own threads: each mode's
/// totals are the same, bit for bit, as in one walk of both (`along_path_both`).
fn walk_path(w: &Walker<'_>, motion: &csm_core::scene::Motion) -> PathWalk {
    let generated =
        || csm_core::motion::poses(&w.setup.camera, motion).map(|p| p.expect("validated when the config was loaded"));
    // A path of up to HELD_POSES frames is generated once and read by both walks (a
    // sweep's paths are short: generating each pose twice cost it a sixth of its time);
    // a longer one is generated as each walk reads it, so memory stays flat.
    // The held poses are the same for every setting of a sweep (its axes change neither the
    // camera nor the path): each thread keeps the last path it generated and reuses it while
    // the camera and the path are equal.
    let frames = generated().len();
    let held: std::sync::Arc<[CameraPose]> = if frames <= HELD_POSES {
        thread_held_poses(&w.setup.camera, motion, generated)
    } else {
        std::sync::Arc::new([])
    };
    let batch = rayon::current_thread_index().is_some();
    if batch && !w.seams && frames <= HELD_POSES && w.cadence.is_empty() && w.config.shadow.precision == Precision::F64
    {
        // A batch row (a sweep's) without a seam count: the walk reads the held poses as they
        // are, and the progress is told the frames it would have been told pose by pose.
        let light = light_track(w.config, 0);
        let (snapped, unsnapped) = rig_path::along_path_both_lit(w.rig, held.iter(), w.probes, light, w.sopts);
        for _ in 0..frames / PROGRESS_FRAMES {
            (w.on_frames)(PROGRESS_FRAMES as u64);
        }
        (w.on_frames)(2 * (frames % PROGRESS_FRAMES) as u64);
        return PathWalk {
            snapped,
            unsnapped,
            lookup_error: None,
            crossings: None,
        };
    }
    let poses = || {
        let streamed = (frames > HELD_POSES).then(generated).into_iter().flatten();
        let all = held.iter().copied().chain(streamed).enumerate().map(|(t, p)| {
            if (t + 1) % PROGRESS_FRAMES == 0 {
                (w.on_frames)(PROGRESS_FRAMES as u64);
            }
            p
        });
        ExactLen(all, frames)
    };
    let remainder = (frames % PROGRESS_FRAMES) as u64;
    // Seam crossings read the same poses as the snapped walk, on its thread: the counter
    // follows each pose as the walk reads it (incremental: only the receivers whose depth
    // could have reached a split since they were last computed are computed again).
    let mut counter = w.seams.then(|| seams::SeamCounter::new(&w.rig.splits, w.seam_points));
    let mut no_counter = None;
    // Inside a parallel batch (a sweep, a comparison) every core is busy already: one walk
    // of both snap modes computes the values they share once per frame. Alone, the two
    // modes walk on two threads. Either way the totals are the same, bit for bit.
    let walked = match w.config.shadow.precision {
        Precision::F64 if !w.cadence.is_empty() => {
            // Cached cascades (refused at load with a moving light or a basis that follows
            // the camera).
            let cadence = Cadence {
                every: w.cadence,
                first_frame: 0,
            };
            let one = |poses, snapped| {
                let [r] = rig_path::along_path_cached(w.rig, poses, w.probes, cadence, [snapped], w.sopts);
                r
            };
            let (s, u) = if batch {
                let [s, u] = rig_path::along_path_cached(
                    w.rig,
                    counted(poses(), &mut counter),
                    w.probes,
                    cadence,
                    [true, false],
                    w.sopts,
                );
                (s, u)
            } else {
                rayon::join(
                    || one(counted(poses(), &mut counter), true),
                    || one(counted(poses(), &mut no_counter), false),
                )
            };
            (s, u, None)
        }
        Precision::F64 => {
            let light = light_track(w.config, 0);
            let one = |poses, snapped| rig_path::along_path_lit(w.rig, poses, w.probes, light, snapped, w.sopts);
            let (s, u) = if batch {
                rig_path::along_path_both_lit(w.rig, counted(poses(), &mut counter), w.probes, light, w.sopts)
            } else {
                rayon::join(
                    || one(counted(poses(), &mut counter), true),
                    || one(counted(poses(), &mut no_counter), false),
                )
            };
            (s, u, None)
        }
        Precision::F32 => {
            let space = w.config.shadow.snap_space;
            let one = |poses, snapped| precision::along_path(w.rig, poses, w.probes, space, snapped, w.sopts);
            let (s, u) = if batch {
                precision::along_path_both(w.rig, counted(poses(), &mut counter), w.probes, space, w.sopts)
            } else {
                rayon::join(
                    || one(counted(poses(), &mut counter), true),
                    || one(counted(poses(), &mut no_counter), false),
                )
            };
            let lookup = if w.config.shadow.snap { s.lookup } else { u.lookup };
            (s.path, u.path, Some(lookup))
        }
    };
    (w.on_frames)(2 * remainder);
    let crossings = counter.map(|c| c.rate());
    PathWalk {
        snapped: walked.0,
        unsnapped: walked.1,
        lookup_error: walked.2,
        crossings,
    }
}

/// What the poses of a generated path depend on, bit for bit: the camera's position, target
/// and up, the path's kind, step and frame count (None for a path file: its rows are read).
type PathKey = [u64; 12];

fn path_key(camera: &csm_core::scene::Camera, motion: &csm_core::scene::Motion) -> Option<PathKey> {
    use csm_core::scene::MotionPath;
    let kind = match motion.path {
        MotionPath::Strafe => 0,
        MotionPath::Dolly => 1,
        MotionPath::Yaw => 2,
        MotionPath::Pitch => 3,
        MotionPath::Orbit => 4,
        MotionPath::Still => 5,
        MotionPath::File { .. } => return None,
    };
    let [p, t, u] = [camera.position, camera.target, camera.up].map(|v| v.to_array().map(f64::to_bits));
    Some([
        p[0],
        p[1],
        p[2],
        t[0],
        t[1],
        t[2],
        u[0],
        u[1],
        u[2],
        motion.step.to_bits(),
        motion.frames as u64,
        kind,
    ])
}

thread_local! {
    /// The last held path this thread generated, with its [`PathKey`].
    static HELD: std::cell::RefCell<Option<(PathKey, std::sync::Arc<[CameraPose]>)>> =
        const { std::cell::RefCell::new(None) };
}

/// The poses `generated` yields for `camera` along `motion`: the thread's last held path when
/// it has the same [`PathKey`] (the same poses), else generated (and kept, but a path file's).
fn thread_held_poses<I: Iterator<Item = CameraPose>>(
    camera: &csm_core::scene::Camera,
    motion: &csm_core::scene::Motion,
    generated: impl Fn() -> I,
) -> std::sync::Arc<[CameraPose]> {
    let Some(key) = path_key(camera, motion) else {
        return generated().collect();
    };
    HELD.with_borrow_mut(|held| {
        if let Some((k, poses)) = held.as_ref() {
            if *k == key {
                return poses.clone();
            }
        }
        let poses: std::sync::Arc<[CameraPose]> = generated().collect();
        *held = Some((key, poses.clone()));
        poses
    })
}

/// What the split range of a set-up fitted to its bounds (not to visible geometry) depends
/// on, bit for bit: the camera's position, target and up, its field of view, aspect and near
/// plane, the shadow's far end (`min(camera far, max_distance)`), the scene bounds and
/// whether the range is fitted to them ([`depth_range::receiver_range`]'s inputs).
type RangeKey = [u64; 20];

fn range_key(setup: &csm_core::scene::Setup) -> RangeKey {
    let c = &setup.camera;
    let b = &setup.bounds;
    let v = [c.position, c.target, c.up, b.min, b.max].map(|v| v.to_array().map(f64::to_bits));
    let mut key = [0u64; 20];
    for (k, x) in key.iter_mut().zip(v.iter().flatten()) {
        *k = *x;
    }
    key[15] = c.fov_y.to_bits();
    key[16] = c.aspect.to_bits();
    key[17] = c.near.to_bits();
    key[18] = setup.shadow_far().to_bits();
    key[19] = u64::from(setup.shadow.fit_depth_to_scene);
    key
}

/// Split ranges a thread keeps at most (then it starts again): one per camera a sweep reads,
/// `[camera]` and each view of a level (160 bytes of key each).
const HELD_RANGES: usize = 4096;

// The split ranges are kept in a `WordMap` (a multiply and a rotate per word of the key, where
// the standard SipHash costs more than the look-up it serves). A cache's hash: a poor one costs
// time, never a wrong range (the map compares whole keys).
use csm_core::hash::WordMap;

thread_local! {
    /// The split ranges this thread computed, by their [`RangeKey`].
    static RANGES: std::cell::RefCell<WordMap<RangeKey, DepthRange>> = std::cell::RefCell::new(WordMap::default());
}

/// [`depth_range::for_setup`] of `setup`: the thread's range of the same [`RangeKey`] (the
/// same inputs, so the same range) when it holds one, else computed (and kept). A sweep's
/// settings share the camera, the shadow distance and the scene, so each thread computes the
/// range once per camera (`[camera]` and each view of a level) instead of three times per
/// setting and view. A range fitted to visible geometry reads the visibility pass and is always
/// computed.
pub(crate) fn split_range(setup: &csm_core::scene::Setup) -> DepthRange {
    if setup.shadow.fit_depth_to_visible {
        return depth_range::for_setup(setup);
    }
    let key = range_key(setup);
    if let Some(&range) = RANGES.with(|held| held.borrow().get(&key).copied()).as_ref() {
        return range;
    }
    let range = depth_range::for_setup(setup);
    RANGES.with(|held| {
        let mut held = held.borrow_mut();
        if held.len() >= HELD_RANGES {
            held.clear();
        }
        held.insert(key, range);
    });
    range
}

/// The split range of `setup` fitted to its bounds, whether or not its splits are fitted to
/// visible geometry: the range the visible depths are clipped to ([`split_range`] of the
/// bounds-only set-up, held the same way).
fn bounds_range(setup: &csm_core::scene::Setup) -> DepthRange {
    if !setup.shadow.fit_depth_to_visible {
        return split_range(setup);
    }
    let mut bounds_only = setup.clone();
    bounds_only.shadow.fit_depth_to_visible = false;
    split_range(&bounds_only)
}

/// Coverage, shimmer, jitter and lookup error over every camera path.
struct PathTotals {
    coverage: csm_core::shimmer::Coverage,
    lookup_error: Option<LookupError>,
    worst_snapped: f64,
    worst_unsnapped: f64,
    jitter: f64,
    /// Cached cascades, configured snapping, over every path.
    stale: Option<StaleStats>,
}

/// Coverage and S7 over every path: violations add up, the worst and the slack take the
/// extreme, S7 the largest of the paths.
fn path_totals(
    snap: bool,
    snapped: &PathResult,
    unsnapped: &PathResult,
    lookup_error: Option<LookupError>,
    extra: &[ExtraPathResult],
) -> PathTotals {
    let mut coverage = if snap { snapped } else { unsnapped }.coverage.clone();
    let mut stale = if snap { snapped } else { unsnapped }.stale.clone();
    let mut lookup_error = lookup_error;
    let (mut worst_snapped, mut worst_unsnapped, mut jitter) = (
        snapped.stats.rms,
        unsnapped.stats.rms,
        snapped.stats.size_jitter.max(unsnapped.stats.size_jitter),
    );
    for e in extra {
        let c = if snap { &e.snapped } else { &e.unsnapped };
        coverage.merge(&c.coverage);
        if let (Some(s), Some(x)) = (stale.as_mut(), c.stale.as_ref()) {
            s.merge(x);
        }
        worst_snapped = worst_snapped.max(e.snapped.stats.rms);
        worst_unsnapped = worst_unsnapped.max(e.unsnapped.stats.rms);
        jitter = jitter
            .max(e.snapped.stats.size_jitter)
            .max(e.unsnapped.stats.size_jitter);
        if let (Some(l), Some(x)) = (lookup_error.as_mut(), e.lookup_error.as_ref()) {
            l.max = l.max.max(x.max);
            l.rms = l.rms.max(x.rms);
            for i in 0..l.cascade_max.len() {
                l.cascade_max[i] = l.cascade_max[i].max(x.cascade_max[i]);
                l.cascade_rms[i] = l.cascade_rms[i].max(x.cascade_rms[i]);
            }
        }
    }
    PathTotals {
        coverage,
        lookup_error,
        worst_snapped,
        worst_unsnapped,
        jitter,
        stale,
    }
}

/// The cached-cascade figures of an analysis from the walks' [`StaleStats`] and, when the
/// ground-truth pass ran, its flicker in the configured snap mode: per cascade and in all.
fn cache_figures(
    stale: Option<&StaleStats>,
    flicker: Option<&csm_core::truth::Flicker>,
) -> Option<(CacheSummary, Vec<CascadeCache>)> {
    let s = stale?;
    let m = s.every.len();
    let frames = s.frames.max(1) as f64;
    let cascades: Vec<CascadeCache> = (0..m)
        .map(|i| CascadeCache {
            update_every: s.every[i] as u64,
            update_rate: 1.0 / s.every[i] as f64,
            figures: StaleFigures {
                stale_coverage_violations: s.violations[i],
                stale_coverage_fraction: s.violations[i] as f64 / frames,
                stale_margin: s.margin_texels[i],
                stale_margin_world: s.margin_world[i],
                update_drift: s.update_drift_rms[i],
                update_flicker: flicker.and_then(|f| {
                    let n = f.update_steps.get(i).copied().unwrap_or(0);
                    (n > 0).then(|| f.update_flips[i] as f64 / n as f64)
                }),
            },
        })
        .collect();
    let worst = |f: fn(&StaleFigures) -> f64| cascades.iter().map(|c| f(&c.figures)).fold(0.0, f64::max);
    let summary = CacheSummary {
        renders_per_frame: cascades.iter().map(|c| c.update_rate).sum(),
        figures: StaleFigures {
            stale_coverage_violations: s.violations.iter().sum(),
            stale_coverage_fraction: worst(|c| c.stale_coverage_fraction),
            stale_margin: worst(|c| c.stale_margin),
            stale_margin_world: worst(|c| c.stale_margin_world),
            update_drift: worst(|c| c.update_drift),
            update_flicker: flicker.and_then(|f| {
                let n: u64 = f.update_steps.iter().sum();
                (n > 0).then(|| f.update_flips.iter().sum::<u64>() as f64 / n as f64)
            }),
        },
    };
    Some((summary, cascades))
}

/// Per cascade: the area of the light-space bounding rectangle of the lit-facing receiver
/// points it serves (clipped to its window) over the window's area; 0 when it serves none.
pub(crate) fn texel_utilization(
    vis: &Visibility,
    rig: &Rig,
    lp: &LightPose,
    windows: &[csm_core::fitting::Window],
) -> Vec<f64> {
    let m = rig.cascade_count();
    let bases: Vec<_> = (0..m).map(|i| rig.basis(i, lp)).collect();
    let mut lo = vec![DVec2::splat(f64::INFINITY); m];
    let mut hi = vec![DVec2::splat(f64::NEG_INFINITY); m];
    let (z_lo, z_hi) = (rig.splits[0], rig.splits[m]);
    let terms = vis.view.ray_terms();
    for (k, s) in vis.samples.iter().enumerate() {
        let Some(s) = s.filter(|s| s.lit && s.depth >= z_lo && s.depth <= z_hi) else {
            continue;
        };
        let i = metrics::cascade_at(&rig.splits, s.depth);
        let p = terms.point(k, s.depth);
        let q = DVec2::new(bases[i].x.dot(p), bases[i].y.dot(p));
        lo[i] = lo[i].min(q);
        hi[i] = hi[i].max(q);
    }
    (0..m)
        .map(|i| {
            let w = &windows[i];
            let wmin = w.min();
            let wmax = wmin + w.texel * w.resolution as f64;
            let size = (hi[i].min(wmax) - lo[i].max(wmin)).max(DVec2::ZERO);
            let area = w.width() * w.height();
            if lo[i].x.is_finite() && area > 0.0 {
                (size.x * size.y / area).min(1.0)
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod split_range_tests {
    use super::*;
    use csm_core::scene::Setup;
    use glam::DVec3;
    use proptest::prelude::*;

    /// The bounds-only sweep's set-up, with bounds to the right of the view axis that the view
    /// frustum clips on both ends (so each input of the range moves it).
    fn base() -> Setup {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/default_bounds_only.toml");
        let mut setup = Config::load(&path).expect("the bundled config loads").setup();
        setup.bounds.min = DVec3::new(20.0, 0.0, -120.0);
        setup.bounds.max = DVec3::new(60.0, 40.0, -20.0);
        setup
    }

    fn bits(r: DepthRange) -> Option<(u64, u64)> {
        r.bounds().map(|(lo, hi)| (lo.to_bits(), hi.to_bits()))
    }

    /// Input `field` of the split range changed by `by` (a toggle for the fit switch).
    fn changed(mut s: Setup, field: usize, by: f64) -> Setup {
        match field {
            0 => s.camera.position.x += by,
            1 => s.camera.position.y += by,
            2 => s.camera.target.z += by,
            3 => s.camera.up.x += by,
            4 => s.camera.fov_y *= 1.0 + by / 20.0,
            5 => s.camera.aspect *= 1.0 + by / 10.0,
            6 => s.camera.near = 30.0 + by.abs(),
            7 => s.camera.far = 100.0 - by.abs() * 10.0,
            8 => s.shadow.max_distance -= 60.0 + by.abs() * 10.0,
            9 => s.bounds.min.z -= 1.0 + by.abs(),
            10 => s.bounds.max.z += 1.0 + by.abs(),
            _ => s.shadow.fit_depth_to_scene = !s.shadow.fit_depth_to_scene,
        }
        s
    }

    /// Each input the range reads moves it, and the thread's held range follows: a key that
    /// missed an input would return the range before the change.
    #[test]
    fn every_input_moves_the_range_and_the_held_one() {
        let b = base();
        assert!(bits(depth_range::for_setup(&b)).is_some());
        for field in 0..12 {
            let s = changed(b.clone(), field, 0.5);
            let alone = depth_range::for_setup(&s);
            assert_ne!(
                bits(alone),
                bits(depth_range::for_setup(&b)),
                "field {field} moves the range"
            );
            assert_eq!(bits(split_range(&b)), bits(depth_range::for_setup(&b)));
            assert_eq!(bits(split_range(&s)), bits(alone), "field {field}");
            assert_eq!(
                bits(split_range(&b)),
                bits(depth_range::for_setup(&b)),
                "field {field}, back"
            );
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

        /// Along any sequence of set-ups (each the one before, or it with one input changed),
        /// the held range equals the range computed alone, bit for bit.
        #[test]
        fn held_range_equals_computed_alone(steps in prop::collection::vec((0usize..14, -3.0f64..3.0), 1..24)) {
            let mut s = base();
            for (field, by) in steps {
                if field < 12 {
                    s = changed(s, field, by);
                }
                prop_assert_eq!(bits(split_range(&s)), bits(depth_range::for_setup(&s)));
            }
        }

        /// Several cameras read in turn (a level's views, setting after setting), each now and
        /// then changed: every held range equals the range computed alone, bit for bit, and
        /// the bounds' range of a set-up fitted to visible geometry is its bounds-only range.
        #[test]
        fn held_ranges_of_cameras_in_turn_equal_computed_alone(
            steps in prop::collection::vec((0usize..5, 0usize..16, -3.0f64..3.0, any::<bool>()), 1..48),
        ) {
            let mut cams: Vec<Setup> = (0..5).map(|k| changed(base(), k % 4, k as f64 * 0.7)).collect();
            for (cam, field, by, visible) in steps {
                if field < 12 {
                    cams[cam] = changed(cams[cam].clone(), field, by);
                }
                let s = &cams[cam];
                prop_assert_eq!(bits(split_range(s)), bits(depth_range::for_setup(s)));
                let mut fitted = s.clone();
                fitted.shadow.fit_depth_to_visible = visible;
                prop_assert_eq!(bits(bounds_range(&fitted)), bits(depth_range::for_setup(s)));
            }
        }
    }
}

#[cfg(test)]
mod view_inputs_tests {
    use super::*;

    /// The 20-view bench level with its `[shadow]` table replaced by `shadow`.
    fn level(shadow: &str) -> Config {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/default_20_views.toml");
        let text = std::fs::read_to_string(&path).expect("the bench config reads");
        let start = text.find("[shadow]").expect("a [shadow] table");
        let end = start + text[start..].find("\n\n").expect("a blank line after it");
        let text = format!("{}{shadow}{}", &text[..start], &text[end..]);
        Config::from_toml_str(&text, "level.toml", None).unwrap_or_else(|e| panic!("{e}\n{shadow}"))
    }

    fn bits(x: &[f64]) -> Vec<u64> {
        x.iter().map(|v| v.to_bits()).collect()
    }

    /// Each view's screen inputs made without copying the config equal those of the view's own
    /// config (`config_for_view`, the direct form), bit for bit: the same pass, splits, texel
    /// sizes, visible range, bands, and band counts equal to counting the receivers in each
    /// band one by one; for csm-lab's own rig (fitted to the bounds and to visible geometry)
    /// and an engine preset's.
    #[test]
    fn view_inputs_equal_those_of_the_views_own_config() {
        let shadows = [
            "[shadow]\nmax_distance = 150.0\ncascades = 4\nlambda = 0.75\nresolution = 2048\nfit = \"sphere\"\nsnap = true\nfit_depth_to_scene = true",
            "[shadow]\nmax_distance = 90.0\ncascades = 3\nlambda = 0.4\nresolution = 1024\nfit = \"aabb\"\nsnap = false\nfit_depth_to_visible = true",
            "[shadow]\npreset = \"unity\"\nmax_distance = 120.0",
        ];
        for shadow in shadows {
            let config = level(shadow);
            assert_eq!(config.views.len(), 20);
            for v in config.views.iter() {
                let own = config_for_view(&config, v);
                assert_eq!(
                    format!("{:?}", config.setup_seen_by(&v.camera)),
                    format!("{:?}", own.setup())
                );
                let a = view_screen_inputs(&config, v).expect("geometry");
                let b = screen_inputs(&own).expect("geometry");
                assert!(std::sync::Arc::ptr_eq(&a.vis, &b.vis), "{}", v.name);
                assert_eq!(bits(&a.splits), bits(&b.splits), "{}", v.name);
                assert_eq!(bits(&a.texel), bits(&b.texel), "{}", v.name);
                assert_eq!(
                    a.visible.map(|(l, h)| (l.to_bits(), h.to_bits())),
                    b.visible.map(|(l, h)| (l.to_bits(), h.to_bits()))
                );
                let flat = |x: &[(f64, f64)]| {
                    x.iter()
                        .flat_map(|&(l, h)| [l.to_bits(), h.to_bits()])
                        .collect::<Vec<_>>()
                };
                assert_eq!(flat(&a.bands), flat(&b.bands));
                let counted: Vec<u64> = a
                    .bands
                    .iter()
                    .map(|&(lo, hi)| a.vis.receivers.iter().filter(|&&(d, _)| d >= lo && d < hi).count() as u64)
                    .collect();
                assert_eq!(a.band_counts, counted, "{}", v.name);
                assert_eq!(bits(&a.band_shares()), bits(&seams::band_shares(&a.vis, &a.bands)));
            }
        }
    }
    /// A view's screen inputs read from what the thread keeps of its split set equal the
    /// direct computation (`screen_inputs` of the view's own config, nothing kept), bit for bit,
    /// along a walk that changes one axis at a time (resolution alone: the kept entry is read;
    /// λ, cascade count, fit, split range, distance, sun, snap: a new split set) and returns
    /// to earlier settings. A key that missed any of these axes would hand back another split
    /// set's splits, bands or pass, and a texel size not moved to the resolution would differ.
    #[test]
    fn view_inputs_kept_per_split_set_equal_the_direct_computation() {
        use crate::commands::sweep::grid::{Setting, Sun};
        use csm_core::scene::SplitRange;
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/default_20_views.toml");
        let base = Config::load(&path).expect("the bench config loads");
        // As a level keeps them (`level_inputs`): every view's pass, so that both forms read one.
        let scene = &base.geometry.as_ref().expect("geometry").scene;
        scene.keep_at_least(2 * base.views.len() + 8);
        let fit = base.shadow.fit;
        let other_fit = match fit {
            csm_core::fitting::Fit::Sphere => csm_core::fitting::Fit::Aabb,
            csm_core::fitting::Fit::Aabb => csm_core::fitting::Fit::Sphere,
        };
        let plain = |lambda, cascades, resolution| Setting::plain(lambda, cascades, resolution, fit);
        let sun = Some(Sun {
            azimuth_deg: 120.0,
            elevation_deg: 35.0,
        });
        let walk = [
            plain(0.5, 4, 512),
            plain(0.5, 4, 2048),
            plain(0.5, 4, 1024),
            plain(0.6, 4, 1024),
            plain(0.6, 3, 1024),
            Setting::plain(0.6, 3, 1024, other_fit),
            Setting::plain(0.6, 3, 4096, other_fit),
            Setting {
                split_range: SplitRange::Visible,
                ..plain(0.6, 3, 4096)
            },
            Setting {
                distance: Some(60.0),
                ..plain(0.6, 3, 4096)
            },
            Setting {
                sun,
                ..plain(0.6, 3, 4096)
            },
            Setting {
                sun,
                ..plain(0.6, 3, 512)
            },
            plain(0.5, 4, 4096),
            plain(0.5, 4, 512),
        ];
        let mut configs: Vec<Config> = walk.iter().map(|s| s.apply(&base).expect("a valid point")).collect();
        // Snap is no axis of the grid: the last point again, unsnapped.
        let mut unsnapped = configs.last().expect("a point").clone();
        unsnapped.shadow.snap = !unsnapped.shadow.snap;
        unsnapped.shadow.params.snap = unsnapped.shadow.snap;
        configs.push(unsnapped);
        for (step, config) in configs.iter().enumerate() {
            for v in config.views.iter() {
                let a = view_screen_inputs(config, v).expect("geometry");
                let b = screen_inputs(&config_for_view(config, v)).expect("geometry");
                let at = format!("step {step}, {}", v.name);
                assert!(std::sync::Arc::ptr_eq(&a.vis, &b.vis), "{at}");
                assert_eq!(bits(&a.splits), bits(&b.splits), "{at}");
                assert_eq!(bits(&a.texel), bits(&b.texel), "{at}");
                assert_eq!(
                    a.visible.map(|(l, h)| (l.to_bits(), h.to_bits())),
                    b.visible.map(|(l, h)| (l.to_bits(), h.to_bits())),
                    "{at}"
                );
                let flat = |x: &[(f64, f64)]| {
                    x.iter()
                        .flat_map(|&(l, h)| [l.to_bits(), h.to_bits()])
                        .collect::<Vec<_>>()
                };
                assert_eq!(flat(&a.bands), flat(&b.bands), "{at}");
                assert_eq!(a.band_counts, b.band_counts, "{at}");
            }
        }
        // Kept entries are read: two resolutions of one split set make one entry per view.
        SPLIT_SETS.with(|h| h.borrow_mut().entries.clear());
        for config in &configs[..2] {
            for v in config.views.iter() {
                view_screen_inputs(config, v).expect("geometry");
            }
        }
        assert_eq!(SPLIT_SETS.with(|h| h.borrow().entries.len()), base.views.len());
    }
}

#[cfg(test)]
mod split_set_done_tests {
    use super::*;

    /// A level's pooled statistics, computed through the scene's memo while split sets are
    /// declared done between them (their windows and served parts dropped), equal the pool
    /// of the same parts computed directly (`screen::pool`, no memo, no hints), bit for bit:
    /// at each resolution of a split set, after it is done (from the level held, or made
    /// again), and when it comes back.
    #[test]
    fn pools_around_a_split_set_done_equal_the_direct_pool() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/default_20_views.toml");
        let base = Config::load(&path).expect("the bench config loads");
        let at = |lambda: f64, cascades: usize, resolution: u32| {
            crate::commands::sweep::grid::Setting::plain(lambda, cascades, resolution, base.shadow.fit)
                .apply(&base)
                .expect("a valid point")
        };
        let order = [
            (0.5, 4, 512),
            (0.5, 4, 1024),
            (0.5, 4, 2048),
            (0.2, 3, 1024),
            (0.2, 3, 4096),
            (0.5, 4, 4096),
            (0.5, 4, 512),
        ];
        for (i, &(lambda, cascades, resolution)) in order.iter().enumerate() {
            let c = at(lambda, cascades, resolution);
            let level = level_screen(&c).expect("views and geometry");
            let pooled = full_pool(&c).expect("views and geometry");
            assert_eq!(level.screen, pooled.level, "step {i}");
            for (v, p) in level.views.iter().zip(&pooled.views) {
                assert_eq!(v.screen, *p, "step {i}, {}", v.name);
            }
            if i % 2 == 0 {
                split_set_done(&c);
            }
            if i == 2 {
                // Again, with no level held: the inputs are made afresh.
                split_set_done(&c);
            }
        }
    }
}
