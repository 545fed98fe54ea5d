#!/usr/bin/env bash
# Reproduces every speed figure that README.md and docs/ publish.
#   scripts/speed.sh            every job in scripts/speed/ (sorted by name)
#   scripts/speed.sh rays sweep only the jobs whose file name contains one of the words
# Each job is one file in scripts/speed/ that calls `measure` and `paired` from
# scripts/speed/lib.sh; adding a figure is one file there. Every row gives wall time and CPU
# time (user + sys) as the best of RUNS runs (default 3) by CPU, with the load average at the
# start, because the build machines are shared: CPU time is the figure that holds under load.
# Peers (numpy, Embree via embreex) are installed from PyPI into target/speed/venv on first use.
# The table is printed and written to target/speed/speed.md.
set -euo pipefail
cd "$(dirname "$0")/.."
export SPEED_ROOT=$PWD
mkdir -p target/speed
cargo build --release --locked --quiet
# shellcheck source=speed/lib.sh
source scripts/speed/lib.sh
speed_header
for job in scripts/speed/[0-9]*.sh; do
  name=$(basename "$job" .sh)
  if [ $# -gt 0 ]; then
    keep=0
    for word in "$@"; do [[ "$name" == *"$word"* ]] && keep=1; done
    [ "$keep" = 1 ] || continue
  fi
  speed_section "$name"
  # shellcheck disable=SC1090
  source "$job"
done
speed_footer
