/*
 * mf_table_kind.h -- the registry of table kinds: what a table of each kind holds, how to
 * recognise one, and the gate it must pass.
 *
 * A kind declares its name, a one-line description, its axes (names, mappings, clamps, default
 * sizes and ranges), its fields (the first `required_fields` of them must be present), a layout
 * check (does this mf_table have the kind's layout? if not, why), and its gate: a table of checks
 * (mf_check.h) and the runner that runs them on a table.  The exporters (table I/O) handle any
 * table; a kind only says what the axes and fields mean and what "valid" means.
 *
 * A table names its kind in the metadata key "kind" (mf_table_kind_tag); mf_table_kind_of finds
 * it from there (and checks the layout), or else detects it from the layout alone (tables
 * written before kinds were recorded, e.g. the default LTC tables, whose bytes must not change).
 *
 * Registered kinds (all exist and are produced by mfkit today):
 *   ltc_isotropic  the isotropic LTC table (mf_ltc_table.h), gate mf_ltc_gate.h
 *   ggx_proxy      the GGX proxy roughness table of `mfkit fit ggx-proxy` (mf_proxy.h)
 *   moment_map     one MIP level of a LEAN/LEADR moment map (mf_maps.h,
 *                  mf_map_moments_to_table); the Toksvig and bump-roughness quantities are
 *                  functions of these five moments (mf_moments.h)
 *   dfg            split-sum DFG scale and bias (mf_energy.h, `mfkit energy dfg`)
 *   kulla_conty    Kulla-Conty E and E_avg (mf_energy.h, `mfkit energy kulla-conty`)
 *   ltc_anisotropic  the 4-D anisotropic LTC table (mf_ltc_aniso_table.h, `mfkit fit ltc-aniso`)
 *
 * Adding a kind (e.g. a 4-D anisotropic LTC table):
 *   1. its layout header and source (like mf_ltc_table.h/.c): the axes and fields, a create
 *      function that tags the table (mf_table_kind_tag);
 *   2. its gate: a table of mf_check_def and a runner (like mf_ltc_gate.h/.c);
 *   3. one entry in k_kinds in lib/src/mf_table_kind.c (axes, fields, layout check, checks,
 *      runner) and its sources in lib/CMakeLists.txt;
 *   4. a test in tests/test_table_kind.c (every registered kind is already looped over there:
 *      its layout is recognised, its default table passes its own layout check).
 * Nothing else changes: detection, `validate` and the exporters go through this registry.
 *
 * Pure C11.
 */
#ifndef MF_TABLE_KIND_H
#define MF_TABLE_KIND_H

#include <stddef.h>

#include "mfkit/mf_check.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_table_kind_axis {
    const char *name;      /* the parameter's name, e.g. "r" */
    const char *physical;  /* the physical quantity, e.g. "alpha" */
    mf_axis_mapping mapping;
    double physical_min;   /* the clamp (-INFINITY: none) */
    int default_size;      /* 0: given by the data (e.g. the size of an image) */
    double lo, hi;         /* the default range of the parameter */
} mf_table_kind_axis;

/* The runner of a kind's gate: runs its checks on t (model may be NULL: the model-free checks
 * only; options: the kind's options struct or NULL for the defaults) into checks[0..cap-1].
 * MF_OK all passed, MF_ERR_CHECK_FAILED, MF_ERR_DOMAIN (layout, cap), MF_ERR_ALLOC. */
typedef mf_status (*mf_table_kind_gate_fn)(const mf_table *t, const mf_brdf_model *model, const void *options,
                                           mf_check *checks, int cap, int *count);

typedef struct mf_table_kind {
    const char *name;         /* stable identifier, recorded in the metadata key "kind" */
    const char *description;  /* one line */
    int naxes;
    const mf_table_kind_axis *axes;
    int nfields;
    const char *const *fields; /* in storage order */
    int required_fields;       /* fields[0 .. required_fields - 1] must be present */
    /* 1 if t has this kind's layout; else 0 and a one-line reason in why (may be NULL). */
    int (*layout_ok)(const mf_table *t, char *why, size_t why_size);
    const mf_check_def *checks; /* the gate's table of checks (names, bounds, needs a model) */
    int nchecks;
    mf_table_kind_gate_fn gate;
} mf_table_kind;

/* The registered kinds: count, i-th (NULL out of range), by name (NULL if unknown). */
int mf_table_kind_count(void);
const mf_table_kind *mf_table_kind_at(int i);
const mf_table_kind *mf_table_kind_find(const char *name);

/* The kind of t: the one named in its "kind" metadata (which must then pass its layout check),
 * or else the first registered kind whose layout check passes.  NULL with a one-line reason in
 * why (may be NULL) when there is none. */
const mf_table_kind *mf_table_kind_of(const mf_table *t, char *why, size_t why_size);

/* Records kind k in t's metadata ("kind" = k->name).  MF_ERR_DOMAIN if the metadata is full. */
mf_status mf_table_kind_tag(mf_table *t, const mf_table_kind *k) MF_WARN_UNUSED;

/* Options of the model-free gates (ggx_proxy, moment_map, dfg, kulla_conty).  Their checks compare
 * stored values with exact ones, so their bounds add the rounding of the storage the values came
 * through: unit_roundoff u = 2^-53 for a table computed in memory (the default: NULL options),
 * 2^-24 for a float32 file, 2^-11 for a half-float file (mf_table_storage_roundoff).  The added
 * terms are derived in lib/src/mf_table_kind.c beside each check. */
typedef struct mf_table_storage_options {
    double unit_roundoff;
} mf_table_storage_options;

/* The unit roundoff of a file's storage: half_float non-zero -> 2^-11, else 2^-24 (float32: every
 * mfkit file format stores at least float32). */
double mf_table_storage_roundoff(int half_float);

/* Runs the gate of t's kind (mf_table_kind_of).  MF_ERR_DOMAIN if t has no known kind. */
mf_status mf_table_kind_gate(const mf_table *t, const mf_brdf_model *model, const void *options, mf_check *checks,
                             int cap, int *count) MF_WARN_UNUSED;

/* ---- the GGX proxy table kind ("ggx_proxy") ----------------------------------------------------
 * Axes log10_alpha, log10_dh (identity); fields alpha, dh (10^ of the axes), alpha_eff (the exact
 * proxy roughness, mf_filter_ggx_proxy_alpha), alpha_eff_sqrt (sqrt(alpha^2 + dh^2)) and
 * alpha_eff_fit (mf_proxy.h's fitted form).  Checks: proxy_finite (no NaN/inf), proxy_exact
 * (|alpha_eff / exact - 1| <= 1e-12 + 3 u: the stored value is the exact one, to the rounding of
 * the atan form, plus the storage rounding u of the three values involved), proxy_fit
 * (|alpha_eff_fit / alpha_eff - 1| <= MF_PROXY_FIT_MAX_REL_ERROR + 3 u, the bound of the shipped
 * coefficients plus storage).  Model-free; options: mf_table_storage_options. */
#define MF_GGX_PROXY_TABLE_NFIELDS 5
extern const char *const mf_ggx_proxy_table_fields[MF_GGX_PROXY_TABLE_NFIELDS];

/* ---- the moment map kind ("moment_map") --------------------------------------------------------
 * One MIP level of a moments map (mf_maps.h): axes "u" (tex_u = (i + 0.5)/w, identity) and "v"
 * (tex_v = 1 - (j + 0.5)/h, y up: row 0 at the top, so the record order is the map's row-major
 * order), fields mean_x, mean_y, m_xx, m_xy, m_yy (MF_MAP_* order).  Checks: moment_finite,
 * moment_covariance (the covariance [[m_xx - mean_x^2, c], [c, m_yy - mean_y^2]],
 * c = m_xy - mean_x mean_y, is positive semi-definite: -(smallest eigenvalue) / (m_xx + m_yy)
 * <= 1e-12 + 5 u; a box filter averages moment vectors of single slopes, whose covariance is
 * exactly 0, so in exact arithmetic the average's covariance is PSD; 1e-12 leaves room for the
 * rounding of sums over large footprints, 5 u for the storage rounding u of the five moments).
 * Model-free; options: mf_table_storage_options. */
#define MF_MOMENT_TABLE_NFIELDS 5
extern const char *const mf_moment_table_fields[MF_MOMENT_TABLE_NFIELDS];

#ifdef __cplusplus
}
#endif
#endif /* MF_TABLE_KIND_H */
