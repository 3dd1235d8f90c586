"""Shared helpers of the verification studies (studies/*): scenarios, the analytic Hertz sphere,
per-particle kinetic energies from a polydem result file, and small plotting conveniences.

Units are SI throughout. Results are read with h5py in the layout of engine/result_h5.h.
"""
import json
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
POLYDEM = os.environ.get("POLYDEM", os.path.join(ROOT, "build", "polydem"))
OUT_ROOT = os.environ.get("STUDIES_OUT", os.path.join(ROOT, "build", "studies"))


def die(msg):
    sys.stderr.write("error: %s\n" % msg)
    sys.exit(1)


def random_quaternions(rng, n):
    """n uniformly distributed unit quaternions (w, x, y, z): normalised 4-d Gaussians."""
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    q[q[:, 0] < 0] *= -1
    return q


def circumradius_factor(shape):
    """Circumradius over the volume-equivalent radius of a scenario shape object, from the
    body-frame vertices the engine itself writes (a one-step run of one particle), so that
    pairs can be placed without overlap at t = 0."""
    import h5py
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        scen = {"name": "shape", "time": {"dt": 1e-6, "duration": 1e-6},
                "gravity": [0, 0, 0],
                "materials": {"m": {"density": 1000, "youngs_modulus": 1e6}},
                "interactions": [{"between": ["m", "m"]}],
                "shapes": {"s": shape},
                "particles": [{"shape": "s", "material": "m",
                               "list": [{"position": [0, 0, 0], "size": 1}]}]}
        write_json(os.path.join(d, "s.json"), scen)
        r = subprocess.run([POLYDEM, "run", os.path.join(d, "s.json"), "-o",
                            os.path.join(d, "s.h5"), "--quiet"], capture_output=True, text=True)
        if r.returncode != 0:
            die("polydem run (shape probe) failed:\n%s%s" % (r.stdout, r.stderr))
        with h5py.File(os.path.join(d, "s.h5"), "r") as f:
            verts = f["shapes/s/vertices"][()]
    return float(np.linalg.norm(verts, axis=1).max()) / 0.5


def validate(path):
    """Runs `polydem validate --json` and returns its summary; exits on a refused scenario."""
    r = subprocess.run([POLYDEM, "validate", path, "--json"], capture_output=True, text=True)
    if r.returncode != 0:
        die("polydem validate %s failed:\n%s%s" % (path, r.stdout, r.stderr))
    return json.loads(r.stdout)


def write_json(path, obj):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        json.dump(obj, f, indent=1)
        f.write("\n")


# ---- the analytic Hertz sphere ---------------------------------------------------------------

def hertz_contact_time(m_eff, r_eff, e_eff, v_rel):
    """Duration of a Hertz impact, 2.8683 (m*^2 / (R* E*^2 v))^(1/5)."""
    return 2.8683 * (m_eff ** 2 / (r_eff * e_eff ** 2 * v_rel)) ** 0.2


def hertz_sphere_energy(m, R, E, nu, v, t):
    """Normalised kinetic energy E_k/E_k0 of two equal elastic spheres (mass m, radius R, Young's
    modulus E, Poisson ratio nu) meeting head-on at speed v each, at times t (s) after first
    touch. Integrates m* x'' = -(4/3) E* sqrt(R*) x^(3/2) (x the overlap) with classical RK4 at
    a step far below the sampling; independent of the engine."""
    m_eff, r_eff = m / 2, R / 2
    e_eff = E / (2 * (1 - nu * nu))
    k = 4.0 / 3.0 * e_eff * math.sqrt(r_eff)
    tc = hertz_contact_time(m_eff, r_eff, e_eff, 2 * v)
    h = tc / 20000

    def acc(x):
        return -k * max(x, 0.0) ** 1.5 / m_eff

    t = np.asarray(t, dtype=float)
    out = np.ones_like(t)
    order = np.argsort(t)
    x, u, tt = 0.0, 2 * v, 0.0  # overlap, its rate (relative speed)
    ke0 = 0.5 * m_eff * (2 * v) ** 2  # = 2 * (1/2 m v^2): the relative motion holds all of it
    for i in order:
        if t[i] <= 0:
            continue
        while tt < t[i] and x >= 0:
            dt = min(h, t[i] - tt)
            k1x, k1u = u, acc(x)
            k2x, k2u = u + 0.5 * dt * k1u, acc(x + 0.5 * dt * k1x)
            k3x, k3u = u + 0.5 * dt * k2u, acc(x + 0.5 * dt * k2x)
            k4x, k4u = u + dt * k3u, acc(x + dt * k3x)
            x += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            u += dt / 6 * (k1u + 2 * k2u + 2 * k3u + k4u)
            tt += dt
        out[i] = 1.0 if x < 0 else 0.5 * m_eff * u * u / ke0
    return out, tc


# ---- results ---------------------------------------------------------------------------------

def mesh_inertia(verts, tris):
    """Volume and inertia tensor (density 1, about the origin) of a closed triangle mesh."""
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    vol6 = np.einsum("ij,ij->i", a, np.cross(b, c))  # 6 x signed tetra volume
    vol = vol6.sum() / 6
    # second moments of each tetrahedron (origin, a, b, c): integral of x_i x_j
    s = a + b + c
    cov = (np.einsum("n,ni,nj->ij", vol6, a, a) + np.einsum("n,ni,nj->ij", vol6, b, b)
           + np.einsum("n,ni,nj->ij", vol6, c, c) + np.einsum("n,ni,nj->ij", vol6, s, s)) / 120
    return vol, np.trace(cov) * np.eye(3) - cov


def quat_to_matrix(q):
    """Rotation matrices (n,3,3) of quaternions q (n,4) = (w, x, y, z)."""
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], -2)


def particle_energies(h5):
    """Kinetic energy (translation + rotation) of every particle in every frame, (F, N) J, and
    the frame times (F,) s. Needs /frames/velocity and /frames/angular_velocity."""
    fr = h5["frames"]
    for name in ("velocity", "angular_velocity"):
        if name not in fr:
            die("%s: no /frames/%s (set output.fields)" % (h5.filename, name))
    mass = h5["particles/mass"][()]
    size = h5["particles/size"][()]
    shape = h5["particles/shape"][()]
    names = [n.decode() if isinstance(n, bytes) else n for n in h5["particles/shape"].attrs["names"]]
    ibody = []  # per shape: inertia per unit mass at size 1 (body frame)
    for nm in names:
        g = h5["shapes"][nm]
        vol, inertia = mesh_inertia(g["vertices"][()], g["triangles"][()])
        ibody.append(inertia / vol)
    ibody = np.array(ibody)
    v = fr["velocity"][()]
    w = fr["angular_velocity"][()]
    q = fr["orientation"][()]
    F, N = v.shape[:2]
    ke = 0.5 * mass[None, :] * np.einsum("fni,fni->fn", v, v)
    rot = quat_to_matrix(q.reshape(-1, 4)).reshape(F, N, 3, 3)
    wb = np.einsum("fnji,fnj->fni", rot, w)  # body-frame angular velocity R^T w
    ib = ibody[shape] * (mass * size * size)[:, None, None]  # (N,3,3)
    ke += 0.5 * np.einsum("fni,nij,fnj->fn", wb, ib, wb)
    return fr["time"][()], ke
