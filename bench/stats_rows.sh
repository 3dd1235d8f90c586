#!/bin/sh
# bench/stats_rows.sh [PARTICLES]: what one stats row costs a run (time.stats_interval). The
# gravity packing's falling lattice (studies/gravity_packing, 1e5 particles by default) runs
# 1000 steps twice: with a row every 10 steps (101 rows) and with rows at its start and end only
# (2), each twice, the faster of the two kept (the first run also builds the kernels). The
# difference per row is the row's cost: the kinetic energy, contact count and wall force sums on
# the device (kernels/stats.cl; until 2026-12-01 the state and pairs were read back and summed on
# the host), and the step it times stage by stage. Prints the runs' times and the cost per row
# (ms); a scenario whose stats_interval is k steps pays cost/k per step on top of its steps.
# POLYDEM and PYTHON (with numpy) name the programs; build/polydem and /usr/bin/python3 otherwise.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
N=${1:-100000}
POLYDEM=${POLYDEM:-$ROOT/build/polydem}
PY=${PYTHON:-/usr/bin/python3}
case $N in '' | *[!0-9]*)
    echo "usage: $0 [PARTICLES]" >&2
    exit 2
    ;;
esac
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$PY" "$ROOT/studies/gravity_packing/packing.py" generate --particles "$N" --out "$T" \
    --allow-unstable-dt >/dev/null
STEPS=1000
"$PY" - "$T" $STEPS <<'EOF'
import json, sys
d, steps = sys.argv[1], int(sys.argv[2])
s = json.load(open(d + "/packing.json"))
dt = s["time"]["dt"]
for name, every in (("rare", steps), ("every", 10)):
    s["time"].update(duration=steps * dt, output_interval=steps * dt, stats_interval=every * dt)
    json.dump(s, open("%s/%s.json" % (d, name), "w"))
EOF
now() { date +%s.%N; }
echo "# stats rows: $N falling Schönhardt prisms, $STEPS steps, $("$POLYDEM" devices | head -n 1)"
for name in rare every rare every; do
    t0=$(now)
    "$POLYDEM" run "$T/$name.json" -o "$T/$name.h5" --quiet
    t1=$(now)
    echo "$name $t0 $t1"
done | awk -v steps=$STEPS '
    { t = $3 - $2; if (!($1 in best) || t < best[$1]) best[$1] = t }
    END {
        # the faster of two runs each (the first also builds the kernels)
        printf "2 rows:   %.2f s for the run, setup included\n", best["rare"]
        printf "101 rows: %.2f s\n", best["every"]
        printf "one stats row: %.2f ms\n", 1000 * (best["every"] - best["rare"]) / 99
    }'
