/* test_filter.c -- NDF filtering over a pixel footprint (mf_filter.h), with docs/math.md,
 * corrections C-K1, C-K3, C-K4, C-K5, C-K6 and C-L6.  Prints the measured accuracy of the rectangle mean and of the GGX proxies. */
#include "mf_test.h"
#include "mfkit/mf_filter.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_rng.h"

#include <float.h>

/* ---- reference: nested adaptive Gauss-Kronrod over the rectangle -------------------------- */

typedef struct quad_ctx {
    double ax, ay;  /* GGX roughness */
    double x0, x1;  /* inner interval */
    double y;       /* outer variable */
    int failures;   /* quadrature statuses other than MF_OK */
    double inner_rel;
} quad_ctx;

/* GGX P22 written out [Heitz 2014, slope form]: an independent copy of mf_ndf_p22, inlined
 * because the nested reference evaluates it ~1e8 times. */
static double p22_ggx_x(double x, void *user)
{
    quad_ctx *c = (quad_ctx *)user;
    double ex = x / c->ax, ey = c->y / c->ay, s = 1.0 + ex * ex + ey * ey;
    return 1.0 / (MF_PI * c->ax * c->ay * s * s);
}

/* integral of f over [a, b], split at 0 (the peak of every integrand here) */
static double integrate_split(mf_fn1 f, quad_ctx *c, double a, double b, double rel, double *err)
{
    double pts[3] = {a, 0.0, b};
    int n = (a < 0.0 && b > 0.0) ? 2 : 1;
    if (n == 1)
        pts[1] = b;
    double sum = 0.0;
    *err = 0.0;
    for (int k = 0; k < n; ++k) {
        mf_result r;
        if (mf_quad_adaptive(f, c, pts[k], pts[k + 1], 0.0, rel, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            ++c->failures;
        sum += r.val;
        *err += r.err;
    }
    return sum;
}

static double inner_integral(double y, void *user)
{
    quad_ctx *c = (quad_ctx *)user;
    c->y = y;
    double err;
    return integrate_split(p22_ggx_x, c, c->x0, c->x1, c->inner_rel, &err);
}

/* mean of P22_GGX over [x0, x1] x [y0, y1]: inner rel. tol. 1e-13, outer 1e-12 (GK's |K15 - G7|
 * estimate is pessimistic: tightening both by 10x changes no measured error) */
static double quad_rect_mean(double ax, double ay, double x0, double x1, double y0, double y1, double *err,
                             int *failures)
{
    quad_ctx c = {ax, ay, x0, x1, 0.0, 0, 1e-13};
    double e;
    double v = integrate_split(inner_integral, &c, y0, y1, 1e-12, &e);
    double area = (x1 - x0) * (y1 - y0);
    *err = e / area;
    *failures += c.failures;
    return v / area;
}

/* ---- reference: 2D convolution of a Gaussian slope density with N(0, P) ------------------- */

/* integral of g(h - L z) phi(z1) phi(z2) dz over z in [-9, 9]^2 (mass outside < 1e-18), with
 * P = L L^T (Cholesky, P may be singular), 24 panels of 16 Gauss-Legendre points per axis. */
static double convolve_gaussian_with_p(const mf_gaussian_slopes *g, mf_sym2 p, double hx, double hy)
{
    double x[16], w[16];
    if (mf_quad_gauss_legendre(16, x, w) != MF_OK)
        return NAN;
    double l00 = sqrt(p.xx), l10 = (l00 > 0.0) ? p.xy / l00 : 0.0;
    double l11 = sqrt(fmax(p.yy - l10 * l10, 0.0));
    const int panels = 24;
    const double zmax = 9.0, hp = 2.0 * zmax / panels;
    double sum = 0.0;
    for (int pi = 0; pi < panels; ++pi)
        for (int i = 0; i < 16; ++i) {
            double z1 = -zmax + hp * (pi + 0.5 * (x[i] + 1.0));
            double w1 = 0.5 * hp * w[i] * exp(-0.5 * z1 * z1) / sqrt(2.0 * MF_PI);
            for (int pj = 0; pj < panels; ++pj)
                for (int j = 0; j < 16; ++j) {
                    double z2 = -zmax + hp * (pj + 0.5 * (x[j] + 1.0));
                    double w2 = 0.5 * hp * w[j] * exp(-0.5 * z2 * z2) / sqrt(2.0 * MF_PI);
                    double sx = hx - l00 * z1, sy = hy - (l10 * z1 + l11 * z2);
                    sum += w1 * w2 * mf_gaussian_p22(g, sx, sy);
                }
        }
    return sum;
}

/* ---- printed formulas, for the tests of the corrections (docs/math.md) -------------------------- */

/* Appendix A's phi, literally */
static double phi_printed(double x, double y, double g, double d)
{
    double r = sqrt(x * x + g * g);
    return x * atan(g * y / (r * d)) / r;
}

/* Appendix A as printed: limits h -+ dh (half widths) and 1 / (2 pi |dh_s dh_t|) (correction C-K1) */
static double appendix_a_printed(double a, double b, double hs, double ht, double dhs, double dht)
{
    double s0 = hs - dhs, s1 = hs + dhs, t0 = ht - dht, t1 = ht + dht;
    double bracket = phi_printed(s0, t0, a, b) - phi_printed(s0, t1, a, b) + phi_printed(s1, t1, a, b)
                   - phi_printed(s1, t0, a, b) + phi_printed(t0, s0, b, a) - phi_printed(t0, s1, b, a)
                   + phi_printed(t1, s1, b, a) - phi_printed(t1, s0, b, a);
    return bracket / (2.0 * MF_PI * fabs(dhs * dht));
}

/* Eq. 20 as extracted (correction C-K3): sqrt(dh^4 4 a^2 + dh^2) / (2 sqrt(atan(dh / sqrt(4a^2 + dh^2)))) */
static double eq20_printed(double a, double dh)
{
    return sqrt(dh * dh * dh * dh * 4.0 * a * a + dh * dh) / (2.0 * sqrt(atan(dh / sqrt(4.0 * a * a + dh * dh))));
}

/* x-marginal of the box-filtered GGX at s = 0: integral over t of the rectangle mean centred at (0, t) */
typedef struct marg_ctx {
    double ax, ay, wx, wy;
    int axis;
} marg_ctx;

static double rect_mean_along(double t, void *user)
{
    marg_ctx *m = (marg_ctx *)user;
    return m->axis == 0 ? mf_filter_ggx_rect_mean(m->ax, m->ay, 0.0, t, m->wx, m->wy)
                        : mf_filter_ggx_rect_mean(m->ax, m->ay, t, 0.0, m->wx, m->wy);
}

static double filtered_marginal_peak(double ax, double ay, double wx, double wy, int axis)
{
    marg_ctx m = {ax, ay, wx, wy, axis};
    mf_result r;
    if (mf_quad_adaptive(rect_mean_along, &m, 0.0, INFINITY, 0.0, 1e-12, 1000, &r) != MF_OK)
        return NAN;
    return 2.0 * r.val;
}

static void test_half_slope_and_signs(mf_pcg32 *rng)
{
    /* correction C-L6: h (mfkit) = -(wo + wi).xy / (wo + wi).z = -h (Kaplanyan Eq. 3); the GGX value
     * is the same at both (P22 is even), so centred filtering does not care. */
    for (int k = 0; k < 500; ++k) {
        double t1 = 1.4 * mf_pcg32_next_double(rng), p1 = 2 * MF_PI * mf_pcg32_next_double(rng);
        double t2 = 1.4 * mf_pcg32_next_double(rng), p2 = 2 * MF_PI * mf_pcg32_next_double(rng);
        mf_vec3 wo = mf_vec3_spherical(t1, p1), wi = mf_vec3_spherical(t2, p2);
        double h[2], hn[2];
        mf_filter_half_slope(wo, wi, h);
        mf_vec3 s = mf_vec3_add(wo, wi);
        double hk[2] = {s.x / s.z, s.y / s.z}; /* Kaplanyan's sign */
        CHECK(h[0] == -hk[0] && h[1] == -hk[1]);
        mf_slope_from_normal(mf_vec3_normalize(s), hn);
        CHECK_ABS(h[0], hn[0], 8 * DBL_EPSILON * (1.0 + fabs(hn[0])));
        CHECK_ABS(h[1], hn[1], 8 * DBL_EPSILON * (1.0 + fabs(hn[1])));
        mf_ndf ggx = mf_ndf_make(MF_NDF_GGX, 0.2, 0.05);
        CHECK(mf_ndf_p22(ggx, h[0], h[1]) == mf_ndf_p22(ggx, hk[0], hk[1]));
    }
    double h[2];
    mf_filter_half_slope(mf_vec3_make(0, 0.6, 0.8), mf_vec3_make(0, -0.6, -0.8), h); /* (wo + wi).z = 0 */
    CHECK(isnan(h[0]) && isnan(h[1]));
    mf_filter_half_slope(mf_vec3_make(NAN, 0, 1), mf_vec3_make(0, 0, 1), h);
    CHECK(isnan(h[0]));
}

static void test_jacobian_and_footprint(void)
{
    /* Eq. 4-5: the planar Jacobian against central differences of h(x) (step 1e-5, error
     * O(step^2 h''') ~ 1e-10 relative; tolerance 1e-8). */
    mf_vec3 eye = {0.3, -2.0, 3.0}, light = {-1.0, 1.5, 2.0}, x = {0.1, 0.2, 0.0};
    double jac[2][2];
    mf_filter_half_slope_jacobian_planar(eye, light, x, jac);
    const double step = 1e-5;
    double fd[2][2];
    for (int j = 0; j < 2; ++j) {
        mf_vec3 xp = x, xm = x;
        if (j == 0) { xp.x += step; xm.x -= step; } else { xp.y += step; xm.y -= step; }
        double hp[2], hm[2];
        mf_filter_half_slope(mf_vec3_normalize(mf_vec3_sub(eye, xp)), mf_vec3_normalize(mf_vec3_sub(light, xp)), hp);
        mf_filter_half_slope(mf_vec3_normalize(mf_vec3_sub(eye, xm)), mf_vec3_normalize(mf_vec3_sub(light, xm)), hm);
        for (int i = 0; i < 2; ++i)
            fd[i][j] = (hp[i] - hm[i]) / (2 * step);
    }
    double scale = fabs(fd[0][0]) + fabs(fd[0][1]) + fabs(fd[1][0]) + fabs(fd[1][1]);
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
            CHECK_ABS(jac[i][j], fd[i][j], 1e-8 * scale);
    /* the Jacobian is not symmetric here, so the reading of Eq. 5 matters */
    CHECK(fabs(jac[0][1] - jac[1][0]) > 1e-3 * scale);
    /* footprint: dh = M dx matches the first-order change of h; the literal row-vector product
     * dx M with Eq. 4's M (= M^T dx) does not. */
    double dxu[2] = {0.01, 0.004}, dxv[2] = {-0.003, 0.008}, dhu[2], dhv[2];
    mf_filter_footprint_to_slope(jac, dxu, dxv, dhu, dhv);
    double hp[2], hm[2], h0[2];
    mf_vec3 xp = {x.x + 1e-3 * dxu[0], x.y + 1e-3 * dxu[1], 0}, xm = {x.x - 1e-3 * dxu[0], x.y - 1e-3 * dxu[1], 0};
    mf_filter_half_slope(mf_vec3_normalize(mf_vec3_sub(eye, xp)), mf_vec3_normalize(mf_vec3_sub(light, xp)), hp);
    mf_filter_half_slope(mf_vec3_normalize(mf_vec3_sub(eye, xm)), mf_vec3_normalize(mf_vec3_sub(light, xm)), hm);
    mf_filter_half_slope(mf_vec3_normalize(mf_vec3_sub(eye, x)), mf_vec3_normalize(mf_vec3_sub(light, x)), h0);
    double dnorm = hypot(dhu[0], dhu[1]);
    for (int i = 0; i < 2; ++i)
        CHECK_ABS((hp[i] - hm[i]) / 2e-3, dhu[i], 1e-6 * dnorm);
    double literal[2] = {jac[0][0] * dxu[0] + jac[1][0] * dxu[1], jac[0][1] * dxu[0] + jac[1][1] * dxu[1]};
    CHECK(hypot(literal[0] - dhu[0], literal[1] - dhu[1]) > 1e-2 * dnorm);
    /* domain */
    mf_filter_half_slope_jacobian_planar(mf_vec3_make(0, 0, -1), light, x, jac);
    CHECK(isnan(jac[0][0]) && isnan(jac[1][1]));
}

static void test_covariance_k4(mf_pcg32 *rng)
{
    /* correction C-K4 numbers: dh_u = (0.1, -0.05), dh_v = (0.02, 0.04). */
    double u[2] = {0.1, -0.05}, v[2] = {0.02, 0.04};
    mf_sym2 p = mf_filter_footprint_covariance(u, v, 1.0);
    CHECK_REL(p.xx, 0.0104, 4 * DBL_EPSILON);
    CHECK_REL(p.xy, -0.0042, 4 * DBL_EPSILON);
    CHECK_REL(p.yy, 0.0041, 4 * DBL_EPSILON);
    /* the printed Eq. 13 (rows dh_u, dh_v: J J^T, the Gram matrix) is [0.0125, 0; 0, 0.0020] */
    mf_sym2 gram = {u[0] * u[0] + u[1] * u[1], u[0] * v[0] + u[1] * v[1], v[0] * v[0] + v[1] * v[1]};
    CHECK_REL(gram.xx, 0.0125, 4 * DBL_EPSILON);
    CHECK_ABS(gram.xy, 0.0, 1e-18);
    CHECK(fabs(gram.xx - p.xx) > 1e-3 && fabs(gram.xy - p.xy) > 1e-3);
    /* same eigenvalues, different eigenvectors */
    mf_eigen2 ep = mf_sym2_eigen(p), eg = mf_sym2_eigen(gram);
    CHECK_REL(ep.l1, eg.l1, 1e-14);
    CHECK_REL(ep.l2, eg.l2, 1e-13);
    CHECK(fabs(ep.v1[0] * eg.v1[0] + ep.v1[1] * eg.v1[1]) < 0.99);
    /* Monte Carlo: the covariance of a dh_u + b dh_v, a, b ~ N(0, 1), is J^T J.  N = 200000:
     * the standard error of a sample (co)variance is sqrt(var(XY) / N); z = 5 (5 sigma, three
     * checks: false alarm < 2e-6), delta = 0. */
    const int n = 200000;
    double sxx = 0, sxy = 0, syy = 0, qxx = 0, qxy = 0, qyy = 0;
    for (int k = 0; k < n; ++k) {
        double a = mf_pcg32_next_normal(rng), b = mf_pcg32_next_normal(rng);
        double x = a * u[0] + b * v[0], y = a * u[1] + b * v[1];
        sxx += x * x; sxy += x * y; syy += y * y;
        qxx += x * x * x * x; qxy += x * x * y * y; qyy += y * y * y * y;
    }
    sxx /= n; sxy /= n; syy /= n;
    CHECK_MC(sxx, sqrt((qxx / n - sxx * sxx) / n), p.xx, 5.0, 0.0);
    CHECK_MC(sxy, sqrt((qxy / n - sxy * sxy) / n), p.xy, 5.0, 0.0);
    CHECK_MC(syy, sqrt((qyy / n - syy * syy) / n), p.yy, 5.0, 0.0);
    CHECK(fabs(sxy - gram.xy) > 10 * sqrt((qxy / n - sxy * sxy) / n)); /* the Gram matrix is rejected */
    /* C-K4's filtered density: Beckmann (0.2, 0.05) at h = (0, 0.05): 10.170 vs 10.542 (printed) */
    mf_gaussian_slopes gk = mf_filter_beckmann(0.2, 0.05, p), gg = mf_filter_beckmann(0.2, 0.05, gram);
    CHECK_ABS(mf_gaussian_p22(&gk, 0.0, 0.05), 10.170, 5e-4);
    CHECK_ABS(mf_gaussian_p22(&gg, 0.0, 0.05), 10.542, 1e-3); /* 10.5415 */
    /* s scales the covariance by s^2 (s = 0.5: one-pixel differentials, sigma = 0.5 pixel) */
    mf_sym2 ph = mf_filter_footprint_covariance(u, v, 0.5);
    CHECK_REL(ph.xx, 0.25 * p.xx, 2 * DBL_EPSILON);
    CHECK_REL(ph.xy, 0.25 * p.xy, 2 * DBL_EPSILON);
    double bad[2] = {NAN, 0};
    CHECK(isnan(mf_filter_footprint_covariance(bad, v, 1.0).xx));
    CHECK(isnan(mf_filter_footprint_covariance(u, v, -1.0).yy));
}

static void test_rect_and_clamps(void)
{
    double u[2] = {0.1, -0.05}, v[2] = {0.02, 0.04}, w[2];
    mf_filter_footprint_rect(u, v, w);
    CHECK_REL(w[0], 0.12, 2 * DBL_EPSILON);
    CHECK_REL(w[1], 0.09, 2 * DBL_EPSILON);
    /* tight: every corner +-u/2 +-v/2 inside, and each side touched by a corner */
    double maxx = 0, maxy = 0;
    for (int a = -1; a <= 1; a += 2)
        for (int b = -1; b <= 1; b += 2) {
            maxx = fmax(maxx, fabs(0.5 * a * u[0] + 0.5 * b * v[0]));
            maxy = fmax(maxy, fabs(0.5 * a * u[1] + 0.5 * b * v[1]));
        }
    CHECK_REL(2 * maxx, w[0], 2 * DBL_EPSILON);
    CHECK_REL(2 * maxy, w[1], 2 * DBL_EPSILON);
    /* Sec. 5.2: rescale the parallelogram so its longer diagonal is lambda */
    double bu[2] = {3.0, 1.0}, bv[2] = {1.0, -2.0};
    double sc = mf_filter_clamp_parallelogram(bu, bv, 1.0);
    CHECK_REL(sc, 1.0 / sqrt(17.0), 4 * DBL_EPSILON); /* |u + v| = sqrt(17), |u - v| = sqrt(13) */
    CHECK_REL(fmax(hypot(bu[0] + bv[0], bu[1] + bv[1]), hypot(bu[0] - bv[0], bu[1] - bv[1])), 1.0, 4 * DBL_EPSILON);
    double su[2] = {0.1, 0.0}, sv[2] = {0.0, 0.1};
    CHECK(mf_filter_clamp_parallelogram(su, sv, 1.0) == 1.0 && su[0] == 0.1);
    CHECK(mf_filter_clamp_parallelogram(su, sv, INFINITY) == 1.0);
    CHECK(isnan(mf_filter_clamp_parallelogram(su, sv, 0.0)) && isnan(su[0]));
    double rw[2] = {1e-6, 7.0};
    mf_filter_clamp_rect(rw, MF_FILTER_KAPLANYAN_LAMBDA, MF_FILTER_KAPLANYAN_EPSILON);
    CHECK(rw[0] == 1e-3 && rw[1] == 1.0);
    double rw2[2] = {0.0, 0.5};
    mf_filter_clamp_rect(rw2, 1.0, 0.0); /* epsilon = 0 allowed: mfkit's rectangle mean is stable */
    CHECK(rw2[0] == 0.0 && rw2[1] == 0.5);
    double rw3[2] = {0.1, 0.1};
    mf_filter_clamp_rect(rw3, 1e-3, 1e-2);
    CHECK(isnan(rw3[0]) && isnan(rw3[1]));
    /* what epsilon = 1e-3 costs at alpha = 1e-4: the peak drops ~33x (header's claim) */
    double ratio = (1.0 / (MF_PI * 1e-8)) / mf_filter_ggx_rect_mean(1e-4, 1e-4, 0, 0, 1e-3, 1e-3);
    CHECK(ratio > 30.0 && ratio < 36.0);
}

static void test_beckmann_k5_k6(void)
{
    /* correction C-K6 (correct formula): B' = diag(alpha^2/2) + P is the exact convolution. Reference:
     * 2D Gauss-Legendre convolution (converged to ~1e-14; tolerance 1e-11). */
    double u[2] = {0.1, -0.05}, v[2] = {0.02, 0.04};
    mf_sym2 p = mf_filter_footprint_covariance(u, v, 1.0);
    mf_gaussian_slopes beck = mf_gaussian_from_beckmann(0.2, 0.05);
    mf_gaussian_slopes filt = mf_filter_beckmann(0.2, 0.05, p);
    const double pts[5][2] = {{0, 0}, {0, 0.05}, {0.1, -0.07}, {-0.25, 0.1}, {0.3, 0.2}};
    for (int k = 0; k < 5; ++k)
        CHECK_REL(mf_gaussian_p22(&filt, pts[k][0], pts[k][1]), convolve_gaussian_with_p(&beck, p, pts[k][0], pts[k][1]),
                  1e-11);
    /* rank-one P (one footprint vector): still a valid Gaussian */
    double z[2] = {0.0, 0.0};
    mf_sym2 p1 = mf_filter_footprint_covariance(u, z, 1.0);
    mf_gaussian_slopes f1 = mf_filter_beckmann(0.2, 0.3, p1);
    mf_gaussian_slopes b1 = mf_gaussian_from_beckmann(0.2, 0.3);
    CHECK(mf_gaussian_valid(&f1));
    CHECK_REL(mf_gaussian_p22(&f1, 0.1, 0.1), convolve_gaussian_with_p(&b1, p1, 0.1, 0.1), 1e-11);
    /* "evaluate Beckmann with 2B'": for a diagonal B' the Beckmann P22 with alpha^2 = 2 B'_ii */
    mf_sym2 pd = {0.01, 0.0, 0.0004};
    mf_gaussian_slopes fd = mf_filter_beckmann(0.1, 0.02, pd);
    mf_ndf bd = mf_ndf_make(MF_NDF_BECKMANN, sqrt(2 * fd.var_x), sqrt(2 * fd.var_y));
    CHECK_REL(mf_gaussian_p22(&fd, 0.05, -0.01), mf_ndf_p22(bd, 0.05, -0.01), 16 * DBL_EPSILON);
    /* Eq. 21: LEAN statistics (non-centred, correlated) + P, against the numerical convolution */
    mf_gaussian_slopes lean = {0.1, -0.05, 0.01, 0.02, 0.005};
    mf_gaussian_slopes lf = mf_filter_gaussian_add(&lean, p);
    CHECK(lf.mean_x == 0.1 && lf.mean_y == -0.05);
    for (int k = 0; k < 5; ++k)
        CHECK_REL(mf_gaussian_p22(&lf, pts[k][0], pts[k][1]), convolve_gaussian_with_p(&lean, p, pts[k][0], pts[k][1]),
                  1e-11);
    /* domain */
    mf_sym2 notpsd = {0.01, 0.02, 0.01};
    CHECK(isnan(mf_filter_beckmann(0.1, 0.1, notpsd).var_x));
    CHECK(isnan(mf_filter_beckmann(-0.1, 0.1, pd).var_x));
    mf_gaussian_slopes badg = {0, 0, -1, 1, 0};
    CHECK(isnan(mf_filter_gaussian_add(&badg, pd).var_x));

    /* correction C-K5 (note): the GGX proxy sqrt(alpha^2 + dh^2) is not the Beckmann covariance sum:
     * a box of full width dh (variance dh^2/12) gives alpha'^2 = alpha^2 + dh^2/6, a standard-
     * deviation vector of length dh gives alpha^2 + 2 dh^2. */
    double a = 0.1, dh = 0.05;
    mf_sym2 pbox = {dh * dh / 12, 0, dh * dh / 12};
    mf_gaussian_slopes fb = mf_filter_beckmann(a, a, pbox);
    CHECK_REL(2 * fb.var_x, a * a + dh * dh / 6, 4 * DBL_EPSILON);
    double sdv[2] = {dh, 0}, sdz[2] = {0, 0};
    mf_gaussian_slopes fs = mf_filter_beckmann(a, a, mf_filter_footprint_covariance(sdv, sdz, 1.0));
    CHECK_REL(2 * fs.var_x, a * a + 2 * dh * dh, 4 * DBL_EPSILON);
    double approx_sq = pow(mf_filter_ggx_proxy_alpha_approx(a, dh), 2);
    CHECK(fabs(2 * fb.var_x - approx_sq) > 0.1 * dh * dh && fabs(2 * fs.var_x - approx_sq) > 0.1 * dh * dh);
}

/* 50-digit values of the mean over [x0, x1] x [y0, y1] (mpmath, same antiderivative). */
static const double rect_refs[][7] = {
    {0.0001, 0.0001, -5e-09, 5e-09, -5e-09, 5e-09, 31830988.51227576908},
    {0.0001, 0.0001, -500.0, 500.0, -500.0, 500.0, 9.999999999999672676e-7},
    {0.0001, 0.0001, 0.5, 0.5000000009313226, -0.25, -0.24999999906867743, 3.2594930210574368516e-8},
    {0.0001, 0.01, 1000.0, 1001.0, -3.0, -2.0, 3.1767432545306073804e-23},
    {1.0, 1.0, 0.75, 0.7500000074505806, -0.5, -0.4999999925494194, 0.096893377759294701675},
    {1.0, 1.0, -1000.0, 1000.0, 0.0, 1e-08, 0.00024999999989389681943},
    {0.3, 0.05, 0.0, 1000.0, 0.0, 1000.0, 2.4999998870627367687e-7},
    {0.01, 0.001, -0.02, 0.03, 0.004, 0.0041, 84.845005888904148251},
    {0.001, 0.001, 0.001, 0.002, -1000.0, 1000.0, 0.04683010245334208746},
    {0.5, 0.0001, -2.0, -1.0, 0.0, 9.5367431640625e-07, 85.884169646532488101},
};

static void test_rect_mean(void)
{
    /* (a) 50-digit references: 32 eps (closed forms; the semi-analytic path is within this too). */
    for (size_t k = 0; k < sizeof rect_refs / sizeof rect_refs[0]; ++k) {
        const double *r = rect_refs[k];
        CHECK_REL(mf_filter_ggx_rect_mean_bounds(r[0], r[1], r[2], r[3], r[4], r[5]), r[6], 32 * DBL_EPSILON);
    }
    /* (b) the grid against nested adaptive Gauss-Kronrod: alpha 1e-4..1 (anisotropic too),
     * sides 1e-8..1e3 per axis, centred / near the peak / off-centre / far / corner on the peak.
     * Tolerance: 4x the outer error estimate + 2e-13 (twice the inner rel. tol.) + 64 eps (ours). */
    const double alphas[6][2] = {{1e-4, 1e-4}, {1e-4, 1e-2}, {1e-2, 1e-3}, {0.3, 0.3}, {1.0, 0.05}, {1.0, 1.0}};
    const double sides[6] = {1e-8, 1e-5, 1e-3, 0.1, 1.0, 1e3};
    double worst = 0.0, worst_case[6] = {0};
    int failures = 0, count = 0;
    for (int ai = 0; ai < 6; ++ai)
        for (int si = 0; si < 6; ++si)
            for (int sj = 0; sj < 6; ++sj)
                for (int pi = 0; pi < 7; ++pi) {
                    double ax = alphas[ai][0], ay = alphas[ai][1], wx = sides[si], wy = sides[sj];
                    double c[7][2] = {{0, 0},        {0.37 * ax, -1.3 * ay}, {5 * ax, 3 * ay}, {0.5, -0.25},
                                      {-30.0, 7.0}, {0.5 * wx, 0.5 * wy},   {0.25 * wx, 0.0}};
                    double x0 = c[pi][0] - 0.5 * wx, x1 = c[pi][0] + 0.5 * wx;
                    double y0 = c[pi][1] - 0.5 * wy, y1 = c[pi][1] + 0.5 * wy;
                    double err;
                    double ref = quad_rect_mean(ax, ay, x0, x1, y0, y1, &err, &failures);
                    double got = mf_filter_ggx_rect_mean_bounds(ax, ay, x0, x1, y0, y1);
                    CHECK_ABS(got, ref, 4 * err + (2e-13 + 64 * DBL_EPSILON) * ref);
                    double rel = fabs(got - ref) / ref;
                    ++count;
                    if (rel > worst) {
                        worst = rel;
                        double wc[6] = {ax, ay, x0, x1, y0, y1};
                        for (int q = 0; q < 6; ++q)
                            worst_case[q] = wc[q];
                    }
                }
    CHECK(failures == 0);
    printf("rect mean vs nested adaptive quadrature: %d rectangles, worst relative error %.3g at alpha (%g, %g), "
           "[%g, %g] x [%g, %g]\n",
           count, worst, worst_case[0], worst_case[1], worst_case[2], worst_case[3], worst_case[4], worst_case[5]);

    /* (c) centre/width form = bounds form when the ends are exact (dyadic centre and width) */
    for (int e = 0; e <= 60; e += 4) {
        double w = ldexp(1.0, -e);
        CHECK_REL(mf_filter_ggx_rect_mean(0.01, 0.003, 0.375, -0.125, w, 0.5 * w),
                  mf_filter_ggx_rect_mean_bounds(0.01, 0.003, 0.375 - 0.5 * w, 0.375 + 0.5 * w, -0.125 - 0.25 * w,
                                                 -0.125 + 0.25 * w),
                  4 * DBL_EPSILON);
    }
    /* (d) tiny rectangles tend to the point value P22 at the centre, continuously */
    mf_ndf g = mf_ndf_make(MF_NDF_GGX, 1e-4, 3e-4);
    const double cs[4][2] = {{0, 0}, {1e-4, -2e-4}, {0.3, 0.1}, {-1e3, 2e2}};
    for (int k = 0; k < 4; ++k) {
        double p = mf_ndf_p22(g, cs[k][0], cs[k][1]);
        CHECK_REL(mf_filter_ggx_rect_mean(1e-4, 3e-4, cs[k][0], cs[k][1], 0.0, 0.0), p, 4 * DBL_EPSILON);
        CHECK_REL(mf_filter_ggx_rect_mean(1e-4, 3e-4, cs[k][0], cs[k][1], 1e-17, 1e-17), p, 4 * DBL_EPSILON);
        /* across the midpoint threshold (1e-9 alpha): the true change is ~1e-18 relative */
        double below = mf_filter_ggx_rect_mean(1e-4, 3e-4, cs[k][0], cs[k][1], 0.999e-13, 2e-13);
        double above = mf_filter_ggx_rect_mean(1e-4, 3e-4, cs[k][0], cs[k][1], 1.001e-13, 2e-13);
        CHECK_REL(below, above, 16 * DBL_EPSILON);
        CHECK_REL(above, p, 16 * DBL_EPSILON);
        /* width 0 along one axis: the 1D mean (a strip), against 1D adaptive quadrature */
        quad_ctx qc = {1e-4, 3e-4, cs[k][0] - 0.5e-3, cs[k][0] + 0.5e-3, cs[k][1], 0, 1e-14};
        double err;
        double strip = integrate_split(p22_ggx_x, &qc, qc.x0, qc.x1, 1e-14, &err) / (qc.x1 - qc.x0);
        CHECK_REL(mf_filter_ggx_rect_mean(1e-4, 3e-4, cs[k][0], cs[k][1], 1e-3, 0.0), strip, 1e-13);
    }
    /* (e) the antiderivative: F(0, t) = F(s, 0) = 0, F(inf, inf) = 1/4, and differences = mass */
    CHECK(mf_filter_ggx_rect_antiderivative(0.1, 0.2, 0.0, 0.3) == 0.0);
    CHECK_REL(mf_filter_ggx_rect_antiderivative(0.1, 0.2, 1e200, 1e200), 0.25, 4 * DBL_EPSILON);
    double f = mf_filter_ggx_rect_antiderivative(0.1, 0.2, 0.3, 0.5);
    CHECK_REL(f, mf_filter_ggx_rect_mean_bounds(0.1, 0.2, 0.0, 0.3, 0.0, 0.5) * 0.15, 16 * DBL_EPSILON);
    /* (f) domain */
    CHECK(isnan(mf_filter_ggx_rect_mean(0.0, 0.1, 0, 0, 0.1, 0.1)));
    CHECK(isnan(mf_filter_ggx_rect_mean(0.1, 0.1, 0, 0, -0.1, 0.1)));
    CHECK(isnan(mf_filter_ggx_rect_mean(0.1, 0.1, NAN, 0, 0.1, 0.1)));
    CHECK(isnan(mf_filter_ggx_rect_mean(0.1, 0.1, 0, 0, INFINITY, 0.1)));
    /* stretched coordinate 1e200 (beyond 1e100: the far-field scaling): P22 ~ 1e-600 there, which
     * underflows to 0 (it was NaN before) */
    CHECK(mf_filter_ggx_rect_mean(1e-200, 0.1, 1.0, 0, 0.1, 0.1) == 0.0);
    CHECK(isnan(mf_filter_ggx_rect_mean_bounds(0.1, 0.1, 1.0, 0.0, 0, 1)));
}

static void test_k1_appendix_a(void)
{
    /* correction C-K1: the printed combination (half-width limits, 1/(2 pi dh_s dh_t)) is exactly 4x the
     * mean over [h -+ dh]; its sign pattern and phi are right (1/(8 pi ...) gives the mean).
     * Moderate rectangles (no cancellation in the literal formula): 1e-13. */
    const double cases[4][6] = {{0.1, 0.1, 0.0, 0.0, 0.05, 0.05},
                                {0.2, 0.05, 0.1, -0.03, 0.07, 0.02},
                                {0.01, 0.03, -0.02, 0.05, 0.015, 0.04},
                                {1.0, 0.5, 0.7, 0.2, 0.9, 0.3}};
    for (int k = 0; k < 4; ++k) {
        const double *c = cases[k];
        double printed = appendix_a_printed(c[0], c[1], c[2], c[3], c[4], c[5]);
        double mean = mf_filter_ggx_rect_mean(c[0], c[1], c[2], c[3], 2 * c[4], 2 * c[5]);
        CHECK_REL(printed, 4.0 * mean, 1e-13);
        CHECK(fabs(printed / mean - 1.0) > 1.0); /* the printed form fails */
        CHECK_REL(printed / 4.0, mean, 1e-13);   /* = 1/(8 pi dh_s dh_t) normalisation */
    }
}

/* Root of the peak equation 1/(pi x^2) = C (rectangle mean of the square of width dh) by bisection
 * on [0.999 alpha, 1.01 sqrt(alpha^2 + dh^2)] (the left side decreases in x) to 1e-15 relative. */
static double bisect_proxy(double a, double dh)
{
    double c = mf_filter_ggx_rect_mean(a, a, 0, 0, dh, dh);
    double lo = a * 0.999, hi = 1.01 * hypot(a, dh);
    for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
        double mid = 0.5 * (lo + hi);
        if (1.0 / (MF_PI * mid * mid) > c)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

static void test_proxy(void)
{
    /* (a) closed form vs bisection on the peak equation 1/(pi a^2) = rectangle mean, to 1e-12 */
    const double as[5] = {1e-4, 1e-3, 0.01, 0.2, 1.0};
    const double dhs[8] = {1e-6, 1e-4, 1e-3, 0.01, 0.1, 1.0, 10.0, 1e3};
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 8; ++j) {
            double a = as[i], dh = dhs[j];
            double exact = mf_filter_ggx_proxy_alpha(a, dh);
            CHECK_REL(exact, bisect_proxy(a, dh), 1e-12);
            /* the literal closed form of C-K3 (no rearrangement) where it does not cancel */
            if (dh >= 1e-3 * a) {
                double q = sqrt(4 * a * a + dh * dh);
                CHECK_REL(exact * exact, dh * q / (4 * atan(dh / q)), 16 * DBL_EPSILON);
            }
        }
    /* (b) asymptotics: alpha^2 + dh^2/3 for dh << alpha (next term O(dh^4/alpha^2)); dh/sqrt(pi) */
    CHECK_REL(pow(mf_filter_ggx_proxy_alpha(0.3, 3e-7), 2), 0.09 + 9e-14 / 3, 8 * DBL_EPSILON);
    CHECK_REL(pow(mf_filter_ggx_proxy_alpha(1e-4, 1e-12), 2), 1e-8 + 1e-24 / 3, 8 * DBL_EPSILON);
    CHECK_REL(mf_filter_ggx_proxy_alpha(1e-4, 1e4), 1e4 / MF_SQRT_PI, 8 * DBL_EPSILON);
    CHECK(mf_filter_ggx_proxy_alpha(0.2, 0.0) == 0.2);
    CHECK(isnan(mf_filter_ggx_proxy_alpha(0.0, 0.1)) && isnan(mf_filter_ggx_proxy_alpha(0.1, -1.0)));
    /* (c) correction C-K3: the printed (extracted) Eq. 20 is far off somewhere on the grid */
    double worst_printed = 0.0;
    for (int i = 0; i < 5; ++i)
        for (int j = 0; j < 8; ++j)
            worst_printed = fmax(worst_printed, fabs(eq20_printed(as[i], dhs[j]) / mf_filter_ggx_proxy_alpha(as[i], dhs[j]) - 1));
    CHECK(worst_printed > 0.5);
    /* (d) accuracy of the paper's fit sqrt(alpha^2 + dh^2) over alpha in [1e-3, 1], dh in [1e-3, 10]
     * (log grids, 61 x 81 points): it always overestimates; the values of C-K3 at dh = 0.1 alpha, alpha. */
    double max_err = 0.0, sum_err = 0.0, max_a = 0, max_dh = 0, max_exact_err = 0.0;
    int n = 0;
    for (int i = 0; i <= 60; ++i)
        for (int j = 0; j <= 80; ++j) {
            double a = pow(10.0, -3.0 + 3.0 * i / 60.0), dh = pow(10.0, -3.0 + 4.0 * j / 80.0);
            double exact = mf_filter_ggx_proxy_alpha(a, dh), approx = mf_filter_ggx_proxy_alpha_approx(a, dh);
            double root = bisect_proxy(a, dh);
            CHECK_REL(exact, root, 1e-12);
            max_exact_err = fmax(max_exact_err, fabs(exact - root) / root);
            double rel = (approx - exact) / exact;
            CHECK(rel >= 0.0);
            sum_err += rel;
            ++n;
            if (rel > max_err) { max_err = rel; max_a = a; max_dh = dh; }
        }
    CHECK(max_err < MF_SQRT_PI - 1.0 && max_err > 0.77);
    CHECK_REL(mf_filter_ggx_proxy_alpha_approx(0.1, 0.01) / mf_filter_ggx_proxy_alpha(0.1, 0.01) - 1, 0.0033, 0.01);
    CHECK_REL(mf_filter_ggx_proxy_alpha_approx(0.1, 0.1) / mf_filter_ggx_proxy_alpha(0.1, 0.1) - 1, 0.227, 0.01);
    printf("GGX proxy over alpha in [1e-3, 1], dh in [1e-3, 10] (%d points): exact closed form vs bisection: "
           "max relative error %.3g; sqrt(alpha^2 + dh^2) vs exact: max relative error %.4f (alpha %g, dh %g), "
           "mean %.4f\n",
           n, max_exact_err, max_err, max_a, max_dh, sum_err / n);
    /* (e) per-axis (paper) and joint solve */
    double pa[2], pj[2];
    mf_filter_ggx_proxy_alpha_per_axis(0.05, 0.05, 0.02, 0.02, pa);
    CHECK(mf_filter_ggx_proxy_alpha_joint(0.05, 0.05, 0.02, 0.02, pj) == MF_OK);
    CHECK_REL(pj[0], pa[0], 8 * DBL_EPSILON); /* isotropic square: both are the exact solution */
    CHECK_REL(pj[1], pa[1], 8 * DBL_EPSILON);
    CHECK(mf_filter_ggx_proxy_alpha_joint(0.02, 0.005, 0.0, 0.0, pj) == MF_OK);
    CHECK_REL(pj[0], 0.02, 8 * DBL_EPSILON);
    CHECK_REL(pj[1], 0.005, 8 * DBL_EPSILON);
    const double jc[4][4] = {{0.01, 0.01, 0.05, 0.001}, {0.1, 0.002, 0.01, 0.03}, {1e-3, 0.3, 0.5, 1e-4}, {0.2, 0.2, 1.0, 0.0}};
    for (int k = 0; k < 4; ++k) {
        double ax = jc[k][0], ay = jc[k][1], wx = jc[k][2], wy = jc[k][3];
        CHECK(mf_filter_ggx_proxy_alpha_joint(ax, ay, wx, wy, pj) == MF_OK);
        double c = mf_filter_ggx_rect_mean(ax, ay, 0, 0, wx, wy);
        CHECK_REL(1.0 / (MF_PI * pj[0] * pj[1]), c, 8 * DBL_EPSILON); /* Eq. 19 holds exactly */
        /* equation (M): the marginal peaks of the filtered density, by quadrature of the
         * rectangle mean over the other axis (rel. tol. 1e-12), equal 1/sqrt(4 alpha^2 + w^2) */
        double mx = filtered_marginal_peak(ax, ay, wx, wy, 0), my = filtered_marginal_peak(ax, ay, wx, wy, 1);
        CHECK_REL(mx, 1.0 / hypot(2 * ax, wx), 1e-10);
        CHECK_REL(my, 1.0 / hypot(2 * ay, wy), 1e-10);
        CHECK_REL(pj[0] / pj[1], my / mx, 1e-10);
        /* the paper's per-axis pair misses Eq. 19 for non-square or anisotropic cases */
        mf_filter_ggx_proxy_alpha_per_axis(ax, ay, wx, wy, pa);
        CHECK(fabs(1.0 / (MF_PI * pa[0] * pa[1]) / c - 1.0) > 1e-3);
    }
    CHECK(mf_filter_ggx_proxy_alpha_joint(-1.0, 0.1, 0.1, 0.1, pj) == MF_ERR_DOMAIN && isnan(pj[0]));
}

int main(void)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20160618), 5);
    test_half_slope_and_signs(&rng);
    test_jacobian_and_footprint();
    test_covariance_k4(&rng);
    test_rect_and_clamps();
    test_beckmann_k5_k6();
    test_rect_mean();
    test_k1_appendix_a();
    test_proxy();
    MF_TEST_MAIN_END();
}
