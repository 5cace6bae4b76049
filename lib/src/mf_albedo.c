/* mf_albedo.c -- the microfacet albedo by panels split at the horizon of wi (see mf_albedo.h). */
#include "mfkit/mf_albedo.h"
#include "mfkit/mf_quad.h"
#include "mf_quad_internal.h"

#include <float.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* The target of the bound: every albedo's error bound is driven below this (absolute), with a
 * quarter of it for the inner (ray) integrals and three quarters for the outer one. */
#define ALBEDO_TOL 5e-10
#define RAY_SEGMENTS 96   /* segments of one ray's adaptive rule, at most */
#define OUTER_SEGMENTS 96 /* segments of the outer (phi) adaptive rule, at most */
/* the initial outer panels are graded towards the exit jump down to OUTER_FACTOR cot(theta_o) / 2
 * (the adaptive rule refines further; 8 measured fastest among 0.5, 2, 4 on a 30 x 30 grid) */
#define OUTER_FACTOR 8.0
#define GRADE 0.2        /* geometric ratio of graded panels */
#define MAX_LEVELS 48     /* graded panels per interval, at most */
#define BECKMANN_R_CUT 7.0 /* exp(-49) r^2 (1 + |k| r) < 1e-17 for tan(theta_o) < 1e4 */
/* A boundary layer whose whole contribution is below this is not graded towards: its
 * integral is then within the rule's error anyway. */
#define LAYER_NEGLIGIBLE 1e-15
/* The layer where G1(wi) turns over is ~alpha wide in wi.z; in the ray's coordinate its width
 * is ~alpha / |d wi.z / dx| at the end.  The initial panels are graded down to LAYER_FACTOR times
 * that; the adaptive rule refines further where the linear estimate is too wide (grazing views). */
#define LAYER_FACTOR 1.0

typedef struct {
    mf_ndf ndf;
    mf_g2_form g2;
    mf_fresnel fresnel;
    int schlick;  /* 1: the two Schlick moments, 0: F(wo.wm) */
    mf_vec3 wo;
    double lambda_o;
    double layer;  /* width of the G1 turnover in wi.z: min(alpha_x, alpha_y, 1) */
} actx;

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

/* Smith Lambda of wi (wi.z > 0) for the centred NDF, inline: s2 = |S wi_xy|^2.
 * GGX [Heitz 2014, Eq. 72]: t = s2 / z^2, Lambda = (sqrt(1 + t) - 1) / 2 = t / (2 (1 + sqrt(1 + t))).
 * Beckmann [Heitz 2014, Eq. 69]: nu = z / sqrt(s2), Lambda = exp(-nu^2) / (2 nu sqrt(pi)) - erfc(nu) / 2.
 * For nu >= 2 the two terms cancel to 1 - 3 digits, but both are below 2.6e-3, so the absolute
 * error stays below 1e-18, far inside the albedo's bound (mf_smith_lambda_beckmann_nu forms the
 * difference exactly with a continued fraction of up to 80 terms, which cost 2/3 of the time). */
static double lambda_i(const actx *c, double wx, double wy, double wz)
{
    double ux = c->ndf.alpha_x * wx, uy = c->ndf.alpha_y * wy;
    double s2 = ux * ux + uy * uy;
    if (c->ndf.type == MF_NDF_GGX) {
        double t = s2 / (wz * wz);
        return t / (2.0 * (1.0 + sqrt(1.0 + t)));
    }
    if (s2 == 0.0)
        return 0.0;
    double nu = wz / sqrt(s2);
    if (nu > 6.0) /* Lambda < exp(-36) / (4 sqrt(pi) nu^3) < 2e-19: below an ulp of 1 + Lambda_o + Lambda_i */
        return 0.0;
    double l = exp(-nu * nu) * (0.5 * MF_INV_SQRT_PI) / nu - 0.5 * erfc(nu);
    return l > 0.0 ? l : 0.0;
}

/* The integrand at inner coordinate x on the ray of stretched direction (sx, sy) = S e, with
 * k = (S e).wo_xy / wo.z: adds weight * value to acc[0] (and acc[1]). */
static void integrand(const actx *c, double x, double sx, double sy, double k, double weight, double *acc)
{
    double vx, vy, vz, meas;
    if (c->ndf.type == MF_NDF_GGX) {
        /* r = tan t: P22 dp = sin t cos t dt dphi / pi, and (1 + k r) sin t cos t = sin t cos t
         * + k sin^2 t */
        double st = sin(x), ct = cos(x);
        vx = st * sx, vy = st * sy, vz = ct;
        meas = (st * ct + k * st * st) * MF_INV_PI;
    } else {
        /* P22 dp = exp(-r^2) r dr dphi / pi */
        vx = x * sx, vy = x * sy, vz = 1.0;
        meas = exp(-x * x) * (x + k * x * x) * MF_INV_PI;
    }
    /* wm = v / |v|; wi = 2 (wo.wm) wm - wo = (2 (wo.v) / |v|^2) v - wo */
    const mf_vec3 wo = c->wo;
    double ov = wo.x * vx + wo.y * vy + wo.z * vz;
    if (!(ov > 0.0))
        return;
    double v2 = vx * vx + vy * vy + vz * vz, f = 2.0 * ov / v2;
    double wx = f * vx - wo.x, wy = f * vy - wo.y, wz = f * vz - wo.z;
    if (!(wz > 0.0))
        return;
    double g2;
    if (c->ndf.type == MF_NDF_GGX) {
        /* 1 + Lambda_i = (wz + sqrt(wz^2 + s2)) / (2 wz) [Heitz 2014, Eq. 72 with tan^2 = s2 / wz^2]:
         * G2 with one square root and one division, no cancellation */
        double ux = c->ndf.alpha_x * wx, uy = c->ndf.alpha_y * wy;
        double rt = sqrt(wz * wz + ux * ux + uy * uy);
        g2 = c->g2 == MF_G2_SEPARABLE ? 2.0 * wz / ((1.0 + c->lambda_o) * (wz + rt))
                                      : 2.0 * wz / ((1.0 + 2.0 * c->lambda_o) * wz + rt);
    } else {
        double li = lambda_i(c, wx, wy, wz);
        g2 = c->g2 == MF_G2_SEPARABLE ? 1.0 / ((1.0 + c->lambda_o) * (1.0 + li)) : 1.0 / (1.0 + c->lambda_o + li);
    }
    double val = weight * meas * g2;
    if (c->schlick) {
        double m = 1.0 - ov / sqrt(v2), m5 = m * m * m * m * m;
        acc[0] += val * (1.0 - m5);
        acc[1] += val * m5;
    } else if (c->fresnel.type == MF_FRESNEL_NONE) {
        acc[0] += val;
    } else {
        acc[0] += val * mf_fresnel_eval(c->fresnel, ov / sqrt(v2));
    }
}

/* QUADPACK's 15-point Kronrod rule (positive half, descending) and its embedded 7-point Gauss rule
 * [Piessens et al. 1983, QK15]: the tables of mf_quad.c (mf_quad_internal.h). */

/* A segment of an adaptive rule: its K15 values (two components) and |K15 - G7| (plus, for the
 * outer rule, the propagated inner bounds). */
typedef struct {
    double a, b, v[2], e[2];
} seg;

/* The 15 nodes of [a, b] in the order mf_quad_qk15_xgk[0] left, right, ..., centre (index 14). */
static double node(double a, double b, int j)
{
    double c = 0.5 * (a + b), h = 0.5 * (b - a);
    return j == 14 ? c : (j & 1 ? c + h * mf_quad_qk15_xgk[j >> 1] : c - h * mf_quad_qk15_xgk[j >> 1]);
}

/* Combines the 15 node values f[j][0..1] of [a, b] into the segment's K15 value and |K15 - G7|. */
static void combine(seg *s, double f[15][2])
{
    double h = 0.5 * (s->b - s->a);
    for (int q = 0; q < 2; ++q) {
        double k = f[14][q] * mf_quad_qk15_wgk[7], g = f[14][q] * mf_quad_qk15_wg[3];
        for (int j = 0; j < 7; ++j) {
            double p = f[2 * j][q] + f[2 * j + 1][q];
            k += mf_quad_qk15_wgk[j] * p;
            if (j & 1)
                g += mf_quad_qk15_wg[j >> 1] * p;
        }
        s->v[q] = h * k;
        s->e[q] = fabs(h * (k - g));
    }
}

/* The ray of angle phi: geometry hoisted out of the integrand. */
typedef struct {
    double sx, sy, k;
} rayc;

static void ray_segment(const actx *c, const rayc *rc, seg *s)
{
    double f[15][2];
    for (int j = 0; j < 15; ++j) {
        f[j][0] = f[j][1] = 0.0;
        integrand(c, node(s->a, s->b, j), rc->sx, rc->sy, rc->k, 1.0, f[j]);
    }
    combine(s, f);
}

/* Global adaptive bisection of the segments sg[0..n) (the worst first) until the summed bound of
 * both components is <= tol or cap segments are used; eval fills a new segment.  Sums in segment
 * order, so the result does not depend on the order of the splits beyond the segments themselves. */
typedef void (*seg_eval)(const actx *c, const void *ctx, seg *s);

static void adapt(const actx *c, const void *ctx, seg_eval eval, seg *sg, int n, int cap, double tol, double v[2],
                  double e[2])
{
    for (; n > 0;) {
        double ev[2] = {0.0, 0.0};
        int worst = 0;
        for (int i = 0; i < n; ++i) {
            ev[0] += sg[i].e[0];
            ev[1] += sg[i].e[1];
            if (sg[i].e[0] + sg[i].e[1] > sg[worst].e[0] + sg[worst].e[1])
                worst = i;
        }
        double mid = 0.5 * (sg[worst].a + sg[worst].b);
        if ((ev[0] <= tol && ev[1] <= tol) || n >= cap || !(mid > sg[worst].a && mid < sg[worst].b))
            break;
        seg l = {sg[worst].a, mid, {0, 0}, {0, 0}}, r = {mid, sg[worst].b, {0, 0}, {0, 0}};
        eval(c, ctx, &l);
        eval(c, ctx, &r);
        sg[worst] = l;
        sg[n++] = r;
    }
    v[0] = v[1] = e[0] = e[1] = 0.0;
    for (int i = 0; i < n; ++i)
        for (int q = 0; q < 2; ++q)
            v[q] += sg[i].v[q], e[q] += sg[i].e[q];
}

static void ray_eval(const actx *c, const void *ctx, seg *s) { ray_segment(c, ctx, s); }

/* The integral along the ray of angle phi (per unit phi) to the absolute tolerance tol: adaptive
 * K15 on panels first graded towards the end of the ray. */
static void ray(const actx *c, double phi, double tol, double v[2], double e[2])
{
    const mf_ndf n = c->ndf;
    const mf_vec3 wo = c->wo;
    rayc rc;
    double sx = n.alpha_x * cos(phi), sy = n.alpha_y * sin(phi);
    double q = sx * sx + sy * sy;
    double k = (sx * wo.x + sy * wo.y) / wo.z;
    rc.sx = sx, rc.sy = sy, rc.k = k;
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
    }
    double bp[MAX_LEVELS + 8];
    int base = ggx ? 1 : (int)ceil(end / 1.5);
    int nb = graded(0.0, end, delta, base, bp, MAX_LEVELS + 8);
    seg sg[RAY_SEGMENTS];
    int ns = 0;
    for (int p = 0; p + 1 < nb && ns < RAY_SEGMENTS; ++p) {
        sg[ns] = (seg){bp[p], bp[p + 1], {0, 0}, {0, 0}};
        ray_segment(c, &rc, &sg[ns++]);
    }
    adapt(c, &rc, ray_eval, sg, ns, RAY_SEGMENTS, tol, v, e);
}

/* An outer segment in phi: K15 over 15 rays, each to tol_ray; its bound adds the rays' bounds
 * weighted by the K15 weights (the value is the K15 sum of the rays' values). */
typedef struct {
    double tol_ray;
} outc;

static void outer_eval(const actx *c, const void *ctx, seg *s)
{
    const outc *o = ctx;
    double f[15][2], fe[15][2];
    for (int j = 0; j < 15; ++j)
        ray(c, node(s->a, s->b, j), o->tol_ray, f[j], fe[j]);
    combine(s, f);
    double h = 0.5 * (s->b - s->a);
    for (int q = 0; q < 2; ++q) {
        double ie = fe[14][q] * mf_quad_qk15_wgk[7];
        for (int j = 0; j < 7; ++j)
            ie += mf_quad_qk15_wgk[j] * (fe[2 * j][q] + fe[2 * j + 1][q]);
        s->e[q] += h * ie;
    }
}

/* Appends the segments between consecutive breakpoints to sg (evaluated). */
static int add_segments(const actx *c, const outc *o, const double *bp, int nb, seg *sg, int ns, int cap)
{
    for (int p = 0; p + 1 < nb && ns < cap; ++p) {
        sg[ns] = (seg){bp[p], bp[p + 1], {0, 0}, {0, 0}};
        outer_eval(c, o, &sg[ns++]);
    }
    return ns;
}

/* Breakpoints of [a, b] graded towards a (the mirror image of graded()). */
static int graded_start(double a, double b, double delta, int base, double *bp, int cap)
{
    int nb = graded(-b, -a, delta, base, bp, cap);
    for (int i = 0; i < nb; ++i)
        bp[i] = -bp[i];
    for (int i = 0; i < nb / 2; ++i) {
        double t = bp[i];
        bp[i] = bp[nb - 1 - i];
        bp[nb - 1 - i] = t;
    }
    return nb;
}

mf_status mf_albedo_dielectric(mf_ndf ndf, mf_g2_form g2, double mu, double eta, mf_result *refl, mf_result *trans);

static mf_status albedo(const mf_microfacet *m, mf_vec3 wo, int schlick, mf_result *out0, mf_result *out1)
{
    if (!m || !mf_ndf_valid(m->ndf) || !mf_vec3_isfinite(wo) || !(wo.z > 0.0)
        || fabs(mf_vec3_dot(wo, wo) - 1.0) > 1e-9 || (m->g2 != MF_G2_JOINT && m->g2 != MF_G2_SEPARABLE)
        || (!schlick && isnan(mf_fresnel_eval(m->fresnel, 1.0))))
        return MF_ERR_DOMAIN;
    if (!schlick && m->fresnel.type == MF_FRESNEL_DIELECTRIC && m->fresnel.eta < 1.0) {
        /* total internal reflection: F has a kink at the critical angle, which these panels do not
         * end on (measured: 1.8e-7 off with a bound of 3.5e-10 at GGX alpha 1, eta 1/1.5, mu 0.5);
         * the dielectric rule ends on it.  Isotropic only (it depends on wo.z alone then). */
        if (m->ndf.alpha_x != m->ndf.alpha_y)
            return MF_ERR_DOMAIN;
        mf_result t;
        return mf_albedo_dielectric(m->ndf, m->g2, wo.z, m->fresnel.eta, out0, &t);
    }
    actx c;
    c.ndf = m->ndf;
    c.g2 = m->g2;
    c.fresnel = m->fresnel;
    c.schlick = schlick;
    c.wo = wo;
    c.lambda_o = mf_smith_lambda(m->ndf, wo);
    c.layer = fmin(1.0, fmin(m->ndf.alpha_x, m->ndf.alpha_y));
    double v[2], e[2], mult;
    double sxy = hypot(wo.x, wo.y);
    int iso = m->ndf.alpha_x == m->ndf.alpha_y;
    /* the azimuthal width of the jump of the ray's exit (where k ~ +-sqrt(q)) */
    double aniso = iso ? 1.0 : fmin(m->ndf.alpha_x / m->ndf.alpha_y, m->ndf.alpha_y / m->ndf.alpha_x);
    double dphi = sxy > 0.0 ? OUTER_FACTOR * aniso * wo.z / sxy : INFINITY;
    if (iso && sxy == 0.0) {
        /* normal incidence, isotropic: the rays are all alike */
        ray(&c, 0.0, ALBEDO_TOL / (2.0 * MF_PI), v, e);
        mult = 2.0 * MF_PI;
    } else {
        /* the rays' bounds add at most (length of phi) * mult * tol_ray = ALBEDO_TOL / 4 */
        outc o = {ALBEDO_TOL / (4.0 * 2.0 * MF_PI)};
        seg sg[OUTER_SEGMENTS];
        double bp[MAX_LEVELS + 8];
        int ns = 0, nb;
        if (iso) {
            /* symmetric about the view's azimuth: [phi_o, phi_o + pi] twice; the exit jumps at
             * phi_o + pi/2 */
            double po = atan2(wo.y, wo.x);
            nb = graded(po, po + 0.5 * MF_PI, dphi, 1, bp, MAX_LEVELS + 8);
            ns = add_segments(&c, &o, bp, nb, sg, ns, OUTER_SEGMENTS);
            nb = graded_start(po + 0.5 * MF_PI, po + MF_PI, dphi, 1, bp, MAX_LEVELS + 8);
            ns = add_segments(&c, &o, bp, nb, sg, ns, OUTER_SEGMENTS);
            mult = 2.0;
        } else {
            /* anisotropic: the full circle from a direction where k = 0, the exit jumping there and
             * half a turn later; each half graded towards both ends */
            double p0 = sxy > 0.0 ? atan2(-m->ndf.alpha_x * wo.x, m->ndf.alpha_y * wo.y) : 0.0;
            for (int h = 0; h < 2; ++h) {
                double a = p0 + h * MF_PI, b = a + MF_PI, mid = 0.5 * (a + b);
                nb = graded_start(a, mid, dphi, 1, bp, MAX_LEVELS + 8);
                ns = add_segments(&c, &o, bp, nb, sg, ns, OUTER_SEGMENTS);
                nb = graded(mid, b, dphi, 1, bp, MAX_LEVELS + 8);
                ns = add_segments(&c, &o, bp, nb, sg, ns, OUTER_SEGMENTS);
            }
            mult = 1.0;
        }
        adapt(&c, &o, outer_eval, sg, ns, OUTER_SEGMENTS, (0.75 * ALBEDO_TOL) / mult, v, e);
    }
    int nout = schlick ? 2 : 1;
    mf_result *outs[2] = {out0, out1};
    for (int i = 0; i < nout; ++i) {
        double val = mult * v[i];
        if (!isfinite(val) || !isfinite(e[i]))
            return MF_ERR_DOMAIN;
        outs[i]->val = val;
        outs[i]->err = mult * e[i] + 64.0 * DBL_EPSILON * fabs(val);
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

/* ---- the independent reference in half-vector polar coordinates ------------------------------ */

/* In the polar angles (theta, phi) of the micro-normal h about the normal, with
 * f wi.z dwi = f wi.z 4 (wo.h) dh [Walter 2007, Eq. 14] and dh = sin(theta) dtheta dphi.  The lobe's
 * peak is the pole theta = 0 (no 1/alpha magnification of the inner integrals), and for wo =
 * (s, 0, c) the horizon of wi = 2 (wo.h) h - wo is, on each azimuth, the single angle
 *   wi.z = s sin(2 theta) cos(phi) + c cos(2 theta) = 0  <=>  theta_k(phi) = atan2(c, -s cos phi) / 2,
 * so the inner integral ends exactly on the kink.  The integrand is D(h) G2(wo, wi) F(wo.h) (wo.h) /
 * wo.z [Walter 2007, Eq. 20 with Eq. 14] through mf_ndf_d and mf_smith_g2: it shares no code with
 * the panel rule above (slopes, P22, its own Lambda calls) beyond the NDF, Lambda and Fresnel. */
typedef struct {
    const mf_microfacet *m;
    mf_vec3 wo;
    double phi, cp, sp;
    double tol_density; /* absolute tolerance of an inner integral, per unit phi */
    int fail;
} href_ctx;

static double href_inner(double theta, void *user)
{
    const href_ctx *r = user;
    double st = sin(theta), ct = cos(theta);
    mf_vec3 h = mf_vec3_make(st * r->cp, st * r->sp, ct);
    double oh = mf_vec3_dot(r->wo, h);
    mf_vec3 wi = mf_vec3_sub(mf_vec3_scale(h, 2.0 * oh), r->wo);
    if (!(oh > 0.0) || !(wi.z > 0.0))
        return 0.0;
    /* D G2 F (wo.h) / wo.z sin(theta), D of h itself: going through mf_brdf_microfacet (which
     * rebuilds h from wo + wi) puts a relative noise ~ 1e-16 / alpha on D, which stalls the
     * adaptive rule at alpha 1e-4 */
    return mf_ndf_d(r->m->ndf, h) * mf_smith_g2(r->m->ndf, r->m->g2, r->wo, wi) * mf_fresnel_eval(r->m->fresnel, oh) * oh
           / r->wo.z * st;
}

/* Breakpoints of [0, tk]: alpha 2^j (j >= -2) from the pole outwards, and tk - alpha 2^j towards the
 * kink (the layer where G1(wi) turns over); the adaptive rule refines between them. */
static int href_breaks(double tk, double alpha, double *bp, int cap)
{
    int n = 0;
    bp[n++] = 0.0;
    for (double x = 0.25 * alpha; x < 0.5 * tk && n < cap / 2 - 1; x *= 2.0)
        bp[n++] = x;
    double tmp[64];
    int nt = 0;
    for (double d = 0.25 * alpha; d < 0.5 * tk && nt < 64 && n + nt < cap - 2; d *= 2.0)
        tmp[nt++] = tk - d;
    for (int i = nt - 1; i >= 0; --i)
        if (tmp[i] > bp[n - 1])
            bp[n++] = tmp[i];
    bp[n++] = tk;
    return n;
}

static double href_outer(double phi, void *user)
{
    href_ctx *r = user;
    r->phi = phi;
    r->cp = cos(phi);
    r->sp = sin(phi);
    double tk = 0.5 * atan2(r->wo.z, -r->wo.x * r->cp);
    if (!(tk > 0.0))
        return 0.0;
    double bp[140], sum = 0.0;
    int nb = href_breaks(tk, r->m->ndf.alpha_x, bp, 140);
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        /* relative 1e-13: the inner values are O(1/pi) at most, so this only guards rounding */
        if (mf_quad_adaptive(href_inner, r, bp[i], bp[i + 1], r->tol_density / nb, 1e-13, MF_QUAD_MAX_INTERVALS, &q)
            != MF_OK) {
            r->fail = 1;
        }
        sum += q.val;
    }
    return 2.0 * sum; /* phi in [0, pi] covers half of the symmetric integral */
}

mf_status mf_albedo_microfacet_reference(const mf_microfacet *m, mf_vec3 wo, double tol, mf_result *out)
{
    out->val = out->err = NAN;
    if (!m || !mf_ndf_valid(m->ndf) || m->ndf.alpha_x != m->ndf.alpha_y || !mf_vec3_isfinite(wo) || !(wo.z > 0.0)
        || wo.y != 0.0 || wo.x < 0.0 || !(tol > 0.0))
        return MF_ERR_DOMAIN;
    /* the inner integrals' errors add at most 2 pi tol_density = tol / 4 to the outer one */
    href_ctx r = {m, wo, 0.0, 0.0, 0.0, tol / (8.0 * MF_PI), 0};
    /* azimuth breaks: theta_k(phi) swings from ~pi/2 to ~theta_o' across phi = pi/2 over a width
     * ~ cot(theta_o) = c / s, so grade geometrically on both sides of pi/2 down to that width / 8 */
    double bp[140];
    int nb = 0;
    bp[nb++] = 0.0;
    double w = wo.x > 0.0 ? fmin(1.0, wo.z / wo.x) : 1.0;
    double ds[64];
    int nd = 0;
    for (double d = 0.125 * w; d < 0.5 * MF_PI && nd < 60; d *= 2.0)
        ds[nd++] = d;
    for (int i = nd - 1; i >= 0; --i)
        bp[nb++] = 0.5 * MF_PI - ds[i];
    bp[nb++] = 0.5 * MF_PI;
    for (int i = 0; i < nd; ++i)
        bp[nb++] = 0.5 * MF_PI + ds[i];
    bp[nb++] = MF_PI;
    double sum = 0.0, err = 0.0;
    mf_status worst = MF_OK;
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        mf_status st = mf_quad_adaptive(href_outer, &r, bp[i], bp[i + 1], tol / nb, 0.0, MF_QUAD_MAX_INTERVALS, &q);
        if (st != MF_OK) {
            worst = st;
        }
        sum += q.val;
        err += q.err;
    }
    if (r.fail && worst == MF_OK)
        worst = MF_ERR_NO_CONVERGENCE;
    out->val = sum;
    out->err = err + 0.25 * tol + 1e-13 * fabs(sum);
    return worst;
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

mf_status mf_albedo_microfacet_reference_wi(const mf_microfacet *m, mf_vec3 wo, double tol, mf_result *out)
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
        if (st != MF_OK) {
            worst = st;
        }
        sum += q.val;
        err += q.err;
    }
    if (r.fail && worst == MF_OK)
        worst = MF_ERR_NO_CONVERGENCE;
    out->val = sum;
    out->err = err;
    return worst;
}

/* ---- the Charlie sheen albedo --------------------------------------------------------------- */

/* D_charlie(h) = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi) [Estevez and Kulla 2017, Eq. 2] and
 * V(wo, wi) = 1 / (4 (wi.z + wo.z - wi.z wo.z)) [Neubelt and Pettineo 2013] (the V that folds
 * 1 / (4 wo.z wi.z) in), F = 1: f = D V.  sin^(1/a) as exp(log(sin) / a) (0 at sin = 0). */
static double charlie_dv(double inv_a, double sin_h, double nov, double nol)
{
    if (!(sin_h > 0.0))
        return 0.0;
    double d = (2.0 + inv_a) * exp(inv_a * log(fmin(1.0, sin_h))) * (0.5 * MF_INV_PI);
    return d / (4.0 * (nol + nov - nol * nov));
}

typedef struct {
    double inv_a, alpha;
    mf_vec3 wo;
    double cp, sp;  /* the current azimuth of h */
    double tol_ray; /* inner tolerance per unit phi */
} chctx;

/* the inner integrand: theta_h at the azimuth (cp, sp); f wi.z dwi = D V wi.z 4 (wo.h) sin dtheta */
static void charlie_inner_eval(const actx *unused, const void *vctx, seg *s)
{
    (void)unused;
    const chctx *c = vctx;
    double f[15][2];
    for (int j = 0; j < 15; ++j) {
        double t = node(s->a, s->b, j), st = sin(t), ct = cos(t);
        double oh = c->wo.x * st * c->cp + c->wo.z * ct; /* wo.y = 0 */
        double wz = 2.0 * oh * ct - c->wo.z;
        f[j][0] = f[j][1] = 0.0;
        if (oh > 0.0 && wz > 0.0)
            f[j][0] = charlie_dv(c->inv_a, st, c->wo.z, wz) * wz * 4.0 * oh * st;
    }
    combine(s, f);
}

static void charlie_ray(const chctx *c0, double phi, double v[2], double e[2])
{
    chctx c = *c0;
    c.cp = cos(phi);
    c.sp = sin(phi);
    /* the horizon of wi on this azimuth of h (see the reference above) */
    double tk = 0.5 * atan2(c.wo.z, -c.wo.x * c.cp);
    double bp[MAX_LEVELS + 8];
    /* graded towards tk, where sin^(1/a) is largest, down to its decay length a tan(tk) */
    int nb = graded(0.0, tk, fmax(1e-12, c.alpha * fmax(1.0, tan(tk))), 1, bp, MAX_LEVELS + 8);
    seg sg[RAY_SEGMENTS];
    int ns = 0;
    for (int p = 0; p + 1 < nb && ns < RAY_SEGMENTS; ++p) {
        sg[ns] = (seg){bp[p], bp[p + 1], {0, 0}, {0, 0}};
        charlie_inner_eval(NULL, &c, &sg[ns++]);
    }
    adapt(NULL, &c, charlie_inner_eval, sg, ns, RAY_SEGMENTS, c.tol_ray, v, e);
}

static void charlie_outer_eval(const actx *unused, const void *vctx, seg *s)
{
    (void)unused;
    double f[15][2], fe[15][2];
    for (int j = 0; j < 15; ++j)
        charlie_ray(vctx, node(s->a, s->b, j), f[j], fe[j]);
    combine(s, f);
    double h = 0.5 * (s->b - s->a), ie = fe[14][0] * mf_quad_qk15_wgk[7];
    for (int j = 0; j < 7; ++j)
        ie += mf_quad_qk15_wgk[j] * (fe[2 * j][0] + fe[2 * j + 1][0]);
    s->e[0] += h * ie;
}

mf_status mf_albedo_charlie(double alpha, double mu, mf_result *out)
{
    out->val = out->err = NAN;
    if (!(alpha > 0.0 && alpha <= 1.0) || !(mu > 0.0 && mu <= 1.0))
        return MF_ERR_DOMAIN;
    chctx c;
    c.inv_a = 1.0 / alpha;
    c.alpha = alpha;
    c.wo = mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu);
    c.cp = 1.0, c.sp = 0.0;
    /* symmetric about phi = 0: [0, pi] twice; the rays' bounds add at most ALBEDO_TOL / 4 */
    c.tol_ray = ALBEDO_TOL / (4.0 * 2.0 * MF_PI);
    double v[2], e[2];
    seg sg[OUTER_SEGMENTS];
    int ns = 0;
    if (c.wo.x == 0.0) {
        charlie_ray(&c, 0.0, v, e);
        out->val = 2.0 * MF_PI * v[0];
        out->err = 2.0 * MF_PI * e[0] + 64.0 * DBL_EPSILON * fabs(out->val);
        return isfinite(out->val) ? MF_OK : MF_ERR_DOMAIN;
    }
    /* theta_k swings across phi = pi/2 over a width ~ cot(theta_o): graded there from both sides */
    double dphi = OUTER_FACTOR * mu / c.wo.x, bp[MAX_LEVELS + 8];
    int nb = graded(0.0, 0.5 * MF_PI, dphi, 2, bp, MAX_LEVELS + 8);
    for (int p = 0; p + 1 < nb; ++p, ++ns) {
        sg[ns] = (seg){bp[p], bp[p + 1], {0, 0}, {0, 0}};
        charlie_outer_eval(NULL, &c, &sg[ns]);
    }
    nb = graded_start(0.5 * MF_PI, MF_PI, dphi, 1, bp, MAX_LEVELS + 8);
    for (int p = 0; p + 1 < nb; ++p, ++ns) {
        sg[ns] = (seg){bp[p], bp[p + 1], {0, 0}, {0, 0}};
        charlie_outer_eval(NULL, &c, &sg[ns]);
    }
    adapt(NULL, &c, charlie_outer_eval, sg, ns, OUTER_SEGMENTS, 0.75 * ALBEDO_TOL / 2.0, v, e);
    out->val = 2.0 * v[0];
    out->err = 2.0 * e[0] + 64.0 * DBL_EPSILON * fabs(out->val);
    return isfinite(out->val) && isfinite(out->err) ? MF_OK : MF_ERR_DOMAIN;
}

/* The Charlie reference: nested adaptive Gauss-Kronrod in the spherical angles of wi (no kink
 * there: the hemisphere is the whole domain and D V is smooth in wi), theta_i graded towards the
 * horizon and phi_i towards the view's azimuth, where h is closest to horizontal. */
typedef struct {
    double inv_a;
    mf_vec3 wo;
    double theta, tol_density;
    int fail;
} chref;

static double chref_inner(double phi, void *user)
{
    const chref *r = user;
    double st = sin(r->theta), ct = cos(r->theta);
    double wx = st * cos(phi), wy = st * sin(phi);
    double hx = r->wo.x + wx, hy = wy, hz = r->wo.z + ct;
    double sin_h = hypot(hx, hy) / sqrt(hx * hx + hy * hy + hz * hz);
    return charlie_dv(r->inv_a, sin_h, r->wo.z, ct) * ct * st;
}

/* [lo, hi] cut at gaps len 2^-j (j = 1..30) from the end it is graded towards; ascending */
static int chref_breaks(double lo, double hi, int towards_hi, double *bp)
{
    int n = 0;
    double len = hi - lo;
    bp[n++] = lo;
    if (towards_hi) {
        for (int j = 1; j <= 30; ++j)
            bp[n++] = hi - len * ldexp(1.0, -j);
    } else {
        for (int j = 30; j >= 1; --j)
            bp[n++] = lo + len * ldexp(1.0, -j);
    }
    bp[n++] = hi;
    return n;
}

static double chref_outer(double theta, void *user)
{
    chref *r = user;
    r->theta = theta;
    double bp[40], sum = 0.0;
    int nb = chref_breaks(0.0, MF_PI, 0, bp);
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        if (mf_quad_adaptive(chref_inner, r, bp[i], bp[i + 1], r->tol_density / nb, 1e-13, MF_QUAD_MAX_INTERVALS, &q)
            != MF_OK)
            r->fail = 1;
        sum += q.val;
    }
    return 2.0 * sum;
}

mf_status mf_albedo_charlie_reference(double alpha, double mu, double tol, mf_result *out)
{
    out->val = out->err = NAN;
    if (!(alpha > 0.0 && alpha <= 1.0) || !(mu > 0.0 && mu <= 1.0) || !(tol > 0.0))
        return MF_ERR_DOMAIN;
    chref r = {1.0 / alpha, mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu), 0.0, tol / (8.0 * MF_PI), 0};
    double bp[40], sum = 0.0, err = 0.0;
    int nb = chref_breaks(0.0, 0.5 * MF_PI, 1, bp);
    mf_status worst = MF_OK;
    for (int i = 0; i + 1 < nb; ++i) {
        mf_result q;
        mf_status st = mf_quad_adaptive(chref_outer, &r, bp[i], bp[i + 1], tol / nb, 0.0, MF_QUAD_MAX_INTERVALS, &q);
        if (st != MF_OK)
            worst = st;
        sum += q.val;
        err += q.err;
    }
    if (r.fail && worst == MF_OK)
        worst = MF_ERR_NO_CONVERGENCE;
    out->val = sum;
    out->err = err + 0.25 * tol + 1e-13 * fabs(sum);
    return worst;
}

/* ---- the rough dielectric: reflection and transmission albedo ------------------------------- */

/* With the micro-normal h (wo.h > 0) as variable, dwi = 4 (wo.h) dh for the reflection [Walter
 * 2007, Eq. 14] and dwi = (eta_o (wo.h) + eta_i (wi.h))^2 / (eta_i^2 |wi.h|) dh for the refraction
 * [Walter 2007, Eq. 17], and both BSDFs [Walter 2007, Eq. 20, 21] times |wi.z| reduce to
 *   E_R = int D(h) F(wo.h) G2(wo, wr) (wo.h) / wo.z dh,   wr = 2 (wo.h) h - wo above the surface,
 *   E_T = int D(h) (1 - F(wo.h)) G2(wo, wt) (wo.h) / wo.z dh, wt = refract(wo, h) below it,
 * E_T being the transmitted energy (no 1 / eta^2 radiance scaling).  G2 for the transmission is
 * the same form with Lambda of wt mirrored above the surface (the height-correlated
 * 1 / (1 + Lambda_o + Lambda_t) that pbrt-v4 and Cycles use; Heitz 2014, Eq. 99 has a Beta function
 * instead).
 *
 * Coordinates: h by its angle b from wo = (s, 0, c) and its azimuth p about wo,
 *   h = cos(b) wo + sin(b) (cos(p) e1 + sin(p) e2),  e1 = (c, 0, -s),  e2 = (0, 1, 0),
 * dh = sin(b) db dp, wo.h = cos(b); the integral over p in [0, pi] is half of the symmetric circle.
 * The OUTER variable is b, the inner one p.  Then F depends on b alone and leaves the inner
 * integral, and every boundary of the domain is, at fixed b, a bound on cos(p) in closed form
 * (each condition is linear in cos p):
 *   h.z  = c cos b - s sin b cos p > 0        <=>  cos p < X_h = c cos b / (s sin b),
 *   wr.z = c cos 2b - s sin 2b cos p > 0      <=>  cos p < X_k = c cos 2b / (s sin 2b)  (E_R's end;
 *          it implies h.z > 0: X_k < X_h for 0 < b < pi/2),
 *   wt.z = -c / eta + k h.z < 0, with k = (cos b - sqrt(eta^2 - sin^2 b)) / eta [Walter 2007, Eq. 40]:
 *          always for eta > 1 (k < 0); for eta < 1 (k > 0) <=>  cos p > X_t = X_h - c / (eta k s sin b)
 *          (E_T's end beside the horizon of h; X_t < X_h always),
 * and total internal reflection is b > b_c = asin(eta) (eta < 1).  Inside these bounds the integrand
 * D G2 (wo.h) / wo.z sin b is smooth in p (D and Lambda are analytic where h.z > 0, w.z > 0).
 * The inner integral J(b) is smooth in b except where an end reaches p = 0 or p = pi (X = +-1:
 * a square root of the distance, since the integrand is even about p = 0 and p = pi), and F at b_c
 * (1 - F ~ sqrt(b_c - b)).  These values of b are, with theta_o = atan2(s, c) (derivation in
 * docs/math.md, "The rough dielectric rule"):
 *   X_k = +1 at b_1 = (pi/2 - theta_o) / 2,  X_k = -1 at b_2 = (pi/2 + theta_o) / 2 (E_R is 0 beyond),
 *   X_h = +1 at b_h = pi/2 - theta_o (X_h > -1 always),
 *   X_t = -1 at tan b_t = eta sin(d) / (1 - eta cos(d)), d = pi/2 - theta_o (eta < 1 and theta_o > b_c
 *   only; X_t < 1 always),
 *   and b_c.
 * Every one of them ends an outer panel, and the panels beside them are integrated in u with
 * b = event +- u^2 (smooth in u); the outer panels are graded around the peak of D at b = theta_o,
 * the inner ones towards the peak at p = pi and towards the ends where G2 turns over (width ~ alpha
 * in w.z).  Both levels are global-adaptive QK15 rules with the bound |K15 - G7| per segment, the
 * outer adding the inner bounds (as mf_albedo_microfacet). */
typedef struct {
    actx a;        /* ndf, g2, lambda_o (lambda_i) */
    double s, c;   /* wo = (s, 0, c) */
    double eta;
    int trans;     /* 0: E_R, 1: E_T */
    double cb, sb; /* the current b */
    double k;      /* the refraction's k at b (E_T) */
    double tol_in; /* absolute tolerance of one inner integral */
} dctx;

/* the inner integrand at (cb, sb) and azimuth p, without the Fresnel factor */
static double dielectric_point(const dctx *c, double p)
{
    double cp = cos(p), sp = sin(p);
    double hx = c->cb * c->s + c->sb * cp * c->c, hy = c->sb * sp, hz = c->cb * c->c - c->sb * cp * c->s;
    if (!(hz > 0.0))
        return 0.0;
    double wx, wy, wz;
    if (!c->trans) {
        wx = 2.0 * c->cb * hx - c->s, wy = 2.0 * c->cb * hy, wz = 2.0 * c->cb * hz - c->c;
    } else {
        /* wt = -wo / eta + k h, mirrored above the surface */
        wx = -c->s / c->eta + c->k * hx, wy = c->k * hy, wz = c->c / c->eta - c->k * hz;
    }
    if (!(wz > 0.0))
        return 0.0;
    /* D of the unit h, isotropic [Walter 2007, Eq. 33 (GGX) and 25 (Beckmann)]: GGX
     * 1 / (pi a^2 ((hx^2 + hy^2) / a^2 + hz^2)^2), Beckmann exp(-tan^2 / a^2) / (pi a^2 hz^4) */
    double a2 = c->a.ndf.alpha_x * c->a.ndf.alpha_x, t2 = hx * hx + hy * hy, d;
    if (c->a.ndf.type == MF_NDF_GGX) {
        double q = t2 / a2 + hz * hz;
        d = 1.0 / (MF_PI * a2 * q * q);
    } else {
        double z2 = hz * hz, e = t2 / (a2 * z2);
        d = e > 800.0 ? 0.0 : exp(-e) / (MF_PI * a2 * z2 * z2); /* exp(-800) underflows, z2^2 may too */
    }
    double li = lambda_i(&c->a, wx, wy, wz);
    double g2 = c->a.g2 == MF_G2_SEPARABLE ? 1.0 / ((1.0 + c->a.lambda_o) * (1.0 + li)) : 1.0 / (1.0 + c->a.lambda_o + li);
    return d * g2 * c->cb / c->c * c->sb;
}

static void dielectric_inner_eval(const actx *unused, const void *vctx, seg *s)
{
    (void)unused;
    double f[15][2];
    for (int j = 0; j < 15; ++j) {
        f[j][0] = dielectric_point(vctx, node(s->a, s->b, j));
        f[j][1] = 0.0;
    }
    combine(s, f);
}

/* cos p = x as an azimuth in [0, pi] (x clamped) */
static double dielectric_acos(double x) { return x >= 1.0 ? 0.0 : x <= -1.0 ? MF_PI : acos(x); }

/* adds to bp the breakpoints of [lo, hi] graded towards x0 (x0 - w 2^j and/or x0 + w 2^j inside) */
static int dielectric_grade(double lo, double hi, double x0, double w, double *bp, int n, int cap)
{
    if (!(w > 0.0))
        return n;
    for (double d = w; d < hi - lo && n < cap; d *= 2.0) {
        if (x0 - d > lo && x0 - d < hi && n < cap)
            bp[n++] = x0 - d;
        if (x0 + d > lo && x0 + d < hi && n < cap)
            bp[n++] = x0 + d;
    }
    return n;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* J(b) = the inner integral over p at b (the caller has set cb, sb, k) */
static void dielectric_inner(const dctx *c, double b, double *v, double *e)
{
    *v = *e = 0.0;
    double lo = 0.0, hi = MF_PI, den = c->s * c->sb;
    /* the ends: E_R p > acos(X_k); E_T acos(X_h) < p < acos(X_t) */
    double dwz_dp = 0.0; /* |d w.z / d p| / sin p at the end where G2 vanishes (w.z = 0) */
    if (!c->trans) {
        double c2 = c->c * (c->cb - c->sb) * (c->cb + c->sb), s2 = 2.0 * c->s * c->sb * c->cb;
        if (s2 > 0.0)
            lo = dielectric_acos(c2 / s2);
        else if (!(c2 > 0.0))
            return;
        dwz_dp = s2;
    } else {
        double ch = c->c * c->cb;
        if (den > 0.0)
            lo = dielectric_acos(ch / den);
        if (c->eta < 1.0) {
            double xt = ch - c->c / (c->eta * c->k);
            if (den > 0.0)
                hi = dielectric_acos(xt / den);
            else if (!(xt < 0.0))
                return;
        }
        dwz_dp = c->k * den;
    }
    if (!(hi > lo))
        return;
    double bp[4 * MAX_LEVELS + 8];
    int nb = 0;
    bp[nb++] = lo;
    bp[nb++] = hi;
    if (den > 0.0) {
        double alpha = c->a.ndf.alpha_x;
        /* the peak of D at p = pi (h nearest the normal), of width ~ (alpha + |b - theta_o|) / sin b */
        if (hi == MF_PI)
            nb = dielectric_grade(lo, hi, MF_PI, 0.25 * (alpha + fabs(b - atan2(c->s, c->c))) / c->sb, bp, nb, 2 * MAX_LEVELS);
        /* the turnover of G2 at an end where w.z = 0: ~alpha wide in w.z, |dw.z/dp| = dwz_dp sin p */
        if (!c->trans || c->eta < 1.0) { /* that end: E_R's lo, E_T's hi (none for eta >= 1) */
            double x = c->trans ? hi : lo, slope = fabs(dwz_dp * sin(x));
            if (x > 0.0 && x < MF_PI && slope > 0.0)
                nb = dielectric_grade(lo, hi, x, fmax(LAYER_FACTOR * c->a.layer / slope, 1e-12), bp, nb, 4 * MAX_LEVELS);
        }
    }
    qsort(bp, (size_t)nb, sizeof bp[0], cmp_double);
    seg sg[2 * RAY_SEGMENTS];
    int ns = 0;
    for (int i = 0; i + 1 < nb && ns < 2 * RAY_SEGMENTS; ++i) {
        if (!(bp[i + 1] > bp[i]))
            continue;
        sg[ns] = (seg){bp[i], bp[i + 1], {0, 0}, {0, 0}};
        dielectric_inner_eval(NULL, c, &sg[ns++]);
    }
    double vv[2], ee[2];
    adapt(NULL, c, dielectric_inner_eval, sg, ns, 2 * RAY_SEGMENTS, c->tol_in, vv, ee);
    *v = vv[0], *e = ee[0];
}

/* the outer integrand at b: F or 1 - F at wo.h = cos b, times J(b) (value and bound) */
static void dielectric_outer_point(dctx *c, double b, double *v, double *e)
{
    c->cb = cos(b), c->sb = sin(b);
    *v = *e = 0.0;
    /* exact unpolarised Fresnel [Born & Wolf, Sec. 1.5.2] from sin b, with the refracted cosine
     * sqrt(eta^2 - sin^2 b) / eta formed as a product (no cancellation near the critical angle) */
    double t2 = (c->eta - c->sb) * (c->eta + c->sb), F = 1.0, ct = 0.0;
    if (t2 > 0.0) {
        ct = sqrt(t2) / c->eta;
        double rp = (c->eta * c->cb - ct) / (c->eta * c->cb + ct), rs = (c->cb - c->eta * ct) / (c->cb + c->eta * ct);
        F = 0.5 * (rp * rp + rs * rs);
    }
    double w = c->trans ? 1.0 - F : F;
    if (!(w > 0.0))
        return;
    c->k = c->cb / c->eta - ct;
    double jv, je;
    dielectric_inner(c, b, &jv, &je);
    *v = w * jv, *e = w * je;
}

/* An outer segment: [a, b] in its variable u, with b = org + dir u^2 (dir = +-1) or b = u (dir 0). */
typedef struct {
    seg s;
    double org;
    int dir;
} dseg;

static void dielectric_outer_eval(dctx *c, dseg *d)
{
    double f[15][2], fe[15];
    for (int j = 0; j < 15; ++j) {
        double u = node(d->s.a, d->s.b, j), b = u, jac = 1.0;
        if (d->dir)
            b = d->org + d->dir * u * u, jac = 2.0 * d->dir * u; /* db/du >= 0 on both sides */
        double v, e;
        dielectric_outer_point(c, b, &v, &e);
        f[j][0] = jac * v, f[j][1] = 0.0, fe[j] = jac * e;
    }
    combine(&d->s, f);
    double h = 0.5 * (d->s.b - d->s.a), ie = fe[14] * mf_quad_qk15_wgk[7];
    for (int j = 0; j < 7; ++j)
        ie += mf_quad_qk15_wgk[j] * (fe[2 * j] + fe[2 * j + 1]);
    d->s.e[0] += h * ie;
}

#define DIEL_OUTER_CAP 160

/* one component (c->trans) over b in [0, end], to the outer tolerance tol */
static void dielectric_component(dctx *c, double tol, double *val, double *err)
{
    double theta_o = atan2(c->s, c->c), bc = c->eta < 1.0 ? asin(c->eta) : 0.5 * MF_PI;
    double ev[8];
    int nev = 0;
    double end;
    if (!c->trans) {
        end = 0.5 * (0.5 * MF_PI + theta_o);
        ev[nev++] = 0.5 * (0.5 * MF_PI - theta_o);
        ev[nev++] = bc;
    } else {
        end = bc;
        ev[nev++] = 0.5 * MF_PI - theta_o;
        if (c->eta < 1.0 && theta_o > bc) { /* else the root is spurious (asin(sin b / eta) = pi - b - d) */
            double d = 0.5 * MF_PI - theta_o;
            ev[nev++] = atan2(c->eta * sin(d), 1.0 - c->eta * cos(d));
        }
    }
    /* the events inside (0, end), then the peak's grading, as plain breakpoints */
    double bp[2 * MAX_LEVELS + 16];
    int isev[2 * MAX_LEVELS + 16], nb = 0;
    bp[nb] = 0.0, isev[nb++] = 0;
    bp[nb] = end, isev[nb++] = 1;
    for (int i = 0; i < nev; ++i)
        if (ev[i] > 0.0 && ev[i] < end)
            bp[nb] = ev[i], isev[nb++] = 1;
    double peak = theta_o < end ? theta_o : -1.0;
    if (peak > 0.0)
        bp[nb] = peak, isev[nb++] = 0;
    if (peak >= 0.0)
        /* down to a quarter of alpha or of wo.z, whichever is smaller: for a grazing view the ends
         * of the inner integral move on the scale pi/2 - b ~ wo.z near b = theta_o (X_k ~ -c / (2 (pi/2
         * - b))); measured without it: Beckmann alpha 1, mu 1e-3, eta 1.5, E_R 1.9e-9 low with a bound
         * of 2.3e-11 (the panel [theta_o - 0.25, theta_o] missed that layer) */
        for (double d = 0.25 * fmin(c->a.ndf.alpha_x, c->c); d < end && nb < 2 * MAX_LEVELS + 12; d *= 2.0) {
            if (peak - d > 0.0)
                bp[nb] = peak - d, isev[nb++] = 0;
            if (peak + d < end)
                bp[nb] = peak + d, isev[nb++] = 0;
        }
    for (int i = 1; i < nb; ++i) /* ascending; an event before a plain point at the same place */
        for (int j = i; j > 0 && (bp[j] < bp[j - 1] || (bp[j] == bp[j - 1] && isev[j] > isev[j - 1])); --j) {
            double t = bp[j];
            bp[j] = bp[j - 1], bp[j - 1] = t;
            int f = isev[j];
            isev[j] = isev[j - 1], isev[j - 1] = f;
        }
    /* the initial segments; beside an event mapped with a square towards it, split in the middle
     * between two events */
    dseg sg[DIEL_OUTER_CAP];
    int ns = 0;
    for (int i = 0; i + 1 < nb && ns + 2 <= DIEL_OUTER_CAP; ++i) {
        double a = bp[i], b = bp[i + 1];
        if (!(b > a))
            continue;
        double cut[3] = {a, b, b};
        int np = 1;
        if (isev[i] && isev[i + 1])
            cut[1] = 0.5 * (a + b), np = 2;
        for (int p = 0; p < np; ++p) {
            int lev = p == 0 && isev[i], rev = p == np - 1 && isev[i + 1];
            dseg *d = &sg[ns++];
            d->s.v[0] = d->s.v[1] = d->s.e[0] = d->s.e[1] = 0.0;
            if (lev) {
                d->org = cut[p], d->dir = 1, d->s.a = 0.0, d->s.b = sqrt(cut[p + 1] - cut[p]);
            } else if (rev) {
                d->org = cut[p + 1], d->dir = -1, d->s.a = -sqrt(cut[p + 1] - cut[p]), d->s.b = 0.0;
            } else {
                d->org = 0.0, d->dir = 0, d->s.a = cut[p], d->s.b = cut[p + 1];
            }
            dielectric_outer_eval(c, d);
        }
    }
    /* global adaptive bisection (as adapt(), with the maps) */
    for (;;) {
        double et = 0.0;
        int worst = 0;
        for (int i = 0; i < ns; ++i) {
            et += sg[i].s.e[0];
            if (sg[i].s.e[0] > sg[worst].s.e[0])
                worst = i;
        }
        double mid = 0.5 * (sg[worst].s.a + sg[worst].s.b);
        if (et <= tol || ns >= DIEL_OUTER_CAP || !(mid > sg[worst].s.a && mid < sg[worst].s.b))
            break;
        dseg l = sg[worst], r = sg[worst];
        l.s.b = mid, r.s.a = mid;
        dielectric_outer_eval(c, &l);
        dielectric_outer_eval(c, &r);
        sg[worst] = l;
        sg[ns++] = r;
    }
    *val = *err = 0.0;
    for (int i = 0; i < ns; ++i)
        *val += sg[i].s.v[0], *err += sg[i].s.e[0];
}

mf_status mf_albedo_dielectric(mf_ndf ndf, mf_g2_form g2, double mu, double eta, mf_result *refl, mf_result *trans)
{
    refl->val = refl->err = trans->val = trans->err = NAN;
    if (!mf_ndf_valid(ndf) || ndf.alpha_x != ndf.alpha_y || (g2 != MF_G2_JOINT && g2 != MF_G2_SEPARABLE)
        || !(mu > 0.0 && mu <= 1.0) || !(eta > 0.0) || !isfinite(eta))
        return MF_ERR_DOMAIN;
    dctx c;
    memset(&c, 0, sizeof c);
    c.a.ndf = ndf;
    c.a.g2 = g2;
    c.a.fresnel = (mf_fresnel){MF_FRESNEL_DIELECTRIC, 0.0, eta, 0.0};
    c.s = sqrt(fmax(0.0, (1.0 - mu) * (1.0 + mu)));
    c.c = mu;
    c.a.wo = mf_vec3_make(c.s, 0.0, mu);
    c.a.lambda_o = mf_smith_lambda(ndf, c.a.wo);
    c.a.layer = fmin(1.0, ndf.alpha_x);
    c.eta = eta;
    /* p in [0, pi] counts twice; b spans at most pi/2: the inner bounds add at most
     * 2 (pi/2) tol_in = ALBEDO_TOL / 4, the outer rule gets the other 3/4 */
    c.tol_in = ALBEDO_TOL / (4.0 * MF_PI);
    const double mult = 2.0;
    mf_result *outs[2] = {refl, trans};
    for (int q = 0; q < 2; ++q) {
        c.trans = q;
        double v, e;
        dielectric_component(&c, 0.75 * ALBEDO_TOL / mult, &v, &e);
        outs[q]->val = mult * v;
        outs[q]->err = mult * e + 64.0 * DBL_EPSILON * fabs(outs[q]->val);
        if (!isfinite(outs[q]->val) || !isfinite(outs[q]->err))
            return MF_ERR_DOMAIN;
    }
    return MF_OK;
}
