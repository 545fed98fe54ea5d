# `csm-lab bench` (docs/speed.md, "`csm-lab bench`"): the whole command (best of RUNS by CPU),
# then one more run whose own table (the smallest sample count reaching 1e-3 with its time, and
# the error and time at the default) becomes one row per metric. Its errors are deterministic;
# its times are its own wall-clock timings of one evaluation (best of --repeats 5 batches).
measure "bench --repeats 5 (whole process)" -- \
  "$BIN" bench --repeats 5 --quiet --out target/speed/out/bench
bench_load=$(cut -d' ' -f1 /proc/loadavg)
"$BIN" bench --repeats 5 --quiet --out target/speed/out/bench |
  awk 'NF == 8 && $1 ~ /^[a-z0-9_]+$/ && $2 ~ /\./ {
         printf "%s reaches 1e-3 at %s (%s s, error %s); default %s: error %s, %s s\n", $1, $3, $4, $5, $6, $7, $8
       }' |
  while read -r bench_line; do
    speed_row "| ${SPEED_JOB:-} | bench: $bench_line | | | | | $bench_load |"
  done
