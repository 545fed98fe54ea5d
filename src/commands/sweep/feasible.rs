//! Feasibility before a sweep: whether any configuration of the grid can be acceptable
//! ([`rank::acceptable`]), decided from the first frames of the camera path.
//!
//! Both failures a row can have are seen early. Coverage violations add up over frames, so
//! one in the first `K` frames stays in the whole path. Snapped shimmer S3 is the RMS
//! `sqrt(Σ ms / P)` of the mean-square drifts `ms` of the `P ≤ (F − 1) m` (frame pair,
//! cascade) entries of an `F`-frame path with `m` cascades: the first `K` frames' entries alone
//! bound it from below, `S3 ≥ sqrt(Σ_K ms / ((F − 1) m))`. When every row fails one of the two
//! within the first frames, nothing can qualify, and the sweep says so before running (a grid
//! of tight-box fits under a turning camera took 14 to 60 s to find that out).

use crate::analysis::{analyze, AnalysisOptions};
use crate::commands::sweep::grid::Setting;
use crate::commands::sweep::rank::STABLE_SHIMMER;
use crate::config::{Config, MotionPath};
use crate::error::{Error, GridError, Result};

/// Frames of the path the check walks per row.
pub(crate) const PREFIX_FRAMES: usize = 8;

/// What the first frames proved about a grid in which no row can qualify.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Infeasible {
    pub rows: usize,
    /// Rows needing no cascades.
    pub no_cascades: usize,
    /// Rows with a slice corner outside its window in the first frames.
    pub coverage_misses: usize,
    /// Rows whose lower bound of snapped shimmer is above [`STABLE_SHIMMER`].
    pub unstable: usize,
    pub prefix: usize,
    pub frames: usize,
}

impl Infeasible {
    /// The sweep's "Nothing qualifies" sentence, as far as the first frames tell it, for a
    /// sweep that stops there.
    pub(crate) fn message(&self) -> String {
        format!(
            "{}; the sweep was not run. Widen the grid (another fit, e.g. --fit sphere, or snapping that keeps the \
             window size) or the motion",
            self.sentence()
        )
    }

    /// The sentence alone.
    pub(crate) fn sentence(&self) -> String {
        format!(
            "Nothing qualifies: of {} configurations, {} miss slice corners (coverage_violations > 0) and {} shimmer \
             when snapped (shimmer_snapped > {STABLE_SHIMMER} texel){}, which the first {} of the path's {} frames \
             already show",
            self.rows,
            self.coverage_misses,
            self.unstable,
            if self.no_cascades > 0 {
                format!(", {} need no cascades", self.no_cascades)
            } else {
                String::new()
            },
            self.prefix,
            self.frames,
        )
    }
}

/// Whether the check applies: one generated camera path longer than the prefix, a still light.
fn applies(base: &Config) -> bool {
    !matches!(base.motion.path, MotionPath::File { .. })
        && base.motion.extra.is_empty()
        && !base.motion.light.moves()
        && base.motion.frames > PREFIX_FRAMES
}

/// Some when the first [`PREFIX_FRAMES`] frames prove that no row of `settings` can be
/// acceptable; None when one might be (or the check does not apply).
pub(crate) fn infeasible(base: &Config, settings: &[Setting]) -> Result<Option<Infeasible>> {
    if !applies(base) || settings.is_empty() {
        return Ok(None);
    }
    let opts = AnalysisOptions {
        frame_rows: true,
        ..AnalysisOptions::summary_only()
    };
    let mut out = Infeasible {
        rows: settings.len(),
        no_cascades: 0,
        coverage_misses: 0,
        unstable: 0,
        prefix: PREFIX_FRAMES,
        frames: base.motion.frames,
    };
    for s in settings {
        // A point the config cannot hold is refused as the sweep refuses it.
        let mut c = s.apply(base).map_err(|e| {
            Error::from(GridError::Point {
                point: s.label(),
                source: Box::new(e),
            })
        })?;
        if !applies(&c) {
            return Ok(None);
        }
        let frames = c.motion.frames;
        out.frames = out.frames.max(frames);
        // The walk does not read the geometry (probes come from the scene bounds): leave out
        // the visibility pass, unless the depth range is fitted to what is visible.
        if !c.shadow.fit_depth_to_visible {
            c.geometry = None;
        }
        c.motion.frames = PREFIX_FRAMES;
        let a = analyze(&c, &opts);
        if !a.summary.cascades_needed {
            out.no_cascades += 1;
            continue;
        }
        let covered = a.summary.coverage_violations == 0;
        let m = a.rig().map_or(1, |r| r.cascade_count());
        let sum_ms: f64 = a
            .snapped()
            .map_or(0.0, |p| p.frames.iter().map(|f| f.phase_drift_rms.powi(2)).sum());
        let bound = (sum_ms / ((frames - 1) * m) as f64).sqrt();
        // A hair of margin: `phase_drift_rms` is the square root of the walk's own sum.
        let unstable = bound > STABLE_SHIMMER * (1.0 + 1e-9);
        out.coverage_misses += !covered as usize;
        out.unstable += unstable as usize;
        if covered && !unstable {
            return Ok(None);
        }
    }
    Ok(Some(out))
}
