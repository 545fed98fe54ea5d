# The plain commands on the default scene: what every other row is compared with.
measure "analyze configs/default.toml" -- \
  "$BIN" analyze configs/default.toml --quiet --out target/speed/out/analyze
measure "sweep configs/default.toml --no-plots" -- \
  "$BIN" sweep configs/default.toml --no-plots --quiet --out target/speed/out/sweep
