//! One module per command: each computes its result from a validated config and hands it
//! to the report layer.

pub mod bench;
pub mod check;
pub mod compare;
pub mod stress;
pub mod sweep;
