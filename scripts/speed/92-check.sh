# A check of the default scene (docs/check.md, "Figures"): `check` with the shipped thresholds
# (the summary analysis and the rules), best of RUNS by CPU.
measure "check configs/default.toml --thresholds configs/thresholds.toml" -- \
  "$BIN" check configs/default.toml --thresholds configs/thresholds.toml
