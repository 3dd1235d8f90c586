#!/bin/sh
# studies/irregular_convergence/run.sh [--quick]: thesis section 6.2. Two particles of one
# irregular shape (the built-in `rock`, seed 1, at 20, 80, 320 and 1280 triangles: the same
# underlying shape meshed at each resolution, volume-normalised) collide head-on (volume-equivalent
# R = 0.1 m, 5 m/s each, E = 21.5 and 464 MPa, nu = 0.25, normal elastic force only) in an
# ensemble of random orientations; output in build/studies/irregular_convergence/. Exits
# non-zero when a result leaves its band (check.py).
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
OUT=${STUDIES_OUT:-$ROOT/build/studies}/irregular_convergence
PAIRS=${PAIRS:-1000}
case ${1:-} in
--quick) PAIRS=${PAIRS_QUICK:-100} ;;
"") ;;
*) echo "usage: $0 [--quick]" >&2; exit 2 ;;
esac
rm -rf "$OUT"
mkdir -p "$OUT"
# 2.5 Hertz contact times after t0: rotating irregular pairs touch longer and more than once
"$PY" "$ROOT/studies/lib/pair_study.py" generate --study irregular_convergence --family rock \
    --rock-seed 1 --triangles 20,80,320,1280 --moduli 21.5e6,464e6 --pairs "$PAIRS" --seed 1 \
    --contacts 2.5 --out "$OUT"
sh "$ROOT/studies/lib/run_cases.sh" "$OUT"
"$PY" "$ROOT/studies/lib/pair_study.py" analyze --out "$OUT"
"$PY" "$HERE/check.py" "$OUT"
