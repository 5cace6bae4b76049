#!/usr/bin/env bash
# test_maps_cli.sh MFKIT TEST_MAPS -- `mfkit maps` end to end: the analytic height field and its
# normals (tests/test_maps.c writes them and checks every level of every output against the
# analytic moments with derived tolerances), as float EXR, 16-bit and 8-bit PNG (through
# oiiotool when present), with OpenGL and DirectX green; then every bad input giving exit 2/3,
# one stderr line, nothing on stdout and no output file.
mfkit="$1"; helper="$2"
. "$(dirname "$0")/cli_test_lib.sh"

# run_check DESC CHECK-ARGS... MAPS-ARGS: runs mfkit maps, then test_maps --check
run_maps() {
  local desc="$1" prefix="$2" mode="$3" source="$4" base="$5"; shift 5
  "$mfkit" maps "$mode" "$@" --out "$prefix" --base-alpha "$base" >"$tmp/out" 2>"$tmp/err"; local rc=$?
  ok '[ $rc -eq 0 ] && [ ! -s "$tmp/err" ]' "$desc: maps exit $rc ($(cat "$tmp/err"))"
  ok '[ "$(wc -l <"$tmp/out")" -ge 7 ]' "$desc: one stdout line per file"
  "$helper" --check "$prefix" "$mode" "$source" "$base" >"$tmp/check" 2>&1; rc=$?
  ok '[ $rc -eq 0 ]' "$desc: $(tail -5 "$tmp/check")"
}

"$helper" --write-height "$tmp/h.exr" && "$helper" --write-normals "$tmp/n.exr" &&
  "$helper" --write-normals "$tmp/ndx.exr" dx && "$helper" --write-normals "$tmp/nenc.exr" enc ||
  { echo "FAIL: test_maps could not write the inputs" >&2; exit 1; }

# --- height map: central differences, periodic, T = 1/64 ---------------------------------------
hopt=(--height --texel-size 0.015625 --height-scale 1)
run_maps "leadr from heights" "$tmp/hl" leadr height 0 "$tmp/h.exr" "${hopt[@]}"
ok '[ -f "$tmp/hl_m1_mip0.exr" ] && [ -f "$tmp/hl_m2_mip6.exr" ] && [ ! -e "$tmp/hl_m1_mip7.exr" ]' "7 levels for 64 x 32"
ok 'grep -qx "$tmp/hl_m2_mip6.exr: level 6, 1 x 1" "$tmp/out"' "stdout names the files: $(tail -1 "$tmp/out")"
run_maps "lean from heights, base alpha" "$tmp/hn" lean height 0.2 "$tmp/h.exr" "${hopt[@]}"
run_maps "bump-roughness from heights" "$tmp/hb" bump-roughness height 0.1 "$tmp/h.exr" "${hopt[@]}"
run_maps "toksvig from heights" "$tmp/ht" toksvig height 0 "$tmp/h.exr" "${hopt[@]}"

# --- normal maps ----------------------------------------------------------------------------------
run_maps "leadr from float normals" "$tmp/nl" leadr float 0 "$tmp/n.exr"
run_maps "leadr from DirectX normals" "$tmp/nd" leadr float 0 "$tmp/ndx.exr" --green down
run_maps "toksvig from float normals" "$tmp/nt" toksvig float 0.05 "$tmp/n.exr"
run_maps "bump-roughness from float normals" "$tmp/nb" bump-roughness float 0 "$tmp/n.exr"
if command -v oiiotool >/dev/null 2>&1; then
  oiiotool "$tmp/nenc.exr" -d uint16 -o "$tmp/n16.png" && oiiotool "$tmp/nenc.exr" -d uint8 -o "$tmp/n8.png" &&
    oiiotool "$tmp/nenc.exr" -d uint16 -o "$tmp/n16.tif"
  run_maps "leadr from a 16-bit PNG" "$tmp/p16" leadr png16 0 "$tmp/n16.png"
  run_maps "leadr from a 16-bit TIFF" "$tmp/t16" leadr png16 0 "$tmp/n16.tif"
  run_maps "leadr from an 8-bit PNG" "$tmp/p8" leadr png8 0 "$tmp/n8.png"
  run_maps "toksvig from an 8-bit PNG" "$tmp/p8t" toksvig png8 0 "$tmp/n8.png"
  # the encoded normals read raw are not unit
  expect_error "unorm file read raw" 2 "not 1 within" maps leadr "$tmp/n16.png" --encoding raw --out "$tmp/raw"
else
  echo "note: oiiotool not found, PNG/TIFF inputs not tested" >&2
fi
# float normals with the green flipped but --green up: different moments, so the check must fail
"$mfkit" maps leadr "$tmp/ndx.exr" --out "$tmp/wrong" >/dev/null 2>&1
"$helper" --check "$tmp/wrong" leadr float 0 >/dev/null 2>&1; rc=$?
ok '[ $rc -ne 0 ]' "the check detects a wrong green convention"

# --- bad inputs: exit 2/3, one stderr line, nothing written ----------------------------------------
for k in twochannel unnormalised negz nan heightnan; do "$helper" --write-bad $k "$tmp/bad_$k.exr"; done
: >"$tmp/empty.exr"
mkdir "$tmp/o"
expect_error "two channels" 2 "needs at least 3 channels" maps leadr "$tmp/bad_twochannel.exr" --out "$tmp/o/x"
expect_error "non-normalised normal" 2 "texel (2, 1) (column, row from the top): normal .* has length 0.9" \
  maps leadr "$tmp/bad_unnormalised.exr" --out "$tmp/o/x"
expect_error "n.z < 0" 2 "texel (2, 1) .*n.z = -0.8 <= 0" maps toksvig "$tmp/bad_negz.exr" --out "$tmp/o/x"
expect_error "NaN normal" 2 "texel (2, 1) .*channel G is NaN" maps lean "$tmp/bad_nan.exr" --out "$tmp/o/x"
expect_error "NaN height" 2 "texel (3, 1) .*height is NaN" maps leadr "$tmp/bad_heightnan.exr" --height --out "$tmp/o/x"
expect_error "empty (zero-size) file" 3 "empty.exr" maps leadr "$tmp/empty.exr" --out "$tmp/o/x"
expect_error "missing file" 3 "missing.exr" maps leadr "$tmp/missing.exr" --out "$tmp/o/x"
expect_error "missing output directory" 3 "nodir" maps leadr "$tmp/n.exr" --out "$tmp/nodir/x"
expect_error "unknown map type" 2 "unknown map type 'lear'" maps lear "$tmp/n.exr" --out "$tmp/o/x"
expect_error "no --out" 2 "needs --out PREFIX" maps leadr "$tmp/n.exr"
expect_error "bad --green" 2 "--green: expected up or down, got 'left'" maps leadr "$tmp/n.exr" --out "$tmp/o/x" --green left
expect_error "--texel-size without --height" 2 "need --height" maps leadr "$tmp/n.exr" --out "$tmp/o/x" --texel-size 2
expect_error "--green with --height" 2 "not with --height" maps leadr "$tmp/h.exr" --height --green down --out "$tmp/o/x"
expect_error "negative base alpha" 2 "--base-alpha: expected a finite number >= 0, got '-1'" maps leadr "$tmp/n.exr" --out "$tmp/o/x" --base-alpha -1
expect_error "zero texel size" 2 "--texel-size: expected a finite number > 0, got '0'" maps leadr "$tmp/h.exr" --height --texel-size 0 --out "$tmp/o/x"
expect_error "unknown option" 2 "unknown option '--bogus'" maps leadr "$tmp/n.exr" --out "$tmp/o/x" --bogus
ok '[ -z "$(ls "$tmp/o")" ] && [ ! -e "$tmp/nodir" ]' "no output after errors: $(ls "$tmp/o")"
# a failure while committing (a directory in the way of the last file) leaves no file either
mkdir -p "$tmp/o/y_m2_mip6.exr"
"$mfkit" maps leadr "$tmp/n.exr" --out "$tmp/o/y" >"$tmp/out" 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 3 ] && [ ! -s "$tmp/out" ] && [ "$(wc -l <"$tmp/err")" -eq 1 ]' "commit failure: rc=$rc $(cat "$tmp/err")"
ok '[ "$(ls "$tmp/o")" = "y_m2_mip6.exr" ]' "commit failure leaves nothing: $(ls "$tmp/o")"
ok '[ -z "$(find "$tmp" -name "*.tmp*")" ]' "no temporary files left: $(find "$tmp" -name "*.tmp*")"

# --- a full disk: exit 3, one message, no output file and no temporary left --------------------
# (ulimit -f 8: files stop at 4 KiB, the mip-0 maps are larger; SIGXFSZ ignored, so write() fails
# with EFBIG as it would with ENOSPC.  Before the atomic image writes this exited 0 with
# zero-byte EXR files.)
mkdir "$tmp/full"
(trap '' XFSZ; ulimit -f 8; "$mfkit" maps leadr "$tmp/h.exr" "${hopt[@]}" --out "$tmp/full/f" --base-alpha 0 \
  >"$tmp/out" 2>"$tmp/err"); rc=$?
ok '[ $rc -eq 3 ]' "full disk: maps exit $rc (want 3): $(cat "$tmp/err")"
ok '[ "$(wc -l < "$tmp/err")" -eq 1 ] && grep -q "full/f" "$tmp/err"' "full disk: one message naming the file: $(cat "$tmp/err")"
ok '[ -z "$(ls -A "$tmp/full")" ]' "full disk: files left: $(ls -A "$tmp/full" | tr '\n' ' ')"

# --- help -----------------------------------------------------------------------------------------
out=$("$mfkit" maps --help); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q "^usage: mfkit maps lean|leadr|bump-roughness|toksvig INPUT --out PREFIX"' "maps --help"
out=$("$mfkit" --help)
ok 'echo "$out" | grep -q "maps lean|leadr"' "mfkit --help lists maps"

finish test_maps_cli
