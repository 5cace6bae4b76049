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
    if (dropin) { /* <stem>_hdrp.cs: Unity HDRP's LTC data, fitted on its grid (mf_ltcfit_hdrp.h) */
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
    double t0 = now_seconds();
    st = mf_ltcfit_table(o->model, &fo, &t, &r->fit, msg, sizeof msg);
    r->fit_seconds = now_seconds() - t0;
    if (st != MF_OK) {
        set_msg(r, "%s%s%s", mf_status_str(st), msg[0] ? ": " : "", msg);
        return st;
    }
    if (r->fit.interrupted) {
        r->interrupted = 1;
        set_msg(r, "interrupted after %d of %d columns; no table written; resume continues from %s",
                r->fit.columns_done, fo.n_r, r->checkpoint);
        return MF_ERR_NO_CONVERGENCE;
    }

    r->stage = MF_LTC_BAKE_STAGE_GATE;
    mf_ltc_gate_options go;
    mf_ltc_gate_options_default(&go);
    go.seed = fo.seed;
    go.threads = fo.threads;
    t0 = now_seconds();
    mf_status gs = mf_ltc_gate_run(&t, o->model, &go, r->checks, (int)(sizeof r->checks / sizeof r->checks[0]),
                                   &r->nchecks);
    r->gate_seconds = now_seconds() - t0;
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
    st = mf_table_set_meta(&t, "validated", r->gate_passed ? "true" : "false");
    if (st != MF_OK)
        set_msg(r, "metadata: %s", mf_status_str(st));
    else
        st = export_all(o, &t, r);
    r->export_seconds = now_seconds() - t0;
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
