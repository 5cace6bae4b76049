/* mf_ltcfit.c -- LTC table fitting (mf_ltcfit.h; the objective is described there and in
 * docs/tables.md). */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_ltcfit.h"

#include "mfkit/mf_brdf.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_sample.h"
#include "mfkit/fit/mf_solver.h"
#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_json.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MF_LTCFIT_DUAL_N 4
#include "mf_ltcfit_shared.h"

/* The checkpoint's magic names the fitter revision: bump it whenever the fitted values change
 * (objective, lights, constants), so that --resume refuses a checkpoint of another revision
 * instead of mixing columns of two fitters.  2: control variate, proximal shears, mirror
 * convention, 4x directions at grazing views.  3: proximal scales too. */
/* Revision 4: the body is followed by its FNV-1a 64 checksum (revision 3 files are refused).
 * 5: the cap about the normal faded for narrow lobes near its rim (normal_cap_factor).
 * 6: charlie fitted in the sheen family (sheen_family). */
#define CKPT_MAGIC "MFLTCCK6"
#define ENTRY_DOUBLES 19
#define PROX_RESIDUALS 4

void mf_ltcfit_options_default(mf_ltcfit_options *o)
{
    memset(o, 0, sizeof *o);
    o->n_r = o->n_u = 64;
    o->threads = 1;
    o->seed = 1;
    o->samples = 4096;
    o->max_iterations = 100;
    o->r_lo = o->u_lo = 0.0;
    o->r_hi = o->u_hi = 1.0;
}

/* Integral of D_LTC over the polygon p (view frame) for M = [[a, 0, b], [0, c, 0], [d, 0, 1]]
 * with its derivatives: the polygon is transformed by the positively scaled inverse
 *   M^-1 ~ [[1, 0, -b], [0, (a - b d)/c, 0], [-d, 0, a]]      ((a - b d) M^-1, det M = c (a - b d))
 * (the integral is invariant under positive scalings of M^-1), clipped at z >= 0 after the
 * transform (docs/math.md, correction C-T4), and integrated by Lambert's edge sum
 *   E = 1/(2 pi) sum_i theta_i (u_i x u_i+1).z / |u_i x u_i+1|,  theta_i = atan2(|u_i x u_i+1|, u_i.u_i+1)
 * [Nahmias Eq. 2.23, 2.32-2.33] (signed: positive for the front-facing lights used here). */
static dual ltc_integral_dual(const mf_polygon *p, const double prm[4])
{
    double a = prm[0], b = prm[1], c = prm[2], d = prm[3];
    double k = (a - b * d) / c;
    double dk[4] = {1.0 / c, -d / c, -k / c, -b / c};
    dvec3 q[MF_POLYGON_MAX_VERTICES];
    for (int i = 0; i < p->n; ++i) {
        mf_vec3 v = p->v[i];
        dvec3 t;
        t.x = dconst(v.x - b * v.z);
        t.x.d[1] = -v.z;
        t.y = dconst(k * v.y);
        for (int j = 0; j < 4; ++j)
            t.y.d[j] = dk[j] * v.y;
        t.z = dconst(-d * v.x + a * v.z);
        t.z.d[0] = v.z;
        t.z.d[3] = -v.x;
        q[i] = t;
    }
    return ltc_clip_integrate_dual(q, p->n);
}

/* The value of ltc_integral_dual alone, with the same floating-point operations in the same
 * order (so bitwise its .v), for the cost evaluations that need no Jacobian (the closed-form
 * start's grid, the warm start's cost, the final residual): ~4x cheaper than the dual form. */
static double ltc_integral_value_v(const mf_vec3 *pv, int pn, const double prm[4])
{
    double a = prm[0], b = prm[1], c = prm[2], d = prm[3];
    double k = (a - b * d) / c;
    mf_vec3 q[MF_POLYGON_MAX_VERTICES + 1];
    for (int i = 0; i < pn; ++i) {
        mf_vec3 v = pv[i];
        q[i].x = v.x - b * v.z;
        q[i].y = k * v.y;
        q[i].z = -d * v.x + a * v.z;
    }
    return ltc_clip_integrate_value(q, pn);
}

/* ---- the sheen family (charlie) --------------------------------------------------------------
 * For the Charlie sheen lobe [Estevez & Kulla 2017] the table is fitted in the restricted family
 * of Zeltner, Burley and Chiang ["Practical Multiple-Scattering Sheen Using Linearly Transformed
 * Cosines", 2022: the same matrix form, M = [[1/a, 0, -b/a], [0, 1/a, 0], [0, 0, 1]]], parametrised in
 * the VIEW frame by its inverse:
 *   M^-1 = [[a, 0, b], [0, a, 0], [0, 0, 1]]      (a > 0; stored table: minv = M^-1 / a)
 * Why not the general family about the lobe's mean (above): near the normal view at low roughness
 * charlie reflects into a ring at the horizon of width ~2 alpha, which that family held as
 * diag(s, s, 1), s ~ 1/(2 alpha), ill-conditioned where the ring meets the horizon lobe; its mean
 * direction is the normal at the normal view and swings by ~3x the view's rate just off it (alpha
 * 0.27: 0, 8, 14 deg at views 0, 2.6, 5.2 deg), and the lobe frame turns with it; and a ring is not
 * unimodal for four parameters (refits landed 16 % to 6x away).  In this family the ring is a -> 0
 * with b = 0 (the cosine stretched towards the horizon, peaking ~a from it), b tilts it towards or
 * away from the view, every parameter is continuous at the normal view (where b = 0 by symmetry)
 * and independent of the lobe's mean (the lights are still placed about it), and two parameters
 * leave one minimum, found by a grid search (closed_form_start). */
/* The sheen family's domain: the stored minv_22 = 1/a and minv_02 = b/a stay within the RGBA16F
 * exports' range (65504): a >= 2^-14, |b| <= 2^15 a.  Without it charlie's texels of albedo
 * ~1e-300 (alpha 1e-4 short of 60 deg, where a is not determined by any light) stored
 * minv_02 = -7.5e5, infinite in half floats. */
#define SHEEN_A_MIN 0x1p-14
#define SHEEN_B_PER_A 0x1p15
static int sheen_family(const mf_brdf_model *m) { return m && m->name && !strcmp(m->name, "charlie"); }

/* The integral of the sheen-family LTC over polygon p (view frame), with d/da and d/db: the
 * polygon transformed by M^-1 itself (positive scalings do not matter), clipped and integrated as
 * in ltc_integral_dual. */
static dual sheen_integral_dual(const mf_vec3 *pv, int pn, const double prm[2])
{
    double a = prm[0], b = prm[1];
    dvec3 q[MF_POLYGON_MAX_VERTICES];
    for (int i = 0; i < pn; ++i) {
        mf_vec3 v = pv[i];
        dvec3 t;
        t.x = dconst(a * v.x + b * v.z);
        t.x.d[0] = v.x;
        t.x.d[1] = v.z;
        t.y = dconst(a * v.y);
        t.y.d[0] = v.y;
        t.z = dconst(v.z);
        q[i] = t;
    }
    return ltc_clip_integrate_dual(q, pn);
}

/* Its value alone (the same operations, so bitwise the .v of sheen_integral_dual). */
static double sheen_integral_value_v(const mf_vec3 *pv, int pn, const double prm[2])
{
    double a = prm[0], b = prm[1];
    mf_vec3 q[MF_POLYGON_MAX_VERTICES + 1];
    for (int i = 0; i < pn; ++i) {
        mf_vec3 v = pv[i];
        q[i].x = a * v.x + b * v.z;
        q[i].y = a * v.y;
        q[i].z = v.z;
    }
    return ltc_clip_integrate_value(q, pn);
}

/* The view-frame M of sheen parameters (a, b): the inverse of [[a, 0, b], [0, a, 0], [0, 0, 1]]. */
static mf_mat3 sheen_matrix(const double q[2])
{
    double a = q[0], b = q[1];
    mf_mat3 mv = {{{1.0 / a, 0.0, -b / a}, {0.0, 1.0 / a, 0.0}, {0.0, 0.0, 1.0}}};
    return mv;
}

/* Sheen parameters of a view-frame matrix: M^-1 normalised by its (2, 2) element, a the mean of
 * its (0, 0) and (1, 1) elements (the projection onto the family); 0 if there is none. */
static int sheen_params(mf_mat3 mv, double q[4])
{
    mf_mat3 inv;
    if (mf_mat3_inverse(mv, &inv) != MF_OK)
        return 0;
    double n = inv.m[2][2];
    if (!(n > 0.0) || !isfinite(n))
        return 0;
    q[0] = q[2] = 0.5 * (inv.m[0][0] + inv.m[1][1]) / n;
    q[1] = inv.m[0][2] / n;
    q[3] = 0.0;
    return q[0] > 0.0 && isfinite(q[0]) && isfinite(q[1]);
}

/* The residual weight of the large cap about the normal (radius NCAP_RADIUS, a vertex at the
 * lobe's azimuth 0 or pi) for a lobe of mean direction m and RMS angular width w:
 *   1 - g(w) h(x),  x = |theta_m - NCAP_RADIUS| / w  (the lobe's distance to the cap's rim in widths),
 * g = 1 for w <= NCAP_FADE_W0 and h = 1 for x <= NCAP_FADE_X0, each falling to 0 by a smoothstep
 * at NCAP_FADE_W1, NCAP_FADE_X1: continuous in the texel, and exactly 1 for lobes wider than
 * NCAP_FADE_W1 or more than NCAP_FADE_X1 widths from the rim.
 * Why: for a narrow lobe the rim is a straight edge through its tail, and the cap's integral is
 * the lobe's tail mass on one side of it.  The LTC's tails are not the model's (Beckmann's fall
 * like a Gaussian), so the fit bent the lobe's skew to match that one number in the rows the rim
 * passes through: Beckmann 64 x 64, alpha 0.004, 69.8 deg (the rim 1.1 deg from the lobe, x = 3.1)
 * took minv_22 across its neighbours' range (the gate's ltc_smooth_spike 1.253), the skew d
 * jumping from -0.04 to +0.07 and back within two rows, at alpha 0.0023 .. 0.0063.  The other
 * lights about the lobe (0.25 w .. 4 w, offsets w and 2.5 w) still hold its shape there. */
#define NCAP_RADIUS 1.2
#define NCAP_FADE_W0 0.015
#define NCAP_FADE_W1 0.03
#define NCAP_FADE_X0 8.0
#define NCAP_FADE_X1 16.0

static double smooth_fall(double v, double lo, double hi)
{
    if (v <= lo)
        return 1.0;
    if (v >= hi)
        return 0.0;
    double s = (v - lo) / (hi - lo);
    return 1.0 - s * s * (3.0 - 2.0 * s);
}

static double normal_cap_factor(mf_vec3 m, double w)
{
    if (!(w < NCAP_FADE_W1))
        return 1.0;
    double x = fabs(acos(fmin(1.0, fmax(-1.0, m.z))) - NCAP_RADIUS) / w;
    if (!(x < NCAP_FADE_X1))
        return 1.0;
    return 1.0 - smooth_fall(w, NCAP_FADE_W0, NCAP_FADE_W1) * smooth_fall(x, NCAP_FADE_X0, NCAP_FADE_X1);
}

/* The light family around a lobe of mean direction m (unit, in the xz plane of the view frame)
 * and angular width w (radians); the cap about the normal weighted by normal_cap_factor. */
static int make_lights(mf_vec3 m, double w, light *out)
{
    mf_vec3 t2 = mf_vec3_make(0.0, 1.0, 0.0);
    mf_vec3 t1 = mf_vec3_cross(t2, m);
    int k = make_lights_basis(m, t1, t2, w, out);
    out[k - 2].factor = normal_cap_factor(m, w); /* the large cap about the normal (make_lights_basis) */
    return k;
}

int mf_ltcfit_light_count(void)
{
    light tmp[LIGHTS_MAX];
    return make_lights(mf_vec3_make(0.0, 0.0, 1.0), 0.1, tmp);
}

/* ---- per-texel preparation ---------------------------------------------------------------- */

typedef struct {
    int k;
    light lights[LIGHTS_MAX];
    double target[LIGHTS_MAX]; /* I_k */
    double inv_weight[LIGHTS_MAX];
    double raw_target[LIGHTS_MAX]; /* I_k from the samples alone (before the control variate) */
    int live;                      /* directions of positive density kept in the workspace */
    double prox;                   /* weight of the proximal residuals (0: none) */
    double prox_at[4];             /* the lobe-frame parameters they pull towards */
    double scale;                  /* the weights' factor to the quadrature magnitude */
    double invn;                   /* scale / N */
    double magnitude, magnitude_err, fresnel;
    double a_min;   /* the sheen family's lower bound of a (SHEEN_A_MIN) */
    int sheen;      /* the sheen family (sheen_family): parameters (a, b) of the view-frame M^-1, and
                     * lobe_poly / lobe_upper hold the lights in the view frame */
    double *sc_dot; /* scratch of texel_light_sums: the cap dot products of a centre's candidates */
    int *sc_in;     /* and the indices inside one light (all sized for the texel's directions) */
    double *sc_x, *sc_y, *sc_z; /* the candidates' components */
    mf_vec3 lobe;   /* mean direction m of f cos (unit, xz plane); the lobe frame is R = [[mz, 0, mx],
                     * [0, 1, 0], [-mx, 0, mz]] (R z = m), and the solver's parameters are those of
                     * M' = R^T M = [[a', 0, b'], [0, c', 0], [d', 0, 1]]: the same 4-parameter family
                     * as the view-frame form, but well conditioned when the lobe nears the horizon
                     * (where the view-frame M22 -> 0 and b -> infinity) */
} texel;

/* The magnitude (albedo) and Fresnel fields: mf_model_albedo_fresnel with the default rule
 * (MF_MODEL_ALBEDO_N = QUAD_PANELS 8-point panels per axis). */
static mf_status texel_magnitude(const mf_brdf_model *m, double alpha, mf_vec3 wo, workspace *ws, texel *t)
{
    (void)ws;
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    mf_result alb, fres;
    mf_status st = mf_model_albedo_fresnel(m, &p, wo, 8 * QUAD_PANELS, &alb, &fres);
    t->magnitude = alb.val;
    t->magnitude_err = alb.err;
    t->fresnel = fres.val;
    return st;
}

static mf_vec3 view_dir(double cos_theta)
{
    return mf_vec3_make(sqrt(fmax(0.0, 1.0 - cos_theta * cos_theta)), 0.0, cos_theta);
}

static mf_mat3 view_matrix(mf_vec3 m, const double q[4]);

/* R^T v: a view-frame direction in the lobe frame of mean direction m (see texel). */
static mf_vec3 to_lobe(mf_vec3 m, mf_vec3 v)
{
    return mf_vec3_make(m.z * v.x - m.x * v.z, v.y, m.x * v.x + m.z * v.z);
}

/* A texel without its scratch (texel_prepare allocates it); texel_free frees both. */
static texel *texel_new(void)
{
    texel *t = malloc(sizeof *t);
    if (t)
        t->sc_dot = t->sc_x = NULL, t->sc_in = NULL;
    return t;
}

static void texel_free(texel *t)
{
    if (t) {
        free(t->sc_dot);
        free(t->sc_in);
        free(t->sc_x);
        free(t);
    }
}

/* The texel's family: its parameter count, domain, integrals and view-frame matrix. */
static int texel_np(const texel *t) { return t->sheen ? 2 : 4; }

static int texel_params_ok(const texel *t, const double *p)
{
    if (t->sheen)
        return p[0] >= t->a_min && fabs(p[1]) <= SHEEN_B_PER_A * p[0];
    return p[0] > 0.0 && p[2] > 0.0 && p[0] - p[1] * p[3] > 0.0;
}

static dual texel_integral_dual(const texel *t, const mf_polygon *poly, const double *p)
{
    return t->sheen ? sheen_integral_dual(poly->v, poly->n, p) : ltc_integral_dual(poly, p);
}

static double texel_integral_value_v(const texel *t, const mf_vec3 *pv, int pn, const double *p)
{
    return t->sheen ? sheen_integral_value_v(pv, pn, p) : ltc_integral_value_v(pv, pn, p);
}

static mf_mat3 texel_view_matrix(const texel *t, const double *p)
{
    return t->sheen ? sheen_matrix(p) : view_matrix(t->lobe, p);
}

/* Samples, magnitude, lobe statistics, lights and their BRDF integrals of one texel. */
static mf_status texel_prepare(const mf_brdf_model *m, double alpha, double cos_theta, const uint32_t scr[2],
                               const mf_result *albedo, const double *fresnel, workspace *ws, texel *t)
{
    mf_vec3 wo = view_dir(cos_theta);
    ws->n = cos_theta < GRAZING_COS ? GRAZING_FACTOR * ws->base : ws->base;
    t->sc_dot = malloc(sizeof *t->sc_dot * (size_t)ws->n);
    t->sc_in = malloc(sizeof *t->sc_in * (size_t)ws->n);
    t->sc_x = malloc(sizeof *t->sc_x * 3 * (size_t)ws->n);
    if (!t->sc_dot || !t->sc_in || !t->sc_x)
        return MF_ERR_ALLOC;
    t->sc_y = t->sc_x + ws->n;
    t->sc_z = t->sc_y + ws->n;
    mf_status st = MF_OK;
    if (albedo) { /* given (mf_ltcfit_entry_fit_albedo, mf_ltcfit_options.albedo): the same rule's
                   * value; the Fresnel moment when given, else NaN */
        t->magnitude = albedo->val;
        t->magnitude_err = albedo->err;
        t->fresnel = fresnel ? *fresnel : NAN;
        if (!isfinite(albedo->val))
            return MF_ERR_DOMAIN;
    } else if ((st = texel_magnitude(m, alpha, wo, ws, t)) != MF_OK)
        return st;
    /* the points depend on the index and the scramble only: every texel of a worker uses the same
     * prefix, computed once (u_n points of u_scr kept in the workspace, with their disk points) */
    if (ws->u_n < ws->n || ws->u_scr[0] != scr[0] || ws->u_scr[1] != scr[1]) {
        for (int j = 0; j < ws->n; ++j)
            mf_sobol2((uint32_t)j, scr[0], scr[1], ws->u + 2 * j);
        mf_model_polar_points(ws->n, ws->u, ws->pp);
        ws->u_n = ws->n;
        ws->u_scr[0] = scr[0];
        ws->u_scr[1] = scr[1];
    }
    mf_brdf_params prm = mf_brdf_params_iso(alpha);
    mf_model_sample_weights_polar(m, &prm, wo, ws->n, ws->u, ws->pp, ws->dir, ws->pdf, ws->w);
    double sum;
    mf_vec3 mean;
    if ((st = ws_weight_sums(ws, &sum, &mean)) != MF_OK)
        return st;
    /* rescale the weights so that their mean is the quadrature albedo */
    double scale = sum > 0.0 ? t->magnitude * ws->n / sum : 0.0;
    double ml = mf_vec3_length(mean);
    mf_vec3 m_dir = ml > 0.0 ? mf_vec3_scale(mean, 1.0 / ml) : mf_vec3_make(0.0, 0.0, 1.0);
    m_dir.y = 0.0; /* isotropic: the lobe's mean lies in the xz plane */
    m_dir = mf_vec3_normalize(m_dir);
    double ang2 = 0.0;
    for (int j = 0; j < ws->n; ++j)
        if (ws->w[j] > 0.0) {
            /* |w - m|^2 = (2 sin(angle/2))^2: the squared angle for small angles, no cancellation */
            mf_vec3 dv = mf_vec3_sub(ws->dir[j], m_dir);
            ang2 += ws->w[j] * mf_vec3_dot(dv, dv);
        }
    double width = sum > 0.0 ? sqrt(ang2 / sum) : 0.5;
    width = fmin(fmax(width, 1e-4), 1.2);
    t->lobe = m_dir;
    t->sheen = sheen_family(m);
    t->a_min = t->sheen ? SHEEN_A_MIN : A_MIN;
    t->k = make_lights(m_dir, width, t->lights);
    double invn = scale / ws->n;
    /* compact the directions of positive density (order kept: same sums; those of zero weight
     * still count for the control variate) */
    int live = 0;
    for (int j = 0; j < ws->n; ++j)
        if (ws->pdf[j] > 0.0) {
            ws->dir[live] = ws->dir[j];
            ws->pdf[live] = ws->pdf[j];
            ws->w[live++] = ws->w[j];
        }
    t->live = live;
    t->prox = 0.0;
    memset(t->prox_at, 0, sizeof t->prox_at);
    t->scale = scale;
    for (int j = 0; j < live; ++j) {
        ws->x[j] = ws->dir[j].x;
        ws->y[j] = ws->dir[j].y;
        ws->z[j] = ws->dir[j].z;
    }
    t->invn = invn;
    for (int k = 0; k < t->k; ++k) {
        light *l = &t->lights[k];
        l->lobe_poly = l->poly;
        for (int i = 0; i < l->poly.n && !t->sheen; ++i)
            l->lobe_poly.v[i] = to_lobe(m_dir, l->poly.v[i]);
        /* the part of the light the samples can reach: clipped to z >= 0 (Sutherland-Hodgman) */
        l->n_upper = 0;
        for (int i = 0; i < l->poly.n; ++i) {
            mf_vec3 a = l->poly.v[i], b = l->poly.v[(i + 1) % l->poly.n];
            if (a.z >= 0.0)
                l->lobe_upper[l->n_upper++] = t->sheen ? a : to_lobe(m_dir, a);
            if ((a.z >= 0.0) != (b.z >= 0.0)) {
                double f = a.z / (a.z - b.z);
                mf_vec3 x = mf_vec3_make(a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), 0.0);
                l->lobe_upper[l->n_upper++] = t->sheen ? x : to_lobe(m_dir, x);
            }
        }
    }
    return MF_OK;
}

/* The candidates i < m (components X, Y, Z, indices cand) inside every edge plane of light l
 * (light_inside's test X ex + Y ey + Z ez > 0 for every edge, without its early exit: the same
 * answer, the tests have no side effects): their indices into in[], in order; returns their count.
 * Two candidates at a time in 2-wide vectors where the compiler has them (GCC and Clang vector
 * extensions): the same IEEE operations in the same order per element (the build contracts
 * nothing), all edges in registers; the scalar loop is the same test. */
static int edge_select(const light *l, int m, const double *X, const double *Y, const double *Z, const int *cand,
                       int *in)
{
    const int ne = l->poly.n;
    int n = 0, i = 0;
#ifdef LS_VEC2
    ls_v2d ex[MF_POLYGON_MAX_VERTICES], ey[MF_POLYGON_MAX_VERTICES], ez[MF_POLYGON_MAX_VERTICES];
    for (int e = 0; e < ne; ++e) {
        ex[e] = (ls_v2d){l->edge_n[e].x, l->edge_n[e].x};
        ey[e] = (ls_v2d){l->edge_n[e].y, l->edge_n[e].y};
        ez[e] = (ls_v2d){l->edge_n[e].z, l->edge_n[e].z};
    }
    for (; i + 2 <= m; i += 2) {
        ls_v2d x, y, z;
        memcpy(&x, X + i, sizeof x);
        memcpy(&y, Y + i, sizeof y);
        memcpy(&z, Z + i, sizeof z);
        ls_v2l ok = (x * ex[0] + y * ey[0] + z * ez[0]) > 0.0;
        for (int e = 1; e < ne; ++e)
            ok &= (x * ex[e] + y * ey[e] + z * ez[e]) > 0.0;
        in[n] = cand[i];
        n += ok[0] != 0;
        in[n] = cand[i + 1];
        n += ok[1] != 0;
    }
#endif
    for (; i < m; ++i) {
        int ok = 1;
        for (int e = 0; e < ne; ++e)
            ok &= X[i] * l->edge_n[e].x + Y[i] * l->edge_n[e].y + Z[i] * l->edge_n[e].z > 0.0;
        in[n] = cand[i];
        n += ok;
    }
    return n;
}

/* The sums over the live directions inside each light k (light_inside's test: the bounding cap,
 * then the edge planes), in index order: out[4 k + 0..3] = sum of w, and with cv also of cw, cw^2
 * and cw w (light_sum, light_sums_cv).  The same sums, bit for bit, with less work: lights whose
 * centres are the same bits (the 16 lights about the lobe's mean, the pairs of side lights) share
 * one pass over the directions, whose cap dot products (the same expression as light_inside's)
 * are kept for the candidates of the widest cap and narrowed in place for each smaller one (a
 * direction within a cap is within every wider cap of the same centre).  48 passes over the
 * directions become 16. */
static void texel_light_sums(const texel *t, const workspace *ws, int cv, double *out)
{
    const int live = t->live;
    const double *x = ws->x, *y = ws->y, *z = ws->z;
    int *cand = ws->cand, *in = t->sc_in;
    double *dot = t->sc_dot;
    unsigned char done[LIGHTS_MAX] = {0};
    for (int k0 = 0; k0 < t->k; ++k0) {
        if (done[k0])
            continue;
        /* the lights of this centre, widest cap (smallest cos_radius) first (stable) */
        int grp[LIGHTS_MAX] = {0}, ng = 0;
        const mf_vec3 c = t->lights[k0].centre;
        for (int k = k0; k < t->k; ++k)
            if (!done[k] && memcmp(&t->lights[k].centre, &c, sizeof c) == 0) {
                int i = ng++;
                while (i > 0 && t->lights[grp[i - 1]].cos_radius > t->lights[k].cos_radius) {
                    grp[i] = grp[i - 1];
                    --i;
                }
                grp[i] = k;
                done[k] = 1;
            }
        const double cx = c.x, cy = c.y, cz = c.z, cr0 = t->lights[grp[0]].cos_radius;
        double *X = t->sc_x, *Y = t->sc_y, *Z = t->sc_z;
        int m = 0;
        for (int j = 0; j < live; ++j) {
            double d = x[j] * cx + y[j] * cy + z[j] * cz;
            cand[m] = j;
            dot[m] = d;
            X[m] = x[j];
            Y[m] = y[j];
            Z[m] = z[j];
            m += d >= cr0;
        }
        double cr_done = cr0;
        for (int g = 0; g < ng; ++g) {
            const light *l = &t->lights[grp[g]];
            const double cr = l->cos_radius;
            if (cr != cr_done) { /* a smaller cap: narrow the candidates in place */
                int m2 = 0;
                for (int i = 0; i < m; ++i) {
                    cand[m2] = cand[i];
                    dot[m2] = dot[i];
                    X[m2] = X[i];
                    Y[m2] = Y[i];
                    Z[m2] = Z[i];
                    m2 += dot[i] >= cr;
                }
                m = m2;
                cr_done = cr;
            }
            const int n = edge_select(l, m, X, Y, Z, cand, in);
            double *o = out + 4 * grp[g];
            if (!cv) {
                double sy = 0.0;
                for (int i = 0; i < n; ++i)
                    sy += ws->w[in[i]];
                o[0] = sy;
                o[1] = o[2] = o[3] = 0.0;
            } else {
                double sy = 0.0, sx = 0.0, sxx = 0.0, sxy = 0.0;
                for (int i = 0; i < n; ++i) {
                    int j = in[i];
                    sy += ws->w[j];
                    sx += ws->cw[j];
                    sxx += ws->cw[j] * ws->cw[j];
                    sxy += ws->cw[j] * ws->w[j];
                }
                o[0] = sy;
                o[1] = sx;
                o[2] = sxx;
                o[3] = sxy;
            }
        }
    }
}

/* The targets from the samples alone: I_k = Y^_k. */
static void texel_targets_raw(texel *t, const workspace *ws)
{
    double sums[4 * LIGHTS_MAX];
    texel_light_sums(t, ws, 0, sums);
    for (int k = 0; k < t->k; ++k) {
        t->target[k] = t->raw_target[k] = sums[4 * k] * t->invn;
        t->inv_weight[k] = t->lights[k].factor / (t->target[k] + WEIGHT_FLOOR * t->magnitude + 1e-300);
    }
}

/* Control variate [Owen, "Monte Carlo theory, methods and examples", 2013, Sec. 8.9]: with an
 * LTC D_0 close to the texel's lobe (lobe-frame parameters p0: the warm start, the previous
 * texel's fit), whose integral over each light is known exactly, the target of light k becomes
 *   I_k = Y^_k - beta_k (X^_k - magnitude C_k),
 *   Y^_k = (1/N) sum_j y_j [w_j in P_k],  y_j = f cos / pdf (scaled to the quadrature magnitude),
 *   X^_k = (1/N) sum_j x_j [w_j in P_k],  x_j = magnitude D_0(w_j) / pdf(w_j),
 *   C_k  = integral of D_0 over P_k clipped to z >= 0 (where the sampler's density is positive),
 * with beta_k = sum_j (x_j - X^_k)(y_j - Y^_k) / sum_j (x_j - X^_k)^2 (sums over all N directions,
 * x_j and y_j 0 outside the light: the least-squares regression coefficient of y on x), clamped
 * to [0, 1]: the estimate stays consistent for any p0, and beta_k -> 0 when D_0 / pdf is heavy
 * tailed (a sliver LTC at grazing views of smooth BRDFs put a direction of weight 4600 x the
 * others' into a light: beta = 1 turned targets of 0.9 into 0.2).  The same directions cross the
 * same light edges in Y^_k and X^_k, so the edge noise of Y^_k (a direction entering or leaving a
 * light between neighbouring texels) cancels to the extent that magnitude D_0 matches f cos.
 * Measured at GGX alpha 1, 4096 samples: the weakly determined skew (view-frame d, 65-88 deg)
 * wandered by +-0.006 between neighbouring rows from this noise; +-0.001 with the control. */
static void texel_control_variate(texel *t, workspace *ws, const double p0[4])
{
    mf_ltc ltc;
    int ok = mf_ltc_init(&ltc, texel_view_matrix(t, p0)) == MF_OK && cv_weights(&ltc, t->magnitude, ws, t->live);
    if (!ok) {
        texel_targets_raw(t, ws);
        return;
    }
    const double n = ws->n;
    double sums[4 * LIGHTS_MAX];
    texel_light_sums(t, ws, 1, sums);
    for (int k = 0; k < t->k; ++k) {
        const light *l = &t->lights[k];
        const double *sm = sums + 4 * k;
        /* y_j = scale w_j */
        double my = sm[0] * t->invn, mx = sm[1] / n;
        double sxx = sm[2] - n * mx * mx, sxy = t->scale * sm[3] - n * mx * my;
        double beta = sxx > 0.0 ? fmin(fmax(sxy / sxx, 0.0), 1.0) : 0.0;
        double c = l->n_upper >= 3 ? texel_integral_value_v(t, l->lobe_upper, l->n_upper, p0) : 0.0;
        t->raw_target[k] = my;
        t->target[k] = my - beta * (mx - t->magnitude * c);
        t->inv_weight[k] = l->factor / (fmax(t->target[k], 0.0) + WEIGHT_FLOOR * t->magnitude + 1e-300);
    }
}

/* ---- the least-squares problem ------------------------------------------------------------ */

/* lambda (b' - b'_prev), lambda (d' - d'_prev), lambda (a' - a'_prev) / a'_prev,
 * lambda (c' - c'_prev) / c'_prev (lambda = t->prox; all 0 when t->prox is 0). */
static void prox_residuals(const texel *t, const double *p, double out[PROX_RESIDUALS])
{
    if (!(t->prox > 0.0)) {
        for (int i = 0; i < PROX_RESIDUALS; ++i)
            out[i] = 0.0;
        return;
    }
    if (t->sheen) { /* the shear relative beyond 1 (at low roughness the fitted b goes from ~-30 at 40 deg
                     * to ~-3 at 78 deg: an absolute pull held a column at b = -35 where its lights'
                     * optimum was -3, cost 20x the optimum's), the scale relative; two unused */
        out[0] = t->prox * (p[1] - t->prox_at[1]) / fmax(1.0, fabs(t->prox_at[1]));
        out[1] = out[3] = 0.0;
        out[2] = t->prox * (p[0] - t->prox_at[0]) / t->prox_at[0];
        return;
    }
    out[0] = t->prox * (p[1] - t->prox_at[1]);
    out[1] = t->prox * (p[3] - t->prox_at[3]);
    out[2] = t->prox * (p[0] - t->prox_at[0]) / t->prox_at[0];
    out[3] = t->prox * (p[2] - t->prox_at[2]) / t->prox_at[2];
}

static int residual_fn(void *user, const double *p, double *res, double *jac)
{
    const texel *t = user;
    const int np = texel_np(t);
    if (!texel_params_ok(t, p))
        return 1;
    for (int k = 0; k < t->k; ++k) {
        dual e = texel_integral_dual(t, &t->lights[k].lobe_poly, p);
        res[k] = (t->magnitude * e.v - t->target[k]) * t->inv_weight[k];
        if (jac)
            for (int j = 0; j < np; ++j)
                jac[np * k + j] = t->magnitude * e.d[j] * t->inv_weight[k];
    }
    /* the proximal residuals (fit_texel): shears absolute, scales relative; 0 without a warm start */
    double pr[PROX_RESIDUALS];
    prox_residuals(t, p, pr);
    for (int i = 0; i < PROX_RESIDUALS; ++i)
        res[t->k + i] = pr[i];
    if (jac && t->sheen) {
        for (int j = 0; j < 2 * PROX_RESIDUALS; ++j)
            jac[2 * t->k + j] = 0.0;
        if (t->prox > 0.0) {
            jac[2 * t->k + 1] = t->prox / fmax(1.0, fabs(t->prox_at[1]));
            jac[2 * (t->k + 2) + 0] = t->prox / t->prox_at[0];
        }
    } else if (jac) {
        for (int j = 0; j < 4 * PROX_RESIDUALS; ++j)
            jac[4 * t->k + j] = 0.0;
        if (t->prox > 0.0) {
            jac[4 * t->k + 1] = t->prox;
            jac[4 * (t->k + 1) + 3] = t->prox;
            jac[4 * (t->k + 2) + 0] = t->prox / t->prox_at[0];
            jac[4 * (t->k + 3) + 2] = t->prox / t->prox_at[2];
        }
    }

    return 0;
}

/* The cost at p, or INFINITY as soon as its partial sum reaches `bound` (the terms are squares
 * added in a fixed order, so the partial sums never decrease: a cost that stops early is >= bound,
 * and one below bound is the same bits as the full sum).  cost_at: no bound. */
static double cost_below(const texel *t, const double p[4], double bound)
{
    if (!texel_params_ok(t, p))
        return INFINITY;
    double c = 0.0;
    for (int k = 0; k < t->k; ++k) {
        const mf_polygon *lp = &t->lights[k].lobe_poly;
        double r = (t->magnitude * texel_integral_value_v(t, lp->v, lp->n, p) - t->target[k]) * t->inv_weight[k];
        c += r * r;
        if (c >= bound)
            return INFINITY;
    }
    double pr[PROX_RESIDUALS];
    prox_residuals(t, p, pr);
    for (int i = 0; i < PROX_RESIDUALS; ++i)
        c += pr[i] * pr[i];
    return c;
}

static double cost_at(const texel *t, const double p[4])
{
    return cost_below(t, p, INFINITY);
}

/* The closed-form start: the cosine lobe scaled by s about the lobe's mean direction,
 * M' = diag(s, s, 1) in the lobe frame, with s the best of the log grid s = 10^(-4.5 + 0.25 i),
 * i = 0..20 (the first of equal costs).  `bound`: only a cost below it matters (the cost of the
 * warm start, INFINITY without one); a grid point's cost stops being summed once it reaches the
 * bound or the best so far (cost_below), which changes no choice.  Returns the cost at the chosen
 * start, or INFINITY (p then unchanged from the identity) if no grid point costs less than bound. */
static double closed_form_start(const texel *t, double p[4], double bound)
{
    double best = INFINITY;
    if (t->sheen) { /* the sheen family: a on the same log grid, b = 0 and +-2^(j/2), j = -8..6 */
        p[0] = p[2] = 1.0;
        p[1] = p[3] = 0.0;
        for (int i = 0; i <= 20; ++i)
            for (int j = 0; j <= 30; ++j) {
                double s = pow(10.0, -4.5 + 0.25 * i);
                double b = j == 0 ? 0.0 : (j % 2 ? 1.0 : -1.0) * pow(2.0, 0.5 * ((j + 1) / 2 - 9));
                double q[4] = {fmax(s, t->a_min), b, fmax(s, t->a_min), 0.0};
                double c = cost_below(t, q, fmin(best, bound));
                if (c < best) {
                    best = c;
                    memcpy(p, q, sizeof q);
                }
            }
        return best;
    }
    p[0] = p[2] = 1.0;
    p[1] = p[3] = 0.0;
    for (int i = 0; i <= 20; ++i) {
        double s = pow(10.0, -4.5 + 0.25 * i);
        double q[4] = {s, 0.0, s, 0.0};
        double c = cost_below(t, q, fmin(best, bound));
        if (c < best) {
            best = c;
            memcpy(p, q, sizeof q);
        }
    }
    return best;
}

/* View-frame matrix M = R M' of lobe-frame parameters q (R of the lobe direction m). */
static mf_mat3 view_matrix(mf_vec3 m, const double q[4])
{
    const double r[9] = {m.z, 0.0, m.x, 0.0, 1.0, 0.0, -m.x, 0.0, m.z};
    return mf_mat3_mul(mf_ltc_matrix_general(r), mf_ltc_matrix_isotropic(q[0], q[1], q[2], q[3]));
}

/* Lobe-frame parameters of a view-frame matrix: R^T M normalised by its (2, 2) element; 0 if that
 * element is not positive (no such representation). */
static int lobe_params(mf_vec3 m, mf_mat3 mv, double q[4])
{
    const double r_t[9] = {m.z, 0.0, -m.x, 0.0, 1.0, 0.0, m.x, 0.0, m.z};
    mf_mat3 l = mf_mat3_mul(mf_ltc_matrix_general(r_t), mv);
    double n = l.m[2][2];
    if (!(n > 0.0) || !isfinite(n))
        return 0;
    q[0] = l.m[0][0] / n;
    q[1] = l.m[0][2] / n;
    q[2] = l.m[1][1] / n;
    q[3] = l.m[2][0] / n;
    return 1;
}

/* start: NULL or a view-frame matrix (9 doubles, row-major) to warm-start from. */
/* start: NULL or a view-frame matrix (9 doubles, row-major) to warm-start from; lobe_start (used
 * instead when not NULL): the lobe-frame parameters of the previous texel of the column, which
 * keep the lobe's shape about its mean when the mean moves between texels (for a narrow lobe the
 * view-frame matrix of the previous texel points many lobe widths away from this texel's lobe:
 * at GGX alpha 0.001, 1.3 deg it was a poor start and a useless control variate).  lobe_out: the
 * fitted lobe-frame parameters (may be NULL). */
static mf_status fit_texel(const mf_brdf_model *m, double alpha, double cos_theta, const mf_result *albedo,
                           const double *fresnel, const double *start,
                           const double *lobe_start, const mf_ltcfit_options *o, const uint32_t scr[2],
                           workspace *ws, mf_ltcfit_entry *out, double *lobe_out)
{
    texel *t = texel_new();
    if (!t)
        return MF_ERR_ALLOC;
    memset(out, 0, sizeof *out);
    mf_status st = texel_prepare(m, alpha, cos_theta, scr, albedo, fresnel, ws, t);
    if (st != MF_OK) {
        texel_free(t);
        return st;
    }
    out->magnitude = t->magnitude;
    out->magnitude_err = t->magnitude_err;
    out->fresnel = t->fresnel;
    double p[4];
    if (t->sheen && !(t->magnitude > 0.0)) {
        /* the sheen family where the albedo underflows to 0 (charlie at alpha 1e-4 short of ~48
         * deg): the texel shades nothing with any matrix; it keeps the previous texel's shape (the
         * column's first such texels take the next fitted texel's shape: fill_sheen_column), so
         * that interpolation towards the fitted texels stays one lobe */
        double q[4] = {1.0, 0.0, 1.0, 0.0};
        if (lobe_start && lobe_start[0] > 0.0)
            memcpy(q, lobe_start, sizeof q);
        mf_mat3 mv = sheen_matrix(q);
        for (int i = 0; i < 9; ++i)
            out->m[i] = mv.m[i / 3][i % 3];
        out->a = out->c = 1.0 / q[0];
        out->b = -q[1] / q[0];
        out->d = 0.0;
        out->converged = 1;
        out->iterations = lobe_start ? 0 : -1; /* -1: no shape yet (fill_sheen_column) */
        if (lobe_out && lobe_start)
            memcpy(lobe_out, q, sizeof q);
        texel_free(t);
        return MF_OK;
    }
    if (!t->sheen && !(t->magnitude > 1e-12)) {
        /* no energy (e.g. a sheen lobe of tiny roughness): any matrix fits; store the identity */
        out->a = out->c = 1.0;
        out->m[0] = out->m[4] = out->m[8] = 1.0;
        out->converged = 1;
        if (lobe_out) {
            lobe_out[0] = lobe_out[2] = 1.0;
            lobe_out[1] = lobe_out[3] = 0.0;
        }
        texel_free(t);
        return MF_OK;
    }
    /* the control variate from the warm start (previous texel of the column), or at the column's
     * first texel from the closed-form start; then the warm start unless the closed-form start is
     * better on the new targets */
    double q[4];
    int warm = lobe_start ? (memcpy(q, lobe_start, sizeof q), 1)
               : start && (t->sheen ? sheen_params(mf_ltc_matrix_general(start), q)
                                    : lobe_params(t->lobe, mf_ltc_matrix_general(start), q));
    if (t->sheen) {
        /* the sheen family: the start chosen on the targets from the samples alone, then the
         * control variate from it, and the proximal pull only when the warm start was chosen.
         * At low roughness the samples' weights span hundreds of orders of magnitude (effective
         * sample size ~40-200 of 4096 at alpha <= 0.001 short of 79 deg), and a control variate
         * from a poor warm start made that start look good on its own targets: charlie 64 x 64,
         * alpha 2.5e-4, rows 40-57 stayed at a = 6, b = -2000 (cost 25.6 on the sample targets)
         * where the grid's best is a ~0.1, b = -6 (cost 0.12). */
        texel_targets_raw(t, ws);
        double cq = warm ? cost_at(t, q) : NAN;
        double c0 = closed_form_start(t, p, isnan(cq) ? INFINITY : cq);
        int use_warm = warm && cq <= c0;
        if (use_warm)
            memcpy(p, q, sizeof p);
        texel_control_variate(t, ws, p);
        if (use_warm && q[0] > 0.0) {
            t->prox = PROX_WEIGHT;
            memcpy(t->prox_at, q, sizeof q);
        }
    } else {
        if (!warm) {
            texel_targets_raw(t, ws);
            closed_form_start(t, q, INFINITY);
        }
        texel_control_variate(t, ws, q);
        t->prox = 0.0;
        if (warm && q[0] > 0.0 && q[2] > 0.0) { /* (a start from mf_ltcfit_entry_fit may be anything) */
            t->prox = PROX_WEIGHT;
            memcpy(t->prox_at, q, sizeof q);
        }
        /* the warm start unless some grid point costs less (a NaN warm cost never wins) */
        double cq = warm ? cost_at(t, q) : NAN;
        double c0 = closed_form_start(t, p, isnan(cq) ? INFINITY : cq);
        if (warm && cq <= c0)
            memcpy(p, q, sizeof p);
    }
    double lower[4] = {t->a_min, -INFINITY, A_MIN, -INFINITY}, upper[4] = {INFINITY, INFINITY, INFINITY, INFINITY};
    mf_solver_options so;
    mf_solver_options_default(&so);
    so.max_iterations = o->max_iterations;
    so.function_tolerance = 1e-10;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-10;
    mf_solver_summary sum;
    st = mf_solver_least_squares(texel_np(t), t->k + PROX_RESIDUALS, residual_fn, t, p, lower, upper, &so, &sum);
    if (st != MF_OK && st != MF_ERR_NO_CONVERGENCE) {
        texel_free(t);
        return st;
    }
    /* The mirror convention.  A lobe whose mean is (near) the normal is (nearly) symmetric under
     * x -> -x, and so is the objective; where the 4-parameter family cannot follow its symmetric
     * shape, it fits about equally well skewed backward (d' < 0) or forward (d' > 0), and the
     * Monte Carlo noise picks one.  Measured: GGX alpha 1, 89.95 deg, d' = +0.252 (cost 0.08418)
     * and -0.254 (0.08444), while every alpha < 1 of that row takes the backward branch (alpha
     * 0.9685: d' = -0.260, no forward minimum): the sign flip at alpha 1 was a jump of 0.47 in
     * minv_20 between neighbouring texels (the gate's ltc_smooth_jump 1.85x).  So where
     * |m.x| < 0.1 and the fit has d' > 0, the mirror image (a', -b', c', -d') is solved too and
     * kept if its cost is within 1 % (the two costs above differ by 0.3 %). */
    if (!t->sheen && fabs(t->lobe.x) < 0.1 && p[3] > 0.0) {
        double pm[4] = {p[0], -p[1], p[2], -p[3]};
        mf_solver_summary sm;
        mf_status sm_st = mf_solver_least_squares(4, t->k + PROX_RESIDUALS, residual_fn, t, pm, lower, upper, &so, &sm);
        if ((sm_st == MF_OK || sm_st == MF_ERR_NO_CONVERGENCE) && pm[3] <= 0.0 &&
            cost_at(t, pm) <= 1.01 * cost_at(t, p)) {
            memcpy(p, pm, sizeof p);
            sm.iterations += sum.iterations;
            sum = sm;
        }
    }
    if (t->sheen)
        p[2] = p[0], p[3] = 0.0;
    mf_mat3 mv = texel_view_matrix(t, p);
    for (int i = 0; i < 9; ++i)
        out->m[i] = mv.m[i / 3][i % 3];
    /* the view-frame form [[a, 0, b], [0, c, 0], [d, 0, 1]]: M / M22 (NaN if M22 <= 0) */
    double n = mv.m[2][2] > 0.0 ? mv.m[2][2] : NAN;
    out->a = mv.m[0][0] / n;
    out->b = mv.m[0][2] / n;
    out->c = mv.m[1][1] / n;
    out->d = mv.m[2][0] / n;
    out->iterations = sum.iterations;
    out->converged = sum.converged;
    t->prox = 0.0; /* the residual reported is that of the lights alone */
    out->residual = sqrt(cost_at(t, p) / t->k);
    if (lobe_out)
        memcpy(lobe_out, p, sizeof p);
    texel_free(t);
    return MF_OK;
}

static int check_options(const mf_ltcfit_options *o)
{
    return o && o->n_r >= 2 && o->n_u >= 2 && o->n_r <= 4096 && o->n_u <= 4096 && o->threads >= 1 &&
           o->threads <= 256 && o->samples >= 64 && o->samples <= (1 << 20) && !(o->samples & (o->samples - 1)) &&
           o->max_iterations >= 1 && o->stop_after_columns >= 0 && o->r_lo >= 0.0 && o->r_hi <= 1.0 &&
           o->r_lo < o->r_hi && o->u_lo >= 0.0 && o->u_hi <= 1.0 && o->u_lo < o->u_hi;
}

mf_status mf_ltcfit_entry_fit_albedo(const mf_brdf_model *model, double alpha, double cos_theta, const double *start,
                                     const mf_ltcfit_options *o, const mf_result *albedo, mf_ltcfit_entry *out)
{
    if (!model || !model->eval_cos || !check_options(o) || !(alpha > 0.0) || !(cos_theta > 0.0 && cos_theta <= 1.0) ||
        !out)
        return MF_ERR_DOMAIN;
    workspace ws;
    if (!ws_init(&ws, o->samples)) {
        ws_free(&ws);
        return MF_ERR_ALLOC;
    }
    uint32_t scr[2];
    sobol_scramble(o->seed, scr);
    mf_status st = fit_texel(model, alpha, cos_theta, albedo, NULL, start, NULL, o, scr, &ws, out, NULL);
    ws_free(&ws);
    return st;
}

mf_status mf_ltcfit_entry_fit(const mf_brdf_model *model, double alpha, double cos_theta, const double *start,
                              const mf_ltcfit_options *o, mf_ltcfit_entry *out)
{
    return mf_ltcfit_entry_fit_albedo(model, alpha, cos_theta, start, o, NULL, out);
}

mf_status mf_ltcfit_objective(const mf_brdf_model *model, double alpha, double cos_theta, const mf_ltcfit_options *o,
                              const double p[4], double *res, double *jac)
{
    if (!model || !check_options(o) || !(alpha > 0.0) || !(cos_theta > 0.0 && cos_theta <= 1.0) || !res)
        return MF_ERR_DOMAIN;
    workspace ws;
    texel *t = texel_new();
    if (!t || !ws_init(&ws, o->samples)) {
        texel_free(t);
        return MF_ERR_ALLOC;
    }
    uint32_t scr[2];
    sobol_scramble(o->seed, scr);
    mf_status st = texel_prepare(model, alpha, cos_theta, scr, NULL, NULL, &ws, t);
    if (st == MF_OK)
        texel_targets_raw(t, &ws);
    double r[LIGHTS_MAX + PROX_RESIDUALS], jb[4 * (LIGHTS_MAX + PROX_RESIDUALS)];
    if (st == MF_OK && residual_fn(t, p, r, jac ? jb : NULL))
        st = MF_ERR_DOMAIN;
    if (st == MF_OK) {
        memcpy(res, r, sizeof *res * (size_t)t->k);
        if (jac)
            memcpy(jac, jb, sizeof *jac * 4 * (size_t)t->k);
    }
    ws_free(&ws);
    texel_free(t);
    return st;
}

/* ---- the table: columns over threads, checkpoint ------------------------------------------ */

typedef struct {
    const mf_brdf_model *model;
    const mf_ltcfit_options *o;
    const mf_table *table;
    mf_ltcfit_entry *entries;
    unsigned char *done;   /* per column */
    int next_column;
    int claimed;           /* columns started in this run */
    int entries_done;
    int total_entries;
    mf_status status;
    char *msg;
    size_t msg_size;
    uint32_t scr[2];
    pthread_mutex_t lock;
    /* the checkpoint writer (ckpt_writer): the newest snapshot not yet taken, under `lock` */
    pthread_cond_t ckpt_cond;
    mf_buf ckpt_pending;
    int ckpt_has_pending, ckpt_quit;
    int ckpt_sync; /* no writer thread could be started: the worker writes (under the lock) */
} job;

static void entry_to_doubles(const mf_ltcfit_entry *e, double *x)
{
    x[0] = e->a;
    x[1] = e->b;
    x[2] = e->c;
    x[3] = e->d;
    x[4] = e->residual;
    x[5] = e->iterations;
    x[6] = e->converged;
    x[7] = e->magnitude;
    x[8] = e->magnitude_err;
    x[9] = e->fresnel;
    for (int i = 0; i < 9; ++i)
        x[10 + i] = e->m[i];
}
static void entry_from_doubles(const double *x, mf_ltcfit_entry *e)
{
    e->a = x[0];
    e->b = x[1];
    e->c = x[2];
    e->d = x[3];
    e->residual = x[4];
    e->iterations = (int)x[5];
    e->converged = (int)x[6];
    e->magnitude = x[7];
    e->magnitude_err = x[8];
    e->fresnel = x[9];
    for (int i = 0; i < 9; ++i)
        e->m[i] = x[10 + i];
}

typedef struct {
    char magic[8];
    char model[32];
    int32_t n_r, n_u, samples, max_iterations;
    uint64_t seed;
    double range[4]; /* r_lo, r_hi, u_lo, u_hi */
} ckpt_header;

static void ckpt_header_make(const job *j, ckpt_header *h)
{
    memset(h, 0, sizeof *h);
    memcpy(h->magic, CKPT_MAGIC, 8);
    snprintf(h->model, sizeof h->model, "%s", j->model->name);
    h->n_r = j->o->n_r;
    h->n_u = j->o->n_u;
    h->samples = j->o->samples;
    h->max_iterations = j->o->max_iterations;
    h->seed = j->o->seed;
    h->range[0] = j->o->r_lo;
    h->range[1] = j->o->r_hi;
    h->range[2] = j->o->u_lo;
    h->range[3] = j->o->u_hi;
}

/* FNV-1a 64 (Fowler, Noll, Vo) of the checkpoint body: a flipped or lost byte changes it. */
static uint64_t ckpt_checksum(const unsigned char *p, size_t n)
{
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < n; ++i) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* The file: the header, one done byte per column, ENTRY_DOUBLES doubles per entry (native byte
 * order: a checkpoint is resumed on the machine that wrote it), then the 8-byte checksum of all
 * that.  ckpt_snapshot builds it in *b (called with the lock held: a consistent state) after each
 * completed column; a thread of its own (ckpt_writer) writes the newest snapshot atomically (mf_io.h),
 * so that no worker waits for the file to be written and synced (64 fsyncs per default table, each
 * up to tens of milliseconds on a busy disk).  A snapshot replaces one the writer has not taken yet:
 * the file is rewritten after completed columns, always with the newest state, and the writer
 * finishes the last one before mf_ltcfit_table returns. */
static void ckpt_snapshot(job *j, mf_buf *b);

/* Writes b to the checkpoint; on failure the reason in why.  Touches nothing shared. */
static mf_status ckpt_write_buf(const job *j, const mf_buf *b, char *why, size_t why_size)
{
    if (b->failed) {
        snprintf(why, why_size, "out of memory");
        return MF_ERR_ALLOC;
    }
    return mf_io_write_buf_atomic(j->o->checkpoint, b, why, why_size);
}

/* The first failure becomes the fit's status and message.  Called with the lock held. */
static void ckpt_failed(job *j, mf_status st, const char *why)
{
    if (st == MF_OK || j->status != MF_OK)
        return;
    j->status = st;
    if (j->msg)
        snprintf(j->msg, j->msg_size, "cannot write the checkpoint: %s", why);
}

static void *ckpt_writer(void *arg)
{
    job *j = arg;
    pthread_mutex_lock(&j->lock);
    for (;;) {
        while (!j->ckpt_has_pending && !j->ckpt_quit)
            pthread_cond_wait(&j->ckpt_cond, &j->lock);
        if (!j->ckpt_has_pending)
            break; /* quit, nothing left to write */
        mf_buf b = j->ckpt_pending;
        memset(&j->ckpt_pending, 0, sizeof j->ckpt_pending);
        j->ckpt_has_pending = 0;
        pthread_mutex_unlock(&j->lock);
        char why[512];
        mf_status st = ckpt_write_buf(j, &b, why, sizeof why);
        mf_buf_free(&b);
        pthread_mutex_lock(&j->lock);
        ckpt_failed(j, st, why);
    }
    pthread_mutex_unlock(&j->lock);
    return NULL;
}

static void ckpt_snapshot(job *j, mf_buf *b)
{
    ckpt_header h;
    ckpt_header_make(j, &h);
    mf_buf_put(b, &h, sizeof h);
    mf_buf_put(b, j->done, (size_t)j->o->n_r);
    size_t n = (size_t)j->o->n_r * (size_t)j->o->n_u;
    for (size_t i = 0; i < n && !b->failed; ++i) {
        double x[ENTRY_DOUBLES];
        entry_to_doubles(&j->entries[i], x);
        mf_buf_put(b, x, sizeof x);
    }
    if (!b->failed) {
        uint64_t sum = ckpt_checksum((const unsigned char *)b->data, b->len);
        mf_buf_put(b, &sum, sizeof sum);
    }
}

/* Loads a checkpoint: MF_OK (columns marked done), MF_ERR_IO (no file: nothing loaded, not an
 * error for the caller), MF_ERR_FORMAT (an older revision, a file of other settings, truncated or
 * corrupted: refused with one message). */
static mf_status ckpt_read(job *j, int *loaded)
{
    *loaded = 0;
    const char *path = j->o->checkpoint;
    unsigned char *d;
    size_t len;
    int missing;
    char why[512];
    mf_status st = mf_io_read_file(path, path, &d, &len, &missing, why, sizeof why);
    if (st != MF_OK) {
        if (missing)
            return MF_ERR_IO;
        if (j->msg)
            snprintf(j->msg, j->msg_size, "%s", why);
        return MF_ERR_FORMAT;
    }
    ckpt_header want;
    ckpt_header_make(j, &want);
    size_t n = (size_t)j->o->n_r * (size_t)j->o->n_u;
    size_t body = sizeof want + (size_t)j->o->n_r + n * ENTRY_DOUBLES * sizeof(double);
    const char *bad = NULL;
    uint64_t sum;
    if (len < 8 || memcmp(d, CKPT_MAGIC, 7) != 0)
        bad = "not an mfkit LTC checkpoint";
    else if (memcmp(d, CKPT_MAGIC, 8) != 0)
        bad = "a checkpoint of another mfkit revision (delete it and fit again)";
    else if (len >= sizeof want && memcmp(d, &want, sizeof want) != 0)
        bad = "not a checkpoint of this fit (other model, size, seed or settings)";
    else if (len != body + sizeof sum)
        bad = "truncated or extended checkpoint (wrong size)";
    else if (memcpy(&sum, d + body, sizeof sum), sum != ckpt_checksum(d, body))
        bad = "corrupted checkpoint (checksum mismatch)";
    if (bad) {
        if (j->msg)
            snprintf(j->msg, j->msg_size, "%s: %s", path, bad);
        free(d);
        return MF_ERR_FORMAT;
    }
    const unsigned char *done = d + sizeof want, *ent = done + j->o->n_r;
    for (int c = 0; c < j->o->n_r; ++c)
        if (done[c]) {
            j->done[c] = 1;
            ++*loaded;
            for (int u = 0; u < j->o->n_u; ++u) {
                size_t i = (size_t)c + (size_t)j->o->n_r * (size_t)u;
                double x[ENTRY_DOUBLES];
                memcpy(x, ent + i * sizeof x, sizeof x);
                entry_from_doubles(x, &j->entries[i]);
            }
        }
    free(d);
    return MF_OK;
}

static int stop_requested(const job *j)
{
    return j->o->cancel && *j->o->cancel;
}

/* The sheen family's texels of no shape yet (fit_texel: albedo 0 at the start of a column,
 * iterations -1) take the shape of the column's first fitted texel. */
static void fill_sheen_column(mf_ltcfit_entry *col, int n_u)
{
    int u0 = 0;
    while (u0 < n_u && col[u0].iterations == -1)
        ++u0;
    if (u0 == n_u)
        return; /* no texel of the column has energy: they keep the cosine */
    for (int u = 0; u < u0; ++u) {
        col[u].a = col[u0].a;
        col[u].b = col[u0].b;
        col[u].c = col[u0].c;
        col[u].d = col[u0].d;
        memcpy(col[u].m, col[u0].m, sizeof col[u].m);
        col[u].iterations = 0;
    }
}

static void *worker(void *arg)
{
    job *j = arg;
    workspace ws;
    if (!ws_init(&ws, j->o->samples)) {
        ws_free(&ws);
        pthread_mutex_lock(&j->lock);
        if (j->status == MF_OK)
            j->status = MF_ERR_ALLOC;
        pthread_mutex_unlock(&j->lock);
        return NULL;
    }
    const int n_r = j->o->n_r, n_u = j->o->n_u;
    mf_ltcfit_entry *col = malloc(sizeof *col * (size_t)n_u);
    for (;;) {
        int c = -1;
        pthread_mutex_lock(&j->lock);
        while (j->next_column < n_r && j->done[j->next_column])
            ++j->next_column;
        if (j->status == MF_OK && col && j->next_column < n_r && !stop_requested(j) &&
            !(j->o->stop_after_columns > 0 && j->claimed >= j->o->stop_after_columns)) {
            c = j->next_column++;
            ++j->claimed;
        }
        pthread_mutex_unlock(&j->lock);
        if (c < 0)
            break;
        double alpha = mf_ltc_table_alpha(j->table, c);
        mf_status st = MF_OK;
        double lobe_prev[4];
        int have_prev = 0;
        for (int u = 0; u < n_u && st == MF_OK; ++u) {
            if (stop_requested(j))
                break;
            /* the texel's albedo and Fresnel moment when the caller computed them (NaN: not) */
            const double *given = j->o->albedo ? j->o->albedo + 3 * ((size_t)c + (size_t)n_r * (size_t)u) : NULL;
            mf_result alb = {given ? given[0] : NAN, given ? given[1] : NAN};
            int use = given && isfinite(given[0]);
            st = fit_texel(j->model, alpha, mf_ltc_table_cos_theta(j->table, u), use ? &alb : NULL,
                           use ? &given[2] : NULL, NULL, have_prev ? lobe_prev : NULL, j->o, j->scr, &ws, &col[u],
                           lobe_prev);
            if (st == MF_OK) {
                have_prev = col[u].iterations != -1; /* (a sheen texel of no shape yet: no lobe_prev) */
                pthread_mutex_lock(&j->lock);
                ++j->entries_done;
                if (j->o->progress)
                    j->o->progress(j->o->progress_user, j->entries_done, j->total_entries);
                pthread_mutex_unlock(&j->lock);
            }
        }
        if (st == MF_OK && !stop_requested(j))
            fill_sheen_column(col, n_u);
        pthread_mutex_lock(&j->lock);
        if (st != MF_OK) {
            if (j->status == MF_OK) {
                j->status = st;
                if (j->msg)
                    snprintf(j->msg, j->msg_size, "fit of column %d (alpha %.6g) failed: %s", c, alpha,
                             mf_status_str(st));
            }
        } else if (!stop_requested(j)) {
            for (int u = 0; u < n_u; ++u)
                j->entries[c + n_r * u] = col[u];
            j->done[c] = 1;
            if (j->o->checkpoint) { /* the newest state for the writer (ckpt_writer) */
                mf_buf_free(&j->ckpt_pending);
                memset(&j->ckpt_pending, 0, sizeof j->ckpt_pending);
                ckpt_snapshot(j, &j->ckpt_pending);
                if (j->ckpt_sync) {
                    char why[512];
                    ckpt_failed(j, ckpt_write_buf(j, &j->ckpt_pending, why, sizeof why), why);
                } else {
                    j->ckpt_has_pending = 1;
                    pthread_cond_signal(&j->ckpt_cond);
                }
            }
        }
        pthread_mutex_unlock(&j->lock);
    }
    if (!col) {
        pthread_mutex_lock(&j->lock);
        if (j->status == MF_OK)
            j->status = MF_ERR_ALLOC;
        pthread_mutex_unlock(&j->lock);
    }
    free(col);
    ws_free(&ws);
    return NULL;
}

void mf_ltcfit_result_free(mf_ltcfit_result *r)
{
    if (r) {
        free(r->entries);
        memset(r, 0, sizeof *r);
    }
}

static double sphere_scale(double z, double len)
{
    if (len <= 0.0)
        return fmax(z, 0.0);
    return mf_ltc_sphere_integral(len, z) / len;
}

mf_status mf_ltcfit_table(const mf_brdf_model *model, const mf_ltcfit_options *o, mf_table *table,
                          mf_ltcfit_result *result, char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
    if (result)
        memset(result, 0, sizeof *result);
    if (table)
        memset(table, 0, sizeof *table);
    if (!model || !model->eval_cos || !check_options(o) || !table || !result || (o->resume && !o->checkpoint)) {
        if (msg)
            snprintf(msg, msg_size, "invalid fit options");
        return MF_ERR_DOMAIN;
    }
    mf_status st = mf_ltc_table_create_range(table, o->n_r, o->r_lo, o->r_hi, o->n_u, o->u_lo, o->u_hi);
    if (st != MF_OK)
        return st;
    size_t n = (size_t)o->n_r * (size_t)o->n_u;
    job j;
    memset(&j, 0, sizeof j);
    j.model = model;
    j.o = o;
    j.table = table;
    j.entries = calloc(n, sizeof *j.entries);
    j.done = calloc((size_t)o->n_r, 1);
    j.msg = msg;
    j.msg_size = msg_size;
    j.status = MF_OK;
    sobol_scramble(o->seed, j.scr);
    if (!j.entries || !j.done) {
        free(j.entries);
        free(j.done);
        mf_table_free(table);
        return MF_ERR_ALLOC;
    }
    if (o->resume) {
        st = ckpt_read(&j, &result->columns_resumed);
        if (st == MF_ERR_FORMAT) {
            free(j.entries);
            free(j.done);
            mf_table_free(table);
            return st;
        }
    }
    j.total_entries = (int)n;
    j.entries_done = result->columns_resumed * o->n_u;
    pthread_mutex_init(&j.lock, NULL);
    pthread_cond_init(&j.ckpt_cond, NULL);
    pthread_t writer_tid;
    int writer = o->checkpoint && pthread_create(&writer_tid, NULL, ckpt_writer, &j) == 0;
    j.ckpt_sync = o->checkpoint && !writer;
    int nt = o->threads;
    pthread_t th[256];
    int started = 0;
    for (int i = 0; i < nt; ++i) {
        if (pthread_create(&th[i], NULL, worker, &j) != 0)
            break;
        ++started;
    }
    if (started == 0)
        worker(&j);
    for (int i = 0; i < started; ++i)
        pthread_join(th[i], NULL);
    if (writer) { /* the last snapshot written, then the writer ends */
        pthread_mutex_lock(&j.lock);
        j.ckpt_quit = 1;
        pthread_cond_signal(&j.ckpt_cond);
        pthread_mutex_unlock(&j.lock);
        pthread_join(writer_tid, NULL);
    }
    mf_buf_free(&j.ckpt_pending);
    pthread_cond_destroy(&j.ckpt_cond);
    pthread_mutex_destroy(&j.lock);
    int done = 0;
    for (int c = 0; c < o->n_r; ++c)
        done += j.done[c];
    result->n_r = o->n_r;
    result->n_u = o->n_u;
    result->entries = j.entries;
    result->columns_done = done;
    free(j.done);
    if (j.status != MF_OK) {
        mf_table_free(table);
        return j.status;
    }
    if (done < o->n_r) {
        result->interrupted = 1;
        mf_table_free(table);
        return MF_OK;
    }
    result->worst_residual = -1.0;
    for (size_t i = 0; i < n; ++i) {
        const mf_ltcfit_entry *e = &j.entries[i];
        double *rec = table->data + i * (size_t)table->nfields;
        double packed[4];
        /* M^-1 / (M^-1)_11 from the unnormalised view-frame M (mf_ltc_table_pack of a, b, c, d,
         * without the division by M22, which vanishes as the lobe reaches the horizon) */
        mf_mat3 inv;
        if (mf_mat3_inverse(mf_ltc_matrix_general(e->m), &inv) == MF_OK && inv.m[1][1] > 0.0) {
            double s11 = inv.m[1][1];
            packed[0] = inv.m[0][0] / s11;
            packed[1] = inv.m[2][0] / s11;
            packed[2] = inv.m[0][2] / s11;
            packed[3] = inv.m[2][2] / s11;
        } else {
            packed[0] = packed[1] = packed[2] = packed[3] = NAN;
        }
        int ir = (int)(i % (size_t)o->n_r), iu = (int)(i / (size_t)o->n_r);
        rec[MF_LTC_F_MINV_00] = packed[0];
        rec[MF_LTC_F_MINV_20] = packed[1];
        rec[MF_LTC_F_MINV_02] = packed[2];
        rec[MF_LTC_F_MINV_22] = packed[3];
        rec[MF_LTC_F_MAGNITUDE] = e->magnitude;
        rec[MF_LTC_F_FRESNEL] = e->fresnel;
        rec[MF_LTC_F_ZERO] = 0.0;
        rec[MF_LTC_F_SPHERE] = sphere_scale(2.0 * mf_table_axis_param(&table->axes[0], ir) - 1.0,
                                            mf_table_axis_param(&table->axes[1], iu));
        if (e->residual > result->worst_residual) {
            result->worst_residual = e->residual;
            result->worst_index = (int)i;
        }
        if (e->iterations > result->max_iterations)
            result->max_iterations = e->iterations;
        result->total_iterations += e->iterations;
        if (!e->converged)
            ++result->not_converged;
    }
    char buf[64];
    mf_status ms = mf_table_set_meta(table, "tool", "mfkit fit ltc");
    if (ms == MF_OK)
        ms = mf_table_set_meta(table, "brdf", model->name);
    snprintf(buf, sizeof buf, "%llu", (unsigned long long)o->seed);
    if (ms == MF_OK)
        ms = mf_table_set_meta(table, "seed", buf);
    snprintf(buf, sizeof buf, "%d", o->samples);
    if (ms == MF_OK)
        ms = mf_table_set_meta(table, "samples", buf);
    if (ms == MF_OK)
        ms = mf_table_set_meta(table, "sphere", "mf_ltc_sphere_integral(len, z)/len at z = 2r-1, len = u");
    if (ms != MF_OK) {
        mf_table_free(table);
        return ms;
    }
    return MF_OK;
}

mf_status mf_ltcfit_write_sidecar(const char *path, const mf_brdf_model *model, const mf_ltcfit_options *o,
                                  const mf_table *table, const mf_ltcfit_result *r, char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
    if (!path || !model || !o || !r || !r->entries || !table) {
        if (msg)
            snprintf(msg, msg_size, "invalid arguments");
        return MF_ERR_DOMAIN;
    }
    /* every number through the one JSON emitter: a failed fit's NaN is "NaN", not a bare nan */
    mf_buf b = {0};
    mf_buf_puts(&b, "{\n  \"format\": \"mfkit-ltcfit\",\n  \"brdf\": ");
    mf_json_string(&b, model->name);
    mf_buf_printf(&b, ",\n  \"n_r\": %d,\n  \"n_u\": %d,\n  \"r_range\": [", r->n_r, r->n_u);
    mf_json_number(&b, o->r_lo);
    mf_buf_puts(&b, ", ");
    mf_json_number(&b, o->r_hi);
    mf_buf_puts(&b, "],\n  \"u_range\": [");
    mf_json_number(&b, o->u_lo);
    mf_buf_puts(&b, ", ");
    mf_json_number(&b, o->u_hi);
    mf_buf_printf(&b, "],\n  \"seed\": %llu,\n  \"samples\": %d,\n  \"lights\": %d,\n  \"entries\": [\n",
                  (unsigned long long)o->seed, o->samples, mf_ltcfit_light_count());
    size_t n = (size_t)r->n_r * (size_t)r->n_u;
    for (size_t i = 0; i < n && !b.failed; ++i) {
        const mf_ltcfit_entry *e = &r->entries[i];
        int ir = (int)(i % (size_t)r->n_r), iu = (int)(i / (size_t)r->n_r);
        const char *names[] = {"alpha", "cos_theta", "a", "b", "c", "d"};
        const double vals[] = {mf_ltc_table_alpha(table, ir), mf_ltc_table_cos_theta(table, iu), e->a, e->b, e->c, e->d};
        mf_buf_printf(&b, "    {\"ir\": %d, \"iu\": %d", ir, iu);
        for (int k = 0; k < 6; ++k) {
            mf_buf_printf(&b, ", \"%s\": ", names[k]);
            mf_json_number(&b, vals[k]);
        }
        mf_buf_puts(&b, ", \"m\": [");
        for (int k = 0; k < 9; ++k) {
            if (k)
                mf_buf_puts(&b, ", ");
            mf_json_number(&b, e->m[k]);
        }
        mf_buf_puts(&b, "], \"residual\": ");
        mf_json_number(&b, e->residual);
        mf_buf_printf(&b, ", \"iterations\": %d, \"converged\": %s, \"magnitude\": ", e->iterations,
                      e->converged ? "true" : "false");
        mf_json_number(&b, e->magnitude);
        mf_buf_puts(&b, ", \"magnitude_err\": ");
        mf_json_number(&b, e->magnitude_err);
        mf_buf_puts(&b, ", \"fresnel\": ");
        mf_json_number(&b, e->fresnel);
        mf_buf_printf(&b, "}%s\n", i + 1 < n ? "," : "");
    }
    mf_buf_puts(&b, "  ]\n}\n");
    mf_status st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
    mf_buf_free(&b);
    return st;
}
