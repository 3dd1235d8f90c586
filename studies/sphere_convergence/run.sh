#!/bin/sh
# studies/sphere_convergence/run.sh [--quick]: thesis section 6.1. Two volume-normalised
# icospheres collide head-on (R = 0.1 m, 5 m/s each, E = 1 and 21.5 MPa, nu = 0.25, normal
# elastic force only) in an ensemble of random orientations; output in build/studies/
# sphere_convergence/. Exits non-zero when a result leaves its band (check.py).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
OUT=${STUDIES_OUT:-$ROOT/build/studies}/sphere_convergence
PAIRS=${PAIRS:-1000}
case ${1:-} in
--quick) PAIRS=${PAIRS_QUICK:-100} ;;
"") ;;
*) echo "usage: $0 [--quick]" >&2; exit 2 ;;
esac
rm -rf "$OUT"
mkdir -p "$OUT"
"$PY" "$ROOT/studies/lib/pair_study.py" generate --study sphere_convergence --family icosphere \
    --triangles 20,80,320,1280 --moduli 1e6,21.5e6 --pairs "$PAIRS" --seed 1 --out "$OUT"
sh "$ROOT/studies/lib/run_cases.sh" "$OUT"
"$PY" "$ROOT/studies/lib/pair_study.py" analyze --out "$OUT" --analytic
"$PY" "$HERE/check.py" "$OUT/summary.json"
