#!/bin/bash
# prefilter_eval_data.sh [--prefilter PF] MFKIT OUT.csv.gz -- the committed
# notebooks_data/prefilter_eval.csv.gz (issue 13, "Ground truth and evaluation"): `mfkit prefilter` on the
# shipped demo map tests/data/normalmaps/vgroove_16.png with the default specular views (8 x 16, what a user
# gets), then `mfkit prefilter-eval` with its default lights (16 texels per level, 3 square lights of half
# side 0.05, 0.2, 0.5, 4096 Monte Carlo points per record, seed 1); the per level / light / elevation
# summary (mean squared and relative RMS error of mfkit's lobes, naive, Toksvig and LEADR against both
# truths: the Monte Carlo one (mse_*, relrms_*) and the thesis' per-texel LTC shading (mean_truth_ltc,
# mse_truth_ltc, mse_ltc_*, relrms_ltc_*), then naive and Toksvig as a renderer shades them (the isotropic LTC at
# the mean normal: mse_naive_ltc, relrms_naive_ltc, mse_ltc_naive_ltc, relrms_ltc_naive_ltc and the same for
# toksvig_ltc), with the prefilter's fitter revision in the provenance line,
# gzip -n -9.  The prefilter runs with --lobes 2 and the evaluation twice: the last three columns,
# mse_mfkit_two_lobes, relrms_mfkit_two_lobes and mse_unbiased_mfkit_two_lobes, are mfkit's against the
# Monte Carlo truth with the two-lobe table (prefilter-eval --lobes 2: the same records, mfkit's shading
# the halves' sum).  About 40 s of CPU for the prefilter and 2 x 29 s for the evaluations.
# --prefilter PF reuses an output of the recorded prefilter command instead of running it (make_figures.sh,
# through prefilter_figures_data.sh, passes the scene figure's run); its manifest must say so (the map,
# GGX at alpha 0.1, 8 x 16 views, 4096 directions, 100 iterations, seed 1) and it must hold the two-lobe
# table (PF/lobe_a, PF/lobe_b), else the script stops.  The
# lobes do not depend on the thread count, so the CSV is the same bytes either way.
# The provenance line's date is the time of the run, or SOURCE_DATE_EPOCH (seconds since 1970, UTC) when
# that is set: with the committed file's date the output is the committed file byte for byte.
# Run from the source directory: analysis/prefilter_eval_data.sh build/bin/mfkit notebooks_data/prefilter_eval.csv.gz
set -eu -o pipefail
usage() {
    echo "usage: analysis/prefilter_eval_data.sh [--prefilter PF] MFKIT OUT.csv.gz" >&2
    exit 2
}
pf_in=
if [ $# -ge 1 ] && [ "$1" = --prefilter ]; then
    [ $# -ge 2 ] || usage
    pf_in=$2
    shift 2
fi
[ $# -eq 2 ] || usage
mfkit=$1 out=$2
src=$(cd "$(dirname "$0")/.." && pwd)
. "$src/analysis/prefilter_data_common.sh"
stamp=$(pf_stamp)
work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_pfeval.XXXXXX")
trap 'rm -rf "$work"' EXIT
map=tests/data/normalmaps/vgroove_16.png
pf="mfkit prefilter $map --base ggx --views 8x16 --threads 2 --lobes 2 --out PF"
ev="mfkit prefilter-eval PF [--lobes 2] --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out EV"
if [ -n "$pf_in" ]; then
    pf_check "$pf_in" "$map" 8 16
    for h in a b; do
        [ -f "$pf_in/lobe_$h/prefilter.json" ] ||
            { echo "$pf_in: no two-lobe table (lobe_$h/prefilter.json): run mfkit prefilter --lobes 2" >&2; exit 2; }
    done
    pfdir=$pf_in
else
    "$mfkit" prefilter "$map" --base ggx --views 8x16 --threads 2 --lobes 2 --out "$work/pf" >/dev/null 2>&1
    pfdir=$work/pf
fi
"$mfkit" prefilter-eval "$pfdir" --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out "$work/ev" >/dev/null
"$mfkit" prefilter-eval "$pfdir" --lobes 2 --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out "$work/ev2" \
    >/dev/null
# the two-lobe evaluation's mfkit columns joined to the one-lobe summary (the same rows: level, light, elevation)
/usr/bin/python3 - "$work/ev/prefilter_eval_summary.csv" "$work/ev2/prefilter_eval_summary.csv" \
    >"$work/summary.csv" <<'PYEOF'
import csv, sys
one = list(csv.reader(open(sys.argv[1])))
two = list(csv.reader(open(sys.argv[2])))
h1, h2 = one[0], two[0]
keys = ("level", "light_half_side", "i_theta")
cols = ("mse_mfkit", "relrms_mfkit", "mse_unbiased_mfkit")
if h1 != h2 or len(one) != len(two):
    sys.exit("prefilter_eval_data.sh: the two evaluations' summaries do not match")
print(",".join(h1 + [c + "_two_lobes" for c in cols]))
for a, b in zip(one[1:], two[1:]):
    if [a[h1.index(k)] for k in keys] != [b[h1.index(k)] for k in keys]:
        sys.exit("prefilter_eval_data.sh: the two evaluations' rows differ")
    print(",".join(a + [b[h1.index(c)] for c in cols]))
PYEOF
ver=$("$mfkit" --version | awk '{print $2}')
rev=$(sed -n 's/.*"fitter_revision": *\([0-9]*\).*/\1/p' "$pfdir/prefilter.json" | head -n 1)
{
    echo "# command=$pf; $ev (analysis/prefilter_eval_data.sh; fitter_revision $rev), mfkit=$ver, seed=1, date=$stamp"
    cat "$work/summary.csv"
} | gzip -n -9 > "$out.tmp"
mv "$out.tmp" "$out"
