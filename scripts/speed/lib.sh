# Shared helpers for scripts/speed.sh: sourced, never run on its own.
# measure LABEL -- CMD...             best of $RUNS runs by CPU time; one table row
# paired LABEL_A LABEL_B -- CMD_A... -- CMD_B...
#                                     A and B interleaved (A B A B ...), best of $RUNS each,
#                                     one row each and a row with the CPU ratio B / A
# Every row also gives the run's peak resident memory (max RSS).
# peer_python                         prints the venv's python (numpy, embreex), installing once
# All rows go to stdout and to target/speed/speed.md.
RUNS=${RUNS:-3}
BIN=${BIN:-$SPEED_ROOT/target/release/csm-lab}
SPEED_MD=$SPEED_ROOT/target/speed/speed.md

speed_row() { printf '%s\n' "$*" | tee -a "$SPEED_MD"; }

speed_header() {
  : > "$SPEED_MD"
  speed_row "# csm-lab speed, $(date -u +%Y-%m-%dT%H:%MZ), commit $(git -C "$SPEED_ROOT" rev-parse --short HEAD 2>/dev/null || echo '?'), $(nproc) cores, best of $RUNS by CPU"
  speed_row ""
  speed_row "| job | run | wall s | CPU s (user+sys) | user s | sys s | load at start | max RSS MiB |"
  speed_row "|---|---|---|---|---|---|---|---|"
}
speed_section() { SPEED_JOB=$1; }
speed_footer() { speed_row ""; speed_row "written to target/speed/speed.md"; }

# one_run CMD...: prints "wall user sys maxrss_kb" of one whole-process run; the command's own output is
# discarded (its exit status must be 0 or 1: 1 is a threshold verdict, not a failure). The
# child's own CPU and peak memory to the microsecond (scripts/speed/one_run.py); without python3,
# /usr/bin/time's, rounded to 10 ms.
one_run() {
  local t
  t=$(mktemp)
  local timer=(/usr/bin/time -f '%e %U %S %M' -o "$t")
  if command -v python3 >/dev/null; then
    timer=(python3 "$SPEED_ROOT/scripts/speed/one_run.py" "$t")
  fi
  "${timer[@]}" "$@" >/dev/null 2>&1 || {
    local rc=$?
    if [ "$rc" -ne 1 ]; then echo "speed: '$*' exited $rc" >&2; rm -f "$t"; return "$rc"; fi
  }
  tail -n 1 "$t"
  rm -f "$t"
}

# best_of N CMD...: runs N times, prints "wall user sys cpu load maxrss_kb" of the run with least CPU
best_of() {
  local n=$1; shift
  local best="" bestcpu=""
  for _ in $(seq "$n"); do
    local load w u s m cpu
    load=$(cut -d' ' -f1 /proc/loadavg)
    read -r w u s m < <(one_run "$@")
    cpu=$(awk -v u="$u" -v s="$s" 'BEGIN { printf "%.3f", u + s }')
    if [ -z "$bestcpu" ] || awk -v a="$cpu" -v b="$bestcpu" 'BEGIN { exit !(a < b) }'; then
      bestcpu=$cpu; best="$w $u $s $cpu $load $m"
    fi
  done
  echo "$best"
}

emit() { # label "wall user sys cpu load maxrss_kb"
  local label=$1 w u s cpu load m
  read -r w u s cpu load m <<<"$2"
  speed_row "| ${SPEED_JOB:-} | $label | $w | $cpu | $u | $s | $load | $(awk -v k="$m" 'BEGIN { printf "%.1f", k / 1024 }') |"
}

measure() {
  local label=$1; shift
  [ "$1" = "--" ] && shift
  emit "$label" "$(best_of "$RUNS" "$@")"
}

paired() {
  local la=$1 lb=$2; shift 2
  [ "$1" = "--" ] && shift
  local a=() b=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do a+=("$1"); shift; done
  shift
  b=("$@")
  local besta="" bestb="" i
  for i in $(seq "$RUNS"); do
    local ra rb
    ra=$(best_of 1 "${a[@]}"); rb=$(best_of 1 "${b[@]}")
    besta=$(pick_less_cpu "$besta" "$ra"); bestb=$(pick_less_cpu "$bestb" "$rb")
  done
  emit "$la" "$besta"
  emit "$lb" "$bestb"
  local ca cb
  ca=$(echo "$besta" | cut -d' ' -f4); cb=$(echo "$bestb" | cut -d' ' -f4)
  speed_row "| ${SPEED_JOB:-} | CPU ratio $lb / $la | | $(awk -v a="$ca" -v b="$cb" 'BEGIN { if (a > 0) printf "%.2f×", b / a; else print "n/a" }') | | | | |"
}

pick_less_cpu() {
  if [ -z "$1" ]; then echo "$2"; return; fi
  local c1 c2
  c1=$(echo "$1" | cut -d' ' -f4); c2=$(echo "$2" | cut -d' ' -f4)
  if awk -v a="$c2" -v b="$c1" 'BEGIN { exit !(a < b) }'; then echo "$2"; else echo "$1"; fi
}

peer_python() {
  local venv=$SPEED_ROOT/target/speed/venv
  if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv" >&2
    "$venv/bin/pip" install --quiet numpy embreex >&2
  fi
  echo "$venv/bin/python"
}
