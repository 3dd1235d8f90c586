#!/bin/sh
# bench/ptx_resources.sh [ARCH]: registers, stack frame and spills per kernel on an NVIDIA GPU
# (default sm_90, the H100/H200), read off without one: every kernel program is compiled as
# OpenCL C 1.2 to PTX by clang's NVPTX back end, with the few OpenCL builtins it calls defined on
# NVVM's (work-item index, atomics, fences, conversions) and libdevice's (atan2, sin, cos) and linked in, then assembled by the
# CUDA toolkit's ptxas -v. NVIDIA's own OpenCL compiler is another compiler, so its figures will
# differ somewhat; what this shows is the order of magnitude: how many registers a work-item of
# the narrow phase holds (occupancy) and how much private memory it spills to the stack.
# Needs clang (make deps) and the CUDA toolkit (ptxas, libdevice); prints a table, both precisions.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
ARCH=${1:-sm_90}
CUDA=${CUDA_HOME:-/usr/local/cuda}
PTXAS=$(command -v ptxas || echo "$CUDA/bin/ptxas")
LIBDEVICE=$(ls "$CUDA"/nvvm/libdevice/libdevice.*.bc 2>/dev/null | head -n 1)
cd "$ROOT"
. tools/cl12.sh # cc, cl12
[ -x "$PTXAS" ] || { echo "ptx_resources: no ptxas (the CUDA toolkit; CUDA_HOME=$CUDA)" >&2; exit 1; }
[ -n "$LIBDEVICE" ] || { echo "ptx_resources: no libdevice under $CUDA/nvvm" >&2; exit 1; }
[ -n "$cc" ] || { echo "ptx_resources: no clang (make deps)" >&2; exit 1; }
"$cc" --print-targets 2>/dev/null | grep -q nvptx64 ||
    { echo "ptx_resources: $cc has no nvptx64 target" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# the builtins the kernels call that clang leaves to an OpenCL runtime library (libclc's role);
# CL2.0 for the generic pointer NVVM's atomic takes, with the same mangled names as in CL1.2
cat >"$tmp/builtins.cl" <<'EOF'
size_t __attribute__((overloadable)) get_global_id(uint d)
{
    return d == 0 ? (size_t)__nvvm_read_ptx_sreg_ctaid_x() * __nvvm_read_ptx_sreg_ntid_x() +
                        __nvvm_read_ptx_sreg_tid_x()
                  : 0;
}
double __attribute__((overloadable)) fabs(double x) { return __builtin_fabs(x); }
float __attribute__((overloadable)) fabs(float x) { return __builtin_fabsf(x); }
double __attribute__((overloadable)) sqrt(double x) { return __builtin_sqrt(x); }
float __attribute__((overloadable)) sqrt(float x) { return __builtin_sqrtf(x); }
double __nv_atan2(double, double);
float __nv_atan2f(float, float);
double __attribute__((overloadable)) atan2(double y, double x) { return __nv_atan2(y, x); }
float __attribute__((overloadable)) atan2(float y, float x) { return __nv_atan2f(y, x); }
int __attribute__((overloadable)) atomic_min(volatile __global int *p, int v)
{
    return __nvvm_atom_min_gen_i((volatile __generic int *)p, v);
}
int __attribute__((overloadable)) atomic_or(volatile __global int *p, int v)
{
    return __nvvm_atom_or_gen_i((volatile __generic int *)p, v);
}
int __attribute__((overloadable)) atomic_inc(volatile __global int *p)
{
    return __nvvm_atom_add_gen_i((volatile __generic int *)p, 1);
}
void __attribute__((overloadable)) mem_fence(cl_mem_fence_flags f) { __nvvm_membar_gl(); }
int __attribute__((overloadable)) min(int a, int b) { return a < b ? a : b; }
ulong __attribute__((overloadable)) clz(ulong x) { return x ? __builtin_clzl(x) : 64; }
int __attribute__((overloadable)) isfinite(double x) { return __builtin_isfinite(x); }
int __attribute__((overloadable)) isfinite(float x) { return __builtin_isfinite(x); }
float __attribute__((overloadable)) convert_float_rtn(double x) { return __nvvm_d2f_rm(x); }
float __attribute__((overloadable)) convert_float_rtp(double x) { return __nvvm_d2f_rp(x); }
double __nv_sin(double);
double __nv_cos(double);
float __nv_sinf(float);
float __nv_cosf(float);
double __attribute__((overloadable)) sin(double x) { return __nv_sin(x); }
double __attribute__((overloadable)) cos(double x) { return __nv_cos(x); }
float __attribute__((overloadable)) sin(float x) { return __nv_sinf(x); }
float __attribute__((overloadable)) cos(float x) { return __nv_cosf(x); }
EOF
"$cc" -x cl -cl-std=CL2.0 -Xclang -finclude-default-header -target nvptx64-nvidia-nvcl -O2 \
    -emit-llvm -c -o "$tmp/builtins.bc" "$tmp/builtins.cl"
echo "# bench/ptx_resources.sh: $ARCH, $("$cc" --version | head -n 1), $("$PTXAS" --version | tail -n 1)"
echo "| program | kernel | precision | registers | stack frame (bytes) | spill stores / loads (bytes) |"
echo "|---|---|---|---|---|---|"
for f in kernels/*.cl; do
    p=$(basename "$f" .cl)
    for d in 1 0; do
        prec=double
        [ "$d" = 1 ] || prec=single
        # -march sm_80: this clang's newest; ptxas assembles its PTX for $ARCH
        if ! cl12 "$f" -DPD_DOUBLE=$d -target nvptx64-nvidia-nvcl -march=sm_80 -O2 -S \
            -Xclang -mlink-builtin-bitcode -Xclang "$tmp/builtins.bc" \
            -Xclang -mlink-builtin-bitcode -Xclang "$LIBDEVICE" \
            -o "$tmp/$p.ptx" 2>"$tmp/log"; then
            echo "| $p | (clang failed: $(grep -m 1 error "$tmp/log")) | $prec | | | |"
            continue
        fi
        if ! "$PTXAS" -arch="$ARCH" -v "$tmp/$p.ptx" -o "$tmp/$p.cubin" >"$tmp/v" 2>&1; then
            echo "| $p | (ptxas failed: $(grep -m 1 -i 'error\|fatal' "$tmp/v")) | $prec | | | |"
            continue
        fi
        # per entry: "Compiling entry function 'K'", "N bytes stack frame, S bytes spill stores,
        # L bytes spill loads", "Used R registers"
        awk -v p="$p" -v prec="$prec" '
            /Compiling entry function/ { k = $0; sub(/.*function .?/, "", k); sub(/.? for .*/, "", k) }
            /bytes stack frame/ && k != "" { st = $1; ss = $5; sl = $9 }
            /Used [0-9]+ registers/ && k != "" {
                r = $0; sub(/.*Used /, "", r); sub(/ registers.*/, "", r)
                printf "| %s | %s | %s | %s | %s | %s / %s |\n", p, k, prec, r, st, ss, sl
                k = "" }' "$tmp/v"
    done
done
