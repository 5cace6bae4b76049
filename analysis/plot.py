#!/usr/bin/python3
"""plot.py DATA_DIR OUT_DIR -- turn mfkit's analysis CSV files into PNG and PDF figures (issue 6).

Run it with Debian's /usr/bin/python3 (packages python3-numpy and python3-matplotlib); no PyPI.
Every *.csv in DATA_DIR is recognised by its column names (not its file name), so renamed files
still plot; unknown CSV files are listed and skipped.  Known data (docs/figures.md):

  study_smith        smith_walter_g1.*, smith_gaussian_lambda.*
  study_furnace      furnace_microfacet.*, furnace_curves.*, furnace_models.*
  study_proxy        proxy_alpha_error.*, proxy_alpha_curves.*, ggx_rect_error.*
  study_leadr_grid   leadr_grid_convergence.*
  bench_ltc --csv    ltc_polygon_error.*

Each figure carries a caption line naming its data file and the file's provenance header
(command, mfkit version, seed, date).  Exit status: 0 when every recognised file plotted,
1 on a plotting error, 2 for bad usage, 3 when numpy or matplotlib is missing.
"""
import csv
import math
import os
import sys
import textwrap

try:
    import numpy as np
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import colors
except ImportError as exc:  # pragma: no cover - depends on the interpreter
    sys.stderr.write(
        "plot.py: cannot import %s with %s (Python %s).\n"
        "plot.py needs numpy and matplotlib: run it with Debian's /usr/bin/python3 after\n"
        "  apt-get install python3-numpy python3-matplotlib\n"
        "(the python3 first on PATH may be a separate build without numpy).\n"
        % (getattr(exc, "name", None) or exc, sys.executable, sys.version.split()[0])
    )
    sys.exit(3)

ERR_FLOOR = 1e-17  # relative errors of exactly 0 are drawn at this floor on log scales
FORMATS = ("png", "pdf")


# ---- reading -------------------------------------------------------------------------------
class Data:
    """A CSV file: its '#' header lines and its columns (float arrays, or str arrays)."""

    def __init__(self, path):
        self.path = path
        self.header = []
        rows = []
        with open(path, newline="") as f:
            lines = [ln for ln in f]
        body = []
        for ln in lines:
            if ln.startswith("#") and not body:
                self.header.append(ln[1:].strip())
            else:
                body.append(ln)
        reader = csv.reader(body)
        self.names = next(reader, [])
        for r in reader:
            if r:
                rows.append(r)
        self.cols = {}
        for j, name in enumerate(self.names):
            vals = [r[j] if j < len(r) else "" for r in rows]
            try:
                self.cols[name] = np.array([float(v) if v != "" else math.nan for v in vals])
            except ValueError:
                self.cols[name] = np.array(vals)

    def __getitem__(self, name):
        return self.cols[name]

    def where(self, mask):
        d = Data.__new__(Data)
        d.path, d.header, d.names = self.path, self.header, self.names
        d.cols = {k: v[mask] for k, v in self.cols.items()}
        return d

    def has(self, *names):
        return all(n in self.cols for n in names)

    def caption(self):
        prov = "; ".join(self.header[:2]) if self.header else "no provenance header in the file"
        return "data: %s  |  %s" % (os.path.basename(self.path), prov)


def grid_of(d, xname, yname, zname):
    """Values z on the regular grid spanned by the unique x and y values (NaN where missing)."""
    xs = np.unique(d[xname][~np.isnan(d[xname])])
    ys = np.unique(d[yname][~np.isnan(d[yname])])
    z = np.full((len(ys), len(xs)), np.nan)
    ix = np.searchsorted(xs, d[xname])
    iy = np.searchsorted(ys, d[yname])
    ok = (ix < len(xs)) & (iy < len(ys))
    z[iy[ok], ix[ok]] = d[zname][ok]
    return xs, ys, z


def edges(v, log=False):
    """Cell edges around sorted centres v (geometric midpoints for log axes)."""
    v = np.asarray(v, dtype=float)
    if len(v) == 1:
        return np.array([v[0] * 0.9, v[0] * 1.1]) if log else np.array([v[0] - 0.5, v[0] + 0.5])
    t = np.log10(v) if log else v
    mid = 0.5 * (t[1:] + t[:-1])
    e = np.concatenate([[t[0] - (mid[0] - t[0])], mid, [t[-1] + (t[-1] - mid[-1])]])
    return 10.0 ** e if log else e


# ---- drawing helpers ------------------------------------------------------------------------
def new_figure(ncols=1, nrows=1, width=6.4, height=4.6):
    fig, axes = plt.subplots(nrows, ncols, figsize=(width * ncols, height * nrows), squeeze=False)
    return fig, axes


def finish(fig, data, out_dir, name, made, note=None):
    text = data.caption() if isinstance(data, Data) else data
    if note:
        text += "  |  " + note
    wrapped = "\n".join(textwrap.wrap(text, width=int(fig.get_figwidth() * 17)))
    nlines = wrapped.count("\n") + 1
    fig.tight_layout(rect=(0, 0.035 * nlines * 4.6 / fig.get_figheight(), 1, 1))
    fig.text(0.01, 0.005, wrapped, fontsize=7, color="0.25", ha="left", va="bottom")
    for ext in FORMATS:
        path = os.path.join(out_dir, "%s.%s" % (name, ext))
        fig.savefig(path, dpi=130)
        made.append(path)
    plt.close(fig)


def heatmap(ax, fig, xs, ys, z, xlabel, ylabel, title, cbar_label, log_colour=False, xlog=False, ylog=False,
            vmin=None, vmax=None, cmap="viridis", masked_label=None):
    zz = np.array(z, dtype=float)
    if log_colour:
        zz = np.where(zz <= 0, ERR_FLOOR, zz)
        finite = zz[np.isfinite(zz)]
        lo = vmin if vmin is not None else (finite.min() if finite.size else ERR_FLOOR)
        hi = vmax if vmax is not None else (finite.max() if finite.size else 1.0)
        if hi <= lo:
            hi = lo * 10.0
        norm = colors.LogNorm(vmin=lo, vmax=hi)
    else:
        norm = colors.Normalize(vmin=vmin if vmin is not None else np.nanmin(zz),
                                vmax=vmax if vmax is not None else np.nanmax(zz))
    cm = plt.get_cmap(cmap).copy()
    cm.set_bad("0.85")
    mesh = ax.pcolormesh(edges(xs, xlog), edges(ys, ylog), np.ma.masked_invalid(zz), norm=norm, cmap=cm,
                         shading="flat")
    if xlog:
        ax.set_xscale("log")
    if ylog:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label(cbar_label)
    if masked_label and np.isnan(zz).any():
        ax.set_title(title + "\ngrey: " + masked_label, fontsize=10)
    return mesh


def fmt_max(v, where=""):
    return "max %.3g%s" % (v, where)


# ---- study_smith ----------------------------------------------------------------------------
def plot_smith(d, out_dir, made):
    w = d.where(d["part"] == "walter")
    if len(w["nu"]):
        order = np.argsort(w["nu"])
        nu, rel = w["nu"][order], w["rel_err_g1"][order]
        fig, ax = new_figure(2, 1, width=5.4)
        a0, a1 = ax[0]
        a0.semilogx(nu, w["g1_exact"][order], label="exact (erfc form)")
        a0.semilogx(nu, w["g1_ref"][order], "--", label="Walter 2007, Eq. 27 (clamped, ERRATA L4)")
        a0.set_xlabel(r"$\nu = \cot\theta / (\sqrt{2}\,\sigma)$ (dimensionless)")
        a0.set_ylabel(r"$G_1 = 1/(1+\Lambda)$")
        a0.set_title("Beckmann Smith $G_1$", fontsize=10)
        a0.legend(fontsize=8)
        i = int(np.nanargmax(rel))
        a1.loglog(nu, np.maximum(rel, ERR_FLOOR), color="C3")
        a1.axvline(1.6, color="0.5", lw=0.8, ls=":")
        a1.text(1.6, a1.get_ylim()[0] * 3, r" $\nu$ = 1.6: Walter's $\Lambda$ = 0", fontsize=7, color="0.3")
        a1.plot(nu[i], rel[i], "o", color="k", ms=4)
        a1.annotate("max %.3g %% at nu = %.3g" % (100 * rel[i], nu[i]), (nu[i], rel[i]), textcoords="offset points",
                    xytext=(-170, -16), fontsize=8)
        a1.set_xlabel(r"$\nu$ (dimensionless)")
        a1.set_ylabel(r"relative error of $G_1$, |Walter - exact| / exact")
        a1.set_title("Walter's rational approximation: error of $G_1$\n(exact zeros drawn at 1e-17)", fontsize=10)
        a1.grid(True, which="major", alpha=0.3)
        finish(fig, d, out_dir, "smith_walter_g1", made)
    g = d.where(d["part"] == "gaussian")
    if len(g["nu"]):
        xs, ys, z = grid_of(g, "mean_slope", "theta_deg", "rel_err_lambda")
        fig, ax = new_figure(1, 1, width=7.0, height=5.0)
        heatmap(ax[0][0], fig, xs, ys, z, "mean slope $\\mu$ along the view azimuth (dimensionless)",
                r"view zenith angle $\theta_o$ (deg)",
                "Non-centred Gaussian $\\Lambda$: closed form vs Smith's integral\n"
                "(variance 0.125 = Beckmann alpha 0.5, view in the plane of the mean; zeros at 1e-17)",
                "relative error |closed - integral| / integral", log_colour=True,
                masked_label="not evaluated (below the mesosurface, or Lambda < 1e-198)")
        finish(fig, d, out_dir, "smith_gaussian_lambda", made, note=fmt_max(np.nanmax(z)))


# ---- study_furnace --------------------------------------------------------------------------
def plot_furnace(d, out_dir, made):
    mf = d.where(d["source"] == "microfacet")
    if len(mf["alpha"]):
        fig, ax = new_figure(2, 2, width=5.6, height=4.4)
        for i, brdf in enumerate(("ggx", "beckmann")):
            for j, fr in enumerate(("none", "schlick_0.04")):
                s = mf.where((mf["brdf"] == brdf) & (mf["fresnel"] == fr))
                if not len(s["alpha"]):
                    continue
                xs, ys, z = grid_of(s, "theta_deg", "alpha", "albedo")
                title = "%s, %s" % ("GGX" if brdf == "ggx" else "Beckmann",
                                    "F = 1 (white furnace)" if fr == "none" else "Schlick F0 = 0.04")
                heatmap(ax[i][j], fig, xs, ys, z, r"view zenith angle $\theta_o$ (deg)", r"roughness $\alpha$",
                        title + ": min %.3f" % np.nanmin(z), "directional albedo (single scattering)",
                        vmin=0.0 if fr == "none" else 0.01, vmax=1.0, log_colour=(fr != "none"), cmap="magma")
        finish(fig, d, out_dir, "furnace_microfacet", made,
               note="quadrature mf_brdf_microfacet_albedo, height-correlated G2")
        # furnace curves: albedo vs theta for a few roughnesses
        fig, ax = new_figure(2, 1, width=5.4)
        alphas = np.unique(mf["alpha"])
        pick = alphas[np.unique(np.linspace(0, len(alphas) - 1, min(5, len(alphas))).round().astype(int))]
        for k, brdf in enumerate(("ggx", "beckmann")):
            a = ax[0][k]
            for c, al in enumerate(pick):
                for fr, ls in (("none", "-"), ("schlick_0.04", "--")):
                    s = mf.where((mf["brdf"] == brdf) & (mf["fresnel"] == fr) & (mf["alpha"] == al))
                    o = np.argsort(s["theta_deg"])
                    a.plot(s["theta_deg"][o], s["albedo"][o], ls, color="C%d" % c,
                           label=r"$\alpha$ = %.2f" % al if fr == "none" else None)
            a.set_xlabel(r"view zenith angle $\theta_o$ (deg)")
            a.set_ylabel("directional albedo")
            a.set_ylim(0, 1.05)
            a.set_title("%s: solid F = 1, dashed Schlick F0 = 0.04" % ("GGX" if brdf == "ggx" else "Beckmann"),
                        fontsize=10)
            a.grid(True, alpha=0.3)
            a.legend(fontsize=8, loc="center left")
        finish(fig, d, out_dir, "furnace_curves", made)
    md = d.where(d["source"] == "model")
    names = [n for n in dict.fromkeys(md["brdf"])]
    if names:
        ncols = 3
        nrows = (len(names) + ncols - 1) // ncols
        fig, ax = new_figure(ncols, nrows, width=4.8, height=3.9)
        top = float(np.nanmax(md["albedo"]))
        for k, name in enumerate(names):
            a = ax[k // ncols][k % ncols]
            s = md.where(md["brdf"] == name)
            xs, ys, z = grid_of(s, "theta_deg", "alpha", "albedo")
            _, _, e = grid_of(s, "theta_deg", "alpha", "err")
            heatmap(a, fig, xs, ys, z, r"$\theta_o$ (deg)", r"roughness parameter $\alpha$",
                    "%s: [%.3f, %.3f], max s.e. %.1g" % (name, np.nanmin(z), np.nanmax(z), np.nanmax(e)),
                    "albedo", vmin=0.0, vmax=max(top, 1.0), cmap="magma")
            # albedo above 1 by more than 3 standard errors (not Monte Carlo noise)
            excess = (z - 1.0) / np.maximum(e, 1e-300)
            if np.nanmax(excess) > 3.0 and np.nanmin(excess) < 3.0:
                a.contour(xs, ys, excess, levels=[3.0], colors="c", linewidths=1.0)
        for k in range(len(names), nrows * ncols):
            ax[k // ncols][k % ncols].axis("off")
        fig.suptitle("Directional albedo of the LTC target models (mf_model.h), F = 1; cyan line: albedo > 1 by 3 s.e. (inside)",
                     fontsize=11)
        finish(fig, d, out_dir, "furnace_models", made, note="stratified Monte Carlo, s.e. = standard error")


# ---- study_proxy ----------------------------------------------------------------------------
def plot_proxy(d, out_dir, made):
    fig, ax = new_figure(2, 1, width=5.8, height=4.6)
    for a, col, title in ((ax[0][0], "rel_err_approx", r"paper: $\sqrt{\alpha^2 + dh^2}$ (Kaplanyan Eq. 20)"),
                          (ax[0][1], "rel_err_fit", "mfkit fitted form (mf_proxy_alpha_fit)")):
        xs, ys, z = grid_of(d, "dh", "alpha", col)
        heatmap(a, fig, xs, ys, z, "filter width dh (slope units, full width)", r"GGX roughness $\alpha$",
                title + "\nmax %.3g" % np.nanmax(z), r"relative error of $\alpha'$ vs exact (Eq. 19)",
                log_colour=True, xlog=True, ylog=True)
    finish(fig, d, out_dir, "proxy_alpha_error", made)

    x = d["dh"] / d["alpha"]
    o = np.argsort(x)
    fig, ax = new_figure(1, 1, width=7.0)
    a = ax[0][0]
    a.loglog(x[o], np.maximum(d["rel_err_approx"][o], ERR_FLOOR), ".", ms=2, label=r"$\sqrt{\alpha^2 + dh^2}$")
    a.loglog(x[o], np.maximum(d["rel_err_fit"][o], ERR_FLOOR), ".", ms=2, label="mfkit fitted form")
    a.axhline(3.2e-6, color="0.4", ls=":", lw=0.8)
    a.text(x[o][0], 3.2e-6 * 1.3, "MF_PROXY_FIT_MAX_REL_ERROR = 3.2e-6", fontsize=7, color="0.3")
    a.set_xlabel(r"dh / $\alpha$ (the error depends on this ratio only)")
    a.set_ylabel(r"relative error of $\alpha'$")
    a.set_title("GGX proxy roughness: error against the exact peak condition", fontsize=10)
    a.grid(True, which="major", alpha=0.3)
    a.legend(fontsize=8, markerscale=4)
    finish(fig, d, out_dir, "proxy_alpha_curves", made)

    fig, ax = new_figure(2, 1, width=5.8, height=4.6)
    hi = np.nanmax([np.nanmax(d["rel_err_rect"]), np.nanmax(d["rel_err_rect_naive"])])
    for a, col, title in ((ax[0][0], "rel_err_rect", "mf_filter_ggx_rect_mean (cancellation-free)"),
                          (ax[0][1], "rel_err_rect_naive", "plain difference of the App. A antiderivative")):
        xs, ys, z = grid_of(d, "dh", "alpha", col)
        heatmap(a, fig, xs, ys, z, "square full width dh (slope units)", r"GGX roughness $\alpha$",
                title + "\nmax %.3g" % np.nanmax(z), "relative error vs nested quadrature",
                log_colour=True, xlog=True, ylog=True, vmin=1e-17, vmax=max(hi, 1e-15))
    finish(fig, d, out_dir, "ggx_rect_error", made,
           note="mean of P22 over the square centred on the peak; exact zeros drawn at 1e-17")


# ---- study_leadr_grid -----------------------------------------------------------------------
def plot_leadr(d, out_dir, made):
    layouts = list(dict.fromkeys(d["layout"]))
    fig, ax = new_figure(len(layouts) + 1, 1, width=5.0, height=4.4)
    for k, lay in enumerate(layouts):
        s = d.where(d["layout"] == lay)
        ns, lams = np.unique(s["N"]), np.unique(s["lambda"])
        z = np.full((len(lams), len(ns)), np.nan)
        for i, n in enumerate(ns):
            for j, lam in enumerate(lams):
                m = (s["N"] == n) & (np.abs(s["lambda"] - lam) < 1e-9)
                if m.any():
                    z[j, i] = np.mean(s["rel_err"][m])
        heatmap(ax[0][k], fig, ns, lams, z, "grid size N (N x N slopes)", r"grid extent $\lambda$ (std. devs.)",
                "layout: %s" % lay, "mean relative error over the cases", log_colour=True)
        best = np.nanmin(z, axis=0)
        bl = lams[np.nanargmin(z, axis=0)]
        ax[0][k].plot(ns, bl, "w.-", lw=0.8, ms=4)
        ax[0][-1].semilogy(ns, best, "o-", ms=3, label=lay)
    a = ax[0][-1]
    a.set_xlabel("grid size N")
    a.set_ylabel(r"mean relative error at the best $\lambda$")
    a.set_title(r"LEADR grid convergence (white dots: best $\lambda$)", fontsize=10)
    a.grid(True, which="major", alpha=0.3)
    a.legend(fontsize=8)
    finish(fig, d, out_dir, "leadr_grid_convergence", made, note="reference: stratified Monte Carlo, median relative s.e. %.2g (the error floor)"
           % np.nanmedian(d["ref_se"] / np.abs(d["ref"])))


# ---- bench_ltc --csv --------------------------------------------------------------------------
def plot_bench_ltc(d, out_dir, made):
    tables = list(dict.fromkeys(d["table"]))
    fig, ax = new_figure(len(tables), 1, width=5.6, height=4.6)
    for k, t in enumerate(tables):
        s = d.where(d["table"] == t)
        views = np.unique(s["view"])
        r = np.array([s["r"][s["view"] == v][0] for v in views])
        th = np.degrees(np.arccos(np.clip([s["cos_theta"][s["view"] == v][0] for v in views], -1, 1)))
        err = np.array([np.mean(s["rel_error"][s["view"] == v]) for v in views])
        a = ax[0][k]
        sc = a.scatter(th, r, c=np.maximum(err, ERR_FLOOR), s=14, cmap="viridis", norm=colors.LogNorm())
        cb = fig.colorbar(sc, ax=a)
        cb.set_label("mean relative polygon error per view")
        a.set_xlabel(r"view zenith angle $\theta_o$ (deg)")
        a.set_ylabel(r"table roughness r ($\alpha = r^2$)")
        a.set_title("%s\nmean %.3g, worst view %.3g" % (os.path.basename(t), np.mean(err), np.max(err)), fontsize=9)
    finish(fig, d, out_dir, "ltc_polygon_error", made,
           note="|LTC - MC| / max(MC, 0.01 albedo), averaged over the random polygons of each view")


# ---- dispatch -------------------------------------------------------------------------------
KINDS = (
    (("part", "nu", "rel_err_g1", "rel_err_lambda"), plot_smith),
    (("source", "brdf", "fresnel", "theta_deg", "alpha", "albedo"), plot_furnace),
    (("alpha", "dh", "rel_err_approx", "rel_err_fit", "rel_err_rect"), plot_proxy),
    (("layout", "N", "lambda", "rel_err"), plot_leadr),
    (("table", "view", "r", "cos_theta", "rel_error"), plot_bench_ltc),
)


def main(argv):
    if len(argv) != 3 or argv[1] in ("-h", "--help"):
        sys.stderr.write("usage: /usr/bin/python3 analysis/plot.py DATA_DIR OUT_DIR\n")
        return 2
    data_dir, out_dir = argv[1], argv[2]
    if not os.path.isdir(data_dir):
        sys.stderr.write("plot.py: %s: not a directory\n" % data_dir)
        return 2
    os.makedirs(out_dir, exist_ok=True)
    made, status = [], 0
    for fn in sorted(os.listdir(data_dir)):
        if not fn.endswith(".csv"):
            continue
        path = os.path.join(data_dir, fn)
        try:
            d = Data(path)
        except (OSError, UnicodeDecodeError) as exc:
            sys.stderr.write("plot.py: %s: %s\n" % (path, exc))
            status = 1
            continue
        for cols, fn_plot in KINDS:
            if d.has(*cols):
                before = len(made)
                try:
                    fn_plot(d, out_dir, made)
                except Exception as exc:  # report and go on with the other files
                    sys.stderr.write("plot.py: %s: %s: %s\n" % (path, type(exc).__name__, exc))
                    status = 1
                print("%s -> %s" % (fn, ", ".join(os.path.basename(p) for p in made[before:]) or "(no figure)"))
                break
        else:
            print("%s: columns not recognised, skipped" % fn)
    if not made:
        sys.stderr.write("plot.py: no figure produced from %s\n" % data_dir)
        return 1
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
