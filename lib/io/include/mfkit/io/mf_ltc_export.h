/*
 * mf_ltc_export.h -- the files real engines load unchanged, for an isotropic LTC table
 * (mf_ltc_table.h), and the readers that turn what users ship back into an LTC table.
 * docs/tables.md ("Engines") says which engine version loads which file and how.
 *
 * The generic formats (EXR, DDS, KTX2, ...) are in mf_table_io.h; the files here have an engine's
 * own layout:
 *   three.js   an ES module with the textures of three.js's RectAreaLightTexturesLib
 *              (LTC_FLOAT_1, LTC_FLOAT_2, LTC_HALF_1, LTC_HALF_2: 64 x 64 RGBA, texel (ir, iu) at
 *              4 (ir + 64 iu), ltc_1 = minv_00 minv_20 minv_02 minv_22, ltc_2 = magnitude fresnel
 *              zero sphere) and a drop-in RectAreaLightUniformsLib;
 *   EEVEE      a C header with Blender EEVEE's split arrays ltc_mat_<brdf>[64][64][4] (the minv
 *              fields) and ltc_mag_<brdf>[64][64][2] (magnitude, fresnel), indexed [iu][ir];
 *   RGBA EXR   ltc_1 / ltc_2 as 4-channel EXRs named R, G, B, A (OpenEXR sorts channel names;
 *              R, G, B, A is the one order image tools keep as RGBA).
 * three.js and EEVEE hard-code a 64 x 64 table over r, u in [0, 1] in their shaders: the writers
 * refuse other tables (MF_ERR_UNSUPPORTED) -- mf_ltc_table_is_dropin says which are accepted.
 *
 * Errors as in mf_table_io.h: "path: reason" in msg, atomic writes, MF_ERR_FORMAT for malformed input.
 */
#ifndef MF_LTC_EXPORT_H
#define MF_LTC_EXPORT_H

#include <stddef.h>

#include <mfkit/mf_core.h>
#include <mfkit/mf_table.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Non-zero if t is an LTC table (mf_ltc_table.h fields and axes r, u) of 64 x 64 texels over the
 * default ranges r, u in [0, 1]: the layout three.js's and EEVEE's shaders sample. */
int mf_ltc_table_is_dropin(const mf_table *t);

/* The three.js module (t: mf_ltc_table_is_dropin).  MF_ERR_UNSUPPORTED for another layout. */
mf_status mf_ltc_write_threejs(const char *path, const mf_table *t, char *msg, size_t msg_size) MF_WARN_UNUSED;
/* Unity HDRP's LTC data source file (LtcData.GGX.cs: partial class LTCAreaLight, static double
 * s_LtcGGXMatrixData[n * n, 9]) from rows in HDRP's layout (mf_ltcfit_hdrp.h: row i_r + n i_theta,
 * {m00, 0, m20, 0, m11, 0, m02, 0, 1} of M^-1 / (M^-1)_22), n = 64 for HDRP.  name: the array's
 * name (NULL: "s_LtcGGXMatrixData"; letters, digits, '_'); note: one more comment line (NULL:
 * none).  MF_ERR_DOMAIN for n < 2, a bad name or a non-finite value. */
mf_status mf_ltc_write_hdrp(const char *path, const double *rows, int n, const char *name, const char *note,
                            char *msg, size_t msg_size) MF_WARN_UNUSED;
/* The EEVEE header; brdf names the arrays (ltc_mat_<brdf>, [A-Za-z0-9_]+; NULL: the table's
 * "brdf" metadata, else "ggx").  MF_ERR_UNSUPPORTED for another layout, MF_ERR_DOMAIN for a bad name. */
mf_status mf_ltc_write_eevee(const char *path, const mf_table *t, const char *brdf, char *msg,
                             size_t msg_size) MF_WARN_UNUSED;
/* ltc_<which> (1: the minv fields, 2: magnitude fresnel zero sphere) as an EXR with channels R, G,
 * B, A, float32 or half; the mfkit metadata names the LTC field of every channel ("channels"), so
 * mf_ltc_read_pair reads the two back.  Needs the image backend (mf_image.h). */
mf_status mf_ltc_write_rgba_exr(const char *path, const mf_table *t, int which, int half_float, char *msg,
                                size_t msg_size) MF_WARN_UNUSED;

/* Reads the three.js module written by mf_ltc_write_threejs (its float arrays and metadata) as an
 * LTC table.  MF_ERR_FORMAT for another file. */
mf_status mf_ltc_read_threejs(const char *path, mf_table *out, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* Reads two RGBA files (DDS with or without sidecar, EXR, KTX2; any pair mf_table_read reads) as
 * the two textures of one LTC table: path1 holds minv_00 minv_20 minv_02 minv_22, path2 magnitude
 * fresnel zero sphere, unless their metadata names the fields.  Files without mfkit metadata (the
 * reference code's ltc_1.dds / ltc_2.dds) get the default axes r, u over [0, 1].  The two must have
 * the same size; *half_float is set if either stores halves (may be NULL).  MF_ERR_FORMAT when the
 * pair does not give the fields minv_* and magnitude exactly once. */
mf_status mf_ltc_read_pair(const char *path1, const char *path2, mf_table *out, int *half_float, char *msg,
                           size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_EXPORT_H */
