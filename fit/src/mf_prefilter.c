/* mf_prefilter.c -- the effective BRDF of a normal-map footprint as a model, and the per-level LTC
 * fits (mf_prefilter.h) [Nahmias 2022, Eq. 2.34-2.36, Ch. 3]. */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_prefilter.h"

#include "mfkit/fit/mf_ltcfit_aniso.h"

#include <math.h>
#include <pthread.h>
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

/* f cos and pdf of the mixture at (wo, wi), wo.z > 0 and wi.z > 0 (one pass over the components). */
static void mix_eval_pdf(const mf_prefilter_mix *x, const mf_brdf_params *p, mf_vec3 wo, mf_vec3 wi, double *f,
                         double *pdf)
{
    double sf = 0.0, sp = 0.0;
    for (int j = 0; j < x->n; ++j) {
        const double *r = x->rot + 9 * j;
        mf_vec3 vo = texel_view(r, wo), vi = rot_t(r, wi);
        sf += x->w[j] * x->base->eval_cos(x->base, p, vo, vi);
        sp += x->w[j] * x->base->pdf(x->base, p, vo, vi);
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

/* The texel from u[0] (the first j with u0 < cdf[j]) and u[0] rescaled into [0, 1) inside its
 * interval, then the base sampler at the texel's view, rotated to the geometric frame. */
static mf_vec3 mix_sample_texel(const mf_prefilter_mix *x, const mf_brdf_params *p, mf_vec3 wo, const double u[2],
                                double *base_pdf)
{
    int lo = 0, hi = x->n - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (u[0] < x->cdf[mid])
            hi = mid;
        else
            lo = mid + 1;
    }
    double c0 = lo > 0 ? x->cdf[lo - 1] : 0.0;
    double v[2] = {(u[0] - c0) / x->w[lo], u[1]};
    v[0] = fmin(fmax(v[0], 0.0), nextafter(1.0, 0.0));
    const double *r = x->rot + 9 * lo;
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
    mf_vec3 wi = mix_sample_texel(x, p, wo, u, &bp);
    if (bp > 0.0 && wi.z > 0.0 && mf_vec3_isfinite(wi)) {
        double f;
        mix_eval_pdf(x, p, wo, wi, &f, pdf);
    }
    return wi;
}

static void mix_sample_weights(const mf_brdf_model *m, const mf_brdf_params *p, mf_vec3 wo, int n, const double *u,
                               mf_vec3 *wi, double *pdf, double *w)
{
    const mf_prefilter_mix *x = mix_of(m);
    for (int i = 0; i < n; ++i) {
        pdf[i] = 0.0;
        w[i] = 0.0;
        if (!(wo.z > 0.0)) {
            wi[i] = mf_vec3_make(0.0, 0.0, 1.0);
            continue;
        }
        double bp;
        wi[i] = mix_sample_texel(x, p, wo, u + 2 * i, &bp);
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

mf_status mf_prefilter_mix_init(mf_prefilter_mix *m, const mf_brdf_model *base, const double *normals, int count)
{
    if (!m)
        return MF_ERR_DOMAIN;
    memset(m, 0, sizeof *m);
    if (!base || !base->sample || !base->pdf || !base->eval_cos || !normals || count < 1)
        return MF_ERR_DOMAIN;
    for (int i = 0; i < count; ++i)
        if (!(normals[3 * i + 2] > 0.0) || !isfinite(normals[3 * i]) || !isfinite(normals[3 * i + 1]))
            return MF_ERR_DOMAIN;
    m->rot = malloc(sizeof(double) * 9 * (size_t)count);
    m->w = malloc(sizeof(double) * (size_t)count);
    m->cdf = malloc(sizeof(double) * (size_t)count);
    int *cnt = calloc((size_t)count, sizeof *cnt), *first = malloc(sizeof(int) * (size_t)count);
    if (!m->rot || !m->w || !m->cdf || !cnt || !first) {
        free(cnt), free(first);
        mf_prefilter_mix_free(m);
        return MF_ERR_ALLOC;
    }
    /* merge bitwise equal normals (quadratic: footprints of a few thousand texels at most here) */
    int n = 0;
    for (int i = 0; i < count; ++i) {
        int j = 0;
        while (j < n && memcmp(normals + 3 * first[j], normals + 3 * i, 3 * sizeof(double)) != 0)
            ++j;
        if (j == n)
            first[n++] = i;
        cnt[j]++;
    }
    double acc = 0.0;
    for (int j = 0; j < n; ++j) {
        min_rotation(normals + 3 * first[j], m->rot + 9 * j);
        m->w[j] = (double)cnt[j] / count;
        acc += cnt[j];
        m->cdf[j] = acc / count;
    }
    m->cdf[n - 1] = 1.0;
    free(cnt), free(first);
    m->n = n;
    m->base = base;
    m->model.name = "prefilter-mix";
    m->model.description = "effective BRDF of a normal-map footprint (Nahmias 2022, Eq. 2.36)";
    m->model.flags = MF_MODEL_ANISOTROPIC;
    m->model.eval_cos = mix_eval_cos;
    m->model.sample = mix_sample;
    m->model.pdf = mix_pdf;
    m->model.sample_weights = mix_sample_weights;
    return MF_OK;
}

void mf_prefilter_mix_free(mf_prefilter_mix *m)
{
    if (!m)
        return;
    free(m->rot), free(m->w), free(m->cdf);
    m->rot = m->w = m->cdf = NULL;
    m->n = 0;
}

mf_status mf_prefilter_mix_albedo(const mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo, mf_result *out)
{
    if (!m || !p || !out || !(wo.z > 0.0))
        return MF_ERR_DOMAIN;
    double val = 0.0, err = 0.0;
    for (int j = 0; j < m->n; ++j) {
        mf_prefilter_mix one = *m; /* the one-texel mixture of component j */
        one.n = 1;
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

/* ---- the levels ------------------------------------------------------------------------------- */

void mf_prefilter_options_default(mf_prefilter_options *o)
{
    memset(o, 0, sizeof *o);
    o->alpha = 0.1;
    o->n_theta = 8;
    o->n_phi = 16;
    o->threads = 1;
    o->samples = 4096;
    o->max_iterations = 100;
    o->seed = 1;
}

double mf_prefilter_theta(const mf_prefilter_options *o, int i) { return i / (double)(o->n_theta - 1) * MF_PREFILTER_THETA_MAX; }
double mf_prefilter_phi(const mf_prefilter_options *o, int j) { return 2.0 * MF_PI * j / o->n_phi; }

void mf_prefilter_levels_free(mf_prefilter_level *levels, int nlevels)
{
    if (!levels)
        return;
    for (int l = 0; l < nlevels; ++l)
        free(levels[l].m), free(levels[l].magnitude);
    free(levels);
}

typedef struct {
    const double *normals;
    int width, height, nlevels;
    const mf_prefilter_options *o;
    const mf_brdf_model *base;
    mf_prefilter_level *levels;
    /* albedo cache: per level-0 texel and view, the one-texel albedo (value, error) */
    double *alb, *alb_err;
    int *uniq;   /* per texel: the index of the first texel with its (bitwise) normal */
    int job_kind; /* 0: albedo cache over texels, 1: fits over the footprints of all levels */
    long next, total;
    mf_status status;
    char *msg;
    size_t msg_size;
    pthread_mutex_t lock;
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

static mf_status albedo_texel(pjob *j, int t)
{
    const mf_prefilter_options *o = j->o;
    int nv = o->n_theta * o->n_phi;
    if (j->uniq[t] != t) /* a copy of an earlier texel's: filled after the pass */
        return MF_OK;
    mf_prefilter_mix one;
    mf_status st = mf_prefilter_mix_init(&one, j->base, j->normals + 3 * (size_t)t, 1);
    if (st != MF_OK)
        return st;
    mf_brdf_params p = mf_brdf_params_iso(o->alpha);
    for (int a = 0; a < o->n_theta && st == MF_OK; ++a)
        for (int b = 0; b < o->n_phi && st == MF_OK; ++b) {
            mf_result r;
            st = mf_prefilter_mix_albedo(&one, &p, view_dir(mf_prefilter_theta(o, a), mf_prefilter_phi(o, b)), &r);
            j->alb[(size_t)t * nv + a * o->n_phi + b] = r.val;
            j->alb_err[(size_t)t * nv + a * o->n_phi + b] = r.err;
        }
    mf_prefilter_mix_free(&one);
    return st;
}

/* One footprint: every view, chained along theta for each phi (warm start from the previous
 * elevation's lobe-frame parameters, taken by the fitter only where its cost is not above the
 * closed-form start's). */
static mf_status fit_footprint(pjob *j, int level, int row, int col, double *buf)
{
    const mf_prefilter_options *o = j->o;
    mf_prefilter_level *lv = &j->levels[level - 1];
    int fw = j->width / lv->width, fh = j->height / lv->height, nfoot = fw * fh;
    int nv = o->n_theta * o->n_phi;
    mf_ltcfit_aniso_options fo;
    mf_ltcfit_aniso_options_default(&fo);
    fo.samples = o->samples;
    fo.max_iterations = o->max_iterations;
    fo.seed = o->seed;
    mf_brdf_params p = mf_brdf_params_iso(o->alpha);
    mf_status st = MF_OK;
    for (int b = 0; b < o->n_phi && st == MF_OK; ++b) {
        double phi = mf_prefilter_phi(o, b), c = cos(phi), s = sin(phi);
        /* the footprint's normals in the view-azimuth-aligned frame (rotated by -phi about z) */
        int k = 0;
        for (int y = row * fh; y < (row + 1) * fh; ++y)
            for (int x = col * fw; x < (col + 1) * fw; ++x, ++k) {
                const double *n = j->normals + 3 * ((size_t)y * j->width + x);
                buf[3 * k] = c * n[0] + s * n[1];
                buf[3 * k + 1] = -s * n[0] + c * n[1];
                buf[3 * k + 2] = n[2];
            }
        mf_prefilter_mix mix;
        if ((st = mf_prefilter_mix_init(&mix, j->base, buf, nfoot)) != MF_OK)
            break;
        double prev[MF_LTCFIT_ANISO_NPARAMS];
        int have_prev = 0;
        for (int a = 0; a < o->n_theta; ++a) {
            double alb = 0.0, err = 0.0;
            for (int y = row * fh; y < (row + 1) * fh; ++y)
                for (int x = col * fw; x < (col + 1) * fw; ++x) {
                    size_t q = (size_t)y * j->width + x;
                    alb += j->alb[q * nv + a * o->n_phi + b];
                    err += j->alb_err[q * nv + a * o->n_phi + b];
                }
            alb /= nfoot, err /= nfoot;
            mf_ltcfit_aniso_entry e;
            st = mf_ltcfit_aniso_entry_fit_general(&mix.model, p, mf_prefilter_theta(o, a), 0.0, alb, err,
                                                   have_prev ? prev : NULL, &fo, &e);
            if (st != MF_OK)
                break;
            memcpy(prev, e.lobe, sizeof prev);
            have_prev = 1;
            size_t idx = (((size_t)row * lv->width + col) * o->n_theta + a) * o->n_phi + b;
            for (int i = 0; i < 9; ++i)
                lv->m[9 * idx + i] = (float)e.m[i];
            lv->magnitude[idx] = (float)alb;
            pthread_mutex_lock(&j->lock);
            if (e.residual > lv->worst_residual)
                lv->worst_residual = e.residual;
            if (err > lv->worst_albedo_err)
                lv->worst_albedo_err = err;
            lv->not_converged += !e.converged;
            lv->iterations += e.iterations;
            lv->lobes++;
            pthread_mutex_unlock(&j->lock);
            if (!(isfinite(e.m[0]) && isfinite(e.m[4]) && isfinite(e.m[8]))) {
                st = MF_ERR_INTERNAL;
                break;
            }
        }
        mf_prefilter_mix_free(&mix);
    }
    return st;
}

static void *worker(void *arg)
{
    pjob *j = arg;
    double *buf = malloc(sizeof(double) * 3 * (size_t)j->width * j->height);
    if (!buf) {
        set_error(j, MF_ERR_ALLOC, "out of memory");
        return NULL;
    }
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
            int l = 0;
            while (t >= (long)j->levels[l].width * j->levels[l].height)
                t -= (long)j->levels[l].width * j->levels[l].height, ++l;
            st = fit_footprint(j, l + 1, (int)(t / j->levels[l].width), (int)(t % j->levels[l].width), buf);
        }
        if (st != MF_OK) {
            char text[128];
            snprintf(text, sizeof text, "%s: %s", j->job_kind ? "LTC fit" : "albedo", mf_status_str(st));
            set_error(j, st, text);
        }
    }
    free(buf);
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

mf_status mf_prefilter_run_from(const double *normals, int width, int height, const mf_prefilter_options *o,
                                int first_level, mf_prefilter_level **levels, int *nlevels, char *msg,
                                size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = '\0';
#define FAIL(...) (msg && msg_size ? (void)snprintf(msg, msg_size, __VA_ARGS__) : (void)0), MF_ERR_DOMAIN
    if (!normals || !o || !levels || !nlevels)
        return FAIL("null argument");
    *levels = NULL;
    *nlevels = 0;
    if (!(o->alpha > 0.0 && o->alpha <= 1.0))
        return FAIL("roughness %g not in (0, 1]", o->alpha);
    if (o->n_theta < 2 || o->n_theta > 256 || o->n_phi < 1 || o->n_phi > 256)
        return FAIL("views %d x %d: need 2..256 elevations x 1..256 azimuths", o->n_theta, o->n_phi);
    if (o->threads < 1 || o->threads > 256)
        return FAIL("threads %d not in 1..256", o->threads);
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
    const mf_brdf_model *base = mf_brdf_model_find("ggx");
    if (!base)
        return MF_ERR_INTERNAL;
    int nl = 0;
    while ((width >> nl) > 1 || (height >> nl) > 1)
        ++nl;
    if (first_level < 1 || first_level > nl) {
        if (msg && msg_size)
            snprintf(msg, msg_size, "first level %d not in 1..%d", first_level, nl);
        return MF_ERR_DOMAIN;
    }
    mf_prefilter_level *lv = calloc((size_t)nl, sizeof *lv);
    size_t ntex = (size_t)width * height, nv = (size_t)o->n_theta * o->n_phi;
    pjob j;
    memset(&j, 0, sizeof j);
    j.alb = malloc(sizeof(double) * ntex * nv);
    j.alb_err = malloc(sizeof(double) * ntex * nv);
    j.uniq = malloc(sizeof(int) * ntex);
    mf_status st = lv && j.alb && j.alb_err && j.uniq ? MF_OK : MF_ERR_ALLOC;
    long total = 0;
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
        if (!lv[l].m || !lv[l].magnitude)
            st = MF_ERR_ALLOC;
        total += (long)lv[l].width * lv[l].height;
    }
    if (st == MF_OK) {
        /* texels with bitwise equal normals share their albedos: the first one computes them */
        for (size_t t = 0; t < ntex; ++t) {
            size_t u = 0;
            while (memcmp(normals + 3 * u, normals + 3 * t, 3 * sizeof(double)) != 0)
                ++u;
            j.uniq[t] = (int)u;
        }
        j.normals = normals;
        j.width = width;
        j.height = height;
        j.nlevels = nl;
        j.o = o;
        j.base = base;
        j.levels = lv;
        j.msg = msg;
        j.msg_size = msg_size;
        pthread_mutex_init(&j.lock, NULL);
        st = run_pass(&j, 0, (long)ntex);
        if (st == MF_OK) {
            for (size_t t = 0; t < ntex; ++t)
                if (j.uniq[t] != (int)t) {
                    memcpy(j.alb + t * nv, j.alb + (size_t)j.uniq[t] * nv, sizeof(double) * nv);
                    memcpy(j.alb_err + t * nv, j.alb_err + (size_t)j.uniq[t] * nv, sizeof(double) * nv);
                }
            st = run_pass(&j, 1, total);
        }
        pthread_mutex_destroy(&j.lock);
    }
    free(j.alb), free(j.alb_err), free(j.uniq);
    if (st != MF_OK) {
        mf_prefilter_levels_free(lv, nl);
        return st;
    }
    *levels = lv;
    *nlevels = nl;
    return MF_OK;
}
