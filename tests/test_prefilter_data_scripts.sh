#!/usr/bin/env bash
# test_prefilter_data_scripts.sh BUILD SRC -- the scripts behind the committed prefilter CSVs
# (analysis/prefilter_figures_data.sh, prefilter_eval_data.sh, prefilter_scenes_lights.sh and their
# prefilter_data_common.sh; docs/prefilter.md, "The committed figures at the default views"), without their
# minute-long runs (about 2 s of CPU: one 2 x 2-view prefilter of the demo map):
# - pf_check accepts a run that is what it is asked for (the demo map, GGX, 2 x 2 views, the default fit
#   options) and refuses, in one line naming the directory and the field, the wrong view count (what the
#   scripts ask: 8 x 16), another map, another seed and a missing manifest;
# - the eval and light-size scripts given that 2 x 2 run with --prefilter refuse it (exit 2, one line, no
#   output file, no temporary file left); the eval script refuses a run of the recorded views without the
#   two-lobe table (lobe_a/, lobe_b/) the same way;
# - pf_stamp: SOURCE_DATE_EPOCH=0 gives 1970-01-01T00:00:00Z, 1700000000 gives 2023-11-14T22:13:20Z, a
#   non-number is refused in one line, and the eval script then writes nothing;
# - usage errors of the three scripts exit 2.
build="$1"; src="$2"
mfkit="$build/bin/mfkit"
source "$(dirname "$0")/cli_test_lib.sh"
. "$src/analysis/prefilter_data_common.sh"
cd "$src" || exit 1
map=tests/data/normalmaps/vgroove_16.png
"$mfkit" prefilter "$map" --base ggx --views 2x2 --threads 2 --out "$tmp/pf" >/dev/null 2>&1
ok '[ -f "$tmp/pf/prefilter.json" ]' "mfkit prefilter $map --views 2x2 ran"

# one refusal: COMMAND... must exit 2 with one stderr line matching PATTERN
refuse() {
  local desc="$1" pattern="$2"; shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"; local rc=$?
  checks=$((checks+1))
  if [ $rc -ne 2 ] || [ "$(wc -l <"$tmp/err")" -ne 1 ] || ! grep -q -- "$pattern" "$tmp/err"; then
    echo "FAIL: $desc (rc=$rc, stderr=$(cat "$tmp/err"))" >&2; fails=$((fails+1))
  fi
}

pf_check "$tmp/pf" "$map" 2 2 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 0 ] && [ ! -s "$tmp/err" ]' "pf_check accepts the 2 x 2 run as 2 x 2 (rc=$rc: $(cat "$tmp/err"))"
refuse "pf_check refuses the 2 x 2 run as 8 x 16" "$tmp/pf: not the recorded prefilter run: elevations is 2, expected 8" \
  pf_check "$tmp/pf" "$map" 8 16
refuse "pf_check refuses 2 azimuths as 4" "azimuths is 2, expected 4" pf_check "$tmp/pf" "$map" 2 4
refuse "pf_check refuses another map" "map is 'tests/data/normalmaps/vgroove_16.png', expected 'other.png'" \
  pf_check "$tmp/pf" other.png 2 2
mkdir -p "$tmp/seed"; sed 's/"seed": 1}/"seed": 2}/' "$tmp/pf/prefilter.json" >"$tmp/seed/prefilter.json"
refuse "pf_check refuses seed 2" "seed is 2, expected 1" pf_check "$tmp/seed" "$map" 2 2
refuse "pf_check refuses a directory without a manifest" "$tmp/none/prefilter.json: unreadable" \
  pf_check "$tmp/none" "$map" 2 2

refuse "prefilter_eval_data.sh --prefilter (2 x 2 views) refused" "elevations is 2, expected 8" \
  analysis/prefilter_eval_data.sh --prefilter "$tmp/pf" "$mfkit" "$tmp/eval.csv.gz"
ok '[ ! -e "$tmp/eval.csv.gz" ] && [ ! -e "$tmp/eval.csv.gz.tmp" ]' "refused eval: no output, no temporary file"
# a reused run without the two-lobe table (the eval's last columns need it): a manifest that passes pf_check
# (its axes rewritten to the recorded 8 x 16 views) but no lobe_a/, lobe_b/: refused in one line, no output
mkdir -p "$tmp/pf816"
/usr/bin/python3 - "$tmp/pf/prefilter.json" "$tmp/pf816/prefilter.json" <<'PY'
import json, math, sys
m = json.load(open(sys.argv[1]))
m["axes"] = {"theta": [i / 7 * 0.999 * math.pi / 2 for i in range(8)], "phi": [2 * math.pi * j / 16 for j in range(16)]}
json.dump(m, open(sys.argv[2], "w"))
PY
refuse "prefilter_eval_data.sh --prefilter without the two-lobe table refused" "no two-lobe table (lobe_a/prefilter.json)" \
  analysis/prefilter_eval_data.sh --prefilter "$tmp/pf816" "$mfkit" "$tmp/eval3.csv.gz"
ok '[ ! -e "$tmp/eval3.csv.gz" ] && [ ! -e "$tmp/eval3.csv.gz.tmp" ]' "refused eval without the halves: no output, no temporary file"
refuse "prefilter_scenes_lights.sh --prefilter (2 x 2 views) refused" "elevations is 2, expected 8" \
  analysis/prefilter_scenes_lights.sh --prefilter "$tmp/pf" "$build" "$tmp/lights.csv.gz"
ok '[ ! -e "$tmp/lights.csv.gz" ] && [ ! -e "$tmp/lights.csv.gz.tmp" ]' "refused light sizes: no output, no temporary file"

s0=$(SOURCE_DATE_EPOCH=0 pf_stamp); s1=$(SOURCE_DATE_EPOCH=1700000000 pf_stamp)
ok '[ "$s0" = 1970-01-01T00:00:00Z ] && [ "$s1" = 2023-11-14T22:13:20Z ]' "pf_stamp from SOURCE_DATE_EPOCH: $s0, $s1"
now=$(SOURCE_DATE_EPOCH= pf_stamp)
ok '[[ "$now" =~ ^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}Z$ ]]' "pf_stamp without SOURCE_DATE_EPOCH: $now"
refuse "pf_stamp refuses SOURCE_DATE_EPOCH=1e9" "SOURCE_DATE_EPOCH=1e9: not a whole number of seconds" \
  env SOURCE_DATE_EPOCH=1e9 bash -c ". '$src/analysis/prefilter_data_common.sh' && pf_stamp"
SOURCE_DATE_EPOCH=yesterday analysis/prefilter_eval_data.sh "$mfkit" "$tmp/eval2.csv.gz" >/dev/null 2>"$tmp/err"; rc=$?
ok '[ $rc -ne 0 ] && [ ! -e "$tmp/eval2.csv.gz" ] && grep -q "not a whole number" "$tmp/err"' \
  "prefilter_eval_data.sh with SOURCE_DATE_EPOCH=yesterday stops before any work (rc=$rc)"

refuse "prefilter_eval_data.sh without OUT" "usage: analysis/prefilter_eval_data.sh" analysis/prefilter_eval_data.sh "$mfkit"
refuse "prefilter_scenes_lights.sh --prefilter without a directory" "usage: analysis/prefilter_scenes_lights.sh" \
  analysis/prefilter_scenes_lights.sh --prefilter
refuse "prefilter_figures_data.sh with a stray third argument" "usage: analysis/prefilter_figures_data.sh" \
  analysis/prefilter_figures_data.sh "$build" "$tmp/data" --zip
finish test_prefilter_data_scripts
