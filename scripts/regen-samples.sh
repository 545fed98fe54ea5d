#!/usr/bin/env bash
# Regenerates the committed samples under reports/ that README.md and the docs show.
# Every other run of the tool writes to out/ (ignored by git) unless --out says otherwise,
# so only this script changes reports/.
#   scripts/regen-samples.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked
bin=target/release/csm-lab
"$bin" analyze configs/default.toml --ground-truth --out reports/default
"$bin" sweep configs/default.toml --quiet --ground-truth --out reports/default
"$bin" compare configs/default.toml --defaults --out reports/default
"$bin" stress --out reports/stress
"$bin" bench --out reports/bench
git status --short reports/
