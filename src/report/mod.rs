//! The report layer: everything that turns a computed result into files or terminal text.
//! [`output`] holds the exporter trait, CSV/JSON encoding and the one atomic writer; [`html`]
//! the one page shell, stylesheet and escaping; one module per command renders that command's
//! result (figures are in [`crate::figures`]).

pub mod analyze;
pub mod bench;
pub mod check;
pub mod compare;
pub mod html;
pub mod junit;
pub mod markdown;
pub mod output;
pub mod stress;
pub mod sweep;
