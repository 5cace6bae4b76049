/*
 * mf_ltc_shader.h -- area-light shader code for an isotropic LTC table (mf_ltc_table.h) in GLSL,
 * HLSL and WGSL, generated from one source (lib/io/src/ltc_shader_gen.c: one body written once in
 * a small neutral dialect, translated token by token; only a two-function prelude per language is
 * written separately), so the languages cannot drift.
 *
 * The code (every function prefixed <prefix>_, docs/tables.md "Shader code"):
 *   texture coordinates   _uv(alpha, cos_theta), _sphere_uv(f_cos, f_len): the texel-centre mapping
 *                         of the table's axes (as the .glsl/.hlsl lookup snippets);
 *   _minv(ltc_1 texel, N, V)  the world-space M^-1 (view frame of mf_ltc_view_frame);
 *   _polygon(minv, pts, n, two_sided)           mf_ltc_integrate_polygon (clipped after the transform);
 *   _polygon_clipless(ltc_2, minv, pts, n, two_sided)  the form factor + the table's sphere channel
 *                                              (mf_ltc_integrate_polygon_sphere, tabulated);
 *   _quad, _quad_clipless                      the same for 4 corners;
 *   _line(minv, p1, p2)                         mf_ltc_integrate_line (per unit width: x 2R);
 *   _disk(ltc_2, minv, c, v1, v2, two_sided)    mf_ltc_integrate_disk with the sphere channel;
 *   _fresnel(ltc_2 texel, f0)                   F0 magnitude + (1 - F0) fresnel.
 * Positions are relative to the shading point, in the world frame of N and V.
 *
 * For an anisotropic LTC table (mf_ltc_aniso_table.h) the same integrals come with its lookup
 * instead: _view(tg, bt, n, v) (the view in the tangent frame, tg along alpha_x), _fold(wo)
 * (theta, the azimuth folded into [0, pi/2], the mirror signs), _lookup(atlas, alpha_x, alpha_y,
 * fold) (one of the three atlases, interpolated over all four axes), _minv(t0, t1, t2, fold, tg,
 * bt, n) (M mirrored back, inverted, in world space; mf_ltc_aniso_lookup), _fresnel(t2 texel, f0);
 * the clipless and disk integrals use the closed-form sphere integral _sphere(f)
 * (mf_ltc_sphere_integral) and take no texture.
 */
#ifndef MF_LTC_SHADER_H
#define MF_LTC_SHADER_H

#include "mfkit/io/mf_io.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mf_shader_lang { MF_SHADER_GLSL = 0, MF_SHADER_HLSL = 1, MF_SHADER_WGSL = 2 } mf_shader_lang;

/* "glsl", "hlsl", "wgsl" (the file extensions); parse returns 0 on success. */
const char *mf_shader_lang_name(mf_shader_lang lang);
int mf_shader_lang_parse(const char *name, mf_shader_lang *out);

/* The shader code for the LTC table t (its axes give the texture-coordinate constants) appended to
 * out.  prefix: an identifier ([A-Za-z_][A-Za-z0-9_]*, at most 64 characters).  MF_ERR_UNSUPPORTED
 * (with a one-line message) if t is neither an isotropic nor an anisotropic LTC table; MF_ERR_DOMAIN
 * for a bad prefix or language. */
mf_status mf_ltc_shader_build(mf_buf *out, const mf_table *t, mf_shader_lang lang, const char *prefix, char *msg,
                              size_t msg_size) MF_WARN_UNUSED;

/* The same written to path (atomically, mf_io.h). */
mf_status mf_ltc_shader_write(const char *path, const mf_table *t, mf_shader_lang lang, const char *prefix,
                              char *msg, size_t msg_size) MF_WARN_UNUSED;

#ifdef __cplusplus
}
#endif
#endif /* MF_LTC_SHADER_H */
