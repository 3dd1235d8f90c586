"""Gravity packing (thesis section 7.1, Table A.3, figures 7.3 and 7.4).

  packing.py generate --particles N --out DIR [--first-impact T]
      writes DIR/packing.json: Schönhardt prisms on a lattice with the thesis's 169:169:35 aspect
      fall from rest onto a plane, with Table A.3's materials and dt = 1e-5 s.
  packing.py analyze --out DIR
      reads DIR/packing.h5: time per step from /stats/wall_time, broad-phase pairs and contacts
      from /stats, against simulated time; writes packing.csv, time_per_step.png (figure 7.3),
      pairs.png (figure 7.4), summary.json; exits 1 when the pile did not form.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)) + "/../lib")
import study  # noqa: E402
from bands import Bands  # noqa: E402

SIZE = 0.02         # volume-equivalent diameter, m (Table A.3 gives none; bench/step's)
DENSITY = 2600      # kg/m^3 (Table A.3 gives none; rock)
# /stats/stage_time's stages and what the thesis's figure 7.3 calls them
STAGES = {"integrate": "integration", "bvh": "BVH construction", "traverse": "BVH traversal",
          "contacts": "narrow phase, overlaps and forces", "gather": "force accumulation"}
RADIUS_RATIO = 0.945  # Schönhardt circumradius / volume-equivalent diameter (engine lattice cell)
G = 9.81


def lattice_dims(n):
    """nx = ny, nz with the thesis's 169:169:35 aspect and nx * ny * nz >= n."""
    nz = max(1, round(35 * (n / (169 * 169 * 35)) ** (1 / 3)))
    nxy = max(1, math.ceil(math.sqrt(n / nz)))
    return nxy, nz


def generate(a):
    nxy, nz = lattice_dims(a.particles)
    n = nxy * nxy * nz
    cell = 2 * RADIUS_RATIO * SIZE * 1.0005
    gap = 0.5 * G * a.first_impact ** 2       # lowest particle centre to the plane, less r
    z0 = gap + cell / 2 - RADIUS_RATIO * SIZE  # region bottom: lowest tip at height `gap`
    top = z0 + nz * cell
    last_impact = math.sqrt(2 * (top - cell) / G)  # the top layer reaches the pile's height ~cell
    duration = math.ceil((last_impact + a.settle) * 100) / 100
    w = nxy * cell
    scen = {
        "name": "gravity_packing_%d" % n,
        "seed": 1,
        "time": {"dt": 1e-5, "duration": duration, "output_interval": duration,
                 "stats_interval": a.stats_interval},
        "gravity": [0, 0, -G],
        "materials": {
            "p": {"density": DENSITY, "youngs_modulus": 2e9, "poisson_ratio": 0.25,
                  "shear_modulus": 1e9},
            "w": {"density": 7800, "youngs_modulus": 1e9, "poisson_ratio": 0.25,
                  "shear_modulus": 1e9}},
        "interactions": [
            {"between": ["p", "p"], "friction": 0.39, "damping": 0.453619},
            {"between": ["p", "w"], "friction": 0.35, "damping": 0.382097}],
        "shapes": {"schonhardt": {"builtin": "schonhardt"}},
        "particles": [{"shape": "schonhardt", "material": "p", "count": n, "size": SIZE,
                       "region": {"min": [-w / 2, -w / 2, z0],
                                  "max": [w / 2, w / 2, z0 + nz * cell]},
                       "orientation": "random"}],
        # the plane: a box wider than the lattice by its height on each side (room to spread)
        "walls": [{"name": "plane", "material": "w",
                   "box": {"min": [-w / 2 - top, -w / 2 - top, -0.05],
                           "max": [w / 2 + top, w / 2 + top, 0]}}],
        "output": {"fields": ["position", "orientation"]},
    }
    if a.allow_unstable_dt:
        scen["allow_unstable_dt"] = True
    path = os.path.join(a.out, "packing.json")
    study.write_json(path, scen)
    v = study.validate(path)
    meta = {"particles": n, "lattice": [nxy, nxy, nz], "size_m": SIZE, "density": DENSITY,
            "dt_s": 1e-5, "first_impact_s": a.first_impact, "last_impact_s": last_impact,
            "duration_s": duration, "validate": v}
    study.write_json(os.path.join(a.out, "meta.json"), meta)
    print("gravity packing: %d Schönhardt prisms (%d x %d x %d), d = %g m, first impact %.3f s, "
          "last ~%.3f s, duration %g s (%d steps)" % (n, nxy, nxy, nz, SIZE, a.first_impact,
                                                     last_impact, duration,
                                                     round(duration / 1e-5)))


def analyze(a):
    import h5py
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    with open(os.path.join(a.out, "meta.json")) as f:
        meta = json.load(f)
    with h5py.File(os.path.join(a.out, "packing.h5"), "r") as h5:
        st = h5["stats"]
        if "wall_time" not in st:
            study.die("packing.h5 has no /stats/wall_time (an engine older than this study)")
        t, step, wall = st["time"][()], st["step"][()], st["wall_time"][()]
        pairs, contacts = st["broad_pairs"][()], st["contacts"][()]
        ke = st["kinetic_energy"][()]
        n = h5["particles/mass"].shape[0]
        # per stage, the step that ends at each row (timed with the device finishing after
        # every stage); engines before it have no /stats/stage_time
        stages = {k: 1e3 * st["stage_time"][k][()] for k in STAGES if "stage_time" in st}
    dstep = np.diff(step)
    ms_per_step = 1e3 * np.diff(wall) / np.where(dstep > 0, dstep, 1)
    tm = 0.5 * (t[1:] + t[:-1])
    with open(os.path.join(a.out, "packing.csv"), "w") as f:
        f.write("time_s,step,wall_time_s,broad_pairs,contacts,kinetic_energy_J,"
                "ms_per_step_since_last_row%s\n" % "".join(",%s_ms" % k for k in stages))
        for i in range(len(t)):
            f.write("%.6g,%d,%.6g,%d,%d,%.6g,%s%s\n" % (
                t[i], step[i], wall[i], pairs[i], contacts[i], ke[i],
                "%.6g" % ms_per_step[i - 1] if i else "",
                "".join(",%.6g" % stages[k][i] for k in stages)))
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(tm, ms_per_step, "k-", lw=1, label="polydem, whole step (stats rows included)")
    for k, colour in zip(stages, ["tab:green", "tab:orange", "tab:purple", "tab:red", "tab:blue"]):
        ax.plot(t[1:], stages[k][1:], "-", color=colour, lw=0.8, label=STAGES[k])
    ax.axvline(meta["first_impact_s"], color="0.6", ls=":", lw=0.8, label="first impact")
    ax.axvline(meta["last_impact_s"], color="0.6", ls="--", lw=0.8, label="last impact (est.)")
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("wall time per step (ms)")
    ax.set_title("gravity packing, %d Schönhardt prisms (fig. 7.3)" % n, fontsize=9)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "time_per_step.png"), dpi=110)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(t, pairs, "k-", lw=1, label="broad-phase pairs")
    ax.plot(t, contacts, "b-", lw=1, label="contacts (overlapping pairs)")
    ax.axvline(meta["first_impact_s"], color="0.6", ls=":", lw=0.8)
    ax.axvline(meta["last_impact_s"], color="0.6", ls="--", lw=0.8)
    ax.set_xlabel("simulated time (s)")
    ax.set_ylabel("pairs")
    ax.set_title("gravity packing, %d Schönhardt prisms (fig. 7.4)" % n, fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "pairs.png"), dpi=110)
    # time per step against pairs (thesis fig. 7.5)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(pairs[1:], ms_per_step, "k.", ms=3)
    ax.set_xlabel("broad-phase pairs")
    ax.set_ylabel("wall time per step (ms)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "time_vs_pairs.png"), dpi=110)

    before = tm < meta["first_impact_s"]
    after = tm > meta["last_impact_s"]
    summ = {"particles": int(n), "steps": int(step[-1]), "wall_s": float(wall[-1]),
            "ms_per_step_mean": float(1e3 * wall[-1] / max(step[-1], 1)),
            "ms_per_step_before_impact": float(np.median(ms_per_step[before])) if before.any()
            else None,
            "ms_per_step_packed": float(np.median(ms_per_step[after])) if after.any() else None,
            "max_broad_pairs": int(pairs.max()), "final_broad_pairs": int(pairs[-1]),
            "final_contacts": int(contacts[-1]), "final_contacts_per_particle":
            float(contacts[-1] / n), "final_kinetic_energy_J": float(ke[-1]),
            "max_kinetic_energy_J": float(ke.max())}
    if summ["ms_per_step_packed"]:
        summ["us_per_pair_step_packed"] = 1e3 * summ["ms_per_step_packed"] / max(pairs[-1], 1)
    for k in stages:  # share of the timed steps' time, before the first impact and packed
        for name, sel in (("before_impact", before), ("packed", after)):
            total = sum(stages[j][1:][sel].sum() for j in stages)
            if total > 0:
                summ["stage_share_%s_%s" % (name, k)] = float(stages[k][1:][sel].sum() / total)
    study.write_json(os.path.join(a.out, "summary.json"), summ)
    for k, v in summ.items():
        print("  %-28s %s" % (k, v))
    if a.partial:  # cut short (bench/device.sh kills a run at its budget): figures, no bands
        print("gravity_packing: a partial run, to t = %.4g s of %.4g s: the figures above; the "
              "bands (a pile formed, the fall stopped) apply to a whole run and are not checked"
              % (t[-1], meta["duration_s"]))
        return
    b = Bands("gravity_packing")
    b.check(contacts[-1] >= 0.5 * n, "final contacts / particles", "%.2f" % (contacts[-1] / n),
            ">= 0.5", "a pile formed: a resting packing has ~1-3 contacts per particle, the "
            "falling lattice none")
    b.check(ke[-1] <= 0.2 * ke.max(), "final / peak kinetic energy", "%.3g" % (ke[-1] / ke.max()),
            "<= 0.2", "the pile stopped the fall (it still settles at the end, as the "
            "thesis's run ends soon after the last impact)")
    b.finish()


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate")
    g.add_argument("--particles", type=int, required=True)
    g.add_argument("--out", required=True)
    g.add_argument("--first-impact", type=float, default=0.05,
                   help="s until the lowest layer touches the plane (thesis: 0.4)")
    g.add_argument("--settle", type=float, default=0.06, help="s simulated after the last impact")
    g.add_argument("--stats-interval", type=float, default=1e-3)
    g.add_argument("--allow-unstable-dt", action="store_true")
    z = sub.add_parser("analyze")
    z.add_argument("--out", required=True)
    z.add_argument("--partial", action="store_true",
                   help="the run was cut short (its .partial file): report and plot, no bands")
    a = ap.parse_args()
    generate(a) if a.cmd == "generate" else analyze(a)


if __name__ == "__main__":
    main()
