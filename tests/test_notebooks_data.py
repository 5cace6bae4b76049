#!/usr/bin/python3
"""test_notebooks_data.py SRC BUILD -- the committed data of notebooks_data/ and its example notebook.

1. Every CSV (FILE.csv.gz) parses: a provenance line "# command=..., mfkit=..., seed=..., date=...", a header of
   unique names, rows of the header's width, every field a number except the text columns.
2. The cheap ones match a regeneration (study_smith, study_proxy: a few seconds): the same command
   (from the provenance line, --out to a scratch file) gives the same bytes after the first line
   (the date differs, so the provenance line is left out).
3. example.ipynb runs headlessly: executed by Debian's jupyter-nbconvert when it is installed (README's
   commands install it), else converted to a script (its code cells in order) and run by
   /usr/bin/python3 -- the output says which.  Both fail on any exception in a cell.
"""
import gzip
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

SRC, BUILD = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
DATA = os.path.join(SRC, "notebooks_data")
failures = []


def check(cond, what):
    print("%s  %s" % ("ok  " if cond else "FAIL", what))
    if not cond:
        failures.append(what)


# study_leadr_grid writes its provenance over three '#' lines ("# command: ...", "# mfkit X; seed S; ...;
# date D"): accepted as long as the four items are there.
LEADR_PROVENANCE = re.compile(r"^# command: .+\n# mfkit \S+; seed \S+;.*date \S+")
PROVENANCE = re.compile(r"^# command=(?P<cmd>.+), mfkit=(?P<ver>[^,]+), seed=(?P<seed>[^,]+), date=(?P<date>\S+)$")
csvs = sorted(f for f in os.listdir(DATA) if f.endswith(".csv.gz"))
stray = sorted(f for f in os.listdir(DATA) if f.endswith(".csv") or ".tmp" in f)
check(not stray, "no uncompressed or temporary files: %s" % stray)
check(len(csvs) >= 5, "notebooks_data holds %d CSV files" % len(csvs))
total = 0
for name in csvs:
    path = os.path.join(DATA, name)
    total += os.path.getsize(path)
    with gzip.open(path, "rt") as f:
        lines = f.read().splitlines()
    nhead = 1
    while nhead < len(lines) and lines[nhead].startswith("#"):
        nhead += 1
    m = (PROVENANCE.match(lines[0]) or LEADR_PROVENANCE.match("\n".join(lines[:nhead]))) if lines else None
    header = lines[nhead].split(",") if len(lines) > nhead else []
    bad = []

    def number(v):
        try:
            float(v)
            return True
        except ValueError:
            return False
    # a column is text (brdf, source, ...) if its first value is not a number; every other column is
    # numeric in every row ("nan" included)
    first = lines[nhead + 1].split(",") if len(lines) > nhead + 1 else []
    numeric = {h for h, v in zip(header, first) if number(v)}
    for i, line in enumerate(lines[nhead + 1:], start=nhead + 2):
        fields = line.split(",")
        if len(fields) != len(header):
            bad.append("line %d: %d fields, header %d" % (i, len(fields), len(header)))
            break
        for h, v in zip(header, fields):
            if h in numeric and not number(v):
                bad.append("line %d, column %s: '%s' is not a number" % (i, h, v))
                break
        if bad:
            break
    check(m is not None and len(header) == len(set(header)) and len(lines) > 2 and not bad,
          "%s: provenance %s, %d columns (%d numeric), %d rows%s" % (
              name, "ok" if m else "MISSING: %r" % lines[:1], len(header), len(numeric), len(lines) - nhead - 1,
              "; " + bad[0] if bad else ""))
check(total <= 4 * 1024 * 1024, "notebooks_data CSVs total %.2f MB compressed (budget 4 MB)" % (total / 1048576.0))

# ---- regeneration of the cheap studies -------------------------------------------------------------
with tempfile.TemporaryDirectory() as tmp:
    for name, prog in (("smith_lambda.csv", "study_smith"), ("ggx_proxy.csv", "study_proxy")):
        path = os.path.join(DATA, name + ".gz")
        with gzip.open(path, "rt") as f:
            first = f.readline()
            body = f.read()
        m = PROVENANCE.match(first.rstrip("\n"))
        args = m.group("cmd").split() if m else []
        if not args or args[0] != prog or "--out" not in args:
            check(False, "%s: provenance command %r is not '%s ... --out FILE'" % (name, args, prog))
            continue
        args[args.index("--out") + 1] = os.path.join(tmp, name)
        p = subprocess.run([os.path.join(BUILD, "analysis", prog)] + args[1:], capture_output=True, text=True)
        again = None
        if p.returncode == 0:
            with open(os.path.join(tmp, name)) as f:
                f.readline()
                again = f.read()
        check(p.returncode == 0 and again == body, "%s: `%s` regenerates the same %d bytes after the provenance line"
              % (name, " ".join(args), len(body)))

    # ---- the example notebook ------------------------------------------------------------------------
    nb = os.path.join(DATA, "example.ipynb")
    env = dict(os.environ, MFKIT_PYTHONPATH=os.path.join(BUILD, "python"), MFKIT_NOTEBOOK_DIR=DATA)
    env.pop("MPLBACKEND", None)  # the kernel's inline backend makes the figures outputs
    nbconvert = shutil.which("jupyter-nbconvert")
    if nbconvert:
        p = subprocess.run([nbconvert, "--to", "notebook", "--execute", "--ExecutePreprocessor.timeout=300",
                            "--output-dir", tmp, "--output", "executed", nb], capture_output=True, text=True, env=env,
                           cwd=DATA)
        outputs = []
        if p.returncode == 0:
            with open(os.path.join(tmp, "executed.ipynb")) as f:
                executed = json.load(f)
            for c in executed["cells"]:
                outputs += [o for o in c.get("outputs", [])]
        errors = [o for o in outputs if o.get("output_type") == "error"]
        images = [o for o in outputs if "image/png" in o.get("data", {})]
        check(p.returncode == 0 and not errors and len(images) >= 3,
              "example.ipynb executed by jupyter-nbconvert: %d outputs, %d images, no error%s"
              % (len(outputs), len(images), "" if p.returncode == 0 else ": " + p.stderr.strip().splitlines()[-1]))
    else:
        with open(nb) as f:
            cells = json.load(f)["cells"]
        script = "\n\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        path = os.path.join(tmp, "example.py")
        with open(path, "w") as f:
            f.write(script + "\n")
        p = subprocess.run(["/usr/bin/python3", path], capture_output=True, text=True, env=dict(env, MPLBACKEND="Agg"),
                           cwd=DATA)
        check(p.returncode == 0, "example.ipynb converted to a script (jupyter-nbconvert not installed) and run%s"
              % ("" if p.returncode == 0 else ": " + (p.stderr.strip().splitlines() or [""])[-1]))
        print(p.stdout)

if failures:
    print("%d FAILED" % len(failures))
    sys.exit(1)
print("all passed")
