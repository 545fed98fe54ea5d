# The criterion kernels (docs/speed.md, "Kernel benchmarks (criterion)"): cascade building,
# one analysis, the default sweep (2 threads, 1 thread, bounds only), one sun angle and the
# engine terms, with a short warm-up and measurement (1 s, 3 s). Criterion times wall-clock
# iterations inside one process and reports their median: one row per kernel, in its own unit,
# with the load at the start (on a loaded machine the multi-threaded sweep's median waits for a
# core; the single-threaded kernels much less). Builds the bench first (cargo bench --no-run).
KERNELS_FILTER=${KERNELS_FILTER:-'^(cascade_build|analyze|sweep|sun|engine_terms)/'}
kernels_load=$(cut -d' ' -f1 /proc/loadavg)
cargo bench --locked --quiet --bench kernels -- --warm-up-time 1 --measurement-time 3 "$KERNELS_FILTER" 2>/dev/null |
  awk '/^[a-z_]+\/[A-Za-z0-9_]+/ { name = $1 }
       /time:/ { i = index($0, "["); split(substr($0, i + 1), t, " ");
                 printf "%s %s %s\n", name, t[3], t[4] }' |
  while read -r kname kmed kunit; do
    speed_row "| ${SPEED_JOB:-} | criterion $kname: median $kmed $kunit | | | | | $kernels_load |"
  done
# Criterion's medians are wall-clock: on a loaded machine they measure waiting more than work.
# SPEED_CALLGRIND=1 adds the load-proof counterpart: instruction counts (valgrind) of the same
# work as whole processes on one thread (RAYON_NUM_THREADS=1): one analysis, the default sweep
# and the bounds-only sweep.
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  KCG=$SPEED_ROOT/target/speed/kernels
  mkdir -p "$KCG"
  # kernels_callgrind NAME LABEL CMD...: one row with the whole process's instructions
  kernels_callgrind() {
    local name=$1 label=$2; shift 2
    RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$KCG/cg.$name" "$@" >/dev/null 2>&1
    callgrind_annotate "$KCG/cg.$name" >"$KCG/cg.$name.txt" 2>/dev/null || true
    speed_row "| ${SPEED_JOB:-} | $label, 1 thread (callgrind): $(awk '/PROGRAM TOTALS/ && !seen { print $1; seen = 1 }' "$KCG/cg.$name.txt") instructions | | | | | |"
  }
  kernels_callgrind analyze "analyze configs/default.toml --quiet" \
    "$BIN" analyze configs/default.toml --quiet --out "$KCG/analyze"
  kernels_callgrind sweep "sweep configs/default.toml --no-plots --quiet" \
    "$BIN" sweep configs/default.toml --no-plots --quiet --out "$KCG/sweep"
  kernels_callgrind sweep-bounds "sweep benches/default_bounds_only.toml --no-plots --quiet" \
    "$BIN" sweep benches/default_bounds_only.toml --no-plots --quiet --out "$KCG/sweep-bounds"
fi
