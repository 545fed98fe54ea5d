//! `csm-lab check`: threshold rules and baseline comparisons for CI, with JUnit XML.

use std::path::Path;

use super::{Format, Outcome};
use crate::analysis::analyze;
use crate::commands::check::*;
use crate::config::Config;
use crate::error::{BaselineError, Error, GridError, IoError, Result};
use crate::output;

/// Writes the JUnit file atomically, creating its directory.
pub(crate) fn write_junit(path: &Path, report: &CheckReport) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        output::ensure_dir(dir)?;
    }
    output::write_atomic(path, crate::report::junit::render(report).as_bytes())
}

/// What `check` was asked to do (the command line's values).
#[derive(Debug, Clone, Copy)]
pub(crate) struct CheckRequest<'a> {
    /// Scene and shadow settings.
    pub config: &'a Path,
    /// Rules and baseline tolerances.
    pub thresholds: &'a Path,
    /// An earlier `summary.json` (or, with `sweep`, `sweep.csv`).
    pub baseline: Option<&'a Path>,
    /// Judge sweep rows instead of the one configuration.
    pub sweep: bool,
    /// With `sweep`: judge this `sweep.csv` (of the config's grid) instead of running the sweep.
    pub sweep_csv: Option<&'a Path>,
    /// With `sweep`: every configuration instead of the summary.
    pub verbose: bool,
    /// With `sweep`: gate every row, not only the recommendation and the configured setting.
    pub all_rows: bool,
    /// Also write a JUnit XML report here.
    pub junit: Option<&'a Path>,
    pub format: Format,
}

/// The `check` command. Every input is read and validated before anything is analysed, and
/// nothing is printed unless the whole check succeeded. When it cannot run (exit 2), the
/// JUnit file, if asked for, is replaced by one that reports the error. Before any work, the
/// JUnit file is replaced by one that reports an unfinished run: whatever ends the run (a
/// panic, a kill, an out-of-memory abort), the file a CI reads never says pass for it, and it
/// says pass only once the run wrote its final report.
pub(crate) fn execute(args: &CheckRequest) -> Result<Outcome> {
    if let Some(p) = args.junit {
        let xml = crate::report::junit::render_error(
            &args.config.display().to_string(),
            "csm-lab check started and has not finished: it was stopped (a crash, a kill, a timeout) \
             before it wrote its report",
        );
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            output::ensure_dir(dir)?;
        }
        output::write_atomic(p, xml.as_bytes())?;
    }
    let result = run(args);
    if let (Err(e), Some(p)) = (&result, args.junit) {
        let xml = crate::report::junit::render_error(&args.config.display().to_string(), &e.to_string());
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            output::ensure_dir(dir)?;
        }
        output::write_atomic(p, xml.as_bytes())?;
        eprintln!("wrote {} (reporting the error)", p.display());
    }
    result
}

fn run(args: &CheckRequest) -> Result<Outcome> {
    let config = Config::load(args.config)?;
    if config.truth.enabled {
        crate::analysis::ground_truth::cost_fits(&config, "analysis.ground_truth")?;
    }
    let thresholds = Thresholds::load(args.thresholds)?;
    // `--baseline` or the thresholds file's `[baseline] file`.
    let baseline_path = args
        .baseline
        .map(Path::to_path_buf)
        .or_else(|| thresholds.baseline_file.clone());
    let args = &CheckRequest {
        baseline: baseline_path.as_deref(),
        ..*args
    };
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
        let rows = match args.sweep_csv {
            Some(p) => sweep::sweep_rows_from_csv(&config, p)?,
            None => sweep::sweep_rows_for(&config)?,
        };
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
        check_rows(
            &config,
            &rows,
            &thresholds,
            label.as_deref().zip(base_rows.as_deref()),
            args.all_rows,
        )?
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
        Format::Table => report.table_with(args.verbose).into_bytes(),
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

/// What `check --init` was asked to do.
#[derive(Debug, Clone, Copy)]
pub(crate) struct InitRequest<'a> {
    pub config: &'a Path,
    /// The thresholds file to write; the baseline goes beside it.
    pub file: &'a Path,
    /// Room each limit leaves over today's value (a fraction).
    pub headroom: f64,
}

/// `check CONFIG --init FILE`: a thresholds file from the config's current values, with
/// `headroom`, and its baseline (`summary.json` content) beside it, named in the file.
pub(crate) fn init(args: &InitRequest) -> Result<Outcome> {
    if !(args.headroom.is_finite() && (0.0..=10.0).contains(&args.headroom)) {
        return Err(Error::flag(
            "--headroom",
            &args.headroom.to_string(),
            "a fraction in 0..=10 (0.05 leaves 5 % of room)",
        ));
    }
    let config = Config::load(args.config)?;
    if config.truth.enabled {
        crate::analysis::ground_truth::cost_fits(&config, "analysis.ground_truth")?;
    }
    // Everything `analyze` computes: the baseline is its summary.json.
    let analysis = analyze(&config, &crate::analysis::AnalysisOptions::full());
    let stem = args
        .file
        .file_stem()
        .map_or_else(|| "thresholds".to_string(), |s| s.to_string_lossy().into_owned());
    let baseline_name = format!("{stem}.baseline.json");
    let baseline_path = args.file.with_file_name(&baseline_name);
    let text = init::thresholds_text(
        &analysis,
        &args.config.display().to_string(),
        &baseline_name,
        args.headroom,
    );
    // The text must load as a thresholds file (the same validation `check` applies).
    Thresholds::from_toml_str(&text, &args.file.display().to_string())?;
    let baseline = output::json_bytes("summary", &crate::report::analyze::summary_value(&analysis))?;
    if let Some(dir) = args.file.parent().filter(|d| !d.as_os_str().is_empty()) {
        output::ensure_dir(dir)?;
    }
    output::write_atomic(&baseline_path, &baseline)?;
    output::write_atomic(args.file, text.as_bytes())?;
    eprintln!(
        "wrote {} ({} rules, {} % headroom) and its baseline {}; commit both, then run\n  csm-lab check {} --thresholds {}",
        args.file.display(),
        text.matches("[[rule]]").count(),
        crate::output::short_number(args.headroom * 100.0),
        baseline_path.display(),
        args.config.display(),
        args.file.display()
    );
    Ok(Outcome::Success)
}
