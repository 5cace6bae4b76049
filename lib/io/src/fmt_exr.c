/* fmt_exr.c -- .exr tables through the image API (mf_image.h): one channel per field, the metadata
 * in the string attribute "mfkit:table"; a table of more than 2 axes as its 2D atlas (mf_table.h),
 * the layout in the metadata's "atlas".  Needs an image backend (OpenImageIO). */
#include "io_internal.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

#include "mfkit/io/mf_image.h"

static mf_status write_exr(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    const int half = c->half_float;
    const mf_half_error *he = c->half;
    mf_table_atlas a;
    mf_status st = io_image_layout(path, t, &a, msg, msg_size);
    if (st != MF_OK)
        return st;
    const size_t nf = (size_t)t->nfields, pixels = (size_t)a.width * (size_t)a.height;
    float *px = NULL;
    uint16_t *hx = NULL;
    if (half)
        hx = malloc(pixels * nf * sizeof *hx);
    else
        px = malloc(pixels * nf * sizeof *px);
    if (!px && !hx) {
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    for (size_t p = 0; p < pixels; ++p) {
        long long texel = io_atlas_texel(&a, p); /* the identity for <= 2 axes */
        for (size_t f = 0; f < nf; ++f) {
            double v = texel < 0 ? 0.0 : t->data[(size_t)texel * nf + f];
            if (half)
                hx[p * nf + f] = mf_half_from_double(v);
            else
                px[p * nf + f] = (float)v;
        }
    }
    mf_buf h = {0};
    io_header_extra x = {half ? "float16" : "float32", half ? he : NULL, NULL, t->naxes > 2 ? &a : NULL};
    io_header_text(&h, t, &x);
    mf_buf_put(&h, "", 1);
    if (h.failed) {
        free(px);
        free(hx);
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    const char *names[MF_TABLE_MAX_FIELDS];
    for (int f = 0; f < t->nfields; ++f)
        names[f] = t->fields[f];
    const char *an[1] = {"mfkit:table"};
    const char *av[1] = {h.data};
    mf_image img = {a.width, a.height, t->nfields, px};
    mf_image_write_options o;
    memset(&o, 0, sizeof o);
    o.half_float = half;
    o.half_bits = hx;
    o.channel_names = names;
    o.nattribs = 1;
    o.attrib_names = an;
    o.attrib_values = av;
    st = mf_image_write_ex(path, &img, &o, msg, msg_size);
    free(px);
    free(hx);
    mf_buf_free(&h);
    return st;
}

/* ---- the file's extent --------------------------------------------------------------------- */

/* Scan lines per chunk of each OpenEXR compression (OpenEXR file layout, "Compression"). */
static int exr_lines_per_chunk(unsigned compression)
{
    static const int k[] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256}; /* NONE RLE ZIPS ZIP PIZ PXR24 B44 B44A DWAA DWAB */
    return compression < sizeof k / sizeof k[0] ? k[compression] : 0;
}

/* Refuses bytes after the last chunk of a single-part scan-line EXR file: the header's
 * attributes give the data window and the compression, hence the number of chunks; the offset
 * table gives where each chunk starts, and each chunk's header its size.  Other layouts (tiled,
 * multi-part, deep) are left to the image library.  Returns MF_OK or MF_ERR_FORMAT (message set). */
static mf_status exr_check_extent(const char *path, char *msg, size_t msg_size)
{
    unsigned char *d;
    size_t len;
    mf_status st = mf_io_read_file(path, path, &d, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    st = MF_OK;
    if (len < 8 || io_get_u32(d) != 20000630u) /* not OpenEXR: the image library says why */
        goto done;
    uint32_t version = io_get_u32(d + 4);
    if (version & (0x200u | 0x800u | 0x1000u)) /* tiled, deep, multi-part */
        goto done;
    size_t p = 8;
    int have_dw = 0;
    long long ymin = 0, ymax = -1;
    unsigned compression = 0;
    for (;;) {
        const unsigned char *name = d + p;
        const unsigned char *z = memchr(name, 0, len - p);
        if (!z)
            goto truncated;
        if (z == name) { /* the empty name ends the header */
            ++p;
            break;
        }
        size_t q = (size_t)(z - d) + 1;
        const unsigned char *z2 = q < len ? memchr(d + q, 0, len - q) : NULL;
        if (!z2 || (size_t)(z2 - d) + 5 > len)
            goto truncated;
        size_t vpos = (size_t)(z2 - d) + 5;
        uint32_t vsize = io_get_u32(z2 + 1);
        if (vsize > len - vpos)
            goto truncated;
        if (strcmp((const char *)name, "dataWindow") == 0 && vsize == 16) {
            ymin = (int32_t)io_get_u32(d + vpos + 4);
            ymax = (int32_t)io_get_u32(d + vpos + 12);
            have_dw = 1;
        } else if (strcmp((const char *)name, "compression") == 0 && vsize == 1) {
            compression = d[vpos];
        }
        p = vpos + vsize;
    }
    int lpc = exr_lines_per_chunk(compression);
    if (!have_dw || ymax < ymin || lpc == 0)
        goto done; /* malformed: the image library reports it */
    size_t chunks = (size_t)((ymax - ymin) / lpc + 1);
    if (chunks > (len - p) / 8)
        goto truncated;
    size_t end = p + 8 * chunks;
    for (size_t i = 0; i < chunks; ++i) {
        uint64_t off = (uint64_t)io_get_u32(d + p + 8 * i) | ((uint64_t)io_get_u32(d + p + 8 * i + 4) << 32);
        if (off > len || len - off < 8)
            goto truncated;
        uint64_t size = io_get_u32(d + off + 4);
        if (size > len - off - 8)
            goto truncated;
        if (off + 8 + size > end)
            end = (size_t)(off + 8 + size);
    }
    if (end != len) {
        mf_io_msg(msg, msg_size, path, "%zu bytes after the last chunk of the image (trailing data)", len - end);
        st = MF_ERR_FORMAT;
    }
    goto done;
truncated:
    mf_io_msg(msg, msg_size, path, "truncated OpenEXR file (a header attribute, the offset table or a chunk ends past "
                                   "the %zu bytes of the file)", len);
    st = MF_ERR_FORMAT;
done:
    free(d);
    return st;
}

/* An EXR channel name as a field name: [A-Za-z0-9_] kept, others '_'; "c<j>" if empty or taken. */
static void sanitize_name(const char *in, int j, char *out, size_t size)
{
    size_t n = 0;
    for (; *in && n + 1 < size; ++in)
        out[n++] = (isalnum((unsigned char)*in) || *in == '_') ? *in : '_';
    out[n] = '\0';
    if (n == 0)
        snprintf(out, size, "c%d", j);
}

static mf_status read_exr(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    mf_image img;
    mf_image_info ii;
    mf_status st = exr_check_extent(path, msg, msg_size);
    if (st != MF_OK)
        return st;
    st = mf_image_read_ex(path, &img, "mfkit:table", &ii, msg, msg_size);
    if (st != MF_OK)
        return st;
    char why[256];
    int sizes[2] = {img.width, img.height};
    mf_table_atlas atlas;
    int have_atlas = 0;
    int naxes = img.height > 1 ? 2 : 1;
    size_t texels = io_texel_product(sizes, 2);
    int perm[MF_TABLE_MAX_FIELDS]; /* field f is channel perm[f] */
    if (img.channels > MF_TABLE_MAX_FIELDS || texels == 0) {
        mf_io_msg(msg, msg_size, path, "%d channels, %d x %d pixels: not a table (at most %d channels)", img.channels,
                img.width, img.height, MF_TABLE_MAX_FIELDS);
        st = MF_ERR_UNSUPPORTED;
        goto done;
    }
    if (info)
        info->half_float = strcmp(ii.pixel_type, "half") == 0;
    if (ii.attrib_value) {
        cJSON *h;
        st = io_json_parse(ii.attrib_value, strlen(ii.attrib_value), &h, why, sizeof why);
        if (st == MF_OK) {
            int half = info ? info->half_float : 0;
            st = io_image_header_to_table(h, img.width, img.height, img.channels, t, info, &atlas, why, sizeof why);
            if (info)
                info->half_float = half; /* what the file stores, whatever the header says */
            cJSON_Delete(h);
        }
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "attribute mfkit:table: %s", why);
            goto done;
        }
        have_atlas = 1;
        for (int f = 0; f < t->nfields; ++f) {
            perm[f] = -1;
            for (int c = 0; c < img.channels; ++c)
                if (strcmp(ii.channel_names[c], t->fields[f]) == 0)
                    perm[f] = c;
            if (perm[f] < 0) {
                mf_io_msg(msg, msg_size, path, "attribute mfkit:table: no channel named '%s'", t->fields[f]);
                mf_table_free(t);
                st = MF_ERR_FORMAT;
                goto done;
            }
        }
    } else {
        char names[MF_TABLE_MAX_FIELDS][MF_TABLE_NAME_LEN];
        const char *np[MF_TABLE_MAX_FIELDS];
        for (int c = 0; c < img.channels; ++c) {
            sanitize_name(ii.channel_names[c], c, names[c], sizeof names[c]);
            for (int d = 0; d < c; ++d)
                if (strcmp(names[c], names[d]) == 0)
                    snprintf(names[c], sizeof names[c], "c%d", c);
            np[c] = names[c];
            perm[c] = c;
        }
        st = io_generic_table(t, naxes, sizes, img.channels, np);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "%s", st == MF_ERR_ALLOC ? "out of memory" : "cannot name the channels");
            goto done;
        }
    }
    for (size_t p = 0; p < texels; ++p) {
        long long i = have_atlas ? io_atlas_texel(&atlas, p) : (long long)p;
        if (i < 0)
            continue; /* an unused tile */
        for (int f = 0; f < t->nfields; ++f)
            t->data[(size_t)i * (size_t)t->nfields + (size_t)f] =
                (double)img.pixels[p * (size_t)img.channels + (size_t)perm[f]];
    }
done:
    mf_image_free(&img);
    mf_image_info_free(&ii);
    return st;
}

static const char *const k_ext[] = {"exr", NULL};
const io_format_ops io_format_exr = {MF_TABLE_FORMAT_EXR, "exr", k_ext, MF_TABLE_MAX_AXES, IO_CAP_HALF | IO_CAP_METADATA,
                                     write_exr, read_exr};
