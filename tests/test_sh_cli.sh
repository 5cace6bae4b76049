#!/usr/bin/env bash
# test_sh_cli.sh MFKIT TEST_MAPS -- `mfkit sh project` end to end: a constant environment
# (L00 = 2 sqrt(pi) L, L20 the derived midpoint-rule term, the rest 0), a single bright texel
# (the basis at its centre times its solid angle), both z-up and y-up, directional lights from a
# CSV; tests/test_maps.c --check-sh parses the JSON and compares.  Errors: exit 2/3, one stderr
# line naming file, line and column, nothing on stdout.
mfkit="$1"; helper="$2"
. "$(dirname "$0")/cli_test_lib.sh"

# project_check DESC KIND UP [LIGHTS]
project_check() {
  local desc="$1" kind="$2" up="$3" lights="${4:-}"
  local args=("$tmp/$kind.exr" --up "$up")
  [ -n "$lights" ] && args+=(--lights "$tmp/lights.csv")
  "$mfkit" sh project "${args[@]}" >"$tmp/$kind.$up$lights.json" 2>"$tmp/err"; local rc=$?
  ok '[ $rc -eq 0 ] && [ ! -s "$tmp/err" ]' "$desc: exit $rc ($(cat "$tmp/err"))"
  "$helper" --check-sh "$tmp/$kind.$up$lights.json" "$kind" "$up" $lights >"$tmp/check" 2>&1; rc=$?
  ok '[ $rc -eq 0 ]' "$desc: $(tail -5 "$tmp/check")"
}

"$helper" --write-env constant "$tmp/constant.exr" && "$helper" --write-env texel "$tmp/texel.exr" ||
  { echo "FAIL: test_maps could not write the environments" >&2; exit 1; }
printf 'dir_x,dir_y,dir_z,r,g,b\n0,0,2,1,2,3\n\n1, 1, 0, 0.5,0.5,0.5\n' >"$tmp/lights.csv"

project_check "constant, z-up" constant z
project_check "constant, y-up" constant y
project_check "texel, z-up" texel z
project_check "texel, y-up" texel y
project_check "constant + lights" constant z lights
out=$(cat "$tmp/constant.z.json")
ok 'echo "$out" | grep -q "\"L00\": 5.3173615527165" && echo "$out" | grep -q "\"channels\": {"' "JSON layout: $out"
if command -v oiiotool >/dev/null 2>&1; then
  oiiotool "$tmp/constant.exr" -o "$tmp/constant.hdr" && oiiotool "$tmp/constant.exr" -d float -o "$tmp/constant.tif"
  for ext in hdr tif; do
    out=$("$mfkit" sh project "$tmp/constant.$ext"); rc=$?
    ok '[ $rc -eq 0 ] && echo "$out" | grep -q "\"L00\": 5.3173615527165"' ".$ext input: $out"
  done
fi

# --- errors -----------------------------------------------------------------------------------------
"$helper" --write-bad nan "$tmp/nan.exr"
printf 'dir_x,dir_y,dir_z,r,g,b\n0,0,1,1,1,1\n0,0,1,1,x,1\n' >"$tmp/l_num.csv"
printf 'dir_x,dir_y,dir_z,r,g\n' >"$tmp/l_col.csv"
printf 'dir_x,dir_y,dir_z,r,g,b\n0,0,1,1,1,-2\n' >"$tmp/l_neg.csv"
printf 'dir_x,dir_y,dir_z,r,g,b\n0,0,0,1,1,1\n' >"$tmp/l_zero.csv"
printf 'dir_x,dir_y,dir_z,r,g,b\n0,0,1,1,1\n' >"$tmp/l_short.csv"
expect_error "bad number" 2 "l_num.csv:3: column 5 (g): 'x' is not a finite number" sh project "$tmp/constant.exr" --lights "$tmp/l_num.csv"
expect_error "missing column" 2 "l_col.csv:1: missing column 'b'" sh project "$tmp/constant.exr" --lights "$tmp/l_col.csv"
expect_error "negative power" 2 "l_neg.csv:2: column 6 (b): irradiance -2 is negative" sh project "$tmp/constant.exr" --lights "$tmp/l_neg.csv"
expect_error "zero direction" 2 "l_zero.csv:2: column 1 (dir_x): the direction (0, 0, 0) has zero length" sh project "$tmp/constant.exr" --lights "$tmp/l_zero.csv"
expect_error "short row" 2 "l_short.csv:2: 5 fields, but the header has 6" sh project "$tmp/constant.exr" --lights "$tmp/l_short.csv"
expect_error "missing lights file" 3 "missing.csv: cannot open" sh project "$tmp/constant.exr" --lights "$tmp/missing.csv"
expect_error "missing env" 3 "missing.exr" sh project "$tmp/missing.exr"
expect_error "NaN texel" 2 "texel (2, 1) .*channel G is NaN" sh project "$tmp/nan.exr"
expect_error "bad --up" 2 "--up: expected z or y, got 'x'" sh project "$tmp/constant.exr" --up x
expect_error "no ENV" 2 "missing argument: usage: mfkit sh project ENV" sh project
expect_error "unknown subcommand" 2 "unknown subcommand 'proj'" sh proj "$tmp/constant.exr"
expect_error "unknown option" 2 "unknown option '--bogus'" sh project "$tmp/constant.exr" --bogus

out=$("$mfkit" sh --help); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q "^usage: mfkit sh project ENV"' "sh --help"
out=$("$mfkit" sh project --help); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q -- "--lights FILE"' "sh project --help"

finish test_sh_cli
