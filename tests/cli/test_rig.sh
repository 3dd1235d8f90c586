#!/bin/sh
# test_rig.sh - the calibration rig's height map and rest measures (studies/calibration_rig/rig.py
# heightmap) on a made-up result of three cube grains whose answers are known: grain 0 rests;
# grain 1 moves 3 mm across the channel (y) between the last two frames, which moves no bin of
# the map (x, z) but is the fastest mapped grain; grain 2 has left the rig (3.6 m below the
# plate). Expected: the map's change 0, the fastest grain's 3 mm, one grain escaped, two in the
# pile, and bin tops at the cubes' top faces. Uses Debian's python3-numpy and python3-h5py.
PY=/usr/bin/python3
. "$(dirname "$0")/lib.sh"
if ! $PY -c "import numpy, h5py" 2>/dev/null; then
    bad rig_heightmap "python3-numpy and python3-h5py are needed (make deps)"
    done_tests
    exit 1
fi
$PY - "$tmp" >"$tmp/out" 2>&1 <<'PY'
import json, subprocess, sys
import h5py, numpy as np
d = sys.argv[1]
size = np.array([0.01, 0.01, 0.01])  # cubes of side 10 mm: vertices +-0.5 x size
verts = np.array([[x, y, z] for x in (-.5, .5) for y in (-.5, .5) for z in (-.5, .5)])
prev = np.array([[0.05, 0.0, 0.005], [0.07, -0.0015, 0.005], [0.05, 0.0, 0.2]])
last = np.array([[0.05, 0.0, 0.005], [0.07, 0.0015, 0.005], [0.05, 0.0, -3.6]])
q = np.tile([1.0, 0, 0, 0], (2, 3, 1))
with h5py.File(d + "/rig_20_2.h5", "w") as f:
    f["frames/position"] = np.stack([prev, last])
    f["frames/orientation"] = q
    f["frames/velocity"] = np.zeros((2, 3, 3))
    f["frames/time"] = [1.17, 1.3]
    f["particles/size"] = size
    f["particles/mass"] = [0.0026] * 3
    f["shapes/rock/vertices"] = verts
    f["stats/time"] = [0.0, 0.5, 1.3]
    f["stats/kinetic_energy"] = [0.0, 0.3, 1e-6]
subprocess.run([sys.executable, "studies/calibration_rig/rig.py", "heightmap", "--triangles", "20",
                "--out", d], check=True, capture_output=True)
with open(d + "/rig_20_hmap.txt") as f:
    meta = json.loads([l for l in f if l.startswith("# meta ")][0][7:])
h = np.loadtxt(d + "/rig_20_hmap.txt")
print(json.dumps({"escaped": meta["escaped"], "pile": meta["pile"],
                  "map_change_m": meta["map_change_m"], "creep_m": meta["creep_m"],
                  "top": float(h[:, 1].max()), "bins_at_top": int((h[:, 1] == 0.01).sum())}))
PY
if [ $? -ne 0 ]; then
    bad rig_heightmap "$(cat "$tmp/out")"
    done_tests
    exit 1
fi
r=$(tail -n 1 "$tmp/out")
field() { echo "$r" | $PY -c "import json, sys; print(json.load(sys.stdin)['$1'])"; }
[ "$(field escaped)" = 1 ] && [ "$(field pile)" = 2 ] && ok escaped_grain_counted ||
    bad escaped_grain_counted "$r"
# a move across the channel changes no bin: exactly 0; the fastest mapped grain moved 3 mm
awk -v m="$(field map_change_m)" -v c="$(field creep_m)" \
    'BEGIN { exit !(m == 0 && c > 0.003 - 1e-12 && c < 0.003 + 1e-12) }' &&
    ok map_change_against_creep || bad map_change_against_creep "$r"
# the cubes' top faces at z = 10 mm: each cube covers its 10 mm in x, two or more 7.5 mm bins
awk -v t="$(field top)" -v n="$(field bins_at_top)" 'BEGIN { exit !(t == 0.01 && n >= 3) }' &&
    ok bin_tops || bad bin_tops "$r"
done_tests
