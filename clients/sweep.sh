#!/bin/bash
# sweep.sh - a parameter sweep against polydemd with curl and jq.
#
#   clients/sweep.sh --server http://127.0.0.1:8080 examples/collision.json \
#       --set '/interactions/0/friction=0.2,0.3,0.4' --set '/materials/rock/youngs_modulus=1e6,2e7'
#
# Submits the full grid (every combination of the --set values), all jobs tagged with one sweep
# id, shows progress on stderr, waits for every job, and writes a CSV (--out FILE, default
# standard output): job_id, one column per --set pointer, status, final_kinetic_energy_J,
# peak_contacts, peak_wall_force_N. A job that fails or is refused gets its row and a message on
# stderr; the rest go on. Mesh files the scenario names by path are uploaded (POST /v1/meshes)
# and named by their id.
#
# Before anything is submitted: every pointer must fit the scenario, --out must be writable, and
# some grid point must pass the daemon's dry run (POST /v1/scenarios/validate). Interrupted
# (Ctrl-C, SIGTERM) or out of --timeout, it writes the CSV with the statuses so far and prints
# how to cancel the jobs still queued or running; it does not cancel them itself.
#
# Exit status: 0 every job succeeded; 1 some job failed, was refused or did not finish in time
# (the CSV is still written); 2 bad usage or input; 3 the server cannot be reached or answers
# something this script does not understand; 130 (143 for SIGTERM) interrupted.
set -euo pipefail

prog=sweep.sh
usage() {
    cat <<'EOF'
usage: clients/sweep.sh [options] SCENARIO.json

  --server URL        polydemd address (default $POLYDEM_SERVER or http://127.0.0.1:8080)
  --token TOKEN       bearer token (default $POLYDEM_TOKEN; none when empty)
  --set PTR=V1,V2,..  sweep the scenario value at JSON pointer PTR over the values; repeat for a
                      grid. Values are JSON (numbers, true, "text", [1,2]) or else plain text;
                      commas inside [..] or {..} do not split
  --out FILE          write the CSV to FILE (default standard output)
  --tag TAG           an extra tag for every job (repeatable); the sweep id is always one
  --priority N        job priority (default 0)
  --poll SECONDS      seconds between status polls (default 1)
  --timeout SECONDS   give up waiting after this long (default 0: wait as long as jobs run)
  -h, --help          this text

CSV columns: job_id, one per --set pointer, status, final_kinetic_energy_J, peak_contacts,
peak_wall_force_N (the largest |F| of any wall at any stats row; empty without walls).
EOF
}

die() { # CODE MESSAGE
    echo "$prog: $2" >&2
    exit "$1"
}

server=${POLYDEM_SERVER:-http://127.0.0.1:8080}
token=${POLYDEM_TOKEN:-}
out=""
priority=0
poll=1
timeout=0
scenario=""
sets=()
tags=()

need_value() { # OPTION REMAINING_ARGS
    [ "$2" -ge 2 ] || die 2 "option '$1' needs a value (see --help)"
}
while [ $# -gt 0 ]; do
    case "$1" in
    --server) need_value "$1" $#; server=$2; shift 2 ;;
    --server=*) server=${1#*=}; shift ;;
    --token) need_value "$1" $#; token=$2; shift 2 ;;
    --token=*) token=${1#*=}; shift ;;
    --set) need_value "$1" $#; sets+=("$2"); shift 2 ;;
    --set=*) sets+=("${1#*=}"); shift ;;
    --out | -o) need_value "$1" $#; out=$2; shift 2 ;;
    --out=*) out=${1#*=}; shift ;;
    --tag) need_value "$1" $#; tags+=("$2"); shift 2 ;;
    --tag=*) tags+=("${1#*=}"); shift ;;
    --priority) need_value "$1" $#; priority=$2; shift 2 ;;
    --priority=*) priority=${1#*=}; shift ;;
    --poll) need_value "$1" $#; poll=$2; shift 2 ;;
    --poll=*) poll=${1#*=}; shift ;;
    --timeout) need_value "$1" $#; timeout=$2; shift 2 ;;
    --timeout=*) timeout=${1#*=}; shift ;;
    -h | --help) usage; exit 0 ;;
    --) shift; [ $# -eq 1 ] || die 2 "expected one scenario file after '--'"; scenario=$1; shift ;;
    -*) die 2 "unknown option '$1' (see --help)" ;;
    *)
        [ -z "$scenario" ] || die 2 "more than one scenario file: '$scenario' and '$1'"
        scenario=$1
        shift
        ;;
    esac
done

for tool in curl jq; do
    command -v "$tool" >/dev/null 2>&1 || die 2 "'$tool' is not installed (Debian: apt-get install $tool)"
done
[ -n "$scenario" ] || die 2 "no scenario file given (see --help)"
[ -r "$scenario" ] || die 2 "cannot read scenario file '$scenario'"
[ ${#sets[@]} -gt 0 ] || die 2 "no --set given: nothing to sweep (see --help)"
[[ "$priority" =~ ^-?[0-9]+$ ]] || die 2 "--priority '$priority': expected an integer"
if ! [[ "$poll" =~ ^([0-9]+\.?[0-9]*|\.[0-9]+)$ ]] || ! awk -v p="$poll" 'BEGIN { exit !(p > 0) }'; then
    die 2 "--poll '$poll': expected seconds > 0, e.g. 1 or 0.5"
fi
case "$timeout" in '' | *[!0-9]*) die 2 "--timeout '$timeout': expected whole seconds" ;; esac
case "$server" in http://?* | https://?*) server=${server%/} ;; *) die 2 "--server '$server': expected http://HOST:PORT or https://..." ;; esac
# The CSV is written at the end: make sure it can be before a whole sweep runs for nothing.
if [ -n "$out" ]; then
    out_dir=$(dirname -- "$out")
    if [ -d "$out" ] || [ "${out%/}" != "$out" ]; then
        die 2 "--out '$out': is a directory; give a file name"
    elif [ ! -d "$out_dir" ]; then
        die 2 "--out '$out': no such directory '$out_dir'"
    elif [ -e "$out" ] && [ ! -w "$out" ]; then
        die 2 "--out '$out': not writable"
    elif [ ! -e "$out" ] && [ ! -w "$out_dir" ]; then
        die 2 "--out '$out': cannot create files in '$out_dir'"
    fi
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if ! jq -e 'type == "object"' "$scenario" >/dev/null 2>"$tmp/err"; then
    die 2 "$scenario: not a JSON object: $(head -c 300 "$tmp/err")"
fi

# jq helpers: split a --set value list at top-level commas, JSON-decode each value when it is
# JSON, turn a JSON pointer into tokens, and set a value at a pointer (containers on the way must
# exist; the last object key may be new).
# shellcheck disable=SC2016 # jq's own variables
jq_lib='
def split_top:
  reduce (split("") | .[]) as $c ({parts: [], cur: "", depth: 0, q: false, esc: false};
    if .q then
      (if .esc then .esc = false elif $c == "\\" then .esc = true elif $c == "\"" then .q = false else . end)
      | .cur += $c
    elif $c == "\"" then .q = true | .cur += $c
    elif $c == "[" or $c == "{" then .depth += 1 | .cur += $c
    elif $c == "]" or $c == "}" then .depth -= 1 | .cur += $c
    elif $c == "," and .depth == 0 then .parts += [.cur] | .cur = ""
    else .cur += $c end)
  | .parts + [.cur];
def value_of: . as $s | (try fromjson catch $s) as $v | if ($s | test("^\\s*$")) then error("empty value") else $v end;
def ptr_tokens: if . == "" then [] else (.[1:] | split("/") | map(gsub("~1"; "/") | gsub("~0"; "~"))) end;
def ptr_set($toks; $v):
  if ($toks | length) == 0 then $v
  else $toks[0] as $t
    | if type == "array" then
        (if $t | test("^(0|[1-9][0-9]*)$") then $t | tonumber else error("\($t) is not an array index") end) as $i
        | if $i < 0 or $i >= length then error("index \($i) is outside the array of \(length)")
          else .[$i] |= ptr_set($toks[1:]; $v) end
      elif type == "object" then
        if ($toks | length) > 1 and (has($t) | not) then error("no member \"\($t)\"")
        else .[$t] |= ptr_set($toks[1:]; $v) end
      else error("\(type) has no member \"\($t)\"") end
  end;
'

jq_msg() { sed -n '1{s/^jq: error (at [^)]*): //; p}' "$tmp/err" | head -c 200; }

# Parse every --set into {pointer, tokens, values} and check it applies to the scenario.
printf '[]' >"$tmp/sets.json"
form="expected POINTER=V1,V2,... with POINTER starting with '/', e.g. /interactions/0/friction=0.2,0.3"
for s in "${sets[@]}"; do
    case "$s" in
    /*=?*) ;;
    /*=) die 2 "--set '$s': no values after '='; $form" ;;
    /*) die 2 "--set '$s': no '=' and values; $form" ;;
    *) die 2 "--set '$s': $form" ;;
    esac
    ptr=${s%%=*}
    vals=${s#*=}
    if ! jq -n --arg p "$ptr" --arg v "$vals" "$jq_lib"'
        ($v | split_top) as $parts
        | {pointer: $p, tokens: ($p | ptr_tokens), values: ($parts | map(value_of)),
           texts: ($parts | map(sub("^\\s+"; "") | sub("\\s+$"; "")))}' \
        >"$tmp/one.json" 2>"$tmp/err"; then
        die 2 "--set '$s': bad value list ($(jq_msg)); expected POINTER=V1,V2,..."
    fi
    if ! jq --slurpfile one "$tmp/one.json" "$jq_lib"'ptr_set($one[0].tokens; $one[0].values[0])' \
        "$scenario" >/dev/null 2>"$tmp/err"; then
        die 2 "--set '$s': '$ptr' does not fit $scenario: $(jq_msg)"
    fi
    jq --slurpfile one "$tmp/one.json" '. + $one' "$tmp/sets.json" >"$tmp/sets2.json"
    mv "$tmp/sets2.json" "$tmp/sets.json"
done

# The grid: every combination of value indices, the first --set varying slowest.
jq -c 'reduce .[] as $s ([[]]; [.[] as $row | range($s.values | length) | $row + [.]])' \
    "$tmp/sets.json" >"$tmp/grid.json"
njobs=$(jq length "$tmp/grid.json")

sweep_id="sweep-$(date +%Y%m%d-%H%M%S)-$(od -An -N3 -tx1 /dev/urandom | tr -d ' \n')"
tags_json=$(printf '%s\n' "$sweep_id" ${tags[@]+"${tags[@]}"} | jq -R . | jq -sc .)

# HTTP: curl with timeouts everywhere; the token goes in a header file, not on the command line.
hdr="$tmp/auth"
: >"$hdr"
chmod 600 "$hdr"
[ -z "$token" ] || printf 'Authorization: Bearer %s\n' "$token" >"$hdr"
http() { # METHOD PATH [BODY_FILE [HEADER]] -> body in $tmp/body, prints the HTTP status
    local args=(-sS -o "$tmp/body" -D "$tmp/headers" -w '%{http_code}' --connect-timeout 5 --max-time 60
        -H @"$hdr" -X "$1")
    if [ $# -ge 3 ]; then
        local ctype='Content-Type: application/json' extra=${4:-}
        case "$extra" in Content-Type:*) ctype=$extra extra="" ;; esac
        args+=(-H "$ctype" --data-binary @"$3" --retry 2 --retry-delay 1)
        if [ -n "$extra" ]; then args+=(-H "$extra"); fi
    fi
    local code
    code=$(curl "${args[@]}" "$server$2" 2>"$tmp/curlerr") || code=000
    echo "$code"
}
http_error() { # a one-line description of the last error answer
    local msg
    msg=$(jq -r 'if type == "object" and (.error | type) == "object"
        then .error.message + ([.error.details[]? | "; " + .path + ": " + .message] | join(""))
        else tostring end' "$tmp/body" 2>/dev/null) || msg=$(head -c 300 "$tmp/body" 2>/dev/null || true)
    printf '%s' "${msg:-no explanation in the answer}" | tr '\n' ' ' | head -c 500
}

code=$(http GET /healthz)
case "$code" in
000) die 3 "cannot reach $server: $(head -c 300 "$tmp/curlerr")" ;;
200) ;;
503) echo "$prog: warning: $server reports it is not healthy (503): $(http_error)" >&2 ;;
*) die 3 "$server does not look like polydemd: GET /healthz answered $code" ;;
esac

# Grid point I's submission in $tmp/job.json: the values put in, then the mesh files named by
# path (shapes and walls, relative to the scenario) uploaded through /v1/meshes and named by the
# returned id, since the daemon cannot read this machine's files. Each file goes up once; the
# values go in first, so a mesh path can be swept.
base_dir=$(dirname "$scenario")
base_name=$(jq -r '.name // "scenario"' "$scenario")
declare -A mesh_ids=()
build_job() { # I
    local where key file path
    jq --slurpfile sets "$tmp/sets.json" --slurpfile grid "$tmp/grid.json" --arg name "${base_name:0:52}-$1" \
        --argjson tags "$tags_json" --argjson prio "$priority" --argjson i "$1" "$jq_lib"'
        . as $sc
        | reduce range($sets[0] | length) as $k ($sc; ptr_set($sets[0][$k].tokens; $sets[0][$k].values[$grid[0][$i][$k]]))
        | .name = $name
        | {scenario: ., tags: $tags, priority: $prio}' "$scenario" >"$tmp/job.json"
    jq -r '.scenario | [(.shapes // {} | to_entries[] | ["shapes", .key, .value.mesh?]),
            (.walls // [] | to_entries[] | ["walls", (.key | tostring), .value.mesh?])]
           | .[] | select(.[2] | type == "string" and (startswith("sha256:") | not)) | @tsv' \
        "$tmp/job.json" >"$tmp/meshes.tsv"
    while IFS=$'\t' read -r where key file; do
        [ -n "$where" ] || continue
        case "$file" in /*) path=$file ;; *) path="$base_dir/$file" ;; esac
        if [ -z "${mesh_ids[$path]:-}" ]; then
            [ -r "$path" ] || die 2 "$where/$key: cannot read mesh file '$path'"
            code=$(http POST /v1/meshes "$path" "Content-Type: application/octet-stream")
            case "$code" in
            200 | 201) ;;
            401 | 403) die 3 "the server refused the token ($code): $(http_error)" ;;
            000) die 3 "cannot reach $server: $(head -c 300 "$tmp/curlerr")" ;;
            *) die 2 "$where/$key: mesh '$path' refused ($code): $(http_error)" ;;
            esac
            mesh_ids[$path]=$(jq -r '.id' "$tmp/body")
            echo "$prog: uploaded $path as ${mesh_ids[$path]}" >&2
        fi
        jq --arg w "$where" --arg k "$key" --arg id "${mesh_ids[$path]}" \
            'if $w == "shapes" then .scenario.shapes[$k].mesh = $id else .scenario.walls[$k | tonumber].mesh = $id end' \
            "$tmp/job.json" >"$tmp/job2.json" && mv "$tmp/job2.json" "$tmp/job.json"
    done <"$tmp/meshes.tsv"
}
point_text() { # I -> "POINTER=VALUE ..." of grid point I
    jq -r --argjson i "$1" --slurpfile g "$tmp/grid.json" \
        '[to_entries[] | .value.pointer + "=" + .value.texts[$g[0][$i][.key]]] | join(" ")' "$tmp/sets.json"
}

# A pointer that fits but names a member the contract does not know (a misspelling of the last
# one) would only give a grid of refusals: unless some grid point passes the daemon's dry run,
# stop before submitting anything. Usually the first one does; a grid whose first point alone
# has a bad value goes on, and that point is refused like any other.
first_err=""
valid=0
for ((i = 0; i < njobs; i++)); do
    build_job "$i"
    jq .scenario "$tmp/job.json" >"$tmp/point.json"
    code=$(http POST /v1/scenarios/validate "$tmp/point.json")
    case "$code" in
    200) valid=1; break ;;
    422) [ -n "$first_err" ] || first_err="$(point_text "$i"): $(http_error)" ;;
    401 | 403) die 3 "the server refused the token ($code): $(http_error)" ;;
    000) die 3 "cannot reach $server: $(head -c 300 "$tmp/curlerr")" ;;
    *) die 3 "POST /v1/scenarios/validate answered $code: $(http_error)" ;;
    esac
done
[ "$valid" = 1 ] || die 2 "no grid point is a valid scenario, nothing submitted; the first, $first_err"

# The CSV, the rows so far: summary numbers from /stats of every succeeded job; a grid point not
# yet submitted when the sweep was interrupted has status "unsubmitted". Then the jobs still
# queued or running, and how to cancel them. Ends the script: EXIT_STATUS, or 0/1 from the rows.
ids=()
states=()
timed_out=0
finish() { # [EXIT_STATUS]
    # a signal's trap may run this inside `IFS=<separator> read`, whose IFS would still hold
    local IFS=$' \t\n'
    local csv="$tmp/out.csv" i st bad=0 left=() auth="" jid jname jst
    # Interrupted while submitting: the server may have made the job whose answer the sweep never
    # read (the signal struck between the two). Its grid point would read "unsubmitted" and the
    # job would run on, missing from the cancel command; find it by its tag and name instead.
    local unsubmitted=0
    for ((i = 0; i < njobs; i++)); do [ -n "${states[i]:-}" ] || unsubmitted=1; done
    if [ "$unsubmitted" = 1 ] && [ "$(http GET "/v1/jobs?tag=$sweep_id&limit=1000")" = 200 ]; then
        while IFS=$'\x1f' read -r jid jname jst; do
            for ((i = 0; i < njobs; i++)); do
                if [ -z "${states[i]:-}" ] && [ "$jname" = "${base_name:0:52}-$i" ]; then
                    ids[i]=$jid
                    states[i]=$jst
                fi
            done
        done < <(jq -r '.jobs[]? | [.id, .name, .status] | map(tostring) | join("\u001f")' "$tmp/body" 2>/dev/null)
    fi
    jq -r '(["job_id"] + map(.pointer) + ["status", "final_kinetic_energy_J", "peak_contacts", "peak_wall_force_N"])
        | map(tostring | if test("[,\"\n]") then "\"" + gsub("\""; "\"\"") + "\"" else . end) | join(",")' \
        "$tmp/sets.json" >"$csv"
    for ((i = 0; i < njobs; i++)); do
        st=${states[i]:-unsubmitted}
        printf '{}' >"$tmp/summary.json"
        if [ "$st" = succeeded ]; then
            code=$(http GET "/v1/jobs/${ids[i]}/stats")
            if [ "$code" = 200 ] && jq '.stats // .
                | if type == "array" then {kinetic_energy: map(.kinetic_energy), contacts: map(.contacts),
                      wall_force: (reduce .[] as $r ({}; reduce ($r.wall_force // {} | to_entries[]) as $w (.;
                          .[$w.key] += [$w.value])))} else . end
                | {ke: (.kinetic_energy // [] | last), contacts: (.contacts // [] | max),
                   wall: ([.wall_force // {} | .[] | .[] | map(. * .) | add | sqrt] | max)}' \
                "$tmp/body" >"$tmp/summary.json" 2>"$tmp/err"; then
                :
            else
                echo "$prog: job ${ids[i]}: no usable /stats ($code): $(head -c 200 "$tmp/body")" >&2
                printf '{}' >"$tmp/summary.json"
            fi
        fi
        case "$st" in
        succeeded) ;;
        queued | running) left+=("${ids[i]}"); bad=1 ;;
        *) bad=1 ;;
        esac
        jq -r --arg id "${ids[i]:-}" --arg st "$st" --argjson i "$i" --slurpfile grid "$tmp/grid.json" \
            --slurpfile sets "$tmp/sets.json" '
            [$id] + [range($sets[0] | length) as $k | $sets[0][$k].texts[$grid[0][$i][$k]]]
            + [$st, .ke, .contacts, .wall]
            | map(if . == null then "" else tostring end
                  | if test("[,\"\n]") then "\"" + gsub("\""; "\"\"") + "\"" else . end) | join(",")' \
            "$tmp/summary.json" >>"$csv"
    done
    if [ -n "$out" ]; then
        cp "$csv" "$out" 2>"$tmp/err" || die 2 "--out '$out': cannot write: $(cat "$tmp/err")"
        echo "$prog: wrote $out ($njobs rows)" >&2
    else
        cat "$csv"
    fi
    if [ ${#left[@]} -gt 0 ]; then
        if [ -n "$token" ]; then
            # shellcheck disable=SC2016 # printed for the user's shell
            if [ "$token" = "${POLYDEM_TOKEN:-}" ]; then auth=' -H "Authorization: Bearer $POLYDEM_TOKEN"'
            else auth=" -H 'Authorization: Bearer TOKEN'"; fi
        fi
        echo "$prog: $sweep_id: ${#left[@]} jobs still queued or running; they go on (the dashboard shows them at $server/index.html?tag=$sweep_id). To cancel them:" >&2
        # joined with spaces whatever IFS holds (the status reads set it to a separator)
        ids_text=$(printf '%s ' "${left[@]}")
        echo "  for id in ${ids_text% }; do curl -sS -X POST$auth $server/v1/jobs/\$id/cancel; echo; done" >&2
    fi
    [ "$timed_out" -eq 0 ] || bad=1
    exit "${1:-$bad}"
}
# shellcheck disable=SC2317 # called by the traps below
on_signal() { # EXIT_STATUS
    trap - INT TERM
    echo "$prog: $sweep_id: interrupted; writing the CSV with the statuses so far" >&2
    finish "$1"
}
trap 'on_signal 130' INT
trap 'on_signal 143' TERM

echo "$prog: $sweep_id: submitting $njobs jobs to $server" >&2
for ((i = 0; i < njobs; i++)); do
    build_job "$i"
    while :; do
        code=$(http POST /v1/jobs "$tmp/job.json" "Idempotency-Key: $sweep_id-$i")
        case "$code" in
        429)
            wait_s=$(grep -i '^retry-after:' "$tmp/headers" 2>/dev/null | tr -dc 0-9 || true)
            echo "$prog: job $i: the server's queue is full; retrying in ${wait_s:-5} s" >&2
            sleep "${wait_s:-5}" || true
            ;;
        *) break ;;
        esac
    done
    case "$code" in
    200 | 201)
        id=$(jq -r '.id // empty' "$tmp/body" 2>/dev/null || true)
        [ -n "$id" ] || die 3 "POST /v1/jobs answered $code without a job id: $(head -c 300 "$tmp/body")"
        ids[i]=$id
        states[i]=queued
        ;;
    401 | 403) die 3 "the server refused the token ($code): $(http_error)" ;;
    000) die 3 "lost contact with $server: $(head -c 300 "$tmp/curlerr")" ;;
    *)
        echo "$prog: job $i ($(point_text "$i")) refused ($code): $(http_error)" >&2
        ids[i]=""
        states[i]=rejected
        ;;
    esac
done

# Wait for every job, printing a status line on stderr when it changes.
start=$(date +%s)
last_counts=""
last_print=0
last_ok=$start
while :; do
    running=0 queued=0 done_n=0 failed=0 active=""
    for ((i = 0; i < njobs; i++)); do
        case "${states[i]}" in
        succeeded) done_n=$((done_n + 1)); continue ;;
        failed | cancelled | rejected | deleted) failed=$((failed + 1)); continue ;;
        esac
        code=$(http GET "/v1/jobs/${ids[i]}")
        if [ "$code" = 404 ]; then
            echo "$prog: job ${ids[i]} is gone (deleted by someone?)" >&2
            states[i]=deleted
            failed=$((failed + 1))
            continue
        fi
        if [ "$code" != 200 ]; then
            if [ $(($(date +%s) - last_ok)) -gt 30 ]; then
                die 3 "lost contact with $server for 30 s (last answer $code): $(head -c 200 "$tmp/curlerr")"
            fi
            if [ "${states[i]}" = running ]; then running=$((running + 1)); else queued=$((queued + 1)); fi
            continue
        fi
        last_ok=$(date +%s)
        # fields joined by US (0x1f), not tabs: read collapses runs of whitespace separators, so
        # an empty ETA would shift the error text out of its place
        IFS=$'\x1f' read -r st frac eta err < <(jq -r '[.status, (.progress.fraction // 0),
            (.progress.eta_seconds // ""), (.error // "" | tostring | gsub("[\n\u001f]"; " "))]
            | map(tostring) | join("\u001f")' "$tmp/body")
        states[i]=$st
        case "$st" in
        succeeded) done_n=$((done_n + 1)) ;;
        failed | cancelled)
            failed=$((failed + 1))
            echo "$prog: job ${ids[i]} $st${err:+: $err}" >&2
            ;;
        running)
            running=$((running + 1))
            active="${active:+$active, }$(awk -v f="$frac" -v e="$eta" 'BEGIN {
                printf "%.0f%%", 100 * f; if (e != "") printf " ETA %.0f s", e }')"
            ;;
        *) queued=$((queued + 1)) ;;
        esac
    done
    line="$sweep_id: $done_n/$njobs succeeded, $failed failed or refused, $running running${active:+ ($active)}, $queued queued"
    counts="$done_n $failed $running $queued"
    if [ "$counts" != "$last_counts" ] || [ $(($(date +%s) - last_print)) -ge 10 ]; then
        echo "$prog: $line" >&2
        last_counts=$counts
        last_print=$(date +%s)
    fi
    [ $((running + queued)) -gt 0 ] || break
    if [ "$timeout" -gt 0 ] && [ $(($(date +%s) - start)) -ge "$timeout" ]; then
        echo "$prog: gave up waiting after $timeout s; $((running + queued)) jobs unfinished" >&2
        timed_out=1
        break
    fi
    sleep "$poll" || true
done
finish
