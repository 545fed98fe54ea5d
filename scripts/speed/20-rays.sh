# The visibility pass's rays against Embree (embreex from PyPI) on the very same rays, one
# thread each: full-HD primary rays of the default camera over the default scene and over a
# 100k- and a 1M-triangle terrain (examples/rays.rs; the peer is benches/peers/embree_rays.py,
# run under `taskset -c 0` so that Embree's TBB build uses one CPU too). Each side is run RUNS
# times, interleaved, and reports its own build and trace CPU time (user + sys of the process
# around that step); the best of each is kept. Then the whole pass as a command: a one-setting
# sweep sampling every pixel against the same sweep sampling 1/8 of each axis (paired, whole
# process), whose CPU difference is what the full-HD pass costs end to end.
if [ -z "${RAYS_BIN:-}" ]; then
  cargo build --release --locked --quiet --example rays
  RAYS_BIN=$SPEED_ROOT/target/release/examples/rays
fi
PY=$(peer_python)
rays_dir=$SPEED_ROOT/target/speed/rays

cpu_of() { printf '%s\n' "$2" | awk -v k="$1" 'index($0, k " CPU s ") == 1 { print $4; exit }'; }
hits_of() { printf '%s\n' "$1" | awk '/^hits / { print $2; exit }'; }
min_of() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b + 0 < a + 0) print b; else print a }'; }

for scene in default terrain-100k terrain-1m; do
  "$RAYS_BIN" "$scene" --dump "$rays_dir/$scene" >/dev/null
  ours_build="" ours_trace="" peer_build="" peer_trace="" ours_hits="" peer_hits="" differ=""
  load=$(cut -d' ' -f1 /proc/loadavg)
  for _ in $(seq "$RUNS"); do
    out=$("$RAYS_BIN" "$scene")
    ours_build=$(min_of "$ours_build" "$(cpu_of build "$out")")
    ours_trace=$(min_of "$ours_trace" "$(cpu_of trace "$out")")
    ours_hits=$(hits_of "$out")
    out=$(taskset -c 0 "$PY" "$SPEED_ROOT/benches/peers/embree_rays.py" "$rays_dir/$scene")
    peer_build=$(min_of "$peer_build" "$(cpu_of build "$out")")
    peer_trace=$(min_of "$peer_trace" "$(cpu_of trace "$out")")
    peer_hits=$(hits_of "$out")
    differ=$(printf '%s\n' "$out" | awk '/^hit or miss differs / { print $5 }')
  done
  rays=$(wc -c <"$rays_dir/$scene/rays.f32")
  rays=$((rays / 32))
  mrays() { awk -v n="$rays" -v t="$1" 'BEGIN { printf "%.2f", n / t / 1e6 }'; }
  speed_row "| ${SPEED_JOB} | $scene: csm-lab build (1 thread) | | $ours_build | | | $load |"
  speed_row "| ${SPEED_JOB} | $scene: csm-lab trace, $rays rays, $ours_hits hits: **$(mrays "$ours_trace") M rays per CPU-second** | | $ours_trace | | | $load |"
  speed_row "| ${SPEED_JOB} | $scene: Embree build (taskset -c 0) | | $peer_build | | | $load |"
  speed_row "| ${SPEED_JOB} | $scene: Embree trace, $rays rays, $peer_hits hits ($differ rays hit in one only): **$(mrays "$peer_trace") M rays per CPU-second** | | $peer_trace | | | $load |"
  speed_row "| ${SPEED_JOB} | $scene: trace CPU ratio Embree / csm-lab (above 1: csm-lab faster) | | $(awk -v a="$ours_trace" -v b="$peer_trace" 'BEGIN { printf "%.2f×", b / a }') | | | |"
  [ "$scene" = default ] && embree_default=$(awk -v c="$peer_build" -v d="$peer_trace" 'BEGIN { printf "%.4f", c + d }')
  speed_row "| ${SPEED_JOB} | $scene: build + trace CPU, csm-lab / Embree | | $(awk -v a="$ours_build" -v b="$ours_trace" -v c="$peer_build" -v d="$peer_trace" 'BEGIN { printf "%.4f / %.4f = %.2f×", a + b, c + d, (a + b) / (c + d) }') | | | |"
done

# The whole pass end to end: the same one-setting sweep at full HD and at 1/8 (whole process,
# every core), interleaved; the CPU difference of the best runs is the full-HD pass's cost.
eighth="" full=""
for _ in $(seq "$RUNS"); do
  eighth=$(pick_less_cpu "$eighth" "$(best_of 1 "$BIN" sweep benches/rays_one_setting_eighth.toml --no-plots --quiet --out target/speed/out/rays-eighth)")
  full=$(pick_less_cpu "$full" "$(best_of 1 "$BIN" sweep benches/rays_one_setting_full_hd.toml --no-plots --quiet --out target/speed/out/rays-full-hd)")
done
emit "sweep benches/rays_one_setting_eighth.toml --no-plots (240 × 135 rays)" "$eighth"
emit "sweep benches/rays_one_setting_full_hd.toml --no-plots (1920 × 1080 rays)" "$full"
pass=$(awk -v a="$(echo "$full" | cut -d' ' -f4)" -v b="$(echo "$eighth" | cut -d' ' -f4)" 'BEGIN { printf "%.2f", a - b }')
speed_row "| ${SPEED_JOB} | the full-HD pass end to end (CPU difference of the two) against Embree's build + trace on the default scene ($embree_default s): **$(awk -v p="$pass" -v e="$embree_default" 'BEGIN { printf "%.2f×", p / e }')** | | $pass | | | |"
# The same two sweeps' instructions (callgrind, whole process; load-proof), with SPEED_CALLGRIND=1.
if [ "${SPEED_CALLGRIND:-0}" = 1 ] && command -v valgrind >/dev/null; then
  rays_ir() {
    valgrind --tool=callgrind --callgrind-out-file="$rays_dir/cg.$1" \
      "$BIN" sweep "benches/rays_one_setting_$1.toml" --no-plots --quiet --out "target/speed/out/rays-cg-$1" >/dev/null 2>&1
    # Through a file: awk's early exit would end callgrind_annotate by SIGPIPE (pipefail).
    callgrind_annotate "$rays_dir/cg.$1" >"$rays_dir/cg.$1.txt" 2>/dev/null || true
    awk '/PROGRAM TOTALS/ && !seen { gsub(",", "", $1); print $1; seen = 1 }' "$rays_dir/cg.$1.txt"
  }
  ir_full=$(rays_ir full_hd)
  ir_eighth=$(rays_ir eighth)
  speed_row "| ${SPEED_JOB} | instructions (callgrind): full HD $ir_full, 1/8 $ir_eighth, the full-HD pass **$(awk -v a="$ir_full" -v b="$ir_eighth" 'BEGIN { printf "%.2f G", (a - b) / 1e9 }')** | | | | | |"
fi
