/*
 * test_gpu_ltc.c -- the generated area-light shader code (mf_ltc_shader.h) against mfkit's C library.
 *
 * 1. Generates the GLSL, HLSL and WGSL of a small LTC table and compiles GLSL and HLSL with
 *    glslangValidator, each inside a main that calls every function (GLSL #version 330 fragment
 *    shader; HLSL with its HLSL front end to SPIR-V).  The WGSL is checked structurally here
 *    (declarations, signatures, no GLSL/HLSL spellings, balanced braces, the same function list as
 *    the GLSL) and validated by naga in tests/test_engines.sh.
 * 2. Runs the GLSL on Mesa's software rasteriser (OSMesa, llvmpipe): an 8 x 8 table built from known
 *    matrices (mf_ltc_table_pack) as float textures (GL_LINEAR, clamp-to-edge), a grid of
 *    (view, roughness, light) cases, one per pixel of a GL_RGBA32F framebuffer, each pixel holding
 *    quad (clipped), quad (clipless), line and disk, times the Fresnel split.  The same float inputs
 *    and the same float table go through the C library in double (mf_table_lookup,
 *    mf_ltc_integrate_polygon, mf_ltc_integrate_line, mf_ellipse_form_factor + the sphere field).
 *    Fails (never skips) when no OSMesa context can be made.
 * 3. With --wgsl NODE_DIR (tests/test_engines.sh, which installs naga): the WGSL with a WGSL main
 *    doing the same, translated to GLSL 3.30 by naga (NODE_DIR/wgsl_to_glsl.mjs), runs the same
 *    cases against the same reference and tolerance.
 */
#define _POSIX_C_SOURCE 200809L
#define GL_GLEXT_PROTOTYPES 1
#include "mf_test.h"

#include "gpu_osmesa.h"
#include "mfkit/io/mf_ltc_shader.h"
#include "mfkit/mf_ltc_lights.h"
#include "mfkit/mf_ltc_table.h"
#include "mfkit/mf_rng.h"

#include <string.h>
#include <unistd.h>

#define NR 8
#define NU 8

/* ---- the table: smooth known matrices, every value rounded to float ------------------------- */
static void build_table(mf_table *t)
{
    CHECK(mf_ltc_table_create(t, NR, NU) == MF_OK);
    for (int iu = 0; iu < NU; ++iu)
        for (int ir = 0; ir < NR; ++ir) {
            double r = mf_table_axis_param(&t->axes[0], ir), u = mf_table_axis_param(&t->axes[1], iu);
            double a = 0.05 + 0.95 * r * r, c = 0.06 + 0.9 * r * r, b = 0.3 * u * u * (1.0 - r), d = -0.25 * u * r;
            double m4[4];
            int idx[2] = {ir, iu};
            double *rec = mf_table_record(t, idx);
            CHECK(mf_ltc_table_pack(a, b, c, d, m4) == MF_OK);
            for (int k = 0; k < 4; ++k)
                rec[k] = m4[k];
            rec[MF_LTC_F_MAGNITUDE] = 0.95 - 0.4 * u * u * (1.0 - r);
            rec[MF_LTC_F_FRESNEL] = 0.02 + 0.3 * u * u * u;
            rec[MF_LTC_F_ZERO] = 0.0;
            /* the sphere field as the fitter stores it: sphere_integral(len, z)/len, z = 2r - 1, len = u */
            double z = 2.0 * r - 1.0;
            rec[MF_LTC_F_SPHERE] = u > 0.0 ? mf_ltc_sphere_integral(u, z) / u : fmax(z, 0.0);
            for (int k = 0; k < MF_LTC_NFIELDS; ++k)
                rec[k] = (double)(float)rec[k];
        }
}

/* ---- compiling with glslangValidator and the WGSL structure -------------------------------- */
static const char *k_glsl_uniforms =
    "uniform sampler2D ltc_1;\nuniform sampler2D ltc_2;\nuniform sampler2D cases;\nuniform int grid_w;\n"
    "out vec4 frag;\n";

/* main of the GPU run: case row = pixel index, texels 0..11 of the row (see put_case) */
static const char *k_glsl_main =
    "void main()\n{\n"
    "    ivec2 px = ivec2(gl_FragCoord.xy);\n"
    "    int id = px.x + grid_w * px.y;\n"
    "    vec4 a = texelFetch(cases, ivec2(0, id), 0);\n"
    "    vec4 b = texelFetch(cases, ivec2(1, id), 0);\n"
    "    vec3 n = a.xyz;\n    vec3 v = b.xyz;\n    float alpha = a.w;\n    vec3 f0 = vec3(b.w);\n"
    "    vec3 q0 = texelFetch(cases, ivec2(2, id), 0).xyz;\n"
    "    vec3 q1 = texelFetch(cases, ivec2(3, id), 0).xyz;\n"
    "    vec3 q2 = texelFetch(cases, ivec2(4, id), 0).xyz;\n"
    "    vec3 q3 = texelFetch(cases, ivec2(5, id), 0).xyz;\n"
    "    vec3 l1 = texelFetch(cases, ivec2(6, id), 0).xyz;\n"
    "    vec3 l2 = texelFetch(cases, ivec2(7, id), 0).xyz;\n"
    "    vec3 dc = texelFetch(cases, ivec2(8, id), 0).xyz;\n"
    "    vec3 d1 = texelFetch(cases, ivec2(9, id), 0).xyz;\n"
    "    vec3 d2 = texelFetch(cases, ivec2(10, id), 0).xyz;\n"
    "    bool two = texelFetch(cases, ivec2(11, id), 0).x > 0.5;\n"
    "    vec4 t1 = ltc_lookup(ltc_1, alpha, dot(n, v));\n"
    "    vec4 t2 = ltc_lookup(ltc_2, alpha, dot(n, v));\n"
    "    mat3 minv = ltc_minv(t1, n, v);\n"
    "    float fr = ltc_fresnel(t2, f0).x;\n"
    "    frag = fr * vec4(ltc_quad(minv, q0, q1, q2, q3, two), ltc_quad_clipless(ltc_2, minv, q0, q1, q2, q3, two),\n"
    "                     ltc_line(minv, l1, l2), ltc_disk(ltc_2, minv, dc, d1, d2, two));\n"
    "}\n";

/* the WGSL main of the same run (--wgsl): translated to GLSL by naga, each texture with its sampler
 * becomes the sampler2D _group_0_binding_<b>_fs */
static const char *k_wgsl_main =
    "@group(0) @binding(0) var ltc_1: texture_2d<f32>;\n@group(0) @binding(1) var ltc_1_s: sampler;\n"
    "@group(0) @binding(2) var ltc_2: texture_2d<f32>;\n@group(0) @binding(3) var ltc_2_s: sampler;\n"
    "@group(0) @binding(4) var cases: texture_2d<f32>;\n"
    "fn case_texel(i: i32, id: i32) -> vec4<f32> { return textureLoad(cases, vec2<i32>(i, id), 0); }\n"
    "@fragment fn main(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {\n"
    "    let id = i32(pos.x) + 32 * i32(pos.y);\n"
    "    let a = case_texel(0, id);\n    let b = case_texel(1, id);\n"
    "    let n = a.xyz;\n    let v = b.xyz;\n    let alpha = a.w;\n    let f0 = vec3<f32>(b.w, b.w, b.w);\n"
    "    let q0 = case_texel(2, id).xyz;\n    let q1 = case_texel(3, id).xyz;\n"
    "    let q2 = case_texel(4, id).xyz;\n    let q3 = case_texel(5, id).xyz;\n"
    "    let l1 = case_texel(6, id).xyz;\n    let l2 = case_texel(7, id).xyz;\n"
    "    let dc = case_texel(8, id).xyz;\n    let d1 = case_texel(9, id).xyz;\n    let d2 = case_texel(10, id).xyz;\n"
    "    let two = case_texel(11, id).x > 0.5;\n"
    "    let t1 = ltc_lookup(ltc_1, ltc_1_s, alpha, dot(n, v));\n"
    "    let t2 = ltc_lookup(ltc_2, ltc_2_s, alpha, dot(n, v));\n"
    "    let minv = ltc_minv(t1, n, v);\n"
    "    let fr = ltc_fresnel(t2, f0).x;\n"
    "    return fr * vec4<f32>(ltc_quad(minv, q0, q1, q2, q3, two), ltc_quad_clipless(ltc_2, ltc_2_s, minv, q0, q1, q2, q3, two),\n"
    "                          ltc_line(minv, l1, l2), ltc_disk(ltc_2, ltc_2_s, minv, dc, d1, d2, two));\n"
    "}\n";

static const char *k_hlsl_main =
    "Texture2D<float4> ltc_1;\nSamplerState ltc_1_s;\nTexture2D<float4> ltc_2;\nSamplerState ltc_2_s;\n"
    "cbuffer C { float3 n; float3 v; float alpha; float3 f0; float3 q0; float3 q1; float3 q2; float3 q3; int two; };\n"
    "float4 main() : SV_Target\n{\n"
    "    float4 t1 = ltc_lookup(ltc_1, ltc_1_s, alpha, dot(n, v));\n"
    "    float4 t2 = ltc_lookup(ltc_2, ltc_2_s, alpha, dot(n, v));\n"
    "    float3x3 minv = ltc_minv(t1, n, v);\n"
    "    float fr = ltc_fresnel(t2, f0).x;\n"
    "    return fr * float4(ltc_quad(minv, q0, q1, q2, q3, two != 0),\n"
    "                       ltc_quad_clipless(ltc_2, ltc_2_s, minv, q0, q1, q2, q3, two != 0),\n"
    "                       ltc_line(minv, q0, q1), ltc_disk(ltc_2, ltc_2_s, minv, q0, q1, q2, two != 0));\n"
    "}\n";

static int count(const char *s, const char *needle)
{
    int n = 0;
    for (const char *p = strstr(s, needle); p; p = strstr(p + 1, needle))
        ++n;
    return n;
}

/* The WGSL checks: what a translation slip would leave behind. */
static void check_wgsl(const char *w, const char *glsl)
{
    static const char *const forbidden[] = {"vec3(", "vec2(", "vec4(", "float ", "int ", "sampler2D", "textureLod",
                                            "mat3(", "float3", "#", "static ", "?", " out ", " inout "};
    /* the code without comments */
    size_t n = strlen(w);
    char *code = malloc(n + 1);
    size_t k = 0;
    for (size_t i = 0; i < n;) {
        if (w[i] == '/' && w[i + 1] == '/') {
            while (i < n && w[i] != '\n')
                ++i;
        } else
            code[k++] = w[i++];
    }
    code[k] = 0;
    for (size_t i = 0; i < sizeof forbidden / sizeof forbidden[0]; ++i)
        if (strstr(code, forbidden[i]))
            MF_FAIL_AT("WGSL contains '%s'", forbidden[i]);
    CHECK(count(code, "{") == count(code, "}"));
    CHECK(count(code, "(") == count(code, ")"));
    /* every declaration typed, every function with a result type (all of ours return a value) */
    int fns = 0;
    for (const char *p = strstr(code, "\nfn "); p; p = strstr(p + 1, "\nfn ")) {
        ++fns;
        const char *eol = strchr(p + 1, '\n');
        const char *arrow = strstr(p, ") -> ");
        if (!arrow || arrow > eol)
            MF_FAIL_AT("WGSL function without a result type: %.60s", p + 1);
    }
    for (const char *kw = "var "; kw; kw = strcmp(kw, "var ") ? NULL : "let ")
        for (const char *p = strstr(code, kw); p; p = strstr(p + 1, kw)) {
            const char *semi = strpbrk(p, ";=");
            const char *colon = strchr(p, ':');
            if (!colon || !semi || colon > semi)
                MF_FAIL_AT("WGSL untyped declaration: %.40s", p);
        }
    /* the same functions as the GLSL (one source): count "<prefix>_" definitions */
    int gl_fns = 0;
    for (const char *p = glsl; (p = strstr(p, "\n")) != NULL; ++p) {
        const char *q = p + 1;
        if (!strncmp(q, "float ", 6) || !strncmp(q, "vec", 3) || !strncmp(q, "mat3 ", 5))
            if (strchr(q, '(') && strchr(q, '(') < strchr(q, '\n') && strstr(q, "ltc_") == strchr(q, ' ') + 1)
                ++gl_fns;
    }
    printf("WGSL: %d functions (GLSL %d); %d var/let declarations checked\n", fns, gl_fns,
           count(code, "var ") + count(code, "let "));
    CHECK(fns == gl_fns && fns >= 17);
    free(code);
}

static char *compile_checks(const char *dir, const mf_table *t)
{
    char path[3][512], msg[512], cmd[2048];
    for (int l = 0; l < 3; ++l) {
        snprintf(path[l], sizeof path[l], "%s/ltc_area.%s", dir, mf_shader_lang_name((mf_shader_lang)l));
        mf_status st = mf_ltc_shader_write(path[l], t, (mf_shader_lang)l, "ltc", msg, sizeof msg);
        if (st != MF_OK)
            MF_FAIL_AT("%s", msg);
    }
    char *glsl = gpu_read_all(path[0]), *hlsl = gpu_read_all(path[1]), *wgsl = gpu_read_all(path[2]);
    CHECK(glsl && hlsl && wgsl);
    if (!glsl || !hlsl || !wgsl)
        return NULL;
    char frag[512], hl[512];
    snprintf(frag, sizeof frag, "%s/main.frag", dir);
    snprintf(hl, sizeof hl, "%s/main.hlsl", dir);
    FILE *f = fopen(frag, "w");
    fprintf(f, "#version 330 core\n%s%s%s", k_glsl_uniforms, glsl, k_glsl_main);
    fclose(f);
    f = fopen(hl, "w");
    fprintf(f, "%s%s", hlsl, k_hlsl_main);
    fclose(f);
    if (system("command -v glslangValidator >/dev/null 2>&1") != 0)
        MF_FAIL_AT("glslangValidator is needed (Debian: glslang-tools)");
    snprintf(cmd, sizeof cmd, "glslangValidator %s", frag);
    CHECK(gpu_run(cmd));
    snprintf(cmd, sizeof cmd, "glslangValidator -V -D -e main -S frag -o %s/main.spv %s", dir, hl);
    CHECK(gpu_run(cmd));
    check_wgsl(wgsl, glsl);
    /* refusals: not an LTC table, bad prefix */
    mf_buf b = {0};
    mf_table other; /* a table of another kind: one field renamed */
    CHECK(mf_table_copy(&other, t) == MF_OK);
    snprintf(other.fields[MF_LTC_F_SPHERE], sizeof other.fields[0], "sphere2");
    CHECK(mf_ltc_shader_build(&b, &other, MF_SHADER_GLSL, "p", msg, sizeof msg) == MF_ERR_UNSUPPORTED && msg[0]);
    CHECK(mf_ltc_shader_build(&b, t, MF_SHADER_GLSL, "1x", msg, sizeof msg) == MF_ERR_DOMAIN && msg[0]);
    mf_table_free(&other);
    mf_buf_free(&b);
    free(hlsl);
    free(wgsl);
    char *full = malloc(strlen(glsl) + 4096);
    sprintf(full, "#version 330 core\n%s%s%s", k_glsl_uniforms, glsl, k_glsl_main);
    free(glsl);
    return full;
}

/* ---- the cases ---------------------------------------------------------------------------- */
#define CASE_W 12
typedef struct gcase {
    float n[3], alpha, v[3], f0, q[4][3], l[2][3], dc[3], d1[3], d2[3], two;
} gcase;

static void put3(float *dst, mf_vec3 v)
{
    dst[0] = (float)v.x;
    dst[1] = (float)v.y;
    dst[2] = (float)v.z;
}
static mf_vec3 get3(const float *s) { return mf_vec3_make(s[0], s[1], s[2]); }

/* a light of kind k in the frame (s, t, n): a parallelogram with centre at polar angle th from n */
static void make_case(gcase *c, mf_pcg32 *rng, double cos_v, double alpha, int kind)
{
    /* a random world normal (half of them the z axis), the view at cos_v in a random azimuth */
    mf_vec3 n = mf_vec3_make(0, 0, 1);
    if (mf_pcg32_next_u32(rng) & 1) {
        double th = 0.8 * mf_pcg32_next_double(rng), ph = 2 * MF_PI * mf_pcg32_next_double(rng);
        n = mf_vec3_spherical(th, ph);
    }
    mf_frame f = mf_frame_from_normal(n);
    double phv = 2 * MF_PI * mf_pcg32_next_double(rng);
    double sv = sqrt(fmax(0.0, 1.0 - cos_v * cos_v));
    mf_vec3 v = mf_frame_to_world(f, mf_vec3_make(sv * cos(phv), sv * sin(phv), cos_v));
    /* light centre: polar angle and distance by kind */
    static const double th_k[] = {0.3, 1.2, 1.5, 0.6, 0.9, 1.75};
    static const double dist_k[] = {2.0, 2.0, 1.5, 20.0, 0.7, 2.0};
    static const double size_k[] = {0.8, 1.0, 0.6, 0.5, 1.0, 0.9};
    double th = th_k[kind] + 0.2 * (mf_pcg32_next_double(rng) - 0.5), ph = 2 * MF_PI * mf_pcg32_next_double(rng);
    mf_vec3 dir = mf_vec3_spherical(th, ph);
    mf_vec3 ctr = mf_vec3_scale(dir, dist_k[kind]);
    /* two edge vectors across dir, tilted a little */
    mf_frame lf = mf_frame_from_normal(dir);
    double tilt = 0.4 * (mf_pcg32_next_double(rng) - 0.5);
    mf_vec3 e1 = mf_vec3_scale(mf_vec3_add(lf.s, mf_vec3_scale(dir, tilt)), 0.5 * size_k[kind]);
    mf_vec3 e2 = mf_vec3_scale(lf.t, 0.35 * size_k[kind]);
    /* clockwise from the shading point (front-facing) unless kind 5 (back-facing, two-sided) */
    mf_vec3 q[4] = {mf_vec3_add(ctr, mf_vec3_add(e1, e2)), mf_vec3_add(ctr, mf_vec3_sub(e1, e2)),
                    mf_vec3_sub(ctr, mf_vec3_add(e1, e2)), mf_vec3_sub(ctr, mf_vec3_sub(e1, e2))};
    mf_vec3 nq = mf_vec3_cross(mf_vec3_sub(q[1], q[0]), mf_vec3_sub(q[2], q[0]));
    int front = mf_vec3_dot(nq, q[0]) > 0.0;
    if (front == (kind == 5)) {
        mf_vec3 tmp = q[1];
        q[1] = q[3];
        q[3] = tmp;
    }
    for (int i = 0; i < 4; ++i)
        put3(c->q[i], mf_frame_to_world(f, q[i]));
    put3(c->l[0], mf_frame_to_world(f, mf_vec3_add(ctr, e1)));
    put3(c->l[1], mf_frame_to_world(f, mf_vec3_sub(ctr, mf_vec3_scale(e1, 1.3))));
    /* the ellipse inscribed in the parallelogram, with the quad's facing: (v1 x v2).c > 0 iff front */
    mf_vec3 d1 = e1, d2 = e2;
    if ((mf_vec3_dot(mf_vec3_cross(d1, d2), ctr) > 0.0) != (kind != 5))
        d2 = mf_vec3_scale(d2, -1.0);
    put3(c->dc, mf_frame_to_world(f, ctr));
    put3(c->d1, mf_frame_to_world(f, d1));
    put3(c->d2, mf_frame_to_world(f, d2));
    put3(c->n, n);
    put3(c->v, v);
    c->alpha = (float)alpha;
    c->f0 = (float)(0.02 + 0.96 * mf_pcg32_next_double(rng));
    c->two = kind >= 4 ? 1.0f : 0.0f;
}

/* The C library on the case's float inputs: quad, clipless quad, line, disk (times the Fresnel
 * split); *sphere_gap gets the largest difference of the tabulated sphere term from the analytic one. */
static void reference(const mf_table *t, const gcase *c, double out[4], double *sphere_gap)
{
    mf_vec3 n = get3(c->n), v = get3(c->v);
    double cos_v = mf_vec3_dot(n, v);
    double p[2] = {sqrt(fmax((double)c->alpha, MF_LTC_ALPHA_MIN)),
                   sqrt(fmax(1.0 - fmax(cos_v, t->axes[1].physical_min), 0.0))};
    double rec[MF_LTC_NFIELDS];
    CHECK(mf_table_lookup(t, p, rec) == MF_OK);
    mf_ltc ltc;
    CHECK(mf_ltc_table_unpack(rec, &ltc) == MF_OK);
    /* the view frame: s along v's tangential part, t = n x s */
    mf_vec3 s = mf_vec3_normalize(mf_vec3_sub(v, mf_vec3_scale(n, cos_v)));
    mf_frame f = {s, mf_vec3_cross(n, s), n};
    mf_vec3 q[4];
    for (int i = 0; i < 4; ++i)
        q[i] = mf_frame_to_local(f, get3(c->q[i]));
    mf_polygon_sided sided = c->two > 0.5f ? MF_POLYGON_TWO_SIDED : MF_POLYGON_ONE_SIDED;
    mf_polygon poly = mf_polygon_make(4, q);
    double fr = c->f0 * rec[MF_LTC_F_MAGNITUDE] + (1.0 - c->f0) * rec[MF_LTC_F_FRESNEL];
    /* float rounding of f0 * magnitude + (1 - f0) * fresnel is part of the GPU value too */
    out[0] = mf_ltc_integrate_polygon(&ltc, &poly, sided);
    /* clipless: F of M^-1 P oriented into the light, the sphere field at (F.z/|F| / 2 + 1/2, |F|) */
    double facing = mf_vec3_dot(mf_vec3_cross(mf_vec3_sub(q[1], q[0]), mf_vec3_sub(q[2], q[0])), q[0]);
    mf_polygon po = poly;
    for (int i = 0; i < 4; ++i)
        po.v[i] = mf_mat3_apply(ltc.inv, q[i]);
    mf_vec3 ff = mf_polygon_form_factor(&po);
    if ((ltc.det < 0.0) != (facing < 0.0))
        ff = mf_vec3_scale(ff, -1.0);
    double sph[2];
    out[1] = 0.0;
    if (sided == MF_POLYGON_TWO_SIDED || facing > 0.0) {
        double len = mf_vec3_length(ff);
        double ps[2] = {0.5 * ff.z / len + 0.5, len}, r8[MF_LTC_NFIELDS];
        CHECK(mf_table_lookup(t, ps, r8) == MF_OK);
        out[1] = len * r8[MF_LTC_F_SPHERE];
        sph[0] = fabs(out[1] - mf_ltc_integrate_polygon_sphere(&ltc, &poly, sided));
    } else
        sph[0] = 0.0;
    out[2] = mf_ltc_integrate_line(&ltc, mf_frame_to_local(f, get3(c->l[0])), mf_frame_to_local(f, get3(c->l[1])));
    mf_vec3 dc = mf_frame_to_local(f, get3(c->dc)), d1 = mf_frame_to_local(f, get3(c->d1)),
            d2 = mf_frame_to_local(f, get3(c->d2));
    out[3] = 0.0;
    sph[1] = 0.0;
    if (sided == MF_POLYGON_TWO_SIDED || mf_vec3_dot(mf_vec3_cross(d1, d2), dc) > 0.0) {
        mf_vec3 fd = mf_ellipse_form_factor(mf_mat3_apply(ltc.inv, dc), mf_mat3_apply(ltc.inv, d1),
                                            mf_mat3_apply(ltc.inv, d2));
        double len = mf_vec3_length(fd);
        double ps[2] = {0.5 * fd.z / len + 0.5, len}, r8[MF_LTC_NFIELDS];
        CHECK(mf_table_lookup(t, ps, r8) == MF_OK);
        out[3] = len * r8[MF_LTC_F_SPHERE];
        sph[1] = fabs(out[3] - mf_ltc_integrate_disk(&ltc, dc, d1, d2, sided));
    }
    *sphere_gap = fmax(sph[0], sph[1]);
    for (int k = 0; k < 4; ++k)
        out[k] *= fr;
}

/* --wgsl NODE_DIR: the generated WGSL with k_wgsl_main, translated to GLSL 3.30 by naga, or NULL. */
static char *wgsl_as_glsl(const mf_table *t, const char *node_dir)
{
    char msg[512];
    mf_buf b = {0};
    CHECK(mf_ltc_shader_build(&b, t, MF_SHADER_WGSL, "ltc", msg, sizeof msg) == MF_OK);
    mf_buf_puts(&b, k_wgsl_main);
    mf_buf_put(&b, "", 1);
    char *glsl = b.failed ? NULL : gpu_wgsl_to_glsl(b.data, node_dir);
    mf_buf_free(&b);
    return glsl;
}

int main(int argc, char **argv)
{
    const char *node_dir = NULL;
    if (argc == 3 && !strcmp(argv[1], "--wgsl"))
        node_dir = argv[2];
    else if (argc != 1) {
        fprintf(stderr, "usage: test_gpu_ltc [--wgsl NODE_DIR]\n");
        return 2;
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(2016), 0);
    mf_table t;
    build_table(&t);

    char dir[] = "/tmp/mfkit_gpu_ltcXXXXXX";
    if (!mkdtemp(dir)) {
        fprintf(stderr, "cannot create a temporary directory\n");
        return 1;
    }
    char *frag_src = compile_checks(dir, &t);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    if (!frag_src)
        MF_TEST_MAIN_END();

    /* the grid: 8 views x 8 roughnesses x 6 lights */
    enum { NV = 8, NA = 8, NK = 6, NCASE = NV * NA * NK, GRID_W = 32 };
    static gcase cases[NCASE];
    int id = 0;
    for (int iv = 0; iv < NV; ++iv)
        for (int ia = 0; ia < NA; ++ia)
            for (int k = 0; k < NK; ++k) {
                double cos_v = 0.04 + 0.96 * (iv + 0.37 * mf_pcg32_next_double(&rng)) / NV; /* between texels */
                double r = 0.03 + 0.97 * (ia + mf_pcg32_next_double(&rng)) / NA;
                make_case(&cases[id++], &rng, fmin(cos_v, 1.0), r * r, k);
            }

    OSMesaContext ctx = gpu_context();
    if (!ctx)
        MF_TEST_MAIN_END();

    /* textures: ltc_1, ltc_2 (NR x NU, row iu = 0 first), the cases (CASE_W x NCASE) */
    static float t1[NR * NU * 4], t2[NR * NU * 4], ct[NCASE * CASE_W * 4];
    for (int i = 0; i < NR * NU; ++i)
        for (int k = 0; k < 4; ++k) {
            t1[4 * i + k] = (float)t.data[MF_LTC_NFIELDS * i + k];
            t2[4 * i + k] = (float)t.data[MF_LTC_NFIELDS * i + 4 + k];
        }
    memset(ct, 0, sizeof ct);
    for (int i = 0; i < NCASE; ++i) {
        float *row = ct + (size_t)i * CASE_W * 4;
        const gcase *c = &cases[i];
        memcpy(row + 0, c->n, 3 * sizeof(float));
        row[3] = c->alpha;
        memcpy(row + 4, c->v, 3 * sizeof(float));
        row[7] = c->f0;
        for (int q = 0; q < 4; ++q)
            memcpy(row + 8 + 4 * q, c->q[q], 3 * sizeof(float));
        memcpy(row + 24, c->l[0], 3 * sizeof(float));
        memcpy(row + 28, c->l[1], 3 * sizeof(float));
        memcpy(row + 32, c->dc, 3 * sizeof(float));
        memcpy(row + 36, c->d1, 3 * sizeof(float));
        memcpy(row + 40, c->d2, 3 * sizeof(float));
        row[44] = c->two;
    }
    gpu_float_texture(0, NR, NU, t1, GL_LINEAR);
    gpu_float_texture(1, NR, NU, t2, GL_LINEAR);
    gpu_float_texture(2, CASE_W, NCASE, ct, GL_NEAREST);

    /* compare.  Tolerance |gpu - C| <= 2e-6 + 2e-4 |C| (docs/tables.md, "Shader code"): the GPU
     * evaluates in float what C evaluates in double on the same float inputs and float table.
     * Absolute part: Lambert's sum adds up to 8 + 2 edge terms of size up to pi, each after ~10
     * float operations: 10 * 10 * 6e-8 * pi / (2 pi) ~ 3e-6 in the worst case, 2e-6 allowed (the
     * measured worst is 7e-7).  Relative part: for a small light the edge terms (size ~ its angular
     * size s) cancel to a result ~ s^2, so the relative error grows like eps / s: 6e-8 * 10 / 0.025
     * = 2.4e-5 for the far light (s ~ 0.025 rad), times the condition of M^-1 (< 10 here): 2e-4.
     * llvmpipe filters float textures with float weights (a C model with 8-bit weights is off by
     * 2.5e-3 relative, i.e. that hardware behaviour would fail this test, as it should: the
     * tolerance is not loose enough to hide it). */
    /* the GLSL, and with --wgsl the WGSL (through naga's GLSL writer) */
    char *wgsl_frag = node_dir ? wgsl_as_glsl(&t, node_dir) : NULL;
    static const char *const names[2][3] = {{"ltc_1", "ltc_2", "cases"},
                                            {"_group_0_binding_0_fs", "_group_0_binding_2_fs", "_group_0_binding_4_fs"}};
    for (int variant = 0; variant < (node_dir ? 2 : 1); ++variant) {
        const char *src = variant ? wgsl_frag : frag_src;
        if (!src)
            continue;
        printf("%s on %s:\n", variant ? "the generated WGSL (translated to GLSL by naga)" : "the generated GLSL",
               (const char *)glGetString(GL_RENDERER));
        GLuint prog = gpu_program(src);
        CHECK(prog != 0);
        static float pix[NCASE * 4];
        for (int i = 0; i < NCASE * 4; ++i) /* no value of an earlier run can pass */
            pix[i] = NAN;
        if (!prog)
            continue;
        glUseProgram(prog);
        for (int k = 0; k < 3; ++k) {
            GLint loc = glGetUniformLocation(prog, names[variant][k]);
            CHECK(loc >= 0);
            glUniform1i(loc, k);
        }
        if (!variant)
            glUniform1i(glGetUniformLocation(prog, "grid_w"), GRID_W);
        CHECK(gpu_draw(3, GRID_W, NCASE / GRID_W, pix));
        glUseProgram(0);
        glDeleteProgram(prog);
        static const char *const what[4] = {"quad", "quad clipless", "line", "disk"};
        double worst[4] = {0}, worst_rel[4] = {0}, gap = 0.0;
        int nonzero[4] = {0};
        for (int i = 0; i < NCASE; ++i) {
            double ref[4], g;
            reference(&t, &cases[i], ref, &g);
            gap = fmax(gap, g);
            for (int k = 0; k < 4; ++k) {
                double gpu = pix[4 * i + k], e = fabs(gpu - ref[k]);
                worst[k] = fmax(worst[k], e);
                if (fabs(ref[k]) > 1e-3) {
                    ++nonzero[k];
                    worst_rel[k] = fmax(worst_rel[k], e / fabs(ref[k]));
                }
                double tol = 2e-4 * fabs(ref[k]) + 2e-6;
                if (!(e <= tol))
                    MF_FAIL_AT("case %d (%s): gpu %.9g vs C %.9g, |diff| %.3g > %.3g", i, what[k], gpu, ref[k], e, tol);
            }
        }
        for (int k = 0; k < 4; ++k)
            printf("%-14s worst |gpu - C| %.3g, worst relative %.3g over %d cases with C > 1e-3 (of %d)\n", what[k],
                   worst[k], worst_rel[k], nonzero[k], NCASE);
        printf("table sphere term vs analytic (not a GPU error): worst %.3g\n", gap);
        for (int k = 0; k < 4; ++k)
            CHECK(nonzero[k] >= NCASE / 4);
    }
    free(wgsl_frag);
    OSMesaDestroyContext(ctx);
    free(frag_src);
    mf_table_free(&t);
    MF_TEST_MAIN_END();
}
