#!/usr/bin/env bash
# test_table_cli.sh MFKIT TEST_TABLE_IO -- `mfkit table convert|info` end to end, on the sample
# table that `test_table_io --write-sample` writes: every output format, a chain of conversions
# that gives back the same JSON byte for byte, half-float reporting, DDS channel choice, and
# every error giving one line on stderr, exit 2 (usage) or 3 (I/O, format), nothing on stdout
# and no output file.
mfkit="$1"; writer="$2"
. "$(dirname "$0")/cli_test_lib.sh"

"$writer" --write-sample "$tmp/t.json" || { echo "FAIL: test_table_io --write-sample" >&2; exit 1; }

# --- info --------------------------------------------------------------------------------------
out=$("$mfkit" table info "$tmp/t.json"); rc=$?
ok '[ $rc -eq 0 ]' "info exit code $rc"
ok 'echo "$out" | grep -qx "texels: 128 = 16 x 8"' "info texels: $out"
ok 'echo "$out" | grep -qF "axis 0: u, 16 texels, u in [0, 1], mapping one_minus_square: cos_theta_o = 1 - u^2 (cos_theta_o from 1 to 0)"' "info axis 0"
ok 'echo "$out" | grep -qF "axis 1: r, 8 texels, r in [0, 1], mapping square: alpha = r^2, clamped to >= 0.0001"' "info axis 1"
ok 'echo "$out" | grep -qF "record: 5 float32 fields (20 bytes), texel-major, first axis fastest: field f of texel (i0, i1) is value (i0 + 16 * i1) * 5 + f"' "info record"
ok 'echo "$out" | grep -qF "uv = (p - lo) / (hi - lo) * (n - 1) / n + 0.5 / n"' "info texel centres"
ok 'echo "$out" | grep -qE "^  4 +e_comp +[-0-9.e]+ +[-0-9.e]+ +0$"' "info field row"
ok 'echo "$out" | grep -qF "  tool = mfkit test_table_io"' "info metadata"

# --- convert to every format, and a chain back to JSON --------------------------------------------
for ext in exr dds h glsl hlsl json npy csv; do
  out=$("$mfkit" table convert "$tmp/t.json" "$tmp/c.$ext" 2>"$tmp/err"); rc=$?
  ok '[ $rc -eq 0 ] && [ -s "$tmp/c.$ext" ] && [ ! -s "$tmp/err" ]' "convert to .$ext (rc=$rc, $(cat "$tmp/err"))"
  ok 'echo "$out" | grep -qF "c.$ext: $ext, 128 texels x 5 fields"' "convert to .$ext stdout: $out"
done
ok '[ -s "$tmp/c.npy.json" ] && [ -s "$tmp/c.dds.json" ]' "sidecars of .npy and .dds"
ok 'grep -q "static const float c_data\[640\]" "$tmp/c.h"' "C header array"
ok 'grep -q "vec4 c_lookup(sampler2D table, float cos_theta_o, float alpha)" "$tmp/c.glsl"' "GLSL lookup"
"$mfkit" table convert "$tmp/t.json" "$tmp/a.exr" >/dev/null &&
  "$mfkit" table convert "$tmp/a.exr" "$tmp/b.npy" >/dev/null &&
  "$mfkit" table convert "$tmp/b.npy" "$tmp/back.json" >/dev/null
ok 'cmp -s "$tmp/t.json" "$tmp/back.json"' "json -> exr -> npy -> json gives the same file"
out=$("$mfkit" table convert "$tmp/t.json" "$tmp/p.h" --prefix my_lut)
ok 'grep -q "static const float my_lut_data\[640\]" "$tmp/p.h"' "--prefix"

# --- half floats: the error on stdout and in the metadata ----------------------------------------
out=$("$mfkit" table convert "$tmp/t.json" "$tmp/h.exr" --half); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -qE "^half-float conversion error: max abs [0-9.e-]+, max rel [0-9.e-]+ \(field [a-z_0-9]+ at texel \([0-9]+, [0-9]+\)\); 0 overflowed to infinity"' "--half report: $out"
out=$("$mfkit" table info "$tmp/h.exr")
ok 'echo "$out" | grep -q "^file: .*h.exr (exr, float16, mfkit metadata)$" && echo "$out" | grep -q "^half-float conversion error: max abs"' "info of a half EXR: $out"
ok 'echo "$out" | grep -qF "record: 5 float16 fields (10 bytes)"' "half record size"

# --- DDS channel choice ------------------------------------------------------------------------------
out=$("$mfkit" table convert "$tmp/t.json" "$tmp/d.dds" --half --dds-fields e_comp,scale,-,g1); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q "half-float conversion error"' "dds --half --dds-fields"
out=$("$mfkit" table info "$tmp/d.dds")
ok 'echo "$out" | grep -qx "dds channels: R=e_comp G=scale B=zero2 A=g1"' "info of the DDS: $out"
ok '[ "$(head -c 4 "$tmp/d.dds")" = "DDS " ] && [ "$(stat -c %s "$tmp/d.dds")" -eq $((148 + 128 * 8)) ]' "DDS size"

# --- errors: one line, exit 2 or 3, no stdout, no output file ----------------------------------------
expect_error "no subcommand" 2 "needs a subcommand" table
expect_error "unknown subcommand" 2 "unknown subcommand 'frobnicate'" table frobnicate
expect_error "convert without OUT" 2 "missing argument: usage: mfkit table convert IN OUT" table convert "$tmp/t.json"
expect_error "unknown option" 2 "unknown option '--bogus'" table convert "$tmp/t.json" "$tmp/x.exr" --bogus
expect_error "unknown output format" 2 "unknown output format" table convert "$tmp/t.json" "$tmp/x.xyz"
expect_error "write-only input" 2 "cannot read csv files" table convert "$tmp/c.csv" "$tmp/x.exr"
expect_error "--half for json" 2 "only .exr and .dds store half floats" table convert "$tmp/t.json" "$tmp/x.json" --half
expect_error "--dds-fields for exr" 2 "not a .dds file" table convert "$tmp/t.json" "$tmp/x.exr" --dds-fields a
expect_error "unknown DDS field" 2 "no field 'nope' in the table (fields: scale, bias, g1, dscale_dr, e_comp)" \
  table convert "$tmp/t.json" "$tmp/x.dds" --dds-fields nope
expect_error "bad prefix" 2 "invalid identifier prefix" table convert "$tmp/t.json" "$tmp/x.h" --prefix 9x
ok '[ ! -e "$tmp/x.exr" ] && [ ! -e "$tmp/x.json" ] && [ ! -e "$tmp/x.dds" ] && [ ! -e "$tmp/x.h" ]' "no output after usage errors"
expect_error "missing input" 3 "missing.json: cannot open" table info "$tmp/missing.json"
expect_error "missing output directory" 3 "nodir/x.exr" table convert "$tmp/t.json" "$tmp/nodir/x.exr"
ok '[ ! -e "$tmp/nodir" ]' "no directory created"
head -c 700 "$tmp/t.json" >"$tmp/trunc.json"
expect_error "truncated JSON" 3 "trunc.json: JSON: unexpected end of input" table convert "$tmp/trunc.json" "$tmp/y.exr"
ok '[ ! -e "$tmp/y.exr" ]' "no output from a truncated input"
head -c 300 "$tmp/c.npy" >"$tmp/trunc.npy"
expect_error "truncated NPY" 3 "trunc.npy: .*truncated or corrupt" table info "$tmp/trunc.npy"
head -c 1000 "$tmp/a.exr" >"$tmp/trunc.exr"
expect_error "truncated EXR" 3 "trunc.exr: " table info "$tmp/trunc.exr"
head -c 200 "$tmp/c.dds" >"$tmp/trunc.dds"
expect_error "truncated DDS" 3 "trunc.dds: .*truncated" table info "$tmp/trunc.dds"
ok '[ -z "$(ls "$tmp" | grep "\.tmp")" ]' "no temporary files left: $(ls "$tmp")"

# --- help -----------------------------------------------------------------------------------------
out=$("$mfkit" table --help); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q "^usage: mfkit table convert IN OUT"' "table --help"
out=$("$mfkit" table convert --help); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q -- "--dds-fields LIST"' "table convert --help"
out=$("$mfkit" table info --help); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q "mfkit table info FILE"' "table info --help"
out=$("$mfkit" --help)
ok 'echo "$out" | grep -q "table convert IN OUT"' "mfkit --help lists table"

finish test_table_cli
