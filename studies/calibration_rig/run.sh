#!/bin/sh
# studies/calibration_rig/run.sh [--quick]: thesis section 6.3, Table A.2, figures 6.9 and 6.10.
# Rock particles fall into a hopper, the trap doors slide open, the particles flow down a tilted
# plane, drop off its free edge and pile up on the bottom plate; the repose angle comes from a
# 20-bin height map of the pile's front flank fitted with eq. 6.1 (studies/calibration/
# repose_fit.c, GSL), against triangles per particle (rig.py). Output in
# build/studies/calibration_rig/: heightmaps.png (fig. 6.9), repose.png (fig. 6.10), repose.csv.
# Exits non-zero when a run or a fit fails, an angle leaves its band (10-45 deg), a pile is too
# low or not at rest (kinetic energy, creep; rig.py analyze). Full: 20-320 triangles, 400
# particles, phase 2 1.3 s; --quick: 20 triangles (the full run's first case).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
POLYDEM=${POLYDEM:-$ROOT/build/polydem}
OUT=${STUDIES_OUT:-$ROOT/build/studies}/calibration_rig
REPOSE_FIT=${REPOSE_FIT:-$ROOT/build/studies/repose_fit}
export POLYDEM REPOSE_FIT
TRIS="20 40 80 160 320"
case ${1:-} in
--quick)
    # one resolution: fewer particles make no pile (README.md), so the quick run is the full
    # run's first case
    TRIS=${TRIS_QUICK:-20}
    ;;
"") ;;
*) echo "usage: $0 [--quick]" >&2; exit 2 ;;
esac
PARTICLES=${PARTICLES:-400}
# SCALE=1.87 PARTICLES=1400: Table A.2's 1 kg, the rig's lengths across the channel scaled so that
# the pile fits its map as 400 particles' does (rig.py apply_scale)
SCALE=${SCALE:-1}
# SEEDS="1 2 3": several runs per resolution (the particles' sizes, places and orientations
# drawn anew), reported as mean and standard deviation (figure 6.10's 11 runs)
SEEDS=${SEEDS:-1}
DURATION=${DURATION:-1.3} # the piles stop creeping by then (README.md)
# CONTACT_PLACES=separate: each place of a pair touching in several is pressed on its own
# (docs/SCENARIO.md, interactions[].contact_places); merged, the thesis's model, by default
PLACES=${CONTACT_PLACES:-merged}
# CONTACT_MOMENTS=off: the thesis's point contact, without twisting friction and the dashpots'
# moments (docs/SCENARIO.md, interactions[].contact_moments); on by default
MOMENTS=${CONTACT_MOMENTS:-on}
[ -x "$POLYDEM" ] || { echo "error: $POLYDEM not built (run make)" >&2; exit 1; }
[ -x "$REPOSE_FIT" ] || { echo "error: $REPOSE_FIT not built (make studies builds it)" >&2; exit 1; }
rm -rf "$OUT"
mkdir -p "$OUT"
run() {
    t0=$(date +%s)
    if ! "$POLYDEM" run "$1" -o "$2" --quiet >"$2.log" 2>&1; then
        cat "$2.log" >&2
        echo "error: polydem run $1 failed" >&2
        exit 1
    fi
    echo $(($(date +%s) - t0))
}
echo "calibration_rig: $PARTICLES particles, phase 2 $DURATION s, triangles $TRIS, seeds $SEEDS," \
    "contact places $PLACES, contact moments $MOMENTS, rig scale $SCALE"
echo '{"cases": [' >"$OUT/cases.json"
sep=
for t in $TRIS; do
    for seed in $SEEDS; do
        tag=$t
        [ "$seed" = 1 ] || tag=${t}_s$seed
        "$PY" "$HERE/rig.py" phase1 --triangles "$t" --seed "$seed" --particles "$PARTICLES" \
            --scale "$SCALE" \
            --contact-places "$PLACES" --contact-moments "$MOMENTS" --out "$OUT"
        s1=$(run "$OUT/rig_${tag}_1.json" "$OUT/rig_${tag}_1.h5")
        "$PY" "$HERE/rig.py" phase2 --triangles "$t" --seed "$seed" --duration "$DURATION" \
            --scale "$SCALE" \
            --contact-places "$PLACES" --contact-moments "$MOMENTS" --out "$OUT"
        s2=$(run "$OUT/rig_${tag}_2.json" "$OUT/rig_${tag}_2.h5")
        echo "  $t triangles, seed $seed: filling $s1 s, flow and pile $s2 s (wall clock)"
        "$PY" "$HERE/rig.py" heightmap --triangles "$t" --seed "$seed" --scale "$SCALE" --out "$OUT"
        printf '%s{"triangles": %d, "seed": %d, "settle_s": %d, "flow_s": %d, "run_s": %d}\n' \
            "$sep" "$t" "$seed" "$s1" "$s2" $((s1 + s2)) >>"$OUT/cases.json"
        sep=,
    done
done
echo ']}' >>"$OUT/cases.json"
"$PY" "$HERE/rig.py" analyze --scale "$SCALE" --out "$OUT"
