# A moving light (docs/speed.md, "A moving light"): the bounds-only scene of configs/sunset.toml
# under a still light (no [sweep] table, no light update or light path, a 240-frame strafe of
# 0.05 units a frame) and the same under a sun turning 0.01° east and 0.02° down per frame:
# `analyze` and the default 672-setting `sweep` of each, best of RUNS by CPU.
# SPEED_CALLGRIND=1 adds their instruction counts (valgrind, load-proof): the whole process and
# the walk (`walk::walk`, inclusive); the sweep on one thread (RAYON_NUM_THREADS=1).
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
  # ml_callgrind LABEL OUT_FILE CMD...: one row with the whole process's and the walk's instructions
  ml_callgrind() {
    local label=$1 cg=$2; shift 2
    valgrind --tool=callgrind --callgrind-out-file="$cg" "$@" >/dev/null 2>&1
    local total walk
    total=$(callgrind_annotate "$cg" 2>/dev/null | awk '/PROGRAM TOTALS/ { print $1; exit }')
    walk=$(callgrind_annotate --inclusive=yes "$cg" 2>/dev/null |
      awk '/walk::walk[^_a-z]/ { print $1; exit }')
    speed_row "| ${SPEED_JOB:-} | $label (callgrind): $total instructions, the walk (walk::walk, inclusive) $walk | | | | | |"
  }
  for ml_light in still sun; do
    ml_callgrind "analyze, $ml_light light" "$ML/cg.analyze.$ml_light" \
      "$BIN" analyze "$ML/$ml_light.toml" --quiet --out "$ML/cga-$ml_light"
    RAYON_NUM_THREADS=1 ml_callgrind "sweep --no-plots, 1 thread, $ml_light light" "$ML/cg.sweep.$ml_light" \
      "$BIN" sweep "$ML/$ml_light.toml" --quiet --no-plots --out "$ML/cgs-$ml_light"
  done
fi
