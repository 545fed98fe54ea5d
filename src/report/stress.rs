//! What `stress` writes: `stress.csv`, one row per case, and the table printed on stdout.

use std::fmt::Write as _;

use crate::commands::stress::{toml_f64, CaseResult, Expect};
use crate::error::Result;
use crate::output;

/// Columns of `stress.csv`: the inputs, then one column per invariant's worst value, the f32
/// residuals, which invariants failed, the status and a note (the error of a rejected input,
/// or why binary32 was not run).
pub fn stress_columns() -> Vec<&'static str> {
    let mut head = vec!["case", "expect"];
    head.extend(super::POSE_COLUMNS);
    head.extend(INPUT_AND_RESULT_COLUMNS);
    head
}

/// The columns after the camera's position and target.
const INPUT_AND_RESULT_COLUMNS: [&str; 45] = [
    "up_x",
    "up_y",
    "up_z",
    "fov_y_deg",
    "near",
    "far",
    "width",
    "height",
    "light_x",
    "light_y",
    "light_z",
    "scene_min_x",
    "scene_min_y",
    "scene_min_z",
    "scene_max_x",
    "scene_max_y",
    "scene_max_z",
    "world_offset_x",
    "world_offset_y",
    "world_offset_z",
    "max_distance",
    "cascades",
    "lambda",
    "resolution",
    "fit",
    "snap",
    "fit_depth_to_scene",
    "motion",
    "step",
    "frames",
    "cascades_needed",
    "nonfinite_values",
    "split_min_gap",
    "split_end_error",
    "coverage_violations",
    "stabilised_shimmer_max",
    "f32_world_drift_max",
    "f32_world_lookup_error_max",
    "f32_world_coverage_violations",
    "f32_relative_drift_max",
    "f32_relative_lookup_error_max",
    "f32_relative_coverage_violations",
    "failed_invariants",
    "status",
    "note",
];

/// A value for the CSV: finite numbers in shortest round-trip form; anything else (which
/// only a failing invariant can produce) spelled out, never `NaN`.
fn cell(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "non-finite".into()
    }
}

/// Input values as written into the TOML. An invalid-by-design NaN or infinity is spelled
/// `non-finite` (the case name says which), so no cell of the file reads as a non-finite number.
fn input_cell(v: f64) -> String {
    if v.is_finite() {
        toml_f64(v)
    } else {
        "non-finite".into()
    }
}

fn row(r: &CaseResult) -> Vec<String> {
    let i = &r.case.inputs;
    let mut out = vec![
        r.case.name.clone(),
        match r.case.expect {
            Expect::Valid => "valid".into(),
            Expect::Rejected { key } => format!("rejected ({key})"),
        },
    ];
    for v in [i.position, i.target, i.up] {
        out.extend(v.iter().map(|x| input_cell(*x)));
    }
    out.extend([input_cell(i.fov_y_deg), input_cell(i.near), input_cell(i.far)]);
    out.extend([i.width.to_string(), i.height.to_string()]);
    for v in [i.light, i.scene_min, i.scene_max, i.world_offset] {
        out.extend(v.iter().map(|x| input_cell(*x)));
    }
    out.extend([
        input_cell(i.max_distance),
        i.cascades.to_string(),
        input_cell(i.lambda),
        i.resolution.to_string(),
        i.fit.to_string(),
        i.snap.to_string(),
        i.fit_depth_to_scene.to_string(),
        i.motion.to_string(),
        input_cell(i.step),
        i.frames.to_string(),
    ]);
    out.push(r.cascades_needed.map_or(String::new(), |b| b.to_string()));
    for inv in [
        "finite",
        "splits_increasing",
        "splits_end_at_range",
        "coverage",
        "stabilised_shimmer_f64",
    ] {
        out.push(r.check(inv).map_or(String::new(), |c| cell(c.worst)));
    }
    for res in [r.f32_world, r.f32_relative] {
        out.push(res.map_or(String::new(), |x| cell(x.drift_max)));
        out.push(res.map_or(String::new(), |x| cell(x.lookup_error_max)));
        out.push(res.map_or(String::new(), |x| x.coverage_violations.to_string()));
    }
    out.push(r.failed().join(";"));
    out.push(if r.pass() { "pass" } else { "fail" }.into());
    out.push(r.note.clone());
    out
}

/// `stress.csv`: one row per case.
pub(crate) fn csv(results: &[CaseResult]) -> Result<Vec<u8>> {
    let rows: Vec<Vec<String>> = results.iter().map(row).collect();
    output::csv_bytes(&stress_columns(), &rows)
}

/// The terminal table.
pub(crate) fn table(results: &[CaseResult]) -> String {
    let g = |v: Option<f64>| v.map_or("-".to_string(), output::short_number);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<40} {:>6} {:>10} {:>8} {:>10} {:>10} {:>10} {:>10}  failed / note",
        "case", "status", "stab. f64", "coverage", "f32 world", "f32 S7", "f32 rel.", "rel. S7"
    );
    for r in results {
        let name: String = r.case.name.chars().take(40).collect();
        let detail = if r.pass() {
            match r.case.expect {
                Expect::Rejected { .. } => format!("rejected as designed: {}", r.note),
                Expect::Valid if r.cascades_needed == Some(false) => "no cascades needed".to_string(),
                Expect::Valid => r.note.clone(),
            }
        } else {
            format!("FAILED {}: {}", r.failed().join(", "), r.note)
        };
        let _ = writeln!(
            out,
            "{:<40} {:>6} {:>10} {:>8} {:>10} {:>10} {:>10} {:>10}  {}",
            name,
            if r.pass() { "pass" } else { "FAIL" },
            g(r.check("stabilised_shimmer_f64").map(|c| c.worst)),
            r.check("coverage").map_or("-".to_string(), |c| format!("{}", c.worst)),
            g(r.f32_world.map(|x| x.drift_max)),
            g(r.f32_world.map(|x| x.lookup_error_max)),
            g(r.f32_relative.map(|x| x.drift_max)),
            g(r.f32_relative.map(|x| x.lookup_error_max)),
            detail.chars().take(160).collect::<String>(),
        );
    }
    let failed = results.iter().filter(|r| !r.pass()).count();
    let _ = writeln!(
        out,
        "{} cases, {} passed, {} failed",
        results.len(),
        results.len() - failed,
        failed
    );
    out
}
