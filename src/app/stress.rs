//! `csm-lab stress`: the battery of pathological inputs and its invariants, as `stress.csv`.

use std::path::PathBuf;

use super::Outcome;
use crate::commands::stress::*;
use crate::error::{Error, Result};
use crate::output;
use crate::report;

/// What `stress` was asked to do (the command line's flags, as plain values).
#[derive(clap::Args, Debug, Clone)]
pub struct StressRequest {
    /// Output directory for stress.csv.
    #[arg(long, default_value = "out/stress")]
    pub out: PathBuf,
    /// Random cases added to the fixed battery (0..=100000).
    #[arg(long, default_value_t = 32, allow_negative_numbers = true)]
    pub cases: u64,
    /// Seed of the random cases (same seed, same cases, same file).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Also fail a case whose f32 drift (texels per frame, either snap space) exceeds this.
    /// By default f32 residuals are reported, not judged.
    #[arg(long, value_name = "TEXELS", allow_negative_numbers = true)]
    pub max_f32_drift: Option<f64>,
    /// No progress bar (it shows only on a terminal, after about a second).
    #[arg(long)]
    pub quiet: bool,
}

/// The `stress` command.
pub(crate) fn execute(args: &StressRequest) -> Result<Outcome> {
    if args.cases > 100_000 {
        return Err(Error::flag(
            "--cases",
            &args.cases.to_string(),
            "at most 100000 random cases",
        ));
    }
    if let Some(limit) = args.max_f32_drift {
        if !(limit.is_finite() && limit >= 0.0) {
            return Err(Error::flag(
                "--max-f32-drift",
                &limit.to_string(),
                "a finite number of texels >= 0",
            ));
        }
    }
    let mut cases = battery();
    cases.extend(random_cases(args.cases as usize, args.seed));
    let opts = StressOptions {
        max_f32_drift: args.max_f32_drift,
        outputs: report::analyze::output_problems,
    };
    let progress = super::progress::Progress::new(args.quiet, cases.len() as u64, "cases");
    let results = run_with_progress(&cases, &opts, &|| progress.inc(1));
    progress.writing();
    let bytes = report::stress::csv(&results)?;
    output::write_files(&args.out, &[("stress.csv", bytes)])?;
    progress.finish();
    print!("{}", report::stress::table(&results));
    println!("wrote {}", args.out.join("stress.csv").display());
    Ok(if results.iter().all(|r| r.pass()) {
        Outcome::Success
    } else {
        Outcome::ThresholdViolated
    })
}
