# Figures against no figures: the default sweep end to end with every figure (SVG, PNG, the
# report's inlined copies) and with --no-plots, paired; then a 6,720-setting grid (the default
# with 40 resolutions), where the heat map draws 6 of them and no PNG passes 8 million pixels,
# for memory (max RSS). The load-proof figure beside it (docs/speed.md) is the instruction count of
# the same two default runs, one thread each:
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
