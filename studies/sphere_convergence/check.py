"""Bands of the sphere convergence study (thesis section 6.1), set from measured runs and the
thesis's figures, not tuned to pass; see README.md for the measured values."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "lib"))
from bands import Bands, load_cases  # noqa: E402

cases = load_cases(sys.argv[1])
b = Bands("sphere_convergence")
tris = sorted({t for t, _ in cases})
moduli = sorted({E for _, E in cases})
for t in tris:
    c = cases.get((t, 1e6))
    if c is None or t < 80:
        continue
    d = c["min_mean"] - c["min_analytic"]
    b.check(d <= 0.02, "E = 1 MPa, %d triangles: min mean E_k/E_k0 - analytic min" % t,
            "%.3g" % d, "<= 0.02",
            "issue 6: within a few percent of the analytic sphere (thesis fig. 6.4: ~0)")
for (t, E), c in sorted(cases.items()):
    if t >= 320:
        d = abs(c["final_mean"] - 1)
        b.check(d <= 1e-3, "E = %g MPa, %d triangles: |final mean E_k/E_k0 - 1|" % (E / 1e6, t),
                "%.3g" % d, "<= 1e-3",
                "no damping, no friction: near-spherical shapes keep their energy "
                "(200 steps per contact)")
for E in moduli:
    seq = [(t, cases[(t, E)]["max_std"]) for t in tris if t >= 80 and (t, E) in cases]
    mono = all(b2 < a2 for (_, a2), (_, b2) in zip(seq, seq[1:]))
    b.check(mono, "E = %g MPa: max std falls with resolution" % (E / 1e6),
            ", ".join("%d: %.3g" % x for x in seq), "decreasing from 80 triangles on",
            "thesis fig. 6.4 (right): convergence in resolution")
E = max(moduli)
if (80, E) in cases and (1280, E) in cases:
    lo, hi = cases[(80, E)]["min_mean"], cases[(1280, E)]["min_mean"]
    b.check(hi < lo, "E = %g MPa: min mean at 1280 below 80 triangles" % (E / 1e6),
            "%.3g < %.3g" % (hi, lo), "1280 < 80",
            "thesis fig. 6.4 (left): stiffer contacts converge from above")
b.finish()
