#!/bin/sh
# test_python_client.sh - clients/python/polydem_client.py: its JSON pointer, value-list and
# /stats helpers and its refusals (no daemon needed), then submit, wait, download (HDF5 and
# XDMF) and a 1x2 sweep against a real polydemd. Prints "N passed, N failed".
# shellcheck source=tests/clients/lib.sh
. tests/clients/lib.sh
CLIENT=clients/python/polydem_client.py

# helpers, through the module
if python3 -B - >"$tmp/unit.out" 2>&1 <<'EOF'; then ok helpers; else bad helpers "$(tail -n 5 "$tmp/unit.out")"; fi
import sys
sys.path.insert(0, "clients/python")
import polydem_client as pc

def eq(what, want, got):
    assert want == got, "%s: expected %r, got %r" % (what, want, got)

sc = {"interactions": [{"friction": 0.5}], "materials": {"a/b": {"E": 1}}}
eq("set array member", 0.2, pc.pointer_set(sc, "/interactions/0/friction", 0.2)["interactions"][0]["friction"])
eq("original untouched", 0.5, sc["interactions"][0]["friction"])
eq("escaped key", 7, pc.pointer_set(sc, "/materials/a~1b/E", 7)["materials"]["a/b"]["E"])
eq("new last member", 0.1, pc.pointer_set(sc, "/interactions/0/damping", 0.1)["interactions"][0]["damping"])
for bad in ("/interactions/3/friction", "/nope/x", "/interactions/x/friction", "/interactions/01/friction"):
    try:
        pc.pointer_set(sc, bad, 1)
        raise AssertionError("accepted " + bad)
    except ValueError:
        pass
eq("values", [("0.2", 0.2), ("1e7", 1e7), ("linear", "linear"), ("[0, 0, -9.81]", [0, 0, -9.81]), ('"a,b"', "a,b")],
   pc.split_values('0.2, 1e7,linear,[0, 0, -9.81],"a,b"'))
eq("parse_set", ("/seed", [("1", 1), ("2", 2)]), pc.parse_set("/seed=1,2"))
for bad in ("seed=1", "/seed=", "/seed=1,,2"):
    try:
        pc.parse_set(bad)
        raise AssertionError("accepted " + bad)
    except ValueError as e:
        assert "expected POINTER=V1,V2" in str(e), str(e)
cols = {"time": [0, 1, 2], "kinetic_energy": [3.0, 2.0, 1.0], "contacts": [0, 5, 2],
        "wall_force": {"floor": [[0, 0, 1], [3, 4, 0], [0, 0, 2]], "lid": [[0, 0, 0]] * 3}}
eq("summary of columns", (1.0, 5, 5.0), pc.summarize(cols))
rows = [{"time": t, "kinetic_energy": k, "contacts": c, "wall_force": {"floor": f}}
        for t, k, c, f in zip([0, 1], [2.0, 1.5], [1, 0], [[0, 0, 6], [0, 0, 1]])]
eq("summary of rows", (1.5, 1, 6.0), pc.summarize(rows))
eq("summary without walls", (None, None, None), pc.summarize({}))
print("helpers ok")
EOF

quick_scenario "$tmp/quick.json"
dead="http://127.0.0.1:$(free_port)"
timeout 20 python3 -B "$CLIENT" --server "$dead" submit "$tmp/quick.json" >/dev/null 2>"$tmp/err"
rc=$?
if [ "$rc" = 3 ] && grep -q "cannot reach $dead" "$tmp/err"; then ok unreachable_server; else
    bad unreachable_server "expected exit 3 naming the server, got $rc: $(cat "$tmp/err")"; fi
timeout 20 python3 -B "$CLIENT" --server "$dead" sweep "$tmp/quick.json" --set 'friction=1' >/dev/null 2>"$tmp/err"
rc=$?
if [ "$rc" = 2 ] && grep -q "expected POINTER=V1,V2" "$tmp/err"; then ok bad_set_syntax; else
    bad bad_set_syntax "expected exit 2 and the form, got $rc: $(cat "$tmp/err")"; fi
timeout 20 python3 -B "$CLIENT" --server "$dead" submit "$tmp/nothere.json" >/dev/null 2>"$tmp/err"
rc=$?
if [ "$rc" = 2 ] && grep -q "cannot read scenario file" "$tmp/err"; then ok missing_file; else
    bad missing_file "expected exit 2 naming the file, got $rc: $(cat "$tmp/err")"; fi
timeout 20 python3 -B "$CLIENT" --server "$dead" --bogus wait x >/dev/null 2>"$tmp/err"
rc=$?
if [ "$rc" = 2 ] && grep -q -- "--bogus" "$tmp/err"; then ok unknown_option; else
    bad unknown_option "expected exit 2 naming --bogus, got $rc: $(cat "$tmp/err")"; fi

if start_daemon; then
    id=$(timeout 30 python3 -B "$CLIENT" --server "$URL" --timeout 120 submit "$tmp/quick.json" --tag pytest 2>"$tmp/err")
    if [ -n "$id" ]; then ok "submit -> $id"; else bad submit "no job id: $(cat "$tmp/err")"; fi
    timeout 130 python3 -B "$CLIENT" --server "$URL" --timeout 120 wait "$id" 2>"$tmp/wait.err"
    rc=$?
    check wait_exit_status 0 "$rc"
    if grep -q "$id succeeded" "$tmp/wait.err"; then ok wait_reports_progress; else
        bad wait_reports_progress "$(tail -n 3 "$tmp/wait.err")"; fi
    timeout 60 python3 -B "$CLIENT" --server "$URL" --timeout 120 download "$id" -o "$tmp/r.h5" 2>"$tmp/err"
    check download_exit_status 0 "$?"
    check download_is_hdf5 "89484446" "$(head -c 4 "$tmp/r.h5" 2>/dev/null | od -An -tx1 | tr -d ' \n')"
    if command -v h5dump >/dev/null 2>&1; then
        if h5dump -H -g /stats "$tmp/r.h5" 2>/dev/null | grep -q kinetic_energy; then
            ok download_opens_with_h5dump; else bad download_opens_with_h5dump "no /stats/kinetic_energy"; fi
    fi
    timeout 60 python3 -B "$CLIENT" --server "$URL" --timeout 120 download "$id" --xmf -o "$tmp/r.xmf" 2>"$tmp/err"
    if grep -q "<Xdmf" "$tmp/r.xmf" 2>/dev/null && grep -q ">$id.h5:/" "$tmp/r.xmf"; then ok download_xmf; else
        bad download_xmf "$(head -c 200 "$tmp/r.xmf" 2>/dev/null) $(cat "$tmp/err")"; fi
    # saved as NAME.h5.xmf, the XDMF refers to NAME.h5 (the README's pair of -o names)
    timeout 60 python3 -B "$CLIENT" --server "$URL" download "$id" --xmf -o "$tmp/r.h5.xmf" 2>"$tmp/err"
    refs=$(grep -o 'Format="HDF">[^:<]*:' "$tmp/r.h5.xmf" 2>/dev/null | sort -u | tr '\n' ' ')
    check xmf_refers_to_local_h5 'Format="HDF">r.h5: ' "$refs"
    # a partial file left by an interrupted download is completed with a Range request, If-Range
    # the ETag it started with
    head -c 1000 "$tmp/r.h5" >"$tmp/again.h5.part"
    curl -sI "$URL/v1/jobs/$id/result" | sed -n 's/^[Ee][Tt][Aa][Gg]: *//p' | tr -d '\r' >"$tmp/again.h5.part.etag"
    timeout 60 python3 -B "$CLIENT" --server "$URL" --timeout 120 download "$id" -o "$tmp/again.h5" 2>"$tmp/err"
    if cmp -s "$tmp/r.h5" "$tmp/again.h5" && [ ! -e "$tmp/again.h5.part.etag" ]; then ok download_resumes; else
        bad download_resumes "the resumed file differs or its .etag stayed: $(cat "$tmp/err")"; fi
    # a .part of another file (its ETag differs, or none was kept) is not glued to this one
    head -c 1000 /dev/zero >"$tmp/other.h5.part"
    echo '"some-other-file"' >"$tmp/other.h5.part.etag"
    timeout 60 python3 -B "$CLIENT" --server "$URL" download "$id" -o "$tmp/other.h5" 2>"$tmp/err"
    if cmp -s "$tmp/r.h5" "$tmp/other.h5"; then ok download_changed_file_starts_over; else
        bad download_changed_file_starts_over "the file differs: $(cat "$tmp/err")"; fi
    head -c 1000 /dev/zero >"$tmp/noetag.h5.part"
    timeout 60 python3 -B "$CLIENT" --server "$URL" download "$id" -o "$tmp/noetag.h5" 2>"$tmp/err"
    if cmp -s "$tmp/r.h5" "$tmp/noetag.h5"; then ok download_unknown_part_starts_over; else
        bad download_unknown_part_starts_over "the file differs: $(cat "$tmp/err")"; fi
    # a connection cut mid-transfer: exit 3, the .part kept (not renamed as if complete), and
    # the next download completes it
    python3 -B tests/clients/cutproxy.py "$port" 30000 >"$tmp/proxy.port" 2>/dev/null &
    proxy_pid=$!
    i=0
    while [ ! -s "$tmp/proxy.port" ] && [ $i -lt 50 ]; do sleep 0.1; i=$((i + 1)); done
    timeout 60 python3 -B "$CLIENT" --server "http://127.0.0.1:$(cat "$tmp/proxy.port")" download "$id" \
        -o "$tmp/cut.h5" 2>"$tmp/err"
    rc=$?
    kill "$proxy_pid" 2>/dev/null
    if [ "$rc" = 3 ] && [ ! -e "$tmp/cut.h5" ] && [ -s "$tmp/cut.h5.part" ] && grep -q "is kept" "$tmp/err"; then
        ok download_cut_keeps_part; else
        bad download_cut_keeps_part "expected exit 3, no cut.h5 and a .part, got $rc: $(cat "$tmp/err")"; fi
    timeout 60 python3 -B "$CLIENT" --server "$URL" download "$id" -o "$tmp/cut.h5" 2>"$tmp/err"
    if cmp -s "$tmp/r.h5" "$tmp/cut.h5"; then ok download_cut_then_resumed; else
        bad download_cut_then_resumed "the file differs: $(cat "$tmp/err")"; fi
    # -o must name a file in an existing directory: a message and exit 2, no traceback, no .part
    mkdir -p "$tmp/dir"
    timeout 20 python3 -B "$CLIENT" --server "$URL" download "$id" -o "$tmp/dir/" 2>"$tmp/err"
    rc=$?
    if [ "$rc" = 2 ] && grep -q "is a directory" "$tmp/err" && [ -z "$(ls -A "$tmp/dir")" ]; then ok download_to_directory; else
        bad download_to_directory "expected exit 2 and an empty directory, got $rc: $(cat "$tmp/err")"; fi
    timeout 20 python3 -B "$CLIENT" --server "$URL" download "$id" -o /nonexistent/dir/x.h5 2>"$tmp/err"
    rc=$?
    if [ "$rc" = 2 ] && grep -q "no such directory" "$tmp/err" && ! grep -q Traceback "$tmp/err"; then
        ok download_missing_directory; else
        bad download_missing_directory "expected exit 2 naming the directory, got $rc: $(cat "$tmp/err")"; fi
    timeout 150 python3 -B "$CLIENT" --server "$URL" --timeout 120 sweep "$tmp/quick.json" --set '/interactions/0/damping=0,0.2' --poll 0.3 \
        >"$tmp/sweep.csv" 2>"$tmp/sweep.err"
    check sweep_exit_status 0 "$?"
    check sweep_header "job_id,/interactions/0/damping,status,final_kinetic_energy_J,peak_contacts,peak_wall_force_N" \
        "$(head -n 1 "$tmp/sweep.csv")"
    check sweep_rows "0,succeeded 0.2,succeeded" \
        "$(tail -n +2 "$tmp/sweep.csv" | cut -d, -f2,3 | tr '\n' ' ' | sed 's/ $//')"
    timeout 30 python3 -B "$CLIENT" --server "$URL" --timeout 120 submit "$tmp/nothere.json" >/dev/null 2>&1
    check missing_file_with_daemon 2 "$?"
    # refused before anything is submitted: an --out that cannot be written, a member the
    # scenario contract does not know (the pointer fits: its last member may be new)
    before=$(api "/v1/jobs?limit=1000" | jq '.jobs | length')
    timeout 30 python3 -B "$CLIENT" --server "$URL" sweep "$tmp/quick.json" --set '/interactions/0/damping=0,0.2' \
        --out /nonexistent/x.csv >/dev/null 2>"$tmp/err"
    rc=$?
    if [ "$rc" = 2 ] && grep -q "/nonexistent/x.csv" "$tmp/err"; then ok sweep_out_unwritable; else
        bad sweep_out_unwritable "expected exit 2 naming the file, got $rc: $(cat "$tmp/err")"; fi
    timeout 30 python3 -B "$CLIENT" --server "$URL" sweep "$tmp/quick.json" --set '/interactions/0/frictoin=0.2,0.3' \
        >/dev/null 2>"$tmp/err"
    rc=$?
    if [ "$rc" = 2 ] && grep -q "frictoin: unknown field" "$tmp/err"; then ok sweep_misspelled_member; else
        bad sweep_misspelled_member "expected exit 2 with the daemon's message, got $rc: $(cat "$tmp/err")"; fi
    check sweep_refusals_submit_nothing "$before" "$(api "/v1/jobs?limit=1000" | jq '.jobs | length')"
    # behind a running job: a sweep job deleted while it waits gets its row (status deleted)
    # and the sweep goes on; a sweep stopped by SIGTERM writes its CSV and says how to cancel.
    # (A queued job is cancelled, then deleted: the long --poll keeps the sweep from seeing it
    # cancelled in between.)
    long=$(long_job_running)
    timeout 150 python3 -B "$CLIENT" --server "$URL" sweep "$tmp/quick.json" --set '/interactions/0/damping=0,0.2' \
        --poll 3 >"$tmp/del.csv" 2>"$tmp/del.err" &
    del_pid=$!
    sid=$(sweep_started "$tmp/del.err" 2)
    first=$(api "/v1/jobs?tag=$sid" | jq -r '.jobs | sort_by(.name) | .[0].id')
    api "/v1/jobs/$first/cancel" -o /dev/null -X POST
    api "/v1/jobs/$first" -o /dev/null -X DELETE
    interrupted_sweep sweep_interrupted python3 -B "$CLIENT" --server "$URL" sweep "$tmp/quick.json" \
        --set '/seed=1,2' --poll 0.3
    hint=$(sed -n 's/^polydem_client: to cancel them: //p' "$tmp/int.err")
    if [ -n "$sid" ] && [ "${hint%" cancel --tag $sid"}" != "$hint" ] && sh -c "$hint" 2>"$tmp/err"; then
        ok sweep_interrupted_says_how_to_cancel; else
        bad sweep_interrupted_says_how_to_cancel "no working cancel command: $(tail -n 3 "$tmp/int.err") $(cat "$tmp/err")"; fi
    check sweep_interrupted_jobs_cancelled "cancelled cancelled" \
        "$(api "/v1/jobs?tag=$sid" | jq -r '[.jobs[].status] | join(" ")')"
    # interrupted while the answer to a submission is on its way (a proxy holds every answer
    # 2 s): the server has made the job, the client has not read its id; the row must still
    # name it, queued (not "unsubmitted")
    held_answers_proxy
    in_flight_sweep python3 -B "$CLIENT" --server "$proxy_url" sweep "$tmp/quick.json" --set '/seed=3' \
        --poll 0.3
    check sweep_interrupted_in_flight_row "143 $rid queued" \
        "$rc $(tail -n +2 "$tmp/race.csv" 2>/dev/null | cut -d, -f1,3 | tr , ' ')"
    api "/v1/jobs/$rid/cancel" -o /dev/null -X POST
    api "/v1/jobs/$blocker/cancel" -o /dev/null -X POST
    api "/v1/jobs/$long/cancel" -o /dev/null -X POST
    wait "$del_pid"
    check sweep_deleted_exit_status 1 "$?"
    check sweep_deleted_rows "deleted succeeded" \
        "$(tail -n +2 "$tmp/del.csv" 2>/dev/null | cut -d, -f3 | tr '\n' ' ' | sed 's/ $//')"
    # a shape given as a mesh file beside the scenario is uploaded and the job runs
    mkdir -p "$tmp/withmesh"
    cube_obj "$tmp/withmesh/cube.obj"
    jq '.shapes.r = {"mesh": "cube.obj"}' "$tmp/quick.json" >"$tmp/withmesh/scenario.json"
    id=$(timeout 60 python3 -B "$CLIENT" --server "$URL" --timeout 60 submit "$tmp/withmesh/scenario.json" --wait \
        2>"$tmp/err")
    rc=$?
    if [ "$rc" = 0 ] && curl -s "$URL/v1/jobs/$id/scenario" | jq -e '.shapes.r.mesh | startswith("sha256:")' >/dev/null; then
        ok mesh_file_uploaded; else bad mesh_file_uploaded "exit $rc: $(tail -n 3 "$tmp/err")"; fi
    # a job cancelled while running: wait fails (exit 1) but says its frames so far can be
    # downloaded, and they download, the file's root attribute status saying "cancelled"
    id=$(timeout 30 python3 -B "$CLIENT" --server "$URL" submit tests/server/long_job.json 2>"$tmp/err")
    i=0
    while [ "$(curl -s "$URL/v1/jobs/$id" | jq -r '.progress.frames // 0')" -lt 1 ] && [ $i -lt 300 ]; do
        sleep 0.1
        i=$((i + 1))
    done
    curl -s -o /dev/null -X POST "$URL/v1/jobs/$id/cancel"
    timeout 60 python3 -B "$CLIENT" --server "$URL" --timeout 30 wait "$id" 2>"$tmp/err"
    rc=$?
    if [ "$rc" = 1 ] && grep -q "job $id cancelled.*can be downloaded" "$tmp/err"; then ok cancelled_wait_says_frames_kept; else
        bad cancelled_wait_says_frames_kept "expected exit 1 saying the frames can be downloaded, got $rc: $(tail -n 2 "$tmp/err")"; fi
    timeout 60 python3 -B "$CLIENT" --server "$URL" download "$id" -o "$tmp/cancelled.h5" 2>"$tmp/err"
    check cancelled_download_exit_status 0 "$?"
    if command -v h5dump >/dev/null 2>&1; then
        check cancelled_download_status cancelled \
            "$(h5dump -a /status "$tmp/cancelled.h5" 2>&1 | sed -n 's/^ *(0): "\(.*\)"$/\1/p')"
    fi
    jq '.interactions[0].friction = -1' "$tmp/quick.json" >"$tmp/invalid.json"
    timeout 30 python3 -B "$CLIENT" --server "$URL" --timeout 120 submit "$tmp/invalid.json" >/dev/null 2>"$tmp/err"
    rc=$?
    if [ "$rc" = 1 ] && grep -q "/interactions/0/friction" "$tmp/err"; then ok invalid_names_field; else
        bad invalid_names_field "expected exit 1 naming /interactions/0/friction, got $rc: $(cat "$tmp/err")"; fi
fi
summary
