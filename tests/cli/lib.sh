# lib.sh - shared by the CLI test scripts (sourced, not run): a scratch folder removed on exit,
# the pass/fail counters with ok/bad, expect_fail for bad-input cases, and done_tests for the
# closing "N passed, N failed" line that tests/run.sh sums.
POLYDEM=${POLYDEM:-build/polydem}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0
ok() { passed=$((passed + 1)); echo "ok   $1"; }
bad() { failed=$((failed + 1)); echo "FAIL $1: $2"; }

# expect_fail NAME EXIT MESSAGE-FRAGMENT -- command...: the command exits with EXIT, says
# MESSAGE-FRAGMENT on stderr and prints nothing on stdout
expect_fail() {
    name=$1 code=$2 frag=$3
    shift 4
    "$@" >"$tmp/out" 2>"$tmp/err"
    rc=$?
    if [ "$rc" -ne "$code" ]; then bad "$name" "exit $rc, expected $code ($(cat "$tmp/err"))"
    elif ! grep -q -- "$frag" "$tmp/err"; then bad "$name" "stderr lacks '$frag': $(cat "$tmp/err")"
    elif [ -s "$tmp/out" ]; then bad "$name" "printed on stdout: $(cat "$tmp/out")"
    else ok "$name"; fi
}

done_tests() {
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
}
