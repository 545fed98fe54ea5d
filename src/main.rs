//! The `csm-lab` binary: parse, dispatch, map the outcome to an exit code
//! (0 success, 1 a quality threshold was violated, 2 any error).

use clap::Parser;

// mimalloc in place of the system allocator: a sweep allocates and frees many mid-sized
// buffers per view and setting; glibc's malloc faulted each view's pages in one by one (17k
// page faults on the 20-view sweep against ~400 here) and its malloc/free took 5-9 % of the
// CPU. Measured in docs/speed.md ("The allocator").
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

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
