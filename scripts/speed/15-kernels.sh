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
