# cli_test_lib.sh -- sourced by the command-line tests (test_cli.sh, test_*_cli.sh) after they set
# $mfkit: the check counters, a temporary directory $tmp removed at exit, and
#   ok CONDITION DESCRIPTION          one check: CONDITION is evaluated, DESCRIPTION printed if false
#   expect_error_in DESC STDIN RC PATTERN ARGS...
#                                     mfkit ARGS with STDIN on its standard input must exit RC, print
#                                     nothing on stdout and one stderr line matching PATTERN
#   expect_error DESC RC PATTERN ARGS...   the same with an empty standard input
#   finish NAME                       prints the counts; the exit status is 0 only if all passed
set -u
fails=0; checks=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

ok() { checks=$((checks+1)); if ! eval "$1"; then echo "FAIL: $2" >&2; fails=$((fails+1)); fi; }

expect_error_in() {
  local desc="$1" input="$2" want="$3" pattern="$4"; shift 4
  printf '%s' "$input" | "$mfkit" "$@" >"$tmp/out" 2>"$tmp/err"; local rc=$?
  checks=$((checks+1))
  if [ $rc -ne "$want" ] || [ -s "$tmp/out" ] || [ "$(wc -l <"$tmp/err")" -ne 1 ] || ! grep -q -- "$pattern" "$tmp/err"; then
    echo "FAIL: $desc (rc=$rc, stdout=$(head -c 200 "$tmp/out"), stderr=$(cat "$tmp/err"))" >&2; fails=$((fails+1))
  fi
}

expect_error() { local desc="$1" want="$2" pattern="$3"; shift 3; expect_error_in "$desc" "" "$want" "$pattern" "$@"; }

finish() {
  echo "$1: $((checks-fails)) passed, $fails failed"
  [ $fails -eq 0 ]
}

# write_const_map OUT.png: a 4 x 4 8-bit unorm normal map, every texel the normal (0.25, 0.15, 1)
# normalised (the prefilter tests' constant map: every level's footprint holds that one normal).
write_const_map() {
    /usr/bin/python3 - "$1" <<'PY'
import math, struct, sys, zlib
n = [0.25, 0.15, 1.0]; l = math.sqrt(sum(x * x for x in n))
e = [round((x / l + 1) / 2 * 255) for x in n]
raw = b''.join(b'\x00' + bytes(e) * 4 for _ in range(4))
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open(sys.argv[1], 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', 4, 4, 8, 2, 0, 0, 0))
                              + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
PY
}
