/*
 * mfkit_py.c -- the few entry points the Python module (fit/python/mfkit/__init__.py) needs
 * beyond the public C API, which the shared library libmfkit_py exports whole (mfkit, mfkit_io,
 * mfkit_eval).  The module calls it through ctypes: plain C types only, every pointer checked.
 */
#include "mfkit/eval/mf_eval.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/io/mf_table_io.h"
#include "mfkit/mfkit.h"
#ifdef MFKIT_PY_HAVE_SOLVER
#include "mfkit/fit/mf_ltc_validate.h"
#endif

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* The layout of the structures the module mirrors, checked at import: a library of another
 * version refuses to load instead of reading garbage. */
enum { MFPY_ABI_N = 9 };
int mfpy_abi(size_t *out, int n)
{
    const size_t v[MFPY_ABI_N] = {sizeof(mf_table), sizeof(mf_table_axis), offsetof(mf_table, data),
                                  sizeof(mf_check), sizeof(mf_table_file_info), sizeof(mf_half_error),
                                  sizeof(mf_eval_value), sizeof(mf_table_write_options), sizeof(mf_eval_option)};
    if (!out || n < MFPY_ABI_N)
        return MFPY_ABI_N;
    memcpy(out, v, sizeof v);
    return MFPY_ABI_N;
}

/* Reads a table file: mf_table_read, or for .csv the reference LTC layout (mf_ltc_reference.h). */
mf_status mfpy_table_read(const char *path, mf_table *out, mf_table_file_info *info, char *msg, size_t msg_size)
{
    if (!path || !out || !info)
        return MF_ERR_DOMAIN;
    memset(info, 0, sizeof *info);
    if (mf_table_format_from_path(path) == MF_TABLE_FORMAT_CSV) {
        info->format = MF_TABLE_FORMAT_CSV;
        return mf_ltc_reference_read_csv(path, out, msg, msg_size);
    }
    return mf_table_read(path, out, info, msg, msg_size);
}

/* The gate of t's kind (mf_table_kind.h), as `mfkit validate TABLE` runs it: the LTC gate and, with
 * a model, the neighbour check (mf_ltc_gate_validate, the CLI's own call) with the model named brdf (NULL: the table's "brdf" metadata; "none": model-free checks), other kinds
 * their model-free gate with the storage rounding of half_float.  kind_out gets the kind's name.
 * MF_OK (all passed), MF_ERR_CHECK_FAILED (the checks are filled either way), MF_ERR_DOMAIN with
 * msg for an unknown kind or BRDF. */
mf_status mfpy_validate_table(const mf_table *t, int half_float, const char *brdf, int quick, uint64_t seed,
                              mf_check *checks, int cap, int *count, char *kind_out, size_t kind_size, char *msg,
                              size_t msg_size)
{
    if (!t || !checks || !count || !kind_out || kind_size == 0 || !msg || msg_size == 0)
        return MF_ERR_DOMAIN;
    *count = 0;
    kind_out[0] = msg[0] = '\0';
    char why[256];
    const mf_table_kind *kind = mf_table_kind_of(t, why, sizeof why);
    if (!kind) {
        snprintf(msg, msg_size, "not a table of a known kind (%d axes, %d fields): %s", t->naxes, t->nfields, why);
        return MF_ERR_DOMAIN;
    }
    snprintf(kind_out, kind_size, "%s", kind->name);
    if (strcmp(kind->name, "ltc_isotropic") != 0) {
        mf_table_storage_options so = {mf_table_storage_roundoff(half_float)};
        return kind->gate(t, NULL, &so, checks, cap, count);
    }
    const mf_brdf_model *model = NULL;
    const char *name = brdf ? brdf : mf_table_get_meta(t, "brdf");
    if (name && strcmp(name, "none") != 0) {
        model = mf_brdf_model_find(name);
        if (!model) {
            snprintf(msg, msg_size, "unknown BRDF '%s'", name);
            return MF_ERR_DOMAIN;
        }
    }
    mf_ltc_gate_options o;
    mf_ltc_gate_options_default(&o);
    o.seed = seed;
    o.quick = quick;
    if (cap < MF_LTC_VALIDATE_MAX_CHECKS) {
        snprintf(msg, msg_size, "room for %d checks, the LTC gate writes up to %d", cap, MF_LTC_VALIDATE_MAX_CHECKS);
        return MF_ERR_DOMAIN;
    }
    /* the gate and, with a model, the neighbour check: what `mfkit validate TABLE` runs */
#ifdef MFKIT_PY_HAVE_SOLVER
    /* with the fitters (libmfkit_py_full.so): a table mfkit's fitter made has the neighbour check's
     * candidate texels refitted, as `mfkit validate` does (mf_ltc_validate.h) */
    mf_status st = mf_ltc_validate_fitted(t, model, &o, checks, cap, count, NULL);
#else
    mf_status st = mf_ltc_gate_validate(t, model, &o, checks, cap, count);
#endif
    if (st == MF_ERR_DOMAIN)
        snprintf(msg, msg_size, "not an LTC table layout (two axes r: alpha = r^2 and u: cos = 1 - u^2, fields "
                                "minv_00, minv_20, minv_02, minv_22, magnitude)");
    return st;
}
