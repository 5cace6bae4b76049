/* mf_json.c -- the one JSON emitter (mf_json.h). */
#include "mfkit/io/mf_json.h"

#include <math.h>
#include <string.h>

void mf_json_string(mf_buf *b, const char *s)
{
    if (!s) {
        mf_buf_puts(b, "null");
        return;
    }
    mf_buf_puts(b, "\"");
    const char *run = s; /* bytes copied as they are, in runs */
    for (; *s; ++s) {
        unsigned char c = (unsigned char)*s;
        if (c != '"' && c != '\\' && c >= 0x20 && c != 0x7f)
            continue;
        mf_buf_put(b, run, (size_t)(s - run));
        run = s + 1;
        if (c == '"' || c == '\\')
            mf_buf_printf(b, "\\%c", c);
        else if (c == '\n')
            mf_buf_puts(b, "\\n");
        else if (c == '\t')
            mf_buf_puts(b, "\\t");
        else
            mf_buf_printf(b, "\\u%04x", c);
    }
    mf_buf_put(b, run, (size_t)(s - run));
    mf_buf_puts(b, "\"");
}

static int nonfinite(mf_buf *b, double v)
{
    if (isnan(v))
        mf_buf_puts(b, "\"NaN\"");
    else if (isinf(v))
        mf_buf_puts(b, v > 0 ? "\"Infinity\"" : "\"-Infinity\"");
    else
        return 0;
    return 1;
}

void mf_json_number(mf_buf *b, double v)
{
    if (!nonfinite(b, v))
        mf_buf_printf(b, "%.17g", v);
}

void mf_json_float(mf_buf *b, float v)
{
    if (nonfinite(b, (double)v))
        return;
    if (v == 0.0f && signbit(v))
        mf_buf_puts(b, "-0.0");
    else
        mf_buf_printf(b, "%.9g", (double)v);
}

void mf_json_bool(mf_buf *b, int v) { mf_buf_puts(b, v ? "true" : "false"); }

void mf_json_checks(mf_buf *b, const mf_check *c, int n)
{
    mf_buf_puts(b, "[\n");
    for (int i = 0; i < n; ++i) {
        mf_buf_puts(b, "    {\"name\": ");
        mf_json_string(b, c[i].name);
        mf_buf_puts(b, ", \"what\": ");
        mf_json_string(b, c[i].what);
        mf_buf_puts(b, ", \"worst\": ");
        mf_json_number(b, c[i].worst);
        mf_buf_puts(b, ", \"bound\": ");
        mf_json_number(b, c[i].bound);
        mf_buf_puts(b, ", \"passed\": ");
        mf_json_bool(b, c[i].passed);
        mf_buf_printf(b, ", \"cases\": %ld, \"worst_at\": ", c[i].cases);
        mf_json_string(b, c[i].worst_at);
        mf_buf_puts(b, i + 1 < n ? "},\n" : "}\n");
    }
    mf_buf_puts(b, "  ]");
}

int mf_json_nonfinite(const char *s, double *out)
{
    if (!s)
        return 0;
    if (strcmp(s, "NaN") == 0)
        *out = NAN;
    else if (strcmp(s, "Infinity") == 0)
        *out = INFINITY;
    else if (strcmp(s, "-Infinity") == 0)
        *out = -INFINITY;
    else
        return 0;
    return 1;
}
