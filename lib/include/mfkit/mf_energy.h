/*
 * mf_energy.h -- the energy tables engines ship beside their LTC tables, computed with the
 * accurate albedo of mf_albedo.h (isotropic GGX or Beckmann, joint or separable G2).
 *
 *  split-sum DFG [Karis 2013, "Real Shading in Unreal Engine 4", the environment BRDF]: per
 *    (cos theta_o, alpha) the Schlick scale and bias, F0 scale + bias = the directional albedo
 *    with Schlick's Fresnel of wo.wm.  Kind "dfg" (mf_table_kind.h): axes "mu" (cos theta_o,
 *    identity) and "r" (alpha = r^2, clamped to 1e-4), texel centres at (i + 0.5) / n, default
 *    128 x 128 -- the size and parameterisation of Filament's DFG LUT (cos theta linear,
 *    perceptual roughness sqrt(alpha) linear); fields dfg_scale, dfg_bias and their error bounds.
 *    Filament stores (bias, scale + bias) instead; UE samples (NoV, Roughness) the same way.
 *    Third channel dfg_charlie (and its bound): the Charlie sheen albedo as Filament's DFG LUT
 *    defines it (DFV_Charlie of its IBL library: Charlie NDF [Estevez and Kulla 2017, Eq. 2],
 *    Neubelt-Pettineo visibility, F = 1, the same alpha = r^2), by mf_albedo_charlie.
 *  multiple-scattering compensation [Kulla and Conty 2017, "Revisiting Physically Based Shading
 *    at Imageworks", Sec. on energy compensation]: E(mu, alpha) (F = 1) and
 *    E_avg(alpha) = 2 integral_0^1 E(mu) mu dmu, with the compensation lobe
 *    f_ms(mu_o, mu_i) = (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), so that with F = 1
 *    E(mu_o) + integral f_ms mu_i dwi = 1 exactly.  Kind "kulla_conty": axes as "dfg", default
 *    32 x 32 (the size of the tables of Kulla and Conty's talk); fields E, E_err, E_avg,
 *    E_avg_err (E_avg repeated along mu).  For conductors the Fresnel average
 *    F_avg = 2 integral F(mu) mu dmu: Schlick (20 F0 + 1) / 21 in closed form, the exact
 *    conductor by quadrature (mf_energy_favg_conductor).
 *  the rough dielectric [Walter 2007, Eq. 20, 21; Kulla and Conty 2017; Turquin 2019]: per
 *    (mu, alpha, eta) the reflected and transmitted energy E_r, E_t (mf_albedo_dielectric, exact
 *    Fresnel), E = E_r + E_t, and per (alpha, eta) E_avg = 2 integral_0^1 E(mu) mu dmu, for the
 *    view outside (eta > 1) and inside (the _inv fields, at 1 / eta).  Kind "dielectric": axes
 *    "mu" (cos theta_o, identity), "r" (alpha = r^2, clamped to 1e-4), "z" (eta = 1 + 2 z^2,
 *    identity; physical name "eta_z"), texel centres at (i + 0.5) / n, default 16 x 16 x 16 -- the
 *    size and the mu and z parameterisation of Blender Cycles' table_ggx_glass_E / _inv_E (its
 *    lookup: x = mu, y = 1 - sqrt(alpha), z = sqrt((ior - 1) / 2), texel centres; so eta covers
 *    1.002 .. 2.88 and Cycles clamps beyond); Cycles' rough axis runs the other way (y = 1 - r).
 *    Fields: E_r, E_r_err, E_t, E_t_err, E, E_avg, E_avg_err, then the same 7 at 1 / eta.
 *
 * Gates (mf_table_kind_gate): finite fields; dfg: scale, bias >= 0 and scale + bias <= 1 within
 * their bounds, and a sample of 3 x 3 texels (both ends of each axis) against the independent nested Gauss-Kronrod reference
 * (mf_albedo_microfacet_reference) within the stored bound + 1e-10, and the Charlie channel at the
 * same texels against mf_albedo_charlie_reference within both bounds; kulla_conty: the white
 * furnace, E(mu_o) + (1 - E(mu_o)) (1 - E_avg') / (1 - E_avg) = 1 at every texel within the
 * propagated bound, E_avg' recomputed independently of the table (Gauss-Legendre in mu on other
 * nodes, fresh albedos).  The gates need the table's metadata "ndf" and "g2".
 *
 * Pure C11.
 */
#ifndef MF_ENERGY_H
#define MF_ENERGY_H

#include "mfkit/mf_albedo.h"
#include "mfkit/mf_check.h"
#include "mfkit/mf_table.h"

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MF_ENERGY_ALPHA_MIN 1e-4
#define MF_DFG_DEFAULT_SIZE 128
#define MF_KULLA_CONTY_DEFAULT_SIZE 32

/* The DFG terms at one point: alpha in [1e-4, 1] (isotropic), cos_theta_o in (0, 1]. */
mf_status mf_energy_dfg(mf_ndf_type ndf, mf_g2_form g2, double alpha, double cos_theta_o, mf_result *scale,
                        mf_result *bias) MF_WARN_UNUSED;
/* E(mu, alpha) with F = 1. */
mf_status mf_energy_e(mf_ndf_type ndf, mf_g2_form g2, double alpha, double mu, mf_result *e) MF_WARN_UNUSED;
/* E_avg(alpha) = 2 integral_0^1 E(mu) mu dmu by Gauss-Legendre in s (mu = s^2, weight 4 s^3) on
 * two panels, 12 points each; err = |Q12 - Q8| + the propagated albedo bounds. */
mf_status mf_energy_eavg(mf_ndf_type ndf, mf_g2_form g2, double alpha, mf_result *eavg) MF_WARN_UNUSED;
/* F_avg of Schlick: (20 F0 + 1) / 21 [Kulla and Conty 2017]. */
double mf_energy_favg_schlick(double f0);
/* F_avg of the exact conductor (mf_fresnel_conductor) by adaptive Gauss-Kronrod to 1e-13. */
mf_status mf_energy_favg_conductor(double eta, double k, mf_result *out) MF_WARN_UNUSED;

/* F_avg of the exact dielectric (mf_fresnel_dielectric), 2 integral_0^1 F(mu) mu dmu, eta = n_other /
 * n_view > 0: closed form below the critical cosine, adaptive Gauss-Kronrod to 1e-14 above it (mapped
 * smooth at its square-root kink).  The two sides obey 1 - F_avg(1/eta) = (1 - F_avg(eta)) / eta^2
 * (tested; docs/math.md). */
mf_status mf_energy_favg_dielectric(double eta, mf_result *out) MF_WARN_UNUSED;

/* Splitting the dielectric compensation lobe [Kulla and Conty 2017, the dielectric part of their
 * energy compensation]: of the missing energy 1 - E(mu_o) seen from the side where the relative index
 * is eta (eta = n_other / n_view), the fraction *t is transmitted and 1 - *t reflected:
 *   t = (1 - F_avg(eta)) A / (A + B),  A = eta^2 (1 - F_avg(1/eta)) (1 - E_avg(1/eta)),
 *   B = (1 - F_avg(eta)) (1 - E_avg(eta)).
 * eavg = E_avg(eta) (this side, total E = E_r + E_t), eavg_inv = E_avg(1/eta) (the other side), favg,
 * favg_inv = F_avg(eta), F_avg(1/eta).  The other side's fraction is the same call with the pairs
 * swapped and 1/eta; the two make the compensation's transmitted flux balance,
 * t (1 - E_avg(eta)) = eta^2 t' (1 - E_avg(1/eta)) (reciprocity: docs/math.md).  With the dielectric
 * table: on the outside eta = the z axis' eta, eavg = E_avg, eavg_inv = E_avg_inv; inside the pairs
 * swap.  The lobes, per unit projected solid angle of wi, in the table's energy units (E_t is the
 * transmitted energy; a BTDF in radiance units scales the transmission as its own E_t):
 *   reflection    mf_energy_kc_lobe(1 - t, E(mu_o), E(mu_i), E_avg)        (wi on the view's side)
 *   transmission  mf_energy_kc_lobe(t, E(mu_o), E_inv(mu_i), E_avg_inv)    (wi on the other side)
 * with E = E_r + E_t; each integrates over its hemisphere to its weight times 1 - E(mu_o).
 * MF_ERR_DOMAIN for arguments out of range. */
mf_status mf_energy_dielectric_ms_split(double eta, double eavg, double eavg_inv, double favg, double favg_inv,
                                        double *t) MF_WARN_UNUSED;
/* weight max(0, 1 - e_o) max(0, 1 - e_i) / (pi (1 - eavg_i)) [Kulla and Conty 2017] (the clamps: an E
 * that rounds above 1 gives 0, not a negative lobe); 0 if eavg_i >= 1. */
double mf_energy_kc_lobe(double weight, double e_o, double e_i, double eavg_i);

/* ---- the dielectric table (kind "dielectric") ---- */
#define MF_DIELECTRIC_DEFAULT_SIZE 16
#define MF_DIELECTRIC_NFIELDS 14
/* The optional fields of a table made with the walk's split (mf_energy_dielectric_table_init_walk),
 * appended after the 14: t_walk, t_walk_se, t_walk_inv, t_walk_inv_se (the random walk's transmitted
 * fraction of its multiple scattering and its standard error, outside and inside), t_split,
 * t_split_inv (the balanced closure the lobes use), constant along mu. */
#define MF_DIELECTRIC_WALK_NFIELDS 20
extern const char *const mf_dielectric_table_fields[MF_DIELECTRIC_WALK_NFIELDS];
#define MF_ENERGY_DIELECTRIC_NCHECKS 6
/* eta of the z axis: 1 + 2 z^2 (Cycles' z = sqrt((eta - 1) / 2)). */
double mf_energy_dielectric_eta(double z);
/* E_avg = 2 integral_0^1 (E_r + E_t)(mu) mu dmu by global-adaptive Gauss-Kronrod to 1e-8 (at most
 * 200 intervals per piece) on panels ending, for eta < 1, on the kinks of E(mu): mu = eta,
 * sqrt(1 - eta^2) and 2 eta sqrt(1 - eta^2) (docs/math.md); each panel halved and each half mapped
 * with a square towards its kink (mu = kink +- u^2); err = the rule's estimate + the largest albedo
 * bound met.  (A fixed 12-point rule with |Q12 - Q8| as its bound was off by 140 times that bound at
 * alpha 0.77, eta 0.395: E(mu) has kinks.)  alpha in [1e-4, 1]. */
mf_status mf_energy_dielectric_eavg(mf_ndf_type ndf, mf_g2_form g2, double alpha, double eta,
                                    mf_result *eavg) MF_WARN_UNUSED;
/* The independent reference of E_T for the gate: nested adaptive Gauss-Kronrod over the transmitted
 * direction wt (polar angle from -z graded around the smooth refraction, azimuth graded around it),
 * the integrand D (1 - F) G2 (wo.h) / wo.z times dh/dwt [Walter 2007, Eq. 16, 17].  tol absolute;
 * MF_ERR_NO_CONVERGENCE if a rule ran out of intervals (out keeps its estimate). */
mf_status mf_energy_dielectric_transmission_reference(mf_ndf ndf, mf_g2_form g2, double mu, double eta, double tol,
                                                      mf_result *out) MF_WARN_UNUSED;
/* The independent reference of E_R and E_T for the gate and the tests: nested adaptive Gauss-Kronrod
 * over the micro-normal's polar angles about wo (not the normal), where total internal reflection is
 * the constant angle asin(eta) from wo; every kink (that one, the horizons of wi, wt and h) is a panel
 * end on each ray, and every azimuth where the kinks change order is a panel end of the outer rule,
 * with a square-root substitution beside the critical angle and beside those azimuths (docs/math.md,
 * "The dielectric energy reference").  tol absolute, per component; err = the outer rule's estimate
 * + tol / 4 + 1e-13 |val|.  Isotropic NDFs; MF_ERR_DOMAIN otherwise; MF_ERR_NO_CONVERGENCE if a rule
 * ran out of intervals (the outputs keep their estimates). */
mf_status mf_energy_dielectric_reference(mf_ndf ndf, mf_g2_form g2, double mu, double eta, double tol,
                                         mf_result *refl, mf_result *trans) MF_WARN_UNUSED;
/* Allocates and tags an n_mu x n_r x n_z dielectric table (values 0), then
 * mf_energy_dielectric_column fills column c (all mu of (r index c % n_r, z index c / n_r), both
 * sides) from nothing but t's axes and metadata: columns are independent, so any number of threads
 * may fill distinct columns and the table is bitwise the same for any order. */
mf_status mf_energy_dielectric_table_init(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                                          int n_z) MF_WARN_UNUSED;
mf_status mf_energy_dielectric_column(mf_table *t, long column) MF_WARN_UNUSED;

/* The split closed by the random walk (mfkit energy dielectric --split walk).  Kulla and Conty's
 * split caps the transmitted fraction at 1 - F_avg(eta), which true multiple scattering exceeds
 * (docs/math.md, "A split closed by the walk").  This one takes, per (alpha, eta) column and side,
 * the transmitted fraction of the walk's multiple scattering, cosine-averaged over the view
 * (mf_walk_dielectric_split, `walks` walks per side, generator (seed, stream 2 column + side)), and
 * projects the pair onto the balance the lobes need, t (1 - E_avg(eta)) = eta^2 t' (1 - E_avg(1/eta)):
 *   (t, t') = lambda (A, B),  A = eta^2 (1 - E_avg(1/eta)),  B = 1 - E_avg(eta),
 *   lambda = (A t_w / se^2 + B t'_w / se'^2) / (A^2 / se^2 + B^2 / se'^2)  (least squares in se units),
 * scaled down if needed so that both are <= 1.  A side without multiply scattered walks takes Kulla and
 * Conty's value with se 1/2 (no information; with none on either side the result is Kulla and Conty's
 * pair, which is balanced).  Inputs: E_avg and F_avg of both sides (as mf_energy_dielectric_ms_split).
 * Outputs (each [2]: outside = this eta, inside = 1 / eta): t_walk, se, t (the closure); chi = the
 * projection's residual in se units (sqrt of its chi-square, one degree of freedom); e1, the walk's own
 * single-scattering albedos (cosine averages). */
typedef struct mf_energy_walk_split {
    double t_walk[2], se[2], t[2], e1[2], chi;
    long ms[2], stopped;
} mf_energy_walk_split;
#define MF_ENERGY_WALK_SPLIT_WALKS 262144L /* 2^18 walks per side: se <= 0.015 from alpha 0.1 */
#define MF_ENERGY_WALK_SPLIT_SEED 14u
mf_status mf_energy_dielectric_walk_split(mf_ndf_type ndf, double alpha, double eta, double eavg, double eavg_inv,
                                          double favg, double favg_inv, long walks, uint64_t seed, uint64_t stream,
                                          mf_energy_walk_split *out) MF_WARN_UNUSED;
/* The projection alone (the gate recomputes it from stored fields): t_walk, se of both sides and the
 * balance's A, B as above -> t[2]; chi as above. */
void mf_energy_walk_split_project(const double t_walk[2], const double se[2], double a, double b, double t[2],
                                  double *chi);
/* A dielectric table with the walk split's 6 fields (20 in all); `walks` per side (>= 1000), recorded
 * in the metadata "split" = "walk", "split_walks", "split_seed".  mf_energy_dielectric_column fills
 * them too. */
mf_status mf_energy_dielectric_table_init_walk(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                                               int n_z, long walks) MF_WARN_UNUSED;

/* Progress callback: done of total texels. */
typedef void (*mf_energy_progress)(void *user, long done, long total);

/* The tables (n_mu x n_r texels, each >= 2; axes as above), tagged with their kind and the
 * metadata "ndf", "g2".  MF_ERR_DOMAIN for bad sizes, MF_ERR_ALLOC. */
mf_status mf_energy_dfg_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                              mf_energy_progress progress, void *user) MF_WARN_UNUSED;
mf_status mf_energy_kulla_conty_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                                      mf_energy_progress progress, void *user) MF_WARN_UNUSED;
/* The dielectric table, one thread (progress counts (alpha, eta) columns). */
mf_status mf_energy_dielectric_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r, int n_z,
                                     mf_energy_progress progress, void *user) MF_WARN_UNUSED;

#define MF_DFG_NFIELDS 6
extern const char *const mf_dfg_table_fields[MF_DFG_NFIELDS];
#define MF_ENERGY_DFG_NCHECKS 4
#define MF_KULLA_CONTY_NFIELDS 4
extern const char *const mf_kulla_conty_table_fields[MF_KULLA_CONTY_NFIELDS];

/* The gates' runners (registered as the kinds' gates).  storage_u: the unit roundoff of the storage
 * the table's values came through (mf_table_storage_roundoff: 2^-24 for a float32 file; 0 for a
 * table computed in memory): every stored value's bound is widened by storage_u |value|, since a
 * file keeps each value rounded but its error bound as computed. */
mf_status mf_energy_dfg_gate(const mf_table *t, double storage_u, mf_check *checks, int cap, int *count) MF_WARN_UNUSED;
mf_status mf_energy_kulla_conty_gate(const mf_table *t, double storage_u, mf_check *checks, int cap,
                                     int *count) MF_WARN_UNUSED;
/* dielectric: finite; E_r, E_t >= 0, E_r + E_t <= 1 at every texel; E_r and E_t against
 * mf_energy_dielectric_reference at every mu of the 4 corner (alpha, eta) columns and one mu of every
 * other column, both sides; the white furnace of the compensation lobe on E = E_r + E_t (as
 * kulla_conty's) at every mu of 3 x 3 (alpha, eta) columns, both sides (diel_furnace); at the same
 * texels the furnace of E_r + E_t + the lobe split into reflection and transmission
 * (mf_energy_dielectric_ms_split), and per column the reciprocity of the transmitted flux,
 * T(eta) = eta^2 T(1/eta), single scattering plus lobe (diel_split; with the stored t_split on a table
 * made with the walk's split).  Tables with the walk split's fields add diel_walk: t_split is the
 * balanced projection of the stored t_walk in every column (to rounding plus the propagated storage
 * rounding), and t_walk agrees with a fresh walk (seed + 1) within 4.5 se at the 3 x 3 gate columns. */
mf_status mf_energy_dielectric_gate(const mf_table *t, double storage_u, mf_check *checks, int cap,
                                    int *count) MF_WARN_UNUSED;
/* The gates' check tables (for the registry). */
extern const mf_check_def mf_energy_dfg_checks[];
extern const int mf_energy_dfg_nchecks;
extern const mf_check_def mf_energy_kulla_conty_checks[];
extern const int mf_energy_kulla_conty_nchecks;
extern const mf_check_def mf_energy_dielectric_checks[];
extern const int mf_energy_dielectric_nchecks;

#ifdef __cplusplus
}
#endif
#endif /* MF_ENERGY_H */
