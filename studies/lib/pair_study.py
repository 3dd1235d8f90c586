"""The ensemble collision studies (thesis sections 6.1 and 6.2): generate the scenarios of one
study (every resolution x Young's modulus, one scenario each holding the whole ensemble), and
analyse the results into a CSV per case, the summary CSV, and the figures.

  pair_study.py generate --study NAME --family icosphere|rock --triangles 80,320 --moduli 1e6,21.5e6
                         --pairs N --seed S --out DIR [--rock-seed K] [--contacts C]
  pair_study.py analyze  --out DIR [--analytic]

generate writes DIR/cases.json (the list of cases with their metadata) and DIR/<case>.json;
the run script runs each scenario into DIR/<case>.h5; analyze writes DIR/<case>.csv (time,
mean, std, the first half's mean and std, and the analytic sphere with --analytic),
DIR/summary.csv and DIR/summary.json, and the PNG figures.
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pairs  # noqa: E402
import study  # noqa: E402


def case_name(tri, E):
    return "t%d_E%gMPa" % (tri, E / 1e6)


def generate(a):
    os.makedirs(a.out, exist_ok=True)
    cases = []
    for E in a.moduli:
        for tri in a.triangles:
            shape = {"builtin": a.family, "triangles": tri}
            if a.family == "rock":
                shape["seed"] = a.rock_seed
            name = case_name(tri, E)
            scen, meta = pairs.pair_scenario(a.study + "_" + name, shape, E, a.pairs, a.seed,
                                             contacts=a.contacts)
            path = os.path.join(a.out, name + ".json")
            study.write_json(path, scen)
            v = study.validate(path)
            if v["dt_s"] > v["dt_stable_s"]:
                study.die("%s: dt %g above the stable estimate %g" % (path, v["dt_s"],
                                                                      v["dt_stable_s"]))
            meta.update({"case": name, "triangles": tri, "shape": shape, "steps": v["steps"],
                         "dt_stable": v["dt_stable_s"]})
            cases.append(meta)
    study.write_json(os.path.join(a.out, "cases.json"), {"study": a.study, "cases": cases})
    print("%s: %d scenarios of %d pairs in %s" % (a.study, len(cases), a.pairs, a.out))


def analyze(a):
    import h5py
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with open(os.path.join(a.out, "cases.json")) as f:
        cfg = json.load(f)
    summary = []
    curves = {}
    for c in cfg["cases"]:
        h5path = os.path.join(a.out, c["case"] + ".h5")
        if not os.path.exists(h5path):
            study.die("%s: missing (run the scenarios first)" % h5path)
        with h5py.File(h5path, "r") as f:
            t, e = pairs.pair_energies(f, c["t0"])
        s = pairs.ensemble_stats(e)
        an = None
        cols = [t, s["mean"], s["std"], s["mean_half"], s["std_half"]]
        head = ["time_s", "mean", "std", "mean_first_half", "std_first_half"]
        if a.analytic:
            an, _ = study.hertz_sphere_energy(c["mass"], c["R"], c["E"], c["nu"], c["v"], t)
            cols.append(an)
            head.append("analytic_sphere")
        with open(os.path.join(a.out, c["case"] + ".csv"), "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(head)
            for row in zip(*cols):
                w.writerow(["%.9g" % x for x in row])
        # contact duration of the mean response: from t0 until the mean is back within 1e-3
        # of its final value (the first time after its minimum)
        imin = int(np.argmin(s["mean"]))
        back = np.nonzero(np.abs(s["mean"][imin:] - s["mean"][-1]) < 1e-3)[0]
        t_end = t[imin + back[0]] if len(back) else float("nan")
        row = {
            "case": c["case"], "triangles": c["triangles"], "E_Pa": c["E"], "pairs": e.shape[1],
            "min_mean": float(s["mean"].min()), "min_mean_first_half": float(s["mean_half"].min()),
            "max_std": float(s["std"].max()), "max_std_first_half": float(s["std_half"].max()),
            "final_mean": float(s["mean"][-1]),
            "max_final_deviation": float(np.abs(e[-1] - 1).max()),
            "mean_back_s": float(t_end), "tc_hertz_s": c["tc_hertz"],
        }
        if an is not None:
            row["min_analytic"] = float(an.min())
            row["max_abs_mean_minus_analytic"] = float(np.abs(s["mean"] - an).max())
        summary.append(row)
        curves[c["case"]] = (c, t, s, an)
    keys = list(summary[0].keys())
    with open(os.path.join(a.out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for r in summary:
            w.writerow(r)
    study.write_json(os.path.join(a.out, "summary.json"), {"study": cfg["study"],
                                                           "cases": summary})

    # figures: mean and std against time (figures 6.2/6.3, 6.6/6.7), one panel per modulus
    moduli = sorted({c["E"] for c in cfg["cases"]})
    for what, label in (("mean", "mean of $E_k/E_k^0$"), ("std", "std of $E_k/E_k^0$")):
        fig, axs = plt.subplots(1, len(moduli), figsize=(5.5 * len(moduli), 4), squeeze=False)
        for ax, E in zip(axs[0], moduli):
            an_done = False
            for name, (c, t, s, an) in curves.items():
                if c["E"] != E:
                    continue
                ax.plot(t * 1e3, s[what], label="%d triangles" % c["triangles"])
                if what == "mean" and an is not None and not an_done:
                    ax.plot(t * 1e3, an, "k:", label="Hertz sphere")
                    an_done = True
            ax.set_title("E = %g MPa (%d pairs)" % (E / 1e6, cfg["cases"][0]["npairs"]))
            ax.set_xlabel("time after the equivalent spheres touch (ms)")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "energy_%s.png" % what), dpi=110)
        plt.close(fig)
    # convergence against resolution (figure 6.4), with the first half of the ensemble
    fig, axs = plt.subplots(1, 2, figsize=(11, 4))
    for E in moduli:
        rows = sorted((r for r in summary if r["E_Pa"] == E), key=lambda r: r["triangles"])
        tri = [r["triangles"] for r in rows]
        for ax, k in ((axs[0], "min_mean"), (axs[1], "max_std")):
            p = ax.plot(tri, [r[k] for r in rows], "o-", label="E = %g MPa" % (E / 1e6))
            ax.plot(tri, [r[k + "_first_half"] for r in rows], "x--", color=p[0].get_color(),
                    label="E = %g MPa, first half of the ensemble" % (E / 1e6))
    for ax, lab in ((axs[0], "minimum of the mean $E_k/E_k^0$"),
                    (axs[1], "maximum of the std of $E_k/E_k^0$")):
        ax.set_xscale("log")
        ax.set_xlabel("triangles per particle")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "convergence.png"), dpi=110)
    plt.close(fig)
    for r in summary:
        print("%-16s pairs %4d  min mean %.4g (half %.4g)  max std %.4g (half %.4g)  final %.6f"
              % (r["case"], r["pairs"], r["min_mean"], r["min_mean_first_half"], r["max_std"],
                 r["max_std_first_half"], r["final_mean"]))
    return summary


def main():
    p = argparse.ArgumentParser()
    sub = p.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("generate")
    g.add_argument("--study", required=True)
    g.add_argument("--family", choices=["icosphere", "rock"], required=True)
    g.add_argument("--triangles", type=lambda s: [int(x) for x in s.split(",")], required=True)
    g.add_argument("--moduli", type=lambda s: [float(x) for x in s.split(",")], required=True)
    g.add_argument("--pairs", type=int, required=True)
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("--rock-seed", type=int, default=1)
    g.add_argument("--contacts", type=float, default=1.5,
                   help="simulated time after t0 in Hertz contact times")
    g.add_argument("--out", required=True)
    an = sub.add_parser("analyze")
    an.add_argument("--out", required=True)
    an.add_argument("--analytic", action="store_true", help="compare with the Hertz sphere")
    a = p.parse_args()
    if a.cmd == "generate":
        generate(a)
    else:
        analyze(a)


if __name__ == "__main__":
    main()
