/*
 * mf_validate.c -- property checks of the core math (see mf_validate.h, docs/validation.md).
 *
 * Integrals over directions are nested adaptive Gauss-Kronrod rules (mf_quad_adaptive) in
 * polar coordinates around a chosen pole, split at the places where the integrand has a kink
 * or a narrow peak, so that each piece is smooth and the rules converge to their tolerance.
 */
#include "mfkit/mf_validate.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_filter.h"
#include "mfkit/mf_proxy.h"
#include "mfkit/mf_quad.h"

#include <float.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#define DEG (MF_PI / 180.0)

/* ---- the grid ------------------------------------------------------------------------------ */
static const double k_alphas[] = {1e-4, 1e-3, 1e-2, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0};
static const double k_ratios[] = {1.0, 0.1, 0.01}; /* alpha_y / alpha_x, alpha_y clamped >= 1e-4 */
static const double k_thetas_deg[] = {0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9, 89.99};
static const double k_phis[] = {0.0, 0.7, 0.5 * MF_PI, 4.0};
#define N_ALPHAS ((int)(sizeof k_alphas / sizeof k_alphas[0]))
#define N_RATIOS ((int)(sizeof k_ratios / sizeof k_ratios[0]))
#define N_THETAS ((int)(sizeof k_thetas_deg / sizeof k_thetas_deg[0]))
#define N_PHIS ((int)(sizeof k_phis / sizeof k_phis[0]))

static const double k_means[][2] = {{0.0, 0.0}, {0.3, 0.0}, {0.0, -0.3}, {1.0, -0.5}, {-1.5, 1.3}, {2.0, 0.0}};
/* var_x, var_y, cov_xy: Beckmann alpha = 0.1 and 1 (var = alpha^2/2), 1:10 anisotropy,
 * a correlated one (the configuration of docs/math.md, correction C-L2), alpha = 1e-4, and a 1:100 one. */
static const double k_covs[][3] = {{0.005, 0.005, 0.0}, {0.5, 0.5, 0.0}, {0.5, 0.005, 0.0},
                                   {2.0, 0.5, -0.9}, {5e-9, 5e-9, 0.0}, {0.02, 2e-6, 0.0}};
#define N_MEANS ((int)(sizeof k_means / sizeof k_means[0]))
#define N_COVS ((int)(sizeof k_covs / sizeof k_covs[0]))

static mf_ndf grid_ndf(int type, int ia, int ir)
{
    double ax = k_alphas[ia];
    double ay = fmax(1e-4, ax * k_ratios[ir]);
    return mf_ndf_make(type ? MF_NDF_BECKMANN : MF_NDF_GGX, ax, ay);
}

/* 1 if grid_ndf(.., ia, ir) duplicates an earlier ratio (alpha_y clamped to the same value). */
static int duplicate_ratio(int ia, int ir)
{
    if (ir == 0)
        return 0;
    double ay = fmax(1e-4, k_alphas[ia] * k_ratios[ir]);
    double prev = fmax(1e-4, k_alphas[ia] * k_ratios[ir - 1]);
    return ay == prev;
}

static mf_gaussian_slopes grid_gaussian(int im, int ic)
{
    mf_gaussian_slopes g = {k_means[im][0], k_means[im][1], k_covs[ic][0], k_covs[ic][1], k_covs[ic][2]};
    return g;
}

/* ---- nested adaptive integration over the slope plane ------------------------------------- */
/* Integrals over micro-normals are taken over their slopes s, with dm = m.z^3 d^2s (the Jacobian
 * of [Dupuy 2013, Eq. 10]), in polar coordinates of the affine map s = mean + L (r cos p, r sin p)
 * with L = Cholesky factor of the distribution's covariance (or diag(alpha)): in (r, p) every
 * NDF of the grid has unit scale, so the rules need no hints about alpha or anisotropy.  The
 * integrands have one kink, along the line where wo.m = 0 (a0 + a.s = 0): in (r, p) that is at
 * cos(p - p0) = c / r, and the inner rule is split there. */
typedef double (*slope_fn)(double sx, double sy, void *user);

typedef struct {
    slope_fn f;
    void *user;
    double mean[2], l[2][2]; /* lower-triangular L */
    double kink_c, kink_b, kink_p0; /* kink where r kink_b cos(p - p0) = kink_c; kink_b = 0: none */
    double r;
    int failed;
} plane_ctx;

static double plane_inner(double p, void *vctx)
{
    plane_ctx *c = vctx;
    double u = c->r * cos(p), v = c->r * sin(p);
    double sx = c->mean[0] + c->l[0][0] * u;
    double sy = c->mean[1] + c->l[1][0] * u + c->l[1][1] * v;
    return c->f(sx, sy, c->user);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Integral over [lo, hi] split at the breakpoints inside it (sorted here). */
static double integrate_pieces(mf_fn1 f, void *ctx, double lo, double hi, double *pts, int npts, double rel_tol,
                               double abs_tol, int *failed)
{
    qsort(pts, (size_t)npts, sizeof(double), cmp_double);
    double sum = 0.0, a = lo;
    for (int i = 0; i <= npts; ++i) {
        double b = (i < npts) ? pts[i] : hi;
        if (!(b > a) || b > hi)
            continue;
        mf_result r;
        if (mf_quad_adaptive(f, ctx, a, b, abs_tol, rel_tol, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            *failed = 1;
        sum += r.val;
        a = b;
    }
    return sum;
}

static double plane_outer(double r, void *vctx)
{
    plane_ctx *c = vctx;
    c->r = r;
    double pts[2];
    int n = 0;
    if (c->kink_b > 0.0) {
        double q = c->kink_c / (r * c->kink_b);
        if (q > -1.0 && q < 1.0) {
            double d = acos(q);
            pts[n++] = c->kink_p0 - d;
            pts[n++] = c->kink_p0 + d;
        }
    }
    for (int i = 0; i < n; ++i) {
        pts[i] = fmod(pts[i], 2.0 * MF_PI);
        if (pts[i] < 0.0)
            pts[i] += 2.0 * MF_PI;
    }
    /* Absolute floor: 1e-13 of the unit-mass scale 1/det(L) of the integrand, for pieces that
     * carry almost nothing (a kink located by acos near +-1 lands a few ulp inside a piece). */
    double inner = integrate_pieces(plane_inner, c, 0.0, 2.0 * MF_PI, pts, n, 1e-11,
                                    1e-13 / (c->l[0][0] * c->l[1][1]), &c->failed);
    return inner * r * c->l[0][0] * c->l[1][1]; /* d^2s = det(L) r dr dp */
}

/* Integral of f over the slope plane; the kink line is wz - wx sx - wy sy = 0 (pass w = 0 for
 * none).  Returns NaN if a rule did not converge. */
static double integrate_slopes(slope_fn f, void *user, double mean_x, double mean_y, double var_x, double var_y,
                               double cov_xy, mf_vec3 w)
{
    plane_ctx c;
    memset(&c, 0, sizeof c);
    c.f = f;
    c.user = user;
    c.mean[0] = mean_x;
    c.mean[1] = mean_y;
    /* Cholesky of [[var_x, cov], [cov, var_y]] (positive definite on the grid) */
    c.l[0][0] = sqrt(var_x);
    c.l[1][0] = cov_xy / c.l[0][0];
    c.l[1][1] = sqrt(var_y - c.l[1][0] * c.l[1][0]);
    /* wz - wx sx - wy sy = (wz - w.mean) - (L^T (wx, wy)) . (u, v) */
    c.kink_c = w.z - w.x * mean_x - w.y * mean_y;
    double bx = c.l[0][0] * w.x + c.l[1][0] * w.y, by = c.l[1][1] * w.y;
    c.kink_b = hypot(bx, by);
    c.kink_p0 = atan2(by, bx);
    /* Outer breakpoints: the scales of the distribution, and the radius r0 = c / b where the
     * kink line touches the circle (the inner integral is not smooth in r there). */
    double pts[8] = {0.25, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0, 0.0};
    int npts = 7;
    if (c.kink_b > 0.0 && c.kink_c > 0.0 && isfinite(c.kink_c / c.kink_b))
        pts[npts++] = c.kink_c / c.kink_b;
    double v = integrate_pieces(plane_outer, &c, 0.0, INFINITY, pts, npts, 1e-10, 1e-14, &c.failed);
    return c.failed ? NAN : v;
}

/* ---- check 1: NDF normalisation ------------------------------------------------------------- */
static double ndf_cos_integrand(double sx, double sy, void *user)
{
    const mf_ndf *ndf = user;
    mf_vec3 m = mf_normal_from_slope(sx, sy);
    double z3 = m.z * m.z * m.z;
    return mf_ndf_d(*ndf, m) * m.z * z3; /* D(m) m.z dm, dm = m.z^3 d^2s */
}

static void check_ndf_normalisation(mf_check *c)
{
    mf_check_begin(c, "ndf_normalisation", "|integral of D(wm) wm.z dwm - 1|, GGX and Beckmann, every alpha and ratio", 1e-8);
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < N_ALPHAS; ++ia)
            for (int ir = 0; ir < N_RATIOS; ++ir) {
                if (duplicate_ratio(ia, ir))
                    continue;
                mf_ndf ndf = grid_ndf(t, ia, ir);
                double v = integrate_slopes(ndf_cos_integrand, &ndf, 0, 0, ndf.alpha_x * ndf.alpha_x,
                                            ndf.alpha_y * ndf.alpha_y, 0, mf_vec3_make(0, 0, 0));
                char at[200];
                snprintf(at, sizeof at, "%s alpha=(%g,%g): integral=%.17g", mf_ndf_type_name(ndf.type), ndf.alpha_x,
                         ndf.alpha_y, v);
                mf_check_record(c, fabs(v - 1.0), at);
            }
    mf_check_finish(c);
}

/* ---- check 2: projected area, centred NDFs -------------------------------------------------- */
typedef struct {
    mf_ndf ndf;
    mf_vec3 wo;
    double g1;
} proj_ctx;

static double proj_integrand(double sx, double sy, void *user)
{
    const proj_ctx *p = user;
    mf_vec3 m = mf_normal_from_slope(sx, sy);
    double c = mf_vec3_dot(p->wo, m);
    return c > 0.0 ? p->g1 * c * mf_ndf_d(p->ndf, m) * m.z * m.z * m.z : 0.0;
}

static void check_projected_area(mf_check *c)
{
    mf_check_begin(c, "projected_area",
               "|integral of G1(wo) max(0,wo.wm) D(wm) dwm / wo.z - 1| (Smith), GGX and Beckmann", 1e-8);
    static const double thetas[] = {0.0, 30.0, 60.0, 85.0, 89.99};
    static const double phis[] = {0.0, 1.1};
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < N_ALPHAS; ++ia)
            for (int ir = 0; ir < N_RATIOS; ++ir) {
                if (duplicate_ratio(ia, ir))
                    continue;
                for (int it = 0; it < 5; ++it)
                    for (int ip = 0; ip < 2; ++ip) {
                        if (it == 0 && ip > 0)
                            continue;
                        proj_ctx p;
                        p.ndf = grid_ndf(t, ia, ir);
                        p.wo = mf_vec3_spherical(thetas[it] * DEG, phis[ip]);
                        p.g1 = mf_smith_g1(p.ndf, p.wo);
                        double v = integrate_slopes(proj_integrand, &p, 0, 0, p.ndf.alpha_x * p.ndf.alpha_x,
                                                    p.ndf.alpha_y * p.ndf.alpha_y, 0, p.wo);
                        char at[200];
                        snprintf(at, sizeof at, "%s alpha=(%g,%g) theta_o=%g deg phi_o=%g: ratio=%.17g",
                                 mf_ndf_type_name(p.ndf.type), p.ndf.alpha_x, p.ndf.alpha_y, thetas[it], phis[ip],
                                 v / p.wo.z);
                        mf_check_record(c, fabs(v / p.wo.z - 1.0), at);
                    }
            }
    mf_check_finish(c);
}

/* ---- check 3: LEADR normalisation identity (after Eq. 16), non-centred Gaussian ------------ */
typedef struct {
    mf_gaussian_slopes g;
    mf_vec3 wo;
    double lambda_o;
} leadr_ctx;

/* Eq. 16's integrand over wi, written over the half vector wh: dwi = 4 (wo.wh) dwh
 * [Walter 2007, Eq. 14] and dwh = wh.z^3 d^2s.  Every wi of the sphere with D(wh) > 0 is the
 * mirror of exactly one wh with wo.wh > 0 and wh.z > 0 (correction C-L5: the full sphere). */
static double leadr_integrand(double sx, double sy, void *user)
{
    const leadr_ctx *p = user;
    mf_vec3 wh = mf_normal_from_slope(sx, sy);
    double c = mf_vec3_dot(p->wo, wh);
    if (!(c > 0.0))
        return 0.0;
    double d = mf_gaussian_d(&p->g, wh);
    return d / (4.0 * (1.0 + p->lambda_o)) * 4.0 * c * wh.z * wh.z * wh.z;
}

static void check_leadr_identity(mf_check *c)
{
    mf_check_begin(c, "leadr_normalisation",
               "|(n.g)/(n.wo) integral over the sphere of D(wh)/(4(1+L(wo))) dwi - 1| [Dupuy 2013, after Eq. 16]",
               1e-8);
    static const double thetas[] = {0.0, 45.0, 80.0, 89.99};
    static const double phis[] = {0.0, 2.5};
    for (int im = 0; im < N_MEANS; ++im)
        for (int ic = 0; ic < N_COVS; ++ic)
            for (int it = 0; it < 4; ++it)
                for (int ip = 0; ip < 2; ++ip) {
                    if (it == 0 && ip > 0)
                        continue;
                    leadr_ctx p;
                    p.g = grid_gaussian(im, ic);
                    p.wo = mf_vec3_spherical(thetas[it] * DEG, phis[ip]);
                    mf_vec3 n = mf_gaussian_mesonormal(&p.g);
                    /* A view below the mesosurface is back-facing: no identity.  A view within
                     * 1e-6 of the mesosurface (n.wo ~ 0, e.g. mean slope 1 at 45 deg) makes the
                     * prefactor (n.g)/(n.wo) ill-conditioned: skipped, documented. */
                    if (mf_vec3_dot(n, p.wo) <= 1e-6)
                        continue;
                    p.lambda_o = mf_smith_lambda_gaussian(&p.g, p.wo);
                    double v = integrate_slopes(leadr_integrand, &p, p.g.mean_x, p.g.mean_y, p.g.var_x, p.g.var_y,
                                                p.g.cov_xy, p.wo);
                    double ratio = n.z / mf_vec3_dot(n, p.wo) * v;
                    char at[200];
                    snprintf(at, sizeof at, "mean=(%g,%g) cov=(%g,%g,%g) theta_o=%g deg phi_o=%g: %.17g", p.g.mean_x,
                             p.g.mean_y, p.g.var_x, p.g.var_y, p.g.cov_xy, thetas[it], phis[ip], ratio);
                    mf_check_record(c, fabs(ratio - 1.0), at);
                }
    mf_check_finish(c);
}

/* ---- check 4: closed-form Lambda against Smith's integral ---------------------------------- */
/* Unit marginal slope densities along a direction: GGX p(x) = (1 + x^2)^(-3/2) / 2 (alpha = 1);
 * Beckmann p(x) = exp(-x^2) / sqrt(pi) (alpha = 1, sigma = 1/sqrt 2); Gaussian standard normal. */
typedef struct {
    int family; /* 0 GGX, 1 Beckmann, 2 standard normal */
    double a;
} smith_ctx;

static double unit_marginal(int family, double x)
{
    if (family == 0)
        return 0.5 / ((1.0 + x * x) * sqrt(1.0 + x * x));
    if (family == 1)
        return exp(-x * x) * MF_INV_SQRT_PI;
    return exp(-0.5 * x * x) / sqrt(2.0 * MF_PI);
}

static double smith_integrand(double y, void *user)
{
    const smith_ctx *s = user;
    return y * unit_marginal(s->family, s->a + y);
}

/* Smith's Lambda relative to the mean plane (correction C-L2):
 * Lambda = 1/(c - mu) * integral_c^inf (x - c) P2(x) dx = (1/a) integral_0^inf y p(a + y) dy
 * with a = (c - mu)/scale, c = cot(theta), in units of the marginal's scale. */
static double smith_lambda_integral(int family, double a, int *failed)
{
    smith_ctx s = {family, a};
    mf_result r;
    /* split at the scale of the integrand's decay so the rules see smooth pieces */
    double pts[3] = {1.0, 4.0, 16.0};
    double v = 0.0, lo = 0.0;
    for (int i = 0; i <= 3; ++i) {
        double hi = i < 3 ? pts[i] : INFINITY;
        if (mf_quad_adaptive(smith_integrand, &s, lo, hi, 0.0, 1e-12, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            *failed = 1;
        v += r.val;
        lo = hi;
    }
    return v / a;
}

static void check_lambda(mf_check *c)
{
    mf_check_begin(c, "lambda_closed_form",
               "max relative |Lambda closed form - Smith integral|: GGX, Beckmann, non-centred Gaussian", 1e-9);
    char at[200];
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < N_ALPHAS; ++ia)
            for (int ir = 0; ir < N_RATIOS; ++ir) {
                if (duplicate_ratio(ia, ir))
                    continue;
                mf_ndf ndf = grid_ndf(t, ia, ir);
                for (int it = 1; it < N_THETAS; ++it)
                    for (int ip = 0; ip < N_PHIS; ++ip) {
                        double th = k_thetas_deg[it] * DEG, ph = k_phis[ip];
                        /* independent path: angles, not the vector form of the closed form */
                        double cot = cos(th) / sin(th);
                        double alpha_phi = sqrt(pow(cos(ph) * ndf.alpha_x, 2) + pow(sin(ph) * ndf.alpha_y, 2));
                        int failed = 0;
                        double ref = smith_lambda_integral(t, cot / alpha_phi, &failed);
                        double got = mf_smith_lambda(ndf, mf_vec3_spherical(th, ph));
                        if (ref < 1e-290 && got < 1e-290)
                            continue; /* both underflow */
                        double rel = failed ? NAN : fabs(got - ref) / ref;
                        snprintf(at, sizeof at, "%s alpha=(%g,%g) theta=%g deg phi=%g: closed=%.17g integral=%.17g",
                                 mf_ndf_type_name(ndf.type), ndf.alpha_x, ndf.alpha_y, k_thetas_deg[it], ph, got, ref);
                        mf_check_record(c, rel, at);
                    }
            }
    /* non-centred Gaussian, including directions below the geometric horizon but above the
     * mesosurface (nu > 0, correction C-L3) */
    static const double thetas_g[] = {15.0, 45.0, 75.0, 89.0, 89.99, 95.0, 120.0};
    for (int im = 0; im < N_MEANS; ++im)
        for (int ic = 0; ic < N_COVS; ++ic)
            for (int it = 0; it < 7; ++it)
                for (int ip = 0; ip < N_PHIS; ++ip) {
                    mf_gaussian_slopes g = grid_gaussian(im, ic);
                    double th = thetas_g[it] * DEG, ph = k_phis[ip];
                    double cot = cos(th) / sin(th);
                    /* [Dupuy 2013, Eq. 14-15] */
                    double mu = cos(ph) * g.mean_x + sin(ph) * g.mean_y;
                    double var = cos(ph) * cos(ph) * g.var_x + sin(ph) * sin(ph) * g.var_y + 2.0 * cos(ph) * sin(ph) * g.cov_xy;
                    /* nu must be > 0 (above the mesosurface), and cot - mu must not be the
                     * difference of nearly equal numbers (condition number > 1e6). */
                    if (!(var > 0.0) || !(cot - mu > 1e-6 * (fabs(cot) + fabs(mu))))
                        continue;
                    int failed = 0;
                    double a = (cot - mu) / sqrt(var);
                    if (a > 30.0)
                        continue; /* Lambda < 1e-198: relative comparison meaningless in the tail */
                    double ref = smith_lambda_integral(2, a, &failed);
                    double got = mf_smith_lambda_gaussian(&g, mf_vec3_spherical(th, ph));
                    double rel = failed ? NAN : fabs(got - ref) / ref;
                    snprintf(at, sizeof at, "gaussian mean=(%g,%g) cov=(%g,%g,%g) theta=%g deg phi=%g: %.17g vs %.17g",
                             g.mean_x, g.mean_y, g.var_x, g.var_y, g.cov_xy, thetas_g[it], ph, got, ref);
                    mf_check_record(c, rel, at);
                }
    mf_check_finish(c);
}

/* ---- check 5: Walter's approximation ------------------------------------------------------- */
static void check_walter(mf_check *c)
{
    mf_check_begin(c, "walter_g1_error",
               "max relative |G1 Walter - G1 exact| over nu in (0, 10], Beckmann/Gaussian (docs/math.md, correction C-L4: 0.31 %)",
               3.2e-3);
    char at[200];
    for (int i = 1; i <= 20000; ++i) {
        double nu = 10.0 * i / 20000.0;
        double g_exact = 1.0 / (1.0 + mf_smith_lambda_beckmann_nu(nu));
        double l_w = mf_smith_lambda_beckmann_walter_nu(nu);
        double rel = fabs(1.0 / (1.0 + l_w) - g_exact) / g_exact;
        if (l_w < 0.0)
            rel = NAN; /* the clamp must keep G1 <= 1 */
        snprintf(at, sizeof at, "nu=%g: G1 exact=%.10g walter=%.10g", nu, g_exact, 1.0 / (1.0 + l_w));
        mf_check_record(c, rel, at);
    }
    mf_check_finish(c);
}

/* ---- check 6: reciprocity ------------------------------------------------------------------ */
static void record_pair(mf_check *c, double a, double b, const char *what)
{
    double m = fmax(fabs(a), fabs(b));
    if (isnan(a) || isnan(b)) {
        mf_check_record(c, NAN, what);
        return;
    }
    if (m < 1e-300)
        return;
    mf_check_record(c, fabs(a - b) / m, what);
}

static void check_reciprocity(mf_check *c)
{
    mf_check_begin(c, "reciprocity",
               "max relative |f(wo,wi) - f(wi,wo)|: microfacet (2 NDFs x 2 G2 x 4 Fresnel), Lambert, LEADR", 64 * DBL_EPSILON);
    static const double thetas[] = {0.0, 20.0, 45.0, 70.0, 85.0, 89.99};
    static const double phis[] = {0.0, 1.0, 2.5, 4.0};
    mf_vec3 dirs[24];
    int nd = 0;
    for (int it = 0; it < 6; ++it)
        for (int ip = 0; ip < 4; ++ip)
            dirs[nd++] = mf_vec3_spherical(thetas[it] * DEG, phis[ip]);
    mf_fresnel fresnels[4] = {{MF_FRESNEL_NONE, 0, 0, 0}, {MF_FRESNEL_SCHLICK, 0.04, 0, 0},
                              {MF_FRESNEL_DIELECTRIC, 0, 1.5, 0}, {MF_FRESNEL_CONDUCTOR, 0, 0.2, 3.9}};
    char at[200];
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < N_ALPHAS; ia += 3)
            for (int ir = 0; ir < N_RATIOS; ++ir)
                for (int form = 0; form < 2; ++form)
                    for (int fr = 0; fr < 4; ++fr) {
                        mf_microfacet m = {grid_ndf(t, ia, ir), (mf_g2_form)form, fresnels[fr]};
                        for (int i = 0; i < nd; ++i)
                            for (int j = 0; j < nd; ++j) {
                                double a = mf_brdf_microfacet(&m, dirs[i], dirs[j]);
                                double b = mf_brdf_microfacet(&m, dirs[j], dirs[i]);
                                snprintf(at, sizeof at, "%s alpha=(%g,%g) g2=%d fresnel=%d dirs %d,%d: %.17g vs %.17g",
                                         mf_ndf_type_name(m.ndf.type), m.ndf.alpha_x, m.ndf.alpha_y, form, fr, i, j, a, b);
                                record_pair(c, a, b, at);
                            }
                    }
    for (int i = 0; i < nd; ++i)
        for (int j = 0; j < nd; ++j) {
            snprintf(at, sizeof at, "lambert dirs %d,%d", i, j);
            record_pair(c, mf_brdf_lambert(0.8, dirs[i], dirs[j]), mf_brdf_lambert(0.8, dirs[j], dirs[i]), at);
        }
    /* LEADR: f(wo,wi) (n.wo) wi.z = eq17(wo,wi) (n.wo) is the symmetric form (mf_brdf.h). */
    for (int im = 0; im < N_MEANS; ++im)
        for (int ic = 0; ic < N_COVS; ++ic) {
            mf_gaussian_slopes g = grid_gaussian(im, ic);
            mf_vec3 n = mf_gaussian_mesonormal(&g);
            for (int i = 0; i < nd; ++i)
                for (int j = 0; j < nd; ++j) {
                    double a = mf_leadr_specular(&g, fresnels[1], dirs[i], dirs[j]) * mf_vec3_dot(n, dirs[i]);
                    double b = mf_leadr_specular(&g, fresnels[1], dirs[j], dirs[i]) * mf_vec3_dot(n, dirs[j]);
                    snprintf(at, sizeof at, "leadr mean=(%g,%g) cov=(%g,%g,%g) dirs %d,%d: %.17g vs %.17g", g.mean_x,
                             g.mean_y, g.var_x, g.var_y, g.cov_xy, i, j, a, b);
                    record_pair(c, a, b, at);
                }
        }
    mf_check_finish(c);
}

/* ---- check 7: albedo <= 1 ------------------------------------------------------------------ */
static void check_albedo(mf_check *c)
{
    mf_check_begin(c, "albedo_at_most_one",
               "max (albedo - quadrature error): microfacet without/with Fresnel, joint/separable G2; LEADR specular",
               1.0 + 1e-12); /* 1e-12: rounding of the n x n weight sum (the integrand is <= 1 pointwise) */
    char at[200];
    mf_fresnel none = {MF_FRESNEL_NONE, 0, 0, 0}, schlick = {MF_FRESNEL_SCHLICK, 0.9, 0, 0};
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < N_ALPHAS; ++ia)
            for (int ir = 0; ir < 2; ++ir)
                for (int it = 0; it < N_THETAS; ++it)
                    for (int form = 0; form < 2; ++form) {
                        mf_microfacet m = {grid_ndf(t, ia, ir), (mf_g2_form)form, none};
                        mf_vec3 wo = mf_vec3_spherical(k_thetas_deg[it] * DEG, 0.7);
                        mf_result r, rf;
                        mf_status st = mf_brdf_microfacet_albedo(&m, wo, 64, &r);
                        m.fresnel = schlick;
                        mf_status stf = mf_brdf_microfacet_albedo(&m, wo, 64, &rf);
                        double v = (st == MF_OK) ? r.val - r.err : NAN;
                        if (stf != MF_OK || rf.val - rf.err > r.val + r.err)
                            v = NAN; /* Fresnel <= 1 cannot raise the albedo */
                        snprintf(at, sizeof at, "%s alpha=(%g,%g) g2=%d theta_o=%g deg: albedo=%.10g +- %.2g",
                                 mf_ndf_type_name(m.ndf.type), m.ndf.alpha_x, m.ndf.alpha_y, form, k_thetas_deg[it],
                                 r.val, r.err);
                        mf_check_record(c, v, at);
                    }
    /* LEADR specular (non-centred slopes), views above the mesosurface */
    mf_fresnel schlick04 = {MF_FRESNEL_SCHLICK, 0.04, 0, 0};
    static const double thetas_l[] = {0.0, 45.0, 80.0, 89.99};
    for (int im = 0; im < N_MEANS; ++im)
        for (int ic = 0; ic < N_COVS; ++ic)
            for (int it = 0; it < 4; ++it) {
                mf_gaussian_slopes g = grid_gaussian(im, ic);
                mf_vec3 wo = mf_vec3_spherical(thetas_l[it] * DEG, 2.5);
                if (!(mf_smith_gaussian_nu(&g, wo) > 0.0))
                    continue;
                mf_result r;
                mf_status st = mf_leadr_specular_albedo(&g, schlick04, wo, 64, &r);
                snprintf(at, sizeof at, "leadr mean=(%g,%g) cov=(%g,%g,%g) theta_o=%g deg: albedo=%.10g +- %.2g",
                         g.mean_x, g.mean_y, g.var_x, g.var_y, g.cov_xy, thetas_l[it], r.val, r.err);
                mf_check_record(c, st == MF_OK ? r.val - r.err : NAN, at);
            }
    mf_check_finish(c);
}

/* ---- check 8: no NaN or Inf where the math has a finite value ------------------------------ */
static void count_bad(mf_check *c, double v, int inf_ok, const char *at, int *bad)
{
    c->cases++;
    if (isnan(v) || (!inf_ok && isinf(v))) {
        if (*bad == 0)
            snprintf(c->worst_at, sizeof c->worst_at, "%s = %g", at, v);
        ++*bad;
    }
}

static void check_finite(mf_check *c)
{
    mf_check_begin(c, "finite_everywhere",
               "count of NaN/Inf outputs on the grid incl. alpha 1e-4, 89.99 deg, below-horizon directions", 0.0);
    mf_vec3 dirs[64];
    int nd = 0;
    static const double thetas[] = {0.0, 30.0, 60.0, 89.0, 89.99, 89.9999, 90.0, 90.01, 120.0, 180.0};
    for (int it = 0; it < 10; ++it)
        for (int ip = 0; ip < N_PHIS; ++ip)
            dirs[nd++] = mf_vec3_spherical(thetas[it] * DEG, k_phis[ip]);
    static const double slopes[] = {0.0, 1e-6, 0.3, 5.0, 1e4, 1e8};
    int bad = 0;
    mf_fresnel schlick = {MF_FRESNEL_SCHLICK, 0.04, 0, 0};
    for (int t = 0; t < 2; ++t)
        for (int ia = 0; ia < N_ALPHAS; ++ia)
            for (int ir = 0; ir < N_RATIOS; ++ir) {
                mf_ndf ndf = grid_ndf(t, ia, ir);
                for (int i = 0; i < 6; ++i)
                    for (int j = 0; j < 6; ++j)
                        count_bad(c, mf_ndf_p22(ndf, slopes[i], -slopes[j]), 0, "P22", &bad);
                for (int i = 0; i < nd; ++i) {
                    count_bad(c, mf_ndf_d(ndf, dirs[i]), 0, "D", &bad);
                    count_bad(c, mf_smith_lambda(ndf, dirs[i]), 1, "Lambda", &bad);
                    count_bad(c, mf_smith_lambda_beckmann_walter(ndf.alpha_x, ndf.alpha_y, dirs[i]), 1, "Lambda_walter", &bad);
                    count_bad(c, mf_smith_g1(ndf, dirs[i]), 0, "G1", &bad);
                    for (int j = 0; j < nd; ++j) {
                        mf_microfacet m = {ndf, MF_G2_JOINT, schlick};
                        count_bad(c, mf_smith_g2(ndf, MF_G2_JOINT, dirs[i], dirs[j]), 0, "G2 joint", &bad);
                        count_bad(c, mf_smith_g2(ndf, MF_G2_SEPARABLE, dirs[i], dirs[j]), 0, "G2 separable", &bad);
                        count_bad(c, mf_brdf_microfacet(&m, dirs[i], dirs[j]), 0, "brdf", &bad);
                    }
                }
            }
    for (int im = 0; im < N_MEANS; ++im)
        for (int ic = 0; ic < N_COVS; ++ic) {
            mf_gaussian_slopes g = grid_gaussian(im, ic);
            for (int i = 0; i < nd; ++i) {
                count_bad(c, mf_gaussian_d(&g, dirs[i]), 0, "gaussian D", &bad);
                count_bad(c, mf_smith_lambda_gaussian(&g, dirs[i]), 1, "gaussian Lambda", &bad);
                count_bad(c, mf_smith_lambda_gaussian_walter(&g, dirs[i]), 1, "gaussian Lambda_walter", &bad);
                for (int j = 0; j < nd; ++j)
                    count_bad(c, mf_leadr_specular(&g, schlick, dirs[i], dirs[j]), 0, "leadr specular", &bad);
            }
        }
    c->worst = bad;
    if (bad == 0)
        snprintf(c->worst_at, sizeof c->worst_at, "none");
    mf_check_finish(c);
}

/* ---- checks 9-11: spherical polygons and LTCs (mf_polygon.h, mf_ltc.h) ---------------------- */
/* Integrals over a planar polygon by a path independent of the library's (no clipping, no edge
 * formula): over the fan triangles (v0, a, b), each parametrised x(s, t) = v0 + s (a - v0) +
 * s t (b - a) on [0, 1]^2, where dA = s |n| ds dt with n = (a - v0) x (b - v0), and the solid
 * angle element is dw = |n.x| dA / (|n| |x|^3); signed, s (n.x) / |x|^3 ds dt, positive when n
 * points away from the shading point (front-facing, mf_polygon.h).  The integrand f(x / |x|) has
 * one kink, on the plane k.x = 0 (k = z for the clamped cosine, k = row 2 of M^-1 for an LTC):
 * k.x is linear in t for fixed s, so the inner rule is split at its root, and the outer rule at
 * the s where that root enters or leaves [0, 1]. */
typedef double (*dir_fn)(mf_vec3 w, const void *user);

typedef struct {
    dir_fn f;
    const void *user;
    mf_vec3 v0, ea, eb, n, k; /* ea = a - v0, eb = b - a */
    int peaked;               /* a narrow lobe: break points around its foot xp */
    mf_vec3 xp;
    double s;
    int failed;
} tri_ctx;

/* Offsets of the break points around a narrow lobe's foot, from 1e-7 of the parameter range
 * (a lobe of angular width 1e-3 seen through a triangle 200 times larger than its distance) to
 * 0.1: the adaptive rules then see the peak at every scale, whatever its width. */
static const double k_peak_offsets[] = {1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 0.1};
#define N_PEAK_OFFSETS ((int)(sizeof k_peak_offsets / sizeof k_peak_offsets[0]))

static int add_peak_points(double centre, double *pts, int np)
{
    for (int i = 0; i < N_PEAK_OFFSETS; ++i)
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            double x = centre + sgn * k_peak_offsets[i];
            if (x > 0.0 && x < 1.0)
                pts[np++] = x;
        }
    return np;
}

static double tri_inner(double t, void *vctx)
{
    tri_ctx *q = vctx;
    mf_vec3 x = mf_vec3_add(q->v0, mf_vec3_scale(mf_vec3_add(q->ea, mf_vec3_scale(q->eb, t)), q->s));
    double r = mf_vec3_length(x);
    return q->f(mf_vec3_scale(x, 1.0 / r), q->user) * q->s * mf_vec3_dot(q->n, x) / (r * r * r);
}

static double tri_outer(double s, void *vctx)
{
    tri_ctx *q = vctx;
    q->s = s;
    double pts[1 + 2 * N_PEAK_OFFSETS];
    int np = 0;
    double ka = mf_vec3_dot(q->k, q->v0) + s * mf_vec3_dot(q->k, q->ea), kb = s * mf_vec3_dot(q->k, q->eb);
    if (kb != 0.0 && -ka / kb > 0.0 && -ka / kb < 1.0)
        pts[np++] = -ka / kb;
    if (q->peaked) {
        /* the t of this row closest to the foot of the lobe */
        mf_vec3 d = mf_vec3_sub(q->xp, mf_vec3_add(q->v0, mf_vec3_scale(q->ea, s)));
        double tp = mf_vec3_dot(d, q->eb) / (s * mf_vec3_dot(q->eb, q->eb));
        if (isfinite(tp))
            np = add_peak_points(tp, pts, np);
    }
    return integrate_pieces(tri_inner, q, 0.0, 1.0, pts, np, 1e-11, 1e-17, &q->failed);
}

/* Signed integral of f over the planar polygon p (NaN if a rule did not converge).  peak: the
 * axis of a narrow lobe of f (or NULL). */
static double integrate_planar_polygon(const mf_polygon *p, dir_fn f, const void *user, mf_vec3 k, const mf_vec3 *peak)
{
    double sum = 0.0;
    int failed = 0;
    for (int i = 1; i + 1 < p->n; ++i) {
        tri_ctx q;
        memset(&q, 0, sizeof q);
        q.f = f;
        q.user = user;
        q.k = k;
        q.v0 = p->v[0];
        q.ea = mf_vec3_sub(p->v[i], p->v[0]);
        q.eb = mf_vec3_sub(p->v[i + 1], p->v[i]);
        q.n = mf_vec3_cross(q.ea, mf_vec3_sub(p->v[i + 1], p->v[0]));
        double pts[2 + 2 * N_PEAK_OFFSETS];
        int np = 0;
        if (peak) {
            /* the foot xp = lambda peak of the lobe's axis on the triangle's plane, and its s:
             * xp - v0 = s ea + u eb (least squares in the plane) */
            double lambda = mf_vec3_dot(q.n, q.v0) / mf_vec3_dot(q.n, *peak);
            if (lambda > 0.0 && isfinite(lambda)) {
                q.peaked = 1;
                q.xp = mf_vec3_scale(*peak, lambda);
                mf_vec3 d = mf_vec3_sub(q.xp, q.v0);
                double aa = mf_vec3_dot(q.ea, q.ea), ab = mf_vec3_dot(q.ea, q.eb), bb = mf_vec3_dot(q.eb, q.eb);
                double da = mf_vec3_dot(d, q.ea), db = mf_vec3_dot(d, q.eb);
                double sp = (da * bb - db * ab) / (aa * bb - ab * ab);
                if (isfinite(sp))
                    np = add_peak_points(sp, pts, np);
            }
        }
        /* outer break points: the kink crosses the edge t = 0 (v0 -> a) or t = 1 (v0 -> b) */
        double k0 = mf_vec3_dot(k, q.v0), k1 = mf_vec3_dot(k, q.ea), k2 = mf_vec3_dot(k, mf_vec3_add(q.ea, q.eb));
        if (k1 != 0.0 && -k0 / k1 > 0.0 && -k0 / k1 < 1.0)
            pts[np++] = -k0 / k1;
        if (k2 != 0.0 && -k0 / k2 > 0.0 && -k0 / k2 < 1.0)
            pts[np++] = -k0 / k2;
        sum += integrate_pieces(tri_outer, &q, 0.0, 1.0, pts, np, 1e-11, 1e-16, &failed);
        failed |= q.failed;
    }
    return failed ? NAN : sum;
}

/* The polygons: planar, at moderate distance; above, across and below the horizon, convex and
 * not, a vertex and an edge exactly on the horizon, a large one nearly filling the hemisphere,
 * and a small one (edges 2e-3) at 60 degrees. */
#define N_VPOLYS 8
static mf_polygon validate_polygon(int i, char *name, size_t name_size)
{
    static const double v[7][8][3] = {
        {{0.5, -0.5, 1}, {0.5, 0.5, 1}, {-0.5, 0.5, 1}, {-0.5, -0.5, 1}},
        {{1, 1, -0.5}, {1, 1, 1.2}, {-1, 1, 1.2}, {-1, 1, -0.5}},
        /* the plane x + y/2 + 2 z = 1 */
        {{1.2, 0.3, -0.175}, {0.4, 1.0, 0.05}, {-0.6, 0.5, 0.675}, {-0.5, -0.7, 0.925}, {0.6, -1.0, 0.45}},
        {{0.3, 0.2, -1}, {-0.4, 0.3, -1}, {0.1, -0.5, -1}},
        /* an L in the plane y = 0.8 */
        {{-1, 0.8, -0.4}, {1, 0.8, -0.4}, {1, 0.8, 0.2}, {-0.2, 0.8, 0.2}, {-0.2, 0.8, 1.1}, {-1, 0.8, 1.1}},
        {{0}},
        /* the plane z = 1.6 (y - 0.5): an edge on the horizon */
        {{1, 0.5, 0}, {-1, 0.5, 0}, {-1, 1, 0.8}, {1, 1, 0.8}},
    };
    static const int nv[7] = {4, 4, 5, 3, 6, 8, 4};
    static const char *names[N_VPOLYS] = {"zenith square", "vertical quad across the horizon", "tilted pentagon across",
                                          "triangle below", "L-shaped hexagon across", "octagon r=5 at z=0.05",
                                          "quad with an edge on the horizon", "triangle 2e-3 at 60 deg"};
    snprintf(name, name_size, "%s", names[i]);
    mf_vec3 w[8];
    if (i == 5) {
        for (int k = 0; k < 8; ++k)
            w[k] = mf_vec3_make(5.0 * cos(MF_PI * k / 4), 5.0 * sin(MF_PI * k / 4), 0.05);
        return mf_polygon_make(8, w);
    }
    if (i == 7) {
        mf_vec3 c = mf_vec3_spherical(60.0 * DEG, 1.0);
        mf_frame f = mf_frame_from_normal(c);
        for (int k = 0; k < 3; ++k)
            w[k] = mf_vec3_add(c, mf_frame_to_world(f, mf_vec3_make(1e-3 * cos(2.1 * k), 1e-3 * sin(2.1 * k), 0.0)));
        return mf_polygon_make(3, w);
    }
    for (int k = 0; k < nv[i]; ++k)
        w[k] = mf_vec3_make(v[i][k][0], v[i][k][1], v[i][k][2]);
    return mf_polygon_make(nv[i], w);
}

static double cosine_dir(mf_vec3 w, const void *user)
{
    (void)user;
    return fmax(0.0, w.z) * MF_INV_PI;
}

static double ltc_dir(mf_vec3 w, const void *user) { return mf_ltc_eval(user, w); }

/* |a - b| relative to |b|; values below `scale` are compared in absolute terms (in units of
 * scale), e.g. 0 for polygons below the horizon. */
static double rel_err(double a, double b, double scale) { return fabs(a - b) / fmax(fabs(b), scale); }

static double one_dir(mf_vec3 w, const void *user)
{
    (void)w;
    (void)user;
    return 1.0;
}

static void check_polygon_cosine(mf_check *c)
{
    mf_check_begin(c, "polygon_cosine",
               "max relative |Lambert's clipped edge sum - quadrature| of integral max(0,z)/pi dw, and of the solid "
               "angle, signed, 8 polygons",
               1e-9);
    char at[200], name[64];
    for (int i = 0; i < N_VPOLYS; ++i) {
        mf_polygon p = validate_polygon(i, name, sizeof name);
        double q = integrate_planar_polygon(&p, cosine_dir, NULL, mf_vec3_make(0, 0, 1), NULL);
        double e = mf_polygon_integrate_cosine_signed(&p);
        snprintf(at, sizeof at, "%s: edge sum %.17g, quadrature %.17g", name, e, q);
        mf_check_record(c, rel_err(e, q, 1e-15), at);
        /* the solid angle: the same quadrature of f = 1 (no kink) */
        double qo = integrate_planar_polygon(&p, one_dir, NULL, mf_vec3_make(0, 0, 0), NULL);
        double o = mf_polygon_solid_angle_signed(&p);
        snprintf(at, sizeof at, "%s: solid angle %.17g, quadrature %.17g", name, o, qo);
        mf_check_record(c, rel_err(o, qo, 1e-15), at);
    }
    mf_check_finish(c);
}

/* The validation matrices: well- and ill-conditioned, det < 0, strong shear, a lobe reaching
 * below the horizon, anisotropy 1:1000, a near-specular lobe (alpha ~ 1e-3). */
#define N_VMATS 8
static mf_mat3 validate_matrix(int i, char *name, size_t name_size)
{
    static const double m[N_VMATS][9] = {
        {1, 0, 0, 0, 1, 0, 0, 0, 1},
        {0.5, 0, 0.2, 0, 0.5, 0, -0.3, 0, 1},
        {0.3, 0, 0.9, 0, 0.4, 0, -0.7, 0, 1},
        {0.8, 0.3, -0.2, -0.1, 0.6, 0.25, 0.3, -0.2, 1.1},
        {-0.7, 0.1, 0.3, 0.2, 0.9, 0.0, 0.1, 0.2, 1.0},
        {1.0, 40.0, 0.0, 0.0, 1.0, 25.0, 0.0, 0.0, 1.0},
        {1e-3, 0, 0, 0, 1, 0, 0, 0.6, 0.8},
        {-1e-3, 0, 2e-4, 0, 1e-3, 0, 5e-4, 0, 1.0},
    };
    static const char *names[N_VMATS] = {"identity", "isotropic (0.5,0.2,0.5,-0.3)", "isotropic grazing (0.3,0.9,0.4,-0.7)",
                                         "general", "det<0", "shear 40/25", "anisotropic 1:1e3", "near-specular 1e-3 det<0"};
    snprintf(name, name_size, "%s", names[i]);
    return mf_ltc_matrix_general(m[i]);
}

/* Integral of D over the sphere in polar coordinates (t, phi) around the lobe's axis
 * p = M z / |M z|: the support (M^-1 w).z = r2.w > 0 ends at t = atan2(r2.p, -r2.e(phi)) (r2.p > 0),
 * where D vanishes linearly, so each inner integrand is smooth; the inner rule is split at
 * t = 1e-5 ... 2 to find lobes of any width. */
typedef struct {
    const mf_ltc *l;
    mf_vec3 p, e1, e2, r2;
    double phi;
    int failed;
} sph_ctx;

static double sph_inner(double t, void *vctx)
{
    sph_ctx *q = vctx;
    mf_vec3 e = mf_vec3_add(mf_vec3_scale(q->e1, cos(q->phi)), mf_vec3_scale(q->e2, sin(q->phi)));
    mf_vec3 w = mf_vec3_add(mf_vec3_scale(q->p, cos(t)), mf_vec3_scale(e, sin(t)));
    return mf_ltc_eval(q->l, w) * sin(t);
}

static double sph_outer(double phi, void *vctx)
{
    sph_ctx *q = vctx;
    q->phi = phi;
    mf_vec3 e = mf_vec3_add(mf_vec3_scale(q->e1, cos(phi)), mf_vec3_scale(q->e2, sin(phi)));
    double tmax = atan2(mf_vec3_dot(q->r2, q->p), -mf_vec3_dot(q->r2, e));
    static const double scales[] = {1e-5, 1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0, 2.0};
    double pts[8];
    int np = 0;
    for (int i = 0; i < 8; ++i)
        if (scales[i] < tmax)
            pts[np++] = scales[i];
    return integrate_pieces(sph_inner, q, 0.0, tmax, pts, np, 1e-12, 1e-16, &q->failed);
}

static void check_ltc_normalisation(mf_check *c)
{
    mf_check_begin(c, "ltc_normalisation",
               "|integral of D(w) dw over the sphere - 1| (docs/math.md, correction C-T2 Jacobian), 8 matrices incl. det<0, shear, 1:1e3",
               1e-9);
    char at[200], name[64];
    for (int i = 0; i < N_VMATS; ++i) {
        mf_ltc l;
        if (mf_ltc_init(&l, validate_matrix(i, name, sizeof name)) != MF_OK) {
            mf_check_record(c, NAN, name);
            continue;
        }
        sph_ctx q;
        memset(&q, 0, sizeof q);
        q.l = &l;
        q.p = mf_vec3_normalize(mf_vec3_make(l.m.m[0][2], l.m.m[1][2], l.m.m[2][2]));
        mf_frame f = mf_frame_from_normal(q.p);
        q.e1 = f.s;
        q.e2 = f.t;
        q.r2 = mf_vec3_make(l.inv.m[2][0], l.inv.m[2][1], l.inv.m[2][2]);
        double pts[7];
        for (int k = 0; k < 7; ++k)
            pts[k] = MF_PI * (k + 1) / 4;
        double v = integrate_pieces(sph_outer, &q, 0.0, 2.0 * MF_PI, pts, 7, 1e-11, 1e-15, &q.failed);
        snprintf(at, sizeof at, "%s: integral=%.17g", name, v);
        mf_check_record(c, q.failed ? NAN : fabs(v - 1.0), at);
    }
    mf_check_finish(c);
}

static void check_ltc_polygon(mf_check *c)
{
    mf_check_begin(c, "ltc_polygon",
               "max relative |integral of D over P (clip after M^-1) - quadrature|, one- and two-sided, 8 x 8 cases",
               1e-9);
    char at[200], pname[64], mname[64];
    for (int i = 0; i < N_VMATS; ++i) {
        mf_ltc l;
        if (mf_ltc_init(&l, validate_matrix(i, mname, sizeof mname)) != MF_OK) {
            mf_check_record(c, NAN, mname);
            continue;
        }
        mf_vec3 r2 = mf_vec3_make(l.inv.m[2][0], l.inv.m[2][1], l.inv.m[2][2]);
        mf_vec3 axis = mf_vec3_normalize(mf_vec3_make(l.m.m[0][2], l.m.m[1][2], l.m.m[2][2])); /* M z */
        for (int j = 0; j < N_VPOLYS; ++j) {
            mf_polygon p = validate_polygon(j, pname, sizeof pname);
            double q = integrate_planar_polygon(&p, ltc_dir, &l, r2, &axis); /* signed by the facing of p */
            double two = mf_ltc_integrate_polygon(&l, &p, MF_POLYGON_TWO_SIDED);
            double one = mf_ltc_integrate_polygon(&l, &p, MF_POLYGON_ONE_SIDED);
            snprintf(at, sizeof at, "%s, %s: %.17g vs quadrature %.17g", mname, pname, two, q);
            /* values below 1e-6 in absolute terms: far in the tail of a narrow lobe the quadrature's
             * absolute floor and the edge sum's cancellation (a sliver of M^-1 P near z_o = 0)
             * leave few relative digits, and nothing depends on them */
            double err = fmax(rel_err(two, fabs(q), 1e-6), rel_err(one, fmax(0.0, q), 1e-6));
            mf_check_record(c, isnan(q) ? NAN : err, at);
        }
    }
    mf_check_finish(c);
}

/* ---- filtering identities [Kaplanyan 2016] (issue 4) ------------------------------------- */

/* Breakpoints for an axis of [lo, hi] with a peak of scale alpha at 0: 0 and +-alpha 10^k,
 * k = -2..2, where they fall strictly inside. */
static int axis_breaks(double lo, double hi, double alpha, double *pts)
{
    static const double k_scales[] = {0.0, 0.01, -0.01, 0.1, -0.1, 1.0, -1.0, 10.0, -10.0, 100.0, -100.0};
    int n = 0;
    for (int i = 0; i < (int)(sizeof k_scales / sizeof k_scales[0]); ++i) {
        double p = k_scales[i] * alpha;
        if (p > lo && p < hi)
            pts[n++] = p;
    }
    return n;
}

typedef struct {
    mf_ndf ndf;
    double s, y0, y1;
    int failed;
} rect_ctx;

static double rect_inner(double t, void *vctx)
{
    rect_ctx *c = vctx;
    return mf_ndf_p22(c->ndf, c->s, t);
}

static double rect_outer(double s, void *vctx)
{
    rect_ctx *c = vctx;
    c->s = s;
    double pts[16];
    int n = axis_breaks(c->y0, c->y1, c->ndf.alpha_y, pts);
    return integrate_pieces(rect_inner, c, c->y0, c->y1, pts, n, 1e-12, 0.0, &c->failed);
}

/* The closed-form mean of GGX's P22 over rectangles [Kaplanyan 2016, Eq. 16, App. A; correction C-K1]
 * against nested adaptive Gauss-Kronrod of P22 itself (independent of the antiderivative). */
static void check_ggx_rect(mf_check *c)
{
    mf_check_begin(c, "ggx_rect_vs_quadrature",
               "GGX slope-density mean over rectangles (Eq. 16, App. A, docs/math.md, correction C-K1) vs nested adaptive quadrature",
               1e-10);
    static const double k_rect_alphas[][2] = {{1e-3, 1e-3}, {0.1, 0.01}, {1.0, 0.5}};
    /* centre and full width in units of alpha_x, alpha_y: tiny at the peak, unit, wide, near the
     * peak off-centre, far tail, corner on the peak, sliver, huge */
    static const double k_rects[][4] = {{0, 0, 1e-6, 1e-6}, {0, 0, 1, 1},     {0, 0, 100, 30},  {0.5, -0.3, 0.3, 0.7},
                                        {50, -20, 1, 2},    {0.5, 0.5, 1, 1}, {3, 0, 1e-4, 5}, {-7, 4, 1e4, 3e3}};
    for (int ia = 0; ia < 3; ++ia) {
        for (int ir = 0; ir < (int)(sizeof k_rects / sizeof k_rects[0]); ++ir) {
            double ax = k_rect_alphas[ia][0], ay = k_rect_alphas[ia][1];
            double cx = k_rects[ir][0] * ax, cy = k_rects[ir][1] * ay;
            double wx = k_rects[ir][2] * ax, wy = k_rects[ir][3] * ay;
            rect_ctx q = {mf_ndf_make(MF_NDF_GGX, ax, ay), 0.0, cy - 0.5 * wy, cy + 0.5 * wy, 0};
            double x0 = cx - 0.5 * wx, x1 = cx + 0.5 * wx;
            double pts[16];
            int n = axis_breaks(x0, x1, ax, pts);
            double integral = integrate_pieces(rect_outer, &q, x0, x1, pts, n, 1e-12, 0.0, &q.failed);
            double ref = integral / ((x1 - x0) * (q.y1 - q.y0));
            double v = mf_filter_ggx_rect_mean(ax, ay, cx, cy, wx, wy);
            char at[200];
            snprintf(at, sizeof at, "alpha (%g, %g), centre (%g, %g), widths (%g, %g)", ax, ay, cx, cy, wx, wy);
            mf_check_record(c, q.failed ? NAN : fabs(v - ref) / ref, at);
        }
    }
    mf_check_finish(c);
}

typedef struct {
    mf_ndf beck;
    mf_gaussian_slopes filt; /* centred, covariance P */
    double s[2];
    double scale;
} conv_ctx;

static double conv_integrand(double yx, double yy, void *user)
{
    const conv_ctx *c = user;
    return c->scale * mf_ndf_p22(c->beck, c->s[0] - yx, c->s[1] - yy) * mf_gaussian_p22(&c->filt, yx, yy);
}

/* Beckmann filtered by a Gaussian of covariance P [Kaplanyan 2016, Eq. 14-15]: the covariance sum
 * B' = diag(alpha^2/2) + P against the numerical convolution integral P22_B(s - y) N_P(y) d^2y. */
static void check_beckmann_convolution(mf_check *c)
{
    mf_check_begin(c, "beckmann_filter_convolution",
               "Beckmann (x) Gaussian filter: covariance sum B' = B + P (Eq. 14-15) vs numerical 2D convolution", 1e-8);
    static const double k_conv_alphas[][2] = {{0.05, 0.05}, {0.5, 0.1}};
    static const double k_conv_p[][3] = {{0.01, 0.0, 0.01}, {0.02, 0.01, 0.015}, {1e-6, 0.0, 4e-6}, {2.0, -0.5, 1.0}};
    static const double k_conv_s[][2] = {{0.0, 0.0}, {0.05, -0.03}, {0.3, 0.2}};
    for (int ia = 0; ia < 2; ++ia) {
        for (int ip = 0; ip < 4; ++ip) {
            for (int is = 0; is < 3; ++is) {
                double ax = k_conv_alphas[ia][0], ay = k_conv_alphas[ia][1];
                mf_sym2 p = {k_conv_p[ip][0], k_conv_p[ip][1], k_conv_p[ip][2]};
                conv_ctx q;
                q.beck = mf_ndf_make(MF_NDF_BECKMANN, ax, ay);
                mf_gaussian_slopes f = {0.0, 0.0, p.xx, p.yy, p.xy};
                q.filt = f;
                q.s[0] = k_conv_s[is][0];
                q.s[1] = k_conv_s[is][1];
                /* The integrand is a Gaussian in y of covariance C = (B^-1 + P^-1)^-1 = B - B (B+P)^-1 B
                 * and mean m = s - B (B+P)^-1 s (Woodbury; B = diag(alpha^2/2)): integrate in its frame. */
                double bx = 0.5 * ax * ax, by = 0.5 * ay * ay;
                double sxx = bx + p.xx, syy = by + p.yy, sxy = p.xy, det = sxx * syy - sxy * sxy;
                double ixx = syy / det, iyy = sxx / det, ixy = -sxy / det; /* (B+P)^-1 */
                double cxx = bx - bx * ixx * bx, cyy = by - by * iyy * by, cxy = -bx * ixy * by;
                double mx = q.s[0] - bx * (ixx * q.s[0] + ixy * q.s[1]);
                double my = q.s[1] - by * (ixy * q.s[0] + iyy * q.s[1]);
                /* scale the integrand to ~1/sqrt(det C) at its peak, the unit-mass scale the
                 * integrator's absolute floor is set for */
                q.scale = 1.0;
                double peak = conv_integrand(mx, my, &q);
                double sqdet = sqrt(cxx * cyy - cxy * cxy);
                q.scale = 1.0 / (peak * sqdet);
                mf_vec3 none = {0.0, 0.0, 0.0};
                double conv = integrate_slopes(conv_integrand, &q, mx, my, cxx, cyy, cxy, none) * peak * sqdet;
                mf_gaussian_slopes g = mf_filter_beckmann(ax, ay, p);
                double ref = mf_gaussian_p22(&g, q.s[0], q.s[1]);
                char at[200];
                snprintf(at, sizeof at, "alpha (%g, %g), P (%g, %g, %g), s (%g, %g)", ax, ay, p.xx, p.xy, p.yy, q.s[0],
                         q.s[1]);
                mf_check_record(c, fabs(conv - ref) / ref, at);
            }
        }
    }
    mf_check_finish(c);
}

/* The exact proxy alpha' satisfies the peak equation 1/(pi alpha'^2) = mean of P22 over the
 * centred square of width dh [Kaplanyan 2016, Eq. 19; correction C-K3], and the joint anisotropic solve
 * 1/(pi a'_x a'_y) = mean over the rectangle; mfkit's fitted form stays within its bound. */
static void check_ggx_proxy_peak(mf_check *c)
{
    mf_check_begin(c, "ggx_proxy_peak",
               "exact GGX proxy alpha' (docs/math.md, correction C-K3; joint anisotropic solve) satisfies 1/(pi a'^2) = rect mean (Eq. 19)",
               64 * DBL_EPSILON);
    static const double k_px_alpha[] = {1e-4, 1e-3, 1e-2, 0.1, 0.5, 1.0};
    static const double k_px_ratio[] = {0.0, 1e-6, 1e-3, 0.1, 1.0, 3.0, 10.0, 1e3, 1e5};
    char at[200];
    for (int ia = 0; ia < 6; ++ia) {
        for (int ir = 0; ir < 9; ++ir) {
            double a = k_px_alpha[ia], dh = a * k_px_ratio[ir];
            double ap = mf_filter_ggx_proxy_alpha(a, dh);
            double mean = mf_filter_ggx_rect_mean(a, a, 0.0, 0.0, dh, dh);
            snprintf(at, sizeof at, "isotropic alpha %g, dh %g", a, dh);
            mf_check_record(c, fabs(MF_PI * ap * ap * mean - 1.0), at);
            /* joint solve, anisotropic: alpha_y = alpha/10 (>= 1e-4), widths dh and dh/3 */
            double ay = fmax(1e-4, 0.1 * a), out[2];
            double wy = dh / 3.0;
            mf_status st = mf_filter_ggx_proxy_alpha_joint(a, ay, dh, wy, out);
            double cm = mf_filter_ggx_rect_mean(a, ay, 0.0, 0.0, dh, wy);
            snprintf(at, sizeof at, "joint alpha (%g, %g), widths (%g, %g)", a, ay, dh, wy);
            mf_check_record(c, st == MF_OK ? fabs(MF_PI * out[0] * out[1] * cm - 1.0) : NAN, at);
        }
    }
    mf_check_finish(c);
}

/* mfkit's fitted proxy (mf_proxy.h) against the exact alpha'. */
static void check_ggx_proxy_fit(mf_check *c)
{
    char at[200];
    mf_check_begin(c, "ggx_proxy_fit_error",
               "max relative error of the fitted proxy mf_proxy_alpha_fit vs the exact alpha', all dh/alpha",
               MF_PROXY_FIT_MAX_REL_ERROR);
    /* alpha'/alpha depends on x = dh^2/(alpha^2 + dh^2) only: sweep x over [0, 1) */
    for (int i = 0; i < 2000; ++i) {
        double x = (i + 0.5) / 2000.0;
        double a = 1.0, dh = sqrt(x / (1.0 - x));
        double e = fabs(mf_proxy_alpha_fit(a, dh) / mf_filter_ggx_proxy_alpha(a, dh) - 1.0);
        snprintf(at, sizeof at, "alpha 1, dh %.6g (x = %.6g)", dh, x);
        mf_check_record(c, e, at);
    }
    mf_check_finish(c);
}

/* ---- driver -------------------------------------------------------------------------------- */
typedef void (*check_fn)(mf_check *c);
static const check_fn k_checks[] = {check_ndf_normalisation, check_projected_area, check_leadr_identity,
                                    check_lambda,            check_walter,         check_reciprocity,
                                    check_albedo,            check_finite,         check_polygon_cosine,
                                    check_ltc_normalisation, check_ltc_polygon,    check_ggx_rect,
                                    check_beckmann_convolution, check_ggx_proxy_peak, check_ggx_proxy_fit};
#define N_CHECKS ((int)(sizeof k_checks / sizeof k_checks[0]))

int mf_validate_core_count(void) { return N_CHECKS; }

mf_status mf_validate_core(mf_check *checks, int cap, mf_validate_progress_fn progress, void *user)
{
    if (!checks || cap < N_CHECKS)
        return MF_ERR_DOMAIN;
    int all = 1;
    for (int i = 0; i < N_CHECKS; ++i) {
        k_checks[i](&checks[i]);
        all = all && checks[i].passed;
        if (progress)
            progress(user, i + 1, N_CHECKS, &checks[i]);
    }
    return all ? MF_OK : MF_ERR_CHECK_FAILED;
}
