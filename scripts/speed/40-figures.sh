# Figures against no figures: the default sweep end to end with every figure (SVG, PNG, the
# report's inlined copies) and with --no-plots, paired; then a 6,720-setting grid (the default
# with 40 resolutions), where the heat map draws 6 of them and no PNG passes 8 million pixels,
# for memory (max RSS). The load-proof figure beside it (docs/speed.md) is the instruction count of
# the same two default runs, one thread each (SPEED_CALLGRIND=1 adds the row):
#   RAYON_NUM_THREADS=1 valgrind --tool=callgrind "$BIN" sweep configs/default.toml [--no-plots] --quiet --out DIR
paired "sweep configs/default.toml --no-plots" "sweep configs/default.toml (every figure)" -- \
  "$BIN" sweep configs/default.toml --no-plots --quiet --out target/speed/out/figures-none -- \
  "$BIN" sweep configs/default.toml --quiet --out target/speed/out/figures
big=target/speed/default-6720.toml
R=$(seq -s ', ' 512 128 5504)
sed -e "/^\[sweep\]/,\$ s/^resolution = .*/resolution = [$R]/" configs/default.toml > "$big"
paired "sweep 6,720 settings --no-plots" "sweep 6,720 settings (every figure)" -- \
  "$BIN" sweep "$big" --no-plots --quiet --out target/speed/out/figures-6720-none -- \
  "$BIN" sweep "$big" --quiet --out target/speed/out/figures-6720
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  fig_cg=$SPEED_ROOT/target/speed/figures-cg
  mkdir -p "$fig_cg"
  # fig_ir NAME ARGS...: the default sweep's instructions on one thread, with ARGS.
  fig_ir() {
    local name=$1; shift
    RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$fig_cg/cg.$name" \
      "$BIN" sweep configs/default.toml "$@" --quiet --out "$fig_cg/out-$name" >/dev/null 2>&1
    # Through a file: awk's early exit would end callgrind_annotate by SIGPIPE (pipefail).
    callgrind_annotate "$fig_cg/cg.$name" >"$fig_cg/cg.$name.txt" 2>/dev/null || true
    awk '/PROGRAM TOTALS/ && !seen { gsub(",", "", $1); print $1; seen = 1 }' "$fig_cg/cg.$name.txt"
  }
  fig_all=$(fig_ir all)
  fig_none=$(fig_ir none --no-plots)
  speed_row "| ${SPEED_JOB:-} | instructions (callgrind, 1 thread): every figure $fig_all, --no-plots $fig_none, the figures' own **$(awk -v a="$fig_all" -v b="$fig_none" 'BEGIN { printf "%.0f M, %.2f×", (a - b) / 1e6, a / b }')** | | | | | |"
fi
