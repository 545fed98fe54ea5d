//! The `csm-lab` binary: parse, dispatch, map the outcome to an exit code
//! (0 success, 1 a quality threshold was violated, 2 any error).

use clap::Parser;

fn main() {
    let cli = csm_lab::cli::Cli::parse();
    match csm_lab::cli::run(cli) {
        Ok(outcome) => std::process::exit(outcome.exit_code()),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
