/*
 * test_gpu_ltc_aniso.c -- the anisotropic table's area-light code (mf_ltc_shader.h on an
 * ltc_anisotropic table) against mfkit's C library, on Mesa's software rasteriser.
 *
 * 1. Generates the GLSL, HLSL and WGSL of a small anisotropic table in each parameterisation
 *    (alpha-xy, alpha-lambda) and compiles GLSL and HLSL with glslangValidator inside a main that
 *    calls every function.  (The WGSL is validated by naga in tests/test_engines.sh.)
 * 2. Runs the GLSL on OSMesa (llvmpipe): the three atlases of a 5 x 4 x 6 x 7 table of known smooth
 *    matrices (every value rounded to float; the matrices hold the exact zero patterns of the
 *    fitted tables at theta = 0, phi = 0 and phi = pi/2, so the azimuth fold is continuous) as
 *    GL_RGBA32F textures (GL_LINEAR, clamp-to-edge), and a grid of cases -- 4 roughness pairs x
 *    4 view elevations x 12 azimuths (3 per quadrant: 2 inside, 1 within 2e-3 rad of a mirror
 *    line) x 6 lights, in a random tangent frame -- one per pixel of a GL_RGBA32F framebuffer, each
 *    pixel holding quad (clipped), quad (clipless), line and disk times the Fresnel split.  The C
 *    library evaluates the same float inputs on the same float table in double:
 *    mf_ltc_aniso_lookup, mf_ltc_init, mf_ltc_integrate_polygon, mf_ltc_integrate_polygon_sphere,
 *    mf_ltc_integrate_line, mf_ltc_integrate_disk.
 * 3. The test can fail: the same run with one mirror sign flipped in the generated GLSL (the S_y of
 *    the fourth quadrant) must exceed the tolerance in most cases of that quadrant.
 * 4. With --wgsl NODE_DIR (tests/test_engines.sh, which installs naga): the WGSL with a WGSL main doing
 *    the same, translated to GLSL 3.30 by naga, on the same cases, reference and tolerance.
 * Fails (never skips) when no OSMesa context can be made.
 */
#define _POSIX_C_SOURCE 200809L
#define GL_GLEXT_PROTOTYPES 1
#include "mf_test.h"

#include "gpu_osmesa.h"

#include "mfkit/io/mf_ltc_shader.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/mf_ltc_lights.h"
#include "mfkit/mf_rng.h"

#include <string.h>
#include <unistd.h>

static const int k_sizes[4] = {5, 4, 6, 7};

/* ---- the table: smooth known matrices with the fitted tables' zero patterns, rounded to float ---- */
static double worst_cond = 0.0; /* the largest |M|_F |M^-1|_F of the table */

static void build_table(mf_table *t, int param)
{
    CHECK(mf_ltc_aniso_table_create(t, k_sizes, param) == MF_OK);
    mf_table_atlas a;
    CHECK(mf_table_atlas_layout(t, 0, &a) == MF_OK);
    CHECK(mf_table_atlas_record(t, &a) == MF_OK);
    int idx[4];
    for (idx[3] = 0; idx[3] < k_sizes[3]; ++idx[3])
        for (idx[2] = 0; idx[2] < k_sizes[2]; ++idx[2])
            for (idx[1] = 0; idx[1] < k_sizes[1]; ++idx[1])
                for (idx[0] = 0; idx[0] < k_sizes[0]; ++idx[0]) {
                    double ax, ay, th, ph;
                    mf_ltc_aniso_entry_values(t, idx, &ax, &ay, &th, &ph);
                    double st = sin(th), s1 = idx[3] == 0 ? 0.0 : sin(ph),
                           c1 = idx[3] == k_sizes[3] - 1 ? 0.0 : cos(ph), s2 = 2.0 * s1 * c1;
                    /* theta = 0: diagonal; phi = 0: m01 = m10 = m12 = m21 = 0; phi = pi/2: m01 = m10 = m02 = m20 = 0 */
                    double m[9] = {0.25 + 0.7 * ax + 0.1 * st * st, 0.15 * st * s2 * (1.0 + ax), 0.3 * st * c1,
                                   -0.1 * st * s2,                  0.2 + 0.75 * ay - 0.05 * st, 0.25 * st * s1 * (1.0 - 0.5 * ay),
                                   -0.2 * st * c1 * (1.0 + ay),     -0.15 * st * s1,              0.9 + 0.1 * cos(th)};
                    double *rec = mf_table_record(t, idx);
                    for (int k = 0; k < 9; ++k)
                        rec[MF_LTCA_F_M00 + k] = (double)(float)m[k];
                    mf_ltc ltc;
                    CHECK(mf_ltc_init(&ltc, mf_ltc_matrix_general(rec + MF_LTCA_F_M00)) == MF_OK);
                    double nm = 0.0, ni = 0.0;
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j) {
                            rec[MF_LTCA_F_MINV00 + 3 * i + j] = ltc.inv.m[i][j];
                            nm += ltc.m.m[i][j] * ltc.m.m[i][j];
                            ni += ltc.inv.m[i][j] * ltc.inv.m[i][j];
                        }
                    worst_cond = fmax(worst_cond, sqrt(nm * ni));
                    rec[MF_LTCA_F_MAGNITUDE] = (double)(float)(0.92 - 0.3 * st * st * ax * (1.0 - 0.3 * ay));
                    rec[MF_LTCA_F_FRESNEL] = (double)(float)(0.04 + 0.2 * st * st * st + 0.02 * ay);
                    rec[MF_LTCA_F_RESIDUAL] = 0.0;
                }
}

/* the three RGBA atlases of the shader (mf_ltc_aniso_shader_fields: tex0 = m00 m01 m02 m10,
 * tex1 = m11 m12 m20 m21, tex2 = m22 magnitude fresnel residual) as floats */
static const int k_tex_fields[3][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {8, MF_LTCA_F_MAGNITUDE, MF_LTCA_F_FRESNEL, MF_LTCA_F_RESIDUAL}};

/* ---- compiling with glslangValidator -------------------------------------------------------- */
static const char *k_glsl_uniforms = "uniform sampler2D tex0;\nuniform sampler2D tex1;\nuniform sampler2D tex2;\n"
                                     "uniform sampler2D cases;\nuniform int grid_w;\nout vec4 frag;\n";

/* main of the GPU run: case row = pixel index, texels 0..12 of the row (see the upload) */
static const char *k_glsl_main =
    "void main()\n{\n"
    "    ivec2 px = ivec2(gl_FragCoord.xy);\n"
    "    int id = px.x + grid_w * px.y;\n"
    "    vec4 a = texelFetch(cases, ivec2(0, id), 0);\n"
    "    vec4 b = texelFetch(cases, ivec2(1, id), 0);\n"
    "    vec4 c = texelFetch(cases, ivec2(2, id), 0);\n"
    "    vec4 d = texelFetch(cases, ivec2(3, id), 0);\n"
    "    vec3 n = a.xyz;\n    vec3 tg = b.xyz;\n    vec3 bt = c.xyz;\n    vec3 v = d.xyz;\n"
    "    float alpha_x = a.w;\n    float alpha_y = b.w;\n    vec3 f0 = vec3(c.w);\n    bool two = d.w > 0.5;\n"
    "    vec3 q0 = texelFetch(cases, ivec2(4, id), 0).xyz;\n"
    "    vec3 q1 = texelFetch(cases, ivec2(5, id), 0).xyz;\n"
    "    vec3 q2 = texelFetch(cases, ivec2(6, id), 0).xyz;\n"
    "    vec3 q3 = texelFetch(cases, ivec2(7, id), 0).xyz;\n"
    "    vec3 l1 = texelFetch(cases, ivec2(8, id), 0).xyz;\n"
    "    vec3 l2 = texelFetch(cases, ivec2(9, id), 0).xyz;\n"
    "    vec3 dc = texelFetch(cases, ivec2(10, id), 0).xyz;\n"
    "    vec3 d1 = texelFetch(cases, ivec2(11, id), 0).xyz;\n"
    "    vec3 d2 = texelFetch(cases, ivec2(12, id), 0).xyz;\n"
    "    vec4 fv = ltca_fold(ltca_view(tg, bt, n, v));\n"
    "    vec4 t0 = ltca_lookup(tex0, alpha_x, alpha_y, fv);\n"
    "    vec4 t1 = ltca_lookup(tex1, alpha_x, alpha_y, fv);\n"
    "    vec4 t2 = ltca_lookup(tex2, alpha_x, alpha_y, fv);\n"
    "    mat3 minv = ltca_minv(t0, t1, t2, fv, tg, bt, n);\n"
    "    float fr = ltca_fresnel(t2, f0).x;\n"
    "    frag = fr * vec4(ltca_quad(minv, q0, q1, q2, q3, two), ltca_quad_clipless(minv, q0, q1, q2, q3, two),\n"
    "                     ltca_line(minv, l1, l2), ltca_disk(minv, dc, d1, d2, two));\n"
    "}\n";

/* the WGSL main of the same run (--wgsl), translated to GLSL by naga (gpu_wgsl_to_glsl) */
static const char *k_wgsl_main =
    "@group(0) @binding(0) var tex0: texture_2d<f32>;\n@group(0) @binding(1) var tex0_s: sampler;\n"
    "@group(0) @binding(2) var tex1: texture_2d<f32>;\n@group(0) @binding(3) var tex1_s: sampler;\n"
    "@group(0) @binding(4) var tex2: texture_2d<f32>;\n@group(0) @binding(5) var tex2_s: sampler;\n"
    "@group(0) @binding(6) var cases: texture_2d<f32>;\n"
    "fn case_texel(i: i32, id: i32) -> vec4<f32> { return textureLoad(cases, vec2<i32>(i, id), 0); }\n"
    "@fragment fn main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {\n"
    "    let id = i32(pos.x) + 48 * i32(pos.y);\n"
    "    let a = case_texel(0, id);\n    let b = case_texel(1, id);\n    let c = case_texel(2, id);\n"
    "    let d = case_texel(3, id);\n"
    "    let n = a.xyz;\n    let tg = b.xyz;\n    let bt = c.xyz;\n    let v = d.xyz;\n"
    "    let f0 = vec3<f32>(c.w, c.w, c.w);\n    let two = d.w > 0.5;\n"
    "    let q0 = case_texel(4, id).xyz;\n    let q1 = case_texel(5, id).xyz;\n"
    "    let q2 = case_texel(6, id).xyz;\n    let q3 = case_texel(7, id).xyz;\n"
    "    let l1 = case_texel(8, id).xyz;\n    let l2 = case_texel(9, id).xyz;\n"
    "    let dc = case_texel(10, id).xyz;\n    let d1 = case_texel(11, id).xyz;\n    let d2 = case_texel(12, id).xyz;\n"
    "    let fv = ltca_fold(ltca_view(tg, bt, n, v));\n"
    "    let t0 = ltca_lookup(tex0, tex0_s, a.w, b.w, fv);\n"
    "    let t1 = ltca_lookup(tex1, tex1_s, a.w, b.w, fv);\n"
    "    let t2 = ltca_lookup(tex2, tex2_s, a.w, b.w, fv);\n"
    "    let minv = ltca_minv(t0, t1, t2, fv, tg, bt, n);\n"
    "    let fr = ltca_fresnel(t2, f0).x;\n"
    "    return fr * vec4<f32>(ltca_quad(minv, q0, q1, q2, q3, two), ltca_quad_clipless(minv, q0, q1, q2, q3, two),\n"
    "                          ltca_line(minv, l1, l2), ltca_disk(minv, dc, d1, d2, two));\n"
    "}\n";

static const char *k_hlsl_main =
    "Texture2D<float4> tex0;\nSamplerState tex0_s;\nTexture2D<float4> tex1;\nSamplerState tex1_s;\n"
    "Texture2D<float4> tex2;\nSamplerState tex2_s;\n"
    "cbuffer C { float3 n; float3 tg; float3 bt; float3 v; float alpha_x; float alpha_y; float3 f0; float3 q0;\n"
    "            float3 q1; float3 q2; float3 q3; int two; };\n"
    "float4 main() : SV_Target\n{\n"
    "    float4 fv = ltca_fold(ltca_view(tg, bt, n, v));\n"
    "    float4 t0 = ltca_lookup(tex0, tex0_s, alpha_x, alpha_y, fv);\n"
    "    float4 t1 = ltca_lookup(tex1, tex1_s, alpha_x, alpha_y, fv);\n"
    "    float4 t2 = ltca_lookup(tex2, tex2_s, alpha_x, alpha_y, fv);\n"
    "    float3x3 minv = ltca_minv(t0, t1, t2, fv, tg, bt, n);\n"
    "    float fr = ltca_fresnel(t2, f0).x;\n"
    "    return fr * float4(ltca_quad(minv, q0, q1, q2, q3, two != 0), ltca_quad_clipless(minv, q0, q1, q2, q3, two != 0),\n"
    "                       ltca_line(minv, q0, q1), ltca_disk(minv, q0, q1, q2, two != 0));\n"
    "}\n";

/* The GLSL fragment shader of table t (NULL on failure); its GLSL and HLSL compiled by glslangValidator. */
static char *compile_checks(const char *dir, const mf_table *t)
{
    char path[3][512], msg[512], cmd[2048];
    for (int l = 0; l < 3; ++l) {
        snprintf(path[l], sizeof path[l], "%s/ltca_area.%s", dir, mf_shader_lang_name((mf_shader_lang)l));
        mf_status st = mf_ltc_shader_write(path[l], t, (mf_shader_lang)l, "ltca", msg, sizeof msg);
        if (st != MF_OK) {
            MF_FAIL_AT("%s", msg);
            return NULL;
        }
    }
    char *glsl = gpu_read_all(path[0]), *hlsl = gpu_read_all(path[1]), *wgsl = gpu_read_all(path[2]);
    CHECK(glsl && hlsl && wgsl);
    if (!glsl || !hlsl || !wgsl) {
        free(glsl);
        free(hlsl);
        free(wgsl);
        return NULL;
    }
    /* one source: the same functions in the three languages */
    static const char *const fns[] = {"ltca_view(", "ltca_fold(", "ltca_lookup(", "ltca_minv(", "ltca_fresnel(",
                                      "ltca_polygon(", "ltca_polygon_clipless(", "ltca_quad(", "ltca_quad_clipless(",
                                      "ltca_line(", "ltca_disk(", "ltca_sphere(", "ltca_atan_minus_x("};
    for (size_t i = 0; i < sizeof fns / sizeof fns[0]; ++i)
        if (!strstr(glsl, fns[i]) || !strstr(hlsl, fns[i]) || !strstr(wgsl, fns[i]))
            MF_FAIL_AT("%s missing from one of the languages", fns[i]);
    char frag[512], hl[512];
    snprintf(frag, sizeof frag, "%s/main.frag", dir);
    snprintf(hl, sizeof hl, "%s/main.hlsl", dir);
    CHECK(gpu_write_file(frag, "#version 330 core\n", k_glsl_uniforms, glsl) && gpu_write_file(hl, hlsl, k_hlsl_main, NULL));
    {
        FILE *f = fopen(frag, "a");
        CHECK(f && fputs(k_glsl_main, f) >= 0 && fclose(f) == 0);
    }
    if (system("command -v glslangValidator >/dev/null 2>&1") != 0)
        MF_FAIL_AT("glslangValidator is needed (Debian: glslang-tools)");
    snprintf(cmd, sizeof cmd, "glslangValidator %s", frag);
    CHECK(gpu_run(cmd));
    snprintf(cmd, sizeof cmd, "glslangValidator -V -D -e main -S frag -o %s/main.spv %s", dir, hl);
    CHECK(gpu_run(cmd));
    free(hlsl);
    free(wgsl);
    size_t n = strlen(glsl) + strlen(k_glsl_uniforms) + strlen(k_glsl_main) + 64;
    char *full = malloc(n);
    snprintf(full, n, "#version 330 core\n%s%s%s", k_glsl_uniforms, glsl, k_glsl_main);
    free(glsl);
    return full;
}

/* ---- the cases ---------------------------------------------------------------------------- */
#define CASE_W 13
typedef struct gcase {
    float n[3], ax, tg[3], ay, bt[3], f0, v[3], two, q[4][3], l[2][3], dc[3], d1[3], d2[3];
    int quadrant; /* of the view's azimuth, 0..3 */
} gcase;

static void put3(float *dst, mf_vec3 v)
{
    dst[0] = (float)v.x;
    dst[1] = (float)v.y;
    dst[2] = (float)v.z;
}
static mf_vec3 get3(const float *s) { return mf_vec3_make(s[0], s[1], s[2]); }

/* a light of kind k around the direction at polar angle th_k from n, in a random tangent frame;
 * the view at (theta, phi) in that frame */
static void make_case(gcase *c, mf_pcg32 *rng, double ax, double ay, double theta, double phi, int kind)
{
    mf_vec3 n = mf_vec3_make(0, 0, 1);
    if (mf_pcg32_next_u32(rng) & 1)
        n = mf_vec3_spherical(0.8 * mf_pcg32_next_double(rng), 2 * MF_PI * mf_pcg32_next_double(rng));
    mf_frame f0 = mf_frame_from_normal(n);
    double rot = 2 * MF_PI * mf_pcg32_next_double(rng); /* the tangent: a random direction across n */
    mf_vec3 tg = mf_vec3_add(mf_vec3_scale(f0.s, cos(rot)), mf_vec3_scale(f0.t, sin(rot)));
    mf_frame f = {tg, mf_vec3_cross(n, tg), n};
    mf_vec3 v = mf_frame_to_world(f, mf_vec3_spherical(theta, phi));
    static const double th_k[] = {0.3, 1.2, 1.5, 0.6, 0.9, 1.75};
    static const double dist_k[] = {2.0, 2.0, 1.5, 20.0, 0.7, 2.0};
    static const double size_k[] = {0.8, 1.0, 0.6, 0.5, 1.0, 0.9};
    double th = th_k[kind] + 0.2 * (mf_pcg32_next_double(rng) - 0.5), ph = 2 * MF_PI * mf_pcg32_next_double(rng);
    mf_vec3 dir = mf_vec3_spherical(th, ph);
    mf_vec3 ctr = mf_vec3_scale(dir, dist_k[kind]);
    mf_frame lf = mf_frame_from_normal(dir);
    double tilt = 0.4 * (mf_pcg32_next_double(rng) - 0.5);
    mf_vec3 e1 = mf_vec3_scale(mf_vec3_add(lf.s, mf_vec3_scale(dir, tilt)), 0.5 * size_k[kind]);
    mf_vec3 e2 = mf_vec3_scale(lf.t, 0.35 * size_k[kind]);
    mf_vec3 q[4] = {mf_vec3_add(ctr, mf_vec3_add(e1, e2)), mf_vec3_add(ctr, mf_vec3_sub(e1, e2)),
                    mf_vec3_sub(ctr, mf_vec3_add(e1, e2)), mf_vec3_sub(ctr, mf_vec3_sub(e1, e2))};
    mf_vec3 nq = mf_vec3_cross(mf_vec3_sub(q[1], q[0]), mf_vec3_sub(q[2], q[0]));
    int front = mf_vec3_dot(nq, q[0]) > 0.0;
    if (front == (kind == 5)) { /* clockwise (front-facing) unless kind 5: back-facing, two-sided */
        mf_vec3 tmp = q[1];
        q[1] = q[3];
        q[3] = tmp;
    }
    for (int i = 0; i < 4; ++i)
        put3(c->q[i], mf_frame_to_world(f, q[i]));
    put3(c->l[0], mf_frame_to_world(f, mf_vec3_add(ctr, e1)));
    put3(c->l[1], mf_frame_to_world(f, mf_vec3_sub(ctr, mf_vec3_scale(e1, 1.3))));
    mf_vec3 d1 = e1, d2 = e2;
    if ((mf_vec3_dot(mf_vec3_cross(d1, d2), ctr) > 0.0) != (kind != 5))
        d2 = mf_vec3_scale(d2, -1.0);
    put3(c->dc, mf_frame_to_world(f, ctr));
    put3(c->d1, mf_frame_to_world(f, d1));
    put3(c->d2, mf_frame_to_world(f, d2));
    put3(c->n, n);
    put3(c->tg, tg);
    put3(c->bt, f.t);
    put3(c->v, v);
    c->ax = (float)ax;
    c->ay = (float)ay;
    c->f0 = (float)(0.02 + 0.96 * mf_pcg32_next_double(rng));
    c->two = kind >= 4 ? 1.0f : 0.0f;
}

/* The C library on the case's float inputs: quad, clipless quad, line, disk, times the Fresnel split. */
static void reference(const mf_table *t, const gcase *c, double out[4])
{
    mf_frame f = {get3(c->tg), get3(c->bt), get3(c->n)};
    mf_vec3 wo = mf_frame_to_local(f, get3(c->v));
    double theta = acos(fmax(-1.0, fmin(1.0, wo.z))), phi = atan2(wo.y, wo.x);
    double m[9], mag, fres;
    CHECK(mf_ltc_aniso_lookup(t, c->ax, c->ay, theta, phi, m, &mag, &fres) == MF_OK);
    mf_ltc ltc;
    CHECK(mf_ltc_init(&ltc, mf_ltc_matrix_general(m)) == MF_OK);
    mf_vec3 q[4];
    for (int i = 0; i < 4; ++i)
        q[i] = mf_frame_to_local(f, get3(c->q[i]));
    mf_polygon_sided sided = c->two > 0.5f ? MF_POLYGON_TWO_SIDED : MF_POLYGON_ONE_SIDED;
    mf_polygon poly = mf_polygon_make(4, q);
    double fr = c->f0 * mag + (1.0 - c->f0) * fres;
    out[0] = mf_ltc_integrate_polygon(&ltc, &poly, sided);
    out[1] = mf_ltc_integrate_polygon_sphere(&ltc, &poly, sided);
    out[2] = mf_ltc_integrate_line(&ltc, mf_frame_to_local(f, get3(c->l[0])), mf_frame_to_local(f, get3(c->l[1])));
    out[3] = mf_ltc_integrate_disk(&ltc, mf_frame_to_local(f, get3(c->dc)), mf_frame_to_local(f, get3(c->d1)),
                                   mf_frame_to_local(f, get3(c->d2)), sided);
    for (int k = 0; k < 4; ++k)
        out[k] *= fr;
}

/* ---- one GPU run ------------------------------------------------------------------------------ */
enum { NPAIR = 4, NTH = 4, NPH = 12, NK = 6, NCASE = NPAIR * NTH * NPH * NK, GRID_W = 48 };

/* names: the sampler uniforms of tex0, tex1, tex2, cases (NULL: the GLSL's, with grid_w) */
static int render(const mf_table *t, const char *frag_src, const gcase *cases, float *pix, const char *const *names)
{
    mf_table_atlas a;
    CHECK(mf_table_atlas_from_meta(t, &a) == MF_OK);
    double *img = malloc((size_t)a.width * a.height * t->nfields * sizeof *img);
    float *rgba = malloc((size_t)a.width * a.height * 4 * sizeof *rgba);
    static float ct[NCASE * CASE_W * 4];
    GLuint tex[4];
    mf_table_atlas_fill(t, &a, img);
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < a.width * a.height; ++i)
            for (int ch = 0; ch < 4; ++ch)
                rgba[4 * i + ch] = (float)img[(size_t)i * t->nfields + k_tex_fields[k][ch]];
        tex[k] = gpu_float_texture(k, a.width, a.height, rgba, GL_LINEAR);
    }
    memset(ct, 0, sizeof ct);
    for (int i = 0; i < NCASE; ++i) {
        float *row = ct + (size_t)i * CASE_W * 4;
        const gcase *c = &cases[i];
        memcpy(row + 0, c->n, 3 * sizeof(float));
        row[3] = c->ax;
        memcpy(row + 4, c->tg, 3 * sizeof(float));
        row[7] = c->ay;
        memcpy(row + 8, c->bt, 3 * sizeof(float));
        row[11] = c->f0;
        memcpy(row + 12, c->v, 3 * sizeof(float));
        row[15] = c->two;
        for (int q = 0; q < 4; ++q)
            memcpy(row + 16 + 4 * q, c->q[q], 3 * sizeof(float));
        memcpy(row + 32, c->l[0], 3 * sizeof(float));
        memcpy(row + 36, c->l[1], 3 * sizeof(float));
        memcpy(row + 40, c->dc, 3 * sizeof(float));
        memcpy(row + 44, c->d1, 3 * sizeof(float));
        memcpy(row + 48, c->d2, 3 * sizeof(float));
    }
    tex[3] = gpu_float_texture(3, CASE_W, NCASE, ct, GL_NEAREST);
    GLuint prog = gpu_program(frag_src);
    int ok = prog != 0;
    if (ok) {
        glUseProgram(prog);
        static const char *const glsl_names[4] = {"tex0", "tex1", "tex2", "cases"};
        for (int k = 0; k < 4; ++k) {
            GLint loc = glGetUniformLocation(prog, (names ? names : glsl_names)[k]);
            CHECK(loc >= 0);
            glUniform1i(loc, k);
        }
        if (!names)
            glUniform1i(glGetUniformLocation(prog, "grid_w"), GRID_W);
        for (int i = 0; i < NCASE * 4; ++i) /* no value of an earlier run can pass */
            pix[i] = NAN;
        ok = gpu_draw(4, GRID_W, NCASE / GRID_W, pix);
        glUseProgram(0);
        glDeleteProgram(prog);
    }
    glDeleteTextures(4, tex);
    free(img);
    free(rgba);
    return ok;
}

/* Compares the GPU values with the C library.  Tolerance |gpu - C| <= 2e-6 + 2e-4 |C|: the
 * isotropic test's (tests/test_gpu_ltc.c: float rounding of up to 10 edge terms of size up to pi,
 * and eps / angular size for the far light's cancellation, times the condition of M^-1 below 10),
 * which covers what the anisotropic lookup adds: theta and phi from acos and atan2 in float (a
 * few 1e-7 rad, times the table's slope per radian, below 2 here: ~1e-6 relative), the fold
 * against pi in float (a 1e-7 rad shift, continuous across the mirror lines by the zero
 * patterns) and the adjugate inverse (relative error ~ 3 eps cond(M), cond(M) = |M|_F |M^-1|_F
 * printed below).  Returns the number of values beyond it; *bad_q4 (if not NULL) gets the number
 * of cases with the view in the fourth azimuth quadrant that have a value beyond it.  Prints the
 * worst errors when verbose. */
static int compare(const mf_table *t, const gcase *cases, const float *pix, int verbose, double *worst_ratio,
                   int *bad_q4)
{
    static const char *const what[4] = {"quad", "quad clipless", "line", "disk"};
    double worst[4] = {0}, worst_rel[4] = {0};
    int nonzero[4] = {0}, bad = 0;
    *worst_ratio = 0.0;
    if (bad_q4)
        *bad_q4 = 0;
    for (int i = 0; i < NCASE; ++i) {
        double ref[4];
        int case_bad = 0;
        reference(t, &cases[i], ref);
        for (int k = 0; k < 4; ++k) {
            double gpu = pix[4 * i + k], e = fabs(gpu - ref[k]);
            double tol = 2e-4 * fabs(ref[k]) + 2e-6;
            worst[k] = fmax(worst[k], e);
            *worst_ratio = fmax(*worst_ratio, e / tol);
            if (fabs(ref[k]) > 1e-3) {
                ++nonzero[k];
                worst_rel[k] = fmax(worst_rel[k], e / fabs(ref[k]));
            }
            if (!(e <= tol)) {
                if (verbose && bad < 10)
                    MF_FAIL_AT("case %d (%s, azimuth quadrant %d): gpu %.9g vs C %.9g, |diff| %.3g > %.3g", i, what[k],
                               cases[i].quadrant, gpu, ref[k], e, tol);
                ++bad;
                case_bad = 1;
            }
        }
        if (bad_q4 && case_bad && cases[i].quadrant == 3)
            ++*bad_q4;
    }
    if (verbose) {
        for (int k = 0; k < 4; ++k) {
            printf("  %-14s worst |gpu - C| %.3g, worst relative %.3g over %d cases with C > 1e-3 (of %d)\n", what[k],
                   worst[k], worst_rel[k], nonzero[k], NCASE);
            CHECK(nonzero[k] >= NCASE / 4); /* the comparison is not of zeros */
        }
        printf("  worst |gpu - C| / tolerance %.3g\n", *worst_ratio);
    }
    return bad;
}

/* the generated GLSL with the S_y mirror of the fourth quadrant dropped (a sign flip): NULL if the
 * pattern is not found */
static char *mutant(const char *src)
{
    const char *pat = "ph = 2.0 * ltca_PI - ph;\n        sy = -1.0;";
    const char *p = strstr(src, pat);
    if (!p)
        return NULL;
    char *m = malloc(strlen(src) + 1);
    strcpy(m, src);
    char *q = m + (p - src) + strlen(pat) - strlen("-1.0;");
    memcpy(q, " 1.0;", 5);
    return m;
}

int main(int argc, char **argv)
{
    const char *node_dir = NULL;
    if (argc == 3 && !strcmp(argv[1], "--wgsl"))
        node_dir = argv[2];
    else if (argc != 1) {
        fprintf(stderr, "usage: test_gpu_ltc_aniso [--wgsl NODE_DIR]\n");
        return 2;
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(2022), 0);
    OSMesaContext ctx = NULL;
    static gcase cases[NCASE];
    static float pix[NCASE * 4];
    for (int param = MF_LTC_ANISO_PARAM_ALPHA_XY; param <= MF_LTC_ANISO_PARAM_ALPHA_LAMBDA; ++param) {
        mf_table t;
        worst_cond = 0.0;
        build_table(&t, param);
        printf("%s table %d x %d x %d x %d: largest cond(M) = |M|_F |M^-1|_F %.3g\n",
               param ? "alpha-lambda" : "alpha-xy", k_sizes[0], k_sizes[1], k_sizes[2], k_sizes[3], worst_cond);
        { /* refusals: an anisotropic table with its theta axis renamed, a bad prefix */
            mf_table other;
            mf_buf b = {0};
            char msg[512];
            CHECK(mf_table_copy(&other, &t) == MF_OK);
            snprintf(other.axes[2].name, sizeof other.axes[2].name, "elev");
            CHECK(mf_ltc_shader_build(&b, &other, MF_SHADER_WGSL, "p", msg, sizeof msg) == MF_ERR_UNSUPPORTED && msg[0]);
            CHECK(mf_ltc_shader_build(&b, &t, MF_SHADER_HLSL, "a-b", msg, sizeof msg) == MF_ERR_DOMAIN && msg[0]);
            mf_table_free(&other);
            mf_buf_free(&b);
        }
        char dir[] = "/tmp/mfkit_gpu_ltcaXXXXXX";
        if (!mkdtemp(dir)) {
            MF_FAIL_AT("cannot create a temporary directory");
            break;
        }
        char *frag_src = compile_checks(dir, &t);
        char cmd[600];
        snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
        if (system(cmd) != 0)
            fprintf(stderr, "could not remove %s\n", dir);
        if (!frag_src) {
            mf_table_free(&t);
            break;
        }
        if (!ctx && !(ctx = gpu_context())) {
            free(frag_src);
            mf_table_free(&t);
            break;
        }
        /* the grid: roughness pairs between the texels (alpha_y < alpha_x for lambda <= 1 in the
         * alpha-lambda table), elevations between the texels, 3 azimuths per quadrant (two inside, one
         * within 2e-3 rad of the quadrant's first mirror line), 6 lights */
        static const double pairs[2][NPAIR][2] = {{{0.11, 0.62}, {0.55, 0.14}, {0.33, 0.37}, {0.87, 0.46}},
                                                  {{0.62, 0.11}, {0.55, 0.14}, {0.37, 0.33}, {0.87, 0.46}}};
        int id = 0;
        for (int ip = 0; ip < NPAIR; ++ip)
            for (int it = 0; it < NTH; ++it)
                for (int iph = 0; iph < NPH; ++iph)
                    for (int k = 0; k < NK; ++k) {
                        double jit = 0.02 * (mf_pcg32_next_double(&rng) - 0.5);
                        double ax = pairs[param][ip][0] + jit, ay = pairs[param][ip][1] - jit;
                        double theta = (0.06 + 1.45 * (it + 0.3 + 0.4 * mf_pcg32_next_double(&rng)) / NTH);
                        int quadrant = iph / 3, sub = iph % 3;
                        double frac = sub == 2 ? 2e-3 * mf_pcg32_next_double(&rng)
                                               : (0.1 + 0.4 * sub + 0.35 * mf_pcg32_next_double(&rng)) * 0.5 * MF_PI;
                        double phi = quadrant * 0.5 * MF_PI + frac - (quadrant == 0 && sub == 2 ? 4e-3 : 0.0);
                        make_case(&cases[id], &rng, ax, ay, theta, phi, k);
                        cases[id].quadrant = (int)floor(fmod(phi + 2 * MF_PI, 2 * MF_PI) / (0.5 * MF_PI));
                        ++id;
                    }
        double ratio, mratio;
        if (render(&t, frag_src, cases, pix, NULL)) {
            printf("generated GLSL on llvmpipe vs the C library, %d cases:\n", NCASE);
            int bad = compare(&t, cases, pix, 1, &ratio, NULL);
            CHECK(bad == 0);
        }
        /* the test can fail: the fourth quadrant without its S_y mirror */
        char *mut = mutant(frag_src);
        CHECK(mut != NULL);
        if (mut && render(&t, mut, cases, pix, NULL)) {
            int bad_q4 = 0, q4 = 0;
            int bad = compare(&t, cases, pix, 0, &mratio, &bad_q4);
            for (int i = 0; i < NCASE; ++i)
                q4 += cases[i].quadrant == 3;
            printf("with the fourth quadrant's S_y mirror flipped: %d of %d values beyond the tolerance, in %d of the "
                   "%d cases of that quadrant; worst |gpu - C| / tolerance %.3g\n", bad, 4 * NCASE, bad_q4, q4, mratio);
            /* most cases of that quadrant must fail (near phi = 2 pi, where the mirrored entries vanish,
             * and at small theta the flip is below the tolerance) */
            if (!(2 * bad_q4 >= q4))
                MF_FAIL_AT("a mirror sign flip went unnoticed: only %d of %d cases fail", bad_q4, q4);
        }
        free(mut);
        if (node_dir) { /* the WGSL, translated to GLSL by naga, on the same cases */
            static const char *const wnames[4] = {"_group_0_binding_0_fs", "_group_0_binding_2_fs",
                                                   "_group_0_binding_4_fs", "_group_0_binding_6_fs"};
            mf_buf b = {0};
            char msg[512];
            CHECK(mf_ltc_shader_build(&b, &t, MF_SHADER_WGSL, "ltca", msg, sizeof msg) == MF_OK);
            mf_buf_puts(&b, k_wgsl_main);
            mf_buf_put(&b, "", 1);
            char *wfrag = b.failed ? NULL : gpu_wgsl_to_glsl(b.data, node_dir);
            mf_buf_free(&b);
            if (wfrag && render(&t, wfrag, cases, pix, wnames)) {
                printf("generated WGSL (translated to GLSL by naga) on llvmpipe vs the C library, %d cases:\n", NCASE);
                CHECK(compare(&t, cases, pix, 1, &ratio, NULL) == 0);
            }
            CHECK(wfrag != NULL);
            free(wfrag);
        }
        free(frag_src);
        mf_table_free(&t);
    }
    if (ctx)
        OSMesaDestroyContext(ctx);
    MF_TEST_MAIN_END();
}
