#!/bin/bash
# prefilter_figures_data.sh BUILD DATA_DIR [--gzip] -- the data of the four prefilter figures (issue 13;
# docs/figures.md, docs/prefilter.md "Evaluation" and "Scene renders") from ONE `mfkit prefilter` run of
# the demo map tests/data/normalmaps/vgroove_16.png with the default specular views and the two-lobe table
# (--base ggx --views 8x16 --threads 2 --lobes 2, about 40 s of CPU):
#   prefilter_scenes.csv         render_prefilter_scenes --prefilter PF (128 x 128, 6 distances, both truths,
#                                images in a scratch directory; about 15 s of CPU)
#   prefilter_scenes_ssim.csv    prefilter_scenes_ssim.py on those images (python3-skimage; about 1 s)
#   prefilter_eval.csv           analysis/prefilter_eval_data.sh --prefilter PF (mfkit prefilter-eval, the
#                                default lights; about 29 s of CPU)
#   prefilter_scenes_lights.csv  analysis/prefilter_scenes_lights.sh --prefilter PF (4 light sizes; about
#                                30 s of CPU)
# each under its provenance line (the command, mfkit version, fitter revision, seed, date), in DATA_DIR;
# with --gzip as FILE.csv.gz (gzip -n -9), the form committed in notebooks_data/.  make_figures.sh runs it.
# The four provenance lines carry one date: SOURCE_DATE_EPOCH if set, else the start of the run (exported
# to the scripts above).  With SOURCE_DATE_EPOCH at the committed files' date and the same fitter, the
# output is the committed files byte for byte:
#   SOURCE_DATE_EPOCH=$(date -d "$(zcat notebooks_data/prefilter_eval.csv.gz | head -n 1 | sed 's/.*date=//')" +%s) \
#       analysis/prefilter_figures_data.sh build DIR --gzip && cmp DIR/prefilter_eval.csv.gz notebooks_data/prefilter_eval.csv.gz
# Run from the source directory (the manifest's map path is relative to it).
set -eu -o pipefail
if [ $# -lt 2 ] || [ $# -gt 3 ] || { [ $# -eq 3 ] && [ "$3" != --gzip ]; }; then
    echo "usage: analysis/prefilter_figures_data.sh BUILD DATA_DIR [--gzip]" >&2
    exit 2
fi
build=$1 data=$2 zip=${3-}
mfkit=$build/bin/mfkit render=$build/analysis/render_prefilter_scenes
for f in "$mfkit" "$render"; do
    [ -x "$f" ] || { echo "prefilter_figures_data.sh: $f: not built" >&2; exit 2; }
done
src=$(cd "$(dirname "$0")/.." && pwd)
. "$src/analysis/prefilter_data_common.sh"
stamp=$(pf_stamp)
[ -n "${SOURCE_DATE_EPOCH:-}" ] || SOURCE_DATE_EPOCH=$(date -u -d "$stamp" +%s)
export SOURCE_DATE_EPOCH
mkdir -p "$data"
work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_pffig.XXXXXX")
trap 'rm -rf "$work"' EXIT
map=tests/data/normalmaps/vgroove_16.png
pfcmd="mfkit prefilter $map --base ggx --views 8x16 --threads 2 --lobes 2 --out PF"
echo "== $pfcmd"
"$mfkit" prefilter "$map" --base ggx --views 8x16 --threads 2 --lobes 2 --out "$work/pf" >/dev/null 2>&1
ver=$("$mfkit" --version | awk '{print $2}')
rev=$(sed -n 's/.*"fitter_revision": *\([0-9]*\).*/\1/p' "$work/pf/prefilter.json" | head -n 1)
echo "== render_prefilter_scenes, prefilter_scenes_ssim.py"
"$render" --prefilter "$work/pf" --out "$work/scenes" >/dev/null 2>&1
{ echo "# command=$pfcmd; render_prefilter_scenes --prefilter PF --out SC (analysis/prefilter_figures_data.sh; fitter_revision $rev), mfkit=$ver, seed=1, date=$stamp"
  tail -n +2 "$work/scenes/prefilter_scenes.csv"; } >"$work/prefilter_scenes.csv"
/usr/bin/python3 "$src/analysis/prefilter_scenes_ssim.py" "$work/scenes" --csv "$work/ssim.csv" >/dev/null
{ echo "# command=$pfcmd; render_prefilter_scenes --prefilter PF --out SC; prefilter_scenes_ssim.py SC (analysis/prefilter_figures_data.sh; fitter_revision $rev), mfkit=$ver, seed=1, date=$stamp"
  tail -n +2 "$work/ssim.csv"; } >"$work/prefilter_scenes_ssim.csv"
echo "== analysis/prefilter_eval_data.sh --prefilter PF"
"$src/analysis/prefilter_eval_data.sh" --prefilter "$work/pf" "$mfkit" "$work/eval.csv.gz"
gzip -dc "$work/eval.csv.gz" >"$work/prefilter_eval.csv"
echo "== analysis/prefilter_scenes_lights.sh --prefilter PF"
"$src/analysis/prefilter_scenes_lights.sh" --prefilter "$work/pf" "$build" "$work/lights.csv.gz"
gzip -dc "$work/lights.csv.gz" >"$work/prefilter_scenes_lights.csv"
# all four written, then moved: no partial set in DATA_DIR
for f in prefilter_scenes prefilter_scenes_ssim prefilter_eval prefilter_scenes_lights; do
    if [ "$zip" = --gzip ]; then
        gzip -n -9 -c "$work/$f.csv" >"$data/$f.csv.gz.tmp"
    else
        cp "$work/$f.csv" "$data/$f.csv.tmp"
    fi
done
for f in prefilter_scenes prefilter_scenes_ssim prefilter_eval prefilter_scenes_lights; do
    if [ "$zip" = --gzip ]; then mv "$data/$f.csv.gz.tmp" "$data/$f.csv.gz"; else mv "$data/$f.csv.tmp" "$data/$f.csv"; fi
done
