#!/bin/bash
# test_plots: the accuracy studies (tiny grids) and analysis/plot.py end to end (issue 6).
#   test_plots.sh SOURCE_DIR STUDY_SMITH STUDY_FURNACE STUDY_PROXY STUDY_LEADR_GRID
# Runs each study into a scratch directory, checks the provenance header, plots with
# /usr/bin/python3 and checks that every expected PNG and PDF exists and is non-empty.
# Skips (exit 0, with the reason) only when /usr/bin/python3 lacks numpy or matplotlib; README
# and CI install python3-numpy and python3-matplotlib, so there it really runs.
set -u
src=$1 smith=$2 furnace=$3 proxy=$4 leadr=$5
py=/usr/bin/python3
if ! [ -x "$py" ] || ! "$py" -c 'import numpy, matplotlib' 2>/dev/null; then
    echo "test_plots: SKIPPED: $py with numpy and matplotlib not available (apt-get install python3-numpy python3-matplotlib)"
    exit 0
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_plots.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
fail() { echo "test_plots: FAIL: $*"; exit 1; }
mkdir -p "$tmp/data" "$tmp/fig"
"$smith" --nu-points 50 --grid 9 --out "$tmp/data/smith_lambda.csv" >/dev/null || fail "study_smith"
"$furnace" --thetas 5 --alphas 4 --quad 16 --strata 4 --out "$tmp/data/furnace.csv" >/dev/null || fail "study_furnace"
"$proxy" --grid 6 --out "$tmp/data/ggx_proxy.csv" >/dev/null || fail "study_proxy"
"$leadr" --samples 64 --out "$tmp/data/leadr_grid_convergence.csv" >/dev/null || fail "study_leadr_grid"
for f in smith_lambda furnace ggx_proxy; do
    head -n 1 "$tmp/data/$f.csv" | grep -Eq '^# command=.*, mfkit=[0-9.]+, seed=[^,]+, date=[0-9]{4}-[0-9]{2}-[0-9]{2}T' ||
        fail "$f.csv: bad provenance header: $(head -n 1 "$tmp/data/$f.csv")"
done
"$py" "$src/analysis/plot.py" "$tmp/data" "$tmp/fig" || fail "plot.py exited with $?"
for name in smith_walter_g1 smith_gaussian_lambda furnace_microfacet furnace_curves furnace_models \
    proxy_alpha_error proxy_alpha_curves ggx_rect_error leadr_grid_convergence; do
    for ext in png pdf; do
        [ -s "$tmp/fig/$name.$ext" ] || fail "missing or empty $name.$ext"
    done
done
echo "test_plots: OK ($(ls "$tmp/fig" | wc -l) files)"
