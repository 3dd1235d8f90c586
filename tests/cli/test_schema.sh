#!/bin/sh
# test_schema.sh - schemas/scenario.schema.json and the C parser agree: documents the schema
# accepts, `polydem validate` accepts (examples/), and documents with a structural error are
# refused by both. Uses Debian's python3-jsonschema (make deps). Prints "N passed, N failed".
PY=/usr/bin/python3
. "$(dirname "$0")/lib.sh"

schema_check() { # FILE -> exit 0 when the schema accepts it, message on stderr otherwise
    $PY - "$1" <<'PY'
import json, sys, jsonschema
schema = json.load(open("schemas/scenario.schema.json"))
jsonschema.Draft202012Validator.check_schema(schema)
errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(json.load(open(sys.argv[1]))),
                key=lambda e: list(e.absolute_path))
for e in errors:
    print("/" + "/".join(str(p) for p in e.absolute_path) + ": " + e.message, file=sys.stderr)
sys.exit(1 if errors else 0)
PY
}

if $PY -c "import jsonschema" 2>/dev/null; then
    for f in examples/*.json; do
        if schema_check "$f" 2>"$tmp/e" && $POLYDEM validate "$f" >/dev/null 2>&1; then
            ok "accepted_by_both $f"
        else bad "accepted_by_both $f" "$(cat "$tmp/e")"; fi
    done
    # an optional field both know
    sed 's/"friction"/"contact_places": "separate", "friction"/' examples/collision.json >"$tmp/places.json"
    if schema_check "$tmp/places.json" 2>"$tmp/e" && $POLYDEM validate "$tmp/places.json" >/dev/null 2>&1; then
        ok "accepted_by_both contact_places separate"
    else bad "accepted_by_both contact_places separate" "$(cat "$tmp/e")"; fi
    # structural errors: both refuse
    n=0
    for edit in 's/"friction"/"frction"/' 's/"dt": 1e-6/"dt": -1/' 's/"size": 0.02/"size": "big"/' \
        's/"rock", "rock"/"rock"/' 's/"friction"/"contact_places": "apart", "friction"/' \
        's/"friction"/"model": "linear", "normal_stiffness": 1e4, "contact_places": "separate", "friction"/'; do
        n=$((n + 1))
        sed "$edit" examples/collision.json >"$tmp/bad$n.json"
        if ! schema_check "$tmp/bad$n.json" 2>/dev/null && ! $POLYDEM validate "$tmp/bad$n.json" >/dev/null 2>&1; then
            ok "refused_by_both $edit"
        else bad "refused_by_both $edit" "one of them accepted it"; fi
    done
else
    bad schema_tools "python3-jsonschema is missing: run make deps"
fi
done_tests
