//! The report layer: everything that turns a computed result into files or terminal text.
//! [`html`] holds the one page shell, stylesheet and escaping; one module per command renders
//! that command's result. Figures are in [`crate::figures`]; the exporter trait, CSV/JSON
//! encoding and the one atomic writer in [`crate::output`].

pub mod analyze;
pub mod bench;
pub mod check;
pub mod compare;
pub mod defs;
pub mod flicker_sample;
pub mod ground_truth;
pub mod html;
pub mod junit;
pub mod markdown;
pub mod optimize;
pub mod stress;
pub mod sweep;
pub mod terms;
pub mod truth;
