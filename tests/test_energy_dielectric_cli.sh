#!/usr/bin/env bash
# test_energy_dielectric_cli.sh MFKIT [full] -- `mfkit energy dielectric` end to end on a 2 x 2 x 2
# table.  Fast part (about 30 s of CPU): bad arguments give one line; the table computed on 1 and on
# 2 threads is bitwise identical, written in every format, tagged with its kind.  Full part (slow,
# about 2 min of CPU): the gate's range and white-furnace checks pass when the table is read back
# from the float32 .npy (range, references at the corners, white furnace), and a corrupted E_avg
# fails the furnace.  Not asserted, and why: the gate of this table computed in memory (no storage
# rounding) fails diel_reference at alpha 0.5625, mu 0.25, eta 0.47 inside (E_r 8e-9 below both
# references, 4 times the slack; a 32000^2 midpoint rule sides with the table; an open defect,
# docs/tables.md); read back from float32, the
# storage rounding (6e-8) covers it, so the read-back check below is the weaker one.
mfkit="$1"
mode="${2:-fast}"
source "$(dirname "$0")/cli_test_lib.sh"

expect_error "threads 0" 2 "\-\-threads" energy dielectric --threads 0 --out "$tmp/no1"
ok '[ ! -e "$tmp/no1" ]' "a refused command creates no output directory"

"$mfkit" energy dielectric --size 2 --threads 2 --no-gate --out "$tmp/d2" --quiet >"$tmp/d2.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "dielectric 2 on 2 threads exits 0 (rc=$rc): $(cat "$tmp/d2.log")"
for f in json npy h dds; do
  ok '[ -s "$tmp/d2/dielectric.$f" ]' "dielectric.$f written"
done
"$mfkit" energy dielectric --size 2 --threads 1 --no-gate --out "$tmp/d1" --quiet >"$tmp/d1.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && cmp -s "$tmp/d1/dielectric.npy" "$tmp/d2/dielectric.npy" && cmp -s "$tmp/d1/dielectric.json" "$tmp/d2/dielectric.json"' \
   "1 and 2 threads give bitwise identical files (rc=$rc): $(cat "$tmp/d1.log")"
info=$("$mfkit" table info "$tmp/d2/dielectric.json" 2>&1)
ok 'echo "$info" | grep -q "^kind: dielectric"' "table info names the kind: $(echo "$info" | head -2)"

if [ "$mode" = full ]; then
  "$mfkit" validate "$tmp/d2/dielectric.npy" >"$tmp/dv.log" 2>&1
  ok 'grep -q "^diel_furnace .* pass" "$tmp/dv.log" && grep -q "^diel_range .* pass" "$tmp/dv.log" && grep -q "^diel_finite .* pass" "$tmp/dv.log" && grep -q "^diel_reference .* pass" "$tmp/dv.log"' \
     "dielectric.npy passes its gate when read back: $(cat "$tmp/dv.log")"
  # E_avg of texel 0 (a furnace column) 1e-6 off: far beyond its bound (~1e-8), must fail the furnace
  python3 - "$tmp/d2/dielectric.json" "$tmp/d_bad.json" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
def walk(o):
    if isinstance(o, dict):
        for k, v in o.items():
            if k == "data" and isinstance(v, list):
                return o
            r = walk(v)
            if r is not None:
                return r
    return None
d = walk(t)
d["data"][0][5] += 1e-6
json.dump(t, open(sys.argv[2], "w"))
PY
  "$mfkit" validate "$tmp/d_bad.json" >"$tmp/dvb.log" 2>&1; rc=$?
  ok '[ $rc -ne 0 ] && grep -q "^diel_furnace .* FAIL" "$tmp/dvb.log"' "a corrupted E_avg fails the furnace (rc=$rc): $(cat "$tmp/dvb.log")"
fi

finish test_energy_dielectric_cli
