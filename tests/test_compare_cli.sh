#!/usr/bin/env bash
# test_compare_cli.sh MFKIT SRC -- `mfkit compare`, `mfkit table plot` and `mfkit table lobe` end to
# end (docs/cli.md): refusals (one line, non-zero exit, no output left), a table against itself
# (zero differences, verdict "identical"), mfkit's fitted GGX table against the vendored reference
# ltc_code table (mfkit's has the smaller shading error: the verdict's direction), and the files of
# plot and lobe, whose CSV numbers are checked against the library at one texel.
# The PNG checks need /usr/bin/python3 with numpy and matplotlib (README and CI install them);
# without them the test says so and checks the CSV files only (--no-plots).
mfkit="$1"; src="$2"
. "$(dirname "$0")/cli_test_lib.sh"
ref=$src/tests/data/reference/ltc_code_ggx_64.csv
[ -f "$ref" ] || { echo "FAIL: the vendored reference table $ref is missing" >&2; exit 1; }
plots=1
if ! /usr/bin/python3 -c 'import numpy, matplotlib' 2>/dev/null; then
  echo "test_compare_cli: /usr/bin/python3 without numpy/matplotlib: PNGs not checked (--no-plots)"
  plots=0
fi
np=(); [ $plots -eq 1 ] || np=(--no-plots)
png_ok() { [ -s "$1" ] && [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ]; }

# --- tables: mfkit's GGX fit at 32 x 32 (6 s of CPU; the 64 x 64 default takes 14 s), a DFG table
# (another kind) -------------------------------------------------------------------------------------
"$mfkit" fit ltc --size 32 --out "$tmp/fit" --quiet >"$tmp/fit.log" 2>&1 || { cat "$tmp/fit.log"; echo "FAIL: mfkit fit ltc" >&2; exit 1; }
mf=$tmp/fit/ltc_ggx.json
"$mfkit" energy dfg --size 8 --out "$tmp/dfg" >/dev/null 2>&1 || { echo "FAIL: mfkit energy dfg" >&2; exit 1; }

# --- refusals: one line, exit status, nothing on stdout, no output directory ----------------------
expect_error "compare of two kinds" 2 "is a table of kind dfg, .* of kind ltc_isotropic: compare needs two tables of the same kind" \
  compare "$tmp/dfg/dfg.json" "$mf" --out "$tmp/o1"
ok '[ ! -e "$tmp/o1" ]' "refused compare left $tmp/o1 behind"
expect_error "compare of a missing file" 3 "missing.json" compare "$tmp/missing.json" "$mf"
printf 'garbage' >"$tmp/bad.json"
expect_error "compare of a bad file" 3 "bad.json" compare "$tmp/bad.json" "$mf" --out "$tmp/o2"
ok '[ ! -e "$tmp/o2" ]' "refused compare left $tmp/o2 behind"
expect_error "compare with one table" 2 "usage: mfkit compare A B" compare "$mf"
expect_error "compare --texels on a dfg table" 2 "apply to ltc_isotropic tables" compare "$tmp/dfg/dfg.json" "$tmp/dfg/dfg.npy" --texels 4
expect_error "compare --brdf unknown" 2 "unknown BRDF 'nope'" compare "$ref" "$mf" --brdf nope
expect_error "lobe of a dfg table" 2 "a dfg; lobes are drawn for ltc_isotropic tables" table lobe "$tmp/dfg/dfg.json" --at 0.5,0.5 --out "$tmp/o3"
expect_error "lobe outside the range" 2 "r 1.5 is outside the table's range" table lobe "$mf" --at 1.5,0.5 --out "$tmp/o3"
expect_error "lobe with an unknown BRDF" 2 "unknown BRDF 'nope'" table lobe "$ref" --brdf nope --at 0.5,0.5 --out "$tmp/o3"
expect_error "lobe with --at and --alpha" 2 "either as --at R,U or as --alpha" table lobe "$mf" --at 0.5,0.5 --alpha 0.3 --out "$tmp/o3"
expect_error "plot without --out" 2 "out" table plot "$mf"
ok '[ ! -e "$tmp/o3" ]' "refused lobe left $tmp/o3 behind"
if [ $plots -eq 1 ]; then
  MFKIT_PYTHON=$tmp/no_python expect_error "lobe without python" 2 "no_python: cannot run it" table lobe "$mf" --at 0.5,0.5 --out "$tmp/o4"
  ok '[ ! -e "$tmp/o4" ]' "lobe without python left $tmp/o4 behind"
fi
for c in "compare" "table plot" "table lobe"; do
  ok '$mfkit $c --help | grep -q "^usage: mfkit $c "' "$c --help"
done

# --- a table against itself: zero differences, "identical" ---------------------------------------
out=$("$mfkit" compare "$mf" "$tmp/fit/ltc_ggx.npy" --texels 4 --samples 4096 --out "$tmp/self" "${np[@]}"); rc=$?
ok '[ $rc -eq 0 ]' "compare with itself: exit $rc"
ok 'echo "$out" | grep -q "^verdict: identical: every common field of A and B is equal"' "self verdict: $(echo "$out" | tail -n 1)"
ok '[ "$(echo "$out" | grep -cE "^  (minv_00|minv_20|minv_02|minv_22|magnitude|fresnel|zero|sphere) +0 +0 +0 +-$")" -eq 8 ]' \
  "self: every field difference 0: $out"
ok 'awk -F, "!/^#/ && NR > 7 { for (i = 1; i <= NF; ++i) if (\$i != \"\" && h[i] ~ /^d_/ && \$i + 0 != 0) bad = 1 }
            !/^#/ && !n++ { for (i = 1; i <= NF; ++i) h[i] = \$i } END { exit bad }" "$tmp/self/compare_diff.csv"' \
  "self: compare_diff.csv has a non-zero d_ column"
ok '[ -s "$tmp/self/compare_diff.npy" ] && [ -s "$tmp/self/compare_diff.npy.json" ] && [ -s "$tmp/self/compare_shading.csv" ]' \
  "self: compare_diff.npy, .npy.json, compare_shading.csv"
if [ $plots -eq 1 ]; then
  ok 'png_ok "$tmp/self/compare_diff.png" && png_ok "$tmp/self/compare_shading.png"' "self: compare PNGs"
fi

# the same table as the other files users ship (KTX2, the legacy DDS pair): identical to its JSON
for x in "$tmp/fit/ltc_ggx.ktx2" "$tmp/fit/ltc_ggx_legacy_1.dds+$tmp/fit/ltc_ggx_legacy_2.dds"; do
  v=$("$mfkit" compare "$mf" "$x" --texels 2 --samples 256 | grep "^verdict: ")
  ok 'echo "$v" | grep -q "^verdict: identical"' "compare JSON vs $x: $v"
done

# --- mfkit's table against the reference: mfkit's is better (the verdict's direction) -------------
# mfkit's 32 x 32 table resampled onto the reference's 64 x 64 grid; 8 x 8 texels, 24 lights each, 2^15
# samples: measured 0.43x, the paired difference 7 standard errors from 0 (the default settings, 16 x 16
# texels and 2^16 samples, say 0.42x; the 64 x 64 default fit 0.42x too).
out=$("$mfkit" compare "$ref" "$mf" --texels 8 --samples 32768); rc=$?
v=$(echo "$out" | grep "^verdict: ")
ok '[ $rc -eq 0 ]' "compare reference vs mfkit: exit $rc"
ratio=$(echo "$v" | sed -n 's/^verdict: B is \([0-9.]*\)x A.s mean shading error .*/\1/p')
ok '[ -n "$ratio" ] && awk -v r="$ratio" "BEGIN { exit !(r < 0.8) }" && ! echo "$v" | grep -q "equally well"' \
  "mfkit's table must shade better than the reference: $v"
out=$("$mfkit" compare "$mf" "$ref" --texels 8 --samples 32768 | grep "^verdict: ")
ratio=$(echo "$out" | sed -n 's/^verdict: B is \([0-9.]*\)x A.s mean shading error .*/\1/p')
ok '[ -n "$ratio" ] && awk -v r="$ratio" "BEGIN { exit !(r > 1.25) }"' "swapped: the reference's error must be larger: $out"
# tables of different sizes: an 8 x 8 DFG table against a 16 x 16 one, resampled onto 16 x 16
"$mfkit" energy dfg --size 16 --out "$tmp/dfg16" >/dev/null 2>&1
out=$("$mfkit" compare "$tmp/dfg/dfg.json" "$tmp/dfg16/dfg.json"); rc=$?
ok '[ $rc -eq 0 ] && echo "$out" | grep -q "^common grid: 16 x 16 " && echo "$out" | grep -q "^verdict: A and B differ: largest |B - A| "' \
  "compare 8 x 8 with 16 x 16 DFG: $out"
ok 'echo "$out" | grep -q "^shading: not measured"' "dfg: shading not measured"

# --- table plot: the CSV and one PNG per field; the CSV equals the table file at one texel ----------
out=$("$mfkit" table plot "$mf" --out "$tmp/plot" "${np[@]}"); rc=$?
ok '[ $rc -eq 0 ] && [ -s "$tmp/plot/ltc_ggx_fields.csv" ]' "table plot: exit $rc, $out"
ok 'grep -q "^# gate: passed its gate$" "$tmp/plot/ltc_ggx_fields.csv"' "table plot: gate verdict in the CSV"
if [ $plots -eq 1 ]; then
  for f in minv_00 minv_20 minv_02 minv_22 magnitude fresnel zero sphere; do
    ok 'png_ok "$tmp/plot/ltc_ggx_$f.png"' "table plot: ltc_ggx_$f.png"
  done
fi
# texel (ir, iu) = (10, 20): the CSV row against the JSON file's record; the JSON stores float32
# values printed to 9 digits, the CSV the double the reader made of them: equal to 1e-7 relative
# (float32 rounding is 6e-8)
ok '/usr/bin/python3 - "$tmp/plot/ltc_ggx_fields.csv" "$mf" <<"EOF"
import csv, json, sys
rows = [r for r in csv.reader(l for l in open(sys.argv[1]) if not l.startswith("#"))]
h, row = rows[0], [r for r in rows[1:] if r[0] == "10" and r[1] == "20"][0]
t = json.load(open(sys.argv[2]))
fields = t["header"]["fields"]
rec = t["data"][(10 + 32 * 20) * len(fields):(11 + 32 * 20) * len(fields)]
for f, v in zip(fields, rec):
    c = float(row[h.index(f)])
    if abs(c - v) > 1e-7 * max(abs(v), 1e-30):
        sys.exit("%s: csv %r json %r" % (f, c, v))
if abs(float(row[h.index("r")]) - 10 / 31) > 1e-15 or abs(float(row[h.index("phys_alpha")]) - (10 / 31) ** 2) > 1e-15:
    sys.exit("axes")
EOF' "table plot: CSV record of texel (10, 20) differs from the table file"

# --- table lobe at texel (10, 20): the CSV's numbers against mfkit eval (the library) -----------------
r=$(awk 'BEGIN { printf "%.17g", 10 / 31 }'); u=$(awk 'BEGIN { printf "%.17g", 20 / 31 }')
out=$("$mfkit" table lobe "$mf" --at "$r,$u" --points 91 --out "$tmp/lobe" "${np[@]}"); rc=$?
ok '[ $rc -eq 0 ] && [ "$(grep -c "^incidence," "$tmp/lobe/lobe.csv")" -eq 91 ] && [ "$(grep -c "^perpendicular," "$tmp/lobe/lobe.csv")" -eq 91 ]' \
  "table lobe: exit $rc, 91 points per slice ($out)"
[ $plots -eq 0 ] || ok 'png_ok "$tmp/lobe/lobe.png"' "table lobe: lobe.png"
# one point of each slice: ltc = magnitude * D of M = inverse of the stored M^-1 (mfkit eval ltc),
# brdf = f(wo, wi) wi.z (mfkit eval brdf); M^-1 and the magnitude from the plot CSV of texel (10, 20)
/usr/bin/python3 - "$tmp/plot/ltc_ggx_fields.csv" "$tmp/lobe/lobe.csv" "$tmp" <<'EOF' || { echo "FAIL: lobe inputs" >&2; fails=$((fails+1)); }
import csv, sys
rows = [r for r in csv.reader(l for l in open(sys.argv[1]) if not l.startswith("#"))]
h, row = rows[0], [r for r in rows[1:] if r[0] == "10" and r[1] == "20"][0]
g = lambda n: float(row[h.index(n)])
a, c, b, d = g("minv_00"), g("minv_20"), g("minv_02"), g("minv_22")  # Minv = [[a, 0, b], [0, 1, 0], [c, 0, d]]
det = a * d - b * c
m = [d / det, 0, -b / det, 0, 1, 0, -c / det, 0, a / det]
meta = dict(l[1:].strip().split(": ", 1) for l in open(sys.argv[2]) if l.startswith("# ") and ": " in l)
pt = dict(kv.strip().split("=") for kv in meta["point"].split(","))
lobe = [r for r in csv.reader(l for l in open(sys.argv[2]) if not l.startswith("#"))]
lh, pick = lobe[0], [r for r in lobe[1:] if r[1] in ("-40", "20")]
with open(sys.argv[3] + "/ltc_in.csv", "w") as f:
    f.write("m00,m01,m02,m10,m11,m12,m20,m21,m22,w_x,w_y,w_z\n")
    for r in pick:
        f.write(",".join("%.17g" % x for x in m) + "," + ",".join(r[2:5]) + "\n")
import math
alpha, ct = float(pt["alpha"]), math.cos(math.radians(float(pt["theta_o_deg"])))
with open(sys.argv[3] + "/brdf_in.csv", "w") as f:
    f.write("alpha_x,alpha_y,wo_x,wo_y,wo_z,wi_x,wi_y,wi_z\n")
    for r in pick:
        f.write("%s,%s,%.17g,0,%.17g,%s\n" % (pt["alpha"], pt["alpha"], math.sqrt(1 - ct * ct), ct, ",".join(r[2:5])))
with open(sys.argv[3] + "/expect.csv", "w") as f:
    for r in pick:
        f.write("%s,%s,%s,%s\n" % (r[0], r[5], r[6], pt["magnitude"]))
EOF
"$mfkit" eval ltc <"$tmp/ltc_in.csv" >"$tmp/ltc_out.csv" && "$mfkit" eval brdf --ndf ggx <"$tmp/brdf_in.csv" >"$tmp/brdf_out.csv"
ok '[ $? -eq 0 ]' "mfkit eval ltc / brdf"
# ltc: the CLI unpacks M^-1 with mf_ltc_table_unpack, the test inverts it by hand: 1e-9 relative
# (a few hundred ulp of a matrix with condition number < 1e3 here); brdf: the same function on the
# same doubles up to wo (cos theta_o through acos/cos in the test): 1e-12 relative
ok 'paste -d, "$tmp/expect.csv" <(tail -n +2 "$tmp/ltc_out.csv" | awk -F, "{ print \$NF }") \
      <(tail -n +2 "$tmp/brdf_out.csv" | awk -F, "{ print \$NF \",\" \$8 }") |
    awk -F, "{ n++; l = \$4 * \$5; b = \$6 * \$7
               if (!(l == \$2 || (l - \$2 < 1e-9 * \$2 && \$2 - l < 1e-9 * \$2))) { print \"ltc \" \$2 \" vs \" l; bad = 1 }
               if (!(b == \$3 || (b - \$3 < 1e-12 * \$3 && \$3 - b < 1e-12 * \$3))) { print \"brdf \" \$3 \" vs \" b; bad = 1 } }
             END { exit bad || n != 4 }"' "table lobe: CSV values against mfkit eval ltc/brdf"
# the physical point gives the same lobe as its coordinates: --alpha (10/31)^2 --theta acos(1 - (20/31)^2)
th=$(awk 'BEGIN { u = 20 / 31; c = 1 - u * u; printf "%.17g", atan2(sqrt(1 - c * c), c) * 45 / atan2(1, 1) }')
al=$(awk 'BEGIN { printf "%.17g", (10 / 31) ^ 2 }')
"$mfkit" table lobe "$mf" --alpha "$al" --theta "$th" --points 91 --out "$tmp/lobe2" --no-plots >/dev/null
ok 'cmp -s <(grep -v "^#" "$tmp/lobe/lobe.csv" | cut -d, -f1-5) <(grep -v "^#" "$tmp/lobe2/lobe.csv" | cut -d, -f1-5) &&
    paste -d, <(grep -v "^#" "$tmp/lobe/lobe.csv" | tail -n +2) <(grep -v "^#" "$tmp/lobe2/lobe.csv" | tail -n +2) |
    awk -F, "{ d = \$6 - \$13; if (d < 0) d = -d; if (d > 1e-9 * (\$6 + 1e-300)) bad = 1 } END { exit bad }"' \
  "table lobe: --alpha/--theta of the texel give the lobe of --at (to 1e-9, the round trip through degrees)"
finish test_compare_cli
