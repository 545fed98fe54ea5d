# Sampled views (docs/view-sources.md): `analyze` of configs/default.toml against the same with
# `[views] sample = 100` (benches/default_100_sampled_views.toml), paired: what sampling and
# checking 100 views and analysing them adds.
paired "analyze configs/default.toml" "analyze benches/default_100_sampled_views.toml" -- \
  "$BIN" analyze configs/default.toml --quiet --out target/speed/out/vs-1 -- \
  "$BIN" analyze benches/default_100_sampled_views.toml --quiet --out target/speed/out/vs-100
