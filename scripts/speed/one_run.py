"""One whole-process run for scripts/speed/lib.sh's one_run: runs argv[2:] with its output
discarded and writes "wall user sys maxrss_kb" to the file argv[1]; exits with the command's
status. CPU and peak memory are the child's own (wait4), to the microsecond: not
RUSAGE_CHILDREN, which would also count what a python launcher (pyenv's shim) reaped before
exec, and not /usr/bin/time, which rounds to 10 ms (12 % of the 0.08 s one-view sweep)."""
import os
import subprocess
import sys
import time

t0 = time.monotonic()
child = subprocess.Popen(sys.argv[2:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
_, status, usage = os.wait4(child.pid, 0)
wall = time.monotonic() - t0
with open(sys.argv[1], "w") as out:
    out.write("%.3f %.4f %.4f %d\n" % (wall, usage.ru_utime, usage.ru_stime, usage.ru_maxrss))
sys.exit(os.waitstatus_to_exitcode(status))
