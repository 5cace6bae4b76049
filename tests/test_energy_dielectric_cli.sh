#!/usr/bin/env bash
# test_energy_dielectric_cli.sh MFKIT [full] -- `mfkit energy dielectric` end to end on a 2 x 2 x 2
# table.  Fast part (about 40 s of CPU): bad arguments give one line; the gate of the table in memory
# passes (diel_split included); the table computed on 1 and on
# 2 threads is bitwise identical, written in every format, tagged with its kind; `mfkit eval
# dielectric` (the pointwise function) reproduces all 16 entries (8 texels x 2 sides) of E_r and E_t
# and their bounds to the float32 rounding of the file.  Full part (slow, about 2 min of CPU): the
# gate of the table computed in memory passes (no storage rounding: diel_reference used to fail
# there at alpha 0.5625, mu 0.25, eta 0.47 inside, 4.06 times its slack, because its references
# did not end on the critical angle; docs/tables.md), the same table passes its gate when read back
# from the float32 .npy, and a corrupted E_avg fails the furnace.
mfkit="$1"
mode="${2:-fast}"
source "$(dirname "$0")/cli_test_lib.sh"

expect_error "threads 0" 2 "\-\-threads" energy dielectric --threads 0 --out "$tmp/no1"
ok '[ ! -e "$tmp/no1" ]' "a refused command creates no output directory"

"$mfkit" energy dielectric --size 2 --threads 2 --out "$tmp/d2" >"$tmp/d2.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "dielectric 2 on 2 threads exits 0 (rc=$rc): $(cat "$tmp/d2.log")"
for f in json npy h dds; do
  ok '[ -s "$tmp/d2/dielectric.$f" ]' "dielectric.$f written"
done
# the gate ran on the table in memory (about 7 s of CPU): every check passes, among them diel_split,
# the white furnace of reflection + transmission with the compensation split between them and the
# reciprocity of the transmitted flux (its power against a corrupted E_avg_inv: tests/test_energy.c)
ok '( for c in diel_finite diel_range diel_reference diel_furnace diel_split; do grep -Eq "^$c +pass" "$tmp/d2.log" || exit 1; done )' \
   "the gate of the 2^3 table passes, diel_split included: $(grep '^diel' "$tmp/d2.log")"
"$mfkit" energy dielectric --size 2 --threads 1 --no-gate --out "$tmp/d1" --quiet >"$tmp/d1.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && cmp -s "$tmp/d1/dielectric.npy" "$tmp/d2/dielectric.npy" && cmp -s "$tmp/d1/dielectric.json" "$tmp/d2/dielectric.json"' \
   "1 and 2 threads give bitwise identical files (rc=$rc): $(cat "$tmp/d1.log")"
# eval dielectric at every texel of the table, both sides: E_r, E_t and their bounds equal the stored
# float32 values within their rounding (2^-24 relative, the storage unit roundoff; the two are the
# same computation in double)
python3 - "$tmp/d2/dielectric.json" >"$tmp/ev_in.csv" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
ax = t["header"]["axes"]
def pts(a):
    return [a["lo"] + (a["hi"] - a["lo"]) * i / (a["size"] - 1) for i in range(a["size"])]
mu, r, z = (pts(a) for a in ax)
print("alpha,cos_theta_o,eta")
for k, zz in enumerate(z):
    for j, rr in enumerate(r):
        for i, m in enumerate(mu):
            eta = 1 + 2 * zz * zz
            for e in (eta, 1 / eta):
                print("%.17g,%.17g,%.17g" % (max(rr * rr, 1e-4), m, e))
PY
"$mfkit" eval dielectric --ndf ggx <"$tmp/ev_in.csv" >"$tmp/ev_out.csv" 2>"$tmp/ev_err"; rc=$?
bad=$(python3 - "$tmp/d2/dielectric.json" "$tmp/ev_out.csv" <<'PY'
import csv, json, sys
t = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
out = []
if len(rows) != 2 * len(t["data"]):
    out.append("%d rows for %d texels" % (len(rows), len(t["data"])))
for x, rec in enumerate(t["data"]):
    for side in range(2):
        row = rows[2 * x + side] if 2 * x + side < len(rows) else None
        if row is None:
            continue
        for col, f in (("E_R", 0), ("E_R_err", 1), ("E_T", 2), ("E_T_err", 3)):
            v, s = float(row[col]), rec[7 * side + f]
            if not abs(v - s) <= 2.0 ** -24 * abs(v) + 1e-300:
                out.append("texel %d side %d %s: eval %.17g stored %.9g" % (x, side, col, v, s))
print("; ".join(out))
PY
)
ok '[ $rc -eq 0 ] && [ -z "$bad" ]' "eval dielectric reproduces every entry of the 2^3 table (rc=$rc): $bad $(cat "$tmp/ev_err")"
info=$("$mfkit" table info "$tmp/d2/dielectric.json" 2>&1)
ok 'echo "$info" | grep -q "^kind: dielectric"' "table info names the kind: $(echo "$info" | head -2)"

if [ "$mode" = full ]; then
  "$mfkit" energy dielectric --size 2 --threads 2 --out "$tmp/dg" >"$tmp/dg.log" 2>&1; rc=$?
  # (the name is padded to 14 columns: diel_reference is followed by one space, so " +pass")
  ok '[ $rc -eq 0 ] && grep -Eq "^diel_reference +pass" "$tmp/dg.log" && grep -Eq "^diel_furnace +pass" "$tmp/dg.log"' \
     "the gate of the 2^3 table computed in memory passes (rc=$rc): $(cat "$tmp/dg.log")"
  "$mfkit" validate "$tmp/d2/dielectric.npy" >"$tmp/dv.log" 2>&1
  ok 'grep -q "^diel_furnace .* pass" "$tmp/dv.log" && grep -q "^diel_range .* pass" "$tmp/dv.log" && grep -q "^diel_finite .* pass" "$tmp/dv.log" && grep -q "^diel_reference .* pass" "$tmp/dv.log" && grep -q "^diel_split .* pass" "$tmp/dv.log"' \
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
