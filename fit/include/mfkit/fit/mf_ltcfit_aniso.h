/*
 * mf_ltcfit_aniso.h -- fit 4-D anisotropic LTC tables (mf_ltc_aniso_table.h) to an anisotropic
 * BRDF model (mf_model.h, e.g. "ggx" with alpha_x != alpha_y).
 *
 * The table.  Axes (alpha_x, alpha_y, theta, phi) [Kt, Heitz, Dupuy, Narayanan 2022, Sec. 5]:
 * alpha = max(i / (n - 1), 1e-4), theta = i / (n - 1) 0.9999 pi / 2, phi = i / (n - 1) pi / 2;
 * the view is wo = (sin theta cos phi, sin theta sin phi, cos theta) in the frame whose x axis is
 * the alpha_x direction.  Optionally the first two axes are (alpha, lambda): alpha_x = max(a, 1e-4),
 * alpha_y = max(a lambda, 1e-4), a = i / (n - 1), lambda = j / (n - 1) (the authors'
 * reparameterisation).  Azimuths outside [0, pi/2] follow from the mirror symmetries of the
 * model (x -> -x: phi -> pi - phi; y -> -y: phi -> -phi): with S_x = diag(-1, 1, 1),
 * S_y = diag(1, -1, 1), the LTC at the mirrored view is S M S (mf_ltc_aniso_table.h).
 *
 * The objective is the isotropic fitter's (mf_ltcfit.h): per entry, the weighted differences of
 * magnitude * E_LTC(P_k; M) and the BRDF's light integrals I_k over a family of K test lights,
 * with the exact magnitude (the model's albedo, mf_model_albedo), the same scrambled Sobol
 * directions mapped through the model's (anisotropic) sampler, the control variate (the warm
 * start's LTC), proximal residuals towards the warm start, exact Jacobians (written out,
 * mf_ltcfit_aniso.c, integral_grad), Ceres Levenberg-Marquardt (mf_solver.h).  The table's fits
 * (and mf_ltcfit_aniso_entry_fit) minimise the expected shading error over random quad lights:
 * the lights are 192 fixed random quads drawn from the SAME distribution as the accuracy
 * benchmark's lights (analysis/bench_ltc_aniso.c: mf_ltc_gate_random_polygons_params, a third
 * centred on directions the model samples, a third across the horizon, a third anywhere,
 * half-extents 0.03..1.2 at distance 1), from a fixed stream of their own (never the
 * benchmark's or the gate's quads), and the residual weight mixes the benchmark's two measures,
 * 1 / albedo + 0.01 / max(I_k, 0.01 albedo) (absolute error in albedos plus 0.01 times the
 * relative error).  That the fit follows the benchmark's distribution is deliberate; against
 * tuning to it, the table is also measured on a second set of points and on three other light
 * distributions (docs/validation.md).  A structured family about the lobe's mean (lobe-sized
 * n-gons shaped by the lobe's second moments, offset n-gons, horizon and large caps) scored the
 * published table's matrices above its own minima at 2845 of 2850 entries, yet shaded random
 * quads worse than the published table: the objective, not the solver, limited it (measurements
 * in mf_ltcfit_aniso.c, "RAND_LIGHTS").  mf_ltcfit_aniso_entry_fit_general keeps the structured
 * family.  A barrier residual keeps the LTC's minor angular width at its peak >= 5e-5 rad (the
 * alpha = 1e-4 slivers: below the lights' resolution the solver drove det M' to 0; see
 * mf_ltcfit_aniso.c).
 *
 * The matrix.  An LTC M is defined up to a positive scale and a rotation R_z about z on the
 * right (the cosine is invariant under it) [Kt et al. 2022, Sec. 4.2]: 9 - 2 = 7 free
 * parameters.  The solver works in the lobe frame: M = R_m M', R_m the minimal rotation taking z
 * to m (about the axis z x m), and
 *     M' = [[a, 0, b], [c, d, e], [f, g, 1]],     a >= 1e-7, d >= 1e-7, det M' > 0.
 * The zero M'_01 and the sign a > 0 fix the rotation R_z (the rotation that makes row 0 of
 * M' [.., 0, ..] with a positive first entry is unique whenever (M'_00, M'_01) != 0, i.e. for
 * every lobe that is not flat along x), M'_22 = 1 fixes the scale, and det > 0 excludes the
 * x/y flips (M diag(1, -1, 1) gives the same lobe density but reverses the orientation of every
 * transformed polygon, so a renderer's edge sum changes sign).  So every lobe has ONE
 * representation: the canonical form is the chart itself, continuous wherever the lobe and its
 * mean direction are, and neighbouring entries whose lobes are close have close matrices (no
 * post-fit alignment search is needed; tests/test_ltcfit_aniso.c sweeps each axis densely).
 * The isotropic family [[a, 0, b], [0, c, 0], [d, 0, 1]] is the subset c = e = g = 0.
 *
 * Degenerate configurations, enforced exactly (parameters held at 0 by equal bounds, the mean
 * direction projected):
 *   phi = 0 (view in the xz plane): the model is symmetric under y -> -y, so the lobe is, and
 *     S_y M S_y = M: view-frame M = [[*, 0, *], [0, *, 0], [*, 0, *]]; m.y = 0, R_m is a
 *     rotation about y, and M' has c = e = g = 0.
 *   phi = pi/2 (view in the yz plane): symmetric under x -> -x, S_x M S_x = M:
 *     M = [[*, 0, 0], [0, *, *], [0, *, *]]; m.x = 0, R_m is a rotation about x, and M' has
 *     b = c = f = 0.
 *   theta = 0 (view along the normal): both symmetries: M = diag(*, *, *) (b = c = e = f = g = 0,
 *     m = z, R_m = I), and the view, hence the fit, does not depend on phi: it is fitted once
 *     (at phi = 0) and copied to every phi, bit for bit.
 *
 * Warm starts.  Each (alpha_x, alpha_y) pair is one job: theta = 0 from a closed-form start (the
 * best cosine scaled by (s_x, s_y), log grids), then for every phi a chain along theta, each
 * entry starting from the previous entry's lobe-frame parameters (when their cost is not above
 * the closed-form start's); the anchor pairs (below) instead run, for every theta, a chain along
 * phi (the mirror rows phi = 0 and pi/2 keep their chains along theta), which keeps the grazing
 * rows' weakly determined thin column continuous along phi (at 8x8x8x32 the chains along theta
 * failed the gate's spike check, 2.26x its bound; along phi 0.87x; docs/validation.md).  Jobs are handed to `threads` pthreads in two phases (the second
 * reads only results of the first): the result does not depend on the thread count, bit for
 * bit.
 *
 * Interruption and resume.  `cancel` (a flag set from a signal handler) and `stop_after_pairs`
 * make the fit return early with result->interrupted = 1; the table is then not filled.  With
 * `checkpoint` set, every completed pair is appended to that file as one record (its entries'
 * float64 bits and a checksum), flushed to the disk before the next pair is handed out;
 * `resume` loads the file, checks that it belongs to the same fitter revision, model, sizes,
 * parameterisation, seed and settings, drops a last record cut short by a kill, and fits only
 * the missing pairs.  Each pair's fit reads only its own inputs and (anchors) phase-1 entries,
 * which are restored bit for bit, so the result is bitwise that of an uninterrupted run, for any
 * thread count (tests/test_ltcfit_aniso.c).
 *
 * Anchor rows.  Where exactly one of the two roughness indices is 0 (alpha = 1e-4 by default)
 * the lobe is a thin curved arc that one LTC cannot follow (weighted residual ~0.2 at
 * (0.857, 1e-4), 89.99 deg), and such entries serve shaders only as interpolation anchors for
 * the cell up to the next grid alpha.  They are not fitted at 1e-4: the second phase fits each
 * at the cell's midpoint (the mean of the two grid roughness pairs; the neighbour's entry is a
 * second start), and stores M_0 = 2 s M_mid - M_nb with s = c_mid . c_nb, the product of the two
 * unit last columns (mf_ltcfit_aniso_anchor_matrix): M_0's last column is a unit vector too, and
 * quadrilinear interpolation gives (M_0 + M_nb) / 2 = s M_mid at the midpoint, the midpoint fit's
 * lobe exactly.  The thin axis' width of that M_0 is close to 0 (the lobe narrows about linearly
 * with alpha), so its determinant scatters about 0 from entry to entry; where
 * det M_0 < 0.01 det M_mid, M_0 is moved along the line to M_mid until det M_0 = 0.01 det M_mid
 * (continuous in the fits; result->anchor_fallbacks counts these; where s <= 0 it keeps M_mid).
 * Keeping M_mid there instead (the first rule) broke the collocation at 1415 of 7680 anchor
 * entries at 16^4.  Magnitude and Fresnel stay those at the anchor's own alphas;
 * residual, iterations and convergence are the midpoint fit's.  Measured
 * (analysis/bench_ltc_aniso.c, 60 points, alpha in [0.02, 1]): the shape error where
 * min(alpha_x, alpha_y) < 1/7 fell 0.0167 -> 0.0074 (mean absolute) against the fits made at
 * 1e-4, the whole table's 0.00475 -> 0.00289, and unconverged entries 377 -> 6 (then, with
 * the residual weight floor at 1 albedo, mf_ltcfit_aniso.c: 0.00263 and none unconverged; with
 * the random lights: 0.00233).
 *
 * Stored per entry (mf_ltc_aniso_table.h): the view-frame forward M divided by the norm of its
 * last column (the published layout), its inverse (the matrix a shader applies to the polygon),
 * the magnitude (albedo by mf_model_albedo_fresnel), the Fresnel moment and the fit residual.
 */
#ifndef MF_LTCFIT_ANISO_H
#define MF_LTCFIT_ANISO_H

#include <stddef.h>
#include <stdint.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_ltc_aniso_table.h>
#include <mfkit/mf_model.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MF_LTCFIT_ANISO_NPARAMS 7

typedef struct mf_ltcfit_aniso_options {
    int n[4];                   /* axis sizes, >= 2 each, <= 256 (default 8 each) */
    int param;                  /* MF_LTC_ANISO_PARAM_ALPHA_XY (default) or MF_LTC_ANISO_PARAM_ALPHA_LAMBDA */
    int threads;                /* worker threads, 1..256 (default 1) */
    uint64_t seed;              /* scramble of the Sobol points (default 1) */
    int samples;                /* directions per entry, a power of two in [64, 1 << 20] (default 4096) */
    int max_iterations;         /* per solve (default 100) */
    const volatile int *cancel; /* may be NULL; non-zero: stop; the pairs in progress are dropped */
    void (*progress)(void *user, int done, int total); /* may be NULL; called under a lock */
    void *progress_user;
    const char *checkpoint;     /* NULL: none; else every completed (alpha_x, alpha_y) pair is appended here */
    int resume;                 /* load `checkpoint` if it exists and fit only the missing pairs */
    int stop_after_pairs;       /* > 0: fit at most this many pairs in this run, then return
                                 * interrupted (a test hook for resume); 0: no limit */
    int objective;              /* MF_LTCFIT_ANISO_OBJECTIVE_DEFAULT (0): residual weights 1 / (I_k + 1 albedo),
                                 * close to absolute errors; MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE (opt-in):
                                 * 1 / (I_k + 0.01 albedo), close to relative errors (docs/validation.md) */
    double ladder_alpha;        /* 0 (default): the entry point's own light family only.  > 0: the structured
                                 * family (mf_ltcfit_aniso_entry_fit_general, _mirrored, _mirrored_two,
                                 * _mirrored_multi: the prefilter's fits) gets MF_LTCFIT_ANISO_LADDER more
                                 * lights, squares at distance 1 centred on the view's mirror direction about
                                 * the normal (at every elevation since prefilter revision 11; before,
                                 * clamped to 75 deg) whose half sides run geometrically
                                 * from ladder_alpha / 4 to 10 ladder_alpha (a base lobe's roughness: lights
                                 * that resolve a mixture of base lobes whose own spread sizes every other
                                 * light; mf_ltcfit_aniso.c, "The ladder").  The
                                 * random family of the table and of mf_ltcfit_aniso_entry_fit never reads it */
    double horizon_min;         /* 0 (default): the lights' integrals are scaled by the given magnitude.  In
                                 * (0, 1) (the prefilter's keep-albedo rule, the structured family only): by
                                 * magnitude / max(h, horizon_min), h the lobe's mass above the horizon, the
                                 * magnitude the prefilter stores, so the fit sees the lobe as it is stored
                                 * (mf_ltcfit_aniso.c, fit_magnitude) */
} mf_ltcfit_aniso_options;

#define MF_LTCFIT_ANISO_LADDER 8

#define MF_LTCFIT_ANISO_OBJECTIVE_DEFAULT 0
#define MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE 1

void mf_ltcfit_aniso_options_default(mf_ltcfit_aniso_options *o);

typedef struct mf_ltcfit_aniso_entry {
    double m[9];         /* view-frame forward M, row-major, divided by the norm of its last column */
    double lobe[MF_LTCFIT_ANISO_NPARAMS]; /* the lobe-frame parameters (a, b, c, d, e, f, g) */
    double lobe_dir[3];  /* the lobe's mean direction m (view frame) */
    double residual;     /* RMS of the K weighted light residuals at the solution */
    int iterations;      /* solver steps */
    int converged;       /* the solver met a tolerance */
    double magnitude, magnitude_err, fresnel;
    int anchor;          /* 0: fitted at its own alphas; 1: an anchor entry, M_0 = 2 s M_mid - M_nb;
                          * 2: an anchor entry moved towards M_mid by the determinant floor (or
                          * M_mid where s <= 0; see "Anchor rows") */
} mf_ltcfit_aniso_entry;

typedef struct mf_ltcfit_aniso_result {
    int n[4];
    mf_ltcfit_aniso_entry *entries; /* table order (axis 0 fastest); owned: mf_ltcfit_aniso_result_free */
    int interrupted;                /* cancelled: the table is not filled */
    double worst_residual;
    int worst_index;
    int max_iterations;
    long total_iterations;
    int not_converged;
    int anchor_fallbacks; /* anchor entries with anchor == 2 (the determinant floor; "Anchor rows") */
    int pairs_done;       /* completed (alpha_x, alpha_y) pairs, including those loaded by resume */
    int pairs_resumed;    /* loaded from the checkpoint */
} mf_ltcfit_aniso_result;

/* Fits every entry of a new table *table (mf_ltc_aniso_table_create with the options' sizes and
 * parameterisation), fills its fields and metadata.  MF_ERR_DOMAIN (bad options; the model must
 * have a sampler-compatible eval_cos), MF_ERR_ALLOC, MF_ERR_INTERNAL.  On cancel: MF_OK with
 * result->interrupted and the table freed.  MF_ERR_FORMAT / MF_ERR_IO: the checkpoint (msg says
 * which). */
mf_status mf_ltcfit_aniso_table(const mf_brdf_model *model, const mf_ltcfit_aniso_options *o, mf_table *table,
                                mf_ltcfit_aniso_result *result, char *msg, size_t msg_size) MF_WARN_UNUSED;
void mf_ltcfit_aniso_result_free(mf_ltcfit_aniso_result *r);

/* Fits one entry at (alpha_x, alpha_y > 0, theta in [0, pi/2), phi in [0, 2 pi)) from the
 * lobe-frame parameters lobe_start (NULL: the closed-form start) with the options' seed, samples
 * and max_iterations.  The degenerate patterns apply when theta == 0, phi == 0 or phi == pi/2
 * exactly (MF_PI / 2).  For tests and studies (e.g. a fit made exactly at an off-grid point). */
mf_status mf_ltcfit_aniso_entry_fit(const mf_brdf_model *model, double alpha_x, double alpha_y, double theta,
                                    double phi, const double *lobe_start, const mf_ltcfit_aniso_options *o,
                                    mf_ltcfit_aniso_entry *out) MF_WARN_UNUSED;

/* The same for a model without the mirror symmetries (e.g. the effective BRDF of a normal-map
 * footprint, mf_prefilter.h): no parameter is held at 0 at theta == 0, phi == 0 or pi/2, and the
 * magnitude is the caller's albedo (value and error estimate, e.g. an exact mixture of albedos)
 * instead of mf_model_albedo_fresnel (out->fresnel = 0: not computed).  The samples, lights,
 * start, solver and stored gauge are those of mf_ltcfit_aniso_entry_fit.  p is passed to the
 * model's eval_cos and sampler as is. */
mf_status mf_ltcfit_aniso_entry_fit_general(const mf_brdf_model *model, mf_brdf_params p, double theta, double phi,
                                            double magnitude, double magnitude_err, const double *lobe_start,
                                            const mf_ltcfit_aniso_options *o, mf_ltcfit_aniso_entry *out) MF_WARN_UNUSED;

/* The anchor matrix of an alpha = 1e-4 entry (see "Anchor rows" above) from the fit at its cell's
 * midpoint m_mid and its neighbour's entry m_nb (both row-major with unit last columns):
 * m0 = 2 s m_mid - m_nb, s = (last column of m_mid) . (last column of m_nb), and 1; or, when
 * det(m0) < 0.01 det(m_mid) (the extrapolated lobe is (nearly) degenerate), the point of the line
 * from m_mid to that m0 where the determinant (last column normalised) is 0.01 det(m_mid), and 0;
 * m_mid itself and 0 when s <= 0. */
int mf_ltcfit_aniso_anchor_matrix(const double m_mid[9], const double m_nb[9], double m0[9]);

/* For tests: the per-entry light integral of the fitter's parameters p (the 7 free entries of M',
 * see "Parameters" in mf_ltcfit_aniso.c) over the polygon v[0..n-1] (xyz triples, clipped at the
 * horizon), by the written-out gradient that the prefilter's fits use and by the forward dual
 * numbers that the table's fits use.  *value_diff = |written value - integral without gradient|
 * (the two are meant to be bitwise equal), *grad_diff = max over the 7 components of
 * |written - dual| / max(1, |dual|).  Returns 0, or -1 when p is not a valid matrix or n is out
 * of range. */
int mf_ltcfit_aniso_gradient_compare(const double p[7], const double *v, int n, double *value_diff,
                                     double *grad_diff);

/* For tests: the containment sets of the prefilter's fits (bit k of cells[j] and direct[j]: whether
 * direction j, dirs[3 j .. 3 j + 2], is inside light k) for nl <= 64 convex spherical polygons
 * (nv[k] vertices each, 3 .. MF_POLYGON_MAX_VERTICES, consecutive in verts, counter-clockwise seen
 * from inside; their bounding caps as the fit's random lights build them), by the fits' cell path
 * about the lobe axis `axis` (axis.z > -|axis| / 2) into cells and by testing every direction
 * against every light into direct.  The two promise the same bits.  -1 on bad arguments or
 * allocation failure. */
int mf_ltcfit_aniso_mask_compare(const double *dirs, int n, const double axis[3], int nl, const int *nv,
                                 const double *verts, uint64_t *cells, uint64_t *direct);

/* For tests: the closed-form start of the fits (the scaled cosine's log grid, then its aspect),
 * evaluated in its hinted order against index order, on one prepared entry of the
 * prefilter's light family (model at prm, view theta in the xz plane, mirrors as
 * mf_ltcfit_aniso_entry_fit_mirrored, magnitude > 0, samples a power of two >= 64).  flat != 0 sets
 * every light's target and the magnitude to 0 (the grid's costs then tie, which tests the
 * tie-break); prox_at (may be NULL): the proximal centre of a warm solve.  Each of 7 bounds (no
 * bound, the cost itself and its neighbouring doubles, half, twice, 0) times 106 hints (none, and 105
 * grid points of scale and aspect) is one comparison of the point and the cost, bit for bit;
 * *mismatches counts those that differ.  Returns the number of comparisons, or -1 on bad
 * arguments or a failed preparation. */
int mf_ltcfit_aniso_closed_form_compare(const mf_brdf_model *model, mf_brdf_params prm, double theta, int mirrors,
                                        double magnitude, int samples, int flat, const double *prox_at,
                                        int *mismatches);

/* mf_ltcfit_aniso_entry_fit_general at phi = 0 (the view in the xz plane) for a model the caller
 * knows to be mirror symmetric: mirrors MF_LTCFIT_ANISO_MIRROR_Y (f invariant under y -> -y)
 * holds the phi = 0 zero pattern exactly, MF_LTCFIT_ANISO_MIRROR_X (under x -> -x; theta == 0
 * only) the phi = pi/2 one, both at theta == 0 the diagonal one (see "Degenerate
 * configurations"); 0 is mf_ltcfit_aniso_entry_fit_general at phi = 0.  alt_start (may be NULL):
 * a second start, taken where its cost is below both the warm start's and the closed-form
 * start's.  MF_ERR_DOMAIN also for MIRROR_X with theta != 0. */
#define MF_LTCFIT_ANISO_MIRROR_Y 1
#define MF_LTCFIT_ANISO_MIRROR_X 2
mf_status mf_ltcfit_aniso_entry_fit_mirrored(const mf_brdf_model *model, mf_brdf_params p, double theta, int mirrors,
                                             double magnitude, double magnitude_err, const double *lobe_start,
                                             const double *alt_start, const mf_ltcfit_aniso_options *o,
                                             mf_ltcfit_aniso_entry *out) MF_WARN_UNUSED;
/* Two solves of one entry of mf_ltcfit_aniso_entry_fit_mirrored on one preparation (directions,
 * lights, targets): from lobe_start (not NULL) and from the closed-form start (lobe_start NULL);
 * out is the one with the lower residual, with the iterations of both.  Bit for bit the better of
 * the two separate calls, at the cost of one preparation less. */
mf_status mf_ltcfit_aniso_entry_fit_mirrored_two(const mf_brdf_model *model, mf_brdf_params p, double theta,
                                                 int mirrors, double magnitude, double magnitude_err,
                                                 const double *lobe_start, const double *alt_start,
                                                 const mf_ltcfit_aniso_options *o,
                                                 mf_ltcfit_aniso_entry *out) MF_WARN_UNUSED;

/* nstarts (1..8) solves of one entry of mf_ltcfit_aniso_entry_fit_mirrored on one preparation:
 * out[i] is the solve from starts[i] (NULL: the closed-form start), bit for bit the separate call's
 * (lobe_start starts[i], no alt_start).  Solve 0 runs first; if its residual is at most accept
 * (-1: never) the others are skipped.  *nsolved (may be NULL): how many out[] hold solves (1 or
 * nstarts).  The caller chooses among them (e.g. mf_prefilter's continuity rule). */
mf_status mf_ltcfit_aniso_entry_fit_mirrored_multi(const mf_brdf_model *model, mf_brdf_params p, double theta,
                                                   int mirrors, double magnitude, double magnitude_err,
                                                   const double *const *starts, int nstarts, double accept,
                                                   const mf_ltcfit_aniso_options *o, mf_ltcfit_aniso_entry *out,
                                                   int *nsolved) MF_WARN_UNUSED;

/* For tests: the ladder's squares (mf_ltcfit_aniso_options.ladder_alpha = alpha > 0) for the view at
 * elevation theta in the xz plane (azimuth 0): v gets MF_LTCFIT_ANISO_LADDER x 4 vertices (xyz, square
 * after square), in the plane at distance 1 of the centre c = (-sin theta, 0, cos theta) (the mirror direction),
 * counter-clockwise about c.  Returns MF_LTCFIT_ANISO_LADDER, or -1 (alpha not > 0 and finite, theta not
 * in [0, pi/2), v NULL). */
int mf_ltcfit_aniso_ladder_lights(double theta, double alpha, double *v);

/* Writes the published layout: a little-endian float32 .npy of shape (n0, n1, n2, n3, 3, 3),
 * C order (the LAST table axis fastest, unlike mf_table's storage), the forward M of each entry
 * divided by the norm of its last column.  Atomic.  MF_ERR_DOMAIN (not an anisotropic LTC
 * table), MF_ERR_IO with msg. */
mf_status mf_ltcfit_aniso_write_kt_npy(const char *path, const mf_table *t, char *msg, size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTCFIT_ANISO_H */
