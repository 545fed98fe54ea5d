//! `csm-lab bench`: run time against error of every sampled quantity.

use std::path::{Path, PathBuf};

use super::Outcome;
use crate::commands::bench::*;
use crate::config::Config;
use crate::error::{Error, Result};
use crate::output::{self, Exporter};
use crate::report;

/// What `bench` was asked to do (the command line's flags, as plain values).
#[derive(clap::Args, Debug, Clone)]
pub struct BenchRequest {
    /// Output directory [default: out/bench/].
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Scene to measure [default: the built-in configs/default.toml].
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Timed repetitions per point; the best is kept (1..=1000).
    #[arg(long, default_value_t = 5, allow_negative_numbers = true)]
    pub repeats: u32,
    /// No progress bar (it shows only on a terminal, after about a second).
    #[arg(long)]
    pub quiet: bool,
}

/// The `bench` command.
pub(crate) fn execute(args: &BenchRequest) -> Result<Outcome> {
    if !(1..=1000).contains(&args.repeats) {
        return Err(Error::flag(
            "--repeats",
            &args.repeats.to_string(),
            "allowed: an integer in 1..=1000",
        ));
    }
    let config = match &args.config {
        Some(path) => Config::load(path)?,
        None => {
            let mut c = Config::from_toml_str(DEFAULT_SCENE, "configs/default.toml (built in)", None)?;
            c.name = "default".to_string();
            c
        }
    };
    let progress = super::progress::Progress::new(args.quiet, BENCH_STEPS, "measurement groups");
    let measured = run_with_progress(&config, args.repeats as usize, &|| progress.inc(1))?;
    progress.writing();
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new(super::DEFAULT_OUT_ROOT).join("bench"));
    let exporters: [&dyn Exporter<BenchReport>; 2] = [&report::bench::BenchCsv, &crate::figures::bench::BenchSvg];
    let written = output::export_all(&dir, &measured, &exporters)?;
    progress.finish();
    print!("{}", report::bench::table(&measured));
    println!("wrote {} files to {}", written.len(), dir.display());
    Ok(Outcome::Success)
}
