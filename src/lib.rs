//! csm-lab: how good are your cascaded shadow maps, before anyone renders a frame?
//!
//! The crate builds the cascades an engine would build (practical splits, a sphere or AABB
//! fit, texel snapping) for a camera, a directional light and the scene's bounds, and measures
//! texel density and perspective aliasing against view depth, shimmer under camera motion,
//! and coverage. Conventions (handedness, light direction, view depth) are stated once in
//! `csm_core::geometry`; every formula is stated in `docs/metrics.md`, and every metric is named once,
//! in the registry [`metric`].
//!
//! Pipeline: [`config`] → `csm_core::scene` (plain domain values) → the math of the
//! [`csm_core`] crate (depth range, splits, cascades, fitting, snapping, metrics, the path walk,
//! shimmer, screen statistics, ground truth) → [`analysis`] → [`report`], [`figures`]. The math
//! crate sees only the domain values and knows no file format or CLI; each command in
//! [`commands`] runs that pipeline and hands its result to the report layer. Where each job
//! lives, the invariants and how to add a metric, an engine, a sweep axis or an output:
//! `docs/architecture.md`.

pub mod analysis;
pub mod app;
pub mod cli;
pub mod commands;
pub mod config;
pub mod drift_table;
pub mod error;
pub mod figures;
pub mod load;
pub mod metric;
pub mod output;
pub mod presets;
pub mod report;
pub mod suggest;

pub use analysis::{analyze, Analysis, AnalysisOptions, Summary};
pub use config::Config;
pub use error::{Error, Result};
