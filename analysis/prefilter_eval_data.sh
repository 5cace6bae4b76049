#!/bin/bash
# prefilter_eval_data.sh MFKIT OUT.csv.gz -- the committed notebooks_data/prefilter_eval.csv.gz (issue 13,
# "Ground truth and evaluation"): `mfkit prefilter` on the shipped demo map tests/data/normalmaps/vgroove_16.png
# (4 x 4 views, to keep it a minute of CPU), then `mfkit prefilter-eval` (16 texels per level, 3 square
# lights, 4096 Monte Carlo points per record, seed 1); the per level / light / elevation summary
# (mean squared and relative RMS error of mfkit's lobes, naive, Toksvig and LEADR against both truths:
# the Monte Carlo one (mse_*, relrms_*) and the thesis' per-texel LTC shading (mean_truth_ltc,
# mse_truth_ltc, mse_ltc_*, relrms_ltc_*), with the prefilter's fitter revision in the provenance
# line, gzip -n (bytes independent of the time but for the date).
# Run from the source directory: analysis/prefilter_eval_data.sh build/bin/mfkit notebooks_data/prefilter_eval.csv.gz
set -eu
if [ $# -ne 2 ]; then
    echo "usage: analysis/prefilter_eval_data.sh MFKIT OUT.csv.gz" >&2
    exit 2
fi
mfkit=$1 out=$2
work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_pfeval.XXXXXX")
trap 'rm -rf "$work"' EXIT
map=tests/data/normalmaps/vgroove_16.png
pf="mfkit prefilter $map --base ggx --views 4x4 --threads 2 --out PF"
ev="mfkit prefilter-eval PF --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out EV"
"$mfkit" prefilter "$map" --base ggx --views 4x4 --threads 2 --out "$work/pf" >/dev/null
"$mfkit" prefilter-eval "$work/pf" --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out "$work/ev" >/dev/null
ver=$("$mfkit" --version | awk '{print $2}')
rev=$(sed -n 's/.*"fitter_revision": *\([0-9]*\).*/\1/p' "$work/pf/prefilter.json" | head -n 1)
{
    echo "# command=$pf; $ev (analysis/prefilter_eval_data.sh; fitter_revision $rev), mfkit=$ver, seed=1, date=$(date -u +%Y-%m-%dT%H:%M:%SZ)"
    cat "$work/ev/prefilter_eval_summary.csv"
} | gzip -n -9 > "$out.tmp"
mv "$out.tmp" "$out"
