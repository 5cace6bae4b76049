/*
 * mfkit_py_full.c -- the second library of the Python module, loaded on demand: the core and
 * table I/O again (a private copy), plus the fitters over Ceres (mf_ltc_bake) and the OpenImageIO
 * image backend (EXR tables).  Built when MFKIT_WITH_CERES or MFKIT_WITH_OIIO is on.
 */
#include "mfkit/io/mf_image.h"
#include "mfkit/mfkit.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#if MFKIT_PY_HAVE_IMAGE
#include "mfkit/fit/mf_image_oiio.h"
#endif
#if MFKIT_PY_HAVE_SOLVER
#include "mfkit/fit/mf_ltc_bake.h"
#endif

/* Installs the image backend; returns a bit set: 1 EXR (OpenImageIO), 2 the fitters (Ceres). */
int mfpy_full_init(void)
{
    int have = 0;
#if MFKIT_PY_HAVE_IMAGE
    mf_image_set_backend(mf_image_oiio_backend());
    have |= 1;
#endif
#if MFKIT_PY_HAVE_SOLVER
    have |= 2;
#endif
    return have;
}

/* The outcome of mfpy_fit_ltc, flat for ctypes. */
typedef struct mfpy_bake_result {
    int status;             /* mf_status */
    int gate_passed, exported, interrupted, stage;
    int nchecks;
    mf_check checks[16];
    int nfiles;
    char files[16][4096];
    char stem[96];
    double fit_seconds, gate_seconds, export_seconds;
    double worst_residual;
    int not_converged;
    char message[1024];
} mfpy_bake_result;

size_t mfpy_bake_result_size(void) { return sizeof(mfpy_bake_result); }

/* mf_ltc_bake with the options the module exposes; progress (may be NULL) gets the fitted
 * texels from the fitting threads. */
int mfpy_fit_ltc(const char *brdf, int size, int samples, uint64_t seed, int threads, const char *out_dir, int force,
                 const volatile int *cancel, void (*progress)(void *, int, int), mfpy_bake_result *res)
{
    if (!res)
        return MF_ERR_DOMAIN;
    memset(res, 0, sizeof *res);
#if MFKIT_PY_HAVE_SOLVER
    mf_ltc_bake_options o;
    mf_ltc_bake_options_default(&o);
    o.model = brdf ? mf_brdf_model_find(brdf) : NULL;
    if (!o.model) {
        snprintf(res->message, sizeof res->message, "unknown BRDF '%s'", brdf ? brdf : "(null)");
        return res->status = MF_ERR_DOMAIN;
    }
    if (size > 0)
        o.fit.n_r = o.fit.n_u = size;
    if (samples > 0)
        o.fit.samples = samples;
    o.fit.seed = seed;
    if (threads > 0)
        o.fit.threads = threads;
    o.out_dir = out_dir;
    o.force = force;
    o.tool = "mfkit (python)";
    o.cancel = cancel;
    o.progress = progress;
    mf_ltc_bake_report r;
    mf_status st = mf_ltc_bake(&o, &r);
    res->status = st;
    res->gate_passed = r.gate_passed;
    res->exported = r.exported;
    res->interrupted = r.interrupted;
    res->stage = r.stage;
    res->nchecks = r.nchecks < 16 ? r.nchecks : 16;
    memcpy(res->checks, r.checks, sizeof(mf_check) * (size_t)res->nchecks);
    res->nfiles = r.nfiles < 16 ? r.nfiles : 16;
    for (int i = 0; i < res->nfiles; ++i)
        snprintf(res->files[i], sizeof res->files[i], "%s", r.files[i]);
    snprintf(res->stem, sizeof res->stem, "%s", r.stem);
    res->fit_seconds = r.fit_seconds;
    res->gate_seconds = r.gate_seconds;
    res->export_seconds = r.export_seconds;
    res->worst_residual = r.fit.worst_residual;
    res->not_converged = r.fit.not_converged;
    snprintf(res->message, sizeof res->message, "%s", r.message);
    mf_ltc_bake_report_free(&r);
    return st;
#else
    (void)brdf, (void)size, (void)samples, (void)seed, (void)threads, (void)out_dir, (void)force, (void)cancel, (void)progress;
    snprintf(res->message, sizeof res->message, "fit_ltc needs the fitters: this build has MFKIT_WITH_CERES off");
    return res->status = MF_ERR_UNSUPPORTED;
#endif
}
