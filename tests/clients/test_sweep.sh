#!/bin/sh
# test_sweep.sh - clients/sweep.sh: bad input is refused with a message naming the option (no
# daemon needed), then a 2x2 grid end to end against a real polydemd that wants a token: the
# CSV's header, one row per job with its parameters, every job succeeded and tagged with the
# sweep id; a missing token, a refused grid point and a mesh file.
# Prints "N passed, N failed".
# shellcheck source=tests/clients/lib.sh
. tests/clients/lib.sh
SWEEP=clients/sweep.sh

expect_refusal() { # NAME WANT_EXIT WANT_TEXT ARGS...
    name=$1 want=$2 text=$3
    shift 3
    timeout 20 bash "$SWEEP" "$@" >"$tmp/out" 2>"$tmp/err"
    rc=$?
    if [ "$rc" = "$want" ] && grep -q -- "$text" "$tmp/err"; then
        ok "$name"
    else
        bad "$name" "expected exit $want and '$text' on stderr, got exit $rc: $(head -c 300 "$tmp/err")"
    fi
}

quick_scenario "$tmp/quick.json"
dead="http://127.0.0.1:$(free_port)"
expect_refusal unknown_option 2 "unknown option '--frobnicate'" --frobnicate "$tmp/quick.json"
expect_refusal set_without_pointer 2 "expected POINTER=V1,V2" "$tmp/quick.json" --set 'friction=0.2'
expect_refusal set_without_values 2 "no values after '='" "$tmp/quick.json" --set '/interactions/0/friction='
expect_refusal set_empty_value 2 "empty value" "$tmp/quick.json" --set '/interactions/0/friction=0.1,,0.2'
expect_refusal set_missing_path 2 "no member \"nope\"" "$tmp/quick.json" --set '/nope/x=1'
expect_refusal set_bad_index 2 "index 7 is outside" "$tmp/quick.json" --set '/interactions/7/friction=1'
expect_refusal no_set 2 "no --set given" "$tmp/quick.json"
expect_refusal missing_file 2 "cannot read scenario file" "$tmp/nothere.json" --set '/seed=1'
expect_refusal bad_server_url 2 "--server 'localhost:1'" --server localhost:1 "$tmp/quick.json" --set '/seed=1'
expect_refusal unreachable_server 3 "cannot reach $dead" --server "$dead" "$tmp/quick.json" --set '/seed=1,2'
expect_refusal bad_poll 2 "--poll '.'" --poll . "$tmp/quick.json" --set '/seed=1'
expect_refusal bad_priority 2 "--priority '-': expected an integer" --priority - "$tmp/quick.json" --set '/seed=1'
expect_refusal out_unwritable 2 "--out '/nonexistent/x.csv'" --server "$dead" --out /nonexistent/x.csv \
    "$tmp/quick.json" --set '/seed=1'

TOKEN="sweep-test-token-0123456789"
echo "$TOKEN tester" >"$tmp/tokens"
POLYDEMD_ARGS="--tokens $tmp/tokens"
if start_daemon; then
    export POLYDEM_TOKEN="$TOKEN" # sweep.sh's default for --token
    expect_refusal token_needed 3 "refused the token (401)" --server "$URL" --token '' "$tmp/quick.json" \
        --set '/seed=1'
    start=$(date +%s)
    timeout 150 bash "$SWEEP" --server "$URL" "$tmp/quick.json" \
        --set '/interactions/0/friction=0.2,0.4' --set '/materials/rock/youngs_modulus=1e7,2e7' \
        --out "$tmp/sweep.csv" --poll 0.3 2>"$tmp/sweep.err"
    rc=$?
    echo "   (sweep took $(($(date +%s) - start)) s)"
    check sweep_exit_status 0 "$rc"
    [ "$rc" = 0 ] || sed 's/^/   | /' "$tmp/sweep.err" | tail -n 15
    check csv_header "job_id,/interactions/0/friction,/materials/rock/youngs_modulus,status,final_kinetic_energy_J,peak_contacts,peak_wall_force_N" \
        "$(head -n 1 "$tmp/sweep.csv" 2>/dev/null)"
    check csv_rows 4 "$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | grep -c .)"
    check csv_grid "0.2,1e7 0.2,2e7 0.4,1e7 0.4,2e7" \
        "$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | cut -d, -f2,3 | tr '\n' ' ' | sed 's/ $//')"
    check csv_all_succeeded "succeeded succeeded succeeded succeeded" \
        "$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | cut -d, -f4 | tr '\n' ' ' | sed 's/ $//')"
    check csv_distinct_job_ids 4 "$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | cut -d, -f1 | grep . | sort -u | wc -l | tr -d ' ')"
    # final kinetic energy: a number >= 0 J (two particles at 1 m/s: about 2 * 0.5 m v^2 ~ 1e-2 J)
    bad_ke=$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | cut -d, -f5 |
        awk '!($1 ~ /^[0-9.eE+-]+$/ && $1 + 0 >= 0 && $1 + 0 < 1) { n++ } END { print n + 0 }')
    check csv_kinetic_energy_numbers 0 "$bad_ke"
    bad_contacts=$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | cut -d, -f6 | grep -cvE '^[0-9]+$')
    check csv_peak_contacts_integers 0 "$bad_contacts"
    check csv_no_walls_no_force "" "$(tail -n +2 "$tmp/sweep.csv" 2>/dev/null | cut -d, -f7 | tr -d '\n')"
    sweep_id=$(sed -n 's/^sweep\.sh: \(sweep-[0-9a-f-]*\): submitting.*/\1/p' "$tmp/sweep.err")
    n=$(curl -s --max-time 10 -H "Authorization: Bearer $TOKEN" "$URL/v1/jobs?tag=$sweep_id" |
        jq '(.jobs // .) | length' 2>/dev/null)
    check jobs_tagged_with_sweep_id 4 "$n"
    if grep -q '4/4 succeeded' "$tmp/sweep.err"; then ok progress_on_stderr; else
        bad progress_on_stderr "no '4/4 succeeded' line: $(tail -n 2 "$tmp/sweep.err")"; fi
    # mesh files named by path are uploaded once and the jobs name them by id
    mkdir -p "$tmp/withmesh"
    cube_obj "$tmp/withmesh/cube.obj"
    jq '.shapes.r = {"mesh": "cube.obj"}' "$tmp/quick.json" >"$tmp/withmesh/scenario.json"
    timeout 100 bash "$SWEEP" --server "$URL" "$tmp/withmesh/scenario.json" --set '/seed=1' \
        --out "$tmp/mesh.csv" --poll 0.3 2>"$tmp/mesh.err"
    rc=$?
    if [ "$rc" = 0 ] && grep -q "uploaded .*cube.obj as sha256:" "$tmp/mesh.err"; then ok mesh_file_uploaded; else
        bad mesh_file_uploaded "exit $rc: $(tail -n 3 "$tmp/mesh.err")"; fi
    # a refused grid point gets its row and a message; the others go on
    timeout 150 bash "$SWEEP" --server "$URL" "$tmp/quick.json" --set '/interactions/0/friction=0.3,-1' \
        --out "$tmp/mixed.csv" --poll 0.3 2>"$tmp/mixed.err"
    rc=$?
    check refused_point_exit_status 1 "$rc"
    check refused_point_rows "succeeded rejected" \
        "$(tail -n +2 "$tmp/mixed.csv" 2>/dev/null | cut -d, -f3 | tr '\n' ' ' | sed 's/ $//')"
    if grep -q '/interactions/0/friction' "$tmp/mixed.err"; then ok refused_point_message; else
        bad refused_point_message "stderr does not name the field: $(head -c 300 "$tmp/mixed.err")"; fi
    # a misspelled member fits the scenario (a pointer's last member may be new) but no grid
    # point passes the daemon's dry run: exit 2 with its message, nothing submitted
    before=$(api "/v1/jobs?limit=1000" | jq '.jobs | length')
    expect_refusal misspelled_member 2 "frictoin: unknown field" --server "$URL" "$tmp/quick.json" \
        --set '/interactions/0/frictoin=0.2,0.3'
    check misspelled_member_submits_nothing "$before" "$(api "/v1/jobs?limit=1000" | jq '.jobs | length')"
    # a swept mesh path is uploaded after the value is put in
    mkdir -p "$tmp/withmesh/sub"
    cube_obj "$tmp/withmesh/sub/cube.obj"
    timeout 100 bash "$SWEEP" --server "$URL" "$tmp/withmesh/scenario.json" --set '/shapes/r/mesh=sub/cube.obj' \
        --out "$tmp/mesh2.csv" --poll 0.3 2>"$tmp/mesh2.err"
    rc=$?
    if [ "$rc" = 0 ] && grep -q "uploaded .*sub/cube.obj as sha256:" "$tmp/mesh2.err"; then ok mesh_path_swept; else
        bad mesh_path_swept "exit $rc: $(tail -n 3 "$tmp/mesh2.err")"; fi
    # a job that fails: its row says failed and stderr gives the job's error (a diverging run)
    jq '.allow_unstable_dt = true | .materials.rock.youngs_modulus = 1e11 | .time.dt = 2e-4
        | .time.duration = 0.2 | .time.output_interval = 0.002 | .particles[0].list[0].velocity = [3, 0, 0]' \
        "$tmp/quick.json" >"$tmp/diverge.json"
    timeout 100 bash "$SWEEP" --server "$URL" "$tmp/diverge.json" --set '/seed=1' --out "$tmp/div.csv" \
        --poll 0.3 2>"$tmp/div.err"
    rc=$?
    if [ "$rc" = 1 ] && grep -q "failed: run diverged" "$tmp/div.err"; then ok failed_job_error_shown; else
        bad failed_job_error_shown "expected exit 1 and the job's error, got $rc: $(tail -n 3 "$tmp/div.err")"; fi
    # interrupted (SIGTERM; a background job here ignores SIGINT) behind a running job: the CSV
    # with the statuses so far, exit 143, and a command that cancels the jobs left
    long=$(long_job_running)
    interrupted_sweep interrupted bash "$SWEEP" --server "$URL" "$tmp/quick.json" --set '/seed=1,2' \
        --poll 0.3
    hint=$(grep '^  for id in ' "$tmp/int.err")
    if [ -n "$hint" ] && bash -c "$hint" >"$tmp/cancel.out" 2>&1 && [ "$(grep -c '"status"' "$tmp/cancel.out")" = 2 ]; then
        ok interrupted_says_how_to_cancel; else
        bad interrupted_says_how_to_cancel "no working cancel command: $(tail -n 3 "$tmp/int.err") -> $(cat "$tmp/cancel.out")"; fi
    check interrupted_jobs_cancelled "cancelled cancelled" \
        "$(api "/v1/jobs?tag=$sid" | jq -r '[.jobs[].status] | join(" ")')"
    # interrupted while the answer to a submission is on its way (a proxy holds every answer 2 s):
    # the server has made the job but the sweep has not read its id; the row must still say
    # queued (not unsubmitted) and the cancel command must name the job, which would run on
    held_answers_proxy
    in_flight_sweep bash "$SWEEP" --server "$proxy_url" "$tmp/quick.json" --set '/seed=3' --poll 0.3
    check interrupted_in_flight_row "143 $rid queued" \
        "$rc $(tail -n +2 "$tmp/race.csv" 2>/dev/null | cut -d, -f1,3 | tr , ' ')"
    check interrupted_in_flight_cancel_names_it true \
        "$(grep -q "^  for id in $rid; do" "$tmp/race.err" && echo true)"
    api "/v1/jobs/$rid/cancel" -o /dev/null -X POST
    api "/v1/jobs/$blocker/cancel" -o /dev/null -X POST
    api "/v1/jobs/$long/cancel" -o /dev/null -X POST
fi
summary
