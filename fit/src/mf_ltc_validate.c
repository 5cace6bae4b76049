/*
 * mf_ltc_validate.c -- the neighbour check of `mfkit validate` with its candidate texels refitted
 * (mf_ltc_validate.h).
 */
#include "mfkit/fit/mf_ltc_validate.h"
#include "mfkit/fit/mf_ltc_bake.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int mf_ltc_validate_fit_options(const mf_table *t, const mf_brdf_model *model, mf_ltcfit_options *fit)
{
    if (!t || !model || !model->name || !fit || t->naxes != 2)
        return 0;
    const char *tool = mf_table_get_meta(t, "tool"), *brdf = mf_table_get_meta(t, "brdf");
    const char *seed = mf_table_get_meta(t, "seed"), *samples = mf_table_get_meta(t, "samples");
    if (!tool || strcmp(tool, "mfkit fit ltc") != 0 || !brdf || strcmp(brdf, model->name) != 0 || !seed || !samples)
        return 0;
    char *end;
    unsigned long long sd = strtoull(seed, &end, 10);
    if (*end || end == seed)
        return 0;
    long ns = strtol(samples, &end, 10);
    if (*end || end == samples || ns < 64 || ns > (1L << 20))
        return 0;
    mf_ltcfit_options_default(fit);
    fit->seed = (uint64_t)sd;
    fit->samples = (int)ns;
    return 1;
}

typedef struct refit_ctx {
    const mf_brdf_model *model;
    mf_ltcfit_options fit;
    uint64_t gate_seed;
    mf_table scratch; /* a copy of the table: the texel's magnitude set to the albedo while refitted */
    int fmag;
} refit_ctx;

static double refit_texel(void *user, const mf_table *t, int ir, int iu)
{
    (void)t; /* the scratch copy holds the same values */
    refit_ctx *r = user;
    mf_result alb;
    if (mf_ltc_gate_texel_albedo(&r->scratch, r->model, ir, iu, &alb) != MF_OK)
        return NAN;
    int idx[2] = {ir, iu};
    double *rec = mf_table_record(&r->scratch, idx), keep = rec[r->fmag];
    rec[r->fmag] = alb.val;
    double d = mf_ltc_bake_texel_value(&r->scratch, r->model, &r->fit, r->gate_seed, ir, iu, NULL);
    rec[r->fmag] = keep;
    return d;
}

/* r's options, scratch copy and magnitude field for t; 0 when t is not recognised (mf_ltc_validate_fit_options),
 * -1 out of memory. */
static int refit_ctx_init(refit_ctx *r, const mf_table *t, const mf_brdf_model *model, uint64_t gate_seed)
{
    memset(r, 0, sizeof *r);
    if (!mf_ltc_validate_fit_options(t, model, &r->fit) || (r->fmag = mf_table_field(t, "magnitude")) < 0)
        return 0;
    if (mf_table_copy(&r->scratch, t) != MF_OK)
        return -1;
    r->model = model;
    r->gate_seed = gate_seed;
    return 1;
}

mf_status mf_ltc_validate_neighbour_check(const mf_table *t, const mf_brdf_model *model, uint64_t seed, mf_check *c,
                                          int *refit_used)
{
    if (refit_used)
        *refit_used = 0;
    refit_ctx r;
    int k = refit_ctx_init(&r, t, model, seed);
    if (k < 0)
        return MF_ERR_ALLOC;
    if (!k)
        return mf_ltc_gate_neighbour_check(t, model, seed, c);
    if (refit_used)
        *refit_used = 1;
    mf_status st = mf_ltc_gate_neighbour_check_refit(t, model, seed, refit_texel, &r, c);
    mf_table_free(&r.scratch);
    return st;
}

mf_status mf_ltc_validate_fitted(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                                 mf_check *checks, int cap, int *count, int *refit_used)
{
    if (refit_used)
        *refit_used = 0;
    mf_ltc_gate_options def;
    if (!o) {
        mf_ltc_gate_options_default(&def);
        o = &def;
    }
    refit_ctx r;
    int k = refit_ctx_init(&r, t, model, o->seed);
    if (k < 0)
        return MF_ERR_ALLOC;
    if (!k)
        return mf_ltc_gate_validate(t, model, o, checks, cap, count);
    if (refit_used)
        *refit_used = 1;
    mf_status st = mf_ltc_gate_validate_refit(t, model, o, refit_texel, &r, checks, cap, count);
    mf_table_free(&r.scratch);
    return st;
}
