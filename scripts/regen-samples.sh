#!/usr/bin/env bash
# Regenerates the committed samples under reports/ that README.md and the docs show.
# Every other run of the tool writes to out/ (ignored by git) unless --out says otherwise,
# each command into its own folder, as the commands do by default (docs/commands.md),
# so only this script changes reports/.
#   scripts/regen-samples.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked
bin=target/release/csm-lab
"$bin" analyze configs/default.toml --ground-truth --out reports/default/analyze
"$bin" sweep configs/default.toml --quiet --ground-truth --out reports/default/sweep
"$bin" compare configs/default.toml --defaults --out reports/default/compare
"$bin" stress --out reports/stress
"$bin" bench --out reports/bench
git status --short reports/
