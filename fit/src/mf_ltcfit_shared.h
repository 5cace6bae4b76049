/*
 * mf_ltcfit_shared.h -- internal: the pieces the isotropic (mf_ltcfit.c) and the anisotropic
 * (mf_ltcfit_aniso.c) LTC fitters share: constants of the objective, forward-mode dual numbers,
 * the clip-and-integrate core of the LTC polygon integral (value and dual forms), the test
 * lights, the sample workspace and the light sums, the Sobol scramble.  Moved here from
 * mf_ltcfit.c unchanged (same operations in the same order: the isotropic table stays bitwise
 * the same); the dual numbers take their derivative count from MF_LTCFIT_DUAL_N, which the
 * including file defines first.  Not installed; not a public API.
 */
#ifndef MF_LTCFIT_SHARED_H
#define MF_LTCFIT_SHARED_H

#ifndef MF_LTCFIT_DUAL_N
#error "define MF_LTCFIT_DUAL_N (derivatives per dual number) before including mf_ltcfit_shared.h"
#endif

#include "mfkit/mf_core.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define LIGHTS_MAX 48

#define A_MIN 1e-7
/* The floor of the residual weights, in units of the texel's albedo: residual_k =
 * (magnitude E_k - I_k) / (I_k + WEIGHT_FLOOR magnitude) (mf_ltcfit.h, docs/tables.md).  0.01 made
 * the lights that catch almost nothing (I_k < 1 % of the albedo: the side lights of narrow lobes)
 * dominate the fit; at the grazing row (89.95 deg, alpha < 0.03) the 4-parameter LTC cannot follow
 * them and the solver collapsed the lobe to a sliver (c' at its 1e-7 bound, minv_02 ~ 1e-5 between
 * neighbours at 0.5: the gate's ltc_smooth_spike 26x, ltc_polygon_entry 0.13).  With 0.2 those
 * lights count as absolute errors of 0.2 albedo, the row is smooth, and the gate's polygon errors
 * halve (ltc_polygon_mean 0.00167 -> 0.00077, ltc_polygon_entry 0.132 -> 0.018). */
#define WEIGHT_FLOOR 0.2
/* Proximal residuals towards the previous texel of the column (its lobe-frame parameters q):
 * PROX_WEIGHT (b' - q_b), (d' - q_d) and PROX_WEIGHT (a' - q_a) / q_a, (c' - q_c) / q_c.  They keep
 * the weakly determined directions of the fit continuous along the column, where the light
 * integrals do not decide.  Shears only (first form): GGX alpha 1, 89.95 deg, where the cost
 * changes by 0.3 % over d' in [-0.2, 0.2], stays continuous (ltc_smooth_jump 1.03 -> 0.96).  With
 * the scales too: the dip of minv_02 at alpha 0.036, 88.2 deg (ltc_smooth_spike 1.019; it shades
 * the same as its neighbours' mean within noise, paired t -1.6 .. +0.7 over 48 polygons) falls to
 * 0.73, the gate's polygon mean moves 0.000764 -> 0.000770 and worst texel 0.0177 -> 0.0187, and the
 * shading error between texels (bench_ltc, bilinear) improves: mean 0.001428 -> 0.001424, p95
 * 0.005859 -> 0.005817. */
#define PROX_WEIGHT 0.1
/* Views beyond cos theta = 0.2 (78.5 deg: the last 7 rows of a 64-row table) get GRAZING_FACTOR
 * times the directions.  There the LTC cannot follow the horizon-clipped lobe (residual ~0.03),
 * so the control variate does not reduce the noise of the targets: GGX alpha 0.049, 86.4 deg,
 * RMS weighted target error against 2^20 directions: 0.0018 with 4096, 0.00046 with 16384
 * (three scrambles each), and the fitted minv_02 wandered by +-0.015 between neighbouring rows
 * (the gate's ltc_smooth_spike 1.7x); with 16384 the chain and a cold start agree to 0.002.
 * The threshold was 0.1 first: with 4096 directions the warm chain drifted between 80 and 84 deg
 * (alpha 0.036: minv_02 0.143 at 84 deg against 0.170 converged), and the switch to 16384 at
 * 84.3 deg snapped back, a step of 0.02 between rows 59 and 60; at 0.2 the chain matches the
 * converged values there (0.1697 at 84 deg) and the step at 78.5 deg is 0.003. */
#define GRAZING_COS 0.2
#define GRAZING_FACTOR 4

/* ---- forward-mode dual numbers with MF_LTCFIT_DUAL_N derivatives (4 for the isotropic fitter:
 * d/da, d/db, d/dc, d/dd; 7 for the anisotropic one) ------------------------------------------ */

/* The dual operations are forced inline: called out of line (GCC left dcross so), every call
 * copied its 3 x 8 doubles through memory.  Inlining changes no operation (no contraction). */
#if defined(__GNUC__) || defined(__clang__)
#define DUAL_INLINE static inline __attribute__((always_inline))
#else
#define DUAL_INLINE static inline
#endif

typedef struct {
    double v, d[MF_LTCFIT_DUAL_N];
} dual;
typedef struct {
    dual x, y, z;
} dvec3;

DUAL_INLINE dual dconst(double v)
{
    dual r = {v, {0.0}};
    return r;
}
DUAL_INLINE dual dadd(dual a, dual b)
{
    dual r;
    r.v = a.v + b.v;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = a.d[i] + b.d[i];
    return r;
}
DUAL_INLINE dual dsub(dual a, dual b)
{
    dual r;
    r.v = a.v - b.v;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = a.d[i] - b.d[i];
    return r;
}
DUAL_INLINE dual dmul(dual a, dual b)
{
    dual r;
    r.v = a.v * b.v;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = a.d[i] * b.v + a.v * b.d[i];
    return r;
}
DUAL_INLINE dual dscale(dual a, double s)
{
    dual r;
    r.v = a.v * s;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = a.d[i] * s;
    return r;
}
DUAL_INLINE dual ddiv(dual a, dual b)
{
    dual r;
    double inv = 1.0 / b.v;
    r.v = a.v * inv;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = (a.d[i] - r.v * b.d[i]) * inv;
    return r;
}
DUAL_INLINE dual dsqrt(dual a)
{
    dual r;
    r.v = sqrt(a.v);
    double g = r.v > 0.0 ? 0.5 / r.v : 0.0;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = a.d[i] * g;
    return r;
}
DUAL_INLINE dual datan2(dual y, dual x)
{
    dual r;
    r.v = atan2(y.v, x.v);
    double den = x.v * x.v + y.v * y.v;
    double g = den > 0.0 ? 1.0 / den : 0.0;
    for (int i = 0; i < MF_LTCFIT_DUAL_N; ++i)
        r.d[i] = (x.v * y.d[i] - y.v * x.d[i]) * g;
    return r;
}
DUAL_INLINE dual ddot(dvec3 a, dvec3 b) { return dadd(dadd(dmul(a.x, b.x), dmul(a.y, b.y)), dmul(a.z, b.z)); }
DUAL_INLINE dvec3 dcross(dvec3 a, dvec3 b)
{
    dvec3 r = {dsub(dmul(a.y, b.z), dmul(a.z, b.y)), dsub(dmul(a.z, b.x), dmul(a.x, b.z)),
               dsub(dmul(a.x, b.y), dmul(a.y, b.x))};
    return r;
}
DUAL_INLINE dvec3 dnormalize(dvec3 a)
{
    dual inv = ddiv(dconst(1.0), dsqrt(ddot(a, a)));
    dvec3 r = {dmul(a.x, inv), dmul(a.y, inv), dmul(a.z, inv)};
    return r;
}

/* Lambert's edge sum of the polygon q[0..pn-1] (already transformed by a positive multiple of
 * M^-1), clipped at z >= 0 after the transform (docs/math.md, correction C-T4):
 *   E = 1/(2 pi) sum_i theta_i (u_i x u_i+1).z / |u_i x u_i+1|,  theta_i = atan2(|u_i x u_i+1|, u_i.u_i+1)
 * [Nahmias Eq. 2.23, 2.32-2.33] (signed: positive for front-facing polygons), with derivatives. */
DUAL_INLINE dual ltc_clip_integrate_dual(const dvec3 *q, int pn)
{
    /* Sutherland-Hodgman against z >= 0 */
    dvec3 cl[MF_POLYGON_MAX_VERTICES + 1];
    int n = 0;
    for (int i = 0; i < pn; ++i) {
        dvec3 s = q[i], e = q[(i + 1) % pn];
        int s_in = s.z.v >= 0.0, e_in = e.z.v >= 0.0;
        if (s_in)
            cl[n++] = s;
        if (s_in != e_in) {
            dual t = ddiv(s.z, dsub(s.z, e.z));
            dvec3 x = {dadd(s.x, dmul(t, dsub(e.x, s.x))), dadd(s.y, dmul(t, dsub(e.y, s.y))), dconst(0.0)};
            cl[n++] = x;
        }
    }
    dual sum = dconst(0.0);
    if (n < 3)
        return sum;
    for (int i = 0; i < n; ++i)
        cl[i] = dnormalize(cl[i]);
    for (int i = 0; i < n; ++i) {
        dvec3 u = cl[i], w = cl[(i + 1) % n];
        dvec3 cr = dcross(u, w);
        dual s = dsqrt(ddot(cr, cr));
        dual cth = ddot(u, w);
        if (s.v > 1e-12) {
            dual th = datan2(s, cth);
            sum = dadd(sum, dmul(ddiv(th, s), cr.z));
        } else if (cth.v > 0.0) {
            sum = dadd(sum, cr.z); /* theta / sin theta -> 1 for a degenerate edge */
        }
    }
    return dscale(sum, 1.0 / (2.0 * MF_PI));
}

/* The value of ltc_clip_integrate_dual alone, with the same floating-point operations in the same
 * order (so bitwise its .v): for the cost evaluations that need no Jacobian. */
DUAL_INLINE double ltc_clip_integrate_value(const mf_vec3 *q, int pn)
{
    mf_vec3 cl[MF_POLYGON_MAX_VERTICES + 2];
    int n = 0;
    for (int i = 0; i < pn; ++i) {
        mf_vec3 s = q[i], e = q[(i + 1) % pn];
        int s_in = s.z >= 0.0, e_in = e.z >= 0.0;
        if (s_in)
            cl[n++] = s;
        if (s_in != e_in) {
            double t = s.z / (s.z - e.z);
            cl[n].x = s.x + t * (e.x - s.x);
            cl[n].y = s.y + t * (e.y - s.y);
            cl[n].z = 0.0;
            ++n;
        }
    }
    double sum = 0.0;
    if (n < 3)
        return sum;
    for (int i = 0; i < n; ++i) {
        mf_vec3 u = cl[i];
        double inv = 1.0 / sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
        cl[i].x = u.x * inv;
        cl[i].y = u.y * inv;
        cl[i].z = u.z * inv;
    }
    for (int i = 0; i < n; ++i) {
        mf_vec3 u = cl[i], w = cl[(i + 1) % n];
        double cx = u.y * w.z - u.z * w.y, cy = u.z * w.x - u.x * w.z, cz = u.x * w.y - u.y * w.x;
        double sn = sqrt(cx * cx + cy * cy + cz * cz);
        double cth = u.x * w.x + u.y * w.y + u.z * w.z;
        if (sn > 1e-12)
            sum = sum + atan2(sn, cth) / sn * cz;
        else if (cth > 0.0)
            sum = sum + cz;
    }
    return sum * (1.0 / (2.0 * MF_PI));
}

/* ---- test lights ------------------------------------------------------------------------- */

typedef struct {
    mf_polygon poly;
    mf_vec3 centre;     /* unit */
    double cos_radius;  /* cos of the angular radius of the vertices about centre */
    mf_vec3 edge_n[MF_POLYGON_MAX_VERTICES]; /* v_i x v_i+1: inside iff every dot is > 0 */
    double factor;        /* the weight of its residual (1 but for the two low lights) */
    mf_polygon lobe_poly; /* the polygon in the lobe frame: R^T v (see texel) */
    mf_vec3 lobe_upper[MF_POLYGON_MAX_VERTICES + 1]; /* the polygon clipped to the shading */
    int n_upper;                                      /* hemisphere z >= 0, in the lobe frame */
} light;

/* Regular n-gon of angular radius rho about the unit direction c, front-facing (vertices run
 * with increasing phi in the right-handed frame (t1, t2, c)). */
static inline light make_light(mf_vec3 c, int n, double rho, double phi0)
{
    light l;
    mf_frame f = mf_frame_from_normal(c);
    rho = fmin(rho, 1.45);
    double cr = cos(rho), sr = sin(rho);
    mf_vec3 v[MF_POLYGON_MAX_VERTICES];
    for (int i = 0; i < n; ++i) {
        double phi = phi0 + 2.0 * MF_PI * i / n;
        v[i] = mf_frame_to_world(f, mf_vec3_make(sr * cos(phi), sr * sin(phi), cr));
    }
    /* front-facing: the vertices must run counter-clockwise about c seen from outside */
    if (mf_vec3_dot(c, mf_vec3_cross(v[0], v[1])) < 0.0)
        for (int i = 0; i < n / 2; ++i) {
            mf_vec3 tmp = v[i];
            v[i] = v[n - 1 - i];
            v[n - 1 - i] = tmp;
        }
    l.poly = mf_polygon_make(n, v);
    for (int i = 0; i < n; ++i)
        l.edge_n[i] = mf_vec3_cross(v[i], v[(i + 1) % n]);
    l.centre = c;
    l.cos_radius = cr;
    l.factor = 1.0;
    return l;
}

/* Direction at angle delta from m towards the unit tangent t. */
static inline mf_vec3 tilt(mf_vec3 m, mf_vec3 t, double delta)
{
    return mf_vec3_normalize(mf_vec3_add(mf_vec3_scale(m, cos(delta)), mf_vec3_scale(t, sin(delta))));
}

/* The light family around a lobe of mean direction m (unit) and angular width w (radians), in a
 * frame where the view lies in the xz plane (x >= 0), with tangents t1, t2 of m (the isotropic
 * fitter: m in the xz plane, t2 = y, t1 = t2 x m). */
static inline int make_lights_basis(mf_vec3 m, mf_vec3 t1, mf_vec3 t2, double w, light *out)
{
    int k = 0;
    static const double centre_sizes[5] = {0.25, 0.5, 1.0, 2.0, 4.0};
    static const int shapes[3] = {4, 3, 8};
    for (int s = 0; s < 5; ++s)
        for (int h = 0; h < 3; ++h)
            out[k++] = make_light(m, shapes[h], centre_sizes[s] * w, 0.3 * h + 0.1 * s);
    static const double offs[2] = {1.0, 2.5};
    static const double off_sizes[2] = {0.5, 1.5};
    for (int o = 0; o < 2; ++o) {
        mf_vec3 dirs[4] = {t1, mf_vec3_scale(t1, -1.0), t2, mf_vec3_scale(t2, -1.0)};
        for (int j = 0; j < 4; ++j)
            for (int s = 0; s < 2; ++s)
                out[k++] = make_light(tilt(m, dirs[j], fmin(offs[o] * w, 1.2)), s ? 4 : 3, off_sizes[s] * w,
                                      0.5 * j + 0.2 * o);
    }
    /* across the horizon: centred on it, at four azimuths; and one low over the lobe's azimuth:
     * two lights, at +x and -x, with residual weights (1 + s) / 2 and (1 - s) / 2, s = m.x / 0.1
     * clamped to [-1, 1].  (Once a single light at sign(m.x): at alpha ~ 1 the lobe's mean is the
     * normal and m.x changes sign between neighbouring views by Monte Carlo noise alone, so the
     * light jumped sides and the fitted skew minv_20 with it, by +-0.03 from row to row: the
     * gate's ltc_smooth_spike 2.35x at alpha 1.  The objective must be a continuous function of
     * the texel; it is unchanged where |m.x| >= 0.1.) */
    for (int j = 0; j < 4; ++j) {
        double phi = 0.5 * MF_PI * j;
        out[k++] = make_light(mf_vec3_make(cos(phi), sin(phi), 0.0), j % 2 ? 4 : 8, 0.6, 0.25);
    }
    double side = fmin(fmax(m.x / 0.1, -1.0), 1.0);
    out[k] = make_light(mf_vec3_normalize(mf_vec3_make(1.0, 0.0, 0.2)), 4, 0.4, 0.0);
    out[k++].factor = 0.5 * (1.0 + side);
    out[k] = make_light(mf_vec3_normalize(mf_vec3_make(-1.0, 0.0, 0.2)), 4, 0.4, 0.0);
    out[k++].factor = 0.5 * (1.0 - side);
    /* large caps */
    out[k++] = make_light(mf_vec3_make(0.0, 0.0, 1.0), 8, 1.2, 0.0);
    out[k++] = make_light(m, 8, 1.45, 0.2);
    return k;
}

typedef struct {
    mf_vec3 *dir;
    double *w;
    double *pdf;       /* the sampler's density of dir */
    double *cw;        /* control-variate weights D_LTC / pdf */
    double *u;         /* sample points, 2 per direction */
    double *pp;        /* their disk points (mf_model_polar_points; the isotropic fitter's) */
    double *x, *y, *z; /* the live directions, component arrays (the cap pre-test) */
    int *cand;         /* indices passing a light's cap test */
    int n;             /* directions of this texel: base, or GRAZING_FACTOR base at grazing views */
    int base;          /* the options' samples (GRAZING_FACTOR base allocated) */
    int u_n;           /* u holds the first u_n Sobol points of the scramble u_scr (0: none; the
                        * isotropic fitter fills it once per worker, mf_ltcfit.c texel_prepare) */
    uint32_t u_scr[2];
} workspace;

/* The quadrature of texel_magnitude: QUAD_PANELS 8-point panels per axis (mf_model_albedo). */
#define QUAD_PANELS 8

static inline int ws_init(workspace *ws, int base)
{
    int n = GRAZING_FACTOR * base;
    ws->u = malloc(sizeof *ws->u * (size_t)n * 2);
    ws->pp = malloc(sizeof *ws->pp * (size_t)n * 2);
    ws->dir = malloc(sizeof *ws->dir * (size_t)n);
    ws->w = malloc(sizeof *ws->w * (size_t)n);
    ws->pdf = malloc(sizeof *ws->pdf * (size_t)n);
    ws->cw = malloc(sizeof *ws->cw * (size_t)n);
    ws->x = malloc(sizeof *ws->x * (size_t)n * 3);
    ws->y = ws->x ? ws->x + n : NULL;
    ws->z = ws->x ? ws->x + 2 * (size_t)n : NULL;
    ws->cand = malloc(sizeof *ws->cand * (size_t)n);
    ws->n = ws->base = base;
    ws->u_n = 0;
    ws->u_scr[0] = ws->u_scr[1] = 0;
    return ws->dir && ws->w && ws->pdf && ws->cw && ws->x && ws->cand && ws->u && ws->pp;
}
static inline void ws_free(workspace *ws)
{
    free(ws->u);
    free(ws->pp);
    free(ws->dir);
    free(ws->w);
    free(ws->pdf);
    free(ws->cw);
    free(ws->x);
    free(ws->cand);
}

/* The indices of the live directions inside light l, in index order, into ws->cand; returns their
 * count.  A branch-free pass collects the indices inside the light's bounding cap (most of the
 * work, and a branch the CPU cannot predict), then the edge planes are tested on those only. */
static inline int light_inside(const light *l, const workspace *ws, int live)
{
    const double cx = l->centre.x, cy = l->centre.y, cz = l->centre.z, cr = l->cos_radius;
    const double *x = ws->x, *y = ws->y, *z = ws->z;
    int *cand = ws->cand, m = 0, n = 0;
    for (int j = 0; j < live; ++j) {
        cand[m] = j;
        m += x[j] * cx + y[j] * cy + z[j] * cz >= cr;
    }
    for (int i = 0; i < m; ++i) {
        int j = cand[i], in = 1;
        for (int e = 0; e < l->poly.n && in; ++e)
            in = mf_vec3_dot(ws->dir[j], l->edge_n[e]) > 0.0;
        cand[n] = j;
        n += in;
    }
    return n;
}

/* Sum of the weights of the live directions inside light l, in index order (so the same sum, bit
 * for bit, as testing `inside` direction by direction). */
static inline double light_sum(const light *l, const workspace *ws, int live)
{
    int n = light_inside(l, ws, live);
    double s = 0.0;
    for (int i = 0; i < n; ++i)
        s += ws->w[ws->cand[i]];
    return s;
}

/* The sums over the live directions inside light l of y = w, x = cw, x^2 and x y (out[0..3]), in
 * index order. */
static inline void light_sums_cv(const light *l, const workspace *ws, int live, double out[4])
{
    int n = light_inside(l, ws, live);
    double sy = 0.0, sx = 0.0, sxx = 0.0, sxy = 0.0;
    for (int i = 0; i < n; ++i) {
        int j = ws->cand[i];
        sy += ws->w[j];
        sx += ws->cw[j];
        sxx += ws->cw[j] * ws->cw[j];
        sxy += ws->cw[j] * ws->w[j];
    }
    out[0] = sy;
    out[1] = sx;
    out[2] = sxx;
    out[3] = sxy;
}

/* After the model's sample_weights filled ws->dir, ws->pdf, ws->w for ws->n directions: marks the
 * directions that are not valid samples (pdf 0), and sums the weights and the weighted directions
 * in sample order (the bits both fitters had).  MF_ERR_DOMAIN for a valid sample with a non-finite
 * weight. */
static inline mf_status ws_weight_sums(workspace *ws, double *sum_out, mf_vec3 *mean_out)
{
    double sum = 0.0;
    mf_vec3 mean = {0.0, 0.0, 0.0};
    for (int j = 0; j < ws->n; ++j) {
        mf_vec3 wi = ws->dir[j];
        double w = ws->w[j];
        if (ws->pdf[j] > 0.0 && wi.z > 0.0 && mf_vec3_isfinite(wi)) {
            if (!isfinite(w))
                return MF_ERR_DOMAIN;
        } else {
            ws->pdf[j] = 0.0;
        }
        sum += w;
        mean = mf_vec3_add(mean, mf_vec3_scale(wi, w));
    }
    *sum_out = sum;
    *mean_out = mean;
    return MF_OK;
}

/* ---- the control variate's weights, two directions at a time (both fitters; moved here from
 * mf_ltcfit.c unchanged, so that the anisotropic fitter shares them) -------------------------- */

/* 2-wide vectors where the compiler has them (GCC and Clang vector extensions); cv_weights and the
 * isotropic fitter's edge_select use them. */
#if defined(__GNUC__) || defined(__clang__)
#define LS_VEC2 1
typedef double ls_v2d __attribute__((vector_size(16)));
typedef long long ls_v2l __attribute__((vector_size(16)));
#endif

/* cw_j = magnitude D(w_j) / pdf_j for the live directions: mf_ltc_eval's operations, in its order,
 * two directions at a time in 2-wide vectors where the compiler has them (the same IEEE operations
 * per element, nothing contracted); a pair with a direction mf_ltc_eval would reject (not finite,
 * zero or overflowing length) goes through mf_ltc_eval itself.  1 if every cw_j is finite. */
static inline int cv_weights(const mf_ltc *ltc, double magnitude, const workspace *ws, int live)
{
    int j = 0;
#ifdef LS_VEC2
    const mf_mat3 a = ltc->inv;
    const ls_v2d k = {ltc->abs_det_inv, ltc->abs_det_inv};
    for (; j + 2 <= live; j += 2) {
        ls_v2d x, y, z, pdf;
        memcpy(&x, ws->x + j, sizeof x);
        memcpy(&y, ws->y + j, sizeof y);
        memcpy(&z, ws->z + j, sizeof z);
        memcpy(&pdf, ws->pdf + j, sizeof pdf);
        ls_v2d len = x * x + y * y + z * z;
        len = (ls_v2d){sqrt(len[0]), sqrt(len[1])};
        if (!(isfinite(x[0]) && isfinite(y[0]) && isfinite(z[0]) && isfinite(x[1]) && isfinite(y[1]) && isfinite(z[1]) &&
              len[0] > 0.0 && len[1] > 0.0 && isfinite(len[0]) && isfinite(len[1]))) {
            for (int q = j; q < j + 2; ++q)
                ws->cw[q] = magnitude * mf_ltc_eval(ltc, ws->dir[q]) / ws->pdf[q];
            continue;
        }
        ls_v2d s = 1.0 / len;
        ls_v2d vx = x * s, vy = y * s, vz = z * s;
        ls_v2d ux = a.m[0][0] * vx + a.m[0][1] * vy + a.m[0][2] * vz;
        ls_v2d uy = a.m[1][0] * vx + a.m[1][1] * vy + a.m[1][2] * vz;
        ls_v2d uz = a.m[2][0] * vx + a.m[2][1] * vy + a.m[2][2] * vz;
        ls_v2d r = ux * ux + uy * uy + uz * uz;
        r = (ls_v2d){sqrt(r[0]), sqrt(r[1])};
        ls_v2d d = (uz / r) * (k / (r * r * r)) * MF_INV_PI;
        ls_v2d cw = magnitude * d / pdf;
        ws->cw[j] = uz[0] > 0.0 ? cw[0] : magnitude * 0.0 / ws->pdf[j];
        ws->cw[j + 1] = uz[1] > 0.0 ? cw[1] : magnitude * 0.0 / ws->pdf[j + 1];
    }
#endif
    for (; j < live; ++j)
        ws->cw[j] = magnitude * mf_ltc_eval(ltc, ws->dir[j]) / ws->pdf[j];
    int ok = 1;
    for (j = 0; j < live; ++j)
        ok &= isfinite(ws->cw[j]) != 0;
    return ok;
}

static inline void sobol_scramble(uint64_t seed, uint32_t scr[2])
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, 0x6c74636669747331ull);
    scr[0] = mf_pcg32_next_u32(&rng);
    scr[1] = mf_pcg32_next_u32(&rng);
}

#endif /* MF_LTCFIT_SHARED_H */
