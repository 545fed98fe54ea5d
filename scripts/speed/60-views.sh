# A level of views (docs/views.md, "Cast once per view"): the 20-view sweep of the default scene
# against the same sweep with [camera] alone (paired, with the CPU ratio), and 100 player views
# sampled on the default scene at the default screen scale (sweep and analyze).
paired "sweep configs/default.toml --no-plots" "sweep benches/default_20_views.toml --no-plots" -- \
  "$BIN" sweep configs/default.toml --no-plots --quiet --out target/speed/out/views-1 -- \
  "$BIN" sweep benches/default_20_views.toml --no-plots --quiet --out target/speed/out/views-20
measure "sweep benches/default_100_sampled_views.toml --no-plots" -- \
  "$BIN" sweep benches/default_100_sampled_views.toml --no-plots --quiet --out target/speed/out/views-100
measure "analyze benches/default_100_sampled_views.toml" -- \
  "$BIN" analyze benches/default_100_sampled_views.toml --quiet --out target/speed/out/views-100-analyze
