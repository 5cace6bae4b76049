#!/bin/bash
# test_plots: the accuracy studies (tiny grids) and analysis/plot.py end to end (issue 6).
#   test_plots.sh SOURCE_DIR STUDY_SMITH STUDY_FURNACE STUDY_PROXY STUDY_LEADR_GRID
# MFKIT_STUDY_LTC_TEXELS (environment; unset without OpenImageIO) is run on the reference
# table tests/data/reference/ltc_code_ggx_64.csv (vendored: if it is missing, the test fails).
# MFKIT_STUDY_SH_IRRADIANCE and MFKIT_STUDY_HALF (environment, set by tests/CMakeLists.txt; the
# latter only with the C++ dependencies) name study_sh_irradiance and study_half.
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
# study_ltc_texels: 4 x 4 texels of the reference table paired with itself (every difference must be
# exactly 0), its provenance header, its error paths (no output left behind).
ltc_figs=
ref=$src/tests/data/reference/ltc_code_ggx_64.csv
[ -f "$ref" ] || fail "the vendored reference table $ref is missing"
texels=${MFKIT_STUDY_LTC_TEXELS:-}
if [ -z "$texels" ]; then
    echo "test_plots: MFKIT_STUDY_LTC_TEXELS not set (study_ltc_texels needs MFKIT_WITH_OIIO=ON): its figures are not checked"
else
    lt=$tmp/data/ltc_texels.csv
    "$texels" --help | grep -q '^usage: study_ltc_texels' || fail "study_ltc_texels --help"
    "$texels" --stride 31 --polygons 4 --samples 1024 --out "$lt" "$ref" "$ref" >/dev/null || fail "study_ltc_texels"
    head -n 1 "$lt" | grep -Eq '^# command=study_ltc_texels .*, mfkit=[0-9.]+, seed=1, date=[0-9]{4}-[0-9]{2}-[0-9]{2}T' ||
        fail "ltc_texels.csv: bad provenance header: $(head -n 1 "$lt")"
    [ "$(tail -n +3 "$lt" | wc -l)" -eq 16 ] || fail "ltc_texels.csv: expected 16 texels (stride 31 of 64: 0, 31, 62, 63)"
    awk -F, 'NR == 2 { for (i = 1; i <= NF; ++i) col[$i] = i; n = 0
                       for (k in col) if (k ~ /^d_/) ++n; if (n != 8) { print "d_ columns: " n; bad = 1 } }
             NR > 2 { for (k in col) if (k ~ /^d_/ && $col[k] + 0 != 0) { print k " = " $col[k] " at row " NR; bad = 1 }
                      if ($col["second_poly_mean_abs"] != $col["poly_mean_abs"]) { print "second_poly_mean_abs differs at row " NR; bad = 1 }
                      if (!($col["poly_mean_rel"] > 0) || !($col["lobe_l1"] >= 0)) { print "bad errors at row " NR; bad = 1 } }
             END { exit bad }' "$lt" || fail "ltc_texels.csv: the table paired with itself must give differences of exactly 0"
    "$texels" --out "$tmp/bad.csv" "$tmp/missing.json" 2>"$tmp/err.txt"; rc=$?
    [ $rc -eq 3 ] && grep -q 'missing.json' "$tmp/err.txt" || fail "study_ltc_texels, missing table: exit $rc, $(cat "$tmp/err.txt")"
    "$texels" --stride 64 --out "$tmp/no_such_dir/x.csv" "$ref" >/dev/null 2>"$tmp/err.txt"; rc=$?
    [ $rc -eq 4 ] && grep -q 'no_such_dir' "$tmp/err.txt" || fail "study_ltc_texels, unwritable --out: exit $rc"
    ! ls "$tmp"/bad.csv* >/dev/null 2>&1 || fail "study_ltc_texels left output behind after an error"
    # a per-BRDF file (make_figures.sh writes ltc_texels_<brdf>.csv) gets suffixed figure names
    cp "$lt" "$tmp/data/ltc_texels_ggx.csv"
    ltc_figs="ltc_texel_errors ltc_texel_pair ltc_texel_side ltc_texel_errors_ggx ltc_texel_pair_ggx ltc_texel_side_ggx"
fi
# study_sh_irradiance (always built; MFKIT_STUDY_SH_IRRADIANCE is set by tests/CMakeLists.txt, else
# it is looked up beside study_smith) on a 6 x 12 grid of normals, and study_half (only with the C++
# dependencies: MFKIT_STUDY_HALF is set then) on the reference table: provenance header, the row
# count, bounds the numbers must obey, the error paths (no output left behind).
sh_study=${MFKIT_STUDY_SH_IRRADIANCE:-$(dirname "$smith")/study_sh_irradiance}
[ -x "$sh_study" ] || fail "study_sh_irradiance not found at $sh_study"
shc=$tmp/data/sh_irradiance.csv
"$sh_study" --help | grep -q '^usage: study_sh_irradiance' || fail "study_sh_irradiance --help"
"$sh_study" --thetas 6 --phis 12 --out "$shc" >"$tmp/sh.txt" || fail "study_sh_irradiance: $(tail -n 3 "$tmp/sh.txt")"
head -n 1 "$shc" | grep -Eq '^# command=study_sh_irradiance .*, mfkit=[0-9.]+, seed=none, date=[0-9]{4}-[0-9]{2}-[0-9]{2}T' ||
    fail "sh_irradiance.csv: bad provenance header: $(head -n 1 "$shc")"
[ "$(tail -n +3 "$shc" | wc -l)" -eq 864 ] || fail "sh_irradiance.csv: expected 4 environments x 3 windows x 72 normals"
# without a window, |E_SH - E| <= (3/32) integral L dw for any L >= 0 (docs/math.md)
awk -F, 'NR > 2 && $2 == "none" && !($10 + 0 <= 0.09375 + 1e-12) { print "norm_err " $10 " at row " NR; bad = 1 }
         END { exit bad }' "$shc" || fail "sh_irradiance.csv: error above the 3/32 bound"
"$sh_study" --thetas 1 --out "$tmp/bad.csv" 2>"$tmp/err.txt"; rc=$?
[ $rc -eq 2 ] && grep -q -- '--thetas' "$tmp/err.txt" || fail "study_sh_irradiance --thetas 1: exit $rc, $(cat "$tmp/err.txt")"
"$sh_study" --thetas 2 --phis 1 --out "$tmp/no_such_dir/x.csv" >/dev/null 2>"$tmp/err.txt"; rc=$?
[ $rc -eq 3 ] && grep -q 'no_such_dir' "$tmp/err.txt" || fail "study_sh_irradiance, unwritable --out: exit $rc"
! ls "$tmp"/bad.csv* >/dev/null 2>&1 || fail "study_sh_irradiance left output behind after an error"
sh_figs="sh_irradiance_error sh_irradiance_curves"
half_figs=
half_ref=$ref
if [ -z "${MFKIT_STUDY_HALF:-}" ]; then
    echo "test_plots: study_half not built (MFKIT_WITH_OIIO=OFF): its figures are not checked"
else
    hc=$tmp/data/half_error.csv
    "$MFKIT_STUDY_HALF" --help | grep -q '^usage: study_half' || fail "study_half --help"
    "$MFKIT_STUDY_HALF" --polygons 2 --out "$hc" "$half_ref" >"$tmp/half.txt" || fail "study_half: $(tail -n 3 "$tmp/half.txt")"
    head -n 1 "$hc" | grep -Eq '^# command=study_half .*, mfkit=[0-9.]+, seed=1, date=[0-9]{4}-[0-9]{2}-[0-9]{2}T' ||
        fail "half_error.csv: bad provenance header: $(head -n 1 "$hc")"
    [ "$(tail -n +3 "$hc" | wc -l)" -eq $((64 * 64 * 9)) ] || fail "half_error.csv: expected 64 x 64 texels x (8 fields + shading)"
    # round to nearest: relative error <= 2^-11 in half's normal range (|x| >= 2^-14); every texel shaded
    awk -F, 'NR > 2 && $2 == "value" && $12 != "nan" && ($9 >= 2^-14 || $9 <= -2^-14) && !($12 + 0 <= 2^-11) {
                 print "rel_err " $12 " of " $9 " at row " NR; bad = 1 }
             NR > 2 && $2 == "shading" && ($14 == "nan" || !($14 + 0 >= 0 && $14 + 0 < 0.1)) {
                 print "shade_rel_worst " $14 " at row " NR; bad = 1 }
             END { exit bad }' "$hc" || fail "half_error.csv: a value breaks the half rounding bound or a texel is unshaded"
    "$MFKIT_STUDY_HALF" --out "$tmp/bad.csv" "$tmp/missing.json" 2>"$tmp/err.txt"; rc=$?
    [ $rc -eq 3 ] && grep -q 'missing.json' "$tmp/err.txt" || fail "study_half, missing table: exit $rc, $(cat "$tmp/err.txt")"
    "$MFKIT_STUDY_HALF" --brdf nope "$half_ref" 2>"$tmp/err.txt"; rc=$?
    [ $rc -eq 2 ] && grep -q "unknown BRDF 'nope'" "$tmp/err.txt" || fail "study_half --brdf nope: exit $rc"
    ! ls "$tmp"/bad.csv* >/dev/null 2>&1 || fail "study_half left output behind after an error"
    half_figs="half_shading_error half_rounding_error"
fi
# captions: no temporary paths, source paths relative; gate verdicts from MFKIT_FIGURE_GATES
printf 'ltc_code_ggx_64.csv\tFAILED its gate (mfkit validate --quick)\n' >"$tmp/gates.tsv"
MFKIT_FIGURE_GATES=$tmp/gates.tsv "$py" - "$src" <<'EOF' || fail "plot.py: clean_paths / gate_of"
import os, sys, tempfile
sys.path.insert(0, os.path.join(sys.argv[1], "analysis"))
import plot
t = tempfile.gettempdir()
got = plot.clean_paths("command=x --out %s/mfkit_figures.AbC/d.csv %s/tests/data/reference/ltc_code_ggx_64.csv, seed=1"
                       % (t, plot.SOURCE_DIR))
want = "command=x --out d.csv tests/data/reference/ltc_code_ggx_64.csv, seed=1"
assert got == want, (got, want)
assert plot.gate_of("/a/ltc_code_ggx_64.csv") == "ltc_code_ggx_64.csv: FAILED its gate (mfkit validate --quick)"
assert plot.gate_of("x.json").startswith("x.json: gate not recorded")
d = plot.Data.__new__(plot.Data)
d.path, d.header = "/x/ltc_texels_ggx.csv", ["command=study_ltc_texels --stride 4 --out /x/ltc_texels.csv /r/a.csv /t/b.exr, mfkit=0.1.0"]
assert plot._texel_tables(d) == ["/r/a.csv", "/t/b.exr"], plot._texel_tables(d)
EOF
# study_random_walk (always built; MFKIT_STUDY_RANDOM_WALK is set by tests/CMakeLists.txt, else it is
# looked up beside study_smith) on one alpha, one view and one eta pair: provenance header, row count,
# the walk's exact invariants in the file (F = 1: albedo exactly 1; R + T = 1), the error paths.
rw_study=${MFKIT_STUDY_RANDOM_WALK:-$(dirname "$smith")/study_random_walk}
[ -x "$rw_study" ] || fail "study_random_walk not found at $rw_study"
rwc=$tmp/data/random_walk.csv
"$rw_study" --help | grep -q '^usage: study_random_walk' || fail "study_random_walk --help"
"$rw_study" --walks 2000 --alphas 0.5,1 --mus 0.5 --etas 1.5 --out "$rwc" >"$tmp/rw.txt" ||
    fail "study_random_walk: $(tail -n 3 "$tmp/rw.txt")"
head -n 1 "$rwc" | grep -Eq '^# command=study_random_walk .*, mfkit=[0-9.]+, seed=1, date=[0-9]{4}-[0-9]{2}-[0-9]{2}T' ||
    fail "random_walk.csv: bad provenance header: $(head -n 1 "$rwc")"
# per NDF (GGX and Beckmann): 2 alphas x 2 etas x (1 view + the average) dielectric rows, 2 alphas x 2 x 4
# channels conductor rows
[ "$(tail -n +3 "$rwc" | wc -l)" -eq 48 ] || fail "random_walk.csv: expected 48 rows, got $(tail -n +3 "$rwc" | wc -l)"
awk -F, 'NR == 2 { for (i = 1; i <= NF; ++i) col[$i] = i }
         NR > 2 && $col["case"] == "conductor" && $col["channel"] == "none" && $col["R_walk"] + 0 != 1 { print "F = 1 albedo " $col["R_walk"]; bad = 1 }
         NR > 2 && $col["case"] == "dielectric" && ($col["R_walk"] + $col["T_walk"] < 1 - 1e-9 || $col["R_walk"] + $col["T_walk"] > 1 + 1e-9) { print "R + T at row " NR; bad = 1 }
         NR > 2 && $col["case"] == "dielectric" && !($col["t_split"] >= 0 && $col["t_split"] <= 1) { print "t at row " NR; bad = 1 }
         END { exit bad }' "$rwc" || fail "random_walk.csv: an invariant of the walk does not hold"
"$rw_study" --walks 5 --out "$tmp/bad.csv" 2>"$tmp/err.txt"; rc=$?
[ $rc -eq 2 ] && grep -q -- '--walks' "$tmp/err.txt" || fail "study_random_walk --walks 5: exit $rc, $(cat "$tmp/err.txt")"
"$rw_study" --walks 100 --alphas 0.5 --mus 0.5 --etas 1.5 --out "$tmp/no_such_dir/x.csv" >/dev/null 2>"$tmp/err.txt"; rc=$?
[ $rc -eq 3 ] && grep -q 'no_such_dir' "$tmp/err.txt" || fail "study_random_walk, unwritable --out: exit $rc"
! ls "$tmp"/bad.csv* >/dev/null 2>&1 || fail "study_random_walk left output behind after an error"
# the committed light-size sweep (analysis/prefilter_scenes_lights.sh): its own figure, not prefilter_scenes'
# (the file has that figure's columns too)
lights_csv=$src/notebooks_data/prefilter_scenes_lights.csv.gz
[ -f "$lights_csv" ] || fail "$lights_csv is missing"
gzip -dc "$lights_csv" >"$tmp/data/prefilter_scenes_lights.csv" || fail "$lights_csv: not gzip"
MFKIT_FIGURE_GATES=$tmp/gates.tsv "$py" "$src/analysis/plot.py" "$tmp/data" "$tmp/fig" || fail "plot.py exited with $?"
[ ! -e "$tmp/fig/prefilter_scenes.png" ] || fail "prefilter_scenes_lights.csv was drawn as prefilter_scenes"
for name in prefilter_scenes_lights smith_walter_g1 smith_gaussian_lambda furnace_microfacet furnace_curves furnace_models \
    proxy_alpha_error proxy_alpha_curves ggx_rect_error leadr_grid_convergence $ltc_figs $sh_figs $half_figs random_walk random_walk_beckmann; do
    for ext in png pdf; do
        [ -s "$tmp/fig/$name.$ext" ] || fail "missing or empty $name.$ext"
    done
done
echo "test_plots: OK ($(ls "$tmp/fig" | wc -l) files)"
