# sweep --optimize-splits on the default scene (28 groups, about 9,400 points evaluated, a
# repeated point looked up), paired with the same sweep without the search (docs/speed.md,
# "sweep --optimize-splits": CPU best of 3 and, with SPEED_CALLGRIND=1, the instructions).
# SPEED_CALLGRIND=1 adds the instruction counts (valgrind, load-proof; slow) of both, on one
# thread (RAYON_NUM_THREADS=1); their difference is the search's.
paired "sweep configs/default.toml --no-plots" "sweep configs/default.toml --optimize-splits --no-plots" -- \
  "$BIN" sweep configs/default.toml --no-plots --quiet --out target/speed/out/optimize-none -- \
  "$BIN" sweep configs/default.toml --optimize-splits --no-plots --quiet --out target/speed/out/optimize
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  for opt_flag in none --optimize-splits; do
    opt_args=()
    [ "$opt_flag" = none ] || opt_args=("$opt_flag")
    RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file=target/speed/out/optimize-cg.out \
      "$BIN" sweep configs/default.toml "${opt_args[@]}" --no-plots --quiet --out target/speed/out/optimize-cg >/dev/null 2>&1
    # Through a file: awk's early exit would end callgrind_annotate by SIGPIPE (pipefail).
    callgrind_annotate target/speed/out/optimize-cg.out >target/speed/out/optimize-cg.txt 2>/dev/null || true
    opt_ir=$(awk '/PROGRAM TOTALS/ { print $1; exit }' target/speed/out/optimize-cg.txt)
    speed_row "| ${SPEED_JOB:-} | instructions, sweep --no-plots ${opt_args[*]:-without the search}, one thread (callgrind): $opt_ir | | | | | |"
  done
fi
