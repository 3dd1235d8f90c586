#!/bin/sh
# studies/lib/run_cases.sh DIR: runs every scenario DIR/<case>.json listed in DIR/cases.json into
# DIR/<case>.h5 with build/polydem (first OpenCL device), printing the wall time of each.
set -eu
dir=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
POLYDEM=${POLYDEM:-$ROOT/build/polydem}
PY=${PYTHON:-/usr/bin/python3}
[ -x "$POLYDEM" ] || { echo "error: $POLYDEM not built (run make)" >&2; exit 1; }
cases=$("$PY" -c 'import json,sys; print(" ".join(c["case"] for c in json.load(open(sys.argv[1]))["cases"]))' "$dir/cases.json")
for c in $cases; do
    t0=$(date +%s.%N)
    if ! "$POLYDEM" run "$dir/$c.json" -o "$dir/$c.h5" --quiet; then
        echo "error: polydem run $dir/$c.json failed" >&2
        exit 1
    fi
    t1=$(date +%s.%N)
    awk -v c="$c" -v a="$t0" -v b="$t1" 'BEGIN { printf "  %-18s %7.1f s\n", c, b - a }'
done
