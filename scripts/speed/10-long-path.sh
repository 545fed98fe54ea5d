# Long paths (docs/speed.md, "Long paths"): `analyze` of the default scene with the camera
# yawing 0.05 degrees a frame (its step unchanged) for 10^6 frames (benches/long_yaw.toml) and
# for 10^5, each the best of RUNS by CPU; then one run of each for its peak memory.
# SPEED_CALLGRIND=1 adds the instruction count at 10^4 frames (valgrind, load-proof; slow).
LONG=$SPEED_ROOT/target/speed/long
mkdir -p "$LONG"
for long_n in 100000 10000; do
  sed "s/^frames = 1000000/frames = $long_n/" benches/long_yaw.toml > "$LONG/yaw$long_n.toml"
done
measure "analyze benches/long_yaw.toml (yaw, 10⁶ frames)" -- \
  "$BIN" analyze benches/long_yaw.toml --quiet --out "$LONG/out6"
measure "analyze, the same at 10⁵ frames" -- \
  "$BIN" analyze "$LONG/yaw100000.toml" --quiet --out "$LONG/out5"
for long_run in "benches/long_yaw.toml 10⁶" "$LONG/yaw100000.toml 10⁵"; do
  read -r long_cfg long_frames <<<"$long_run"
  long_rss=$(/usr/bin/time -f '%M' "$BIN" analyze "$long_cfg" --quiet --out "$LONG/rss" 2>&1 >/dev/null | tail -n 1)
  speed_row "| ${SPEED_JOB:-} | max RSS at $long_frames frames: $long_rss KB | | | | | $(cut -d' ' -f1 /proc/loadavg) |"
done
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  valgrind --tool=callgrind --callgrind-out-file="$LONG/cg.out" \
    "$BIN" analyze "$LONG/yaw10000.toml" --quiet --out "$LONG/cg" >/dev/null 2>&1
  # Through a file: awk's early exit would end callgrind_annotate by SIGPIPE (pipefail).
  callgrind_annotate "$LONG/cg.out" >"$LONG/cg.txt" 2>/dev/null || true
  long_ir=$(awk '/PROGRAM TOTALS/ { print $1; exit }' "$LONG/cg.txt")
  speed_row "| ${SPEED_JOB:-} | instructions at 10⁴ frames (callgrind): $long_ir | | | | | |"
fi
