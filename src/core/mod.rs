//! The math: pure functions and plain types, no configuration, no I/O.
//!
//! Conventions are stated once in [`geometry`]. Nothing here imports `config`, `cli`,
//! `report`, `figures` or `presets`; those layers call into the core.

pub mod cascades;
pub mod depth_range;
pub mod fitting;
pub mod geometry;
pub mod metrics;
pub mod motion;
pub mod precision;
pub mod rng;
pub mod scene;
pub mod shimmer;
pub mod snapping;
pub mod splits;
pub mod walk;
