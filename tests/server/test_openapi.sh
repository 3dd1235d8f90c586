#!/bin/sh
# test_openapi.sh - schemas/openapi.yaml and the daemon in step: the file parses as OpenAPI 3,
# every $ref resolves, it describes every route `polydemd --routes` lists and no other, and the
# daemon's job, list, device, health and error objects carry exactly the fields it documents,
# and real answers of every route (statuses, content types, headers, bodies) are ones it
# documents (tests/server/openapi_check.py). Prints "N passed, N failed".
. tests/server/lib.sh

"$POLYDEMD_BIN" --routes >"$tmp/routes.txt"
check routes_listed 0 "$?"
python3 - schemas/openapi.yaml "$tmp/routes.txt" >"$tmp/spec.out" 2>&1 <<'PY'
import re, sys
try:
    import yaml
except ImportError:
    print("FAIL yaml: python3-yaml is missing (make deps installs it)")
    sys.exit(0)
spec = yaml.safe_load(open(sys.argv[1]))
def out(name, good, why=""):
    print(("ok   %s" % name) if good else ("FAIL %s: %s" % (name, why)))
out("openapi_3", str(spec.get("openapi", "")).startswith("3."), spec.get("openapi"))
served = set()
for line in open(sys.argv[2]):
    m, p = line.split()
    served.add((m.lower(), p))
documented = set()
for p, item in spec["paths"].items():
    for m in ("get", "put", "post", "delete", "patch", "head", "options"):
        if m in item:
            documented.add((m, p))
missing = sorted(served - documented)
extra = sorted(documented - served)
out("every_route_documented", not missing, missing)
out("no_undocumented_route", not extra, extra)
refs = []
def walk(x):
    if isinstance(x, dict):
        for k, v in x.items():
            if k == "$ref":
                refs.append(v)
            walk(v)
    elif isinstance(x, list):
        for v in x:
            walk(v)
walk(spec)
def resolve(ref):
    node = spec
    for part in ref.lstrip("#/").split("/"):
        node = node[part]
    return node
bad = []
for r in refs:
    try:
        resolve(r)
    except (KeyError, TypeError):
        bad.append(r)
out("refs_resolve", not bad and len(refs) > 20, bad or len(refs))
ops = [(m, p, spec["paths"][p][m]) for m, p in documented]
out("operations_have_responses", all(o.get("responses") for _, _, o in ops))
ids = [o.get("operationId") for _, _, o in ops]
out("operation_ids_unique", None not in ids and len(set(ids)) == len(ids), ids)
job = spec["components"]["schemas"]["Job"]
contract = ["id", "status", "name", "tags", "created_at", "started_at", "finished_at", "error", "progress"]
out("job_contract_fields", all(f in job["required"] for f in contract), job["required"])
prog = spec["components"]["schemas"]["Progress"]["properties"]
pc = ["step", "steps_total", "sim_time", "fraction", "steps_per_second", "eta_seconds", "particles",
      "contacts", "kinetic_energy"]
out("progress_contract_fields", all(f in prog for f in pc), list(prog))
out("progress_units_described", all("description" in prog[f] for f in ["sim_time", "eta_seconds", "kinetic_energy", "steps_per_second"]))
print("done")
PY
cat "$tmp/spec.out"
grep -q '^done$' "$tmp/spec.out" || bad spec_checks "the check script stopped early"
passed=$((passed + $(grep -c '^ok ' "$tmp/spec.out")))
failed=$((failed + $(grep -c '^FAIL ' "$tmp/spec.out")))

# the live objects against the documented ones
quick_scenario "$tmp/quick.json"
start_daemon "$tmp/data" --device 99 || { summary; exit 1; }
id=$(submit "$tmp/quick.json")
req GET "/v1/jobs/$id" >/dev/null && cp "$tmp/body" "$tmp/job.json"
req GET /v1/jobs >/dev/null && cp "$tmp/body" "$tmp/list.json"
req GET /v1/device >/dev/null && cp "$tmp/body" "$tmp/device.json"
req GET /healthz >/dev/null && cp "$tmp/body" "$tmp/health.json"
req POST /v1/jobs --data-binary '{"time": 1}' >/dev/null && cp "$tmp/body" "$tmp/error.json"
req POST /v1/scenarios/validate --data-binary @"$tmp/quick.json" >/dev/null && cp "$tmp/body" "$tmp/valid.json"
stop_daemon TERM
python3 - schemas/openapi.yaml "$tmp" >"$tmp/live.out" 2>&1 <<'PY'
import json, sys, yaml
spec = yaml.safe_load(open(sys.argv[1]))
S = spec["components"]["schemas"]
d = sys.argv[2]
def load(n):
    return json.load(open(d + "/" + n))
def out(name, good, why=""):
    print(("ok   %s" % name) if good else ("FAIL %s: %s" % (name, why)))
job = load("job.json")
out("live_job_fields", sorted(job) == sorted(S["Job"]["properties"]), sorted(job))
lst = load("list.json")
out("live_list_fields", sorted(lst) == sorted(S["JobList"]["properties"]), sorted(lst))
dev = load("device.json")
out("live_device_fields", set(dev) <= set(S["Device"]["properties"]) and set(S["Device"]["required"]) <= set(dev), sorted(dev))
out("live_device_selftest_fields", set(dev["selftest"]) <= set(S["Device"]["properties"]["selftest"]["properties"]), sorted(dev["selftest"]))
h = load("health.json")
out("live_health_fields", set(h) <= set(S["Health"]["properties"]), sorted(h))
e = load("error.json")["error"]
out("live_error_fields", set(e) <= set(S["Error"]["properties"]["error"]["properties"]) and e["details"] and all(set(x) == {"path", "message"} for x in e["details"]), e)
v = load("valid.json")
out("live_validation_fields", set(v["summary"]) == set(S["Validation"]["properties"]["summary"]["properties"]), sorted(v["summary"]))
print("done")
PY
cat "$tmp/live.out"
grep -q '^done$' "$tmp/live.out" || bad live_checks "the check script stopped early"
passed=$((passed + $(grep -c '^ok ' "$tmp/live.out")))
failed=$((failed + $(grep -c '^FAIL ' "$tmp/live.out")))

# ---- real answers of every route against the operation's documented statuses, content types,
#      headers and schemas (tests/server/openapi_check.py): a daemon without a device (jobs stay
#      queued), then one with the device for results, a running job and its cancellation
mkdir -p "$tmp/cases"
: >"$tmp/cases.txt"
# rec NAME METHOD TEMPLATE PATH [CURL ARGS...]: records one answer for the checker
rec() {
    n=$1 m=$2 t=$3 p=$4
    shift 4
    c=$(req "$m" "$p" "$@")
    cp "$tmp/hdr" "$tmp/cases/$n.h"
    cp "$tmp/body" "$tmp/cases/$n.b"
    echo "$n $m $t $c $tmp/cases/$n.h $tmp/cases/$n.b" >>"$tmp/cases.txt"
}
printf 'solid t\n' >"$tmp/bad.stl"
start_daemon "$tmp/data2" --device 99 || { summary; exit 1; }
q=$(submit "$tmp/quick.json")
rec healthz_503 GET /healthz /healthz
rec metrics GET /metrics /metrics
rec device GET /v1/device /v1/device
rec device_400 GET /v1/device '/v1/device?selftest=maybe'
rec device_409 GET /v1/device '/v1/device?selftest=1'
rec events_400 GET /v1/events '/v1/events?x=1'
rec create_201 POST /v1/jobs /v1/jobs --data-binary @"$tmp/quick.json" -H 'Idempotency-Key: k1'
rec create_200 POST /v1/jobs /v1/jobs --data-binary @"$tmp/quick.json" -H 'Idempotency-Key: k1'
rec create_400 POST /v1/jobs /v1/jobs --data-binary '{"time":'
rec create_400_empty POST /v1/jobs /v1/jobs
rec create_400_header POST /v1/jobs /v1/jobs --data-binary @"$tmp/quick.json" -H 'Idempotency-Key: a b'
rec create_413 POST /v1/jobs /v1/jobs --data-binary @"$tmp/quick.json" -H 'Content-Length: 99999999999'
rec create_422 POST /v1/jobs /v1/jobs --data-binary '{"time": 1}'
rec create_422_key POST /v1/jobs /v1/jobs --data-binary '{"name": "other"}' -H 'Idempotency-Key: k1'
rec create_422_scalar POST /v1/jobs /v1/jobs --data-binary '42'
rec list GET /v1/jobs '/v1/jobs?limit=1'
rec list_400 GET /v1/jobs '/v1/jobs?limit=0'
rec list_400_twice GET /v1/jobs '/v1/jobs?tag=a&tag=b'
rec job GET '/v1/jobs/{id}' "/v1/jobs/$q"
for p in "/v1/jobs/0123456789abcdef" "/v1/jobs/%2e%2e" "/v1/jobs/a%20b" "/v1/jobs/..%5c.."; do
    rec "job_404_$(echo "$p" | tr -c 'a-z0-9\n' _)" GET '/v1/jobs/{id}' "$p"
done
rec scenario GET '/v1/jobs/{id}/scenario' "/v1/jobs/$q/scenario"
rec scenario_404 GET '/v1/jobs/{id}/scenario' /v1/jobs/nosuch/scenario
for sub in result result.xmf stats frames shapes; do
    rec "${sub}_409_queued" GET "/v1/jobs/{id}/$sub" "/v1/jobs/$q/$sub"
    rec "${sub}_404" GET "/v1/jobs/{id}/$sub" "/v1/jobs/nosuch/$sub"
done
rec frame_409_queued GET '/v1/jobs/{id}/frames/{k}' "/v1/jobs/$q/frames/0"
rec frame_400 GET '/v1/jobs/{id}/frames/{k}' "/v1/jobs/$q/frames/first"
rec events_404 GET '/v1/jobs/{id}/events' /v1/jobs/nosuch/events
rec events_job_400 GET '/v1/jobs/{id}/events' "/v1/jobs/$q/events?x=1"
rec delete_409 DELETE '/v1/jobs/{id}' "/v1/jobs/$q"
rec cancel_200 POST '/v1/jobs/{id}/cancel' "/v1/jobs/$q/cancel"
rec cancel_409 POST '/v1/jobs/{id}/cancel' "/v1/jobs/$q/cancel"
rec cancel_404 POST '/v1/jobs/{id}/cancel' /v1/jobs/nosuch/cancel
rec result_409_cancelled GET '/v1/jobs/{id}/result' "/v1/jobs/$q/result"
rec delete_204 DELETE '/v1/jobs/{id}' "/v1/jobs/$q"
rec delete_404 DELETE '/v1/jobs/{id}' "/v1/jobs/$q"
rec validate_200 POST /v1/scenarios/validate /v1/scenarios/validate --data-binary @"$tmp/quick.json"
rec validate_422 POST /v1/scenarios/validate /v1/scenarios/validate --data-binary '[]'
rec validate_400 POST /v1/scenarios/validate /v1/scenarios/validate --data-binary 'x'
rec mesh_400 POST /v1/meshes /v1/meshes
rec mesh_422 POST /v1/meshes /v1/meshes --data-binary @"$tmp/bad.stl"
rec jobs_405 PUT /v1/jobs /v1/jobs
rec job_405 PATCH '/v1/jobs/{id}' /v1/jobs/nosuch
rec cancel_405 GET '/v1/jobs/{id}/cancel' /v1/jobs/nosuch/cancel
rec cross_origin_403 POST /v1/jobs /v1/jobs --data-binary @"$tmp/quick.json" -H 'Origin: http://evil.example'
rec dashboard GET / /
rec example GET '/examples/{file}' /examples/collision.json
rec example_404 GET '/examples/{file}' /examples/..%2fMakefile
rec static_404 GET '/static/{file}' /static/nosuch.js
stop_daemon TERM
start_daemon "$tmp/data3" --no-selftest || { summary; exit 1; }
done_id=$(submit "$tmp/quick.json")
st=$(wait_status "$done_id" succeeded 60)
check openapi_quick_job_succeeded succeeded "$st"
long=$(submit tests/server/long_job.json)
st=$(wait_status "$long" running 60)
rec healthz_200 GET /healthz /healthz
rec job_running GET '/v1/jobs/{id}' "/v1/jobs/$long"
rec stats_partial GET '/v1/jobs/{id}/stats' "/v1/jobs/$long/stats"
rec result_409_running GET '/v1/jobs/{id}/result' "/v1/jobs/$long/result"
rec cancel_202 POST '/v1/jobs/{id}/cancel' "/v1/jobs/$long/cancel"
rec list_all GET /v1/jobs /v1/jobs
rec result_200 GET '/v1/jobs/{id}/result' "/v1/jobs/$done_id/result"
etag=$(header ETag)
rec result_206 GET '/v1/jobs/{id}/result' "/v1/jobs/$done_id/result" -H 'Range: bytes=-100'
rec result_304 GET '/v1/jobs/{id}/result' "/v1/jobs/$done_id/result" -H "If-None-Match: $etag"
rec result_416 GET '/v1/jobs/{id}/result' "/v1/jobs/$done_id/result" -H 'Range: bytes=999999999-'
rec result_head HEAD '/v1/jobs/{id}/result' "/v1/jobs/$done_id/result" -I
rec xmf_200 GET '/v1/jobs/{id}/result.xmf' "/v1/jobs/$done_id/result.xmf"
rec stats_200 GET '/v1/jobs/{id}/stats' "/v1/jobs/$done_id/stats"
rec frames_200 GET '/v1/jobs/{id}/frames' "/v1/jobs/$done_id/frames"
rec frame_200 GET '/v1/jobs/{id}/frames/{k}' "/v1/jobs/$done_id/frames/-1"
rec frame_404 GET '/v1/jobs/{id}/frames/{k}' "/v1/jobs/$done_id/frames/1000"
rec shapes_200 GET '/v1/jobs/{id}/shapes' "/v1/jobs/$done_id/shapes"
st=$(wait_status "$long" cancelled 30)
check openapi_long_job_cancelled cancelled "$st"
rec job_cancelled GET '/v1/jobs/{id}' "/v1/jobs/$long"
rec stats_cancelled GET '/v1/jobs/{id}/stats' "/v1/jobs/$long/stats"
rec shapes_walls GET '/v1/jobs/{id}/shapes' "/v1/jobs/$long/shapes"
stop_daemon TERM
python3 tests/server/openapi_check.py schemas/openapi.yaml "$tmp/cases.txt" >"$tmp/cases.out" 2>&1
cat "$tmp/cases.out"
grep -q '^done$' "$tmp/cases.out" || bad openapi_check "the checker stopped early"
check openapi_cases_checked "$(grep -c . "$tmp/cases.txt")" "$(grep -c '^ok \|^FAIL ' "$tmp/cases.out")"
passed=$((passed + $(grep -c '^ok ' "$tmp/cases.out")))
failed=$((failed + $(grep -c '^FAIL ' "$tmp/cases.out")))
summary
