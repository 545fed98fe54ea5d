#!/usr/bin/env python3
"""The peer of csm-lab's visibility pass: Embree (embreex from PyPI) on the very same rays.

    cargo run --release --example rays -- default --dump target/speed/rays/default
    taskset -c 0 python3 benches/peers/embree_rays.py target/speed/rays/default

Reads the dump the `rays` example writes: `tris.f32` (9 binary32 per triangle), `rays.f32`
(8 per ray: origin, unit direction, tmin, tmax) and, if present, `hits.u32` (csm-lab's
triangle per ray, 2^32 - 1 for a miss). Builds an Embree scene of the triangles and traces
every ray once with `rtcIntersect1` (embreex's `run(..., output=1)`), then prints the CPU
time (user + sys of the process, `time.process_time`) of the build and of the trace, rays per
CPU-second, the number of rays that hit, and how many rays csm-lab answers differently.

One thread: Embree's build runs on TBB, which uses every CPU the process may run on, so run
it under `taskset -c 0` (the trace is one thread whatever the mask: embreex calls
`rtcIntersect1` ray by ray). embreex exposes no tmin: its rays start at the origin. csm-lab's
tmin is the camera's near plane (0.1 m), and nothing in these scenes is that close to the
camera, so the hits are the same; the count of disagreements below checks it.
"""
import os
import sys
import time

import numpy as np
from embreex import mesh_construction, rtcore_scene


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: embree_rays.py DUMP_DIR")
    d = sys.argv[1]
    tris = np.fromfile(os.path.join(d, "tris.f32"), dtype="<f4").reshape(-1, 3, 3)
    rays = np.fromfile(os.path.join(d, "rays.f32"), dtype="<f4").reshape(-1, 8)
    origins = np.ascontiguousarray(rays[:, 0:3])
    dirs = np.ascontiguousarray(rays[:, 3:6])
    tmax = np.ascontiguousarray(rays[:, 7])

    t0 = time.process_time()
    scene = rtcore_scene.EmbreeScene()
    mesh_construction.TriangleMesh(scene, tris)
    # Embree builds lazily, on the first query: one ray that misses everything commits it.
    scene.run(np.zeros((1, 3), np.float32), np.array([[0.0, 1.0, 0.0]], np.float32),
              dists=np.zeros(1, np.float32))
    build = time.process_time() - t0

    t1 = time.process_time()
    out = scene.run(origins, dirs, dists=tmax, output=1)
    trace = time.process_time() - t1

    prim = out["primID"]
    hits = int((prim >= 0).sum())
    n = len(rays)
    print(f"embree: {len(tris)} triangles, {n} rays, affinity {sorted(os.sched_getaffinity(0))}")
    print(f"build CPU s {build:.4f}")
    print(f"trace CPU s {trace:.4f} ({n / trace / 1e6:.2f} M rays per CPU-second)")
    print(f"build+trace CPU s {build + trace:.4f}")
    print(f"hits {hits}")
    path = os.path.join(d, "hits.u32")
    if os.path.exists(path):
        ours = np.fromfile(path, dtype="<u4").astype(np.int64)
        ours[ours == 0xFFFFFFFF] = -1
        theirs = prim.astype(np.int64)
        print(f"csm-lab hits {int((ours >= 0).sum())}")
        print(f"hit or miss differs {int(((ours >= 0) != (theirs >= 0)).sum())}")
        print(f"other triangle {int(((ours >= 0) & (theirs >= 0) & (ours != theirs)).sum())}")


if __name__ == "__main__":
    main()
