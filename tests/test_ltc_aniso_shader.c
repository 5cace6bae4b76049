/*
 * test_ltc_aniso_shader.c -- the GLSL/HLSL lookup snippet of the anisotropic LTC table
 * (mf_ltc_aniso_shader.h), for both parameterisations (alpha_x, alpha_y) and (alpha, lambda):
 *   - the GLSL compiles as a #version 330 fragment shader and the HLSL through the HLSL front end
 *     (-D -e main -S frag) of glslangValidator;
 *   - the generated GLSL itself, compiled as C++ over a small shim of the GLSL types and a
 *     software bilinear sampler (clamp-to-edge, texel centres at (i + 0.5)/n), in float with
 *     single-precision constants (as a GPU evaluates it) and in double, equals mf_ltc_aniso_lookup
 *     (M, magnitude, fresnel) and the double inverse of its M (minv) at random (alpha_x, alpha_y,
 *     theta, phi in [0, 2 pi)) with points in all four azimuth quadrants, exactly on the mirror
 *     lines phi = 0, pi/2, pi, 3 pi/2 and 1e-9 beside them; the view-vector entry point
 *     (_ltc_view) in double as well;
 *   - refusals: a table of another layout, a bad prefix, WGSL (one-line messages).
 * The table is synthetic (sizes 4 x 3 x 5 x 6, so a mix-up of axes shows), float32 values with
 * the symmetry of anisotropic GGX built in: at phi = 0 the entries odd under y -> -y (m01, m10,
 * m12, m21) are 0, at phi = pi/2 those odd under x -> -x (m01, m10, m02, m20), and at theta = 0
 * nothing depends on phi, as in a fitted table (mf_ltc_aniso_table.h) -- so the mirrored lookup
 * is continuous across the mirror lines and a float rounding that puts a point on the other side
 * of a line moves the result by rounding only.  Fixed seed; tolerances stated where used.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mfkit/io/mf_ltc_aniso_shader.h>
#include <mfkit/io/mf_table_io.h>
#include <mfkit/mf_ltc_aniso_table.h>
#include <mfkit/mf_rng.h>

#include "glsl_cxx_shim.h"
#include "mf_test.h"
#include "test_files.h"

static char dir[] = "/tmp/mfkit_test_ltc_aniso_shader_XXXXXX";
static const int k_n[4] = {4, 3, 5, 6};

static int run_logged(const char *cmd)
{
    char full[8192];
    snprintf(full, sizeof full, "(%s) >%s/cmd.log 2>&1", cmd, dir);
    int rc = system(full);
    if (rc != 0) {
        fprintf(stderr, "failed (%d): %s\n", rc, cmd);
        snprintf(full, sizeof full, "head -c 4000 %s/cmd.log >&2", dir);
        if (system(full) != 0)
            fprintf(stderr, "(no log)\n");
    }
    return rc;
}

/* The synthetic table described above. */
static void make_table(mf_table *t, int param)
{
    mf_status st = mf_ltc_aniso_table_create(t, k_n, param);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        exit(1);
    int idx[4];
    for (idx[3] = 0; idx[3] < k_n[3]; ++idx[3])
        for (idx[2] = 0; idx[2] < k_n[2]; ++idx[2])
            for (idx[1] = 0; idx[1] < k_n[1]; ++idx[1])
                for (idx[0] = 0; idx[0] < k_n[0]; ++idx[0]) {
                    double ax, ay, th, ph;
                    mf_ltc_aniso_entry_values(t, idx, &ax, &ay, &th, &ph);
                    double st_ = sin(th);
                    double cp = idx[3] == k_n[3] - 1 ? 0.0 : cos(ph), sp = idx[3] == 0 ? 0.0 : sin(ph);
                    double c = st_ * cp, s = st_ * sp;
                    double g[12];
                    for (int f = 0; f < 12; ++f)
                        g[f] = 0.05 * sin(0.37 * (idx[0] + 7 * idx[1] + 13 * idx[2]) + f) +
                               0.03 * st_ * sin(1.3 * idx[3] + f);
                    double m[9] = {1.0 + 0.5 * ax + 0.2 * th + g[0], c * s * (0.2 + g[1]), c * (0.3 + g[2]),
                                   c * s * (0.1 + g[3]),           1.0 + 0.4 * ay + 0.1 * th + g[4], s * (0.25 + g[5]),
                                   c * (0.2 + g[6]),               s * (0.15 + g[7]), 1.2 + 0.3 * (ax + ay) + g[8]};
                    double *r = mf_table_record(t, idx);
                    mf_mat3 mm, mi;
                    for (int k = 0; k < 9; ++k) {
                        r[MF_LTCA_F_M00 + k] = (double)(float)m[k]; /* the texture holds float32 */
                        mm.m[k / 3][k % 3] = r[MF_LTCA_F_M00 + k];
                    }
                    CHECK(mf_mat3_inverse(mm, &mi) == MF_OK);
                    for (int k = 0; k < 9; ++k)
                        r[MF_LTCA_F_MINV00 + k] = mi.m[k / 3][k % 3];
                    r[MF_LTCA_F_MAGNITUDE] = (double)(float)(0.6 + 0.2 * ax - 0.1 * th + g[9]);
                    r[MF_LTCA_F_FRESNEL] = (double)(float)(0.1 + 0.05 * ay + 0.5 * g[10]);
                    r[MF_LTCA_F_RESIDUAL] = (double)(float)(1e-3 + 0.1 * g[11] * g[11]);
                }
}

static char *snippet(const mf_table *t, int hlsl, const char *name)
{
    char path[512], msg[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    mf_status st = mf_ltc_aniso_shader_write(path, t, hlsl ? MF_SHADER_HLSL : MF_SHADER_GLSL, "lta", msg, sizeof msg);
    if (st != MF_OK)
        fprintf(stderr, "%s: %s\n", name, msg);
    CHECK(st == MF_OK);
    long len = 0;
    return (char *)mf_test_read_file(path, &len);
}

static void test_compiles(void)
{
    if (!mf_test_have_tool("glslangValidator")) {
        fprintf(stderr, "glslangValidator is needed (Debian: glslang-tools)\n");
        CHECK(0);
        return;
    }
    for (int param = 0; param <= 1; ++param) {
        mf_table t;
        make_table(&t, param);
        for (int hlsl = 0; hlsl <= 1; ++hlsl) {
            char name[64], path[512], cmd[2048];
            snprintf(name, sizeof name, "lta%d.%s", param, hlsl ? "hlsl" : "glsl");
            char *snip = snippet(&t, hlsl, name);
            if (!snip) {
                CHECK(0);
                continue;
            }
            size_t size = strlen(snip) + 2048;
            char *src = malloc(size);
            if (!src)
                exit(1);
            if (hlsl)
                snprintf(src, size,
                         "%s\nTexture2D<float4> t0 : register(t0);\nTexture2D<float4> t1 : register(t1);\n"
                         "Texture2D<float4> t2 : register(t2);\nSamplerState s : register(s0);\n"
                         "float4 main(float4 x : TEXCOORD0) : SV_Target {\n"
                         "  lta_ltc a = lta_ltc_angles(t0, t1, t2, s, x.x, x.y, x.z, x.w);\n"
                         "  lta_ltc b = lta_ltc_view(t0, t1, t2, s, x.x, x.y, normalize(x.xyz));\n"
                         "  return float4(mul(a.minv, x.xyz) + mul(b.m, x.xyz), a.magnitude + b.fresnel);\n}\n",
                         snip);
            else
                snprintf(src, size,
                         "#version 330\n%s\nuniform sampler2D t0;\nuniform sampler2D t1;\nuniform sampler2D t2;\n"
                         "in vec4 x;\nout vec4 color;\nvoid main() {\n"
                         "  lta_ltc a = lta_ltc_angles(t0, t1, t2, x.x, x.y, x.z, x.w);\n"
                         "  lta_ltc b = lta_ltc_view(t0, t1, t2, x.x, x.y, normalize(x.xyz));\n"
                         "  color = vec4(a.minv * x.xyz + b.m * x.xyz, a.magnitude + b.fresnel);\n}\n",
                         snip);
            snprintf(path, sizeof path, "%s/use_lta%d.%s", dir, param, hlsl ? "hlsl" : "frag");
            CHECK(mf_test_write_file(path, src, strlen(src)) == 0);
            if (hlsl)
                snprintf(cmd, sizeof cmd, "glslangValidator -V -D -e main -S frag -o %s/lta.spv %s", dir, path);
            else
                snprintf(cmd, sizeof cmd, "glslangValidator %s", path);
            CHECK(run_logged(cmd) == 0);
            free(src);
            free(snip);
        }
        mf_table_free(&t);
    }
}


/* argv: width height img0 img1 img2 points; per point: the angles entry point's m (row-major),
 * minv (row-major), magnitude, fresnel, then the same of the view entry point. */
static const char k_twin_main[] =
    "static void put(const lta_ltc &r) {\n"
    "  for (int i = 0; i < 3; ++i) for (int j = 0; j < 3; ++j) {\n"
    "    const vec3 &c = r.m[j]; printf(\"%.17g \", double(i == 0 ? c.x : i == 1 ? c.y : c.z)); }\n"
    "  for (int i = 0; i < 3; ++i) for (int j = 0; j < 3; ++j) {\n"
    "    const vec3 &c = r.minv[j]; printf(\"%.17g \", double(i == 0 ? c.x : i == 1 ? c.y : c.z)); }\n"
    "  printf(\"%.17g %.17g \", double(r.magnitude), double(r.fresnel));\n"
    "}\n"
    "int main(int argc, char **argv) {\n"
    "  if (argc != 7) return 2;\n"
    "  texture tex[3];\n"
    "  for (int k = 0; k < 3; ++k) {\n"
    "    tex[k].w = atoi(argv[1]); tex[k].h = atoi(argv[2]);\n"
    "    FILE *f = fopen(argv[3 + k], \"r\"); if (!f) return 2;\n"
    "    double d;\n"
    "    while (fscanf(f, \"%lf\", &d) == 1) tex[k].t.push_back(float(d));\n"
    "    fclose(f);\n"
    "    if (tex[k].t.size() != size_t(tex[k].w) * size_t(tex[k].h) * 4) return 3;\n"
    "  }\n"
    "  FILE *p = fopen(argv[6], \"r\"); if (!p) return 2;\n"
    "  double q[4];\n"
    "  while (fscanf(p, \"%lf %lf %lf %lf\", &q[0], &q[1], &q[2], &q[3]) == 4) {\n"
    "    put(lta_ltc_angles(tex[0], tex[1], tex[2], float(q[0]), float(q[1]), float(q[2]), float(q[3])));\n"
    "    vec3 wo(float(std::sin(q[2]) * std::cos(q[3])), float(std::sin(q[2]) * std::sin(q[3])), float(std::cos(q[2])));\n"
    "    put(lta_ltc_view(tex[0], tex[1], tex[2], float(q[0]), float(q[1]), wo));\n"
    "    printf(\"\\n\");\n"
    "  }\n"
    "  fclose(p);\n"
    "  return 0;\n"
    "}\n";

enum { NPTS = 480 };

static void test_twin(void)
{
    if (!mf_test_have_tool("c++")) {
        fprintf(stderr, "c++ is needed for the shader twin test\n");
        CHECK(0);
        return;
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20240612), 0);
    for (int param = 0; param <= 1; ++param) {
        mf_table t;
        make_table(&t, param);
        mf_table_atlas a;
        CHECK(mf_table_atlas_layout(&t, 0, &a) == MF_OK);
        char name[64], img[3][512], pts[512], src[512], cmd[8192];
        snprintf(name, sizeof name, "twin%d.glsl", param);
        char *snip = snippet(&t, 0, name);
        free(snip);
        /* the three textures: the atlas of the table's fields mf_ltc_aniso_shader_fields */
        size_t npx = (size_t)a.width * (size_t)a.height;
        double *image = malloc(npx * (size_t)t.nfields * sizeof *image);
        if (!image)
            exit(1);
        mf_table_atlas_fill(&t, &a, image);
        for (int k = 0; k < 3; ++k) {
            snprintf(img[k], sizeof img[k], "%s/twin%d_tex%d.txt", dir, param, k);
            FILE *fi = fopen(img[k], "w");
            CHECK(fi != NULL);
            if (!fi)
                exit(1);
            for (size_t i = 0; i < npx; ++i)
                for (int c = 0; c < 4; ++c)
                    fprintf(fi, "%.17g\n", image[i * (size_t)t.nfields + (size_t)mf_ltc_aniso_shader_fields[k][c]]);
            fclose(fi);
        }
        free(image);
        /* points: alpha_x, alpha_y and theta over their range and 10% beyond (clamp-to-edge; for
         * the (alpha, lambda) table alpha_y up to alpha_x so lambda covers [0, 1]), phi uniform in
         * [0, 2 pi); the first 40 exactly on the mirror lines k pi/2 (as the double nearest) and
         * 1e-9 to either side of them */
        static double p[NPTS][4];
        int quadrant[4] = {0, 0, 0, 0}, on_line = 0;
        snprintf(pts, sizeof pts, "%s/twin%d_points.txt", dir, param);
        FILE *fp = fopen(pts, "w");
        CHECK(fp != NULL);
        if (!fp)
            exit(1);
        for (int j = 0; j < NPTS; ++j) {
            p[j][0] = -0.1 + 1.2 * mf_pcg32_next_double(&rng);
            p[j][1] = param ? p[j][0] * (-0.1 + 1.2 * mf_pcg32_next_double(&rng)) : -0.1 + 1.2 * mf_pcg32_next_double(&rng);
            p[j][2] = MF_LTC_ANISO_THETA_MAX * (-0.1 + 1.2 * mf_pcg32_next_double(&rng));
            p[j][3] = 2.0 * MF_PI * mf_pcg32_next_double(&rng);
            if (j < 40) {
                int k = j % 4, side = (j / 4) % 3; /* side 0: on the line, 1: below, 2: above */
                p[j][3] = k * (0.5 * MF_PI) + (side == 1 ? -1e-9 : side == 2 ? 1e-9 : 0.0);
                if (p[j][3] < 0.0)
                    p[j][3] += 2.0 * MF_PI;
                on_line += side == 0;
            }
            int q = (int)(p[j][3] / (0.5 * MF_PI));
            quadrant[q > 3 ? 3 : q]++;
            fprintf(fp, "%.17g %.17g %.17g %.17g\n", p[j][0], p[j][1], p[j][2], p[j][3]);
        }
        fclose(fp);
        CHECK(on_line >= 12 && quadrant[0] >= 60 && quadrant[1] >= 60 && quadrant[2] >= 60 && quadrant[3] >= 60);
        printf("(%s) points per azimuth quadrant %d %d %d %d, %d exactly on a mirror line\n", param ? "alpha, lambda" : "alpha_x, alpha_y",
               quadrant[0], quadrant[1], quadrant[2], quadrant[3], on_line);
        /* scales for the tolerances: the largest |value| of a field, its largest step between
         * neighbouring texels, and per axis the largest slope (step / spacing) */
        double maxabs = 0.0, maxstep = 0.0, slope[4] = {0, 0, 0, 0};
        size_t texels = mf_table_texels(&t);
        for (size_t i = 0; i < texels; ++i) {
            size_t stride = 1;
            for (int k = 0; k < 4; ++k) {
                size_t ik = (i / stride) % (size_t)k_n[k];
                double h = (t.axes[k].hi - t.axes[k].lo) / (k_n[k] - 1);
                for (int f = 0; f < 20; ++f) {
                    if (f >= MF_LTCA_F_MINV00 && f < MF_LTCA_F_MAGNITUDE)
                        continue;
                    double v = t.data[i * (size_t)t.nfields + (size_t)f];
                    maxabs = fmax(maxabs, fabs(v));
                    if (ik + 1 < (size_t)k_n[k]) {
                        double d = fabs(t.data[(i + stride) * (size_t)t.nfields + (size_t)f] - v);
                        maxstep = fmax(maxstep, d);
                        slope[k] = fmax(slope[k], d / h);
                    }
                }
                stride *= (size_t)k_n[k];
            }
        }
        for (int dbl = 0; dbl <= 1; ++dbl) {
            snprintf(src, sizeof src, "%s/twin%d_%d.cpp", dir, param, dbl);
            char body[16384];
            snprintf(body, sizeof body, "%s#include \"twin%d.glsl\"\n%s", k_glsl_cxx_shim, param, k_twin_main);
            CHECK(mf_test_write_file(src, body, strlen(body)) == 0);
            snprintf(cmd, sizeof cmd,
                     "c++ -std=c++17 -O1 -ffp-contract=off %s -I%s %s -o %s/twin%d_%d && %s/twin%d_%d %d %d %s %s %s %s "
                     ">%s/twin%d_%d.out",
                     dbl ? "-DTWIN_DOUBLE" : "-fsingle-precision-constant", dir, src, dir, param, dbl, dir, param, dbl,
                     a.width, a.height, img[0], img[1], img[2], pts, dir, param, dbl);
            CHECK(run_logged(cmd) == 0);
            char out[512];
            snprintf(out, sizeof out, "%s/twin%d_%d.out", dir, param, dbl);
            FILE *fo = fopen(out, "r");
            CHECK(fo != NULL);
            if (!fo)
                continue;
            /* Tolerance of M, magnitude and fresnel.
             * double: the snippet and mf_table_lookup differ in the order of a few roundings (the
             * bilinear weights of the atlas taps against the multilinear blend; mf_table_lookup's
             * snap to texel centres within 8 ulp), and the azimuth fold (floor against fmod) by an
             * ulp of 2 pi: 1e-12 of the largest value.
             * float: as test_table_nd's twin, every coordinate is rounded to float32 (about 8
             * roundings of 2^-24), which moves a filter position of up to max(width, height)
             * texels by 8 2^-24 max(width, height) texels, i.e. the value by that times the largest
             * step between neighbouring texels; the sums of 4 x 4 float terms add 2^-24 4 16
             * max |value|; the fold adds 4 roundings of 2^-24 2 pi to phi, times the slope along phi.
             * Tolerance of minv, per point: to first order minv moves by |Minv|^2 |dM| (Frobenius),
             * plus the rounding of the adjugate and the determinant, 64 eps |M| |Minv|^2. */
            double eps = dbl ? 0x1p-53 : 0x1p-24;
            double side = (double)(a.width > a.height ? a.width : a.height);
            double tol = dbl ? 1e-12 * maxabs
                             : 8.0 * eps * side * maxstep + eps * 4.0 * 16.0 * maxabs + 4.0 * eps * 2.0 * MF_PI * slope[3];
            /* the view entry point (checked in double only, where theta is in (0.01, theta max)):
             * acos of the rounded cos theta is off by up to sqrt(2 eps) < 2e-8 rad, atan2 by an ulp */
            double tol_view = tol + 2e-8 * slope[2] + 1e-15 * slope[3];
            double worst = 0.0, worst_minv = 0.0, worst_view = 0.0;
            int bad = 0, count = 0, nview = 0;
            for (int j = 0; j < NPTS; ++j) {
                double got[40];
                int okread = 1;
                for (int k = 0; k < 40; ++k)
                    okread = okread && fscanf(fo, "%lf", &got[k]) == 1;
                if (!okread)
                    break;
                double m[9], mag, fr;
                CHECK(mf_ltc_aniso_lookup(&t, p[j][0], p[j][1], p[j][2], p[j][3], m, &mag, &fr) == MF_OK);
                mf_mat3 mm, mi;
                double nm = 0.0, ni = 0.0;
                for (int k = 0; k < 9; ++k) {
                    mm.m[k / 3][k % 3] = m[k];
                    nm += m[k] * m[k];
                }
                CHECK(mf_mat3_inverse(mm, &mi) == MF_OK);
                for (int k = 0; k < 9; ++k)
                    ni += mi.m[k / 3][k % 3] * mi.m[k / 3][k % 3];
                nm = sqrt(nm);
                ni = sqrt(ni);
                double want[20];
                for (int k = 0; k < 9; ++k) {
                    want[k] = m[k];
                    want[9 + k] = mi.m[k / 3][k % 3];
                }
                want[18] = mag;
                want[19] = fr;
                int view = dbl && p[j][2] > 0.01 && p[j][2] < MF_LTC_ANISO_THETA_MAX;
                nview += view;
                for (int v = 0; v <= view; ++v)
                    for (int k = 0; k < 20; ++k) {
                        double tk = v ? tol_view : tol;
                        int is_minv = k >= 9 && k < 18;
                        if (is_minv)
                            tk = ni * ni * tk * 3.0 + 64.0 * eps * nm * ni * ni;
                        double e = fabs(got[20 * v + k] - want[k]);
                        if (v)
                            worst_view = fmax(worst_view, e / tk);
                        else if (is_minv)
                            worst_minv = fmax(worst_minv, e / tk);
                        else
                            worst = fmax(worst, e / tk);
                        if (!(e <= tk) && bad++ < 5)
                            fprintf(stderr,
                                    "param %d %s%s, point %d (alpha %.6g %.6g, theta %.6g, phi %.17g) value %d: "
                                    "snippet %.17g, mf_ltc_aniso_lookup %.17g, |diff| %.3g > %.3g\n",
                                    param, dbl ? "double" : "float", v ? " view" : "", j, p[j][0], p[j][1], p[j][2],
                                    p[j][3], k, got[20 * v + k], want[k], e, tk);
                    }
                ++count;
            }
            fclose(fo);
            CHECK(count == NPTS && bad == 0 && (!dbl || nview > NPTS / 2));
            printf("(%s) %s: %d points, max |snippet - mf_ltc_aniso_lookup| / tolerance: M, magnitude, fresnel %.3g "
                   "(tolerance %.3g), minv %.3g, view entry %.3g (%d points)\n",
                   param ? "alpha, lambda" : "alpha_x, alpha_y", dbl ? "double" : "float", count, worst, tol,
                   worst_minv, worst_view, nview);
        }
        mf_table_free(&t);
    }
}

static void test_refusals(void)
{
    mf_table t;
    make_table(&t, 0);
    mf_buf b = {0};
    char msg[512];
    CHECK(mf_ltc_aniso_shader_build(&b, &t, MF_SHADER_GLSL, "9bad", NULL, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(strstr(msg, "prefix") && !strchr(msg, '\n'));
    CHECK(mf_ltc_aniso_shader_build(&b, &t, MF_SHADER_WGSL, "ok", NULL, msg, sizeof msg) == MF_ERR_UNSUPPORTED);
    CHECK(strstr(msg, "GLSL and HLSL") && !strchr(msg, '\n'));
    snprintf(t.axes[3].name, sizeof t.axes[3].name, "psi");
    char path[512];
    snprintf(path, sizeof path, "%s/refused.glsl", dir);
    CHECK(mf_ltc_aniso_shader_write(path, &t, MF_SHADER_GLSL, "ok", msg, sizeof msg) == MF_ERR_UNSUPPORTED);
    CHECK(strstr(msg, "refused.glsl: not an anisotropic LTC table") && !strchr(msg, '\n'));
    if (!strstr(msg, "refused.glsl"))
        fprintf(stderr, "message: %s\n", msg);
    CHECK(access(path, F_OK) != 0); /* no partial output */
    mf_buf_free(&b);
    mf_table_free(&t);
}

int main(void)
{
    mf_test_seed(1);
    if (mkdtemp(dir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    test_compiles();
    test_twin();
    test_refusals();
    if (mf_test_failures == 0)
        CHECK(mf_test_remove_dir(dir) == 0);
    else
        fprintf(stderr, "files kept in %s\n", dir);
    MF_TEST_MAIN_END();
}
