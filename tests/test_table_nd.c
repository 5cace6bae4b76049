/*
 * test_table_nd.c -- tables of 3 to 6 axes in every format (mf_table_io.h, docs/tables.md):
 *   - bitwise float32 round trips (axes, fields, metadata and every value) through EXR, DDS,
 *     JSON and NPY; EXR and DDS store the 2D atlas of mf_table.h, checked texel for texel
 *     against mf_table_atlas_fill, with the default and a recorded (unused tiles) layout, and
 *     in half floats;
 *   - CSV rows and the C header of a 4-axis table compiling with -Wall -Wextra -pedantic
 *     -Werror as C11 and C++17 and indexing as its comment says;
 *   - the GLSL and HLSL lookup snippets of 2 to 5 axes: compiled by glslangValidator (GLSL as a
 *     #version 330 fragment shader, HLSL by its HLSL front end), and the GLSL snippet itself,
 *     compiled as C++ over a small shim of the GLSL types and a software bilinear sampler,
 *     equal to mf_table_atlas_lookup (the C twin) at random points.
 * Fixed seeds; tolerances stated where they are used.
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <mfkit/io/mf_image.h>
#include <mfkit/io/mf_table_io.h>
#include <mfkit/fit/mf_image_oiio.h>
#include <mfkit/mf_rng.h>
#include <mfkit/mf_table.h>

#include "glsl_cxx_shim.h"
#include "mf_test.h"
#include "test_tables.h"
#include "test_files.h"

static char dir[] = "/tmp/mfkit_test_table_nd_XXXXXX";

static void path_in_dir(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", dir, name); }

static int spit(const char *path, const char *text) { return mf_test_write_file(path, text, strlen(text)); }

/* Runs cmd with its output in dir/cmd.log, printed on failure. */
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

/* ---- the sample tables ---------------------------------------------------------------------- */

static const int k_sizes[MF_TABLE_MAX_AXES] = {5, 4, 3, 2, 3, 2};
static const char *const k_fields[4] = {"a", "b", "c", "d"};

/* A table of naxes axes (sizes k_sizes, mixed mappings and a clamp) and 4 fields: smooth values
 * plus a few that are not float32 values (they must round), a -0 and a float subnormal. */
static void make_nd(mf_table *t, int naxes, int nfields)
{
    mf_table_axis ax[MF_TABLE_MAX_AXES];
    memset(ax, 0, sizeof ax);
    for (int k = 0; k < naxes; ++k) {
        snprintf(ax[k].name, sizeof ax[k].name, "p%d", k);
        snprintf(ax[k].physical, sizeof ax[k].physical, "x%d", k);
        ax[k].size = k_sizes[k];
        ax[k].lo = 0.1 * k;
        ax[k].hi = 1.0 + 0.3 * k;
        ax[k].mapping = (mf_axis_mapping)(k % 4);
        ax[k].physical_min = k == 1 ? 1e-3 : -INFINITY;
    }
    mf_status st = mf_table_create(t, naxes, ax, nfields, k_fields);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        exit(1);
    CHECK(mf_table_set_meta(t, "tool", "mfkit test_table_nd") == MF_OK);
    CHECK(mf_table_set_meta(t, "kind", "none") == MF_OK);
    size_t n = mf_table_texels(t) * (size_t)nfields;
    for (size_t i = 0; i < n; ++i)
        t->data[i] = sin(0.37 * (double)i + 0.1 * naxes) * (1.0 + 0.01 * (double)(i % 7)) + 0.25 * (double)(i % 3);
    t->data[1] = -0.0;
    t->data[2] = 1.401298464324817e-45;
    t->data[n - 1] = 0.1;
}

/* b's values are exactly round(a's values) (float32, or half with `half`), bit for bit. */
static int same_values(const mf_table *a, const mf_table *b, int half)
{
    size_t n = mf_table_texels(a) * (size_t)a->nfields;
    if (mf_table_texels(b) * (size_t)b->nfields != n)
        return 0;
    for (size_t i = 0; i < n; ++i) {
        double want = half ? mf_half_to_double(mf_half_from_double(a->data[i])) : (double)(float)a->data[i];
        if (mf_test_float_bits((float)want) != mf_test_float_bits((float)b->data[i]) ||
            (double)(float)b->data[i] != b->data[i]) {
            fprintf(stderr, "value %zu: %.9g read back as %.9g\n", i, want, b->data[i]);
            return 0;
        }
    }
    return 1;
}

/* ---- round trips ---------------------------------------------------------------------------- */

static void round_trip(const mf_table *t, const char *name, int half)
{
    char path[512], msg[512];
    path_in_dir(path, sizeof path, name);
    mf_table_write_options o;
    mf_table_write_options_default(&o);
    o.half_float = half;
    mf_status st = mf_table_write(path, t, &o, NULL, msg, sizeof msg);
    if (st != MF_OK)
        fprintf(stderr, "write %s: %s\n", name, msg);
    CHECK(st == MF_OK);
    mf_table back;
    mf_table_file_info info;
    st = mf_table_read(path, &back, &info, msg, sizeof msg);
    if (st != MF_OK)
        fprintf(stderr, "read %s: %s\n", name, msg);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        return;
    int ok_meta = mf_test_same_metadata(t, &back), ok_val = same_values(t, &back, half);
    if (!ok_meta || !ok_val)
        fprintf(stderr, "%s (%d axes): metadata %s, values %s\n", name, t->naxes, ok_meta ? "same" : "DIFFER",
                ok_val ? "same" : "DIFFER");
    CHECK(ok_meta && ok_val);
    CHECK(info.has_metadata && info.half_float == half);
    mf_table_free(&back);
}

/* The pixels of the EXR and the DDS equal mf_table_atlas_fill of the table (as float32). */
static void check_atlas_pixels(const mf_table *t, const char *exr_name, const char *dds_name)
{
    mf_table_atlas a;
    CHECK(mf_table_atlas_from_meta(t, &a) == MF_OK || mf_table_atlas_layout(t, 0, &a) == MF_OK);
    size_t n = (size_t)a.width * (size_t)a.height * (size_t)t->nfields;
    double *fill = malloc(n * sizeof *fill);
    if (!fill)
        exit(1);
    mf_table_atlas_fill(t, &a, fill);
    char path[512], msg[512];
    path_in_dir(path, sizeof path, exr_name);
    mf_image img;
    mf_image_info ii;
    CHECK(mf_image_read_ex(path, &img, NULL, &ii, msg, sizeof msg) == MF_OK);
    CHECK(img.width == a.width && img.height == a.height && img.channels == t->nfields);
    if (img.pixels && img.width == a.width && img.height == a.height && img.channels == t->nfields) {
        size_t bad = 0, nf = (size_t)t->nfields;
        for (size_t c = 0; c < nf; ++c) { /* OpenEXR orders the channels by name */
            int f = mf_table_field(t, ii.channel_names[c]);
            CHECK(f >= 0);
            for (size_t p = 0; f >= 0 && p < n / nf; ++p)
                bad += mf_test_float_bits(img.pixels[p * nf + c]) !=
                       mf_test_float_bits((float)fill[p * nf + (size_t)f]);
        }
        if (bad)
            fprintf(stderr, "%s: %zu pixels differ from mf_table_atlas_fill\n", exr_name, bad);
        CHECK(bad == 0);
    }
    mf_image_free(&img);
    mf_image_info_free(&ii);
    /* DDS: 148 header bytes, then RGBA32F rows from the top; the first 4 fields */
    path_in_dir(path, sizeof path, dds_name);
    long len = 0;
    unsigned char *d = mf_test_read_file(path, &len);
    size_t px = (size_t)a.width * (size_t)a.height;
    CHECK(d && len == (long)(148 + 16 * px));
    if (d && len == (long)(148 + 16 * px)) {
        uint32_t h, w;
        memcpy(&h, d + 12, 4);
        memcpy(&w, d + 16, 4);
        CHECK((int)w == a.width && (int)h == a.height);
        size_t bad = 0;
        for (size_t p = 0; p < px; ++p)
            for (int c = 0; c < 4; ++c) {
                float v;
                memcpy(&v, d + 148 + 16 * p + 4 * (size_t)c, 4);
                bad += mf_test_float_bits(v) != mf_test_float_bits((float)fill[p * (size_t)t->nfields + (size_t)c]);
            }
        if (bad)
            fprintf(stderr, "%s: %zu values differ from mf_table_atlas_fill\n", dds_name, bad);
        CHECK(bad == 0);
    }
    free(d);
    free(fill);
}

static void test_round_trips(void)
{
    const char *ext[4] = {"exr", "dds", "json", "npy"};
    for (int naxes = 3; naxes <= 6; ++naxes) {
        mf_table t;
        make_nd(&t, naxes, 4);
        char name[64], exr[64], dds[64];
        for (int e = 0; e < 4; ++e) {
            snprintf(name, sizeof name, "t%d.%s", naxes, ext[e]);
            round_trip(&t, name, 0);
        }
        snprintf(exr, sizeof exr, "t%d.exr", naxes);
        snprintf(dds, sizeof dds, "t%d.dds", naxes);
        check_atlas_pixels(&t, exr, dds);
        /* half floats */
        snprintf(name, sizeof name, "h%d.exr", naxes);
        round_trip(&t, name, 1);
        snprintf(name, sizeof name, "h%d.dds", naxes);
        round_trip(&t, name, 1);
        /* a recorded layout with unused tiles: the writers follow it, the reader restores the table
         * (and the "atlas" metadata stays the table's own) */
        mf_table_atlas a;
        int tiles = 1;
        for (int k = 2; k < naxes; ++k)
            tiles *= t.axes[k].size;
        CHECK(mf_table_atlas_layout(&t, tiles > 4 ? 4 : 2, &a) == MF_OK);
        CHECK(mf_table_atlas_record(&t, &a) == MF_OK);
        snprintf(exr, sizeof exr, "r%d.exr", naxes);
        snprintf(dds, sizeof dds, "r%d.dds", naxes);
        round_trip(&t, exr, 0);
        round_trip(&t, dds, 0);
        check_atlas_pixels(&t, exr, dds);
        /* CSV: a header row and one row per texel */
        snprintf(name, sizeof name, "t%d.csv", naxes);
        char path[512], msg[512];
        path_in_dir(path, sizeof path, name);
        CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
        long len = 0;
        char *csv = (char *)mf_test_read_file(path, &len);
        size_t rows = 0;
        for (long i = 0; csv && i < len; ++i)
            rows += csv[i] == '\n';
        CHECK(rows == mf_table_texels(&t) + 1);
        free(csv);
        mf_table_free(&t);
    }
    /* a DDS of a 3-axis table with only 3 fields (a channel of zeros) reads back its 3 fields */
    mf_table t;
    make_nd(&t, 3, 3);
    char path[512], msg[512];
    path_in_dir(path, sizeof path, "f3.dds");
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
    mf_table back;
    mf_table_file_info info;
    CHECK(mf_table_read(path, &back, &info, msg, sizeof msg) == MF_OK);
    if (back.data) {
        CHECK(back.naxes == 3 && back.nfields == 4 && strcmp(back.fields[3], "zero3") == 0);
        CHECK(info.dds_fields[0] == 0 && info.dds_fields[2] == 2 && info.dds_fields[3] == -1);
        int same = 1;
        for (size_t i = 0; i < mf_table_texels(&t); ++i)
            for (int f = 0; f < 4; ++f)
                same = same && back.data[4 * i + (size_t)f] == (f < 3 ? (double)(float)t.data[3 * i + (size_t)f] : 0.0);
        CHECK(same);
    }
    mf_table_free(&back);
    mf_table_free(&t);
}

/* A tampered atlas record is refused with a message, not misread. */
static void test_bad_atlas(void)
{
    mf_table t;
    make_nd(&t, 4, 4);
    char path[512], side[600], msg[512];
    path_in_dir(path, sizeof path, "bad.dds");
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
    snprintf(side, sizeof side, "%s.json", path);
    long len = 0;
    char *s = (char *)mf_test_read_file(side, &len);
    char *p = s ? strstr(s, "\"atlas\": \"tiles_x=3") : NULL;
    CHECK(p != NULL);
    if (p) {
        p[18] = '2'; /* tiles_x=2: the tile rows no longer match */
        CHECK(spit(side, s) == 0);
        mf_table back;
        CHECK(mf_table_read(path, &back, NULL, msg, sizeof msg) == MF_ERR_FORMAT);
        CHECK(strstr(msg, "atlas") != NULL && strchr(msg, '\n') == NULL);
        if (!strstr(msg, "atlas"))
            fprintf(stderr, "message: %s\n", msg);
    }
    free(s);
    mf_table_free(&t);
}

/* ---- the C header of a 4-axis table --------------------------------------------------------- */

static void test_c_header(void)
{
    mf_table t;
    make_nd(&t, 4, 4);
    char path[512], src[512], cmd[4096], msg[512];
    path_in_dir(path, sizeof path, "lut4.h");
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
    if (!mf_test_have_tool("cc") || !mf_test_have_tool("c++")) {
        fprintf(stderr, "cc and c++ are needed to compile the header\n");
        CHECK(0);
        mf_table_free(&t);
        return;
    }
    /* texel (4, 3, 2, 1), field 2, indexed as the header's comment says */
    int idx[4] = {4, 3, 2, 1};
    float want = (float)mf_table_record(&t, idx)[2];
    char prog[2048];
    snprintf(prog, sizeof prog,
             "#include \"lut4.h\"\n"
             "int main(void)\n{\n"
             "    int i0 = 4, i1 = 3, i2 = 2, i3 = 1;\n"
             "    float v = lut4_data[(i0 + LUT4_SIZE_0 * (i1 + LUT4_SIZE_1 * (i2 + LUT4_SIZE_2 * i3))) * LUT4_NFIELDS"
             " + LUT4_FIELD_c];\n"
             "    int ok = LUT4_NAXES == 4 && lut4_sizes[3] == LUT4_SIZE_3 && LUT4_NTEXELS == %zu;\n"
             "    ok = ok && lut4_axis_lo[2] == %.17g && lut4_axis_hi[3] == %.17g;\n"
             "    return ok && v == %af ? 0 : 1;\n}\n",
             mf_table_texels(&t), t.axes[2].lo, t.axes[3].hi, (double)want);
    for (int cxx = 0; cxx <= 1; ++cxx) {
        snprintf(src, sizeof src, "%s/use_lut4.%s", dir, cxx ? "cpp" : "c");
        CHECK(spit(src, prog) == 0);
        snprintf(cmd, sizeof cmd, "%s -Wall -Wextra -pedantic -Werror -I%s %s -o %s/use_lut4_%d && %s/use_lut4_%d",
                 cxx ? "c++ -std=c++17" : "cc -std=c11", dir, src, dir, cxx, dir, cxx);
        CHECK(run_logged(cmd) == 0);
    }
    mf_table_free(&t);
}

/* ---- the shader snippets -------------------------------------------------------------------- */


/* main: argv = width height image.txt points.txt naxes; prints the lookup of every point. */
static const char k_twin_main[] =
    "int main(int argc, char **argv) {\n"
    "  if (argc != 6) return 2;\n"
    "  texture tex; tex.w = atoi(argv[1]); tex.h = atoi(argv[2]);\n"
    "  int n = atoi(argv[5]);\n"
    "  FILE *f = fopen(argv[3], \"r\"); if (!f) return 2;\n"
    "  double d;\n"
    "  while (fscanf(f, \"%lf\", &d) == 1) tex.t.push_back(float(d));\n"
    "  fclose(f);\n"
    "  if (tex.t.size() != size_t(tex.w) * size_t(tex.h) * 4) return 3;\n"
    "  FILE *p = fopen(argv[4], \"r\"); if (!p) return 2;\n"
    "  double q[6];\n"
    "  for (;;) {\n"
    "    for (int k = 0; k < n; ++k) if (fscanf(p, \"%lf\", &q[k]) != 1) { fclose(p); return 0; }\n"
    "    vec4 r = LOOKUP(tex, q);\n"
    "    printf(\"%.17g %.17g %.17g %.17g\\n\", double(r.x), double(r.y), double(r.z), double(r.w));\n"
    "  }\n"
    "}\n";

/* A table of naxes axes (2 .. 5) for the shader tests: 4 fields of float32 values. */
static void make_shader_table(mf_table *t, int naxes)
{
    make_nd(t, naxes, 4);
    size_t n = mf_table_texels(t) * 4;
    for (size_t i = 0; i < n; ++i)
        t->data[i] = (double)(float)t->data[i]; /* the texture holds float32 */
}

static void test_shader_compiles(void)
{
    if (!mf_test_have_tool("glslangValidator")) {
        fprintf(stderr, "glslangValidator is needed (Debian: glslang-tools)\n");
        CHECK(0);
        return;
    }
    static const char *const xyzw[6] = {"x.x", "x.y", "x.z", "x.w", "x.x", "x.y"};
    for (int naxes = 2; naxes <= 5; ++naxes) {
        mf_table t;
        make_shader_table(&t, naxes);
        char path[512], msg[512], name[64], cmd[4096], args[128] = "";
        for (int k = 0; k < naxes; ++k)
            snprintf(args + strlen(args), sizeof args - strlen(args), ", %s", xyzw[k]);
        for (int hlsl = 0; hlsl <= 1; ++hlsl) {
            snprintf(name, sizeof name, "lut%d.%s", naxes, hlsl ? "hlsl" : "glsl");
            path_in_dir(path, sizeof path, name);
            CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
            long len = 0;
            char *snip = (char *)mf_test_read_file(path, &len);
            if (!snip) {
                CHECK(0);
                continue;
            }
            size_t size = (size_t)len + 1024;
            char *src = malloc(size);
            if (!src)
                exit(1);
            if (hlsl)
                snprintf(src, size,
                         "%s\nTexture2D<float4> tab : register(t0);\nSamplerState smp : register(s0);\n"
                         "float4 main(float4 x : TEXCOORD0) : SV_Target { return lut%d_lookup(tab, smp%s); }\n",
                         snip, naxes, args);
            else
                snprintf(src, size,
                         "#version 330\n%s\nuniform sampler2D tab;\nin vec4 x;\nout vec4 color;\n"
                         "void main() { color = lut%d_lookup(tab%s); }\n",
                         snip, naxes, args);
            snprintf(name, sizeof name, "use_lut%d.%s", naxes, hlsl ? "hlsl" : "frag");
            path_in_dir(path, sizeof path, name);
            CHECK(spit(path, src) == 0);
            if (hlsl)
                snprintf(cmd, sizeof cmd, "glslangValidator -V -D -e main -S frag -o %s/lut.spv %s", dir, path);
            else
                snprintf(cmd, sizeof cmd, "glslangValidator %s", path);
            CHECK(run_logged(cmd) == 0);
            free(src);
            free(snip);
        }
        mf_table_free(&t);
    }
}

/* The GLSL snippet's arithmetic, compiled as C++ (in float with single-precision constants, as a
 * GPU evaluates it, and in double), against mf_table_atlas_lookup at random parameters. */
static void test_shader_twin(void)
{
    if (!mf_test_have_tool("c++")) {
        fprintf(stderr, "c++ is needed for the shader twin test\n");
        CHECK(0);
        return;
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20240611), 0);
    for (int naxes = 2; naxes <= 5; ++naxes) {
        mf_table t;
        make_shader_table(&t, naxes);
        mf_table_atlas a;
        CHECK(mf_table_atlas_layout(&t, 0, &a) == MF_OK);
        char path[512], msg[512], img[512], pts[512], src[512], cmd[4096];
        snprintf(path, sizeof path, "%s/twin%d.glsl", dir, naxes);
        CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
        /* the atlas image, and the points: parameters over the range and 10% beyond (clamping) */
        size_t npx = (size_t)a.width * (size_t)a.height;
        double *image = malloc(npx * 4 * sizeof *image);
        if (!image)
            exit(1);
        mf_table_atlas_fill(&t, &a, image);
        snprintf(img, sizeof img, "%s/twin%d_image.txt", dir, naxes);
        snprintf(pts, sizeof pts, "%s/twin%d_points.txt", dir, naxes);
        FILE *fi = fopen(img, "w"), *fp = fopen(pts, "w");
        CHECK(fi && fp);
        if (!fi || !fp)
            exit(1);
        for (size_t i = 0; i < npx * 4; ++i)
            fprintf(fi, "%.17g\n", image[i]);
        enum { NPTS = 400 };
        static double p[NPTS][MF_TABLE_MAX_AXES];
        for (int j = 0; j < NPTS; ++j) {
            for (int k = 0; k < naxes; ++k) {
                const mf_table_axis *ax = &t.axes[k];
                double u = -0.1 + 1.2 * mf_pcg32_next_double(&rng);
                if (j < 2 * naxes && j / 2 == k)
                    u = j % 2 ? 1.0 : 0.0; /* the ends exactly */
                p[j][k] = ax->lo + (ax->hi - ax->lo) * u;
                fprintf(fp, "%s%.17g", k ? " " : "", p[j][k]);
            }
            fputc('\n', fp);
        }
        fclose(fi);
        fclose(fp);
        /* the largest difference between neighbouring texels of a field along any axis, for the
         * float tolerance below */
        double maxabs = 0.0, maxstep = 0.0;
        size_t texels = mf_table_texels(&t);
        for (size_t i = 0; i < texels; ++i) {
            size_t stride = 1;
            for (int k = 0; k < naxes; ++k) {
                size_t ik = (i / stride) % (size_t)t.axes[k].size;
                for (int f = 0; f < 4; ++f) {
                    maxabs = fmax(maxabs, fabs(t.data[4 * i + (size_t)f]));
                    if (ik + 1 < (size_t)t.axes[k].size)
                        maxstep = fmax(maxstep, fabs(t.data[4 * (i + stride) + (size_t)f] - t.data[4 * i + (size_t)f]));
                }
                stride *= (size_t)t.axes[k].size;
            }
        }
        for (int dbl = 0; dbl <= 1; ++dbl) {
            snprintf(src, sizeof src, "%s/twin%d_%d.cpp", dir, naxes, dbl);
            char body[16384];
            char args[256] = "";
            for (int k = 0; k < naxes; ++k)
                snprintf(args + strlen(args), sizeof args - strlen(args), ", float(q[%d])", k);
            snprintf(body, sizeof body, "%s#include \"twin%d.glsl\"\n#define LOOKUP(tex, q) twin%d_lookup_params(tex%s)\n%s",
                     k_glsl_cxx_shim, naxes, naxes, args, k_twin_main);
            CHECK(spit(src, body) == 0);
            snprintf(cmd, sizeof cmd,
                     "c++ -std=c++17 -O1 -ffp-contract=off %s -I%s %s -o %s/twin%d_%d && %s/twin%d_%d %d %d %s %s %d "
                     ">%s/twin%d_%d.out",
                     dbl ? "-DTWIN_DOUBLE" : "-fsingle-precision-constant", dir, src, dir, naxes, dbl, dir, naxes, dbl,
                     a.width, a.height, img, pts, naxes, dir, naxes, dbl);
            CHECK(run_logged(cmd) == 0);
            char out[512];
            snprintf(out, sizeof out, "%s/twin%d_%d.out", dir, naxes, dbl);
            FILE *fo = fopen(out, "r");
            CHECK(fo != NULL);
            if (!fo)
                continue;
            /* Tolerances.  double: the snippet and mf_table_atlas_lookup differ only in the order of
             * a few roundings (the blend weights multiplied before or after the bilinear sum), so
             * 1e-13 of the largest value.  float: every coordinate is rounded to float32 (relative
             * 2^-24 per operation, about 8 operations), which moves a filter position of up to
             * max(width, height) texels by at most 8 * 2^-24 * max(width, height) texels, i.e. the
             * value by that times the largest step between neighbouring texels, plus the rounding
             * of the float sums of up to 4 * 2^(naxes - 2) terms: 2^-24 * 4 * 2^naxes * max |value|. */
            double side = (double)(a.width > a.height ? a.width : a.height);
            double tol = dbl ? 1e-13 * maxabs
                             : 8.0 * 0x1p-24 * side * maxstep + 0x1p-24 * 4.0 * (double)(1 << naxes) * maxabs;
            double worst = 0.0;
            int bad = 0, count = 0;
            for (int j = 0; j < NPTS; ++j) {
                double got[4], want[4];
                if (fscanf(fo, "%lf %lf %lf %lf", &got[0], &got[1], &got[2], &got[3]) != 4)
                    break;
                CHECK(mf_table_atlas_lookup(&t, &a, image, p[j], want) == MF_OK);
                for (int f = 0; f < 4; ++f) {
                    double e = fabs(got[f] - want[f]);
                    worst = fmax(worst, e);
                    if (!(e <= tol) && bad++ < 3)
                        fprintf(stderr, "%d axes (%s), point %d field %d: snippet %.17g, C twin %.17g, |diff| %.3g > %.3g\n",
                                naxes, dbl ? "double" : "float", j, f, got[f], want[f], e, tol);
                }
                ++count;
            }
            fclose(fo);
            CHECK(count == NPTS && bad == 0);
            printf("shader twin, %d axes, %s: %d points, max |snippet - mf_table_atlas_lookup| = %.3g (tolerance %.3g)\n",
                   naxes, dbl ? "double" : "float", count, worst, tol);
        }
        free(image);
        mf_table_free(&t);
    }
}

int main(void)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    mf_test_seed(1);
    if (mkdtemp(dir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    test_round_trips();
    test_bad_atlas();
    test_c_header();
    test_shader_compiles();
    test_shader_twin();
    if (mf_test_failures == 0)
        CHECK(mf_test_remove_dir(dir) == 0);
    else
        fprintf(stderr, "files kept in %s\n", dir);
    MF_TEST_MAIN_END();
}
