//! What `bench` writes besides its figure: `bench.csv` and the table printed on stdout.

use std::fmt::Write as _;

use crate::commands::bench::{BenchReport, TARGET_ERROR};
use crate::error::Result;
use crate::output::{csv_bytes, num, short_number, Exporter};

/// The terminal table: per metric, the smallest count reaching [`TARGET_ERROR`] and its
/// time, and the error and time at the current default.
pub(crate) fn table(report: &BenchReport) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "bench ({}): smallest sample count reaching relative error {}, and the defaults",
        report.scene,
        short_number(TARGET_ERROR)
    );
    let _ = writeln!(
        out,
        "{:<31} {:<26} {:>8} {:>11} {:>10}   {:>8} {:>10} {:>11}",
        "metric", "knob", "reaches", "time (s)", "error", "default", "error", "time (s)"
    );
    for m in &report.metrics {
        let (count, time, err) = match report.first_reaching(m.name, TARGET_ERROR) {
            Some(r) => (r.samples.to_string(), short_number(r.seconds), short_number(r.error)),
            None => {
                let max = report.rows_of(m.name).map(|r| r.samples).max().unwrap_or(0);
                (format!(">{max}"), "-".to_string(), "-".to_string())
            }
        };
        let (derr, dtime) = match report.at(m.name, m.default) {
            Some(r) => (short_number(r.error), short_number(r.seconds)),
            None => ("-".to_string(), "-".to_string()),
        };
        let _ = writeln!(
            out,
            "{:<31} {:<26} {:>8} {:>11} {:>10}   {:>8} {:>10} {:>11}",
            m.name, m.knob, count, time, err, m.default, derr, dtime
        );
    }
    for m in report.metrics.iter().filter(|m| !m.note.is_empty()) {
        let _ = writeln!(out, "  {}: {}", m.name, m.note);
    }
    out
}

/// `bench.csv`: one row per metric and sample count.
pub(crate) struct BenchCsv;

pub(crate) const BENCH_COLUMNS: [&str; 6] = ["metric", "samples", "seconds", "error", "estimate", "reference"];

impl Exporter<BenchReport> for BenchCsv {
    fn file_name(&self) -> &'static str {
        "bench.csv"
    }

    fn render(&self, report: &BenchReport) -> Result<Vec<u8>> {
        let rows = report
            .rows
            .iter()
            .map(|r| {
                Ok(vec![
                    r.metric.to_string(),
                    r.samples.to_string(),
                    num("seconds", r.seconds)?,
                    num("error", r.error)?,
                    num("estimate", r.estimate)?,
                    num("reference", r.reference)?,
                ])
            })
            .collect::<Result<Vec<_>>>()?;
        csv_bytes(&BENCH_COLUMNS, &rows)
    }
}
