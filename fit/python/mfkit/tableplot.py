#!/usr/bin/python3
"""tableplot.py -- the figures of `mfkit table plot`, `mfkit table lobe` and `mfkit compare`.

The mfkit command line computes every number with the C library and writes it as CSV; this module
only draws.  It is installed with mfkit's Python package and runs as a script (it does not import
the package, so it needs no compiled library):

  tableplot.py --cmd CMD check                               numpy and matplotlib importable?
  tableplot.py --cmd CMD fields CSV OUTDIR STEM              OUTDIR/STEM_<field>.png per field
  tableplot.py --cmd CMD lobe CSV OUTDIR                     OUTDIR/lobe.png
  tableplot.py --cmd CMD compare DIFF_CSV SHADING_CSV|- OUTDIR   compare_diff.png (+ compare_shading.png)

CSV files start with "# key: value" lines (table, kind, gate, verdict, ...), then a header row.
Errors: one line "mfkit CMD: ..." on stderr; exit 2 when numpy or matplotlib is missing, 3 for a
file that cannot be read or written.  Run with Debian's /usr/bin/python3 (python3-numpy,
python3-matplotlib).
"""
import csv
import math
import os
import sys

CMD = "table"


def die(msg, code=3):
    sys.stderr.write("mfkit %s: %s\n" % (CMD, msg))
    sys.exit(code)


try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    from matplotlib import colors
except ImportError as exc:  # reported by the check subcommand (and any other)
    np = None
    IMPORT_ERROR = "%s (with %s)" % (getattr(exc, "name", None) or exc, sys.executable)
else:
    IMPORT_ERROR = None


# ---- reading ----------------------------------------------------------------------------------
def read_csv(path):
    """(meta dict from the '# key: value' lines, column names, dict of columns: float arrays or
    lists of strings)."""
    meta, rows = {}, []
    try:
        with open(path, newline="") as f:
            lines = f.read().splitlines()
    except OSError as exc:
        die("%s: %s" % (path, exc.strerror or exc))
    body = []
    for ln in lines:
        if ln.startswith("#") and not body:
            key, sep, val = ln[1:].strip().partition(":")
            if sep:
                meta[key.strip()] = val.strip()
        elif ln.strip():
            body.append(ln)
    reader = csv.reader(body)
    names = next(reader, None)
    if not names:
        die("%s: no header row" % path)
    for r in reader:
        rows.append(r)
    cols = {}
    for j, n in enumerate(names):
        vals = [r[j] if j < len(r) else "nan" for r in rows]
        try:
            cols[n] = np.array([float(v) for v in vals])
        except ValueError:
            cols[n] = vals
    return meta, names, cols


# ---- axes in physical units -------------------------------------------------------------------
def physical(name, values):
    """(label, values to draw) of an axis' physical quantity: cos_theta_* become angles in degrees."""
    if name.startswith("cos_theta"):
        sub = name[len("cos_theta"):].lstrip("_") or ""
        return (r"view zenith angle $\theta_{%s}$ (deg)" % sub if sub else r"$\theta$ (deg)",
                np.degrees(np.arccos(np.clip(values, -1.0, 1.0))))
    if name == "alpha":
        return r"roughness $\alpha$ ($= r^2$, clamped)", values
    if name.startswith("alpha_"):
        return r"roughness $\alpha_{%s}$" % name[len("alpha_"):], values
    return name, values


def edges(c):
    """Cell edges around monotonic centres c (midpoints; the outer cells mirrored)."""
    c = np.asarray(c, dtype=float)
    if len(c) == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


class Grid:
    """The texel grid of a CSV with columns i0.., the axis parameters and phys_<physical>: which
    two axes are drawn (x, y), their physical centres, and the rows of the drawn slice."""

    def __init__(self, names, cols):
        self.naxes = sum(1 for n in names if len(n) > 1 and n[0] == "i" and n[1:].isdigit())
        if self.naxes < 1:
            die("no texel index columns i0, i1, ...")
        self.axis_names = names[self.naxes:2 * self.naxes]
        self.phys_names = [n[len("phys_"):] for n in names[2 * self.naxes:3 * self.naxes]]
        idx = [cols["i%d" % k].astype(int) for k in range(self.naxes)]
        sizes = [int(i.max()) + 1 for i in idx]
        sel = np.ones(len(idx[0]), dtype=bool)
        self.slice_note = ""
        notes = []
        for k in range(2, self.naxes):
            mid = sizes[k] // 2
            sel &= idx[k] == mid
            v = cols[names[2 * self.naxes + k]][idx[k] == mid][0]
            lab, vv = physical(self.phys_names[k], np.array([v]))
            notes.append("%s = %.4g" % (self.phys_names[k], v))
        if notes:
            self.slice_note = "slice through the middle texel of the further axes: " + ", ".join(notes)
        # the view angle goes on x (as in mfkit's other LTC figures); else axis 0 on x
        if self.naxes >= 2 and self.phys_names[1].startswith("cos_theta"):
            self.xa, self.ya = 1, 0
        elif self.naxes >= 2:
            self.xa, self.ya = 0, 1
        else:
            self.xa, self.ya = 0, None
        self.sel = sel
        self.idx = [i[sel] for i in idx]
        self.sizes = sizes

        def centres(a):
            c = np.full(sizes[a], np.nan)
            c[idx[a]] = cols[names[2 * self.naxes + a]]
            return physical(self.phys_names[a], c)

        self.xlabel, self.xc = centres(self.xa)
        if self.ya is not None:
            self.ylabel, self.yc = centres(self.ya)

    def image(self, values):
        """The selected rows' values as a (ny, nx) image."""
        v = np.asarray(values)[self.sel]
        if self.ya is None:
            z = np.full((1, self.sizes[self.xa]), np.nan)
            z[0, self.idx[self.xa]] = v
            return z
        z = np.full((self.sizes[self.ya], self.sizes[self.xa]), np.nan)
        z[self.idx[self.ya], self.idx[self.xa]] = v
        return z


def heat(ax, fig, g, z, title, cbar_label, diverging=False, norm=None, cmap=None):
    """One heat map in physical units with its colour bar.  diverging: centred on 0, symmetric."""
    zz = np.ma.masked_invalid(z)
    if norm is None:
        finite = z[np.isfinite(z)]
        if diverging:
            m = float(np.max(np.abs(finite))) if finite.size else 0.0
            if not m > 0:
                m = 1.0
                title += "\n(every value exactly 0)" if finite.size else ""
            norm = colors.TwoSlopeNorm(vcenter=0.0, vmin=-m, vmax=m)
            cmap = cmap or "RdBu_r"
        else:
            lo = float(finite.min()) if finite.size else 0.0
            hi = float(finite.max()) if finite.size else 1.0
            if hi <= lo:
                hi = lo + (abs(lo) if lo else 1.0) * 1e-9 + 1e-300
            norm = colors.Normalize(vmin=lo, vmax=hi)
    cm = plt.get_cmap(cmap or "viridis").copy()
    cm.set_bad("0.85")
    if g.ya is None:
        mesh = ax.pcolormesh(edges(g.xc), [0, 1], zz, norm=norm, cmap=cm, shading="flat")
        ax.set_yticks([])
    else:
        mesh = ax.pcolormesh(edges(g.xc), edges(g.yc), zz, norm=norm, cmap=cm, shading="flat")
        ax.set_ylabel(g.ylabel)
    ax.set_xlabel(g.xlabel)
    ax.set_title(title, fontsize=9)
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label(cbar_label, fontsize=8)
    if np.isnan(z).any():
        ax.text(0.99, 0.01, "grey: NaN", transform=ax.transAxes, ha="right", va="bottom", fontsize=7)
    return mesh


def caption(fig, text):
    fig.text(0.01, 0.005, text, fontsize=6.5, color="0.3", ha="left", va="bottom", wrap=True)


def save(fig, path):
    try:
        fig.savefig(path, dpi=110)
    except OSError as exc:
        die("%s: %s" % (path, exc.strerror or exc))
    plt.close(fig)


# ---- table plot -------------------------------------------------------------------------------
def cmd_fields(csv_path, out_dir, stem):
    meta, names, cols = read_csv(csv_path)
    g = Grid(names, cols)
    fields = names[3 * g.naxes:]
    gate = meta.get("gate", "gate not recorded")
    for fld in fields:
        z = g.image(cols[fld])
        finite = z[np.isfinite(z)]
        signed = finite.size and finite.min() < 0 < finite.max()
        fig, ax = plt.subplots(figsize=(6.4, 4.9))
        title = "%s: %s\n%s table, %s" % (os.path.basename(meta.get("table", stem)), fld, meta.get("kind", "?"), gate)
        if finite.size:
            title += "\nrange [%.4g, %.4g]" % (finite.min(), finite.max())
        heat(ax, fig, g, z, title, fld + (" (diverging at 0)" if signed else ""), diverging=bool(signed))
        fig.tight_layout(rect=(0, 0.04, 1, 1))
        note = "table: %s; each cell is one texel, centred on its texel's value" % meta.get("table", "?")
        if g.slice_note:
            note += "; " + g.slice_note
        caption(fig, note)
        save(fig, os.path.join(out_dir, "%s_%s.png" % (stem, fld)))


# ---- table lobe -------------------------------------------------------------------------------
def cmd_lobe(csv_path, out_dir):
    meta, names, cols = read_csv(csv_path)
    sl = np.array(cols["slice"])
    point = dict(kv.strip().split("=", 1) for kv in meta.get("point", "").split(",") if "=" in kv)
    th = float(point.get("theta_o_deg", "nan"))
    fig = plt.figure(figsize=(13.5, 4.6))
    axes = [fig.add_subplot(1, 3, 1), fig.add_subplot(1, 3, 2), fig.add_subplot(1, 3, 3, projection="polar")]
    titles = {"incidence": r"incidence plane: $w_i = (\sin s, 0, \cos s)$",
              "perpendicular": "perpendicular plane through the mirror direction"}
    for a, which in zip(axes[:2], ("incidence", "perpendicular")):
        m = sl == which
        s, l, b = cols["s_deg"][m], cols["ltc"][m], cols["brdf"][m]
        a.plot(s, b, color="k", lw=1.6, label=r"BRDF $f\,\cos\theta_i$ (%s)" % point.get("brdf", "?"))
        a.plot(s, l, color="C1", lw=1.3, ls="--", label=r"LTC: magnitude $\times\,D_{LTC}$")
        if which == "incidence" and math.isfinite(th):
            a.axvline(-th, color="0.5", lw=0.8, ls=":")
            a.axvline(th, color="C0", lw=0.8, ls=":")
            a.text(-th, a.get_ylim()[1] * 0.97, " mirror", fontsize=7, color="0.4", va="top")
            a.text(th, a.get_ylim()[1] * 0.97, " view", fontsize=7, color="C0", va="top")
        a.set_xlabel("s (deg)" + (", > 0: towards the view" if which == "incidence" else ", > 0: towards +y"))
        a.set_ylabel("cosine-weighted value (1/sr)")
        a.set_xlim(-90, 90)
        a.set_title(titles[which], fontsize=9)
        a.grid(True, alpha=0.3)
        a.legend(fontsize=7)
    p = axes[2]
    m = sl == "incidence"
    ang = np.radians(cols["s_deg"][m])
    p.plot(ang, cols["brdf"][m], color="k", lw=1.6, label="BRDF")
    p.plot(ang, cols["ltc"][m], color="C1", lw=1.3, ls="--", label="LTC")
    if math.isfinite(th):
        r = max(np.nanmax(cols["brdf"][m]), np.nanmax(cols["ltc"][m]))
        p.plot([math.radians(th)] * 2, [0, r], color="C0", lw=0.8, ls=":")
    p.set_theta_zero_location("N")
    p.set_theta_direction(-1)
    p.set_thetamin(-90)
    p.set_thetamax(90)
    p.tick_params(labelsize=7)
    p.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
    p.set_title("incidence plane, polar (up: the normal; dotted: the view)", fontsize=9)
    p.legend(fontsize=7, loc="lower left")
    fig.suptitle("%s (%s, %s): lobe at alpha = %.4g, theta_o = %.2f deg (r = %.4g, u = %.4g), magnitude %.4g" % (
        os.path.basename(meta.get("table", "?")), meta.get("kind", "?"), meta.get("gate", "?"),
        float(point.get("alpha", "nan")), th, float(point.get("r", "nan")), float(point.get("u", "nan")),
        float(point.get("magnitude", "nan"))), fontsize=10)
    fig.tight_layout(rect=(0, 0.04, 1, 0.95))
    caption(fig, "numbers: lobe.csv, from mfkit's C library (mf_ltc_eval of the interpolated record, the model's "
                 "eval_cos); both per steradian, the LTC scaled by the tabulated magnitude (albedo)")
    save(fig, os.path.join(out_dir, "lobe.png"))


# ---- compare ----------------------------------------------------------------------------------
def cmd_compare(diff_csv, shading_csv, out_dir):
    meta, names, cols = read_csv(diff_csv)
    g = Grid(names, cols)
    fields = [n[2:] for n in names if n.startswith("d_")]
    ncols = min(4, len(fields))
    nrows = (len(fields) + ncols - 1) // ncols
    fig, axs = plt.subplots(nrows, ncols, figsize=(4.8 * ncols, 3.9 * nrows + 0.6), squeeze=False)
    for k, fld in enumerate(fields):
        z = g.image(cols["d_" + fld])
        finite = z[np.isfinite(z)]
        heat(axs[k // ncols][k % ncols], fig, g, z,
             "%s: B - A\nmax |B - A| %.3g" % (fld, float(np.max(np.abs(finite))) if finite.size else float("nan")),
             "B - A (blue: B smaller, red: B larger)", diverging=True)
    for k in range(len(fields), nrows * ncols):
        axs[k // ncols][k % ncols].axis("off")
    fig.suptitle("A = %s, B = %s (%s)\nverdict: %s" % (meta.get("A", "?"), meta.get("B", "?"), meta.get("kind", "?"),
                                                     meta.get("verdict", "?")), fontsize=9)
    fig.tight_layout(rect=(0, 0.03, 1, 0.93))
    caption(fig, "both tables resampled onto the common grid by their own multilinear interpolation; each colour "
                 "map is centred on 0 (no difference)" + ("; " + g.slice_note if g.slice_note else ""))
    save(fig, os.path.join(out_dir, "compare_diff.png"))
    if shading_csv == "-":
        return
    meta, names, cols = read_csv(shading_csv)
    th, al = cols["theta_o_deg"], cols["alpha"]
    xs, ys = np.unique(th), np.unique(al)
    ix, iy = np.searchsorted(xs, th), np.searchsorted(ys, al)

    def img(v):
        z = np.full((len(ys), len(xs)), np.nan)
        z[iy, ix] = v
        return z

    gg = type("G", (), {})()
    gg.xc, gg.yc, gg.ya = xs, ys, 0
    gg.xlabel, gg.ylabel = r"view zenith angle $\theta_o$ (deg)", r"roughness $\alpha$"
    a_err, b_err, se = cols["a_mean_abs"], cols["b_mean_abs"], cols["mc_mean_se"]
    both = np.concatenate([a_err, b_err])
    both = both[np.isfinite(both) & (both > 0)]
    # one colour scale for A and B; its floor is the Monte Carlo noise (an error below the mean
    # standard error is noise, not a measurable error)
    floor = max(float(np.nanmedian(se)), 1e-12)
    hi = max(float(both.max()) if both.size else floor * 10, floor * 10)
    norm = colors.LogNorm(vmin=floor, vmax=hi)
    fig, axs = plt.subplots(1, 3, figsize=(16.5, 4.9), squeeze=False)
    for a, v, who in ((axs[0][0], a_err, "A"), (axs[0][1], b_err, "B")):
        heat(a, fig, gg, img(np.maximum(v, floor)), "%s: mean |LTC - MC| per texel, mean %.3g\n%s" % (
            who, float(np.mean(v)), os.path.basename(meta.get(who, "?"))),
             "mean |LTC - MC| (log; shared by A and B; floor = MC noise)", norm=norm, cmap="magma")
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (b_err - a_err) / np.where(se > 0, se, np.nan)
    heat(axs[0][2], fig, gg, img(t), "B - A in units of the MC standard error\n(|value| < 3: within the noise; "
         "blue: B better)", "(B - A) / s.e.", norm=colors.TwoSlopeNorm(vcenter=0.0, vmin=-10.0, vmax=10.0),
         cmap="RdBu_r")
    fig.suptitle("polygon shading error against Monte Carlo, same lights for A and B\nverdict: %s"
                 % meta.get("verdict", "?"), fontsize=9)
    fig.tight_layout(rect=(0, 0.03, 1, 0.9))
    caption(fig, "A = %s, B = %s; colour of the right panel clipped at +-10" % (meta.get("A", "?"), meta.get("B", "?")))
    save(fig, os.path.join(out_dir, "compare_shading.png"))


def main(argv):
    global CMD
    args = argv[1:]
    if len(args) >= 2 and args[0] == "--cmd":
        CMD = args[1]
        args = args[2:]
    if not args:
        die("tableplot.py: no subcommand (check, fields, lobe, compare)", 2)
    if IMPORT_ERROR:
        die("plots need numpy and matplotlib, cannot import %s: apt-get install python3-numpy python3-matplotlib "
            "(or --no-plots)" % IMPORT_ERROR, 2)
    sub, rest = args[0], args[1:]
    if sub == "check" and not rest:
        return 0
    if sub == "fields" and len(rest) == 3:
        cmd_fields(*rest)
    elif sub == "lobe" and len(rest) == 2:
        cmd_lobe(*rest)
    elif sub == "compare" and len(rest) == 3:
        cmd_compare(*rest)
    else:
        die("tableplot.py: bad arguments: %s" % " ".join(args), 2)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv))
    except SystemExit:
        raise
    except Exception as exc:  # one line, whatever went wrong while drawing
        die("plotting failed: %s: %s" % (type(exc).__name__, exc))
