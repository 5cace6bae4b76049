/* mf_ltcfit_hdrp.c -- the isotropic LTC fitted on Unity HDRP's grid (mf_ltcfit_hdrp.h). */
#include "mfkit/fit/mf_ltcfit_hdrp.h"

#include "mfkit/mf_ltc.h"
#include "mfkit/mf_ltc_table.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

typedef struct hjob {
    const mf_brdf_model *model;
    const mf_table *start;
    const mf_ltcfit_options *o;
    int n, first, stride;
    double *rows;
    double *residual; /* per texel; NaN: fallback */
    mf_status st;
} hjob;

/* HDRP's row from the four stored fields (minv_00, minv_20, minv_02, minv_22; M^-1 / (M^-1)_11):
 * M^-1 / (M^-1)_22, transposed */
static int hdrp_row(const double f[4], double row[9])
{
    if (!(f[3] > 0.0) || !isfinite(f[0]) || !isfinite(f[1]) || !isfinite(f[2]) || !isfinite(f[3]))
        return 0;
    const double s = 1.0 / f[3];
    const double r[9] = {f[0] * s, 0.0, f[1] * s, 0.0, s, 0.0, f[2] * s, 0.0, 1.0};
    memcpy(row, r, sizeof r);
    return 1;
}

static void fit_texel(hjob *j, int ir, int it)
{
    const int n = j->n;
    const double r = (double)ir / (n - 1);
    const double alpha = fmax(r * r, MF_LTC_ALPHA_MIN);
    const double theta = fmin((double)it / (n - 1) * 0.5 * MF_PI, MF_LTC_THETA_MAX);
    const double cos_theta = cos(theta);
    double *row = j->rows + (size_t)(ir + n * it) * 9;
    /* the start: mfkit's table at (r, u = sqrt(1 - cos theta)) */
    double p[2] = {sqrt(alpha), sqrt(fmax(1.0 - cos_theta, 0.0))}, rec[MF_LTC_NFIELDS];
    mf_ltc ltc;
    mf_status st = mf_table_lookup(j->start, p, rec);
    if (st == MF_OK)
        st = mf_ltc_table_unpack(rec, &ltc);
    if (st != MF_OK) {
        j->st = st;
        return;
    }
    double m0[9];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            m0[3 * a + b] = ltc.m.m[a][b];
    mf_ltcfit_entry e;
    double f4[4];
    j->residual[ir + n * it] = NAN;
    if (mf_ltcfit_entry_fit(j->model, alpha, cos_theta, m0, j->o, &e) == MF_OK && isfinite(e.a) && isfinite(e.b) &&
        isfinite(e.c) && isfinite(e.d) && mf_ltc_table_pack(e.a, e.b, e.c, e.d, f4) == MF_OK && hdrp_row(f4, row)) {
        j->residual[ir + n * it] = e.residual;
        return;
    }
    if (!hdrp_row(rec, row)) /* the start, kept */
        j->st = MF_ERR_DOMAIN;
}

static void *worker(void *arg)
{
    hjob *j = arg;
    for (int ir = j->first; ir < j->n && j->st == MF_OK; ir += j->stride)
        for (int it = 0; it < j->n && j->st == MF_OK; ++it)
            fit_texel(j, ir, it);
    return NULL;
}

mf_status mf_ltcfit_hdrp(const mf_brdf_model *model, const mf_table *start, const mf_ltcfit_options *o, int n,
                         double *rows, mf_ltcfit_hdrp_report *report)
{
    if (!model || !start || !o || !rows || n < 2 || n > 4096 || start->naxes != 2 ||
        start->nfields != MF_LTC_NFIELDS || o->threads < 1 || o->threads > 256)
        return MF_ERR_DOMAIN;
    const int nt = o->threads < n ? o->threads : n;
    double *residual = malloc((size_t)n * n * sizeof *residual);
    hjob *jobs = calloc((size_t)nt, sizeof *jobs);
    pthread_t *th = calloc((size_t)nt, sizeof *th);
    if (!residual || !jobs || !th) {
        free(residual);
        free(jobs);
        free(th);
        return MF_ERR_ALLOC;
    }
    int started = 0;
    for (int k = 0; k < nt; ++k) {
        hjob j = {model, start, o, n, k, nt, rows, residual, MF_OK};
        jobs[k] = j;
    }
    for (int k = 1; k < nt; ++k)
        if (pthread_create(&th[k], NULL, worker, &jobs[k]) == 0)
            started = k;
        else
            break;
    /* columns of threads that did not start run here */
    for (int k = started + 1; k < nt; ++k)
        worker(&jobs[k]);
    worker(&jobs[0]);
    for (int k = 1; k <= started; ++k)
        pthread_join(th[k], NULL);
    mf_status st = MF_OK;
    for (int k = 0; k < nt; ++k)
        if (jobs[k].st != MF_OK)
            st = jobs[k].st;
    if (report) {
        memset(report, 0, sizeof *report);
        report->worst_index = -1;
        for (int i = 0; i < n * n; ++i) {
            if (isnan(residual[i]))
                ++report->fallbacks;
            else if (report->worst_index < 0 || residual[i] > report->worst_residual) {
                report->worst_residual = residual[i];
                report->worst_index = i;
            }
        }
    }
    free(residual);
    free(jobs);
    free(th);
    return st;
}
