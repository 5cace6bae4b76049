#!/bin/bash
# make_figures.sh BUILD_DIR OUT_DIR [DATA_DIR] -- run the accuracy studies (fast settings) and plot
# them (issue 6; docs/figures.md).  Run from the source directory, e.g.
#   analysis/make_figures.sh build out/figures
# CSV files go to DATA_DIR (default: a scratch directory, removed afterwards), figures (PNG + PDF)
# to OUT_DIR.  `analysis/make_figures.sh build out/figures notebooks_data` regenerates the committed
# data behind the figures (notebooks_data/README.md): only CSV files, each starting with its
# provenance line (command, version, seed, date), gzip-compressed (FILE.csv.gz, `gzip -n`: the bytes
# do not depend on the time; 17 MB of text become 3.2 MB) after plotting; the intermediate LTC fits
# go to a scratch directory, never to DATA_DIR.
# bench_ltc's per-polygon CSV of the reference table tests/data/reference/ltc_code_ggx_64.csv
# (vendored; its absence is an error) is added when bench_ltc was built (C++ dependencies on), and
# so is study_ltc_texels' per-texel CSV (paired with the table named by the environment variable MFKIT_LTC_TABLE, if set,
# e.g. MFKIT_LTC_TABLE=out/ltc/ltc_ggx.exr analysis/make_figures.sh build out/figures).  Needs /usr/bin/python3 with
# python3-numpy and python3-matplotlib.
set -eu
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
    echo "usage: analysis/make_figures.sh BUILD_DIR OUT_DIR [DATA_DIR]" >&2
    exit 2
fi
build=$1 out=$2
src=$(cd "$(dirname "$0")/.." && pwd)
bin=$build/analysis
work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_figures.XXXXXX")
trap 'rm -rf "$work"' EXIT
if [ $# -eq 3 ]; then
    data=$3
    mkdir -p "$data"
else
    data=$work/data
    mkdir -p "$data"
fi
for s in study_smith study_furnace study_proxy study_leadr_grid; do
    [ -x "$bin/$s" ] || { echo "make_figures.sh: $bin/$s not built (cmake --build $build)" >&2; exit 1; }
done
echo "== study_smith";       "$bin/study_smith" --out "$data/smith_lambda.csv"
echo "== study_furnace";     "$bin/study_furnace" --out "$data/furnace.csv"
echo "== study_proxy";       "$bin/study_proxy" --out "$data/ggx_proxy.csv"
echo "== study_leadr_grid";  "$bin/study_leadr_grid" --samples 65536 --out "$data/leadr_grid_convergence.csv" | tail -n 3
ref=$src/tests/data/reference/ltc_code_ggx_64.csv
[ -f "$ref" ] || { echo "make_figures.sh: the vendored reference table $ref is missing" >&2; exit 1; }
if [ -x "$bin/bench_ltc" ]; then
    echo "== bench_ltc"
    "$bin/bench_ltc" --views 64 --polygons 16 --csv "$data/bench_ltc.csv" "$ref" >/dev/null
fi
# study_ltc_texels: the reference table's error per texel (every 4th texel: 17 x 17, ~10 s); with
# MFKIT_LTC_TABLE=FILE (a 64 x 64 table of `mfkit fit ltc`, e.g. out/ltc/ltc_ggx.exr) paired with
# that table too (figure ltc_texel_pair).
if [ -x "$bin/study_ltc_texels" ]; then
    echo "== study_ltc_texels"
    "$bin/study_ltc_texels" --stride 4 --out "$data/ltc_texels.csv" "$ref" ${MFKIT_LTC_TABLE:+"$MFKIT_LTC_TABLE"} >/dev/null
fi
# study_sh_irradiance: 30 x 60 normals (~10 s); study_half: the reference table's half-float error
# (~1 s), and of MFKIT_LTC_TABLE if set, when it was built (C++ dependencies on).
[ -x "$bin/study_sh_irradiance" ] ||
    { echo "make_figures.sh: $bin/study_sh_irradiance not built (cmake --build $build)" >&2; exit 1; }
echo "== study_sh_irradiance"
"$bin/study_sh_irradiance" --thetas 30 --phis 60 --out "$data/sh_irradiance.csv"
half_tables=("$ref")
[ -n "${MFKIT_LTC_TABLE:-}" ] && half_tables+=("$MFKIT_LTC_TABLE")
if [ -x "$bin/study_half" ]; then
    echo "== study_half"
    "$bin/study_half" --out "$data/half_error.csv" "${half_tables[@]}"
fi
# LTC error per texel of each shipped BRDF: a 12 x 12 fit of each (--force: most fail their gate,
# issue 7; the figures show where), 16 polygons and 16384 Monte Carlo samples per texel (~40 s in
# all).  MFKIT_FIGURES_BRDFS chooses the BRDFs (default: all but leadr-diffuse, whose model integrates
# numerically per evaluation (256 nodes): its 12 x 12 fit, gate and map take minutes; "" for none).
if [ -x "$bin/study_ltc_texels" ] && [ -x "$build/bin/mfkit" ]; then
    for b in ${MFKIT_FIGURES_BRDFS-ggx beckmann lambert disney charlie}; do
        echo "== fit ltc --brdf $b --size 12, study_ltc_texels"
        "$build/bin/mfkit" fit ltc --brdf "$b" --size 12 --force --quiet --out "$work/ltc_$b" >/dev/null
        "$bin/study_ltc_texels" --polygons 16 --samples 16384 --out "$data/ltc_texels_$b.csv" \
            "$work/ltc_$b/ltc_${b//-/_}.json" >/dev/null
    done
fi
echo "== plot.py"
/usr/bin/python3 "$src/analysis/plot.py" "$data" "$out"
if [ $# -eq 3 ]; then
    for f in "$data"/*.csv; do gzip -n -9 -f "$f"; done
    echo "== $data: $(ls "$data"/*.csv.gz | wc -l) files, $(cat "$data"/*.csv.gz | wc -c) bytes (.csv.gz)"
fi
