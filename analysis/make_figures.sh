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
# Every LTC table a figure shows gets its gate verdict (the "validated" metadata `mfkit fit ltc`
# records, or `mfkit validate --quick` for a table without it, e.g. the reference), passed to plot.py
# through MFKIT_FIGURE_GATES.  At the end the script lists the figures it skipped and why.
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
    data=$(cd "$data" && pwd)
else
    data=$work/data
    mkdir -p "$data"
fi
skipped=()   # "figure: why", printed at the end
gates=$work/gates.tsv
: >"$gates"
# gate_of TABLE: appends "NAME<TAB>verdict" to $gates (the table's "validated" metadata, else a quick
# run of its gate)
gate_of() {
    local t=$1 v
    v=$("$build/bin/mfkit" table info "$t" 2>/dev/null | sed -n 's/^  validated = //p')
    case "$v" in
        true) v="passed its gate (recorded by mfkit fit ltc)" ;;
        false) v="FAILED its gate (fitted with --force)" ;;
        *) if "$build/bin/mfkit" validate "$t" --quick --quiet >/dev/null 2>&1; then v="passed its gate (mfkit validate --quick)"
           else v="FAILED its gate (mfkit validate --quick)"; fi ;;
    esac
    printf '%s\t%s\n' "$(basename "$t")" "$v" >>"$gates"
}
for s in study_smith study_furnace study_proxy study_leadr_grid; do
    [ -x "$bin/$s" ] || { echo "make_figures.sh: $bin/$s not built (cmake --build $build)" >&2; exit 1; }
done
echo "== study_smith";       "$bin/study_smith" --out "$data/smith_lambda.csv"
echo "== study_furnace";     "$bin/study_furnace" --out "$data/furnace.csv"
echo "== study_proxy";       "$bin/study_proxy" --out "$data/ggx_proxy.csv"
echo "== study_leadr_grid";  "$bin/study_leadr_grid" --samples 65536 --out "$data/leadr_grid_convergence.csv" | tail -n 3
ref=$src/tests/data/reference/ltc_code_ggx_64.csv
[ -f "$ref" ] || { echo "make_figures.sh: the vendored reference table $ref is missing" >&2; exit 1; }
gate_of "$ref"
[ -n "${MFKIT_LTC_TABLE:-}" ] && gate_of "$MFKIT_LTC_TABLE"
# bench_ltc: the reference table, and MFKIT_LTC_TABLE beside it (one colour scale) when it is set
if [ -x "$bin/bench_ltc" ]; then
    echo "== bench_ltc"
    "$bin/bench_ltc" --views 64 --polygons 16 --csv "$data/bench_ltc.csv" "$ref" ${MFKIT_LTC_TABLE:+"$MFKIT_LTC_TABLE"} >/dev/null
    [ -n "${MFKIT_LTC_TABLE:-}" ] || skipped+=("mfkit's table beside the reference in ltc_polygon_error, ltc_texel_side, ltc_texel_pair: MFKIT_LTC_TABLE not set")
else
    skipped+=("ltc_polygon_error: $bin/bench_ltc not built (needs MFKIT_WITH_OIIO=ON)")
fi
# study_ltc_texels: the reference table's error per texel (every 4th texel: 17 x 17, ~10 s); with
# MFKIT_LTC_TABLE=FILE (a 64 x 64 table of `mfkit fit ltc`, e.g. out/ltc/ltc_ggx.exr) paired with
# that table too (figure ltc_texel_pair).
if [ -x "$bin/study_ltc_texels" ]; then
    echo "== study_ltc_texels"
    "$bin/study_ltc_texels" --stride 4 --out "$data/ltc_texels.csv" "$ref" ${MFKIT_LTC_TABLE:+"$MFKIT_LTC_TABLE"} >/dev/null
else
    skipped+=("ltc_texel_errors, ltc_texel_side, ltc_texel_pair, ltc_texel_errors_<brdf>: $bin/study_ltc_texels not built (needs MFKIT_WITH_OIIO=ON)")
fi
# study_sh_irradiance: 30 x 60 normals (~10 s); study_half: the reference table's half-float error
# (~1 s), and of MFKIT_LTC_TABLE if set, when it was built (C++ dependencies on).
[ -x "$bin/study_sh_irradiance" ] ||
    { echo "make_figures.sh: $bin/study_sh_irradiance not built (cmake --build $build)" >&2; exit 1; }
echo "== study_sh_irradiance"
"$bin/study_sh_irradiance" --thetas 30 --phis 60 --out "$data/sh_irradiance.csv"
# study_random_walk: mfkit's energy compensation against the random walk on the Smith microsurface
# (about 2 min of CPU at the default 100000 walks per cell, GGX and Beckmann; docs/math.md)
[ -x "$bin/study_random_walk" ] ||
    { echo "make_figures.sh: $bin/study_random_walk not built (cmake --build $build)" >&2; exit 1; }
echo "== study_random_walk"
"$bin/study_random_walk" --out "$data/random_walk.csv" | tail -n 6
half_tables=("$ref")
[ -n "${MFKIT_LTC_TABLE:-}" ] && half_tables+=("$MFKIT_LTC_TABLE")
if [ -x "$bin/study_half" ]; then
    echo "== study_half"
    "$bin/study_half" --out "$data/half_error.csv" "${half_tables[@]}"
else
    skipped+=("half_shading_error, half_rounding_error: $bin/study_half not built (needs MFKIT_WITH_OIIO=ON)")
fi
# LTC error per texel of each shipped BRDF: a 12 x 12 fit of each (--force: most fail their gate,
# issue 7; the figures show where), 16 polygons and 16384 Monte Carlo samples per texel (~40 s in
# all).  MFKIT_FIGURES_BRDFS chooses the BRDFs (default: all but leadr-diffuse, whose model integrates
# numerically per evaluation (adaptive panels): its 12 x 12 fit, gate and map take minutes; "" for none).
if [ -x "$bin/study_ltc_texels" ] && [ -x "$build/bin/mfkit" ]; then
    for b in ${MFKIT_FIGURES_BRDFS-ggx beckmann lambert disney charlie oren-nayar eon}; do
        echo "== fit ltc --brdf $b --size 12, study_ltc_texels"
        "$build/bin/mfkit" fit ltc --brdf "$b" --size 12 --force --quiet --out "$work/ltc_$b" >/dev/null
        gate_of "$work/ltc_$b/ltc_${b//-/_}.json"
        "$bin/study_ltc_texels" --polygons 16 --samples 16384 --out "$data/ltc_texels_$b.csv" \
            "$work/ltc_$b/ltc_${b//-/_}.json" >/dev/null
    done
    [[ " ${MFKIT_FIGURES_BRDFS-ggx beckmann lambert disney charlie oren-nayar eon} " == *" leadr-diffuse "* ]] ||
        skipped+=("ltc_texel_errors_leadr_diffuse: leadr-diffuse is not in MFKIT_FIGURES_BRDFS (its model integrates numerically per evaluation: its 12 x 12 fit takes minutes)")
elif [ -x "$bin/study_ltc_texels" ]; then
    skipped+=("ltc_texel_errors_<brdf>: $build/bin/mfkit not built")
fi
# The prefilter figures of the demo map (issue 13; docs/prefilter.md, "Evaluation", "Scene renders"): ONE
# `mfkit prefilter tests/data/normalmaps/vgroove_16.png --base ggx --views 8x16` (the default views, about
# 18 s of CPU) behind all four: the thesis' scene renders (Nahmias 2022, Ch. 4.1.3; about 15 s of CPU, the
# images stay in a scratch directory) and their SSIM (python3-skimage), mfkit prefilter-eval with its
# default lights (about 29 s of CPU) and the renders against the light's size (about 30 s of CPU):
# analysis/prefilter_figures_data.sh.
if [ -x "$bin/render_prefilter_scenes" ] && [ -x "$build/bin/mfkit" ]; then
    echo "== analysis/prefilter_figures_data.sh"
    (cd "$src" && analysis/prefilter_figures_data.sh "$build" "$data")
else
    skipped+=("prefilter_scenes, prefilter_scenes_ssim, prefilter_eval, prefilter_scenes_lights: $bin/render_prefilter_scenes or $build/bin/mfkit not built (needs Ceres and OpenImageIO)")
fi
echo "== plot.py"
MFKIT_FIGURE_GATES=$gates /usr/bin/python3 "$src/analysis/plot.py" "$data" "$out"
if [ ${#skipped[@]} -eq 0 ]; then
    echo "== skipped: none"
else
    echo "== skipped ${#skipped[@]}:"
    printf '   %s\n' "${skipped[@]}"
fi
if [ $# -eq 3 ]; then
    for f in "$data"/*.csv; do gzip -n -9 -f "$f"; done
    echo "== $data: $(ls "$data"/*.csv.gz | wc -l) files, $(cat "$data"/*.csv.gz | wc -c) bytes (.csv.gz)"
fi
