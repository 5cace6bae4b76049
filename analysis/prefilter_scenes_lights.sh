#!/bin/bash
# prefilter_scenes_lights.sh [--prefilter PF] BUILD OUT.csv.gz [H,H,...] -- the scene renders' error against
# the size of the light (issue 13, "the thesis' error-vs-light-size figure"; Nahmias 2022, Ch. 4.1.3):
# `mfkit prefilter` on the demo map tests/data/normalmaps/vgroove_16.png (--base ggx --views 8x16: the
# default views, the scene figure's run), then analysis/render_prefilter_scenes without images (--images 0,
# --mc-samples 0: the per-texel LTC truth only) once per light half side H (default 0.25,0.5,1,1.5; 1 is
# the renderer's default, 1.5 its largest: the grazing light must stay above the plane).  One CSV: the
# renderer's columns with light_half_side first, under one provenance line, gzip -n -9.  About 8 s of CPU
# per light size plus 18 s for the prefilter.
# --prefilter PF reuses an output of the recorded prefilter command instead of running it (make_figures.sh,
# through prefilter_figures_data.sh, passes the scene figure's run); its manifest must say so, else the
# script stops.  The provenance date is now, or SOURCE_DATE_EPOCH when set (prefilter_data_common.sh).
# Run from the source directory: analysis/prefilter_scenes_lights.sh build notebooks_data/prefilter_scenes_lights.csv.gz
set -eu -o pipefail
usage() {
    echo "usage: analysis/prefilter_scenes_lights.sh [--prefilter PF] BUILD OUT.csv.gz [H,H,...]" >&2
    exit 2
}
pf_in=
if [ $# -ge 1 ] && [ "$1" = --prefilter ]; then
    [ $# -ge 2 ] || usage
    pf_in=$2
    shift 2
fi
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
    usage
fi
build=$1 out=$2 halves=${3-0.25,0.5,1,1.5}
mfkit=$build/bin/mfkit render=$build/analysis/render_prefilter_scenes
for f in "$mfkit" "$render"; do
    [ -x "$f" ] || { echo "prefilter_scenes_lights.sh: $f: not built" >&2; exit 2; }
done
src=$(cd "$(dirname "$0")/.." && pwd)
. "$src/analysis/prefilter_data_common.sh"
stamp=$(pf_stamp)
work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_pflights.XXXXXX")
trap 'rm -rf "$work"' EXIT
map=tests/data/normalmaps/vgroove_16.png
if [ -n "$pf_in" ]; then
    pf_check "$pf_in" "$map" 8 16
    pfdir=$pf_in
else
    "$mfkit" prefilter "$map" --base ggx --views 8x16 --threads 2 --out "$work/pf" >/dev/null 2>&1
    pfdir=$work/pf
fi
ver=$("$mfkit" --version | awk '{print $2}')
rev=$(sed -n 's/.*"fitter_revision": *\([0-9]*\).*/\1/p' "$pfdir/prefilter.json" | head -n 1)
{
    echo "# command=mfkit prefilter $map --base ggx --views 8x16 --threads 2 --out PF; render_prefilter_scenes --prefilter PF --images 0 --mc-samples 0 --light-half H for H in $halves (analysis/prefilter_scenes_lights.sh; fitter_revision $rev), mfkit=$ver, seed=1, date=$stamp"
    first=1
    for h in ${halves//,/ }; do
        "$render" --prefilter "$pfdir" --images 0 --mc-samples 0 --light-half "$h" --out "$work/sc" \
            --csv "$work/sc.csv" >/dev/null 2>&1
        if [ $first = 1 ]; then
            sed -n 2p "$work/sc.csv" | sed 's/^/light_half_side,/'
            first=0
        fi
        tail -n +3 "$work/sc.csv" | sed "s/^/$h,/"
    done
} | gzip -n -9 > "$out.tmp"
mv "$out.tmp" "$out"
