#!/bin/sh
# studies/calibration_rig/prototype.sh [--quick]: thesis section 6.3, Table A.2, figures 6.9
# and 6.10. A prototype, not yet run.sh (so `make studies` does not run it): the eq. 6.1 fit does
# not converge on this rig's piles yet (README.md). Rock particles settle in a hopper, the trap
# doors slide open, the particles flow down a tilted plane and pile against a back wall; the
# repose angle from a 20-bin height map fitted with eq. 6.1 (studies/calibration/repose_fit.c,
# GSL), against triangles per particle. Output in build/studies/calibration_rig/; exits non-zero
# when the fit fails, an angle leaves its band (15-45 deg, not yet measured) or a pile is not at
# rest (rig.py analyze).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
POLYDEM=${POLYDEM:-$ROOT/build/polydem}
OUT=${STUDIES_OUT:-$ROOT/build/studies}/calibration_rig
FIT=${REPOSE_FIT:-$ROOT/build/studies/repose_fit}
TRIS="20 40 80 160 320"
PARTICLES_DEFAULT=220
DURATION_DEFAULT=0.8
case ${1:-} in
--quick) TRIS="20 80"; PARTICLES=${PARTICLES:-160}; DURATION=${DURATION:-0.6} ;;
"") ;;
*) echo "usage: $0 [--quick]" >&2; exit 2 ;;
esac
PARTICLES=${PARTICLES:-$PARTICLES_DEFAULT}
DURATION=${DURATION:-$DURATION_DEFAULT}
[ -x "$POLYDEM" ] || { echo "error: $POLYDEM not built (run make)" >&2; exit 1; }
[ -x "$FIT" ] || { echo "error: $FIT not built (make studies builds it)" >&2; exit 1; }
rm -rf "$OUT"
mkdir -p "$OUT"
run() {
    t0=$(date +%s)
    if ! "$POLYDEM" run "$1" -o "$2" --quiet; then
        echo "error: polydem run $1 failed" >&2
        exit 1
    fi
    echo $(($(date +%s) - t0))
}
echo '{"cases": [' >"$OUT/cases.json"
sep=
for t in $TRIS; do
    "$PY" "$HERE/rig.py" phase1 --triangles "$t" --particles "$PARTICLES" --out "$OUT"
    s1=$(run "$OUT/rig_${t}_1.json" "$OUT/rig_${t}_1.h5")
    "$PY" "$HERE/rig.py" phase2 --triangles "$t" --duration "$DURATION" --out "$OUT"
    s2=$(run "$OUT/rig_${t}_2.json" "$OUT/rig_${t}_2.h5")
    echo "  $t triangles: settling $s1 s, flow and pile $s2 s"
    "$PY" "$HERE/rig.py" heightmap --triangles "$t" --out "$OUT"
    printf '%s{"triangles": %d, "run_s": %d}\n' "$sep" "$t" $((s1 + s2)) >>"$OUT/cases.json"
    sep=,
done
echo ']}' >>"$OUT/cases.json"
"$PY" "$HERE/rig.py" analyze --out "$OUT"
