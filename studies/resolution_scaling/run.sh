#!/bin/sh
# studies/resolution_scaling/run.sh [--quick]: thesis section 7.2.1, figure 7.6. Time of one
# polyhedral overlap of two `rock` particles (seed 1) against triangles per particle, with the
# half-plane filter on and off, at overlap depths standing in for the thesis's stiffnesses.
# Output in build/studies/resolution_scaling/ (scaling.csv, scaling.png); exits non-zero when
# the filter's scaling leaves its band (plot.py).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
BIN=${OVERLAP_SCALING:-$ROOT/build/studies/overlap_scaling}
OUT=${STUDIES_OUT:-$ROOT/build/studies}/resolution_scaling
# depths (fraction of the volume-equivalent diameter): 1 % (bench/overlap's), and the peak
# Hertz overlaps of the pair studies' spheres (R 0.1 m, 1000 kg/m^3, 5 m/s each) at
# E = 464 MPa (3.3 %) and 21.5 MPa (11 %)
TRIS="20 40 80 160 320 640 1280"
# beyond 1280 triangles the filter only (--no-filter-off): without it an overlap takes seconds
HIGH_TRIS="2560 5120 10240 20000"
DEPTHS="0.01 0.033 0.11"
MIN_TIME=0.5
case ${1:-} in
--quick) TRIS="20 80 320 1280"; HIGH_TRIS="5120"; DEPTHS="0.01 0.11"; MIN_TIME=0.2 ;;
"") ;;
*) echo "usage: $0 [--quick]" >&2; exit 2 ;;
esac
[ -x "$BIN" ] || { echo "error: $BIN not built (make studies builds it)" >&2; exit 1; }
rm -rf "$OUT"
mkdir -p "$OUT"
echo "shape,triangles,depth,pairs,kept_tris_filter_on,ns_filter_on,ns_filter_off" > "$OUT/scaling.csv"
for d in $DEPTHS; do
    for t in $TRIS; do
        "$BIN" rock "$t" "$d" 1 --min-time "$MIN_TIME" | tee -a "$OUT/scaling.csv"
    done
    for t in $HIGH_TRIS; do
        "$BIN" rock "$t" "$d" 1 --min-time "$MIN_TIME" --no-filter-off |
            tee -a "$OUT/scaling.csv"
    done
done
"$PY" "$HERE/plot.py" "$OUT"
