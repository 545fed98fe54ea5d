//! The math: pure functions and plain types, no configuration, no I/O.
//!
//! Conventions are stated once in [`geometry`]: right-handed world with +Y up, world units for
//! every length, radians for every angle (degrees exist only in the config file), the light
//! direction is the way light travels, and light space is a pure rotation named
//! `light_from_world`. The inputs are the plain values of [`scene`]. Nothing here imports
//! `config`, `cli`, `report`, `figures`, `presets`, `commands` or `analysis`; those layers
//! call into the core, and the core depends only on glam, serde derives and std.

pub mod cascades;
pub mod depth_range;
pub mod fitting;
pub mod free_splits;
pub mod geometry;
pub mod light_motion;
pub mod mesh;
pub mod metrics;
pub mod motion;
pub mod precision;
pub mod rng;
pub mod scene;
pub mod screen;
pub mod seams;
pub mod shade;
pub mod shimmer;
pub mod snapping;
pub mod splits;
pub mod sun;
pub mod truth;
pub mod visibility;
pub mod walk;
