#!/bin/sh
# test_run.sh - `polydem run` as users and scripts call it: the result file and its contract
# (HDF5 paths, XDMF beside it), the summary line, and clear errors for bad input.
# Prints "N passed, N failed".
POLYDEM=${POLYDEM:-build/polydem}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0
ok() { passed=$((passed + 1)); echo "ok   $1"; }
bad() { failed=$((failed + 1)); echo "FAIL $1: $2"; }

# expect_fail NAME EXIT MESSAGE-FRAGMENT -- command...
expect_fail() {
    name=$1 code=$2 frag=$3
    shift 4
    "$@" >"$tmp/out" 2>"$tmp/err"
    rc=$?
    if [ "$rc" -ne "$code" ]; then bad "$name" "exit $rc, expected $code ($(cat "$tmp/err"))"
    elif ! grep -q -- "$frag" "$tmp/err"; then bad "$name" "stderr lacks '$frag': $(cat "$tmp/err")"
    else ok "$name"; fi
}

# a ball dropped on a floor, 2000 steps
cat >"$tmp/drop.json" <<'JSON'
{"name": "drop", "time": {"dt": 1e-5, "duration": 0.02, "output_interval": 0.005,
  "stats_interval": 0.001},
 "gravity": [0, 0, -9.81],
 "materials": {"m": {"density": 2500, "youngs_modulus": 1e7, "poisson_ratio": 0.25}},
 "interactions": [{"between": ["m", "m"], "friction": 0.3, "damping": 0.2}],
 "shapes": {"ball": {"sphere": {}}, "s": {"builtin": "schonhardt"}},
 "particles": [{"shape": "ball", "material": "m",
                "list": [{"position": [0, 0, 0.0101], "velocity": [0, 0, -0.5], "size": 0.02}]},
               {"shape": "s", "material": "m",
                "list": [{"position": [0.05, 0, 0.03], "velocity": [0, 0, -0.5], "size": 0.02}]}],
 "walls": [{"name": "floor", "material": "m", "box": {"min": [-1, -1, -0.1], "max": [1, 1, 0]}}],
 "output": {"fields": ["position", "orientation", "velocity", "angular_velocity"]}}
JSON

$POLYDEM run "$tmp/drop.json" -o "$tmp/drop.h5" >"$tmp/out" 2>"$tmp/err"
rc=$?
if [ "$rc" -eq 0 ] && grep -q "drop.h5: 2000 steps" "$tmp/out" && grep -q "kinetic energy" "$tmp/out"; then
    ok run_summary
else bad run_summary "exit $rc: $(cat "$tmp/out" "$tmp/err")"; fi
if [ -f "$tmp/drop.h5" ] && [ -f "$tmp/drop.h5.xmf" ] && [ ! -e "$tmp/drop.h5.partial" ]; then
    ok run_files
else bad run_files "$(ls "$tmp")"; fi

# the HDF5 contract (issue 3): paths and shapes other tools read
h5ls -r "$tmp/drop.h5" >"$tmp/ls" 2>&1
missing=""
for p in "/frames/position Dataset {5/Inf, 2, 3}" "/frames/orientation Dataset {5/Inf, 2, 4}" \
    "/frames/velocity Dataset {5/Inf, 2, 3}" "/frames/angular_velocity Dataset {5/Inf, 2, 3}" \
    "/frames/time Dataset {5/Inf}" "/stats/kinetic_energy Dataset {21/Inf}" \
    "/stats/contacts Dataset {21/Inf}" "/stats/broad_pairs Dataset {21/Inf}" \
    "/stats/max_overlap_ratio Dataset {21/Inf}" "/stats/wall_force/floor Dataset {21/Inf, 3}" \
    "/stats/wall_time Dataset {21/Inf}" "/stats/stage_time/integrate Dataset {21/Inf}" \
    "/stats/stage_time/bvh Dataset {21/Inf}" "/stats/stage_time/traverse Dataset {21/Inf}" \
    "/stats/stage_time/contacts Dataset {21/Inf}" "/stats/stage_time/gather Dataset {21/Inf}" \
    "/particles/mass Dataset {2}" "/particles/shape Dataset {2}" "/shapes/ball/vertices" \
    "/shapes/s/triangles" "/walls/floor/vertices"; do
    tr -s ' ' <"$tmp/ls" | grep -qF "$p" || missing="$missing [$p]"
done
if [ -z "$missing" ]; then ok result_contract_paths; else bad result_contract_paths "missing$missing"; fi
if h5dump -a /format "$tmp/drop.h5" 2>/dev/null | grep -q '"polydem-result"'; then
    ok result_format_attribute
else bad result_format_attribute "$(h5dump -a /format "$tmp/drop.h5" 2>&1 | head -5)"; fi
if xmllint --noout "$tmp/drop.h5.xmf" 2>"$tmp/x"; then ok xdmf_well_formed; else bad xdmf_well_formed "$(cat "$tmp/x")"; fi

# ParaView shows the polyhedra's shapes by default (issue 3): with a polyhedron in the scene every
# particle's surface is written per frame (a sphere's 80-triangle icosphere has 42 vertices, the
# Schonhardt prism 6) and the XDMF file draws it; --no-meshes leaves points only, and so does a
# scene of spheres alone. `validate --json` predicts the frames and the bytes.
if tr -s ' ' <"$tmp/ls" | grep -qF "/xdmf/vertices Dataset {5/Inf, 48, 3}" &&
    grep -q "xdmf/vertices" "$tmp/drop.h5.xmf"; then
    ok meshes_written_by_default
else bad meshes_written_by_default "$(grep xdmf "$tmp/ls")"; fi
$POLYDEM validate "$tmp/drop.json" --json >"$tmp/v" 2>&1
if python3 -c 'import json,sys; d = json.load(open(sys.argv[1]))
sys.exit(not (d["frames"] == 5 and d["mesh_view_bytes"] == 5 * 48 * 3 * 8 and d["mesh_view_default"] is True))' "$tmp/v"; then
    ok validate_predicts_frames_and_meshes
else bad validate_predicts_frames_and_meshes "$(cat "$tmp/v")"; fi
$POLYDEM run "$tmp/drop.json" -o "$tmp/nomesh.h5" --quiet --no-meshes >"$tmp/out" 2>&1
if [ $? -eq 0 ] && ! h5ls -r "$tmp/nomesh.h5" | grep -q "/xdmf/vertices" && ! grep -q "xdmf/vertices" "$tmp/nomesh.h5.xmf"; then
    ok no_meshes_flag
else bad no_meshes_flag "$(cat "$tmp/out"; h5ls -r "$tmp/nomesh.h5" | grep xdmf)"; fi
python3 -c 'import json,sys; d = json.load(open(sys.argv[1])); d["particles"] = d["particles"][:1]
json.dump(d, open(sys.argv[2], "w"))' "$tmp/drop.json" "$tmp/balls.json"
$POLYDEM run "$tmp/balls.json" -o "$tmp/balls.h5" --quiet >"$tmp/out" 2>&1
if [ $? -eq 0 ] && ! h5ls -r "$tmp/balls.h5" | grep -q "/xdmf/vertices"; then
    ok spheres_alone_are_points
else bad spheres_alone_are_points "$(cat "$tmp/out"; h5ls -r "$tmp/balls.h5" | grep xdmf)"; fi

# the same scenario run twice, in two processes, gives bit-identical frames and physics rows
# (issue 3: deterministic gather, no floating-point atomics); only the wall-clock rows differ
$POLYDEM run "$tmp/drop.json" -o "$tmp/again.h5" --quiet >"$tmp/out" 2>&1
same=""
for obj in /frames /stats/kinetic_energy /stats/contacts /stats/broad_pairs /stats/max_overlap_ratio \
    /stats/wall_force/floor /xdmf/vertices; do
    h5diff "$tmp/drop.h5" "$tmp/again.h5" "$obj" "$obj" >"$tmp/d" 2>&1 || same="$same [$obj: $(head -3 "$tmp/d")]"
done
if [ -z "$same" ]; then ok reruns_bit_identical_across_processes; else bad reruns_bit_identical_across_processes "$same"; fi

# while the ball is on the floor (it lands at once and bounces off within ~1 ms at 0.5 m/s),
# the force it exerts on the floor, as a load cell in the floor reads it, points down
h5dump -d /stats/wall_force/floor -s "1,0" -c "1,3" "$tmp/drop.h5" >"$tmp/wf" 2>&1
fz=$(sed -n 's/^ *(1,0): *\([^,]*\), *\([^,]*\), *\([^ ,]*\).*/\3/p' "$tmp/wf")
mass=$(h5dump -d /particles/mass "$tmp/drop.h5" | sed -n 's/^ *(0): *\([^,]*\), *\([^ ,]*\).*/\1 \2/p')
if awk -v f="$fz" -v m="$mass" 'BEGIN { split(m, a, " "); w = (a[1] + a[2]) * 9.81; exit !(f < -w) }'; then
    ok wall_force_points_down
else bad wall_force_points_down "Fz '$fz' masses '$mass'"; fi

# per-stage times: each row times the one step that ends at it (the first row, the initial force
# evaluation), so the stages are non-negative, sum to more than zero, and fit in the wall-clock
# interval since the previous row. With a row every step, times carried over from earlier steps
# (not reset per row) overflow that interval within a few rows.
sed -e 's/"duration": 0.02/"duration": 0.0005/' -e 's/"stats_interval": 0.001/"stats_interval": 1e-5/' \
    -e 's/"output_interval": 0.005/"output_interval": 0.0005/' "$tmp/drop.json" >"$tmp/every.json"
$POLYDEM run "$tmp/every.json" -o "$tmp/every.h5" --quiet >"$tmp/out" 2>&1 || cat "$tmp/out"
column() { h5dump -m %.17g -y -w 0 -d "$1" "$tmp/every.h5" | awk '/DATA \{/ { getline; gsub(/,/, " "); print; exit }'; }
{
    column /stats/wall_time
    for st in integrate bvh traverse contacts gather; do column "/stats/stage_time/$st"; done
} >"$tmp/stages"
if awk 'NR == 1 { for (i = 1; i <= NF; i++) wt[i] = $i; n = NF; next }
        { if (NF != n) bad = "rows " NF " != " n
          for (i = 1; i <= NF; i++) { if ($i < 0) bad = "negative time"; sum[i] += $i } }
        END { for (i = 1; i <= n && !bad; i++) {
                  span = i == 1 ? wt[1] : wt[i] - wt[i - 1]
                  if (!(sum[i] > 0)) bad = "row " i - 1 ": stages sum to 0"
                  else if (sum[i] > span) bad = "row " i - 1 ": stages " sum[i] " s > interval " span " s" }
              if (n != 51) bad = bad " " n " rows"
              if (bad) { print bad; exit 1 } }' "$tmp/stages" >"$tmp/why"; then
    ok stage_times_per_row
else bad stage_times_per_row "$(cat "$tmp/why")"; fi

$POLYDEM run "$tmp/drop.json" -o "$tmp/q.h5" --quiet >"$tmp/out" 2>&1
if [ $? -eq 0 ] && [ ! -s "$tmp/out" ] && [ -f "$tmp/q.h5" ]; then ok run_quiet; else bad run_quiet "$(cat "$tmp/out")"; fi

# Ctrl-C (SIGINT) stops a long run: exit 130, a message saying what was kept, and the frames so
# far in the result, whose root attribute status says "cancelled"
sed 's/"duration": 0.02/"duration": 1000/' "$tmp/drop.json" >"$tmp/long.json"
$POLYDEM run "$tmp/long.json" -o "$tmp/long.h5" >"$tmp/out" 2>"$tmp/err" &
pid=$!
i=0
while [ ! -e "$tmp/long.h5.partial" ] && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
sleep 1
kill -INT "$pid"
wait "$pid"
rc=$?
st=$(h5dump -a /status "$tmp/long.h5" 2>&1 | sed -n 's/^ *(0): "\(.*\)"$/\1/p')
nf=$(h5dump -H -d /frames/time "$tmp/long.h5" 2>&1 | sed -n 's/.*SIMPLE { ( \([0-9]*\) ).*/\1/p')
if [ "$rc" -eq 130 ] && [ "$st" = cancelled ] && [ "${nf:-0}" -ge 1 ] && [ -f "$tmp/long.h5.xmf" ] &&
    [ ! -e "$tmp/long.h5.partial" ] && grep -q "kept the $nf frame" "$tmp/err"; then
    ok ctrl_c_keeps_frames
else bad ctrl_c_keeps_frames "exit $rc, status '$st', $nf frames: $(cat "$tmp/err")"; fi

# bad input: a message naming the flag, file or field; 2 for usage, 1 for a scenario or run
expect_fail no_output 2 "-o" -- $POLYDEM run "$tmp/drop.json"
expect_fail no_scenario 2 "scenario file" -- $POLYDEM run -o "$tmp/x.h5"
expect_fail unknown_option 2 "--fast" -- $POLYDEM run "$tmp/drop.json" -o "$tmp/x.h5" --fast
expect_fail bad_device_number 2 "--device" -- $POLYDEM run "$tmp/drop.json" -o "$tmp/x.h5" --device x
expect_fail missing_device 2 "device 99" -- $POLYDEM run "$tmp/drop.json" -o "$tmp/x.h5" --device 99
expect_fail missing_scenario 1 "nope.json" -- $POLYDEM run "$tmp/nope.json" -o "$tmp/x.h5"
sed 's/"dt": 1e-5/"dt": -1/' "$tmp/drop.json" >"$tmp/bad.json"
expect_fail invalid_scenario 1 "/time/dt" -- $POLYDEM run "$tmp/bad.json" -o "$tmp/x.h5"
expect_fail unwritable_output 1 "/nonexistent/dir/x.h5" -- $POLYDEM run "$tmp/drop.json" -o /nonexistent/dir/x.h5
if [ ! -e "$tmp/x.h5" ] && [ ! -e "$tmp/x.h5.partial" ]; then ok no_result_after_errors; else bad no_result_after_errors "$(ls "$tmp")"; fi

# physically sound runs are not stopped as "diverged" (QA 2026-12-02: the runaway bound took the
# scene's height from the particles' centres alone and ignored time fallen, flows and stored
# overlaps): one ball dropped 0.5 m onto a floor (the bound allowed 3.5 cm), and one starting
# 1 mm into the floor with no gravity (pushed out from energy the overlap stores)
cat >"$tmp/fall.json" <<'JSON'
{"name": "fall", "time": {"dt": 2e-5, "duration": 0.4, "output_interval": 0.1},
 "materials": {"m": {"density": 1000, "youngs_modulus": 1e7},
               "s": {"density": 7800, "youngs_modulus": 2e11, "poisson_ratio": 0.3}},
 "interactions": [{"between": ["m", "m"]}, {"between": ["m", "s"], "damping": 0.5}],
 "shapes": {"b": {"sphere": {}}},
 "particles": [{"shape": "b", "material": "m", "list": [{"position": [0, 0, 0.5], "size": 0.05}]}],
 "walls": [{"name": "floor", "material": "s", "box": {"min": [-1, -1, -0.1], "max": [1, 1, 0]}}]}
JSON
$POLYDEM run "$tmp/fall.json" -o "$tmp/fall.h5" --quiet >"$tmp/out" 2>&1
check_rc=$?
if [ "$check_rc" -eq 0 ]; then ok long_fall_is_not_divergence; else bad long_fall_is_not_divergence "exit $check_rc: $(cat "$tmp/out")"; fi
sed -e 's/"duration": 0.4/"duration": 0.01/' -e 's/"output_interval": 0.1/"output_interval": 0.005/' \
    -e 's/"position": \[0, 0, 0.5\], "size": 0.05/"position": [0, 0, 0.024], "size": 0.05/' \
    -e 's/"name": "fall", /"name": "push", "gravity": [0, 0, 0], /' "$tmp/fall.json" >"$tmp/push.json"
$POLYDEM run "$tmp/push.json" -o "$tmp/push.h5" --quiet >"$tmp/out" 2>&1
check_rc=$?
if [ "$check_rc" -eq 0 ]; then ok overlap_push_is_not_divergence; else bad overlap_push_is_not_divergence "exit $check_rc: $(cat "$tmp/out")"; fi

# a full disk (a small tmpfs; needs root to mount, skipped otherwise): the error names it and the
# run exits 1 (HDF5's exit-time clean-up of the file it could not close used to segfault: 139);
# when it fills after some frames, those are kept in the .partial; when only the XDMF file does
# not fit, the complete result is kept
mkdir -p "$tmp/small"
if mount -t tmpfs -o size=100k tmpfs "$tmp/small" 2>/dev/null; then
    sed -e 's/"output_interval": 0.1/"output_interval": 0.0004/' "$tmp/fall.json" >"$tmp/frames.json"
    $POLYDEM run "$tmp/frames.json" -o "$tmp/small/r.h5" --quiet >"$tmp/out" 2>&1
    rc=$?
    if [ "$rc" -eq 1 ] && grep -q "No space left on device" "$tmp/out"; then ok disk_full_is_an_error_not_a_crash
    else bad disk_full_is_an_error_not_a_crash "exit $rc: $(cat "$tmp/out")"; fi
    umount "$tmp/small"
    # the disk fills after some frames: the frames so far are kept in the .partial (not renamed:
    # it is incomplete), which the error names with their count and last time; every dataset of
    # /frames holds exactly that many whole frames and every /stats column the same rows
    mount -t tmpfs -o size=150k tmpfs "$tmp/small"
    $POLYDEM run "$tmp/frames.json" -o "$tmp/small/r.h5" --quiet >"$tmp/out" 2>&1
    rc=$?
    kept=$(sed -n "s/.*No space left on device.*; the \([0-9]*\) frames up to t = \([0-9.e-]*\) s are kept in '.*small\/r\.h5\.partial'.*/\1 \2/p" "$tmp/out")
    n=${kept%% *}
    h5ls -r "$tmp/small/r.h5.partial" >"$tmp/ls" 2>&1
    rows() { sed -n "s|^$1 *Dataset {\([0-9]*\)/Inf.*|\1|p" "$tmp/ls"; }
    st=$(rows /stats/time)
    shapes="$(rows /frames/time) $(rows /frames/step) $(rows /frames/position) $(rows /frames/orientation)"
    shapes="$shapes $(rows /frames/velocity) $(rows /frames/angular_velocity)"
    want="$n $n $n $n $n $n"
    stats="$(rows /stats/kinetic_energy) $(rows /stats/contacts) $(rows /stats/wall_force/floor)"
    last=$(h5dump -d /frames/time -s $((${n:-1} - 1)) -c 1 "$tmp/small/r.h5.partial" 2>/dev/null |
        sed -n 's/^ *([0-9]*): \([0-9.e-]*\)$/\1/p')
    if [ "$rc" -eq 1 ] && [ -n "$n" ] && [ "$n" -ge 2 ] && [ ! -e "$tmp/small/r.h5" ] &&
        [ "$shapes" = "$want" ] && [ -n "$st" ] && [ "$stats" = "$st $st $st" ] &&
        h5dump "$tmp/small/r.h5.partial" >/dev/null 2>&1 &&
        awk -v a="$last" -v b="${kept#* }" 'BEGIN { exit !(a != "" && a - b < 1e-9 && b - a < 1e-9) }'; then
        ok disk_full_keeps_frames_so_far
    else bad disk_full_keeps_frames_so_far "exit $rc, kept '$kept', frames '$shapes', stats '$st' '$stats', last time '$last': $(cat "$tmp/out"; ls -l "$tmp/small")"; fi
    umount "$tmp/small"
    sed -e 's/"duration": 0.4/"duration": 0.02/' -e 's/"output_interval": 0.1/"output_interval": 0.0002/' \
        "$tmp/fall.json" >"$tmp/frames.json"
    mount -t tmpfs -o size=300k tmpfs "$tmp/small"
    $POLYDEM run "$tmp/frames.json" -o "$tmp/small/r.h5" --quiet >"$tmp/out" 2>&1
    rc=$?
    st=$(h5dump -a /status "$tmp/small/r.h5" 2>&1 | sed -n 's/^ *(0): "\(.*\)"$/\1/p')
    if [ "$rc" -eq 1 ] && [ "$st" = complete ] && grep -q "complete and kept" "$tmp/out"; then ok result_kept_without_its_xmf
    else bad result_kept_without_its_xmf "exit $rc, status '$st': $(cat "$tmp/out"; ls -l "$tmp/small")"; fi
    umount "$tmp/small"
else
    echo "skip disk_full tests: cannot mount a tmpfs (needs root)"
fi

# a moving wall is recorded where it is at each frame (/walls/<name>/frame_vertices) and shown
# there in the XDMF file: a ball riding a platform that rises at 0.5 m/s sits on the platform's
# recorded top at every frame: its centre one radius above it less the Hertz overlap under its
# weight, delta = (m g / (4/3 E* sqrt(R)))^(2/3) = 2.75e-5 m (E* = E / (2 (1 - nu^2))), once the
# damped contact has settled (frames 1 and 2; frame 0 is the touching start), to 5 % of delta;
# a fixed wall has no frame_vertices
cat >"$tmp/lift.json" <<'JSON'
{"name": "lift", "time": {"dt": 1e-5, "duration": 0.1, "output_interval": 0.05},
 "materials": {"m": {"density": 2500, "youngs_modulus": 1e7}},
 "interactions": [{"between": ["m", "m"], "damping": 0.5}],
 "shapes": {"ball": {"sphere": {}}},
 "particles": [{"shape": "ball", "material": "m",
                "list": [{"position": [0, 0, 0.01], "velocity": [0, 0, 0.5], "size": 0.02}]}],
 "walls": [{"name": "platform", "material": "m", "box": {"min": [-0.1, -0.1, -0.02], "max": [0.1, 0.1, 0]},
            "velocity": [0, 0, 0.5]},
           {"name": "ground", "material": "m", "box": {"min": [-1, -1, -1], "max": [1, 1, -0.5]}}]}
JSON
$POLYDEM run "$tmp/lift.json" -o "$tmp/lift.h5" --quiet >"$tmp/out" 2>&1
rc=$?
h5get() { h5dump -m %.17g -w 0 -d "$1" "$tmp/lift.h5" | awk '/DATA \{/ {on = 1; next} on && /\}/ {exit} on {sub(/^ *\([^)]*\): */, ""); gsub(/,/, " "); printf "%s ", $0}'; }
zs=$(h5get /frames/position)
tops=$(h5get /walls/platform/frame_vertices)
res=$(echo "$zs|$tops" | awk -F'|' '{
    n = split($1, p, " "); m = split($2, v, " ");
    if (n != 9 || m != 72) { print "bad sizes " n " " m; exit }
    worst = 0
    for (f = 0; f < 3; f++) {
        top = -1e9; for (k = 0; k < 8; k++) { z = v[f * 24 + 3 * k + 3]; if (z > top) top = z }
        want = 0.5 * 0.05 * f; if (top - want > 1e-12 || want - top > 1e-12) { print "top " top " at frame " f; exit }
        m = 2500 * 3.141592653589793 / 6 * 0.02 ^ 3; es = 1e7 / (2 * (1 - 0.25 ^ 2))
        delta = f ? (m * 9.81 / (4 / 3 * es * sqrt(0.01))) ^ (2 / 3) : 0
        d = p[3 * f + 3] - (top + 0.01 - delta); if (d < 0) d = -d; if (d > worst) worst = d
    }
    print (worst < 0.05 * 2.75e-5 ? "ok" : "off by " worst) }')
if [ "$rc" -eq 0 ] && [ "$res" = ok ] && ! h5ls "$tmp/lift.h5/walls/ground/frame_vertices" >/dev/null 2>&1 &&
    grep -q 'lift.h5:/walls/platform/frame_vertices|2 0 0:1 1 1:1 8 3:3 8 3' "$tmp/lift.h5.xmf" &&
    [ "$(grep -c '<Grid Name="ground"' "$tmp/lift.h5.xmf")" -eq 3 ]; then
    ok moving_wall_frames
else bad moving_wall_frames "exit $rc, $res: $(cat "$tmp/out")"; fi

# -o must never destroy what the scenario was read from: the scenario itself (also through a
# symbolic link, or as the .xmf written beside the result) and its mesh files; each is refused
# before any work and left as it was
mkdir "$tmp/in"
cp "$tmp/drop.json" "$tmp/in/self.json"
expect_fail output_is_scenario 1 "would overwrite" -- $POLYDEM run "$tmp/in/self.json" -o "$tmp/in/self.json"
ln -s self.json "$tmp/in/link.h5"
expect_fail output_links_to_scenario 1 "would overwrite" -- $POLYDEM run "$tmp/in/self.json" -o "$tmp/in/link.h5"
cp "$tmp/drop.json" "$tmp/in/r.h5.xmf"
expect_fail output_xmf_is_scenario 1 "would overwrite" -- $POLYDEM run "$tmp/in/r.h5.xmf" -o "$tmp/in/r.h5"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >"$tmp/in/tet.obj"
sed 's/"s": {"builtin": "schonhardt"}/"s": {"mesh": "tet.obj"}/' "$tmp/drop.json" >"$tmp/in/tet.json"
expect_fail output_is_mesh 1 "tet.obj" -- $POLYDEM run "$tmp/in/tet.json" -o "$tmp/in/tet.obj"
if cmp -s "$tmp/drop.json" "$tmp/in/self.json" && cmp -s "$tmp/drop.json" "$tmp/in/r.h5.xmf" &&
    [ "$(head -c 7 "$tmp/in/tet.obj")" = "v 0 0 0" ] && [ ! -e "$tmp/in/r.h5" ]; then
    ok inputs_left_intact
else bad inputs_left_intact "$(ls -l "$tmp/in")"; fi
mkdir "$tmp/outdir"
expect_fail output_is_directory 1 "is a directory" -- $POLYDEM run "$tmp/drop.json" -o "$tmp/outdir"
# an output that exists as something other than a file would be replaced by the result: root
# running `-o /dev/null` replaced the system's /dev/null with a file. Pipes stand in for devices
# here (the same check; a regression must not cost the test machine its /dev/null).
mkfifo "$tmp/pipe.h5" "$tmp/x.h5.xmf"
expect_fail output_is_a_pipe 1 "'$tmp/pipe.h5' is a pipe, not a regular file" -- \
    $POLYDEM run "$tmp/drop.json" -o "$tmp/pipe.h5"
expect_fail output_xmf_is_a_pipe 1 "x.h5.xmf' is a pipe" -- $POLYDEM run "$tmp/drop.json" -o "$tmp/x.h5"
if [ -p "$tmp/pipe.h5" ] && [ -p "$tmp/x.h5.xmf" ] && [ ! -e "$tmp/x.h5" ]; then ok pipes_left_alone
else bad pipes_left_alone "$(ls -l "$tmp")"; fi

# two runs writing the same result: the second is refused and leaves the first's file alone (it
# used to truncate the first's .partial, then remove it on its own failure)
$POLYDEM run "$tmp/long.json" -o "$tmp/same.h5" >"$tmp/out1" 2>"$tmp/err1" &
pid=$!
i=0
while [ ! -e "$tmp/same.h5.partial" ] && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
sleep 0.5
expect_fail second_run_same_output 1 "another run is writing" -- $POLYDEM run "$tmp/drop.json" -o "$tmp/same.h5"
partial_kept=0
[ -s "$tmp/same.h5.partial" ] && partial_kept=1
kill -INT "$pid"
wait "$pid"
rc=$?
st=$(h5dump -a /status "$tmp/same.h5" 2>&1 | sed -n 's/^ *(0): "\(.*\)"$/\1/p')
if [ "$partial_kept" -eq 1 ] && [ "$rc" -eq 130 ] && [ "$st" = cancelled ]; then
    ok first_run_keeps_its_result
else bad first_run_keeps_its_result "partial kept $partial_kept, exit $rc, status '$st': $(cat "$tmp/err1")"; fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
