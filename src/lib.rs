//! csm-lab: how good are your cascaded shadow maps, before anyone renders a frame?
//!
//! The crate builds the cascades an engine would build (practical splits, a sphere or AABB
//! fit, texel snapping) for a camera, a directional light and the scene's bounds, and measures
//! texel density and perspective aliasing against view depth, shimmer under camera motion,
//! and coverage. Conventions (handedness, light direction, view depth) are stated once in
//! [`geometry`]; formulas follow `csm-math.md` of the project's reference material.
//!
//! Pipeline: [`config`] → [`depth_range`] → [`splits`] → [`cascades`] ([`fitting`],
//! [`snapping`]) → [`metrics`], [`shimmer`] → [`analysis`] → [`output`], [`plots`].

pub mod analysis;
pub mod bench;
pub mod cascades;
pub mod check;
pub mod cli;
pub mod compare;
pub mod config;
pub mod depth_range;
pub mod error;
pub mod fitting;
pub mod geometry;
pub mod metrics;
pub mod motion;
pub mod output;
pub mod plots;
pub mod precision;
pub mod presets;
pub mod report;
pub mod rng;
pub mod shimmer;
pub mod snapping;
pub mod splits;
pub mod stress;
pub mod sweep;

pub use analysis::{analyze, Analysis, AnalysisOptions, Summary};
pub use config::Config;
pub use error::{Error, Result};
