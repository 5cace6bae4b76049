/*
 * mf_ltc_aniso_shader.h -- the GLSL/HLSL lookup snippet of an anisotropic LTC table
 * (mf_ltc_aniso_table.h, table kind "ltc_anisotropic"): the shader twin of mf_ltc_aniso_lookup.
 *
 * The table is stored as three 2D atlases (mf_table.h: axis 0 along x, axis 1 along y within a
 * tile, one tile per (theta, phi) with theta fastest), RGBA float, bilinear, clamp-to-edge:
 *   texture 0 = (m00, m01, m02, m10), texture 1 = (m11, m12, m20, m21),
 *   texture 2 = (m22, magnitude, fresnel, residual)          (mf_ltc_aniso_shader_fields)
 * (`mfkit fit ltc-aniso` writes them as <p>_m0.dds, <p>_m1.dds, <p>_m2.dds).
 *
 * The snippet (every name prefixed <prefix>_; docs/tables.md):
 *   <prefix>_ltc_angles(tex0, tex1, tex2, alpha_x, alpha_y, theta, phi)   any phi (radians)
 *   <prefix>_ltc_view(tex0, tex1, tex2, alpha_x, alpha_y, wo)             wo: unit view, tangent frame
 * return a struct <prefix>_ltc { mat3 minv; mat3 m; float magnitude; float fresnel; }: phi is
 * folded into [0, pi/2] with the mirrors S of mf_ltc_aniso_lookup, the 9 entries of M and the
 * scalars are interpolated over all four axes (hardware bilinear in (alpha_x, alpha_y) within a
 * tile, a manual lerp across theta and phi: the generic snippet's _lookup_params), M is
 * mirrored back (S M S) and inverted (adjugate / determinant).  minv * v (GLSL) or mul(minv, v)
 * (HLSL) applies M^-1 to a vector of the tangent frame.
 */
#ifndef MF_LTC_ANISO_SHADER_H
#define MF_LTC_ANISO_SHADER_H

#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_ltc_shader.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The table field of channel c (R, G, B, A) of texture k (mf_ltc_aniso_table.h's field indices). */
extern const int mf_ltc_aniso_shader_fields[3][4];

/* The snippet for t appended to out.  lang: MF_SHADER_GLSL or MF_SHADER_HLSL (WGSL:
 * MF_ERR_UNSUPPORTED); prefix an identifier of at most 64 characters (else MF_ERR_DOMAIN);
 * file_name for the first comment line (NULL: "<prefix>.glsl/.hlsl").  MF_ERR_UNSUPPORTED with a
 * one-line message if t does not have the anisotropic LTC layout. */
mf_status mf_ltc_aniso_shader_build(mf_buf *out, const mf_table *t, mf_shader_lang lang, const char *prefix,
                                    const char *file_name, char *msg, size_t msg_size) MF_WARN_UNUSED;

/* The same written to path (atomically, mf_io.h); the first comment line names path's file. */
mf_status mf_ltc_aniso_shader_write(const char *path, const mf_table *t, mf_shader_lang lang, const char *prefix,
                                    char *msg, size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_ANISO_SHADER_H */
