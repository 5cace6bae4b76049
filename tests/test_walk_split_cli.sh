#!/usr/bin/env bash
# test_walk_split_cli.sh MFKIT -- `mfkit energy dielectric --split walk` end to end on a 2 x 2 x 2 table
# (20000 walks per column and side; about 30 s of CPU): bad arguments give one line; the gate passes,
# diel_walk included (t_split the balanced projection of t_walk in every column, t_walk against fresh
# walks); 1 and 2 threads give bitwise identical files; `mfkit eval dielectric-walk-split` reproduces
# the 6 walk fields of every column to the float32 rounding of the file; the file read back passes
# `mfkit validate`; a t_split moved by 0.01 (its projection is exact to rounding) fails diel_walk, and
# so does a t_walk moved by 0.2 (far beyond 4.5 se of a fresh walk, se <= 0.03 here).
mfkit="$1"
source "$(dirname "$0")/cli_test_lib.sh"

expect_error "split on dfg" 2 "\-\-split" energy dfg --split walk --out "$tmp/no1"
expect_error "walks without split" 2 "\-\-walks" energy dielectric --walks 5000 --out "$tmp/no2"
expect_error "walks too few" 2 "\-\-walks" energy dielectric --split walk --walks 10 --out "$tmp/no3"
ok '[ ! -e "$tmp/no1" ] && [ ! -e "$tmp/no2" ] && [ ! -e "$tmp/no3" ]' "a refused command creates no output directory"

"$mfkit" energy dielectric --split walk --walks 20000 --size 2 --threads 2 --out "$tmp/w2" >"$tmp/w2.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "--split walk on 2 threads exits 0 (rc=$rc): $(cat "$tmp/w2.log")"
ok '( for c in diel_finite diel_range diel_reference diel_furnace diel_split diel_walk; do grep -Eq "^$c +pass" "$tmp/w2.log" || exit 1; done )' \
   "the gate passes, diel_walk included: $(grep '^diel' "$tmp/w2.log")"
"$mfkit" energy dielectric --split walk --walks 20000 --size 2 --threads 1 --no-gate --quiet --out "$tmp/w1" >"$tmp/w1.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && cmp -s "$tmp/w1/dielectric.npy" "$tmp/w2/dielectric.npy" && cmp -s "$tmp/w1/dielectric.json" "$tmp/w2/dielectric.json"' \
   "1 and 2 threads give bitwise identical files (rc=$rc): $(cat "$tmp/w1.log")"

# eval dielectric-walk-split at every column (stream 2 x column): the 6 fields equal the stored float32
python3 - "$tmp/w2/dielectric.json" >"$tmp/ev_in.csv" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
ax = t["header"]["axes"]
def pts(a):
    return [a["lo"] + (a["hi"] - a["lo"]) * i / (a["size"] - 1) for i in range(a["size"])]
mu, r, z = (pts(a) for a in ax)
print("alpha,eta,walks,stream")
for k, zz in enumerate(z):
    for j, rr in enumerate(r):
        print("%.17g,%.17g,20000,%d" % (max(rr * rr, 1e-4), 1 + 2 * zz * zz, 2 * (k * len(r) + j)))
PY
"$mfkit" eval dielectric-walk-split --ndf ggx <"$tmp/ev_in.csv" >"$tmp/ev_out.csv" 2>"$tmp/ev_err"; rc=$?
bad=$(python3 - "$tmp/w2/dielectric.json" "$tmp/ev_out.csv" <<'PY'
import csv, json, sys
t = json.load(open(sys.argv[1]))
rows = list(csv.DictReader(open(sys.argv[2])))
n_mu = t["header"]["axes"][0]["size"]
out = []
names = ["t_walk", "t_walk_se", "t_walk_inv", "t_walk_inv_se", "t_split", "t_split_inv"]
if len(rows) * n_mu != len(t["data"]):
    out.append("%d rows for %d texels" % (len(rows), len(t["data"])))
for c, row in enumerate(rows):
    for i in range(n_mu):
        rec = t["data"][c * n_mu + i]
        for f, name in enumerate(names):
            v, s = float(row[name]), rec[14 + f]
            if not abs(v - s) <= 2.0 ** -24 * abs(v) + 1e-300:
                out.append("column %d mu %d %s: eval %.17g stored %.9g" % (c, i, name, v, s))
print("; ".join(out))
PY
)
ok '[ $rc -eq 0 ] && [ -z "$bad" ]' "eval dielectric-walk-split reproduces the walk fields of every column (rc=$rc): $bad $(cat "$tmp/ev_err")"

"$mfkit" validate "$tmp/w2/dielectric.json" >"$tmp/v.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && grep -q "^diel_walk .* pass" "$tmp/v.log" && grep -q "^diel_split .* pass" "$tmp/v.log"' \
   "the float32 file passes its gate when read back (rc=$rc): $(grep diel_ "$tmp/v.log")"
for corrupt in "18 0.01" "14 0.2"; do
  set -- $corrupt
  python3 - "$tmp/w2/dielectric.json" "$tmp/bad.json" "$1" "$2" <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))
f, d = int(sys.argv[3]), float(sys.argv[4])
n_mu = t["header"]["axes"][0]["size"]
c = 3  # the last column (alpha 0.5625, eta 2.125): a gate column, with multiple scattering on both sides
for i in range(n_mu):
    rec = t["data"][c * n_mu + i]
    rec[f] = rec[f] - d if rec[f] > 0.5 else rec[f] + d
json.dump(t, open(sys.argv[2], "w"))
PY
  "$mfkit" validate "$tmp/bad.json" >"$tmp/vb.log" 2>&1; rc=$?
  ok '[ $rc -ne 0 ] && grep -q "^diel_walk .* FAIL" "$tmp/vb.log"' "field $1 moved by $2 fails diel_walk (rc=$rc): $(grep diel_walk "$tmp/vb.log")"
done

finish test_walk_split_cli
