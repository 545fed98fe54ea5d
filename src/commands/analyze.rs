//! `csm-lab analyze`: one scene and shadow setting, built and measured, written as CSV, JSON
//! and SVG, with a summary on stdout.

use super::{default_out_dir, load_with_preset_flag, Format, Outcome};
use crate::analysis::{analyze, AnalysisOptions};
use crate::cli::AnalyzeArgs;
use crate::error::Result;
use crate::output;
use crate::precision::{self, Precision};
use crate::report;

/// The `analyze` command.
pub fn execute(args: &AnalyzeArgs) -> Result<Outcome> {
    let mut config = load_with_preset_flag(&args.config, args.preset.as_deref())?;
    if let Some(p) = args.precision {
        if p == Precision::F32 && config.shadow.preset.is_some() {
            return Err(crate::error::Error::flag(
                "--precision",
                "f32",
                "the binary32 emulation models csm-lab's own sphere and aabb pipelines, not engine presets",
            ));
        }
        config.shadow.precision = p;
        if p == Precision::F32 {
            if let Some(why) = precision::f32_range_problem(&config) {
                return Err(crate::error::Error::flag("--precision", "f32", why));
            }
        }
    }
    let analysis = analyze(&config, &AnalysisOptions::full());
    let dir = args.out.clone().unwrap_or_else(|| default_out_dir(&config));
    let written = output::export_all(&dir, &analysis, &report::analyze::exporters())?;
    match args.format {
        Format::Table => {
            print!("{}", report::analyze::summary_table(&analysis));
            println!("wrote {} files to {}", written.len(), dir.display());
        }
        Format::Json => {
            let bytes = output::json_bytes("summary", &report::analyze::summary_value(&analysis))?;
            print!("{}", String::from_utf8_lossy(&bytes));
            eprintln!("wrote {} files to {}", written.len(), dir.display());
        }
    }
    Ok(Outcome::Success)
}
