"""Scenarios of many independent head-on collisions of two equal particles (thesis sections 6.1
and 6.2): pairs on a grid far apart from each other, random orientations, normal elastic force
only (friction 0, damping 0, no gravity), and the ensemble analysis of E_k/E_k0 per pair.

One scenario holds the whole ensemble: the engine's per-step cost is then spent on many pairs at
once instead of on the overhead of many tiny runs.
"""
import math

import numpy as np

import study

SPACING = 10.0  # grid spacing between pairs, in radii (pairs never meet)


def pair_scenario(name, shape, E, npairs, seed, R=0.1, v=5.0, nu=0.25, rho=1000.0,
                  steps_per_contact=300, samples_per_contact=100, contacts=2.0):
    """The scenario dict and its metadata. shape is the scenario's shape object. Pair k collides along x; both
    particles start with the separation at which their circumscribed spheres are 2 mm apart,
    and meet head-on at v each. The time axis of the analysis starts when the two
    volume-equivalent spheres would touch, t0 = (separation - 2R) / (2v)."""
    m = rho * 4.0 / 3.0 * math.pi * R ** 3
    e_eff = E / (2 * (1 - nu * nu))
    tc = study.hertz_contact_time(m / 2, R / 2, e_eff, 2 * v)
    rc = study.circumradius_factor(shape) * R
    sep = 2 * rc + 0.002
    t0 = (sep - 2 * R) / (2 * v)
    dt = tc / steps_per_contact
    out_dt = tc / samples_per_contact
    duration = t0 + contacts * tc
    rng = np.random.default_rng(seed)
    quats = study.random_quaternions(rng, 2 * npairs)
    side = int(math.ceil(math.sqrt(npairs)))
    plist = []
    for k in range(npairs):
        y, z = SPACING * R * (k % side), SPACING * R * (k // side)
        for j, sgn in enumerate((-1, 1)):
            plist.append({"position": [sgn * 0.5 * sep, y, z],
                          "orientation": [float(c) for c in quats[2 * k + j]],
                          "velocity": [-sgn * v, 0, 0], "size": 2 * R})
    scen = {
        "name": name, "seed": seed,
        "time": {"dt": dt, "duration": duration, "output_interval": out_dt,
                 "stats_interval": out_dt},
        "gravity": [0, 0, 0],
        "materials": {"m": {"density": rho, "youngs_modulus": E, "poisson_ratio": nu}},
        "interactions": [{"between": ["m", "m"], "friction": 0, "damping": 0}],
        "shapes": {"s": shape},
        "particles": [{"shape": "s", "material": "m", "list": plist}],
        "output": {"fields": ["position", "orientation", "velocity", "angular_velocity"]},
    }
    meta = {"E": E, "nu": nu, "rho": rho, "R": R, "v": v, "mass": m, "npairs": npairs,
            "seed": seed, "t0": t0, "tc_hertz": tc, "dt": dt}
    return scen, meta


def pair_energies(h5, t0):
    """Per-pair normalised kinetic energy: (times after t0 (F,), e (F, npairs)). Particles 2k and
    2k+1 form pair k (the order of the generated list)."""
    t, ke = study.particle_energies(h5)
    n = ke.shape[1]
    if n % 2:
        study.die("%s: odd particle count %d in a pair ensemble" % (h5.filename, n))
    pe = ke[:, 0::2] + ke[:, 1::2]
    return t - t0, pe / pe[0][None, :]


def ensemble_stats(e):
    """Mean and standard deviation over pairs (axis 1), and the same for the first half of the
    ensemble: the convergence check of the statistics."""
    h = max(1, e.shape[1] // 2)
    return {"mean": e.mean(1), "std": e.std(1, ddof=1) if e.shape[1] > 1 else 0 * e[:, 0],
            "mean_half": e[:, :h].mean(1),
            "std_half": e[:, :h].std(1, ddof=1) if h > 1 else 0 * e[:, 0]}
