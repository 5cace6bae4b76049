/* mf_albedo.c -- the microfacet albedo by panels split at the horizon of wi (see mf_albedo.h). */
#include "mfkit/mf_albedo.h"
#include "mfkit/mf_quad.h"

#include <float.h>
#include <stddef.h>

#define N_LO 8            /* points per panel of the estimate rule */
#define N_HI 12           /* points per panel of the value rule */
#define GRADE 0.2        /* geometric ratio of graded panels */
#define MAX_LEVELS 48     /* graded panels per interval, at most */
#define BECKMANN_R_CUT 7.0 /* exp(-49) r^2 (1 + |k| r) < 1e-17 for tan(theta_o) < 1e4 */
/* A boundary layer whose whole contribution is below this is not graded towards: its
 * integral is then within the rule's error anyway. */
#define LAYER_NEGLIGIBLE 1e-15
/* The layer where G1(wi) turns over is ~alpha wide in wi.z; in the ray's coordinate its width
 * is alpha / |d wi.z / dx| at the end only where wi.z is close to linear over it.  It is not
 * (the curvature of wi.z(x) at the exit is large at grazing views): measured on a 100 x 100 grid
 * the linear estimate is up to ~100 times too wide, so the grading goes 100 times further. */
#define LAYER_FACTOR 0.01

typedef struct {
    double x[N_HI], w[N_HI];
    int n;
} gl_rule;

typedef struct {
    mf_ndf ndf;
    mf_g2_form g2;
    mf_fresnel fresnel;
    int schlick;  /* 1: the two Schlick moments, 0: F(wo.wm) */
    mf_vec3 wo;
    double lambda_o;
    double layer;  /* width of the G1 turnover in wi.z: min(alpha_x, alpha_y, 1) */
    gl_rule lo, hi;
} actx;

static int make_rule(gl_rule *r, int n)
{
    r->n = n;
    return mf_quad_gauss_legendre(n, r->x, r->w) == MF_OK ? 0 : -1;
}

/* Breakpoints of [a, b] graded towards b: panels [a, b - L g], [b - L g, b - L g^2], ...,
 * [b - L g^K, b] with L = b - a and K the smallest with L g^K <= delta (K = 0: one panel),
 * and the first panel cut into `base` equal ones.  Returns the number of breakpoints (panels + 1). */
static int graded(double a, double b, double delta, int base, double *bp, int cap)
{
    double len = b - a;
    int levels = 0;
    if (delta < len)
        levels = (int)ceil(log(delta / len) / log(GRADE));
    if (levels > MAX_LEVELS)
        levels = MAX_LEVELS;
    if (levels < 0)
        levels = 0;
    if (base < 1)
        base = 1;
    if (levels + base + 1 > cap)
        base = 1, levels = cap - 2;
    int n = 0;
    double first_end = levels > 0 ? b - len * GRADE : b;
    for (int i = 0; i < base; ++i)
        bp[n++] = a + (first_end - a) * i / base;
    double g = GRADE;
    for (int k = 1; k < levels; ++k) {
        bp[n++] = b - len * g;
        g *= GRADE;
    }
    if (levels > 0)
        bp[n++] = b - len * g;
    bp[n++] = b;
    return n;
}

/* The integrand at inner coordinate x on the ray of stretched direction (sx, sy) = S e, with
 * k = (S e).wo_xy / wo.z: adds weight * value to acc[0] (and acc[1]). */
static void integrand(const actx *c, double x, double sx, double sy, double k, double weight, double *acc)
{
    mf_vec3 v;
    double meas;
    if (c->ndf.type == MF_NDF_GGX) {
        /* r = tan t: P22 dp = sin t cos t dt dphi / pi, and (1 + k r) sin t cos t = sin t cos t
         * + k sin^2 t */
        double st = sin(x), ct = cos(x);
        v = mf_vec3_make(st * sx, st * sy, ct);
        meas = (st * ct + k * st * st) * MF_INV_PI;
    } else {
        /* P22 dp = exp(-r^2) r dr dphi / pi */
        v = mf_vec3_make(x * sx, x * sy, 1.0);
        meas = exp(-x * x) * (x + k * x * x) * MF_INV_PI;
    }
    mf_vec3 wm = mf_vec3_normalize(v);
    double oh = mf_vec3_dot(c->wo, wm);
    if (!(oh > 0.0))
        return;
    mf_vec3 wi = mf_vec3_sub(mf_vec3_scale(wm, 2.0 * oh), c->wo);
    if (!(wi.z > 0.0))
        return;
    double li = mf_smith_lambda(c->ndf, wi);
    double g2 = c->g2 == MF_G2_SEPARABLE ? 1.0 / ((1.0 + c->lambda_o) * (1.0 + li)) : 1.0 / (1.0 + c->lambda_o + li);
    double val = weight * meas * g2;
    if (c->schlick) {
        double m = 1.0 - oh, m5 = m * m * m * m * m;
        acc[0] += val * (1.0 - m5);
        acc[1] += val * m5;
    } else {
        acc[0] += val * mf_fresnel_eval(c->fresnel, oh);
    }
}

/* The integral along the ray of angle phi (per unit phi), by rule r on graded panels. */
static void ray(const actx *c, double phi, const gl_rule *r, double *acc)
{
    const mf_ndf n = c->ndf;
    const mf_vec3 wo = c->wo;
    double sx = n.alpha_x * cos(phi), sy = n.alpha_y * sin(phi);
    double q = sx * sx + sy * sy;
    double k = (sx * wo.x + sy * wo.y) / wo.z;
    double root = sqrt(k * k + q);
    /* the ray leaves the disk of wi.z > 0 at r_max: the positive root of q r^2 - 2 k r - 1 */
    double rmax = k >= 0.0 ? (k + root) / q : 1.0 / (root - k);
    const int ggx = n.type == MF_NDF_GGX;
    double end = ggx ? atan(rmax) : fmin(rmax, BECKMANN_R_CUT);
    double delta = end; /* the scale of the nearest singularity to the end of the interval */
    if (ggx || rmax < BECKMANN_R_CUT) {
        /* d(wi.z)/dx at the end: wi.z = wo.z (2 N / L2 - 1) */
        double nn, dn, l2, dl2, wmag;
        if (ggx) {
            double st = sin(end), ct = cos(end), s2 = sin(2.0 * end), c2 = cos(2.0 * end);
            nn = k * st * ct + ct * ct;
            dn = k * c2 - s2;
            l2 = q * st * st + ct * ct;
            dl2 = (q - 1.0) * s2;
            wmag = fabs(st * ct + k * st * st) * MF_INV_PI;
        } else {
            nn = k * end + 1.0;
            dn = k;
            l2 = q * end * end + 1.0;
            dl2 = 2.0 * q * end;
            wmag = exp(-end * end) * fabs(end + k * end * end) * MF_INV_PI;
        }
        double dc = fabs(2.0 * wo.z * (dn * l2 - nn * dl2) / (l2 * l2));
        if (dc > 0.0)
            delta = LAYER_FACTOR * c->layer / dc;
        if (ggx) /* the micro-normal turns horizontal (|v|^2 = 0) at t = pi/2 +- i ~sqrt(q) */
            delta = fmin(delta, (0.5 * MF_PI - end) + sqrt(q));
        double negligible = LAYER_NEGLIGIBLE / (2.0 * MF_PI * wmag + 1e-300);
        delta = fmax(delta, negligible);
    } else {
        delta = end;
    }
    double bp[MAX_LEVELS + 8];
    int base = ggx ? 2 : (int)ceil(end / 0.5); /* measured: 1-wide panels left 7.5e-7 at alpha 1 */
    int nb = graded(0.0, end, delta, base, bp, MAX_LEVELS + 8);
    for (int p = 0; p + 1 < nb; ++p) {
        double a = bp[p], h = 0.5 * (bp[p + 1] - bp[p]);
        for (int j = 0; j < r->n; ++j)
            integrand(c, a + h * (1.0 + r->x[j]), sx, sy, k, h * r->w[j], acc);
    }
}

/* The outer integral over [a, b] in phi on the given panels, both rules. */
static void outer_panels(const actx *c, const double *bp, int nb, double mult, double *lo, double *hi)
{
    for (int p = 0; p + 1 < nb; ++p) {
        double a = bp[p], h = 0.5 * (bp[p + 1] - bp[p]);
        for (int j = 0; j < c->hi.n; ++j) {
            double acc[2] = {0.0, 0.0};
            ray(c, a + h * (1.0 + c->hi.x[j]), &c->hi, acc);
            hi[0] += mult * h * c->hi.w[j] * acc[0];
            hi[1] += mult * h * c->hi.w[j] * acc[1];
        }
        for (int j = 0; j < c->lo.n; ++j) {
            double acc[2] = {0.0, 0.0};
            ray(c, a + h * (1.0 + c->lo.x[j]), &c->lo, acc);
            lo[0] += mult * h * c->lo.w[j] * acc[0];
            lo[1] += mult * h * c->lo.w[j] * acc[1];
        }
    }
}

/* [a, b] graded towards a AND b (split in the middle). */
static void outer_two_sided(const actx *c, double a, double b, double delta, double mult, double *lo, double *hi)
{
    double bp[MAX_LEVELS + 8], m = 0.5 * (a + b);
    int nb = graded(m, b, delta, 1, bp, MAX_LEVELS + 8);
    outer_panels(c, bp, nb, mult, lo, hi);
    nb = graded(-m, -a, delta, 1, bp, MAX_LEVELS + 8); /* mirrored: graded towards a */
    for (int i = 0; i < nb / 2; ++i) {
        double t = bp[i];
        bp[i] = bp[nb - 1 - i];
        bp[nb - 1 - i] = t;
    }
    for (int i = 0; i < nb; ++i)
        bp[i] = -bp[i];
    outer_panels(c, bp, nb, mult, lo, hi);
}

static mf_status albedo(const mf_microfacet *m, mf_vec3 wo, int schlick, mf_result *out0, mf_result *out1)
{
    if (!m || !mf_ndf_valid(m->ndf) || !mf_vec3_isfinite(wo) || !(wo.z > 0.0)
        || fabs(mf_vec3_dot(wo, wo) - 1.0) > 1e-9 || (m->g2 != MF_G2_JOINT && m->g2 != MF_G2_SEPARABLE)
        || (!schlick && isnan(mf_fresnel_eval(m->fresnel, 1.0))))
        return MF_ERR_DOMAIN;
    actx c;
    c.ndf = m->ndf;
    c.g2 = m->g2;
    c.fresnel = m->fresnel;
    c.schlick = schlick;
    c.wo = wo;
    c.lambda_o = mf_smith_lambda(m->ndf, wo);
    c.layer = fmin(1.0, fmin(m->ndf.alpha_x, m->ndf.alpha_y));
    if (make_rule(&c.lo, N_LO) || make_rule(&c.hi, N_HI))
        return MF_ERR_INTERNAL;
    double lo[2] = {0.0, 0.0}, hi[2] = {0.0, 0.0};
    double sxy = hypot(wo.x, wo.y);
    int iso = m->ndf.alpha_x == m->ndf.alpha_y;
    /* the azimuthal width of the jump of the ray's exit (where k ~ +-sqrt(q)) */
    double aniso = iso ? 1.0 : fmin(m->ndf.alpha_x / m->ndf.alpha_y, m->ndf.alpha_y / m->ndf.alpha_x);
    double dphi = sxy > 0.0 ? 0.5 * aniso * wo.z / sxy : INFINITY;
    if (iso && sxy == 0.0) {
        /* normal incidence, isotropic: the rays are all alike */
        double a_lo[2] = {0.0, 0.0}, a_hi[2] = {0.0, 0.0};
        ray(&c, 0.0, &c.lo, a_lo);
        ray(&c, 0.0, &c.hi, a_hi);
        for (int i = 0; i < 2; ++i)
            lo[i] = 2.0 * MF_PI * a_lo[i], hi[i] = 2.0 * MF_PI * a_hi[i];
    } else if (iso) {
        /* symmetric about the view's azimuth: [phi_o, phi_o + pi] twice; the exit jumps at
         * phi_o + pi/2 */
        double po = atan2(wo.y, wo.x);
        double bp[MAX_LEVELS + 8];
        /* [po, po + pi/2] graded towards its end, [po + pi/2, po + pi] towards its start */
        int nb = graded(po, po + 0.5 * MF_PI, dphi, 2, bp, MAX_LEVELS + 8);
        outer_panels(&c, bp, nb, 2.0, lo, hi);
        nb = graded(-(po + MF_PI), -(po + 0.5 * MF_PI), dphi, 2, bp, MAX_LEVELS + 8);
        for (int i = 0; i < nb; ++i)
            bp[i] = -bp[i];
        for (int i = 0; i < nb / 2; ++i) {
            double t = bp[i];
            bp[i] = bp[nb - 1 - i];
            bp[nb - 1 - i] = t;
        }
        outer_panels(&c, bp, nb, 2.0, lo, hi);
    } else {
        /* anisotropic: the full circle from a direction where k = 0, the exit jumping there and
         * half a turn later */
        double p0 = sxy > 0.0 ? atan2(-m->ndf.alpha_x * wo.x, m->ndf.alpha_y * wo.y) : 0.0;
        for (int h = 0; h < 2; ++h)
            outer_two_sided(&c, p0 + h * MF_PI, p0 + (h + 1) * MF_PI, dphi, 1.0, lo, hi);
    }
    int nout = schlick ? 2 : 1;
    mf_result *outs[2] = {out0, out1};
    for (int i = 0; i < nout; ++i) {
        if (!isfinite(hi[i]) || !isfinite(lo[i]))
            return MF_ERR_DOMAIN;
        outs[i]->val = hi[i];
        outs[i]->err = fabs(hi[i] - lo[i]) + 64.0 * DBL_EPSILON * fabs(hi[i]);
    }
    return MF_OK;
}

mf_status mf_albedo_microfacet(const mf_microfacet *m, mf_vec3 wo, mf_result *out)
{
    out->val = out->err = NAN;
    return albedo(m, wo, 0, out, NULL);
}

mf_status mf_albedo_microfacet_schlick(const mf_microfacet *m, mf_vec3 wo, mf_result *scale, mf_result *bias)
{
    scale->val = scale->err = bias->val = bias->err = NAN;
    return albedo(m, wo, 1, scale, bias);
}

/* ---- the independent reference: nested adaptive Gauss-Kronrod over wi's spherical angles ---- */

typedef struct {
    const mf_microfacet *m;
    mf_vec3 wo;
    double theta;
    double tol;
    int fail;
} ref_ctx;

static double ref_inner(double phi, void *user)
{
    const ref_ctx *r = user;
    double st = sin(r->theta), ct = cos(r->theta);
    mf_vec3 wi = mf_vec3_make(st * cos(phi), st * sin(phi), ct);
    return mf_brdf_microfacet(r->m, r->wo, wi) * ct * st;
}

/* Breakpoints of [lo, hi] graded geometrically (ratio 1/2, down to 2^-44 of the interval) on both
 * sides of c: the adaptive rule then sees every scale of the lobe around c, whatever alpha is (a
 * lobe much narrower than the first Kronrod node's distance from c would otherwise be missed,
 * with an error estimate of 0).  Returns the count. */
static int ref_breaks(double lo, double hi, double c, double *bp)
{
    int n = 0;
    bp[n++] = lo;
    double len = hi - lo;
    for (int j = 0; j <= 44; ++j) { /* c - len 2^-j, increasing */
        double x = c - len * ldexp(1.0, -j);
        if (x > bp[n - 1] && x < hi)
            bp[n++] = x;
    }
    if (c > bp[n - 1] && c < hi)
        bp[n++] = c;
    for (int j = 44; j >= 0; --j) {
        double x = c + len * ldexp(1.0, -j);
        if (x > bp[n - 1] && x < hi)
            bp[n++] = x;
    }
    bp[n++] = hi;
    return n;
}

static double ref_outer(double theta, void *user)
{
    ref_ctx *r = user;
    r->theta = theta;
    double bp[100], sum = 0.0;
    int nb = ref_breaks(0.0, MF_PI, MF_PI, bp); /* the lobe is at phi = pi (the mirror azimuth) */
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        if (mf_quad_adaptive(ref_inner, r, bp[i], bp[i + 1], r->tol / (4.0 * nb), 0.0, MF_QUAD_MAX_INTERVALS, &q)
            != MF_OK)
            r->fail = 1;
        sum += q.val;
    }
    return 2.0 * sum;
}

mf_status mf_albedo_microfacet_reference(const mf_microfacet *m, mf_vec3 wo, double tol, mf_result *out)
{
    out->val = out->err = NAN;
    if (!m || !mf_ndf_valid(m->ndf) || m->ndf.alpha_x != m->ndf.alpha_y || !mf_vec3_isfinite(wo) || !(wo.z > 0.0)
        || wo.y != 0.0 || !(tol > 0.0))
        return MF_ERR_DOMAIN;
    ref_ctx r = {m, wo, 0.0, tol, 0};
    double bp[100];
    int nb = ref_breaks(0.0, 0.5 * MF_PI, acos(fmin(1.0, wo.z)), bp); /* around the mirror direction */
    double sum = 0.0, err = 0.0;
    mf_status worst = MF_OK;
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        mf_status st = mf_quad_adaptive(ref_outer, &r, bp[i], bp[i + 1], tol / nb, 0.0, MF_QUAD_MAX_INTERVALS, &q);
        if (st != MF_OK)
            worst = st;
        sum += q.val;
        err += q.err;
    }
    if (r.fail && worst == MF_OK)
        worst = MF_ERR_NO_CONVERGENCE;
    out->val = sum;
    out->err = err;
    return worst;
}
