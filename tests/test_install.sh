#!/usr/bin/env bash
# test_install.sh SRC BUILD -- `cmake --install` into a scratch prefix, then a consumer program
# builds and runs against it twice: with find_package(mfkit) and with pkg-config.
set -eu
src="$1"; build="$2"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src/tests/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/consumer"
pcdir=$(dirname "$(find "$work/prefix" -name mfkit.pc | head -1)")
PKG_CONFIG_PATH="$pcdir" cc -std=c11 "$src/tests/consumer/consumer.c" -o "$work/consumer_pc" \
  $(PKG_CONFIG_PATH="$pcdir" pkg-config --cflags --libs mfkit)
"$work/consumer_pc"
test -x "$work/prefix/bin/mfkit"
echo "test_install: 3 passed, 0 failed"
