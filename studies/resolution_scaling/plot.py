"""Figure 7.6 from build/studies/resolution_scaling/scaling.csv: time per overlap relative to the
lowest resolution, filter on and off, per depth; and the triangles the filter keeps. Checks the
filter's scaling band (see README.md) and exits 1 outside it."""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))
from bands import Bands  # noqa: E402

out = sys.argv[1]
with open(os.path.join(out, "scaling.csv")) as f:
    rows = [{k: float(v) if k != "shape" else v for k, v in r.items()} for r in csv.DictReader(f)]
if not rows:
    sys.exit("error: %s/scaling.csv holds no rows" % out)
depths = sorted({r["depth"] for r in rows})
fig, axs = plt.subplots(1, 2, figsize=(11, 4))
b = Bands("resolution_scaling")
for d in depths:
    rs = sorted((r for r in rows if r["depth"] == d), key=lambda r: r["triangles"])
    t = [r["triangles"] for r in rs]
    # the unfiltered time is measured up to 1280 triangles only (nan beyond: run.sh)
    ro = [r for r in rs if not math.isnan(r["ns_filter_off"])]
    p = axs[0].plot(t, [r["ns_filter_on"] / rs[0]["ns_filter_on"] for r in rs], "o-",
                    label="filter on, depth %g D" % d)
    axs[0].plot([r["triangles"] for r in ro], [r["ns_filter_off"] / ro[0]["ns_filter_off"]
                                               for r in ro], "x--",
                color=p[0].get_color(), label="filter off, depth %g D" % d)
    axs[1].plot(t, [r["kept_tris_filter_on"] / (2 * r["triangles"]) for r in rs], "o-",
                label="depth %g D" % d)

    def exponent(lo, hi, key):
        return math.log(hi[key] / lo[key]) / math.log(hi["triangles"] / lo["triangles"])

    # exponents of the time against triangles: with the filter over the whole range, and
    # with and without it over the range both were measured
    if len(ro) > 1:
        k_on = exponent(rs[0], rs[-1], "ns_filter_on")
        k_on_lo = exponent(ro[0], ro[-1], "ns_filter_on")
        k_off = exponent(ro[0], ro[-1], "ns_filter_off")
        print("  depth %g D: time ~ triangles^%.2f with the filter (%d-%d); %d-%d: ^%.2f with "
              "the filter, ^%.2f without" % (d, k_on, t[0], t[-1], ro[0]["triangles"],
                                            ro[-1]["triangles"], k_on_lo, k_off))
        if d <= 0.035:
            b.check(k_on <= 1.0, "depth %g D: exponent with the filter, %d-%d triangles"
                    % (d, t[0], t[-1]), "%.2f" % k_on, "<= 1.0",
                    "thesis fig. 7.6: close to linear for stiff contacts")
        b.check(k_on_lo < k_off, "depth %g D: the filter scales better than no filter" % d,
                "%.2f < %.2f" % (k_on_lo, k_off), "on < off",
                "the filter's purpose (section 5.2)")
xs = sorted({r["triangles"] for r in rows})
axs[0].plot(xs, [x / xs[0] for x in xs], "k:", lw=0.8, label="linear")
axs[0].plot(xs, [(x / xs[0]) ** 2 for x in xs], "k-.", lw=0.8, label="quadratic")
axs[0].set_xscale("log")
axs[0].set_yscale("log")
axs[0].set_xlabel("triangles per particle (rock)")
axs[0].set_ylabel("time per overlap / time at %d triangles" % xs[0])
axs[0].legend(fontsize=7)
axs[0].grid(alpha=0.3)
axs[1].set_xscale("log")
axs[1].set_xlabel("triangles per particle (rock)")
axs[1].set_ylabel("fraction of the pair's triangles the filter keeps")
axs[1].legend(fontsize=7)
axs[1].grid(alpha=0.3)
fig.tight_layout()
fig.savefig(os.path.join(out, "scaling.png"), dpi=110)
b.finish()
