/*
 * mf_prefilter.h -- normal-map appearance prefiltering with LTCs [Nahmias 2022, Ch. 2.3 and 3]:
 * for every MIP level >= 1, every texel of that level and every tabulated view, one anisotropic
 * LTC (mf_ltcfit_aniso.h, 7-parameter lobe-frame chart) fitted to the effective BRDF of the
 * texel's footprint.
 *
 * The effective BRDF [Nahmias 2022, Eq. 2.34-2.36]: the footprint F of a level-l texel is the
 * 2^l x 2^l block of level-0 texels q under it (box MIP), gamma_F = (1/N) sum_q delta(n - n(q))
 * (Eq. 2.34), and
 *     f_eff(wo, wi) = (1/N) sum_q f(R_q^T wo, R_q^T wi)                       (Eq. 2.36)
 * with R_q a rotation taking z to n(q) (the base BRDF, GGX, is isotropic, so the rotation about
 * n(q) does not matter).  What is fitted (the model's eval_cos, per steradian of wi):
 *     (1/N) sum_q f(wo_q, R_q^T wi) (R_q^T wi).z,     wi.z > 0 (the geometric hemisphere),
 * i.e. each texel's lobe weighted by its own (texel-frame) cosine -- the footprint average of the
 * per-texel shading a renderer would do at level 0 -- and 0 below the geometric horizon, where
 * an LTC has no support.  It is evaluated deterministically over ALL texels of the footprint
 * (a finite mixture; texels with bitwise equal normals are merged into one component with their
 * count as weight, which is exact), never by random texel samples.
 *
 * Views below a texel's horizon [Nahmias 2022, Sec. 3, "Sampling the base BRDF"]: the thesis
 * clamps the cosine of the view elevation in the texel frame to a small positive constant
 * ("since we cannot shade a texel if the view is underneath the microfacet"; its listing names
 * the constant ZEROZEROONE; read here as 0.001: with 0.01 the last tabulated elevation,
 * 0.999 pi/2 (cos = 0.00157), is clamped even on a flat map, and a constant map's grazing-row
 * albedo came out 0.9765 instead of GGX's 0.9959) and keeps the view's azimuth about n(q) (its
 * second rotation R_1 aligns the tangent-plane projections of the texel-frame and the geometric
 * view).  mfkit does the same: wo_q = R_q^T wo, and where wo_q.z < MF_PREFILTER_COS_MIN, wo_q is
 * replaced by the direction of the same azimuth about n(q) with cosine MF_PREFILTER_COS_MIN (the
 * azimuth x if wo = -n(q)).  Such a texel keeps its weight 1/N: its grazing lobe still counts.
 *
 * Frame: the view-azimuth-aligned frame.  For the tabulated view (theta, phi) in the tangent
 * frame (x = +column, y = up the image, z = the geometric normal), the footprint's normals are
 * rotated by -phi about z, so that the view is wo = (sin theta, 0, cos theta); the stored M is
 * the forward LTC in that frame (a shader rotates the polygon by -phi about the normal, then
 * applies M^-1), divided by the norm of its last column (mf_ltcfit_aniso.h).
 *
 * Fits (mf_prefilter_run).  Levels coarse to fine; per footprint:
 *   - the light family: the anisotropic fitter's structured family (mf_ltcfit_aniso_entry_fit_general),
 *     and for GGX since revision 6 its ladder of 8 squares centred on the view's mirror direction
 *     (since revision 11 at every elevation; before, clamped to 75 deg),
 *     half sides alpha / 4 .. 10 alpha (mf_ltcfit_aniso_options.ladder_alpha = alpha; options.fit_lights):
 *     the structured family sizes its lights by the footprint lobe's own spread, so a mixture of
 *     base lobes far apart (a groove seen along the groove) had no light that resolves the gap
 *     where the single lobe puts its peak (docs/prefilter_log.md, "The fit's light family").
 *   - its normals, clustered when it has >= MF_PREFILTER_CLUSTER_MIN texels: cells of side
 *     cluster_cell * alpha in slope space, each cell one component (the normalised sum of its
 *     normals, weight count / N).  Measured (tests/test_prefilter.c, test_clusters, 8 x 8 map of
 *     slopes up to 0.3): the lobes' shading of 6 quad lights moves by at most 3e-4 of the albedo
 *     at every level; on a 16 x 16 bump map (slopes up to 0.6, 256-texel top footprint, and 1024
 *     instead of 4096 samples per fit at the same time) mean 0.003, worst 0.021.
 *   - mirror symmetry: a footprint whose normals (aligned frame) are, as a weighted set, invariant
 *     under y -> -y (checked on a MF_PREFILTER_MIRROR_TOL grid) is snapped to an exactly
 *     symmetric set and fitted with the phi = 0 zero pattern held exactly (as the anisotropic
 *     fitter does for plain GGX): the V-groove's lobes are symmetric, and a flat map gives the
 *     plain-GGX fit at every elevation, 89.9 deg included.
 *   - canonical order: the components are sorted (x, y, z, weight) before the mixture is built,
 *     so the same set gives the same quasi-random samples and the same fit (phi and phi + pi of a
 *     V-groove agree to 1e-5; a permutation of unclustered texels gives the same mixture).
 *   - theta = 0 is fitted once: M_phi = R_z(-phi) M_0 R_z(phi) (the view along z does not depend
 *     on phi; the conjugation keeps the polar gauge and the last column's norm).
 *   - a footprint whose normals are invariant under the half-turn about z (normals on the
 *     MF_PREFILTER_MIRROR_TOL_NORMAL grid below, weights on the fine one) sees at
 *     phi + pi what it sees at phi: those rows are copies of the rows phi (a V-groove's).
 *   - each (phi) row is a chain along theta: the previous elevation's lobe is the warm start
 *     (with the fitter's proximal residuals) and the first azimuth's entries get a second solve
 *     from the closed-form start: at rows with cos theta < MF_PREFILTER_MULTISTART_COS the lower
 *     residual is kept, elsewhere the warm start's unless the other is lower by more than
 *     MF_PREFILTER_CONTINUITY_MARGIN (revision 9; before, those rows had the warm start's solve
 *     alone).  From the second
 *     azimuth on, every entry also gets a solve from the previous azimuth's lobe at the same
 *     elevation and one from the closed-form start (revision 6: on every row; one preparation,
 *     mf_ltcfit_aniso_entry_fit_mirrored_multi), and the previous azimuth's solve is kept
 *     unless its residual exceeds the best solve's by more than MF_PREFILTER_CONTINUITY_MARGIN:
 *     where a single lobe has several fits of similar cost (the two facets of a groove), the
 *     neighbouring azimuths keep the same one instead of flipping between them (a lobe on one
 *     facet next to a lobe on the other is blended by the bilinear view filter into a lobe
 *     between them).  The previous azimuth's solve runs first and is kept alone, the other
 *     solves skipped, when its residual is at most 1.1 times that neighbour's own (revision 5;
 *     mf_prefilter.c, MF_PREFILTER_ACCEPT).
 *   - symmetric to the map's precision only: a row (theta > 0) whose normals are y-mirror symmetric
 *     on the MF_PREFILTER_MIRROR_TOL_NORMAL grid (3/255: an 8-bit map cannot encode 0) but not on
 *     the fine one is fitted twice, to the snapped symmetric set (zero pattern held) and to the
 *     map's own set, each by the rule above; the symmetric lobe is kept unless its residual exceeds
 *     the free one's by more than MF_PREFILTER_SYMMETRY_MARGIN.  So a groove's lobe passes
 *     through the symmetric (centred) lobe where the view runs along the groove, and the facet
 *     choice is continuous around the circle: on the demo map (vgroove_16.png, 4 x 8 views) 0
 *     facet flips between neighbouring azimuths at levels 2-4, 84 of 504 before (docs/prefilter.md,
 *     test_prefilter_gate).
 * The stored M is in the fitter's canonical gauge (one representation per lobe, the polar gauge
 * of the upper-left block), so neighbouring texels, views and levels whose lobes are close have
 * close matrices, which is what trilinear MIP filtering and bilinear view interpolation of M
 * need.  That the lobes vary continuously across texels and views is checked by the gate against
 * a reference: gated as `excess` (a lobe jumping further than the effective BRDF does), the error
 * spikes reported only for GGX (mf_prefilter_gate_run_ref).
 *
 * Magnitude: the effective BRDF's albedo, exactly the mixture of the texels' albedos
 * (1/N) sum_q rho_q(wo), rho_q the integral over the geometric hemisphere of the texel's
 * cosine-weighted lobe, each by mf_model_albedo (n = MF_PREFILTER_ALBEDO_N) of the one-texel
 * mixture (the clip at the geometric horizon is a discontinuity of the integrand: its error is
 * the stored error estimate |Q(n) - Q(n/2)|; measured against n = 512 for 40 normals of slope
 * up to 0.5 and 48 views: worst 2.3e-3 at n = 128, 4.8e-3 at n = 64; on the 512 (texel, view)
 * pairs of `bench_prefilter --size 32 --albedo-check 3`: n = 128 worst 1.3e-3, mean 5.9e-5;
 * n = 64 worst 2.6e-3, mean 1.6e-4, at a quarter of the cost: n = 64 since revision 2).  Since
 * revision 3 the GGX texels' albedos are read from a table of that rule over the three numbers the
 * one-texel albedo depends on (mf_prefilter_texel_albedo, MF_PREFILTER_ALBEDO_TABLE).  Optionally
 * divided by the lobe's mass above the horizon (options.keep_albedo).  Lambert: (1 + n.z) / 2 per
 * texel, exact.
 */
#ifndef MF_PREFILTER_H
#define MF_PREFILTER_H

#include <stddef.h>
#include <stdint.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_model.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MF_PREFILTER_COS_MIN 0.001
/* Names the fitted values: bump it whenever they change (objective, starts, constants), so that a
 * resumed `mfkit prefilter` refuses tiles of another revision.  12: a fit without a warm start no
 * longer reads its unset proximal centre (mf_ltcfit_aniso.c, residual_fn), which made such a fit stop
 * at its start, unconverged, when the heap held a NaN there; the lobes are revision 11's wherever
 * revision 11's were reproducible (docs/prefilter.md, "Fitter revision 12"). */
#define MF_PREFILTER_REVISION 12
#define MF_PREFILTER_ALBEDO_N 64
#define MF_PREFILTER_THETA_MAX (0.999 * 0.5 * MF_PI)
/* Footprints of at least MF_PREFILTER_CLUSTER_MIN texels are fitted to a clustered mixture: cells
 * of side cluster_cell * alpha (GGX) or cluster_cell * MF_PREFILTER_CLUSTER_LAMBERT (Lambert) in
 * slope space (see mf_prefilter_options).  The magnitudes stay the exact mixture of the texels'
 * albedos. */
#define MF_PREFILTER_CLUSTER_CELL 0.25
#define MF_PREFILTER_CLUSTER_MIN 64
#define MF_PREFILTER_CLUSTER_LAMBERT 0.5
/* The grazing views of the gate's grazing spike check.  Up to revision 8 also the only rows of a
 * footprint's first azimuth that got two solves (the warm start's and the closed-form start's, the
 * lower residual kept): at 89.9 deg the warm-started chain of plain GGX ended at residual 0.0153,
 * the closed-form start at 0.0114, lobes 0.03 of the albedo apart in shading.  Revision 9 solves
 * the first azimuth's other rows twice as well, under the continuity margin (mf_prefilter.c,
 * fit_row_entry). */
#define MF_PREFILTER_MULTISTART_COS 0.2
/* Mirror symmetry of a footprint's normals is detected on this grid (mf_prefilter_run). */
#define MF_PREFILTER_MIRROR_TOL 1e-9
/* ... and the normals' components on this grid (3/255): an 8-bit unorm map cannot encode 0 (128
 * decodes to 1/255), so the mirror partner of a normal differs from the decoded one by up to 2/255
 * in the mirrored component; a snap moves no normal by more than this. */
#define MF_PREFILTER_MIRROR_TOL_NORMAL (3.0 / 255.0)
/* The continuity rule along phi (mf_prefilter_run): the previous azimuth's solution is kept unless
 * its residual exceeds the best start's by more than this fraction; along theta on a footprint's
 * first azimuth, the previous elevation's (revision 9, rows with cos theta >= MULTISTART_COS). */
#define MF_PREFILTER_CONTINUITY_MARGIN 0.1
/* ... and the symmetric lobe of a footprint symmetric only to the map's 8-bit precision is kept unless
 * its residual exceeds the free lobe's by more than this fraction (mf_prefilter_run).  Demo map
 * (vgroove_16.png, 4 x 8 views): with 0.1 the symmetric lobes are refused where the facet flips are
 * (a one-facet lobe 13 % better at 30 deg) and 84 of 504 azimuth pairs flip; with 0.2, 0. */
#define MF_PREFILTER_SYMMETRY_MARGIN 0.2
#define MF_PREFILTER_HORIZON_MIN 0.5

/* The effective BRDF of a footprint as an mf_brdf_model: `model` is the first member, so the
 * fitters take &mix->model (its functions cast back).  eval_cos, sample (pick a texel by weight
 * with u[0], rescaled to [0, 1) inside its interval, then the base sampler rotated to the texel;
 * the returned density is the mixture's), pdf (the mixture of the texels' densities, 0 below the
 * geometric horizon) and sample_weights (bit for bit the separate calls).  Not thread-safe to
 * build; read-only (hence shareable) once built. */
/* The base BRDF of a table: specular GGX (isotropic, alpha from the options) or Lambert 1/pi. */
enum { MF_PREFILTER_BASE_OTHER = 0, MF_PREFILTER_BASE_GGX = 1, MF_PREFILTER_BASE_LAMBERT = 2 };

typedef struct mf_prefilter_mix {
    mf_brdf_model model;
    const mf_brdf_model *base;
    int n;        /* components (distinct normals) */
    double *rot;  /* 9 per component, row-major R_q (texel -> geometric frame; column 2 = n(q)) */
    double *w;    /* weights, sum 1 */
    double *cdf;  /* cumulative weights; cdf[n - 1] = 1 */
    int kind;     /* MF_PREFILTER_BASE_*: "ggx" and "lambert" are evaluated in closed form here */
    double *cache; /* internal (the fits' per-view cache of the texel-frame views); NULL from mix_init */
    double cache_wo[3], cache_a;
} mf_prefilter_mix;

/* Builds the mixture of `count` unit normals (xyz, n.z > 0), each of weight 1/count, bitwise
 * equal normals merged (their order: the first occurrence).  base: an isotropic model with a
 * sampler (e.g. "ggx"), or "lambert" (sampled here: the cosine about n(q)).  MF_ERR_DOMAIN,
 * MF_ERR_ALLOC. */
mf_status mf_prefilter_mix_init(mf_prefilter_mix *m, const mf_brdf_model *base, const double *normals,
                                int count) MF_WARN_UNUSED;
void mf_prefilter_mix_free(mf_prefilter_mix *m);

/* The albedo of the mixture at wo (wo.z > 0): sum_j w_j rho_j (see above), err the weighted sum
 * of the components' error estimates. */
mf_status mf_prefilter_mix_albedo(const mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo,
                                  mf_result *out) MF_WARN_UNUSED;

/* Monte Carlo integrals of functions over a square light, for the evaluations' ground truths
 * (mfkit prefilter-eval, analysis/study_prefilter_cell, analysis/render_prefilter_scenes' truth_mc).
 * The light, seen from the shading point at the origin: the square c + a e1 + b e2, |a|, |b| <= h, with
 * c its centre (at any distance) and e1, e2 orthonormal edge directions (its plane's normal n = e1 x e2;
 * either side is lit); what lies below the geometric horizon (wi.z <= 0) counts 0.
 *
 * Multiple importance sampling with the balance heuristic [Veach and Guibas 1995, "Optimally
 * combining sampling techniques for Monte Carlo rendering", Eq. 7 with n_1 = n_2]: strategy 0 draws a
 * uniform point of the light's area (density p_L(wi) = r^2 / (4 h^2 |wi . n|) per steradian, r the
 * point's distance), strategy 1 draws from the mixture's sampler (density p_M, mf_prefilter_mix's
 * `pdf`).  mf_prefilter_quad_mis_sample returns w = 1 / (p_L(wi) / 2 + p_M(wi) / 2) where wi is above
 * the horizon and on the light, else 0, and *fcos the mixture's f cos at wi (0 where w is 0; one pass
 * over the components for f and p_M).  With equally many samples of each strategy, (1/n) sum_i g(wi_i)
 * w_i is an unbiased estimate of the integral of g over the light for any g (p_L covers the light),
 * and where g is the mixture's f cos its variance is at most about twice that of the better strategy:
 * uniform points alone (the estimator before) have a variance that grows as the lobe narrows (alpha
 * 0.01 under a light of half side 0.8 about the mirror direction: relative standard error 0.43 to 0.52
 * at 4096 points against 0.0032 to 0.0040 here; tests/test_prefilter_quad_mis.c).  u: two uniform
 * numbers in [0, 1). */
typedef struct mf_prefilter_quad {
    mf_vec3 c, e1, e2;
    double h;
} mf_prefilter_quad;
double mf_prefilter_quad_mis_sample(const mf_prefilter_mix *m, const mf_brdf_params *p, mf_vec3 wo,
                                    const mf_prefilter_quad *q, int strategy, const double u[2], mf_vec3 *wi,
                                    double *fcos);
/* The mean and standard error of the estimator above from per-strategy sums of its terms g w: n[s]
 * terms of strategy s with sum s1[s] and sum of squares s2[s] (the strategies are independent:
 * variance (n_0 var_0 + n_1 var_1) / (n_0 + n_1)^2). */
void mf_prefilter_quad_mis_mean(const double n[2], const double s1[2], const double s2[2], double *mean, double *se);

/* MF_PREFILTER_ALBEDO_TABLE: the table's accuracy, measured by `bench_prefilter --size 32
 * --albedo-check 16` (2048 (texel, view) pairs of the synthetic bump map, slopes up to 0.8, the
 * default 8 x 16 views, alpha 0.1) against mf_model_albedo at n = 512: table worst 2.7e-3, mean
 * 1.36e-4; the rule it tabulates (mf_prefilter_mix_albedo, n = 64, revision 2) worst 3.4e-3, mean
 * 1.51e-4; table vs that rule worst 4.3e-3.  A lookup costs about 0.01 ms of CPU against the
 * rule's 0.67 ms (fused: 0.17 ms); the nodes cost 0.17 ms each, 833 per tilt slab, once per
 * process and alpha, only for the slabs the map's tilts touch. */

/* The one-texel GGX albedo of the fits' magnitudes (revision 3): the texel of unit normal n
 * (n.z > 0) at the geometric view wo (wo.z > 0), roughness alpha; the integral of
 * mf_prefilter_mix_albedo for a one-texel mixture, by the same rule fused (direct = 1), or
 * through the process-wide table of that rule over (texel-frame view elevation, tilt, relative
 * azimuth) with tricubic interpolation (direct = 0, what the fits use; see mf_prefilter.c and
 * MF_PREFILTER_ALBEDO_TABLE).  err: the rule's estimate |Q(n) - Q(n / 2)| (table: the largest at
 * the 8 nodes about the point, plus |tricubic - trilinear|).  MF_ERR_DOMAIN, MF_ERR_ALLOC. */
mf_status mf_prefilter_texel_albedo(double alpha, const double n[3], mf_vec3 wo, int direct,
                                    mf_result *out) MF_WARN_UNUSED;

typedef struct mf_prefilter_options {
    int base;            /* MF_PREFILTER_BASE_GGX (default) or MF_PREFILTER_BASE_LAMBERT */
    double alpha;        /* base GGX roughness (default 0.1; not read for Lambert) */
    int n_theta, n_phi;  /* views: theta_i = i / (n_theta - 1) MF_PREFILTER_THETA_MAX, phi_j = 2 pi j / n_phi
                            (default 8 x 16; n_theta >= 2, n_phi >= 1, each <= 256) */
    int threads;         /* 1..256 (default 1); the result does not depend on it */
    int samples;         /* directions per fit (mf_ltcfit_aniso_options; default 4096) */
    int max_iterations;  /* per fit (default 100) */
    uint64_t seed;       /* default 1 */
    int keep_albedo;     /* 1: magnitude = albedo / (the lobe's mass above the horizon,
                            (1 + n.z) / 2, n = M^T z / |M^T z|; floored at MF_PREFILTER_HORIZON_MIN), so
                            that the lobe's albedo is the effective BRDF's; 0: magnitude = albedo (the
                            mass an LTC puts below the horizon is lost, as in the thesis; the default, which keeps
                            magnitudes in [0, 1] for existing readers; the gate's energy check
                            fails on such tables at grazing views: measured up to 0.17 lost) */
    double cluster_cell; /* slope-space cell of the normal clusters, in units of alpha (GGX) or of
                            MF_PREFILTER_CLUSTER_LAMBERT (default MF_PREFILTER_CLUSTER_CELL); 0: none */
    /* Progress: called with 1 after each stored lobe, from the worker threads (so it must be thread
     * safe), outside the library's locks; NULL (the default): not called.  It does not change the
     * result. */
    void (*progress)(void *user, long lobes);
    void *progress_user;
    int fit_lights;      /* the fits' light family: MF_PREFILTER_LIGHTS_LADDER (0, the default since revision 6):
                            the structured family plus, for GGX, a ladder of squares sized by the base
                            lobe (mf_ltcfit_aniso_options.ladder_alpha = alpha; Lambert: no ladder, the
                            same lobes as MF_PREFILTER_LIGHTS_LOBE); MF_PREFILTER_LIGHTS_LOBE (1): the
                            structured family alone, every light sized by the footprint lobe's own spread
                            (revision 5; for comparisons).  docs/prefilter_log.md, "The fit's light family" */
    int level1_shift;    /* level 1 (2 x 2 footprints, three quarters of a map's lobes) fits with
                            max(64, samples >> level1_shift) directions (default 2 for GGX: 1024 of 4096,
                            revision 7; 0 for Lambert and the diffuse defaults: samples); 0..8.
                            docs/prefilter_log.md, "Speed of revision 7" */
    int lobe;            /* 0 (the default): each entry's lobe is fitted to the whole footprint's effective
                            BRDF.  1 or 2: to the part of it of one half of the footprint's texels, half a
                            (1) or half b (2) of the 2-means split of its normals (mf_prefilter_split_two),
                            so that the two tables' lobes sum to a two-lobe table: the entry's magnitude and
                            albedo are the half's share, (1/N) sum over the half's texels of their albedos
                            (the two halves' albedos sum to the footprint's), and its M is the fit of the
                            half's own mixture (its texels at equal weights).  A footprint with one distinct
                            normal has no split: half a is all of it, half b empty (M the identity,
                            magnitude and albedo 0).  docs/prefilter.md, "Two lobes per entry" */
    int reuse;           /* 1 (the default): a footprint whose fit has exactly the inputs of one already
                            fitted in the same call (its normals or clusters in the same order, their
                            weights, its albedos, its half's share and its number of directions, all bit
                            for bit) gets a copy of that footprint's lobes and fit statistics instead of
                            its own fits, which would compute the same bits (a fit depends on nothing
                            else: not on the footprint's place, nor on the other footprints).  Within one
                            call (one tile of the pipeline), at most MF_PREFILTER_REUSE_BYTES of copies
                            kept.  0: every footprint fitted.  The lobes, albedos, magnitudes and
                            statistics are the same bits either way (tested); only the time differs.
                            docs/prefilter.md, "Identical footprints are fitted once" */
} mf_prefilter_options;

/* The memory for the copies of options.reuse within one call: about 20 KB per distinct footprint at
 * 8 x 16 views, so a default region tile (64 x 64 texels, 1,365 footprints) keeps all of its own. */
#define MF_PREFILTER_REUSE_BYTES ((size_t)96 << 20)

#define MF_PREFILTER_LIGHTS_LADDER 0
#define MF_PREFILTER_LIGHTS_LOBE 1

void mf_prefilter_options_default(mf_prefilter_options *o);
/* The diffuse table's defaults: Lambert, 2 x 4 views, the rest as mf_prefilter_options_default. */
void mf_prefilter_options_default_diffuse(mf_prefilter_options *o);

/* One level's lobes.  Index (row from the top, column, i_theta, i_phi) in C order. */
typedef struct mf_prefilter_level {
    int level, width, height, n_theta, n_phi;
    float *m;          /* (h, w, n_theta, n_phi, 3, 3): forward M, row-major */
    float *magnitude;  /* (h, w, n_theta, n_phi): the lobe's magnitude: the effective BRDF's albedo,
                          divided by the lobe's mass above the horizon when options.keep_albedo */
    float *albedo;     /* (h, w, n_theta, n_phi): the effective BRDF's albedo (the exact mixture of the
                          texels' albedos) */
    double worst_residual, worst_albedo_err;
    int not_converged;
    long iterations, lobes;
    long reused; /* of lobes, those copied from an identical footprint (options.reuse); not in the files */
} mf_prefilter_level;

/* Fits every level >= 1 of a width x height map of unit normals (xyz per texel, rows from the
 * top, n.z > 0; width and height powers of two, at least one > 1): *levels gets
 * log2(max(width, height)) records (free with mf_prefilter_levels_free).  MF_ERR_DOMAIN with msg
 * (bad options or map), MF_ERR_ALLOC, MF_ERR_INTERNAL. */
mf_status mf_prefilter_run(const double *normals, int width, int height, const mf_prefilter_options *o,
                           mf_prefilter_level **levels, int *nlevels, char *msg, size_t msg_size) MF_WARN_UNUSED;
void mf_prefilter_levels_free(mf_prefilter_level *levels, int nlevels);

/* mf_prefilter_run for the levels first_level..log2(max(width, height)) only: the records of the
 * levels below first_level have width = height = 0 and no arrays.  Each footprint's lobes depend
 * only on its own normals and the options, so a tile of the map (a sub-map whose footprints are
 * footprints of the whole map) gives bit for bit the whole map's lobes of those footprints: the
 * `mfkit prefilter` pipeline fits the map tile by tile with it. */
mf_status mf_prefilter_run_from(const double *normals, int width, int height, const mf_prefilter_options *o,
                                int first_level, mf_prefilter_level **levels, int *nlevels, char *msg,
                                size_t msg_size) MF_WARN_UNUSED;

/* The effective BRDF's albedos of a level: a footprint's is the mean of its texels' one-texel
 * albedos (Nahmias 2022, Eq. 2.36: an equal-weight mixture), computed as the mean of its children's
 * at the level below (2 x 2 children, 2 x 1 once a dimension is 1), level by level from level 0.
 * That order is fixed, so a level's albedos do not depend on the tile that computes them, and a tile
 * can start from the albedos of a level below its first one instead of its level-0 texels':
 * mf_prefilter_run_tile.  Memory: the cache of level 0 (16 bytes per texel and view) and the next
 * level up. */

/* The albedos of level `level` (1..log2(max(width, height))) of a width x height map: out gets, per
 * texel of that level (rows from the top) and view (i_theta, i_phi), the albedo and its quadrature
 * error estimate, 2 * max(width >> level, 1) * max(height >> level, 1) * n_theta * n_phi doubles.
 * The `mfkit prefilter` pipeline computes them once per region tile (its top level), so that the
 * footprint tiles above never hold level-0 albedos. */
mf_status mf_prefilter_albedo_level(const double *normals, int width, int height, const mf_prefilter_options *o,
                                    int level, double *out, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* mf_prefilter_run_from with the albedos of level base_level (0 <= base_level < first_level; the
 * layout of mf_prefilter_albedo_level's output for this sub-map) given: the tile's albedos are
 * reduced from them, so it computes no one-texel albedos.  albedo_base NULL: from level 0 (as
 * mf_prefilter_run_from).  The same bits either way. */
mf_status mf_prefilter_run_tile(const double *normals, int width, int height, const mf_prefilter_options *o,
                                int first_level, const double *albedo_base, int base_level,
                                mf_prefilter_level **levels, int *nlevels, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* The gate before export (mf_prefilter_gate_run), over all levels of one table.  Lights: quads of
 * half-width 0.05, 0.2 and 0.8 about the view's mirror direction and about the normal (aligned
 * frame); a lobe's shading is magnitude * its LTC integral (one-sided, clipped at the horizon).
 *   energy: the lobe's albedo, magnitude * (1 + n.z) / 2 with n = M^T z / |M^T z| (its mass above
 *     the horizon), against the effective BRDF's albedo (the stored magnitude, the exact mixture of
 *     the texels' albedos): worst |ratio - 1| <= max_energy (default 0.01);
 *   nan: no non-finite matrix entry, magnitude or shading, no singular M;
 *   level: the effective BRDF of a footprint is exactly the mean of its four children's, so
 *     |parent shading - mean of the children's| / parent albedo <= max_level;
 *     (bound 0.5: one LTC cannot follow a two-lobed mixture, and the V-groove's level-2 lobe
 *     differs from the mean of its children's single lobes by up to 0.19 (3 x 4 views) and 0.33
 *     (8 x 16 views) of the albedo; a lobe mirrored into the wrong half-space differs by more);
 *   view (reported, pass_view, NOT part of pass): half the second difference of the shading
 *     along theta (interior rows) and phi (periodic), / albedo, against max_view_spike;
 *   texel (reported, pass_texel, NOT part of pass): a lone texel whose shading is above (or
 *     below) both neighbours along x or y by more than max_texel_spike albedo.
 * The view and texel measures have no reference: a coarse view grid or a sharp map gives genuine
 * spikes (measured on the V-groove: view 1.8 with 4 azimuths, texel 5.3: its level-1 texels
 * alternate between two tilts), so they cannot tell a local-minimum jump from the effective
 * BRDF's own variation; mf_prefilter_gate_run_ref measures them against a reference. */
#define MF_PREFILTER_GATE_ENERGY 0.01
#define MF_PREFILTER_GATE_LEVEL 0.5
#define MF_PREFILTER_GATE_VIEW_SPIKE 0.1
#define MF_PREFILTER_GATE_TEXEL_SPIKE 0.25
typedef struct mf_prefilter_gate {
    double max_energy, max_level, max_view_spike, max_texel_spike; /* bounds (inputs) */
    double worst_energy, worst_level, worst_view_spike, worst_texel_spike;
    long nan_entries;
    int pass, pass_energy, pass_nan, pass_level, pass_view, pass_texel;
    char where_energy[128], where_level[128], where_view[128], where_texel[128];
    /* continuity against a reference (mf_prefilter_gate_run_ref; zero and unused after
     * mf_prefilter_gate_run alone, has_ref = 0) */
    int has_ref;
    double max_cont_texel, max_cont_view;       /* bounds (inputs) */
    double worst_cont_texel, worst_cont_view;   /* reported: lone error spikes (see below) */
    double worst_jump_texel, worst_jump_view;   /* reported: the largest error jump between neighbours */
    double worst_ref_error;                     /* reported: max |lobe shading - reference| / albedo */
    int pass_cont_texel, pass_cont_view;
    char where_cont_texel[128], where_cont_view[128];
    double max_cont_grazing, worst_cont_grazing; /* both spikes at views with cos theta < MF_PREFILTER_MULTISTART_COS */
    int pass_cont_grazing;
    char where_cont_grazing[128];
    double max_cont_lambert; /* the Lambert table's bound for all three spikes (input) */
    int cont_gated;          /* 1: the continuity spikes are part of pass (the Lambert table) */
    /* (mf_prefilter_gate_run_ref; REPORTED, not part of pass, for both tables) cross: the error's lone
     * extreme along every axis at once -- the smallest, over the axes an entry has (texels x and y,
     * periodic; theta, interior rows; phi, rows theta > 0), of the lone extreme of e along that axis,
     * / albedo, over the entries with at least one texel axis (levels larger than 1 x 1); a map's
     * own variation is rarely an extreme along all of them (the V-groove's texels are the same along
     * y), one wrong lobe is.  cross_texel: the same over the texel axes alone.  pass_cont_cross
     * compares it with max_cont_cross (MF_PREFILTER_GATE_CONT_CROSS).  Measured (docs/prefilter_log.md,
     * "Gate"): 0 on good runs of the constant and V-groove maps, but 0.08-0.15 on the bump map's, at
     * single lobes that are wrong by that much against a brute-force integral of the effective BRDF
     * (so a bound would fail those runs: reported only). */
    double max_cont_cross, worst_cont_cross, worst_cont_cross_texel;
    int pass_cont_cross;
    char where_cont_cross[128];
    /* (mf_prefilter_gate_run_ref; GATED, part of pass, for both tables) excess: continuity across
     * texels measured against the effective BRDF's own change.  Per entry, light and axis (texels x
     * and y, periodic; theta, interior rows; phi, rows theta > 0), with S the lobe's shading and R the
     * reference: the lobe's lone extreme min(S - S0, S - S1) less the reference's own,
     * max(0, min(R - R0, R - R1)), and the same downwards; the smallest over the axes the entry has,
     * / albedo, the worst over the entries with a texel axis (levels larger than 1 x 1).  A lobe may
     * rise (or dip) as far as the footprint's effective BRDF does, and may smooth out the BRDF's own
     * extremes (the bump maps' worst cross entries were such: the reference dips where a light falls
     * between the footprint's texel lobes, the lobe does not).  pass_cont_excess: worst_cont_excess <=
     * max_cont_excess (MF_PREFILTER_GATE_CONT_EXCESS). */
    double max_cont_excess, worst_cont_excess;
    int pass_cont_excess;
    char where_cont_excess[128];
    /* (mf_prefilter_gate_run_ref; GATED, part of pass, for both tables) own fit: lobes copied, swapped
     * or shifted between neighbouring entries, which excess cannot see (a copy ties its neighbour).
     * Per entry, with s = S / albedo, r = R / albedo and r_j, s_j a neighbour's, |.| the largest over
     * the gate's lights (mf_prefilter_gate_own_fit):
     *   owner: the largest over the texel neighbours (x and y, periodic) of |s - r| - |s - r_j|, how
     *     much better the lobe shades a neighbour's footprint than its own (a lobe copied from, or
     *     swapped with, neighbour j shades r_j to j's own fitting error);
     *   owner_view: the same over the azimuth neighbours (phi +- 1, periodic; the same lights);
     *   dominated (reported): the largest, over both, of |s - r| - |s_j - r|, how much better a
     *     neighbour's lobe shades this footprint than the entry's own lobe does.
     * Every level is covered (the 1 x 1 top level by its azimuth neighbours).  pass_cont_owner: owner
     * and owner_view <= max_cont_owner (MF_PREFILTER_GATE_OWN_FIT) (docs/prefilter.md, "Gating copied
     * lobes (own fit)"). */
    double max_cont_owner, worst_cont_owner, worst_cont_owner_view, worst_cont_dominated;
    int pass_cont_owner;
    char where_cont_owner[128], where_cont_owner_view[128], where_cont_dominated[128];
    /* (mf_prefilter_gate_run_ref) own fit across elevations: the same measures over the theta
     * neighbours (a +- 1, the same texel and azimuth), whose gate lights about the mirror direction
     * lie about another mirror direction.  Each lobe is shaded under its theta neighbours' three
     * mirror lights as well (the three lights about the normal are the same at every elevation), and
     * each entry is judged at its own view's lights (mf_prefilter_gate_own_fit_cross):
     *   owner_theta: max_j |s - r| - |x_j - r_j|, x_j the lobe's shading of j's lights / albedo, r_j
     *     j's reference of its lights / j's albedo: how much better the lobe shades the neighbouring
     *     elevation's footprint view than its own (a lobe copied from, or swapped with, j);
     *   dominated_theta (reported): max_j |s - r| - |y_j - r|, y_j j's lobe under this entry's lights.
     * pass_cont_owner_theta: owner_theta <= max_cont_owner_theta (MF_PREFILTER_GATE_OWN_FIT_THETA);
     * owner_theta_gated: 1 when it is part of pass (docs/prefilter.md, "Own fit across elevations"). */
    double max_cont_owner_theta, worst_cont_owner_theta, worst_cont_dominated_theta;
    int pass_cont_owner_theta, owner_theta_gated;
    char where_cont_owner_theta[128], where_cont_dominated_theta[128];
    /* 1 for a table of one half of two lobes (options.lobe 1 or 2): pass is energy and nan alone.  The
     * level check (a parent's half is not the union of its children's halves: each level splits its own
     * footprints) and every check against the reference (the whole footprint's: a half shades part of
     * it) are computed and reported, not gated. */
    int half_table;
} mf_prefilter_gate;

/* Sets the default bounds and clears the results. */
void mf_prefilter_gate_bounds_default(mf_prefilter_gate *g);
/* Runs every check on levels[0 .. nlevels - 1] (mf_prefilter_run's output, all with the same
 * views) with g's bounds; MF_OK whether or not it passes (g->pass), MF_ERR_DOMAIN, MF_ERR_ALLOC. */
mf_status mf_prefilter_gate_run(const mf_prefilter_level *levels, int nlevels, mf_prefilter_gate *g) MF_WARN_UNUSED;

/* The gate with a reference (mf_prefilter_gate_run plus continuity measures).  normals: the
 * width x height map the levels were fitted to (as mf_prefilter_run takes it), o: the options
 * they were fitted with (base, alpha, views).
 *
 * Reference: the shading of the gate's lights by the effective BRDF, computed independently of
 * the fits: per level-0 texel q, the polygon clipped at the geometric horizon (wi.z >= 0),
 * rotated into the texel frame (R_q^T, the view's azimuth about n(q) turned to 0) and
 * integrated with the base BRDF's isotropic LTC at the texel-frame view (wo_q with the
 * below-horizon rule of this file) [Heitz et al. 2016]: GGX's from mf_ltcfit_entry_fit at
 * MF_PREFILTER_GATE_REF_N elevations (u = sqrt(1 - cos theta) uniform, a, b, d and the
 * magnitude interpolated linearly in u, as a table lookup does), Lambert's exactly (the cosine
 * over the clipped polygon / pi).  A footprint's reference is the mean of its texels'
 * [Nahmias 2022, Eq. 2.36], computed as the mean of its children's (exact: equal areas).
 * With e = lobe shading - reference (per entry and light), divided by the entry's albedo (GGX:
 * REPORTED, not part of pass, pass_cont_* compare them with the max_cont_* bounds; Lambert: GATED,
 * cont_gated = 1, all three against max_cont_lambert, since there the reference is exact and good
 * runs stay below 0.012 of the albedo):
 *   cont_texel: a lone texel: e above (or below) both neighbours along x or y (periodic: maps
 *     tile) by more than max_cont_texel (the smaller of the two jumps);
 *   cont_view: the same along theta (interior rows) and phi (periodic), max_cont_view;
 *   cont_grazing: both of them at the views with cos theta < MF_PREFILTER_MULTISTART_COS;
 *   jump_texel, jump_view: the largest |e_A - e_B| between neighbours;
 *   ref_error: the largest |e|.
 * Why reported only: on good runs (V-groove, bump map; 8 x 8, 4 x 8 views) the single lobes' own
 * error against the reference varies between neighbours by up to 0.25 of the albedo, as much as a
 * lobe with one matrix entry scaled by 1.5 or swapped with its phi neighbour changes it
 * (docs/prefilter_log.md, "Gate": power and false alarms).  The default bounds (0.3) lie above every
 * good run measured.  Lambert: the fits follow the (smooth) diffuse mixture closely, so e stays
 * below 0.012 of the albedo on good runs (constant, V-groove, bump map, 2 x 4 views) and the
 * bound MF_PREFILTER_GATE_CONT_LAMBERT = 0.03 is gated.
 * The level check needs no reference: the reference is linear, so the parent's is exactly the
 * mean of its children's and the reference-corrected check equals max_level's.
 * MF_OK whether or not it passes; MF_ERR_DOMAIN (levels not those of the map and views),
 * MF_ERR_ALLOC, or the reference fit's error. */
#define MF_PREFILTER_GATE_REF_N 32
#define MF_PREFILTER_GATE_CONT_TEXEL 0.3
#define MF_PREFILTER_GATE_CONT_VIEW 0.3
#define MF_PREFILTER_GATE_CONT_GRAZING 0.3
#define MF_PREFILTER_GATE_CONT_LAMBERT 0.03
/* cross's reported bound: above the V-groove's and the constant map's good runs (0), below the
 * bump map's outlier lobes (0.08-0.15) */
#define MF_PREFILTER_GATE_CONT_CROSS 0.05
/* excess's gated bound: good runs of every map measured read at most 0.092 at the default views
 * (docs/prefilter.md, "Gating continuity across texels": false alarms and power) */
#define MF_PREFILTER_GATE_CONT_EXCESS 0.2
/* own fit's gated bound: good runs at the default views read at most 0.170 (texel neighbours, the
 * 64 x 64 bump map; 0.134, 0.156 at 16 and 32: the tail grows with the map) and 0.161 (azimuth
 * neighbours), 0.189 with the cheap fits of --samples 128, where a lobe cannot follow a dip of its
 * footprint's BRDF and sits nearer a neighbour's.  0.3 leaves a factor 1.76 at the default settings
 * and catches as many of the copies and swaps that change a light's shading by 0.4 of the albedo or
 * more as 0.25 did (docs/prefilter.md, "Gating copied lobes (own fit)") */
#define MF_PREFILTER_GATE_OWN_FIT 0.3
/* own fit across elevations (owner_theta): bound and whether it is part of pass.  Good runs read at most
 * 0.218 (the demo V-groove at 4 x 8 views, whose two-normal footprints a single lobe cannot follow;
 * bump maps 0.147 to 0.169 from 16^2 to 128^2; diffuse tables at most 0.012): a factor 1.37.  It
 * catches every theta copy, swap and one-elevation shift of >= 0.4 of the albedo measured (57 of 57;
 * the gate before it 38) (docs/prefilter.md, "Own fit across elevations") */
#define MF_PREFILTER_GATE_OWN_FIT_THETA 0.3
#define MF_PREFILTER_GATE_OWN_FIT_THETA_GATED 1
/* The GGX roughness every bound above was set at (the default).  Below it one lobe's own error reaches the
 * bounds on the shipped maps (at 0.05: own fit across elevations 0.30 to 0.35) while the lobes still beat
 * every baseline per level; bounds scaled with roughness would catch half the corruptions (docs/prefilter.md,
 * "Fitter revision 9").  `mfkit prefilter` says so when the gate fails below it. */
#define MF_PREFILTER_GATE_TUNED_ALPHA 0.1
mf_status mf_prefilter_gate_run_ref(const mf_prefilter_level *levels, int nlevels, const double *normals, int width,
                                    int height, const mf_prefilter_options *o, mf_prefilter_gate *g) MF_WARN_UNUSED;

/* The own-fit check of one entry against its neighbours (the gate's owner and dominated measures; a
 * separate function so that any traversal of the entries can call it).  S, R: the entry's lobe
 * shading and reference of nlights lights, albedo its effective BRDF's albedo; nS[j], nR[j], nalb[j]
 * the same of neighbour j (0 <= j < nn), shaded under the same lights (the same view elevation: a
 * texel or azimuth neighbour).  With s = S / albedo, r = R / albedo, s_j = nS[j] / nalb[j],
 * r_j = nR[j] / nalb[j] (albedos below 1e-6 taken as 1e-6) and |.| the largest over the lights:
 *   owner = max_j |s - r| - |s - r_j|, owner_at its j;
 *   dominated = max_j |s - r| - |s_j - r|, dominated_at its j.
 * The largest positive value and the first j reaching it; 0 and -1 when none is positive, when the
 * entry has a non-finite value (the gate's nan check counts it), and for the neighbours with one
 * (skipped).  Any of the pointers may be NULL when nn is 0. */
typedef struct mf_prefilter_gate_own {
    double owner, dominated;
    int owner_at, dominated_at;
} mf_prefilter_gate_own;
void mf_prefilter_gate_own_fit(int nlights, const double *S, const double *R, double albedo, int nn,
                               const double *const *nS, const double *const *nR, const double *nalb,
                               mf_prefilter_gate_own *out);
/* The same across lights that differ between the entry and its neighbours (theta neighbours: their
 * gate lights lie about another mirror direction).  S, R, albedo: the entry's shading and reference of
 * its own lights; for neighbour j: xS[j] the entry's lobe under j's lights, nR[j] j's reference of
 * j's lights, yS[j] j's lobe under the entry's lights, nalb[j] j's albedo.  With s, r as above,
 * x_j = xS[j] / albedo, y_j = yS[j] / nalb[j], r_j = nR[j] / nalb[j]:
 *   owner = max_j |s - r| - |x_j - r_j|;  dominated = max_j |s - r| - |y_j - r|;
 * the rest as mf_prefilter_gate_own_fit, which is this function with xS[j] = S and yS[j] = nS[j]
 * (the same bits). */
void mf_prefilter_gate_own_fit_cross(int nlights, const double *S, const double *R, double albedo, int nn,
                                     const double *const *xS, const double *const *nR, const double *const *yS,
                                     const double *nalb, mf_prefilter_gate_own *out);

/* The gate streamed row by row, for levels not held whole (`mfkit prefilter`'s assembly): the same
 * result as mf_prefilter_gate_run (normals NULL) or mf_prefilter_gate_run_ref (normals, width,
 * height, o as there), bit for bit, places included (ties go to the first place of a whole-level
 * pass).  shapes: the levels' level, width, height, n_theta, n_phi (their arrays are not read).
 * Rows must come in the order mf_prefilter_gate_stream_next gives (each level's rows in order,
 * level l's row r right after rows 2r and 2r + 1 of level l - 1); the stream holds five rows of
 * each level (S and R: 2 x GATE_NLIGHTS doubles per lobe, plus a float), so its memory is
 * about 5 x 100 bytes x the lobes of one row of each level, independent of the map's height.
 * Threads: o->threads (1 without o) split each row's columns; the result, places included, is the
 * same bytes for any count (the threads' worsts are merged with the ties rule above).
 *   begin: checks the shapes (as the entry points do), clears g's results, fits the reference's
 *     base lobes (GGX: MF_PREFILTER_GATE_REF_N small fits); MF_ERR_DOMAIN, MF_ERR_ALLOC;
 *   next: 1 and the level index (0 for level 1) and row wanted next, 0 when all were fed;
 *   row: the row's m (9 floats per lobe), magnitude and albedo (NULL: the magnitude) arrays,
 *     width * n_theta * n_phi lobes in C order; MF_ERR_DOMAIN if it is not the row next wants;
 *   end: sets g's pass flags and frees the stream; MF_ERR_DOMAIN (and frees) if rows are missing;
 *   free: frees a stream without finishing it (after an error). */
typedef struct mf_prefilter_gate_stream mf_prefilter_gate_stream;
mf_status mf_prefilter_gate_stream_begin(const mf_prefilter_level *shapes, int nlevels, const double *normals,
                                         int width, int height, const mf_prefilter_options *o, mf_prefilter_gate *g,
                                         mf_prefilter_gate_stream **out) MF_WARN_UNUSED;
int mf_prefilter_gate_stream_next(const mf_prefilter_gate_stream *s, int *level_index, int *row);
mf_status mf_prefilter_gate_stream_row(mf_prefilter_gate_stream *s, int level_index, int row, const float *m,
                                       const float *magnitude, const float *albedo) MF_WARN_UNUSED;
/* As mf_prefilter_gate_stream_row, with the row's reference R given (MF_PREFILTER_GATE_NLIGHTS doubles
 * per lobe, as mf_prefilter_gate_reference computes it; NULL: the stream computes it).  A stream with
 * normals only; the result is the same bytes as computing it.  `mfkit prefilter` reads the region
 * tiles' R from their files (docs/prefilter.md, "The gate across ranks"). */
mf_status mf_prefilter_gate_stream_row_ref(mf_prefilter_gate_stream *s, int level_index, int row, const float *m,
                                           const float *magnitude, const float *albedo,
                                           const double *ref) MF_WARN_UNUSED;
mf_status mf_prefilter_gate_stream_end(mf_prefilter_gate_stream *s) MF_WARN_UNUSED;
/* Two lobes per entry (the two-lobe table of options.lobe 1 and 2, gated as one table): called after
 * begin (a whole gate, not a region stream nor a half table's: options.lobe 0) and before the first row,
 * nlobes 2 makes every row's m hold 18 floats per entry (half a's M, then half b's), its magnitude 2 (a's,
 * b's) and its albedo (required) the entry's, the halves' sum.  Every check then reads the entry's
 * shading as the sum of its lobes' (energy: the sum of the lobes' albedos against the entry's), so the
 * level check and the checks against the reference judge the two-lobe table as they judge one lobe.
 * MF_ERR_DOMAIN otherwise. */
mf_status mf_prefilter_gate_stream_set_lobes(mf_prefilter_gate_stream *s, int nlobes) MF_WARN_UNUSED;
/* One row of a two-lobe table from its halves' rows (n entries each): m (18 n), mag (2 n), alb (n; the sum
 * of the halves', rounded once to float). */
void mf_prefilter_gate_pair_row(const float *ma, const float *ga, const float *aa, const float *mb, const float *gb,
                                const float *ab, size_t n, float *m, float *mag, float *alb);
/* The gate of a two-lobe table held whole: the levels of its halves a and b (mf_prefilter_run with
 * options.lobe 1 and 2; o: their options with lobe 0), fed with set_lobes 2.  MF_ERR_DOMAIN on levels of
 * different shapes or without arrays (matrices, magnitudes, albedos). */
mf_status mf_prefilter_gate_run_pair(const mf_prefilter_level *la, const mf_prefilter_level *lb, int nlevels,
                                     const double *normals, int width, int height, const mf_prefilter_options *o,
                                     mf_prefilter_gate *g) MF_WARN_UNUSED;
void mf_prefilter_gate_stream_free(mf_prefilter_gate_stream *s);

/* The gate's reference R where a region is fitted: for levels 1 .. nlevels of the width x height
 * map `normals` (shapes: level l + 1 at index l, its width, height max(width >> (l + 1), 1) ..., n_theta
 * and n_phi as o's; their arrays are not read), R[l] (the caller's, MF_PREFILTER_GATE_NLIGHTS doubles
 * per lobe in the level's C order) gets each lobe's reference shading of the gate's lights, the
 * values the streamed gate computes for the same entries of a map holding this region as a tile
 * (every footprint inside it: a region tile of `mfkit prefilter`), bit for bit.  Level 1's rows are
 * split over o->threads (the same bits for any count).  MF_ERR_DOMAIN, MF_ERR_ALLOC, or the reference
 * fit's status. */
#define MF_PREFILTER_GATE_NLIGHTS 6
mf_status mf_prefilter_gate_reference(const mf_prefilter_level *shapes, int nlevels, const double *normals, int width,
                                      int height, const mf_prefilter_options *o, double *const *R) MF_WARN_UNUSED;

/* The gate across tiles (docs/prefilter.md, "The gate across ranks").  A region tile's part of the
 * gate: every check of its entries, but the texel checks of its border entries (their neighbours lie
 * in the next tile), with the keys of its worsts (global: the map's levels and places).
 * mf_prefilter_gate_region computes it where the tile is fitted: levels 1 .. nlevels of the rw x rh
 * region at level-0 texel (x0, y0) of a map_w x map_h map (levels and R as mf_prefilter_gate_reference
 * takes them, with their m, magnitude and albedo).  Rank 0 then begins its stream with
 * mf_prefilter_gate_stream_begin_regions (begin's arguments, and rw x rh, nreg: the region tiles' size
 * and levels; it needs no reference fit, as every level-1 R is given), feeds the region levels' rows
 * with their R (mf_prefilter_gate_stream_row_ref) and every tile's part once
 * (mf_prefilter_gate_stream_merge, any order): it computes S only for the two outer rings of each tile
 * and runs the texel checks of the borders (the seams) and everything at the levels above.  The result
 * is the same bytes as the whole gate's (the worsts merged by the gate's rule: the larger value, on a
 * tie the smaller key). */
typedef struct {
    mf_prefilter_gate res; /* the part's worsts, places, reported maxima and NaN count */
    uint64_t keys[14];     /* the worsts' keys: energy, level, view, texel, cont_texel, cont_view,
                              cont_grazing, cont_cross, cont_excess, cont_owner, cont_owner_view,
                              cont_dominated, cont_owner_theta, cont_dominated_theta */
} mf_prefilter_gate_part;
mf_status mf_prefilter_gate_region(const mf_prefilter_level *levels, int nlevels, double *const *R, int map_w,
                                   int map_h, int x0, int y0, int rw, int rh, const mf_prefilter_options *o,
                                   mf_prefilter_gate_part *part) MF_WARN_UNUSED;
mf_status mf_prefilter_gate_stream_begin_regions(const mf_prefilter_level *shapes, int nlevels, const double *normals,
                                                 int width, int height, int rw, int rh, int nreg,
                                                 const mf_prefilter_options *o, mf_prefilter_gate *g,
                                                 mf_prefilter_gate_stream **out) MF_WARN_UNUSED;
mf_status mf_prefilter_gate_stream_merge(mf_prefilter_gate_stream *s, const mf_prefilter_gate_part *p) MF_WARN_UNUSED;
/* The entries of a region tile's level whose R rank 0 reads: in row y (0 <= y < th) of the tile's tw x th
 * texels at that level, the columns [c[0], c[1]) and, if it returns 2, [c[2], c[3]): the tile's two
 * outer rings (the seams' texel checks read them; the top region level, whose R the level check above
 * averages, is 1 x 1 and so a ring).  Rank 0's stream reads no other entry's R, so `mfkit prefilter`
 * stores only these in its tile files (docs/prefilter.md, "The gate across ranks").  Returns 0 for
 * arguments out of range. */
int mf_prefilter_gate_ref_cols(int tw, int th, int y, int c[4]);

/* The 2-means split of mf_prefilter_options.lobe: count unit normals (xyz) into two halves, side[q] = 0
 * (half a) or 1 (half b); returns the size of half b, 0 when the normals do not split (one distinct
 * normal: every side 0).  Lloyd's iteration in R^3 from the normal farthest from the mean and the normal
 * farthest from that (the first such in the given order), at most 50 rounds; it depends only on the
 * normals and their order (a footprint's texels are taken row by row, so not on the tiling).  The
 * halves' order: half a is the one whose normals' mean has the larger x, then y, then z (on an exact
 * tie, the first-found cluster), so a groove's facets keep their tables across texels and levels
 * (a split along y has a seam where the order flips: any rule on an unoriented axis has one). */
int mf_prefilter_split_two(const double *normals, int count, int *side);

/* The view of table index (i_theta, i_phi). */
double mf_prefilter_theta(const mf_prefilter_options *o, int i);
double mf_prefilter_phi(const mf_prefilter_options *o, int j);

/* Reading an output directory back (mf_prefilter_files.c).  Each returns NULL (0) with a one-line
 * reason in msg on failure; the caller frees.
 * mf_prefilter_read_file: a whole file, NUL-terminated (the manifest prefilter.json).
 * mf_prefilter_read_npy: a little-endian float32 C-order .npy of the given rank (<= 8); its shape
 *   in dims.
 * mf_prefilter_json_string: the string value of "key": "..." in a JSON text (escapes \" and \\
 *   only), 1 if found and it fits in out. */
char *mf_prefilter_read_file(const char *path, size_t *len, char *msg, size_t msz);
float *mf_prefilter_read_npy(const char *path, int rank, long *dims, char *msg, size_t msz);
int mf_prefilter_json_string(const char *js, const char *key, char *out, size_t osz);

#ifdef __cplusplus
}
#endif
#endif /* MF_PREFILTER_H */
