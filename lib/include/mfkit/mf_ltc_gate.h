/*
 * mf_ltc_gate.h -- the gate an LTC table must pass before it is exported: energy, normalisation,
 * polygon shading against Monte Carlo, smoothness.
 *
 * The table is an isotropic LTC table (mf_ltc_table.h: axes r (alpha = r^2, clamped) and
 * u = sqrt(1 - cos theta_o); fields minv_00, minv_20, minv_02, minv_22, magnitude and, optionally,
 * fresnel).  The checks, their bounds and the reasons for the bounds are in docs/validation.md
 * ("The LTC gate").  In short:
 *
 *   ltc_finite          no NaN or infinity in any field of any texel                  (model-free)
 *   ltc_energy          magnitude <= 1 + 1e-5 and 0 <= fresnel <= magnitude + 1e-5     (model-free)
 *   ltc_normalisation   the unpacked LTC of every texel integrates to 1 over the sphere: the
 *                       sum of its exact integrals over the 8 octant triangles of a randomly
 *                       rotated frame (mf_ltc_integrate_polygon, the renderer's path)  (model-free)
 *   ltc_smooth_jump     |difference| of every field between neighbouring texels <= 16 h
 *                       (h = 1/(n - 1), the axis spacing)                              (model-free)
 *   ltc_smooth_spike    no texel lies outside the range of its two neighbours (along either
 *                       axis) by more than 80 h^2 (with a model, a magnitude spike is measured
 *                       on magnitude - albedo: the true albedo spikes at grazing)      (model-free)
 *   ltc_albedo_quad     |magnitude - albedo| / max(albedo, 0.01) <= 1e-3 + 4 err / albedo, the
 *                       albedo by a deterministic product Gauss-Legendre rule through the
 *                       model's sampler (err its error estimate)                      (model)
 *   ltc_albedo_mc       |magnitude - MC| <= z se + 1e-3 magnitude, z = 5.5, an independent
 *                       Monte Carlo estimate with the model's sampler                  (model)
 *   ltc_polygon_mean    over random quads and triangles (a third crossing the horizon) at sampled
 *                       texels: the mean of max(0, |LTC - MC| - z se) / albedo <= budget
 *   ltc_polygon_entry   the same mean per texel, worst texel <= budget                 (model)
 * where LTC = magnitude * mf_ltc_integrate_polygon (clipped after the transform, one-sided) and
 * MC the Monte Carlo integral of f cos over the polygon (the model's sampler, its weights).
 * The fit side adds one check that needs the fitter (mf_ltc_bake_texel_check, run by
 * `mfkit fit ltc`): ltc_texel_refit, every texel against a fresh fit of it, with the building
 * blocks at the end of this header.  `mfkit validate`, which has no fitter, adds instead the
 * fitter-free ltc_texel_neighbours (every texel against predictions from its neighbours,
 * mf_ltc_gate_neighbour_check at the end of this header).
 *
 * Deterministic: every random number comes from PCG32 streams keyed by (seed, texel, purpose),
 * so a result depends on the seed only (the gate is single-threaded; `threads` is accepted for
 * the callers that parallelise and does not change any result).  Pure C11.
 */
#ifndef MF_LTC_GATE_H
#define MF_LTC_GATE_H

#include <stddef.h>
#include <stdint.h>

#include "mfkit/mf_ltc_table.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_check.h"
#include "mfkit/mf_validate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Aggregates of the polygon check, for reports (errors in units of the reflected radiance from a
 * light of unit radiance, i.e. the polygon integral of f cos; relative errors against
 * max(MC, 0.01 albedo)).  Filled when options->stats is not NULL and a model is given. */
typedef struct mf_ltc_gate_stats {
    long polygons;          /* polygon tests done */
    long entries;           /* texels with polygon tests */
    double mean_abs, p95_abs, worst_abs;
    double mean_rel, p95_rel, worst_rel;
    double mean_se;         /* mean Monte Carlo standard error of the reference integrals */
    double worst_albedo_rel; /* worst |magnitude - quadrature| / max(albedo, 0.01) */
} mf_ltc_gate_stats;

typedef struct mf_ltc_gate_options {
    uint64_t seed; /* all random numbers derive from it (default 1) */
    int threads;   /* accepted for the callers; the lib gate is single-threaded (results never
                    * depend on it) */
    int quick;     /* 1: model checks on an 8 x 8 grid of texels (< 2 s for 64 x 64); 0: albedo at every
                    * texel, polygons on a 16 x 16 grid */
    /* Added fields (defaults by mf_ltc_gate_options_default): */
    int mc_samples;           /* Monte Carlo samples per tested texel (0: 32768 quick, 65536 full) */
    int polygons_per_entry;   /* random polygons per tested texel (0: 24, half quads, half triangles) */
    double polygon_budget_mean;  /* <= 0: the default MF_LTC_GATE_POLYGON_MEAN */
    double polygon_budget_entry; /* <= 0: the default MF_LTC_GATE_POLYGON_ENTRY */
    mf_ltc_gate_stats *stats; /* optional output, NULL by default */
    /* Optional, NULL by default: the model's albedo at every texel (2 doubles per texel, index
     * 2 (ir + nr iu): val and err of mf_ltc_gate_texel_albedo for this table and model), computed
     * beforehand, e.g. by a caller that parallelises it; a NaN val is computed here.  It must be
     * what mf_ltc_gate_texel_albedo returns: the results are then the same bits as without it. */
    const double *albedo;
} mf_ltc_gate_options;

/* Default error budgets of the polygon check, in units of the texel's albedo (docs/validation.md). */
#define MF_LTC_GATE_POLYGON_MEAN 0.01
#define MF_LTC_GATE_POLYGON_ENTRY 0.05

/* The number of checks mf_ltc_gate_run writes at most. */
#define MF_LTC_GATE_MAX_CHECKS 9

void mf_ltc_gate_options_default(mf_ltc_gate_options *o);

/* The model's albedo at texel (ir, iu) of the LTC table t, as the gate's albedo checks compute it
 * (mf_model_albedo, 64 points per axis, at alpha = mf_ltc_table_alpha and the view
 * mf_ltc_gate_view(mf_ltc_table_cos_theta)).  MF_ERR_DOMAIN for a bad table, texel or model. */
mf_status mf_ltc_gate_texel_albedo(const mf_table *t, const mf_brdf_model *model, int ir, int iu, mf_result *out);

/* mf_ltc_gate_texel_albedo and, from the same pass over the same points, the Schlick moment of the
 * LTC table's Fresnel field (mf_model_albedo_fresnel): *albedo is the same bits as
 * mf_ltc_gate_texel_albedo's whenever this returns MF_OK (it fails also where the moment alone is
 * not finite).  These are the values the LTC fitter computes for its magnitude and Fresnel fields
 * (mf_ltcfit.h, mf_ltcfit_options.albedo), so one quadrature per texel can serve the gate and the
 * fit (mf_ltc_bake). */
mf_status mf_ltc_gate_texel_albedo_fresnel(const mf_table *t, const mf_brdf_model *model, int ir, int iu,
                                           mf_result *albedo, mf_result *fresnel);

/* Runs the gate on t.  model may be NULL: then only the model-free checks run.  o may be NULL
 * (defaults).  Writes *count checks into checks[0..cap-1] (cap >= MF_LTC_GATE_MAX_CHECKS, else
 * MF_ERR_DOMAIN).  Returns MF_OK when all passed, MF_ERR_CHECK_FAILED otherwise, MF_ERR_DOMAIN for a
 * table that is not an LTC table layout (two axes with the square / one-minus-square mappings and
 * the fields minv_00, minv_20, minv_02, minv_22, magnitude), MF_ERR_ALLOC. */
mf_status mf_ltc_gate_run(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                          mf_check *checks, int cap, int *count) MF_WARN_UNUSED;

/* The gate's table of checks, in the order mf_ltc_gate_run writes them (*n gets the count): name,
 * what, bound (the polygon checks take theirs from the options), whether it needs the model.  The
 * check functions run on the gate's private context: run them through mf_ltc_gate_run.  Each
 * check records its cases through mf_check.h (a NaN case fails the check, worst = NaN; a texel
 * whose matrix cannot be unpacked or whose model integral fails counts as +infinity). */
const mf_check_def *mf_ltc_gate_checks(int *n);
/* The same table as an array (for static initialisers such as the table-kind registry). */
extern const mf_check_def mf_ltc_gate_check_table[MF_LTC_GATE_MAX_CHECKS];

/* 1 if t has the layout the gate needs (see mf_ltc_gate_run); 0 with a one-line reason in why
 * (may be NULL) otherwise. */
int mf_ltc_gate_layout_ok(const mf_table *t, char *why, size_t why_size);

/* ---- building blocks, also used by analysis/bench_ltc ---------------------------------------- */

/* The view direction of the isotropic view frame: (sqrt(1 - cos^2), 0, cos). */
mf_vec3 mf_ltc_gate_view(double cos_theta);

/* A fixed-seed set of n convex, front-facing polygons in the view frame (quads for even i,
 * triangles for odd i): centres towards the lobe (drawn with the model's sampler) or anywhere
 * in z >= -0.35, so about a third cross the horizon; sizes from 0.003 sr to about 2 sr. */
void mf_ltc_gate_random_polygons(const mf_brdf_model *model, double alpha, mf_vec3 wo, uint64_t seed,
                                 uint64_t stream, int n, mf_polygon *out);

/* Monte Carlo integrals of f cos over each of n convex front-facing polygons (and the albedo,
 * over the hemisphere), with nsamples model samples from PCG32(seed, stream): val[i], se[i]
 * (standard errors); albedo may be NULL.  MF_ERR_DOMAIN for a non-finite weight. */
mf_status mf_ltc_gate_polygon_mc(const mf_brdf_model *model, double alpha, mf_vec3 wo, const mf_polygon *p,
                                 int n, int nsamples, uint64_t seed, uint64_t stream, double *val, double *se,
                                 mf_result *albedo) MF_WARN_UNUSED;

/* The same two with a full parameter record (anisotropic models: mf_ltc_aniso_table.h's gate);
 * the functions above are these with mf_brdf_params_iso(alpha). */
void mf_ltc_gate_random_polygons_params(const mf_brdf_model *model, const mf_brdf_params *p, mf_vec3 wo,
                                        uint64_t seed, uint64_t stream, int n, mf_polygon *out);
mf_status mf_ltc_gate_polygon_mc_params(const mf_brdf_model *model, const mf_brdf_params *prm, mf_vec3 wo,
                                        const mf_polygon *p, int n, int nsamples, uint64_t seed, uint64_t stream,
                                        double *val, double *se, mf_result *albedo) MF_WARN_UNUSED;

/* ---- the texel check (one texel against a fresh fit of it; the fit side runs it) -------------
 * A texel "shades a light differently" from a reference texel (a fresh fit of the same texel) by
 *   d = max over the polygons P with max(s, r) > 0.02 A of |s - r| / max(r, 0.02 A),
 *   s = magnitude * E(P; stored LTC),  r = ref_magnitude * E(P; reference LTC),
 * E the LTC polygon integral (mf_ltc_integrate_polygon, one-sided), A = ref_magnitude (the albedo).
 * The definition of a bad texel is d > 0.1 on the texel's gate polygons
 * (mf_ltc_gate_texel_polygons); docs/validation.md ("The texel check") says how the fit side gets
 * the reference texel and why. */
#define MF_LTC_GATE_TEXEL_REL 0.10   /* a texel fails when d > 0.1 */
#define MF_LTC_GATE_TEXEL_FLOOR 0.02 /* polygons shaded below 0.02 albedo by both texels do not count */
#define MF_LTC_GATE_TEXEL_POLYGONS 24 /* the polygon checks' default count per texel */

/* The n gate polygons of texel (ir, iu) of t for the given seed: the polygons the polygon checks
 * use at that texel (mf_ltc_gate_random_polygons with the texel's stream), for any texel. */
void mf_ltc_gate_texel_polygons(const mf_table *t, const mf_brdf_model *model, uint64_t seed, int ir, int iu, int n,
                                mf_polygon *out);

/* The stored LTC and magnitude of texel (ir, iu) of an LTC table t (layout as mf_ltc_gate_run).
 * MF_ERR_DOMAIN for a non-finite field, a matrix that cannot be unpacked or a bad layout/index. */
mf_status mf_ltc_gate_texel(const mf_table *t, int ir, int iu, mf_ltc *ltc, double *magnitude) MF_WARN_UNUSED;

/* d above for the stored texel (ltc, magnitude) against the reference (ref, ref_magnitude) over
 * p[0..n-1]; *worst (may be NULL) gets the index of the polygon that gave d (-1 if no polygon
 * counted: d = 0).  NaN if an integral is NaN. */
double mf_ltc_gate_texel_difference(const mf_ltc *ltc, double magnitude, const mf_ltc *ref, double ref_magnitude,
                                    const mf_polygon *p, int n, int *worst);

/* ---- the neighbour check (fitter-free: `mfkit validate TABLE` with a model) ---------------------
 * ltc_texel_neighbours: every texel against predictions from its neighbours.  Each texel (ir, iu) is
 * predicted by 6 stencils along r and 6 along u (centred cubic and linear, one-sided quadratic and
 * linear extrapolations from up to 3 neighbours; polynomials in log(alpha) along r, in the index
 * along u), each in two spaces of the matrix block
 * [[minv_00, minv_02], [minv_20, minv_22]]: the stored fields, and log-polar (B = R(psi) S, S
 * symmetric positive definite: psi and log S), which follows the narrow lobes of low roughness
 * whose fields change by orders of magnitude between texels (a prediction whose block has
 * determinant <= 0, a lobe peaking at or below the horizon, is dropped).  With d the texel check's difference
 * (mf_ltc_gate_texel_difference, magnitudes 1: the albedo checks cover the magnitude) on the texel's
 * gate polygons (mf_ltc_gate_texel_polygons):
 *   s = the second smallest, over the 12 predictions, of d(stored, prediction) (each the smaller
 *       of its two spaces; one prediction alone can lie near a corrupted texel where the stencils
 *       scatter),
 *   e = max over the texel's 4 axis neighbours j of their smallest d without the stencils that use
 *       this texel, and over its 4 diagonal neighbours of their smallest d (no stencil of theirs
 *       uses the texel),
 *   value = s / (MF_LTC_GATE_NEIGHBOUR_TAU + MF_LTC_GATE_NEIGHBOUR_C e), bound 1.
 * A smooth region (e small) allows a texel 0.06 of shading difference from its neighbours'
 * prediction, a little over half the 10 % (so that a corruption of 0.1 still reads above
 * it after the prediction's own error; 0.05 left a fitted Beckmann 32 x 32 texel at 0.99 of the
 * bound); where the neighbours themselves are predicted only to e (the grazing rows, the narrow
 * lobes), the allowance grows with e.  docs/validation.md ("The neighbour
 * check") gives the measured power and false alarms.  No fitter: pure table and polygon arithmetic
 * (about 1 s of CPU for 64 x 64). */
#define MF_LTC_GATE_NEIGHBOUR_TAU 0.06
#define MF_LTC_GATE_NEIGHBOUR_C 2.0
/* Tables with fewer texels along an axis are not checked (the check records no case and passes,
 * its `what` says so): there the neighbours are too far apart to predict a texel, and good tables
 * fail (fitted GGX 8 x 8, 10 x 10, 12 x 12 read 97, 2.5 and 1.2; 16 x 16 and larger pass). */
#define MF_LTC_GATE_NEIGHBOUR_MIN_SIZE 16

/* s, e and the value above for every texel (arrays of nr * nu, index ir + nr iu; any may be NULL);
 * +inf where the texel or every prediction is unusable, NaN for a NaN integral.  MF_ERR_DOMAIN
 * without a model or for a table that is not an LTC layout, MF_ERR_ALLOC. */
mf_status mf_ltc_gate_neighbour_scores(const mf_table *t, const mf_brdf_model *model, uint64_t seed, double *s,
                                       double *e, double *value) MF_WARN_UNUSED;

/* The same for the texels of the box r0..r1 x u0..u1 (inclusive) only, computing the predictions of
 * the box and its axis neighbours: what a power study needs after changing one texel (the values of
 * texels more than 4 steps from it along both axes cannot change).  The arrays are still of
 * nr * nu; entries outside the box are not written. */
mf_status mf_ltc_gate_neighbour_scores_box(const mf_table *t, const mf_brdf_model *model, uint64_t seed, int r0,
                                           int r1, int u0, int u1, double *s, double *e,
                                           double *value) MF_WARN_UNUSED;

/* The refit of candidate texels.  A fitter-free comparison with neighbours cannot tell a real bend
 * of a fitted table at the grid's scale from a corrupted texel (docs/validation.md: charlie 64 x 64),
 * and misses some corruptions where the neighbours predict poorly (the grazing rows at 16 x 16).
 * When the caller has the fitter that made the table (`mfkit validate` of a table whose metadata
 * names mfkit's fitter, its model, seed and samples), it passes `refit`: d of texel (ir, iu) against
 * a fresh fit of that texel (the refit check "ltc_texel_refit" of mf_ltc_bake.h at one texel), NaN
 * when it cannot say.  Every texel whose neighbour value exceeds MF_LTC_GATE_NEIGHBOUR_REFIT_FROM
 * (or is not a number) is refitted, and its value becomes d / MF_LTC_GATE_TEXEL_REL: the issue's
 * own measure against the fitted texel, which the neighbours only estimate.  (refit NULL: the
 * fitter-free check above.)  *refit_d (may be NULL, else nr * nu): the refit's d, NaN where none ran. */
typedef double (*mf_ltc_gate_refit_fn)(void *user, const mf_table *t, int ir, int iu);
/* 0.15 of the bound: each candidate costs one texel fit, so the threshold trades cost for power.
 * Measured on 300 corruptions of the 16 x 16 GGX table: 153 of 154 with shading change D >= 0.11
 * caught at 0.15, 149 at 0.25 (the 4 extra misses grazing texels); the good tables of every model
 * refit at most 106 texels (charlie 64 x 64; docs/validation.md, "Choosing 0.15"). */
#define MF_LTC_GATE_NEIGHBOUR_REFIT_FROM 0.15
mf_status mf_ltc_gate_neighbour_scores_box_refit(const mf_table *t, const mf_brdf_model *model, uint64_t seed, int r0,
                                                 int r1, int u0, int u1, mf_ltc_gate_refit_fn refit, void *user,
                                                 double *s, double *e, double *value, double *refit_d) MF_WARN_UNUSED;

/* The check ltc_texel_neighbours into *c (begun and finished here; the worst texel with its s and e).
 * Returns MF_OK when it ran (c->passed says whether it passed), else as mf_ltc_gate_neighbour_scores
 * (c then failed). */
mf_status mf_ltc_gate_neighbour_check(const mf_table *t, const mf_brdf_model *model, uint64_t seed, mf_check *c);
/* The same with the refit of candidate texels (refit, user: as above). */
mf_status mf_ltc_gate_neighbour_check_refit(const mf_table *t, const mf_brdf_model *model, uint64_t seed,
                                            mf_ltc_gate_refit_fn refit, void *user, mf_check *c);

/* What `mfkit validate TABLE` runs on an LTC table (and the Python module's validate(), so both
 * give the same report): mf_ltc_gate_run, then with a model the neighbour check
 * (mf_ltc_gate_neighbour_check with o's seed) as the last check.  cap >= MF_LTC_VALIDATE_MAX_CHECKS.
 * Returns as mf_ltc_gate_run (MF_ERR_CHECK_FAILED when any check, the neighbour check included,
 * failed). */
#define MF_LTC_VALIDATE_MAX_CHECKS (MF_LTC_GATE_MAX_CHECKS + 1)
mf_status mf_ltc_gate_validate(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                               mf_check *checks, int cap, int *count) MF_WARN_UNUSED;
/* The same with the refit of candidate texels in the neighbour check (refit, user: as above;
 * `mfkit validate` passes them for tables its own fitter made). */
mf_status mf_ltc_gate_validate_refit(const mf_table *t, const mf_brdf_model *model, const mf_ltc_gate_options *o,
                                     mf_ltc_gate_refit_fn refit, void *user, mf_check *checks, int cap,
                                     int *count) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_GATE_H */
