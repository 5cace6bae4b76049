/*
 * test_image.c -- the OpenImageIO bridge (mf_image.h): EXR round trips (float bitwise, half
 * within its rounding), atomic writes, and errors on missing, truncated and garbage files.
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <mfkit/io/mf_image.h>
#include <mfkit/fit/mf_image_oiio.h>

#include "mf_test.h"
#include "test_files.h"

#define W 7
#define H 5
#define C 4

static char dir[] = "/tmp/mfkit_test_image_XXXXXX";

static void path_in_dir(char *out, size_t size, const char *name)
{
    snprintf(out, size, "%s/%s", dir, name);
}

/* Known values: magnitudes spread over [2^-6, 2^8] with both signs and mantissas that need
 * all 24 bits (so half precision must round them), all in half's normal range. */
static float test_value(int x, int y, int c)
{
    int k = (x + W * y) * C + c;
    double v = (1.0 + (double)(((unsigned)k * 2654435761u) % 1000003u) / 1000003.0) * ldexp(1.0, (k % 15) - 6);
    return (float)((k % 3 == 1) ? -v : v);
}

static void fill_image(float *px)
{
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < C; ++c)
                px[(y * W + x) * C + c] = test_value(x, y, c);
}

/* float -> half -> float for a value in half's normal range: keep 11 significant bits, round to
 * nearest even (rint in the default rounding mode), as Imath's float-to-half conversion does. */
static float round_to_half(float v)
{
    int e;
    double m = frexp((double)v, &e); /* v = m 2^e, 0.5 <= |m| < 1 */
    return (float)ldexp(rint(ldexp(m, 11)), e - 11);
}

static void test_float_round_trip(void)
{
    float px[W * H * C];
    fill_image(px);
    mf_image img = {W, H, C, px};
    char path[512], msg[512];
    path_in_dir(path, sizeof path, "float.exr");

    CHECK(mf_image_write(path, &img, 0, msg, sizeof msg) == MF_OK);
    CHECK(msg[0] == '\0');
    CHECK(mf_test_file_exists(path));
    CHECK(mf_test_count_temporaries(dir) == 0);

    mf_image back = {-1, -1, -1, NULL};
    CHECK(mf_image_read(path, &back, msg, sizeof msg) == MF_OK);
    CHECK(msg[0] == '\0');
    CHECK(back.width == W && back.height == H && back.channels == C);
    CHECK(back.pixels != NULL);
    if (back.pixels)
        CHECK(memcmp(back.pixels, px, sizeof px) == 0); /* 32-bit float EXR is lossless */
    mf_image_free(&back);
    CHECK(back.pixels == NULL && back.width == 0);
    mf_image_free(&back); /* twice is safe */
    mf_image_free(NULL);

    /* Special values survive float storage bitwise: infinities, signed zero, float subnormals,
     * the largest float. */
    float sp[6] = {INFINITY, -INFINITY, -0.0f, 1e-40f, FLT_MAX, -FLT_MIN};
    mf_image spi = {3, 2, 1, sp};
    path_in_dir(path, sizeof path, "special.exr");
    CHECK(mf_image_write(path, &spi, 0, msg, sizeof msg) == MF_OK);
    CHECK(mf_image_read(path, &back, msg, sizeof msg) == MF_OK);
    CHECK(back.width == 3 && back.height == 2 && back.channels == 1);
    if (back.pixels)
        CHECK(memcmp(back.pixels, sp, sizeof sp) == 0);
    mf_image_free(&back);

    /* Overwriting an existing file replaces it (by rename). */
    float one[1] = {0.25f};
    mf_image onei = {1, 1, 1, one};
    CHECK(mf_image_write(path, &onei, 0, msg, sizeof msg) == MF_OK);
    CHECK(mf_image_read(path, &back, msg, sizeof msg) == MF_OK);
    CHECK(back.width == 1 && back.height == 1 && back.channels == 1 && back.pixels && back.pixels[0] == 0.25f);
    mf_image_free(&back);
    CHECK(mf_test_count_temporaries(dir) == 0);
}

static void test_half_round_trip(void)
{
    float px[W * H * C];
    fill_image(px);
    mf_image img = {W, H, C, px};
    char path[512], msg[512];
    path_in_dir(path, sizeof path, "half.exr");
    CHECK(mf_image_write(path, &img, 1, msg, sizeof msg) == MF_OK);

    mf_image back = {0, 0, 0, NULL};
    CHECK(mf_image_read(path, &back, msg, sizeof msg) == MF_OK);
    CHECK(back.width == W && back.height == H && back.channels == C);
    if (back.pixels && back.width == W && back.height == H && back.channels == C) {
        /* Half has 11 significant bits; rounding to nearest changes a value in its normal range
         * [2^-14, 65504] by at most half an ulp, i.e. a relative 2^-11 (every test value is in
         * that range).  The values also equal float -> half -> float exactly. */
        double max_rel = 0.0;
        int exact = 1, changed = 0;
        for (int i = 0; i < W * H * C; ++i) {
            double rel = fabs((double)back.pixels[i] - (double)px[i]) / fabs((double)px[i]);
            if (!(rel <= max_rel))
                max_rel = rel; /* NaN sticks */
            if (back.pixels[i] != round_to_half(px[i]))
                exact = 0;
            if (back.pixels[i] != px[i])
                changed = 1;
        }
        CHECK(max_rel <= ldexp(1.0, -11));
        CHECK(exact);
        CHECK(changed); /* the file really stores halves (the test values need 24 bits) */
    }
    mf_image_free(&back);

    /* Half storage halves the pixel data: the file is smaller than the float one. */
    char fpath[512];
    path_in_dir(fpath, sizeof fpath, "half_vs_float.exr");
    CHECK(mf_image_write(fpath, &img, 0, msg, sizeof msg) == MF_OK);
    CHECK(mf_test_file_size(path) > 0 && mf_test_file_size(path) < mf_test_file_size(fpath));
}

/* A failed read: non-OK with the expected code, a message naming the file, and a zeroed image. */
static void check_read_fails(const char *path, mf_status expected)
{
    char msg[512];
    memset(msg, 'x', sizeof msg);
    static float not_heap[1];
    mf_image img = {3, 3, 3, not_heap}; /* stale contents: overwritten, never freed */
    mf_status st = mf_image_read(path, &img, msg, sizeof msg);
    CHECK(st != MF_OK);
    CHECK(st == expected);
    CHECK(img.pixels == NULL && img.width == 0 && img.height == 0 && img.channels == 0);
    CHECK(memchr(msg, '\0', sizeof msg) != NULL);
    CHECK(strncmp(msg, path, strlen(path)) == 0 && strlen(msg) > strlen(path) + 2);
    CHECK(strchr(msg, '\n') == NULL);
}

static void test_read_errors(void)
{
    char path[512];

    path_in_dir(path, sizeof path, "missing.exr");
    check_read_fails(path, MF_ERR_IO);

    /* Garbage with an image extension, and without one. */
    path_in_dir(path, sizeof path, "garbage.exr");
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (f) {
        for (int i = 0; i < 200; ++i)
            fputs("this is not an image; ", f);
        fclose(f);
    }
    check_read_fails(path, MF_ERR_FORMAT);
    path_in_dir(path, sizeof path, "garbage.noext");
    f = fopen(path, "wb");
    if (f) {
        fputs("neither is this", f);
        fclose(f);
    }
    check_read_fails(path, MF_ERR_FORMAT);

    /* An empty file. */
    path_in_dir(path, sizeof path, "empty.exr");
    f = fopen(path, "wb");
    if (f)
        fclose(f);
    check_read_fails(path, MF_ERR_FORMAT);

    /* A valid EXR truncated to half its bytes, and to just past its magic number. */
    float px[W * H * C];
    fill_image(px);
    mf_image img = {W, H, C, px};
    char msg[512];
    const long cut[2] = {-1, 8};
    for (int k = 0; k < 2; ++k) {
        path_in_dir(path, sizeof path, k ? "truncated8.exr" : "truncated.exr");
        CHECK(mf_image_write(path, &img, 0, msg, sizeof msg) == MF_OK);
        long size = mf_test_file_size(path);
        CHECK(size > 16);
        long to = cut[k] < 0 ? size / 2 : cut[k];
        CHECK(truncate(path, (off_t)to) == 0);
        CHECK(mf_test_file_size(path) == to);
        check_read_fails(path, MF_ERR_FORMAT);
    }

    /* NULL arguments. */
    mf_image out;
    CHECK(mf_image_read(NULL, &out, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_image_read(path, NULL, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_image_read(path, NULL, NULL, 0) == MF_ERR_DOMAIN); /* no message buffer */
}

static void test_write_errors(void)
{
    float px[W * H * C];
    fill_image(px);
    mf_image img = {W, H, C, px};
    char path[512], msg[512];

    /* A directory that does not exist: IO error naming the file, and nothing created. */
    path_in_dir(path, sizeof path, "no_such_dir/out.exr");
    memset(msg, 'x', sizeof msg);
    mf_status st = mf_image_write(path, &img, 0, msg, sizeof msg);
    CHECK(st != MF_OK);
    CHECK(st == MF_ERR_IO);
    CHECK(memchr(msg, '\0', sizeof msg) != NULL);
    CHECK(strncmp(msg, path, strlen(path)) == 0 && strlen(msg) > strlen(path) + 2);
    CHECK(!mf_test_file_exists(path));
    char sub[512];
    path_in_dir(sub, sizeof sub, "no_such_dir");
    CHECK(!mf_test_file_exists(sub));

    /* An extension no writer knows. */
    path_in_dir(path, sizeof path, "out.not_an_image_format");
    st = mf_image_write(path, &img, 0, msg, sizeof msg);
    CHECK(st == MF_ERR_UNSUPPORTED);
    CHECK(strncmp(msg, path, strlen(path)) == 0);
    CHECK(!mf_test_file_exists(path));
    CHECK(mf_test_count_temporaries(dir) == 0);

    /* A format that refuses the image (PNG stores at most 4 channels): this fails after the
     * temporary file was created, so it checks that the temporary is removed again. */
    float px5[2 * 2 * 5] = {0};
    mf_image five = {2, 2, 5, px5};
    path_in_dir(path, sizeof path, "five.png");
    st = mf_image_write(path, &five, 0, msg, sizeof msg);
    CHECK(st == MF_ERR_UNSUPPORTED);
    CHECK(strncmp(msg, path, strlen(path)) == 0 && strlen(msg) > strlen(path) + 2);
    CHECK(!mf_test_file_exists(path));
    CHECK(mf_test_count_temporaries(dir) == 0);

    /* A failing write does not touch an existing file. */
    path_in_dir(path, sizeof path, "keep.exr");
    CHECK(mf_image_write(path, &img, 0, msg, sizeof msg) == MF_OK);
    long before = mf_test_file_size(path);
    mf_image bad = {W, H, C, NULL};
    CHECK(mf_image_write(path, &bad, 0, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_test_file_size(path) == before);

    /* Invalid images. */
    mf_image zero = {0, H, C, px};
    CHECK(mf_image_write(path, &zero, 0, msg, sizeof msg) == MF_ERR_DOMAIN);
    mf_image neg = {W, -1, C, px};
    CHECK(mf_image_write(path, &neg, 0, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_image_write(path, NULL, 0, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_image_write(NULL, &img, 0, msg, sizeof msg) == MF_ERR_DOMAIN);
    CHECK(mf_image_write("", &img, 0, NULL, 0) == MF_ERR_DOMAIN);
    CHECK(mf_test_file_size(path) == before);
    CHECK(mf_test_count_temporaries(dir) == 0);
}

int main(void)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    mf_test_seed(0); /* nothing random here */
    if (mkdtemp(dir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    test_float_round_trip();
    test_half_round_trip();
    test_read_errors();
    test_write_errors();
    CHECK(mf_test_remove_dir(dir) == 0);
    MF_TEST_MAIN_END();
}
