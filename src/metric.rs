//! The metric registry: one table per kind of metric says, for each metric, its name, unit,
//! which direction is worse, what it means and how to read it from a result.
//!
//! Everything that lists metrics is generated from these tables: the summary columns of
//! `sweep.csv` and `compare.csv`, the summary keys of `summary.json` and `recommendation.json`,
//! `analyze`'s summary on stdout, `check`'s metric names, lookup and "did you mean"
//! suggestions, and the metric tables of docs/metrics.md and docs/check.md
//! ([`markdown_table`], kept in step by a test). Adding a metric means adding its computation and one entry here.

use crate::analysis::{CascadeReport, Summary};
use crate::error::Result;
use crate::output::num;
use csm_core::scene::SplitRange;

/// Which way a metric gets worse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    HigherIsWorse,
    LowerIsWorse,
    /// A position, not a quality: changes are reported, never as regressions.
    Neither,
}

impl Direction {
    pub(crate) fn describe(self) -> &'static str {
        match self {
            Direction::HigherIsWorse => "higher is worse",
            Direction::LowerIsWorse => "lower is worse",
            Direction::Neither => "neither (a position, not a quality)",
        }
    }

    /// The word of the docs tables' "worse" column.
    #[cfg(test)]
    fn word(self) -> &'static str {
        match self {
            Direction::HigherIsWorse => "higher",
            Direction::LowerIsWorse => "lower",
            Direction::Neither => "neither",
        }
    }

    /// How much worse `current` is than `baseline`, in the metric's units (negative when it
    /// improved); None for [`Direction::Neither`].
    pub(crate) fn worsening(self, baseline: f64, current: f64) -> Option<f64> {
        match self {
            Direction::HigherIsWorse => Some(current - baseline),
            Direction::LowerIsWorse => Some(baseline - current),
            Direction::Neither => None,
        }
    }
}

/// A metric's value with its type: how it is written in CSV and JSON.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    Flag(bool),
    Count(u64),
    Real(f64),
    /// Not measured (too little data): `n/a` in CSV, `null` in JSON.
    Missing,
}

impl Value {
    /// Booleans read 1 (true) or 0 (false), counts their value.
    pub(crate) fn as_f64(self) -> f64 {
        match self {
            Value::Flag(b) => f64::from(u8::from(b)),
            Value::Count(n) => n as f64,
            Value::Real(x) => x,
            Value::Missing => f64::NAN,
        }
    }

    /// A real when known, [`Value::Missing`] otherwise.
    pub(crate) fn maybe(x: Option<f64>) -> Value {
        x.map_or(Value::Missing, Value::Real)
    }

    pub(crate) fn json(self) -> serde_json::Value {
        match self {
            Value::Flag(b) => b.into(),
            Value::Count(n) => n.into(),
            Value::Real(x) => serde_json::json!(x),
            Value::Missing => serde_json::Value::Null,
        }
    }

    /// The CSV field; a non-finite real is refused (named `what`).
    pub(crate) fn csv(self, what: &str) -> Result<String> {
        match self {
            Value::Flag(b) => Ok(b.to_string()),
            Value::Count(n) => Ok(n.to_string()),
            Value::Real(x) => num(what, x),
            Value::Missing => Ok("n/a".to_string()),
        }
    }
}

/// How `analyze`'s summary on stdout shows a metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shown {
    /// Not in the table.
    Never,
    /// Always, fixed with 4 decimals.
    Fixed,
    /// Always, in scientific notation with 3 decimals.
    Scientific,
    /// Always, as a whole number.
    Whole,
    /// Only with `precision = "f32"`, in scientific notation.
    F32Scientific,
}

/// One summary metric.
#[derive(Debug, Clone, Copy)]
pub struct SummaryDef {
    pub name: &'static str,
    /// Unit of the value ("" for pure ratios and flags).
    pub unit: &'static str,
    pub direction: Direction,
    /// What it means, for `check`, the docs and the JSON of `check`.
    pub help: &'static str,
    /// The shorter wording of `analyze`'s stdout summary.
    pub brief: &'static str,
    pub shown: Shown,
    /// A column of the per-configuration tables (`sweep.csv`, `compare.csv`).
    pub in_rows: bool,
    /// A screen metric: only with scene geometry (absent from every output without it).
    pub screen: bool,
    pub value: fn(&Summary) -> Value,
}

/// Every summary metric, in the order of `summary.json`'s flat keys and of the CSV columns.
pub(crate) const SUMMARY: &[SummaryDef] = &[
    SummaryDef {
        name: "cascades_needed",
        unit: "",
        // Losing the cascades means the scene left the shadowed range; every other metric
        // then reads 0, which must not pass for an improvement.
        direction: Direction::LowerIsWorse,
        help: "1 when the scene is visible within the shadow distance, else 0",
        brief: "",
        shown: Shown::Never,
        in_rows: false,
        screen: false,
        value: |s| Value::Flag(s.cascades_needed),
    },
    SummaryDef {
        name: "z_lo",
        unit: "world units",
        direction: Direction::Neither,
        help: "near end of the split range (world units of view depth)",
        brief: "",
        shown: Shown::Never,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.z_lo),
    },
    SummaryDef {
        name: "z_hi",
        unit: "world units",
        direction: Direction::Neither,
        help: "far end of the split range (world units of view depth)",
        brief: "",
        shown: Shown::Never,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.z_hi),
    },
    SummaryDef {
        name: "max_aliasing",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "worst texel-to-pixel size ratio anywhere (at a cascade's near edge)",
        brief: "worst texel/pixel ratio (at a cascade's near edge)",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.max_aliasing),
    },
    SummaryDef {
        name: "mean_aliasing",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "aliasing ratio averaged over view depth",
        brief: "mean over depth",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.mean_aliasing),
    },
    SummaryDef {
        name: "mean_log_aliasing",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "aliasing ratio averaged over log depth (every doubling of distance counts the same)",
        brief: "mean over log depth",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.mean_log_aliasing),
    },
    SummaryDef {
        name: "undersampled_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "share of the depth range where aliasing > 1",
        brief: "share of depth with aliasing > 1",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.undersampled_fraction),
    },
    SummaryDef {
        name: "shimmer",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "RMS sub-texel drift (S3) of world-fixed points per frame with the configured snapping (`shadow.snap`), worst over the motion paths (texels)",
        brief: "RMS sub-texel drift per frame, as configured (texels)",
        shown: Shown::Scientific,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.shimmer),
    },
    SummaryDef {
        name: "shimmer_snapped",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "the same with snapping, whatever the config says (information; texels)",
        brief: "RMS sub-texel drift per frame, snapped (texels)",
        shown: Shown::Scientific,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.shimmer_snapped),
    },
    SummaryDef {
        name: "shimmer_unsnapped",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "the same without snapping, whatever the config says (information; texels)",
        brief: "the same without snapping",
        shown: Shown::Scientific,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.shimmer_unsnapped),
    },
    SummaryDef {
        name: "size_jitter",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "largest relative texel-size change between frames (S1); snapping cannot remove it",
        brief: "largest texel-size change between frames",
        shown: Shown::Scientific,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.size_jitter),
    },
    SummaryDef {
        name: "coverage_violations",
        unit: "count",
        direction: Direction::HigherIsWorse,
        help: "slice corners outside their window, all cascades and frames; 0 means every slice is covered",
        brief: "slice corners outside their window",
        shown: Shown::Whole,
        in_rows: true,
        screen: false,
        value: |s| Value::Count(s.coverage_violations),
    },
    SummaryDef {
        name: "memory_bytes",
        unit: "bytes",
        direction: Direction::HigherIsWorse,
        help: "cascades x resolution^2 x 4 bytes",
        brief: "cascades x resolution^2 x 4",
        shown: Shown::Whole,
        in_rows: true,
        screen: false,
        value: |s| Value::Count(s.memory_bytes),
    },
    SummaryDef {
        name: "lookup_error_max",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "largest static f32 lookup error S7 (texels; 0 in f64)",
        brief: "S7: largest |s_f32 - s_exact| lookup error (texels)",
        shown: Shown::F32Scientific,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.lookup_error_max),
    },
    SummaryDef {
        name: "lookup_error_rms",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "RMS static f32 lookup error S7 (texels; 0 in f64)",
        brief: "RMS of S7 (texels)",
        shown: Shown::F32Scientific,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.lookup_error_rms),
    },
    SummaryDef {
        name: "overlap_area_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "shadow-map texels spent twice on the blend bands (each finer map's texels over its far band's slice), over all maps' texels; 0 without bands",
        brief: "map texels spent twice on blend bands (share of all)",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| Value::Real(s.overlap_area_fraction),
    },
    SummaryDef {
        name: "seam_crossings",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "fraction of world-fixed receiver points whose cascade changes from one frame to the next, averaged over the frames, worst over the motion paths (not a sweep column)",
        brief: "receivers changing cascade per frame (seams sweeping)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.seam_crossings.unwrap_or(0.0)),
    },
    SummaryDef {
        name: "light_crawl",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "moving light: RMS sub-texel drift (S3) over the frame pairs whose used light direction did not change (between updates), with the configured snapping, worst over the motion paths; only when the light moves",
        brief: "moving light: drift between light updates (RMS texels)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.light.map_or(0.0, |l| l.crawl)),
    },
    SummaryDef {
        name: "light_crawl_snapped",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "light_crawl with snapping",
        brief: "",
        shown: Shown::Never,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.light.map_or(0.0, |l| l.crawl_snapped)),
    },
    SummaryDef {
        name: "light_crawl_unsnapped",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "light_crawl without snapping",
        brief: "",
        shown: Shown::Never,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.light.map_or(0.0, |l| l.crawl_unsnapped)),
    },
    SummaryDef {
        name: "light_jump",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "moving light: the largest move of a world-fixed probe's texel coordinates (not wrapped) between the two frames of a light update, in windows without snapping (a snapped window's whole-texel re-snap moves no shadow), worst over the motion paths; only when the light moves",
        brief: "moving light: largest probe move at an update (texels)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.light.map_or(0.0, |l| l.jump)),
    },
    SummaryDef {
        name: "light_jump_snapped",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "light_jump in the snapped windows: adds their whole-texel re-snap at the update",
        brief: "",
        shown: Shown::Never,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.light.map_or(0.0, |l| l.jump_snapped)),
    },
    SummaryDef {
        name: "light_jump_unsnapped",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "light_jump without snapping",
        brief: "",
        shown: Shown::Never,
        in_rows: false,
        screen: false,
        value: |s| Value::Real(s.light.map_or(0.0, |l| l.jump_unsnapped)),
    },
    SummaryDef {
        name: "renders_per_frame",
        unit: "cascades",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: cascade renders per frame on average, the sum over cascades of 1 / update_every (the cascade count without caching); only with [shadow] update_every",
        brief: "cached: cascade renders per frame (sum of 1/update_every)",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| s.cache.map_or(Value::Missing, |c| Value::Real(c.renders_per_frame)),
    },
    SummaryDef {
        name: "stale_coverage_violations",
        unit: "count",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: frames in which a cascade kept an earlier window that does not hold the current slice (a coverage hole), summed over cascades and motion paths, configured snapping; only with [shadow] update_every",
        brief: "cached: stale frames whose window misses the slice",
        shown: Shown::Never,
        in_rows: true,
        screen: false,
        value: |s| s.cache.map_or(Value::Missing, |c| Value::Count(c.figures.stale_coverage_violations)),
    },
    SummaryDef {
        name: "stale_coverage_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: the worst cascade's share of the frames walked with such a hole; only with [shadow] update_every",
        brief: "cached: worst cascade's share of frames with a hole",
        shown: Shown::Never,
        in_rows: true,
        screen: false,
        value: |s| s.cache.map_or(Value::Missing, |c| Value::Real(c.figures.stale_coverage_fraction)),
    },
    SummaryDef {
        name: "stale_margin",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: the largest growth of a held window, in its own texels on every side, that covers the slice in every stale frame (0 when none has a hole); only with [shadow] update_every",
        brief: "cached: window growth that closes every hole (texels)",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| s.cache.map_or(Value::Missing, |c| Value::Real(c.figures.stale_margin)),
    },
    SummaryDef {
        name: "stale_margin_world",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: stale_margin in world units (each cascade's growth times its texel size), the largest over the cascades; only with [shadow] update_every",
        brief: "cached: the same in world units",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| s.cache.map_or(Value::Missing, |c| Value::Real(c.figures.stale_margin_world)),
    },
    SummaryDef {
        name: "update_drift",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: the worst cascade's RMS sub-texel drift (S3) over the frame pairs at which it is rendered again, configured snapping, worst over the motion paths (a held window does not drift between updates); only with [shadow] update_every",
        brief: "cached: RMS drift at a cascade's updates (texels)",
        shown: Shown::Fixed,
        in_rows: true,
        screen: false,
        value: |s| s.cache.map_or(Value::Missing, |c| Value::Real(c.figures.update_drift)),
    },
    SummaryDef {
        name: "update_flicker",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cached cascades, ground truth: S5 over the receiver steps at the frames their cascade is rendered again, configured snapping; only with [shadow] update_every and ground_truth",
        brief: "cached: S5 at cascade updates",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::maybe(s.cache.and_then(|c| c.figures.update_flicker)),
    },
    SummaryDef {
        name: "acne_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: share of the receiver points at frame 0 that are truly lit but the sampled map shadows (acne); only with ground_truth",
        brief: "truly lit points the map shadows (acne)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.acne_fraction)),
    },
    SummaryDef {
        name: "edge_error_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: share of the receiver points at frame 0 whose answer is wrong because the texels read hold another surface (the blocky shadow edge, either way; only resolution fixes it); only with ground_truth",
        brief: "points wrong at a shadow edge (another surface's texels)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.edge_error_fraction)),
    },
    SummaryDef {
        name: "leak_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: share of the receiver points at frame 0 that are truly shadowed but the sampled map lights only because of the bias (peter-panning, leaks); only with ground_truth",
        brief: "truly shadowed points the map lights (leaks)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.leak_fraction)),
    },
    SummaryDef {
        name: "flicker_snapped",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "S5 with snapping: share of receiver points whose lit/shadowed answer changes between consecutive frames (same cascade), over the path; only with ground_truth",
        brief: "S5 flicker, snapped (state changes per point and frame)",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.flicker_snapped)),
    },
    SummaryDef {
        name: "flicker_unsnapped",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "S5 without snapping (see flicker_snapped); only with ground_truth",
        brief: "S5 flicker, unsnapped",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.flicker_unsnapped)),
    },
    SummaryDef {
        name: "flicker_edge_snapped",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "the part of flicker_snapped at points whose texels hold another surface in either frame (the shadow edge crawling); only with ground_truth",
        brief: "S5 at shadow edges, snapped",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.flicker_edge_snapped)),
    },
    SummaryDef {
        name: "flicker_edge_unsnapped",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "the part of flicker_unsnapped at shadow edges (see flicker_edge_snapped); only with ground_truth",
        brief: "S5 at shadow edges, unsnapped",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.flicker_edge_unsnapped)),
    },
    SummaryDef {
        name: "flicker_acne_snapped",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "the rest of flicker_snapped: changes where every texel read holds the point's own surface in both frames (acne coming and going); only with ground_truth",
        brief: "S5 from acne, snapped",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.flicker_acne_snapped)),
    },
    SummaryDef {
        name: "flicker_acne_unsnapped",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "the rest of flicker_unsnapped (see flicker_acne_snapped); only with ground_truth",
        brief: "S5 from acne, unsnapped",
        shown: Shown::Fixed,
        in_rows: false,
        screen: true,
        value: |s| Value::Real(s.truth.map_or(0.0, |t| t.flicker_acne_unsnapped)),
    },
    SummaryDef {
        name: "screen_receiver_fraction",
        unit: "",
        direction: Direction::LowerIsWorse,
        help: "share of sampled screen pixels that see a lit-facing receiver (a surface whose normal points toward the light)",
        brief: "share of pixels on lit-facing receivers",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.receiver_fraction)),
    },
    SummaryDef {
        name: "screen_self_shadowed_fraction",
        unit: "",
        direction: Direction::Neither,
        help: "share of sampled screen pixels that see a surface facing away from the light (self-shadowed whatever the map holds)",
        brief: "share of pixels facing away from the light",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.self_shadowed_fraction)),
    },
    SummaryDef {
        name: "screen_aliasing_mean",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "per-pixel aliasing m = 1/sigma_min(J) averaged over the served lit-facing receiver pixels",
        brief: "mean per-pixel aliasing m on screen",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.aliasing_mean)),
    },
    SummaryDef {
        name: "screen_aliasing_p50",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "median (nearest rank) of the per-pixel aliasing m over the served receiver pixels",
        brief: "median m on screen",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.aliasing_p50)),
    },
    SummaryDef {
        name: "screen_aliasing_p95",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "95th percentile (nearest rank) of the per-pixel aliasing m over the served receiver pixels",
        brief: "95th percentile of m on screen",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.aliasing_p95)),
    },
    SummaryDef {
        name: "screen_aliasing_p99",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "99th percentile (nearest rank) of the per-pixel aliasing m over the served receiver pixels",
        brief: "99th percentile of m on screen",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.aliasing_p99)),
    },
    SummaryDef {
        name: "screen_aliasing_max",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "largest per-pixel aliasing m over the served receiver pixels (finite: grazing light is clamped)",
        brief: "largest m on screen",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.aliasing_max)),
    },
    SummaryDef {
        name: "visible_aliasing_mean",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "mean of m over the served receiver pixels, each weighted by its direct-light contrast N·L (0 facing away from the light, 1 facing it): the aliasing as visible under shading",
        brief: "contrast-weighted mean m on screen",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_mean)),
    },
    SummaryDef {
        name: "visible_aliasing_p50",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "weighted median of m (weights N·L, exact nearest rank on the weights)",
        brief: "contrast-weighted median m",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_p50)),
    },
    SummaryDef {
        name: "visible_aliasing_p95",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "weighted 95th percentile of m (weights N·L, exact nearest rank on the weights): continuous in the light direction; the default sweep objective with scene geometry",
        brief: "contrast-weighted 95th percentile of m",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_p95)),
    },
    SummaryDef {
        name: "visible_aliasing_p99",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "weighted 99th percentile of m (weights N·L, exact nearest rank on the weights)",
        brief: "contrast-weighted 99th percentile of m",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_p99)),
    },
    SummaryDef {
        name: "visible_aliasing_max",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "largest m over the served receiver pixels with weight N·L above 0",
        brief: "largest m of a lit pixel",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_max)),
    },
    SummaryDef {
        name: "screen_undersampled_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "share of the served receiver pixels with m > 1 (blocky shadows)",
        brief: "share of receiver pixels with m > 1",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.undersampled_fraction)),
    },
    SummaryDef {
        name: "screen_band_pixel_share",
        unit: "",
        direction: Direction::Neither,
        help: "share of the lit-facing receiver pixels inside a blend band (both cascades rendered, the coarser read), all splits together",
        brief: "share of receiver pixels in blend bands",
        shown: Shown::Fixed,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.band_pixel_share),
    },
    SummaryDef {
        name: "visible_z_lo",
        unit: "world units",
        direction: Direction::Neither,
        help: "nearest view depth of the visible geometry, within the bounds' split range",
        brief: "",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_z_lo)),
    },
    SummaryDef {
        name: "visible_z_hi",
        unit: "world units",
        direction: Direction::Neither,
        help: "farthest view depth of the visible geometry, within the bounds' split range",
        brief: "",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| Value::Real(s.screen.as_ref().map_or(0.0, |x| x.visible_z_hi)),
    },
    SummaryDef {
        name: "caster_objects",
        unit: "draws",
        direction: Direction::HigherIsWorse,
        help: "cost: draw calls of frame 0, summed over the cascades: the objects (the ground, a box, a glTF mesh primitive under its node) whose world bounds meet a cascade's caster volume (window rectangle, scene light near to cascade light far); culled by receivers with [cost] cull = \"receivers\"",
        brief: "draw calls, all cascades (frame 0)",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.counts.map_or(Value::Missing, |c| Value::Count(c.caster_objects)),
    },
    SummaryDef {
        name: "caster_triangles",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: the triangles of those objects, summed over the cascades (what the GPU processes)",
        brief: "caster triangles, all cascades",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.counts.map_or(Value::Missing, |c| Value::Count(c.caster_triangles)),
    },
    SummaryDef {
        name: "caster_triangles_inside",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: those triangles that intersect their cascade's caster volume (what a per-triangle culler keeps)",
        brief: "caster triangles inside the volumes",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.counts.map_or(Value::Missing, |c| Value::Count(c.caster_triangles_inside)),
    },
    SummaryDef {
        name: "raster_fragments",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: area of the casters' triangles (no face culling) projected along the light and clipped exactly to each cascade's window, in texels, overdraw included, summed over the cascades",
        brief: "fragments rasterised (texels, overdraw included)",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.counts.map_or(Value::Missing, |c| Value::Real(c.raster_fragments)),
    },
    SummaryDef {
        name: "texels_cleared",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: texels cleared per update, the sum of resolution^2 over the cascades rendered",
        brief: "texels cleared per update",
        shown: Shown::Never,
        in_rows: true,
        screen: false,
        value: |s| Value::Count(s.cost.texels_cleared),
    },
    SummaryDef {
        name: "bytes_written",
        unit: "bytes",
        direction: Direction::HigherIsWorse,
        help: "cost: bytes the clears write per update (texels_cleared x 4, 32-bit depth)",
        brief: "bytes the clears write per update",
        shown: Shown::Never,
        in_rows: true,
        screen: false,
        value: |s| Value::Count(s.cost.bytes_written),
    },
    SummaryDef {
        name: "cost_index",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cost: the linear cost model over draws, triangles, fragments and cleared texels (docs/cost.md), over the configured setting's (1 for the configured setting)",
        brief: "cost over the configured setting's",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| Value::maybe(s.cost.cost_index),
    },
    SummaryDef {
        name: "shadow_ms",
        unit: "ms",
        direction: Direction::HigherIsWorse,
        help: "cost: the cost model with the calibrated coefficients ([cost] ns_per_*), in milliseconds per frame; only when calibrated",
        brief: "shadow rendering time (calibrated model)",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| Value::maybe(s.cost.shadow_ms),
    },
    SummaryDef {
        name: "caster_objects_mean",
        unit: "draws",
        direction: Direction::HigherIsWorse,
        help: "cost: caster_objects per frame on average over every frame of the motion paths (a cascade held by [shadow] update_every draws nothing in its stale frames); with scene geometry, without culling, under a fixed light basis",
        brief: "draw calls per frame, mean over the path",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.means.map_or(Value::Missing, |m| Value::Real(m.caster_objects_mean)),
    },
    SummaryDef {
        name: "caster_triangles_mean",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: caster_triangles per frame on average over the motion paths (as caster_objects_mean)",
        brief: "caster triangles per frame, mean over the path",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.means.map_or(Value::Missing, |m| Value::Real(m.caster_triangles_mean)),
    },
    SummaryDef {
        name: "caster_triangles_inside_mean",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: caster_triangles_inside per frame on average over the motion paths (as caster_objects_mean)",
        brief: "caster triangles inside, mean over the path",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.means.map_or(Value::Missing, |m| Value::Real(m.caster_triangles_inside_mean)),
    },
    SummaryDef {
        name: "raster_fragments_mean",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: raster_fragments per frame on average over the motion paths (as caster_objects_mean)",
        brief: "fragments per frame, mean over the path",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.means.map_or(Value::Missing, |m| Value::Real(m.raster_fragments_mean)),
    },
    SummaryDef {
        name: "texels_cleared_mean",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: texels cleared per frame on average over the motion paths (a held cascade clears nothing in its stale frames)",
        brief: "texels cleared per frame, mean over the path",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| s.cost.means.map_or(Value::Missing, |m| Value::Real(m.texels_cleared_mean)),
    },
    SummaryDef {
        name: "cost_index_mean",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cost: the cost model of the means over the motion paths, over the configured setting's frame 0 (below cost_index where cached cascades save)",
        brief: "cost per frame over the path, over the configured frame 0",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| Value::maybe(s.cost.means.and_then(|m| m.cost_index_mean)),
    },
    SummaryDef {
        name: "shadow_ms_mean",
        unit: "ms",
        direction: Direction::HigherIsWorse,
        help: "cost: the calibrated cost model of the means over the motion paths, in milliseconds per frame; only when calibrated",
        brief: "shadow rendering time per frame over the path (calibrated)",
        shown: Shown::Never,
        in_rows: true,
        screen: true,
        value: |s| Value::maybe(s.cost.means.and_then(|m| m.shadow_ms_mean)),
    },
];

/// A copyable handle on one registry entry: ordered, hashed and printed (`Debug`) by its
/// place and name in the table.
macro_rules! handle {
    ($(#[$doc:meta])* $handle:ident, $def:ty, $table:ident, $kind:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $handle(usize);

        impl std::fmt::Debug for $handle {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl $handle {
            /// Every metric of this kind, in registry order.
            pub fn all() -> impl Iterator<Item = $handle> {
                (0..$table.len()).map($handle)
            }

            pub fn def(self) -> &'static $def {
                &$table[self.0]
            }

            pub fn name(self) -> &'static str {
                self.def().name
            }

            pub(crate) fn from_name(name: &str) -> Option<Self> {
                $table.iter().position(|d| d.name == name).map($handle)
            }

            /// The metric of a name known to be in the registry (panics otherwise: a
            /// programming error).
            pub fn named(name: &str) -> Self {
                Self::from_name(name).unwrap_or_else(|| panic!("no {} metric named {name}", $kind))
            }

            pub fn direction(self) -> Direction {
                self.def().direction
            }

            pub fn description(self) -> &'static str {
                self.def().help
            }
        }
    };
}

handle!(
    /// A summary metric: a handle on its [`SUMMARY`] entry.
    SummaryMetric,
    SummaryDef,
    SUMMARY,
    "summary"
);

impl SummaryMetric {
    /// The typed value.
    pub(crate) fn typed(self, s: &Summary) -> Value {
        (self.def().value)(s)
    }

    /// The value as a number; booleans read 1 (true) or 0 (false), counts as their value.
    /// Only meaningful when [`Self::measured`]: an unmeasured metric has no value.
    pub fn value(self, s: &Summary) -> f64 {
        self.typed(s).as_f64()
    }

    /// Whether the analysis behind `s` measured this metric (screen metrics need scene
    /// geometry, the moving-light ones a moving light, the ground-truth ones that pass,
    /// `seam_crossings` its pass). An unmeasured metric is absent from every output, never 0.
    pub fn measured(self, s: &Summary) -> bool {
        shown_for(self.def(), s)
    }

    /// How to measure this metric when a summary does not have it (None: always measured).
    pub(crate) fn how_to_measure(self) -> Option<&'static str> {
        let name = self.name();
        if TRUTH_SUMMARY.contains(&name) {
            Some("it comes from the ground-truth pass: set `[analysis] ground_truth = true` in the config (it needs scene geometry)")
        } else if COST_COUNTS.contains(&name) {
            Some("it is a cost count: it needs scene geometry (scene.ground, [[scene.box]] or scene.gltf) and cost.counts on")
        } else if COST_MEANS.contains(&name) {
            Some("it is a mean over the camera path of the cost counts: it needs scene geometry with cost.counts on, cost.cull = \"none\", a still light and a light basis that does not follow the camera (a sweep also needs [sweep] cost_means = true or cached cascades; shadow_ms_mean a calibrated [cost])")
        } else if self.def().screen {
            Some("it is a screen metric: give the config scene geometry (scene.ground, [[scene.box]] or scene.gltf)")
        } else if is_light_motion(name) {
            Some("it is measured only under a moving light: give the config a light motion ([motion.light])")
        } else if CACHE_METRICS.contains(&name) {
            Some("it is measured only with cached cascades: set `[shadow] update_every` (a value above 1; update_flicker also needs ground_truth)")
        } else if name == SEAM_CROSSINGS {
            Some("it is measured by `analyze` and `check`, not in sweep rows")
        } else {
            None
        }
    }

    /// A fraction (a share of something, in [0, 1]).
    pub(crate) fn is_fraction(self) -> bool {
        self.def().unit.is_empty() && self.name().ends_with("_fraction")
    }

    /// The screen statistic of per-pixel aliasing this metric is (a field of
    /// [`csm_core::screen::ScreenStats`] that [`csm_core::screen::Statistic`] names), if any:
    /// what a level's sweep measures of each view's own for ranking it, and what the split
    /// search measures alone.
    pub(crate) fn screen_statistic(self) -> Option<csm_core::screen::Statistic> {
        use csm_core::screen::Statistic;
        Some(match self.name() {
            "screen_aliasing_mean" => Statistic::AliasingMean,
            "screen_aliasing_p50" => Statistic::AliasingP50,
            "screen_aliasing_p95" => Statistic::AliasingP95,
            "screen_aliasing_p99" => Statistic::AliasingP99,
            "screen_aliasing_max" => Statistic::AliasingMax,
            "screen_undersampled_fraction" => Statistic::UndersampledFraction,
            "visible_aliasing_mean" => Statistic::VisibleMean,
            "visible_aliasing_p50" => Statistic::VisibleP50,
            "visible_aliasing_p95" => Statistic::VisibleP95,
            "visible_aliasing_p99" => Statistic::VisibleP99,
            "visible_aliasing_max" => Statistic::VisibleMax,
            _ => return None,
        })
    }
}

/// The objective of a sweep of `config`: `[sweep] objective` if written, else the
/// contrast-weighted 95th percentile of the per-pixel aliasing on screen
/// (`visible_aliasing_p95`) when the scene has geometry, else the mean aliasing over depth.
/// `commands::sweep::rank::default_objective` is this (the name tests and reports use); it is
/// defined here because the sweep's row runner (`commands::sweep::run`), which keeps of each
/// view what the objective reads, cannot import `rank`: `rank` ranks `run`'s rows.
pub(crate) fn sweep_objective(config: &crate::config::Config) -> SummaryMetric {
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

/// The one "worst case" csm-lab prints, ranks and breaks ties on. With scene geometry it is on
/// screen: `screen_aliasing_max`, the largest per-pixel aliasing over the served receiver
/// pixels. Without geometry only the bounds metric `max_aliasing` exists: the aliasing at a
/// cascade's near edge over the depth range of the bounds, which may lie where nothing is drawn
/// (at the 0.1 m near plane of a scene whose first visible surface is 13 m away), so it is
/// named the bounds max aliasing wherever a screen value is also shown.
pub(crate) fn worst_aliasing(screen: bool) -> SummaryMetric {
    SummaryMetric::named(if screen { "screen_aliasing_max" } else { "max_aliasing" })
}

/// The words for the worst case of a run ([`worst_aliasing`]): (prose label,
/// short column head). On screen it is "worst on screen"; the bounds metric keeps its name,
/// "max aliasing", and is called the bounds max aliasing wherever a screen value is shown too.
pub(crate) fn worst_words(worst: SummaryMetric) -> (&'static str, &'static str) {
    if worst.name() == "max_aliasing" {
        ("max aliasing", "max")
    } else {
        ("worst on screen", "worst")
    }
}

/// Every summary metric of a summary (the screen metrics only with geometry), in registry order.
pub fn summary_values(s: &Summary) -> Vec<(SummaryMetric, f64)> {
    SummaryMetric::all()
        .filter(|m| shown_for(m.def(), s))
        .map(|m| (m, m.value(s)))
        .collect()
}

/// The summary as flat JSON keys, in registry order (`summary.json`, `recommendation.json`).
pub fn summary_json(s: &Summary) -> Vec<(&'static str, serde_json::Value)> {
    SUMMARY
        .iter()
        .filter(|d| shown_for(d, s))
        .map(|d| (d.name, (d.value)(s).json()))
        .collect()
}

/// Whether a metric belongs in the outputs of a summary: screen metrics only with geometry.
fn shown_for(d: &SummaryDef, s: &Summary) -> bool {
    (!d.screen || s.screen.is_some())
        && (d.name != SEAM_CROSSINGS || s.seam_crossings.is_some())
        && (!is_light_motion(d.name) || s.light.is_some())
        && (!TRUTH_SUMMARY.contains(&d.name) || s.truth.is_some())
        && (!CACHE_METRICS.contains(&d.name) || s.cache.is_some())
        && (d.name != UPDATE_FLICKER || s.truth.is_some())
        && (d.name != SHADOW_MS || s.cost.shadow_ms.is_some())
        && (d.name != COST_INDEX || s.cost.cost_index.is_some())
        && (!COST_COUNTS.contains(&d.name) || s.cost.counts.is_some())
        && (!COST_MEANS.contains(&d.name) || s.cost.means.is_some())
        && (d.name != COST_INDEX_MEAN || s.cost.means.is_some_and(|m| m.cost_index_mean.is_some()))
        && (d.name != SHADOW_MS_MEAN || s.cost.means.is_some_and(|m| m.shadow_ms_mean.is_some()))
}

/// The cost counts (summary and per cascade): with scene geometry unless `[cost] counts =
/// false`; absent from `summary.json` otherwise, `n/a` in a table that has the column.
const COST_COUNTS: [&str; 4] = [
    "caster_objects",
    "caster_triangles",
    "caster_triangles_inside",
    "raster_fragments",
];

/// The cost counts' means over the camera path (summary and per cascade): only where measured
/// (`crate::analysis::cost::means_measurable`), absent from every output otherwise.
pub(crate) const COST_MEANS: [&str; 7] = [
    "caster_objects_mean",
    "caster_triangles_mean",
    "caster_triangles_inside_mean",
    "raster_fragments_mean",
    "texels_cleared_mean",
    COST_INDEX_MEAN,
    SHADOW_MS_MEAN,
];

const COST_INDEX_MEAN: &str = "cost_index_mean";
const SHADOW_MS_MEAN: &str = "shadow_ms_mean";

/// The optional columns of a per-configuration table (`sweep.csv`, `compare.csv`) beyond the
/// screen metrics: `shadow_ms` only with a calibrated cost model, the means over the path only
/// when the rows measured them, `shadow_ms_mean` only with both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct RowColumns {
    /// Scene geometry: the screen metrics and the cost counts.
    pub(crate) screen: bool,
    /// `[cost] ns_per_*`: `shadow_ms`.
    pub(crate) calibrated: bool,
    /// The rows carry the means over the path ([`COST_MEANS`]).
    pub(crate) means: bool,
    /// Some row caches cascades: the cached-cascade figures ([`ROW_CACHE`]; n/a in a row that
    /// renders every cascade every frame).
    pub(crate) cache: bool,
}

/// The cached-cascade figures that are columns of a per-configuration table when some row
/// caches cascades (`update_flicker` needs the ground-truth pass, which sweep rows skip).
const ROW_CACHE: [&str; 6] = [
    "renders_per_frame",
    "stale_coverage_violations",
    "stale_coverage_fraction",
    "stale_margin",
    "stale_margin_world",
    "update_drift",
];

impl RowColumns {
    /// Whether the optional column `name` is in a table of these columns (true for a column
    /// that is not optional).
    fn has(self, name: &str) -> bool {
        if name == SHADOW_MS_MEAN {
            self.calibrated && self.means
        } else if name == SHADOW_MS {
            self.calibrated
        } else if COST_MEANS.contains(&name) {
            self.means
        } else if ROW_CACHE.contains(&name) {
            self.cache
        } else {
            true
        }
    }
}

/// Whether a summary metric is a column only in some tables ([`RowColumns`]).
pub(crate) fn optional_row_column(name: &str) -> bool {
    name == SHADOW_MS || COST_MEANS.contains(&name) || ROW_CACHE.contains(&name)
}

/// The cached-cascade metrics (summary and per cascade): only with `[shadow] update_every`
/// holding some cascade, absent from every output otherwise.
pub(crate) const CACHE_METRICS: [&str; 9] = [
    "renders_per_frame",
    "update_every",
    "update_rate",
    "stale_coverage_violations",
    "stale_coverage_fraction",
    "stale_margin",
    "stale_margin_world",
    "update_drift",
    UPDATE_FLICKER,
];

/// The cached-cascade metric that also needs the ground-truth pass.
const UPDATE_FLICKER: &str = "update_flicker";

/// Whether a metric is a column of a per-configuration row: as [`shown_for`], but
/// `cost_index` is a column whenever the counts are (n/a where it has no reference: a
/// configured setting that needs no cascade).
fn in_row_for(d: &SummaryDef, s: &Summary, cols: RowColumns) -> bool {
    d.in_rows
        && cols.has(d.name)
        && (shown_for(d, s)
            || ((d.name == COST_INDEX || COST_COUNTS.contains(&d.name) || optional_row_column(d.name))
                && s.screen.is_some())
            || ROW_CACHE.contains(&d.name))
}

/// The one cost metric in milliseconds: only with a calibrated model (`[cost] ns_per_*`),
/// never from the default weights.
const SHADOW_MS: &str = "shadow_ms";

/// The cost relative to the configured setting: absent when there is nothing to relate it to.
const COST_INDEX: &str = "cost_index";

/// The moving-light metrics (`light_crawl*`, `light_jump*`, in the summary and per cascade):
/// only when the light moves ([`Summary::light`]), absent from every output under a still
/// light. (`light_near` and `light_far` are not among them.)
fn is_light_motion(name: &str) -> bool {
    name.starts_with("light_crawl") || name.starts_with("light_jump")
}

/// The summary metrics of the ground-truth pass: only in the outputs of analyses that ran it.
pub(crate) const TRUTH_SUMMARY: [&str; 9] = [
    "acne_fraction",
    "edge_error_fraction",
    "leak_fraction",
    "flicker_snapped",
    "flicker_unsnapped",
    "flicker_edge_snapped",
    "flicker_edge_unsnapped",
    "flicker_acne_snapped",
    "flicker_acne_unsnapped",
];

/// The per-cascade metrics of the ground-truth pass: only in `cascades.csv` when it ran.
pub(crate) const TRUTH_CASCADE: [&str; 6] = [
    "acne_fraction",
    "edge_error_fraction",
    "leak_fraction",
    "bias_needed",
    "slope_bias_needed",
    "peter_pan",
];

/// The one summary metric an analysis computes only on request ([`crate::analysis::AnalysisOptions::seams`]):
/// absent from the outputs of analyses without it (sweep rows).
const SEAM_CROSSINGS: &str = "seam_crossings";

/// The setting columns every per-configuration table starts with.
pub(crate) const SETTING_COLUMNS: [&str; 4] = ["lambda", "cascades", "resolution", "fit"];

/// With scene geometry, rows also say which depths the splits divide (`bounds` or `visible`).
pub(crate) const SPLIT_RANGE_COLUMN: &str = "split_range";

/// The columns every per-configuration table shares (`sweep.csv`, `compare.csv`): the setting,
/// then the summary metrics marked `in_rows`. A contract: users' scripts and CI baselines read
/// them by name. The screen metrics are columns only with scene geometry (`screen`).
pub(crate) fn summary_columns(cols: RowColumns) -> Vec<&'static str> {
    SETTING_COLUMNS
        .into_iter()
        .chain(cols.screen.then_some(SPLIT_RANGE_COLUMN))
        .chain(
            SUMMARY
                .iter()
                .filter(|d| d.in_rows && (cols.screen || !d.screen) && cols.has(d.name))
                .map(|d| d.name),
        )
        .collect()
}

/// The fields of [`summary_columns`] for one configuration (`lambda` may be empty where a
/// split rule has none).
pub(crate) fn summary_fields(
    lambda: String,
    cascades: usize,
    resolution: u32,
    fit: &str,
    split_range: SplitRange,
    s: &Summary,
    cols: RowColumns,
) -> Result<Vec<String>> {
    let mut fields = vec![lambda, cascades.to_string(), resolution.to_string(), fit.to_string()];
    if s.screen.is_some() {
        fields.push(split_range.name().to_string());
    }
    for d in SUMMARY.iter().filter(|d| in_row_for(d, s, cols)) {
        fields.push((d.value)(s).csv(d.name)?);
    }
    Ok(fields)
}

/// The lines of `analyze`'s stdout summary for the metrics shown with `f32` on or off:
/// (name, formatted value, brief).
pub(crate) fn summary_lines(s: &Summary, f32_block: bool) -> Vec<(&'static str, String, &'static str)> {
    SUMMARY
        .iter()
        .filter(|d| shown_for(d, s))
        .filter_map(|d| {
            let v = (d.value)(s);
            let text = match (d.shown, f32_block) {
                // Numbers for people (crate::output::short_number): "0", "< 1e-9", 4 significant digits.
                (Shown::Fixed, false) | (Shown::Scientific, false) | (Shown::F32Scientific, true) => {
                    crate::output::short_number(v.as_f64())
                }
                (Shown::Whole, false) => match v {
                    Value::Count(n) => n.to_string(),
                    other => format!("{}", other.as_f64()),
                },
                _ => return None,
            };
            Some((d.name, text, d.brief))
        })
        .collect()
}

/// One per-cascade metric.
#[derive(Debug, Clone, Copy)]
pub struct CascadeDef {
    pub name: &'static str,
    pub unit: &'static str,
    pub direction: Direction,
    pub help: &'static str,
    /// A screen metric: only with scene geometry (absent from every output without it).
    pub screen: bool,
    pub value: fn(&CascadeReport) -> Value,
}

/// Every per-cascade metric, in the order of `cascades.csv` (after `cascade`).
pub(crate) const CASCADE: &[CascadeDef] = &[
    CascadeDef {
        name: "near",
        unit: "world units",
        direction: Direction::Neither,
        help: "view depth where the cascade starts (world units)",
        screen: false,
        value: |c| Value::Real(c.near),
    },
    CascadeDef {
        name: "far",
        unit: "world units",
        direction: Direction::Neither,
        help: "view depth where the cascade ends (world units)",
        screen: false,
        value: |c| Value::Real(c.far),
    },
    CascadeDef {
        name: "radius",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "minimal bounding-sphere radius of the slice (world units)",
        screen: false,
        value: |c| Value::Real(c.radius),
    },
    CascadeDef {
        name: "width",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "window width in light space (world units)",
        screen: false,
        value: |c| Value::Real(c.width),
    },
    CascadeDef {
        name: "height",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "window height in light space (world units)",
        screen: false,
        value: |c| Value::Real(c.height),
    },
    CascadeDef {
        name: "texel_size",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "world size of one shadow texel",
        screen: false,
        value: |c| Value::Real(c.texel_size),
    },
    CascadeDef {
        name: "centre_x",
        unit: "world units",
        direction: Direction::Neither,
        help: "window centre along the light's x axis at frame 0 (world units)",
        screen: false,
        value: |c| Value::Real(c.centre_x),
    },
    CascadeDef {
        name: "centre_y",
        unit: "world units",
        direction: Direction::Neither,
        help: "window centre along the light's y axis at frame 0 (world units)",
        screen: false,
        value: |c| Value::Real(c.centre_y),
    },
    CascadeDef {
        name: "centre_x_texels",
        unit: "texels",
        direction: Direction::Neither,
        help: "window centre along the light's x axis at frame 0, in texels of this cascade",
        screen: false,
        value: |c| Value::Real(c.centre_x_texels),
    },
    CascadeDef {
        name: "centre_y_texels",
        unit: "texels",
        direction: Direction::Neither,
        help: "window centre along the light's y axis at frame 0, in texels of this cascade",
        screen: false,
        value: |c| Value::Real(c.centre_y_texels),
    },
    CascadeDef {
        name: "light_near",
        unit: "world units",
        direction: Direction::Neither,
        help: "light-space depth where the cascade's render starts",
        screen: false,
        value: |c| Value::Real(c.light_near),
    },
    CascadeDef {
        name: "light_far",
        unit: "world units",
        direction: Direction::Neither,
        help: "light-space depth where the cascade's render ends",
        screen: false,
        value: |c| Value::Real(c.light_far),
    },
    CascadeDef {
        name: "coverage_violations",
        unit: "count",
        direction: Direction::HigherIsWorse,
        help: "slice corners outside the window over the path",
        screen: false,
        value: |c| Value::Count(c.coverage_violations),
    },
    CascadeDef {
        name: "coverage_worst_texels",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "farthest a slice corner got outside the window (texels)",
        screen: false,
        value: |c| Value::Real(c.coverage_worst_texels),
    },
    CascadeDef {
        name: "min_slack_texels",
        unit: "texels",
        // Less room between the slice and its window edge: closer to a coverage hole.
        direction: Direction::LowerIsWorse,
        help: "smallest margin between a slice corner and the window edge (texels)",
        screen: false,
        value: |c| Value::Real(c.min_slack_texels),
    },
    CascadeDef {
        name: "max_aliasing",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "aliasing ratio at the cascade's near edge",
        screen: false,
        value: |c| Value::Real(c.max_aliasing),
    },
    CascadeDef {
        name: "min_aliasing",
        unit: "texel / pixel",
        direction: Direction::HigherIsWorse,
        help: "aliasing ratio at the cascade's far edge",
        screen: false,
        value: |c| Value::Real(c.min_aliasing),
    },
    CascadeDef {
        name: "lookup_error_max",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "largest static f32 lookup error S7 in this cascade (texels)",
        screen: false,
        value: |c| Value::Real(c.lookup_error_max),
    },
    CascadeDef {
        name: "lookup_error_rms",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "RMS static f32 lookup error S7 in this cascade (texels)",
        screen: false,
        value: |c| Value::Real(c.lookup_error_rms),
    },
    CascadeDef {
        name: "split_jump",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "texel size of the next cascade over this one's: the jump at this cascade's far split (0 for the last)",
        screen: false,
        value: |c| Value::Real(c.split_jump),
    },
    CascadeDef {
        name: "band_near",
        unit: "world units",
        direction: Direction::Neither,
        help: "view depth where the blend band at this cascade's far split starts (equal to band_far when there is none)",
        screen: false,
        value: |c| Value::Real(c.band_near),
    },
    CascadeDef {
        name: "band_far",
        unit: "world units",
        direction: Direction::Neither,
        help: "view depth where that blend band ends",
        screen: false,
        value: |c| Value::Real(c.band_far),
    },
    CascadeDef {
        name: "overlap_area_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "texels of this cascade's map that render its far band (also rendered by the next cascade), over all maps' texels",
        screen: false,
        value: |c| Value::Real(c.overlap_area_fraction),
    },
    CascadeDef {
        name: "light_crawl",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "moving light: this cascade's RMS sub-texel drift (S3) over the frame pairs between light updates, with the configured snapping, worst over the motion paths; only when the light moves",
        screen: false,
        value: |c| Value::Real(c.light.map_or(0.0, |l| l.crawl)),
    },
    CascadeDef {
        name: "light_jump",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "moving light: this cascade's largest move of a world-fixed probe's texel coordinates at a light update, in windows without snapping, worst over the motion paths; only when the light moves",
        screen: false,
        value: |c| Value::Real(c.light.map_or(0.0, |l| l.jump)),
    },
    CascadeDef {
        name: "update_every",
        unit: "frames",
        direction: Direction::Neither,
        help: "cached cascades: frames between two renders of this cascade; only with [shadow] update_every",
        screen: false,
        value: |c| Value::Count(c.cache.map_or(1, |x| x.update_every)),
    },
    CascadeDef {
        name: "update_rate",
        unit: "",
        direction: Direction::Neither,
        help: "cached cascades: 1 / update_every, the share of frames that render this cascade (what its render costs per frame, relative to every frame); only with [shadow] update_every",
        screen: false,
        value: |c| Value::Real(c.cache.map_or(1.0, |x| x.update_rate)),
    },
    CascadeDef {
        name: "stale_coverage_violations",
        unit: "count",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: frames in which this cascade kept an earlier window that does not hold the current slice, over the motion paths; only with [shadow] update_every",
        screen: false,
        value: |c| Value::Count(c.cache.map_or(0, |x| x.figures.stale_coverage_violations)),
    },
    CascadeDef {
        name: "stale_coverage_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: stale_coverage_violations over the frames walked; only with [shadow] update_every",
        screen: false,
        value: |c| Value::Real(c.cache.map_or(0.0, |x| x.figures.stale_coverage_fraction)),
    },
    CascadeDef {
        name: "stale_margin",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: the smallest growth of this cascade's held window, in its texels on every side, that covers the slice in every stale frame; only with [shadow] update_every",
        screen: false,
        value: |c| Value::Real(c.cache.map_or(0.0, |x| x.figures.stale_margin)),
    },
    CascadeDef {
        name: "stale_margin_world",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: stale_margin in world units; only with [shadow] update_every",
        screen: false,
        value: |c| Value::Real(c.cache.map_or(0.0, |x| x.figures.stale_margin_world)),
    },
    CascadeDef {
        name: "update_drift",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cached cascades: RMS sub-texel drift (S3) of this cascade over the frame pairs at which it is rendered again, configured snapping; only with [shadow] update_every",
        screen: false,
        value: |c| Value::Real(c.cache.map_or(0.0, |x| x.figures.update_drift)),
    },
    CascadeDef {
        name: "update_flicker",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cached cascades, ground truth: S5 over the receiver steps this cascade serves at its renders; n/a when it serves none; only with [shadow] update_every and ground_truth",
        screen: true,
        value: |c| Value::maybe(c.cache.and_then(|x| x.figures.update_flicker)),
    },
    CascadeDef {
        name: "acne_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: share of this cascade's receiver points at frame 0 that are truly lit but the map shadows while every texel read holds their own surface (acne); n/a under 1000 points",
        screen: true,
        value: |c| Value::maybe(c.truth.as_ref().and_then(|t| t.acne_fraction)),
    },
    CascadeDef {
        name: "edge_error_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: share of this cascade's receiver points at frame 0 wrong because the texels read hold another surface (the blocky edge); n/a under 1000 points",
        screen: true,
        value: |c| Value::maybe(c.truth.as_ref().and_then(|t| t.edge_error_fraction)),
    },
    CascadeDef {
        name: "leak_fraction",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: share of this cascade's receiver points at frame 0 that are truly shadowed but lit because of the bias; n/a under 1000 points",
        screen: true,
        value: |c| Value::maybe(c.truth.as_ref().and_then(|t| t.leak_fraction)),
    },
    CascadeDef {
        name: "bias_needed",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "ground truth: smallest depth bias (along the light) leaving acne on at most 0.1 % of this cascade's points, plus a margin (0.1 % of it and one step of the configured depth format; bias.csv has every format); n/a under 1000 points",
        screen: true,
        value: |c| Value::maybe(c.truth.as_ref().and_then(|t| t.chosen_bias)),
    },
    CascadeDef {
        name: "slope_bias_needed",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "ground truth: smallest slope bias alone (times the depth slope per texel) doing the same, exact depths",
        screen: true,
        value: |c| Value::maybe(c.truth.as_ref().and_then(|t| t.slope_bias)),
    },
    CascadeDef {
        name: "peter_pan",
        unit: "world units",
        direction: Direction::HigherIsWorse,
        help: "ground truth: largest distance along the receiver from a caster to where its shadow starts, at bias_needed",
        screen: true,
        value: |c| Value::maybe(c.truth.as_ref().and_then(|t| t.peter_pan)),
    },
    CascadeDef {
        name: "screen_pixels",
        unit: "",
        direction: Direction::Neither,
        help: "share of the lit-facing receiver pixels this cascade serves",
        screen: true,
        value: |c| Value::Real(c.screen.map_or(0.0, |x| x.pixels)),
    },
    CascadeDef {
        name: "band_pixels",
        unit: "",
        direction: Direction::Neither,
        help: "share of the lit-facing receiver pixels inside the blend band at this cascade's far split",
        screen: true,
        value: |c| Value::Real(c.screen.map_or(0.0, |x| x.band_pixels)),
    },
    CascadeDef {
        name: "texel_utilization",
        unit: "",
        direction: Direction::LowerIsWorse,
        help: "area of the light-space rectangle around the cascade's receiver points over its window's area",
        screen: true,
        value: |c| Value::Real(c.screen.map_or(0.0, |x| x.texel_utilization)),
    },
    CascadeDef {
        name: "caster_objects",
        unit: "draws",
        direction: Direction::HigherIsWorse,
        help: "cost: this cascade's draw calls at frame 0 (objects whose world bounds meet its caster volume)",
        screen: true,
        value: |c| c.cost.counts.map_or(Value::Missing, |x| Value::Count(x.caster_objects)),
    },
    CascadeDef {
        name: "caster_triangles",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: the triangles of those objects",
        screen: true,
        value: |c| c.cost.counts.map_or(Value::Missing, |x| Value::Count(x.caster_triangles)),
    },
    CascadeDef {
        name: "caster_triangles_inside",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: those triangles that intersect the caster volume",
        screen: true,
        value: |c| c.cost.counts.map_or(Value::Missing, |x| Value::Count(x.caster_triangles_inside)),
    },
    CascadeDef {
        name: "raster_fragments",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: the casters' projected triangle area clipped to the window, in texels (overdraw included)",
        screen: true,
        value: |c| c.cost.counts.map_or(Value::Missing, |x| Value::Real(x.raster_fragments)),
    },
    CascadeDef {
        name: "texels_cleared",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: resolution^2",
        screen: false,
        value: |c| Value::Count(c.cost.texels_cleared),
    },
    CascadeDef {
        name: "bytes_written",
        unit: "bytes",
        direction: Direction::HigherIsWorse,
        help: "cost: bytes the clear writes (texels_cleared x 4)",
        screen: false,
        value: |c| Value::Count(c.cost.bytes_written),
    },
    CascadeDef {
        name: "cost_index",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cost: this cascade's share of the setting's cost model (the cascades add up to the setting's cost_index)",
        screen: true,
        value: |c| Value::maybe(c.cost.cost_index),
    },
    CascadeDef {
        name: "shadow_ms",
        unit: "ms",
        direction: Direction::HigherIsWorse,
        help: "cost: this cascade's time from the calibrated model; only when calibrated",
        screen: true,
        value: |c| Value::maybe(c.cost.shadow_ms),
    },
    CascadeDef {
        name: "caster_objects_mean",
        unit: "draws",
        direction: Direction::HigherIsWorse,
        help: "cost: this cascade's draw calls per frame on average over the motion paths (0 in the frames it is held)",
        screen: true,
        value: |c| c.cost.means.map_or(Value::Missing, |m| Value::Real(m.caster_objects_mean)),
    },
    CascadeDef {
        name: "caster_triangles_mean",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: its caster triangles per frame on average over the motion paths",
        screen: true,
        value: |c| c.cost.means.map_or(Value::Missing, |m| Value::Real(m.caster_triangles_mean)),
    },
    CascadeDef {
        name: "caster_triangles_inside_mean",
        unit: "triangles",
        direction: Direction::HigherIsWorse,
        help: "cost: its caster triangles inside the volume per frame on average over the motion paths",
        screen: true,
        value: |c| c.cost.means.map_or(Value::Missing, |m| Value::Real(m.caster_triangles_inside_mean)),
    },
    CascadeDef {
        name: "raster_fragments_mean",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: its fragments per frame on average over the motion paths",
        screen: true,
        value: |c| c.cost.means.map_or(Value::Missing, |m| Value::Real(m.raster_fragments_mean)),
    },
    CascadeDef {
        name: "texels_cleared_mean",
        unit: "texels",
        direction: Direction::HigherIsWorse,
        help: "cost: its cleared texels per frame on average over the motion paths (resolution^2 over update_every, about)",
        screen: true,
        value: |c| c.cost.means.map_or(Value::Missing, |m| Value::Real(m.texels_cleared_mean)),
    },
    CascadeDef {
        name: "cost_index_mean",
        unit: "",
        direction: Direction::HigherIsWorse,
        help: "cost: this cascade's share of the setting's cost_index_mean (the cascades add up to it)",
        screen: true,
        value: |c| Value::maybe(c.cost.means.and_then(|m| m.cost_index_mean)),
    },
    CascadeDef {
        name: "shadow_ms_mean",
        unit: "ms",
        direction: Direction::HigherIsWorse,
        help: "cost: this cascade's calibrated time per frame over the motion paths; only when calibrated",
        screen: true,
        value: |c| Value::maybe(c.cost.means.and_then(|m| m.shadow_ms_mean)),
    },
];

handle!(
    /// A per-cascade metric: a handle on its [`CASCADE`] entry (cascade 0 is the nearest).
    CascadeMetric,
    CascadeDef,
    CASCADE,
    "per-cascade"
);

impl CascadeMetric {
    pub(crate) fn value(self, c: &CascadeReport) -> f64 {
        (self.def().value)(c).as_f64()
    }

    /// Whether cascade `c`'s analysis measured this metric (as [`SummaryMetric::measured`]).
    pub(crate) fn measured(self, c: &CascadeReport) -> bool {
        let d = self.def();
        (!d.screen || c.screen.is_some() || TRUTH_CASCADE.contains(&d.name))
            && (!is_light_motion(d.name) || c.light.is_some())
            && (!TRUTH_CASCADE.contains(&d.name) || c.truth.is_some())
            && (!CACHE_METRICS.contains(&d.name) || c.cache.is_some())
            && (d.name != UPDATE_FLICKER || c.truth.is_some())
            && (d.name != SHADOW_MS || c.cost.shadow_ms.is_some())
            && (!COST_COUNTS.contains(&d.name) || c.cost.counts.is_some())
            && (!COST_MEANS.contains(&d.name) || c.cost.means.is_some())
            && (d.name != COST_INDEX_MEAN || c.cost.means.is_some_and(|m| m.cost_index_mean.is_some()))
            && (d.name != SHADOW_MS_MEAN || c.cost.means.is_some_and(|m| m.shadow_ms_mean.is_some()))
    }

    /// How to measure this metric when a cascade does not have it.
    pub(crate) fn how_to_measure(self) -> &'static str {
        if TRUTH_CASCADE.contains(&self.name()) {
            "it comes from the ground-truth pass: set `[analysis] ground_truth = true` in the config (it needs scene geometry)"
        } else if self.def().screen {
            "it is a screen metric: give the config scene geometry (scene.ground, [[scene.box]] or scene.gltf)"
        } else if is_light_motion(self.name()) {
            "it is measured only under a moving light: give the config a light motion ([motion.light])"
        } else if CACHE_METRICS.contains(&self.name()) {
            "it is measured only with cached cascades: set `[shadow] update_every` (a value above 1; the flicker also needs ground_truth)"
        } else {
            "it is not measured for this config"
        }
    }
}

/// The columns of `cascades.csv` (the screen columns only with scene geometry, the
/// moving-light columns only when the light moves, the ground-truth columns only when that pass
/// ran, the cached-cascade columns only with cached cascades, `shadow_ms` only with a calibrated
/// cost model).
#[allow(clippy::fn_params_excessive_bools)]
pub fn cascade_columns(
    screen: bool,
    light: bool,
    truth: bool,
    cache: bool,
    calibrated: bool,
    means: bool,
) -> Vec<&'static str> {
    std::iter::once("cascade")
        .chain(
            CASCADE
                .iter()
                .filter(|d| {
                    (screen || !d.screen)
                        && (light || !is_light_motion(d.name))
                        && (truth || !TRUTH_CASCADE.contains(&d.name))
                        && (cache || !CACHE_METRICS.contains(&d.name))
                        && (truth || d.name != UPDATE_FLICKER)
                        && (calibrated || d.name != SHADOW_MS)
                        && (means || !COST_MEANS.contains(&d.name))
                        && ((calibrated && means) || d.name != SHADOW_MS_MEAN)
                })
                .map(|d| d.name),
        )
        .collect()
}

/// The fields of [`cascade_columns`] for one cascade.
pub fn cascade_fields(c: &CascadeReport) -> Result<Vec<String>> {
    let mut fields = vec![c.cascade.to_string()];
    for d in CASCADE.iter().filter(|d| {
        (!d.screen || c.screen.is_some())
            && (!is_light_motion(d.name) || c.light.is_some())
            && (c.truth.is_some() || !TRUTH_CASCADE.contains(&d.name))
            && (c.cache.is_some() || !CACHE_METRICS.contains(&d.name))
            && (c.truth.is_some() || d.name != UPDATE_FLICKER)
            && (d.name != SHADOW_MS || c.cost.shadow_ms.is_some())
            && (!COST_MEANS.contains(&d.name) || c.cost.means.is_some())
            && (d.name != SHADOW_MS_MEAN || c.cost.means.is_some_and(|m| m.shadow_ms_mean.is_some()))
    }) {
        fields.push((d.value)(c).csv(d.name)?);
    }
    Ok(fields)
}

/// The Markdown table of a set of metrics, as docs/metrics.md and docs/check.md show it.
#[cfg(test)]
fn table<'a>(rows: impl Iterator<Item = (&'a str, &'a str, &'a str, Direction)>) -> String {
    let mut out = String::from("| metric | unit | meaning | worse |\n|---|---|---|---|\n");
    for (name, unit, help, direction) in rows {
        let unit = if unit.is_empty() { "-" } else { unit };
        out.push_str(&format!("| `{name}` | {unit} | {help} | {} |\n", direction.word()));
    }
    out
}

/// The docs' table of summary metrics (docs/metrics.md, docs/check.md): a test keeps the docs
/// in step with it.
#[cfg(test)]
fn markdown_table() -> String {
    table(SUMMARY.iter().map(|d| (d.name, d.unit, d.help, d.direction)))
}

/// The docs' table of per-cascade metrics (docs/check.md).
#[cfg(test)]
fn markdown_cascade_table() -> String {
    table(CASCADE.iter().map(|d| (d.name, d.unit, d.help, d.direction)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_within_a_kind() {
        for names in [
            SUMMARY.iter().map(|d| d.name).collect::<Vec<_>>(),
            CASCADE.iter().map(|d| d.name).collect::<Vec<_>>(),
        ] {
            let mut dedup = names.clone();
            dedup.sort_unstable();
            dedup.dedup();
            assert_eq!(dedup.len(), names.len());
        }
    }

    #[test]
    fn the_docs_show_the_registry() {
        let metrics = include_str!("../docs/metrics.md");
        let check = include_str!("../docs/check.md");
        let summary = markdown_table();
        assert!(metrics.contains(&summary), "docs/metrics.md: paste\n{summary}");
        assert!(check.contains(&summary), "docs/check.md: paste\n{summary}");
        let cascade = markdown_cascade_table();
        assert!(check.contains(&cascade), "docs/check.md: paste\n{cascade}");
    }
}
