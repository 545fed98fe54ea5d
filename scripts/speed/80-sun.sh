# Sun-angle sweeps (docs/speed.md, "Sun-angle sweeps"): the configured setting of the default
# scene under 24 azimuths × 17 elevations = 408 light directions, every file written (figures
# included), bounds only (benches/default_bounds_only.toml) and with the scene geometry
# (configs/default.toml: the rays cast once, shaded once per angle). Best of RUNS by CPU each.
SUN_ARGS=(--quiet --lambda 0.75 --cascades 4 --resolution 2048 --sun-azimuth 0:345:15 --sun-elevation 5:85:5)
measure "sweep benches/default_bounds_only.toml, 408 sun angles" -- \
  "$BIN" sweep benches/default_bounds_only.toml "${SUN_ARGS[@]}" --out target/speed/out/sun-bounds
measure "sweep configs/default.toml, 408 sun angles" -- \
  "$BIN" sweep configs/default.toml "${SUN_ARGS[@]}" --out target/speed/out/sun-geometry
