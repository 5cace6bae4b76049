#!/usr/bin/env bash
# test_prefilter_eval_cells.sh SRC -- analysis/prefilter_eval_cells.py on summaries written here (under a
# second, standard library only).  Two levels of two cells (light x elevation) each, every method's MSE
# chosen so that the renderer table (mfkit against naive_ltc and toksvig_ltc, and the two-lobe column
# when present) has known rows:
#   level 1: mfkit 1e-4 and 1e-3 (mean 5.5e-4), two lobes 1e-5 and 1.19e-3 (6.0e-4), naive_ltc 5e-5 and
#            1e-2 (5.0e-3), toksvig_ltc 6e-4 and 1e-2 (5.3e-3): one lobe loses the first cell to naive_ltc
#            (1 of 2) and wins the level mean, two lobes win both;
#   level 2: mfkit 1e-2 twice, two lobes 1e-4, both baselines 1e-3: one lobe loses everything.
# Without the _ltc columns the renderer table is absent; without the two-lobe column it has one lobe only.
# A file that is not a summary is refused (exit 2, one line).
src="$1"
mfkit=/bin/false
source "$(dirname "$0")/cli_test_lib.sh"
py=/usr/bin/python3
$py - "$tmp" <<'PY'
import sys
d = sys.argv[1]
meth = ("mfkit", "naive", "toksvig", "leadr")
cells = [  # level, h, mfkit, naive, toksvig, leadr, naive_ltc, toksvig_ltc, two lobes
    (1, 0.05, 1e-4, 2e-4, 3e-4, 4e-4, 5e-5, 6e-4, 1e-5),
    (1, 0.5, 1e-3, 1e-2, 1e-2, 1e-2, 1e-2, 1e-2, 1.19e-3),
    (2, 0.05, 1e-2, 2e-2, 2e-2, 2e-2, 1e-3, 1e-3, 1e-4),
    (2, 0.5, 1e-2, 2e-2, 2e-2, 2e-2, 1e-3, 1e-3, 1e-4)]
def write(name, ltc, two):
    head = ["level", "light_half_side", "i_theta", "theta"] + ["mse_" + m for m in meth] + ["mse_ltc_" + m for m in meth]
    head += ["mse_naive_ltc", "mse_toksvig_ltc"] if ltc else []
    head += ["mse_mfkit_two_lobes"] if two else []
    with open("%s/%s" % (d, name), "w") as f:
        f.write("# command=test\n" + ",".join(head) + "\n")
        for c in cells:
            row = [c[0], c[1], 0, 0.0] + list(c[2:6]) * 2 + (list(c[6:8]) if ltc else []) + ([c[8]] if two else [])
            f.write(",".join(repr(x) for x in row) + "\n")
write("full.csv", 1, 1)
write("one.csv", 1, 0)
write("old.csv", 0, 0)
open("%s/bad.csv" % d, "w").write("a,b\n1,2\n")
PY
cells="$src/analysis/prefilter_eval_cells.py"
$py "$cells" "$tmp/full.csv" >"$tmp/full.out" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "full summary: exit 0 (rc=$rc: $(tail -2 "$tmp/full.out"))"
ok 'grep -qxF "| 1 | 5.5e-4 | 6.0e-4 | 5.0e-3 | 5.3e-3 | yes, 1 / 2 | yes, 2 / 2 |" "$tmp/full.out"' \
  "level 1 of the renderer table, one lobe and two (got: $(grep "^| 1 |" "$tmp/full.out" | tail -1))"
ok 'grep -qxF "| 2 | 1.0e-2 | 1.0e-4 | 1.0e-3 | 1.0e-3 | no, 0 / 2 | yes, 2 / 2 |" "$tmp/full.out"' \
  "level 2 of the renderer table (got: $(grep "^| 2 |" "$tmp/full.out" | tail -1))"
$py "$cells" "$tmp/one.csv" >"$tmp/one.out" 2>&1
ok 'grep -qxF "| 1 | 5.5e-4 | 5.0e-3 | 5.3e-3 | yes, 1 / 2 |" "$tmp/one.out"' \
  "without the two-lobe column: one lobe only (got: $(grep "^| 1 |" "$tmp/one.out" | tail -1))"
$py "$cells" "$tmp/old.csv" >"$tmp/old.out" 2>&1; rc=$?
ok '[ $rc -eq 0 ] && ! grep -q "shaded as a renderer" "$tmp/old.out" && [ "$(grep -c "^| 1 |" "$tmp/old.out")" -eq 2 ]' \
  "without the _ltc columns: the two tables of before, no renderer table (rc=$rc)"
$py "$cells" "$tmp/bad.csv" >"$tmp/bad.out" 2>"$tmp/bad.err"; rc=$?
ok '[ $rc -eq 2 ] && [ "$(wc -l <"$tmp/bad.err")" -eq 1 ] && grep -q "bad.csv: not a prefilter-eval summary" "$tmp/bad.err"' \
  "a file that is not a summary is refused (rc=$rc: $(cat "$tmp/bad.err"))"
finish test_prefilter_eval_cells
