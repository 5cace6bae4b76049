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
  study_sh_irradiance  sh_irradiance_error.*, sh_irradiance_curves.*
  study_half         half_shading_error.* (LTC tables), half_rounding_error.*
  study_ltc_texels   ltc_texel_errors.*, and ltc_texel_pair.* with a SECOND_TABLE
  study_random_walk  random_walk.* (GGX), random_walk_beckmann.*

Each figure carries a caption line naming its data file and the file's provenance header
(command, mfkit version, seed, date); paths in it are shown relative to the source tree, and files
of temporary directories by their name only.  Figures of an LTC table say whether the table passed
its gate: MFKIT_FIGURE_GATES (environment, set by make_figures.sh) names a file of lines
"TABLE_FILE_NAME<TAB>verdict"; without it the figures say that the gate was not recorded.
Exit status: 0 when every recognised file plotted, 1 on a plotting error, 2 for bad usage, 3 when
numpy or matplotlib is missing.
"""
import csv
import math
import os
import re
import sys
import tempfile
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
SOURCE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def clean_paths(text):
    """Paths as a reader of the figure can use them: the source tree's relative to its root, files
    in temporary directories (make_figures.sh's scratch fits) by their name alone."""
    text = text.replace(SOURCE_DIR + "/", "")
    temps = {"/tmp", "/var/tmp", tempfile.gettempdir(), os.environ.get("TMPDIR", "/tmp").rstrip("/")}
    for t in sorted((t for t in temps if t), key=len, reverse=True):
        text = re.sub(re.escape(t) + r"/[^\s,;]*", lambda m: os.path.basename(m.group(0)), text)
    return text


def _read_gates():
    """{table file name: verdict} from the file named by MFKIT_FIGURE_GATES (make_figures.sh)."""
    path = os.environ.get("MFKIT_FIGURE_GATES")
    gates = {}
    if path:
        try:
            with open(path) as f:
                for ln in f:
                    name, sep, verdict = ln.rstrip("\n").partition("\t")
                    if sep:
                        gates[os.path.basename(name)] = verdict
        except OSError as exc:
            sys.stderr.write("plot.py: MFKIT_FIGURE_GATES=%s: %s\n" % (path, exc))
    return gates


GATES = _read_gates()


def gate_of(table):
    """'NAME: passed its gate' (or failed, or not recorded) for a table path or name."""
    name = os.path.basename(str(table))
    return "%s: %s" % (name, GATES.get(name, "gate not recorded (make_figures.sh records it)"))


def gates_in(text):
    """The gate verdicts of the tables named in text (a provenance line), in order."""
    names = [n for n in GATES if n in text]
    names.sort(key=text.find)
    return "; ".join("%s: %s" % (n, GATES[n]) for n in names) if names else "gate not recorded (make_figures.sh records it)"


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
        return "data: %s  |  %s" % (os.path.basename(self.path), clean_paths(prov))


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
    text = data.caption() if isinstance(data, Data) else clean_paths(data)
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
            vmin=None, vmax=None, cmap="viridis", masked_label=None, norm=None):
    zz = np.array(z, dtype=float)
    if norm is not None:
        if isinstance(norm, colors.LogNorm):
            zz = np.where(zz <= 0, norm.vmin, zz)
    elif log_colour:
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
        a0.semilogx(nu, w["g1_ref"][order], "--", label="Walter 2007, Eq. 27 (clamped, docs/math.md, correction C-L4)")
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
            # centred on 1, the threshold that matters: blue below (energy lost), red above (created)
            heatmap(a, fig, xs, ys, z, r"$\theta_o$ (deg)", r"roughness parameter $\alpha$",
                    "%s: [%.3f, %.3f], max s.e. %.1g" % (name, np.nanmin(z), np.nanmax(z), np.nanmax(e)),
                    "albedo (white: 1)", cmap="RdBu_r",
                    norm=colors.TwoSlopeNorm(vcenter=1.0, vmin=0.0, vmax=max(top, 1.05)))
            # albedo above 1 by more than 3 standard errors (not Monte Carlo noise)
            excess = (z - 1.0) / np.maximum(e, 1e-300)
            if np.nanmax(excess) > 3.0 and np.nanmin(excess) < 3.0:
                a.contour(xs, ys, excess, levels=[3.0], colors="c", linewidths=1.0)
        for k in range(len(names), nrows * ncols):
            ax[k // ncols][k % ncols].axis("off")
        fig.suptitle("Directional albedo of the LTC target models (mf_model.h), F = 1; colours centred on 1 (white); "
                     "cyan line: albedo > 1 by 3 s.e. (inside)", fontsize=11)
        finish(fig, d, out_dir, "furnace_models", made, note="stratified Monte Carlo, s.e. = standard error")


# ---- study_proxy ----------------------------------------------------------------------------
def plot_proxy(d, out_dir, made):
    fig, ax = new_figure(2, 1, width=5.8, height=4.6)
    # one colour scale for both panels (they are compared): from the smallest non-zero error of
    # either to the largest of either
    both = np.concatenate([d["rel_err_approx"], d["rel_err_fit"]])
    both = both[np.isfinite(both) & (both > 0)]
    lo = max(float(both.min()) if both.size else ERR_FLOOR, ERR_FLOOR)
    hi = max(float(both.max()) if both.size else 1.0, lo * 10.0)
    for a, col, title in ((ax[0][0], "rel_err_approx", r"paper: $\sqrt{\alpha^2 + dh^2}$ (Kaplanyan Eq. 20)"),
                          (ax[0][1], "rel_err_fit", "mfkit fitted form (mf_proxy_alpha_fit)")):
        xs, ys, z = grid_of(d, "dh", "alpha", col)
        heatmap(a, fig, xs, ys, z, "filter width dh (slope units, full width)", r"GGX roughness $\alpha$",
                title + "\nmax %.3g" % np.nanmax(z), r"relative error of $\alpha'$ vs exact (Eq. 19)",
                log_colour=True, xlog=True, ylog=True, vmin=lo, vmax=hi)
    finish(fig, d, out_dir, "proxy_alpha_error", made, note="both panels share one colour scale")

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
    per = []
    for t in tables:
        s = d.where(d["table"] == t)
        views = np.unique(s["view"])
        r = np.array([s["r"][s["view"] == v][0] for v in views])
        th = np.degrees(np.arccos(np.clip([s["cos_theta"][s["view"] == v][0] for v in views], -1, 1)))
        err = np.array([np.mean(s["rel_error"][s["view"] == v]) for v in views])
        per.append((t, th, r, np.maximum(err, ERR_FLOOR)))
    # one colour scale for every table (the reference beside mfkit's)
    allerr = np.concatenate([p[3] for p in per])
    norm = colors.LogNorm(vmin=float(allerr.min()), vmax=max(float(allerr.max()), float(allerr.min()) * 10))
    for k, (t, th, r, err) in enumerate(per):
        a = ax[0][k]
        sc = a.scatter(th, r, c=err, s=14, cmap="viridis", norm=norm)
        cb = fig.colorbar(sc, ax=a)
        cb.set_label("mean relative polygon error per view (shared scale)")
        a.set_xlabel(r"view zenith angle $\theta_o$ (deg)")
        a.set_ylabel(r"table roughness r ($\alpha = r^2$)")
        a.set_title("%s\nmean %.3g, worst view %.3g" % (gate_of(t), np.mean(err), np.max(err)), fontsize=9)
    finish(fig, d, out_dir, "ltc_polygon_error", made,
           note="|LTC - MC| / max(MC, 0.01 albedo), averaged over the random polygons of each view; the same "
                "views and polygons for every table")


# ---- study_ltc_texels ---------------------------------------------------------------------------
MC_NOISE_RATIO = 1.5  # mean |LTC - MC| <= 1.5 mean standard errors: Monte Carlo noise.  An exact table
                      # gives E|N(0, se)| = 0.80 se per polygon; over 16 polygons the mean spreads by
                      # about 0.6 se / 4 = 0.15 se, so 1.5 is 4.7 spreads above what noise alone gives
ALBEDO_ROUNDING = 1e-12  # relative albedo differences below this are rounding (the quadrature's own error
                         # estimate is ~1e-15 for smooth lobes): the colour limit never goes below it
LTC_TEXEL_FLOOR = 1e-4  # log colour scales start here: the r = 0 row (alpha 1e-4 or 1e-5, a near-delta
                        # lobe) is ~1e-8 and would squeeze every other texel into one colour


def _clip_limit(z):
    """A symmetric colour limit for signed data: the 98th percentile of |z|, so that a few
    outlying texels (drawn in the darkest colour) do not wash out the rest."""
    a = np.abs(z[np.isfinite(z)])
    return float(np.percentile(a, 98)) if a.size else 0.0


def _diverging(ax, fig, xs, ys, z, xlabel, ylabel, title, cbar_label, limit=None):
    """Heat map centred on 0 (blue < 0 < red); symmetric limits, or +-limit."""
    m = limit if limit is not None else float(np.nanmax(np.abs(z))) if np.isfinite(z).any() else 0.0
    if not m > 0:
        m = 1.0  # every value exactly 0 (or missing): any symmetric range shows them white
        title += "\n(every value exactly 0)" if np.isfinite(z).any() else ""
    return heatmap(ax, fig, xs, ys, z, xlabel, ylabel, title, cbar_label, vmin=-m, vmax=m, cmap="RdBu_r")


def _texel_tables(d):
    """The table files study_ltc_texels read (the last one or two paths of its provenance command,
    not its --out file)."""
    cmd = (d.header[0] if d.header else "").split(", mfkit=")[0] + " "
    out = re.search(r"--out (\S+)", cmd)
    found = re.findall(r"(\S+\.(?:csv|json|exr|npy|dds|ktx2))(?= )", cmd)
    return [t for t in found if not (out and t == out.group(1))][-2:]


def plot_ltc_texels(d, out_dir, made):
    # ltc_texels.csv -> ltc_texel_errors; ltc_texels_<x>.csv (one per BRDF) -> ltc_texel_errors_<x>
    stem = os.path.splitext(os.path.basename(d.path))[0]
    suffix = stem[len("ltc_texels"):] if stem.startswith("ltc_texels") else ""
    th_label, r_label = r"view zenith angle $\theta_o$ (deg)", r"roughness r ($\alpha = r^2$)"
    xs, ys = np.unique(d["theta_deg"]), np.unique(d["r"])
    ix, iy = np.searchsorted(xs, d["theta_deg"]), np.searchsorted(ys, d["r"])

    def grid(values):
        z = np.full((len(ys), len(xs)), np.nan)
        z[iy, ix] = values
        return z

    def where(z, fn):
        i = int(fn(np.where(np.isfinite(z), z, np.nan)))
        return "%.4g deg, r = %.3f" % (xs[i % len(xs)], ys[i // len(xs)])

    def axes_0_90(a):
        a.set_xlim(0, 90)  # the last texel (89.95 deg) sits on the edge, its cell is cut in half
        a.set_ylim(0, 1)
        a.set_xticks(range(0, 91, 15))

    n = len(d["ir"])
    fig, ax = new_figure(2, 2, width=6.2, height=4.8)
    # Monte Carlo noise is shown as noise: a texel whose mean |LTC - MC| is within MC_NOISE_RATIO
    # mean standard errors is drawn as "noise" (hatched), not as an error of the table (an exact
    # table, e.g. Lambert's, is all noise)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(d["mc_mean_se"] > 0, d["poly_mean_abs"] / d["mc_mean_se"], np.nan)
    noise = np.isfinite(q) & (q <= MC_NOISE_RATIO)
    z = grid(np.where(noise, np.nan, d["poly_mean_rel"]))
    zn = grid(np.where(noise, 1.0, np.nan))
    shown = z[np.isfinite(z)]
    heatmap(ax[0][0], fig, xs, ys, z, th_label, r_label,
            "polygon shading: mean |LTC - MC| / max(MC, 0.01 albedo)\n%s\nhatched: within Monte Carlo noise (%d of %d texels)"
            % ("mean %.3g, worst %.3g at %s" % (np.nanmean(z), np.nanmax(z), where(z, np.nanargmax)) if shown.size
               else "every texel within Monte Carlo noise", int(noise.sum()), n),
            "mean relative error over the polygons (log)", log_colour=True, vmin=LTC_TEXEL_FLOOR)
    if noise.any():
        ax[0][0].pcolor(edges(xs), edges(ys), np.ma.masked_invalid(zn), hatch="///", alpha=0.0, shading="flat")
    z = grid(q)
    heatmap(ax[0][1], fig, xs, ys, z, th_label, r_label,
            "mean |LTC - MC| in units of the mean MC standard error, median %.2g\n(white, about 1: Monte Carlo noise; "
            "red: a real error; clipped at 1/100 and 100)" % np.nanmedian(z),
            "mean |LTC - MC| / mean s.e. (log, centred on 1)", cmap="RdBu_r",
            norm=colors.LogNorm(vmin=1e-2, vmax=1e2), masked_label="MC standard error 0 (a delta-like lobe)")
    z = grid(d["lobe_l1"])
    heatmap(ax[1][0], fig, xs, ys, z, th_label, r_label,
            "lobe: L1 distance over the sphere, relative to the albedo\nmean %.3g, worst %.3g at %s"
            % (np.nanmean(z), np.nanmax(z), where(z, np.nanargmax)),
            r"$\int |m\,D_{LTC} - f\,\cos\theta_i|\,d\omega_i$ / albedo (log)", log_colour=True,
            vmin=LTC_TEXEL_FLOOR)
    z = grid(d["albedo_rel_diff"])
    lim = max(_clip_limit(z), ALBEDO_ROUNDING)
    _diverging(ax[1][1], fig, xs, ys, z, th_label, r_label,
               "albedo: (magnitude - quadrature) / quadrature\nworst %+.3g at %s; colour clipped at +-%.2g (>= 1e-12: "
               "less is rounding)"
               % (z.flat[int(np.nanargmax(np.abs(z)))], where(np.abs(z), np.nanargmax), lim),
               "relative albedo error (signed)", limit=lim)
    for a in ax.flat:
        axes_0_90(a)
    note = ("%d texels, %d polygons each; MC = Monte Carlo; hatched: mean |LTC - MC| <= %g mean s.e. (what an exact "
            "table gives); log colour scales start at %g; any light's error <= (L1 albedo + |magnitude - albedo|) / 2"
            % (n, int(np.nanmax(d["polygons"])), MC_NOISE_RATIO, LTC_TEXEL_FLOOR))
    tables = _texel_tables(d)
    gate = gate_of(tables[0]) if tables else gates_in(d.header[0] if d.header else "")
    fig.suptitle("LTC table%s, error per texel (the first table of the command)\n%s"
                 % (" of " + suffix.lstrip("_") if suffix else "", gate), fontsize=10)
    finish(fig, d, out_dir, "ltc_texel_errors" + suffix, made, note=note)

    if not d.has("d_poly_mean_rel", "d_poly_mean_abs", "d_poly_mean_abs_se", "d_minv_00", "d_magnitude"):
        return
    # the two tables side by side on one colour scale (e.g. the reference beside mfkit's table), so a
    # reader can judge a number of one against the other
    fig, ax = new_figure(2, 1, width=6.2, height=4.8)
    za, zb = grid(d["poly_mean_rel"]), grid(d["second_poly_mean_rel"])
    both = np.concatenate([za[np.isfinite(za)], zb[np.isfinite(zb)]])
    hi = max(float(both.max()) if both.size else 1.0, LTC_TEXEL_FLOOR * 10)
    tables = _texel_tables(d)
    for a, z, k in ((ax[0][0], za, 0), (ax[0][1], zb, 1)):
        label = gate_of(tables[k]) if len(tables) == 2 else ("first table" if k == 0 else "second table")
        heatmap(a, fig, xs, ys, z, th_label, r_label,
                "%s\nmean relative polygon error: mean %.3g, worst %.3g" % (label, np.nanmean(z), np.nanmax(z)),
                "mean |LTC - MC| / max(MC, 0.01 albedo) (log, shared)",
                norm=colors.LogNorm(vmin=LTC_TEXEL_FLOOR, vmax=hi))
        axes_0_90(a)
    finish(fig, d, out_dir, "ltc_texel_side" + suffix, made,
           note="same texels, polygons and Monte Carlo values for both tables; one colour scale")
    fig, ax = new_figure(2, 2, width=6.2, height=4.8)
    z = grid(d["d_poly_mean_rel"])
    lim = _clip_limit(z)
    _diverging(ax[0][0], fig, xs, ys, z, th_label, r_label,
               "second - first: mean relative polygon error (paired)\nmean %+.3g; colour clipped at +-%.2g"
               % (np.nanmean(z), lim), "difference of mean relative errors", limit=lim)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(d["d_poly_mean_abs"] == 0, 0.0, d["d_poly_mean_abs"] / d["d_poly_mean_abs_se"])
    z = grid(t)
    _diverging(ax[0][1], fig, xs, ys, z, th_label, r_label,
               "paired t of the mean |LTC - MC| difference\n(spread over the polygons; colour clipped at +-5)",
               "difference / its standard error", limit=5.0)
    dmax = np.nanmax(np.abs(np.vstack([d[c] for c in ("d_minv_00", "d_minv_20", "d_minv_02", "d_minv_22")])), axis=0)
    z = grid(dmax)
    heatmap(ax[1][0], fig, xs, ys, z, th_label, r_label,
            "largest |second - first| of minv_00, _20, _02, _22\nmax %.3g (exact zeros drawn at 1e-17)" % np.nanmax(z),
            "|difference| of the stored M^-1 fields (log)", log_colour=True)
    z = grid(d["d_magnitude"])
    lim = _clip_limit(z)
    _diverging(ax[1][1], fig, xs, ys, z, th_label, r_label,
               "second - first: magnitude\nmax |d| %.3g; colour clipped at +-%.2g" % (np.nanmax(np.abs(z)), lim),
               "difference of the stored magnitude", limit=lim)
    for a in ax.flat:
        axes_0_90(a)
    finish(fig, d, out_dir, "ltc_texel_pair" + suffix, made,
           note="first = TABLE, second = SECOND_TABLE of the command line; same polygons and Monte Carlo values for "
                "both (paired); red: the second is larger (worse, for the errors)")


# ---- study_sh_irradiance ----------------------------------------------------------------------
SH_ENV_TITLES = {
    "overcast": "CIE overcast sky (0 below the horizon)",
    "sun_sky": "smooth sky with a soft sun lobe",
    "sun_disc": "overcast sky + solar disc (P = 20)",
    "directional": "one directional light (P = 1)",
}
SH_WINDOW_STYLES = {"none": "-", "hanning": "--", "lanczos": ":"}


def _sh_env_grid(s, col):
    xs, ys, z = grid_of(s, "phi_deg", "theta_deg", col)
    return xs, ys, z


def plot_sh_irradiance(d, out_dir, made):
    envs = list(dict.fromkeys(d["env"]))
    windows = list(dict.fromkeys(d["window"]))
    base = d.where(d["window"] == "none") if "none" in windows else d.where(d["window"] == windows[0])
    wname = "none" if "none" in windows else windows[0]
    ncols = 2 if len(envs) > 1 else 1
    nrows = (len(envs) + ncols - 1) // ncols
    fig, ax = new_figure(ncols, nrows, width=6.0, height=4.3)
    lo, hi = 1e-4, 10.0
    for k, env in enumerate(envs):
        a = ax[k // ncols][k % ncols]
        s = base.where(base["env"] == env)
        xs, ys, z = _sh_env_grid(s, "rel_err")
        _, _, zn = _sh_env_grid(s, "norm_err")
        th = s["theta_deg"]
        w = np.sin(np.radians(th))
        title = "%s: %s\n" r"max $|E_{SH} - E| / \int L\,d\omega$ = %.3g, mean %.3g (bound 3/32 = 0.094)" % (
            env, SH_ENV_TITLES.get(env, ""), np.nanmax(s["norm_err"]), np.sum(w * s["norm_err"]) / np.sum(w))
        heatmap(a, fig, xs, ys, z, r"azimuth of the normal $\phi_n$ (deg)", r"zenith angle of the normal $\theta_n$ (deg)",
                title, r"relative error $|E_{SH} - E| / E$ (log; clipped to [1e-4, 10])", log_colour=True,
                vmin=lo, vmax=hi, cmap="magma")
        if np.isnan(z).any():
            a.text(0.99, 0.02, "grey: E = 0 (no light reaches the normal)", transform=a.transAxes, ha="right",
                   va="bottom", fontsize=7, color="k", bbox=dict(fc="w", ec="none", alpha=0.7))
        lt, lp = s["light_theta_deg"][0], s["light_phi_deg"][0]
        if np.isfinite(lt) and np.isfinite(lp):
            a.plot([lp], [lt], marker="*", ms=11, mfc="cyan", mec="k", ls="none")
            a.annotate("light", (lp, lt), textcoords="offset points", xytext=(7, -3), fontsize=8, color="cyan")
        a.set_xlim(0, 360)
        a.set_ylim(180, 0)  # zenith at the top, as in a latitude-longitude map
        a.set_xticks(range(0, 361, 60))
        a.set_yticks(range(0, 181, 30))
    for k in range(len(envs), nrows * ncols):
        ax[k // ncols][k % ncols].axis("off")
    fig.suptitle("Order-2 SH irradiance (9 coefficients, window: %s) vs quadrature, over the sphere of normals" % wname,
                 fontsize=11)
    finish(fig, d, out_dir, "sh_irradiance_error", made,
           note="E = integral L max(0, n.w) dw by quadrature; star: direction of the sun (or sun lobe); dark thin "
                "curves: E_SH crosses E (the error changes sign)")

    # summary: the worst error over the azimuths per zenith angle, every window; and the fraction of the
    # sphere of normals above a relative error
    fig, ax = new_figure(2, 1, width=6.2, height=4.6)
    a0, a1 = ax[0]
    for k, env in enumerate(envs):
        for win in windows:
            s = d.where((d["env"] == env) & (d["window"] == win))
            ths = np.unique(s["theta_deg"])
            worst = np.array([np.nanmax(s["norm_err"][s["theta_deg"] == t]) for t in ths])
            a0.semilogy(ths, np.maximum(worst, ERR_FLOOR), SH_WINDOW_STYLES.get(win, "-."), color="C%d" % k,
                        label="%s, %s" % (env, win) if win == wname or len(windows) == 1 else None)
        s = base.where(base["env"] == env)
        rel = s["rel_err"]
        w = np.sin(np.radians(s["theta_deg"]))
        ok = np.isfinite(rel)
        o = np.argsort(rel[ok])
        r_sorted, w_sorted = rel[ok][o], w[ok][o]
        frac = 1.0 - (np.cumsum(w_sorted) - w_sorted) / np.sum(w_sorted)  # share with an error >= this one
        median = r_sorted[min(np.searchsorted(np.cumsum(w_sorted), 0.5 * np.sum(w_sorted)), len(r_sorted) - 1)]
        a1.loglog(np.maximum(r_sorted, ERR_FLOOR), frac, color="C%d" % k, label="%s (median %.2g)" % (env, median))
    a0.axhline(3.0 / 32.0, color="k", lw=1.0, label="3/32: bound for any L >= 0, no window")
    for win in windows:
        a0.plot([], [], SH_WINDOW_STYLES.get(win, "-."), color="0.4", label="window: %s" % win)
    a0.set_xlabel(r"zenith angle of the normal $\theta_n$ (deg)")
    a0.set_ylabel(r"max over $\phi_n$ of $|E_{SH} - E|$ / $\int L\,d\omega$")
    a0.set_title("worst error per zenith angle of the normal\n(colour: environment; line style: SH window of width 3)",
                 fontsize=10)
    a0.set_xlim(0, 180)
    a0.set_ylim(1e-8, 1.0)  # room for the legend below the curves
    a0.set_xticks(range(0, 181, 30))
    a0.grid(True, which="major", alpha=0.3)
    a0.legend(fontsize=7, loc="lower right", ncol=2)
    a1.set_xlabel(r"relative error $|E_{SH} - E| / E$")
    a1.set_ylabel("fraction of the normals with E > 0 (by solid angle)\nwhose relative error is at least x")
    a1.set_title("distribution of the relative error over the lit normals\n(window: %s)" % wname, fontsize=10)
    a1.axvline(0.01, color="0.5", lw=0.8, ls=":")
    a1.grid(True, which="major", alpha=0.3)
    a1.legend(fontsize=8)
    finish(fig, d, out_dir, "sh_irradiance_curves", made,
           note="left: error relative to the total incident flux integral L dw; right: pointwise relative error, "
                "unbounded where E -> 0 (the terminator of a light, downward normals under a sky)")


# ---- study_half -------------------------------------------------------------------------------
HALF_REL = 2.0 ** -11  # round to nearest in half's normal range: relative error <= 2^-11
HALF_MIN_NORMAL = 2.0 ** -14


def plot_half(d, out_dir, made):
    tables = list(dict.fromkeys(d["table"]))
    sh = d.where(d["kind"] == "shading")
    ltc = [t for t in tables if np.any(sh["table"] == t)]
    if ltc:
        fig, ax = new_figure(len(ltc), 1, width=7.2, height=5.0)
        for k, t in enumerate(ltc):
            s = sh.where(sh["table"] == t)
            xs, ys, z = grid_of(s, "theta_o_deg", "p0", "shade_rel_worst")
            i = int(np.nanargmax(s["shade_rel_worst"]))
            heatmap(ax[0][k], fig, xs, ys, z, r"view zenith angle $\theta_o$ (deg)", r"roughness r ($\alpha = r^2$)",
                    "%s\nhalf-float export, change of LTC polygon shading: "
                    "worst %.3g at %.2f deg, r = %.3f; mean over the texels %.3g" % (
                        gate_of(t), s["shade_rel_worst"][i], s["theta_o_deg"][i], s["p0"][i],
                        np.nanmean(s["shade_rel_worst"])),
                    r"worst $|m_h\,E(M_h, P) - m\,E(M, P)|\ /\ m$ over the polygons P", log_colour=True, vmin=1e-7,
                    masked_label="not shaded (singular matrix or magnitude <= 0)")
            ax[0][k].set_xlim(0, 90)
            ax[0][k].set_xticks(range(0, 91, 15))
        finish(fig, d, out_dir, "half_shading_error", made,
               note="m = magnitude (the albedo), M = LTC rebuilt from minv_*, _h: from their halves "
                    "(mf_half_from_double); P: random polygons of mf_ltc_gate_random_polygons; log colour from 1e-7")

    v = d.where(d["kind"] == "value")
    fig, ax = new_figure(2, len(tables), width=6.4, height=4.6)
    for k, t in enumerate(tables):
        s = v.where(v["table"] == t)
        fields = list(dict.fromkeys(s["field"]))
        a0, a1 = ax[k]
        for j, fld in enumerate(fields):
            r = s["rel_err"][s["field"] == fld]
            r = r[np.isfinite(r)]
            if not r.size:
                a0.text(j, 2e-8, "all 0", ha="center", fontsize=7, rotation=90)
                continue
            a0.plot([j - 0.18], [max(np.max(r), ERR_FLOOR)], "v", color="C3", label="max" if j == 0 else None)
            a0.plot([j], [max(np.percentile(r, 99), ERR_FLOOR)], "s", color="C1", ms=5,
                    label="99th percentile" if j == 0 else None)
            a0.plot([j + 0.18], [max(np.median(r), ERR_FLOOR)], "o", color="C0", ms=5,
                    label="median" if j == 0 else None)
        a0.set_yscale("log")
        a0.set_ylim(1e-8, 2.0)
        a0.axhline(HALF_REL, color="0.3", lw=0.8, ls="--")
        a0.text(0.99, HALF_REL * 2.0, "$2^{-11}$: bound in half's normal range", fontsize=7, color="0.3",
                ha="right", transform=a0.get_yaxis_transform())
        a0.set_xticks(range(len(fields)))
        a0.set_xticklabels(fields, rotation=30, ha="right", rotation_mode="anchor", fontsize=8)
        a0.set_xlabel("field")
        a0.set_ylabel("relative rounding error |half(x) - x| / |x|")
        a0.set_title("%s: per field (x != 0)" % os.path.basename(t), fontsize=10)
        a0.grid(True, axis="y", alpha=0.3)
        a0.legend(fontsize=7, loc="lower left")
        for j, fld in enumerate(fields):
            m = (s["field"] == fld) & np.isfinite(s["rel_err"])
            a1.loglog(np.abs(s["value"][m]), np.maximum(s["rel_err"][m], 1e-8), ".", ms=2, color="C%d" % (j % 10),
                      label=fld, rasterized=True)  # thousands of points: a bitmap inside the PDF
        pos = np.abs(s["value"][np.isfinite(s["rel_err"])])
        xx = np.logspace(np.log10(max(np.min(pos), 1e-300)) if pos.size else -11, 1, 400)
        a1.loglog(xx, np.minimum(np.where(xx >= HALF_MIN_NORMAL, HALF_REL, 2.0 ** -25 / xx), 1.0), color="k", lw=0.8,
                  label="bound: $2^{-11}$, $2^{-25}/|x|$ (subnormal), 1 (flushed)")
        a1.axvline(HALF_MIN_NORMAL, color="0.5", lw=0.8, ls=":")
        a1.set_ylim(1e-8, 2.0)
        a1.set_xlabel("|x| (stored value)")
        a1.set_ylabel("relative rounding error (exact 0 drawn at 1e-8)")
        a1.set_title("error against magnitude (dotted: $2^{-14}$, smallest normal half)", fontsize=10)
        a1.grid(True, which="major", alpha=0.3)
        a1.legend(fontsize=6, markerscale=4, loc="lower left", ncol=2)
    finish(fig, d, out_dir, "half_rounding_error", made,
           note="half(x) = mf_half_to_double(mf_half_from_double(x)), round to nearest even, as the --half writers")


# ---- dispatch -------------------------------------------------------------------------------
KINDS = (
    (("part", "nu", "rel_err_g1", "rel_err_lambda"), plot_smith),
    (("source", "brdf", "fresnel", "theta_deg", "alpha", "albedo"), plot_furnace),
    (("alpha", "dh", "rel_err_approx", "rel_err_fit", "rel_err_rect"), plot_proxy),
    (("layout", "N", "lambda", "rel_err"), plot_leadr),
    (("env", "window", "theta_deg", "phi_deg", "e_exact", "e_sh", "norm_err"), plot_sh_irradiance),
    (("table", "kind", "field", "half", "rel_err", "shade_rel_worst"), plot_half),
    (("table", "view", "r", "cos_theta", "rel_error"), plot_bench_ltc),
    (("ir", "iu", "theta_deg", "poly_mean_rel", "lobe_l1", "albedo_rel_diff"), plot_ltc_texels),
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


def plot_prefilter_eval(d, out_dir, made):
    """mfkit prefilter-eval's summary: mean squared shading error of the prefiltered lobes and the
    baselines against the Monte Carlo truth, per MIP level (the thesis' error against distance) and per
    light size (its error against light size), each averaged over the tabulated view elevations.  Naive
    and Toksvig solid: exact integrals; dashed (columns mse_naive_ltc, mse_toksvig_ltc, when present):
    as a renderer shades them, with the isotropic LTC."""
    methods = [("mfkit", "mfkit lobes", "C3"), ("naive", "naive (mean normal)", "C0"),
               ("toksvig", "Toksvig", "C1"), ("leadr", "LEADR", "C2")]
    if d.has("mse_mfkit_two_lobes"):  # prefilter_eval_data.sh: the two-lobe table (--lobes 2)
        methods.insert(1, ("mfkit_two_lobes", "mfkit, two lobes", "C4"))
    # naive and Toksvig as a renderer shades them (the isotropic LTC at the mean normal), dashed
    extra = [(k, lab, c) for k, lab, c in (("naive_ltc", "naive, LTC-shaded", "C0"), ("toksvig_ltc", "Toksvig, LTC-shaded",
                                                                                      "C1")) if d.has("mse_" + k)]
    methods = methods + extra
    style = {k: "o--" for k, _, _ in extra}
    levels = np.unique(d["level"])
    lights = np.unique(d["light_half_side"])
    fig, axes = new_figure(2, 1, width=5.6)
    ax = axes[0][0]
    mid = lights[len(lights) // 2]
    for key, label, colour in methods:
        ys = [np.mean(d["mse_" + key][(d["level"] == k) & (d["light_half_side"] == mid)]) for k in levels]
        ax.plot(levels, np.maximum(ys, 1e-12), style.get(key, "o-"), color=colour, label=label)
    ax.set_yscale("log")
    ax.set_xlabel("MIP level (footprint 2^k x 2^k texels)")
    ax.set_ylabel("MSE vs Monte Carlo truth (mean over elevations)")
    ax.set_title("error against level, light half side %.3g" % mid)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax = axes[0][1]
    for key, label, colour in methods:
        ys = [np.mean(d["mse_" + key][d["light_half_side"] == h]) for h in lights]
        ax.plot(lights, np.maximum(ys, 1e-12), style.get(key, "o-"), color=colour, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("light half side (square at distance 1)")
    ax.set_ylabel("MSE (mean over levels and elevations)")
    ax.set_title("error against light size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    finish(fig, d, out_dir, "prefilter_eval", made,
           note="values 0 (a baseline exact on one-normal footprints) drawn at 1e-12")


KINDS = KINDS + ((("level", "light_half_side", "i_theta", "mse_mfkit", "mse_naive", "mse_toksvig", "mse_leadr"),
                  plot_prefilter_eval),)


def plot_prefilter_scenes(d, out_dir, made):
    """analysis/render_prefilter_scenes: mean squared error of each method's image against the
    supersampled ground truth as a function of camera distance, for the near-normal and the grazing
    scene (the thesis' error-against-distance graphs, Nahmias 2022, Fig. 4.6 and 4.10).  Solid: against
    the per-texel LTC truth (the thesis'); dashed: against the exact GGX by Monte Carlo."""
    methods = [("mfkit", "mfkit lobes", "C3"), ("mfkit_taps", "mfkit lobes, split lookup", "C4"),
               ("naive", "naive (MIP normal)", "C0"), ("toksvig", "Toksvig", "C1"), ("leadr", "LEADR", "C2")]
    methods = [m for m in methods if np.any(d["method"] == m[0])]
    scenes = [s for s in ("normal", "grazing") if np.any(d["scene"] == s)]
    fig, axes = new_figure(len(scenes), 1, width=5.2)
    for i, sc in enumerate(scenes):
        ax = axes[0][i]
        for key, label, colour in methods:
            sel = (d["scene"] == sc) & (d["method"] == key)
            order = np.argsort(d["distance"][sel])
            x = d["distance"][sel][order]
            ax.plot(x, np.maximum(d["mse"][sel][order], 1e-12), "o-", color=colour, label=label)
            if np.all(np.isfinite(d["mse_mc"][sel])):
                ax.plot(x, np.maximum(d["mse_mc"][sel][order], 1e-12), "--", color=colour, alpha=0.6)
        sel = (d["scene"] == sc) & (d["method"] == "mfkit")
        order = np.argsort(d["distance"][sel])
        for x, lod in zip(d["distance"][sel][order], d["mean_lod"][sel][order]):
            ax.annotate("lod %.1f" % lod, (x, 1.0), xycoords=("data", "axes fraction"), fontsize=6,
                        ha="center", va="top", color="0.4")
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_xlabel("camera distance (plane units; lod = mean level of detail)")
        ax.set_ylabel("image MSE vs ground truth")
        ax.set_title("%s view" % ("near-normal (scene 1)" if sc == "normal" else "grazing (scene 2)"))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
    finish(fig, d, out_dir, "prefilter_scenes", made,
           note="solid: vs per-texel LTC truth; dashed: vs Monte Carlo GGX truth")


KINDS = KINDS + ((("scene", "distance", "mean_lod", "method", "mse", "mse_mc"), plot_prefilter_scenes),)


def plot_prefilter_scenes_ssim(d, out_dir, made):
    """analysis/prefilter_scenes_ssim.py: SSIM (Wang et al. 2004) of each method's display image against
    the ground truth's over the plane, per camera distance, for both scenes (the thesis' pooled perceptual
    metric, there FLIP, Nahmias 2022, Fig. 4.6 and 4.10)."""
    methods = [("mfkit", "mfkit lobes", "C3"), ("mfkit_taps", "mfkit lobes, split lookup", "C4"),
               ("naive", "naive (MIP normal)", "C0"), ("toksvig", "Toksvig", "C1"), ("leadr", "LEADR", "C2"),
               ("truth_mc", "Monte Carlo truth", "0.5")]
    scenes = [s for s in ("normal", "grazing") if np.any(d["scene"] == s)]
    fig, axes = new_figure(len(scenes), 1, width=5.2)
    for i, sc in enumerate(scenes):
        ax = axes[0][i]
        for key, label, colour in methods:
            sel = (d["scene"] == sc) & (d["method"] == key)
            if not np.any(sel):
                continue
            order = np.argsort(d["distance"][sel])
            ax.plot(d["distance"][sel][order], d["ssim"][sel][order], marker="o", color=colour, label=label,
                    ls="--" if key == "truth_mc" else "-")
        ax.set_xscale("log", base=2)
        ax.set_ylim(min(0.0, float(np.nanmin(d["ssim"]))), 1.02)
        ax.set_xlabel("camera distance (plane units)")
        ax.set_ylabel("SSIM vs ground truth over the plane (1 = identical)")
        ax.set_title("%s view" % ("near-normal (scene 1)" if sc == "normal" else "grazing (scene 2)"))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
    finish(fig, d, out_dir, "prefilter_scenes_ssim", made,
           note="display images (radiance / the truth's peak, gamma 1/2.2); Gaussian window 11, sigma 1.5")


KINDS = KINDS + ((("scene", "distance", "method", "ssim", "ssim_image"), plot_prefilter_scenes_ssim),)


def plot_prefilter_scenes_lights(d, out_dir, made):
    """analysis/prefilter_scenes_lights.sh: the scene renders' error against the size of the quad light
    (the thesis' error-against-light-size graphs, Nahmias 2022, Ch. 4.1.3), near-normal and grazing scene.
    Left of each pair: image MSE against the per-texel LTC truth, averaged over the camera distances
    whose mean level of detail is at least 1 (the prefiltered levels; nearer, every method shades level
    0 alike); right: the relative RMS error there (MSE grows with the light's power, the relative error
    does not)."""
    methods = [("mfkit", "mfkit lobes", "C3"), ("mfkit_taps", "mfkit lobes, split lookup", "C4"),
               ("naive", "naive (MIP normal)", "C0"), ("toksvig", "Toksvig", "C1"), ("leadr", "LEADR", "C2")]
    methods = [m for m in methods if np.any(d["method"] == m[0])]
    scenes = [s for s in ("normal", "grazing") if np.any(d["scene"] == s)]
    lights = np.unique(d["light_half_side"])
    fig, axes = new_figure(2, len(scenes), width=5.0, height=4.0)
    for i, sc in enumerate(scenes):
        far = (d["scene"] == sc) & (d["mean_lod"] >= 1.0)
        nd = len(np.unique(d["distance"][far]))
        for j, (col, ylabel) in enumerate((("mse", "image MSE vs per-texel LTC truth"),
                                           ("rel_rms", "relative RMS error"))):
            ax = axes[i][j]
            for key, label, colour in methods:
                ys = [np.mean(d[col][far & (d["method"] == key) & (d["light_half_side"] == h)]) for h in lights]
                ax.plot(lights, np.maximum(ys, 1e-12), "o-", color=colour, label=label)
            ax.set_xscale("log", base=2)
            ax.set_xticks(lights)
            ax.set_xticklabels(["%g" % h for h in lights])
            ax.set_yscale("log")
            ax.set_xlabel("light half side (plane units)")
            ax.set_ylabel(ylabel + " (mean over %d distances)" % nd, fontsize=8)
            ax.set_title("%s view" % ("near-normal (scene 1)" if sc == "normal" else "grazing (scene 2)"))
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
    finish(fig, d, out_dir, "prefilter_scenes_lights", made,
           note="distances with mean level of detail >= 1 only (nearer ones shade level 0 alike)")


# before prefilter_scenes' entry: this file has its columns too (and light_half_side)
KINDS = ((("light_half_side", "scene", "distance", "mean_lod", "method", "mse", "rel_rms"),
          plot_prefilter_scenes_lights),) + KINDS


def plot_random_walk(d, out_dir, made):
    """analysis/study_random_walk: one figure per NDF in the file (random_walk for GGX, random_walk_beckmann)."""
    if "ndf" not in d.cols:
        _plot_random_walk_one(d, out_dir, made, "random_walk", "GGX")
        return
    for ndf, name in (("ggx", "random_walk"), ("beckmann", "random_walk_beckmann")):
        sel = d["ndf"] == ndf
        if np.any(sel):
            _plot_random_walk_one(d.where(sel), out_dir, made, name, "GGX" if ndf == "ggx" else "Beckmann")


def _plot_random_walk_one(d, out_dir, made, name, ndf_label):
    """mfkit's energy compensation against the random walk on the Smith microsurface, one NDF.  Top left and
    middle: the dielectric compensation's transmitted fraction, Kulla and Conty's t (mf_energy_dielectric_ms_split;
    solid lines), the split closed by the walk (mf_energy_dielectric_walk_split, column t_clos; dotted) and the
    fraction of the walk's own multiple scattering that is transmitted (markers, +-2 s.e.), cosine averages over
    the view, outside (eta > 1) and inside (eta < 1); top right: the compensated transmitted albedo against the
    walk's, T_kc - T_walk (markers with error bars) and T_clos - T_walk (dotted, open markers), cosine averages;
    bottom left: the single-scattering part E_t - T1_beta (mfkit's transmission G2 against the walk's
    Beta-function G2) per view; bottom middle: the Kulla-Conty compensation's transmitted energy against the
    walk's; bottom right: the conductor's Kulla-Conty albedo with Fresnel against the walk's (gold-like
    channels)."""
    diel = d["case"] == "dielectric"
    cond = d["case"] == "conductor"
    avg = d["avg"] == 1
    etas = np.unique(d["eta"][diel])
    outside = sorted(e for e in etas if e > 1)
    fig, axes = new_figure(3, 2, width=4.6, height=3.8)
    for j, (side, title) in enumerate(((lambda e: e, "outside (eta = n_other / n_view > 1)"),
                                       (lambda e: 1.0 / e, "inside (eta < 1)"))):
        ax = axes[0][j]
        for k, e0 in enumerate(outside):
            e = side(e0)
            sel = diel & avg & np.isclose(d["eta"], e)
            order = np.argsort(d["alpha"][sel])
            al = d["alpha"][sel][order]
            colour = "C%d" % k
            ax.plot(al, d["t_split"][sel][order], "-", color=colour, label="Kulla-Conty t, eta %.3g" % e)
            if "t_clos" in d.cols:
                ax.plot(al, d["t_clos"][sel][order], ":", lw=1.6, color=colour, label="walk closure, eta %.3g" % e)
            ax.errorbar(al, d["t_walk"][sel][order], yerr=2 * d["t_walk_se"][sel][order], fmt="o", ms=3,
                        color=colour, label="walk, eta %.3g" % e)
        ax.set_xlabel("alpha")
        ax.set_ylabel("transmitted fraction of the multiple scattering")
        ax.set_title("split, " + title, fontsize=9)
        ax.set_ylim(0, 1.02)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
    ax = axes[0][2]
    for k, e0 in enumerate(outside):
        for e, style in ((e0, "o-"), (1.0 / e0, "s--")):
            sel = diel & avg & np.isclose(d["eta"], e)
            order = np.argsort(d["alpha"][sel])
            ax.errorbar(d["alpha"][sel][order], d["err_T"][sel][order], yerr=2 * d["T_walk_se"][sel][order],
                        fmt=style, ms=3, color="C%d" % k, label="eta %.3g" % e)
            if "err_T_clos" in d.cols:
                ax.plot(d["alpha"][sel][order], d["err_T_clos"][sel][order], style[0] + ":", ms=2, mfc="none",
                        color="C%d" % k)
    ax.axhline(0, color="0.5", lw=0.8)
    ax.set_xlabel("alpha")
    ax.set_ylabel("T - T_walk (cosine average); dotted: walk closure")
    ax.set_title("compensated transmission against the walk", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    ax = axes[1][0]
    alphas = np.unique(d["alpha"][diel])
    for k, a in enumerate(alphas):
        for e, style in ((outside[len(outside) // 2], "o-"), (1.0 / outside[len(outside) // 2], "s--")):
            sel = diel & ~avg & np.isclose(d["eta"], e) & np.isclose(d["alpha"], a)
            order = np.argsort(d["mu"][sel])
            ax.plot(d["mu"][sel][order], d["dT_single"][sel][order], style, ms=3, color="C%d" % k,
                    label="alpha %.2g, eta %.3g" % (a, e))
    ax.axhline(0, color="0.5", lw=0.8)
    ax.set_xlabel("mu = cos theta_o")
    ax.set_ylabel("E_t (mfkit, joint G2) - T1 (walk, Beta G2)")
    ax.set_title("single-scattering transmission", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=5, ncol=2)
    ax = axes[1][1]
    for k, e0 in enumerate(outside):
        for e, style in ((e0, "o-"), (1.0 / e0, "s--")):
            sel = diel & avg & np.isclose(d["eta"], e)
            order = np.argsort(d["alpha"][sel])
            ax.plot(d["alpha"][sel][order], d["dT_ms"][sel][order], style, ms=3, color="C%d" % k, label="eta %.3g" % e)
    ax.axhline(0, color="0.5", lw=0.8)
    ax.set_xlabel("alpha")
    ax.set_ylabel("t (1 - E) - T_ms,walk (cosine average)")
    ax.set_title("compensation's transmitted energy against the walk's", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    ax = axes[1][2]
    for k, ch in enumerate(("gold_r", "gold_g", "gold_b", "none")):
        sel = cond & avg & (d["channel"] == ch)
        if not np.any(sel):
            continue
        order = np.argsort(d["alpha"][sel])
        ax.errorbar(d["alpha"][sel][order], d["err_R"][sel][order], yerr=2 * d["R_walk_se"][sel][order], fmt="o-",
                    ms=3, color=("C3", "C2", "C0", "0.3")[k], label="F = 1" if ch == "none" else ch)
    ax.axhline(0, color="0.5", lw=0.8)
    ax.set_xlabel("alpha")
    ax.set_ylabel("R_kc - R_walk (cosine average)")
    ax.set_title("conductor: Kulla-Conty with F_avg against the walk", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=6)
    finish(fig, d, out_dir, name, made, note="%s, random walk of Heitz et al. 2016; error bars 2 s.e." % ndf_label)


KINDS = KINDS + ((("case", "channel", "alpha", "eta", "mu", "avg", "R_walk", "T_walk", "t_split", "t_walk"),
                  plot_random_walk),)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
