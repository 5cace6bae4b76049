/* mf_quad.c -- Gauss-Legendre rules and adaptive Gauss-Kronrod (see mf_quad.h). */
#include "mfkit/mf_quad.h"
#include "mf_quad_internal.h"

#include <float.h>

mf_status mf_quad_gauss_legendre(int n, double *nodes, double *weights)
{
    if (n < 1 || n > 1024 || !nodes || !weights)
        return MF_ERR_DOMAIN;
    int half = (n + 1) / 2;
    for (int i = 0; i < half; ++i) {
        /* Tricomi's initial guess for the i-th largest root, then Newton on P_n. */
        double x = cos(MF_PI * (i + 0.75) / (n + 0.5));
        double dp = 1.0;
        for (int it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = x;
            for (int k = 2; k <= n; ++k) {
                double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            if (n == 1) { p1 = x; p0 = 1.0; }
            /* P_n'(x) = n (x P_n - P_{n-1}) / (x^2 - 1) */
            dp = n * (x * p1 - p0) / (x * x - 1.0);
            double dx = p1 / dp;
            x -= dx;
            if (fabs(dx) <= 2.0 * DBL_EPSILON * fabs(x) + 1e-300)
                break;
        }
        /* recompute the derivative at the converged root for the weight */
        double p0 = 1.0, p1 = x;
        for (int k = 2; k <= n; ++k) {
            double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
            p0 = p1;
            p1 = p2;
        }
        dp = (n == 1) ? 1.0 : n * (x * p1 - p0) / (x * x - 1.0);
        double w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[n - 1 - i] = x;
        nodes[i] = -x;
        weights[i] = weights[n - 1 - i] = w;
    }
    if (n % 2 == 1)
        nodes[n / 2] = 0.0;
    return MF_OK;
}

/* QUADPACK qk15 abscissae (Kronrod, positive half, descending) and weights (mf_quad_internal.h). */
const double mf_quad_qk15_xgk[8] = {
    0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
    0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
    0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
    0.207784955007898467600689403773245, 0.000000000000000000000000000000000};
const double mf_quad_qk15_wgk[8] = {
    0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
    0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
    0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
    0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
const double mf_quad_qk15_wg[4] = {
    0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
    0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

typedef struct {
    mf_fn1 f;
    void *user;
    double a;
    int infinite;
} qctx;

static double qeval(const qctx *c, double t)
{
    if (!c->infinite)
        return c->f(t, c->user);
    /* x = a + t / (1 - t), dx/dt = 1 / (1 - t)^2 */
    double omt = 1.0 - t;
    return c->f(c->a + t / omt, c->user) / (omt * omt);
}

static int qk15(const qctx *c, double a, double b, double *val, double *err)
{
    double center = 0.5 * (a + b), hl = 0.5 * (b - a);
    double fc = qeval(c, center);
    double rk = fc * mf_quad_qk15_wgk[7], rg = fc * mf_quad_qk15_wg[3];
    for (int j = 0; j < 7; ++j) {
        double dx = hl * mf_quad_qk15_xgk[j];
        double f1 = qeval(c, center - dx), f2 = qeval(c, center + dx);
        rk += mf_quad_qk15_wgk[j] * (f1 + f2);
        if (j % 2 == 1)
            rg += mf_quad_qk15_wg[j / 2] * (f1 + f2);
    }
    *val = rk * hl;
    *err = fabs((rk - rg) * hl);
    return isfinite(*val) && isfinite(*err);
}

typedef struct {
    double a, b, val, err;
} qinterval;

mf_status mf_quad_adaptive(mf_fn1 f, void *user, double a, double b, double abs_tol, double rel_tol,
                           int max_intervals, mf_result *out)
{
    out->val = NAN;
    out->err = NAN;
    if (!f || !(a == a) || !(b > a) || isinf(a) || max_intervals < 1 || max_intervals > MF_QUAD_MAX_INTERVALS
        || !(abs_tol >= 0.0) || !(rel_tol >= 0.0))
        return MF_ERR_DOMAIN;
    qctx c = {f, user, a, isinf(b)};
    double lo = c.infinite ? 0.0 : a, hi = c.infinite ? 1.0 : b;

    qinterval iv[MF_QUAD_MAX_INTERVALS];
    int n = 1;
    iv[0].a = lo;
    iv[0].b = hi;
    if (!qk15(&c, lo, hi, &iv[0].val, &iv[0].err))
        return MF_ERR_DOMAIN;
    for (;;) {
        /* Sum in interval order each time: the result does not depend on summation history. */
        double val = 0.0, err = 0.0;
        int worst = 0;
        for (int i = 0; i < n; ++i) {
            val += iv[i].val;
            err += iv[i].err;
            if (iv[i].err > iv[worst].err)
                worst = i;
        }
        out->val = val;
        out->err = err;
        double tol = fmax(abs_tol, rel_tol * fabs(val));
        if (err <= tol)
            return MF_OK;
        if (n >= max_intervals)
            return MF_ERR_NO_CONVERGENCE;
        double mid = 0.5 * (iv[worst].a + iv[worst].b);
        if (!(mid > iv[worst].a && mid < iv[worst].b))
            return MF_ERR_NO_CONVERGENCE; /* interval too small to split */
        qinterval left = {iv[worst].a, mid, 0, 0}, right = {mid, iv[worst].b, 0, 0};
        if (!qk15(&c, left.a, left.b, &left.val, &left.err) || !qk15(&c, right.a, right.b, &right.val, &right.err)) {
            out->val = NAN;
            return MF_ERR_DOMAIN;
        }
        iv[worst] = left;
        iv[n++] = right;
    }
}
