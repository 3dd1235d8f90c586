#!/bin/sh
# studies/gravity_packing/run.sh [--quick | --full]: thesis section 7.1, Table A.3, figures 7.3
# and 7.4. Schönhardt prisms fall from a lattice onto a plane; time per step (from
# /stats/wall_time) and broad-phase pairs against simulated time. 1e4 particles by default
# (CPU, ~10 min), ~1e3 with --quick (~2 min), ~1e6 with --full (a GPU; the thesis's 0.4 s to the
# first impact). Output in build/studies/gravity_packing/. A performance study without a band:
# it fails only when the run fails or no pile forms (packing.py analyze).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
POLYDEM=${POLYDEM:-$ROOT/build/polydem}
OUT=${STUDIES_OUT:-$ROOT/build/studies}/gravity_packing
ARGS="--particles ${PARTICLES:-10000}"
case ${1:-} in
--quick) ARGS="--particles ${PARTICLES:-1000}" ;;
# Table A.3's dt (1e-5 s) exceeds validate's estimate (8.7e-6 s) for the full fall height: the
# estimate takes two particles closing head-on at twice the largest fall speed
# --full: a stats row every 5 ms (500 steps): one row costs ~32 ms for 1e6 particles on an H200
# (bench/stats_rows.sh), which every 100 steps would add half again to a falling step
--full) ARGS="--particles ${PARTICLES:-1000000} --first-impact 0.4 --settle 0.1 --allow-unstable-dt --stats-interval 0.005" ;;
"") ;;
*) echo "usage: $0 [--quick | --full]" >&2; exit 2 ;;
esac
[ -x "$POLYDEM" ] || { echo "error: $POLYDEM not built (run make)" >&2; exit 1; }
rm -rf "$OUT"
mkdir -p "$OUT"
# shellcheck disable=SC2086
"$PY" "$HERE/packing.py" generate $ARGS --out "$OUT"
t0=$(date +%s)
if ! "$POLYDEM" run "$OUT/packing.json" -o "$OUT/packing.h5" --quiet; then
    echo "error: polydem run $OUT/packing.json failed" >&2
    exit 1
fi
echo "  run: $(($(date +%s) - t0)) s"
"$PY" "$HERE/packing.py" analyze --out "$OUT"
