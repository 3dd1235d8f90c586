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
    sed 's/"friction"/"contact_moments": false, "friction"/' examples/collision.json >"$tmp/moments.json"
    if schema_check "$tmp/moments.json" 2>"$tmp/e" && $POLYDEM validate "$tmp/moments.json" >/dev/null 2>&1; then
        ok "accepted_by_both contact_moments false"
    else bad "accepted_by_both contact_moments false" "$(cat "$tmp/e")"; fi
    # structural errors: both refuse
    n=0
    for edit in 's/"friction"/"frction"/' 's/"dt": 1e-6/"dt": -1/' 's/"size": 0.02/"size": "big"/' \
        's/"rock", "rock"/"rock"/' 's/"friction"/"contact_places": "apart", "friction"/' \
        's/"friction"/"model": "linear", "normal_stiffness": 1e4, "contact_places": "separate", "friction"/' \
        's/"friction"/"contact_moments": 1, "friction"/' \
        's/"friction"/"model": "linear", "normal_stiffness": 1e4, "contact_moments": true, "friction"/'; do
        n=$((n + 1))
        sed "$edit" examples/collision.json >"$tmp/bad$n.json"
        if ! schema_check "$tmp/bad$n.json" 2>/dev/null && ! $POLYDEM validate "$tmp/bad$n.json" >/dev/null 2>&1; then
            ok "refused_by_both $edit"
        else bad "refused_by_both $edit" "one of them accepted it"; fi
    done

    # jedit IN OUT CODE: OUT is IN's JSON after CODE (Python, on the document d)
    jedit() {
        $PY - "$1" "$2" "$3" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
exec(sys.argv[3])
json.dump(d, open(sys.argv[2], "w"))
PY
    }
    # both NAME accept|refuse IN CODE: the schema and `polydem validate` agree on the edited IN
    # (each of these was a disagreement: one of them accepted what the other refused)
    both() {
        jedit "$3" "$tmp/both.json" "$4"
        schema_check "$tmp/both.json" 2>"$tmp/e"
        s=$?
        $POLYDEM validate "$tmp/both.json" >"$tmp/v" 2>&1
        v=$?
        want=0 label=accepted_by_both
        [ "$2" = refuse ] && want=1 label=refused_by_both
        if [ "$s" -eq "$want" ] && [ "$v" -eq "$want" ]; then ok "$label $1"
        else bad "$label $1" "schema exit $s ($(head -c 300 "$tmp/e")), validate exit $v ($(head -c 300 "$tmp/v"))"; fi
    }
    C=examples/collision.json H=examples/hopper.json P=examples/packing.json
    # names: a shape's or wall's names an HDF5 group; a material's is at most 63 characters
    both shape_name_slash refuse $C 'd["shapes"]["a/b"] = {"sphere": {}}'
    both shape_name_dot refuse $C 'd["shapes"]["."] = {"sphere": {}}'
    both shape_name_empty refuse $C 'd["shapes"][""] = {"sphere": {}}'
    both shape_name_63_unicode accept $C 'd["shapes"]["\U0001F600" * 63] = {"sphere": {}}'
    both wall_name_dotdot refuse $H 'd["walls"][0]["name"] = ".."'
    both wall_name_slash refuse $H 'd["walls"][0]["name"] = "plate/1"'
    both material_name_64 refuse $C 'd["materials"]["m" * 64] = {"density": 1000, "youngs_modulus": 1e7}'
    both material_name_63_unicode accept $C 'd["materials"]["\u00e9" * 63] = {"density": 1000, "youngs_modulus": 1e7}'
    both materials_65 refuse $C 'd["materials"].update({"m%d" % i: {"density": 1000, "youngs_modulus": 1e7} for i in range(64)})'
    # shapes: one form's fields are errors beside another's
    both sphere_with_triangles refuse $C 'd["shapes"]["ball"]["triangles"] = 80'
    both inline_mesh_with_seed refuse $C 'd["shapes"]["t"] = {"vertices": [[1,1,1],[1,-1,-1],[-1,1,-1],[-1,-1,1]], "triangles": [[0,1,2],[0,3,1],[0,2,3],[1,3,2]], "seed": 3}'
    both inline_mesh_integer_triangles refuse $C 'd["shapes"]["t"] = {"vertices": [[1,1,1],[1,-1,-1],[-1,1,-1],[-1,-1,1]], "triangles": 4}'
    both builtin_with_vertices refuse $C 'd["shapes"]["r"]["vertices"] = [[1,1,1],[1,-1,-1],[-1,1,-1],[-1,-1,1]]'
    both builtin_with_triangle_list refuse $C 'd["shapes"]["r"]["triangles"] = [[0,1,2],[0,3,1],[0,2,3],[1,3,2]]'
    both cube_80_triangles refuse $C 'd["shapes"]["c"] = {"builtin": "cube", "triangles": 80}'
    both cube_12_triangles accept $C 'd["shapes"]["c"] = {"builtin": "cube", "triangles": 12}'
    both cube_seed refuse $C 'd["shapes"]["c"] = {"builtin": "cube", "seed": 1}'
    both rock_odd_triangles refuse $C 'd["shapes"]["r"]["triangles"] = 81'
    both rock_30000_triangles refuse $C 'd["shapes"]["r"]["triangles"] = 30000'
    both icosphere_100_triangles refuse $C 'd["shapes"]["i"] = {"builtin": "icosphere", "triangles": 100}'
    both icosphere_320_triangles accept $C 'd["shapes"]["i"] = {"builtin": "icosphere", "triangles": 320}'
    # integers: 80.0 is the integer 80 to JSON Schema
    both inline_mesh_real_indices accept $C 'd["shapes"]["t"] = {"vertices": [[1,1,1],[1,-1,-1],[-1,1,-1],[-1,-1,1]], "triangles": [[0.0,1,2],[0,3,1],[0,2,3],[1,3,2]]}'
    both count_real accept $P 'd["particles"][0]["count"] = 300.0'
    both seed_real accept $C 'd["seed"] = 3.0'
    both seed_1e18 accept $C 'd["seed"] = 1e18'
    both seed_2e19 refuse $C 'd["seed"] = 2e19'
    both seed_2_63 refuse $C 'd["seed"] = 2**63'
    # an integer beyond 64 bits is a JSON number where a number is meant (jansson refused it)
    both integer_1e23_as_number accept $H 'd["walls"][0]["center"] = [10**23, 0, 0]'
    # a listed group takes none of the generated group's fields
    both list_with_velocity refuse $C 'd["particles"][0]["velocity"] = [1, 0, 0]'
    both list_with_orientation refuse $C 'd["particles"][0]["orientation"] = "random"'
    both list_with_arrangement refuse $C 'd["particles"][0]["arrangement"] = "lattice"'
    # a uniform size has no mean or std (they were silently ignored)
    both uniform_with_mean refuse $P 'd["particles"][0]["size"] = {"distribution": "uniform", "min": 0.007, "max": 0.01, "mean": 0.05}'
    both uniform_with_std refuse $P 'd["particles"][0]["size"] = {"distribution": "uniform", "min": 0.007, "max": 0.01, "std": 0.001}'
    # cohesion needs its range
    both cohesion_without_range refuse $C 'd["interactions"][0]["cohesion"] = 10'
    both cohesion_zero_range refuse $C 'd["interactions"][0].update(cohesion=10, cohesion_range=0)'
    both cohesion_with_range accept $C 'd["interactions"][0].update(cohesion=10, cohesion_range=0.001)'
    # output fields: each once
    both output_field_twice refuse $C 'd["output"] = {"fields": ["velocity", "velocity"]}'
else
    bad schema_tools "python3-jsonschema is missing: run make deps"
fi
done_tests
