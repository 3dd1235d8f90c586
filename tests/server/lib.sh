# lib.sh - shared by tests/server/test_*.sh (POSIX sh, sourced): ok/bad counters, a scratch
# directory, polydemd started on a free loopback port (port 0, read back from its log) and
# stopped on exit, and small HTTP and JSON helpers (curl, python3).
#
#   . tests/server/lib.sh
#   start_daemon DATA_DIR [ARGS...] || { summary; exit 1; }   # sets URL, PID, LOG
#   req GET /v1/jobs                 # HTTP status on stdout, body in $tmp/body, headers in $tmp/hdr
#   jget "$tmp/body" 'd["jobs"][0]["id"]'   # a Python expression over the decoded JSON
#   stop_daemon TERM                 # SIGTERM (or KILL), waits, checks the exit status
#   summary                          # "N passed, N failed"; exit status with it

BUILD=${BUILD:-build}
POLYDEMD_BIN=${POLYDEMD_BIN:-$BUILD/polydemd}
passed=0
failed=0
tmp=$(mktemp -d)
PID=""
URL=""
LOG=""
ndaemon=0

ok() { passed=$((passed + 1)); echo "ok   $1"; }
bad() { failed=$((failed + 1)); echo "FAIL $1: $2"; }
check() { # NAME EXPECTED ACTUAL
    if [ "$2" = "$3" ]; then ok "$1"; else bad "$1" "expected '$2', got '$3'"; fi
}

cleanup() {
    if [ -n "$PID" ] && kill -0 "$PID" 2>/dev/null; then
        kill -9 "$PID" 2>/dev/null
        wait "$PID" 2>/dev/null
    fi
    if [ -n "$jeval_pid" ]; then
        exec 7>&- 8<&-
        wait "$jeval_pid" 2>/dev/null
    fi
    rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# start_daemon DATA_DIR [ARGS...]: starts polydemd listening on 127.0.0.1:0 and waits (up to
# 30 s) for its "listening on" line; sets PID, URL and LOG (a new log per start).
start_daemon() {
    data=$1
    shift
    ndaemon=$((ndaemon + 1))
    LOG="$tmp/polydemd.$ndaemon.log"
    "$POLYDEMD_BIN" --listen 127.0.0.1:0 --data "$data" "$@" >"$LOG" 2>&1 &
    PID=$!
    i=0
    while [ $i -lt 300 ]; do
        port=$(sed -n 's/^polydemd: listening on http:\/\/127\.0\.0\.1:\([0-9]*\).*/\1/p' "$LOG")
        if [ -n "$port" ]; then
            URL="http://127.0.0.1:$port"
            return 0
        fi
        if ! kill -0 "$PID" 2>/dev/null; then
            bad "start_daemon_$ndaemon" "polydemd exited at start: $(tail -n 5 "$LOG")"
            PID=""
            return 1
        fi
        sleep 0.1
        i=$((i + 1))
    done
    bad "start_daemon_$ndaemon" "no 'listening on' line within 30 s: $(tail -n 5 "$LOG")"
    return 1
}

# stop_daemon [TERM|KILL]: with TERM, checks that the daemon exits 0 within 20 s (a sanitizer
# report makes the exit status non-zero and fails here).
stop_daemon() {
    sig=${1:-TERM}
    [ -n "$PID" ] || return 1
    kill -"$sig" "$PID" 2>/dev/null
    i=0
    while kill -0 "$PID" 2>/dev/null && [ $i -lt 200 ]; do
        sleep 0.1
        i=$((i + 1))
    done
    if kill -0 "$PID" 2>/dev/null; then
        bad "stop_daemon_$ndaemon" "still running 20 s after SIG$sig"
        kill -9 "$PID" 2>/dev/null
    fi
    wait "$PID"
    rc=$?
    PID=""
    if [ "$sig" = TERM ] && [ "$rc" -ne 0 ]; then
        bad "daemon_${ndaemon}_exit" "exit status $rc after SIGTERM: $(tail -n 20 "$LOG")"
        return 1
    fi
    return 0
}

# req METHOD PATH [CURL ARGS...]: prints the HTTP status; body in $tmp/body, headers in $tmp/hdr.
req() {
    m=$1
    p=$2
    shift 2
    rm -f "$tmp/body" "$tmp/hdr"
    touch "$tmp/body"
    curl -s -X "$m" -o "$tmp/body" -D "$tmp/hdr" -w '%{http_code}' --max-time 30 "$@" "$URL$p"
}

# jget FILE EXPR: evaluates a Python expression over the JSON in FILE (as d); prints the value
# (strings bare, the rest as JSON), or "ERROR: ..." when it cannot. One Python process
# (tests/server/jeval.py) answers every query of the script.
jget() {
    printf '%s\t%s\n' "$1" "$2" >&7
    IFS= read -r answer <&8
    printf '%s\n' "$answer"
}
mkfifo "$tmp/jeval.in" "$tmp/jeval.out"
python3 tests/server/jeval.py <"$tmp/jeval.in" >"$tmp/jeval.out" &
jeval_pid=$!
exec 7>"$tmp/jeval.in" 8<"$tmp/jeval.out"

# jstr KEY [FILE]: the first string value of "KEY" in compact JSON (default $tmp/body), without
# starting Python: for the daemon's one-line answers ("id", "status", an error's "code").
jstr() {
    grep -o "\"$1\":\"[^\"]*\"" "${2:-$tmp/body}" | head -n 1 | sed 's/^"[^"]*":"//; s/"$//'
}

# jall KEY [FILE]: every string value of "KEY", joined with commas.
jall() {
    grep -o "\"$1\":\"[^\"]*\"" "${2:-$tmp/body}" | sed 's/^"[^"]*":"//; s/"$//' | paste -sd, -
}

# header NAME: a response header from $tmp/hdr (case-insensitive), without the trailing CR.
header() {
    sed -n "s/^$1: *//Ip" "$tmp/hdr" | tr -d '\r' | head -n 1
}

# submit FILE [CURL ARGS...]: POSTs a scenario; prints the new job's id ("" on failure).
submit() {
    f=$1
    shift
    code=$(req POST /v1/jobs --data-binary @"$f" -H 'Content-Type: application/json' "$@")
    case "$code" in
    200 | 201) jstr id ;;
    *) echo "" ;;
    esac
}

# wait_status ID STATUS SECONDS: polls until the job has STATUS (or has ended otherwise);
# prints the last status seen.
wait_status() {
    n=$(awk -v s="$3" 'BEGIN { print int(s * 10) }')
    i=0
    st=""
    while [ $i -lt "$n" ]; do
        curl -s --max-time 5 -o "$tmp/wait.json" "$URL/v1/jobs/$1"
        st=$(jstr status "$tmp/wait.json")
        [ "$st" = "$2" ] && break
        case "$st" in succeeded | failed | cancelled) break ;; esac
        sleep 0.1
        i=$((i + 1))
    done
    echo "$st"
}

# quick_scenario OUT: examples/collision.json cut to 1000 steps and 11 frames (about a second).
quick_scenario() {
    python3 -c '
import json, sys
s = json.load(open("examples/collision.json"))
s["time"]["duration"] = 0.001
s["time"]["output_interval"] = 0.0001
s["name"] = sys.argv[2]
json.dump(s, open(sys.argv[1], "w"))
' "$1" "${2:-quick-collision}"
}

summary() {
    if [ "$failed" -ne 0 ] && [ -n "$LOG" ] && [ -s "$LOG" ]; then
        echo "-- polydemd log (last 15 lines):"
        tail -n 15 "$LOG"
    fi
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
}
