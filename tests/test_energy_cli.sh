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
ok '"$mfkit" validate "$tmp/dfg/dfg.json" >"$tmp/dv.log" 2>&1 && grep -q "^dfg_reference .* pass" "$tmp/dv.log" && grep -q "^dfg_charlie_ref .* pass" "$tmp/dv.log"' \
   "dfg.json passes its gate when read back: $(cat "$tmp/dv.log")"
info=$("$mfkit" table info "$tmp/dfg/dfg.dds" 2>&1)
ok 'echo "$info" | grep -q "dds channels: R=dfg_scale G=dfg_bias B=dfg_charlie"' "dfg.dds holds scale, bias, Charlie: $info"
# a corrupted Charlie entry at a gate texel must fail the gate (field 4 of texel (0, 0), 1 % off; the
# gate reads the JSON's values as they are, which is also what catches the 1 %)
python3 - "$tmp/dfg/dfg.json" "$tmp/dfg_bad.json" <<'PY'
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
d["data"][0][4] *= 1.01  # texel (0, 0): alpha 0.0156, mu 0.125, Charlie ~1.4, bound ~1e-10
json.dump(t, open(sys.argv[2], "w"))
PY
"$mfkit" validate "$tmp/dfg_bad.json" >"$tmp/dvb.log" 2>&1; rc=$?
ok '[ $rc -ne 0 ] && grep -q "^dfg_charlie_ref .* FAIL" "$tmp/dvb.log"' "a corrupted Charlie entry fails the gate (rc=$rc): $(cat "$tmp/dvb.log")"
info=$("$mfkit" table info "$tmp/dfg/dfg.json" 2>&1)
ok 'echo "$info" | grep -q "^kind: dfg"' "table info names the kind: $(echo "$info" | head -2)"

# eval dfg: the split-sum terms of mf_energy_dfg; scale + bias is the albedo with F = 1, so it must
# equal `eval albedo` within the albedo's own bound plus 1e-9 (the bound of scale + bias, mf_albedo.h)
rows='alpha,cos_theta_o
0.5,1
1e-4,0.0039
0.2,0.5
1,0.01
0.05,0.9
1e-4,0.000174533
2,0.5
0.3,0'
for ndf in ggx beckmann; do
  printf '%s\n' "$rows" | "$mfkit" eval dfg --ndf $ndf >"$tmp/dfg_$ndf.csv" 2>"$tmp/dfg_err"; rc=$?
  ok '[ $rc -eq 0 ] && head -1 "$tmp/dfg_$ndf.csv" | grep -qx "alpha,cos_theta_o,dfg_scale,dfg_bias"' \
     "eval dfg --ndf $ndf header (rc=$rc): $(head -1 "$tmp/dfg_$ndf.csv") $(cat "$tmp/dfg_err")"
  printf '%s\n' "$rows" | "$mfkit" eval albedo --ndf $ndf >"$tmp/alb_$ndf.csv"
  bad=$(paste -d, "$tmp/dfg_$ndf.csv" "$tmp/alb_$ndf.csv" | awk -F, 'NR > 1 && NR <= 7 {
      d = $3 + $4 - $7; if (d < 0) d = -d
      if (!(d <= $8 + 1e-9) || !($3 > 0) || !($4 > 0)) print NR": "$0 }
    NR > 7 && ($3 != "nan" || $4 != "nan") { print NR" (outside the domain, want nan): "$0 }')
  ok '[ -z "$bad" ]' "eval dfg --ndf $ndf: scale + bias = albedo within its bound; nan outside the domain: $bad"
done
# the issue's value: GGX alpha 0.5, normal view, albedo 0.68784852 (scale + bias, F = 1)
v=$(awk -F, 'NR == 2 { printf "%.10f", $3 + $4 }' "$tmp/dfg_ggx.csv")
ok 'awk -v v="$v" "BEGIN { d = v - 0.68784852; exit !(d < 1e-8 && d > -1e-8) }"' "GGX 0.5 normal view: $v vs 0.68784852"
expect_error_in "eval dfg without --ndf" "$rows" 2 "dfg: --ndf ggx|beckmann is required" eval dfg

finish test_energy_cli
