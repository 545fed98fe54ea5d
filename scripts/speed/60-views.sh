# A level of views (docs/views.md, "Cast once per view"): the 20-view sweep of the default scene
# against the same sweep with [camera] alone (paired, with the CPU ratio), and 100 player views
# sampled on the default scene at the default screen scale (sweep and analyze). The pair runs
# at least 10 times each (interleaved): a 0.08 s run varies by 5-10 % here, and the ratio is
# issue 22's goal.
RUNS=$((RUNS > 10 ? RUNS : 10)) paired "sweep configs/default.toml --no-plots" "sweep benches/default_20_views.toml --no-plots" -- \
  "$BIN" sweep configs/default.toml --no-plots --quiet --out target/speed/out/views-1 -- \
  "$BIN" sweep benches/default_20_views.toml --no-plots --quiet --out target/speed/out/views-20
measure "sweep benches/default_100_sampled_views.toml --no-plots" -- \
  "$BIN" sweep benches/default_100_sampled_views.toml --no-plots --quiet --out target/speed/out/views-100
measure "analyze benches/default_100_sampled_views.toml" -- \
  "$BIN" analyze benches/default_100_sampled_views.toml --quiet --out target/speed/out/views-100-analyze
# SPEED_CALLGRIND=1 adds the instruction counts of the two paired sweeps at --threads 1 and
# their ratio (valgrind, load-proof; slow: about a minute for the 20 views).
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  views_dir=$SPEED_ROOT/target/speed/views-cg
  mkdir -p "$views_dir"
  views_ir=()
  for views_cfg in configs/default.toml benches/default_20_views.toml; do
    valgrind --tool=callgrind --callgrind-out-file="$views_dir/cg.out" \
      "$BIN" sweep "$views_cfg" --no-plots --quiet --threads 1 --out "$views_dir/out" >/dev/null 2>&1
    # Through a file: awk's early exit would end callgrind_annotate by SIGPIPE (pipefail).
    callgrind_annotate "$views_dir/cg.out" >"$views_dir/cg.txt" 2>/dev/null || true
    views_ir+=("$(awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1; exit }' "$views_dir/cg.txt")")
  done
  speed_row "| ${SPEED_JOB:-} | instructions (callgrind, --threads 1), 1 view / 20 views: ${views_ir[0]} / ${views_ir[1]} ($(awk -v a="${views_ir[0]}" -v b="${views_ir[1]}" 'BEGIN { printf "%.2f", b / a }') ×) | | | | | |"
fi
# SPEED_CACHEGRIND=1 adds the simulated first-level data misses (D1, reads + writes) of the same
# two sweeps at --threads 1 (valgrind --tool=cachegrind --cache-sim=yes; this machine's
# virtualised CPU gives perf no hardware counters).
if [ "${SPEED_CACHEGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  views_dir=$SPEED_ROOT/target/speed/views-cg
  mkdir -p "$views_dir"
  views_d1=()
  for views_cfg in configs/default.toml benches/default_20_views.toml; do
    valgrind --tool=cachegrind --cache-sim=yes --cachegrind-out-file="$views_dir/cachegrind.out" \
      "$BIN" sweep "$views_cfg" --no-plots --quiet --threads 1 --out "$views_dir/out" >/dev/null 2>"$views_dir/cachegrind.txt" || true
    views_d1+=("$(awk '/D1  misses:/ { gsub(",", "", $4); print $4; exit }' "$views_dir/cachegrind.txt")")
  done
  speed_row "| ${SPEED_JOB:-} | D1 misses (cachegrind, --threads 1), 1 view / 20 views: ${views_d1[0]} / ${views_d1[1]} ($(awk -v a="${views_d1[0]}" -v b="${views_d1[1]}" 'BEGIN { printf "%.2f", b / a }') ×) | | | | | |"
fi
