/* mf_prefilter.c -- the effective BRDF of a normal-map footprint as a model, and the per-level LTC
 * fits (mf_prefilter.h) [Nahmias 2022, Eq. 2.34-2.36, Ch. 3]. */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_prefilter.h"

#include "mf_prefilter_internal.h"

#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the mixture ------------------------------------------------------------------------------ */

static const mf_prefilter_mix *mix_of(const mf_brdf_model *m) { return (const mf_prefilter_mix *)(const void *)m; }

static mf_vec3 rot_apply(const double *r, mf_vec3 v) /* R v */
{
    return mf_vec3_make(r[0] * v.x + r[1] * v.y + r[2] * v.z, r[3] * v.x + r[4] * v.y + r[5] * v.z,
                        r[6] * v.x + r[7] * v.y + r[8] * v.z);
}

static mf_vec3 rot_t(const double *r, mf_vec3 v) /* R^T v */
{
    return mf_vec3_make(r[0] * v.x + r[3] * v.y + r[6] * v.z, r[1] * v.x + r[4] * v.y + r[7] * v.z,
                        r[2] * v.x + r[5] * v.y + r[8] * v.z);
}

/* The view in texel frame j, its elevation cosine clamped to MF_PREFILTER_COS_MIN at the same
 * azimuth about n(q) [Nahmias 2022, Sec. 3, "Sampling the base BRDF"]. */
static mf_vec3 texel_view(const double *r, mf_vec3 wo)
{
    mf_vec3 v = rot_t(r, wo);
    if (v.z >= MF_PREFILTER_COS_MIN)
        return v;
    double h = sqrt(v.x * v.x + v.y * v.y);
    double s = sqrt(1.0 - MF_PREFILTER_COS_MIN * MF_PREFILTER_COS_MIN);
    if (!(h > 0.0))
        return mf_vec3_make(s, 0.0, MF_PREFILTER_COS_MIN);
    return mf_vec3_make(v.x / h * s, v.y / h * s, MF_PREFILTER_COS_MIN);
}

/* Isotropic GGX in closed form (the "ggx" model's formulas, mf_model_ggx.c: f = D G2 / (4 wo.z wi.z),
 * height-correlated G2 [Heitz 2014], density G1(wo) D(h) / (4 wo.z) [Heitz 2018; Walter 2007,
 * Eq. 14]), f cos and density sharing D(h) and Lambda(wo) -- one component of the mixture
 * (evaluated by ggx_fpdf_cached below). */
static double ggx_lambda_iso(double a2, mf_vec3 w)
{
    double t = a2 * (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return 0.5 * t / (1.0 + sqrt(1.0 + t));
}


/* Per view, per component, VC_N doubles (view_cache_fill): the texel-frame view vo and Lambda(vo),
 * then the visible-normal sampler's frame of vo [Heitz 2018, Listing 1]: vh, t1, t2 and
 * s = (1 + vh.z) / 2, computed with mf_sample_ggx_vndf's operations (so a sample from the cache
 * has its bits). */
#define VC_N 17
static void view_cache_fill(double alpha, mf_vec3 vo, double *c)
{
    double a2 = alpha * alpha, lo = ggx_lambda_iso(a2, vo);
    c[14] = a2 / (4.0 * MF_PI * vo.z), c[15] = 1.0 + 2.0 * lo, c[16] = 1.0 / (1.0 + lo);
    c[0] = vo.x, c[1] = vo.y, c[2] = vo.z, c[3] = ggx_lambda_iso(alpha * alpha, vo);
    mf_vec3 vh = mf_vec3_normalize(mf_vec3_make(alpha * vo.x, alpha * vo.y, vo.z));
    double lensq = vh.x * vh.x + vh.y * vh.y;
    mf_vec3 t1 = lensq > 0.0 ? mf_vec3_scale(mf_vec3_make(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq))
                             : mf_vec3_make(1.0, 0.0, 0.0);
    mf_vec3 t2 = mf_vec3_cross(vh, t1);
    c[4] = vh.x, c[5] = vh.y, c[6] = vh.z, c[7] = t1.x, c[8] = t1.y, c[9] = t1.z, c[10] = t2.x, c[11] = t2.y;
    c[12] = t2.z, c[13] = 0.5 * (1.0 + vh.z);
}

/* ggx_fpdf at a cached view, rearranged to two divisions and one square root (the model's form: five and
 * two): with h = vo + vi, s = h.x^2 + h.y^2, z = h.z^2, den = a^2 z + s,
 *   D / (4 vo.z) = [a^2 / (4 pi vo.z)] (s + z)^2 / den^2,
 *   1 + Lambda(vo) + Lambda(vi) = (1 + 2 Lambda(vo) + sqrt(1 + t)) / 2 with t = a^2 (vi.x^2 + vi.y^2) / vi.z^2
 *     (Lambda = (sqrt(1 + t) - 1) / 2; the sum has no cancellation), and
 *     sqrt(1 + t) = sqrt(vi.z^2 + a^2 (vi.x^2 + vi.y^2)) / vi.z,
 * so f cos = 2 dq vi.z / ((1 + 2 Lambda(vo)) vi.z + sqrt(vi.z^2 + a^2 (vi.x^2 + vi.y^2))) and
 * pdf = dq / (1 + Lambda(vo)), dq = D / (4 vo.z) (the model's values to rounding). */
static void ggx_fpdf_cached(double a2, const double *c, mf_vec3 vi, double *f, double *pdf)
{
    *f = *pdf = 0.0;
    if (!(vi.z > 0.0))
        return;
    double hx = c[0] + vi.x, hy = c[1] + vi.y, hz = c[2] + vi.z;
    double s2 = hx * hx + hy * hy, z2 = hz * hz;
    double den = a2 * z2 + s2, l2 = s2 + z2;
    double dq = c[14] * (l2 * l2) / (den * den);
    *f = 2.0 * dq * vi.z / (c[15] * vi.z + sqrt(vi.z * vi.z + a2 * (vi.x * vi.x + vi.y * vi.y)));
    if (hz > 0.0 && c[0] * hx + c[1] * hy + c[2] * hz > 0.0)
        *pdf = dq * c[16];
}

/* mf_sample_ggx_vndf at the cached view (the same operations), reflected: the texel-frame wi, and
 * whether the model's sampler would give it a positive density (wi.z > 0, vo.wm > 0, wm.z > 0). */
static mf_vec3 ggx_sample_cached(double alpha, const double *c, const double u[2], int *ok)
{
    double r = sqrt(u[0]);
    double phi = 2.0 * MF_PI * u[1];
    double p1 = r * cos(phi), p2 = r * sin(phi);
    double s = c[13];
    p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
    double pz = sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
    mf_vec3 nh = mf_vec3_add(mf_vec3_add(mf_vec3_scale(mf_vec3_make(c[7], c[8], c[9]), p1),
                                         mf_vec3_scale(mf_vec3_make(c[10], c[11], c[12]), p2)),
                             mf_vec3_scale(mf_vec3_make(c[4], c[5], c[6]), pz));
    mf_vec3 wm = mf_vec3_normalize(mf_vec3_make(alpha * nh.x, alpha * nh.y, fmax(0.0, nh.z)));
    mf_vec3 vo = mf_vec3_make(c[0], c[1], c[2]);
    mf_vec3 wi = mf_vec3_reflect(vo, wm);
    *ok = wi.z > 0.0 && mf_vec3_dot(vo, wm) > 0.0 && wm.z > 0.0;
    return wi;
}

/* Per view, per component: the texel-frame view and Lambda there (mix_set_view). */
static const double *view_cache(const mf_prefilter_mix *x, const mf_brdf_params *p, mf_vec3 wo)
{
    if (x->cache && x->cache_wo[0] == wo.x && x->cache_wo[1] == wo.y && x->cache_wo[2] == wo.z &&
        x->cache_a == p->alpha_x && p->alpha_x == p->alpha_y)
        return x->cache;
    return NULL;
}

/* f cos and pdf of the mixture at (wo, wi), wo.z > 0 and wi.z > 0 (one pass over the components). */
static void mix_eval_pdf(const mf_prefilter_mix *x, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi, double *f,
                         double *pdf)
{
    double sf = 0.0, sp = 0.0;
    if (x->kind == MF_PREFILTER_BASE_LAMBERT) {
        for (int j = 0; j < x->n; ++j) {
            const double *r = x->rot + 9 * j;
            double c = r[2] * wi.x + r[5] * wi.y + r[8] * wi.z; /* n(q) . wi */
            if (c > 0.0)
                sf += x->w[j] * c;
        }
        *f = *pdf = sf * MF_INV_PI;
        return;
    }
    const double *vc = x->kind == MF_PREFILTER_BASE_GGX ? view_cache(x, p, wo) : NULL;
    if (vc) {
        double a2 = p->alpha_x * p->alpha_x;
        for (int j = 0; j < x->n; ++j) {
            const double *r = x->rot + 9 * j, *c = vc + VC_N * j;
            double fj, pj;
            ggx_fpdf_cached(a2, c, rot_t(r, wi), &fj, &pj);
            sf += x->w[j] * fj;
            sp += x->w[j] * pj;
        }
    } else {
        for (int j = 0; j < x->n; ++j) {
            const double *r = x->rot + 9 * j;
            mf_vec3 vo = texel_view(r, wo), vi = rot_t(r, wi);
            sf += x->w[j] * x->base->eval_cos(x->base, p, vo, vi);
            sp += x->w[j] * x->base->pdf(x->base, p, vo, vi);
        }
    }
    *f = sf;
    *pdf = sp;
}

static double mix_eval_cos(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    if (isnan(wo.z) || isnan(wi.z) || !(p->alpha_x > 0.0))
        return NAN;
    if (!(wo.z > 0.0) || !(wi.z > 0.0))
        return 0.0;
    double f, pdf;
    mix_eval_pdf(mix_of(m), p, wo, wi, &f, &pdf);
    return f;
}

static double mix_pdf(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi)
{
    if (!(wo.z > 0.0) || !(wi.z > 0.0))
        return 0.0;
    double f, pdf;
    mix_eval_pdf(mix_of(m), p, wo, wi, &f, &pdf);
    return pdf;
}

/* The texel from u0 (the first j with u0 < cdf[j]); *v: u0 rescaled into [0, 1) inside its interval. */
static int mix_pick_texel(const mf_prefilter_mix *x, double u0, double *v)
{
    int lo = 0, hi = x->n - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (u0 < x->cdf[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    double c0 = lo > 0 ? x->cdf[lo - 1] : 0.0;
    *v = fmin(fmax((u0 - c0) / x->w[lo], 0.0), nextafter(1.0, 0.0));
    return lo;
}

/* The texel from u[0] and u[0] rescaled (mix_pick_texel), then the base sampler at the texel's view,
 * rotated to the geometric frame. */
static mf_vec3 mix_sample_texel(const mf_prefilter_mix *x, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                                double *base_pdf, const double *vc)
{
    double v[2] = {0.0, u[1]};
    int lo = mix_pick_texel(x, u[0], &v[0]);
    const double *r = x->rot + 9 * lo;
    if (x->kind == MF_PREFILTER_BASE_LAMBERT) { /* the cosine about n(q) (Malley) */
        double rr = sqrt(v[0]), ph = 2.0 * MF_PI * v[1];
        double z = sqrt(fmax(0.0, 1.0 - v[0]));
        *base_pdf = z * MF_INV_PI;
        return rot_apply(r, mf_vec3_make(rr * cos(ph), rr * sin(ph), z));
    }
    if (vc) { /* the cached view (GGX, mix_set_view): only the sign of the density is read */
        int ok;
        mf_vec3 wi_t = ggx_sample_cached(p->alpha_x, vc + VC_N * lo, v, &ok);
        *base_pdf = ok ? 1.0 : 0.0;
        return rot_apply(r, wi_t);
    }
    mf_vec3 wi_t = x->base->sample(x->base, p, texel_view(r, wo), v, base_pdf);
    return rot_apply(r, wi_t);
}

static mf_vec3 mix_sample(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, const double u[2], double *pdf)
{
    const mf_prefilter_mix *x = mix_of(m);
    *pdf = 0.0;
    if (!(wo.z > 0.0))
        return mf_vec3_make(0.0, 0.0, 1.0);
    double bp;
    mf_vec3 wi = mix_sample_texel(x, p, wo, u, &bp, x->kind == MF_PREFILTER_BASE_GGX ? view_cache(x, p, wo) : NULL);
    if (bp > 0.0 && wi.z > 0.0 && mf_vec3_isfinite(wi)) {
        double f;
        mix_eval_pdf(x, p, wo, wi, &f, pdf);
    }
    return wi;
}

/* mix_eval_pdf at the cached view (GGX) for cnt directions (components vx, vy, vz) into f, pdf:
 * ggx_fpdf_cached's operations in its order per direction and component, summed over the
 * components in their order (the same bits), two directions at a time in 2-wide vectors where the
 * compiler has them (GCC and Clang vector extensions; nothing is contracted); a lane whose texel
 * frame direction is below the horizon, or whose density condition fails, takes 0 as the scalar
 * rule does (its other values are computed and dropped). */
#if defined(__GNUC__) || defined(__clang__)
#define MIX_VEC2 1
typedef double mix_v2d __attribute__((vector_size(16)));
typedef long long mix_v2l __attribute__((vector_size(16)));
/* The square roots of a vector's lanes: one packed instruction (IEEE square roots are correctly
 * rounded, so a packed root has each lane's scalar bits; the argument is a sum of squares, >= 0 or
 * NaN, where both give the same NaN).  Elsewhere lane by lane. */
#if defined(__SSE2__)
#define mix_vsqrt2(v) __builtin_ia32_sqrtpd(v)
#else
static inline mix_v2d mix_vsqrt2(mix_v2d v)
{
    for (int k = 0; k < 2; ++k)
        v[k] = sqrt(v[k]);
    return v;
}
#endif
#endif
/* One definition for both widths: the vector loop W directions at a time in vectors VD (lanes
 * compared into VL), then the scalar rule for the rest. */
#define MIX_EVAL_PDF_BATCH_LANES(VD, VL, W, SQRTV)                                                          \
    for (; i + (W) <= cnt; i += (W)) {                                                                      \
        VD ax, ay, az;                                                                                      \
        memcpy(&ax, vx + i, sizeof ax);                                                                     \
        memcpy(&ay, vy + i, sizeof ay);                                                                     \
        memcpy(&az, vz + i, sizeof az);                                                                     \
        const VD tx = r[0] * ax + r[3] * ay + r[6] * az, ty = r[1] * ax + r[4] * ay + r[7] * az,           \
                 tz = r[2] * ax + r[5] * ay + r[8] * az; /* rot_t */                                        \
        const VD hx = c[0] + tx, hy = c[1] + ty, hz = c[2] + tz;                                            \
        const VD s2 = hx * hx + hy * hy, z2 = hz * hz;                                                      \
        const VD den = a2 * z2 + s2, l2 = s2 + z2;                                                          \
        const VD dq = c[14] * (l2 * l2) / (den * den);                                                      \
        const VD q = SQRTV(tz * tz + a2 * (tx * tx + ty * ty));                                             \
        const VD fj = 2.0 * dq * tz / (c[15] * tz + q);                                                     \
        const VD pj = dq * c[16];                                                                           \
        const VL up = tz > 0.0;                                                                             \
        const VL dens = up & (hz > 0.0) & ((c[0] * hx + c[1] * hy + c[2] * hz) > 0.0);                      \
        const VD fs = (VD)(up & (VL)fj), ps = (VD)(dens & (VL)pj); /* or +0 */                              \
        VD sf, sp;                                                                                          \
        memcpy(&sf, f + i, sizeof sf);                                                                      \
        memcpy(&sp, pdf + i, sizeof sp);                                                                    \
        sf += wj * fs;                                                                                      \
        sp += wj * ps;                                                                                      \
        memcpy(f + i, &sf, sizeof sf);                                                                      \
        memcpy(pdf + i, &sp, sizeof sp);                                                                    \
    }

#define MIX_EVAL_PDF_BATCH_DEF(NAME, LANES)                                                                 \
    static void NAME(const mf_prefilter_mix *x, double a2, const double *vc, int cnt, const double *vx,     \
                     const double *vy, const double *vz, double *f, double *pdf)                            \
    {                                                                                                       \
        for (int i = 0; i < cnt; ++i)                                                                       \
            f[i] = pdf[i] = 0.0;                                                                            \
        for (int j = 0; j < x->n; ++j) {                                                                    \
            const double *r = x->rot + 9 * j, *c = vc + VC_N * j, wj = x->w[j];                             \
            int i = 0;                                                                                      \
            LANES                                                                                           \
            for (; i < cnt; ++i) {                                                                          \
                double fj, pj;                                                                              \
                ggx_fpdf_cached(a2, c, rot_t(r, mf_vec3_make(vx[i], vy[i], vz[i])), &fj, &pj);              \
                f[i] += wj * fj;                                                                            \
                pdf[i] += wj * pj;                                                                          \
            }                                                                                               \
        }                                                                                                   \
    }

#ifdef MIX_VEC2
MIX_EVAL_PDF_BATCH_DEF(mix_eval_pdf_batch, MIX_EVAL_PDF_BATCH_LANES(mix_v2d, mix_v2l, 2, mix_vsqrt2))
#else
MIX_EVAL_PDF_BATCH_DEF(mix_eval_pdf_batch, )
#endif

/* mix_eval_pdf_batch four directions at a time, compiled for AVX2 (x86-64 with GCC or Clang; 4-wide
 * vectors of the same operations in the same order per lane: the same bits, nothing contracted, no
 * FMA), called where the CPU has AVX2 and mf_prefilter_mix_wide is set (mix_eval_pdf_batch_any).
 * Measured (bench_prefilter --size 8 --threads 1, profile samples): the mixture's sampling and
 * evaluation 6,251 -> 4,498 samples, the run 30,795 -> 27,625 (docs/prefilter_log.md, "Speed: cheaper
 * kernels, the same bits"). */
#if defined(MIX_VEC2) && defined(__x86_64__)
#define MIX_VEC4 1
typedef double mix_v4d __attribute__((vector_size(32)));
typedef long long mix_v4l __attribute__((vector_size(32)));
#define mix_vsqrt4(v) __builtin_ia32_sqrtpd256(v)
__attribute__((target("avx2"))) MIX_EVAL_PDF_BATCH_DEF(mix_eval_pdf_batch4, MIX_EVAL_PDF_BATCH_LANES(mix_v4d, mix_v4l, 4, mix_vsqrt4))
#endif

int mf_prefilter_mix_wide = 1;

int mf_prefilter_mix_wide_available(void)
{
#ifdef MIX_VEC4
    return __builtin_cpu_supports("avx2") ? 1 : 0;
#else
    return 0;
#endif
}

static void mix_eval_pdf_batch_any(const mf_prefilter_mix *x, double a2, const double *vc, int cnt, const double *vx,
                                   const double *vy, const double *vz, double *f, double *pdf)
{
#ifdef MIX_VEC4
    if (mf_prefilter_mix_wide && __builtin_cpu_supports("avx2")) {
        mix_eval_pdf_batch4(x, a2, vc, cnt, vx, vy, vz, f, pdf);
        return;
    }
#endif
    mix_eval_pdf_batch(x, a2, vc, cnt, vx, vy, vz, f, pdf);
}

/* The directions of mix_sample_weights' fused path are sampled and evaluated in chunks of this
 * many. */
#define MIX_CHUNK 64

/* mix_sample_texel at the cached view (GGX) for cnt <= MIX_CHUNK points u: the texel and the
 * angle's cosine and sine per direction, then ggx_sample_cached's operations (in its order, its
 * fmax calls kept) two directions at a time, each lane reading its own texel's cache; wi in the
 * geometric frame, ok[i] its sampler's positive-density test (the same bits: tested by
 * test_prefilter_mix_fast). */
#ifdef MIX_VEC2
static inline mix_v2d mix_sqrt2(mix_v2d a) { return mix_vsqrt2(a); } /* the same bits as lane by lane */
static inline mix_v2d mix_fmax02(mix_v2d a) { return (mix_v2d){fmax(0.0, a[0]), fmax(0.0, a[1])}; }
#endif
/* The cosines and sines of phi = 2 pi u[2 i + 1] (ggx_sample_cached's angle) for the points u:
 * the fits draw the same Sobol points for every entry, so each thread keeps the last points' values
 * and recomputes only where a point differs (compared bit for bit; the same function of the same
 * argument: the same bits). */
typedef struct {
    uint64_t *u1; /* the bits of u[2 i + 1] */
    double *cs, *sn;
    int cap;
} mix_angles;

static pthread_key_t g_mix_angles_key;
static pthread_once_t g_mix_angles_once = PTHREAD_ONCE_INIT;
static int g_mix_angles_ok;

static void mix_angles_free(void *p)
{
    mix_angles *a = p;
    if (a)
        free(a->u1), free(a->cs), free(a->sn);
    free(a);
}

static void mix_angles_key(void) { g_mix_angles_ok = pthread_key_create(&g_mix_angles_key, mix_angles_free) == 0; }

/* The thread's angles of u[0 .. 2 n - 1]; NULL if out of memory (the caller computes them). */
static const mix_angles *mix_angles_get(const double *u, int n)
{
    pthread_once(&g_mix_angles_once, mix_angles_key);
    if (!g_mix_angles_ok)
        return NULL;
    mix_angles *a = pthread_getspecific(g_mix_angles_key);
    if (!a || a->cap < n) {
        mix_angles_free(a);
        pthread_setspecific(g_mix_angles_key, NULL);
        a = calloc(1, sizeof *a);
        if (!a)
            return NULL;
        a->u1 = malloc(sizeof *a->u1 * (size_t)n);
        a->cs = malloc(sizeof *a->cs * (size_t)n);
        a->sn = malloc(sizeof *a->sn * (size_t)n);
        if (!a->u1 || !a->cs || !a->sn || pthread_setspecific(g_mix_angles_key, a) != 0) {
            mix_angles_free(a);
            return NULL;
        }
        a->cap = n;
        for (int i = 0; i < n; ++i) { /* no point cached: computed below */
            double phi = 2.0 * MF_PI * u[2 * i + 1];
            memcpy(&a->u1[i], &u[2 * i + 1], sizeof a->u1[i]);
            a->cs[i] = cos(phi);
            a->sn[i] = sin(phi);
        }
        return a;
    }
    for (int i = 0; i < n; ++i) {
        uint64_t b;
        memcpy(&b, &u[2 * i + 1], sizeof b);
        if (b != a->u1[i]) {
            double phi = 2.0 * MF_PI * u[2 * i + 1];
            a->u1[i] = b;
            a->cs[i] = cos(phi);
            a->sn[i] = sin(phi);
        }
    }
    return a;
}

/* ang: the angles' cosines and sines of these cnt points (mix_angles_get), or NULL. */
static void mix_sample_chunk(const mf_prefilter_mix *x, double alpha, const double *vc, const double *u, int cnt,
                             const double *ang_cs, const double *ang_sn, mf_vec3 *wi, int *ok)
{
    int lo_[MIX_CHUNK];
    double v0[MIX_CHUNK], cs_[MIX_CHUNK], sn_[MIX_CHUNK];
    const double *cs = ang_cs ? ang_cs : cs_, *sn = ang_sn ? ang_sn : sn_;
    for (int i = 0; i < cnt; ++i) { /* the texel and u[0] rescaled, as mix_sample_texel (mix_pick_texel) */
        const double *ui = u + 2 * i;
        lo_[i] = mix_pick_texel(x, ui[0], &v0[i]);
        if (!ang_cs) {
            double phi = 2.0 * MF_PI * ui[1];
            cs_[i] = cos(phi);
            sn_[i] = sin(phi);
        }
    }
    int i = 0;
#ifdef MIX_VEC2
    for (; i + 2 <= cnt; i += 2) {
        const double *ca = vc + VC_N * lo_[i], *cb = vc + VC_N * lo_[i + 1];
#define MIX_C(q) ((mix_v2d){ca[q], cb[q]})
        mix_v2d r = mix_sqrt2((mix_v2d){v0[i], v0[i + 1]});
        mix_v2d p1 = r * (mix_v2d){cs[i], cs[i + 1]}, p2 = r * (mix_v2d){sn[i], sn[i + 1]};
        mix_v2d s = MIX_C(13);
        p2 = (1.0 - s) * mix_sqrt2(mix_fmax02(1.0 - p1 * p1)) + s * p2;
        mix_v2d pz = mix_sqrt2(mix_fmax02(1.0 - p1 * p1 - p2 * p2));
        mix_v2d nx = MIX_C(7) * p1 + MIX_C(10) * p2 + MIX_C(4) * pz;
        mix_v2d ny = MIX_C(8) * p1 + MIX_C(11) * p2 + MIX_C(5) * pz;
        mix_v2d nz = MIX_C(9) * p1 + MIX_C(12) * p2 + MIX_C(6) * pz;
        mix_v2d mx = alpha * nx, my = alpha * ny, mz = mix_fmax02(nz);
        mix_v2d inv = 1.0 / mix_sqrt2(mx * mx + my * my + mz * mz);
        mx = mx * inv, my = my * inv, mz = mz * inv;
        mix_v2d ox = MIX_C(0), oy = MIX_C(1), oz = MIX_C(2);
        mix_v2d d = ox * mx + oy * my + oz * mz;
        mix_v2d k = 2.0 * d;
        mix_v2d wx = mx * k - ox, wy = my * k - oy, wz = mz * k - oz;
#undef MIX_C
        for (int q = 0; q < 2; ++q) {
            ok[i + q] = wz[q] > 0.0 && d[q] > 0.0 && mz[q] > 0.0;
            wi[i + q] = rot_apply(x->rot + 9 * lo_[i + q], mf_vec3_make(wx[q], wy[q], wz[q]));
        }
    }
#endif
    for (; i < cnt; ++i) {
        double v[2] = {v0[i], u[2 * i + 1]};
        wi[i] = rot_apply(x->rot + 9 * lo_[i], ggx_sample_cached(alpha, vc + VC_N * lo_[i], v, &ok[i]));
    }
}


static void mix_sample_weights(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                               mf_vec3 *wi, double *pdf, double *w)
{
    const mf_prefilter_mix *x = mix_of(m);
    const double *vc = x->kind == MF_PREFILTER_BASE_GGX ? view_cache(x, p, wo) : NULL;
    if (vc && wo.z > 0.0) { /* the cached view: sample a chunk, then evaluate the mixture over it */
        const double a2 = p->alpha_x * p->alpha_x;
        const mix_angles *ang = mix_angles_get(u, n);
        for (int i0 = 0; i0 < n; i0 += MIX_CHUNK) {
            int ix[MIX_CHUNK], cnt = 0, i1 = i0 + MIX_CHUNK < n ? i0 + MIX_CHUNK : n;
            double vx[MIX_CHUNK], vy[MIX_CHUNK], vz[MIX_CHUNK], f[MIX_CHUNK], pd[MIX_CHUNK];
            int ok[MIX_CHUNK];
            mix_sample_chunk(x, p->alpha_x, vc, u + 2 * i0, i1 - i0, ang ? ang->cs + i0 : NULL, ang ? ang->sn + i0 : NULL,
                             wi + i0, ok);
            for (int i = i0; i < i1; ++i) {
                pdf[i] = 0.0;
                w[i] = 0.0;
                if (ok[i - i0] && wi[i].z > 0.0 && mf_vec3_isfinite(wi[i])) {
                    ix[cnt] = i;
                    vx[cnt] = wi[i].x, vy[cnt] = wi[i].y, vz[cnt] = wi[i].z;
                    ++cnt;
                }
            }
            mix_eval_pdf_batch_any(x, a2, vc, cnt, vx, vy, vz, f, pd);
            for (int q = 0; q < cnt; ++q) {
                int i = ix[q];
                pdf[i] = pd[q];
                if (pdf[i] > 0.0)
                    w[i] = f[q] / pdf[i];
            }
        }
        return;
    }
    if (x->kind == MF_PREFILTER_BASE_LAMBERT && wo.z > 0.0) {
        /* mix_sample_texel's Lambert branch and mix_eval_pdf with the same operations (the same bits),
         * the cosines and sines of 2 pi u[1] from the thread's angle cache (mix_angles_get: the GGX
         * path's; they were 9 % of the diffuse table's CPU, bench_prefilter --size 32 --base lambert) */
        const mix_angles *ang = mix_angles_get(u, n);
        for (int i = 0; i < n; ++i) {
            double v0;
            const double *r = x->rot + 9 * mix_pick_texel(x, u[2 * i], &v0);
            double rr = sqrt(v0), z = sqrt(fmax(0.0, 1.0 - v0)), cs, sn;
            if (ang)
                cs = ang->cs[i], sn = ang->sn[i];
            else {
                double ph = 2.0 * MF_PI * u[2 * i + 1];
                cs = cos(ph), sn = sin(ph);
            }
            double bp = z * MF_INV_PI;
            wi[i] = rot_apply(r, mf_vec3_make(rr * cs, rr * sn, z));
            pdf[i] = 0.0;
            w[i] = 0.0;
            if (bp > 0.0 && wi[i].z > 0.0 && mf_vec3_isfinite(wi[i])) {
                double f;
                mix_eval_pdf(x, p, wo, wi[i], &f, &pdf[i]);
                if (pdf[i] > 0.0)
                    w[i] = f / pdf[i];
            }
        }
        return;
    }
    for (int i = 0; i < n; ++i) {
        pdf[i] = 0.0;
        w[i] = 0.0;
        if (!(wo.z > 0.0)) {
            wi[i] = mf_vec3_make(0.0, 0.0, 1.0);
            continue;
        }
        double bp;
        wi[i] = mix_sample_texel(x, p, wo, u + 2 * i, &bp, vc);
        if (bp > 0.0 && wi[i].z > 0.0 && mf_vec3_isfinite(wi[i])) {
            double f;
            mix_eval_pdf(x, p, wo, wi[i], &f, &pdf[i]);
            if (pdf[i] > 0.0)
                w[i] = f / pdf[i];
        }
    }
}

/* The minimal rotation taking z to the unit n (n.z > -1): R = I + [k]x + [k]x^2 / (1 + n.z),
 * k = z x n = (-n.y, n.x, 0). */
static void min_rotation(const double *n, double *r)
{
    double kx = -n[1], ky = n[0], c = 1.0 / (1.0 + n[2]);
    r[0] = 1.0 - ky * ky * c, r[1] = kx * ky * c, r[2] = ky;
    r[3] = kx * ky * c, r[4] = 1.0 - kx * kx * c, r[5] = -kx;
    r[6] = -ky, r[7] = kx, r[8] = n[2];
}

/* The mixture of `count` unit normals with weights wt (NULL: 1/count each; else positive, summing
 * to 1), bitwise equal normals merged. */
static mf_status mix_build(mf_prefilter_mix *m, const mf_brdf_model *base, const double *normals, const double *wt,
                           int count)
{
    if (!m)
        return MF_ERR_DOMAIN;
    memset(m, 0, sizeof *m);
    if (!base || !base->eval_cos || !normals || count < 1)
        return MF_ERR_DOMAIN;
    int kind = !strcmp(base->name, "ggx") ? MF_PREFILTER_BASE_GGX
               : !strcmp(base->name, "lambert") ? MF_PREFILTER_BASE_LAMBERT : MF_PREFILTER_BASE_OTHER;
    if (kind != MF_PREFILTER_BASE_LAMBERT && (!base->sample || !base->pdf))
        return MF_ERR_DOMAIN;
    for (int i = 0; i < count; ++i)
        if (!(normals[3 * i + 2] > 0.0) || !isfinite(normals[3 * i]) || !isfinite(normals[3 * i + 1]) ||
            (wt && !(wt[i] > 0.0)))
            return MF_ERR_DOMAIN;
    m->rot = malloc(sizeof(double) * 9 * (size_t)count);
    m->w = malloc(sizeof(double) * (size_t)count);
    m->cdf = malloc(sizeof(double) * (size_t)count);
    double *acc_w = calloc((size_t)count, sizeof *acc_w);
    int *first = malloc(sizeof(int) * (size_t)count);
    if (!m->rot || !m->w || !m->cdf || !acc_w || !first) {
        free(acc_w), free(first);
        mf_prefilter_mix_free(m);
        return MF_ERR_ALLOC;
    }
    /* merge bitwise equal normals (quadratic in the components: footprints are clustered to at
     * most MF_PREFILTER_CLUSTER_MAX components before they get here, see fit_footprint) */
    int n = 0;
    for (int i = 0; i < count; ++i) {
        int j = 0;
        while (j < n && memcmp(normals + 3 * first[j], normals + 3 * i, 3 * sizeof(double)) != 0)
            ++j;
        if (j == n)
            first[n++] = i;
        acc_w[j] += wt ? wt[i] : 1.0;
    }
    double acc = 0.0, tot = 0.0;
    for (int j = 0; j < n; ++j)
        tot += acc_w[j];
    for (int j = 0; j < n; ++j) {
        min_rotation(normals + 3 * first[j], m->rot + 9 * j);
        m->w[j] = acc_w[j] / tot;
        acc += acc_w[j];
        m->cdf[j] = acc / tot;
    }
    m->cdf[n - 1] = 1.0;
    free(acc_w), free(first);
    m->n = n;
    m->base = base;
    m->kind = kind;
    m->model.name = "prefilter-mix";
    m->model.description = "effective BRDF of a normal-map footprint (Nahmias 2022, Eq. 2.36)";
    m->model.flags = MF_MODEL_ANISOTROPIC;
    m->model.eval_cos = mix_eval_cos;
    m->model.sample = mix_sample;
    m->model.pdf = mix_pdf;
    m->model.sample_weights = mix_sample_weights;
    return MF_OK;
}

mf_status mf_prefilter_mix_init(mf_prefilter_mix *m, const mf_brdf_model *base, const double *normals, int count)
{
    return mix_build(m, base, normals, NULL, count);
}

/* The fits' per-view cache (GGX only): the texel-frame view of every component and Lambda there,
 * valid while eval/pdf are called with this wo and an isotropic alpha (checked per call). */
static mf_status mix_set_view(mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo)
{
    if (m->kind != MF_PREFILTER_BASE_GGX || p->alpha_x != p->alpha_y)
        return MF_OK;
    if (!m->cache && !(m->cache = malloc(sizeof(double) * VC_N * (size_t)m->n)))
        return MF_ERR_ALLOC;
    for (int j = 0; j < m->n; ++j)
        view_cache_fill(p->alpha_x, texel_view(m->rot + 9 * j, wo), m->cache + VC_N * j);
    m->cache_wo[0] = wo.x, m->cache_wo[1] = wo.y, m->cache_wo[2] = wo.z;
    m->cache_a = p->alpha_x;
    return MF_OK;
}

mf_status mf_prefilter_mix_set_view(mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo)
{
    return mix_set_view(m, p, wo);
}

void mf_prefilter_mix_free(mf_prefilter_mix *m)
{
    if (!m)
        return;
    free(m->rot), free(m->w), free(m->cdf), free(m->cache);
    m->rot = m->w = m->cdf = m->cache = NULL;
    m->n = 0;
}

double mf_prefilter_quad_mis_sample(const mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo,
                                    const mf_prefilter_quad *q, int strategy, const double u[2], mf_vec3 *wi,
                                    double *fcos)
{
    *fcos = 0.0;
    *wi = mf_vec3_make(0.0, 0.0, 1.0);
    if (!(wo.z > 0.0) || !(q->h > 0.0))
        return 0.0;
    const mf_vec3 c = q->c, e1 = q->e1, e2 = q->e2, n = mf_vec3_cross(e1, e2);
    const double h = q->h, area = 4.0 * h * h;
    double pl = 0.0; /* p_L(wi) per steradian, 0 off the light */
    mf_vec3 d;
    if (strategy == 0) {
        double a = (2.0 * u[0] - 1.0) * h, b = (2.0 * u[1] - 1.0) * h;
        mf_vec3 x = mf_vec3_make(c.x + a * e1.x + b * e2.x, c.y + a * e1.y + b * e2.y, c.z + a * e1.z + b * e2.z);
        double r2 = x.x * x.x + x.y * x.y + x.z * x.z, rl = sqrt(r2);
        d = mf_vec3_make(x.x / rl, x.y / rl, x.z / rl);
        pl = r2 / (area * fabs(d.x * n.x + d.y * n.y + d.z * n.z));
    } else {
        double bp;
        d = mix_sample_texel(m, p, wo, u, &bp, m->kind == MF_PREFILTER_BASE_GGX ? view_cache(m, p, wo) : NULL);
        if (!(bp > 0.0) || !mf_vec3_isfinite(d))
            return 0.0;
        double dn = d.x * n.x + d.y * n.y + d.z * n.z; /* the ray meets the light's plane at t = (c . n) / dn */
        double t = (c.x * n.x + c.y * n.y + c.z * n.z) / dn;
        if (!(t > 0.0) || !isfinite(t))
            return 0.0;
        mf_vec3 x = mf_vec3_make(t * d.x - c.x, t * d.y - c.y, t * d.z - c.z);
        double a = x.x * e1.x + x.y * e1.y + x.z * e1.z, b = x.x * e2.x + x.y * e2.y + x.z * e2.z;
        if (!(fabs(a) <= h && fabs(b) <= h))
            return 0.0;
        pl = t * t / (area * fabs(dn));
    }
    *wi = d;
    if (!(d.z > 0.0) || !(pl > 0.0) || !isfinite(pl))
        return 0.0;
    double f, pm;
    mix_eval_pdf(m, p, wo, d, &f, &pm);
    *fcos = f;
    return 1.0 / (0.5 * pl + 0.5 * pm);
}

void mf_prefilter_quad_mis_mean(const double n[2], const double s1[2], const double s2[2], double *mean, double *se)
{
    double nt = n[0] + n[1], var = 0.0;
    *mean = nt > 0.0 ? (s1[0] + s1[1]) / nt : 0.0;
    for (int k = 0; k < 2; ++k)
        if (n[k] > 1.0) {
            double mk = s1[k] / n[k], vk = (s2[k] / n[k] - mk * mk) * n[k] / (n[k] - 1.0);
            var += n[k] * (vk > 0.0 ? vk : 0.0);
        }
    *se = nt > 0.0 ? sqrt(var) / nt : 0.0;
}

mf_status mf_prefilter_mix_albedo(const mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo, mf_result *out)
{
    if (!m || !p || !out || !(wo.z > 0.0))
        return MF_ERR_DOMAIN;
    double val = 0.0, err = 0.0;
    if (m->kind == MF_PREFILTER_BASE_LAMBERT) {
        /* the clamped cosine about n(q) over the geometric hemisphere: (1 + n(q).z) / 2 (the view
         * factor of the sky hemisphere from a plane tilted by acos n.z), independent of wo */
        for (int j = 0; j < m->n; ++j)
            val += m->w[j] * 0.5 * (1.0 + m->rot[9 * j + 8]);
        out->val = val;
        out->err = 0.0;
        return MF_OK;
    }
    for (int j = 0; j < m->n; ++j) {
        mf_prefilter_mix one = *m; /* the one-texel mixture of component j */
        one.n = 1;
        one.cache = NULL;
        double c4[VC_N];
        if (m->kind == MF_PREFILTER_BASE_GGX && p->alpha_x == p->alpha_y) { /* the fused evaluation */
            view_cache_fill(p->alpha_x, texel_view(m->rot + 9 * j, wo), c4);
            one.cache = c4;
            one.cache_wo[0] = wo.x, one.cache_wo[1] = wo.y, one.cache_wo[2] = wo.z;
            one.cache_a = p->alpha_x;
        }
        one.rot = m->rot + 9 * j;
        double w1 = 1.0, c1 = 1.0;
        one.w = &w1;
        one.cdf = &c1;
        mf_result r;
        mf_status st = mf_model_albedo(&one.model, p, wo, MF_PREFILTER_ALBEDO_N, &r);
        if (st != MF_OK)
            return st;
        val += m->w[j] * r.val;
        err += m->w[j] * r.err;
    }
    out->val = val;
    out->err = err;
    return MF_OK;
}

/* ---- the one-texel GGX albedo: a fused rule and a table over its three parameters ------------- */

/* The one-texel albedo depends on the texel-frame view v (after the below-horizon clamp of
 * texel_view) and the geometric normal in the texel frame, g = R^T z = (-n.x, -n.y, n.z), only
 * through three numbers (it is invariant under a rotation of both about the texel normal, and
 * even in their relative azimuth): theta_v = acos v.z, the tilt tau = acos n.z and the azimuth
 * delta in [0, pi] between the horizontal parts of v and g.  albedo_rule integrates exactly what
 * mf_prefilter_mix_albedo integrates for a one-texel mixture -- mf_model_albedo's product rule
 * (composite 8-point Gauss-Legendre panels, the first axis graded by u0 = 1 - (1 - t)^3) over the
 * visible-normal sampler [Heitz 2018, Listing 1], weight f cos / pdf = G2 / G1 =
 * (1 + Lambda(v)) / (1 + Lambda(v) + Lambda(wi)) where wi is above both horizons (texel:
 * wi.z > 0, geometric: g.wi > 0), 0 elsewhere -- fused (no model calls, the view's frame
 * hoisted), at MF_PREFILTER_ALBEDO_N and half of it (the error estimate).  The table holds it at
 * ALB_NT x ALB_NU x ALB_ND nodes (theta_v uniform on [0, acos MF_PREFILTER_COS_MIN], tau uniform
 * on [0, pi/2], delta uniform on [0, pi]); a lookup interpolates it by Catmull-Rom splines along
 * the three axes (ghost nodes: the reflections theta -> -theta, tau -> -tau and delta -> -delta,
 * 2 pi - delta are exact nodes; beyond theta_max and pi/2 quadratic extrapolation).  Nodes are
 * computed on first use, one tau slab (all theta x delta nodes of one tau) at a time, and kept for
 * the process (per alpha): a slab's values are a function of its node coordinates only, so the
 * results do not depend on the order, the threads or the tiling.  Accuracy: see
 * MF_PREFILTER_ALBEDO_TABLE in mf_prefilter.h. */
static const double alb_gl8_x[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                                    0.1834346424956498,  0.5255324099163290,  0.7966664774136267,  0.9602898564975363};
static const double alb_gl8_w[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                                    0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

static double albedo_rule_panels(double alpha, mf_vec3 v, mf_vec3 g, int panels)
{
    double a2 = alpha * alpha;
    double lo = ggx_lambda_iso(a2, v), num = 1.0 + lo;
    mf_vec3 vh = mf_vec3_normalize(mf_vec3_make(alpha * v.x, alpha * v.y, v.z));
    double lensq = vh.x * vh.x + vh.y * vh.y;
    mf_vec3 t1 = lensq > 0.0 ? mf_vec3_scale(mf_vec3_make(-vh.y, vh.x, 0.0), 1.0 / sqrt(lensq))
                             : mf_vec3_make(1.0, 0.0, 0.0);
    mf_vec3 t2 = mf_vec3_cross(vh, t1);
    double s = 0.5 * (1.0 + vh.z), sum = 0.0;
    double cph[8 * 64], sph[8 * 64], u1w[8 * 64];
    int row = 8 * panels;
    for (int q = 0; q < row; ++q) {
        int pj = q / 8, jj = q % 8;
        double u1 = (pj + 0.5 * (alb_gl8_x[jj] + 1.0)) / panels;
        cph[q] = cos(2.0 * MF_PI * u1), sph[q] = sin(2.0 * MF_PI * u1);
        u1w[q] = alb_gl8_w[jj];
    }
    for (int pi = 0; pi < panels; ++pi)
        for (int i = 0; i < 8; ++i) {
            double tt = (pi + 0.5 * (alb_gl8_x[i] + 1.0)) / panels, om = 1.0 - tt;
            double u0 = 1.0 - om * om * om, rr = sqrt(u0);
            double wrow = 0.25 * alb_gl8_w[i] / ((double)panels * panels) * 3.0 * om * om, srow = 0.0;
            for (int q = 0; q < row; ++q) {
                double p1 = rr * cph[q], p2 = rr * sph[q];
                p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
                double pz = sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
                mf_vec3 nh = mf_vec3_make(t1.x * p1 + t2.x * p2 + vh.x * pz, t1.y * p1 + t2.y * p2 + vh.y * pz,
                                          t1.z * p1 + t2.z * p2 + vh.z * pz);
                mf_vec3 wm = mf_vec3_normalize(mf_vec3_make(alpha * nh.x, alpha * nh.y, fmax(0.0, nh.z)));
                double vm = mf_vec3_dot(v, wm);
                if (!(vm > 0.0) || !(wm.z > 0.0))
                    continue;
                mf_vec3 wi = mf_vec3_sub(mf_vec3_scale(wm, 2.0 * vm), v);
                if (!(wi.z > 0.0) || !(mf_vec3_dot(g, wi) > 0.0))
                    continue;
                srow += u1w[q] * (num / (num + ggx_lambda_iso(a2, wi)));
            }
            sum += wrow * srow;
        }
    return sum;
}

/* The one-texel albedo (value, error estimate |Q(n) - Q(n / 2)|) at texel-frame view v and
 * texel-frame geometric normal g. */
static void albedo_rule(double alpha, mf_vec3 v, mf_vec3 g, double *val, double *err)
{
    double a1 = albedo_rule_panels(alpha, v, g, MF_PREFILTER_ALBEDO_N / 8);
    double a2 = albedo_rule_panels(alpha, v, g, MF_PREFILTER_ALBEDO_N / 16);
    *val = a1;
    *err = fabs(a1 - a2);
}

#define ALB_NT 49
#define ALB_NU 33
#define ALB_ND 17

typedef struct alb_table {
    double alpha;
    double *val, *err;   /* [u][t][d] */
    int ready[ALB_NU];   /* slab u computed (read and written with atomics) */
    struct alb_table *next;
} alb_table;

static pthread_mutex_t g_alb_lock = PTHREAD_MUTEX_INITIALIZER;
static alb_table *g_alb_tables;

static double alb_theta_max(void) { return acos(MF_PREFILTER_COS_MIN); }

static void alb_fill_slab(alb_table *t, int u)
{
    double tau = u * (0.5 * MF_PI) / (ALB_NU - 1);
    mf_vec3 g = mf_vec3_make(sin(tau), 0.0, cos(tau));
    for (int it = 0; it < ALB_NT; ++it) {
        double th = it * alb_theta_max() / (ALB_NT - 1), st = sin(th), ct = cos(th);
        for (int d = 0; d < ALB_ND; ++d) {
            double de = d * MF_PI / (ALB_ND - 1);
            mf_vec3 v = mf_vec3_make(st * cos(de), st * sin(de), ct);
            size_t k = ((size_t)u * ALB_NT + it) * ALB_ND + d;
            albedo_rule(t->alpha, v, g, &t->val[k], &t->err[k]);
        }
    }
}

/* The table of alpha, its slabs u0..u1 computed (NULL: out of memory). */
static alb_table *alb_get(double alpha, int u0, int u1)
{
    pthread_mutex_lock(&g_alb_lock);
    alb_table *t = g_alb_tables;
    while (t && t->alpha != alpha)
        t = t->next;
    if (!t && (t = calloc(1, sizeof *t))) {
        size_t n = (size_t)ALB_NU * ALB_NT * ALB_ND;
        t->val = malloc(sizeof(double) * n);
        t->err = malloc(sizeof(double) * n);
        if (!t->val || !t->err) {
            free(t->val), free(t->err), free(t);
            t = NULL;
        } else {
            t->alpha = alpha;
            t->next = g_alb_tables;
            g_alb_tables = t;
        }
    }
    pthread_mutex_unlock(&g_alb_lock);
    if (!t)
        return NULL;
    for (int u = u0; u <= u1; ++u)
        if (!__atomic_load_n(&t->ready[u], __ATOMIC_ACQUIRE)) {
            pthread_mutex_lock(&g_alb_lock);
            if (!t->ready[u]) {
                alb_fill_slab(t, u);
                __atomic_store_n(&t->ready[u], 1, __ATOMIC_RELEASE);
            }
            pthread_mutex_unlock(&g_alb_lock);
        }
    return t;
}

/* Catmull-Rom weights at fraction f. */
static void cr_weights(double f, double w[4])
{
    double f2 = f * f, f3 = f2 * f;
    w[0] = 0.5 * (-f3 + 2.0 * f2 - f);
    w[1] = 0.5 * (3.0 * f3 - 5.0 * f2 + 2.0);
    w[2] = 0.5 * (-3.0 * f3 + 4.0 * f2 + f);
    w[3] = 0.5 * (f3 - f2);
}

/* Node (u, t, d) with the ghost rules (u, t in -1..N, d in -1..ND). */
static double alb_node(const double *a, int u, int t, int d)
{
    if (d < 0)
        d = -d;
    if (d > ALB_ND - 1)
        d = 2 * (ALB_ND - 1) - d;
    if (u < 0) /* tau -> -tau: g turned by pi, delta -> pi - delta */
        return alb_node(a, -u, t, ALB_ND - 1 - d);
    if (t < 0) /* theta -> -theta: v turned by pi */
        return alb_node(a, u, -t, ALB_ND - 1 - d);
    if (u > ALB_NU - 1)
        return 3.0 * alb_node(a, ALB_NU - 1, t, d) - 3.0 * alb_node(a, ALB_NU - 2, t, d) + alb_node(a, ALB_NU - 3, t, d);
    if (t > ALB_NT - 1)
        return 3.0 * alb_node(a, u, ALB_NT - 1, d) - 3.0 * alb_node(a, u, ALB_NT - 2, d) + alb_node(a, u, ALB_NT - 3, d);
    return a[((size_t)u * ALB_NT + t) * ALB_ND + d];
}

static void alb_cell(double x, double h, int n, int *i, double *f)
{
    double q = x / h;
    int k = (int)floor(q);
    if (k < 0)
        k = 0;
    if (k > n - 2)
        k = n - 2;
    *i = k;
    *f = fmin(fmax(q - k, 0.0), 1.0);
}

/* The one-texel albedo of the unit normal n (n.z > 0) at the geometric view wo (wo.z > 0) through
 * the table: value and error (the rule's estimate at the nodes, the largest of the 8 about the
 * point, plus |tricubic - trilinear| as the interpolation's). */
static mf_status texel_albedo_table(double alpha, const double *n, const double *r, mf_vec3 wo, double *val,
                                    double *err)
{
    mf_vec3 v = texel_view(r, wo);
    double gx = -n[0], gy = -n[1], gh = sqrt(gx * gx + gy * gy), vh = sqrt(v.x * v.x + v.y * v.y);
    double tau = atan2(gh, n[2]), th = atan2(vh, v.z);
    double de = gh > 0.0 && vh > 0.0 ? atan2(fabs(v.x * gy - v.y * gx), v.x * gx + v.y * gy) : 0.0;
    int iu, it, id;
    double fu, ft, fd;
    alb_cell(tau, 0.5 * MF_PI / (ALB_NU - 1), ALB_NU, &iu, &fu);
    alb_cell(th, alb_theta_max() / (ALB_NT - 1), ALB_NT, &it, &ft);
    alb_cell(de, MF_PI / (ALB_ND - 1), ALB_ND, &id, &fd);
    int u0 = iu - 1 < 0 ? 0 : iu - 1, u1 = iu + 2 > ALB_NU - 1 ? ALB_NU - 1 : iu + 2;
    if (iu == 0) /* the ghost u = -1 reads slab 1 */
        u1 = u1 > 1 ? u1 : 1;
    if (iu + 2 > ALB_NU - 1) /* the extrapolated ghost reads the last three */
        u0 = ALB_NU - 3 < u0 ? ALB_NU - 3 : u0;
    alb_table *t = alb_get(alpha, u0, u1);
    if (!t)
        return MF_ERR_ALLOC;
    double wu[4], wt[4], wd[4];
    cr_weights(fu, wu), cr_weights(ft, wt), cr_weights(fd, wd);
    double s = 0.0;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
            double sd = 0.0;
            for (int c = 0; c < 4; ++c)
                sd += wd[c] * alb_node(t->val, iu - 1 + a, it - 1 + b, id - 1 + c);
            s += wu[a] * wt[b] * sd;
        }
    double lin = 0.0, e = 0.0;
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c) {
                double w = (a ? fu : 1.0 - fu) * (b ? ft : 1.0 - ft) * (c ? fd : 1.0 - fd);
                lin += w * alb_node(t->val, iu + a, it + b, id + c);
                e = fmax(e, alb_node(t->err, iu + a, it + b, id + c));
            }
    *val = s;
    *err = e + fabs(s - lin);
    return MF_OK;
}

mf_status mf_prefilter_texel_albedo(double alpha, const double n[3], mf_vec3 wo, int direct, mf_result *out)
{
    if (!n || !out || !(alpha > 0.0 && alpha <= 1.0) || !(wo.z > 0.0) || !(n[2] > 0.0))
        return MF_ERR_DOMAIN;
    double r[9];
    min_rotation(n, r);
    if (direct) {
        mf_vec3 v = texel_view(r, wo);
        albedo_rule(alpha, v, mf_vec3_make(-n[0], -n[1], n[2]), &out->val, &out->err);
        return MF_OK;
    }
    return texel_albedo_table(alpha, n, r, wo, &out->val, &out->err);
}

/* ---- the levels ------------------------------------------------------------------------------- */

/* level-1 directions: samples >> 2 for GGX (see level1_samples) */
#define MF_PREFILTER_LEVEL1_SHIFT 2

void mf_prefilter_options_default(mf_prefilter_options *o)
{
    memset(o, 0, sizeof *o);
    o->base = MF_PREFILTER_BASE_GGX;
    o->alpha = 0.1;
    o->n_theta = 8;
    o->n_phi = 16;
    o->threads = 1;
    o->samples = 4096;
    o->max_iterations = 100;
    o->seed = 1;
    o->cluster_cell = MF_PREFILTER_CLUSTER_CELL;
    o->keep_albedo = 0;
    o->level1_shift = MF_PREFILTER_LEVEL1_SHIFT;
    o->reuse = 1;
}

void mf_prefilter_options_default_diffuse(mf_prefilter_options *o)
{
    mf_prefilter_options_default(o);
    o->base = MF_PREFILTER_BASE_LAMBERT;
    o->n_theta = 2;
    o->n_phi = 4;
    /* 4096 directions at level 1 too: 1024 (shift 2) made the diffuse level-1 MSE of a 32 x 32 bump
     * map 17 % worse, 2048 (shift 1) 2.2 % (prefilter-eval; docs/prefilter.md, "Diffuse table") */
    o->level1_shift = 0;
}

double mf_prefilter_theta(const mf_prefilter_options *o, int i) { return i / (double)(o->n_theta - 1) * MF_PREFILTER_THETA_MAX; }
double mf_prefilter_phi(const mf_prefilter_options *o, int j) { return 2.0 * MF_PI * j / o->n_phi; }

void mf_prefilter_levels_free(mf_prefilter_level *levels, int nlevels)
{
    if (!levels)
        return;
    for (int l = 0; l < nlevels; ++l)
        free(levels[l].m), free(levels[l].magnitude), free(levels[l].albedo);
    free(levels);
}

/* options.reuse: one footprint's stored entries as its fits produced them (what store was given), so that
 * an identical footprint stores the same bits without fitting */
typedef struct {
    double m[9], lobe[MF_LTCFIT_ANISO_NPARAMS], residual;
    int converged, iterations;
} memo_entry;

typedef struct memo_node {
    struct memo_node *next;
    uint64_t hash;
    size_t nkey;      /* doubles in key */
    double *key;      /* the fit's inputs, bit for bit (memo_key) */
    memo_entry *ent;  /* per view */
} memo_node;

#define MEMO_BUCKETS 4096

typedef struct {
    const double *normals;
    int width, height, nlevels;
    const mf_prefilter_options *o;
    const mf_brdf_model *base;
    mf_prefilter_level *levels;
    double **lobes; /* per level: the lobe-frame parameters of every entry (the children's starts) */
    /* albedo cache: per level-0 texel and view, the one-texel albedo and its error, interleaved
     * (alb[2 (t nv + v)], alb[2 (t nv + v) + 1]) */
    double *alb;
    double **lalb; /* per level l >= 1 (lalb[l - 1]): the footprints' albedos, the same layout */
    int *uniq;    /* per texel: the index of the first texel with its (bitwise) normal */
    int job_kind; /* 0: albedo cache over texels, 1: fits over the footprints of one level */
    int level;    /* job_kind 1 */
    long next, total;
    mf_status status;
    char *msg;
    size_t msg_size;
    pthread_mutex_t lock;
    /* options.reuse: the fitted footprints by their inputs (NULL: off), their bytes, under memo_lock */
    memo_node **memo;
    size_t memo_bytes;
    pthread_mutex_t memo_lock;
} pjob;

static void set_error(pjob *j, mf_status st, const char *text)
{
    pthread_mutex_lock(&j->lock);
    if (j->status == MF_OK) {
        j->status = st;
        if (j->msg && j->msg_size)
            snprintf(j->msg, j->msg_size, "%s", text);
    }
    pthread_mutex_unlock(&j->lock);
}

static mf_vec3 view_dir(double theta, double phi)
{
    return mf_vec3_make(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

static mf_brdf_params base_params(const mf_prefilter_options *o)
{
    return mf_brdf_params_iso(o->base == MF_PREFILTER_BASE_LAMBERT ? 1.0 : o->alpha);
}

/* The one-texel albedos of the unit normal n at every view: out[2 v], out[2 v + 1] the albedo and its
 * error estimate (v = i_theta n_phi + i_phi). */
static mf_status one_texel_albedo(const mf_prefilter_options *o, const mf_brdf_model *base, const double *n, double *out)
{
    if (o->base == MF_PREFILTER_BASE_GGX) { /* the table of the one-texel rule (revision 3) */
        double r[9];
        min_rotation(n, r);
        for (int a = 0; a < o->n_theta; ++a)
            for (int b = 0; b < o->n_phi; ++b) {
                size_t k = (size_t)a * o->n_phi + b;
                mf_status st = texel_albedo_table(o->alpha, n, r, view_dir(mf_prefilter_theta(o, a), mf_prefilter_phi(o, b)),
                                                  &out[2 * k], &out[2 * k + 1]);
                if (st != MF_OK)
                    return st;
            }
        return MF_OK;
    }
    mf_prefilter_mix one;
    mf_status st = mf_prefilter_mix_init(&one, base, n, 1);
    if (st != MF_OK)
        return st;
    mf_brdf_params p = base_params(o);
    for (int a = 0; a < o->n_theta && st == MF_OK; ++a)
        for (int b = 0; b < o->n_phi && st == MF_OK; ++b) {
            mf_result r;
            st = mf_prefilter_mix_albedo(&one, &p, view_dir(mf_prefilter_theta(o, a), mf_prefilter_phi(o, b)), &r);
            out[2 * ((size_t)a * o->n_phi + b)] = r.val;
            out[2 * ((size_t)a * o->n_phi + b) + 1] = r.err;
        }
    mf_prefilter_mix_free(&one);
    return st;
}

static mf_status albedo_texel(pjob *j, int t)
{
    int nv = j->o->n_theta * j->o->n_phi;
    if (j->uniq[t] != t) /* a copy of an earlier texel's: filled after the pass */
        return MF_OK;
    return one_texel_albedo(j->o, j->base, j->normals + 3 * (size_t)t, j->alb + 2 * (size_t)t * nv);
}

/* ---- clusters and mirror symmetry ------------------------------------------------------------- */

typedef struct {
    int64_t k[4];
} qkey;

static int qkey_cmp(const void *a, const void *b)
{
    const qkey *x = a, *y = b;
    for (int i = 0; i < 4; ++i)
        if (x->k[i] != y->k[i])
            return x->k[i] < y->k[i] ? -1 : 1;
    return 0;
}

/* The keys of n weighted normals (key[0 .. n)) and of their images (key[n .. 2 n)) under the
 * reflection that negates the coordinates of the bits of flip (bit c: coordinate c): normals on
 * a grid of step 1 / q, weights on the MF_PREFILTER_MIRROR_TOL grid. */
static void mirror_keys(const double *nrm, const double *w, int n, double q, int flip, qkey *key)
{
    const double qw = 1.0 / MF_PREFILTER_MIRROR_TOL;
    for (int i = 0; i < n; ++i)
        for (int m = 0; m < 2; ++m) {
            qkey *k = &key[m * n + i];
            for (int c = 0; c < 3; ++c)
                k->k[c] = llround(nrm[3 * i + c] * q * (m && (flip >> c & 1) ? -1.0 : 1.0));
            k->k[3] = llround(w[i] * qw);
        }
}

/* Whether the weighted normals (nrm, w) are, as a multiset, invariant under the mirror of
 * coordinate `axis` (0: x -> -x, 1: y -> -y): the normals' components compared on a grid of side
 * tol (MF_PREFILTER_MIRROR_TOL_NORMAL: the precision of an 8-bit map), the weights on the
 * MF_PREFILTER_MIRROR_TOL grid (a tie at a grid boundary can only miss a symmetry); if so, they are
 * replaced by an exactly symmetric multiset of the same size (those with a positive coordinate and
 * their exact mirrors; those on the plane with the coordinate set to 0, renormalised), moving no
 * normal by more than the tolerance.  key: 2 n scratch keys. */
static int mirror_snap(double *nrm, double *w, int n, int axis, double tol, qkey *key)
{
    const double q = 1.0 / tol;
    mirror_keys(nrm, w, n, q, 1 << axis, key);
    qsort(key, (size_t)n, sizeof *key, qkey_cmp);
    qsort(key + n, (size_t)n, sizeof *key, qkey_cmp);
    if (memcmp(key, key + n, sizeof *key * (size_t)n) != 0)
        return 0;
    /* the snapped set, written after the positive ones' (reads stay ahead of writes) */
    int pos = 0, on = 0;
    for (int i = 0; i < n; ++i) {
        int64_t s = llround(nrm[3 * i + axis] * q);
        pos += s > 0, on += s == 0;
    }
    if (2 * pos + on != n)
        return 0;
    double *tn = malloc(sizeof(double) * 3 * (size_t)n), *tw = malloc(sizeof(double) * (size_t)n);
    if (!tn || !tw) {
        free(tn), free(tw);
        return 0;
    }
    int k = 0;
    for (int i = 0; i < n; ++i) {
        int64_t s = llround(nrm[3 * i + axis] * q);
        if (s < 0)
            continue;
        memcpy(tn + 3 * k, nrm + 3 * i, 3 * sizeof(double));
        tw[k] = w[i];
        if (s == 0) {
            tn[3 * k + axis] = 0.0;
            double l = sqrt(tn[3 * k] * tn[3 * k] + tn[3 * k + 1] * tn[3 * k + 1] + tn[3 * k + 2] * tn[3 * k + 2]);
            for (int c = 0; c < 3; ++c)
                tn[3 * k + c] /= l;
            ++k;
        } else {
            ++k;
            memcpy(tn + 3 * k, nrm + 3 * i, 3 * sizeof(double));
            tn[3 * k + axis] = -tn[3 * k + axis];
            tw[k++] = w[i];
        }
    }
    memcpy(nrm, tn, sizeof(double) * 3 * (size_t)n);
    memcpy(w, tw, sizeof(double) * (size_t)n);
    free(tn), free(tw);
    return 1;
}

typedef struct {
    int64_t cx, cy;
    int idx;
} cell_item;

static int cell_cmp(const void *a, const void *b)
{
    const cell_item *x = a, *y = b;
    if (x->cx != y->cx)
        return x->cx < y->cx ? -1 : 1;
    if (x->cy != y->cy)
        return x->cy < y->cy ? -1 : 1;
    return (x->idx > y->idx) - (x->idx < y->idx);
}

/* Weighted clusters of n unit normals: cells of side h in slope space (n.x / n.z, n.y / n.z),
 * centred on the origin (cell index round(slope / h): the grid is symmetric under the x and y
 * mirrors and the diagonal swap), each cell one component: the normalised sum of its normals
 * (summed in texel order), weight count / n.  Returns the number of components (out: 3 per
 * component, wout: weights); -1 on allocation failure. */
static int cluster_normals(const double *nrm, int n, double h, double *out, double *wout)
{
    cell_item *it = malloc(sizeof *it * (size_t)n);
    if (!it)
        return -1;
    for (int i = 0; i < n; ++i) {
        const double *v = nrm + 3 * i;
        it[i].cx = (int64_t)floor(v[0] / v[2] / h + 0.5);
        it[i].cy = (int64_t)floor(v[1] / v[2] / h + 0.5);
        it[i].idx = i;
    }
    qsort(it, (size_t)n, sizeof *it, cell_cmp);
    int nc = 0;
    for (int i = 0; i < n;) {
        int e = i;
        double sx = 0.0, sy = 0.0, sz = 0.0;
        while (e < n && it[e].cx == it[i].cx && it[e].cy == it[i].cy) {
            const double *v = nrm + 3 * it[e].idx;
            sx += v[0], sy += v[1], sz += v[2];
            ++e;
        }
        double l = sqrt(sx * sx + sy * sy + sz * sz);
        out[3 * nc] = sx / l, out[3 * nc + 1] = sy / l, out[3 * nc + 2] = sz / l;
        wout[nc++] = (double)(e - i) / n;
        i = e;
    }
    free(it);
    return nc;
}

typedef struct {
    double v[4]; /* x, y, z, weight */
} wnormal;

static int wnormal_cmp(const void *a, const void *b)
{
    const wnormal *x = a, *y = b;
    for (int i = 0; i < 4; ++i)
        if (x->v[i] != y->v[i])
            return x->v[i] < y->v[i] ? -1 : 1;
    return 0;
}

/* The canonical order of a weighted normal set (lexicographic in x, y, z, weight): the mixture's
 * sampler assigns the quasi-random points to components in their order, so two views or texels
 * whose footprints hold the same set (e.g. phi and phi + pi of a V-groove, or permuted texels) get
 * the same points and the same fit, whatever the texels' order. */
static void canonical_order(double *nrm, double *w, int n, wnormal *tmp)
{
    for (int i = 0; i < n; ++i) {
        memcpy(tmp[i].v, nrm + 3 * i, 3 * sizeof(double));
        tmp[i].v[3] = w[i];
    }
    qsort(tmp, (size_t)n, sizeof *tmp, wnormal_cmp);
    for (int i = 0; i < n; ++i) {
        memcpy(nrm + 3 * i, tmp[i].v, 3 * sizeof(double));
        w[i] = tmp[i].v[3];
    }
}

/* Whether the weighted normals (nrm, w) are, as a multiset, invariant under the half-turn about z
 * ((x, y) -> (-x, -y)), compared on the MF_PREFILTER_MIRROR_TOL grid as mirror_snap does: then the
 * view at phi + pi sees, in its aligned frame, the footprint of phi (a V-groove, any footprint with a
 * centre of symmetry).  key: 2 n scratch keys. */
static int halfturn_symmetric(const double *nrm, const double *w, int n, qkey *key)
{
    mirror_keys(nrm, w, n, 1.0 / MF_PREFILTER_MIRROR_TOL_NORMAL, 3, key);
    qsort(key, (size_t)n, sizeof *key, qkey_cmp);
    qsort(key + n, (size_t)n, sizeof *key, qkey_cmp);
    return memcmp(key, key + n, sizeof *key * (size_t)n) == 0;
}

static double dist2(const double *a, const double *b)
{
    return (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
}

int mf_prefilter_split_two(const double *n, int count, int *side)
{
    if (!n || !side || count < 1)
        return 0;
    double mean[3] = {0.0, 0.0, 0.0};
    for (int q = 0; q < count; ++q) {
        side[q] = 0;
        for (int i = 0; i < 3; ++i)
            mean[i] += n[3 * q + i];
    }
    for (int i = 0; i < 3; ++i)
        mean[i] /= count;
    int a = 0, b = 0;
    double best = -1.0;
    for (int q = 0; q < count; ++q)
        if (dist2(n + 3 * q, mean) > best)
            best = dist2(n + 3 * q, mean), a = q;
    best = -1.0;
    for (int q = 0; q < count; ++q)
        if (dist2(n + 3 * q, n + 3 * a) > best)
            best = dist2(n + 3 * q, n + 3 * a), b = q;
    if (!(best > 0.0))
        return 0;
    double c[2][3] = {{n[3 * a], n[3 * a + 1], n[3 * a + 2]}, {n[3 * b], n[3 * b + 1], n[3 * b + 2]}};
    int cnt[2] = {0, 0};
    for (int round = 0; round < 50; ++round) {
        int changed = 0;
        double sum[2][3] = {{0, 0, 0}, {0, 0, 0}};
        cnt[0] = cnt[1] = 0;
        for (int q = 0; q < count; ++q) {
            int sd = dist2(n + 3 * q, c[1]) < dist2(n + 3 * q, c[0]);
            changed |= round == 0 || side[q] != sd;
            side[q] = sd;
            cnt[sd]++;
            for (int i = 0; i < 3; ++i)
                sum[sd][i] += n[3 * q + i];
        }
        if (cnt[0] == 0 || cnt[1] == 0)
            break;
        for (int k = 0; k < 2; ++k)
            for (int i = 0; i < 3; ++i)
                c[k][i] = sum[k][i] / cnt[k];
        if (!changed)
            break;
    }
    if (cnt[0] == 0 || cnt[1] == 0) {
        for (int q = 0; q < count; ++q)
            side[q] = 0;
        return 0;
    }
    /* the order: half a has the larger mean x, then y, then z (c holds the final means) */
    int swap = 0;
    for (int i = 0; i < 3; ++i)
        if (c[0][i] != c[1][i]) {
            swap = c[1][i] > c[0][i];
            break;
        }
    if (swap)
        for (int q = 0; q < count; ++q)
            side[q] = !side[q];
    return swap ? cnt[0] : cnt[1];
}

/* ---- one footprint ---------------------------------------------------------------------------- */

/* The mass of the LTC M above the horizon: the clamped cosine over the half-space (M^T z).w > 0,
 * (1 + n.z) / 2 with n = M^T z / |M^T z| (row 2 of M). */
static double horizon_mass(const double m[9])
{
    return 0.5 * (1.0 + m[8] / sqrt(m[6] * m[6] + m[7] * m[7] + m[8] * m[8]));
}

static void store(pjob *j, mf_prefilter_level *lv, size_t idx, const double m[9], const double lobe[7], double alb,
                  double err, const mf_ltcfit_aniso_entry *e, int count)
{
    for (int i = 0; i < 9; ++i)
        lv->m[9 * idx + i] = (float)m[i];
    lv->albedo[idx] = (float)alb;
    lv->magnitude[idx] = (float)(j->o->keep_albedo ? alb / fmax(horizon_mass(m), MF_PREFILTER_HORIZON_MIN) : alb);
    memcpy(j->lobes[lv->level - 1] + MF_LTCFIT_ANISO_NPARAMS * idx, lobe, sizeof(double) * MF_LTCFIT_ANISO_NPARAMS);
    if (!count)
        return;
    pthread_mutex_lock(&j->lock);
    if (e->residual > lv->worst_residual)
        lv->worst_residual = e->residual;
    if (err > lv->worst_albedo_err)
        lv->worst_albedo_err = err;
    lv->not_converged += !e->converged;
    lv->iterations += e->iterations;
    lv->lobes++;
    pthread_mutex_unlock(&j->lock);
    if (j->o->progress)
        j->o->progress(j->o->progress_user, 1);
}

/* store, and the entry as given into rec[v] (rec NULL: not recorded; options.reuse) */
static void keep(pjob *j, mf_prefilter_level *lv, size_t base_idx, int v, const double m[9], const double lobe[7],
                 double alb, double err, const mf_ltcfit_aniso_entry *e, memo_entry *rec)
{
    store(j, lv, base_idx + (size_t)v, m, lobe, alb, err, e, 1);
    if (rec) {
        memcpy(rec[v].m, m, sizeof rec[v].m);
        memcpy(rec[v].lobe, lobe, sizeof rec[v].lobe);
        rec[v].residual = e->residual;
        rec[v].converged = e->converged;
        rec[v].iterations = e->iterations;
    }
}

/* options.reuse.  A footprint's fits read only: the directions' count fo.samples, the half's share, the
 * components (normals cn and weights cw, nc of them, in their order) and the albedos alb (value and error
 * per view); the options are the call's.  Everything else in fit_footprint is computed from these (the
 * mirror and half-turn symmetries, the mixtures, the starts and chains within the footprint), with no
 * input from its place or from other footprints (the parent's lobes as starts are off:
 * PREFILTER_PARENT_STARTS), and a fit reads only memory it has written (test_ltcfit_aniso,
 * heap_history), so equal inputs give the same stored bits.  The key is those inputs as doubles,
 * compared bit for bit. */
static double *memo_key(int samples, double share, int nc, const double *cn, const double *cw, const double *alb,
                        int nv, size_t *nkey)
{
    size_t n = 3 + 4 * (size_t)nc + 2 * (size_t)nv;
    double *k = malloc(sizeof(double) * n);
    if (!k)
        return NULL;
    k[0] = samples, k[1] = share, k[2] = nc;
    memcpy(k + 3, cn, sizeof(double) * 3 * (size_t)nc);
    memcpy(k + 3 + 3 * (size_t)nc, cw, sizeof(double) * (size_t)nc);
    memcpy(k + 3 + 4 * (size_t)nc, alb, sizeof(double) * 2 * (size_t)nv);
    *nkey = n;
    return k;
}

static uint64_t memo_hash(const double *k, size_t n) /* FNV-1a over the bytes */
{
    const unsigned char *b = (const unsigned char *)k;
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < n * sizeof(double); ++i)
        h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

/* The entries of the footprint with this key, copied into out (nv), or 0 if none is kept. */
static int memo_find(pjob *j, uint64_t h, const double *k, size_t n, memo_entry *out, int nv)
{
    int found = 0;
    pthread_mutex_lock(&j->memo_lock);
    for (const memo_node *q = j->memo[h % MEMO_BUCKETS]; q && !found; q = q->next)
        if (q->hash == h && q->nkey == n && !memcmp(q->key, k, sizeof(double) * n)) {
            memcpy(out, q->ent, sizeof(memo_entry) * (size_t)nv);
            found = 1;
        }
    pthread_mutex_unlock(&j->memo_lock);
    return found;
}

/* Keeps key k (n doubles) and ent (nv entries), taking both, unless the key is there already (another
 * thread fitted the same footprint: the same bits) or the memory is spent; frees what it does not keep. */
static void memo_add(pjob *j, uint64_t h, double *k, size_t n, memo_entry *ent, int nv)
{
    size_t bytes = sizeof(memo_node) + sizeof(double) * n + sizeof(memo_entry) * (size_t)nv;
    memo_node *q = malloc(sizeof *q);
    pthread_mutex_lock(&j->memo_lock);
    int keep_it = q && j->memo_bytes + bytes <= MF_PREFILTER_REUSE_BYTES;
    for (const memo_node *r = j->memo[h % MEMO_BUCKETS]; r && keep_it; r = r->next)
        if (r->hash == h && r->nkey == n && !memcmp(r->key, k, sizeof(double) * n))
            keep_it = 0;
    if (keep_it) {
        *q = (memo_node){j->memo[h % MEMO_BUCKETS], h, n, k, ent};
        j->memo[h % MEMO_BUCKETS] = q;
        j->memo_bytes += bytes;
    }
    pthread_mutex_unlock(&j->memo_lock);
    if (!keep_it)
        free(q), free(k), free(ent);
}

static void memo_free(pjob *j)
{
    for (int b = 0; j->memo && b < MEMO_BUCKETS; ++b)
        for (memo_node *q = j->memo[b]; q;) {
            memo_node *nx = q->next;
            free(q->key), free(q->ent), free(q);
            q = nx;
        }
    free(j->memo);
    j->memo = NULL;
}

/* The early accept of the continuity rule: the solve from the previous azimuth's lobe is taken alone,
 * without the solves from the previous elevation's lobe and the closed-form start, when its RMS
 * residual is at most MF_PREFILTER_ACCEPT times that neighbour's own (stored) residual.  Measured with
 * the revision-4 rule that solves all of them (bench_prefilter --size 8, 2,205 entries with a
 * neighbour: the neighbour's solve was kept at every entry, and 85 % of them meet this test; no
 * entry that meets it had a kept solve other than the neighbour's), so on such maps the lobes are
 * the same bits at about half the solves.  On the demo groove (8 x 16 views) 4,589 of 8,344 entries
 * meet it, and 981 of those had kept another solve (nearly all at level 1, where the neighbour's solve was up to
 * 65 % worse): prefilter-eval with 4 x 8 views, level 1 mean MSE 2.779e-4 -> 2.788e-4, levels 2-4
 * the same to 4 digits (docs/prefilter_log.md, "Speed of revision 5").  Skipping the neighbour's solve
 * instead at footprints of one distinct normal cost more (level 1: 3.036e-4) and saved less. */
#define MF_PREFILTER_ACCEPT 1.1

/* One entry of a phi row (theta > 0) of the mixture mix at elevation th: solved from prev (the previous
 * elevation's lobe); with nb (the previous azimuth's lobe at th, b > 0; its residual nb_res) the
 * continuity rule: solves from nb, from prev and from the closed-form start on one preparation, nb's
 * kept unless its residual exceeds the best one's by more than MF_PREFILTER_CONTINUITY_MARGIN, so that
 * where a footprint's mixture has several single-lobe fits of similar cost (the facets of a groove)
 * neighbouring azimuths keep the same one; nb's solve alone when its residual is at most
 * MF_PREFILTER_ACCEPT nb_res.  Without nb (the first azimuth of a footprint), grazing rows (cos theta <
 * MF_PREFILTER_MULTISTART_COS) get two solves, from prev and from the closed-form start, the lower
 * residual kept; the other rows the same two solves with the continuity rule along theta: prev's
 * kept unless the closed-form one's residual is lower by more than MF_PREFILTER_CONTINUITY_MARGIN.
 * alb: the albedo and its error.
 *
 * Revision 9, the second solve on the first azimuth's non-grazing rows (before, prev's alone).  That
 * chain along theta had no other start, and below the default roughness it ran into poor minima: on
 * make_bump.py's 16 x 16 map at alpha 0.05 (8 x 16 views) the worst own-fit entry of the gate (level
 * 1, texel (7, 0), view (64.2 deg, 0)) held a sheared lobe, 21 % of its mass below the horizon, that
 * shades a 0.8 light at 0.140 against a truth of 0.109 (a fresh fit: 0.121); the gate's own fit fell
 * 0.3495 -> 0.2856 (passed).  The margin: with the lower residual kept instead, the demo's views
 * between the tabulated elevations got worse (render_prefilter_scenes, normal scene at lod 3: MSE
 * 8.6e-4 -> 2.3e-3) while prefilter-eval on the tabulated views read 6 % better: the closed-form
 * solve took the other facet's minimum at some elevations, and the bilinear view filter blends the
 * two.  With the margin the demo's levels 2-4 keep their bits; at alpha 0.1 on a 32 x 32 bump map
 * the gate and prefilter-eval read the same (docs/prefilter.md, "Fitter revision 9").
 *
 * The closed-form start on every row, not only the grazing ones (revision 6): the two warm starts
 * carry the fitter's proximal pull towards lobes of other views, and a chain of them can hold a run
 * of azimuths in a poor minimum that the neighbouring texels (fitted from other chains) do not share.
 * Measured on a 16 x 16 bump map (make_bump.py, default views, level 1, 7,146 entries re-solved from
 * their own lobe, the four texel neighbours' and both azimuth neighbours' lobes at the same view, and
 * the closed-form start): with revision 5, 22 entries had a start 10 % or more below their stored
 * solve, 21 of them the closed-form one; the worst `cross` entry of the gate (0.133 of the albedo) had
 * residual 0.034 against 0.0225 from the closed-form start and 0.023 from its texel neighbours' lobes.
 * With the closed-form solve wherever the early accept does not take: 4 entries, none 20 % lower;
 * the gate's cross 0.133 -> 0.116; bench_prefilter --size 8: +3 % CPU; prefilter-eval, demo map
 * with 4 x 8 views, level 1 MSE -6 % over three seeds (docs/prefilter_log.md, "Gate": "Why single
 * bump-map lobes landed far off"). */
static mf_status fit_row_entry(mf_prefilter_mix *mix, const mf_brdf_params *p, double th, int mir, const double *alb,
                               const double *prev, const double *nb, double nb_res, const mf_ltcfit_aniso_options *fo,
                               mf_ltcfit_aniso_entry *e)
{
    mf_status st = mix_set_view(mix, p, mf_vec3_make(sin(th), 0.0, cos(th)));
    if (st != MF_OK)
        return st;
    /* The fitter's elevation: the Lambert mixture does not depend on the view (mix_eval_pdf), and the
     * fitter reads theta only to sample the model at wo and to take GRAZING_FACTOR times the
     * directions at grazing views (mf_ltcfit_aniso.c, atexel_prepare), so the diffuse table's rows are
     * fitted at theta = 0 (the same problem, the base number of directions; revision 8); the starts
     * stay the elevation's (grazing above).  Measured side by side (bench_prefilter --size 32 --base
     * lambert, with the Lambert angle cache of mix_sample_weights): 1.30 -> 0.59-0.65 ms of CPU per
     * lobe, eval MSE per level within -3.1 % .. +1.8 % of revision 7's.  Conjugating the theta = 0
     * lobe to every view instead (no row fits) made the demo's levels 2-4 6.7 times worse.
     * docs/prefilter.md, "Diffuse table: evaluation and cost (fitter revision 8)". */
    double fth = mix->kind == MF_PREFILTER_BASE_LAMBERT ? 0.0 : th;
    if (!nb && cos(th) < MF_PREFILTER_MULTISTART_COS)
        return mf_ltcfit_aniso_entry_fit_mirrored_two(&mix->model, *p, fth, mir, alb[0], alb[1], prev, NULL, fo, e);
    /* with nb: nb, prev and the closed form; without (the first azimuth, revision 9: the continuity rule
     * along theta): prev and the closed form, prev's kept unless the other is lower by the margin */
    const double *starts[3] = {nb ? nb : prev, nb ? prev : NULL, NULL};
    int nsolved = 0;
    mf_ltcfit_aniso_entry ee[3];
    st = mf_ltcfit_aniso_entry_fit_mirrored_multi(&mix->model, *p, fth, mir, alb[0], alb[1], starts, nb ? 3 : 2,
                                                  nb && nb_res >= 0.0 ? MF_PREFILTER_ACCEPT * nb_res : -1.0, fo, ee,
                                                  &nsolved);
    if (st != MF_OK)
        return st;
    int best = 0, it = 0;
    for (int k = 0; k < nsolved; ++k) {
        it += ee[k].iterations;
        if (ee[k].residual < ee[best].residual)
            best = k;
    }
    if (ee[0].residual <= ee[best].residual * (1.0 + MF_PREFILTER_CONTINUITY_MARGIN))
        best = 0;
    *e = ee[best];
    e->iterations = it;
    return MF_OK;
}

/* The directions of a level-1 fit of a footprint whose texels do not all share one normal
 * (mf_prefilter_options.level1_shift; a power of two >= 64, as mf_ltcfit_aniso_options.samples
 * must be).  A uniform footprint keeps `samples` at every level: its effective BRDF is the base
 * lobe rotated, the same mixture at every level, and its lobe must not depend on the level (a
 * constant map gives the same lobe at every level, bit for bit: tests/test_prefilter_eval.sh).
 * Revision 7: a 2 x 2 footprint's effective BRDF is a
 * mixture of at most 4 GGX lobes, and the preparation (sampling the mixture, the inside sets of
 * the 51 lights) was about half of a level-1 fit's CPU at 4096 directions.  Measured with 4096 /
 * 1024 level-1 directions (prefilter-eval, the committed setup of analysis/prefilter_eval_data.sh):
 * demo map 30 / 30 of 48 cells, level-1 MSE 3.121e-4 / 3.101e-4 (levels 2-4 unchanged: their fits
 * do not read level 1; measured before uniform footprints kept `samples`: the demo's level-1
 * footprints are all uniform, so with that rule its level 1 is unchanged); the 32 x 32 bump map (make_bump.py) 45 / 45 of 60 cells, level-1 MSE
 * 5.346e-4 / 5.406e-4 (+1.1 %).  Fewer at every level (1024 at all levels) made levels 2-4 of the
 * demo 2.6 to 4.4 % worse (2048: 2.5 %), so levels >= 2 keep `samples`.  docs/prefilter_log.md,
 * "Speed of revision 7". */
static int level1_samples(const mf_prefilter_options *o)
{
    int n = o->samples >> o->level1_shift;
    return n < 64 ? 64 : n;
}

/* options.lobe: keeps in nrm (compacted, in their order) the texels of the selected half of the
 * footprint's 2-means split (mf_prefilter_split_two; half a: all of them when it does not split, half b
 * none), *nsel their count, and sets alb (2 per view) to the mean of their one-texel albedos and error
 * estimates: the albedo of the half's own mixture.  Texels with bitwise equal normals share one
 * computation (the normals are sorted for it, so the sums' order does not depend on the texels'). */
static mf_status half_select(const mf_prefilter_options *o, const mf_brdf_model *base, double *nrm, int n,
                             double *alb, int *nsel)
{
    int nv = o->n_theta * o->n_phi;
    int *side = malloc(sizeof(int) * (size_t)n);
    if (!side)
        return MF_ERR_ALLOC;
    int want = o->lobe - 1, m = 0;
    mf_prefilter_split_two(nrm, n, side);
    for (int q = 0; q < n; ++q)
        if (side[q] == want)
            memmove(nrm + 3 * m++, nrm + 3 * q, sizeof(double) * 3);
    free(side);
    *nsel = m;
    if (!m)
        return MF_OK;
    wnormal *srt = malloc(sizeof *srt * (size_t)m);
    double *one = malloc(sizeof(double) * 2 * (size_t)nv);
    mf_status st = srt && one ? MF_OK : MF_ERR_ALLOC;
    if (st == MF_OK) {
        for (int q = 0; q < m; ++q) {
            memcpy(srt[q].v, nrm + 3 * q, sizeof(double) * 3);
            srt[q].v[3] = 0.0;
        }
        qsort(srt, (size_t)m, sizeof *srt, wnormal_cmp);
        memset(alb, 0, sizeof(double) * 2 * (size_t)nv);
        for (int q = 0; q < m && st == MF_OK;) {
            int e = q;
            while (e < m && !memcmp(srt[e].v, srt[q].v, sizeof(double) * 3))
                ++e;
            st = one_texel_albedo(o, base, srt[q].v, one);
            for (int i = 0; i < 2 * nv && st == MF_OK; ++i)
                alb[i] += (e - q) * one[i];
            q = e;
        }
        for (int i = 0; i < 2 * nv; ++i)
            alb[i] /= m;
    }
    free(srt), free(one);
    return st;
}

/* One footprint: its (clustered) normals; theta = 0 fitted once (the view along the normal does not
 * depend on phi: the lobe at phi is the phi = 0 lobe rotated, M_phi = R_z(-phi) M_0 R_z(phi)); for
 * every phi the normals in the view-azimuth-aligned frame, their mirror symmetry y -> -y if they
 * have it, then the chain along theta: each fit starts from the previous elevation's lobe (a
 * proximal warm start).  (Offering the parent level's lobe at the same view as a second start
 * is implemented but off, PREFILTER_PARENT_STARTS: it breaks the tiling invariance.) */
#define PREFILTER_PARENT_STARTS 0
static mf_status fit_footprint(pjob *j, int level, int row, int col)
{
    const mf_prefilter_options *o = j->o;
    mf_prefilter_level *lv = &j->levels[level - 1];
    int fw = j->width / lv->width, fh = j->height / lv->height, nfoot = fw * fh;
    int nv = o->n_theta * o->n_phi;
    const double *parent = NULL;
    size_t pidx = 0;
    /* The parent level's lobe as a second start is off: a tile of the map (mf_prefilter_run_from)
     * has no parent for its own top level, so the start would make the lobes depend on the tiling
     * (and on the number of MPI ranks); the pipeline promises the same bits for any tiling. */
    if (PREFILTER_PARENT_STARTS && level < j->nlevels) {
        const mf_prefilter_level *pl = &j->levels[level];
        parent = j->lobes[level];
        pidx = ((size_t)(row * pl->height / lv->height) * pl->width + (size_t)(col * pl->width / lv->width)) * nv;
    }
    mf_ltcfit_aniso_options fo;
    mf_ltcfit_aniso_options_default(&fo);
    fo.samples = o->samples; /* level 1: see level1_samples, below */
    fo.max_iterations = o->max_iterations;
    fo.seed = o->seed;
    /* the ladder of base-lobe-sized lights (revision 6; mf_ltcfit_aniso_options.ladder_alpha) */
    fo.ladder_alpha = o->fit_lights == MF_PREFILTER_LIGHTS_LADDER && o->base == MF_PREFILTER_BASE_GGX ? o->alpha : 0.0;
    /* GGX: the stored magnitude (store: the albedo over the lobe's mass above the horizon) in the fit's
     * objective (revision 10; mf_ltcfit_aniso.c, fit_magnitude).  Measured on make_bump.py 32 (8 x 16
     * views, prefilter-eval --texels 64 --samples 1024): mean MSE per level 1-5 -17 % to -45 %; the demo
     * groove: level 1 -44 %, levels 2-4 +3.5 %, its grazing scene -5 % to -39 %, its normal scene at
     * lod 2 +24 % (docs/prefilter.md, "Fitter revision 10").  Not for Lambert: its levels 1 and 2 read
     * 30 % and 53 % worse, so the diffuse table keeps revision 9's lobes. */
    fo.horizon_min = o->keep_albedo && o->base == MF_PREFILTER_BASE_GGX ? MF_PREFILTER_HORIZON_MIN : 0.0;
    mf_brdf_params p = base_params(o);
    /* the per-component arrays (rn .. key) are sized by the component count nc, known after the
     * clustering: bounded for the largest footprints (one per occupied slope cell) */
    double *tex = malloc(sizeof(double) * 3 * (size_t)nfoot), *cn = malloc(sizeof(double) * 3 * (size_t)nfoot);
    double *cw = malloc(sizeof(double) * (size_t)nfoot), *rn = NULL;
    double *rw = NULL, *alb = malloc(sizeof(double) * 2 * (size_t)nv);
    double *un = NULL, *uw = NULL;
    double *res = malloc(sizeof(double) * (size_t)nv); /* the stored entries' residuals (MF_PREFILTER_ACCEPT) */
    qkey *key = NULL;
    mf_status st = tex && cn && cw && alb && res ? MF_OK : MF_ERR_ALLOC;
    int nc = 0;
    /* share: the part of the footprint's texels this table fits (options.lobe: a half; 1 otherwise); the
     * fits see the half's own mixture (its albedos alb, the mean over its texels), the stored albedos
     * and magnitudes are scaled by share (at store) */
    double share = 1.0;
    size_t base_idx = ((size_t)row * lv->width + col) * nv;
    if (st == MF_OK) {
        int k = 0;
        for (int y = row * fh; y < (row + 1) * fh; ++y)
            for (int x = col * fw; x < (col + 1) * fw; ++x, ++k)
                memcpy(tex + 3 * k, j->normals + 3 * ((size_t)y * j->width + x), 3 * sizeof(double));
        if (o->lobe) {
            int nsel = 0;
            st = half_select(o, j->base, tex, nfoot, alb, &nsel);
            if (st == MF_OK && nsel == 0) { /* half b of a footprint that does not split: empty */
                const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[MF_LTCFIT_ANISO_NPARAMS] = {0};
                mf_ltcfit_aniso_entry e0;
                memset(&e0, 0, sizeof e0);
                e0.converged = 1;
                for (int v = 0; v < nv; ++v)
                    store(j, lv, base_idx + v, id, zero, 0.0, 0.0, &e0, 1);
                free(tex), free(cn), free(cw), free(alb), free(res);
                return MF_OK;
            }
            share = (double)nsel / nfoot;
            nfoot = nsel;
        }
    }
    if (st == MF_OK) {
        int uniform = 1;
        for (int i = 1; i < nfoot && uniform; ++i)
            uniform = tex[3 * i] == tex[0] && tex[3 * i + 1] == tex[1] && tex[3 * i + 2] == tex[2];
        if (level == 1 && !uniform)
            fo.samples = level1_samples(o);
        double h = o->cluster_cell * (o->base == MF_PREFILTER_BASE_LAMBERT ? MF_PREFILTER_CLUSTER_LAMBERT : o->alpha);
        if (h > 0.0 && nfoot >= MF_PREFILTER_CLUSTER_MIN) {
            nc = cluster_normals(tex, nfoot, h, cn, cw);
            if (nc < 0)
                st = MF_ERR_ALLOC;
        } else {
            memcpy(cn, tex, sizeof(double) * 3 * (size_t)nfoot);
            for (int i = 0; i < nfoot; ++i)
                cw[i] = 1.0 / nfoot;
            nc = nfoot;
        }
        /* the magnitudes: the exact mixture of the texels' albedos (not of the clusters'), from the
         * level's albedo pyramid (albedo_reduce); a half's from its texels (half_select) */
        if (!o->lobe)
            memcpy(alb, j->lalb[level - 1] + 2 * ((size_t)row * lv->width + col) * nv, sizeof(double) * 2 * (size_t)nv);
        /* A negative albedo, which the fit refuses as outside its domain: the one-texel albedo table's
         * quadrature does not resolve the base lobe (alpha 0.002 on make_bump.py's map: -0.0104 at the
         * grazing view, estimated error 0.025).  Said here, naming the footprint, view and roughness. */
        for (int v = 0; v < nv && st == MF_OK; ++v)
            if (!(alb[2 * v] >= 0.0)) {
                char text[256];
                int a = v / o->n_phi, b = v % o->n_phi;
                snprintf(text, sizeof text,
                         "the albedo of its level-%d texel (%d, %d) at view (%.4g deg, %.4g deg) is %.3g (estimated "
                         "error %.3g): the albedo rule does not resolve roughness %g",
                         level, col, row, mf_prefilter_theta(o, a) * 180.0 / MF_PI, mf_prefilter_phi(o, b) * 180.0 / MF_PI,
                         alb[2 * v], alb[2 * v + 1], o->alpha);
                set_error(j, MF_ERR_NO_CONVERGENCE, text);
                st = MF_ERR_NO_CONVERGENCE;
            }
    }
    /* options.reuse: the entries of an identical footprint fitted before in this call, if one is kept
     * (memo_key says why they are this footprint's own bits); otherwise rec records this one's */
    memo_entry *rec = NULL;
    double *mkey = NULL;
    size_t nkey = 0;
    uint64_t mhash = 0;
    if (st == MF_OK && j->memo) {
        rec = malloc(sizeof(memo_entry) * (size_t)nv);
        mkey = rec ? memo_key(fo.samples, share, nc, cn, cw, alb, nv, &nkey) : NULL;
        if (!mkey)
            st = MF_ERR_ALLOC;
        else if (mhash = memo_hash(mkey, nkey), memo_find(j, mhash, mkey, nkey, rec, nv)) {
            for (int v = 0; v < nv; ++v) {
                mf_ltcfit_aniso_entry e;
                memset(&e, 0, sizeof e);
                e.residual = rec[v].residual;
                e.converged = rec[v].converged;
                e.iterations = rec[v].iterations;
                store(j, lv, base_idx + (size_t)v, rec[v].m, rec[v].lobe, share * alb[2 * v], share * alb[2 * v + 1],
                      &e, 1);
            }
            pthread_mutex_lock(&j->lock);
            lv->reused += nv;
            pthread_mutex_unlock(&j->lock);
            free(rec), free(mkey), free(tex), free(cn), free(cw), free(alb), free(res);
            return MF_OK;
        }
    }
    free(tex);
    tex = NULL;
    if (st == MF_OK && nc < nfoot) { /* give the footprint-sized memory back */
        double *c2 = realloc(cn, sizeof(double) * 3 * (size_t)nc), *w2 = realloc(cw, sizeof(double) * (size_t)nc);
        cn = c2 ? c2 : cn, cw = w2 ? w2 : cw;
    }
    if (st == MF_OK) {
        rn = malloc(sizeof(double) * 3 * (size_t)nc), rw = malloc(sizeof(double) * (size_t)nc);
        un = malloc(sizeof(double) * 3 * (size_t)nc), uw = malloc(sizeof(double) * (size_t)nc);
        key = malloc(sizeof(qkey) * 2 * (size_t)nc);
        if (!rn || !rw || !un || !uw || !key)
            st = MF_ERR_ALLOC;
    }
    /* theta = 0: once, at phi = 0.  Its symmetries only on the fine MF_PREFILTER_MIRROR_TOL grid: this
     * one lobe, conjugated, serves every azimuth, so it is continuous in phi by construction, and the
     * free fit of an 8-bit groove is the better one (demo map, 4 x 8 views, levels 2-4, with the rows'
     * symmetric lobes forced: prefilter-eval MSE 3.5e-3 with the fine grid here, 4.1e-3 with the
     * 3/255 grid; SCENE 1 lod 2-4 1.33e-3 / 1.21e-3 / 8.5e-4 against 1.72e-3 / 1.49e-3 / 9.2e-4) */
    double lobe0[MF_LTCFIT_ANISO_NPARAMS];
    if (st == MF_OK) {
        memcpy(rn, cn, sizeof(double) * 3 * (size_t)nc);
        memcpy(rw, cw, sizeof(double) * (size_t)nc);
        int mir = 0;
        if (mirror_snap(rn, rw, nc, 1, MF_PREFILTER_MIRROR_TOL, key))
            mir |= MF_LTCFIT_ANISO_MIRROR_Y;
        if (mirror_snap(rn, rw, nc, 0, MF_PREFILTER_MIRROR_TOL, key))
            mir |= MF_LTCFIT_ANISO_MIRROR_X;
        canonical_order(rn, rw, nc, (wnormal *)(void *)key);
        mf_prefilter_mix mix;
        st = mix_build(&mix, j->base, rn, rw, nc);
        if (st == MF_OK) {
            st = mix_set_view(&mix, &p, mf_vec3_make(0.0, 0.0, 1.0));
            mf_ltcfit_aniso_entry e;
            if (st == MF_OK)
                st = mf_ltcfit_aniso_entry_fit_mirrored(&mix.model, p, 0.0, mir, alb[0], alb[1], NULL,
                                                        parent ? parent + MF_LTCFIT_ANISO_NPARAMS * pidx : NULL, &fo, &e);
            if (st == MF_OK && !(isfinite(e.m[0]) && isfinite(e.m[4]) && isfinite(e.m[8])))
                st = MF_ERR_INTERNAL;
            if (st == MF_OK) {
                memcpy(lobe0, e.lobe, sizeof lobe0);
                for (int b = 0; b < o->n_phi; ++b) {
                    /* M_phi = R_z(-phi) M_0 R_z(phi) (b = 0: M_0 itself, bit for bit) */
                    double ph = mf_prefilter_phi(o, b), c = b ? cos(ph) : 1.0, s = b ? sin(ph) : 0.0, t[9], m[9];
                    for (int col2 = 0; col2 < 3; ++col2) {
                        t[col2] = c * e.m[col2] + s * e.m[3 + col2];
                        t[3 + col2] = -s * e.m[col2] + c * e.m[3 + col2];
                        t[6 + col2] = e.m[6 + col2];
                    }
                    for (int r = 0; r < 3; ++r) {
                        m[3 * r] = c * t[3 * r] + s * t[3 * r + 1];
                        m[3 * r + 1] = -s * t[3 * r] + c * t[3 * r + 1];
                        m[3 * r + 2] = t[3 * r + 2];
                    }
                    int v = b; /* i_theta = 0 */
                    keep(j, lv, base_idx, v, b ? m : e.m, e.lobe, share * alb[2 * v], share * alb[2 * v + 1], &e, rec);
                }
            }
            mf_prefilter_mix_free(&mix);
        }
    }
    /* a footprint with a centre of symmetry: the rows phi + pi are the rows phi (fitted once) */
    int half = st == MF_OK && o->n_phi % 2 == 0 && halfturn_symmetric(cn, cw, nc, key) ? o->n_phi / 2 : 0;
    for (int b = 0; b < o->n_phi && st == MF_OK; ++b) {
        if (half && b >= half) {
            mf_ltcfit_aniso_entry e0;
            memset(&e0, 0, sizeof e0);
            e0.converged = 1;
            for (int a = 1; a < o->n_theta; ++a) {
                size_t v = (size_t)a * o->n_phi + b, u = v - (size_t)half;
                double m[9];
                for (int i = 0; i < 9; ++i)
                    m[i] = lv->m[9 * (base_idx + u) + i];
                keep(j, lv, base_idx, (int)v, m, j->lobes[level - 1] + MF_LTCFIT_ANISO_NPARAMS * (base_idx + u),
                     share * alb[2 * v], share * alb[2 * v + 1], &e0, rec);
            }
            continue;
        }
        double phi = mf_prefilter_phi(o, b), c = cos(phi), s = sin(phi);
        for (int i = 0; i < nc; ++i) { /* rotated by -phi about z */
            rn[3 * i] = c * cn[3 * i] + s * cn[3 * i + 1];
            rn[3 * i + 1] = -s * cn[3 * i] + c * cn[3 * i + 1];
            rn[3 * i + 2] = cn[3 * i + 2];
            rw[i] = cw[i];
        }
        /* the y mirror: exact (1e-9 grid) -> that symmetric set only; only at the map's 8-bit precision
         * (3/255 grid) -> two mixtures, the snapped symmetric one and the map's own, both fitted and
         * the symmetric lobe kept unless its residual exceeds the free one's by more than
         * MF_PREFILTER_SYMMETRY_MARGIN (the free lobe may sit on one facet; the symmetric one is the
         * continuous choice where the view runs along a groove) */
        memcpy(un, rn, sizeof(double) * 3 * (size_t)nc);
        memcpy(uw, rw, sizeof(double) * (size_t)nc);
        int mir = mirror_snap(un, uw, nc, 1, MF_PREFILTER_MIRROR_TOL, key) ? MF_LTCFIT_ANISO_MIRROR_Y : 0;
        int two = !mir && mirror_snap(rn, rw, nc, 1, MF_PREFILTER_MIRROR_TOL_NORMAL, key);
        canonical_order(un, uw, nc, (wnormal *)(void *)key);
        mf_prefilter_mix mix, mixs;
        if ((st = mix_build(&mix, j->base, un, uw, nc)) != MF_OK)
            break;
        if (two) {
            canonical_order(rn, rw, nc, (wnormal *)(void *)key);
            if ((st = mix_build(&mixs, j->base, rn, rw, nc)) != MF_OK) {
                mf_prefilter_mix_free(&mix);
                break;
            }
        }
        const double *prev = lobe0;
        for (int a = 1; a < o->n_theta; ++a) {
            double th = mf_prefilter_theta(o, a);
            int v = a * o->n_phi + b;
            const double *nb = b > 0 ? j->lobes[level - 1] + MF_LTCFIT_ANISO_NPARAMS * (base_idx + v - 1) : NULL;
            mf_ltcfit_aniso_entry e;
            double nbr = nb ? res[v - 1] : -1.0;
            st = fit_row_entry(&mix, &p, th, mir, alb + 2 * v, prev, nb, nbr, &fo, &e);
            if (st == MF_OK && two) {
                mf_ltcfit_aniso_entry es;
                st = fit_row_entry(&mixs, &p, th, MF_LTCFIT_ANISO_MIRROR_Y, alb + 2 * v, prev, nb, nbr, &fo, &es);
                if (st == MF_OK) {
                    int it = e.iterations + es.iterations;
                    if (es.residual <= e.residual * (1.0 + MF_PREFILTER_SYMMETRY_MARGIN))
                        e = es;
                    e.iterations = it;
                }
            }
            if (st != MF_OK)
                break;
            if (!(isfinite(e.m[0]) && isfinite(e.m[4]) && isfinite(e.m[8]))) {
                st = MF_ERR_INTERNAL;
                break;
            }
            keep(j, lv, base_idx, v, e.m, e.lobe, share * alb[2 * v], share * alb[2 * v + 1], &e, rec);
            res[v] = e.residual;
            prev = j->lobes[level - 1] + MF_LTCFIT_ANISO_NPARAMS * (base_idx + v);
        }
        if (two)
            mf_prefilter_mix_free(&mixs);
        mf_prefilter_mix_free(&mix);
    }
    free(tex), free(cn), free(cw), free(rn), free(rw), free(un), free(uw), free(alb), free(key), free(res);
    if (rec && st == MF_OK)
        memo_add(j, mhash, mkey, nkey, rec, nv); /* takes mkey and rec */
    else
        free(rec), free(mkey);
    return st;
}

static void *worker(void *arg)
{
    pjob *j = arg;
    for (;;) {
        pthread_mutex_lock(&j->lock);
        long t = j->status == MF_OK && j->next < j->total ? j->next++ : -1;
        pthread_mutex_unlock(&j->lock);
        if (t < 0)
            break;
        mf_status st;
        if (j->job_kind == 0) {
            st = albedo_texel(j, (int)t);
        } else {
            const mf_prefilter_level *lv = &j->levels[j->level - 1];
            st = fit_footprint(j, j->level, (int)(t / lv->width), (int)(t % lv->width));
        }
        if (st != MF_OK) {
            char text[128];
            snprintf(text, sizeof text, "%s: %s", j->job_kind ? "LTC fit" : "albedo", mf_status_str(st));
            set_error(j, st, text);
        }
    }
    return NULL;
}

static mf_status run_pass(pjob *j, int kind, long total)
{
    j->job_kind = kind;
    j->next = 0;
    j->total = total;
    int nt = j->o->threads;
    pthread_t th[256];
    int started = 0;
    for (; started < nt - 1; ++started)
        if (pthread_create(&th[started], NULL, worker, j) != 0)
            break;
    worker(j);
    for (int i = 0; i < started; ++i)
        pthread_join(th[i], NULL);
    return j->status;
}

static int is_pow2(int n) { return n > 0 && (n & (n - 1)) == 0; }

mf_status mf_prefilter_run(const double *normals, int width, int height, const mf_prefilter_options *o,
                           mf_prefilter_level **levels, int *nlevels, char *msg, size_t msg_size)
{
    return mf_prefilter_run_from(normals, width, height, o, 1, levels, nlevels, msg, msg_size);
}

/* The albedos of the level above the w x h level src (per texel and view, value and error
 * interleaved, as pjob.alb): each texel's the mean of its children (2 x 2, or 2 x 1 / 1 x 2 once a
 * dimension is 1), summed row by row.  The effective BRDF is the equal-weight mixture of its texels'
 * base lobes (Nahmias 2022, Eq. 2.36), so its albedo, the mean of its texels' albedos, is also the
 * mean of its children's: every level is reduced from the one below it in this one order, whatever
 * the tile that holds it, so the bits do not depend on the tiling (and level 1, summed in the
 * texels' row order, is what summing a footprint's texels gives). */
static double *albedo_reduce(const double *src, int w, int h, size_t nv, int *ow, int *oh)
{
    int dw = w > 1 ? w / 2 : 1, dh = h > 1 ? h / 2 : 1, fx = w / dw, fy = h / dh;
    double *d = malloc(sizeof(double) * 2 * (size_t)dw * dh * nv);
    if (!d)
        return NULL;
    for (int r = 0; r < dh; ++r)
        for (int c = 0; c < dw; ++c)
            for (size_t v = 0; v < nv; ++v) {
                double a = 0.0, e = 0.0;
                for (int y = r * fy; y < (r + 1) * fy; ++y)
                    for (int x = c * fx; x < (c + 1) * fx; ++x) {
                        const double *s = src + 2 * (((size_t)y * w + x) * nv + v);
                        a += s[0], e += s[1];
                    }
                double *t = d + 2 * (((size_t)r * dw + c) * nv + v);
                t[0] = a / (fx * fy), t[1] = e / (fx * fy);
            }
    *ow = dw, *oh = dh;
    return d;
}

/* j->lalb[l - 1] for the levels first_level..j->nlevels: from the albedos of level base_level
 * (base, max(w >> b, 1) x max(h >> b, 1) texels), or, base NULL, from the one-texel albedos of
 * level 0 (texels with bitwise equal normals share them: the first one computes them).  Each level
 * below first_level is freed once the next one is built, so the memory is the cache of level 0 (or
 * of base_level) and the next level up. */
static mf_status albedo_pyramid(pjob *j, const double *base, int base_level, int first_level)
{
    size_t ntex = (size_t)j->width * j->height, nv = (size_t)j->o->n_theta * j->o->n_phi;
    const double *cur = base;
    double *own = NULL;
    int cw = j->width >> base_level > 0 ? j->width >> base_level : 1;
    int ch = j->height >> base_level > 0 ? j->height >> base_level : 1;
    mf_status st = MF_OK;
    if (!base) {
        base_level = 0, cw = j->width, ch = j->height;
        j->alb = malloc(sizeof(double) * 2 * ntex * nv);
        j->uniq = malloc(sizeof(int) * ntex);
        qkey *key = malloc(sizeof *key * ntex);
        if (!j->alb || !j->uniq || !key) {
            free(key);
            return MF_ERR_ALLOC;
        }
        for (size_t t = 0; t < ntex; ++t) {
            for (int c = 0; c < 3; ++c)
                memcpy(&key[t].k[c], j->normals + 3 * t + c, sizeof(double));
            key[t].k[3] = (int64_t)t;
        }
        qsort(key, ntex, sizeof *key, qkey_cmp);
        for (size_t i = 0; i < ntex;) {
            size_t e = i;
            while (e < ntex && !memcmp(key[e].k, key[i].k, 3 * sizeof(int64_t)))
                j->uniq[key[e++].k[3]] = (int)key[i].k[3]; /* the smallest index: the first in the run */
            i = e;
        }
        free(key);
        st = run_pass(j, 0, (long)ntex);
        if (st != MF_OK)
            return st;
        for (size_t t = 0; t < ntex; ++t)
            if (j->uniq[t] != (int)t)
                memcpy(j->alb + 2 * t * nv, j->alb + 2 * (size_t)j->uniq[t] * nv, sizeof(double) * 2 * nv);
        free(j->uniq);
        j->uniq = NULL;
        cur = own = j->alb;
        j->alb = NULL;
    }
    for (int l = base_level + 1; l <= j->nlevels; ++l) {
        int nw, nh;
        double *next = albedo_reduce(cur, cw, ch, nv, &nw, &nh);
        free(own);
        own = NULL;
        if (!next)
            return MF_ERR_ALLOC;
        cur = next, cw = nw, ch = nh;
        if (l >= first_level)
            j->lalb[l - 1] = next;
        else
            own = next;
    }
    free(own);
    return st;
}

/* The checks of mf_prefilter_run_tile's map and options; MF_ERR_DOMAIN with msg. */
static mf_status check_run(const double *normals, int width, int height, const mf_prefilter_options *o, char *msg,
                           size_t msg_size)
{
#define FAIL(...) (msg && msg_size ? (void)snprintf(msg, msg_size, __VA_ARGS__) : (void)0), MF_ERR_DOMAIN
    if (!normals || !o)
        return FAIL("null argument");
    if (o->base != MF_PREFILTER_BASE_GGX && o->base != MF_PREFILTER_BASE_LAMBERT)
        return FAIL("base %d: need MF_PREFILTER_BASE_GGX or MF_PREFILTER_BASE_LAMBERT", o->base);
    if (o->base == MF_PREFILTER_BASE_GGX && !(o->alpha > 0.0 && o->alpha <= 1.0))
        return FAIL("roughness %g not in (0, 1]", o->alpha);
    if (o->n_theta < 2 || o->n_theta > 256 || o->n_phi < 1 || o->n_phi > 256)
        return FAIL("views %d x %d: need 2..256 elevations x 1..256 azimuths", o->n_theta, o->n_phi);
    if (o->threads < 1 || o->threads > 256)
        return FAIL("threads %d not in 1..256", o->threads);
    if (o->fit_lights != MF_PREFILTER_LIGHTS_LADDER && o->fit_lights != MF_PREFILTER_LIGHTS_LOBE)
        return FAIL("fit_lights %d is neither MF_PREFILTER_LIGHTS_LADDER nor MF_PREFILTER_LIGHTS_LOBE", o->fit_lights);
    if (!(o->cluster_cell >= 0.0 && o->cluster_cell <= 4.0))
        return FAIL("cluster cell %g not in [0, 4]", o->cluster_cell);
    if (o->level1_shift < 0 || o->level1_shift > 8)
        return FAIL("level1_shift %d not in 0..8", o->level1_shift);
    if (o->lobe < 0 || o->lobe > 2)
        return FAIL("lobe %d not in 0..2", o->lobe);
    if (o->reuse != 0 && o->reuse != 1)
        return FAIL("reuse %d is neither 0 nor 1", o->reuse);
    if (!is_pow2(width) || !is_pow2(height) || (width == 1 && height == 1) || width > 4096 || height > 4096)
        return FAIL("map size %d x %d: width and height must be powers of two, 1..4096, not both 1", width, height);
    for (long t = 0; t < (long)width * height; ++t) {
        const double *n = normals + 3 * t;
        double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(fabs(len - 1.0) <= 1e-9) || !(n[2] > 0.0))
            return FAIL("texel (%ld, %ld): normal (%g, %g, %g) is not a unit vector with n.z > 0", t % width,
                        t / width, n[0], n[1], n[2]);
    }
#undef FAIL
    return MF_OK;
}

static int count_levels(int width, int height)
{
    int nl = 0;
    while ((width >> nl) > 1 || (height >> nl) > 1)
        ++nl;
    return nl;
}

mf_status mf_prefilter_albedo_level(const double *normals, int width, int height, const mf_prefilter_options *o,
                                    int level, double *out, char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
    mf_status st = check_run(normals, width, height, o, msg, msg_size);
    if (st != MF_OK)
        return st;
    int nl = count_levels(width, height);
    if (!out || level < 1 || level > nl) {
        if (msg && msg_size)
            snprintf(msg, msg_size, "level %d not in 1..%d", level, nl);
        return MF_ERR_DOMAIN;
    }
    const mf_brdf_model *base = mf_brdf_model_find(o->base == MF_PREFILTER_BASE_LAMBERT ? "lambert" : "ggx");
    double *lalb[16] = {0};
    if (!base)
        return MF_ERR_INTERNAL;
    pjob j;
    memset(&j, 0, sizeof j);
    j.normals = normals, j.width = width, j.height = height, j.nlevels = level, j.o = o, j.base = base;
    j.lalb = lalb, j.msg = msg, j.msg_size = msg_size;
    pthread_mutex_init(&j.lock, NULL);
    st = albedo_pyramid(&j, NULL, 0, level);
    pthread_mutex_destroy(&j.lock);
    if (st == MF_OK) {
        size_t n = (size_t)(width >> level > 0 ? width >> level : 1) * (height >> level > 0 ? height >> level : 1);
        memcpy(out, lalb[level - 1], sizeof(double) * 2 * n * o->n_theta * o->n_phi);
    }
    free(j.alb), free(j.uniq), free(lalb[level - 1]);
    return st;
}

mf_status mf_prefilter_run_from(const double *normals, int width, int height, const mf_prefilter_options *o,
                                int first_level, mf_prefilter_level **levels, int *nlevels, char *msg,
                                size_t msg_size)
{
    return mf_prefilter_run_tile(normals, width, height, o, first_level, NULL, 0, levels, nlevels, msg, msg_size);
}

mf_status mf_prefilter_run_tile(const double *normals, int width, int height, const mf_prefilter_options *o,
                                int first_level, const double *albedo_base, int base_level,
                                mf_prefilter_level **levels, int *nlevels, char *msg, size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
    if (!levels || !nlevels) {
        if (msg && msg_size)
            snprintf(msg, msg_size, "null argument");
        return MF_ERR_DOMAIN;
    }
    *levels = NULL;
    *nlevels = 0;
    mf_status st = check_run(normals, width, height, o, msg, msg_size);
    if (st != MF_OK)
        return st;
    const mf_brdf_model *base = mf_brdf_model_find(o->base == MF_PREFILTER_BASE_LAMBERT ? "lambert" : "ggx");
    if (!base)
        return MF_ERR_INTERNAL;
    int nl = count_levels(width, height);
    if (first_level < 1 || first_level > nl) {
        if (msg && msg_size)
            snprintf(msg, msg_size, "first level %d not in 1..%d", first_level, nl);
        return MF_ERR_DOMAIN;
    }
    if (albedo_base && (base_level < 0 || base_level >= first_level)) {
        if (msg && msg_size)
            snprintf(msg, msg_size, "albedo base level %d not in 0..%d", base_level, first_level - 1);
        return MF_ERR_DOMAIN;
    }
    mf_prefilter_level *lv = calloc((size_t)nl, sizeof *lv);
    double **lobes = calloc((size_t)nl, sizeof *lobes);
    double **lalb = calloc((size_t)nl, sizeof *lalb);
    size_t nv = (size_t)o->n_theta * o->n_phi;
    pjob j;
    memset(&j, 0, sizeof j);
    st = lv && lobes && lalb ? MF_OK : MF_ERR_ALLOC;
    for (int l = 0; l < nl && st == MF_OK; ++l) {
        lv[l].level = l + 1;
        lv[l].width = width >> (l + 1) > 0 ? width >> (l + 1) : 1;
        lv[l].height = height >> (l + 1) > 0 ? height >> (l + 1) : 1;
        lv[l].n_theta = o->n_theta;
        lv[l].n_phi = o->n_phi;
        if (l + 1 < first_level) { /* skipped: no texels, so the fit pass passes over it */
            lv[l].width = lv[l].height = 0;
            continue;
        }
        size_t n = (size_t)lv[l].width * lv[l].height * nv;
        lv[l].m = malloc(sizeof(float) * 9 * n);
        lv[l].magnitude = malloc(sizeof(float) * n);
        lv[l].albedo = malloc(sizeof(float) * n);
        lobes[l] = malloc(sizeof(double) * MF_LTCFIT_ANISO_NPARAMS * n);
        if (!lv[l].m || !lv[l].magnitude || !lv[l].albedo || !lobes[l])
            st = MF_ERR_ALLOC;
    }
    if (st == MF_OK) {
        j.normals = normals;
        j.width = width;
        j.height = height;
        j.nlevels = nl;
        j.o = o;
        j.base = base;
        j.levels = lv;
        j.lobes = lobes;
        j.lalb = lalb;
        j.msg = msg;
        j.msg_size = msg_size;
        pthread_mutex_init(&j.lock, NULL);
        pthread_mutex_init(&j.memo_lock, NULL);
        if (o->reuse && !(j.memo = calloc(MEMO_BUCKETS, sizeof *j.memo)))
            st = MF_ERR_ALLOC;
        if (st == MF_OK)
            st = albedo_pyramid(&j, albedo_base, base_level, first_level);
        /* coarse to fine: each level's fits read the parent level's lobes */
        for (int l = nl; l >= first_level && st == MF_OK; --l) {
            j.level = l;
            st = run_pass(&j, 1, (long)lv[l - 1].width * lv[l - 1].height);
            free(lalb[l - 1]);
            lalb[l - 1] = NULL;
        }
        memo_free(&j);
        pthread_mutex_destroy(&j.memo_lock);
        pthread_mutex_destroy(&j.lock);
    }
    free(j.alb), free(j.uniq);
    for (int l = 0; lalb && l < nl; ++l)
        free(lalb[l]);
    free(lalb);
    for (int l = 0; lobes && l < nl; ++l)
        free(lobes[l]);
    free(lobes);
    if (st != MF_OK) {
        mf_prefilter_levels_free(lv, nl);
        return st;
    }
    *levels = lv;
    *nlevels = nl;
    return MF_OK;
}

/* ---- shared with the gate (mf_prefilter_gate.c, through mf_prefilter_internal.h) ---------------- */

void mf_prefilter_min_rotation(const double *n, double *r) { min_rotation(n, r); }
mf_vec3 mf_prefilter_texel_view(const double *r, mf_vec3 wo) { return texel_view(r, wo); }
mf_vec3 mf_prefilter_rot_t(const double *r, mf_vec3 v) { return rot_t(r, v); }
