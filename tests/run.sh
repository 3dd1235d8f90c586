#!/bin/sh
# Runs every test program and CLI test script, then prints the suite's closing line
# "N passed, N failed". A program that crashes or exits non-zero without reporting a failure
# counts as one failure.
passed=0
failed=0
BUILD=${BUILD:-build}
export POLYDEM="$BUILD/polydem"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$(pwd)/tests/lsan.supp:print_suppressions=0}
for t in "$@" tests/cli/test_*.sh tests/server/test_*.sh tests/clients/test_*.sh; do
    [ -e "$t" ] || continue
    echo "== $t"
    out=$(mktemp)
    case "$t" in
    *.sh) sh "$t" >"$out" 2>&1 ;;
    *) "$t" >"$out" 2>&1 ;;
    esac
    rc=$?
    cat "$out"
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$out" | tail -n 1)
    rm -f "$out"
    if [ -z "$line" ]; then
        echo "FAIL $t: no summary line (exit $rc)"
        failed=$((failed + 1))
        continue
    fi
    p=${line%% passed*}
    f=${line#*, }
    f=${f%% failed}
    passed=$((passed + p))
    failed=$((failed + f))
    if [ "$rc" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "FAIL $t: exit $rc with no failed test (crash or sanitizer report)"
        failed=$((failed + 1))
    fi
done
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
