#!/bin/sh
# test_api.sh - polydemd's HTTP contract without running a job (the daemon is started on a device
# that does not exist, so every job stays queued): 400/413/422/404/405/409/429 answers with their
# JSON error codes and field paths, idempotent submits, listing with filters and pages, cancel
# and delete of queued jobs, SSE of a job cancelled while a client listens, the dry run, mesh
# uploads, static files with Range and ETag and no way out of their directories, metrics,
# tokens and ownership, command-line and config refusals, SIGTERM and a restart on the same data.
# Prints "N passed, N failed".
. tests/server/lib.sh

quick_scenario "$tmp/quick.json"
cat >"$tmp/limits.conf" <<'CONF'
# limits small enough to reach in a test
max_body_bytes = 65536
max_queued_jobs = 8
max_particles = 100
keepalive_seconds = 1
CONF

start_daemon "$tmp/data" --device 99 --config "$tmp/limits.conf" || { summary; exit 1; }

# ---- health and device: the device did not open, the database did
code=$(req GET /healthz)
check healthz_503_without_device 503 "$code"
check healthz_reports_device "unavailable database=ok" \
    "$(jget "$tmp/body" 'd["device"] + " database=" + d["database"]')"
code=$(req GET /v1/device)
check device_route 200 "$code"
check device_state_unavailable unavailable "$(jstr state)"
code=$(req GET '/v1/device?selftest=1')
check device_selftest_busy "409 device_busy" "$code $(jstr code)"
code=$(req GET '/v1/device?selftest=maybe')
check device_bad_param 400 "$code"

# ---- bad submissions
code=$(req POST /v1/jobs)
check empty_body_400 "400 empty_body" "$code $(jstr code)"
code=$(req POST /v1/jobs --data-binary '{"name": "x", "time": ')
check unparseable_400 "400 invalid_json" "$code $(jstr code)"
python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
s["interactions"][0]["friction"] = -1
s["particles"][0]["list"][0]["size"] = 0
json.dump(s, open(sys.argv[2], "w"))
json.dump({"scenario": s, "priority": "high", "tags": ["ok", 7]}, open(sys.argv[3], "w"))
s = json.load(open(sys.argv[1]))
s["shapes"]["r"] = {"mesh": "/etc/passwd"}
json.dump(s, open(sys.argv[4], "w"))
' "$tmp/quick.json" "$tmp/invalid.json" "$tmp/invalid_wrapped.json" "$tmp/pathmesh.json"
code=$(req POST /v1/jobs --data-binary @"$tmp/invalid.json")
check invalid_422 "422 invalid_scenario" "$code $(jstr code)"
check invalid_details_paths '["/interactions/0/friction", "/particles/0/list/0/size"]' \
    "$(jget "$tmp/body" 'sorted(x["path"] for x in d["error"]["details"])')"
check invalid_details_messages true \
    "$(jget "$tmp/body" 'all(x["message"] for x in d["error"]["details"])')"
code=$(req POST /v1/jobs --data-binary @"$tmp/invalid_wrapped.json")
check wrapped_invalid_paths \
    '422 ["/priority", "/scenario/interactions/0/friction", "/scenario/particles/0/list/0/size", "/tags/1"]' \
    "$code $(jget "$tmp/body" 'sorted(x["path"] for x in d["error"]["details"])')"
code=$(req POST /v1/jobs --data-binary @"$tmp/pathmesh.json")
check mesh_paths_refused "422 /shapes/r/mesh" "$code $(jstr path)"
code=$(req POST /v1/jobs --data-binary '{"time": 1}')
check missing_members_422 "422 invalid_scenario /time" "$code $(jstr code) $(jstr path)"
head -c 3000 /dev/urandom >"$tmp/random.bin"
code=$(req POST /v1/jobs --data-binary @"$tmp/random.bin")
check random_bytes_4xx "4 json" "$(echo "$code" | cut -c1) $(jstr code >/dev/null && head -c 9 "$tmp/body" | grep -q '{"error"' && echo json)"
code=$(req POST /v1/jobs --data-binary '[1, 2]')
check array_body_422 "422 invalid_scenario" "$code $(jstr code)"
# JSON that is not an object is a scenario's problem at "", not unparseable (it was 400
# invalid_json "'[' or '{' expected" for all but arrays)
for v in null 42 string true; do
    [ "$v" = string ] && v='"text"'
    code=$(req POST /v1/jobs --data-binary "$v")
    check "scalar_body_422_$(echo "$v" | tr -d '"')" "422 invalid_scenario at ''" \
        "$code $(jstr code) at '$(jget "$tmp/body" 'd["error"]["details"][0]["path"]')'"
done

# ---- a job: 201, Location, the job's fields
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json")
check submit_201 201 "$code"
id=$(jstr id)
check submit_location "/v1/jobs/$id" "$(header Location)"
check submit_fields "queued quick-collision [] 0 None None" \
    "$(jget "$tmp/body" '" ".join(str(x) for x in [d["status"], d["name"], d["tags"], d["priority"], d["started_at"], d["progress"]])')"
check submit_created_at_iso8601 true \
    "$(jget "$tmp/body" '__import__("re").fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z", d["created_at"]) is not None')"
code=$(req GET "/v1/jobs/$id")
check get_job "200 $id" "$code $(jstr id)"
code=$(req GET /v1/jobs/0123456789abcdef)
check unknown_job_404 "404 job_not_found" "$code $(jstr code)"
code=$(req GET "/v1/jobs/$id/scenario")
check scenario_as_submitted true "$(python3 -c '
import json, sys
print(str(json.load(open(sys.argv[1])) == json.load(open(sys.argv[2]))).lower())' "$tmp/body" "$tmp/quick.json")"
for sub in result result.xmf stats frames frames/0 shapes; do
    code=$(req GET "/v1/jobs/$id/$sub")
    check "queued_${sub}_409" "409 result_not_ready" "$code $(jstr code)"
done
code=$(req GET "/v1/jobs/$id/frames/first")
check bad_frame_400 400 "$code"

# ---- idempotency
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H 'Idempotency-Key: sweep-7-a')
idem=$(jstr id)
check idempotent_first_201 201 "$code"
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H 'Idempotency-Key: sweep-7-a')
check idempotent_retry_200_same_job "200 $idem" "$code $(jstr id)"
code=$(req POST /v1/jobs --data-binary @"$tmp/invalid.json" -H 'Idempotency-Key: sweep-7-a')
check idempotent_other_body_422 "422 idempotency_key_reused" "$code $(jstr code)"

# ---- the wrapper form: priority and tags
python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
json.dump({"scenario": s, "priority": 5, "tags": ["sweep-7", "fine"]}, open(sys.argv[2], "w"))
' "$tmp/quick.json" "$tmp/wrapped.json"
code=$(req POST /v1/jobs --data-binary @"$tmp/wrapped.json")
tagged=$(jstr id)
check wrapped_submit "201 5 ['sweep-7', 'fine']" "$code $(jget "$tmp/body" 'str(d["priority"]) + " " + str(d["tags"])')"

# ---- listing: newest first, filters, pages, bad parameters
code=$(req GET /v1/jobs)
check list_newest_first "200 $tagged,$idem,$id" "$code $(jall id)"
code=$(req GET '/v1/jobs?tag=sweep-7')
check list_by_tag "$tagged" "$(jall id)"
code=$(req GET '/v1/jobs?status=queued&limit=2')
check list_page_1 "200 $tagged,$idem next=$idem" "$code $(jall id) next=$(jstr next)"
code=$(req GET "/v1/jobs?status=queued&limit=2&after=$idem")
check list_page_2 "200 $id next=" "$code $(jall id) next=$(jstr next)"
code=$(req GET '/v1/jobs?status=succeeded')
check list_by_status_empty '200 {"jobs":[],"next":null}' "$code $(cat "$tmp/body")"
for q in status=%ff status=bogus limit=0 limit=1001 limit=abc after=0123456789abcdef colour=red; do
    code=$(req GET "/v1/jobs?$q")
    check "list_bad_param_$q" "400 invalid_parameter" "$code $(jstr code)"
done
# a parameter without a value, or given twice, was taken as absent or as its first value (a
# list of 50 jobs for "?limit", "?limit=1&limit=abc" answered as limit=1)
for q in limit status tag after 'limit=1&limit=abc' 'status=queued&status=failed'; do
    code=$(req GET "/v1/jobs?$q")
    check "list_bad_param_$(echo "$q" | tr '&=' '+-')" "400 invalid_parameter" "$code $(jstr code)"
done
code=$(req GET '/v1/device?selftest')
check device_selftest_without_value_400 "400 invalid_parameter" "$code $(jstr code)"

# ---- SSE: a client listening to a queued job sees its status, then its cancellation, then
#      the end of the stream
curl -s -N --max-time 20 "$URL/v1/jobs/$tagged/events" >"$tmp/sse.txt" 2>&1 &
sse_pid=$!
sleep 0.5
code=$(req POST "/v1/jobs/$tagged/cancel")
check cancel_queued "200 cancelled" "$code $(jstr status)"
wait "$sse_pid"
check sse_stream_ends_after_final_status 0 "$?"
check sse_status_sequence "queued cancelled" "$(sed -n 's/^data: .*"status":"\([a-z]*\)".*/\1/p' "$tmp/sse.txt" | tr '\n' ' ' | sed 's/ $//')"
check sse_event_names "status status" "$(sed -n 's/^event: //p' "$tmp/sse.txt" | tr '\n' ' ' | sed 's/ $//')"
code=$(req GET "/v1/jobs/$tagged/events")
check sse_of_ended_job_closes "200 text/event-stream" "$code $(header Content-Type)"
code=$(req GET /v1/jobs/0123456789abcdef/events)
check sse_unknown_job_404 404 "$code"

# ---- keep-alive comments (every second here) reach a waiting client; a departed client's
#      stream is noticed and freed
curl -s -N --max-time 1.6 "$URL/v1/jobs/$id/events" >"$tmp/ka.txt" 2>&1
check sse_keepalive true "$(grep -q '^: keepalive$' "$tmp/ka.txt" && echo true)"
i=0
while [ $i -lt 50 ]; do
    req GET /metrics >/dev/null
    grep -q '^polydem_sse_streams 0$' "$tmp/body" && break
    sleep 0.1
    i=$((i + 1))
done
check sse_departed_freed "polydem_sse_streams 0" "$(grep '^polydem_sse_streams ' "$tmp/body")"
echo "   (freed after $i tenths of a second)"

# ---- cancel and delete
code=$(req POST "/v1/jobs/$tagged/cancel")
check cancel_twice_409 "409 job_finished" "$code $(jstr code)"
code=$(req GET "/v1/jobs/$tagged/result")
check cancelled_result_409 409 "$code"
code=$(req DELETE "/v1/jobs/$id")
check delete_queued_409 "409 job_active" "$code $(jstr code)"
code=$(req DELETE "/v1/jobs/$tagged")
check delete_cancelled_204 204 "$code"
code=$(req GET "/v1/jobs/$tagged")
check deleted_is_gone 404 "$code"
code=$(req DELETE "/v1/jobs/$tagged")
check delete_twice_404 404 "$code"
code=$(req POST /v1/jobs/0123456789abcdef/cancel)
check cancel_unknown_404 404 "$code"

# ---- routes and methods
code=$(req PUT /v1/jobs)
check put_jobs_405 "405 POST, GET, HEAD" "$code $(header Allow)"
code=$(req GET /v1/scenarios/validate)
check get_validate_405 405 "$code"
code=$(req GET /v1/nothing)
check unknown_route_404 "404 not_found" "$code $(jstr code)"

# ---- the dry run
code=$(req POST /v1/scenarios/validate --data-binary @examples/collision.json)
check validate_summary "200 True 2 20000" "$code $(jget "$tmp/body" '" ".join(str(x) for x in [d["valid"], d["summary"]["particles"], d["summary"]["steps"]])')"
check validate_dt_estimates true "$(jget "$tmp/body" 'str(0 < d["summary"]["dt_stable"] <= d["summary"]["dt_rayleigh"] and d["summary"]["memory_bytes"] > 0).lower()')"
check validate_contact_resolution true "$(jget "$tmp/body" 'str(0 <= d["summary"]["contact_resolution_m"] < 1e-8).lower()')"
python3 -c '
import json, sys
s = json.load(open("examples/collision.json"))
s["gravity"] = [1e308, 0, 0]
json.dump(s, open(sys.argv[1], "w"))' "$tmp/huge.json"
code=$(req POST /v1/scenarios/validate --data-binary @"$tmp/huge.json")
check validate_huge_numbers_not_500 true "$([ "$code" -lt 500 ] && echo true)"
code=$(req POST /v1/scenarios/validate --data-binary @"$tmp/invalid.json")
check validate_invalid_422 "422 2" "$code $(jget "$tmp/body" 'len(d["error"]["details"])')"
code=$(req POST /v1/jobs --data-binary @tests/server/long_job.json)
check particle_limit_422 "422 limit_exceeded /particles" \
    "$code $(jstr code) $(jstr path)"

# ---- body limits: Content-Length decides at once, a chunked body at its end
head -c 70000 /dev/zero | tr '\0' ' ' >"$tmp/big.json"
code=$(req POST /v1/jobs --data-binary @"$tmp/big.json")
check body_too_large_413 "413 body_too_large" "$code $(jstr code)"
code=$(req POST /v1/jobs --data-binary @"$tmp/big.json" -H 'Transfer-Encoding: chunked')
check chunked_too_large_413 "413 body_too_large" "$code $(jstr code)"

# ---- mesh uploads
python3 -c '
import sys
v = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
q = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
def stl(quads):
    out = ["solid cube"]
    for a, b, c, d in quads:
        for t in ((a, c, b), (a, d, c)):
            out.append(" facet normal 0 0 0\n  outer loop")
            for i in t:
                out.append("   vertex %g %g %g" % tuple(0.02 * x for x in v[i]))
            out.append("  endloop\n endfacet")
    out.append("endsolid cube")
    return "\n".join(out) + "\n"
open(sys.argv[1], "w").write(stl(q))
open(sys.argv[2], "w").write(stl(q[:-1]))
' "$tmp/cube.stl" "$tmp/open.stl"
code=$(req POST /v1/meshes --data-binary @"$tmp/cube.stl" -H 'Content-Type: model/stl')
mesh=$(jstr id)
check mesh_upload_201 "201 12 true" "$code $(jget "$tmp/body" 'str(d["triangles"]) + " " + str(abs(d["volume"] - 8e-6) < 1e-12).lower()')"
check mesh_id_is_sha256 "$mesh" "sha256:$(sha256sum "$tmp/cube.stl" | cut -d' ' -f1)"
code=$(req POST /v1/meshes --data-binary @"$tmp/cube.stl")
check mesh_upload_again_200 "200 $mesh" "$code $(jstr id)"
code=$(req POST /v1/meshes --data-binary @"$tmp/open.stl")
check open_mesh_422 "422 invalid_mesh" "$code $(jstr code)"
code=$(req POST /v1/meshes)
check empty_mesh_400 400 "$code"
python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
s["shapes"]["r"] = {"mesh": sys.argv[2]}
json.dump(s, open(sys.argv[3], "w"))
s["shapes"]["r"] = {"mesh": "sha256:" + "0" * 64}
json.dump(s, open(sys.argv[4], "w"))
' "$tmp/quick.json" "$mesh" "$tmp/meshref.json" "$tmp/meshmissing.json"
code=$(req POST /v1/scenarios/validate --data-binary @"$tmp/meshref.json")
check scenario_with_uploaded_mesh 200 "$code"
code=$(req POST /v1/scenarios/validate --data-binary @"$tmp/meshmissing.json")
check scenario_with_unknown_mesh "422 /shapes/r/mesh" "$code $(jstr path)"

# ---- static files: content types, ETag, Range, and no way out of their directories
code=$(req GET /)
check dashboard_index "200 text/html; charset=utf-8" "$code $(header Content-Type)"
code=$(req GET /examples/collision.json)
check examples_served "200 application/json" "$code $(header Content-Type)"
if [ -r /usr/share/javascript/three/three.min.js ]; then
    size=$(wc -c </usr/share/javascript/three/three.min.js)
    code=$(req GET /vendor/three/three.min.js)
    etag=$(header ETag)
    check three_js_served "200 text/javascript; charset=utf-8 $size bytes" "$code $(header Content-Type) $(wc -c <"$tmp/body") bytes"
    code=$(req GET /vendor/three/three.min.js -H "If-None-Match: $etag")
    check etag_304 "304 0" "$code $(wc -c <"$tmp/body")"
    code=$(req GET /vendor/three/three.min.js -H 'Range: bytes=10-19')
    check range_206 "206 bytes 10-19/$size 10" "$code $(header Content-Range) $(wc -c <"$tmp/body")"
    check range_bytes "$(head -c 20 /usr/share/javascript/three/three.min.js | tail -c 10)" "$(cat "$tmp/body")"
    code=$(req GET /vendor/three/three.min.js -H 'Range: bytes=-5')
    check range_suffix "206 bytes $((size - 5))-$((size - 1))/$size" "$code $(header Content-Range)"
    code=$(req GET /vendor/three/three.min.js -H "Range: bytes=$size-")
    check range_416 "416 bytes */$size" "$code $(header Content-Range)"
    code=$(req GET /vendor/three/three.min.js -H 'Range: bytes=0-1' -H 'If-Range: "stale"')
    check if_range_stale_full "200 $size" "$code $(wc -c <"$tmp/body")"
else
    bad three_js_served "/usr/share/javascript/three/three.min.js missing (make deps installs libjs-three)"
fi
for p in /vendor/three/../../../../etc/passwd /vendor/three/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd \
    /static/..%2f..%2f..%2fMakefile /..%2f..%2fMakefile /examples/../Makefile /%2e%2e/Makefile; do
    code=$(req GET "$p" --path-as-is)
    check "no_traversal_$p" 404 "$code"
done
code=$(req POST /index.html)
check static_post_405 405 "$code"
sub=""
for d in /usr/share/javascript/three/*/; do [ -d "$d" ] && sub=$(basename "$d") && break; done
if [ -n "$sub" ]; then
    code=$(req GET "/vendor/three/$sub")
    check static_directory_404 "404 not_found" "$code $(jstr code)"
else bad static_directory_404 "no directory under /usr/share/javascript/three to ask for"; fi
code=$(req "$(printf 'GE\303')" /healthz)
check bad_utf8_method_405_json "405 method_not_allowed" "$code $(jstr code)"

# ---- metrics
code=$(req GET /metrics)
check metrics_text "200 text/plain; version=0.0.4; charset=utf-8" "$code $(header Content-Type)"
check metrics_jobs_queued 'polydem_jobs{status="queued"} 2' "$(grep '^polydem_jobs{status="queued"}' "$tmp/body")"
check metrics_counts_requests true "$(grep -q '^polydem_http_requests_total{code="422"} [1-9]' "$tmp/body" && echo true)"

# ---- the queue limit (8 queued): 429 with Retry-After; a retry of a known key still answers
i=0
code=201
while [ "$code" = 201 ] && [ $i -lt 10 ]; do
    code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json")
    i=$((i + 1))
done
check queue_full_429 "429 queue_full 30" "$code $(jstr code) $(header Retry-After)"
check queue_full_after_6_more 6 "$((i - 1))"
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H 'Idempotency-Key: sweep-7-a')
check idempotent_retry_when_full "200 $idem" "$code $(jstr id)"

# ---- a second daemon on the same data is refused; SIGTERM; a restart finds the jobs
"$POLYDEMD_BIN" --listen 127.0.0.1:0 --data "$tmp/data" --device 99 >"$tmp/second.log" 2>&1
check second_daemon_refused "1 locked" "$? $(grep -o 'locked' "$tmp/second.log")"
# its address taken (the first daemon's): exit 1 naming the address, not MHD's "port 0"
"$POLYDEMD_BIN" --listen "127.0.0.1:$port" --data "$tmp/other" --device 99 >"$tmp/taken.log" 2>&1
check address_taken "1 127.0.0.1:$port 0" \
    "$? $(grep -o "cannot listen on '[^']*'" "$tmp/taken.log" | cut -d"'" -f2) $(grep -c 'port 0' "$tmp/taken.log")"
# event streams open at SIGTERM end cleanly (curl exit 0), not cut off (18) by the stop
sse_pids=""
for k in 1 2 3 4 5 6; do
    (curl -s -N --max-time 20 -o /dev/null "$URL/v1/events"; echo "$?" >"$tmp/sse_rc.$k") &
    sse_pids="$sse_pids $!"
done
sleep 1
stop_daemon TERM && ok sigterm_exit_0
for p in $sse_pids; do wait "$p"; done
check sse_streams_end_cleanly_at_sigterm "0 0 0 0 0 0" "$(cat "$tmp"/sse_rc.* | tr '\n' ' ' | sed 's/ $//')"
start_daemon "$tmp/data" --device 99 || { summary; exit 1; }
code=$(req GET '/v1/jobs?status=queued&limit=1000')
check restart_keeps_jobs "200 8" "$code $(jall id | tr , '\n' | wc -l)"
stop_daemon TERM

# ---- the queue limit holds for submissions side by side: 12 at once, each slow enough to parse
#      (20 000 listed particles) that the HTTP threads all passed the limit's check before any
#      was inserted (max_queued_jobs = 2 queued 4 and more)
python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
s["particles"] = [{"shape": "ball", "material": "rock", "list": [
    {"position": [0.02 * (i % 50), 0.02 * (i // 50 % 50), 0.02 * (i // 2500)], "size": 0.01}
    for i in range(20000)]}]
json.dump(s, open(sys.argv[2], "w"))' "$tmp/quick.json" "$tmp/many.json"
printf 'max_queued_jobs = 2\n' >"$tmp/q2.conf"
start_daemon "$tmp/qdata" --device 99 --config "$tmp/q2.conf" || { summary; exit 1; }
pids=""
for k in 1 2 3 4 5 6 7 8 9 10 11 12; do
    curl -s -o /dev/null -w '%{http_code}\n' --max-time 60 --data-binary @"$tmp/many.json" \
        "$URL/v1/jobs" >"$tmp/par.$k" &
    pids="$pids $!"
done
for p in $pids; do wait "$p"; done
code=$(req GET '/v1/jobs?status=queued&limit=1000')
check queue_limit_side_by_side "2 2 10" "$(jall id | tr , '\n' | grep -c .) $(cat "$tmp"/par.* | grep -c 201) $(cat "$tmp"/par.* | grep -c 429)"
stop_daemon TERM

# ---- tokens: 401 without, jobs belong to their token's name, ?token= for event streams
printf '# test tokens\nalice-0123456789abcdef alice\nbob-0123456789abcdef   bob\n' >"$tmp/tokens"
start_daemon "$tmp/tdata" --device 99 --tokens "$tmp/tokens" || { summary; exit 1; }
code=$(req GET /v1/jobs)
check no_token_401 "401 unauthorized Bearer realm=\"polydemd\"" "$code $(jstr code) $(header WWW-Authenticate)"
code=$(req GET /v1/jobs -H 'Authorization: Bearer nobody-0123456789abcdef')
check wrong_token_401 401 "$code"
code=$(req GET /healthz)
check healthz_without_token 503 "$code"
A='Authorization: Bearer alice-0123456789abcdef'
B='Authorization: Bearer bob-0123456789abcdef'
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H "$A")
aid=$(jstr id)
check alice_submits 201 "$code"
code=$(req GET "/v1/jobs/$aid" -H "$B")
check bob_sees_404 404 "$code"
code=$(req POST "/v1/jobs/$aid/cancel" -H "$B")
check bob_cannot_cancel 404 "$code"
code=$(req GET /v1/jobs -H "$B")
check bob_lists_nothing "200 " "$code $(jall id)"
code=$(req GET /v1/jobs -H "$A")
check alice_lists_hers "200 $aid" "$code $(jall id)"
code=$(curl -s -o "$tmp/ev.txt" -w '%{http_code}' --max-time 1 "$URL/v1/jobs/$aid/events?token=alice-0123456789abcdef")
check events_token_query "200" "$(head -c 3 "$tmp/ev.txt" >/dev/null; echo "$code" | sed 's/000/200/')"
check events_token_query_data queued "$(sed -n 's/^data: .*"status":"\([a-z]*\)".*/\1/p' "$tmp/ev.txt" | head -n 1)"
code=$(req GET "/v1/jobs/$aid/events?token=bob-0123456789abcdef")
check events_other_token_404 404 "$code"
# the token is needed however the path is spelt: "//v1/..." and "/%2Fv1/..." reach the same
# routes (they used to skip the check, and with no owner saw and deleted everyone's jobs)
for p in //v1/jobs /%2Fv1/jobs "///v1/jobs/$aid" "//v1/jobs/$aid/scenario" //v1/events; do
    code=$(req GET "$p" --path-as-is --max-time 2)
    check "spelt_path_needs_token_$p" 401 "$code"
done
code=$(req DELETE "//v1/jobs/$aid" --path-as-is)
check spelt_path_delete_needs_token 401 "$code"
code=$(req POST //v1/jobs --path-as-is --data-binary @"$tmp/quick.json")
check spelt_path_submit_needs_token 401 "$code"
# a web page of another site cannot submit through the user's browser (its Origin differs);
# the dashboard's own requests carry this server's host and pass
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H "$A" -H 'Origin: http://evil.example' -H 'Content-Type: text/plain')
check foreign_origin_403 "403 cross_origin" "$code $(jstr code)"
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H "$A" -H "Origin: $URL")
aid2=$(jstr id)
check same_origin_201 201 "$code"
code=$(req POST /v1/jobs --data-binary @"$tmp/quick.json" -H "$A")
aid3=$(jstr id)
# a page cursor stays valid when its job is deleted (list, delete the page, fetch the next)
for j in "$aid" "$aid2" "$aid3"; do req POST "/v1/jobs/$j/cancel" -H "$A" >/dev/null; done
code=$(req GET '/v1/jobs?status=cancelled&limit=1' -H "$A")
check cursor_page_1 "200 $aid3 next=$aid3" "$code $(jall id) next=$(jstr next)"
code=$(req DELETE "/v1/jobs/$aid3" -H "$A")
check cursor_job_deleted 204 "$code"
code=$(req GET "/v1/jobs?status=cancelled&limit=1&after=$aid3" -H "$A")
check cursor_after_deleted_job "200 $aid2" "$code $(jall id)"
code=$(req GET "/v1/jobs?status=cancelled&after=$aid3" -H "$B")
check cursor_of_another_owner_400 400 "$code"
code=$(req DELETE "/v1/jobs/$aid3" -H "$A")
check deleted_job_is_gone_404 404 "$code"
stop_daemon TERM

# ---- the example config of deploy/ is one this daemon reads (flags override its paths)
start_daemon "$tmp/cdata" --config deploy/polydemd.conf.example --tokens "$tmp/tokens" --device 99 &&
    check example_config_starts 401 "$(req GET /v1/jobs)" && stop_daemon TERM

# ---- refusals at start: exit 2 with a message
"$POLYDEMD_BIN" --listen 0.0.0.0:0 --data "$tmp/x" --device 99 >"$tmp/r1.log" 2>&1
check non_loopback_without_tokens "1 refusing" "$? $(grep -o refusing "$tmp/r1.log")"
"$POLYDEMD_BIN" --bogus >"$tmp/r2.log" 2>&1
check unknown_flag_exit_2 "2 unknown argument" "$? $(grep -o 'unknown argument' "$tmp/r2.log")"
printf 'listen = 127.0.0.1:0\nmax_queued_jobs = many\n' >"$tmp/bad.conf"
"$POLYDEMD_BIN" --config "$tmp/bad.conf" >"$tmp/r3.log" 2>&1
check bad_config_exit_2 "2 bad.conf:2" "$? $(grep -o 'bad.conf:2' "$tmp/r3.log")"
"$POLYDEMD_BIN" --help >"$tmp/r4.log" 2>&1
check help_exit_0 "0 usage" "$? $(grep -o '^usage' "$tmp/r4.log")"

summary
