# The ground-truth pass's memory and filters (docs/ground-truth.md, "Speed" and the paragraph on
# streaming): `analyze --ground-truth` of configs/default.toml with the default bilinear filter
# and with `pcf_filter = "nearest"` (paired), then at `screen_scale = 0.05` over 240 and over
# 2,400 frames, whose peak RSS must not grow with the path (best of RUNS by CPU each).
GTM=$SPEED_ROOT/target/speed/gt-memory
mkdir -p "$GTM"
sed 's/^\[shadow\]$/[shadow]\npcf_filter = "nearest"/' configs/default.toml > "$GTM/nearest.toml"
for gtm_frames in 240 2400; do
  sed -e 's/^\[analysis\]$/[analysis]\nscreen_scale = 0.05/' -e "s/^frames = .*/frames = $gtm_frames/" \
    configs/default.toml > "$GTM/scale005-$gtm_frames.toml"
  grep -q '^screen_scale = 0.05' "$GTM/scale005-$gtm_frames.toml" ||
    printf '\n[analysis]\nscreen_scale = 0.05\n' >> "$GTM/scale005-$gtm_frames.toml"
done
paired "analyze configs/default.toml --ground-truth (bilinear)" "the same with pcf_filter = \"nearest\"" -- \
  "$BIN" analyze configs/default.toml --ground-truth --quiet --out "$GTM/bilinear" -- \
  "$BIN" analyze "$GTM/nearest.toml" --ground-truth --quiet --out "$GTM/nearest"
for gtm_frames in 240 2400; do
  measure "analyze --ground-truth, screen_scale 0.05, $gtm_frames frames" -- \
    "$BIN" analyze "$GTM/scale005-$gtm_frames.toml" --ground-truth --quiet --out "$GTM/s$gtm_frames"
done
