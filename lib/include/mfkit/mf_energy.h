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
 *    conductor by quadrature (mf_energy_favg_conductor).  The dielectric (mu, alpha, eta) table is
 *    not implemented (the pointwise reflection and transmission: mf_albedo_dielectric).
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

/* Progress callback: done of total texels. */
typedef void (*mf_energy_progress)(void *user, long done, long total);

/* The tables (n_mu x n_r texels, each >= 2; axes as above), tagged with their kind and the
 * metadata "ndf", "g2".  MF_ERR_DOMAIN for bad sizes, MF_ERR_ALLOC. */
mf_status mf_energy_dfg_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
                              mf_energy_progress progress, void *user) MF_WARN_UNUSED;
mf_status mf_energy_kulla_conty_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n_mu, int n_r,
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
/* The gates' check tables (for the registry). */
extern const mf_check_def mf_energy_dfg_checks[];
extern const int mf_energy_dfg_nchecks;
extern const mf_check_def mf_energy_kulla_conty_checks[];
extern const int mf_energy_kulla_conty_nchecks;

#ifdef __cplusplus
}
#endif
#endif /* MF_ENERGY_H */
