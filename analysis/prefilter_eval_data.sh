#!/bin/bash
# prefilter_eval_data.sh [--prefilter PF] MFKIT OUT.csv.gz -- the committed
# notebooks_data/prefilter_eval.csv.gz (issue 13, "Ground truth and evaluation"): `mfkit prefilter` on the
# shipped demo map tests/data/normalmaps/vgroove_16.png with the default specular views (8 x 16, what a user
# gets), then `mfkit prefilter-eval` with its default lights (16 texels per level, 3 square lights of half
# side 0.05, 0.2, 0.5, 4096 Monte Carlo points per record, seed 1); the per level / light / elevation
# summary (mean squared and relative RMS error of mfkit's lobes, naive, Toksvig and LEADR against both
# truths: the Monte Carlo one (mse_*, relrms_*) and the thesis' per-texel LTC shading (mean_truth_ltc,
# mse_truth_ltc, mse_ltc_*, relrms_ltc_*), with the prefilter's fitter revision in the provenance line,
# gzip -n -9.  About 18 s of CPU for the prefilter and 29 s for the evaluation.
# --prefilter PF reuses an output of the recorded prefilter command instead of running it (make_figures.sh,
# through prefilter_figures_data.sh, passes the scene figure's run); its manifest must say so (the map,
# GGX at alpha 0.1, 8 x 16 views, 4096 directions, 100 iterations, seed 1), else the script stops.  The
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
pf="mfkit prefilter $map --base ggx --views 8x16 --threads 2 --out PF"
ev="mfkit prefilter-eval PF --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out EV"
if [ -n "$pf_in" ]; then
    pf_check "$pf_in" "$map" 8 16
    pfdir=$pf_in
else
    "$mfkit" prefilter "$map" --base ggx --views 8x16 --threads 2 --out "$work/pf" >/dev/null
    pfdir=$work/pf
fi
"$mfkit" prefilter-eval "$pfdir" --texels 16 --samples 4096 --seed 1 --lights 0.05,0.2,0.5 --out "$work/ev" >/dev/null
ver=$("$mfkit" --version | awk '{print $2}')
rev=$(sed -n 's/.*"fitter_revision": *\([0-9]*\).*/\1/p' "$pfdir/prefilter.json" | head -n 1)
{
    echo "# command=$pf; $ev (analysis/prefilter_eval_data.sh; fitter_revision $rev), mfkit=$ver, seed=1, date=$stamp"
    cat "$work/ev/prefilter_eval_summary.csv"
} | gzip -n -9 > "$out.tmp"
mv "$out.tmp" "$out"
