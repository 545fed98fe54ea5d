//! Prints the drift-against-world-offset table of `docs/accuracy.md` (Markdown).
//! Run: `cargo run --release --example drift_table`.

fn main() {
    match csm_lab::drift_table::drift_table() {
        Ok(rows) => print!("{}", csm_lab::drift_table::drift_table_markdown(&rows)),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
