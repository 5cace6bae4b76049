/*
 * mf_eval.h -- the functions of `mfkit eval` as a library: one registry of function names, their
 * options and their input and output columns, and one vectorised evaluator, used by the command
 * line (CSV in, CSV out) and by the Python module (numpy arrays in and out), so both give the
 * same bits.  docs/cli.md lists the functions; their names and columns are a public interface.
 *
 * A function reads its inputs from named columns of doubles and writes its outputs to named
 * columns, row by row; a row outside a function's domain gives NaN outputs (never an error).
 * Polygon functions take the vertex count n and the columns v0_x, v0_y, v0_z, ..., v7_z: v0..v2
 * are required, v3..v7 may be absent; a NaN vertex coordinate (or an absent column) means
 * "unused", so rows with different n can share one call.  A row whose n is not an integer in
 * [3, 8] or whose first n vertices are not all given gives NaN.
 *
 * Options (MF_EVAL_OPT_*) are spelled "--ndf" on the command line and ndf= in Python; each has a
 * kind, limits and a default (mf_eval_option).  An option a function does not take is refused;
 * "ndf" has no default and is required by the functions that take it.
 *
 * Errors: every function returning mf_status fills msg (may be NULL) with one line saying what
 * is wrong (the empty string on success).  Plain C11 over the core (mfkit); thread-safe (no
 * global state).
 */
#ifndef MF_EVAL_H
#define MF_EVAL_H

#include <stddef.h>

#include <mfkit/mf_core.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MF_EVAL_MAX_INPUTS 37 /* 12 listed + f0 + 24 vertex coordinates */
#define MF_EVAL_MAX_OUTPUTS 6

/* ---- options --------------------------------------------------------------------------------- */

typedef enum mf_eval_option_kind {
    MF_EVAL_KIND_ENUM,  /* one of choices; the value is its index */
    MF_EVAL_KIND_INT,   /* an integer in [lo, hi], a multiple of `multiple` if > 0 */
    MF_EVAL_KIND_DOUBLE /* a finite number in [dlo, dhi] ((dlo, dhi] with lo_open) */
} mf_eval_option_kind;

/* The options, in the order of the registry. */
typedef enum mf_eval_option_id {
    MF_EVAL_OPT_NDF = 0,     /* ggx | beckmann */
    MF_EVAL_OPT_FRESNEL,     /* none | schlick (brdf; schlick adds the input column f0) */
    MF_EVAL_OPT_G2,          /* joint | separable */
    MF_EVAL_OPT_POINTS,      /* albedo: quadrature points per axis */
    MF_EVAL_OPT_SIDED,       /* one | two (polygon functions) */
    MF_EVAL_OPT_GRID,        /* leadr: N of the N x N grid */
    MF_EVAL_OPT_LAMBDA,      /* leadr: the grid's extent in standard deviations */
    MF_EVAL_OPT_GRID_LAYOUT, /* leadr: end-points | cell-centres */
    MF_EVAL_NOPTS
} mf_eval_option_id;

typedef struct mf_eval_option {
    const char *name;            /* "ndf", "grid-layout" (the command line adds "--") */
    const char *metavar;         /* "N"; NULL for enums */
    mf_eval_option_kind kind;
    const char *const *choices;  /* ENUM: NULL-terminated */
    long lo, hi, multiple;       /* INT */
    double dlo, dhi;             /* DOUBLE */
    int lo_open;                 /* DOUBLE: dlo excluded */
    const char *def;             /* the default as text; NULL: none (required where taken, unless optional) */
    const char *help;            /* one paragraph */
    unsigned mask;               /* the group of functions taking it (mf_eval_function_options) */
    int optional;                /* with def NULL: may be left out, and then means something else than any
                                  * value (albedo without --points: the rule split at the horizon) */
} mf_eval_option;

/* The option of id k (0 <= k < MF_EVAL_NOPTS), NULL otherwise. */
const mf_eval_option *mf_eval_option_at(int k);
/* The id of the option named `name` ("grid-layout"), or -1. */
int mf_eval_option_find(const char *name);

/* A value of an option.  `set` 0: the option's default applies. */
typedef struct mf_eval_value {
    int set;
    long i;   /* ENUM: the choice's index; INT: the value */
    double d; /* DOUBLE */
} mf_eval_value;

/* Parses text as a value of option k (strict: the whole text; numbers as strtod reads them).
 * MF_ERR_DOMAIN with "ndf: expected ggx or beckmann, got 'phong'" when it is not one. */
mf_status mf_eval_option_parse(int k, const char *text, mf_eval_value *v, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* ---- functions ------------------------------------------------------------------------------- */

typedef struct mf_eval_function mf_eval_function; /* an entry of the registry */

int mf_eval_function_count(void);
const mf_eval_function *mf_eval_function_at(int i);        /* NULL outside [0, count) */
const mf_eval_function *mf_eval_function_find(const char *name); /* NULL if unknown */
const char *mf_eval_function_name(const mf_eval_function *f);
const char *mf_eval_function_summary(const mf_eval_function *f);
/* Non-zero if f takes option k; mf_eval_function_requires: and needs it given (ndf). */
int mf_eval_function_takes(const mf_eval_function *f, int k);
int mf_eval_function_requires(const mf_eval_function *f, int k);
/* Non-zero for the polygon functions (inputs followed by n's vertex columns). */
int mf_eval_function_polygon(const mf_eval_function *f);

/* Checks opts (MF_EVAL_NOPTS values, NULL: all defaults) for f: an option f does not take, a
 * required one missing, a value outside its option's limits.  MF_ERR_DOMAIN with the reason. */
mf_status mf_eval_check_options(const mf_eval_function *f, const mf_eval_value *opts, char *msg,
                                size_t msg_size) MF_WARN_UNUSED;

/* The input columns of f with these options (they decide e.g. brdf's f0): names[] (at most
 * MF_EVAL_MAX_INPUTS) and, if required is not NULL, whether each must be given.  Returns the
 * count.  The listed inputs first (brdf: f0 after them), then the vertex columns of a polygon. */
int mf_eval_inputs(const mf_eval_function *f, const mf_eval_value *opts, const char **names, int *required);
/* The output columns (at most MF_EVAL_MAX_OUTPUTS; they can depend on the NDF).  Returns the count. */
int mf_eval_outputs(const mf_eval_function *f, const mf_eval_value *opts, const char **names);

/*
 * Evaluates f on n rows.
 *   opts       MF_EVAL_NOPTS values (NULL: defaults), checked by mf_eval_check_options.
 *   col_names  ncols names of input columns (each an input of f, at most once; every required
 *              input present); cols[j] holds n doubles of column col_names[j].
 *   outs       one array of n doubles per output, in the order of mf_eval_outputs.
 * Row r's outputs depend only on row r's inputs (the same bits as one row at a time).
 * Returns MF_OK; MF_ERR_DOMAIN for NULL pointers, bad options, an unknown, repeated or missing
 * column ("missing required column 'm_z'").
 */
mf_status mf_eval_run_function(const mf_eval_function *f, const mf_eval_value *opts, int ncols,
                               const char *const *col_names, const double *const *cols, size_t n,
                               double *const *outs, char *msg, size_t msg_size) MF_WARN_UNUSED;
/* The same with f by name ("unknown function 'x'" if there is none). */
mf_status mf_eval_run(const char *function, const mf_eval_value *opts, int ncols, const char *const *col_names,
                      const double *const *cols, size_t n, double *const *outs, char *msg,
                      size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif

#endif /* MF_EVAL_H */
