//! The report layer: exporters (CSV, JSON, HTML, Markdown, tables) and atomic writes.

pub mod output;
mod sweep;

pub use self::sweep::*;
