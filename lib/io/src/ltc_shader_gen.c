/*
 * ltc_shader_gen.c -- GLSL, HLSL and WGSL area-light code for an LTC table from one source
 * (mf_ltc_shader.h).
 *
 * The body below is written once in a neutral dialect and translated token by token:
 *   types      float vec2 vec3 vec4 mat3 int bool (vec3[8]: an array)
 *   var T x = e;  let T x = e;  const T X = e;   declarations (let: immutable; WGSL needs the split)
 *   fn T name(T a, tex t, ...) { }               functions (fn void: no result)
 *   tex t      a texture parameter: GLSL sampler2D; HLSL Texture2D<float4> + SamplerState t_s;
 *              WGSL texture_2d<f32> + sampler t_s
 *   SAMPLE(t, uv)   bilinear sample at mip 0;   TEXARG(t)  passing a texture on
 *   atan2(y, x)     GLSL atan(y, x);            @_name  the prefix
 * Restrictions that keep one text valid in all three: braces on every if/else/for body, no ternary,
 * no assignment to parameters, no out parameters, no vector splat constructors, matrices only
 * through @_rows (from rows) and @_mul (matrix times vector), the per-language prelude.
 */
#include "io_internal.h"
#include "mfkit/io/mf_ltc_shader.h"
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/mf_ltc_table.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The isotropic table's lookup: texture coordinates, the texels, M^-1 in world space, Fresnel. */
static const char *const k_iso_lookup =
    "// ---- texture coordinates at the texel centres (docs/tables.md): p in [lo, hi] of n texels\n"
    "fn float @_coord(float p, float lo, float hi, float n) {\n"
    "    return (clamp(p, min(lo, hi), max(lo, hi)) - lo) / (hi - lo) * (n - 1.0) / n + 0.5 / n;\n"
    "}\n"
    "// the texture coordinate of (alpha, cos theta_o): r = sqrt(max(alpha, alpha_min)),\n"
    "// u = sqrt(1 - max(cos theta_o, cos_min))\n"
    "fn vec2 @_uv(float alpha, float cos_theta) {\n"
    "    let float r = sqrt(max(alpha, @_ALPHA_MIN));\n"
    "    let float u = sqrt(max(1.0 - max(cos_theta, @_COS_MIN), 0.0));\n"
    "    return vec2(@_coord(r, @_R_LO, @_R_HI, @_R_N), @_coord(u, @_U_LO, @_U_HI, @_U_N));\n"
    "}\n"
    "// the texture coordinate of the sphere channel (ltc_2.a) for a form factor of length f_len\n"
    "// whose direction has cosine f_cos with the normal: (r, u) = (f_cos / 2 + 1/2, f_len)\n"
    "fn vec2 @_sphere_uv(float f_cos, float f_len) {\n"
    "    return vec2(@_coord(0.5 * f_cos + 0.5, @_R_LO, @_R_HI, @_R_N), @_coord(f_len, @_U_LO, @_U_HI, @_U_N));\n"
    "}\n"
    "// the table's texels at (alpha, cos theta_o): ltc_1 = (minv_00, minv_20, minv_02, minv_22),\n"
    "// ltc_2 = (magnitude, fresnel, 0, sphere)\n"
    "fn vec4 @_lookup(tex table, float alpha, float cos_theta) {\n"
    "    return SAMPLE(table, @_uv(alpha, cos_theta));\n"
    "}\n"
    "// M^-1 in world space from the ltc_1 texel, the normal n and the view direction v (unit):\n"
    "// Minv = [[m00, 0, m02], [0, 1, 0], [m20, 0, m22]] in the view frame (s, t, n), s along v's\n"
    "// tangential part, t = n x s (mf_ltc_view_frame), times the rotation into that frame\n"
    "fn mat3 @_minv(vec4 t1, vec3 n, vec3 v) {\n"
    "    var vec3 s = v - n * dot(v, n);\n"
    "    if (dot(s, s) < 1e-12) {\n"
    "        if (abs(n.x) < 0.9) {\n"
    "            s = cross(n, vec3(1.0, 0.0, 0.0));\n"
    "        } else {\n"
    "            s = cross(n, vec3(0.0, 1.0, 0.0));\n"
    "        }\n"
    "    }\n"
    "    s = normalize(s);\n"
    "    let vec3 t = cross(n, s);\n"
    "    return @_rows(s * t1.x + n * t1.z, t, s * t1.y + n * t1.w);\n"
    "}\n"
    "// the Fresnel split of the ltc_2 texel: F0 magnitude + (1 - F0) fresnel (Schlick)\n"
    "fn vec3 @_fresnel(vec4 t2, vec3 f0) {\n"
    "    return f0 * t2.x + (vec3(1.0, 1.0, 1.0) - f0) * t2.y;\n"
    "}\n";

/* The isotropic sphere integral: the table's sphere channel. */
static const char *const k_iso_sphere =
    "// the horizon-clipped sphere integral of a form factor f (pointing into the light) from the\n"
    "// table's sphere channel: |f| ltc_2.a at (f.z / |f|, |f|) (mf_ltc_sphere_integral, tabulated)\n"
    "fn float @_sphere(tex ltc_2, vec3 f) {\n"
    "    let float f_len = length(f);\n"
    "    if (f_len <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    return f_len * SAMPLE(ltc_2, @_sphere_uv(f.z / f_len, f_len)).w;\n"
    "}\n";

/* The anisotropic table's lookup [Kt, Heitz, Dupuy, Narayanan 2022, Sec. 5]: the view in the tangent
 * frame, the azimuth folded into [0, pi/2] with the mirrors of mf_ltc_aniso_lookup, the three atlas
 * textures interpolated over all four axes (mf_table_lookup), M mirrored back, inverted (adjugate)
 * and taken to world space; Fresnel. */
static const char *const k_aniso_lookup =
    "// ---- texture coordinates at the texel centres (docs/tables.md): p in [lo, hi] of n texels\n"
    "fn float @_coord(float p, float lo, float hi, float n) {\n"
    "    return (clamp(p, min(lo, hi), max(lo, hi)) - lo) / (hi - lo) * (n - 1.0) / n + 0.5 / n;\n"
    "}\n"
    "// the continuous texel index of p in [0, n - 1] (the lerp across tiles)\n"
    "fn float @_pos(float p, float lo, float hi, float n) {\n"
    "    return clamp((p - lo) / (hi - lo) * (n - 1.0), 0.0, n - 1.0);\n"
    "}\n"
    "// tile number `tile` (theta index + n_theta phi index) of an atlas, bilinear at the in-tile\n"
    "// coordinate uv (within [0.5/n, 1 - 0.5/n], so the filter never reaches a neighbouring tile)\n"
    "fn vec4 @_tile(tex atlas, vec2 uv, float tile) {\n"
    "    let float row = floor((tile + 0.5) / @_TILES_X);\n"
    "    let float col = tile - row * @_TILES_X;\n"
    "    return SAMPLE(atlas, vec2((col + uv.x) * @_TILE_W / @_ATLAS_W, (row + uv.y) * @_TILE_H / @_ATLAS_H));\n"
    "}\n"
    "// the view direction in the tangent frame (tg along alpha_x, bt along alpha_y, n the normal; unit)\n"
    "fn vec3 @_view(vec3 tg, vec3 bt, vec3 n, vec3 v) {\n"
    "    return vec3(dot(v, tg), dot(v, bt), dot(v, n));\n"
    "}\n"
    "// the table coordinates of the view wo (tangent frame): vec4(theta, phi', s_x, s_y) with the azimuth\n"
    "// phi = atan2(wo.y, wo.x) folded into phi' in [0, pi/2] and the mirror S = diag(s_x, s_y, 1):\n"
    "// (pi/2, pi]: pi - phi, S_x; (pi, 3pi/2]: phi - pi, S_x S_y; (3pi/2, 2pi): 2pi - phi, S_y\n"
    "// (theta by atan2, not acos: accurate near the normal, and GPUs approximate acos coarsely --\n"
    "// llvmpipe's is off by 1.6e-4 rad, its atan2 by 3e-6)\n"
    "fn vec4 @_fold(vec3 wo) {\n"
    "    let float theta = atan2(sqrt(wo.x * wo.x + wo.y * wo.y), wo.z);\n"
    "    var float ph = 0.0;\n"
    "    if (wo.x != 0.0 || wo.y != 0.0) {\n"
    "        ph = atan2(wo.y, wo.x);\n"
    "    }\n"
    "    if (ph < 0.0) {\n"
    "        ph = ph + 2.0 * @_PI;\n"
    "    }\n"
    "    var float sx = 1.0;\n"
    "    var float sy = 1.0;\n"
    "    if (ph > 1.5 * @_PI) {\n"
    "        ph = 2.0 * @_PI - ph;\n"
    "        sy = -1.0;\n"
    "    } else if (ph > @_PI) {\n"
    "        ph = ph - @_PI;\n"
    "        sx = -1.0;\n"
    "        sy = -1.0;\n"
    "    } else if (ph > 0.5 * @_PI) {\n"
    "        ph = @_PI - ph;\n"
    "        sx = -1.0;\n"
    "    }\n"
    "    return vec4(theta, ph, sx, sy);\n"
    "}\n"
    "// the texel of one atlas (tex0 = (m00, m01, m02, m10), tex1 = (m11, m12, m20, m21), tex2 = (m22,\n"
    "// magnitude, fresnel, residual)) at (alpha_x, alpha_y) and the folded view fv: bilinear over the\n"
    "// two roughness axes by the sampler, linear across theta and phi between tiles (mf_table_lookup)\n"
    "fn vec4 @_lookup(tex atlas, float alpha_x, float alpha_y, vec4 fv) {\n"
    "    var float p1 = alpha_y;\n"
    "    if (@_LAMBDA > 0.5) {\n"
    "        p1 = 0.0;\n"
    "        if (alpha_x > 0.0) {\n"
    "            p1 = alpha_y / alpha_x;\n"
    "        }\n"
    "    }\n"
    "    let vec2 uv = vec2(@_coord(alpha_x, @_A0_LO, @_A0_HI, @_A0_N), @_coord(p1, @_A1_LO, @_A1_HI, @_A1_N));\n"
    "    let float f2 = @_pos(fv.x, @_A2_LO, @_A2_HI, @_A2_N);\n"
    "    let float f3 = @_pos(fv.y, @_A3_LO, @_A3_HI, @_A3_N);\n"
    "    let float i2 = min(floor(f2), @_A2_N - 2.0);\n"
    "    let float i3 = min(floor(f3), @_A3_N - 2.0);\n"
    "    let float w2 = f2 - i2;\n"
    "    let float w3 = f3 - i3;\n"
    "    let float k = i2 + @_A2_N * i3;\n"
    "    return @_tile(TEXARG(atlas), uv, k) * ((1.0 - w2) * (1.0 - w3)) + @_tile(TEXARG(atlas), uv, k + 1.0) * (w2 * (1.0 - w3))\n"
    "        + @_tile(TEXARG(atlas), uv, k + @_A2_N) * ((1.0 - w2) * w3) + @_tile(TEXARG(atlas), uv, k + @_A2_N + 1.0) * (w2 * w3);\n"
    "}\n"
    "// M^-1 in world space from the three texels at fv and the tangent frame: M(phi) = S M(phi') S\n"
    "// (entry (i, j) times s_i s_j), M^-1 = adj(M) / det M, times the rotation R = rows(tg, bt, n)\n"
    "fn mat3 @_minv(vec4 t0, vec4 t1, vec4 t2, vec4 fv, vec3 tg, vec3 bt, vec3 n) {\n"
    "    let vec3 s = vec3(fv.z, fv.w, 1.0);\n"
    "    let vec3 r0 = vec3(t0.x, t0.y, t0.z) * s * fv.z;\n"
    "    let vec3 r1 = vec3(t0.w, t1.x, t1.y) * s * fv.w;\n"
    "    let vec3 r2 = vec3(t1.z, t1.w, t2.x) * s;\n"
    "    // the columns of adj(M): r1 x r2, r2 x r0, r0 x r1; det M = r0 . (r1 x r2)\n"
    "    let vec3 c0 = cross(r1, r2);\n"
    "    let vec3 c1 = cross(r2, r0);\n"
    "    let vec3 c2 = cross(r0, r1);\n"
    "    let float inv_det = 1.0 / dot(r0, c0);\n"
    "    // row i of M^-1 R: (c0_i tg + c1_i bt + c2_i n) / det M\n"
    "    return @_rows((tg * c0.x + bt * c1.x + n * c2.x) * inv_det, (tg * c0.y + bt * c1.y + n * c2.y) * inv_det,\n"
    "        (tg * c0.z + bt * c1.z + n * c2.z) * inv_det);\n"
    "}\n"
    "// the Fresnel split of the tex2 texel: F0 magnitude + (1 - F0) fresnel (Schlick)\n"
    "fn vec3 @_fresnel(vec4 t2, vec3 f0) {\n"
    "    return f0 * t2.y + (vec3(1.0, 1.0, 1.0) - f0) * t2.z;\n"
    "}\n";

/* The anisotropic sphere integral, in closed form (the table has no sphere channel). */
static const char *const k_aniso_sphere =
    "// atan(z) - z for 0 <= z < 1: the series -z^3/3 + z^5/5 - ... below 0.1 (5 terms: the first omitted\n"
    "// one is below 1e-10 of the sum), the difference above (it keeps all but log10(3 / z^2) <= 2.5 digits)\n"
    "fn float @_atan_minus_x(float z) {\n"
    "    if (z >= 0.1) {\n"
    "        return atan(z) - z;\n"
    "    }\n"
    "    let float z2 = z * z;\n"
    "    return z * z2 * (-1.0 / 3.0 + z2 * (1.0 / 5.0 + z2 * (-1.0 / 7.0 + z2 * (1.0 / 9.0 - z2 / 11.0))));\n"
    "}\n"
    "// the horizon-clipped integral of max(0, z) / pi over the spherical cap whose form factor is f\n"
    "// (sin^2 sigma = |f|, centre at cos theta = f.z / |f|) [Snyder 1996, as in Heitz and Hill 2017], in\n"
    "// the rearranged form of mf_ltc_sphere_integral (docs/math.md)\n"
    "fn float @_sphere(vec3 f) {\n"
    "    let float f_len = length(f);\n"
    "    if (f_len <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let float s2 = min(f_len, 1.0);\n"
    "    let float c = clamp(f.z / f_len, -1.0, 1.0);\n"
    "    if (c * c >= s2) {\n"
    "        return max(c, 0.0) * s2;\n"
    "    }\n"
    "    if (s2 >= 1.0) {\n"
    "        return 0.5 * (1.0 + c);\n"
    "    }\n"
    "    let float sn = sqrt(1.0 - c * c);\n"
    "    let float x = sqrt(1.0 - s2) / sqrt(s2);\n"
    "    let float y = clamp(-x * c / sn, -1.0, 1.0);\n"
    "    let float sy = sqrt(max(1.0 - y * y, 0.0));\n"
    "    let float q = sn * sy;\n"
    "    let float z = q / x;\n"
    "    var float t = atan(z) - x * q * s2;\n"
    "    if (z < 1.0) {\n"
    "        t = @_atan_minus_x(z) + z * s2;\n"
    "    }\n"
    "    // acos(y) as atan2(sqrt(1 - y^2), y): GPUs approximate acos coarsely (see @_fold)\n"
    "    return (c * atan2(sy, y) * s2 + t) / @_PI;\n"
    "}\n";

/* The integrals shared by both tables (C twins in mf_ltc.h, mf_ltc_lights.h).  SPHERE_TEX and
 * SPHERE_ARG stand for the sphere integral's texture parameter and argument ("tex ltc_2, " and
 * "TEXARG(ltc_2), " for the isotropic table, nothing for the anisotropic one). */
static const char *const k_integrals_1 =
    "// one edge of Lambert's formula: theta / sin(theta) (a x b) for unit a, b (theta = angle(a, b);\n"
    "// atan2 keeps small angles accurate; the series 1 + theta^2/6 below sin theta = 1e-4)\n"
    "fn vec3 @_edge(vec3 a, vec3 b) {\n"
    "    let vec3 c = cross(a, b);\n"
    "    let float s = length(c);\n"
    "    let float th = atan2(s, dot(a, b));\n"
    "    var float k = 1.0 + th * th / 6.0;\n"
    "    if (s > 1e-4 || dot(a, b) < 0.0) {\n"
    "        k = th / s;\n"
    "    }\n"
    "    return c * k;\n"
    "}\n"
    "// integral of the LTC over the polygon pts[0..n-1] (n <= 8, positions relative to the shading\n"
    "// point): the transformed polygon clipped at z >= 0 AFTER the transform (Sutherland-Hodgman on\n"
    "// the fly), Lambert's formula; one-sided: 0 unless the corners run clockwise seen from the point\n"
    "fn float @_polygon(mat3 minv, vec3[8] pts, int n, bool two_sided) {\n"
    "    var vec3[8] q = pts;\n"
    "    for (var int i = 0; i < n; i++) {\n"
    "        q[i] = @_mul(minv, q[i]);\n"
    "    }\n"
    "    var float sum = 0.0;\n"
    "    var vec3 exit_p = vec3(0.0, 0.0, 0.0);\n"
    "    var vec3 first_entry = vec3(0.0, 0.0, 0.0);\n"
    "    var bool have_exit = false;\n"
    "    var bool pending = false;\n"
    "    for (var int i = 0; i < n; i++) {\n"
    "        let vec3 a = q[i];\n"
    "        let vec3 b = q[(i + 1) % n];\n"
    "        if (a.z >= 0.0 && b.z >= 0.0) {\n"
    "            sum = sum + @_edge(normalize(a), normalize(b)).z;\n"
    "        } else if (a.z >= 0.0) {\n"
    "            let vec3 x = normalize(a + (b - a) * (a.z / (a.z - b.z)));\n"
    "            sum = sum + @_edge(normalize(a), x).z;\n"
    "            exit_p = x;\n"
    "            have_exit = true;\n"
    "        } else if (b.z >= 0.0) {\n"
    "            let vec3 x = normalize(b + (a - b) * (b.z / (b.z - a.z)));\n"
    "            if (have_exit) {\n"
    "                sum = sum + @_edge(exit_p, x).z;\n"
    "            } else {\n"
    "                first_entry = x;\n"
    "                pending = true;\n"
    "            }\n"
    "            sum = sum + @_edge(x, normalize(b)).z;\n"
    "        }\n"
    "    }\n"
    "    if (pending) {\n"
    "        sum = sum + @_edge(exit_p, first_entry).z;\n"
    "    }\n"
    "    var float e = sum / (2.0 * @_PI);\n"
    "    if (determinant(minv) < 0.0) {\n"
    "        e = -e;\n"
    "    }\n"
    "    if (two_sided) {\n"
    "        return abs(e);\n"
    "    }\n"
    "    return max(e, 0.0);\n"
    "}\n";

static const char *const k_integrals_2 =
    "// the clipless variant of @_polygon for a planar polygon: the form factor of the unclipped\n"
    "// transformed polygon and @_sphere (mf_ltc_integrate_polygon_sphere)\n"
    "fn float @_polygon_clipless(SPHERE_TEX mat3 minv, vec3[8] pts, int n, bool two_sided) {\n"
    "    var vec3[8] q = pts;\n"
    "    let float facing = dot(cross(q[1] - q[0], q[2] - q[0]), q[0]);\n"
    "    if (!two_sided && facing <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    for (var int i = 0; i < n; i++) {\n"
    "        q[i] = normalize(@_mul(minv, q[i]));\n"
    "    }\n"
    "    var vec3 f = vec3(0.0, 0.0, 0.0);\n"
    "    for (var int i = 0; i < n; i++) {\n"
    "        f = f + @_edge(q[i], q[(i + 1) % n]);\n"
    "    }\n"
    "    f = f / (2.0 * @_PI);\n"
    "    if ((determinant(minv) < 0.0) != (facing < 0.0)) {\n"
    "        f = -f;\n"
    "    }\n"
    "    return @_sphere(SPHERE_ARG f);\n"
    "}\n"
    "// quads: corners p0..p3 (clockwise seen from the shading point for one-sided lights)\n"
    "fn float @_quad(mat3 minv, vec3 p0, vec3 p1, vec3 p2, vec3 p3, bool two_sided) {\n"
    "    var vec3[8] pts;\n"
    "    pts[0] = p0;\n"
    "    pts[1] = p1;\n"
    "    pts[2] = p2;\n"
    "    pts[3] = p3;\n"
    "    for (var int i = 4; i < 8; i++) {\n"
    "        pts[i] = p0;\n"
    "    }\n"
    "    return @_polygon(minv, pts, 4, two_sided);\n"
    "}\n"
    "fn float @_quad_clipless(SPHERE_TEX mat3 minv, vec3 p0, vec3 p1, vec3 p2, vec3 p3, bool two_sided) {\n"
    "    var vec3[8] pts;\n"
    "    pts[0] = p0;\n"
    "    pts[1] = p1;\n"
    "    pts[2] = p2;\n"
    "    pts[3] = p3;\n"
    "    for (var int i = 4; i < 8; i++) {\n"
    "        pts[i] = p0;\n"
    "    }\n"
    "    return @_polygon_clipless(SPHERE_ARG minv, pts, 4, two_sided);\n"
    "}\n"
    "// the cosine integral over the segment p1 p2 clipped to z >= 0, per unit width (mf_line_integrate_cosine)\n"
    "fn float @_line_cosine(vec3 p1_in, vec3 p2_in) {\n"
    "    var vec3 p1 = p1_in;\n"
    "    var vec3 p2 = p2_in;\n"
    "    if (p1.z < 0.0 && p2.z < 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    if (p1.z < 0.0) {\n"
    "        p1 = p1 + (p2 - p1) * (p1.z / (p1.z - p2.z));\n"
    "    } else if (p2.z < 0.0) {\n"
    "        p2 = p2 + (p1 - p2) * (p2.z / (p2.z - p1.z));\n"
    "    }\n"
    "    let vec3 d_vec = p2 - p1;\n"
    "    let float seg = length(d_vec);\n"
    "    if (seg <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let vec3 t = d_vec / seg;\n"
    "    let float d = length(cross(p1, t));\n"
    "    if (d <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let float l1 = dot(p1, t);\n"
    "    let float l2 = l1 + seg;\n"
    "    let vec3 po = p1 - t * l1;\n"
    "    let float d2 = d * d;\n"
    "    let float ab = (d2 + l1 * l1) * (d2 + l2 * l2);\n"
    "    let float i_po = seg * (d2 - l1 * l2) / ab + atan2(d * seg, d2 + l1 * l2) / d;\n"
    "    let float i_t = d * seg * (l1 + l2) / ab;\n"
    "    return 0.5 / @_PI * ((po.z / d) * i_po + t.z * i_t);\n"
    "}\n"
    "// integral of the LTC over a thin line light p1 p2 per unit width (x 2R for a cylinder of radius R;\n"
    "// mf_ltc_integrate_line): width factor |det M^-1| |p1 x p2| / |M^-1 p1 x M^-1 p2|\n"
    "fn float @_line(mat3 minv, vec3 p1, vec3 p2) {\n"
    "    let vec3 q1 = @_mul(minv, p1);\n"
    "    let vec3 q2 = @_mul(minv, p2);\n"
    "    let float co = length(cross(q1, q2));\n"
    "    if (co <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let float w = abs(determinant(minv)) * length(cross(p1, p2)) / co;\n"
    "    return w * @_line_cosine(q1, q2);\n"
    "}\n"
    "// integral of the LTC over the ellipse c + cos(phi) v1 + sin(phi) v2 (a disk: perpendicular v1, v2\n"
    "// of equal length), front-facing when (v1 x v2).c > 0 (mf_ltc_integrate_disk): the form factor of\n"
    "// the transformed ellipse from the negative eigenvalue of its cone, @_sphere for the horizon\n"
    "fn float @_disk(SPHERE_TEX mat3 minv, vec3 c_in, vec3 v1_in, vec3 v2_in, bool two_sided) {\n"
    "    if (!two_sided && dot(cross(v1_in, v2_in), c_in) <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let vec3 c = @_mul(minv, c_in);\n"
    "    let vec3 v1 = @_mul(minv, v1_in);\n"
    "    let vec3 v2 = @_mul(minv, v2_in);\n"
    "    let float d11 = dot(v1, v1);\n"
    "    let float d22 = dot(v2, v2);\n"
    "    let float d12 = dot(v1, v2);\n"
    "    let vec3 nv = cross(v1, v2);\n"
    "    let float area2 = dot(nv, nv);\n"
    "    if (area2 <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    // principal semi-axes of the ellipse\n"
    "    let float e_max = 0.5 * (d11 + d22 + sqrt((d11 - d22) * (d11 - d22) + 4.0 * d12 * d12));\n"
    "    let float e_min = area2 / e_max;\n"
    "    var vec3 e1 = v1 * d12 + v2 * (e_max - d11);\n"
    "    let vec3 e1b = v1 * (e_max - d22) + v2 * d12;\n"
    "    if (dot(e1b, e1b) > dot(e1, e1)) {\n"
    "        e1 = e1b;\n"
    "    }\n"
    "    if (dot(e1, e1) <= 0.0) {\n"
    "        e1 = v1;\n"
    "    }\n"
    "    e1 = normalize(e1);\n"
    "    var vec3 nrm = nv / sqrt(area2);\n"
    "    var float z0 = dot(nrm, c);\n"
    "    if (z0 < 0.0) {\n"
    "        nrm = -nrm;\n"
    "        z0 = -z0;\n"
    "    }\n"
    "    if (z0 <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let vec3 e2 = cross(nrm, e1);\n"
    "    let float x0 = dot(e1, c) / z0;\n"
    "    let float y0 = dot(e2, c) / z0;\n"
    "    let float al = z0 * z0 / e_max;\n"
    "    let float be = z0 * z0 / e_min;\n"
    "    // the negative root of the cone's cubic: trigonometric formula and one Newton step\n"
    "    let float c0 = al * be;\n"
    "    let float c1 = al * be * (1.0 + x0 * x0 + y0 * y0) - al - be;\n"
    "    let float c2 = 1.0 - al * (1.0 + x0 * x0) - be * (1.0 + y0 * y0);\n"
    "    let float pp = c1 - c2 * c2 / 3.0;\n"
    "    let float qq = 2.0 * c2 * c2 * c2 / 27.0 - c2 * c1 / 3.0 + c0;\n"
    "    let float r = sqrt(max(-pp / 3.0, 0.0));\n"
    "    var float cphi = -1.0;\n"
    "    if (r > 0.0) {\n"
    "        cphi = clamp(-qq / (2.0 * r * r * r), -1.0, 1.0);\n"
    "    }\n"
    "    var float lam = -2.0 * r * cos((acos(cphi) - @_PI) / 3.0) - c2 / 3.0;\n"
    "    let float pv = ((lam + c2) * lam + c1) * lam + c0;\n"
    "    let float dv = (3.0 * lam + 2.0 * c2) * lam + c1;\n"
    "    if (dv > 0.0) {\n"
    "        lam = lam - pv / dv;\n"
    "    }\n"
    "    if (lam >= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let float dp = -c0 / lam + c2 * lam + 2.0 * lam * lam;\n"
    "    if (dp <= 0.0) {\n"
    "        return 0.0;\n"
    "    }\n"
    "    let float f_len = min(1.0, abs(lam) / sqrt(dp));\n"
    "    let vec3 axis = normalize(e1 * (al * x0 / (al - lam)) + e2 * (be * y0 / (be - lam)) + nrm);\n"
    "    return @_sphere(SPHERE_ARG axis * f_len);\n"
    "}\n";

/* ---- the translator ----------------------------------------------------------------------- */

typedef struct gen {
    mf_buf *b;
    mf_shader_lang lang;
    const char *prefix;
} gen;

static const char *map_type(const gen *g, const char *t)
{
    static const char *const names[][3] = {
        {"float", "float", "f32"},           {"vec2", "float2", "vec2<f32>"}, {"vec3", "float3", "vec3<f32>"},
        {"vec4", "float4", "vec4<f32>"},     {"mat3", "float3x3", "mat3x3<f32>"}, {"int", "int", "i32"},
        {"bool", "bool", "bool"},            {"void", "void", "void"}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        if (!strcmp(t, names[i][0]))
            return names[i][g->lang];
    return NULL;
}

static int is_id(int c) { return isalnum(c) || c == '_'; }

/* reads an identifier (or @_name, the prefix expanded) at *s into out; 0 if none */
static int read_id(const gen *g, const char **s, char *out, size_t size)
{
    const char *p = *s;
    size_t n = 0;
    out[0] = 0;
    if (*p == '@') {
        n = (size_t)snprintf(out, size, "%s", g->prefix);
        ++p;
    } else if (!is_id((unsigned char)*p) || isdigit((unsigned char)*p)) {
        return 0;
    }
    while (is_id((unsigned char)*p) && n + 1 < size)
        out[n++] = *p++;
    out[n] = 0;
    *s = p;
    return 1;
}

static void skip_ws(const char **s)
{
    while (**s == ' ')
        ++*s;
}

/* a type with an optional [N]: the translated type in decl form */
static void put_type(const gen *g, const char *t, const char *arr, mf_buf *b)
{
    const char *mt = map_type(g, t);
    if (!mt)
        mt = t;
    if (arr[0] && g->lang == MF_SHADER_WGSL)
        mf_buf_printf(b, "array<%s, %s>", mt, arr);
    else
        mf_buf_puts(b, mt);
}

/* "T[N] name" or "tex name" at *s (a declaration's or parameter's head) */
static void decl_head(const gen *g, const char **s, const char *kw, mf_buf *b)
{
    char t[64], name[128], arr[16] = "";
    skip_ws(s);
    read_id(g, s, t, sizeof t);
    if (**s == '[') {
        size_t n = 0;
        ++*s;
        while (**s && **s != ']' && n + 1 < sizeof arr)
            arr[n++] = *(*s)++;
        arr[n] = 0;
        if (**s == ']')
            ++*s;
    }
    skip_ws(s);
    read_id(g, s, name, sizeof name);
    if (!strcmp(t, "tex")) {
        if (g->lang == MF_SHADER_GLSL)
            mf_buf_printf(b, "sampler2D %s", name);
        else if (g->lang == MF_SHADER_HLSL)
            mf_buf_printf(b, "Texture2D<float4> %s, SamplerState %s_s", name, name);
        else
            mf_buf_printf(b, "%s: texture_2d<f32>, %s_s: sampler", name, name);
        return;
    }
    if (g->lang == MF_SHADER_WGSL) {
        if (kw)
            mf_buf_printf(b, "%s ", kw);
        mf_buf_printf(b, "%s: ", name);
        put_type(g, t, arr, b);
    } else {
        if (kw && !strcmp(kw, "const"))
            mf_buf_puts(b, g->lang == MF_SHADER_HLSL ? "static const " : "const ");
        put_type(g, t, "", b);
        mf_buf_printf(b, " %s", name);
        if (arr[0])
            mf_buf_printf(b, "[%s]", arr);
    }
}

/* copies an argument list "(...)" at *s (balanced), translating its contents */
static void translate_span(const gen *g, const char *s, size_t n, mf_buf *b);

static const char *match_paren(const char *s)
{
    int depth = 0;
    for (; *s; ++s) {
        if (*s == '(')
            ++depth;
        else if (*s == ')' && --depth == 0)
            return s;
    }
    return NULL;
}

static void translate_span(const gen *g, const char *s, size_t n, mf_buf *b)
{
    const char *end = s + n;
    while (s < end) {
        if (s[0] == '/' && s[1] == '/') { /* comments verbatim to the end of the line */
            const char *e = strchr(s, '\n');
            size_t len = e && e < end ? (size_t)(e - s) : (size_t)(end - s);
            for (size_t i = 0; i < len; ++i) { /* @_name: the prefix, as in code */
                if (s[i] == '@')
                    mf_buf_puts(b, g->prefix);
                else
                    mf_buf_put(b, s + i, 1);
            }
            s += len;
            continue;
        }
        char id[128];
        const char *p = s;
        if (!read_id(g, &p, id, sizeof id)) {
            if (isdigit((unsigned char)*s)) { /* a number: copy it whole (1e-4 is not an identifier) */
                while (s < end && (is_id((unsigned char)*s) || *s == '.' ||
                                   ((*s == '-' || *s == '+') && (s[-1] == 'e' || s[-1] == 'E'))))
                    mf_buf_put(b, s++, 1);
                continue;
            }
            mf_buf_put(b, s++, 1);
            continue;
        }
        if (!strcmp(id, "var") || !strcmp(id, "let") || !strcmp(id, "const")) {
            decl_head(g, &p, id, b);
            s = p;
        } else if (!strcmp(id, "fn")) {
            char rt[64], name[128];
            skip_ws(&p);
            read_id(g, &p, rt, sizeof rt);
            skip_ws(&p);
            read_id(g, &p, name, sizeof name);
            if (g->lang == MF_SHADER_WGSL)
                mf_buf_printf(b, "fn %s(", name);
            else
                mf_buf_printf(b, "%s %s(", map_type(g, rt), name);
            /* parameters */
            if (*p == '(')
                ++p;
            int first = 1;
            while (*p && *p != ')') {
                if (!first)
                    mf_buf_puts(b, ", ");
                first = 0;
                decl_head(g, &p, NULL, b);
                skip_ws(&p);
                if (*p == ',')
                    ++p;
            }
            if (*p == ')')
                ++p;
            mf_buf_puts(b, ")");
            if (g->lang == MF_SHADER_WGSL && strcmp(rt, "void"))
                mf_buf_printf(b, " -> %s", map_type(g, rt));
            s = p;
        } else if (!strcmp(id, "SAMPLE") && *p == '(') {
            const char *close = match_paren(p);
            const char *a = p + 1;
            char t[128];
            skip_ws(&a);
            read_id(g, &a, t, sizeof t);
            while (*a == ',' || *a == ' ')
                ++a;
            if (g->lang == MF_SHADER_GLSL)
                mf_buf_printf(b, "textureLod(%s, ", t);
            else if (g->lang == MF_SHADER_HLSL)
                mf_buf_printf(b, "%s.SampleLevel(%s_s, ", t, t);
            else
                mf_buf_printf(b, "textureSampleLevel(%s, %s_s, ", t, t);
            translate_span(g, a, (size_t)(close - a), b);
            mf_buf_puts(b, ", 0.0)");
            s = close + 1;
        } else if (!strcmp(id, "TEXARG") && *p == '(') {
            const char *close = match_paren(p);
            const char *a = p + 1;
            char t[128];
            read_id(g, &a, t, sizeof t);
            if (g->lang == MF_SHADER_GLSL)
                mf_buf_puts(b, t);
            else
                mf_buf_printf(b, "%s, %s_s", t, t);
            s = close + 1;
        } else if (!strcmp(id, "atan2") && g->lang == MF_SHADER_GLSL) {
            mf_buf_puts(b, "atan");
            s = p;
        } else {
            const char *mt = map_type(g, id);
            mf_buf_puts(b, mt ? mt : id);
            s = p;
        }
    }
}

/* ---- the file ---------------------------------------------------------------------------- */

const char *mf_shader_lang_name(mf_shader_lang lang)
{
    switch (lang) {
    case MF_SHADER_GLSL: return "glsl";
    case MF_SHADER_HLSL: return "hlsl";
    case MF_SHADER_WGSL: return "wgsl";
    }
    return "?";
}

int mf_shader_lang_parse(const char *name, mf_shader_lang *out)
{
    for (int l = 0; l < 3; ++l)
        if (name && !strcmp(name, mf_shader_lang_name((mf_shader_lang)l))) {
            *out = (mf_shader_lang)l;
            return 0;
        }
    return -1;
}

/* the shortest decimal that reads back as the float of v */
static void put_float(mf_buf *b, double v)
{
    char s[64];
    float f = (float)v;
    for (int p = 6; p <= 9; ++p) {
        snprintf(s, sizeof s, "%.*g", p, (double)f);
        if ((float)strtod(s, NULL) == f)
            break;
    }
    mf_buf_puts(b, s);
    if (!strpbrk(s, ".eEn"))
        mf_buf_puts(b, ".0");
}

static void put_const(const gen *g, const char *name, double v)
{
    if (g->lang == MF_SHADER_WGSL)
        mf_buf_printf(g->b, "const %s_%s: f32 = ", g->prefix, name);
    else
        mf_buf_printf(g->b, "%sconst float %s_%s = ", g->lang == MF_SHADER_HLSL ? "static " : "", g->prefix, name);
    put_float(g->b, v);
    mf_buf_puts(g->b, ";\n");
}

static int valid_prefix(const char *p)
{
    if (!p || !p[0] || strlen(p) > 64 || isdigit((unsigned char)p[0]))
        return 0;
    for (; *p; ++p)
        if (!is_id((unsigned char)*p))
            return 0;
    return 1;
}

static void set_msg(char *msg, size_t size, const char *fmt, const char *arg)
{
    if (msg && size)
        snprintf(msg, size, fmt, arg);
}

/* text with SPHERE_TEX / SPHERE_ARG replaced (k_integrals_2 for one table kind), translated */
static void translate_sphere_variant(const gen *g, const char *text, int iso)
{
    mf_buf t = {0};
    for (const char *s = text; *s;) {
        if (!strncmp(s, "SPHERE_TEX ", 11)) {
            if (iso)
                mf_buf_puts(&t, "tex ltc_2, ");
            s += 11;
        } else if (!strncmp(s, "SPHERE_ARG ", 11)) {
            if (iso)
                mf_buf_puts(&t, "TEXARG(ltc_2), ");
            s += 11;
        } else
            mf_buf_put(&t, s++, 1);
    }
    mf_buf_put(&t, "", 1); /* the translator scans NUL-terminated text */
    if (t.failed)
        g->b->failed = 1;
    else
        translate_span(g, t.data, t.len - 1, g->b);
    mf_buf_free(&t);
}

static int is_iso_table(const mf_table *t)
{
    int ok = t->naxes == 2 && t->nfields == MF_LTC_NFIELDS && t->axes[0].mapping == MF_AXIS_SQUARE &&
             t->axes[1].mapping == MF_AXIS_ONE_MINUS_SQUARE && t->axes[0].size >= 2 && t->axes[1].size >= 2;
    for (int f = 0; ok && f < MF_LTC_NFIELDS; ++f)
        ok = !strcmp(t->fields[f], mf_ltc_table_fields[f]);
    return ok;
}

mf_status mf_ltc_shader_build(mf_buf *out, const mf_table *t, mf_shader_lang lang, const char *prefix, char *msg,
                              size_t msg_size)
{
    if (msg && msg_size)
        msg[0] = 0;
    if (!out || !t || (lang != MF_SHADER_GLSL && lang != MF_SHADER_HLSL && lang != MF_SHADER_WGSL)) {
        set_msg(msg, msg_size, "%s", "shader: no table or unknown language");
        return MF_ERR_DOMAIN;
    }
    if (!valid_prefix(prefix)) {
        set_msg(msg, msg_size, "shader: prefix '%s' is not an identifier", prefix ? prefix : "");
        return MF_ERR_DOMAIN;
    }
    const int iso = is_iso_table(t);
    mf_table_atlas atlas;
    memset(&atlas, 0, sizeof atlas);
    if (!iso) {
        int aniso = mf_ltc_aniso_layout_ok(t, NULL, 0) && t->nfields >= MF_LTCA_NFIELDS &&
                    (mf_table_atlas_from_meta(t, &atlas) == MF_OK || mf_table_atlas_layout(t, 0, &atlas) == MF_OK);
        if (!aniso) {
            set_msg(msg, msg_size, "%s",
                    "shader: the area-light code needs an isotropic LTC table (axes r, u; fields minv_00 .. sphere) "
                    "or an anisotropic one (axes ax/a, ay/lambda, theta, phi; fields m00 .. fresnel)");
            return MF_ERR_UNSUPPORTED;
        }
    }
    gen g = {out, lang, prefix};
    static const char *const lang_title[] = {"GLSL (3.30 / ES 3.0 and later)", "HLSL (Shader Model 4 and later)",
                                             "WGSL"};
    if (iso)
        mf_buf_printf(out,
                      "// %s_area.%s -- LTC area lights, %s (generated by mfkit from one source for GLSL, HLSL and\n"
                      "// WGSL; do not edit).  Textures: ltc_1 = (minv_00, minv_20, minv_02, minv_22), ltc_2 =\n"
                      "// (magnitude, fresnel, 0, sphere), float, bilinear, clamp-to-edge, no mipmaps (docs/tables.md).\n"
                      "//\n"
                      "// Use (positions relative to the shading point, world space; n, v unit):\n"
                      "//   t1 = %s_lookup(ltc_1, alpha, dot(n, v)); t2 = %s_lookup(ltc_2, alpha, dot(n, v));\n"
                      "//   minv = %s_minv(t1, n, v);\n"
                      "//   spec = radiance * %s_quad(minv, p0, p1, p2, p3, false) * %s_fresnel(t2, f0);\n"
                      "//   diffuse: the same with minv = identity (%s_rows of the unit vectors), no Fresnel.\n"
                      "// Lines: %s_line(...) * 2 R for a cylinder of radius R.  Disks and %s_quad_clipless use\n"
                      "// the sphere channel of ltc_2 (exact while the light is above the horizon).\n\n",
                      prefix, mf_shader_lang_name(lang), lang_title[lang], prefix, prefix, prefix, prefix, prefix,
                      prefix, prefix, prefix);
    else
        mf_buf_printf(out,
                      "// %s_area.%s -- anisotropic LTC area lights, %s (generated by mfkit from one source for\n"
                      "// GLSL, HLSL and WGSL; do not edit).  Textures: the three %d x %d atlases %s_m0.dds = (m00, m01,\n"
                      "// m02, m10), %s_m1.dds = (m11, m12, m20, m21), %s_m2.dds = (m22, magnitude, fresnel, residual),\n"
                      "// float, bilinear, clamp-to-edge, no mipmaps (docs/tables.md).\n"
                      "//\n"
                      "// Use (positions relative to the shading point, world space; tg, bt, n the unit tangent frame\n"
                      "// with tg along alpha_x; v the unit view direction):\n"
                      "//   fv = %s_fold(%s_view(tg, bt, n, v));\n"
                      "//   t0 = %s_lookup(tex0, alpha_x, alpha_y, fv); t1, t2 likewise from tex1, tex2;\n"
                      "//   minv = %s_minv(t0, t1, t2, fv, tg, bt, n);\n"
                      "//   spec = radiance * %s_quad(minv, p0, p1, p2, p3, false) * %s_fresnel(t2, f0);\n"
                      "// Lines: %s_line(...) * 2 R for a cylinder of radius R.  Disks and %s_quad_clipless use the\n"
                      "// closed-form sphere integral %s_sphere (exact while the light is above the horizon).\n\n",
                      prefix, mf_shader_lang_name(lang), lang_title[lang], atlas.width, atlas.height, prefix, prefix,
                      prefix, prefix, prefix, prefix, prefix, prefix, prefix, prefix, prefix, prefix);
    if (lang != MF_SHADER_WGSL) {
        char up[80];
        size_t n = strlen(prefix);
        for (size_t i = 0; i <= n; ++i)
            up[i] = (char)toupper((unsigned char)prefix[i]);
        mf_buf_printf(out, "#ifndef %s_AREA\n#define %s_AREA\n\n", up, up);
    }
    if (iso) {
        const mf_table_axis *ar = &t->axes[0], *au = &t->axes[1];
        mf_buf_printf(out, "// the table's axes: r (%d texels over [%.9g, %.9g]), u (%d texels over [%.9g, %.9g])\n",
                      ar->size, ar->lo, ar->hi, au->size, au->lo, au->hi);
        put_const(&g, "PI", MF_PI);
        put_const(&g, "R_LO", ar->lo);
        put_const(&g, "R_HI", ar->hi);
        put_const(&g, "R_N", ar->size);
        put_const(&g, "U_LO", au->lo);
        put_const(&g, "U_HI", au->hi);
        put_const(&g, "U_N", au->size);
        put_const(&g, "ALPHA_MIN", isfinite(ar->physical_min) ? ar->physical_min : 0.0);
        put_const(&g, "COS_MIN", isfinite(au->physical_min) ? au->physical_min : -1.0);
    } else {
        mf_buf_puts(out, "// the table's axes (texels over [lo, hi]) and its atlas (tile = i_theta + n_theta i_phi at\n"
                         "// column tile % TILES_X, row tile / TILES_X)\n");
        for (int k = 0; k < 4; ++k)
            mf_buf_printf(out, "//   axis %d: %s, %d texels over [%.9g, %.9g]\n", k, t->axes[k].name, t->axes[k].size,
                          t->axes[k].lo, t->axes[k].hi);
        put_const(&g, "PI", MF_PI);
        for (int k = 0; k < 4; ++k) {
            char nm[16];
            snprintf(nm, sizeof nm, "A%d_LO", k);
            put_const(&g, nm, t->axes[k].lo);
            snprintf(nm, sizeof nm, "A%d_HI", k);
            put_const(&g, nm, t->axes[k].hi);
            snprintf(nm, sizeof nm, "A%d_N", k);
            put_const(&g, nm, t->axes[k].size);
        }
        put_const(&g, "LAMBDA", mf_ltc_aniso_table_param(t) == MF_LTC_ANISO_PARAM_ALPHA_LAMBDA ? 1.0 : 0.0);
        put_const(&g, "TILES_X", atlas.tiles_x);
        put_const(&g, "TILE_W", atlas.tile_w);
        put_const(&g, "TILE_H", atlas.tile_h);
        put_const(&g, "ATLAS_W", atlas.width);
        put_const(&g, "ATLAS_H", atlas.height);
    }
    mf_buf_puts(out, "\n// ---- the per-language prelude: matrices from rows, matrix times vector\n");
    switch (lang) {
    case MF_SHADER_GLSL:
        mf_buf_printf(out, "mat3 %s_rows(vec3 r0, vec3 r1, vec3 r2) { return transpose(mat3(r0, r1, r2)); }\n", prefix);
        mf_buf_printf(out, "vec3 %s_mul(mat3 m, vec3 v) { return m * v; }\n\n", prefix);
        break;
    case MF_SHADER_HLSL:
        mf_buf_printf(out, "float3x3 %s_rows(float3 r0, float3 r1, float3 r2) { return float3x3(r0, r1, r2); }\n",
                      prefix);
        mf_buf_printf(out, "float3 %s_mul(float3x3 m, float3 v) { return mul(m, v); }\n\n", prefix);
        break;
    case MF_SHADER_WGSL:
        mf_buf_printf(out,
                      "fn %s_rows(r0: vec3<f32>, r1: vec3<f32>, r2: vec3<f32>) -> mat3x3<f32> { return "
                      "transpose(mat3x3<f32>(r0, r1, r2)); }\n",
                      prefix);
        mf_buf_printf(out, "fn %s_mul(m: mat3x3<f32>, v: vec3<f32>) -> vec3<f32> { return m * v; }\n\n", prefix);
        break;
    }
    const char *lookup = iso ? k_iso_lookup : k_aniso_lookup, *sphere = iso ? k_iso_sphere : k_aniso_sphere;
    translate_span(&g, lookup, strlen(lookup), out);
    translate_span(&g, k_integrals_1, strlen(k_integrals_1), out);
    translate_span(&g, sphere, strlen(sphere), out);
    translate_sphere_variant(&g, k_integrals_2, iso);
    if (lang != MF_SHADER_WGSL)
        mf_buf_puts(out, "\n#endif\n");
    if (out->failed) {
        set_msg(msg, msg_size, "%s", "shader: out of memory");
        return MF_ERR_ALLOC;
    }
    return MF_OK;
}

mf_status mf_ltc_shader_write(const char *path, const mf_table *t, mf_shader_lang lang, const char *prefix,
                              char *msg, size_t msg_size)
{
    mf_buf b = {0};
    mf_status st = mf_ltc_shader_build(&b, t, lang, prefix, msg, msg_size);
    if (st == MF_OK)
        st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
    else if (msg && msg_size && path) {
        char tmp[512];
        snprintf(tmp, sizeof tmp, "%s", msg);
        snprintf(msg, msg_size, "%s: %s", path, tmp);
    }
    mf_buf_free(&b);
    return st;
}
