/*
 * mf_ltc_bake.c -- fit -> gate -> export of an isotropic LTC table (see mf_ltc_bake.h).
 */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_ltc_bake.h"
#include "mfkit/fit/mf_ltcfit_hdrp.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_json.h"
#include "mfkit/io/mf_ltc_export.h"
#include "mfkit/io/mf_ltc_shader.h"
#include "mfkit/io/mf_table_io.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void mf_ltc_bake_options_default(mf_ltc_bake_options *o)
{
    memset(o, 0, sizeof *o);
    mf_ltcfit_options_default(&o->fit);
    o->out_dir = "out";
    o->tool = "mf_ltc_bake";
    o->version = "";
}

static double now_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void set_msg(mf_ltc_bake_report *r, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->message, sizeof r->message, fmt, ap);
    va_end(ap);
}

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* ---- the texel check (mf_ltc_bake_texel_check; docs/validation.md, "The texel check") ---------
 * Why a fresh fit and not the BRDF: a good table's own error against the BRDF exceeds 10 % at
 * many texels (its shape family cannot follow the BRDF), so no bound on that error both passes a
 * good table and catches a texel changed by 10 %; the "10 % from the fitted texel" needs
 * the fitted texel, which only the fitter can recompute.  Why several starts: a refit from the
 * stored texel converges to the same texel within 1 % at 98.5 % of the default table's texels
 * (measured, 4096 samples), but where the objective is flat (grazing views of low roughness)
 * the table's fitter keeps its texel near the previous texel of the column (its proximal terms)
 * and the unconstrained refit drifts up to 16 %; started from that previous texel, as the
 * table's fitter started, it lands within 6 % of the stored texel. */

#define TEXEL_CHECK_STEPS 3 /* solver steps of the first refit: the fit converges in 4 on average */
/* A texel whose d exceeds half the bound gets the further refits: a good texel then reads well
 * below the bound (Beckmann 32 x 32 read 0.098 at alpha 0.23, 34.5 deg when only texels above
 * the bound got them), and a corrupted one reads about the same in every refit. */
#define TEXEL_ESCALATE (0.5 * MF_LTC_GATE_TEXEL_REL)
/* A first refit whose residual is above 2 x its neighbours' largest (+ 0.01) is an outlier and
 * gets the further refits; among the refits of a texel, only those within 2 x the best residual
 * (+ 0.01) count.  Why: a refit started from a grossly wrong texel can stay stuck near it
 * (minv_22 set to 0 turned a GGX texel, alpha 0.82, 18 deg, into a needle lobe; 3 steps from it
 * gave d = 0.0001 against the corrupted texel, which differed from the fitted one by 1.13); a
 * stuck refit fits the lights much worse than its neighbours' refits do. */
#define TEXEL_RESIDUAL_OUTLIER 2.0
#define TEXEL_RESIDUAL_FLOOR 0.01
#define MF_LTC_BAKE_GATE_MC_SAMPLES 16384 /* Monte Carlo samples of the gate's polygon checks (see mf_ltc_bake) */

typedef struct texel_job {
    const mf_table *t;
    const mf_brdf_model *model;
    mf_ltcfit_options quick, full;
    uint64_t seed;
    int nr, nu, threads, npoly;
    int pass;       /* 1: the first refit of every texel; 2: the further refits where needed */
    double *d1, *r1; /* per texel: d and residual of the first refit (NaN: not computed) */
    double *val;    /* per texel: the check's value, +inf if unusable */
    const double *albedo; /* NULL, or 2 per texel: mf_ltc_gate_texel_albedo (the refits' magnitude) */
    signed char *stage; /* per texel: the refit that gave val (1..4), 0 if unusable */
    mf_status status;
} texel_job;

/* d of the stored texel (ltc, mag) against a refit from the view-frame matrix `start` with
 * options o, and the refit's residual (the fitter's RMS of weighted light residuals); +inf
 * for both if the refit failed. */
static double texel_refit_d(texel_job *j, int ir, int iu, const mf_ltc *ltc, double mag, const mf_mat3 *start,
                            const mf_ltcfit_options *o, const mf_polygon *polys, double *residual)
{
    double m9[9];
    for (int i = 0; i < 9; ++i)
        m9[i] = start->m[i / 3][i % 3];
    mf_ltcfit_entry e;
    *residual = INFINITY;
    /* the model's albedo at the texel, when the caller computed it (the rule the fitter uses: the
     * same refit, bit for bit, without its quadrature) */
    size_t k = (size_t)ir + (size_t)j->nr * (size_t)iu;
    mf_result alb, *albp = NULL;
    if (j->albedo && isfinite(j->albedo[2 * k])) {
        alb.val = j->albedo[2 * k];
        alb.err = j->albedo[2 * k + 1];
        albp = &alb;
    }
    mf_status st = mf_ltcfit_entry_fit_albedo(j->model, mf_ltc_table_alpha(j->t, ir), mf_ltc_table_cos_theta(j->t, iu),
                                              m9, o, albp, &e);
    if (st == MF_ERR_ALLOC)
        j->status = MF_ERR_ALLOC;
    if (st != MF_OK)
        return INFINITY;
    mf_mat3 m;
    for (int i = 0; i < 9; ++i)
        m.m[i / 3][i % 3] = e.m[i];
    mf_ltc ref;
    if (mf_ltc_init(&ref, m) != MF_OK)
        return INFINITY;
    double d = mf_ltc_gate_texel_difference(ltc, mag, &ref, e.magnitude, polys, j->npoly, NULL);
    if (isnan(d) || !isfinite(e.residual))
        return INFINITY;
    *residual = e.residual;
    return d;
}

/* Pass 1 at texel k: the first refit (from the stored texel, few directions, few steps). */
static void texel_pass1(texel_job *j, size_t k, mf_polygon *polys)
{
    int ir = (int)(k % (size_t)j->nr), iu = (int)(k / (size_t)j->nr);
    mf_ltc ltc;
    double mag;
    j->d1[k] = j->r1[k] = INFINITY;
    if (mf_ltc_gate_texel(j->t, ir, iu, &ltc, &mag) != MF_OK)
        return;
    mf_ltc_gate_texel_polygons(j->t, j->model, j->seed, ir, iu, j->npoly, polys);
    j->d1[k] = texel_refit_d(j, ir, iu, &ltc, mag, &ltc.m, &j->quick, polys, &j->r1[k]);
}

/* Pass 2 at texel k (pass 1 done at k and its neighbours): the value and the refit that gave it. */
static void texel_pass2(texel_job *j, size_t k, mf_polygon *polys)
{
    int ir = (int)(k % (size_t)j->nr), iu = (int)(k / (size_t)j->nr);
    mf_ltc ltc, prev;
    double mag, pmag;
    j->val[k] = INFINITY;
    j->stage[k] = 0;
    if (mf_ltc_gate_texel(j->t, ir, iu, &ltc, &mag) != MF_OK)
        return;
    /* the first refit's residual against its neighbours' (an outlier: the refit may be stuck
     * near a wrong texel, see TEXEL_RESIDUAL_OUTLIER) */
    double rn = 0.0;
    const int nb[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
    for (int n = 0; n < 4; ++n) {
        int r2 = ir + nb[n][0], u2 = iu + nb[n][1];
        if (r2 < 0 || u2 < 0 || r2 >= j->nr || u2 >= j->nu)
            continue;
        double v = j->r1[(size_t)r2 + (size_t)j->nr * (size_t)u2];
        if (isfinite(v) && v > rn)
            rn = v;
    }
    double d1 = j->d1[k], r1 = j->r1[k];
    int outlier = !(r1 <= TEXEL_RESIDUAL_OUTLIER * rn + TEXEL_RESIDUAL_FLOOR);
    if (!(d1 > TEXEL_ESCALATE) && !outlier) {
        j->val[k] = d1;
        j->stage[k] = 1;
        return;
    }
    /* the further refits: from the stored texel with the fit's settings, and from the previous
     * texel of the column as the table's fitter starts; the value is the smallest d among the
     * refits whose residual is within TEXEL_RESIDUAL_OUTLIER of the best one (a refit stuck
     * near a corrupted start fits worse than one that found the fitted texel) */
    mf_ltc_gate_texel_polygons(j->t, j->model, j->seed, ir, iu, j->npoly, polys);
    double d[4] = {d1, INFINITY, INFINITY, INFINITY}, r[4] = {r1, INFINITY, INFINITY, INFINITY};
    d[1] = texel_refit_d(j, ir, iu, &ltc, mag, &ltc.m, &j->full, polys, &r[1]);
    if (iu > 0 && mf_ltc_gate_texel(j->t, ir, iu - 1, &prev, &pmag) == MF_OK) {
        /* 3: the previous texel as stored; 4: its lobe turned about y by the change of the view
         * angle, so that it keeps its place relative to the mirror direction.  The table's
         * fitter starts from the previous lobe-frame shape about the new lobe, which neither
         * reproduces exactly; each is the one that finds the stored texel somewhere (GGX 32 x 32,
         * 89.95 deg: at alpha 0.004 the stored start gives d 18 with a residual 4x the best and
         * the turned one d 0.077; at alpha 0.0094, 0.012 and 0.127) */
        d[2] = texel_refit_d(j, ir, iu, &ltc, mag, &prev.m, &j->full, polys, &r[2]);
        double dphi = acos(mf_ltc_table_cos_theta(j->t, iu - 1)) - acos(mf_ltc_table_cos_theta(j->t, iu));
        mf_mat3 ry = {{{cos(dphi), 0.0, sin(dphi)}, {0.0, 1.0, 0.0}, {-sin(dphi), 0.0, cos(dphi)}}};
        mf_mat3 start = mf_mat3_mul(ry, prev.m);
        d[3] = texel_refit_d(j, ir, iu, &ltc, mag, &start, &j->full, polys, &r[3]);
    }
    double rbest = fmin(fmin(r[0], r[1]), fmin(r[2], r[3]));
    double v = INFINITY;
    int best = 0;
    for (int i = 0; i < 4; ++i)
        if (r[i] <= TEXEL_RESIDUAL_OUTLIER * rbest + TEXEL_RESIDUAL_FLOOR && d[i] < v) {
            v = d[i];
            best = i + 1;
        }
    j->val[k] = v;
    j->stage[k] = (signed char)(isfinite(v) ? best : 0);
}

static void texel_job_init(texel_job *j, const mf_table *t, const mf_brdf_model *model, const mf_ltcfit_options *fit,
                           uint64_t gate_seed, int threads)
{
    memset(j, 0, sizeof *j);
    j->t = t;
    j->model = model;
    j->seed = gate_seed;
    j->nr = (int)t->axes[0].size;
    j->nu = (int)t->axes[1].size;
    j->npoly = MF_LTC_GATE_TEXEL_POLYGONS;
    j->threads = threads > 256 ? 256 : threads;
    j->full = *fit;
    j->full.threads = 1;
    j->full.checkpoint = NULL;
    j->full.resume = 0;
    j->full.cancel = NULL;
    j->full.progress = NULL;
    j->full.albedo = NULL; /* the refits get the albedo per texel (texel_refit_d) */
    j->quick = j->full;
    j->quick.samples = fit->samples / 4 >= 64 ? fit->samples / 4 : 64;
    j->quick.max_iterations = TEXEL_CHECK_STEPS < fit->max_iterations ? TEXEL_CHECK_STEPS : fit->max_iterations;
    j->status = MF_OK;
}

static int texel_job_alloc(texel_job *j)
{
    size_t n = (size_t)j->nr * (size_t)j->nu;
    j->d1 = malloc(sizeof *j->d1 * n);
    j->r1 = malloc(sizeof *j->r1 * n);
    j->val = malloc(sizeof *j->val * n);
    j->stage = malloc(n);
    if (!j->d1 || !j->r1 || !j->val || !j->stage)
        return 0;
    for (size_t k = 0; k < n; ++k)
        j->d1[k] = j->r1[k] = NAN;
    return 1;
}

static void texel_job_free(texel_job *j)
{
    free(j->d1);
    free(j->r1);
    free(j->val);
    free(j->stage);
}

double mf_ltc_bake_texel_value(const mf_table *t, const mf_brdf_model *model, const mf_ltcfit_options *fit,
                               uint64_t gate_seed, int ir, int iu, int *refit)
{
    if (refit)
        *refit = 0;
    if (!model || !fit || !mf_ltc_gate_layout_ok(t, NULL, 0) || ir < 0 || iu < 0 || ir >= (int)t->axes[0].size ||
        iu >= (int)t->axes[1].size)
        return NAN;
    texel_job j;
    texel_job_init(&j, t, model, fit, gate_seed, 1);
    if (!texel_job_alloc(&j)) {
        texel_job_free(&j);
        return NAN;
    }
    mf_polygon polys[MF_LTC_GATE_TEXEL_POLYGONS];
    const int nb[5][2] = {{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}};
    for (int n = 0; n < 5; ++n) {
        int r2 = ir + nb[n][0], u2 = iu + nb[n][1];
        if (r2 >= 0 && u2 >= 0 && r2 < j.nr && u2 < j.nu)
            texel_pass1(&j, (size_t)r2 + (size_t)j.nr * (size_t)u2, polys);
    }
    size_t k = (size_t)ir + (size_t)j.nr * (size_t)iu;
    texel_pass2(&j, k, polys);
    double v = j.val[k];
    if (refit)
        *refit = j.stage[k];
    texel_job_free(&j);
    return v;
}

typedef struct texel_worker_arg {
    texel_job *j;
    int id;
} texel_worker_arg;

static void *texel_worker(void *arg)
{
    texel_worker_arg *a = arg;
    texel_job *j = a->j;
    mf_polygon polys[MF_LTC_GATE_TEXEL_POLYGONS];
    /* texel k goes to worker k mod threads: each texel is computed alone (pass 2 reads pass 1's
     * finished results), so the values do not depend on the thread count */
    for (size_t k = (size_t)a->id; k < (size_t)j->nr * (size_t)j->nu; k += (size_t)j->threads) {
        if (j->pass == 1)
            texel_pass1(j, k, polys);
        else
            texel_pass2(j, k, polys);
    }
    return NULL;
}

static void texel_run_pass(texel_job *j, int pass)
{
    pthread_t tid[256];
    texel_worker_arg args[256];
    int started[256] = {0};
    j->pass = pass;
    for (int i = 0; i < j->threads; ++i) {
        args[i].j = j;
        args[i].id = i;
        if (i > 0)
            started[i] = pthread_create(&tid[i], NULL, texel_worker, &args[i]) == 0;
    }
    texel_worker(&args[0]);
    for (int i = 1; i < j->threads; ++i) {
        if (started[i])
            pthread_join(tid[i], NULL);
        else
            texel_worker(&args[i]); /* no thread: this worker's texels run here */
    }
}

/* mf_ltc_bake_texel_check with the model's albedo per texel given (NULL: each refit computes it). */
static mf_status texel_check(const mf_table *t, const mf_brdf_model *model, const mf_ltcfit_options *fit,
                             uint64_t gate_seed, int threads, const double *albedo, mf_check *c)
{
    if (!c || !model || !fit || threads < 1 || !mf_ltc_gate_layout_ok(t, NULL, 0))
        return MF_ERR_DOMAIN;
    mf_check_begin(c, "ltc_texel_refit",
                   "max over texels of the shading difference d from a fresh fit of the texel (gate polygons)",
                   MF_LTC_GATE_TEXEL_REL);
    texel_job j;
    texel_job_init(&j, t, model, fit, gate_seed, threads);
    j.albedo = albedo;
    if (!texel_job_alloc(&j)) {
        texel_job_free(&j);
        mf_check_fail(c, "out of memory");
        return MF_ERR_ALLOC;
    }
    texel_run_pass(&j, 1);
    texel_run_pass(&j, 2);
    size_t n = (size_t)j.nr * (size_t)j.nu;
    long staged[5] = {0, 0, 0, 0, 0};
    for (size_t k = 0; k < n; ++k) {
        int ir = (int)(k % (size_t)j.nr), iu = (int)(k / (size_t)j.nr);
        ++staged[j.stage[k] >= 0 && j.stage[k] <= 4 ? j.stage[k] : 0];
        mf_check_recordf(c, j.val[k], "%s (ir %d, iu %d: alpha %.4g, theta %.2f deg)",
                         j.stage[k] ? "shading vs refit" : "texel cannot be unpacked or refitted", ir, iu,
                         mf_ltc_table_alpha(t, ir), acos(mf_ltc_table_cos_theta(t, iu)) * 180.0 / MF_PI);
    }
    snprintf(c->what, sizeof c->what,
             "max over texels of min over refits of d (gate polygons, > 0.02 albedo); refits 1/2/3/4: %ld/%ld/%ld/%ld",
             staged[1], staged[2], staged[3], staged[4]);
    mf_check_finish(c);
    mf_status st = j.status;
    texel_job_free(&j);
    if (st != MF_OK) {
        mf_check_fail(c, "out of memory");
        return st;
    }
    return MF_OK;
}

mf_status mf_ltc_bake_texel_check(const mf_table *t, const mf_brdf_model *model, const mf_ltcfit_options *fit,
                                  uint64_t gate_seed, int threads, mf_check *c)
{
    return texel_check(t, model, fit, gate_seed, threads, NULL, c);
}

/* The model's albedo and Fresnel moment at every texel of the table's layout
 * (mf_ltc_gate_texel_albedo_fresnel; 3 doubles per texel: albedo, its error, moment; NaN where it
 * fails), over threads, before the fit: the gate's quadrature, which the fitter takes for its
 * magnitude and Fresnel fields (mf_ltcfit_options.albedo: the values it would compute, so the same
 * table) and the gate's albedo checks and the texel check's refits use in turn.  One quadrature
 * per texel instead of two.  The gate's albedo stays its own: computed from the model at the
 * table's axes by the gate's routine, not read from the fit, and ltc_energy / ltc_albedo_quad still
 * compare the table's magnitude field with it.  Texel k goes to worker k mod threads; each value
 * is computed alone, so the array does not depend on the thread count. */
typedef struct albedo_job {
    const mf_table *t;
    const mf_brdf_model *model;
    double *out;
    int threads, id;
} albedo_job;

static void *albedo_worker(void *arg)
{
    albedo_job *a = arg;
    const int nr = (int)a->t->axes[0].size;
    const size_t n = (size_t)nr * a->t->axes[1].size;
    for (size_t k = (size_t)a->id; k < n; k += (size_t)a->threads) {
        mf_result r, f;
        if (mf_ltc_gate_texel_albedo_fresnel(a->t, a->model, (int)(k % (size_t)nr), (int)(k / (size_t)nr), &r, &f) ==
            MF_OK) {
            a->out[3 * k] = r.val;
            a->out[3 * k + 1] = r.err;
            a->out[3 * k + 2] = f.val;
        } else {
            a->out[3 * k] = a->out[3 * k + 1] = a->out[3 * k + 2] = NAN;
        }
    }
    return NULL;
}

/* NULL if out of memory (the fit and the gate then compute the albedo themselves).  t: any table
 * of the fit's layout (its fields are not read). */
static double *texel_albedos(const mf_table *t, const mf_brdf_model *model, int threads)
{
    const size_t n = (size_t)t->axes[0].size * t->axes[1].size;
    double *out = malloc(sizeof *out * 3 * n);
    if (!out)
        return NULL;
    if (threads > 256)
        threads = 256;
    pthread_t tid[256];
    albedo_job args[256];
    int started[256] = {0};
    for (int i = 0; i < threads; ++i) {
        albedo_job a = {t, model, out, threads, i};
        args[i] = a;
        if (i > 0)
            started[i] = pthread_create(&tid[i], NULL, albedo_worker, &args[i]) == 0;
    }
    albedo_worker(&args[0]);
    for (int i = 1; i < threads; ++i) {
        if (started[i])
            pthread_join(tid[i], NULL);
        else
            albedo_worker(&args[i]);
    }
    return out;
}

typedef struct gate_thread_arg {
    const mf_table *t;
    const mf_brdf_model *model;
    const mf_ltc_gate_options *go;
    mf_check *checks;
    int cap, n;
    mf_status st;
} gate_thread_arg;

static void *gate_thread(void *arg)
{
    gate_thread_arg *a = arg;
    a->st = mf_ltc_gate_run(a->t, a->model, a->go, a->checks, a->cap, &a->n);
    return NULL;
}

/* ---- the gate report (JSON) ------------------------------------------------------------------
 * The format of the command line's check reports (mf_json_checks), after the fit's summary;
 * non-finite numbers as the strings of mf_json.h. */
static void gate_json(mf_buf *b, const mf_ltc_bake_options *o, const mf_ltc_bake_report *r)
{
    mf_buf_puts(b, "{\n  \"tool\": ");
    mf_json_string(b, o->tool ? o->tool : "mf_ltc_bake");
    mf_buf_puts(b, ",\n  \"version\": ");
    mf_json_string(b, o->version ? o->version : "");
    mf_buf_puts(b, ",\n  \"brdf\": ");
    mf_json_string(b, o->model->name);
    mf_buf_puts(b, ",\n  \"passed\": ");
    mf_json_bool(b, r->gate_passed);
    mf_buf_puts(b, ",\n  \"fit\": {\"worst_residual\": ");
    mf_json_number(b, r->fit.worst_residual);
    mf_buf_printf(b, ", \"max_iterations\": %d, \"total_iterations\": %ld, \"not_converged\": %d},\n  \"checks\": ",
                  r->fit.max_iterations, r->fit.total_iterations, r->fit.not_converged);
    mf_json_checks(b, r->checks, r->nchecks);
    mf_buf_puts(b, "\n}\n");
}

/* ---- export ---------------------------------------------------------------------------------- */

static mf_status add_file(mf_ltc_bake_report *r, const char *dir, const char *suffix, char **path)
{
    if (r->nfiles >= MF_LTC_BAKE_MAX_FILES)
        return MF_ERR_INTERNAL;
    char *p = r->files[r->nfiles];
    int n = snprintf(p, MF_LTC_BAKE_PATH_LEN, "%s/%s%s", dir, r->stem, suffix);
    if (n < 0 || n >= MF_LTC_BAKE_PATH_LEN) {
        set_msg(r, "%s: path too long", dir);
        return MF_ERR_DOMAIN;
    }
    *path = p;
    return MF_OK;
}

enum { EX_TABLE, EX_THREEJS, EX_EEVEE, EX_RGBA_EXR };

static mf_status export_all(const mf_ltc_bake_options *o, const mf_table *t, mf_ltc_bake_report *r)
{
    /* The first eleven are the generic formats (docs/tables.md); the rest the engine layouts
     * (mf_ltc_export.h, docs/tables.md "Engines"). */
    static const struct {
        const char *suffix;
        int half;
        int dds_set; /* 0 all fields, 1 ltc_1, 2 ltc_2 (DDS channels; EX_RGBA_EXR: which texture) */
        int kind;
        int legacy;  /* DDS: legacy header */
        int zstd;    /* KTX2: Zstandard level */
    } files[] = {{".exr", 0, 0, EX_TABLE, 0, 0},         {"_half.exr", 1, 0, EX_TABLE, 0, 0},
                 {"_1.dds", 0, 1, EX_TABLE, 0, 0},       {"_2.dds", 0, 2, EX_TABLE, 0, 0},
                 {"_1_f16.dds", 1, 1, EX_TABLE, 0, 0},   {"_2_f16.dds", 1, 2, EX_TABLE, 0, 0},
                 {".h", 0, 0, EX_TABLE, 0, 0},           {".glsl", 0, 0, EX_TABLE, 0, 0},
                 {".hlsl", 0, 0, EX_TABLE, 0, 0},        {".json", 0, 0, EX_TABLE, 0, 0},
                 {".npy", 0, 0, EX_TABLE, 0, 0},         {"_legacy_1.dds", 0, 1, EX_TABLE, 1, 0},
                 {"_legacy_2.dds", 0, 2, EX_TABLE, 1, 0}, {".ktx2", 0, 0, EX_TABLE, 0, 0},
                 {"_f16.ktx2", 1, 0, EX_TABLE, 0, 19},   {"_1.exr", 0, 1, EX_RGBA_EXR, 0, 0},
                 {"_2.exr", 0, 2, EX_RGBA_EXR, 0, 0},    {"_three.js", 0, 0, EX_THREEJS, 0, 0},
                 {"_eevee.h", 0, 0, EX_EEVEE, 0, 0}};
    char msg[1024];
    char *path;
    mf_status st;
    const int dropin = mf_ltc_table_is_dropin(t);
    for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
        /* three.js and EEVEE hard-code the 64 x 64 default layout: other tables leave them out */
        if ((files[i].kind == EX_THREEJS || files[i].kind == EX_EEVEE) && !dropin)
            continue;
        if ((st = add_file(r, o->out_dir, files[i].suffix, &path)) != MF_OK)
            return st;
        /* EXR goes through the image API: without a backend (a build without OpenImageIO) the EXR
         * files are left out, and report->files lists what was written. */
        if (mf_table_format_from_path(path) == MF_TABLE_FORMAT_EXR && !mf_image_get_backend())
            continue;
        if (files[i].kind == EX_THREEJS)
            st = mf_ltc_write_threejs(path, t, msg, sizeof msg);
        else if (files[i].kind == EX_EEVEE)
            st = mf_ltc_write_eevee(path, t, NULL, msg, sizeof msg);
        else if (files[i].kind == EX_RGBA_EXR)
            st = mf_ltc_write_rgba_exr(path, t, files[i].dds_set, files[i].half, msg, sizeof msg);
        else {
            mf_table_write_options wo;
            mf_table_write_options_default(&wo);
            wo.half_float = files[i].half;
            wo.prefix = r->stem;
            wo.dds_legacy = files[i].legacy;
            wo.zstd_level = files[i].zstd;
            if (files[i].dds_set) {
                wo.dds_fields_set = 1;
                int base = files[i].dds_set == 1 ? MF_LTC_F_MINV_00 : MF_LTC_F_MAGNITUDE;
                for (int c = 0; c < 4; ++c)
                    wo.dds_fields[c] = base + c;
            }
            st = mf_table_write(path, t, &wo, NULL, msg, sizeof msg);
        }
        if (st != MF_OK) {
            set_msg(r, "%s (%s)", msg[0] ? msg : path, mf_status_str(st));
            return st;
        }
        ++r->nfiles;
    }
    if (dropin && o->hdrp) { /* <stem>_hdrp.cs: Unity HDRP's LTC data, fitted on its grid (mf_ltcfit_hdrp.h) */
        const int n = MF_LTC_HDRP_SIZE;
        double *rows = malloc((size_t)n * n * 9 * sizeof *rows);
        mf_ltcfit_hdrp_report hr;
        char note[160];
        if (!rows)
            return MF_ERR_ALLOC;
        if ((st = mf_ltcfit_hdrp(o->model, t, &o->fit, n, rows, &hr)) != MF_OK) {
            free(rows);
            set_msg(r, "HDRP fit (%s)", mf_status_str(st));
            return st;
        }
        snprintf(note, sizeof note, "%d x %d texels fitted, %d kept at mfkit's interpolated start; worst residual %.3g",
                 n, n, hr.fallbacks, hr.worst_residual);
        if ((st = add_file(r, o->out_dir, "_hdrp.cs", &path)) == MF_OK)
            st = mf_ltc_write_hdrp(path, rows, n, NULL, note, msg, sizeof msg);
        free(rows);
        if (st != MF_OK) {
            set_msg(r, "%s", msg);
            return st;
        }
        ++r->nfiles;
    }
    for (int l = 0; l < 3; ++l) { /* <stem>_area.glsl/.hlsl/.wgsl: the area-light code (mf_ltc_shader.h) */
        char suffix[16];
        snprintf(suffix, sizeof suffix, "_area.%s", mf_shader_lang_name((mf_shader_lang)l));
        if ((st = add_file(r, o->out_dir, suffix, &path)) != MF_OK)
            return st;
        if ((st = mf_ltc_shader_write(path, t, (mf_shader_lang)l, r->stem, msg, sizeof msg)) != MF_OK) {
            set_msg(r, "%s", msg);
            return st;
        }
        ++r->nfiles;
    }
    if ((st = add_file(r, o->out_dir, "_fit.json", &path)) != MF_OK)
        return st;
    st = mf_ltcfit_write_sidecar(path, o->model, &o->fit, t, &r->fit, msg, sizeof msg);
    if (st != MF_OK) {
        set_msg(r, "%s", msg[0] ? msg : path);
        return st;
    }
    ++r->nfiles;
    if ((st = add_file(r, o->out_dir, "_gate.json", &path)) != MF_OK)
        return st;
    mf_buf b = {0};
    gate_json(&b, o, r);
    st = mf_io_write_buf_atomic(path, &b, msg, sizeof msg);
    mf_buf_free(&b);
    if (st != MF_OK) {
        set_msg(r, "%s", msg);
        return st;
    }
    ++r->nfiles;
    return MF_OK;
}

/* ---- the pipeline ---------------------------------------------------------------------------- */

mf_status mf_ltc_bake(const mf_ltc_bake_options *o, mf_ltc_bake_report *r)
{
    memset(r, 0, sizeof *r);
    r->stage = MF_LTC_BAKE_STAGE_FIT;
    if (!o || !o->model || !o->out_dir || !o->out_dir[0]) {
        set_msg(r, "no model or no output directory");
        return MF_ERR_DOMAIN;
    }
    snprintf(r->stem, sizeof r->stem, "ltc_%s", o->model->name);
    for (char *s = r->stem; *s; ++s)
        if (*s == '-')
            *s = '_';
    int n = snprintf(r->checkpoint, sizeof r->checkpoint, "%s/%s.checkpoint", o->out_dir, r->stem);
    if (n < 0 || n >= (int)sizeof r->checkpoint) {
        set_msg(r, "%s: path too long", o->out_dir);
        return MF_ERR_DOMAIN;
    }
    if (o->hdrp && !(o->fit.n_r == MF_LTC_HDRP_SIZE && o->fit.n_u == MF_LTC_HDRP_SIZE && o->fit.r_lo == 0.0 &&
                     o->fit.r_hi == 1.0 && o->fit.u_lo == 0.0 && o->fit.u_hi == 1.0)) {
        set_msg(r, "the HDRP file needs the default layout (64 x 64, default ranges)");
        return MF_ERR_DOMAIN;
    }
    char msg[1024] = "";
    mf_status st = mf_io_make_dirs(o->out_dir, msg, sizeof msg);
    if (st != MF_OK) {
        set_msg(r, "%s", msg);
        return st;
    }
    mf_ltcfit_options fo = o->fit;
    fo.checkpoint = r->checkpoint;
    fo.resume = o->resume;
    fo.cancel = o->cancel;
    fo.progress = o->progress;
    fo.progress_user = o->progress_user;
    if (!o->resume)
        remove(r->checkpoint); /* a fresh fit never mixes with an old checkpoint */

    mf_table t;
    double t0 = now_seconds(), f0 = cpu_seconds();
    /* the albedo and Fresnel moment of every texel, once for the fit and the gate (texel_albedos);
     * counted in the fit's time (they are its magnitude and Fresnel fields) */
    double *albedo3 = NULL;
    mf_table lay;
    if (mf_ltc_table_create_range(&lay, fo.n_r, fo.r_lo, fo.r_hi, fo.n_u, fo.u_lo, fo.u_hi) == MF_OK) {
        if (mf_ltc_gate_layout_ok(&lay, NULL, 0))
            albedo3 = texel_albedos(&lay, o->model, fo.threads >= 1 ? fo.threads : 1);
        mf_table_free(&lay);
    }
    fo.albedo = albedo3;
    st = mf_ltcfit_table(o->model, &fo, &t, &r->fit, msg, sizeof msg);
    fo.albedo = NULL;
    r->fit_seconds = now_seconds() - t0;
    r->fit_cpu_seconds = cpu_seconds() - f0;
    if (st != MF_OK) {
        free(albedo3);
        set_msg(r, "%s%s%s", mf_status_str(st), msg[0] ? ": " : "", msg);
        return st;
    }
    if (r->fit.interrupted) {
        free(albedo3);
        r->interrupted = 1;
        set_msg(r, "interrupted after %d of %d columns; no table written; resume continues from %s",
                r->fit.columns_done, fo.n_r, r->checkpoint);
        return MF_ERR_NO_CONVERGENCE;
    }

    r->stage = MF_LTC_BAKE_STAGE_GATE;
    const size_t n_texels = (size_t)fo.n_r * (size_t)fo.n_u;
    mf_ltc_gate_options go;
    mf_ltc_gate_options_default(&go);
    go.seed = fo.seed;
    go.threads = fo.threads;
    /* The texel check below compares every texel with a fresh fit; the polygon checks against the
     * BRDF stay as the model's cross-check on 16 x 16 texels, with 16384 samples instead of
     * 65536 (their bound subtracts 5.5 standard errors, so fewer samples make them more lenient,
     * never a false alarm): 0.7 s of CPU instead of 2.8 s on the default table. */
    go.mc_samples = MF_LTC_BAKE_GATE_MC_SAMPLES;
    t0 = now_seconds();
    double c0 = cpu_seconds();
    /* the gate's albedo array (val, err per texel) from the quadrature above; NaN entries (and all
     * of them if it could not be allocated) are computed by the gate */
    double *albedo = NULL;
    if (albedo3 && mf_ltc_gate_layout_ok(&t, NULL, 0) && (albedo = malloc(sizeof *albedo * 2 * n_texels)) != NULL)
        for (size_t k = 0; k < n_texels; ++k) {
            albedo[2 * k] = albedo3[3 * k];
            albedo[2 * k + 1] = albedo3[3 * k + 1];
        }
    free(albedo3);
    albedo3 = NULL;
    go.albedo = albedo;
    /* The library gate (single-threaded) runs in a thread of its own beside the texel check's
     * workers when more than one thread is allowed: the two read the table and the albedo array
     * only, and neither result depends on the other or on the timing. */
    gate_thread_arg ga = {&t, o->model, &go, r->checks, (int)(sizeof r->checks / sizeof r->checks[0]), 0,
                          MF_ERR_INTERNAL};
    pthread_t gate_tid;
    int gate_threaded = fo.threads > 1 && pthread_create(&gate_tid, NULL, gate_thread, &ga) == 0;
    if (!gate_threaded)
        gate_thread(&ga);
    /* the texel check: every texel against a fresh fit of it (mf_ltc_bake_texel_check) */
    mf_check tc;
    mf_status ts = MF_OK;
    if (gate_threaded || ga.st == MF_OK || ga.st == MF_ERR_CHECK_FAILED)
        ts = texel_check(&t, o->model, &fo, go.seed, fo.threads, albedo, &tc);
    if (gate_threaded)
        pthread_join(gate_tid, NULL);
    mf_status gs = ga.st;
    r->nchecks = ga.n;
    if (gs == MF_OK || gs == MF_ERR_CHECK_FAILED) {
        if (ts != MF_OK)
            gs = ts;
        else {
            r->checks[r->nchecks++] = tc;
            if (!tc.passed)
                gs = MF_ERR_CHECK_FAILED;
        }
    }
    free(albedo);
    r->gate_seconds = now_seconds() - t0;
    r->gate_cpu_seconds = cpu_seconds() - c0;
    if (gs != MF_OK && gs != MF_ERR_CHECK_FAILED) {
        mf_table_free(&t);
        set_msg(r, "gate: %s", mf_status_str(gs));
        return gs;
    }
    r->gate_passed = gs == MF_OK;
    if (!r->gate_passed && !o->force) {
        mf_table_free(&t);
        set_msg(r, "the gate failed; nothing exported");
        return MF_ERR_CHECK_FAILED;
    }

    r->stage = MF_LTC_BAKE_STAGE_EXPORT;
    t0 = now_seconds();
    double e0 = cpu_seconds();
    st = mf_table_set_meta(&t, "validated", r->gate_passed ? "true" : "false");
    if (st != MF_OK)
        set_msg(r, "metadata: %s", mf_status_str(st));
    else
        st = export_all(o, &t, r);
    r->export_seconds = now_seconds() - t0;
    r->export_cpu_seconds = cpu_seconds() - e0;
    mf_table_free(&t);
    if (st != MF_OK)
        return st;
    r->exported = 1;
    r->stage = MF_LTC_BAKE_STAGE_DONE;
    remove(r->checkpoint);
    return MF_OK;
}

void mf_ltc_bake_report_free(mf_ltc_bake_report *r)
{
    if (r)
        mf_ltcfit_result_free(&r->fit);
}
