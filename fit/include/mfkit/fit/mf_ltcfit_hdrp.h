/*
 * mf_ltcfit_hdrp.h -- the isotropic LTC fitted on Unity HDRP's grid, in HDRP's layout.
 *
 * HDRP (com.unity.render-pipelines.high-definition: LTCAreaLight.hlsl, Lit.hlsl GetPreLightData,
 * LTCAreaLight.cs LoadLUT, LtcData.GGX.cs) samples its 64 x 64 LTC texture at
 *   uv = 0.5/64 + 63/64 (perceptualRoughness, theta / (pi/2)),   theta = acos(N.V),
 * i.e. texel (i_r, i_theta) holds r = i_r / 63 (alpha = r^2) and theta = i_theta / 63 * pi/2: a view
 * axis linear in theta, where mfkit's table (mf_ltc_table.h) uses u = sqrt(1 - cos theta).  Its
 * data is the C# array s_LtcGGXMatrixData[64 * 64, 9], row i_r + 64 i_theta, each row the 3 x 3
 * inverse matrix M^-1 (view frame of mf_ltc_view_frame) divided by its (2, 2) entry and stored
 * transposed: {m00, 0, m20, 0, m11, 0, m02, 0, 1} with m_ij = (M^-1)_ij / (M^-1)_22.  A shader
 * interpolating those rows bilinearly needs values fitted at those points, so every texel is
 * fitted there (mf_ltcfit_entry_fit), started from mfkit's table interpolated at the same point.
 */
#ifndef MF_LTCFIT_HDRP_H
#define MF_LTCFIT_HDRP_H

#include <mfkit/fit/mf_ltcfit.h>

#ifdef __cplusplus
extern "C" {
#endif

#define MF_LTC_HDRP_SIZE 64

typedef struct mf_ltcfit_hdrp_report {
    int fallbacks;         /* texels whose fit did not converge or was unusable: the start is kept */
    double worst_residual; /* over the converged fits */
    int worst_index;       /* its row */
} mf_ltcfit_hdrp_report;

/* Fits the n x n texels of HDRP's grid (n = MF_LTC_HDRP_SIZE for HDRP itself; >= 2) to the model
 * and writes rows[(i_r + n i_theta) * 9 + k] in HDRP's layout above.  start: a fitted isotropic
 * LTC table (mf_ltc_table.h) of the same model, interpolated for the starts and kept where a fit
 * fails.  alpha = max(r^2, MF_LTC_ALPHA_MIN), theta clamped to MF_LTC_THETA_MAX, as mfkit's fit.
 * The options' seed, samples, max_iterations and threads are used; the result does not depend
 * on the thread count.  MF_ERR_DOMAIN, MF_ERR_ALLOC. */
mf_status mf_ltcfit_hdrp(const mf_brdf_model *model, const mf_table *start, const mf_ltcfit_options *o, int n,
                         double *rows, mf_ltcfit_hdrp_report *report) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTCFIT_HDRP_H */
