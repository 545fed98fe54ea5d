//! `csm-lab check`: threshold rules and baseline comparisons for CI, with JUnit XML.

use std::path::Path;

use super::{Format, Outcome};
use crate::analysis::analyze;
use crate::commands::check::*;
use crate::config::Config;
use crate::error::{BaselineError, Error, GridError, IoError, Result};
use crate::output;

/// Writes the JUnit file atomically, creating its directory.
pub fn write_junit(path: &Path, report: &CheckReport) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        output::ensure_dir(dir)?;
    }
    output::write_atomic(path, crate::report::junit::render(report).as_bytes())
}

/// What `check` was asked to do (the command line's values).
#[derive(Debug, Clone, Copy)]
pub struct CheckRequest<'a> {
    /// Scene and shadow settings.
    pub config: &'a Path,
    /// Rules and baseline tolerances.
    pub thresholds: &'a Path,
    /// An earlier `summary.json` (or, with `sweep`, `sweep.csv`).
    pub baseline: Option<&'a Path>,
    /// Judge sweep rows instead of the one configuration.
    pub sweep: bool,
    /// Also write a JUnit XML report here.
    pub junit: Option<&'a Path>,
    pub format: Format,
}

/// The `check` command. Every input is read and validated before anything is analysed, and
/// nothing is printed or written unless the whole check succeeded.
pub fn execute(args: &CheckRequest) -> Result<Outcome> {
    let config = Config::load(args.config)?;
    let thresholds = Thresholds::load(args.thresholds)?;
    if thresholds.rules.is_empty() && args.baseline.is_none() {
        return Err(Error::flag(
            "--thresholds",
            &args.thresholds.display().to_string(),
            "has no [[rule]] entries and no --baseline was given: nothing to check",
        ));
    }
    let report = if args.sweep {
        let base_rows = match &args.baseline {
            Some(p) => Some(sweep::read_sweep_csv(p).map_err(|e| {
                with_hint(
                    e,
                    "with --sweep, --baseline takes a sweep.csv; compare a summary.json without --sweep",
                )
            })?),
            None => None,
        };
        let rows = sweep::sweep_rows_for(&config)?;
        let applicable = thresholds
            .rules
            .iter()
            .any(|r| matches!(r.target, thresholds::Target::Summary(_)));
        if !applicable && args.baseline.is_none() {
            return Err(GridError::Unusable {
                context: "--sweep".to_string(),
                message: format!(
                    "none of the rules in {} applies to sweep rows (only summary-metric rules do) \
                     and no --baseline was given: nothing to check",
                    thresholds.label
                ),
            }
            .into());
        }
        let label = args.baseline.as_ref().map(|p| p.display().to_string());
        check_rows(&config, &rows, &thresholds, label.as_deref().zip(base_rows.as_deref()))?
    } else {
        let base = match &args.baseline {
            Some(p) => Some(
                baseline::read_summary_json_for(p, &config.scene_hash())
                    .map_err(|e| with_hint(e, "to compare with a sweep.csv, add --sweep"))?,
            ),
            None => None,
        };
        let analysis = analyze(&config, &check_options());
        let label = args.baseline.as_ref().map(|p| p.display().to_string());
        check_analysis(&analysis, &thresholds, label.as_deref().zip(base.as_ref()))?
    };

    let stdout = match args.format {
        Format::Table => report.table().into_bytes(),
        Format::Json => output::json_bytes("check", &report.json())?,
    };
    if let Some(p) = &args.junit {
        write_junit(p, &report)?;
    }
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(&stdout)
        .and_then(|_| out.flush())
        .map_err(|e| Error::from(IoError::Stdout(e)))?;
    if let Some(p) = &args.junit {
        eprintln!("wrote {}", p.display());
    }
    Ok(if report.passed() {
        Outcome::Success
    } else {
        Outcome::ThresholdViolated
    })
}

/// Appends a hint to data-file errors about which kind of baseline a mode expects.
fn with_hint(e: Error, hint: &str) -> Error {
    match e {
        Error::Io(IoError::DataFile { path, line, message }) => {
            Error::data_file(&path, line, format!("{message} ({hint})"))
        }
        Error::Baseline(BaselineError::Invalid { label, message }) => BaselineError::Invalid {
            label,
            message: format!("{message} ({hint})"),
        }
        .into(),
        other => other,
    }
}
