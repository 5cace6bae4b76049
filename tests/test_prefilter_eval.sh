#!/usr/bin/env bash
# test_prefilter_eval.sh MFKIT SRC STUDY -- `mfkit prefilter-eval` (about 2 s of CPU), and
# analysis/study_prefilter_two.py over STUDY (analysis/study_prefilter_cell):
# a constant, tilted 4 x 4 normal map (n = (0.25, 0.15, 1) normalised, 8-bit) prefiltered with 3 x 4 views.
# - Every footprint holds one normal, so the naive and Toksvig baselines ARE the ground truth's integrand
#   (the same rotated GGX on the same light samples; Toksvig's |n_a| = 1 leaves alpha unchanged): each must
#   equal the Monte Carlo truth within 4 standard errors (in fact to rounding).
# - The prefiltered lobe is the fit of that rotated GGX: its shading must match the truth to the LTC fit's
#   own error.  Relative RMS error over texels and azimuths, light half side 0.4, the two non-grazing
#   elevations: bound 0.06 (measured 0.027 and 0.035; the MC standard error is about 3 % of the truth per
#   record and averages down over 16 records; the azimuth rotation taken with the wrong sign gives 0.23,
#   so the bound checks the view-frame convention).
# - Level 2's lobes are level 1's (the same one-normal effective BRDF): equal shading to 1e-9 relative.
# - The per-texel LTC truth (truth_ltc; the isotropic table fitted at the base alpha) is the LTC of the same
#   rotated GGX: against the Monte Carlo truth its relative RMS error at the two non-grazing elevations is
#   0.018 to 0.077 (the isotropic fit's own error; MC standard error about 0.6 %); bound 0.15.  Level 2's
#   equals level 1's to 1e-12 relative; the summary's truth_ltc MSEs of naive equal mse_truth_ltc (naive is
#   the MC truth's integrand here).  --ltc-table with the reference CSV runs; an unreadable table is refused.
# - The baselines as a renderer shades them (naive_ltc, toksvig_ltc: the isotropic LTC at the mean normal):
#   here the mean normal is each texel's, so naive_ltc is truth_ltc (the same lookup; 1e-14 relative: the
#   footprint average of up to 16 equal terms rounds by up to 16 ulps, 3.6e-15; measured 1.7e-15) and
#   toksvig_ltc is naive_ltc (alpha' = alpha up to the rounding of the mean normal's length, 1e-16, which
#   moves the lookup by about 3e-14 of a roughness column; its table's first column is the same fit as
#   naive's: 1e-12 relative); the summary's
#   mse_ltc_naive_ltc is 0 to that rounding and mse_naive_ltc equals mse_truth_ltc (1e-9 relative).  The
#   same with --ltc-table (one table for both).
# - Refusals: one line, non-zero exit, no output directory.
mfkit="$1"; src="$2"; study="$3"
source "$(dirname "$0")/cli_test_lib.sh"
py=/usr/bin/python3

write_const_map "$tmp/const_4.png"
"$mfkit" prefilter "$tmp/const_4.png" --base ggx --views 3x4 --out "$tmp/pf" >"$tmp/pf.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "prefilter of the constant map exits 0 (rc=$rc): $(tail -2 "$tmp/pf.log")"
"$mfkit" prefilter-eval "$tmp/pf" --samples 4096 --lights 0.1,0.4 --out "$tmp/ev" >"$tmp/ev.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "prefilter-eval exits 0 (rc=$rc): $(tail -2 "$tmp/ev.log")"
res=$($py - "$tmp/ev" <<'PY'
import csv, math, sys
d = sys.argv[1]
rec = list(csv.DictReader(open(d + "/prefilter_eval.csv")))
out = []
nrec = len(rec)
if nrec != (4 + 1) * 3 * 4 * 2:
    out.append("records %d, expected 120" % nrec)
worst = 0.0
for r in rec:
    t, se = float(r["truth"]), float(r["truth_se"])
    for m in ("naive", "toksvig"):
        z = abs(float(r[m]) - t) / se if se > 0 else (0.0 if float(r[m]) == t else math.inf)
        worst = max(worst, z)
if not worst <= 4.0:
    out.append("baseline off the truth by %.3g standard errors" % worst)
for it in ("0", "1"):
    sel = [r for r in rec if r["i_theta"] == it and float(r["light_half_side"]) == 0.4 and r["level"] == "1"]
    mse = sum((float(r["mfkit"]) - float(r["truth"])) ** 2 for r in sel) / len(sel)
    mt = sum(float(r["truth"]) for r in sel) / len(sel)
    rel = math.sqrt(mse) / mt
    print("i_theta %s: mfkit relative RMS %.4f over %d records" % (it, rel, len(sel)), file=sys.stderr)
    if not rel <= 0.06:
        out.append("i_theta %s: mfkit relative RMS %.4f > 0.06" % (it, rel))
l1 = {(r["i_theta"], r["i_phi"], r["light_half_side"]): float(r["mfkit"]) for r in rec if r["level"] == "1"}
for r in rec:
    if r["level"] == "2":
        a, b = l1[(r["i_theta"], r["i_phi"], r["light_half_side"])], float(r["mfkit"])
        if not abs(a - b) <= 1e-9 * max(abs(a), 1e-300):
            out.append("level 2 lobe shading %.17g != level 1's %.17g" % (b, a)); break
worst = 0.0
for it in ("0", "1"):
    for h in ("0.10000000000000001", "0.40000000000000002"):
        sel = [r for r in rec if r["i_theta"] == it and r["light_half_side"] == h and r["level"] == "1"]
        mse = sum((float(r["truth_ltc"]) - float(r["truth"])) ** 2 for r in sel) / len(sel)
        rel = math.sqrt(mse) / (sum(float(r["truth"]) for r in sel) / len(sel))
        worst = max(worst, rel)
print("truth_ltc vs truth: worst relative RMS %.4f" % worst, file=sys.stderr)
if not worst <= 0.15:
    out.append("truth_ltc vs the MC truth: relative RMS %.4f > 0.15" % worst)
l1 = {(r["i_theta"], r["i_phi"], r["light_half_side"]): float(r["truth_ltc"]) for r in rec if r["level"] == "1"}
for r in rec:
    if r["level"] == "2":
        a, b = l1[(r["i_theta"], r["i_phi"], r["light_half_side"])], float(r["truth_ltc"])
        if not abs(a - b) <= 1e-12 * max(abs(a), 1e-300):
            out.append("level 2 truth_ltc %.17g != level 1's %.17g" % (b, a)); break
s = list(csv.DictReader(open(d + "/prefilter_eval_summary.csv")))
if len(s) != 2 * 2 * 3:
    out.append("summary rows %d, expected 12" % len(s))
# mse_unbiased_<method>: per cell the mean of (est - truth)^2 - dse^2 over its records, dse = truth_se
# for mfkit (its lobe is exact) and se_diff_<baseline> for a baseline (recomputed here from the records:
# a wrong aggregation, or subtracting se^2 twice, fails; relative 1e-9 + 1e-30: the file's 17 digits).
# Naive and Toksvig are the truth's own integrand here: their se_diff is rounding (<= 1e-9 truth).
for r in rec:
    for m in ("naive", "toksvig"):
        if not float(r["se_diff_" + m]) <= 1e-9 * float(r["truth"]):
            out.append("se_diff_%s %s on the constant map (truth %s)" % (m, r["se_diff_" + m], r["truth"])); break
for c in s:
    sel = [r for r in rec if (r["level"], r["i_theta"]) == (c["level"], c["i_theta"]) and
           float(r["light_half_side"]) == float(c["light_half_side"])]
    for m in ("mfkit", "naive", "toksvig", "leadr"):
        dse = "truth_se" if m == "mfkit" else "se_diff_" + m
        want = sum((float(r[m]) - float(r["truth"])) ** 2 - float(r[dse]) ** 2 for r in sel) / len(sel)
        got = float(c["mse_unbiased_" + m])
        if not abs(got - want) <= 1e-9 * abs(want) + 1e-30:
            out.append("mse_unbiased_%s %.17g, recomputed %.17g" % (m, got, want)); break
for r in s:
    a, b = float(r["mse_ltc_naive"]), float(r["mse_truth_ltc"])
    if not abs(a - b) <= 1e-9 * max(a, 1e-300):
        out.append("summary: mse_ltc_naive %.17g != mse_truth_ltc %.17g" % (a, b)); break
for r in rec:
    tl, nl, tk = float(r["truth_ltc"]), float(r["naive_ltc"]), float(r["toksvig_ltc"])
    if not abs(nl - tl) <= 1e-14 * abs(tl) or not abs(tk - nl) <= 1e-12 * abs(nl):
        out.append("record: naive_ltc %.17g, toksvig_ltc %.17g, truth_ltc %.17g" % (nl, tk, tl)); break
for r in s:
    a, b = float(r["mse_naive_ltc"]), float(r["mse_truth_ltc"])
    if not abs(a - b) <= 1e-9 * max(b, 1e-300) or not float(r["mse_ltc_naive_ltc"]) <= (1e-14 * float(r["mean_truth_ltc"])) ** 2:
        out.append("summary: mse_naive_ltc %.17g, mse_truth_ltc %.17g, mse_ltc_naive_ltc %s" % (a, b, r["mse_ltc_naive_ltc"]))
        break
print("; ".join(out) if out else "ok")
PY
)
ok '[ "$res" = ok ]' "constant map: baselines equal the truth, the lobe matches it to the fit error ($res)"

"$mfkit" prefilter-eval "$tmp/pf" --samples 64 --lights 0.4 --ltc-table "$src/tests/data/reference/ltc_code_ggx_64.csv" \
  --out "$tmp/evref" >"$tmp/evref.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && [ -s "$tmp/evref/prefilter_eval_summary.csv" ]' "--ltc-table with the reference CSV runs (rc=$rc)"
res=$($py - "$tmp/evref/prefilter_eval.csv" <<'PY'
import csv, sys
bad = [r for r in csv.DictReader(open(sys.argv[1])) if not (
       abs(float(r["naive_ltc"]) - float(r["truth_ltc"])) <= 1e-14 * abs(float(r["truth_ltc"])) and
       abs(float(r["toksvig_ltc"]) - float(r["naive_ltc"])) <= 1e-12 * abs(float(r["naive_ltc"])))]
print("ok" if not bad else "naive_ltc %s, toksvig_ltc %s, truth_ltc %s" % (bad[0]["naive_ltc"], bad[0]["toksvig_ltc"],
                                                                          bad[0]["truth_ltc"]))
PY
)
ok '[ "$res" = ok ]' "--ltc-table: naive_ltc and toksvig_ltc are the per-texel LTC truth on the constant map ($res)"
expect_error "unreadable --ltc-table" 3 "\-\-ltc-table" prefilter-eval "$tmp/pf" --ltc-table "$tmp/const_4.png" --out "$tmp/bad5"
expect_error "missing directory" 3 "nonexistent/prefilter.json" prefilter-eval "$tmp/nonexistent" --out "$tmp/bad1"
expect_error "bad --lights" 2 "\-\-lights" prefilter-eval "$tmp/pf" --lights 0.1,-2 --out "$tmp/bad2"
cp -r "$tmp/pf" "$tmp/pfcut"
head -c 100 "$tmp/pf/ltc_mip2.npy" > "$tmp/pfcut/ltc_mip2.npy"
expect_error "truncated npy" 3 "ltc_mip2.npy" prefilter-eval "$tmp/pfcut" --out "$tmp/bad3"
cp -r "$tmp/pf" "$tmp/pfshape"
cp "$tmp/pf/ltc_mip2.npy" "$tmp/pfshape/ltc_mip1.npy"
expect_error "level shape mismatch" 2 "does not match" prefilter-eval "$tmp/pfshape" --out "$tmp/bad4"
ok '[ ! -e "$tmp/bad1" ] && [ ! -e "$tmp/bad2" ] && [ ! -e "$tmp/bad3" ] && [ ! -e "$tmp/bad4" ] && [ ! -e "$tmp/bad5" ]' \
   "refusals leave no output directory: $(ls "$tmp")"
# the per-level lines on stdout agree with the summary file: per level the mean over its cells (light x
# elevation) of mse_<method>, printed to 3 significant digits (so a relative tolerance of 5e-3, the
# rounding of %.3g), the cells where mfkit's MSE is below every baseline's, and whether its level mean
# is.  On the demo groove (3 x 4 views, 256 directions; about 2 s of CPU) level 1 is lost (naive and
# Toksvig exact) and levels 2-4 are won in some cells, so both answers and the counts are exercised.
"$mfkit" prefilter "$src/tests/data/normalmaps/vgroove_16.png" --base ggx --views 3x4 --samples 256 --out "$tmp/pfv" \
    >"$tmp/pfv.log" 2>&1; rc=$?
"$mfkit" prefilter-eval "$tmp/pfv" --texels 2 --samples 512 --lights 0.1,0.4 --out "$tmp/evv" >"$tmp/evv.log" 2>&1
rc2=$?
res=$($py - "$tmp/evv" "$tmp/evv.log" <<'PY'
import csv, re, sys
rows = list(csv.DictReader(open(sys.argv[1] + "/prefilter_eval_summary.csv")))
lines = [l for l in open(sys.argv[2]) if l.startswith("level ") and " the baselines shaded " not in l]
rlines = [l for l in open(sys.argv[2]) if l.startswith("level ") and " the baselines shaded " in l]
meth = ("mfkit", "naive", "toksvig", "leadr")
out, levels, answers = [], sorted({int(r["level"]) for r in rows}), set()
if len(lines) != len(levels):
    out.append("%d level lines for %d levels" % (len(lines), len(levels)))
for lev, line in zip(levels, lines):
    cells = [r for r in rows if int(r["level"]) == lev]
    mean = {m: sum(float(r["mse_" + m]) for r in cells) / len(cells) for m in meth}
    won = sum(all(float(r["mse_mfkit"]) < float(r["mse_" + m]) for m in meth[1:]) for r in cells)
    best = "yes" if all(mean["mfkit"] < mean[m] for m in meth[1:]) else "no"
    answers.add(best)
    got = {m: float(v) for m, v in re.findall(r"(mfkit|naive|toksvig|leadr) ([0-9.e+-]+)[,;]", line)}
    n = re.search(r"best in (\d+) of (\d+) cells .*best level mean: (yes|no)", line)
    if set(got) != set(meth) or not n:
        out.append("level %d: unparsed line %r" % (lev, line.strip())); continue
    for m in meth:
        if not abs(got[m] - mean[m]) <= 5e-3 * abs(mean[m]):
            out.append("level %d: %s printed %g, the file's mean %.6g" % (lev, m, got[m], mean[m]))
    if (int(n.group(1)), int(n.group(2)), n.group(3)) != (won, len(cells), best):
        out.append("level %d: printed %s of %s cells, %s; the file: %d of %d, %s" % (lev, n.group(1), n.group(2),
                   n.group(3), won, len(cells), best))
if answers != {"yes", "no"}:
    out.append("the demo should read both yes and no over its levels: %s" % sorted(answers))
# the renderer reading: mfkit against naive_ltc and toksvig_ltc, the same way
rmeth = ("naive_ltc", "toksvig_ltc")
if len(rlines) != len(levels):
    out.append("%d renderer lines for %d levels" % (len(rlines), len(levels)))
for lev, line in zip(levels, rlines):
    cells = [r for r in rows if int(r["level"]) == lev]
    mean = {m: sum(float(r["mse_" + m]) for r in cells) / len(cells) for m in ("mfkit",) + rmeth}
    won = sum(all(float(r["mse_mfkit"]) < float(r["mse_" + m]) for m in rmeth) for r in cells)
    best = "yes" if all(mean["mfkit"] < mean[m] for m in rmeth) else "no"
    got = {m: float(v) for m, v in re.findall(r"(naive_ltc|toksvig_ltc) ([0-9.e+-]+)[,;]", line)}
    n = re.search(r"^level (\d+): .*best in (\d+) of (\d+) cells, best level mean: (yes|no)", line)
    if set(got) != set(rmeth) or not n or int(n.group(1)) != lev:
        out.append("level %d: unparsed renderer line %r" % (lev, line.strip())); continue
    for m in rmeth:
        if not abs(got[m] - mean[m]) <= 5e-3 * abs(mean[m]):
            out.append("level %d: %s printed %g, the file's mean %.6g" % (lev, m, got[m], mean[m]))
    if (int(n.group(2)), int(n.group(3)), n.group(4)) != (won, len(cells), best):
        out.append("level %d: renderer line %s of %s cells, %s; the file: %d of %d, %s" % (lev, n.group(2), n.group(3),
                   n.group(4), won, len(cells), best))
# toksvig_ltc is Toksvig's widened lobe: on the groove's levels 2-4 (facets 30 deg off: alpha' 0.57), seen
# along the normal (i_theta 0), it is within the isotropic LTC's own error of the exact Toksvig
# (relative RMS measured 0.012 to 0.033; bound 0.1); shaded at the base's alpha instead it would read
# naive's lobe, about 7 times Toksvig's shading there
rec = list(csv.DictReader(open(sys.argv[1] + "/prefilter_eval.csv")))
for lev in ("2", "3", "4"):
    sel = [r for r in rec if r["level"] == lev and r["i_theta"] == "0"]
    mse = sum((float(r["toksvig_ltc"]) - float(r["toksvig"])) ** 2 for r in sel) / len(sel)
    mt = sum(float(r["toksvig"]) for r in sel) / len(sel)
    if not (mse ** 0.5 / mt <= 0.1):
        out.append("level %s: toksvig_ltc relative RMS %.4g against the exact Toksvig" % (lev, mse ** 0.5 / mt))
print("; ".join(out) if out else "ok")
PY
)
ok '[ $rc -eq 0 ] && [ $rc2 -eq 0 ] && [ "$res" = ok ]' "prefilter-eval's level lines match its summary file (rc=$rc, $rc2): $res: $(head -2 "$tmp/evv.log")"
# --lobes 2 (mfkit prefilter --lobes 2; mfkit's shading the sum of DIR/lobe_a's and DIR/lobe_b's lobes), the
# same groove and settings (about 4 s of CPU more): the one-lobe table in DIR is the same bits as without
# --lobes 2; the records' truth and baselines are the one-lobe evaluation's (the same seeds); at level 1
# every footprint holds one normal, so half a is the whole footprint and half b is empty: mfkit's records
# equal the one-lobe ones to 1e-5 relative (the half's albedo is its texels' mean, the whole's the albedo
# pyramid's: an ulp apart, and the fit answers that with a few 1e-7); levels 2-4, whose footprints hold
# both facets, must read at most a fifth of the one-lobe MSE (measured 9.7x, 16x and 12x lower).
"$mfkit" prefilter "$src/tests/data/normalmaps/vgroove_16.png" --base ggx --views 3x4 --samples 256 --lobes 2 \
    --out "$tmp/pfv2" >"$tmp/pfv2.log" 2>&1; rc=$?
nd=0
for f in "$tmp/pfv"/*.npy "$tmp/pfv"/*.exr; do cmp -s "$f" "$tmp/pfv2/$(basename "$f")" || nd=$((nd+1)); done
ok '[ $rc -eq 0 ] && [ $nd -eq 0 ] && [ -s "$tmp/pfv2/lobe_a/prefilter.json" ] && [ -s "$tmp/pfv2/lobe_b/ltc_mip4.npy" ]' \
   "prefilter --lobes 2 exits 0, writes lobe_a and lobe_b, and the one-lobe table's bits (rc=$rc, $nd files differ): $(tail -1 "$tmp/pfv2.log")"
"$mfkit" prefilter-eval "$tmp/pfv2" --lobes 2 --texels 2 --samples 512 --lights 0.1,0.4 --out "$tmp/evv2" >"$tmp/evv2.log" 2>&1
rc=$?
res=$($py - "$tmp/evv" "$tmp/evv2" <<'PY'
import csv, sys
one = list(csv.DictReader(open(sys.argv[1] + "/prefilter_eval.csv")))
two = list(csv.DictReader(open(sys.argv[2] + "/prefilter_eval.csv")))
out = [] if len(one) == len(two) and one else ["%d records against %d" % (len(two), len(one))]
worst1 = 0.0
for a, b in zip(one, two):
    if any(a[k] != b[k] for k in ("level", "row", "col", "i_theta", "i_phi", "truth", "truth_se", "naive", "toksvig", "leadr")):
        out.append("record %s differs outside mfkit" % [a[k] for k in ("level", "row", "col", "i_theta", "i_phi")]); break
    if a["level"] == "1":
        worst1 = max(worst1, abs(float(b["mfkit"]) / float(a["mfkit"]) - 1))
if worst1 > 1e-5:
    out.append("level 1: the two-lobe records differ from the one-lobe ones by %.3g relative" % worst1)
def mse(rows, lev):
    sel = [r for r in rows if r["level"] == str(lev)]
    return sum((float(r["mfkit"]) - float(r["truth"])) ** 2 for r in sel) / len(sel)
for lev in (2, 3, 4):
    m1, m2 = mse(one, lev), mse(two, lev)
    print("level %d: one lobe %.3g, two lobes %.3g (%.1fx)" % (lev, m1, m2, m1 / m2), file=sys.stderr)
    if not m2 <= m1 / 5:
        out.append("level %d: two lobes %.3g against one lobe %.3g" % (lev, m2, m1))
print("; ".join(out) if out else "ok")
PY
)
ok '[ $rc -eq 0 ] && [ "$res" = ok ] && grep -q "^mfkit: the two-lobe table" "$tmp/evv2.log"' \
   "prefilter-eval --lobes 2: the baselines' records unchanged, level 1 the one lobe, levels 2-4 at most a fifth of its MSE (rc=$rc): $res"
expect_error "--lobes 2 without the two-lobe tables" 3 "lobe_a/prefilter.json" prefilter-eval "$tmp/pfv" --lobes 2 --out "$tmp/bad7"
mkdir -p "$tmp/fake" && cp "$tmp/pfv"/* "$tmp/fake/" && mkdir -p "$tmp/fake/lobe_a" "$tmp/fake/lobe_b" && cp "$tmp/pfv"/* "$tmp/fake/lobe_a/"
expect_error "--lobes 2 with a lobe_a that is not a half table" 2 "is not half a of this table's two-lobe table" \
   prefilter-eval "$tmp/fake" --lobes 2 --out "$tmp/bad8"
# halves of another run (--seed 2) beside this table's one-lobe files: refused, naming what differs
"$mfkit" prefilter "$src/tests/data/normalmaps/vgroove_16.png" --base ggx --views 3x4 --samples 256 --lobes 2 --seed 2 \
    --out "$tmp/pfs2" >/dev/null 2>&1
mkdir -p "$tmp/mixed" && cp "$tmp/pfv2"/*.* "$tmp/mixed/" && cp -r "$tmp/pfs2/lobe_a" "$tmp/pfs2/lobe_b" "$tmp/mixed/"
expect_error "--lobes 2 with the halves of another run" 2 "another map, base BRDF, views or fit settings" \
   prefilter-eval "$tmp/mixed" --lobes 2 --out "$tmp/bad10"
expect_error "--lobes 3" 2 "\-\-lobes" prefilter-eval "$tmp/pfv2" --lobes 3 --out "$tmp/bad9"
# odd --samples: the estimator draws half its points on the light, half from the BRDF
expect_error "odd --samples" 2 "\-\-samples 17: must be even" prefilter-eval "$tmp/pfv" --samples 17 --out "$tmp/bad6"
# analysis/study_prefilter_two.py on the same table: every view of one level-2 footprint (3 x 4 views, 2
# lights: 12 records of 2 lights), one line per level with 6 cells (lights x elevations), the records file;
# a bad --texels is refused (exit 2), a failing study run stops it (exit 3: a texel outside the level)
"$py" "$src/analysis/study_prefilter_two.py" --prefilter "$tmp/pfv" --level 2 --texels 0,0 --study "$study" \
    --lights 0.1,0.4 --samples 512 --records "$tmp/two.csv" >"$tmp/two.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && grep -Eq "^level 2: cells won: stored [0-6] of 6, two [0-6] of 6; mean MSE: stored" "$tmp/two.log" && [ "$(wc -l <"$tmp/two.csv")" -eq 25 ]' \
   "study_prefilter_two.py runs (rc=$rc): $(tail -2 "$tmp/two.log")"
"$py" "$src/analysis/study_prefilter_two.py" --prefilter "$tmp/pfv" --level 2 --texels 0 --study "$study" >"$tmp/two2.log" 2>&1
rc=$?
ok '[ $rc -eq 2 ] && grep -q "\-\-texels 0: expected X,Y" "$tmp/two2.log"' "study_prefilter_two.py refuses --texels 0 (rc=$rc)"
"$py" "$src/analysis/study_prefilter_two.py" --prefilter "$tmp/pfv" --level 2 --texels 9,9 --study "$study" >"$tmp/two3.log" 2>&1
rc=$?
ok '[ $rc -eq 3 ] && grep -q "texel 9,9" "$tmp/two3.log"' "study_prefilter_two.py stops on a failing study run (rc=$rc): $(tail -1 "$tmp/two3.log")"
# fitter revision 10: the fit sees the magnitude it stores (the albedo over the lobe's mass above the
# horizon).  The constant map at alpha 0.03, default views, level 1, view (77.1 deg, 202.5 deg): the
# tilted texel faces away and its lobe leaves the hemisphere by 8 to 12 %.  The lobe's shading of the
# h = 0.2 and 0.8 lights must be within 10 % of the Monte Carlo truth (plus 3 standard errors, about
# 0.3 %): 10 % is about one LTC's own error for a GGX lobe at 77 deg; revision 10 reads 6.1 % and 3.3 %,
# revision 9 (magnitude not in the fit: the stored lobe 1 / h times the fitted one) 17 % and 16 %.
# (--force: the gate is not the subject here.)  About 4 s of CPU.
"$mfkit" prefilter "$tmp/const_4.png" --base ggx --roughness 0.03 --threads 2 --force --out "$tmp/pf03" >"$tmp/pf03.log" 2>&1
rc=$?
"$mfkit" prefilter-eval "$tmp/pf03" --texels 1 --samples 65536 --lights 0.2,0.8 --out "$tmp/ev03" >"$tmp/ev03.log" 2>&1
rc2=$?
res=$($py - "$tmp/ev03" <<'PY'
import csv, sys
sel = [r for r in csv.DictReader(open(sys.argv[1] + "/prefilter_eval.csv"))
       if r["level"] == "1" and r["i_theta"] == "6" and r["i_phi"] == "9"]
out = [] if len(sel) == 2 else ["%d records at (6, 9), want 2" % len(sel)]
for r in sel:
    t, m, se = float(r["truth"]), float(r["mfkit"]), float(r["truth_se"])
    print("h %.1f: truth %.6f (se %.2g), lobe %.6f, %+.1f %%" % (float(r["light_half_side"]), t, se, m, 100 * (m - t) / t),
          file=sys.stderr)
    if not abs(m - t) <= 0.10 * t + 3 * se:
        out.append("h %.1f: lobe %.6f against truth %.6f (%+.1f %%, bound 10 %% + 3 se)" % (float(r["light_half_side"]), m, t,
                   100 * (m - t) / t))
print("; ".join(out) if out else "ok")
PY
)
ok '[ $rc -eq 0 ] && [ $rc2 -eq 0 ] && [ "$res" = ok ]' "a grazing lobe leaving the hemisphere shades within 10 % (rc=$rc, $rc2): $res"
finish test_prefilter_eval
