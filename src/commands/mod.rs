//! What each command computes, as plain results: a sweep's grid, rows, Pareto front and
//! recommendation; a comparison of presets; the stress battery's case results; the bench
//! measurements; check's rule results and baseline comparisons; the engine settings each
//! engine's `recommendation.<engine>.txt` holds. Nothing here writes a file or
//! prints: [`crate::app`] runs a command and hands its result to [`crate::report`] and
//! [`crate::figures`].

pub(crate) mod bench;
pub mod check;
pub mod compare;
pub mod stress;
pub mod sweep;
pub mod terms;
