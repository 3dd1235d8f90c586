#!/bin/sh
# test_kernels_cl12.sh - every kernel program compiles as strict OpenCL C 1.2 in both precisions,
# and those with the overlap also without its separate places (OVL_PLACES_BUILD=0, the default);
# then each as OpenCL C 3.0 with the generic address space, and to PTX, as for an NVIDIA GPU
# (below). A GPU driver is stricter about address spaces than PoCL on the test machines: a
# pointer passed to the wrong address space builds here and fails there. Checked with the clang
# that PoCL itself depends on (Debian's libpocl2 -> clang-N), as the drivers do:
# __OPENCL_VERSION__ set, cl_khr_fp64 available.
. tests/cli/lib.sh
. tools/cl12.sh
if [ -z "$cc" ]; then
    bad "clang" "no clang found (PoCL's Debian package depends on one; run make deps)"
    done_tests
    exit 1
fi
for f in kernels/*.cl; do
    # the programs that contain the overlap (through their headers) have both builds
    builds=1
    cl12 "$f" -DPD_DOUBLE=1 -E 2>/dev/null | grep -q ovl_compute && builds="1 0"
    for d in 0 1; do
        for p in $builds; do
            name="$(basename "$f") PD_DOUBLE=$d"
            [ "$p" = 1 ] || name="$name OVL_PLACES_BUILD=0"
            if cl12 "$f" -DPD_DOUBLE=$d -DOVL_PLACES_BUILD=$p -fsyntax-only >"$tmp/log" 2>&1; then
                ok "$name"
            else
                bad "$name" "$(grep -m 3 error "$tmp/log")"
            fi
        done
    done
done
# NVIDIA's driver, given no -cl-std, compiles OpenCL C 3.0 with the generic address space, where
# clang puts array parameters (`const pd_real q[4]`) in __private: passing a pointer into a struct
# there is an error that OpenCL C 1.2 (everything __private) does not show. It stopped the
# contact program, and so every simulation, on the first GPU run (an H200, 2026-11-30)
for f in kernels/*.cl; do
    for d in 0 1; do
        name="$(basename "$f") PD_DOUBLE=$d as OpenCL C 3.0"
        if cl30 "$f" -DPD_DOUBLE=$d -DOVL_PLACES_BUILD=1 -fsyntax-only >"$tmp/log" 2>&1; then
            ok "$name"
        else
            bad "$name" "$(grep -m 3 error "$tmp/log")"
        fi
    done
done
# and every program compiles to PTX with LLVM's NVPTX backend (-O0: the code generator's own
# limits, not the optimiser's): NVIDIA's driver has a compiler of its own, but a builtin, a type
# or a construct that no GPU back end lowers shows here rather than in a GPU session's minutes
if "$cc" --print-targets 2>/dev/null | grep -q nvptx64; then
    for f in kernels/*.cl; do
        for d in 0 1; do
            name="$(basename "$f") PD_DOUBLE=$d to PTX"
            if cl12 "$f" -DPD_DOUBLE=$d -target nvptx64-nvidia-nvcl -O0 -S -o "$tmp/k.ptx" \
                >"$tmp/log" 2>&1 && grep -q "^.entry\|\.entry" "$tmp/k.ptx"; then
                ok "$name"
            else
                bad "$name" "$(grep -m 3 error "$tmp/log")"
            fi
        done
    done
else
    echo "skip PTX: $cc has no nvptx64 target"
fi
done_tests
