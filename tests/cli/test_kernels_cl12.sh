#!/bin/sh
# test_kernels_cl12.sh - every kernel program compiles as strict OpenCL C 1.2 in both precisions.
# NVIDIA's driver compiles OpenCL C 1.2 (its OpenCL 3.0 has no generic address space), while
# PoCL on the test machines accepts OpenCL C 3.0: a pointer passed to the wrong address space
# builds here and fails on a GPU. Checked with the clang that PoCL itself depends on (Debian's
# libpocl2 -> clang-N), as the drivers do: __OPENCL_VERSION__ set, cl_khr_fp64 available.
. tests/cli/lib.sh
cc=$(command -v clang || ls /usr/bin/clang-[0-9]* 2>/dev/null | sort -t- -k2 -n | tail -n 1)
if [ -z "$cc" ]; then
    bad "clang" "no clang found (PoCL's Debian package depends on one; run make deps)"
    done_tests
    exit 1
fi
for f in kernels/*.cl; do
    for d in 0 1; do
        name="$(basename "$f") PD_DOUBLE=$d"
        if "$cc" -x cl -cl-std=CL1.2 -Xclang -finclude-default-header -D__OPENCL_VERSION__=120 \
            -Xclang -cl-ext=+cl_khr_fp64 -DPD_DOUBLE=$d -Ikernels -fsyntax-only "$f" >"$tmp/log" 2>&1; then
            ok "$name"
        else
            bad "$name" "$(grep -m 3 error "$tmp/log")"
        fi
    done
done
done_tests
