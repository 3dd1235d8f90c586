#!/bin/sh
# test_dashboard.sh - the web dashboard in headless Chromium (Debian's chromium, driven over the
# DevTools pipe by tests/clients/test_dashboard.py) against a real polydemd: submit, jobs list
# with progress to 100%, plots and 3D viewer rendered, the field error of an invalid scenario,
# all with a token.
# SHOTS=DIR keeps the screenshots. Prints "N passed, N failed".
# shellcheck source=tests/clients/lib.sh
. tests/clients/lib.sh

browser=""
for b in chromium chromium-browser google-chrome; do
    if command -v "$b" >/dev/null 2>&1; then browser=$b; break; fi
done
if [ -z "$browser" ]; then
    bad chromium "no chromium to drive (make deps installs Debian's chromium)"
elif [ ! -r /usr/share/javascript/three/three.min.js ]; then
    bad libjs-three "/usr/share/javascript/three/three.min.js is missing (make deps installs libjs-three)"
else
    # the daemon wants a token: the dashboard's token field, its Authorization header and the
    # event streams' ?token= are all on the way
    token="browser-test-token-0123456789"
    echo "$token tester" >"$tmp/tokens"
    POLYDEMD_ARGS="--tokens $tmp/tokens"
    start_daemon || { summary; exit 1; }
    quick_scenario "$tmp/quick.json"
    # with a turning wall below the pair: the viewer redraws it at every frame it shows (a
    # script error there fails no_script_errors)
    jq '.walls = [{"name": "turntable", "material": "rock", "angular_velocity": [0, 0, 300],
                   "box": {"min": [-0.05, -0.02, -0.04], "max": [0.05, 0.02, -0.03]}}]' \
        "$tmp/quick.json" >"$tmp/quick_wall.json" && mv "$tmp/quick_wall.json" "$tmp/quick.json"
    timeout 90 python3 -B tests/clients/test_dashboard.py "$URL" "$tmp/quick.json" "$token" \
        >"$tmp/browser.out" 2>&1
    rc=$?
    cat "$tmp/browser.out"
    passed=$((passed + $(grep -c '^ok ' "$tmp/browser.out")))
    failed=$((failed + $(grep -c '^FAIL ' "$tmp/browser.out")))
    if [ "$rc" -ne 0 ] && ! grep -q '^FAIL ' "$tmp/browser.out"; then
        bad browser_test "exit $rc without a failed check (timeout or crash)"
    fi
fi
summary
