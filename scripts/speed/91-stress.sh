# The stress battery (docs/accuracy.md, "Measured"): `csm-lab stress` with its default battery
# (66 fixed and 32 random cases, up to 4 analyses each), best of RUNS by CPU.
measure "stress (the default battery, 98 cases)" -- \
  "$BIN" stress --out target/speed/out/stress
