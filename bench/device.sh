#!/bin/sh
# bench/device.sh [--cpu] [--budget SECONDS]: every GPU measurement of bench/RESULTS.md and the
# 1e6 gravity packing (studies/gravity_packing --full) in one call, for a machine that has a GPU
# and no package manager (the `device` tool's). Prepared and tried on the CPU machines, so that a
# session that is lent a GPU spends its few minutes measuring, not setting up:
#
#   here:   make build/polydem build/bench/step build/bench/overlap && sh tools/device_bundle.sh
#   there:  sh bench/device.sh                 (the device tool's run, carrying build/device)
#
# It finds the NVIDIA driver's OpenCL library (libnvidia-opencl.so.1), points the carried ICD
# loader at it, and runs, each stage under a timeout taken from what is left of the budget (540 s
# by default, so that a 600 s call returns with its files): the devices; one overlap on the host
# and through OpenCL, each in both precisions (the kernels' first build on that driver);
# bench/overlap; bench/step for falling Schönhardt prisms at 1e3-1e6 and 5e4 settled spheres;
# the dense bed; depth-first against breadth-first traversal; the step in single precision; then
# the 1e6 packing with what time is left. A stage that fails or times out is logged and the
# next one runs. Everything goes to $OUT (the device tool's folder; build/device-out otherwise):
# device.log, and the packing's CSV and plots (at most 8 files come back).
# --cpu: the same on this machine's first OpenCL device (PoCL), at sizes that finish in minutes.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
B=${BUNDLE:-$ROOT/build/device}
OUT=${OUT:-$ROOT/build/device-out}
BUDGET=540
CPU=0
while [ $# -gt 0 ]; do
    case $1 in
    --cpu) CPU=1 ;;
    --budget)
        BUDGET=${2:?--budget needs seconds}
        shift
        ;;
    *)
        echo "usage: $0 [--cpu] [--budget SECONDS]" >&2
        exit 2
        ;;
    esac
    shift
done
mkdir -p "$OUT"
LOG=$OUT/device.log
: >"$LOG"
T0=$(date +%s)
say() { echo "$*" | tee -a "$LOG"; }
left() { echo $((BUDGET - ($(date +%s) - T0))); }

[ -x "$B/bin/polydem" ] || {
    say "device.sh: $B/bin/polydem missing: run tools/device_bundle.sh here and carry build/device"
    exit 1
}
say "# bench/device.sh, commit $(cat "$B/COMMIT" 2>/dev/null), $(date -u '+%Y-%m-%d %H:%M UTC')," \
    "budget $BUDGET s"
say "# built against $(cat "$B/glibc/VERSION" 2>/dev/null); here $(ldd --version 2>&1 | head -n 1)"
command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L 2>&1 | tee -a "$LOG"

# OpenCL: the NVIDIA driver's ICD, named in a vendors folder of our own for the carried loader
WRAP=$(mktemp -d)
if [ "$CPU" = 0 ]; then
    nv=
    for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64 \
        /usr/lib /lib/x86_64-linux-gnu; do
        [ -e "$d/libnvidia-opencl.so.1" ] && nv=$d/libnvidia-opencl.so.1 && break
    done
    [ -n "$nv" ] || nv=$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1/ { print $NF; exit }')
    if [ -z "$nv" ]; then
        say "device.sh: no libnvidia-opencl.so.1 on this machine (looked in /usr/local/nvidia," \
            "/usr/lib*, ldconfig): no OpenCL for the GPU"
        exit 1
    fi
    mkdir -p "$WRAP/icd"
    echo "$nv" >"$WRAP/icd/nvidia.icd"
    export OCL_ICD_VENDORS="$WRAP/icd"
    # the driver's own libraries (libcuda.so.1, which it loads by name) beside it
    export LD_LIBRARY_PATH="${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}$(dirname "$nv")"
    say "# OpenCL ICD: $nv"
fi

# the programs, through wrappers: the carried libraries first; the carried C library and its
# loader only when the machine's own is too old for the programs
export LD_LIBRARY_PATH="$B/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
loader=
if ! "$B/bin/polydem" mesh-info builtin:cube >/dev/null 2>"$WRAP/err"; then
    if grep -q GLIBC "$WRAP/err"; then
        loader="$(ls "$B"/glibc/ld-linux*.so* | head -n 1) --library-path $B/lib:$B/glibc"
        say "# this machine's C library is older than the build's: the carried one runs them"
    else
        say "device.sh: polydem does not start: $(cat "$WRAP/err")"
        exit 1
    fi
fi
for p in polydem step overlap; do
    printf '#!/bin/sh\nexec %s %s "$@"\n' "$loader" "$B/bin/$p" >"$WRAP/$p"
    chmod +x "$WRAP/$p"
done
export POLYDEM="$WRAP/polydem"

SIG=TERM
stage() { # NAME SECONDS COMMAND...: runs it under a timeout (signal $SIG), its output into the log
    name=$1
    want=$2
    shift 2
    t=$(left)
    [ "$want" -lt "$t" ] || want=$t
    if [ "$want" -lt 10 ]; then
        say "## $name: skipped, the budget is spent"
        return 1
    fi
    say "## $name (timeout $want s): $*"
    s0=$(date +%s)
    timeout -s "$SIG" "$want" "$@" >>"$LOG" 2>&1
    rc=$?
    case $rc in 124 | 137) note=' (timed out)' ;; *) note= ;; esac
    say "## $name: exit $rc after $(($(date +%s) - s0)) s$note"
    return $rc
}

if [ "$CPU" = 1 ]; then
    SIZES=1000,10000
    SPHERES=5000
    BED_SETTLE=2000
    PACK=2000
    PACK_MODE=--quick
else
    SIZES=1000,10000,100000,1000000
    SPHERES=50000
    BED_SETTLE=20000
    PACK=1000000
    PACK_MODE=--full
fi
# --json: whether single precision's / and sqrt are correctly rounded (fp32_rounded) is shown
stage devices 30 "$POLYDEM" devices --json
# the kernels' first build on this driver; host and OpenCL must agree to 1e-12 in double precision
# (issue 2), and in single precision to the bit where the device has fp32_rounded
pose="--pose-a '0 0 0 0.8 0.2 -0.3 0.1' --pose-b '0.8 0.01 0.005 0.3 0.5 0.7 -0.2'"
for mode in "" "--opencl" "--single" "--opencl --single"; do
    stage "overlap ${mode:-host}" 120 sh -c "'$POLYDEM' overlap builtin:rock:1280 builtin:rock:1280 \
        $pose $mode"
done
stage "bench/overlap" 120 "$WRAP/overlap" --no-filter-off
stage "bench/step, falling" 200 "$WRAP/step" --sizes $SIZES --spheres $SPHERES --settle 300 \
    --steps 20
stage "bench/step, dense bed" 150 "$WRAP/step" --sizes 1000 --spheres 0 --settle $BED_SETTLE \
    --steps 100
# depth-first against breadth-first traversal (the thesis found breadth first 5-10x faster on its
# GPU; on the CPU it is 2.7-4.2x slower), and single precision's step
stage "bench/step, traversal" 120 "$WRAP/step" --sizes $SIZES --spheres $SPHERES --settle 300 \
    --steps 5 --traversal
stage "bench/step, single" 120 "$WRAP/step" --single --sizes $SIZES --spheres $SPHERES \
    --settle 300 --steps 20
# the 1e6 packing (thesis section 7.1) with what is left, less a minute for its analysis. Its
# stats rows are flushed as they are written: a run killed (not cancelled, which removes the
# file) leaves packing.h5.partial, whose rows give time per step against simulated time up to
# there
PY=
for p in "$(command -v python3)" /usr/bin/python3; do # one with the study's packages
    [ -x "$p" ] && "$p" -c 'import numpy, h5py, matplotlib' 2>/dev/null && PY=$p && break
done
SO=$(mktemp -d)
pack_t=$(($(left) - 60))
SIG=KILL
if [ -n "$PY" ]; then # the study generates its scenario and plots with them
    stage "gravity packing, $PACK" $pack_t env PARTICLES=$PACK PYTHON="$PY" STUDIES_OUT="$SO" \
        sh "$ROOT/studies/gravity_packing/run.sh" $PACK_MODE
else
    say "## gravity packing: skipped, no python3 with numpy, h5py and matplotlib"
fi
SIG=TERM
gp=$SO/gravity_packing
if [ ! -f "$gp/packing.h5" ] && [ -f "$gp/packing.h5.partial" ]; then
    # cut short: the analysis of what was written
    mv "$gp/packing.h5.partial" "$gp/packing.h5"
    stage "packing analysis" 60 "$PY" "$ROOT/studies/gravity_packing/packing.py" analyze --out "$gp" \
        --partial
fi
for f in packing.csv time_per_step.png pairs.png time_vs_pairs.png; do
    [ -f "$gp/$f" ] && cp "$gp/$f" "$OUT/"
done
say "# done in $(($(date +%s) - T0)) s; files in $OUT: $(ls "$OUT" | tr '\n' ' ')"
rm -rf "$WRAP" "$SO"
