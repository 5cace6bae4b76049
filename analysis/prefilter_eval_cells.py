#!/usr/bin/python3
"""prefilter_eval_cells.py [FILE] -- the issue-13 quality target read off a prefilter-eval summary
(docs/prefilter.md, "Evaluation"; default FILE notebooks_data/prefilter_eval.csv.gz, plain or gzip CSV
as analysis/prefilter_eval_data.sh writes it).  A cell is one (level, light half side, view elevation)
row of the summary; mfkit wins it when its MSE is below naive's, Toksvig's and LEADR's (a tie is lost).
Two readings of "mfkit beats every baseline in mean squared error at every level >= 1":
  per cell   cells won per level, and the cells lost (light, elevation, the baseline that beat it);
  per level  the level's mean MSE (over its lights and elevations) of mfkit and of each baseline.
Both against the Monte Carlo truth (mse_<method>) and against the thesis' per-texel LTC truth
(mse_ltc_<method>); then, when the summary has them, against naive and Toksvig as a renderer shades them
(mse_naive_ltc, mse_toksvig_ltc: the isotropic LTC at the mean normal).  Markdown tables on stdout;
standard library only."""
import csv
import gzip
import sys

METHODS = ("mfkit", "naive", "toksvig", "leadr")
BASELINES = METHODS[1:]


def fmt(v):
    """the docs' form: 2 significant digits, 0 as 0"""
    return "0" if v == 0 else ("%.1e" % v).replace("e-0", "e-").replace("e+00", "")


def main(argv):
    if len(argv) > 2 or (len(argv) == 2 and argv[1] in ("-h", "--help")):
        sys.stderr.write("usage: analysis/prefilter_eval_cells.py [SUMMARY.csv[.gz]]\n")
        return 2
    path = argv[1] if len(argv) == 2 else "notebooks_data/prefilter_eval.csv.gz"
    try:
        opener = gzip.open if path.endswith(".gz") else open
        with opener(path, "rt") as f:
            first = f.readline()
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.stderr.write("prefilter_eval_cells.py: %s: %s\n" % (path, e))
        return 2
    need = {"level", "light_half_side", "theta"} | {p + m for p in ("mse_", "mse_ltc_") for m in METHODS}
    if not first.startswith("#") or not rows or not need <= set(rows[0]):
        sys.stderr.write("prefilter_eval_cells.py: %s: not a prefilter-eval summary with its provenance line\n" % path)
        return 2
    print(first.strip())
    levels = sorted({int(r["level"]) for r in rows})
    for prefix, truth in (("mse_", "Monte Carlo truth"), ("mse_ltc_", "per-texel LTC truth")):
        print("\nAgainst the %s (%s<method>):\n" % (truth, prefix))
        print("| level | mfkit | naive | Toksvig | LEADR | level mean: mfkit best | cells won | cells lost (h, elevation deg: to) |")
        print("|---|---|---|---|---|---|---|---|")
        for k in levels:
            rs = [r for r in rows if int(r["level"]) == k]
            mean = {m: sum(float(r[prefix + m]) for r in rs) / len(rs) for m in METHODS}
            lost = []
            for r in rs:
                best = min(BASELINES, key=lambda b: float(r[prefix + b]))
                if not float(r[prefix + "mfkit"]) < float(r[prefix + best]):
                    lost.append("(%g, %.1f: %s)" % (float(r["light_half_side"]), float(r["theta"]) * 180 / 3.141592653589793,
                                                     best))
            if len(lost) == len(rs):
                # every cell: say to whom, and whether that baseline is exact (MSE 0) on every cell
                exact = all(min(float(r[prefix + b]) for b in BASELINES) == 0 for r in rs)
                lost_text = "all%s" % (" (a baseline exact: MSE 0)" if exact else "")
            else:
                lost_text = ", ".join(lost) if lost else "none"
            print("| %d | %s | %s | %s | %s | %s | %d / %d | %s |" % (
                k, *(fmt(mean[m]) for m in METHODS),
                "yes" if all(mean["mfkit"] < mean[b] for b in BASELINES) else "no",
                len(rs) - len(lost), len(rs), lost_text))
    # the baselines as a renderer shades them (prefilter-eval's naive_ltc and toksvig_ltc: the isotropic
    # LTC at the mean normal), when the summary has them
    if {"mse_naive_ltc", "mse_toksvig_ltc"} <= set(rows[0]):
        rend = ("naive_ltc", "toksvig_ltc")
        print("\nAgainst the Monte Carlo truth, the baselines shaded as a renderer does (isotropic LTC at the mean "
              "normal; mse_naive_ltc, mse_toksvig_ltc):\n")
        # with the two-lobe columns of prefilter_eval_data.sh, the two-lobe table's reading too
        ours = ("mfkit", "mfkit_two_lobes") if "mse_mfkit_two_lobes" in rows[0] else ("mfkit",)
        print("| level | %s | naive, LTC | Toksvig, LTC | %s |" % (" | ".join(ours), " | ".join(
            "%s: level mean best, cells won" % o for o in ours)))
        print("|---" * (3 + 2 * len(ours)) + "|")
        for k in levels:
            rs = [r for r in rows if int(r["level"]) == k]
            mean = {m: sum(float(r["mse_" + m]) for r in rs) / len(rs) for m in ours + rend}
            verdict = []
            for o in ours:
                won = sum(all(float(r["mse_" + o]) < float(r["mse_" + b]) for b in rend) for r in rs)
                verdict.append("%s, %d / %d" % ("yes" if all(mean[o] < mean[b] for b in rend) else "no", won, len(rs)))
            print("| %d | %s | %s |" % (k, " | ".join(fmt(mean[m]) for m in ours + rend), " | ".join(verdict)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
