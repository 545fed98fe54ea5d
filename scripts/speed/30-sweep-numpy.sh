# The bounds-only sweep against numpy (docs/speed.md, "The bounds-only sweep against numpy"):
# the default grid (672 settings, 240 strafe frames) of configs/default.toml without its scene
# geometry, whole processes. The numpy peer (benches/peers/sweep_numpy.py, in the venv of
# peer_python) first checks its rows against csm-lab's sweep.csv (--check; the job stops if they
# disagree), then the two run paired. Their CPU times are tens of milliseconds, so this job takes
# the best of at least 5 pairs. SPEED_CALLGRIND=1 adds csm-lab's instruction count (callgrind);
# SPEED_PERF=1 adds its CPU by `perf stat -r 20 -e task-clock` (0.1 ms resolution, against the
# 10 ms of /usr/bin/time), at the default thread count and at RAYON_NUM_THREADS=1.
NUMPY_CFG=benches/default_bounds_only.toml
NUMPY_OUT=target/speed/out/numpy
NUMPY_PY=$(peer_python)
mkdir -p "$NUMPY_OUT"
"$BIN" sweep "$NUMPY_CFG" --no-plots --quiet --out "$NUMPY_OUT/csm-lab" >/dev/null
"$NUMPY_PY" benches/peers/sweep_numpy.py "$NUMPY_CFG" --out "$NUMPY_OUT/numpy.csv" \
  --check "$NUMPY_OUT/csm-lab/sweep.csv" >&2
NUMPY_RUNS_BEFORE=$RUNS
RUNS=$((RUNS < 5 ? 5 : RUNS))
paired "csm-lab sweep $NUMPY_CFG --no-plots" "numpy peer (benches/peers/sweep_numpy.py)" -- \
  "$BIN" sweep "$NUMPY_CFG" --no-plots --quiet --out "$NUMPY_OUT/csm-lab" -- \
  "$NUMPY_PY" benches/peers/sweep_numpy.py "$NUMPY_CFG" --out "$NUMPY_OUT/numpy.csv"
RUNS=$NUMPY_RUNS_BEFORE
# SPEED_CALLGRIND=1 adds csm-lab's instruction count for the same sweep (valgrind, load-proof).
# The awk programs read to the end: an early `exit` closes the pipe, and under speed.sh's
# `set -o pipefail` the writer's SIGPIPE ends the whole run without a row.
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  valgrind --tool=callgrind --callgrind-out-file="$NUMPY_OUT/cg.out" \
    "$BIN" sweep "$NUMPY_CFG" --no-plots --quiet --out "$NUMPY_OUT/cg" >/dev/null 2>&1
  numpy_ir=$(callgrind_annotate "$NUMPY_OUT/cg.out" 2>/dev/null | awk '/PROGRAM TOTALS/ && !n { print $1; n = 1 }')
  speed_row "| ${SPEED_JOB:-} | csm-lab instructions (callgrind): $numpy_ir | | | | | |"
fi
# SPEED_PERF=1: csm-lab's CPU by perf (the mean task-clock of 20 runs), default threads and one.
if [ "${SPEED_PERF:-0}" = 1 ] && command -v perf >/dev/null; then
  for numpy_threads in default 1; do
    numpy_tc=$(if [ "$numpy_threads" = 1 ]; then export RAYON_NUM_THREADS=1; fi
      perf stat -r 20 -e task-clock "$BIN" sweep "$NUMPY_CFG" --no-plots --quiet --out "$NUMPY_OUT/perf" 2>&1 >/dev/null |
        awk '/task-clock/ && !n { print $1; n = 1 }')
    speed_row "| ${SPEED_JOB:-} | csm-lab task-clock ms (perf stat -r 20, threads: $numpy_threads): $numpy_tc | | | | | load $(cut -d' ' -f1 /proc/loadavg) | |"
  done
fi
