#!/bin/sh
# test_cli.sh - the polydem CLI contract, driven as other tools drive it: JSON on stdout, exit 2
# with a message on stderr for bad arguments or meshes. Prints "N passed, N failed".
. "$(dirname "$0")/lib.sh"

# json_num FILE KEY [INDEX]: a number (or an array element, 0-based) from the one-line JSON output
# (the "units" object, which repeats key names, is dropped first)
json_num() {
    sed 's/, "units": {[^}]*}//' "$1" | sed -n "s/.*\"$2\": *\(\[[^]]*\]\|[^,}]*\).*/\1/p" | head -n 1 |
        tr -d '[]' | awk -F', *' -v i="${3:-0}" '{ print $(i + 1) }'
}
# near EXPECTED ACTUAL TOL: |e - a| <= tol
near() { awk -v e="$1" -v a="$2" -v t="$3" 'BEGIN { d = e - a; if (d < 0) d = -d; exit !(a != "" && d <= t) }'; }

# 1. offset unit cubes: the box [0, 0.5] x [-.5, .5]^2, exact in binary
$POLYDEM overlap builtin:cube builtin:cube --pose-a "0 0 0 1 0 0 0" --pose-b "0.5 0 0 1 0 0 0" >"$tmp/o1"
if near 0.5 "$(json_num "$tmp/o1" volume)" 1e-12 && near 0.25 "$(json_num "$tmp/o1" centroid 0)" 1e-12 &&
    near 1 "$(json_num "$tmp/o1" normal 0)" 1e-12 && near 0.5 "$(json_num "$tmp/o1" depth)" 1e-12; then
    ok overlap_offset_cubes
else bad overlap_offset_cubes "$(cat "$tmp/o1")"; fi

# 2. the contract's key order and full precision
# (then the places, added later: "places": n, "places_known": bool, "effective_volume": m^3, "effective_depth": m,
# "effective_point": [m])
if grep -Eq '^\{"volume": [-0-9.e]+, "centroid": \[[^]]*\], "normal": \[[^]]*\], "depth": [-0-9.e]+, "places": [0-9]+, "places_known": (true|false), "effective_volume": [-0-9.e]+, "effective_depth": [-0-9.e]+, "effective_point": \[[^]]*\]\}$' "$tmp/o1"; then
    ok overlap_json_shape
else bad overlap_json_shape "$(cat "$tmp/o1")"; fi

# 2b. separate places (thesis section 5.4): two unit cubes in one mesh, 1 m apart, pressed 0.25 m
# into a slab: V = 0.5, depth 0.25 and two places of V_k = d_k = 0.25, so sum sqrt(V_k d_k) = 0.5
# and sum sqrt(V_k / d_k) = 2 give the effective volume 0.5 x 2 = 1 and depth 0.5 / 2 = 0.25; equal
# forces act midway between the places' centroids, at x = 1.5
box_obj() { # X0 Y0 Z0 X1 Y1 Z1 FIRST: a box's 8 vertices and 12 outward triangles, OBJ numbering
    awk -v x0="$1" -v y0="$2" -v z0="$3" -v x1="$4" -v y1="$5" -v z1="$6" -v o="$7" 'BEGIN {
        for (i = 0; i < 8; i++)
            printf "v %s %s %s\n", (i % 2 ? x1 : x0), (int(i / 2) % 2 ? y1 : y0), (i >= 4 ? z1 : z0)
        n = split("1 3 2 2 3 4 5 6 7 6 8 7 1 2 5 2 6 5 3 7 4 4 7 8 1 5 3 3 5 7 2 4 6 4 8 6", t, " ")
        for (k = 1; k <= n; k += 3)
            printf "f %d %d %d\n", t[k] + o, t[k + 1] + o, t[k + 2] + o }'
}
{ box_obj 0 0 0 1 1 1 0; box_obj 2 0 0 3 1 1 8; } >"$tmp/two.obj"
box_obj -1 -1 -1 4 2 0 0 >"$tmp/slab.obj"
$POLYDEM overlap "$tmp/two.obj" "$tmp/slab.obj" --pose-b "0 0 0.25 1 0 0 0" >"$tmp/o2b" 2>&1
if near 0.5 "$(json_num "$tmp/o2b" volume)" 1e-12 && [ "$(json_num "$tmp/o2b" places)" = 2 ] &&
    near 1 "$(json_num "$tmp/o2b" effective_volume)" 1e-12 &&
    near 0.25 "$(json_num "$tmp/o2b" effective_depth)" 1e-12 &&
    near 1.5 "$(json_num "$tmp/o2b" effective_point 0)" 1e-12; then
    ok overlap_separate_places
else bad overlap_separate_places "$(cat "$tmp/o2b")"; fi

# 3. apart: exactly {"volume": 0}
$POLYDEM overlap builtin:cube builtin:cube --pose-b "2 0 0 1 0 0 0" >"$tmp/o3"
if [ "$(cat "$tmp/o3")" = '{"volume": 0}' ]; then ok overlap_apart_is_zero; else bad overlap_apart_is_zero "$(cat "$tmp/o3")"; fi

# 4. face on face (touching) is no overlap either
$POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 1 1 0 0 0" >"$tmp/o4"
if [ "$(cat "$tmp/o4")" = '{"volume": 0}' ]; then ok overlap_touching_is_zero; else bad overlap_touching_is_zero "$(cat "$tmp/o4")"; fi

# 5. --opencl agrees with the host path to 1e-12 relative (double precision)
pa="0.01 0.02 0.03 0.9 0.1 -0.3 0.2"
pb="0.6 0.3 -0.2 0.5 0.5 0.5 -0.5"
$POLYDEM overlap builtin:rock:80 builtin:schonhardt --pose-a "$pa" --pose-b "$pb" >"$tmp/h5"
if $POLYDEM overlap builtin:rock:80 builtin:schonhardt --pose-a "$pa" --pose-b "$pb" --opencl >"$tmp/c5" 2>"$tmp/e5"; then
    good=1
    for key in volume depth; do
        h=$(json_num "$tmp/h5" $key) c=$(json_num "$tmp/c5" $key)
        near "$h" "$c" "$(awk -v h="$h" 'BEGIN { print (h < 0 ? -h : h) * 1e-12 }')" || good=0
    done
    for i in 0 1 2; do
        near "$(json_num "$tmp/h5" centroid $i)" "$(json_num "$tmp/c5" centroid $i)" 1e-12 || good=0
        near "$(json_num "$tmp/h5" normal $i)" "$(json_num "$tmp/c5" normal $i)" 1e-12 || good=0
    done
    v=$(json_num "$tmp/h5" volume)
    if [ "$good" = 1 ] && awk -v v="$v" 'BEGIN { exit !(v > 0) }'; then ok overlap_opencl_matches_host
    else bad overlap_opencl_matches_host "host $(cat "$tmp/h5") opencl $(cat "$tmp/c5")"; fi
else bad overlap_opencl_matches_host "$(cat "$tmp/e5")"; fi

# 6. --single: close to double (float's 1.2e-7 amplified by the cusp sums' cancellation)
$POLYDEM overlap builtin:rock:80 builtin:schonhardt --pose-a "$pa" --pose-b "$pb" --single >"$tmp/s6"
if near "$(json_num "$tmp/h5" volume)" "$(json_num "$tmp/s6" volume)" "$(awk -v h="$(json_num "$tmp/h5" volume)" 'BEGIN { print h * 1e-3 }')"; then
    ok overlap_single_precision
else bad overlap_single_precision "$(cat "$tmp/s6") vs $(cat "$tmp/h5")"; fi

# 7. mesh files are used in their own coordinates: an ASCII STL cube at [10,11]^3 and a builtin
#    unit cube centred at (11, 10.5, 10.5) overlap in [10.5, 11] x [10, 11]^2
cat >"$tmp/cube.stl" <<'STL'
solid c
facet normal 0 0 0
outer loop
vertex 10 10 10
vertex 10 11 10
vertex 11 10 10
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 11 10 10
vertex 10 11 10
vertex 11 11 10
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 10 10 11
vertex 11 10 11
vertex 10 11 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 11 10 11
vertex 11 11 11
vertex 10 11 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 10 10 10
vertex 11 10 10
vertex 10 10 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 11 10 10
vertex 11 10 11
vertex 10 10 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 10 11 10
vertex 10 11 11
vertex 11 11 10
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 11 11 10
vertex 10 11 11
vertex 11 11 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 10 10 10
vertex 10 10 11
vertex 10 11 10
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 10 11 10
vertex 10 10 11
vertex 10 11 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 11 10 10
vertex 11 11 10
vertex 11 10 11
endloop
endfacet
facet normal 0 0 0
outer loop
vertex 11 11 10
vertex 11 11 11
vertex 11 10 11
endloop
endfacet
endsolid c
STL
$POLYDEM overlap "$tmp/cube.stl" builtin:cube --pose-b "11 10.5 10.5 1 0 0 0" >"$tmp/o7"
if near 0.5 "$(json_num "$tmp/o7" volume)" 1e-12 && near 10.75 "$(json_num "$tmp/o7" centroid 0)" 1e-11 &&
    near 10.5 "$(json_num "$tmp/o7" centroid 1)" 1e-11 && near 1 "$(json_num "$tmp/o7" normal 0)" 1e-12; then
    ok overlap_stl_in_file_coordinates
else bad overlap_stl_in_file_coordinates "$(cat "$tmp/o7")"; fi

# 8. quaternions are normalised: (2,0,0,0) is the identity
$POLYDEM overlap builtin:cube builtin:cube --pose-b "0.5 0 0 2 0 0 0" >"$tmp/o8"
if near 0.5 "$(json_num "$tmp/o8" volume)" 1e-12; then ok overlap_normalises_quaternion
else bad overlap_normalises_quaternion "$(cat "$tmp/o8")"; fi

# 9. mesh-info on a builtin and on the STL
$POLYDEM mesh-info builtin:cube >"$tmp/m9" && $POLYDEM mesh-info "$tmp/cube.stl" >"$tmp/m9b"
if near 1 "$(json_num "$tmp/m9" volume)" 1e-12 && [ "$(json_num "$tmp/m9" triangles)" = 12 ] &&
    near 10.5 "$(json_num "$tmp/m9b" centroid 2)" 1e-12 && grep -q '"closed": true' "$tmp/m9" &&
    near 0.16666666666666666 "$(json_num "$tmp/m9" principal_moments 0)" 1e-12; then
    ok mesh_info
else bad mesh_info "$(cat "$tmp/m9") $(cat "$tmp/m9b")"; fi
# a cube's products of inertia are exact zeros, printed as 0, not -0
if ! grep -q -- '-0[],]' "$tmp/m9" && grep -q '"inertia": \[\[0.16666666666666666, 0, 0\]' "$tmp/m9"
then ok mesh_info_prints_no_negative_zero
else bad mesh_info_prints_no_negative_zero "$(cat "$tmp/m9")"; fi

# devices: at least the device the tests use, as text and as JSON, with whether its single
# precision rounds / and sqrt as the host does (the text says so only where it does not)
if $POLYDEM devices >"$tmp/d1" && grep -q '^0: ' "$tmp/d1" && $POLYDEM devices --json >"$tmp/d2" &&
    grep -q '^\[{"index": 0, "name": ' "$tmp/d2" &&
    grep -Eq '"fp64": (true|false), "fp32_rounded": (true|false)}' "$tmp/d2" &&
    [ "$(grep -c '"fp32_rounded": false' "$tmp/d2")" = "$(grep -c 'not correctly rounded' "$tmp/d1")" ]; then
    ok devices
else bad devices "$(cat "$tmp/d1" "$tmp/d2")"; fi
expect_fail devices_bad_flag 2 "--bogus" -- $POLYDEM devices --bogus

# validate: a valid scenario prints its summary with units, exit 0
if $POLYDEM validate examples/collision.json >"$tmp/v1" 2>&1 && grep -q "valid" "$tmp/v1" &&
    grep -q "particles: 2 " "$tmp/v1" && grep -Eq "stable dt estimate: [0-9.e+-]+ s" "$tmp/v1"; then
    ok validate_valid
else bad validate_valid "$(cat "$tmp/v1")"; fi
# the contact resolution: reported for polyhedra, with a warning in single precision against the
# example's walls (64 ulps of ~0.5 m is ~4e-6 m), none in double
sed 's/"name": "packing",/"name": "packing", "precision": "single",/' examples/packing.json >"$tmp/single.json"
$POLYDEM validate examples/packing.json >"$tmp/vd" 2>&1
$POLYDEM validate "$tmp/single.json" >"$tmp/vs" 2>&1
if grep -q "contacts resolved to about" "$tmp/vd" && ! grep -q "warning" "$tmp/vd" &&
    grep -q "warning: contact depths below" "$tmp/vs"; then
    ok validate_contact_resolution
else bad validate_contact_resolution "$(cat "$tmp/vd" "$tmp/vs")"; fi
# every error with its JSON path, exit 1
sed -e 's/"density": 2600/"density": -2600/' -e 's/"friction": 0.35/"frction": 0.35/' \
    examples/collision.json >"$tmp/bad.json"
$POLYDEM validate "$tmp/bad.json" >"$tmp/v2" 2>&1
rc=$?
if [ "$rc" -eq 1 ] && grep -q "/materials/rock/density: must be > 0" "$tmp/v2" &&
    grep -q "/interactions/0/frction: unknown field" "$tmp/v2" && grep -q "2 errors" "$tmp/v2"; then
    ok validate_reports_every_error
else bad validate_reports_every_error "exit $rc: $(cat "$tmp/v2")"; fi
$POLYDEM validate "$tmp/bad.json" --json >"$tmp/v3"
if grep -q '"valid": false' "$tmp/v3" && grep -q '"path": "/materials/rock/density"' "$tmp/v3"; then
    ok validate_json_errors
else bad validate_json_errors "$(cat "$tmp/v3")"; fi
$POLYDEM validate examples/collision.json --json >"$tmp/v4"
if grep -q '"valid": true' "$tmp/v4" && near 2 "$(json_num "$tmp/v4" particles)" 0; then
    ok validate_json_summary
else bad validate_json_summary "$(cat "$tmp/v4")"; fi
$POLYDEM validate "$tmp/none.json" >"$tmp/v5" 2>&1
rc=$?
if [ "$rc" -eq 1 ] && grep -q "none.json: cannot open" "$tmp/v5"; then ok validate_missing_file
else bad validate_missing_file "exit $rc: $(cat "$tmp/v5")"; fi

# 10-18. bad input: exit 2 and a message naming what is wrong, nothing on stdout
head -n 78 "$tmp/cube.stl" >"$tmp/open.stl" # 11 of the 12 facets: one hole
echo "endsolid c" >>"$tmp/open.stl"
expect_fail missing_file 2 "nope.stl" -- $POLYDEM overlap "$tmp/nope.stl" builtin:cube
expect_fail open_mesh 2 "open edge" -- $POLYDEM overlap "$tmp/open.stl" builtin:cube
expect_fail pose_too_few_numbers 2 "--pose-a" -- $POLYDEM overlap builtin:cube builtin:cube --pose-a "0 0 0 1 0 0"
expect_fail pose_not_a_number 2 "--pose-b" -- $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 x 1 0 0 0"
expect_fail zero_quaternion 2 "quaternion" -- $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 0 0 0 0 0"
expect_fail pose_nan 2 'number 2 of 7, "nan", is not finite' -- $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 nan 0 1 0 0 0"
expect_fail pose_overflow 2 'number 1 of 7, "1e999", is not finite' -- $POLYDEM overlap builtin:cube builtin:cube --pose-a "1e999 0 0 1 0 0 0"
expect_fail pose_too_many_numbers 2 "got more than 7" -- $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 0 1 0 0 0 5"
expect_fail pose_trailing_text 2 '"m" after number 7 is not a number' -- $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 0 1 0 0 0 m"
# a coordinate too small to hold is the nearest one held (strtod's underflow), not an error:
# 1e-320 m beside 0.5 m moves nothing, so the answer is the one for 0
if $POLYDEM overlap builtin:cube builtin:cube --pose-b "1e-320 0 0.5 1 0 0 0" >"$tmp/sub" 2>&1 &&
    $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 0.5 1 0 0 0" >"$tmp/sub0" 2>&1 &&
    grep -q '"volume": 0.4999' "$tmp/sub" && cmp -s "$tmp/sub" "$tmp/sub0"; then
    ok pose_subnormal_taken
else bad pose_subnormal_taken "$(cat "$tmp/sub")"; fi
expect_fail one_mesh_only 2 "two meshes" -- $POLYDEM overlap builtin:cube
expect_fail unknown_option 2 "--bogus" -- $POLYDEM overlap builtin:cube builtin:cube --bogus
expect_fail unknown_builtin 2 "dodecahedron" -- $POLYDEM mesh-info builtin:dodecahedron
expect_fail unknown_command 2 "frobnicate" -- $POLYDEM frobnicate

# 19. a mesh that is a FIFO with no writer, or a device: refused at once, naming the field (a FIFO
# hung `validate` in fopen, waiting for a writer; /dev/zero was read up to the 2 GiB limit)
mkfifo "$tmp/fifo.stl"
sed 's|{"builtin": "rock", "triangles": 80}|{"mesh": "fifo.stl"}|' examples/collision.json >"$tmp/fifo.json"
expect_fail mesh_fifo_without_writer 1 '/shapes/r/mesh: .*fifo.stl: empty file' -- timeout 20 $POLYDEM validate "$tmp/fifo.json"
sed 's|{"builtin": "rock", "triangles": 80}|{"mesh": "/dev/zero"}|' examples/collision.json >"$tmp/zero.json"
expect_fail mesh_device 1 '/shapes/r/mesh: /dev/zero: cannot read: a device' -- timeout 20 $POLYDEM validate "$tmp/zero.json"
expect_fail mesh_info_device 2 '/dev/zero: cannot read: a device' -- timeout 20 $POLYDEM mesh-info /dev/zero
# a pipe is still read: what its writer sends
if cat "$tmp/cube.stl" | $POLYDEM mesh-info /dev/stdin >"$tmp/pipe.out" 2>&1 &&
    grep -q '"triangles": 12' "$tmp/pipe.out"; then ok mesh_from_pipe
else bad mesh_from_pipe "$(cat "$tmp/pipe.out")"; fi


# 20. output that cannot be written is an error, exit 1 with a message, for every command that
# prints on stdout (a full disk was exit 0 with the JSON lost); with stdout closed too
cat >"$tmp/printers" <<'LIST'
mesh_info|mesh-info builtin:cube
overlap|overlap builtin:cube builtin:cube --pose-b 0.5,0,0,1,0,0,0
overlap_apart|overlap builtin:cube builtin:cube --pose-b 2,0,0,1,0,0,0
devices|devices
devices_json|devices --json
validate|validate examples/collision.json
validate_json|validate examples/collision.json --json
help|--help
overlap_help|overlap --help
LIST
while IFS='|' read -r name args; do
    if [ -c /dev/full ]; then
        $POLYDEM $args </dev/null >/dev/full 2>"$tmp/wf"
        rc=$?
        if [ "$rc" -eq 1 ] && grep -q '^polydem: writing the output failed: No space left on device$' "$tmp/wf"; then
            ok "output_full_$name"
        else bad "output_full_$name" "exit $rc: $(cat "$tmp/wf")"; fi
    fi
    $POLYDEM $args </dev/null >&- 2>"$tmp/wc"
    rc=$?
    if [ "$rc" -eq 1 ] && grep -q '^polydem: writing the output failed' "$tmp/wc"; then
        ok "output_closed_$name"
    else bad "output_closed_$name" "exit $rc: $(cat "$tmp/wc")"; fi
done <"$tmp/printers"
[ -c /dev/full ] || echo "skip output_full tests: no /dev/full"
# a run's summary line too: the result itself is written and kept
if [ -c /dev/full ]; then
    $POLYDEM run examples/collision.json -o "$tmp/full.h5" >/dev/full 2>"$tmp/wr"
    rc=$?
    if [ "$rc" -eq 1 ] && grep -q '^polydem: writing the output failed: No space left on device$' "$tmp/wr" &&
        [ -s "$tmp/full.h5" ]; then
        ok output_full_run
    else bad output_full_run "exit $rc: $(cat "$tmp/wr")"; fi
fi
# a failure that printed nothing keeps its own exit status
expect_fail output_closed_usage_error 2 "two meshes" -- sh -c '"$0" overlap builtin:cube >&-' "$POLYDEM"

# 21. JSON strings are valid UTF-8 whatever the file name's bytes: valid UTF-8 passes through,
# each byte of an ill-formed sequence (a stray byte, an overlong form, a surrogate, above
# U+10FFFF, a sequence cut short) becomes U+FFFD; quotes and control characters are escaped
if command -v python3 >/dev/null; then
    ff=$tmp/$(printf 'cube_\377.obj')
    cp "$tmp/two.obj" "$ff"
    $POLYDEM mesh-info "$ff" >"$tmp/u1" 2>&1
    rc=$?
    if [ "$rc" -eq 0 ] && python3 -c 'import json, sys
sys.exit(json.load(sys.stdin)["mesh"] != sys.argv[1] + "/cube_\ufffd.obj")' "$tmp" <"$tmp/u1"; then
        ok mesh_info_json_invalid_utf8
    else bad mesh_info_json_invalid_utf8 "exit $rc: $(od -c "$tmp/u1" | head -n 5)"; fi
    ff=$tmp/$(printf 'u_\303\251\342\202\254\360\237\230\200_\300\257_\355\240\200_\364\220\200\200_\342\202_\377_"\\\001\177.obj')
    cp "$tmp/two.obj" "$ff"
    $POLYDEM mesh-info "$ff" >"$tmp/u2" 2>&1
    rc=$?
    if [ "$rc" -eq 0 ] && python3 -c 'import json, sys
want = sys.argv[1] + "/u_\u00e9\u20ac\U0001f600_" + "\ufffd" * 2 + "_" + "\ufffd" * 3 + "_" + \
    "\ufffd" * 4 + "_" + "\ufffd" * 2 + "_\ufffd_\"\\\u0001\u007f.obj"
sys.exit(json.load(sys.stdin)["mesh"] != want)' "$tmp" <"$tmp/u2"; then
        ok mesh_info_json_utf8_each_bad_byte
    else bad mesh_info_json_utf8_each_bad_byte "exit $rc: $(od -c "$tmp/u2" | head -n 8)"; fi
else echo "skip UTF-8 tests: no python3"; fi

# 22. --help or -h after any command: that command's usage on stdout, exit 0 (overlap took it for
# an unknown option, mesh-info for a file); every command the general usage lists
cmds=$($POLYDEM --help | sed -n 's/^  \([a-z][a-z-]*\) .*/\1/p')
[ -n "$cmds" ] || bad help_lists_commands "$($POLYDEM --help)"
for c in $cmds; do
    for h in --help -h; do
        $POLYDEM "$c" $h >"$tmp/h1" 2>"$tmp/h2"
        rc=$?
        if [ "$rc" -eq 0 ] && head -n 1 "$tmp/h1" | grep -q "^usage: polydem $c " && [ ! -s "$tmp/h2" ]; then
            ok "help_${c}_$h"
        else bad "help_${c}_$h" "exit $rc: $(cat "$tmp/h1" "$tmp/h2")"; fi
    done
done
# also after other arguments
if $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 0 1 0 0 0" --help >"$tmp/h3" 2>&1 &&
    grep -q '^usage: polydem overlap ' "$tmp/h3" && $POLYDEM mesh-info builtin:cube -h >"$tmp/h4" 2>&1 &&
    grep -q '^usage: polydem mesh-info ' "$tmp/h4"; then
    ok help_after_arguments
else bad help_after_arguments "$(cat "$tmp/h3" "$tmp/h4")"; fi

# 23. a pose's numbers may have whitespace of any kind around them (a trailing newline from a
# file or $(...), a \r from a CRLF file were refused); junk is shown escaped, not as raw control
# characters that redraw the terminal
nl='
'
cr=$(printf '\r')
esc=$(printf '\033')
good=1
for pose in "0.5 0 0 1 0 0 0$nl" "0.5 0 0 1 0 0 0$cr" "0.5 0 0 1 0 0 0$cr$nl" "$nl	 0.5${nl}0 0 1 0 0 0 "; do
    $POLYDEM overlap builtin:cube builtin:cube --pose-a "0 0 0 1 0 0 0" --pose-b "$pose" >"$tmp/ws" 2>&1 &&
        cmp -s "$tmp/ws" "$tmp/o1" || { good=0; bad pose_whitespace "$(printf '%s' "$pose" | od -c | head -n 1): $(cat "$tmp/ws")"; }
done
[ "$good" = 1 ] && ok pose_whitespace
expect_fail pose_junk_escaped 2 '"\\x1b\[2J" after number 7 is not a number): "0.5 0 0 1 0 0 0 \\x1b\[2J"' -- \
    $POLYDEM overlap builtin:cube builtin:cube --pose-b "0.5 0 0 1 0 0 0 $esc[2J"
if grep -q "$esc" "$tmp/err"; then bad pose_junk_no_raw_escape "$(od -c "$tmp/err")"; else ok pose_junk_no_raw_escape; fi
expect_fail pose_junk_control 2 'number 3 of 7, "\\x01", is not a number' -- \
    $POLYDEM overlap builtin:cube builtin:cube --pose-b "0.5 0 $(printf '\001') 1 0 0 0"
expect_fail pose_zero_quaternion_escaped 2 'quaternion "0 0 0 0 0 0 0\\r" has zero length' -- \
    $POLYDEM overlap builtin:cube builtin:cube --pose-b "0 0 0 0 0 0 0$cr"
if grep -q "$cr" "$tmp/err"; then bad pose_no_raw_cr "$(od -c "$tmp/err")"; else ok pose_no_raw_cr; fi

# 24. an option with a value given twice is refused, naming it (the second silently replaced the
# first); so are run's --meshes and --no-meshes together (the later one won)
expect_fail overlap_pose_b_twice 2 'overlap: --pose-b given twice' -- \
    $POLYDEM overlap builtin:cube builtin:cube --pose-b "0.5 0 0 1 0 0 0" --pose-b "1 0 0 1 0 0 0"
expect_fail overlap_pose_a_twice 2 'overlap: --pose-a given twice' -- \
    $POLYDEM overlap builtin:cube builtin:cube --pose-a "0 0 0 1 0 0 0" --pose-a "0 0 0 1 0 0 0"
expect_fail overlap_device_twice 2 'overlap: --device given twice' -- \
    $POLYDEM overlap builtin:cube builtin:cube --opencl --device 0 --device 0
expect_fail run_output_twice 2 'run: -o given twice' -- \
    $POLYDEM run examples/collision.json -o "$tmp/r1.h5" -o "$tmp/r2.h5"
expect_fail run_output_long_and_short 2 'run: --output given twice' -- \
    $POLYDEM run examples/collision.json -o "$tmp/r1.h5" --output "$tmp/r2.h5"
expect_fail run_device_twice 2 'run: --device given twice' -- \
    $POLYDEM run examples/collision.json -o "$tmp/r1.h5" --device 0 --device 0
expect_fail run_meshes_and_no_meshes 2 'run: --meshes and --no-meshes contradict' -- \
    $POLYDEM run examples/collision.json -o "$tmp/r1.h5" --meshes --no-meshes
if [ -e "$tmp/r1.h5" ] || [ -e "$tmp/r2.h5" ]; then bad run_refused_writes_nothing "$(ls "$tmp")"
else ok run_refused_writes_nothing; fi

# 25. builtin specs: a field the shape does not take, and an empty, zero or non-numeric count or
# seed, are refused naming the spec (a seed on an icosphere was ignored, a count of 0 taken as
# the default, empty fields as defaults); the spellings in use still work
expect_fail builtin_seed_on_icosphere 2 "'builtin:icosphere:80:3': only builtin:rock takes a seed" -- \
    $POLYDEM mesh-info builtin:icosphere:80:3
expect_fail builtin_seed_on_schonhardt 2 "'builtin:schonhardt:8:1': only builtin:rock takes a seed" -- \
    $POLYDEM overlap builtin:schonhardt:8:1 builtin:cube
expect_fail builtin_zero_count 2 "'builtin:icosphere:0': triangle count '0' must be at least 1" -- \
    $POLYDEM mesh-info builtin:icosphere:0
expect_fail builtin_empty_fields 2 "'builtin:rock::': triangle count is empty" -- $POLYDEM mesh-info builtin:rock::
expect_fail builtin_empty_seed 2 "'builtin:rock:80:': seed is empty" -- $POLYDEM mesh-info builtin:rock:80:
expect_fail builtin_empty_count 2 "'builtin:icosphere:': triangle count is empty" -- $POLYDEM mesh-info builtin:icosphere:
expect_fail builtin_count_not_a_number 2 "'builtin:rock:8x': triangle count '8x' is not a whole number" -- \
    $POLYDEM mesh-info builtin:rock:8x
expect_fail builtin_seed_not_a_number 2 "'builtin:rock:80:-3': seed '-3' is not a whole number" -- \
    $POLYDEM mesh-info builtin:rock:80:-3
expect_fail builtin_seed_too_large 2 "'builtin:rock:80:4294967296': seed '4294967296' is too large" -- \
    $POLYDEM mesh-info builtin:rock:80:4294967296
expect_fail builtin_too_many_fields 2 "'builtin:rock:80:1:2': too many fields" -- $POLYDEM mesh-info builtin:rock:80:1:2
expect_fail builtin_bad_fixed_count 2 "builtin:cube: bad triangle count 13" -- $POLYDEM mesh-info builtin:cube:13
good=1
for spec in builtin:cube builtin:cube:12 builtin:tetrahedron:4 builtin:schonhardt builtin:schonhardt:8 \
    builtin:icosphere builtin:icosphere:320 builtin:rock builtin:rock:80 builtin:rock:80:3 \
    builtin:rock:100:5 builtin:rock:80:0 builtin:rock:80:4294967295; do
    $POLYDEM mesh-info "$spec" >"$tmp/b1" 2>&1 || { good=0; bad "builtin_valid $spec" "$(cat "$tmp/b1")"; }
done
[ "$good" = 1 ] && ok builtin_valid_spellings
# the seed still picks the rock, and a field left out is the default
for s in 80:3 80:4 "" 80:1; do
    $POLYDEM mesh-info "builtin:rock${s:+:$s}" | sed 's/"mesh": "[^"]*", //' >"$tmp/rock$s"
done
if ! cmp -s "$tmp/rock80:3" "$tmp/rock80:4" && cmp -s "$tmp/rock" "$tmp/rock80:1" && [ -s "$tmp/rock" ]; then
    ok builtin_seed_and_defaults
else bad builtin_seed_and_defaults "$(cat "$tmp/rock80:3" "$tmp/rock80:4" "$tmp/rock" "$tmp/rock80:1")"; fi

# 26. one solid wholly inside the other: the normal is the line from A's centroid to B's, not
# from A's frame origin to B's (README): the box [0,2] x [0,1] x [0,3] holds the cube
# [0.5,1] x [0.25,0.75] x [1,1.5], centroids (1, 0.5, 1.5) and (0.75, 0.5, 1.25)
box_obj 0 0 0 2 1 3 0 >"$tmp/tall.obj"
box_obj 0 0 0 0.5 0.5 0.5 0 >"$tmp/small.obj"
$POLYDEM overlap "$tmp/tall.obj" "$tmp/small.obj" --pose-b "0.5 0.25 1 1 0 0 0" >"$tmp/in" 2>&1
if near 0.125 "$(json_num "$tmp/in" volume)" 1e-12 && near -0.70710678118654757 "$(json_num "$tmp/in" normal 0)" 1e-12 &&
    near 0 "$(json_num "$tmp/in" normal 1)" 1e-12 && near -0.70710678118654757 "$(json_num "$tmp/in" normal 2)" 1e-12; then
    ok overlap_contained_normal_joins_centroids
else bad overlap_contained_normal_joins_centroids "$(cat "$tmp/in")"; fi

done_tests
