#!/bin/sh
# tools/device_bundle.sh [DIR]: packs the built programs a GPU machine without a package manager
# needs into DIR (default build/device): bin/ (polydem, bench/step, bench/overlap) and lib/ (every
# shared library ldd lists for them, except the C library's own, which the machine has; those go
# to glibc/, used only when the machine's C library is older than the one we built against).
# bench/device.sh runs them there. Build them first:
#   make build/polydem build/bench/step build/bench/overlap
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DIR=${1:-$ROOT/build/device}
BUILD=${BUILD:-build} # the build folder the programs come from (build/san under SANITIZE=1)
BINS="$BUILD/polydem $BUILD/bench/step $BUILD/bench/overlap"
cd "$ROOT"
for b in $BINS; do
    [ -x "$b" ] || { echo "device_bundle: $b not built (run: make $b)" >&2; exit 1; }
done
rm -rf "$DIR"
mkdir -p "$DIR/bin" "$DIR/lib" "$DIR/glibc"
for b in $BINS; do
    cp "$b" "$DIR/bin/"
    strip --strip-debug "$DIR/bin/$(basename "$b")" 2>/dev/null || true # less to carry
done
# the libraries, resolved on this machine; the C library's parts and the loader go to glibc/
ldd $BINS | awk '/=> \// { print $3 } /^\t\/.*ld-linux/ { print $1 }' | sort -u |
    while read -r lib; do
        case $(basename "$lib") in
        ld-linux*.so* | libc.so* | libm.so* | libpthread.so* | libdl.so* | librt.so* | \
            libresolv.so* | libutil.so*) cp -L "$lib" "$DIR/glibc/" ;;
        *) cp -L "$lib" "$DIR/lib/" ;;
        esac
    done
# which C library the programs were built against (bench/device.sh compares)
ldd --version | head -n 1 >"$DIR/glibc/VERSION"
git rev-parse --short HEAD >"$DIR/COMMIT" 2>/dev/null || echo unknown >"$DIR/COMMIT"
echo "device_bundle: $(ls "$DIR/lib" | wc -l) libraries, $(du -sh "$DIR" | cut -f1) in $DIR" \
    "(commit $(cat "$DIR/COMMIT"))"
