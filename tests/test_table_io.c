/*
 * test_table_io.c -- table files (mf_table_io.h): bitwise float32 round trips of EXR, JSON and
 * NPY with identical metadata; half floats equal to IEEE round-to-nearest-even (and to
 * OpenImageIO's own float -> half, bit for bit); DDS 32F/16F through our reader and, when
 * /usr/bin/python3 has numpy, through numpy; OpenImageIO refusing float DDS with an error; the C
 * header compiling (and its literals round-tripping) as C and C++; GLSL/HLSL snippets (checked by
 * glslangValidator when it is installed); CSV; truncated and bit-flipped inputs of every
 * readable format failing cleanly; atomic writes that leave nothing behind on failure.
 *
 * `test_table_io --write-sample PATH` writes the sample table to PATH (used by test_table_cli.sh).
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
#include <mfkit/mf_rng.h>
#include <mfkit/mf_table.h>
#include <mfkit/io/mf_table_io.h>
#include <mfkit/fit/mf_image_oiio.h>

#include "mf_test.h"
#include "test_tables.h"
#include "test_files.h"

static char dir[] = "/tmp/mfkit_test_table_io_XXXXXX";
static int have_numpy = -1;

static void path_in_dir(char *out, size_t size, const char *name) { snprintf(out, size, "%s/%s", dir, name); }

static int run(const char *cmd)
{
    int rc = system(cmd);
    return rc;
}

static int numpy_available(void)
{
    if (have_numpy < 0) {
        have_numpy = access("/usr/bin/python3", X_OK) == 0 &&
                     run("/usr/bin/python3 -c 'import numpy' >/dev/null 2>&1") == 0;
        if (!have_numpy)
            printf("note: /usr/bin/python3 with numpy not found: the numpy checks are skipped\n");
    }
    return have_numpy;
}

/* ---- the sample tables ---------------------------------------------------------------------- */

static const char *const k_fields[5] = {"scale", "bias", "g1", "dscale_dr", "e_comp"};

/* Karis' analytic fit of the GGX split-sum terms (scale, bias) at (cos_theta, r) [Karis 2014,
 * "Physically Based Shading on Mobile"], the Smith G1 of GGX, a signed derivative, and the
 * multiple-scattering energy compensation 1 / (scale + bias) - 1: realistic magnitudes. */
static void sample_record(double cos_theta, double r, double alpha, double *rec)
{
    double c0[4] = {-1.0, -0.0275, -0.572, 0.022}, c1[4] = {1.0, 0.0425, 1.04, -0.04};
    double rr[4];
    for (int i = 0; i < 4; ++i)
        rr[i] = r * c0[i] + c1[i];
    double a004 = fmin(rr[0] * rr[0], exp2(-9.28 * cos_theta)) * rr[0] + rr[1];
    rec[0] = -1.04 * a004 + rr[2];
    rec[1] = 1.04 * a004 + rr[3];
    double tan_sq = (1.0 - cos_theta * cos_theta) / fmax(cos_theta * cos_theta, 1e-300);
    rec[2] = cos_theta > 0.0 ? 2.0 / (1.0 + sqrt(1.0 + alpha * alpha * tan_sq)) : 0.0;
    rec[3] = -(0.3 + 0.7 * cos_theta) * sin(3.0 * r) * 0.8; /* negative on most of the table */
    rec[4] = 1.0 / (rec[0] + rec[1]) - 1.0;
}

/* u = sqrt(1 - cos theta) (MF_AXIS_ONE_MINUS_SQUARE... with u^2 = 1 - cos: cos = 1 - u^2) by
 * r with alpha = max(r^2, 1e-4).  With `extremes`, a few records hold tiny, huge, negative
 * zero, float-subnormal and float-max values. */
static void make_table(mf_table *t, int n0, int n1, int extremes)
{
    mf_table_axis axes[2];
    memset(axes, 0, sizeof axes);
    snprintf(axes[0].name, sizeof axes[0].name, "u");
    snprintf(axes[0].physical, sizeof axes[0].physical, "cos_theta_o");
    axes[0].size = n0;
    axes[0].lo = 0.0;
    axes[0].hi = 1.0;
    axes[0].mapping = MF_AXIS_ONE_MINUS_SQUARE;
    axes[0].physical_min = -INFINITY;
    snprintf(axes[1].name, sizeof axes[1].name, "r");
    snprintf(axes[1].physical, sizeof axes[1].physical, "alpha");
    axes[1].size = n1;
    axes[1].lo = 0.0;
    axes[1].hi = 1.0;
    axes[1].mapping = MF_AXIS_SQUARE;
    axes[1].physical_min = 1e-4;
    mf_status st = mf_table_create(t, 2, axes, 5, k_fields);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        exit(1);
    CHECK(mf_table_set_meta(t, "tool", "mfkit test_table_io") == MF_OK);
    CHECK(mf_table_set_meta(t, "brdf", "ggx, Smith joint; \"quoted\" \\ and */ /* and \xc3\xa9") == MF_OK);
    CHECK(mf_table_set_meta(t, "samples", "4096") == MF_OK);
    for (int i1 = 0; i1 < n1; ++i1)
        for (int i0 = 0; i0 < n0; ++i0) {
            int idx[2] = {i0, i1};
            double c = mf_table_axis_physical(&t->axes[0], mf_table_axis_param(&t->axes[0], i0));
            double r = mf_table_axis_param(&t->axes[1], i1);
            double alpha = mf_table_axis_physical(&t->axes[1], r);
            sample_record(c, r, alpha, mf_table_record(t, idx));
        }
    if (extremes) {
        double *d = t->data;
        d[0] = 1e-30;          /* float normal, half underflow */
        d[1] = -1e30;          /* float normal, half overflow */
        d[2] = -0.0;
        d[3] = 1.401298464324817e-45; /* the smallest float subnormal */
        d[4] = 3.4028234663852886e38; /* FLT_MAX */
        d[5] = 6.5e-6;         /* half subnormal */
        d[6] = -65519.0;       /* rounds to -65504 in half */
        d[7] = 0.1;            /* not a float: rounds */
    }
}

/* Every value of b is exactly the float32 of the same value of a (bitwise). */
static int same_float_data(const mf_table *a, const mf_table *b)
{
    size_t n = mf_table_texels(a) * (size_t)a->nfields;
    if (mf_table_texels(b) * (size_t)b->nfields != n)
        return 0;
    for (size_t i = 0; i < n; ++i) {
        float fa = (float)a->data[i];
        if ((double)(float)b->data[i] != b->data[i] && !isnan(b->data[i]))
            return 0; /* not a float32 value */
        if (mf_test_float_bits(fa) != mf_test_float_bits((float)b->data[i])) {
            fprintf(stderr, "value %zu: %.9g vs %.9g\n", i, (double)fa, b->data[i]);
            return 0;
        }
    }
    return 1;
}

/* ---- half floats ---------------------------------------------------------------------------- */

static double half_round(double x) { return mf_half_to_double(mf_half_from_double(x)); }

static void test_half_conversion(void)
{
    /* every finite half survives half -> double -> half, and the encoding is monotonic */
    int roundtrip = 1, monotonic = 1;
    for (uint32_t h = 0; h < 0x7c00; ++h) {
        double v = mf_half_to_double((uint16_t)h);
        if (mf_half_from_double(v) != h || mf_half_from_double(-v) != (h | 0x8000u))
            roundtrip = 0;
        if (h && !(v > mf_half_to_double((uint16_t)(h - 1))))
            monotonic = 0;
    }
    CHECK(roundtrip);
    CHECK(monotonic);
    CHECK(mf_half_to_double(0x3c00) == 1.0);
    CHECK(mf_half_to_double(0x7bff) == 65504.0);
    CHECK(mf_half_to_double(0x0001) == ldexp(1.0, -24));
    CHECK(mf_half_to_double(0x0400) == ldexp(1.0, -14));
    CHECK(isinf(mf_half_to_double(0x7c00)) && isnan(mf_half_to_double(0x7e00)));
    /* ties go to the even neighbour; just off a tie goes to the nearer one */
    int ties = 1;
    for (uint32_t h = 0; h + 1 < 0x7c00; ++h) {
        double lo = mf_half_to_double((uint16_t)h), hi = mf_half_to_double((uint16_t)(h + 1));
        double mid = 0.5 * (lo + hi); /* exact in double */
        uint16_t even = (h & 1u) ? (uint16_t)(h + 1) : (uint16_t)h;
        if (mf_half_from_double(mid) != even || mf_half_from_double(nextafter(mid, 0.0)) != h ||
            mf_half_from_double(nextafter(mid, INFINITY)) != h + 1)
            ties = 0;
    }
    CHECK(ties);
    CHECK(mf_half_from_double(65519.999) == 0x7bff);
    CHECK(mf_half_from_double(65520.0) == 0x7c00);
    CHECK(mf_half_from_double(-1e30) == 0xfc00);
    CHECK(mf_half_from_double(ldexp(1.0, -25)) == 0x0000);        /* tie between 0 and 2^-24: even */
    CHECK(mf_half_from_double(nextafter(ldexp(1.0, -25), 1)) == 0x0001);
    CHECK(mf_half_from_double(-0.0) == 0x8000);
    CHECK(mf_half_from_double(NAN) == 0x7e00 && mf_half_from_double(-NAN) == 0xfe00);
    CHECK(mf_half_from_double(INFINITY) == 0x7c00 && mf_half_from_double(-INFINITY) == 0xfc00);
    /* the error report */
    double xs[6] = {1.0, 0.1, 1e-9, 1e6, NAN, -0.0};
    mf_half_error e;
    mf_half_error_of(xs, 6, &e);
    CHECK(e.count == 6 && e.overflow_count == 1 && e.underflow_count == 1);
    CHECK(isinf(e.max_abs_error) && isinf(e.max_rel_error) && e.worst_rel_index == 3);
    mf_half_error_of(xs, 3, &e);
    CHECK(e.max_rel_error == 1.0 && e.worst_rel_index == 2); /* 1e-9 flushed to zero */
    CHECK_REL(e.max_abs_error, fabs(half_round(0.1) - 0.1), 0.0);
}

/* OpenImageIO's float -> half (Imath's, inside the EXR writer) is bit for bit ours. */
static void test_half_matches_oiio(void)
{
    const int w = 1024;
    size_t n = 0, cap = 0x7c00u * 4u + 65536u;
    float *v = malloc(cap * sizeof *v);
    CHECK(v != NULL);
    if (!v)
        return;
    for (uint32_t h = 0; h < 0x7c00; ++h) {
        double x = mf_half_to_double((uint16_t)h), y = mf_half_to_double((uint16_t)(h + 1));
        float mid = (float)(0.5 * (x + y)); /* a tie, exactly representable as a float */
        v[n++] = (float)x;
        v[n++] = (h & 1) ? -mid : mid;
        v[n++] = nextafterf(mid, 0.0f);
        v[n++] = nextafterf(mid, INFINITY);
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(20240611), 1);
    while (n < cap) { /* random bit patterns: every exponent, subnormals, overflow */
        uint32_t u = mf_pcg32_next_u32(&rng);
        float f;
        memcpy(&f, &u, 4);
        if (!isnan(f))
            v[n++] = f;
    }
    int hgt = (int)(n / (size_t)w);
    n = (size_t)w * (size_t)hgt;
    mf_image img = {w, hgt, 1, v};
    char path[512], msg[512];
    path_in_dir(path, sizeof path, "imath_half.exr");
    CHECK(mf_image_write(path, &img, 1, msg, sizeof msg) == MF_OK);
    mf_image back = {0, 0, 0, NULL};
    CHECK(mf_image_read(path, &back, msg, sizeof msg) == MF_OK);
    size_t mismatches = 0, first = 0;
    if (back.pixels && back.width == w && back.height == hgt)
        for (size_t i = 0; i < n; ++i) {
            double ours = half_round((double)v[i]);
            if (mf_test_float_bits((float)ours) != mf_test_float_bits(back.pixels[i]) && mismatches++ == 0)
                first = i;
        }
    else
        mismatches = 1;
    if (mismatches)
        fprintf(stderr, "half mismatch: %zu values, first %.9g -> ours %.9g, OpenImageIO %.9g\n", mismatches,
                (double)v[first], half_round((double)v[first]), back.pixels ? (double)back.pixels[first] : 0.0);
    CHECK(mismatches == 0);
    printf("OpenImageIO's EXR float->half matches mf_half_from_float on %zu values (all half ties)\n", n);
    mf_image_free(&back);
    free(v);
    remove(path);
}

/* ---- round trips ----------------------------------------------------------------------------- */

static void write_ok(const char *name, const mf_table *t, const mf_table_write_options *o, mf_half_error *he,
                     char *path, size_t size)
{
    char msg[512];
    path_in_dir(path, size, name);
    mf_status st = mf_table_write(path, t, o, he, msg, sizeof msg);
    if (st != MF_OK)
        fprintf(stderr, "write %s: %s\n", name, msg);
    CHECK(st == MF_OK);
    CHECK(msg[0] == '\0');
    CHECK(mf_test_file_exists(path));
}

static void check_round_trip(const char *name, const mf_table *t, mf_table_format fmt)
{
    char path[512], msg[512];
    write_ok(name, t, NULL, NULL, path, sizeof path);
    mf_table back;
    mf_table_file_info info;
    mf_status st = mf_table_read(path, &back, &info, msg, sizeof msg);
    if (st != MF_OK)
        fprintf(stderr, "read %s: %s\n", name, msg);
    CHECK(st == MF_OK);
    if (st != MF_OK)
        return;
    CHECK(info.format == fmt && info.has_metadata && !info.half_float && !info.has_half_error);
    CHECK(mf_test_same_metadata(t, &back));
    CHECK(same_float_data(t, &back));
    mf_table_free(&back);
}

static void test_round_trips(void)
{
    mf_table t;
    make_table(&t, 64, 64, 1);
    check_round_trip("t.exr", &t, MF_TABLE_FORMAT_EXR);
    check_round_trip("t.json", &t, MF_TABLE_FORMAT_JSON);
    check_round_trip("t.npy", &t, MF_TABLE_FORMAT_NPY);
    char path[512];
    path_in_dir(path, sizeof path, "t.npy.json");
    CHECK(mf_test_file_exists(path));
    CHECK(mf_test_count_temporaries(dir) == 0);

    /* special values in JSON: NaN as null (reads back as a NaN), infinities as 1e999, -0 kept */
    mf_table s;
    make_table(&s, 3, 2, 0);
    s.data[0] = NAN;
    s.data[1] = INFINITY;
    s.data[2] = -INFINITY;
    s.data[3] = -0.0;
    s.data[4] = 1e-45;
    char msg[512];
    const char *names[3] = {"s.json", "s.exr", "s.npy"};
    for (int k = 0; k < 3; ++k) {
        write_ok(names[k], &s, NULL, NULL, path, sizeof path);
        mf_table b;
        CHECK(mf_table_read(path, &b, NULL, msg, sizeof msg) == MF_OK);
        if (b.data) {
            CHECK(isnan(b.data[0]) && b.data[1] == INFINITY && b.data[2] == -INFINITY);
            CHECK(b.data[3] == 0.0 && signbit(b.data[3]));
            CHECK(b.data[4] == (double)1e-45f);
            int rest = 1;
            for (int i = 5; i < 30; ++i)
                rest = rest && mf_test_float_bits((float)b.data[i]) == mf_test_float_bits((float)s.data[i]);
            CHECK(rest);
        }
        mf_table_free(&b);
    }
    /* 1D and 4D tables through JSON, NPY and EXR (1D: height 1) */
    mf_table_axis ax[4];
    memset(ax, 0, sizeof ax);
    for (int k = 0; k < 4; ++k) {
        snprintf(ax[k].name, sizeof ax[k].name, "p%d", k);
        snprintf(ax[k].physical, sizeof ax[k].physical, "theta%d", k);
        ax[k].size = k + 2;
        ax[k].lo = 0.0;
        ax[k].hi = 1.5;
        ax[k].mapping = MF_AXIS_COS;
        ax[k].physical_min = -INFINITY;
    }
    const char *one[1] = {"v"};
    for (int naxes = 1; naxes <= 4; naxes += 3) {
        mf_table m;
        CHECK(mf_table_create(&m, naxes, ax, 1, one) == MF_OK);
        for (size_t i = 0; i < mf_table_texels(&m); ++i)
            m.data[i] = 1.0 / (1.0 + (double)i);
        check_round_trip(naxes == 1 ? "m1.json" : "m4.json", &m, MF_TABLE_FORMAT_JSON);
        check_round_trip(naxes == 1 ? "m1.npy" : "m4.npy", &m, MF_TABLE_FORMAT_NPY);
        /* EXR stores a 4-axis table as its 2D atlas (more in test_table_nd.c) */
        check_round_trip(naxes == 1 ? "m1.exr" : "m4.exr", &m, MF_TABLE_FORMAT_EXR);
        mf_table_free(&m);
    }
    mf_table_free(&s);
    mf_table_free(&t);
}

/* ---- half-float EXR ------------------------------------------------------------------------- */

static void test_exr_half(void)
{
    mf_table t;
    make_table(&t, 64, 64, 0);
    char path[512], msg[512];
    mf_table_write_options o;
    mf_table_write_options_default(&o);
    o.half_float = 1;
    mf_half_error he;
    write_ok("h.exr", &t, &o, &he, path, sizeof path);
    mf_half_error ref;
    mf_half_error_of(t.data, mf_table_texels(&t) * 5, &ref);
    CHECK(memcmp(&he, &ref, sizeof he) == 0);
    CHECK(he.count == 64 * 64 * 5 && he.overflow_count == 0 && he.underflow_count == 0);
    printf("half-float error of the realistic 64 x 64 x 5 table: max abs %.3g, max rel %.3g (field %s, texel %zu), "
           "%zu half subnormals\n",
           he.max_abs_error, he.max_rel_error, k_fields[he.worst_rel_index % 5], he.worst_rel_index / 5,
           he.subnormal_count);
    /* per field */
    for (int f = 0; f < 5; ++f) {
        double *col = malloc(sizeof(double) * 64 * 64);
        if (!col)
            continue;
        for (int i = 0; i < 64 * 64; ++i)
            col[i] = t.data[i * 5 + f];
        mf_half_error fe;
        mf_half_error_of(col, 64 * 64, &fe);
        printf("  %-10s max abs %.3g, max rel %.3g\n", k_fields[f], fe.max_abs_error, fe.max_rel_error);
        free(col);
    }
    /* with round to nearest, the relative error in half's normal range is <= 2^-11 */
    CHECK(he.subnormal_count > 0 || he.max_rel_error <= ldexp(1.0, -11));

    mf_table back;
    mf_table_file_info info;
    CHECK(mf_table_read(path, &back, &info, msg, sizeof msg) == MF_OK);
    CHECK(info.half_float && info.has_metadata && info.has_half_error);
    CHECK(info.half_error.max_abs_error == he.max_abs_error && info.half_error.max_rel_error == he.max_rel_error);
    CHECK(mf_test_same_metadata(&t, &back));
    int exact = 1, changed = 0;
    if (back.data)
        for (size_t i = 0; i < 64 * 64 * 5; ++i) {
            if (memcmp(&back.data[i], &(double){half_round(t.data[i])}, sizeof(double)) != 0)
                exact = 0;
            if (back.data[i] != (double)(float)t.data[i])
                changed = 1;
        }
    CHECK(exact && changed);
    mf_table_free(&back);

    /* extremes: overflow and underflow are counted and reported as such */
    mf_table x;
    make_table(&x, 8, 4, 1);
    write_ok("hx.exr", &x, &o, &he, path, sizeof path);
    CHECK(he.overflow_count == 2 && he.underflow_count >= 2 && isinf(he.max_abs_error));
    CHECK(mf_table_read(path, &back, &info, msg, sizeof msg) == MF_OK);
    CHECK(info.has_half_error && isinf(info.half_error.max_abs_error) && info.half_error.overflow_count == 2);
    if (back.data) {
        CHECK(back.data[1] == -INFINITY && back.data[4] == INFINITY && back.data[0] == 0.0);
        CHECK(back.data[6] == -65504.0);
    }
    mf_table_free(&back);
    mf_table_free(&x);

    /* half in a format without halves */
    path_in_dir(path, sizeof path, "h.json");
    CHECK(mf_table_write(path, &t, &o, &he, msg, sizeof msg) == MF_ERR_UNSUPPORTED);
    CHECK(!mf_test_file_exists(path) && strncmp(msg, path, strlen(path)) == 0);
    mf_table_free(&t);
}

/* ---- DDS ------------------------------------------------------------------------------------- */

/* numpy parses the DDS bytes itself (header words, pixels at offset 148) and compares with the
 * float32 values we expect in the file. */
static void numpy_check_dds(const char *dds, const float *expect, size_t n, int half, int w, int h)
{
    if (!numpy_available())
        return;
    char raw[512], py[512], cmd[2048];
    path_in_dir(raw, sizeof raw, "dds_expect.f32");
    path_in_dir(py, sizeof py, "check_dds.py");
    CHECK(mf_test_write_file(raw, expect, n * sizeof(float)) == 0);
    const char *script =
        "import sys, numpy as np\n"
        "b = open(sys.argv[1], 'rb').read()\n"
        "assert b[:4] == b'DDS ', b[:4]\n"
        "h = np.frombuffer(b, dtype='<u4', count=37)\n"
        "assert h[1] == 124 and h[19] == 32 and b[84:88] == b'DX10'\n"
        "fmt, dim, arr = int(h[32]), int(h[33]), int(h[35])\n"
        "half, w, hgt = int(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])\n"
        "assert fmt == (10 if half else 2) and dim == 3 and arr == 1, (fmt, dim, arr)\n"
        "assert int(h[3]) == hgt and int(h[4]) == w\n"
        "px = np.frombuffer(b, dtype='<f2' if half else '<f4', offset=148)\n"
        "assert px.size == hgt * w * 4, px.size\n"
        "px = px.astype(np.float32).reshape(hgt, w, 4)\n"
        "exp = np.fromfile(sys.argv[2], dtype='<f4').reshape(hgt, w, 4)\n"
        "assert np.array_equal(px.view(np.uint32), exp.view(np.uint32))\n";
    CHECK(mf_test_write_file(py, script, strlen(script)) == 0);
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s %s %d %d %d", py, dds, raw, half, w, h);
    CHECK(run(cmd) == 0);
}

static void test_dds(void)
{
    mf_table t;
    make_table(&t, 16, 8, 1);
    char path[512], msg[512];
    for (int half = 0; half <= 1; ++half)
        for (int custom = 0; custom <= 1; ++custom) {
            mf_table_write_options o;
            mf_table_write_options_default(&o);
            o.half_float = half;
            int ch[4] = {0, 1, 2, 3};
            if (custom) {
                int c[4] = {4, 0, -1, 2}; /* e_comp, scale, zeros, g1 */
                memcpy(ch, c, sizeof ch);
                memcpy(o.dds_fields, c, sizeof c);
                o.dds_fields_set = 1;
            }
            char name[64];
            snprintf(name, sizeof name, "t%s%s.dds", half ? "16" : "32", custom ? "c" : "");
            mf_half_error he;
            write_ok(name, &t, &o, &he, path, sizeof path);
            CHECK(mf_test_file_size(path) == 148 + 16 * 8 * (half ? 8 : 16));
            if (half) {
                CHECK(he.count == 16 * 8 * (size_t)(custom ? 3 : 4));
                CHECK(he.overflow_count == (custom ? 1u : 1u)); /* -1e30 (scale) in both */
            }
            /* (a) our reader */
            mf_table back;
            mf_table_file_info info;
            mf_status st = mf_table_read(path, &back, &info, msg, sizeof msg);
            CHECK(st == MF_OK);
            float *expect = malloc(sizeof(float) * 16 * 8 * 4);
            if (st == MF_OK && expect) {
                CHECK(info.has_metadata && info.half_float == half && info.format == MF_TABLE_FORMAT_DDS);
                CHECK(back.nfields == 4 && back.naxes == 2 && back.axes[0].size == 16 && back.axes[1].size == 8);
                CHECK(memcmp(info.dds_fields, ch, sizeof ch) == 0);
                CHECK(strcmp(back.fields[0], ch[0] < 0 ? "zero0" : k_fields[ch[0]]) == 0);
                CHECK(!custom || strcmp(back.fields[2], "zero2") == 0);
                CHECK(back.nmeta == t.nmeta && strcmp(back.meta[1].value, t.meta[1].value) == 0);
                int ok = 1;
                for (size_t i = 0; i < 16 * 8; ++i)
                    for (int c = 0; c < 4; ++c) {
                        double v = ch[c] < 0 ? 0.0 : t.data[i * 5 + (size_t)ch[c]];
                        double e = half ? half_round(v) : (double)(float)v;
                        expect[i * 4 + (size_t)c] = (float)e;
                        if (memcmp(&e, &back.data[i * 4 + (size_t)c], sizeof e) != 0)
                            ok = 0;
                    }
                CHECK(ok);
                /* (b) numpy, independently */
                numpy_check_dds(path, expect, 16 * 8 * 4, half, 16, 8);
            }
            free(expect);
            mf_table_free(&back);
            /* (c) OpenImageIO 2.4 refuses uncompressed float DDS: an error, not a crash */
            mf_image img;
            st = mf_image_read(path, &img, msg, sizeof msg);
            CHECK(st == MF_ERR_FORMAT);
            CHECK(strncmp(msg, path, strlen(path)) == 0);
            if (st == MF_OK) {
                printf("note: this OpenImageIO reads float DDS now (%d x %d x %d)\n", img.width, img.height,
                       img.channels);
                mf_image_free(&img);
            }
        }
    /* without the sidecar: generic axes, channels R, G, B, A */
    path_in_dir(path, sizeof path, "t32.dds.json");
    CHECK(remove(path) == 0);
    path_in_dir(path, sizeof path, "t32.dds");
    mf_table back;
    mf_table_file_info info;
    CHECK(mf_table_read(path, &back, &info, msg, sizeof msg) == MF_OK);
    CHECK(!info.has_metadata && back.nfields == 4 && strcmp(back.fields[3], "A") == 0);
    CHECK(back.naxes == 2 && back.axes[0].lo == 0.5 / 16 && back.axes[1].hi == 1.0 - 0.5 / 8);
    if (back.data)
        CHECK(back.data[4] == (double)(float)t.data[5]); /* texel 1, channel R = field 0 */
    mf_table_free(&back);
    /* bad channel choices */
    mf_table_write_options o;
    mf_table_write_options_default(&o);
    o.dds_fields_set = 1;
    int bad[2][4] = {{0, 1, 5, -1}, {0, 1, 1, -1}};
    for (int k = 0; k < 2; ++k) {
        memcpy(o.dds_fields, bad[k], sizeof bad[k]);
        path_in_dir(path, sizeof path, "bad.dds");
        CHECK(mf_table_write(path, &t, &o, NULL, msg, sizeof msg) == MF_ERR_DOMAIN);
        CHECK(!mf_test_file_exists(path));
    }
    mf_table_free(&t);
}

/* ---- NPY through numpy, JSON through Python's json -------------------------------------------- */

static void test_numpy(void)
{
    if (!numpy_available())
        return;
    mf_table t;
    make_table(&t, 64, 32, 1);
    char path[512], raw[512], py[512], cmd[4096];
    write_ok("np.npy", &t, NULL, NULL, path, sizeof path);
    size_t n = mf_table_texels(&t) * 5;
    float *f = malloc(n * sizeof *f);
    CHECK(f != NULL);
    if (!f)
        return;
    for (size_t i = 0; i < n; ++i)
        f[i] = (float)t.data[i];
    path_in_dir(raw, sizeof raw, "np_expect.f32");
    CHECK(mf_test_write_file(raw, f, n * sizeof *f) == 0);
    path_in_dir(py, sizeof py, "check_npy.py");
    /* a[i1, i0, f] is field f of texel (i0, i1): spot values checked against the formula's float */
    int idx[2] = {17, 9};
    const double *rec = mf_table_record(&t, idx);
    char script[2048];
    snprintf(script, sizeof script,
             "import sys, json, numpy as np\n"
             "a = np.load(sys.argv[1], allow_pickle=False)\n"
             "assert a.dtype == np.float32 and a.shape == (32, 64, 5), (a.dtype, a.shape)\n"
             "e = np.fromfile(sys.argv[2], dtype='<f4').reshape(32, 64, 5)\n"
             "assert np.array_equal(a.view(np.uint32), e.view(np.uint32))\n"
             "assert a[9, 17, 0] == np.float32(%.17g) and a[9, 17, 4] == np.float32(%.17g)\n"
             "assert a[0, 0, 1] == np.float32(-1e30)\n"
             "m = json.load(open(sys.argv[1] + '.json'))\n"
             "assert [x['size'] for x in m['axes']] == [64, 32] and m['fields'][4] == 'e_comp'\n"
             "assert m['axes'][1]['physical_min'] == 1e-4 and m['axes'][0]['physical_min'] is None\n"
             "j = json.load(open(sys.argv[3]))\n"
             "assert len(j['data']) == 64 * 32 and j['header']['meta']['samples'] == '4096'\n"
             "assert np.array_equal(np.array(j['data'], dtype=np.float32).reshape(32, 64, 5).view(np.uint32),"
             " e.view(np.uint32))\n",
             rec[0], rec[4]);
    CHECK(mf_test_write_file(py, script, strlen(script)) == 0);
    char jpath[512];
    write_ok("np.json", &t, NULL, NULL, jpath, sizeof jpath);
    snprintf(cmd, sizeof cmd, "/usr/bin/python3 %s %s %s %s", py, path, raw, jpath);
    CHECK(run(cmd) == 0);
    free(f);
    mf_table_free(&t);
}

/* ---- C header, GLSL, HLSL, CSV ---------------------------------------------------------------- */

static void test_c_header(void)
{
    mf_table t;
    make_table(&t, 64, 64, 1);
    char path[512], src[512], obj[512], bin[512], out[512], cmd[4096];
    write_ok("lut_ggx.h", &t, NULL, NULL, path, sizeof path);
    int have_cc = mf_test_have_tool("cc"), have_cxx = mf_test_have_tool("c++");
    if (!have_cc && !have_cxx) {
        printf("note: no cc or c++: the C header is not compiled\n");
        mf_table_free(&t);
        return;
    }
    /* a program that uses every declaration and dumps the array */
    const char *prog =
        "#include <stdio.h>\n"
        "#include \"lut_ggx.h\"\n"
        "int main(int argc, char **argv)\n"
        "{\n"
        "    FILE *f = argc > 1 ? fopen(argv[1], \"wb\") : NULL;\n"
        "    if (!f) return 1;\n"
        "    int ok = fwrite(lut_ggx_data, sizeof lut_ggx_data, 1, f) == 1;\n"
        "    ok = ok && sizeof lut_ggx_data == sizeof(float) * LUT_GGX_NTEXELS * LUT_GGX_NFIELDS;\n"
        "    ok = ok && lut_ggx_sizes[0] == LUT_GGX_SIZE_0 && LUT_GGX_FIELD_e_comp == 4 && LUT_GGX_NAXES == 2;\n"
        "    ok = ok && lut_ggx_axis_lo[1] == 0.0 && lut_ggx_axis_hi[1] == 1.0;\n"
        "    return (fclose(f) == 0 && ok) ? 0 : 1;\n"
        "}\n";
    for (int cxx = 0; cxx <= 1; ++cxx) {
        if (cxx ? !have_cxx : !have_cc)
            continue;
        snprintf(src, sizeof src, "%s/use_lut.%s", dir, cxx ? "cpp" : "c");
        snprintf(obj, sizeof obj, "%s/use_lut_%d.o", dir, cxx);
        snprintf(bin, sizeof bin, "%s/use_lut_%d", dir, cxx);
        snprintf(out, sizeof out, "%s/lut_dump_%d.f32", dir, cxx);
        CHECK(mf_test_write_file(src, prog, strlen(prog)) == 0);
        snprintf(cmd, sizeof cmd, "%s -Wall -Wextra -pedantic -Werror -I%s -c %s -o %s", cxx ? "c++ -std=c++17" : "cc -std=c11",
                 dir, src, obj);
        int rc = run(cmd);
        if (rc != 0)
            fprintf(stderr, "failed: %s\n", cmd);
        CHECK(rc == 0);
        snprintf(cmd, sizeof cmd, "%s %s -o %s && %s %s", cxx ? "c++" : "cc", obj, bin, bin, out);
        CHECK(run(cmd) == 0);
        long len;
        unsigned char *dump = mf_test_read_file(out, &len);
        CHECK(dump != NULL && len == (long)(mf_table_texels(&t) * 5 * sizeof(float)));
        if (dump && len == (long)(mf_table_texels(&t) * 5 * sizeof(float))) {
            int same = 1;
            for (size_t i = 0; i < mf_table_texels(&t) * 5; ++i) {
                float f;
                memcpy(&f, dump + 4 * i, 4);
                if (mf_test_float_bits(f) != mf_test_float_bits((float)t.data[i]))
                    same = 0;
            }
            CHECK(same); /* the %.9g literals give back every float bit for bit */
        }
        free(dump);
    }
    /* non-finite values need <math.h>: still compiles cleanly */
    t.data[10] = NAN;
    t.data[11] = -INFINITY;
    write_ok("lut_nf.h", &t, NULL, NULL, path, sizeof path);
    const char *prog2 = "#include \"lut_nf.h\"\nint lut_first_is_nan(void);\n"
                        "int lut_first_is_nan(void) { return lut_nf_data[10] != lut_nf_data[10] && lut_nf_data[11] < 0; }\n";
    snprintf(src, sizeof src, "%s/use_nf.c", dir);
    CHECK(mf_test_write_file(src, prog2, strlen(prog2)) == 0);
    if (have_cc) {
        snprintf(cmd, sizeof cmd, "cc -std=c11 -Wall -Wextra -pedantic -Werror -I%s -c %s -o %s/use_nf.o", dir, src, dir);
        CHECK(run(cmd) == 0);
    }
    if (have_cxx) {
        snprintf(cmd, sizeof cmd, "c++ -std=c++17 -x c++ -Wall -Wextra -pedantic -Werror -I%s -c %s -o %s/use_nf_cxx.o",
                 dir, src, dir);
        CHECK(run(cmd) == 0);
    }
    /* a bad prefix */
    mf_table_write_options o;
    mf_table_write_options_default(&o);
    o.prefix = "9bad";
    char msg[512];
    path_in_dir(path, sizeof path, "bad_prefix.h");
    CHECK(mf_table_write(path, &t, &o, NULL, msg, sizeof msg) == MF_ERR_DOMAIN && !mf_test_file_exists(path));
    o.prefix = "my_lut";
    write_ok("named.h", &t, &o, NULL, path, sizeof path);
    long len;
    char *text = (char *)mf_test_read_file(path, &len);
    if (text) {
        text[len] = '\0';
        CHECK(strstr(text, "static const float my_lut_data[20480] = {") != NULL);
    }
    free(text);
    mf_table_free(&t);
}

/* Brackets balance, no C float suffixes, every float literal has a point or exponent. */
static int shader_sane(const char *s)
{
    int paren = 0, brace = 0, ok = 1;
    int in_comment = 0;
    for (const char *p = s; *p; ++p) {
        if (p[0] == '/' && p[1] == '/')
            in_comment = 1;
        if (*p == '\n')
            in_comment = 0;
        if (in_comment)
            continue;
        paren += (*p == '(') - (*p == ')');
        brace += (*p == '{') - (*p == '}');
        if (paren < 0 || brace < 0)
            ok = 0;
        /* a number token right after an operator or '(' inside an expression */
        if ((*p >= '0' && *p <= '9') && p > s && !(p[-1] == '_' || (p[-1] >= 'a' && p[-1] <= 'z') ||
                                                    (p[-1] >= 'A' && p[-1] <= 'Z') || (p[-1] >= '0' && p[-1] <= '9') ||
                                                    p[-1] == '.')) {
            const char *q = p;
            while ((*q >= '0' && *q <= '9') || *q == '.' || *q == 'e' || *q == 'E' ||
                   ((*q == '-' || *q == '+') && (q[-1] == 'e' || q[-1] == 'E')))
                ++q;
            if (*q == 'f' || *q == 'F')
                ok = 0; /* C suffix */
        }
    }
    return ok && paren == 0 && brace == 0;
}

static void test_shaders(void)
{
    mf_table t;
    make_table(&t, 32, 16, 0);
    char glsl[512], hlsl[512], path[512], cmd[4096];
    write_ok("lut.glsl", &t, NULL, NULL, glsl, sizeof glsl);
    write_ok("lut.hlsl", &t, NULL, NULL, hlsl, sizeof hlsl);
    long len;
    char *g = (char *)mf_test_read_file(glsl, &len);
    if (g) {
        g[len] = '\0';
        CHECK(shader_sane(g));
        CHECK(strstr(g, "vec4 lut_lookup(sampler2D table, float cos_theta_o, float alpha)") != NULL);
        CHECK(strstr(g, "return sqrt(max(1.0 - cos_theta_o, 0.0));") != NULL);
        CHECK(strstr(g, "alpha = max(alpha, 0.0001);") != NULL);
        CHECK(strstr(g, "return (u - (0.0)) / (1.0) * 31.0 / 32.0 + 0.5 / 32.0;") != NULL);
        CHECK(strstr(g, "\"physical_min\": 0.0001") != NULL);
    }
    char *h = (char *)mf_test_read_file(hlsl, &len);
    if (h) {
        h[len] = '\0';
        CHECK(shader_sane(h));
        CHECK(strstr(h, "float4 lut_lookup(Texture2D<float4> table, SamplerState samp, float cos_theta_o, float alpha)") !=
              NULL);
        CHECK(strstr(h, "table.SampleLevel(samp, uv, 0.0)") != NULL);
    }
    if (mf_test_have_tool("glslangValidator")) {
        /* GLSL 3.30 fragment shader and an HLSL pixel shader around the snippets */
        path_in_dir(path, sizeof path, "use_lut.frag");
        char *src = malloc((size_t)len + 4096 + (g ? strlen(g) : 0));
        if (src && g && h) {
            snprintf(src, (size_t)len + 4096 + strlen(g),
                     "#version 330\n%s\nuniform sampler2D tab;\nin vec2 x;\nout vec4 color;\n"
                     "void main() { color = lut_lookup(tab, x.x, x.y) + vec4(lut_uv(x.y, x.x), 0.0, 0.0); }\n",
                     g);
            CHECK(mf_test_write_file(path, src, strlen(src)) == 0);
            snprintf(cmd, sizeof cmd, "glslangValidator %s >%s/glslang.log 2>&1 || cat %s/glslang.log", path, dir, dir);
            CHECK(run(cmd) == 0);
            path_in_dir(path, sizeof path, "use_lut.hlsl");
            snprintf(src, (size_t)len + 4096 + strlen(g),
                     "%s\nTexture2D<float4> tab : register(t0);\nSamplerState smp : register(s0);\n"
                     "float4 main(float2 x : TEXCOORD0) : SV_Target { return lut_lookup(tab, smp, x.x, x.y); }\n",
                     h);
            CHECK(mf_test_write_file(path, src, strlen(src)) == 0);
            snprintf(cmd, sizeof cmd,
                     "glslangValidator -V -D -e main -S frag -o %s/hlsl.spv %s >%s/glslang.log 2>&1 || cat %s/glslang.log",
                     dir, path, dir, dir);
            CHECK(run(cmd) == 0);
        }
        free(src);
    } else {
        printf("note: glslangValidator not found (apt-get install glslang-tools): shaders only sanity-checked\n");
    }
    free(g);
    free(h);
    mf_table_free(&t);
}

static void test_csv(void)
{
    mf_table t;
    make_table(&t, 4, 3, 1);
    char path[512];
    write_ok("t.csv", &t, NULL, NULL, path, sizeof path);
    long len;
    char *s = (char *)mf_test_read_file(path, &len);
    if (s) {
        s[len] = '\0';
        const char *head = "i0,i1,u,r,cos_theta_o,alpha,scale,bias,g1,dscale_dr,e_comp\n";
        CHECK(strncmp(s, head, strlen(head)) == 0);
        int lines = 0;
        for (char *p = s; *p; ++p)
            lines += (*p == '\n');
        CHECK(lines == 1 + 12);
        /* first row: texel (0, 0), u = 0 -> cos 1, r = 0 -> alpha clamped to 1e-4 */
        CHECK(strstr(s, "\n0,0,0,0,1,0.0001,1e-30,-1.00000002e+30,-0,1.40129846e-45,3.40282347e+38\n") != NULL);
        CHECK(strstr(s, "\n1,0,0.33333333333333331,0,") != NULL);
    }
    free(s);
    mf_table_free(&t);
}

/* ---- corrupt inputs ------------------------------------------------------------------------- */

/* Reading path must not crash; a failure must name the file on one line and leave a zeroed table. */
static mf_status read_checked(const char *path)
{
    char msg[512];
    memset(msg, 'x', sizeof msg);
    mf_table t;
    mf_status st = mf_table_read(path, &t, NULL, msg, sizeof msg);
    if (st != MF_OK) {
        CHECK(t.data == NULL && t.naxes == 0);
        CHECK(memchr(msg, '\0', sizeof msg) != NULL);
        int named = strncmp(msg, path, strlen(path)) == 0 && strlen(msg) > strlen(path) + 2 && !strchr(msg, '\n');
        if (!named)
            fprintf(stderr, "bad message: %s\n", msg);
        CHECK(named);
    } else {
        CHECK(t.data != NULL && t.naxes >= 1 && t.nfields >= 1);
        mf_table_free(&t);
    }
    return st;
}

static void fuzz_file(const char *name, int every_offset, int flips, uint64_t seed)
{
    char path[512], bad[512];
    path_in_dir(path, sizeof path, name);
    long len;
    unsigned char *orig = mf_test_read_file(path, &len);
    CHECK(orig != NULL && len > 0);
    if (!orig)
        return;
    /* bad files keep the extension so that the same reader runs; sidecars are not copied, except
     * for the .npy/.dds whose sidecar is part of the check */
    const char *ext = strrchr(name, '.');
    snprintf(bad, sizeof bad, "%s/fuzz%s", dir, ext);
    int truncations_ok = 0, trunc_fail = 0;
    long step = every_offset ? 1 : (len / 997 + 1);
    for (long cut = 0; cut < len; cut += step) {
        CHECK(mf_test_write_file(bad, orig, (size_t)cut) == 0);
        mf_status st = read_checked(bad);
        if (st == MF_OK) {
            /* only whitespace may have been cut */
            int ws = 1;
            for (long i = cut; i < len; ++i)
                if (!(orig[i] == ' ' || orig[i] == '\n'))
                    ws = 0;
            if (!ws)
                fprintf(stderr, "%s truncated to %ld of %ld bytes reads OK\n", name, cut, len);
            CHECK(ws);
            ++truncations_ok;
        } else {
            ++trunc_fail;
        }
    }
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, mf_test_seed(seed), 7);
    unsigned char *copy = malloc((size_t)len);
    int flip_fail = 0;
    for (int k = 0; k < flips && copy; ++k) {
        memcpy(copy, orig, (size_t)len);
        int nbits = 1 + (int)(mf_pcg32_next_u32(&rng) % 4);
        /* half of the trials aim at the first 512 bytes (headers), half anywhere */
        for (int b = 0; b < nbits; ++b) {
            uint32_t r = mf_pcg32_next_u32(&rng);
            size_t at = (k & 1) ? r % (uint32_t)len : r % (uint32_t)(len < 512 ? len : 512);
            copy[at] ^= (unsigned char)(1u << (mf_pcg32_next_u32(&rng) % 8));
        }
        CHECK(mf_test_write_file(bad, copy, (size_t)len) == 0);
        flip_fail += read_checked(bad) != MF_OK;
    }
    printf("fuzz %-10s %6ld bytes: %d truncations failed cleanly (%d whitespace-only OK), %d of %d bit-flipped "
           "files refused, none crashed\n",
           name, len, trunc_fail, truncations_ok, flip_fail, flips);
    free(copy);
    free(orig);
    remove(bad);
}

static void test_corrupt_inputs(void)
{
    mf_table t;
    make_table(&t, 6, 4, 1);
    char path[512], msg[512];
    const char *names[5] = {"c.json", "c.npy", "c.exr", "c32.dds", "c16.exr"};
    for (int k = 0; k < 5; ++k) {
        mf_table_write_options o;
        mf_table_write_options_default(&o);
        o.half_float = (k == 4);
        write_ok(names[k], &t, &o, NULL, path, sizeof path);
    }
    mf_table_free(&t);
    fuzz_file("c.json", 1, 2000, 11);
    fuzz_file("c.npy", 1, 1000, 12);
    fuzz_file("c32.dds", 1, 1000, 13);
    fuzz_file("c.exr", 1, 1000, 14);
    fuzz_file("c16.exr", 0, 300, 15);
    /* the sidecars of NPY and DDS: truncated and flipped metadata */
    fuzz_file("c.npy.json", 1, 1000, 16);
    path_in_dir(path, sizeof path, "c.npy.json");
    long len;
    unsigned char *side = mf_test_read_file(path, &len);
    CHECK(side != NULL);
    if (side) {
        char npy[512];
        path_in_dir(npy, sizeof npy, "c.npy");
        mf_pcg32 rng;
        mf_pcg32_seed(&rng, mf_test_seed(17), 3);
        int refused = 0;
        for (long cut = 0; cut < len; ++cut) {
            CHECK(mf_test_write_file(path, side, (size_t)cut) == 0);
            refused += read_checked(npy) != MF_OK;
        }
        CHECK(refused >= len - 2); /* all but cuts of the trailing newline */
        for (int k = 0; k < 500; ++k) {
            unsigned char *c = malloc((size_t)len);
            if (!c)
                break;
            memcpy(c, side, (size_t)len);
            c[mf_pcg32_next_u32(&rng) % (uint32_t)len] ^= (unsigned char)(1u << (k % 8));
            CHECK(mf_test_write_file(path, c, (size_t)len) == 0);
            (void)read_checked(npy);
            free(c);
        }
        CHECK(mf_test_write_file(path, side, (size_t)len) == 0);
        CHECK(read_checked(npy) == MF_OK);
        free(side);
    }
    /* garbage the JSON parser must refuse: deep nesting, bad escapes, huge numbers, NUL bytes */
    const char *garbage[] = {
        "", " ", "{", "[", "{\"header\": 1, \"data\": []}", "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[]]]",
        "{\"a\": \"\\ud800\"}", "{\"a\": \"\\u0000\"}", "{\"a\": \"\\x\"}", "{\"a\": 1e99999999999999999999}",
        "{\"a\": -}", "{\"a\": 01}", "{\"a\": 1.}", "{\"a\": tru}", "{\"a\" 1}", "{\"a\": 1,}", "[1,]", "{} {}",
        "{\"header\": {\"format\": \"mfkit-table\", \"version\": 1, \"axes\": [{\"name\": \"u\", \"physical\": \"x\", "
        "\"size\": 1048576, \"lo\": 0, \"hi\": 1, \"mapping\": \"identity\"}, {\"name\": \"v\", \"physical\": \"y\", "
        "\"size\": 1048576, \"lo\": 0, \"hi\": 1, \"mapping\": \"identity\"}], \"fields\": [\"a\"]}, \"data\": []}",
    };
    path_in_dir(path, sizeof path, "garbage.json");
    for (size_t k = 0; k < sizeof garbage / sizeof *garbage; ++k) {
        CHECK(mf_test_write_file(path, garbage[k], strlen(garbage[k])) == 0);
        CHECK(read_checked(path) == MF_ERR_FORMAT);
    }
    CHECK(mf_test_write_file(path, "{\"a\":\0 1}", 9) == 0);
    CHECK(read_checked(path) == MF_ERR_FORMAT);
    /* a .npy header announcing a huge array backed by no data */
    const char *dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (1048576, 4096, 32), }\n";
    char huge[256];
    memcpy(huge, "\x93NUMPY\x01\x00", 8);
    huge[8] = (char)strlen(dict);
    huge[9] = 0;
    memcpy(huge + 10, dict, strlen(dict));
    path_in_dir(path, sizeof path, "huge.npy");
    CHECK(mf_test_write_file(path, huge, 10 + strlen(dict)) == 0);
    CHECK(read_checked(path) == MF_ERR_FORMAT);
    /* missing files and write-only formats */
    path_in_dir(path, sizeof path, "missing.json");
    memset(&t, 0xff, sizeof t); /* stale contents are overwritten, never freed */
    CHECK(mf_table_read(path, &t, NULL, msg, sizeof msg) == MF_ERR_IO && strncmp(msg, path, strlen(path)) == 0);
    CHECK(t.data == NULL);
    path_in_dir(path, sizeof path, "t.csv");
    CHECK(mf_table_read(path, &t, NULL, msg, sizeof msg) == MF_ERR_UNSUPPORTED);
    CHECK(mf_table_read(NULL, &t, NULL, msg, sizeof msg) == MF_ERR_DOMAIN);
}

/* ---- atomic writes ---------------------------------------------------------------------------- */

static void test_write_errors(void)
{
    mf_table t;
    make_table(&t, 8, 4, 0);
    const char *exts[8] = {"exr", "dds", "h", "glsl", "hlsl", "json", "npy", "csv"};
    char path[512], msg[512], sub[512];
    path_in_dir(sub, sizeof sub, "no_such_dir");
    for (int k = 0; k < 8; ++k) {
        char name[64];
        snprintf(name, sizeof name, "no_such_dir/out.%s", exts[k]);
        path_in_dir(path, sizeof path, name);
        memset(msg, 'x', sizeof msg);
        mf_status st = mf_table_write(path, &t, NULL, NULL, msg, sizeof msg);
        CHECK(st == MF_ERR_IO);
        CHECK(memchr(msg, '\0', sizeof msg) && strncmp(msg, path, strlen(path)) == 0 && !strchr(msg, '\n'));
        CHECK(!mf_test_file_exists(path) && !mf_test_file_exists(sub));
    }
    /* unknown extension; invalid arguments */
    path_in_dir(path, sizeof path, "out.xyz");
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_ERR_UNSUPPORTED && !mf_test_file_exists(path));
    CHECK(mf_table_write(NULL, &t, NULL, NULL, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_table_write(path, NULL, NULL, NULL, msg, sizeof msg) == MF_ERR_DOMAIN);
    /* a failed write leaves an existing file as it was */
    write_ok("keep.json", &t, NULL, NULL, path, sizeof path);
    long before = mf_test_file_size(path);
    mf_table_write_options o;
    mf_table_write_options_default(&o);
    o.half_float = 1;
    CHECK(mf_table_write(path, &t, &o, NULL, msg, sizeof msg) == MF_ERR_UNSUPPORTED);
    CHECK(mf_test_file_size(path) == before);
    /* a read-only directory (skipped as root, who may write anyway) */
    if (geteuid() != 0) {
        char ro[512];
        path_in_dir(ro, sizeof ro, "ro");
        CHECK(mkdir(ro, 0555) == 0);
        path_in_dir(path, sizeof path, "ro/out.npy");
        CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_ERR_IO && !mf_test_file_exists(path));
        rmdir(ro);
    }
    CHECK(mf_test_count_temporaries(dir) == 0);
    mf_table_free(&t);
}

static void test_formats(void)
{
    CHECK(mf_table_format_from_path("a/b.EXR") == MF_TABLE_FORMAT_EXR);
    CHECK(mf_table_format_from_path("x.h") == MF_TABLE_FORMAT_C_HEADER);
    CHECK(mf_table_format_from_path("x.npy.json") == MF_TABLE_FORMAT_JSON);
    CHECK(mf_table_format_from_path("dir.d/noext") == MF_TABLE_FORMAT_UNKNOWN);
    CHECK(mf_table_format_from_path(".json") == MF_TABLE_FORMAT_UNKNOWN);
    CHECK(strcmp(mf_table_format_name(MF_TABLE_FORMAT_HLSL), "hlsl") == 0);
    CHECK(mf_table_format_readable(MF_TABLE_FORMAT_DDS) && !mf_table_format_readable(MF_TABLE_FORMAT_CSV));
}

int main(int argc, char **argv)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    if (argc == 3 && strcmp(argv[1], "--write-sample") == 0) {
        mf_table t;
        make_table(&t, 16, 8, 0);
        char msg[512];
        mf_status st = mf_table_write(argv[2], &t, NULL, NULL, msg, sizeof msg);
        if (st != MF_OK)
            fprintf(stderr, "%s\n", msg);
        mf_table_free(&t);
        return st == MF_OK ? 0 : 1;
    }
    mf_test_seed(1);
    if (mkdtemp(dir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    test_formats();
    test_half_conversion();
    test_half_matches_oiio();
    test_round_trips();
    test_exr_half();
    test_dds();
    test_numpy();
    test_c_header();
    test_shaders();
    test_csv();
    test_corrupt_inputs();
    test_write_errors();
    CHECK(mf_test_remove_dir(dir) == 0);
    MF_TEST_MAIN_END();
}
