//! What `sweep --ground-truth` adds: `flicker.csv` (the sampled rows' S3, S4 and S5 in both snap
//! modes), the `flicker_vs_shimmer` figure and the reports' sentences saying which rows were
//! sampled and how well S3 and S4 predict S5 ([`crate::commands::flicker_sample`]).

use std::fmt::Write as _;

use super::html;
use crate::commands::sweep::flicker::FlickerSample;
use crate::commands::sweep::SweepResult;
use crate::error::Result;
use crate::figures::truth::{fit, flicker_vs_shimmer_figure, Fit, ShimmerPoint, FLICKER_VS_SHIMMER_CAPTION};
use crate::output::{num, short_number};

/// The file of the sampled rows.
pub(crate) const FILE: &str = "flicker.csv";

/// `flicker.csv`'s columns.
pub(crate) const COLUMNS: [&str; 14] = [
    "row",
    "setting",
    "lambda",
    "cascades",
    "resolution",
    "fit",
    "split_range",
    "recommended",
    "s3_snapped",
    "s4_snapped",
    "flicker_snapped",
    "s3_unsnapped",
    "s4_unsnapped",
    "flicker_unsnapped",
];

/// `flicker.csv`: one line per sampled row that has cascades, in row order. `row` is the
/// 0-based index of the setting in grid order (the line of `sweep.csv` after its header; in a
/// sun sweep, the setting's judged row at its worst sun, named in `setting`).
pub(crate) fn csv(r: &SweepResult, s: &FlickerSample) -> Result<Vec<u8>> {
    let rec = r.recommendation.as_ref().map(|x| x.index);
    let rows = s.measured.iter().map(|m| {
        let st = &r.rows[m.index].setting;
        Ok(vec![
            m.index.to_string(),
            st.label(),
            num("lambda", st.lambda)?,
            st.cascades.to_string(),
            st.resolution.to_string(),
            st.fit.name().to_string(),
            st.split_range.to_string(),
            (rec == Some(m.index)).to_string(),
            num("s3_snapped", m.snapped.s3)?,
            num("s4_snapped", m.snapped.s4.unwrap_or(0.0))?,
            num("flicker_snapped", m.snapped.s5)?,
            num("s3_unsnapped", m.unsnapped.s3)?,
            num("s4_unsnapped", m.unsnapped.s4.unwrap_or(0.0))?,
            num("flicker_unsnapped", m.unsnapped.s5)?,
        ])
    });
    crate::output::csv_bytes_from(&COLUMNS, rows)
}

/// The figure's points (both snap modes of every measured row).
pub(crate) fn points(s: &FlickerSample) -> Vec<ShimmerPoint> {
    s.points()
        .map(|p| ShimmerPoint {
            s3: p.s3,
            s4: p.s4.unwrap_or(0.0),
            s5: p.s5,
            snapped: p.snapped,
        })
        .collect()
}

/// The fits of S5 on S3 and on S4 over all points, as the figure draws them.
pub(crate) struct Fits {
    pub s3: Fit,
    pub s4: Fit,
}

pub(crate) fn fits(points: &[ShimmerPoint]) -> Fits {
    let s5: Vec<f64> = points.iter().map(|p| p.s5).collect();
    let s3: Vec<f64> = points.iter().map(|p| p.s3).collect();
    let s4: Vec<f64> = points.iter().map(|p| p.s4).collect();
    Fits {
        s3: fit(&s3, &s5),
        s4: fit(&s4, &s5),
    }
}

/// "S5 ≈ a + b·S3, r = ..., ρ = ... (n points)" or why there is no line.
pub(crate) fn fit_words(proxy: &str, f: &Fit) -> String {
    let r = |v: Option<f64>| v.map_or("undefined (a constant)".to_string(), |v| format!("{v:.3}"));
    match f.line {
        Some((a, b)) => format!(
            "S5 ≈ {} + {}·{proxy}, Pearson r = {}, Spearman ρ = {} over {} points",
            short_number(a),
            short_number(b),
            r(f.pearson),
            r(f.spearman),
            f.n
        ),
        None => format!(
            "no line of S5 on {proxy} ({} points; {proxy} is constant or too few points)",
            f.n
        ),
    }
}

/// The sentences of a sample: which rows, the two fits, and the snapped rows' largest S5.
pub(crate) fn lines(s: &FlickerSample) -> Vec<String> {
    let p = points(s);
    let f = fits(&p);
    let max = |snapped: bool| {
        p.iter()
            .filter(|x| x.snapped == snapped)
            .map(|x| x.s5)
            .fold(0.0f64, f64::max)
    };
    // Snapped sphere fits sit at S3 = S4 = S5 = 0 and pull the line of all points; the
    // unsnapped points alone say whether the proxies rank the configurations that do flicker.
    let free: Vec<ShimmerPoint> = p.iter().filter(|x| !x.snapped).copied().collect();
    let ff = fits(&free);
    // The edge part of S5 (changes where a texel read holds another surface) of the same rows.
    let edge: Vec<ShimmerPoint> = s
        .points()
        .filter(|x| !x.snapped)
        .map(|x| ShimmerPoint {
            s3: x.s3,
            s4: x.s4.unwrap_or(0.0),
            s5: x.s5_edge,
            snapped: false,
        })
        .collect();
    let fe = fits(&edge);
    let mut sources: Vec<&str> = s.points().map(|x| x.bias_source.name()).collect();
    sources.sort_unstable();
    sources.dedup();
    let recommended = if sources.contains(&"recommended") {
        " (recommended: that row's own bias_needed per cascade, acne at most 0.1 %)"
    } else {
        ""
    };
    vec![
        format!("{} (flicker.csv).", s.sentence()),
        format!(
            "S5 is measured at the bias each row's pass sampled with: bias_source = {}{recommended}.",
            sources.join(", ")
        ),
        format!("Against S3, all points: {}.", fit_words("S3", &f.s3)),
        format!("Against S4, all points: {}.", fit_words("S4", &f.s4)),
        format!(
            "Unsnapped points alone: against S3 {}; against S4 {}.",
            fit_words("S3", &ff.s3),
            fit_words("S4", &ff.s4)
        ),
        format!(
            "Unsnapped points alone, the edge part of S5 (flicker_edge_unsnapped): against S3 {}; against S4 {}.",
            fit_words("S3", &fe.s3),
            fit_words("S4", &fe.s4)
        ),
        format!(
            "Largest S5: snapped {}, unsnapped {} (share of receivers flipping per frame).",
            short_number(max(true)),
            short_number(max(false))
        ),
    ]
}

/// The figure, when the sweep has a sample.
pub(crate) fn figure(r: &SweepResult) -> Result<Option<(&'static str, String, Vec<u8>)>> {
    match &r.flicker {
        None => Ok(None),
        Some(s) => {
            let (stem, _, svg) = flicker_vs_shimmer_figure(&r.config.name, &points(s))?;
            Ok(Some((stem, FLICKER_VS_SHIMMER_CAPTION.to_string(), svg)))
        }
    }
}

/// The report.html section ("Does shimmer predict flicker?"); empty without a sample.
pub(crate) fn html_section(r: &SweepResult) -> String {
    let Some(s) = &r.flicker else {
        return String::new();
    };
    let mut h = String::from("<h2>Does shimmer predict flicker?</h2>\n");
    h.push_str(&html::list(&lines(s), None));
    h
}

/// The report.md section; empty without a sample.
pub(crate) fn md_section(r: &SweepResult) -> String {
    let Some(s) = &r.flicker else {
        return String::new();
    };
    let mut m = String::from("## Does shimmer predict flicker?\n\n");
    for l in lines(s) {
        let _ = writeln!(m, "- {l}");
    }
    m.push('\n');
    m
}
