# The ground-truth pass on the default scene (docs/speed.md, "The ground-truth pass"): the
# default sweep with and without --ground-truth (12 sampled rows, 240 frames, both snap modes),
# and analyze --ground-truth (one setting, with the texel counts it prints).
# SPEED_CALLGRIND=1 adds the instruction count (valgrind, one thread, load-proof; slow) of the
# sweep reduced to three rows (λ 0.2, 0.4, 0.6 at 4 cascades of 2048²) and 24 frames.
paired "sweep configs/default.toml" "sweep configs/default.toml --ground-truth" -- \
  "$BIN" sweep configs/default.toml --quiet --out target/speed/out/gt-plain -- \
  "$BIN" sweep configs/default.toml --quiet --ground-truth --out target/speed/out/gt-sweep
measure "analyze configs/default.toml --ground-truth" -- \
  "$BIN" analyze configs/default.toml --ground-truth --quiet --out target/speed/out/gt-analyze
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  GT=$SPEED_ROOT/target/speed/gt
  mkdir -p "$GT"
  sed -e 's/^frames = 240/frames = 24/' \
    -e 's/^lambda = {.*/lambda = [0.2, 0.4, 0.6]/' \
    -e 's/^cascades = \[1, .*/cascades = [4]/' \
    -e 's/^resolution = \[512, .*/resolution = [2048]/' configs/default.toml > "$GT/three_rows.toml"
  RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$GT/cg.out" \
    "$BIN" sweep "$GT/three_rows.toml" --ground-truth --quiet --out "$GT/out" >/dev/null 2>&1
  gt_ir=$(callgrind_annotate "$GT/cg.out" 2>/dev/null | awk '/PROGRAM TOTALS/ { print $1; exit }')
  speed_row "| ${SPEED_JOB:-} | instructions, sweep --ground-truth of 3 rows at 24 frames (callgrind, 1 thread): $gt_ir | | | | | |"
fi
