/* fmt_shader.c -- .glsl and .hlsl lookup snippets (write-only, no data): physical inputs -> axis
 * parameters -> texture coordinates at the texel centres, and a lookup of any number of axes: the
 * texture itself for 1 or 2 axes, the 2D atlas of mf_table.h (bilinear within a tile, a manual
 * lerp across the further axes, as mf_table_atlas_lookup) for more. */
#include "io_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* The lookup functions of a snippet (everything between its include guard): see io_internal.h. */
void io_shader_lookup_functions(mf_buf *b, const mf_table *t, const char *prefix, int hlsl)
{
    char up[128];
    io_upper_prefix(up, sizeof up, prefix);
    const char *vec2 = hlsl ? "float2" : "vec2", *vec4 = hlsl ? "float4" : "vec4";
    const char *tex_param = hlsl ? "Texture2D<float4> table, SamplerState samp" : "sampler2D table";
    const char *sample_uv = hlsl ? "table.SampleLevel(samp, uv, 0.0)" : "textureLod(table, uv, 0.0)";
    /* the physical inputs are named after the axes' physical quantities, unless two share one */
    int distinct = 1;
    for (int k = 0; k < t->naxes; ++k)
        for (int j = 0; j < k; ++j)
            if (strcmp(t->axes[k].physical, t->axes[j].physical) == 0)
                distinct = 0;
    for (int k = 0; k < t->naxes; ++k) /* the lookup's other parameters */
        if (!strcmp(t->axes[k].physical, "table") || !strcmp(t->axes[k].physical, "samp"))
            distinct = 0;
    char in[MF_TABLE_MAX_AXES][MF_TABLE_NAME_LEN + 8];
    for (int k = 0; k < t->naxes; ++k) {
        if (distinct)
            snprintf(in[k], sizeof in[k], "%s", t->axes[k].physical);
        else
            snprintf(in[k], sizeof in[k], "x%d", k);
    }
    for (int k = 0; k < t->naxes; ++k) {
        const mf_table_axis *a = &t->axes[k];
        /* physical -> parameter: the inverse of the mapping, after the same clamp as the table */
        mf_buf_printf(b, "// axis %d: the parameter %s of the physical %s\n", k, a->name, a->physical);
        mf_buf_printf(b, "float %s_param%d(float %s)\n{\n", prefix, k, in[k]);
        if (isfinite(a->physical_min)) {
            mf_buf_printf(b, "    %s = max(%s, ", in[k], in[k]);
            io_shader_literal(b, a->physical_min);
            mf_buf_puts(b, ");\n");
        }
        switch (a->mapping) {
        case MF_AXIS_IDENTITY: mf_buf_printf(b, "    return %s;\n", in[k]); break;
        case MF_AXIS_ONE_MINUS_SQUARE: mf_buf_printf(b, "    return sqrt(max(1.0 - %s, 0.0));\n", in[k]); break;
        case MF_AXIS_SQUARE: mf_buf_printf(b, "    return sqrt(max(%s, 0.0));\n", in[k]); break;
        case MF_AXIS_COS: mf_buf_printf(b, "    return acos(clamp(%s, -1.0, 1.0));\n", in[k]); break;
        }
        mf_buf_puts(b, "}\n");
        double lo = fmin(a->lo, a->hi), hi = fmax(a->lo, a->hi);
        if (k < 2) {
            /* parameter -> texture coordinate at the texel centres (mf_table_uv_from_param) */
            mf_buf_printf(b, "// axis %d: the texture coordinate of %s (texel centres, clamped to the table)\n", k,
                          a->name);
            mf_buf_printf(b, "float %s_coord%d(float %s)\n{\n", prefix, k, a->name);
            if (a->size <= 1) {
                mf_buf_printf(b, "    return 0.5 + 0.0 * %s;\n}\n\n", a->name);
                continue;
            }
            mf_buf_printf(b, "    %s = clamp(%s, ", a->name, a->name);
            io_shader_literal(b, lo);
            mf_buf_puts(b, ", ");
            io_shader_literal(b, hi);
            mf_buf_printf(b, ");\n    return (%s - (", a->name);
            io_shader_literal(b, a->lo);
            mf_buf_puts(b, ")) / (");
            io_shader_literal(b, a->hi - a->lo);
            mf_buf_printf(b, ") * %d.0 / %d.0 + 0.5 / %d.0;\n}\n\n", a->size - 1, a->size, a->size);
        } else if (a->size > 1) {
            /* parameter -> continuous texel index in [0, n - 1] (the manual lerp across tiles) */
            mf_buf_printf(b, "// axis %d: the texel position of %s in [0, %d] (clamped to the table)\n", k, a->name,
                          a->size - 1);
            mf_buf_printf(b, "float %s_pos%d(float %s)\n{\n    return clamp((%s - (", prefix, k, a->name, a->name);
            io_shader_literal(b, a->lo);
            mf_buf_puts(b, ")) / (");
            io_shader_literal(b, a->hi - a->lo);
            mf_buf_printf(b, ") * %d.0, 0.0, %d.0);\n}\n\n", a->size - 1, a->size - 1);
        }
    }
    if (t->naxes <= 2) {
        mf_buf_printf(b, "// The texture coordinate of the physical inputs.\n%s %s_uv(", vec2, prefix);
        for (int k = 0; k < t->naxes; ++k)
            mf_buf_printf(b, "%sfloat %s", k ? ", " : "", in[k]);
        if (t->naxes == 1)
            mf_buf_printf(b, ")\n{\n    return %s(%s_coord0(%s_param0(%s)), 0.5);\n}\n\n", vec2, prefix, prefix, in[0]);
        else
            mf_buf_printf(b, ")\n{\n    return %s(%s_coord0(%s_param0(%s)), %s_coord1(%s_param1(%s)));\n}\n\n", vec2,
                          prefix, prefix, in[0], prefix, prefix, in[1]);
    }
    /* the lookup at the axis parameters */
    if (t->naxes <= 2) {
        mf_buf_puts(b, "// The record at the axis parameters p<k> (see the axes above), bilinearly interpolated (mip level 0).\n");
        mf_buf_printf(b, "%s %s_lookup_params(%s", vec4, prefix, tex_param);
        for (int k = 0; k < t->naxes; ++k)
            mf_buf_printf(b, ", float p%d", k);
        mf_buf_printf(b, ")\n{\n    %s uv = %s(%s_coord0(p0), ", vec2, vec2, prefix);
        if (t->naxes == 1)
            mf_buf_puts(b, "0.5);\n");
        else
            mf_buf_printf(b, "%s_coord1(p1));\n", prefix);
        mf_buf_printf(b, "    return %s;\n}\n\n", sample_uv);
    } else {
        mf_table_atlas a;
        if (mf_table_atlas_from_meta(t, &a) != MF_OK && mf_table_atlas_layout(t, 0, &a) != MF_OK)
            memset(&a, 0, sizeof a); /* the writer refuses such tables before */
        mf_buf_printf(b, "// The %d-axis table as a 2D atlas (an EXR or DDS written by mfkit; the metadata's \"atlas\"):\n"
                         "// axis 0 along x and axis 1 along y within a tile of %d x %d texels; one tile per combination\n"
                         "// of axes 2..%d, tile = i2 + n2 (i3 + n3 (...)), at column tile %% %d, row tile / %d.\n",
                      t->naxes, a.tile_w, a.tile_h, t->naxes - 1, a.tiles_x, a.tiles_x);
        mf_buf_printf(b, "#define %s_ATLAS_TILES_X %d\n#define %s_ATLAS_TILE_W %d\n#define %s_ATLAS_TILE_H %d\n", up,
                      a.tiles_x, up, a.tile_w, up, a.tile_h);
        mf_buf_printf(b, "#define %s_ATLAS_WIDTH %d\n#define %s_ATLAS_HEIGHT %d\n\n", up, a.width, up, a.height);
        mf_buf_puts(b, "// Tile `tile` sampled with the bilinear filter at the in-tile coordinate uv (in [0.5/n, 1 - 0.5/n],\n"
                       "// so the filter never reaches a neighbouring tile).\n");
        mf_buf_printf(b, "%s %s_tile(%s, %s uv, int tile)\n{\n", vec4, prefix, tex_param, vec2);
        mf_buf_printf(b, "    int col = tile %% %s_ATLAS_TILES_X;\n    int row = tile / %s_ATLAS_TILES_X;\n", up, up);
        mf_buf_printf(b, "    uv = %s((float(col) + uv.x) * %d.0 / %d.0, (float(row) + uv.y) * %d.0 / %d.0);\n", vec2,
                      a.tile_w, a.width, a.tile_h, a.height);
        mf_buf_printf(b, "    return %s;\n}\n\n", sample_uv);
        mf_buf_puts(b, "// The record at the axis parameters p<k>: bilinear within a tile (axes 0, 1), linear across the further\n"
                       "// axes between neighbouring tiles (the C twin is mf_table_atlas_lookup).\n");
        mf_buf_printf(b, "%s %s_lookup_params(%s", vec4, prefix, tex_param);
        for (int k = 0; k < t->naxes; ++k)
            mf_buf_printf(b, ", float p%d", k);
        mf_buf_printf(b, ")\n{\n    %s uv = %s(%s_coord0(p0), %s_coord1(p1));\n", vec2, vec2, prefix, prefix);
        int lerp[MF_TABLE_MAX_AXES], nlerp = 0;
        for (int k = 2; k < t->naxes; ++k) {
            if (t->axes[k].size <= 1)
                continue; /* one texel: index 0, weight 1 */
            lerp[nlerp++] = k;
            mf_buf_printf(b, "    float f%d = %s_pos%d(p%d);\n", k, prefix, k, k);
            mf_buf_printf(b, "    int i%d = min(int(floor(f%d)), %d);\n", k, k, t->axes[k].size - 2);
            mf_buf_printf(b, "    float w%d = f%d - float(i%d);\n", k, k, k);
        }
        mf_buf_printf(b, "    %s r = %s(0.0);\n", vec4, vec4);
        for (int corner = 0; corner < (1 << nlerp); ++corner) {
            mf_buf_puts(b, "    r += (");
            if (nlerp == 0)
                mf_buf_puts(b, "1.0");
            for (int j = 0; j < nlerp; ++j) {
                int k = lerp[j], upk = (corner >> j) & 1;
                if (upk)
                    mf_buf_printf(b, "%sw%d", j ? " * " : "", k);
                else
                    mf_buf_printf(b, "%s(1.0 - w%d)", j ? " * " : "", k);
            }
            mf_buf_printf(b, ") * %s_tile(table%s, uv, ", prefix, hlsl ? ", samp" : "");
            /* tile = sum_k stride_k (i_k + up_k) over the further axes */
            long stride = 1;
            int first = 1;
            for (int k = 2; k < t->naxes; ++k) {
                int j = -1;
                for (int q = 0; q < nlerp; ++q)
                    if (lerp[q] == k)
                        j = q;
                if (j >= 0) {
                    int upk = (corner >> j) & 1;
                    mf_buf_printf(b, "%s", first ? "" : " + ");
                    if (stride == 1)
                        mf_buf_printf(b, upk ? "(i%d + 1)" : "i%d", k);
                    else
                        mf_buf_printf(b, upk ? "%ld * (i%d + 1)" : "%ld * i%d", stride, k);
                    first = 0;
                }
                stride *= t->axes[k].size;
            }
            mf_buf_puts(b, first ? "0);\n" : ");\n");
        }
        mf_buf_puts(b, "    return r;\n}\n\n");
    }
    mf_buf_puts(b, "// The record at the physical inputs.\n");
    mf_buf_printf(b, "%s %s_lookup(%s", vec4, prefix, tex_param);
    for (int k = 0; k < t->naxes; ++k)
        mf_buf_printf(b, ", float %s", in[k]);
    mf_buf_printf(b, ")\n{\n    return %s_lookup_params(table%s", prefix, hlsl ? ", samp" : "");
    for (int k = 0; k < t->naxes; ++k)
        mf_buf_printf(b, ", %s_param%d(%s)", prefix, k, in[k]);
    mf_buf_puts(b, ");\n}\n\n");
}

/* GLSL and HLSL lookup snippets. */
static void build_shader(mf_buf *b, const mf_table *t, const char *prefix, const char *file_name, int hlsl)
{
    char up[128];
    io_upper_prefix(up, sizeof up, prefix);
    mf_buf_printf(b, "// %s -- %s lookup of an mfkit table (generated by %s; do not edit).\n//\n", file_name,
              hlsl ? "HLSL" : "GLSL", io_generator(t));
    mf_buf_puts(b, "// The table is a texture (EXR or DDS written by mfkit): axis 0 runs along x (u), axis 1 along y (v),\n"
               "// texel (i0, i1) at uv = ((i0 + 0.5) / n0, (i1 + 0.5) / n1), row i1 = 0 first in the file.\n"
               "// EXR: one channel per field, named after it; DDS: R, G, B, A = the fields chosen at export.\n"
               "// Sample with bilinear filtering and clamp-to-edge.  Texel i of an axis of n texels holds the\n"
               "// parameter p_i = lo + (hi - lo) * i / (n - 1), so uv = (p - lo) / (hi - lo) * (n - 1) / n + 0.5 / n.\n");
    io_put_axes_comment(b, t, "// ", 9);
    mf_buf_puts(b, "//\n// Metadata:\n");
    io_put_metadata_comment(b, t, "// ", 0);
    mf_buf_printf(b, "#ifndef %s_LOOKUP\n#define %s_LOOKUP\n\n", up, up);
    io_shader_lookup_functions(b, t, prefix, hlsl);
    mf_buf_printf(b, "#endif // %s_LOOKUP\n", up);
}


static mf_status write_shader(const char *path, const mf_table *t, int hlsl, const io_write_ctx *c, char *msg,
                              size_t msg_size)
{
    mf_buf b = {0};
    build_shader(&b, t, c->prefix, io_base_name(path), hlsl);
    mf_status st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
    mf_buf_free(&b);
    return st;
}

static mf_status write_glsl(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    return write_shader(path, t, 0, c, msg, msg_size);
}

static mf_status write_hlsl(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    return write_shader(path, t, 1, c, msg, msg_size);
}

static const char *const k_glsl_ext[] = {"glsl", NULL};
static const char *const k_hlsl_ext[] = {"hlsl", NULL};
const io_format_ops io_format_glsl = {MF_TABLE_FORMAT_GLSL, "glsl", k_glsl_ext, MF_TABLE_MAX_AXES,
                                      IO_CAP_METADATA | IO_CAP_PREFIX, write_glsl, NULL};
const io_format_ops io_format_hlsl = {MF_TABLE_FORMAT_HLSL, "hlsl", k_hlsl_ext, MF_TABLE_MAX_AXES,
                                      IO_CAP_METADATA | IO_CAP_PREFIX, write_hlsl, NULL};
