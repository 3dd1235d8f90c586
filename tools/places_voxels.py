#!/usr/bin/python3
"""places_voxels.py - an independent check of the overlap's separate places (thesis section 5.4).

For random poses of two OBJ meshes, `polydem overlap` reports how many separate places the
overlap has (kernels/overlap.h, ovl_places: a graph over the overlap's nodes). This counts them
another way: the overlap's box is sampled on a G^3 grid (a coarse pass finds where the overlap is,
a second pass samples that region), each point is tested inside both solids by ray parity, and
the inside points are split into connected components (scipy.ndimage.label, 26-neighbours).

A grid cannot see a place thinner than its spacing and may cut a thin one in two, so the two
counts can differ on places far below the overlap's volume; every disagreement is printed with
the components' volumes (m^3) for judging.

usage: tools/places_voxels.py A.obj B.obj [--trials N] [--distance D] [--seed S] [--grid G]
Needs python3-numpy and python3-scipy (Debian) and build/polydem.
"""
import argparse
import json
import math
import os
import random
import subprocess

import numpy as np
from scipy import ndimage

POLYDEM = os.environ.get("POLYDEM", os.path.join(os.path.dirname(__file__), "..", "build",
                                                 "polydem"))


def read_obj(path):
    v, f = [], []
    with open(path) as fh:
        for line in fh:
            t = line.split()
            if t and t[0] == "v":
                v.append([float(x) for x in t[1:4]])
            elif t and t[0] == "f":
                f.append([int(x.split("/")[0]) - 1 for x in t[1:4]])
    return np.array(v), np.array(f)


def rotation(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def inside(pts, v, f):
    """Ray parity along a fixed generic direction (Moller-Trumbore per triangle)."""
    d = np.array([0.5773, 0.5774, 0.5773])
    d /= np.linalg.norm(d)
    count = np.zeros(len(pts), int)
    for tri in f:
        a, b, c = v[tri[0]], v[tri[1]], v[tri[2]]
        e1, e2 = b - a, c - a
        h = np.cross(d, e2)
        det = e1 @ h
        if abs(det) < 1e-15:
            continue
        s = pts - a
        u = (s @ h) / det
        qv = np.cross(s, e1)
        w = (qv @ d) / det
        t = (qv @ e2) / det
        count += (u >= 0) & (w >= 0) & (u + w <= 1) & (t > 0)
    return count % 2 == 1


def unit_quaternion(rng):
    q = [rng.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(x * x for x in q))
    return [x / n for x in q]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--distance", type=float, default=2.2, help="m between the meshes' origins")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--grid", type=int, default=70)
    a = ap.parse_args()
    va, fa = read_obj(a.a)
    vb, fb = read_obj(a.b)
    rng = random.Random(a.seed)
    total = agree = 0
    counts = {}
    for k in range(a.trials):
        d = np.array([rng.gauss(0, 1) for _ in range(3)])
        d *= a.distance * rng.uniform(0.8, 1.0) / np.linalg.norm(d)
        qa, qb = unit_quaternion(rng), unit_quaternion(rng)
        pose_a = " ".join(repr(x) for x in [0, 0, 0] + qa)
        pose_b = " ".join(repr(float(x)) for x in list(d) + qb)
        out = subprocess.run([POLYDEM, "overlap", a.a, a.b, "--pose-a", pose_a, "--pose-b",
                              pose_b], capture_output=True, text=True, check=True).stdout
        o = json.loads(out)
        if o["volume"] == 0:
            continue
        wa, wb = va @ rotation(qa).T, vb @ rotation(qb).T + d
        lo, hi = np.maximum(wa.min(0), wb.min(0)), np.minimum(wa.max(0), wb.max(0))
        for stage in range(2):
            axes = [np.linspace(lo[i], hi[i], a.grid) for i in range(3)]
            grid = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], 1)
            m = inside(grid, wa, fa) & inside(grid, wb, fb)
            if stage == 0 and m.any():  # the second pass samples where the overlap is
                h = (hi - lo) / (a.grid - 1)
                lo = np.maximum(lo, grid[m].min(0) - 1.5 * h)
                hi = np.minimum(hi, grid[m].max(0) + 1.5 * h)
        labels, n = ndimage.label(m.reshape((a.grid,) * 3), structure=np.ones((3, 3, 3)))
        if n == 0:
            continue  # below the grid's resolution
        cell = np.prod((hi - lo) / (a.grid - 1))
        sizes = sorted(ndimage.sum(m.reshape((a.grid,) * 3), labels, range(1, n + 1)) * cell,
                       reverse=True)
        total += 1
        counts[o["places"]] = counts.get(o["places"], 0) + 1
        if n == o["places"]:
            agree += 1
        else:
            print("trial %d: places %d, grid components %s m^3, overlap %.4g m^3" %
                  (k, o["places"], ["%.3g" % s for s in sizes[:5]], o["volume"]))
    print("overlaps %d, by places %s; the grid agrees on %d, disagrees on %d" %
          (total, dict(sorted(counts.items())), agree, total - agree))


if __name__ == "__main__":
    main()
