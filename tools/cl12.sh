# tools/cl12.sh - sourced (not run) by the scripts that compile the kernels with clang as a GPU
# driver would (tests/cli/test_kernels_cl12.sh, bench/ptx_resources.sh): sets cc to a clang (the
# one PoCL's Debian package depends on when there is no plain `clang`; empty when none) and
# defines cl12 FILE OPTIONS..., strict OpenCL C 1.2 with the drivers' defines (__OPENCL_VERSION__,
# cl_khr_fp64) and the kernels' headers; and cl30 FILE OPTIONS..., OpenCL C 3.0 with the generic
# address space and fp64, the dialect NVIDIA's driver compiles a program in when no -cl-std is
# given (seen on an H200, 2026-11-30). Paths are relative to the repository's root.
cc=$(command -v clang || ls /usr/bin/clang-[0-9]* 2>/dev/null | sort -t- -k2 -n | tail -n 1)
cl12() {
    f=$1
    shift
    "$cc" -x cl -cl-std=CL1.2 -Xclang -finclude-default-header -D__OPENCL_VERSION__=120 \
        -Xclang -cl-ext=+cl_khr_fp64 -Ikernels "$@" "$f"
}
cl30() {
    f=$1
    shift
    "$cc" -x cl -cl-std=CL3.0 -Xclang -finclude-default-header -D__OPENCL_VERSION__=300 \
        -Xclang -cl-ext=+cl_khr_fp64,+__opencl_c_fp64,+__opencl_c_generic_address_space \
        -Ikernels "$@" "$f"
}
