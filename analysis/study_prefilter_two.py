#!/usr/bin/env python3
"""study_prefilter_two.py -- what a second lobe per entry would buy, cell by cell (issue 13).

Runs analysis/study_prefilter_cell on every tabulated view of the given footprints and sums its
records into prefilter-eval's cells (level, light half side, view elevation): the mean squared error
against the Monte Carlo truth (the balance-heuristic estimator of prefilter-eval, --samples points per
record) of
  stored   the stored lobe,
  two      two lobes: the footprint's normals split in two by 2-means, each half's mixture fitted as
           study_prefilter_cell's `fresh` lobe (separately, not jointly), weighted by the halves' sizes,
  naive, toksvig  the baselines,
  leadr    (with --eval-summary) LEADR's cell MSE from a prefilter-eval summary of the same table; its
           footprints are prefilter-eval's, not the ones studied here, so use it only where every
           footprint of a level is alike (the demo V-groove at levels 2-4).
A cell is won by a method whose MSE is below every baseline's.  Prints the cells lost by `stored` or
`two` and one line per level; --records FILE keeps every record.

Usage (from the source directory, after a build):
  analysis/study_prefilter_two.py --prefilter PF --level 2 --texels 0,0 [--texels X,Y ...]
      [--study build/analysis/study_prefilter_cell] [--eval-summary EV/prefilter_eval_summary.csv]
      [--lights 0.05,0.2,0.5] [--samples 4096] [--jobs 2] [--records FILE]
Exit 2 on a bad argument, 3 if a study run fails (its message is printed).
"""
import argparse
import collections
import concurrent.futures
import csv
import json
import os
import subprocess
import sys

BASELINES = ("naive", "toksvig")


def fail(code, msg):
    print(f"study_prefilter_two.py: {msg}", file=sys.stderr)
    sys.exit(code)


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--prefilter", required=True, help="a mfkit prefilter output directory (GGX table)")
    ap.add_argument("--level", required=True, type=int, action="append", help="MIP level (repeatable)")
    ap.add_argument("--texels", required=True, action="append", help="X,Y of a footprint at every level (repeatable)")
    ap.add_argument("--study", default="build/analysis/study_prefilter_cell", help="the study_prefilter_cell binary")
    ap.add_argument("--eval-summary", help="prefilter_eval_summary.csv of the same table (adds LEADR's cell MSE)")
    ap.add_argument("--lights", default="0.05,0.2,0.5", help="light half sides (prefilter-eval's default)")
    ap.add_argument("--samples", type=int, default=4096, help="Monte Carlo points per record (even)")
    ap.add_argument("--jobs", type=int, default=2, help="study runs at once")
    ap.add_argument("--records", help="write every record to this CSV")
    a = ap.parse_args()
    if not os.path.isfile(os.path.join(a.prefilter, "prefilter.json")):
        fail(2, f"--prefilter {a.prefilter}: no prefilter.json there")
    if not os.access(a.study, os.X_OK):
        fail(2, f"--study {a.study}: not an executable (build the analysis programs first)")
    if a.samples < 16 or a.samples % 2:
        fail(2, f"--samples {a.samples}: must be even and >= 16")
    if a.jobs < 1:
        fail(2, f"--jobs {a.jobs}: must be >= 1")
    for t in a.texels:
        p = t.split(",")
        if len(p) != 2 or not all(s.strip().isdigit() for s in p):
            fail(2, f"--texels {t}: expected X,Y (non-negative integers)")
    if a.eval_summary and not os.path.isfile(a.eval_summary):
        fail(2, f"--eval-summary {a.eval_summary}: no such file")
    return a


def view_counts(pf):
    with open(os.path.join(pf, "prefilter.json")) as f:
        m = json.load(f)
    try:
        return len(m["axes"]["theta"]), len(m["axes"]["phi"])
    except (KeyError, TypeError):
        fail(2, f"{pf}/prefilter.json: no axes.theta and axes.phi")


def main():
    a = parse_args()
    nt, nphi = view_counts(a.prefilter)
    jobs = [(lv, t, i, j) for lv in a.level for t in a.texels for i in range(nt) for j in range(nphi)]

    def run(job):
        lv, t, i, j = job
        r = subprocess.run([a.study, "--prefilter", a.prefilter, "--level", str(lv), "--texel", t, "--view", f"{i},{j}",
                            "--lights", a.lights, "--samples", str(a.samples)], capture_output=True, text=True)
        if r.returncode:
            return job, None, r.stderr.strip()
        return job, [ln for ln in r.stdout.splitlines() if ln[:1].isdigit()], ""

    cells = collections.defaultdict(lambda: collections.defaultdict(list))
    rec = open(a.records, "w") if a.records else None
    if rec:
        rec.write("level,texel,i_theta,i_phi,h,truth,stored,lookup,stored_mag_albedo,fresh,two,naive,toksvig\n")
    done = 0
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        for job, lines, err in ex.map(run, jobs):
            if lines is None:
                fail(3, f"level {job[0]}, texel {job[1]}, view {job[2]},{job[3]}: {err}")
            lv, t, i, j = job
            for ln in lines:
                v = ln.split(",")
                h, truth = float(v[0]), float(v[1])
                row = dict(zip(("stored", "lookup", "stored_mag_albedo", "fresh", "two", "naive", "toksvig"),
                               map(float, v[2:9])))
                for k in ("stored", "two") + BASELINES:
                    cells[(lv, h, i)][k].append((row[k] - truth) ** 2)
                if rec:
                    rec.write(f'{lv},"{t}",{i},{j},{ln}\n')
            done += 1
            if done % 256 == 0 or done == len(jobs):
                print(f"study_prefilter_two.py: {done} of {len(jobs)} records", file=sys.stderr)
    if rec:
        rec.close()
    leadr = {}
    if a.eval_summary:
        with open(a.eval_summary) as f:
            for x in csv.DictReader(f):
                leadr[(int(x["level"]), float(x["light_half_side"]), int(x["i_theta"]))] = float(x["mse_leadr"])
    per = collections.defaultdict(collections.Counter)
    sums = collections.defaultdict(lambda: collections.defaultdict(float))
    for key in sorted(cells):
        m = {k: sum(v) / len(v) for k, v in cells[key].items()}
        base = [m[k] for k in BASELINES]
        if key in leadr:
            m["leadr"] = leadr[key]
            base.append(leadr[key])
        best = min(base)
        lv = key[0]
        per[lv]["cells"] += 1
        for k in ("stored", "two"):
            per[lv][k] += m[k] < best
        for k, v in m.items():
            sums[lv][k] += v
        lost = [k for k in ("stored", "two") if not m[k] < best]
        if lost:
            print(f"level {lv}, h {key[1]:g}, theta row {key[2]}: " + ", ".join(f"{k} {v:.3g}" for k, v in m.items())
                  + "; lost by " + " and ".join(lost))
    for lv in sorted(per):
        n = per[lv]["cells"]
        print(f"level {lv}: cells won: stored {per[lv]['stored']} of {n}, two {per[lv]['two']} of {n}; mean MSE: "
              + ", ".join(f"{k} {v / n:.3g}" for k, v in sums[lv].items()))


if __name__ == "__main__":
    main()
