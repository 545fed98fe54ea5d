# The ground-truth pass on the default scene (docs/speed.md, "The ground-truth pass"): the
# default sweep with and without --ground-truth (12 sampled rows, 240 frames, both snap modes),
# and analyze --ground-truth (one setting, with the texel counts it prints).
# SPEED_CALLGRIND=1 adds the instruction counts (valgrind, one thread, load-proof; slow) of the
# sweep reduced to three rows (λ 0.2, 0.4, 0.6 at 4 cascades of 2048²), at 24 frames (frame 0's
# passes weigh more) and at the file's 240 (the walks weigh as in the whole sweep), and of one
# row of them (λ 0.4) at 240 frames.
paired "sweep configs/default.toml" "sweep configs/default.toml --ground-truth" -- \
  "$BIN" sweep configs/default.toml --quiet --out target/speed/out/gt-plain -- \
  "$BIN" sweep configs/default.toml --quiet --ground-truth --out target/speed/out/gt-sweep
measure "analyze configs/default.toml --ground-truth" -- \
  "$BIN" analyze configs/default.toml --ground-truth --quiet --out target/speed/out/gt-analyze
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  GT=$SPEED_ROOT/target/speed/gt
  mkdir -p "$GT"
  for run in "three_rows 24 0.2, 0.4, 0.6" "three_rows 240 0.2, 0.4, 0.6" "one_row 240 0.4"; do
    read -r name frames lambdas <<<"$run"
    sed -e "s/^frames = 240/frames = $frames/" \
      -e "s/^lambda = {.*/lambda = [$lambdas]/" \
      -e 's/^cascades = \[1, .*/cascades = [4]/' \
      -e 's/^resolution = \[512, .*/resolution = [2048]/' configs/default.toml > "$GT/${name}_$frames.toml"
    RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$GT/cg_${name}_$frames.out" \
      "$BIN" sweep "$GT/${name}_$frames.toml" --ground-truth --quiet --out "$GT/out_${name}_$frames" >/dev/null 2>&1
    callgrind_annotate "$GT/cg_${name}_$frames.out" > "$GT/cg_${name}_$frames.txt" 2>/dev/null
    gt_ir=$(awk '/PROGRAM TOTALS/ { print $1; exit }' "$GT/cg_${name}_$frames.txt")
    speed_row "| ${SPEED_JOB:-} | instructions, sweep --ground-truth of ${name/_/ } (λ $lambdas) at $frames frames (callgrind, 1 thread): $gt_ir | | | | | |"
  done
fi
