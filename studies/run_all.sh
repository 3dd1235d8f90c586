#!/bin/sh
# studies/run_all.sh [--quick] STUDY...: runs each studies/STUDY/run.sh, goes on after a failure,
# prints one line per study with its wall time and exits 1 when any failed.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
quick=
if [ "${1:-}" = --quick ]; then
    quick=--quick
    shift
fi
[ $# -gt 0 ] || { echo "usage: $0 [--quick] STUDY..." >&2; exit 2; }
failed=0
report=
for s in "$@"; do
    echo "== $s $quick"
    t0=$(date +%s)
    if sh "$HERE/$s/run.sh" $quick; then res=ok; else res=FAILED; failed=$((failed + 1)); fi
    report="$report$(printf '%-24s %-6s %5d s' "$s" "$res" $(($(date +%s) - t0)))
"
done
echo "== studies${quick:+ (quick)}: results in build/studies/"
printf '%s' "$report"
[ "$failed" -eq 0 ]
