#!/usr/bin/env bash
# test_prefilter_eval_diffuse.sh MFKIT SRC -- `mfkit prefilter-eval` on a diffuse (Lambert) table (a few
# seconds of CPU): a constant, tilted 4 x 4 normal map (n = (0.25, 0.15, 1) normalised, 8-bit), prefiltered
# with both tables (`--views 3x4`, the diffuse table at its default 2 x 4 views), then DIR/diffuse evaluated.
# - The records and summary have the Lambert layout (their header lines compared whole) and counts:
#   (4 + 1) footprints x 2 x 4 views x 2 lights = 80 records, 2 levels x 2 lights x 2 elevations = 8 rows.
# - Every footprint holds one normal, so naive (Lambert at the normalised mean normal, the truth's own
#   closed form) equals the exact truth to rounding: relative 1e-12 (the mean of four equal normals and
#   its normalisation change it by a few ulps).
# - LEADR's diffuse at the floor alpha 1e-4 (no slope variance) is Lambert to O(alpha^2) = 1e-8 in the mean
#   normal's frame, with the same geometric horizon: its Monte Carlo estimate must be within 5 standard
#   errors + 1e-6 x truth of the truth in every record (80 records: a false alarm has probability about
#   80 x 5.7e-7; 1e-6 is 100 times the O(alpha^2) bias).
# - The lobe: one normal, so the same lobe at every level (level 2's shading equals level 1's to 1e-9
#   relative), and it shades like the truth to the LTC fit's own error: relative RMS over the 16 level-1
#   records of each (light, elevation) at most 0.12 (measured 0.022 to 0.086: the lobe is the fit of a
#   tilted clamped cosine cut at the geometric horizon, not an LTC itself; with the footprint's normals
#   rotated by +phi instead of -phi in the eval the grazing rows read 0.56 and 0.74, so the bound checks
#   the view frame).
# - Refusals: --ltc-table on a Lambert table, a manifest whose base is neither GGX nor Lambert: one line,
#   non-zero exit, no output directory.
mfkit="$1"; src="$2"
source "$(dirname "$0")/cli_test_lib.sh"
py=/usr/bin/python3

write_const_map "$tmp/const_4.png"
"$mfkit" prefilter "$tmp/const_4.png" --views 3x4 --out "$tmp/pf" >"$tmp/pf.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && [ -s "$tmp/pf/diffuse/prefilter.json" ]' "prefilter (both tables) exits 0 (rc=$rc): $(tail -2 "$tmp/pf.log")"
"$mfkit" prefilter-eval "$tmp/pf/diffuse" --samples 4096 --lights 0.1,0.4 --out "$tmp/ev" >"$tmp/ev.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "prefilter-eval DIR/diffuse exits 0 (rc=$rc): $(tail -2 "$tmp/ev.log")"
res=$($py - "$tmp/ev" <<'PY'
import csv, math, sys
d = sys.argv[1]
out = []
hr = open(d + "/prefilter_eval.csv").readline().strip()
if hr != "level,row,col,i_theta,theta,i_phi,phi,light_half_side,truth,truth_se,mfkit,naive,leadr,leadr_se":
    out.append("records header %s" % hr)
hs = open(d + "/prefilter_eval_summary.csv").readline().strip()
if hs != ("level,light_half_side,i_theta,theta,records,mean_truth,mean_truth_se,mse_mfkit,relrms_mfkit,"
          "mse_naive,relrms_naive,mse_leadr,relrms_leadr,mean_leadr_se"):
    out.append("summary header %s" % hs)
rec = list(csv.DictReader(open(d + "/prefilter_eval.csv")))
if len(rec) != 80:
    out.append("records %d, expected 80" % len(rec))
worst_n = worst_z = 0.0
for r in rec:
    t = float(r["truth"])
    if float(r["truth_se"]) != 0.0 or not t > 0.0:
        out.append("truth %s, truth_se %s (exact and positive expected)" % (r["truth"], r["truth_se"])); break
    worst_n = max(worst_n, abs(float(r["naive"]) - t) / t)
    se = float(r["leadr_se"])
    worst_z = max(worst_z, (abs(float(r["leadr"]) - t) - 1e-6 * t) / se if se > 0 else math.inf)
print("naive vs truth: worst relative %.3g; leadr: worst (|diff| - 1e-6 truth) / se %.3g" % (worst_n, worst_z),
      file=sys.stderr)
if not worst_n <= 1e-12:
    out.append("naive off the exact truth by %.3g relative" % worst_n)
if not worst_z <= 5.0:
    out.append("leadr off the truth by %.3g standard errors" % worst_z)
for it in ("0", "1"):
    for h in ("0.10000000000000001", "0.40000000000000002"):
        sel = [r for r in rec if r["i_theta"] == it and r["light_half_side"] == h and r["level"] == "1"]
        mse = sum((float(r["mfkit"]) - float(r["truth"])) ** 2 for r in sel) / len(sel)
        rel = math.sqrt(mse) / (sum(float(r["truth"]) for r in sel) / len(sel))
        print("i_theta %s, h %.2g: mfkit relative RMS %.4f over %d records" % (it, float(h), rel, len(sel)),
              file=sys.stderr)
        if not rel <= 0.12:
            out.append("i_theta %s h %s: mfkit relative RMS %.4f > 0.12" % (it, h, rel))
l1 = {(r["i_theta"], r["i_phi"], r["light_half_side"]): float(r["mfkit"]) for r in rec if r["level"] == "1"}
for r in rec:
    if r["level"] == "2":
        a, b = l1[(r["i_theta"], r["i_phi"], r["light_half_side"])], float(r["mfkit"])
        if not abs(a - b) <= 1e-9 * abs(a):
            out.append("level 2 lobe shading %.17g != level 1's %.17g" % (b, a)); break
s = list(csv.DictReader(open(d + "/prefilter_eval_summary.csv")))
if len(s) != 8:
    out.append("summary rows %d, expected 8" % len(s))
print("; ".join(out) if out else "ok")
PY
)
ok '[ "$res" = ok ]' "constant map, diffuse table: naive is the exact truth, LEADR within its MC error, the lobe to the fit error ($res)"

expect_error "--ltc-table on a Lambert table" 2 "only for a GGX table" prefilter-eval "$tmp/pf/diffuse" \
  --ltc-table "$src/tests/data/reference/ltc_code_ggx_64.csv" --out "$tmp/bad1"
cp -r "$tmp/pf/diffuse" "$tmp/pfbase"
sed -i 's/"model": "lambert"/"model": "oren-nayar"/' "$tmp/pfbase/prefilter.json"
expect_error "unknown base" 2 "neither GGX" prefilter-eval "$tmp/pfbase" --out "$tmp/bad2"
ok '[ ! -e "$tmp/bad1" ] && [ ! -e "$tmp/bad2" ]' "refusals leave no output directory: $(ls "$tmp")"
finish test_prefilter_eval_diffuse
