# The bounds-only sweep against numpy (docs/speed.md, "The bounds-only sweep against numpy"):
# the default grid (672 settings, 240 strafe frames) of configs/default.toml without its scene
# geometry, whole processes. The numpy peer (benches/peers/sweep_numpy.py, in the venv of
# peer_python) first checks its rows against csm-lab's sweep.csv (--check; the job stops if they
# disagree), then the two run paired. Their CPU times are tens of milliseconds, so this job takes
# the best of at least 5 pairs. SPEED_CALLGRIND=1 adds csm-lab's instruction count (callgrind).
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
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  valgrind --tool=callgrind --callgrind-out-file="$NUMPY_OUT/cg.out" \
    "$BIN" sweep "$NUMPY_CFG" --no-plots --quiet --out "$NUMPY_OUT/cg" >/dev/null 2>&1
  numpy_ir=$(callgrind_annotate "$NUMPY_OUT/cg.out" 2>/dev/null | awk '/PROGRAM TOTALS/ { print $1; exit }')
  speed_row "| ${SPEED_JOB:-} | csm-lab instructions (callgrind): $numpy_ir | | | | | |"
fi
