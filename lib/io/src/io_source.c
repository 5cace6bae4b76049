/* io_source.c -- helpers of the generated-source formats (.h, .glsl, .hlsl). */
#include "io_internal.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

/* Appends text with every line prefixed by `lead`, and "*" "/" or "/" "*" pairs broken apart so
 * that the text can sit in a C block comment. */
void io_put_commented(mf_buf *b, const char *text, const char *lead, int block_comment)
{
    mf_buf_puts(b, lead);
    for (const char *s = text; *s; ++s) {
        if (*s == '\n') {
            if (s[1] != '\0') {
                mf_buf_puts(b, "\n");
                mf_buf_puts(b, lead);
            }
            continue;
        }
        mf_buf_put(b, s, 1);
        if (block_comment && ((s[0] == '*' && s[1] == '/') || (s[0] == '/' && s[1] == '*')))
            mf_buf_puts(b, " ");
    }
    mf_buf_puts(b, "\n");
}

void io_upper_prefix(char *up, size_t up_size, const char *prefix)
{
    size_t i = 0;
    for (; prefix[i] && i + 1 < up_size; ++i)
        up[i] = (char)toupper((unsigned char)prefix[i]);
    up[i] = '\0';
}

void io_put_axes_comment(mf_buf *b, const mf_table *t, const char *lead, int digits)
{
    for (int k = 0; k < t->naxes; ++k) {
        char desc[256];
        mf_axis_describe(&t->axes[k], desc, sizeof desc);
        mf_buf_printf(b, "%saxis %d: %s, %d texels, %s in [%.*g, %.*g]; %s\n", lead, k, t->axes[k].name,
                      t->axes[k].size, t->axes[k].name, digits, t->axes[k].lo, digits, t->axes[k].hi, desc);
    }
}

void io_put_metadata_comment(mf_buf *b, const mf_table *t, const char *lead, int block_comment)
{
    mf_buf h = {0};
    io_header_extra x = {"float32", NULL, NULL, NULL};
    io_header_text(&h, t, &x);
    mf_buf_put(&h, "", 1);
    if (h.failed)
        b->failed = 1;
    else
        io_put_commented(b, h.data, lead, block_comment);
    mf_buf_free(&h);
}

/* The program that made the table (its "tool" metadata, if it is a short printable mfkit command),
 * for the headers of generated source files. */
const char *io_generator(const mf_table *t)
{
    const char *tool = mf_table_get_meta(t, "tool");
    if (!tool || strncmp(tool, "mfkit ", 6) != 0 || strlen(tool) > 64)
        return "mfkit";
    for (const char *p = tool; *p; ++p)
        if (!isalnum((unsigned char)*p) && *p != ' ' && *p != '-')
            return "mfkit";
    return tool;
}

/* A float literal for C (suffix "f"), GLSL and HLSL (no suffix): %.9g with a '.' or exponent. */
void io_float_literal(mf_buf *b, double v, const char *suffix)
{
    char s[64];
    snprintf(s, sizeof s, "%.9g", v);
    mf_buf_puts(b, s);
    if (!strpbrk(s, ".eE"))
        mf_buf_puts(b, ".0");
    mf_buf_puts(b, suffix);
}


/* The shortest decimal literal that reads back as the double v (so a shader compiled in double
 * precision, or the C++ twin tests, see the values exactly), with a '.' or an exponent so that
 * GLSL and HLSL read it as a floating-point literal. */
void io_shader_literal(mf_buf *b, double v)
{
    char s[64];
    for (int p = 9; p <= 17; ++p) {
        snprintf(s, sizeof s, "%.*g", p, v);
        if (strtod(s, NULL) == v)
            break;
    }
    mf_buf_puts(b, s);
    if (!strpbrk(s, ".eEn"))
        mf_buf_puts(b, ".0");
}
