#!/usr/bin/env python3
"""The bounds-only sweep written in numpy: what a user would write instead of csm-lab.

    sweep_numpy.py CONFIG [--out FILE]           the sweep; its rows as CSV (default stdout)
    sweep_numpy.py CONFIG --check SWEEP_CSV       the sweep, then every row compared with the
                                                  same row of csm-lab's sweep.csv (exit 1 if any
                                                  value is outside the tolerance below)

It reads the same TOML file (camera, screen, light, scene bounds, shadow, motion, [sweep]) and
computes, for every setting of the grid (lambda x cascades x resolution, fit "sphere"), the
bounds-only columns of csm-lab's sweep.csv:

* the split range [z_lo, z_hi]: the scene box clipped to the view frustum (near to
  min(far, max_distance)) with `fit_depth_to_scene`, else [near, min(far, max_distance)];
* practical splits, the minimal bounding sphere of each slice, the window side 2R*N/(N-1);
* the aliasing aggregates (max, mean over depth, mean over log depth, under-sampled share);
* along the camera path, for both snap modes: each cascade's window (centre on the view axis
  at the sphere's centre depth, in texel units, rounded half away from zero when snapped),
  the slice corners outside it (coverage) and the RMS sub-texel drift S3 of the window origin
  between frames (the drift every world-fixed point shares when the window keeps its size);
* memory, cleared texels and bytes written.

Everything is vectorised over the settings and the frames: one array per quantity with a row
per cascade of every (lambda, cascades) pair, a column per resolution and an axis of frames.
Only the path (one pose per frame) and the depth range are set up once in plain numpy.

Tolerance of --check: relative 1e-9 on z_lo, z_hi and the aliasing aggregates, absolute 1e-9
texel on the shimmer columns (sums of 10^3 squared drifts in another order), exact on the counts
and sizes. The Pareto front and the recommendation are not part of the peer (csm-lab's ranking
of 672 rows is a negligible part of its run).
"""

import argparse
import csv
import math
import sys
import tomllib
from decimal import Decimal

import numpy as np


def normalize(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def rotate(v, axis, angle):
    """Rodrigues: v (F,3) turned by angle (F,) about the unit axis (3,)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return v * c + np.cross(axis, v) * s + axis * (v @ axis)[:, None] * (1.0 - c)


def camera_path(cam, motion):
    """Positions, forward, right and up axes per frame, (F,3) each."""
    p0 = np.array(cam["position"], float)
    target = np.array(cam["target"], float)
    up = np.array(cam.get("up", [0.0, 1.0, 0.0]), float)
    frames = int(motion.get("frames", 1))
    path = motion.get("path", "still")
    step = float(motion.get("step", 0.0))
    t = np.arange(frames, dtype=float)
    dir0 = target - p0
    fwd0 = normalize(dir0)
    right0 = normalize(np.cross(fwd0, up))
    pos = np.repeat(p0[None], frames, 0)
    dirs = np.repeat(dir0[None], frames, 0)
    if path == "strafe":
        pos = p0 + np.outer(step * t, right0)
    elif path == "dolly":
        pos = p0 + np.outer(step * t, fwd0)
    elif path == "yaw":
        dirs = rotate(dirs, normalize(up), np.radians(step) * t)
    elif path == "pitch":
        dirs = rotate(dirs, right0, np.radians(step) * t)
    elif path == "orbit":
        pos = target + rotate(np.repeat((p0 - target)[None], frames, 0), normalize(up), np.radians(step) * t)
        dirs = target - pos
    elif path != "still":
        sys.exit(f"sweep_numpy: motion.path {path!r} is not one the peer models")
    forward = normalize(dirs)
    right = normalize(np.cross(forward, up))
    return pos, forward, right, np.cross(right, forward)


def light_basis(direction):
    z = normalize(np.array(direction, float))
    ref = np.array([0.0, 0.0, 1.0]) if np.linalg.norm(np.cross([0.0, 1.0, 0.0], z)) < 1e-6 else np.array([0.0, 1.0, 0.0])
    x = normalize(np.cross(ref, z))
    return x, np.cross(z, x)


def depth_range(pos, fwd, right, up, tan_h, tan_v, near, far, lo, hi, fit_to_scene):
    """[z_lo, z_hi]: the view-depth extent of the scene box clipped to the frustum."""
    if not fit_to_scene:
        return near, far
    # Half-spaces n.p <= d of the frustum and the box; the extremes of a linear function over
    # their (convex) intersection sit at its vertices, which lie on edges of one of the two
    # solids where they cross a plane of the other, or at vertices of either.
    fr = [right - tan_h * fwd, -right - tan_h * fwd, up - tan_v * fwd, -up - tan_v * fwd, -fwd, fwd]
    fd = [n @ pos for n in fr[:4]] + [-(fwd @ pos + near), fwd @ pos + far]
    box_n = [np.eye(3)[k] * s for k in range(3) for s in (1.0, -1.0)]
    box_d = [hi[k] if s > 0 else -lo[k] for k in range(3) for s in (1.0, -1.0)]
    normals, offsets = np.array(fr + box_n), np.array(fd + box_d)
    corners = lambda z: [pos + fwd * z + right * (sx * tan_h * z) + up * (sy * tan_v * z) for sx in (-1, 1) for sy in (-1, 1)]
    fv = np.array(corners(near) + corners(far))
    bv = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
    fedges = [(0, 1), (2, 3), (0, 2), (1, 3), (4, 5), (6, 7), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]
    a = np.concatenate([fv[[e[0] for e in fedges]], bv[[e[0] for e in edges]]])
    b = np.concatenate([fv[[e[1] for e in fedges]], bv[[e[1] for e in edges]]])
    na, nb = a @ normals.T, b @ normals.T  # (E, P)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (offsets - na) / (nb - na)
    s = np.where((s >= 0) & (s <= 1), s, np.nan)
    cross = a[:, None] + (b - a)[:, None] * s[..., None]
    points = np.concatenate([fv, bv, cross.reshape(-1, 3)])
    points = points[~np.isnan(points).any(1)]
    scale = max(1.0, np.abs(hi - lo).max(), far)
    inside = (points @ normals.T <= offsets + 1e-9 * scale).all(1)
    z = (points[inside] - pos) @ fwd
    if z.size == 0:
        sys.exit("sweep_numpy: the scene is not visible within the shadow distance")
    return max(near, z.min()), min(far, z.max())


def decimal_range(spec):
    if isinstance(spec, list):
        return [float(x) for x in spec]
    start, end, step = (Decimal(repr(float(spec[k]))) for k in ("start", "end", "step"))
    return [float(start + k * step) for k in range(int((end - start) / step) + 1)]


def round_half_away(x):
    return np.copysign(np.floor(np.abs(x) + 0.5), x)


def wrap(x):
    return x - round_half_away(x)


def sweep(cfg):
    cam, screen, shadow, motion = cfg["camera"], cfg["screen"], cfg["shadow"], cfg.get("motion", {})
    grid = cfg["sweep"]
    lambdas = decimal_range(grid.get("lambda", [shadow.get("lambda", 0.5)]))
    counts = [int(m) for m in grid.get("cascades", [shadow.get("cascades", 4)])]
    res = np.array(grid.get("resolution", [shadow.get("resolution", 2048)]), float)
    if grid.get("fit", ["sphere"]) != ["sphere"]:
        sys.exit("sweep_numpy: only fit = [\"sphere\"] is modelled")
    height = float(screen["height"])
    tan_v = math.tan(math.radians(cam["fov_y_deg"]) / 2)
    tan_h = float(screen["width"]) / height * tan_v
    k2 = tan_h * tan_h + tan_v * tan_v
    pos, fwd, right, up = camera_path(cam, motion)
    lx, ly = light_basis(cfg["light"]["direction"])
    near = float(cam["near"])
    far = min(float(cam["far"]), float(shadow["max_distance"]))
    scene = cfg["scene"]
    z_lo, z_hi = depth_range(pos[0], fwd[0], right[0], up[0], tan_h, tan_v, near, far,
                             np.array(scene["min"], float), np.array(scene["max"], float),
                             shadow.get("fit_depth_to_scene", False))

    # The camera frame in light space per frame: (F,2) each.
    to_xy = lambda v: np.stack([v @ lx, v @ ly], -1)
    P, Fw, Rt, Up = to_xy(pos), to_xy(fwd), to_xy(right), to_xy(up)

    # One row per cascade of every (cascades, lambda) pair, in the grid's row order.
    lam = np.array(lambdas)
    near_c, far_c, setting = [], [], []
    for m in counts:
        i = np.arange(1, m)
        inner = lam[:, None] * (z_lo * (z_hi / z_lo) ** (i / m)) + (1 - lam[:, None]) * (z_lo + (z_hi - z_lo) * (i / m))
        splits = np.hstack([np.full((len(lam), 1), z_lo), inner, np.full((len(lam), 1), z_hi)])
        near_c.append(splits[:, :-1].ravel())
        far_c.append(splits[:, 1:].ravel())
        setting.append(np.repeat(np.arange(len(lam)) + len(lam) * len(setting), m))
    n, f, setting = np.concatenate(near_c), np.concatenate(far_c), np.concatenate(setting)
    n_settings = len(lam) * len(counts)

    # Minimal bounding sphere of each slice (closed form), window side and texel (C, R).
    far_cap = k2 >= (f - n) / (f + n)
    centre = np.where(far_cap, f, 0.5 * (f + n) * (1 + k2))
    radius = np.where(far_cap, math.sqrt(k2) * f, np.sqrt(k2 * f * f + (f - centre) ** 2))
    texel = 2 * radius[:, None] / (res - 1)  # 2R*N/(N-1) / N

    # Aliasing aggregates per setting (sums over its cascades), (S, R).
    K = height / (2 * tan_v)
    kt = K * texel
    add = lambda x: np.add.reduceat(x, np.flatnonzero(np.r_[True, np.diff(setting) != 0]), axis=0)
    max_al = np.maximum.reduceat(kt / n[:, None], np.flatnonzero(np.r_[True, np.diff(setting) != 0]), axis=0)
    mean_al = add(kt * np.log(f / n)[:, None]) / (z_hi - z_lo)
    mean_log = add(kt * (1 / n - 1 / f)[:, None]) / math.log(z_hi / z_lo)
    under = np.minimum(add(np.clip(kt, n[:, None], f[:, None]) - n[:, None]) / (z_hi - z_lo), 1.0)

    # Along the path: window centres (C, F, 2), and the slice corners' extremes (the corner
    # offsets are linear in depth, so each axis' extreme is at the near or the far cap).
    centres = P[None] + centre[:, None, None] * Fw[None]
    spread = np.abs(Rt) * tan_h + np.abs(Up) * tan_v  # (F, 2)
    lo_n, lo_f = (Fw - spread)[None] * n[:, None, None], (Fw - spread)[None] * f[:, None, None]
    hi_n, hi_f = (Fw + spread)[None] * n[:, None, None], (Fw + spread)[None] * f[:, None, None]
    lo = P[None] + np.minimum(lo_n, lo_f)
    hi = P[None] + np.maximum(hi_n, hi_f)
    T = texel[:, :, None, None]  # (C, R, 1, 1)
    half = (0.5 * res)[None, :, None, None]
    c_tex = centres[:, None] / T  # (C, R, F, 2)
    frames = P.shape[0]
    out = {}
    for snapped in (True, False):
        origin = (round_half_away(c_tex) if snapped else c_tex) - half
        slack = np.minimum(lo[:, None] / T - origin, half * 2 - (hi[:, None] / T - origin))  # (C,R,F,2)
        outside = np.zeros(slack.shape[:2], dtype=np.int64)  # corners outside, (C, R)
        # Only where the extremes leave some corner more than 1e-9 texel outside: each corner
        # of those windows against the window, with a rounding tolerance of a few ulps.
        for c, j in zip(*np.nonzero((slack.min(-1) < -1e-9).any(-1))):
            z = np.array([n[c]] * 4 + [f[c]] * 4)[None, :, None]
            sx = np.array([-1, -1, 1, 1] * 2)[None, :, None] * tan_h
            sy = np.array([-1, 1, -1, 1] * 2)[None, :, None] * tan_v
            pts = P[:, None] + Fw[:, None] * z + Rt[:, None] * (sx * z) + Up[:, None] * (sy * z)  # (F, 8, 2)
            t = pts / texel[c, j]
            s = t - origin[c, j][:, None]
            sl = np.minimum(np.minimum(s[..., 0], res[j] - s[..., 0]), np.minimum(s[..., 1], res[j] - s[..., 1]))
            tol = 1e-9 + 8 * np.finfo(float).eps * np.abs(t).max(-1)
            outside[c, j] = (-sl > tol).sum()
        drift = wrap(np.diff(origin, axis=2))  # (C, R, F-1, 2)
        ms = (drift ** 2).sum((-1, -2))  # (C, R)
        pairs = add(np.ones_like(n))[:, None] * max(frames - 1, 0)
        rms = np.sqrt(np.where(pairs > 0, add(ms) / np.maximum(pairs, 1), 0.0))
        out[snapped] = (rms, add(outside))
    memory = np.array([[m * r * r * 4 for r in res] for m in counts for _ in lam])
    rows = []
    snap_cfg = shadow.get("snap", True)
    for s in range(n_settings):
        m = counts[s // len(lam)]
        for j, r in enumerate(res):
            rows.append({
                "lambda": lam[s % len(lam)], "cascades": m, "resolution": int(r), "fit": "sphere",
                "z_lo": z_lo, "z_hi": z_hi, "max_aliasing": max_al[s, j], "mean_aliasing": mean_al[s, j],
                "mean_log_aliasing": mean_log[s, j], "undersampled_fraction": under[s, j],
                "shimmer": out[snap_cfg][0][s, j], "shimmer_snapped": out[True][0][s, j],
                "shimmer_unsnapped": out[False][0][s, j], "size_jitter": 0.0,
                "coverage_violations": int(out[snap_cfg][1][s, j]),
                "memory_bytes": int(memory[s, j]), "texels_cleared": int(m * r * r), "bytes_written": int(4 * m * r * r),
            })
    # csm-lab's row order: resolution outermost, then cascades, then lambda.
    rows.sort(key=lambda r: (r["resolution"], r["cascades"], r["lambda"]))
    return rows


COLUMNS = ["lambda", "cascades", "resolution", "fit", "z_lo", "z_hi", "max_aliasing", "mean_aliasing",
           "mean_log_aliasing", "undersampled_fraction", "shimmer", "shimmer_snapped", "shimmer_unsnapped",
           "size_jitter", "coverage_violations", "memory_bytes", "texels_cleared", "bytes_written"]
RELATIVE = {"z_lo", "z_hi", "max_aliasing", "mean_aliasing", "mean_log_aliasing", "undersampled_fraction"}
ABSOLUTE = {"shimmer", "shimmer_snapped", "shimmer_unsnapped", "size_jitter"}


def check(rows, path):
    with open(path, newline="") as fh:
        theirs = list(csv.DictReader(fh))
    if len(theirs) != len(rows):
        print(f"check: {len(rows)} rows here, {len(theirs)} in {path}")
        return 1
    worst = {c: 0.0 for c in RELATIVE | ABSOLUTE}
    bad = 0
    for mine, row in zip(rows, theirs):
        key = (float(row["lambda"]), int(row["cascades"]), int(row["resolution"]))
        if key != (mine["lambda"], mine["cascades"], mine["resolution"]):
            print(f"check: row order differs at {key}")
            return 1
        for c in COLUMNS[4:]:
            a, b = float(mine[c]), float(row[c])
            if c in RELATIVE:
                err = abs(a - b) / max(abs(b), 1e-300)
                ok = err <= 1e-9
            elif c in ABSOLUTE:
                err = abs(a - b)
                ok = err <= 1e-9
            else:
                err, ok = abs(a - b), a == b
            if c in worst:
                worst[c] = max(worst[c], err)
            if not ok:
                bad += 1
                if bad <= 10:
                    print(f"check: {key} {c}: numpy {a!r}, csm-lab {b!r}")
    print(f"check: {len(rows)} rows, {len(COLUMNS) - 4} columns each, {bad} outside the tolerance; largest differences:")
    for c in sorted(worst):
        print(f"  {c}: {worst[c]:.3g} ({'relative' if c in RELATIVE else 'texels'})")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("config")
    ap.add_argument("--out", help="write the rows here (CSV) instead of stdout")
    ap.add_argument("--check", metavar="SWEEP_CSV", help="compare with csm-lab's sweep.csv")
    args = ap.parse_args()
    with open(args.config, "rb") as fh:
        cfg = tomllib.load(fh)
    rows = sweep(cfg)
    out = open(args.out, "w", newline="") if args.out else sys.stdout
    w = csv.writer(out)
    w.writerow(COLUMNS)
    w.writerows([[repr(r[c]) if isinstance(r[c], float) else r[c] for c in COLUMNS] for r in rows])
    if args.out:
        out.close()
    if args.check:
        sys.exit(check(rows, args.check))


if __name__ == "__main__":
    main()
