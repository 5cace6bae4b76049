#!/usr/bin/env bash
# test_prefilter_split_study.sh STUDY SRC -- analysis/study_prefilter_split on record files written here
# (no fit: about 2 s).  The demo groove (vgroove_16.png): every level-1 footprint holds one
# normal, every footprint of levels 2-4 both facets, whose mean normals are 60 deg apart (the map's 8-bit
# facets: 1.043 rad).  Two records per footprint, mfkit = truth + 0.01 in the "two lobes" file at every
# level; in the "one lobe" file truth + 0.01 at level 1 (a tie: not "better") and truth + 0.02 above.
# So, at --alpha 0.1 (angle 10.4 alpha), the rows must read
#   | >= 10 | 21 | 2, 3, 4 | 21 | 0.0001 | 0.0004 | 0.25 |   and   | one normal | 64 | 1 | 0 | 0.0001 | 0.0001 | 1.00 |
# and at --alpha 0.2 (5.2 alpha) the split footprints move to the [4, 6) row: the angle is in units of
# alpha.  Refusals (exit 2, one stderr line naming the file): a missing column, records of different
# footprints in the two files, a texel outside the map, a missing file; usage errors exit 2.
study="$1"; src="$2"
mfkit=/bin/false
source "$(dirname "$0")/cli_test_lib.sh"
map="$src/tests/data/normalmaps/vgroove_16.png"

/usr/bin/python3 - "$tmp" <<'PY'
import sys
d = sys.argv[1]
head = "level,row,col,i_theta,theta,i_phi,phi,light_half_side,truth,truth_se,mfkit,naive\n"
for name, above in (("two.csv", 0.01), ("one.csv", 0.02)):
    with open("%s/%s" % (d, name), "w") as f:
        f.write(head)
        for level in range(1, 5):
            w = 16 >> level
            for r in range(w):
                for c in range(w):
                    for h in (0.05, 0.5):
                        e = 0.01 if level == 1 else above
                        f.write("%d,%d,%d,0,0,0,0,%g,0.5,0.001,%.17g,0.3\n" % (level, r, c, h, 0.5 + e))
# a file of other footprints: level 2's texel (0, 0) missing
with open("%s/fewer.csv" % d, "w") as f:
    for line in open("%s/two.csv" % d):
        if not line.startswith("2,0,0,"):
            f.write(line)
open("%s/nocol.csv" % d, "w").write(head.replace("mfkit", "other") + "1,0,0,0,0,0,0,0.05,0.5,0.001,0.51,0.3\n")
open("%s/outside.csv" % d, "w").write(head + "2,4,0,0,0,0,0,0.05,0.5,0.001,0.51,0.3\n")
PY

"$study" --map "$map" --alpha 0.1 --two "$tmp/two.csv" --one "$tmp/one.csv" >"$tmp/out" 2>"$tmp/err"; rc=$?
ok '[ $rc -eq 0 ] && [ ! -s "$tmp/err" ]' "the study runs (rc=$rc: $(cat "$tmp/err"))"
ok 'grep -qxF "| >= 10 | 21 | 2, 3, 4 | 21 | 0.0001 | 0.0004 | 0.25 |" "$tmp/out"' \
  "alpha 0.1: levels 2-4 in the >= 10 row, two lobes better in all 21 (got: $(cat "$tmp/out"))"
ok 'grep -qxF "| one normal | 64 | 1 | 0 | 0.0001 | 0.0001 | 1.00 |" "$tmp/out"' \
  "alpha 0.1: level 1 in the one-normal row, ties not counted as better"
ok '[ "$(grep -c "^|" "$tmp/out")" -eq 4 ]' "alpha 0.1: a header, its rule and two rows"
"$study" --map "$map" --alpha 0.2 --two "$tmp/two.csv" --one "$tmp/one.csv" >"$tmp/out" 2>&1
ok 'grep -qxF "| [4, 6) | 21 | 2, 3, 4 | 21 | 0.0001 | 0.0004 | 0.25 |" "$tmp/out"' \
  "alpha 0.2: the split footprints in the [4, 6) row (got: $(cat "$tmp/out"))"

refuse() {
  local desc="$1" pattern="$2"; shift 2
  "$study" "$@" >"$tmp/out" 2>"$tmp/err"; local rc=$?
  checks=$((checks+1))
  if [ $rc -ne 2 ] || [ -s "$tmp/out" ] || [ "$(wc -l <"$tmp/err")" -ne 1 ] || ! grep -q -- "$pattern" "$tmp/err"; then
    echo "FAIL: $desc (rc=$rc, stderr=$(cat "$tmp/err"))" >&2; fails=$((fails+1))
  fi
}
refuse "a file without the mfkit column" "nocol.csv: no column \"mfkit\"" \
  --map "$map" --alpha 0.1 --two "$tmp/nocol.csv" --one "$tmp/one.csv"
refuse "records of other footprints" "level 2 texel (0, 0): 0 records in .*fewer.csv, 2 in" \
  --map "$map" --alpha 0.1 --two "$tmp/fewer.csv" --one "$tmp/one.csv"
refuse "a texel outside the map" "outside.csv, line 2: not a record of this map's footprints" \
  --map "$map" --alpha 0.1 --two "$tmp/outside.csv" --one "$tmp/one.csv"
refuse "a missing file" "missing.csv: cannot open" --map "$map" --alpha 0.1 --two "$tmp/missing.csv" --one "$tmp/one.csv"
refuse "no --one" "usage: study_prefilter_split" --map "$map" --alpha 0.1 --two "$tmp/two.csv"
refuse "alpha 0" "usage: study_prefilter_split" --map "$map" --alpha 0 --two "$tmp/two.csv" --one "$tmp/one.csv"
"$study" --help >"$tmp/out" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && grep -q "usage: study_prefilter_split" "$tmp/out"' "--help exits 0 with the usage"
finish test_prefilter_split_study
