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
