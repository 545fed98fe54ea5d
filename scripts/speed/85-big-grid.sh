# 100,000 configurations (docs/speed.md, "100,000 configurations"): the default scene with
# 500 λ values × 8 cascade counts × 25 resolutions, as one sweep with and without figures, as 4
# shards merged with and without figures, and through `check --sweep` with and without
# `--sweep-csv`; every row gives its peak RSS. These runs take minutes each, so the job runs
# each once (BIG_RUNS=1, whatever RUNS says; set BIG_RUNS=3 for best of 3). It also checks
# that the merged directory equals the unsharded sweep's, file for file.
BIG=$SPEED_ROOT/target/speed/big
rm -rf "$BIG"
mkdir -p "$BIG"
big_res=$(seq -s ', ' 512 128 3584)
sed -e '/^\[sweep\]/,$ s/^lambda = .*/lambda = { start = 0.002, end = 1.0, step = 0.002 }/' \
  -e "/^\[sweep\]/,\$ s/^resolution = .*/resolution = [$big_res]/" configs/default.toml > "$BIG/big.toml"
big_runs_before=$RUNS
RUNS=${BIG_RUNS:-1}
measure "sweep, 100,000 settings (every figure)" -- \
  "$BIN" sweep "$BIG/big.toml" --quiet --out "$BIG/full"
measure "sweep, 100,000 settings --no-plots" -- \
  "$BIN" sweep "$BIG/big.toml" --quiet --no-plots --out "$BIG/full-np"
for big_k in 1 2 3 4; do
  measure "sweep --shard $big_k/4 --no-plots (25,000 settings)" -- \
    "$BIN" sweep "$BIG/big.toml" --quiet --no-plots --shard "$big_k/4" --out "$BIG/s$big_k"
done
measure "merge of the 4 shards (every figure)" -- \
  "$BIN" merge "$BIG/s1" "$BIG/s2" "$BIG/s3" "$BIG/s4" --quiet --out "$BIG/merged"
measure "merge of the 4 shards --no-plots" -- \
  "$BIN" merge "$BIG/s1" "$BIG/s2" "$BIG/s3" "$BIG/s4" --quiet --no-plots --out "$BIG/merged-np"
if diff -r "$BIG/full" "$BIG/merged" >/dev/null; then big_same=identical; else big_same=DIFFERENT; fi
speed_row "| ${SPEED_JOB:-} | merged directory against the unsharded sweep's (diff -r): $big_same | | | | | |"
measure "check --sweep (runs the sweep)" -- \
  "$BIN" check "$BIG/big.toml" --thresholds configs/thresholds.toml --sweep
measure "check --sweep --sweep-csv merged/sweep.csv" -- \
  "$BIN" check "$BIG/big.toml" --thresholds configs/thresholds.toml --sweep --sweep-csv "$BIG/merged/sweep.csv"
RUNS=$big_runs_before
