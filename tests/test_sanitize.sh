#!/usr/bin/env bash
# test_sanitize.sh SRC BUILD -- the pure C build (MFKIT_WITH_CERES=OFF, MFKIT_WITH_OIIO=OFF) with
# AddressSanitizer + UndefinedBehaviorSanitizer runs its unit tests: the core's, the CLI's, and
# test_frontend, which converts, describes and validates tables of every non-EXR format with the
# front end and checks that it links no C++ library.  This proves that lib/, lib/io/, the CLI and
# their tests build and pass without Ceres and OpenImageIO.
set -eu
src="$1"; build="$2"
dir="$build/sanitize-core"
cmake -S "$src" -B "$dir" -DMFKIT_WITH_CERES=OFF -DMFKIT_WITH_OIIO=OFF -DMFKIT_SANITIZE=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$dir" -j2 >/dev/null
test ! -e "$dir/libexec/mfkit/mfkit-full" || { echo "test_sanitize: mfkit-full built with both options OFF"; exit 1; }
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$dir" -L unit --output-on-failure --no-tests=error
