/* mf_check.c -- recording a property check (see mf_check.h for the rules). */
#include "mfkit/mf_check.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

void mf_check_begin(mf_check *c, const char *name, const char *what, double bound)
{
    memset(c, 0, sizeof *c);
    snprintf(c->name, sizeof c->name, "%s", name ? name : "");
    snprintf(c->what, sizeof c->what, "%s", what ? what : "");
    c->bound = bound;
    c->worst = 0.0;
    c->passed = 1;
}

/* 1 if a value v at the next case must be described in worst_at (and *set_worst: becomes worst). */
static int takes_worst(const mf_check *c, double v)
{
    if (isnan(c->worst))
        return 0; /* the first NaN decided the check */
    return isnan(v) || v > c->worst || !c->worst_at[0];
}

static void take(mf_check *c, double v, const char *where)
{
    if (isnan(v)) {
        c->worst = NAN;
        snprintf(c->worst_at, sizeof c->worst_at, "NaN at %.*s", (int)sizeof c->worst_at - 8, where);
        return;
    }
    if (v > c->worst)
        c->worst = v;
    snprintf(c->worst_at, sizeof c->worst_at, "%s", where);
}

void mf_check_record(mf_check *c, double v, const char *where)
{
    c->cases++;
    if (takes_worst(c, v))
        take(c, v, where ? where : "");
}

void mf_check_recordf(mf_check *c, double v, const char *where_fmt, ...)
{
    c->cases++;
    if (!takes_worst(c, v))
        return;
    char where[sizeof c->worst_at];
    va_list ap;
    va_start(ap, where_fmt);
    vsnprintf(where, sizeof where, where_fmt, ap);
    va_end(ap);
    take(c, v, where);
}

void mf_check_fail(mf_check *c, const char *why)
{
    c->passed = 0;
    if (!isnan(c->worst))
        snprintf(c->worst_at, sizeof c->worst_at, "%s", why ? why : "failed");
}

void mf_check_finish(mf_check *c) { c->passed = c->passed && !isnan(c->worst) && c->worst <= c->bound; }

int mf_check_defs_count(const mf_check_def *defs, int n, int has_model)
{
    int k = 0;
    for (int i = 0; i < n; ++i)
        k += has_model || !defs[i].needs_model;
    return k;
}

mf_status mf_check_run_defs(const mf_check_def *defs, int n, void *ctx, int has_model, mf_check *checks, int cap,
                            int *count)
{
    if (count)
        *count = 0;
    if (!defs || !checks || !count || n < 0 || cap < mf_check_defs_count(defs, n, has_model))
        return MF_ERR_DOMAIN;
    int k = 0, all = 1;
    for (int i = 0; i < n; ++i) {
        if (defs[i].needs_model && !has_model)
            continue;
        mf_check *c = &checks[k++];
        mf_check_begin(c, defs[i].name, defs[i].what, defs[i].bound);
        defs[i].run(ctx, c);
        mf_check_finish(c);
        all = all && c->passed;
    }
    *count = k;
    return all ? MF_OK : MF_ERR_CHECK_FAILED;
}
