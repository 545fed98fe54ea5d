//! The math: pure functions and plain types, no configuration, no I/O.
//!
//! Conventions are stated once in [`geometry`]: right-handed world with +Y up, world units for
//! every length, radians for every angle (degrees exist only in the config file), the light
//! direction is the way light travels, and light space is a pure rotation named
//! `light_from_world`. The inputs are the plain values of [`scene`]. This crate knows no
//! configuration file, file format, CLI or report: the application crate (`csm-lab`) calls into
//! it. Its dependencies are glam (vectors), serde (derives only), rayon (parallel walks and
//! ray casts) and obvhs (the binary BVH that the visibility pass's four-wide BVH is collapsed
//! from); the architecture test holds it to that.
//!
//! Inside, plain values sit at the bottom ([`scene`], [`geometry`]) and no module circle exists:
//! [`shimmer`] defines the motion metrics, [`walk`] is the one walk along a camera path,
//! [`rig_path`] walks the exact f64 rig and [`precision`] the binary32 pipeline.

mod bvh4;
pub mod cascades;
pub mod cost;
pub mod depth_range;
pub mod fitting;
pub mod free_splits;
pub mod geometry;
pub mod hash;
pub mod light_cover;
pub mod light_motion;
pub mod mesh;
pub mod metrics;
pub mod motion;
pub mod precision;
pub mod rig_path;
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
pub mod viewpoints;
pub mod visibility;
pub mod walk;
