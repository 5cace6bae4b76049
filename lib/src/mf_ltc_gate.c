/* mf_ltc_gate.c -- the LTC table gate (see mf_ltc_gate.h; bounds and reasons in docs/validation.md). */
#include "mfkit/mf_ltc_gate.h"

#include "mfkit/mf_rng.h"
#include "mfkit/mf_sample.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- bounds (docs/validation.md, "The LTC gate") ------------------------------------------- */
#define GATE_ENERGY_SLACK 1e-5      /* magnitude <= 1 + this; fresnel <= magnitude + this */
#define GATE_NORM_BOUND 1e-6        /* |sum over the octants - 1| */
#define GATE_JUMP_PER_H 16.0        /* |neighbour difference| <= 16 h */
#define GATE_SPIKE_PER_H2 80.0      /* excess outside the neighbours' range <= 80 h^2 */
#define GATE_ALBEDO_REL 1e-3        /* |magnitude - albedo| / max(albedo, 0.01) */
#define GATE_ALBEDO_FLOOR 0.01
#define GATE_ALBEDO_ERR_FACTOR 4.0  /* the quadrature's error estimate counts 4 times */
#define GATE_Z 5.5                  /* two-sided 3.8e-8 per test: < 1e-3 family-wise up to 26000 tests */
#define GATE_QUAD_N 64              /* albedo quadrature: 64 x 64 (error from 32 x 32) */
#define GATE_REL_FLOOR 0.01         /* relative polygon errors against max(MC, 0.01 albedo) */
/* The storage floor of a magnitude: the smallest float32 denormal, 2^-149.  A table exported as
 * float32 stores a magnitude below it as 0 (charlie's albedo at alpha 1e-4 reaches 1e-257), so a
 * file's magnitude, and the shading it scales (an LTC integral is at most 1), may be off by this
 * much in absolute terms; the Monte Carlo checks allow it.  It changes no comparison of a value
 * above about 1e-29 in double precision. */
#define GATE_MAG_STORAGE 0x1p-149
/* The smoothness checks' shape weight: min(1, m / GATE_SHAPE_MAG), m the largest magnitude of the
 * texels compared (smooth_weight): the absolute magnitude error ltc_albedo_quad accepts below its
 * floor (GATE_ALBEDO_REL x GATE_ALBEDO_FLOOR = 1e-5) */
#define GATE_SHAPE_MAG (GATE_ALBEDO_REL * GATE_ALBEDO_FLOOR)

/* Stream tags: each purpose and texel has its own PCG32 stream. */
enum { STREAM_NORM = 1, STREAM_POLY = 2, STREAM_MC = 3 };

static uint64_t stream_id(int purpose, size_t texel) { return ((uint64_t)texel << 4) | (uint64_t)purpose; }

void mf_ltc_gate_options_default(mf_ltc_gate_options *o)
{
    memset(o, 0, sizeof *o);
    o->seed = 1;
    o->threads = 1;
    o->quick = 0;
    o->mc_samples = 0;
    o->polygons_per_entry = 0;
    o->polygon_budget_mean = MF_LTC_GATE_POLYGON_MEAN;
    o->polygon_budget_entry = MF_LTC_GATE_POLYGON_ENTRY;
    o->stats = NULL;
    o->albedo = NULL;
}

mf_vec3 mf_ltc_gate_view(double cos_theta)
{
    double s = 1.0 - cos_theta * cos_theta;
    return mf_vec3_make(sqrt(s > 0.0 ? s : 0.0), 0.0, cos_theta);
}

/* ---- the model as an integrand -------------------------------------------------------------- */

/* One sample of the model's sampler (cosine hemisphere without one): wi and the weight
 * f cos / pdf (0 for a discarded sample). */
static double model_weight_p(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                             mf_vec3 *wi)
{
    double pdf;
    *wi = mf_model_sample(m, p, wo, u, &pdf);
    if (!(pdf > 0.0) || !mf_vec3_isfinite(*wi) || wi->z <= 0.0)
        return 0.0;
    return m->eval_cos(m, p, wo, *wi) / pdf;
}

/* The model's albedo by the fitter's rule (mf_model_albedo, GATE_QUAD_N points per axis). */
static mf_status gate_albedo(const mf_brdf_model *model, double alpha, mf_vec3 wo, mf_result *out)
{
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    return mf_model_albedo(model, &p, wo, GATE_QUAD_N, out);
}

/* ---- random polygons --------------------------------------------------------------------------- */

static double det3(mf_vec3 a, mf_vec3 b, mf_vec3 c) { return mf_vec3_dot(a, mf_vec3_cross(b, c)); }

static void make_front_facing(mf_polygon *p)
{
    if (det3(p->v[0], p->v[1], p->v[2]) < 0.0) {
        for (int i = 0; i < p->n / 2; ++i) {
            mf_vec3 tmp = p->v[i];
            p->v[i] = p->v[p->n - 1 - i];
            p->v[p->n - 1 - i] = tmp;
        }
    }
}

void mf_ltc_gate_random_polygons(const mf_brdf_model *model, double alpha, mf_vec3 wo, uint64_t seed,
                                 uint64_t stream, int n, mf_polygon *out)
{
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    mf_ltc_gate_random_polygons_params(model, &p, wo, seed, stream, n, out);
}

void mf_ltc_gate_random_polygons_params(const mf_brdf_model *model, const mf_brdf_params *prm, mf_vec3 wo,
                                        uint64_t seed, uint64_t stream, int n, mf_polygon *out)
{
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, stream);
    for (int i = 0; i < n; ++i) {
        /* Draw every number whatever the branch, so polygon i does not depend on the model. */
        double r[12];
        for (int k = 0; k < 12; ++k)
            r[k] = mf_pcg32_next_double(&rng);
        mf_vec3 c = mf_vec3_make(NAN, NAN, NAN);
        int kind = (i / 2) % 3; /* 0: towards the lobe, 1: across the horizon, 2: anywhere above */
        if (kind == 0 && model) {
            double u[2] = {r[0], r[1]};
            mf_vec3 wi;
            if (model_weight_p(model, prm, wo, u, &wi) > 0.0)
                c = wi;
        }
        if (!mf_vec3_isfinite(c) || kind == 2) {
            c = mf_sample_cosine_hemisphere((double[2]){r[0], r[1]});
        }
        if (kind == 1) {
            double z = -0.3 + 0.6 * r[0], phi = 2.0 * MF_PI * r[1], s = sqrt(1.0 - z * z);
            c = mf_vec3_make(s * cos(phi), s * sin(phi), z);
        }
        c = mf_vec3_normalize(c);
        /* Plane normal: c tilted by up to 1 rad in a random direction. */
        mf_frame fc = mf_frame_from_normal(c);
        double tilt = 1.0 * r[2], tphi = 2.0 * MF_PI * r[3];
        mf_vec3 nrm = mf_vec3_add(mf_vec3_scale(c, cos(tilt)),
                                  mf_vec3_scale(mf_vec3_add(mf_vec3_scale(fc.s, cos(tphi)), mf_vec3_scale(fc.t, sin(tphi))),
                                                sin(tilt)));
        mf_frame fp = mf_frame_from_normal(mf_vec3_normalize(nrm));
        double rot = 2.0 * MF_PI * r[4];
        mf_vec3 e1 = mf_vec3_add(mf_vec3_scale(fp.s, cos(rot)), mf_vec3_scale(fp.t, sin(rot)));
        mf_vec3 e2 = mf_vec3_cross(fp.n, e1);
        /* Half-extents log-uniform in [0.03, 1.2] at distance 1, aspect up to 2:1. */
        double s1 = 0.03 * exp(log(40.0) * r[5]);
        double s2 = s1 * exp(0.7 * (2.0 * r[6] - 1.0));
        mf_polygon p;
        memset(&p, 0, sizeof p);
        if (i % 2 == 0) {
            p.n = 4;
            const double sx[4] = {1, -1, -1, 1}, sy[4] = {1, 1, -1, -1};
            for (int k = 0; k < 4; ++k)
                p.v[k] = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(e1, s1 * sx[k]), mf_vec3_scale(e2, s2 * sy[k])));
        } else {
            p.n = 3;
            double phase = 2.0 * MF_PI * r[7];
            for (int k = 0; k < 3; ++k) {
                double a = phase + 2.0 * MF_PI * k / 3.0 + 0.5 * (2.0 * r[8 + k] - 1.0);
                p.v[k] = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(e1, 1.3 * s1 * cos(a)), mf_vec3_scale(e2, 1.3 * s2 * sin(a))));
            }
        }
        make_front_facing(&p);
        out[i] = p;
    }
}

/* ---- Monte Carlo over polygons -------------------------------------------------------------- */

mf_status mf_ltc_gate_polygon_mc(const mf_brdf_model *model, double alpha, mf_vec3 wo, const mf_polygon *p,
                                 int n, int nsamples, uint64_t seed, uint64_t stream, double *val, double *se,
                                 mf_result *albedo)
{
    mf_brdf_params prm = mf_brdf_params_iso(alpha);
    return mf_ltc_gate_polygon_mc_params(model, &prm, wo, p, n, nsamples, seed, stream, val, se, albedo);
}

mf_status mf_ltc_gate_polygon_mc_params(const mf_brdf_model *model, const mf_brdf_params *prm, mf_vec3 wo,
                                        const mf_polygon *p, int n, int nsamples, uint64_t seed, uint64_t stream,
                                        double *val, double *se, mf_result *albedo)
{
    if (!model || n < 0 || nsamples < 2 || (n > 0 && (!p || !val || !se)))
        return MF_ERR_DOMAIN;
    mf_vec3 *edge = malloc(sizeof *edge * (size_t)(n > 0 ? n : 1) * MF_POLYGON_MAX_VERTICES);
    double *s1 = calloc((size_t)(n > 0 ? n : 1) * 2, sizeof *s1);
    if (!edge || !s1) {
        free(edge);
        free(s1);
        return MF_ERR_ALLOC;
    }
    double *s2 = s1 + (n > 0 ? n : 1);
    /* Edge planes of the convex front-facing polygons: w is inside iff w.(v_k x v_k+1) >= 0 for all k. */
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < p[i].n; ++k)
            edge[i * MF_POLYGON_MAX_VERTICES + k] = mf_vec3_cross(p[i].v[k], p[i].v[(k + 1) % p[i].n]);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, seed, stream);
    double a1 = 0.0, a2 = 0.0;
    /* The sums of squares are of w s, s = 4^-j with j = floor(log2(max |w| so far) / 2) (the
     * largest w s in [1, 4); when the maximum grows, the sums so far are rescaled): a sheen
     * texel's weights are ~1e-257 (charlie, alpha 1e-4, 51 deg), whose squares underflow to 0 and
     * gave se = 0 (ltc_albedo_mc 23.4 on Monte Carlo noise alone); a scale fixed by the first
     * weight fails the other way when later weights are 1e200 times larger (charlie, alpha 0.004,
     * 76 deg).  s and the rescalings are even powers of two, so wherever nothing underflows or
     * overflows, every sum, the variance and the square root scale exactly: the same bits as
     * without the scale. */
    double s = 1.0;
    int jcur = 0, have_j = 0;
    mf_status st = MF_OK;
    /* The samples in batches (mf_model_sample_weights: the bits of sample + eval_cos one at a time,
     * with the view-dependent parts computed once per batch), drawn in the same order. */
    enum { MC_BATCH = 64 };
    double u[2 * MC_BATCH], pdf[MC_BATCH], wt[MC_BATCH];
    mf_vec3 dir[MC_BATCH];
    for (int s0 = 0; s0 < nsamples && st == MF_OK; s0 += MC_BATCH) {
        int k = nsamples - s0 < MC_BATCH ? nsamples - s0 : MC_BATCH;
        for (int q = 0; q < 2 * k; ++q)
            u[q] = mf_pcg32_next_double(&rng);
        mf_model_sample_weights(model, prm, wo, k, u, dir, pdf, wt);
        for (int q = 0; q < k; ++q) {
            double w = wt[q];
            if (!isfinite(w)) {
                st = MF_ERR_DOMAIN;
                break;
            }
            if (w == 0.0)
                continue;
            if (!have_j || fabs(w) * s >= 4.0) { /* a new maximum beyond the scale's [1, 4) (exact test) */
                int lg = ilogb(w), jw = lg >= 0 ? lg / 2 : -((1 - lg) / 2); /* floor(lg / 2) */
                if (have_j) {
                    double f = ldexp(1.0, -4 * (jw - jcur)); /* (s_new / s_old)^2 */
                    a2 *= f;
                    for (int i = 0; i < n; ++i)
                        s2[i] *= f;
                }
                jcur = jw;
                have_j = 1;
                s = ldexp(1.0, -2 * jcur);
            }
            const mf_vec3 wi = dir[q];
            const double ws = w * s;
            a1 += w;
            a2 += ws * ws;
            for (int i = 0; i < n; ++i) {
                const mf_vec3 *e = edge + i * MF_POLYGON_MAX_VERTICES;
                int inside = 1;
                for (int j = 0; j < p[i].n && inside; ++j)
                    inside = mf_vec3_dot(wi, e[j]) >= 0.0;
                if (inside) {
                    s1[i] += w;
                    s2[i] += ws * ws;
                }
            }
        }
    }
    if (st == MF_OK) {
        double nn = (double)nsamples, is = 1.0 / s;
        for (int i = 0; i < n; ++i) {
            double m = s1[i] / nn, ms = m * s, var = s2[i] / nn - ms * ms; /* var of w s */
            val[i] = m;
            se[i] = sqrt((var > 0.0 ? var : 0.0) / (nn - 1.0)) * is;
        }
        if (albedo) {
            double m = a1 / nn, ms = m * s, var = a2 / nn - ms * ms;
            albedo->val = m;
            albedo->err = sqrt((var > 0.0 ? var : 0.0) / (nn - 1.0)) * is;
        }
    }
    free(edge);
    free(s1);
    return st;
}

/* ---- the gate: layout, context, helpers --------------------------------------------------------- */

typedef struct gate_layout {
    int f[MF_LTC_NFIELDS]; /* field index of each LTC field, -1 if absent */
    int nr, nu;
} gate_layout;

static int layout_of(const mf_table *t, gate_layout *L)
{
    if (!t || !t->data || t->naxes != 2 || t->axes[0].mapping != MF_AXIS_SQUARE ||
        t->axes[1].mapping != MF_AXIS_ONE_MINUS_SQUARE || t->axes[0].size < 2 || t->axes[1].size < 2)
        return 0;
    for (int k = 0; k < MF_LTC_NFIELDS; ++k)
        L->f[k] = mf_table_field(t, mf_ltc_table_fields[k]);
    for (int k = 0; k <= MF_LTC_F_MAGNITUDE; ++k)
        if (L->f[k] < 0)
            return 0;
    L->nr = t->axes[0].size;
    L->nu = t->axes[1].size;
    return 1;
}

int mf_ltc_gate_layout_ok(const mf_table *t, char *why, size_t why_size)
{
    gate_layout L;
    if (layout_of(t, &L))
        return 1;
    if (why && why_size) {
        if (!t || !t->data)
            snprintf(why, why_size, "no table data");
        else if (t->naxes != 2)
            snprintf(why, why_size, "%d axes, an isotropic LTC table has 2 (r, u)", t->naxes);
        else if (t->axes[0].mapping != MF_AXIS_SQUARE || t->axes[1].mapping != MF_AXIS_ONE_MINUS_SQUARE)
            snprintf(why, why_size, "axis mappings %s, %s; an isotropic LTC table has square, one_minus_square",
                     mf_axis_mapping_name(t->axes[0].mapping), mf_axis_mapping_name(t->axes[1].mapping));
        else if (t->axes[0].size < 2 || t->axes[1].size < 2)
            snprintf(why, why_size, "an axis of fewer than 2 texels");
        else {
            int k = 0;
            while (k < MF_LTC_F_MAGNITUDE && mf_table_field(t, mf_ltc_table_fields[k]) >= 0)
                ++k;
            snprintf(why, why_size, "no field '%s'", mf_ltc_table_fields[k]);
        }
    }
    return 0;
}

/* Everything the checks share: the table, the options, and the caches of the expensive model
 * integrals (computed on first use, so the checks can run in any subset and order with the same
 * results: every integral is a deterministic function of its texel and the seed). */
typedef struct gate_entry {
    int ir, iu, ok;
    double alpha, ct, mag;
    mf_result alb;   /* Monte Carlo albedo */
    double excess;   /* sum over the polygons of max(0, |LTC - MC| - z se) / albedo */
} gate_entry;

typedef struct gate_ctx {
    const mf_table *t;
    const mf_brdf_model *model;
    mf_ltc_gate_options o;
    gate_layout L;
    int nr, nu;
    double hr, hu;
    double budget_mean, budget_entry;
    int nsamples, npoly;
    mf_status status;    /* MF_ERR_ALLOC if a check ran out of memory */
    double *qalb;        /* 2 per texel: quadrature albedo and its error estimate; NaN: not computed */
    double worst_alb;    /* worst |magnitude - quadrature| / max(albedo, 0.01) */
    /* the polygon pass (run once, by the first check that needs it) */
    int poly_done;
    gate_entry *ent;
    long nent;
    double *eabs, *erel;
    long np;
    double sum_excess, sum_abs, sum_rel, sum_se, worst_abs, worst_rel;
} gate_ctx;

static const double *rec(const mf_table *t, int ir, int iu)
{
    return t->data + ((size_t)ir + (size_t)t->axes[0].size * (size_t)iu) * (size_t)t->nfields;
}

static int unpack_at(const mf_table *t, const gate_layout *L, int ir, int iu, mf_ltc *ltc)
{
    const double *r = rec(t, ir, iu);
    double m4[4] = {r[L->f[0]], r[L->f[1]], r[L->f[2]], r[L->f[3]]};
    for (int k = 0; k < 4; ++k)
        if (!isfinite(m4[k]))
            return 0;
    return mf_ltc_table_unpack(m4, ltc) == MF_OK;
}

/* Records value v of texel (ir, iu), described by `what` and the texel's indices and parameters. */
static void record_texel(mf_check *c, double v, const char *what, int ir, int iu, double alpha, double cos_theta)
{
    mf_check_recordf(c, v, "%s (ir %d, iu %d: alpha %.4g, theta %.2f deg)", what, ir, iu, alpha,
                     acos(cos_theta) * 180.0 / MF_PI);
}

static void out_of_memory(gate_ctx *g, mf_check *c)
{
    g->status = MF_ERR_ALLOC;
    mf_check_fail(c, "out of memory");
}

mf_status mf_ltc_gate_texel_albedo(const mf_table *t, const mf_brdf_model *model, int ir, int iu, mf_result *out)
{
    gate_layout L;
    if (!out || !model || !layout_of(t, &L) || ir < 0 || iu < 0 || ir >= L.nr || iu >= L.nu)
        return MF_ERR_DOMAIN;
    return gate_albedo(model, mf_ltc_table_alpha(t, ir), mf_ltc_gate_view(mf_ltc_table_cos_theta(t, iu)), out);
}

mf_status mf_ltc_gate_texel_albedo_fresnel(const mf_table *t, const mf_brdf_model *model, int ir, int iu,
                                           mf_result *albedo, mf_result *fresnel)
{
    gate_layout L;
    if (!albedo || !fresnel || !model || !layout_of(t, &L) || ir < 0 || iu < 0 || ir >= L.nr || iu >= L.nu)
        return MF_ERR_DOMAIN;
    mf_brdf_params p = mf_brdf_params_iso(mf_ltc_table_alpha(t, ir));
    return mf_model_albedo_fresnel(model, &p, mf_ltc_gate_view(mf_ltc_table_cos_theta(t, iu)), GATE_QUAD_N, albedo,
                                   fresnel);
}

/* The model's albedo at texel (ir, iu) by the 64 x 64 quadrature, cached; 0 if it failed. */
static int quad_albedo(gate_ctx *g, int ir, int iu, mf_result *q)
{
    size_t texel = (size_t)ir + (size_t)g->nr * (size_t)iu;
    if (!g->qalb) {
        size_t n = (size_t)g->nr * (size_t)g->nu * 2;
        g->qalb = malloc(sizeof *g->qalb * n);
        if (!g->qalb)
            return 0;
        for (size_t i = 0; i < n; ++i)
            g->qalb[i] = g->o.albedo ? g->o.albedo[i] : NAN;
    }
    if (isnan(g->qalb[2 * texel])) {
        const mf_table *t = g->t;
        const mf_brdf_model *model = g->model;
        mf_result r;
        if (gate_albedo(model, mf_ltc_table_alpha(t, ir), mf_ltc_gate_view(mf_ltc_table_cos_theta(t, iu)), &r) !=
            MF_OK)
            return 0;
        g->qalb[2 * texel] = r.val;
        g->qalb[2 * texel + 1] = r.err;
    }
    q->val = g->qalb[2 * texel];
    q->err = g->qalb[2 * texel + 1];
    return 1;
}

/* A uniformly random rotation (unit quaternion from 4 normals). */
static mf_mat3 random_rotation(mf_pcg32 *rng)
{
    double q[4], n2 = 0.0;
    for (int k = 0; k < 4; ++k) {
        q[k] = mf_pcg32_next_normal(rng);
        n2 += q[k] * q[k];
    }
    double s = 1.0 / sqrt(n2), w = q[0] * s, x = q[1] * s, y = q[2] * s, z = q[3] * s;
    mf_mat3 r = {{{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                  {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                  {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}}};
    return r;
}

/* Integral of the LTC over the sphere as the sum of its exact integrals over the 8 octant
 * triangles of the rotated frame r (each made front-facing). */
static double octant_sum(const mf_ltc *ltc, mf_mat3 r)
{
    mf_vec3 ax[3];
    for (int k = 0; k < 3; ++k)
        ax[k] = mf_vec3_make(r.m[0][k], r.m[1][k], r.m[2][k]);
    double sum = 0.0;
    for (int o = 0; o < 8; ++o) {
        mf_polygon p;
        memset(&p, 0, sizeof p);
        p.n = 3;
        for (int k = 0; k < 3; ++k)
            p.v[k] = mf_vec3_scale(ax[k], (o >> k) & 1 ? -1.0 : 1.0);
        make_front_facing(&p);
        sum += mf_ltc_integrate_polygon(ltc, &p, MF_POLYGON_ONE_SIDED);
    }
    return sum;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double percentile95(double *v, long n)
{
    if (n <= 0)
        return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    long k = (long)ceil(0.95 * (double)n) - 1;
    return v[k < 0 ? 0 : k];
}

/* The sampled texel indices along an axis of n texels: k texels evenly spread, both ends included. */
static int sample_axis(int n, int k, int *idx)
{
    if (k >= n) {
        for (int i = 0; i < n; ++i)
            idx[i] = i;
        return n;
    }
    int m = 0;
    for (int j = 0; j < k; ++j) {
        int i = (int)floor((double)j * (n - 1) / (k - 1) + 0.5);
        if (m == 0 || idx[m - 1] != i)
            idx[m++] = i;
    }
    return m;
}

/* ---- the checks (one function each; the table mf_ltc_gate_check_table below lists them) ------------------ */

static void check_finite(void *ctx, mf_check *c)
{
    const gate_ctx *g = ctx;
    const mf_table *t = g->t;
    size_t bad = 0, first = (size_t)-1;
    size_t nv = mf_table_texels(t) * (size_t)t->nfields;
    for (size_t i = 0; i < nv; ++i)
        if (!isfinite(t->data[i])) {
            if (first == (size_t)-1)
                first = i;
            ++bad;
        }
    /* a count, not a value per case: worst = the number of non-finite values, where = the first */
    c->cases = (long)nv;
    c->worst = (double)bad;
    if (bad) {
        size_t tex = first / (size_t)t->nfields;
        snprintf(c->worst_at, sizeof c->worst_at, "first: field %s of texel (ir %d, iu %d)",
                 t->fields[first % (size_t)t->nfields], (int)(tex % (size_t)g->nr), (int)(tex / (size_t)g->nr));
    }
}

/* Energy.  Every texel: magnitude >= 0, 0 <= fresnel <= magnitude, and magnitude <= 1 unless the
 * model is known not to claim it (no MF_MODEL_ENERGY_CONSERVING: Burley's diffuse reaches 1.19).
 * With a model, also magnitude <= its own albedo Q + 4 err (Q the 64 x 64 quadrature of
 * ltc_albedo_quad, on the same texels: all of them, or the quick 8 x 8 grid), plus the rounding
 * of a half-float magnitude (RGBA16F files are validated too); without a model
 * magnitude <= 1 is the only upper bound there is. */
static void check_energy(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    const mf_table *t = g->t;
    const gate_layout *L = &g->L;
    int conserving = !g->model || (g->model->flags & MF_MODEL_ENERGY_CONSERVING);
    if (g->model && conserving)
        snprintf(c->what, sizeof c->what,
                 "max(magnitude - min(1, albedo + 4 err), fresnel - magnitude, -fresnel, -magnitude); albedo by 64x64 "
                 "quadrature");
    else if (g->model)
        snprintf(c->what, sizeof c->what,
                 "max(magnitude - (albedo + 4 err), fresnel - magnitude, -fresnel, -magnitude); %s does not declare "
                 "energy conservation: magnitude <= 1 not tested",
                 g->model->name);
    for (int iu = 0; iu < g->nu; ++iu)
        for (int ir = 0; ir < g->nr; ++ir) {
            const double *r = rec(t, ir, iu);
            double mag = r[L->f[MF_LTC_F_MAGNITUDE]];
            double v = -mag;
            const char *w = "magnitude < 0";
            if (conserving && mag - 1.0 > v)
                v = mag - 1.0, w = "magnitude > 1";
            if (L->f[MF_LTC_F_FRESNEL] >= 0) {
                double fr = r[L->f[MF_LTC_F_FRESNEL]];
                if (fr - mag > v)
                    v = fr - mag, w = "fresnel > magnitude";
                if (-fr > v)
                    v = -fr, w = "fresnel < 0";
            }
            record_texel(c, v, w, ir, iu, mf_ltc_table_alpha(t, ir), mf_ltc_table_cos_theta(t, iu));
        }
    if (!g->model)
        return;
    int ir_idx[1024], iu_idx[1024];
    int mr = sample_axis(g->nr, g->o.quick ? 8 : 1024, ir_idx), mu = sample_axis(g->nu, g->o.quick ? 8 : 1024, iu_idx);
    for (int b = 0; b < mu; ++b)
        for (int a = 0; a < mr; ++a) {
            int ir = ir_idx[a], iu = iu_idx[b];
            mf_result q;
            double v = INFINITY;
            if (quad_albedo(g, ir, iu, &q)) {
                /* allowance: the rounding of a magnitude stored as a half float (2^-11 relative,
                 * the coarsest format mfkit writes); ltc_albedo_quad is the tighter two-sided check */
                double mag = rec(t, ir, iu)[L->f[MF_LTC_F_MAGNITUDE]];
                v = mag - (q.val + GATE_ALBEDO_ERR_FACTOR * q.err) - ldexp(fabs(mag), -11);
            }
            else if (!g->qalb) {
                out_of_memory(g, c);
                return;
            }
            record_texel(c, v, v == INFINITY ? "quadrature failed (model NaN)" : "magnitude > the model's albedo",
                         ir, iu, mf_ltc_table_alpha(t, ir), mf_ltc_table_cos_theta(t, iu));
        }
}

static void check_normalisation(void *ctx, mf_check *c)
{
    const gate_ctx *g = ctx;
    const mf_table *t = g->t;
    for (int iu = 0; iu < g->nu; ++iu)
        for (int ir = 0; ir < g->nr; ++ir) {
            mf_ltc ltc;
            double v = INFINITY;
            const char *w = "singular or non-finite matrix";
            if (unpack_at(t, &g->L, ir, iu, &ltc)) {
                mf_pcg32 rng;
                mf_pcg32_seed(&rng, g->o.seed, stream_id(STREAM_NORM, (size_t)ir + (size_t)g->nr * (size_t)iu));
                v = fabs(octant_sum(&ltc, random_rotation(&rng)) - 1.0);
                w = "octant sum";
            }
            record_texel(c, v, w, ir, iu, mf_ltc_table_alpha(t, ir), mf_ltc_table_cos_theta(t, iu));
        }
}

/* What the smoothness checks read (docs/validation.md, "Smoothness of the shape").  The four matrix
 * fields and the implied minv_11 = 1 (field index t->nfields) define the LTC up to a positive
 * scale, so they are read scaled by their largest magnitude, max(1, |minv_00|, |minv_20|,
 * |minv_02|, |minv_22|): the stored values wherever the implied 1 is the largest (every texel of
 * every registered model but charlie), and a bounded shape where a lobe held against the horizon
 * needs a large entry (charlie's ring: minv ~ diag(1, 1, 1 / (2 alpha))).  Other fields as stored. */
static int is_shape_field(const gate_ctx *g, int f)
{
    if (f == g->t->nfields)
        return 1;
    for (int k = 0; k < 4; ++k)
        if (f == g->L.f[k])
            return 1;
    return 0;
}

static const char *smooth_field_name(const gate_ctx *g, int f)
{
    return f == g->t->nfields ? "minv_11 (implied 1)" : g->t->fields[f];
}

static double smooth_value(const gate_ctx *g, int f, int ir, int iu)
{
    const double *r = rec(g->t, ir, iu);
    if (!is_shape_field(g, f))
        return r[f];
    double n = 1.0;
    for (int k = 0; k < 4; ++k) {
        double v = fabs(r[g->L.f[k]]);
        if (!isfinite(v))
            return NAN;
        n = v > n ? v : n;
    }
    return (f == g->t->nfields ? 1.0 : r[f]) / n;
}

/* The weight of a shape difference among texels whose magnitudes range from lo to hi (1 for every
 * other field, and where a magnitude is not finite):
 *   min(1, hi / GATE_SHAPE_MAG) / max(1, log2(hi / lo)).
 * The first factor: the light a lobe reflects is at most its magnitude, so below GATE_SHAPE_MAG
 * even a wrong shape shades less than the magnitude error ltc_albedo_quad accepts there.  The
 * second: the magnitude is the one field whose truth the gate knows (ltc_albedo_quad holds it to
 * the model's albedo within 1e-3), and where it changes by a factor 2^s > 2 between the texels
 * compared, the model itself changes by s doublings within one step: the grid resolves it s times
 * more coarsely than a field that doubles per step, and so the shape may change s times as much
 * (charlie at alpha 1e-4: albedo 0.25 at 88.2 deg, 17.2 at 89.95 deg, and its lobe's azimuthal
 * width doubles).  No texel of the other registered models has neighbours' magnitudes a factor
 * 2 apart, so both factors are 1 for them. */
static double smooth_weight(const gate_ctx *g, int f, double hi, double lo)
{
    if (!is_shape_field(g, f) || !isfinite(hi) || !isfinite(lo))
        return 1.0;
    double w = hi < GATE_SHAPE_MAG ? (hi > 0.0 ? hi / GATE_SHAPE_MAG : 0.0) : 1.0;
    if (!(lo > 0.0))
        return hi > 0.0 ? 0.0 : w; /* a magnitude 0 beside a positive one: unresolved (log2 infinite) */
    double s = log2(hi / lo);
    return s > 1.0 ? w / s : w;
}

static void magnitude_range(const gate_ctx *g, const int *ir, const int *iu, int n, double *hi, double *lo)
{
    *hi = 0.0;
    *lo = INFINITY;
    for (int k = 0; k < n; ++k) {
        double v = fabs(rec(g->t, ir[k], iu[k])[g->L.f[MF_LTC_F_MAGNITUDE]]);
        if (!isfinite(v)) {
            *hi = *lo = NAN;
            return;
        }
        *hi = v > *hi ? v : *hi;
        *lo = v < *lo ? v : *lo;
    }
}

static int quad_fresnel(gate_ctx *g, int ir, int iu, mf_result *q);

/* Neighbour pairs and triples: every field but "zero" (the shape read by smooth_value, weighted by
 * smooth_weight), then the implied minv_11, along r then u, in texel order.  With a model, a jump
 * of the magnitude or fresnel field above the bound is measured on its error against the model
 * (as in ltc_smooth_spike): the true albedo itself jumps where it varies faster than a row (charlie
 * at alpha 1e-4: 8.3e-4 at 86.4 deg, 17.2 at 89.95 deg). */
static void check_smooth_jump(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    const mf_table *t = g->t;
    const int mag_field = g->L.f[MF_LTC_F_MAGNITUDE], fres_field = g->L.f[MF_LTC_F_FRESNEL];
    if (g->model)
        snprintf(c->what, sizeof c->what, "%s",
                 "max |neighbour difference| / (16 h), every field (matrix: scaled, weighted; magnitude, fresnel: "
                 "minus the model's albedo, moment)");
    for (int f = 0; f <= t->nfields; ++f) {
        if (f < t->nfields && !strcmp(t->fields[f], "zero"))
            continue;
        for (int axis = 0; axis < 2; ++axis) {
            int dr = axis == 0, du = axis == 1;
            double h = axis == 0 ? g->hr : g->hu;
            for (int iu = 0; iu < g->nu; ++iu)
                for (int ir = 0; ir < g->nr; ++ir) {
                    if (ir + dr >= g->nr || iu + du >= g->nu)
                        continue;
                    double a = smooth_value(g, f, ir, iu), b = smooth_value(g, f, ir + dr, iu + du);
                    if (!isfinite(a) || !isfinite(b))
                        continue;
                    const int tr[2] = {ir, ir + dr}, tu[2] = {iu, iu + du};
                    double mhi, mlo;
                    magnitude_range(g, tr, tu, 2, &mhi, &mlo);
                    double wt = smooth_weight(g, f, mhi, mlo);
                    char w[64];
                    snprintf(w, sizeof w, "%s along %s", smooth_field_name(g, f), axis == 0 ? "r" : "u");
                    double d = fabs(b - a);
                    int is_fres = f == fres_field && fres_field >= 0;
                    if (g->model && f < t->nfields && (f == mag_field || is_fres) && d > GATE_JUMP_PER_H * h) {
                        double e[2];
                        int ok = 1;
                        for (int k = 0; k < 2 && ok; ++k) {
                            mf_result q;
                            ok = is_fres ? quad_fresnel(g, tr[k], tu[k], &q) : quad_albedo(g, tr[k], tu[k], &q);
                            if (ok)
                                e[k] = rec(t, tr[k], tu[k])[f] - q.val;
                        }
                        if (!is_fres && !g->qalb) {
                            out_of_memory(g, c);
                            return;
                        }
                        if (ok) {
                            d = fabs(e[1] - e[0]);
                            snprintf(w, sizeof w, "%s - %s along %s", t->fields[f], is_fres ? "moment" : "albedo",
                                     axis == 0 ? "r" : "u");
                        }
                    }
                    record_texel(c, wt * d / (GATE_JUMP_PER_H * h), w, ir, iu, mf_ltc_table_alpha(t, ir),
                                 mf_ltc_table_cos_theta(t, iu));
                }
        }
    }
}

/* The model's Schlick moment (the fresnel field's quantity, mf_model_albedo_fresnel) at texel
 * (ir, iu) by the same 64 x 64 quadrature; not cached (needed at a few texels only); 0 if it failed. */
static int quad_fresnel(gate_ctx *g, int ir, int iu, mf_result *q)
{
    mf_brdf_params p = mf_brdf_params_iso(mf_ltc_table_alpha(g->t, ir));
    mf_result a;
    return mf_model_albedo_fresnel(g->model, &p, mf_ltc_gate_view(mf_ltc_table_cos_theta(g->t, iu)), GATE_QUAD_N, &a,
                                   q) == MF_OK;
}

/* With a model, a spike of the magnitude is measured on its error magnitude - Q (Q the model's
 * albedo by quadrature, computed for the texels involved only): the true albedo itself has
 * spikes at the grazing rows of low roughness that no 64-row table resolves
 * (docs/validation.md: GGX alpha 0.016, 86.4 / 88.2 / 89.95 deg: 0.962, 0.912, 0.990, a dip
 * of 2.5 x 80 h^2), and a wrong magnitude is a spike of the error as much as of the value.  The
 * fresnel field (the Schlick moment) has the same true spikes (Beckmann alpha 0.00025 / 0.001 /
 * 0.0023 at 89.95 deg: 0.9848, 0.9095, 0.9325 by 1024 x 1024, a dip of 1.14 x 80 h^2 along r), so
 * it is measured on fresnel - the model's moment the same way. */
static void check_smooth_spike(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    const mf_table *t = g->t;
    const int mag_field = g->L.f[MF_LTC_F_MAGNITUDE], fres_field = g->L.f[MF_LTC_F_FRESNEL];
    if (g->model)
        snprintf(c->what, sizeof c->what, "%s",
                 "max excess of a texel outside its 2 neighbours' range / (80 h^2), every field (magnitude, fresnel: "
                 "minus the model's albedo, Schlick moment), both axes");
    for (int f = 0; f <= t->nfields; ++f) {
        if (f < t->nfields && !strcmp(t->fields[f], "zero"))
            continue;
        for (int axis = 0; axis < 2; ++axis) {
            int dr = axis == 0, du = axis == 1;
            double h = axis == 0 ? g->hr : g->hu;
            for (int iu = 0; iu < g->nu; ++iu)
                for (int ir = 0; ir < g->nr; ++ir) {
                    if (ir + dr >= g->nr || iu + du >= g->nu || ir - dr < 0 || iu - du < 0)
                        continue;
                    double a = smooth_value(g, f, ir, iu), b = smooth_value(g, f, ir + dr, iu + du);
                    double l = smooth_value(g, f, ir - dr, iu - du);
                    if (!isfinite(a) || !isfinite(b) || !isfinite(l))
                        continue;
                    const int t3r[3] = {ir - dr, ir, ir + dr}, t3u[3] = {iu - du, iu, iu + du};
                    double mhi, mlo;
                    magnitude_range(g, t3r, t3u, 3, &mhi, &mlo);
                    double wt = smooth_weight(g, f, mhi, mlo);
                    char w[64];
                    snprintf(w, sizeof w, "%s along %s", smooth_field_name(g, f), axis == 0 ? "r" : "u");
                    double lo = l < b ? l : b, hi = l < b ? b : l;
                    double ex = a > hi ? a - hi : (a < lo ? lo - a : 0.0);
                    int is_fres = f == fres_field && fres_field >= 0;
                    if (g->model && (f == mag_field || is_fres) && ex > GATE_SPIKE_PER_H2 * h * h) {
                        const int tr[3] = {ir - dr, ir, ir + dr}, tu[3] = {iu - du, iu, iu + du};
                        double e[3];
                        int ok = 1;
                        for (int k = 0; k < 3 && ok; ++k) {
                            mf_result q;
                            ok = is_fres ? quad_fresnel(g, tr[k], tu[k], &q) : quad_albedo(g, tr[k], tu[k], &q);
                            if (ok)
                                e[k] = rec(t, tr[k], tu[k])[f] - q.val;
                        }
                        if (!g->qalb) {
                            out_of_memory(g, c);
                            return;
                        }
                        if (ok) {
                            lo = e[0] < e[2] ? e[0] : e[2];
                            hi = e[0] < e[2] ? e[2] : e[0];
                            ex = e[1] > hi ? e[1] - hi : (e[1] < lo ? lo - e[1] : 0.0);
                            snprintf(w, sizeof w, "%s - %s along %s", t->fields[f], is_fres ? "moment" : "albedo",
                                     axis == 0 ? "r" : "u");
                        }
                    }
                    record_texel(c, wt * ex / (GATE_SPIKE_PER_H2 * h * h), w, ir, iu, mf_ltc_table_alpha(t, ir),
                                 mf_ltc_table_cos_theta(t, iu));
                }
        }
    }
}

static void check_albedo_quad(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    const mf_table *t = g->t;
    int ir_idx[1024], iu_idx[1024];
    int mr = sample_axis(g->nr, g->o.quick ? 8 : 1024, ir_idx); /* every texel in full mode (up to 1024 per axis) */
    int mu = sample_axis(g->nu, g->o.quick ? 8 : 1024, iu_idx);
    for (int b = 0; b < mu; ++b)
        for (int a = 0; a < mr; ++a) {
            int ir = ir_idx[a], iu = iu_idx[b];
            double alpha = mf_ltc_table_alpha(t, ir), ct = mf_ltc_table_cos_theta(t, iu);
            double mag = rec(t, ir, iu)[g->L.f[MF_LTC_F_MAGNITUDE]];
            mf_result q;
            double v = INFINITY;
            const char *w = "quadrature failed (model NaN)";
            if (quad_albedo(g, ir, iu, &q)) {
                double den = q.val > GATE_ALBEDO_FLOOR ? q.val : GATE_ALBEDO_FLOOR;
                double ex = fabs(mag - q.val) - GATE_ALBEDO_ERR_FACTOR * q.err;
                v = (ex > 0.0 ? ex : 0.0) / den;
                if (fabs(mag - q.val) / den > g->worst_alb)
                    g->worst_alb = fabs(mag - q.val) / den;
                w = mag > q.val ? "magnitude above the albedo" : "magnitude below the albedo";
            } else if (!g->qalb) {
                out_of_memory(g, c);
                return;
            }
            record_texel(c, v, w, ir, iu, alpha, ct);
        }
}

/* The polygon pass: random polygons and the Monte Carlo albedo at the polygon texels (the quick
 * 8 x 8 grid, or 16 x 16 in full mode), once for the three checks that read it.  0 when out of
 * memory. */
static int polygon_pass(gate_ctx *g)
{
    if (g->poly_done)
        return g->ent != NULL;
    g->poly_done = 1;
    const mf_table *t = g->t;
    const mf_brdf_model *model = g->model;
    const int npoly = g->npoly, nsamples = g->nsamples, nr = g->nr;
    int kq = g->o.quick ? 8 : 16;
    int pr_idx[1024], pu_idx[1024];
    int pmr = sample_axis(nr, kq, pr_idx), pmu = sample_axis(g->nu, kq, pu_idx);
    long maxpoly = (long)pmr * pmu * npoly;
    g->ent = malloc(sizeof *g->ent * (size_t)pmr * (size_t)pmu);
    g->eabs = malloc(sizeof *g->eabs * (size_t)(maxpoly > 0 ? maxpoly : 1));
    g->erel = malloc(sizeof *g->erel * (size_t)(maxpoly > 0 ? maxpoly : 1));
    mf_polygon *polys = malloc(sizeof *polys * (size_t)npoly);
    double *mc = malloc(sizeof *mc * (size_t)npoly * 2);
    if (!g->ent || !g->eabs || !g->erel || !polys || !mc) {
        free(polys);
        free(mc);
        free(g->ent);
        g->ent = NULL;
        return 0;
    }
    double *se = mc + npoly;
    for (int b = 0; b < pmu; ++b)
        for (int a = 0; a < pmr; ++a) {
            int ir = pr_idx[a], iu = pu_idx[b];
            size_t texel = (size_t)ir + (size_t)nr * (size_t)iu;
            gate_entry *e = &g->ent[g->nent++];
            e->ir = ir;
            e->iu = iu;
            double alpha = e->alpha = mf_ltc_table_alpha(t, ir), ct = e->ct = mf_ltc_table_cos_theta(t, iu);
            mf_vec3 wo = mf_ltc_gate_view(ct);
            double mag = e->mag = rec(t, ir, iu)[g->L.f[MF_LTC_F_MAGNITUDE]];
            mf_ltc ltc;
            int ok = unpack_at(t, &g->L, ir, iu, &ltc) && isfinite(mag);
            mf_ltc_gate_random_polygons(model, alpha, wo, g->o.seed, stream_id(STREAM_POLY, texel), npoly, polys);
            mf_result alb = {0}, q; /* alb is read (and ignored) by record_entry when !ok */
            if (mf_ltc_gate_polygon_mc(model, alpha, wo, polys, npoly, nsamples, g->o.seed, stream_id(STREAM_MC, texel), mc,
                                       se, &alb) != MF_OK)
                ok = 0;
            if (!quad_albedo(g, ir, iu, &q))
                ok = 0;
            e->ok = ok;
            e->alb = alb;
            e->excess = INFINITY;
            if (!ok) {
                g->sum_excess += INFINITY;
                continue;
            }
            double albedo = q.val > 1e-300 ? q.val : 1e-300;
            double ent = 0.0;
            for (int i = 0; i < npoly; ++i) {
                double ltcv = mag * mf_ltc_integrate_polygon(&ltc, &polys[i], MF_POLYGON_ONE_SIDED);
                double d = fabs(ltcv - mc[i]);
                if (isnan(d))
                    ent = NAN; /* a NaN case (mf_check.h); the aggregates count it as infinite */
                if (!isfinite(d))
                    d = INFINITY;
                double ex = d - GATE_Z * se[i] - GATE_MAG_STORAGE;
                ex = (ex > 0.0 ? ex : 0.0) / albedo;
                ent += ex;
                double rden = mc[i] > GATE_REL_FLOOR * albedo ? mc[i] : GATE_REL_FLOOR * albedo;
                g->eabs[g->np] = d;
                g->erel[g->np] = d / rden;
                g->sum_abs += d;
                g->sum_rel += g->erel[g->np];
                g->sum_se += se[i];
                if (d > g->worst_abs)
                    g->worst_abs = d;
                if (g->erel[g->np] > g->worst_rel)
                    g->worst_rel = g->erel[g->np];
                ++g->np;
            }
            g->sum_excess += ent;
            e->excess = ent;
        }
    free(polys);
    free(mc);
    return 1;
}

/* Records v for the MC entry e, or +inf if its texel or the model was unusable (v is not used). */
static void record_entry(mf_check *c, const gate_entry *e, double v, const char *what)
{
    if (!e->ok)
        record_texel(c, INFINITY, "unusable entry or model", e->ir, e->iu, e->alpha, e->ct);
    else
        record_texel(c, v, what, e->ir, e->iu, e->alpha, e->ct);
}

/* Runs the polygon pass for the check c (once per gate); 0 (c failed: out of memory) if it could not. */
static int need_polygon_pass(gate_ctx *g, mf_check *c)
{
    if (polygon_pass(g))
        return 1;
    out_of_memory(g, c);
    return 0;
}

static void check_albedo_mc(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    if (!need_polygon_pass(g, c))
        return;
    for (long k = 0; k < g->nent; ++k) {
        const gate_entry *e = &g->ent[k];
        /* magnitude and MC albedo both exactly 0 (a sheen texel whose albedo underflows, every
         * sample's weight 0, se 0): exact agreement, 0, not 0/0; any other NaN stays NaN */
        double diff = fabs(e->mag - e->alb.val);
        record_entry(c, e, diff == 0.0 ? 0.0 : diff / (GATE_Z * e->alb.err + 1e-3 * fabs(e->mag) + GATE_MAG_STORAGE),
                     e->mag > e->alb.val ? "magnitude above MC" : "magnitude below MC");
    }
}

static void check_polygon_mean(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    snprintf(c->what, sizeof c->what, "mean over polygons of max(0, |LTC - MC| - 5.5 se - 2^-149) / albedo (budget %g)",
             g->budget_mean);
    c->bound = g->budget_mean;
    if (!need_polygon_pass(g, c))
        return;
    /* one aggregate value: the mean excess over all polygons (+inf for an unusable texel) */
    long np = g->np;
    mf_check_recordf(c, np > 0 ? g->sum_excess / (double)np : INFINITY,
                     "%ld texels x %d polygons, %d samples; |LTC-MC| mean %.3g worst %.3g, rel mean %.3g worst %.3g",
                     g->nent, g->npoly, g->nsamples, np ? g->sum_abs / np : NAN, g->worst_abs,
                     np ? g->sum_rel / np : NAN, g->worst_rel);
    c->cases = np;
}

static void check_polygon_entry(void *ctx, mf_check *c)
{
    gate_ctx *g = ctx;
    snprintf(c->what, sizeof c->what, "worst texel's mean of max(0, |LTC - MC| - 5.5 se - 2^-149) / albedo (budget %g)",
             g->budget_entry);
    c->bound = g->budget_entry;
    if (!need_polygon_pass(g, c))
        return;
    for (long k = 0; k < g->nent; ++k)
        record_entry(c, &g->ent[k], g->ent[k].excess / g->npoly, "mean polygon excess");
}

/* The gate: name, what it measures, bound, needs a model, function (bounds and reasons in
 * docs/validation.md, "The LTC gate").  The polygon checks take their bounds from the options. */
const mf_check_def mf_ltc_gate_check_table[MF_LTC_GATE_MAX_CHECKS] = {
    {"ltc_finite", "number of NaN or infinite values in any field (bound 0)", 0.0, 0, check_finite},
    {"ltc_energy", "max(magnitude - 1, fresnel - magnitude, -fresnel, -magnitude) over all texels", GATE_ENERGY_SLACK, 0,
     check_energy},
    {"ltc_normalisation", "|integral over the sphere - 1|: exact integrals over 8 rotated octant triangles, every texel",
     GATE_NORM_BOUND, 0, check_normalisation},
    {"ltc_smooth_jump", "max |neighbour difference| / (16 h) of every field, the matrix scaled by its largest entry and "
                        "weighted by min(1, magnitude / 1e-5) (h: axis spacing)", 1.0, 0,
     check_smooth_jump},
    {"ltc_smooth_spike", "max excess of a texel outside its 2 neighbours' range / (80 h^2), every field (the matrix as in "
                         "ltc_smooth_jump), both axes", 1.0,
     0, check_smooth_spike},
    {"ltc_albedo_quad",
     "max (|magnitude - albedo| - 4 err) / max(albedo, 0.01), albedo by 64x64 Gauss-Legendre quadrature",
     GATE_ALBEDO_REL, 1, check_albedo_quad},
    {"ltc_albedo_mc", "max |magnitude - MC albedo| / (5.5 se + 1e-3 magnitude + 2^-149), independent MC", 1.0, 1,
     check_albedo_mc},
    {"ltc_polygon_mean", "mean over polygons of max(0, |LTC - MC| - 5.5 se - 2^-149) / albedo", MF_LTC_GATE_POLYGON_MEAN, 1,
     check_polygon_mean},
    {"ltc_polygon_entry", "worst texel's mean of max(0, |LTC - MC| - 5.5 se - 2^-149) / albedo", MF_LTC_GATE_POLYGON_ENTRY, 1,
     check_polygon_entry},
};
#define N_GATE_CHECKS MF_LTC_GATE_MAX_CHECKS

const mf_check_def *mf_ltc_gate_checks(int *n)
{
    if (n)
        *n = N_GATE_CHECKS;
    return mf_ltc_gate_check_table;
}

/* ---- the driver ------------------------------------------------------------------------------ */

mf_status mf_ltc_gate_run(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o_in,
                          mf_check *checks, int cap, int *count)
{
    if (count)
        *count = 0;
    if (!checks || !count || cap < MF_LTC_GATE_MAX_CHECKS)
        return MF_ERR_DOMAIN;
    gate_ctx g;
    memset(&g, 0, sizeof g);
    if (o_in)
        g.o = *o_in;
    else
        mf_ltc_gate_options_default(&g.o);
    if (!layout_of(t, &g.L))
        return MF_ERR_DOMAIN;
    g.t = t;
    g.model = model;
    g.budget_mean = g.o.polygon_budget_mean > 0.0 ? g.o.polygon_budget_mean : MF_LTC_GATE_POLYGON_MEAN;
    g.budget_entry = g.o.polygon_budget_entry > 0.0 ? g.o.polygon_budget_entry : MF_LTC_GATE_POLYGON_ENTRY;
    g.nsamples = g.o.mc_samples > 0 ? g.o.mc_samples : (g.o.quick ? 32768 : 65536);
    g.npoly = g.o.polygons_per_entry > 0 ? g.o.polygons_per_entry : 24;
    if (g.npoly > 256)
        g.npoly = 256;
    g.nr = g.L.nr;
    g.nu = g.L.nu;
    g.hr = fabs(t->axes[0].hi - t->axes[0].lo) / (g.nr - 1);
    g.hu = fabs(t->axes[1].hi - t->axes[1].lo) / (g.nu - 1);
    g.status = MF_OK;

    mf_status st = mf_check_run_defs(mf_ltc_gate_check_table, N_GATE_CHECKS, &g, model != NULL, checks, cap, count);

    if (model && g.o.stats && g.poly_done && g.ent) {
        mf_ltc_gate_stats *s = g.o.stats;
        long np = g.np;
        memset(s, 0, sizeof *s);
        s->polygons = np;
        s->entries = g.nent;
        s->mean_abs = np ? g.sum_abs / np : NAN;
        s->mean_rel = np ? g.sum_rel / np : NAN;
        s->mean_se = np ? g.sum_se / np : NAN;
        s->worst_abs = g.worst_abs;
        s->worst_rel = g.worst_rel;
        s->p95_abs = percentile95(g.eabs, np);
        s->p95_rel = percentile95(g.erel, np);
        s->worst_albedo_rel = g.worst_alb;
    }
    free(g.qalb);
    free(g.ent);
    free(g.eabs);
    free(g.erel);
    if (g.status != MF_OK) {
        *count = 0;
        return g.status;
    }
    return st;
}

/* ---- the texel check's building blocks (mf_ltc_gate.h; the fit side runs the check) ---------- */

void mf_ltc_gate_texel_polygons(const mf_table *t, const mf_brdf_model *model, uint64_t seed, int ir, int iu, int n,
                                mf_polygon *out)
{
    size_t texel = (size_t)ir + (size_t)t->axes[0].size * (size_t)iu;
    mf_ltc_gate_random_polygons(model, mf_ltc_table_alpha(t, ir), mf_ltc_gate_view(mf_ltc_table_cos_theta(t, iu)),
                                seed, stream_id(STREAM_POLY, texel), n, out);
}

mf_status mf_ltc_gate_texel(const mf_table *t, int ir, int iu, mf_ltc *ltc, double *magnitude)
{
    gate_layout L;
    if (!ltc || !magnitude || !layout_of(t, &L) || ir < 0 || iu < 0 || ir >= L.nr || iu >= L.nu)
        return MF_ERR_DOMAIN;
    double mag = rec(t, ir, iu)[L.f[MF_LTC_F_MAGNITUDE]];
    if (!isfinite(mag) || !unpack_at(t, &L, ir, iu, ltc))
        return MF_ERR_DOMAIN;
    *magnitude = mag;
    return MF_OK;
}

double mf_ltc_gate_texel_difference(const mf_ltc *ltc, double magnitude, const mf_ltc *ref, double ref_magnitude,
                                    const mf_polygon *p, int n, int *worst)
{
    const double floor = MF_LTC_GATE_TEXEL_FLOOR * ref_magnitude;
    double d = 0.0;
    int at = -1;
    for (int i = 0; i < n; ++i) {
        double s = magnitude * mf_ltc_integrate_polygon(ltc, &p[i], MF_POLYGON_ONE_SIDED);
        double r = ref_magnitude * mf_ltc_integrate_polygon(ref, &p[i], MF_POLYGON_ONE_SIDED);
        if (isnan(s) || isnan(r)) {
            if (worst)
                *worst = i;
            return NAN;
        }
        if (!(s > floor) && !(r > floor))
            continue;
        double v = fabs(s - r) / (r > floor ? r : floor);
        if (v > d || at < 0) {
            d = v;
            at = i;
        }
    }
    if (worst)
        *worst = at;
    return d;
}

/* ---- the neighbour check (fitter-free; mf_ltc_gate.h, docs/validation.md "The neighbour check") ----
 * Every texel is predicted from its neighbours along r and along u by six stencils per axis, in two
 * spaces of the 2 x 2 block B = [[minv_00, minv_02], [minv_20, minv_22]] (the stored fields; and
 * log-polar: B = R(psi) S, S symmetric positive definite, coordinates psi and the three entries of
 * log S), and the stored texel is compared with each prediction by the texel check's d on its 24 gate
 * polygons, magnitudes set to 1 (the magnitude is the albedo checks' business).  s = the second
 * smallest d over the predictions; e = the largest, over the texel's (up to 4) axis neighbours, of
 * the neighbour's smallest d over its predictions whose stencils do not use this texel, and over its
 * (up to 4) diagonal neighbours, of the neighbour's smallest d.  The
 * check's value is s / (NB_TAU + NB_C e). */
#define NB_TAU MF_LTC_GATE_NEIGHBOUR_TAU
#define NB_C MF_LTC_GATE_NEIGHBOUR_C
#define NB_AXIS_PRED 6
#define NB_PRED (2 * NB_AXIS_PRED)

/* The stencils: the neighbour offsets each one uses.  The weights are Lagrange's for a polynomial
 * through the stencil's texels evaluated at the texel (nb_weights): on the r axis in the abscissa
 * log(alpha), along u in the texel index.  In the index these are the centred cubic
 * (-1, 4, 4, -1) / 6, the centred mean, and the one-sided extrapolations (3, -3, 1) and (2, -1). */
static const int nb_off[NB_AXIS_PRED][4] = {{-2, -1, 1, 2}, {-1, 1, 0, 0}, {-1, -2, -3, 0},
                                            {1, 2, 3, 0},    {-1, -2, 0, 0}, {1, 2, 0, 0}};
static const int nb_n[NB_AXIS_PRED] = {4, 2, 3, 3, 2, 2};

/* Lagrange weights of stencil pr at texel k of axis ax.  Along r the abscissa is log(alpha): a
 * narrow lobe's matrix changes with alpha over orders of magnitude near the table's low-roughness
 * edge (alpha = r^2, so log alpha = 2 log r), where a polynomial in the index predicts it badly;
 * where two texels share an alpha (a clamp) the index is used. */
static void nb_weights(const mf_table *t, int ax, int k, int pr, double *w)
{
    double xi[4], xt = 0.0;
    int idx = ax == 1;
    if (!idx) {
        xt = log(mf_ltc_table_alpha(t, k));
        for (int i = 0; i < nb_n[pr]; ++i)
            xi[i] = log(mf_ltc_table_alpha(t, k + nb_off[pr][i]));
        idx = !isfinite(xt);
        for (int i = 0; i < nb_n[pr] && !idx; ++i) {
            idx = !isfinite(xi[i]) || xi[i] == xt;
            for (int j = 0; j < i && !idx; ++j)
                idx = xi[i] == xi[j];
        }
    }
    if (idx) {
        xt = 0.0;
        for (int i = 0; i < nb_n[pr]; ++i)
            xi[i] = (double)nb_off[pr][i];
    }
    for (int i = 0; i < nb_n[pr]; ++i) {
        double v = 1.0;
        for (int j = 0; j < nb_n[pr]; ++j)
            if (j != i)
                v *= (xt - xi[j]) / (xi[i] - xi[j]);
        w[i] = v;
    }
}

/* Stored fields (minv_00, minv_20, minv_02, minv_22) -> log-polar (psi, L11, L12, L22); 0 if the
 * block's determinant is not positive. */
static int nb_to_logpolar(const double f[4], double x[4])
{
    double a = f[0], c = f[1], b = f[2], d = f[3];
    if (!(a * d - b * c > 0.0))
        return 0;
    double psi = atan2(c - b, a + d), cs = cos(psi), sn = sin(psi);
    double s11 = cs * a + sn * c, s22 = -sn * b + cs * d;
    double s12 = 0.5 * ((cs * b + sn * d) + (-sn * a + cs * c));
    double half = 0.5 * (s11 + s22), df = 0.5 * (s11 - s22), r = sqrt(df * df + s12 * s12);
    double l1 = half + r, l2 = half - r;
    if (!(l2 > 0.0) || !isfinite(l1))
        return 0;
    double th = 0.5 * atan2(2.0 * s12, s11 - s22), ct = cos(th), st = sin(th);
    double g1 = log(l1), g2 = log(l2);
    x[0] = psi;
    x[1] = ct * ct * g1 + st * st * g2;
    x[2] = ct * st * (g1 - g2);
    x[3] = st * st * g1 + ct * ct * g2;
    return 1;
}

static void nb_from_logpolar(const double x[4], double f[4])
{
    double l11 = x[1], l12 = x[2], l22 = x[3];
    double half = 0.5 * (l11 + l22), df = 0.5 * (l11 - l22), r = sqrt(df * df + l12 * l12);
    double th = 0.5 * atan2(2.0 * l12, l11 - l22), ct = cos(th), st = sin(th);
    double e1 = exp(half + r), e2 = exp(half - r);
    double s11 = ct * ct * e1 + st * st * e2, s12 = ct * st * (e1 - e2), s22 = st * st * e1 + ct * ct * e2;
    double cs = cos(x[0]), sn = sin(x[0]);
    f[0] = cs * s11 - sn * s12; /* minv_00 */
    f[1] = sn * s11 + cs * s12; /* minv_20 */
    f[2] = cs * s12 - sn * s22; /* minv_02 */
    f[3] = sn * s12 + cs * s22; /* minv_22 */
}

/* d of each prediction of texel (ir, iu) (NB_PRED values: NB_NONE where a stencil leaves the table
 * or meets a non-finite texel, +inf where the stored texel or the prediction cannot be unpacked, NaN
 * for a NaN integral). */
#define NB_NONE (-1.0)
static void nb_texel(const mf_table *t, const gate_layout *L, const mf_brdf_model *model, uint64_t seed, int ir, int iu,
                     double *d)
{
    mf_polygon p[MF_LTC_GATE_TEXEL_POLYGONS];
    mf_ltc_gate_texel_polygons(t, model, seed, ir, iu, MF_LTC_GATE_TEXEL_POLYGONS, p);
    mf_ltc s;
    int sok = unpack_at(t, L, ir, iu, &s);
    for (int ax = 0; ax < 2; ++ax) {
        int n = ax ? L->nu : L->nr, k = ax ? iu : ir;
        double raw[7][4], lp[7][4];
        int have[7], have_lp[7];
        for (int o = -3; o <= 3; ++o) {
            int kk = k + o, j = o + 3;
            have[j] = have_lp[j] = 0;
            if (o == 0 || kk < 0 || kk >= n)
                continue;
            const double *r = rec(t, ax ? ir : kk, ax ? kk : iu);
            for (int q = 0; q < 4; ++q)
                raw[j][q] = r[L->f[q]];
            have[j] = isfinite(raw[j][0]) && isfinite(raw[j][1]) && isfinite(raw[j][2]) && isfinite(raw[j][3]);
            have_lp[j] = have[j] && nb_to_logpolar(raw[j], lp[j]);
        }
        /* psi unwrapped about the nearest neighbour's (either side) */
        double ref = NAN;
        for (int o = 1; o <= 3 && isnan(ref); ++o)
            ref = have_lp[3 - o] ? lp[3 - o][0] : have_lp[3 + o] ? lp[3 + o][0] : NAN;
        for (int j = 0; j < 7; ++j)
            if (have_lp[j])
                lp[j][0] -= 2.0 * MF_PI * floor((lp[j][0] - ref) / (2.0 * MF_PI) + 0.5);
        for (int pr = 0; pr < NB_AXIS_PRED; ++pr) {
            double best = NB_NONE, wt[4];
            int inside = 1;
            for (int i = 0; i < nb_n[pr]; ++i)
                inside &= k + nb_off[pr][i] >= 0 && k + nb_off[pr][i] < n;
            if (inside)
                nb_weights(t, ax, k, pr, wt);
            for (int space = 0; space < 2; ++space) {
                int ok = 1;
                double x[4] = {0, 0, 0, 0}, f[4];
                for (int i = 0; i < nb_n[pr] && ok; ++i) {
                    int j = nb_off[pr][i] + 3;
                    ok = inside && (space ? have_lp[j] : have[j]);
                    for (int q = 0; q < 4 && ok; ++q)
                        x[q] += wt[i] * (space ? lp[j][q] : raw[j][q]);
                }
                if (!ok)
                    continue;
                if (space)
                    nb_from_logpolar(x, f);
                else
                    memcpy(f, x, sizeof f);
                /* A block of determinant <= 0 is a lobe whose peak M z lies at or below the horizon
                 * (M z ~ (-minv_02, 0, minv_00) / det): no fitted texel of a reflectance lobe is
                 * one, and such a prediction shades (almost) nothing, so it "agrees" with a
                 * corrupted texel that shades nothing too (a point lobe at alpha 1e-4 flipped by
                 * minv_22 -> minv_22 - 0.001: D = 1, read d = 0).  It is not a prediction. */
                if (!(f[0] * f[3] - f[2] * f[1] > 0.0))
                    continue;
                mf_ltc q;
                double v = INFINITY;
                if (sok && mf_ltc_table_unpack(f, &q) == MF_OK)
                    v = mf_ltc_gate_texel_difference(&s, 1.0, &q, 1.0, p, MF_LTC_GATE_TEXEL_POLYGONS, NULL);
                if (isnan(v) || isnan(best))
                    best = NAN; /* a NaN integral is reported, not hidden by the other space */
                else if (best == NB_NONE || v < best)
                    best = v;
            }
            d[ax * NB_AXIS_PRED + pr] = best;
        }
    }
}

/* The smallest d of texel j over its predictions, leaving out those whose stencil uses the texel
 * (xr, xu) (xr < 0: none left out).  +inf if there is none. */
static double nb_min(const double *dj, int jr, int ju, int xr, int xu)
{
    double b = INFINITY;
    for (int ax = 0; ax < 2; ++ax)
        for (int pr = 0; pr < NB_AXIS_PRED; ++pr) {
            double v = dj[ax * NB_AXIS_PRED + pr];
            if (v == NB_NONE || !(isnan(v) || v < b))
                continue;
            int uses = 0;
            for (int i = 0; i < nb_n[pr] && xr >= 0; ++i) {
                int o = nb_off[pr][i];
                if ((ax ? jr : jr + o) == xr && (ax ? ju + o : ju) == xu)
                    uses = 1;
            }
            if (!uses) {
                if (isnan(v))
                    return NAN;
                b = v;
            }
        }
    return b;
}

/* The second smallest d of texel k over its predictions (the smallest if it has only one): one
 * prediction alone may pass anywhere near a corrupted texel where the stencils scatter (a narrow
 * lobe, whose predictions put it in or out of a polygon), two seldom do.  +inf if there is none;
 * NaN if a prediction's integral was NaN. */
static double nb_second(const double *dk)
{
    double m1 = INFINITY, m2 = INFINITY;
    int any = 0;
    for (int q = 0; q < NB_PRED; ++q) {
        double v = dk[q];
        if (v == NB_NONE)
            continue;
        if (isnan(v))
            return NAN;
        any = 1;
        if (v < m1) {
            m2 = m1;
            m1 = v;
        } else if (v < m2)
            m2 = v;
    }
    if (!any)
        return INFINITY;
    return m2 < INFINITY ? m2 : m1; /* one usable prediction: that one */
}

mf_status mf_ltc_gate_neighbour_scores_box(const mf_table *t, const mf_brdf_model *model, uint64_t seed, int r0,
                                           int r1, int u0, int u1, double *s, double *e, double *v)
{
    return mf_ltc_gate_neighbour_scores_box_refit(t, model, seed, r0, r1, u0, u1, NULL, NULL, s, e, v, NULL);
}

mf_status mf_ltc_gate_neighbour_scores_box_refit(const mf_table *t, const mf_brdf_model *model, uint64_t seed, int r0,
                                                 int r1, int u0, int u1, mf_ltc_gate_refit_fn refit, void *user,
                                                 double *s, double *e, double *v, double *refit_d)
{
    gate_layout L;
    if (!model || !layout_of(t, &L) || r0 < 0 || u0 < 0 || r1 >= L.nr || u1 >= L.nu || r0 > r1 || u0 > u1)
        return MF_ERR_DOMAIN;
    /* d of every prediction of the box and the texels around it (the allowance reads theirs) */
    int br0 = r0 > 0 ? r0 - 1 : 0, br1 = r1 + 1 < L.nr ? r1 + 1 : r1;
    int bu0 = u0 > 0 ? u0 - 1 : 0, bu1 = u1 + 1 < L.nu ? u1 + 1 : u1, bnr = br1 - br0 + 1;
    size_t nb_texels = (size_t)bnr * (size_t)(bu1 - bu0 + 1);
    double *d = malloc(sizeof *d * nb_texels * NB_PRED);
    if (!d)
        return MF_ERR_ALLOC;
#define NB_D(ir, iu) (d + ((size_t)((ir) - br0) + (size_t)bnr * (size_t)((iu) - bu0)) * NB_PRED)
    for (int iu = bu0; iu <= bu1; ++iu)
        for (int ir = br0; ir <= br1; ++ir)
            nb_texel(t, &L, model, seed, ir, iu, NB_D(ir, iu));
    /* e: the axis neighbours' smallest d without the stencils that use the texel, and the diagonal
     * neighbours' smallest d (none of their stencils uses the texel: they lie on other rows and
     * columns), so a fast change along a line through the texel, which spoils the diagonals'
     * predictions too, widens the allowance, and a single bad texel, which spoils none of theirs,
     * does not. */
    const int nb[8][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
    for (int iu = u0; iu <= u1; ++iu)
        for (int ir = r0; ir <= r1; ++ir) {
            size_t k = (size_t)ir + (size_t)L.nr * iu;
            double sk = nb_second(NB_D(ir, iu)), ek = 0.0;
            for (int q = 0; q < 8; ++q) {
                int jr = ir + nb[q][0], ju = iu + nb[q][1];
                if (jr < 0 || ju < 0 || jr >= L.nr || ju >= L.nu)
                    continue;
                double x = q < 4 ? nb_min(NB_D(jr, ju), jr, ju, ir, iu) : nb_min(NB_D(jr, ju), jr, ju, -1, -1);
                if (isfinite(x) && x > ek)
                    ek = x;
            }
            if (s)
                s[k] = sk;
            if (e)
                e[k] = ek;
            double vk = sk / (NB_TAU + NB_C * ek), rd = NAN;
            /* A candidate (or a flagged texel) with a fitter at hand: the refit check's own value
             * (d against a fresh fit of the texel, bound MF_LTC_GATE_TEXEL_REL) replaces the
             * neighbours' estimate (docs/validation.md, "The refit of candidate texels"). */
            if (refit && !(vk <= MF_LTC_GATE_NEIGHBOUR_REFIT_FROM)) {
                rd = refit(user, t, ir, iu);
                if (!isnan(rd))
                    vk = rd / MF_LTC_GATE_TEXEL_REL;
            }
            if (refit_d)
                refit_d[k] = rd;
            if (v)
                v[k] = vk;
        }
#undef NB_D
    free(d);
    return MF_OK;
}

mf_status mf_ltc_gate_neighbour_scores(const mf_table *t, const mf_brdf_model *model, uint64_t seed, double *s,
                                       double *e, double *v)
{
    gate_layout L;
    if (!model || !layout_of(t, &L))
        return MF_ERR_DOMAIN;
    return mf_ltc_gate_neighbour_scores_box(t, model, seed, 0, L.nr - 1, 0, L.nu - 1, s, e, v);
}

mf_status mf_ltc_gate_neighbour_check(const mf_table *t, const mf_brdf_model *model, uint64_t seed, mf_check *c)
{
    return mf_ltc_gate_neighbour_check_refit(t, model, seed, NULL, NULL, c);
}

mf_status mf_ltc_gate_neighbour_check_refit(const mf_table *t, const mf_brdf_model *model, uint64_t seed,
                                            mf_ltc_gate_refit_fn refit, void *user, mf_check *c)
{
    if (!c)
        return MF_ERR_DOMAIN;
    mf_check_begin(c, "ltc_texel_neighbours",
                   "max over texels of s / (0.06 + 2 e): s the 2nd smallest shading difference d from 12 neighbour predictions",
                   1.0);
    gate_layout L;
    if (!model || !layout_of(t, &L)) {
        mf_check_fail(c, "no model or not an LTC table layout");
        return MF_ERR_DOMAIN;
    }
    if (L.nr < MF_LTC_GATE_NEIGHBOUR_MIN_SIZE || L.nu < MF_LTC_GATE_NEIGHBOUR_MIN_SIZE) {
        /* no cases: the check passes with a note (docs/validation.md: fitted GGX 8, 10, 12 read
         * 97, 2.5, 1.2, 16 and more pass) */
        snprintf(c->what, sizeof c->what,
                 "not run: fewer than %d texels along an axis (neighbours too far apart to predict a texel)",
                 MF_LTC_GATE_NEIGHBOUR_MIN_SIZE);
        snprintf(c->worst_at, sizeof c->worst_at, "table %d x %d: not run", L.nr, L.nu);
        mf_check_finish(c);
        return MF_OK;
    }
    size_t n = (size_t)L.nr * (size_t)L.nu;
    double *s = malloc(sizeof *s * n * 4);
    if (!s) {
        mf_check_fail(c, "out of memory");
        return MF_ERR_ALLOC;
    }
    double *e = s + n, *v = e + n, *rd = v + n;
    mf_status st =
        mf_ltc_gate_neighbour_scores_box_refit(t, model, seed, 0, L.nr - 1, 0, L.nu - 1, refit, user, s, e, v, rd);
    if (st != MF_OK) {
        free(s);
        mf_check_fail(c, "out of memory");
        return st;
    }
    int nrefit = 0;
    for (int iu = 0; iu < L.nu; ++iu)
        for (int ir = 0; ir < L.nr; ++ir) {
            size_t k = (size_t)ir + (size_t)L.nr * iu;
            char w[96];
            if (isnan(rd[k]))
                snprintf(w, sizeof w, "s %.3g, e %.3g", s[k], e[k]);
            else {
                snprintf(w, sizeof w, "refit d %.3g (neighbours %.3g: s %.3g, e %.3g)", rd[k],
                         s[k] / (NB_TAU + NB_C * e[k]), s[k], e[k]);
                ++nrefit;
            }
            record_texel(c, v[k], w, ir, iu, mf_ltc_table_alpha(t, ir), mf_ltc_table_cos_theta(t, iu));
        }
    if (refit) {
        size_t len = strlen(c->what);
        snprintf(c->what + len, sizeof c->what - len, "; %d texels above %g refitted: d / %g", nrefit,
                 MF_LTC_GATE_NEIGHBOUR_REFIT_FROM, MF_LTC_GATE_TEXEL_REL);
    }
    free(s);
    mf_check_finish(c);
    return MF_OK;
}

mf_status mf_ltc_gate_validate(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                               mf_check *checks, int cap, int *count)
{
    return mf_ltc_gate_validate_refit(t, model, o, NULL, NULL, checks, cap, count);
}

mf_status mf_ltc_gate_validate_refit(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                                     mf_ltc_gate_refit_fn refit, void *user, mf_check *checks, int cap, int *count)
{
    if (!checks || !count || cap < MF_LTC_VALIDATE_MAX_CHECKS)
        return MF_ERR_DOMAIN;
    mf_ltc_gate_options def;
    if (!o) {
        mf_ltc_gate_options_default(&def);
        o = &def;
    }
    mf_status st = mf_ltc_gate_run(t, model, o, checks, cap, count);
    /* With a model, every texel against its neighbours' predictions (ltc_texel_neighbours: the
     * fitter-free stand-in for fit ltc's refit check, docs/validation.md "The neighbour check"). */
    if (model && (st == MF_OK || st == MF_ERR_CHECK_FAILED)) {
        mf_status ns = mf_ltc_gate_neighbour_check_refit(t, model, o->seed, refit, user, &checks[*count]);
        if (ns == MF_ERR_ALLOC)
            return ns;
        if (ns == MF_OK) {
            if (!checks[*count].passed)
                st = MF_ERR_CHECK_FAILED;
            ++*count;
        } else
            st = ns;
    }
    return st;
}
