/*
 * mf_ltc_reference.h -- read LTC tables that mfkit did not write: the CSV conversion of the public
 * reference table of Heitz et al. 2016 (`ltc_code`, fit/results/; tests/data/reference/README.md).
 *
 * The CSV has one row per texel with named columns; the reader uses
 *   i_alpha, i_theta                      texel indices (a = 0..n_r-1 along r, t = 0..n_u-1 along u)
 *   roughness, x_theta                    checked against a/(n_r-1) and t/(n_u-1) (1e-6)
 *   invMn_r0c0, invMn_r2c0, invMn_r0c2, invMn_r2c2   -> minv_00, minv_20, minv_02, minv_22 (ltc_1.rgba)
 *   magnitude, fresnel, sphere            -> magnitude, fresnel, sphere (ltc_2.r, .g, .a)
 * and ignores the others.  The result is an mfkit LTC table (mf_ltc_table.h) with the reference's
 * own clamps: alpha = max(r^2, 1e-5) (MF_LTC_REFERENCE_ALPHA_MIN; mfkit's own tables use 1e-4) and
 * theta_o <= 1.57 rad, texel centres on the grid points (the same convention as mfkit's).  The
 * values are the CSV's decimal values (6 significant digits as shipped), not rounded to float.
 */
#ifndef MF_LTC_REFERENCE_H
#define MF_LTC_REFERENCE_H

#include <stddef.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_table.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The reference fitter's alpha clamp. */
#define MF_LTC_REFERENCE_ALPHA_MIN 1e-5

/* Reads the reference CSV at path into *out (caller frees with mf_table_free; zeroed on failure).
 * Every texel of the n_r x n_u grid must appear exactly once (n_r, n_u >= 2 from the largest
 * indices).  msg (may be NULL) gets "path: reason" on failure, "" on success.
 * Returns MF_OK, MF_ERR_DOMAIN (NULL arguments), MF_ERR_IO (cannot open or read), MF_ERR_FORMAT
 * (missing column, bad number, duplicated or missing texel, axis values off the grid),
 * MF_ERR_ALLOC. */
mf_status mf_ltc_reference_read_csv(const char *path, mf_table *out, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* Non-zero when path names a file whose first line is a CSV header with the columns above (so a
 * command can accept either this CSV or an mfkit table file). */
int mf_ltc_reference_is_csv(const char *path);

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_REFERENCE_H */
