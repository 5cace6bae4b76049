/*
 * test_sample.c -- statistical tests of every sampler of mf_sample.h against its pdf.
 *
 * Chi-square goodness of fit, in the manner of Mitsuba 3's chi-square harness
 * (src/python/python/chi2.py, class ChiSquareTest, and mitsuba::chi2() in
 * include/mitsuba/core/math.h) and of pbrt's BSDF tests (pbrt-v3 src/tests/bsdfs.cpp
 * chi2test(); pbrt-v4 src/pbrt/bsdfs_test.cpp):
 *
 *  1. Draw N directions with PCG32 (seed from mf_test_seed(), one PCG stream per test).
 *     Every sample must be finite and unit length (|len - 1| <= 1e-12).
 *  2. Bin them on a grid of N_MU rows x N_PHI columns over (cos theta, phi).  The columns are
 *     uniform in phi.  The rows are uniform in cos theta for the sphere / hemisphere / cosine
 *     samplers and for reflected directions; for the micro-normal samplers they are uniform in
 *     the quantile q of cos theta under an isotropic NDF (closed form, see mu_of_q()), so the
 *     peak at alpha = 0.05 (1 - cos theta ~ 1e-3) is spread over all rows instead of landing
 *     in one.  The partition only decides the test's power: the chi-square test is valid for
 *     any partition fixed before sampling.
 *  3. Expected count of a cell = N * integral of the pdf over the cell (the pdfs are densities
 *     per steradian and d omega = d(cos theta) d phi), by an adaptive product Gauss-Legendre
 *     rule (mf_quad_gauss_legendre, 4 points per sub-interval; see cell_integral() for the
 *     scheme and why it is accurate to ~1e-11 per cell).
 *  4. Pool the cells whose expected count is < 5 (sorted by expected count, pooling until the
 *     pool reaches 5 -- pbrt-v3 chi2test(), the same rule as Mitsuba's chi2()), compute
 *     X^2 = sum (obs - exp)^2 / exp and the p-value Q(dof / 2, X^2 / 2), dof = cells - 1
 *     (no parameter is fitted).  Q is the regularized upper incomplete gamma function,
 *     implemented below after Numerical Recipes in C, 2nd ed., Sec. 6.2 (gser / gcf).
 *  5. Reject at p < ALPHA_TOTAL / (number of chi-square tests) (Bonferroni correction, so the
 *     whole program has a false-alarm rate <= 1% for correct samplers).  Also fail when a
 *     sample falls in a cell whose expected count is 0, or outside the pdf's domain.
 *
 * Further checks: every pdf integrates to 1 (the sum of the cell integrals), the VNDF pdf
 * equals G1(wo) max(0, wo.wm) D(wm) / wo.z, negative controls (deliberately wrong pdfs must be
 * rejected, so the test is able to fail), and extreme inputs (u at the corners of [0,1)^2,
 * alpha = 1e-4 at grazing views).
 */
#include "mf_test.h"
#include "mf_stats.h"
#include "mfkit/mf_ndf.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_sample.h"
#include "mfkit/mf_smith.h"

#include <string.h>

#define N_MU 20
#define N_PHI 40
#define N_CELLS (N_MU * N_PHI)
#define N_SAMPLES 200000
#define GL_ORDER 4
#define MIN_EXPECTED 5.0 /* pooling threshold of Mitsuba 3 / pbrt */
#define ALPHA_TOTAL 0.01
#define TWO_PI (2.0 * MF_PI)
#define DEG (MF_PI / 180.0)
#define U_MAX 0x1.fffffffffffffp-1 /* largest double < 1 */

static double gl_x[GL_ORDER], gl_w[GL_ORDER];

/* ---- the distributions under test ------------------------------------------------------------ */
typedef enum { K_SPHERE, K_HEMI, K_COSINE, K_NDF, K_VNDF, K_VNDF_REFLECTED, K_COSINE_POLAR } kind;

/* A sampler or a pdf: kind, NDF (K_NDF: its type and alphas; K_VNDF*: GGX alphas), view. */
typedef struct dist {
    kind k;
    mf_ndf ndf;
    mf_vec3 wo;
} dist;

static dist make_simple(kind k) { dist d = {k, mf_ndf_make(MF_NDF_GGX, 1.0, 1.0), {0.0, 0.0, 1.0}}; return d; }
static dist make_ndf(mf_ndf_type t, double ax, double ay)
{
    dist d = {K_NDF, mf_ndf_make(t, ax, ay), {0.0, 0.0, 1.0}};
    return d;
}
static dist make_vndf(kind k, double ax, double ay, double theta_o, double phi_o)
{
    dist d = {k, mf_ndf_make(MF_NDF_GGX, ax, ay), mf_vec3_spherical(theta_o, phi_o)};
    return d;
}

static mf_vec3 dist_sample(const dist *d, const double u[2])
{
    switch (d->k) {
    case K_SPHERE: return mf_sample_uniform_sphere(u);
    case K_HEMI: return mf_sample_uniform_hemisphere(u);
    case K_COSINE: return mf_sample_cosine_hemisphere(u);
    case K_COSINE_POLAR: return mf_sample_cosine_hemisphere_polar(u);
    case K_NDF: return mf_sample_ndf_normal(d->ndf, u);
    case K_VNDF: return mf_sample_ggx_vndf(d->ndf.alpha_x, d->ndf.alpha_y, d->wo, u);
    case K_VNDF_REFLECTED:
        return mf_vec3_reflect(d->wo, mf_sample_ggx_vndf(d->ndf.alpha_x, d->ndf.alpha_y, d->wo, u));
    }
    return mf_vec3_make(NAN, NAN, NAN);
}

/* Density per steradian of the sampled direction. */
static double dist_pdf(const dist *d, mf_vec3 w)
{
    switch (d->k) {
    case K_SPHERE: return mf_pdf_uniform_sphere();
    case K_HEMI: return mf_pdf_uniform_hemisphere(w);
    case K_COSINE:
    case K_COSINE_POLAR: return mf_pdf_cosine_hemisphere(w);
    case K_NDF: return mf_pdf_ndf_normal(d->ndf, w);
    case K_VNDF: return mf_pdf_ggx_vndf(d->ndf.alpha_x, d->ndf.alpha_y, d->wo, w);
    case K_VNDF_REFLECTED: {
        /* wi = reflect(wo, wm)  <=>  wm = (wo + wi) / |wo + wi|; Jacobian 1 / (4 wo.wm). */
        mf_vec3 h = mf_vec3_add(d->wo, w);
        double len = mf_vec3_length(h);
        if (!(len > 0.0))
            return 0.0;
        mf_vec3 wm = mf_vec3_scale(h, 1.0 / len);
        double p = mf_pdf_ggx_vndf(d->ndf.alpha_x, d->ndf.alpha_y, d->wo, wm);
        return p > 0.0 ? mf_pdf_reflected(p, d->wo, wm) : 0.0;
    }
    }
    return NAN;
}

/* Lowest cos theta of the pdf's support.  Reflected VNDF: wi.z = 2 (wo.wm) wm.z - wo.z >= -wo.z,
 * and the pdf jumps to 0 at wi.z = -wo.z (wm at the horizon): that line is a grid edge. */
static double dist_mu_lo(const dist *d)
{
    switch (d->k) {
    case K_SPHERE: return -1.0;
    case K_VNDF_REFLECTED: return -d->wo.z;
    default: return 0.0;
    }
}

/* Rows of the grid.  For the micro-normal samplers the rows are uniform in q, the quantile of
 * cos theta under the isotropic NDF of roughness alpha = max(alpha_x, alpha_y) (GGX for the
 * VNDF): with r the stretched slope radius (tan theta = alpha r), the radial CDFs are
 * GGX r^2 / (1 + r^2) and Beckmann 1 - exp(-r^2) (the slope-space forms of Walter 2007,
 * Eq. 28 and 35).  So the peak at alpha = 0.05 (1 - cos theta ~ 1e-3) is spread over all rows.
 * For the other samplers the rows are uniform in cos theta.  Any partition fixed before
 * sampling is valid for the chi-square test; these ones only give it power. */
static int rows_in_q(const dist *d) { return d->k == K_NDF || d->k == K_VNDF; }
static mf_ndf_type q_type(const dist *d) { return d->k == K_NDF ? d->ndf.type : MF_NDF_GGX; }
/* GGX: the geometric mean of the alphas.  Beckmann: the larger alpha, because with
 * alpha_q^2 (cos^2 phi / ax^2 + sin^2 phi / ay^2) = k the density in q is ~ (1 - q)^(k - 1),
 * which must not blow up at q -> 1 (k >= 1); for GGX it is 1 / (1 - q + k q)^2, bounded. */
static double q_alpha(const dist *d)
{
    if (q_type(d) == MF_NDF_BECKMANN)
        return fmax(d->ndf.alpha_x, d->ndf.alpha_y);
    return sqrt(d->ndf.alpha_x * d->ndf.alpha_y);
}

/* cos theta at quantile q in [0, 1), and |d cos theta / d q| if jac != NULL. */
static double mu_of_q(mf_ndf_type t, double alpha, double q, double *jac)
{
    if (q >= 1.0) {
        if (jac)
            *jac = 0.0;
        return 0.0;
    }
    double a2 = alpha * alpha, tan2, dtan2;
    if (t == MF_NDF_GGX) {
        tan2 = a2 * q / (1.0 - q);
        dtan2 = a2 / ((1.0 - q) * (1.0 - q));
    } else {
        tan2 = -a2 * log1p(-q);
        dtan2 = a2 / (1.0 - q);
    }
    double mu = 1.0 / sqrt(1.0 + tan2);
    if (jac)
        *jac = 0.5 * mu * mu * mu * dtan2; /* d/dt (1 + t)^(-1/2) = -(1 + t)^(-3/2) / 2 */
    return mu;
}

/* Quantile q of a direction (1 at and below the horizon). */
static double q_of_dir(mf_ndf_type t, double alpha, mf_vec3 w)
{
    if (!(w.z > 0.0))
        return 1.0;
    double r2 = (w.x * w.x + w.y * w.y) / (w.z * w.z) / (alpha * alpha);
    return t == MF_NDF_GGX ? 1.0 / (1.0 + 1.0 / r2) : -expm1(-r2);
}

/* Row of a direction; -1 if it is outside the pdf's domain (cos theta < its lower end). */
static int row_of_dir(const dist *d, mf_vec3 w)
{
    double lo = dist_mu_lo(d);
    if (!(w.z >= lo))
        return -1;
    double v = rows_in_q(d) ? q_of_dir(q_type(d), q_alpha(d), w) : (w.z - lo) / (1.0 - lo);
    int i = (int)(v * N_MU);
    return i < 0 ? 0 : (i >= N_MU ? N_MU - 1 : i);
}

/* Integration variable of a row: q for K_NDF (the density in q of an isotropic NDF is constant,
 * so even Beckmann's super-exponential tail in the last row [0, cos theta(0.95)] is a smooth
 * integrand), cos theta otherwise (for the VNDF, its factor wo.wm / cos theta relative to the
 * NDF would make the density in q blow up like (1 - q)^(-1/2) at the horizon). */
static int integrates_in_q(const dist *d) { return d->k == K_NDF; }

static void row_range(const dist *d, int i, double *a, double *b)
{
    if (integrates_in_q(d)) {
        *a = (double)i / N_MU;
        *b = (double)(i + 1) / N_MU;
    } else if (rows_in_q(d)) {
        *a = mu_of_q(q_type(d), q_alpha(d), (double)(i + 1) / N_MU, NULL);
        *b = mu_of_q(q_type(d), q_alpha(d), (double)i / N_MU, NULL);
    } else {
        double lo = dist_mu_lo(d);
        *a = lo + (1.0 - lo) * i / N_MU;
        *b = (i == N_MU - 1) ? 1.0 : lo + (1.0 - lo) * (i + 1) / N_MU;
    }
}

static mf_vec3 dir_from(double mu, double phi)
{
    double s = sqrt(fmax(0.0, 1.0 - mu * mu));
    return mf_vec3_make(s * cos(phi), s * sin(phi), mu);
}

/* The part of the cell's phi range [pa, pb] where the pdf is (possibly) non-zero, for one
 * cos theta = mu; up to 3 pieces.  For the VNDF, wo.wm = sin(t) sin(to) cos(phi - phi_o) +
 * mu cos(to) > 0 is the arc |phi - phi_o| < acos(-mu cos(to) / (sin(t) sin(to))): integrating
 * only over it removes the kink of max(0, wo.wm) from the integrand. */
static int phi_pieces(const dist *d, double mu, double pa, double pb, double lo[3], double hi[3])
{
    if (d->k != K_VNDF) {
        lo[0] = pa;
        hi[0] = pb;
        return 1;
    }
    double st = sqrt(fmax(0.0, 1.0 - mu * mu));
    double sto = sqrt(d->wo.x * d->wo.x + d->wo.y * d->wo.y);
    double A = st * sto, B = mu * d->wo.z;
    double half;
    if (A <= 0.0)
        half = (B > 0.0) ? MF_PI : -1.0;
    else {
        double c = -B / A;
        half = (c <= -1.0) ? MF_PI : (c >= 1.0 ? -1.0 : acos(c));
    }
    if (half < 0.0)
        return 0;
    if (half >= MF_PI) {
        lo[0] = pa;
        hi[0] = pb;
        return 1;
    }
    double phio = atan2(d->wo.y, d->wo.x);
    int n = 0;
    for (int k = -1; k <= 2; ++k) {
        double l = fmax(pa, phio - half + k * TWO_PI), h = fmin(pb, phio + half + k * TWO_PI);
        if (l < h && n < 3) {
            lo[n] = l;
            hi[n] = h;
            ++n;
        }
    }
    return n;
}

/* Cell integration: an adaptive product Gauss-Legendre rule.
 *  inner (phi, for one cos theta): GL_ORDER points on m equal sub-intervals of each piece of
 *    phi_pieces(), m doubled from 2 until two estimates agree to 1e-13 + 1e-10 relative
 *    (at most INNER_M_MAX);
 *  outer (cos theta, or q for K_NDF): the row is cut at the break points of outer_breaks(),
 *    each piece into 4 equal intervals, and each interval bisected recursively while
 *    |left + right - whole| > tol (tol halved per level, 1e-11 for the whole cell), at most
 *    OUTER_DEPTH_MAX levels.
 * Why this is accurate enough.  Every kink or jump of the pdfs lies on a grid line (horizon,
 * wi.z = -wo.z), on a piece end (the VNDF's wo.wm = 0) or on an outer break point, so the rule
 * only sees integrands that are analytic on each sub-interval, where the 4-point rule's error
 * falls like h^8 and |left + right - whole| (the error of the coarser estimate) bounds that of
 * the finer one that is returned.  The summed estimates (quad err, printed) are ~1e-10 per test,
 * far below what matters: a relative error e of the expected counts inflates X^2 by about
 * N e^2 ~ 0 (e ~ 1e-8 here), and the normalization check below tolerates 1e-6.  The one point
 * singularity left is that of the reflected-direction pdf at wi = -wo (a corner of the domain,
 * where wm = (wo + wi) / |wo + wi| is undefined and the bounded pdf has a direction-dependent
 * limit); there the inner rule hits INNER_M_MAX at a few nodes ("caps" in the output) on a
 * region of negligible mass.  A missed region (a "blind" rule) would show as a normalization
 * error: that is what the integral check guards against. */
#define INNER_M_MAX 64
#define OUTER_DEPTH_MAX 40
#define CELL_TOL 1e-11
#define OUTER_TOL_FLOOR 1e-18

typedef struct cellctx {
    const dist *d;
    int in_q;
    double pa, pb;
    double err;
    int capped;
} cellctx;

static double inner_rule(const dist *d, double mu, const double *lo, const double *hi, int np, int m)
{
    double s = 0.0;
    for (int p = 0; p < np; ++p) {
        double h = (hi[p] - lo[p]) / m;
        for (int j = 0; j < m; ++j)
            for (int b = 0; b < GL_ORDER; ++b)
                s += 0.5 * h * gl_w[b] * dist_pdf(d, dir_from(mu, lo[p] + h * (j + 0.5 * (1.0 + gl_x[b]))));
    }
    return s;
}

static double inner_integral(cellctx *c, double mu)
{
    double lo[3], hi[3];
    int np = phi_pieces(c->d, mu, c->pa, c->pb, lo, hi);
    if (np == 0)
        return 0.0;
    int m = 2;
    double prev = inner_rule(c->d, mu, lo, hi, np, m);
    for (;;) {
        m *= 2;
        double cur = inner_rule(c->d, mu, lo, hi, np, m);
        double diff = fabs(cur - prev);
        if (diff <= 1e-13 + 1e-10 * fabs(cur))
            return cur;
        if (m >= INNER_M_MAX) {
            c->capped++;
            return cur;
        }
        prev = cur;
    }
}

static double outer_rule(cellctx *c, double a, double b)
{
    double s = 0.0, h = b - a;
    for (int k = 0; k < GL_ORDER; ++k) {
        double v = a + 0.5 * h * (1.0 + gl_x[k]), mu = v, jac = 1.0;
        if (c->in_q)
            mu = mu_of_q(q_type(c->d), q_alpha(c->d), v, &jac);
        s += 0.5 * h * gl_w[k] * jac * inner_integral(c, mu);
    }
    return s;
}

static double outer_adapt(cellctx *c, double a, double b, double whole, double tol, int depth)
{
    double m = 0.5 * (a + b);
    double l = outer_rule(c, a, m), r = outer_rule(c, m, b);
    double diff = fabs(l + r - whole);
    if (diff <= tol || depth >= OUTER_DEPTH_MAX) {
        if (!(diff <= tol))
            c->capped++;
        c->err += diff;
        return l + r;
    }
    /* The floor keeps the halved tolerance above what rounding can resolve in the far tails
     * (q -> 1 with masses ~1e-20); it adds at most ~1e-18 per leaf. */
    tol = fmax(0.5 * tol, OUTER_TOL_FLOOR);
    return outer_adapt(c, a, m, l, tol, depth + 1) + outer_adapt(c, m, b, r, tol, depth + 1);
}

/* Break points of the outer integrand inside (a, b): the cos theta where the VNDF's arc
 * wo.wm > 0 becomes the full circle (cos theta = sin theta_o) and where an end of the arc
 * crosses the cell's phi edges (cos(phi_e - phi_o) sin(theta) sin(theta_o) + cos(theta)
 * cos(theta_o) = 0).  Without them a thin sliver of the arc entering a cell between two
 * outer nodes would be missed entirely (seen at alpha 0.05, theta_o 85: 2e-6 of the mass). */
static int outer_breaks(const dist *d, double a, double b, double pa, double pb, double br[3])
{
    if (d->k != K_VNDF)
        return 0;
    double sto = sqrt(d->wo.x * d->wo.x + d->wo.y * d->wo.y), cto = d->wo.z;
    double phio = atan2(d->wo.y, d->wo.x), cand[3];
    int nc = 0, n = 0;
    cand[nc++] = sto;
    const double pe[2] = {pa, pb};
    for (int e = 0; e < 2; ++e) {
        double cd = cos(pe[e] - phio);
        if (cd < 0.0 && sto > 0.0)
            cand[nc++] = -cd * sto / sqrt(cd * cd * sto * sto + cto * cto);
    }
    for (int k = 0; k < nc; ++k)
        if (cand[k] > a && cand[k] < b)
            br[n++] = cand[k];
    for (int i = 1; i < n; ++i) /* sort (n <= 3) */
        for (int j = i; j > 0 && br[j] < br[j - 1]; --j) {
            double t = br[j];
            br[j] = br[j - 1];
            br[j - 1] = t;
        }
    return n;
}

static double cell_integral(const dist *d, int row, int col, double *err, int *capped)
{
    cellctx c = {d, integrates_in_q(d), TWO_PI * col / N_PHI, TWO_PI * (col + 1) / N_PHI, 0.0, 0};
    double a, b, s = 0.0, pts[5];
    row_range(d, row, &a, &b);
    pts[0] = a;
    int nb = outer_breaks(d, a, b, c.pa, c.pb, pts + 1);
    pts[nb + 1] = b;
    for (int seg = 0; seg <= nb; ++seg) {
        double sa = pts[seg], sb = pts[seg + 1];
        for (int k = 0; k < 4; ++k) {
            double a1 = sa + (sb - sa) * k / 4, b1 = (k == 3) ? sb : sa + (sb - sa) * (k + 1) / 4;
            s += outer_adapt(&c, a1, b1, outer_rule(&c, a1, b1), CELL_TOL / (4.0 * (nb + 1)), 0);
        }
    }
    *err += c.err;
    *capped += c.capped;
    return s;
}

/* ---- the chi-square test --------------------------------------------------------------------- */
typedef struct chi2_result {
    double chi2, pvalue;
    int dof, pooled_cells;
    double integral;     /* sum of the cell integrals (should be 1) */
    double quad_err;     /* summed per-cell quadrature error estimates */
    int quad_capped;     /* integrals stopped at the depth / order limit */
    long bad_samples;    /* NaN or not unit length */
    long zero_cell_hits; /* samples in cells with expected count 0, or outside the domain */
} chi2_result;

static chi2_result chi2_test(const dist *sampler, const dist *pdf, uint64_t seed, uint64_t stream)
{
    static double expected[N_CELLS];
    static long observed[N_CELLS];
    static int order[N_CELLS];
    chi2_result r;
    memset(&r, 0, sizeof r);

    /* expected counts */
    for (int i = 0; i < N_MU; ++i)
        for (int j = 0; j < N_PHI; ++j) {
            double v = cell_integral(pdf, i, j, &r.quad_err, &r.quad_capped);
            r.integral += v;
            expected[i * N_PHI + j] = v * N_SAMPLES;
        }

    /* observed counts */
    memset(observed, 0, sizeof observed);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, stream);
    for (long n = 0; n < N_SAMPLES; ++n) {
        double u[2];
        u[0] = mf_pcg32_next_double(&rng);
        u[1] = mf_pcg32_next_double(&rng);
        mf_vec3 w = dist_sample(sampler, u);
        double len = mf_vec3_length(w);
        if (!mf_vec3_isfinite(w) || !(fabs(len - 1.0) <= 1e-12)) {
            if (r.bad_samples++ < 3)
                fprintf(stderr, "  bad sample u = (%.17g, %.17g): (%.17g, %.17g, %.17g), |w| - 1 = %.3g\n", u[0],
                        u[1], w.x, w.y, w.z, len - 1.0);
            continue;
        }
        int i = row_of_dir(pdf, w);
        if (i < 0) {
            if (r.zero_cell_hits++ < 3)
                fprintf(stderr, "  sample outside the pdf's domain: u = (%.17g, %.17g): w.z = %.17g\n", u[0], u[1],
                        w.z);
            continue;
        }
        observed[i * N_PHI + chi2_phi_cell(w.y, w.x, N_PHI)]++;
    }

    /* pooling, as pbrt-v3 chi2test() (sorted by expected count; pool while < MIN_EXPECTED) */
    chi2_pooled p = chi2_pool(expected, observed, order, N_CELLS, MIN_EXPECTED);
    r.chi2 = p.chi2;
    r.dof = p.dof;
    r.pooled_cells = p.pooled_cells;
    r.zero_cell_hits += p.zero_hits;
    r.pvalue = chi2_pvalue(r.chi2, r.dof);
    return r;
}

/* ---- test cases -------------------------------------------------------------------------------- */
typedef struct test_case {
    char name[96];
    dist d;
} test_case;

#define MAX_CASES 64
static test_case cases[MAX_CASES];
static int n_cases = 0;

static void add_case(dist d, const char *fmt, double a, double b, double c)
{
    test_case *t = &cases[n_cases++];
    t->d = d;
    snprintf(t->name, sizeof t->name, fmt, a, b, c);
}

static void build_cases(void)
{
    add_case(make_simple(K_SPHERE), "uniform_sphere", 0, 0, 0);
    add_case(make_simple(K_HEMI), "uniform_hemisphere", 0, 0, 0);
    add_case(make_simple(K_COSINE), "cosine_hemisphere", 0, 0, 0);
    add_case(make_simple(K_COSINE_POLAR), "cosine_hemisphere_polar", 0, 0, 0);
    static const double alphas[4][2] = {{0.05, 0.05}, {0.3, 0.3}, {1.0, 1.0}, {0.1, 0.6}};
    for (int t = 0; t < 2; ++t)
        for (int a = 0; a < 4; ++a)
            add_case(make_ndf(t ? MF_NDF_BECKMANN : MF_NDF_GGX, alphas[a][0], alphas[a][1]),
                     t ? "ndf_normal beckmann a=(%g,%g)" : "ndf_normal ggx a=(%g,%g)", alphas[a][0], alphas[a][1], 0);
    static const double thetas[4] = {0.0, 30.0, 60.0, 85.0};
    for (int a = 0; a < 4; ++a)
        for (int t = 0; t < 4; ++t) {
            double phio = 0.7 + 1.3 * t; /* some azimuth, different per view */
            add_case(make_vndf(K_VNDF, alphas[a][0], alphas[a][1], thetas[t] * DEG, phio),
                     "ggx_vndf a=(%g,%g) theta_o=%g", alphas[a][0], alphas[a][1], thetas[t]);
        }
    /* reflected directions: the VNDF pushed through mf_pdf_reflected's Jacobian */
    add_case(make_vndf(K_VNDF_REFLECTED, 0.3, 0.3, 30.0 * DEG, 2.0), "vndf_reflected a=(%g,%g) theta_o=%g", 0.3,
             0.3, 30.0);
    add_case(make_vndf(K_VNDF_REFLECTED, 1.0, 1.0, 60.0 * DEG, -1.0), "vndf_reflected a=(%g,%g) theta_o=%g", 1.0,
             1.0, 60.0);
    add_case(make_vndf(K_VNDF_REFLECTED, 0.1, 0.6, 60.0 * DEG, 0.4), "vndf_reflected a=(%g,%g) theta_o=%g", 0.1,
             0.6, 60.0);
}

/* ---- individual checks ------------------------------------------------------------------------- */

/* Q(a, x) against closed forms: Q(1, x) = exp(-x); Q(1/2, x) = erfc(sqrt(x)); for integer n,
 * Q(n, x) = exp(-x) sum_{i<n} x^i / i! (the Poisson CDF), which exercises both the series and
 * the continued fraction up to a = 400 (dof = 800, the largest used here). */
static void test_gamma_q(void)
{
    const double xs[] = {1e-3, 0.1, 0.5, 1.0, 2.0, 5.0, 20.0};
    for (int i = 0; i < 7; ++i) {
        CHECK_REL(gamma_q(1.0, xs[i]), exp(-xs[i]), 1e-13);
        CHECK_REL(gamma_q(0.5, xs[i]), erfc(sqrt(xs[i])), 1e-12);
    }
    const int ns[] = {2, 10, 50, 200, 400};
    const double fx[] = {0.5, 0.9, 1.0, 1.1, 1.3};
    for (int i = 0; i < 5; ++i)
        for (int k = 0; k < 5; ++k) {
            int n = ns[i];
            double x = fx[k] * n, term = exp(-x), sum = term;
            for (int m = 1; m < n; ++m) {
                term *= x / m;
                sum += term;
            }
            CHECK_REL(gamma_q(n, x), sum, 1e-11);
        }
    CHECK(gamma_q(3.0, 0.0) == 1.0);
    CHECK(gamma_q(100.0, 1e4) >= 0.0 && gamma_q(100.0, 1e4) < 1e-300);
}

/* The VNDF pdf against its definition [Heitz 2018, Eq. 1 / mf_sample.h] from mf_smith_g1 and
 * mf_ndf_d, and at normal incidence against the NDF pdf D(wm) wm.z. */
static void test_vndf_pdf_formula(void)
{
    static const double alphas[4][2] = {{0.05, 0.05}, {0.3, 0.3}, {1.0, 1.0}, {0.1, 0.6}};
    static const double thetas[4] = {0.0, 30.0, 60.0, 85.0};
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_current_seed, 1000);
    for (int a = 0; a < 4; ++a)
        for (int t = 0; t < 4; ++t) {
            mf_ndf ndf = mf_ndf_make(MF_NDF_GGX, alphas[a][0], alphas[a][1]);
            mf_vec3 wo = mf_vec3_spherical(thetas[t] * DEG, 0.3 + t);
            for (int k = 0; k < 8; ++k) {
                double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
                mf_vec3 wm = mf_sample_uniform_hemisphere(u); /* includes back-facing wo.wm < 0 */
                double ref = mf_smith_g1(ndf, wo) * fmax(0.0, mf_vec3_dot(wo, wm)) * mf_ndf_d(ndf, wm) / wo.z;
                CHECK_REL(mf_pdf_ggx_vndf(ndf.alpha_x, ndf.alpha_y, wo, wm), ref, 1e-12);
                if (t == 0)
                    CHECK_REL(mf_pdf_ggx_vndf(ndf.alpha_x, ndf.alpha_y, wo, wm), mf_pdf_ndf_normal(ndf, wm), 1e-12);
            }
        }
}

static int is_unit_finite(mf_vec3 w) { return mf_vec3_isfinite(w) && fabs(mf_vec3_length(w) - 1.0) <= 1e-12; }

static void test_extreme_inputs(void)
{
    /* VNDF, alpha = 1e-4 (the documented lower end) at theta_o = 89.99 deg, 10k random u. */
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_current_seed, 2000);
    static const double ax_list[2][2] = {{1e-4, 1e-4}, {1e-4, 0.5}};
    for (int a = 0; a < 2; ++a) {
        mf_vec3 wo = mf_vec3_spherical(89.99 * DEG, 0.8);
        long bad = 0;
        for (int n = 0; n < 10000; ++n) {
            double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)};
            mf_vec3 wm = mf_sample_ggx_vndf(ax_list[a][0], ax_list[a][1], wo, u);
            if (!is_unit_finite(wm) || !(wm.z >= 0.0)) {
                if (bad++ < 3)
                    fprintf(stderr, "  vndf a=(%g,%g) theta_o=89.99 u=(%.17g, %.17g): (%.17g, %.17g, %.17g)\n",
                            ax_list[a][0], ax_list[a][1], u[0], u[1], wm.x, wm.y, wm.z);
            }
        }
        CHECK(bad == 0);
    }

    /* Corners of [0, 1)^2 for every sampler. */
    static const double corners[4][2] = {{0.0, 0.0}, {U_MAX, U_MAX}, {0.0, U_MAX}, {U_MAX, 0.0}};
    static const double ex_alphas[6][2] = {{1e-4, 1e-4}, {0.05, 0.05}, {1.0, 1.0}, {1e3, 1e3}, {0.1, 0.6}, {1e-4, 1e3}};
    static const double ex_thetas[4] = {0.0, 60.0, 89.0, 89.99};
    for (int c = 0; c < 4; ++c) {
        const double *u = corners[c];
        mf_vec3 w = mf_sample_uniform_sphere(u);
        CHECK(is_unit_finite(w));
        w = mf_sample_uniform_hemisphere(u);
        CHECK(is_unit_finite(w) && w.z >= 0.0);
        w = mf_sample_cosine_hemisphere(u);
        CHECK(is_unit_finite(w) && w.z >= 0.0);
        w = mf_sample_cosine_hemisphere_polar(u);
        CHECK(is_unit_finite(w) && w.z >= 0.0);
        CHECK(isfinite(mf_pdf_cosine_hemisphere(w)) && isfinite(mf_pdf_uniform_hemisphere(w)));
        for (int a = 0; a < 6; ++a) {
            for (int t = 0; t < 2; ++t) {
                mf_ndf ndf = mf_ndf_make(t ? MF_NDF_BECKMANN : MF_NDF_GGX, ex_alphas[a][0], ex_alphas[a][1]);
                w = mf_sample_ndf_normal(ndf, u);
                int ok = is_unit_finite(w) && w.z >= 0.0 && isfinite(mf_pdf_ndf_normal(ndf, w));
                if (!ok)
                    fprintf(stderr, "  ndf_normal %s a=(%g,%g) u=(%a, %a): (%.17g, %.17g, %.17g)\n",
                            mf_ndf_type_name(ndf.type), ndf.alpha_x, ndf.alpha_y, u[0], u[1], w.x, w.y, w.z);
                CHECK(ok);
            }
            for (int t = 0; t < 4; ++t) {
                mf_vec3 wo = mf_vec3_spherical(ex_thetas[t] * DEG, 2.5);
                w = mf_sample_ggx_vndf(ex_alphas[a][0], ex_alphas[a][1], wo, u);
                double p = mf_pdf_ggx_vndf(ex_alphas[a][0], ex_alphas[a][1], wo, w);
                int ok = is_unit_finite(w) && w.z >= 0.0 && isfinite(p);
                if (!ok)
                    fprintf(stderr, "  ggx_vndf a=(%g,%g) theta_o=%g u=(%a, %a): (%.17g, %.17g, %.17g) pdf %g\n",
                            ex_alphas[a][0], ex_alphas[a][1], ex_thetas[t], u[0], u[1], w.x, w.y, w.z, p);
                CHECK(ok);
            }
        }
    }
}

int main(void)
{
    uint64_t seed = mf_test_seed(0x5a3b1e2dULL);
    CHECK(mf_quad_gauss_legendre(GL_ORDER, gl_x, gl_w) == MF_OK);

    test_gamma_q();
    test_vndf_pdf_formula();
    test_extreme_inputs();

    build_cases();
    const double threshold = ALPHA_TOTAL / n_cases; /* Bonferroni */
    printf("chi-square: %d tests, N = %d, %d x %d cells, reject at p < %.3g (seed %#" PRIx64 ")\n", n_cases,
           N_SAMPLES, N_MU, N_PHI, threshold, seed);
    double pmin = 1.0, pmax = 0.0, worst_int = 0.0;
    for (int c = 0; c < n_cases; ++c) {
        chi2_result r = chi2_test(&cases[c].d, &cases[c].d, seed, (uint64_t)c);
        printf("  %-40s X2 %8.2f dof %3d p %.4f pooled %3d |int - 1| %.1e quad err %.1e caps %d\n", cases[c].name, r.chi2,
               r.dof, r.pvalue, r.pooled_cells, fabs(r.integral - 1.0), r.quad_err,
               r.quad_capped);
        pmin = fmin(pmin, r.pvalue);
        pmax = fmax(pmax, r.pvalue);
        worst_int = fmax(worst_int, fabs(r.integral - 1.0));
        if (!(r.pvalue >= threshold))
            MF_FAIL_AT("%s: chi-square rejects: X2 = %.3f, dof = %d, p = %.3g < %.3g", cases[c].name, r.chi2, r.dof,
                       r.pvalue, threshold);
        ++mf_test_checks;
        if (r.bad_samples || r.zero_cell_hits)
            MF_FAIL_AT("%s: %ld NaN / non-unit samples, %ld samples where the pdf integrates to 0", cases[c].name,
                       r.bad_samples, r.zero_cell_hits);
        ++mf_test_checks;
        /* Normalization.  The summed quadrature error estimate must be < 1e-7 (checked), so a
         * deviation above 1e-6 is the pdf's, not the rule's; the chi-square test alone only
         * resolves a total-mass error of order 1/sqrt(N) ~ 2e-3. */
        CHECK(r.quad_err < 1e-7);
        CHECK_ABS(r.integral, 1.0, 1e-6);
    }
    printf("chi-square p-values in [%.4f, %.4f]; max |integral - 1| = %.2e\n", pmin, pmax, worst_int);

    /* Negative controls: a wrong pdf must be rejected at the same threshold. */
    struct {
        const char *name;
        dist sampler, pdf;
    } neg[] = {
        {"ggx a=0.3 samples vs a=0.33 pdf", make_ndf(MF_NDF_GGX, 0.3, 0.3), make_ndf(MF_NDF_GGX, 0.33, 0.33)},
        {"cosine samples vs uniform hemisphere pdf", make_simple(K_COSINE), make_simple(K_HEMI)},
        {"vndf a=0.3 theta_o=60 vs ndf pdf (no visibility)", make_vndf(K_VNDF, 0.3, 0.3, 60.0 * DEG, 0.5),
         make_ndf(MF_NDF_GGX, 0.3, 0.3)},
        {"ggx a=(0.1,0.6) samples vs a=(0.6,0.1) pdf", make_ndf(MF_NDF_GGX, 0.1, 0.6), make_ndf(MF_NDF_GGX, 0.6, 0.1)},
        {"beckmann a=0.3 samples vs ggx a=0.3 pdf", make_ndf(MF_NDF_BECKMANN, 0.3, 0.3), make_ndf(MF_NDF_GGX, 0.3, 0.3)},
    };
    for (int k = 0; k < (int)(sizeof neg / sizeof neg[0]); ++k) {
        chi2_result r = chi2_test(&neg[k].sampler, &neg[k].pdf, seed, 100u + (uint64_t)k);
        printf("  negative control %-48s X2 %10.1f dof %3d p %.3g\n", neg[k].name, r.chi2, r.dof, r.pvalue);
        ++mf_test_checks;
        if (!(r.pvalue < threshold))
            MF_FAIL_AT("negative control not rejected: %s: X2 = %.3f, dof = %d, p = %.3g >= %.3g", neg[k].name, r.chi2,
                       r.dof, r.pvalue, threshold);
    }

    MF_TEST_MAIN_END();
}
