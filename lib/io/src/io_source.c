/* io_source.c -- helpers of the generated-source formats (.h, .glsl, .hlsl). */
#include "io_internal.h"

#include <ctype.h>
#include <stdio.h>

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

