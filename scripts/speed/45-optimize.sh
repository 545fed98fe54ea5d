# sweep --optimize-splits on the default scene (28 groups, about 9,400 analyses), paired with
# the same sweep without the search.
paired "sweep configs/default.toml --no-plots" "sweep configs/default.toml --optimize-splits --no-plots" -- \
  "$BIN" sweep configs/default.toml --no-plots --quiet --out target/speed/out/optimize-none -- \
  "$BIN" sweep configs/default.toml --optimize-splits --no-plots --quiet --out target/speed/out/optimize
