#!/usr/bin/env bash
# test_sanitize.sh SRC BUILD -- the pure C core without the C++ dependencies, built with
# AddressSanitizer + UndefinedBehaviorSanitizer, runs its unit tests (and the CLI test).
# This also proves that lib/ and its tests build and pass with MFKIT_WITH_CXX_DEPS=OFF.
set -eu
src="$1"; build="$2"
dir="$build/sanitize-core"
cmake -S "$src" -B "$dir" -DMFKIT_WITH_CXX_DEPS=OFF -DMFKIT_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build "$dir" -j2 >/dev/null
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$dir" -L unit --output-on-failure
