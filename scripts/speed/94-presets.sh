# Engine presets (docs/presets.md): `compare` over every preset with the file's settings and at
# the presets' own defaults; the default Unreal sweep (224 settings) and the same over five
# shadow distances (1,120); and three.js's fade bands: `analyze` of configs/village.toml with
# `preset = "threejs"`, without and with `[threejs] fade = true` (paired). Best of RUNS by CPU.
PRE=$SPEED_ROOT/target/speed/presets
mkdir -p "$PRE"
measure "compare configs/default.toml (every preset)" -- \
  "$BIN" compare configs/default.toml --quiet --out "$PRE/compare"
measure "compare configs/default.toml --defaults (every preset)" -- \
  "$BIN" compare configs/default.toml --defaults --quiet --out "$PRE/compare-defaults"
measure "sweep configs/default.toml --preset unreal --no-plots (224 settings)" -- \
  "$BIN" sweep configs/default.toml --preset unreal --quiet --no-plots --out "$PRE/unreal"
measure "the same with --distance 75,112.5,150,225,300 (1,120 settings)" -- \
  "$BIN" sweep configs/default.toml --preset unreal --distance 75,112.5,150,225,300 --quiet --no-plots --out "$PRE/unreal-d"
sed -e "s|^gltf = .*|gltf = \"$SPEED_ROOT/configs/village.gltf\"|" -e 's/^\[shadow\]$/[shadow]\npreset = "threejs"/' \
  configs/village.toml > "$PRE/threejs-off.toml"
printf '\n[threejs]\nfade = true\n' | cat "$PRE/threejs-off.toml" - > "$PRE/threejs-on.toml"
paired "analyze village, preset threejs" "the same with [threejs] fade = true" -- \
  "$BIN" analyze "$PRE/threejs-off.toml" --quiet --out "$PRE/off" -- \
  "$BIN" analyze "$PRE/threejs-on.toml" --quiet --out "$PRE/on"
