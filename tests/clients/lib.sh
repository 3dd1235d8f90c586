# lib.sh - shared by tests/clients/test_*.sh (POSIX sh, sourced): ok/bad counters, a scratch
# directory, and a real polydemd on a free loopback port, stopped on exit.
#
#   . tests/clients/lib.sh
#   start_daemon || { summary; exit 1; }   # sets $URL; $POLYDEMD_ARGS adds daemon options
#   ...
#   summary                                # prints "N passed, N failed"; exit status with it

BUILD=${BUILD:-build}
POLYDEMD=${POLYDEMD:-$BUILD/polydemd}
passed=0
failed=0
tmp=$(mktemp -d)
daemon_pid=""

ok() { passed=$((passed + 1)); echo "ok   $1"; }
bad() { failed=$((failed + 1)); echo "FAIL $1: $2"; }
check() { # NAME EXPECTED ACTUAL
    if [ "$2" = "$3" ]; then ok "$1"; else bad "$1" "expected '$2', got '$3'"; fi
}

cleanup() {
    if [ -n "$daemon_pid" ]; then
        kill "$daemon_pid" 2>/dev/null
        # SIGTERM lets a running job reach a safe point; give it a few seconds, then insist.
        i=0
        while kill -0 "$daemon_pid" 2>/dev/null && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
        kill -9 "$daemon_pid" 2>/dev/null
        wait "$daemon_pid" 2>/dev/null
    fi
    rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

free_port() {
    python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# Starts $POLYDEMD with a fresh data directory; waits up to 60 s for /healthz (the daemon
# compiles its kernels and runs the device self-test first).
start_daemon() {
    if [ ! -x "$POLYDEMD" ]; then
        bad daemon "$POLYDEMD is not built (the daemon, issue 4; make builds it once server/ lands)"
        return 1
    fi
    port=$(free_port)
    URL="http://127.0.0.1:$port"
    # shellcheck disable=SC2086 # POLYDEMD_ARGS is a list of options
    "$POLYDEMD" --listen "127.0.0.1:$port" --data "$tmp/data" ${POLYDEMD_ARGS:-} \
        >"$tmp/polydemd.log" 2>&1 &
    daemon_pid=$!
    i=0
    while [ $i -lt 600 ]; do
        if ! kill -0 "$daemon_pid" 2>/dev/null; then
            bad daemon "polydemd exited at start: $(tail -n 5 "$tmp/polydemd.log")"
            daemon_pid=""
            return 1
        fi
        code=$(curl -s -o /dev/null -w '%{http_code}' --max-time 2 "$URL/healthz" 2>/dev/null)
        if [ "$code" = 200 ]; then
            ok "daemon answers /healthz on port $port"
            return 0
        fi
        sleep 0.1
        i=$((i + 1))
    done
    bad daemon "no healthy /healthz within 60 s (last $code): $(tail -n 5 "$tmp/polydemd.log")"
    return 1
}

# examples/collision.json cut to 1000 steps and 11 frames, for tests that need jobs to finish fast.
quick_scenario() { # OUT_FILE
    jq '.time.duration = 0.001 | .time.output_interval = 0.0001 | .name = "quick-collision"' \
        examples/collision.json >"$1"
}

# A unit cube as a Wavefront OBJ (outward triangles), for the clients' mesh uploads.
cube_obj() { # OUT_FILE
    cat >"$1" <<'OBJ'
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
OBJ
}

api() { # PATH [CURL_ARGS...]: curl $URL$PATH, with $POLYDEM_TOKEN when it is set
    api_path=$1
    shift
    if [ -n "${POLYDEM_TOKEN:-}" ]; then
        curl -s --max-time 10 -H "Authorization: Bearer $POLYDEM_TOKEN" "$@" "$URL$api_path"
    else
        curl -s --max-time 10 "$@" "$URL$api_path"
    fi
}

# tests/server/long_job.json submitted and running (so that jobs after it wait in the queue);
# prints its id. Cancel it when done.
long_job_running() {
    jq '{scenario: ., tags: ["blocker"]}' tests/server/long_job.json >"$tmp/long_job_body.json"
    lj=$(api /v1/jobs --data-binary @"$tmp/long_job_body.json" | jq -r .id)
    i=0
    while [ "$(api "/v1/jobs/$lj" | jq -r .status)" != running ] && [ $i -lt 300 ]; do
        sleep 0.1
        i=$((i + 1))
    done
    echo "$lj"
}

# Waits up to 30 s for a sweep's id on its stderr (either client's "ID: submitting" line) and
# N jobs carrying it as a tag; prints the id.
sweep_started() { # STDERR_FILE N
    i=0
    while [ $i -lt 300 ]; do
        sid=$(sed -n 's/^[a-z_.]*: \(sweep-[0-9]*-[0-9]*-[0-9a-f]*\): submitting.*/\1/p' "$1" | head -n 1)
        if [ -n "$sid" ] && [ "$(api "/v1/jobs?tag=$sid" | jq '.jobs | length')" = "$2" ]; then
            echo "$sid"
            return 0
        fi
        sleep 0.1
        i=$((i + 1))
    done
    return 1
}

# interrupted_sweep NAME CMD...: runs a two-point sweep command in the background (its CSV in
# $tmp/int.csv, its stderr in $tmp/int.err), sends it SIGTERM once both jobs are submitted, and
# checks NAME_exit_status (143) and NAME_rows (both points still queued); sets sid to its id.
interrupted_sweep() {
    name=$1
    shift
    # (--foreground: a plain timeout passes the signal on to its whole process group as well,
    # and a second signal ends a sweep at once, without its CSV)
    timeout --foreground 60 "$@" --out "$tmp/int.csv" 2>"$tmp/int.err" &
    int_pid=$!
    sid=$(sweep_started "$tmp/int.err" 2)
    kill -TERM "$int_pid"
    wait "$int_pid"
    check "${name}_exit_status" 143 "$?"
    check "${name}_rows" "queued queued" \
        "$(tail -n +2 "$tmp/int.csv" 2>/dev/null | cut -d, -f3 | tr '\n' ' ' | sed 's/ $//')"
}

# held_answers_proxy: a blocker job ten times the usual length (what is submitted next stays
# queued behind it) and a proxy to the daemon that holds every answer 2 s (cutproxy.py DELAY);
# sets blocker, proxy_pid and proxy_url.
held_answers_proxy() {
    jq '{scenario: (.time.duration *= 10), tags: ["blocker"]}' tests/server/long_job.json >"$tmp/blocker.json"
    blocker=$(api /v1/jobs --data-binary @"$tmp/blocker.json" | jq -r .id)
    rm -f "$tmp/race.port"
    python3 -B tests/clients/cutproxy.py "$port" 0 2 >"$tmp/race.port" 2>/dev/null &
    proxy_pid=$!
    i=0
    while [ ! -s "$tmp/race.port" ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
    proxy_url="http://127.0.0.1:$(cat "$tmp/race.port")"
}

# in_flight_sweep CMD...: runs a one-point sweep command (through $proxy_url) in the background,
# its CSV in $tmp/race.csv and its stderr in $tmp/race.err, sends it SIGTERM as soon as the server
# has the job (its answer still held by the proxy), and stops the proxy; sets rc (the sweep's exit
# status) and rid (the job).
in_flight_sweep() {
    timeout --foreground 60 "$@" --out "$tmp/race.csv" 2>"$tmp/race.err" &
    race_pid=$!
    race_sid=$(sweep_started "$tmp/race.err" 1)
    kill -TERM "$race_pid"
    wait "$race_pid"
    rc=$?
    kill "$proxy_pid" 2>/dev/null
    rid=$(api "/v1/jobs?tag=$race_sid" | jq -r '.jobs[0].id')
}

summary() {
    if [ "$failed" -ne 0 ] && [ -s "$tmp/polydemd.log" ]; then
        echo "-- polydemd log (last 15 lines):"
        tail -n 15 "$tmp/polydemd.log"
    fi
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
}
