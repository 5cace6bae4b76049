/* mf_prefilter_files.c -- reading a `mfkit prefilter` output directory back: its manifest's text
 * and its float32 .npy levels (for `mfkit prefilter-eval` and the analysis programs). */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/io/mf_io.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Reads a whole file (mf_io_read_file: NUL-terminated, its messages); NULL with msg on failure. */
char *mf_prefilter_read_file(const char *path, size_t *len, char *msg, size_t msz)
{
    unsigned char *b = NULL;
    if (mf_io_read_file(path, NULL, &b, len, NULL, msg, msz) != MF_OK)
        return NULL;
    return (char *)b;
}

/* A float32 little-endian C-order .npy of the expected rank; shape in dims. */
float *mf_prefilter_read_npy(const char *path, int rank, long *dims, char *msg, size_t msz)
{
    size_t len;
    char *b = mf_prefilter_read_file(path, &len, msg, msz);
    if (!b)
        return NULL;
    float *out = NULL;
    if (len < 10 || memcmp(b, "\x93NUMPY", 6) != 0) {
        snprintf(msg, msz, "%s: not a .npy file", path);
        goto done;
    }
    size_t hl, off;
    if (b[6] == 1)
        hl = (unsigned char)b[8] | (size_t)(unsigned char)b[9] << 8, off = 10;
    else
        hl = (unsigned char)b[8] | (size_t)(unsigned char)b[9] << 8 | (size_t)(unsigned char)b[10] << 16 |
             (size_t)(unsigned char)b[11] << 24,
        off = 12;
    if (off + hl > len) {
        snprintf(msg, msz, "%s: truncated header", path);
        goto done;
    }
    char hdr[1024];
    size_t cl = hl < sizeof hdr - 1 ? hl : sizeof hdr - 1;
    memcpy(hdr, b + off, cl), hdr[cl] = 0;
    const char *sh = strstr(hdr, "'shape': (");
    if (!strstr(hdr, "'descr': '<f4'") || !strstr(hdr, "'fortran_order': False") || !sh) {
        snprintf(msg, msz, "%s: expected little-endian float32 in C order", path);
        goto done;
    }
    sh += 10;
    size_t count = 1;
    for (int i = 0; i < rank; ++i) {
        char *end;
        dims[i] = strtol(sh, &end, 10);
        if (end == sh || dims[i] <= 0 || dims[i] > (1L << 24)) {
            snprintf(msg, msz, "%s: expected a shape of rank %d", path, rank);
            goto done;
        }
        count *= (size_t)dims[i];
        sh = end;
        while (*sh == ',' || *sh == ' ')
            ++sh;
    }
    if (*sh != ')') {
        snprintf(msg, msz, "%s: expected a shape of rank %d", path, rank);
        goto done;
    }
    if (len - off - hl != count * 4) {
        snprintf(msg, msz, "%s: %zu data bytes for %zu float32 values", path, len - off - hl, count);
        goto done;
    }
    out = malloc(count * sizeof(float));
    if (!out) {
        snprintf(msg, msz, "out of memory");
        goto done;
    }
    memcpy(out, b + off + hl, count * 4); /* little-endian hosts (checked by the build's io tests) */
done:
    free(b);
    return out;
}

/* The string value of "key": "..." in a JSON text (no escapes beyond \" and \\). */
int mf_prefilter_json_string(const char *js, const char *key, char *out, size_t osz)
{
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\": \"", key);
    const char *p = strstr(js, pat);
    if (!p)
        return 0;
    p += strlen(pat);
    size_t n = 0;
    for (; *p && *p != '"'; ++p) {
        if (*p == '\\' && p[1])
            ++p;
        if (n + 1 >= osz)
            return 0;
        out[n++] = *p;
    }
    out[n] = 0;
    return *p == '"';
}

