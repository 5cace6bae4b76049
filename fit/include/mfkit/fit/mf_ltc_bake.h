/*
 * mf_ltc_bake.h -- the fit -> gate -> export pipeline of an isotropic LTC table as one call:
 * fit the table to a BRDF model (mf_ltcfit.h), run the LTC gate (mf_ltc_gate.h), and write every
 * export format only if every gate check passed (or with `force`, marked unvalidated).  This is
 * what `mfkit fit ltc` does; a build system can bake validated tables without the command line.
 *
 * Files in out_dir, <p> = ltc_<model> ('-' becomes '_'): <p>.exr, <p>_half.exr, <p>_1.dds,
 * <p>_2.dds (RGBA32F: minv_00 minv_20 minv_02 minv_22 / magnitude fresnel zero sphere),
 * <p>_1_f16.dds, <p>_2_f16.dds (RGBA16F), <p>.h, <p>.glsl, <p>.hlsl, <p>.json, <p>.npy (with the
 * sidecars of mf_table_io.h); the engine files <p>_legacy_1.dds, <p>_legacy_2.dds (legacy DDS
 * header, as the reference LTC code writes), <p>.ktx2 (RGBA32F, 2-layer array: ltc_1, ltc_2),
 * <p>_f16.ktx2 (RGBA16F, Zstandard), <p>_1.exr, <p>_2.exr (channels R, G, B, A), and for the
 * 64 x 64 default layout <p>_three.js and <p>_eevee.h (mf_ltc_export.h); <p>_fit.json (mf_ltcfit_write_sidecar) and <p>_gate.json (the
 * gate report: tool, version, brdf, passed, the fit summary and the checks; no timing and no
 * timestamp, so two runs with the same options give the same bytes).  Every file is written
 * atomically; the checkpoint <p>.checkpoint is removed after a successful export.  The EXR files
 * need an image backend (mfkit/io/mf_image.h): without one they are left out and report->files
 * lists the others.
 */
#ifndef MF_LTC_BAKE_H
#define MF_LTC_BAKE_H

#include "mfkit/mf_ltc_gate.h"
#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_validate.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MF_LTC_BAKE_MAX_FILES 32
#define MF_LTC_BAKE_PATH_LEN 4096

typedef struct {
    const mf_brdf_model *model; /* required (mf_brdf_model_find) */
    mf_ltcfit_options fit;      /* size, samples, seed, threads, ranges (its checkpoint, resume,
                                   cancel and progress members are set by mf_ltc_bake from below) */
    const char *out_dir;        /* created with its parents if missing; default "out" */
    int resume;                 /* continue from out_dir/<p>.checkpoint (same settings) if it exists;
                                   0: an old checkpoint is deleted first */
    int force;                  /* export even if a gate check fails (metadata validated = "false") */
    const char *tool;           /* the gate report's "tool"; default "mf_ltc_bake" */
    const char *version;        /* the gate report's "version"; default "" */
    const volatile int *cancel; /* polled between columns; non-zero stops (see interrupted) */
    void (*progress)(void *user, int done, int total); /* fitted texels, from the fitting threads */
    void *progress_user;
    int hdrp;                   /* also fit Unity HDRP's grid and write <p>_hdrp.cs (mf_ltcfit_hdrp.h):
                                   a second fit of 64 x 64 texels, as long as the table's own, so
                                   opt-in; only for the default 64 x 64 layout (else MF_ERR_DOMAIN
                                   before the fit) */
} mf_ltc_bake_options;

typedef enum {
    MF_LTC_BAKE_STAGE_FIT = 0,
    MF_LTC_BAKE_STAGE_GATE,
    MF_LTC_BAKE_STAGE_EXPORT,
    MF_LTC_BAKE_STAGE_DONE
} mf_ltc_bake_stage;

typedef struct {
    mf_ltcfit_result fit;                 /* free with mf_ltc_bake_report_free */
    mf_check checks[MF_LTC_GATE_MAX_CHECKS + 4];
    int nchecks;
    int gate_passed;                      /* every gate check passed */
    int exported;                         /* the files were written */
    int interrupted;                      /* cancel was set: nothing written, the checkpoint kept */
    mf_ltc_bake_stage stage;              /* where it stopped (DONE after an export) */
    char stem[96];                        /* <p> */
    char checkpoint[MF_LTC_BAKE_PATH_LEN];
    int nfiles;                           /* the files written, in order */
    char files[MF_LTC_BAKE_MAX_FILES][MF_LTC_BAKE_PATH_LEN];
    double fit_seconds, gate_seconds, export_seconds; /* wall clock, not written to any file */
    char message[1024];                   /* the reason of a failure (empty on success) */
    double fit_cpu_seconds, gate_cpu_seconds, export_cpu_seconds; /* process CPU time (all threads) */
} mf_ltc_bake_report;

void mf_ltc_bake_options_default(mf_ltc_bake_options *o);

/* The texel check "ltc_texel_refit" (docs/validation.md, "The texel check"), which the pipeline
 * runs after mf_ltc_gate_run: every texel of the isotropic LTC table t is compared with a fresh
 * fit of that texel by the fitter `fit` describes (its seed, samples, iterations), on the texel's
 * gate polygons (mf_ltc_gate_texel_polygons with gate_seed), by d of mf_ltc_gate.h; the texel
 * fails when d > MF_LTC_GATE_TEXEL_REL.  The fresh fits (mf_ltcfit_entry_fit):
 *   1. warm-started from the stored texel, fit->samples / 4 directions, 3 solver steps;
 *   2. where 1 gave d > MF_LTC_GATE_TEXEL_REL / 2 or a residual above 2 x its neighbours' largest
 *      + 0.01 (a refit stuck near a grossly wrong texel): the same with fit->samples directions
 *      and fit->max_iterations steps;
 *   3, 4. in the same cases (iu > 0): started from the stored texel before it along the view
 *      axis, as stored and turned about y by the change of view angle (the table's fitter starts
 *      from that texel; where the fit is not unique, this finds the fit's own branch).
 * The value is the smallest d among the refits whose residual is within 2 x the best + 0.01.
 * Writes one check into *c (+inf for a texel that cannot be unpacked or refitted).  `threads`
 * (>= 1) workers share the texels; the result does not depend on it.  MF_ERR_DOMAIN (bad table
 * layout or arguments), MF_ERR_ALLOC. */
mf_status mf_ltc_bake_texel_check(const mf_table *t, const mf_brdf_model *model, const mf_ltcfit_options *fit,
                                  uint64_t gate_seed, int threads, mf_check *c) MF_WARN_UNUSED;
/* The value of that check at one texel (ir, iu): the smallest d of the refits tried (+inf for a
 * texel that cannot be unpacked or refitted, NaN for bad arguments); *refit (may be NULL) gets the
 * refit (1..4) that gave it, 0 if none.  For studies of the check's power (analysis/bench_ltc). */
double mf_ltc_bake_texel_value(const mf_table *t, const mf_brdf_model *model, const mf_ltcfit_options *fit,
                               uint64_t gate_seed, int ir, int iu, int *refit);

/* Runs the pipeline.  Returns MF_OK when the files were written (with force also after a gate
 * failure: report->gate_passed says which), MF_ERR_CHECK_FAILED when the gate failed and nothing
 * was written, MF_ERR_NO_CONVERGENCE with report->interrupted set when cancel stopped the fit
 * (nothing written; resume continues), and otherwise the first error (MF_ERR_DOMAIN for bad
 * options, MF_ERR_FORMAT for a checkpoint of other settings, MF_ERR_IO for a file that could not
 * be written, in which case report->message names it).  The report is always filled; free it
 * with mf_ltc_bake_report_free. */
mf_status mf_ltc_bake(const mf_ltc_bake_options *o, mf_ltc_bake_report *report);
void mf_ltc_bake_report_free(mf_ltc_bake_report *report);

#ifdef __cplusplus
}
#endif

#endif /* MF_LTC_BAKE_H */
