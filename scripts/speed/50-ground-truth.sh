# The ground-truth pass on the default scene (docs/speed.md, "The ground-truth pass"): the
# default sweep with and without --ground-truth (12 sampled rows, 240 frames, both snap modes),
# and analyze --ground-truth (one setting, with the texel counts it prints).
paired "sweep configs/default.toml" "sweep configs/default.toml --ground-truth" -- \
  "$BIN" sweep configs/default.toml --quiet --out target/speed/out/gt-plain -- \
  "$BIN" sweep configs/default.toml --quiet --ground-truth --out target/speed/out/gt-sweep
measure "analyze configs/default.toml --ground-truth" -- \
  "$BIN" analyze configs/default.toml --ground-truth --quiet --out target/speed/out/gt-analyze
