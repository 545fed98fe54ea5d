# What counting the render cost costs a sweep (docs/cost.md, "Measured overhead"): the same
# binary with `[cost] counts = false` (no counts) against the default counts, then against
# receiver-aware culling and against the means over the camera path, on the default scene and
# on a ~97k-triangle glTF terrain (`examples/gltf_scene.rs ... 220`: 96,912 triangles, one
# terrain object of 96,800 and eight houses). Paired runs (A B A B ...), best of RUNS by CPU.
# Figures are off (--no-plots) so the rows time the counting, not the drawing of cost_pareto.
# With BIN_BEFORE=path (an older release binary) each sweep row is also paired before → after:
# the same config and command with BIN_BEFORE and with BIN. With CALLGRIND=1 each sweep's
# instructions are counted too (valgrind --tool=callgrind, one run each: the figure that does
# not depend on the machine's load; one thread, RAYON_NUM_THREADS=1), as rows "instructions ...".
COST_DIR=$SPEED_ROOT/target/speed/cost
mkdir -p "$COST_DIR"
if [ ! -s "$COST_DIR/big.gltf" ]; then
  (cd "$SPEED_ROOT" && cargo run --release --locked --quiet --example gltf_scene -- "$COST_DIR/big.gltf" 220 >&2)
fi

# cost_config SRC DST GLTF COST_TABLE SWEEP_EXTRA: SRC with scene.gltf = GLTF (when given),
# COST_TABLE appended as [cost] (when given) and SWEEP_EXTRA added to its [sweep] table.
cost_config() {
  local src=$1 dst=$2 gltf=$3 cost=$4 sweep=$5
  sed -e "s|^gltf = .*|gltf = \"$gltf\"|" -e "s|^\[sweep\]$|[sweep]\n$sweep|" "$src" > "$dst"
  if [ -n "$cost" ]; then printf '\n[cost]\n%s\n' "$cost" >> "$dst"; fi
}

# instructions LABEL CMD...: one row with the instructions executed by CMD (callgrind's Ir),
# when CALLGRIND=1.
instructions() {
  [ "${CALLGRIND:-0}" = 1 ] || return 0
  local label=$1; shift
  local out
  out=$(mktemp)
  RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$out" "$@" >/dev/null 2>&1
  speed_row "| ${SPEED_JOB:-} | instructions: $label | | $(callgrind_annotate "$out" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); printf "%.3f G", $1 / 1e9 }') | | | | |"
  rm -f "$out"
}

for scene in default big; do
  case $scene in
    default) src=$SPEED_ROOT/configs/default.toml; gltf="" ;;
    big) src=$SPEED_ROOT/configs/village.toml; gltf=$COST_DIR/big.gltf ;;
  esac
  cost_config "$src" "$COST_DIR/$scene-off.toml" "$gltf" "counts = false" ""
  cost_config "$src" "$COST_DIR/$scene-on.toml" "$gltf" "" ""
  cost_config "$src" "$COST_DIR/$scene-cull.toml" "$gltf" 'cull = "receivers"' ""
  cost_config "$src" "$COST_DIR/$scene-means.toml" "$gltf" "" "cost_means = true"
  sweep() { echo "$BIN" sweep "$COST_DIR/$scene-$1.toml" --no-plots --quiet --out "$COST_DIR/out-$scene-$1"; }
  analyze() { echo "$BIN" analyze "$COST_DIR/$scene-$1.toml" --quiet --out "$COST_DIR/analyze-$scene-$1"; }
  # shellcheck disable=SC2046
  paired "$scene sweep, counts off" "$scene sweep, counts on" -- $(sweep off) -- $(sweep on)
  if [ -n "${BIN_BEFORE:-}" ]; then
    for kind in on cull; do
      # shellcheck disable=SC2046
      paired "$scene sweep $kind, before" "$scene sweep $kind, after" -- $(BIN=$BIN_BEFORE sweep $kind) -- $(sweep $kind)
    done
  fi
  for kind in off on cull; do
    # shellcheck disable=SC2046
    instructions "$scene sweep $kind" $(sweep $kind)
    # shellcheck disable=SC2046
    [ -z "${BIN_BEFORE:-}" ] || instructions "$scene sweep $kind, before" $(BIN=$BIN_BEFORE sweep $kind)
  done
  # shellcheck disable=SC2046
  paired "$scene sweep, counts on" "$scene sweep, cull = receivers" -- $(sweep on) -- $(sweep cull)
  # The means over the path count every frame: on the default scene a whole sweep, on the big
  # one a single analysis (frame 0's counts and the means over its 240 frames against neither;
  # a sweep of it with the means takes minutes).
  if [ "$scene" = default ]; then
    # shellcheck disable=SC2046
    paired "$scene sweep, counts on" "$scene sweep, cost_means = true" -- $(sweep on) -- $(sweep means)
  fi
  # shellcheck disable=SC2046
  paired "$scene analyze, counts off" "$scene analyze, counts and means" -- $(analyze off) -- $(analyze on)
done
