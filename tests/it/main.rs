//! The integration tests, built as one test crate (one link instead of one per file).

mod architecture;
mod bad_inputs;
mod check_sweep;
mod cli_accuracy;
mod cli_analyze;
mod cli_bench;
mod cli_check;
mod cli_compare;
mod cli_stress;
mod cli_sweep;
mod common;
mod figures;
mod geometry;
mod golden_outputs;
mod precision;
mod preset_sweeps;
mod presets;
mod prop_analysis;
mod prop_specs;
mod prop_toml;
mod readme_ci;
mod readme_clean;
mod regressions;
mod shimmer;
mod shimmer_fast_paths;
