# A moving light (docs/speed.md, "A moving light"): the bounds-only scene of configs/sunset.toml
# under a still light (no [sweep] table, no light update or light path, a 240-frame strafe of
# 0.05 units a frame) and the same under a sun turning 0.01° east and 0.02° down per frame:
# `analyze` and the default 672-setting `sweep` of each, best of RUNS by CPU.
# SPEED_CALLGRIND=1 adds instruction counts (valgrind, load-proof): the whole process and the
# walk (`walk::walk`, inclusive) of `analyze` under each light, and of the still light's sweep
# on one thread (RAYON_NUM_THREADS=1).
ML=$SPEED_ROOT/target/speed/moving-light
mkdir -p "$ML"
sed -e '/^\[sweep\]/,$d' -e '/^light_update/d' -e '/^light_path/d' -e '/^sun_/d' \
  -e 's/^path = .*/path = "strafe"\nstep = 0.05/' -e 's/^frames = .*/frames = 240/' \
  configs/sunset.toml > "$ML/still.toml"
sed -e 's/^frames = 240/frames = 240\nlight_path = "sun"\nsun_azimuth_step_deg = 0.01\nsun_elevation_step_deg = -0.02/' \
  "$ML/still.toml" > "$ML/sun.toml"
for ml_light in still sun; do
  measure "analyze, sunset scene bounds only, $ml_light light" -- \
    "$BIN" analyze "$ML/$ml_light.toml" --quiet --out "$ML/a-$ml_light"
  measure "sweep --no-plots, 672 settings, $ml_light light" -- \
    "$BIN" sweep "$ML/$ml_light.toml" --quiet --no-plots --out "$ML/s-$ml_light"
done
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  # ml_callgrind LABEL OUT_FILE WALK CMD...: one row with the whole process's instructions and
  # the walk's, inclusive: the first function whose name matches the pattern WALK (`analyze`:
  # the generic walker `walk::walk*`; the sweep: `analysis::walk_path`, into which the
  # probe-free walk is inlined)
  ml_callgrind() {
    local label=$1 cg=$2 pattern=$3; shift 3
    valgrind --tool=callgrind --callgrind-out-file="$cg" "$@" >/dev/null 2>&1
    callgrind_annotate "$cg" >"$cg.txt" 2>/dev/null || true
    callgrind_annotate --inclusive=yes "$cg" >"$cg.inclusive.txt" 2>/dev/null || true
    local total walk
    total=$(awk '/PROGRAM TOTALS/ && !seen { print $1; seen = 1 }' "$cg.txt")
    walk=$(awk -v p="$pattern" '$0 ~ p && !seen { print $1, $3; seen = 1 }' "$cg.inclusive.txt")
    speed_row "| ${SPEED_JOB:-} | $label (callgrind): $total instructions; the walk, inclusive: $walk | | | | | |"
  }
  for ml_light in still sun; do
    ml_callgrind "analyze, $ml_light light" "$ML/cg.analyze.$ml_light" 'walk::walk' \
      "$BIN" analyze "$ML/$ml_light.toml" --quiet --out "$ML/cga-$ml_light"
  done
  # The sweep under the still light only: under the turning sun it runs about 13 s of CPU,
  # which valgrind stretches past ten minutes.
  RAYON_NUM_THREADS=1 ml_callgrind "sweep --no-plots, 1 thread, still light" "$ML/cg.sweep.still" 'analysis::walk_path' \
    "$BIN" sweep "$ML/still.toml" --quiet --no-plots --out "$ML/cgs-still"
fi
