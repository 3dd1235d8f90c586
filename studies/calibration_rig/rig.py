"""Calibration rig (thesis section 6.3, Table A.2, figures 6.8-6.10).

A quasi-2-d rig between two side walls 40 mm apart: a hopper whose trap doors (box walls) hold the
particles while they settle, a plane tilted at 30 degrees below it, a back wall under the plane's
lower edge and a bottom plate. Phase 1 settles the particles in the closed hopper; phase 2 starts
from phase 1's final state (positions, orientations, velocities, sizes; the tangential springs
start afresh) with the doors sliding apart at 1 m/s. The particles flow down the plane and pile
up against the back wall; the repose angle comes from a 20-bin height map of the pile fitted
with eq. 6.1 by studies/calibration/repose_fit.c (GSL).

  rig.py phase1 --triangles T --out DIR        writes DIR/rig_T_1.json
  rig.py phase2 --triangles T --out DIR        DIR/rig_T_1.h5 -> DIR/rig_T_2.json
  rig.py heightmap --triangles T --out DIR     DIR/rig_T_2.h5 -> DIR/rig_T_hmap.txt
  rig.py analyze --out DIR                     fits, repose.csv, repose.png, heightmaps.png, bands
"""
import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)) + "/../lib")
import study  # noqa: E402
from bands import Bands  # noqa: E402

W = 0.04                  # inner width between the side walls, m
TILT = math.radians(30)   # the plane's slope
EDGE_Z = 0.03             # height of the plane's lower edge (x = 0), m
PLANE_X0 = -0.15          # the plane's upper end
HOP_X = (-0.13, -0.05)    # hopper interior
DOOR_Z = 0.13             # hopper floor (top of the doors)
HOP_TOP = 0.40
BINS = (0.0, 0.20, 20)    # height map: x range behind the back wall, bins
SETTLE_1 = 0.06           # s, phase 1
DOOR_SPEED = 1.0          # m/s
DT = 1e-5                 # Table A.2


def tilted_plane_obj(path):
    """A 10 mm thick slab whose top face runs from (PLANE_X0, z(PLANE_X0)) down to (0, EDGE_Z)."""
    t = math.tan(TILT)
    z0 = EDGE_Z - PLANE_X0 * t
    ys = (-W / 2 - 0.01, W / 2 + 0.01)
    top = [(PLANE_X0, z0), (0.0, EDGE_Z)]
    nx, nz = math.sin(TILT), math.cos(TILT)  # the top face's outward normal is (nx, 0, nz)
    bot = [(x - 0.01 * nx, z - 0.01 * nz) for x, z in top]
    v = []
    for (x, z) in bot + top:
        for y in ys:
            v.append((x, y, z))
    # vertices: 0..3 bottom (x0y0, x0y1, x1y0, x1y1), 4..7 top, same order
    quads = [(4, 6, 7, 5), (0, 1, 3, 2), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    with open(path, "w") as f:
        f.write("# tilted plane of the calibration rig (rig.py)\n")
        for p in v:
            f.write("v %.9g %.9g %.9g\n" % p)
        for a, b, c, d in quads:
            f.write("f %d %d %d\nf %d %d %d\n" % (a + 1, b + 1, c + 1, a + 1, c + 1, d + 1))


def box(name, lo, hi, **kw):
    w = {"name": name, "material": "wall", "box": {"min": list(lo), "max": list(hi)}}
    w.update(kw)
    return w


def base_scenario(a, doors_open):
    zt = HOP_TOP + 0.01
    mid = 0.5 * (HOP_X[0] + HOP_X[1])
    door_kw_l = {"velocity": [-DOOR_SPEED, 0, 0]} if doors_open else {}
    door_kw_r = {"velocity": [DOOR_SPEED, 0, 0]} if doors_open else {}
    walls = [
        box("bottom", (-0.2, -W / 2 - 0.01, -0.01), (0.26, W / 2 + 0.01, 0)),
        box("side_y0", (-0.2, -W / 2 - 0.01, 0), (0.26, -W / 2, zt)),
        box("side_y1", (-0.2, W / 2, 0), (0.26, W / 2 + 0.01, zt)),
        box("back", (-0.01, -W / 2, 0), (0, W / 2, EDGE_Z)),
        box("end", (0.25, -W / 2, 0), (0.26, W / 2, 0.1)),
        box("hopper_x0", (HOP_X[0] - 0.01, -W / 2, DOOR_Z - 0.01), (HOP_X[0], W / 2, HOP_TOP)),
        box("hopper_x1", (HOP_X[1], -W / 2, DOOR_Z - 0.01), (HOP_X[1] + 0.01, W / 2, HOP_TOP)),
        box("door_l", (HOP_X[0] - 0.01, -W / 2, DOOR_Z - 0.01), (mid, W / 2, DOOR_Z), **door_kw_l),
        box("door_r", (mid, -W / 2, DOOR_Z - 0.01), (HOP_X[1] + 0.01, W / 2, DOOR_Z), **door_kw_r),
        {"name": "plane", "material": "wall", "mesh": "plane.obj"},
    ]
    return {
        "name": "calibration_rig_%d" % a.triangles,
        "seed": a.seed,
        "gravity": [0, 0, -9.81],
        "materials": {
            # Table A.2: particles E 20 MPa, walls 100 MPa, nu 0.25, G 20 MPa both; the densities
            # are not given (rock, steel)
            "rock": {"density": 2600, "youngs_modulus": 2e7, "poisson_ratio": 0.25,
                     "shear_modulus": 2e7},
            "wall": {"density": 7800, "youngs_modulus": 1e8, "poisson_ratio": 0.25,
                     "shear_modulus": 2e7}},
        "interactions": [
            {"between": ["rock", "rock"], "friction": 0.39, "damping": 0.453619},
            {"between": ["rock", "wall"], "friction": 0.35, "damping": 0.382097}],
        "shapes": {"rock": {"builtin": "rock", "triangles": a.triangles, "seed": 1}},
        "walls": walls,
    }


def phase1(a):
    os.makedirs(a.out, exist_ok=True)
    tilted_plane_obj(os.path.join(a.out, "plane.obj"))
    s = base_scenario(a, False)
    s["time"] = {"dt": DT, "duration": SETTLE_1, "output_interval": SETTLE_1,
                 "stats_interval": 1e-3}
    # Table A.2: normal(mean 10 mm, std 5 mm) truncated to [5, 10] mm; here the volume-equivalent
    # diameter (the thesis's is the middle bounding-box dimension)
    s["particles"] = [{"shape": "rock", "material": "rock", "count": a.particles,
                       "size": {"distribution": "normal", "mean": 0.01, "std": 0.005,
                                "min": 0.005, "max": 0.01},
                       "region": {"min": [HOP_X[0], -W / 2, DOOR_Z],
                                  "max": [HOP_X[1], W / 2, HOP_TOP]},
                       "arrangement": "random", "orientation": "random"}]
    p = os.path.join(a.out, "rig_%d_1.json" % a.triangles)
    study.write_json(p, s)
    v = study.validate(p)
    print("  %d triangles: %d particles, stable dt estimate %s s (dt %g s)"
          % (a.triangles, a.particles, "%.3g" % v["dt_stable_s"], DT))


def phase2(a):
    import h5py
    with h5py.File(os.path.join(a.out, "rig_%d_1.h5" % a.triangles), "r") as h5:
        fr = h5["frames"]
        x, q = fr["position"][-1], fr["orientation"][-1]
        v, w = fr["velocity"][-1], fr["angular_velocity"][-1]
        size = h5["particles/size"][()]
        mass = h5["particles/mass"][()]
    s = base_scenario(a, True)
    s["time"] = {"dt": DT, "duration": a.duration, "output_interval": a.duration / 10,
                 "stats_interval": 2e-3}
    s["output"] = {"fields": ["position", "orientation", "velocity"]}
    s["particles"] = [{"shape": "rock", "material": "rock", "list": [
        {"position": x[i].tolist(), "orientation": q[i].tolist(), "velocity": v[i].tolist(),
         "angular_velocity": w[i].tolist(), "size": float(size[i])} for i in range(len(size))]}]
    p = os.path.join(a.out, "rig_%d_2.json" % a.triangles)
    study.write_json(p, s)
    study.validate(p)
    print("  %d triangles: phase 2 with %d particles, %.3f kg (Table A.2: 1 kg)"
          % (a.triangles, len(size), mass.sum()))


def heightmap(a):
    """Per bin the highest point of any particle (its shape's vertices, posed) over the bottom
    plate, for particles whose centre lies behind the back wall (x > 0)."""
    import h5py
    with h5py.File(os.path.join(a.out, "rig_%d_2.h5" % a.triangles), "r") as h5:
        x, q = h5["frames/position"][-1], h5["frames/orientation"][-1]
        size = h5["particles/size"][()]
        verts = h5["shapes/rock/vertices"][()]
        ke = h5["stats/kinetic_energy"][()]
        mass = h5["particles/mass"][()]
    rot = study.quat_to_matrix(q)
    pts = x[:, None, :] + size[:, None, None] * np.einsum("nij,vj->nvi", rot, verts)
    lo, hi, nb = BINS
    edges = np.linspace(lo, hi, nb + 1)
    h = np.zeros(nb)
    on = x[:, 0] > 0
    for p in pts[on].reshape(-1, 3):
        k = int((p[0] - lo) // ((hi - lo) / nb))
        if 0 <= k < nb:
            h[k] = max(h[k], p[2])
    with open(os.path.join(a.out, "rig_%d_hmap.txt" % a.triangles), "w") as f:
        f.write("# x_m h_m: 20-bin height map of the pile (rig.py); final KE %.3g J, peak %.3g "
                "J, %d of %d particles behind the back wall, %.4f kg\n"
                % (ke[-1], ke.max(), on.sum(), len(x), mass.sum()))
        for k in range(nb):
            f.write("%.6f %.6f\n" % (0.5 * (edges[k] + edges[k + 1]), h[k]))


def analyze(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fit_bin = os.environ.get("REPOSE_FIT", os.path.join(study.ROOT, "build", "studies",
                                                        "repose_fit"))
    with open(os.path.join(a.out, "cases.json")) as f:
        cases = json.load(f)["cases"]
    rows = []
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for c in cases:
        hm = os.path.join(a.out, "rig_%d_hmap.txt" % c["triangles"])
        r = subprocess.run([fit_bin, hm], capture_output=True, text=True)
        if r.returncode != 0:
            study.die("repose_fit %s failed: %s%s" % (hm, r.stdout, r.stderr))
        fit = json.loads(r.stdout)
        with open(hm) as f:
            head = f.readline()
        d = np.loadtxt(hm)
        ke = [float(t.split()[0]) for t in head.split("final KE ")[1:]][0]
        peak = float(head.split("peak ")[1].split()[0])
        nbehind = int(head.split(" J, ")[1].split()[0])
        ntot = int(head.split(" of ")[1].split()[0])
        rows.append(dict(c, **fit, final_ke_J=ke, peak_ke_J=peak, behind=nbehind, n=ntot))
        p = ax.plot(d[:, 0] * 1e3, d[:, 1] * 1e3, "o", ms=3, label="%d triangles: %.1f deg"
                    % (c["triangles"], fit["angle_deg"]))
        xs = np.linspace(BINS[0], BINS[1], 200)
        ax.plot(xs * 1e3, 1e3 * fit["c"] / (1 + np.exp(fit["a"] * (xs - fit["b"]))), "-",
                color=p[0].get_color(), lw=1)
    ax.set_xlabel("distance from the back wall (mm)")
    ax.set_ylabel("pile height (mm)")
    ax.set_title("height maps and eq. 6.1 fits (fig. 6.9)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "heightmaps.png"), dpi=110)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    tri = [r["triangles"] for r in rows]
    ax.plot(tri, [r["angle_deg"] for r in rows], "ko-")
    ax.axhspan(33, 42, color="0.85", label="experimental range (thesis): 33-42 deg")
    ax.set_xscale("log")
    ax.set_xlabel("triangles per particle (rock)")
    ax.set_ylabel("repose angle (deg)")
    ax.set_title("repose angle against resolution (fig. 6.10, one run each)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "repose.png"), dpi=110)
    keys = ["triangles", "n", "behind", "angle_deg", "a", "b", "c", "rms_m", "final_ke_J",
            "peak_ke_J", "run_s"]
    with open(os.path.join(a.out, "repose.csv"), "w") as f:
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(str(r.get(k, "")) for k in keys) + "\n")
    study.write_json(os.path.join(a.out, "summary.json"), {"cases": rows})
    b = Bands("calibration_rig")
    for r in rows:
        print("  %4d triangles: repose angle %.1f deg (a %.4g 1/m, b %.4g m, c %.4g m, rms %.2g "
              "m), %d of %d particles in the pile, final/peak KE %.2g"
              % (r["triangles"], r["angle_deg"], r["a"], r["b"], r["c"], r["rms_m"], r["behind"],
                 r["n"], r["final_ke_J"] / r["peak_ke_J"]))
        b.check(a.band[0] <= r["angle_deg"] <= a.band[1], "%d triangles: repose angle"
                % r["triangles"], "%.1f deg" % r["angle_deg"], "%g-%g deg" % tuple(a.band),
                "mu 0.35-0.39 rock on rock and steel: piles of angular grains stand at "
                "~atan(mu) to ~45 deg (thesis's experiments 33-42)")
        b.check(r["final_ke_J"] <= 0.01 * r["peak_ke_J"], "%d triangles: pile at rest"
                % r["triangles"], "final/peak KE %.2g" % (r["final_ke_J"] / r["peak_ke_J"]),
                "<= 0.01", "the angle is measured in the steady state (section 6.3, step 4)")
    b.finish()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["phase1", "phase2", "heightmap", "analyze"])
    ap.add_argument("--triangles", type=int)
    ap.add_argument("--out", required=True)
    ap.add_argument("--particles", type=int, default=220)
    ap.add_argument("--duration", type=float, default=0.8, help="s of phase 2")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--band", type=float, nargs=2, default=[15, 45])
    a = ap.parse_args()
    {"phase1": phase1, "phase2": phase2, "heightmap": heightmap, "analyze": analyze}[a.cmd](a)


if __name__ == "__main__":
    main()
