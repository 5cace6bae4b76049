/*
 * test_io_faults.c -- the failure behaviour of table file I/O (mfkit_io): every writer fails with
 * MF_ERR_IO and leaves nothing when the disk is full (RLIMIT_FSIZE), readers refuse trailing
 * bytes, EXR output is bitwise the same between runs, non-finite values go through the one JSON
 * rule and read back, and without an image backend EXR is refused cleanly.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <inttypes.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "mf_test.h"
#include "test_files.h"

#include <mfkit/io/mf_image.h>
#include <mfkit/io/mf_io.h>
#include <mfkit/io/mf_table_io.h>
#include <mfkit/fit/mf_image_oiio.h>

static char g_dir[256];

/* A 64 x 64 table of 4 fields (64 KiB as float32: larger than the file size limit below). */
static void make_table(mf_table *t)
{
    mf_table_axis ax[2];
    memset(ax, 0, sizeof ax);
    for (int k = 0; k < 2; ++k) {
        snprintf(ax[k].name, sizeof ax[k].name, "%s", k ? "v" : "u");
        snprintf(ax[k].physical, sizeof ax[k].physical, "%s", k ? "y" : "x");
        ax[k].size = 64;
        ax[k].lo = 0.0;
        ax[k].hi = 1.0;
        ax[k].mapping = MF_AXIS_IDENTITY;
        ax[k].physical_min = -INFINITY;
    }
    const char *names[4] = {"a", "b", "c", "d"};
    if (mf_table_create(t, 2, ax, 4, names) != MF_OK) {
        fprintf(stderr, "mf_table_create failed\n");
        exit(2);
    }
    for (size_t i = 0; i < 64 * 64 * 4; ++i)
        t->data[i] = sin(0.37 * (double)i) * 3.0;
}

/* Files in dir (not . and ..), their names in list (for messages). */
static int dir_entries(const char *dir, char *list, size_t size)
{
    DIR *d = opendir(dir);
    int n = 0;
    list[0] = '\0';
    if (!d)
        return -1;
    for (struct dirent *e; (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        ++n;
        size_t l = strlen(list);
        snprintf(list + l, size - l, "%s ", e->d_name);
    }
    closedir(d);
    return n;
}

/* A full disk: every format's write fails with MF_ERR_IO, names the file, and leaves neither the
 * target nor a temporary.  RLIMIT_FSIZE = 4096 bytes makes write() fail with EFBIG past 4 KiB
 * (SIGXFSZ ignored), as ENOSPC would; every file below is larger than that. */
static void test_full_disk(void)
{
    mf_table t;
    make_table(&t);
    const char *exts[] = {"exr", "dds", "json", "npy", "csv", "h"};
    struct rlimit old, lim;
    if (getrlimit(RLIMIT_FSIZE, &old) != 0) {
        MF_FAIL_AT("getrlimit failed");
        return;
    }
    signal(SIGXFSZ, SIG_IGN);
    for (size_t k = 0; k < sizeof exts / sizeof exts[0]; ++k)
        for (int half = 0; half <= (k < 2); ++half) {
            char path[512], msg[1024], list[1024];
            snprintf(path, sizeof path, "%s/full.%s", g_dir, exts[k]);
            mf_table_write_options o;
            mf_table_write_options_default(&o);
            o.half_float = half;
            lim = old;
            lim.rlim_cur = 4096;
            CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);
            mf_status st = mf_table_write(path, &t, &o, NULL, msg, sizeof msg);
            CHECK(setrlimit(RLIMIT_FSIZE, &old) == 0);
            if (st != MF_ERR_IO)
                MF_FAIL_AT(".%s (half %d) on a full disk: status %s (want MF_ERR_IO), message '%s'", exts[k], half,
                           mf_status_str(st), msg);
            if (!strstr(msg, path))
                MF_FAIL_AT(".%s on a full disk: message '%s' does not name %s", exts[k], msg, path);
            int n = dir_entries(g_dir, list, sizeof list);
            if (n != 0)
                MF_FAIL_AT(".%s (half %d) on a full disk left %d file(s): %s", exts[k], half, n, list);
            mf_test_clear_dir(g_dir);
        }
    signal(SIGXFSZ, SIG_DFL);
    /* the same writes succeed without the limit (the test above fails for the right reason) */
    for (size_t k = 0; k < sizeof exts / sizeof exts[0]; ++k) {
        char path[512], msg[1024];
        snprintf(path, sizeof path, "%s/ok.%s", g_dir, exts[k]);
        mf_status st = mf_table_write(path, &t, NULL, NULL, msg, sizeof msg);
        if (st != MF_OK)
            MF_FAIL_AT(".%s without a limit: %s", exts[k], msg);
    }
    mf_test_clear_dir(g_dir);
    mf_table_free(&t);
}

/* Every reader refuses bytes after the data (as the NPY reader always did). */
static void test_trailing_bytes(void)
{
    mf_table t;
    make_table(&t);
    const char *exts[] = {"exr", "dds", "npy", "json"};
    for (size_t k = 0; k < sizeof exts / sizeof exts[0]; ++k) {
        for (int half = 0; half <= (k < 2); ++half) {
            char path[512], msg[1024];
            snprintf(path, sizeof path, "%s/trail_%d.%s", g_dir, half, exts[k]);
            mf_table_write_options o;
            mf_table_write_options_default(&o);
            o.half_float = half;
            CHECK(mf_table_write(path, &t, &o, NULL, msg, sizeof msg) == MF_OK);
            mf_table r;
            mf_status st = mf_table_read(path, &r, NULL, msg, sizeof msg);
            if (st != MF_OK)
                MF_FAIL_AT("%s: clean file refused: %s", path, msg);
            mf_table_free(&r);
            FILE *f = fopen(path, "ab");
            CHECK(f && fputs("garbage", f) >= 0 && fclose(f) == 0);
            st = mf_table_read(path, &r, NULL, msg, sizeof msg);
            if (st != MF_ERR_FORMAT)
                MF_FAIL_AT("%s with 7 trailing bytes: status %s (want MF_ERR_FORMAT), message '%s'", path,
                           mf_status_str(st), msg);
            if (!strstr(msg, "trailing"))
                MF_FAIL_AT("%s with trailing bytes: message '%s' does not say so", path, msg);
            mf_table_free(&r);
        }
    }
    mf_test_clear_dir(g_dir);
    mf_table_free(&t);
}

static int file_bytes(const char *path, unsigned char **data, size_t *len)
{
    char msg[512];
    return mf_io_read_file(path, NULL, data, len, NULL, msg, sizeof msg) == MF_OK;
}

/* The same table written twice, more than a second apart (a time stamp would differ), gives the
 * same bytes, float32 and half. */
static void test_exr_deterministic(void)
{
    mf_table t;
    make_table(&t);
    for (int half = 0; half <= 1; ++half) {
        char p1[512], p2[512], msg[1024];
        snprintf(p1, sizeof p1, "%s/det1.exr", g_dir);
        snprintf(p2, sizeof p2, "%s/det2.exr", g_dir);
        mf_table_write_options o;
        mf_table_write_options_default(&o);
        o.half_float = half;
        CHECK(mf_table_write(p1, &t, &o, NULL, msg, sizeof msg) == MF_OK);
        struct timespec ts = {1, 100000000};
        nanosleep(&ts, NULL);
        CHECK(mf_table_write(p2, &t, &o, NULL, msg, sizeof msg) == MF_OK);
        unsigned char *a = NULL, *b = NULL;
        size_t na = 0, nb = 0;
        CHECK(file_bytes(p1, &a, &na) && file_bytes(p2, &b, &nb));
        if (!a || !b || na != nb || memcmp(a, b, na) != 0) {
            size_t at = 0;
            while (a && b && at < na && at < nb && a[at] == b[at])
                ++at;
            MF_FAIL_AT("EXR (half %d) written twice: %zu and %zu bytes, first difference at byte %zu", half, na, nb, at);
        }
        free(a);
        free(b);
    }
    mf_test_clear_dir(g_dir);
    mf_table_free(&t);
}

/* NaN and infinities: the JSON table holds the strings of the one emitter and reads back; files
 * of the older rule (null, 1e999) still read. */
static void test_json_nonfinite(void)
{
    mf_table t;
    make_table(&t);
    t.data[0] = NAN;
    t.data[1] = INFINITY;
    t.data[2] = -INFINITY;
    char path[512], msg[1024];
    snprintf(path, sizeof path, "%s/nf.json", g_dir);
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
    unsigned char *d = NULL;
    size_t n = 0;
    CHECK(file_bytes(path, &d, &n));
    CHECK(d && strstr((const char *)d, "[\"NaN\", \"Infinity\", \"-Infinity\", ") != NULL);
    CHECK(d && strstr((const char *)d, " nan") == NULL && strstr((const char *)d, " inf") == NULL);
    mf_table r;
    CHECK(mf_table_read(path, &r, NULL, msg, sizeof msg) == MF_OK);
    if (r.data) {
        CHECK(isnan(r.data[0]) && r.data[1] == INFINITY && r.data[2] == -INFINITY);
        CHECK(r.data[3] == (double)(float)t.data[3]);
        mf_table_free(&r);
    }
    /* the older rule: NaN as null, infinities as +-1e999 */
    if (d) {
        char *s = strstr((char *)d, "[\"NaN\", \"Infinity\", \"-Infinity\", ");
        if (s) {
            mf_buf b = {0};
            mf_buf_put(&b, d, (size_t)(s - (char *)d));
            mf_buf_puts(&b, "[null, 1e999, -1e999, ");
            mf_buf_puts(&b, s + strlen("[\"NaN\", \"Infinity\", \"-Infinity\", "));
            CHECK(mf_io_write_buf_atomic(path, &b, msg, sizeof msg) == MF_OK);
            mf_buf_free(&b);
            CHECK(mf_table_read(path, &r, NULL, msg, sizeof msg) == MF_OK);
            if (r.data) {
                CHECK(isnan(r.data[0]) && r.data[1] == INFINITY && r.data[2] == -INFINITY);
                mf_table_free(&r);
            }
        }
    }
    free(d);
    /* a syntax error names the line and column */
    CHECK(mf_io_write_atomic(path, "{\n  \"header\": [1,\n  ]\n}\n", 23, msg, sizeof msg) == MF_OK);
    CHECK(mf_table_read(path, &r, NULL, msg, sizeof msg) == MF_ERR_FORMAT);
    if (!strstr(msg, path) || !strstr(msg, "line 3"))
        MF_FAIL_AT("JSON syntax error: message '%s' should name %s and line 3", msg, path);
    mf_test_clear_dir(g_dir);
    mf_table_free(&t);
}

/* Without an image backend EXR is refused with one clear message and nothing is written. */
static void test_no_backend(void)
{
    mf_table t;
    make_table(&t);
    const mf_image_backend *saved = mf_image_get_backend();
    mf_image_set_backend(NULL);
    char path[512], msg[1024], list[512];
    snprintf(path, sizeof path, "%s/nob.exr", g_dir);
    mf_status st = mf_table_write(path, &t, NULL, NULL, msg, sizeof msg);
    CHECK(st == MF_ERR_UNSUPPORTED);
    if (!strstr(msg, "writing EXR needs the OpenImageIO build") || !strstr(msg, path))
        MF_FAIL_AT("no backend: message '%s'", msg);
    CHECK(dir_entries(g_dir, list, sizeof list) == 0);
    mf_table r;
    st = mf_table_read(path, &r, NULL, msg, sizeof msg);
    CHECK(st == MF_ERR_UNSUPPORTED || st == MF_ERR_IO); /* no file: the extent check may see it first */
    /* the non-image formats do not need a backend */
    snprintf(path, sizeof path, "%s/nob.dds", g_dir);
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
    mf_image_set_backend(saved);
    snprintf(path, sizeof path, "%s/nob.exr", g_dir);
    CHECK(mf_table_write(path, &t, NULL, NULL, msg, sizeof msg) == MF_OK);
    mf_image_set_backend(NULL);
    st = mf_table_read(path, &r, NULL, msg, sizeof msg);
    if (st != MF_ERR_UNSUPPORTED || !strstr(msg, "reading EXR needs the OpenImageIO build"))
        MF_FAIL_AT("no backend, reading: status %s, message '%s'", mf_status_str(st), msg);
    mf_image_set_backend(saved);
    mf_test_clear_dir(g_dir);
    mf_table_free(&t);
}

/* The atomic write reports a missing directory and leaves nothing. */
static void test_atomic_errors(void)
{
    char path[512], msg[1024];
    snprintf(path, sizeof path, "%s/no/such/dir/x.bin", g_dir);
    CHECK(mf_io_write_atomic(path, "x", 1, msg, sizeof msg) == MF_ERR_IO);
    if (!strstr(msg, path) || !strstr(msg, "temporary"))
        MF_FAIL_AT("missing directory: message '%s'", msg);
}

int main(void)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    snprintf(g_dir, sizeof g_dir, "/tmp/test_io_faults_%ld", (long)getpid());
    if (!mkdtemp(strcat(g_dir, "_XXXXXX"))) {
        fprintf(stderr, "cannot create a temporary directory\n");
        return 2;
    }
    test_full_disk();
    test_trailing_bytes();
    test_exr_deterministic();
    test_json_nonfinite();
    test_no_backend();
    test_atomic_errors();
    CHECK(mf_test_remove_dir(g_dir) == 0);
    MF_TEST_MAIN_END();
}
