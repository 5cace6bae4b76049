#!/usr/bin/env bash
# test_energy_cli.sh MFKIT -- `mfkit energy` end to end on small tables: bad arguments give one line,
# exit 2 and no output directory; a Kulla-Conty and a DFG table are computed, pass their gate,
# are written in every format, and pass their gate again when read back from the float32 files
# (the gates' bounds add the storage rounding, mf_table_kind.h).
mfkit="$1"
source "$(dirname "$0")/cli_test_lib.sh"

expect_error "unknown KIND" 2 "unknown KIND 'bogus'" energy bogus --out "$tmp/no1"
expect_error "missing KIND" 2 "energy" energy --out "$tmp/no2"
expect_error "size below 2" 2 "\-\-size" energy dfg --size 1 --out "$tmp/no3"
expect_error "unknown NDF" 2 "\-\-ndf" energy dfg --ndf phong --out "$tmp/no4"
ok '[ ! -e "$tmp/no1" ] && [ ! -e "$tmp/no2" ] && [ ! -e "$tmp/no3" ] && [ ! -e "$tmp/no4" ]' \
   "a refused command creates no output directory: $(ls "$tmp")"

# Kulla-Conty 8 x 8 (about 1 s): the white-furnace gate passes, every format is written
"$mfkit" energy kulla-conty --size 8 --out "$tmp/kc" --quiet >"$tmp/kc.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "kulla-conty 8 exits 0 (rc=$rc): $(tail -3 "$tmp/kc.log")"
for f in json npy h dds; do
  ok '[ -s "$tmp/kc/kulla_conty.$f" ]' "kulla_conty.$f written"
done
ok '"$mfkit" validate "$tmp/kc/kulla_conty.npy" >"$tmp/kcv.log" 2>&1 && grep -q "^kc_furnace .* pass" "$tmp/kcv.log"' \
   "kulla_conty.npy passes its gate when read back: $(cat "$tmp/kcv.log")"

# DFG 4 x 4 (the gate's reference quadrature takes a few seconds): passes, and again from JSON
"$mfkit" energy dfg --size 4 --out "$tmp/dfg" --quiet >"$tmp/dfg.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "dfg 4 exits 0 (rc=$rc): $(tail -3 "$tmp/dfg.log")"
ok '"$mfkit" validate "$tmp/dfg/dfg.json" >"$tmp/dv.log" 2>&1 && grep -q "^dfg_reference .* pass" "$tmp/dv.log"' \
   "dfg.json passes its gate when read back: $(cat "$tmp/dv.log")"
info=$("$mfkit" table info "$tmp/dfg/dfg.json" 2>&1)
ok 'echo "$info" | grep -q "^kind: dfg"' "table info names the kind: $(echo "$info" | head -2)"

finish test_energy_cli
