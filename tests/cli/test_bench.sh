#!/bin/sh
# test_bench.sh - bench/contacts (the pairs of a saved state through the overlap, on the host):
# two analytic contacts read back from a result file, and bad input; bench/replay against a
# single-precision run's own stats; bench/stats_rows.sh and bench/overlap run.
. tests/cli/lib.sh
CONTACTS=${POLYDEM%/polydem}/bench/contacts

# Two cube pairs at t = 0 (size 0.02 m: side s = 0.02 (pi/6)^(1/3) = 0.0161199 m), pressed
# h = 1e-6 m into each other: face on face, a slab (V = s^2 h, depth h, area s^2, rho 1); and the
# second cube turned 45 deg about z, its edge in the first's face, a wedge (V = h^2 s, depth h,
# area 2 h s, rho 2). A common velocity gives the run an energy budget for the contact forces.
cat >"$tmp/pairs.json" <<'JSON'
{"name": "pairs", "time": {"dt": 1e-6, "duration": 2e-6, "output_interval": 1e-6},
 "gravity": [0, 0, 0],
 "materials": {"m": {"density": 2500, "youngs_modulus": 1e5, "poisson_ratio": 0.25}},
 "interactions": [{"between": ["m", "m"], "friction": 0.3, "damping": 0.2}],
 "shapes": {"c": {"builtin": "cube"}},
 "particles": [{"shape": "c", "material": "m", "list": [
   {"position": [0, 0, 0], "velocity": [0, 0, 1], "size": 0.02},
   {"position": [0.016118919540164693, 0, 0], "velocity": [0, 0, 1], "size": 0.02},
   {"position": [0, 0.1, 0], "velocity": [0, 0, 1], "size": 0.02},
   {"position": [0.019457464189114336, 0.1, 0], "velocity": [0, 0, 1], "size": 0.02,
    "orientation": [0.9238795325112867, 0, 0, 0.3826834323650898]}]}],
 "output": {"fields": ["position", "orientation"]}}
JSON
if ! $POLYDEM run "$tmp/pairs.json" -o "$tmp/pairs.h5" --quiet 2>"$tmp/err"; then
    bad pairs_run "$(cat "$tmp/err")"
fi
"$CONTACTS" "$tmp/pairs.h5" --frame 0 --reps 2 --list >"$tmp/out" 2>"$tmp/err"
rc=$?
# the same numbers from the formulas above, and what the report reads back (%.6g; rho %.4g)
check_pair() { # NAME PAIR VOLUME DEPTH AREA RHO
    line=$(grep "^pair $2:" "$tmp/out")
    # double: the printed 6 digits (1e-5 relative); single: 1 % (its resolution here is 64 ulps
    # of 0.02 m, 1.5e-7 m of the 1e-6 m depth; measured 1e-3)
    awk -v l="$line" -v v="$3" -v d="$4" -v a="$5" -v r="$6" '
        function near(x, y, tol) { return x / y - 1 < tol && 1 - x / y < tol }
        BEGIN {
        n = split(l, f, " ");
        # fields: pair i j: volume V m^3, depth D m, area A m^2, rho R, single volume S m^3
        V = f[5] + 0; D = f[8] + 0; A = f[11] + 0; R = f[14] + 0; S = f[17] + 0;
        ok = n >= 18 && near(V, v, 1e-5) && near(D, d, 1e-5) && near(A, a, 1e-5) &&
             near(R, r, 1e-3) && near(S, v, 1e-2);
        exit ok ? 0 : 1 }' && ok "$1" || bad "$1" "expected V $3, depth $4, area $5, rho $6: '$line'"
}
if [ "$rc" -ne 0 ]; then
    bad contacts_runs "exit $rc: $(cat "$tmp/err")"
else
    ok contacts_runs
    check_pair slab_rho_1 "0 1" 2.598518e-10 1e-6 2.598518e-04 1
    check_pair wedge_rho_2 "2 3" 1.611992e-14 1e-6 3.223984e-08 2
    if grep -q "^touching (double precision): 2 (2 degenerate" "$tmp/out" &&
        grep -q "^single precision: 2 of the 2 touching pairs found, 0 missed" "$tmp/out"; then
        ok contacts_summary
    else bad contacts_summary "$(cat "$tmp/out")"; fi
fi

expect_fail contacts_no_args 2 "usage" -- "$CONTACTS"
expect_fail contacts_bad_option 2 "usage" -- "$CONTACTS" "$tmp/pairs.h5" --bogus
expect_fail contacts_missing_file 1 "nope.h5: not an HDF5 file" -- "$CONTACTS" "$tmp/nope.h5"
expect_fail contacts_json_not_h5 1 "pairs.json: not an HDF5 file" -- "$CONTACTS" "$tmp/pairs.json"
expect_fail contacts_frame_out_of_range 1 "frame 99 of /frames/position" -- \
    "$CONTACTS" "$tmp/pairs.h5" --frame 99

# bench/replay (a single-precision run's particle contacts replayed step by step as the engine
# computed them): the pairs above in single precision, the first pair closing at 0.05 m/s, with a
# frame and a stats row every step. Each frame's largest depth / size must be that step's
# /stats/max_overlap_ratio: with PoCL (CI) to every printed digit; the band, 1e-4 relative,
# leaves room for a device that rounds otherwise. The rows change by ~5 % a step, so a frame read
# against the wrong row fails.
REPLAY=${POLYDEM%/polydem}/bench/replay
sed -e 's/"name": "pairs"/"name": "pairs-single", "precision": "single"/' \
    -e 's/"duration": 2e-6, "output_interval": 1e-6}/"duration": 2e-5, "output_interval": 1e-6, "stats_interval": 1e-6}/' \
    -e 's/"position": \[0.016118919540164693, 0, 0\], "velocity": \[0, 0, 1\]/"position": [0.016118919540164693, 0, 0], "velocity": [-0.05, 0.01, 1]/' \
    "$tmp/pairs.json" >"$tmp/single.json"
if ! $POLYDEM run "$tmp/single.json" -o "$tmp/single.h5" --quiet 2>"$tmp/err"; then
    bad replay_run "$(cat "$tmp/err")"
elif ! "$REPLAY" "$tmp/single.h5" 0 20 >"$tmp/rp" 2>"$tmp/err"; then
    bad replay_runs "$(cat "$tmp/err")"
else
    h5dump -y -w 1 -d /stats/max_overlap_ratio "$tmp/single.h5" |
        sed -n '/DATA {/,/}/p' | tr -d ' ,' | grep -E '^[0-9.e+-]+$' >"$tmp/rows"
    if awk 'NR == FNR { row[n++] = $1 + 0; next }
        /^frame / { f = $2 + 0; v = $10 + 0; k++
                    if (!(f in row) || row[f] <= 0 || v / row[f] - 1 > 1e-4 || 1 - v / row[f] > 1e-4) bad++ }
        END { exit k == 21 && n == 21 && !bad && row[20] > 1.5 * row[0] ? 0 : 1 }' \
        "$tmp/rows" "$tmp/rp"; then
        ok replay_matches_the_runs_stats
    else bad replay_matches_the_runs_stats "$(cat "$tmp/rows" "$tmp/rp")"; fi
    if "$REPLAY" "$tmp/single.h5" 3 4 --pair 1 0 >"$tmp/rp" 2>"$tmp/err" &&
        grep -q "^  pair 0 1, frame 3: poses {.*}, last 0 " "$tmp/rp" &&
        grep -q "^  pair 0 1, frame 4: poses {.*}, last 1 " "$tmp/rp" &&
        grep -q "^  pair 0 1, frame 4: depth / size [0-9.e-]*, volume " "$tmp/rp"; then
        ok replay_one_pair
    else bad replay_one_pair "$(cat "$tmp/rp" "$tmp/err")"; fi
fi
expect_fail replay_no_args 2 "usage" -- "$REPLAY"
expect_fail replay_backwards 2 "usage" -- "$REPLAY" "$tmp/single.h5" 5 4
expect_fail replay_bad_pair 2 "the run has 4 particles" -- "$REPLAY" "$tmp/single.h5" 0 1 --pair 0 9
expect_fail replay_double_run 1 "a double-precision run" -- "$REPLAY" "$tmp/pairs.h5" 0 1
expect_fail replay_missing_file 1 "nope.h5: not an HDF5 file" -- "$REPLAY" "$tmp/nope.h5" 0 1
expect_fail replay_frame_out_of_range 1 "frame 99 of /frames/position" -- \
    "$REPLAY" "$tmp/single.h5" 99 100

# bench/stats_rows.sh on a small lattice: both runs and the cost per row are printed (a figure,
# so no band on it), and bad use is refused
if POLYDEM="$POLYDEM" sh bench/stats_rows.sh 300 >"$tmp/sr" 2>&1 &&
    grep -Eq "^2 rows: +[0-9]+\.[0-9]+ s" "$tmp/sr" && grep -Eq "^101 rows: +[0-9]+\.[0-9]+ s" "$tmp/sr" &&
    grep -Eq "^one stats row: -?[0-9]+\.[0-9]+ ms$" "$tmp/sr"; then
    ok stats_rows
else bad stats_rows "$(cat "$tmp/sr")"; fi
expect_fail stats_rows_bad_count 2 "usage" -- sh bench/stats_rows.sh 12x

# bench/overlap on the host, one pass over its Schönhardt configurations: a row with the kept
# triangles and a host time (figures, no bands), after its check that the configurations' copies
# of A's vertices, which the timing shares, are equal
OVERLAP=${POLYDEM%/polydem}/bench/overlap
if "$OVERLAP" --quick --no-opencl --only schonhardt --reps 1 >"$tmp/ov" 2>&1 &&
    grep -Eq '^\| schonhardt \| 8 \| [0-9.]+ \| [0-9]+ \|' "$tmp/ov" && ! grep -q digest "$tmp/ov"; then
    ok overlap_bench_runs
else bad overlap_bench_runs "$(cat "$tmp/ov")"; fi
expect_fail overlap_bench_bad_arg 2 "usage" -- "$OVERLAP" --frobnicate
expect_fail overlap_bench_unknown_shape 2 "--only cube: no such shape" -- "$OVERLAP" --only cube
# through OpenCL (PoCL in CI): two shapes in one run, so that the second's batches run on the
# device's overlap scratch as the first's left it (ovl_run_cl keeps it between calls); every double
# result of each shape's last batch agrees with the host's to 1e-12, and every single one is the
# host's single-precision result to the bit, PoCL rounding / and sqrt correctly (the bench checks;
# exit 1 if not)
if "$OVERLAP" --quick --no-filter-off --only schonhardt --only icosphere80 >"$tmp/ovcl" 2>&1 &&
    [ "$(grep -Ec '^# opencl double against the host, (schonhardt 8|icosphere 80): ([1-9][0-9]*) of \2 pairs agree to 1e-12$' "$tmp/ovcl")" -eq 2 ] &&
    [ "$(grep -Ec '^# opencl single against the host, (schonhardt 8|icosphere 80): ([1-9][0-9]*) of \2 pairs agree to the bit$' "$tmp/ovcl")" -eq 2 ] &&
    grep -Eq '^\| icosphere \| 80 \| [0-9.]+ \| [0-9]+ \| - \| [0-9]+ \| [0-9]+ \| [0-9]+ \|$' "$tmp/ovcl"; then
    ok overlap_bench_opencl_agrees
else bad overlap_bench_opencl_agrees "$(cat "$tmp/ovcl")"; fi
# the 1280 / 80 ratio from the rows and from five back-to-back rounds: the median lies in the
# range printed with it, and a 1280-triangle pair costs more than an 80-triangle one (~4.5x)
if "$OVERLAP" --quick --no-opencl --no-filter-off --reps 1 --digest >"$tmp/ov" 2>&1 &&
    awk '/^icosphere 1280 \/ 80 host time ratio/ {
        n = split($0, w, /[^0-9.]+/); k = 0
        for (i = 1; i <= n; i++) if (w[i] != "") v[++k] = w[i] + 0
        # 1280 80 rows-ratio 5 median lo hi
        found = k == 7 && v[3] > 1 && v[4] == 5 && v[6] > 1 && v[6] <= v[5] && v[5] <= v[7] }
        END { exit found ? 0 : 1 }' "$tmp/ov"; then
    ok overlap_bench_ratio_rounds
else bad overlap_bench_ratio_rounds "$(tail -n 2 "$tmp/ov")"; fi
# --digest (the same run): a line per shape, each a 16-digit hex digest of that shape's results,
# all different and none FNV-1a's starting value (nothing hashed); a second run of one shape
# places the same configurations and gets the same answers, so the same digest
grep '^# digest of the host results' "$tmp/ov" >"$tmp/dg"
if [ "$(grep -Ec ': [0-9a-f]{16} \(1024 configurations\)$' "$tmp/dg")" -eq 5 ] &&
    [ "$(awk '{print $(NF-2)}' "$tmp/dg" | sort -u | grep -vc cbf29ce484222325)" -eq 5 ] &&
    "$OVERLAP" --quick --no-opencl --no-filter-off --only schonhardt --reps 1 --digest >"$tmp/ov1" 2>&1 &&
    grep '^# digest of the host results, schonhardt 8:' "$tmp/ov1" >"$tmp/dg1" &&
    grep -qxF "$(cat "$tmp/dg1")" "$tmp/dg"; then
    ok overlap_bench_digest
else bad overlap_bench_digest "$(cat "$tmp/dg") / $(cat "$tmp/ov1" 2>/dev/null | tail -n 1)"; fi
done_tests
