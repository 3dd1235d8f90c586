#!/bin/sh
# test_openapi.sh - schemas/openapi.yaml and the daemon in step: the file parses as OpenAPI 3,
# every $ref resolves, it describes every route `polydemd --routes` lists and no other, and the
# daemon's job, list, device, health and error objects carry exactly the fields it documents.
# Prints "N passed, N failed".
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
summary
