"""Calibration rig (thesis section 6.3, Table A.2, figures 6.8-6.10).

A quasi-2-d rig between two side walls 40 mm apart: a hopper whose trap doors (box walls) hold the
particles, a plane tilted at 30 degrees below it whose lower edge stands 60 mm over a bottom plate,
and the plate, closed by end walls far from the pile. Phase 1 lets the particles fall into the
closed hopper; phase 2 starts from phase 1's final state (positions, orientations, velocities,
sizes; the tangential springs start afresh) with the doors sliding apart at 1 m/s. The particles
flow down the plane, drop off its free edge and pile up on the plate with free flanks on both
sides. The repose angle comes from a 20-bin height map of the pile's top and front flank (along
+x, away from the plane) fitted with eq. 6.1 by studies/calibration/repose_fit.c (GSL).

  rig.py phase1 --triangles T [--seed S] --out DIR   writes DIR/rig_T_1.json (rig_T_sS_1.json)
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
EDGE_Z = 0.06             # height of the plane's lower edge (x = 0) over the plate, m
PLANE_X0 = -0.27          # the plane's upper end
PLANE_T = 0.01            # the plane's thickness
HOP_X = (-0.25, -0.09)    # hopper interior, over the plane's upper part
DOOR_Z = 0.23             # hopper floor (top of the doors)
PLATE_X = (-0.30, 0.35)   # the bottom plate, between the two end walls
NBINS, BIN_W = 20, 0.0075  # height map: 20 bins of 7.5 mm along +x,
TOP_BIN = 2                # the pile's top in the third
SETTLE_1 = 0.06           # s, phase 1: the doors hold the particles while they start falling
DOOR_SPEED = 1.0          # m/s
DT = 1e-5                 # Table A.2
END_H = 0.1               # the end walls' height
CELL = 0.0139             # the engine's lattice cell: the largest particle's circumscribed diameter


def apply_scale(s):
    """--scale S: every length of the rig across the channel's plane (x and z) times S, the
    channel's width and the particles kept, so that S^2 times the particles (S^2 the mass) make a
    pile of the same shape relative to the rig and its height map: Table A.2's 1 kg is about
    1 400 particles, S = sqrt(1400 / 400) = 1.87."""
    global EDGE_Z, PLANE_X0, HOP_X, DOOR_Z, PLATE_X, BIN_W, END_H
    EDGE_Z *= s
    PLANE_X0 *= s
    HOP_X = (HOP_X[0] * s, HOP_X[1] * s)
    DOOR_Z *= s
    PLATE_X = (PLATE_X[0] * s, PLATE_X[1] * s)
    BIN_W *= s
    END_H *= s


def hop_top(particles):
    """The hopper's height: room for the lattice the engine places the particles on (cells of
    the largest particle's circumscribed diameter, 13.9 mm at 20 triangles: 11 x 2 per layer in
    the 160 x 40 mm hopper), with a margin."""
    per_layer = int((HOP_X[1] - HOP_X[0]) / CELL) * int(W / CELL)
    return DOOR_Z + 0.02 + 0.0145 * math.ceil(particles / per_layer)


def plane_top_z(x):
    """Height of the plane's top face at x (x <= 0)."""
    return EDGE_Z - x * math.tan(TILT)


def tilted_plane_obj(path):
    """A 10 mm thick slab whose top face runs from (PLANE_X0, z(PLANE_X0)) down to (0, EDGE_Z)."""
    ys = (-W / 2 - 0.01, W / 2 + 0.01)
    top = [(PLANE_X0, plane_top_z(PLANE_X0)), (0.0, EDGE_Z)]
    nx, nz = math.sin(TILT), math.cos(TILT)  # the top face's outward normal is (nx, 0, nz)
    bot = [(x - PLANE_T * nx, z - PLANE_T * nz) for x, z in top]
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
    top = hop_top(a.particles)
    zt = top + 0.01
    mid = 0.5 * (HOP_X[0] + HOP_X[1])
    x0, x1 = PLATE_X
    door_kw_l = {"velocity": [-DOOR_SPEED, 0, 0]} if doors_open else {}
    door_kw_r = {"velocity": [DOOR_SPEED, 0, 0]} if doors_open else {}
    walls = [
        box("bottom", (x0 - 0.01, -W / 2 - 0.01, -0.01), (x1 + 0.01, W / 2 + 0.01, 0)),
        box("side_y0", (x0 - 0.01, -W / 2 - 0.01, 0), (x1 + 0.01, -W / 2, zt)),
        box("side_y1", (x0 - 0.01, W / 2, 0), (x1 + 0.01, W / 2 + 0.01, zt)),
        # the back wall as high as the side walls: the left door, sliding back 4 mm over the
        # plane's upper end, swept a grain off it that went over a wall of END_H and out of the
        # rig (160 triangles, seed 5: falling at 8.5 m/s at the end, README.md)
        box("end_x0", (x0 - 0.01, -W / 2, 0), (x0, W / 2, zt)),
        box("end_x1", (x1, -W / 2, 0), (x1 + 0.01, W / 2, END_H)),
        box("hopper_x0", (HOP_X[0] - 0.01, -W / 2, DOOR_Z - 0.01), (HOP_X[0], W / 2, top)),
        box("hopper_x1", (HOP_X[1], -W / 2, DOOR_Z - 0.01), (HOP_X[1] + 0.01, W / 2, top)),
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
            {"between": ["rock", "rock"], "friction": 0.39, "damping": 0.453619,
             "contact_places": a.contact_places,
             "contact_moments": a.contact_moments == "on"},
            {"between": ["rock", "wall"], "friction": 0.35, "damping": 0.382097,
             "contact_places": a.contact_places,
             "contact_moments": a.contact_moments == "on"}],
        "shapes": {"rock": {"builtin": "rock", "triangles": a.triangles, "seed": 1}},
        "walls": walls,
    }


def tag(triangles, seed):
    """The file name part of one run: rig_T_... for seed 1 (as before seeds were added), rig_T_sS_...
    for the others."""
    return "%d" % triangles if seed == 1 else "%d_s%d" % (triangles, seed)


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
                                  "max": [HOP_X[1], W / 2, hop_top(a.particles)]},
                       "arrangement": "random", "orientation": "random"}]
    p = os.path.join(a.out, "rig_%s_1.json" % tag(a.triangles, a.seed))
    study.write_json(p, s)
    v = study.validate(p)
    print("  %d triangles: %d particles, stable dt estimate %s s (dt %g s)"
          % (a.triangles, a.particles, "%.3g" % v["dt_stable_s"], DT))


def phase2(a):
    import h5py
    with h5py.File(os.path.join(a.out, "rig_%s_1.h5" % tag(a.triangles, a.seed)), "r") as h5:
        fr = h5["frames"]
        x, q = fr["position"][-1], fr["orientation"][-1]
        v, w = fr["velocity"][-1], fr["angular_velocity"][-1]
        size = h5["particles/size"][()]
        mass = h5["particles/mass"][()]
    a.particles = len(size)  # the hopper's height as in phase 1
    s = base_scenario(a, True)
    s["time"] = {"dt": DT, "duration": a.duration, "output_interval": a.duration / 10,
                 "stats_interval": 2e-3}
    s["output"] = {"fields": ["position", "orientation", "velocity"]}
    s["particles"] = [{"shape": "rock", "material": "rock", "list": [
        {"position": x[i].tolist(), "orientation": q[i].tolist(), "velocity": v[i].tolist(),
         "angular_velocity": w[i].tolist(), "size": float(size[i])} for i in range(len(size))]}]
    p = os.path.join(a.out, "rig_%s_2.json" % tag(a.triangles, a.seed))
    study.write_json(p, s)
    study.validate(p)
    print("  %d triangles: phase 2 with %d particles, %.3f kg (Table A.2: 1 kg)"
          % (a.triangles, len(size), mass.sum()))


def bin_tops(pp, lo):
    """The height map: in each of the NBINS bins of BIN_W from lo along +x, the highest of the
    points pp (n, 3) that lie in it (0 where none does)."""
    h = np.zeros(NBINS)
    k = np.floor((pp[:, 0] - lo) / BIN_W).astype(int)
    for kk, z in zip(k, pp[:, 2]):
        if 0 <= kk < NBINS:
            h[kk] = max(h[kk], z)
    return h


def heightmap(a):
    """The pile is every particle on the plate: in front of the plane's edge (x > 0) or under
    the plane (centre below its bottom face). The map runs NBINS bins of BIN_W along +x, away
    from the plane, placed so that bin TOP_BIN is centred on the pile's top (the highest point
    of the pile's profile smoothed over 15 mm): two bins of the rounded top behind it, then the front flank, its foot and the start
    of the one-particle runout layer (150 mm in all). Each bin holds the highest posed vertex of
    the pile's particles that lies in it."""
    import h5py
    with h5py.File(os.path.join(a.out, "rig_%s_2.h5" % tag(a.triangles, a.seed)), "r") as h5:
        x, q = h5["frames/position"][-1], h5["frames/orientation"][-1]
        x_prev = h5["frames/position"][-2]  # a tenth of phase 2 earlier: the creep
        q_prev = h5["frames/orientation"][-2]
        t_frames = h5["frames/time"][()]
        v = h5["frames/velocity"][-1]
        size = h5["particles/size"][()]
        verts = h5["shapes/rock/vertices"][()]
        t = h5["stats/time"][()]
        ke = h5["stats/kinetic_energy"][()]
        mass = h5["particles/mass"][()]
    def posed(x, q):  # every grain's mesh vertices in the world (n, v, 3)
        return x[:, None, :] + size[:, None, None] * np.einsum(
            "nij,vj->nvi", study.quat_to_matrix(q), verts)

    pts = posed(x, q)
    under = x[:, 2] < plane_top_z(np.minimum(x[:, 0], 0)) - PLANE_T / math.cos(TILT)
    # out of the rig: below the plate or beyond its ends (nothing holds a grain there)
    out = (x[:, 2] < -0.01) | (x[:, 0] < PLATE_X[0]) | (x[:, 0] > PLATE_X[1])
    pile = ((x[:, 0] > 0) | under) & ~out
    pp = pts[pile].reshape(-1, 3)
    # the pile's top: the highest point of a 2.5 mm map smoothed over 15 mm, so that one grain
    # on the top does not place it
    fine_lo = pp[:, 0].min()
    kf = np.floor((pp[:, 0] - fine_lo) / 0.0025).astype(int)
    fine = np.zeros(kf.max() + 1)
    np.maximum.at(fine, kf, pp[:, 2])
    smooth = np.convolve(fine, np.ones(6) / 6, mode="same")
    i = int(np.argmax(smooth))
    top = np.array([fine_lo + (i + 0.5) * 0.0025, 0.0, fine[max(i - 3, 0):i + 3].max()])
    lo = top[0] - (TOP_BIN + 0.5) * BIN_W
    mapped = pile & (x[:, 0] >= lo) & (x[:, 0] < lo + NBINS * BIN_W)
    h = bin_tops(pp, lo)
    # the same grains' map a frame earlier (a tenth of phase 2), in the same bins: how much the
    # map the angle is fitted to still changed, which the rest check bounds
    h_prev = bin_tops(posed(x_prev, q_prev)[pile].reshape(-1, 3), lo)
    # the flow phase's mean kinetic energy (figure 6.10's other measure): over the rows where
    # it is above 1 % of its peak
    flow = ke > 0.01 * ke.max()
    meta = {"final_ke_J": float(ke[-1]), "peak_ke_J": float(ke.max()),
            "flow_ke_J": float(ke[flow].mean()), "t_end_s": float(t[-1]),
            "pile": int(pile.sum()), "n": len(x), "mass_kg": float(mass.sum()),
            "top_x_m": float(top[0]), "top_h_m": float(top[2]),
            "max_speed_m_s": float(np.linalg.norm(v, axis=1).max()),
            # how far the mapped part of the pile (centres over the map's 20 bins: the top and
            # the flank the angle comes from) moved over the last frame interval; a grain or
            # two still rolling out on the plate beyond it does not change the angle
            "creep_m": float(np.linalg.norm(x[mapped] - x_prev[mapped], axis=1).max()),
            "creep_s": float(t_frames[-1] - t_frames[-2]),
            "map_change_m": float(np.abs(h - h_prev).max()),
            "escaped": int(out.sum()),
            "rolling": int((np.linalg.norm(x[pile] - x_prev[pile], axis=1) > a.max_creep).sum())}
    with open(os.path.join(a.out, "rig_%s_hmap.txt" % tag(a.triangles, a.seed)), "w") as f:
        f.write("# x_m h_m: %d-bin height map of the pile's top and front flank (rig.py)\n"
                % NBINS)
        f.write("# meta %s\n" % json.dumps(meta))
        for i in range(NBINS):
            f.write("%.6f %.6f\n" % (lo + (i + 0.5) * BIN_W, h[i]))
    print("  %d triangles: %d of %d particles in the pile, top %.1f mm high at x = %.1f mm, "
          "final/peak KE %.2g" % (a.triangles, meta["pile"], meta["n"], 1e3 * top[2],
                                  1e3 * top[0], meta["final_ke_J"] / meta["peak_ke_J"]))


def read_hmap(path):
    with open(path) as f:
        for line in f:
            if line.startswith("# meta "):
                meta = json.loads(line[len("# meta "):])
                break
    return np.loadtxt(path), meta


def analyze(a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fit_bin = os.environ.get("REPOSE_FIT", os.path.join(study.ROOT, "build", "studies",
                                                        "repose_fit"))
    with open(os.path.join(a.out, "cases.json")) as f:
        cases = json.load(f)["cases"]
    rows = []
    failed = []
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for c in cases:
        c.setdefault("seed", 1)
        hm = os.path.join(a.out, "rig_%s_hmap.txt" % tag(c["triangles"], c["seed"]))
        d, meta = read_hmap(hm)
        r = subprocess.run([fit_bin, hm], capture_output=True, text=True)
        try:
            fit = json.loads(r.stdout)
        except ValueError:
            fit = {}
        if r.returncode != 0:
            failed.append("%d triangles: repose_fit %s failed: %s%s"
                          % (c["triangles"], hm, r.stdout, r.stderr))
            fit = {"angle_deg": float("nan"), "a": float("nan"), "b": float("nan"),
                   "c": float("nan"), "rms_m": float("nan")}
        rows.append(dict(c, **fit, **meta))
        x0 = meta["top_x_m"]
        p = ax.plot((d[:, 0] - x0) * 1e3, d[:, 1] * 1e3, "o", ms=3,
                    label="%d triangles, seed %d: %.1f deg" % (c["triangles"], c["seed"],
                                                                fit["angle_deg"]))
        if math.isfinite(fit["a"]):
            xs = np.linspace(d[0, 0], d[-1, 0], 200)
            ax.plot((xs - x0) * 1e3, 1e3 * fit["c"] / (1 + np.exp(fit["a"] * (xs - fit["b"]))),
                    "-", color=p[0].get_color(), lw=1)
    ax.set_xlabel("distance from the pile's top (mm)")
    ax.set_ylabel("pile height (mm)")
    ax.set_title("height maps and eq. 6.1 fits (fig. 6.9)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "heightmaps.png"), dpi=110)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    # per resolution: the mean and (with more than one seed) the sample standard deviation over
    # the seeds' runs, as figure 6.10's error bars over its 11 runs
    tri = sorted(set(r["triangles"] for r in rows))
    ens = {}
    for t in tri:
        ang = np.array([r["angle_deg"] for r in rows if r["triangles"] == t])
        ke = np.array([r["flow_ke_J"] for r in rows if r["triangles"] == t])
        ens[t] = {"triangles": t, "runs": len(ang), "angle_mean_deg": float(ang.mean()),
                  "angle_std_deg": float(ang.std(ddof=1)) if len(ang) > 1 else 0.0,
                  "flow_ke_mean_J": float(ke.mean()),
                  "flow_ke_std_J": float(ke.std(ddof=1)) if len(ke) > 1 else 0.0}
    ax1.errorbar(tri, [ens[t]["flow_ke_mean_J"] * 1e3 for t in tri],
                 yerr=[ens[t]["flow_ke_std_J"] * 1e3 for t in tri], fmt="ko-", capsize=3)
    ax1.set_ylabel("mean kinetic energy, flow phase (mJ)")
    ax2.errorbar(tri, [ens[t]["angle_mean_deg"] for t in tri],
                 yerr=[ens[t]["angle_std_deg"] for t in tri], fmt="ko-", capsize=3)
    ax2.axhspan(33, 42, color="0.85", label="experimental range (thesis): 33-42 deg")
    ax2.set_ylabel("repose angle (deg)")
    ax2.legend(fontsize=7)
    for ax in (ax1, ax2):
        ax.set_xscale("log")
        ax.set_xticks(tri)
        ax.set_xticklabels([str(t) for t in tri])
        ax.minorticks_off()
        ax.set_xlabel("triangles per particle (rock)")
        ax.grid(alpha=0.3)
    runs = sorted(set(ens[t]["runs"] for t in tri))
    fig.suptitle("calibration rig against resolution (fig. 6.10, %s run%s each%s)"
                 % ("/".join(str(n) for n in runs), "" if runs == [1] else "s",
                    "" if runs == [1] else ", mean and standard deviation"), fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "repose.png"), dpi=110)
    keys = ["triangles", "seed", "n", "pile", "mass_kg", "angle_deg", "a", "b", "c", "rms_m",
            "top_h_m", "top_x_m", "flow_ke_J", "final_ke_J", "peak_ke_J", "max_speed_m_s",
            "map_change_m", "creep_m",
            "settle_s", "flow_s", "run_s"]
    with open(os.path.join(a.out, "repose.csv"), "w") as f:
        f.write(",".join(keys) + "\n")
        for r in rows:
            f.write(",".join(str(r.get(k, "")) for k in keys) + "\n")
    study.write_json(os.path.join(a.out, "summary.json"),
                     {"cases": rows, "resolutions": [ens[t] for t in tri]})
    b = Bands("calibration_rig")
    for r in rows:
        print("  %4d triangles (seed %d): repose angle %.1f deg (a %.4g 1/m, b %.4g m, c %.4g m, rms %.2g "
              "m), %d of %d particles in the pile (%.3f kg), top %.1f mm, flow-phase KE %.3g "
              "mJ, final/peak KE %.2g, run %s s"
              % (r["triangles"], r["seed"], r["angle_deg"], r["a"], r["b"], r["c"], r["rms_m"],
                 r["pile"],
                 r["n"], r["mass_kg"], 1e3 * r["top_h_m"], 1e3 * r["flow_ke_J"],
                 r["final_ke_J"] / r["peak_ke_J"], r.get("run_s", "?")))
    for t in tri:
        if ens[t]["runs"] > 1:
            print("  %4d triangles, %d runs: repose angle %.1f +- %.1f deg (mean, sample std), "
                  "flow-phase KE %.3g +- %.2g mJ" % (t, ens[t]["runs"], ens[t]["angle_mean_deg"],
                                                     ens[t]["angle_std_deg"],
                                                     1e3 * ens[t]["flow_ke_mean_J"],
                                                     1e3 * ens[t]["flow_ke_std_J"]))
    for msg in failed:
        print("  " + msg.strip())
    for r in rows:
        b.check(math.isfinite(r["angle_deg"]), "%d triangles: eq. 6.1 fit converged"
                % r["triangles"], "yes" if math.isfinite(r["angle_deg"]) else "no", "yes",
                "GSL multifit_nlinear on the 20-bin map")
        b.check(r["top_h_m"] >= a.min_height, "%d triangles: a pile, not a layer"
                % r["triangles"], "top %.1f mm" % (1e3 * r["top_h_m"]),
                ">= %g mm" % (1e3 * a.min_height), "3.5 of the largest grains (10 mm); 150-250 "
                "particles made mounds 22-31 mm high whose fits gave 8-15 deg (README.md)")
        b.check(a.band[0] <= r["angle_deg"] <= a.band[1], "%d triangles: repose angle"
                % r["triangles"], "%.1f deg" % r["angle_deg"], "%g-%g deg" % tuple(a.band),
                "mu 0.35-0.39 is a friction angle of 19-21 deg; angular (coarse) grains stand "
                "steeper, up to ~45 (thesis's experiments 33-42), rounded (fine) ones without "
                "rolling resistance below it: 14.6 deg measured at 160 triangles (README.md)")
        if "escaped" in r:
            b.check(r["escaped"] == 0, "%d triangles (seed %d): every grain stays in the rig"
                    % (r["triangles"], r["seed"]), "%d left it" % r["escaped"], "0",
                    "a grain out of the rig falls for ever, and its kinetic energy fails the "
                    "rest check below although the pile rests")
        b.check(r["final_ke_J"] <= 0.01 * r["peak_ke_J"], "%d triangles: pile at rest"
                % r["triangles"], "final/peak KE %.2g" % (r["final_ke_J"] / r["peak_ke_J"]),
                "<= 0.01", "the angle is measured in the steady state (section 6.3, step 4)")
        if "map_change_m" in r:
            # the map the angle is fitted to, not the fastest grain: one grain rolling down the
            # flank or out on the plate moved up to 14 mm while no bin changed by 0.1 mm
            b.check(r["map_change_m"] <= a.max_creep, "%d triangles (seed %d): pile no longer "
                    "creeps" % (r["triangles"], r["seed"]), "map changed by %.2f mm in the last "
                    "%.2f s" % (1e3 * r["map_change_m"], r["creep_s"]),
                    "<= %g mm" % (1e3 * a.max_creep),
                    "the height map's largest change of a bin over the last tenth of phase 2; "
                    "half the smallest grain (5 mm); the kinetic-energy check passed piles still "
                    "slumping 8 mm (README.md); the most a mapped grain moved: %.2f mm, %d grains "
                    "moved more than %g mm" % (1e3 * r["creep_m"], r.get("rolling", 0),
                                               1e3 * a.max_creep))
        elif "creep_m" in r:  # a map written before the map change was measured
            b.check(r["creep_m"] <= a.max_creep, "%d triangles: pile no longer creeps"
                    % r["triangles"], "%.2f mm in the last %.2f s"
                    % (1e3 * r["creep_m"], r["creep_s"]), "<= %g mm" % (1e3 * a.max_creep),
                    "the mapped top and flank; half the smallest grain (5 mm), so the 7.5 mm bins "
                    "no longer change; the kinetic-energy check passed piles still slumping 8 mm "
                    "(README.md); %d grains still rolling elsewhere" % r.get("rolling", 0))
    b.finish()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["phase1", "phase2", "heightmap", "analyze"])
    ap.add_argument("--triangles", type=int)
    ap.add_argument("--out", required=True)
    ap.add_argument("--particles", type=int, default=400)
    ap.add_argument("--duration", type=float, default=1.3, help="s of phase 2")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--contact-places", default="merged", choices=["merged", "separate"],
                    help="thesis section 5.4: one contact per pair, or one per place")
    ap.add_argument("--contact-moments", default="on", choices=["on", "off"],
                    help="twisting friction and the dashpots' moments (docs/SCENARIO.md); off: "
                    "the thesis's point contact")
    ap.add_argument("--band", type=float, nargs=2, default=[10, 45])
    ap.add_argument("--min-height", type=float, default=0.035,
                    help="m, the pile's top (times --scale)")
    ap.add_argument("--scale", type=float, default=1.0,
                    help="the rig's lengths across the channel (apply_scale); 1.87 with 1 400 "
                    "particles for Table A.2's 1 kg")
    ap.add_argument("--max-creep", type=float, default=0.0025,
                    help="m a bin of the height map may change over the last frame interval (a "
                    "tenth of phase 2)")
    a = ap.parse_args()
    if not a.scale > 0:
        ap.error("--scale must be > 0")
    apply_scale(a.scale)
    a.min_height *= a.scale
    {"phase1": phase1, "phase2": phase2, "heightmap": heightmap, "analyze": analyze}[a.cmd](a)


if __name__ == "__main__":
    main()
