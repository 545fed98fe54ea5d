//! The report layer: everything that turns a computed result into files or terminal text.
//! [`html`] holds the one page shell, stylesheet and escaping; one module per command renders
//! that command's result. Figures are in [`crate::figures`]; the exporter trait, CSV/JSON
//! encoding and the one atomic writer in [`crate::output`].

pub mod analyze;
pub(crate) mod bench;
pub(crate) mod check;
pub(crate) mod compare;
pub(crate) mod defs;
pub(crate) mod flicker_sample;
pub(crate) mod ground_truth;
pub mod html;
pub(crate) mod junit;
pub(crate) mod markdown;
pub(crate) mod optimize;
pub mod stress;
pub(crate) mod sweep;
pub mod terms;
pub mod truth;
pub(crate) mod views;

/// A camera pose as CSV columns: the position and the target, in world units as written.
pub(crate) const POSE_COLUMNS: [&str; 6] = [
    "position_x",
    "position_y",
    "position_z",
    "target_x",
    "target_y",
    "target_z",
];
