//! csm-lab: how good are your cascaded shadow maps, before anyone renders a frame?
//!
//! The crate builds the cascades an engine would build (practical splits, a sphere or AABB
//! fit, texel snapping) for a camera, a directional light and the scene's bounds, and measures
//! texel density and perspective aliasing against view depth, shimmer under camera motion,
//! and coverage. Conventions (handedness, light direction, view depth) are stated once in
//! [`geometry`]; every formula is stated in `docs/metrics.md`, and every metric is named once,
//! in the registry [`metric`].
//!
//! Pipeline: [`config`] → [`scene`] (plain domain values) → [`depth_range`] → [`splits`] →
//! [`cascades`] ([`fitting`], [`snapping`]) → [`metrics`], [`walk`] ([`shimmer`], [`precision`])
//! → [`analysis`] → [`report`], [`figures`]. The core (`src/core/`) sees only the domain values;
//! each command in [`commands`] runs that pipeline and hands its result to the report layer.

pub mod analysis;
pub mod app;
pub mod cli;
pub mod commands;
pub mod config;
pub mod core;
pub mod drift_table;
pub mod error;
pub mod figures;
pub mod load;
pub mod metric;
pub mod output;
pub mod presets;
pub mod report;
pub mod suggest;

// Short paths for the modules most callers use.
pub use crate::commands::{bench, check, compare, stress, sweep};
pub use crate::core::{
    cascades, depth_range, fitting, geometry, light_motion, mesh, metrics, motion, precision, rng, scene, screen,
    seams, shade, shimmer, snapping, splits, sun, visibility, walk,
};
pub use crate::figures as plots;

pub use analysis::{analyze, Analysis, AnalysisOptions, Summary};
pub use config::Config;
pub use error::{Error, Result};
