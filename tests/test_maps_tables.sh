#!/usr/bin/env bash
# test_maps_tables.sh MFKIT TEST_MAPS -- `mfkit maps ... --table-format LIST`: every MIP level's
# moments as a moment_map table in every format; the tables carry their kind, pass their gate
# (`mfkit validate`), read back bit for bit (a JSON or EXR level converted to .npy equals the .npy
# written directly), agree with the EXR moment maps (same field ranges), and bad lists are refused
# with one line and no output.
set -u
mfkit="$1"; helper="$2"
fails=0; checks=0
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
ok() { checks=$((checks+1)); if ! eval "$1"; then echo "FAIL: $2" >&2; fails=$((fails+1)); fi; }

"$helper" --write-height "$tmp/h.exr" || { echo "FAIL: test_maps could not write the input" >&2; exit 1; }
hopt=(--height --texel-size 0.015625 --height-scale 1)

"$mfkit" maps leadr "$tmp/h.exr" "${hopt[@]}" --out "$tmp/m" --table-format json,npy,h,exr,dds,glsl,csv \
  >"$tmp/out" 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 0 ] && [ ! -s "$tmp/err" ]' "maps --table-format exit $rc ($(cat "$tmp/err"))"
ok '[ ! -e "$tmp/.mfkit_maps_tables.tmp"* ] 2>/dev/null; ! ls -a "$tmp" | grep -q "tmp"' "no temporaries left: $(ls -a "$tmp")"
for k in 0 1 2 3 4 5 6; do
  for e in json npy npy.json h exr dds dds.json glsl csv; do
    ok '[ -s "$tmp/m_moments_mip$k.$e" ]' "level $k: m_moments_mip$k.$e written"
  done
done
ok '[ ! -e "$tmp/m_moments_mip7.json" ] && [ -s "$tmp/m_m1_mip6.exr" ]' "7 levels, the EXR maps still written"
ok 'grep -q "m_moments_mip3.npy: level 3" "$tmp/out" 2>/dev/null || grep -q "m_m1_mip3.exr: level 3" "$tmp/out"' "stdout lists the files"
ok 'grep -q "m_moments_mip6\.h\|m_moments_mip6.json" "$tmp/out"' "stdout lists the table files: $(tail -2 "$tmp/out")"
for k in 0 3 6; do
  for e in json npy exr; do
    info=$("$mfkit" table info "$tmp/m_moments_mip$k.$e" 2>&1)
    ok 'echo "$info" | grep -q "^kind: moment_map"' "level $k .$e: table info names the kind: $(echo "$info" | head -3)"
  done
  # a DDS holds 4 of the 5 fields (R, G, B, A = mean_x, mean_y, m_xx, m_xy): not a whole moment map
  info=$("$mfkit" table info "$tmp/m_moments_mip$k.dds" 2>&1)
  ok 'echo "$info" | grep -q "^kind: none (metadata says kind .moment_map. but no field .m_yy.)"' \
    "level $k .dds: 4 of 5 fields, named as such: $(echo "$info" | head -3)"
  # the kind's own gate passes on the float32 file (its covariance bound adds the storage rounding)
  "$mfkit" validate "$tmp/m_moments_mip$k.json" >"$tmp/v" 2>&1; rc=$?
  ok '[ $rc -eq 0 ] && grep -q "^moment_map gate" "$tmp/v" && grep -q "^moment_finite .* pass" "$tmp/v" &&
      grep -q "^moment_covariance .* pass" "$tmp/v"' "level $k: the moment_map gate passes (rc $rc): $(cat "$tmp/v")"
  # bitwise: JSON and EXR read back and written as .npy give the directly written .npy's data
  for e in json exr; do
    "$mfkit" table convert "$tmp/m_moments_mip$k.$e" "$tmp/back_$e$k.npy" >/dev/null 2>&1
    ok 'cmp -s "$tmp/back_$e$k.npy" "$tmp/m_moments_mip$k.npy"' "level $k: .$e -> .npy equals the written .npy"
  done
  # the same moments as the EXR maps: ranges of mean_x = R of m1, m_xx = R of m2 (base 0)
  r1=$("$mfkit" table info "$tmp/m_m1_mip$k.exr" | awk '$2 == "R" {print $3, $4}')
  r2=$("$mfkit" table info "$tmp/m_m2_mip$k.exr" | awk '$2 == "R" {print $3, $4}')
  t1=$("$mfkit" table info "$tmp/m_moments_mip$k.json" | awk '$2 == "mean_x" {print $3, $4}')
  t2=$("$mfkit" table info "$tmp/m_moments_mip$k.json" | awk '$2 == "m_xx" {print $3, $4}')
  ok '[ -n "$r1" ] && [ "$r1" = "$t1" ] && [ "$r2" = "$t2" ]' "level $k: table ranges equal the EXR maps' ($r1 / $t1, $r2 / $t2)"
done
ok 'grep -q "m_moments_mip0_lookup" "$tmp/m_moments_mip0.glsl"' "GLSL snippet named after the final file"

# --- refusals: exit 2, one line, nothing written --------------------------------------------------
for bad in "json,xyz" "json,json" "json," ""; do
  "$mfkit" maps leadr "$tmp/h.exr" "${hopt[@]}" --out "$tmp/bad" --table-format "$bad" >"$tmp/out" 2>"$tmp/err"; rc=$?
  ok '[ $rc -eq 2 ] && [ ! -s "$tmp/out" ] && [ "$(wc -l <"$tmp/err")" -eq 1 ] && ! ls "$tmp" | grep -q "^bad"' \
    "--table-format '$bad' refused (rc $rc: $(cat "$tmp/err"))"
done
"$mfkit" maps toksvig "$tmp/h.exr" "${hopt[@]}" --out "$tmp/bad" --table-format json >"$tmp/out" 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 2 ] && grep -q "toksvig" "$tmp/err" && ! ls "$tmp" | grep -q "^bad"' "toksvig refused: $(cat "$tmp/err")"
# a failure after some levels leaves nothing: an output directory that is not writable
if [ "$(id -u)" -ne 0 ]; then
  mkdir "$tmp/ro" && chmod 555 "$tmp/ro"
  "$mfkit" maps leadr "$tmp/h.exr" "${hopt[@]}" --out "$tmp/ro/x" --table-format json >"$tmp/out" 2>"$tmp/err"; rc=$?
  ok '[ $rc -eq 3 ] && [ -z "$(ls -A "$tmp/ro")" ]' "read-only directory: exit 3, nothing left (rc $rc)"
fi

echo "test_maps_tables: $checks checks, $fails failed"
[ $fails -eq 0 ]
